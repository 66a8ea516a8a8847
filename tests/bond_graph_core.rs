//! Bond-graph core against textbook graphs with hand-derived equations, causality errors,
//! Jacobian, power balance and DOT export.

use hydraulic_slewing_plate::bond_graph::{
    BondGraph, BondGraphError, CompiledModel, Law, NonlinearLaw,
};
use nalgebra::DMatrix;

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Log-uniform around `v`, one decade either way.
    fn around(&mut self, v: f64) -> f64 {
        v * 10f64.powf(2.0 * self.next() - 1.0)
    }
    /// Uniform in [-a, a].
    fn sym(&mut self, a: f64) -> f64 {
        a * (2.0 * self.next() - 1.0)
    }
}

fn close(a: f64, b: f64, rel: f64, scale: f64) -> bool {
    (a - b).abs() <= rel * (a.abs().max(b.abs()).max(scale))
}

// ---------------------------------------------------------------- Se-1-I-C-R

/// Se - 1 - {I, C, R}: force on a mass-spring-damper. `reversed` draws the storage and R bonds
/// pointing into the junction instead of out of it.
fn msd(m: f64, c: f64, r: f64, reversed: bool) -> BondGraph {
    let mut g = BondGraph::new("msd");
    let f = g.add_input("F");
    let se = g.add_se("force", f);
    let j = g.add_one("v");
    let i = g.add_i("mass", m);
    let k = g.add_c("spring", c);
    let d = g.add_r("damper", r);
    g.bond(se, j);
    let bm = if reversed { g.bond(i, j) } else { g.bond(j, i) };
    if reversed {
        g.bond(k, j);
        g.bond(d, j);
    } else {
        g.bond(j, k);
        g.bond(j, d);
    }
    g.add_flow_output("velocity", bm);
    g.add_state_output("x_spring", k, 0);
    g
}

#[test]
fn se_1_i_c_r_matches_hand_derivation() {
    let mut rng = Rng(12345);
    for reversed in [false, true] {
        for _ in 0..20 {
            let (m, c, r) = (rng.around(2.0), rng.around(0.01), rng.around(3.0));
            let model = msd(m, c, r, reversed).compile().unwrap();
            assert_eq!(model.state_names(), ["mass.p", "spring.q"]);
            let x = [rng.sym(5.0), rng.sym(0.1)];
            let u = [rng.sym(10.0)];
            let mut dx = [0.0; 2];
            model.derivatives(&x, &u, &mut dx);
            // dp/dt = F - q/C - R p/m, dq/dt = p/m. Reversed: the element flows are minus the
            // bond flows, so the junction's common flow (the source's flow) is -p/m: the
            // source pushes the other way, dp/dt = -F - q/C - R p/m.
            let fs = if reversed { -u[0] } else { u[0] };
            let want = [fs - x[1] / c - r * x[0] / m, x[0] / m];
            let scale = u[0].abs() + (x[1] / c).abs() + (r * x[0] / m).abs();
            assert!(close(dx[0], want[0], 1e-13, scale), "{dx:?} {want:?}");
            assert!(close(dx[1], want[1], 1e-13, 0.0));
            let mut y = [0.0; 2];
            model.outputs(&x, &u, &mut y);
            // the bond from I to the junction carries the velocity against its half arrow
            let v = if reversed { -x[0] / m } else { x[0] / m };
            assert!(close(y[0], v, 1e-14, 0.0), "{} {}", y[0], v);
            assert_eq!(y[1], x[1]);
            let lin = model.linearize(&x, &u);
            let a = DMatrix::from_row_slice(2, 2, &[-r / m, -1.0 / c, 1.0 / m, 0.0]);
            for k in 0..4 {
                assert!(close(lin.a[k], a[k], 1e-14, 0.0));
            }
            assert_eq!(lin.b[(0, 0)], if reversed { -1.0 } else { 1.0 });
            assert_eq!(lin.b[(1, 0)], 0.0);
            // energy
            let e = model.stored_energy(&x);
            let e_want = x[0] * x[0] / (2.0 * m) + x[1] * x[1] / (2.0 * c);
            assert!(close(e, e_want, 1e-14, 0.0));
        }
    }
}

// ---------------------------------------------------------------- TF and GY chain

