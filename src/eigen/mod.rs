//! Eigenvalues of a real square matrix, balanced first, as LAPACK's `dgeev` computes them.
//!
//! This module knows numbers only: no FMI, no physics. It exists because the linearised model's
//! `A` is badly scaled: in SI units a pressure's row holds entries of 1e11 beside an angle's of
//! 1 and a few of 1e-12. The implicit double-shift QR iteration behind nalgebra's
//! `complex_eigenvalues` makes errors of the order of the machine epsilon times the norm of the
//! matrix it is given, which on such an `A` is as large as the slow pairs' real parts: it gets
//! them wrong in the second or third digit. LAPACK's `dgeev` first *balances* the matrix
//! (`dgebal`), and so does [`eigenvalues`]:
//!
//! 1. **Isolation** ([`isolate`]). A column that is zero off the diagonal makes its diagonal
//!    entry an eigenvalue (`A e_j = a_jj e_j`), and so does a row that is zero off the diagonal
//!    (`e_iᵀ A = a_ii e_iᵀ`). Deleting that row and column leaves a matrix with the remaining
//!    eigenvalues (permuted, `A` is block triangular with that 1 × 1 block on the diagonal). The
//!    search repeats on what is left until no such row or column remains. The isolated
//!    eigenvalues are exact: the model's free integrators (e.g. the hub angle with the hub free,
//!    an exactly zero column of `A`) come out as exact zeros, not as round-off of the largest
//!    eigenvalue. `dgebal` does the same by permuting those rows and columns to the ends.
//! 2. **Scaling** ([`balance`]). The rest is replaced by `D⁻¹ A D`, `D` diagonal with powers of
//!    two, chosen so that each row and its column have norms of the same size. The similarity
//!    has the same eigenvalues, and multiplying by a power of two is exact in floating point, so
//!    the balanced matrix is the same matrix to the last bit, only with a norm closer to its
//!    eigenvalues. This is the algorithm of Parlett and Reinsch ("Balancing a matrix for
//!    calculation of eigenvalues and eigenvectors", Numer. Math. 13:293–304, 1969), as LAPACK's
//!    `dgebal` implements it since version 3.5.0 (row and column 2-norms including the diagonal,
//!    as James, Langou and Lowery recommended in 2014, and the same guards against over- and
//!    underflow).
//! 3. **QR.** nalgebra's real Schur decomposition of the balanced matrix (Hessenberg reduction,
//!    implicit double-shift QR), with an iteration limit: a matrix on which it does not converge
//!    gives NaN eigenvalues rather than an endless loop.
//!
//! On the complete model's `A` (45 states) this takes the slow pairs' real parts from errors of
//! 0.6 to 2 % to agreement with a 40-digit computation to better than 1e-4 in every part of every
//! eigenvalue (`tests/python/test_eigenvalues_precision.py`).
//!
//! [`Mode`] gives an eigenvalue's natural frequency and damping ratio, and [`least_damped`] the
//! least damped mode of a spectrum, skipping the zero eigenvalues of rigid-body and integrator
//! states.
//!
//! [`derivative`] differentiates the eigenpairs of symmetric (and symmetric generalised)
//! eigenproblems along a parameter, for the plate's modes' sensitivities.
//!
//! Everything here is IEEE arithmetic (sums, products, quotients and `sqrt`, each correctly
//! rounded) and nalgebra's decomposition, whose scalar functions come from the `libm` crate
//! ([`crate::math`]): the same doubles on every platform.

pub mod derivative;

use nalgebra::{Complex, DMatrix, Schur};

/// The radix of the scaling: `D`'s entries are powers of two, so scaling is exact.
const RADIX: f64 = 2.0;

/// A row and column pair is rescaled only if that lowers the sum of their norms below this
/// fraction of what it was (`dgebal`'s `FACTOR`): the iteration stops when no pair improves by
/// 5 %.
const FACTOR: f64 = 0.95;

/// The smallest scale factor that keeps `1 / f` finite with room for the matrix's entries:
/// `dgebal`'s `SFMIN1`, the safe minimum over the precision.
const SFMIN1: f64 = f64::MIN_POSITIVE / f64::EPSILON;
const SFMAX1: f64 = 1.0 / SFMIN1;
const SFMIN2: f64 = SFMIN1 * RADIX;
const SFMAX2: f64 = 1.0 / SFMIN2;

