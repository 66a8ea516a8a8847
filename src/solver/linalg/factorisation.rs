//! LU factors of M for a [`Partition`] (see the module documentation of [`super`]): the block
//! elimination with its Schur complement; the solves with them are in `solve`.

mod solve;

use std::sync::Arc;

use nalgebra::DMatrix;

use super::lu::{factor_one, lu_in_place, lu_solve, lu_solve_loops, pivots_clear, scales};
use super::partition::Partition;
use super::scalar::Scalar;

/// A block with a pivot below this share of its row's and column's scales is left to the dense
/// LU: elimination inside blocks does not pivot across them ([`pivots_clear`]).
const PIVOT_FLOOR: f64 = 1e-10;

/// The entries of a matrix to factorise: a closure `|i, j| M_ij`, or a type that also gives a
/// whole leading column at once ([`Shifted`]), which the dense partition's one block fills from.
pub trait Entries<T> {
    /// M_ij.
    fn entry(&self, i: usize, j: usize) -> T;
    /// M_rj for the rows r in 0..out.len() of column j, into `out`: by default entry by entry.
    fn leading_column(&self, j: usize, out: &mut [T]) {
        for (r, v) in out.iter_mut().enumerate() {
            *v = self.entry(r, j);
        }
    }
    /// M's entries at the positions `at` (i + j n of an n × n matrix stored column-major) into
    /// `out`, those at the places `diagonal` of `at` being on M's diagonal (and only those);
    /// false, writing nothing, if M is not stored so (by default: the caller then reads entry
    /// by entry).
    fn gather_at(&self, n: usize, at: &[usize], diagonal: &[usize], out: &mut [T]) -> bool {
        let _ = (n, at, diagonal, out);
        false
    }
}

impl<T, F: Fn(usize, usize) -> T> Entries<T> for F {
    fn entry(&self, i: usize, j: usize) -> T {
        self(i, j)
    }
}

/// M = c I − J for a Jacobian J: the iteration matrix W = I/(h γ) − J of the Rosenbrock methods
/// (c = 1/(h γ)). A column comes as J's column negated with c added on the diagonal, the same
/// operations as entry by entry (so the same bits), without indexing each entry.
pub struct Shifted<'a> {
    /// The shift c.
    pub c: f64,
    /// J, square.
    pub jac: &'a DMatrix<f64>,
}

impl Entries<f64> for Shifted<'_> {
    fn entry(&self, i: usize, j: usize) -> f64 {
        let v = self.jac[(i, j)];
        if i == j {
            self.c - v
        } else {
            -v
        }
    }

    fn leading_column(&self, j: usize, out: &mut [f64]) {
        let n = self.jac.nrows();
        let column = &self.jac.as_slice()[j * n..j * n + out.len()];
        for (o, &v) in out.iter_mut().zip(column) {
            *o = -v;
        }
        if let Some(d) = out.get_mut(j) {
            *d = self.c - column[j];
        }
    }

    fn gather_at(&self, n: usize, at: &[usize], diagonal: &[usize], out: &mut [f64]) -> bool {
        if self.jac.shape() != (n, n) {
            return false;
        }
        let jac = self.jac.as_slice();
        for (v, &a) in out.iter_mut().zip(at) {
            *v = -jac[a];
        }
        for &d in diagonal {
            out[d] = self.c - jac[at[d]];
        }
        true
    }
}

/// LU factors of M for a [`Partition`] (see the [module documentation](super)).
#[derive(Clone, Debug)]
pub struct Factorisation<T: Scalar> {
    part: Arc<Partition>,
    /// LU of each block, column-major k × k, one after the other.
    lu: Vec<T>,
    /// Row interchanges of each block (LAPACK style, local to the block), at the block's
    /// positions.
    piv: Vec<usize>,
    /// X_b = A_b⁻¹ B_b, column-major k × (links of b), one block after the other.
    x: Vec<T>,
    /// C_b, row-major (links of b) × k, at the same offsets as `x`.
    c: Vec<T>,
    /// LU of the Schur complement (m × m, column-major) and its interchanges.
    schur: Vec<T>,
    schur_piv: Vec<usize>,
    /// Scratch: a block's row and column scales before its LU ([`pivots_clear`]).
    scales: Vec<f64>,
    /// The dense partition [`factor_with_fallback`] falls back to, kept once made: a system
    /// whose structured elimination fails at every step (a badly scaled block) then allocates
    /// nothing per step.
    dense_fallback: Option<Arc<Partition>>,
    /// Judge the pivots of a dense partition too ([`Factorisation::judging_pivots`]).
    judge_dense: bool,
}

impl<T: Scalar> Factorisation<T> {
    /// An empty factorisation that judges the pivots of every partition, the dense one
    /// included, by the equilibrated test of the structured ones: for a caller that needs to
    /// know whether a matrix is singular to rounding (a Newton step that must fall back to a
    /// least-norm solve), not for an iteration matrix, which the dense LU must take as it is.
    pub fn judging_pivots(part: Arc<Partition>) -> Self {
        Factorisation {
            judge_dense: true,
            ..Self::new(part)
        }
    }

    /// An empty factorisation (to be filled by [`Factorisation::factor`]).
    pub fn new(part: Arc<Partition>) -> Self {
        Factorisation {
            part,
            lu: Vec::new(),
            piv: Vec::new(),
            x: Vec::new(),
            c: Vec::new(),
            schur: Vec::new(),
            schur_piv: Vec::new(),
            scales: Vec::new(),
            dense_fallback: None,
            judge_dense: false,
        }
    }

    /// The partition in use.
    pub fn partition(&self) -> &Arc<Partition> {
        &self.part
    }

    /// Factorises the matrix with entries `entry(i, j)` for the partition `part` (reusing this
    /// factorisation's memory). False if a pivot is zero, or, for a structured partition, small
    /// against its row and column (below 1e-10 in the block with its rows and columns scaled to
    /// a largest entry of 1, as LAPACK's `dgeequ` scales); the factors are then unusable.
    pub fn factor(&mut self, part: &Arc<Partition>, entry: impl Entries<T>) -> bool {
        self.factor_by(part, &entry)
    }

