"""The measures of a manoeuvre (docs/model.md, "Measures of a manoeuvre") exist twice, in Rust for
`hsp run`'s summary (src/bin/hsp/manoeuvre.rs) and in Python for the sweep tool and the examples
(tools/manoeuvre.py). tools/manoeuvre.py against closed forms, and against what `hsp run` prints
for the CSV it writes, to the printed digits: a move that settles, the same run long enough to
ring down, a 1 s move that does not settle within the run, and a step of r without a move."""

import math
import re
import subprocess
import sys

import numpy as np
import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "tools"))
import manoeuvre  # noqa: E402


def grid(stop, h):
    return np.arange(round(stop / h) + 1) * h


def test_a_first_order_approach_settles_at_tau_ln_50_after_the_command():
    # y = A (1 - exp(-(t - t_end) / tau)) after t_end: |y - A| = 0.02 A at t - t_end = tau ln 50.
    a, tau, t_end, h = 0.5, 0.3, 1.0, 1e-3
    t = grid(4.0, h)
    y = np.where(t < t_end, 0.0, a * (1 - np.exp(-(t - t_end) / tau)))
    expected = tau * math.log(50)
    s = manoeuvre.settling(t, y, a, t_end)
    assert expected <= s < expected + h, (s, expected)
    assert manoeuvre.settling(t, -y, -a, t_end) == s
    n = int((t_end + 0.9 * expected) / h)
    assert math.isnan(manoeuvre.settling(t[:n], y[:n], a, t_end))  # cut before it settles
    assert math.isnan(manoeuvre.settling(t[:500], y[:500], a, t_end))  # cut before t_end
    assert manoeuvre.overshoot_pct(y, a) == 0.0


def test_excursions_before_the_command_ends_do_not_count():
    t = grid(3.0, 0.5)
    assert manoeuvre.settling(t, [0, 2, 1.5, 1, 1.01, 0.99, 1], 1.0, 1.5) == 0.0
    assert manoeuvre.settling(t, [0, 2, 1.5, 1, 1.05, 0.99, 1], 1.0, 1.5) == 1.0
    assert math.isnan(manoeuvre.settling(t, [0, 2, 1.5, 1, 1, 1, 1.03], 1.0, 1.5))
    # The band is 2 % of the change from the first value: 1 to 2, band 0.02.
    y = [1, 2, 2.03, 2.015, 2, 2, 2]
    assert manoeuvre.settling(t, y, 2.0, 0.0) == 1.5
    assert abs(manoeuvre.overshoot_pct(y, 2.0) - 3.0) < 1e-9


def test_a_decaying_sine_rings_down_where_its_envelope_reaches_the_level():
    # w = W exp(-sigma s) sin(omega s), s = t - t_end; a 0.2 m swing before t_end is not residual.
    big, sigma, omega, t_end, h = 0.02, 0.8, 2 * math.pi, 2.5, 1e-4
    t = grid(12.0, h)
    s = t - t_end
    w = np.where(s < 0, np.where(np.abs(t - 1.0) < 1e-9, 0.2, 0.0),
                 big * np.exp(-sigma * s) * np.sin(omega * s))
    s_env = math.log(big / manoeuvre.RING_LEVEL) / sigma
    r = manoeuvre.ring_down(t, w, t_end)
    assert s_env - math.pi / omega < r <= s_env + h, (r, s_env)
    s_star = math.atan(omega / sigma) / omega  # the first maximum after t_end
    expected = big * math.exp(-sigma * s_star) * omega / math.hypot(omega, sigma)
    peak = manoeuvre.residual_peak(t, w, t_end)
    assert expected * (1 - 1e-6) < peak <= expected, (peak, expected)
    n = round((t_end + 1.25) / h) + 1  # cut at a crest, 7.4 mm
    assert w[n - 1] > 5 * manoeuvre.RING_LEVEL
    assert math.isnan(manoeuvre.ring_down(t[:n], w[:n], t_end))
    assert math.isnan(manoeuvre.residual_peak(t[:20000], w[:20000], t_end))
    assert math.isnan(manoeuvre.ring_down(t[:20000], w[:20000], t_end))
    assert manoeuvre.ring_down(t, w, t_end, 0.1) == 0.0


