//! The oscillation monitor: one warning when the position loop oscillates without decaying after
//! its command has settled (a limit cycle), with the oscillation's frequency and amplitude
//! (docs/model.md, "Where the model stops").
//!
//! The watched signal is the loop's error `e = reference − y_POT` \[V\] (the analog controller's
//! own input), sampled at the communication points. Once the loop's reference has been constant
//! for two windows of [`WINDOW`] seconds, every window the last two windows are compared: the
//! amplitude spectrum of each (a cubic trend taken out, then a Hann-windowed Fourier sum over the
//! samples, exact for uneven sampling) is evaluated from [`F_MIN`] to [`F_MAX`] Hz on a grid of
//! [`F_STEP`] and refined around its peaks. A spectral peak of the later window whose amplitude is above
//! [`AMPLITUDE_RAD`] of motor angle (times `k_pot`) and not below [`SUSTAINED`] times the earlier
//! window's at that frequency, and at least [`DOMINANT`] of the later window's largest
//! excursion, is an oscillation that does not decay: the monitor warns once per simulation. A
//! decaying vibration (the plate ringing after a move) always shows a smaller amplitude in the
//! later window and never warns, however slowly it decays.
//!
//! Limits: frequencies between [`F_MIN`] and the smaller of [`F_MAX`] and a quarter of the
//! sampling rate (5 Hz at 50 ms communication steps), as peaks inside that band (a maximum at
//! its edge is the flank of a slower or faster motion); a command that changes at every point (a
//! loop closed by the importer through `r`) never settles and is not watched; with
//! `controller.external` the FMU's loop is open and the monitor is off.
//!
//! Cost: a sample is kept at most every [`MIN_SPACING`] (400 per window); the spectra are
//! computed once per window of simulated time: on the grid about 4·10^4 complex multiply-adds and
//! two sine–cosine pairs a sample (`grid_sums`), at each peak two exact sums.

/// The length of each of the two compared windows \[s\]: four periods of the slowest loop mode
/// it is meant for (2 Hz), a frequency resolution of 0.5 Hz before refinement.
pub const WINDOW: f64 = 2.0;
/// Lowest frequency watched \[Hz\]: two periods in a window.
pub const F_MIN: f64 = 1.0;
/// Highest frequency watched \[Hz\]: above the loop's and the valve's slow modes, below the
/// structure's stiff ones, which no loop drives into a limit cycle.
pub const F_MAX: f64 = 25.0;
/// Grid step of the spectra \[Hz\]; the peak is refined by parabolic interpolation.
pub const F_STEP: f64 = 0.25;
/// The smallest amplitude reported, in motor angle \[rad\]: 1 mrad (0.057 deg), one and a half
/// counts of a 12-bit reading of the potentiometer's 150 deg.
pub const AMPLITUDE_RAD: f64 = 1e-3;
/// The later window's amplitude must be at least this fraction of the earlier one's: an
/// oscillation that loses less than 1 % in a window (at 3.3 Hz, a damping ratio below 2.4e-4)
/// does not decay; the fraction absorbs the round-off of equal amplitudes.
pub const SUSTAINED: f64 = 0.99;
/// The peak must carry at least this fraction of the later window's largest excursion (its
/// detrended error): a limit cycle is what the loop does, while a small growing component under
/// a larger ring-down (the harmonics the motor's seal friction adds as the motion decays) is a
/// detail of a decaying response.
pub const DOMINANT: f64 = 0.5;
/// The shortest spacing of the samples kept \[s\] (finer communication steps are thinned).
pub const MIN_SPACING: f64 = 0.005;

/// An oscillation found: frequency \[Hz\], amplitude in the later window and in the earlier one
/// \[V of loop error\], the time it was found and since when the command has been held \[s\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Oscillation {
    pub f_hz: f64,
    pub amplitude: f64,
    pub earlier: f64,
    pub t: f64,
    pub held_since: f64,
}

