#!/usr/bin/env python3
"""A parameter sweep on Dask: how the torsion bar's stiffness shapes the slewing move.

Runs the FMU's default experiment (its built-in 30 deg move, minimum-jerk over 2 s from t = 0.5 s,
the analog loop; stop time and step from the model description's DefaultExperiment) for four
values of `torsion_bar.k` [N m/rad], one Dask task each on a LocalCluster of 2 worker processes,
through the project's sweep tool, tools/sweep.py (imported, not copied: it sends the FMU to each
worker once and runs `run_point` there). The same sweep from the command line:
    .venv/bin/python tools/sweep.py --grid torsion_bar.k=1000,2500,5000,10000 --workers 2
Prints the settings, then per stiffness: the peak of |w_tip|, and the measures of the manoeuvre
(tools/manoeuvre.py; docs/model.md, "Measures of a manoeuvre"): the residual peak of |w_tip| after
the move, its ring-down time to 1 mm and the settling times (2 % of the move around its target) of
the hub and of y_pot, all counted from the move's end ("not rung down", "not settled" when the run
ends first); and the final hub angle. The wall-clock time is on its own line. Writes sweep_dask.csv into --out.
Run: .venv/bin/python examples/sweep_dask.py [--fmu FMU] [--out results/examples] [--k 1000,5000] [--stop S]
"""
import argparse
import pathlib
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
import sweep  # noqa: E402  (tools/sweep.py)

from distributed import Client, LocalCluster  # noqa: E402

if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--fmu", default=str(ROOT / "fmu" / "HydraulicSlewingPlate.fmu"))
    ap.add_argument("--out", default=str(ROOT / "results" / "examples"), help="output folder")
    ap.add_argument("--k", default="1000,2500,5000,10000", help="torsion_bar.k values [N m/rad]")
    ap.add_argument("--stop", type=float, help="stop time [s] (default: the DefaultExperiment's)")
    a = ap.parse_args()

    stop, step = sweep.default_experiment(a.fmu)
    options = {"inputs": {}, "stop": a.stop or stop, "step": step, "tolerance": None}
    print(sweep.describe(options, {}, (stop, step)))
    points = sweep.grid_points([("torsion_bar.k", a.k.split(","))])
    started = time.perf_counter()
    with LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        rows = sweep.sweep(client, a.fmu, points, options)
    print(sweep.format_table(rows, ["torsion_bar.k"]))
    print(f"wall-clock: {time.perf_counter() - started:.1f} s for {len(rows)} runs on 2 Dask workers")
    pathlib.Path(a.out).mkdir(parents=True, exist_ok=True)
    sweep.write_csv(pathlib.Path(a.out) / "sweep_dask.csv", rows, ["torsion_bar.k"])
    print("wrote sweep_dask.csv")
    sys.exit(0 if all(r["status"] == "ok" for r in rows) else 1)
