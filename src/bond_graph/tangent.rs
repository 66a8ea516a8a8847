//! The Jacobian's varying entries from one value pass and short tangent sweeps.
//!
//! Once the constant entries are fixed, each step needs the varying entries only: one
//! dual-number pass per group of the variable colouring (`structure.rs`), each through the
//! operations the rows it reads need. Those passes compute the same values again and again (the
//! values do not depend on the seeds), call every nonlinear law in each of them, and carry
//! tangents through operations the seeds never reach. [`TangentSweeps`] splits the work:
//!
//! * **One value pass** through the operations the sweeps read, in dual numbers with no seed: it
//!   gives every slot's value, the partial derivatives of each law at its operands, and the
//!   tangent every slot has in a pass whose seeds do not reach it (its *zero tangent*: `+0`,
//!   `-0`, or NaN where a value is not finite; the same in every pass, as it depends on the
//!   values alone).
//! * **Tangent sweeps**, [`LANES`] groups at a time (one lane per group, so that each operation
//!   is one vector operation over the groups): only the operations of the groups' passes that
//!   read a slot the seeds of one of them reach, each computing the tangents alone from the
//!   values of the value pass.
//!
//! Why the entries have the bits of the dual passes: in its lane, every operation of a sweep
//! makes the floating-point operations of the dual pass on the tangents. An operand the seeds of
//! no group of the sweep reach is read as its zero tangent, the tangent the dual pass has there.
//! An operation that the seeds of its lane's group do not reach but those of another lane's do
//! gets, in its lane, the dual pass's operations on zero tangents, hence its zero tangent again.
//! A term of a linear combination whose operand no seed of the sweep reaches is left out: it
//! adds a zero tangent to a sum that starts at `+0` and so is never `-0` (a sum of doubles is
//! `-0` only if both terms are), which leaves the sum's bits as they are, unless the zero
//! tangent is NaN. When the value pass finds a NaN zero tangent the caller runs the dual passes
//! instead.

// Lane loops mirror the dual passes' formulas, one lane per group.
#![allow(clippy::needless_range_loop)]

use super::element::NonlinearLaw;
use super::plan::{Op, NONE};
use super::structure::for_each_read;

/// Groups per sweep: sixteen doubles, four 256-bit vectors (the complete system has 15 groups:
/// one sweep; the chains of additions of four vectors overlap).
pub(super) const LANES: usize = 16;

/// The tangents of one slot, one per group of a sweep.
pub(super) type Lanes = [f64; LANES];

/// One operation of a tangent sweep. Operand indices `a`, `b`, `arg`, `m`, `src` and the terms'
/// point into the lane buffer: the sweep's own tangents of slot `s` at `n_slots + s`, its zero
/// tangent (in every lane) at `s`, and `+0` at `2 n_slots`; `dst` is the slot written (at
/// `n_slots + dst`); `va`, `vb` and `law` are slots, whose values and partials the value pass
/// holds.
#[derive(Clone, Copy, Debug)]
pub(super) enum Tangent {
    /// `t = t_src`
    Copy { dst: u32, src: u32 },
    /// `t = Σ t_src k` over `terms[start..end]`, from `+0`.
    Lin { dst: u32, start: u32, end: u32 },
    /// `t = (t_a v_b + v_a t_b) k`
    Mul {
        dst: u32,
        a: u32,
        b: u32,
        va: u32,
        vb: u32,
        k: f64,
    },
    /// `t = ((t_a − q t_b) / v_b) k` with `q = v_a / v_b`
    Div {
        dst: u32,
        a: u32,
        b: u32,
        va: u32,
        vb: u32,
        k: f64,
    },
    /// `t = (L_x (t_arg ki) + L_m t_m) ko` with the partials `L_x`, `L_m` of the law whose
    /// result is slot `law`, from the value pass.
    Law {
        dst: u32,
        arg: u32,
        m: u32,
        law: u32,
        ki: f64,
        ko: f64,
    },
}

