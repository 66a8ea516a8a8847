//! The torsion bar between the vane motor's shaft and the hub (section 2.1 of the paper: "the
//! output axis of the vane motor is coupled to a torsion bar that drives the central hub").
//!
//! The paper does not give its stiffness. Default 2.5e3 N m/rad: a steel bar of 20 mm diameter
//! and 0.5 m (`G J / L` = 80e9 * pi 0.02^4 / 32 / 0.5 = 2.5e3), which puts the rigid mode of hub and
//! plate on the bar near 2.5 Hz (docs/model-notes.md, item 13).
//!
//! Bond graph: motor 1-junction -> 0-junction `<prefix>` (common effort: the bar torque) -> C
//! `<prefix>.k` (compliance `1 / k`, state: twist \[rad\]); the 0-junction is then bonded to the
//! hub (and, in the paper formulation, through TFs to the modes, which twist the bar with the
//! root slope).

use crate::bond_graph::{BondGraph, BondId, ElementId, SignalId};

/// Default torsion-bar stiffness \[N m/rad\].
pub const DEFAULT_STIFFNESS: f64 = 2.5e3;

/// Handles into the torsion-bar fragment.
#[derive(Clone, Copy, Debug)]
pub struct TorsionBarPorts {
    /// The 0-junction carrying the bar torque; bond it to what the bar drives.
    pub node: ElementId,
    /// The bar compliance.
    pub c: ElementId,
    /// Bond node -> C (effort: bar torque).
    pub c_bond: BondId,
    /// The bar torque \[N m\] (`<prefix>.torque`).
    pub torque: SignalId,
}

/// Adds a torsion bar of stiffness `k` driven from the 1-junction `motor`.
pub fn add_torsion_bar(
    g: &mut BondGraph,
    prefix: &str,
    k: f64,
    motor: ElementId,
) -> TorsionBarPorts {
    let node = g.add_zero(prefix.to_string());
    let c = g.add_c(format!("{prefix}.k"), 1.0 / k);
    g.bond(motor, node);
    let c_bond = g.bond(node, c);
    let torque = g.add_effort_sensor(format!("{prefix}.torque"), c_bond);
    TorsionBarPorts {
        node,
        c,
        c_bond,
        torque,
    }
}
