//! RADAU5's tunables, gathered with their defaults ([`Radau5Options`]).

/// The tunables of the Radau IIA integrator, in the manner of the IWORK/WORK parameters of
/// Hairer's RADAU5: each field gives its meaning, its RADAU5 name (IWORK(n), WORK(n), or the
/// variable of RADCOR or ESTRAD where the Fortran hard-codes it) and its default. The defaults
/// are the numbers the integrator runs with; they are RADAU5's own, except for the step map's
/// settings, which RADAU5 does not have.
///
/// The integrator uses `Radau5Options::default()`; they are not part of
/// [`SolverOptions`](crate::solver::SolverOptions), which the integrator saves with its state.
///
/// RADAU5's other parameters are elsewhere or fixed: IWORK(2) (NMAX) corresponds to
/// [`SolverOptions::max_steps`](crate::solver::SolverOptions::max_steps) (per call), WORK(7)
/// (HMAX) to [`SolverOptions::max_step`](crate::solver::SolverOptions::max_step), WORK(1)
/// (UROUND) is `f64::EPSILON`; the Newton start values are always the extrapolated collocation polynomial
/// (IWORK(4) = 0), the step-size strategy always Gustafsson's predictive controller
/// (IWORK(8) = 1), and J is never transformed to Hessenberg form (IWORK(1) = 0). The method's
/// coefficients ([`nodes`](super::nodes), [`T`](super::T), …) and the tolerance transformation
/// rtol' = 0.1 rtol^(2/3) are not tunables: they define the method and what rtol means.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Radau5Options {
    /// Most simplified Newton iterations per step attempt; an attempt that needs more is
    /// rejected, and the convergence monitor gives up early when the predicted error after
    /// this many is too large. RADAU5's NIT, IWORK(3). Default 7, RADAU5's.
    pub nit: usize,
    /// Safety factor of the step-size prediction, h_new = h · fac / err^(1/4) with
    /// fac = min(safe, (1 + 2 NIT) safe / (NEWT + 2 NIT)), so that it falls with the Newton
    /// iterations NEWT used; also divides Gustafsson's predicted factor. RADAU5's SAFE,
    /// WORK(2). Default 0.9, RADAU5's.
    pub safe: f64,
    /// Jacobian reuse threshold: after an accepted step, J is kept (and with [`quot1`] and
    /// [`quot2`] the step size and its factorisations too) while the Newton contraction
    /// estimate θ stays at or below it; otherwise J is evaluated afresh. Also the contraction
    /// a mapped step reports, and the Newton iteration's θ before it has an estimate. RADAU5's
    /// THET, WORK(3). Default 0.001, RADAU5's, which it recommends for small systems (it
    /// suggests 0.1 when evaluating J is costly).
    ///
    /// [`quot1`]: Radau5Options::quot1
    /// [`quot2`]: Radau5Options::quot2
    pub thet: f64,
    /// Cap of the Newton stopping criterion FNEWT = max(10 UROUND / rtol', min(fnewt_cap,
    /// √rtol')), rtol' the transformed relative tolerance: the iteration stops when
    /// η_k ‖ΔW^k‖ ≤ FNEWT (Hairer & Wanner IV.8, κ·Tol of the "stopping criterion"). RADAU5's
    /// default of FNEWT, WORK(4) (the 0.03 of MIN(0.03D0, RTOL**0.5D0)). Default 0.03, RADAU5's.
    pub fnewt_cap: f64,
    /// Lower end of the window in which the step size is kept: when the proposed
    /// h_new / h lies in [quot1, quot2] and θ ≤ [`thet`](Radau5Options::thet), the next step
    /// has the same h and goes on with J and its factorisations (no new LU). RADAU5's QUOT1,
    /// WORK(5). Default 1.0, RADAU5's (for small systems; it suggests 0.99 for large full
    /// ones).
    pub quot1: f64,
    /// Upper end of the window of [`quot1`](Radau5Options::quot1). RADAU5's QUOT2, WORK(6).
    /// Default 1.2, RADAU5's (it suggests 2.0 for large full systems).
    pub quot2: f64,
    /// Largest factor by which the step-size prediction shrinks a step: h_new ≥ h / facl.
    /// RADAU5's FACL = 1/WORK(8).
    /// Default 5.0, RADAU5's (WORK(8) = 0.2).
    pub facl: f64,
    /// Reciprocal of the largest factor by which the step-size prediction lets a step grow:
    /// h_new ≤ h / facr. RADAU5's FACR = 1/WORK(9). Default 0.125, RADAU5's (WORK(9) = 8).
    pub facr: f64,
    /// Exponent with which the convergence-rate estimate FACCON carried from the last step is
    /// aged at the start of each step's Newton iteration (FACCON = max(FACCON, UROUND)^0.8,
    /// which moves an estimate below 1 towards 1), and at each mapped step. RADCOR's 0.8D0.
    /// Default 0.8, RADAU5's.
    pub faccon_exponent: f64,
    /// Contraction θ at or above which the Newton iteration is taken to diverge: the attempt
    /// is rejected with h · [`unexpected_reject`](Radau5Options::unexpected_reject). RADCOR's
    /// 0.99D0. Default 0.99, RADAU5's.
    pub theta_diverge: f64,
    /// Safety factor of the step cut when Newton converges too slowly to finish within
    /// [`nit`](Radau5Options::nit) iterations: h_new = hhfac_safety · qnewt^(-1/(4 + NIT - 1 -
    /// NEWT)), qnewt the predicted error over FNEWT. RADCOR's HHFAC = .8D0*…. Default 0.8,
    /// RADAU5's.
    pub hhfac_safety: f64,
    /// Lower bound of qnewt in that step cut (RADCOR's QNEWT = MAX(1.0D-4, …)); the cut is
    /// made only for qnewt ≥ 1, so the bound does not act. Default 1e-4, RADAU5's.
    pub qnewt_min: f64,
    /// Upper bound of qnewt in that step cut (RADCOR's QNEWT = …MIN(20.0D0, DYTH)). Default
    /// 20, RADAU5's: the cut is never below hhfac_safety · 20^(-1/(4 + NIT - 1 - NEWT)).
    pub qnewt_max: f64,
    /// Factor of h after an attempt fails other than by the error test: a singular iteration
    /// matrix, f or the Newton increments not finite, Newton diverging
    /// ([`theta_diverge`](Radau5Options::theta_diverge)) or out of iterations. RADCOR's
    /// "unexpected step-rejection", label 78, H = H*0.5D0. Default 0.5, RADAU5's.
    pub unexpected_reject: f64,
    /// Most singular iteration matrices in one call: at the `nsing`-th the call gives up with
    /// [`SolverErrorKind::SingularMatrix`](crate::solver::SolverErrorKind::SingularMatrix)
    /// instead of halving h again. RADAU5's NSING (RADCOR, label 78: `NSING=NSING+1; IF
    /// (NSING.GE.5) GOTO 176`, "MATRIX IS REPEATEDLY SINGULAR", IDID = −4), counted over the
    /// call, not reset by an accepted step. Default 5, RADAU5's. Why give up: a singular
    /// (γ/h) I − J means γ/h (or (α ± iβ)/h) is an eigenvalue of J, or J's entries swamp the
    /// diagonal; halving h a few times moves past an eigenvalue, and a matrix that stays
    /// singular after that will stay so (without the limit the step was halved up to
    /// `max_consecutive_rejections` = 50 times, to 1e-15 of itself, before failing).
    pub nsing: u32,
    /// Factor of h when the first step (of a start, or after a discontinuity) is rejected by
    /// the error test, in place of the controller's proposal. RADCOR's H = H*0.1D0 (IF FIRST).
    /// Default 0.1, RADAU5's.
    pub first_reject: f64,
    /// Floor of the error estimate's norm, of ESTRAD's and of a mapped step's
    /// (ESTRAD's ERR = MAX(SQRT(ERR/N), 1.D-10)). Default 1e-10, RADAU5's.
    pub err_floor: f64,
    /// Floor of the error remembered for Gustafsson's predictive controller (RADCOR's
    /// ERRACC = MAX(1.0D-2, ERR)): it bounds Gustafsson's factor (err² / ERRACC)^(1/4) of the
    /// next accepted step after one with a very small error. Default 1e-2, RADAU5's.
    pub erracc_floor: f64,
    /// Largest system whose steps may be taken as affine maps (a constant J of an autonomous
    /// system; see the module documentation of [`super`]); above it the ordinary steps' structured
    /// solves are cheaper than the map's dense product. No RADAU5 counterpart. Default 128, the
    /// bound the solver uses for every dense map (and Rodas5P's explicit inverse), measured
    /// with the LOES and the plate.
    pub map_max_dim: usize,
    /// A factorisation's step map is built once it has served ⌈n / map_after_divisor⌉ steps
    /// (n states). Building costs n + 1 responses of three solves each, about as much as n/2
    /// ordinary steps (each a few f evaluations and three solves), so a factorisation that has
    /// already served that many is likely to serve as many more (the cost of building never
    /// exceeds that of the steps taken without the map by much, whatever the run of steps at
    /// one size). At least 1. No RADAU5 counterpart. Default 2.
    pub map_after_divisor: usize,
}

