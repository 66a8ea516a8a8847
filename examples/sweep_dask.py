#!/usr/bin/env python3
"""A design sweep on Dask: how the torsion bar's stiffness shapes the slewing move.

What it shows
    The default slewing move (30 deg of motor angle, minimum-jerk over 2 s from t = 0.5 s, the
    FMU's analog loop, default preset) run for several values of `torsion_bar.k` [N m/rad], one
    Dask task per value on a LocalCluster, through the project's sweep tool (tools/sweep.py:
    `sweep.sweep` sends the FMU to each worker once and runs `run_point` there). It prints, per
    stiffness, the tip deflection's peak and its residual (largest |w_tip| over the last 10 % of
    the run), the hub's settling time (2 % of its change) and the final hub angle, and plots
    the residual against the stiffness (sweep_dask_residual_w_tip.png, with the CSV, in --out).

    The same sweep from the command line:
        .venv/bin/python tools/sweep.py --grid torsion_bar.k=1000,2500,5000 --input r=0 \
            --stop 4 --step 0.005 --plot residual_w_tip
    This script is the same thing from Python, for a user who wants the rows in hand.

How to run (from the repository root, after `cargo run --release --bin hsp -- package`):
    .venv/bin/python examples/sweep_dask.py [--fmu fmu/HydraulicSlewingPlate.fmu] [--out results/examples]
        [--k 1000,2500,5000,10000] [--stop 4] [--workers 2]
Needs dask[distributed] and matplotlib (tests/requirements.txt).
"""

import argparse
import math
import pathlib
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))

import sweep  # noqa: E402  (tools/sweep.py: the project's Dask sweep)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--fmu", default=str(ROOT / "fmu" / "HydraulicSlewingPlate.fmu"))
    ap.add_argument("--out", default=str(ROOT / "results" / "examples"), help="output folder")
    ap.add_argument("--k", default="1000,2500,5000,10000", help="torsion_bar.k values [N m/rad]")
    ap.add_argument("--stop", type=float, default=4.0, help="stop time [s]: the move ends at 2.5 s")
    ap.add_argument("--step", type=float, default=5e-3, help="communication step [s]")
    ap.add_argument("--workers", type=int, default=2, help="LocalCluster workers")
    a = ap.parse_args(argv)
    out = pathlib.Path(a.out)
    out.mkdir(parents=True, exist_ok=True)

    points = sweep.grid_points([("torsion_bar.k", a.k.split(","))])
    # r = 0: the FMU's own move alone (tools/sweep.py adds a 1 V step of r unless told).
    options = {"inputs": {"r": "0"}, "stop": a.stop, "step": a.step, "tolerance": None}

    from distributed import Client, LocalCluster

    started = time.perf_counter()
    with LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        rows = sweep.sweep(client, a.fmu, points, options)
    wall = time.perf_counter() - started

    print(f"{len(rows)} points on {a.workers} Dask workers in {wall:.1f} s "
          f"({a.stop:g} s runs, {a.step * 1e3:g} ms communication step)")
    print(f"{'torsion_bar.k':>14s}{'status':>8s}{'peak w_tip':>12s}{'residual':>12s}"
          f"{'settling':>10s}{'final hub':>11s}")
    print(f"{'[N m/rad]':>14s}{'':>8s}{'[mm]':>12s}{'[mm]':>12s}{'[s]':>10s}{'[deg]':>11s}")
    for r in rows:
        if r["status"] != "ok":
            print(f"{r['torsion_bar.k']:>14s}{r['status']:>8s}  {r['message']}")
            continue
        print(f"{float(r['torsion_bar.k']):14.0f}{r['status']:>8s}{r['peak_w_tip'] * 1e3:12.3f}"
              f"{r['residual_w_tip'] * 1e3:12.3f}{r['settling_time_theta_hub']:10.3f}"
              f"{math.degrees(r['final_theta_hub']):11.3f}")
    csv_path = out / "sweep_dask.csv"
    sweep.write_csv(csv_path, rows, ["torsion_bar.k"])
    png = out / "sweep_dask_residual_w_tip.png"
    sweep.plot(rows, "residual_w_tip", "torsion_bar.k", None, png)
    print(f"wrote {csv_path} and {png}")
    return 0 if all(r["status"] == "ok" for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
