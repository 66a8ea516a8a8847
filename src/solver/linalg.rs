//! LU factorisation of the iteration matrices that uses their sparsity: bordered
//! block-diagonal (Schur complement) elimination, with the dense LU as its special case.
//!
//! Both methods solve with a matrix `M = c I - J` (Rodas5P: real c = 1/(h γ); Radau5: a real
//! and a complex one). In a model whose parts meet only at a few states (the plate's modes
//! meet only at the hub and the torsion bar), most states form small groups that are coupled
//! with each other only through a few *border* states. Ordered group after group with the border
//! last, M is bordered block-diagonal ("arrowhead"):
//!
//! ```text
//!     [ A_1           B_1 ]
//!     [      ...      ... ]      A_b: small square blocks (a group's states)
//! M = [           A_k B_k ]      D:   the border (m × m)
//!     [ C_1  ...  C_k  D  ]
//! ```
//!
//! and it is factorised block by block: an LU with partial pivoting of every A_b,
//! X_b = A_b⁻¹ B_b, and a dense LU of the Schur complement S = D - Σ C_b X_b. A solve is then
//! a forward pass over the blocks, a solve with S for the border, and a back substitution
//! x_b = y_b - X_b x_border. Work and memory grow with Σ k_b³ + m³ (factorisation) and
//! Σ k_b² + m² (solve) plus the couplings, instead of n³ and n².
//!
//! [`Partition::detect`] finds the groups and the border from the nonzero pattern of J alone
//! (nothing about the model): it moves the state with the most neighbours into the border until
//! the estimated work stops falling, and keeps the best split it saw; if that split does not
//! save at least half of the dense work it returns the dense partition (one block holding every
//! state, no border), which is an ordinary LU with partial pivoting. The elimination does not
//! pivot across blocks, so a block whose pivots are small against its own entries (or an exactly
//! singular one) makes [`Factorisation::factor`] report failure; the caller then factorises
//! with the dense partition, which fails only if M is singular.
//!
//! Everything is deterministic (the same J gives the same partition and the same bits), which
//! keeps a restored integrator, which refactorises, bit-identical to the original.
//! [`Factorisation::factor`] reuses the memory of the previous factorisation, and
//! [`Factorisation::solve`] takes the caller's scratch vector, so neither allocates once warm.

// Index loops mirror the elimination formulas.
#![allow(clippy::needless_range_loop)]

use std::ops::{Add, Div, Mul, Neg, Sub};
use std::sync::Arc;

use nalgebra::{Complex, DMatrix};

/// The scalars the iteration matrices have: f64 (Rodas5P, Radau5's real system) and
/// `Complex<f64>` (Radau5's complex system).
pub trait Scalar:
    Copy
    + PartialEq
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + std::fmt::Debug
{
    const ZERO: Self;
    const ONE: Self;
    /// |re| + |im|, the pivot size LAPACK's `izamax` uses.
    fn norm1(self) -> f64;
}

impl Scalar for f64 {
    const ZERO: f64 = 0.0;
    const ONE: f64 = 1.0;
    #[inline]
    fn norm1(self) -> f64 {
        self.abs()
    }
}

impl Scalar for Complex<f64> {
    const ZERO: Complex<f64> = Complex { re: 0.0, im: 0.0 };
    const ONE: Complex<f64> = Complex { re: 1.0, im: 0.0 };
    #[inline]
    fn norm1(self) -> f64 {
        self.re.abs() + self.im.abs()
    }
}

/// Solves per factorisation assumed by the work estimate (Rodas5P makes 8 per step, Radau5 about
/// 3 per Newton iteration, and a constant Jacobian's factorisation serves many steps).
const SOLVES_PER_FACTORISATION: f64 = 10.0;

/// The structured split is used only if it needs at most this share of the dense work.
const STRUCTURED_SHARE: f64 = 0.5;

/// A block whose smallest pivot is below this share of its largest entry is left to the dense
/// LU: elimination inside blocks does not pivot across them.
const PIVOT_FLOOR: f64 = 1e-10;

