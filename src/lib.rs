//! # Hydraulic slewing plate
//!
//! The reference open implementation of Barbosa & Góes, "Modeling system of a flexible structure
//! with hydraulic actuation using bond-graphs" (II CONEM, 2002): a flexible aluminium plate on a
//! gas-bearing hub, slewed through a torsion bar by a vane motor under a two-stage
//! electro-hydraulic servo valve and an analog position loop. It is shipped as an FMI 2.0 FMU and
//! an FMI 3.0 FMU, each offering Co-Simulation and Model Exchange, from one binary (model
//! identifier `HydraulicSlewingPlate`).
//!
//! The layers, each usable and testable on its own:
//!
//! | module | what it is | knows about |
//! | --- | --- | --- |
//! | [`solver`] | stiff one-step integrators (Rodas5P, Radau IIA) | numbers only |
//! | [`eigen`] | eigenvalues of a real matrix, balanced first as LAPACK's `dgeev` does; damping ratios; derivatives of symmetric eigenpairs | numbers only |
//! | [`bond_graph`] | elements, causality, compilation to state equations | energy and signals |
//! | [`fragments`] | the paper's physical parts as bond-graph fragments | physics, no FMI |
//! | [`model`] | the assembled model behind the FMU, its parameters and outputs | fragments, solver |
//! | [`fmu`] | the version-neutral FMU core: instance, state machine, values, FMU states, logging | a model trait, no FMI version, no physics |
//! | [`fmi2`] | the FMI 2.0 C ABI (Co-Simulation, Model Exchange): C types, argument translation, symbols | the core |
//! | [`fmi3`] | the FMI 3.0 C ABI (Co-Simulation, Model Exchange): C types, argument translation, symbols | the core |
//! | [`web`] | the browser build: a simulation API for JavaScript, exported by the `.wasm` | the core |
//!
//! The offline analysis the tools and tests use (the stiff test set, the paper's printed values,
//! frequency responses, the comparison with `G_est`, and [`web`] on the host) is behind the
//! `analysis` feature, which the command-line tools enable and the FMU's binaries leave out.

#![deny(unsafe_op_in_unsafe_fn)]

pub mod bond_graph;
pub mod eigen;
pub mod fmi2;
pub mod fmi3;
pub mod fmu;
pub mod fnv1a;
pub mod fragments;
pub mod math;
pub mod model;
pub mod solver;
#[cfg(any(
    all(target_family = "wasm", not(target_os = "wasi")),
    feature = "analysis"
))]
pub mod web;

// The hash of the sources this library is built from (`SOURCE_HASH`, `SOURCE_MARKER`), written by
// build.rs (tools/source_hash.rs): a test tells a stale packaged FMU by it.
include!(concat!(env!("OUT_DIR"), "/source_hash.rs"));

// The FMI 2.0 C API (Co-Simulation and Model Exchange) of the shipped FMU.
#[cfg(not(target_family = "wasm"))]
export_fmi2_cosimulation!(crate::model::HydraulicSlewingPlate);
// The FMI 3.0 C API of the same model, for the FMI 3.0 FMU (the same binary), and under the
// WebAssembly component of the FMI 3.0 FMU (`fmi3::component`, built for wasm32-wasip2).
#[cfg(any(not(target_family = "wasm"), target_os = "wasi"))]
export_fmi3!(crate::model::HydraulicSlewingPlate);
