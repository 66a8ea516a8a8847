//! Element kinds, identifiers and constitutive laws.

use std::fmt;
use std::sync::Arc;

use nalgebra::DMatrix;

use crate::math::dual::{Dual, HyperDual};

/// Identifier of a bond-graph element (source, storage, resistor, two-port, junction, field).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ElementId(pub(crate) usize);

/// Identifier of a bond.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct BondId(pub(crate) usize);

/// Identifier of a signal (the output of a signal block: input, constant, gain, sum, product,
/// integrator, sensor or signal port).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct SignalId(pub(crate) usize);

impl ElementId {
    /// Position of the element in creation order.
    pub fn index(self) -> usize {
        self.0
    }
}
impl BondId {
    /// Position of the bond in creation order.
    pub fn index(self) -> usize {
        self.0
    }
}
impl SignalId {
    /// Position of the signal block in creation order.
    pub fn index(self) -> usize {
        self.0
    }
}

/// A scalar nonlinear function `y = phi(x, m)` with its partial derivatives, where `m` is an
/// optional modulating signal (0 when the element is not modulated).
///
/// The closure returns `(phi, d phi / d x, d phi / d m)`. The derivatives must be exact (they feed
/// the Jacobian of the stiff integrator); use a smooth (regularised) law where the textbook one has
/// an infinite slope, e.g. the orifice law near zero pressure drop.
pub type LawFn = dyn Fn(f64, f64) -> (f64, f64, f64) + Send + Sync;

/// A nonlinear constitutive law: a labelled closure with its derivatives.
#[derive(Clone)]
pub struct NonlinearLaw {
    /// Short description, shown in `Debug` output and DOT labels.
    pub label: String,
    pub(crate) f: Arc<LawFn>,
    /// `phi` alone: the same closure compiled a second time with its value as the only result,
    /// so that evaluating f (not its Jacobian) does not pay for the derivatives. Same
    /// operations for the value, so the same bits as `f`'s first result.
    pub(crate) value: Arc<dyn Fn(f64, f64) -> f64 + Send + Sync>,
    pub(crate) energy: Option<Arc<dyn Fn(f64) -> f64 + Send + Sync>>,
    /// `(k, c)` with `|E(x)| <= k x^2 + c` for every finite `x`, if the law's author shows one
    /// ([`NonlinearLaw::with_energy_bound`]).
    pub(crate) energy_bound: Option<(f64, f64)>,
    /// `(k, c)` with `|phi(v, m)| <= k s^2 + c`, `s = max(|v|, |m|)`, wherever
    /// `s <= VALUE_BOUND_RANGE`, if the law's author shows one
    /// ([`NonlinearLaw::with_value_bound`]).
    pub(crate) value_bound: Option<(f64, f64)>,
    /// The law in hyper-dual numbers ([`NonlinearLaw::with_hyper`]), if its author gave it: what
    /// the parameter sensitivities of the linearisation need where a law's argument or its own
    /// constants move with the parameter.
    pub(crate) hyper: Option<Arc<HyperLawFn>>,
}

/// A law `phi(x, m)` in hyper-dual numbers ([`NonlinearLaw::with_hyper`]).
pub type HyperLawFn = dyn Fn(HyperDual, HyperDual) -> HyperDual + Send + Sync;

/// How far a law's declared value bound ([`NonlinearLaw::with_value_bound`]) must hold: for
/// every argument and modulator up to 2^500 in magnitude, well below where a square of them
/// overflows (2^512), so that a law may square its argument (`v^2 + c^2`, `|v| v`) without its
/// author having to reason about overflow; beyond, no bound is promised.
pub const VALUE_BOUND_RANGE: f64 = 3.273_390_607_896_142e150; // 2^500, exactly

impl NonlinearLaw {
    /// An unmodulated law: `phi` returns `(y, dy/dx)`.
    pub fn new<F>(label: impl Into<String>, phi: F) -> Self
    where
        F: Fn(f64) -> (f64, f64) + Send + Sync + 'static,
    {
        let phi = Arc::new(phi);
        let value = Arc::clone(&phi);
        NonlinearLaw {
            label: label.into(),
            f: Arc::new(move |x, _m| {
                let (y, dy) = phi(x);
                (y, dy, 0.0)
            }),
            value: Arc::new(move |x, _m| value(x).0),
            energy: None,
            energy_bound: None,
            value_bound: None,
            hyper: None,
        }
    }