/// Groups and border of the states (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct Partition {
    n: usize,
    /// The states in elimination order: block after block, then the border.
    perm: Vec<usize>,
    /// Block b holds positions `starts[b]..starts[b + 1]` of `perm`; the border is
    /// `perm[nb..]` with `nb = starts[k]`.
    starts: Vec<usize>,
    /// Border positions (0-based within the border) coupled to block b, ascending:
    /// `links[link_starts[b]..link_starts[b + 1]]`.
    links: Vec<usize>,
    link_starts: Vec<usize>,
    /// Where each block's data lie, precomputed for the solves (see [`BlockAt`]): the blocks
    /// coupled to the border, and apart the free ones (no link to the border), which a solve
    /// finishes in one go (a plate mode that no force of the hub excites is one).
    linked: Vec<BlockAt>,
    free: Vec<BlockAt>,
    /// Numbers of the blocks' LUs (Σ k²) and of their X_b (and C_b) (Σ k × links), which
    /// [`BlockAt::lu`] and [`BlockAt::x`] lay out one block after the other.
    lu_len: usize,
    x_len: usize,
}

/// One block's place in the partition and in the factors: what a solve would otherwise
/// recompute from `starts` and `link_starts` block by block.
#[derive(Clone, Copy, Debug, PartialEq)]
struct BlockAt {
    /// First position of the block in `perm`.
    start: usize,
    /// Its size k.
    size: usize,
    /// Offset of its k × k LU in the factors.
    lu: usize,
    /// Offset of its X_b and C_b (k × links numbers each).
    x: usize,
    /// Its border links: `links[links_from..links_to]`.
    links_from: usize,
    links_to: usize,
}

impl Partition {
    /// The partition with these fields, and the offsets derived from them.
    fn with(
        n: usize,
        perm: Vec<usize>,
        starts: Vec<usize>,
        links: Vec<usize>,
        link_starts: Vec<usize>,
    ) -> Partition {
        let (mut linked, mut free) = (Vec::new(), Vec::new());
        let (mut lu, mut x) = (0, 0);
        for b in 0..starts.len() - 1 {
            let (start, size) = (starts[b], starts[b + 1] - starts[b]);
            let (links_from, links_to) = (link_starts[b], link_starts[b + 1]);
            let at = BlockAt {
                start,
                size,
                lu,
                x,
                links_from,
                links_to,
            };
            if links_to > links_from {
                linked.push(at);
            } else {
                free.push(at);
            }
            lu += size * size;
            x += size * (links_to - links_from);
        }
        Partition {
            n,
            perm,
            starts,
            links,
            link_starts,
            linked,
            free,
            lu_len: lu,
            x_len: x,
        }
    }

    /// One block holding every state in natural order, no border: a dense LU.
    pub fn dense(n: usize) -> Partition {
        Partition::with(n, (0..n).collect(), vec![0, n], Vec::new(), vec![0, 0])
    }

    /// The split of the states of an n × n matrix whose off-diagonal nonzeros are
    /// `(i, j)` for `nonzero(i, j)` (the diagonal is taken as nonzero).
    pub fn detect(n: usize, nonzero: impl Fn(usize, usize) -> bool) -> Partition {
        // Symmetrised adjacency without the diagonal.
        let mut adj: Vec<Vec<usize>> = vec![Vec::new(); n];
        for j in 0..n {
            for i in 0..n {
                if i != j && nonzero(i, j) {
                    adj[i].push(j);
                    adj[j].push(i);
                }
            }
        }
        for a in &mut adj {
            a.sort_unstable();
            a.dedup();
        }
        let dense_cost = work(&[n], &[0], 0);
        let mut in_border = vec![false; n];
        let mut degree: Vec<usize> = adj.iter().map(Vec::len).collect();
        let mut border: Vec<usize> = Vec::new();
        let mut best = (f64::INFINITY, 0usize);
        let mut comp = Components::default();
        loop {
            comp.find(&adj, &in_border);
            let cost = work(&comp.sizes, &comp.link_counts, border.len());
            if cost < best.0 {
                best = (cost, border.len());
            }
            if cost > 2.0 * best.0 || 2 * border.len() >= n {
                break;
            }
            // The state with the most neighbours outside the border (the first of equals).
            let Some(v) = (0..n)
                .filter(|&v| !in_border[v] && degree[v] > 0)
                .max_by(|&a, &b| degree[a].cmp(&degree[b]).then(b.cmp(&a)))
            else {
                break;
            };
            in_border[v] = true;
            border.push(v);
            for &u in &adj[v] {
                degree[u] -= 1;
            }
        }
        if best.0 > STRUCTURED_SHARE * dense_cost || best.1 == 0 {
            return Partition::dense(n);
        }
        border.truncate(best.1);
        border.sort_unstable();
        in_border.fill(false);
        for &v in &border {
            in_border[v] = true;
        }
        comp.find(&adj, &in_border);
        let mut border_pos = vec![usize::MAX; n];
        for (p, &v) in border.iter().enumerate() {
            border_pos[v] = p;
        }
        // Blocks in the order of their first state; states ascending inside a block.
        let mut perm = Vec::with_capacity(n);
        let mut starts = vec![0];
        let mut links = Vec::new();
        let mut link_starts = vec![0];
        for members in comp.members() {
            perm.extend_from_slice(&members);
            starts.push(perm.len());
            let first = links.len();
            for &v in &members {
                links.extend(
                    adj[v]
                        .iter()
                        .filter(|&&u| in_border[u])
                        .map(|&u| border_pos[u]),
                );
            }
            links[first..].sort_unstable();
            let mut unique = first;
            for r in first..links.len() {
                if r == first || links[r] != links[unique - 1] {
                    links[unique] = links[r];
                    unique += 1;
                }
            }
            links.truncate(unique);
            link_starts.push(links.len());
        }
        perm.extend_from_slice(&border);
        Partition::with(n, perm, starts, links, link_starts)
    }