/// One sweep: up to [`LANES`] groups, their operations, and the entries it delivers.
#[derive(Clone, Debug)]
pub(super) struct Sweep {
    /// `(state, lanes)`: the seeded states, with a tangent of 1 in the lanes whose group holds
    /// the state and 0 in the others.
    pub seeds: Vec<(u32, Lanes)>,
    pub ops: Vec<Tangent>,
    /// `(i, j, index, lane)`: entry `(i, j)` is the lane buffer at `index`, in `lane`.
    pub entries: Vec<(u32, u32, u32, u32)>,
}

/// The value pass and the tangent sweeps of the variable colouring.
#[derive(Clone, Debug, Default)]
pub(super) struct TangentSweeps {
    /// The operations whose values, partials or zero tangents the sweeps read, in plan order.
    pub value_ops: Vec<Op>,
    pub sweeps: Vec<Sweep>,
    /// The terms of the sweeps' linear combinations, `(k, lane buffer index)`.
    pub terms: Vec<(f64, u32)>,
}

impl TangentSweeps {
    /// Number of operations of all sweeps.
    pub fn len(&self) -> usize {
        self.sweeps.iter().map(|s| s.ops.len()).sum()
    }
}

/// Builds the value pass and the sweeps for the groups `colours` (their columns are the seeds)
/// with the entries `row_column` (per group, the column each row delivers, or `NONE`) and the
/// operations each group's pass runs, `group_ops` (plan order, subsets of `deriv_ops`, each
/// closed under the slots its operations read); `needed_ops(ops, targets)` are the operations
/// of `ops` the `targets` need.
#[allow(clippy::too_many_arguments)]
pub(super) fn build(
    deriv_ops: &[Op],
    terms: &[(f64, u32)],
    n_slots: usize,
    deriv_slots: &[u32],
    colours: &[Vec<u32>],
    row_column: &[Vec<u32>],
    group_ops: &[Vec<Op>],
    needed_ops: impl Fn(&[Op], &[u32]) -> Vec<Op>,
) -> TangentSweeps {
    let n = n_slots as u32;
    let zero = 2 * n;
    let mut out = TangentSweeps::default();
    // The slots whose value, partials or zero tangent some sweep reads.
    let mut value_targets: Vec<u32> = Vec::new();
    let mut reached = vec![false; n_slots];
    let mut in_sweep = vec![false; deriv_ops.len()];
    let position = |op: &Op| super::structure::dst(op);
    // The position of each slot's operation in `deriv_ops`.
    let mut writer = vec![u32::MAX; n_slots];
    for (k, op) in deriv_ops.iter().enumerate() {
        writer[position(op) as usize] = k as u32;
    }
    for first in (0..colours.len()).step_by(LANES) {
        let groups = first..(first + LANES).min(colours.len());
        reached.fill(false);
        in_sweep.fill(false);
        let mut seeds: Vec<(u32, Lanes)> = Vec::new();
        for (lane, g) in groups.clone().enumerate() {
            for &j in &colours[g] {
                reached[j as usize] = true;
                let mut lanes = [0.0; LANES];
                lanes[lane] = 1.0;
                seeds.push((j, lanes));
            }
            for op in &group_ops[g] {
                in_sweep[writer[position(op) as usize] as usize] = true;
            }
        }
        // The lane buffer index of slot s: the sweep's own tangents if a seed reaches it, else
        // its zero tangent (which the value pass must compute).
        let index = |s: u32, reached: &[bool], targets: &mut Vec<u32>| {
            if reached[s as usize] {
                n + s
            } else {
                targets.push(s);
                s
            }
        };
        let mut ops = Vec::new();
        for (op, _) in deriv_ops.iter().zip(&in_sweep).filter(|(_, &i)| i) {
            let mut any = false;
            for_each_read(op, terms, |s| any |= reached[s as usize]);
            if !any {
                continue;
            }
            let t = match *op {
                Op::Const { .. } => unreachable!("a constant reads no slot"),
                Op::Copy { dst, src } => Tangent::Copy { dst, src: n + src },
                Op::Lin { dst, start, end } => {
                    let first = out.terms.len() as u32;
                    for &(k, s) in &terms[start as usize..end as usize] {
                        if reached[s as usize] {
                            out.terms.push((k, n + s));
                        } else {
                            // Left out; the value pass checks that its zero tangent is no NaN.
                            value_targets.push(s);
                        }
                    }
                    Tangent::Lin {
                        dst,
                        start: first,
                        end: out.terms.len() as u32,
                    }
                }
                Op::Mul { dst, a, b, k } => {
                    value_targets.extend([a, b]);
                    Tangent::Mul {
                        dst,
                        a: index(a, &reached, &mut value_targets),
                        b: index(b, &reached, &mut value_targets),
                        va: a,
                        vb: b,
                        k,
                    }
                }
                Op::Div { dst, a, b, k } => {
                    value_targets.extend([a, b]);
                    Tangent::Div {
                        dst,
                        a: index(a, &reached, &mut value_targets),
                        b: index(b, &reached, &mut value_targets),
                        va: a,
                        vb: b,
                        k,
                    }
                }
                Op::Law {
                    dst,
                    arg,
                    ki,
                    ko,
                    m,
                    ..
                } => {
                    value_targets.push(dst);
                    Tangent::Law {
                        dst,
                        arg: index(arg, &reached, &mut value_targets),
                        m: if m == NONE {
                            zero
                        } else {
                            index(m, &reached, &mut value_targets)
                        },
                        law: dst,
                        ki,
                        ko,
                    }
                }
            };
            ops.push(t);
            reached[position(op) as usize] = true;
        }
        let mut entries = Vec::new();
        for (lane, g) in groups.enumerate() {
            for (i, &j) in row_column[g].iter().enumerate() {
                if j != NONE {
                    let k = index(deriv_slots[i], &reached, &mut value_targets);
                    entries.push((i as u32, j, k, lane as u32));
                }
            }
        }
        out.sweeps.push(Sweep {
            seeds,
            ops,
            entries,
        });
    }
    value_targets.sort_unstable();
    value_targets.dedup();
    out.value_ops = needed_ops(deriv_ops, &value_targets);
    out
}

