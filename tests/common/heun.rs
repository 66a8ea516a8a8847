//! A method written outside the crate, as a newcomer would add one (CONTRIBUTING.md, "Adding a
//! solver method"): Heun's explicit second-order method with the explicit Euler step as its
//! embedded first-order estimate, adaptive, for non-stiff problems. It is this one module plus
//! one registration (`solver::register::<Heun>()`); it uses the public API only ([`OdeMethod`],
//! [`Stepper`], [`OdeSystem`]).

#![allow(dead_code)]
// Index loops over components mirror the formulas.
#![allow(clippy::needless_range_loop)]

use hydraulic_slewing_plate::solver::{
    OdeMethod, OdeSystem, SolverError, SolverErrorKind, SolverOptions, Stepper,
};
use serde::{Deserialize, Serialize};

/// Heun's method (the explicit trapezoidal rule), with local extrapolation.
pub struct Heun;

/// The version of [`HeunState`]'s saved form: any number, raised when its fields change.
pub const STATE_VERSION: u32 = 7;

/// Safety factor of the step-size proposal h_new = h · SAFE / √err.
/// Default 0.9, the usual (Hairer, Nørsett & Wanner I, II.4).
pub const SAFE: f64 = 0.9;
/// Largest growth of h in one step. Default 5, the usual for explicit methods.
pub const FAC_MAX: f64 = 5.0;
/// Largest shrink of h in one step. Default 0.2, the usual.
pub const FAC_MIN: f64 = 0.2;
/// First step of a fresh start. Default 1e-3: the test problems change on a scale of 1.
pub const H0: f64 = 1e-3;

/// What Heun keeps between calls: whether the last attempt was rejected (it limits the next
/// step's growth), and buffers that change no result.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct HeunState {
    pub last_rejected: bool,
    #[serde(skip)]
    scratch: Scratch,
}

/// The stage vectors, kept so that a warm call allocates nothing. A clone starts empty; `==`
/// ignores them.
#[derive(Default)]
struct Scratch {
    k1: Vec<f64>,
    k2: Vec<f64>,
    y: Vec<f64>,
    at: Vec<f64>,
}

impl Clone for Scratch {
    fn clone(&self) -> Self {
        Scratch::default()
    }
}

impl PartialEq for Scratch {
    fn eq(&self, _: &Scratch) -> bool {
        true
    }
}

impl std::fmt::Debug for Scratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Scratch")
    }
}

impl OdeMethod for Heun {
    const NAME: &'static str = "heun-test";
    const STATE_VERSION: u32 = STATE_VERSION;
    type State = HeunState;

    fn fresh(_: &SolverOptions, _: usize) -> HeunState {
        HeunState::default()
    }

    fn advance(
        run: &mut Stepper<HeunState>,
        sys: &dyn OdeSystem,
        t_end: f64,
        _limit: f64,
        times: &[f64],
        out: &mut dyn FnMut(f64, &[f64]),
    ) -> Result<(), SolverError> {
        let Stepper {
            options,
            t,
            x,
            h,
            stats,
            state,
        } = run;
        let n = x.len();
        let s = &mut state.scratch;
        for v in [&mut s.k1, &mut s.k2, &mut s.y, &mut s.at] {
            v.resize(n, 0.0);
        }
        if *h <= 0.0 {
            *h = H0;
        }
        let mut next = times.iter().position(|&w| w > *t).unwrap_or(times.len());
        let mut attempts = 0u64;
        while *t < t_end {
            attempts += 1;
            if attempts > options.max_steps {
                return Err(SolverError::new(
                    SolverErrorKind::TooManySteps,
                    *t,
                    "too many steps",
                ));
            }
            let remaining = t_end - *t;
            let last = *h >= remaining;
            let step = if last { remaining } else { *h };
            sys.rhs(*t, x, &mut s.k1);
            for i in 0..n {
                s.y[i] = x[i] + step * s.k1[i];
            }
            sys.rhs(*t + step, &s.y, &mut s.k2);
            stats.f_evals += 2;
            let mut sum = 0.0;
            for i in 0..n {
                let sc = options.atol.get(i) + options.rtol * x[i].abs();
                let e = 0.5 * step * (s.k2[i] - s.k1[i]) / sc;
                sum += e * e;
            }
            let err = (sum / n as f64).sqrt();
            if !err.is_finite() {
                return Err(SolverError::new(
                    SolverErrorKind::NonFinite,
                    *t,
                    "f is not finite",
                ));
            }
            let accepted = err <= 1.0;
            let grow = if state.last_rejected { 1.0 } else { FAC_MAX };
            let fac = if err > 0.0 {
                (SAFE / err.sqrt()).clamp(FAC_MIN, grow)
            } else {
                grow
            };
            if accepted {
                let t1 = if last { t_end } else { *t + step };
                for i in 0..n {
                    s.y[i] = x[i] + 0.5 * step * (s.k1[i] + s.k2[i]);
                }
                while next < times.len() && times[next] <= t1 {
                    let theta = (times[next] - *t) / step;
                    for i in 0..n {
                        s.at[i] = x[i] + theta * (s.y[i] - x[i]);
                    }
                    out(times[next], &s.at);
                    next += 1;
                }
                x.copy_from_slice(&s.y);
                *t = t1;
                stats.accepted += 1;
                state.last_rejected = false;
                // A last step cut short by t_end does not shrink the next call's first step.
                *h = if last { h.max(step * fac) } else { step * fac };
            } else {
                stats.rejected += 1;
                state.last_rejected = true;
                *h = step * fac;
            }
            *h = h.min(options.max_step);
        }
        Ok(())
    }

    fn notify_discontinuity(state: &mut HeunState) {
        state.last_rejected = false;
    }

    fn after_failure(state: &mut HeunState) {
        state.last_rejected = false;
    }
}
