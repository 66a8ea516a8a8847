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
    for name in ["index.html", "page.css", "hsp.js", "worker.js", "controls.js", "plots.js",
                 "plate.js", "status.js", "export.js", "page.js", "hsp.wasm", "hsp.wasm.js"]:
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
    retype(driver.find_element(By.ID, field), text)


def retype(box, text):
    """Types `text` into the field `box` in place of its value and leaves it."""
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
    # At real time: as fast as possible, the model now runs the page's longest run (600 s) in a
    # few seconds, and the run could end before the click.
    open_page(probe, page_dir, "?speed=realtime&stop=600")
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


# ---------------------------------------------------------------- the parameter panel (issue 42)

def xml_groups():
    """Each parameter's group as modelDescription.xml groups them (the comment before it in
    <ModelVariables>), and its display unit, read here with Python's own parser."""
    import xml.etree.ElementTree as ET
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True))
    root = ET.parse(ROOT / "modelDescription" / "modelDescription.xml", parser).getroot()
    units = {u.get("name"): [d.get("name") for d in u.findall("DisplayUnit")]
             for u in root.find("UnitDefinitions")}
    groups, shown, group = {}, {}, None
    for node in root.find("ModelVariables"):
        if node.tag is ET.Comment:
            group = " ".join(node.text.split())
        elif node.get("causality") == "parameter":
            groups[node.get("name")] = group
            t = node[0]
            unit = t.get("unit")
            shown[node.get("name")] = t.get("displayUnit") or (units.get(unit) or [unit])[0]
    return groups, shown


def panel_rows(driver):
    return driver.execute_script("""
        return [...document.querySelectorAll('#parameter-groups tr[data-name]')].map((tr) => ({
            name: tr.dataset.name, group: tr.closest('details').dataset.group,
            unit: tr.querySelector('td.unit').textContent, preset: tr.querySelector('td.preset').textContent,
            range: tr.querySelector('td.range').textContent, value: tr.querySelector('td.value > *').value,
            disabled: tr.querySelector('td.value > *').disabled,
            description: tr.querySelector('.desc').textContent, changed: tr.classList.contains('changed')}));""")


def panel_field(driver, name):
    """The panel's field of a parameter, its group opened."""
    driver.execute_script("""document.querySelector(`#parameter-groups tr[data-name="${arguments[0]}"]`)
        .closest('details').open = true;""", name)
    return driver.find_element(By.CSS_SELECTOR, f'#parameter-groups tr[data-name="{name}"] td.value > *')


def test_the_parameter_panel_shows_every_parameter_as_the_xml_declares_it(probe, page_dir, md):
    open_page(probe, page_dir, "?speed=fast&preset=loes-motor")
    wait_for_run(probe)
    rows = {r["name"]: r for r in panel_rows(probe)}
    # Every parameter of the packaged FMU's model description (read by fmpy), in its XML group
    # and display unit (read by Python's XML parser), with its description.
    parameters = {v.name: v for v in md.modelVariables if v.causality == "parameter"}
    assert set(rows) == set(parameters), set(rows) ^ set(parameters)
    groups, shown = xml_groups()
    for name, v in parameters.items():
        assert rows[name]["group"] == groups[name], (name, rows[name]["group"], groups[name])
        assert rows[name]["unit"] == ("" if shown[name] in (None, "1") else shown[name]), name
        assert rows[name]["description"] == v.description, name
    assert rows["controller.k_pot"]["unit"] == "V/deg"
    assert rows["servo_valve.p_supply"]["unit"] == "bar" and rows["servo_valve.p_supply"]["preset"] == "140"
    assert rows["solver.rtol"]["range"] == "1e-15 … 1"
    # The preset's value (loes-motor's switch to the LOES), in the display unit (cm3/rad).
    assert rows["hydraulics.model"]["preset"] == "1 = Loes", rows["hydraulics.model"]
    assert rows["loes.D_m"]["unit"] == "cm3/rad" and rows["loes.D_m"]["preset"] == "80.3787285294"
    # What the controls set is shown, not edited.
    assert rows["controller.A1"]["disabled"] and rows["controller.A1"]["value"] == "2"
    assert rows["loes.D_m"]["disabled"] and not rows["servo_valve.D_m"]["disabled"]


