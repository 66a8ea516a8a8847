#!/usr/bin/env python3
"""Your own controller in place of the FMU's analog loop: an LQG controller that damps the plate.

What it shows
    With `controller.external = true` the FMU's analog position loop is out and the input `e_in`
    [V] drives the servo-valve coil. This script designs a controller from the model's
    linearisation (`hsp linearize`), closes the loop on the FMU in Python (fmpy's FMU2Slave,
    co-simulation with a communication step of 1 ms, the controller's sampling period), and runs
    the FMU's default slewing move (30 deg of motor angle, minimum-jerk over 2 s from t = 0.5 s,
    default preset `complete`) twice: once with the FMU's own analog loop, once with this
    controller. It prints and plots, for both (the measures of tools/manoeuvre.py, docs/model.md
    "Measures of a manoeuvre"):
      - settling time: from the end of the move until the hub angle stays within 2 % of the
        move (0.6 deg) of its target ("nan": not settled within the run);
      - residual tip vibration: RMS and peak of the tip deflection w_tip from the end of the move
        to the end of the run, and its ring-down time: from the end of the move until |w_tip|
        stays at or below 1 mm ("nan": not rung down within the run);
      - the largest values of the FMU's validity monitors and any warning the FMU logged.

The controller (designed here, from A, B, C of `hsp linearize --set controller.external=true`)
    1. Model reduction: the linearisation at rest has 44 states, with servo-valve modes up to
       6e4 1/s. The states are balanced, put in ordered real Schur form and block-diagonalised;
       the 16 states of the modes slower than 200 1/s are kept and the fast ones enter through
       their static gain (singular perturbation).
    2. Discretisation of the reduced model with a zero-order hold at h = 1 ms.
    3. LQR on the reduced model: the cost weighs the hub angle's deviation from the rigid-body
       reference (0.002 rad), the tip deflection (5 mm) and the drive voltage (3 V) by Bryson's
       rule; the reference is the rigid rotation of motor and hub by theta_ref(t).
    4. A steady-state Kalman filter (predictor form) on the reduced model, measuring what a rig
       measures: the potentiometer y_pot, the torsion bar's torque (a strain gauge) and the tip
       deflection w_tip; process noise enters where e_in and the shaker forces F1, F2 enter.
    5. A velocity feedforward: e_ff = theta_ref'(t) / k_v, with k_v the low-frequency gain from
       e_in to the motor speed of the linearisation.
    The law at each step: e_in = e_ff - K (x_hat - v theta_ref), v the rigid rotation.

How to run (from the repository root, after `cargo run --release --bin hsp -- package`):
    .venv/bin/python examples/own_controller.py [--fmu fmu/HydraulicSlewingPlate.fmu] [--out results/examples]
It calls `cargo run --release --bin hsp -- linearize --json --set controller.external=true`
unless you pass that command's output with --linearization FILE. Writes own_controller.png and
own_controller.csv into --out. Needs numpy, scipy, fmpy and matplotlib (all in tests/requirements.txt).
"""

import argparse
import csv
import json
import pathlib
import shutil
import subprocess
import sys

import numpy as np
import scipy.linalg
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
from fmpy.fmi2 import fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
import manoeuvre  # noqa: E402  (tools/manoeuvre.py: settling and ring-down, one definition)

H = 1e-3           # communication step = the controller's sampling period [s]
CUT = 200.0        # modes slower than this [1/s] are kept in the reduced model
BAND = manoeuvre.BAND  # settling band, a fraction of the move (drawn on the plot)
RECORDED = ["theta_motor", "theta_hub", "w_tip", "y_pot", "torsion_bar.torque",
            "controller.reference", "controller.e_out", "plate.w_tip_ratio", "plate.stress",
            "torsion_bar.stress", "hub.omega_ratio"]
MONITORS = ["plate.w_tip_ratio", "plate.stress", "torsion_bar.stress", "hub.omega_ratio"]


def minimum_jerk(t, angle, t0, duration):
    """The FMU's command generator (src/fragments/reference.rs): theta_ref and its rate."""
    s = np.clip((t - t0) / duration, 0.0, 1.0)
    value = angle * s ** 3 * (10 - 15 * s + 6 * s * s)
    rate = np.where((s > 0) & (s < 1), angle * 30 * s * s * (1 - s) ** 2 / duration, 0.0)
    return value, rate


def linearization(path):
    if path:
        return json.loads(pathlib.Path(path).read_text())
    out = subprocess.run(["cargo", "run", "--release", "--quiet", "--bin", "hsp", "--", "linearize",
                          "--json", "--set", "controller.external=true"],
                         cwd=ROOT, capture_output=True, text=True, check=True).stdout
    return json.loads(out)