/// Se(V) - 1a{L, Ra} - GY k - 1b{J, b} - TF n - 1c - C (shaft spring to a fixed end).
fn motor_chain(p: &[f64; 7], modulated: bool) -> BondGraph {
    let [l, ra, k, j, bf, n, cs] = *p;
    let mut g = BondGraph::new("motor");
    let v = g.add_input("u_V");
    let (kk, nn) = if modulated {
        (
            Some(g.add_input("u_k")), // modulated gyrator and transformer moduli
            Some(g.add_input("u_n")),
        )
    } else {
        (None, None)
    };
    let se = g.add_se("V", v);
    let j1a = g.add_one("current");
    let il = g.add_i("L", l);
    let rr = g.add_r("Ra", ra);
    let gy = match kk {
        Some(s) => g.add_gy("k", s),
        None => g.add_gy("k", k),
    };
    let j1b = g.add_one("omega");
    let ij = g.add_i("J", j);
    let rb = g.add_r("b", bf);
    let tf = match nn {
        Some(s) => g.add_tf("n", s),
        None => g.add_tf("n", n),
    };
    let j1c = g.add_one("omega_out");
    let c = g.add_c("shaft", cs);
    g.bond(se, j1a);
    g.bond(j1a, il);
    g.bond(j1a, rr);
    g.bond(j1a, gy);
    g.bond(gy, j1b);
    g.bond(j1b, ij);
    g.bond(j1b, rb);
    g.bond(j1b, tf);
    g.bond(tf, j1c);
    g.bond(j1c, c);
    g
}

#[test]
fn tf_gy_chain_matches_hand_derivation() {
    let mut rng = Rng(777);
    for modulated in [false, true] {
        for _ in 0..20 {
            let p = [
                rng.around(0.5),
                rng.around(100.0),
                rng.around(0.1),
                rng.around(1e-3),
                rng.around(1e-4),
                rng.around(5.0),
                rng.around(1e-2),
            ];
            let [l, ra, k, j, bf, n, cs] = p;
            let model = motor_chain(&p, modulated).compile().unwrap();
            assert_eq!(model.state_names(), ["L.p", "J.p", "shaft.q"]);
            let x = [rng.sym(0.1), rng.sym(1e-2), rng.sym(0.1)];
            let u: Vec<f64> = if modulated {
                vec![rng.sym(10.0), k, n]
            } else {
                vec![rng.sym(10.0)]
            };
            let mut dx = [0.0; 3];
            model.derivatives(&x, &u, &mut dx);
            let (i, w, tau_s) = (x[0] / l, x[1] / j, x[2] / cs);
            // TF: e2 = n e1, f1 = n f2 (gear: output torque n times input, speed / n)
            let want = [u[0] - ra * i - k * w, k * i - bf * w - tau_s / n, w / n];
            let scales = [
                u[0].abs() + (ra * i).abs() + (k * w).abs(),
                (k * i).abs() + (bf * w).abs() + (tau_s / n).abs(),
                0.0,
            ];
            for q in 0..3 {
                assert!(
                    close(dx[q], want[q], 1e-13, scales[q]),
                    "modulated={modulated} dx[{q}] {} vs {}",
                    dx[q],
                    want[q]
                );
            }
            check_jacobian(&model, &x, &u);
            check_power(&model, &x, &u);
        }
    }
}

// ---------------------------------------------------------------- fields

fn spd(rng: &mut Rng, n: usize, scale: f64) -> DMatrix<f64> {
    let a = DMatrix::from_fn(n, n, |_, _| rng.sym(1.0));
    (&a * a.transpose() + DMatrix::identity(n, n) * 0.5) * scale
}

/// Se F on v1; I-field (mass matrix M) and C-field (stiffness K) over the two velocities v1, v2;
/// damper R on v2.
fn two_dof(m: &DMatrix<f64>, k: &DMatrix<f64>, r: f64) -> BondGraph {
    let mut g = BondGraph::new("two_dof");
    let f = g.add_input("F");
    let se = g.add_se("force", f);
    let v1 = g.add_one("v1");
    let v2 = g.add_one("v2");
    let mi = g.add_i_field("M", m.clone());
    let kc = g.add_c_field("K", k.clone());
    let d = g.add_r("R", r);
    g.bond(se, v1);
    g.bond(v1, mi);
    g.bond(v2, mi);
    g.bond(v1, kc);
    g.bond(kc, v2); // reversed orientation on purpose
    g.bond(v2, d);
    g
}

