"""FMI cross-check: the FMU laid out as a vendor's cross-check entry (<model>.fmu, _ref.opt, _in.csv,
_ref.csv with the default configuration integrated by Radau IIA at rtol 1e-10 as the reference), checked by fmpy's own cross-check
validators: the entry is well-formed, and fmpy's simulation of it matches the reference with no
outliers in fmpy's tube."""

import shutil

import numpy as np
from fmpy import simulate_fmu
from fmpy.cross_check.validate_vendor_repo import validate_test_fmu
from fmpy.util import read_csv, read_ref_opt_file, validate_result, write_csv


MODEL = "HydraulicSlewingPlate"


def make_entry(root, fmu_path):
    d = root / "2.0" / "cs" / "linux64" / "hydraulic-slewing-plate" / "0.1.0" / MODEL
    d.mkdir(parents=True)
    shutil.copy(fmu_path, d / f"{MODEL}.fmu")
    (d / f"{MODEL}_ref.opt").write_text("StartTime,0.0\nStopTime,0.5\nStepSize,0.001\nRelTol,1e-6\n")
    # A reference step of 1 V at t = 0.05 s: the input table holds r.
    inp = np.array([(0.0, 0.0), (0.05, 0.0), (0.05, 1.0), (0.5, 1.0)], dtype=[("time", float), ("r", float)])
    write_csv(d / f"{MODEL}_in.csv", inp)
    # A cross-check entry cannot set parameters: it runs the FMU's defaults, the complete system.
    # The reference is the same experiment with the other integrator (Radau IIA) at rtol 1e-10.
    ref_run = simulate_fmu(fmu_path, stop_time=0.5, output_interval=1e-3, relative_tolerance=1e-10, input=inp,
                           output=["y_pot", "theta_motor"], start_values={"solver.method": 2})
    ref = np.array(list(zip(ref_run["time"], ref_run["y_pot"], ref_run["theta_motor"])),
                   dtype=[("time", float), ("y_pot", float), ("theta_motor", float)])
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
    # check above could have failed. The tight comparisons (against the analytic LOES) are in
    # test_simulation.py.
    wrong = ref.copy()
    wrong["y_pot"] *= 1.2
    assert validate_result(res, wrong, stop_time=opts["StopTime"]) > 0
