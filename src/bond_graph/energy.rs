//! Energy bookkeeping of the compiled model: the stored energy `H(x)` and the power balance
//! `dH/dt = P_sources - P_dissipated`.
//!
//! Lowering records one [`Storage`] per I, C or field element (its states and law) and one
//! [`PowerTerm`] per source and resistor (the slots of its bond's effort and flow). The energy
//! of a one-port is `int_0^x phi(s) ds` (in closed form for a linear law, from the law's energy
//! function if given, else by Gauss-Legendre quadrature); a field's is `x' W x / 2`. Its rate is
//! the co-energy variable `phi(x)` (`W x` for a field), the exact gradient of the energy, times
//! `dx/dt`; so [`PowerBalance::residual`] is zero up to round-off for any correctly compiled
//! graph, a cheap check of the compiler and of a model.

use nalgebra::DMatrix;

use super::compiled::CompiledModel;
use super::element::{Law, NonlinearLaw};

/// How a storage element contributes energy and power.
#[derive(Clone, Debug)]
pub(super) enum Storage {
    /// One-port I or C: state index and law.
    One {
        name: String,
        state: usize,
        law: Law,
    },
    /// Field: energy `x' W x / 2` (W = M^-1 for an I-field, K for a C-field).
    Field {
        name: String,
        states: Vec<usize>,
        w: DMatrix<f64>,
    },
}

/// Power term of a source or resistor: `sign * e * f` (delivered for sources, dissipated for R).
#[derive(Clone, Debug)]
pub(super) struct PowerTerm {
    pub(super) name: String,
    /// Slots of the bond's effort and flow.
    pub(super) e: usize,
    pub(super) f: usize,
    pub(super) sign: f64,
    pub(super) source: bool,
}

/// Power balance of the model at a state: `stored_rate = source_power - dissipated_power`
/// (up to round-off), the bond-graph statement of energy conservation.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PowerBalance {
    /// `dE/dt`: rate of change of the total stored energy, `sum(dH/dx_i * dx_i/dt)` over the
    /// storage elements.
    pub stored_rate: f64,
    /// Power delivered by all sources (Se, Sf, modulated or not) into the graph.
    pub source_power: f64,
    /// Power dissipated in all resistors.
    pub dissipated_power: f64,
    /// `stored_rate - (source_power - dissipated_power)`; zero up to round-off.
    pub residual: f64,
    /// Per element: storage rate (I, C, fields), delivered power (sources), dissipated power (R).
    pub elements: Vec<(String, f64)>,
}

impl CompiledModel {
    /// The states that hold energy (of I, C and field elements), ascending: those the stored
    /// energy depends on.
    pub fn storage_states(&self) -> Vec<usize> {
        let mut states: Vec<usize> = self
            .storages
            .iter()
            .flat_map(|st| match st {
                Storage::One { state, .. } => vec![*state],
                Storage::Field { states, .. } => states.clone(),
            })
            .collect();
        states.sort_unstable();
        states.dedup();
        states
    }

    /// Total energy stored in the I, C and field elements at state `x` (integrator states carry
    /// no energy). Nonlinear laws use their energy function if given
    /// ([`NonlinearLaw::with_energy`]), otherwise a Gauss-Legendre quadrature of the law from 0.
    pub fn stored_energy(&self, x: &[f64]) -> f64 {
        assert_eq!(x.len(), self.n_states(), "state vector length");
        self.storages.iter().map(|st| storage_energy(st, x)).sum()
    }

    /// Constants `(K, C)` with |H(x)| ≤ K max_i |x_i|² + C for every x, when every storage is
    /// linear (a one-port with a linear law, or a field: C = 0) or has a law that declares such a
    /// bound ([`super::NonlinearLaw::with_energy_bound`]); None when one does not. Shows the
    /// stored energy finite at x without computing it: K max|x|² + C is finite.
    pub fn stored_energy_bound(&self) -> Option<(f64, f64)> {
        self.storages
            .iter()
            .map(|st| match st {
                Storage::One {
                    law: Law::Linear(k),
                    ..
                } => Some((0.5 / k.v.abs(), 0.0)),
                Storage::One {
                    law: Law::Nonlinear(l) | Law::Conductance(l),
                    ..
                } => l.energy_bound,
                Storage::Field { w, .. } => {
                    Some((0.5 * w.iter().map(|v| v.abs()).sum::<f64>(), 0.0))
                }
            })
            .try_fold((0.0, 0.0), |(k, c), b| b.map(|(kb, cb)| (k + kb, c + cb)))
    }

    /// Stored energy per storage element, in creation order.
    pub fn stored_energies(&self, x: &[f64]) -> Vec<(String, f64)> {
        self.storages
            .iter()
            .map(|st| {
                let name = match st {
                    Storage::One { name, .. } | Storage::Field { name, .. } => name.clone(),
                };
                (name, storage_energy(st, x))
            })
            .collect()
    }