impl Default for Radau5Options {
    fn default() -> Self {
        Radau5Options {
            nit: 7,
            safe: 0.9,
            thet: 0.001,
            fnewt_cap: 0.03,
            quot1: 1.0,
            quot2: 1.2,
            facl: 5.0,
            facr: 0.125,
            faccon_exponent: 0.8,
            theta_diverge: 0.99,
            hhfac_safety: 0.8,
            qnewt_min: 1e-4,
            qnewt_max: 20.0,
            unexpected_reject: 0.5,
            nsing: 5,
            first_reject: 0.1,
            err_floor: 1e-10,
            erracc_floor: 1e-2,
            map_max_dim: crate::solver::step_map::MAX_DIM,
            map_after_divisor: 2,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Radau5Options;

    /// The defaults are RADAU5's: its IWORK/WORK defaults (FACL and FACR the reciprocals of
    /// WORK(8) = 0.2 and WORK(9) = 8) and the numbers RADCOR and ESTRAD hard-code.
    #[test]
    fn the_defaults_are_radau5s() {
        let o = Radau5Options::default();
        assert_eq!((o.nit, o.safe, o.thet, o.fnewt_cap), (7, 0.9, 0.001, 0.03));
        assert_eq!((o.quot1, o.quot2, o.facl, o.facr), (1.0, 1.2, 5.0, 0.125));
        assert_eq!((o.faccon_exponent, o.theta_diverge), (0.8, 0.99));
        assert_eq!(
            (o.hhfac_safety, o.qnewt_min, o.qnewt_max),
            (0.8, 1e-4, 20.0)
        );
        assert_eq!((o.unexpected_reject, o.first_reject), (0.5, 0.1));
        assert_eq!(o.nsing, 5);
        assert_eq!((o.err_floor, o.erracc_floor), (1e-10, 1e-2));
        assert_eq!((o.map_max_dim, o.map_after_divisor), (128, 2));
    }
}
