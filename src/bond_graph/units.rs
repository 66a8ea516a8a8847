//! The SI units of a bond graph's states. A storage element's state is the time integral of the
//! power variable its port integrates: an I element's momentum `p = ∫ e dt` (its derivative is
//! the effort), a C element's displacement `q = ∫ f dt` (its derivative is the flow). Which
//! units those are depends on the energy domain of the port, which the fragment that adds the
//! element states ([`BondGraph::set_domains`](super::BondGraph::set_domains)); an integrator's
//! units are stated directly
//! ([`BondGraph::set_integrator_units`](super::BondGraph::set_integrator_units)). The unit names
//! are those of the model description's `<UnitDefinitions>`.

/// The energy domain of a port: its effort and flow.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Domain {
    /// Force \[N\] and velocity \[m/s\].
    Translation,
    /// Torque \[N m\] and angular velocity \[rad/s\].
    Rotation,
    /// Pressure \[Pa\] and volume flow \[m^3/s\].
    Hydraulic,
    /// Voltage \[V\] and current \[A\].
    Electrical,
}

/// The units of a state and of its time derivative.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StateUnits {
    /// The state's unit.
    pub state: &'static str,
    /// Its time derivative's unit.
    pub derivative: &'static str,
}

impl Domain {
    /// An I element's momentum `p = ∫ e dt` and its derivative, the effort.
    pub fn momentum(self) -> StateUnits {
        let (state, derivative) = match self {
            Domain::Translation => ("N.s", "N"),
            Domain::Rotation => ("N.m.s", "N.m"),
            Domain::Hydraulic => ("Pa.s", "Pa"),
            Domain::Electrical => ("V.s", "V"),
        };
        StateUnits { state, derivative }
    }

    /// A C element's displacement `q = ∫ f dt` and its derivative, the flow.
    pub fn displacement(self) -> StateUnits {
        let (state, derivative) = match self {
            Domain::Translation => ("m", "m/s"),
            Domain::Rotation => ("rad", "rad/s"),
            Domain::Hydraulic => ("m3", "m3/s"),
            Domain::Electrical => ("C", "A"),
        };
        StateUnits { state, derivative }
    }
}
