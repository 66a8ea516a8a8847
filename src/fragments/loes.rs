//! The low-order equivalent system (LOES) of the hydraulic actuation loop: Fig. 3 and eq. 1 of
//! the paper.
//!
//! Bond graph (power flows left to right):
//!
//! ```text
//!   MSf ---> 0 (p3) ---> TF D_m ---> 1 (omega) ---> I_b
//!  Q_valve   |  \                     rotor
//!            v   v
//!           C3   R7
//! ```
//!
//! * `MSf` `<prefix>.valve`: valve flow `Q = k_sv e_in` \[m^3/s\], modulated by the valve command
//!   `e_in` \[V\] (in the closed loop `e_in = A2 A1 (r - k_POT theta_a)`);
//! * 0-junction `<prefix>.chamber`: the load pressure `p3` \[Pa\]; C3 `<prefix>.C3` (chamber
//!   compressibility, state `q_3` \[m^3\], `p3 = q3 / C3`) and R7 `<prefix>.R7` (leakage,
//!   `Q_leak = p3 / R7`);
//! * TF `<prefix>.D_m`: vane motor displacement, torque `= D_m p3`, `Q_motor = D_m omega`;
//! * 1-junction `<prefix>.rotor`: rotor speed `omega` \[rad/s\]; I `<prefix>.I_b` (rotor inertia,
//!   state `p_b` \[N m s\] = `I_b omega`);
//! * the rotor angle `theta_a` \[rad\] is the integral of `omega` (integrator `<prefix>.theta_a`).
//!
//! The states are, in this order, `theta_a` (`<prefix>.theta_a`), `p_b` (`<prefix>.I_b.p`),
//! `q_3` (`<prefix>.C3.q`), those of eq. 1, and the graph yields exactly eq. 1:
//!
//! ```text
//! d theta_a/dt = p_b / I_b
//! d p_b/dt     = D_m q_3 / C3
//! d q_3/dt     = -k_sv A1 A2 k_POT theta_a - D_m p_b / I_b - q_3 / (R7 C3) + k_sv A1 A2 r
//! y_POT        = k_POT theta_a
//! ```

use nalgebra::DMatrix;

use crate::bond_graph::{BondGraph, BondId, Domain, ElementId, SignalId};
use crate::math::dual::Dual;

use super::controller::{self, ControllerParameters};

/// Gain of the identified open-loop transfer function `G_est(s) = K / (s (s + a) (s + b))`,
/// eq. 2 of the paper \[V/V / s^3\].
pub const G_EST_GAIN: f64 = 2.25e6;
/// First real pole of `G_est` \[rad/s\] (eq. 2: `s + 65`).
pub const G_EST_POLE_1: f64 = 65.0;
/// Second real pole of `G_est` \[rad/s\] (eq. 2: `s + 753`).
pub const G_EST_POLE_2: f64 = 753.0;
/// Chamber capacitance printed in the paper \[m^5/N\].
pub const PRINTED_C3: f64 = 5.28e-11;
/// Rotor inertia printed in the paper \[kg m^2\] (printed as "I_6", read I_b).
pub const PRINTED_I_B: f64 = 0.0025;
/// Leakage resistance printed in the paper \[N s/m^5\] (inconsistent with `G_est`, see
/// docs/model-notes.md, item 7).
pub const PRINTED_R7: f64 = 3.8e7;

/// Physical parameters of the LOES (SI units).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LoesParameters<S = f64> {
    /// Chamber capacitance `C3` \[m^5/N\].
    pub c3: S,
    /// Rotor inertia `I_b` \[kg m^2\].
    pub i_b: S,
    /// Leakage resistance `R7` \[N s/m^5\].
    pub r7: S,
    /// Vane motor displacement `D_m` \[m^3/rad\].
    pub d_m: S,
    /// Valve flow gain `k_sv` \[m^3/(s V)\].
    pub k_sv: S,
}