    /// [`Factorisation::factor`] with the entries by reference.
    fn factor_by<E: Entries<T>>(&mut self, part: &Arc<Partition>, entry: &E) -> bool {
        if !Arc::ptr_eq(&self.part, part) {
            self.part = Arc::clone(part);
        }
        let p = &*self.part;
        let n = p.n;
        let nb = p.starts[p.blocks()];
        let m = n - nb;
        let floor = if p.is_dense() && !self.judge_dense {
            0.0
        } else {
            PIVOT_FLOOR
        };
        grow(&mut self.lu, p.lu_len, T::ZERO);
        grow(&mut self.x, p.x_len, T::ZERO);
        grow(&mut self.c, p.x_len, T::ZERO);
        grow(&mut self.piv, n, 0);
        grow(&mut self.schur, m * m, T::ZERO);
        grow(&mut self.schur_piv, m, 0);
        if floor > 0.0 {
            grow(&mut self.scales, 3 * n, 0.0);
        }
        // The blocks' LUs first, at the offsets the solves read them from: a block with a small
        // pivot fails the factorisation before any of the couplings' work is done (a model whose
        // structured elimination fails then pays only its small blocks before the dense LU).
        // A structured partition's entries in one pass per buffer where M is stored column-major
        // (`Shifted`), else entry by entry, block by block.
        let g = &p.gather;
        let flat =
            !p.is_dense() && entry.gather_at(n, &g.lu, &g.lu_diagonal, &mut self.lu[..p.lu_len]);
        for at in p.linked.iter().chain(&p.free) {
            let (s, k) = (at.start, at.size);
            let idx = &p.perm[s..s + k];
            let a = &mut self.lu[at.lu..at.lu + k * k];
            if !flat {
                if idx.iter().enumerate().all(|(i, &v)| i == v) {
                    // A block of the first k states in natural order (`Partition::dense`'s one
                    // block): no indirection.
                    for (cj, column) in a.chunks_exact_mut(k).enumerate() {
                        entry.leading_column(cj, column);
                    }
                } else {
                    gather(entry, idx, idx, a);
                }
            }
            if !factor_block(a, k, &mut self.piv[s..s + k], floor, &mut self.scales) {
                return false;
            }
        }
        let border = &p.perm[nb..];
        let (x, c) = (&mut self.x[..p.x_len], &mut self.c[..p.x_len]);
        if flat {
            entry.gather_at(n, &g.schur, &g.schur_diagonal, &mut self.schur[..m * m]);
            entry.gather_at(n, &g.x, &[], x);
            entry.gather_at(n, &g.c, &[], c);
        } else {
            gather(entry, border, border, &mut self.schur[..m * m]);
        }
        // The couplings: the Schur complement takes the linked blocks' updates in block order
        // (the free ones have none).
        for at in &p.linked {
            let (s, k) = (at.start, at.size);
            let (links, states) = (
                &p.links[at.links_from..at.links_to],
                &p.link_states[at.links_from..at.links_to],
            );
            let idx = &p.perm[s..s + k];
            let l = links.len();
            let x = &mut x[at.x..at.x + k * l];
            let c = &mut c[at.x..at.x + k * l];
            if !flat {
                gather(entry, idx, states, x);
                gather_row_major(entry, states, idx, c);
            }
            let (a, piv) = (&self.lu[at.lu..at.lu + k * k], &self.piv[s..s + k]);
            let schur = &mut self.schur[..m * m];
            // With k known the loops unroll (the plate's modes are blocks of one state).
            match k {
                1 => couple_one(a[0], x, c, links, schur, m),
                2 => couple(2, a, piv, x, c, links, schur, m),
                3 => couple(3, a, piv, x, c, links, schur, m),
                4 => couple(4, a, piv, x, c, links, schur, m),
                _ => couple(k, a, piv, x, c, links, schur, m),
            }
        }
        factor_block(
            &mut self.schur[..m * m],
            m,
            &mut self.schur_piv[..m],
            floor,
            &mut self.scales,
        )
    }
}

/// `s[i]` without the bounds check, for the solve's indices that the partition's construction
/// checked ([`Factorisation::solve`]).
///
/// # Safety
///
/// `i < s.len()`.
#[inline(always)]
unsafe fn get<T: Copy>(s: &[T], i: usize) -> T {
    debug_assert!(i < s.len());
    // SAFETY: i < s.len() (the caller's promise).
    unsafe { *s.get_unchecked(i) }
}

/// `&mut s[i]` without the bounds check ([`get`]).
///
/// # Safety
///
/// `i < s.len()`.
#[inline(always)]
unsafe fn get_mut<T>(s: &mut [T], i: usize) -> &mut T {
    debug_assert!(i < s.len());
    // SAFETY: i < s.len() (the caller's promise).
    unsafe { s.get_unchecked_mut(i) }
}

/// M[rows, cols] into `out`, column-major (`out[r + c * rows.len()]` = M_{rows[r], cols[c]}),
/// entry by entry.
fn gather<T: Scalar>(entry: &impl Entries<T>, rows: &[usize], cols: &[usize], out: &mut [T]) {
    for (&j, column) in cols.iter().zip(out.chunks_exact_mut(rows.len().max(1))) {
        for (v, &i) in column.iter_mut().zip(rows) {
            *v = entry.entry(i, j);
        }
    }
}

/// M[rows, cols] into `out`, row-major (`out[c + r * cols.len()]` = M_{rows[r], cols[c]}),
/// entry by entry.
fn gather_row_major<T: Scalar>(
    entry: &impl Entries<T>,
    rows: &[usize],
    cols: &[usize],
    out: &mut [T],
) {
    for (&i, row) in rows.iter().zip(out.chunks_exact_mut(cols.len().max(1))) {
        for (v, &j) in row.iter_mut().zip(cols) {
            *v = entry.entry(i, j);
        }
    }
}

