//! The consistent plate model: the Lagrangian of hub and plate (eqs. 3-5 in full),
//! docs/model-notes.md, items 2 and 18.
//!
//! In the hub frame the deflection is `w = sum phi_n(x) psi_m(y) eta_nm` with clamped-free
//! functions along `x` (the root is clamped to the hub) and the free-free family across; the
//! absolute displacement is `x theta + w`. For the two arms moving antisymmetrically,
//!
//! * kinetic energy (eq. 4): `T = (I_H + 2 I_P) theta'^2 / 2 + 2 theta' int int m x w' + int int m
//!   w'^2` (both arms), so the hub and the plate are coupled through `int int m x phi_n psi_m`;
//! * strain energy (eq. 5), Kirchhoff with Poisson and twist terms:
//!   `K = D [X22 Y00 + X00 Y22 + nu (X20 Y02 + X02 Y20) + 2 (1 - nu) X11 Y11]` (times two arms),
//!   `Xij = int phi^(i) phi^(j) dx`, `Yij = int psi^(i) psi^(j) dy`: a full (coupled) matrix;
//!   the Poisson term couples `m = 1` and `m = 3` (docs/model-notes.md, item 9);
//! * the mass matrix of the plate alone is `2 m a b` times the identity (the functions are
//!   orthogonal), so the plate part is first diagonalised exactly: the coordinates of the model
//!   are the natural modes of the clamped plate (eigenvectors of the Ritz problem), with an R
//!   per mode (`2 zeta omega` modal damping of the clamped plate). The mass matrix then couples
//!   the hub angle to these modes. The bond graph carries this kinetic energy on one-port
//!   inertias, the hub's and one per mode on its absolute rate ([`super::AbsoluteRates`]).
//! * the air's added mass ([`super::added_mass`]) joins the plate's: the modes are then those of
//!   the plate in air, still normalised to the modal mass `2 m a b`, and the hub gains the air's
//!   share of the slewing inertia and of the coupling.
//!
//! Without damping the model conserves energy exactly (a Hamiltonian system), and as a
//! Rayleigh-Ritz model its frequencies converge from above as `N x M` grows. It does not
//! reproduce eq. 16 and must not be tuned to (docs/model-notes.md, item 10).

use nalgebra::{DMatrix, DVector};

use super::beam_functions::{
    moment_integral, product_tables, BeamFunction, BeamKind, TABLE_ORDERS,
};
use super::{
    added_mass, beam_value, powi, DualDisplacementMap, DualModel, PlateParameters, Root, ZERO,
};
use crate::eigen::derivative::symmetric_eigen_derivative;
use crate::math::dual::{Dual, Real};

/// Number of arms described by the coordinates (antisymmetric motion of the symmetric plate).
pub const ARMS: f64 = 2.0;

/// The Ritz matrices of the plate alone (both arms) in the assumed-mode coordinates
/// `j = N (m - 1) + n`: `(M, K)`, `M = 2 m a b I`.
pub fn ritz_matrices(p: &PlateParameters) -> (DMatrix<f64>, DMatrix<f64>) {
    let (m, k) = ritz_matrices_dual(&p.map(Dual::from));
    (m.map(|x| x.v), k.map(|x| x.v))
}

/// [`ritz_matrices`] with their derivatives along the parameter seeded in `p`: the tables are
/// dimensionless, so `dK` and `dM` are the entries' formulas differentiated in `D`, `nu`, `m`
/// and the lengths `a`, `b` that scale them.
pub fn ritz_matrices_dual(p: &PlateParameters<Dual>) -> (DMatrix<Dual>, DMatrix<Dual>) {
    let (a, b, d, nu) = (p.a, p.b, p.rigidity(), p.nu);
    // The dimensionless tables of the families, scaled by the lengths of their directions.
    let scaled = |kind: BeamKind, count: usize, len: Dual| {
        let tables = product_tables(kind, count);
        std::array::from_fn(|k| {
            let (i, j) = TABLE_ORDERS[k];
            let factor = powi(len, 1 - i as i32 - j as i32);
            DMatrix::from_fn(count, count, |r, c| tables[k][(r, c)] * factor)
        })
    };
    let [x00, x11, x20, x22] = scaled(BeamKind::ClampedFree, p.n, a);
    let [y00, y11, y20, y22] = scaled(BeamKind::FreeFree, p.m, b);
    let nm = p.n * p.m;
    let idx = |j: usize| (j % p.n, j / p.n);
    let mut k = DMatrix::from_element(nm, nm, ZERO);
    let mut m = DMatrix::from_element(nm, nm, ZERO);
    for r in 0..nm {
        let (n1, m1) = idx(r);
        for c in 0..nm {
            let (n2, m2) = idx(c);
            k[(r, c)] = ARMS
                * d
                * (x22[(n1, n2)] * y00[(m1, m2)]
                    + x00[(n1, n2)] * y22[(m1, m2)]
                    + nu * (x20[(n1, n2)] * y20[(m2, m1)] + x20[(n2, n1)] * y20[(m1, m2)])
                    + 2.0 * (1.0 - nu) * x11[(n1, n2)] * y11[(m1, m2)]);
            m[(r, c)] = ARMS * p.areal_mass() * x00[(n1, n2)] * y00[(m1, m2)];
        }
    }
    // symmetrise rounding
    (symmetrised(&m), symmetrised(&k))
}

