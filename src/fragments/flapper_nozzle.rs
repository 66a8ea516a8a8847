//! BG2 of the paper (Fig. 2b): the flapper-nozzle pilot stage and the spool it drives.
//!
//! ```text
//!  supply 0 --> 1 R1 --> 0 p_a --> 1 R(x_f) A --> 0 tank        (and the same for side B)
//!                        |  \
//!                        v   v
//!                      C_H   TF A_s --> 1 spool (v_v) --> TF 1/A_s --> 0 p_b
//!                                       |     |     |
//!                                       v     v     v
//!                                     I m_v R b_v  C 1/k_v
//! ```
//!
//! * Two control chambers `<prefix>.chamber_a`, `<prefix>.chamber_b` (0-junctions), each with
//!   the oil compressibility `C_H = V_H / beta` (states `<prefix>.C_Ha.q`, `<prefix>.C_Hb.q`, oil
//!   volume compressed in the chamber, `p = q / C_H` above the cavitation floor of
//!   [`super::servo_valve::limits::chamber`]).
//! * Each chamber is fed from the supply through a fixed inlet orifice (`<prefix>.R1`,
//!   `<prefix>.R2`, diameter `d_0`) and drained to the tank through its nozzle
//!   (`<prefix>.R_nozzle_a`, `<prefix>.R_nozzle_b`), a curtain area `pi d_n (x_f0 -+ x_f)` that the
//!   flapper modulates: moving by `+x_f` closes nozzle A and opens nozzle B. All four are the
//!   regularised orifice of [`super::orifice`]; the gap passes through the smooth ramp, so the
//!   flapper touching a nozzle closes it smoothly instead of making the area negative.
//! * The chamber pressures act on the spool ends (area `A_s = pi d_s^2 / 4`, two TFs): force
//!   `A_s (p_a - p_b)`, and the spool displaces `A_s v_v` out of chamber B into chamber A's end.
//! * The spool (`<prefix>.spool`, 1-junction, velocity `v_v`): mass `m_v`, viscous friction `b_v`,
//!   centring spring `k_v`; the spring is part of the spring field (below), whose second state is
//!   the spool position `x_v`. The end stops at `+-x_v_max` keep the spool within its stroke: a
//!   smooth contact spring, stored energy, as the field's nonlinear law on its spool port
//!   ([`super::servo_valve::limits::spool_stop_spring`]), and a contact damping
//!   (`<prefix>.spool_stop`, an R modulated by `x_v`,
//!   [`super::servo_valve::limits::spool_stop_damping`]).
//!
//! **Feedback spring.** A spool driven only by `k_v` (as in the paper's BG2) must be very stiff
//! for a usable null, and then the pilot flow cannot move it faster than a few hundred rad/s
//! (time constant `2 A_s^2 / (K_c k_v)`). Like every two-stage flapper-nozzle valve with
//! mechanical feedback, this model adds a feedback wire: a spring `k_w` on the relative
//! displacement `x_f + x_v` between flapper and spool, pushing the flapper back towards null as
//! the spool moves. The spool then settles where the wire force balances the motor force
//! (`x_v ~ k_phi i / k_w`), and its bandwidth is set by the pilot flow gain
//! (`~ K_qp k_w / (A_s (k_f + k_w))`). `k_v` stays as a weak centring spring.
//!
//! **Spring field.** `k_f` (flapper pivot, BG1), `k_v` (spool, BG2) and `k_w` (wire) are three
//! springs on the two coordinates `x_f`, `x_v`; as three one-port C elements their states would
//! be dependent (`q_w = q_f + q_v`, a zero eigenvalue and a singular Jacobian at rest). They form
//! one 2-port C-field ([`add_spring_field`]) with states `(x_f, x_v)` and stiffness
//! `K = [[k_f + k_w, k_w], [k_w, k_v + k_w]]`, energy
//! `k_f x_f^2 / 2 + k_v x_v^2 / 2 + k_w (x_f + x_v)^2 / 2`, plus the stop spring's energy on `x_v`.
//!
//! Sign conventions: `x_f > 0` raises `p_a`, `p_a > p_b` drives `x_v > 0`; chamber volumes flow
//! in positive.

use nalgebra::DMatrix;

