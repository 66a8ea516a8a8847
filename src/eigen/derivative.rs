//! Derivatives of the eigenpairs of symmetric eigenproblems along one parameter `p`, by the full
//! modal expansion (Fox and Kapoor, "Rates of change of eigenvalues and eigenvectors", AIAA
//! Journal 6(12):2426–2429, 1968; Nelson, AIAA Journal 14(9):1201–1205, 1976, for why a
//! *complete* set of vectors makes the expansion exact).
//!
//! This module knows numbers only: no physics, no FMI. The plate builds its modes from such
//! eigenproblems ([`crate::fragments::plate::modes::generalized_eigen`], the consistent
//! formulation's `symmetric_eigen`), keeping every Ritz mode, and `hsp identify`'s exact
//! sensitivities (docs/identify.md) need the modes' derivatives with respect to a parameter.
//!
//! **The generalised problem.** For symmetric `K(p)`, symmetric positive definite `M(p)` and
//! `K φᵢ = λᵢ M φᵢ`, `Φᵀ M Φ = I` (`Φ` the `n × n` matrix of *all* `n` eigenvectors),
//! differentiating gives `(K − λᵢ M) dφᵢ = −(dK − λᵢ dM) φᵢ + dλᵢ M φᵢ`. Write
//! `dφᵢ = Σⱼ cⱼᵢ φⱼ` (exact: the `φⱼ` are a basis) and multiply by `φⱼᵀ`:
//!
//! * `j = i`: `dλᵢ = φᵢᵀ (dK − λᵢ dM) φᵢ`;
//! * `j ≠ i`: `cⱼᵢ = φⱼᵀ (dK − λᵢ dM) φᵢ / (λᵢ − λⱼ)`;
//! * the normalisation `φᵢᵀ M φᵢ = 1` differentiated, `2 φᵢᵀ M dφᵢ + φᵢᵀ dM φᵢ = 0`, gives
//!   `cᵢᵢ = −½ φᵢᵀ dM φᵢ`.
//!
//! So `dΦ = Φ C`, computed from `Ck = Φᵀ dK Φ` and `Cm = Φᵀ dM Φ` alone: neither `K` nor `M` is
//! needed. The standard problem `A vᵢ = λᵢ vᵢ`, `Vᵀ V = I`, is the case `M = I`, `dM = 0`
//! ([`symmetric_eigen_derivative`]); there `C` is antisymmetric, so `dVᵀ V + Vᵀ dV = Cᵀ + C = 0`
//! holds to the last bit of the products.
//!
//! **Order and sign.** The pairs may come in any order and each vector with either sign: the
//! formulas are per pair, so the derivatives come in the same order, and flipping `φᵢ` flips
//! `dφᵢ` (and leaves every other derivative as it was). A solver's convention, such as sorting
//! ascending or making a vector's largest component positive, is constant near a point of
//! distinct eigenvalues (and no tie between two largest components), so the derivative of the
//! vectors it returns is the derivative computed here from them.
//!
//! **When it is refused** ([`MIN_RELATIVE_GAP`]): two eigenvalues closer than
//! `MIN_RELATIVE_GAP · max |λ|`. A repeated eigenvalue has no derivative of its vectors (any
//! basis of the eigenspace is one) and, taken one by one in order, not of its values either
//! (their one-sided derivatives are the eigenvalues of the restriction of `dK − λ dM` to the
//! eigenspace, Lancaster 1964); a nearly repeated one has derivatives the computed pairs do
//! not determine accurately. [`generalized_eigen_dual`] runs a solver on the values of a
//! [`Dual`]-valued pair of matrices and returns its eigenpairs with their tangents.

use nalgebra::DMatrix;

use crate::math::dual::Dual;
use crate::math::product;

