//! Latency of one communication step through the FMU's C ABI, for real-time use (hardware in
//! the loop). Not a test.
//!
//! ```text
//! cargo run --release --bin hsp -- package            # build fmu/HydraulicSlewingPlate.fmu
//! cargo run --release --bin bench-latency             # writes bench/latency.md
//! cargo run --release --bin bench-latency -- --steps 20000 --rounds 1 --only complete
//! cargo run --release --bin bench-latency -- --steps 3000 --rounds 1 \
//!     --only "complete system | 1 ms | Rodas5P" --set servo_valve.drive=1
//! ```
//!
//! Loads the packaged FMU's Linux library as an importer does and closes a loop around it, as a
//! real-time target would: at every communication point the importer reads `y_pot`, computes
//! the coil drive of a proportional controller, `e_in = A1 A2 (r − y_pot)` (the analog loop's
//! law, `controller.external = true`), with `r` a square wave (0 and [`R_HIGH`] V, period
//! [`PERIOD`] s: steps of about 3.75 deg of motor angle, inside linear theory), sets it, and
//! calls `fmi2DoStep` (or `fmi3DoStep`). So the input changes at every step. After
//! [`WARM_UP`] steps, each `DoStep` of `--steps` (default 100 000) is timed by the calling
//! thread's CPU clock (`CLOCK_THREAD_CPUTIME_ID`: what the step costs, without the time the
//! thread waits while the operating system runs others) and by the wall clock
//! (`CLOCK_MONOTONIC`).
//!
//! `--set NAME=VALUE` (repeatable) sets a parameter in every configuration after its preset, to
//! see what a parameter costs (the tolerance comes from `fmi2SetupExperiment`, so
//! `solver.rtol` has no effect here). Each round's line also gives the solver's steps (with the
//! rejected ones) per communication step, the work behind the figures.
//!
//! For every configuration (a preset, a communication step, a solver) the run is repeated
//! `--rounds` times (default 3), the rounds of all configurations interleaved, and each figure is
//! the median over the rounds with the range beside it. The figures: the step's p50, p99, p99.9
//! and maximum, the ratio max/p50, and the largest communication-step rate the configuration
//! sustains with a 2× margin, 1 / (2 max), of its thread CPU time; a configuration sustains its
//! own period when that rate is at least 1 / period.
//!
//! Beside every configuration runs a control ([`control`]): a chain of multiply-adds of a fixed
//! length, calibrated before the rounds to the configuration's p50 in a pilot run of a twentieth
//! of the steps (and after every round scaled by the ratio of the two p50s of the round), and timed by the same two clocks right after every one of its steps, in the same
//! run ([`closed_loop`]). The control's work never varies, so its tails are the machine's; the
//! table "Tails against the control" gives the FMU's p99.9/p50 and max/p50 (thread CPU time and
//! wall) beside the control's, with the ratio FMU/control of each round. The report's timing
//! block names the command, the date and the load average at the start and the end.
//!
//! With `--interrupts` it instead counts, step by step, the interrupts that reach the
//! processor while a step runs, and times the steps without any apart; it writes
//! `bench/latency_interrupts.md` (see [`interrupts`]).
//!
//! With `--accuracy` it instead compares the real-time method's results with the adaptive
//! solver's and scans its stability, and writes `bench/realtime_accuracy.md` (see
//! [`accuracy`]).
//!
//! The clock reads are inside every figure (reading the thread's CPU clock is a system call; its
//! cost was not measured apart).
//!
//! A second table tells where the slow steps come from: the share of steps slower than 1.5 ×
//! p50, the CPU time between successive ones, and the rate of the machine's local timer
//! interrupts during the run. A periodic interrupt (the scheduler's tick) is handled on the
//! running thread's time, so it lengthens one step in every tick period; the tick's rate and
//! the slow steps' spacing show whether that is what sets p99.9 and the maximum.

#[allow(dead_code)]
#[path = "../hsp/loader.rs"]
mod loader;
#[path = "../bench-common/machine.rs"]
mod machine;
#[path = "../bench-common/measure.rs"]
mod measure;

