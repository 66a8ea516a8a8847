//! The [`Integrator`]: the driver every method shares. It checks the arguments of each call,
//! keeps the shared point (options, t, x, h, counters) and hands the steps to the method
//! ([`OdeMethod`](super::OdeMethod)) behind it, which keeps its own state.

use serde::{Deserialize, Serialize};

use super::common::check_times;
use super::registry::{self, DynStepper, Saved};
use super::{OdeSystem, SolverError, SolverErrorKind, SolverOptions, Stats};

/// A stiff integrator: the shared point (options, t, x, next step size, counters) and the state
/// of its method ([`SolverOptions::method`]).
///
/// It is `Clone` and serde-serialisable; a restored copy continues bit-identically (see the
/// module documentation). No non-finite number is ever stored in it. Its saved form is the
/// shared point, then the method's state in the method's own format with that format's
/// version ([`OdeMethod::STATE_VERSION`](super::OdeMethod::STATE_VERSION)); reading a state of
/// another version fails with a message naming both.
pub struct Integrator {
    run: Box<dyn DynStepper>,
}

impl Clone for Integrator {
    fn clone(&self) -> Self {
        Integrator {
            run: self.run.clone_box(),
        }
    }
}

impl PartialEq for Integrator {
    fn eq(&self, other: &Integrator) -> bool {
        self.run.eq_dyn(&*other.run)
    }
}

/// The shared point; the method's state is in the saved form (serialise it to see all).
impl std::fmt::Debug for Integrator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Integrator")
            .field("method", &self.options().method)
            .field("t", &self.t())
            .field("x", &self.x())
            .field("h", &self.step_size())
            .field("stats", self.stats())
            .finish_non_exhaustive()
    }
}

impl Serialize for Integrator {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        registry::save_stepper(&*self.run)
            .map_err(serde::ser::Error::custom)?
            .serialize(s)
    }
}

impl<'de> Deserialize<'de> for Integrator {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let saved = Saved::deserialize(d)?;
        let run = registry::read_saved(saved).map_err(serde::de::Error::custom)?;
        Ok(Integrator { run })
    }
}

/// Lets a system of any type (also unsized) be handed to a method as `&dyn OdeSystem`.
struct Erased<'a, S: ?Sized>(&'a S);

impl<S: OdeSystem + ?Sized> OdeSystem for Erased<'_, S> {
    #[inline]
    fn dim(&self) -> usize {
        self.0.dim()
    }
    #[inline]
    fn rhs(&self, t: f64, x: &[f64], dxdt: &mut [f64]) {
        self.0.rhs(t, x, dxdt)
    }
    #[inline]
    fn jacobian(&self, t: f64, x: &[f64], jac: &mut nalgebra::DMatrix<f64>) -> bool {
        self.0.jacobian(t, x, jac)
    }
    #[inline]
    fn constant_jacobian(&self) -> Option<u64> {
        self.0.constant_jacobian()
    }
    #[inline]
    fn jacobian_constant_part(&self) -> Option<u64> {
        self.0.jacobian_constant_part()
    }
    #[inline]
    fn jacobian_varying(&self, t: f64, x: &[f64], jac: &mut nalgebra::DMatrix<f64>) -> bool {
        self.0.jacobian_varying(t, x, jac)
    }
    #[inline]
    fn jacobian_varying_pattern(&self) -> Option<&[Vec<u32>]> {
        self.0.jacobian_varying_pattern()
    }
    #[inline]
    fn jacobian_pattern(&self) -> Option<&[Vec<u32>]> {
        self.0.jacobian_pattern()
    }
    #[inline]
    fn is_autonomous(&self) -> bool {
        self.0.is_autonomous()
    }
    #[inline]
    fn time_derivative(&self, t: f64, x: &[f64], dfdt: &mut [f64]) -> bool {
        self.0.time_derivative(t, x, dfdt)
    }
}

impl Integrator {
    /// A new integrator at (t0, x0). Fails if the options or the initial point are invalid.
    pub fn new(options: SolverOptions, t0: f64, x0: Vec<f64>) -> Result<Self, SolverError> {
        options.validate(x0.len()).map_err(|mut e| {
            e.t = t0;
            e
        })?;
        check_point(t0, &x0)?;
        Ok(Integrator {
            run: registry::fresh(options, t0, x0, Stats::default()),
        })
    }

    pub fn t(&self) -> f64 {
        self.run.t()
    }
    pub fn x(&self) -> &[f64] {
        self.run.x()
    }
    pub fn stats(&self) -> &Stats {
        self.run.stats()
    }
    pub fn options(&self) -> &SolverOptions {
        self.run.options()
    }
    /// Step size the next step will try (0 before the first step).
    pub fn step_size(&self) -> f64 {
        self.run.h()
    }