use crate::bond_graph::{BondGraph, BondId, Domain, ElementId, Law, SignalId};
use crate::math::dual::Dual;

use super::orifice::{fixed_orifice, variable_orifice, OrificeFluid};
use super::servo_valve::limits::{spool_stop_damping, spool_stop_spring};
use super::servo_valve::{limits, ServoValveParameters};

/// Handles into the flapper-nozzle fragment.
#[derive(Clone, Copy, Debug)]
pub struct FlapperNozzlePorts {
    /// The spool 1-junction `<prefix>.spool` (common flow: spool velocity).
    pub spool: ElementId,
    /// Control chamber A 0-junction (common effort `p_a`).
    pub chamber_a: ElementId,
    /// Control chamber B 0-junction (common effort `p_b`).
    pub chamber_b: ElementId,
    /// Spool position \[m\] (signal port `<prefix>.x_v`, connected by the spring field).
    pub x_v: SignalId,
    /// Control pressure `p_a` \[Pa\] (`<prefix>.p_a`).
    pub p_a: SignalId,
    /// Control pressure `p_b` \[Pa\] (`<prefix>.p_b`).
    pub p_b: SignalId,
    /// Bond supply -> R1 junction (its flow is the pilot flow of side A).
    pub supply_a_bond: BondId,
    /// Bond supply -> R2 junction (its flow is the pilot flow of side B).
    pub supply_b_bond: BondId,
}

/// A hydraulic restriction between two 0-junctions: `from -> 1 -> to`, `1 -> R`. Returns the
/// junction and the bond from `from` (whose flow is the flow through the restriction).
pub(crate) fn restriction(
    g: &mut BondGraph,
    name: &str,
    from: ElementId,
    to: ElementId,
    r: ElementId,
) -> (ElementId, BondId) {
    let j = g.add_one(format!("{name}.dp"));
    let b = g.bond(from, j);
    g.bond(j, to);
    g.bond(j, r);
    (j, b)
}

