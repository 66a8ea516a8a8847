#!/usr/bin/env python3
"""Parameter sweeps of the HydraulicSlewingPlate FMU on Dask (dask.distributed).

Each point of a grid (``--grid NAME=v1,v2,...``, the Cartesian product of all grids) or of a
random sample (``--sample N --range NAME=lo:hi[:log]``) is one Dask task: it runs the FMU with
fmpy's low-level API (co-simulation, fixed communication step) and returns one row: the
parameters, the summary metrics and the status. A point the FMU refuses (fmi2Error at
initialisation, fmi2Discard in a step, any exception) becomes a row with status ``error`` and the
FMU's message; the sweep goes on.

The FMU's bytes are sent to every worker once (a worker plugin), and each worker extracts them once
into its local directory, so a cluster needs no shared file system.

Each run is the FMU's default experiment unless told otherwise: the stop time and the
communication step of the model description's <DefaultExperiment> (``--stop``, ``--step``), no
input (``--input r=1`` adds a constant 1 V to the reference), the built-in move of the command
generator. The settings used are printed first. The measures of the manoeuvre are those of
tools/manoeuvre.py (docs/model.md, "Measures of a manoeuvre"), the rule `hsp run` prints: settling
times counted from the end of the move (t = 0 without a move) into 2 % of the commanded change
around the command's target, the residual peak of |w_tip| after the move and its ring-down time to
1 mm; "not settled" and "not rung down" (an empty cell in the CSV, NaN in the rows) when the run
ends first.

Runs on a LocalCluster by default (``--workers N``), or on any running scheduler
(``--scheduler tcp://host:8786``). Prints a table of the points, writes a CSV (``--out``) and, with
``--plot METRIC``, a picture of one metric against one or two swept parameters.

Example:

    python tools/sweep.py --grid torsion_bar.k=1000,2500,5000 --grid plate.zeta=0.005,0.02 \\
        --set hydraulics.motor_coupled=true --plot residual_peak_w_tip
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import io
import itertools
import math
import os
import pathlib
import random
import shutil
import sys
import tempfile
import time
import zipfile

# tools/manoeuvre.py, beside this file (in the repository and in a Dask worker's directory).
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import manoeuvre  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]
DEFAULT_FMU = ROOT / "fmu" / "HydraulicSlewingPlate.fmu"

#: Outputs recorded at every communication point to compute the metrics.
RECORDED = ["y_pot", "theta_motor", "theta_hub", "w_tip", "p_load"]
#: Solver statistics read at the end of a run (integer outputs of the FMU).
SOLVER_STATS = ["solver.steps", "solver.rejected", "solver.f_evals", "solver.jac_evals", "solver.lu"]
#: The metrics of a row, in CSV order.
METRICS = [
    "peak_w_tip",
    "residual_peak_w_tip",
    "ring_down_w_tip",
    "settling_after_move_theta_hub",
    "settling_after_move_y_pot",
    "final_theta_hub",
    "peak_p_load",
] + [s.replace(".", "_") for s in SOLVER_STATS] + ["wall_s"]


# ------------------------------------------------------------------------------------------------
# One point, anywhere (a Dask worker or this process)
# ------------------------------------------------------------------------------------------------

def extract(fmu_bytes: bytes, directory: str) -> str:
    """Extracts an FMU archive into a new folder of `directory`; returns the folder."""
    digest = hashlib.sha256(fmu_bytes).hexdigest()[:16]
    target = os.path.join(directory, f"hsp-fmu-{digest}")
    if not os.path.isdir(target):
        partial = tempfile.mkdtemp(dir=directory)
        with zipfile.ZipFile(io.BytesIO(fmu_bytes)) as z:
            z.extractall(partial)
        try:
            os.rename(partial, target)
        except OSError:  # another process of the same machine got there first
            shutil.rmtree(partial, ignore_errors=True)
    return target


def metrics(t, series, stats, wall, values):
    """The summary metrics of one run: peak |w_tip|, the measures of the manoeuvre
    (tools/manoeuvre.py: residual peak of |w_tip| after the move and its ring-down time to 1 mm,
    settling times of the hub and y_pot after the move; NaN when the run ends first or the loop
    has no target), final hub angle, peak |p_load|, solver statistics and wall time. `values`
    are the run's parameter values and inputs as `manoeuvre.command` reads them."""
    m = manoeuvre.measures(t, series, values)
    row = {
        "peak_w_tip": max(abs(v) for v in series["w_tip"]),
        "residual_peak_w_tip": m["residual_peak_w_tip"],
        "ring_down_w_tip": m["ring_down_w_tip"],
        "settling_after_move_theta_hub": m["settling_theta_hub"],
        "settling_after_move_y_pot": m["settling_y_pot"],
        "final_theta_hub": series["theta_hub"][-1],
        "peak_p_load": max(abs(v) for v in series["p_load"]),
        "wall_s": wall,
    }
    for name, value in zip(SOLVER_STATS, stats):
        row[name.replace(".", "_")] = value
    return row


