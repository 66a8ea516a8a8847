//! BG3 of the paper (Fig. 2b): the power stage of the servo valve and the rotary vane actuator.
//!
//! ```text
//!   supply 0 --> 1 PA(x_v) --> 0 p_1 --> 1 AT(x_v) --> 0 tank
//!   supply 0 --> 1 PB(x_v) --> 0 p_2 --> 1 BT(x_v) --> 0 tank
//!   0 p_1 --> 1 leak --> 0 p_2        (R_leak, laminar internal leakage)
//!   0 p_1 --> 1 load --> 0 p_2 ;  1 load --> TF D_m --> 1 rotor (omega) --> I I_m, R b_m
//! ```
//!
//! * Four-way critical-centre spool: edges P->A and B->T open for `x_v > 0`, P->B and A->T for
//!   `x_v < 0`, each of area `w ramp(+-x_v, c_r)` with area gradient `w` and radial clearance
//!   `c_r` ([`super::orifice::smooth_ramp`]), through the regularised orifice law.
//! * Actuator chambers `<prefix>.chamber_1`, `<prefix>.chamber_2` (0-junctions) with
//!   compressibility `C = V_1 / beta` (states `<prefix>.C_1.q`, `<prefix>.C_2.q`) and the
//!   cavitation floor of [`super::servo_valve::limits::chamber`].
//! * Internal leakage across the vanes `<prefix>.R_leak` \[N s/m^5\] (laminar).
//! * The vane motor: TF `<prefix>.D_m` from the load 1-junction (pressure `p_1 - p_2`, flow
//!   through the motor) to the rotor 1-junction `<prefix>.rotor` (speed `omega`): torque
//!   `D_m (p_1 - p_2)`, swept flow `D_m omega`.
//! * Rotor inertia `I_m` (state `<prefix>.I_m.p` = angular momentum) and viscous friction `b_m`
//!   \[N m s/rad\].
//! * Seal friction `<prefix>.friction` (not in the paper; [`friction`]): a nonlinear R on the rotor
//!   junction with the running torque `T_c`, the breakaway torque `T_s` and the Stribeck speed
//!   `omega_s`, regularised near zero speed so the integrator sees a smooth law. Left out when
//!   `T_c = T_s = 0` (the paper's presets).
//!
//! The supply (`Se p_s`) and tank (`Se p_t`) are the 0-junctions passed in; they are shared with
//! the pilot stage (BG2). The torsion bar of the coupled model bonds onto the rotor junction.
//!
//! Sign conventions: `x_v > 0` fills chamber 1, `p_1 > p_2` turns the rotor positive; the metered
//! flow `q_valve` is the net flow into chamber 1 (P->A minus A->T).

use crate::bond_graph::{BondGraph, BondId, Domain, ElementId, Law, NonlinearLaw, SignalId};
use crate::math::dual::{Dual, HyperDual, Real};
use crate::math::{exp, tanh};

use super::flapper_nozzle::restriction;
use super::orifice::variable_orifice;
use super::servo_valve::{limits, ServoValveParameters};

/// Handles into the power stage and vane motor fragment.
#[derive(Clone, Copy, Debug)]
pub struct VaneMotorPorts {
    /// The rotor 1-junction `<prefix>.rotor` (common flow: rotor speed).
    pub rotor: ElementId,
    /// Chamber 1 0-junction (pressure `p_1`).
    pub chamber_1: ElementId,
    /// Chamber 2 0-junction (pressure `p_2`).
    pub chamber_2: ElementId,
    /// The rotor inertia `<prefix>.I_m`.
    pub i_m: ElementId,
    /// Bond rotor -> I_m (its flow is the rotor speed).
    pub i_m_bond: BondId,
    /// Chamber pressure `p_1` \[Pa\] (`<prefix>.p_1`).
    pub p_1: SignalId,
    /// Chamber pressure `p_2` \[Pa\] (`<prefix>.p_2`).
    pub p_2: SignalId,
    /// Load pressure `p_1 - p_2` \[Pa\] (`<prefix>.p_load`).
    pub p_load: SignalId,
    /// Net metered flow into chamber 1 \[m^3/s\] (`<prefix>.q_valve`).
    pub q_valve: SignalId,
    /// Rotor speed \[rad/s\] (`<prefix>.omega`).
    pub omega: SignalId,
    /// Bonds supply -> P->A and supply -> P->B junctions (main-stage supply flows).
    pub supply_bonds: [BondId; 2],
}