/// The smallest gap between two eigenvalues, as a fraction of the spectrum's scale `max |λ|`,
/// below which the derivatives are refused.
///
/// A backward-stable symmetric eigen-solver (nalgebra's implicit QR; with a Cholesky
/// factorisation first for the generalised problem) returns the exact eigenpairs of a matrix
/// within `‖E‖ ≈ c ε max |λ|` of the one it was given (`ε = 2.2e-16`, `max |λ|` the 2-norm of
/// the symmetric matrix it works on, `L⁻¹ K L⁻ᵀ` for the generalised problem). By Davis and
/// Kahan's sin θ theorem a computed vector `φᵢ` is then off by about `‖E‖ / gapᵢ`, and the error
/// lies mostly along the vector of the nearest eigenvalue. The expansion divides by that same
/// gap: a mixing `δ` of `φᵢ` with `φⱼ` changes `dφᵢ` by about `δ ‖dφⱼ‖` and `dλᵢ` by about
/// `δ ‖dK − λ dM‖`, so the derivatives carry a *relative* error of about `ε max |λ| / gap`. At a
/// relative gap of `1e-8 ≈ √ε` that is `2e-8`: half the digits are still right, the accuracy
/// of a central difference at its best step. Closer pairs are refused (a tighter rule would turn
/// away derivatives still good to more than seven digits, a looser one would accept ones
/// dominated by round-off).
///
/// Passing this rule says nothing of the derivative's *range*: the Taylor remainder of `φᵢ(p)`
/// is of order `(h ‖dK − λ dM‖ / gap)²`, so a close pair (a crossing or veering of two modes)
/// is linear only over a step `h` small beside `gap / ‖dK − λ dM‖`.
pub const MIN_RELATIVE_GAP: f64 = 1e-8;

/// How far `Vᵀ V` (`Φᵀ M Φ` in [`generalized_eigen_dual`]) may be from the identity, the
/// largest entry of the difference, and how far `dA` from symmetric (relative to its largest
/// entry): errors of that relative size pass into the derivatives, and `1e-8` keeps them within
/// the accuracy [`MIN_RELATIVE_GAP`] allows. A solver's vectors are orthonormal to about
/// `n ε`; a miss by more is a wrong normalisation (say unit vectors for an `M`-orthonormal
/// problem), not round-off.
pub const NORMALISATION_TOLERANCE: f64 = 1e-8;

/// The derivatives `dλ` and `dV` of the eigenpairs of a symmetric matrix `A = V Λ Vᵀ` along a
/// symmetric direction `dA`: `dλᵢ = vᵢᵀ dA vᵢ`, `dvᵢ = Σ_{j≠i} vⱼ (vⱼᵀ dA vᵢ) / (λᵢ − λⱼ)`
/// (Fox and Kapoor 1968; the module's derivation with `M = I`).
///
/// `values` and the columns of `vectors` are all `n` eigenpairs of `A`, in any order, the
/// columns orthonormal (`Vᵀ V = I` within [`NORMALISATION_TOLERANCE`]); the derivatives come in
/// the same order, each `dvᵢ` orthogonal to `vᵢ` (the unit norm kept: `dVᵀ V + Vᵀ dV = 0`) and
/// with the sign of `vᵢ` (flipping `vᵢ` flips `dvᵢ`).
///
/// # Errors
///
/// When the shapes do not agree (`vectors` must be `n × n`: the expansion needs every vector),
/// an input is not finite, `vectors` is not orthonormal, `dA` is not symmetric (within
/// [`NORMALISATION_TOLERANCE`] of its largest entry), or two eigenvalues are closer than
/// [`MIN_RELATIVE_GAP`] times `max |λ|` (the message names the closest pair: indices and
/// values).
pub fn symmetric_eigen_derivative(
    values: &[f64],
    vectors: &DMatrix<f64>,
    d_a: &DMatrix<f64>,
) -> Result<(Vec<f64>, DMatrix<f64>), String> {
    let what = "symmetric_eigen_derivative";
    check_pairs(what, values, vectors)?;
    check_symmetric(what, "dA", d_a, values.len())?;
    check_identity(what, "Vᵀ V", &product(&vectors.transpose(), vectors))?;
    let c = congruence(vectors, d_a);
    Ok(expansion(values, vectors, &c, None))
}