/// Block b's share of the factorisation once its LU (`a`, `piv`) is made: X_b = A_b⁻¹ B_b in
/// place of B_b in `x` (k × links, column-major), and S -= C_b X_b (C_b in `c`, links × k,
/// row-major) where the block touches the border: entry (r, q) of S for the links r and q, each
/// the dot product over the block's k states in order, from zero. Inlined, so that a constant
/// k unrolls the loops (the same operations in the same order for every k, so the same bits).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn couple<T: Scalar>(
    k: usize,
    a: &[T],
    piv: &[usize],
    x: &mut [T],
    c: &[T],
    links: &[usize],
    schur: &mut [T],
    m: usize,
) {
    for column in x.chunks_exact_mut(k) {
        if k <= 4 {
            // Inlined (for a constant k, unrolled): the bits of `lu_solve`'s written-out and
            // unrolled solves (`small_block_solves_match_the_loops_bit_for_bit`).
            lu_solve_loops(a, k, piv, column);
        } else {
            lu_solve(a, k, piv, column);
        }
    }
    #[cfg(target_arch = "x86_64")]
    if (k == 3 || k == 4) && std::arch::is_x86_feature_detected!("avx2") {
        if let (Some(xr), Some(cr), Some(sr)) =
            (T::as_reals(x), T::as_reals(c), T::as_reals_mut(schur))
        {
            assert!(xr.len() == k * links.len() && cr.len() == k * links.len());
            assert!(sr.len() >= m * m);
            // SAFETY: the processor has AVX2 (checked just above), the lengths are checked
            // just above, and every link is below m (`Partition::with` checked them).
            unsafe {
                if k == 3 {
                    schur_update_small_real_avx2::<3>(xr, cr, links, sr, m);
                } else {
                    schur_update_small_real_avx2::<4>(xr, cr, links, sr, m);
                }
            }
            return;
        }
    }
    for (&q, xc) in links.iter().zip(x.chunks_exact(k)) {
        let s = &mut schur[q * m..q * m + m];
        for (&r, cr) in links.iter().zip(c.chunks_exact(k)) {
            let mut acc = T::ZERO;
            for i in 0..k {
                acc = acc + cr[i] * xc[i];
            }
            s[r] = s[r] - acc;
        }
    }
}

/// [`couple`]'s update of S for a real block of K = 3 or 4 states (the servo valve's blocks,
/// with 10 and 15 links: a dot product of K terms for each of up to 225 entries of S), four
/// links r at a time, with the same bits.
///
/// Each entry (r, q) is still `S_rq − (((0 + C_r0 X_q0) + C_r1 X_q1) + …)`, the same
/// multiplications and additions in the same order, never fused, only four r side by side in
/// a vector: C's entries of four rows are laid across the lanes once for all q, S's four entries
/// of column q are gathered and stored back one by one (they lie at the links' rows, not next
/// to each other). Every entry of S is updated once, so the order of the entries does not
/// matter. The last links, fewer than four, take the loops.
///
/// # Safety
///
/// The processor has AVX2, `x` and `c` hold K × links.len() entries, every link is below m, and
/// `schur` holds at least m × m entries.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn schur_update_small_real_avx2<const K: usize>(
    x: &[f64],
    c: &[f64],
    links: &[usize],
    schur: &mut [f64],
    m: usize,
) {
    use std::arch::x86_64::*;
    let l = links.len();
    let full = l - l % 4;
    for r0 in (0..full).step_by(4) {
        let rows = [links[r0], links[r0 + 1], links[r0 + 2], links[r0 + 3]];
        let mut cv = [_mm256_setzero_pd(); K];
        for (i, v) in cv.iter_mut().enumerate() {
            *v = _mm256_setr_pd(
                c[r0 * K + i],
                c[(r0 + 1) * K + i],
                c[(r0 + 2) * K + i],
                c[(r0 + 3) * K + i],
            );
        }
        let idx = _mm256_setr_epi64x(
            rows[0] as i64,
            rows[1] as i64,
            rows[2] as i64,
            rows[3] as i64,
        );
        for (&q, xq) in links.iter().zip(x.chunks_exact(K)) {
            let mut acc = _mm256_setzero_pd();
            for i in 0..K {
                acc = _mm256_add_pd(acc, _mm256_mul_pd(cv[i], _mm256_set1_pd(xq[i])));
            }
            // SAFETY: q and the rows are links, below m (the caller's promise), so column q's
            // entries q m + row lie below m² ≤ schur.len().
            unsafe {
                let base = schur.as_mut_ptr().add(q * m);
                let new = _mm256_sub_pd(_mm256_i64gather_pd::<8>(base, idx), acc);
                let (lo, hi) = (_mm256_castpd256_pd128(new), _mm256_extractf128_pd::<1>(new));
                _mm_storel_pd(base.add(rows[0]), lo);
                _mm_storeh_pd(base.add(rows[1]), lo);
                _mm_storel_pd(base.add(rows[2]), hi);
                _mm_storeh_pd(base.add(rows[3]), hi);
            }
        }
    }
    for (&q, xc) in links.iter().zip(x.chunks_exact(K)) {
        let s = &mut schur[q * m..q * m + m];
        for (&r, cr) in links[full..].iter().zip(c[full * K..].chunks_exact(K)) {
            let mut acc = 0.0;
            for i in 0..K {
                acc += cr[i] * xc[i];
            }
            s[r] -= acc;
        }
    }
}

/// [`couple`] for a block of one state (the plate's modes, twenty of the default plant's
/// blocks): the same operations in the same order, X_b's entries scaled by the block's one
/// factor `inv_a` (the pivot's reciprocal) and S's entries (r, q) less `0 + C_r X_q`, with S
/// indexed without a bounds check per entry: the links are below m, which `Partition::with`
/// checked when it made the partition, and `schur` is m × m (checked here).
#[inline(always)]
fn couple_one<T: Scalar>(
    inv_a: T,
    x: &mut [T],
    c: &[T],
    links: &[usize],
    schur: &mut [T],
    m: usize,
) {
    for v in x.iter_mut() {
        *v = *v * inv_a;
    }
    let schur = &mut schur[..m * m];
    for (&q, &xq) in links.iter().zip(x.iter()) {
        debug_assert!(q < m);
        for (&r, &cr) in links.iter().zip(c) {
            // SAFETY: q, r < m (`Partition::with` checked every link against the border's
            // size), so q m + r < m² = schur.len().
            let s = unsafe { get_mut(schur, q * m + r) };
            *s = *s - (T::ZERO + cr * xq);
        }
    }
}

/// The LU of one block or of the Schur complement in place ([`lu_in_place`]); with a `floor`
/// (a structured partition), false unless every pivot is above `floor` in the equilibrated
/// block ([`pivots_clear`]; `scratch` holds at least 3k entries).
fn factor_block<T: Scalar>(
    a: &mut [T],
    k: usize,
    piv: &mut [usize],
    floor: f64,
    scratch: &mut [f64],
) -> bool {
    if let ([a], [piv]) = (&mut *a, &mut *piv) {
        // A block of one state (the plate's modes): the same verdict and bits, directly.
        return factor_one(a, piv, floor);
    }
    if floor == 0.0 {
        return lu_in_place(a, k, piv);
    }
    scales(a, k, scratch);
    lu_in_place(a, k, piv) && pivots_clear(a, k, piv, scratch, floor)
}