/// Adds BG3 under `prefix`, between `supply` and `tank`, with the spool position `x_v`.
pub fn add_vane_motor<S: Copy + Into<Dual>>(
    g: &mut BondGraph,
    prefix: &str,
    p: &ServoValveParameters<S>,
    supply: ElementId,
    tank: ElementId,
    x_v: SignalId,
) -> VaneMotorPorts {
    let p = &p.map(Into::<Dual>::into);
    let fluid = p.fluid();
    let chamber_1 = g.add_zero(format!("{prefix}.chamber_1"));
    let chamber_2 = g.add_zero(format!("{prefix}.chamber_2"));
    let c_1 = g.add_c(format!("{prefix}.C_1"), limits::chamber(p.v_1, p.beta));
    let c_2 = g.add_c(format!("{prefix}.C_2"), limits::chamber(p.v_1, p.beta));
    g.set_nominal(c_1, &[(p.v_1 / p.beta * p.p_supply).v]);
    g.set_nominal(c_2, &[(p.v_1 / p.beta * p.p_supply).v]);
    g.set_domains(c_1, &[Domain::Hydraulic]);
    g.set_domains(c_2, &[Domain::Hydraulic]);
    let c1_bond = g.bond(chamber_1, c_1);
    let c2_bond = g.bond(chamber_2, c_2);

    let edge = |g: &mut BondGraph, name: &str, sign: f64| -> ElementId {
        let law = variable_orifice(name, p.w, 0.0, sign, p.c_r, fluid);
        g.add_r_modulated(format!("{prefix}.{name}"), law, x_v)
    };
    let pa = edge(g, "R_PA", 1.0);
    let at = edge(g, "R_AT", -1.0);
    let pb = edge(g, "R_PB", -1.0);
    let bt = edge(g, "R_BT", 1.0);
    let (_, pa_bond) = restriction(g, &format!("{prefix}.R_PA"), supply, chamber_1, pa);
    let (_, at_bond) = restriction(g, &format!("{prefix}.R_AT"), chamber_1, tank, at);
    let (_, pb_bond) = restriction(g, &format!("{prefix}.R_PB"), supply, chamber_2, pb);
    restriction(g, &format!("{prefix}.R_BT"), chamber_2, tank, bt);

    let r_leak = g.add_r(format!("{prefix}.R_leak"), p.r_leak);
    restriction(g, &format!("{prefix}.R_leak"), chamber_1, chamber_2, r_leak);

    let load = g.add_one(format!("{prefix}.load"));
    g.bond(chamber_1, load);
    g.bond(load, chamber_2);
    let d_m = g.add_tf(format!("{prefix}.D_m"), p.d_m);
    let rotor = g.add_one(format!("{prefix}.rotor"));
    g.bond(load, d_m);
    g.bond(d_m, rotor);
    let i_m = g.add_i(format!("{prefix}.I_m"), p.i_m);
    let b_m = g.add_r(format!("{prefix}.b_m"), p.b_m);
    let i_m_bond = g.bond(rotor, i_m);
    g.bond(rotor, b_m);
    if p.t_s > 0.0 {
        let law = friction_law(p.t_c, p.t_s, p.omega_s);
        let r = g.add_r(format!("{prefix}.friction"), Law::Nonlinear(law));
        g.bond(rotor, r);
    }
    // The rotor's momentum at 1 rad/s: the speed of a slewing move (the default 30 deg in 2 s
    // peaks at 0.57 rad/s). 10 rad/s let an importer's BDF at rtol 1e-6 miss the rotor's speed
    // by 2e-4 of its range in that move (docs/model-exchange.md).
    g.set_nominal(i_m, &[p.i_m.v]);
    g.set_domains(i_m, &[Domain::Rotation]);

    let p_1 = g.add_effort_sensor(format!("{prefix}.p_1"), c1_bond);
    let p_2 = g.add_effort_sensor(format!("{prefix}.p_2"), c2_bond);
    let p_load = g.add_sum(format!("{prefix}.p_load"), &[(1.0, p_1), (-1.0, p_2)]);
    let q_pa = g.add_flow_sensor(format!("{prefix}.q_PA"), pa_bond);
    let q_at = g.add_flow_sensor(format!("{prefix}.q_AT"), at_bond);
    let q_valve = g.add_sum(format!("{prefix}.q_valve"), &[(1.0, q_pa), (-1.0, q_at)]);
    let omega = g.add_flow_sensor(format!("{prefix}.omega"), i_m_bond);
    VaneMotorPorts {
        rotor,
        chamber_1,
        chamber_2,
        i_m,
        i_m_bond,
        p_1,
        p_2,
        p_load,
        q_valve,
        omega,
        supply_bonds: [pa_bond, pb_bond],
    }
}

