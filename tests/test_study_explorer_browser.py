"""The study page in a real browser (headless Chromium, 1280 px wide; tests/browser.py):
it loads with no JavaScript error and no request off the machine, the front shows as many
points as feasible designs, a click shows that design's numbers, a filter changes the
visible count, a screenshot is not blank; the worked studies' committed pages render their
plots; a 10,000-design page opens in a few seconds. Where no browser can run, they skip
and say why."""

from __future__ import annotations

import io
import time
from pathlib import Path

import pytest

from browser import browser, console_errors, external_requests, open_page  # noqa: F401
from granplate.study import explorer as X
from test_study_explorer import LARGE, synthetic_outcome

STUDIES = Path(__file__).resolve().parent.parent / "docs" / "studies"
WORKED = ("intruder-map", "intruder-map-plastic", "calibration", "two-layer")
#: The most seconds a 10,000-design page may take to load and draw its first screen (a
#: few; docs/benchmarks.md has the measured time).
LARGE_LOAD_S = 15.0
N_SMALL = 200


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    """The page of a 200-trial synthetic optimisation (constraints, infeasible and failed
    trials), and its outcome."""
    folder = tmp_path_factory.mktemp("explorer-browser")
    out = synthetic_outcome(N_SMALL, folder)
    return X.write_explorer(out, {}, []), out


@pytest.fixture(scope="module")
def opened(browser, small):
    """The small page, loaded once for the module, its logs cleared before."""
    console_errors(browser)
    external_requests(browser)
    open_page(browser, small[0])
    wait_for(browser, "return document.querySelectorAll('#fig-main .scatterlayer .trace').length > 0")
    return browser, small[1]


@pytest.fixture()
def loaded(opened):
    """The small page as loaded: every filter off ('show all'), no panel, at its top."""
    driver, out = opened
    driver.execute_script(
        "document.getElementById('panel').hidden = true; window.scrollTo(0, 0);"
        "document.getElementById('reset').click();"
    )
    all_shown = "return document.getElementById('shown').textContent.indexOf('%d of') === 0" % N_SMALL
    wait_for(driver, all_shown)
    return driver, out


def wait_for(driver, script: str, timeout: float = 20.0) -> None:
    end = time.monotonic() + timeout
    while not driver.execute_script(script):
        if time.monotonic() > end:
            raise TimeoutError(script)
        time.sleep(0.05)


def shown_count(driver) -> int:
    text = driver.find_element("id", "shown").text
    return int(text.split(" of ")[0])


def test_page_loads_without_errors_or_requests_off_the_machine(loaded):
    """No SEVERE console entry, no URL outside file:// requested."""
    driver, _ = loaded
    assert console_errors(driver) == []
    assert external_requests(driver) == []


def test_front_view_has_as_many_points_as_feasible_designs(loaded):
    """The main view's first trace ('designs (feasible)') draws one SVG point per feasible
    completed design."""
    driver, out = loaded
    feasible = sum(1 for r in out.rows if r.ok and r.feasible)
    n = driver.execute_script(
        "return document.querySelectorAll('#fig-main .scatterlayer .trace')[0].querySelectorAll('path.point').length"
    )
    assert n == feasible > 0


