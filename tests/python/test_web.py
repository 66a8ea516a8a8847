"""The interactive page with the browser build (docs/web/, and documentation/web/ in the FMU), in
headless Chromium driven by Selenium through Debian's chromedriver: the page from the FMU loads
from the disk with no request leaving the machine, runs the default move, shows what a native
run of the FMU gives for the same settings, changes its result when a control moves, and draws
a real picture; and it refuses what it cannot take by name (text in a number field, a value
beyond a field's limits, an unknown preset), marks the results on screen stale when it does,
shows validity warnings at the top and in the status's colour, and keeps Pause, Resume and Reset
consistent (the tests after "the page's defects", each of which fails on the page before them).

The agreement with the native FMU is asserted to 1e-9 of each output's range (the same Rust code
on both sides: only libm's last bits may differ, the browser's WebAssembly build using Rust's
own libm and the native build the system's); which presets agree to the bit is printed and
written in docs/web.md from bench/web_speed.py's run."""

import json
import time
import zipfile

import numpy as np
import pytest

from selenium.webdriver.common.by import By
from selenium.webdriver.common.keys import Keys
from selenium.webdriver.support.ui import WebDriverWait

from conftest import ROOT, page_requests
from figures import assert_png
from webpage import (AGREEMENT, choose_preset, chrome, deviation, native, page_state, serve,
                     wait_for_run)

def go_fast(driver):
    driver.find_element(By.CSS_SELECTOR, 'input[name="speed"][value="fast"]').click()


@pytest.fixture(scope="module")
def page_dir(fmu_path, tmp_path_factory):
    """documentation/web/ of the packaged FMU, unpacked as an importer's tool would."""
    out = tmp_path_factory.mktemp("fmu-doc")
    with zipfile.ZipFile(fmu_path) as z:
        for name in z.namelist():
            if name.startswith("documentation/"):
                z.extract(name, out)
    return out / "documentation" / "web"


@pytest.fixture(scope="module")
def browser(page_dir, tmp_path_factory):
    """The FMU's page opened from the disk; the net log is read when the module's tests end."""
    tmp = tmp_path_factory.mktemp("chromium")
    net_log = tmp / "net.json"
    driver = chrome(tmp, net_log)
    driver.get((page_dir / "index.html").as_uri())
    state = {"driver": driver, "net_log": net_log, "first": None}
    yield state
    driver.quit()


@pytest.fixture(scope="module")
def first_run(browser):
    """The run the page starts by itself on load (the default move), finished as fast as
    possible."""
    driver = browser["driver"]
    WebDriverWait(driver, 60).until(lambda d: d.execute_script(
        "return !!(window.hspPage && (hspPage.run || hspPage.error))"))
    go_fast(driver)
    return wait_for_run(driver)


def test_the_page_runs_the_default_move_from_the_disk(first_run):
    assert first_run["error"] is None, first_run["error"]
    assert first_run["failed"] is None, first_run["failed"]
    assert first_run["request"]["preset"] == "complete"
    t = first_run["samples"]["t"]
    assert len(t) == 5001 and abs(t[-1] - 5.0) < 1e-9, (len(t), t[-1])
    assert "5.0 s simulated" in first_run["status"], first_run["status"]
    # The default move: 30 degrees of motor angle, with no validity warning.
    assert abs(np.degrees(first_run["samples"]["theta_motor"][-1]) - 30) < 0.2
    assert not [m for m in first_run["messages"] if m["status"] != "ok"], first_run["messages"]
    # Loaded from the script form of the module (browsers refuse fetch() on file:// pages).
    assert first_run and first_run["samples"]


