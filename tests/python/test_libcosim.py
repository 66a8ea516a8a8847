"""Two instances of the FMU in one libcosim execution (stepped on libcosim's thread pool) agree
with fmpy's results for the same experiments.

The preset servo-valve-motor (the full servo valve on the motor alone, the paper's voltage drive)
sets its switches through libcosim's integer setter: they are Integers in the FMI 2.0 description
(libcosim ignores FMI 2.0 Enumeration variables, "Enumeration variable type not supported"), and
the test reads them back."""

import numpy as np
from fmpy import simulate_fmu
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimObserver import CosimObserver
from libcosimpy.CosimSlave import CosimLocalSlave

from conftest import preset

# The full servo valve on the motor alone (the two step responses differ by more than 0.1 V), the
# coil driven by voltage, as the preset has it (away from the FMU's default, the current drive).
PRESET = preset("servo-valve-motor")

STEP_NS = 10_000_000  # 10 ms
STEPS = 200  # to 2 s


def fmpy_run(fmu_path, r, a1):
    inp = np.array([(0.0, r), (10.0, r)], dtype=[("time", np.float64), ("r", np.float64)])
    return simulate_fmu(fmu_path, stop_time=STEPS * STEP_NS * 1e-9, output_interval=STEP_NS * 1e-9,
                        input=inp, output=["y_pot", "p_load"], start_values={**PRESET, "controller.A1": a1})


def test_the_preset_sets_a_switch_away_from_its_default(md):
    """The test needs a switch libcosim would have skipped as an FMI 2.0 Enumeration."""
    variables = {v.name: v for v in md.modelVariables}
    assert variables["servo_valve.drive"].type == "Integer"
    assert PRESET["servo_valve.drive"] != int(variables["servo_valve.drive"].start)


def test_two_instances_agree_with_fmpy(fmu_path, vr, md):
    execution = CosimExecution.from_step_size(step_size=STEP_NS)
    a = execution.add_local_slave(CosimLocalSlave(fmu_path=fmu_path, instance_name="plate_a"))
    b = execution.add_local_slave(CosimLocalSlave(fmu_path=fmu_path, instance_name="plate_b"))
    execution.real_initial_value(a, vr["r"], 1.0)
    execution.real_initial_value(b, vr["r"], 0.5)
    execution.real_initial_value(b, vr["controller.A1"], 1.0)
    for s in (a, b):
        for name, value in PRESET.items():
            setter = {bool: execution.boolean_initial_value, int: execution.integer_initial_value,
                      float: execution.real_initial_value}[type(value)]
            setter(s, vr[name], value)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    refs = [vr["y_pot"], vr["p_load"]]
    got = {a: [], b: []}
    for _ in range(STEPS):
        assert execution.step()
        for s in (a, b):
            got[s].append(observer.last_real_values(slave_index=s, variable_references=refs))
    drive = observer.last_integer_values(slave_index=a, variable_references=[vr["servo_valve.drive"]])
    assert list(drive) == [PRESET["servo_valve.drive"]]
    for s, (r, a1) in ((a, (1.0, 2.0)), (b, (0.5, 1.0))):
        ref = fmpy_run(fmu_path, r, a1)
        mine = np.array(got[s])
        np.testing.assert_allclose(mine[:, 0], ref["y_pot"][1:], rtol=0, atol=1e-9)
        np.testing.assert_allclose(mine[:, 1], ref["p_load"][1:], rtol=1e-9, atol=1e-3)
    # The two instances are different experiments, so their results differ.
    assert abs(got[a][-1][0] - got[b][-1][0]) > 0.1
