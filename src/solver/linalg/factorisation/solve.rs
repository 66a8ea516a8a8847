//! [`Factorisation::solve`]: the solve with the factors of a structured partition (the blocks,
//! the border's right-hand side border state by border state, the border's dense solve, the
//! blocks' back substitution).

use super::super::lu::{lu_solve, lu_solve_loops, solve_2x2};
use super::super::partition::Partition;
use super::super::scalar::Scalar;
use super::{get, get_mut, Factorisation};

impl<T: Scalar> Factorisation<T> {
    /// Solves M x = rhs in place; `scratch` is any vector of the same length (its contents are
    /// overwritten).
    ///
    /// Four passes: y_b = A_b⁻¹ r_b for the blocks coupled to the border; the border's
    /// right-hand side r_B − Σ C_b y_b and its solve; each coupled block's back substitution
    /// x_b = y_b − X_b x_B, written straight to its states; and the free blocks, whose solve is
    /// final at once. The blocks of one state, most of them (the plate's modes), come from
    /// their own list (`OneAt`), without the dispatch on the block size and the slicing of a
    /// block's data.
    ///
    /// The border's right-hand side is made border state by border state: r_q, less one term
    /// C_b[q, :] y_b (a `Term`) for each block b linked to q, in block order, each term the
    /// dot product over the block's states in order, from zero. Those are the operations, in
    /// the same order on each value, of a pass block by block that subtracts each block's
    /// terms from the border states it touches (how this solve was written before): there,
    /// too, r_q takes its terms in block order, each `r_q − (((0 + c_0 y_0) + c_1 y_1) + …)`
    /// (the `0 +` kept: it turns a product of −0 into +0), so the bits are the same, signed
    /// zeros and non-finite values included; but each r_q stays in a register through its
    /// terms instead of going through memory from one block to the next, and the blocks'
    /// solves need not wait for it. The bits do not depend on a block size's path or on
    /// a block's being free either: the written-out blocks have the general block solve's and
    /// the block formulas' operations in their order.
    ///
    /// The passes read and write their entries without bounds checks: a block of one state has
    /// a multiplication and a few multiply-adds with the border, fewer instructions than the
    /// checks and slices of its data would take. Their indices are the partition's, which
    /// `Partition::with` checked against its dimensions or derived within them when it made it
    /// (every state below n, every link below the border's m, each block's data and each term
    /// within the factors' lengths), and the lengths of the vectors they index are checked once
    /// here.
    ///
    /// Where the processor has AVX2 the passes are compiled for it (`solve_avx2`).
    pub fn solve(&self, rhs: &mut [T], scratch: &mut [T]) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2 (checked just above).
            return unsafe { self.solve_avx2(rhs, scratch) };
        }
        self.solve_passes(rhs, scratch);
    }

    /// [`Factorisation::solve`]'s passes compiled for AVX2: the same operations (separate
    /// multiplications and additions, never fused: AVX2 does not include FMA), so the same
    /// bits, in fewer instructions (three-operand forms, wider loads).
    ///
    /// # Safety
    ///
    /// The processor has AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn solve_avx2(&self, rhs: &mut [T], scratch: &mut [T]) {
        self.solve_passes(rhs, scratch);
    }

    /// [`Factorisation::solve`]'s passes (inlined into its callers, each compiled for its own
    /// instruction set).
    #[inline(always)]
    pub(super) fn solve_passes(&self, rhs: &mut [T], scratch: &mut [T]) {
        let p = &*self.part;
        let (n, nb) = (p.n, p.starts[p.blocks()]);
        let m = n - nb;
        let rhs = &mut rhs[..n];
        let (lu, x, c) = (&self.lu[..p.lu_len], &self.x[..p.x_len], &self.c[..p.x_len]);
        let (piv, links) = (&self.piv[..n], &p.links[..]);
        let (terms, term_starts) = (&p.terms[..], &p.term_starts[..m + 1]);
        let (blocks, border) = scratch[..n].split_at_mut(nb);
        let (perm, border_states) = p.perm.split_at(nb);
        // y_b = A_b⁻¹ r_b.
        for o in &p.ones {
            // SAFETY: `Partition::with` checked or derived: o.pos < nb = blocks.len(), o.state <
            // n = rhs.len(), o.lu < lu_len = lu.len().
            unsafe { *get_mut(blocks, o.pos) = get(rhs, o.state) * get(lu, o.lu) };
        }
        for at in &p.multi {
            let (st, k) = (at.start, at.size);
            if k == 2 {
                // SAFETY: `Partition::with` checked: st + 2 ≤ nb = blocks.len() = perm.len(),
                // perm's entries < n = rhs.len(), at.lu + 4 ≤ lu.len(), st + 1 < n = piv.len().
                unsafe {
                    let r = (get(rhs, get(perm, st)), get(rhs, get(perm, st + 1)));
                    let (v0, v1) = block_2x2(lu, piv, at.lu, st, r);
                    (*get_mut(blocks, st), *get_mut(blocks, st + 1)) = (v0, v1);
                }
                continue;
            }
            let (lu, piv) = (&lu[at.lu..at.lu + k * k], &piv[st..st + k]);
            let (idx, y) = (&perm[st..st + k], &mut blocks[st..st + k]);
            // The servo valve's blocks of three and four states: with k known, the loops
            // unroll.
            match k {
                3 => block_solve(3, lu, piv, idx, rhs, y),
                4 => block_solve(4, lu, piv, idx, rhs, y),
                _ => block_solve(k, lu, piv, idx, rhs, y),
            }
        }
        // r_q − Σ_b C_b[q, :] y_b, the blocks in order.
        for (q, (dst, &i)) in border.iter_mut().zip(border_states).enumerate() {
            // SAFETY: i < n = rhs.len() (`Partition::with` checked `perm`); q < m, so
            // term_starts[q + 1] ≤ terms.len(); each term's t.c + t.k ≤ x_len = c.len() and
            // t.y + t.k ≤ nb = blocks.len() (`Partition::with` derived them from the blocks).
            unsafe {
                let mut b = get(rhs, i);
                let (from, to) = (get(term_starts, q), get(term_starts, q + 1));
                for t in terms.get_unchecked(from..to) {
                    let (cr, y) = (c.as_ptr().add(t.c), blocks.as_ptr().add(t.y));
                    // With k known, the dot product unrolls (the plate's modes: k = 1).
                    b = b - if t.k == 1 {
                        dot(1, cr, y)
                    } else if t.k == 4 {
                        dot(4, cr, y)
                    } else if t.k == 3 {
                        dot(3, cr, y)
                    } else {
                        dot(t.k, cr, y)
                    };
                }
                *dst = b;
            }
        }
        lu_solve(&self.schur[..m * m], m, &self.schur_piv[..m], border);
        // x_b = y_b - X_b x_B.
        for o in &p.ones {
            // SAFETY: as in the first pass, with o.links_from < o.links_to ≤ links.len() (the
            // block is linked: at least one link), o.x + (its links) ≤ x_len = x.len(), and
            // links < m = border.len().
            unsafe {
                let mut y0 = get(blocks, o.pos);
                let (mut l, end) = (
                    links.as_ptr().add(o.links_from),
                    links.as_ptr().add(o.links_to),
                );
                let mut xp = x.as_ptr().add(o.x);
                loop {
                    y0 = y0 - *xp * get(border, *l);
                    (l, xp) = (l.add(1), xp.add(1));
                    if l == end {
                        break;
                    }
                }
                *get_mut(rhs, o.state) = y0;
            }
        }
        for at in &p.multi {
            let (st, k) = (at.start, at.size);
            let links = &links[at.links_from..at.links_to];
            let x = &x[at.x..at.x + k * links.len()];
            let (idx, y) = (&perm[st..st + k], &mut blocks[st..st + k]);
            match k {
                2 => back(2, idx, y, links, x, border, rhs),
                3 => back(3, idx, y, links, x, border, rhs),
                4 => back(4, idx, y, links, x, border, rhs),
                _ => back(k, idx, y, links, x, border, rhs),
            }
        }
        scatter_border_and_free_blocks(p, lu, piv, border, blocks, rhs);
    }
}

