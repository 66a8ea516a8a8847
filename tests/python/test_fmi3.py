"""The FMI 3.0 FMU (fmu/fmi3/HydraulicSlewingPlate.fmu): checked by fmpy's validation and by
fmutool, run by fmpy, agreeing with the FMI 2.0 FMU on the same experiment, reproducing the LOES's
analytic step response, and restoring a serialised FMU state in another process to the bit."""

import json
import pathlib
import subprocess
import sys
import zipfile

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

from conftest import ROOT, closed_loop_step, packaged_source_hash, preset

FMU3 = ROOT / "fmu" / "fmi3" / "HydraulicSlewingPlate.fmu"


@pytest.fixture(scope="session")
def fmu3_path(fmu_path):
    """Written by `hsp package` beside the FMI 2.0 FMU (the fmu_path fixture builds both from the
    checkout's sources); checked to carry the same source hash."""
    assert packaged_source_hash(FMU3, "x86_64-linux") == packaged_source_hash(fmu_path), FMU3
    return str(FMU3)


def test_fmpy_validate_reports_nothing(fmu3_path):
    assert validate_fmu(fmu3_path) == []


def test_fmutool_check_passes(fmu3_path):
    fmutool = pathlib.Path(sys.executable).parent / "fmutool"
    run = subprocess.run([str(fmutool), "-input", fmu3_path, "-check"], capture_output=True, text=True)
    out = run.stdout + run.stderr
    assert run.returncode == 0, out
    assert "seems to be compliant with FMI-3.0" in out, out
    assert "No semantic error" in out, out
    assert not any(line.startswith(("ERROR", "CRITICAL")) for line in out.splitlines()), out


def test_archive_holds_the_same_binaries_under_fmi3_platform_names(fmu_path, fmu3_path):
    two, three = zipfile.ZipFile(fmu_path), zipfile.ZipFile(fmu3_path)
    names = set(three.namelist())
    assert "binaries/x86_64-linux/HydraulicSlewingPlate.so" in names
    assert "documentation/index.html" in names
    assert three.read("binaries/x86_64-linux/HydraulicSlewingPlate.so") == two.read("binaries/linux64/HydraulicSlewingPlate.so")
    if "binaries/win64/HydraulicSlewingPlate.dll" in two.namelist():
        assert three.read("binaries/x86_64-windows/HydraulicSlewingPlate.dll") == two.read("binaries/win64/HydraulicSlewingPlate.dll")


def test_model_description_arrays_and_token(fmu_path, fmu3_path):
    md2, md3 = read_model_description(fmu_path), read_model_description(fmu3_path)
    assert md3.fmiVersion == "3.0"
    assert md3.instantiationToken == md2.guid
    by_name = {v.name: v for v in md3.modelVariables}
    assert by_name["time"].causality == "independent"
    assert [int(d.start) for d in by_name["acc"].dimensions] == [12]
    assert by_name["acc"].valueReference == {v.name: v for v in md2.modelVariables}["acc[1]"].valueReference


@pytest.mark.parametrize("name, stop, start", [
    ("complete", 1.0, {"r": 2.0}),
    ("paper-fig9b", 1.0, {"r": 1.0, "F1": 0.5}),
])
def test_fmi3_cs_agrees_with_fmi2_cs(fmu_path, fmu3_path, name, stop, start):
    """The same binary behind both interfaces: the results agree to 1e-9 (in fact to the bit)."""
    values = {**preset(name), **start}
    r2 = simulate_fmu(fmu_path, stop_time=stop, output_interval=1e-3, start_values=values,
                      output=["y_pot", "theta_hub", "w_tip"] + [f"acc[{k}]" for k in range(1, 13)])
    r3 = simulate_fmu(fmu3_path, fmi_type="CoSimulation", stop_time=stop, output_interval=1e-3,
                      start_values=values, output=["y_pot", "theta_hub", "w_tip", "acc"])
    assert len(r2) == len(r3) == round(stop / 1e-3) + 1
    for out in ["y_pot", "theta_hub", "w_tip"]:
        scale = max(np.max(np.abs(r2[out])), 1e-300)
        assert np.max(np.abs(r3[out] - r2[out])) <= 1e-9 * scale, out
    acc3 = np.asarray(r3["acc"])
    for k in range(12):
        a2 = r2[f"acc[{k + 1}]"]
        assert np.max(np.abs(acc3[:, k] - a2)) <= 1e-9 * max(np.max(np.abs(a2)), 1e-300), k
    assert np.max(np.abs(r3["y_pot"])) > 0.1, "the experiment moved the motor"


