//! The ROS34PW2 W-method (src/solver/ros34pw2/): its tableau against the published numbers,
//! the order conditions of a W-method (order 3, embedded order 2), the order observed with a
//! wrong Jacobian (what makes J and W reusable). The contract of every method (restore bit for
//! bit with the kept J, no allocation, ...) is `tests/solver_methods.rs`'s.
//!
//! W-method order conditions (Hairer & Wanner II, Sec. IV.7, "W-methods"; Rang & Angermann 2005,
//! Sec. 2): with an arbitrary matrix A in place of J the elementary differentials of f and of A
//! separate, so that up to order 3, with α_i = Σ_j α_ij and γ_i = Σ_j γ_ij (Γ with its
//! diagonal γ):
//! Σ b_i = 1; Σ b_i α_i = 1/2, Σ b_i γ_i = 0; Σ b_i α_i² = 1/3, Σ b_i α_ij α_j = 1/6,
//! Σ b_i α_ij γ_j = 0, Σ b_i γ_ij α_j = 0, Σ b_i γ_ij γ_j = 0.

// Wrapped in a module so that `cargo test solver` selects these tests by name. The published
// coefficients are written with the 17 digits they are printed with.
#[allow(clippy::excessive_precision)]
mod solver_ros34pw2 {
    use hydraulic_slewing_plate::solver::ros34pw2::{classical_form, C_NODES, D, GAMMA};
    use hydraulic_slewing_plate::solver::{Atol, Integrator, Method, OdeSystem, SolverOptions};
    use nalgebra::{DMatrix, DVector};

    /// The published classical form (Rang & Angermann 2005; the same digits in PETSc's
    /// `TSROSWRA34PW2` and MATLODE's `Coefficients_ROS34PW2.m`): α, the strictly lower γ_ij,
    /// b and b̂.
    const ALPHA: [(usize, usize, f64); 4] = [
        (1, 0, 8.7173304301691801e-01),
        (2, 0, 8.4457060015369423e-01),
        (2, 1, -1.1299064236484185e-01),
        (3, 2, 1.0),
    ];
    const GAMMA_IJ: [(usize, usize, f64); 6] = [
        (1, 0, -8.7173304301691801e-01),
        (2, 0, -9.0338057013044082e-01),
        (2, 1, 5.4180672388095326e-02),
        (3, 0, 2.4212380706095346e-01),
        (3, 1, -1.2232505839045147e+00),
        (3, 2, 5.4526025533510214e-01),
    ];
    const B: [f64; 4] = [
        2.4212380706095346e-01,
        -1.2232505839045147e+00,
        1.5452602553351020e+00,
        4.3586652150845900e-01,
    ];
    const B_HAT: [f64; 4] = [
        3.7810903145819369e-01,
        -9.6042292212423178e-02,
        0.5,
        2.1793326075422950e-01,
    ];

    /// Rounding of 17 published digits through one 4 × 4 inversion and product.
    const TOL: f64 = 1e-14;

    /// The transformed tableau the step uses gives back the published classical form.
    #[test]
    fn transformed_tableau_is_the_published_method() {
        let (alpha, gamma, b, b_hat) = classical_form();
        for i in 0..4 {
            for j in 0..4 {
                let a = ALPHA
                    .iter()
                    .find(|&&(r, c, _)| (r, c) == (i, j))
                    .map_or(0.0, |e| e.2);
                let g = if i == j {
                    GAMMA
                } else {
                    GAMMA_IJ
                        .iter()
                        .find(|&&(r, c, _)| (r, c) == (i, j))
                        .map_or(0.0, |e| e.2)
                };
                assert!((alpha[(i, j)] - a).abs() < TOL, "alpha[{i}][{j}]");
                assert!((gamma[(i, j)] - g).abs() < TOL, "gamma[{i}][{j}]");
            }
            assert!((b[i] - B[i]).abs() < TOL, "b[{i}]");
            assert!((b_hat[i] - B_HAT[i]).abs() < TOL, "b_hat[{i}]");
            let alpha_i: f64 = (0..4).map(|j| alpha[(i, j)]).sum();
            let gamma_i: f64 = (0..4).map(|j| gamma[(i, j)]).sum();
            assert!((C_NODES[i] - alpha_i).abs() < TOL, "c[{i}]");
            assert!((D[i] - gamma_i).abs() < TOL, "d[{i}]");
        }
    }