/// Makes `v` at least `len` long, never shorter: the buffers serve partitions of different
/// sizes in turn (a structured one and its dense fallback, when the structured elimination fails
/// at every step), and a buffer resized down and up again at every factorisation had its grown
/// part zeroed each time, to be overwritten (every entry a factorisation or a solve reads is
/// written by the factorisation first, within the partition's lengths).
fn grow<V: Copy>(v: &mut Vec<V>, len: usize, zero: V) {
    if v.len() < len {
        v.resize(len, zero);
    }
}

/// Factorises `entry` with `part`, or with the dense partition if the structured elimination
/// fails (a small pivot inside a block); reuses `f`'s memory. False if M is singular.
pub(crate) fn factor_with_fallback<T: Scalar>(
    f: &mut Factorisation<T>,
    part: &Arc<Partition>,
    entry: impl Entries<T>,
) -> bool {
    if f.factor_by(part, &entry) {
        return true;
    }
    if part.is_dense() {
        return false;
    }
    let dense = match &f.dense_fallback {
        Some(d) if d.dim() == part.dim() => Arc::clone(d),
        _ => {
            let d = Arc::new(Partition::dense(part.dim()));
            f.dense_fallback = Some(Arc::clone(&d));
            d
        }
    };
    f.factor_by(&dense, &entry)
}

#[cfg(test)]
mod tests {
    use nalgebra::{Complex, DMatrix};

    use super::super::testing::{arrowhead, arrowhead_with_free, residual, Rng};
    use super::*;

    /// The solve as it was written before [`Factorisation::solve`] was flattened: block by
    /// block through [`Partition::block`] and [`lu_solve`], gathering into and scattering from
    /// the elimination order. The reference for the flat solve's bits.
    fn solve_blockwise<T: Scalar>(f: &Factorisation<T>, rhs: &mut [T], scratch: &mut [T]) {
        let p = &*f.part;
        let n = p.n;
        let nb = p.starts[p.blocks()];
        let m = n - nb;
        let s = &mut scratch[..n];
        for (dst, &i) in s.iter_mut().zip(&p.perm) {
            *dst = rhs[i];
        }
        let (blocks, border) = s.split_at_mut(nb);
        // y_b = A_b⁻¹ r_b, and the border's right-hand side r_B - Σ C_b y_b.
        let (mut lo, mut xo) = (0, 0);
        for b in 0..p.blocks() {
            let (st, k, links) = p.block(b);
            let y = &mut blocks[st..st + k];
            lu_solve(&f.lu[lo..lo + k * k], k, &f.piv[st..st + k], y);
            for (li, &q) in links.iter().enumerate() {
                let cr = &f.c[xo + li * k..xo + (li + 1) * k];
                let mut acc = T::ZERO;
                for i in 0..k {
                    acc = acc + cr[i] * y[i];
                }
                border[q] = border[q] - acc;
            }
            lo += k * k;
            xo += k * links.len();
        }
        lu_solve(&f.schur[..m * m], m, &f.schur_piv[..m], border);
        // x_b = y_b - X_b x_B.
        let mut xo = 0;
        for b in 0..p.blocks() {
            let (st, k, links) = p.block(b);
            let y = &mut blocks[st..st + k];
            for (li, &q) in links.iter().enumerate() {
                let v = border[q];
                let xc = &f.x[xo + li * k..xo + (li + 1) * k];
                for i in 0..k {
                    y[i] = y[i] - xc[i] * v;
                }
            }
            xo += k * links.len();
        }
        for (src, &i) in s.iter().zip(&p.perm) {
            rhs[i] = *src;
        }
    }

    /// The portable loops' LU with the structured partition's pivot test (`factor_block`).
    fn loops_with_floor<T: Scalar>(a: &mut [T], k: usize, piv: &mut [usize], floor: f64) -> bool {
        let mut scratch = vec![0.0; 3 * k];
        scales(a, k, &mut scratch);
        super::super::lu::lu_in_place_loops(a, k, piv)
            && (floor == 0.0 || pivots_clear(a, k, piv, &mut scratch, floor))
    }

    /// The factorisation as it was written before its gathers and its couplings' loops were
    /// specialised: entry by entry, one solve per column of X_b, and the Schur update pair of
    /// links by pair. The reference for [`Factorisation::factor`]'s bits.
    fn factor_entrywise<T: Scalar, E: Entries<T>>(
        f: &mut Factorisation<T>,
        part: &Arc<Partition>,
        entry: &E,
    ) -> bool {
        f.part = Arc::clone(part);
        let p = &*f.part;
        let n = p.n;
        let nb = p.starts[p.blocks()];
        let m = n - nb;
        let floor = if p.is_dense() { 0.0 } else { PIVOT_FLOOR };
        f.lu = vec![T::ZERO; p.lu_len];
        f.x = vec![T::ZERO; p.x_len];
        f.c = vec![T::ZERO; p.x_len];
        f.piv = vec![0; n];
        f.schur = vec![T::ZERO; m * m];
        f.schur_piv = vec![0; m];
        for at in p.linked.iter().chain(&p.free) {
            let (s, k) = (at.start, at.size);
            let idx = &p.perm[s..s + k];
            let a = &mut f.lu[at.lu..at.lu + k * k];
            for cj in 0..k {
                for r in 0..k {
                    a[r + cj * k] = entry.entry(idx[r], idx[cj]);
                }
            }
            if !loops_with_floor(a, k, &mut f.piv[s..s + k], floor) {
                return false;
            }
        }
        let border = &p.perm[nb..];
        for q in 0..m {
            for r in 0..m {
                f.schur[r + q * m] = entry.entry(border[r], border[q]);
            }
        }
        for at in &p.linked {
            let (s, k) = (at.start, at.size);
            let links = &p.links[at.links_from..at.links_to];
            let idx = &p.perm[s..s + k];
            let a = &f.lu[at.lu..at.lu + k * k];
            let l = links.len();
            let x = &mut f.x[at.x..at.x + k * l];
            let c = &mut f.c[at.x..at.x + k * l];
            for (li, &q) in links.iter().enumerate() {
                let col = &mut x[li * k..(li + 1) * k];
                for r in 0..k {
                    col[r] = entry.entry(idx[r], border[q]);
                    c[li * k + r] = entry.entry(border[q], idx[r]);
                }
                super::super::lu::lu_solve_loops(a, k, &f.piv[s..s + k], col);
            }
            for (l2, &q) in links.iter().enumerate() {
                let xc = &x[l2 * k..(l2 + 1) * k];
                for (l1, &r) in links.iter().enumerate() {
                    let cr = &c[l1 * k..(l1 + 1) * k];
                    let mut acc = T::ZERO;
                    for i in 0..k {
                        acc = acc + cr[i] * xc[i];
                    }
                    f.schur[r + q * m] = f.schur[r + q * m] - acc;
                }
            }
        }
        loops_with_floor(&mut f.schur[..m * m], m, &mut f.schur_piv[..m], floor)
    }