#: The parameters the measures of a manoeuvre read (manoeuvre.command).
COMMAND_PARAMETERS = ["reference.angle", "reference.t_start", "reference.duration",
                      "controller.k_pot", "controller.external"]


def command_values(variables, values, inputs):
    """The values `manoeuvre.command` reads, typed: each of COMMAND_PARAMETERS from `values`
    (name -> value as given) or its start value, and the input r from `inputs` (0 when absent)."""
    def value(name):
        v = values.get(name, variables[name].start)
        return str(v).strip().lower() in ("true", "1") if variables[name].type == "Boolean" else float(v)

    typed = {name: value(name) for name in COMMAND_PARAMETERS}
    typed["r"] = float(inputs.get("r", 0.0))
    return typed


def default_experiment(fmu_path):
    """The stop time and communication step of the FMU's <DefaultExperiment> (None where it
    gives none)."""
    from fmpy import read_model_description

    e = read_model_description(str(fmu_path)).defaultExperiment
    return tuple(None if e is None or getattr(e, a) is None else float(getattr(e, a))
                 for a in ("stopTime", "stepSize"))


def describe(options, fixed, default):
    """The settings of a sweep as one printed line; `default` is the DefaultExperiment's
    (stop, step)."""
    def mark(value, own):
        return f"{value:g} s" + (" (DefaultExperiment)" if value == own else "")

    inputs = ", ".join(f"{k}={v}" for k, v in options["inputs"].items()) or "none"
    tol = options.get("tolerance")
    return (f"settings: stop {mark(options['stop'], default[0])}, step {mark(options['step'], default[1])}, "
            f"tolerance {'%g' % tol if tol else 'solver.rtol'}, inputs {inputs}, "
            f"fixed {', '.join(f'{k}={v}' for k, v in fixed.items()) or 'none'}")


def format_table(rows, names):
    """The rows as a text table: the swept parameters, the status and the main metrics; a
    settling time that the run does not reach reads "not settled", a ring-down time "not rung
    down"."""
    def time(v, words):
        return words if math.isnan(v) else f"{v:.3f}"

    cols = [("status", 7), ("peak w_tip [mm]", 16), ("residual peak [mm]", 19),
            ("ring-down 1 mm [s]", 19), ("settling hub [s]", 17), ("settling y_pot [s]", 19),
            ("final hub [deg]", 16)]
    widths = [max(len(n), 10) + 2 for n in names]
    lines = ["".join(f"{n:>{w}s}" for n, w in zip(names, widths))
             + "".join(f"{c:>{w}s}" for c, w in cols)]
    for r in rows:
        line = "".join(f"{r[n]:>{w}.6g}" if isinstance(r[n], float) else f"{str(r[n]):>{w}s}"
                       for n, w in zip(names, widths)) + f"{r['status']:>7s}"
        if r["status"] != "ok":
            lines.append(line + "  " + r["message"])
            continue
        residual = r["residual_peak_w_tip"]
        lines.append(line + f"{r['peak_w_tip'] * 1e3:16.3f}"
                     f"{'-' if math.isnan(residual) else f'{residual * 1e3:.3f}':>19s}"
                     f"{time(r['ring_down_w_tip'], 'not rung down'):>19s}"
                     f"{time(r['settling_after_move_theta_hub'], 'not settled'):>17s}"
                     f"{time(r['settling_after_move_y_pot'], 'not settled'):>19s}"
                     f"{math.degrees(r['final_theta_hub']):16.3f}")
    return "\n".join(lines)


