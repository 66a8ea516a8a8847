//! Stiff test problems with analytic Jacobians and reference solutions.
//!
//! ROBER, VDPOL (ε = 1e-6), HIRES and OREGO are from the Mazzia–Magherini "Test Set for IVP
//! Solvers" (release 2.4); their reference values at the end time are those of
//! docs/model-notes.md, item 19 (from that test set). Prothero–Robinson and the lightly
//! damped oscillator have exact solutions.
//!
//! Absolute tolerances follow the test set's spirit — a component counts as significant
//! from the size at which the problem's end values live — so that the relative scd measure
//! (`scd`) is meaningful for every component:
//! ROBER atol = 1e-14 rtol (y2 ≈ 8e-14 at t = 1e11), HIRES atol = 1e-4 rtol (components
//! 6e-5 … 6e-3), the others atol = rtol (components of order one or larger).

use nalgebra::DMatrix;

use super::{Atol, OdeSystem};

/// A test problem: an [`OdeSystem`] plus its data.
pub trait TestProblem: OdeSystem {
    fn name(&self) -> &'static str;
    fn t0(&self) -> f64 {
        0.0
    }
    fn t_end(&self) -> f64;
    fn y0(&self) -> Vec<f64>;
    /// Reference (or exact) solution at `t_end`.
    fn reference(&self) -> Vec<f64>;
    /// The absolute tolerance to use with relative tolerance `rtol`.
    fn atol(&self, rtol: f64) -> Atol {
        Atol::Scalar(rtol)
    }
}

/// Names accepted by [`problem`].
pub const PROBLEMS: [&str; 6] = [
    "rober",
    "vdpol",
    "hires",
    "orego",
    "prothero-robinson",
    "oscillator",
];

/// Look up a problem by name.
pub fn problem(name: &str) -> Option<Box<dyn TestProblem>> {
    match name.to_ascii_lowercase().as_str() {
        "rober" => Some(Box::new(Rober)),
        "vdpol" => Some(Box::new(Vdpol { eps: 1e-6 })),
        "hires" => Some(Box::new(Hires)),
        "orego" => Some(Box::new(Orego)),
        "prothero-robinson" | "pr" => Some(Box::new(ProtheroRobinson { lambda: -1e6 })),
        "oscillator" => Some(Box::new(Oscillator {
            omega: 1e5,
            zeta: 0.01,
        })),
        _ => None,
    }
}

/// Significant correct digits: -log10(max_i |x_i - r_i| / |r_i|), absolute error where r_i = 0.
pub fn scd(x: &[f64], reference: &[f64]) -> f64 {
    let mut worst: f64 = 0.0;
    for (xi, ri) in x.iter().zip(reference) {
        let e = if *ri == 0.0 {
            (xi - ri).abs()
        } else {
            ((xi - ri) / ri).abs()
        };
        worst = worst.max(if e.is_nan() { f64::INFINITY } else { e });
    }
    -crate::math::log10(worst)
}

/// ROBER: Robertson's chemical kinetics, 3 states, t ∈ [0, 1e11].
pub struct Rober;

impl OdeSystem for Rober {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&self, _t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = -0.04 * y[0] + 1e4 * y[1] * y[2];
        f[2] = 3e7 * y[1] * y[1];
        f[1] = -f[0] - f[2];
    }
    fn jacobian(&self, _t: f64, y: &[f64], j: &mut DMatrix<f64>) -> bool {
        j.fill(0.0);
        j[(0, 0)] = -0.04;
        j[(0, 1)] = 1e4 * y[2];
        j[(0, 2)] = 1e4 * y[1];
        j[(1, 0)] = 0.04;
        j[(1, 1)] = -1e4 * y[2] - 6e7 * y[1];
        j[(1, 2)] = -1e4 * y[1];
        j[(2, 1)] = 6e7 * y[1];
        true
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

impl TestProblem for Rober {
    fn name(&self) -> &'static str {
        "rober"
    }
    fn t_end(&self) -> f64 {
        1e11
    }
    fn y0(&self) -> Vec<f64> {
        vec![1.0, 0.0, 0.0]
    }
    fn reference(&self) -> Vec<f64> {
        vec![
            2.083340149701255e-8,
            8.333360770334713e-14,
            0.999_999_979_166_505, // published as 0.9999999791665050
        ]
    }
    fn atol(&self, rtol: f64) -> Atol {
        Atol::Scalar(1e-14 * rtol)
    }
}

/// VDPOL: van der Pol oscillator in the test set's scaling, y2' = ((1 - y1²) y2 - y1)/ε.
pub struct Vdpol {
    pub eps: f64,
}

impl OdeSystem for Vdpol {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = y[1];
        f[1] = ((1.0 - y[0] * y[0]) * y[1] - y[0]) / self.eps;
    }
    fn jacobian(&self, _t: f64, y: &[f64], j: &mut DMatrix<f64>) -> bool {
        j[(0, 0)] = 0.0;
        j[(0, 1)] = 1.0;
        j[(1, 0)] = (-2.0 * y[0] * y[1] - 1.0) / self.eps;
        j[(1, 1)] = (1.0 - y[0] * y[0]) / self.eps;
        true
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

impl TestProblem for Vdpol {
    fn name(&self) -> &'static str {
        "vdpol"
    }
    fn t_end(&self) -> f64 {
        2.0
    }
    fn y0(&self) -> Vec<f64> {
        vec![2.0, 0.0]
    }
    fn reference(&self) -> Vec<f64> {
        vec![1.706167732170483, -0.8928097010247975]
    }
}

