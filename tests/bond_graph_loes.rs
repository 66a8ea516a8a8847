//! The LOES of Fig. 3 against eq. 1 and the identified G_est of eq. 2.

use hydraulic_slewing_plate::bond_graph::CompiledModel;
use hydraulic_slewing_plate::eigen;
use hydraulic_slewing_plate::fragments::controller::ControllerParameters;
use hydraulic_slewing_plate::fragments::loes::{self, LoesParameters};
use nalgebra::{Complex, DMatrix};

/// Eq. 1 of the paper, written out by hand.
fn eq1(p: &LoesParameters, c: &ControllerParameters) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
    let k = p.k_sv * c.a1 * c.a2;
    let a = DMatrix::from_row_slice(
        3,
        3,
        &[
            0.0,
            1.0 / p.i_b,
            0.0,
            0.0,
            0.0,
            p.d_m / p.c3,
            -k * c.k_pot,
            -p.d_m / p.i_b,
            -1.0 / (p.r7 * p.c3),
        ],
    );
    let b = DMatrix::from_row_slice(3, 1, &[0.0, 0.0, k]);
    let cm = DMatrix::from_row_slice(1, 3, &[c.k_pot, 0.0, 0.0]);
    (a, b, cm)
}

fn assert_close(got: &DMatrix<f64>, want: &DMatrix<f64>, rel: f64, what: &str) {
    assert_eq!(got.shape(), want.shape(), "{what} shape");
    for i in 0..got.nrows() {
        for j in 0..got.ncols() {
            let (g, w) = (got[(i, j)], want[(i, j)]);
            assert!(
                (g - w).abs() <= rel * w.abs(),
                "{what}[{i},{j}]: got {g:e}, want {w:e}\n{got}\n{want}"
            );
        }
    }
}

fn compile_loop(p: &LoesParameters, c: &ControllerParameters) -> CompiledModel {
    loes::build_loop(p, c).compile().expect("LOES compiles")
}

fn check_eq1(p: &LoesParameters, c: &ControllerParameters) {
    let m = compile_loop(p, c);
    assert_eq!(m.state_names(), ["loes.theta_a", "loes.I_b.p", "loes.C3.q"]);
    assert_eq!(m.input_names(), ["r"]);
    assert_eq!(
        m.output_names(),
        ["y_pot", "theta_motor", "omega_motor", "p_load", "q_valve"]
    );
    let lin = m.linearize(&[0.0; 3], &[0.0]);
    let (a, b, cm) = eq1(p, c);
    let (a2, b2, c2) = loes::eq1_matrices(p, c);
    assert_eq!((&a2, &b2, &c2), (&a, &b, &cm));
    assert_close(&lin.a, &a, 1e-14, "A");
    assert_close(&lin.b, &b, 1e-14, "B");
    assert_close(&lin.c.rows(0, 1).into_owned(), &cm, 1e-14, "C");
    // D: only q_valve = k_sv A1 A2 (r - k_POT theta_a) feeds through.
    assert_eq!(lin.d.rows(0, 4).amax(), 0.0, "D");
    assert!((lin.d[(4, 0)] - b[2]).abs() <= 1e-14 * b[2], "D q_valve");
    // The model is linear: the linearisation is the same anywhere.
    let lin2 = m.linearize(&[0.3, -1e-3, 2e-7], &[1.5]);
    assert_close(&lin2.a, &a, 1e-14, "A at another point");
    // f(x, u) = A x + B u
    let (x, u) = ([0.2, 3e-4, -1e-8], [0.7]);
    let mut dx = [0.0; 3];
    m.derivatives(&x, &u, &mut dx);
    let want = &a * DMatrix::from_column_slice(3, 1, &x) + &b * u[0];
    let scale = [
        (a[(0, 1)] * x[1]).abs(),
        (a[(1, 2)] * x[2]).abs(),
        (a[(2, 0)] * x[0]).abs()
            + (a[(2, 1)] * x[1]).abs()
            + (a[(2, 2)] * x[2]).abs()
            + (b[2] * u[0]).abs(),
    ];
    for i in 0..3 {
        assert!(
            (dx[i] - want[i]).abs() <= 1e-13 * scale[i],
            "dx[{i}] {} vs {}",
            dx[i],
            want[i]
        );
    }
    // outputs
    let mut y = [0.0; 5];
    m.outputs(&x, &u, &mut y);
    let k = p.k_sv * c.a1 * c.a2;
    let want_y = [
        c.k_pot * x[0],
        x[0],
        x[1] / p.i_b,
        x[2] / p.c3,
        k * (u[0] - c.k_pot * x[0]),
    ];
    for i in 0..5 {
        assert!(
            (y[i] - want_y[i]).abs() <= 1e-13 * want_y[i].abs(),
            "output {} got {} want {}",
            m.output_names()[i],
            y[i],
            want_y[i]
        );
    }
}