/// The value pass: a dual-number pass with no seed through `ops` (states `x`, inputs `u` in the
/// first slots), split into the values `v` and the zero tangents, written in every lane of
/// `t[s]` (with `t[2 n_slots]` = +0), and the partial derivatives of each law at its operands
/// into `pdx`, `pdm` at its slot: the operations of the dual passes on the values and on the
/// tangents. Returns false if a zero tangent is NaN.
#[allow(clippy::too_many_arguments)]
pub(super) fn value_pass(
    ops: &[Op],
    terms: &[(f64, u32)],
    laws: &[NonlinearLaw],
    x: &[f64],
    u: &[f64],
    v: &mut [f64],
    t: &mut [Lanes],
    pdx: &mut [f64],
    pdm: &mut [f64],
) -> bool {
    let slots = v.len();
    let known = x.len() + u.len();
    for (i, xi) in x.iter().chain(u).enumerate() {
        v[i] = *xi;
    }
    t[..known].fill([0.0; LANES]);
    t[2 * slots] = [0.0; LANES];
    let mut nan = false;
    for op in ops {
        let z = |s: u32| t[s as usize][0];
        let (dst, value, tangent) = match *op {
            Op::Const { dst, c } => (dst, c, 0.0),
            Op::Copy { dst, src } => (dst, v[src as usize], z(src)),
            Op::Lin { dst, start, end } => {
                let (mut av, mut at) = (0.0, 0.0);
                for &(k, s) in &terms[start as usize..end as usize] {
                    av += v[s as usize] * k;
                    at += z(s) * k;
                }
                (dst, av, at)
            }
            Op::Law {
                dst,
                law,
                arg,
                ki,
                ko,
                m,
            } => {
                let (xv, xt) = (v[arg as usize] * ki, z(arg) * ki);
                let (mv, mt) = if m == NONE {
                    (0.0, 0.0)
                } else {
                    (v[m as usize], z(m))
                };
                let (y, dx, dm) = (laws[law as usize].f)(xv, mv);
                pdx[dst as usize] = dx;
                pdm[dst as usize] = dm;
                (dst, y * ko, (dx * xt + dm * mt) * ko)
            }
            Op::Mul { dst, a, b, k } => {
                let (av, at, bv, bt) = (v[a as usize], z(a), v[b as usize], z(b));
                (dst, (av * bv) * k, (at * bv + av * bt) * k)
            }
            Op::Div { dst, a, b, k } => {
                let (av, at, bv, bt) = (v[a as usize], z(a), v[b as usize], z(b));
                let q = av / bv;
                (dst, q * k, ((at - q * bt) / bv) * k)
            }
        };
        nan |= tangent.is_nan();
        v[dst as usize] = value;
        t[dst as usize] = [tangent; LANES];
    }
    !nan
}

