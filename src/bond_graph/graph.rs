//! The bond-graph builder.

use std::collections::HashMap;

use nalgebra::DMatrix;

use super::element::*;
use super::units::{Domain, StateUnits};
use crate::math::dual::Dual;

/// A bond graph under construction: elements, bonds, signal blocks and outputs.
///
/// Builder methods never fail; every check (parameter ranges, number of bonds per element,
/// unconnected signals, duplicate names, causality, algebraic loops) happens in
/// [`BondGraph::compile`], which names the elements involved in its error.
#[derive(Clone, Debug)]
pub struct BondGraph {
    pub(crate) name: String,
    pub(crate) elements: Vec<Element>,
    pub(crate) bonds: Vec<Bond>,
    /// Each bond's name and the first bond of that name, the index of [`BondGraph::find_bond`]
    /// and of [`BondGraph::bond`]'s unique names (a graph has hundreds of bonds).
    bond_index: HashMap<String, BondId>,
    pub(crate) signals: Vec<SignalBlock>,
    pub(crate) outputs: Vec<OutputDef>,
    /// State-bearing items in creation order: this is the order of the model's states.
    pub(crate) state_order: Vec<StateOwner>,
    /// Typical magnitudes of states, set by the fragment that owns them (see
    /// [`BondGraph::set_nominal`]), keyed by the state owner.
    nominals: Vec<(StateOwner, Vec<f64>)>,
    /// The units of states, set by the fragment that owns them (see [`BondGraph::set_domains`]).
    units: Vec<(StateOwner, Vec<StateUnits>)>,
    /// The derivatives of fields' matrices with respect to the parameter the model is built
    /// for, where a fragment gave them ([`BondGraph::set_field_derivative`]).
    pub(crate) field_derivatives: Vec<(ElementId, DMatrix<f64>)>,
}

/// An item that carries states: a storage element or an integrator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum StateOwner {
    Element(ElementId),
    Integrator(SignalId),
}

/// Records what `owner` states about its states (nominals, units), replacing what it stated
/// before.
fn restate<T>(stated: &mut Vec<(StateOwner, Vec<T>)>, owner: StateOwner, values: Vec<T>) {
    stated.retain(|(o, _)| *o != owner);
    stated.push((owner, values));
}

impl BondGraph {
    /// An empty graph.
    pub fn new(name: impl Into<String>) -> Self {
        BondGraph {
            name: name.into(),
            elements: Vec::new(),
            bonds: Vec::new(),
            bond_index: HashMap::new(),
            signals: Vec::new(),
            outputs: Vec::new(),
            state_order: Vec::new(),
            nominals: Vec::new(),
            units: Vec::new(),
            field_derivatives: Vec::new(),
        }
    }

    /// The number of states of the storage element `element` (one for an I or C, one per port
    /// for a field), 0 for any other element.
    fn states_of(&self, element: ElementId) -> usize {
        match &self.elements[element.0].kind {
            ElementKind::I(_) | ElementKind::C(_) => 1,
            ElementKind::IField(m) | ElementKind::CField(m, _) => m.nrows(),
            _ => 0,
        }
    }

    /// States the energy domain of each port of the storage element `element` (one per state),
    /// which gives its states' units (see [`super::units`]).
    ///
    /// # Panics
    /// If `element` carries no state, or the number of domains differs from its number of
    /// states (a programming error in the fragment).
    pub fn set_domains(&mut self, element: ElementId, domains: &[Domain]) {
        let states = self.states_of(element);
        assert!(
            states > 0 && states == domains.len(),
            "set_domains: {} has {states} states, got {} domains",
            self.elements[element.0].name,
            domains.len()
        );
        let momentum = matches!(
            self.elements[element.0].kind,
            ElementKind::I(_) | ElementKind::IField(_)
        );
        let units = domains
            .iter()
            .map(|d| {
                if momentum {
                    d.momentum()
                } else {
                    d.displacement()
                }
            })
            .collect();
        restate(&mut self.units, StateOwner::Element(element), units);
    }