def test_a_panel_value_is_checked_run_and_carried_by_the_address(probe, page_dir):
    open_page(probe, page_dir, "?speed=fast&stop=1")
    first = wait_for_run(probe)
    # Beyond the model's range: refused, named with the parameter and its limit; nothing runs.
    rtol = panel_field(probe, "solver.rtol")
    retype(rtol, "2")
    WebDriverWait(probe, 10).until(lambda d: d.execute_script("return hspPage.error"))
    state = page_state(probe)
    assert state["id"] == first["id"], "a run started with solver.rtol = 2"
    assert "solver.rtol" in state["error"] and "above the model's maximum of 1" in state["error"], \
        state["error"]
    assert rtol.get_attribute("aria-invalid") is not None
    retype(rtol, "abc")
    WebDriverWait(probe, 10).until(lambda d: "'abc' is not a number" in d.execute_script("return hspPage.error"))
    retype(rtol, "1e-6")
    # In the display unit: 120 bar of supply pressure is 1.2e7 Pa for the model.
    supply = panel_field(probe, "servo_valve.p_supply")
    retype(supply, "120")
    run = wait_for_run(probe)
    assert run["id"] > first["id"] and run["error"] is None, run["error"]
    assert run["request"]["settings"]["servo_valve.p_supply"] == 1.2e7, run["request"]["settings"]
    assert "solver.rtol" not in run["request"]["settings"]  # the preset's value again
    assert {r["name"] for r in panel_rows(probe) if r["changed"]} == {"servo_valve.p_supply"}
    link = probe.current_url
    assert "servo_valve.p_supply=12000000" in link, link
    # The JSON settings carry it; the link opened again runs it to the same doubles.
    probe.get("about:blank")
    open_page(probe, page_dir, link[link.index("?"):])
    again = wait_for_run(probe)
    assert again["request"] == run["request"] and again["samples"] == run["samples"]
    assert panel_field(probe, "servo_valve.p_supply").get_attribute("value") == "120"
    # A parameter the controls set is refused from the address, by name.
    state = open_page(probe, page_dir, "?speed=fast&controller.A1=3")
    assert state["runs"] == 0 and "'controller.A1' in the address is set by the page's control 'A1'" \
        in state["error"], state["error"]


def test_the_shakers_drive_the_plate_of_paper_fig10(probe, page_dir, fmu_path):
    open_page(probe, page_dir, "?speed=fast&preset=complete")
    wait_for_run(probe)
    assert not probe.find_element(By.ID, "shakers").is_displayed()
    open_page(probe, page_dir, "?speed=fast&preset=paper-fig10&stop=1.5&F1=2&F2=-1&shaker_f=3")
    run = wait_for_run(probe)
    assert probe.find_element(By.ID, "shakers").is_displayed()
    assert run["error"] is None and run["failed"] is None, (run["error"], run["failed"])
    forces = run["forces"]
    assert len(forces) == 2 * len(run["inputs"]) == 2 * 1500
    # 2 N and -1 N times sin(2 pi 3 Hz (t - 0.5 s)) from the preset's start, 0.5 s.
    k = 600  # the step from t = 0.6 s
    wave = np.sin(2 * np.pi * 3 * (run["samples"]["t"][k] - 0.5))
    assert forces[2 * k] == pytest.approx(2 * wave, rel=1e-12) and forces[2 * k + 1] == pytest.approx(-wave, rel=1e-12)
    assert forces[2 * 100] == 0
    assert max(abs(w) for w in run["samples"]["w_tip"]) > 1e-5  # the plate is shaken
    # The same forces through the native FMU: the same outputs.
    dev = deviation(run["samples"], native(fmu_path, run))
    worst = max(dev, key=lambda n: dev[n][0])
    assert dev[worst][0] <= AGREEMENT, (worst, dev[worst])