/// Adds BG2 under `prefix`: the pilot stage between the `supply` and `tank` 0-junctions,
/// modulated by the flapper displacement `x_f`, and the spool.
pub fn add_flapper_nozzle<S: Copy + Into<Dual>>(
    g: &mut BondGraph,
    prefix: &str,
    p: &ServoValveParameters<S>,
    supply: ElementId,
    tank: ElementId,
    x_f: SignalId,
) -> FlapperNozzlePorts {
    let p = &p.map(Into::<Dual>::into);
    let fluid = p.fluid();
    let a0 = std::f64::consts::PI * p.d_0 * p.d_0 / 4.0;
    let nozzle_width = std::f64::consts::PI * p.d_n;
    let a_s = p.spool_area();
    // Smallest nozzle gap: a hundredth of the null gap (contact of flapper and nozzle).
    let gap_rounding = 0.01 * p.x_f0;

    let chamber_a = g.add_zero(format!("{prefix}.chamber_a"));
    let chamber_b = g.add_zero(format!("{prefix}.chamber_b"));
    let c_ha = g.add_c(format!("{prefix}.C_Ha"), limits::chamber(p.v_h, p.beta));
    let c_hb = g.add_c(format!("{prefix}.C_Hb"), limits::chamber(p.v_h, p.beta));
    // Compressed volume at the supply pressure.
    g.set_nominal(c_ha, &[(p.v_h / p.beta * p.p_supply).v]);
    g.set_domains(c_ha, &[Domain::Hydraulic]);
    g.set_domains(c_hb, &[Domain::Hydraulic]);
    g.set_nominal(c_hb, &[(p.v_h / p.beta * p.p_supply).v]);
    let ca_bond = g.bond(chamber_a, c_ha);
    let cb_bond = g.bond(chamber_b, c_hb);

    let r1 = g.add_r(format!("{prefix}.R1"), fixed_orifice("R1", a0, fluid));
    let r2 = g.add_r(format!("{prefix}.R2"), fixed_orifice("R2", a0, fluid));
    let nozzle = |label: &str, sign: f64, fluid: OrificeFluid<Dual>| -> Law {
        variable_orifice(label, nozzle_width, p.x_f0, sign, gap_rounding, fluid)
    };
    let rna = g.add_r_modulated(
        format!("{prefix}.R_nozzle_a"),
        nozzle("R(x_f) A", -1.0, fluid),
        x_f,
    );
    let rnb = g.add_r_modulated(
        format!("{prefix}.R_nozzle_b"),
        nozzle("R(x_f) B", 1.0, fluid),
        x_f,
    );
    let (_, supply_a_bond) = restriction(g, &format!("{prefix}.R1"), supply, chamber_a, r1);
    let (_, supply_b_bond) = restriction(g, &format!("{prefix}.R2"), supply, chamber_b, r2);
    restriction(g, &format!("{prefix}.R_nozzle_a"), chamber_a, tank, rna);
    restriction(g, &format!("{prefix}.R_nozzle_b"), chamber_b, tank, rnb);

    let spool = g.add_one(format!("{prefix}.spool"));
    let tf_a = g.add_tf(format!("{prefix}.A_s_a"), a_s);
    let tf_b = g.add_tf(format!("{prefix}.A_s_b"), 1.0 / a_s);
    g.bond(chamber_a, tf_a);
    g.bond(tf_a, spool);
    g.bond(spool, tf_b);
    g.bond(tf_b, chamber_b);
    let m_v = g.add_i(format!("{prefix}.m_v"), p.m_v);
    let b_v = g.add_r(format!("{prefix}.b_v"), p.b_v);
    g.bond(spool, m_v);
    g.bond(spool, b_v);
    g.set_nominal(m_v, &[p.m_v.v * 0.1]); // 0.1 m/s
    g.set_domains(m_v, &[Domain::Translation]);
    let x_v = g.add_signal_port(format!("{prefix}.x_v"));
    let stop = g.add_r_modulated(
        format!("{prefix}.spool_stop"),
        spool_stop_damping(p.x_v_max, p.stop_stiffness(), p.m_v),
        x_v,
    );
    g.bond(spool, stop);
    let p_a = g.add_effort_sensor(format!("{prefix}.p_a"), ca_bond);
    let p_b = g.add_effort_sensor(format!("{prefix}.p_b"), cb_bond);
    FlapperNozzlePorts {
        spool,
        chamber_a,
        chamber_b,
        x_v,
        p_a,
        p_b,
        supply_a_bond,
        supply_b_bond,
    }
}

/// The springs of flapper and spool as one 2-port C-field `<prefix>.springs` (see the module
/// documentation): port 1 on the `flapper` junction (state `<prefix>.springs.q[1]` = `x_f`),
/// port 2 on the `spool` junction (`.q[2]` = `x_v`). Connects the signal ports `x_f` and `x_v`.
#[allow(clippy::too_many_arguments)]
pub fn add_spring_field<S: Copy + Into<Dual>>(
    g: &mut BondGraph,
    prefix: &str,
    p: &ServoValveParameters<S>,
    flapper: ElementId,
    spool: ElementId,
    x_f: SignalId,
    x_v: SignalId,
) -> ElementId {
    let p = &p.map(Into::<Dual>::into);
    let k = [p.k_f + p.k_w, p.k_w, p.k_w, p.k_v + p.k_w];
    let part = |f: fn(&Dual) -> f64| DMatrix::from_row_slice(2, 2, &k.map(|x| f(&x)));
    let stop = spool_stop_spring(p.x_v_max, p.stop_stiffness());
    let field = g.add_c_field_with_port_laws(
        format!("{prefix}.springs"),
        part(|x| x.v),
        vec![None, Some(stop)],
    );
    if k.iter().any(|x| x.d != 0.0) {
        g.set_field_derivative(field, part(|x| x.d));
    }
    // The flapper's null gap, the spool's stroke.
    g.set_nominal(field, &[p.x_f0.v, p.x_v_max.v]);
    g.set_domains(field, &[Domain::Translation, Domain::Translation]);
    g.bond(flapper, field);
    g.bond(spool, field);
    let sf = g.add_field_state_sensor(format!("{prefix}.x_f_sensor"), field, 0);
    let sv = g.add_field_state_sensor(format!("{prefix}.x_v_sensor"), field, 1);
    g.connect_signal_port(x_f, sf);
    g.connect_signal_port(x_v, sv);
    field
}
