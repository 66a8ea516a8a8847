//! The eigenpairs' derivatives against sources independent of the expansion: closed forms (a
//! 2 × 2 matrix, a rotated 3 × 3 one), the differentiated defining identities on random
//! matrices, central differences of nalgebra's solver and of the plate's, the refusals, and the
//! plate's Ritz problem, whose stiffness is proportional to Young's modulus and whose mass to
//! the density.

use nalgebra::{DMatrix, DVector};

use super::*;
use crate::fragments::plate::consistent::ritz_matrices;
use crate::fragments::plate::modes::generalized_eigen;
use crate::fragments::plate::PlateParameters;
use crate::math::dual::Dual;
use crate::math::sin_cos;

#[path = "../../../tools/splitmix64.rs"]
mod splitmix64;
use splitmix64::SplitMix64;

/// An `n × n` symmetric matrix of entries uniform in [−1, 1).
fn random_symmetric(n: usize, rng: &mut SplitMix64) -> DMatrix<f64> {
    let r = DMatrix::from_fn(n, n, |_, _| 2.0 * rng.uniform() - 1.0);
    (&r + r.transpose()) * 0.5
}

/// An `n × n` symmetric positive definite matrix, its eigenvalues between ½ and about 1.5.
fn random_spd(n: usize, rng: &mut SplitMix64) -> DMatrix<f64> {
    let b = DMatrix::from_fn(n, n, |_, _| 2.0 * rng.uniform() - 1.0);
    let m = &b * b.transpose() / (2.0 * n as f64) + DMatrix::identity(n, n) * 0.5;
    (&m + m.transpose()) * 0.5
}

/// The diagonal matrix of `d`.
fn diag(d: &[f64]) -> DMatrix<f64> {
    DMatrix::from_diagonal(&DVector::from_column_slice(d))
}

/// nalgebra's eigenpairs of a symmetric `a`, ascending.
fn sorted_symmetric_eigen(a: &DMatrix<f64>) -> (Vec<f64>, DMatrix<f64>) {
    let eig = a.clone().symmetric_eigen();
    let mut order: Vec<usize> = (0..a.nrows()).collect();
    order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
    let values = order.iter().map(|&i| eig.eigenvalues[i]).collect();
    let vectors = DMatrix::from_fn(a.nrows(), a.nrows(), |r, c| eig.eigenvectors[(r, order[c])]);
    (values, vectors)
}

/// `vectors` with each column's sign flipped where it points away from `reference`'s.
fn aligned(vectors: &DMatrix<f64>, reference: &DMatrix<f64>) -> DMatrix<f64> {
    let mut v = vectors.clone();
    for c in 0..v.ncols() {
        if v.column(c).dot(&reference.column(c)) < 0.0 {
            v.column_mut(c).neg_mut();
        }
    }
    v
}

/// The largest entry of `|x − y|` over the largest of `|y|`.
fn relative_miss(x: &[f64], y: &[f64]) -> f64 {
    let scale = y.iter().fold(0.0_f64, |s, v| s.max(v.abs()));
    x.iter()
        .zip(y)
        .fold(0.0_f64, |s, (a, b)| s.max((a - b).abs()))
        / scale
}