#[test]
fn fields_match_hand_derivation() {
    let mut rng = Rng(4242);
    for _ in 0..20 {
        let m = spd(&mut rng, 2, 3.0);
        let k = spd(&mut rng, 2, 100.0);
        let r = rng.around(2.0);
        let model = two_dof(&m, &k, r).compile().unwrap();
        assert_eq!(
            model.state_names(),
            ["M.p[1]", "M.p[2]", "K.q[1]", "K.q[2]"]
        );
        let x = [rng.sym(1.0), rng.sym(1.0), rng.sym(0.1), rng.sym(0.1)];
        let u = [rng.sym(10.0)];
        let mut dx = [0.0; 4];
        model.derivatives(&x, &u, &mut dx);
        let p = nalgebra::Vector2::new(x[0], x[1]);
        let q = nalgebra::Vector2::new(x[2], x[3]);
        let v = m.clone().try_inverse().unwrap() * p;
        let kq = &k * q;
        // K's second port points out of the field into v2: its inflow is -v2 and its effort
        // enters v2 with a + sign.
        let want = [u[0] - kq[0], kq[1] - r * v[1], v[0], -v[1]];
        for i in 0..4 {
            assert!(
                close(dx[i], want[i], 1e-12, 1.0),
                "dx[{i}] {} vs {}",
                dx[i],
                want[i]
            );
        }
        let e_want = 0.5 * p.dot(&(m.clone().try_inverse().unwrap() * p)) + 0.5 * q.dot(&kq);
        assert!(close(model.stored_energy(&x), e_want, 1e-12, 0.0));
        check_jacobian(&model, &x, &u);
        check_power(&model, &x, &u);
    }
}

#[test]
fn field_validation() {
    let k = DMatrix::from_row_slice(2, 2, &[1.0, 0.5, 0.4, 1.0]);
    let m = DMatrix::identity(2, 2);
    let err = two_dof(&m, &k, 1.0).compile().unwrap_err();
    assert!(
        err.to_string().contains("'K'") && err.to_string().contains("symmetric"),
        "{err}"
    );
    let m_bad = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
    let err = two_dof(&m_bad, &DMatrix::identity(2, 2), 1.0)
        .compile()
        .unwrap_err();
    assert!(
        err.to_string().contains("'M'") && err.to_string().contains("positive definite"),
        "{err}"
    );
    let m3 = DMatrix::identity(3, 3);
    let err = two_dof(&m3, &DMatrix::identity(2, 2), 1.0)
        .compile()
        .unwrap_err();
    assert!(
        err.to_string().contains("'M'") && err.to_string().contains("3x3"),
        "{err}"
    );
}

// ---------------------------------------------------------------- causality errors

#[test]
fn dependent_inertia_is_rejected_naming_both() {
    let mut g = BondGraph::new("dep");
    let se = g.add_se("F", 1.0);
    let j = g.add_one("v");
    let i1 = g.add_i("I1", 1.0);
    let i2 = g.add_i("I2", 2.0);
    g.bond(se, j);
    g.bond(j, i1);
    g.bond(j, i2);
    let err = g.compile().unwrap_err();
    match &err {
        BondGraphError::DerivativeCausality { element, forced_by } => {
            assert_eq!(element, "I2");
            assert_eq!(forced_by, &["I1".to_string()]);
        }
        e => panic!("wrong error {e:?}"),
    }
    let msg = err.to_string();
    assert!(
        msg.contains("'I2'") && msg.contains("'I1'") && msg.contains("derivative"),
        "{msg}"
    );
    // DOT still draws the graph, with the error as label
    assert!(g.to_dot().contains("derivative causality"));
}

#[test]
fn dependent_capacitors_on_a_zero_junction_are_rejected() {
    let mut g = BondGraph::new("dep_c");
    let sf = g.add_sf("Q", 1.0);
    let j = g.add_zero("p");
    let c1 = g.add_c("C1", 1.0);
    let c2 = g.add_c("C2", 1.0);
    g.bond(sf, j);
    g.bond(j, c1);
    g.bond(j, c2);
    let msg = g.compile().unwrap_err().to_string();
    assert!(msg.contains("'C2'") && msg.contains("'C1'"), "{msg}");
}

