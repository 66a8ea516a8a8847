//! Mode shapes of the plate model for `hsp modes --plot`: the deflection of each natural mode over
//! a grid of the plate, relative to the hub frame.
//!
//! The plate fragment gives, for a shaker point `(x1, y1)`, the generalised force per unit force,
//! which by virtual work is the deflection at that point per unit coordinate, whatever the
//! formulation (paper or consistent). Moving the shaker point over a grid thus samples every
//! coordinate's shape; an eigenvector of `K v = omega^2 M v` weights them into the mode shape.

use hydraulic_slewing_plate::fragments::plate::modes::{generalized_eigen, natural_modes};
use hydraulic_slewing_plate::fragments::plate::{PlateModel, PlateParameters};

/// One natural mode: its label `(n, m)`, frequency and deflection `w[iy][ix]` (scaled to a peak
/// of 1) on a grid of `x` (along the plate, from the root) and `y` (across).
pub struct ModeShape {
    pub label: (usize, usize),
    pub f_hz: f64,
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub w: Vec<Vec<f64>>,
}

/// The first `count` elastic mode shapes on an `nx` x `ny` grid.
pub fn mode_shapes(
    p: &PlateParameters,
    count: usize,
    nx: usize,
    ny: usize,
) -> Result<Vec<ModeShape>, String> {
    let model = PlateModel::new(p)?;
    let modes = natural_modes(&model)?;
    let (vals, vecs) = generalized_eigen(&model.stiffness, &model.mass)?;
    let scale = vals.iter().fold(0.0f64, |s, v| s.max(v.abs()));
    // The same filter as natural_modes: the free hub's rigid-body mode is left out.
    let elastic: Vec<usize> = (0..vals.len())
        .filter(|&c| vals[c] > 1e-10 * scale)
        .collect();
    let first = model.first_plate();
    let x: Vec<f64> = (0..nx).map(|i| p.a * i as f64 / (nx - 1) as f64).collect();
    let y: Vec<f64> = (0..ny).map(|j| p.b * j as f64 / (ny - 1) as f64).collect();
    // Deflection per unit plate coordinate at every grid point.
    let mut per_coordinate = vec![vec![Vec::new(); nx]; ny];
    for (iy, &yy) in y.iter().enumerate() {
        for (ix, &xx) in x.iter().enumerate() {
            let at = PlateParameters {
                x1: xx,
                y1: yy,
                ..p.clone()
            };
            let m = PlateModel::new(&at)?;
            per_coordinate[iy][ix] = (first..m.dim()).map(|j| m.forces[0][j]).collect::<Vec<_>>();
        }
    }
    let mut out = Vec::new();
    for (mode, &c) in modes.iter().zip(&elastic).take(count) {
        let v = vecs.column(c);
        let mut w: Vec<Vec<f64>> = per_coordinate
            .iter()
            .map(|row| {
                row.iter()
                    .map(|s| s.iter().enumerate().map(|(j, sj)| sj * v[first + j]).sum())
                    .collect()
            })
            .collect();
        let peak = w
            .iter()
            .flatten()
            .fold(0.0f64, |m, v| if v.abs() > m.abs() { *v } else { m });
        if peak != 0.0 {
            w.iter_mut().flatten().for_each(|v| *v /= peak);
        }
        out.push(ModeShape {
            label: mode.label,
            f_hz: mode.f_hz,
            x: x.clone(),
            y: y.clone(),
            w,
        });
    }
    Ok(out)
}