@pytest.mark.parametrize("preset", ["complete", "servo-valve-motor", "loes-motor", "paper-fig9b"])
def test_the_page_agrees_with_the_native_fmu(browser, first_run, fmu_path, preset):
    driver = browser["driver"]
    before = driver.execute_script("return hspPage.run.id")
    choose_preset(driver, preset)
    run = wait_for_run(driver)
    assert run["id"] > before and run["request"]["preset"] == preset
    assert run["error"] is None and run["failed"] is None, (run["error"], run["failed"])
    rows = native(fmu_path, run)
    dev = deviation(run["samples"], rows)
    worst = max(dev, key=lambda n: dev[n][0])
    identical = all(same for _, same in dev.values())
    print(f"{preset}: worst {worst} {dev[worst][0]:.3e} of its range; bit-identical: {identical}")
    assert dev[worst][0] <= AGREEMENT, (preset, worst, dev[worst])


def test_moving_a_control_changes_the_result(browser, first_run):
    driver = browser["driver"]
    choose_preset(driver, "complete")
    default = wait_for_run(driver)
    peak = max(abs(v) for v in default["samples"]["w_tip"])
    duration = driver.find_element(By.ID, "duration")
    duration.clear()
    duration.send_keys("1", Keys.TAB)  # the change event: a new run
    fast = wait_for_run(driver)
    assert fast["id"] > default["id"]
    assert fast["request"]["settings"]["reference.duration"] == 1
    peak_fast = max(abs(v) for v in fast["samples"]["w_tip"])
    # The same 30 degrees in half the time: four times the acceleration bends the plate more.
    assert peak_fast > 1.5 * peak, (peak, peak_fast)
    shown = driver.find_element(By.CSS_SELECTOR, '#summary tr[data-key="peak_w_tip"]')
    assert float(shown.get_attribute("data-value")) == peak_fast
    duration.clear()
    duration.send_keys("2", Keys.TAB)
    wait_for_run(driver)


def test_the_slider_drives_r_while_the_run_goes_on(browser, first_run):
    driver = browser["driver"]
    driver.find_element(By.CSS_SELECTOR, 'input[name="speed"][value="realtime"]').click()
    driver.find_element(By.CSS_SELECTOR, 'input[name="command"][value="slider"]').click()
    slider = driver.find_element(By.ID, "r")
    assert slider.is_enabled()
    id_before = driver.execute_script("return hspPage.run.id")
    slider.send_keys(*[Keys.ARROW_RIGHT] * 50)  # 50 steps of 0.01 V: r = 0.5 V
    run = wait_for_run(driver, timeout=60)
    assert run["id"] == id_before, "moving the slider must not restart the run"
    ref, y = run["samples"]["controller.reference"], run["samples"]["y_pot"]
    assert ref[0] == 0 and abs(ref[-1] - 0.5) < 1e-12, (ref[0], ref[-1])
    # The loop follows r (about its mean over the last second: the plate's slow mode rings on).
    assert abs(np.mean(y[-1000:]) - 0.5) < 0.01, np.mean(y[-1000:])
    go_fast(driver)
    driver.find_element(By.CSS_SELECTOR, 'input[name="command"][value="move"]').click()
    wait_for_run(driver)


def test_the_page_draws_a_real_picture(browser, first_run, tmp_path):
    driver = browser["driver"]
    drawn = driver.execute_script("""
        return [...document.querySelectorAll('canvas')].map(c => {
          const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
          let inked = 0;
          for (let i = 3; i < d.length; i += 4) if (d[i] > 0) inked++;
          return [c.id, inked];
        });""")
    assert len(drawn) == 6, drawn
    for canvas, inked in drawn:
        assert inked > 2000, (canvas, inked)
    shot = tmp_path / "page.png"
    driver.save_screenshot(str(shot))
    assert_png(shot.read_bytes(), min_width=1200, min_height=1000, min_bytes=60_000)


def test_no_request_leaves_the_machine(browser, first_run):
    # The net log is complete once the browser is closed.
    browser["driver"].quit()
    assert page_requests(browser["net_log"]) == []