    /// The split for the nonzero pattern of a dense matrix.
    pub fn of_matrix(m: &DMatrix<f64>) -> Partition {
        Partition::detect(m.nrows(), |i, j| m[(i, j)] != 0.0)
    }

    /// Number of states.
    pub fn dim(&self) -> usize {
        self.n
    }
    /// Number of independent blocks.
    pub fn blocks(&self) -> usize {
        self.starts.len() - 1
    }
    /// Number of border states.
    pub fn border(&self) -> usize {
        self.n - self.starts[self.blocks()]
    }
    /// Size of the largest block.
    pub fn largest_block(&self) -> usize {
        self.starts
            .windows(2)
            .map(|w| w[1] - w[0])
            .max()
            .unwrap_or(0)
    }
    /// Whether this is the dense partition (one block, no border).
    pub fn is_dense(&self) -> bool {
        self.blocks() == 1 && self.border() == 0
    }

    /// Block b's first position, size and border links (the tests' view; the factorisation and
    /// the solves read [`BlockAt`]).
    #[cfg(test)]
    fn block(&self, b: usize) -> (usize, usize, &[usize]) {
        let (s, e) = (self.starts[b], self.starts[b + 1]);
        (
            s,
            e - s,
            &self.links[self.link_starts[b]..self.link_starts[b + 1]],
        )
    }
}

/// Estimated flops of a factorisation plus [`SOLVES_PER_FACTORISATION`] solves for blocks of
/// `sizes` with `links` border couplings each and a border of `m` states.
fn work(sizes: &[usize], links: &[usize], m: usize) -> f64 {
    let mut f = (m as f64).powi(3) / 3.0;
    let mut s = (m * m) as f64;
    for (&k, &l) in sizes.iter().zip(links) {
        let (k, l) = (k as f64, l as f64);
        f += k * k * k / 3.0 + k * k * l + k * l * l;
        s += k * k + 2.0 * k * l;
    }
    f + SOLVES_PER_FACTORISATION * s
}

/// Connected components of the states outside the border, with their border links.
#[derive(Default)]
struct Components {
    /// Component of each state (usize::MAX in the border).
    of: Vec<usize>,
    sizes: Vec<usize>,
    link_counts: Vec<usize>,
    stack: Vec<usize>,
    /// Last component that counted a border state as its link.
    seen_by: Vec<usize>,
}

