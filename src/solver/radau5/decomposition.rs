//! The iteration matrices of the simplified Newton iteration: J at the current point (RADCOR
//! label 20) and the factorisations of (γ/h) I - J and ((α + iβ)/h) I - J (RADAU5's DECOMR and
//! DECOMC).

use std::sync::Arc;

use nalgebra::{Complex, DMatrix};

use super::coefficients::inverse_eigenvalues;
use super::state::State;
use super::workspace::Work;
use super::Radau5Options;
use crate::solver::common::jacobian_here;
use crate::solver::constant_jacobian::{front_factorisation, SAME_STEP};
use crate::solver::linalg::{factor_with_fallback, Factorisation, Partition, Shifted};
use crate::solver::method::Stepper;
use crate::solver::step_map::StepMap;
use crate::solver::OdeSystem;

/// The real LU of (γ/h) I - J and the complex LU of ((α + iβ)/h) I - J for the step size `h`.
pub(crate) struct Lu {
    pub(super) real: Factorisation<f64>,
    pub(super) complex: Factorisation<Complex<f64>>,
    pub(super) h: f64,
    /// A step of size `h` as one affine map, for a system affine in x (see [`StepMap`]); made
    /// from these factorisations, cleared when they are remade.
    pub(super) map: StepMap,
}

/// Factorises both iteration matrices for step size `h` into `lu` (reusing its memory) with the
/// partition `part` of J; false if either is singular.
fn factor_into(lu: &mut Lu, part: &Arc<Partition>, jac: &DMatrix<f64>, h: f64) -> bool {
    let (u1, alph, beta) = inverse_eigenvalues();
    let fac1 = u1 / h;
    let (alphn, betan) = (alph / h, beta / h);
    lu.h = h;
    lu.map.clear();
    factor_with_fallback(&mut lu.real, part, Shifted { c: fac1, jac })
        && factor_with_fallback(&mut lu.complex, part, |i, j| {
            if i == j {
                Complex::new(alphn - jac[(i, j)], betan)
            } else {
                Complex::new(-jac[(i, j)], 0.0)
            }
        })
}

/// Factorisations of both iteration matrices for step size `h` (in the memory of `old` if
/// given); None if either is singular.
pub(super) fn factor(
    jac: &DMatrix<f64>,
    part: &Arc<Partition>,
    h: f64,
    old: Option<Lu>,
) -> Option<Lu> {
    let mut lu = old.unwrap_or_else(|| Lu {
        real: Factorisation::new(Arc::clone(part)),
        complex: Factorisation::new(Arc::clone(part)),
        h,
        map: StepMap::default(),
    });
    factor_into(&mut lu, part, jac, h).then_some(lu)
}

/// The Jacobian J = ∂f/∂y at the current point (RADCOR label 20: analytic or by finite
/// differences). A constant J ([`OdeSystem::constant_jacobian`]) is the same everywhere and is
/// kept in the method's cache with its factorisations; otherwise J goes into `work.jac` and
/// the factorisations of the old J are dropped (their memory kept as the spare). False if J is
/// not finite.
pub(super) fn jacobian_at<S: OdeSystem + ?Sized>(
    integ: &mut Stepper<State>,
    sys: &S,
    work: &mut Work,
    lus: &mut Vec<Lu>,
    stamp: Option<u64>,
    rtol: f64,
) -> bool {
    if stamp.is_none() {
        if let Some(lu) = lus.pop() {
            work.spare = Some(lu);
        }
        lus.clear();
    }
    let fd = Some((&work.atol_for_fd, rtol));
    jacobian_here(
        integ,
        |s: &mut State| (&mut s.counted, &mut s.cache),
        sys,
        stamp,
        &work.f0,
        fd,
        &mut work.jac,
        &mut work.jac_holds,
    )
}

/// Makes `lus[0]` the factorisations for step size `h` (RADAU5's DECOMR and DECOMC: the real LU
/// of (γ/h) I - J and the complex LU of ((α + iβ)/h) I - J, the blocks of the transformed
/// Newton matrix, Hairer & Wanner IV.8, eq. 8.16ff), reusing those in `lus` where they fit.
/// False if a matrix is singular.
///
/// The simplified Newton iteration converges with factorisations for a step size within
/// SAME_STEP of h as with exact ones (the difference is rounding in t_end - t); with a constant J
/// the factorisation in use is the one counted (also after a restore, which rebuilds it with the
/// same bits). A changing J is refactorised in the memory of its last factorisation, with the
/// partition of the system's structural pattern (`structure`) if it has one.
pub(super) fn decompose(
    integ: &mut Stepper<State>,
    work: &mut Work,
    lus: &mut Vec<Lu>,
    (stamp, structure): (Option<u64>, Option<&[Vec<u32>]>),
    h: f64,
    opts: &Radau5Options,
) -> bool {
    let Work {
        jac,
        pattern,
        spare,
        ..
    } = work;
    match stamp {
        Some(_) => {
            let lu_h = integ
                .state
                .counted
                .factorisation_step(h, &mut integ.stats, 2, false);
            let jac = &integ.state.cache.jac;
            front_factorisation(
                lus,
                lu_h,
                |l| l.h,
                |old| {
                    let fresh = old.is_none();
                    let mut lu = factor(jac, pattern.partition(jac, stamp), lu_h, old)?;
                    let n = jac.nrows();
                    if fresh && n <= opts.map_max_dim {
                        // Its step map is built later, mid-run: take its memory with the rest.
                        lu.map.reserve(2 * n, n);
                    }
                    Some(lu)
                },
            )
        }
        None => {
            if lus.first().is_none_or(|l| (l.h - h).abs() > SAME_STEP * h) {
                integ.stats.lu_decompositions += 2;
                if lus.is_empty() {
                    lus.extend(spare.take());
                }
                lus.truncate(1);
                let part = pattern.partition_within(jac, structure);
                match lus.first_mut() {
                    Some(lu) => {
                        if !factor_into(lu, part, jac, h) {
                            *spare = lus.pop();
                        }
                    }
                    None => lus.extend(factor(jac, part, h, None)),
                }
            }
            !lus.is_empty()
        }
    }
}