#[test]
fn algebraic_loop_is_rejected_naming_elements() {
    // Se - 1{R1} - 0{R2} - 1'{R3, I}: R1 and R2 form an algebraic loop.
    let mut g = BondGraph::new("loop");
    let se = g.add_se("Se", 1.0);
    let j1 = g.add_one("J1");
    let r1 = g.add_r("R1", 1.0);
    let j0 = g.add_zero("J0");
    let r2 = g.add_r("R2", 2.0);
    let j1b = g.add_one("J1b");
    let r3 = g.add_r("R3", 3.0);
    let i = g.add_i("I", 1.0);
    g.bond(se, j1);
    g.bond(j1, r1);
    g.bond(j1, j0);
    g.bond(j0, r2);
    g.bond(j0, j1b);
    g.bond(j1b, r3);
    g.bond(j1b, i);
    let err = g.compile().unwrap_err();
    match &err {
        BondGraphError::AlgebraicLoop { elements } => {
            for n in ["R1", "R2", "J1", "J0"] {
                assert!(elements.contains(&n.to_string()), "{elements:?}");
            }
            assert!(!elements.contains(&"I".to_string()));
        }
        e => panic!("wrong error {e:?}"),
    }
    assert!(
        err.to_string().starts_with("algebraic loop through"),
        "{err}"
    );
}

#[test]
fn signal_algebraic_loop_is_rejected() {
    let mut g = BondGraph::new("sigloop");
    let u = g.add_input("u");
    let port = g.add_signal_port("fb");
    let sum = g.add_sum("sum", &[(1.0, u), (-1.0, port)]);
    let k = g.add_gain("k", 2.0, sum);
    g.connect_signal_port(port, k);
    g.add_output("y", k);
    let err = g.compile().unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("'sum'") && msg.contains("'k'") && msg.contains("'fb'"),
        "{msg}"
    );
}

#[test]
fn two_effort_sources_on_a_zero_junction_conflict() {
    let mut g = BondGraph::new("conflict");
    let s1 = g.add_se("S1", 1.0);
    let s2 = g.add_se("S2", 2.0);
    let j = g.add_zero("J");
    let c = g.add_c("C", 1.0);
    g.bond(s1, j);
    g.bond(s2, j);
    g.bond(j, c);
    let msg = g.compile().unwrap_err().to_string();
    assert!(
        msg.contains("'J'") && msg.contains("'S1'") && msg.contains("'S2'"),
        "{msg}"
    );
}

#[test]
fn parameter_validation_names_the_element() {
    let mut g = BondGraph::new("bad");
    let sf = g.add_sf("loes.valve", 1.0);
    let j = g.add_zero("loes.chamber");
    let c = g.add_c("loes.C3", -1e-11);
    g.bond(sf, j);
    g.bond(j, c);
    assert_eq!(
        g.compile().unwrap_err().to_string(),
        "element 'loes.C3': capacitance must be positive and finite, got -1e-11"
    );
    let mut g2 = msd(f64::NAN, 1.0, 1.0, false);
    let msg = g2.compile().unwrap_err().to_string();
    assert!(msg.contains("'mass'") && msg.contains("inertance"), "{msg}");
    g2 = msd(1.0, 1.0, 0.0, false);
    let msg = g2.compile().unwrap_err().to_string();
    assert!(
        msg.contains("'damper'") && msg.contains("resistance"),
        "{msg}"
    );
    // structure: an I with two bonds, a duplicate name, an unconnected port
    let mut g3 = BondGraph::new("s");
    let a = g3.add_one("a");
    let b = g3.add_one("b");
    let i = g3.add_i("I", 1.0);
    g3.bond(a, i);
    g3.bond(b, i);
    let msg = g3.compile().unwrap_err().to_string();
    assert!(
        msg.contains("'I'") && msg.contains("exactly one bond"),
        "{msg}"
    );
    let mut g4 = BondGraph::new("d");
    g4.add_one("x");
    g4.add_input("x");
    assert_eq!(
        g4.compile().unwrap_err(),
        BondGraphError::DuplicateName { name: "x".into() }
    );
    let mut g5 = BondGraph::new("p");
    g5.add_signal_port("loes.valve_command");
    let msg = g5.compile().unwrap_err().to_string();
    assert!(
        msg.contains("'loes.valve_command'") && msg.contains("not connected"),
        "{msg}"
    );
}

// ---------------------------------------------------------------- nonlinear graph