/// The 2-norm of `values`, accumulated as a scaled sum of squares (the reference BLAS `dnrm2`'s
/// way), so that no square over- or underflows.
fn norm2(values: impl Iterator<Item = f64>) -> f64 {
    let (mut scale, mut ssq) = (0.0_f64, 1.0_f64);
    for x in values {
        let ax = x.abs();
        if ax == 0.0 {
            continue;
        }
        if scale < ax {
            let q = scale / ax;
            ssq = 1.0 + ssq * q * q;
            scale = ax;
        } else {
            let q = ax / scale;
            ssq += q * q;
        }
    }
    scale * ssq.sqrt()
}

/// The largest absolute value of `values` (0 if there are none).
fn max_abs(values: impl Iterator<Item = f64>) -> f64 {
    values.fold(0.0, |m, x| m.max(x.abs()))
}

/// Balances `a` in place: replaces it by `D⁻¹ A D` and returns the diagonal of `D`, each entry a
/// power of two, so that `balanced[(i, j)] == a[(i, j)] * d[j] / d[i]` exactly.
///
/// The algorithm of Parlett and Reinsch (1969) as LAPACK's `dgebal` runs it (job `'S'`, scaling
/// only): sweep over the indices; for each `i` with `c` the 2-norm of column `i` and `r` that of
/// row `i` (diagonal included), find the power of two `f` that brings `c f` and `r / f` within a
/// factor of two of each other, and apply it (multiply column `i` by `f`, row `i` by `1 / f`)
/// only if it lowers `c + r` below 0.95 of what it was and keeps `d[i]` and the entries clear
/// of over- and underflow. Sweep again until a sweep changes nothing. A row or column that is
/// zero is left alone (its index is one that [`isolate`] takes out).
///
/// A matrix with a NaN or infinite entry is left as it is (all of `d` 1).
///
/// # Panics
///
/// If `a` is not square.
pub fn balance(a: &mut DMatrix<f64>) -> Vec<f64> {
    assert!(a.is_square(), "balance: the matrix is not square");
    let n = a.nrows();
    let mut d = vec![1.0; n];
    if a.iter().any(|x| !x.is_finite()) {
        return d;
    }
    let mut changed = true;
    while changed {
        changed = false;
        for (i, di) in d.iter_mut().enumerate() {
            let mut c = norm2(a.column(i).iter().copied());
            let mut r = norm2(a.row(i).iter().copied());
            let mut ca = max_abs(a.column(i).iter().copied());
            let mut ra = max_abs(a.row(i).iter().copied());
            if c == 0.0 || r == 0.0 {
                continue;
            }
            let s = c + r;
            let mut f = 1.0_f64;
            let mut g = r / RADIX;
            while c < g && f.max(c).max(ca) < SFMAX2 && r.min(g).min(ra) > SFMIN2 {
                f *= RADIX;
                c *= RADIX;
                ca *= RADIX;
                r /= RADIX;
                g /= RADIX;
                ra /= RADIX;
            }
            g = c / RADIX;
            while g >= r && r.max(ra) < SFMAX2 && f.min(c).min(g).min(ca) > SFMIN2 {
                f /= RADIX;
                c /= RADIX;
                g /= RADIX;
                ca /= RADIX;
                r *= RADIX;
                ra *= RADIX;
            }
            if c + r >= FACTOR * s {
                continue;
            }
            if f < 1.0 && *di < 1.0 && f * *di <= SFMIN1 {
                continue;
            }
            if f > 1.0 && *di > 1.0 && *di >= SFMAX1 / f {
                continue;
            }
            *di *= f;
            changed = true;
            let g = 1.0 / f;
            a.row_mut(i).iter_mut().for_each(|x| *x *= g);
            a.column_mut(i).iter_mut().for_each(|x| *x *= f);
        }
    }
    d
}

