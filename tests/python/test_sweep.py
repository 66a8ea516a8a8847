"""tools/sweep.py on a Dask LocalCluster of 2 worker processes over 8 points: the table equals the
same points run serially in this process, failed points are rows with the FMU's message, each
worker extracts the FMU once; and the command line writes the CSV and the plot."""

import csv
import importlib.util
import math
import pathlib
import subprocess
import sys

import pytest

from conftest import preset
from figures import assert_png

ROOT = pathlib.Path(__file__).resolve().parents[2]
spec = importlib.util.spec_from_file_location("sweep", ROOT / "tools" / "sweep.py")
sweep = importlib.util.module_from_spec(spec)
sys.modules["sweep"] = sweep
spec.loader.exec_module(sweep)

# The LOES driving the hub and plate (preset paper-fig9b, the paper's Fig. 9b setup), over 0.3 s:
# enough for the metrics to depend on the parameters, short enough for a test.
OPTIONS = {"inputs": {"r": "1.0"}, "stop": 0.3, "step": 1e-3, "tolerance": None}
GOOD = sweep.grid_points([("torsion_bar.k", ["1000", "2500", "5000"]),
                          ("plate.zeta", ["0.005", "0.02"])])
BAD = [{"torsion_bar.k": "2500", "plate.zeta": "-1"},      # below its minimum: fmi2Error
       {"torsion_bar.k": "2500", "plate.zeta": "0.01", "no.such": "1"}]  # not a variable


def as_text(value):
    return str(value).lower() if isinstance(value, bool) else str(value)


FIXED = {k: as_text(v) for k, v in preset("paper-fig9b").items()}
POINTS = [dict(FIXED, **p) for p in GOOD + BAD]
COMPARED = [m for m in sweep.METRICS if m != "wall_s"]


@pytest.fixture(scope="module")
def cluster_rows(fmu_path):
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        rows = sweep.sweep(client, fmu_path, POINTS, OPTIONS)
        extractions = client.run(lambda dask_worker: dask_worker.plugins["hsp-fmu"].extractions)
    return rows, extractions


@pytest.fixture(scope="module")
def serial_rows(fmu_path, tmp_path_factory):
    unzipdir = sweep.extract(pathlib.Path(fmu_path).read_bytes(), str(tmp_path_factory.mktemp("fmu")))
    return [dict(p, **sweep.run_point(unzipdir, p, OPTIONS)) for p in POINTS]


def same(a, b):
    return (isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b)) or a == b


def test_cluster_table_equals_serial_runs(cluster_rows, serial_rows):
    rows, _ = cluster_rows
    assert len(rows) == len(POINTS) == 8
    for got, want, point in zip(rows, serial_rows, POINTS):
        for k, v in point.items():
            assert got[k] == v
        assert got["status"] == want["status"], (got, want)
        assert got["message"] == want["message"]
        # The same binary on the same inputs is deterministic: equal to the last bit.
        for m in COMPARED if got["status"] == "ok" else []:
            assert same(got[m], want[m]), (m, got[m], want[m])


def test_metrics_respond_to_the_parameters(cluster_rows):
    rows = [r for r in cluster_rows[0] if r["status"] == "ok"]
    assert len(rows) == 6
    for r in rows:
        assert r["peak_w_tip"] > 0 and r["peak_p_load"] > 0 and r["solver_steps"] > 0
        assert 0 < r["residual_w_tip"] <= r["peak_w_tip"]
    # More plate damping, less residual vibration, at every bar stiffness.
    by = {(r["torsion_bar.k"], r["plate.zeta"]): r for r in rows}
    for k in ("1000", "2500", "5000"):
        assert by[(k, "0.02")]["residual_w_tip"] < by[(k, "0.005")]["residual_w_tip"]


def test_failed_points_are_rows_with_the_message(cluster_rows):
    rows = cluster_rows[0]
    below, unknown = rows[-2], rows[-1]
    assert below["status"] == "error" and "plate.zeta" in below["message"], below
    assert unknown["status"] == "error" and "no.such" in unknown["message"], unknown


def test_each_worker_extracts_the_fmu_once(cluster_rows):
    rows, extractions = cluster_rows
    assert len(extractions) == 2 and all(n == 1 for n in extractions.values()), extractions
    # ... and runs several points on that one copy.
    per_worker = {}
    for r in rows:
        per_worker[r["worker"]] = per_worker.get(r["worker"], 0) + 1
    assert max(per_worker.values()) > 1, per_worker


def test_command_line_writes_csv_and_plot(fmu_path, tmp_path):
    out = tmp_path / "sweep.csv"
    done = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "sweep.py"), "--fmu", fmu_path, "--workers", "2",
         "--grid", "plate.zeta=0.005,0.02", "--grid", "torsion_bar.k=1000,5000",
         *[a for k, v in FIXED.items() for a in ("--set", f"{k}={v}")],
         "--stop", "0.2", "--out", str(out), "--plot", "peak_w_tip"],
        capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    with open(out) as f:
        table = list(csv.DictReader(f))
    assert len(table) == 4 and all(r["status"] == "ok" for r in table)
    assert {"plate.zeta", "torsion_bar.k", "peak_w_tip", "solver_steps", "message"} <= set(table[0])
    assert_png((tmp_path / "sweep_peak_w_tip.png").read_bytes(), min_width=600)