    /// The W-method order conditions (module documentation) of `w` up to `order`: the
    /// residuals.
    fn w_conditions(alpha: &DMatrix<f64>, gamma: &DMatrix<f64>, w: &DVector<f64>) -> Vec<f64> {
        let one = DVector::from_element(4, 1.0);
        let a = alpha * &one;
        let g = gamma * &one;
        let a2 = a.component_mul(&a);
        vec![
            w.dot(&one) - 1.0,
            w.dot(&a) - 0.5,
            w.dot(&g),
            w.dot(&a2) - 1.0 / 3.0,
            w.dot(&(alpha * &a)) - 1.0 / 6.0,
            w.dot(&(alpha * &g)),
            w.dot(&(gamma * &a)),
            w.dot(&(gamma * &g)),
        ]
    }

    /// b meets the W-method conditions of order 3, b̂ those of order 2 and not all of order 3
    /// (else the error estimate would vanish at order 3).
    #[test]
    fn w_method_order_conditions() {
        let (alpha, gamma, b, b_hat) = classical_form();
        let main = w_conditions(&alpha, &gamma, &b);
        for (k, r) in main.iter().enumerate() {
            assert!(r.abs() < TOL, "condition {k} of b: residual {r:e}");
        }
        let embedded = w_conditions(&alpha, &gamma, &b_hat);
        for (k, r) in embedded[..3].iter().enumerate() {
            assert!(r.abs() < TOL, "condition {k} of b_hat: residual {r:e}");
        }
        assert!(embedded[3..].iter().any(|r| r.abs() > 1e-3));
    }

    /// y' = y² from y(0) = 1: y = 1/(1 − t), y(0.5) = 2 (nonlinear, so f'' enters the error),
    /// with a Jacobian that is wrong on purpose: `wrong` in place of 2y.
    struct Riccati {
        wrong: f64,
    }

    impl OdeSystem for Riccati {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&self, _t: f64, x: &[f64], f: &mut [f64]) {
            f[0] = x[0] * x[0];
        }
        fn jacobian(&self, _t: f64, _x: &[f64], j: &mut DMatrix<f64>) -> bool {
            j[(0, 0)] = self.wrong;
            true
        }
    }

    fn error_with(method: Method, wrong: f64, steps: u32) -> f64 {
        let opts = SolverOptions {
            method,
            substeps: steps,
            rtol: 1e-6,
            atol: Atol::Scalar(1e-6),
            ..Default::default()
        };
        let mut integ = Integrator::new(opts, 0.0, vec![1.0]).unwrap();
        integ.advance_to(&Riccati { wrong }, 0.5).unwrap();
        (integ.x()[0] - 2.0).abs()
    }

    /// With a Jacobian far from the true one (0 and −3 for 2y ∈ [2, 4]) the fixed-step driver
    /// still converges with order 3: halving the step divides the error by about 8. (A
    /// Rosenbrock method needs the exact J for its order: Rodas5P's fixed step with the same
    /// wrong J converges with a lower order, the control.)
    #[test]
    fn order_three_with_a_wrong_jacobian() {
        for wrong in [0.0, -3.0] {
            let e: Vec<f64> = [40, 80, 160]
                .iter()
                .map(|&n| error_with(Method::Ros34pw2Fixed, wrong, n))
                .collect();
            for k in 0..2 {
                let order = (e[k] / e[k + 1]).log2();
                assert!(
                    (2.7..3.5).contains(&order),
                    "J = {wrong}: errors {e:?}, observed order {order:.2}"
                );
            }
            let rodas: Vec<f64> = [40, 80]
                .iter()
                .map(|&n| error_with(Method::Rodas5PFixed, wrong, n))
                .collect();
            let order = (rodas[0] / rodas[1]).log2();
            assert!(order < 2.5, "Rodas5P with J = {wrong}: order {order:.2}");
        }
    }
}