/// The monitor's memory over a simulation.
#[derive(Clone, Debug, Default)]
pub struct OscillationWatch {
    /// `(t, e)` since the reference last changed: the last two windows, and before them at
    /// most as many older samples, not yet dropped.
    samples: Vec<(f64, f64)>,
    /// The reference at the last sample (bits), and since when it has been constant.
    reference: Option<u64>,
    held_since: f64,
    /// Simulated time of the next comparison.
    next_check: f64,
    warned: bool,
    /// The two windows' [`detrended`] samples (memory reused: no allocation in the steady
    /// state).
    scratch: [Vec<(f64, f64, f64)>; 2],
    /// The later window's [`grid_sums`] (memory reused as well).
    sums: Vec<(f64, f64)>,
}

impl OscillationWatch {
    /// Forgets everything (a new simulation, or a restored state).
    pub fn reset(&mut self) {
        *self = OscillationWatch::default();
    }

    /// Whether the monitor has warned in this simulation.
    pub fn has_warned(&self) -> bool {
        self.warned
    }

    /// Keeps the sample `(t, e)` unless the last one kept is less than [`MIN_SPACING`] before.
    fn record(&mut self, t: f64, e: f64) {
        if self
            .samples
            .last()
            .is_none_or(|&(last, _)| t - last >= MIN_SPACING * (1.0 - 1e-9))
        {
            self.samples.push((t, e));
        }
    }

    /// The index of the first sample of the two windows before `t` (and of the sample just
    /// before them, which weights the first), after the older samples were dropped if they are
    /// as many as the kept ones. They are not dropped at every point: moving the kept ones to
    /// the front at every point cost a copy of up to 800 samples a point, about a third of the
    /// monitor's cost.
    fn keep_two_windows(&mut self, t: f64) -> usize {
        let start = t - 2.0 * WINDOW;
        let first = self
            .samples
            .partition_point(|&(s, _)| s < start)
            .saturating_sub(1);
        if first > 0 && 2 * first >= self.samples.len() {
            self.samples.drain(..first);
            return 0;
        }
        first
    }

    /// Takes the sample at the communication point `t` (the loop's reference and error \[V\]);
    /// returns the oscillation the first time one is found. `threshold` is the amplitude of
    /// error \[V\] below which nothing is reported.
    pub fn observe(
        &mut self,
        t: f64,
        reference: f64,
        error: f64,
        threshold: f64,
    ) -> Option<Oscillation> {
        if self.warned || !(t.is_finite() && error.is_finite()) {
            return None;
        }
        if self.reference != Some(reference.to_bits()) {
            self.reference = Some(reference.to_bits());
            self.held_since = t;
            self.samples.clear();
            self.next_check = t + 2.0 * WINDOW;
        }
        self.record(t, error);
        let first = self.keep_two_windows(t);
        if t < self.next_check {
            return None;
        }
        self.next_check = t + WINDOW;
        let found = compare(
            &self.samples[first..],
            t,
            threshold,
            &mut self.scratch,
            &mut self.sums,
        )?;
        self.warned = true;
        Some(Oscillation {
            held_since: self.held_since,
            ..found
        })
    }
}