def run_point(unzipdir: str, params: dict, options: dict) -> dict:
    """Runs the FMU extracted in `unzipdir` with `params` (name -> value, as text or number) and
    `options` (inputs, stop, step, tolerance); returns the row: status, message, metrics."""
    from fmpy import read_model_description
    from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
    from fmpy.fmi2 import fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE

    md = read_model_description(os.path.join(unzipdir, "modelDescription.xml"))
    variables = {v.name: v for v in md.modelVariables}
    messages = []

    def log(env, instance, status, category, message):
        if status >= 1:  # warnings, discards and errors: what a failed point reports
            messages.append(message.decode(errors="replace").replace("%%", "%"))

    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(log)
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(lambda n, s: None)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(lambda p: None)

    row = {"status": "ok", "message": ""}
    slave = None
    started = time.perf_counter()
    try:
        slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir,
                          modelIdentifier=md.coSimulation.modelIdentifier,
                          instanceName="sweep")
        slave.instantiate(callbacks=callbacks, loggingOn=False)
        stop, step = options["stop"], options["step"]
        slave.setupExperiment(tolerance=options.get("tolerance"), startTime=0.0, stopTime=stop)
        for name, value in list(params.items()) + list(options["inputs"].items()):
            set_value(slave, variables, name, value)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        vrs = [variables[n].valueReference for n in RECORDED if n in variables]
        names = [n for n in RECORDED if n in variables]
        n = int(round(stop / step))
        t = [0.0]
        values = [slave.getReal(vrs)]
        for i in range(n):
            t0 = i * step
            t1 = stop if i + 1 == n else (i + 1) * step
            slave.doStep(currentCommunicationPoint=t0, communicationStepSize=t1 - t0)
            t.append(t1)
            values.append(slave.getReal(vrs))
        stats = slave.getInteger([variables[s].valueReference for s in SOLVER_STATS])
        slave.terminate()
        series = {name: [v[k] for v in values] for k, name in enumerate(names)}
        for name in RECORDED:
            series.setdefault(name, [0.0] * len(t))
        values = command_values(variables, params, options["inputs"])
        row.update(metrics(t, series, stats, time.perf_counter() - started, values))
    except Exception as e:  # a failed point is a row, never a lost sweep
        detail = "; ".join(messages)
        row["status"] = "error"
        row["message"] = f"{e}: {detail}" if detail else str(e)
        row["wall_s"] = time.perf_counter() - started
    finally:
        if slave is not None:
            try:
                slave.freeInstance()
            except Exception:
                pass
    return row


def set_value(slave, variables, name, value):
    """Sets a variable by name, converting text to its type; a clear error names the culprit."""
    v = variables.get(name)
    if v is None:
        raise ValueError(f"{name}: no such variable in the FMU")
    vr = [v.valueReference]
    if v.type == "Real":
        slave.setReal(vr, [float(value)])
    elif v.type in ("Integer", "Enumeration"):
        slave.setInteger(vr, [int(float(value))])
    elif v.type == "Boolean":
        text = str(value).strip().lower()
        if text not in ("true", "false", "1", "0"):
            raise ValueError(f"{name}: expected true or false, got {value!r}")
        slave.setBoolean(vr, [text in ("true", "1")])
    else:
        raise ValueError(f"{name}: type {v.type} cannot be set by the sweep")


# ------------------------------------------------------------------------------------------------
# Dask
# ------------------------------------------------------------------------------------------------

def _plugin_class():
    from distributed.diagnostics.plugin import WorkerPlugin

    class ExtractFMU(WorkerPlugin):
        """Extracts the FMU once per worker, into the worker's local directory."""

        name = "hsp-fmu"

        def __init__(self, fmu_bytes: bytes):
            self.fmu_bytes = fmu_bytes
            self.path = None
            self.extractions = 0

        def setup(self, worker):
            self.path = extract(self.fmu_bytes, worker.local_directory)
            self.extractions += 1

    return ExtractFMU


def dask_point(params: dict, options: dict) -> dict:
    """A Dask task: one point on the worker's extracted FMU."""
    from distributed import get_worker

    worker = get_worker()
    plugin = worker.plugins["hsp-fmu"]
    row = run_point(plugin.path, params, options)
    row["worker"] = worker.address
    return row