    /// States the units of the integrator `signal`'s state and of its input, the derivative.
    ///
    /// # Panics
    /// If `signal` is not an integrator.
    pub fn set_integrator_units(&mut self, signal: SignalId, units: StateUnits) {
        assert!(
            matches!(self.signals[signal.0].kind, SignalKind::Integrator(_)),
            "set_integrator_units: {} is not an integrator",
            self.signals[signal.0].name
        );
        restate(&mut self.units, StateOwner::Integrator(signal), vec![units]);
    }

    /// The stated units of every state, in the compiled model's state order (`None` where the
    /// owner stated none).
    pub fn state_units(&self) -> Vec<Option<StateUnits>> {
        self.per_state(&self.units)
    }

    /// States a typical magnitude of each state of the storage element `element` (one value
    /// per state: one for an I or C, one per port for a field), for the integrator's absolute
    /// tolerance. The fragment that adds an element knows its scale (a pilot chamber holds
    /// 1e-13 m^3 of compressed oil, a rotor angle is of order 1 rad); stating it here keeps it
    /// with the element through renames. Values must be finite and positive.
    ///
    /// # Panics
    /// If `element` carries no state, or the number of values differs from its number of states
    /// (a programming error in the fragment).
    pub fn set_nominal(&mut self, element: ElementId, nominal: &[f64]) {
        let states = self.states_of(element);
        assert!(
            states > 0 && states == nominal.len(),
            "set_nominal: {} has {states} states, got {} nominal values",
            self.elements[element.0].name,
            nominal.len()
        );
        self.put_nominal(StateOwner::Element(element), nominal.to_vec());
    }

    /// States a typical magnitude of the state of the integrator `signal` (see
    /// [`BondGraph::set_nominal`]).
    ///
    /// # Panics
    /// If `signal` is not an integrator.
    pub fn set_integrator_nominal(&mut self, signal: SignalId, nominal: f64) {
        assert!(
            matches!(self.signals[signal.0].kind, SignalKind::Integrator(_)),
            "set_integrator_nominal: {} is not an integrator",
            self.signals[signal.0].name
        );
        self.put_nominal(StateOwner::Integrator(signal), vec![nominal]);
    }

    fn put_nominal(&mut self, owner: StateOwner, values: Vec<f64>) {
        assert!(
            values.iter().all(|v| v.is_finite() && *v > 0.0),
            "nominal values must be finite and positive, got {values:?}"
        );
        restate(&mut self.nominals, owner, values);
    }

    /// The stated nominal magnitude of every state, in the compiled model's state order
    /// (`None` where the owner stated none).
    pub fn state_nominals(&self) -> Vec<Option<f64>> {
        self.per_state(&self.nominals)
    }

    /// One entry per state, in the compiled model's state order, from the values stated per
    /// owner (`None` for the states of an owner that stated none).
    fn per_state<T: Copy>(&self, stated: &[(StateOwner, Vec<T>)]) -> Vec<Option<T>> {
        let mut out = Vec::new();
        for owner in &self.state_order {
            let n = match owner {
                StateOwner::Element(e) => self.states_of(*e),
                StateOwner::Integrator(_) => 1,
            };
            match stated.iter().find(|(o, _)| o == owner) {
                Some((_, v)) => out.extend(v.iter().map(|x| Some(*x))),
                None => out.extend(std::iter::repeat_n(None, n)),
            }
        }
        out
    }

    /// The graph's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// All elements, in creation order (index = [`ElementId::index`]).
    pub fn elements(&self) -> &[Element] {
        &self.elements
    }

    /// All bonds, in creation order.
    pub fn bonds(&self) -> &[Bond] {
        &self.bonds
    }

    /// All signal blocks, in creation order.
    pub fn signals(&self) -> &[SignalBlock] {
        &self.signals
    }

    /// All outputs, in creation order.
    pub fn outputs(&self) -> &[OutputDef] {
        &self.outputs
    }

    /// The element or signal block with this name.
    pub fn find_element(&self, name: &str) -> Option<ElementId> {
        self.elements
            .iter()
            .position(|e| e.name == name)
            .map(ElementId)
    }

    /// The signal block with this name.
    pub fn find_signal(&self, name: &str) -> Option<SignalId> {
        self.signals
            .iter()
            .position(|e| e.name == name)
            .map(SignalId)
    }

