//! The checks every law's hyper-dual form ([`NonlinearLaw::with_hyper`]) passes in its module's
//! tests: (a) its value, and the value of the law written once generic in
//! [`crate::math::dual::Real`], are the hand-coded closure's doubles; (b) its derivatives along
//! the argument and the modulator are the hand-coded ones; (c) its mixed second derivative in
//! the argument and one of the law's constants is a central difference of the hand-coded
//! derivative in that constant.

use crate::bond_graph::NonlinearLaw;
use crate::math::dual::{Dual, HyperDual};

/// Zero of both signs, the smallest subnormal and normal doubles, `scale` times the decades
/// from 1e-6 to 1e6 and a few odd multiples, the largest double, and the negatives of all of
/// them: the arguments a law is checked on.
pub fn grid(scale: f64) -> Vec<f64> {
    let mut g = vec![0.0, 5e-324, f64::MIN_POSITIVE, 1e-300, 1e300, f64::MAX];
    for k in -6..=6 {
        g.push(scale * crate::math::powf(10.0, f64::from(k)));
    }
    for c in [0.37, 0.93, 1.0, 1.07, 1.6, 2.9] {
        g.push(scale * c);
    }
    let negative: Vec<f64> = g.iter().map(|x| -x).collect();
    g.extend(negative);
    g
}

/// The law's hyper-dual form, which it must have.
pub fn hyper(law: &NonlinearLaw) -> &(dyn Fn(HyperDual, HyperDual) -> HyperDual + Send + Sync) {
    law.hyper
        .as_deref()
        .unwrap_or_else(|| panic!("{}: no hyper-dual form", law.label))
}

/// (a) At every `(x, m)`: the generic value in `f64`, `generic(x, m)`, the law's hyper-dual
/// form (with zero tangents and with unit ones), its closure's value ([`NonlinearLaw::eval`])
/// and its value-only closure give the same bits.
pub fn assert_same_bits(
    law: &NonlinearLaw,
    generic: impl Fn(f64, f64) -> f64,
    xs: &[f64],
    ms: &[f64],
) {
    let h = hyper(law);
    for &x in xs {
        for &m in ms {
            let closure = law.eval(x, m).0;
            let values = [
                ("generic", generic(x, m)),
                ("value-only closure", (law.value)(x, m)),
                ("hyper-dual", h(HyperDual::from(x), HyperDual::from(m)).v),
                (
                    "hyper-dual with tangents",
                    h(
                        HyperDual::from_parts(x, 1.0, -0.5, 0.25),
                        HyperDual::from_parts(m, 0.5, 1.0, -2.0),
                    )
                    .v,
                ),
            ];
            for (what, v) in values {
                assert_eq!(
                    v.to_bits(),
                    closure.to_bits(),
                    "{}: {what} {v:e} vs the closure's {closure:e} at x {x:e}, m {m:e}",
                    law.label
                );
            }
        }
    }
}

/// `|ad - hand| <= tol max(|hand|, scale)`, plus four units of the smallest subnormal double,
/// for a derivative the two compute through different intermediate products that underflow
/// into the subnormals differently (`c |v| v` at `v` = 5e-324).
fn assert_close(what: &str, ad: f64, hand: f64, tol: f64, scale: f64) {
    assert!(
        (ad - hand).abs() <= tol * hand.abs().max(scale) + 4.0 * f64::from_bits(1),
        "{what}: {ad:e} vs the hand-coded {hand:e} (relative {:e})",
        ((ad - hand) / hand).abs()
    );
}

