"""The FMI contract: bad calls get fmi2Error with a log line naming the culprit, solver failure
gets fmi2Discard with the last good state, and fmi2Reset is a fresh start."""

import ctypes

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import fmi2LastSuccessfulTime, fmi2Terminated

from conftest import apply_preset, make_slave


def errors(slave):
    return [m for st, _, m in slave.recorder.messages if st == 3]


def initialise(s, vr, **reals):
    s.setupExperiment(startTime=0.0)
    for k, v in reals.items():
        s.setReal([vr[k]], [v])
    s.enterInitializationMode()
    s.exitInitializationMode()


def test_wrong_guid_gives_null(md, unzipped):
    with pytest.raises(Exception):
        make_slave(md, unzipped, guid="{00000000-0000-0000-0000-000000000000}")


def test_out_of_order_call_is_an_error_with_a_log_line(slave_factory, vr):
    s = slave_factory()
    with pytest.raises(FMICallException):
        s.doStep(0.0, 1e-3)  # before initialisation
    assert any("illegal call sequence" in m for m in errors(s)), s.recorder.text()


def test_unknown_value_reference(slave_factory):
    s = slave_factory()
    with pytest.raises(FMICallException):
        s.setReal([987654], [1.0])
    assert any("987654" in m for m in errors(s)), s.recorder.text()


def test_wrong_type(slave_factory, vr):
    s = slave_factory()
    with pytest.raises(FMICallException):
        s.setReal([vr["solver.method"]], [1.0])
    assert any("solver.method" in m and "Integer" in m for m in errors(s)), s.recorder.text()


def test_null_arrays(slave_factory, vr):
    s = slave_factory()
    initialise(s, vr)
    f = s.dll.fmi2GetReal
    f.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t, ctypes.c_void_p]
    f.restype = ctypes.c_int
    value = (ctypes.c_double * 1)()
    assert f(s.component, None, 1, value) == 3
    assert any("NULL" in m for m in errors(s)), s.recorder.text()


def test_nan_input(slave_factory, vr):
    s = slave_factory()
    initialise(s, vr)
    with pytest.raises(FMICallException):
        s.setReal([vr["r"]], [float("nan")])
    assert any("'r'" in m or m.startswith("fmi2SetReal: r:") for m in errors(s)), s.recorder.text()


@pytest.mark.parametrize("name,value", [("loes.C3", -5e-11), ("loes.I_b", -1.0), ("loes.C3", 0.0),
                                        ("loes.I_b", 0.0), ("solver.rtol", -1e-6)])
def test_nonphysical_parameters(slave_factory, vr, name, value):
    s = slave_factory()
    with pytest.raises(FMICallException):
        s.setReal([vr[name]], [value])
    assert any(name in m for m in errors(s)), s.recorder.text()


def test_parameter_cannot_change_after_initialisation(slave_factory, vr):
    s = slave_factory()
    initialise(s, vr)
    with pytest.raises(FMICallException):
        s.setReal([vr["loes.C3"]], [6e-11])
    assert any("loes.C3" in m for m in errors(s)), s.recorder.text()


def test_output_cannot_be_set(slave_factory, vr):
    s = slave_factory()
    with pytest.raises(FMICallException):
        s.setReal([vr["y_pot"]], [1.0])
    assert any("y_pot" in m for m in errors(s)), s.recorder.text()


def test_after_error_only_reset_helps(slave_factory, vr):
    s = slave_factory()
    initialise(s, vr, r=1.0)
    with pytest.raises(FMICallException):
        s.doStep(0.5, 1e-3)  # wrong communication point
    assert any("currentCommunicationPoint" in m for m in errors(s)), s.recorder.text()
    with pytest.raises(FMICallException):
        s.doStep(0.0, 1e-3)  # the instance is in the error state now
    s.reset()
    initialise(s, vr, r=1.0)
    s.doStep(0.0, 1e-3)


