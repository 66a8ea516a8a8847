//! The iteration matrix of a fixed step size whose Jacobian changes in a few rows only:
//! the constant rows eliminated once, and at every step only a small Schur complement.
//!
//! See [`VaryingRows`].

use std::sync::Arc;

use nalgebra::DMatrix;

use super::super::dense::{product, DenseInverse};
use super::lu::{lu_in_place, lu_solve};
use super::{Entries, Factorisation, Partition, Shifted};

/// M = c I − J factorised for varying rows.
///
/// In a fixed-step Rosenbrock method M = c I − J has the same c at every step (c = 1/(h γ)).
/// If only the rows R of J vary with the state (r of the n rows: the nonlinear laws'
/// rows) and the others, P, are constant, then with the states ordered P first,
///
/// ```text
///     [ M_PP  M_PR ]      M_PP, M_PR: the constant rows, the same at every step
/// M = [            ]
///     [ M_RP  M_RR ]      M_RP, M_RR: the varying rows
/// ```
///
/// and M is factorised by block elimination of M_PP: once per (c, constant part), the dense
/// inverse Q = M_PP⁻¹ (from its LU with partial pivoting) and X = Q M_PR; at every step the
/// r × r Schur complement S = M_RR − M_RP X and its LU with partial pivoting. A solve of
/// M x = b is then y = Q b_P, z = S⁻¹ (b_R − M_RP y), x_P = y − X z, x_R = z. Per step that
/// is r² times the couplings of a varying row plus r³/3 (instead of factorising all of M), and
/// per solve p² + 2 p r + r² plus the couplings (p = n − r), as dense products.
///
/// Since det M = det M_PP · det S, S is singular exactly when M is (M_PP is checked once).
/// The elimination does not pivot between P and R (within M_PP and within S it does), so it
/// is as stable as M_PP is well conditioned; the tests measure its backward error and compare
/// its solves with the dense LU's on every preset whose Jacobian varies
/// (`tests/varying_rows.rs`).
///
/// Everything is deterministic: the same J, c and rows give the same bits, so an integrator
/// restored from a saved state, which rebuilds this, continues bit for bit.
#[derive(Debug, Default)]
pub struct VaryingRows {
    /// The shift c the constant part was eliminated for.
    c: f64,
    /// The varying rows R and the constant ones P, each ascending.
    rows: Vec<usize>,
    kept: Vec<usize>,
    /// For each varying row a, the columns of P where J_{R_a} may be nonzero: (position in P,
    /// column), flattened with `coupling_start` (r + 1 offsets).
    couplings: Vec<(u32, u32)>,
    coupling_start: Vec<usize>,
    /// J_{R_a, j} of the couplings at the last factorisation (the solves' M_RP = −J_RP).
    coupling_values: Vec<f64>,
    /// Q = M_PP⁻¹.
    q: DenseInverse,
    /// −X = −M_PP⁻¹ M_PR, column-major p × r.
    minus_x: Vec<f64>,
    /// −X again, row-major (p × r): the factorisation's sums run along its rows.
    minus_x_rows: Vec<f64>,
    /// A row of S under construction (r).
    s_row: Vec<f64>,
    /// LU of S (r × r, column-major) and its interchanges.
    s: Vec<f64>,
    piv: Vec<usize>,
}