/// `[[a, b], [b, c]](p)` with `a`, `b`, `c` linear in `p`: `λ± = (a + c)/2 ± r`,
/// `r = √(((a − c)/2)² + b²)`, `v+ = (cos θ, sin θ)`, `v− = (−sin θ, cos θ)` with
/// `θ = ½ atan2(2b, a − c)`, and their derivatives by hand:
/// `dλ± = (a' + c')/2 ± ((a − c)(a' − c')/4 + b b') / r`,
/// `θ' = ((a − c) b' − b (a' − c')) / ((a − c)² + 4 b²)`, `v±' = θ' (v∓ rotated)`.
#[test]
fn two_by_two_closed_form() {
    let (a, b, c): (f64, f64, f64) = (3.0, 1.2, -1.0);
    let (da, db, dc) = (0.7, -0.4, 1.5);
    let r = (((a - c) / 2.0) * ((a - c) / 2.0) + b * b).sqrt();
    let (lp, lm) = ((a + c) / 2.0 + r, (a + c) / 2.0 - r);
    let dr = ((a - c) * (da - dc) / 4.0 + b * db) / r;
    let (dlp, dlm) = ((da + dc) / 2.0 + dr, (da + dc) / 2.0 - dr);
    let theta = 0.5 * libm::atan2(2.0 * b, a - c);
    let dtheta = ((a - c) * db - b * (da - dc)) / ((a - c) * (a - c) + 4.0 * b * b);
    let (s, co) = sin_cos(theta);
    let m = DMatrix::from_row_slice(2, 2, &[a, b, b, c]);
    let d_m = DMatrix::from_row_slice(2, 2, &[da, db, db, dc]);
    // the hand formulas' pairs are eigenpairs
    let vectors = DMatrix::from_row_slice(2, 2, &[-s, co, co, s]);
    let residual = &m * &vectors - &vectors * diag(&[lm, lp]);
    assert!(residual.amax() < 1e-14 * r, "{residual}");

    let (dl, dv) = symmetric_eigen_derivative(&[lm, lp], &vectors, &d_m).unwrap();
    let expected = DMatrix::from_row_slice(2, 2, &[-co, -s, -s, co]) * dtheta;
    assert!(relative_miss(&dl, &[dlm, dlp]) < 1e-14, "{dl:?}");
    assert!(
        (&dv - &expected).amax() < 1e-14 * dtheta.abs(),
        "{dv} {expected}"
    );

    // the other order, v+ flipped: the derivatives follow
    let flipped = DMatrix::from_row_slice(2, 2, &[-co, -s, -s, co]);
    let (dl, dv) = symmetric_eigen_derivative(&[lp, lm], &flipped, &d_m).unwrap();
    let expected = DMatrix::from_row_slice(2, 2, &[s, -co, -co, -s]) * dtheta;
    assert!(relative_miss(&dl, &[dlp, dlm]) < 1e-14, "{dl:?}");
    assert!(
        (&dv - &expected).amax() < 1e-14 * dtheta.abs(),
        "{dv} {expected}"
    );
}

/// `A(p) = R(θ(p)) D(p) R(θ(p))ᵀ`, `R` the rotation by `θ = θ₀ + θ₁ p` about a fixed unit axis
/// `u` (Rodrigues: `R = I + sin θ U + (1 − cos θ) U²`, `U = [u]×`, so `dR/dp = θ₁ U R`) and `D`
/// diagonal, linear in `p`, its entries not sorted: the eigenvalues are `D`'s, the vectors `R`'s
/// columns, `dλ = D'` and `dV = θ₁ U R` exactly; `dA = θ₁ (U A − A U) + R D' Rᵀ` by the product
/// rule.
#[test]
fn rotated_three_by_three_closed_form() {
    let u = [1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0];
    let skew = DMatrix::from_row_slice(
        3,
        3,
        &[0.0, -u[2], u[1], u[2], 0.0, -u[0], -u[1], u[0], 0.0],
    );
    let (theta, d_theta) = (0.4, 0.9);
    let (s, c) = sin_cos(theta);
    let rot = DMatrix::identity(3, 3) + &skew * s + &skew * &skew * (1.0 - c);
    let (d, d_d) = ([3.0, 1.0, 2.0], [0.5, -2.0, 0.25]);
    let a = &rot * diag(&d) * rot.transpose();
    let d_a = (&skew * &a - &a * &skew) * d_theta + &rot * diag(&d_d) * rot.transpose();
    let d_a = (&d_a + d_a.transpose()) * 0.5;
    let (dl, dv) = symmetric_eigen_derivative(&d, &rot, &d_a).unwrap();
    assert!(relative_miss(&dl, &d_d) < 1e-14, "{dl:?}");
    let expected = &skew * &rot * d_theta;
    assert!((&dv - &expected).amax() < 1e-14, "{dv} {expected}");
}