def test_loes_step_is_the_analytic_response(fmu3_path):
    r = simulate_fmu(fmu3_path, stop_time=0.3, output_interval=1e-3,
                     start_values={**preset("loes-motor"), "r": 1.0}, output=["y_pot"])
    # As the FMI 2.0 test: the LOES reproduces G_est to round-off, Rodas5P's global error at rtol
    # 1e-6 stays near 1e-6 V; 1e-5 V bounds it with a 10x margin.
    err = np.max(np.abs(r["y_pot"] - closed_loop_step(r["time"])))
    assert err < 1e-5, err


CHILD = """
import json, sys
sys.path.insert(0, {tests!r})
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave
md = read_model_description({fmu!r})
s = FMU3Slave(guid=md.instantiationToken, unzipDirectory=extract({fmu!r}),
              modelIdentifier=md.coSimulation.modelIdentifier, instanceName="child")
s.instantiate()
blob = open({blob!r}, "rb").read()
state = s.deserializeFMUState(blob)
s.setFMUState(state)
vr = {vr!r}
out = []
t = {t0!r}
for k in range(50):
    s.setFloat64([vr["r"]], [1.0 if (k // 10) % 2 == 0 else -1.0])
    s.doStep(t, 1e-3)
    t += 1e-3
    out.append([v.hex() for v in s.getFloat64([vr["y_pot"], vr["theta_hub"], vr["acc"]], 14)])
print(json.dumps(out))
"""


def test_serialized_state_continues_in_another_process_bit_for_bit(fmu3_path, tmp_path):
    md = read_model_description(fmu3_path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    s = FMU3Slave(guid=md.instantiationToken, unzipDirectory=extract(fmu3_path),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName="parent")
    s.instantiate()
    s.setInt64([vr["hydraulics.model"]], [2])
    s.enterInitializationMode(startTime=0.0)
    s.setFloat64([vr["r"]], [1.0])
    s.exitInitializationMode()
    t = 0.0
    for _ in range(50):
        s.doStep(t, 1e-3)
        t += 1e-3
    state = s.getFMUState()
    blob = s.serializeFMUState(state)
    s.freeFMUState(state)
    ref = []
    t0 = t
    for k in range(50):
        s.setFloat64([vr["r"]], [1.0 if (k // 10) % 2 == 0 else -1.0])
        s.doStep(t, 1e-3)
        t += 1e-3
        ref.append([v.hex() for v in s.getFloat64([vr["y_pot"], vr["theta_hub"], vr["acc"]], 14)])
    s.terminate()
    s.freeInstance()
    (tmp_path / "state.bin").write_bytes(blob)
    code = CHILD.format(tests=str(ROOT / "tests" / "python"), fmu=fmu3_path, blob=str(tmp_path / "state.bin"),
                        vr=vr, t0=t0)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout.strip().splitlines()[-1]) == ref


def test_model_exchange_loes_step_is_the_analytic_response(fmu3_path):
    """fmpy's CVode integrates the FMI 3.0 Model Exchange interface: the LOES step to 1e-6 V
    (observed 1.4e-8 V at CVode's rtol 1e-10)."""
    r = simulate_fmu(fmu3_path, fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-10,
                     stop_time=0.3, output_interval=1e-3, start_values={**preset("loes-motor"), "r": 1.0},
                     output=["y_pot"])
    err = np.max(np.abs(r["y_pot"] - closed_loop_step(r["time"])))
    assert err < 1e-6, err


def test_model_exchange_fmi3_equals_fmi2_and_agrees_with_cs(fmu_path, fmu3_path):
    """The complete system with a 2 V step: FMI 3.0 ME gives what FMI 2.0 ME gives (the same
    derivatives, so CVode takes the same path), and both agree with co-simulation within the
    tolerances' reach (CVode rtol 1e-8 against Rodas5P rtol 1e-6: 1e-6 V; observed 1.3e-8 V)."""
    kw = dict(stop_time=0.2, output_interval=1e-3, start_values={"r": 2.0}, output=["y_pot", "theta_hub"])
    me3 = simulate_fmu(fmu3_path, fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-8, **kw)
    me2 = simulate_fmu(fmu_path, fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-8, **kw)
    cs = simulate_fmu(fmu3_path, fmi_type="CoSimulation", **kw)
    assert np.array_equal(me3["y_pot"], me2["y_pot"])
    assert np.max(np.abs(me3["y_pot"] - cs["y_pot"])) < 1e-6
    assert np.max(np.abs(me3["y_pot"])) > 0.1