/// A block's y = A⁻¹ r in [`Factorisation::solve`]'s first pass, for its states `idx` (into
/// `y`). Inlined, so that a constant k unrolls the loops (the same operations in the same
/// order for every k, so the same bits).
#[inline(always)]
fn block_solve<T: Scalar>(
    k: usize,
    lu: &[T],
    piv: &[usize],
    idx: &[usize],
    rhs: &[T],
    y: &mut [T],
) {
    let (idx, y) = (&idx[..k], &mut y[..k]);
    for (dst, &i) in y.iter_mut().zip(idx) {
        *dst = rhs[i];
    }
    if k <= 4 {
        // Inlined (for a constant k, unrolled): the bits of `lu_solve`'s unrolled solves
        // (`small_block_solves_match_the_loops_bit_for_bit`).
        lu_solve_loops(lu, k, piv, y);
    } else {
        lu_solve(lu, k, piv, y);
    }
}

/// A term of a border state's right-hand side ([`Factorisation::solve`]): the dot product of
/// the k numbers at `c` and at `y`, in order, from zero. Inlined, so that a constant k unrolls
/// the loop.
///
/// # Safety
///
/// `c` and `y` point to k numbers each.
#[inline(always)]
unsafe fn dot<T: Scalar>(k: usize, c: *const T, y: *const T) -> T {
    let mut acc = T::ZERO;
    for i in 0..k {
        // SAFETY: i < k (the caller's promise).
        acc = acc + unsafe { *c.add(i) * *y.add(i) };
    }
    acc
}

