//! The dense LU of one block (or of the border's Schur complement): LU with partial pivoting in
//! place, and its solves, written out for the small block sizes.
//!
//! A large block (the dense partition's one block, above all: a model whose structured
//! elimination does not apply factorises the whole iteration matrix at every step) is factorised
//! and solved, on x86-64 processors with AVX2 (detected at run time), by the same loops compiled
//! for 4-wide vectors. Their multiplications and subtractions stay separate, never fused, and
//! each entry is updated by the same operations in the same order, so the bits are those of the
//! portable loops on every processor (`avx2_kernels_have_the_portable_bits`). A block too large
//! for the first-level cache is factorised in panels of four columns, again with the same bits
//! (`the_panels_have_the_loops_bits`).

use super::scalar::Scalar;

/// Blocks of fewer states than this are factorised and solved by the portable loops: the vector
/// versions pay off only for long columns (and the small sizes' solves are unrolled instead).
#[cfg(target_arch = "x86_64")]
const VECTOR_FROM: usize = 9;

/// LU with partial pivoting of the column-major k × k matrix `a` in place (unit lower L below
/// the diagonal, U above it, and the reciprocals of U's diagonal on the diagonal), interchanges
/// in `piv` (row j was swapped with row piv[j]). False if a pivot is zero or not finite; a
/// structured partition judges its blocks' pivots afterwards ([`pivots_clear`]).
///
/// The diagonal is stored inverted because every factorisation serves many solves (8 per
/// Rodas5P step, several per Newton iteration of Radau5, hundreds of steps with a constant
/// Jacobian): a solve then multiplies where it would divide, and a division (a complex one
/// above all) costs several multiplications' latency on the solve's critical path.
pub(super) fn lu_in_place<T: Scalar>(a: &mut [T], k: usize, piv: &mut [usize]) -> bool {
    // The plate's modes make blocks of one state, the servo valve's three and four: with k
    // known the loops unroll (the same operations in the same order, so the same bits).
    match k {
        1 => return lu_in_place_loops(a, 1, piv),
        2 => return lu_in_place_loops(a, 2, piv),
        3 => return lu_in_place_loops(a, 3, piv),
        4 => return lu_in_place_loops(a, 4, piv),
        _ => {}
    }
    #[cfg(target_arch = "x86_64")]
    {
        if k >= VECTOR_FROM && !portable_only() && std::arch::is_x86_feature_detected!("avx2") {
            if k <= SMALL_REAL {
                if let Some(ra) = T::as_reals_mut(a) {
                    // SAFETY: the processor has AVX2 (checked just above), and k ≤ SMALL_REAL.
                    return unsafe { lu_in_place_small_real_avx2(ra, k, piv) };
                }
            }
            // SAFETY: the processor has AVX2 (checked just above).
            return unsafe { lu_in_place_avx2(a, k, piv) };
        }
    }
    lu_in_place_large(a, k, piv)
}

/// [`lu_in_place`] for a block of more than four states: in panels from [`PANELS_FROM`]
/// states, the loops below.
#[inline(always)]
fn lu_in_place_large<T: Scalar>(a: &mut [T], k: usize, piv: &mut [usize]) -> bool {
    if k >= PANELS_FROM {
        lu_in_place_panels(a, k, piv)
    } else {
        lu_in_place_loops(a, k, piv)
    }
}

/// Blocks of this many states or more are factorised in panels ([`lu_in_place_panels`]): from
/// about here the matrix (72 kB at 96 states) no longer fits in the processor's first-level
/// cache, and the loops stream it from further away at every elimination. Measured with AVX2,
/// dense random matrices, one factorisation at a time (median of many): panels 18 µs against
/// the loops' 15 µs at 46 states, 0.091 ms against 0.097 ms at 96, 0.60 ms against 0.80 ms at
/// 200, 24–33 ms against 44–54 ms at 816 (the default plant with a 20 × 20 plate).
const PANELS_FROM: usize = 96;

/// The number of columns [`lu_in_place_panels`] factorises before it updates the columns after
/// them: each entry of those is then loaded and stored once for `PANEL` eliminations, not once
/// for each.
const PANEL: usize = 4;

