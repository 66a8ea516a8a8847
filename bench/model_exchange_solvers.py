#!/usr/bin/env python3
"""scipy's solve_ivp (Radau, BDF, LSODA) and SUNDIALS CVODE (fmpy's CVodeSolver) on the FMU's
Model Exchange interface: the competitors of `bench-fmu` on the nonlinear plant, whose
right-hand side only the FMU has.

Usage, by the FMU speed benchmark (`cargo run --release --bin bench-fmu`), from the repository
root:

    .venv/bin/python bench/model_exchange_solvers.py RUN.json

RUN.json: {"fmu": the packaged FMU, "sets": ["NAME=VALUE", ...] (set before the
initialisation, after "r" = 1), "stop": s, "step": the communication step, "outputs": [names],
"reference": the outputs at the points step, 2 step, ..., stop (one row a point, from the FMU at
rtol 1e-10), "target": the error to reach (the FMU's at its default rtol)}.

Each method runs for rtol 1e-3, 1e-4, ... (bench/scipy_reference.py's RTOLS) until a run reaches
the target and the next tighter one is slower, or a run takes over TOO_LONG (60 s; a method
stopped so before it reached the target is reported with its most accurate run); atol = 1e-2 rtol times
each state's nominal value (`fmi2GetNominalsOfContinuousStates`), as the FMU's own solver.
  - scipy: the method's OdeSolver stepped to the stop time (what solve_ivp does), the states at
    the points from its dense output; f(t, x) is fmi2SetTime, fmi2SetContinuousStates,
    fmi2GetDerivatives, and the Jacobian (Radau, BDF, LSODA alike) comes column by column from
    fmi2GetDirectionalDerivative (exact, as the FMU's own solver has it).
  - CVODE: fmpy's CVodeSolver (SUNDIALS 7, BDF, dense LU, difference-quotient Jacobian, the
    maximum step fmpy's simulate_fmu sets, stop / 50), called to every point as simulate_fmu does.
The time of a run is its wall time: the integration and, at every point, the reading of the
outputs (fmi2SetContinuousStates for scipy, whose points come from its dense output, and
fmi2GetReal), as the FMU's time in bench-fmu includes its fmi2GetReal. Error: the outputs'
largest deviation from the reference relative to their largest magnitude (scipy_reference's
delivered_error). Beside the runs it measures the cost of one right-hand side through fmpy
(ctypes), and the FMU's own Co-Simulation driven through fmpy (fmi2DoStep and fmi2GetReal at
every point) at its default rtol, which is the FMU's run with the same Python overhead per point.
Prints {"Radau": [{rtol, err, wall, steps, nfev, njev, nlu}, ...], ..., "CVODE": [...],
"stopped": [the methods stopped by TOO_LONG before the target], "f_us": the least cost of one
right-hand side in 10 batches of 200 calls [us], "cs_fmpy": {"wall", "err"}} as JSON on stdout.
"""
import json
import os
import pathlib
import shutil
import sys
import time
from ctypes import POINTER, byref, c_double, c_int, c_long, c_void_p

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from fmpy.sundials import CVodeSolver
from fmpy.sundials.libraries import sundials_cvode
from scipy.integrate import BDF, LSODA, Radau

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "examples"))
from model_exchange import MEInstance, set_values  # noqa: E402
from scipy_reference import RTOLS, delivered_error  # noqa: E402

SCIPY = {"Radau": Radau, "BDF": BDF, "LSODA": LSODA}
# The FMU's default relative tolerance (the default experiment's), for its run through fmpy.
FMU_RTOL = 1e-6
TOO_LONG = 60.0
_P = POINTER(c_double)


def counter(name):
    """A CVodeGetNum... function of SUNDIALS: (cvode_mem, long *) -> status."""
    f = getattr(sundials_cvode, name)
    f.argtypes = [c_void_p, POINTER(c_long)]
    f.restype = c_int
    return f


CV_STATS = {k: counter(n) for k, n in [("steps", "CVodeGetNumSteps"), ("nfev", "CVodeGetNumRhsEvals"),
                                       ("nfev_jac", "CVodeGetNumLinRhsEvals"), ("njev", "CVodeGetNumJacEvals"),
                                       ("nlu", "CVodeGetNumLinSolvSetups")]}


class Plant:
    """The FMU's Model Exchange instance at its start: f, its Jacobian, the outputs."""

    def __init__(self, md, unzipped, values, outputs):
        self.me = MEInstance(md, unzipped, values)
        self.x0 = self.me.x.copy()
        self.nominal = self.me.nominal.copy()
        refs = {v.name: v.valueReference for v in md.modelVariables}
        self.outputs = [refs[o] for o in outputs]
        self.der = [d.variable.valueReference for d in md.derivatives]
        self.states = [d.variable.derivative.valueReference for d in md.derivatives]

    def f(self, t, x):
        return self.me.derivatives(t, x)

    def jac(self, t, x):
        fmu = self.me.fmu
        fmu.setTime(t)
        fmu.setContinuousStates(np.ascontiguousarray(x).ctypes.data_as(_P), self.me.n)
        return np.array([fmu.getDirectionalDerivative(self.der, [s], [1.0]) for s in self.states]).T

    def read(self, t, x):
        """The outputs at (t, x)."""
        fmu = self.me.fmu
        fmu.setTime(t)
        fmu.setContinuousStates(np.ascontiguousarray(x).ctypes.data_as(_P), self.me.n)
        return fmu.getReal(self.outputs)