def test_served_over_http_the_page_fetches_the_wasm_and_gives_the_same_run(page_dir, tmp_path,
                                                                            fmu_path):
    server = serve(page_dir)
    driver = chrome(tmp_path)
    try:
        driver.get(f"http://127.0.0.1:{server.server_port}/index.html?speed=fast")
        run = wait_for_run(driver)
        assert run["error"] is None and run["failed"] is None
        # fetch() got hsp.wasm: the base64 script was never loaded.
        assert driver.execute_script("return typeof globalThis.HSP_WASM_BASE64") == "undefined"
        rows = native(fmu_path, run)
        dev = deviation(run["samples"], rows)
        assert max(d for d, _ in dev.values()) <= AGREEMENT, dev
    finally:
        driver.quit()
        server.shutdown()


def test_the_repository_page_is_the_fmus(page_dir):
    """docs/web/ (the sources, and the module `hsp package` writes beside them) is what the FMU
    carries."""
    for name in ["index.html", "page.js", "page.css", "hsp.js", "worker.js", "hsp.wasm",
                 "hsp.wasm.js"]:
        assert (ROOT / "docs" / "web" / name).read_bytes() == (page_dir / name).read_bytes(), name
    assert (page_dir / "hsp.wasm").stat().st_size < 1_500_000
    text = (page_dir / "hsp.wasm.js").read_text()
    assert json.loads(text[text.index('"'):text.rindex('"') + 1])  # a non-empty string literal


# ---------------------------------------------------------------- the page's defects (issue 42)

@pytest.fixture(scope="module")
def probe(page_dir, tmp_path_factory):
    """A browser of its own for the pages opened with an address's settings."""
    driver = chrome(tmp_path_factory.mktemp("probe"))
    yield driver
    driver.quit()


def open_page(driver, page_dir, query):
    """Opens the FMU's page with `query` and waits until it has run, or refused to."""
    driver.get((page_dir / "index.html").as_uri() + query)
    WebDriverWait(driver, 60).until(lambda d: d.execute_script(
        "const p = window.hspPage; return !!p && (!!p.error || !!(p.run && p.run.samples.t.length))"))
    return page_state(driver)


def change(driver, field, text):
    """Types `text` into a field in place of its value and leaves it (the change event)."""
    box = driver.find_element(By.ID, field)
    box.send_keys(Keys.CONTROL, "a")
    box.send_keys(Keys.DELETE)
    box.send_keys(text, Keys.TAB)


def visible(driver, element_id):
    """Whether the element is shown within the window as it opens (no scrolling)."""
    return driver.execute_script("""
        const e = document.getElementById(arguments[0]);
        if (!e || e.hidden) return false;
        const r = e.getBoundingClientRect();
        return r.height > 0 && r.top >= 0 && r.bottom <= window.innerHeight;""", element_id)


def test_text_in_a_number_field_is_named_and_nothing_runs(probe, page_dir):
    state = open_page(probe, page_dir, "?A1=abc&speed=fast")
    assert state["runs"] == 0, "a run started with the gain the browser dropped (0)"
    assert "Error amplifier A1" in state["error"] and "'abc' is not a number" in state["error"], \
        state["error"]
    assert state["status_class"] == "error" and state["error"] in state["status"]
    assert probe.find_element(By.ID, "A1").get_attribute("aria-invalid") is not None
    # Typed: what the browser's number field does not take is refused by name; no run starts.
    state = open_page(probe, page_dir, "?speed=fast")
    wait_for_run(probe)
    change(probe, "A1", "abc")
    after = page_state(probe)
    assert after["runs"] == 1, "a run started with a silent 0"
    assert after["error"] and after["error"].startswith("Not run: Error amplifier A1: "), after["error"]


@pytest.mark.parametrize("query, field, limit", [
    ("?angle=720", "Angle [deg]", "90"), ("?angle=-1e6", "Angle [deg]", "-90"),
    ("?duration=0.01", "Duration [s]", "0.1"), ("?stop=1e6", "Stop time [s]", "600"),
])
def test_the_pages_limits_are_enforced(probe, page_dir, query, field, limit):
    state = open_page(probe, page_dir, query + "&speed=fast")
    assert state["runs"] == 0, f"{query} ran"
    assert f"{field}: " in state["error"] and f"limit of {limit}" in state["error"], state["error"]
    # The stop time's bound is stated beside it.
    assert "Up to 600 s" in probe.find_element(By.ID, "stop-note").text


