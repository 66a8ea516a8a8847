"""FMU states: get/set, serialisation across processes, and rejection of damaged blobs."""

import json
import subprocess
import sys

import pytest
from fmpy.fmi1 import FMICallException

from conftest import ROOT

H = 1e-3


def start(slave, vr, r=1.0, stop=None, method=1):
    slave.setupExperiment(tolerance=1e-7, startTime=0.0, stopTime=stop)
    slave.setInteger([vr["solver.method"]], [method])
    slave.setReal([vr["r"]], [r])
    slave.enterInitializationMode()
    slave.exitInitializationMode()


def run(slave, vr, t0, n, r_at=None):
    """n steps of H from t0 (a multiple of H); r_at(t) gives the input to set before the step at t.
    The communication points are k * H, so that every run meets the same floating-point grid."""
    outs = []
    names = ["y_pot", "theta_motor", "omega_motor", "p_load", "q_valve", "energy"]
    refs = [vr[n_] for n_ in names]
    k0 = round(t0 / H)
    for k in range(k0, k0 + n):
        t = k * H
        if r_at is not None:
            slave.setReal([vr["r"]], [r_at(t)])
        slave.doStep(t, (k + 1) * H - t)
        outs.append(slave.getReal(refs))
    return outs


def square_wave(t):
    return 1.0 if int(t / 0.05) % 2 == 0 else -0.5


@pytest.mark.parametrize("method", [1, 2])
def test_get_step_set_step_is_bit_identical(slave_factory, vr, method):
    s = slave_factory()
    start(s, vr, method=method)
    run(s, vr, 0.0, 37, square_wave)
    state = s.getFMUstate()
    first = run(s, vr, 37 * H, 80, square_wave)
    s.setFMUstate(state)
    second = run(s, vr, 37 * H, 80, square_wave)
    s.freeFMUstate(state)
    assert first == second  # bit-identical, not approximately equal


def test_uninterrupted_equals_checkpointed(slave_factory, vr):
    a, b = slave_factory(name="a"), slave_factory(name="b")
    start(a, vr)
    start(b, vr)
    ref = run(a, vr, 0.0, 100, square_wave)
    head = run(b, vr, 0.0, 50, square_wave)
    state = b.getFMUstate()
    blob = b.serializeFMUstate(state)
    b.freeFMUstate(state)
    restored = b.deSerializeFMUstate(blob)
    b.setFMUstate(restored)
    tail = run(b, vr, 50 * H, 50, square_wave)
    b.freeFMUstate(restored)
    assert head + tail == ref


CHILD = r"""
import json, sys
sys.path.insert(0, {tests!r})
from conftest import make_slave
from fmpy import extract, read_model_description
from test_fmu_state import run, square_wave, H
md = read_model_description({fmu!r})
d = extract({fmu!r})
vr = {{v.name: v.valueReference for v in md.modelVariables}}
s = make_slave(md, d, name="child")
s.setupExperiment(tolerance=1e-7, startTime=0.0)
s.enterInitializationMode(); s.exitInitializationMode()
blob = open({blob!r}, "rb").read()
st = s.deSerializeFMUstate(blob)
s.setFMUstate(st)
print(json.dumps(run(s, vr, 50 * H, 50, square_wave)))
"""


def test_serialized_state_continues_in_another_process(slave_factory, vr, fmu_path, tmp_path):
    a = slave_factory()
    start(a, vr)
    run(a, vr, 0.0, 50, square_wave)
    state = a.getFMUstate()
    blob = a.serializeFMUstate(state)
    a.freeFMUstate(state)
    ref = run(a, vr, 50 * H, 50, square_wave)
    (tmp_path / "state.bin").write_bytes(blob)
    code = CHILD.format(tests=str(ROOT / "tests" / "python"), fmu=fmu_path, blob=str(tmp_path / "state.bin"))
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout.strip().splitlines()[-1]) == ref


@pytest.mark.parametrize("damage", ["truncate", "flip", "empty", "garbage"])
def test_damaged_blob_is_rejected(slave_factory, vr, damage):
    s = slave_factory()
    start(s, vr)
    run(s, vr, 0.0, 5)
    state = s.getFMUstate()
    blob = bytearray(s.serializeFMUstate(state))
    s.freeFMUstate(state)
    if damage == "truncate":
        blob = blob[: len(blob) // 2]
    elif damage == "flip":
        blob[len(blob) - 10] ^= 0x20
    elif damage == "empty":
        blob = bytearray(b"\0")
    else:
        blob = bytearray(b"not an FMU state at all" * 3)
    with pytest.raises(FMICallException, match="fmi2DeSerializeFMUstate"):
        s.deSerializeFMUstate(bytes(blob))
    assert any(st == 3 and "fmi2DeSerializeFMUstate" in m for st, _, m in s.recorder.messages), s.recorder.text()
