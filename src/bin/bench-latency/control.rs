//! The control the FMU's steps are compared with: work of a fixed operation count, calibrated to
//! a length of thread CPU time on this machine. Its steps do the same work every time, so
//! whatever spreads their times (interrupts, the hypervisor, the other processes' use of the
//! caches and of the shared core) is the machine's; the FMU's tails are the machine's as far as
//! they match the control's of the same p50, timed the same way in the same run.

/// A dependent chain of `n` multiply-adds: work of a fixed operation count that touches no
/// memory.
pub fn multiply_adds(n: u64) -> f64 {
    let mut x = 1.0f64;
    for _ in 0..n {
        x = std::hint::black_box(x) * 0.999_999_9 + 1e-7;
    }
    x
}

/// The chain length whose run, timed by [`crate::timed`], takes about `ns` nanoseconds of
/// thread CPU time here: the median of 21 timed runs of a long chain gives the time of one
/// multiply-add, the median of 21 timings of nothing the clocks' own cost, which the timed
/// run includes.
pub fn calibrate(ns: f64) -> u64 {
    const N: u64 = 200_000;
    let mut clocks: Vec<u64> = (0..21).map(|_| crate::timed(|| {}).0).collect();
    clocks.sort_unstable();
    let mut t: Vec<u64> = (0..21)
        .map(|_| {
            crate::timed(|| {
                std::hint::black_box(multiply_adds(N));
            })
            .0
        })
        .collect();
    t.sort_unstable();
    ((ns - clocks[10] as f64) / (t[10] as f64 / N as f64))
        .round()
        .max(1.0) as u64
}
