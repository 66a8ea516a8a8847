#!/usr/bin/env python3
"""scipy reference counts for the work-precision benchmark of the stiff integrators.

Usage (from the repository root):

    python3 -m venv .venv && .venv/bin/pip install scipy numpy   # once
    .venv/bin/python bench/scipy_reference.py                    # -> bench/scipy_reference.json

Runs scipy.integrate.solve_ivp with method="Radau" and "LSODA" on the same problems, end times,
reference solutions and (prescribed) absolute tolerances as src/solver/testset.rs, with the
analytic Jacobians, for rtol = 1e-3 ... 1e-10. Records scd (same definition as the Rust side),
accepted steps (len(sol.t) - 1), f evaluations, Jacobian evaluations and LU factorisations as
scipy reports them, and wall-clock time (Python; not comparable with Rust times).
`cargo run --release --bin work-precision` merges the JSON into bench/work_precision.md.

Second use, by the FMU speed benchmark (`cargo run --release --bin bench-fmu`):

    .venv/bin/python bench/scipy_reference.py --linear MODEL.json

MODEL.json holds a linear configuration of the FMU's model in the layout `hsp linearize --json`
prints (Linearization::to_json: A, B, the start state x0, and here only the rows C, D of the
outputs whose error is measured), with what the benchmark adds: the held input u, each state's
nominal value, the stop time and the communication step. One solve_ivp
call per method (Radau, BDF, LSODA) and rtol (1e-3 ... 1e-10; atol = 1e-2 rtol nominal, as the
FMU), with the constant Jacobian A (sparse when A is large and sparse), output at every
communication point. Each run's delivered error is the largest deviation of each output from the
exact discretisation x_{k+1} = expm(A h) x_k + (int_0^h expm(A s) ds) B u, relative to that
output's largest magnitude (the worst output). Prints {"Radau": [{rtol, err, wall, nfev, njev,
nlu}, ...], ...} as JSON on stdout.
"""
import json
import math
import os
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp


def rober():
    def f(t, y):
        a = -0.04 * y[0] + 1e4 * y[1] * y[2]
        c = 3e7 * y[1] ** 2
        return [a, -a - c, c]

    def jac(t, y):
        return [[-0.04, 1e4 * y[2], 1e4 * y[1]],
                [0.04, -1e4 * y[2] - 6e7 * y[1], -1e4 * y[1]],
                [0.0, 6e7 * y[1], 0.0]]

    return dict(f=f, jac=jac, t_end=1e11, y0=[1.0, 0.0, 0.0],
                ref=[2.083340149701255e-8, 8.333360770334713e-14, 0.9999999791665050],
                atol=lambda r: 1e-14 * r)


def vdpol():
    eps = 1e-6

    def f(t, y):
        return [y[1], ((1 - y[0] ** 2) * y[1] - y[0]) / eps]

    def jac(t, y):
        return [[0.0, 1.0], [(-2 * y[0] * y[1] - 1) / eps, (1 - y[0] ** 2) / eps]]

    return dict(f=f, jac=jac, t_end=2.0, y0=[2.0, 0.0],
                ref=[1.706167732170483, -0.8928097010247975], atol=lambda r: r)