def test_the_ssv_download_applied_by_the_fmu_gives_the_pages_run(probe, page_dir, fmu_path, tmp_path):
    from conftest import read_ssv
    probe.execute_cdp_cmd("Browser.setDownloadBehavior",
                          {"behavior": "allow", "downloadPath": str(tmp_path)})
    open_page(probe, page_dir, "?speed=fast&stop=2&A1=3&servo_valve.p_supply=12000000&preset=complete")
    run = wait_for_run(probe)
    assert run["request"]["settings"]["servo_valve.p_supply"] == 1.2e7
    probe.find_element(By.ID, "download-ssv").click()
    probe.find_element(By.ID, "download-json").click()
    WebDriverWait(probe, 20).until(lambda d: list(tmp_path.glob("*.ssv")) and list(tmp_path.glob("*.json")))
    # The panel's setting is in the JSON settings too.
    settings = json.loads(next(tmp_path.glob("*.json")).read_text())["settings"]
    assert settings["servo_valve.p_supply"] == 1.2e7 and settings["controller.A1"] == 3
    text = next(tmp_path.glob("*.ssv")).read_text()
    assert "<ssv:ParameterSet" in text and "the browser page" in text
    values = read_ssv(text)
    # The preset's settings and the page's over them, in one set the FMU applies alone.
    assert values["hydraulics.model"] == 2 and values["controller.A1"] == 3
    assert values["servo_valve.p_supply"] == 1.2e7
    alone = {**run, "request": {"preset": "", "settings": values}}
    dev = deviation(run["samples"], native(fmu_path, alone))
    worst = max(dev, key=lambda n: dev[n][0])
    identical = all(same for _, same in dev.values())
    print(f".ssv through fmpy: worst {worst} {dev[worst][0]:.3e} of its range; bit-identical: {identical}")
    assert dev[worst][0] <= AGREEMENT, (worst, dev[worst])


# ---------------------------------------------------------------- plots to read (issue 42)

@pytest.fixture(scope="module")
def plots(page_dir, tmp_path_factory):
    """The FMU's page from the disk in a browser of its own, after the default move."""
    driver = chrome(tmp_path_factory.mktemp("plots"))
    open_page(driver, page_dir, "?speed=fast")
    wait_for_run(driver)
    yield driver
    driver.quit()


def plot_point(driver, canvas_id, fraction):
    """The offset from the canvas's centre (CSS pixels) of the point at `fraction` of its frame's
    width, halfway up."""
    return driver.execute_script("""
        const c = document.getElementById(arguments[0]), lay = hspPage.layout[arguments[0]];
        const r = c.getBoundingClientRect(), k = r.width / c.width;
        const x = (lay.frame.x + arguments[1] * lay.frame.w) * k, y = (lay.frame.y + lay.frame.h / 2) * k;
        return [Math.round(x - r.width / 2), Math.round(y - r.height / 2)];""", canvas_id, fraction)


def test_the_legends_sit_outside_the_data(plots):
    layout = plots.execute_script("return hspPage.layout")
    for canvas in ["plot-loop", "plot-angles", "plot-tip", "plot-pressures"]:
        frame = layout[canvas]["frame"]
        assert layout[canvas]["legend"], canvas
        for box in layout[canvas]["legend"]:
            assert box["y"] + box["h"] <= frame["y"], (canvas, box, frame)  # above the frame


def test_hovering_a_plot_reads_its_values(plots):
    from selenium.webdriver.common.action_chains import ActionChains
    driver = plots
    canvas = driver.find_element(By.ID, "plot-loop")
    dx, dy = plot_point(driver, "plot-loop", 0.3)
    ActionChains(driver).move_to_element_with_offset(canvas, dx, dy).perform()
    readout = driver.execute_script("return hspPage.readout")
    run = page_state(driver)
    i = readout["i"]
    span = driver.execute_script("return hspPage.layout['plot-loop']")
    assert abs(readout["t"] - (span["x0"] + 0.3 * (span["x1"] - span["x0"]))) < 0.02, readout
    assert readout["t"] == run["samples"]["t"][i]
    assert readout["values"]["y_pot"] == run["samples"]["y_pot"][i]
    assert readout["values"]["reference"] == run["samples"]["controller.reference"][i]
    text = driver.find_element(By.ID, "readout").text
    assert driver.find_element(By.ID, "readout").is_displayed() and f"t = {readout['t']:.3f} s" in text, text
    ActionChains(driver).move_by_offset(0, 400).perform()


