//! Forward sensitivities of a simulation: the derivatives of the outputs of a time series with
//! respect to the FMU's Real parameters, integrated beside the states (what `hsp identify` fits
//! measured time series with, docs/identify.md).
//!
//! The simulation is the FMU's co-simulation of the configuration: it starts at rest at the
//! first time, its inputs held from one time to the next (zero-order hold), its outputs read at
//! every time. Along a parameter `p` (taken as `p = p0 + c s`, `c` the caller's scale, so that
//! the derivatives come in the units of the states), the states' sensitivity
//! `S = dx/ds` solves the sensitivity equations
//!
//! ```text
//! S' = J(x, u) S + c ∂f/∂p(x, u),    S(t0) = c dx0/dp,
//! dy/ds = C(x, u) S + c ∂y/∂p(x, u),
//! ```
//!
//! with `dx0/dp` the rest state's own derivative ([`Seeded::rest_derivative`]). Their right-hand
//! side is one hyper-dual pass of the model built in dual numbers for the parameter
//! ([`CompiledModel::parameter_derivative`] with the states moving as `S / c`): `J S` and
//! `∂f/∂p` together, exact, without the Jacobian itself or any finite difference.
//!
//! **The integration.** States and sensitivities are one system of `n (1 + k)` equations for `k`
//! parameters, integrated by Radau IIA (RADAU5) at the configuration's tolerances, its error
//! control over the sensitivities too (their absolute tolerance that of the states they belong
//! to: `c` makes them commensurate). Its simplified Newton iteration takes the block-diagonal
//! matrix `diag(J, ..., J)`: the coupling `∂(J S)/∂x` is left out of the iteration matrix, not
//! out of the equations, so the iteration converges to the same collocation solution (the
//! states' block is exact, and the sensitivities follow one iteration behind), as the
//! simultaneous corrector of CVODES does. The block structure keeps the matrix's factorisation
//! at `k + 1` times the model's (the solver's block partition, from the pattern). The
//! sensitivities are therefore those of the exact solution, to the integrator's tolerance; they
//! are not the derivatives of the FMU's own discrete steps (its method may differ:
//! `solver.method`), which agree with them to that tolerance.
//!
//! The model is autonomous with held inputs, and its laws smooth (friction regularised, limits
//! by smooth laws), so the sensitivities are continuous across the inputs' jumps, where the
//! integrator restarts its history as the FMU does.

use std::cell::RefCell;

use nalgebra::DMatrix;

use crate::bond_graph::CompiledModel;
use crate::fmu::{Experiment, FmuModel, LogCategory, Value, Values};
use crate::model::assembly::Assembled;
use crate::model::parameters::Parameters;
use crate::model::variables::{position, VARIABLES};
use crate::model::HydraulicSlewingPlate;
use crate::solver::{Atol, Integrator, Method, OdeSystem};

use super::Seeded;

/// The inputs that drive a simulation, held from one time to the next, and the outputs read.
#[derive(Clone, Copy, Debug)]
pub struct Drive<'a> {
    /// The times, strictly increasing; the simulation starts at rest at the first.
    pub time: &'a [f64],
    /// `(index among the FMU's variables, value at each time)` of each input set.
    pub inputs: &'a [(usize, &'a [f64])],
    /// The outputs read at each time, by their indices among the FMU's variables.
    pub outputs: &'a [usize],
}

impl Drive<'_> {
    /// The configuration `values` with the inputs of time `k`.
    fn values_at(&self, values: &Values, k: usize) -> Values {
        let mut v = values.clone();
        self.set_inputs(&mut v, k);
        v
    }

    /// Sets the inputs of time `k` in `values`.
    fn set_inputs(&self, values: &mut Values, k: usize) {
        for &(i, u) in self.inputs {
            values.set(i, Value::Real(u[k]));
        }
    }

    /// The FMU's experiment over the times.
    fn experiment(&self) -> Experiment {
        Experiment {
            start_time: self.time[0],
            stop_time: self.time.last().copied(),
            ..Experiment::default()
        }
    }

    /// An error unless there are two times or more, strictly increasing.
    fn check(&self) -> Result<(), String> {
        let increasing = self.time.windows(2).all(|w| w[0] < w[1]);
        if self.time.len() < 2 || !increasing {
            return Err("a simulation needs at least two times, strictly increasing".into());
        }
        Ok(())
    }
}

