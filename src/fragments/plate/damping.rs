//! Structural damping stated on the modes of the assembled structure (consistent formulation,
//! hub on its bearing; docs/model-notes.md, item 25).
//!
//! A viscous dashpot `c = 2 zeta sqrt(k m)` gives its element the damping ratio `zeta` at one
//! frequency only. Put on the clamped-plate modes and on the torsion bar separately, such
//! dashpots damp the modes of the assembled hub-bar-plate structure with ratios that are not
//! `zeta` at all: the slow coupled mode carries strain energy of plate modes far above its own
//! frequency, where their dashpots are weak, and of a bar dashpot sized for a rigid plate.
//!
//! Here the damping is stated where a user sees it: on the undamped modes `phi_i` (mass
//! normalised, frequency `omega_i`) of the structure *with the motor clamped*, coordinates
//! `q = (theta, eta)`, mass matrix `M` and stiffness `K` = plate stiffness plus the bar on
//! `theta`. The damping matrix
//!
//! `C = sum_i 2 zeta omega_i (M phi_i) (M phi_i)'`
//!
//! gives every such mode exactly the ratio `zeta` (modal damping, Craig and Kurdila, *Fundamentals
//! of Structural Dynamics*, 2006, sec. 10.5), and it damps deformation only: it acts on the
//! deformation rates `(theta' - theta_motor', eta')`, so a rigid rotation of motor, bar, hub and
//! plate together costs nothing. Without the bar (motor uncoupled) the structure is free: its
//! rigid mode gets no damper, and the elastic modes, `M`-orthogonal to it, are not damped by a
//! rigid rotation either.
//!
//! In the bond graph each term is a *modal dashpot*: a 0-junction whose flow is the modal rate
//! `(M phi_i)' q'`, bonded through TFs of moduli `(M phi_i)_j` to the coordinates (the hub's
//! through the bar's twist junction, whose flow is `theta_motor' - theta'`) and a linear R of
//! `2 zeta omega_i`. It dissipates `2 zeta omega_i (modal rate)^2 >= 0`.

//!
//! **Derivatives** (exact sensitivities, `crate::model::sensitivity`). The dashpots carry their
//! constants in dual numbers: along `zeta` the resistances move (`2 omega_i d zeta`), along the
//! bar's stiffness and the plate's and hub's parameters the modes move too, and their
//! derivatives are those of the generalised eigenpairs of the subproblem (hub and
//! [`damped_coordinates`], all its modes kept, the free structure's rigid mode included in the
//! expansion though it gets no dashpot): [`crate::eigen::derivative::generalized_eigen_dual`]
//! with `dK` the bar's `dk` on the hub plus the model's `dK` ([`super::PlateDerivative`]) and
//! `dM` the model's. The values are the `f64` computation's, bit for bit.

use nalgebra::{DMatrix, DVector};

use super::modes::generalized_eigen;
use super::PlateModel;
use crate::eigen::derivative::generalized_eigen_dual;
use crate::math::dual::{Dual, Real};

/// One term of the modal damping matrix, its constants with their derivatives along the
/// parameter the model is built for (zero in a model of `f64` parameters).
#[derive(Clone, Debug, PartialEq)]
pub struct ModalDashpot {
    /// `M phi_i`: the modal rate is `velocity . (deformation rates)` (entry 0: the hub's rate
    /// relative to the motor).
    pub velocity: DVector<Dual>,
    /// `2 zeta omega_i` \[1/s, with the mass-normalised modes\].
    pub resistance: Dual,
    /// `omega_i` \[rad/s\].
    pub omega: Dual,
}

/// Most plate coordinates (those of lowest frequency) the modal dashpots span: all of the
/// default 3 x 5 plate's. Each dashpot couples every coordinate it spans, so a large plate would
/// turn the Jacobian dense; its stiffer clamped-plate modes, which the hub barely moves, keep
/// their own R (`2 zeta sqrt(k m)`, exact for them with the hub locked).
pub const DAMPED_MODES: usize = 15;

/// The plate coordinates the modal dashpots span: the [`DAMPED_MODES`] of lowest frequency.
pub fn damped_coordinates(model: &PlateModel) -> Vec<usize> {
    let first = model.first_plate();
    let mut plate: Vec<usize> = (first..model.dim()).collect();
    let omega2 = |j: usize| model.stiffness[(j, j)] / model.mass[(j, j)];
    plate.sort_by(|&i, &j| omega2(i).total_cmp(&omega2(j)).then(i.cmp(&j)));
    plate.truncate(DAMPED_MODES);
    plate.sort_unstable();
    plate
}