/// [`lu_in_place_loops`] in panels of [`PANEL`] columns, with the same bits.
///
/// Each panel's columns are brought up to date with the panel's earlier eliminations as they
/// are reached, pivoted and scaled; then each column after the panel receives the panel's
/// eliminations, in their order, each entry kept in a register through them. Every entry sees
/// the same operations on the same operands in the same order as in the loops, step after
/// step: an elimination delayed past later row interchanges reads the interchanged rows of the
/// multipliers as well, and a multiplier `a[s, c]` that is zero skips its elimination as there.
/// A column is loaded and stored once per panel instead of once per elimination, which for a
/// large block (the dense LU of a system of hundreds of states) is the difference between
/// streaming the matrix from memory at every elimination and at every fourth.
#[inline(always)]
pub(super) fn lu_in_place_panels<T: Scalar>(a: &mut [T], k: usize, piv: &mut [usize]) -> bool {
    let a = &mut a[..k * k];
    let mut j0 = 0;
    while j0 < k {
        let j1 = (j0 + PANEL).min(k);
        for j in j0..j1 {
            // The panel's earlier eliminations on column j, then its pivot and scaling.
            let (left, right) = a.split_at_mut(j * k);
            let column = &mut right[..k];
            for s in j0..j {
                let f = column[s];
                if f != T::ZERO {
                    let l = &left[s * k + s + 1..s * k + k];
                    for (v, &lr) in column[s + 1..].iter_mut().zip(l) {
                        *v = *v - lr * f;
                    }
                }
            }
            if !pivot_and_scale(a, k, j, piv) {
                return false;
            }
        }
        // The columns after the panel: its eliminations s = j0, ..., j1 - 1 in turn.
        let (left, right) = a.split_at_mut(j1 * k);
        let panel = &left[j0 * k..];
        for col in right.chunks_exact_mut(k) {
            // Rows j0 + 1 .. j1 (the multipliers of the later eliminations) one elimination
            // after the other; then the rows below, all eliminations at once.
            let mut active = [(0usize, T::ZERO); PANEL];
            let mut n = 0;
            for s in j0..j1 {
                let f = col[s];
                if f != T::ZERO {
                    let l = &panel[(s - j0) * k..(s - j0 + 1) * k];
                    for r in s + 1..j1 {
                        col[r] = col[r] - l[r] * f;
                    }
                    active[n] = (s - j0, f);
                    n += 1;
                }
            }
            let below = &mut col[j1..];
            let l = |i: usize| &panel[active[i].0 * k + j1..(active[i].0 + 1) * k];
            match n {
                0 => {}
                1 => {
                    let f0 = active[0].1;
                    for (v, &l0) in below.iter_mut().zip(l(0)) {
                        *v = *v - l0 * f0;
                    }
                }
                2 => {
                    let (f0, f1) = (active[0].1, active[1].1);
                    for ((v, &l0), &l1) in below.iter_mut().zip(l(0)).zip(l(1)) {
                        *v = (*v - l0 * f0) - l1 * f1;
                    }
                }
                3 => {
                    let (f0, f1, f2) = (active[0].1, active[1].1, active[2].1);
                    for (((v, &l0), &l1), &l2) in below.iter_mut().zip(l(0)).zip(l(1)).zip(l(2)) {
                        *v = ((*v - l0 * f0) - l1 * f1) - l2 * f2;
                    }
                }
                _ => {
                    let (f0, f1, f2, f3) = (active[0].1, active[1].1, active[2].1, active[3].1);
                    for ((((v, &l0), &l1), &l2), &l3) in
                        below.iter_mut().zip(l(0)).zip(l(1)).zip(l(2)).zip(l(3))
                    {
                        *v = (((*v - l0 * f0) - l1 * f1) - l2 * f2) - l3 * f3;
                    }
                }
            }
        }
        j0 = j1;
    }
    true
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn lu_in_place_avx2<T: Scalar>(a: &mut [T], k: usize, piv: &mut [usize]) -> bool {
    lu_in_place_large(a, k, piv)
}

/// [`lu_in_place_loops`] for a real block of [`VECTOR_FROM`] to [`SMALL_REAL`] states (the
/// servo valve's border's Schur complement: 19), with the same bits.
///
/// As in [`lu_solve_small_real_avx2`], the loops' columns are short here and their compiled
/// vectors leave most rows to the scalar remainder: this kernel divides the pivot's column by
/// the pivot and subtracts its multiples from the columns after it in vectors of four rows, the
/// last one partial (masked loads and stores, so that nothing past a column's end, nor past the
/// matrix, is read or written). Every entry is updated by the same division, or the same
/// multiplication and subtraction, never fused, as in the loops, in the same order, and a zero
/// multiplier still skips its column; the pivot search and the row interchanges are the loops'.
///
/// # Safety
///
/// The processor has AVX2, and `k ≤ SMALL_REAL`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn lu_in_place_small_real_avx2(a: &mut [f64], k: usize, piv: &mut [usize]) -> bool {
    use std::arch::x86_64::*;
    assert!(k <= SMALL_REAL);
    let (a, piv) = (&mut a[..k * k], &mut piv[..k]);
    for j in 0..k {
        if !pivot(a, k, j, piv) {
            return false;
        }
        let (left, right) = a.split_at_mut((j + 1) * k);
        let column = &mut left[j * k..];
        let d = column[j];
        let (from, to) = (j + 1, k);
        // SAFETY: rows r..r + 4 of the column (k entries) are read and written only where
        // r + 4 ≤ to = k, and the partial vector's lanes past `to` are masked off (neither read
        // nor written). AVX2 is enabled in this function.
        unsafe {
            let (dd, c) = (_mm256_set1_pd(d), column.as_mut_ptr());
            let mut r = from;
            while r + 4 <= to {
                _mm256_storeu_pd(c.add(r), _mm256_div_pd(_mm256_loadu_pd(c.add(r)), dd));
                r += 4;
            }
            if r < to {
                let mask = _mm256_loadu_si256(PARTIAL_MASKS[to - r].as_ptr().cast());
                let y = _mm256_maskload_pd(c.add(r), mask);
                _mm256_maskstore_pd(c.add(r), mask, _mm256_div_pd(y, dd));
            }
        }
        column[j] = 1.0 / d;
        let l = &column[..k];
        for col in right.chunks_exact_mut(k) {
            let f = col[j];
            if f != 0.0 {
                // SAFETY: rows from..to of column j (l, k entries) and of `col` (k entries)
                // lie within them (to = k); AVX2 is enabled in this function.
                unsafe { sub_multiple(l.as_ptr(), col.as_mut_ptr(), from, to, f) };
            }
        }
    }
    true
}

/// `y[r] - l[r] f` into `y[r]` for the rows r in from..to, in vectors of four, the last one
/// partial (masked loads and stores: nothing outside those rows is read or written): the small
/// real kernels' updates, each entry by a multiplication and a subtraction, never fused, as in
/// the loops.
///
/// # Safety
///
/// The processor has AVX2, and `l` and `y` are valid for reads (and `y` writes) of their
/// entries from..to.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn sub_multiple(l: *const f64, y: *mut f64, from: usize, to: usize, f: f64) {
    use std::arch::x86_64::*;
    // SAFETY: whole vectors read and write rows r..r + 4 only where r + 4 ≤ to, the partial
    // vector's lanes past `to` are masked off (the caller's promise covers from..to).
    unsafe {
        let ff = _mm256_set1_pd(f);
        let mut r = from;
        while r + 4 <= to {
            let t = _mm256_mul_pd(_mm256_loadu_pd(l.add(r)), ff);
            let v = _mm256_loadu_pd(y.add(r));
            _mm256_storeu_pd(y.add(r), _mm256_sub_pd(v, t));
            r += 4;
        }
        if r < to {
            let mask = _mm256_loadu_si256(PARTIAL_MASKS[to - r].as_ptr().cast());
            let t = _mm256_mul_pd(_mm256_maskload_pd(l.add(r), mask), ff);
            let v = _mm256_maskload_pd(y.add(r), mask);
            _mm256_maskstore_pd(y.add(r), mask, _mm256_sub_pd(v, t));
        }
    }
}

/// The masks of the small real kernels' partial vectors by their number of lanes in (0 to 4):
/// all bits set in a lane that is in. Also the dense products' last vector's
/// (`solver::dense`).
#[cfg(target_arch = "x86_64")]
pub(crate) const PARTIAL_MASKS: [[i64; 4]; 5] = [
    [0; 4],
    [-1, 0, 0, 0],
    [-1, -1, 0, 0],
    [-1, -1, -1, 0],
    [-1, -1, -1, -1],
];

/// Whether the tests asked for the portable loops only (always false outside the tests).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn portable_only() -> bool {
    #[cfg(test)]
    return tests::PORTABLE_ONLY.with(|p| p.get());
    #[cfg(not(test))]
    false
}