    /// Forgets the next step size if it is below `h` (0 < h_next < h): the next call starts
    /// from a fresh estimate. After a communication step shorter than the minimum step, the
    /// step size the integrator carries on with is as short and may not grow past that
    /// minimum in the next step.
    pub fn forget_step_size_below(&mut self, h: f64) {
        let next = self.run.h();
        if next > 0.0 && next < h {
            self.run.set_h(0.0);
        }
    }

    /// Checks a restored integrator as strictly as a fresh one, for the system `sys` at the
    /// time `time`: its options must be exactly `options` (so they pass the same checks), its
    /// time `time` bit for bit, its state finite and of the system's size, its next step size
    /// finite and non-negative (and within the maximum step, for an adaptive method), and its
    /// method's state sound ([`OdeMethod::check_restored`](super::OdeMethod::check_restored)).
    /// The message completes "the FMU state is refused:" (numbers printed with `{}`).
    pub fn check_restored<S: OdeSystem + ?Sized>(
        &self,
        sys: &S,
        options: &SolverOptions,
        time: f64,
    ) -> Result<(), String> {
        let dim = sys.dim();
        let x = self.x();
        if x.len() != dim {
            return Err(format!(
                "its integrator has {} states, the model {dim}",
                x.len()
            ));
        }
        if self.options() != options {
            return Err(
                "its solver options differ from those its parameters give (solver.*, tolerance)"
                    .into(),
            );
        }
        options.validate(dim).map_err(|e| e.message)?;
        if self.t().to_bits() != time.to_bits() {
            return Err(format!(
                "its integrator is at t = {}, the FMU at t = {time}",
                self.t()
            ));
        }
        if let Some((i, x)) = x.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return Err(format!("its state x[{i}] = {x} is not finite"));
        }
        registry::check_restored(&*self.run, sys.jacobian_pattern())
    }

    /// [`Method::Rodas5PFixed`](super::Method::Rodas5PFixed): the largest embedded error estimate of the steps of the last
    /// call, as a multiple of the tolerances (the RMS norm the adaptive drivers test against 1:
    /// above 1, a step they would have rejected). 0 before the first call and after a
    /// discontinuity, and always 0 for the adaptive methods (whose step-size controller keeps
    /// another number in the same place).
    pub fn fixed_step_error(&self) -> f64 {
        self.run.error_estimate()
    }

    /// Replace the options (e.g. tolerances) keeping the state. Resets history like
    /// [`Integrator::notify_discontinuity`] since the controller history refers to the old
    /// tolerances.
    pub fn set_options(&mut self, options: SolverOptions) -> Result<(), SolverError> {
        options.validate(self.x().len()).map_err(|mut e| {
            e.t = self.t();
            e
        })?;
        if options.method != self.options().method {
            // Another method: its fresh state at the same point, with the same counters.
            let (t, x, stats) = (self.t(), self.x().to_vec(), *self.stats());
            self.run = registry::fresh(options, t, x, stats);
        } else {
            self.run.set_options(options);
        }
        Ok(())
    }

    /// Advance to exactly t_end (t() == t_end bit-exactly afterwards on success). On error the
    /// integrator stays at the last accepted point (t() < t_end) and remains usable.
    pub fn advance_to<S: OdeSystem + ?Sized>(
        &mut self,
        sys: &S,
        t_end: f64,
    ) -> Result<(), SolverError> {
        self.advance_to_with_output(sys, t_end, &[], &mut |_, _| {})
    }

    /// Same, calling `out(t, x)` at each requested output time in (t(), t_end] via dense
    /// output. `times` must be finite and non-decreasing; times outside (t(), t_end] are
    /// ignored.
    pub fn advance_to_with_output<S: OdeSystem + ?Sized>(
        &mut self,
        sys: &S,
        t_end: f64,
        times: &[f64],
        out: &mut dyn FnMut(f64, &[f64]),
    ) -> Result<(), SolverError> {
        self.advance(sys, t_end, t_end, times, out)
    }

    /// Advance to `t_end` without ending a step there: steps keep the size the error control
    /// chooses and may go past `t_end`, though never past `limit` (`t_end <= limit`, `+inf`
    /// for none). Afterwards `t()` is `t_end` bit-exactly and `x()` the state there,
    /// interpolated from the dense output of the step that covers it (Rodas5P's continuous
    /// extension of order 4), which is within the tolerance like the step's end point.
    /// Radau5 ends its steps on `t_end` all the same: its dense output, the collocation
    /// polynomial, is of order 3 only and would spoil the accuracy between its steps.
    ///
    /// The integrator keeps that step: a next call whose `t_end` it also covers only
    /// interpolates, and one beyond it goes on from the step's end, so that a run of short
    /// calls costs about as many steps as one long call. [`Integrator::notify_discontinuity`]
    /// and [`Integrator::reset`] drop the step and go on from the reported point, as after
    /// [`Integrator::advance_to`]. The step is part of the integrator's saved state, so a
    /// restored copy continues bit-identically.
    ///
    /// With `limit == t_end` this is [`Integrator::advance_to`].
    pub fn advance_past<S: OdeSystem + ?Sized>(
        &mut self,
        sys: &S,
        t_end: f64,
        limit: f64,
    ) -> Result<(), SolverError> {
        self.advance(sys, t_end, limit, &[], &mut |_, _| {})
    }

    /// Is (t(), x()) a point inside the last accepted step, interpolated by
    /// [`Integrator::advance_past`], rather than a step's end?
    pub fn is_past(&self) -> bool {
        self.run.is_past()
    }

    /// Where integration has got to: the end of the step kept past `t()` if
    /// [`Integrator::is_past`], else `t()`. Never past the `limit` of [`Integrator::advance_past`].
    pub fn reached(&self) -> f64 {
        self.run.reached()
    }

    fn advance<S: OdeSystem + ?Sized>(
        &mut self,
        sys: &S,
        t_end: f64,
        limit: f64,
        times: &[f64],
        out: &mut dyn FnMut(f64, &[f64]),
    ) -> Result<(), SolverError> {
        let (t, n) = (self.t(), self.x().len());
        if limit.is_nan() || limit < t_end {
            return Err(SolverError::new(
                SolverErrorKind::InvalidInput,
                t,
                format!("the limit {limit} lies before t_end = {t_end}"),
            ));
        }
        if sys.dim() != n {
            return Err(SolverError::new(
                SolverErrorKind::InvalidInput,
                t,
                format!(
                    "system has {} states but the integrator holds {}",
                    sys.dim(),
                    n
                ),
            ));
        }
        if !t_end.is_finite() || t_end < t {
            return Err(SolverError::new(
                SolverErrorKind::InvalidInput,
                t,
                format!("t_end must be finite and not before t = {t}, got {t_end}"),
            ));
        }
        check_point(t, self.x())?;
        check_times(times, t)?;
        if t_end == t {
            return Ok(());
        }
        let result = self.run.advance(&Erased(sys), t_end, limit, times, out);
        if let Err(e) = &result {
            if e.kind != SolverErrorKind::TooManySteps {
                // The step size and history that led into the failure are no guide for the
                // next attempt (typically made after the caller changed something): restart
                // with a fresh step-size estimate.
                self.run.after_failure();
            }
        }
        result
    }

    /// The inputs of the system jumped (zero-order hold at a communication point): forget
    /// whatever history assumes smoothness across this point (controller history, Newton
    /// start polynomial). Keeps h as a guess, and Radau5's kept Jacobian: the simplified Newton
    /// iteration needs only an approximate one, and its convergence monitor asks for a new J
    /// when the old one no longer serves (RADAU5 knows nothing of jumps either).
    pub fn notify_discontinuity(&mut self) {
        self.run.notify_discontinuity();
    }

    /// Replace the state (e.g. re-initialisation); resets history like notify_discontinuity.
    /// A non-finite t or x, or a length change, is reported by the next `advance_to`.
    pub fn reset(&mut self, t: f64, x: Vec<f64>) {
        let resized = x.len() != self.x().len();
        self.run.set_point(t, x);
        // A Jacobian kept from elsewhere is no guide at the new point.
        self.run.reset_state(resized);
    }

    /// Like [`Integrator::reset`] but validates the new point.
    pub fn try_reset(&mut self, t: f64, x: Vec<f64>) -> Result<(), SolverError> {
        check_point(t, &x)?;
        if x.len() != self.x().len() {
            if let super::Atol::Vector(_) = self.options().atol {
                return Err(SolverError::new(
                    SolverErrorKind::InvalidInput,
                    t,
                    format!(
                        "new state has {} components, atol vector has {}",
                        x.len(),
                        self.x().len()
                    ),
                ));
            }
        }
        self.reset(t, x);
        Ok(())
    }
}

fn check_point(t: f64, x: &[f64]) -> Result<(), SolverError> {
    if !t.is_finite() {
        return Err(SolverError::new(
            SolverErrorKind::InvalidInput,
            0.0,
            format!("t must be finite, got {t}"),
        ));
    }
    if let Some((i, v)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(SolverError::new(
            SolverErrorKind::InvalidInput,
            t,
            format!("state x[{i}] is not finite: {v}"),
        ));
    }
    Ok(())
}
