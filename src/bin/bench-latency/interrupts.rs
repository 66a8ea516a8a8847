//! `bench-latency --interrupts`: which steps an interrupt lands in. Writes
//! `bench/latency_interrupts.md`.
//!
//! The main table times each `DoStep` by the thread's CPU clock, and an interrupt handled
//! while the step runs (the scheduler's tick, a device's, an inter-processor call) is charged
//! to that clock. Its second table infers from the slow steps' spacing that the tick sets
//! p99.9 and the maximum; this pass measures it step by step. The thread is pinned to the
//! processor it runs on, and just before and just after every timed step it reads that
//! processor's column of `/proc/interrupts` (every source summed). A step is "clean" when the
//! count did not move: no interrupt reached the processor between the two reads, and so none
//! within the step, which they enclose. A step is "interrupted" otherwise (the reads
//! themselves take longer than the step, so an interrupt counted there may also have landed
//! outside it).
//!
//! The clean steps' figures are then what the step costs with the operating system's
//! interrupts taken out, on the same run and the same inputs. They still hold what the guest
//! cannot see: the hypervisor's own exits and the host's other work, and the cache misses the
//! two reads leave behind them (so a clean step's p50 is higher than the main table's).

use std::fmt::Write as _;
use std::fs::File;
use std::os::unix::fs::FileExt;

/// This processor's interrupts so far, read from `/proc/interrupts` through an open file and
/// a buffer allocated once.
pub struct Counter {
    file: File,
    buf: Vec<u8>,
    /// The processor the thread is pinned to, the column read.
    cpu: usize,
}

impl Counter {
    /// Pins the calling thread to the processor it runs on and opens `/proc/interrupts`.
    pub fn pinned() -> Result<Counter, String> {
        // SAFETY: sched_getcpu takes no arguments; sched_setaffinity reads the set it is
        // given, which CPU_ZERO / CPU_SET initialise.
        let cpu = unsafe {
            let cpu = libc::sched_getcpu();
            if cpu < 0 {
                return Err("sched_getcpu failed".into());
            }
            let mut set: libc::cpu_set_t = std::mem::zeroed();
            libc::CPU_ZERO(&mut set);
            libc::CPU_SET(cpu as usize, &mut set);
            if libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set) != 0 {
                return Err(format!(
                    "sched_setaffinity to processor {cpu}: {}",
                    std::io::Error::last_os_error()
                ));
            }
            cpu as usize
        };
        let file = File::open("/proc/interrupts").map_err(|e| format!("/proc/interrupts: {e}"))?;
        let mut counter = Counter {
            file,
            buf: vec![0; 1 << 16],
            cpu,
        };
        counter.read()?;
        Ok(counter)
    }

    /// The processor's interrupts so far, every source summed (rows without a column for
    /// this processor, such as `ERR:`, are skipped).
    pub fn read(&mut self) -> Result<u64, String> {
        // A read at offset 0 makes the kernel write the table afresh.
        let mut len = 0;
        loop {
            let n = self
                .file
                .read_at(&mut self.buf[len..], len as u64)
                .map_err(|e| format!("/proc/interrupts: {e}"))?;
            if n == 0 {
                break;
            }
            len += n;
            if len == self.buf.len() {
                return Err("/proc/interrupts is larger than 64 KiB".into());
            }
        }
        let text = std::str::from_utf8(&self.buf[..len])
            .map_err(|_| "/proc/interrupts is not UTF-8".to_string())?;
        Ok(rows(text)
            .filter_map(|(_, mut counts)| counts.nth(self.cpu)?.parse::<u64>().ok())
            .sum())
    }
}

/// The rows of `/proc/interrupts`: each source's name and its counts, one per processor,
/// followed by its description (the first line, naming the processors, is skipped).
fn rows(text: &str) -> impl Iterator<Item = (&str, std::str::SplitWhitespace<'_>)> {
    text.lines().skip(1).filter_map(|line| {
        let (source, rest) = line.split_once(':')?;
        Some((source.trim(), rest.split_whitespace()))
    })
}