impl<S: Copy> LoesParameters<S> {
    /// The parameters `f(self, other)` field by field, the others (choices, counts) `self`'s:
    /// the one list of the real fields, for carrying them in another scalar (a value and its
    /// derivative, [`crate::math::dual::Dual`]).
    pub fn zip<T: Copy, U>(
        &self,
        other: &LoesParameters<T>,
        f: impl Fn(S, T) -> U,
    ) -> LoesParameters<U> {
        LoesParameters {
            c3: f(self.c3, other.c3),
            i_b: f(self.i_b, other.i_b),
            r7: f(self.r7, other.r7),
            d_m: f(self.d_m, other.d_m),
            k_sv: f(self.k_sv, other.k_sv),
        }
    }

    /// The parameters `f(self)` field by field ([`LoesParameters::zip`]).
    pub fn map<U>(&self, f: impl Fn(S) -> U) -> LoesParameters<U> {
        self.zip(self, |a, _| f(a))
    }
}

impl Default for LoesParameters {
    /// The `G(s)`-consistent set (docs/model-notes.md, item 7), derived from `G_est` with the
    /// default controller gains: see [`LoesParameters::from_g_est`].
    fn default() -> Self {
        Self::from_g_est(&ControllerParameters::default())
    }
}

impl LoesParameters {
    /// Parameters reproducing the identified `G_est(s) = 2.25e6 / (s (s + 65) (s + 753))`
    /// (eq. 2) exactly, given the controller gains.
    ///
    /// From eq. 1 the direct path is
    /// `G(s) = k_POT A1 A2 k_sv (D_m / (C3 I_b)) / (s (s^2 + s / (R7 C3) + D_m^2 / (C3 I_b)))`,
    /// so with `(s + 65)(s + 753) = s^2 + 818 s + 48945`:
    /// * keep the printed `C3 = 5.28e-11` and `I_b = 0.0025`;
    /// * `R7 = 1 / (818 C3)` = 2.3153e7 N s/m^5 (the printed 3.8e7 would put the poles at 135
    ///   and 364 rad/s);
    /// * `D_m = sqrt(48945 C3 I_b)` = 8.0379e-5 m^3/rad;
    /// * `k_sv = 2.25e6 C3 I_b / (A1 A2 D_m k_POT)` = 4.8367e-5 m^3/(s V) with the default
    ///   `A1 = 2`, `A2 = 10`, `k_POT = 10 V / 150 deg`.
    pub fn from_g_est(ctrl: &ControllerParameters) -> Self {
        Self::from_transfer_function(
            G_EST_GAIN,
            G_EST_POLE_1,
            G_EST_POLE_2,
            PRINTED_C3,
            PRINTED_I_B,
            ctrl,
        )
    }

    /// Parameters giving `G(s) = gain / (s (s + a) (s + b))` for given `C3`, `I_b` and
    /// controller gains (the derivation of [`LoesParameters::from_g_est`]).
    pub fn from_transfer_function(
        gain: f64,
        a: f64,
        b: f64,
        c3: f64,
        i_b: f64,
        ctrl: &ControllerParameters,
    ) -> Self {
        let r7 = 1.0 / ((a + b) * c3);
        let d_m = (a * b * c3 * i_b).sqrt();
        let k_sv = gain * c3 * i_b / (ctrl.a1 * ctrl.a2 * d_m * ctrl.k_pot);
        LoesParameters {
            c3,
            i_b,
            r7,
            d_m,
            k_sv,
        }
    }

    /// The set printed in the paper: `C3 = 5.28e-11`, `I_b = 0.0025`, `R7 = 3.8e7`. The paper
    /// prints neither `D_m` nor `k_sv`; they are taken from the `G(s)`-consistent set
    /// (docs/model-notes.md, item 7: `D_m` = 8.038e-5 m^3/rad, `k_sv` = 4.84e-5 m^3/(s V)).
    /// With this set the open-loop poles are at 0, -135 and -364 rad/s, not those of `G_est`.
    pub fn paper_printed() -> Self {
        LoesParameters {
            r7: PRINTED_R7,
            ..Self::default()
        }
    }