/// The modal dashpots of the structure of `model` (which must have its hub): every elastic mode
/// of `(M, K + bar)` over the hub and the [`damped_coordinates`], with the bar's stiffness
/// `bar_k` on the hub coordinate when the motor drives it (clamped motor), damped with `zeta`.
///
/// `bar_k` and `zeta` in `f64` or in dual numbers: the dashpots carry the derivatives (the
/// module's **Derivatives**), and so do the model's matrices ([`PlateModel::derivative`]); the
/// modes' derivatives are computed only when `bar_k` or the matrices carry one, so a model of
/// `f64` parameters meets no condition of theirs (distinct eigenvalues).
pub fn modal_dashpots<S: Copy + Into<Dual>>(
    model: &PlateModel,
    bar_k: Option<S>,
    zeta: S,
) -> Result<Vec<ModalDashpot>, String> {
    assert!(model.hub, "modal dashpots are for the structure on its hub");
    let (bar_k, zeta): (Option<Dual>, Dual) = (bar_k.map(Into::into), zeta.into());
    if zeta.v == 0.0 && zeta.d == 0.0 {
        return Ok(Vec::new());
    }
    let coords: Vec<usize> = std::iter::once(0)
        .chain(damped_coordinates(model))
        .collect();
    let n = coords.len();
    let sub = |m: &DMatrix<Dual>| DMatrix::from_fn(n, n, |i, j| m[(coords[i], coords[j])]);
    let (mass, mut k) = (sub(&model.mass_dual()), sub(&model.stiffness_dual()));
    if let Some(kb) = bar_k {
        k[(0, 0)] = k[(0, 0)] + kb;
    }
    // The eigenpairs and their derivatives along the parameter (zero when neither the bar nor
    // the structure moves).
    let moves = |m: &DMatrix<Dual>| m.iter().any(|x| x.d != 0.0);
    let (vals, vecs, d_vals, d_vecs) = if moves(&k) || moves(&mass) {
        let (vals, vecs) = generalized_eigen_dual(&k, &mass, generalized_eigen)
            .map_err(|e| format!("the structure's modes: {e}"))?;
        (
            vals.iter().map(|x| x.v).collect::<Vec<f64>>(),
            vecs.map(|x| x.v),
            vals.iter().map(|x| x.d).collect::<Vec<f64>>(),
            vecs.map(|x| x.d),
        )
    } else {
        let (vals, vecs) = generalized_eigen(&k.map(|x| x.v), &mass.map(|x| x.v))?;
        (vals, vecs, vec![0.0; n], DMatrix::zeros(n, n))
    };
    let (mass, d_mass) = (mass.map(|x| x.v), mass.map(|x| x.d));
    let scale = vals.iter().fold(0.0f64, |s, v| s.max(v.abs()));
    let mut out = Vec::new();
    for (i, &w2) in vals.iter().enumerate() {
        if w2 <= 1e-10 * scale {
            continue; // the free structure's rigid rotation
        }
        let omega = Real::sqrt(Dual::new(w2, d_vals[i]));
        let spanned = &mass * vecs.column(i);
        let d_spanned = &mass * d_vecs.column(i) + &d_mass * vecs.column(i);
        let mut velocity = DVector::from_element(model.dim(), Dual::from(0.0));
        for ((&c, &v), &d) in coords.iter().zip(spanned.iter()).zip(d_spanned.iter()) {
            velocity[c] = Dual::new(v, d);
        }
        out.push(ModalDashpot {
            velocity,
            resistance: 2.0 * zeta * omega,
            omega,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fragments::plate::{Formulation, PlateParameters, Root};

    fn model(formulation: Formulation, root: Root) -> PlateModel {
        let p = PlateParameters {
            formulation,
            root,
            ..PlateParameters::default()
        };
        PlateModel::new(&p).unwrap()
    }

    /// Each coordinate's R is `2 zeta sqrt(K_jj M_jj)` to the bit in both formulations, and
    /// along `zeta` (the model built with `zeta` seeded) its derivative is `2 sqrt(K_jj M_jj)`.
    #[test]
    fn the_coordinates_damping_is_the_differentiated_formula() {
        let zeta = PlateParameters::default().zeta;
        for formulation in [Formulation::Paper, Formulation::Consistent] {
            for root in [Root::Hub, Root::Locked] {
                let m = model(formulation, root);
                let p = PlateParameters {
                    formulation,
                    root,
                    ..PlateParameters::default()
                };
                let mut seeded = p.map(Dual::from);
                seeded.zeta = Dual::new(zeta, 1.0);
                let d = PlateModel::for_parameters(&seeded)
                    .unwrap()
                    .damping_derivative;
                for (j, &r) in m.damping.iter().enumerate() {
                    let c = m.first_plate() + j;
                    let k_m = m.stiffness[(c, c)] * m.mass[(c, c)];
                    assert_eq!(r, 2.0 * zeta * k_m.sqrt(), "{formulation:?} {root:?} {j}");
                    assert_eq!(d[j], 2.0 * k_m.sqrt());
                }
            }
        }
    }

    /// Along the bar's stiffness the dashpots' frequencies, resistances and rates `M phi` are
    /// central differences of the `f64` dashpots, with each mode's sign taken from its rate (a
    /// solver may flip a vector); the values are the `f64` dashpots' bits. Along `zeta` only
    /// the resistances move, by `2 omega_i`.
    ///
    /// Step 1e-4 relative: the modes are analytic in `k`, so the truncation is `h^2` (1e-8)
    /// of a derivative times the ratio of its higher derivatives, within the `1e-6` relative
    /// allowed. Round-off: the eigen-solver is backward stable, its eigenvalues off by about
    /// `eps lambda_max`, its vectors by `eps lambda_max / gap_i` (Davis and Kahan), which the
    /// difference divides by `2 h k`: the floor `50 eps lambda_max / (2 h k)` (the highest
    /// modes, which the bar does not move, show 10 `eps lambda_max` of such noise) on an
    /// eigenvalue, half that over `omega_i` on `omega_i`, times `|M phi| / gap_i` on a rate.
    #[test]
    fn the_dashpots_derivatives_are_central_differences() {
        let m = model(Formulation::Consistent, Root::Hub);
        let (k, zeta) = (2.5e3, 0.02);
        let exact = modal_dashpots(&m, Some(Dual::new(k, 1.0)), Dual::from(zeta)).unwrap();
        let values = modal_dashpots(&m, Some(k), zeta).unwrap();
        assert_eq!(exact.len(), values.len());
        for (e, v) in exact.iter().zip(&values) {
            assert_eq!(e.omega.v, v.omega.v);
            assert_eq!(e.resistance.v, v.resistance.v);
            assert!(e
                .velocity
                .iter()
                .zip(v.velocity.iter())
                .all(|(a, b)| a.v == b.v));
        }
        let h = 1e-4;
        let plus = modal_dashpots(&m, Some(k * (1.0 + h)), zeta).unwrap();
        let minus = modal_dashpots(&m, Some(k * (1.0 - h)), zeta).unwrap();
        let lambdas: Vec<f64> = exact.iter().map(|d| d.omega.v * d.omega.v).collect();
        let lambda_max = lambdas.iter().fold(0.0f64, |a, &b| a.max(b));
        let noise = 50.0 * f64::EPSILON * lambda_max / (2.0 * h * k);
        let (mut worst, mut moved) = (0.0f64, 0.0f64);
        for (i, e) in exact.iter().enumerate() {
            let fd =
                |f: &dyn Fn(&ModalDashpot) -> f64| (f(&plus[i]) - f(&minus[i])) / (2.0 * h * k);
            let omega = e.omega.v;
            let gap = lambdas
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .fold(f64::INFINITY, |g, (_, &l)| g.min((l - omega * omega).abs()));
            let mut check = |what: &str, exact: f64, fd: f64, floor: f64| {
                let ratio = (exact - fd).abs() / (1e-6 * fd.abs() + floor);
                assert!(
                    ratio <= 1.0,
                    "mode {i}: d {what}/dk {exact:e} against {fd:e}"
                );
                worst = worst.max(ratio);
            };
            check(
                "omega",
                e.omega.d,
                fd(&|d| d.omega.v),
                noise / (2.0 * omega),
            );
            check(
                "resistance",
                e.resistance.d,
                fd(&|d| d.resistance.v),
                2.0 * zeta * noise / (2.0 * omega),
            );
            let value: DVector<f64> = e.velocity.map(|x| x.v);
            let aligned = |d: &ModalDashpot| {
                let v = d.velocity.map(|x| x.v);
                if v.dot(&value) < 0.0 {
                    -v
                } else {
                    v
                }
            };
            let d_v = (aligned(&plus[i]) - aligned(&minus[i])) / (2.0 * h * k);
            let exact_v = e.velocity.map(|x| x.d);
            for (&x, &f) in exact_v.iter().zip(d_v.iter()) {
                check("(M phi)", x, f, noise * value.amax() / gap);
            }
            moved = moved.max(exact_v.amax() * k / value.amax());
        }
        eprintln!(
            "dashpots along k: worst {worst:.3e} of the tolerance, rates move by {moved:.3e}"
        );
        // The bar moves the modes: their rates change by a sizeable fraction per unit relative k.
        assert!(
            moved > 1e-3,
            "the modes barely move with the bar: {moved:e}"
        );
        let along_zeta = modal_dashpots(&m, Some(Dual::from(k)), Dual::new(zeta, 1.0)).unwrap();
        for (z, v) in along_zeta.iter().zip(&values) {
            assert_eq!(z.resistance.d, 2.0 * v.omega.v);
            assert!(z.velocity.iter().all(|x| x.d == 0.0) && z.omega.d == 0.0);
        }
    }
}
