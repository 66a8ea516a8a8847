"""The browser page in headless Chromium, measured (a benchmark, not a test): the .wasm's size, the
time from navigation to the first result on screen, the simulation's speed in the page against
the same run natively, and the page's agreement with the native FMU preset by preset. Writes
bench/web.md and the page's screenshot docs/img/web_page.png.

    cargo run --release --bin hsp -- package        # the FMU, and docs/web/hsp.wasm beside the page
    .venv/bin/python bench/web_speed.py [--rounds 5]

Speed: the page opened with ?speed=fast&stop=10 (the default move, 10 s at 1 ms communication
steps, drawn as it goes), each round in a fresh Chromium (cold cache: the module is compiled
anew, and its first run goes partly through V8's baseline code before the optimised code takes
over), then the same run again in the same page (warm: what a user sees once the first run is
done), from the disk (file://, as an FMU's documentation is opened, the module from its base64
script) and served over HTTP from 127.0.0.1 (the module by fetch()). "In the page" is simulated
time over the run's wall time, drawing included; "model" is simulated time over the time spent
stepping only. Native: the same run (the same settings, r before every step, the same outputs
read after every step) through the same API (`bench-web-native`), in the same session.
"""

import argparse
import json
import pathlib
import statistics
import subprocess
import sys
import tempfile

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "python"))

from selenium.webdriver.common.by import By  # noqa: E402

from webpage import RECORDED, choose_preset, chrome, deviation, native, serve, wait_for_run  # noqa: E402

PAGE = ROOT / "docs" / "web"
FMU = ROOT / "fmu" / "HydraulicSlewingPlate.fmu"
PRESETS = ["complete", "complete-hub-locked", "servo-valve-motor", "loes-motor", "paper-eq16",
           "paper-fig9b", "paper-fig10"]


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
                    step: r.stepMs, simulated: r.samples.t[r.samples.t.length - 1]};"""
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


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--out", default=str(ROOT / "bench" / "web.md"))
    parser.add_argument("--screenshot", default=str(ROOT / "docs" / "img" / "web_page.png"))
    args = parser.parse_args()
    wasm = (PAGE / "hsp.wasm").stat().st_size
    script = (PAGE / "hsp.wasm.js").stat().st_size
    subprocess.run(["cargo", "build", "--release", "--quiet", "--bin", "bench-web-native"],
                   cwd=ROOT, check=True)

    server = serve(PAGE)
    query = "index.html?speed=fast&stop=10"
    sources = {"file": (PAGE / "index.html").as_uri() + query[len("index.html"):],
               "http": f"http://127.0.0.1:{server.server_port}/{query}"}
    results = {k: [] for k in sources}
    native_walls = []
    version = "?"
    last_run = None
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(args.rounds):
            for kind, url in sources.items():
                run, timing, version = page_round(url, pathlib.Path(tmp) / f"{kind}{i}")
                results[kind].append(timing)
                last_run = run
            # The native run of the same job, in the same round.
            job = {"request": last_run["request"], "inputs": last_run["inputs"], "names": RECORDED,
                   "rounds": 1, "step": 1e-3}
            out = subprocess.run([str(ROOT / "target" / "release" / "bench-web-native")],
                                 input=json.dumps(job), capture_output=True, text=True, check=True)
            native_walls.append(json.loads(out.stdout)["wall_s"][0])
            print(f"round {i + 1}: " + ", ".join(
                f"{k} {r[-1]['simulated'] / (r[-1]['wall'] / 1000):.0f}x" for k, r in results.items())
                + f", native {10 / native_walls[-1]:.0f}x", flush=True)

        # Agreement with the native FMU, preset by preset, and the screenshot of the default.
        agreement = []
        driver = chrome(pathlib.Path(tmp) / "agreement")
        try:
            driver.get((PAGE / "index.html").as_uri() + "?speed=fast")
            wait_for_run(driver)
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
                print(f"{preset}: {dev[worst][0]:.1e} ({worst}), bit-identical {identical}", flush=True)
            choose_preset(driver, "complete")
            wait_for_run(driver)
            driver.save_screenshot(args.screenshot)
        finally:
            driver.quit()
    server.shutdown()

    native_factor = [10 / w for w in native_walls]
    lines = [
        "# The browser build in Chromium",
        "",
        "Written by `.venv/bin/python bench/web_speed.py` (method in its header) on this 2-core "
        f"x86-64 machine, headless Chromium {version}, {args.rounds} rounds; median (range).",
        "",
        f"Size: `hsp.wasm` {wasm:,} bytes; `hsp.wasm.js` (the same as base64, for pages opened "
        f"from the disk) {script:,} bytes.".replace(",", " ").replace("base64 ", "base64,"),
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
            lines.append(
                f"| {'disk (file://)' if kind == 'file' else 'HTTP (127.0.0.1)'} | {run_kind} "
                f"| {first[0] if wall == 'wall' else ''} | {first[1] if wall == 'wall' else ''} "
                f"| {median_range(page_factor, '{:.0f}')} | {median_range(model_factor, '{:.0f}')} "
                f"| {median_range(native_factor, '{:.0f}')} | {median_range(ratio, '{:.2f}')} |")
    lines += [
        "",
        "Agreement of the page with the native FMU (fmpy's FMU2Slave, the same settings and inputs, "
        "1 ms steps, 5 s): the largest difference of any recorded output over the run, relative to "
        "that output's range.",
        "",
        "| preset | settings the page adds | largest difference / range | worst output | bit-identical | "
        "validity warnings |",
        "| --- | --- | ---: | --- | --- | ---: |",
    ]
    for preset, run, worst, d, identical, warnings in agreement:
        command = "move" if run["request"]["settings"]["reference.angle"] != 0 else "step of r"
        lines.append(f"| {preset} | the controls' values, {command} | {d:.1e} | "
                     f"{worst if d > 0 else '–'} | "
                     f"{'yes' if identical else 'no'} | {warnings} |")
    pathlib.Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out} and {args.screenshot}")


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
