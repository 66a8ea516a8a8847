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
//! Across machines (`tools/identify_dask.py`): `--start K` runs start K alone and prints where it
//! ended as one JSON line ([`end_line`]: the end's coordinates and cost as the bits of their
//! doubles, so nothing is lost in decimal); `--ends FILE` takes the N ends from such lines
//! ([`read_ends`]) instead of running them, and the report follows as from the threads.
//!
//! The minima: two starts that end within [`SAME_MINIMUM`] of each other in every `z` reached the
//! same minimum (their costs then agree too). The report lists each distinct minimum with the number of starts
//! that reached it; when the best one was reached from a single start, a warning says so (more
//! starts, or a narrower box, would tell whether a lower one exists).

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use super::data::Fitted;
use super::optimiser::{levenberg_marquardt, Outcome, Stop, Tolerances};
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

/// Where start `k` ended, as one JSON line: `{"start": k, "t": [bits], "cost": bits,
/// "iterations": n, "stop": name}` (the doubles as the hexadecimal of their bits), or
/// `{"start": k, "error": message}`.
pub fn end_line(k: usize, end: &Result<Outcome, String>) -> String {
    let bits = |v: f64| format!("{:016x}", v.to_bits());
    let line = match end {
        Ok(o) => serde_json::json!({
            "start": k,
            "t": o.t.iter().map(|&v| bits(v)).collect::<Vec<_>>(),
            "cost": bits(o.cost),
            "iterations": o.iterations,
            "stop": format!("{:?}", o.stop),
        }),
        Err(e) => serde_json::json!({"start": k, "error": e}),
    };
    line.to_string()
}

/// The ends of the starts `z0s` from `file`, lines of [`end_line`] in any order (blank lines
/// skipped); an error names the file and the line, a start given twice, or the starts missing.
pub fn read_ends(file: &str, z0s: Vec<Vec<f64>>) -> Result<Vec<Start>, String> {
    let text = std::fs::read_to_string(file).map_err(|e| format!("--ends {file}: {e}"))?;
    let mut ends: Vec<Option<Result<Outcome, String>>> = z0s.iter().map(|_| None).collect();
    for (i, line) in text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
    {
        let at = |what: &str| format!("--ends {file}, line {}: {what}", i + 1);
        let v: serde_json::Value =
            serde_json::from_str(line).map_err(|e| at(&format!("not JSON ({e})")))?;
        let k = v["start"].as_u64().ok_or_else(|| at("no \"start\""))? as usize;
        let slot = ends.get_mut(k).ok_or_else(|| {
            at(&format!(
                "start {k}, but the starts are 0 to {}",
                z0s.len() - 1
            ))
        })?;
        if slot.is_some() {
            return Err(at(&format!("start {k} given twice")));
        }
        let double = |v: &serde_json::Value| {
            v.as_str()
                .and_then(|h| u64::from_str_radix(h, 16).ok())
                .map(f64::from_bits)
                .ok_or_else(|| at("a double that is not 16 hexadecimal digits"))
        };
        *slot = Some(match v["error"].as_str() {
            Some(e) => Err(e.to_string()),
            None => {
                let t = v["t"]
                    .as_array()
                    .ok_or_else(|| at("no \"t\""))?
                    .iter()
                    .map(double)
                    .collect::<Result<Vec<_>, _>>()?;
                if t.len() != z0s[k].len() {
                    return Err(at(&format!(
                        "{} coordinates for {} fitted parameters",
                        t.len(),
                        z0s[k].len()
                    )));
                }
                let stop = match v["stop"].as_str() {
                    Some("Cost") => Stop::Cost,
                    Some("Step") => Stop::Step,
                    Some("Gradient") => Stop::Gradient,
                    Some("Iterations") => Stop::Iterations,
                    _ => return Err(at("no known \"stop\"")),
                };
                Ok(Outcome {
                    t,
                    cost: double(&v["cost"])?,
                    iterations: v["iterations"]
                        .as_u64()
                        .ok_or_else(|| at("no \"iterations\""))?
                        as usize,
                    stop,
                })
            }
        });
    }
    let missing: Vec<usize> = (0..ends.len()).filter(|&k| ends[k].is_none()).collect();
    if !missing.is_empty() {
        return Err(format!("--ends {file}: no end of the starts {missing:?}"));
    }
    Ok(z0s
        .into_iter()
        .zip(ends)
        .map(|(z0, end)| Start {
            z0,
            end: end.unwrap_or_else(|| Err("the start was not run".into())),
        })
        .collect())
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

    /// `--start K`'s lines give back the same ends to the bit through `--ends`, in any order;
    /// a start given twice or missing is refused by name.
    #[test]
    fn the_ends_of_the_starts_come_back_to_the_bit() {
        let ends = [
            Ok(Outcome {
                t: vec![0.1 + 0.2, -1e-300, f64::MIN_POSITIVE / 3.0],
                cost: 2.625e-21,
                iterations: 7,
                stop: Stop::Gradient,
            }),
            Err("the model refused it".to_string()),
        ];
        let z0s = vec![vec![1.0, 2.0, 3.0], vec![4.0, 5.0, 6.0]];
        let dir = std::env::temp_dir().join(format!("hsp-ends-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("ends.jsonl");
        let lines = format!("{}\n\n{}\n", end_line(1, &ends[1]), end_line(0, &ends[0]));
        std::fs::write(&file, &lines).unwrap();
        let back = read_ends(file.to_str().unwrap(), z0s.clone()).unwrap();
        let o = back[0].end.as_ref().unwrap();
        let e = ends[0].as_ref().unwrap();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&o.t), bits(&e.t));
        assert_eq!(o.cost.to_bits(), e.cost.to_bits());
        assert_eq!((o.iterations, o.stop), (e.iterations, e.stop));
        assert_eq!(back[1].end.as_ref().err().unwrap(), "the model refused it");
        assert_eq!(back[1].z0, z0s[1]);

        std::fs::write(&file, format!("{lines}{}\n", end_line(0, &ends[0]))).unwrap();
        let e = read_ends(file.to_str().unwrap(), z0s.clone())
            .err()
            .unwrap();
        assert!(
            e.contains("line 4") && e.contains("start 0 given twice"),
            "{e}"
        );
        std::fs::write(&file, end_line(1, &ends[1])).unwrap();
        let e = read_ends(file.to_str().unwrap(), z0s).err().unwrap();
        assert!(e.contains("no end of the starts [0]"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_parameter_without_a_box_is_named() {
        let e = points(&[fitted("plate.E")], 4, 1).err().unwrap();
        assert!(e.contains("'plate.E'") && e.contains("LOW:HIGH"), "{e}");
    }
}
