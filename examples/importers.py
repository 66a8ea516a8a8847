#!/usr/bin/env python3
"""Every importer this checkout can drive, on the default experiment, against one reference.

What it shows
    The default experiment (the FMU's own 30 deg slewing move, 6 s, outputs every 5 ms, the
    FMU's tolerance) run by each importer the project names (docs/ecosystem.md), in each FMI
    version and interface it offers: fmpy (FMI 2.0 and 3.0, Co-Simulation and Model Exchange
    with CVode at the FMU's tolerance and its state nominals), libcosim (FMI 2.0 Co-Simulation;
    libcosim 0.0.6 reads no FMI 3.0) and ecos (FMI 2.0 and 3.0 Co-Simulation). The reference is
    fmpy's FMI 2.0 Co-Simulation run. For each run: the largest difference of every output from
    the reference as a fraction of the output's range, by group (the groups of
    model_exchange.py), over the points before the last, and the same at the last point (fmpy
    passes the stop time; libcosim and ecos do not, so there the FMU ends on its last step's
    dense output instead of on the point).

How to run (from the repository root, after `cargo run --release --bin hsp -- package`):
    .venv/bin/python examples/importers.py [--fmu fmu/HydraulicSlewingPlate.fmu]
        [--fmu3 fmu/fmi3/HydraulicSlewingPlate.fmu]
docs/ecosystem.md quotes the table of one run.
"""

import argparse
import contextlib
import os
import pathlib
import shutil
import sys
import tempfile

import numpy as np
from fmpy import read_model_description, simulate_fmu

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from model_exchange import GROUPS, OUTPUTS  # noqa: E402  (the one list of the output groups)

ROOT = pathlib.Path(__file__).resolve().parents[1]


def column(res, name):
    """An output's column; FMI 3.0 holds acc[1..12] as one array variable `acc`."""
    if name in res.dtype.names:
        return np.asarray(res[name], dtype=float)
    base, _, index = name.partition("[")
    return np.asarray(res[base], dtype=float)[:, int(index.rstrip("]")) - 1]


def fmpy_run(fmu, interface, experiment):
    stop, step, tol = experiment
    outputs = sorted({n.partition("[")[0] for n in OUTPUTS}) if "fmi3" in str(fmu) else OUTPUTS
    kwargs = dict(solver="CVode", relative_tolerance=tol) if interface == "ModelExchange" else {}
    res = simulate_fmu(fmu, fmi_type=interface, stop_time=stop, output_interval=step,
                       output=outputs, **kwargs)
    return np.array([column(res, n) for n in OUTPUTS]).T[1:]  # the points after t = 0


def libcosim_run(fmu, experiment):
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    stop, step, _ = experiment
    md = read_model_description(fmu)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    execution = CosimExecution.from_step_size(step_size=int(round(step * 1e9)))
    plate = execution.add_local_slave(CosimLocalSlave(fmu_path=str(fmu), instance_name="plate"))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    refs = [vr[n] for n in OUTPUTS]
    rows = []
    for _ in range(round(stop / step)):
        assert execution.step()
        rows.append(observer.last_real_values(slave_index=plate, variable_references=refs))
    return np.array(rows)


@contextlib.contextmanager
def quiet_stdout():
    """libcosim and ecos log to the process's standard output from C++ (debug, trace, warnings):
    to /dev/null while it runs, so that this script prints only its table."""
    sys.stdout.flush()
    saved = os.dup(1)
    with open(os.devnull, "w") as null:
        os.dup2(null.fileno(), 1)
        try:
            yield
        finally:
            sys.stdout.flush()
            os.dup2(saved, 1)
            os.close(saved)


def ecos_run(fmu, experiment):
    """ecos through a one-component structure. ecos 0.7.2 reads an FMI 3.0 array variable as
    one scalar (`acc` is acc[1]) and has no name for its other elements: those columns are NaN."""
    from ecospy import EcosSimulation, EcosSimulationStructure

    stop, step, _ = experiment
    structure = EcosSimulationStructure()
    structure.add_model("plate", str(fmu))
    sim = EcosSimulation(step, structure=structure)
    try:
        assert sim.init(0)
        readable = []
        for n in OUTPUTS:
            try:
                sim.get_real(f"plate::{n}")
                readable.append(n)
            except Exception:  # "No real property plate::acc[1] found!"
                pass
        rows = []
        for _ in range(round(stop / step)):
            sim.step()
            rows.append([sim.get_real(f"plate::{n}") if n in readable else np.nan for n in OUTPUTS])
    finally:
        sim.terminate()
    return np.array(rows)


