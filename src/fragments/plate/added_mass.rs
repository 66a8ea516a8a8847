//! The air's added mass on the plate (not in the paper; docs/model-notes.md, item 30).
//!
//! A plate moving normal to itself through air drags air along: the kinetic energy of the flow it
//! sets up is that of an added mass. Strip theory takes each section of the arm (width `b`, at
//! distance `x` from the hub axis) as a two-dimensional flat plate in potential flow, whose added
//! mass per unit length is (Newman, *Marine Hydrodynamics*, 1977, sec. 4.13; Blevins, *Formulas
//! for Natural Frequency and Mode Shape*, 1979, table 14-1)
//!
//! * in heave (the section's mean normal velocity `h'`): `m_h = C_a rho_air pi b^2 / 4`;
//! * in twist about its centre line (the section's rotation rate `alpha'`):
//!   `m_alpha = C_a rho_air pi b^4 / 128`;
//!
//! with no coupling between the two about the centre line. `C_a` (`plate.Ca`) is 1 for strip
//! theory. With the paper's plate (`b` = 0.4685 m, `rho h` = 7.41 kg/m^2) and air at 1.2 kg/m^3
//! the heave term is 0.207 kg/m, 6.0 % of the plate's 3.47 kg/m, and the twist term 2.2 % of the
//! section's own rotary inertia.
//!
//! **On the assumed modes** `phi_n(x/a) psi_m(y/b)` of eq. 7: a section's heave per unit amplitude
//! is `phi_n h_m` with `h_m = int_0^1 psi_m` and its rotation `phi_n alpha_m` with
//! `alpha_m = (12 / b) int_0^1 (eta - 1/2) psi_m` (the least-squares slope across the section).
//! The free-free family's first two functions are the section's rigid heave and rotation and the
//! others are orthogonal to both, so only `m = 1` (heave) and `m = 2` (twist) gain added mass,
//! and, the `phi_n` being orthonormal, the added mass matrix of the assumed modes is diagonal:
//! `a (m_h h_m^2 + m_alpha alpha_m^2)` per arm. The rigid rotation `x theta` adds
//! `m_h a^3 / 3` per arm to the slewing inertia (3.9 % of the default hub and plate) and couples
//! to the heave modes through `m_h a^2 int xi phi_n h_m`, as the plate's own mass does.
//!
//! **Where strip theory stops.** It gives each section the flow of an infinitely long strip: the
//! air escaping round the tip and the root makes the true added mass smaller, more so for modes
//! with nodes along the arm (a rectangular plate of aspect ratio 3 in heave has about 0.8 of the
//! strip value; Blevins, table 14-2), and the chordwise bending shapes (`m >= 3`, above 60 Hz)
//! get none here although they have some. The slow modes, which carry a slewing move, are the
//! ones it describes best. A measured frequency shift between air and vacuum, or `plate.Ca`
//! fitted to the measured first bending frequency, replaces it.

use nalgebra::DVector;

use super::beam_functions::{moment_integral, product_integral, BeamFunction};
use super::{powi, PlateParameters};
use crate::math::dual::Dual;

/// The added mass of the air on the assumed modes of one formulation, in `f64` or with the
/// derivatives along a parameter ([`Dual`]).
#[derive(Clone, Debug, PartialEq)]
pub struct AddedMass<S = f64> {
    /// On each assumed-mode product `j = N (m - 1) + n` (the diagonal of the added mass matrix)
    /// \[kg\], over `arms` arms.
    pub modes: DVector<S>,
    /// On the rigid rotation, `arms m_h a^3 / 3` \[kg m^2\].
    pub hub: S,
    /// Between the rigid rotation and each assumed-mode product,
    /// `arms m_h a^2 int xi phi_n dxi h_m` \[kg m\].
    pub coupling: DVector<S>,
}

/// Strip theory's added mass per unit length of the arm, `(m_h, m_alpha)`: heave \[kg/m\] and
/// twist about the centre line \[kg m\].
pub fn per_length(p: &PlateParameters) -> (f64, f64) {
    let (m_h, m_alpha) = per_length_dual(&p.map(Dual::from));
    (m_h.v, m_alpha.v)
}

/// [`per_length`] with the derivatives.
pub fn per_length_dual(p: &PlateParameters<Dual>) -> (Dual, Dual) {
    let c = p.ca * p.rho_air * std::f64::consts::PI;
    (c * p.b * p.b / 4.0, c * powi(p.b, 4) / 128.0)
}

