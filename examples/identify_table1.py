#!/usr/bin/env python3
"""`hsp identify --peaks` on the paper's Table 1 (docs/identify.md): the worked case.

Table 1's second column, the resonance peaks of Fig. 9b (4.98, 16.0, 33.3 Hz, the response from r
to the tip acceleration), is in examples/data/table1_fig9b_peaks.csv with a standard uncertainty
of half a unit of the last printed digit (`tests/identify.rs` checks the file against
src/model/paper.rs). Four fits, each with `hsp identify --json --peaks r:acc_tip:FILE`:

1. the paper's model (preset paper-fig9b), its plate's Young's modulus alone;
2. the same with the plate's density: only their ratio reaches the peaks;
3. the complete system (preset complete) from its defaults: its peaks are not there;
4. the complete system with the parameters that can move its peaks there: the hub's inertia,
   the torsion bar's stiffness and the plate's modulus, from a light hub on a soft bar.

Each prints the fitted values, their 95 % intervals, the model's peaks against the measured and
the command's warnings.

Run (from the repository root):
.venv/bin/python examples/identify_table1.py
"""
import json
import pathlib
import subprocess

ROOT = pathlib.Path(__file__).resolve().parents[1]
PEAKS = "examples/data/table1_fig9b_peaks.csv"  # from the repository root, the working folder


def identify(*args):
    """`hsp identify --json --peaks r:acc_tip:PEAKS ARGS`: its JSON, or its error."""
    done = subprocess.run(["cargo", "run", "--release", "--quiet", "--bin", "hsp", "--", "identify",
                           "--json", "--peaks", f"r:acc_tip:{PEAKS}", *args],
                          cwd=ROOT, capture_output=True, text=True)
    if done.returncode != 0:
        return done.stderr.strip().removeprefix("hsp: error: ")
    return json.loads(done.stdout)


def show(title, fit):
    print(title)
    if isinstance(fit, str):
        print(f"  refused: {fit}")
        return
    print(f"  cost {fit['cost']:.3g} from {fit['residuals']} peaks, {fit['iterations']} iterations, "
          f"{fit['evaluations']} model evaluations")
    for name in fit["fitted"]:
        p = fit["parameters"][name]
        ci = "none" if p["ci95"] is None else "[{:.4g}, {:.4g}]".format(*p["ci95"])
        print(f"  {name:<14} start {p['start']:<9.4g} fitted {p['value']:<10.4g} "
              f"({p['value'] / p['start'] - 1:+.1%})  95 % interval {ci}")
    peaks = fit["peaks"][0]
    print("  peaks [Hz]: measured " + ", ".join(f"{f:g}" for f in peaks["measured_Hz"])
          + "; start " + ", ".join(f"{f:.3f}" for f in peaks["start_Hz"])
          + "; fitted " + ", ".join(f"{f:.3f}" for f in peaks["fitted_Hz"]))
    for w in fit["warnings"]:
        print(f"  warning: {w}")


show("1. paper-fig9b, plate.E", identify("--preset", "paper-fig9b", "--fit", "plate.E"))
show("2. paper-fig9b, plate.E and plate.rho",
     identify("--preset", "paper-fig9b", "--fit", "plate.E", "--fit", "plate.rho"))
show("3. complete, from its defaults (hub.I_H 3.5, torsion_bar.k 2500)",
     identify("--preset", "complete", "--fit", "plate.E"))
show("4. complete, hub.I_H, torsion_bar.k and plate.E from a light hub on a soft bar",
     identify("--preset", "complete", "--set", "hub.I_H=0.01", "--set", "torsion_bar.k=100",
              "--fit", "hub.I_H:1e-3:10", "--fit", "torsion_bar.k:1:1e5", "--fit", "plate.E"))