/// Runs the sweep's operations on the lane buffer `t` (its zero tangents written by
/// [`value_pass`]) with the values `v` and the laws' partials `pdx`, `pdm`, and calls
/// `entry(i, j, J_ij)` for each entry it delivers.
pub(super) fn run_sweep(
    sweep: &Sweep,
    terms: &[(f64, u32)],
    (v, pdx, pdm): (&[f64], &[f64], &[f64]),
    t: &mut [Lanes],
    entry: impl FnMut(usize, usize, f64),
) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2 (checked just above).
            return unsafe { run_sweep_avx2(sweep, terms, (v, pdx, pdm), t, entry) };
        }
    }
    run_sweep_body(sweep, terms, (v, pdx, pdm), t, entry)
}

/// [`run_sweep_body`] compiled for 256-bit vectors: one operation on the lanes is four vector
/// operations. Multiplications and additions stay separate (no fused multiply-add), so
/// the bits are those of the portable code.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn run_sweep_avx2(
    sweep: &Sweep,
    terms: &[(f64, u32)],
    values: (&[f64], &[f64], &[f64]),
    t: &mut [Lanes],
    entry: impl FnMut(usize, usize, f64),
) {
    run_sweep_body(sweep, terms, values, t, entry)
}

#[inline(always)]
fn run_sweep_body(
    sweep: &Sweep,
    terms: &[(f64, u32)],
    (v, pdx, pdm): (&[f64], &[f64], &[f64]),
    t: &mut [Lanes],
    mut entry: impl FnMut(usize, usize, f64),
) {
    let n = v.len();
    for &(j, lanes) in &sweep.seeds {
        t[n + j as usize] = lanes;
    }
    for op in &sweep.ops {
        let (dst, d) = match *op {
            Tangent::Copy { dst, src } => (dst, t[src as usize]),
            Tangent::Lin { dst, start, end } => {
                let mut acc = [0.0; LANES];
                for &(k, i) in &terms[start as usize..end as usize] {
                    let ti = &t[i as usize];
                    for l in 0..LANES {
                        acc[l] += ti[l] * k;
                    }
                }
                (dst, acc)
            }
            Tangent::Mul {
                dst,
                a,
                b,
                va,
                vb,
                k,
            } => {
                let (ta, tb) = (&t[a as usize], &t[b as usize]);
                let (va, vb) = (v[va as usize], v[vb as usize]);
                let mut d = [0.0; LANES];
                for l in 0..LANES {
                    d[l] = (ta[l] * vb + va * tb[l]) * k;
                }
                (dst, d)
            }
            Tangent::Div {
                dst,
                a,
                b,
                va,
                vb,
                k,
            } => {
                let (ta, tb) = (&t[a as usize], &t[b as usize]);
                let vb = v[vb as usize];
                let q = v[va as usize] / vb;
                let mut d = [0.0; LANES];
                for l in 0..LANES {
                    d[l] = ((ta[l] - q * tb[l]) / vb) * k;
                }
                (dst, d)
            }
            Tangent::Law {
                dst,
                arg,
                m,
                law,
                ki,
                ko,
            } => {
                let (ta, tm) = (&t[arg as usize], &t[m as usize]);
                let (dx, dm) = (pdx[law as usize], pdm[law as usize]);
                let mut d = [0.0; LANES];
                for l in 0..LANES {
                    d[l] = (dx * (ta[l] * ki) + dm * tm[l]) * ko;
                }
                (dst, d)
            }
        };
        t[n + dst as usize] = d;
    }
    for &(i, j, k, lane) in &sweep.entries {
        entry(i as usize, j as usize, t[k as usize][lane as usize]);
    }
}
