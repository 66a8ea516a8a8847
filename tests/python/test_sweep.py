"""tools/sweep.py on a Dask LocalCluster of 2 worker processes over 8 points: the table equals the
same points run serially in this process, failed points are rows with the FMU's message, each
worker extracts the FMU once; the command line writes the CSV and the plot, runs the FMU's
default experiment unless told otherwise and prints its settings, and reports "not settled" and
"not rung down" for a run that stops before the move ends. The measures themselves are
tests/python/test_manoeuvre.py's."""

import csv
import importlib.util
import math
import pathlib
import re
import shlex
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile

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
        # No built-in move (a step of r at t = 0): the residual is counted from t = 0, so it is
        # the peak itself.
        assert r["residual_peak_w_tip"] == r["peak_w_tip"], r
    # Regression (measured 2.539/2.464, 2.546/2.472, 2.549/2.475 mm at zeta 0.005/0.02): more
    # plate damping lowers the peak tip deflection on every bar; a stiffer bar asks for more load
    # pressure (measured 0.2213, 0.2221, 0.2224 bar at zeta 0.005).
    by = {(r["torsion_bar.k"], r["plate.zeta"]): r for r in rows}
    for k in ("1000", "2500", "5000"):
        assert by[(k, "0.02")]["peak_w_tip"] < by[(k, "0.005")]["peak_w_tip"]
    loads = [by[(k, "0.005")]["peak_p_load"] for k in ("1000", "2500", "5000")]
    assert loads == sorted(loads), loads


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