/// [`lu_in_place`]'s loops.
#[inline(always)]
pub(super) fn lu_in_place_loops<T: Scalar>(a: &mut [T], k: usize, piv: &mut [usize]) -> bool {
    let a = &mut a[..k * k];
    for j in 0..k {
        if !pivot_and_scale(a, k, j, piv) {
            return false;
        }
        // The columns after j, with column j's multipliers.
        let (left, right) = a.split_at_mut((j + 1) * k);
        let l = &left[j * k + j + 1..];
        for col in right.chunks_exact_mut(k) {
            let f = col[j];
            if f != T::ZERO {
                for (v, &lr) in col[j + 1..].iter_mut().zip(l) {
                    *v = *v - lr * f;
                }
            }
        }
    }
    true
}

/// Solves with the factors of [`lu_in_place`] in place.
#[inline]
pub(super) fn lu_solve<T: Scalar>(a: &[T], k: usize, piv: &[usize], x: &mut [T]) {
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
        _ => lu_solve_large(a, k, piv, x),
    }
}

/// [`lu_solve`] for a block of more than eight states: the loops, compiled for AVX2 where the
/// processor has it (see the module documentation).
fn lu_solve_large<T: Scalar>(a: &[T], k: usize, piv: &[usize], x: &mut [T]) {
    #[cfg(target_arch = "x86_64")]
    {
        if k >= VECTOR_FROM && !portable_only() && std::arch::is_x86_feature_detected!("avx2") {
            if let (true, Some(ra), Some(rx)) =
                (k <= SMALL_REAL, T::as_reals(a), T::as_reals_mut(x))
            {
                // SAFETY: the processor has AVX2 (checked just above), and k ≤ SMALL_REAL.
                unsafe { lu_solve_small_real_avx2(ra, k, piv, rx) };
                return;
            }
            // SAFETY: the processor has AVX2 (checked just above).
            unsafe { lu_solve_avx2(a, k, piv, x) };
            return;
        }
    }
    lu_solve_loops(a, k, piv, x);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn lu_solve_avx2<T: Scalar>(a: &[T], k: usize, piv: &[usize], x: &mut [T]) {
    lu_solve_loops(a, k, piv, x);
}

/// The largest real block [`lu_solve_small_real_avx2`] solves: its right-hand side is copied
/// to a buffer of this many entries on the stack. Above it the columns are long
/// enough for the loops' vectors to pay.
#[cfg(target_arch = "x86_64")]
const SMALL_REAL: usize = 64;

/// [`lu_solve_loops`] for a real block of [`VECTOR_FROM`] to [`SMALL_REAL`] states (the servo
/// valve's border: 19), with the same bits.
///
/// The loops' columns are short here, 18 rows and fewer, and the compiled loops do most of
/// their rows one by one after the last whole vector. This kernel does every column's rows in
/// vectors of four, the last one partial, its lanes past the column's rows masked off
/// ([`sub_multiple`]), so that every entry is updated by the same multiplication and
/// subtraction, never fused, as in the loops, and a zero multiplier still skips its column. The
/// right-hand side is worked on in a copy on the stack; up to [`IN_REGISTERS`] states (the
/// border), in registers instead ([`lu_solve_in_registers`]).
///
/// # Safety
///
/// The processor has AVX2, and `k ≤ SMALL_REAL`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn lu_solve_small_real_avx2(a: &[f64], k: usize, piv: &[usize], x: &mut [f64]) {
    assert!(k <= SMALL_REAL);
    // SAFETY: (each arm) the processor has AVX2 (the caller's promise), and N = ⌈k/4⌉.
    match k {
        9..=12 => return unsafe { lu_solve_in_registers::<3>(a, k, piv, x) },
        13..=16 => return unsafe { lu_solve_in_registers::<4>(a, k, piv, x) },
        17..=IN_REGISTERS => return unsafe { lu_solve_in_registers::<5>(a, k, piv, x) },
        _ => {}
    }
    let (a, piv, x) = (&a[..k * k], &piv[..k], &mut x[..k]);
    let mut buf = [0.0f64; SMALL_REAL];
    buf[..k].copy_from_slice(x);
    for j in 0..k {
        if piv[j] != j {
            buf[..k].swap(j, piv[j]);
        }
    }
    // Rows from..to of the right-hand side less v times the same rows of column j.
    let update = |buf: &mut [f64; SMALL_REAL], j: usize, from: usize, to: usize, v: f64| {
        debug_assert!(from <= to && to <= k && j < k);
        // SAFETY: column j's entries are a[j k .. j k + k], within a (j < k, a's length k²),
        // and the buffer's entries from..to within its SMALL_REAL (to ≤ k ≤ SMALL_REAL);
        // AVX2 is enabled in this function.
        unsafe { sub_multiple(a.as_ptr().add(j * k), buf.as_mut_ptr(), from, to, v) };
    };
    for j in 0..k {
        let v = buf[j];
        if v != 0.0 {
            update(&mut buf, j, j + 1, k, v);
        }
    }
    for j in (0..k).rev() {
        let v = buf[j] * a[j * k + j];
        buf[j] = v;
        if v != 0.0 {
            update(&mut buf, j, 0, j, v);
        }
    }
    x.copy_from_slice(&buf[..k]);
}

/// The largest real block [`lu_solve_small_real_avx2`] solves with its right-hand side in
/// registers ([`lu_solve_in_registers`]): five vectors of four rows, which leave the sixteen
/// AVX2 registers room for the column's vectors, the multiplier and the partial results.
#[cfg(target_arch = "x86_64")]
const IN_REGISTERS: usize = 20;