/// Hydraulic-flavoured nonlinear graph: a pressure source feeds a chamber through a regularised
/// orifice (conductance law, modulated by an opening signal), a hardening-spring capacitor, a
/// nonlinear leak, a vane motor (modulated TF) onto a nonlinear inertia with quadratic friction,
/// an integrator and a product signal.
fn nonlinear_graph() -> BondGraph {
    let mut g = BondGraph::new("nl");
    let ps = g.add_input("p_s");
    let opening = g.add_input("x_v");
    let dm = g.add_input("D_m");
    let src = g.add_se("supply", ps);
    let j1 = g.add_one("orifice_flow");
    let p_cr = 1e4;
    let orifice = NonlinearLaw::modulated("orifice", move |dp: f64, x: f64| {
        let k = 1e-6;
        let s = dp * dp + p_cr * p_cr;
        let r = s.powf(0.25);
        let q = k * x * dp / r;
        let dq_ddp = k * x * (1.0 / r - 0.5 * dp * dp / (s * r));
        let dq_dx = k * dp / r;
        (q, dq_ddp, dq_dx)
    });
    let ro = g.add_r_modulated("orifice", Law::Conductance(orifice), opening);
    let j0 = g.add_zero("chamber");
    let (c0, k3) = (1e-11, 1e30);
    let spring = NonlinearLaw::new("hardening", move |q: f64| {
        (q / c0 + k3 * q * q * q, 1.0 / c0 + 3.0 * k3 * q * q)
    })
    .with_energy(move |q| q * q / (2.0 * c0) + k3 * q.powi(4) / 4.0);
    let c = g.add_c("C", Law::Nonlinear(spring));
    let leak = g.add_r(
        "leak",
        Law::Conductance(NonlinearLaw::new("leak", |p: f64| {
            (p / 2e10 + 1e-30 * p * p * p, 1.0 / 2e10 + 3e-30 * p * p)
        })),
    );
    let tf = g.add_tf("motor", dm);
    let j2 = g.add_one("omega");
    // no energy function given: stored energy by quadrature
    let ii = g.add_i(
        "rotor",
        Law::Nonlinear(NonlinearLaw::new("I_nl", |p: f64| {
            (p / 0.01 + 0.1 * p * p * p, 1.0 / 0.01 + 0.3 * p * p)
        })),
    );
    let fr = g.add_r(
        "friction",
        Law::Nonlinear(NonlinearLaw::new("quad_friction", |w: f64| {
            let s = (w * w + 1.0).sqrt();
            (0.01 * w * s, 0.01 * (s + w * w / s))
        })),
    );
    g.bond(src, j1);
    g.bond(j1, ro);
    g.bond(j1, j0);
    g.bond(j0, c);
    g.bond(j0, leak);
    g.bond(j0, tf);
    g.bond(tf, j2);
    let bi = g.bond(j2, ii);
    g.bond(j2, fr);
    let w = g.add_flow_sensor("w", bi);
    let th = g.add_integrator("theta", w);
    let p3 = g.add_state_sensor("qC", c);
    let prod = g.add_product("w_times_q", w, p3);
    g.add_output("theta", th);
    g.add_output("wq", prod);
    let bc = g.find_bond("chamber->C").unwrap();
    g.add_effort_output("p_chamber", bc);
    g
}

#[test]
fn nonlinear_resistor_in_the_wrong_form_is_rejected() {
    // Sf - 0 - {C, R}: the 0-junction imposes the effort on R, so R must be in conductance form.
    let mut g = BondGraph::new("wrong_form");
    let sf = g.add_sf("Q", 1.0);
    let j = g.add_zero("p");
    let c = g.add_c("C", 1.0);
    let r = g.add_r(
        "leak",
        Law::Nonlinear(NonlinearLaw::new("cubic", |f: f64| {
            (f * f * f, 3.0 * f * f)
        })),
    );
    g.bond(sf, j);
    g.bond(j, c);
    g.bond(j, r);
    let err = g.compile().unwrap_err();
    assert!(
        matches!(err, BondGraphError::NonInvertibleLaw { .. }),
        "{err:?}"
    );
    assert!(err.to_string().starts_with("element 'leak':"), "{err}");
}

fn random_nl_state(rng: &mut Rng) -> ([f64; 3], [f64; 3]) {
    (
        [rng.sym(1e-4), rng.sym(2.0), rng.sym(3.0)],
        [rng.sym(2e7), rng.around(1.0), rng.around(8e-5)],
    )
}