def test_results_are_marked_stale_after_an_error(probe, page_dir):
    open_page(probe, page_dir, "?speed=fast")
    shown = wait_for_run(probe)
    assert not visible(probe, "stale")
    change(probe, "bar_k", "-5")
    WebDriverWait(probe, 30).until(lambda d: d.execute_script("return hspPage.error"))
    state = page_state(probe)
    assert visible(probe, "stale") and "Stale" in probe.find_element(By.ID, "stale").text
    assert "stale" in probe.find_element(By.ID, "results").get_attribute("class")
    assert "Torsion bar k [N·m/rad]: -5 is below" in state["error"], state["error"]
    assert state["id"] == shown["id"], "the results on screen are the last run's"
    # A value the page takes and the model refuses: the model's message, the same marking.
    change(probe, "bar_k", "1e308")
    WebDriverWait(probe, 30).until(lambda d: "absurd" in (d.execute_script("return hspPage.error") or ""))
    state = page_state(probe)
    assert state["error"].startswith("create: torsion_bar.k: 1e308 is physically absurd"), state["error"]
    assert state["id"] == shown["id"] and state["status_class"] == "error"
    assert visible(probe, "stale")
    # Good settings again: a new run, no longer marked.
    change(probe, "bar_k", "2500")
    fresh = wait_for_run(probe)
    assert fresh["id"] > shown["id"] and fresh["error"] is None
    assert not visible(probe, "stale")


def test_validity_warnings_are_above_the_fold_and_colour_the_status(probe, page_dir):
    # The paper's 2 V step (30 degrees through k_pot) trips the monitors on the default plant.
    open_page(probe, page_dir, "?command=step&angle=30&speed=fast")
    run = wait_for_run(probe)
    warnings = [m["message"] for m in run["messages"] if m["status"] == "warning"]
    assert warnings, run["messages"]
    assert run["status_class"] == "warning" and "validity warning" in run["status"], run["status"]
    colour = probe.execute_script(
        "return getComputedStyle(document.getElementById('status')).color")
    assert colour == "rgb(180, 83, 9)", colour  # page.css's amber, not the green of a clean run
    assert visible(probe, "alerts")
    assert warnings[0] in probe.find_element(By.ID, "alerts").text
    # A clean run: green, no alerts.
    open_page(probe, page_dir, "?speed=fast")
    run = wait_for_run(probe)
    assert run["status_class"] == "ok" and not visible(probe, "alerts")


def test_pause_resume_and_reset_stay_consistent(probe, page_dir):
    open_page(probe, page_dir, "?speed=fast&stop=600")
    now = "return hspPage.run.time"
    WebDriverWait(probe, 60).until(lambda d: d.execute_script(now) > 1)
    pause = probe.find_element(By.ID, "pause")
    pause.click()
    assert pause.text == "Resume"
    # A control changed while paused: a new run, which is not paused.
    before = page_state(probe)["id"]
    change(probe, "A1", "3")
    assert page_state(probe)["id"] == before + 1
    assert pause.text == "Pause" and pause.is_enabled(), pause.text
    WebDriverWait(probe, 30).until(lambda d: d.execute_script(now) > 1)
    # Paused, it stops (the worker says so) and stays; resumed, it goes on.
    pause.click()
    assert pause.text == "Resume"
    WebDriverWait(probe, 10).until(lambda d: d.execute_script("return hspPage.timing.pauseActed"))
    t = probe.execute_script(now)
    time.sleep(0.3)
    assert probe.execute_script(now) == t < 600, "the run goes on while paused"
    pause.click()
    assert pause.text == "Pause"
    WebDriverWait(probe, 30).until(lambda d: d.execute_script(now) > t)
    # Reset: the page as it opens, the slider disabled.
    probe.find_element(By.CSS_SELECTOR, 'input[name="command"][value="slider"]').click()
    assert probe.find_element(By.ID, "r").is_enabled()
    probe.find_element(By.ID, "reset").click()
    assert not probe.find_element(By.ID, "r").is_enabled()
    assert probe.find_element(By.ID, "stop").get_attribute("value") == "5"
    assert probe.find_element(By.CSS_SELECTOR, 'input[name="command"]:checked').get_attribute(
        "value") == "move"
    done = wait_for_run(probe)
    assert done["request"]["settings"]["controller.A1"] == 2 and pause.text == "Pause"
    assert not pause.is_enabled()  # nothing to pause once the run is done