/// The eigenvalues that rows and columns zero off the diagonal isolate, and the indices of the
/// rows and columns left, in increasing order.
///
/// Repeatedly, on the rows and columns not yet taken out: a row `i` whose entries off the
/// diagonal are all zero, else a column `j` whose entries off the diagonal are all zero, is taken
/// out and its diagonal entry is an eigenvalue (rows are searched first and from the last, as
/// `dgebal` does). The eigenvalues of the submatrix of `a` on the indices left are the other
/// eigenvalues of `a`: taking out such a row or column is a block-triangular deflation. The
/// isolated eigenvalues are `a`'s diagonal entries, exactly, in the order they were found.
///
/// # Panics
///
/// If `a` is not square.
pub fn isolate(a: &DMatrix<f64>) -> (Vec<f64>, Vec<usize>) {
    assert!(a.is_square(), "isolate: the matrix is not square");
    let mut left: Vec<usize> = (0..a.nrows()).collect();
    let mut isolated = Vec::new();
    loop {
        let zero_off_diagonal = |k: usize, entry: &dyn Fn(usize) -> f64| {
            left.iter().all(|&m| m == k || entry(m) == 0.0)
        };
        let found = left
            .iter()
            .rposition(|&i| zero_off_diagonal(i, &|j| a[(i, j)]))
            .or_else(|| {
                left.iter()
                    .position(|&j| zero_off_diagonal(j, &|i| a[(i, j)]))
            });
        match found {
            Some(at) => {
                let k = left.remove(at);
                isolated.push(a[(k, k)]);
            }
            None => return (isolated, left),
        }
    }
}

/// The eigenvalues of `a`, as LAPACK's `dgeev` would find them: the eigenvalues that rows and
/// columns zero off the diagonal isolate ([`isolate`], exact), then those of the rest, balanced
/// ([`balance`]), from nalgebra's real Schur decomposition.
///
/// Order: by real part, largest first (the least stable first), then by imaginary part, largest
/// first, so that a complex pair comes as `re + im j`, `re − im j`. The members of a pair are
/// exact conjugates (both come from one 2 × 2 block of the Schur form), and a zero part is
/// `+0.0`, never `−0.0`.
///
/// All `n` eigenvalues are NaN if `a` has a NaN or infinite entry, or if the QR iteration does
/// not converge within LAPACK's `dlahqr` limit of 30 iterations per eigenvalue (at least 300).
///
/// # Panics
///
/// If `a` is not square.
pub fn eigenvalues(a: &DMatrix<f64>) -> Vec<Complex<f64>> {
    assert!(a.is_square(), "eigenvalues: the matrix is not square");
    let n = a.nrows();
    let failed = || vec![Complex::new(f64::NAN, f64::NAN); n];
    if a.iter().any(|x| !x.is_finite()) {
        return failed();
    }
    let (isolated, left) = isolate(a);
    let mut ev: Vec<Complex<f64>> = isolated.iter().map(|&x| Complex::new(x, 0.0)).collect();
    if !left.is_empty() {
        let m = left.len();
        let mut b = DMatrix::from_fn(m, m, |i, j| a[(left[i], left[j])]);
        balance(&mut b);
        match Schur::try_new(b, f64::EPSILON, 30 * m.max(10)) {
            Some(schur) => ev.extend(schur.complex_eigenvalues().iter()),
            None => return failed(),
        }
    }
    // x + 0.0 is +0.0 for x = -0.0 and x for every other x.
    for z in &mut ev {
        *z = Complex::new(z.re + 0.0, z.im + 0.0);
    }
    ev.sort_by(|x, y| y.re.total_cmp(&x.re).then(y.im.total_cmp(&x.im)));
    ev
}

/// `|z|`, as `sqrt(re² + im²)` (correctly rounded operations, the same on every platform;
/// overflows only for `|z|` beyond 1e154).
pub fn modulus(z: Complex<f64>) -> f64 {
    (z.re * z.re + z.im * z.im).sqrt()
}

/// An eigenvalue `λ` as a mode: its natural frequency `|λ|` and damping ratio `−Re λ / |λ|`
/// (`λ = −ζ ω ± ω √(1 − ζ²) j` for a pair of a second-order system).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mode {
    /// The eigenvalue (1/s).
    pub eigenvalue: Complex<f64>,
    /// The natural frequency `ω = |λ|` (rad/s).
    pub omega: f64,
    /// The damping ratio `ζ = −Re λ / |λ|`: 1 for a stable real eigenvalue, −1 for an unstable
    /// one, between 0 and 1 for a stable pair, negative for an unstable pair; 0 for `λ = 0`
    /// (an integrator neither decays nor grows).
    pub zeta: f64,
}

