"""External control through fmpy: with controller.external = true the input e_in drives the valve
coil, and a controller written in Python closes the loop on y_pot."""

import numpy as np
from fmpy import simulate_fmu

from conftest import A1, A2, K_POT, K_SV, D_M, apply_preset, closed_loop_step, preset


def external(name, **extra):
    return preset(name, **{"controller.external": True, **extra})


def test_e_in_zero_keeps_the_motor_at_rest_whatever_r(fmu_path):
    r = np.array([(0.0, 4.0), (1.0, 4.0)], dtype=[("time", float), ("r", float)])
    res = simulate_fmu(fmu_path, stop_time=0.3, output_interval=1e-3, input=r,
                       output=["theta_motor", "y_pot", "controller.e_out"],
                       start_values=external("loes-motor"))
    for n in ["theta_motor", "y_pot", "controller.e_out"]:
        assert np.all(res[n] == 0.0), n


def test_constant_e_in_turns_the_motor_at_the_flow_gain_rate(fmu_path):
    # LOES on the motor alone: omega = k_sv e_in / D_m once the hydraulic transient (poles at 65 and
    # 753 1/s) has died out; the angle then grows linearly at that rate.
    e_in = 1.5
    inp = np.array([(0.0, e_in), (1.0, e_in)], dtype=[("time", float), ("e_in", float)])
    res = simulate_fmu(fmu_path, stop_time=1.0, output_interval=1e-3, input=inp, relative_tolerance=1e-9,
                       output=["omega_motor", "theta_motor"], start_values=external("loes-motor"))
    rate = K_SV * e_in / D_M
    assert abs(res["omega_motor"][-1] - rate) < 1e-6 * rate
    slope = (res["theta_motor"][-1] - res["theta_motor"][-101]) / (res["time"][-1] - res["time"][-101])
    assert abs(slope - rate) < 1e-6 * rate


def test_a_python_controller_closes_the_loop(slave_factory, md, vr):
    # A proportional controller e_in = A1 A2 (r - y_pot), sampled every 1 ms with a zero-order
    # hold, is the paper's analog loop but for the sampling: the response follows the analytic
    # closed loop of eq. 1. The hold delays the control by half a sample on average (0.5 ms, 1.3 deg
    # of phase at the 46 rad/s crossover), so the two differ by a little; 2 % of the step bounds it.
    s = slave_factory()
    s.setupExperiment(startTime=0.0)
    apply_preset(s, md, "loes-motor")
    s.setBoolean([vr["controller.external"]], [True])
    s.enterInitializationMode()
    s.exitInitializationMode()
    h, r, k = 1e-3, 1.0, A1 * A2
    t, y = [0.0], [0.0]
    for i in range(500):
        y_pot = s.getReal([vr["y_pot"]])[0]
        s.setReal([vr["e_in"]], [k * (r - y_pot)])
        s.doStep(i * h, h)
        t.append((i + 1) * h)
        y.append(s.getReal([vr["y_pot"]])[0])
    exact = closed_loop_step(np.array(t), r=r)
    diff = np.max(np.abs(np.array(y) - exact))
    print(f"max |y_pot(sampled P) - y_pot(analog)| = {diff:.4f} V")
    assert diff < 0.02 * r, diff
    assert abs(y[-1] - r) < 1e-3
    assert abs(K_POT * s.getReal([vr["theta_motor"]])[0] - y[-1]) < 1e-12