/// HIRES: "High Irradiance RESponse" of photomorphogenesis, 8 states.
pub struct Hires;

impl OdeSystem for Hires {
    fn dim(&self) -> usize {
        8
    }
    fn rhs(&self, _t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = -1.71 * y[0] + 0.43 * y[1] + 8.32 * y[2] + 0.0007;
        f[1] = 1.71 * y[0] - 8.75 * y[1];
        f[2] = -10.03 * y[2] + 0.43 * y[3] + 0.035 * y[4];
        f[3] = 8.32 * y[1] + 1.71 * y[2] - 1.12 * y[3];
        f[4] = -1.745 * y[4] + 0.43 * y[5] + 0.43 * y[6];
        f[5] = -280.0 * y[5] * y[7] + 0.69 * y[3] + 1.71 * y[4] - 0.43 * y[5] + 0.69 * y[6];
        f[6] = 280.0 * y[5] * y[7] - 1.81 * y[6];
        f[7] = -f[6];
    }
    fn jacobian(&self, _t: f64, y: &[f64], j: &mut DMatrix<f64>) -> bool {
        j.fill(0.0);
        j[(0, 0)] = -1.71;
        j[(0, 1)] = 0.43;
        j[(0, 2)] = 8.32;
        j[(1, 0)] = 1.71;
        j[(1, 1)] = -8.75;
        j[(2, 2)] = -10.03;
        j[(2, 3)] = 0.43;
        j[(2, 4)] = 0.035;
        j[(3, 1)] = 8.32;
        j[(3, 2)] = 1.71;
        j[(3, 3)] = -1.12;
        j[(4, 4)] = -1.745;
        j[(4, 5)] = 0.43;
        j[(4, 6)] = 0.43;
        j[(5, 3)] = 0.69;
        j[(5, 4)] = 1.71;
        j[(5, 5)] = -280.0 * y[7] - 0.43;
        j[(5, 6)] = 0.69;
        j[(5, 7)] = -280.0 * y[5];
        j[(6, 5)] = 280.0 * y[7];
        j[(6, 6)] = -1.81;
        j[(6, 7)] = 280.0 * y[5];
        j[(7, 5)] = -280.0 * y[7];
        j[(7, 6)] = 1.81;
        j[(7, 7)] = -280.0 * y[5];
        true
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

impl TestProblem for Hires {
    fn name(&self) -> &'static str {
        "hires"
    }
    fn t_end(&self) -> f64 {
        321.8122
    }
    fn y0(&self) -> Vec<f64> {
        vec![1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0057]
    }
    fn reference(&self) -> Vec<f64> {
        vec![
            7.371312573325668e-4,
            1.442485726316185e-4,
            5.888729740967575e-5,
            1.175651343283149e-3,
            2.386356198831331e-3,
            6.238968252742796e-3,
            2.849998395185769e-3,
            2.850001604814231e-3,
        ]
    }
    fn atol(&self, rtol: f64) -> Atol {
        Atol::Scalar(1e-4 * rtol)
    }
}

/// OREGO: the Oregonator (Belousov–Zhabotinskii reaction), 3 states.
pub struct Orego;

impl OdeSystem for Orego {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&self, _t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = 77.27 * (y[1] + y[0] * (1.0 - 8.375e-6 * y[0] - y[1]));
        f[1] = (y[2] - (1.0 + y[0]) * y[1]) / 77.27;
        f[2] = 0.161 * (y[0] - y[2]);
    }
    fn jacobian(&self, _t: f64, y: &[f64], j: &mut DMatrix<f64>) -> bool {
        j[(0, 0)] = 77.27 * (1.0 - 2.0 * 8.375e-6 * y[0] - y[1]);
        j[(0, 1)] = 77.27 * (1.0 - y[0]);
        j[(0, 2)] = 0.0;
        j[(1, 0)] = -y[1] / 77.27;
        j[(1, 1)] = -(1.0 + y[0]) / 77.27;
        j[(1, 2)] = 1.0 / 77.27;
        j[(2, 0)] = 0.161;
        j[(2, 1)] = 0.0;
        j[(2, 2)] = -0.161;
        true
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

impl TestProblem for Orego {
    fn name(&self) -> &'static str {
        "orego"
    }
    fn t_end(&self) -> f64 {
        360.0
    }
    fn y0(&self) -> Vec<f64> {
        vec![1.0, 2.0, 3.0]
    }
    fn reference(&self) -> Vec<f64> {
        vec![1.000814870318523, 1228.178521549917, 132.0554942846706]
    }
}

/// Prothero–Robinson: y' = λ (y - g(t)) + g'(t) with g = sin, λ = -1e6; exact y = sin t.
/// Non-autonomous (exercises the ∂f/∂t terms of Rosenbrock methods); t ∈ [0, 10].
pub struct ProtheroRobinson {
    pub lambda: f64,
}

impl OdeSystem for ProtheroRobinson {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = self.lambda * (y[0] - crate::math::sin(t)) + crate::math::cos(t);
    }
    fn jacobian(&self, _t: f64, _y: &[f64], j: &mut DMatrix<f64>) -> bool {
        j[(0, 0)] = self.lambda;
        true
    }
    fn time_derivative(&self, t: f64, _y: &[f64], d: &mut [f64]) -> bool {
        d[0] = -self.lambda * crate::math::cos(t) - crate::math::sin(t);
        true
    }
}