def quiet(run):
    with quiet_stdout():
        return run()


def worst_by_group(got, ref):
    """{group: (before the last point, at the last point)}: the largest |got - ref| / range."""
    span = np.ptp(ref, axis=0)
    span[span == 0] = 1.0
    before = np.max(np.abs(got[:-1] - ref[:-1]), axis=0) / span
    last = np.abs(got[-1] - ref[-1]) / span
    out = {}
    for group, names in GROUPS.items():
        k = [OUTPUTS.index(n) for n in names if np.all(np.isfinite(got[:, OUTPUTS.index(n)]))]
        out[group] = (np.max(before[k]), np.max(last[k])) if k else (np.nan, np.nan)
    return out


def unread(got):
    """The outputs a run could not read (NaN columns)."""
    return [n for k, n in enumerate(OUTPUTS) if not np.all(np.isfinite(got[:, k]))]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--fmu", default=str(ROOT / "fmu" / "HydraulicSlewingPlate.fmu"))
    ap.add_argument("--fmu3", default=str(ROOT / "fmu" / "fmi3" / "HydraulicSlewingPlate.fmu"))
    a = ap.parse_args(argv)
    de = read_model_description(a.fmu).defaultExperiment
    experiment = (float(de.stopTime), float(de.stepSize), float(de.tolerance))
    with tempfile.TemporaryDirectory() as tmp:
        # fmpy names FMI 3.0 files by folder; a copy keeps the two FMUs' paths apart.
        fmu3 = pathlib.Path(tmp) / "fmi3" / "HydraulicSlewingPlate.fmu"
        fmu3.parent.mkdir()
        shutil.copy(a.fmu3, fmu3)
        ref = fmpy_run(a.fmu, "CoSimulation", experiment)
        runs = [
            ("fmpy", "FMI 2.0", "CS", lambda: ref),
            ("fmpy", "FMI 3.0", "CS", lambda: fmpy_run(fmu3, "CoSimulation", experiment)),
            ("fmpy (CVode)", "FMI 2.0", "ME", lambda: fmpy_run(a.fmu, "ModelExchange", experiment)),
            ("fmpy (CVode)", "FMI 3.0", "ME", lambda: fmpy_run(fmu3, "ModelExchange", experiment)),
            ("libcosim", "FMI 2.0", "CS", lambda: libcosim_run(a.fmu, experiment)),
            ("ecos", "FMI 2.0", "CS", lambda: ecos_run(a.fmu, experiment)),
            ("ecos", "FMI 3.0", "CS", lambda: ecos_run(fmu3, experiment)),
        ]
        runs = [(tool, version, interface, run if tool not in ("ecos", "libcosim")
                 else (lambda run=run: quiet(run)))
                for tool, version, interface, run in runs
        ]
        stop, step, tol = experiment
        print(f"default experiment: {stop:g} s, points every {step:g} s, tolerance {tol:g}; "
              "reference fmpy FMI 2.0 CS; largest |difference| / range, before the last point "
              "(at the last point)")
        groups = list(GROUPS)
        print("| tool | FMI | interface | " + " | ".join(groups) + " |")
        print("| --- | --- | --- | " + " | ".join("---:" for _ in groups) + " |")
        notes = []
        for tool, version, interface, run in runs:
            got = run()
            worst = worst_by_group(got, ref)
            cells = [f"{b:.1e} ({l:.0e})" for b, l in (worst[g] for g in groups)]
            missing = unread(got)
            if missing:
                notes.append(f"{tool} {version} {interface} cannot read {', '.join(missing)}: "
                             "its group's figure is over the others")
                cells = [c + " *" if any(n in GROUPS[g] for n in missing) else c
                         for c, g in zip(cells, groups)]
            print(f"| {tool} | {version} | {interface} | " + " | ".join(cells) + " |")
        for note in notes:
            print(f"* {note}")


if __name__ == "__main__":
    main()
