"""The browser the page tests use: a local page loads, its script runs, its errors and
requests are seen (so the page tests can fail)."""

from __future__ import annotations

from browser import browser, console_errors, external_requests, open_page  # noqa: F401


def test_a_local_page_runs_its_script_and_its_errors_are_reported(browser, tmp_path):
    """A script's DOM change is visible and a thrown error reaches console_errors."""
    page = tmp_path / "p.html"
    page.write_text(
        "<html><body><p id='x'>before</p><script>document.getElementById('x')"
        ".textContent = 'after'; setTimeout(function(){ throw new Error('boom'); }, 0);"
        "</script></body></html>"
    )
    open_page(browser, page)
    browser.execute_script("return 1")
    assert browser.find_element("id", "x").text == "after"
    import time

    time.sleep(0.2)
    errors = console_errors(browser)
    assert any("boom" in e for e in errors), errors


def test_a_request_off_the_machine_is_seen(browser, tmp_path):
    """An image from a remote host shows up in external_requests (it cannot load here)."""
    page = tmp_path / "q.html"
    page.write_text("<html><body><img src='https://example.invalid/x.png'></body></html>")
    external_requests(browser)  # clear the log
    open_page(browser, page)
    assert any("example.invalid" in u for u in external_requests(browser))