    /// A named set: "default" / "g_est" (the `G(s)`-consistent set) or "paper_printed".
    pub fn by_name(name: &str) -> Option<Self> {
        match name {
            "default" | "g_est" | "consistent" => Some(Self::default()),
            "paper_printed" | "paper" | "printed" => Some(Self::paper_printed()),
            _ => None,
        }
    }
}

/// Eq. 1 of the paper written out: `(A, B, C)` of the closed loop with states
/// `(theta_a, p_b, q_3)`, input `r` and output `y_POT`. The graph built by [`build_loop`] yields
/// exactly these matrices; this function is for checks and reports, not used to build the model.
pub fn eq1_matrices(
    p: &LoesParameters,
    c: &ControllerParameters,
) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
    let k = p.k_sv * c.a1 * c.a2;
    #[rustfmt::skip]
    let a = DMatrix::from_row_slice(3, 3, &[
        0.0, 1.0 / p.i_b, 0.0,
        0.0, 0.0, p.d_m / p.c3,
        -k * c.k_pot, -p.d_m / p.i_b, -1.0 / (p.r7 * p.c3),
    ]);
    let b = DMatrix::from_row_slice(3, 1, &[0.0, 0.0, k]);
    let cm = DMatrix::from_row_slice(1, 3, &[c.k_pot, 0.0, 0.0]);
    (a, b, cm)
}

/// Handles into the LOES fragment, for bonding and wiring other fragments onto it.
#[derive(Clone, Copy, Debug)]
pub struct LoesPorts {
    /// The rotor 1-junction `<prefix>.rotor` (common flow: rotor speed). Bond a torsion bar
    /// (a C between this junction and the hub inertia) onto it.
    pub rotor: ElementId,
    /// The chamber 0-junction `<prefix>.chamber` (common effort: load pressure `p3`).
    pub chamber: ElementId,
    /// The valve flow source `<prefix>.valve` (MSf).
    pub valve: ElementId,
    /// The chamber capacitance `<prefix>.C3`.
    pub c3: ElementId,
    /// The leakage resistance `<prefix>.R7`.
    pub r7: ElementId,
    /// The motor transformer `<prefix>.D_m`.
    pub d_m: ElementId,
    /// The rotor inertia `<prefix>.I_b`.
    pub i_b: ElementId,
    /// Bond valve -> chamber (its flow is the valve flow).
    pub valve_bond: BondId,
    /// Bond chamber -> C3 (its effort is the load pressure).
    pub c3_bond: BondId,
    /// Bond rotor -> I_b (its flow is the rotor speed).
    pub i_b_bond: BondId,
    /// Input signal port `<prefix>.valve_command`: the valve command voltage `e_in` \[V\]. Must be
    /// connected with [`BondGraph::connect_signal_port`].
    pub valve_command: SignalId,
    /// Rotor angle `theta_a` \[rad\] (integrator `<prefix>.theta_a`, a state).
    pub theta: SignalId,
    /// Rotor speed `omega` \[rad/s\] (`<prefix>.omega`).
    pub omega: SignalId,
    /// Load pressure `p3 = q3 / C3` \[Pa\] (`<prefix>.p_load`).
    pub p_load: SignalId,
    /// Valve flow `Q = k_sv e_in` \[m^3/s\] (`<prefix>.q_valve`).
    pub q_valve: SignalId,
}