use measure::{median_range, now};

mod accuracy;
mod control;
mod fmi3;
mod interrupts;

use std::fmt::Write as _;
use std::path::PathBuf;

use hydraulic_slewing_plate::fmi2::ffi::Fmi2Status;
use hydraulic_slewing_plate::fmi3::ffi::Fmi3Status;
use hydraulic_slewing_plate::model::presets;
use hydraulic_slewing_plate::model::variables::vr;
use loader::Fmu;

/// The square wave's high level \[V\]; its low level is 0.
const R_HIGH: f64 = 0.25;
/// The square wave's period \[s\].
const PERIOD: f64 = 2.0;
/// The analog loop's gains A1 A2 (controller.A1 = 2, controller.A2 = 10): the controller the
/// importer runs.
const GAIN: f64 = 20.0;
/// Untimed steps before the timed ones (caches, the solver's first Jacobian, the page faults of
/// its workspace).
const WARM_UP: usize = 1_000;
/// The relative tolerance given to the adaptive solvers (through `fmi2SetupExperiment` /
/// `fmi3EnterInitializationMode`): the FMU's default.
const RTOL: f64 = 1e-6;

/// The solvers compared: a name, `solver.method`, `solver.substeps`.
const SOLVERS: &[(&str, i32, i32)] = &[
    ("Rodas5P (adaptive, default)", 1, 1),
    ("Radau IIA (adaptive)", 2, 1),
    ("real time, 1 substep", 3, 1),
    ("real time, 4 substeps", 3, 4),
    ("real time ROS34PW2, 1 substep", 4, 1),
];

/// The plants: a name and the preset it applies (the preset's own move is switched off by
/// `controller.external`).
const PLANTS: &[(&str, &str)] = &[
    ("complete system", presets::COMPLETE),
    ("LOES motor alone", "loes-motor"),
    ("LOES with hub and plate (Fig. 9b)", "paper-fig9b"),
];

/// The timed steps and the rounds of a full run (`--steps`, `--rounds`): only a run with these
/// and every configuration writes `bench/latency.md`.
const DEFAULT_STEPS: usize = 100_000;
const DEFAULT_ROUNDS: usize = 3;

/// The communication steps \[s\].
const STEPS: &[f64] = &[1e-3, 1e-4];

#[derive(Clone, Copy, PartialEq, Eq)]
enum Version {
    Fmi2,
    Fmi3,
}

impl Version {
    fn name(self) -> &'static str {
        match self {
            Version::Fmi2 => "fmi2DoStep",
            Version::Fmi3 => "fmi3DoStep",
        }
    }
}

struct Config {
    plant: (&'static str, &'static str),
    solver: (&'static str, i32, i32),
    step: f64,
    version: Version,
    /// `--set NAME=VALUE`s, applied after the preset and the configuration's own settings.
    sets: Vec<(String, String)>,
}

/// The figures of one run, in nanoseconds.
#[derive(Clone, Copy, Default)]
struct Figures {
    p50: f64,
    p99: f64,
    p999: f64,
    max: f64,
    wall_p50: f64,
    wall_p999: f64,
    wall_max: f64,
    /// The share of the timed steps slower than [`SLOW`] × p50.
    slow_share: f64,
    /// The median thread CPU time from one such slow step to the next, ns (NaN for fewer than
    /// two).
    slow_spacing: f64,
    /// Local timer interrupts per second of wall time over the timed steps, all processors
    /// (`/proc/interrupts`, `LOC`; NaN where it cannot be read).
    timer_rate: f64,
    /// The solver's steps (accepted and rejected) per communication step over the whole run,
    /// warm-up included (the FMU's `solver.steps` and `solver.rejected`; NaN through FMI 3.0).
    solver_steps: f64,
}

/// A step slower than this multiple of the median counts as slow in [`Figures::slow_share`].
const SLOW: f64 = 1.5;

/// The share of `cpu` (step times in run order) slower than [`SLOW`] × `p50`, and the median
/// CPU time between successive slow steps (NaN for fewer than two).
fn slow_steps(cpu: &[u64], p50: f64) -> (f64, f64) {
    let mut elapsed = 0u64;
    let mut at = Vec::new();
    for &c in cpu {
        if c as f64 > SLOW * p50 {
            at.push(elapsed);
        }
        elapsed += c;
    }
    let mut spacing: Vec<f64> = at.windows(2).map(|w| (w[1] - w[0]) as f64).collect();
    spacing.sort_by(f64::total_cmp);
    let median = spacing.get(spacing.len() / 2).copied().unwrap_or(f64::NAN);
    (at.len() as f64 / cpu.len().max(1) as f64, median)
}

/// The value at quantile `q` of sorted nanoseconds (the smallest value with at least q of the
/// sample at or below it).
fn quantile(sorted: &[u64], q: f64) -> f64 {
    let k = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len());
    sorted[k - 1] as f64
}

