//! The assembled model as the [`OdeSystem`] the integrator advances: `f`, its Jacobian (constant,
//! or its constant part kept and the varying entries refreshed) and its sparsity pattern.

use super::*;

/// FNV-1a hash of a matrix's bits: identifies a constant Jacobian for the solver's cache.
pub(super) fn stamp(m: &DMatrix<f64>) -> u64 {
    m.iter().fold(fnv1a::OFFSET_BASIS, |h, v| {
        fnv1a::fnv1a64_from(h, &v.to_bits().to_le_bytes())
    })
}

impl OdeSystem for Assembled {
    fn dim(&self) -> usize {
        self.compiled.n_states()
    }

    fn rhs(&self, _t: f64, x: &[f64], dxdt: &mut [f64]) {
        match &self.affine {
            Some(affine) => affine.derivatives(&self.compiled, x, &self.inputs, dxdt),
            None => self.compiled.derivatives(x, &self.inputs, dxdt),
        }
    }

    fn jacobian(&self, _t: f64, x: &[f64], jac: &mut DMatrix<f64>) -> bool {
        match &self.constant_jacobian {
            Some((_, j)) => jac.copy_from(j),
            None => {
                self.compiled.jacobian(x, &self.inputs, jac);
                // The varying entries with the bits `jacobian_varying` gives them, so that a
                // full evaluation and an update of a held matrix agree to the bit (a restored
                // FMU state starts from a full one).
                if self.constant_part.is_some() {
                    self.varying_entries(x, jac);
                }
            }
        }
        true
    }

    fn constant_jacobian(&self) -> Option<u64> {
        self.constant_jacobian.as_ref().map(|(s, _)| *s)
    }

    fn jacobian_constant_part(&self) -> Option<u64> {
        self.constant_part
    }

    fn jacobian_varying(&self, _t: f64, x: &[f64], jac: &mut DMatrix<f64>) -> bool {
        self.constant_part.is_some() && self.varying_entries(x, jac)
    }

    fn jacobian_varying_pattern(&self) -> Option<&[Vec<u32>]> {
        self.constant_part
            .map(|_| self.compiled.jacobian_varying_pattern())
    }

    fn jacobian_pattern(&self) -> Option<&[Vec<u32>]> {
        // The compiled plan's structural dependencies: J is zero outside them at every point.
        Some(self.compiled.jacobian_pattern())
    }

    fn is_autonomous(&self) -> bool {
        // The inputs are held constant over a communication step.
        true
    }
}

impl Assembled {
    /// The Jacobian's varying entries into `jac`: from the forms of the rows that are not affine
    /// where they give finite entries, else through the plan (whose passes handle a law's
    /// infinite slope at a zero weight). Whether they are finite.
    fn varying_entries(&self, x: &[f64], jac: &mut DMatrix<f64>) -> bool {
        let by_forms = |a: &Affine| a.jacobian_varying(&self.compiled, x, &self.inputs, jac);
        self.affine.as_ref().is_some_and(by_forms)
            || self.compiled.jacobian_varying(x, &self.inputs, jac)
    }
}
