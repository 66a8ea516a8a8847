//! The structure of the state equations, read off the compiled plan once per parameter set:
//! which operations `dx/dt` needs, which states each derivative depends on (the sparsity
//! pattern of the Jacobian), a column colouring of that pattern, and whether the Jacobian is
//! constant.
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
//! * **Constant Jacobian.** The plan is affine in x with constant coefficients when no
//!   operation multiplies two quantities that depend on x, on x and an input, divides by a
//!   quantity that depends on x, or applies a nonlinear law to one. Then J is the same at every
//!   (x, u), and the solver may factorise it once per step size (the LOES with the plate).

use super::plan::{Op, NONE};

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
}

/// Calls `read` with every slot `op` reads.
fn for_each_read(op: &Op, terms: &[(f64, u32)], mut read: impl FnMut(u32)) {
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

fn dst(op: &Op) -> u32 {
    match *op {
        Op::Const { dst, .. }
        | Op::Copy { dst, .. }
        | Op::Lin { dst, .. }
        | Op::Law { dst, .. }
        | Op::Mul { dst, .. }
        | Op::Div { dst, .. } => dst,
    }
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
) -> Structure {
    // Backwards from the derivatives: the operations they need.
    let mut needed = vec![false; n_slots];
    for &d in deriv_slots {
        needed[d as usize] = true;
    }
    let mut keep = vec![false; ops.len()];
    for (k, op) in ops.iter().enumerate().rev() {
        if needed[dst(op) as usize] {
            keep[k] = true;
            for_each_read(op, terms, |s| needed[s as usize] = true);
        }
    }
    let deriv_ops: Vec<Op> = ops
        .iter()
        .zip(&keep)
        .filter(|(_, k)| **k)
        .map(|(op, _)| *op)
        .collect();

    // Forwards: the states each slot depends on (a bit set per slot), whether it depends on an
    // input, and whether its gradient in x varies (`jvar`).
    let words = n_states.div_ceil(64).max(1);
    let mut deps = vec![0u64; n_slots * words];
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
    for op in &deriv_ops {
        acc.fill(0);
        let mut u = false;
        let mut var = false;
        for_each_read(op, terms, |s| {
            let s = s as usize;
            for (a, d) in acc.iter_mut().zip(&deps[s * words..(s + 1) * words]) {
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
        let d = dst(op) as usize;
        deps[d * words..(d + 1) * words].copy_from_slice(&acc);
        dep_u[d] = u;
        jvar[d] = var;
    }
    let constant = deriv_slots.iter().all(|&d| !jvar[d as usize]);
    let pattern: Vec<Vec<u32>> = deriv_slots
        .iter()
        .map(|&d| {
            let row = &deps[d as usize * words..(d as usize + 1) * words];
            (0..n_states as u32)
                .filter(|&j| row[j as usize / 64] & (1 << (j % 64)) != 0)
                .collect()
        })
        .collect();
    let (colours, row_column) = colour(&pattern, n_states);
    Structure {
        deriv_ops,
        pattern,
        colours,
        row_column,
        constant,
    }
}

/// Greedy column colouring of a sparsity pattern (rows -> columns): columns by decreasing
/// count, each into the first group none of whose rows it touches.
fn colour(pattern: &[Vec<u32>], n: usize) -> (Vec<Vec<u32>>, Vec<Vec<u32>>) {
    let mut rows_of: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (i, row) in pattern.iter().enumerate() {
        for &j in row {
            rows_of[j as usize].push(i as u32);
        }
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by_key(|&j| std::cmp::Reverse(rows_of[j].len()));
    let mut colours: Vec<Vec<u32>> = Vec::new();
    let mut row_column: Vec<Vec<u32>> = Vec::new();
    for j in order {
        if rows_of[j].is_empty() {
            continue; // a column of zeros needs no pass
        }
        let free = row_column
            .iter()
            .position(|rc| rows_of[j].iter().all(|&i| rc[i as usize] == NONE));
        let c = free.unwrap_or_else(|| {
            colours.push(Vec::new());
            row_column.push(vec![NONE; pattern.len()]);
            colours.len() - 1
        });
        colours[c].push(j as u32);
        for &i in &rows_of[j] {
            row_column[c][i as usize] = j as u32;
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
        let (colours, row_column) = colour(&pattern, 4);
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
}