/// The square-wave reference at time t.
fn reference(t: f64) -> f64 {
    if (t % PERIOD) < PERIOD / 2.0 {
        R_HIGH
    } else {
        0.0
    }
}

/// The settings of a configuration, as `NAME=VALUE`.
fn settings(config: &Config) -> Result<Vec<(String, String)>, String> {
    let mut sets: Vec<(String, String)> = presets::preset(config.plant.1)?
        .settings
        .iter()
        .map(|(n, v)| (n.to_string(), v.to_string()))
        .collect();
    sets.push(("controller.external".into(), "true".into()));
    sets.push(("solver.method".into(), config.solver.1.to_string()));
    sets.push(("solver.substeps".into(), config.solver.2.to_string()));
    sets.extend(config.sets.iter().cloned());
    Ok(sets)
}

/// What a run records of its timed steps: their thread CPU times and wall times (ns), the rate
/// of local timer interrupts over them, and with a [`interrupts::Counter`] the interrupts each
/// step's two reads enclosed.
#[derive(Default)]
struct Record {
    cpu: Vec<u64>,
    wall: Vec<u64>,
    timer_rate: f64,
    interrupts: Vec<u32>,
    /// See [`Figures::solver_steps`].
    solver_steps: f64,
}

/// The thread CPU time and the wall time of `work` \[ns\]: the one way every step here is
/// timed (the FMU's and the control's).
fn timed(work: impl FnOnce()) -> (u64, u64) {
    let (c0, w0) = (
        now(libc::CLOCK_THREAD_CPUTIME_ID),
        now(libc::CLOCK_MONOTONIC),
    );
    work();
    let (c1, w1) = (
        now(libc::CLOCK_THREAD_CPUTIME_ID),
        now(libc::CLOCK_MONOTONIC),
    );
    (c1 - c0, w1 - w0)
}