/// `A V = V Λ` and `Vᵀ V = I` differentiated: `dA V + A dV − dV Λ − V dΛ = 0` and
/// `dVᵀ V + Vᵀ dV = 0`, exact identities the expansion must satisfy whatever its formula; on
/// random symmetric matrices in nalgebra's (unsorted) order.
#[test]
fn random_symmetric_identities() {
    let mut rng = SplitMix64(20260501);
    for n in [5, 12, 30] {
        let (a, d_a) = (random_symmetric(n, &mut rng), random_symmetric(n, &mut rng));
        let eig = a.clone().symmetric_eigen();
        let values: Vec<f64> = eig.eigenvalues.iter().copied().collect();
        let v = eig.eigenvectors;
        let (dl, dv) = symmetric_eigen_derivative(&values, &v, &d_a).unwrap();
        let lambda = DMatrix::from_diagonal(&eig.eigenvalues);
        let d_lambda = diag(&dl);
        let stationary = &d_a * &v + &a * &dv - &dv * &lambda - &v * &d_lambda;
        let scale = d_a.norm() + a.norm() * dv.norm() + dv.norm() * lambda.amax() + d_lambda.norm();
        assert!(
            stationary.norm() < 1e-10 * scale,
            "n {n}: {:e}",
            stationary.norm() / scale
        );
        let normal = dv.transpose() * &v + v.transpose() * &dv;
        assert!(
            normal.norm() < 1e-10 * dv.norm(),
            "n {n}: {:e}",
            normal.norm()
        );
    }
}

/// `K Φ = M Φ Λ` and `Φᵀ M Φ = I` differentiated:
/// `dK Φ + K dΦ − dM Φ Λ − M dΦ Λ − M Φ dΛ = 0` and `dΦᵀ M Φ + Φᵀ dM Φ + Φᵀ M dΦ = 0`, on random
/// symmetric `K`, `dK`, `dM` and a random positive definite `M`, the pairs from the plate's
/// solver.
#[test]
fn random_generalized_identities() {
    let mut rng = SplitMix64(7);
    for n in [5, 12, 30] {
        let (k, m) = (random_symmetric(n, &mut rng), random_spd(n, &mut rng));
        let (d_k, d_m) = (random_symmetric(n, &mut rng), random_symmetric(n, &mut rng));
        let (values, phi) = generalized_eigen(&k, &m).unwrap();
        let (dl, d_phi) = generalized_eigen_derivative(&values, &phi, &d_k, &d_m).unwrap();
        let lambda = diag(&values);
        let d_lambda = diag(&dl);
        let stationary = &d_k * &phi + &k * &d_phi
            - &d_m * &phi * &lambda
            - &m * &d_phi * &lambda
            - &m * &phi * &d_lambda;
        let scale = (d_k.norm() + d_m.norm() * lambda.amax()) * phi.norm()
            + (k.norm() + m.norm() * lambda.amax()) * d_phi.norm()
            + m.norm() * phi.norm() * d_lambda.norm();
        assert!(
            stationary.norm() < 1e-10 * scale,
            "n {n}: {:e}",
            stationary.norm() / scale
        );
        let normal = d_phi.transpose() * &m * &phi
            + phi.transpose() * &d_m * &phi
            + phi.transpose() * &m * &d_phi;
        let scale = 2.0 * d_phi.norm() * m.norm() * phi.norm() + d_m.norm() * phi.norm_squared();
        assert!(
            normal.norm() < 1e-10 * scale,
            "n {n}: {:e}",
            normal.norm() / scale
        );
    }
}

/// The largest miss of the central difference `(x(p + h) − x(p − h)) / 2h` of nalgebra's
/// ascending, sign-aligned eigenpairs of `a + p d_a` against `(dl, dv)`.
fn central_difference_miss(
    a: &DMatrix<f64>,
    d_a: &DMatrix<f64>,
    h: f64,
    (dl, dv): (&[f64], &DMatrix<f64>),
) -> f64 {
    let (_, v0) = sorted_symmetric_eigen(a);
    let (lp, vp) = sorted_symmetric_eigen(&(a + d_a * h));
    let (lm, vm) = sorted_symmetric_eigen(&(a - d_a * h));
    let fd_l: Vec<f64> = lp
        .iter()
        .zip(&lm)
        .map(|(p, m)| (p - m) / (2.0 * h))
        .collect();
    let fd_v = (aligned(&vp, &v0) - aligned(&vm, &v0)) / (2.0 * h);
    let miss_l = fd_l
        .iter()
        .zip(dl)
        .fold(0.0_f64, |s, (x, y)| s.max((x - y).abs()));
    miss_l.max((fd_v - dv).amax())
}

