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
use super::{added_mass, PlateModel, PlateParameters, Root};

/// Number of arms described by the coordinates (antisymmetric motion of the symmetric plate).
pub const ARMS: f64 = 2.0;

/// The Ritz matrices of the plate alone (both arms) in the assumed-mode coordinates
/// `j = N (m - 1) + n`: `(M, K)`, `M = 2 m a b I`.
pub fn ritz_matrices(p: &PlateParameters) -> (DMatrix<f64>, DMatrix<f64>) {
    let (a, b, d, nu) = (p.a, p.b, p.rigidity(), p.nu);
    // The dimensionless tables of the families, scaled by the lengths of their directions.
    let scaled = |kind: BeamKind, count: usize, len: f64| {
        let tables = product_tables(kind, count);
        std::array::from_fn(|k| {
            let (i, j) = TABLE_ORDERS[k];
            DMatrix::from_fn(count, count, |r, c| {
                tables[k][(r, c)] * len.powi(1 - i as i32 - j as i32)
            })
        })
    };
    let [x00, x11, x20, x22] = scaled(BeamKind::ClampedFree, p.n, a);
    let [y00, y11, y20, y22] = scaled(BeamKind::FreeFree, p.m, b);
    let nm = p.n * p.m;
    let idx = |j: usize| (j % p.n, j / p.n);
    let mut k = DMatrix::zeros(nm, nm);
    let mut m = DMatrix::zeros(nm, nm);
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
    let k = (&k + k.transpose()) * 0.5;
    let m = (&m + m.transpose()) * 0.5;
    (m, k)
}

/// Builds the consistent formulation, with the map from a point `(x, y)` to its displacement
/// per unit coordinate (the hub's rotation `x theta` included).
pub fn build(p: &PlateParameters) -> (PlateModel, impl Fn(f64, f64) -> DVector<f64>) {
    let phis = BeamFunction::family(BeamKind::ClampedFree, p.n);
    let psis = BeamFunction::family(BeamKind::FreeFree, p.m);
    let (a, b, mu) = (p.a, p.b, p.areal_mass());
    let nm = p.n * p.m;
    let (_, kr) = ritz_matrices(p);
    let modal_mass = ARMS * mu * a * b;
    // M = modal_mass I + the air's diagonal added mass D_a: with S = diag(sqrt(modal_mass /
    // (modal_mass + D_a))), the modes are S u for the eigenvectors u of S K S, whose eigenvalues
    // are the modal stiffnesses at the modal mass `modal_mass` (S = I without air: the plate
    // modes are the eigenvectors of K)
    let air = added_mass::strip(p, &phis, &psis, ARMS);
    let scale = match &air {
        Some(air) => air.modes.map(|d| (modal_mass / (modal_mass + d)).sqrt()),
        None => DVector::from_element(nm, 1.0),
    };
    let eig = match &air {
        Some(_) => DMatrix::from_fn(nm, nm, |r, c| scale[r] * kr[(r, c)] * scale[c]),
        None => kr,
    }
    .symmetric_eigen();
    let mut order: Vec<usize> = (0..nm).collect();
    order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
    let mut phi_mat = DMatrix::zeros(nm, nm);
    let mut lambdas = Vec::with_capacity(nm);
    for (c, &i) in order.iter().enumerate() {
        let mut v = eig.eigenvectors.column(i).component_mul(&scale);
        let imax = v.iamax();
        if v[imax] < 0.0 {
            v = -v;
        }
        phi_mat.set_column(c, &v);
        lambdas.push(eig.eigenvalues[i]);
    }
    let shape = |x: f64, y: f64| {
        DVector::from_fn(nm, |j, _| {
            phis[j % p.n].value(x / a) * psis[j / p.n].value(y / b)
        })
    };
    let hub = p.root == Root::Hub;
    let first = usize::from(hub);
    let n = first + nm;
    let mut mass = DMatrix::zeros(n, n);
    let mut stiffness = DMatrix::zeros(n, n);
    let mut damping = Vec::with_capacity(nm);
    let mut labels = Vec::with_capacity(nm);
    for c in 0..nm {
        mass[(first + c, first + c)] = modal_mass;
        stiffness[(first + c, first + c)] = lambdas[c];
        damping.push(2.0 * p.zeta * (lambdas[c] * modal_mass).sqrt());
        let j = phi_mat.column(c).iamax();
        labels.push((j % p.n + 1, j / p.n + 1));
    }
    let mut torque = DVector::zeros(n);
    let points = p.accelerometer_points();
    let mut accelerometers = Vec::new();
    let modal = |v: DVector<f64>| phi_mat.transpose() * v;
    let embed = |hub_part: f64, plate: DVector<f64>| {
        let mut v = DVector::zeros(n);
        if hub {
            v[0] = hub_part;
        }
        v.rows_mut(first, nm).copy_from(&plate);
        v
    };
    if hub {
        mass[(0, 0)] = p.i_h + ARMS * p.i_p() + air.as_ref().map_or(0.0, |air| air.hub);
        // int int m x phi_n psi_m dx dy, both arms, and the air's
        let along: Vec<f64> = phis.iter().map(|phi| moment_integral(phi, 1)).collect();
        let across: Vec<f64> = psis.iter().map(|psi| moment_integral(psi, 0)).collect();
        let mut coupling = DVector::from_fn(nm, |j, _| {
            ARMS * mu * a * a * along[j % p.n] * b * across[j / p.n]
        });
        if let Some(air) = &air {
            coupling += &air.coupling;
        }
        let c = modal(coupling);
        for i in 0..nm {
            let v = if c[i].abs() > 1e-13 * mass[(0, 0)] {
                c[i]
            } else {
                0.0
            };
            mass[(0, first + i)] = v;
            mass[(first + i, 0)] = v;
        }
        torque[0] = 1.0;
    }
    for &(x, y) in &points {
        accelerometers.push(embed(x, modal(shape(x, y))));
    }
    let forces = [
        embed(p.x1, modal(shape(p.x1, p.y1))),
        embed(p.x2, modal(shape(p.x2, p.y2))),
    ];
    let tip = embed(0.0, modal(shape(a, b / 2.0)));
    // The clamped root bends most: the stress on its centre line.
    let stress_point = (0.0, 0.5 * b);
    let stress = embed(0.0, modal(super::stress_row(p, &phis, &psis, stress_point)));
    let point = {
        let (phis, psis, phi_mat, (a, b, nn)) =
            (phis.clone(), psis.clone(), phi_mat.clone(), (a, b, p.n));
        move |x: f64, y: f64| {
            let shape = DVector::from_fn(nm, |j, _| {
                phis[j % nn].value(x / a) * psis[j / nn].value(y / b)
            });
            let mut v = DVector::zeros(n);
            if hub {
                v[0] = x;
            }
            v.rows_mut(first, nm)
                .copy_from(&(phi_mat.transpose() * shape));
            v
        }
    };
    let model = PlateModel {
        hub,
        labels,
        mass,
        stiffness,
        damping_derivative: vec![0.0; damping.len()],
        damping,
        torque,
        forces,
        tip,
        stress,
        stress_point,
        accelerometers,
        drag: Vec::new(),
        dashpots: Vec::new(),
        nominal: super::PlateNominal::of(p),
    };
    (model, point)
}