/// The local timer interrupts so far, summed over the processors (`LOC` in
/// `/proc/interrupts`).
pub fn timer_interrupts() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/interrupts").ok()?;
    let (_, counts) = rows(&text).find(|(source, _)| *source == "LOC")?;
    Some(counts.map_while(|v| v.parse::<u64>().ok()).sum())
}

/// What one run's per-step interrupt counts say, in nanoseconds.
#[derive(Clone, Copy, Default)]
pub struct Split {
    /// The share of the timed steps an interrupt may have landed in.
    pub interrupted_share: f64,
    /// The clean steps' p50, p99, p99.9 and maximum.
    pub clean: [f64; 4],
    /// The share of the interrupted steps slower than [`crate::SLOW`] × the clean steps' p50,
    /// and their maximum (NaN if none).
    pub interrupted: [f64; 2],
    /// The share of the clean steps slower than [`crate::SLOW`] × their p50.
    pub clean_slow_share: f64,
}

/// Splits the steps' CPU times by whether their interrupt count moved.
pub fn split(cpu: &[u64], interrupts: &[u32]) -> Split {
    let mut clean: Vec<u64> = Vec::with_capacity(cpu.len());
    let mut hit: Vec<u64> = Vec::new();
    for (&c, &i) in cpu.iter().zip(interrupts) {
        if i == 0 {
            clean.push(c);
        } else {
            hit.push(c);
        }
    }
    clean.sort_unstable();
    hit.sort_unstable();
    let q = |v: &[u64], p: f64| {
        if v.is_empty() {
            f64::NAN
        } else {
            crate::quantile(v, p)
        }
    };
    let p50 = q(&clean, 0.5);
    Split {
        interrupted_share: hit.len() as f64 / cpu.len().max(1) as f64,
        clean: [p50, q(&clean, 0.99), q(&clean, 0.999), q(&clean, 1.0)],
        interrupted: [slow_share(&hit, p50), q(&hit, 1.0)],
        clean_slow_share: slow_share(&clean, p50),
    }
}

/// The share of `steps` slower than [`crate::SLOW`] × `p50` (NaN for none).
fn slow_share(steps: &[u64], p50: f64) -> f64 {
    let slow = steps
        .iter()
        .filter(|&&c| c as f64 > crate::SLOW * p50)
        .count();
    slow as f64 / steps.len() as f64
}

/// The controls' target lengths \[ns\]: from about the real-time mode's step of the LOES
/// presets to about the complete system's.
const CONTROLS: [f64; 4] = [2_000.0, 5_000.0, 10_000.0, 20_000.0];