/// Against central differences of nalgebra's `symmetric_eigen`. `A = Q diag(1, …, n) Qᵀ` (unit
/// gaps, `Q` random orthogonal) and `‖dA‖_F = 1`, so each derivative of an eigenpair is of
/// order one: the difference's truncation error `h² x''' / 6` is of order `h²` and its
/// round-off `ε n / h` far below it at these steps. So the miss is under `h²` (1e-6 at
/// `h = 1e-3`) and halving `h` divides it by four (between 3.5 and 4.5): the agreement is the
/// difference's own `O(h²)`, not a fault of the expansion.
#[test]
fn central_difference_of_nalgebra() {
    let mut rng = SplitMix64(99);
    let n = 8;
    let q = DMatrix::from_fn(n, n, |_, _| 2.0 * rng.uniform() - 1.0)
        .qr()
        .q();
    let ladder = DMatrix::from_fn(n, n, |i, j| if i == j { (i + 1) as f64 } else { 0.0 });
    let a = &q * ladder * q.transpose();
    let a = (&a + a.transpose()) * 0.5;
    let d_a = random_symmetric(n, &mut rng);
    let d_a = &d_a / d_a.norm();
    let (values, vectors) = sorted_symmetric_eigen(&a);
    let (dl, dv) = symmetric_eigen_derivative(&values, &vectors, &d_a).unwrap();
    let coarse = central_difference_miss(&a, &d_a, 2e-3, (&dl, &dv));
    let fine = central_difference_miss(&a, &d_a, 1e-3, (&dl, &dv));
    assert!(fine < 1e-6, "{fine:e}");
    assert!((3.5..4.5).contains(&(coarse / fine)), "{coarse:e} {fine:e}");
}

/// A repeated eigenvalue is refused, naming the pair in the caller's order.
#[test]
fn repeated_eigenvalue_is_refused() {
    let mut rng = SplitMix64(3);
    let d_a = random_symmetric(3, &mut rng);
    let error =
        symmetric_eigen_derivative(&[2.0, 1.0, 2.0], &DMatrix::identity(3, 3), &d_a).unwrap_err();
    assert!(
        error.contains("eigenvalues 0 and 2 (λ = 2e0 and 2e0)"),
        "{error}"
    );
    let error = generalized_eigen_derivative(
        &[2.0, 1.0, 2.0],
        &DMatrix::identity(3, 3),
        &d_a,
        &DMatrix::zeros(3, 3),
    )
    .unwrap_err();
    assert!(error.contains("eigenvalues 0 and 2"), "{error}");
}

/// The rule: a gap not above `MIN_RELATIVE_GAP · max |λ|` is refused, a wider one accepted.
#[test]
fn close_eigenvalues_are_refused_by_the_relative_gap_rule() {
    let mut rng = SplitMix64(4);
    let d_a = random_symmetric(3, &mut rng);
    let v = DMatrix::identity(3, 3);
    let at = |gap: f64| symmetric_eigen_derivative(&[3.0, 1.0, 1.0 + gap], &v, &d_a);
    // the threshold is 3e-8 here
    let error = at(2e-8).unwrap_err();
    assert!(error.contains("eigenvalues 1 and 2"), "{error}");
    assert!(error.contains("max |λ| = 3e0"), "{error}");
    let (_, dv) = at(4e-8).unwrap();
    // the pair's coupling over its gap, as the expansion says
    assert!((dv[(2, 1)] - d_a[(2, 1)] / -4e-8).abs() < 1e-6 * dv[(2, 1)].abs());
    assert!(symmetric_eigen_derivative(
        &[0.0, 0.0],
        &DMatrix::identity(2, 2),
        &d_a.view((0, 0), (2, 2)).into_owned()
    )
    .is_err());
}

/// What is not an eigen-decomposition of the promised kind is refused with a reason.
#[test]
fn malformed_input_is_refused() {
    let mut rng = SplitMix64(5);
    let d_a = random_symmetric(3, &mut rng);
    let v = DMatrix::identity(3, 3);
    let values = [1.0, 2.0, 3.0];
    let refusal = |values: &[f64], v: &DMatrix<f64>, d_a: &DMatrix<f64>| {
        symmetric_eigen_derivative(values, v, d_a).unwrap_err()
    };
    assert!(refusal(&values, &v.columns(0, 2).into_owned(), &d_a).contains("all 3 eigenvectors"));
    assert!(refusal(&values, &(&v * 2.0), &d_a).contains("not normalised"));
    let mut skew = d_a.clone();
    skew[(0, 1)] += 1e-3;
    assert!(refusal(&values, &v, &skew).contains("not symmetric"));
    assert!(refusal(&[1.0, f64::NAN, 3.0], &v, &d_a).contains("not finite"));
    assert!(refusal(&values, &v, &DMatrix::zeros(2, 2)).contains("dA is 2 × 2"));
}

