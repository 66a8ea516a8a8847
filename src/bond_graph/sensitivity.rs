//! The derivatives of the linearisation `A, B, C, D` with respect to the parameter the model
//! was built for, exact: hyper-dual numbers through the full plan.
//!
//! A model built for a parameter `p` carries, beside every constant of its plan, the constant's
//! derivative `dc/dp` (the [`crate::math::dual::Dual`] parts of the bond graph's constants,
//! folded through lowering; `plan::ConstantDerivatives`), and each nonlinear law its hyper-dual
//! form, whose own constants carry theirs ([`super::NonlinearLaw::with_hyper`]). One pass of
//! the plan in [`HyperDual`] numbers with `ε₁` seeded on state or input `j` and `ε₂` on the
//! parameter (its constants' derivatives, and the states' own derivative `dx/dp` where the
//! operating point moves with `p`, as a rest state does) gives, in every slot, the value, its
//! derivative in `x_j` (the column `j` of `A` or `B`, `C` or `D`), its total derivative in `p`,
//! and the mixed part: the column `j` of `dA/dp` (`dB/dp`, `dC/dp`, `dD/dp`), the total
//! derivative along `p` of the linearisation at the moving point,
//!
//! ```text
//! dA/dp = ∂²f/∂x∂p + Σ_k ∂²f/∂x∂x_k dx_k/dp,
//! ```
//!
//! the second term the laws' curvature met by the moving operating point. What `hsp identify`
//! needs for the exact sensitivity of a frequency response, `dH/dp = dC X + C (jω - A)⁻¹ (dA X +
//! dB) + dD` with `X = (jω - A)⁻¹ B` (docs/identify.md).
//!
//! A law without a hyper-dual form is evaluated from its first derivatives where that is exact:
//! where its argument and modulator do not move with the parameter (`b` parts 0), or do not
//! move with the seeded state (`a` parts 0); elsewhere its second derivatives would be needed,
//! and the pass refuses, naming the law. Such a law's own constants are taken not to depend on
//! the parameter: a fragment that gives a law constants with derivatives gives it its
//! hyper-dual form.

use nalgebra::DMatrix;

use super::compiled::CompiledModel;
use super::dual::{Constants, Scalar};
use super::element::NonlinearLaw;
use crate::math::dual::HyperDual;

/// The derivatives of `A, B, C, D` along the parameter the model was built for, at an operating
/// point moving with it ([`CompiledModel::linearize_with_sensitivity`]).
#[derive(Clone, Debug)]
pub struct LinearizationDerivative {
    /// `dA/dp`, n x n.
    pub a: DMatrix<f64>,
    /// `dB/dp`, n x m.
    pub b: DMatrix<f64>,
    /// `dC/dp`, p x n.
    pub c: DMatrix<f64>,
    /// `dD/dp`, p x m.
    pub d: DMatrix<f64>,
    /// `df/dp` at the point: the total derivative of the state derivatives (0 where the point
    /// is a rest state that moves with the parameter as `dx/dp` says).
    pub f: Vec<f64>,
    /// `dy/dp` at the point: the outputs' total derivative.
    pub y: Vec<f64>,
}

/// The plan's constants with their derivatives along the parameter in their `b` parts: those
/// of the constants each slot's [`super::plan::Op::Const`] writes (0 for every other slot), and
/// those of the terms' coefficients (none for a model not built for a parameter).
struct AlongParameter<'a> {
    slots: &'a [f64],
    terms: &'a [f64],
}

impl Constants<HyperDual> for AlongParameter<'_> {
    #[inline]
    fn constant(&self, dst: u32, c: f64) -> HyperDual {
        HyperDual::from_parts(c, 0.0, self.slots[dst as usize], 0.0)
    }
    #[inline]
    fn term(&self, t: usize, k: f64, x: HyperDual) -> HyperDual {
        let dk = self.terms.get(t).copied().unwrap_or(0.0);
        x * HyperDual::from_parts(k, 0.0, dk, 0.0)
    }
}

impl Scalar for HyperDual {
    /// The error naming a law without a hyper-dual form where its second derivatives are
    /// needed.
    type Refusal = String;
    #[inline]
    fn cst(c: f64) -> Self {
        HyperDual::from(c)
    }
    #[inline]
    fn scale(self, k: f64) -> Self {
        self * k
    }
    /// A law in hyper-dual numbers: its own form, or its first derivatives where they suffice
    /// (module docs); an error naming it elsewhere.
    fn law(law: &NonlinearLaw, x: Self, m: Self) -> Result<Self, String> {
        if let Some(h) = &law.hyper {
            return Ok(h(x, m));
        }
        let still_in_p = x.b == 0.0 && m.b == 0.0;
        let still_in_x = x.a == 0.0 && m.a == 0.0;
        if !(still_in_p || still_in_x) {
            return Err(format!(
                "the law '{}' has no hyper-dual form (NonlinearLaw::with_hyper): its second \
                 derivatives, which the parameter's sensitivity needs there, are not available",
                law.label
            ));
        }
        let (y, dx, dm) = (law.f)(x.v, m.v);
        Ok(HyperDual::from_parts(
            y,
            dx * x.a + dm * m.a,
            dx * x.b + dm * m.b,
            dx * x.ab + dm * m.ab,
        ))
    }
}