/// `n` communication steps of size `h`: `input(t)` sets the inputs (untimed), then `step(t)`
/// takes the step, timed by [`timed`], and with a `counter` enclosed by two reads of the
/// processor's interrupt count; the steps after the warm-up go into `record`. With a
/// `control`, a chain of that many multiply-adds ([`control::multiply_adds`]) is timed the same
/// way right after every step, into the control's record: the FMU's steps and the control's
/// alternate, so that both meet the machine at the same moments.
fn closed_loop(
    n: usize,
    h: f64,
    record: &mut Record,
    mut counter: Option<&mut interrupts::Counter>,
    mut control: Option<(u64, &mut Record)>,
    mut input: impl FnMut(f64) -> Result<(), String>,
    mut step: impl FnMut(f64) -> Result<(), String>,
) -> Result<(), String> {
    let Record {
        cpu,
        wall,
        timer_rate: timer,
        interrupts,
        ..
    } = record;
    let mut timer_start = None;
    let mut wall_start = 0;
    for k in 0..n {
        if k == WARM_UP {
            timer_start = interrupts::timer_interrupts();
            wall_start = now(libc::CLOCK_MONOTONIC);
        }
        let t = k as f64 * h;
        input(t)?;
        let i0 = match counter.as_deref_mut() {
            Some(c) => c.read()?,
            None => 0,
        };
        let mut result = Ok(());
        let (c, w) = timed(|| result = step(t));
        let i1 = match counter.as_deref_mut() {
            Some(c) => c.read()?,
            None => 0,
        };
        result?;
        let controlled = control.as_mut().map(|(length, record)| {
            let length = *length;
            let spent = timed(|| {
                std::hint::black_box(control::multiply_adds(length));
            });
            (spent, record)
        });
        if k >= WARM_UP {
            cpu.push(c);
            wall.push(w);
            if counter.is_some() {
                interrupts.push(u32::try_from(i1 - i0).unwrap_or(u32::MAX));
            }
            if let Some(((c, w), record)) = controlled {
                record.cpu.push(c);
                record.wall.push(w);
            }
        }
    }
    let seconds = (now(libc::CLOCK_MONOTONIC) - wall_start) as f64 * 1e-9;
    *timer = match (timer_start, interrupts::timer_interrupts()) {
        (Some(a), Some(b)) if seconds > 0.0 => (b - a) as f64 / seconds,
        _ => f64::NAN,
    };
    Ok(())
}

/// Runs one configuration: `steps` timed steps after the warm-up, with a `counter` also
/// counting the interrupts of each, and with a `control` (a chain length and its record) the
/// control timed after each (see [`closed_loop`]).
fn run(
    fmu: &Fmu,
    config: &Config,
    steps: usize,
    mut counter: Option<&mut interrupts::Counter>,
    control: Option<(u64, &mut Record)>,
) -> Result<Record, String> {
    let n = WARM_UP + steps;
    let h = config.step;
    let stop = n as f64 * h;
    let mut record = Record {
        cpu: Vec::with_capacity(steps),
        wall: Vec::with_capacity(steps),
        timer_rate: f64::NAN,
        interrupts: Vec::with_capacity(if counter.is_some() { steps } else { 0 }),
        solver_steps: f64::NAN,
    };
    let sets = settings(config)?;
    match config.version {
        Version::Fmi2 => {
            let inst = fmu.instantiate("bench-latency")?;
            inst.setup(Some(RTOL), 0.0, stop)?;
            for (name, value) in &sets {
                inst.set_from_text(&format!("{name}={value}"))?;
            }
            inst.enter_initialization()?;
            inst.exit_initialization()?;
            let mut y = [0.0];
            let input = |t: f64| {
                inst.get_reals_into(&[vr::Y_POT], &mut y)?;
                inst.set_real(vr::E_IN, GAIN * (reference(t) - y[0]))
            };
            let step = |t: f64| match inst.do_step_status(t, h) {
                s if s <= Fmi2Status::Warning => Ok(()),
                s => Err(format!("fmi2DoStep returned {s:?} at t = {t}")),
            };
            closed_loop(
                n,
                h,
                &mut record,
                counter.as_deref_mut(),
                control,
                input,
                step,
            )?;
            let stats = inst.solver_stats()?;
            record.solver_steps = f64::from(stats[0] + stats[1]) / n as f64;
            inst.terminate()?;
        }
        Version::Fmi3 => {
            let inst = fmi3::Instance::new(fmu)?;
            for (name, value) in &sets {
                inst.set_from_text(name, value)?;
            }
            inst.initialize(RTOL, stop)?;
            let mut y = 0.0;
            let input = |t: f64| {
                let s1 = inst.get_real(vr::Y_POT, &mut y);
                let s2 = inst.set_real(vr::E_IN, GAIN * (reference(t) - y));
                if s1.max(s2) > Fmi3Status::Warning {
                    return Err(format!("fmi3GetFloat64/SetFloat64 failed at t = {t}"));
                }
                Ok(())
            };
            let step = |t: f64| match inst.do_step(t, h) {
                s if s <= Fmi3Status::Warning => Ok(()),
                s => Err(format!("fmi3DoStep returned {s:?} at t = {t}")),
            };
            closed_loop(n, h, &mut record, counter, control, input, step)?;
        }
    }
    Ok(record)
}