    /// A law modulated by a signal: `phi(x, m)` returns `(y, dy/dx, dy/dm)`.
    pub fn modulated<F>(label: impl Into<String>, phi: F) -> Self
    where
        F: Fn(f64, f64) -> (f64, f64, f64) + Send + Sync + 'static,
    {
        let phi = Arc::new(phi);
        let value = Arc::clone(&phi);
        NonlinearLaw {
            label: label.into(),
            f: phi,
            value: Arc::new(move |x, m| value(x, m).0),
            energy: None,
            energy_bound: None,
            value_bound: None,
            hyper: None,
        }
    }

    /// Attaches the stored-energy function `E(x) = int_0^x phi(s) ds` of a storage law (used by
    /// [`super::CompiledModel::stored_energy`]; without it the integral is computed by
    /// quadrature).
    pub fn with_energy<F>(mut self, energy: F) -> Self
    where
        F: Fn(f64) -> f64 + Send + Sync + 'static,
    {
        self.energy = Some(Arc::new(energy));
        self
    }

    /// Declares `|E(x)| <= k x^2 + c` for every finite `x` (`E` the stored energy, from 0): with
    /// it, [`super::CompiledModel::stored_energy_bound`] shows the stored energy finite at a
    /// state without computing it, so that a communication point need not (the FMU computes it
    /// when it is read). The law's author proves the bound; a test samples it.
    pub fn with_energy_bound(mut self, k: f64, c: f64) -> Self {
        self.energy_bound = Some((k, c));
        self
    }

    /// Declares `|phi(v, m)| <= k s^2 + c` with `s = max(|v|, |m|)`, the value finite, for every
    /// `v`, `m` with `s <= VALUE_BOUND_RANGE` (`m` = 0 for a law without modulator), as
    /// computed (rounding included). With it, the FMU shows the outputs and rows of `f` that go
    /// through the law finite at a state without computing them (`PointForms::finite_radius`),
    /// so that a communication point need not: they are computed when read. The law's author
    /// proves the bound in the law's documentation; a test samples it.
    pub fn with_value_bound(mut self, k: f64, c: f64) -> Self {
        self.value_bound = Some((k, c));
        self
    }

    /// [`NonlinearLaw::with_value_bound`] when `bound` is some: for a law whose bound holds
    /// only for some of its parameters (a positive width, say).
    pub fn with_value_bound_if(self, bound: Option<(f64, f64)>) -> Self {
        match bound {
            Some((k, c)) => self.with_value_bound(k, c),
            None => self,
        }
    }

    /// Gives the law in hyper-dual numbers: `phi(x, m)` with `x` and `m` carrying derivatives
    /// along two directions (`ε₁` a state's, `ε₂` a parameter's), and the law's own constants
    /// entering with their derivatives along `ε₂` (captured as [`crate::math::dual::Dual`]s, the
    /// derivatives with respect to the parameter the model was built for). Written once,
    /// generic in [`crate::math::dual::Real`], its value must be the law's own to the bit; its
    /// `a` part the closure's derivatives. The parameter sensitivities of the linearisation
    /// ([`super::CompiledModel::linearize_with_sensitivity`]) need it wherever the law's
    /// argument, modulator or constants move with the parameter, and refuse, naming the law,
    /// where it is missing.
    pub fn with_hyper<F>(mut self, phi: F) -> Self
    where
        F: Fn(HyperDual, HyperDual) -> HyperDual + Send + Sync + 'static,
    {
        self.hyper = Some(Arc::new(phi));
        self
    }

    /// The bound declared by [`NonlinearLaw::with_value_bound`], if any.
    pub fn value_bound(&self) -> Option<(f64, f64)> {
        self.value_bound
    }

    /// Evaluates `(phi, dphi/dx, dphi/dm)`.
    pub fn eval(&self, x: f64, m: f64) -> (f64, f64, f64) {
        (self.f)(x, m)
    }
}

impl fmt::Debug for NonlinearLaw {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "NonlinearLaw({:?})", self.label)
    }
}