/// The derivatives `dλ` and `dΦ` of the eigenpairs of `K φᵢ = λᵢ M φᵢ` (`K` symmetric, `M`
/// symmetric positive definite) along symmetric directions `dK`, `dM`:
/// `dλᵢ = φᵢᵀ (dK − λᵢ dM) φᵢ` and
/// `dφᵢ = Σ_{j≠i} φⱼ φⱼᵀ (dK − λᵢ dM) φᵢ / (λᵢ − λⱼ) − ½ φᵢ (φᵢᵀ dM φᵢ)` (Fox and Kapoor 1968;
/// the module's derivation).
///
/// `values` and the columns of `vectors` are all `n` eigenpairs, in any order, `M`-orthonormal
/// (`Φᵀ M Φ = I`: the caller's to ensure, `M` is not an argument; [`generalized_eigen_dual`]
/// checks it); the derivatives come in the same order, keep the `M`-normalisation
/// (`dΦᵀ M Φ + Φᵀ dM Φ + Φᵀ M dΦ = 0`) and each vector's sign.
///
/// # Errors
///
/// As [`symmetric_eigen_derivative`]: shapes, non-finite input, `dK` or `dM` not symmetric, or
/// two eigenvalues closer than [`MIN_RELATIVE_GAP`] times `max |λ|` (the closest pair named).
pub fn generalized_eigen_derivative(
    values: &[f64],
    vectors: &DMatrix<f64>,
    d_k: &DMatrix<f64>,
    d_m: &DMatrix<f64>,
) -> Result<(Vec<f64>, DMatrix<f64>), String> {
    let what = "generalized_eigen_derivative";
    check_pairs(what, values, vectors)?;
    check_symmetric(what, "dK", d_k, values.len())?;
    check_symmetric(what, "dM", d_m, values.len())?;
    let ck = congruence(vectors, d_k);
    let cm = congruence(vectors, d_m);
    Ok(expansion(values, vectors, &ck, Some(&cm)))
}

/// The eigenpairs of `K φ = λ M φ` for [`Dual`]-valued `K` and `M` (a value and a tangent along
/// one parameter in each entry): `solve` on the values, then [`generalized_eigen_derivative`]
/// along the tangents, returned as `λᵢ + dλᵢ ε` and `φ + dφ ε`.
///
/// `solve` is the solver whose eigenpairs are wanted, its order and sign convention included
/// (the plate's [`crate::fragments::plate::modes::generalized_eigen`], say): the derivatives
/// are those of its vectors. It must return all `n` pairs with `M`-orthonormal vectors, which is
/// checked (`Φᵀ M Φ = I` within [`NORMALISATION_TOLERANCE`]). The standard problem is `M = I`
/// with zero tangents.
///
/// # Errors
///
/// `solve`'s, a shape mismatch (`K` and `M` must be square and of one size), vectors that are
/// not `M`-orthonormal, and [`generalized_eigen_derivative`]'s.
pub fn generalized_eigen_dual<F>(
    k: &DMatrix<Dual>,
    m: &DMatrix<Dual>,
    solve: F,
) -> Result<(Vec<Dual>, DMatrix<Dual>), String>
where
    F: FnOnce(&DMatrix<f64>, &DMatrix<f64>) -> Result<(Vec<f64>, DMatrix<f64>), String>,
{
    let what = "generalized_eigen_dual";
    if !k.is_square() || k.shape() != m.shape() {
        return Err(format!(
            "{what}: K ({} × {}) and M ({} × {}) must be square and of one size",
            k.nrows(),
            k.ncols(),
            m.nrows(),
            m.ncols()
        ));
    }
    let (k_v, k_d) = (k.map(|x| x.v), k.map(|x| x.d));
    let (m_v, m_d) = (m.map(|x| x.v), m.map(|x| x.d));
    let (values, vectors) = solve(&k_v, &m_v)?;
    check_pairs(what, &values, &vectors)?;
    check_identity(what, "Φᵀ M Φ", &congruence(&vectors, &m_v))?;
    let (d_values, d_vectors) = generalized_eigen_derivative(&values, &vectors, &k_d, &m_d)?;
    let values = values
        .iter()
        .zip(&d_values)
        .map(|(&v, &d)| Dual::new(v, d))
        .collect();
    let vectors = vectors.zip_map(&d_vectors, Dual::new);
    Ok((values, vectors))
}

/// `Φᵀ B Φ`, symmetrised (`B` is symmetric; the two triangles of the product differ in the
/// last bits, and a symmetric `Cᵀ = C` makes the expansion's coefficients exactly
/// antisymmetric where they should be).
fn congruence(vectors: &DMatrix<f64>, b: &DMatrix<f64>) -> DMatrix<f64> {
    let c = product(&product(&vectors.transpose(), b), vectors);
    (&c + c.transpose()) * 0.5
}

