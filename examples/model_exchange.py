#!/usr/bin/env python3
"""Model Exchange: the importer's solver integrates the FMU's states. Stiff: use an implicit solver.

What it shows
    1. The stiffness, from the model's linearisation at rest as the integrators see it
       (`hsp linearize --as-integrated`, default preset; the vane motor's regularised seal
       friction included):
       the eigenvalue of largest modulus, the smallest, their ratio, and the largest stable step
       of explicit Euler and of RK45 (Dormand-Prince) for those eigenvalues.
    2. fmpy's CVode (BDF, absolute tolerance rtol x the state nominals the FMU reports) on the
       Model Exchange interface against the Co-Simulation interface (the FMU's own Rodas5P),
       over the default experiment (the 30 deg slewing move, 6 s): the largest difference of
       every output as a fraction of its range, by group, at rtol and at rtol / 10; then CVode
       with the nominals replaced by 1 (what an importer that ignores them does).
    3. Explicit Euler at 1 ms on the same experiment: it diverges; the growth of its increments
       per step against |1 + h lambda_max| from the linearisation.
    4. Explicit Euler from a 0.1 V step of r for 5 ms at half and at twice its stable step:
       bounded below the bound, growing above it.
    Writes model_exchange.png (the CVode and CS outputs, and Euler's growth) into --out.

How to run (from the repository root, after `cargo run --release --bin hsp -- package`):
    .venv/bin/python examples/model_exchange.py [--fmu fmu/HydraulicSlewingPlate.fmu] [--out results/examples]
It calls `cargo run --release --bin hsp -- linearize --json --as-integrated` unless you pass that command's
output with --linearization FILE. `--rtol` sets CVode's and the co-simulation's relative
tolerance (default 1e-6). docs/model-exchange.md gives the figures of one run.
"""

import argparse
import json
import pathlib
import shutil
import subprocess
import sys
import time
from ctypes import POINTER, c_double

import numpy as np
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Model
from fmpy.simulation import instantiate_fmu

ROOT = pathlib.Path(__file__).resolve().parents[1]
# Every output of the FMU but the solver's counters, in groups (one line of the table each).
GROUPS = {
    "angles and rates": ["controller.reference", "y_pot", "theta_motor", "theta_hub", "omega_motor", "omega_hub", "hub.omega_ratio",
                         "controller.e_out"],
    "plate: tip, stress": ["w_tip", "plate.w_tip_ratio", "plate.stress"],
    "accelerometers": ["acc_tip"] + [f"acc[{k}]" for k in range(1, 13)],
    "bar": ["torsion_bar.torque", "torsion_bar.stress"],
    "hydraulics": ["p_load", "servo_valve.p_1", "servo_valve.p_2", "q_valve", "servo_valve.q_supply",
                   "servo_valve.x_v", "servo_valve.i_coil"],
    "pilot stage": ["servo_valve.x_f", "servo_valve.p_a", "servo_valve.p_b"],
    "energy": ["energy"],
}
OUTPUTS = [name for names in GROUPS.values() for name in names]
EULER_H = 1e-3
_p = POINTER(c_double)


def linearization(path):
    if path:
        return json.loads(pathlib.Path(path).read_text())
    out = subprocess.run(["cargo", "run", "--release", "--quiet", "--bin", "hsp", "--", "linearize", "--json",
                          "--as-integrated"],
                         cwd=ROOT, capture_output=True, text=True, check=True).stdout
    return json.loads(out)


def stable_step(eigenvalues, stability):
    """Largest h with |R(h lambda)| <= 1 for every eigenvalue (bisection; R the method's stability
    function). Zero eigenvalues are neutral for every method and are left out."""
    lam = eigenvalues[np.abs(eigenvalues) > 1e-9]
    ok = lambda h: np.all(np.abs(stability(h * lam)) <= 1.0 + 1e-12)
    lo, hi = 0.0, 1.0
    while ok(hi):
        hi *= 2
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    return lo


def euler_r(z):
    return 1 + z


def dopri5_r(z):
    """Stability function of Dormand-Prince 5(4) (the 5th-order solution that RK45 propagates)."""
    return 1 + z + z ** 2 / 2 + z ** 3 / 6 + z ** 4 / 24 + z ** 5 / 120 + z ** 6 / 600


def set_values(fmu, md, values):
    """Sets variables by name: a Real, an Integer or Enumeration, a Boolean (True/False or
    "true"/"false"); the values may be text."""
    variables = {v.name: v for v in md.modelVariables}
    for name, value in values.items():
        v = variables[name]
        if v.type == "Real":
            fmu.setReal([v.valueReference], [float(value)])
        elif v.type == "Boolean":
            fmu.setBoolean([v.valueReference], [value in (True, "true", "1")])
        else:  # Integer, Enumeration
            fmu.setInteger([v.valueReference], [int(value)])