/// The samples of `s` in `[a, b)` ready for [`amplitude`]: `(t − a, residual, weight)`, the
/// residual being what is left of the signal after a least-squares cubic in time (weighted by
/// the time to the next sample) is taken out, the weight the Hann window times that time. The
/// cubic removes what moves slower than the window (a drift, or a mode below [`F_MIN`] whose
/// Hann side lobes would otherwise show as a peak inside the band); a sinusoid of two or more
/// periods in the window is almost orthogonal to it.
fn detrended(s: &[(f64, f64)], a: f64, b: f64, points: &mut Vec<(f64, f64, f64)>) {
    let span = b - a;
    points.clear();
    points.extend(
        s.iter()
            .enumerate()
            .filter(|(_, &(t, _))| t >= a && t < b)
            .map(|(k, &(t, e))| {
                let dt = s.get(k + 1).map_or(0.0, |&(n, _)| n.min(b) - t);
                (t - a, e, dt)
            }),
    );
    // Normal equations of the cubic in x = 2 (t - a) / span - 1, in [-1, 1).
    let basis = |x: f64| [1.0, x, x * x, x * x * x];
    let mut gram = nalgebra::Matrix4::<f64>::zeros();
    let mut rhs = nalgebra::Vector4::<f64>::zeros();
    for &(t, e, dt) in points.iter() {
        let p = basis(2.0 * t / span - 1.0);
        for i in 0..4 {
            rhs[i] += dt * p[i] * e;
            for j in 0..4 {
                gram[(i, j)] += dt * p[i] * p[j];
            }
        }
    }
    let coefficients = gram
        .lu()
        .solve(&rhs)
        .unwrap_or_else(nalgebra::Vector4::zeros);
    for (t, e, dt) in points.iter_mut() {
        let p = basis(2.0 * *t / span - 1.0);
        *e -= (0..4).map(|i| coefficients[i] * p[i]).sum::<f64>();
        let hann = 0.5 - 0.5 * crate::math::cos(2.0 * core::f64::consts::PI * *t / span);
        *dt *= hann;
    }
}

/// The amplitude at `f` \[Hz\] of a sinusoid in the [`detrended`] samples `points`: the
/// Hann-windowed Fourier sum, exact for uneven spacing.
fn amplitude(points: &[(f64, f64, f64)], f: f64) -> f64 {
    let w = 2.0 * core::f64::consts::PI * f;
    let (mut re, mut im, mut sw) = (0.0, 0.0, 0.0);
    for &(t, e, q) in points {
        let (sin, cos) = crate::math::sin_cos(w * t);
        re += q * e * cos;
        im -= q * e * sin;
        sw += q;
    }
    magnitude((re, im), sw)
}

/// The Fourier sums of [`amplitude`] at the `n` grid frequencies `F_MIN + k F_STEP` into
/// `sums` (their amplitudes are [`magnitude`]`(sums[k], weight)`, the weight returned), with two
/// sine–cosine evaluations a sample instead of one a sample and frequency: each sample's phasor
/// `exp(-j w t)` is carried from one grid frequency to the next by the rotation
/// `exp(-j 2 pi F_STEP t)`. After `k` rotations its rounding is within about `k` units in the
/// last place, a relative 1e-14 over the grid, against the 1 % the monitor's decisions rest on;
/// the peaks found on the grid are then evaluated by [`amplitude`] itself.
fn grid_sums(points: &[(f64, f64, f64)], n: usize, sums: &mut Vec<(f64, f64)>) -> f64 {
    sums.clear();
    sums.resize(n, (0.0, 0.0));
    let mut sw = 0.0;
    for &(t, e, q) in points {
        let (s0, c0) = crate::math::sin_cos(2.0 * core::f64::consts::PI * F_MIN * t);
        let (sd, cd) = crate::math::sin_cos(2.0 * core::f64::consts::PI * F_STEP * t);
        let (mut c, mut s) = (c0, s0);
        let qe = q * e;
        for (re, im) in sums.iter_mut() {
            *re += qe * c;
            *im -= qe * s;
            (c, s) = (c * cd - s * sd, s * cd + c * sd);
        }
        sw += q;
    }
    sw
}

/// The amplitude of a sinusoid from its Hann-windowed Fourier sum `(re, im)` and the window's
/// total weight `sw`.
fn magnitude((re, im): (f64, f64), sw: f64) -> f64 {
    if sw <= 0.0 {
        return 0.0;
    }
    2.0 * (re * re + im * im).sqrt() / sw
}

