//! RADAU5's work arrays: the buffers of one call, kept between calls.

use nalgebra::{Complex, DMatrix, DVector};

use super::decomposition::Lu;
use super::tolerances::Tolerances;
use crate::solver::common::Workspace;
use crate::solver::linalg::PatternCache;
use crate::solver::Atol;

/// Buffers of `advance`, kept between calls in the method's cache (no allocation per call);
/// overwritten before they are read.
pub(crate) struct Work {
    pub(super) jac: DMatrix<f64>,
    /// The stamp of the constant part of the J that `jac` holds (see
    /// [`OdeSystem::jacobian_constant_part`]), None while it holds none.
    pub(super) jac_holds: Option<u64>,
    pub(super) f0: Vec<f64>,
    /// 1/SCAL (see [`set_scal`](super::tolerances::set_scal)).
    pub(super) inv_scal: Vec<f64>,
    /// Stage increments Z_i = Y_i - y0.
    pub(super) z: [Vec<f64>; 3],
    /// Transformed increments W = T⁻¹ Z.
    pub(super) w: [Vec<f64>; 3],
    /// f at the stages.
    pub(super) a: [Vec<f64>; 3],
    pub(super) ytmp: Vec<f64>,
    pub(super) f2: Vec<f64>,
    pub(super) x1: Vec<f64>,
    /// f(t, 0), the constant part of an affine f, for the step map (evaluated once per call).
    pub(super) c0: Vec<f64>,
    /// The step map's result: Z3 (rows 0..n) and the error estimate's vector (n..2n).
    pub(super) mapped: Vec<f64>,
    /// [`transformed_tolerances`](super::tolerances::transformed_tolerances), with `atol` and `atol_for_fd`, once made (the options do
    /// not change under a workspace: `set_options` drops it).
    pub(super) tolerances: Option<Tolerances>,
    pub(super) atol: Vec<f64>,
    /// `atol` again, in the form the finite-difference Jacobian takes.
    pub(super) atol_for_fd: Atol,
    pub(super) rr: DVector<f64>,
    pub(super) rc: DVector<Complex<f64>>,
    /// Scratch of the structured solves.
    pub(super) scratch_r: Vec<f64>,
    pub(super) scratch_c: Vec<Complex<f64>>,
    /// Partition of J into blocks and border (see [`crate::solver::linalg`]).
    pub(super) pattern: PatternCache,
    /// The memory of the last factorisations of a Jacobian that changes from step to step:
    /// refactorised into, so a step allocates nothing. Their contents are stale unless
    /// `kept_synced` says otherwise.
    pub(super) spare: Option<Lu>,
    /// `jac` holds the integrator's [`KeptJacobian`](crate::solver::integrator::KeptJacobian), and if
    /// that has factorisations, `spare` holds them (set when a call ends keeping J; a new
    /// workspace, as after a restore, starts without).
    pub(super) kept_synced: bool,
}

impl Workspace for Work {
    type Lu = Lu;
    fn new(n: usize) -> Self {
        let v = || vec![0.0; n];
        Work {
            jac: DMatrix::zeros(n, n),
            jac_holds: None,
            f0: v(),
            inv_scal: v(),
            z: [v(), v(), v()],
            w: [v(), v(), v()],
            a: [v(), v(), v()],
            ytmp: v(),
            f2: v(),
            x1: v(),
            c0: v(),
            mapped: vec![0.0; 2 * n],
            tolerances: None,
            atol: v(),
            atol_for_fd: Atol::Vector(v()),
            rr: DVector::zeros(n),
            rc: DVector::zeros(n),
            scratch_r: v(),
            scratch_c: vec![Complex::new(0.0, 0.0); n],
            pattern: PatternCache::default(),
            spare: None,
            kept_synced: false,
        }
    }
    fn dim(&self) -> usize {
        self.f0.len()
    }
    fn spare(&mut self) -> &mut Option<Lu> {
        &mut self.spare
    }
}
