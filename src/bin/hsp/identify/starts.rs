//! Multi-start (`--starts N`): a fit that is not convex (a resonance started far from its
//! measured place locks onto another peak, or onto a bound) ends where its start leads it, so the
//! fit is run from `N` starting points and the lowest cost is kept.
//!
//! The points: the configuration's own start first, then `N - 1` drawn in the box of every
//! fitted parameter (`--fit NAME:LOW:HIGH`, required) by a Latin hypercube in the parameters'
//! coordinates `z` ([`super::data::Scale`]: log-uniform for a positive parameter), so that each
//! parameter's range is cut into `N - 1` strata and each stratum is started from once, whatever
//! the number of parameters. Seeded (`--seed`): the same command draws the same points.
//!
//! The starts run on `--jobs` threads (all the machine's cores by default); the model
//! evaluations are independent, so a start's result does not depend on the threads. A start
//! whose model fails at its starting point is reported with the model's message and takes no
//! further part.
//!
//! The minima: two starts that end within [`SAME_MINIMUM`] of each other in every `z` reached the
//! same minimum (their costs then agree too). The report lists each distinct minimum with the number of starts
//! that reached it; when the best one was reached from a single start, a warning says so (more
//! starts, or a narrower box, would tell whether a lower one exists).

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use super::data::Fitted;
use super::optimiser::{levenberg_marquardt, Outcome, Tolerances};
use super::Unconstrained;

/// Two ends closer than this in every coordinate `z` (a relative 1e-4 of a log-scaled
/// parameter) are one minimum.
pub const SAME_MINIMUM: f64 = 1e-4;

/// One start: where it began (`z`) and where it ended, or why the model refused it.
pub struct Start {
    pub z0: Vec<f64>,
    pub end: Result<Outcome, String>,
}

/// A distinct minimum: the index of its best start among the starts, and how many reached it.
pub struct Minimum {
    pub start: usize,
    pub reached: usize,
}

#[path = "../../../../tools/splitmix64.rs"]
mod splitmix64;
use splitmix64::SplitMix64;

/// A uniform index in `0..n` from `rng`.
fn below(rng: &mut SplitMix64, n: usize) -> usize {
    ((rng.uniform() * n as f64) as usize).min(n - 1)
}