/// The Dual helper: values bit for bit those of the solver, tangents those of central
/// differences of the solver (`h = 1e-5`: truncation about `h² / gap³`, round-off
/// `ε / (h gap)`, both below 1e-7 for these gaps).
#[test]
fn dual_helper_follows_the_solver() {
    let mut rng = SplitMix64(11);
    let n = 6;
    let (k, m) = (random_symmetric(n, &mut rng), random_spd(n, &mut rng));
    let (d_k, d_m) = (
        random_symmetric(n, &mut rng),
        random_symmetric(n, &mut rng) * 0.1,
    );
    let k_dual = k.zip_map(&d_k, Dual::new);
    let m_dual = m.zip_map(&m.zip_map(&d_m, |_, d| d), Dual::new);
    let (values, vectors) = generalized_eigen_dual(&k_dual, &m_dual, generalized_eigen).unwrap();
    let (v0, phi0) = generalized_eigen(&k, &m).unwrap();
    assert!(values.iter().zip(&v0).all(|(x, y)| x.v == *y));
    assert_eq!(vectors.map(|x| x.v), phi0);

    let h = 1e-5;
    let (vp, pp) = generalized_eigen(&(&k + &d_k * h), &(&m + &d_m * h)).unwrap();
    let (vm, pm) = generalized_eigen(&(&k - &d_k * h), &(&m - &d_m * h)).unwrap();
    let fd_l: Vec<f64> = vp
        .iter()
        .zip(&vm)
        .map(|(p, m)| (p - m) / (2.0 * h))
        .collect();
    let dl: Vec<f64> = values.iter().map(|x| x.d).collect();
    assert!(
        relative_miss(&dl, &fd_l) < 1e-7,
        "{:e}",
        relative_miss(&dl, &fd_l)
    );
    let fd_v = (aligned(&pp, &phi0) - aligned(&pm, &phi0)) / (2.0 * h);
    let dv = vectors.map(|x| x.d);
    assert!(
        (&dv - &fd_v).amax() < 1e-7 * fd_v.amax(),
        "{:e}",
        (&dv - &fd_v).amax()
    );

    // a solver whose vectors are unit, not M-orthonormal, is caught
    let unit = |k: &DMatrix<f64>, _: &DMatrix<f64>| Ok(sorted_symmetric_eigen(k));
    let twice = m_dual.map(|x| Dual::new(2.0 * x.v, x.d));
    let error = generalized_eigen_dual(&k_dual, &twice, unit).unwrap_err();
    assert!(error.contains("not normalised"), "{error}");
}

/// The default plate's Ritz problem (the consistent formulation's assumed modes, both arms).
fn plate() -> (PlateParameters, DMatrix<f64>, DMatrix<f64>) {
    // no air: `ritz_matrices` is the plate alone anyway (the air's added mass joins in
    // `consistent::build`), so `M` is proportional to ρ
    let p = PlateParameters {
        ca: 0.0,
        ..PlateParameters::default()
    };
    let (m, k) = ritz_matrices(&p);
    (p, m, k)
}