impl Components {
    fn find(&mut self, adj: &[Vec<usize>], in_border: &[bool]) {
        let n = adj.len();
        self.of.clear();
        self.of.resize(n, usize::MAX);
        self.seen_by.clear();
        self.seen_by.resize(n, usize::MAX);
        self.sizes.clear();
        self.link_counts.clear();
        for root in 0..n {
            if in_border[root] || self.of[root] != usize::MAX {
                continue;
            }
            let c = self.sizes.len();
            let (mut size, mut nlinks) = (0, 0);
            self.of[root] = c;
            self.stack.push(root);
            while let Some(v) = self.stack.pop() {
                size += 1;
                for &u in &adj[v] {
                    if in_border[u] {
                        if self.seen_by[u] != c {
                            self.seen_by[u] = c;
                            nlinks += 1;
                        }
                    } else if self.of[u] == usize::MAX {
                        self.of[u] = c;
                        self.stack.push(u);
                    }
                }
            }
            self.sizes.push(size);
            self.link_counts.push(nlinks);
        }
    }

    /// The members of every component, ascending, components in the order of their first state.
    fn members(&self) -> Vec<Vec<usize>> {
        let mut out = vec![Vec::new(); self.sizes.len()];
        for (v, &c) in self.of.iter().enumerate() {
            if c != usize::MAX {
                out[c].push(v);
            }
        }
        out
    }
}

/// LU factors of M for a [`Partition`] (see the module documentation).
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
}

