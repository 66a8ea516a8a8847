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

use nalgebra::{DMatrix, DVector};

use super::modes::generalized_eigen;
use super::PlateModel;

/// One term of the modal damping matrix.
#[derive(Clone, Debug, PartialEq)]
pub struct ModalDashpot {
    /// `M phi_i`: the modal rate is `velocity . (deformation rates)` (entry 0: the hub's rate
    /// relative to the motor).
    pub velocity: DVector<f64>,
    /// `2 zeta omega_i` \[1/s, with the mass-normalised modes\].
    pub resistance: f64,
    /// `omega_i` \[rad/s\].
    pub omega: f64,
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
pub fn modal_dashpots(
    model: &PlateModel,
    bar_k: Option<f64>,
    zeta: f64,
) -> Result<Vec<ModalDashpot>, String> {
    assert!(model.hub, "modal dashpots are for the structure on its hub");
    if zeta == 0.0 {
        return Ok(Vec::new());
    }
    let coords: Vec<usize> = std::iter::once(0)
        .chain(damped_coordinates(model))
        .collect();
    let n = coords.len();
    let sub = |m: &DMatrix<f64>| DMatrix::from_fn(n, n, |i, j| m[(coords[i], coords[j])]);
    let (mass, mut k) = (sub(&model.mass), sub(&model.stiffness));
    if let Some(kb) = bar_k {
        k[(0, 0)] += kb;
    }
    let (vals, vecs) = generalized_eigen(&k, &mass)?;
    let scale = vals.iter().fold(0.0f64, |s, v| s.max(v.abs()));
    let mut out = Vec::new();
    for (i, &w2) in vals.iter().enumerate() {
        if w2 <= 1e-10 * scale {
            continue; // the free structure's rigid rotation
        }
        let omega = w2.sqrt();
        let spanned = &mass * vecs.column(i);
        let mut velocity = DVector::zeros(model.dim());
        for (&c, &v) in coords.iter().zip(spanned.iter()) {
            velocity[c] = v;
        }
        out.push(ModalDashpot {
            velocity,
            resistance: 2.0 * zeta * omega,
            omega,
        });
    }
    Ok(out)
}
