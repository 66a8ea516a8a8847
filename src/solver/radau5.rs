//! Radau IIA order 5 (placeholder, being written).
use super::integrator::Integrator;
use super::{OdeSystem, SolverError, SolverErrorKind};

pub(crate) fn advance<S: OdeSystem + ?Sized>(
    integ: &mut Integrator,
    _sys: &S,
    _t_end: f64,
    _times: &[f64],
    _out: &mut dyn FnMut(f64, &[f64]),
) -> Result<(), SolverError> {
    Err(SolverError::new(
        SolverErrorKind::InvalidOptions,
        integ.t,
        "radau5 not yet implemented",
    ))
}