impl<T: Scalar> Factorisation<T> {
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
        }
    }

    /// The partition in use.
    pub fn partition(&self) -> &Arc<Partition> {
        &self.part
    }

    /// Factorises the matrix with entries `entry(i, j)` for the partition `part` (reusing this
    /// factorisation's memory). False if a pivot is zero, or, for a structured partition, small
    /// against its block (below 1e-10 of its largest entry); the factors are then unusable.
    pub fn factor(&mut self, part: &Arc<Partition>, entry: impl Fn(usize, usize) -> T) -> bool {
        if !Arc::ptr_eq(&self.part, part) {
            self.part = Arc::clone(part);
        }
        let p = &*self.part;
        let n = p.n;
        let nb = p.starts[p.blocks()];
        let m = n - nb;
        let floor = if p.is_dense() { 0.0 } else { PIVOT_FLOOR };
        resize(&mut self.lu, p.lu_len);
        resize(&mut self.x, p.x_len);
        resize(&mut self.c, p.x_len);
        self.piv.resize(n, 0);
        resize(&mut self.schur, m * m);
        self.schur_piv.resize(m, 0);
        let border = &p.perm[nb..];
        for q in 0..m {
            for r in 0..m {
                self.schur[r + q * m] = entry(border[r], border[q]);
            }
        }
        // The blocks at the offsets the solves read them from (the Schur complement takes the
        // linked blocks' updates in block order; the free ones have none).
        for at in p.linked.iter().chain(&p.free) {
            let (s, k) = (at.start, at.size);
            let links = &p.links[at.links_from..at.links_to];
            let idx = &p.perm[s..s + k];
            let a = &mut self.lu[at.lu..at.lu + k * k];
            for cj in 0..k {
                for r in 0..k {
                    a[r + cj * k] = entry(idx[r], idx[cj]);
                }
            }
            if !lu_in_place(a, k, &mut self.piv[s..s + k], floor) {
                return false;
            }
            let l = links.len();
            let x = &mut self.x[at.x..at.x + k * l];
            let c = &mut self.c[at.x..at.x + k * l];
            for (li, &q) in links.iter().enumerate() {
                let col = &mut x[li * k..(li + 1) * k];
                for r in 0..k {
                    col[r] = entry(idx[r], border[q]);
                    c[li * k + r] = entry(border[q], idx[r]);
                }
                lu_solve(a, k, &self.piv[s..s + k], col);
            }
            // S -= C_b X_b, only where block b touches the border.
            for (l2, &q) in links.iter().enumerate() {
                let xc = &x[l2 * k..(l2 + 1) * k];
                for (l1, &r) in links.iter().enumerate() {
                    let cr = &c[l1 * k..(l1 + 1) * k];
                    let mut acc = T::ZERO;
                    for i in 0..k {
                        acc = acc + cr[i] * xc[i];
                    }
                    self.schur[r + q * m] = self.schur[r + q * m] - acc;
                }
            }
        }
        lu_in_place(&mut self.schur, m, &mut self.schur_piv, floor)
    }

    /// Solves M x = rhs in place; `scratch` is any vector of the same length (its contents are
    /// overwritten).
    ///
    /// One pass over the blocks coupled to the border forward (each block's solve and its share
    /// of the border's right-hand side), the border's solve, one pass back (each block's back
    /// substitution, written straight to its states), and one pass over the free blocks, whose
    /// solve is final at once. Blocks of one and two states, all the plate's modes, are written
    /// out; the operations and their order are those of the general block solve and the block
    /// formulas, so the bits do not depend on the block size's path or on a block's being free.
    pub fn solve(&self, rhs: &mut [T], scratch: &mut [T]) {
        let p = &*self.part;
        let nb = p.starts[p.blocks()];
        let (blocks, border) = scratch[..p.n].split_at_mut(nb);
        for (dst, &i) in border.iter_mut().zip(&p.perm[nb..]) {
            *dst = rhs[i];
        }
        // y_b = A_b⁻¹ r_b, and the border's right-hand side r_B - Σ C_b y_b.
        for at in &p.linked {
            let (st, k) = (at.start, at.size);
            let links = &p.links[at.links_from..at.links_to];
            let lu = &self.lu[at.lu..at.lu + k * k];
            let c = &self.c[at.x..at.x + k * links.len()];
            let idx = &p.perm[st..st + k];
            match (lu, idx, &mut blocks[st..st + k]) {
                (&[inv_u00], &[i0], [y0]) => {
                    let v = rhs[i0] * inv_u00;
                    *y0 = v;
                    for (&q, &c0) in links.iter().zip(c) {
                        border[q] = border[q] - (T::ZERO + c0 * v);
                    }
                }
                (&[inv_u00, l10, u01, inv_u11], &[i0, i1], [y0, y1]) => {
                    let (v0, v1) = solve_2x2(
                        inv_u00,
                        l10,
                        u01,
                        inv_u11,
                        self.piv[st] != 0,
                        rhs[i0],
                        rhs[i1],
                    );
                    (*y0, *y1) = (v0, v1);
                    for (&q, cr) in links.iter().zip(c.chunks_exact(2)) {
                        border[q] = border[q] - (T::ZERO + cr[0] * v0 + cr[1] * v1);
                    }
                }
                (_, _, y) => {
                    for (dst, &i) in y.iter_mut().zip(idx) {
                        *dst = rhs[i];
                    }
                    lu_solve(lu, k, &self.piv[st..st + k], y);
                    for (&q, cr) in links.iter().zip(c.chunks_exact(k)) {
                        let mut acc = T::ZERO;
                        for i in 0..k {
                            acc = acc + cr[i] * y[i];
                        }
                        border[q] = border[q] - acc;
                    }
                }
            }
        }
        lu_solve(&self.schur, p.n - nb, &self.schur_piv, border);
        // x_b = y_b - X_b x_B.
        for at in &p.linked {
            let (st, k) = (at.start, at.size);
            let links = &p.links[at.links_from..at.links_to];
            let x = &self.x[at.x..at.x + k * links.len()];
            let idx = &p.perm[st..st + k];
            match (idx, &mut blocks[st..st + k]) {
                (&[i0], &mut [mut y0]) => {
                    for (&q, &x0) in links.iter().zip(x) {
                        y0 = y0 - x0 * border[q];
                    }
                    rhs[i0] = y0;
                }
                (&[i0, i1], &mut [mut y0, mut y1]) => {
                    for (&q, xc) in links.iter().zip(x.chunks_exact(2)) {
                        let v = border[q];
                        y0 = y0 - xc[0] * v;
                        y1 = y1 - xc[1] * v;
                    }
                    (rhs[i0], rhs[i1]) = (y0, y1);
                }
                (_, y) => {
                    for (&q, xc) in links.iter().zip(x.chunks_exact(k)) {
                        let v = border[q];
                        for i in 0..k {
                            y[i] = y[i] - xc[i] * v;
                        }
                    }
                    for (&yi, &i) in y.iter().zip(idx) {
                        rhs[i] = yi;
                    }
                }
            }
        }
        for (&v, &i) in border.iter().zip(&p.perm[nb..]) {
            rhs[i] = v;
        }
        // x_b = A_b⁻¹ r_b for the blocks without a border link (the dense partition's one
        // block among them).
        for at in &p.free {
            let (st, k) = (at.start, at.size);
            let lu = &self.lu[at.lu..at.lu + k * k];
            match (lu, &p.perm[st..st + k]) {
                (&[inv_u00], &[i0]) => rhs[i0] = rhs[i0] * inv_u00,
                (&[inv_u00, l10, u01, inv_u11], &[i0, i1]) => {
                    let swap = self.piv[st] != 0;
                    (rhs[i0], rhs[i1]) =
                        solve_2x2(inv_u00, l10, u01, inv_u11, swap, rhs[i0], rhs[i1]);
                }
                (_, idx) => {
                    let y = &mut blocks[st..st + k];
                    for (dst, &i) in y.iter_mut().zip(idx) {
                        *dst = rhs[i];
                    }
                    lu_solve(lu, k, &self.piv[st..st + k], y);
                    for (&yi, &i) in y.iter().zip(idx) {
                        rhs[i] = yi;
                    }
                }
            }
        }
    }
}