def test_dragging_zooms_every_plot_and_a_double_click_shows_the_whole_run(plots):
    from selenium.webdriver.common.action_chains import ActionChains
    driver = plots
    run = wait_for_run(driver)
    canvas = driver.find_element(By.ID, "plot-tip")
    a, y = plot_point(driver, "plot-tip", 0.25)
    b, _ = plot_point(driver, "plot-tip", 0.5)
    ActionChains(driver).move_to_element_with_offset(canvas, a, y).click_and_hold() \
        .move_by_offset((b - a) // 2, 0).move_by_offset(b - a - (b - a) // 2, 0).release().perform()
    view = driver.execute_script("return hspPage.view")
    stop = run["samples"]["t"][-1]
    assert view and abs(view["x0"] - 0.25 * stop) < 0.03 and abs(view["x1"] - 0.5 * stop) < 0.03, view
    layout = driver.execute_script("return hspPage.layout")
    for canvas_id in ["plot-loop", "plot-angles", "plot-tip", "plot-pressures"]:
        assert (layout[canvas_id]["x0"], layout[canvas_id]["x1"]) == (view["x0"], view["x1"])
    # The zoomed plot's range is that of the points in the span, not of the whole run.
    tip = np.array(run["samples"]["w_tip"]) * 1e3
    t = np.array(run["samples"]["t"])
    inside = tip[(t >= view["x0"]) & (t <= view["x1"])]
    lo, hi = layout["plot-tip"]["lo"], layout["plot-tip"]["hi"]
    pad = 0.06 / 1.12 * (hi - lo)
    assert lo + pad == pytest.approx(inside.min(), rel=1e-9) or np.ptp(inside) == 0
    driver.execute_script("""document.getElementById('plot-tip').dispatchEvent(
        new MouseEvent('dblclick', {bubbles: true}))""")
    WebDriverWait(driver, 5).until(lambda d: d.execute_script(
        "return hspPage.view === null && hspPage.layout['plot-tip'].x1 === hspPage.run.stop"))


def scrub(driver, t):
    driver.execute_script("""const c = document.getElementById('cursor'); c.value = arguments[0];
        c.dispatchEvent(new Event('input'));""", t)
    WebDriverWait(driver, 5).until(lambda d: d.execute_script(
        "return hspPage.plateView && Math.abs(hspPage.plateView.t - arguments[0]) < 0.002", t))
    return driver.execute_script("return hspPage.plateView")


def test_the_time_cursor_scrubs_the_plate_through_the_run(plots):
    driver = plots
    run = wait_for_run(driver)
    w_tip = run["samples"]["w_tip"]
    views = []
    for t in (0.0, 1.2, 2.0, 4.5):
        view = scrub(driver, t)
        # The drawn plate at the cursor is the model's state then: its tip is w_tip there.
        assert view["tip"] == pytest.approx(w_tip[view["at"]], rel=1e-12, abs=1e-15), view
        assert f"t = {view['t']:.3f} s" in driver.find_element(By.ID, "plate-caption").text
        views.append(view)
    assert abs(views[0]["tip"]) < 1e-12 and abs(views[1]["tip"]) > 1e-3  # at rest at t = 0
    # The cursor drawn on the plots; "Follow the run" lets go of it.
    assert driver.execute_script("return hspPage.cursor") == 4.5
    driver.find_element(By.ID, "cursor-live").click()
    assert driver.execute_script("return hspPage.cursor") is None


def test_the_face_view_keeps_one_colour_scale_with_its_legend(plots):
    driver = plots
    wait_for_run(driver)
    run = page_state(driver)
    early, late = scrub(driver, 1.2), scrub(driver, 4.5)
    # One scale for the run, whatever the deflection at the cursor: a 1-2-5 number at or above
    # the run's largest deflection (at least its tip's).
    scale = early["scale"]
    assert late["scale"] == scale, (early, late)
    assert scale >= max(abs(w) for w in run["samples"]["w_tip"])
    mantissa = scale / 10 ** np.floor(np.log10(scale))
    assert min(abs(mantissa - m) for m in (1, 2, 5)) < 1e-9, scale
    assert early["wmax"] != late["wmax"] and max(early["wmax"], late["wmax"]) <= scale
    driver.find_element(By.ID, "cursor-live").click()


def test_the_previous_run_is_overlaid_dimmed(plots):
    from selenium.webdriver.common.action_chains import ActionChains
    driver = plots
    choose_preset(driver, "complete")
    before = wait_for_run(driver)
    change(driver, "duration", "1")
    after = wait_for_run(driver)
    assert after["id"] > before["id"]
    layout = driver.execute_script("return hspPage.layout")
    assert layout["plot-tip"]["overlay"] == before["id"]
    assert any("previous" in box["label"] for box in layout["plot-tip"]["legend"])
    # The readout gives both runs' values at the time under the pointer.
    dx, dy = plot_point(driver, "plot-tip", 0.3)
    ActionChains(driver).move_to_element_with_offset(driver.find_element(By.ID, "plot-tip"), dx, dy).perform()
    readout = driver.execute_script("return hspPage.readout")
    assert readout["previous"]["w_tip"] == before["samples"]["w_tip"][readout["i"]] * 1e3
    assert readout["values"]["w_tip"] == after["samples"]["w_tip"][readout["i"]] * 1e3
    # Off: no overlay.
    driver.find_element(By.ID, "overlay").click()
    WebDriverWait(driver, 5).until(lambda d: d.execute_script("return hspPage.layout['plot-tip'].overlay") is None)
    driver.find_element(By.ID, "overlay").click()
    change(driver, "duration", "2")
    wait_for_run(driver)


def test_a_plate_at_rest_is_said_to_be_and_not_exaggerated(probe, page_dir):
    # The servo valve on the motor alone: the motor is not coupled to the hub, the plate is not
    # driven (no shaker force).
    open_page(probe, page_dir, "?speed=fast&preset=servo-valve-motor&stop=1")
    run = wait_for_run(probe)
    assert max(abs(w) for w in run["samples"]["w_tip"]) < 1e-6
    view = probe.execute_script("return hspPage.plateView")
    assert view["atRest"] and view["exaggeration"] == 1 and "the plate is at rest" in view["label"], view
    open_page(probe, page_dir, "?speed=fast&stop=1")
    wait_for_run(probe)
    view = probe.execute_script("return hspPage.plateView")
    assert not view["atRest"] and view["exaggeration"] > 1 and "drawn ×" in view["label"], view


def test_a_narrow_window_shows_the_whole_page(page_dir, tmp_path):
    # The narrowest window headless Chromium makes (it widens 420 px to 500): nothing is cut off
    # at the right, the parameter panel's open tables scrolling within their box.
    driver = chrome(tmp_path, size="420,900")
    try:
        open_page(driver, page_dir, "?speed=fast")
        wait_for_run(driver)
        driver.execute_script(
            "document.querySelectorAll('#parameter-groups details').forEach((d) => { d.open = true; })")
        width, window = driver.execute_script(
            "return [document.documentElement.scrollWidth, window.innerWidth]")
        assert width <= window, (width, window)
    finally:
        driver.quit()


def test_a_switch_in_the_panel_moves_the_controls_with_it(probe, page_dir, md):
    from selenium.webdriver.support.ui import Select
    start = {v.name: v.start for v in md.modelVariables}
    # A preset's motor displacement runs as the model has it, not as the 6 digits shown.
    open_page(probe, page_dir, "?speed=fast&stop=0.5&preset=loes-motor")
    run = wait_for_run(probe)
    assert probe.find_element(By.ID, "D_m").get_attribute("value") == "80.3787"
    assert run["request"]["settings"]["loes.D_m"] == float(start["loes.D_m"])
    # The complete system switched to the LOES in the panel: the motor control sets the LOES's
    # displacement, the pressures plotted are the LOES's, the full valve's D_m is the panel's.
    open_page(probe, page_dir, "?speed=fast&stop=0.5")
    wait_for_run(probe)
    Select(panel_field(probe, "hydraulics.model")).select_by_value("1")
    run = wait_for_run(probe)
    settings = run["request"]["settings"]
    assert settings["hydraulics.model"] == 1 and settings["loes.D_m"] == float(start["loes.D_m"])
    assert "servo_valve.D_m" not in settings, settings
    assert panel_field(probe, "loes.D_m").get_attribute("disabled") is not None
    assert panel_field(probe, "servo_valve.D_m").get_attribute("disabled") is None
    assert probe.find_element(By.ID, "pressure-caption").text == "Load pressure [bar]"
    # The motor uncoupled in the panel: the shakers are offered; the address carries both.
    Select(panel_field(probe, "hydraulics.motor_coupled")).select_by_value("false")
    wait_for_run(probe)
    assert probe.find_element(By.ID, "shakers").is_displayed()
    link = probe.current_url
    assert "hydraulics.model=1" in link and "hydraulics.motor_coupled=false" in link, link
    probe.get("about:blank")
    again = open_page(probe, page_dir, link[link.index("?"):])
    assert again["error"] is None and wait_for_run(probe)["request"]["settings"]["hydraulics.model"] == 1
    assert probe.find_element(By.ID, "shakers").is_displayed()
