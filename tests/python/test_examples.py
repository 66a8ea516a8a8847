"""The scripts in examples/ run as a user runs them (a subprocess with this Python), on the FMU
built from the checkout, into a temporary folder; each test parses what the script prints and
checks it. The figures quoted in examples/README.md and docs/model-exchange.md come from these
scripts."""

import csv
import math
import re
import subprocess
import sys

import pytest

from conftest import ROOT, hsp, packaged_source_hash

EXAMPLES = ROOT / "examples"
FMU3 = ROOT / "fmu" / "fmi3" / "HydraulicSlewingPlate.fmu"
NUMBER = r"([-+]?(?:\d+\.?\d*(?:[eE][-+]?\d+)?|nan))"


def run(script, *args):
    done = subprocess.run([sys.executable, str(EXAMPLES / script), *map(str, args)],
                          cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    print(done.stdout)
    return done.stdout


def find(pattern, text):
    m = re.search(pattern, text)
    assert m, f"{pattern!r} not in:\n{text}"
    return [float(g) for g in m.groups()]


@pytest.fixture(scope="module")
def tool_output(tmp_path_factory):
    """The `hsp` outputs the scripts would otherwise compute themselves (cargo run)."""
    d = tmp_path_factory.mktemp("hsp")
    files = {"lin_ext": ["linearize", "--json", "--set", "controller.external=true"],
             "lin": ["linearize", "--json"], "modes": ["modes", "--json"]}
    for name, args in files.items():
        (d / f"{name}.json").write_text(hsp(*args))
    return {name: d / f"{name}.json" for name in files}


def test_own_controller_damps_the_residual_vibration(fmu_path, tool_output, tmp_path):
    out = run("own_controller.py", "--fmu", fmu_path, "--out", tmp_path,
              "--linearization", tool_output["lin_ext"])
    row = lambda label: find(re.escape(label) + r"\s+" + NUMBER + r"\s+" + NUMBER, out)
    # The script's minimum-jerk move is the FMU's command generator's (recorded in the analog run).
    assert find(r"max \|controller.reference - k_pot theta_ref\| = " + NUMBER, out)[0] < 1e-9
    settle_analog, settle_lqg = row("settling time (2 % of the move) [s]")
    rms_analog, rms_lqg = row("residual RMS w_tip [mm]")
    ring_analog, ring_lqg = row("ring-down to 1 mm after move [s]")
    # Both settle within the run; the LQG controller leaves less than half the analog loop's
    # residual vibration and rings down below 1 mm within the run, which the analog loop does not
    # (its slowest pair decays at 0.096 1/s).
    assert settle_analog > 0 and settle_lqg > 0 and not math.isnan(settle_lqg)
    assert rms_lqg < 0.5 * rms_analog, (rms_lqg, rms_analog)
    assert not math.isnan(ring_lqg) and (math.isnan(ring_analog) or ring_lqg < ring_analog)
    # The moves stay inside the validity monitors' ranges: no warning from the FMU.
    assert "validity warnings, analog loop: 0" in out
    assert "validity warnings, LQG (Python): 0" in out
    # The design: the state feedback damps the slow pair (from the same linearisation).
    analog = find(r"50 1/s, analog loop: " + NUMBER + NUMBER + r"j \(zeta " + NUMBER, out)
    lqr = find(r"50 1/s, LQR \(state feedback\): " + NUMBER + NUMBER + r"j \(zeta " + NUMBER, out)
    assert lqr[2] > 5 * analog[2], (lqr, analog)
    for name in ["own_controller.png", "own_controller.csv"]:
        assert (tmp_path / name).stat().st_size > 0


def test_model_exchange_needs_an_implicit_solver(fmu_path, tool_output, tmp_path):
    # 3 s: the move (0.5 s to 2.5 s) and half a second after it.
    out = run("model_exchange.py", "--fmu", fmu_path, "--out", tmp_path,
              "--linearization", tool_output["lin"], "--stop", 3)
    re_, im_ = find(r"fastest eigenvalue " + NUMBER + r" " + NUMBER + "j", out)
    h_euler, h_rk45 = find(r"explicit Euler " + NUMBER + r" s, RK45 \(Dormand-Prince\) " + NUMBER, out)
    # Explicit Euler's bound for a complex pair is 2 |Re| / |lambda|^2 (the disc |1 + z| <= 1):
    # the script's bisection over all eigenvalues must agree with the closed form for the fastest
    # pair, to the 4 digits printed.
    closed_form = 2 * abs(re_) / (re_ ** 2 + im_ ** 2)
    assert abs(h_euler - closed_form) < 1e-3 * closed_form, (h_euler, closed_form)
    assert h_euler < h_rk45 < 1e-3
    # CVode (BDF, atol = rtol x nominals) reproduces co-simulation at rtol 1e-6 to 1e-4 of each
    # output's range (tests/python/test_model_exchange.py: 1e-6 at rtol 1e-9); without the
    # nominals, the hydraulic states (nominals 1e-9 m^3) are lost in the absolute tolerance.
    me, me1 = find(r"max difference CVode-CS: " + NUMBER + r" of the range; without nominals: " + NUMBER, out)
    assert me < 1e-4, me
    assert me1 > 10 * me, (me, me1)
    # The XML declares every state's nominal, the ones the FMU reports (tests/state_nominals.rs).
    assert "equal to fmi2GetNominalsOfContinuousStates: True" in out
    # Euler at 1 ms diverges: in the linearisation's modal coordinates the dominant mode's
    # amplitude grows by |1 + h lambda| of its eigenvalue every step.
    assert "explicit Euler, h = 0.001 s: diverged" in out
    growth, steps, predicted = find(r"measured growth per step " + NUMBER + r" \((\d+) steps, the dominant "
                                    r"mode's amplitude\); \|1 \+ h lambda\| of its eigenvalue \S+: " + NUMBER, out)
    assert steps >= 3, steps
    assert abs(growth - predicted) < 1e-3 * predicted, (growth, predicted)
    # Below its stable step Euler's increments shrink; above it they grow.
    below = find(r"h = 0.5 x \S+ s: \d+ steps; largest scaled increment at 5 ms / at 1 ms = " + NUMBER, out)[0]
    above = find(r"h = 2 x \S+ s: \d+ steps; largest scaled increment at 5 ms / at 1 ms = " + NUMBER, out)[0]
    assert below < 1 < 100 < above, (below, above)
    assert (tmp_path / "model_exchange.png").stat().st_size > 0


def test_sweep_dask_runs_the_grid_on_workers(fmu_path, tmp_path):
    out = run("sweep_dask.py", "--fmu", fmu_path, "--out", tmp_path, "--k", "1000,5000", "--stop", 3.5)
    rows = re.findall(r"^\s+(\d+)\s+ok" + r"\s+" + NUMBER * 1 + r"\s+" + NUMBER + r"\s+" + NUMBER
                      + r"\s+" + NUMBER + r"$", out, re.M)
    assert [int(r[0]) for r in rows] == [1000, 5000], out
    with open(tmp_path / "sweep_dask.csv") as f:
        table = list(csv.DictReader(f))
    assert [t["status"] for t in table] == ["ok", "ok"]
    for printed, saved in zip(rows, table):
        assert abs(float(printed[2]) - 1e3 * float(saved["residual_w_tip"])) < 1e-3
        # The hub ends within the 2 % band of the 30 deg move.
        assert abs(float(printed[4]) - 30.0) < 0.6, printed
    assert (tmp_path / "sweep_dask_residual_w_tip.png").stat().st_size > 0


def test_fmi3_arrays(fmu_path, tool_output, tmp_path):
    # Written by `hsp package` beside the FMI 2.0 FMU (the fmu_path fixture builds both).
    assert packaged_source_hash(FMU3, "x86_64-linux") == packaged_source_hash(fmu_path), FMU3
    out = run("fmi3_arrays.py", "--fmu", FMU3, "--out", tmp_path, "--modes", tool_output["modes"], "--stop", 3)
    assert "array acc[12]: Float64, causality output" in out
    assert "array plate.f[20]: Float64, causality calculatedParameter" in out
    # The array getter delivers the frequencies hsp computes (same Rust code, no FMU).
    assert find(r"plate.f vs hsp modes --json: " + NUMBER, out)[0] < 1e-12
    # acc[11] is the tip's absolute acceleration: relative part plus a times the hub's angular
    # acceleration; the central difference at 5 ms errs by O(h^2) (measured 3e-4 of the peak).
    assert find(r"tip check: .* = " + NUMBER, out)[0] < 1e-3
    # The rigid rotation dominates: each column's RMS grows from the hub to the tip.
    grid = [find(rf"x = {i}a/4 " + r"\s*" + NUMBER + r"\s+" + NUMBER + r"\s+" + NUMBER, out)
            for i in range(1, 5)]
    for j in range(3):
        assert all(grid[i][j] < grid[i + 1][j] for i in range(3)), grid
    assert (tmp_path / "fmi3_arrays.png").stat().st_size > 0