impl VaryingRows {
    /// The elimination of the constant rows of M = c I − `jac` (every row not listed in
    /// `varying`, which gives for each row the columns whose entry varies; a row with none is
    /// constant). `pattern`, if given, lists for each row the columns where J may be nonzero
    /// (the diagonal need not be listed); without it every column is a coupling. None if
    /// M_PP is singular or no row varies.
    pub fn new(
        jac: &DMatrix<f64>,
        c: f64,
        varying: &[Vec<u32>],
        pattern: Option<&[Vec<u32>]>,
    ) -> Option<Self> {
        let n = jac.nrows();
        let rows: Vec<usize> = (0..n).filter(|&i| !varying[i].is_empty()).collect();
        if rows.is_empty() {
            return None;
        }
        let kept: Vec<usize> = (0..n).filter(|&i| varying[i].is_empty()).collect();
        let (p, r) = (kept.len(), rows.len());
        // Position of each state in P (usize::MAX for a varying row).
        let mut in_p = vec![usize::MAX; n];
        for (k, &i) in kept.iter().enumerate() {
            in_p[i] = k;
        }
        let mut couplings = Vec::new();
        let mut coupling_start = vec![0];
        for &i in &rows {
            let mut cols: Vec<usize> = match pattern {
                Some(pat) => pat[i].iter().map(|&j| j as usize).collect(),
                None => (0..n).collect(),
            };
            cols.sort_unstable();
            cols.dedup();
            couplings.extend(
                cols.into_iter()
                    .filter(|&j| in_p[j] != usize::MAX)
                    .map(|j| (in_p[j] as u32, j as u32)),
            );
            coupling_start.push(couplings.len());
        }
        let shifted = Shifted { c, jac };
        let entry = |i: usize, j: usize| shifted.entry(i, j);
        let mut q = DenseInverse::default();
        if p > 0 {
            let dense = Arc::new(Partition::dense(p));
            let mut lu = Factorisation::new(Arc::clone(&dense));
            if !lu.factor(&dense, |a, b| entry(kept[a], kept[b])) {
                return None;
            }
            q.build(&lu, p, &mut vec![0.0; p]);
        }
        // −X = −Q M_PR, a column per varying row.
        let mut minus_x = vec![0.0; p * r];
        let mut column = vec![0.0; p];
        for (b, &j) in rows.iter().enumerate() {
            for (k, &i) in kept.iter().enumerate() {
                column[k] = jac[(i, j)];
            }
            // Q (−M_PR e_b) = Q J_{P, R_b}.
            q.apply(&column, &mut minus_x[b * p..(b + 1) * p]);
        }
        let n_couplings = couplings.len();
        let mut minus_x_rows = vec![0.0; p * r];
        for k in 0..p {
            for b in 0..r {
                minus_x_rows[k * r + b] = minus_x[k + b * p];
            }
        }
        Some(VaryingRows {
            c,
            rows,
            kept,
            couplings,
            coupling_start,
            coupling_values: vec![0.0; n_couplings],
            q,
            minus_x,
            minus_x_rows,
            s_row: vec![0.0; r],
            s: vec![0.0; r * r],
            piv: vec![0; r],
        })
    }

    /// The shift c this elimination was made for.
    pub fn shift(&self) -> f64 {
        self.c
    }

    /// The number of varying rows r.
    pub fn varying_rows(&self) -> usize {
        self.rows.len()
    }

    /// Factorises M = c I − `jac` for a `jac` whose constant rows are those this elimination
    /// was made from (only its varying rows are read): the Schur complement S and its LU.
    /// False if S, and so M, is singular.
    pub fn factor(&mut self, jac: &DMatrix<f64>) -> bool {
        let r = self.rows.len();
        for (a, &i) in self.rows.iter().enumerate() {
            let span = self.coupling_start[a]..self.coupling_start[a + 1];
            for (v, &(_, j)) in self.coupling_values[span.clone()]
                .iter_mut()
                .zip(&self.couplings[span])
            {
                *v = jac[(i, j as usize)];
            }
        }
        // S_ab = M_{R_a R_b} − Σ_k M_{R_a, P_k} X_{k b}
        //      = c δ_ab − J_{R_a R_b} − Σ_k J_{R_a P_k} (−X)_{k b}, a row of S at a time: the
        // sum over the couplings k of row a, each adding a row of −X (contiguous).
        for (a, &i) in self.rows.iter().enumerate() {
            self.s_row.fill(0.0);
            let span = self.coupling_start[a]..self.coupling_start[a + 1];
            for (&(k, _), &v) in self.couplings[span.clone()]
                .iter()
                .zip(&self.coupling_values[span])
            {
                let k = k as usize;
                let x_row = &self.minus_x_rows[k * r..(k + 1) * r];
                for (acc, &x) in self.s_row.iter_mut().zip(x_row) {
                    *acc += v * x;
                }
            }
            for (b, &j) in self.rows.iter().enumerate() {
                let diagonal = if i == j { self.c } else { 0.0 };
                self.s[a + b * r] = diagonal - jac[(i, j)] - self.s_row[b];
            }
        }
        lu_in_place(&mut self.s, r, &mut self.piv)
    }

    /// Σ_k J_{R_a, P_k} v_k over the couplings of varying row `a` (`v` indexed by position
    /// in P), with the values of the last factorisation.
    #[inline]
    fn coupling_dot(&self, a: usize, v: &[f64]) -> f64 {
        let span = self.coupling_start[a]..self.coupling_start[a + 1];
        self.couplings[span.clone()]
            .iter()
            .zip(&self.coupling_values[span])
            .fold(0.0, |sum, (&(k, _), &jv)| sum + jv * v[k as usize])
    }

