//! The torsion bar between the vane motor's shaft and the hub (section 2.1 of the paper: "the
//! output axis of the vane motor is coupled to a torsion bar that drives the central hub").
//!
//! The paper gives neither its stiffness nor its damping (docs/model-notes.md, item 13).
//!
//! * Stiffness, default 2.5e3 N m/rad: a steel bar of 20 mm diameter and 0.5 m
//!   (`G J / L` = 80e9 * pi 0.02^4 / 32 / 0.5 = 2.5e3), which puts the rigid mode of hub and plate
//!   on the bar near 2.5 Hz.
//! * Structural damping, a Kelvin-Voigt dashpot `c` in parallel with the spring, given as the
//!   damping ratio `zeta` of the hub (with the plate rigid, inertia `I`) on the bar with the motor
//!   held: `c = 2 zeta sqrt(k I)` ([`damping_coefficient`]). Default `zeta` = 0.02: a steel bar
//!   alone damps less (material loss factors of 1e-3), its keyed or clamped couplings at both
//!   ends bring it to the 1-5 % usual for bolted steel assemblies. Without it nothing damps the
//!   hub on the bar but the loop, which is then barely stable.
//!
//! Bond graph: motor 1-junction -> 0-junction `<prefix>` (common effort: the bar torque) ->
//! 1-junction `<prefix>.twist` (common flow: twist rate) -> C `<prefix>.k` (compliance `1 / k`,
//! state: twist \[rad\]) and R `<prefix>.c`; the 0-junction is then bonded to the hub (and, in
//! the paper formulation, through TFs to the modes, which twist the bar with the root slope).

use crate::bond_graph::{BondGraph, BondId, Domain, ElementId, SignalId};
use crate::math::dual::{Dual, Real};

/// Default torsion-bar stiffness \[N m/rad\].
pub const DEFAULT_STIFFNESS: f64 = 2.5e3;

/// Default structural damping ratio of the hub on the bar \[-\].
pub const DEFAULT_ZETA: f64 = 0.02;

/// The dashpot `c = 2 zeta sqrt(k I)` \[N m s/rad\] that gives an inertia `I` on a bar of
/// stiffness `k` the damping ratio `zeta`.
pub fn damping_coefficient<S: Real>(k: S, zeta: S, inertia: S) -> S {
    zeta * 2.0 * (k * inertia).sqrt()
}

/// Handles into the torsion-bar fragment.
#[derive(Clone, Copy, Debug)]
pub struct TorsionBarPorts {
    /// The 0-junction carrying the bar torque; bond it to what the bar drives.
    pub node: ElementId,
    /// The bar compliance.
    pub c: ElementId,
    /// The twist junction (common flow: motor speed less the speed of what the bar drives).
    pub twist: ElementId,
    /// Bond node -> twist junction (effort: bar torque, spring and dashpot).
    pub torque_bond: BondId,
    /// The bar torque \[N m\] (`<prefix>.torque`).
    pub torque: SignalId,
}

/// Adds a torsion bar of stiffness `k` and structural damping `c` (a dashpot in parallel,
/// see [`damping_coefficient`]; 0 for none) driven from the 1-junction `motor`. Both in `f64`
/// or with their derivatives along a parameter (exact sensitivities).
pub fn add_torsion_bar(
    g: &mut BondGraph,
    prefix: &str,
    k: impl Into<Dual>,
    c: impl Into<Dual>,
    motor: ElementId,
) -> TorsionBarPorts {
    let (k, c) = (k.into(), c.into());
    let node = g.add_zero(prefix.to_string());
    let twist = g.add_one(format!("{prefix}.twist"));
    let spring = g.add_c(format!("{prefix}.k"), 1.0 / k);
    g.set_nominal(spring, &[1e-2]); // 0.01 rad, 25 N m
    g.set_domains(spring, &[Domain::Rotation]);
    g.bond(motor, node);
    let torque_bond = g.bond(node, twist);
    g.bond(twist, spring);
    // A dashpot of zero coefficient but a derivative stays (its sensitivity), adding no state.
    if c > 0.0 || c.d != 0.0 {
        let damper = g.add_r(format!("{prefix}.c"), c);
        g.bond(twist, damper);
    }
    let torque = g.add_effort_sensor(format!("{prefix}.torque"), torque_bond);
    TorsionBarPorts {
        node,
        c: spring,
        twist,
        torque_bond,
        torque,
    }
}
