//! Air drag of the plate swept broadside (not in the paper; docs/model-notes.md, item 24).
//!
//! Slewing turns the plate face-on into the air. Each area element feels the quadratic drag of a
//! flat plate normal to the flow, `f = -1/2 rho_air C_d |v| v` per unit area, with `v(x, y)` the
//! absolute normal velocity (the rigid rotation `x theta'` plus the deflection rate). Its
//! generalised force on coordinate `j` is `Q_j = -int int 1/2 rho_air C_d |v| v dv/dq'_j dA`,
//! over both arms (the motion is antisymmetric and the law odd, so the two arms give the same).
//!
//! **Quadrature.** The integral is taken by a [`POINTS_X`] x [`POINTS_Y`] Gauss-Legendre rule
//! over the arm: at point `k`, `v_k = s_k . q'` (the velocity map of the point, rigid rotation
//! included) and the drag `c_k |v_k| v_k`, `c_k = 2 arms x 1/2 rho_air C_d w_k` with `w_k` the
//! point's area weight. The rule integrates the rigid rotation's moment `int x^3 dx` exactly; for
//! the deflection it is as exact as the modes are smooth (`|v| v` has a kink where `v` changes
//! sign).
//!
//! **Which coordinates.** Drag matters where velocities are large: the hub's rotation and the
//! slow modes. It acts on the hub and the [`DRAG_MODES`] plate coordinates of lowest frequency:
//! the dense coupling drag brings stays a small block (each point's drag depends on the rates of
//! all the coordinates it acts on), and the plan and the Jacobian stay small enough that the
//! default model keeps most of its speed; a 20 x 20 plate keeps its structured linear algebra for
//! the other modes.
//!
//! **Bond graph.** Per point a 0-junction `<prefix>.drag[k].point` bonded through TFs of moduli
//! `s_kj` to the coordinates' 1-junctions (its flow is `v_k`, as a shaker's point) and a
//! nonlinear R `<prefix>.drag[k]` with `e = c_k |f| f`, which dissipates `c_k |v_k|^3 >= 0`: the
//! drag's power appears in the power balance like any resistor's.
//!
//! **Coefficients.** `C_d` of a flat plate normal to the flow: 1.17-1.2 for aspect ratios 1 to 5,
//! 2.0 for an infinite strip (Hoerner, *Fluid-Dynamic Drag*, 1965, ch. 3); the arm is 1.41 m by
//! 0.47 m, an aspect ratio of 3: 1.2. `rho_air` = 1.2 kg/m^3 (air at 20 degC, sea level).

use nalgebra::DVector;

use super::beam_functions::gauss_legendre_rule;
use super::{PlateModel, PlateParameters};
use crate::bond_graph::NonlinearLaw;
use crate::math::dual::{Dual, HyperDual, Real};

/// Gauss-Legendre points along the arm: the rigid rotation's moment (`x^3`) exactly, and the
/// bending shapes of the modes the drag acts on (up to two nodes along the arm).
pub const POINTS_X: usize = 6;
/// Gauss-Legendre points across the arm: the modes the drag acts on are uniform or linear
/// across (bending and twist, `m = 1, 2`).
pub const POINTS_Y: usize = 3;
/// Most plate coordinates (those of lowest frequency) the drag acts on: with the default plate
/// the modes up to 41 Hz, the first bending and twist modes, which carry the plate's velocity in
/// a slewing move.
pub const DRAG_MODES: usize = 6;
/// Number of arms the coordinates describe.
const ARMS: f64 = 2.0;

/// One quadrature point of the drag.
#[derive(Clone, Debug, PartialEq)]
pub struct DragPoint {
    /// Where it is on the arm, `(x, y)` \[m\].
    pub at: (f64, f64),
    /// Its normal velocity per unit rate of each coordinate (zero for the coordinates the drag
    /// leaves out), with its derivative along the parameter the model is built for.
    pub velocity: DVector<Dual>,
    /// `c_k`: the drag force is `c_k |v_k| v_k` \[N s^2/m^2\], with its derivative.
    pub coefficient: Dual,
}

/// The drag points of `model` (whose drag is not set yet), from the velocity map `map(x, y)` of
/// a point (its displacement per unit coordinate, rigid rotation included); none without drag.
pub fn drag_points(
    p: &PlateParameters<Dual>,
    model: &PlateModel,
    map: impl Fn(Dual, Dual) -> DVector<Dual>,
) -> Vec<DragPoint> {
    let c = 0.5 * p.rho_air * p.cd;
    if c.v == 0.0 && c.d == 0.0 {
        return Vec::new();
    }
    // The plate coordinates of lowest frequency (stiffness and mass are diagonal over them).
    let first = model.first_plate();
    let mut plate: Vec<usize> = (first..model.dim()).collect();
    let omega2 = |j: usize| model.stiffness[(j, j)] / model.mass[(j, j)];
    plate.sort_by(|&i, &j| omega2(i).total_cmp(&omega2(j)).then(i.cmp(&j)));
    let kept: Vec<usize> = (0..first)
        .chain(plate.into_iter().take(DRAG_MODES))
        .collect();
    let (gx, gy) = (gauss_legendre_rule(POINTS_X), gauss_legendre_rule(POINTS_Y));
    let mut out = Vec::with_capacity(POINTS_X * POINTS_Y);
    for &(u, wu) in &gx {
        for &(v, wv) in &gy {
            let (x, y) = (0.5 * p.a * (1.0 + u), 0.5 * p.b * (1.0 + v));
            let weight = 0.25 * p.a * p.b * wu * wv;
            let full = map(x, y);
            let mut velocity = DVector::from_element(full.len(), Dual::from(0.0));
            for &j in &kept {
                velocity[j] = full[j];
            }
            out.push(DragPoint {
                at: (x.v, y.v),
                velocity,
                coefficient: ARMS * c * weight,
            });
        }
    }
    out
}