    /// Solves M x = `rhs` in place with the last [`VaryingRows::factor`]; `scratch` holds at
    /// least n values.
    pub fn solve(&self, rhs: &mut [f64], scratch: &mut [f64]) {
        let (p, r) = (self.kept.len(), self.rows.len());
        let (b_p, rest) = scratch.split_at_mut(p);
        let z = &mut rest[..r];
        for (v, &i) in b_p.iter_mut().zip(&self.kept) {
            *v = rhs[i];
        }
        // y = Q b_P, in rhs[..p] (the right-hand side is all in the scratch now).
        for (v, &i) in z.iter_mut().zip(&self.rows) {
            *v = rhs[i];
        }
        let y = &mut rhs[..p];
        if p > 0 {
            self.q.apply(b_p, y);
        }
        // z = S⁻¹ (b_R − M_RP y) = S⁻¹ (b_R + J_RP y).
        for (a, v) in z.iter_mut().enumerate() {
            *v += self.coupling_dot(a, y);
        }
        lu_solve(&self.s, r, &self.piv, z);
        // x_P = y + (−X) z, into the scratch's first p, then both parts to their states.
        product(&self.minus_x, p, Some(y), z, b_p);
        for (&v, &i) in b_p.iter().zip(&self.kept) {
            rhs[i] = v;
        }
        for (&v, &i) in z.iter().zip(&self.rows) {
            rhs[i] = v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::Rng;
    use super::*;

    /// A matrix with a few dense varying rows and sparse constant ones, and its structural
    /// pattern; the solve agrees with nalgebra's LU, and a refactorisation with other values
    /// in the varying rows too.
    #[test]
    fn solves_agree_with_the_dense_lu() {
        let mut rng = Rng(0x51f1_5eed);
        let n = 23;
        let varying_rows = [2usize, 9, 10, 17];
        let mut pattern = vec![Vec::new(); n];
        let mut varying = vec![Vec::new(); n];
        let mut jac = DMatrix::zeros(n, n);
        for i in 0..n {
            for j in 0..n {
                let dense_row = varying_rows.contains(&i);
                if dense_row || (i + 3 * j) % 5 == 0 || i.abs_diff(j) == 1 {
                    jac[(i, j)] = 40.0 * rng.next();
                    pattern[i].push(j as u32);
                    if dense_row && j % 2 == 0 {
                        varying[i].push(j as u32);
                    }
                }
            }
        }
        let c = 50.0;
        let mut lu = VaryingRows::new(&jac, c, &varying, Some(&pattern)).unwrap();
        assert_eq!(lu.varying_rows(), 4);
        assert_eq!(lu.shift(), c);
        let mut scratch = vec![f64::NAN; n];
        for round in 0..3 {
            if round > 0 {
                for &i in &varying_rows {
                    for &j in &varying[i] {
                        jac[(i, j as usize)] = 40.0 * rng.next();
                    }
                }
            }
            assert!(lu.factor(&jac));
            let m = DMatrix::identity(n, n) * c - &jac;
            let b: Vec<f64> = (0..n).map(|_| rng.next()).collect();
            let mut x = b.clone();
            lu.solve(&mut x, &mut scratch);
            let want = m
                .clone()
                .lu()
                .solve(&nalgebra::DVector::from_column_slice(&b))
                .unwrap();
            for i in 0..n {
                assert!(
                    (x[i] - want[i]).abs() <= 1e-12 * want.amax(),
                    "round {round}, x[{i}] = {} against {}",
                    x[i],
                    want[i]
                );
            }
        }
    }

    /// A singular M is reported: through M_PP at construction, through S at factorisation.
    #[test]
    fn singular_matrices_are_reported() {
        let n = 4;
        let varying = vec![vec![], vec![0, 1], vec![], vec![]];
        // M_PP singular: states 0 and 2 have the same constant rows of M.
        let mut jac = DMatrix::from_fn(n, n, |i, j| if i == j { 1.0 } else { 0.0 });
        jac[(0, 0)] = 3.0;
        jac[(2, 2)] = 3.0;
        jac[(0, 2)] = -2.0;
        jac[(2, 0)] = -2.0;
        // c I − J_PP: rows (c − 3, 2) and (2, c − 3) with c = 5: singular.
        assert!(VaryingRows::new(&jac, 5.0, &varying, None).is_none());
        // S singular: row 1 of M equal to row 3's.
        let mut jac = DMatrix::zeros(n, n);
        jac[(3, 0)] = 1.0;
        let mut lu = VaryingRows::new(&jac, 2.0, &varying, None).unwrap();
        jac[(1, 0)] = 1.0;
        jac[(1, 1)] = 2.0;
        jac[(1, 3)] = -2.0;
        // Row 1 of M: (−1, 0, 0, 2) = row 3 of M: (−1, 0, 0, 2).
        assert!(!lu.factor(&jac));
        // No varying row: nothing to eliminate.
        assert!(VaryingRows::new(&jac, 2.0, &[vec![], vec![], vec![], vec![]], None).is_none());
    }
}