def sweep(client, fmu_path, points, options):
    """Runs every point on the cluster of `client`; returns the rows in the order of `points`.
    Call it from the module `sweep` (`import sweep`), not from a script's `__main__`."""
    # The workers import this file as the module `sweep` (uploaded to each of them, so a cluster
    # needs no copy of the repository), and the tasks refer to its functions by name.
    # manoeuvre.py first: sweep imports it.
    here = pathlib.Path(__file__).resolve()
    client.upload_file(str(here.with_name("manoeuvre.py")))
    client.upload_file(str(here))
    fmu_bytes = pathlib.Path(fmu_path).read_bytes()
    plugin = _plugin_class()(fmu_bytes)
    if hasattr(client, "register_plugin"):
        client.register_plugin(plugin)
    else:  # dask.distributed < 2023.9
        client.register_worker_plugin(plugin)
    futures = client.map(dask_point, points, options=options, pure=False)
    rows = client.gather(futures, errors="raise")
    return [dict(p, **r) for p, r in zip(points, rows)]


# ------------------------------------------------------------------------------------------------
# Points, CSV, plot
# ------------------------------------------------------------------------------------------------

def parse_assignment(text, what):
    name, sep, value = text.partition("=")
    if not sep or not name.strip() or not value.strip():
        raise SystemExit(f"{what} '{text}': expected NAME=VALUE")
    return name.strip(), value.strip()


def grid_points(grids):
    """The Cartesian product of `[(name, [values])]`."""
    names = [n for n, _ in grids]
    return [dict(zip(names, combo)) for combo in itertools.product(*[v for _, v in grids])]


def sample_points(ranges, n, seed):
    """`n` points drawn uniformly (or log-uniformly) in `[(name, lo, hi, log)]`."""
    rng = random.Random(seed)
    points = []
    for _ in range(n):
        p = {}
        for name, lo, hi, log in ranges:
            u = rng.random()
            p[name] = math.exp(math.log(lo) + u * (math.log(hi) - math.log(lo))) if log else lo + u * (hi - lo)
        points.append(p)
    return points


def write_csv(path, rows, parameter_names):
    columns = list(parameter_names) + ["status", "message"] + METRICS + ["worker"]
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns, extrasaction="ignore")
        w.writeheader()
        for r in rows:  # NaN (not settled, not rung down, no measure) is an empty cell
            w.writerow({c: "" if isinstance(r.get(c), float) and math.isnan(r[c]) else r.get(c, "")
                        for c in columns})


