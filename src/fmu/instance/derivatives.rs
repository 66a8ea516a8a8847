//! Partial derivatives from the model's exact Jacobian: the directional derivative of both FMI
//! versions (the adjoint of FMI 3.0 is built from it, a column per known, by the FMI 3.0 layer).

use super::super::calls::Operation;
use super::super::logging::Short;
use super::super::variables::Causality;
use super::super::{FmuModel, Status};
use super::Instance;

impl<M: FmuModel> Instance<M> {
    /// The checks of a partial-derivative call before anything is computed: the call is allowed
    /// in this state, every value reference is a Real, every unknown an output or a state
    /// derivative and every known an input or a continuous state. Returns the variables'
    /// indices. FMI 3.0's adjoint runs it once up front, so that a call with no knowns is
    /// refused wherever one with knowns would be.
    pub fn check_derivative_call(
        &mut self,
        unknown_vrs: &[u32],
        known_vrs: &[u32],
    ) -> Result<(Vec<usize>, Vec<usize>), Status> {
        self.allowed(Operation::DirectionalDerivative)?;
        let unknowns = self.resolve(unknown_vrs, "Real")?;
        let knowns = self.resolve(known_vrs, "Real")?;
        let states = M::continuous_states();
        for &u in &unknowns {
            let var = &M::variables()[u];
            let derivative = states.iter().any(|&(_, d)| d == u);
            if !(var.causality == Causality::Output || derivative) {
                return Err(self.refuse(&format!(
                    "unknown '{}' (value reference {}) is neither an output nor a state derivative",
                    var.name, var.value_reference
                )));
            }
        }
        for &k in &knowns {
            let var = &M::variables()[k];
            let state = states.iter().any(|&(x, _)| x == k);
            if !(var.causality == Causality::Input || state) {
                return Err(self.refuse(&format!(
                    "known '{}' (value reference {}) is neither an input nor a continuous state",
                    var.name, var.value_reference
                )));
            }
        }
        Ok((unknowns, knowns))
    }

    /// The directional derivative `dv_unknown = (d unknowns / d knowns) dv_known` from the
    /// model's exact Jacobian, at the current point. Unknowns are outputs or state derivatives,
    /// knowns inputs or continuous states (FMI 2.0.4, section 2.1.9; FMI 3.0, section 2.2.11),
    /// all Real. `seed` names the seed argument in messages (`dvKnown` in FMI 2.0, `seed` in
    /// FMI 3.0).
    pub fn directional_derivative(
        &mut self,
        seed: &str,
        unknown_vrs: &[u32],
        known_vrs: &[u32],
        dv_known: &[f64],
        dv_unknown: &mut [f64],
    ) -> Status {
        let (unknowns, knowns) = match self.check_derivative_call(unknown_vrs, known_vrs) {
            Ok(indices) => indices,
            Err(s) => return s,
        };
        if let Some((k, v)) = dv_known.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return self.refuse(&format!("{seed}[{k}] = {v} is not finite"));
        }
        if let Err(s) = self.bring_up_to_date() {
            return s;
        }
        self.model.refresh(&mut self.values, None);
        let result = self.model.directional_derivative(
            &self.values,
            &unknowns,
            &knowns,
            dv_known,
            dv_unknown,
        );
        if let Err(msg) = result {
            return self.refuse(&msg);
        }
        if let Some(k) = dv_unknown.iter().position(|d| !d.is_finite()) {
            let name = M::variables()[unknowns[k]].name;
            return self.refuse(&format!(
                "the derivative of '{name}' is not finite at t = {}",
                Short(self.time)
            ));
        }
        Status::Ok
    }
}