#[test]
fn loes_graph_gives_eq1_default() {
    check_eq1(&LoesParameters::default(), &ControllerParameters::linear());
}

#[test]
fn loes_graph_gives_eq1_paper_printed() {
    check_eq1(
        &LoesParameters::paper_printed(),
        &ControllerParameters::linear(),
    );
}

#[test]
fn loes_graph_gives_eq1_random_parameters() {
    // xorshift, reproducible
    let mut s: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut rnd = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..50 {
        let mut f = |v: f64| v * 10f64.powf(2.0 * rnd() - 1.0);
        let p = LoesParameters {
            c3: f(5.28e-11),
            i_b: f(0.0025),
            r7: f(3.8e7),
            d_m: f(8e-5),
            k_sv: f(4.8e-5),
        };
        let c = ControllerParameters {
            a1: f(2.0),
            a2: f(10.0),
            k_pot: f(3.8),
            ..ControllerParameters::linear()
        };
        check_eq1(&p, &c);
    }
}

fn sorted_eigs(a: &DMatrix<f64>) -> Vec<Complex<f64>> {
    let mut e = eigen::eigenvalues(a);
    e.sort_by(|x, y| {
        x.re.partial_cmp(&y.re)
            .unwrap()
            .then(x.im.partial_cmp(&y.im).unwrap())
    });
    e
}

#[test]
fn default_open_loop_is_g_est() {
    let m = loes::build_open_loop(&LoesParameters::default(), &ControllerParameters::linear())
        .compile()
        .unwrap();
    let lin = m.linearize(&[0.0; 3], &[0.0]);
    let e = sorted_eigs(&lin.a);
    println!("open-loop poles: {e:?}");
    let want = [-753.0, -65.0, 0.0];
    for (g, w) in e.iter().zip(want) {
        assert!(
            (g.re - w).abs() < 1e-9 * 753.0 && g.im.abs() < 1e-9,
            "pole {g} vs {w}"
        );
    }
    // G(s) = C (sI - A)^-1 B = CB/s + CAB/s^2 + CA^2B/s^3 + ...; for K/(s(s+a)(s+b)):
    // CB = CAB = 0 and the gain K = C A^2 B.
    let c = lin.c.rows(0, 1).into_owned();
    let cb = (&c * &lin.b)[0];
    let cab = (&c * &lin.a * &lin.b)[0];
    let gain = (&c * &lin.a * &lin.a * &lin.b)[0];
    println!("open-loop gain C A^2 B = {gain}");
    assert_eq!(cb, 0.0);
    assert_eq!(cab, 0.0);
    assert!((gain - 2.25e6).abs() < 1e-9 * 2.25e6, "gain {gain}");
    // and the frequency response at s = j 100 against K / (s (s+65) (s+753))
    let s = Complex::new(0.0, 100.0);
    let n = 3;
    let mut si_a = DMatrix::<Complex<f64>>::zeros(n, n);
    for i in 0..n {
        for j in 0..n {
            si_a[(i, j)] = Complex::new(-lin.a[(i, j)], 0.0);
        }
        si_a[(i, i)] += s;
    }
    let bc = lin.b.map(|v| Complex::new(v, 0.0));
    let x = si_a.lu().solve(&bc).unwrap();
    let g: Complex<f64> = (0..n).map(|i| x[i] * lin.c[(0, i)]).sum();
    let want = Complex::new(2.25e6, 0.0) / (s * (s + 65.0) * (s + 753.0));
    assert!(
        (g - want).norm() < 1e-10 * want.norm(),
        "G(j100) {g} vs {want}"
    );
}