impl CompiledModel {
    /// Whether the model was built for a parameter: some constant of its plan moves with it
    /// (the laws' own constants aside, which only their hyper-dual forms know).
    pub fn has_constant_derivatives(&self) -> bool {
        self.constant_derivatives.is_some()
    }

    /// The derivative of the constant each slot's [`Op::Const`] writes (0 for every other slot).
    fn constant_slot_derivatives(&self) -> Vec<f64> {
        let mut dc = vec![0.0; self.n_slots];
        if let Some(c) = &self.constant_derivatives {
            for &(dst, d) in &c.consts {
                dc[dst as usize] = d;
            }
        }
        dc
    }

    /// Runs the full plan in hyper-dual numbers on `s` (states and inputs set), the constants
    /// carrying their derivatives along the parameter in their `b` parts (`dc` those of the
    /// slots, [`CompiledModel::constant_slot_derivatives`]).
    fn run_hyper(&self, dc: &[f64], s: &mut [HyperDual]) -> Result<(), String> {
        let terms = self
            .constant_derivatives
            .as_ref()
            .map(|c| c.terms.as_slice())
            .unwrap_or(&[]);
        self.run(&self.ops, &AlongParameter { slots: dc, terms }, s)
    }

    /// The derivatives of `A, B, C, D` along the parameter the model was built for, at the
    /// states `x` moving with it as `dx` (`dx/dp`; zeros for a fixed point) and the inputs `u`
    /// (fixed): one hyper-dual pass of the full plan per state and input (module docs). An
    /// error naming a law whose second derivatives it would need and lacks, or when a
    /// derivative is not finite. A model not built for a parameter gives zeros, except where
    /// `dx` moves the point.
    pub fn linearize_with_sensitivity(
        &self,
        x: &[f64],
        dx: &[f64],
        u: &[f64],
    ) -> Result<LinearizationDerivative, String> {
        let (n, m, p) = (self.n_states(), self.n_inputs(), self.n_outputs());
        assert_eq!(x.len(), n, "state vector length");
        assert_eq!(dx.len(), n, "state derivative vector length");
        assert_eq!(u.len(), m, "input vector length");
        let dc = self.constant_slot_derivatives();
        let mut out = LinearizationDerivative {
            a: DMatrix::zeros(n, n),
            b: DMatrix::zeros(n, m),
            c: DMatrix::zeros(p, n),
            d: DMatrix::zeros(p, m),
            f: vec![0.0; n],
            y: vec![0.0; p],
        };
        let mut s = vec![HyperDual::default(); self.n_slots];
        for j in 0..n + m {
            for i in 0..n {
                s[i] = HyperDual::from_parts(x[i], 0.0, dx[i], 0.0);
            }
            for k in 0..m {
                s[n + k] = HyperDual::from(u[k]);
            }
            s[j].a = 1.0;
            self.run_hyper(&dc, &mut s)?;
            let LinearizationDerivative { a, b, c, d, .. } = &mut out;
            self.copy_column(j, &s, |v| v.ab, [a, b, c, d]);
        }
        (out.f, out.y) = self.parameter_parts(&s);
        let finite = |v: &f64| v.is_finite();
        if !(out.a.iter().all(finite)
            && out.b.iter().all(finite)
            && out.c.iter().all(finite)
            && out.d.iter().all(finite)
            && out.f.iter().all(finite)
            && out.y.iter().all(finite))
        {
            return Err(format!(
                "the parameter sensitivity of the linearisation of '{}' is not finite",
                self.name
            ));
        }
        Ok(out)
    }

    /// `(df/dp, dy/dp)` at `(x, u)` with the states moving as `dx` (zeros: the partial
    /// derivatives at a fixed point): one hyper-dual pass without a state seed, which needs no
    /// law's second derivatives. What the rest state's derivative along the parameter solves
    /// for (`-J⁻¹ ∂f/∂p`).
    pub fn parameter_derivative(
        &self,
        x: &[f64],
        dx: &[f64],
        u: &[f64],
    ) -> Result<(Vec<f64>, Vec<f64>), String> {
        let n = self.n_states();
        assert_eq!(x.len(), n, "state vector length");
        assert_eq!(dx.len(), n, "state derivative vector length");
        assert_eq!(u.len(), self.n_inputs(), "input vector length");
        let dc = self.constant_slot_derivatives();
        let mut s = vec![HyperDual::default(); self.n_slots];
        for i in 0..n {
            s[i] = HyperDual::from_parts(x[i], 0.0, dx[i], 0.0);
        }
        for (k, &v) in u.iter().enumerate() {
            s[n + k] = HyperDual::from(v);
        }
        self.run_hyper(&dc, &mut s)?;
        Ok(self.parameter_parts(&s))
    }