/// [`lu_solve_small_real_avx2`] for a block of at most [`IN_REGISTERS`] states (the servo
/// valve's border), in N = ⌈k/4⌉ vectors of four rows, with the same bits.
///
/// Column by column, a solve is a chain: row j's value, once its column's updates are all in,
/// is the multiplier of the next column's. Through a buffer in memory that chain reloads each
/// row's value right after storing it, often from a masked store, which the processor cannot
/// forward to the load. Here the right-hand side stays in N vectors, every column's updates are
/// unrolled over them (monomorphised on N, the lanes' indices constants), and row j's value is
/// taken from its vector by a lane broadcast: nothing in the chain goes through memory.
///
/// The bits are the loops': every row in j+1..k (forward) or 0..j (back) is updated by the
/// same multiplication, then subtraction, never fused, in the same order as in the loops, and
/// a zero multiplier still skips its column. The vector that holds row j is updated in all its
/// lanes but takes back, by a blend, only the rows the loops update: the others keep their
/// bits exactly (a zero multiple subtracted instead would turn a -0 into a +0, and with an
/// infinite or NaN multiplier any row into NaN). Row j's own value is the loops' too: in the
/// back substitution, x_j times the diagonal's reciprocal, blended into its lane whether or
/// not it is zero. The lanes past k (the last vector's, if k is not a multiple of four) hold
/// whatever they hold, affect no row and are never stored back.
///
/// # Safety
///
/// The processor has AVX2 (k and N are checked: N = ⌈k/4⌉, k ≤ `IN_REGISTERS`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
// The unrolled steps' constants make some of their tests always true or false (L > 0 for
// L = 0), and their last column's `src` is never read.
#[allow(unused_assignments, clippy::absurd_extreme_comparisons)]
unsafe fn lu_solve_in_registers<const N: usize>(a: &[f64], k: usize, piv: &[usize], x: &mut [f64]) {
    use std::arch::x86_64::*;
    // `$body` once for each constant `$c` of the list (the unrolling that keeps the right-hand
    // side's vectors, indexed by constants, in registers).
    macro_rules! unrolled {
        ($c:ident in [$($n:literal),*] $body:block) => {
            $({
                const $c: usize = $n;
                $body
            })*
        };
    }
    assert!(k <= IN_REGISTERS && N >= 1 && k.div_ceil(4) == N);
    let (a, piv, x) = (&a[..k * k], &piv[..k], &mut x[..k]);
    // The interchanges, on the rows' indices: row r of the interchanged right-hand side is
    // x[rows[r]] (the rows past k, the last vector's padding, read x[0]). They do not wait for
    // the right-hand side.
    let mut rows = [0usize; IN_REGISTERS];
    for (r, row) in rows[..k].iter_mut().enumerate() {
        *row = r;
    }
    for (j, &p) in piv.iter().enumerate() {
        if p != j {
            rows[..k].swap(j, p);
        }
    }
    // The lanes of the last vector that are rows (1 to 4).
    let m = k - 4 * (N - 1);
    // Column j's vector i is read at a[j k + 4 i .. j k + 4 i + 4]; with 4 (N - 1) < k, that
    // lies within a (k² entries) for every i < N - 1 and every j < k, and also for i = N - 1 if
    // j ≤ k - 2 (j k + 4 N - 1 ≤ (k - 2) k + k + 2 < k²). The forward pass reads only columns
    // j ≤ k - 2; the back pass reads column k - 1's last vector, the one read that could pass
    // the end of a, with its lanes past k masked off (`tail`). The diagonal's entry j k + j < k².
    // SAFETY: AVX2 is enabled in this function; every read is within a (above), and the stores
    // write x's k entries only.
    unsafe {
        let tail = _mm256_castsi256_pd(_mm256_cmpgt_epi64(
            _mm256_set1_epi64x(m as i64),
            _mm256_setr_epi64x(0, 1, 2, 3),
        ));
        let mut v = [_mm256_setzero_pd(); N];
        unrolled!(I in [0, 1, 2, 3, 4] {
            if I < N {
                let at = |l: usize| x[rows[4 * I + l]];
                v[I] = _mm256_setr_pd(at(0), at(1), at(2), at(3));
            }
        });
        // Forward substitution. `src` is a vector whose lanes from j's on hold rows' values
        // with all of the columns before j in (row j's vector, or the unblended result of the
        // column before it): the chain runs through it, the blends into `v` stay off it.
        let mut src = v[0];
        'forward: {
            unrolled!(B in [0, 1, 2, 3, 4] {
                if B < N {
                    unrolled!(L in [0, 1, 2, 3] {
                        let j = 4 * B + L;
                        if j + 1 >= k {
                            break 'forward;
                        }
                        let f = _mm256_permute4x64_pd::<{ 0x55 * L as i32 }>(src);
                        if _mm256_cvtsd_f64(f) != 0.0 {
                            let c = a.as_ptr().add(j * k);
                            if L < 3 {
                                // Rows j + 1 .. 4 B + 4: the lanes above L.
                                let t = _mm256_sub_pd(
                                    src,
                                    _mm256_mul_pd(_mm256_loadu_pd(c.add(4 * B)), f),
                                );
                                v[B] = _mm256_blend_pd::<{ (0b1110 << L) & 0b1111 }>(v[B], t);
                                src = t;
                            }
                            unrolled!(I in [1, 2, 3, 4] {
                                if B + I < N {
                                    let l = _mm256_loadu_pd(c.add(4 * (B + I)));
                                    v[B + I] = _mm256_sub_pd(v[B + I], _mm256_mul_pd(l, f));
                                }
                            });
                        }
                        if L == 3 && B + 1 < N {
                            src = v[B + 1];
                        }
                    });
                }
            });
        }
        // Back substitution, from row k - 1 (the last vector's lane m - 1) up. `src`: a vector
        // whose lanes up to j's hold rows' values with all of the columns after j in.
        let mut src = v[N - 1];
        unrolled!(BB in [0, 1, 2, 3, 4] {
            const B: usize = 4 - BB;
            if B < N {
                unrolled!(LL in [0, 1, 2, 3] {
                    const L: usize = 3 - LL;
                    let j = 4 * B + L;
                    if j < k {
                        let c = a.as_ptr().add(j * k);
                        let d = _mm256_broadcast_sd(&*c.add(j));
                        let f = _mm256_mul_pd(
                            _mm256_permute4x64_pd::<{ 0x55 * L as i32 }>(src),
                            d,
                        );
                        v[B] = _mm256_blend_pd::<{ 1 << L }>(v[B], f);
                        if _mm256_cvtsd_f64(f) != 0.0 {
                            if L > 0 {
                                // Rows 4 B .. j: the lanes below L.
                                let l = if B + 1 < N {
                                    _mm256_loadu_pd(c.add(4 * B))
                                } else {
                                    _mm256_maskload_pd(c.add(4 * B), _mm256_castpd_si256(tail))
                                };
                                let t = _mm256_sub_pd(src, _mm256_mul_pd(l, f));
                                v[B] = _mm256_blend_pd::<{ (1 << L) - 1 }>(v[B], t);
                                src = t;
                            }
                            unrolled!(I in [1, 2, 3, 4] {
                                if I <= B {
                                    let l = _mm256_loadu_pd(c.add(4 * (B - I)));
                                    v[B - I] = _mm256_sub_pd(v[B - I], _mm256_mul_pd(l, f));
                                }
                            });
                        }
                        if L == 0 && B > 0 {
                            src = v[B - 1];
                        }
                    }
                });
            }
        });
        unrolled!(I in [0, 1, 2, 3] {
            if I + 1 < N {
                _mm256_storeu_pd(x.as_mut_ptr().add(4 * I), v[I]);
            }
        });
        // The last vector's rows one by one (a masked store would not forward to the caller's
        // loads).
        let (lo, hi) = (
            _mm256_castpd256_pd128(v[N - 1]),
            _mm256_extractf128_pd::<1>(v[N - 1]),
        );
        let last = &mut x[4 * (N - 1)..];
        _mm_store_sd(&mut last[0], lo);
        if m > 1 {
            _mm_storeh_pd(&mut last[1], lo);
        }
        if m > 2 {
            _mm_store_sd(&mut last[2], hi);
        }
        if m > 3 {
            _mm_storeh_pd(&mut last[3], hi);
        }
    }
}

