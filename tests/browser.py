"""A real browser for the page tests: Debian's headless Chromium driven by selenium.

`browser` is a pytest fixture (import it into a test module: `from browser import browser`): a selenium WebDriver on headless Chromium, 1280 x 900, with
no network beyond the machine (background networking off, every request outside file://
and localhost refused by the test that checks it). Where selenium, Chromium or ChromeDriver
is missing the tests using it skip and say which one; `.ci/run` installs them.

`console_errors(driver)` returns the page's JavaScript errors (severity SEVERE) from the
browser log; `open_page(driver, path)` loads a local file and waits until the document is
complete.
"""

from __future__ import annotations

import shutil
import tempfile
import time
from pathlib import Path

import pytest

#: where Debian puts them (packages chromium and chromium-driver).
CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"
#: the flags that keep a headless Chromium off the network and quiet.
FLAGS = (
    "--headless=new",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-dev-shm-usage",
    "--window-size=1280,900",
)


def missing() -> str:
    """Why no browser can run here ('' when one can)."""
    try:
        import selenium  # noqa: F401
    except ImportError:
        return "selenium is not installed (pip install granplate[test])"
    chromium = shutil.which("chromium") or (CHROMIUM if Path(CHROMIUM).exists() else None)
    driver = shutil.which("chromedriver") or (CHROMEDRIVER if Path(CHROMEDRIVER).exists() else None)
    if chromium is None:
        return "Chromium is not installed (Debian: apt-get install chromium chromium-driver)"
    if driver is None:
        return "ChromeDriver is not installed (Debian: apt-get install chromium-driver)"
    return ""


def new_driver():
    """A headless Chromium WebDriver with its own empty profile and the browser log on."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    opts.binary_location = shutil.which("chromium") or CHROMIUM
    for flag in FLAGS:
        opts.add_argument(flag)
    opts.add_argument(f"--user-data-dir={tempfile.mkdtemp(prefix='granplate-chromium-')}")
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL", "performance": "ALL"})
    service = Service(executable_path=shutil.which("chromedriver") or CHROMEDRIVER)
    return webdriver.Chrome(options=opts, service=service)


@pytest.fixture(scope="module")
def browser():
    """A headless Chromium for the module's tests (skips, saying why, where none can run)."""
    why = missing()
    if why:
        pytest.skip(f"no browser: {why}")
    driver = new_driver()
    try:
        yield driver
    finally:
        driver.quit()


def open_page(driver, path: Path, timeout: float = 30.0) -> None:
    """Load the local file `path` and wait until the document and its scripts are done."""
    driver.get(Path(path).resolve().as_uri())
    end = time.monotonic() + timeout
    while driver.execute_script("return document.readyState") != "complete":
        if time.monotonic() > end:
            raise TimeoutError(f"{path} did not finish loading in {timeout} s")
        time.sleep(0.05)


def console_errors(driver) -> list[str]:
    """The JavaScript errors (SEVERE entries) the page logged since the last call."""
    return [e["message"] for e in driver.get_log("browser") if e.get("level") == "SEVERE"]


def requested_urls(driver) -> list[str]:
    """Every URL the page requested (from the performance log) since the last call."""
    import json

    urls = []
    for entry in driver.get_log("performance"):
        msg = json.loads(entry["message"])["message"]
        if msg.get("method") == "Network.requestWillBeSent":
            urls.append(msg["params"]["request"]["url"])
    return urls


def external_requests(driver) -> list[str]:
    """The requested URLs that would leave the machine (not file:, data:, blob:, the
    browser's own chrome: pages or localhost)."""
    local = (
        "file:",
        "data:",
        "blob:",
        "about:",
        "chrome:",
        "chrome-untrusted:",
        "devtools:",
        "http://localhost",
        "http://127.0.0.1",
    )
    return [u for u in requested_urls(driver) if not u.startswith(local)]