/// `dλ` and `dΦ = Φ C` from `Ck = Φᵀ dK Φ` and `Cm = Φᵀ dM Φ` (`None`: `dM = 0`): the
/// module's formulas. The gaps are checked before.
fn expansion(
    values: &[f64],
    vectors: &DMatrix<f64>,
    ck: &DMatrix<f64>,
    cm: Option<&DMatrix<f64>>,
) -> (Vec<f64>, DMatrix<f64>) {
    let n = values.len();
    let cm_at = |j: usize, i: usize| cm.map_or(0.0, |cm| cm[(j, i)]);
    let d_values = (0..n)
        .map(|i| ck[(i, i)] - values[i] * cm_at(i, i))
        .collect();
    let coefficients = DMatrix::from_fn(n, n, |j, i| {
        if j == i {
            -0.5 * cm_at(i, i)
        } else {
            (ck[(j, i)] - values[i] * cm_at(j, i)) / (values[i] - values[j])
        }
    });
    (d_values, product(vectors, &coefficients))
}

/// The checks of the eigenpairs: `n` values and `n × n` vectors, all finite, no two values
/// closer than [`MIN_RELATIVE_GAP`] times the largest magnitude.
fn check_pairs(what: &str, values: &[f64], vectors: &DMatrix<f64>) -> Result<(), String> {
    let n = values.len();
    if vectors.shape() != (n, n) {
        return Err(format!(
            "{what}: {n} eigenvalues need all {n} eigenvectors as an {n} × {n} matrix (the modal \
             expansion is exact only in the full basis), got {} × {}",
            vectors.nrows(),
            vectors.ncols()
        ));
    }
    if values.iter().chain(vectors.iter()).any(|x| !x.is_finite()) {
        return Err(format!(
            "{what}: an eigenvalue or eigenvector is not finite"
        ));
    }
    let scale = values.iter().fold(0.0_f64, |s, v| s.max(v.abs()));
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| values[i].total_cmp(&values[j]));
    let closest = order
        .windows(2)
        .map(|w| (values[w[1]] - values[w[0]], w[0].min(w[1]), w[0].max(w[1])))
        .min_by(|x, y| x.0.total_cmp(&y.0));
    if let Some((gap, i, j)) = closest {
        if gap <= MIN_RELATIVE_GAP * scale {
            return Err(format!(
                "{what}: eigenvalues {i} and {j} (λ = {:e} and {:e}) are too close to \
                 differentiate: their gap {gap:e} is not above {MIN_RELATIVE_GAP:e} times the \
                 spectrum's scale max |λ| = {scale:e} (a repeated eigenvalue has no derivative \
                 of its vectors, nor of its values one by one; a nearly repeated one none that \
                 the computed pairs determine accurately)",
                values[i], values[j]
            ));
        }
    }
    Ok(())
}

/// `dA` is `n × n`, finite and symmetric within [`NORMALISATION_TOLERANCE`] of its largest
/// entry.
fn check_symmetric(what: &str, name: &str, d: &DMatrix<f64>, n: usize) -> Result<(), String> {
    if d.shape() != (n, n) {
        return Err(format!(
            "{what}: {name} is {} × {}, the eigenproblem {n} × {n}",
            d.nrows(),
            d.ncols()
        ));
    }
    if d.iter().any(|x| !x.is_finite()) {
        return Err(format!("{what}: {name} is not finite"));
    }
    let largest = d.amax();
    for i in 0..n {
        for j in 0..i {
            let skew = (d[(i, j)] - d[(j, i)]).abs();
            if skew > NORMALISATION_TOLERANCE * largest {
                return Err(format!(
                    "{what}: {name} is not symmetric: entries ({i}, {j}) and ({j}, {i}) differ \
                     by {skew:e}, its largest entry is {largest:e}"
                ));
            }
        }
    }
    Ok(())
}

/// `gram` (`Vᵀ V` or `Φᵀ M Φ`) is the identity within [`NORMALISATION_TOLERANCE`].
fn check_identity(what: &str, name: &str, gram: &DMatrix<f64>) -> Result<(), String> {
    let n = gram.nrows();
    let miss = (gram - DMatrix::identity(n, n)).amax();
    if miss > NORMALISATION_TOLERANCE {
        return Err(format!(
            "{what}: the eigenvectors are not normalised: {name} differs from the identity by \
             {miss:e} (more than {NORMALISATION_TOLERANCE:e})"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests;