/// A block's share of [`Factorisation::solve`]'s pass back: x_b = y_b − X_b x_B, the links in
/// order, written to its states `idx` in `rhs`. Inlined, so that a constant k unrolls the
/// loops.
#[inline(always)]
fn back<T: Scalar>(
    k: usize,
    idx: &[usize],
    y: &mut [T],
    links: &[usize],
    x: &[T],
    border: &[T],
    rhs: &mut [T],
) {
    let mut acc = [T::ZERO; 4];
    if k <= 4 {
        // In registers, with k known.
        acc[..k].copy_from_slice(&y[..k]);
        for (&q, xc) in links.iter().zip(x.chunks_exact(k)) {
            let v = border[q];
            for i in 0..k {
                acc[i] = acc[i] - xc[i] * v;
            }
        }
        for (&v, &i) in acc[..k].iter().zip(&idx[..k]) {
            rhs[i] = v;
        }
        return;
    }
    let y = &mut y[..k];
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

/// The solve of a block of two states whose factors `[inv_u00, l10, u01, inv_u11]` start at
/// `lu[a]`, its interchange flag at `piv[st]`, for the right-hand side `r` ([`solve_2x2`]).
///
/// # Safety
///
/// `a + 4 <= lu.len()` and `st < piv.len()`.
#[inline(always)]
unsafe fn block_2x2<T: Scalar>(lu: &[T], piv: &[usize], a: usize, st: usize, r: (T, T)) -> (T, T) {
    // SAFETY: a + 3 < lu.len() and st < piv.len() (the caller's promise).
    unsafe {
        let f = (get(lu, a), get(lu, a + 1), get(lu, a + 2), get(lu, a + 3));
        solve_2x2(f.0, f.1, f.2, f.3, get(piv, st) != 0, r.0, r.1)
    }
}

/// The solve's last pass: the border's values into their states, and x_b = A_b⁻¹ r_b for the
/// blocks without a border link (the dense partition's one block among them), from `rhs`.
#[inline(always)]
fn scatter_border_and_free_blocks<T: Scalar>(
    p: &Partition,
    lu: &[T],
    piv: &[usize],
    border: &[T],
    blocks: &mut [T],
    rhs: &mut [T],
) {
    let nb = p.starts[p.blocks()];
    let (perm, border_states) = p.perm.split_at(nb);
    for (&v, &i) in border.iter().zip(border_states) {
        // SAFETY: i < n = rhs.len() (`Partition::with` checked `perm`).
        unsafe { *get_mut(rhs, i) = v };
    }
    // x_b = A_b⁻¹ r_b for the blocks without a border link (the dense partition's one
    // block among them).
    for at in &p.free {
        let (st, k) = (at.start, at.size);
        match k {
            // SAFETY: st < nb = perm.len(), perm's entries below n = rhs.len(),
            // at.lu < lu_len = lu.len() (`Partition::with` checked them).
            1 => unsafe {
                let r = get_mut(rhs, get(perm, st));
                *r = *r * get(lu, at.lu);
            },
            // SAFETY: as for the block of one state, with st + 1 < nb, at.lu + 4 ≤ lu.len()
            // and st < n = piv.len().
            2 => unsafe {
                let (i0, i1) = (get(perm, st), get(perm, st + 1));
                let (v0, v1) = block_2x2(lu, piv, at.lu, st, (get(rhs, i0), get(rhs, i1)));
                *get_mut(rhs, i0) = v0;
                *get_mut(rhs, i1) = v1;
            },
            _ => {
                let idx = &perm[st..st + k];
                let y = &mut blocks[st..st + k];
                for (dst, &i) in y.iter_mut().zip(idx) {
                    *dst = rhs[i];
                }
                lu_solve(&lu[at.lu..at.lu + k * k], k, &piv[st..st + k], y);
                for (&yi, &i) in y.iter().zip(idx) {
                    rhs[i] = yi;
                }
            }
        }
    }
}
