"""Simulations through fmpy against the analytic LOES loop (eq. 1 closed around G_est, eq. 2)."""

import numpy as np
import pytest
from fmpy import simulate_fmu

from conftest import closed_loop_step, preset

# These tests mean the paper's identification setup: the LOES on the motor alone with the linear
# amplifier of eq. 1.
LOES = "loes-motor"


def step_input(r=1.0):
    return np.array([(0.0, r), (1e3, r)], dtype=[("time", np.float64), ("r", np.float64)])


def test_step_response_matches_analytic_closed_loop(fmu_path):
    # Motor uncoupled (the paper's identification setup), unit step in r, tight tolerance: the FMU
    # must reproduce the exact linear response to 1e-6 V.
    res = simulate_fmu(fmu_path, stop_time=0.5, output_interval=1e-3, relative_tolerance=1e-9,
                       input=step_input(1.0), output=["y_pot", "theta_motor"],
                       start_values=preset(LOES))
    exact = closed_loop_step(res["time"])
    err = np.max(np.abs(res["y_pot"] - exact))
    assert err < 1e-6, f"max |y_pot - analytic| = {err:.3e} V"
    # The analytic loop settles to r with the underdamped pair of note 8 (zeta 0.557): ~12 % overshoot.
    assert abs(res["y_pot"][-1] - 1.0) < 1e-4
    overshoot = res["y_pot"].max() - 1.0
    assert 0.05 < overshoot < 0.2, overshoot


@pytest.mark.parametrize("interval,stop", [(0.015, 1.5), (0.5, 4.0), (7.0, 21.0)])
def test_output_intervals_land_on_grid(fmu_path, interval, stop):
    res = simulate_fmu(fmu_path, stop_time=stop, output_interval=interval, input=step_input(0.5),
                       output=["y_pot"], start_values=preset(LOES))
    n = int(round(stop / interval))
    grid = np.arange(n + 1) * interval
    assert len(res["time"]) == n + 1
    np.testing.assert_allclose(res["time"], grid, rtol=1e-12, atol=1e-12)
    assert res["time"][-1] == pytest.approx(stop, abs=1e-12)
    # And the values at those points are the exact ones (rtol 1e-6 default tolerance).
    np.testing.assert_allclose(res["y_pot"], closed_loop_step(res["time"], r=0.5), atol=5e-5)


def test_parameter_change_before_initialisation(fmu_path):
    # Halving A1 halves the loop gain: the analytic model with A1 = 1 must be followed, and the
    # response must differ from the default one.
    times = np.linspace(0, 0.3, 301)
    res = simulate_fmu(fmu_path, stop_time=0.3, output_interval=1e-3, relative_tolerance=1e-9,
                       input=step_input(1.0), output=["y_pot"], start_values=preset(LOES, **{"controller.A1": 1.0}))
    expected = closed_loop_step(res["time"], a1=1.0)
    default = closed_loop_step(res["time"])
    assert np.max(np.abs(res["y_pot"] - expected)) < 1e-6
    assert np.max(np.abs(res["y_pot"] - default)) > 1e-2


def test_paper_printed_leakage_moves_the_poles(fmu_path):
    # The paper's printed R7 = 3.8e7 (note 7) gives another, analytically known response.
    res = simulate_fmu(fmu_path, stop_time=0.3, output_interval=1e-3, relative_tolerance=1e-9,
                       input=step_input(1.0), output=["y_pot"], start_values=preset(LOES, **{"loes.R7": 3.8e7}))
    expected = closed_loop_step(res["time"], r7=3.8e7)
    assert np.max(np.abs(res["y_pot"] - expected)) < 1e-6


@pytest.mark.parametrize("method", [1, 2])
def test_both_methods_agree_with_analytic(fmu_path, method):
    res = simulate_fmu(fmu_path, stop_time=0.3, output_interval=1e-3, relative_tolerance=1e-8,
                       input=step_input(1.0), output=["y_pot", "solver.steps"],
                       start_values=preset(LOES, **{"solver.method": method}))
    assert np.max(np.abs(res["y_pot"] - closed_loop_step(res["time"]))) < 1e-5
    assert res["solver.steps"][-1] > 0


def test_energy_is_stored_and_finite(fmu_path):
    res = simulate_fmu(fmu_path, stop_time=0.2, output_interval=1e-3, input=step_input(1.0),
                       output=["energy", "p_load", "q_valve", "omega_motor"], start_values=preset(LOES))
    for name in ["energy", "p_load", "q_valve", "omega_motor"]:
        assert np.all(np.isfinite(res[name])), name
    assert res["energy"][0] == 0.0
    assert np.all(res["energy"] >= 0.0)
    assert res["energy"].max() > 0.0