impl TestProblem for ProtheroRobinson {
    fn name(&self) -> &'static str {
        "prothero-robinson"
    }
    fn t_end(&self) -> f64 {
        10.0
    }
    fn y0(&self) -> Vec<f64> {
        vec![0.0]
    }
    fn reference(&self) -> Vec<f64> {
        vec![crate::math::sin(10f64)]
    }
}

/// Lightly damped oscillator x'' + 2 ζ ω x' + ω² x = 0 with ω = 1e5 rad/s, ζ = 0.01 (a plate
/// mode / valve spool far out on the imaginary axis), states y1 = x, y2 = x'/ω, x(0) = 1,
/// x'(0) = 0, t ∈ [0, 1e-3] (about 16 periods, amplitude decays to e^-1).
pub struct Oscillator {
    pub omega: f64,
    pub zeta: f64,
}

impl Oscillator {
    /// Exact solution at t.
    pub fn exact(&self, t: f64) -> Vec<f64> {
        let (w, z) = (self.omega, self.zeta);
        let wd = w * (1.0 - z * z).sqrt();
        let e = crate::math::exp(-z * w * t);
        let (s, c) = crate::math::sin_cos(wd * t);
        vec![e * (c + z * w / wd * s), -e * (w / wd) * s]
    }
}

impl OdeSystem for Oscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = self.omega * y[1];
        f[1] = -self.omega * y[0] - 2.0 * self.zeta * self.omega * y[1];
    }
    fn jacobian(&self, _t: f64, _y: &[f64], j: &mut DMatrix<f64>) -> bool {
        j[(0, 0)] = 0.0;
        j[(0, 1)] = self.omega;
        j[(1, 0)] = -self.omega;
        j[(1, 1)] = -2.0 * self.zeta * self.omega;
        true
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

impl TestProblem for Oscillator {
    fn name(&self) -> &'static str {
        "oscillator"
    }
    fn t_end(&self) -> f64 {
        1e-3
    }
    fn y0(&self) -> Vec<f64> {
        vec![1.0, 0.0]
    }
    fn reference(&self) -> Vec<f64> {
        self.exact(self.t_end())
    }
}

/// Result of one test-set run (see [`run`]).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct RunResult {
    pub problem: String,
    pub method: String,
    pub rtol: f64,
    pub atol: f64,
    /// Significant correct digits at the end time (see [`scd`]); `None` if the run failed.
    pub scd: Option<f64>,
    pub steps: u64,
    pub rejected: u64,
    pub f_evals: u64,
    pub jac_evals: u64,
    pub lu: u64,
    pub seconds: f64,
    /// Error message if the integration failed.
    pub error: Option<String>,
}

/// Integrate `prob` from t0 to t_end in one `advance_to` call with the given method and
/// tolerances (`atol = None`: the problem's prescribed atol) and measure the result.
pub fn run(
    prob: &dyn TestProblem,
    method: super::Method,
    rtol: f64,
    atol: Option<f64>,
) -> RunResult {
    use super::{Integrator, SolverOptions};
    let atol = match atol {
        Some(a) => Atol::Scalar(a),
        None => prob.atol(rtol),
    };
    let atol_scalar = atol.get(0);
    let opts = SolverOptions {
        method,
        rtol,
        atol,
        max_steps: 10_000_000,
        ..Default::default()
    };
    let start = std::time::Instant::now();
    let mut integ = match Integrator::new(opts, prob.t0(), prob.y0()) {
        Ok(i) => i,
        Err(e) => {
            return RunResult {
                problem: prob.name().into(),
                method: method.name().into(),
                rtol,
                atol: atol_scalar,
                scd: None,
                steps: 0,
                rejected: 0,
                f_evals: 0,
                jac_evals: 0,
                lu: 0,
                seconds: 0.0,
                error: Some(e.to_string()),
            }
        }
    };
    let res = integ.advance_to(prob, prob.t_end());
    let seconds = start.elapsed().as_secs_f64();
    let s = *integ.stats();
    RunResult {
        problem: prob.name().into(),
        method: method.name().into(),
        rtol,
        atol: atol_scalar,
        scd: res.as_ref().ok().map(|_| scd(integ.x(), &prob.reference())),
        steps: s.accepted,
        rejected: s.rejected,
        f_evals: s.f_evals,
        jac_evals: s.jac_evals,
        lu: s.lu_decompositions,
        seconds,
        error: res.err().map(|e| e.to_string()),
    }
}
