"""The plate in the FMU: calculated frequencies, the coupled model through fmpy, the CLI."""

import json
import math

import numpy as np
from fmpy import simulate_fmu
from fmpy.validation import validate_fmu

from conftest import hsp, preset

ACC = [f"acc[{k}]" for k in range(1, 13)]
OUTPUTS = ["y_pot", "theta_motor", "theta_hub", "omega_hub", "torsion_bar.torque", "w_tip", "acc_tip", "energy"] + ACC


def test_plate_variables_validate(fmu_path, md):
    assert validate_fmu(fmu_path) == []
    names = {v.name: v for v in md.modelVariables}
    for n in ["plate.formulation", "plate.root", "plate.N", "plate.M", "plate.E", "plate.rho", "plate.a", "plate.b",
              "plate.h", "plate.nu", "plate.zeta", "hub.I_H", "torsion_bar.k", "plate.x1", "plate.y1", "plate.x2",
              "plate.y2", "F1", "F2", "theta_hub", "omega_hub", "torsion_bar.torque", "w_tip", "acc_tip"] + ACC:
        assert n in names, n
        assert names[n].description
        assert 300 <= names[n].valueReference < 600
    for k in range(1, 21):
        v = names[f"plate.f[{k}]"]
        assert v.causality == "calculatedParameter" and v.variability == "fixed"


def test_coupled_step_in_r_with_the_plate(fmu_path):
    r = np.array([(0.0, 1.0), (1.0, 1.0)], dtype=[("time", float), ("r", float)])
    res = simulate_fmu(fmu_path, stop_time=1.0, output_interval=1e-3, input=r, output=OUTPUTS,
                       start_values=preset("paper-fig9b"))
    for n in OUTPUTS:
        assert np.all(np.isfinite(res[n])), n
    # the plate moves: the hub turns, the bar carries torque, the tip vibrates
    assert abs(res["theta_hub"][-1]) > 1e-3
    assert np.max(np.abs(res["torsion_bar.torque"])) > 1.0
    assert np.max(np.abs(res["acc_tip"])) > 1e-3
    assert np.all(res["energy"] >= 0)


def test_calculated_frequencies_reproduce_eq16(fmu_path):
    res = simulate_fmu(fmu_path, stop_time=0.01, output_interval=1e-3,
                       start_values=preset("paper-eq16"),
                       output=[f"plate.f[{k}]" for k in range(1, 21)])
    f = [res[f"plate.f[{k}]"][-1] for k in range(1, 21)]
    # eq. 16 (paper formulation, 3 x 5, pinned-free with the hub); 15 modes, then zeros
    for want in [4.914, 15.926, 33.228, 66.761, 73.465, 86.1]:
        assert min(abs(x - want) for x in f[:15]) <= 1e-3 * want, (want, f)
    assert f[15:] == [0.0] * 5
    assert f[:15] == sorted(f[:15])


def test_forcing_f1_on_the_locked_plate(fmu_path):
    f1 = np.array([(0.0, 1.0), (1.0, 1.0)], dtype=[("time", float), ("F1", float)])
    res = simulate_fmu(fmu_path, stop_time=0.5, output_interval=1e-3, input=f1, output=OUTPUTS,
                       start_values=preset("paper-fig10", **{"plate.formulation": 2}))
    assert np.all(res["theta_hub"] == 0.0)
    assert np.max(np.abs(res["w_tip"])) > 1e-4
    for n in OUTPUTS:
        assert np.all(np.isfinite(res[n])), n


def test_hsp_modes_json():
    d = json.loads(hsp("modes", "--json", "--set", "plate.formulation=2"))
    assert len(d["f_hz"]) == len(d["labels"]) == 15
    assert d["f_hz"] == sorted(d["f_hz"])
    assert all(lbl.startswith("(") and lbl.endswith(")") for lbl in d["labels"])
