//! The confidence intervals of a fit and what its data cannot determine, from the Jacobian `J`
//! of the weighted residuals with respect to the parameters' coordinates `z` (`ln p`, or `p`
//! over its scale) at the optimum.
//!
//! - Residual variance `s^2 = cost / (N - k)` (`N` real residuals, `k` parameters), so the
//!   weights need only be relative; `s^2 = 1` where the residuals are in units of known standard
//!   uncertainties (measured peaks alone, `super::peaks`), with a warning when the cost exceeds
//!   the 95 % quantile of chi-squared on `max(N - k, 1)` degrees of freedom (the model misses the
//!   data by more than their uncertainties); covariance `C = s^2 (J^T J)^-1` (the Gauss–Newton
//!   approximation), interval `z ± 1.96 sqrt(C_ii)` (the normal 97.5 % quantile; `N` is large),
//!   mapped back to `p` (asymmetric for a log-scaled parameter).
//! - **Not seen:** a parameter whose column of `J` has an RMS below [`NOT_SEEN`] (a change of
//!   `ln p` by 1, a factor e, moves the weighted residuals by less than 1e-6 each): no interval.
//! - **Cannot separate:** the information matrix of the others scaled to a unit diagonal,
//!   `G = D^-1 J^T J D^-1` with `D = diag |J_i|`, has an eigenvalue below [`WEAK`]. For two
//!   parameters `G`'s eigenvalues are `1 ± rho`, so this is exactly `|correlation| > 0.99`; for
//!   more it also finds a combination of three or more. The warning names the direction of
//!   change the data barely see (the eigenvector, as changes of the `z`, the parameters whose
//!   change is at least [`COMPONENT`] of the largest; one parameter alone: the data barely see
//!   it).
//! - **Undetermined:** such an eigenvalue below [`UNDETERMINED`] (numerically singular at the
//!   sensitivities' accuracy, `residuals.rs`): the parameters in its direction get no interval.
//!   The others' covariance is computed with `G`'s eigenvalues floored at [`UNDETERMINED`].

use nalgebra::{DMatrix, SymmetricEigen};

use super::data::{Fitted, Scale};

/// The normal distribution's 97.5 % quantile.
pub const Z95: f64 = 1.959_963_984_540_054;
/// The RMS of a column of `J` below which the data do not see its parameter.
pub const NOT_SEEN: f64 = 1e-6;
/// The eigenvalue of the scaled information matrix below which the data cannot separate the
/// parameters of its direction (`|correlation| > 0.99` for two).
pub const WEAK: f64 = 1e-2;
/// The eigenvalue below which the direction is undetermined: no interval.
pub const UNDETERMINED: f64 = 1e-6;
/// The smallest change of a parameter's `z` along a weak direction, relative to the largest,
/// that counts it into the combination.
pub const COMPONENT: f64 = 0.1;

/// What the fit's data determine.
#[derive(Clone, Debug)]
pub struct Statistics {
    /// The residual variance `s^2`.
    pub variance: f64,
    /// Per parameter, its 95 % interval in `p`, or `None` (not seen, undetermined, or not
    /// finite in `p`).
    pub ci95: Vec<Option<(f64, f64)>>,
    /// The correlation matrix, `None` for a parameter the data do not see.
    pub correlations: Vec<Vec<Option<f64>>>,
    /// The warnings, each naming what it is about.
    pub warnings: Vec<String>,
}

/// The coordinate `z` of a parameter as text: `ln(NAME)` or `NAME/scale`.
fn coordinate(f: &Fitted) -> String {
    match f.scale {
        Scale::Log => format!("ln({})", f.name),
        Scale::Linear(s) => format!("{}/{s:e}", f.name),
    }
}

/// The 95 % quantile of chi-squared on `nu` degrees of freedom, by Wilson and Hilferty's cube
/// (1931): within 3 % of the exact value at `nu` = 1 (3.75 against 3.84), closer above.
pub fn chi2_95(nu: usize) -> f64 {
    let c = 2.0 / (9.0 * nu as f64);
    nu as f64 * (1.0 - c + 1.644_853_626_951_472_2 * c.sqrt()).powi(3)
}

