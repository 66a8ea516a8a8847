//! The cache of the last Jacobian's partition ([`PatternCache`]).

use std::sync::Arc;

use nalgebra::DMatrix;

use super::partition::Partition;

/// The partition of the last Jacobian and its nonzero pattern: re-detected only when the
/// pattern changes, so a Jacobian evaluated at every step costs one scan of J, no allocation.
#[derive(Clone, Debug)]
pub(crate) struct PatternCache {
    /// (column, row) of every nonzero off-diagonal entry, column-major order.
    nonzeros: Vec<(u32, u32)>,
    part: Arc<Partition>,
    /// Stamp of the constant Jacobian the partition was made for (no scan needed for it).
    stamp: Option<u64>,
    /// The partition was made from a structural pattern (no scan needed while it is given).
    structural: bool,
}

impl Default for PatternCache {
    fn default() -> Self {
        PatternCache {
            nonzeros: Vec::new(),
            part: Arc::new(Partition::dense(0)),
            stamp: None,
            structural: false,
        }
    }
}

impl PatternCache {
    /// The partition for J; `stamp` is that of a constant Jacobian (see
    /// [`OdeSystem::constant_jacobian`](crate::solver::OdeSystem::constant_jacobian)), for which the
    /// partition is found once.
    pub fn partition(&mut self, jac: &DMatrix<f64>, stamp: Option<u64>) -> &Arc<Partition> {
        let n = jac.nrows();
        if stamp.is_some() && stamp == self.stamp && self.part.dim() == n {
            return &self.part;
        }
        self.stamp = stamp;
        self.structural = false;
        let mut same = self.part.dim() == n;
        let mut count = 0usize;
        if same {
            'scan: for j in 0..n {
                for (i, v) in jac.column(j).iter().enumerate() {
                    if i != j && *v != 0.0 {
                        if self.nonzeros.get(count) != Some(&(j as u32, i as u32)) {
                            same = false;
                            break 'scan;
                        }
                        count += 1;
                    }
                }
            }
        }
        if !(same && count == self.nonzeros.len()) {
            self.nonzeros.clear();
            for j in 0..n {
                for (i, v) in jac.column(j).iter().enumerate() {
                    if i != j && *v != 0.0 {
                        self.nonzeros.push((j as u32, i as u32));
                    }
                }
            }
            self.part = Arc::new(Partition::of_matrix(jac));
        }
        &self.part
    }

    /// The partition for a Jacobian whose nonzeros lie within `pattern` (for each row, the
    /// columns that may be nonzero; see
    /// [`OdeSystem::jacobian_pattern`](crate::solver::OdeSystem::jacobian_pattern)): found once from the
    /// pattern, valid for every J within it, and the same for a restored integrator (it does not
    /// depend on which entries happened to be zero). With no pattern, [`PatternCache::partition`].
    pub fn partition_within(
        &mut self,
        jac: &DMatrix<f64>,
        pattern: Option<&[Vec<u32>]>,
    ) -> &Arc<Partition> {
        let n = jac.nrows();
        match pattern {
            Some(rows) if rows.len() == n => {
                if !(self.structural && self.part.dim() == n) {
                    let mut nonzero = vec![false; n * n];
                    for (i, cols) in rows.iter().enumerate() {
                        for &j in cols {
                            nonzero[i * n + j as usize] = true;
                        }
                    }
                    self.part = Arc::new(Partition::detect(n, |i, j| nonzero[i * n + j]));
                    self.nonzeros.clear();
                    self.stamp = None;
                    self.structural = true;
                }
                &self.part
            }
            _ => self.partition(jac, None),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::{arrowhead, residual, Rng};
    use super::super::{factor_with_fallback, Factorisation};
    use super::*;

    #[test]
    fn the_pattern_cache_redetects_only_on_a_new_pattern() {
        let mut rng = Rng(5);
        let j = arrowhead(&mut rng, 20, 2, 3);
        let mut cache = PatternCache::default();
        let p1 = Arc::clone(cache.partition(&j, None));
        let p2 = Arc::clone(cache.partition(&(&j * 2.0), None));
        assert!(Arc::ptr_eq(&p1, &p2));
        let mut j2 = j.clone();
        j2[(0, j.ncols() - 1)] = 1.0 + j2[(0, j.ncols() - 1)].abs();
        j2[(1, j.ncols() - 2)] = 1.0 + j2[(1, j.ncols() - 2)].abs();
        let p3 = Arc::clone(cache.partition(&j2, None));
        assert!(!Arc::ptr_eq(&p1, &p3));
        assert_eq!(*p3, Partition::of_matrix(&j2));
        // Under one constant-Jacobian stamp the partition is not looked for again.
        let p4 = Arc::clone(cache.partition(&j, Some(1)));
        assert_eq!(*p4, *p1);
        let p5 = Arc::clone(cache.partition(&j2, Some(1)));
        assert!(Arc::ptr_eq(&p4, &p5));
    }

    #[test]
    fn a_structural_pattern_gives_one_partition_for_every_jacobian_within_it() {
        let mut rng = Rng(7);
        let j = arrowhead(&mut rng, 20, 2, 3);
        let n = j.nrows();
        let rows: Vec<Vec<u32>> = (0..n)
            .map(|i| {
                (0..n as u32)
                    .filter(|&c| j[(i, c as usize)] != 0.0)
                    .collect()
            })
            .collect();
        let mut cache = PatternCache::default();
        let p1 = Arc::clone(cache.partition_within(&j, Some(&rows)));
        assert_eq!(*p1, Partition::of_matrix(&j));
        // Entries of J that happen to be zero do not change it (a scan of J would have).
        let mut sparser = j.clone();
        for i in 0..n {
            for c in 0..n {
                if i != c && (i + c) % 3 == 0 {
                    sparser[(i, c)] = 0.0;
                }
            }
        }
        assert_ne!(Partition::of_matrix(&sparser), *p1);
        let p2 = Arc::clone(cache.partition_within(&sparser, Some(&rows)));
        assert!(Arc::ptr_eq(&p1, &p2));
        // And the factorisation with it still solves the sparser matrix.
        let entry = |r: usize, c: usize| sparser[(r, c)] + if r == c { 10.0 } else { 0.0 };
        let mut f = Factorisation::new(Arc::clone(&p2));
        assert!(factor_with_fallback(&mut f, &p2, entry));
        let b: Vec<f64> = (0..n).map(|_| rng.next()).collect();
        let mut x = b.clone();
        f.solve(&mut x, &mut vec![0.0; n]);
        assert!(residual(n, entry, &x, &b) < 1e-9);
        // Without a pattern, the scan of J as before.
        let p3 = Arc::clone(cache.partition_within(&sparser, None));
        assert_eq!(*p3, Partition::of_matrix(&sparser));
    }
}
