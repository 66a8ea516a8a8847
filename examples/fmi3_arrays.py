#!/usr/bin/env python3
"""The FMI 3.0 FMU's arrays from Python (fmpy's FMU3Slave): one fmi3GetFloat64 call per array.

fmu/fmi3/HydraulicSlewingPlate.fmu declares two arrays (<Dimension> in modelDescription.xml):
`plate.f[20]` (the plate's lowest natural frequencies [Hz], a calculated parameter) and `acc[12]`
(a 4 x 3 grid of accelerometers on one arm of the plate [m/s^2], an output). The script runs the
default experiment (the built-in 30 deg move; stop time and step from the DefaultExperiment),
reads `plate.f` once and `acc` at every step, one call each (nValues = the array's size).
Prints each array's declaration; the non-zero frequencies and their largest relative difference
to `hsp modes --json` (the project's tool, without the FMU); the RMS of each accelerometer over
the run as the 4 x 3 grid; and the tip check: acc[11] (x = a, y = b/2) against the scalar outputs,
acc_tip (relative to the hub frame) plus a times the hub's angular acceleration (by central
differences of omega_hub).
Run: .venv/bin/python examples/fmi3_arrays.py [--fmu FMU] [--modes FILE: hsp modes --json's output]
"""
import argparse
import json
import pathlib
import shutil
import subprocess

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave

ROOT = pathlib.Path(__file__).resolve().parents[1]
ap = argparse.ArgumentParser()
ap.add_argument("--fmu", default=str(ROOT / "fmu" / "fmi3" / "HydraulicSlewingPlate.fmu"))
ap.add_argument("--modes", help="a file with the output of `hsp modes --json` (default: run it)")
a = ap.parse_args()
modes = pathlib.Path(a.modes).read_text() if a.modes else subprocess.run(
    ["cargo", "run", "--release", "--quiet", "--bin", "hsp", "--", "modes", "--json"],
    cwd=ROOT, capture_output=True, text=True, check=True).stdout

md = read_model_description(a.fmu)
var = {v.name: v for v in md.modelVariables}
size = {v.name: int(v.dimensions[0].start) for v in md.modelVariables if v.dimensions}
for name, n in size.items():
    print(f"array {name}[{n}]: {var[name].type}, causality {var[name].causality}, unit {var[name].unit}")
stop, h = float(md.defaultExperiment.stopTime), float(md.defaultExperiment.stepSize)
steps = round(stop / h)
unzipped = extract(a.fmu)
fmu = FMU3Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier)
fmu.instantiate()
fmu.enterInitializationMode(startTime=0.0, stopTime=stop)
fmu.exitInitializationMode()
f_hz = np.array(fmu.getFloat64([var["plate.f"].valueReference], size["plate.f"]))
acc, scalars = [], []
for i in range(steps + 1):
    acc.append(fmu.getFloat64([var["acc"].valueReference], size["acc"]))
    scalars.append(fmu.getFloat64([var["acc_tip"].valueReference, var["omega_hub"].valueReference]))
    if i < steps:
        fmu.doStep(currentCommunicationPoint=i * h, communicationStepSize=h)
fmu.terminate()
fmu.freeInstance()
shutil.rmtree(unzipped, ignore_errors=True)
acc, (acc_tip, omega_hub) = np.array(acc), np.array(scalars).T

ref = np.array(json.loads(modes)["f_hz"])[: len(f_hz)]
print(f"plate.f, {np.count_nonzero(f_hz)} non-zero [Hz]: " + " ".join(f"{f:.4g}" for f in f_hz[f_hz > 0]))
print(f"max relative difference plate.f vs hsp modes --json: {np.max(np.abs(f_hz[:len(ref)] - ref) / ref):.1e}")
print(f"acc RMS over {stop:g} s [m/s^2]:" + "".join(f"{y:>10s}" for y in ("y = b/6", "y = b/2", "y = 5b/6")))
for i, row in enumerate(np.sqrt(np.mean(acc**2, axis=0)).reshape(4, 3)):  # rows x = a/4 ... a
    print(f"{f'x = {i + 1}a/4':28s}" + "".join(f"{v:10.4f}" for v in row))
rigid = acc_tip + float(var["plate.a"].start) * np.gradient(omega_hub, h)  # a d(omega_hub)/dt
err = np.max(np.abs(acc[2:-2, 10] - rigid[2:-2])) / np.max(np.abs(acc[:, 10]))
print(f"tip check: max |acc[11] - (acc_tip + a d omega_hub/dt)| / max |acc[11]| = {err:.1e} "
      f"(central differences at {h * 1e3:g} ms)")
