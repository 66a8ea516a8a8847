//! Exact sensitivities of the linearisation at rest with respect to the FMU's Real parameters:
//! what `hsp identify` fits frequency responses with (docs/identify.md).
//!
//! For each parameter the model is built again from the parameters in dual numbers seeded on
//! it ([`Parameters::seeded`]): every constant the fragments give the bond graph carries its
//! derivative, lowering folds them into the compiled plan, and hyper-dual passes of the plan
//! give `dA/dp, dB/dp, dC/dp, dD/dp` at the rest state
//! ([`crate::bond_graph::CompiledModel::linearize_with_sensitivity`]). No finite difference.
//!
//! **What is built, what is not.** Carried in dual numbers through their fragments: the LOES
//! (`loes.*`); the servo valve (`servo_valve.*`); the controller (`controller.A1`, `A2`, `k_pot`, the last also in the command
//! generator's move, `k_pl` except at 0, where the pressure feedback's state is not in the model,
//! `f_pl`, `e_max`); the torsion bar's stiffness and damping ratio; the plate (every `plate.*`)
//! and the hub's inertia `hub.I_H`, through the plate's Ritz model built in dual numbers
//! ([`crate::fragments::plate::PlateModel::for_parameters`]: the clamped plate's modes by the
//! derivatives of their eigenpairs), per plate coordinate and on the structure's modes, whose
//! modal dashpots move with all of these and the bar's stiffness by the derivatives of the
//! structure's eigenpairs ([`crate::fragments::plate::damping`]); the validity monitors' gains
//! (`torsion_bar.d`; the strengths move no output); the command generator's move
//! (`reference.*`). `controller.k_pl` at 0 gets an error that says why, which `hsp identify`
//! answers with central differences for it, and says so. The servo valve's parameters are all
//! carried (`servo_valve.*`). Where the rates at rest move with the
//! parameter (the servo valve's null pressures and volumes with `beta` and `p_supply`), the
//! rest state's own derivative is part of the point's move: `dx0/dp = -J⁻¹ ∂f/∂p` on the
//! equations the rest state solves, the Newton step of the rest state applied to `∂f/∂p`
//! ([`crate::fragments::servo_valve::rest::rest_state_derivative`]).

pub mod series;

use crate::bond_graph::{CompiledModel, Linearization, LinearizationDerivative};
use crate::fmu::{Experiment, Values};

use super::assembly::Assembled;
use super::compose::bond_graph_and_plate_for;
use super::parameters::{HydraulicsModel, Parameters};
use super::variables::VARIABLES;
use crate::fragments::servo_valve::{self, rest::rest_state_derivative};

/// The linearisation at rest of the configuration `values` (the vane motor sliding, as `hsp
/// frf` takes it), and for each parameter of `seeds` (indices among the FMU's variables) the
/// exact derivative of `A, B, C, D` with respect to it, or the reason it is not available. An
/// error when the linearisation itself is.
pub fn linearization_at_rest_with_derivatives(
    values: &Values,
    seeds: &[usize],
) -> Result<(Linearization, Vec<Result<LinearizationDerivative, String>>), String> {
    linearization_at_rest_of(values, seeded_at_rest(values, seeds))
}

/// The models of `values` in dual numbers for each parameter of `seeds`, the vane motor
/// sliding as at rest, or why one is not available (a part whose fragments take `f64`
/// constants, or a configuration its model refuses): what a caller checks before it asks for
/// the linearisation ([`linearization_at_rest_of`]), to skip it when no parameter has a
/// derivative.
pub fn seeded_at_rest(values: &Values, seeds: &[usize]) -> Vec<Result<Seeded, String>> {
    let experiment = Experiment::default();
    seeds
        .iter()
        .map(|&seed| Seeded::build(values, &experiment, seed, true))
        .collect()
}

