"""Screenshots of the built site in headless Chromium, to look at before a release: the
landing page, a tutorial and the API reference, at a laptop's width and a phone's.

    python -m sphinx -W --keep-going -b html docs docs/_build/html
    python docs/_tools/screenshots.py [--site docs/_build/html] [--out docs/_build/screenshots]

Needs selenium (the `test` extra) and Debian's chromium and chromium-driver. Writes one PNG
per page and width (the whole page's height, up to MAX_HEIGHT pixels) and prints their
paths; the images are for reading, not for the repository.
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1]
#: the pages shot: name -> path in the built site
PAGES = {
    "landing": "index.html",
    "tutorial": "tutorials/paper-energies.html",
    "api": "reference/api.html",
}
#: window widths [px]: a laptop and a phone
WIDTHS = {"wide": 1280, "narrow": 420}
#: the tallest screenshot taken [px] (a long page is cut there)
MAX_HEIGHT = 4000


def driver(width: int, height: int = 900):
    """A headless Chromium (no network beyond the machine) of this window size."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    opts.binary_location = shutil.which("chromium") or "/usr/bin/chromium"
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-background-networking"):
        opts.add_argument(flag)
    opts.add_argument(f"--window-size={width},{height}")
    opts.add_argument(f"--user-data-dir={tempfile.mkdtemp(prefix='granplate-shots-')}")
    service = Service(executable_path=shutil.which("chromedriver") or "/usr/bin/chromedriver")
    return webdriver.Chrome(options=opts, service=service)


def shoot(site: Path, out: Path) -> list[Path]:
    """Screenshot every page of PAGES at every width of WIDTHS; the PNGs written."""
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for label, width in WIDTHS.items():
        browser = driver(width)
        try:
            for name, page in PAGES.items():
                path = site / page
                if not path.exists():
                    raise SystemExit(f"{path} is missing: build the site first")
                browser.set_window_size(width, 900)
                browser.get(path.resolve().as_uri())
                while browser.execute_script("return document.readyState") != "complete":
                    time.sleep(0.05)
                height = browser.execute_script("return document.documentElement.scrollHeight")
                browser.set_window_size(width, min(int(height), MAX_HEIGHT))
                time.sleep(0.3)  # the theme lays out again at the new size
                png = out / f"{name}-{label}.png"
                browser.save_screenshot(str(png))
                written.append(png)
        finally:
            browser.quit()
    return written


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--site", default=str(DOCS / "_build" / "html"), help="the built site")
    parser.add_argument("--out", default=str(DOCS / "_build" / "screenshots"), help="where the PNGs go")
    args = parser.parse_args()
    for png in shoot(Path(args.site), Path(args.out)):
        print(png)


if __name__ == "__main__":
    main()
