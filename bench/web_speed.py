"""The browser page in headless Chromium, measured (a benchmark, not a test): the .wasm's size, the
time from navigation to the first result on screen, the simulation's speed in the page against
the same run natively, and the page's agreement with the native FMU preset by preset. Writes
bench/web.md and the page's screenshot docs/img/web_page.png.

    cargo run --release --bin hsp -- package        # the FMU, and docs/web/hsp.wasm beside the page
    .venv/bin/python bench/web_speed.py [--rounds 5] [--before REV] [--parts speed,pause,agreement,screenshot]

Speed: the page opened with ?speed=fast&stop=10 (the default move, 10 s at 1 ms communication
steps, drawn as it goes), each round in a fresh Chromium (cold cache: the module is compiled
anew, and its first run goes partly through V8's baseline code before the optimised code takes
over), then the same run again in the same page (warm: what a user sees once the first run is
done), from the disk (file://, as an FMU's documentation is opened, the module from its base64
script) and served over HTTP from 127.0.0.1 (the module by fetch()). "In the page" is simulated
time over the run's wall time, drawing included; "model" is simulated time over the time spent
stepping only. Native: the same run (the same settings, r before every step, the same outputs
read after every step) through the same API (`bench-web-native`), in the same session.

Pause: the page opened from the disk with ?speed=fast&stop=600 (the longest run the page takes),
paused by a click at a random moment (0 to 0.5 s, seeded) after the run's simulated time is seen
past 300 s (300 001 points recorded and drawn), sent as the browser's own mouse input
(DevTools' Input.dispatchMouseEvent: no script of Selenium's runs in the page first). The
latency is from the click's time stamp (the moment the bench sent it, handed to the browser with
the input) to the moment the simulation has stopped: for a page that steps on its own thread,
the end of its click handler (it stops stepping there); for a page that steps in a worker, the
worker's answer that it has stopped (hspPage.timing.pauseActed). Beside it: how long the
dispatch of the press and release took to come back, and the longest task of the page's thread
between the first result and the click (Chromium's long-task entries, 50 ms and more; 0: none).
With --before REV, the page's sources of commit REV (with this build's module) are measured in
the same rounds, interleaved, for the figures before and after: its speed from the disk, its
Pause in the same 600 s run, and in a 3000 s run paused after t = 2500 s (which this page
refuses: its stop time is at most 600 s).
"""

import argparse
import datetime
import json
import os
import pathlib
import random
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "python"))

from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.support.ui import WebDriverWait  # noqa: E402

from webpage import RECORDED, choose_preset, chrome, deviation, native, serve, wait_for_run  # noqa: E402

PAGE = ROOT / "docs" / "web"
FMU = ROOT / "fmu" / "HydraulicSlewingPlate.fmu"
DOC = ROOT / "docs" / "web.md"
SOURCES = ["index.html", "page.css", "hsp.js", "worker.js", "controls.js", "plots.js", "plate.js",
           "status.js", "export.js", "page.js"]  # src/bin/hsp/web.rs
PRESETS = ["complete", "complete-hub-locked", "servo-valve-motor", "loes-motor", "paper-eq16",
           "paper-fig9b", "paper-fig10"]
# The run's stop time and when it is paused [s]: early enough that the page, at 250x real time
# on the steady part of the run, is still running when the click comes (at most 0.5 s later).
PAUSE_STOP, PAUSE_AT = 600, 300
# A longer run for the page before (this page refuses stop times beyond 600 s).
LONG_STOP, LONG_AT = 3000, 2500

# Installed before the page's own scripts: the long tasks of the page's thread, and the Pause
# click's time stamp and the end of the page's handling of it.
INSTRUMENT = """
window.__bench = {tasks: [], clicked: 0, handled: 0};
new PerformanceObserver((list) => {
  for (const e of list.getEntries()) __bench.tasks.push([e.startTime, e.duration]);
}).observe({type: "longtask", buffered: true});
addEventListener("click", (e) => { if (e.target.id === "pause") __bench.clicked = e.timeStamp; }, true);
addEventListener("click", (e) => { if (e.target.id === "pause") __bench.handled = performance.now(); });
"""


def median_range(values, fmt):
    return f"{fmt.format(statistics.median(values))} ({fmt.format(min(values))}–{fmt.format(max(values))})"