#[test]
fn default_closed_loop_poles() {
    let m = compile_loop(&LoesParameters::default(), &ControllerParameters::linear());
    let lin = m.linearize(&[0.0; 3], &[0.0]);
    let e = sorted_eigs(&lin.a);
    println!("closed-loop poles: {e:?}");
    assert!(
        (e[0].re + 757.29).abs() < 5e-3 && e[0].im.abs() < 1e-9,
        "{}",
        e[0]
    );
    for (k, sign) in [(1, -1.0), (2, 1.0)] {
        assert!((e[k].re + 30.354).abs() < 5e-4, "{}", e[k]);
        assert!((e[k].im - sign * 45.274).abs() < 5e-4, "{}", e[k]);
    }
    // product of the poles = -2.25e6 (characteristic polynomial s^3 + 818 s^2 + 48945 s + 2.25e6)
    let prod = e.iter().fold(Complex::new(1.0, 0.0), |a, b| a * b);
    assert!((prod.re + 2.25e6).abs() < 1e-6 * 2.25e6 && prod.im.abs() < 1e-3);
    // static gain from r to y_pot is 1 (type-1 loop)
    let dc = -(lin.c.rows(0, 1) * lin.a.clone().try_inverse().unwrap() * &lin.b)[0];
    assert!((dc - 1.0).abs() < 1e-12, "dc gain {dc}");
}

#[test]
fn paper_printed_open_loop_poles() {
    let m = loes::build_open_loop(
        &LoesParameters::paper_printed(),
        &ControllerParameters::linear(),
    )
    .compile()
    .unwrap();
    let e = sorted_eigs(&m.linearize(&[0.0; 3], &[0.0]).a);
    println!("paper-printed open-loop poles: {e:?}");
    // s^2 + s/(R7 C3) + D_m^2/(C3 I_b) = s^2 + 498.4 s + 48945: about -364 and -135
    // (docs/model-notes.md, item 7)
    assert!((e[0].re + 364.0).abs() < 1.0 && (e[1].re + 135.0).abs() < 1.0);
}

#[test]
fn default_parameters_match_model_notes() {
    let p = LoesParameters::default();
    let c = ControllerParameters::linear();
    assert!((p.r7 - 2.315e7).abs() < 1e-3 * 2.315e7, "{}", p.r7);
    assert!((p.d_m - 8.038e-5).abs() < 1e-3 * 8.038e-5, "{}", p.d_m);
    assert!((p.k_sv - 4.84e-5).abs() < 1e-3 * 4.84e-5, "{}", p.k_sv);
    assert!((p.k_sv * c.k_pot - 1.8475e-4).abs() < 1e-3 * 1.8475e-4);
    assert!((c.k_pot - 3.8197).abs() < 1e-4);
    assert_eq!(LoesParameters::paper_printed().r7, 3.8e7);
    assert_eq!(
        LoesParameters::by_name("paper_printed"),
        Some(LoesParameters::paper_printed())
    );
}

#[test]
fn loes_power_balance_and_jacobian() {
    let m = compile_loop(&LoesParameters::default(), &ControllerParameters::linear());
    let mut s: u64 = 0xDEAD_BEEF_CAFE_F00D;
    let mut rnd = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    for _ in 0..20 {
        let x = [rnd(), 0.05 * rnd(), 1e-3 * 5.28e-11 * 1e7 * rnd()];
        let u = [5.0 * rnd()];
        let pb = m.power_balance(&x, &u);
        let size = pb.stored_rate.abs() + pb.source_power.abs() + pb.dissipated_power.abs();
        assert!(pb.residual.abs() <= 1e-13 * size, "{pb:?}");
        let names: Vec<&str> = pb.elements.iter().map(|e| e.0.as_str()).collect();
        assert_eq!(names, ["loes.I_b", "loes.C3", "loes.valve", "loes.R7"]);
        // the valve delivers Q p3, the leakage dissipates p3^2 / R7
        let p = LoesParameters::default();
        let p3 = x[2] / p.c3;
        assert!((pb.dissipated_power - p3 * p3 / p.r7).abs() <= 1e-13 * pb.dissipated_power);
        let mut y = [0.0; 5];
        m.outputs(&x, &u, &mut y);
        assert!((pb.source_power - y[4] * y[3]).abs() <= 1e-13 * pb.source_power.abs());
        let (mut dx1, mut dx2, mut y2) = ([0.0; 3], [0.0; 3], [0.0; 5]);
        m.derivatives(&x, &u, &mut dx1);
        m.evaluate(&x, &u, &mut dx2, &mut y2);
        assert_eq!((dx1, y), (dx2, y2));
        let mut jac = DMatrix::zeros(3, 3);
        m.jacobian(&x, &u, &mut jac);
        assert_eq!(jac, m.linearize(&x, &u).a);
    }
    let json = m.linearize(&[0.0; 3], &[0.0]).to_json();
    assert_eq!(json["states"][0], "loes.theta_a");
    assert_eq!(json["A"].as_array().unwrap().len(), 3);
}