/// Runs `configs` and the controls `rounds` times, interleaved, with the interrupts of each
/// step counted, and returns the Markdown table.
pub fn report(
    fmu: &crate::loader::Fmu,
    configs: &[crate::Config],
    steps: usize,
    rounds: usize,
) -> Result<String, String> {
    let mut counter = Counter::pinned()?;
    let controls = CONTROLS.map(crate::control::calibrate);
    let mut labels: Vec<String> = configs.iter().map(crate::name).collect();
    for (n, ns) in controls.iter().zip(CONTROLS) {
        labels.push(format!(
            "control: {n} dependent multiply-adds (about {:.0} µs) | – | – | –",
            ns / 1e3
        ));
    }
    let mut results: Vec<Vec<(crate::Figures, Split)>> = vec![Vec::new(); labels.len()];
    for round in 0..rounds {
        for (k, label) in labels.iter().enumerate() {
            let record = match configs.get(k) {
                Some(c) => crate::run(fmu, c, steps, Some(&mut counter), None),
                None => {
                    let n = controls[k - configs.len()];
                    let mut record = crate::Record::default();
                    crate::closed_loop(
                        crate::WARM_UP + steps,
                        1e-3,
                        &mut record,
                        Some(&mut counter),
                        None,
                        |_| Ok(()),
                        |_| {
                            std::hint::black_box(crate::control::multiply_adds(n));
                            Ok(())
                        },
                    )
                    .map(|()| record)
                }
            }
            .map_err(|e| format!("{label}: {e}"))?;
            let s = split(&record.cpu, &record.interrupts);
            let f = crate::figures(record);
            eprintln!(
                "round {}: {}: all p99.9 {:.1} µs, max {:.1} µs; interrupted {:.2} %; clean p50 \
                 {:.1} µs, p99.9 {:.1} µs, max {:.1} µs",
                round + 1,
                label,
                f.p999 / 1e3,
                f.max / 1e3,
                100.0 * s.interrupted_share,
                s.clean[0] / 1e3,
                s.clean[2] / 1e3,
                s.clean[3] / 1e3,
            );
            results[k].push((f, s));
        }
    }
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# The steps an interrupt lands in\n\n\
         Written by `cargo run --release --bin bench-latency -- --interrupts` (see \
         `src/bin/bench-latency/interrupts.rs` for the method) on {} pinned to processor {}, \
         {steps} timed steps after {} of warm-up, {rounds} rounds interleaved: each figure is \
         the median over the rounds with the range in brackets. The closed loop and the clocks \
         of `bench/latency.md`, and two reads of this processor's interrupt counts \
         (`/proc/interrupts`, every source) around each step. \"all\": every timed step of the \
         run. \"interrupted\": the share of the steps whose count moved; \"interrupted slow\" \
         the share of those slower than {} × the clean steps' p50. \"clean\": the steps whose count did not move, so that no interrupt was \
         handled while they ran; \"slow\" is the share of them slower than {} × their p50. \
         Thread CPU time in µs.\n",
        crate::cpu_model(),
        counter.cpu,
        crate::WARM_UP,
        crate::SLOW,
        crate::SLOW
    );
    let _ = writeln!(
        md,
        "| plant | step | solver | call | all p50 | all p99.9 | all max | interrupted | \
         interrupted slow | interrupted max | clean p50 | clean p99 | clean p99.9 | clean max | \
         clean max/p50 | clean slow |\n\
         | --- | ---: | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: \
         | ---: | ---: | ---: |"
    );
    for (label, r) in labels.iter().zip(&results) {
        let all = |f: fn(&crate::Figures) -> f64| {
            crate::us(&r.iter().map(|x| f(&x.0)).collect::<Vec<_>>())
        };
        let clean = |k: usize| crate::us(&r.iter().map(|x| x.1.clean[k]).collect::<Vec<_>>());
        let hit_max = crate::us(&r.iter().map(|x| x.1.interrupted[1]).collect::<Vec<_>>());
        let share = |f: fn(&Split) -> f64| {
            let (m, lo, hi) =
                crate::median_range(&r.iter().map(|x| 100.0 * f(&x.1)).collect::<Vec<_>>());
            format!("{m:.2} % ({lo:.2}–{hi:.2})")
        };
        let ratios: Vec<f64> = r.iter().map(|x| x.1.clean[3] / x.1.clean[0]).collect();
        let _ = writeln!(
            md,
            "| {label} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            all(|f| f.p50),
            all(|f| f.p999),
            all(|f| f.max),
            share(|s| s.interrupted_share),
            share(|s| s.interrupted[0]),
            hit_max,
            clean(0),
            clean(1),
            clean(2),
            clean(3),
            crate::ratio(&ratios),
            share(|s| s.clean_slow_share),
        );
    }
    Ok(md)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_sorts_steps_by_their_interrupt_count() {
        let cpu = [10, 11, 40, 12, 50, 13];
        let irq = [0, 0, 1, 0, 2, 0];
        let s = split(&cpu, &irq);
        assert_eq!(s.interrupted_share, 2.0 / 6.0);
        assert_eq!(s.clean, [11.0, 13.0, 13.0, 13.0]);
        assert_eq!(s.interrupted, [1.0, 50.0]);
        assert_eq!(s.clean_slow_share, 0.0);
    }

    #[test]
    fn the_counter_sees_the_timer_that_ends_a_sleep() {
        // The sleep ends by a timer interrupt on the processor the thread is pinned to.
        let mut c = Counter::pinned().expect("pinned counter");
        let a = c.read().unwrap();
        std::thread::sleep(std::time::Duration::from_millis(30));
        let b = c.read().unwrap();
        assert!(b > a, "{b} <= {a}");
    }
}
