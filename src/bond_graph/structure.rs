//! The structure of the state equations, read off the compiled plan once per parameter set:
//! which operations `dx/dt` needs, which states each derivative depends on (the sparsity
//! pattern of the Jacobian), which entries of the Jacobian vary with `(x, u)`, column
//! colourings of the pattern, and whether the Jacobian is constant.
//!
//! * **Derivative plan.** The full plan also computes every output (accelerometers and tip sums
//!   over all plate modes) and every bond variable; `f` and its Jacobian run only the operations
//!   a derivative depends on, in the same order, so their values are bit-identical to the full
//!   plan's.
//! * **Colouring.** Two columns of J that share no row can be seeded in the same dual-number
//!   pass: each row then receives the derivative of the one column of the group it depends on,
//!   exactly (the other seeds never reach it, so not even rounding differs from a pass per
//!   column). A greedy colouring, largest columns first (Curtis, Powell & Reid 1974; Coleman &
//!   Moré 1983), needs a handful of passes where a pass per state needed dozens or hundreds.
//! * **Varying entries.** Most of the model is linear with constant coefficients (the plate's
//!   modes, the hub, the torsion bar, the controller), so most entries `J_ij` are the same at
//!   every `(x, u)`. For every slot `s` the analysis keeps two sets of states: `deps(s)`, the
//!   states `s` depends on, and `var(s) ⊆ deps(s)`, the states `j` for which `ds/dx_j` may vary
//!   with `(x, u)`. A slot *depends on anything* when it depends on a state or an input. Rules,
//!   one per operation (`k`, `ki`, `ko` are constants):
//!   - `Const`: both empty.
//!   - `Copy`, `Lin` (`s = sum k_r r`): `ds/dx_j = sum k_r dr/dx_j`, so both sets are the unions
//!     of the operands' sets.
//!   - `Law` (`s = ko L(ki a, m)`): `ds/dx_j = ko (L_a ki da/dx_j + L_m dm/dx_j)` with partials
//!     taken at `(a, m)`, which vary as soon as `a` or `m` depends on a state: `var(s) =
//!     deps(s)`. (If neither depends on a state, both sets are empty.)
//!   - `Mul` (`s = k a b`): `ds/dx_j = k (b da/dx_j + a db/dx_j)`: `var(a) ∪ var(b)`, plus
//!     `deps(a)` when `b` depends on anything, plus `deps(b)` when `a` depends on anything.
//!   - `Div` (`s = k a / b`): `ds/dx_j = k (da/dx_j / b - a db/dx_j / b²)`: `var(a) ∪ var(b)`,
//!     plus `deps(b)` (the `b²` varies with the states `b` depends on), plus `deps(a)` when `b`
//!     depends on anything.
//!
//!   Entry `(i, j)` *varies* if `j ∈ var(f_i)` (a superset: terms that cancel are not seen);
//!   column `j` is *variable* if one of its entries varies. J is constant exactly when no column
//!   is variable (the flag [`Structure::constant`], found by its own simpler propagation; a test
//!   checks that both agree on every preset); then the solver may factorise it once per step
//!   size (the LOES with the plate).
//! * **Variable colouring.** Once the constant entries are known (evaluated once per parameter
//!   set, `CompiledModel::fix_constant_entries`), a Jacobian needs only passes over the variable
//!   columns, and in them only the varying entries: a column `j` may share a group with columns
//!   that meet it in a row `i` as long as neither entry of that row needs reading, i.e. a group
//!   may not hold a column whose entry `(i, j)` varies together with another column of row `i`.
//!   Each of these passes runs only the operations the rows it reads need.

use super::plan::{Op, NONE};
use super::tangent::{self, TangentSweeps};