def test_reset_then_rerun_equals_first_run(slave_factory, vr):
    s = slave_factory()

    def once():
        initialise(s, vr, r=1.0)
        out = []
        for i in range(100):
            s.doStep(i * 1e-3, 1e-3)
            out.append(s.getReal([vr["y_pot"], vr["p_load"]]))
        return out

    first = once()
    s.terminate()
    s.reset()
    assert once() == first


def test_unknown_log_category(slave_factory):
    s = slave_factory()
    with pytest.raises(FMICallException):
        s.setDebugLogging(True, ["logNoSuchThing"])
    assert any("logNoSuchThing" in m for m in errors(s)), s.recorder.text()


def test_log_categories_filter(slave_factory, vr):
    # Logging off at instantiation, then only logSolver: solver lines, and no call lines.
    s = slave_factory(logging_on=False)
    s.setDebugLogging(True, ["logSolver"])
    initialise(s, vr, r=1.0)
    s.doStep(0.0, 1e-2)
    cats = [c for _, c, _ in s.recorder.messages]
    assert any(c == "logSolver" and "steps" in m for _, c, m in s.recorder.messages), s.recorder.text()
    assert "logCalls" not in cats
    # logCalls on: every call is logged with its arguments.
    s.setDebugLogging(True, ["logCalls"])
    s.doStep(1e-2, 1e-2)
    assert any(c == "logCalls" and "fmi2DoStep(currentCommunicationPoint=0.01" in m
               for _, c, m in s.recorder.messages), s.recorder.text()
    # All off: nothing more but warnings and errors.
    s.setDebugLogging(False, [])
    n = len(s.recorder.messages)
    s.doStep(2e-2, 1e-2)
    assert len(s.recorder.messages) == n


def test_solver_failure_is_a_discard_with_last_successful_time(slave_factory, vr, md):
    s = slave_factory()
    s.setupExperiment(startTime=0.0)
    apply_preset(s, md, "loes-motor")  # the motor must have moved within 50 us
    s.setReal([vr["solver.max_step"]], [1e-6])
    s.setInteger([vr["solver.max_steps"]], [50])
    s.setReal([vr["r"]], [1.0])
    s.enterInitializationMode()
    s.exitInitializationMode()
    s.doStep(0.0, 1e-5)  # 10 steps of 1e-6: fine
    with pytest.raises(FMICallException, match="discard"):
        s.doStep(1e-5, 1e-3)  # would need 1000 steps
    t = s.getRealStatus(fmi2LastSuccessfulTime)
    assert 1e-5 < t < 1e-5 + 1e-3
    assert t <= 1e-5 + 50 * 1e-6 * (1 + 1e-9)  # at most max_steps steps of max_step
    assert s.getBooleanStatus(fmi2Terminated) is False
    assert any(st == 2 for st, _, m in s.recorder.messages), s.recorder.text()
    # The outputs are those of the last good state: finite, and the motor has moved.
    y = s.getReal([vr["y_pot"]])[0]
    assert np.isfinite(y) and y > 0.0
    s.terminate()


def test_get_and_set_strings_and_unsupported_functions(slave_factory, vr):
    # Directional derivatives are offered (providesDirectionalDerivative="true"): y_pot does not
    # depend on r directly, controller.e_out does (the amplifier gain A1 A2, linear at rest).
    s = slave_factory()
    initialise(s, vr)
    assert s.getDirectionalDerivative([vr["y_pot"], vr["controller.e_out"]], [vr["r"]], [1.0])[0] == 0.0
    assert s.getDirectionalDerivative([vr["controller.e_out"]], [vr["r"]], [1.0])[0] > 0.0
    # Output derivatives are not (maxOutputDerivativeOrder="0").
    with pytest.raises(FMICallException):
        s.getRealOutputDerivatives([vr["y_pot"]], [1])
    assert any("not supported" in m for m in errors(s)), s.recorder.text()
