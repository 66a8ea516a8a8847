//! Ordering the equations: each after the equations that compute the slots it reads.
//!
//! A topological sort (Kahn's algorithm) of the graph "equation reads a slot another equation
//! writes". States and inputs are given, so only the slots from `n_given` on are dependencies.
//! Equations left over lie on or downstream of a cycle without integration, an algebraic loop
//! (e.g. resistors on adjacent junctions with no storage element between them to set one of
//! their variables). The error names the elements and signal blocks of one cycle only, not
//! what merely depends on it, so it points at where to add a storage element or change the
//! graph. The order depends only on the equations, so the same graph gives the same plan.

use super::error::BondGraphError;
use super::plan::Equation;

/// Topological order of the equations; a cycle is an algebraic loop.
pub(super) fn sort_equations(
    eqs: &[Equation],
    n_slots: usize,
    n_given: usize,
) -> Result<Vec<usize>, BondGraphError> {
    let mut producer = vec![usize::MAX; n_slots];
    for (k, eq) in eqs.iter().enumerate() {
        debug_assert!(
            producer[eq.dst] == usize::MAX,
            "slot written twice by '{}'",
            eq.owner
        );
        producer[eq.dst] = k;
    }
    let deps: Vec<Vec<usize>> = eqs
        .iter()
        .map(|eq| {
            eq.expr
                .reads()
                .into_iter()
                .filter(|&s| s >= n_given)
                .map(|s| {
                    let p = producer[s];
                    assert!(
                        p != usize::MAX,
                        "slot {s} read by '{}' is never computed",
                        eq.owner
                    );
                    p
                })
                .collect()
        })
        .collect();
    let mut users: Vec<Vec<usize>> = vec![Vec::new(); eqs.len()];
    let mut indeg = vec![0usize; eqs.len()];
    for (k, d) in deps.iter().enumerate() {
        indeg[k] = d.len();
        for &p in d {
            users[p].push(k);
        }
    }
    let mut ready: Vec<usize> = (0..eqs.len()).filter(|&k| indeg[k] == 0).rev().collect();
    let mut order = Vec::with_capacity(eqs.len());
    while let Some(k) = ready.pop() {
        order.push(k);
        for &u in &users[k] {
            indeg[u] -= 1;
            if indeg[u] == 0 {
                ready.push(u);
            }
        }
    }
    if order.len() == eqs.len() {
        return Ok(order);
    }
    // Find a cycle among the unsorted equations: walk dependencies until one repeats.
    let left: Vec<bool> = indeg.iter().map(|&d| d > 0).collect();
    let start = (0..eqs.len()).find(|&k| left[k]).unwrap();
    let mut seen = vec![usize::MAX; eqs.len()];
    let mut path = Vec::new();
    let mut k = start;
    while seen[k] == usize::MAX {
        seen[k] = path.len();
        path.push(k);
        k = *deps[k].iter().find(|&&p| left[p]).unwrap();
    }
    let cycle = &path[seen[k]..];
    let mut elements: Vec<String> = Vec::new();
    for &c in cycle.iter().rev() {
        if !elements.contains(&eqs[c].owner) {
            elements.push(eqs[c].owner.clone());
        }
    }
    Err(BondGraphError::AlgebraicLoop { elements })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bond_graph::plan::Expr;

    #[test]
    fn sorting_reports_the_cycle_only() {
        // slots: 0 = state; 1..=4 computed. 1 = x; 2 = 3 + 1; 3 = 2; 4 = 3 (downstream of the cycle)
        let eq = |dst, t: Vec<(f64, usize)>, o: &str| Equation {
            dst,
            expr: Expr::Lin(t.into_iter().map(|(k, s)| (k.into(), s)).collect()),
            owner: o.into(),
        };
        let eqs = vec![
            eq(1, vec![(1.0, 0)], "a"),
            eq(2, vec![(1.0, 3), (1.0, 1)], "b"),
            eq(3, vec![(2.0, 2)], "c"),
            eq(4, vec![(1.0, 3)], "d"),
        ];
        match sort_equations(&eqs, 5, 1) {
            Err(BondGraphError::AlgebraicLoop { mut elements }) => {
                elements.sort();
                assert_eq!(elements, ["b", "c"]);
            }
            r => panic!("{r:?}"),
        }
        let ok = vec![
            eqs[0].clone(),
            eq(2, vec![(1.0, 1)], "b"),
            eq(3, vec![(1.0, 2)], "c"),
        ];
        assert_eq!(sort_equations(&ok, 5, 1).unwrap(), [0, 1, 2]);
    }
}