/// What the structure of the plan says about `f` and its Jacobian.
#[derive(Clone, Debug)]
pub(crate) struct Structure {
    /// The operations the state derivatives need, in plan order.
    pub deriv_ops: Vec<Op>,
    /// For each row i of J, the states `f_i` depends on, ascending.
    pub pattern: Vec<Vec<u32>>,
    /// Groups of columns with no row in common; one dual-number pass per group.
    pub colours: Vec<Vec<u32>>,
    /// `row_column[c][i]`: the column of group `c` that row `i` depends on, or `NONE`.
    pub row_column: Vec<Vec<u32>>,
    /// J is independent of x and u.
    pub constant: bool,
    /// For each row i, the columns j (ascending) whose entry `J_ij` may vary with `(x, u)`: a
    /// subset of `pattern[i]`.
    pub varying: Vec<Vec<u32>>,
    /// Groups of the variable columns for the passes once the constant entries are known.
    pub variable_colours: Vec<Vec<u32>>,
    /// `variable_row_column[c][i]`: the column of group `c` whose varying entry row `i`
    /// delivers in that pass, or `NONE`.
    pub variable_row_column: Vec<Vec<u32>>,
    /// For each group of `variable_colours`, the operations the rows read in its pass need, in
    /// plan order (a subset of `deriv_ops`).
    pub variable_ops: Vec<Vec<Op>>,
    /// The same passes as one value pass and a tangent sweep per group (`tangent.rs`).
    pub tangents: TangentSweeps,
    /// The rows `i` whose derivative is not affine in x with coefficients independent of x and
    /// u (`s(x, u) = g x + s(0, u)`: its gradient in x does not vary), ascending.
    pub nonaffine_rows: Vec<u32>,
    /// The operations those rows need, in plan order (a subset of `deriv_ops`): with the affine
    /// rows as a product with their constant gradients, `f` needs only these.
    pub nonaffine_ops: Vec<Op>,
    /// The operations the affine rows need (for their values at x = 0): affine slots read only
    /// affine slots, so none of these is a nonlinear law of a state.
    pub affine_ops: Vec<Op>,
    /// The outputs `k` that are not affine in x, ascending.
    pub nonaffine_outputs: Vec<u32>,
    /// The operations of the full plan that the outputs and rows that are not affine need: a
    /// communication point's pass when the rest are products.
    pub nonaffine_point_ops: Vec<Op>,
    /// The operations of the full plan that the affine outputs need (for their values at x = 0).
    pub affine_output_ops: Vec<Op>,
}

/// Calls `read` with every slot `op` reads.
pub(super) fn for_each_read(op: &Op, terms: &[(f64, u32)], mut read: impl FnMut(u32)) {
    match *op {
        Op::Const { .. } => {}
        Op::Copy { src, .. } => read(src),
        Op::Lin { start, end, .. } => {
            for &(_, s) in &terms[start as usize..end as usize] {
                read(s);
            }
        }
        Op::Law { arg, m, .. } => {
            read(arg);
            if m != NONE {
                read(m);
            }
        }
        Op::Mul { a, b, .. } | Op::Div { a, b, .. } => {
            read(a);
            read(b);
        }
    }
}

pub(super) fn dst(op: &Op) -> u32 {
    match *op {
        Op::Const { dst, .. }
        | Op::Copy { dst, .. }
        | Op::Lin { dst, .. }
        | Op::Law { dst, .. }
        | Op::Mul { dst, .. }
        | Op::Div { dst, .. } => dst,
    }
}

/// The operations of `ops` (in order) that the `targets` slots need.
fn needed_ops(ops: &[Op], terms: &[(f64, u32)], n_slots: usize, targets: &[u32]) -> Vec<Op> {
    let mut needed = vec![false; n_slots];
    for &d in targets {
        needed[d as usize] = true;
    }
    let mut keep = vec![false; ops.len()];
    for (k, op) in ops.iter().enumerate().rev() {
        if needed[dst(op) as usize] {
            keep[k] = true;
            for_each_read(op, terms, |s| needed[s as usize] = true);
        }
    }
    ops.iter()
        .zip(&keep)
        .filter(|(_, k)| **k)
        .map(|(op, _)| *op)
        .collect()
}