    /// The bond with this name.
    pub fn find_bond(&self, name: &str) -> Option<BondId> {
        self.bond_index.get(name).copied()
    }

    /// Name of an element.
    pub fn element_name(&self, id: ElementId) -> &str {
        &self.elements[id.0].name
    }

    /// Name of a signal block.
    pub fn signal_name(&self, id: SignalId) -> &str {
        &self.signals[id.0].name
    }

    /// Name of a bond.
    pub fn bond_name(&self, id: BondId) -> &str {
        &self.bonds[id.0].name
    }

    /// The element, for reading or changing its parameters (e.g. a new capacitance before
    /// recompiling).
    pub fn element_mut(&mut self, id: ElementId) -> &mut Element {
        &mut self.elements[id.0]
    }

    fn push(&mut self, name: impl Into<String>, kind: ElementKind) -> ElementId {
        let stateful = matches!(
            kind,
            ElementKind::I(_)
                | ElementKind::C(_)
                | ElementKind::IField(_)
                | ElementKind::CField(..)
        );
        self.elements.push(Element {
            name: name.into(),
            kind,
        });
        let id = ElementId(self.elements.len() - 1);
        if stateful {
            self.state_order.push(StateOwner::Element(id));
        }
        id
    }

    fn push_signal(&mut self, name: impl Into<String>, kind: SignalKind) -> SignalId {
        let stateful = matches!(kind, SignalKind::Integrator(_));
        self.signals.push(SignalBlock {
            name: name.into(),
            kind,
        });
        let id = SignalId(self.signals.len() - 1);
        if stateful {
            self.state_order.push(StateOwner::Integrator(id));
        }
        id
    }

    // ---------------------------------------------------------------- elements

    /// Effort source (`Se`), constant or modulated (`MSe`) by a signal. Its effort and flow are
    /// those of a bond pointing away from the source; its power `e f` is delivered to the graph.
    pub fn add_se(&mut self, name: impl Into<String>, value: impl Into<SourceValue>) -> ElementId {
        self.push(name, ElementKind::Se(value.into()))
    }

    /// Flow source (`Sf`), constant or modulated (`MSf`) by a signal.
    pub fn add_sf(&mut self, name: impl Into<String>, value: impl Into<SourceValue>) -> ElementId {
        self.push(name, ElementKind::Sf(value.into()))
    }

    /// Inertia; state `p` (generalised momentum), named `<name>.p`. `Law::Linear(i)` is the
    /// inertance: `f = p / i`, kinetic energy `p^2 / (2 i)`.
    pub fn add_i(&mut self, name: impl Into<String>, law: impl Into<Law>) -> ElementId {
        self.push(name, ElementKind::I(law.into()))
    }

    /// Capacitor; state `q` (generalised displacement), named `<name>.q`. `Law::Linear(c)` is
    /// the capacitance (compliance): `e = q / c`, potential energy `q^2 / (2 c)`.
    pub fn add_c(&mut self, name: impl Into<String>, law: impl Into<Law>) -> ElementId {
        self.push(name, ElementKind::C(law.into()))
    }

    /// Resistor. `Law::Linear(r)`: `e = r f`, dissipating `r f^2`.
    pub fn add_r(&mut self, name: impl Into<String>, law: impl Into<Law>) -> ElementId {
        self.push(name, ElementKind::R(law.into(), None))
    }

    /// Resistor whose nonlinear law is modulated by a signal `m` (e.g. a metering orifice whose
    /// area follows the spool position): `e = phi(f, m)` or `f = phi(e, m)`.
    pub fn add_r_modulated(
        &mut self,
        name: impl Into<String>,
        law: Law,
        modulator: SignalId,
    ) -> ElementId {
        self.push(name, ElementKind::R(law, Some(modulator)))
    }

    /// Transformer with modulus `m` (constant or modulated, `MTF`): `e2 = m e1`, `f1 = m f2`,
    /// where port 1 is the bond whose half arrow points into the TF and port 2 the bond pointing
    /// out of it. Example: a vane motor from the hydraulic side (pressure, volume flow) to the
    /// shaft (torque, speed) has `m = D_m`: torque = D_m p, Q = D_m omega.
    pub fn add_tf(&mut self, name: impl Into<String>, modulus: impl Into<Modulus>) -> ElementId {
        self.push(name, ElementKind::Tf(modulus.into()))
    }