#[test]
fn nonlinear_jacobian_matches_finite_differences() {
    let m = nonlinear_graph().compile().unwrap();
    let mut rng = Rng(99);
    for _ in 0..20 {
        let (x, u) = random_nl_state(&mut rng);
        check_jacobian(&m, &x, &u);
    }
}

#[test]
fn power_balance_holds_at_random_states() {
    let mut rng = Rng(2024);
    let nl = nonlinear_graph().compile().unwrap();
    let lin = msd(2.0, 0.01, 3.0, true).compile().unwrap();
    for _ in 0..20 {
        let (x, u) = random_nl_state(&mut rng);
        check_power(&nl, &x, &u);
        let x2 = [rng.sym(5.0), rng.sym(0.1)];
        check_power(&lin, &x2, &[rng.sym(10.0)]);
    }
}

// ---------------------------------------------------------------- helpers

/// Exact Jacobian against Richardson-extrapolated central differences, 1e-7 relative.
fn check_jacobian(m: &CompiledModel, x: &[f64], u: &[f64]) {
    let n = m.n_states();
    let mut jac = DMatrix::zeros(n, n);
    m.jacobian(x, u, &mut jac);
    let f = |xx: &[f64]| {
        let mut d = vec![0.0; n];
        m.derivatives(xx, u, &mut d);
        d
    };
    let f0 = f(x);
    for j in 0..n {
        let h = 1e-3 * x[j].abs().max(1e-12);
        let cd = |h: f64| {
            let mut xp = x.to_vec();
            let mut xm = x.to_vec();
            xp[j] += h;
            xm[j] -= h;
            let (fp, fm) = (f(&xp), f(&xm));
            (0..n)
                .map(|i| (fp[i] - fm[i]) / (2.0 * h))
                .collect::<Vec<_>>()
        };
        let (d1, d2) = (cd(h), cd(h / 2.0));
        for i in 0..n {
            let fd = (4.0 * d2[i] - d1[i]) / 3.0;
            // scale: size of the contributions to f_i, to judge cancellation
            let scale = jac
                .row(i)
                .iter()
                .zip(x)
                .map(|(a, b)| (a * b).abs())
                .sum::<f64>()
                / x[j].abs().max(1e-300)
                + f0[i].abs() / x[j].abs().max(1e-300) * 1e-3;
            assert!(
                (fd - jac[(i, j)]).abs() <= 1e-7 * jac[(i, j)].abs().max(1e-6 * scale),
                "J[{i},{j}]: exact {:e}, finite differences {:e} (states {:?})",
                jac[(i, j)],
                fd,
                m.state_names()
            );
        }
    }
    // linearize agrees with jacobian
    let lin = m.linearize(x, u);
    assert_eq!(lin.a, jac);
}

/// dE/dt = P_sources - P_dissipated, both from the power terms and from finite differences of
/// the stored energy along the trajectory.
fn check_power(m: &CompiledModel, x: &[f64], u: &[f64]) {
    let pb = m.power_balance(x, u);
    let size = pb.stored_rate.abs() + pb.source_power.abs() + pb.dissipated_power.abs();
    assert!(
        pb.residual.abs() <= 1e-12 * size,
        "residual {:e} vs {:e}: {pb:?}",
        pb.residual,
        size
    );
    assert!(pb.dissipated_power >= -1e-12 * size, "{pb:?}");
    let n = m.n_states();
    let mut dx = vec![0.0; n];
    m.derivatives(x, u, &mut dx);
    let e = |t: f64| {
        let xx: Vec<f64> = x.iter().zip(&dx).map(|(a, b)| a + t * b).collect();
        m.stored_energy(&xx)
    };
    let xs = x
        .iter()
        .zip(&dx)
        .map(|(a, b)| (a / b).abs())
        .fold(f64::INFINITY, f64::min);
    let h = 1e-4 * xs.min(1.0);
    let rate = (8.0 * (e(h) - e(-h)) - (e(2.0 * h) - e(-2.0 * h))) / (12.0 * h);
    let scale = pb
        .elements
        .iter()
        .map(|(_, p)| p.abs())
        .sum::<f64>()
        .max(1e-300);
    assert!(
        (rate - pb.stored_rate).abs() <= 1e-6 * scale,
        "dE/dt by differences {rate:e} vs {:e}",
        pb.stored_rate
    );
}

