"""FMI cross-check: the FMU laid out as a vendor's cross-check entry (<model>.fmu, _ref.opt, _in.csv,
_ref.csv with the analytic LOES closed loop as the reference), checked by fmpy's own cross-check
validators: the entry is well-formed, and fmpy's simulation of it matches the reference with no
outliers in fmpy's tube."""

import re
import zipfile

import numpy as np
from fmpy import simulate_fmu
from fmpy.cross_check.validate_vendor_repo import validate_test_fmu
from fmpy.util import read_csv, read_ref_opt_file, validate_result, write_csv

from conftest import K_POT, closed_loop_step, preset

MODEL = "HydraulicSlewingPlate"


def copy_with_start_values(src, dst, start_values):
    """The FMU with other start values in its modelDescription.xml (a cross-check entry cannot set
    parameters, so the entry's FMU carries them); the GUID stays, the binary is the same."""
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w", zipfile.ZIP_DEFLATED) as zout:
        for item in zin.infolist():
            data = zin.read(item.filename)
            if item.filename == "modelDescription.xml":
                text = data.decode()
                for name, value in start_values.items():
                    text, n = re.subn(r'(<ScalarVariable name="%s".*?start=")[^"]*(")' % re.escape(name),
                                      lambda m: m.group(1) + str(value).lower() + m.group(2), text,
                                      count=1, flags=re.S)
                    assert n == 1, name
                data = text.encode()
            zout.writestr(item, data)


def make_entry(root, fmu_path):
    d = root / "2.0" / "cs" / "linux64" / "hydraulic-slewing-plate" / "0.1.0" / MODEL
    d.mkdir(parents=True)
    # The reference is the analytic LOES loop on the motor alone (linear amplifier).
    copy_with_start_values(fmu_path, d / f"{MODEL}.fmu", preset("loes-motor"))
    (d / f"{MODEL}_ref.opt").write_text("StartTime,0.0\nStopTime,0.5\nStepSize,0.001\nRelTol,1e-6\n")
    # A reference step of 1 V at t = 0.05 s: the input table holds r.
    inp = np.array([(0.0, 0.0), (0.05, 0.0), (0.05, 1.0), (0.5, 1.0)], dtype=[("time", float), ("r", float)])
    write_csv(d / f"{MODEL}_in.csv", inp)
    t = np.linspace(0.0, 0.5, 501)
    y = np.where(t < 0.05, 0.0, closed_loop_step(np.maximum(t - 0.05, 0.0)))
    ref = np.array(list(zip(t, y, y / K_POT)), dtype=[("time", float), ("y_pot", float), ("theta_motor", float)])
    write_csv(d / f"{MODEL}_ref.csv", ref)
    return d


def test_cross_check_entry_is_valid_and_reproduced(fmu_path, tmp_path):
    d = make_entry(tmp_path, fmu_path)
    assert validate_test_fmu(str(d)) == []
    opts = read_ref_opt_file(d / f"{MODEL}_ref.opt")
    inp = read_csv(d / f"{MODEL}_in.csv")
    ref = read_csv(d / f"{MODEL}_ref.csv")
    res = simulate_fmu(str(d / f"{MODEL}.fmu"), start_time=opts["StartTime"], stop_time=opts["StopTime"],
                       output_interval=opts["StepSize"], relative_tolerance=opts["RelTol"], input=inp,
                       output=["y_pot", "theta_motor"])
    assert validate_result(res, ref, stop_time=opts["StopTime"]) == 0
    # fmpy's tube is wide (a tenth of the signal range), but it notices a 20 % gain error: the
    # check above could have failed. The tight comparisons are in test_simulation.py.
    wrong = ref.copy()
    wrong["y_pot"] *= 1.2
    assert validate_result(res, wrong, stop_time=opts["StopTime"]) > 0
