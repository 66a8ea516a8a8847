//! Order conditions, consistency and stability of the Rodas5P tableau (src/solver/rodas5p.rs).
//!
//! Rosenbrock order conditions via rooted trees (Hairer & Wanner II, Sec. IV.7): for a tree t,
//! Φ(t) is built recursively; a vertex with exactly one child contributes the matrix
//! β = α + Γ (Γ including its diagonal γ, because the J-term of the method is linear), a
//! vertex with two or more children contributes α. Order p  <=>  bᵀΦ(t) = 1/γ(t) for all trees
//! with |t| <= p, where γ(t) is the tree's density.

// Wrapped in a module so that `cargo test solver` selects these tests by name.
mod solver_rodas5p_tableau {
    use hydraulic_slewing_plate::solver::rodas5p::{
        self, classical_form, C_NODES, D, GAMMA, STAGES,
    };
    use nalgebra::{Complex, DMatrix, DVector};

    #[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
    struct Tree(Vec<Tree>);

    impl Tree {
        fn order(&self) -> usize {
            1 + self.0.iter().map(Tree::order).sum::<usize>()
        }
        fn density(&self) -> f64 {
            self.order() as f64 * self.0.iter().map(Tree::density).product::<f64>()
        }
    }

    /// All rooted trees with exactly n vertices (canonical: children sorted).
    fn trees(n: usize) -> Vec<Tree> {
        if n == 1 {
            return vec![Tree(vec![])];
        }
        // Children forests of total size n-1, built as non-increasing sequences of subtrees.
        let mut pool: Vec<Tree> = Vec::new();
        for k in 1..n {
            pool.extend(trees(k));
        }
        pool.sort();
        let mut out = Vec::new();
        fn forests(
            pool: &[Tree],
            max_idx: usize,
            remaining: usize,
            cur: &mut Vec<Tree>,
            out: &mut Vec<Tree>,
        ) {
            if remaining == 0 {
                out.push(Tree(cur.clone()));
                return;
            }
            for idx in 0..=max_idx.min(pool.len() - 1) {
                let o = pool[idx].order();
                if o <= remaining {
                    cur.push(pool[idx].clone());
                    forests(pool, idx, remaining - o, cur, out);
                    cur.pop();
                }
            }
        }
        forests(&pool, pool.len() - 1, n - 1, &mut Vec::new(), &mut out);
        for t in out.iter_mut() {
            t.0.sort();
        }
        out.sort();
        out.dedup();
        out
    }

    fn phi(t: &Tree, alpha: &DMatrix<f64>, beta: &DMatrix<f64>) -> DVector<f64> {
        let s = alpha.nrows();
        let mut v = DVector::from_element(s, 1.0);
        let m = if t.0.len() == 1 { beta } else { alpha };
        for child in &t.0 {
            let w = m * phi(child, alpha, beta);
            v.component_mul_assign(&w);
        }
        v
    }

    fn max_defect(
        order: usize,
        b: &DVector<f64>,
        alpha: &DMatrix<f64>,
        beta: &DMatrix<f64>,
    ) -> f64 {
        trees(order)
            .iter()
            .map(|t| (b.dot(&phi(t, alpha, beta)) - 1.0 / t.density()).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn tree_counts() {
        let counts: Vec<usize> = (1..=6).map(|n| trees(n).len()).collect();
        assert_eq!(counts, vec![1, 1, 2, 4, 9, 20]);
    }

    #[test]
    fn rodas5p_has_order_5_and_embedded_order_4() {
        let (alpha, gam, b) = classical_form();
        let beta = &alpha + &gam;
        for p in 1..=5 {
            let d = max_defect(p, &b, &alpha, &beta);
            assert!(d < 1e-12, "order-{p} conditions violated by {d:e}");
        }
        // Embedded solution ŷ1 = Y_8 (weights m̂ = row 8 of A): order 4, not 5.
        let mhat = DMatrix::from_fn(1, STAGES, |_, j| rodas5p::A[7][j]);
        let bhat = DVector::from_column_slice((&mhat * &gam).as_slice());
        for p in 1..=4 {
            let d = max_defect(p, &bhat, &alpha, &beta);
            assert!(d < 1e-12, "embedded order-{p} conditions violated by {d:e}");
        }
        assert!(
            max_defect(5, &bhat, &alpha, &beta) > 1e-6,
            "embedded method should be of order 4 only"
        );
    }

    #[test]
    fn rodas5p_nodes_d_and_stiff_accuracy() {
        let (alpha, gam, b) = classical_form();
        for i in 0..STAGES {
            // c_i = Σ_j α_ij, d_i = γ_i = Σ_j γ_ij, diagonal of Γ = γ.
            assert!(
                (alpha.row(i).sum() - C_NODES[i]).abs() < 1e-12,
                "c_{} mismatch",
                i + 1
            );
            assert!(
                (gam.row(i).sum() - D[i]).abs() < 1e-12,
                "d_{} mismatch",
                i + 1
            );
            assert!((gam[(i, i)] - GAMMA).abs() < 1e-15);
            // Stiff accuracy: b_j = β_sj (last row of α + Γ).
            assert!(
                (b[i] - (alpha[(STAGES - 1, i)] + gam[(STAGES - 1, i)])).abs() < 1e-12,
                "not stiffly accurate at {i}"
            );
        }
    }

    /// Stability function R(z) = 1 + z bᵀ (I - z β)⁻¹ 1.
    fn stability(z: Complex<f64>) -> Complex<f64> {
        let (alpha, gam, b) = classical_form();
        let beta = (&alpha + &gam).map(|v| Complex::new(v, 0.0));
        let s = STAGES;
        let m = DMatrix::<Complex<f64>>::identity(s, s) - beta * z;
        let one = DVector::from_element(s, Complex::new(1.0, 0.0));
        let k = m.lu().solve(&one).expect("I - zβ regular");
        let bc = b.map(|v| Complex::new(v, 0.0));
        Complex::new(1.0, 0.0) + z * bc.dot(&k)
    }

    #[test]
    fn rodas5p_is_a_stable_and_l_stable() {
        for k in -60..=60 {
            let y = 10f64.powf(k as f64 / 10.0);
            let r = stability(Complex::new(0.0, y)).norm();
            assert!(r <= 1.0 + 1e-12, "|R(i {y:e})| = {r}");
        }
        for x in [-1e-2, -1.0, -10.0, -1e3] {
            assert!(stability(Complex::new(x, 0.0)).norm() < 1.0);
        }
        assert!(
            stability(Complex::new(-1e14, 0.0)).norm() < 1e-10,
            "R(-inf) should be 0"
        );
    }
}