def test_hovering_and_clicking_a_design_shows_its_numbers(loaded):
    """Hovering the star of the best design (with the mouse) names it with its parameters
    and metrics in the units shown (the modulus in MPa); a click opens the panel of that
    design with its metrics; a click on a column sorts the table by it, a click on a row
    opens that row's design."""
    from selenium.webdriver.common.action_chains import ActionChains

    driver, out = loaded
    from granplate.study.report import best_designs

    i = best_designs(out)["ep_max_fraction"]
    traces = driver.find_elements("css selector", "#fig-main .scatterlayer .trace")
    star = traces[-2].find_elements("css selector", "path.point")[0]  # best ep_max_fraction
    ActionChains(driver).move_to_element(star).perform()
    wait_for(driver, "return document.querySelectorAll('#fig-main .hoverlayer .hovertext').length > 0")
    hover = driver.find_element("css selector", "#fig-main .hoverlayer .hovertext").text
    r = out.rows[i]
    assert f"trial {r.number}" in hover
    assert f"materials.steel.E = {r.params['materials.steel.E'] * 1e-6:.4g} MPa" in hover
    assert f"max_von_mises = {r.metrics['max_von_mises'] * 1e-6:.4g} MPa" in hover
    ActionChains(driver).move_to_element(star).click().perform()
    wait_for(driver, "return !document.getElementById('panel').hidden")
    title = driver.find_element("id", "panel-title")
    assert title.get_attribute("data-design") == str(out.rows[i].number)
    values = {
        e.get_attribute("data-metric"): e.text for e in driver.find_elements("css selector", "#panel .metric-value")
    }
    assert values["ep_max_fraction"] == f"{out.rows[i].metrics['ep_max_fraction']:.4g}"
    assert values["max_von_mises"] == f"{out.rows[i].metrics['max_von_mises'] * 1e-6:.4g} MPa"
    driver.find_element("css selector", "#panel .close").click()
    assert not driver.find_element("id", "panel").is_displayed()
    # the table sorts by a metric's column: the least max_von_mises first, then the most
    header = next(
        th for th in driver.find_elements("css selector", "#designs thead th") if th.text.startswith("max_von_mises")
    )
    column = int(header.get_attribute("data-col"))
    driver.execute_script("arguments[0].scrollIntoView({block: 'center'})", header)
    header.click()
    least = min(r.metrics["max_von_mises"] for r in out.rows if r.ok)
    first = driver.find_elements("css selector", "#designs tbody tr")[0].find_elements("css selector", "td")
    assert first[column].text == f"{least * 1e-6:.4g}"
    driver.find_element("css selector", f"#designs thead th[data-col='{column}']").click()
    first = driver.find_elements("css selector", "#designs tbody tr")[0].find_elements("css selector", "td")
    assert first[column].text == f"{max(r.metrics['max_von_mises'] for r in out.rows if r.ok) * 1e-6:.4g}"
    row = driver.find_elements("css selector", "#designs tbody tr")[3]
    number = row.find_elements("css selector", "td")[0].text.split()[0]
    driver.execute_script("arguments[0].scrollIntoView({block: 'center'})", row)
    row.click()
    assert driver.find_element("id", "panel-title").get_attribute("data-design") == number


def test_filters_change_the_visible_count(loaded):
    """'feasible only' shows the feasible designs' count (the table as many rows, the
    parallel coordinates the others faint); a range brushed on a parallel-coordinates axis
    narrows it; 'show all' restores it."""
    driver, out = loaded
    assert shown_count(driver) == N_SMALL
    driver.find_element("id", "only-feasible").click()
    feasible = sum(1 for r in out.rows if r.ok and r.feasible)
    assert shown_count(driver) == feasible < N_SMALL
    assert len(driver.find_elements("css selector", "#designs tbody tr")) == feasible
    # the parallel coordinates show it: the lines filtered out are faint (colour 0.5)
    faint = driver.execute_script(
        "return document.getElementById('fig-parcoords').data[0].line.color"
        ".filter(function (c) { return c === 0.5; }).length"
    )
    assert faint == sum(1 for r in out.rows if r.ok) - feasible
    # brush the radius axis (layout.R1, in m) to its lower half
    driver.execute_script(
        "var pc = document.getElementById('fig-parcoords');"
        "var k = pc.data[0].dimensions.findIndex(function (d) { return d.name === 'layout.R1'; });"
        "var u = {}; u['dimensions[' + k + '].constraintrange'] = [[0.004, 0.0075]];"
        "Plotly.restyle(pc, u);"
    )
    both = sum(1 for r in out.rows if r.ok and r.feasible and r.params["layout.R1"] <= 0.0075)
    wait_for(driver, f"return document.getElementById('shown').textContent.indexOf('{both} of') === 0")
    assert shown_count(driver) == both < feasible
    driver.find_element("id", "reset").click()
    assert shown_count(driver) == N_SMALL