// ---------------------------------------------------------------- misc

#[test]
fn compiled_model_is_send_sync_clone() {
    fn assert_traits<T: Send + Sync + Clone + std::fmt::Debug>() {}
    assert_traits::<CompiledModel>();
    assert_traits::<BondGraph>();
    let m = nonlinear_graph().compile().unwrap();
    let m2 = m.clone();
    let h = std::thread::spawn(move || {
        let mut dx = vec![0.0; m2.n_states()];
        m2.derivatives(&[1e-5, 0.1, 0.0], &[1e7, 1.0, 8e-5], &mut dx);
        dx
    });
    let mut dx = vec![0.0; m.n_states()];
    m.derivatives(&[1e-5, 0.1, 0.0], &[1e7, 1.0, 8e-5], &mut dx);
    assert_eq!(h.join().unwrap(), dx);
}

#[test]
fn dot_export_shows_names_and_causal_strokes() {
    let g = motor_chain(&[0.5, 100.0, 0.1, 1e-3, 1e-4, 5.0, 1e-2], false);
    let dot = g.to_dot();
    assert!(dot.starts_with("digraph \"motor\""));
    for n in [
        "GY: k",
        "TF: n",
        "C: shaft",
        "I: J",
        "tee",
        "lnormal",
        "current->L",
    ] {
        assert!(dot.contains(n), "missing {n} in\n{dot}");
    }
    // one edge line per bond
    assert_eq!(dot.matches("dir=both").count(), g.bonds().len());
}

#[test]
fn outputs_of_any_effort_flow_state_and_signal() {
    let g = nonlinear_graph();
    let m = g.compile().unwrap();
    assert_eq!(m.output_names(), ["theta", "wq", "p_chamber"]);
    let x = [2e-5, 0.3, 0.7];
    let u = [1e7, 1.0, 8e-5];
    let mut y = [0.0; 3];
    m.outputs(&x, &u, &mut y);
    assert_eq!(y[0], 0.7);
    let w = 0.3 / 0.01 + 0.1 * 0.027;
    assert!(close(y[1], w * 2e-5, 1e-14, 0.0));
    let p = 2e-5 / 1e-11 + 1e30 * 8e-15;
    assert!(close(y[2], p, 1e-14, 0.0));
    let mut e = vec![0.0; g.bonds().len()];
    let mut f = vec![0.0; g.bonds().len()];
    m.bond_values(&x, &u, &mut e, &mut f);
    assert_eq!(e[0], 1e7);
}

#[test]
fn causal_strokes_of_the_mass_spring_damper() {
    // bonds: force->v, v->mass, v->spring, v->damper
    let m = msd(1.0, 1.0, 1.0, false).compile().unwrap();
    // Se imposes the effort on the junction (stroke at the junction, the head); the mass
    // receives the effort (head); the spring imposes it (tail); the damper receives the flow
    // (junction imposes flow, R computes effort: stroke at the junction, the tail).
    assert_eq!(m.causal_strokes(), [true, true, false, false]);
}

#[test]
fn two_flow_sources_on_a_one_junction_conflict() {
    let mut g = BondGraph::new("conflict");
    let s1 = g.add_sf("Q1", 1.0);
    let s2 = g.add_sf("Q2", 2.0);
    let j = g.add_one("J");
    let i = g.add_i("I", 1.0);
    g.bond(s1, j);
    g.bond(s2, j);
    g.bond(j, i);
    let err = g.compile().unwrap_err();
    assert!(
        matches!(err, BondGraphError::CausalConflict { .. }),
        "{err:?}"
    );
    let msg = err.to_string();
    assert!(
        msg.contains("'J'") && msg.contains("'Q1'") && msg.contains("'Q2'"),
        "{msg}"
    );
}

#[test]
fn effort_source_on_a_capacitor_is_derivative_causality() {
    let mut g = BondGraph::new("se_c");
    let se = g.add_se("E", 1.0);
    let c = g.add_c("C", 1.0);
    g.bond(se, c);
    match g.compile().unwrap_err() {
        BondGraphError::DerivativeCausality { element, forced_by } => {
            assert_eq!(element, "C");
            assert_eq!(forced_by, ["E"]);
        }
        e => panic!("{e:?}"),
    }
}