impl Mode {
    /// The mode of eigenvalue `eigenvalue`.
    pub fn new(eigenvalue: Complex<f64>) -> Mode {
        let omega = modulus(eigenvalue);
        let zeta = if omega == 0.0 {
            0.0
        } else {
            -eigenvalue.re / omega
        };
        Mode {
            eigenvalue,
            omega,
            zeta,
        }
    }

    /// The natural frequency in Hz, `|λ| / 2π`.
    pub fn frequency_hz(&self) -> f64 {
        self.omega / (2.0 * std::f64::consts::PI)
    }
}

/// The least damped mode of the eigenvalues `ev` (smallest damping ratio; of a pair, the member
/// with the positive imaginary part), leaving out the eigenvalues of modulus below `skip_below`
/// (the zeros of rigid-body and integrator states, which are not modes). Of modes with the same
/// damping ratio, the first in `ev`'s order.
///
/// `None` if no eigenvalue is left. If any eigenvalue is NaN (the result of [`eigenvalues`] that
/// failed), that one: a damping ratio NaN, not a margin computed from part of the spectrum.
pub fn least_damped(ev: &[Complex<f64>], skip_below: f64) -> Option<Mode> {
    if let Some(&z) = ev.iter().find(|z| z.re.is_nan() || z.im.is_nan()) {
        return Some(Mode::new(z));
    }
    ev.iter()
        .filter(|z| z.im >= 0.0 && modulus(**z) >= skip_below)
        .map(|&z| Mode::new(z))
        .reduce(|best, m| if m.zeta < best.zeta { m } else { best })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Sylvester–Hadamard matrix of order 16 over 4: symmetric, orthogonal, and its own
    /// inverse, with entries ±1/4, so that `H T H` is exact for a `T` of small dyadic entries.
    fn hadamard16() -> DMatrix<f64> {
        DMatrix::from_fn(16, 16, |i, j| {
            if (i & j).count_ones() % 2 == 0 {
                0.25
            } else {
                -0.25
            }
        })
    }

    /// The known eigenvalues of [`badly_scaled`]: five pairs and six reals, from 0.125 to 96 in
    /// modulus, all of them dyadic.
    fn known() -> Vec<Complex<f64>> {
        let mut ev: Vec<Complex<f64>> = Vec::new();
        for (re, im) in [
            (-0.125, 6.0),
            (-0.25, 20.5),
            (-1.0, 44.0),
            (-3.5, 0.75),
            (-12.0, 96.0),
        ] {
            ev.push(Complex::new(re, im));
            ev.push(Complex::new(re, -im));
        }
        for re in [-0.5, -2.0, -7.25, -30.0, -64.0, 1.5] {
            ev.push(Complex::new(re, 0.0));
        }
        ev.sort_by(|x, y| y.re.total_cmp(&x.re).then(y.im.total_cmp(&x.im)));
        ev
    }

    /// `D H T H D⁻¹`, exactly: `T` block diagonal with the pairs of [`known`] as 2 × 2 blocks
    /// `[[re, im], [−im, re]]` and its reals on the diagonal, `H` [`hadamard16`] (so `H T H`, a
    /// normal matrix with these eigenvalues, is dense, and its entries are sums of `±T_kl / 16`,
    /// exact), `D` diagonal with powers of two from 2^−27 to 2^27 (7e-9 to 1.3e8), in a scrambled
    /// order. The entries span 1e-16 to 1e16 times those of `H T H`.
    fn badly_scaled() -> (DMatrix<f64>, Vec<f64>) {
        let mut t = DMatrix::zeros(16, 16);
        let pairs: Vec<Complex<f64>> = known().into_iter().filter(|z| z.im > 0.0).collect();
        for (k, z) in pairs.iter().enumerate() {
            let b = 2 * k;
            t[(b, b)] = z.re;
            t[(b + 1, b + 1)] = z.re;
            t[(b, b + 1)] = z.im;
            t[(b + 1, b)] = -z.im;
        }
        let reals: Vec<f64> = known()
            .into_iter()
            .filter(|z| z.im == 0.0)
            .map(|z| z.re)
            .collect();
        for (k, re) in reals.iter().enumerate() {
            t[(10 + k, 10 + k)] = *re;
        }
        let h = hadamard16();
        let a0 = crate::math::product(&crate::math::product(&h, &t), &h);
        let exponents = [
            27, -20, 3, -27, 14, -9, 21, 0, -14, 9, -3, 18, -24, 6, 24, -18,
        ];
        let d: Vec<f64> = exponents.iter().map(|&e| 2f64.powi(e)).collect();
        let a = DMatrix::from_fn(16, 16, |i, j| a0[(i, j)] * d[i] / d[j]);
        (a, d)
    }

    /// The largest relative distance from a known eigenvalue to the nearest computed one.
    fn worst_error(computed: &[Complex<f64>], known: &[Complex<f64>]) -> f64 {
        known
            .iter()
            .map(|k| {
                computed
                    .iter()
                    .map(|c| modulus(c - k) / modulus(*k))
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn balancing_recovers_the_eigenvalues_of_a_badly_scaled_matrix() {
        let (a, _) = badly_scaled();
        let want = known();
        // nalgebra's QR on the unbalanced matrix: errors of the order of eps times its norm
        // (measured: 0.91 of |λ|, balanced 7e-15).
        let unbalanced: Vec<Complex<f64>> = Schur::try_new(a.clone(), f64::EPSILON, 3000)
            .map(|s| s.complex_eigenvalues().iter().copied().collect())
            .unwrap_or_default();
        let before = if unbalanced.len() == 16 {
            worst_error(&unbalanced, &want)
        } else {
            f64::INFINITY
        };
        let ev = eigenvalues(&a);
        let after = worst_error(&ev, &want);
        println!("worst relative error: unbalanced {before:e}, balanced {after:e}");
        assert!(before > 1e-3, "unbalanced: {before:e}");
        assert!(after < 1e-12, "balanced: {after:e}: {ev:?}");
        // In the documented order, each part to 1e-12 of |λ|.
        assert_eq!(ev.len(), 16);
        for (z, k) in ev.iter().zip(&want) {
            assert!(modulus(z - k) < 1e-12 * modulus(*k), "{z} vs {k}");
        }
    }

    #[test]
    fn scaling_is_exact_and_by_powers_of_two() {
        let (a, d0) = badly_scaled();
        let mut b = a.clone();
        let d = balance(&mut b);
        for &x in &d {
            // A power of two: no mantissa bits.
            assert_eq!(x.to_bits() & ((1u64 << 52) - 1), 0, "{x}");
        }
        for i in 0..16 {
            for j in 0..16 {
                assert_eq!(b[(i, j)], a[(i, j)] * d[j] / d[i], "({i}, {j})");
            }
        }
        // The balancing undoes the scrambling: H T H's rows and columns have norms of the same
        // size, and D is D0 exactly, up to a constant factor (4).
        let exponent = |x: f64| ((x.to_bits() >> 52) & 0x7ff) as i32 - 1023;
        let e: Vec<i32> = (0..16).map(|i| exponent(d[i] / d0[i])).collect();
        assert!(e.iter().all(|&k| k == e[0]), "log2(D / D0) = {e:?}");
        let norm = |m: &DMatrix<f64>| norm2(m.iter().copied());
        assert!(norm(&b) < 1e-12 * norm(&a), "{} vs {}", norm(&b), norm(&a));
    }

    #[test]
    fn a_balanced_matrix_is_left_alone() {
        let a = DMatrix::from_row_slice(3, 3, &[1.0, 2.0, 0.5, -1.0, 3.0, 2.0, 0.5, -2.0, 1.0]);
        let mut b = a.clone();
        assert_eq!(balance(&mut b), vec![1.0; 3]);
        assert_eq!(a, b);
    }

    #[test]
    fn zero_columns_and_rows_give_exact_eigenvalues() {
        // Column 1 is zero (a free integrator: eigenvalue 0), row 4 is zero off the diagonal
        // (eigenvalue -0.7), and so is row 3 without column 4 (eigenvalue -3); the rest, rows
        // and columns 0 and 2, is [[-1, 4], [-4, -1]]: -1 ± 4j.
        let a = DMatrix::from_row_slice(
            5,
            5,
            &[
                -1.0, 0.0, 4.0, 7.0, 1e9, //
                2e-9, 0.0, 3.0, 0.0, 5.0, //
                -4.0, 0.0, -1.0, 2.0, 1e-3, //
                0.0, 0.0, 0.0, -3.0, 8.0, //
                0.0, 0.0, 0.0, 0.0, -0.7,
            ],
        );
        let (isolated, left) = isolate(&a);
        let mut sorted = isolated.clone();
        sorted.sort_by(f64::total_cmp);
        assert_eq!(sorted, vec![-3.0, -0.7, 0.0]);
        assert_eq!(left, vec![0, 2]);
        let ev = eigenvalues(&a);
        assert_eq!(
            ev,
            vec![
                Complex::new(0.0, 0.0),
                Complex::new(-0.7, 0.0),
                Complex::new(-1.0, 4.0),
                Complex::new(-1.0, -4.0),
                Complex::new(-3.0, 0.0),
            ]
        );
        // +0.0, not -0.0.
        assert!(ev[0].re.is_sign_positive() && ev[0].im.is_sign_positive());
        // A matrix of zeros, and an empty one.
        assert_eq!(
            eigenvalues(&DMatrix::zeros(3, 3)),
            vec![Complex::new(0.0, 0.0); 3]
        );
        assert!(eigenvalues(&DMatrix::zeros(0, 0)).is_empty());
        // A zero column leaves the balancing alone too.
        let mut b = a.clone();
        let d = balance(&mut b);
        assert_eq!(d[1], 1.0);
    }

    #[test]
    fn pairs_are_exact_conjugates_in_the_documented_order() {
        let (a, _) = badly_scaled();
        let ev = eigenvalues(&a);
        for w in ev.windows(2) {
            let (x, y) = (w[0], w[1]);
            assert!(
                x.re > y.re || (x.re == y.re && x.im >= y.im),
                "{x} before {y}"
            );
        }
        for z in ev.iter().filter(|z| z.im > 0.0) {
            assert!(ev.contains(&z.conj()), "{z} has no exact conjugate");
        }
        assert_eq!(ev.iter().filter(|z| z.im > 0.0).count(), 5);
        assert_eq!(ev.iter().filter(|z| z.im == 0.0).count(), 6);
    }

    #[test]
    fn non_finite_entries_give_nan() {
        let mut a = DMatrix::<f64>::identity(3, 3);
        a[(0, 2)] = f64::NAN;
        let ev = eigenvalues(&a);
        assert_eq!(ev.len(), 3);
        assert!(ev.iter().all(|z| z.re.is_nan() && z.im.is_nan()));
        let mut b = a.clone();
        assert_eq!(balance(&mut b), vec![1.0; 3]);
        let m = least_damped(&ev, 1e-9).unwrap();
        assert!(m.zeta.is_nan());
    }

    #[test]
    fn modes_and_the_least_damped() {
        let m = Mode::new(Complex::new(-0.6, 0.8));
        assert_eq!((m.omega, m.zeta), (1.0, 0.6));
        assert_eq!(m.frequency_hz(), 1.0 / (2.0 * std::f64::consts::PI));
        assert_eq!(Mode::new(Complex::new(-2.0, 0.0)).zeta, 1.0);
        assert_eq!(Mode::new(Complex::new(2.0, 0.0)).zeta, -1.0);
        assert_eq!(Mode::new(Complex::new(0.0, 0.0)).zeta, 0.0);
        let ev = eigenvalues(&badly_scaled().0);
        // The unstable real 1.5 (ζ -1) is the least damped.
        let least = least_damped(&ev, 1e-9).unwrap();
        assert_eq!(least.eigenvalue.im, 0.0);
        assert!((least.eigenvalue.re - 1.5).abs() < 1e-12, "{least:?}");
        // Without it: -0.25 ± 20.5j (ζ 0.0122), of the pair the upper member.
        let stable: Vec<Complex<f64>> = ev.iter().copied().filter(|z| z.re < 0.0).collect();
        let least = least_damped(&stable, 1e-9).unwrap();
        assert!(
            modulus(least.eigenvalue - Complex::new(-0.25, 20.5)) < 1e-12,
            "{least:?}"
        );
        // Zeros below the threshold are skipped; nothing left gives None.
        let zeros = [Complex::new(0.0, 0.0), Complex::new(1e-12, 0.0)];
        assert_eq!(least_damped(&zeros, 1e-9), None);
        assert_eq!(least_damped(&zeros, 0.0).unwrap().zeta, -1.0);
    }
}