def test_an_unknown_preset_in_the_address_is_refused(probe, page_dir):
    state = open_page(probe, page_dir, "?preset=nope&colour=red&speed=fast")
    assert state["runs"] == 0
    assert "preset 'nope' in the address is not one of the presets (complete, " in state["error"]
    assert "'colour' in the address is not a setting of the page" in state["error"]
    assert state["status_class"] == "error"
    # The list shows a preset, not a blank.
    assert probe.find_element(By.ID, "preset").get_attribute("value") == "complete"


# ---------------------------------------------------------------- taking results away (issue 42)

def test_the_address_carries_the_settings_and_reproduces_the_run(probe, page_dir):
    open_page(probe, page_dir, "?speed=fast&preset=loes-motor")
    wait_for_run(probe)
    change(probe, "A1", "3")
    first = wait_for_run(probe)
    link = probe.current_url
    assert "preset=loes-motor" in link and "A1=3" in link and "speed=fast" in link, link
    # The link's own box and the copy button show the same address.
    probe.find_element(By.ID, "copy-link").click()
    WebDriverWait(probe, 5).until(lambda d: d.execute_script("return hspPage.copied"))
    assert probe.find_element(By.ID, "link").get_attribute("value") == link
    assert probe.find_element(By.ID, "link-note").text
    # Opened again, the link runs the same settings to the same doubles.
    probe.get("about:blank")
    again = open_page(probe, page_dir, link[link.index("?"):])
    again = wait_for_run(probe)
    assert again["request"] == first["request"], (again["request"], first["request"])
    assert again["samples"] == first["samples"] and again["inputs"] == first["inputs"]


def test_results_download_as_csv_and_settings_as_json(probe, page_dir, tmp_path):
    probe.execute_cdp_cmd("Browser.setDownloadBehavior",
                          {"behavior": "allow", "downloadPath": str(tmp_path)})
    open_page(probe, page_dir, "?speed=fast&command=step&angle=10&stop=2")
    run = wait_for_run(probe)
    probe.find_element(By.ID, "download-csv").click()
    probe.find_element(By.ID, "download-json").click()
    WebDriverWait(probe, 20).until(lambda d: len(
        [f for f in tmp_path.iterdir() if f.suffix in (".csv", ".json")]) == 2)
    csv_file = next(tmp_path.glob("*.csv"))
    json_file = next(tmp_path.glob("*.json"))
    lines = csv_file.read_text().splitlines()
    header = lines[0].split(",")
    assert header[:3] == ["time [s]", "r [V]", "controller.reference [V]"], header
    assert "theta_hub [rad]" in header and "p_load [Pa]" in header, header
    rows = [line.split(",") for line in lines[1:]]
    assert len(rows) == len(run["samples"]["t"]) == 2001
    # Every value is the page's double, to the last bit.
    assert [float(r[0]) for r in rows] == run["samples"]["t"]
    assert rows[0][1] == "" and [float(r[1]) for r in rows[1:]] == run["inputs"]
    for k, name in enumerate(header[2:]):
        assert [float(r[2 + k]) for r in rows] == run["samples"][name.split(" ")[0]], name
    settings = json.loads(json_file.read_text())
    assert settings["preset"] == "complete" and settings["settings"] == run["request"]["settings"]
    assert settings["stop_time"] == 2 and settings["step_size"] == 1e-3
    assert settings["command"] == "step" and "r steps from 0 to" in settings["input_r"]
    assert settings["address"] == probe.current_url