/// Compares the two windows ending at `t`: the largest spectral peak of the later one above
/// `threshold` whose amplitude is at least [`SUSTAINED`] times the earlier window's at the same
/// frequency.
fn compare(
    s: &[(f64, f64)],
    t: f64,
    threshold: f64,
    scratch: &mut [Vec<(f64, f64, f64)>; 2],
    sums: &mut Vec<(f64, f64)>,
) -> Option<Oscillation> {
    let (a, m) = (t - 2.0 * WINDOW, t - WINDOW);
    // The band the sampling resolves: a quarter of the sampling rate.
    let spacing = s
        .windows(2)
        .filter(|p| p[1].0 > a)
        .map(|p| p[1].0 - p[0].0)
        .fold(0.0, f64::max);
    let f_max = F_MAX.min(0.25 / spacing.max(f64::MIN_POSITIVE));
    let n = ((f_max - F_MIN) / F_STEP).floor() as usize + 1;
    let [earlier, later] = scratch;
    detrended(s, a, m, earlier);
    detrended(s, m, t + 1e-9, later);
    let sw = grid_sums(later, n, sums);
    let at = |k: usize| magnitude(sums[k], sw);
    let excursion = later.iter().fold(0.0, |m: f64, p| m.max(p.1.abs()));
    let mut best: Option<Oscillation> = None;
    // Interior peaks only: a maximum at an end of the band is the flank of something outside it.
    // The spectrum at bins k - 1, k, k + 1, slid along the grid.
    let (mut left, mut centre) = (at(0), at(1.min(n - 1)));
    for k in 1..n.saturating_sub(1) {
        let (l, c, r) = (left, centre, at(k + 1));
        (left, centre) = (c, r);
        if !(c >= l && c >= r) || c <= threshold {
            continue;
        }
        // Parabolic interpolation of the peak on the grid.
        let den = l - 2.0 * c + r;
        let shift = if den < 0.0 { 0.5 * (l - r) / den } else { 0.0 };
        let f = F_MIN + (k as f64 + shift.clamp(-0.5, 0.5)) * F_STEP;
        let now = amplitude(later, f);
        let before = amplitude(earlier, f);
        if now > threshold
            && now >= SUSTAINED * before
            && now >= DOMINANT * excursion
            && best.is_none_or(|b| now > b.amplitude)
        {
            best = Some(Oscillation {
                f_hz: f,
                amplitude: now,
                earlier: before,
                t,
                held_since: f64::NAN,
            });
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs the watch over `e(t)` sampled every `h` to `stop`, the reference held from 0.
    fn watch(h: f64, stop: f64, e: impl Fn(f64) -> f64) -> Option<Oscillation> {
        let mut w = OscillationWatch::default();
        let n = (stop / h).round() as usize;
        (1..=n).find_map(|k| {
            let t = k as f64 * h;
            w.observe(t, 1.0, e(t), 0.004)
        })
    }

    #[test]
    fn a_sustained_sinusoid_is_found_with_its_frequency_and_amplitude() {
        for (h, f) in [(0.005, 3.3), (0.001, 7.9), (0.02, 1.6)] {
            let o = watch(h, 10.0, |t| {
                0.02 * crate::math::sin(2.0 * core::f64::consts::PI * f * t)
            })
            .unwrap_or_else(|| panic!("{f} Hz at h = {h}: not found"));
            assert!((o.f_hz - f).abs() < 0.02 * f, "{f} Hz: {o:?}");
            assert!((o.amplitude - 0.02).abs() < 0.002, "{o:?}");
            // Found at the first comparison: two windows after the reference settled.
            assert!((o.t - 2.0 * WINDOW).abs() < 1.5 * h, "{o:?}");
        }
    }

    #[test]
    fn a_growing_oscillation_is_found_and_a_decaying_one_is_not() {
        let sine = |t: f64, sigma: f64| {
            0.02 * crate::math::exp(sigma * t)
                * crate::math::sin(2.0 * core::f64::consts::PI * 3.3 * t)
        };
        assert!(watch(0.005, 10.0, |t| sine(t, 0.05)).is_some());
        // Decaying as slowly as a mode of damping ratio 4.8e-4 at 3.3 Hz (2 % per window): not
        // sustained.
        assert!(watch(0.005, 20.0, |t| sine(t, -0.01)).is_none());
        // A slow decaying ring plus noise-free constant: nothing.
        assert!(watch(0.005, 20.0, |t| 0.5 + sine(t, -0.2)).is_none());
        // A small component growing under a larger ring-down at 1.2 Hz (friction's harmonics):
        // nothing while the ring dominates; reported once the growing one does.
        let ring = |t: f64| {
            0.2 * crate::math::exp(-0.3 * t)
                * crate::math::sin(2.0 * core::f64::consts::PI * 1.2 * t)
        };
        let o = watch(0.005, 30.0, |t| ring(t) + 0.005 * sine(t, 0.05) / 0.02)
            .expect("the growing oscillation, once it dominates");
        assert!((o.f_hz - 3.3).abs() < 0.1 && o.t > 8.0, "{o:?}");
    }

    #[test]
    fn below_the_threshold_or_while_the_command_moves_nothing_is_reported() {
        assert!(watch(0.005, 10.0, |t| 0.003
            * crate::math::sin(2.0 * core::f64::consts::PI * 3.0 * t))
        .is_none());
        let mut w = OscillationWatch::default();
        for k in 1..=2000 {
            let t = k as f64 * 0.005;
            // The reference changes at every point (an importer's loop): never settled.
            let e = 0.05 * crate::math::sin(2.0 * core::f64::consts::PI * 3.0 * t);
            assert!(w.observe(t, t, e, 0.004).is_none());
        }
    }

    /// The grid's sums by rotation are the direct sums of [`amplitude`] to rounding, on
    /// unevenly spaced samples over a window at the far end of a long run (large `t`, where
    /// the rotation's phase is largest).
    #[test]
    fn the_rotated_grid_sums_are_the_direct_ones() {
        let points: Vec<(f64, f64, f64)> = (0..400)
            .map(|k| {
                let t = 1000.0 + 0.005 * k as f64 + 1e-3 * crate::math::sin(k as f64);
                let e = crate::math::cos(7.7 * t) + 0.3 * crate::math::sin(31.0 * t);
                (t, e, 0.005 + 1e-4 * (k % 7) as f64)
            })
            .collect();
        let n = ((F_MAX - F_MIN) / F_STEP) as usize + 1;
        let mut sums = Vec::new();
        let sw = grid_sums(&points, n, &mut sums);
        let largest = (0..n)
            .map(|k| amplitude(&points, F_MIN + k as f64 * F_STEP))
            .fold(0.0, f64::max);
        for (k, &sum) in sums.iter().enumerate() {
            let direct = amplitude(&points, F_MIN + k as f64 * F_STEP);
            let rotated = magnitude(sum, sw);
            assert!(
                (rotated - direct).abs() <= 1e-11 * largest,
                "bin {k}: {rotated} against {direct}"
            );
        }
    }

    /// At every point the samples compared start at the one just before the two windows,
    /// whether or not the older ones are dropped at that point (at 5 ms and at 1 ms
    /// communication steps, the latter thinned to [`MIN_SPACING`] as `observe` thins them).
    #[test]
    fn the_samples_compared_are_the_two_windows_at_every_point() {
        for h in [0.005, 0.001] {
            let mut w = OscillationWatch::default();
            let mut drops = 0;
            for k in 1..=(30.0 / h) as usize {
                let t = k as f64 * h;
                w.record(t, 0.0);
                let before = w.samples.len();
                let first = w.keep_two_windows(t);
                drops += usize::from(w.samples.len() < before);
                let kept = &w.samples[first..];
                let start = t - 2.0 * WINDOW;
                assert!(kept.len() < 2 || kept[1].0 >= start, "h = {h}, t = {t}");
                assert!(first == 0 || kept[0].0 < start, "h = {h}, t = {t}");
            }
            assert!(drops > 0, "h = {h}: no drop exercised");
        }
    }

    #[test]
    fn it_warns_once() {
        let mut w = OscillationWatch::default();
        let found = (1..=4000)
            .filter_map(|k| {
                let t = k as f64 * 0.005;
                w.observe(
                    t,
                    1.0,
                    0.05 * crate::math::sin(2.0 * core::f64::consts::PI * 3.0 * t),
                    0.004,
                )
            })
            .count();
        assert_eq!(found, 1);
        assert!(w.has_warned());
    }
}