/// The main table's figures of a run.
fn figures(record: Record) -> Figures {
    let Record {
        cpu,
        mut wall,
        timer_rate,
        solver_steps,
        ..
    } = record;
    let mut sorted = cpu.clone();
    sorted.sort_unstable();
    let (slow_share, slow_spacing) = slow_steps(&cpu, quantile(&sorted, 0.5));
    let cpu = sorted;
    wall.sort_unstable();
    Figures {
        slow_share,
        slow_spacing,
        timer_rate,
        solver_steps,
        p50: quantile(&cpu, 0.5),
        p99: quantile(&cpu, 0.99),
        p999: quantile(&cpu, 0.999),
        max: quantile(&cpu, 1.0),
        wall_p50: quantile(&wall, 0.5),
        wall_p999: quantile(&wall, 0.999),
        wall_max: quantile(&wall, 1.0),
    }
}

/// Microseconds with their range over the rounds: "18.3 (18.1–18.9)".
fn us(values: &[f64]) -> String {
    let (m, lo, hi) = median_range(values);
    if values.len() == 1 {
        format!("{:.1}", m / 1e3)
    } else {
        format!("{:.1} ({:.1}–{:.1})", m / 1e3, lo / 1e3, hi / 1e3)
    }
}

fn ratio(values: &[f64]) -> String {
    let (m, lo, hi) = median_range(values);
    if values.len() == 1 {
        format!("{m:.1}")
    } else {
        format!("{m:.1} ({lo:.1}–{hi:.1})")
    }
}

/// A configuration's row label: "plant | step | solver | call".
fn name(c: &Config) -> String {
    format!(
        "{} | {} ms | {} | {}",
        c.plant.0,
        c.step * 1e3,
        c.solver.0,
        c.version.name()
    )
}

fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, m)| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into())
}

struct Args {
    steps: usize,
    rounds: usize,
    only: Option<String>,
    sets: Vec<(String, String)>,
    out: Option<PathBuf>,
    accuracy: bool,
    interrupts: bool,
}

fn args() -> Args {
    let mut a = Args {
        steps: DEFAULT_STEPS,
        rounds: DEFAULT_ROUNDS,
        only: None,
        sets: Vec::new(),
        accuracy: false,
        interrupts: false,
        out: Some(PathBuf::from(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/bench/latency.md"
        ))),
    };
    let mut it = std::env::args().skip(1);
    while let Some(arg) = it.next() {
        let mut value = |what: &str| it.next().unwrap_or_else(|| panic!("{arg} needs {what}"));
        match arg.as_str() {
            "--steps" => a.steps = value("a number").parse().expect("--steps N"),
            "--rounds" => a.rounds = value("a number").parse().expect("--rounds N"),
            "--only" => a.only = Some(value("a name")),
            "--set" => {
                let set = value("NAME=VALUE");
                let (name, v) = set
                    .split_once('=')
                    .unwrap_or_else(|| panic!("--set {set}: expected NAME=VALUE"));
                a.sets.push((name.into(), v.into()));
            }
            "--print" => a.out = None,
            "--accuracy" => a.accuracy = true,
            "--interrupts" => a.interrupts = true,
            _ => panic!(
                "unknown argument {arg}; expected --steps N, --rounds N, --only TEXT, \
                 --set NAME=VALUE, --print, --interrupts or --accuracy"
            ),
        }
    }
    // A partial run is printed, not written over the committed table.
    if a.only.is_some()
        || !a.sets.is_empty()
        || a.steps != DEFAULT_STEPS
        || a.rounds != DEFAULT_ROUNDS
    {
        a.out = None;
    }
    a
}