    /// Gyrator with modulus `r` (constant or modulated, `MGY`): `e1 = r f2`, `e2 = r f1` (port 1
    /// pointing in, port 2 pointing out). Example: a DC motor, torque = k i, voltage = k omega.
    pub fn add_gy(&mut self, name: impl Into<String>, modulus: impl Into<Modulus>) -> ElementId {
        self.push(name, ElementKind::Gy(modulus.into()))
    }

    /// 0-junction (common effort; the flows of bonds pointing in minus those pointing out sum
    /// to zero).
    pub fn add_zero(&mut self, name: impl Into<String>) -> ElementId {
        self.push(name, ElementKind::Zero)
    }

    /// 1-junction (common flow; the efforts of bonds pointing in minus those pointing out sum
    /// to zero).
    pub fn add_one(&mut self, name: impl Into<String>) -> ElementId {
        self.push(name, ElementKind::One)
    }

    /// Multiport I-field with a symmetric positive-definite mass matrix `M` (n x n, one port per
    /// bond, in bond creation order): `f = M^-1 p`, states `<name>.p[1]` .. `<name>.p[n]`,
    /// energy `p' M^-1 p / 2`.
    pub fn add_i_field(&mut self, name: impl Into<String>, mass: DMatrix<f64>) -> ElementId {
        self.push(name, ElementKind::IField(mass))
    }

    /// Multiport C-field with a symmetric positive-semidefinite stiffness matrix `K` (n x n, one
    /// port per bond, in bond creation order): `e = K q`, states `<name>.q[1]` .. `<name>.q[n]`,
    /// energy `q' K q / 2`.
    pub fn add_c_field(&mut self, name: impl Into<String>, stiffness: DMatrix<f64>) -> ElementId {
        self.push(name, ElementKind::CField(stiffness, Vec::new()))
    }

    /// A C-field as [`Self::add_c_field`] with a nonlinear law `phi_i(q_i)` added to the
    /// effort of each port that has one (one entry per port, `None` for a linear port):
    /// `e = K q + phi(q)`, energy `q' K q / 2 + sum_i E_i(q_i)` with `E_i` the law's energy
    /// function ([`NonlinearLaw::with_energy`]) or its quadrature. For a contact spring on a
    /// coordinate the field already holds (a spool's end stops on the spool's spring): a
    /// one-port C on the same junction would add a second state integrating the same flow.
    pub fn add_c_field_with_port_laws(
        &mut self,
        name: impl Into<String>,
        stiffness: DMatrix<f64>,
        port_laws: Vec<Option<NonlinearLaw>>,
    ) -> ElementId {
        self.push(name, ElementKind::CField(stiffness, port_laws))
    }

    /// Gives the derivative of a field's matrix (`M` of an I-field, `K` of a C-field) with
    /// respect to the parameter the model is built for, as the scalars' [`Dual`] parts give
    /// theirs: the parameter sensitivities of the compiled model
    /// ([`super::CompiledModel::linearize_with_sensitivity`]) carry it. Panics if `element` is
    /// not a field or the sizes differ.
    pub fn set_field_derivative(&mut self, element: ElementId, derivative: DMatrix<f64>) {
        let e = &self.elements[element.0];
        let n = match &e.kind {
            ElementKind::IField(m) | ElementKind::CField(m, _) => m.nrows(),
            _ => panic!("set_field_derivative: element '{}' is not a field", e.name),
        };
        assert_eq!(
            derivative.shape(),
            (n, n),
            "set_field_derivative: the derivative of '{}' is not {n} x {n}",
            e.name
        );
        self.field_derivatives.retain(|(id, _)| *id != element);
        self.field_derivatives.push((element, derivative));
    }

    /// The derivative [`BondGraph::set_field_derivative`] gave for `element`, if any.
    pub(crate) fn field_derivative(&self, element: ElementId) -> Option<&DMatrix<f64>> {
        self.field_derivatives
            .iter()
            .find(|(id, _)| *id == element)
            .map(|(_, d)| d)
    }