fn resize<T: Scalar>(v: &mut Vec<T>, len: usize) {
    v.resize(len, T::ZERO);
}

/// LU with partial pivoting of the column-major k × k matrix `a` in place (unit lower L below
/// the diagonal, U above it, and the reciprocals of U's diagonal on the diagonal), interchanges
/// in `piv` (row j was swapped with row piv[j]). False if a pivot is zero or below `floor`
/// times the largest entry of `a`.
///
/// The diagonal is stored inverted because every factorisation serves many solves (8 per
/// Rodas5P step, several per Newton iteration of Radau5, hundreds of steps with a constant
/// Jacobian): a solve then multiplies where it would divide, and a division (a complex one
/// above all) costs several multiplications' latency on the solve's critical path.
fn lu_in_place<T: Scalar>(a: &mut [T], k: usize, piv: &mut [usize], floor: f64) -> bool {
    let amax = a.iter().fold(0.0f64, |m, v| m.max(v.norm1()));
    let tiny = floor * amax;
    for j in 0..k {
        let mut p = j;
        let mut pmax = a[j + j * k].norm1();
        for r in j + 1..k {
            let v = a[r + j * k].norm1();
            if v > pmax {
                p = r;
                pmax = v;
            }
        }
        piv[j] = p;
        if pmax == 0.0 || pmax <= tiny || !pmax.is_finite() {
            return false;
        }
        if p != j {
            for c in 0..k {
                a.swap(j + c * k, p + c * k);
            }
        }
        let d = a[j + j * k];
        for r in j + 1..k {
            a[r + j * k] = a[r + j * k] / d;
        }
        // The elimination below reads only rows and columns after j: the pivot is free to go.
        a[j + j * k] = T::ONE / d;
        for c in j + 1..k {
            let f = a[j + c * k];
            if f != T::ZERO {
                let (left, right) = a.split_at_mut(c * k);
                let lcol = &left[j * k..j * k + k];
                let col = &mut right[..k];
                for r in j + 1..k {
                    col[r] = col[r] - lcol[r] * f;
                }
            }
        }
    }
    true
}

/// Solves with the factors of [`lu_in_place`] in place.
#[inline]
fn lu_solve<T: Scalar>(a: &[T], k: usize, piv: &[usize], x: &mut [T]) {
    // The plate's modes make blocks of one or two states: written out, the same operations in
    // the same order (so the same bits) cost a fraction of the loops' bookkeeping.
    match (k, a, piv, &mut *x) {
        (1, &[inv_u00], _, [x0]) => *x0 = *x0 * inv_u00,
        (2, &[inv_u00, l10, u01, inv_u11], &[p0, _], [x0, x1]) => {
            (*x0, *x1) = solve_2x2(inv_u00, l10, u01, inv_u11, p0 != 0, *x0, *x1);
        }
        // The servo valve's border and its three-state block: with k known, the loops unroll.
        (3, ..) => lu_solve_loops(a, 3, piv, x),
        (4, ..) => lu_solve_loops(a, 4, piv, x),
        (5, ..) => lu_solve_loops(a, 5, piv, x),
        (6, ..) => lu_solve_loops(a, 6, piv, x),
        (7, ..) => lu_solve_loops(a, 7, piv, x),
        (8, ..) => lu_solve_loops(a, 8, piv, x),
        _ => lu_solve_loops(a, k, piv, x),
    }
}

