//! Seeded random FMI call sequences through the exported C functions, in the manner of the outside
//! campaign of issue 11: calls in any order, good and bad values, FMU states taken and restored
//! across instances' histories. An oracle written from the standard's state table (not from the
//! FMU's) knows when a call is illegal or its arguments bad. Asserted for every call:
//! * never fmi2Fatal;
//! * fmi2Error where the oracle says an error is due (never fmi2OK there);
//! * a log line with every fmi2Error and fmi2Discard;
//! * after fmi2OK from a step, every output is finite.
//!
//! `FMI2_FUZZ_SEQUENCES` sets the number of sequences (default 2000, the CI size); the seed of a
//! failing sequence is in the message, and `FMI2_FUZZ_SEED` reruns that one alone.

#[path = "common/fmu.rs"]
mod fmu;

use fmu::Fmu;
use hydraulic_slewing_plate::fmi2::ffi::*;
use hydraulic_slewing_plate::fmi2_exports::*;
use hydraulic_slewing_plate::fmu::Causality;
use hydraulic_slewing_plate::model::variables::VARIABLES;

/// xorshift64*: small, seeded, good enough to pick calls.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    fn pick<T: Copy>(&mut self, items: &[T]) -> T {
        items[self.below(items.len())]
    }
}

/// The oracle's view of the state machine (FMI 2.0.4, section 4.2.4).
#[derive(Clone, Copy, Debug, PartialEq)]
enum S {
    Instantiated,
    Init,
    Complete,
    Failed,
    Terminated,
    Error,
}

const REALS: [&str; 10] = [
    "r",
    "F1",
    "F2",
    "plate.rho",
    "plate.a",
    "servo_valve.p_supply",
    "servo_valve.beta",
    "loes.C3",
    "solver.rtol",
    "controller.A1",
];
const INTEGERS: [(&str, [i32; 3]); 3] = [
    ("hydraulics.model", [1, 2, 3]),
    ("plate.N", [0, 2, 13]),
    ("solver.method", [1, 2, 0]),
];

fn start_value(name: &str) -> f64 {
    match VARIABLES.iter().find(|v| v.name == name).unwrap().kind {
        hydraulic_slewing_plate::fmu::Kind::Real { start, .. } => start.unwrap_or(0.0),
        _ => 0.0,
    }
}

/// What the sequences did: calls answered fmi2OK from a step, fmi2Discard, fmi2Error, FMU
/// states restored.
#[derive(Default, Debug)]
struct Coverage {
    steps: usize,
    discards: usize,
    errors: usize,
    restores: usize,
}

