//! Behaviour of the public integrator API: exact stop times, bit-exact checkpoint/restore,
//! failure reporting, Jacobian checks, dense output, option validation.

// Wrapped in a module so that `cargo test solver` selects these tests by name.
mod solver_api {
    use std::cell::Cell;

    use hydraulic_slewing_plate::bond_graph::ExactDiscretisation;
    use hydraulic_slewing_plate::solver::testset::{problem, Oscillator, TestProblem, PROBLEMS};
    use hydraulic_slewing_plate::solver::{
        finite_difference_jacobian, Atol, Integrator, Method, OdeSystem, SolverErrorKind,
        SolverOptions,
    };
    use nalgebra::{DMatrix, DVector};

    const METHODS: [Method; 2] = [Method::Rodas5P, Method::Radau5];

    fn opts(method: Method, rtol: f64, atol: f64) -> SolverOptions {
        SolverOptions {
            method,
            rtol,
            atol: Atol::Scalar(atol),
            ..Default::default()
        }
    }

    /// A stiff first-order lag with a zero-order-held input u (changed by the "master" at
    /// communication points) plus a lightly damped mode driven by it: like a servo valve
    /// feeding a plate mode.
    struct Plant {
        u: Cell<f64>,
    }

    impl OdeSystem for Plant {
        fn dim(&self) -> usize {
            3
        }
        fn rhs(&self, _t: f64, x: &[f64], f: &mut [f64]) {
            let (w, z) = (2e3, 0.02);
            f[0] = -1e5 * (x[0] - self.u.get());
            f[1] = w * x[2];
            f[2] = -w * x[1] - 2.0 * z * w * x[2] + w * x[0];
        }
        fn jacobian(&self, _t: f64, _x: &[f64], j: &mut DMatrix<f64>) -> bool {
            let (w, z) = (2e3, 0.02);
            j.fill(0.0);
            j[(0, 0)] = -1e5;
            j[(1, 2)] = w;
            j[(2, 1)] = -w;
            j[(2, 2)] = -2.0 * z * w;
            j[(2, 0)] = w;
            true
        }
        fn is_autonomous(&self) -> bool {
            true
        }
    }

    fn input_at(k: usize) -> f64 {
        ((k as f64) * 0.7).sin()
    }

    /// Co-simulation loop: input jump, notify, advance one communication step.
    fn cosim(integ: &mut Integrator, plant: &Plant, k0: usize, k1: usize, dt: f64) {
        for k in k0..k1 {
            plant.u.set(input_at(k));
            integ.notify_discontinuity();
            let t_end = (k + 1) as f64 * dt;
            integ.advance_to(plant, t_end).unwrap();
            assert_eq!(
                integ.t().to_bits(),
                t_end.to_bits(),
                "stop time not hit exactly"
            );
        }
    }

    #[test]
    fn stop_times_are_hit_exactly() {
        for method in METHODS {
            let p = problem("vdpol").unwrap();
            let mut integ = Integrator::new(opts(method, 1e-6, 1e-6), 0.0, p.y0()).unwrap();
            // Awkward, non-representable communication points.
            for k in 1..=30 {
                let t_end = k as f64 * 0.0667;
                integ.advance_to(p.as_ref(), t_end).unwrap();
                assert_eq!(integ.t(), t_end, "{method:?}");
            }
            // advance_to the current time is a no-op.
            let before = integ.clone();
            integ.advance_to(p.as_ref(), integ.t()).unwrap();
            assert_eq!(before, integ);
            // Going backwards is an error naming the problem, and leaves the state alone.
            let e = integ.advance_to(p.as_ref(), 0.5).unwrap_err();
            assert_eq!(e.kind, SolverErrorKind::InvalidInput);
            assert!(e.message.contains("t_end"), "{e}");
            assert_eq!(before, integ);
        }
    }

