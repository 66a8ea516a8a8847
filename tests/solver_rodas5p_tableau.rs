//! Order conditions, consistency and stability of the Rodas5P tableau (src/solver/rodas5p/mod.rs).
//!
//! Rosenbrock order conditions via rooted trees (Hairer & Wanner II, Sec. IV.7): for a tree t,
//! Φ(t) is built recursively; a vertex with exactly one child contributes the matrix
//! β = α + Γ (Γ including its diagonal γ, because the J-term of the method is linear), a
//! vertex with two or more children contributes α. Order p  <=>  bᵀΦ(t) = 1/γ(t) for all trees
//! with |t| <= p, where γ(t) is the tree's density.

// Wrapped in a module so that `cargo test solver` selects these tests by name.
// Index loops over stages mirror the formulas they implement.
#[allow(clippy::needless_range_loop)]
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

    /// One Rodas5P step for the semi-explicit index-1 DAE M x' = F(t, x), M = diag(1, 1, 0),
    /// in the transformed form with a mass matrix (as Hairer's RODAS with IMAS = 1):
    /// (M/(hγ) - J) U_i = F(t0 + c_i h, x0 + Σ a_ij U_j) + M Σ (C_ij/h) U_j + h d_i F_t.
    /// Returns (y1, ŷ1) = (x0 + Σ m_j U_j, y1 - U_8).
    fn dae_step(t0: f64, x0: &DVector<f64>, h: f64) -> (DVector<f64>, DVector<f64>) {
        let mass = DVector::from_column_slice(&[1.0, 1.0, 0.0]);
        let mut w = -dae_jac(x0);
        for i in 0..3 {
            w[(i, i)] += mass[i] / (h * GAMMA);
        }
        let lu = w.lu();
        let ft = dae_ft(t0);
        let mut u: Vec<DVector<f64>> = Vec::new();
        for s in 0..STAGES {
            let mut y = x0.clone();
            let mut cu = DVector::zeros(3);
            for j in 0..s {
                y += &u[j] * rodas5p::A[s][j];
                cu += &u[j] * (rodas5p::C[s][j] / h);
            }
            let rhs = dae_f(t0 + C_NODES[s] * h, &y) + mass.component_mul(&cu) + &ft * (h * D[s]);
            u.push(lu.solve(&rhs).expect("regular"));
        }
        let mut y1 = x0.clone();
        for j in 0..STAGES {
            y1 += &u[j] * rodas5p::M[j];
        }
        let yhat = &y1 - &u[STAGES - 1];
        (y1, yhat)
    }

    /// Exact solution of the test DAE, its first and second derivatives.
    fn dae_exact(t: f64) -> [DVector<f64>; 3] {
        [
            DVector::from_column_slice(&[1.0 + t.sin(), (-t).exp(), 0.5 + 0.3 * (2.0 * t).cos()]),
            DVector::from_column_slice(&[t.cos(), -(-t).exp(), -0.6 * (2.0 * t).sin()]),
            DVector::from_column_slice(&[-t.sin(), (-t).exp(), -1.2 * (2.0 * t).cos()]),
        ]
    }

    /// Autonomous, nonlinear part G(x) (g_z = 1 + 0.6 z² ≠ 0: index 1).
    fn dae_g(x: &DVector<f64>) -> DVector<f64> {
        let (y1, y2, z) = (x[0], x[1], x[2]);
        DVector::from_column_slice(&[
            -y2 + z.sin() + 0.5 * y1,
            y1 * z - 0.3 * y2 * y2,
            z + 0.2 * z * z * z - y1 * y2 - y1.cos(),
        ])
    }

    #[rustfmt::skip]
    fn dae_jac(x: &DVector<f64>) -> DMatrix<f64> {
        let (y1, y2, z) = (x[0], x[1], x[2]);
        DMatrix::from_row_slice(
            3,
            3,
            &[
                0.5, -1.0, z.cos(),
                z, -0.6 * y2, y1,
                -y2 + y1.sin(), -y1, 1.0 + 0.6 * z * z,
            ],
        )
    }

    /// F(t, x) = G(x) + r(t) with r(t) = M x*'(t) - G(x*(t)), so that x* is the solution.
    fn dae_f(t: f64, x: &DVector<f64>) -> DVector<f64> {
        let [xs, dxs, _] = dae_exact(t);
        let mut r = -dae_g(&xs);
        r[0] += dxs[0];
        r[1] += dxs[1];
        dae_g(x) + r
    }

    /// ∂F/∂t = r'(t) = M x*'' - G_x(x*) x*'.
    fn dae_ft(t: f64) -> DVector<f64> {
        let [xs, dxs, ddxs] = dae_exact(t);
        let mut r = -(dae_jac(&xs) * &dxs);
        r[0] += ddxs[0];
        r[1] += ddxs[1];
        r
    }

    /// Index-1 DAE orders, measured: local error of y1 O(h^6) in the differential and
    /// O(h^5) (at least) in the algebraic component, i.e. DAE order 5; the embedded ŷ1 has
    /// DAE order 4. Exercises A, C, c, d, m and γ together on a non-autonomous nonlinear DAE
    /// (the index-1 conditions of Hairer & Wanner VI.3 beyond the ODE trees).
    #[test]
    fn rodas5p_index1_dae_orders() {
        let t0 = 0.3;
        let x0 = dae_exact(t0)[0].clone();
        let hs = [0.1, 0.05, 0.025, 0.0125];
        let mut e = Vec::new();
        for &h in &hs {
            let (y1, yhat) = dae_step(t0, &x0, h);
            let x = &dae_exact(t0 + h)[0];
            let ey = (y1[0] - x[0]).abs().max((y1[1] - x[1]).abs());
            let ez = (y1[2] - x[2]).abs();
            let ehy = (yhat[0] - x[0]).abs().max((yhat[1] - x[1]).abs());
            let ehz = (yhat[2] - x[2]).abs();
            e.push([ey, ez, ehy, ehz]);
        }
        let ord = |c: usize| (e[0][c] / e[3][c]).log2() / 3.0;
        eprintln!("DAE local errors [y, z, ŷ, ẑ]: {e:?}");
        eprintln!(
            "orders: y {:.2}, z {:.2}, ŷ {:.2}, ẑ {:.2}",
            ord(0),
            ord(1),
            ord(2),
            ord(3)
        );
        assert!(
            ord(0) > 5.7,
            "differential component: local order {:.2}",
            ord(0)
        );
        assert!(
            ord(1) > 4.7,
            "algebraic component: local order {:.2}",
            ord(1)
        );
        assert!(
            ord(2) > 4.5 && ord(2) < 5.5,
            "embedded y: local order {:.2}",
            ord(2)
        );
        assert!(ord(3) > 4.3, "embedded z: local order {:.2}", ord(3));
    }
}
