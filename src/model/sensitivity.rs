//! Exact sensitivities of the linearisation at rest with respect to the FMU's Real parameters:
//! what `hsp identify` fits frequency responses with (docs/identify.md).
//!
//! For each parameter the model is built again from the parameters in dual numbers seeded on
//! it ([`Parameters::seeded`]): every constant the fragments give the bond graph carries its
//! derivative, lowering folds them into the compiled plan, and hyper-dual passes of the plan
//! give `dA/dp, dB/dp, dC/dp, dD/dp` at the rest state
//! ([`crate::bond_graph::CompiledModel::linearize_with_sensitivity`]). No finite difference.
//!
//! **What is built, what is not.** The parameters of the LOES (`loes.*`) and the torsion bar's
//! stiffness (where the structure is not damped on its own modes) are carried in dual numbers
//! through their fragments; the other parts' fragments still fold their parameters in as `f64`
//! constants, and a parameter of theirs gets an error that says so (`compose::values_only`),
//! which `hsp identify` answers with central differences for that parameter, and says so. The
//! rest state must not move with the parameter (the LOES's rest is zero whatever its
//! constants): where `∂f/∂p` is nonzero at rest the derivative of the rest state would be
//! needed, `-J⁻¹ ∂f/∂p` on the rest state's equations, which is not built yet either.

use crate::bond_graph::{Linearization, LinearizationDerivative};
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
    let experiment = Experiment::default();
    let p = Parameters::from_values(values, &experiment)?.sliding();
    let (_, lin) = Assembled::with_linearization_at_rest(&p)?;
    let derivatives = seeds
        .iter()
        .map(|&seed| derivative_at_rest(values, &experiment, &lin, seed))
        .collect();
    Ok((lin, derivatives))
}

/// The derivative of `lin` (the linearisation at rest of `values`) with respect to the
/// parameter `seed`.
fn derivative_at_rest(
    values: &Values,
    experiment: &Experiment,
    lin: &Linearization,
    seed: usize,
) -> Result<LinearizationDerivative, String> {
    let name = VARIABLES[seed].name;
    let p = Parameters::seeded(values, experiment, seed)?.sliding();
    let (graph, _) = bond_graph_and_plate_for(&p).map_err(|e| format!("{name}: {e}"))?;
    let compiled = graph.compile().map_err(|e| e.to_string())?;
    if compiled.state_names() != lin.state_names.as_slice() {
        return Err(format!(
            "{name}: the model built for its derivative has other states than the model"
        ));
    }
    let still = vec![0.0; lin.x0.len()];
    let (f_p, _) = compiled.parameter_derivative(&lin.x0, &still, &lin.u0)?;
    // The rest state moves with the parameter where the rates at rest do.
    let dx0 = match (f_p.iter().position(|&v| v != 0.0), p.hydraulics) {
        (None, _) => still,
        (Some(_), HydraulicsModel::ServoValve) => rest_state_derivative(
            &compiled,
            &lin.x0,
            &lin.u0,
            &f_p,
            &servo_valve::nominals(&graph),
        )?,
        (Some(i), HydraulicsModel::Loes) => {
            return Err(format!(
                "{name}: the LOES's rest state moves with it (the rate of {} at rest), which it \
                 should not",
                lin.state_names[i]
            ))
        }
    };
    compiled
        .linearize_with_sensitivity(&lin.x0, &dx0, &lin.u0)
        .map_err(|e| format!("{name}: {e}"))
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

    /// The largest miss of `exact` against `fd`, entry by entry, in units of the tolerance
    /// `1e-5 |fd_ij| + 1e-8 (|X|_row i + |X|_col j) / |p|`: relative where the entry is
    /// large, and relative to its row's and column's scale where it is small or zero.
    fn miss(exact: &DMatrix<f64>, fd: &DMatrix<f64>, x: &DMatrix<f64>, p: f64) -> f64 {
        let mut worst = 0.0f64;
        for i in 0..x.nrows() {
            for j in 0..x.ncols() {
                let row = x.row(i).amax();
                let col = x.column(j).amax();
                let tol = 1e-5 * fd[(i, j)].abs() + 1e-8 * (row + col) / p.abs();
                worst = worst.max((exact[(i, j)] - fd[(i, j)]).abs() / tol);
            }
        }
        worst
    }

    #[test]
    fn the_servo_valves_derivatives_agree_with_central_differences() {
        // The default configuration: the full servo valve at its null pressures. Central
        // differences of the whole linearisation at rest (the rest state found again by Newton
        // at each step), relative step 1e-4: the truncation error is of order 1e-8 of a
        // derivative (the model is smooth at rest), the round-off 1e-16 / 1e-4 of an entry;
        // `miss` allows 1e-5 relative. The exact derivatives carry the rest state's own
        // derivative (p_supply and beta move the null pressures and volumes).
        let values = Values::from_start(&VARIABLES);
        let seeds = [
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
        ];
        let (lin, derivatives) = linearization_at_rest_with_derivatives(&values, &seeds).unwrap();
        for (&seed, d) in seeds.iter().zip(&derivatives) {
            let name = VARIABLES[seed].name;
            let d = d.as_ref().unwrap_or_else(|e| panic!("{name}: {e}"));
            let p = values.real(seed);
            let h = 1e-4;
            let at = |s: f64| {
                let mut v = values.clone();
                v.set_real(seed, p * (1.0 + s));
                linearization_at_rest_with_derivatives(&v, &[]).unwrap().0
            };
            let (up, down) = (at(h), at(-h));
            let fd = |a: &DMatrix<f64>, b: &DMatrix<f64>| (a - b) / (2.0 * h * p);
            for (what, exact, fd, x) in [
                ("A", &d.a, fd(&up.a, &down.a), &lin.a),
                ("B", &d.b, fd(&up.b, &down.b), &lin.b),
                ("C", &d.c, fd(&up.c, &down.c), &lin.c),
                ("D", &d.d, fd(&up.d, &down.d), &lin.d),
            ] {
                let m = miss(exact, &fd, x, p);
                assert!(m <= 1.0, "{name}: d{what}/dp misses by {m} tolerances");
            }
            assert!(d.a.amax() > 0.0, "{name}: dA/dp is zero");
            // The rest state moves so that the rates stay zero (the clock's aside).
            let f_scale = lin.a.amax() * lin.x0.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(
                d.f.iter().all(|v| v.abs() <= 1e-9 * f_scale / p.abs()),
                "{name}: df/dp at the moving rest {:?}",
                d.f
            );
        }
    }

    #[test]
    fn a_part_not_built_in_dual_numbers_is_named() {
        let values = Values::from_start(&VARIABLES);
        let (_, d) = linearization_at_rest_with_derivatives(&values, &[idx::PLATE_E]).unwrap();
        let e = d[0].as_ref().unwrap_err();
        assert!(e.contains("plate.E") && e.contains("plate"), "{e}");
    }
}
