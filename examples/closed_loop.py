#!/usr/bin/env python3
"""Your own position loop from Python, on the co-simulation FMU (fmpy's FMU2Slave).

With `controller.external = true` the analog controller is out and the input `e_in` [V] drives
the servo-valve coil. This loop runs at a 1 ms communication step:
    e_in = Kp (r - y_pot) + Kd (dr/dt - k_pot omega_motor),   y_pot = k_pot theta_motor [V],
r [V] being the FMU's default move (minimum jerk, 30 deg of motor angle over 2 s from 0.5 s: the
start values of reference.*) computed here; reference.angle = 0 turns the built-in one off.
With Kp = A1 A2 = 20, the analog loop's gain, it must match the FMU's own analog loop of eq. 1
(run too, with controller.k_pl = 0: the default analog controller also feeds back the load
pressure, which this loop leaves out);
the last run adds a derivative term. Prints k_pot, then per run the final motor angle, overshoot,
settling time of the motor angle and residual peak of |w_tip| after the move (tools/manoeuvre.py:
from the move's end, 2 % of the move, "not settled" when the run ends first) and peak |w_tip|;
and the P loop's largest gaps to the analog loop.  Run: .venv/bin/python examples/closed_loop.py [--fmu FMU]
"""
import argparse
import math
import pathlib
import shutil
import sys

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "tools"))
import manoeuvre  # noqa: E402  (tools/manoeuvre.py: settling and residual, one definition)

ap = argparse.ArgumentParser()
ap.add_argument("--fmu", default=str(pathlib.Path(__file__).parents[1] / "fmu" / "HydraulicSlewingPlate.fmu"))
fmu = ap.parse_args().fmu
md = read_model_description(fmu)
vr = {v.name: v.valueReference for v in md.modelVariables}
start = {v.name: float(v.start) for v in md.modelVariables if v.type == "Real" and v.start is not None}
k_pot = start["controller.k_pot"]  # V/rad
# The built-in move's amplitude, start and duration; the default experiment's stop time.
MOVE, T0, DUR = start["reference.angle"], start["reference.t_start"], start["reference.duration"]
STOP, H = float(md.defaultExperiment.stopTime), 1e-3
KP = start["controller.A1"] * start["controller.A2"]  # the analog loop's gain: 20


def run(kp=None, kd=0.0):  # kp None: the FMU's analog loop of eq. 1 and built-in move
    slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier)
    slave.instantiate()
    slave.setupExperiment(startTime=0.0, stopTime=STOP)
    if kp is None:
        slave.setReal([vr["controller.k_pl"]], [0.0])
    else:
        slave.setBoolean([vr["controller.external"]], [True])
        slave.setReal([vr["reference.angle"]], [0.0])
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    rows = []
    for i in range(round(STOP / H) + 1):
        theta, omega, y, w = slave.getReal([vr[n] for n in ("theta_motor", "omega_motor", "y_pot", "w_tip")])
        rows.append((i * H, theta, w, y))
        s = min(max((i * H - T0) / DUR, 0.0), 1.0)  # minimum jerk: r [V] and dr/dt [V/s]
        r = k_pot * MOVE * (10 * s**3 - 15 * s**4 + 6 * s**5)
        dr = k_pot * MOVE * (30 * s**2 - 60 * s**3 + 30 * s**4) / DUR
        if kp is not None:
            slave.setReal([vr["e_in"]], [kp * (r - y) + kd * (dr - k_pot * omega)])
        if i < round(STOP / H):
            slave.doStep(currentCommunicationPoint=i * H, communicationStepSize=H)
    slave.terminate()
    slave.freeInstance()
    return np.array(rows)


unzipped = extract(fmu)
runs = {"analog loop (FMU)": run(), f"P, Kp = {KP:g} (Python)": run(kp=KP),
        "PD, Kd = 1 s (Python)": run(kp=KP, kd=1.0)}
shutil.rmtree(unzipped, ignore_errors=True)
_, theta, _, y = runs["analog loop (FMU)"][-1]  # the FMU's outputs at the end of the run
print(f"k_pot = {k_pot:.6f} V/rad (10 V / 150 deg = {10 / math.radians(150):.6f}; "
      f"y_pot / theta_motor at {STOP:g} s: {y / theta:.6f})")
print(f"{'':24s}{'final':>10s}{'overshoot':>11s}{'settling':>13s}{'residual':>11s}{'peak w_tip':>11s}")
print(f"{'':24s}{'[deg]':>10s}{'[%]':>11s}{'[s]':>13s}{'[mm]':>11s}{'[mm]':>11s}")
for label, (t, theta, w, _) in ((k, x.T) for k, x in runs.items()):
    settling = manoeuvre.settling(t, theta, MOVE, T0 + DUR)  # the move's end: T0 + DUR
    settle = "not settled" if math.isnan(settling) else f"{settling:.3f}"
    print(f"{label:24s}{math.degrees(theta[-1]):10.3f}{manoeuvre.overshoot_pct(theta, MOVE):11.3f}"
          f"{settle:>13s}{1e3 * manoeuvre.residual_peak(t, w, T0 + DUR):11.3f}{1e3 * np.abs(w).max():11.3f}")
gap = np.abs(runs[f"P, Kp = {KP:g} (Python)"] - runs["analog loop (FMU)"]).max(axis=0)
print(f"P loop - analog loop: max |theta_motor| {math.degrees(gap[1]):.4f} deg, max |w_tip| {1e3 * gap[2]:.3f} mm")