/// The added mass on the products of `phis` (along the arm) and `psis` (across it) for `arms`
/// arms, with its derivatives; `None` when there is none (`plate.Ca` or `plate.rho_air` zero,
/// and not moving).
pub fn strip(
    p: &PlateParameters<Dual>,
    phis: &[BeamFunction],
    psis: &[BeamFunction],
    arms: f64,
) -> Option<AddedMass<Dual>> {
    let (m_h, m_alpha) = per_length_dual(p);
    if m_h.v == 0.0 && m_h.d == 0.0 {
        return None;
    }
    let (a, b) = (p.a, p.b);
    let heave: Vec<f64> = psis.iter().map(|psi| moment_integral(psi, 0)).collect();
    let twist: Vec<Dual> = psis
        .iter()
        .map(|psi| 12.0 * (moment_integral(psi, 1) - 0.5 * moment_integral(psi, 0)) / b)
        .collect();
    // each along-arm function's int phi^2 and int xi phi, computed once
    let squares: Vec<f64> = phis
        .iter()
        .map(|phi| product_integral(phi, 0, phi, 0))
        .collect();
    let moments: Vec<f64> = phis.iter().map(|phi| moment_integral(phi, 1)).collect();
    let n = phis.len();
    let count = n * psis.len();
    let modes = DVector::from_fn(count, |j, _| {
        let m = j / n;
        arms * a * squares[j % n] * (m_h * heave[m] * heave[m] + m_alpha * twist[m] * twist[m])
    });
    let coupling = DVector::from_fn(count, |j, _| {
        arms * m_h * a * a * moments[j % n] * heave[j / n]
    });
    Some(AddedMass {
        modes,
        hub: arms * m_h * powi(a, 3) / 3.0,
        coupling,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fragments::plate::modes::generalized_eigen;
    use crate::fragments::plate::{Formulation, PlateModel, Root};
    use nalgebra::DMatrix;

    fn plate(formulation: Formulation, root: Root, ca: f64) -> PlateParameters {
        PlateParameters {
            formulation,
            root,
            ca,
            ..PlateParameters::default()
        }
    }

    /// Frequencies of `(M, K)` with `extra` added to `K[0][0]` (the bar on the hub, the motor
    /// clamped), ascending \[rad/s\], and the mass-normalised modes.
    fn frequencies(model: &PlateModel, extra: f64) -> (Vec<f64>, DMatrix<f64>) {
        let mut k = model.stiffness.clone();
        k[(0, 0)] += extra;
        let (vals, vecs) = generalized_eigen(&k, &model.mass).unwrap();
        (vals.iter().map(|v| v.max(0.0).sqrt()).collect(), vecs)
    }

    /// With the root clamped, a bending mode uniform across the width gains the heave added mass
    /// along its whole length, so its frequency falls by the closed form
    /// `1 - 1/sqrt(1 + m_h / (rho h b))` (2.85 %): the first two bending modes within 10 % of that
    /// drop (the Poisson coupling to `m = 3`, which gets no added mass, is the difference), in
    /// both formulations. The first twist mode falls by the twist term's fraction.
    #[test]
    fn clamped_bending_frequencies_fall_by_the_strip_theory_fraction() {
        for formulation in [Formulation::Consistent, Formulation::Paper] {
            let dry = PlateModel::new(&plate(formulation, Root::Locked, 0.0)).unwrap();
            let wet_p = plate(formulation, Root::Locked, 1.0);
            let wet = PlateModel::new(&wet_p).unwrap();
            let (m_h, m_alpha) = per_length(&wet_p);
            let mu_b = wet_p.areal_mass() * wet_p.b;
            let bending = 1.0 - 1.0 / (1.0 + m_h / mu_b).sqrt();
            let rotary = wet_p.areal_mass() * wet_p.b.powi(3) / 12.0;
            let twist = 1.0 - 1.0 / (1.0 + m_alpha / rotary).sqrt();
            // locked root: the coordinates are the clamped modes (diagonal M and K), labelled
            let omega = |m: &PlateModel, label: (usize, usize)| {
                let j = m.labels.iter().position(|l| *l == label).unwrap();
                (m.stiffness[(j, j)] / m.mass[(j, j)]).sqrt()
            };
            let drop = |label| 1.0 - omega(&wet, label) / omega(&dry, label);
            for (label, expect, what) in [
                ((1, 1), bending, "first bending"),
                ((2, 1), bending, "second bending"),
                ((1, 2), twist, "first twist"),
            ] {
                let rel = (drop(label) - expect).abs() / expect;
                println!(
                    "{formulation:?}, root locked, {what} {label:?}: falls by {:.3} %, strip \
                     theory {:.3} %",
                    100.0 * drop(label),
                    100.0 * expect
                );
                assert!(
                    rel < 0.1,
                    "{formulation:?} {what}: drop {} vs {expect} ({rel})",
                    drop(label)
                );
            }
        }
    }

    /// With the hub on the torsion bar and the motor clamped, each mode's frequency falls by the
    /// fraction Rayleigh's quotient gives from the dry mode shape: `1 - 1/sqrt(1 + T_air / T)`,
    /// with `T_air` the strip-theory kinetic energy of that shape, integrated here by quadrature
    /// of the deflection field the model draws (the section's mean and slope across the width,
    /// 40 x 40 midpoint points per arm), not from this module's formulas. The first two bending
    /// modes (the hub on the bar with the plate, and the first plate bending) within 10 % of it.
    #[test]
    fn motor_clamped_frequencies_fall_by_rayleighs_fraction() {
        let bar_k = 2500.0;
        let dry_p = plate(Formulation::Consistent, Root::Hub, 0.0);
        let (dry, map) = PlateModel::with_displacements(&dry_p).unwrap();
        let wet = PlateModel::new(&plate(Formulation::Consistent, Root::Hub, 1.0)).unwrap();
        let (f_dry, modes) = frequencies(&dry, bar_k);
        let (f_wet, _) = frequencies(&wet, bar_k);
        let (m_h, m_alpha) = per_length(&plate(Formulation::Consistent, Root::Hub, 1.0));
        let (a, b) = (dry_p.a, dry_p.b);
        let points = 40;
        let mut checked = 0;
        for i in 0..f_dry.len() {
            let phi = modes.column(i);
            // T = phi' M phi = 1 (mass-normalised); the air's, over both arms
            let (mut t_heave, mut t_twist) = (0.0, 0.0);
            for ix in 0..points {
                let x = (ix as f64 + 0.5) * a / points as f64;
                let (mut mean, mut slope) = (0.0, 0.0);
                for iy in 0..points {
                    let eta = (iy as f64 + 0.5) / points as f64;
                    let w = map(x, eta * b).dot(&phi);
                    mean += w / points as f64;
                    slope += 12.0 * (eta - 0.5) * w / points as f64 / b;
                }
                t_heave += 2.0 * m_h * mean * mean * a / points as f64;
                t_twist += 2.0 * m_alpha * slope * slope * a / points as f64;
            }
            let t_air = t_heave + t_twist;
            let expect = 1.0 - 1.0 / (1.0 + t_air).sqrt();
            let drop = 1.0 - f_wet[i] / f_dry[i];
            // the bending modes (heave, not twist): the hub on the bar, then the plate's first
            // bending
            if t_heave > t_twist && checked < 2 {
                let rel = (drop - expect).abs() / expect;
                println!(
                    "motor clamped, mode at {:.3} Hz: falls by {:.3} %, Rayleigh {:.3} %",
                    f_dry[i] / (2.0 * std::f64::consts::PI),
                    100.0 * drop,
                    100.0 * expect
                );
                assert!(
                    rel < 0.1,
                    "mode {i} ({:.3} Hz): drop {drop} vs Rayleigh {expect}",
                    f_dry[i] / (2.0 * std::f64::consts::PI)
                );
                checked += 1;
            }
        }
        assert_eq!(checked, 2);
    }

    /// The slewing inertia gains `2 m_h a^3 / 3` (3.9 % of hub and plate with the defaults).
    #[test]
    fn the_rigid_rotation_gains_the_strip_inertia() {
        for formulation in [Formulation::Consistent, Formulation::Paper] {
            let p = plate(formulation, Root::Hub, 1.0);
            let wet = PlateModel::new(&p).unwrap();
            let dry = PlateModel::new(&plate(formulation, Root::Hub, 0.0)).unwrap();
            let (m_h, _) = per_length(&p);
            let gain = wet.mass[(0, 0)] - dry.mass[(0, 0)];
            let expect = 2.0 * m_h * p.a.powi(3) / 3.0;
            assert!((gain - expect).abs() < 1e-12 * expect, "{gain} vs {expect}");
            let fraction = expect / p.hub_total_inertia();
            assert!((0.038..0.040).contains(&fraction), "{fraction}");
        }
    }
}
