//! Sparse dot products four at a time, each with the operations it has alone, in their order,
//! so each value has the same bits as alone.
//!
//! The model's right-hand side is mostly sparse linear forms `c + Σ a_t w_{v_t}` over its
//! variables: the affine rows of f (a sparse product with the constant Jacobian) and, in the
//! rows that are not affine, the operands of the nonlinear operations and the rows themselves
//! ([`crate::bond_graph::NonaffineForms`]). The plate's drag makes most of them: at each of its
//! points the relative air speed is a form over the same few momenta, and each mode's row sums
//! the forces of all the points with the modes' linear terms. Alone, each term costs a load of
//! its (variable, coefficient) pair, a bounds check, a load of the variable, a product and a
//! sum, each sum waiting on the one before. Forms of one length side by side, their terms
//! stored term by term across the [`LANES`] forms of a chunk, share the loop: a term's four
//! variables are one gather, its products and sums one vector operation for the four forms.
//!
//! A form is summed in one of two orders ([`Summation`]), the order its alone evaluation uses;
//! the lanes keep it, without fused multiply-adds, so the bits are those of the form alone on
//! every platform (the unit test `each_lane_is_its_form_alone_to_the_bit`, with the AVX2
//! kernel and with the portable loops the browser build uses).

use std::ops::Range;

/// The number of forms side by side.
pub const LANES: usize = 4;

/// How a form `c + Σ_t a_t w_t` is summed (by its evaluation alone, which the lanes repeat).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Summation {
    /// From `c`, term after term: `((c + p_0) + p_1) + …`.
    Fold,
    /// With `len ≥ from` terms: four running sums over the terms up to the last multiple of
    /// four (term `4i + s` into sum `s`, each from 0), the other terms added to `c` in order,
    /// then `rest + ((s_0 + s_1) + (s_2 + s_3))`; a shorter form as [`Summation::Fold`]. Four
    /// sums let the products of a long form proceed without waiting on each other's sums.
    Split {
        /// The least number of terms summed so.
        from: usize,
    },
}

impl Summation {
    /// The form `c + Σ a_t w_{v_t}` over `terms` (variable, coefficient) alone, summed in this
    /// order: the value a lane of a run repeats to the bit.
    #[inline(always)]
    pub fn sum(self, w: &[f64], c: f64, terms: &[(u32, f64)]) -> f64 {
        let term = |&(v, a): &(u32, f64)| a * w[v as usize];
        let (body, tail) = terms.split_at(self.body(terms.len()));
        let rest = tail.iter().fold(c, |acc, t| acc + term(t));
        if body.is_empty() {
            return rest;
        }
        let mut sums = [0.0; 4];
        for four in body.chunks_exact(4) {
            for (s, t) in sums.iter_mut().zip(four) {
                *s += term(t);
            }
        }
        rest + ((sums[0] + sums[1]) + (sums[2] + sums[3]))
    }

    /// The number of leading terms of a form of `len` terms that go to the four running sums.
    fn body(self, len: usize) -> usize {
        match self {
            Summation::Split { from } if len >= from => len - len % 4,
            _ => 0,
        }
    }
}

/// A run of consecutive forms of `len` terms each, laid out by [`Lanes::add`]: `count` forms
/// from the `first`, in chunks of [`LANES`] (the last padded with forms of zero coefficients,
/// whose values are not used).
#[derive(Clone, Copy, Debug)]
pub struct Run {
    first: u32,
    count: u32,
    len: u32,
    /// Chunk `k`'s term `t` of lane `l` is at `at + (k len + t) LANES + l` of the layout.
    at: u32,
    summation: Summation,
    /// Bit `k` set: in every term of chunk `k` the four lanes read one variable (the drag
    /// points' air speeds over the same momenta), which the AVX2 kernel then loads once and
    /// broadcasts instead of gathering it. Chunks from the 32nd on are gathered.
    shared: u32,
}

impl Run {
    /// The number of chunks of [`LANES`] forms.
    pub fn chunks(&self) -> usize {
        (self.count as usize).div_ceil(LANES)
    }

    /// The forms (their indices as given to [`Lanes::add`]) of chunk `k`: up to [`LANES`], fewer
    /// in the last chunk.
    pub fn chunk(&self, k: usize) -> Range<usize> {
        let from = self.first as usize + k * LANES;
        from..((self.first + self.count) as usize).min(from + LANES)
    }

    /// The forms of the run.
    pub fn forms(&self) -> Range<usize> {
        self.first as usize..(self.first + self.count) as usize
    }

    /// Whether the lanes of chunk `k` read one variable in every term (see `shared`): the AVX2
    /// kernel loads each once and broadcasts it.
    pub fn is_shared(&self, k: usize) -> bool {
        k < 32 && self.shared >> k & 1 == 1
    }
}