def test_a_box_drawn_on_the_front_filters_the_table(loaded):
    """Dragging a box over the left half of the front (select mode, with the mouse)
    leaves fewer designs shown, and the table lists only those."""
    from selenium.webdriver.common.action_chains import ActionChains

    driver, _ = loaded
    drag = driver.find_element("css selector", "#fig-main .nsewdrag")
    w, h = drag.size["width"], drag.size["height"]
    ActionChains(driver).move_to_element_with_offset(drag, -w // 2 + 5, -h // 2 + 5).click_and_hold().move_by_offset(
        w // 3, h // 2
    ).move_by_offset(w // 6, h // 2 - 10).release().perform()
    wait_for(driver, f"return document.getElementById('shown').textContent.indexOf('{N_SMALL} of') !== 0")
    n = shown_count(driver)
    assert 0 < n < N_SMALL
    assert len(driver.find_elements("css selector", "#designs tbody tr")) <= n


def test_screenshot_is_not_blank(loaded):
    """The first screen, as a PNG, has many colours and no single colour covers 97%."""
    from PIL import Image

    driver, _ = loaded
    image = Image.open(io.BytesIO(driver.get_screenshot_as_png())).convert("RGB")
    colours = image.getcolors(maxcolors=1 << 20)
    assert len(colours) > 50
    assert max(c for c, _ in colours) < 0.97 * image.width * image.height


@pytest.mark.parametrize("name", WORKED)
def test_worked_study_pages_render_their_plots_offline(browser, name):
    """Each committed worked page draws its plots (SVG or WebGL canvases) with no
    console error and no request off the machine."""
    console_errors(browser)
    external_requests(browser)
    open_page(browser, STUDIES / name / "report.html")
    wait_for(browser, "return document.querySelectorAll('#fig-main .main-svg').length > 0")
    assert browser.execute_script("return document.querySelectorAll('.js-plotly-plot').length") >= 3
    assert console_errors(browser) == []
    assert external_requests(browser) == []


def test_a_large_study_opens_in_a_few_seconds(browser, tmp_path):
    """A 10,000-design page (WebGL) loads and draws its first screen within LARGE_LOAD_S;
    the parallel coordinates below it are drawn once scrolled to."""
    page = X.write_explorer(synthetic_outcome(LARGE, tmp_path), {}, [])
    console_errors(browser)
    t0 = time.monotonic()
    open_page(browser, page, timeout=LARGE_LOAD_S)
    wait_for(
        browser,
        "return document.querySelectorAll('#fig-main canvas').length > 0 && "
        "document.querySelectorAll('#designs tbody tr').length > 0",
        LARGE_LOAD_S,
    )
    seconds = time.monotonic() - t0
    t1 = time.monotonic()
    browser.execute_script("document.getElementById('fig-parcoords').scrollIntoView()")
    wait_for(browser, "return document.querySelectorAll('#fig-parcoords canvas').length > 0", 4 * LARGE_LOAD_S)
    later = time.monotonic() - t1
    print(
        f"10,000-design page: {page.stat().st_size / 1e6:.1f} MB, first screen in {seconds:.1f} s, "
        f"parallel coordinates in {later:.1f} s more"
    )
    assert seconds < LARGE_LOAD_S
    assert console_errors(browser) == []


def test_a_filter_blanks_the_heat_map_cells_of_the_designs_it_hides(browser):
    """On a sweep's page (the intruder map, whose heat maps follow its front), a range brushed on a
    parallel-coordinates axis hides designs, and exactly their cells of the heat map go
    blank; 'show all' brings every cell back."""
    console_errors(browser)
    open_page(browser, STUDIES / "intruder-map" / "report.html")
    wait_for(
        browser,
        "var d = document.getElementById('fig-heat'); return d.data && d.data.some("
        "function (t) { return t.type === 'heatmap'; }) && document.getElementById('fig-parcoords').data",
    )
    total = shown_count(browser)
    blank = (
        "var d = document.getElementById('fig-heat'); var n = 0; d.data.forEach(function (t) {"
        " if (t.type !== 'heatmap') { return; } t.z.forEach(function (row, r) { row.forEach(function (v, c) {"
        " if (v === null && t.customdata[r][c] >= 0) { n += 1; } }); }); }); return n;"
    )
    hidden_cells = (
        "var s = new Set(Array.from(document.querySelectorAll('#designs tbody tr')).map(function (tr) {"
        " return tr.getAttribute('data-i'); })); var d = document.getElementById('fig-heat'); var n = 0;"
        " d.data.forEach(function (t) { if (t.type !== 'heatmap') { return; } t.customdata.forEach("
        " function (row) { row.forEach(function (i) { if (i >= 0 && !s.has(String(i))) { n += 1; } }); }); });"
        " return n;"
    )
    assert browser.execute_script(blank) == 0
    browser.execute_script(
        "var pc = document.getElementById('fig-parcoords'); var v = pc.data[0].dimensions[0].values;"
        "var lo = Math.min.apply(null, v), hi = Math.max.apply(null, v);"
        "Plotly.restyle(pc, {'dimensions[0].constraintrange': [[lo, lo + 0.5 * (hi - lo)]]});"
    )
    wait_for(browser, f"return document.getElementById('shown').textContent.indexOf('{total} of') !== 0")
    n_blank = browser.execute_script(blank)
    assert n_blank > 0
    assert n_blank == browser.execute_script(hidden_cells)
    browser.find_element("id", "reset").click()
    wait_for(browser, f"return document.getElementById('shown').textContent.indexOf('{total} of') === 0")
    assert browser.execute_script(blank) == 0
    assert console_errors(browser) == []