    /// `(df/dp, dy/dp)`: the `b` parts of the derivatives' and the outputs' slots of a
    /// hyper-dual pass (the same in every pass, whatever state or input it seeds).
    fn parameter_parts(&self, s: &[HyperDual]) -> (Vec<f64>, Vec<f64>) {
        let part = |slots: &[u32]| slots.iter().map(|&k| s[k as usize].b).collect();
        (part(&self.deriv_slots), part(&self.output_slots))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bond_graph::{BondGraph, Law, NonlinearLaw};
    use crate::math::dual::{Dual, Real};

    /// A mass on a spring and a damper pushed by a force `F` (the module example of
    /// `bond_graph`), with the velocity as output; `m`, `k`, `c` as given (with derivatives).
    /// States `(p, q)`: `dp/dt = F - k q - c p/m`, `dq/dt = p/m`; `y = p/m`.
    fn msd(m: Dual, k: Dual, c: Law) -> crate::bond_graph::CompiledModel {
        let mut g = BondGraph::new("msd");
        let f = g.add_input("F");
        let se = g.add_se("force", f);
        let j = g.add_one("v");
        let mass = g.add_i("mass", m);
        let spring = g.add_c("spring", <Dual as Real>::cst(1.0) / k);
        let damper = g.add_r("damper", c);
        g.bond(se, j);
        let bm = g.bond(j, mass);
        g.bond(j, spring);
        g.bond(j, damper);
        g.add_flow_output("velocity", bm);
        g.compile().unwrap()
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-14 * (1.0 + b.abs())
    }

    #[test]
    fn the_linear_constants_give_the_closed_form_derivatives() {
        let (m, k, c) = (2.0, 100.0, 3.0);
        let x = [0.7, -0.01];
        let zero = [0.0; 2];
        // Along k: A = [[-c/m, -k], [1/m, 0]], so dA/dk = [[0, -1], [0, 0]].
        let model = msd(m.into(), Dual::new(k, 1.0), c.into());
        assert!(model.has_constant_derivatives());
        let d = model.linearize_with_sensitivity(&x, &zero, &[0.0]).unwrap();
        assert_eq!(d.a.as_slice(), &[0.0, 0.0, -1.0, 0.0]);
        assert!(d
            .b
            .iter()
            .chain(d.c.iter())
            .chain(d.d.iter())
            .all(|&v| v == 0.0));
        // df/dp at a fixed point: (-q, 0).
        assert!(close(d.f[0], 0.01) && d.f[1] == 0.0, "{:?}", d.f);
        // Along m: dA/dm = [[c/m², 0], [-1/m², 0]], dC/dm = [-1/m², 0], dy/dm = -p/m².
        let model = msd(Dual::new(m, 1.0), k.into(), c.into());
        let d = model.linearize_with_sensitivity(&x, &zero, &[0.0]).unwrap();
        assert!(close(d.a[(0, 0)], c / (m * m)) && close(d.a[(1, 0)], -1.0 / (m * m)));
        assert_eq!((d.a[(0, 1)], d.a[(1, 1)]), (0.0, 0.0));
        assert!(close(d.c[(0, 0)], -1.0 / (m * m)) && d.c[(0, 1)] == 0.0);
        assert!(close(d.y[0], -x[0] / (m * m)));
        // Along c: dA/dc = [[-1/m, 0], [0, 0]].
        let model = msd(m.into(), k.into(), Dual::new(c, 1.0).into());
        let d = model.linearize_with_sensitivity(&x, &zero, &[0.0]).unwrap();
        assert!(close(d.a[(0, 0)], -1.0 / m));
        assert_eq!(d.a.iter().filter(|&&v| v != 0.0).count(), 1);
        // A model built for no parameter gives zeros, and has no derivatives to carry.
        let model = msd(m.into(), k.into(), c.into());
        assert!(!model.has_constant_derivatives());
        let d = model.linearize_with_sensitivity(&x, &zero, &[0.0]).unwrap();
        assert!(d.a.iter().chain(d.f.iter()).all(|&v| v == 0.0));
    }

    /// A cubic damper `e = c3 f³` with its hyper-dual form, `c3` captured with its derivative.
    fn cubic(c3: Dual) -> Law {
        let law = NonlinearLaw::new("cubic damper", move |f| {
            (c3.v * f * f * f, 3.0 * c3.v * f * f)
        })
        .with_hyper(move |f, _| f * f * f * HyperDual::from(c3));
        Law::Nonlinear(law)
    }

    #[test]
    fn a_law_and_a_moving_point_give_the_closed_form_derivatives() {
        let (m, k, c3) = (2.0, 100.0, 0.5);
        let (p, q) = (0.7, -0.01);
        let v = p / m;
        // dp/dt = F - k q - c3 (p/m)³: A00 = -3 c3 v² / m.
        // Along c3 at a fixed point: dA00/dc3 = -3 v² / m.
        let model = msd(m.into(), k.into(), cubic(Dual::new(c3, 1.0)));
        let d = model
            .linearize_with_sensitivity(&[p, q], &[0.0, 0.0], &[0.0])
            .unwrap();
        let expected = -3.0 * v * v / m;
        assert!(
            (d.a[(0, 0)] - expected).abs() < 1e-14,
            "{} {expected}",
            d.a[(0, 0)]
        );
        // A point moving with the parameter as dp/dc3 = 0.3: the law's curvature adds
        // d(A00)/dp * 0.3 = -6 c3 v / m² * 0.3.
        let d = model
            .linearize_with_sensitivity(&[p, q], &[0.3, 0.0], &[0.0])
            .unwrap();
        let expected = -3.0 * v * v / m - 6.0 * c3 * v / (m * m) * 0.3;
        assert!(
            (d.a[(0, 0)] - expected).abs() < 1e-14,
            "{} {expected}",
            d.a[(0, 0)]
        );
        // df/dc3 with the point moving: -v³ - 3 c3 v² 0.3/m - (p moving adds nothing else).
        let expected_f = -v * v * v - 3.0 * c3 * v * v * 0.3 / m;
        assert!(
            (d.f[0] - expected_f).abs() < 1e-14,
            "{} {expected_f}",
            d.f[0]
        );
        assert!((d.f[1] - 0.3 / m).abs() < 1e-15);
    }

    #[test]
    fn a_law_without_its_hyper_form_is_refused_where_its_curvature_is_needed() {
        let law = NonlinearLaw::new("cubic damper, no hyper form", |f| (f * f * f, 3.0 * f * f));
        let model = msd(
            Dual::new(2.0, 1.0),
            100.0.into(),
            Law::Nonlinear(law.clone()),
        );
        // The mass moves the law's argument p/m: its second derivative would be needed.
        let e = model
            .linearize_with_sensitivity(&[0.7, 0.0], &[0.0, 0.0], &[0.0])
            .unwrap_err();
        assert!(e.contains("cubic damper, no hyper form"), "{e}");
        // The first derivatives suffice for df/dp, and where nothing moves the argument.
        assert!(model
            .parameter_derivative(&[0.7, 0.0], &[0.0, 0.0], &[0.0])
            .is_ok());
        let model = msd(2.0.into(), Dual::new(100.0, 1.0), Law::Nonlinear(law));
        let d = model
            .linearize_with_sensitivity(&[0.7, 0.0], &[0.0, 0.0], &[0.0])
            .unwrap();
        assert_eq!(d.a.as_slice(), &[0.0, 0.0, -1.0, 0.0]);
    }

    #[test]
    fn a_fields_derivative_is_carried_through_its_inverse() {
        // Two masses in one I-field M, each on its own spring of stiffness 1: dq_i/dt = (M^-1
        // p)_i, so the block dA[q, p] = d(M^-1)/dp = -M^-1 dM M^-1.
        let mass = DMatrix::from_row_slice(2, 2, &[2.0, 0.5, 0.5, 1.0]);
        let dm = DMatrix::from_row_slice(2, 2, &[1.0, 0.25, 0.25, 0.0]);
        let mut g = BondGraph::new("field");
        let field = g.add_i_field("M", mass.clone());
        g.set_field_derivative(field, dm.clone());
        for i in 0..2 {
            let j = g.add_one(format!("v{i}"));
            let s = g.add_c(format!("k{i}"), 1.0);
            g.bond(j, field);
            g.bond(j, s);
        }
        let model = g.compile().unwrap();
        assert!(model.has_constant_derivatives());
        let names = model.state_names().to_vec();
        let n = names.len();
        let d = model
            .linearize_with_sensitivity(&vec![0.1; n], &vec![0.0; n], &[])
            .unwrap();
        let minv = mass.try_inverse().unwrap();
        let expected = -(&minv * &dm * &minv);
        let p = |i: usize| names.iter().position(|s| s == &format!("M.p[{}]", i + 1));
        let q = |i: usize| names.iter().position(|s| s == &format!("k{i}.q"));
        for r in 0..2 {
            for c in 0..2 {
                let got = d.a[(q(r).unwrap(), p(c).unwrap())];
                assert!(
                    (got - expected[(r, c)]).abs() < 1e-15,
                    "{got} {}",
                    expected[(r, c)]
                );
            }
        }
    }
}
