#!/usr/bin/env python3
"""The FMI 3.0 FMU from Python: fmpy's FMI 3 API, with the FMU's array variables.

What it shows
    fmu/fmi3/HydraulicSlewingPlate.fmu declares two arrays (modelDescription.xml, <Dimension>):
    `acc` (12 accelerometers of a 4 x 3 grid on one arm of the plate, m/s^2, an output) and
    `plate.f` (the plate model's 20 lowest natural frequencies, Hz, a calculated parameter). One
    value reference reads a whole array: fmi3GetFloat64 with nValues = the array's size.
    The script
      1. reads the model description and prints each array with its dimension;
      2. runs the FMU's default slewing move with FMU3Slave (co-simulation, 5 ms communication
         step; --stop, default 3 s) and reads `plate.f` after initialisation and `acc` at every
         step, each in one call;
      3. prints the natural frequencies against `hsp modes --json` (the project's tool computes
         them in Rust, without the FMU), and the RMS of each accelerometer as the 4 x 3 grid;
      4. checks the tip accelerometer acc[11] (x = a, y = b/2) against the scalar outputs:
         acc_tip (the tip's acceleration relative to the hub frame) plus a times the hub's
         angular acceleration (d omega_hub / dt, by central differences), the rigid part.
    Writes fmi3_arrays.png (the grid's RMS and the tip check) into --out.

How to run (from the repository root, after `cargo run --release --bin hsp -- package`):
    .venv/bin/python examples/fmi3_arrays.py [--fmu fmu/fmi3/HydraulicSlewingPlate.fmu] [--out results/examples]
It calls `cargo run --release --bin hsp -- modes --json` unless you pass its output with --modes FILE.
"""

import argparse
import json
import pathlib
import shutil
import subprocess
import sys

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave

ROOT = pathlib.Path(__file__).resolve().parents[1]
STEP = 5e-3


def modes(path):
    if path:
        return json.loads(pathlib.Path(path).read_text())
    out = subprocess.run(["cargo", "run", "--release", "--quiet", "--bin", "hsp", "--", "modes", "--json"],
                         cwd=ROOT, capture_output=True, text=True, check=True).stdout
    return json.loads(out)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--fmu", default=str(ROOT / "fmu" / "fmi3" / "HydraulicSlewingPlate.fmu"))
    ap.add_argument("--out", default=str(ROOT / "results" / "examples"), help="output folder")
    ap.add_argument("--modes", metavar="FILE", help="output of hsp modes --json")
    ap.add_argument("--stop", type=float, default=3.0, help="stop time [s]")
    a = ap.parse_args(argv)
    out = pathlib.Path(a.out)
    out.mkdir(parents=True, exist_ok=True)

    md = read_model_description(a.fmu)
    assert md.fmiVersion == "3.0", md.fmiVersion
    var = {v.name: v for v in md.modelVariables}
    arrays = {v.name: [int(d.start) for d in v.dimensions] for v in md.modelVariables if v.dimensions}
    for name, dims in arrays.items():
        v = var[name]
        print(f"array {name}{dims}: {v.type}, causality {v.causality}, unit {v.unit}, "
              f"value reference {v.valueReference}")
    n_acc, n_f = arrays["acc"][0], arrays["plate.f"][0]
    scalars = ["acc_tip", "omega_hub", "theta_hub", "w_tip"]
    plate_a = float(var["plate.a"].start)

    unzipped = extract(a.fmu)
    try:
        fmu = FMU3Slave(guid=md.guid, unzipDirectory=unzipped,
                        modelIdentifier=md.coSimulation.modelIdentifier, instanceName="fmi3")
        fmu.instantiate()
        fmu.enterInitializationMode(startTime=0.0, stopTime=a.stop)
        fmu.exitInitializationMode()
        f_hz = np.array(fmu.getFloat64([var["plate.f"].valueReference], n_f))
        refs = [var[n].valueReference for n in scalars]
        steps = int(round(a.stop / STEP))
        acc, sc = [], []
        for i in range(steps + 1):
            acc.append(fmu.getFloat64([var["acc"].valueReference], n_acc))
            sc.append(fmu.getFloat64(refs))
            if i < steps:
                fmu.doStep(currentCommunicationPoint=i * STEP, communicationStepSize=STEP)
        fmu.terminate()
        fmu.freeInstance()
    finally:
        shutil.rmtree(unzipped, ignore_errors=True)
    t = np.arange(steps + 1) * STEP
    acc, sc = np.array(acc), np.array(sc)

    # Natural frequencies: the FMU's array against the project's tool.
    ref = np.array(modes(a.modes)["f_hz"])
    k = min(len(ref), n_f)
    nonzero = f_hz[f_hz > 0]
    dev = np.max(np.abs(f_hz[:k] - ref[:k]) / np.maximum(ref[:k], 1e-300))
    print(f"\nplate.f (one call, {n_f} values, {len(nonzero)} non-zero) [Hz]: "
          + " ".join(f"{f:.4g}" for f in nonzero[:8]) + (" ..." if len(nonzero) > 8 else ""))
    print(f"max relative difference plate.f vs hsp modes --json: {dev:.2e} ({k} frequencies)")

    # Accelerometer grid: RMS over the run, rows x = a/4 ... a, columns y = b/6, b/2, 5b/6.
    rms = np.sqrt(np.mean(acc ** 2, axis=0)).reshape(4, 3)
    print(f"\nacc RMS over {a.stop:g} s [m/s^2] (acc read as one array of {n_acc} per step):")
    print(f"{'':10s}{'y = b/6':>10s}{'y = b/2':>10s}{'y = 5b/6':>10s}")
    for i in range(4):
        print(f"x = {i + 1}a/4 " + "".join(f"{v:10.4f}" for v in rms[i]))

    # The tip accelerometer = relative + rigid: acc[11] = acc_tip + a * d(omega_hub)/dt.
    alpha = np.gradient(sc[:, 1], t)
    rigid = sc[:, 0] + plate_a * alpha
    inner = slice(2, -2)
    tip_err = np.max(np.abs(acc[inner, 10] - rigid[inner])) / np.max(np.abs(acc[:, 10]))
    print(f"\ntip check: max |acc[11] - (acc_tip + a d omega_hub/dt)| / max |acc[11]| = {tip_err:.2e} "
          f"(central differences at {STEP * 1e3:g} ms)")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    im = axes[0].imshow(rms, origin="lower", cmap="viridis", aspect="auto")
    axes[0].set_xticks(range(3), ["b/6", "b/2", "5b/6"])
    axes[0].set_yticks(range(4), ["a/4", "a/2", "3a/4", "a"])
    axes[0].set_xlabel("y across the plate")
    axes[0].set_ylabel("x from the hub axis")
    axes[0].set_title("RMS of acc[1..12] over the move [m/s²]")
    fig.colorbar(im, ax=axes[0])
    axes[1].plot(t, acc[:, 10], label="acc[11] (array element)")
    axes[1].plot(t, rigid, "--", label="acc_tip + a dω_hub/dt (scalars)")
    axes[1].set_xlabel("time [s]")
    axes[1].set_ylabel("m/s²")
    axes[1].set_title("tip accelerometer")
    axes[1].legend(fontsize=8)
    axes[1].grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "fmi3_arrays.png", dpi=100)
    plt.close(fig)
    print(f"wrote {out / 'fmi3_arrays.png'}")


if __name__ == "__main__":
    sys.exit(main())
