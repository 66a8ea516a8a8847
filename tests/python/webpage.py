"""The browser page's helpers shared by tests/python/test_web.py and bench/web_speed.py: Debian's
chromium driven by Selenium, the page's run as the page keeps it, the same run through the
native FMU, and their comparison."""

import functools
import http.server
import shutil
import threading

import numpy as np
from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import Select, WebDriverWait

from conftest import apply_preset, make_slave, set_values

STEP = 1e-3
# The outputs the page records at every communication point (RECORDED in docs/web/page.js).
RECORDED = ["controller.reference", "y_pot", "theta_motor", "theta_hub", "w_tip", "p_load",
            "servo_valve.p_1", "servo_valve.p_2", "controller.e_out",
            "plate.w_tip_ratio", "plate.stress", "torsion_bar.stress", "hub.omega_ratio"]
AGREEMENT = 1e-9


def chrome(tmp, net_log=None, size="1400,1300"):
    """Debian's chromium through its chromedriver (no download by Selenium)."""
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    driver = shutil.which("chromedriver")
    assert chromium and driver, "tests/setup.sh installs chromium and chromium-driver"
    options = webdriver.ChromeOptions()
    options.binary_location = chromium
    for flag in ["--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync",
                 "--no-first-run", f"--user-data-dir={tmp / 'profile'}", f"--window-size={size}"]:
        options.add_argument(flag)
    if net_log:
        options.add_argument(f"--log-net-log={net_log}")
    return webdriver.Chrome(service=Service(driver), options=options)


def wait_for_run(driver, timeout=120):
    """Waits until the page's current run is done and drawn (or failed to start) and returns its
    state."""
    WebDriverWait(driver, timeout).until(lambda d: d.execute_script(
        "const p = window.hspPage; return !!p && (!!p.error || !!(p.run && p.run.shown));"))
    return page_state(driver)


def page_state(driver):
    """The page's run as the page keeps it (its recorded points as plain arrays), its error and
    its status."""
    return driver.execute_script("""
        const p = window.hspPage, r = p.run, rec = p.recorded ? p.recorded() : {};
        return {error: p.error, failed: r && r.failed, request: r && r.request,
                samples: rec.samples || null, inputs: rec.inputs || null,
                forces: rec.forces || null,
                messages: r && r.messages, status: document.getElementById('status').textContent,
                status_class: document.getElementById('status').className, id: r && r.id,
                runs: p.runs};""")


@functools.lru_cache(maxsize=None)
def _md_and_dir(fmu_path):
    from fmpy import extract, read_model_description
    return read_model_description(fmu_path), extract(fmu_path)


def native(fmu_path, run):
    """The page's run through the packaged FMU's C ABI (fmpy's low-level FMU2Slave): the same
    preset and settings, the same communication steps with the same r set before each, the same
    outputs at every point (and the shakers' forces before each step when the page drove them)."""
    request = run["request"]
    md, unzipped = _md_and_dir(fmu_path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = make_slave(md, unzipped, name="native")
    try:
        if request["preset"]:
            apply_preset(slave, md, request["preset"])
        set_values(slave, md, request["settings"])
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        refs = [vr[n] for n in RECORDED]
        rows = [slave.getReal(refs)]
        t = 0.0
        forces = run.get("forces") or []
        for k, r in enumerate(run["inputs"]):
            slave.setReal([vr["r"]], [r])
            if forces:  # the shakers' F1, F2 of the step, as the page set them
                slave.setReal([vr["F1"], vr["F2"]], forces[2 * k:2 * k + 2])
            slave.doStep(t, STEP)
            t += STEP  # the FMU's own time, as the page reads it (the same sum of steps)
            rows.append(slave.getReal(refs))
        return np.array(rows)
    finally:
        slave.freeInstance()


def deviation(page_samples, native_rows):
    """Per output: the largest |page - native| over the run relative to the output's range, and
    whether every value is the same double."""
    out = {}
    for k, name in enumerate(RECORDED):
        p = np.array(page_samples[name], dtype=float)
        n = native_rows[:, k]
        assert p.shape == n.shape, (name, p.shape, n.shape)
        span = np.ptp(n)
        diff = np.max(np.abs(p - n))
        out[name] = (diff / span if span > 0 else diff, bool(np.array_equal(p, n)))
    return out


def choose_preset(driver, preset):
    """Chooses a preset, which starts a new run (the Run button when it is already chosen)."""
    select = Select(driver.find_element(By.ID, "preset"))
    if select.first_selected_option.get_attribute("value") == preset:
        driver.find_element(By.ID, "run").click()
    else:
        select.select_by_value(preset)


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


def serve(directory):
    """A static HTTP server of `directory` on 127.0.0.1 (a free port) in a thread; call
    shutdown() when done."""
    handler = functools.partial(_QuietHandler, directory=str(directory))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server
