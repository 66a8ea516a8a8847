//! The real-time mode's elimination of the Jacobian's constant rows
//! (`solver::linalg::VaryingRows`, used by the fixed-step driver) on the models the FMU builds:
//! on every preset whose Jacobian varies, the iteration matrix W = I/(h γ) − J at 1 ms and
//! 0.1 ms steps, at points around rest and far from it, solved with a backward error of a few
//! rounding units, and within 1e-11 of the dense LU's solution (measured: backward errors below
//! 1e-21, differences below 2e-13 of the largest entry).

#[path = "common/points.rs"]
mod points;

use hydraulic_slewing_plate::model::assembly::Assembled;
use hydraulic_slewing_plate::model::presets;
use hydraulic_slewing_plate::solver::linalg::VaryingRows;
use hydraulic_slewing_plate::solver::rodas5p::GAMMA;
use nalgebra::{DMatrix, DVector};
use points::parameters;

#[test]
fn solves_with_the_kept_constant_rows_agree_with_the_dense_lu() {
    let mut compared = 0;
    for preset in presets::PRESETS {
        let system = Assembled::new(&parameters(preset.name)).unwrap();
        let m = system.compiled();
        if m.jacobian_is_constant() {
            continue;
        }
        let varying = m.jacobian_varying_pattern();
        let n = m.n_states();
        let rows = varying.iter().filter(|v| !v.is_empty()).count();
        // The fixed-step driver takes this path for at most half the rows varying.
        assert!(2 * rows <= n, "{}: {rows} of {n} rows vary", preset.name);
        let mut k = 0u64;
        let mut next = move || {
            k += 1;
            ((k * 7919) as f64).sin()
        };
        let mut pts = points::around_rest(&system, 10, 0.1, &mut next);
        pts.extend(points::around_rest(&system, 10, 1.0, &mut next));
        for h in [1e-3, 1e-4] {
            let c = 1.0 / (h * GAMMA);
            let (x0, u0) = &pts[0];
            let mut jac = DMatrix::zeros(n, n);
            m.jacobian(x0, u0, &mut jac);
            let mut lu = VaryingRows::new(&jac, c, varying, Some(m.jacobian_pattern()))
                .unwrap_or_else(|| panic!("{}: the constant rows' block is singular", preset.name));
            assert_eq!(lu.varying_rows(), rows);
            let mut scratch = vec![0.0; n];
            for (x, u) in &pts {
                m.jacobian(x, u, &mut jac);
                assert!(lu.factor(&jac), "{}: W singular", preset.name);
                let w = DMatrix::identity(n, n) * c - &jac;
                let b: Vec<f64> = (0..n).map(|_| next()).collect();
                let mut sol = b.clone();
                lu.solve(&mut sol, &mut scratch);
                let sol = DVector::from_column_slice(&sol);
                let b = DVector::from_column_slice(&b);
                // Normwise backward error ‖W x − b‖ / (‖W‖ ‖x‖ + ‖b‖) (infinity norms).
                let norm_w = w
                    .row_iter()
                    .map(|r| r.iter().map(|v| v.abs()).sum::<f64>())
                    .fold(0.0, f64::max);
                let backward = (&w * &sol - &b).amax() / (norm_w * sol.amax() + b.amax());
                assert!(
                    backward <= 1e-14,
                    "{} at h = {h}: backward error {backward:e}",
                    preset.name
                );
                let dense = w.clone().lu().solve(&b).unwrap();
                let forward = (&sol - &dense).amax() / dense.amax();
                assert!(
                    forward <= 1e-11,
                    "{} at h = {h}: differs from the dense LU by {forward:e} of its largest entry",
                    preset.name
                );
                compared += 1;
            }
        }
    }
    assert!(compared >= 40, "{compared} solves compared");
}