/// The states whose bits are set in one slot's row of a bit-set table.
fn members(row: &[u64], n: usize) -> Vec<u32> {
    (0..n as u32)
        .filter(|&j| row[j as usize / 64] & (1 << (j % 64)) != 0)
        .collect()
}

/// Analyses a plan whose slots start with the `n_states` states and then the `n_inputs`
/// inputs, and whose derivatives are in `deriv_slots`.
pub(crate) fn analyse(
    ops: &[Op],
    terms: &[(f64, u32)],
    n_slots: usize,
    n_states: usize,
    n_inputs: usize,
    deriv_slots: &[u32],
    output_slots: &[u32],
) -> Structure {
    // Backwards from the derivatives: the operations they need.
    let deriv_ops = needed_ops(ops, terms, n_slots, deriv_slots);

    // Forwards: the states each slot depends on (a bit set per slot), whether it depends on an
    // input, whether its gradient in x varies (`jvar`, for the constant flag), and the states
    // through which it varies (`vdeps`, a bit set per slot; rules in the module doc).
    let words = n_states.div_ceil(64).max(1);
    let mut deps = vec![0u64; n_slots * words];
    let mut vdeps = vec![0u64; n_slots * words];
    let mut dep_u = vec![false; n_slots];
    let mut jvar = vec![false; n_slots];
    for k in 0..n_states {
        deps[k * words + k / 64] |= 1 << (k % 64);
    }
    for flag in dep_u.iter_mut().skip(n_states).take(n_inputs) {
        *flag = true;
    }
    let dep_x = |deps: &[u64], s: u32| {
        deps[s as usize * words..(s as usize + 1) * words]
            .iter()
            .any(|w| *w != 0)
    };
    let mut acc = vec![0u64; words];
    let mut vacc = vec![0u64; words];
    // Over the whole plan, so that the outputs' slots are classified too; the derivatives'
    // operations are among them, in the same order.
    for op in ops {
        acc.fill(0);
        vacc.fill(0);
        let mut u = false;
        let mut var = false;
        for_each_read(op, terms, |s| {
            let s = s as usize;
            let row = s * words..(s + 1) * words;
            for (a, d) in acc.iter_mut().zip(&deps[row.clone()]) {
                *a |= d;
            }
            for (a, d) in vacc.iter_mut().zip(&vdeps[row]) {
                *a |= d;
            }
            u |= dep_u[s];
            var |= jvar[s];
        });
        let depends = |s: u32| dep_x(&deps, s) || dep_u[s as usize];
        var |= match *op {
            Op::Law { arg, m, .. } => dep_x(&deps, arg) || (m != NONE && dep_x(&deps, m)),
            Op::Mul { a, b, .. } => {
                (dep_x(&deps, a) && depends(b)) || (dep_x(&deps, b) && depends(a))
            }
            Op::Div { a, b, .. } => dep_x(&deps, b) || (dep_x(&deps, a) && depends(b)),
            Op::Const { .. } | Op::Copy { .. } | Op::Lin { .. } => false,
        };
        // The operands whose dependencies become varying ones.
        let (first, second) = match *op {
            Op::Law { .. } => (None, None), // all of them: below
            Op::Mul { a, b, .. } => (depends(b).then_some(a), depends(a).then_some(b)),
            Op::Div { a, b, .. } => (depends(b).then_some(a), Some(b)),
            Op::Const { .. } | Op::Copy { .. } | Op::Lin { .. } => (None, None),
        };
        if let Op::Law { .. } = op {
            vacc.copy_from_slice(&acc);
        }
        for s in [first, second].into_iter().flatten() {
            let s = s as usize;
            for (a, d) in vacc.iter_mut().zip(&deps[s * words..(s + 1) * words]) {
                *a |= d;
            }
        }
        let d = dst(op) as usize;
        deps[d * words..(d + 1) * words].copy_from_slice(&acc);
        vdeps[d * words..(d + 1) * words].copy_from_slice(&vacc);
        dep_u[d] = u;
        jvar[d] = var;
    }
    let constant = deriv_slots.iter().all(|&d| !jvar[d as usize]);
    let rows_of = |table: &[u64]| -> Vec<Vec<u32>> {
        deriv_slots
            .iter()
            .map(|&d| {
                members(
                    &table[d as usize * words..(d as usize + 1) * words],
                    n_states,
                )
            })
            .collect()
    };
    let pattern = rows_of(&deps);
    let varying = rows_of(&vdeps);
    let (colours, row_column) = colour(&pattern, n_states, |_, _| true);
    let (variable_colours, variable_row_column) = colour(&pattern, n_states, |i, j| {
        varying[i].binary_search(&j).is_ok()
    });
    let variable_ops = variable_row_column
        .iter()
        .map(|row_column| {
            let rows: Vec<u32> = deriv_slots
                .iter()
                .zip(row_column)
                .filter(|(_, &j)| j != NONE)
                .map(|(&d, _)| d)
                .collect();
            needed_ops(&deriv_ops, terms, n_slots, &rows)
        })
        .collect::<Vec<_>>();
    let tangents = tangent::build(
        &deriv_ops,
        terms,
        n_slots,
        deriv_slots,
        &variable_colours,
        &variable_row_column,
        &variable_ops,
        |ops, targets| needed_ops(ops, terms, n_slots, targets),
    );
    let (affine_derivs, nonaffine_derivs) = split_by_affinity(deriv_slots, &jvar);
    let slots_of = |rows: &[(usize, u32)]| rows.iter().map(|&(_, d)| d).collect::<Vec<u32>>();
    let nonaffine_ops = needed_ops(&deriv_ops, terms, n_slots, &slots_of(&nonaffine_derivs));
    let affine_ops = needed_ops(&deriv_ops, terms, n_slots, &slots_of(&affine_derivs));
    let nonaffine_rows = nonaffine_derivs.iter().map(|&(i, _)| i as u32).collect();
    let (affine_outs, nonaffine_outs) = split_by_affinity(output_slots, &jvar);
    let mut point_targets = slots_of(&nonaffine_outs);
    point_targets.extend(slots_of(&nonaffine_derivs));
    let nonaffine_point_ops = needed_ops(ops, terms, n_slots, &point_targets);
    let affine_output_ops = needed_ops(ops, terms, n_slots, &slots_of(&affine_outs));
    let nonaffine_outputs = nonaffine_outs.iter().map(|&(k, _)| k as u32).collect();
    Structure {
        nonaffine_outputs,
        nonaffine_point_ops,
        affine_output_ops,
        nonaffine_rows,
        nonaffine_ops,
        affine_ops,
        deriv_ops,
        pattern,
        colours,
        row_column,
        constant,
        varying,
        variable_colours,
        variable_row_column,
        variable_ops,
        tangents,
    }
}

