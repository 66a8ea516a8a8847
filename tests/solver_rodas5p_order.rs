//! Measured convergence orders of Rodas5P (src/solver/rodas5p/mod.rs) through the public API.
//!
//! One step of size h is taken with error control switched off (huge tolerances, first step
//! = h, t_end = t0 + h); the reference is a tight Radau5 solution. Local error of an order-5
//! method: O(h^6). On the stiff VDPOL (ε = 1e-6) the slow component keeps O(h^6); the fast
//! component has, besides the O(h^5..6) DAE part, an O(ε h²) term (Rosenbrock stage order 1;
//! measured ≈ 2 ε h², linear in ε) that dominates for h below ~5e-3 but stays ≤ 1e-11 there:
//! it is what a "one-step error ~ h²" measurement on VDPOL sees, and it is harmless.

mod solver_rodas5p_order {
    use hydraulic_slewing_plate::solver::testset::Vdpol;
    use hydraulic_slewing_plate::solver::{Atol, Integrator, Method, OdeSystem, SolverOptions};

    /// Integrate from (t0, x0) to t1 with Rodas5P at the fixed step h (error control off).
    fn fixed_steps(sys: &dyn OdeSystem, t0: f64, x0: &[f64], t1: f64, h: f64) -> Vec<f64> {
        let opts = SolverOptions {
            method: Method::Rodas5P,
            rtol: 1.0,
            atol: Atol::Scalar(1e30),
            initial_step: Some(h),
            max_step: h,
            min_step: 0.0,
            ..Default::default()
        };
        let mut integ = Integrator::new(opts, t0, x0.to_vec()).unwrap();
        integ.advance_to(sys, t1).unwrap();
        assert_eq!(integ.stats().rejected, 0);
        let n = ((t1 - t0) / h).round() as u64;
        assert!(integ.stats().accepted.abs_diff(n) <= 1);
        integ.x().to_vec()
    }

    /// Tight Radau5 solution (the reference).
    fn reference(sys: &dyn OdeSystem, t0: f64, x0: &[f64], t1: f64) -> Vec<f64> {
        let opts = SolverOptions {
            method: Method::Radau5,
            rtol: 1e-14,
            atol: Atol::Scalar(1e-14),
            max_steps: 10_000_000,
            ..Default::default()
        };
        let mut integ = Integrator::new(opts, t0, x0.to_vec()).unwrap();
        integ.advance_to(sys, t1).unwrap();
        integ.x().to_vec()
    }

    /// Per-component one-step errors for each h.
    fn local_errors(sys: &dyn OdeSystem, t0: f64, x0: &[f64], hs: &[f64]) -> Vec<[f64; 2]> {
        hs.iter()
            .map(|&h| {
                let x1 = fixed_steps(sys, t0, x0, t0 + h, h);
                let r = reference(sys, t0, x0, t0 + h);
                [(x1[0] - r[0]).abs(), (x1[1] - r[1]).abs()]
            })
            .collect()
    }

    /// Observed order between the first and last h (h halved each time).
    fn order(e_first: f64, e_last: f64, halvings: usize) -> f64 {
        (e_first / e_last).log2() / halvings as f64
    }

    const HS: [f64; 4] = [0.1, 0.05, 0.025, 0.0125];

    #[test]
    fn nonstiff_local_error_is_order_6() {
        let sys = Vdpol { eps: 1.0 };
        let x0 = reference(&sys, 0.0, &[2.0, 0.0], 0.4);
        let e = local_errors(&sys, 0.4, &x0, &HS);
        eprintln!("vdpol eps=1 local errors {e:?}");
        for c in 0..2 {
            let p = order(e[0][c], e[3][c], 3);
            assert!(p > 5.5, "component {c}: local order {p:.2} (errors {e:?})");
        }
    }

    #[test]
    fn nonstiff_global_error_is_order_5() {
        let sys = Vdpol { eps: 1.0 };
        let x0 = [2.0, 0.0];
        let r = reference(&sys, 0.0, &x0, 1.0);
        let e: Vec<f64> = [0.05, 0.025, 0.0125]
            .iter()
            .map(|&h| {
                let x = fixed_steps(&sys, 0.0, &x0, 1.0, h);
                (x[0] - r[0]).abs().max((x[1] - r[1]).abs())
            })
            .collect();
        eprintln!("vdpol eps=1 global errors {e:?}");
        let p = order(e[0], e[2], 2);
        assert!(p > 4.7 && p < 5.5, "global order {p:.2} (errors {e:?})");
    }

    #[test]
    fn stiff_vdpol_slow_component_order_6_fast_component_eps_h2() {
        let eps = 1e-6;
        let sys = Vdpol { eps };
        for t0 in [0.4, 1.2] {
            // A point on the slow manifold (the initial transient is long gone).
            let x0 = reference(&sys, 0.0, &[2.0, 0.0], t0);
            let hs = [0.05, 0.025, 0.0125];
            let e = local_errors(&sys, t0, &x0, &hs);
            eprintln!("vdpol eps=1e-6 t0={t0} local errors {e:?}");
            let p = order(e[0][0], e[2][0], 2);
            assert!(p > 5.7, "slow component: local order {p:.2} (errors {e:?})");
            // Fast component, small h: the ε h² term, bounded by a small multiple of ε h².
            let hs = [1.5625e-3, 7.8125e-4, 3.90625e-4];
            let e = local_errors(&sys, t0, &x0, &hs);
            for (h, ek) in hs.iter().zip(&e) {
                let k = ek[1] / (eps * h * h);
                eprintln!("t0={t0} h={h:e}: fast error {:e} = {k:.2} eps h^2", ek[1]);
                assert!(
                    k < 4.0,
                    "fast component error {:e} > 4 eps h^2 at h = {h:e}",
                    ek[1]
                );
                assert!(
                    ek[0] < 1e-14,
                    "slow component error {:e} at h = {h:e}",
                    ek[0]
                );
            }
        }
    }
}