/// The drag force `c |f| f` of a point in any [`Real`]: [`law`]'s value.
#[inline]
pub fn force<S: Real>(coefficient: S, f: S) -> S {
    coefficient * f.abs() * f
}

/// The drag law of a point: `(e, de/df) = (c |f| f, 2 c |f|)` ([`force`] and its derivative).
#[inline]
pub fn law(coefficient: f64, f: f64) -> (f64, f64) {
    (force(coefficient, f), 2.0 * coefficient * f.abs())
}

/// The drag of a point as an R law in resistance form: [`law`], with its value bound
/// ([`value_bound`]) and its hyper-dual form ([`NonlinearLaw::with_hyper`]), [`force`] with the
/// coefficient's derivative.
pub fn nonlinear_law(coefficient: impl Into<Dual>) -> NonlinearLaw {
    let c_d = coefficient.into();
    let c = c_d.v;
    NonlinearLaw::new(format!("air drag {c:.3e} |v| v"), move |f| law(c, f))
        .with_value_bound_if(value_bound(c))
        .with_hyper(move |f, _| force(HyperDual::from(c_d), f))
}

/// The value bound of [`law`] ([`crate::bond_graph::NonlinearLaw::with_value_bound`]):
/// `|c |v| v| <= 2 |c| v² + MIN_POSITIVE`, the factor 2 for the two roundings of the product
/// (2^-52 each) and the smallest normal double for its underflow. For `|v| <=
/// VALUE_BOUND_RANGE`, `v²` is finite; declared for a finite coefficient.
pub fn value_bound(coefficient: f64) -> Option<(f64, f64)> {
    coefficient
        .is_finite()
        .then_some((2.0 * coefficient.abs(), f64::MIN_POSITIVE))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fragments::plate::{Formulation, Root};

    /// The plate turning rigidly at `omega` feels the drag moment `rho C_d b omega^2 a^4 / 4`
    /// (both arms: `2 int_0^a int_0^b 1/2 rho C_d (x omega)^2 x dy dx`), which the rule
    /// integrates exactly.
    #[test]
    fn rigid_rotation_drag_moment_is_the_closed_form() {
        for formulation in [Formulation::Paper, Formulation::Consistent] {
            let p = PlateParameters {
                formulation,
                ..PlateParameters::default()
            };
            let model = PlateModel::new(&p).unwrap();
            let omega = 0.7;
            let mut rate = DVector::zeros(model.dim());
            rate[0] = omega;
            let moment: f64 = model
                .drag
                .iter()
                .map(|d| {
                    let velocity = d.velocity.map(|x| x.v);
                    let v = velocity.dot(&rate);
                    law(d.coefficient.v, v).0 * velocity[0]
                })
                .sum();
            let exact = p.rho_air * p.cd * p.b * omega * omega * p.a.powi(4) / 4.0;
            assert!(
                ((moment - exact) / exact).abs() < 1e-13,
                "{formulation:?}: {moment} vs {exact}"
            );
        }
    }

    #[test]
    fn drag_is_off_without_a_coefficient_and_keeps_few_modes() {
        let p = PlateParameters {
            cd: 0.0,
            ..PlateParameters::default()
        };
        assert!(PlateModel::new(&p).unwrap().drag.is_empty());
        let p = PlateParameters {
            n: 6,
            m: 6,
            root: Root::Locked,
            ..PlateParameters::default()
        };
        let model = PlateModel::new(&p).unwrap();
        assert_eq!(model.drag.len(), POINTS_X * POINTS_Y);
        for d in &model.drag {
            assert!(d.velocity.iter().filter(|v| v.v != 0.0).count() <= DRAG_MODES);
        }
    }

    use crate::fragments::law_checks::{
        assert_hand_derivatives, assert_mixed, assert_same_bits, grid,
    };

    #[test]
    fn drag_in_hyper_dual_numbers() {
        let c = 0.37;
        let law = nonlinear_law(c);
        let vs = grid(1.0);
        assert_same_bits(&law, |v, _| force(c, v), &vs, &[0.0]);
        for &v in &vs {
            // The law as it was before its value had one source.
            let before = (c * v.abs() * v, 2.0 * c * v.abs());
            let (e, de, _) = law.eval(v, 0.0);
            assert_eq!(
                (e.to_bits(), de.to_bits()),
                (before.0.to_bits(), before.1.to_bits())
            );
        }
        let dual = |v, _| force(Dual::from(c), v);
        assert_hand_derivatives(&law, dual, &vs, &[0.0], 1e-12, |_, _| (0.0, 0.0));
        // d²e/dv dc = 2 |v|: linear in c, the central difference exact but for rounding.
        for v in [-3.0, -0.2, 0.05, 1.7] {
            assert_mixed(nonlinear_law, c, 1e-4, c, v, 0.0, false);
        }
    }
}