def page_round(url, tmp):
    driver = chrome(tmp)
    try:
        driver.get(url)
        run = wait_for_run(driver)
        assert run["error"] is None and run["failed"] is None, (run["error"], run["failed"])
        script = """
            const p = hspPage, r = p.run;
            return {loaded: p.timing.loaded, first: p.timing.firstResult, wall: r.wallMs,
                    step: r.stepMs, simulated: r.time};"""
        timing = driver.execute_script(script)
        # The same run again in the same page (the Run button): the module's code is compiled
        # by then, as when a user tunes a control after the first run.
        driver.find_element(By.ID, "run").click()
        again = wait_for_run(driver)
        assert again["id"] == run["id"] + 1 and again["samples"] == run["samples"]
        warm = driver.execute_script(script)
        timing["warm_wall"], timing["warm_step"] = warm["wall"], warm["step"]
        return run, timing, driver.capabilities.get("browserVersion", "?")
    finally:
        driver.quit()


def pause_round(url, tmp, delay, stop=PAUSE_STOP, at=PAUSE_AT):
    """The Pause latency of one long run (see the header): {latency_ms, click_ms, longest_ms}.
    The click is sent `delay` seconds after the run is seen past `at` (a script that reads the
    page's state runs between two of its tasks: a click sent right after it would always find
    the page's thread free)."""
    driver = chrome(tmp)
    try:
        driver.execute_cdp_cmd("Page.addScriptToEvaluateOnNewDocument", {"source": INSTRUMENT})
        driver.get(url)
        now = "return window.hspPage && hspPage.run ? hspPage.run.time : -1"
        WebDriverWait(driver, 300, poll_frequency=0.2).until(
            lambda d: d.execute_script(now) >= 1)
        x, y = driver.execute_script("""
            const r = document.getElementById('pause').getBoundingClientRect();
            return [r.x + r.width / 2, r.y + r.height / 2];""")
        WebDriverWait(driver, 900, poll_frequency=0.5).until(
            lambda d: d.execute_script(now) >= at)
        time.sleep(delay)
        # The click as the browser's input (no script of Selenium's runs in the page first).
        t0 = time.perf_counter()
        sent = time.time()  # the events' time stamp (the page's clock is the machine's)
        for kind in ["mousePressed", "mouseReleased"]:
            driver.execute_cdp_cmd("Input.dispatchMouseEvent", {
                "type": kind, "x": x, "y": y, "button": "left", "clickCount": 1,
                "timestamp": sent})
        click_ms = 1000 * (time.perf_counter() - t0)
        acted = ("const p = hspPage; return p.timing.pauseActed !== undefined ? p.timing.pauseActed "
                 ": __bench.handled")
        try:
            WebDriverWait(driver, 60).until(lambda d: d.execute_script(acted))
        except Exception as e:
            state = driver.execute_script(
                "return [document.getElementById('status').textContent, __bench, hspPage.run.time]")
            raise RuntimeError(f"{url}: the Pause click did not act: {state}") from e
        stopped = driver.execute_script(acted)
        clicked, tasks, first = driver.execute_script(
            "return [__bench.clicked, __bench.tasks, hspPage.timing.firstResult]")
        # It has stopped: the simulated time stays.
        t_paused = driver.execute_script(now)
        time.sleep(0.5)
        assert driver.execute_script(now) == t_paused < stop, "the run did not pause"
        longest = max([d for start, d in tasks if first < start < clicked], default=0)
        return {"latency_ms": stopped - clicked, "click_ms": click_ms, "longest_ms": longest}
    finally:
        driver.quit()


def old_page(rev, out):
    """The page's sources at commit `rev`, with this build's module, in `out`."""
    out.mkdir(parents=True, exist_ok=True)
    for name in SOURCES + ["hsp.wasm", "hsp.wasm.js"]:
        shown = subprocess.run(["git", "show", f"{rev}:docs/web/{name}"], cwd=ROOT,
                               capture_output=True)
        if name.startswith("hsp.wasm"):
            (out / name).write_bytes((PAGE / name).read_bytes())
        elif shown.returncode == 0:
            (out / name).write_bytes(shown.stdout)
    return out


def copy_block(label, content, source):
    """Writes a timing block of bench/web.md into docs/web.md, saying where it comes from."""
    text = DOC.read_text()
    start, end = f"<!-- hsp timing: {label} -->\n", f"<!-- /hsp timing: {label} -->"
    head, rest = text.split(start, 1)
    _, tail = rest.split(end, 1)
    first, _, body = content.partition("\n")
    copied = f"{first} Copied from [`{source}`](../{source}).\n{body}"
    DOC.write_text(head + start + copied + end + tail)