/// Constitutive law of a one-port I, C or R element.
///
/// | element | `Linear(k)` | `Nonlinear(phi)` | `Conductance(phi)` |
/// | --- | --- | --- | --- |
/// | I (state `p`) | inertance: `f = p / k` | `f = phi(p)` | not allowed |
/// | C (state `q`) | capacitance: `e = q / k` | `e = phi(q)` | not allowed |
/// | R | resistance: `e = k f` (either causality) | `e = phi(f)` (R must receive the flow) | `f = phi(e)` (R must receive the effort) |
///
/// Here `e` and `f` are the element's own effort and flow, with the flow counted positive into the
/// element (power `e f` into the element). Only R laws may be modulated by a signal
/// ([`super::BondGraph::add_r_modulated`]); storage laws are functions of the state alone so that
/// the stored energy is a state function.
#[derive(Clone, Debug)]
pub enum Law {
    /// Linear law with the given parameter (inertance, capacitance or resistance), and its
    /// derivative with respect to the parameter the model is built for (0 unless the fragment
    /// gave one, [`crate::math::dual`]).
    Linear(Dual),
    /// Nonlinear law in the element's "natural" form (see the table).
    Nonlinear(NonlinearLaw),
    /// Nonlinear R law in conductance form `f = phi(e)` (e.g. an orifice `Q = g(dp)`).
    Conductance(NonlinearLaw),
}

impl From<f64> for Law {
    fn from(v: f64) -> Self {
        Law::Linear(v.into())
    }
}
impl From<Dual> for Law {
    fn from(v: Dual) -> Self {
        Law::Linear(v)
    }
}

/// A source value: constant or modulated by a signal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SourceValue {
    /// A constant effort or flow (with its derivative, as [`Law::Linear`]'s).
    Constant(Dual),
    /// The value of a signal (a modulated source, `MSe` / `MSf`).
    Signal(SignalId),
}

impl From<f64> for SourceValue {
    fn from(v: f64) -> Self {
        SourceValue::Constant(v.into())
    }
}
impl From<Dual> for SourceValue {
    fn from(v: Dual) -> Self {
        SourceValue::Constant(v)
    }
}
impl From<SignalId> for SourceValue {
    fn from(s: SignalId) -> Self {
        SourceValue::Signal(s)
    }
}

/// The modulus of a TF or GY: constant or a signal (`MTF`, `MGY`).
pub type Modulus = SourceValue;

/// The kind of a bond-graph element together with its parameters.
#[derive(Clone, Debug)]
pub enum ElementKind {
    /// Effort source: imposes `e` on its bond.
    Se(SourceValue),
    /// Flow source: imposes `f` on its bond.
    Sf(SourceValue),
    /// Inertia, state = generalised momentum `p`, `dp/dt = e`.
    I(Law),
    /// Capacitor, state = generalised displacement `q`, `dq/dt = f`.
    C(Law),
    /// Resistor, optionally modulated by a signal (only for nonlinear laws).
    R(Law, Option<SignalId>),
    /// Transformer: `e2 = m e1`, `f1 = m f2` (port 1 = the bond pointing into the TF, port 2 = the
    /// bond pointing out of it).
    Tf(Modulus),
    /// Gyrator: `e1 = r f2`, `e2 = r f1`.
    Gy(Modulus),
    /// 0-junction: common effort, flows sum to zero.
    Zero,
    /// 1-junction: common flow, efforts sum to zero.
    One,
    /// Multiport I-field with symmetric positive-definite mass (inertance) matrix `M`:
    /// `f = M^-1 p`, `dp/dt = e`. Ports in bond order.
    IField(DMatrix<f64>),
    /// Multiport C-field with symmetric positive-semidefinite stiffness matrix `K` and an
    /// optional nonlinear law `phi_i` on each port's own state: `e = K q + phi(q)` (`phi_i(q_i)`
    /// in row i, 0 where a port has none), `dq/dt = f`; energy `q' K q / 2 + sum_i E_i(q_i)`.
    /// Ports in bond order; the law vector is empty or one entry per port.
    CField(DMatrix<f64>, Vec<Option<NonlinearLaw>>),
}

