//! The block partition of the states (see the module documentation of [`super`]): groups of
//! states (blocks) and the border, in elimination order, with where each block's data lie in the
//! factors. Found by [`Partition::detect`].

/// Groups and border of the states (see the [module documentation](super)).
#[derive(Clone, Debug, PartialEq)]
pub struct Partition {
    pub(super) n: usize,
    /// The states in elimination order: block after block, then the border.
    pub(super) perm: Vec<usize>,
    /// Block b holds positions `starts[b]..starts[b + 1]` of `perm`; the border is
    /// `perm[nb..]` with `nb = starts[k]`.
    pub(super) starts: Vec<usize>,
    /// Border positions (0-based within the border) coupled to block b, ascending:
    /// `links[link_starts[b]..link_starts[b + 1]]`.
    pub(super) links: Vec<usize>,
    pub(super) link_starts: Vec<usize>,
    /// The states of the links, `perm[nb + links[i]]` for each i (the rows of C_b and the
    /// columns of X_b).
    pub(super) link_states: Vec<usize>,
    /// Where the factorisation reads M's entries (see [`Gather`]).
    pub(super) gather: Gather,
    /// Where each block's data lie, precomputed for the solves (see [`BlockAt`]): the blocks
    /// coupled to the border, and apart the free ones (no link to the border), which a solve
    /// finishes in one go (a plate mode that no force of the hub excites is one).
    pub(super) linked: Vec<BlockAt>,
    pub(super) free: Vec<BlockAt>,
    /// The linked blocks again, split for the solves (see [`OneAt`] and [`Term`]): those of one
    /// state, and those of more.
    pub(super) ones: Vec<OneAt>,
    pub(super) multi: Vec<BlockAt>,
    /// The border's right-hand side's terms, border state after border state (q's are
    /// `terms[term_starts[q]..term_starts[q + 1]]`), each state's in block order.
    pub(super) terms: Vec<Term>,
    pub(super) term_starts: Vec<usize>,
    /// Numbers of the blocks' LUs (Σ k²) and of their X_b (and C_b) (Σ k × links), which
    /// [`BlockAt::lu`] and [`BlockAt::x`] lay out one block after the other.
    pub(super) lu_len: usize,
    pub(super) x_len: usize,
}

/// Where the factorisation of a structured partition reads M's entries: positions i + j n of M
/// stored column-major (n × n), in the order of the factors' buffers, and the places in those
/// lists that lie on M's diagonal; a matrix stored so ([`super::Shifted`]) is then read in one
/// pass per buffer, without the block structure's bookkeeping. Empty for the dense partition,
/// whose one block is read column by column.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Gather {
    /// Every block's k × k entries, column-major, at the blocks' LU offsets.
    pub(super) lu: Vec<usize>,
    pub(super) lu_diagonal: Vec<usize>,
    /// B_b (k × links, column-major) and C_b (links × k, row-major), at the blocks' X offsets.
    pub(super) x: Vec<usize>,
    pub(super) c: Vec<usize>,
    /// The border's m × m entries, column-major.
    pub(super) schur: Vec<usize>,
    pub(super) schur_diagonal: Vec<usize>,
}

impl Gather {
    fn of(
        n: usize,
        perm: &[usize],
        nb: usize,
        blocks: &[BlockAt],
        link_states: &[usize],
    ) -> Gather {
        let mut g = Gather::default();
        let mut blocks = blocks.to_vec();
        blocks.sort_by_key(|at| at.lu);
        for at in &blocks {
            let idx = &perm[at.start..at.start + at.size];
            let states = &link_states[at.links_from..at.links_to];
            for (cj, &j) in idx.iter().enumerate() {
                g.lu_diagonal.push(g.lu.len() + cj);
                g.lu.extend(idx.iter().map(|&i| i + j * n));
            }
            for &j in states {
                g.x.extend(idx.iter().map(|&i| i + j * n));
            }
            for &i in states {
                g.c.extend(idx.iter().map(|&j| i + j * n));
            }
        }
        let border = &perm[nb..];
        for (q, &j) in border.iter().enumerate() {
            g.schur_diagonal.push(g.schur.len() + q);
            g.schur.extend(border.iter().map(|&i| i + j * n));
        }
        g
    }
}

/// One block's place in the partition and in the factors: what a solve would otherwise
/// recompute from `starts` and `link_starts` block by block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct BlockAt {
    /// First position of the block in `perm`.
    pub(super) start: usize,
    /// Its size k.
    pub(super) size: usize,
    /// Offset of its k × k LU in the factors.
    pub(super) lu: usize,
    /// Offset of its X_b and C_b (k × links numbers each).
    pub(super) x: usize,
    /// Its border links: `links[links_from..links_to]`.
    pub(super) links_from: usize,
    pub(super) links_to: usize,
}