    /// A random arrowhead matrix with blocks of the given sizes (dense inside, each state
    /// coupled to a random subset of the `m` border states, some blocks to none), states
    /// shuffled, exact zeros sprinkled among the couplings.
    fn arrowhead_of_sizes(rng: &mut Rng, sizes: &[usize], m: usize) -> DMatrix<f64> {
        let nb: usize = sizes.iter().sum();
        let n = nb + m;
        let mut a = DMatrix::zeros(n, n);
        let mut s = 0;
        for (b, &k) in sizes.iter().enumerate() {
            for i in s..s + k {
                for j in s..s + k {
                    a[(i, j)] = rng.next();
                }
                a[(i, i)] += 4.0;
                for q in nb..n {
                    if b % 7 != 6 && rng.next() > 0.2 {
                        a[(i, q)] = if rng.next() > 0.9 { 0.0 } else { rng.next() };
                        a[(q, i)] = rng.next();
                    }
                }
            }
            s += k;
        }
        for i in nb..n {
            for j in nb..n {
                a[(i, j)] = rng.next();
            }
        }
        let mut perm: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            let j = ((rng.next() + 1.0) / 2.0 * (i + 1) as f64) as usize % (i + 1);
            perm.swap(i, j);
        }
        DMatrix::from_fn(n, n, |i, j| a[(perm[i], perm[j])])
    }

    /// [`Factorisation::factor`] (its gathers, the unrolled couplings of blocks of one to four
    /// states and the general one, the small blocks' unrolled LUs) gives the bits of the entry
    /// by entry factorisation, and so do the solves from it: random arrowhead matrices with
    /// blocks of one to nine states, mostly of one, factorised from [`Shifted`] and from a
    /// closure, real and complex.
    #[test]
    fn the_factorisation_has_the_entrywise_bits() {
        fn check<T: Scalar, E: Entries<T>>(part: &Arc<Partition>, entry: E, b: &[T]) {
            let mut reference = Factorisation::new(Arc::clone(part));
            assert!(factor_entrywise(&mut reference, part, &entry));
            let mut f = Factorisation::new(Arc::clone(part));
            assert!(f.factor(part, entry));
            let factors = |f: &Factorisation<T>| {
                let p = &*f.part;
                let m = p.border();
                format!(
                    "{:?} {:?} {:?} {:?} {:?} {:?}",
                    &f.lu[..p.lu_len],
                    &f.piv[..p.n],
                    &f.x[..p.x_len],
                    &f.c[..p.x_len],
                    &f.schur[..m * m],
                    &f.schur_piv[..m]
                )
            };
            assert_eq!(factors(&f), factors(&reference));
            let (mut x, mut x_ref) = (b.to_vec(), b.to_vec());
            let mut scratch = vec![T::ZERO; b.len()];
            f.solve(&mut x, &mut scratch);
            solve_blockwise(&reference, &mut x_ref, &mut scratch);
            assert_eq!(format!("{x:?}"), format!("{x_ref:?}"));
        }
        let mut rng = Rng(0x6a09_e667_f3bc_c909);
        let mut seen = [false; 6];
        for sizes in [
            &[1, 1, 3, 3, 1, 1, 4, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1][..],
            &[2, 1, 5, 1, 2, 9, 1, 1, 3, 4, 1, 6, 1, 2][..],
            &[1; 40][..],
        ] {
            for m in [3, 9, 17] {
                let j = arrowhead_of_sizes(&mut rng, sizes, m);
                let n = j.nrows();
                let part = Arc::new(Partition::of_matrix(&j));
                if part.is_dense() {
                    continue;
                }
                for at in &part.linked {
                    seen[at.size.min(5)] = true;
                }
                let b: Vec<f64> = (0..n)
                    .map(|i| if i % 6 == 0 { 0.0 } else { rng.next() })
                    .collect();
                let c = 1.0 / (1e-3 * 0.21193756319429014);
                check(&part, Shifted { c, jac: &j }, &b);
                check(
                    &part,
                    |i, jj| if i == jj { c } else { 0.0 } - j[(i, jj)],
                    &b,
                );
                let bc: Vec<Complex<f64>> = b.iter().map(|&v| Complex::new(v, 0.5 * v)).collect();
                check(&part, shifted_complex(&j, Complex::new(2.0, 1.5)), &bc);
            }
        }
        assert_eq!(
            seen,
            [false, true, true, true, true, true],
            "block sizes covered"
        );
    }

    /// [`couple`] gives the loops' bits for real blocks of three and four states (whose update
    /// of S is [`schur_update_small_real_avx2`]'s where the processor has AVX2), for every
    /// number of links from none to 19, with exact zeros among X's and C's entries.
    #[test]
    fn the_small_blocks_coupling_has_the_loops_bits() {
        let mut rng = Rng(0x510e_527f_ade6_82d1);
        let m = 23;
        for k in [3, 4] {
            for l in 0..=19 {
                let mut a: Vec<f64> = (0..k * k).map(|_| rng.next()).collect();
                let mut piv = vec![0; k];
                assert!(super::super::lu::lu_in_place_loops(&mut a, k, &mut piv));
                let mut links: Vec<usize> = (0..m).collect();
                for i in (1..m).rev() {
                    let j = ((rng.next() + 1.0) / 2.0 * (i + 1) as f64) as usize % (i + 1);
                    links.swap(i, j);
                }
                links.truncate(l);
                links.sort_unstable();
                let zeroed = |rng: &mut Rng| {
                    let v = rng.next();
                    if v.abs() < 0.15 {
                        0.0
                    } else {
                        v
                    }
                };
                let x: Vec<f64> = (0..k * l).map(|_| zeroed(&mut rng)).collect();
                let c: Vec<f64> = (0..k * l).map(|_| zeroed(&mut rng)).collect();
                let schur: Vec<f64> = (0..m * m).map(|_| zeroed(&mut rng)).collect();
                let (mut x_fast, mut s_fast) = (x.clone(), schur.clone());
                couple(k, &a, &piv, &mut x_fast, &c, &links, &mut s_fast, m);
                let (mut x_loops, mut s_loops) = (x, schur);
                for column in x_loops.chunks_exact_mut(k) {
                    super::super::lu::lu_solve_loops(&a, k, &piv, column);
                }
                for (&q, xc) in links.iter().zip(x_loops.chunks_exact(k)) {
                    for (&r, cr) in links.iter().zip(c.chunks_exact(k)) {
                        let mut acc = 0.0;
                        for i in 0..k {
                            acc += cr[i] * xc[i];
                        }
                        s_loops[r + q * m] -= acc;
                    }
                }
                let bits = |v: &[f64]| v.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&x_fast), bits(&x_loops), "k = {k}, {l} links");
                assert_eq!(bits(&s_fast), bits(&s_loops), "k = {k}, {l} links");
            }
        }
    }

    /// `c I − J` entry by entry with a complex shift (Radau5's complex matrix).
    fn shifted_complex(
        j: &DMatrix<f64>,
        c: Complex<f64>,
    ) -> impl Fn(usize, usize) -> Complex<f64> + '_ {
        move |i, jj| {
            let d = if i == jj {
                c
            } else {
                <Complex<f64> as Scalar>::ZERO
            };
            d - Complex::new(j[(i, jj)], 0.0)
        }
    }

    /// The solve with the border's right-hand side made border state by border state gives
    /// the bits of the block after block one (`solve_blockwise`), compiled for AVX2 and
    /// not: random partitions (blocks of one to five states, up to a dozen, borders of none to
    /// twenty states, each block linked to a random subset of the border, some to none),
    /// random factors with exact zeros and negative zeros (mostly zeros in every third round,
    /// so that signed zeros reach the results), right-hand sides with zeros,
    /// negative zeros and, in turn, infinities (the factors too) or NaNs (the factors finite:
    /// the bits of NaN meeting NaN depend on the operands' order, which an addition does not
    /// fix); real and complex.
    #[test]
    fn the_solve_by_border_states_has_the_blocks_first_bits() {
        fn pick(rng: &mut Rng, below: usize) -> usize {
            ((rng.next() + 1.0) / 2.0 * below as f64) as usize % below.max(1)
        }
        /// A value: random, or (each with probability `special`) 0, -0, or one of `extra`.
        fn value(rng: &mut Rng, special: f64, extra: &[f64]) -> f64 {
            let u = (rng.next() + 1.0) / 2.0;
            if u >= special {
                return rng.next();
            }
            let choices = 2 + extra.len();
            match pick(rng, choices) {
                0 => 0.0,
                1 => -0.0,
                i => extra[i - 2],
            }
        }
        fn random_partition(rng: &mut Rng) -> Partition {
            let blocks = 1 + pick(rng, 12);
            let sizes: Vec<usize> = (0..blocks).map(|_| 1 + pick(rng, 5)).collect();
            let m = pick(rng, 21);
            let nb: usize = sizes.iter().sum();
            let n = nb + m;
            let mut perm: Vec<usize> = (0..n).collect();
            for i in (1..n).rev() {
                perm.swap(i, pick(rng, i + 1));
            }
            let mut starts = vec![0];
            for &k in &sizes {
                starts.push(starts[starts.len() - 1] + k);
            }
            let (mut links, mut link_starts) = (Vec::new(), vec![0]);
            for _ in 0..blocks {
                let density = (rng.next() + 1.0) / 2.0;
                if rng.next() > -0.6 {
                    links.extend((0..m).filter(|_| (rng.next() + 1.0) / 2.0 < density));
                }
                link_starts.push(links.len());
            }
            Partition::with(n, perm, starts, links, link_starts)
        }
        /// Made-up factors (the solves need no consistency, only valid interchanges).
        fn made_up<T: Scalar>(
            part: &Arc<Partition>,
            rng: &mut Rng,
            v: &mut impl FnMut(&mut Rng) -> T,
        ) -> Factorisation<T> {
            let p = &**part;
            let m = p.border();
            let mut f = Factorisation::new(Arc::clone(part));
            f.lu = (0..p.lu_len).map(|_| v(rng)).collect();
            f.x = (0..p.x_len).map(|_| v(rng)).collect();
            f.c = (0..p.x_len).map(|_| v(rng)).collect();
            f.schur = (0..m * m).map(|_| v(rng)).collect();
            f.piv = vec![0; p.n];
            for b in 0..p.blocks() {
                let (s, k, _) = p.block(b);
                for j in 0..k {
                    f.piv[s + j] = j + pick(rng, k - j);
                }
            }
            f.schur_piv = (0..m).map(|j| j + pick(rng, m - j)).collect();
            f
        }
        fn check<T: Scalar>(f: &Factorisation<T>, b: &[T], bits: impl Fn(&[T]) -> Vec<u64>) {
            let n = b.len();
            let (mut reference, mut solved, mut portable) = (b.to_vec(), b.to_vec(), b.to_vec());
            let mut scratch = vec![T::ZERO; n];
            solve_blockwise(f, &mut reference, &mut scratch);
            f.solve(&mut solved, &mut scratch);
            f.solve_passes(&mut portable, &mut scratch);
            assert_eq!(bits(&solved), bits(&reference), "{:?}", f.part);
            assert_eq!(bits(&portable), bits(&reference), "{:?}", f.part);
        }
        let real = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let complex = |v: &[Complex<f64>]| {
            v.iter()
                .flat_map(|z| [z.re.to_bits(), z.im.to_bits()])
                .collect::<Vec<_>>()
        };
        let mut rng = Rng(0x9b05_688c_2b3e_6c1f);
        let (inf, nan) = (f64::INFINITY, f64::NAN);
        let mut seen = [false; 6];
        for round in 0..3000 {
            let part = Arc::new(random_partition(&mut rng));
            for at in &part.linked {
                seen[at.size] = true;
            }
            let n = part.dim();
            let (factor_extra, rhs_extra): (&[f64], &[f64]) = if round % 2 == 0 {
                (&[inf, -inf], &[inf, -inf])
            } else {
                (&[], &[nan])
            };
            // Mostly zeros every third round, so that signed zeros reach the results.
            let special = if round % 3 == 2 { 0.8 } else { 0.25 };
            let f = made_up(&part, &mut rng, &mut |r: &mut Rng| {
                value(r, special, factor_extra)
            });
            let b: Vec<f64> = (0..n)
                .map(|_| value(&mut rng, special, rhs_extra))
                .collect();
            check(&f, &b, real);
            if round % 5 == 0 {
                let f = made_up(&part, &mut rng, &mut |r: &mut Rng| {
                    Complex::new(value(r, 0.2, &[]), value(r, 0.2, &[]))
                });
                let b: Vec<Complex<f64>> = (0..n)
                    .map(|_| Complex::new(value(&mut rng, 0.3, &[]), value(&mut rng, 0.3, &[])))
                    .collect();
                check(&f, &b, complex);
            }
        }
        assert_eq!(
            seen,
            [false, true, true, true, true, true],
            "linked block sizes"
        );
    }

    /// The flat solve gives the bits of the block-by-block one, for blocks of one, two and
    /// three states, linked to the border and free, real and complex, with zeros in the
    /// right-hand side (which the written-out blocks skip as the loops do).
    #[test]
    fn the_flat_solve_has_the_blockwise_bits() {
        fn check<T: Scalar>(part: &Arc<Partition>, entry: impl Fn(usize, usize) -> T, b: &[T]) {
            let mut f = Factorisation::new(Arc::clone(part));
            assert!(f.factor(part, entry));
            let n = b.len();
            let (mut flat, mut blockwise) = (b.to_vec(), b.to_vec());
            let mut scratch = vec![T::ZERO; n];
            f.solve(&mut flat, &mut scratch);
            solve_blockwise(&f, &mut blockwise, &mut scratch);
            assert_eq!(format!("{flat:?}"), format!("{blockwise:?}"));
        }
        let mut rng = Rng(0x2545_f491_4f6c_dd1d);
        for &(blocks, k, m) in &[(30, 2, 4), (60, 1, 3), (12, 3, 5)] {
            let j = arrowhead_with_free(&mut rng, blocks, k, m, 3);
            let n = j.nrows();
            let part = Arc::new(Partition::of_matrix(&j));
            assert!(!part.is_dense());
            assert!(!part.free.is_empty() && !part.linked.is_empty());
            let b: Vec<f64> = (0..n)
                .map(|i| if i % 5 == 0 { 0.0 } else { rng.next() })
                .collect();
            check(
                &part,
                |i, jj| if i == jj { 3.0 } else { 0.0 } - j[(i, jj)],
                &b,
            );
            let bc: Vec<Complex<f64>> = b.iter().map(|&v| Complex::new(v, 0.5 * v)).collect();
            check(&part, shifted_complex(&j, Complex::new(2.0, 1.5)), &bc);
        }
    }

    #[test]
    fn complex_arrowhead_matches_the_dense_lu() {
        let mut rng = Rng(7);
        let j = arrowhead(&mut rng, 40, 2, 6);
        let n = j.nrows();
        let part = Arc::new(Partition::of_matrix(&j));
        assert!(!part.is_dense());
        let shift = Complex::new(2.5, 1.7);
        let entry = |i: usize, jj: usize| {
            let d = if i == jj { shift } else { Complex::ZERO };
            d - Complex::new(j[(i, jj)], 0.0)
        };
        let mut f = Factorisation::new(Arc::clone(&part));
        assert!(f.factor(&part, entry));
        let b: Vec<Complex<f64>> = (0..n)
            .map(|_| Complex::new(rng.next(), rng.next()))
            .collect();
        let mut x = b.clone();
        let mut scratch = vec![Complex::ZERO; n];
        f.solve(&mut x, &mut scratch);
        let m_dense = DMatrix::from_fn(n, n, entry);
        let reference = m_dense.lu().solve(&nalgebra::DVector::from(b)).unwrap();
        let diff = x
            .iter()
            .zip(reference.iter())
            .map(|(a, r)| (a - r).norm())
            .fold(0.0, f64::max);
        let scale = reference.iter().map(|v| v.norm()).fold(0.0, f64::max);
        assert!(diff <= 1e-11 * scale, "{diff:e} vs {scale:e}");
    }

    #[test]
    fn singular_matrices_are_reported_and_bad_blocks_fall_back_to_dense() {
        // Exactly singular: two equal rows.
        let mut m = DMatrix::from_fn(4, 4, |i, j| (i * 4 + j) as f64 + 1.0);
        m.set_row(3, &m.row(0).clone_owned());
        let part = Arc::new(Partition::dense(4));
        let mut f = Factorisation::new(Arc::clone(&part));
        assert!(!factor_with_fallback(&mut f, &part, |i, j| m[(i, j)]));
        // A block that is singular on its own inside a regular matrix: the border rescues it
        // only with pivoting across blocks, which the dense fallback does.
        let mut rng = Rng(11);
        let mut j = arrowhead(&mut rng, 30, 2, 3);
        let part = Arc::new(Partition::of_matrix(&j));
        assert!(!part.is_dense());
        let (s, _, _) = part.block(0);
        let v = part.perm[s];
        for c in 0..j.ncols() {
            if part.perm[..part.starts[part.blocks()]].contains(&c) {
                j[(v, c)] = 0.0; // row v vanishes inside its block...
            }
        }
        let (_, _, links) = part.block(0);
        let nb = part.starts[part.blocks()];
        let q = part.perm[nb + links.first().copied().unwrap_or(0)];
        j[(v, q)] = 1.0; // ...but not towards the border
        let n = j.nrows();
        let entry = |i: usize, k: usize| j[(i, k)];
        let mut f = Factorisation::new(Arc::clone(&part));
        assert!(!f.factor(&part, entry));
        let dense_ok = DMatrix::from_fn(n, n, entry).lu().is_invertible();
        assert_eq!(factor_with_fallback(&mut f, &part, entry), dense_ok);
        if dense_ok {
            assert!(f.partition().is_dense());
            let b: Vec<f64> = (0..n).map(|_| rng.next()).collect();
            let mut x = b.clone();
            f.solve(&mut x, &mut vec![0.0; n]);
            assert!(residual(n, entry, &x, &b) < 1e-9);
        }
    }

    /// The blocks' pivot test does not depend on the states' units: an arrowhead matrix whose
    /// rows and columns are scaled by powers of ten up to 1e±8 (so that entries of one block
    /// differ by up to 1e32, beyond the 1e10 a test against the block's largest entry allows) is
    /// factorised with its structure and solves to rounding; a block singular to rounding stays
    /// refused whatever its rows' scales.
    #[test]
    fn the_pivot_test_is_the_equilibrated_blocks() {
        let mut rng = Rng(23);
        for round in 0..20 {
            let j = arrowhead(&mut rng, 40, 2, 4);
            let n = j.nrows();
            let part = Arc::new(Partition::of_matrix(&j));
            assert!(!part.is_dense());
            let mut scale = || 10f64.powi((8.0 * rng.next()) as i32);
            let row: Vec<f64> = (0..n).map(|_| scale()).collect();
            let col: Vec<f64> = (0..n).map(|_| scale()).collect();
            let c = 3.0;
            let scaled = |i: usize, k: usize| {
                let m = if i == k { c - j[(i, k)] } else { -j[(i, k)] };
                row[i] * m * col[k]
            };
            let mut f = Factorisation::new(Arc::clone(&part));
            assert!(f.factor(&part, scaled), "round {round}: refused");
            let b: Vec<f64> = (0..n).map(|_| rng.next()).collect();
            let mut x = b.clone();
            f.solve(&mut x, &mut vec![0.0; n]);
            // each row's residual relative to the size of its terms
            let worst = (0..n)
                .map(|i| {
                    let terms = (0..n).map(|k| scaled(i, k) * x[k]);
                    let size = terms.clone().map(f64::abs).fold(b[i].abs(), f64::max);
                    (terms.sum::<f64>() - b[i]).abs() / size
                })
                .fold(0.0, f64::max);
            assert!(worst < 1e-12, "round {round}: relative residual {worst:e}");
        }
        // A block singular to rounding, one row scaled by 1e6: refused (the dense LU's job).
        let mut j = arrowhead(&mut rng, 10, 2, 3);
        let part = Arc::new(Partition::of_matrix(&j));
        let (s, _, _) = part.block(0);
        let (u, v) = (part.perm[s], part.perm[s + 1]);
        for k in [u, v] {
            j[(v, k)] = j[(u, k)] * (1.0 + 1e-15);
        }
        let entry = |i: usize, k: usize| if i == v { 1e6 * j[(i, k)] } else { j[(i, k)] };
        let mut f = Factorisation::new(Arc::clone(&part));
        assert!(!f.factor(&part, entry));
    }

    /// [`Shifted`]'s columns and gathered submatrices are its entries, bit for bit, and so is
    /// the dense factorisation
    /// made from them: the same operations (a negation, c − J_jj on the diagonal), only without
    /// indexing each entry.
    #[test]
    fn shifted_columns_are_its_entries_bit_for_bit() {
        let mut rng = Rng(5);
        let n = 23;
        let jac = DMatrix::from_fn(n, n, |_, _| rng.next() - 0.5);
        let c = 1.0 / (1e-3 * 0.21193756319429014);
        let shifted = Shifted { c, jac: &jac };
        let closure = |i: usize, j: usize| {
            if i == j {
                c - jac[(i, j)]
            } else {
                -jac[(i, j)]
            }
        };
        for j in 0..n {
            for len in [n, j + 1, j, 1] {
                let mut column = vec![f64::NAN; len];
                shifted.leading_column(j, &mut column);
                for (r, v) in column.iter().enumerate() {
                    assert_eq!(v.to_bits(), closure(r, j).to_bits(), "({r}, {j}) of {len}");
                    assert_eq!(v.to_bits(), shifted.entry(r, j).to_bits());
                }
            }
        }
        let at: Vec<usize> = (0..60).map(|e| (e * 37 + e / 3) % (n * n)).collect();
        let diagonal: Vec<usize> = (0..60).filter(|&e| at[e].is_multiple_of(n + 1)).collect();
        assert!(!diagonal.is_empty());
        let mut gathered = vec![f64::NAN; at.len()];
        assert!(shifted.gather_at(n, &at, &diagonal, &mut gathered));
        for (v, &a) in gathered.iter().zip(&at) {
            let bits = closure(a % n, a / n).to_bits();
            assert_eq!(v.to_bits(), bits, "({}, {})", a % n, a / n);
        }
        assert!(!shifted.gather_at(n + 1, &at, &diagonal, &mut gathered));
        let part = Arc::new(Partition::dense(n));
        let (mut by_columns, mut by_entries) = (
            Factorisation::new(Arc::clone(&part)),
            Factorisation::new(Arc::clone(&part)),
        );
        assert!(by_columns.factor(&part, Shifted { c, jac: &jac }));
        assert!(by_entries.factor(&part, closure));
        let bits = |f: &Factorisation<f64>| f.lu.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&by_columns), bits(&by_entries));
    }

    /// A factorisation whose memory served a larger partition before (the buffers only grow)
    /// factorises and solves to the same bits as a fresh one: a structured partition after the
    /// dense one, and the dense one again after it.
    #[test]
    fn reused_memory_of_another_partition_gives_the_same_bits_as_fresh_memory() {
        let mut rng = Rng(17);
        let j = arrowhead(&mut rng, 12, 2, 3);
        let n = j.nrows();
        let entry = |i: usize, k: usize| j[(i, k)];
        let structured = Arc::new(Partition::of_matrix(&j));
        assert!(!structured.is_dense());
        let dense = Arc::new(Partition::dense(n));
        let b: Vec<f64> = (0..n).map(|_| rng.next()).collect();
        let solved = |f: &Factorisation<f64>| {
            let mut x = b.clone();
            f.solve(&mut x, &mut vec![0.0; n]);
            x.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        };
        let mut reused = Factorisation::new(Arc::clone(&dense));
        for part in [&dense, &structured, &dense, &structured] {
            let mut fresh = Factorisation::new(Arc::clone(part));
            assert!(fresh.factor(part, entry));
            assert!(reused.factor(part, entry));
            assert_eq!(solved(&reused), solved(&fresh));
        }
    }
}