    /// Sets or replaces the modulating signal of a source, TF or GY (making it `MSe`, `MSf`,
    /// `MTF`, `MGY`). Panics if the element is of another kind.
    pub fn set_modulation(&mut self, element: ElementId, signal: SignalId) {
        let e = &mut self.elements[element.0];
        match &mut e.kind {
            ElementKind::Se(v) | ElementKind::Sf(v) | ElementKind::Tf(v) | ElementKind::Gy(v) => {
                *v = SourceValue::Signal(signal)
            }
            _ => panic!(
                "set_modulation: element '{}' is not a source, TF or GY",
                e.name
            ),
        }
    }

    /// A bond with half arrow (power direction) `from -> to`, named "from->to" (with a "#k"
    /// suffix if that name is taken).
    pub fn bond(&mut self, from: ElementId, to: ElementId) -> BondId {
        // Joined by hand: a graph has hundreds of bonds, and `format!` costs ten times as much.
        let (a, b) = (&self.elements[from.0].name, &self.elements[to.0].name);
        let mut base = String::with_capacity(a.len() + 2 + b.len());
        base.push_str(a);
        base.push_str("->");
        base.push_str(b);
        if !self.bond_index.contains_key(&base) {
            return self.bond_named(base, from, to);
        }
        let mut k = 2;
        let mut name = format!("{base}#{k}");
        while self.bond_index.contains_key(&name) {
            k += 1;
            name = format!("{base}#{k}");
        }
        self.bond_named(name, from, to)
    }

    /// A named bond with half arrow `from -> to`.
    pub fn bond_named(
        &mut self,
        name: impl Into<String>,
        from: ElementId,
        to: ElementId,
    ) -> BondId {
        let name = name.into();
        let id = BondId(self.bonds.len());
        self.bond_index.entry(name.clone()).or_insert(id);
        self.bonds.push(Bond { name, from, to });
        id
    }

    // ---------------------------------------------------------------- signals

    /// An external input signal; inputs are numbered in creation order (`u[0]`, `u[1]`, ...).
    pub fn add_input(&mut self, name: impl Into<String>) -> SignalId {
        self.push_signal(name, SignalKind::Input)
    }

    /// A constant signal.
    pub fn add_constant(&mut self, name: impl Into<String>, value: impl Into<Dual>) -> SignalId {
        self.push_signal(name, SignalKind::Constant(value.into()))
    }

    /// `y = k u`.
    pub fn add_gain(
        &mut self,
        name: impl Into<String>,
        k: impl Into<Dual>,
        input: SignalId,
    ) -> SignalId {
        self.push_signal(name, SignalKind::Gain(k.into(), Some(input)))
    }

    /// `y = sum k_i u_i`, terms given as `(k_i, u_i)`, e.g. `&[(1.0, r), (-1.0, y)]`.
    pub fn add_sum<K: Copy + Into<Dual>>(
        &mut self,
        name: impl Into<String>,
        terms: &[(K, SignalId)],
    ) -> SignalId {
        let terms = terms.iter().map(|&(k, s)| (k.into(), s)).collect();
        self.push_signal(name, SignalKind::Sum(terms))
    }

    /// `y = a b`.
    pub fn add_product(&mut self, name: impl Into<String>, a: SignalId, b: SignalId) -> SignalId {
        self.push_signal(name, SignalKind::Product(a, b))
    }

    /// `y = phi(u)`: a static nonlinear function with its exact derivative (`law` returns
    /// `(phi, dphi/du)`, see [`NonlinearLaw::new`]), e.g. the smooth output limit of an amplifier.
    pub fn add_function(
        &mut self,
        name: impl Into<String>,
        law: NonlinearLaw,
        input: SignalId,
    ) -> SignalId {
        self.push_signal(name, SignalKind::Function(law, Some(input)))
    }

    /// `dy/dt = u`; `y` becomes a state named `<name>` (e.g. the rotor angle "loes.theta_a", the
    /// integral of the rotor speed).
    pub fn add_integrator(&mut self, name: impl Into<String>, input: SignalId) -> SignalId {
        self.push_signal(name, SignalKind::Integrator(Some(input)))
    }

