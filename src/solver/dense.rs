//! Dense products for small systems with a constant Jacobian: the step map's `L x + a`
//! ([`super::step_map`]) and the solve with an explicit inverse of Rodas5P's iteration matrix
//! ([`DenseInverse`]).
//!
//! The product runs a column at a time (`y += L[:, j] x_j`), so its inner loop is over
//! contiguous memory and vectorises. On x86-64 processors with AVX2 (detected at run time, so the
//! library still runs on any x86-64) the same loop is compiled for 4-wide vectors; it multiplies
//! and adds separately, never fused, so every component goes through the same roundings in the
//! same order as in the portable loop: the same bits on every processor.

use super::linalg::Factorisation;

/// `y = a + L x` (or `L x` without `a`), L `rows × x.len()` column-major; columns whose
/// `x_j` is zero are skipped (they add exact zeros).
pub(crate) fn product(lin: &[f64], rows: usize, a: Option<&[f64]>, x: &[f64], y: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            let (lin, y) = (&lin[..lin.len() / rows.max(1) * rows], &mut y[..rows]);
            let a = a.map(|a| &a[..rows]);
            // SAFETY: the processor has AVX2 (checked just above); `lin` holds whole columns of
            // `rows` entries, `y` and `a` (if any) `rows` entries, and the kernel of V vectors
            // gets 4 (V − 1) < rows ≤ 4 V.
            unsafe {
                match rows.div_ceil(4) {
                    0 => product_loop(lin, rows, a, x, y),
                    1 => product_small_avx2::<1>(lin, rows, a, x, y),
                    2 => product_small_avx2::<2>(lin, rows, a, x, y),
                    3 => product_small_avx2::<3>(lin, rows, a, x, y),
                    4 => product_small_avx2::<4>(lin, rows, a, x, y),
                    5 => product_small_avx2::<5>(lin, rows, a, x, y),
                    6 => product_small_avx2::<6>(lin, rows, a, x, y),
                    7 => product_small_avx2::<7>(lin, rows, a, x, y),
                    8 => product_small_avx2::<8>(lin, rows, a, x, y),
                    _ => product_avx2(lin, rows, a, x, y),
                }
            }
            return;
        }
    }
    product_loop(lin, rows, a, x, y);
}