def command_line(fmu_path, out, *args):
    """Runs tools/sweep.py on 2 workers; returns what it printed and the CSV's rows."""
    done = subprocess.run([sys.executable, str(ROOT / "tools" / "sweep.py"), "--fmu", fmu_path,
                           "--workers", "2", "--out", str(out), *args],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    print(done.stdout)
    with open(out) as f:
        return done.stdout, list(csv.DictReader(f))


def default_experiment(fmu_path):
    """(stopTime, stepSize) of the DefaultExperiment, read from the FMU's modelDescription.xml."""
    with zipfile.ZipFile(fmu_path) as z:
        e = ET.fromstring(z.read("modelDescription.xml")).find("DefaultExperiment")
    return float(e.get("stopTime")), float(e.get("stepSize"))


def printed_rows(out, n_params):
    """The rows of the printed table: parameters, status, then the six metrics as text."""
    rows = []
    for line in out.splitlines():
        cells = re.split(r"\s{2,}", line.strip().replace("not settled", "not_settled")
                         .replace("not rung down", "not_rung_down"))
        if len(cells) == n_params + 7 and cells[n_params] == "ok":
            rows.append(cells)
    return rows


def test_command_line_writes_csv_and_plot(fmu_path, tmp_path):
    out = tmp_path / "sweep.csv"
    printed, table = command_line(
        fmu_path, out, "--grid", "plate.zeta=0.005,0.02", "--grid", "torsion_bar.k=1000,5000",
        *[a for k, v in FIXED.items() for a in ("--set", f"{k}={v}")],
        "--input", "r=1.0", "--stop", "0.2", "--step", "0.001", "--plot", "peak_w_tip")
    assert "settings: stop 0.2 s, step 0.001 s, tolerance solver.rtol, inputs r=1.0, fixed " in printed
    assert len(table) == 4 and all(r["status"] == "ok" for r in table)
    assert {"plate.zeta", "torsion_bar.k", "peak_w_tip", "solver_steps", "message"} <= set(table[0])
    assert_png((tmp_path / "sweep_peak_w_tip.png").read_bytes(), min_width=600)


def test_defaults_are_the_fmus_default_experiment(fmu_path, md, tmp_path):
    """No --stop, --step or --input: the whole default experiment (the built-in move, no added
    step of r), its settings printed; the hub and y_pot settle within it, after the move."""
    printed, table = command_line(fmu_path, tmp_path / "sweep.csv", "--grid", "torsion_bar.k=1000,5000")
    stop, step = default_experiment(fmu_path)
    assert (f"settings: stop {stop:g} s (DefaultExperiment), step {step:g} s (DefaultExperiment), "
            "tolerance solver.rtol, inputs none, fixed none") in printed
    start = {v.name: float(v.start) for v in md.modelVariables if v.type == "Real" and v.start}
    move = start["reference.angle"]
    move_end = start["reference.t_start"] + start["reference.duration"]
    assert move_end < stop  # the run goes on past the move
    rows = printed_rows(printed, 1)
    assert [r[0] for r in rows] == ["1000", "5000"], printed
    for row, saved in zip(rows, table):
        # The hub ends in the 2 % band of the move; the hub and y_pot settle within the run,
        # counted from the move's end, as printed and as saved.
        assert abs(float(saved["final_theta_hub"]) - move) < 0.02 * move, saved
        for name, text in (("settling_after_move_theta_hub", row[5]), ("settling_after_move_y_pot", row[6])):
            value = float(saved[name])
            assert 0 <= value < stop - move_end, (name, saved)
            assert text == f"{value:.3f}", (text, value)
        # The residual peak (after the move) is below the peak; printed as saved.
        residual = float(saved["residual_peak_w_tip"])
        assert 0 < residual < float(saved["peak_w_tip"]) and row[3] == f"{1e3 * residual:.3f}", (row, saved)
        # The run's samples are the default step's: the settling times fall on its grid.
        assert abs(float(saved["settling_after_move_theta_hub"]) / step
                   - round(float(saved["settling_after_move_theta_hub"]) / step)) < 1e-6


def test_a_run_that_stops_mid_move_is_not_settled(fmu_path, md, tmp_path):
    """Stopped at 1 s, a quarter of the way into the move (0.5 s to 2.5 s): the hub is still
    turning and the move has not ended, so no settling time (the words "not settled", an empty
    CSV cell), no ring-down time ("not rung down") and no residual ("-")."""
    start = {v.name: float(v.start) for v in md.modelVariables if v.type == "Real" and v.start}
    stop = 1.0
    assert start["reference.t_start"] < stop < start["reference.t_start"] + start["reference.duration"]
    printed, table = command_line(fmu_path, tmp_path / "sweep.csv", "--grid", "torsion_bar.k=1000,5000",
                                  "--stop", str(stop))
    rows = printed_rows(printed, 1)
    assert len(rows) == 2 and all(r[5] == r[6] == "not_settled" and r[4] == "not_rung_down"
                                  and r[3] == "-" for r in rows), printed
    for saved in table:
        assert saved["status"] == "ok"
        for name in ("settling_after_move_theta_hub", "settling_after_move_y_pot",
                     "residual_peak_w_tip", "ring_down_w_tip"):
            assert saved[name] == "", (name, saved)
        # The hub has turned only part of the move (minimum jerk at a quarter of its time: 10 %).
        assert 0 < float(saved["final_theta_hub"]) < 0.2 * start["reference.angle"], saved
        assert float(saved["peak_w_tip"]) > 0


def test_first_example_prints_what_the_docs_quote(fmu_path, tmp_path):
    """docs/sweeps.md's first command prints the block the page quotes under it (the line with
    the wall-clock time aside), so the page's figures are this FMU's."""
    text = (ROOT / "docs" / "sweeps.md").read_text()
    command, quoted = re.search(r"```sh\n(.*?)```.*?```text\n(.*?)```", text, re.S).groups()
    args = shlex.split(command.replace("\\\n", " "), comments=True)
    assert args[:2] == [".venv/bin/python", "tools/sweep.py"], args
    printed, table = command_line(fmu_path, tmp_path / "sweep.csv", *args[2:])
    assert len(table) == 6 and all(r["status"] == "ok" for r in table)

    def lines(t):
        return [line for line in t.splitlines() if "wall-clock" not in line]

    assert lines(printed) == lines(quoted), f"docs/sweeps.md quotes another output: paste this one\n{printed}"