impl ElementKind {
    /// Short kind label: "Se", "Sf", "I", "C", "R", "TF", "GY", "0", "1", "IF", "CF".
    pub fn label(&self) -> &'static str {
        match self {
            ElementKind::Se(SourceValue::Constant(_)) => "Se",
            ElementKind::Se(SourceValue::Signal(_)) => "MSe",
            ElementKind::Sf(SourceValue::Constant(_)) => "Sf",
            ElementKind::Sf(SourceValue::Signal(_)) => "MSf",
            ElementKind::I(_) => "I",
            ElementKind::C(_) => "C",
            ElementKind::R(_, None) => "R",
            ElementKind::R(_, Some(_)) => "MR",
            ElementKind::Tf(SourceValue::Constant(_)) => "TF",
            ElementKind::Tf(SourceValue::Signal(_)) => "MTF",
            ElementKind::Gy(SourceValue::Constant(_)) => "GY",
            ElementKind::Gy(SourceValue::Signal(_)) => "MGY",
            ElementKind::Zero => "0",
            ElementKind::One => "1",
            ElementKind::IField(_) => "IF",
            ElementKind::CField(..) => "CF",
        }
    }
}

/// A named bond-graph element.
#[derive(Clone, Debug)]
pub struct Element {
    /// Unique name, e.g. "loes.C3".
    pub name: String,
    /// Kind and parameters.
    pub kind: ElementKind,
}

/// A bond: power flows (half arrow) from `from` to `to`.
#[derive(Clone, Debug)]
pub struct Bond {
    /// Name, by default "from->to".
    pub name: String,
    /// Element at the tail of the half arrow.
    pub from: ElementId,
    /// Element at the head of the half arrow.
    pub to: ElementId,
}

/// What a bond or state sensor measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// The effort on a bond.
    Effort(BondId),
    /// The flow on a bond (sign as the bond's half arrow).
    Flow(BondId),
    /// The state (energy variable `p` or `q`) of a storage element; `port` selects the port of a
    /// field (0 for one-port elements).
    State(ElementId, usize),
}

/// A signal block.
#[derive(Clone, Debug)]
pub enum SignalKind {
    /// External input `u[i]`, in creation order of inputs.
    Input,
    /// A constant (constants and gains carry their derivatives, as [`Law::Linear`]'s).
    Constant(Dual),
    /// `y = k * u`.
    Gain(Dual, Option<SignalId>),
    /// `y = sum(k_i * u_i)`.
    Sum(Vec<(Dual, SignalId)>),
    /// `y = u1 * u2`.
    Product(SignalId, SignalId),
    /// `dy/dt = u`; `y` is a state of the model.
    Integrator(Option<SignalId>),
    /// `y = phi(u)`, a static nonlinear function (e.g. an amplifier's smooth output limit); the
    /// law's derivative enters the Jacobian.
    Function(NonlinearLaw, Option<SignalId>),
    /// A sensor of an effort, a flow or a state.
    Sensor(Quantity),
    /// A named pass-through whose source is connected later (forward reference between
    /// fragments); see [`super::BondGraph::connect_signal_port`].
    Port(Option<SignalId>),
}

impl SignalKind {
    /// Short label for DOT output.
    pub fn label(&self) -> &'static str {
        match self {
            SignalKind::Input => "input",
            SignalKind::Constant(_) => "const",
            SignalKind::Gain(..) => "gain",
            SignalKind::Sum(_) => "sum",
            SignalKind::Product(..) => "product",
            SignalKind::Integrator(_) => "integrator",
            SignalKind::Function(..) => "function",
            SignalKind::Sensor(Quantity::Effort(_)) => "De",
            SignalKind::Sensor(Quantity::Flow(_)) => "Df",
            SignalKind::Sensor(Quantity::State(..)) => "Dx",
            SignalKind::Port(_) => "port",
        }
    }
}

/// A named signal block.
#[derive(Clone, Debug)]
pub struct SignalBlock {
    /// Unique name (shares the namespace of elements), e.g. "controller.A1".
    pub name: String,
    /// Kind and parameters.
    pub kind: SignalKind,
}

/// A named model output.
#[derive(Clone, Debug)]
pub struct OutputDef {
    /// Output name, e.g. "y_pot".
    pub name: String,
    /// What the output reads.
    pub source: OutputSource,
}

/// What an output reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputSource {
    /// A bond effort, flow or storage state.
    Quantity(Quantity),
    /// A signal.
    Signal(SignalId),
}