/// Runs of forms laid out across lanes (see the [module documentation](self)).
#[derive(Clone, Debug, Default)]
pub struct Lanes {
    variable: Vec<u32>,
    coefficient: Vec<f64>,
    /// One more than the largest variable a lane reads: the least length of the variables a
    /// chunk is evaluated at.
    reads_below: usize,
}

/// The ranges of consecutive forms of one length, at least `min_terms` long, that make runs of
/// two forms or more (the forms' lengths given in order).
pub fn equal_lengths(lengths: &[usize], min_terms: usize) -> Vec<Range<usize>> {
    let mut out = Vec::new();
    let mut r = 0;
    while r < lengths.len() {
        let end = r + lengths[r..]
            .iter()
            .take_while(|&&n| n == lengths[r])
            .count();
        if lengths[r] >= min_terms && end - r >= 2 {
            out.push(r..end);
        }
        r = end;
    }
    out
}

impl Lanes {
    /// Lays out `forms` (their terms (variable, coefficient), all of one length), the first
    /// being form `first` of the caller's numbering, summed by `summation`.
    pub fn add(&mut self, first: usize, forms: &[&[(u32, f64)]], summation: Summation) -> Run {
        let len = forms.first().map_or(0, |f| f.len());
        assert!(
            forms.iter().all(|f| f.len() == len),
            "a run's forms have one length"
        );
        let mut run = Run {
            first: first as u32,
            count: forms.len() as u32,
            len: len as u32,
            at: self.variable.len() as u32,
            summation,
            shared: 0,
        };
        for (k, chunk) in forms.chunks(LANES).enumerate() {
            let shared = (0..len).all(|t| chunk.iter().all(|f| f[t].0 == chunk[0][t].0));
            if shared && k < 32 {
                run.shared |= 1 << k;
            }
            for t in 0..len {
                // Padding lanes read the first lane's variable with a zero coefficient.
                let lane = |l: usize| chunk.get(l).map_or((chunk[0][t].0, 0.0), |f| f[t]);
                let row: [(u32, f64); LANES] = std::array::from_fn(lane);
                for (v, a) in row {
                    assert!(v < 1 << 31, "a variable fits a gather's index");
                    self.reads_below = self.reads_below.max(v as usize + 1);
                    self.variable.push(v);
                    self.coefficient.push(a);
                }
            }
        }
        run
    }

    /// The values of the forms of `run` at the variables `w`, each given to `out(form, value)`
    /// in order, the form `i`'s constant being `constant(i)` (forms numbered as given to
    /// [`Lanes::add`]): each value to the bit that of the form alone summed by the run's
    /// [`Summation`]. With AVX2, where the processor has it, the four lanes of a chunk are one
    /// vector operation (products and sums apart, no fused multiply-add, so the same bits as
    /// the portable loops).
    #[inline]
    pub fn each_value(
        &self,
        w: &[f64],
        run: &Run,
        constant: impl Fn(usize) -> f64,
        out: impl FnMut(usize, f64),
    ) {
        assert!(w.len() >= self.reads_below, "the forms' variables");
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the processor has AVX2 (checked just above); every variable of the
                // lanes is below `reads_below` (`add`), which `w`'s length is not below
                // (asserted above).
                unsafe { self.each_value_avx2(w, run, constant, out) };
                return;
            }
        }
        self.each_chunk::<false>(w, run, constant, out);
    }

    /// [`Lanes::each_value`] compiled for AVX2.
    ///
    /// # Safety
    /// The processor has AVX2 and `w` is at least `reads_below` long.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn each_value_avx2(
        &self,
        w: &[f64],
        run: &Run,
        constant: impl Fn(usize) -> f64,
        out: impl FnMut(usize, f64),
    ) {
        self.each_chunk::<true>(w, run, constant, out);
    }

    /// [`Lanes::each_value`]'s loop over the chunks, with the AVX2 kernel (`AVX2`, which the
    /// caller has checked the processor has, and `w`'s length) or the portable loops.
    #[inline(always)]
    fn each_chunk<const AVX2: bool>(
        &self,
        w: &[f64],
        run: &Run,
        constant: impl Fn(usize) -> f64,
        mut out: impl FnMut(usize, f64),
    ) {
        let len = run.len as usize;
        let body = run.summation.body(len);
        for k in 0..run.chunks() {
            let chunk = run.chunk(k);
            let c = std::array::from_fn(|l| {
                let i = chunk.start + l;
                if i < chunk.end {
                    constant(i)
                } else {
                    0.0
                }
            });
            let from = run.at as usize + k * LANES * len;
            let variable = &self.variable[from..from + LANES * len];
            let coefficient = &self.coefficient[from..from + LANES * len];
            let values = if AVX2 {
                #[cfg(target_arch = "x86_64")]
                {
                    // SAFETY: the caller has checked that the processor has AVX2 and that
                    // `w` is long enough for every variable of the lanes; the slices hold
                    // `len` rows of terms.
                    unsafe {
                        match run.is_shared(k) {
                            true => values_avx2::<true>(w, variable, coefficient, body, c),
                            false => values_avx2::<false>(w, variable, coefficient, body, c),
                        }
                    }
                }
                #[cfg(not(target_arch = "x86_64"))]
                unreachable!("AVX2 is an x86-64 extension")
            } else {
                values_loops(w, variable, coefficient, body, c)
            };
            for (i, v) in chunk.zip(values) {
                out(i, v);
            }
        }
    }
}