/// (b) At every `(x, m)` where the law's value and hand-coded derivatives are finite: `dual`
/// (the generic value in [`Dual`] with the law's constants) seeded along `x`, then along `m`,
/// and the law's hyper-dual form seeded along `x` in `ε₁` and along `m` in `ε₂` give the
/// closure's `dphi/dx` and `dphi/dm` to `tol` relative.
///
/// Relative to the larger of the derivative and `scale(x, m)`, for a derivative that the
/// hand-coded and the automatic forms both compute as a sum of terms that cancel (the spool
/// stops' damping in the spool position at null, a ramp far below its corner): the error of
/// either is then a few ulps of the terms, which `scale` gives (the sum of their magnitudes);
/// `(0, 0)` where no terms cancel.
pub fn assert_hand_derivatives(
    law: &NonlinearLaw,
    dual: impl Fn(Dual, Dual) -> Dual,
    xs: &[f64],
    ms: &[f64],
    tol: f64,
    scale: impl Fn(f64, f64) -> (f64, f64),
) {
    let h = hyper(law);
    for &x in xs {
        for &m in ms {
            let (v, dx, dm) = law.eval(x, m);
            if !(v.is_finite() && dx.is_finite() && dm.is_finite()) {
                continue;
            }
            let (sx, sm) = scale(x, m);
            let at = format!("{} at x {x:e}, m {m:e}", law.label);
            let along_x = dual(Dual::new(x, 1.0), Dual::from(m)).d;
            let along_m = dual(Dual::from(x), Dual::new(m, 1.0)).d;
            let both = h(
                HyperDual::from_parts(x, 1.0, 0.0, 0.0),
                HyperDual::from_parts(m, 0.0, 1.0, 0.0),
            );
            assert_close(&format!("{at}: Dual dphi/dx"), along_x, dx, tol, sx);
            assert_close(&format!("{at}: Dual dphi/dm"), along_m, dm, tol, sm);
            assert_close(&format!("{at}: HyperDual dphi/dx"), both.a, dx, tol, sx);
            assert_close(&format!("{at}: HyperDual dphi/dm"), both.b, dm, tol, sm);
        }
    }
}

/// (c) The mixed second derivative of the law `law_of(θ)` (its constant `θ` seeded as
/// `Dual(θ, 1)`) at `(x, m)`, in its argument (or, with `along_m`, its modulator) and `θ`:
/// the hyper-dual form's `ab` part, against the central difference
/// `(D(θ + h) - D(θ - h)) / 2h` of the hand-coded derivative `D` of the laws built for
/// `θ ± h`.
///
/// The difference's error is its truncation, `h² D'''(θ)/6`, plus its rounding, a few ulps of
/// `D` divided by `2h`. The caller picks `h = rel L`, `L` the scale over which `D` varies in
/// `θ` (its derivatives `D^(n) ~ D'/L^(n-1)`), so that the truncation is about `rel²/6` of
/// `D'`; this checks `|ab - fd| <= 10 rel² |fd| + 1e-14 |D| / h` (four times the truncation
/// estimate, and a hundred ulps of rounding), and that `fd` is far above that bound, so that a
/// form that drops the constant's tangent (`ab` = 0) fails.
#[allow(clippy::too_many_arguments)]
pub fn assert_mixed(
    law_of: impl Fn(Dual) -> NonlinearLaw,
    theta: f64,
    rel: f64,
    scale: f64,
    x: f64,
    m: f64,
    along_m: bool,
) {
    let h = rel * scale;
    let law = law_of(Dual::new(theta, 1.0));
    let seed = |v: f64, on: bool| HyperDual::from_parts(v, if on { 1.0 } else { 0.0 }, 0.0, 0.0);
    let ab = hyper(&law)(seed(x, !along_m), seed(m, along_m)).ab;
    let derivative = |t: f64| {
        let (_, dx, dm) = law_of(Dual::from(t)).eval(x, m);
        if along_m {
            dm
        } else {
            dx
        }
    };
    let d = derivative(theta);
    let fd = (derivative(theta + h) - derivative(theta - h)) / (2.0 * h);
    let bound = 10.0 * rel * rel * fd.abs() + 1e-14 * d.abs() / h;
    assert!(
        fd.abs() > 100.0 * bound,
        "{}: the mixed derivative at x {x:e}, m {m:e} is too small to check ({fd:e}, bound {bound:e})",
        law.label
    );
    assert!(
        (ab - fd).abs() <= bound,
        "{}: mixed derivative {ab:e} vs the central difference {fd:e} at x {x:e}, m {m:e} \
         (bound {bound:e})",
        law.label
    );
}
