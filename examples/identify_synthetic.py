#!/usr/bin/env python3
"""`hsp identify` on synthetic measurements (docs/identify.md): the worked example.

1. "Measures" the complete system's responses from r to y_pot and to acc_tip with `hsp frf` (the
   linearised model) at 200 log-spaced points from 0.5 to 120 Hz, with three parameters away
   from the defaults (the truth below), multiplies each point by 1 + n with n complex Gaussian
   noise of 1 % RMS (--noise; numpy, seed 1), and writes them as hsp identify's CSV
   (f_Hz,re,im).
2. Fits servo_valve.beta, plate.zeta and torsion_bar.k from the defaults with `hsp identify
   --json --out fitted.ssv` and prints each with the truth, the fitted value, its 95 % interval
   and whether the interval holds the truth; then the same fit for the seeds 2 to 20 (--seeds):
   how often each interval holds the truth, the mean error and the mean half-width.
3. Applies fitted.ssv (every parameter of the FMU) with fmpy's SSP reader, which validates it
   against the SSP 1.0 schema, to the packaged FMU and reads the three parameters back.
4. Asks for what the data cannot give: controller.A1 and controller.A2 with the load-pressure
   feedback off (the loop has their product only), and prints the command's warning.

Run (from the repository root, after `cargo run --release --bin hsp -- package`):
.venv/bin/python examples/identify_synthetic.py [--out DIR] [--fmu FMU] [--seeds N] [--noise RMS]
"""
import argparse
import json
import pathlib
import subprocess

import numpy as np
from fmpy import simulate_fmu
from fmpy.ssp.ssd import read_ssv

ROOT = pathlib.Path(__file__).resolve().parents[1]
TRUTH = {"servo_valve.beta": 1.0e9, "plate.zeta": 0.03, "torsion_bar.k": 3200.0}
OUTPUTS = ["y_pot", "acc_tip"]

ap = argparse.ArgumentParser()
ap.add_argument("--out", default=str(ROOT / "results" / "examples" / "identify"))
ap.add_argument("--fmu", default=str(ROOT / "fmu" / "HydraulicSlewingPlate.fmu"))
ap.add_argument("--seeds", type=int, default=20, help="noise seeds of the coverage count")
ap.add_argument("--noise", type=float, default=0.01, help="RMS of the relative complex noise")
a = ap.parse_args()
out = pathlib.Path(a.out)
out.mkdir(parents=True, exist_ok=True)


def hsp(*args):
    return subprocess.run(["cargo", "run", "--release", "--quiet", "--bin", "hsp", "--", *args],
                          cwd=ROOT, capture_output=True, text=True, check=True)


def responses(sets):
    """The model's responses from r to OUTPUTS with `sets`: {output: (f, H)}."""
    settings = [arg for name, v in sets.items() for arg in ("--set", f"{name}={v!r}")]
    out = {}
    for output in OUTPUTS:
        h = json.loads(hsp("frf", "--json", "--input", "r", "--output", output, "--from", "0.5",
                           "--to", "120", "--points", "200", *settings).stdout)
        out[output] = (np.array(h["f_hz"]), np.array(h["magnitude"]) * np.exp(1j * np.radians(h["phase_deg"])))
    return out


def measure(folder, exact, rng):
    """`exact` with complex noise of RMS a.noise from `rng`, as CSV files in `folder`: --frf
    arguments."""
    folder.mkdir(exist_ok=True)
    frfs = []
    for output, (f, H) in exact.items():
        H = H * (1 + a.noise * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) / np.sqrt(2))
        path = folder / f"{output}.csv"
        np.savetxt(path, np.column_stack([f, H.real, H.imag]), delimiter=",", header="f_Hz,re,im",
                   comments="", fmt="%.17g")
        frfs += ["--frf", f"r:{output}:{path}"]
    return frfs


def fit_three(seed, *extra):
    frfs = measure(out / f"seed{seed}", exact, np.random.default_rng(seed))
    fitted = [arg for n in TRUTH for arg in ("--fit", n)]
    return json.loads(hsp("identify", "--json", *frfs, *fitted, *extra).stdout)


def inside(fit, name):
    lo, hi = fit["parameters"][name]["ci95"]
    return lo <= TRUTH[name] <= hi


exact = responses(TRUTH)
ssv = out / "fitted.ssv"
fit = fit_three(1, "--out", str(ssv))
print(f"seed 1: {len(TRUTH)} parameters from {fit['residuals']} residuals (r -> {', '.join(OUTPUTS)}, "
      f"{100 * a.noise:g} % noise): cost {fit['cost']:.4f}, {fit['iterations']} iterations, "
      f"{fit['evaluations']} model evaluations, "
      f"{len(fit['warnings'])} warnings")
print(f"{'parameter':<18} {'truth':>10} {'start':>10} {'fitted':>10}   {'95 % interval':<24} truth inside")
for name, truth in TRUTH.items():
    p = fit["parameters"][name]
    ci = "[{:.4g}, {:.4g}]".format(*p["ci95"])
    print(f"{name:<18} {truth:>10.4g} {p['start']:>10.4g} {p['value']:>10.4g}   {ci:<24} "
          f"{'yes' if inside(fit, name) else 'no'}")
corr = fit["correlations"]
print("largest |correlation|: " + f"{max(abs(corr[i][j]) for i in range(3) for j in range(3) if i != j):.3f}")

# The same fit on a.seeds noise seeds: how often each interval holds the truth.
fits = [fit] + [fit_three(seed) for seed in range(2, a.seeds + 1)]
print(f"over seeds 1 to {a.seeds}: intervals holding the truth, mean (fitted - truth) / truth, "
      "mean interval half-width / truth")
for name, truth in TRUTH.items():
    values = np.array([f["parameters"][name]["value"] for f in fits])
    half = np.array([np.diff(f["parameters"][name]["ci95"])[0] / 2 for f in fits])
    print(f"  {name:<18} {sum(inside(f, name) for f in fits):>3} of {a.seeds}  "
          f"{np.mean(values / truth - 1):+.2e}  {np.mean(half) / truth:.2e}")

# The SSP tools' view: fmpy reads the set (validating it against the SSP 1.0 schema) and the FMU
# takes every value; the fitted ones come back.
parameters = read_ssv(str(ssv)).parameters
start = {p.name: p.value for p in parameters}
res = simulate_fmu(a.fmu, stop_time=0.01, output_interval=0.01, start_values=start, output=list(TRUTH))
back = all(float(res[n][-1]) == fit["parameters"][n]["value"] for n in TRUTH)
print(f"fmpy applies fitted.ssv ({len(parameters)} parameters, valid SSP 1.0) to the FMU and reads "
      f"back the fitted values bit for bit: {back}")

# What the data cannot give: with the load-pressure feedback off the loop has A1 A2 only.
frfs = measure(out / "product", responses({"controller.k_pl": 0.0, "controller.A1": 2.5}),
               np.random.default_rng(1))
done = hsp("identify", "--json", *frfs, "--fit", "controller.A1", "--fit", "controller.A2",
           "--set", "controller.k_pl=0")
product = json.loads(done.stdout)
print("A1 and A2 from the same kind of data: intervals "
      + ", ".join(f"{n} {product['parameters'][n]['ci95']}" for n in ("controller.A1", "controller.A2")))
for w in product["warnings"]:
    print(f"warning: {w}")