    #[test]
    fn checkpoint_restore_continue_is_bit_identical() {
        for method in METHODS {
            let dt = 1e-3;
            let plant = Plant { u: Cell::new(0.0) };
            let mut a = Integrator::new(opts(method, 1e-7, 1e-9), 0.0, vec![0.0; 3]).unwrap();
            cosim(&mut a, &plant, 0, 20, dt);
            // Save (serialise) the state at a communication point.
            let json = serde_json::to_string(&a).unwrap();
            // Radau5's state holds the Jacobian it goes on with.
            assert_eq!(
                json.contains("kept_jac"),
                method == Method::Radau5,
                "{method:?}"
            );
            let copy = a.clone();
            cosim(&mut a, &plant, 20, 50, dt);

            let mut b: Integrator = serde_json::from_str(&json).unwrap();
            assert_eq!(b, copy, "JSON round trip must be exact");
            cosim(&mut b, &plant, 20, 50, dt);
            let mut c = copy;
            cosim(&mut c, &plant, 20, 50, dt);
            for other in [&b, &c] {
                assert_eq!(a.t().to_bits(), other.t().to_bits());
                let xa: Vec<u64> = a.x().iter().map(|v| v.to_bits()).collect();
                let xo: Vec<u64> = other.x().iter().map(|v| v.to_bits()).collect();
                assert_eq!(xa, xo, "{method:?}: state differs after restore");
                assert_eq!(a.stats(), other.stats());
                assert_eq!(&a, other);
            }
            assert!(a.stats().accepted > 50);
        }
    }

    /// Radau5 keeps a (varying) Jacobian from call to call while Newton converges fast, as
    /// RADAU5 keeps it from step to step: one call per communication step must not cost a
    /// Jacobian and two LUs each. The kept J is part of the saved state (a restored copy,
    /// whose cache starts empty, rebuilds it and its LUs uncounted and continues with the same
    /// bits: `checkpoint_restore_continue_is_bit_identical`), survives input jumps, and is
    /// dropped by a reset.
    #[test]
    fn radau5_keeps_its_jacobian_across_calls() {
        let dt = 1e-3;
        // A unit step of the input, then 200 points with the input held, and a jump.
        let plant = Plant { u: Cell::new(1.0) };
        let mut a = Integrator::new(opts(Method::Radau5, 1e-7, 1e-9), 0.0, vec![0.0; 3]).unwrap();
        for k in 1..=200 {
            a.advance_to(&plant, k as f64 * dt).unwrap();
        }
        let s = *a.stats();
        assert!(s.accepted >= 200, "{s:?}");
        // The plant's J is the same everywhere (though not declared constant), so Newton
        // converges at once: J is evaluated afresh only after a rejected step (as RADAU5 does),
        // not once per call as before.
        assert!(s.jac_evals <= s.rejected + 1, "{s:?}");
        assert!(s.jac_evals < 200, "{s:?}");
        let before = s.jac_evals;
        cosim(&mut a, &plant, 200, 201, dt);
        assert!(
            a.stats().rejected > s.rejected || a.stats().jac_evals == before,
            "an input jump keeps J"
        );
        let json = serde_json::to_string(&a).unwrap();
        assert!(json.contains("\"kept_jac\""), "{json}");
        // Rodas5P needs J at every step (a Rosenbrock method's order rests on it) and keeps
        // none.
        let mut r = Integrator::new(opts(Method::Rodas5P, 1e-7, 1e-9), 0.0, vec![0.0; 3]).unwrap();
        cosim(&mut r, &plant, 0, 20, dt);
        assert!(!serde_json::to_string(&r).unwrap().contains("kept_jac"));
        // A reset drops it: the next call evaluates J at the new point.
        a.reset(a.t(), vec![0.5, 0.0, 0.0]);
        assert!(!serde_json::to_string(&a).unwrap().contains("kept_jac"));
        let (before, rejected) = (a.stats().jac_evals, a.stats().rejected);
        cosim(&mut a, &plant, 201, 202, dt);
        assert!(a.stats().jac_evals > before, "{:?}", a.stats());
        assert!(a.stats().jac_evals <= before + 1 + a.stats().rejected - rejected);
    }

    /// [`Plant`] declaring what it is: a constant Jacobian (Radau5 may then take its steps as
    /// affine maps).
    struct ConstantPlant(Plant);

    impl OdeSystem for ConstantPlant {
        fn dim(&self) -> usize {
            3
        }
        fn rhs(&self, t: f64, x: &[f64], f: &mut [f64]) {
            self.0.rhs(t, x, f)
        }
        fn jacobian(&self, t: f64, x: &[f64], j: &mut DMatrix<f64>) -> bool {
            self.0.jacobian(t, x, j)
        }
        fn constant_jacobian(&self) -> Option<u64> {
            Some(1)
        }
        fn is_autonomous(&self) -> bool {
            true
        }
    }