/// The FMU's co-simulation of the configuration `values` driven by `drive`: initialised at rest
/// at the first time with the first inputs, stepped from time to time with each time's inputs
/// held to the next, the outputs read at every time, one vector per output.
pub fn simulate(values: &Values, drive: Drive) -> Result<Vec<Vec<f64>>, String> {
    drive.check()?;
    let mut model = HydraulicSlewingPlate::new();
    let mut log = |_: LogCategory, _: &dyn Fn() -> String| {};
    let experiment = drive.experiment();
    let mut values = drive.values_at(values, 0);
    model
        .initialize(&mut values, &experiment, &mut log)
        .map_err(|e| format!("initialising: {e}"))?;
    let time = drive.time;
    let mut out: Vec<Vec<f64>> = vec![Vec::with_capacity(time.len()); drive.outputs.len()];
    for k in 0..time.len() {
        if k > 0 {
            model
                .do_step(&mut values, time[k - 1], time[k], &mut log)
                .map_err(|e| e.message)?;
            drive.set_inputs(&mut values, k);
        }
        model.refresh(&mut values, None);
        for (o, &i) in drive.outputs.iter().enumerate() {
            out[o].push(values.real(i));
        }
    }
    Ok(out)
}

/// A parameter to differentiate along: its index among the FMU's variables and the scale `c`
/// (module doc: the derivative is `c dy/dp`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Direction {
    pub seed: usize,
    pub scale: f64,
}

/// A simulation's outputs and their sensitivities ([`simulate_with_sensitivities`]).
#[derive(Clone, Debug)]
pub struct SeriesSensitivities {
    /// `outputs[o][k]`: output `o` of [`Drive::outputs`] at time `k`.
    pub outputs: Vec<Vec<f64>>,
    /// Per direction, `c dy_o/dp` at each time (laid out as `outputs`), or why it is not
    /// available (a part whose fragments take `f64` constants).
    pub derivatives: Vec<Result<Vec<Vec<f64>>, String>>,
    /// Steps the integrator took (accepted).
    pub steps: u64,
}