#[test]
fn loes_rotor_junction_accepts_a_torsion_bar_and_hub() {
    // Preview of issue 5: motor rotor -> torsion bar C -> hub inertia, bonded onto the LOES
    // rotor 1-junction.
    use hydraulic_slewing_plate::bond_graph::BondGraph;
    use hydraulic_slewing_plate::fragments::controller;
    let mut g = BondGraph::new("coupled");
    let r = g.add_input("r");
    let l = loes::add_loes(&mut g, "loes", &LoesParameters::default());
    let c = controller::add_controller(
        &mut g,
        "controller",
        &ControllerParameters::linear(),
        r,
        l.theta,
        l.p_load,
    );
    g.connect_signal_port(l.valve_command, c.command);
    let shaft = g.add_zero("shaft.torque");
    let k_bar = g.add_c("shaft.K", 1.0 / 2.5e3);
    let hub_j = g.add_one("hub.omega");
    let hub = g.add_i("hub.I", 3.5);
    g.bond(l.rotor, shaft);
    g.bond(shaft, k_bar);
    g.bond(shaft, hub_j);
    g.bond(hub_j, hub);
    let m = g.compile().unwrap();
    assert_eq!(
        m.state_names(),
        [
            "loes.theta_a",
            "loes.I_b.p",
            "loes.C3.q",
            "shaft.K.q",
            "hub.I.p"
        ]
    );
    // still a stable closed loop
    let a = m.linearize(&[0.0; 5], &[0.0]).a;
    for e in eigen::eigenvalues(&a) {
        assert!(e.re < 0.0, "{e}");
    }
    let dot = g.to_dot();
    assert!(dot.contains("loes.rotor->shaft.torque"));
}

#[test]
fn loes_dot_export() {
    let g = loes::build_loop(&LoesParameters::default(), &ControllerParameters::linear());
    let dot = g.to_dot();
    for n in [
        "C: loes.C3",
        "I: loes.I_b",
        "R: loes.R7",
        "TF: loes.D_m",
        "MSf: loes.valve",
        "gain controller.A1",
        "integrator loes.theta_a",
        "teelnormal",
    ] {
        assert!(dot.contains(n), "missing {n}:\n{dot}");
    }
}

#[test]
fn loes_plan_listing_reads_like_eq1() {
    let m = compile_loop(&LoesParameters::default(), &ControllerParameters::linear());
    let text = m.plan_listing();
    println!("{text}");
    for line in [
        "d(loes.theta_a)/dt = loes.omega",
        "d(loes.I_b.p)/dt = e(loes.rotor->loes.I_b)",
        "d(loes.C3.q)/dt = f(loes.chamber->loes.C3)",
    ] {
        assert!(text.contains(line), "missing {line}");
    }
    assert!(text.lines().count() >= m.plan_len());
}

#[test]
fn loes_bad_parameter_is_named() {
    let p = LoesParameters {
        c3: -1e-11,
        ..LoesParameters::default()
    };
    let err = loes::build_loop(&p, &ControllerParameters::linear())
        .compile()
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        "element 'loes.C3': capacitance must be positive and finite, got -1e-11"
    );
    let p = LoesParameters {
        i_b: f64::INFINITY,
        ..LoesParameters::default()
    };
    let err = loes::build_loop(&p, &ControllerParameters::linear())
        .compile()
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        "element 'loes.I_b': inertance must be positive and finite, got inf"
    );
}