/// [`linearization_at_rest_with_derivatives`] with the models in dual numbers already built
/// ([`seeded_at_rest`]).
pub fn linearization_at_rest_of(
    values: &Values,
    seeded: Vec<Result<Seeded, String>>,
) -> Result<(Linearization, Vec<Result<LinearizationDerivative, String>>), String> {
    let p = Parameters::from_values(values, &Experiment::default())?.sliding();
    let (_, lin) = Assembled::with_linearization_at_rest(&p)?;
    let derivatives = seeded
        .into_iter()
        .map(|s| s.and_then(|s| s.derivative_at_rest(&lin)))
        .collect();
    Ok((lin, derivatives))
}

/// The model built in dual numbers for one parameter ([`Parameters::seeded`]): its compiled
/// plan carries the derivatives of its constants along the parameter, its values are the
/// model's to the bit.
pub struct Seeded {
    /// The parameter, by its index among the FMU's variables.
    pub seed: usize,
    /// The compiled model with its constants' derivatives.
    pub compiled: CompiledModel,
    /// What the servo valve's rest state is scaled by ([`servo_valve::nominals`]), with the
    /// full servo valve.
    rest_scale: Option<Vec<f64>>,
}

impl Seeded {
    /// Builds the model of `values` seeded on the parameter `seed`, with the vane motor sliding
    /// if `sliding` (as linearisations at rest take it); an error names the parameter.
    pub fn build(
        values: &Values,
        experiment: &Experiment,
        seed: usize,
        sliding: bool,
    ) -> Result<Seeded, String> {
        let name = VARIABLES.get(seed).map_or("?", |v| v.name);
        let p = Parameters::seeded(values, experiment, seed)?;
        let p = if sliding { p.sliding() } else { p };
        let (graph, _) = bond_graph_and_plate_for(&p).map_err(|e| format!("{name}: {e}"))?;
        let compiled = graph.compile().map_err(|e| e.to_string())?;
        let rest_scale =
            (p.hydraulics == HydraulicsModel::ServoValve).then(|| servo_valve::nominals(&graph));
        Ok(Seeded {
            seed,
            compiled,
            rest_scale,
        })
    }

    /// An error unless the model's states are `state_names`, those of the model it is a
    /// derivative of.
    pub fn check_states(&self, state_names: &[String]) -> Result<(), String> {
        if self.compiled.state_names() != state_names {
            return Err(format!(
                "{}: the model built for its derivative has other states than the model",
                VARIABLES[self.seed].name
            ));
        }
        Ok(())
    }

    /// The derivative of `lin`, the linearisation at rest of the model, along the parameter.
    pub fn derivative_at_rest(
        &self,
        lin: &Linearization,
    ) -> Result<LinearizationDerivative, String> {
        self.check_states(&lin.state_names)?;
        let dx0 = self.rest_derivative(&lin.x0, &lin.u0)?;
        self.compiled
            .linearize_with_sensitivity(&lin.x0, &dx0, &lin.u0)
            .map_err(|e| format!("{}: {e}", VARIABLES[self.seed].name))
    }

