"""The measures of a manoeuvre, one definition (docs/model.md, "Measures of a manoeuvre"); the
same rule as `hsp run`'s summary (src/bin/hsp/manoeuvre.rs), which tests/python/test_manoeuvre.py
holds it to.

- The command's target: the motor angle theta* = reference.angle (when the built-in move is on)
  + r / controller.k_pot; y_pot's target is k_pot theta*.
- The command ends at t_end = reference.t_start + reference.duration (the move's end), or at
  t = 0 for a step of r without a move.
- Settling time of a quantity: the time from t_end after which it stays within BAND of the
  commanded change (target minus its value at t = 0) around its target; NaN ("not settled") when
  it is outside the band at the end of the run, or the run ends before t_end. No minimum hold.
- Residual vibration: the peak of |w_tip| from t_end on (NaN when the run ends before t_end), and
  its ring-down time, the time from t_end after which |w_tip| stays at or below RING_LEVEL; NaN
  ("not rung down") when it is above at the end of the run or the run ends before t_end.
- Without a target (controller.external: the importer's loop) there are no measures.

Only the communication points are read. Pure Python and numpy.
"""

import math

import numpy as np

#: The settling band, a fraction of the commanded change.
BAND = 0.02
#: The level of |w_tip| of the ring-down time [m]: 1 mm at the 1.41 m plate's tip is 0.71 mrad of
#: the arm seen from the hub, below the 1 mrad the oscillation monitor takes as the smallest
#: motion the rig resolves.
RING_LEVEL = 1e-3


def command(values):
    """The command's target motor angle [rad] and end time [s] for the parameter values `values`
    (name -> value: reference.angle, reference.t_start, reference.duration, controller.k_pot,
    controller.external, and the input r [V], 0 when absent); None without a target
    (controller.external)."""
    if values.get("controller.external", False):
        return None
    angle = float(values["reference.angle"])
    r = float(values.get("r", 0.0))
    target = angle + r / float(values["controller.k_pot"])
    t_end = float(values["reference.t_start"]) + float(values["reference.duration"]) if angle != 0 else 0.0
    return target, t_end


def _stays_inside_from(t, outside, t_end):
    """Time from t_end after which `outside` (booleans per sample) stays false over the samples at
    or after t_end; 0 when it never holds there; NaN when it holds at the last sample or the run
    ends before t_end."""
    t = np.asarray(t, dtype=float)
    after = np.nonzero(t >= t_end)[0]
    if not len(after):
        return math.nan
    out = np.nonzero(np.asarray(outside)[after[0]:])[0]
    if not len(out):
        return 0.0
    last = after[0] + out[-1]
    return math.nan if last + 1 >= len(t) else float(t[last + 1] - t_end)


def settling(t, y, target, t_end, band=BAND):
    """Settling time of y(t) against `target` after t_end [s from t_end]; NaN: not settled."""
    y = np.asarray(y, dtype=float)
    return _stays_inside_from(t, np.abs(y - target) > band * abs(target - y[0]), t_end)


def residual_peak(t, w, t_end):
    """Peak of |w| at the samples at or after t_end; NaN when the run ends before t_end."""
    after = np.asarray(t, dtype=float) >= t_end
    return float(np.max(np.abs(np.asarray(w)[after]))) if after.any() else math.nan


def ring_down(t, w, t_end, level=RING_LEVEL):
    """Ring-down time of w(t) to `level` after t_end [s from t_end]; NaN: not rung down."""
    return _stays_inside_from(t, np.abs(np.asarray(w, dtype=float)) > level, t_end)


def overshoot_pct(y, target):
    """Largest excursion of y beyond `target`, in % of the commanded change from y[0]."""
    y = np.asarray(y, dtype=float)
    change = target - y[0]
    if change == 0:
        return 0.0
    return float(max(0.0, np.max(np.sign(change) * (y - target))) / abs(change) * 100)


def measures(t, series, values):
    """Every measure of one run: `series` maps theta_motor, theta_hub, y_pot, w_tip to their
    samples at the times `t` (a missing one is left out), `values` as for `command`. Returns a
    dict of settling_theta_motor, settling_theta_hub, settling_y_pot, residual_peak_w_tip,
    ring_down_w_tip (NaN where not settled / not rung down / no target)."""
    names = ["settling_theta_motor", "settling_theta_hub", "settling_y_pot", "residual_peak_w_tip",
             "ring_down_w_tip"]
    c = command(values)
    if c is None:
        return dict.fromkeys(names, math.nan)
    target, t_end = c
    targets = {"theta_motor": target, "theta_hub": target,
               "y_pot": float(values["controller.k_pot"]) * target}
    row = {f"settling_{n}": settling(t, series[n], targets[n], t_end) if n in series else math.nan
           for n in targets}
    w = series.get("w_tip")
    row["residual_peak_w_tip"] = math.nan if w is None else residual_peak(t, w, t_end)
    row["ring_down_w_tip"] = math.nan if w is None else ring_down(t, w, t_end)
    return row
