//! What the assembled model writes into the FMU's values: the outputs, the stored energy, the
//! continuous states and their derivatives, at every communication point or when read
//! ([`OnDemand`]); and its directional derivatives.

use super::*;

impl Assembled {
    /// Writes the outputs (and the stored energy), the continuous states and their derivatives
    /// for state `x` into the FMU's values. A declared state the model does not have keeps its
    /// value, with derivative 0.
    pub fn write_outputs(&self, x: &[f64], values: &mut Values) {
        match &self.affine {
            Some(
                affine @ Affine {
                    outputs: Some(outputs),
                    ..
                },
            ) => {
                // Linear outputs: y(0, u) + C x instead of a pass through the plan.
                let mut y = [0.0; MAX_AFFINE_OUTPUTS];
                let y = &mut y[..outputs.y0.len()];
                outputs.blocks.product(x, &outputs.y0, y);
                for (i, slot) in self.state_slot.iter().enumerate() {
                    if let Some(k) = *slot {
                        values.set_real(CONTINUOUS_STATES[k].1, affine.derivative(i, x));
                    }
                }
                if affine.partial {
                    // The valve's outputs and rows, as forms.
                    affine.point.for_each(
                        &self.compiled,
                        x,
                        &self.inputs,
                        |k, v| y[k] = v,
                        |i, v| {
                            if let Some(k) = self.state_slot[i] {
                                values.set_real(CONTINUOUS_STATES[k].1, v);
                            }
                        },
                    );
                }
                for (&yk, target) in y.iter().zip(&self.output_index) {
                    if let Some(i) = *target {
                        values.set_real(i, yk);
                    }
                }
            }
            _ => self.write_plan_values(values, |output, derivative| {
                self.compiled
                    .for_each_output_and_derivative(x, &self.inputs, output, derivative)
            }),
        }
        for (slot, &xi) in self.state_slot.iter().zip(x) {
            if let Some(k) = slot {
                values.set_real(CONTINUOUS_STATES[*k].0, xi);
            }
        }
        values.set_real(idx::ENERGY, self.compiled.stored_energy(x));
    }

    /// Writes the derivatives of the declared states at state `x` into the FMU's values: the
    /// right-hand side the integrator advances ([`OdeSystem::rhs`]), computed into `rates`
    /// (resized to the state dimension, kept by the caller so that nothing is allocated once
    /// warm). Model Exchange's derivatives, so that an importer's solver integrates the same
    /// function as the Co-Simulation's.
    pub fn write_derivatives(&self, x: &[f64], rates: &mut Vec<f64>, values: &mut Values) {
        rates.resize(x.len(), 0.0);
        self.rhs(0.0, x, rates);
        for (slot, &r) in self.state_slot.iter().zip(rates.iter()) {
            if let Some(k) = *slot {
                values.set_real(CONTINUOUS_STATES[k].1, r);
            }
        }
    }

    /// Runs `pass`, a pass of the plan that reports compiled outputs `(k, y_k)` and rows of f
    /// `(i, dx_i/dt)`, writing each into its place among the FMU's values (an output that is no
    /// FMU variable, or the row of a state the XML does not declare, is dropped).
    fn write_plan_values(
        &self,
        values: &mut Values,
        pass: impl FnOnce(&mut dyn FnMut(usize, f64), &mut dyn FnMut(usize, f64)),
    ) {
        let values = std::cell::RefCell::new(values);
        pass(
            &mut |k, v| {
                if let Some(i) = self.output_index[k] {
                    values.borrow_mut().set_real(i, v);
                }
            },
            &mut |i, v| {
                if let Some(k) = self.state_slot[i] {
                    values.borrow_mut().set_real(CONTINUOUS_STATES[k].1, v);
                }
            },
        );
    }