def plot(rows, metric, x, y, path):
    """`metric` against parameter `x` (one line per value of `y` when given); failed points are
    marked at the bottom of the axes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = [r for r in rows if r["status"] == "ok"]
    fig, ax = plt.subplots(figsize=(8, 5))
    groups = {}
    for r in ok:
        groups.setdefault(r[y] if y else None, []).append(r)
    for key, rs in sorted(groups.items(), key=lambda kv: (kv[0] is None, float(kv[0]) if kv[0] is not None else 0)):
        rs = sorted(rs, key=lambda r: float(r[x]))
        label = f"{y} = {key}" if y else None
        ax.plot([float(r[x]) for r in rs], [float(r[metric]) for r in rs], "o-", label=label)
    failed = [r for r in rows if r["status"] != "ok"]
    if failed:
        ax.plot([float(r[x]) for r in failed], [0.0] * len(failed), "rx", label="failed")
    ax.set_xlabel(x)
    ax.set_ylabel(metric)
    ax.grid(True, alpha=0.3)
    if y or failed:
        ax.legend()
    ax.set_title(f"{metric} against {x}" + (f" and {y}" if y else ""))
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--fmu", default=str(DEFAULT_FMU), help="the FMU (default: %(default)s)")
    ap.add_argument("--grid", action="append", default=[], metavar="NAME=V1,V2,...",
                    help="values of one parameter; several grids give their Cartesian product")
    ap.add_argument("--sample", type=int, metavar="N", help="N random points in the --range boxes")
    ap.add_argument("--range", action="append", default=[], metavar="NAME=LO:HI[:log]",
                    help="range of one parameter for --sample (log: log-uniform)")
    ap.add_argument("--seed", type=int, default=0, help="random seed of --sample")
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                    help="a parameter fixed for every point")
    ap.add_argument("--input", action="append", default=[], metavar="NAME=VALUE",
                    help="a constant input from t = 0, such as r=1 (a 1 V step of the reference "
                    "added to the built-in move); default: none")
    ap.add_argument("--stop", type=float, help="stop time, s (default: the FMU's DefaultExperiment)")
    ap.add_argument("--step", type=float, help="communication step, s (default: the FMU's DefaultExperiment)")
    ap.add_argument("--tolerance", type=float, help="relative tolerance for fmi2SetupExperiment")
    ap.add_argument("--scheduler", metavar="ADDRESS",
                    help="a running Dask scheduler (tcp://host:8786); default: a LocalCluster")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 2,
                    help="LocalCluster workers (default: the number of CPUs)")
    ap.add_argument("--out", default=str(ROOT / "results" / "sweep.csv"), help="the CSV")
    ap.add_argument("--plot", metavar="METRIC", help="plot METRIC against the swept parameters")
    ap.add_argument("--plot-x", metavar="NAME", help="x axis parameter (default: the first swept)")
    ap.add_argument("--plot-by", metavar="NAME", help="one line per value of this parameter "
                    "(default: the second grid parameter, if any)")
    a = ap.parse_args(argv)

    if not pathlib.Path(a.fmu).exists():
        raise SystemExit(f"{a.fmu}: no such FMU (build it with: cargo run --release --bin hsp -- package)")
    if a.sample is not None:
        if a.grid:
            raise SystemExit("--grid and --sample exclude each other")
        ranges = []
        for r in a.range:
            name, spec = parse_assignment(r, "--range")
            parts = spec.split(":")
            if len(parts) not in (2, 3) or (len(parts) == 3 and parts[2] != "log"):
                raise SystemExit(f"--range '{r}': expected NAME=LO:HI or NAME=LO:HI:log")
            lo, hi = float(parts[0]), float(parts[1])
            log = len(parts) == 3
            if not lo < hi or (log and lo <= 0):
                raise SystemExit(f"--range '{r}': need LO < HI (and LO > 0 for log)")
            ranges.append((name, lo, hi, log))
        if not ranges or a.sample < 1:
            raise SystemExit("--sample N needs N >= 1 and at least one --range")
        points = sample_points(ranges, a.sample, a.seed)
        names = [r[0] for r in ranges]
    else:
        grids = []
        for g in a.grid:
            name, values = parse_assignment(g, "--grid")
            grids.append((name, [v.strip() for v in values.split(",") if v.strip()]))
        if not grids:
            raise SystemExit("give --grid NAME=V1,V2,... or --sample N --range NAME=LO:HI")
        points = grid_points(grids)
        names = [g[0] for g in grids]
    fixed = dict(parse_assignment(s, "--set") for s in a.set)
    points = [dict(fixed, **p) for p in points]
    inputs = dict(parse_assignment(s, "--input") for s in a.input)
    stop, step = default_experiment(a.fmu)
    options = {"inputs": inputs, "stop": stop if a.stop is None else a.stop,
               "step": step if a.step is None else a.step, "tolerance": a.tolerance}
    if options["stop"] is None or options["step"] is None:
        raise SystemExit(f"{a.fmu}: no DefaultExperiment stopTime and stepSize; give --stop and --step")
    print(describe(options, fixed, (stop, step)), flush=True)

    if a.plot and a.plot not in METRICS:
        raise SystemExit(f"--plot {a.plot}: not a metric ({', '.join(METRICS)})")

    from distributed import Client, LocalCluster

    started = time.perf_counter()
    if a.scheduler:
        client = Client(a.scheduler)
        cluster = None
    else:
        cluster = LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
    try:
        import sweep as module  # this file by its module name, which the workers can import

        rows = module.sweep(client, a.fmu, points, options)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    write_csv(a.out, rows, list(fixed) + names)
    failed = sum(r["status"] != "ok" for r in rows)
    print(format_table(rows, names))
    print(f"{len(rows)} points, {failed} failed")
    written = [a.out]
    if a.plot:
        x = a.plot_x or names[0]
        by = a.plot_by or (names[1] if len(names) > 1 and a.sample is None else None)
        written.append(str(pathlib.Path(a.out).with_suffix("")) + f"_{a.plot}.png")
        plot(rows, a.plot, x, by, written[-1])
    shown = [os.path.relpath(w) if not os.path.relpath(w).startswith("..") else w for w in written]
    print(f"wrote {' and '.join(shown)} (wall-clock {time.perf_counter() - started:.1f} s)")
    return 1 if failed == len(rows) else 0


if __name__ == "__main__":
    sys.exit(main())