/// Adds the LOES of Fig. 3 under `prefix` (e.g. "loes"). The valve command port is left
/// unconnected, to be wired to the controller output.
pub fn add_loes<S: Copy + Into<Dual>>(
    g: &mut BondGraph,
    prefix: &str,
    p: &LoesParameters<S>,
) -> LoesPorts {
    let p = p.map(Into::<Dual>::into);
    // Signals first so that theta_a is the first state, as in eq. 1.
    let omega = g.add_signal_port(format!("{prefix}.omega"));
    let theta = g.add_integrator(format!("{prefix}.theta_a"), omega);
    g.set_integrator_units(theta, Domain::Rotation.displacement());
    let valve_command = g.add_signal_port(format!("{prefix}.valve_command"));
    let flow_cmd = g.add_gain(format!("{prefix}.k_sv"), p.k_sv, valve_command);

    let valve = g.add_sf(format!("{prefix}.valve"), flow_cmd);
    let chamber = g.add_zero(format!("{prefix}.chamber"));
    let rotor = g.add_one(format!("{prefix}.rotor"));
    let d_m = g.add_tf(format!("{prefix}.D_m"), p.d_m);
    let i_b = g.add_i(format!("{prefix}.I_b"), p.i_b);
    let c3 = g.add_c(format!("{prefix}.C3"), p.c3);
    g.set_domains(i_b, &[Domain::Rotation]);
    g.set_domains(c3, &[Domain::Hydraulic]);
    let r7 = g.add_r(format!("{prefix}.R7"), p.r7);

    let valve_bond = g.bond(valve, chamber);
    let c3_bond = g.bond(chamber, c3);
    g.bond(chamber, r7);
    g.bond(chamber, d_m);
    g.bond(d_m, rotor);
    let i_b_bond = g.bond(rotor, i_b);

    let speed = g.add_flow_sensor(format!("{prefix}.omega_sensor"), i_b_bond);
    g.connect_signal_port(omega, speed);
    let p_load = g.add_effort_sensor(format!("{prefix}.p_load"), c3_bond);
    let q_valve = g.add_flow_sensor(format!("{prefix}.q_valve"), valve_bond);
    LoesPorts {
        rotor,
        chamber,
        valve,
        c3,
        r7,
        d_m,
        i_b,
        valve_bond,
        c3_bond,
        i_b_bond,
        valve_command,
        theta,
        omega,
        p_load,
        q_valve,
    }
}

/// The closed loop of eq. 1: reference input "r" \[V\], the LOES under "loes", the controller
/// under "controller"; states `loes.theta_a`, `loes.I_b.p`, `loes.C3.q`; outputs "y_pot" \[V\],
/// "theta_motor" \[rad\], "omega_motor" \[rad/s\], "p_load" \[Pa\], "q_valve" \[m^3/s\].
pub fn build_loop(loes: &LoesParameters, ctrl: &ControllerParameters) -> BondGraph {
    let mut g = BondGraph::new("loes_closed_loop");
    let r = g.add_input("r");
    let l = add_loes(&mut g, "loes", loes);
    let c = controller::add_controller(&mut g, "controller", ctrl, r, l.theta, l.p_load);
    g.connect_signal_port(l.valve_command, c.command);
    add_standard_outputs(&mut g, &l, c.y_pot);
    g
}

/// The open loop `G(s)` of eq. 2: input "e" (the error voltage `r - y_POT`) through `A1`, `A2`,
/// the LOES and the potentiometer; same outputs as [`build_loop`].
pub fn build_open_loop(loes: &LoesParameters, ctrl: &ControllerParameters) -> BondGraph {
    let mut g = BondGraph::new("loes_open_loop");
    let e = g.add_input("e");
    let l = add_loes(&mut g, "loes", loes);
    let (_, command) = controller::add_amplifiers(&mut g, "controller", ctrl, e, l.p_load);
    g.connect_signal_port(l.valve_command, command);
    let y_pot = controller::add_potentiometer(&mut g, "controller", ctrl, l.theta);
    add_standard_outputs(&mut g, &l, y_pot);
    g
}

fn add_standard_outputs(g: &mut BondGraph, l: &LoesPorts, y_pot: SignalId) {
    super::add_loop_outputs(g, y_pot, l.theta, l.omega, l.p_load, l.q_valve);
}