/// [`product_loop`] for `4 (V − 1) < rows ≤ 4 V`, V ≤ 8, with the same bits: `y` is held in V
/// registers of four lanes through all the columns (the last one's lanes past `rows` masked off
/// when loading and storing), so that each column costs V multiplications and V additions of
/// vectors instead of a load and a store of `y`, which made every column wait on the one
/// before. Each entry still starts at `a_i` (or 0) and adds `l_ij x_j` column after column,
/// multiplied and added apart (never fused), a zero `x_j` skipping its column: the loop's
/// operations in its order. The real-time mode's solve with the varying rows (29 kept rows on
/// the complete system) and the inverses of small constant systems take this path.
///
/// # Safety
///
/// The processor has AVX2; `lin.len()` is a multiple of `rows`, `y.len() == rows`, `a` (if
/// any) holds `rows` entries, and `4 (V − 1) < rows ≤ 4 V`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn product_small_avx2<const V: usize>(
    lin: &[f64],
    rows: usize,
    a: Option<&[f64]>,
    x: &[f64],
    y: &mut [f64],
) {
    use super::linalg::PARTIAL_MASKS;
    use std::arch::x86_64::*;
    debug_assert!(4 * (V - 1) < rows && rows <= 4 * V && y.len() == rows);
    debug_assert!(lin.len().is_multiple_of(rows) && a.is_none_or(|a| a.len() == rows));
    let last = rows - 4 * (V - 1);
    // SAFETY: the full vectors cover entries 4v..4v + 4 ≤ 4 (V − 1) < rows of a column (or of
    // `a`, `y`), the last one only its `last` ≤ 4 entries from 4 (V − 1), the lanes past them
    // masked off; every column lies within `lin` (its length is a multiple of `rows`).
    unsafe {
        let mask = _mm256_loadu_si256(PARTIAL_MASKS[last].as_ptr().cast());
        let load = |p: *const f64, v: usize| {
            if v + 1 < V {
                _mm256_loadu_pd(p.add(4 * v))
            } else {
                _mm256_maskload_pd(p.add(4 * v), mask)
            }
        };
        let mut acc = [_mm256_setzero_pd(); V];
        if let Some(a) = a {
            for (v, acc) in acc.iter_mut().enumerate() {
                *acc = load(a.as_ptr(), v);
            }
        }
        for (column, &xj) in lin.chunks_exact(rows).zip(x) {
            if xj != 0.0 {
                let xj = _mm256_set1_pd(xj);
                for (v, acc) in acc.iter_mut().enumerate() {
                    let l = load(column.as_ptr(), v);
                    *acc = _mm256_add_pd(*acc, _mm256_mul_pd(l, xj));
                }
            }
        }
        for (v, acc) in acc.iter().enumerate() {
            if v + 1 < V {
                _mm256_storeu_pd(y.as_mut_ptr().add(4 * v), *acc);
            } else {
                _mm256_maskstore_pd(y.as_mut_ptr().add(4 * v), mask, *acc);
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn product_avx2(lin: &[f64], rows: usize, a: Option<&[f64]>, x: &[f64], y: &mut [f64]) {
    product_loop(lin, rows, a, x, y);
}

#[inline(always)]
fn product_loop(lin: &[f64], rows: usize, a: Option<&[f64]>, x: &[f64], y: &mut [f64]) {
    let y = &mut y[..rows];
    match a {
        Some(a) => y.copy_from_slice(&a[..rows]),
        None => y.fill(0.0),
    }
    for (column, &xj) in lin.chunks_exact(rows).zip(x) {
        if xj != 0.0 {
            for (yi, &l) in y.iter_mut().zip(column) {
                *yi += l * xj;
            }
        }
    }
}

/// The explicit inverse of a small iteration matrix, made from its LU factorisation (one
/// solve per unit vector), so that a solve is one dense product: for Rodas5P with a constant
/// Jacobian, whose eight solves per step with the structured LU (blocks of one or two states
/// and a border) cost more in bookkeeping than in arithmetic. Its rounding error is bounded
/// by a small multiple of n ε ‖M⁻¹‖ ‖b‖, of the order of the LU solve's forward error
/// ε cond(M) ‖x‖, and far below the tolerances the steps are controlled to.
#[derive(Debug, Default)]
pub(crate) struct DenseInverse {
    /// Columns of M⁻¹ (empty: none made).
    inv: Vec<f64>,
    n: usize,
}

impl DenseInverse {
    /// Is there an inverse (since the last [`DenseInverse::clear`])?
    pub fn is_built(&self) -> bool {
        self.n > 0
    }

    /// Forgets the inverse (its factorisation changed), keeping the memory.
    pub fn clear(&mut self) {
        self.n = 0;
    }

    /// M⁻¹ from the factorisation `lu` of M (n × n), its columns the solves with the unit
    /// vectors; `scratch` is any vector of length n.
    pub fn build(&mut self, lu: &Factorisation<f64>, n: usize, scratch: &mut [f64]) {
        self.inv.resize(n * n, 0.0);
        for (j, column) in self.inv.chunks_exact_mut(n).enumerate() {
            column.fill(0.0);
            column[j] = 1.0;
            lu.solve(column, scratch);
        }
        self.n = n;
    }

    /// Solves M x = rhs in place (`scratch` of length n is overwritten).
    pub fn solve(&self, rhs: &mut [f64], scratch: &mut [f64]) {
        self.apply(rhs, scratch);
        rhs.copy_from_slice(&scratch[..self.n]);
    }

    /// x = M⁻¹ b into `x` (`b` and `x` of length n).
    pub fn apply(&self, b: &[f64], x: &mut [f64]) {
        product(&self.inv, self.n, None, b, x);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::linalg::Partition;
    use nalgebra::DMatrix;
    use std::sync::Arc;

    /// The kernels with `y` in registers give the portable loop's bits for every number of
    /// rows they take (1 to 32) and the ones around them (33 to 37, the columns' loop), with
    /// zero, signed-zero and non-finite entries, with and without `a`.
    #[test]
    fn the_small_products_have_the_loops_bits() {
        let special = [0.0, -0.0, f64::INFINITY, f64::NAN, -1e-310, 1e300];
        let value = |k: usize| match k % 11 {
            4 => special[(k / 11) % special.len()],
            _ => ((k * 2654435761) % 2000) as f64 / 97.0 - 10.0,
        };
        // A NaN's sign and payload depend on which operand the processor saw first, which the
        // compiler may swap in a commutative operation: NaNs compare as NaN.
        let bits = |v: &[f64]| {
            v.iter()
                .map(|x| if x.is_nan() { u64::MAX } else { x.to_bits() })
                .collect::<Vec<_>>()
        };
        for rows in 1..=37 {
            for columns in [0, 1, 2, 5, 15, 16] {
                let lin: Vec<f64> = (0..rows * columns).map(|k| value(k + 3)).collect();
                // Every third x is zero (its column skipped), one of them −0.
                let x: Vec<f64> = (0..columns)
                    .map(|j| match j % 3 {
                        0 if j % 2 == 0 => 0.0,
                        0 => -0.0,
                        _ => value(7 * j + rows),
                    })
                    .collect();
                let a: Vec<f64> = (0..rows).map(|i| value(5 * i + 1)).collect();
                for a in [Some(&a[..]), None] {
                    let (mut y, mut y_loop) = (vec![f64::NAN; rows], vec![f64::NAN; rows]);
                    product(&lin, rows, a, &x, &mut y);
                    product_loop(&lin, rows, a, &x, &mut y_loop);
                    assert_eq!(bits(&y), bits(&y_loop), "{rows} rows, {columns} columns");
                }
            }
        }
    }

    /// The vectorised product gives the portable loop's bits, and the inverse solves.
    #[test]
    fn product_and_inverse() {
        let (rows, n) = (11, 7);
        let lin: Vec<f64> = (0..rows * n)
            .map(|k| ((k * 37 % 17) as f64 - 8.0) * 0.37)
            .collect();
        let x: Vec<f64> = (0..n)
            .map(|j| {
                if j == 3 {
                    0.0
                } else {
                    crate::math::sin(j as f64) * 1e3
                }
            })
            .collect();
        let a: Vec<f64> = (0..rows).map(|i| i as f64 - 2.5).collect();
        let (mut y, mut y_loop) = (vec![f64::NAN; rows], vec![f64::NAN; rows]);
        product(&lin, rows, Some(&a), &x, &mut y);
        product_loop(&lin, rows, Some(&a), &x, &mut y_loop);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&y), bits(&y_loop));
        for i in 0..rows {
            let want = (0..n).fold(a[i], |s, j| s + lin[i + j * rows] * x[j]);
            assert!((y[i] - want).abs() <= 1e-12 * want.abs().max(1.0));
        }
        let m = DMatrix::from_fn(n, n, |i, j| {
            if i == j {
                4.0 + i as f64
            } else {
                0.3 * (i as f64 - j as f64)
            }
        });
        let mut lu = Factorisation::new(Arc::new(Partition::dense(n)));
        assert!(lu.factor(&Arc::new(Partition::dense(n)), |i, j| m[(i, j)]));
        let mut inv = DenseInverse::default();
        assert!(!inv.is_built());
        let mut scratch = vec![0.0; n];
        inv.build(&lu, n, &mut scratch);
        assert!(inv.is_built());
        let b: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
        let mut sol = b.clone();
        inv.solve(&mut sol, &mut scratch);
        let residual = &m * nalgebra::DVector::from_column_slice(&sol)
            - nalgebra::DVector::from_column_slice(&b);
        assert!(residual.amax() < 1e-13, "{residual}");
        inv.clear();
        assert!(!inv.is_built());
    }
}