/// `(A + A') / 2` on the values and on the derivatives.
fn symmetrised(a: &DMatrix<Dual>) -> DMatrix<Dual> {
    let half = |b: DMatrix<f64>| (&b + b.transpose()) * 0.5;
    half(a.map(|x| x.v)).zip_map(&half(a.map(|x| x.d)), Dual::new)
}

/// `Phi' v` for `Phi` and `v` with their derivatives: the value `Phi' v` (the `f64` product),
/// the derivative `dPhi' v + Phi' dv`.
fn transposed_product(phi: &(DMatrix<f64>, DMatrix<f64>), v: &DVector<Dual>) -> DVector<Dual> {
    let (value, slope) = (v.map(|x| x.v), v.map(|x| x.d));
    let product = phi.0.transpose() * &value;
    let derivative = phi.1.transpose() * &value + phi.0.transpose() * &slope;
    product.zip_map(&derivative, Dual::new)
}

/// Builds the consistent formulation, with the map from a point `(x, y)` to its displacement
/// per unit coordinate (the hub's rotation `x theta` included), in dual numbers: the modes'
/// derivatives are the clamped plate's eigenpairs' ([`symmetric_eigen_derivative`] on
/// `S K S`), which fails when two of its modes are too close to differentiate (only when a
/// derivative is seeded).
pub(crate) fn build(p: &PlateParameters<Dual>) -> Result<(DualModel, DualDisplacementMap), String> {
    let phis = BeamFunction::family(BeamKind::ClampedFree, p.n);
    let psis = BeamFunction::family(BeamKind::FreeFree, p.m);
    let (a, b, mu) = (p.a, p.b, p.areal_mass());
    let nm = p.n * p.m;
    let (_, kr) = ritz_matrices_dual(p);
    let modal_mass = ARMS * mu * a * b;
    // M = modal_mass I + the air's diagonal added mass D_a: with S = diag(sqrt(modal_mass /
    // (modal_mass + D_a))), the modes are S u for the eigenvectors u of S K S, whose eigenvalues
    // are the modal stiffnesses at the modal mass `modal_mass` (S = I without air: the plate
    // modes are the eigenvectors of K)
    let air = added_mass::strip(p, &phis, &psis, ARMS);
    let scale = match &air {
        Some(air) => air.modes.map(|d| Real::sqrt(modal_mass / (modal_mass + d))),
        None => DVector::from_element(nm, Dual::from(1.0)),
    };
    let problem = match &air {
        Some(_) => DMatrix::from_fn(nm, nm, |r, c| scale[r] * kr[(r, c)] * scale[c]),
        None => kr,
    };
    let (d_problem, problem) = (problem.map(|x| x.d), problem.map(|x| x.v));
    let eig = problem.symmetric_eigen();
    // The eigenpairs' derivatives, when the problem moves.
    let (d_values, d_vectors) = if d_problem.iter().any(|&x| x != 0.0) {
        symmetric_eigen_derivative(eig.eigenvalues.as_slice(), &eig.eigenvectors, &d_problem)
            .map_err(|e| format!("the clamped plate's modes: {e}"))?
    } else {
        (vec![0.0; nm], DMatrix::zeros(nm, nm))
    };
    let mut order: Vec<usize> = (0..nm).collect();
    order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
    let mut phi_mat = (DMatrix::zeros(nm, nm), DMatrix::zeros(nm, nm));
    let mut lambdas = Vec::with_capacity(nm);
    for (c, &i) in order.iter().enumerate() {
        let mut v = DVector::from_fn(nm, |r, _| {
            Dual::new(eig.eigenvectors[(r, i)], d_vectors[(r, i)]) * scale[r]
        });
        let imax = v.map(|x| x.v).iamax();
        if v[imax].v < 0.0 {
            v = v.map(|x| -x);
        }
        phi_mat.0.set_column(c, &v.map(|x| x.v));
        phi_mat.1.set_column(c, &v.map(|x| x.d));
        lambdas.push(Dual::new(eig.eigenvalues[i], d_values[i]));
    }
    let shape = |x: Dual, y: Dual| {
        DVector::from_fn(nm, |j, _| {
            beam_value(&phis[j % p.n], 0, x / a) * beam_value(&psis[j / p.n], 0, y / b)
        })
    };
    let hub = p.root == Root::Hub;
    let first = usize::from(hub);
    let n = first + nm;
    let mut mass = DMatrix::from_element(n, n, ZERO);
    let mut stiffness = DMatrix::from_element(n, n, ZERO);
    let mut damping = Vec::with_capacity(nm);
    let mut labels = Vec::with_capacity(nm);
    for c in 0..nm {
        mass[(first + c, first + c)] = modal_mass;
        stiffness[(first + c, first + c)] = lambdas[c];
        damping.push(2.0 * p.zeta * Real::sqrt(lambdas[c] * modal_mass));
        let j = phi_mat.0.column(c).iamax();
        labels.push((j % p.n + 1, j / p.n + 1));
    }
    let mut torque = DVector::from_element(n, ZERO);
    let points = p.accelerometer_points();
    let mut accelerometers = Vec::new();
    let modal = |v: DVector<Dual>| transposed_product(&phi_mat, &v);
    let embed = |hub_part: Dual, plate: DVector<Dual>| {
        let mut v = DVector::from_element(n, ZERO);
        if hub {
            v[0] = hub_part;
        }
        v.rows_mut(first, nm).copy_from(&plate);
        v
    };
    if hub {
        mass[(0, 0)] = p.i_h + ARMS * p.i_p() + air.as_ref().map_or(ZERO, |air| air.hub);
        // int int m x phi_n psi_m dx dy, both arms, and the air's
        let along: Vec<f64> = phis.iter().map(|phi| moment_integral(phi, 1)).collect();
        let across: Vec<f64> = psis.iter().map(|psi| moment_integral(psi, 0)).collect();
        let mut coupling = DVector::from_fn(nm, |j, _| {
            ARMS * mu * a * a * along[j % p.n] * b * across[j / p.n]
        });
        if let Some(air) = &air {
            coupling = coupling.zip_map(&air.coupling, |x, y| x + y);
        }
        let c = modal(coupling);
        for i in 0..nm {
            let v = if c[i].v.abs() > 1e-13 * mass[(0, 0)].v {
                c[i]
            } else {
                ZERO
            };
            mass[(0, first + i)] = v;
            mass[(first + i, 0)] = v;
        }
        torque[0] = Dual::from(1.0);
    }
    for &(x, y) in &points {
        accelerometers.push(embed(x, modal(shape(x, y))));
    }
    let forces = [
        embed(p.x1, modal(shape(p.x1, p.y1))),
        embed(p.x2, modal(shape(p.x2, p.y2))),
    ];
    let tip = embed(ZERO, modal(shape(a, b / 2.0)));
    // The clamped root bends most: the stress on its centre line.
    let stress_point = (ZERO, 0.5 * b);
    let stress = embed(
        ZERO,
        modal(super::stress_row(p, &phis, &psis, stress_point)),
    );
    let point = {
        let (phis, psis, phi_mat, (a, b, nn)) =
            (phis.clone(), psis.clone(), phi_mat.clone(), (a, b, p.n));
        move |x: Dual, y: Dual| {
            let shape = DVector::from_fn(nm, |j, _| {
                beam_value(&phis[j % nn], 0, x / a) * beam_value(&psis[j / nn], 0, y / b)
            });
            let mut v = DVector::from_element(n, ZERO);
            if hub {
                v[0] = x;
            }
            v.rows_mut(first, nm)
                .copy_from(&transposed_product(&phi_mat, &shape));
            v
        }
    };
    let model = DualModel {
        hub,
        labels,
        mass,
        stiffness,
        damping,
        torque,
        forces,
        tip,
        stress,
        stress_point: (stress_point.0.v, stress_point.1.v),
        accelerometers,
    };
    Ok((model, Box::new(point)))
}