/// A linked block of one state (the plate's modes, most of the blocks): its place in the
/// partition and in the factors, for the solves' written-out passes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct OneAt {
    /// Its state, `perm[pos]`.
    pub(super) state: usize,
    /// Its position in `perm`.
    pub(super) pos: usize,
    /// Offset of its one factor (the pivot's reciprocal) in the LU.
    pub(super) lu: usize,
    /// Offset of its X_b and C_b (one number per link each).
    pub(super) x: usize,
    /// Its border links: `links[links_from..links_to]`.
    pub(super) links_from: usize,
    pub(super) links_to: usize,
}

/// One term C_b[q, :] y_b of border state q's right-hand side r_q − Σ_b C_b[q, :] y_b: the row
/// of C_b at `c` (k numbers), y_b at position `y` of the elimination order (k numbers).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Term {
    pub(super) c: usize,
    pub(super) y: usize,
    pub(super) k: usize,
}

impl Partition {
    /// The partition with these fields, and the offsets derived from them.
    ///
    /// Panics unless the fields are consistent: `perm` n states below n, `starts` rising from 0
    /// to at most n, `link_starts` as many, rising to at most `links.len()`, and every link
    /// below the border's size. [`super::Factorisation::solve`] indexes with them without
    /// bounds checks, relying on this check (the blocks' offsets into the factors are derived
    /// here, within `lu_len` and `x_len` by their construction).
    pub(super) fn with(
        n: usize,
        perm: Vec<usize>,
        starts: Vec<usize>,
        links: Vec<usize>,
        link_starts: Vec<usize>,
    ) -> Partition {
        let rising = |v: &[usize], to: usize| {
            v.first() == Some(&0) && v.windows(2).all(|w| w[0] <= w[1]) && v[v.len() - 1] <= to
        };
        assert!(perm.len() == n && perm.iter().all(|&i| i < n), "perm");
        assert!(rising(&starts, n) && starts.len() == link_starts.len());
        assert!(rising(&link_starts, links.len()));
        let m = n - starts[starts.len() - 1];
        assert!(links.iter().all(|&q| q < m), "a link outside the border");
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
        let nb = starts[starts.len() - 1];
        let (mut ones, mut multi) = (Vec::new(), Vec::new());
        // Each link's term with its border state, in block order; sorted stably by border
        // state, every state's terms stay in block order.
        let mut by_state = Vec::with_capacity(links.len());
        for at in &linked {
            if at.size == 1 {
                ones.push(OneAt {
                    state: perm[at.start],
                    pos: at.start,
                    lu: at.lu,
                    x: at.x,
                    links_from: at.links_from,
                    links_to: at.links_to,
                });
            } else {
                multi.push(*at);
            }
            for (li, &q) in links[at.links_from..at.links_to].iter().enumerate() {
                let term = Term {
                    c: at.x + li * at.size,
                    y: at.start,
                    k: at.size,
                };
                by_state.push((q, term));
            }
        }
        by_state.sort_by_key(|&(q, _)| q);
        let mut term_starts = vec![0; m + 1];
        for &(q, _) in &by_state {
            term_starts[q + 1] += 1;
        }
        for q in 0..m {
            term_starts[q + 1] += term_starts[q];
        }
        let terms = by_state.into_iter().map(|(_, t)| t).collect();
        let link_states: Vec<usize> = links.iter().map(|&q| perm[nb + q]).collect();
        let dense = starts.len() == 2 && nb == n;
        let gather = if dense {
            Gather::default()
        } else {
            let all: Vec<BlockAt> = linked.iter().chain(&free).copied().collect();
            Gather::of(n, &perm, nb, &all, &link_states)
        };
        Partition {
            n,
            perm,
            starts,
            links,
            link_starts,
            link_states,
            gather,
            linked,
            free,
            ones,
            multi,
            terms,
            term_starts,
            lu_len: lu,
            x_len: x,
        }
    }

    /// One block holding every state in natural order, no border: a dense LU.
    pub fn dense(n: usize) -> Partition {
        Partition::with(n, (0..n).collect(), vec![0, n], Vec::new(), vec![0, 0])
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
    pub(super) fn block(&self, b: usize) -> (usize, usize, &[usize]) {
        let (s, e) = (self.starts[b], self.starts[b + 1]);
        (
            s,
            e - s,
            &self.links[self.link_starts[b]..self.link_starts[b + 1]],
        )
    }
}