def hires():
    def f(t, y):
        r = 280.0 * y[5] * y[7]
        return [-1.71 * y[0] + 0.43 * y[1] + 8.32 * y[2] + 0.0007,
                1.71 * y[0] - 8.75 * y[1],
                -10.03 * y[2] + 0.43 * y[3] + 0.035 * y[4],
                8.32 * y[1] + 1.71 * y[2] - 1.12 * y[3],
                -1.745 * y[4] + 0.43 * y[5] + 0.43 * y[6],
                -r + 0.69 * y[3] + 1.71 * y[4] - 0.43 * y[5] + 0.69 * y[6],
                r - 1.81 * y[6],
                -r + 1.81 * y[6]]

    def jac(t, y):
        j = np.zeros((8, 8))
        j[0, 0:3] = [-1.71, 0.43, 8.32]
        j[1, 0:2] = [1.71, -8.75]
        j[2, 2:5] = [-10.03, 0.43, 0.035]
        j[3, 1:4] = [8.32, 1.71, -1.12]
        j[4, 4:7] = [-1.745, 0.43, 0.43]
        j[5, 3:8] = [0.69, 1.71, -280.0 * y[7] - 0.43, 0.69, -280.0 * y[5]]
        j[6, 5:8] = [280.0 * y[7], -1.81, 280.0 * y[5]]
        j[7, 5:8] = [-280.0 * y[7], 1.81, -280.0 * y[5]]
        return j

    return dict(f=f, jac=jac, t_end=321.8122, y0=[1, 0, 0, 0, 0, 0, 0, 0.0057],
                ref=[7.371312573325668e-4, 1.442485726316185e-4, 5.888729740967575e-5,
                     1.175651343283149e-3, 2.386356198831331e-3, 6.238968252742796e-3,
                     2.849998395185769e-3, 2.850001604814231e-3],
                atol=lambda r: 1e-4 * r)


def orego():
    def f(t, y):
        return [77.27 * (y[1] + y[0] * (1 - 8.375e-6 * y[0] - y[1])),
                (y[2] - (1 + y[0]) * y[1]) / 77.27,
                0.161 * (y[0] - y[2])]

    def jac(t, y):
        return [[77.27 * (1 - 2 * 8.375e-6 * y[0] - y[1]), 77.27 * (1 - y[0]), 0.0],
                [-y[1] / 77.27, -(1 + y[0]) / 77.27, 1 / 77.27],
                [0.161, 0.0, -0.161]]

    return dict(f=f, jac=jac, t_end=360.0, y0=[1.0, 2.0, 3.0],
                ref=[1.000814870318523, 1228.178521549917, 132.0554942846706], atol=lambda r: r)


def prothero_robinson():
    lam = -1e6

    def f(t, y):
        return [lam * (y[0] - math.sin(t)) + math.cos(t)]

    def jac(t, y):
        return [[lam]]

    return dict(f=f, jac=jac, t_end=10.0, y0=[0.0], ref=[math.sin(10.0)], atol=lambda r: r)


def oscillator():
    w, z = 1e5, 0.01

    def f(t, y):
        return [w * y[1], -w * y[0] - 2 * z * w * y[1]]

    def jac(t, y):
        return [[0.0, w], [-w, -2 * z * w]]

    t_end = 1e-3
    wd = w * math.sqrt(1 - z * z)
    e = math.exp(-z * w * t_end)
    ref = [e * (math.cos(wd * t_end) + z * w / wd * math.sin(wd * t_end)),
           -e * (w / wd) * math.sin(wd * t_end)]
    return dict(f=f, jac=jac, t_end=t_end, y0=[1.0, 0.0], ref=ref, atol=lambda r: r)


PROBLEMS = {"rober": rober, "vdpol": vdpol, "hires": hires, "orego": orego,
            "prothero-robinson": prothero_robinson, "oscillator": oscillator}
RTOLS = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10]


def scd(y, ref):
    worst = 0.0
    for a, r in zip(y, ref):
        e = abs(a - r) if r == 0 else abs((a - r) / r)
        worst = max(worst, e if not math.isnan(e) else math.inf)
    return -math.log10(worst) if worst > 0 else math.inf


def delivered_error(y, exact):
    """The largest deviation of each output (a column of y, at the communication points) from
    the exact one, relative to that output's largest magnitude; the worst output (outputs that
    stay zero are left out). bench-fmu's `delivered_error` for the FMU's runs."""
    y, exact = np.asarray(y), np.asarray(exact)
    scale = np.abs(exact).max(axis=0)
    keep = scale > 0
    return float((np.abs(y - exact).max(axis=0)[keep] / scale[keep]).max())