/// [`lu_solve`] for k = 2, from the factors `[inv_u00, l10, u01, inv_u11]` (column-major), the
/// interchange of the two rows if `swap`, and the right-hand side (r0, r1).
#[inline(always)]
fn solve_2x2<T: Scalar>(
    inv_u00: T,
    l10: T,
    u01: T,
    inv_u11: T,
    swap: bool,
    r0: T,
    r1: T,
) -> (T, T) {
    let (mut x0, mut x1) = if swap { (r1, r0) } else { (r0, r1) };
    if x0 != T::ZERO {
        x1 = x1 - l10 * x0;
    }
    x1 = x1 * inv_u11;
    if x1 != T::ZERO {
        x0 = x0 - u01 * x1;
    }
    (x0 * inv_u00, x1)
}

/// [`lu_solve`] for any k (inlined, so that a constant k unrolls the loops).
#[inline(always)]
fn lu_solve_loops<T: Scalar>(a: &[T], k: usize, piv: &[usize], x: &mut [T]) {
    let (a, piv, x) = (&a[..k * k], &piv[..k], &mut x[..k]);
    for j in 0..k {
        if piv[j] != j {
            x.swap(j, piv[j]);
        }
    }
    for j in 0..k {
        let v = x[j];
        if v != T::ZERO {
            let col = &a[j * k..j * k + k];
            for r in j + 1..k {
                x[r] = x[r] - col[r] * v;
            }
        }
    }
    for j in (0..k).rev() {
        let col = &a[j * k..j * k + k];
        let v = x[j] * col[j];
        x[j] = v;
        if v != T::ZERO {
            for r in 0..j {
                x[r] = x[r] - col[r] * v;
            }
        }
    }
}

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
    /// [`OdeSystem::constant_jacobian`](super::OdeSystem::constant_jacobian)), for which the
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
    /// [`OdeSystem::jacobian_pattern`](super::OdeSystem::jacobian_pattern)): found once from the
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