    /// Writes what a communication point at state `x` needs at once and leaves the rest until it
    /// is read ([`Assembled::write_on_demand`]), and returns true, when the affine outputs and
    /// derivatives (and the energy of linear storages) are shown to be finite at `x`
    /// (`Affine::finite_within`, `CompiledModel::stored_energy_bound`), so that none of them can
    /// turn out infinite when read. Otherwise (or when the model has nothing to leave) writes
    /// nothing and returns false: the caller writes everything with
    /// [`Assembled::write_outputs`].
    ///
    /// The outputs and derivatives that are not affine (the servo valve's, the plate's air
    /// drag, the reference move: [`crate::bond_graph::PointForms`]) wait too when every state
    /// and input is within the radius their laws' declared value bounds show them finite in
    /// (`Affine::point_radius`, [`crate::bond_graph::PointForms::finite_radius`]); beyond it
    /// (or when a law declares no bound: radius 0) they are written here, as before, and the
    /// stored energy too if a storage is nonlinear without a bound.
    ///
    /// An importer reads a few of the 23 to 31 outputs, and the states and their derivatives
    /// rarely in co-simulation: computing all of them at every point cost as much as the steps
    /// of a linear configuration, and the servo valve's own forms more than a third of a
    /// default run.
    pub fn write_at_point(&self, x: &[f64], values: &mut Values) -> bool {
        let Some(affine) = &self.affine else {
            return false;
        };
        let x_max = max_abs_all(x);
        let energy_finite = self
            .energy_bound
            .is_none_or(|(k, c)| k * x_max * x_max + c < FINITE_BOUND);
        if self.on_demand.is_empty() || !affine.finite_within(x_max) || !energy_finite {
            return false;
        }
        // Not `<=` on its own: a NaN input fails.
        // With no radius (a law without a bound) nothing that is not affine waits, not even at
        // a state and inputs of exactly zero: those values are not left to be read.
        let point_waits = affine.point_radius > 0.0
            && x_max.max(max_abs_all(&self.inputs)) <= affine.point_radius;
        if affine.partial && !point_waits {
            self.write_plan_values(values, |output, derivative| {
                affine
                    .point
                    .for_each(&self.compiled, x, &self.inputs, output, derivative)
            });
        }
        if self.energy_bound.is_none() {
            values.set_real(idx::ENERGY, self.compiled.stored_energy(x));
        }
        true
    }

    /// Is the FMU's variable `index` left by [`Assembled::write_at_point`] to be computed when
    /// it is read?
    pub fn on_demand(&self, index: usize) -> bool {
        self.on_demand
            .get(index)
            .is_some_and(|&d| d != OnDemand::No)
    }

    /// Computes the FMU's variable `index` at state `x` into `values`, if it is one that
    /// [`Assembled::write_at_point`] leaves: the value [`Assembled::write_outputs`] writes, to
    /// the bit. `point` holds the nonlinear results computed so far at the communication point
    /// its stamp names (not 0; a new stamp for each point), which the outputs and derivatives
    /// that are not affine share.
    pub fn write_on_demand(
        &self,
        x: &[f64],
        index: usize,
        values: &mut Values,
        point: (&mut PointCache, u64),
    ) {
        let xu = (x, self.inputs.as_slice());
        let v = match (self.on_demand.get(index), &self.affine) {
            (Some(&OnDemand::PointOutput(k)), Some(a)) => {
                a.point.output(&self.compiled, xu, k as usize, point)
            }
            (Some(&OnDemand::PointDerivative(i)), Some(a)) => {
                a.point.derivative(&self.compiled, xu, i as usize, point)
            }
            (Some(&OnDemand::Output(k)), Some(a)) => a.output(k as usize, x),
            (Some(&OnDemand::State(i)), _) => Some(x[i as usize]),
            (Some(&OnDemand::Derivative(i)), Some(a)) => Some(a.derivative(i as usize, x)),
            (Some(&OnDemand::Energy), _) => Some(self.compiled.stored_energy(x)),
            _ => None,
        };
        if let Some(v) = v {
            values.set_real(index, v);
        }
    }

