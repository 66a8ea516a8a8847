//! The search for the partition ([`Partition::detect`]): from J's nonzero pattern alone, the
//! state with the most neighbours is moved into the border until the estimated work stops
//! falling, and the best split seen is kept (see the module documentation of [`super`]).

use nalgebra::DMatrix;

use super::partition::Partition;

/// Solves per factorisation assumed by the work estimate (Rodas5P makes 8 per step, Radau5 about
/// 3 per Newton iteration, and a constant Jacobian's factorisation serves many steps).
const SOLVES_PER_FACTORISATION: f64 = 10.0;

/// The structured split is used only if it needs at most this share of the dense work.
const STRUCTURED_SHARE: f64 = 0.5;

impl Partition {
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

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::super::testing::{arrowhead, residual, Rng};
    use super::super::Factorisation;
    use super::*;

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
}