/// The statistics of the fit at `z` with the Jacobian `jac` (`N x k`) and the cost `|r|^2`;
/// `known`: the residuals are in units of known standard uncertainties (module doc).
pub fn statistics(
    fitted: &[Fitted],
    z: &[f64],
    jac: &DMatrix<f64>,
    cost: f64,
    known: bool,
) -> Result<Statistics, String> {
    let (n, k) = jac.shape();
    if n < k || (n == k && !known) {
        return Err(format!(
            "{k} parameters to fit from {n} residuals: the data need more points than the fit \
             has parameters{}",
            if known {
                ""
            } else {
                " (as many, with known uncertainties)"
            }
        ));
    }
    let mut warnings = Vec::new();
    let variance = if known {
        // With as many residuals as parameters a model that explains the data reaches them:
        // one degree of freedom is then the check's generous side.
        let nu = (n - k).max(1);
        if cost > chi2_95(nu) {
            warnings.push(format!(
                "the fitted model misses the data by more than their uncertainties: cost {cost:.3} \
                 above {:.3}, the 95 % quantile of chi-squared on {nu} degree(s) of freedom; the \
                 intervals assume the model can explain the data",
                chi2_95(nu),
            ));
        }
        1.0
    } else {
        cost / (n - k) as f64
    };
    let norms: Vec<f64> = (0..k).map(|j| jac.column(j).norm()).collect();
    let seen: Vec<usize> = (0..k)
        .filter(|&j| {
            let rms = norms[j] / (n as f64).sqrt();
            let ok = rms >= NOT_SEEN;
            if !ok {
                warnings.push(format!(
                    "the data do not see {}: a change of {} by 1 moves the weighted residuals by \
                     {rms:.1e} RMS (rule: below {NOT_SEEN:e}); no interval",
                    fitted[j].name,
                    coordinate(&fitted[j])
                ));
            }
            ok
        })
        .collect();
    let m = seen.len();
    if m == 0 {
        // Nothing the data see: no interval, no correlation but each parameter's own.
        return Ok(Statistics {
            variance,
            ci95: vec![None; k],
            correlations: (0..k)
                .map(|i| (0..k).map(|j| (i == j).then_some(1.0)).collect())
                .collect(),
            warnings,
        });
    }
    let g = DMatrix::from_fn(m, m, |a, b| {
        let (i, j) = (seen[a], seen[b]);
        jac.column(i).dot(&jac.column(j)) / (norms[i] * norms[j])
    });
    let eig = SymmetricEigen::new(g);
    let mut undetermined = vec![false; k];
    for (e, &lambda) in eig.eigenvalues.iter().enumerate() {
        if lambda >= WEAK {
            continue;
        }
        let v = eig.eigenvectors.column(e);
        // The direction as changes of the z: v_a / D_a, the largest scaled to 1.
        let dz: Vec<f64> = (0..m).map(|a| v[a] / norms[seen[a]]).collect();
        let biggest = dz.iter().fold(0.0f64, |acc, x| acc.max(x.abs()));
        let members: Vec<usize> = (0..m)
            .filter(|&a| dz[a].abs() >= COMPONENT * biggest)
            .collect();
        let names: Vec<&str> = members
            .iter()
            .map(|&a| fitted[seen[a]].name.as_str())
            .collect();
        // An eigenvector's sign is arbitrary: the first member's change is made positive.
        let sign = members.first().map_or(1.0, |&a| dz[a].signum());
        let change: Vec<String> = members
            .iter()
            .map(|&a| {
                let c = sign * dz[a] / biggest;
                format!("{c:+.3} in {}", coordinate(&fitted[seen[a]]))
            })
            .collect();
        let singular = lambda < UNDETERMINED;
        if singular {
            for &a in &members {
                undetermined[seen[a]] = true;
            }
        }
        // An eigenvalue below UNDETERMINED is at the sensitivities' round-off: not printed.
        let size = if singular {
            format!("below {UNDETERMINED:e}: undetermined, no interval")
        } else {
            format!("{lambda:.1e}; rule: below {WEAK}")
        };
        let what = if names.len() == 1 {
            format!("the data barely see {}", names[0])
        } else {
            format!("the data cannot separate {}", names.join(", "))
        };
        warnings.push(format!(
            "{what}: the change ({}) leaves the fit all but unchanged (eigenvalue of the scaled \
             information matrix {size})",
            change.join(", "),
        ));
    }
    // C = s^2 D^-1 G^-1 D^-1, G's eigenvalues floored at UNDETERMINED.
    let floored = eig.eigenvalues.map(|l| 1.0 / l.max(UNDETERMINED));
    let g_inv = &eig.eigenvectors * DMatrix::from_diagonal(&floored) * eig.eigenvectors.transpose();
    let cov = |a: usize, b: usize| variance * g_inv[(a, b)] / (norms[seen[a]] * norms[seen[b]]);
    let mut ci95 = vec![None; k];
    let mut correlations = vec![vec![None; k]; k];
    for a in 0..m {
        let i = seen[a];
        for b in 0..m {
            correlations[i][seen[b]] = Some(cov(a, b) / (cov(a, a) * cov(b, b)).sqrt());
        }
        if !undetermined[i] {
            let half = Z95 * cov(a, a).sqrt();
            let (lo, hi) = (fitted[i].p_of(z[i] - half), fitted[i].p_of(z[i] + half));
            ci95[i] = (lo.is_finite() && hi.is_finite()).then_some((lo, hi));
        }
    }
    for (j, f) in fitted.iter().enumerate() {
        correlations[j][j] = Some(1.0);
        if f.at_bound(f.p_of(z[j])) {
            warnings.push(format!(
                "{} ended on a bound of its box: its interval describes the fit there, not \
                 the parameter",
                f.name
            ));
        }
    }
    Ok(Statistics {
        variance,
        ci95,
        correlations,
        warnings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use hydraulic_slewing_plate::fmu::Values;
    use hydraulic_slewing_plate::model::variables::VARIABLES;

    fn fitted(names: &[&str]) -> Vec<Fitted> {
        let values = Values::from_start(&VARIABLES);
        names
            .iter()
            .map(|n| Fitted::parse(n, &values).unwrap())
            .collect()
    }

    /// One parameter whose every residual moves by `c` per unit of `z`: `C = s^2 / (N c^2)`,
    /// `s^2 = cost / (N - 1)`, the interval `z ± 1.96 sqrt(C)` (the closed form of a mean).
    #[test]
    fn one_parameters_interval_is_the_closed_form() {
        let f = fitted(&["torsion_bar.k"]);
        let (n, c, cost) = (101, 0.5, 2.0);
        let z = [f[0].z_of(2500.0)];
        let st = statistics(&f, &z, &DMatrix::from_element(n, 1, c), cost, false).unwrap();
        let half = Z95 * (cost / (n - 1) as f64 / (n as f64 * c * c)).sqrt();
        let (lo, hi) = st.ci95[0].unwrap();
        assert!((lo.ln() - (z[0] - half)).abs() < 1e-14 && (hi.ln() - (z[0] + half)).abs() < 1e-14);
        assert!(st.warnings.is_empty(), "{:?}", st.warnings);
    }

    /// Wilson–Hilferty against the tabulated 95 % quantiles of chi-squared (Abramowitz and
    /// Stegun, table 26.8): 3.841 (1), 5.991 (2), 18.307 (10).
    #[test]
    fn chi_squared_quantiles_match_the_table() {
        for (nu, table, tol) in [(1, 3.841, 0.03), (2, 5.991, 0.01), (10, 18.307, 0.001)] {
            let q = chi2_95(nu);
            assert!((q / table - 1.0).abs() < tol, "{nu}: {q} against {table}");
        }
    }

    /// Known uncertainties: the covariance is `(J^T J)^-1` without `s^2`, and a cost beyond
    /// chi-squared's quantile is a warning.
    #[test]
    fn known_uncertainties_set_the_variance_and_a_miss_is_reported() {
        let f = fitted(&["torsion_bar.k"]);
        let z = [f[0].z_of(2500.0)];
        let jac = DMatrix::from_element(3, 1, 2.0);
        let st = statistics(&f, &z, &jac, 1.0, true).unwrap();
        assert_eq!(st.variance, 1.0);
        let (lo, hi) = st.ci95[0].unwrap();
        assert!((hi.ln() - z[0] - Z95 / 12f64.sqrt()).abs() < 1e-14 && lo < 2500.0);
        assert!(st.warnings.is_empty(), "{:?}", st.warnings);
        let st = statistics(&f, &z, &jac, 10.0, true).unwrap();
        assert!(
            st.warnings[0].contains("misses the data"),
            "{:?}",
            st.warnings
        );
        // As many residuals as parameters: allowed with known uncertainties only.
        assert!(statistics(&f, &z, &jac.rows(0, 1).into_owned(), 0.0, true).is_ok());
        assert!(statistics(&f, &z, &jac.rows(0, 1).into_owned(), 0.0, false).is_err());
    }

    /// Two parameters with the same column (they enter as a product), a third apart, a fourth
    /// the data do not see: the pair undetermined and named, the third's interval as if alone,
    /// the fourth not seen.
    #[test]
    fn a_product_and_an_unseen_parameter_get_no_interval() {
        let f = fitted(&[
            "controller.A1",
            "controller.A2",
            "torsion_bar.k",
            "plate.sigma_y",
        ]);
        let z: Vec<f64> = f.iter().map(|f| f.z_of(f.start)).collect();
        let n = 50;
        let jac = DMatrix::from_fn(n, 4, |i, j| match j {
            0 | 1 => 1.0,
            2 => {
                if i % 2 == 0 {
                    1.0
                } else {
                    -1.0
                }
            }
            _ => 0.0,
        });
        let st = statistics(&f, &z, &jac, 1.0, false).unwrap();
        assert_eq!(st.ci95[0], None);
        assert_eq!(st.ci95[1], None);
        assert_eq!(st.ci95[3], None);
        let (lo, hi) = st.ci95[2].unwrap();
        let half = Z95 * (1.0 / (n - 4) as f64 / n as f64).sqrt();
        assert!((hi.ln() - lo.ln() - 2.0 * half).abs() < 1e-12);
        assert_eq!(st.warnings.len(), 2, "{:?}", st.warnings);
        assert!(st
            .warnings
            .iter()
            .any(|w| w.contains("do not see plate.sigma_y")));
        assert!(st.warnings.iter().any(|w| w
            .contains("cannot separate controller.A1, controller.A2")
            && w.contains("undetermined")));
        assert_eq!(st.correlations[3][0], None);
        // Only the unseen one: no interval, a warning, no eigenvalue problem of size 0.
        let st = statistics(
            &f[3..],
            &z[3..],
            &jac.columns(3, 1).into_owned(),
            1.0,
            false,
        )
        .unwrap();
        assert_eq!(st.ci95, vec![None]);
        assert_eq!(st.correlations, vec![vec![Some(1.0)]]);
        assert_eq!(st.warnings.len(), 1, "{:?}", st.warnings);
    }
}