    /// The rest state's derivative along the parameter, `x0` the rest state and `u0` the inputs
    /// it was found with: zero unless the rates at rest move with the parameter, which for the
    /// full servo valve move its null pressures and volumes (`dx0/dp = -J⁻¹ ∂f/∂p` on the
    /// equations the rest state solves), and which for the LOES they should not.
    pub fn rest_derivative(&self, x0: &[f64], u0: &[f64]) -> Result<Vec<f64>, String> {
        let name = VARIABLES[self.seed].name;
        let still = vec![0.0; x0.len()];
        let (f_p, _) = self.compiled.parameter_derivative(x0, &still, u0)?;
        match (f_p.iter().position(|&v| v != 0.0), &self.rest_scale) {
            (None, _) => Ok(still),
            (Some(_), Some(scale)) => rest_state_derivative(&self.compiled, x0, u0, &f_p, scale),
            (Some(i), None) => Err(format!(
                "{name}: the LOES's rest state moves with it (the rate of {} at rest), which it \
                 should not",
                self.compiled.state_names()[i]
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::frf::{output_of, state_response_at};
    use crate::model::presets;
    use crate::model::variables::idx;
    use nalgebra::DMatrix;

    fn loes_values() -> Values {
        let mut values = Values::from_start(&VARIABLES);
        presets::apply(&mut values, "loes-motor").unwrap();
        values
    }

    /// `A` of the configuration with `values[seed]` scaled by `1 + h`.
    fn a_at(values: &Values, seed: usize, h: f64) -> DMatrix<f64> {
        let mut v = values.clone();
        v.set_real(seed, values.real(seed) * (1.0 + h));
        linearization_at_rest_with_derivatives(&v, &[]).unwrap().0.a
    }

    #[test]
    fn the_loes_derivatives_agree_with_central_differences() {
        // An independent check of the dual numbers through the LOES: central differences of
        // the linearisation, step 1e-4 relative. The LOES is linear in its states and each A
        // entry a rational function of the constants, so the truncation error is of order
        // h^2 = 1e-8 of an entry's derivative; round-off 1e-16 / 1e-4 of the entry.
        let values = loes_values();
        let seeds = [
            idx::LOES_C3,
            idx::LOES_I_B,
            idx::LOES_R7,
            idx::LOES_D_M,
            idx::LOES_K_SV,
        ];
        let (lin, derivatives) = linearization_at_rest_with_derivatives(&values, &seeds).unwrap();
        for (&seed, d) in seeds.iter().zip(&derivatives) {
            let d = d.as_ref().unwrap();
            let p = values.real(seed);
            let h = 1e-4;
            let fd = (a_at(&values, seed, h) - a_at(&values, seed, -h)) / (2.0 * h * p);
            let scale = lin.a.abs().max() / p;
            let worst = (&d.a - &fd).abs().max();
            assert!(
                worst <= 1e-6 * scale,
                "{}: dA/dp off by {worst:e} (scale {scale:e})",
                VARIABLES[seed].name
            );
            assert!(d.a.abs().max() > 0.0 || d.b.abs().max() > 0.0);
        }
    }

    #[test]
    fn the_derivative_of_a_response_is_its_closed_form() {
        // H = C (jw - A)^-1 B + D of the LOES from e_in's path: with dA along R7, dH =
        // C (jw - A)^-1 dA (jw - A)^-1 B: compared with the response's central difference.
        let values = loes_values();
        let (lin, d) = linearization_at_rest_with_derivatives(&values, &[idx::LOES_R7]).unwrap();
        let d = d[0].as_ref().unwrap();
        let input = lin.input_names.iter().position(|n| n == "r").unwrap();
        let output = lin.output_names.iter().position(|n| n == "y_pot").unwrap();
        for f in [0.5, 5.0, 30.0] {
            let (x, dx) =
                crate::model::frf::state_response_and_derivative_at(&lin, d, input, f).unwrap();
            let dh = crate::model::frf::output_derivative_of(&lin, d, &x, &dx, input, output);
            let h = 1e-5;
            let r7 = values.real(idx::LOES_R7);
            let at = |s: f64| {
                let mut v = values.clone();
                v.set_real(idx::LOES_R7, r7 * (1.0 + s));
                let l = linearization_at_rest_with_derivatives(&v, &[]).unwrap().0;
                output_of(&l, &state_response_at(&l, input, f).unwrap(), input, output)
            };
            let fd = (at(h) - at(-h)) / (2.0 * h * r7);
            assert!(
                (dh - fd).norm() <= 1e-6 * fd.norm(),
                "{f} Hz: {dh} against {fd}"
            );
        }
    }

    /// The linearisation at rest of `values` with `values[seed]` scaled by `1 + h`.
    fn linearization_at(values: &Values, seed: usize, h: f64) -> Linearization {
        let mut v = values.clone();
        v.set_real(seed, values.real(seed) * (1.0 + h));
        linearization_at_rest_with_derivatives(&v, &[]).unwrap().0
    }

    /// Relative step of the central differences below, and their tolerance.
    ///
    /// Truncation: the linearisation is smooth in each of these parameters (the plate's R and
    /// the dashpots' resistances are linear in `zeta`; the modes of `(M, K + k e0 e0')` are
    /// analytic in `k` while their eigenvalues stay apart; the controller's constants enter
    /// `A` as polynomials), so a central difference's error is `h² p³ |∂³X/∂p³| / 6` of an
    /// entry: `1e-8` of the entry's derivative times the ratio of its third derivative to its
    /// first (in the relative variable). That ratio is 1 or less but along the bar's stiffness,
    /// whose modes' derivatives reach 5e-7 of an entry (measured): `RELATIVE` = 1e-5 leaves a
    /// factor 20, and is still far below what dropping a part of a derivative costs (the
    /// modes' vectors' derivatives are 35 % of `dA/dk`'s largest entry). Round-off: an entry
    /// of `X` is a sum of terms of about the size of its row's and column's largest entries
    /// (the dashpots' couplings of the modes cancel to 1e-8 of them), computed to `ε` of
    /// those, which the difference divides by `2 h`: `ε / 2h ≈ 1e-12` of
    /// `√(rowmax_i colmax_j) / p`, bounded by `ROUND_OFF` = 1e-9 with a factor 1000.
    ///
    /// Where a parameter moves the clamped plate's modes (the plate's and hub's constants, the
    /// consistent formulation), an entry the modes' vectors give carries the eigen-solver's
    /// error, larger than `ε` of its scale by up to `κ = λ_max / gap` (Davis and Kahan; `κ` =
    /// 1.1e5 for the default plate, whose closest pair are its modes (2, 1) and (1, 2)): the
    /// hub's coupling to the twist mode, zero in exact arithmetic, is 1.7e-11 of the hub's
    /// inertia there, and moves at random with the parameter. A mode's column (or row) takes
    /// up to `c ε κ` of its neighbour's, so the noise of an entry is that of the larger of its
    /// row's and its column's largest entries, and its central difference `c ε κ / 2h` of it,
    /// not a derivative: [`modes_round_off`] adds that floor (`c` = 10) to those parameters'
    /// tolerance.
    const STEP: f64 = 1e-4;
    /// An entry's error against its own derivative (truncation).
    const RELATIVE: f64 = 1e-5;
    /// An entry's error against its row's and column's scale `√(rowmax_i colmax_j) / p`
    /// (round-off).
    const ROUND_OFF: f64 = 1e-9;

    /// The exact derivative of `values`'s linearisation along `seed` against central
    /// differences, entry by entry, in `A`, `B`, `C`, `D`: `|exact − fd| ≤ RELATIVE |fd| +
    /// ROUND_OFF √(rowmax_i colmax_j) / p + floor max(rowmax_i, colmax_j) / p` (`STEP`), `floor`
    /// 0 but for the parameters that move the clamped plate's modes ([`modes_round_off`]). Prints the largest
    /// error relative to the matrix's largest derivative and the entry closest to its
    /// tolerance. Returns the derivative and the worst error found as a fraction of the
    /// tolerance (≤ 1 when it passes).
    fn agrees_with_central_differences(
        values: &Values,
        seed: usize,
    ) -> (LinearizationDerivative, f64) {
        agrees_within(values, seed, 0.0)
    }

    /// The round-off floor of the central differences along a parameter that moves the clamped
    /// plate's modes (`STEP`): `10 ε κ / 2h`, `κ = λ_max / min gap` of the clamped plate's
    /// modal stiffnesses in the consistent formulation, 0 in the paper's (no eigen-solver).
    fn modes_round_off(values: &Values) -> f64 {
        let p = Parameters::from_values(values, &Experiment::default()).unwrap();
        if p.plate.formulation != crate::fragments::plate::Formulation::Consistent {
            return 0.0;
        }
        let model = crate::fragments::plate::PlateModel::new(&p.plate).unwrap();
        let first = model.first_plate();
        let mut lambdas: Vec<f64> = (first..model.dim())
            .map(|j| model.stiffness[(j, j)])
            .collect();
        lambdas.sort_by(f64::total_cmp);
        let gap = lambdas
            .windows(2)
            .map(|w| w[1] - w[0])
            .fold(f64::INFINITY, f64::min);
        let kappa = lambdas[lambdas.len() - 1] / gap;
        10.0 * f64::EPSILON * kappa / (2.0 * STEP)
    }

    /// [`agrees_with_central_differences`] with the round-off floor `floor` of
    /// [`modes_round_off`].
    fn agrees_within(values: &Values, seed: usize, floor: f64) -> (LinearizationDerivative, f64) {
        let name = VARIABLES[seed].name;
        let (lin, d) = linearization_at_rest_with_derivatives(values, &[seed]).unwrap();
        let d = d.into_iter().next().unwrap();
        let d = d.unwrap_or_else(|e| panic!("{name}: {e}"));
        let p = values.real(seed);
        let (plus, minus) = (
            linearization_at(values, seed, STEP),
            linearization_at(values, seed, -STEP),
        );
        let (mut worst, mut relative, mut at) = (0.0f64, 0.0f64, String::new());
        let mut per_matrix = String::new();
        for (what, exact, value, plus, minus) in [
            ("A", &d.a, &lin.a, &plus.a, &minus.a),
            ("B", &d.b, &lin.b, &plus.b, &minus.b),
            ("C", &d.c, &lin.c, &plus.c, &minus.c),
            ("D", &d.d, &lin.d, &plus.d, &minus.d),
        ] {
            let fd = (plus - minus) / (2.0 * STEP * p);
            let rows: Vec<f64> = value.row_iter().map(|r| r.amax()).collect();
            let columns: Vec<f64> = value.column_iter().map(|c| c.amax()).collect();
            for i in 0..fd.nrows() {
                for j in 0..fd.ncols() {
                    let (e, f) = (exact[(i, j)], fd[(i, j)]);
                    let terms = (rows[i] * columns[j]).sqrt();
                    let tolerance = RELATIVE * f.abs()
                        + ROUND_OFF * terms / p.abs()
                        + floor * rows[i].max(columns[j]) / p.abs();
                    let ratio = if e == f {
                        0.0
                    } else {
                        (e - f).abs() / tolerance
                    };
                    assert!(
                        ratio <= 1.0,
                        "{name}: d{what}/dp ({i}, {j}) is {e:e}, the central difference \
                         {f:e} (tolerance {tolerance:e})"
                    );
                    if ratio > worst {
                        worst = ratio;
                        at = format!("d{what}/dp ({i}, {j}): {e:e} against {f:e}");
                    }
                }
            }
            let miss = (exact - &fd).amax();
            if fd.amax() > 0.0 {
                relative = relative.max(miss / fd.amax());
                per_matrix += &format!(" d{what} {:.1e} of {:.1e};", miss / fd.amax(), fd.amax());
            }
        }
        eprintln!(
            "{name}: largest error {relative:.1e} of the largest derivative ({per_matrix}); \
             worst entry {worst:.1e} of its tolerance, {at}"
        );
        (d, worst)
    }

    /// Whether any entry of the derivative is nonzero.
    fn moves(d: &LinearizationDerivative) -> bool {
        [&d.a, &d.b, &d.c, &d.d].iter().any(|x| x.amax() > 0.0)
    }

    fn default_values() -> Values {
        Values::from_start(&VARIABLES)
    }

    fn preset(name: &str) -> Values {
        let mut values = default_values();
        presets::apply(&mut values, name).unwrap();
        values
    }

    /// The column of the state named `state` in the linearisation of `values`.
    fn state(values: &Values, state: &str) -> usize {
        let lin = linearization_at_rest_with_derivatives(values, &[])
            .unwrap()
            .0;
        lin.state_names
            .iter()
            .position(|n| n == state)
            .unwrap_or_else(|| panic!("no state {state} in {:?}", lin.state_names))
    }

    #[test]
    fn the_plate_damping_ratio_is_exact_on_the_modes_and_per_coordinate() {
        // The default (consistent plate on its hub, damped on the structure's modes, motor
        // coupled), the same with the motor uncoupled (a free structure: its rigid mode has
        // no dashpot), the paper's formulation (an R per plate coordinate) and the consistent
        // plate with its hub locked (an R per clamped-plate mode).
        for (label, values) in [
            ("default", default_values()),
            ("servo-valve-motor", preset("servo-valve-motor")),
            ("paper-fig9b", preset("paper-fig9b")),
            ("complete-hub-locked", preset("complete-hub-locked")),
        ] {
            let (d, worst) = agrees_with_central_differences(&values, idx::PLATE_ZETA);
            eprintln!("plate.zeta, {label}: worst {worst:.3e} of the tolerance");
            assert!(d.a.amax() > 0.0, "{label}: dA/dzeta is zero");
        }
    }

    #[test]
    fn the_bar_stiffness_is_exact_where_the_structure_is_damped_on_its_modes() {
        // The structure's modes move with the bar: the dashpots' rates and resistances with
        // them (the derivatives of the generalised eigenpairs), beside the spring's own entry.
        let values = default_values();
        let (d, worst) = agrees_with_central_differences(&values, idx::TORSION_BAR_K);
        eprintln!("torsion_bar.k, default: worst {worst:.3e} of the tolerance");
        // The spring k acts through the bar's twist alone: any entry of dA/dk in another column
        // is the dashpots' (the modes' derivatives), and it is there.
        let twist = state(&values, "torsion_bar.k.q");
        let dashpots =
            d.a.column_iter()
                .enumerate()
                .filter(|(j, _)| *j != twist)
                .fold(0.0f64, |m, (_, c)| m.max(c.amax()));
        eprintln!(
            "torsion_bar.k, default: largest dashpot entry {dashpots:e}, spring's {:e}",
            d.a.column(twist).amax()
        );
        assert!(dashpots > 0.0, "dA/dk has no entry but the spring's");
        assert!(d.a.column(twist).amax() > 0.0);
        // The paper's formulation (the bar's own dashpot, which moves with k too).
        let (_, worst) =
            agrees_with_central_differences(&preset("paper-fig9b"), idx::TORSION_BAR_K);
        eprintln!("torsion_bar.k, paper-fig9b: worst {worst:.3e} of the tolerance");
    }

    #[test]
    fn the_bar_damping_ratio_is_exact_where_the_bar_has_its_dashpot() {
        let (d, worst) =
            agrees_with_central_differences(&preset("paper-fig9b"), idx::TORSION_BAR_ZETA);
        eprintln!("torsion_bar.zeta, paper-fig9b: worst {worst:.3e} of the tolerance");
        assert!(d.a.amax() > 0.0, "dA/dzeta_bar is zero");
        // Damped on the structure's modes, the bar has no dashpot of its own: no derivative.
        let (d, _) = agrees_with_central_differences(&default_values(), idx::TORSION_BAR_ZETA);
        assert!(
            !moves(&d),
            "torsion_bar.zeta moves the modally damped model"
        );
    }

    #[test]
    fn the_controller_parameters_are_exact() {
        // The default (servo valve, pressure feedback, saturating amplifier) and the paper's
        // loop (LOES, no pressure feedback, linear amplifier).
        let gains = [
            idx::CONTROLLER_A1,
            idx::CONTROLLER_A2,
            idx::CONTROLLER_K_POT,
        ];
        for (label, values) in [
            ("default", default_values()),
            ("paper-fig9b", preset("paper-fig9b")),
        ] {
            for seed in gains {
                let name = VARIABLES[seed].name;
                let (d, worst) = agrees_with_central_differences(&values, seed);
                eprintln!("{name}, {label}: worst {worst:.3e} of the tolerance");
                assert!(d.a.amax() > 0.0, "{label}: {name} leaves A");
            }
        }
        let values = default_values();
        for seed in [idx::CONTROLLER_K_PL, idx::CONTROLLER_F_PL] {
            let name = VARIABLES[seed].name;
            let (d, worst) = agrees_with_central_differences(&values, seed);
            eprintln!("{name}, default: worst {worst:.3e} of the tolerance");
            assert!(d.a.amax() > 0.0, "{name} leaves A");
        }
        // The amplifier is linear at rest (|u| below 0.8 e_max): its rail moves nothing there.
        let (d, _) = agrees_with_central_differences(&values, idx::CONTROLLER_E_MAX);
        assert!(!moves(&d), "e_max moves the linearisation at rest");
        // Without pressure feedback its filter is not in the model: f_pl moves nothing, and
        // k_pl at 0 (where the model has one state less than anywhere else) is refused.
        let paper = preset("paper-fig9b");
        let (d, _) = agrees_with_central_differences(&paper, idx::CONTROLLER_F_PL);
        assert!(!moves(&d));
        let (_, d) =
            linearization_at_rest_with_derivatives(&paper, &[idx::CONTROLLER_K_PL]).unwrap();
        let e = d[0].as_ref().unwrap_err();
        assert!(e.contains("controller.k_pl"), "{e}");
    }

    /// Each parameter of `seeds` in the configurations the plate's and hub's constants are
    /// checked in, against central differences (with the clamped plate's modes' round-off,
    /// [`modes_round_off`]): the default (consistent plate on its hub, in air, damped on the
    /// structure's modes, motor coupled), the motor uncoupled (a free structure), the paper's
    /// formulation on the LOES and the consistent plate with its hub locked. `what_moves`
    /// asserts what the derivative `d` moves (the configuration, its values, the parameter).
    /// A parameter at 0 (a relative step from it is none) is checked for its derivative's
    /// existence only.
    fn plate_parameters_agree(
        seeds: &[usize],
        what_moves: impl Fn(&str, &Values, usize, &LinearizationDerivative),
    ) {
        for (label, values) in [
            ("default", default_values()),
            ("servo-valve-motor", preset("servo-valve-motor")),
            ("paper-fig9b", preset("paper-fig9b")),
            ("complete-hub-locked", preset("complete-hub-locked")),
        ] {
            for &seed in seeds {
                let name = VARIABLES[seed].name;
                if values.real(seed) == 0.0 {
                    let (_, d) = linearization_at_rest_with_derivatives(&values, &[seed]).unwrap();
                    assert!(d[0].is_ok(), "{label}: {name}");
                    continue;
                }
                let (d, worst) = agrees_within(&values, seed, modes_round_off(&values));
                eprintln!("{name}, {label}: worst {worst:.3e} of the tolerance");
                what_moves(label, &values, seed, &d);
            }
        }
    }

    #[test]
    fn the_plates_material_and_the_hubs_inertia_are_exact() {
        // E, rho, h and nu reach the Ritz matrices, the clamped plate's modes (through the
        // air's added mass, the mass-normalised scaling) and the structure's modal dashpots;
        // I_H the hub's inertia, the structure's dashpots or the bar's (with the hub locked,
        // I_H still sizes the bar's dashpot, `2 zeta sqrt(k I)`).
        let seeds = [
            idx::PLATE_E,
            idx::PLATE_RHO,
            idx::PLATE_H,
            idx::PLATE_NU,
            idx::HUB_I_H,
        ];
        plate_parameters_agree(&seeds, |label, _, seed, d| {
            let name = VARIABLES[seed].name;
            assert!(d.a.amax() > 0.0, "{label}: {name} leaves A");
        });
    }

    #[test]
    fn the_plates_geometry_air_and_points_are_exact() {
        // The lengths scale the tables and move every point on the plate; the air's density
        // and Ca the added mass (none in the presets in vacuum, where Ca = 0: its derivative at
        // 0 is still there, the air's density's is zero); Cd the drag, whose law has no slope at
        // rest; the shaker's points the input matrix.
        let seeds = [
            idx::PLATE_A,
            idx::PLATE_B,
            idx::PLATE_RHO_AIR,
            idx::PLATE_CA,
            idx::PLATE_CD,
            idx::PLATE_X1,
            idx::PLATE_Y1,
            idx::PLATE_X2,
            idx::PLATE_Y2,
        ];
        plate_parameters_agree(&seeds, |label, values, seed, d| {
            let name = VARIABLES[seed].name;
            let in_vacuum = values.real(idx::PLATE_CA) == 0.0;
            match seed {
                idx::PLATE_CD => assert!(!moves(d), "{label}: the drag moves the rest"),
                idx::PLATE_RHO_AIR if in_vacuum => {
                    assert!(!moves(d), "{label}: the air moves the plate in vacuum")
                }
                idx::PLATE_X1 | idx::PLATE_Y1 | idx::PLATE_X2 | idx::PLATE_Y2 => {
                    assert!(d.b.amax() > 0.0, "{label}: {name} leaves B")
                }
                _ => assert!(d.a.amax() > 0.0, "{label}: {name} leaves A"),
            }
        });
    }

    #[test]
    fn the_validity_monitors_are_exact() {
        // The bar's diameter sizes the stress monitor's gain 16 / (pi d^3); the strengths set
        // only the warnings' thresholds: they move no output.
        let values = default_values();
        let (d, worst) = agrees_with_central_differences(&values, idx::TORSION_BAR_D);
        eprintln!("torsion_bar.d, default: worst {worst:.3e} of the tolerance");
        assert!(d.c.amax() > 0.0 && d.a.amax() == 0.0);
        for seed in [
            idx::PLATE_SIGMA_Y,
            idx::PLATE_SIGMA_F,
            idx::TORSION_BAR_TAU_Y,
        ] {
            let (d, _) = agrees_with_central_differences(&values, seed);
            assert!(!moves(&d), "{} moves an output", VARIABLES[seed].name);
        }
    }

    #[test]
    fn a_parameter_without_a_derivative_is_refused_by_name() {
        // The pressure feedback at k_pl = 0 is not in the model: no derivative along k_pl.
        let mut values = default_values();
        values.set_real(idx::CONTROLLER_K_PL, 0.0);
        let (_, d) =
            linearization_at_rest_with_derivatives(&values, &[idx::CONTROLLER_K_PL]).unwrap();
        let e = d[0].as_ref().unwrap_err();
        assert!(e.contains("controller.k_pl at 0"), "{e}");
    }

    #[test]
    fn the_servo_valves_derivatives_agree_with_central_differences() {
        // The default configuration: the full servo valve at its null pressures, which move
        // with beta and p_supply (the rest state's own derivative is part of dA/dp there; the
        // test fails without it). The tolerance's reasoning is `STEP`'s.
        let values = default_values();
        let (lin, _) = linearization_at_rest_with_derivatives(&values, &[]).unwrap();
        for seed in [
            idx::SERVO_VALVE_BETA,
            idx::SERVO_VALVE_R_LEAK,
            idx::SERVO_VALVE_P_SUPPLY,
            idx::SERVO_VALVE_K_PHI,
            idx::SERVO_VALVE_L_BOB,
            idx::SERVO_VALVE_K_W,
            idx::SERVO_VALVE_CD,
            idx::SERVO_VALVE_W,
            idx::SERVO_VALVE_D_M,
            idx::SERVO_VALVE_I_M,
        ] {
            let name = VARIABLES[seed].name;
            let (d, _) = agrees_with_central_differences(&values, seed);
            assert!(d.a.amax() > 0.0, "{name}: dA/dp is zero");
            // The rest state moves so that the rates stay zero.
            let p = values.real(seed);
            let f_scale = lin.a.amax() * lin.x0.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(
                d.f.iter().all(|v| v.abs() <= 1e-9 * f_scale / p.abs()),
                "{name}: df/dp at the moving rest {:?}",
                d.f
            );
        }
    }
}