/// Along Young's modulus `E`: `K ∝ E` (checked on `ritz_matrices` itself), `M` independent of
/// it, so `λ ∝ E` and the vectors do not move: `dλ = λ / E`, `dφ = 0`. The same for the
/// consistent formulation's standard problem (`symmetric_eigen` of `K`, unit vectors), and
/// through the Dual helper.
#[test]
fn plate_ritz_derivative_along_young_modulus() {
    let (p, m, k) = plate();
    let (m2, k2) = ritz_matrices(&PlateParameters { e: 2.0 * p.e, ..p });
    assert!((&k2 - &k * 2.0).amax() < 1e-15 * k.amax() && m2 == m);
    let d_k = &k / p.e;
    let (values, phi) = generalized_eigen(&k, &m).unwrap();
    let (dl, d_phi) =
        generalized_eigen_derivative(&values, &phi, &d_k, &DMatrix::zeros(k.nrows(), k.nrows()))
            .unwrap();
    let expected: Vec<f64> = values.iter().map(|l| l / p.e).collect();
    assert!(relative_miss(&dl, &expected) < 1e-12, "{dl:?}");
    // round-off: `ε max λ` in `φⱼᵀ dK φᵢ` over the closest gap, 2e-6 of `max λ`
    // (default_plate_eigenvalue_spacing), about 1e-10 relative at the worst
    assert!(
        d_phi.amax() < 1e-9 * phi.amax() / p.e,
        "{:e}",
        d_phi.amax() * p.e
    );

    let (values, v) = sorted_symmetric_eigen(&k);
    let (dl, dv) = symmetric_eigen_derivative(&values, &v, &d_k).unwrap();
    let expected: Vec<f64> = values.iter().map(|l| l / p.e).collect();
    assert!(relative_miss(&dl, &expected) < 1e-12, "{dl:?}");
    assert!(dv.amax() < 1e-9 / p.e, "{:e}", dv.amax() * p.e);

    let k_dual = k.zip_map(&d_k, Dual::new);
    let m_dual = m.map(Dual::from);
    let (values, phi) = generalized_eigen_dual(&k_dual, &m_dual, generalized_eigen).unwrap();
    let dl: Vec<f64> = values.iter().map(|x| x.d).collect();
    let expected: Vec<f64> = values.iter().map(|x| x.v / p.e).collect();
    assert!(relative_miss(&dl, &expected) < 1e-12, "{dl:?}");
    assert!(phi.map(|x| x.d).amax() < 1e-9 * phi.map(|x| x.v).amax() / p.e);
}

/// Along the density `ρ`: `M ∝ ρ` (checked on `ritz_matrices`), `K` independent of it, so
/// `λ ∝ 1/ρ` and `φ ∝ 1/√ρ` (the `M`-normalisation): `dλ = −λ / ρ`, `dφ = −φ / (2ρ)`.
#[test]
fn plate_ritz_derivative_along_density() {
    let (p, m, k) = plate();
    let (m2, k2) = ritz_matrices(&PlateParameters {
        rho: 2.0 * p.rho,
        ..p
    });
    assert!((&m2 - &m * 2.0).amax() < 1e-15 * m.amax() && k2 == k);
    let d_m = &m / p.rho;
    let (values, phi) = generalized_eigen(&k, &m).unwrap();
    let (dl, d_phi) =
        generalized_eigen_derivative(&values, &phi, &DMatrix::zeros(k.nrows(), k.nrows()), &d_m)
            .unwrap();
    let expected: Vec<f64> = values.iter().map(|l| -l / p.rho).collect();
    assert!(relative_miss(&dl, &expected) < 1e-12, "{dl:?}");
    let expected = &phi / (-2.0 * p.rho);
    assert!((&d_phi - &expected).amax() < 1e-10 * expected.amax());
}

/// The default plate's eigenvalue spacing: the closest pair of the Ritz problem is modes 1 and 2
/// (ascending, from 0), the second bending mode (2, 1) and the first torsion mode (1, 2),
/// 6.854 and 6.875 Hz, 0.6 % apart in `λ = ω²` but only 2e-6 of the spectrum's scale
/// (`λ` of the 381 Hz mode): two hundred times [`MIN_RELATIVE_GAP`], so its derivatives are
/// accepted. The two are of the two symmetry classes across the width (`m` odd and even), which
/// `K` does not couple: a parameter that moves bending and torsion apart (`b`, `ν`) can make
/// them cross, where the ascending order swaps them.
#[test]
fn default_plate_eigenvalue_spacing() {
    let (_, m, k) = plate();
    let (values, _) = generalized_eigen(&k, &m).unwrap();
    let scale = values.iter().fold(0.0_f64, |s, v| s.max(v.abs()));
    let (gap, i) = (1..values.len())
        .map(|i| ((values[i] - values[i - 1]) / scale, i))
        .min_by(|x, y| x.0.total_cmp(&y.0))
        .unwrap();
    let hz = |l: f64| l.sqrt() / (2.0 * std::f64::consts::PI);
    assert_eq!(i, 2, "closest pair {} and {i}", i - 1);
    assert!((hz(values[1]) - 6.854).abs() < 1e-3 && (hz(values[2]) - 6.875).abs() < 1e-3);
    assert!((1e-6..1e-5).contains(&gap), "{gap:e}");
    assert!(gap > 100.0 * MIN_RELATIVE_GAP);
}