def design(lin):
    """The LQG controller of the module's docstring; returns a dict of matrices and gains."""
    A, B, C, D = (np.array(lin[k], dtype=float) for k in "ABCD")
    u = {n: i for i, n in enumerate(lin["inputs"])}
    y = {n: i for i, n in enumerate(lin["outputs"])}
    s = {n: i for i, n in enumerate(lin["states"])}
    n = len(A)
    assert all(D[y[m], u["e_in"]] == 0 for m in ["y_pot", "torsion_bar.torque", "w_tip"])

    # 1. Balance (the states range from m^3 to rad), ordered Schur form, block-diagonalise.
    Ab, (scale, _) = scipy.linalg.matrix_balance(A, permute=False, separate=True)
    T, Zb, k = scipy.linalg.schur(Ab, output="real", sort=lambda re, im: abs(complex(re, im)) < CUT)
    Z, Zinv = scale[:, None] * Zb, Zb.T / scale[None, :]
    X = scipy.linalg.solve_sylvester(T[:k, :k], -T[k:, k:], -T[:k, k:])
    Ar = T[:k, :k]
    Bz = Zinv @ B
    Br = Bz[:k] - X @ Bz[k:]
    slow = Z[:, :k]                                    # x = slow @ xr + (fast part)
    fast = slow @ X + Z[:, k:]
    x_static = -fast @ np.linalg.solve(T[k:, k:], Bz[k:])   # state of the fast part per input

    def reduce(x):
        xi = Zinv @ x
        return xi[:k] - X @ xi[k:]

    # 2. Zero-order hold at H.
    M = np.zeros((k + B.shape[1], k + B.shape[1]))
    M[:k, :k], M[:k, k:] = Ar * H, Br * H
    E = scipy.linalg.expm(M)
    Ad, Bd = E[:k, :k], E[:k, k:]
    b = Bd[:, u["e_in"]]

    # The rigid rotation of motor and hub (A v = 0) is the reference's direction in state space.
    v = np.zeros(n)
    v[s["servo_valve.theta_a"]] = 1.0
    v[s["hub.theta"]] = 1.0
    assert np.abs(A @ v).max() == 0.0
    vr = reduce(v)

    # The bond graph keeps both angles and the bar's twist as states, so theta_motor - theta_hub
    # - twist is conserved: a direction w with w' Ar = 0 and w' Br = 0, an eigenvalue 0 that no
    # input moves and no sensor sees, on which neither Riccati equation has a stabilising
    # solution. The motion stays in w' xr = 0 (the FMU starts there, and w' Ad = w', w' Bd = 0
    # keep the observer there too), so both designs are made in coordinates z of that subspace,
    # xr = W z with W an orthonormal basis of it, and their gains mapped back.
    Ub, sv, _ = np.linalg.svd(np.hstack([Ar, Br]))
    assert sv[-1] < 1e-9 * sv[0], sv[-3:] / sv[0]
    W = scipy.linalg.null_space(Ub[:, -1][None, :])
    Az, bz = W.T @ Ad @ W, W.T @ b

    # 3. LQR, Bryson's rule.
    Cz = np.vstack([C[y["theta_hub"]], C[y["w_tip"]]]) @ slow @ W
    Q = Cz.T @ np.diag([1 / 0.002 ** 2, 1 / 0.005 ** 2]) @ Cz
    R = 1 / 3.0 ** 2
    P = scipy.linalg.solve_discrete_are(Az, bz[:, None], Q, np.array([[R]]))
    K = (bz @ P @ Az) / (R + bz @ P @ bz) @ W.T

    # 4. Kalman filter (predictor form) on y_pot, torsion bar torque, w_tip.
    meas = ["y_pot", "torsion_bar.torque", "w_tip"]
    Cm_full = np.vstack([C[y[m]] for m in meas])
    Cm = Cm_full @ slow
    Dm = Cm_full @ x_static[:, u["e_in"]]
    G = W.T @ Bd[:, [u["e_in"], u["F1"], u["F2"]]]
    Qn = G @ np.diag([0.1 ** 2, 1.0 ** 2, 1.0 ** 2]) @ G.T        # 0.1 V, 1 N, 1 N
    sigma = np.array([1e-3, 0.1, 1e-4])                           # 1 mV, 0.1 N m, 0.1 mm
    # Measurements in units of their noise keep the equation well scaled.
    Cs = Cm @ W / sigma[:, None]
    Pk = scipy.linalg.solve_discrete_are(Az.T, Cs.T, Qn, np.eye(len(meas)))
    L = W @ Az @ Pk @ Cs.T @ np.linalg.inv(Cs @ Pk @ Cs.T + np.eye(len(meas))) / sigma[None, :]

    # 5. Velocity feedforward: motor speed per volt at 1e-3 rad/s.
    w = 1e-3
    kv = (C[y["omega_motor"]] @ np.linalg.solve(1j * w * np.eye(n) - A, B[:, u["e_in"]])).real

    closed = np.log(np.linalg.eigvals(Ad - np.outer(b, K)).astype(complex)) / H
    return dict(Ad=Ad, b=b, K=K, L=L, Cm=Cm, Dm=Dm, vr=vr, kv=kv, meas=meas, k=k, n=n,
                closed=closed, A=A, b_full=B[:, u["e_in"]], c_pot=C[y["y_pot"]])