fn main() {
    let a = args();
    let fmu_path = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/fmu/HydraulicSlewingPlate.fmu"
    ));
    let fmu = Fmu::load(&fmu_path).unwrap_or_else(|e| {
        panic!("{e}: build it first with `cargo run --release --bin hsp -- package`")
    });
    if a.accuracy {
        let md = accuracy::report(&fmu).unwrap_or_else(|e| {
            eprintln!("{e}");
            std::process::exit(1)
        });
        print!("{md}");
        let out = concat!(env!("CARGO_MANIFEST_DIR"), "/bench/realtime_accuracy.md");
        std::fs::write(out, &md).unwrap_or_else(|e| panic!("{out}: {e}"));
        eprintln!("wrote {out}");
        return;
    }
    let mut configs = Vec::new();
    for &plant in PLANTS {
        for &step in STEPS {
            for &solver in SOLVERS {
                // Four substeps of 25 µs make no sense at a 0.1 ms communication step.
                if solver.2 > 1 && step < 1e-3 {
                    continue;
                }
                for version in [Version::Fmi2, Version::Fmi3] {
                    // FMI 3.0 steps into the same core as FMI 2.0: timed on the complete
                    // system at 1 ms only.
                    if version == Version::Fmi3 && (plant.1 != presets::COMPLETE || step < 1e-3) {
                        continue;
                    }
                    configs.push(Config {
                        plant,
                        solver,
                        step,
                        version,
                        sets: a.sets.clone(),
                    });
                }
            }
        }
    }
    if let Some(only) = &a.only {
        configs.retain(|c| name(c).contains(only.as_str()));
    }
    if a.interrupts {
        // Each step costs two reads of /proc/interrupts more: the complete system's
        // configurations and the real-time mode's.
        configs.retain(|c| c.plant.1 == presets::COMPLETE || c.solver.1 == 3);
        let md = interrupts::report(&fmu, &configs, a.steps, a.rounds).unwrap_or_else(|e| {
            eprintln!("{e}");
            std::process::exit(1)
        });
        print!("{md}");
        if a.out.is_some() {
            let out = concat!(env!("CARGO_MANIFEST_DIR"), "/bench/latency_interrupts.md");
            std::fs::write(out, &md).unwrap_or_else(|e| panic!("{out}: {e}"));
            eprintln!("wrote {out}");
        }
        return;
    }
    // Each configuration's control: calibrated to the p50 of a pilot run of the configuration.
    let pilot = (a.steps / 20).max(1_000);
    let mut lengths: Vec<u64> = configs
        .iter()
        .map(|c| match run(&fmu, c, pilot, None, None) {
            Ok(record) => control::calibrate(figures(record).p50),
            Err(e) => {
                eprintln!("{}: {e}", name(c));
                std::process::exit(1);
            }
        })
        .collect();
    let load_start = machine::load();
    let mut results: Vec<Vec<Figures>> = vec![Vec::new(); configs.len()];
    let mut controls: Vec<Vec<Figures>> = vec![Vec::new(); configs.len()];
    for round in 0..a.rounds {
        eprintln!("round {}: load {}", round + 1, machine::load());
        for (k, c) in configs.iter().enumerate() {
            let mut control = Record {
                cpu: Vec::with_capacity(a.steps),
                wall: Vec::with_capacity(a.steps),
                ..Record::default()
            };
            match run(&fmu, c, a.steps, None, Some((lengths[k], &mut control))).map(figures) {
                Ok(f) => {
                    let g = figures(control);
                    eprintln!(
                        "round {}: {}: p50 {:.1} µs, p99.9 {:.1} µs, max {:.1} µs (control: \
                         p50 {:.1} µs, p99.9 {:.1} µs, max {:.1} µs); slow steps {:.2} % every \
                         {:.1} ms of CPU, {:.0} timer interrupts/s; {:.2} solver steps (with the \
                         rejected) per communication step",
                        round + 1,
                        name(c),
                        f.p50 / 1e3,
                        f.p999 / 1e3,
                        f.max / 1e3,
                        g.p50 / 1e3,
                        g.p999 / 1e3,
                        g.max / 1e3,
                        100.0 * f.slow_share,
                        f.slow_spacing / 1e6,
                        f.timer_rate,
                        f.solver_steps
                    );
                    // The next round's control: its length scaled to this round's p50s.
                    lengths[k] = ((lengths[k] as f64) * f.p50 / g.p50).round().max(1.0) as u64;
                    results[k].push(f);
                    controls[k].push(g);
                }
                Err(e) => {
                    eprintln!("{}: {e}", name(c));
                    std::process::exit(1);
                }
            }
        }
    }
    let load_end = machine::load();
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Latency of a communication step\n\n\
         Written by `cargo run --release --bin bench-latency` (see that file's header for the \
         method) on {} ({} cores as the machine reports them), {} timed steps after {WARM_UP} \
         of warm-up, {} rounds interleaved: each figure is the median over the rounds with the \
         range in brackets. A closed loop: `e_in = {GAIN} (r − y_pot)` set before every step, \
         `r` a square wave of 0 and {R_HIGH} V with period {PERIOD} s. Times are the calling \
         thread's CPU time of one `DoStep` in µs; \"wall\" is the wall-clock time of the same \
         calls. \"rate\" is the largest communication-step rate with a 2× margin on the \
         maximum, 1 / (2 max); \"fits\" says whether that is at least the configuration's own \
         rate. The adaptive solvers run at rtol {RTOL:e}.\n\n\
         Beside each configuration, a control ([`control.rs`](../src/bin/bench-latency/control.rs)): \
         a dependent chain of multiply-adds, work of a fixed operation count that touches no \
         memory, its length calibrated to the configuration's p50 (of a pilot run of {pilot} \
         steps, then scaled by the ratio of the two p50s after every round), timed by the same clocks right after every step of the configuration, in the \
         same run. Its steps do the same work every time: the spread of their times is the \
         machine's. The table \"Tails against the control\" sets the FMU's p99.9/p50 and \
         max/p50 beside the control's, and their ratio FMU/control (per round, then the median \
         and range over the rounds); the goal is a ratio of at most 1.2, tails the machine's.\n\n\
         <!-- hsp timing: latency -->\n\
         Made by `{}` on {}, load {load_start} at the start \
         and {load_end} at the end (`/proc/loadavg`, the 1-minute average; each round's is in \
         the run's log).\n",
        cpu_model(),
        std::thread::available_parallelism().map_or(0, |n| n.get()),
        a.steps,
        a.rounds,
        machine::command("bench-latency"),
        machine::today()
    );
    let _ = writeln!(
        md,
        "| plant | step | solver | call | p50 | p99 | p99.9 | max | max/p50 | wall p50 | wall p99.9 | wall max | rate (2× margin) | fits |\n\
         | --- | ---: | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |"
    );
    for (c, figures) in configs.iter().zip(&results) {
        let pick = |f: fn(&Figures) -> f64| figures.iter().map(f).collect::<Vec<f64>>();
        let max = pick(|f| f.max);
        let ratios: Vec<f64> = figures.iter().map(|f| f.max / f.p50).collect();
        let (max_median, _, _) = median_range(&max);
        let rate = 1e9 / (2.0 * max_median);
        let fits = if rate >= 1.0 / c.step { "yes" } else { "no" };
        let _ = writeln!(
            md,
            "| {} | {} ms | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.0} Hz | {fits} |",
            c.plant.0,
            c.step * 1e3,
            c.solver.0,
            c.version.name(),
            us(&pick(|f| f.p50)),
            us(&pick(|f| f.p99)),
            us(&pick(|f| f.p999)),
            us(&max),
            ratio(&ratios),
            us(&pick(|f| f.wall_p50)),
            us(&pick(|f| f.wall_p999)),
            us(&pick(|f| f.wall_max)),
            rate
        );
    }
    let _ = writeln!(
        md,
        "\n## Tails against the control\n\n\
         The FMU's (\"FMU\") and its control's (\"ctl\") p50 in µs, their p99.9/p50 and \
         max/p50, by thread CPU time and by wall time, and the ratio FMU/ctl of each; \"≤ 1.2\" \
         says whether the thread CPU time's ratios (p99.9, max) are at most 1.2.\n\n\
         | plant | step | solver | call | p50 FMU | p50 ctl | p99.9/p50 FMU | ctl | FMU/ctl | max/p50 FMU | ctl | FMU/ctl | wall p99.9/p50 FMU | ctl | FMU/ctl | wall max/p50 FMU | ctl | FMU/ctl | ≤ 1.2 (p99.9, max) |\n\
         | --- | ---: | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |"
    );
    for ((c, fmu), ctl) in configs.iter().zip(&results).zip(&controls) {
        let pick =
            |runs: &[Figures], f: fn(&Figures) -> f64| runs.iter().map(f).collect::<Vec<_>>();
        let mut cells = vec![us(&pick(fmu, |f| f.p50)), us(&pick(ctl, |f| f.p50))];
        let mut within = Vec::new();
        let tails: [fn(&Figures) -> f64; 4] = [
            |f| f.p999 / f.p50,
            |f| f.max / f.p50,
            |f| f.wall_p999 / f.wall_p50,
            |f| f.wall_max / f.wall_p50,
        ];
        for (k, tail) in tails.into_iter().enumerate() {
            let of_fmu = pick(fmu, tail);
            let of_ctl = pick(ctl, tail);
            let ratios: Vec<f64> = of_fmu.iter().zip(&of_ctl).map(|(a, b)| a / b).collect();
            if k < 2 {
                within.push(if median_range(&ratios).0 <= 1.2 {
                    "yes"
                } else {
                    "no"
                });
            }
            let (m, lo, hi) = median_range(&ratios);
            cells.extend([
                ratio(&of_fmu),
                ratio(&of_ctl),
                format!("{m:.2} ({lo:.2}–{hi:.2})"),
            ]);
        }
        let _ = writeln!(
            md,
            "| {} | {} ms | {} | {} | {} | {} |",
            c.plant.0,
            c.step * 1e3,
            c.solver.0,
            c.version.name(),
            cells.join(" | "),
            within.join(", ")
        );
    }
    let _ = writeln!(
        md,
        "\n## The slow steps\n\n\
         The steps slower than {SLOW} × p50 of the same run: their share of the timed steps, the \
         median thread CPU time of the timed steps from one to the next (ms), and the rate of \
         the local timer interrupts over the run (`LOC` of `/proc/interrupts`, all processors, \
         per second of wall time). Slow steps that recur about every 1 / (timer rate), less the \
         loop's own time between the steps, are the interrupts' handling, charged to the \
         thread that was running; they reach p99.9 when they hit more than 0.1 % of the \
         steps, that is when a step lasts more than about 0.001 / (timer rate).\n\n\
         | plant | step | solver | call | slow steps | spacing (ms of CPU) | timer interrupts / s |\n\
         | --- | ---: | --- | --- | ---: | ---: | ---: |"
    );
    for (c, figures) in configs.iter().zip(&results) {
        let pick = |f: fn(&Figures) -> f64| figures.iter().map(f).collect::<Vec<f64>>();
        let (share, _, _) = median_range(&pick(|f| f.slow_share));
        let (spacing, _, _) = median_range(&pick(|f| f.slow_spacing));
        let (timer, _, _) = median_range(&pick(|f| f.timer_rate));
        let _ = writeln!(
            md,
            "| {} | {} ms | {} | {} | {:.2} % | {:.1} | {:.0} |",
            c.plant.0,
            c.step * 1e3,
            c.solver.0,
            c.version.name(),
            100.0 * share,
            spacing / 1e6,
            timer
        );
    }
    md.push_str("<!-- /hsp timing: latency -->\n");
    print!("{md}");
    if let Some(out) = a.out {
        std::fs::write(&out, &md).unwrap_or_else(|e| panic!("{}: {e}", out.display()));
        eprintln!("wrote {}", out.display());
    }
}