/// One random sequence; `Err` describes the first broken promise.
fn sequence(seed: u64, cov: &mut Coverage) -> Result<(), String> {
    let mut rng = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    let f = Fmu::new();
    let mut s = S::Instantiated;
    let mut t = 0.0f64;
    let mut saved: Vec<(Fmi2FmuState, S, f64)> = Vec::new();
    let outputs: Vec<u32> = VARIABLES
        .iter()
        .filter(|v| v.causality == Causality::Output && v.kind.type_name() == "Real")
        .map(|v| v.value_reference)
        .collect();
    let mut trace = Vec::new();
    let len = 4 + rng.below(14);
    for _ in 0..len {
        let before = f.log_len();
        // The state an FMU state restores to, when one is restored.
        let mut restored = None;
        // (call, status, an error is due)
        // Mostly the call that moves the simulation on, else any call: sequences reach every
        // state, and the illegal calls are tried in each.
        let natural = match s {
            S::Instantiated => rng.pick(&[0, 1, 3, 5]),
            S::Init => rng.pick(&[2, 2, 3, 9]),
            S::Complete => rng.pick(&[6, 6, 6, 3, 9, 10, 11]),
            _ => rng.pick(&[10, 11]),
        };
        let pick = if rng.below(5) == 0 {
            rng.below(12)
        } else {
            natural
        };
        let (call, status, due): (String, Fmi2Status, bool) = match pick {
            0 => {
                let start = rng.pick(&[0.0, 0.0, 0.5, 1e15]);
                let st = f.setup(start);
                if st == Fmi2Status::Ok {
                    t = start;
                }
                (format!("setup({start})"), st, s != S::Instantiated)
            }
            1 => ("enter".into(), f.enter(), s != S::Instantiated),
            2 => ("exit".into(), f.exit(), s != S::Init),
            3 | 4 => {
                let name = rng.pick(&REALS);
                let v = start_value(name);
                let value = rng.pick(&[v, 2.0 * v, 0.5 * v, 1e300, 1e-300, -1.0, 0.0, f64::NAN]);
                let input = name == "r" || name.starts_with('F');
                let legal = matches!(s, S::Instantiated | S::Init) || (s == S::Complete && input);
                let st = f.set_real(name, value);
                (
                    format!("setReal({name}, {value})"),
                    st,
                    !legal || value.is_nan(),
                )
            }
            5 => {
                let (name, values) = rng.pick(&INTEGERS);
                let value = rng.pick(&values);
                let legal = matches!(s, S::Instantiated | S::Init);
                let st = f.set_integer(name, value);
                (format!("setInteger({name}, {value})"), st, !legal)
            }
            6..=8 => {
                let h = rng.pick(&[1e-3, 1e-3, 1e-3, 2e-3, 1e-15, 0.0, -1e-3, f64::NAN]);
                let at = if rng.below(8) == 0 {
                    t + 1.0 + 1e-6 * t.abs()
                } else {
                    t
                };
                let st = f.step(at, h);
                let bad = h.is_nan() || h <= 0.0 || at != t || t + h == t;
                if st == Fmi2Status::Ok {
                    t = at + h;
                    let mut y = vec![0.0; outputs.len()];
                    let got =
                        unsafe { fmi2GetReal(f.c, outputs.as_ptr(), y.len(), y.as_mut_ptr()) };
                    if got != Fmi2Status::Ok || y.iter().any(|v| !v.is_finite()) {
                        return Err(format!("seed {seed}: fmi2OK from a step with non-finite outputs {y:?}; calls {trace:?}"));
                    }
                }
                (format!("doStep({at}, {h})"), st, s != S::Complete || bad)
            }
            9 => {
                let vr = rng.pick(&outputs);
                let mut v = 0.0;
                let st = unsafe { fmi2GetReal(f.c, &vr, 1, &mut v) };
                (format!("getReal({vr})"), st, matches!(s, S::Instantiated))
            }
            10 => match rng.below(4) {
                0 => (
                    "terminate".into(),
                    unsafe { fmi2Terminate(f.c) },
                    !matches!(s, S::Complete | S::Failed),
                ),
                1 => {
                    let st = unsafe { fmi2Reset(f.c) };
                    if st == Fmi2Status::Ok {
                        t = 0.0;
                    }
                    ("reset".into(), st, false)
                }
                _ => {
                    let (st, state) = f.get_state();
                    if st == Fmi2Status::Ok {
                        saved.push((state, s, t));
                    }
                    ("getFMUstate".into(), st, false)
                }
            },
            _ => {
                if saved.is_empty() {
                    continue;
                }
                let k = rng.below(saved.len());
                let (state, taken_in, taken_at) = saved[k];
                let st = f.set_state(state);
                if st == Fmi2Status::Ok {
                    t = taken_at;
                    restored = Some(taken_in);
                }
                // A state taken in the error state cannot be continued.
                (
                    format!("setFMUstate(taken in {taken_in:?})"),
                    st,
                    taken_in == S::Error,
                )
            }
        };
        trace.push(format!("{call} -> {status:?}"));
        match status {
            Fmi2Status::Ok if call.starts_with("doStep") => cov.steps += 1,
            Fmi2Status::Ok if call.starts_with("setFMUstate") => cov.restores += 1,
            Fmi2Status::Discard => cov.discards += 1,
            Fmi2Status::Error => cov.errors += 1,
            _ => {}
        }
        if status == Fmi2Status::Fatal {
            return Err(format!(
                "seed {seed}: fmi2Fatal; calls {trace:?}\n{:?}",
                f.log()
            ));
        }
        if due && status == Fmi2Status::Ok {
            return Err(format!(
                "seed {seed}: fmi2OK where an error is due; calls {trace:?}"
            ));
        }
        if matches!(status, Fmi2Status::Error | Fmi2Status::Discard) && f.log_len() == before {
            return Err(format!(
                "seed {seed}: {status:?} without a log line; calls {trace:?}"
            ));
        }
        // The oracle follows what happened.
        s = match (status, call.as_str()) {
            (Fmi2Status::Error, _) => S::Error,
            (Fmi2Status::Discard, _) => S::Failed,
            (_, "enter") => S::Init,
            (_, "exit") => S::Complete,
            (_, "terminate") => S::Terminated,
            (_, "reset") => S::Instantiated,
            _ => restored.unwrap_or(s),
        };
    }
    for (state, _, _) in saved {
        f.free_state(state);
    }
    Ok(())
}

#[test]
fn random_call_sequences_keep_the_contract() {
    let seeds: Vec<u64> = match std::env::var("FMI2_FUZZ_SEED") {
        Ok(seed) => vec![seed.parse().unwrap()],
        Err(_) => {
            let n = std::env::var("FMI2_FUZZ_SEQUENCES")
                .ok()
                .and_then(|n| n.parse().ok())
                .unwrap_or(2000u64);
            (1..=n).collect()
        }
    };
    let many = seeds.len() >= 100;
    let mut cov = Coverage::default();
    for seed in seeds {
        if let Err(e) = sequence(seed, &mut cov) {
            panic!("{e}");
        }
    }
    eprintln!("{cov:?}");
    if many {
        // The sequences reach the running state and its failures, not only the refusals.
        assert!(
            cov.steps > 0 && cov.errors > 0 && cov.restores > 0,
            "{cov:?}"
        );
    }
}