/// Factorises `entry` with `part`, or with the dense partition if the structured elimination
/// fails (a small pivot inside a block); reuses `f`'s memory. False if M is singular.
pub(crate) fn factor_with_fallback<T: Scalar>(
    f: &mut Factorisation<T>,
    part: &Arc<Partition>,
    entry: impl Fn(usize, usize) -> T,
) -> bool {
    if f.factor(part, &entry) {
        return true;
    }
    if part.is_dense() {
        return false;
    }
    let dense = Arc::new(Partition::dense(part.dim()));
    f.factor(&dense, &entry)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// xorshift64*: deterministic test matrices without a dependency.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            let v = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d);
            (v >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

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
        lu_solve(&f.schur, m, &f.schur_piv, border);
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

    /// A random arrowhead matrix: `blocks` groups of `k` states, each group dense inside and
    /// coupled to a random subset of a `m`-state dense border; states shuffled.
    fn arrowhead(rng: &mut Rng, blocks: usize, k: usize, m: usize) -> DMatrix<f64> {
        arrowhead_with_free(rng, blocks, k, m, 0)
    }

    /// [`arrowhead`] in which every `free`-th block (none for 0) has no link to the border.
    fn arrowhead_with_free(
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

    /// The written-out solves for blocks of one and two states, and the unrolled ones of three
    /// to eight, give the loops' bits, with and without a row interchange, for real and complex
    /// systems, zeros included.
    #[test]
    fn small_block_solves_match_the_loops_bit_for_bit() {
        fn check<T: Scalar + std::fmt::Debug>(a: &[T], k: usize, rhs: &[T]) {
            let mut lu = a.to_vec();
            let mut piv = vec![0; k];
            assert!(lu_in_place(&mut lu, k, &mut piv, 0.0));
            let (mut fast, mut loops) = (rhs.to_vec(), rhs.to_vec());
            lu_solve(&lu, k, &piv, &mut fast);
            lu_solve_loops(&lu, k, &piv, &mut loops);
            assert_eq!(
                format!("{fast:?}"),
                format!("{loops:?}"),
                "k = {k}, pivots {piv:?}"
            );
        }
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let mut pivoted = 0;
        for trial in 0..2000 {
            let a: Vec<f64> = (0..4).map(|_| rng.next()).collect();
            let mut rhs: Vec<f64> = (0..2).map(|_| rng.next()).collect();
            if trial % 7 == 0 {
                rhs[trial % 2] = 0.0;
            }
            pivoted += usize::from(a[1].abs() > a[0].abs());
            check(&a, 2, &rhs);
            check(&a[..1], 1, &rhs[..1]);
            let c = |i: usize| Complex::new(a[i], a[(i + 1) % 4]);
            check(
                &[c(0), c(1), c(2), c(3)],
                2,
                &[c(2), Complex::new(0.0, 0.0)],
            );
        }
        assert!(pivoted > 500, "both pivot orders are exercised: {pivoted}");
        // The sizes whose loops are unrolled (3 to 8), and 9, which is not.
        for k in 3..=9 {
            for trial in 0..50 {
                let a: Vec<f64> = (0..k * k).map(|_| rng.next()).collect();
                let mut rhs: Vec<f64> = (0..k).map(|_| rng.next()).collect();
                rhs[trial % k] = 0.0;
                check(&a, k, &rhs);
                let ac: Vec<Complex<f64>> = a
                    .iter()
                    .enumerate()
                    .map(|(i, &x)| Complex::new(x, a[(i * 7) % (k * k)]))
                    .collect();
                let rc: Vec<Complex<f64>> = rhs.iter().map(|&v| Complex::new(v, -v)).collect();
                check(&ac, k, &rc);
            }
        }
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
            let c = Complex::new(2.0, 1.5);
            let entry = |i: usize, jj: usize| {
                let d = if i == jj {
                    c
                } else {
                    <Complex<f64> as Scalar>::ZERO
                };
                d - Complex::new(j[(i, jj)], 0.0)
            };
            check(&part, entry, &bc);
        }
    }

    fn residual<T: Scalar>(n: usize, entry: impl Fn(usize, usize) -> T, x: &[T], b: &[T]) -> f64 {
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

    #[test]
    fn arrowhead_is_detected_and_solved_like_the_dense_lu() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        for &(blocks, k, m) in &[(30, 2, 4), (60, 1, 3), (12, 3, 5), (100, 2, 8)] {
            let j = arrowhead(&mut rng, blocks, k, m);
            let n = j.nrows();
            let part = Arc::new(Partition::of_matrix(&j));
            assert!(!part.is_dense(), "{blocks}x{k}+{m}: not detected");
            // The greedy split may move a few block states into the border when the work
            // estimate says so, but it must find the blocks.
            assert!(
                part.border() <= 2 * m,
                "{blocks}x{k}+{m}: border {}",
                part.border()
            );
            assert!(part.largest_block() <= k);
            let c = 3.0; // M = c I - J
            let entry = |i: usize, jj: usize| if i == jj { c } else { 0.0 } - j[(i, jj)];
            let mut f = Factorisation::new(Arc::clone(&part));
            assert!(f.factor(&part, entry));
            let b: Vec<f64> = (0..n).map(|_| rng.next()).collect();
            let mut x = b.clone();
            let mut scratch = vec![0.0; n];
            f.solve(&mut x, &mut scratch);
            let m_dense = DMatrix::from_fn(n, n, entry);
            let m_max = m_dense.amax();
            let reference = m_dense
                .lu()
                .solve(&nalgebra::DVector::from(b.clone()))
                .unwrap();
            let scale = reference.amax();
            let diff = x
                .iter()
                .zip(reference.iter())
                .map(|(a, r)| (a - r).abs())
                .fold(0.0, f64::max);
            assert!(
                diff <= 1e-11 * scale,
                "{blocks}x{k}+{m}: {diff:e} vs {scale:e}"
            );
            assert!(residual(n, entry, &x, &b) <= 1e-12 * scale * m_max * n as f64);
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
    fn a_dense_matrix_gets_the_dense_partition_and_solves() {
        let mut rng = Rng(3);
        let n = 20;
        let j = DMatrix::from_fn(n, n, |_, _| rng.next());
        let part = Arc::new(Partition::of_matrix(&j));
        assert!(part.is_dense());
        let mut f = Factorisation::new(Arc::clone(&part));
        assert!(f.factor(&part, |i, k| j[(i, k)]));
        let b: Vec<f64> = (0..n).map(|_| rng.next()).collect();
        let mut x = b.clone();
        f.solve(&mut x, &mut vec![0.0; n]);
        assert!(residual(n, |i, k| j[(i, k)], &x, &b) < 1e-12 * n as f64);
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