class Controller:
    """The sampled LQG law; step() takes the measurements and the reference, returns e_in."""

    def __init__(self, lqg):
        self.c = lqg
        self.xh = np.zeros(lqg["k"])

    def step(self, measured, theta_ref, rate_ref):
        c = self.c
        e = rate_ref / c["kv"] - c["K"] @ (self.xh - c["vr"] * theta_ref)
        innovation = measured - c["Cm"] @ self.xh - c["Dm"] * e
        self.xh = c["Ad"] @ self.xh + c["b"] * e + c["L"] @ innovation
        return e


def run(unzipped, md, stop, controller=None):
    """One run of the default experiment; the analog loop when `controller` is None."""
    vr = {v.name: v.valueReference for v in md.modelVariables}
    start = {v.name: v.start for v in md.modelVariables}
    warnings = []

    def log(env, instance, status, category, message):
        if status >= 1:
            warnings.append(message.decode(errors="replace").replace("%%", "%"))

    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(log)
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(lambda n, s: None)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(lambda p: None)
    slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="plant")
    slave.instantiate(callbacks=callbacks)
    slave.setupExperiment(startTime=0.0, stopTime=stop)
    if controller is not None:
        slave.setBoolean([vr["controller.external"]], [True])
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    angle, t0, duration = (float(start[f"reference.{p}"]) for p in ["angle", "t_start", "duration"])
    refs = [vr[n] for n in RECORDED]
    meas = [vr[n] for n in controller.c["meas"]] if controller else []
    steps = int(round(stop / H))
    rows = []
    for i in range(steps + 1):
        t = i * H
        values = slave.getReal(refs)
        if controller is not None:
            theta, rate = minimum_jerk(t, angle, t0, duration)
            e = controller.step(np.array(slave.getReal(meas)), float(theta), float(rate))
            slave.setReal([vr["e_in"]], [e])
        rows.append([t] + values)
        if i < steps:
            slave.doStep(currentCommunicationPoint=t, communicationStepSize=H)
    slave.terminate()
    slave.freeInstance()
    data = {name: np.array([r[j + 1] for r in rows]) for j, name in enumerate(RECORDED)}
    data["time"] = np.array([r[0] for r in rows])
    return data, warnings


def summary(data, move):
    angle, t0, duration = move
    t, hub, w = data["time"], data["theta_hub"], data["w_tip"]
    t_end = t0 + duration  # the move's end: the command's target is reached there
    after = t >= t_end
    return {
        "settling_after_move_s": manoeuvre.settling(t, hub, angle, t_end),
        "residual_rms_w_tip_m": float(np.sqrt(np.mean(w[after] ** 2))),
        "residual_peak_w_tip_m": manoeuvre.residual_peak(t, w, t_end),
        "ring_down_s": manoeuvre.ring_down(t, w, t_end),
        "peak_w_tip_m": float(np.max(np.abs(w))),
        "peak_e_out_V": float(np.max(np.abs(data["controller.e_out"]))),
        **{f"max_{m}": float(np.max(np.abs(data[m]))) for m in MONITORS},
    }