def test_the_command_target_and_end():
    values = {"reference.angle": 0.5, "reference.t_start": 0.5, "reference.duration": 2.0,
              "controller.k_pot": 4.0, "controller.external": False}
    assert manoeuvre.command(values) == (0.5, 2.5)
    assert manoeuvre.command(dict(values, r=2.0)) == (1.0, 2.5)  # a step of r on the move
    assert manoeuvre.command(dict(values, r=2.0, **{"reference.angle": 0.0})) == (0.5, 0.0)
    assert manoeuvre.command(dict(values, **{"controller.external": True})) is None
    m = manoeuvre.measures([0.0, 1.0], {"w_tip": [0.0, 0.0]}, dict(values, **{"controller.external": True}))
    assert all(math.isnan(v) for v in m.values())


# ------------------------------------------------------------------------------------------------
# The same figures as hsp run
# ------------------------------------------------------------------------------------------------

RUNS = {
    "default move": ([], {}),
    "default move, 20 s": (["--stop", "20"], {}),
    "1 s move": (["--set", "reference.duration=1", "--stop", "4"], {"reference.duration": 1.0}),
    "step of r": (["--profile", "step", "--r", "0.5", "--stop", "40"], {"reference.angle": 0.0}),
}
TIME = r"(\d+\.\d{3} s|not settled|not rung down)"


@pytest.mark.parametrize("name", RUNS)
def test_tools_manoeuvre_prints_what_hsp_run_prints(name, fmu_path, md, tmp_path):
    args, overrides = RUNS[name]
    csv = tmp_path / "run.csv"
    out = subprocess.run(["cargo", "run", "--release", "--quiet", "--bin", "hsp", "--", "run",
                          "--no-build", "--fmu", fmu_path, "--no-plot", "--csv", str(csv), *args],
                         cwd=ROOT, capture_output=True, text=True, check=True).stdout
    print(out)
    data = np.genfromtxt(csv, delimiter=",", names=True)
    start = {v.name: v.start for v in md.modelVariables}
    values = {n: float(start[n]) for n in ("reference.angle", "reference.t_start",
                                           "reference.duration", "controller.k_pot")}
    values.update(overrides, r=float(data["r"][0]))
    target, t_end = manoeuvre.command(values)
    t = data["time"]

    def text(v, words):
        return words if math.isnan(v) else f"{v:.3f} s"

    for label, column in (("motor", "theta_motor"), ("hub", "theta_hub")):
        m = re.search(rf"^  {label} +final \S+ deg, overshoot (\S+) %, settling \(2 %, from t = (\S+) s\) "
                      rf"{TIME}$", out, re.M)
        assert m, out
        assert m.group(1) == f"{manoeuvre.overshoot_pct(data[column], target):.2f}"
        assert float(m.group(2)) == t_end
        assert m.group(3) == text(manoeuvre.settling(t, data[column], target, t_end), "not settled")
    m = re.search(r"^  tip +peak \|w_tip\| \S+ mm; from t = (\S+) s residual peak (\S+) mm, ring-down to "
                  rf"1 mm {TIME}$", out, re.M)
    assert m, out
    assert float(m.group(1)) == t_end
    assert m.group(2) == f"{1e3 * manoeuvre.residual_peak(t, data['w_tip'], t_end):.3f}"
    assert m.group(3) == text(manoeuvre.ring_down(t, data["w_tip"], t_end), "not rung down")
    # What each run was chosen to show: the default move settles and rings on past 6 s (its
    # slowest pair has a damping ratio near 0.03) but rings down within 20 s; the 1 s move does
    # not settle within 4 s; the step settles and rings down within 40 s.
    hub = re.search(rf"^  hub .*\) {TIME}$", out, re.M).group(1)
    settles, rings_down = {"default move": (True, False), "default move, 20 s": (True, True),
                           "1 s move": (False, False), "step of r": (True, True)}[name]
    assert (hub != "not settled", m.group(3) != "not rung down") == (settles, rings_down), out
