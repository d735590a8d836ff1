"""The verification page and a paper report page in a real browser (headless Chromium):
they load with no JavaScript error and no request leaving the machine, their tables sort
numerically by a numeric column both ways (by click and by keyboard), a details block
opens on click, the first screen is not blank, and nothing is cut off or overlaps, even
in a narrow window. Skips, saying why, where no browser can run (tests/browser.py)."""

from __future__ import annotations

import io
import re
import shutil
import time
import warnings
from pathlib import Path

import pytest

from browser import browser, console_errors, external_requests, open_page  # noqa: F401

DOCS = Path(__file__).resolve().parents[1] / "docs"

#: The first number of a cell ("1.5e-03 J", "45.2%", "1,234"), read independently of the page's script.
NUMBER = re.compile(r"^\s*[-+]?(\d[\d,]*(\.\d*)?|\.\d+)(e[-+]?\d+)?", re.IGNORECASE)


@pytest.fixture(scope="module")
def pages(tmp_path_factory) -> dict[str, Path]:
    """The verification page rebuilt from docs/validation.json (its figures beside it) and
    the report of the six presets' shortened runs."""
    from granplate.errors import YieldWarning
    from granplate.paper import report
    from granplate.results.document import to_html
    from granplate.verification.page import render_pages

    from short_results import short_results

    folder = tmp_path_factory.mktemp("pages")
    verify = folder / "verification"
    verify.mkdir()
    shutil.copy(DOCS / "validation.json", verify / "validation.json")
    (verify / "validation-figures").symlink_to(DOCS / "validation-figures", target_is_directory=True)
    render_pages(verify)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", YieldWarning)
        runs = short_results()
    paper = folder / "report.html"
    paper.write_text(to_html(report.build_report(runs, {}), folder), encoding="utf-8")
    return {"verification": verify / "validation.html", "report": paper}


def _open(driver, path: Path) -> None:
    """Open a page with the browser's logs emptied first (so what follows is the page's own)."""
    console_errors(driver)
    external_requests(driver)
    open_page(driver, path)
    time.sleep(0.2)  # let late errors reach the log


def _column(driver, table, col: int) -> list[str]:
    return driver.execute_script(
        "return Array.from(arguments[0].tBodies[0].rows).map(r => r.cells[arguments[1]].textContent.trim())", table, col
    )


def _header(driver, label: str):
    """(table, column index, th) of the first table with a header cell reading `label`."""
    for table in driver.find_elements("css selector", "table"):
        heads = table.find_elements("css selector", "thead th")
        for i, th in enumerate(heads):
            if th.text.replace("\u2195", "").replace("\u25b2", "").replace("\u25bc", "").strip() == label:
                return table, i, th
    raise AssertionError(f"no table has a column {label!r}")


def _numbers(cells: list[str]) -> list[float]:
    filled = [c for c in cells if c not in ("", "-", "nan")]
    assert filled and all(NUMBER.match(c) for c in filled), cells
    return [float(NUMBER.match(c).group(0).replace(",", "")) for c in filled]


@pytest.mark.parametrize("page", ["verification", "report"])
def test_page_loads_with_no_error_and_no_request_off_the_machine(browser, pages, page):
    """No JavaScript console error, no request but file:/data: ones, and every table has sort buttons."""
    _open(browser, pages[page])
    assert console_errors(browser) == []
    assert external_requests(browser) == []
    n_tables = browser.execute_script("return document.querySelectorAll('table').length")
    n_sortable = browser.execute_script("return document.querySelectorAll('table thead th button.sort').length")
    n_heads = browser.execute_script("return document.querySelectorAll('table thead th').length")
    assert n_tables > 1 and n_sortable == n_heads > 0


