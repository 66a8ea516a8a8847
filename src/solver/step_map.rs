//! A step of fixed size as one affine map, for systems that are affine in x.
//!
//! When f(t, x) = J x + c with a constant Jacobian J ([`OdeSystem::constant_jacobian`]) and an
//! autonomous right-hand side, every quantity a one-step method computes in a step of size h is
//! affine in the step's start x0: the stage values solve linear systems whose right-hand sides
//! are affine in x0, and the end point and the error estimate are linear combinations of them.
//! So a step is `y = L x0 + a` for an `m × n` matrix L and a vector a that depend only on J, h
//! and c. [`StepMap`] holds them; a method fills L column by column with its own stage formulas
//! applied to f ≡ J e_j (the response to the unit start e_j without the constant part), and a
//! with the same formulas applied to f ≡ c. Its steps then cost one dense product with L (2 n²
//! flops for the end point and the error estimate together) instead of the stage evaluations
//! and the solves with the iteration matrices.
//!
//! The map is exact up to rounding: the simplified Newton iteration of an implicit method
//! converges in one iteration on a linear problem whose Jacobian it has exactly, and the map
//! holds that converged result. It is rebuilt from the same factorisation with the same bits,
//! so an integrator restored from a saved state, which rebuilds its factorisations, makes the
//! same map and goes on bit-identically.
//!
//! Building it costs n + 1 responses, each a few solves with the iteration matrices, so a
//! method builds it only for a factorisation that has served a number of steps already, and
//! only while n is small enough for the dense product to be the cheaper path
//! ([`MAX_DIM`]).
//!
//! [`OdeSystem::constant_jacobian`]: super::OdeSystem::constant_jacobian

use nalgebra::DMatrix;

/// Largest system for which a step map (and Rodas5P's explicit inverse) is built. A mapped step
/// costs 2n² multiply-adds (the map's 2n rows), against the ordinary step's solves, whose cost
/// grows about linearly with n for the plate's arrowhead matrices; at 128 states the product is
/// 33 000 multiply-adds, about what the structured step costs there. Measured with the LOES and
/// the plate: faster at 36 states (3 x 5 plate, Radau IIA 4x) and 78 (6 x 6, 2.8x); the 294 of a
/// 12 x 12 plate are left to the structured solves.
pub(crate) const MAX_DIM: usize = 128;

/// `y = L x + a`, with L stored column by column (`rows` × `n`) and the offsets `c` of f the
/// constant part `a` was made for; or nothing yet (`rows == 0`), its memory kept for the next
/// build, so that a map remade for a new factorisation allocates nothing.
#[derive(Debug, Default)]
pub(crate) struct StepMap {
    rows: usize,
    lin: Vec<f64>,
    aff: Vec<f64>,
    c: Vec<f64>,
}

impl StepMap {
    /// Is there a map (since the last [`StepMap::clear`])?
    pub fn is_built(&self) -> bool {
        self.rows > 0
    }

    /// Takes the memory of a map with `rows` outputs of `n` states now, so that building it
    /// later allocates nothing (it is built in the middle of a run, after some steps).
    pub fn reserve(&mut self, rows: usize, n: usize) {
        self.lin.reserve_exact(rows * n);
        self.aff.reserve_exact(rows);
        self.c.reserve_exact(n);
    }

    /// Forgets the map (its factorisation changed), keeping the memory.
    pub fn clear(&mut self) {
        self.rows = 0;
    }

    /// Makes the map with `rows` outputs for the Jacobian `jac` and the constant part `c` of f:
    /// `response(v, out)` writes into `out` (`rows` long) what a step computes when f ≡ v at
    /// every stage and at the step's start, leaving out the start state itself.
    pub fn build(
        &mut self,
        rows: usize,
        jac: &DMatrix<f64>,
        c: &[f64],
        mut response: impl FnMut(&[f64], &mut [f64]),
    ) {
        let n = jac.ncols();
        self.lin.resize(rows * n, 0.0);
        for (j, column) in self.lin.chunks_exact_mut(rows).enumerate() {
            response(jac.column(j).as_slice(), column);
        }
        self.aff.resize(rows, 0.0);
        response(c, &mut self.aff);
        self.c.clear();
        self.c.extend_from_slice(c);
        self.rows = rows;
    }

    /// Was the constant part made for these offsets of f (bit for bit)?
    pub fn fits(&self, c: &[f64]) -> bool {
        self.c.len() == c.len()
            && self
                .c
                .iter()
                .zip(c)
                .all(|(a, b)| a.to_bits() == b.to_bits())
    }

    /// Remakes the constant part for new offsets `c` of f (the held inputs changed): one
    /// response.
    pub fn refit(&mut self, c: &[f64], response: impl FnOnce(&[f64], &mut [f64])) {
        response(c, &mut self.aff);
        self.c.clear();
        self.c.extend_from_slice(c);
    }

    /// `y = L x + a` (`y` is `rows` long), a column at a time ([`super::dense::product`]).
    pub fn apply(&self, x: &[f64], y: &mut [f64]) {
        super::dense::product(&self.lin, self.rows, Some(&self.aff), x, y);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A response that is affine in v stands for itself: applying the map to x gives
    /// response(J x) + response(c), the step of the affine f at x.
    #[test]
    fn the_map_of_a_linear_response_is_its_matrix() {
        let jac = DMatrix::from_row_slice(2, 2, &[-1.0, 2.0, 0.5, -3.0]);
        // rows: 2v and v0 - v1.
        let response = |v: &[f64], out: &mut [f64]| {
            out[0] = 2.0 * v[0];
            out[1] = 2.0 * v[1];
            out[2] = v[0] - v[1];
        };
        let c = [0.25, -0.5];
        let mut map = StepMap::default();
        assert!(!map.is_built());
        map.build(3, &jac, &c, response);
        assert!(map.is_built());
        let x = [1.5, -2.0];
        let mut y = [0.0; 3];
        map.apply(&x, &mut y);
        let f = [
            jac[(0, 0)] * x[0] + jac[(0, 1)] * x[1] + c[0],
            jac[(1, 0)] * x[0] + jac[(1, 1)] * x[1] + c[1],
        ];
        let mut want = [0.0; 3];
        response(&f, &mut want);
        for (a, b) in y.iter().zip(want) {
            assert!(
                (a - b).abs() <= 1e-14 * b.abs().max(1.0),
                "{y:?} against {want:?}"
            );
        }
        assert!(map.fits(&c));
        let c2 = [1.0, 0.0];
        assert!(!map.fits(&c2));
        map.refit(&c2, response);
        assert!(map.fits(&c2));
        map.apply(&[0.0, 0.0], &mut y);
        assert_eq!(y, [2.0, 0.0, 1.0]);
        map.clear();
        assert!(!map.is_built());
    }
}
