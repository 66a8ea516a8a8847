//! Natural frequencies of a plate model (eq. 14): `K v = omega^2 M v`, solved as a symmetric
//! generalised eigenproblem (Cholesky `M = L L'`, symmetric eigen-solver on `L^-1 K L^-T`,
//! nalgebra). Rigid-body modes (the free hub's rotation, `omega = 0`) are left out.

use nalgebra::DMatrix;

use super::PlateModel;

/// A natural mode: frequency and the `(n, m)` label of its dominant plate coordinate.
#[derive(Clone, Debug, PartialEq)]
pub struct NaturalMode {
    /// Frequency \[Hz\].
    pub f_hz: f64,
    /// `(n, m)` of the plate coordinate with the largest share of the mode's kinetic energy.
    pub label: (usize, usize),
}

/// Eigenvalues `omega^2` (ascending) and `M`-orthonormal eigenvectors of `K v = omega^2 M v`;
/// an error when `M` is not numerically positive definite or the result is not finite.
pub fn generalized_eigen(
    k: &DMatrix<f64>,
    m: &DMatrix<f64>,
) -> Result<(Vec<f64>, DMatrix<f64>), String> {
    let l = m
        .clone()
        .cholesky()
        .ok_or("the plate's mass matrix is not numerically positive definite")?
        .l();
    let linv = l
        .clone()
        .try_inverse()
        .ok_or("the Cholesky factor of the plate's mass matrix is singular")?;
    let a = crate::math::product(&crate::math::product(&linv, k), &linv.transpose());
    let a = (&a + a.transpose()) * 0.5;
    let eig = a.symmetric_eigen();
    let n = k.nrows();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
    let vals: Vec<f64> = order.iter().map(|&i| eig.eigenvalues[i]).collect();
    let mut vecs = DMatrix::zeros(n, n);
    for (c, &i) in order.iter().enumerate() {
        vecs.set_column(c, &(linv.transpose() * eig.eigenvectors.column(i)));
    }
    if vals.iter().chain(vecs.iter()).any(|v: &f64| !v.is_finite()) {
        return Err("the plate's natural modes are not finite".into());
    }
    Ok((vals, vecs))
}

/// The elastic natural modes of a plate model, ascending; an error instead of a panic when the
/// eigenproblem is degenerate (parameters are validated before, so this is a last guard).
pub fn natural_modes(model: &PlateModel) -> Result<Vec<NaturalMode>, String> {
    let (vals, vecs) = generalized_eigen(&model.stiffness, &model.mass)?;
    let scale = vals.iter().fold(0.0f64, |s, v| s.max(v.abs()));
    let first = model.first_plate();
    let mut out = Vec::new();
    for (c, &w2) in vals.iter().enumerate() {
        if w2 <= 1e-10 * scale {
            continue; // rigid-body mode of the free hub
        }
        let v = vecs.column(c);
        let mut best = (0.0, 0);
        for j in first..model.dim() {
            let e = v[j] * v[j] * model.mass[(j, j)];
            if e > best.0 {
                best = (e, j);
            }
        }
        let label = best
            .1
            .checked_sub(first)
            .and_then(|j| model.labels.get(j))
            .ok_or("a natural mode of the plate has no plate coordinate with kinetic energy")?;
        out.push(NaturalMode {
            f_hz: w2.sqrt() / (2.0 * std::f64::consts::PI),
            label: *label,
        });
    }
    Ok(out)
}