@pytest.mark.parametrize(
    "page, label",
    [("verification", "time [s]"), ("verification", "error"), ("report", "E_shock [J]"), ("report", "plate peak")],
)
def test_a_numeric_column_sorts_numerically_both_ways(browser, pages, page, label):
    """A click sorts the column ascending by value (not as text: scientific notation and
    percentages), a second click descending, blanks ("-") last both ways; the header says
    which (aria-sort); Enter on the focused header does the same."""
    from selenium.webdriver.common.keys import Keys

    _open(browser, pages[page])
    table, col, th = _header(browser, label)
    cells = _column(browser, table, col)
    before = _numbers(cells)
    assert len(set(before)) > 1
    button = th.find_element("css selector", "button.sort")
    button.click()
    up = _numbers(_column(browser, table, col))
    assert up == sorted(before) and th.get_attribute("aria-sort") == "ascending"
    button.click()
    down_cells = _column(browser, table, col)
    down = _numbers(down_cells)
    assert down == sorted(before, reverse=True) and th.get_attribute("aria-sort") == "descending"
    n_blank = len(cells) - len(before)
    assert all(c in ("", "-", "nan") for c in down_cells[len(down_cells) - n_blank :])
    button.send_keys(Keys.ENTER)
    assert _numbers(_column(browser, table, col)) == up and th.get_attribute("aria-sort") == "ascending"
    assert console_errors(browser) == []


def test_a_details_block_opens_on_click(browser, pages):
    """A collapsed details block hides its content; a click on its summary line shows it."""
    _open(browser, pages["verification"])
    block = browser.find_element("css selector", "details")
    inner = block.find_element("css selector", "summary + *")
    assert block.get_attribute("open") is None and not inner.is_displayed()
    summary = block.find_element("css selector", "summary")
    browser.execute_script("arguments[0].scrollIntoView({block: 'center'})", summary)
    summary.click()
    assert block.get_attribute("open") is not None and inner.is_displayed()


@pytest.mark.parametrize("page", ["verification", "report"])
def test_first_screen_is_not_blank(browser, pages, page):
    """The screenshot of the first screen has more than one colour and is not all white; the
    summary cards are on it."""
    import matplotlib.image as mpimg
    import numpy as np

    _open(browser, pages[page])
    image = mpimg.imread(io.BytesIO(browser.get_screenshot_as_png()), format="png")[..., :3]
    colours = np.unique(image.reshape(-1, 3), axis=0)
    assert len(colours) > 1 and not np.all(image == 1.0)
    top = browser.execute_script("return document.querySelector('.summary').getBoundingClientRect().bottom")
    assert 0 < top <= browser.execute_script("return window.innerHeight")


#: Every table box either fits or scrolls; the page itself never scrolls sideways; cells of
#: a header row and the summary's cards never overlap.
LAYOUT = """
const out = {boxes: [], page: [document.documentElement.scrollWidth, document.documentElement.clientWidth],
             overlaps: []};
for (const box of document.querySelectorAll('.table-box')) {
  const r = box.getBoundingClientRect();
  out.boxes.push([box.scrollWidth, box.clientWidth, getComputedStyle(box).overflowX, r.right]);
}
function overlapping(els) {
  const rs = Array.from(els).map(e => e.getBoundingClientRect());
  for (let i = 0; i < rs.length; i++) for (let j = i + 1; j < rs.length; j++) {
    const a = rs[i], b = rs[j];
    if (a.left < b.right - 1 && b.left < a.right - 1 && a.top < b.bottom - 1 && b.top < a.bottom - 1) return true;
  }
  return false;
}
for (const row of document.querySelectorAll('thead tr, tbody tr:first-child')) {
  if (overlapping(row.cells)) out.overlaps.push(row.textContent.slice(0, 80));
}
if (overlapping(document.querySelectorAll('.card'))) out.overlaps.push('cards');
return out;
"""


@pytest.mark.parametrize("page", ["verification", "report"])
@pytest.mark.parametrize("width", [1280, 700])
def test_nothing_is_cut_off_or_overlaps(browser, pages, page, width):
    """At 1280 and 700 px wide: every table fits its box or the box scrolls, no box reaches past
    the window, the page does not scroll sideways, and no cells or cards overlap."""
    browser.set_window_size(width, 900)
    try:
        _open(browser, pages[page])
        layout = browser.execute_script(LAYOUT)
    finally:
        browser.set_window_size(1280, 900)
    page_width, view = layout["page"]
    assert page_width <= view, f"the page scrolls sideways ({page_width} > {view} px)"
    for scroll, client, overflow, right in layout["boxes"]:
        assert scroll <= client or overflow in ("auto", "scroll"), (scroll, client, overflow)
        assert right <= view + 1
    assert layout["overlaps"] == []
    if width == 700 and page == "verification":
        assert any(s > c for s, c, _, _ in layout["boxes"]), "the wide check table should scroll in its box"