/// `(index, slot)` pairs of some of a list of slots.
type IndexedSlots = Vec<(usize, u32)>;

/// Splits `slots` (with their indices) into those affine in x (`jvar` false) and the others.
fn split_by_affinity(slots: &[u32], jvar: &[bool]) -> (IndexedSlots, IndexedSlots) {
    slots
        .iter()
        .copied()
        .enumerate()
        .partition(|&(_, d)| !jvar[d as usize])
}

/// Greedy column colouring of a sparsity pattern (rows -> columns), columns by decreasing
/// count, for passes that must deliver the entries `(i, j)` where `read(i, j)` (the others are
/// known otherwise). A column goes into the first group where each row it must be read in
/// meets no other column of the group, and each other row it meets is read in no column of the
/// group; a column with no entry to read needs no pass. With `read` always true this is the
/// plain colouring: no two columns of a group share a row. Returns the groups and, per group,
/// the column each row is read in (or `NONE`).
fn colour(
    pattern: &[Vec<u32>],
    n: usize,
    read: impl Fn(usize, u32) -> bool,
) -> (Vec<Vec<u32>>, Vec<Vec<u32>>) {
    let mut rows_of: Vec<Vec<(u32, bool)>> = vec![Vec::new(); n];
    for (i, row) in pattern.iter().enumerate() {
        for &j in row {
            rows_of[j as usize].push((i as u32, read(i, j)));
        }
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by_key(|&j| std::cmp::Reverse(rows_of[j].len()));
    let mut colours: Vec<Vec<u32>> = Vec::new();
    let mut row_column: Vec<Vec<u32>> = Vec::new();
    // `met[c][i]`: some column of group c meets row i.
    let mut met: Vec<Vec<bool>> = Vec::new();
    for j in order {
        if !rows_of[j].iter().any(|&(_, r)| r) {
            continue; // nothing to read: a column of zeros, or of known entries
        }
        let fits = |c: usize| {
            rows_of[j].iter().all(|&(i, r)| {
                let i = i as usize;
                if r {
                    !met[c][i]
                } else {
                    row_column[c][i] == NONE
                }
            })
        };
        let c = (0..colours.len()).find(|&c| fits(c)).unwrap_or_else(|| {
            colours.push(Vec::new());
            row_column.push(vec![NONE; pattern.len()]);
            met.push(vec![false; pattern.len()]);
            colours.len() - 1
        });
        colours[c].push(j as u32);
        for &(i, r) in &rows_of[j] {
            met[c][i as usize] = true;
            if r {
                row_column[c][i as usize] = j as u32;
            }
        }
    }
    (colours, row_column)
}

/// For each of the `targets` slots, the first `n_known` slots (states, then inputs) it depends
/// on through `ops`, ascending: a structural dependency (a path through the plan), which holds
/// at every `(x, u)` where a numerical zero of the Jacobian may hide one.
pub(crate) fn dependencies(
    ops: &[Op],
    terms: &[(f64, u32)],
    n_slots: usize,
    n_known: usize,
    targets: &[u32],
) -> Vec<Vec<u32>> {
    let words = n_known.div_ceil(64).max(1);
    let mut deps = vec![0u64; n_slots * words];
    for k in 0..n_known {
        deps[k * words + k / 64] |= 1 << (k % 64);
    }
    let mut acc = vec![0u64; words];
    for op in ops {
        acc.fill(0);
        for_each_read(op, terms, |s| {
            for (a, d) in acc.iter_mut().zip(&deps[s as usize * words..]) {
                *a |= d;
            }
        });
        let d = dst(op) as usize;
        deps[d * words..(d + 1) * words].copy_from_slice(&acc);
    }
    targets
        .iter()
        .map(|&t| {
            (0..n_known)
                .filter(|&k| deps[t as usize * words + k / 64] >> (k % 64) & 1 == 1)
                .map(|k| k as u32)
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colouring_separates_columns_that_share_a_row() {
        // Arrowhead: row 0 touches every column, rows 1..4 only their own and column 0.
        let pattern: Vec<Vec<u32>> = vec![vec![0, 1, 2, 3], vec![0, 1], vec![0, 2], vec![0, 3]];
        let (colours, row_column) = colour(&pattern, 4, |_, _| true);
        for (c, group) in colours.iter().enumerate() {
            for (i, row) in pattern.iter().enumerate() {
                let hits: Vec<u32> = group.iter().copied().filter(|j| row.contains(j)).collect();
                assert!(hits.len() <= 1, "row {i} meets {hits:?} in group {c}");
                assert_eq!(row_column[c][i], hits.first().copied().unwrap_or(NONE));
            }
        }
        // Row 0 touches all four columns: four groups are needed and enough.
        assert_eq!(colours.len(), 4);
        let mut all: Vec<u32> = colours.concat();
        all.sort();
        assert_eq!(all, [0, 1, 2, 3]);
    }

    #[test]
    fn known_entries_let_columns_share_a_row() {
        // The arrowhead again, with only the diagonal entries (1, 1), (2, 2), (3, 3) to read:
        // columns 1, 2, 3 meet only in row 0, whose entries are known, so one pass reads all
        // three; column 0 has nothing to read and no pass.
        let pattern: Vec<Vec<u32>> = vec![vec![0, 1, 2, 3], vec![0, 1], vec![0, 2], vec![0, 3]];
        let (colours, row_column) = colour(&pattern, 4, |i, j| i > 0 && i == j as usize);
        assert_eq!(colours, [vec![1, 2, 3]]);
        assert_eq!(row_column, [vec![NONE, 1, 2, 3]]);
        // Reading (0, 1) too: row 0 then meets columns 2 and 3 in the pass that reads it, so
        // column 1 needs a pass of its own.
        let read = |i: usize, j: u32| (i > 0 && i == j as usize) || (i, j) == (0, 1);
        let (colours, row_column) = colour(&pattern, 4, read);
        assert_eq!(colours, [vec![1], vec![2, 3]]);
        assert_eq!(row_column, [vec![1, 1, NONE, NONE], vec![NONE, NONE, 2, 3]]);
    }

    #[test]
    fn varying_entries_follow_the_rules_of_each_operation() {
        // States x0, x1, x2 (slots 0..3), input u (slot 3), a constant c (slot 4); derivatives
        // in slots 10, 11, 12, 13.
        let terms = vec![(2.0, 0), (3.0, 5), (1.0, 1), (-1.0, 2)];
        let ops = vec![
            Op::Const { dst: 4, c: 2.5 },
            // 5 = c x0: constant factor, constant gradient.
            Op::Mul {
                dst: 5,
                a: 0,
                b: 4,
                k: 1.0,
            },
            // 10 = 2 x0 + 3 (c x0): linear throughout, nothing varies.
            Op::Lin {
                dst: 10,
                start: 0,
                end: 2,
            },
            // 6 = u x1: the input makes d/dx1 vary.
            Op::Mul {
                dst: 6,
                a: 1,
                b: 3,
                k: 1.0,
            },
            // 7 = x1 - x2, 11 = L(7): a law of states, its gradient varies in both.
            Op::Lin {
                dst: 7,
                start: 2,
                end: 4,
            },
            Op::Law {
                dst: 11,
                law: 0,
                arg: 7,
                ki: 1.0,
                ko: 1.0,
                m: NONE,
            },
            // 12 = x0 / c: a constant divisor, nothing varies.
            Op::Div {
                dst: 12,
                a: 0,
                b: 4,
                k: 1.0,
            },
            // 8 = c / x2: the divisor depends on x2.
            Op::Div {
                dst: 8,
                a: 4,
                b: 2,
                k: 1.0,
            },
            // 13 = u x1 + c / x2 + 2 x0: varies in x1 and x2, not in x0.
            Op::Lin {
                dst: 13,
                start: 4,
                end: 7,
            },
        ];
        let mut terms = terms;
        terms.extend([(1.0, 6), (1.0, 8), (2.0, 0)]);
        let st = analyse(&ops, &terms, 14, 3, 1, &[10, 11, 12, 13], &[]);
        assert_eq!(st.pattern, [vec![0], vec![1, 2], vec![0], vec![0, 1, 2]]);
        assert_eq!(st.varying, [vec![], vec![1, 2], vec![], vec![1, 2]]);
        assert!(!st.constant);
        // Columns 1 and 2 vary, and rows 1 and 3 read both: two passes, each running the
        // operations of rows 1 and 3 only (not the Mul and Lin of row 0 nor the Div of row 2).
        assert_eq!(st.variable_colours.len(), 2);
        for ops in &st.variable_ops {
            assert_eq!(ops.len(), 6);
            assert!(ops.iter().all(|op| !matches!(op, Op::Div { dst: 12, .. })));
        }
        // Without the rows that vary, the same plan has a constant Jacobian.
        let st = analyse(&ops, &terms, 14, 3, 1, &[10, 12], &[]);
        assert!(st.constant && st.varying.iter().all(Vec::is_empty));
        assert!(st.variable_colours.is_empty());
    }
}