    /// Radau5's step map on a linear system with a declared constant Jacobian: it is used (far
    /// fewer f evaluations than RADAU5's four per step), it delivers the accuracy of the
    /// ordinary steps against the exact solution, it follows a change of the held input, and
    /// a copy restored before or after the map was built goes on with the same bits.
    #[test]
    fn radau5_steps_of_an_affine_system_by_its_step_map() {
        // About one step per point, as in a co-simulation at a fine communication step.
        let dt = 1e-5;
        let points = 400;
        let run = |declared: bool, u: &dyn Fn(usize) -> f64| {
            let plant = ConstantPlant(Plant { u: Cell::new(0.0) });
            let mut integ =
                Integrator::new(opts(Method::Radau5, 1e-7, 1e-9), 0.0, vec![0.0; 3]).unwrap();
            let mut xs = Vec::new();
            for k in 0..points {
                if u(k) != plant.0.u.get() {
                    plant.0.u.set(u(k));
                    integ.notify_discontinuity();
                }
                let t_end = (k + 1) as f64 * dt;
                if declared {
                    integ.advance_to(&plant, t_end).unwrap();
                } else {
                    integ.advance_to(&plant.0, t_end).unwrap();
                }
                xs.push(integ.x().to_vec());
            }
            (xs, *integ.stats())
        };
        // A unit step, and a second step of the input half-way.
        let u = |k: usize| if k < points / 2 { 1.0 } else { -0.5 };
        let (mapped, s) = run(true, &u);
        let (ordinary, s0) = run(false, &u);
        // An ordinary step costs at least 4 f evaluations (3 stages and f0), a mapped one none
        // (f(t, 0) once per call): under 3 per step means the map took a good part of them
        // (all but the first steps with each new factorisation and those after the jumps).
        assert!(s0.f_evals >= 4 * s0.accepted, "{s0:?}");
        assert!(
            s.f_evals < 3 * s.accepted,
            "the map takes many steps: {s:?}"
        );
        // The exact solution at the points (the input held over each).
        let (w, z) = (2e3, 0.02);
        let a = DMatrix::from_row_slice(3, 3, &[-1e5, 0.0, 0.0, 0.0, 0.0, w, w, -w, -2.0 * z * w]);
        let b = DMatrix::from_row_slice(3, 1, &[1e5, 0.0, 0.0]);
        let disc = ExactDiscretisation::new(&a, &b, dt);
        let mut x = DVector::zeros(3);
        let mut next = DVector::zeros(3);
        let (mut err_mapped, mut err_ordinary, mut scale) = (0.0_f64, 0.0_f64, 0.0_f64);
        for k in 0..points {
            disc.step(&x, &disc.input_term(&[u(k)]), &mut next);
            std::mem::swap(&mut x, &mut next);
            for i in 0..3 {
                scale = scale.max(x[i].abs());
                err_mapped = err_mapped.max((mapped[k][i] - x[i]).abs());
                err_ordinary = err_ordinary.max((ordinary[k][i] - x[i]).abs());
            }
        }
        // Both within the tolerance of the largest state, and the map no worse than the
        // ordinary steps but for rounding (the map is their converged Newton iterate).
        assert!(err_mapped <= 1e-6 * scale, "{err_mapped:e} of {scale:e}");
        assert!(
            err_mapped <= 1.5 * err_ordinary + 1e-12 * scale,
            "{err_mapped:e} against {err_ordinary:e}"
        );
        // Restored before the map is built (k = 3) and after (k = 150, and after the input
        // changed, k = 300): the same bits to the end.
        for split in [3, 150, 300] {
            let plant = ConstantPlant(Plant { u: Cell::new(0.0) });
            let mut a =
                Integrator::new(opts(Method::Radau5, 1e-7, 1e-9), 0.0, vec![0.0; 3]).unwrap();
            let mut b = None;
            for k in 0..points {
                if u(k) != plant.0.u.get() {
                    plant.0.u.set(u(k));
                    a.notify_discontinuity();
                    if let Some(b) = &mut b {
                        Integrator::notify_discontinuity(b);
                    }
                }
                if k == split {
                    let json = serde_json::to_string(&a).unwrap();
                    b = Some(serde_json::from_str::<Integrator>(&json).unwrap());
                }
                let t_end = (k + 1) as f64 * dt;
                a.advance_to(&plant, t_end).unwrap();
                if let Some(b) = &mut b {
                    b.advance_to(&plant, t_end).unwrap();
                    let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(a.x()), bits(b.x()), "restored at {split}, t = {t_end}");
                }
            }
            assert_eq!(Some(&a), b.as_ref(), "restored at {split}");
        }
    }

    #[test]
    fn checkpoint_without_discontinuities_is_bit_identical() {
        // Same without notify_discontinuity: the controller history and Radau's Newton start
        // polynomial are carried across calls and must be part of the saved state.
        for method in METHODS {
            let p = problem("orego").unwrap();
            let mut a = Integrator::new(opts(method, 1e-6, 1e-6), 0.0, p.y0()).unwrap();
            for k in 1..=10 {
                a.advance_to(p.as_ref(), k as f64 * 7.0).unwrap();
            }
            let json = serde_json::to_string(&a).unwrap();
            for k in 11..=30 {
                a.advance_to(p.as_ref(), k as f64 * 7.0).unwrap();
            }
            let mut b: Integrator = serde_json::from_str(&json).unwrap();
            for k in 11..=30 {
                b.advance_to(p.as_ref(), k as f64 * 7.0).unwrap();
            }
            assert_eq!(a, b, "{method:?}");
        }
    }

    /// Advances `integ` through the points `k * dt` for k in k0+1..=k1 with `advance_past`
    /// (no limit), returning the states there.
    fn past(
        integ: &mut Integrator,
        sys: &dyn OdeSystem,
        k0: usize,
        k1: usize,
        dt: f64,
    ) -> Vec<Vec<f64>> {
        (k0 + 1..=k1)
            .map(|k| {
                let t = k as f64 * dt;
                integ.advance_past(sys, t, f64::INFINITY).unwrap();
                assert_eq!(
                    integ.t().to_bits(),
                    t.to_bits(),
                    "point not reported exactly"
                );
                integ.x().to_vec()
            })
            .collect()
    }

    #[test]
    fn stepping_past_points_is_accurate_and_takes_fewer_steps() {
        // Orego is stiff and oscillates; points every 0.5 s are much closer than the steps
        // rtol 1e-6 allows. The states at the points must agree with a tight reference as well
        // as those of steps ending on each point do. (Rodas5P only: Radau5 ends its steps on
        // the points, checked below.)
        for method in [Method::Rodas5P] {
            let p = problem("orego").unwrap();
            let mut reference = Integrator::new(opts(method, 1e-11, 1e-11), 0.0, p.y0()).unwrap();
            let mut ending = Integrator::new(opts(method, 1e-6, 1e-6), 0.0, p.y0()).unwrap();
            let mut free = ending.clone();
            let free_x = past(&mut free, p.as_ref(), 0, 200, 0.5);
            let mut worst = [0.0_f64; 2];
            for (k, xf) in free_x.iter().enumerate() {
                let t = (k + 1) as f64 * 0.5;
                reference.advance_to(p.as_ref(), t).unwrap();
                ending.advance_to(p.as_ref(), t).unwrap();
                for (w, x) in worst.iter_mut().zip([xf.as_slice(), ending.x()]) {
                    for (a, b) in x.iter().zip(reference.x()) {
                        *w = w.max((a - b).abs() / (1e-6 + b.abs()));
                    }
                }
            }
            assert!(
                worst[0] < 10.0 * worst[1].max(1e-6),
                "{method:?}: past {:e}, ending {:e}",
                worst[0],
                worst[1]
            );
            assert!(
                free.stats().accepted < ending.stats().accepted,
                "{method:?}: {:?} vs {:?}",
                free.stats(),
                ending.stats()
            );
        }
    }

    #[test]
    fn radau5_ends_its_steps_on_the_points() {
        let p = problem("orego").unwrap();
        let mut a = Integrator::new(opts(Method::Radau5, 1e-6, 1e-6), 0.0, p.y0()).unwrap();
        let mut b = a.clone();
        let xa = past(&mut a, p.as_ref(), 0, 100, 0.5);
        for (k, x) in xa.iter().enumerate() {
            b.advance_to(p.as_ref(), (k + 1) as f64 * 0.5).unwrap();
            assert_eq!(x.as_slice(), b.x());
            assert!(!a.is_past());
        }
        assert_eq!(a, b);
    }

    #[test]
    fn a_step_kept_past_a_point_is_saved_and_dropped_on_a_jump() {
        for method in [Method::Rodas5P] {
            let p = problem("orego").unwrap();
            let mut a = Integrator::new(opts(method, 1e-6, 1e-6), 0.0, p.y0()).unwrap();
            past(&mut a, p.as_ref(), 0, 10, 0.5);
            // Find a point inside a kept step, save there, and go on in both copies.
            let mut k = 10;
            while !a.is_past() {
                k += 1;
                past(&mut a, p.as_ref(), k - 1, k, 0.5);
            }
            let json = serde_json::to_string(&a).unwrap();
            let mut b: Integrator = serde_json::from_str(&json).unwrap();
            assert_eq!(a, b, "{method:?}: JSON round trip must be exact");
            let xa = past(&mut a, p.as_ref(), k, k + 40, 0.5);
            let xb = past(&mut b, p.as_ref(), k, k + 40, 0.5);
            assert_eq!(xa, xb, "{method:?}: states differ after restore");
            assert_eq!(a, b);
            // A jump goes on from the reported point, with no step kept.
            while !a.is_past() {
                k += 1;
                past(&mut a, p.as_ref(), k + 39, k + 40, 0.5);
            }
            let (t, x) = (a.t(), a.x().to_vec());
            a.notify_discontinuity();
            assert!(!a.is_past());
            assert_eq!((a.t(), a.x()), (t, x.as_slice()));
            // The limit is respected, and a limit before t_end is refused by name.
            let limit = t + 0.25;
            for j in 1..=5 {
                let t_end = (t + 0.05 * j as f64).min(limit);
                a.advance_past(p.as_ref(), t_end, limit).unwrap();
                assert_eq!(a.t(), t_end);
                assert!(
                    a.reached() <= limit,
                    "{method:?}: {} past {limit}",
                    a.reached()
                );
            }
            assert_eq!(
                a.reached(),
                limit,
                "{method:?}: the step was cut at the limit"
            );
            let e = a.advance_past(p.as_ref(), t + 0.2, t + 0.15).unwrap_err();
            assert_eq!(e.kind, SolverErrorKind::InvalidInput);
            assert!(e.message.contains("limit"), "{e}");
        }
    }

    #[test]
    fn serialised_state_has_no_non_finite_numbers() {
        for method in METHODS {
            let p = problem("hires").unwrap();
            let integ = Integrator::new(opts(method, 1e-6, 1e-10), 0.0, p.y0()).unwrap();
            let j = serde_json::to_string(&integ).unwrap();
            // serde_json writes NaN/inf as null; the only null allowed is initial_step: None.
            let stripped = j.replace("\"initial_step\":null", "");
            assert!(!stripped.contains("null"), "{j}");
            let back: Integrator = serde_json::from_str(&j).unwrap();
            assert_eq!(back, integ);
        }
    }

    struct NanAfter {
        t_bad: f64,
    }

    impl OdeSystem for NanAfter {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&self, t: f64, x: &[f64], f: &mut [f64]) {
            if t > self.t_bad {
                f[0] = f64::NAN;
                f[1] = 0.0;
            } else {
                f[0] = -x[0];
                f[1] = -1e4 * (x[1] - x[0]);
            }
        }
    }

    #[test]
    fn nan_everywhere_is_an_error_not_a_panic() {
        for method in METHODS {
            let sys = NanAfter { t_bad: -1.0 };
            let mut integ = Integrator::new(opts(method, 1e-6, 1e-9), 0.0, vec![1.0, 0.0]).unwrap();
            let before = integ.clone();
            let e = integ.advance_to(&sys, 1.0).unwrap_err();
            assert_eq!(e.kind, SolverErrorKind::NonFinite, "{method:?}: {e}");
            assert_eq!(e.t, 0.0);
            assert_eq!(integ.t(), before.t());
            assert_eq!(integ.x(), before.x());
            assert!(!e.to_string().is_empty());
        }
    }

    #[test]
    fn nan_later_stops_at_last_good_point_and_stays_usable() {
        for method in METHODS {
            let sys = NanAfter { t_bad: 0.5 };
            let mut integ = Integrator::new(opts(method, 1e-6, 1e-9), 0.0, vec![1.0, 0.0]).unwrap();
            let e = integ.advance_to(&sys, 1.0).unwrap_err();
            assert!(
                matches!(
                    e.kind,
                    SolverErrorKind::NonFinite
                        | SolverErrorKind::StepTooSmall
                        | SolverErrorKind::TooManyRejections
                ),
                "{method:?}: {e}"
            );
            assert!(e.t <= 0.5 && e.t > 0.4, "{method:?}: stopped at {}", e.t);
            assert_eq!(integ.t(), e.t);
            assert!(integ.x().iter().all(|v| v.is_finite()));
            // The state is still serialisable and the integrator usable with a healthy model.
            let _ = serde_json::to_string(&integ).unwrap();
            let good = NanAfter {
                t_bad: f64::INFINITY,
            };
            integ.advance_to(&good, 1.0).unwrap();
            assert_eq!(integ.t(), 1.0);
            assert!(
                (integ.x()[0] - (-1.0f64).exp()).abs() < 1e-5,
                "{method:?}: {:?}",
                integ.x()
            );
        }
    }

    #[test]
    fn too_many_steps_is_reported() {
        let p = problem("vdpol").unwrap();
        let mut o = opts(Method::Rodas5P, 1e-8, 1e-8);
        o.max_steps = 10;
        let mut integ = Integrator::new(o, 0.0, p.y0()).unwrap();
        let e = integ.advance_to(p.as_ref(), 2.0).unwrap_err();
        assert_eq!(e.kind, SolverErrorKind::TooManySteps);
        assert_eq!(integ.t(), e.t);
        assert!(e.t > 0.0 && e.t < 2.0);
    }

    #[test]
    fn analytic_jacobians_match_finite_differences() {
        for name in PROBLEMS {
            let p = problem(name).unwrap();
            let n = p.dim();
            let y0 = p.y0();
            // Check at y0 and at a perturbed point with all components non-zero.
            let y1: Vec<f64> = y0
                .iter()
                .enumerate()
                .map(|(i, v)| v * 1.1 + 1e-3 * (i as f64 + 1.0))
                .collect();
            for y in [y0, y1] {
                let t = 0.3 * p.t_end();
                let mut ja = DMatrix::zeros(n, n);
                assert!(
                    p.jacobian(t, &y, &mut ja),
                    "{name} has an analytic Jacobian"
                );
                let jf = finite_difference_jacobian(p.as_ref(), t, &y);
                let scale = ja.abs().max().max(1.0);
                let diff = (&ja - &jf).abs().max();
                assert!(
                    diff <= 1e-6 * scale,
                    "{name}: |J - J_fd| = {diff:e} (scale {scale:e})\n{ja}\n{jf}"
                );
            }
        }
    }

    /// HIRES without its Jacobian: exercises the finite-difference fallback.
    struct NoJac(Box<dyn TestProblem>);
    impl OdeSystem for NoJac {
        fn dim(&self) -> usize {
            self.0.dim()
        }
        fn rhs(&self, t: f64, x: &[f64], f: &mut [f64]) {
            self.0.rhs(t, x, f)
        }
        fn is_autonomous(&self) -> bool {
            self.0.is_autonomous()
        }
    }

    #[test]
    fn finite_difference_fallback_works() {
        use hydraulic_slewing_plate::solver::testset::scd;
        for name in ["hires", "rober", "prothero-robinson"] {
            for method in METHODS {
                let p = problem(name).unwrap();
                let sys = NoJac(problem(name).unwrap());
                let o = SolverOptions {
                    method,
                    rtol: 1e-6,
                    atol: p.atol(1e-6),
                    ..Default::default()
                };
                let mut integ = Integrator::new(o, 0.0, p.y0()).unwrap();
                integ.advance_to(&sys, p.t_end()).unwrap();
                let s = scd(integ.x(), &p.reference());
                assert!(s >= 4.5, "{name} {method:?} with FD Jacobian: scd {s}");
                assert!(integ.stats().f_evals > integ.stats().jac_evals * p.dim() as u64);
            }
        }
    }

    #[test]
    fn dense_output_is_accurate() {
        for method in METHODS {
            let osc0 = Oscillator {
                omega: 1e5,
                zeta: 0.01,
            };
            let mut plain = Integrator::new(opts(method, 1e-8, 1e-8), 0.0, vec![1.0, 0.0]).unwrap();
            plain.advance_to(&osc0, 1e-3).unwrap();
            let osc = Oscillator {
                omega: 1e5,
                zeta: 0.01,
            };
            let mut integ = Integrator::new(opts(method, 1e-8, 1e-8), 0.0, vec![1.0, 0.0]).unwrap();
            let times: Vec<f64> = (1..=200).map(|k| k as f64 * 5e-6).collect();
            let mut seen = Vec::new();
            integ
                .advance_to_with_output(&osc, 1e-3, &times, &mut |t, x| {
                    let ex = osc.exact(t);
                    let err = (x[0] - ex[0]).abs().max((x[1] - ex[1]).abs());
                    seen.push((t, err, x.to_vec()));
                })
                .unwrap();
            assert_eq!(seen.len(), times.len());
            for ((t, err, _), w) in seen.iter().zip(&times) {
                assert_eq!(t, w);
                assert!(
                    *err < 1e-5,
                    "{method:?}: dense output error {err:e} at t = {t}"
                );
            }
            // The last output time is the end point: reported exactly as the state.
            assert_eq!(seen.last().unwrap().2, integ.x());
            // Outputs must not change the steps taken.
            assert_eq!(integ, plain);
        }
    }

    #[test]
    fn output_times_must_be_sorted() {
        let p = problem("vdpol").unwrap();
        let mut integ = Integrator::new(SolverOptions::default(), 0.0, p.y0()).unwrap();
        let e = integ
            .advance_to_with_output(p.as_ref(), 1.0, &[0.5, 0.2], &mut |_, _| {})
            .unwrap_err();
        assert_eq!(e.kind, SolverErrorKind::InvalidInput);
        assert_eq!(integ.t(), 0.0);
    }

    #[test]
    fn invalid_options_name_the_culprit() {
        let bad = |o: SolverOptions, dim: usize, word: &str| {
            let e = o.validate(dim).unwrap_err();
            assert_eq!(e.kind, SolverErrorKind::InvalidOptions);
            assert!(
                e.message.contains(word),
                "message {:?} should name {word}",
                e.message
            );
            assert!(Integrator::new(o, 0.0, vec![0.0; dim]).is_err());
        };
        let d = SolverOptions::default;
        bad(SolverOptions { rtol: -1.0, ..d() }, 2, "rtol");
        bad(
            SolverOptions {
                rtol: f64::NAN,
                ..d()
            },
            2,
            "rtol",
        );
        bad(
            SolverOptions {
                atol: Atol::Scalar(-1.0),
                ..d()
            },
            2,
            "atol",
        );
        bad(
            SolverOptions {
                atol: Atol::Vector(vec![1e-6; 3]),
                ..d()
            },
            2,
            "atol",
        );
        bad(
            SolverOptions {
                atol: Atol::Vector(vec![1e-6, f64::INFINITY]),
                ..d()
            },
            2,
            "atol[1]",
        );
        bad(
            SolverOptions {
                max_step: f64::INFINITY,
                ..d()
            },
            2,
            "max_step",
        );
        bad(
            SolverOptions {
                max_step: 0.0,
                ..d()
            },
            2,
            "max_step",
        );
        bad(
            SolverOptions {
                min_step: -1.0,
                ..d()
            },
            2,
            "min_step",
        );
        bad(
            SolverOptions {
                initial_step: Some(0.0),
                ..d()
            },
            2,
            "initial_step",
        );
        bad(
            SolverOptions {
                max_steps: 0,
                ..d()
            },
            2,
            "max_steps",
        );
        assert!(d().validate(2).is_ok());
        // Default options serialise (finite max_step).
        let j = serde_json::to_string(&d()).unwrap();
        assert_eq!(serde_json::from_str::<SolverOptions>(&j).unwrap(), d());
        // Non-finite initial state and dimension mismatch are input errors.
        let e = Integrator::new(d(), 0.0, vec![f64::NAN]).unwrap_err();
        assert_eq!(e.kind, SolverErrorKind::InvalidInput);
        let p = problem("hires").unwrap();
        let mut integ = Integrator::new(d(), 0.0, vec![0.0; 2]).unwrap();
        assert_eq!(
            integ.advance_to(p.as_ref(), 1.0).unwrap_err().kind,
            SolverErrorKind::InvalidInput
        );
    }

    #[test]
    fn max_step_is_respected_and_reset_works() {
        for method in METHODS {
            let p = problem("hires").unwrap();
            let o = SolverOptions {
                method,
                rtol: 1e-4,
                atol: Atol::Scalar(1e-8),
                max_step: 1.0,
                ..Default::default()
            };
            let mut integ = Integrator::new(o, 0.0, p.y0()).unwrap();
            integ.advance_to(p.as_ref(), 50.0).unwrap();
            assert!(integ.stats().accepted >= 50, "{method:?}: max_step ignored");
            assert!(integ.step_size() <= 1.0);
            integ.reset(0.0, p.y0());
            assert_eq!(integ.t(), 0.0);
            assert_eq!(integ.x(), &p.y0()[..]);
            integ.advance_to(p.as_ref(), 1.0).unwrap();
            assert_eq!(integ.t(), 1.0);
        }
    }

    struct Decay;
    impl OdeSystem for Decay {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&self, _t: f64, x: &[f64], f: &mut [f64]) {
            f[0] = -x[0];
        }
    }

    #[test]
    fn final_steps_shorter_than_min_step_are_allowed() {
        // Communication steps below min_step: such a step size is dictated by t_end, not by error
        // control, so it is no failure, and it is a real step (accurate).
        for method in METHODS {
            let o = SolverOptions {
                method,
                rtol: 1e-8,
                atol: Atol::Scalar(1e-10),
                min_step: 1e-3,
                ..Default::default()
            };
            let mut integ = Integrator::new(o, 0.0, vec![1.0]).unwrap();
            for k in 1..=10 {
                integ.advance_to(&Decay, k as f64 * 1e-5).unwrap();
            }
            assert_eq!(integ.stats().accepted, 10);
            assert!(
                (integ.x()[0] - (-1e-4f64).exp()).abs() < 1e-13,
                "{method:?}: {}",
                integ.x()[0]
            );
        }
    }

    #[test]
    fn dense_output_on_stiff_problem_matches_tight_reference() {
        // HIRES: outputs from a tolerance-1e-7 run must agree with a tight (1e-11) run of the other
        // method at 40 interior times, i.e. the interpolants are accurate in the stiff regime too.
        let p = problem("hires").unwrap();
        let times: Vec<f64> = (1..=40).map(|k| k as f64 * 8.0).collect();
        let collect = |method: Method, rtol: f64| {
            let o = SolverOptions {
                method,
                rtol,
                atol: p.atol(rtol),
                ..Default::default()
            };
            let mut integ = Integrator::new(o, 0.0, p.y0()).unwrap();
            let mut vals = Vec::new();
            integ
                .advance_to_with_output(p.as_ref(), 321.8122, &times, &mut |_, x| {
                    vals.push(x.to_vec())
                })
                .unwrap();
            vals
        };
        for (method, other) in [
            (Method::Rodas5P, Method::Radau5),
            (Method::Radau5, Method::Rodas5P),
        ] {
            let reference = collect(other, 1e-11);
            let got = collect(method, 1e-7);
            assert_eq!(got.len(), times.len());
            for (k, (g, r)) in got.iter().zip(&reference).enumerate() {
                for i in 0..g.len() {
                    let tol = 1e-5 * r[i].abs() + 1e-10;
                    assert!(
                        (g[i] - r[i]).abs() < tol,
                        "{method:?} t = {} comp {i}: {} vs {}",
                        times[k],
                        g[i],
                        r[i]
                    );
                }
            }
        }
    }

    #[test]
    fn notify_discontinuity_keeps_the_step_size() {
        for method in METHODS {
            let p = problem("orego").unwrap();
            let mut integ = Integrator::new(opts(method, 1e-6, 1e-6), 0.0, p.y0()).unwrap();
            integ.advance_to(p.as_ref(), 10.0).unwrap();
            let h = integ.step_size();
            assert!(h > 0.0);
            integ.notify_discontinuity();
            assert_eq!(integ.step_size(), h);
            assert_eq!(integ.t(), 10.0);
        }
    }
}