def main():
    out = []
    for name, make in PROBLEMS.items():
        p = make()
        for method in ["Radau", "LSODA"]:
            for rtol in RTOLS:
                atol = p["atol"](rtol)
                t0 = time.perf_counter()
                try:
                    sol = solve_ivp(p["f"], (0.0, p["t_end"]), p["y0"], method=method,
                                    rtol=rtol, atol=atol, jac=p["jac"])
                    ok = sol.success
                    msg = sol.message
                except Exception as e:  # noqa: BLE001 - record any failure
                    ok, msg, sol = False, str(e), None
                secs = time.perf_counter() - t0
                rec = dict(problem=name, method=method, rtol=rtol, atol=atol, seconds=secs,
                           scd=None, steps=None, f_evals=None, jac_evals=None, lu=None)
                if sol is not None:
                    rec.update(steps=len(sol.t) - 1, f_evals=int(sol.nfev),
                               jac_evals=int(sol.njev), lu=int(sol.nlu))
                if ok:
                    rec["scd"] = scd(sol.y[:, -1], p["ref"])
                else:
                    rec["error"] = msg
                print(f"{name:18} {method:6} rtol {rtol:7.0e} scd {rec['scd']} "
                      f"steps {rec['steps']} f {rec['f_evals']} lu {rec['lu']} {secs:.2f}s",
                      file=sys.stderr)
                out.append(rec)
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "scipy_reference.json")
    with open(path, "w") as fh:
        json.dump(out, fh, indent=1)
        fh.write("\n")
    print(f"wrote {path}", file=sys.stderr)


def linear(path):
    from scipy.linalg import expm
    from scipy.sparse import csc_matrix

    with open(path) as fh:
        m = json.load(fh)
    a, b = np.array(m["A"]), np.array(m["B"])
    c, d = np.array(m["C"]), np.array(m["D"])
    x0, u = np.array(m["x0"]), np.array(m["u"])
    nominal = np.array(m["nominal"])
    stop, step = m["stop"], m["step"]
    n = int(round(stop / step))
    nx, nu = b.shape
    aug = np.zeros((nx + nu, nx + nu))
    aug[:nx, :nx] = a * step
    aug[:nx, nx:] = b * step
    e = expm(aug)
    phi, gu = e[:nx, :nx], e[:nx, nx:] @ u
    x = x0.copy()
    exact = np.empty((n, c.shape[0]))
    for k in range(n):
        x = phi @ x + gu
        exact[k] = c @ x + d @ u
    bu = b @ u
    jac = csc_matrix(a) if nx > 100 and np.count_nonzero(a) < 0.1 * a.size else a
    t_eval = np.arange(1, n + 1) * step

    def f(t, x):
        return a @ x + bu

    out = {}
    # LSODA takes the Jacobian only as a callable returning a dense array (scipy's LSODA tests
    # `jac or ...`, which a constant array fails with "truth value ... ambiguous").
    dense_a = np.asarray(a)
    jacs = {"Radau": jac, "BDF": jac, "LSODA": lambda t, x: dense_a}
    for method in ["Radau", "BDF", "LSODA"]:
        runs = []
        for rtol in RTOLS:
            t0 = time.perf_counter()
            try:
                sol = solve_ivp(f, (0.0, stop), x0, method=method, rtol=rtol,
                                atol=1e-2 * rtol * nominal, jac=jacs[method], t_eval=t_eval)
            except Exception as ex:  # noqa: BLE001 - record any failure
                print(f"{method} rtol {rtol}: {ex}", file=sys.stderr)
                continue
            wall = time.perf_counter() - t0
            if not sol.success:
                continue
            y = (c @ sol.y).T + d @ u
            err = delivered_error(y, exact)
            runs.append(dict(rtol=rtol, err=err, wall=wall, nfev=int(sol.nfev),
                             njev=int(sol.njev), nlu=int(sol.nlu)))
            print(f"{method:6} rtol {rtol:7.0e} err {err:.2e} {wall:.2f}s", file=sys.stderr)
            if wall > 60:
                break  # tighter tolerances only take longer
        out[method] = runs
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--linear":
        linear(sys.argv[2])
    else:
        main()