    /// Exact directional derivatives at state `x` and inputs `u`: `dz = (d unknowns / d
    /// knowns) dv`, with `unknowns` positions of outputs or state derivatives among the FMU's
    /// variables and `knowns` positions of inputs or continuous states (checked by the caller).
    /// One forward pass of dual numbers through the plan.
    pub fn directional_derivative(
        &self,
        x: &[f64],
        u: &[f64],
        (unknowns, knowns): (&[usize], &[usize]),
        dv: &[f64],
        dz: &mut [f64],
    ) -> Result<(), String> {
        let c = &self.compiled;
        let mut vx = vec![0.0; c.n_states()];
        let mut vu = vec![0.0; c.n_inputs()];
        for (&k, &v) in knowns.iter().zip(dv) {
            if let Some(j) = self.input_index.iter().position(|&i| i == k) {
                vu[j] += v;
            } else if let Some(slot) = CONTINUOUS_STATES.iter().position(|&(s, _)| s == k) {
                // A declared state the model does not have moves nothing.
                if let Some(i) = self.state_slot.iter().position(|&s| s == Some(slot)) {
                    vx[i] += v;
                }
            } else {
                return Err(format!(
                    "'{}' is neither an input nor a continuous state of the model",
                    VARIABLES[k].name
                ));
            }
        }
        let mut ddx = vec![0.0; c.n_states()];
        let mut dy = vec![0.0; c.n_outputs()];
        c.directional(x, u, (&vx, &vu), &mut ddx, &mut dy);
        for (&k, out) in unknowns.iter().zip(dz.iter_mut()) {
            *out = if k == idx::ENERGY {
                c.stored_energy_derivative(x, &vx)
            } else if let Some(o) = self.output_index.iter().position(|&i| i == Some(k)) {
                dy[o]
            } else if let Some(slot) = CONTINUOUS_STATES.iter().position(|&(_, d)| d == k) {
                match self.state_slot.iter().position(|&s| s == Some(slot)) {
                    Some(i) => ddx[i],
                    // The derivative of a declared state the model does not have is 0.
                    None => 0.0,
                }
            } else if VARIABLES[k].causality == crate::fmu::Causality::Output {
                // An output of another configuration (the servo valve's with the LOES): 0.
                0.0
            } else {
                return Err(format!(
                    "'{}' is neither an output nor a state derivative of the model",
                    VARIABLES[k].name
                ));
            };
        }
        Ok(())
    }
}

/// Which of the FMU's variables can be left until they are read (see [`OnDemand`]): with affine
/// outputs, those outputs, the declared states and their affine derivatives, and the others
/// when their laws show them finite within a radius (`Affine::point_radius` > 0); none
/// otherwise.
pub(super) fn on_demand(
    compiled: &CompiledModel,
    affine: Option<&Affine>,
    output_index: &[Option<usize>],
    state_slot: &[Option<usize>],
) -> Vec<OnDemand> {
    if affine.is_none_or(|a| a.outputs.is_none()) {
        return Vec::new();
    }
    let mut table = vec![OnDemand::No; VARIABLES.len()];
    let nonaffine = |list: &[u32], i: usize| list.binary_search(&(i as u32)).is_ok();
    let point = affine.is_some_and(|a| a.partial && a.point_radius > 0.0);
    for (k, target) in output_index.iter().enumerate() {
        match (*target, nonaffine(compiled.nonaffine_outputs(), k)) {
            (Some(i), false) => table[i] = OnDemand::Output(k as u32),
            (Some(i), true) if point => table[i] = OnDemand::PointOutput(k as u32),
            _ => {}
        }
    }
    for (i, slot) in state_slot.iter().enumerate() {
        if let Some(k) = *slot {
            let (state, derivative) = CONTINUOUS_STATES[k];
            table[state] = OnDemand::State(i as u32);
            if !nonaffine(compiled.nonaffine_rows(), i) {
                table[derivative] = OnDemand::Derivative(i as u32);
            } else if point {
                table[derivative] = OnDemand::PointDerivative(i as u32);
            }
        }
    }
    table
}
