//! Test matrices shared by the tests of the linear algebra.

use nalgebra::DMatrix;

use super::Scalar;

/// xorshift64*: deterministic test matrices without a dependency.
pub(super) struct Rng(pub(super) u64);
impl Rng {
    pub(super) fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let v = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d);
        (v >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// A random arrowhead matrix: `blocks` groups of `k` states, each group dense inside and
/// coupled to a random subset of a `m`-state dense border; states shuffled.
pub(super) fn arrowhead(rng: &mut Rng, blocks: usize, k: usize, m: usize) -> DMatrix<f64> {
    arrowhead_with_free(rng, blocks, k, m, 0)
}

/// [`arrowhead`] in which every `free`-th block (none for 0) has no link to the border.
pub(super) fn arrowhead_with_free(
    rng: &mut Rng,
    blocks: usize,
    k: usize,
    m: usize,
    free: usize,
) -> DMatrix<f64> {
    let n = blocks * k + m;
    let mut a = DMatrix::zeros(n, n);
    for b in 0..blocks {
        for i in 0..k {
            for j in 0..k {
                a[(b * k + i, b * k + j)] = rng.next();
            }
            for q in 0..m {
                if rng.next() > 0.3 && (free == 0 || b % free != 0) {
                    a[(b * k + i, blocks * k + q)] = rng.next();
                    a[(blocks * k + q, b * k + i)] = rng.next();
                }
            }
        }
    }
    for i in 0..m {
        for j in 0..m {
            a[(blocks * k + i, blocks * k + j)] = rng.next();
        }
    }
    // A random symmetric permutation hides the order.
    let mut perm: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        let j = ((rng.next() + 1.0) / 2.0 * (i + 1) as f64) as usize % (i + 1);
        perm.swap(i, j);
    }
    DMatrix::from_fn(n, n, |i, j| a[(perm[i], perm[j])])
}

pub(super) fn residual<T: Scalar>(
    n: usize,
    entry: impl Fn(usize, usize) -> T,
    x: &[T],
    b: &[T],
) -> f64 {
    (0..n)
        .map(|i| {
            let mut acc = T::ZERO;
            for j in 0..n {
                acc = acc + entry(i, j) * x[j];
            }
            (acc - b[i]).norm1()
        })
        .fold(0.0, f64::max)
}
