//! Bond-graph core: elements, causality assignment, compilation to state equations.
//!
//! The paper (Barbosa & Góes 2002) describes every energy domain of the slewing plate (servo
//! valve, vane motor, torsion bar, hub, plate modes) in one bond-graph language and derives the
//! state equations from the graph, as CAMP-G does. This module does the same in Rust; it knows
//! about energy and signals, not about FMI or the paper's physics (see [`crate::fragments`]).
//!
//! # Building a graph
//!
//! ```
//! use hydraulic_slewing_plate::bond_graph::BondGraph;
//!
//! // Se - 1 - I, C, R: a mass on a spring and damper pushed by a force F.
//! let mut g = BondGraph::new("msd");
//! let f = g.add_input("F");
//! let se = g.add_se("force", f); // modulated effort source (MSe)
//! let j = g.add_one("v"); // common velocity
//! let m = g.add_i("mass", 2.0); // inertance = mass [kg]
//! let k = g.add_c("spring", 1.0 / 100.0); // linear law: capacitance = 1/stiffness
//! let d = g.add_r("damper", 3.0); // resistance = damping [N s/m]
//! g.bond(se, j); // half arrow: power flows from the source into the junction
//! let bm = g.bond(j, m);
//! g.bond(j, k);
//! g.bond(j, d);
//! g.add_flow_output("velocity", bm);
//! let model = g.compile().unwrap();
//! assert_eq!(model.state_names(), ["mass.p", "spring.q"]);
//! let mut dx = [0.0; 2];
//! model.derivatives(&[2.0, 0.01], &[5.0], &mut dx);
//! // dp/dt = F - q/C - R p/m = 5 - 1 - 3 = 1;  dq/dt = p/m = 1
//! assert!((dx[0] - 1.0).abs() < 1e-12 && (dx[1] - 1.0).abs() < 1e-12);
//! ```
//!
//! * Elements are named (names must be unique; fragments prefix them, e.g. "loes.C3") and the
//!   builder returns typed ids: [`ElementId`], [`BondId`], [`SignalId`].
//! * `bond(from, to)` draws the half arrow `from -> to`: the power `e f` is positive when it flows
//!   that way. A 0-junction sums the flows of bonds pointing in minus those pointing out; a
//!   1-junction does the same with efforts.
//! * Energy variables and signs: an I element has the state `p` (momentum), `dp/dt = e`,
//!   `f = p / I`; a C element has the state `q` (displacement), `dq/dt = f`, `e = q / C`, where
//!   `e` and `f` are the element's effort and inflow (bond flow with the sign of the half arrow
//!   into the element). Sources' effort and flow are those of a bond pointing away from them.
//!   So reversing the half arrow of a one-port flips its flow, not its effort: on a 0-junction
//!   (common effort) that changes nothing physically; on a 1-junction it makes the element move
//!   against the junction's common flow. Draw one-ports with the half arrow pointing into them
//!   (sources: out of them) unless there is a reason not to.
//! * TF: `e2 = m e1`, `f1 = m f2`; GY: `e1 = r f2`, `e2 = r f1`; port 1 is the bond pointing in,
//!   port 2 the bond pointing out. Both may be modulated by a signal (MTF, MGY).
//! * I- and C-fields: multiport storage with a symmetric mass (`f = M^-1 p`) or stiffness
//!   (`e = K q`) matrix, for coupled modes. All ports of a field are in integral causality; a
//!   graph that would need otherwise is rejected like a dependent storage element.
//! * Signal blocks (inputs, constants, gains, sums, products, integrators, effort / flow / state
//!   sensors, and signal ports for forward references between fragments) make a controlled bond
//!   graph. An integrator's output is a state (the rotor angle `theta_a` of eq. 1 is the integral
//!   of the rotor speed).
//! * States are numbered in creation order of I, C, fields and integrators; inputs in creation
//!   order of `add_input`; outputs in creation order.
//!
//! # Causality
//!
//! [`BondGraph::compile`] validates the parameters (non-positive or non-finite I, C, R values are
//! errors naming the element), then runs the sequential causality assignment procedure (SCAP, of
//! Karnopp, Margolis & Rosenberg, *System Dynamics*): sources first, then every storage element
//! in integral causality, each followed by propagation through junctions, TFs and GYs, then the
//! resistors, then any bond left. A storage element that ends in derivative causality (e.g. two
//! rigidly coupled inertias), a contradiction (two effort sources on one 0-junction) or an
//! algebraic loop (found when sorting the equations) is an error naming the elements involved;
//! such graphs are never turned silently into wrong equations.
//!
//! # The compiled model
//!
//! The causal graph becomes a flat plan (a `Vec` of operations over numbered slots, no maps or
//! tree walking at run time) computing every bond effort and flow, every signal, the state
//! derivatives and the outputs. [`CompiledModel`] gives `dx/dt = f(x, u)`, outputs, the exact
//! Jacobian (forward-mode dual numbers through the same plan), linearisation `A, B, C, D`, the
//! stored energy and the power balance `dE/dt = P_sources - P_dissipated`.
//!
//! `f` and the Jacobian run only the part of the plan the derivatives need (outputs and bond
//! variables that feed no derivative are left out), and the Jacobian seeds several columns per
//! dual-number pass: columns that share no row, by a colouring of the sparsity pattern read off
//! the plan. The plan also tells whether the Jacobian is constant (affine equations with constant
//! coefficients, as the LOES with the plate), which lets the solver factorise it once per step
//! size ([`CompiledModel::jacobian_is_constant`]). Short of that, it tells which entries vary
//! with `(x, u)`: [`CompiledModel::fix_constant_entries`] evaluates the others once, and each
//! Jacobian afterwards runs passes over the variable columns only, with the same bits.
//! [`BondGraph::to_dot`] draws the graph with its causal strokes.
//!
//! `CompiledModel` is `Clone + Send + Sync`; evaluation uses a per-thread scratch buffer, so one
//! model can be used from several threads at once (a law closure must not call back into the
//! model). Parameters are baked into the plan: to change one, change the graph (or rebuild it
//! from its fragment) and compile again, which takes microseconds for graphs of this size.
//! A modulated TF or GY whose causality needs the inverse modulus divides by the signal; keep it
//! away from zero.

// The graph and its checks.
mod element;
mod error;
mod graph;
pub mod units;
mod validate;
// Compilation, in pipeline order: causality, lowering to equations, sorting, the flat plan, the
// structure read off it.
mod causality;
mod forms;
mod lower;
mod plan;
mod sort;
mod structure;
mod tangent;
// The compiled model: evaluation (values and dual numbers), energy, linearisation.
mod compiled;
mod discretisation;
mod dual;
mod energy;
mod linearization;
mod sensitivity;
// Drawing.
mod dot;

pub use compiled::{AffineOffsets, CompiledModel};
pub use discretisation::ExactDiscretisation;
pub use element::{
    Bond, BondId, Element, ElementId, ElementKind, Law, LawFn, Modulus, NonlinearLaw, OutputDef,
    OutputSource, Quantity, SignalBlock, SignalId, SignalKind, SourceValue, VALUE_BOUND_RANGE,
};
pub use energy::PowerBalance;
pub use error::BondGraphError;
pub use forms::{FormsJacobian, NonaffineForms, PointCache, PointForms};
pub use graph::BondGraph;
pub use linearization::Linearization;
pub use sensitivity::LinearizationDerivative;
pub use units::{Domain, StateUnits};