/// Speed of the regularisation as a fraction of the Stribeck speed: below `omega_s / 10` the
/// friction torque rises smoothly through zero (`tanh`) instead of jumping from `-T_s` to `T_s`.
pub const REGULARISATION: f64 = 0.1;

/// The value bound of [`friction`] ([`NonlinearLaw::with_value_bound`]): `|T| <= 2 max(|T_c|,
/// |T_s|)` whatever the speed. The Stribeck factor `exp(-u²)` lies in `[0, 1]`, so the bracket
/// lies between `T_c` and `T_s`, and `|tanh| <= 1`; the factor 2 covers rounding many times
/// over. Declared for `omega_s > 0` (at `omega_s` = 0 the law is 0/0 at rest) and finite
/// torques: `omega / omega_s` may overflow to ±inf, which `exp` and `tanh` take.
pub fn friction_bound(t_c: f64, t_s: f64, omega_s: f64) -> Option<(f64, f64)> {
    (omega_s > 0.0 && t_c.is_finite() && t_s.is_finite())
        .then_some((0.0, 2.0 * t_c.abs().max(t_s.abs())))
}

/// The seal friction torque of the rotor at speed `omega` and its derivative, `(T, dT/domega)`:
///
/// `T(omega) = [T_c + (T_s - T_c) exp(-(omega/omega_s)^2)] tanh(omega / omega_t)`,
/// `omega_t = REGULARISATION omega_s`.
///
/// The bracket is the Stribeck curve: the breakaway torque `T_s` at rest falls to the running
/// (Coulomb) torque `T_c` over a few `omega_s` (Armstrong-Hélouvry, Dupont and Canudas de Wit,
/// *Automatica* 30(7), 1994, the static part of their friction model). The `tanh` replaces the
/// sign function: a rotor held by less than `T_s` creeps at `omega_t atanh(T / T_s)` instead of
/// sticking, which keeps the right-hand side smooth for the implicit integrator at the price of
/// a creep speed below `omega_t` (0.05 rad/s with the defaults: 1.5 mm/s at the vane tips). The torque always opposes the
/// motion, so the element dissipates `T omega >= 0`.
pub fn friction(t_c: f64, t_s: f64, omega_s: f64, omega: f64) -> (f64, f64) {
    let omega_t = REGULARISATION * omega_s;
    let u = omega / omega_s;
    let stribeck = exp(-u * u);
    let level = t_c + (t_s - t_c) * stribeck;
    let slope = (t_s - t_c) * stribeck * (-2.0 * u / omega_s);
    let th = tanh(omega / omega_t);
    (level * th, slope * th + level * (1.0 - th * th) / omega_t)
}

/// The seal friction torque [`friction`]'s value in any [`Real`]: the same operations, so the
/// same doubles.
pub fn friction_value<S: Real>(t_c: S, t_s: S, omega_s: S, omega: S) -> S {
    let omega_t = omega_s * REGULARISATION;
    let u = omega / omega_s;
    let stribeck = S::exp(-u * u);
    let level = t_c + (t_s - t_c) * stribeck;
    level * S::tanh(omega / omega_t)
}