def scipy_run(plant, method, rtol, stop, points):
    started = time.perf_counter()
    solver = SCIPY[method](plant.f, 0.0, plant.x0.copy(), stop, rtol=rtol, atol=1e-2 * rtol * plant.nominal,
                           jac=plant.jac)
    y = np.empty((len(points), len(plant.outputs)))
    k, steps = 0, 0
    while solver.status == "running":
        message = solver.step()
        if solver.status == "failed":
            raise RuntimeError(message)
        steps += 1
        j = int(np.searchsorted(points, solver.t, side="right"))
        if j > k:
            dense = solver.dense_output()
            for i in range(k, j):
                y[i] = plant.read(points[i], dense(points[i]))
            k = j
    wall = time.perf_counter() - started
    return y, dict(wall=wall, steps=steps, nfev=int(solver.nfev), njev=int(solver.njev), nlu=int(solver.nlu))


def cvode_run(plant, rtol, stop, points):
    fmu, n = plant.me.fmu, plant.me.n
    fmu.setTime(0.0)
    fmu.setContinuousStates(plant.x0.ctypes.data_as(_P), n)

    def nominals(pointer, size):
        np.ctypeslib.as_array(pointer, (size,))[:] = 1e-2 * plant.nominal

    started = time.perf_counter()
    solver = CVodeSolver(nx=n, nz=0, get_x=fmu.getContinuousStates, set_x=fmu.setContinuousStates,
                         get_dx=fmu.getDerivatives, get_z=lambda z, nz: None, get_nominals=nominals,
                         set_time=fmu.setTime, input=None, startTime=0.0, maxStep=stop / 50.0,
                         relativeTolerance=rtol)
    y = np.empty((len(points), len(plant.outputs)))
    t = 0.0
    for i, t_next in enumerate(points):
        solver.step(t, t_next)
        fmu.setTime(t_next)
        y[i] = fmu.getReal(plant.outputs)
        t = t_next
    wall = time.perf_counter() - started
    stats = {}
    for key, get in CV_STATS.items():
        v = c_long()
        get(solver.cvode_mem, byref(v))
        stats[key] = v.value
    stats["nfev"] += stats.pop("nfev_jac")  # the difference quotients' evaluations too
    return y, dict(wall=wall, **stats)


def cs_through_fmpy(md, unzipped, values, outputs, stop, step):
    """The FMU's own Co-Simulation at FMU_RTOL, driven point by point from Python."""
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="cs")
    fmu.instantiate()
    fmu.setupExperiment(tolerance=FMU_RTOL, startTime=0.0, stopTime=stop)
    set_values(fmu, md, values)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    refs = [v.valueReference for o in outputs for v in md.modelVariables if v.name == o]
    n = int(round(stop / step))
    y = np.empty((n, len(refs)))
    started = time.perf_counter()
    for k in range(n):
        fmu.doStep(currentCommunicationPoint=k * step, communicationStepSize=step)
        y[k] = fmu.getReal(refs)
    wall = time.perf_counter() - started
    fmu.terminate()
    fmu.freeInstance()
    return y, wall


def main(path):
    # The JSON goes to the standard output as it was; everything else printed there (fmpy's
    # logger, the FMU's messages) to the standard error.
    result = os.fdopen(os.dup(1), "w")
    os.dup2(2, 1)
    run = json.loads(pathlib.Path(path).read_text())
    stop, step, target = run["stop"], run["step"], run["target"]
    reference = np.array(run["reference"])
    n = int(round(stop / step))
    points = np.arange(1, n + 1) * step
    points[-1] = stop
    values = {"r": 1.0}
    values.update(s.split("=", 1) for s in run["sets"])
    md = read_model_description(run["fmu"])
    unzipped = extract(run["fmu"])
    out = {}
    try:
        plant = Plant(md, unzipped, values, run["outputs"])
        # The least of 10 batches: the cost with the least of the machine's load in it.
        batches = []
        for _ in range(10):
            started = time.perf_counter()
            for _ in range(200):
                plant.f(0.0, plant.x0)
            batches.append((time.perf_counter() - started) / 200 * 1e6)
        out["f_us"] = min(batches)
        y, wall = cs_through_fmpy(md, unzipped, values, run["outputs"], stop, step)
        out["cs_fmpy"] = dict(wall=wall, err=delivered_error(y, reference))
        print(f"FMU through fmpy (CS, rtol {FMU_RTOL:g}): {wall:.2f} s; f through fmpy {out['f_us']:.1f} us",
              file=sys.stderr)
        for method in [*SCIPY, "CVODE"]:
            runs, reached = [], None
            for rtol in RTOLS:
                try:
                    if method == "CVODE":
                        y, rec = cvode_run(plant, rtol, stop, points)
                    else:
                        y, rec = scipy_run(plant, method, rtol, stop, points)
                except Exception as ex:  # noqa: BLE001 - record any failure, go on
                    print(f"{method} rtol {rtol:g}: {ex}", file=sys.stderr)
                    continue
                rec.update(rtol=rtol, err=delivered_error(y, reference))
                runs.append(rec)
                print(f"{method:6} rtol {rtol:7.0e} err {rec['err']:.2e} {rec['wall']:.2f}s {rec['steps']} steps",
                      file=sys.stderr)
                if rec["wall"] > TOO_LONG:
                    if reached is None and rec["err"] > target:
                        out.setdefault("stopped", []).append(method)
                    break
                if reached is not None and rec["wall"] > reached:
                    break  # tighter tolerances only take longer
                if rec["err"] <= target and reached is None:
                    reached = rec["wall"]
            out[method] = runs
        plant.me.free()
    finally:
        shutil.rmtree(unzipped, ignore_errors=True)
    json.dump(out, result)
    result.close()


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