def load_text(loads):
    return f"load {min(loads):.1f} to {max(loads):.1f} (1-minute load average over the run)"


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--pause-rounds", type=int, default=3)
    parser.add_argument("--before", metavar="REV",
                        help="also measure the Pause of the page's sources at commit REV")
    parser.add_argument("--parts", default="speed,pause,agreement,screenshot",
                        help="what to do (--parts screenshot: only the screenshot)")
    parser.add_argument("--out", default=str(ROOT / "bench" / "web.md"))
    parser.add_argument("--screenshot", default=str(ROOT / "docs" / "img" / "web_page.png"))
    args = parser.parse_args()
    parts = args.parts.split(",")
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    subprocess.run(["cargo", "build", "--release", "--quiet", "--bin", "bench-web-native"],
                   cwd=ROOT, check=True)
    loads = [os.getloadavg()[0]]
    version = "?"
    lines = []

    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        before = None
        if args.before:
            rev = subprocess.run(["git", "rev-parse", "--short", args.before], cwd=ROOT,
                                 capture_output=True, text=True, check=True).stdout.strip()
            before = (f"before (commit {rev})", old_page(args.before, tmp / "before"))
        if "speed" in parts:
            server = serve(PAGE)
            query = "index.html?speed=fast&stop=10"
            sources = {"file": (PAGE / "index.html").as_uri() + query[len("index.html"):],
                       "http": f"http://127.0.0.1:{server.server_port}/{query}"}
            if before:
                sources["before"] = (before[1] / "index.html").as_uri() + query[len("index.html"):]
            results = {k: [] for k in sources}
            native_walls = []
            last_run = None
            for i in range(args.rounds):
                for kind, url in sources.items():
                    run, timing, version = page_round(url, tmp / f"{kind}{i}")
                    results[kind].append(timing)
                    if kind == "file":
                        last_run = run
                # The native run of the same job, in the same round.
                job = {"request": last_run["request"], "inputs": last_run["inputs"],
                       "names": RECORDED, "rounds": 1, "step": 1e-3}
                out = subprocess.run([str(target / "release" / "bench-web-native")],
                                     input=json.dumps(job), capture_output=True, text=True,
                                     check=True)
                native_walls.append(json.loads(out.stdout)["wall_s"][0])
                loads.append(os.getloadavg()[0])
                print(f"round {i + 1}: " + ", ".join(
                    f"{k} {r[-1]['simulated'] / (r[-1]['wall'] / 1000):.0f}x"
                    for k, r in results.items())
                    + f", native {10 / native_walls[-1]:.0f}x, load {loads[-1]:.1f}", flush=True)
            server.shutdown()
            native_factor = [10 / w for w in native_walls]
            block = [
                f"Made by `.venv/bin/python bench/web_speed.py` on {datetime.date.today()}, "
                f"{load_text(loads)}.",
                "",
                "| page from | run | first result on screen (ms after navigation) | module ready (ms) | "
                "× real time in the page | × real time, model only | native × real time | "
                "model only / native |",
                "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |",
            ]
            for kind, rs in results.items():
                for run_kind, wall, step in [("first (cold)", "wall", "step"),
                                             ("second (warm)", "warm_wall", "warm_step")]:
                    page_factor = [r["simulated"] / (r[wall] / 1000) for r in rs]
                    model_factor = [r["simulated"] / (r[step] / 1000) for r in rs]
                    ratio = [m / n for m, n in zip(model_factor, native_factor)]
                    first = (median_range([r["first"] for r in rs], "{:.0f}"),
                             median_range([r["loaded"] for r in rs], "{:.0f}"))
                    source = {"file": "disk (file://)", "http": "HTTP (127.0.0.1)",
                              "before": f"disk (file://), {before[0] if before else ''}"}[kind]
                    block.append(
                        f"| {source} | {run_kind} "
                        f"| {first[0] if wall == 'wall' else ''} | {first[1] if wall == 'wall' else ''} "
                        f"| {median_range(page_factor, '{:.0f}')} "
                        f"| {median_range(model_factor, '{:.0f}')} "
                        f"| {median_range(native_factor, '{:.0f}')} | {median_range(ratio, '{:.2f}')} |")
            lines += ["<!-- hsp timing: web-speed -->", *block, "<!-- /hsp timing: web-speed -->", ""]
            copy_block("web-speed", "\n".join(block) + "\n", "bench/web.md")

        if "pause" in parts:
            cases = {f"this page, {PAUSE_STOP} s run": (PAGE, PAUSE_STOP, PAUSE_AT)}
            if before:
                cases = {f"{before[0]}, {PAUSE_STOP} s run": (before[1], PAUSE_STOP, PAUSE_AT),
                         **cases,
                         f"{before[0]}, {LONG_STOP} s run, clicked at t ≥ {LONG_AT} s":
                             (before[1], LONG_STOP, LONG_AT)}
            pause = {k: [] for k in cases}
            rng = random.Random(42)  # the delays of the clicks after the threshold, 0 to 0.5 s
            loads_pause = [os.getloadavg()[0]]
            for i in range(args.pause_rounds):
                for n, (kind, (directory, stop, at)) in enumerate(cases.items()):
                    url = (directory / "index.html").as_uri() + f"?speed=fast&stop={stop}"
                    delay = rng.uniform(0, 0.5)
                    pause[kind].append(pause_round(url, tmp / f"pause{i}-{n}", delay, stop, at))
                    loads_pause.append(os.getloadavg()[0])
                    print(f"pause round {i + 1}, {kind}: {pause[kind][-1]}", flush=True)
            block = [
                f"Made by `.venv/bin/python bench/web_speed.py"
                f"{f' --before {args.before}' if args.before else ''}` on {datetime.date.today()}, "
                f"{load_text(loads_pause)}.",
                "",
                f"| page | Pause latency (ms) | the click's dispatch returned after (ms) | "
                f"longest task of the page's thread during the run (ms) |",
                "| --- | ---: | ---: | ---: |",
            ]
            for kind, rs in pause.items():
                block.append(f"| {kind} | {median_range([r['latency_ms'] for r in rs], '{:.0f}')} "
                             f"| {median_range([r['click_ms'] for r in rs], '{:.0f}')} "
                             f"| {median_range([r['longest_ms'] for r in rs], '{:.0f}')} |")
            lines += [f"Pause in a run as fast as possible, clicked at t ≥ {PAUSE_AT} s of a "
                      f"{PAUSE_STOP} s run unless said ({args.pause_rounds} rounds, each in a fresh "
                      "browser):", "",
                      "<!-- hsp timing: web-pause -->", *block, "<!-- /hsp timing: web-pause -->", ""]
            copy_block("web-pause", "\n".join(block) + "\n", "bench/web.md")

        if "agreement" in parts:
            # Agreement with the native FMU, preset by preset, and the screenshot of the default.
            agreement = []
            driver = chrome(tmp / "agreement")
            try:
                driver.get((PAGE / "index.html").as_uri() + "?speed=fast")
                wait_for_run(driver)
                version = driver.capabilities.get("browserVersion", "?")
                for preset in PRESETS:
                    before = driver.execute_script("return hspPage.run.id")
                    choose_preset(driver, preset)
                    run = wait_for_run(driver)
                    assert run["id"] > before
                    dev = deviation(run["samples"], native(str(FMU), run))
                    worst = max(dev, key=lambda n: dev[n][0])
                    identical = all(same for _, same in dev.values())
                    warnings = sum(1 for m in run["messages"] if m["status"] == "warning")
                    agreement.append((preset, run, worst, dev[worst][0], identical, warnings))
                    print(f"{preset}: {dev[worst][0]:.1e} ({worst}), bit-identical {identical}",
                          flush=True)
            finally:
                driver.quit()
            lines += [
                "Agreement of the page with the native FMU (fmpy's FMU2Slave, the same settings "
                "and inputs, 1 ms steps, 5 s): the largest difference of any recorded output over "
                "the run, relative to that output's range.",
                "",
                "| preset | settings the page adds | largest difference / range | worst output | "
                "bit-identical | validity warnings |",
                "| --- | --- | ---: | --- | --- | ---: |",
            ]
            for preset, run, worst, d, identical, warnings in agreement:
                command = "move" if run["request"]["settings"]["reference.angle"] != 0 else "step of r"
                lines.append(f"| {preset} | the controls' values, {command} | {d:.1e} | "
                             f"{worst if d > 0 else '–'} | "
                             f"{'yes' if identical else 'no'} | {warnings} |")

        if "screenshot" in parts:
            # The page after the default move, the link box blanked (it shows where the page
            # was opened from: a path of this machine).
            driver = chrome(tmp / "screenshot")
            try:
                driver.get((PAGE / "index.html").as_uri() + "?speed=fast")
                wait_for_run(driver)
                driver.execute_script("document.getElementById('link').value = ''")
                driver.save_screenshot(args.screenshot)
            finally:
                driver.quit()
            if parts == ["screenshot"]:
                print(f"wrote {args.screenshot}")
                return

    size = lambda name: f"<!-- hsp docs: web-size {name} -->0<!-- /hsp docs: web-size -->"  # noqa: E731
    head = [
        "# The browser build in Chromium",
        "",
        "Written by `.venv/bin/python bench/web_speed.py` (method in its header) on this 2-core "
        f"x86-64 machine, headless Chromium {version}; median (range) of {args.rounds} rounds "
        f"(speed) and {args.pause_rounds} (Pause).",
        "",
        "Size (of the packaged FMU's `documentation/web/`, by `hsp docs`): `hsp.wasm` "
        f"{size('hsp.wasm')} bytes; `hsp.wasm.js` (the same as base64, for pages opened from the "
        f"disk) {size('hsp.wasm.js')} bytes.",
        "",
    ]
    pathlib.Path(args.out).write_text("\n".join(head + lines).rstrip("\n") + "\n")
    print(f"wrote {args.out}, {DOC} and {args.screenshot}; sizes: run `hsp docs`")


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