class MEInstance:
    """A Model Exchange instance in continuous-time mode, with its states as numpy arrays."""

    def __init__(self, md, unzipped, inputs=None):
        """`inputs`: values set before the initialisation, by name (inputs or parameters; a
        Boolean as True/False or "true"/"false")."""
        self.fmu = FMU2Model(guid=md.guid, unzipDirectory=unzipped,
                             modelIdentifier=md.modelExchange.modelIdentifier, instanceName="me")
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0)
        set_values(self.fmu, md, inputs or {})
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        while self.fmu.newDiscreteStates()[0]:
            pass
        self.fmu.enterContinuousTimeMode()
        self.n = md.numberOfContinuousStates
        self.x, self.dx, self.nominal = np.zeros(self.n), np.zeros(self.n), np.zeros(self.n)
        self.fmu.getNominalsOfContinuousStates(self.nominal.ctypes.data_as(_p), self.n)
        self.fmu.getContinuousStates(self.x.ctypes.data_as(_p), self.n)
        states = [d.variable.derivative.name for d in md.derivatives]
        self.moving = np.array([s != "x.reference.clock" for s in states])

    def derivatives(self, t, x):
        self.fmu.setTime(t)
        self.fmu.setContinuousStates(np.ascontiguousarray(x).ctypes.data_as(_p), self.n)
        self.fmu.getDerivatives(self.dx.ctypes.data_as(_p), self.n)
        return self.dx.copy()

    def free(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


def euler(inst, h, t_end, limit=1e6):
    """Explicit Euler from the instance's initial state until t_end, or until the scaled state
    passes `limit` or the FMU refuses it. Returns the times, the largest scaled state
    |x_i / nominal_i| after each step, and the largest scaled increment of the states other
    than the clock of the command generator (which grows by h every step), and the scaled
    increments themselves (one row per step)."""
    x, t = inst.x.copy(), 0.0
    times, size, incr, steps_scaled = [], [], [], []
    steps = int(round(t_end / h))
    for _ in range(steps):
        try:
            dx = inst.derivatives(t, x)
        except Exception:  # the FMU refuses a non-finite or absurd state
            break
        step = h * dx
        x = x + step
        t += h
        times.append(t)
        size.append(np.max(np.abs(x / inst.nominal)))
        incr.append(np.max(np.abs(step / inst.nominal)[inst.moving]))
        steps_scaled.append(step / inst.nominal)
        if not np.isfinite(size[-1]) or size[-1] > limit:
            break
    return np.array(times), np.array(size), np.array(incr), np.array(steps_scaled)


def cvode(unzipped, md, rtol, stop, interval, unit_nominals=False):
    """The default experiment with fmpy's CVode on the Model Exchange interface."""
    inst = instantiate_fmu(unzipped, md, "ModelExchange")
    if unit_nominals:
        def ones(pointer, n):
            np.ctypeslib.as_array(pointer, (n,))[:] = 1.0
        inst.getNominalsOfContinuousStates = ones
    started = time.perf_counter()
    try:
        res = simulate_fmu(unzipped, fmi_type="ModelExchange", solver="CVode", stop_time=stop,
                           relative_tolerance=rtol, output_interval=interval, output=OUTPUTS,
                           fmu_instance=inst, model_description=md)
    finally:
        inst.freeInstance()
    return res, time.perf_counter() - started


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--fmu", default=str(ROOT / "fmu" / "HydraulicSlewingPlate.fmu"))
    ap.add_argument("--out", default=str(ROOT / "results" / "examples"), help="output folder")
    ap.add_argument("--linearization", metavar="FILE", help="output of hsp linearize --json --as-integrated")
    ap.add_argument("--rtol", type=float, default=1e-6, help="relative tolerance of CVode and CS")
    ap.add_argument("--stop", type=float, help="stop time [s] (default: the FMU's)")
    a = ap.parse_args(argv)
    out = pathlib.Path(a.out)
    out.mkdir(parents=True, exist_ok=True)

    # 1. Stiffness from the linearisation.
    lin = linearization(a.linearization)
    lam = np.linalg.eigvals(np.array(lin["A"], dtype=float))
    nonzero = lam[np.abs(lam) > 1e-9]
    fast = nonzero[np.argmax(np.abs(nonzero))]
    slow = nonzero[np.argmin(np.abs(nonzero))]
    h_euler, h_rk45 = stable_step(lam, euler_r), stable_step(lam, dopri5_r)
    growth_predicted = abs(1 + EULER_H * fast)
    print(f"linearisation at rest: {len(lam)} states; fastest eigenvalue {fast.real:.1f} "
          f"{fast.imag:+.1f}j 1/s (|lambda| {abs(fast):.4g}), slowest non-zero {abs(slow):.4g} 1/s, "
          f"stiffness ratio {abs(fast) / abs(slow):.3g}")
    print(f"largest stable step: explicit Euler {h_euler:.4g} s, RK45 (Dormand-Prince) {h_rk45:.4g} s")
    print(f"explicit Euler at h = {EULER_H:g} s: |1 + h lambda_max| = {growth_predicted:.4g} per step")

    md = read_model_description(a.fmu)
    # Which states the fastest modes live in: eigenvectors of A in states scaled by their nominals.
    nominal = {d.variable.derivative.name: float(d.variable.derivative.nominal) for d in md.derivatives}
    state_index = {d.variable.derivative.name: i for i, d in enumerate(md.derivatives)}
    scale = np.array([nominal["x." + name] for name in lin["states"]])
    lam_s, vec = np.linalg.eig(np.array(lin["A"], dtype=float) * scale[None, :] / scale[:, None])
    shown = []
    for i in np.argsort(-np.abs(lam_s)):
        if lam_s[i].imag < 0 or len(shown) == 4:
            continue
        shown.append(i)
        v = np.abs(vec[:, i]) / np.abs(vec[:, i]).max()
        top = ", ".join(f"{lin['states'][j]} {v[j]:.2f}" for j in np.argsort(-v)[:3])
        print(f"  mode {lam_s[i].real:.4g}{lam_s[i].imag:+.4g}j 1/s: largest scaled components {top}")
    missing = {v.name for v in md.modelVariables if v.causality == "output"
               and not v.name.startswith("solver.")} - set(OUTPUTS)
    if missing:
        sys.exit(f"outputs in no group of GROUPS: {sorted(missing)}")
    stop = a.stop or float(md.defaultExperiment.stopTime)
    interval = float(md.defaultExperiment.stepSize)
    unzipped = extract(a.fmu)
    try:
        # 2. CVode against co-simulation, every output, at rtol and at rtol / 10.
        started = time.perf_counter()
        cs = simulate_fmu(unzipped, fmi_type="CoSimulation", stop_time=stop, relative_tolerance=a.rtol,
                          output_interval=interval, output=OUTPUTS, model_description=md)
        wall_cs = time.perf_counter() - started
        me, wall_me = cvode(unzipped, md, a.rtol, stop, interval)
        me10, _ = cvode(unzipped, md, a.rtol / 10, stop, interval)
        try:
            me1, wall_me1 = cvode(unzipped, md, a.rtol, stop, interval, unit_nominals=True)
            failed = None
        except RuntimeError as e:  # CVode gives up (mxstep) where the errors it ignores blow up
            me1, wall_me1, failed = None, float("nan"), str(e).split(": ")[-1]
        print(f"\ndefault experiment, {stop:g} s, output every {interval:g} s, rtol {a.rtol:g}: "
              f"CS {wall_cs:.2f} s, CVode {wall_me:.2f} s, CVode without nominals {wall_me1:.2f} s (wall)")
        print(f"{'outputs':22s}{'n':>3s}{'CVode-CS':>12s}{'rtol/10':>12s}{'(no nominals)':>15s}   "
              f"(largest max |ME - CS| / range of the group, and its output)")
        worst = {}
        for group, names in GROUPS.items():
            rows = []
            for name in names:
                span = np.ptp(cs[name])
                d = np.max(np.abs(me[name] - cs[name])) / span
                d10 = np.max(np.abs(me10[name] - cs[name])) / span
                d1 = np.max(np.abs(me1[name] - cs[name])) / span if me1 is not None else float("nan")
                rows.append((d, d10, d1, name))
            d, d10, d1, name = max(rows)
            worst[group] = (d, max(r[1] for r in rows), max(r[2] for r in rows))
            print(f"{group:22s}{len(names):3d}{d:12.3e}{worst[group][1]:12.3e}{worst[group][2]:15.3e}   {name}")
        # The pilot stage moves by a thousandth of its own scale in this gentle move (the flapper
        # 34 nm of its 39 um null gap): its errors also against that scale, the state's nominal
        # for x_f and the mean pressure for p_a, p_b.
        flapper_gap = nominal["x.servo_valve.springs.q[1]"]
        pilot = max(np.max(np.abs(me[n] - cs[n])) / (flapper_gap if n.endswith("x_f") else np.mean(np.abs(cs[n])))
                    for n in GROUPS["pilot stage"])
        print(f"pilot stage against its own scale (x_f: the null gap {flapper_gap:.3g} m; p_a, p_b: their "
              f"mean): {pilot:.3e}")
        main = [g for g in GROUPS if g != "pilot stage"]
        tail = (f"without nominals: {max(worst[g][2] for g in main):.3e}" if failed is None
                else f"without nominals: CVode failed: {failed}")
        print(f"max difference CVode-CS (all outputs but the pilot stage): {max(worst[g][0] for g in main):.3e} "
              f"of the range, at rtol/10 {max(worst[g][1] for g in main):.3e}; {tail}")

        # 3. Explicit Euler at 1 ms on the default experiment.
        inst = MEInstance(md, unzipped)
        xml = np.array([float(d.variable.derivative.nominal or "nan") for d in md.derivatives])
        print(f"state nominals: the XML declares {np.isfinite(xml).sum()} of {len(xml)}, from "
              f"{np.nanmin(xml):.3g} to {np.nanmax(xml):.3g}; equal to fmi2GetNominalsOfContinuousStates: "
              f"{bool(np.array_equal(xml, inst.nominal))}")
        order = [state_index["x." + name] for name in lin["states"]]
        t_e, size_e, incr_e, steps_e = euler(inst, EULER_H, stop)
        inst.free()
        blew = len(t_e) < int(round(stop / EULER_H)) or size_e[-1] > 1e6
        # The growth per step while the deviation is still small (linear: increments between
        # 1e-9 and 1 of the nominals), in the modal coordinates of the linearisation (the scaled
        # eigenvectors above): there each mode's amplitude grows by |1 + h lambda| per step,
        # whichever modes the round-off at rest happened to excite. (The largest component of
        # the increments mixes the modes, and the fastest pair turns by about 90 deg per step.)
        linear = (incr_e > 1e-9) & (incr_e < 1.0)
        modal = np.abs(np.linalg.solve(vec, steps_e[linear][:, order].T)).T
        dominant = int(np.argmax(modal[-1])) if len(modal) else 0
        ratios = modal[1:, dominant] / modal[:-1, dominant]
        growth = float(np.median(ratios)) if len(ratios) else float("nan")
        closest = lam_s[dominant]
        print(f"\nexplicit Euler, h = {EULER_H:g} s: " + (
            f"diverged: max |x/nominal| = {size_e[-1]:.3g} at t = {t_e[-1]:.3f} s; "
            if blew else "did not diverge; ") +
            f"measured growth per step {growth:.4g} ({len(ratios)} steps, the dominant mode's "
            f"amplitude); |1 + h lambda| of its eigenvalue "
            f"{closest.real:.1f}{closest.imag:+.1f}j: {abs(1 + EULER_H * closest):.4g} "
            f"(of the fastest: {growth_predicted:.4g})")

        # 4. Euler around its stable step, from a 0.1 V step of r.
        print("explicit Euler from a 0.1 V step of r for 5 ms:")
        demo = {}
        for factor in (0.5, 2.0):
            inst = MEInstance(md, unzipped, {"r": 0.1})
            h = factor * h_euler
            t_d, size_d, incr_d, _ = euler(inst, h, 5e-3)
            inst.free()
            demo[factor] = (t_d, incr_d)
            at_1ms = incr_d[np.searchsorted(t_d, 1e-3)]
            print(f"  h = {factor:g} x {h_euler:.4g} s: {len(t_d)} steps; largest scaled increment "
                  f"at 5 ms / at 1 ms = {incr_d[-1] / at_1ms:.3g}")
    finally:
        shutil.rmtree(unzipped, ignore_errors=True)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(11, 7))
    for ax, name in zip(axes.flat[:2], ["theta_hub", "w_tip"]):
        ax.plot(cs["time"], cs[name], label="Co-Simulation (Rodas5P)")
        ax.plot(me["time"], me[name], "--", label="Model Exchange (CVode BDF)")
        ax.set_title(name)
        ax.set_xlabel("time [s]")
        ax.legend(fontsize=8)
        ax.grid(True, alpha=0.3)
    axes[1, 0].semilogy(t_e * 1e3, incr_e)
    axes[1, 0].set_title(f"explicit Euler, h = {EULER_H * 1e3:g} ms: |increment / nominal|")
    axes[1, 0].set_xlabel("time [ms]")
    for factor, (t_d, incr_d) in demo.items():
        axes[1, 1].semilogy(t_d * 1e3, incr_d, label=f"h = {factor:g} x stable step")
    axes[1, 1].set_title("explicit Euler around its stable step: |increment / nominal|")
    axes[1, 1].set_xlabel("time [ms]")
    axes[1, 1].legend(fontsize=8)
    for ax in axes[1]:
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "model_exchange.png", dpi=100)
    plt.close(fig)
    print(f"wrote {out / 'model_exchange.png'}")


if __name__ == "__main__":
    sys.exit(main())