/// The `n` starting points in `z`: the configuration's start, then `n - 1` of a Latin hypercube
/// over the boxes, from `seed`. An error names a fitted parameter without a box.
pub fn points(fitted: &[Fitted], n: usize, seed: u64) -> Result<Vec<Vec<f64>>, String> {
    let boxes = fitted
        .iter()
        .map(|f| {
            f.z_bounds().ok_or_else(|| {
                format!(
                    "--starts draws starting points in each parameter's box: give '{}' one \
                     (--fit {}:LOW:HIGH)",
                    f.name, f.name
                )
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut out = vec![fitted.iter().map(|f| f.z_of(f.start)).collect::<Vec<_>>()];
    let drawn = n.saturating_sub(1);
    let mut rng = SplitMix64(seed);
    // Per parameter, a random order of the strata (Fisher–Yates).
    let strata: Vec<Vec<usize>> = boxes
        .iter()
        .map(|_| {
            let mut order: Vec<usize> = (0..drawn).collect();
            for i in (1..drawn).rev() {
                order.swap(i, below(&mut rng, i + 1));
            }
            order
        })
        .collect();
    for k in 0..drawn {
        out.push(
            boxes
                .iter()
                .zip(&strata)
                .map(|(&(lo, hi), order)| {
                    let u = (order[k] as f64 + rng.uniform()) / drawn as f64;
                    lo + (hi - lo) * u
                })
                .collect(),
        );
    }
    Ok(out)
}

/// Runs the fit from every point of `z0s` on `jobs` threads.
pub fn run(
    problem: &Unconstrained,
    z0s: Vec<Vec<f64>>,
    tolerances: Tolerances,
    jobs: usize,
) -> Vec<Start> {
    let next = AtomicUsize::new(0);
    let ends: Vec<Mutex<Option<Result<Outcome, String>>>> =
        z0s.iter().map(|_| Mutex::new(None)).collect();
    std::thread::scope(|scope| {
        for _ in 0..jobs.clamp(1, z0s.len().max(1)) {
            scope.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                let Some(z0) = z0s.get(k) else { break };
                let t0: Vec<f64> = problem
                    .0
                    .fitted
                    .iter()
                    .zip(z0)
                    .map(|(f, &z)| f.t_of_z(z))
                    .collect();
                let end = levenberg_marquardt(problem, &t0, tolerances);
                *ends[k].lock().unwrap_or_else(|e| e.into_inner()) = Some(end);
            });
        }
    });
    z0s.into_iter()
        .zip(ends)
        .map(|(z0, end)| Start {
            z0,
            end: end
                .into_inner()
                .unwrap_or_else(|e| e.into_inner())
                .unwrap_or_else(|| Err("the start was not run".into())),
        })
        .collect()
}

/// The index of the start with the lowest cost (the first of equals), if any ended.
pub fn best(starts: &[Start]) -> Option<usize> {
    starts
        .iter()
        .enumerate()
        .filter_map(|(k, s)| s.end.as_ref().ok().map(|o| (k, o.cost)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(k, _)| k)
}

/// The distinct minima the starts ended in, lowest cost first; `z` of a start's end by `z_of`.
pub fn minima(starts: &[Start], z_of: impl Fn(&[f64]) -> Vec<f64>) -> Vec<Minimum> {
    let mut order: Vec<usize> = (0..starts.len())
        .filter(|&k| starts[k].end.is_ok())
        .collect();
    let cost = |k: usize| starts[k].end.as_ref().map_or(f64::INFINITY, |o| o.cost);
    order.sort_by(|&a, &b| cost(a).total_cmp(&cost(b)));
    let mut out: Vec<(Minimum, Vec<f64>)> = Vec::new();
    for k in order {
        let Ok(end) = &starts[k].end else { continue };
        let z = z_of(&end.t);
        let same = out.iter_mut().find(|(_, zm)| {
            z.iter()
                .zip(zm.iter())
                .all(|(a, b)| (a - b).abs() <= SAME_MINIMUM)
        });
        match same {
            Some((m, _)) => m.reached += 1,
            None => out.push((
                Minimum {
                    start: k,
                    reached: 1,
                },
                z,
            )),
        }
    }
    out.into_iter().map(|(m, _)| m).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use hydraulic_slewing_plate::fmu::Values;
    use hydraulic_slewing_plate::model::variables::VARIABLES;

    fn fitted(spec: &str) -> Fitted {
        Fitted::parse(spec, &Values::from_start(&VARIABLES)).unwrap()
    }

    #[test]
    fn the_points_stratify_each_box_and_start_at_the_configuration() {
        let f = [
            fitted("plate.E:1e10:4e11"),
            fitted("torsion_bar.k:500:10000"),
        ];
        let n = 9;
        let z = points(&f, n, 7).unwrap();
        assert_eq!(z.len(), n);
        assert_eq!(z[0], [f[0].z_of(f[0].start), f[1].z_of(f[1].start)]);
        for (j, f) in f.iter().enumerate() {
            let (lo, hi) = f.z_bounds().unwrap();
            // one drawn point in each of the n - 1 strata of the box
            let mut strata: Vec<usize> = z[1..]
                .iter()
                .map(|p| ((p[j] - lo) / (hi - lo) * (n - 1) as f64) as usize)
                .collect();
            strata.sort();
            assert_eq!(strata, (0..n - 1).collect::<Vec<_>>(), "{}", f.name);
        }
        assert_eq!(z, points(&f, n, 7).unwrap(), "the seed sets the points");
        assert_ne!(z, points(&f, n, 8).unwrap());
    }

    #[test]
    fn a_parameter_without_a_box_is_named() {
        let e = points(&[fitted("plate.E")], 4, 1).err().unwrap();
        assert!(e.contains("'plate.E'") && e.contains("LOW:HIGH"), "{e}");
    }
}