/// Simulates the configuration `values` driven by `drive` (module doc) and integrates the
/// sensitivities along each of `directions` that the model gives in dual numbers; the others
/// get their reason. An error when the simulation itself fails.
pub fn simulate_with_sensitivities(
    values: &Values,
    drive: Drive,
    directions: &[Direction],
) -> Result<SeriesSensitivities, String> {
    drive.check()?;
    let time = drive.time;
    let experiment = drive.experiment();
    let p = Parameters::from_values(values, &experiment)?;
    let mut system = Assembled::new(&p)?;
    let names = system.compiled().output_names();
    let outputs = drive
        .outputs
        .iter()
        .map(|&o| {
            let name = VARIABLES.get(o).map_or("?", |v| v.name);
            names
                .iter()
                .position(|n| position(n) == Some(o))
                .ok_or_else(|| format!("{name} is not an output of the model's equations"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    // The rest state, found with zero inputs, and the sensitivities' start there.
    let x0 = system.initial_state();
    let u0 = system.inputs().to_vec();
    let state_names = system.compiled().state_names().to_vec();
    let mut carried = Vec::new();
    let mut derivatives: Vec<Result<Vec<Vec<f64>>, String>> = Vec::new();
    let mut start = x0.clone();
    for d in directions {
        if !(d.scale.is_finite() && d.scale != 0.0) {
            let name = VARIABLES.get(d.seed).map_or("?", |v| v.name);
            derivatives.push(Err(format!(
                "{name}: the direction's scale {} is not a finite nonzero number",
                d.scale
            )));
            continue;
        }
        let built = Seeded::build(values, &experiment, d.seed, false).and_then(|s| {
            s.check_states(&state_names)?;
            Ok((s.rest_derivative(&x0, &u0)?, s))
        });
        match built {
            Ok((dx0, s)) => {
                start.extend(dx0.iter().map(|v| d.scale * v));
                carried.push((s.compiled, d.scale));
                derivatives.push(Ok(vec![Vec::with_capacity(time.len()); outputs.len()]));
            }
            Err(e) => derivatives.push(Err(e)),
        }
    }
    let mut held = drive.values_at(values, 0);
    system.set_inputs(&held);
    let n = system.dim();
    let mut options = p.solver_options(&system);
    options.method = Method::Radau5;
    let nominal = system.nominal().to_vec();
    options.atol = Atol::Vector(
        (0..=carried.len())
            .flat_map(|_| nominal.iter().map(|v| v * p.atol))
            .collect(),
    );
    let mut integrator = Integrator::new(options, time[0], start).map_err(|e| e.to_string())?;
    let mut augmented = Augmented::new(system, carried);
    let mut out = vec![Vec::with_capacity(time.len()); outputs.len()];
    let mut y = vec![0.0; augmented.system.compiled().n_outputs()];
    for (k, &t) in time.iter().enumerate() {
        if k > 0 {
            drive.set_inputs(&mut held, k - 1);
            if augmented.system.set_inputs(&held) {
                integrator.notify_discontinuity();
            }
            integrator
                .advance_to(&augmented, t)
                .map_err(|e| format!("the simulation with its sensitivities: {e}"))?;
        }
        // The outputs with the inputs held over the step that ends here, as the FMU writes
        // them at the point.
        let z = integrator.x();
        let u = augmented.system.inputs().to_vec();
        augmented.system.compiled().outputs(&z[..n], &u, &mut y);
        for (o, &j) in outputs.iter().enumerate() {
            out[o].push(y[j]);
        }
        let mut carried = augmented.carried.iter().enumerate();
        for d in derivatives.iter_mut().filter_map(|d| d.as_mut().ok()) {
            let (c, (model, scale)) = carried.next().expect("one model per direction carried");
            let (_, dy) = model.parameter_derivative(&z[..n], &along(z, n, c, *scale), &u)?;
            for (o, &j) in outputs.iter().enumerate() {
                d[o].push(scale * dy[j]);
            }
        }
    }
    Ok(SeriesSensitivities {
        outputs: out,
        derivatives,
        steps: integrator.stats().accepted,
    })
}

/// The states' move along the carried direction `c` per unit of its parameter, `S_c / scale`,
/// from the joint state `z` (`n` states, then each direction's `n` sensitivities).
fn along(z: &[f64], n: usize, c: usize, scale: f64) -> Vec<f64> {
    z[n * (1 + c)..n * (2 + c)]
        .iter()
        .map(|v| v / scale)
        .collect()
}

/// States and sensitivities as one system (module doc).
struct Augmented {
    system: Assembled,
    /// Per direction carried: the model in dual numbers for its parameter, and its scale.
    carried: Vec<(CompiledModel, f64)>,
    /// The pattern of `diag(J, ..., J)`.
    pattern: Vec<Vec<u32>>,
    /// The model's Jacobian, copied into each diagonal block.
    jacobian: RefCell<DMatrix<f64>>,
}

impl Augmented {
    fn new(system: Assembled, carried: Vec<(CompiledModel, f64)>) -> Augmented {
        let n = system.dim();
        let own = system.compiled().jacobian_pattern();
        let pattern = (0..=carried.len())
            .flat_map(|b| {
                own.iter().map(move |row| {
                    row.iter()
                        .map(|&j| j + (b * n) as u32)
                        .collect::<Vec<u32>>()
                })
            })
            .collect();
        Augmented {
            system,
            carried,
            pattern,
            jacobian: RefCell::new(DMatrix::zeros(n, n)),
        }
    }
}

impl OdeSystem for Augmented {
    fn dim(&self) -> usize {
        self.system.dim() * (1 + self.carried.len())
    }

    fn rhs(&self, t: f64, z: &[f64], dzdt: &mut [f64]) {
        let n = self.system.dim();
        let (x, dx) = (&z[..n], &mut dzdt[..n]);
        self.system.rhs(t, x, dx);
        let u = self.system.inputs();
        for (c, (model, scale)) in self.carried.iter().enumerate() {
            let range = n * (1 + c)..n * (2 + c);
            match model.parameter_derivative(x, &along(z, n, c, *scale), u) {
                Ok((ds, _)) => {
                    for (o, v) in dzdt[range].iter_mut().zip(ds) {
                        *o = scale * v;
                    }
                }
                // A law without its hyper-dual form (refused by name where the model is
                // built): the step fails on the non-finite rate.
                Err(_) => dzdt[range].fill(f64::NAN),
            }
        }
    }

    fn jacobian(&self, t: f64, z: &[f64], jac: &mut DMatrix<f64>) -> bool {
        let n = self.system.dim();
        let mut own = self.jacobian.borrow_mut();
        if !self.system.jacobian(t, &z[..n], &mut own) {
            return false;
        }
        jac.fill(0.0);
        for b in 0..=self.carried.len() {
            jac.view_mut((b * n, b * n), (n, n)).copy_from(&*own);
        }
        true
    }

    fn jacobian_pattern(&self) -> Option<&[Vec<u32>]> {
        Some(&self.pattern)
    }

    fn is_autonomous(&self) -> bool {
        self.system.is_autonomous()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::variables::idx;

    /// The default configuration's move with a chirp of `r` on top (0.1 V, 0.5 to 10 Hz over
    /// `stop`), held over 5 ms steps: times and `r`.
    fn chirp(stop: f64) -> (Vec<f64>, Vec<f64>) {
        let h = 0.005;
        let steps = (stop / h).round() as usize;
        let time: Vec<f64> = (0..=steps).map(|k| k as f64 * h).collect();
        let (f0, f1) = (0.5, 10.0);
        let r = time
            .iter()
            .map(|&t| {
                let phase = f0 * t + (f1 - f0) * t * t / (2.0 * stop);
                0.1 * crate::math::sin(2.0 * std::f64::consts::PI * phase)
            })
            .collect();
        (time, r)
    }

    /// The default configuration driven by [`chirp`] over `stop`, `y_pot` and `acc_tip` read.
    fn case(stop: f64) -> (Values, Vec<f64>, Vec<f64>) {
        let (time, r) = chirp(stop);
        (Values::from_start(&VARIABLES), time, r)
    }

    #[test]
    fn forward_sensitivities_agree_with_central_differences_of_the_fmu() {
        // An independent check: central differences of the FMU's own simulation (Rodas5P, its
        // co-simulation through `FmuModel`) at rtol 1e-10, relative step 1e-4 (truncation of
        // order 1e-8 of a sensitivity, the integrator's error 1e-10 / 1e-4 = 1e-6 of an output).
        // The forward sensitivities at the default rtol 1e-6 (Radau5) must agree within 2e-5 of
        // each output's largest sensitivity over the run; they agree to 4e-8 to 9.4e-6 (measured),
        // and a sensitivity equation without its `J S` or its `∂f/∂p` term is off by far more.
        // The parameters: the valve's bulk modulus, the bar's stiffness and the move's start
        // time (the command generator's, through its minimum-jerk law).
        let (values, time, r) = case(1.0);
        let inputs = [(idx::R, r.as_slice())];
        let outputs = [idx::Y_POT, idx::ACC_TIP];
        let drive = Drive {
            time: &time,
            inputs: &inputs,
            outputs: &outputs,
        };
        let seeds = [
            idx::SERVO_VALVE_BETA,
            idx::TORSION_BAR_K,
            idx::REFERENCE_T_START,
            idx::Y_POT,
        ];
        let directions: Vec<Direction> = seeds
            .iter()
            .map(|&seed| Direction {
                seed,
                // y_pot is no parameter (refused below); 1 keeps its scale valid.
                scale: if seed == idx::Y_POT {
                    1.0
                } else {
                    values.real(seed)
                },
            })
            .collect();
        let run = simulate_with_sensitivities(&values, drive, &directions).unwrap();
        // The outputs are the FMU's, to its tolerance.
        let fmu = simulate(&values, drive).unwrap();
        for (o, (a, b)) in fmu.iter().zip(&run.outputs).enumerate() {
            let big = a.iter().map(|v| v.abs()).fold(0.0, f64::max);
            let worst = a
                .iter()
                .zip(b)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(worst <= 1e-5 * big, "output {o}: {worst:e} of {big:e}");
        }
        // A variable that is not a parameter is refused, by name.
        let refused = run.derivatives[3].as_ref().unwrap_err();
        assert!(refused.contains("y_pot: not a Real parameter"), "{refused}");
        let mut tight = values.clone();
        tight.set_real(idx::SOLVER_RTOL, 1e-10);
        for (d, s) in directions.iter().zip(&run.derivatives).take(3) {
            let s = s.as_ref().unwrap();
            let h = 1e-4;
            let at = |e: f64| {
                let mut v = tight.clone();
                v.set_real(d.seed, d.scale * (1.0 + e));
                simulate(&v, drive).unwrap()
            };
            let (up, down) = (at(h), at(-h));
            for o in 0..outputs.len() {
                let fd: Vec<f64> = up[o]
                    .iter()
                    .zip(&down[o])
                    .map(|(a, b)| (a - b) / (2.0 * h))
                    .collect();
                let big = fd.iter().map(|v| v.abs()).fold(0.0, f64::max);
                let worst = fd
                    .iter()
                    .zip(&s[o])
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max);
                assert!(
                    big > 0.0 && worst <= 2e-5 * big,
                    "{} output {o}: off by {worst:e} of {big:e}",
                    VARIABLES[d.seed].name
                );
            }
        }
    }

    #[test]
    fn the_start_moves_with_the_rest_state() {
        // The servo valve's chamber volumes at rest (its states, `q = V p / beta`) move with
        // the bulk modulus, its null pressures do not: with no input and no move the pressure
        // `p_1` stays at rest and its sensitivity at zero, which it would not (`p_1 / beta`)
        // if the sensitivities started from zero while the rest state moved.
        let (mut values, time, _) = case(0.2);
        values.set_real(idx::REFERENCE_ANGLE, 0.0);
        let drive = Drive {
            time: &time,
            inputs: &[],
            outputs: &[idx::SERVO_VALVE_P_1],
        };
        let beta = Direction {
            seed: idx::SERVO_VALVE_BETA,
            scale: values.real(idx::SERVO_VALVE_BETA),
        };
        let run = simulate_with_sensitivities(&values, drive, &[beta]).unwrap();
        let dy = &run.derivatives[0].as_ref().unwrap()[0];
        let worst = dy.iter().map(|v| v.abs()).fold(0.0, f64::max);
        let p_1 = run.outputs[0][0];
        assert!(
            worst <= 1e-9 * p_1,
            "p_1's sensitivity at rest: {worst:e} of p_1 = {p_1:e}"
        );
    }

    #[test]
    fn a_drive_needs_increasing_times() {
        let values = Values::from_start(&VARIABLES);
        let drive = Drive {
            time: &[0.0, 0.1, 0.1],
            inputs: &[],
            outputs: &[idx::Y_POT],
        };
        let e = simulate_with_sensitivities(&values, drive, &[]).unwrap_err();
        assert!(e.contains("strictly increasing"), "{e}");
        assert!(simulate(&values, drive).is_err());
    }

    #[test]
    fn a_direction_without_a_scale_is_refused_by_name() {
        let values = Values::from_start(&VARIABLES);
        let drive = Drive {
            time: &[0.0, 0.01],
            inputs: &[],
            outputs: &[idx::Y_POT],
        };
        let zero = Direction {
            seed: idx::TORSION_BAR_K,
            scale: 0.0,
        };
        let run = simulate_with_sensitivities(&values, drive, &[zero]).unwrap();
        let e = run.derivatives[0].as_ref().unwrap_err();
        assert!(e.contains("torsion_bar.k") && e.contains("scale 0"), "{e}");
    }
}