/// A chunk's values lane by lane: each form's terms summed as the form alone sums them, the
/// first `body` into the four running sums.
fn values_loops(
    w: &[f64],
    variable: &[u32],
    coefficient: &[f64],
    body: usize,
    c: [f64; LANES],
) -> [f64; LANES] {
    std::array::from_fn(|l| {
        let term = |t: usize| coefficient[t * LANES + l] * w[variable[t * LANES + l] as usize];
        let len = variable.len() / LANES;
        let mut sums = [0.0; 4];
        for t in (0..body).step_by(4) {
            for (s, sum) in sums.iter_mut().enumerate() {
                *sum += term(t + s);
            }
        }
        let rest = (body..len).fold(c[l], |acc, t| acc + term(t));
        if body == 0 {
            rest
        } else {
            rest + ((sums[0] + sums[1]) + (sums[2] + sums[3]))
        }
    })
}

/// A chunk's values with AVX2: a row of four terms is one gather of its variables (with
/// `SHARED`, a chunk whose lanes read one variable in every row, one load of it broadcast to
/// the four lanes: the same four values, so the same bits), one vector product and one vector
/// sum. (The choice is made per chunk when the chunks are laid out: a branch per row cost more
/// instructions than the broadcast saved, by callgrind on the default plant.)
///
/// # Safety
/// The processor has AVX2; `variable` and `coefficient` hold the same number of rows of
/// [`LANES`] terms; every variable is below `w.len()` (and below 2^31); with `SHARED`, the four
/// variables of each row are one.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn values_avx2<const SHARED: bool>(
    w: &[f64],
    variable: &[u32],
    coefficient: &[f64],
    body: usize,
    c: [f64; LANES],
) -> [f64; LANES] {
    use std::arch::x86_64::*;
    let len = variable.len() / LANES;
    let (v, a, w) = (variable.as_ptr(), coefficient.as_ptr(), w.as_ptr());
    let row = |t: usize| -> __m256d {
        // SAFETY: row `t < len` of `variable` and `coefficient` is at `t · LANES`; a variable
        // read is below `w`'s length (the caller's contract).
        unsafe {
            let x = if SHARED {
                _mm256_broadcast_sd(&*w.add(*v.add(t * LANES) as usize))
            } else {
                let index = _mm_loadu_si128(v.add(t * LANES) as *const __m128i);
                _mm256_i32gather_pd::<8>(w, index)
            };
            _mm256_mul_pd(_mm256_loadu_pd(a.add(t * LANES)), x)
        }
    };
    let mut sums = [_mm256_setzero_pd(); 4];
    let mut t = 0;
    while t < body {
        for (s, sum) in sums.iter_mut().enumerate() {
            *sum = _mm256_add_pd(*sum, row(t + s));
        }
        t += 4;
    }
    // SAFETY: `c` holds four doubles.
    let mut rest = unsafe { _mm256_loadu_pd(c.as_ptr()) };
    for t in body..len {
        rest = _mm256_add_pd(rest, row(t));
    }
    if body > 0 {
        let pairs = _mm256_add_pd(
            _mm256_add_pd(sums[0], sums[1]),
            _mm256_add_pd(sums[2], sums[3]),
        );
        rest = _mm256_add_pd(rest, pairs);
    }
    let mut out = [0.0; LANES];
    // SAFETY: `out` holds four doubles.
    unsafe { _mm256_storeu_pd(out.as_mut_ptr(), rest) };
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pseudo-random doubles of mixed magnitudes and signs (no rounding-free sums).
    fn value(i: usize) -> f64 {
        let x = ((i as f64 + 1.0) * 0.618_033_988_749_895).fract();
        (x - 0.5) * 10f64.powi((i % 7) as i32 - 3)
    }

    /// The two orders as their documentation writes them, term by term.
    #[test]
    fn the_summations_are_the_documented_orders() {
        let w: Vec<f64> = (0..12).map(|i| value(5 * i + 2)).collect();
        let terms: Vec<(u32, f64)> = (0..9).map(|t| ((11 - t) as u32, value(t + 40))).collect();
        let p: Vec<f64> = terms.iter().map(|&(v, a)| a * w[v as usize]).collect();
        let c = value(77);
        let fold = ((c + p[0]) + p[1]) + p[2];
        assert_eq!(
            Summation::Fold.sum(&w, c, &terms[..3]).to_bits(),
            fold.to_bits()
        );
        // Split from 8: terms 0..8 into four sums (term 4i + s into sum s), term 8 onto c.
        let s: Vec<f64> = (0..4).map(|k| (0.0 + p[k]) + p[k + 4]).collect();
        let split = (c + p[8]) + ((s[0] + s[1]) + (s[2] + s[3]));
        let summation = Summation::Split { from: 8 };
        assert_eq!(summation.sum(&w, c, &terms).to_bits(), split.to_bits());
        // Below `from`, a split summation folds.
        let fold7 = p[..7].iter().fold(c, |acc, &t| acc + t);
        assert_eq!(summation.sum(&w, c, &terms[..7]).to_bits(), fold7.to_bits());
    }

    /// Every run length (1 to 9 forms, so full and padded chunks), form length (1 to 13, both
    /// summations), and rows where every form reads one variable and where not: each lane's
    /// value is the form's alone to the bit, by the AVX2 kernel where the processor has it and
    /// by the portable loops.
    #[test]
    fn each_lane_is_its_form_alone_to_the_bit() {
        let w: Vec<f64> = (0..40).map(|i| value(3 * i + 1)).collect();
        let mut checked = 0;
        for (summation, all_shared) in [
            (Summation::Fold, false),
            (Summation::Split { from: 8 }, false),
            (Summation::Fold, true),
            (Summation::Split { from: 8 }, true),
        ] {
            for count in 1..=9 {
                for len in 1..=13 {
                    let forms: Vec<Vec<(u32, f64)>> = (0..count)
                        .map(|f| {
                            (0..len)
                                .map(|t| {
                                    // Every other term reads the same variable in all forms
                                    // (with `all_shared` every term: the kernel broadcasts).
                                    let v = if t % 2 == 0 || all_shared {
                                        t * 3
                                    } else {
                                        (f * 7 + t * 5) % 40
                                    };
                                    (v as u32, value(f * 31 + t))
                                })
                                .collect()
                        })
                        .collect();
                    let constants: Vec<f64> = (0..count).map(|f| value(f + 100)).collect();
                    let refs: Vec<&[(u32, f64)]> = forms.iter().map(|f| f.as_slice()).collect();
                    let mut lanes = Lanes::default();
                    lanes.add(0, &[&[(0, 1.0)]], summation);
                    let run = lanes.add(5, &refs, summation);
                    assert_eq!(run.forms(), 5..5 + count);
                    // A chunk of one form (its padding lanes read its variables) is shared.
                    let shared = match all_shared || len == 1 {
                        true => run.chunks(),
                        false => usize::from(count % LANES == 1),
                    };
                    let chunks = (0..run.chunks()).filter(|&k| run.is_shared(k)).count();
                    assert_eq!(chunks, shared, "{count} {len}");
                    let constant = |i: usize| constants[i - 5];
                    let mut got = Vec::new();
                    lanes.each_value(&w, &run, constant, |i, v| got.push((i, v)));
                    let mut portable = Vec::new();
                    lanes.each_chunk::<false>(&w, &run, constant, |i, v| portable.push((i, v)));
                    let order: Vec<usize> = got.iter().map(|&(i, _)| i).collect();
                    assert_eq!(order, (5..5 + count).collect::<Vec<_>>());
                    for ((i, got), (_, portable)) in got.into_iter().zip(portable) {
                        let f = i - 5;
                        let want = summation.sum(&w, constants[f], &forms[f]);
                        assert_eq!(got.to_bits(), want.to_bits(), "{count} {len} {f}");
                        assert_eq!(portable.to_bits(), want.to_bits());
                        checked += 1;
                    }
                }
            }
        }
        assert_eq!(checked, 4 * 13 * 45);
    }

    #[test]
    fn equal_lengths_makes_runs_of_two_or_more_long_enough_forms() {
        let lengths = [3, 5, 5, 5, 2, 2, 7, 4, 4, 9];
        assert_eq!(equal_lengths(&lengths, 4), vec![1..4, 7..9]);
        assert_eq!(equal_lengths(&lengths, 2), vec![1..4, 4..6, 7..9]);
    }

    #[test]
    #[should_panic(expected = "the forms' variables")]
    fn a_chunk_is_not_evaluated_at_too_few_variables() {
        let mut lanes = Lanes::default();
        let run = lanes.add(0, &[&[(9, 1.0)], &[(2, 1.0)]], Summation::Fold);
        lanes.each_value(&[0.0; 5], &run, |_| 0.0, |_, _| ());
    }
}