/// The seal friction `<prefix>.friction` as a law of the rotor speed: [`friction`], with its
/// value bound ([`friction_bound`]) and its hyper-dual form ([`NonlinearLaw::with_hyper`]),
/// [`friction_value`] with the constants' derivatives.
pub fn friction_law(
    t_c: impl Into<Dual>,
    t_s: impl Into<Dual>,
    omega_s: impl Into<Dual>,
) -> NonlinearLaw {
    let (t_c_d, t_s_d, omega_s_d) = (t_c.into(), t_s.into(), omega_s.into());
    let (t_c, t_s, omega_s) = (t_c_d.v, t_s_d.v, omega_s_d.v);
    NonlinearLaw::new(
        format!("seal friction, running {t_c} N m, breakaway {t_s} N m"),
        move |omega| friction(t_c, t_s, omega_s, omega),
    )
    .with_value_bound_if(friction_bound(t_c, t_s, omega_s))
    .with_hyper(move |omega, _| {
        let c = HyperDual::from;
        friction_value(c(t_c_d), c(t_s_d), c(omega_s_d), omega)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The law's values against its closed form at rest, in the Stribeck range and far above it,
    /// its derivative against a central difference, and its dissipation.
    #[test]
    fn friction_falls_from_breakaway_to_running_torque() {
        let (t_c, t_s, w_s) = (1.0, 1.5, 0.5);
        assert_eq!(friction(t_c, t_s, w_s, 0.0).0, 0.0);
        // far above the Stribeck speed: the running torque, with the sign of the motion
        let (t, _) = friction(t_c, t_s, w_s, 10.0 * w_s);
        assert!((t - t_c).abs() < 1e-12, "{t}");
        assert!((friction(t_c, t_s, w_s, -10.0 * w_s).0 + t_c).abs() < 1e-12);
        // at 3 omega_t: the closed form
        let w = 3.0 * REGULARISATION * w_s;
        let expect = (t_c + (t_s - t_c) * exp(-(w / w_s) * (w / w_s))) * tanh(3.0);
        assert!((friction(t_c, t_s, w_s, w).0 - expect).abs() < 1e-14);
        // the regularised breakaway: the largest torque, reached at about 2 omega_t, is within
        // 4 % of T_s (and never above it)
        let peak = (1..1000)
            .map(|i| friction(t_c, t_s, w_s, i as f64 * 1e-3 * w_s).0)
            .fold(0.0, f64::max);
        assert!(peak > 0.96 * t_s && peak <= t_s, "{peak}");
        for omega in [-0.3, -0.04, -1e-3, 1e-4, 0.002, 0.05, 0.2, 1.0] {
            let (t, d) = friction(t_c, t_s, w_s, omega);
            assert!(t * omega > 0.0, "dissipates at {omega}");
            let h = 1e-7 * omega.abs().max(1e-3);
            let fd = (friction(t_c, t_s, w_s, omega + h).0 - friction(t_c, t_s, w_s, omega - h).0)
                / (2.0 * h);
            assert!(
                (d - fd).abs() < 1e-6 * d.abs().max(1.0),
                "{omega}: {d} vs {fd}"
            );
        }
    }

    use crate::fragments::law_checks::{
        assert_hand_derivatives, assert_mixed, assert_same_bits, grid,
    };

    #[test]
    fn friction_in_hyper_dual_numbers() {
        let (t_c, t_s, w_s) = (1.0, 1.5, 0.5);
        let law = friction_law(t_c, t_s, w_s);
        let mut omegas = grid(w_s);
        omegas.extend(grid(REGULARISATION * w_s));
        assert_same_bits(
            &law,
            |w, _| friction_value(t_c, t_s, w_s, w),
            &omegas,
            &[0.0],
        );
        let dual = |w, _| friction_value(Dual::from(t_c), Dual::from(t_s), Dual::from(w_s), w);
        // dT/domega = slope tanh + level (1 - tanh²)/omega_t: the Stribeck fall and the
        // regularisation's rise cancel near the peak torque, so the sum of the terms'
        // magnitudes is its scale.
        let scale = |w: f64, _| {
            let omega_t = REGULARISATION * w_s;
            let u = w / w_s;
            let stribeck = exp(-u * u);
            let th = tanh(w / omega_t);
            let slope = (t_s - t_c) * stribeck * (2.0 * u / w_s);
            let level = t_c + (t_s - t_c) * stribeck;
            (
                (slope * th).abs() + (level * (1.0 - th * th) / omega_t).abs(),
                0.0,
            )
        };
        assert_hand_derivatives(&law, dual, &omegas, &[0.0], 1e-12, scale);
        // d²T/domega domega_s: the law varies in omega_s over omega_s / (omega/omega_t) and
        // omega_s / (omega/omega_s)², at most omega_s / 26 at these speeds.
        for w in [-0.6, -0.04, 0.0, 0.02, 0.11, 0.5, 1.3] {
            let law_of = |w_s: Dual| friction_law(t_c, t_s, w_s);
            assert_mixed(law_of, w_s, 1e-4, w_s / 30.0, w, 0.0, false);
        }
    }
}