/// [`lu_solve`] for k = 2, from the factors `[inv_u00, l10, u01, inv_u11]` (column-major), the
/// interchange of the two rows if `swap`, and the right-hand side (r0, r1).
#[inline(always)]
pub(super) fn solve_2x2<T: Scalar>(
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

/// The scales of the column-major k × k `a` that [`pivots_clear`] measures its pivots with,
/// into `out` (length 3k, the last k a scratch): the largest entry (in [`Scalar::norm1`]) of
/// each row, `out[..k]`, and of each column once every row is divided by its own,
/// `out[k..2k]` (LAPACK's `dgeequ` equilibration, as sizes rather than their reciprocals).
pub(super) fn scales<T: Scalar>(a: &[T], k: usize, out: &mut [f64]) {
    if k == 0 {
        // An empty block (a partition without a border): nothing to scale.
        return;
    }
    let (rows, rest) = out[..3 * k].split_at_mut(k);
    let (columns, inverse) = rest.split_at_mut(k);
    rows.fill(0.0);
    for column in a[..k * k].chunks_exact(k) {
        for (m, v) in rows.iter_mut().zip(column) {
            *m = larger(*m, v.norm1());
        }
    }
    // A product by each row's reciprocal instead of a division per entry (a zero row, whose
    // reciprocal is taken as 0, adds nothing), and at most 1, which the exact quotients are and
    // the rounded products may exceed by an ulp. The scales only judge the pivots: their
    // rounding changes no result.
    for (q, &r) in inverse.iter_mut().zip(rows.iter()) {
        *q = if r > 0.0 { 1.0 / r } else { 0.0 };
    }
    for (m, column) in columns.iter_mut().zip(a[..k * k].chunks_exact(k)) {
        // Four running maxima, so that the comparisons do not wait on each other.
        let mut four = [0.0f64; 4];
        let (body, tail) = column.split_at(k - k % 4);
        for (v, q) in body.chunks_exact(4).zip(inverse.chunks_exact(4)) {
            for l in 0..4 {
                four[l] = larger(four[l], v[l].norm1() * q[l]);
            }
        }
        let quotients = tail.iter().zip(&inverse[k - k % 4..]);
        let most = quotients.fold(
            larger(larger(four[0], four[1]), larger(four[2], four[3])),
            |m, (v, &q)| larger(m, v.norm1() * q),
        );
        *m = most.min(1.0);
    }
}

/// The larger of `m` and `x`, `m` if `x` is NaN: one comparison the compiler can vectorise
/// (`f64::max`'s handling of NaN in either operand keeps it from doing so).
#[inline(always)]
fn larger(m: f64, x: f64) -> f64 {
    if x > m {
        x
    } else {
        m
    }
}

/// Whether every pivot of the LU `lu` from [`lu_in_place`] (interchanges `piv`) is above
/// `floor` in the equilibrated matrix: `|u_jj| > floor r c`, with `r` the largest entry of the
/// row the pivot came from and `c` that of its column once the rows are scaled to 1 (`scales`,
/// [`scales`] of the matrix before the factorisation; its rows' part is permuted here as the rows
/// were).
///
/// The test does not depend on the rows' and columns' scales, which are the states' units: a
/// plate mode's block pairs its displacement's row, whose entries are near `1/(h γ)` and `1/m`,
/// with its momentum's, near its stiffness, up to 1e11 apart in a 20 × 20 plate, and a block of
/// the servo valve has a column of pressures' rates per unit volume, 1e16 against the others'
/// 1e2. Against the block's largest entry, such blocks would be refused though their
/// elimination is as stable as any. Every pivot that measure accepts is accepted here too:
/// `r` is at most the largest entry and `c` at most 1.
pub(super) fn pivots_clear<T: Scalar>(
    lu: &[T],
    k: usize,
    piv: &[usize],
    scales: &mut [f64],
    floor: f64,
) -> bool {
    let (rows, columns) = scales[..2 * k].split_at_mut(k);
    for j in 0..k {
        rows.swap(j, piv[j]);
        // The diagonal holds the pivot's reciprocal (finite and non-zero: the kernels refuse
        // other pivots).
        let pivot = (T::ONE / lu[j + j * k]).norm1();
        if pivot <= floor * rows[j] * columns[j] {
            return false;
        }
    }
    true
}

/// The LU of a block of one state `a` in place and its pivot test, with the verdict and the
/// bits of [`scales`], [`lu_in_place`] and [`pivots_clear`] (with `floor`; none if it is 0):
/// the plate's modes are such blocks, twenty of them in every factorisation of the default
/// plant, and the general path's slices, scratch and loops cost several times the few
/// operations they come to for k = 1.
///
/// For k = 1 those come to: the pivot's size `|a|` ([`Scalar::norm1`]), refused if zero or not
/// finite; `1/a` in place; the row's scale `r = |a|` and the column's `min(|a| (1/r), 1)`, and
/// the test `|1/(1/a)| > floor r c` (false, as there, if the pivot is not above it).
pub(super) fn factor_one<T: Scalar>(a: &mut T, piv: &mut usize, floor: f64) -> bool {
    let v = *a;
    let size = v.norm1();
    *piv = 0;
    if size == 0.0 || !size.is_finite() {
        return false;
    }
    *a = T::ONE / v;
    if floor == 0.0 {
        return true;
    }
    let row = size;
    let column = larger(0.0, size * (1.0 / row)).min(1.0);
    let pivot = (T::ONE / *a).norm1();
    if pivot <= floor * row * column {
        return false;
    }
    true
}

/// Step j's pivot ([`pivot`]) and column j made into multipliers: its entries below the
/// diagonal divided by the pivot, the pivot's reciprocal on the diagonal. False if the pivot is
/// refused.
#[inline(always)]
fn pivot_and_scale<T: Scalar>(a: &mut [T], k: usize, j: usize, piv: &mut [usize]) -> bool {
    if !pivot(a, k, j, piv) {
        return false;
    }
    let column = &mut a[j * k..j * k + k];
    let d = column[j];
    for v in &mut column[j + 1..] {
        *v = *v / d;
    }
    column[j] = T::ONE / d;
    true
}

/// Step j's partial pivoting in the column-major k × k `a`: the row of column j's largest entry
/// at or below the diagonal, recorded in `piv[j]` and swapped into row j; false if that entry
/// is zero, not finite, or not above `tiny`.
#[inline(always)]
fn pivot<T: Scalar>(a: &mut [T], k: usize, j: usize, piv: &mut [usize]) -> bool {
    let column = &a[j * k..j * k + k];
    let mut p = j;
    let mut pmax = column[j].norm1();
    for (r, v) in column.iter().enumerate().skip(j + 1) {
        let v = v.norm1();
        if v > pmax {
            p = r;
            pmax = v;
        }
    }
    piv[j] = p;
    if pmax == 0.0 || !pmax.is_finite() {
        return false;
    }
    if p != j {
        // Column by column, so that the indices' checks (j, p < k) do not depend on the column
        // and leave the loop.
        for column in a[..k * k].chunks_exact_mut(k) {
            column.swap(j, p);
        }
    }
    true
}

/// [`lu_solve`] for any k (inlined, so that a constant k unrolls the loops).
#[inline(always)]
pub(super) fn lu_solve_loops<T: Scalar>(a: &[T], k: usize, piv: &[usize], x: &mut [T]) {
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

#[cfg(test)]
mod tests {
    use std::cell::Cell;

    use nalgebra::Complex;

    use super::super::testing::Rng;
    use super::*;

    /// The smallest block the vector kernels take (on x86-64; on other processors every size is
    /// the loops').
    const VECTOR_FROM_ALL: usize = 9;

    thread_local! {
        /// The kernels take the portable loops even where AVX2 is available.
        pub(super) static PORTABLE_ONLY: Cell<bool> = const { Cell::new(false) };
    }

    /// [`pivots_clear`] accepts every block that a test against the block's largest entry
    /// (every pivot above 1e-10 of it) accepts, and more: random blocks of 1 to 6 states, some nearly singular, with rows
    /// and columns scaled by up to 1e±6.
    #[test]
    fn the_equilibrated_test_accepts_what_the_block_test_accepts() {
        let mut rng = Rng(5);
        let (mut old_accepts, mut only_new) = (0, 0);
        for round in 0..4000 {
            let k = 1 + round % 6;
            let mut a: Vec<f64> = (0..k * k).map(|_| rng.next()).collect();
            if round % 3 == 0 && k > 1 {
                // row k-1 nearly a multiple of row 0
                let f = rng.next();
                for c in 0..k {
                    a[k - 1 + c * k] = f * a[c * k] + 1e-11 * rng.next();
                }
            }
            let row: Vec<f64> = (0..k)
                .map(|_| 10f64.powi((6.0 * rng.next()) as i32))
                .collect();
            let col: Vec<f64> = (0..k)
                .map(|_| 10f64.powi((6.0 * rng.next()) as i32))
                .collect();
            for (i, v) in a.iter_mut().enumerate() {
                *v *= row[i % k] * col[i / k];
            }
            // The block test: every pivot above 1e-10 of the block's largest entry (the
            // pivots are those of the same elimination; the diagonal holds their reciprocals).
            let largest = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let mut scratch = vec![0.0; 3 * k];
            scales(&a, k, &mut scratch);
            let mut piv = vec![0; k];
            let factorised = lu_in_place(&mut a, k, &mut piv);
            let by_block =
                factorised && (0..k).all(|j| (1.0 / a[j + j * k]).abs() > 1e-10 * largest);
            let by_rows = factorised && pivots_clear(&a, k, &piv, &mut scratch, 1e-10);
            assert!(
                !by_block || by_rows,
                "round {round}: refused what the block test accepts"
            );
            old_accepts += usize::from(by_block);
            only_new += usize::from(by_rows && !by_block);
        }
        assert!(
            old_accepts > 1000 && only_new > 100,
            "{old_accepts} {only_new}"
        );
    }

    /// [`lu_in_place`]'s elimination as it was written with index loops (its pivoting is the
    /// same [`pivot`]), the reference for the bits of the iterator loops; and the solve with the
    /// index loops of [`lu_solve_loops`].
    fn lu_indexed(a: &mut [f64], k: usize, piv: &mut [usize]) -> bool {
        for j in 0..k {
            if !pivot(a, k, j, piv) {
                return false;
            }
            let d = a[j + j * k];
            for r in j + 1..k {
                a[r + j * k] /= d;
            }
            a[j + j * k] = 1.0 / d;
            for c in j + 1..k {
                let f = a[j + c * k];
                if f != 0.0 {
                    for r in j + 1..k {
                        a[r + c * k] -= a[r + j * k] * f;
                    }
                }
            }
        }
        true
    }

    fn solve_indexed(a: &[f64], k: usize, piv: &[usize], x: &mut [f64]) {
        for j in 0..k {
            if piv[j] != j {
                x.swap(j, piv[j]);
            }
        }
        for j in 0..k {
            let v = x[j];
            if v != 0.0 {
                for r in j + 1..k {
                    x[r] -= a[r + j * k] * v;
                }
            }
        }
        for j in (0..k).rev() {
            let v = x[j] * a[j + j * k];
            x[j] = v;
            if v != 0.0 {
                for r in 0..j {
                    x[r] -= a[r + j * k] * v;
                }
            }
        }
    }

    /// The iterator loops of the factorisation (portable and AVX2) give the bits of the index
    /// loops they replaced, and so do the solves, on random matrices of 0 to 60 states with zeros.
    #[test]
    fn the_loops_have_the_index_loops_bits() {
        let mut rng = Rng(0x2f7b_91c3_0a6d_5e41);
        for k in [0, 1, 2, 3, 5, 8, 9, 17, 46, 60] {
            for trial in 0..4 {
                let a: Vec<f64> = (0..k * k)
                    .map(|i| {
                        if (i + trial) % 6 == 2 {
                            0.0
                        } else {
                            rng.next()
                        }
                    })
                    .collect();
                let rhs: Vec<f64> = (0..k)
                    .map(|i| if i % 4 == 1 { 0.0 } else { rng.next() })
                    .collect();
                let (mut lu, mut reference) = (a.clone(), a.clone());
                let (mut piv, mut piv_ref) = (vec![0; k], vec![0; k]);
                let ok = lu_in_place(&mut lu, k, &mut piv);
                assert_eq!(ok, lu_indexed(&mut reference, k, &mut piv_ref));
                if !ok {
                    // Refused at the same column; the half-eliminated rest is nobody's (the
                    // panels leave it differently).
                    assert_eq!(piv, piv_ref, "k = {k}");
                    continue;
                }
                assert_eq!(
                    format!("{lu:?} {piv:?}"),
                    format!("{reference:?} {piv_ref:?}"),
                    "k = {k}"
                );
                let (mut x, mut x_ref) = (rhs.clone(), rhs.clone());
                lu_solve(&lu, k, &piv, &mut x);
                solve_indexed(&reference, k, &piv_ref, &mut x_ref);
                assert_eq!(format!("{x:?}"), format!("{x_ref:?}"), "k = {k}");
            }
        }
    }

    /// The factorisation in panels gives the bits of the loops one elimination at a time, real
    /// and complex, for sizes around and across the panel width, with zeros (whose
    /// eliminations are skipped, some whole panels' worth) and row interchanges; and a singular
    /// matrix is refused at the same column.
    #[test]
    fn the_panels_have_the_loops_bits() {
        fn both<T: Scalar + std::fmt::Debug>(a: &[T], k: usize) -> [String; 2] {
            let mut lu = a.to_vec();
            let mut piv = vec![usize::MAX; k];
            let ok = lu_in_place_panels(&mut lu, k, &mut piv);
            let mut reference = a.to_vec();
            let mut piv_ref = vec![usize::MAX; k];
            let ok_ref = lu_in_place_loops(&mut reference, k, &mut piv_ref);
            // A refused matrix is left half-eliminated, differently: only the refusal and the
            // column it came at (the pivots chosen up to it) are compared.
            if !(ok && ok_ref) {
                return [format!("{ok} {piv:?}"), format!("{ok_ref} {piv_ref:?}")];
            }
            [
                format!("{ok} {lu:?} {piv:?}"),
                format!("{ok_ref} {reference:?} {piv_ref:?}"),
            ]
        }
        let mut rng = Rng(0x1d8e_4e27_c47d_124f);
        let mut swaps = 0;
        for k in [9, 10, 11, 12, 13, 16, 17, 46, 61, 100] {
            for trial in 0..6 {
                let a: Vec<f64> = (0..k * k)
                    .map(|i| {
                        let (r, c) = (i % k, i / k);
                        match trial {
                            // Zeros scattered, and whole rows of zeros right of the diagonal
                            // (multipliers that skip every elimination of a panel).
                            1 if r % 5 == 2 && c > r => 0.0,
                            2 if (i * 7) % 3 == 0 => 0.0,
                            // Singular: two equal columns.
                            3 if c == k - 2 => 0.0,
                            _ => rng.next(),
                        }
                    })
                    .collect();
                let mut a = a;
                if trial == 4 {
                    let (first, rest) = a.split_at_mut(5 * k);
                    rest[..k].copy_from_slice(&first[2 * k..3 * k]);
                }
                let [panels, loops] = both(&a, k);
                assert_eq!(panels, loops, "real, k = {k}, trial {trial}");
                let mut piv = vec![0; k];
                lu_in_place_loops(&mut a.clone(), k, &mut piv);
                swaps += piv.iter().enumerate().filter(|&(j, &p)| p != j).count();
                let ac: Vec<Complex<f64>> = a
                    .iter()
                    .enumerate()
                    .map(|(i, &x)| {
                        Complex::new(x, if x == 0.0 { 0.0 } else { a[(i * 5) % (k * k)] })
                    })
                    .collect();
                let [panels, loops] = both(&ac, k);
                assert_eq!(panels, loops, "complex, k = {k}, trial {trial}");
            }
        }
        assert!(swaps > 500, "row interchanges exercised: {swaps}");
    }

    /// The factorisation and the solve of a large block compiled for AVX2 give the portable
    /// loops' bits: random real and complex matrices of 9 to 130 states, panels from 96 (with
    /// zeros, which the loops skip, and row interchanges), factorised and solved both ways,
    /// compared bit for bit.
    /// (On a processor without AVX2 both ways are the portable loops.)
    #[test]
    fn avx2_kernels_have_the_portable_bits() {
        fn both<T: Scalar + std::fmt::Debug>(a: &[T], k: usize, rhs: &[T]) -> [String; 2] {
            [false, true].map(|portable| {
                PORTABLE_ONLY.with(|p| p.set(portable));
                let mut lu = a.to_vec();
                let mut piv = vec![0; k];
                let ok = lu_in_place(&mut lu, k, &mut piv);
                let mut x = rhs.to_vec();
                lu_solve(&lu, k, &piv, &mut x);
                PORTABLE_ONLY.with(|p| p.set(false));
                format!("{ok} {lu:?} {piv:?} {x:?}")
            })
        }
        let mut rng = Rng(0x5851_f42d_4c95_7f2d);
        for k in [9, 13, 17, 31, 46, 60, 97, 130] {
            let a: Vec<f64> = (0..k * k)
                .map(|i| if i % 7 == 3 { 0.0 } else { rng.next() })
                .collect();
            let rhs: Vec<f64> = (0..k)
                .map(|i| if i % 5 == 0 { 0.0 } else { rng.next() })
                .collect();
            let [vector, portable] = both(&a, k, &rhs);
            assert_eq!(vector, portable, "real, k = {k}");
            let ac: Vec<Complex<f64>> = a
                .iter()
                .enumerate()
                .map(|(i, &x)| Complex::new(x, a[(i * 5) % (k * k)]))
                .collect();
            let rc: Vec<Complex<f64>> = rhs.iter().map(|&v| Complex::new(v, 0.5 - v)).collect();
            let [vector, portable] = both(&ac, k, &rc);
            assert_eq!(vector, portable, "complex, k = {k}");
        }
    }

    /// The AVX2 kernel for the LU of small real blocks ([`lu_in_place_small_real_avx2`], where
    /// the processor has AVX2) gives the loops' bits for every size it takes, every length of
    /// its partial vectors: matrices with exact zeros (a zero multiplier skips its column),
    /// some with a zero column (refused at the same step, the entries left as the loops leave
    /// them).
    #[test]
    fn the_small_real_lu_kernel_has_the_loops_bits() {
        let mut rng = Rng(0x7137_449d_23ef_65cd);
        for k in VECTOR_FROM_ALL..=70 {
            for trial in 0..6 {
                let mut a: Vec<f64> = (0..k * k)
                    .map(|_| rng.next())
                    .map(|v| if v.abs() < 0.1 { 0.0 } else { v })
                    .collect();
                if trial == 5 {
                    let c = k / 2;
                    a[c * k..c * k + k].fill(0.0);
                }
                let (mut fast, mut loops) = (a.clone(), a);
                let (mut pf, mut pl) = (vec![0; k], vec![0; k]);
                let ok = lu_in_place(&mut fast, k, &mut pf);
                assert_eq!(ok, lu_in_place_loops(&mut loops, k, &mut pl));
                assert_eq!(ok, trial != 5, "k = {k}, trial {trial}");
                let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&fast), bits(&loops), "k = {k}, trial {trial}");
                assert_eq!(pf, pl);
            }
        }
    }

    /// [`factor_one`] gives the verdict and the bits of the general path for a block of one
    /// state, with and without a floor, real and complex: ordinary values, values whose
    /// reciprocal's reciprocal is not exact, subnormals (whose reciprocal overflows), the
    /// largest and smallest normal numbers, zeros, infinities and NaN.
    #[test]
    fn the_block_of_one_state_has_the_general_paths_bits() {
        fn general<T: Scalar>(v: T, floor: f64) -> (bool, T, usize) {
            let (mut a, mut piv, mut scratch) = ([v], [7usize], [f64::NAN; 3]);
            let ok = if floor == 0.0 {
                lu_in_place(&mut a, 1, &mut piv)
            } else {
                scales(&a, 1, &mut scratch);
                lu_in_place(&mut a, 1, &mut piv) && pivots_clear(&a, 1, &piv, &mut scratch, floor)
            };
            (ok, a[0], piv[0])
        }
        fn check<T: Scalar>(v: T) {
            for floor in [0.0, 1e-10, 0.5, 1.0, 2.0] {
                let (mut a, mut piv) = (v, 7usize);
                let ok = factor_one(&mut a, &mut piv, floor);
                let (ok_ref, a_ref, piv_ref) = general(v, floor);
                assert_eq!(ok, ok_ref, "{v:?}, floor {floor}");
                if ok {
                    assert_eq!(format!("{a:?} {piv}"), format!("{a_ref:?} {piv_ref}"));
                }
            }
        }
        let mut rng = Rng(0x3c6e_f372_fe94_f82b);
        let mut values = vec![
            0.0,
            -0.0,
            1.0,
            3.0,
            -7.0,
            f64::MIN_POSITIVE,
            f64::MIN_POSITIVE / 3.0,
            -5e-324,
            f64::MAX,
            -f64::MAX,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            1e308 * 1.7,
            1e-308 * 1.3,
        ];
        values.extend((0..500).map(|i| rng.next() * 10f64.powi(i % 600 - 300)));
        for &v in &values {
            check(v);
            for &w in &values[..20] {
                check(Complex::new(v, w));
                check(Complex::new(w, v));
            }
        }
    }

    /// The AVX2 kernels for small real blocks ([`lu_solve_small_real_avx2`], and
    /// [`lu_solve_in_registers`] up to [`IN_REGISTERS`] states, where the processor has AVX2)
    /// give the loops' bits for every size they take, every length of their partial vectors:
    /// right-hand sides with zeros of both signs (a zero multiplier skips its column, a
    /// negative zero left in place stays one) and exactly zero factors; then made-up factors,
    /// mostly zeros (zero multipliers in the middle of the chains, zeros on the diagonal) with
    /// random interchanges, right-hand sides of negative zeros but for one row, and infinite
    /// and NaN entries (infinite factors; NaN only in the right-hand side, since of a product
    /// of two NaNs the loops' own bits are the compiler's choice of operand order).
    #[test]
    fn the_small_real_kernel_has_the_loops_bits() {
        let mut rng = Rng(0x1405_7b7e_f767_814f);
        for k in VECTOR_FROM_ALL..=70 {
            for trial in 0..6 {
                let a: Vec<f64> = (0..k * k)
                    .map(|_| rng.next())
                    .map(|v| if v.abs() < 0.1 { 0.0 } else { v })
                    .collect();
                let mut lu = a.clone();
                let mut piv = vec![0; k];
                assert!(lu_in_place_loops(&mut lu, k, &mut piv));
                let rhs: Vec<f64> = (0..k)
                    .map(|i| match (i + trial) % 6 {
                        0 => 0.0,
                        1 if trial % 2 == 0 => -0.0,
                        _ => rng.next(),
                    })
                    .collect();
                let (mut fast, mut loops) = (rhs.clone(), rhs);
                lu_solve(&lu, k, &piv, &mut fast);
                lu_solve_loops(&lu, k, &piv, &mut loops);
                let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&fast), bits(&loops), "k = {k}, trial {trial}");
            }
            for trial in 0..24 {
                let mut lu: Vec<f64> = (0..k * k)
                    .map(|_| rng.next())
                    .map(|v| if v.abs() < 0.7 { 0.0 } else { v * 3.0 })
                    .collect();
                let piv: Vec<usize> = (0..k)
                    .map(|j| j + ((rng.next() + 1.0) * k as f64) as usize % (k - j))
                    .collect();
                let mut rhs: Vec<f64> = (0..k)
                    .map(|_| rng.next())
                    .map(|v| {
                        if v.abs() < 0.3 {
                            [0.0, -0.0][trial % 2]
                        } else {
                            v
                        }
                    })
                    .collect();
                let at = |r: f64| ((r + 1.0) * k as f64) as usize % k;
                match trial % 8 {
                    0 => rhs.fill(-0.0),
                    1 => {
                        rhs.fill(-0.0);
                        rhs[at(rng.next())] = rng.next();
                    }
                    2 => rhs[at(rng.next())] = f64::INFINITY,
                    3 => {
                        rhs[at(rng.next())] = f64::NEG_INFINITY;
                        rhs[at(rng.next())] = f64::NAN;
                    }
                    4 => {
                        for _ in 0..3 {
                            lu[at(rng.next()) * k + at(rng.next())] = f64::INFINITY;
                        }
                    }
                    5 => {
                        let j = at(rng.next());
                        lu[j * k + j] = f64::NEG_INFINITY;
                        rhs[at(rng.next())] = f64::INFINITY;
                    }
                    _ => {}
                }
                let (mut fast, mut loops) = (rhs.clone(), rhs);
                lu_solve(&lu, k, &piv, &mut fast);
                lu_solve_loops(&lu, k, &piv, &mut loops);
                let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&fast), bits(&loops), "k = {k}, made-up trial {trial}");
            }
        }
    }

    /// The written-out solves for blocks of one and two states, and the unrolled ones of three
    /// to eight, give the loops' bits, with and without a row interchange, for real and complex
    /// systems, zeros included.
    #[test]
    fn small_block_solves_match_the_loops_bit_for_bit() {
        fn check<T: Scalar + std::fmt::Debug>(a: &[T], k: usize, rhs: &[T]) {
            let mut lu = a.to_vec();
            let mut piv = vec![0; k];
            assert!(lu_in_place(&mut lu, k, &mut piv));
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
}