    /// Sensor of the effort on a bond (`De`).
    pub fn add_effort_sensor(&mut self, name: impl Into<String>, bond: BondId) -> SignalId {
        self.push_signal(name, SignalKind::Sensor(Quantity::Effort(bond)))
    }

    /// Sensor of the flow on a bond (`Df`), positive in the half-arrow direction.
    pub fn add_flow_sensor(&mut self, name: impl Into<String>, bond: BondId) -> SignalId {
        self.push_signal(name, SignalKind::Sensor(Quantity::Flow(bond)))
    }

    /// Sensor of the state (`p` of an I, `q` of a C) of a one-port storage element.
    pub fn add_state_sensor(&mut self, name: impl Into<String>, element: ElementId) -> SignalId {
        self.push_signal(name, SignalKind::Sensor(Quantity::State(element, 0)))
    }

    /// Sensor of the state of port `port` (0-based, bond order) of an I- or C-field.
    pub fn add_field_state_sensor(
        &mut self,
        name: impl Into<String>,
        element: ElementId,
        port: usize,
    ) -> SignalId {
        self.push_signal(name, SignalKind::Sensor(Quantity::State(element, port)))
    }

    /// A named signal port: a pass-through whose source is connected later with
    /// [`BondGraph::connect_signal_port`]. Fragments use it for signals they consume but that
    /// another fragment produces (e.g. the valve command of the LOES, produced by the
    /// controller, which itself needs the LOES rotor angle).
    pub fn add_signal_port(&mut self, name: impl Into<String>) -> SignalId {
        self.push_signal(name, SignalKind::Port(None))
    }

    /// Connects the source of a signal port (or replaces it). Panics if `port` is not a port.
    pub fn connect_signal_port(&mut self, port: SignalId, source: SignalId) {
        let s = &mut self.signals[port.0];
        match &mut s.kind {
            SignalKind::Port(p) => *p = Some(source),
            _ => panic!("connect_signal_port: '{}' is not a signal port", s.name),
        }
    }

    // ---------------------------------------------------------------- outputs

    /// A named model output reading a signal.
    pub fn add_output(&mut self, name: impl Into<String>, signal: SignalId) {
        self.outputs.push(OutputDef {
            name: name.into(),
            source: OutputSource::Signal(signal),
        });
    }

    /// A named model output reading the effort of a bond.
    pub fn add_effort_output(&mut self, name: impl Into<String>, bond: BondId) {
        self.outputs.push(OutputDef {
            name: name.into(),
            source: OutputSource::Quantity(Quantity::Effort(bond)),
        });
    }

    /// A named model output reading the flow of a bond.
    pub fn add_flow_output(&mut self, name: impl Into<String>, bond: BondId) {
        self.outputs.push(OutputDef {
            name: name.into(),
            source: OutputSource::Quantity(Quantity::Flow(bond)),
        });
    }

    /// A named model output reading the state of a storage element (port 0 for one-ports).
    pub fn add_state_output(&mut self, name: impl Into<String>, element: ElementId, port: usize) {
        self.outputs.push(OutputDef {
            name: name.into(),
            source: OutputSource::Quantity(Quantity::State(element, port)),
        });
    }

    /// Bonds attached to an element, with the sign `+1` if the half arrow points into the
    /// element, `-1` if it points out, in bond creation order.
    pub fn ports(&self, element: ElementId) -> Vec<(BondId, f64)> {
        let mut v = Vec::new();
        for (i, b) in self.bonds.iter().enumerate() {
            if b.to == element {
                v.push((BondId(i), 1.0));
            }
            if b.from == element {
                v.push((BondId(i), -1.0));
            }
        }
        v
    }

    /// Every element's [`Self::ports`], indexed by element, in one pass over the bonds.
    pub fn port_table(&self) -> Vec<Vec<(BondId, f64)>> {
        let mut table = vec![Vec::new(); self.elements.len()];
        for (i, b) in self.bonds.iter().enumerate() {
            if let Some(t) = table.get_mut(b.to.0) {
                t.push((BondId(i), 1.0));
            }
            if let Some(t) = table.get_mut(b.from.0) {
                t.push((BondId(i), -1.0));
            }
        }
        table
    }
}