    /// The derivative of the stored energy at `x` in the direction `v`, `sum(dH/dx_i v_i)`: the
    /// co-energy variables (efforts of C, flows of I elements) are the exact gradient of H.
    pub fn stored_energy_derivative(&self, x: &[f64], v: &[f64]) -> f64 {
        assert_eq!(x.len(), self.n_states(), "state vector length");
        assert_eq!(v.len(), self.n_states(), "direction length");
        self.storages.iter().map(|st| storage_rate(st, x, v)).sum()
    }

    /// Power balance at `(x, u)`.
    pub fn power_balance(&self, x: &[f64], u: &[f64]) -> PowerBalance {
        let mut dx = vec![0.0; self.n_states()];
        self.derivatives(x, u, &mut dx);
        self.with_f64(&self.ops, x, u, |s| {
            let mut elements = Vec::new();
            let mut stored_rate = 0.0;
            for st in &self.storages {
                let name = match st {
                    Storage::One { name, .. } | Storage::Field { name, .. } => name,
                };
                let r = storage_rate(st, x, &dx);
                stored_rate += r;
                elements.push((name.clone(), r));
            }
            let mut source_power = 0.0;
            let mut dissipated_power = 0.0;
            for t in &self.power_terms {
                let pw = t.sign * s[t.e] * s[t.f];
                if t.source {
                    source_power += pw;
                } else {
                    dissipated_power += pw;
                }
                elements.push((t.name.clone(), pw));
            }
            PowerBalance {
                stored_rate,
                source_power,
                dissipated_power,
                residual: stored_rate - (source_power - dissipated_power),
                elements,
            }
        })
    }
}

const GL8: [(f64, f64); 8] = [
    (-0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
    (-0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (-0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (-0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
];

/// `int_0^x phi(s) ds` by composite 8-point Gauss-Legendre on 16 panels.
fn quad_energy(law: &NonlinearLaw, x: f64) -> f64 {
    let panels = 16;
    let h = x / panels as f64;
    let mut sum = 0.0;
    for k in 0..panels {
        let a = k as f64 * h;
        for &(t, w) in &GL8 {
            sum += w * law.eval(a + 0.5 * h * (t + 1.0), 0.0).0;
        }
    }
    sum * 0.5 * h
}

/// `dH/dt` of one storage element at `x` when the states move at `v`: the co-energy variables
/// (`dH/dx`) dotted with `v`.
fn storage_rate(st: &Storage, x: &[f64], v: &[f64]) -> f64 {
    match st {
        Storage::One { state, law, .. } => {
            let co = match law {
                Law::Linear(k) => x[*state] / k.v,
                Law::Nonlinear(l) | Law::Conductance(l) => l.eval(x[*state], 0.0).0,
            };
            co * v[*state]
        }
        Storage::Field { states, w, .. } => {
            let mut r = 0.0;
            for (i, &si) in states.iter().enumerate() {
                let co: f64 = states
                    .iter()
                    .enumerate()
                    .map(|(j, &sj)| w[(i, j)] * x[sj])
                    .sum();
                r += co * v[si];
            }
            r
        }
    }
}

#[inline]
fn storage_energy(st: &Storage, x: &[f64]) -> f64 {
    match st {
        Storage::One { state, law, .. } => {
            let v = x[*state];
            match law {
                Law::Linear(k) => 0.5 * v * v / k.v,
                Law::Nonlinear(l) | Law::Conductance(l) => match &l.energy {
                    Some(e) => e(v),
                    None => quad_energy(l, v),
                },
            }
        }
        Storage::Field { states, w, .. } => {
            // ½ xᵀ W x as Σ_j x_j (column j of W)ᵀ x: each column's sum is a chain of its own
            // (the processor overlaps them) over contiguous memory, where one running sum over
            // all (i, j) was a single chain of k² dependent additions, computed at every
            // communication point.
            let e: f64 = states
                .iter()
                .enumerate()
                .map(|(j, &sj)| {
                    let column: f64 = w
                        .column(j)
                        .iter()
                        .zip(states)
                        .map(|(wij, &si)| wij * x[si])
                        .sum();
                    column * x[sj]
                })
                .sum();
            0.5 * e
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quadrature_energy_is_accurate() {
        let law = NonlinearLaw::new("cubic", |q| (q + q * q * q, 1.0 + 3.0 * q * q));
        for q in [-2.0, -0.3, 0.0, 0.7, 5.0] {
            let exact = q * q / 2.0 + q * q * q * q / 4.0;
            assert!((quad_energy(&law, q) - exact).abs() <= 1e-13 * exact.abs().max(1.0));
        }
        let tanh = NonlinearLaw::new("tanh", |q: f64| {
            (crate::math::tanh(q), 1.0 - crate::math::tanh(q).powi(2))
        });
        let exact = crate::math::ln(crate::math::cosh(3.0f64));
        assert!((quad_energy(&tanh, 3.0) - exact).abs() < 1e-12);
    }
}