def plot(results, move, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    angle, t0, duration = move
    fig, axes = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    for label, (data, _) in results.items():
        t = data["time"]
        axes[0].plot(t, np.degrees(data["theta_hub"]), label=label)
        axes[1].plot(t, 1e3 * data["w_tip"], label=label)
        axes[2].plot(t, data["controller.e_out"], label=label)
    theta, _ = minimum_jerk(t, angle, t0, duration)
    axes[0].plot(t, np.degrees(theta), "k:", label="reference (motor angle)")
    for a in (angle * (1 - BAND), angle * (1 + BAND)):
        axes[0].axhline(np.degrees(a), color="grey", lw=0.5)
    axes[0].set_ylabel("hub angle [deg]")
    axes[1].set_ylabel("tip deflection w_tip [mm]")
    axes[2].set_ylabel("coil drive e_out [V]")
    axes[2].set_xlabel("time [s]")
    for ax in axes:
        ax.axvline(t0 + duration, color="grey", ls="--", lw=0.8)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    axes[0].set_title("Default slewing move: the FMU's analog loop against an LQG controller in Python")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--fmu", default=str(ROOT / "fmu" / "HydraulicSlewingPlate.fmu"))
    ap.add_argument("--out", default=str(ROOT / "results" / "examples"), help="output folder")
    ap.add_argument("--linearization", metavar="FILE",
                    help="output of hsp linearize --json --set controller.external=true")
    ap.add_argument("--stop", type=float, default=None, help="stop time [s] (default: the FMU's)")
    a = ap.parse_args(argv)
    out = pathlib.Path(a.out)
    out.mkdir(parents=True, exist_ok=True)

    lqg = design(linearization(a.linearization))
    md = read_model_description(a.fmu)
    start = {v.name: v.start for v in md.modelVariables}
    # The analog loop is e_in = A1 A2 (reference - y_pot): its poles from the same linearisation.
    gain = float(start["controller.A1"]) * float(start["controller.A2"])
    analog_poles = np.linalg.eigvals(lqg["A"] - gain * np.outer(lqg["b_full"], lqg["c_pot"]))
    slow = lambda ev: sorted((e for e in ev if 0.1 < abs(e) < 50 and e.imag > 0), key=abs)
    print(f"reduced model: {lqg['k']} of {lqg['n']} states (modes slower than {CUT:g} 1/s); "
          f"k_v = {lqg['kv']:.4f} rad/s per V; communication step {H * 1e3:g} ms")
    for label, poles in [("analog loop", analog_poles), ("LQR (state feedback)", lqg["closed"])]:
        print(f"poles below 50 1/s, {label}: " + ", ".join(
            f"{e.real:.3f}{e.imag:+.3f}j (zeta {-e.real / abs(e):.3f})" for e in slow(poles)))

    stop = a.stop or float(md.defaultExperiment.stopTime)
    unzipped = extract(a.fmu)
    try:
        results = {"analog loop": run(unzipped, md, stop),
                   "LQG (Python)": run(unzipped, md, stop, Controller(lqg))}
    finally:
        shutil.rmtree(unzipped, ignore_errors=True)
    move = tuple(float(start[f"reference.{p}"]) for p in ["angle", "t_start", "duration"])
    angle, t0, duration = move

    # The move this script computes is the FMU's own command (the analog run records it).
    analog = results["analog loop"][0]
    theta, _ = minimum_jerk(analog["time"], *move)
    k_pot = float(start["controller.k_pot"])
    ref_err = float(np.max(np.abs(analog["controller.reference"] - k_pot * theta)))
    print(f"move: {np.degrees(angle):.1f} deg from t = {t0} s over {duration} s; stop {stop} s; "
          f"max |controller.reference - k_pot theta_ref| = {ref_err:.2e} V")

    rows = {label: summary(data, move) for label, (data, _) in results.items()}
    print(f"\n{'':34s}{'analog loop':>14s}{'LQG (Python)':>14s}")
    lines = [("settling after the move (2 %) [s]", "settling_after_move_s", 1, "{:.3f}"),
             ("residual RMS w_tip [mm]", "residual_rms_w_tip_m", 1e3, "{:.3f}"),
             ("residual peak w_tip [mm]", "residual_peak_w_tip_m", 1e3, "{:.3f}"),
             ("ring-down to 1 mm after move [s]", "ring_down_s", 1, "{:.3f}"),
             ("peak w_tip [mm]", "peak_w_tip_m", 1e3, "{:.3f}"),
             ("peak coil drive [V]", "peak_e_out_V", 1, "{:.3f}")]
    lines += [(f"max {m}", f"max_{m}", 1, "{:.4g}") for m in MONITORS]
    for text, key, factor, fmt in lines:
        cells = "".join(f"{fmt.format(rows[l][key] * factor):>14s}" for l in rows)
        print(f"{text:34s}{cells}")
    print("(nan: the hub is not settled, or |w_tip| not rung down to 1 mm, at the end of the run)")
    for label, (_, warnings) in results.items():
        print(f"validity warnings, {label}: {len(warnings)}" + "".join(f"\n  {w}" for w in warnings))

    with open(out / "own_controller.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["controller"] + list(next(iter(rows.values()))))
        for label, r in rows.items():
            w.writerow([label] + list(r.values()))
    plot(results, move, out / "own_controller.png")
    print(f"wrote {out / 'own_controller.png'} and {out / 'own_controller.csv'}")


if __name__ == "__main__":
    sys.exit(main())
