//! A warm-up: a drift at the start of an axis that the Allan analysis would take for random
//! walk or ramp (it raises the long-τ curve).
//!
//! **Detection**, free of any fitted noise model: the mean of the start against the mean of
//! what follows, at every scale — the first T/200 of the record against its second half,
//! and the first `T_k` against `[2T_k, 4T_k)` for `T_k` = T/200, T/100, … up to T/8 (a
//! drift of time constant `T_k` is most of the first mean and little of the other). Each
//! difference's variance is ≈ σ²(a) + σ²(b) + 2σ²(Δ) (σ² the record's own Allan variance,
//! a and b the two means' lengths, Δ the distance between them: their noise and how far the
//! bias may wander in between). σ² is measured on the whole record's window means, robustly
//! (the median of the squared differences of overlapping cluster means, so that the drift
//! at the start, a few of them, does not raise it), up to clusters of an eighth of the
//! record, and extrapolated beyond as a random walk (the steepest ordinary growth:
//! conservative). A start beyond [`WARMUP_Z`] of that at any scale is a warm-up.
//!
//! **Power** (the seeded study `warmup_power_study` in `tests/warmup_power.rs`, which
//! `scripts/test.sh` runs): on white noise, a drift `a·exp(−t/T)` with `a` in standard
//! deviations σ of the first window's mean (the record's first two-hundredth) is flagged on
//! 39–40 of 40 records from `a` = 10 σ when T is four windows to an eighth of the record,
//! 32–38 of 40 at one window, and on every record from 14 σ, for 10 min, 1 h, 4 h and 24 h
//! (at 6 σ: 27–37 of 40 from four windows, 4–9 at one); its drift-free records (white
//! noise, and white noise with a random walk as large as it at a twentieth of the record)
//! gave 1 false alarm in 2000. Each axis is tested on its own, so a drift on three axes is
//! flagged on each with that power. A random walk the record shows takes its share: a drift
//! within what the walk can do in the same time is not told from it.
//!
//! **Size and advice**: an exponential `c + a·exp(−t/T)` fitted by least squares to the
//! window means of the whole record (T by a log-grid search and golden-section refinement,
//! `c` and `a` linear). The advised `--skip-start` covers the decay until what is left is a
//! [`WARMUP_RESIDUAL`] of the noise's own Allan deviation at τ = T, and at least
//! [`WARMUP_MIN_CONSTANTS`] time constants, so that the rerun leaves no drift the analysis
//! could see.

use super::{Axis, Finding, Kind, Level};

/// A start this many standard deviations from what follows, at some scale, is not noise
/// (the variance is conservative: 1 of the study's 2000 drift-free records went past it).
pub const WARMUP_Z: f64 = 4.0;
/// Window means over the record for the exponential fit (of at least 10 samples each).
pub const WARMUP_WINDOWS: usize = 1000;
/// Fine windows per detection window: the first T/200 of the record is compared.
pub const DETECT_WINDOWS: usize = 5;
/// Samples per window at least.
const MIN_WINDOW: usize = 10;
/// Clusters the record's Allan variance is taken over at least (an eighth of the record
/// at the longest: its overlapping differences are about 8 independent ones).
pub const NOISE_CLUSTERS: usize = 8;
/// The median of a χ² variable of one degree of freedom: the median of the squared
/// difference of two Gaussian means is this times its mean.
const MEDIAN_CHI2_1: f64 = 0.454_936_423_119_572_8;
/// The advised skip leaves at most this fraction of the noise's Allan deviation at τ = T.
pub const WARMUP_RESIDUAL: f64 = 0.25;
/// The advised skip covers at least this many time constants (1.8 % of the drift left).
pub const WARMUP_MIN_CONSTANTS: f64 = 4.0;
/// A skip longer than this share of the record leaves too little of it: record longer.
pub const MAX_SKIP_SHARE: f64 = 0.5;
/// Time constants searched, as multiples of the window: up to ten records.
const GRID_POINTS: usize = 60;

/// The fitted warm-up of one axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fit {
    /// Length of the start compared, s (T/200, or 50 samples at least, or a longer scale).
    pub start: f64,
    /// What it was compared with: from and to, s (the second half, or `[2·start, 4·start)`).
    pub reference: (f64, f64),
    /// Its mean minus the reference's mean, in the signal's unit.
    pub start_offset: f64,
    /// That in standard deviations of the noise.
    pub sigmas: f64,
    /// `a` of `c + a·exp(−t/T)`: the drift at t = 0.
    pub amplitude: f64,
    /// `T`, s.
    pub tau: f64,
    /// `c`: the level it settles to.
    pub level: f64,
    /// The noise's Allan deviation at τ = T.
    pub noise_at_tau: f64,
    /// The `--skip-start` that outlasts it, s.
    pub skip: f64,
    /// The drift left after that skip.
    pub left: f64,
}

impl Fit {
    /// The drift at `t` s.
    pub fn drift(&self, t: f64) -> f64 {
        self.amplitude * (-t / self.tau).exp()
    }
}

/// The record's own Allan variance from its window means `m` (each `wt` s), robustly: at
/// octave cluster sizes and at an eighth of the record (at least [`NOISE_CLUSTERS`]
/// clusters), the median of the squared differences of overlapping cluster means over
/// [`MEDIAN_CHI2_1`] (a drift confined to the start, a minority of them, barely moves it).
/// (τ, AVAR) pairs in increasing τ.
fn robust_avar(m: &[f64], wt: f64) -> Vec<(f64, f64)> {
    let j = m.len();
    let mut prefix = Vec::with_capacity(j + 1);
    prefix.push(0.0);
    for &x in m {
        prefix.push(prefix[prefix.len() - 1] + x);
    }
    let mut sizes: Vec<usize> = std::iter::successors(Some(1usize), |c| Some(c * 2))
        .take_while(|&c| j / c >= NOISE_CLUSTERS)
        .collect();
    if sizes.last().is_some_and(|&c| j / NOISE_CLUSTERS > c) {
        sizes.push(j / NOISE_CLUSTERS);
    }
    let mut out = Vec::new();
    for c in sizes {
        let mut d: Vec<f64> = (0..=j - 2 * c)
            .map(|k| {
                let a = prefix[k + c] - prefix[k];
                let b = prefix[k + 2 * c] - prefix[k + c];
                ((b - a) / c as f64).powi(2)
            })
            .collect();
        let k = d.len() / 2;
        let med = *d.select_nth_unstable_by(k, f64::total_cmp).1;
        let avar = med / (2.0 * MEDIAN_CHI2_1);
        if avar > 0.0 && avar.is_finite() {
            out.push((c as f64 * wt, avar));
        }
    }
    out
}

/// σ²(τ) from the measured points: log-log between them, a random walk beyond the last,
/// white noise before the first.
fn noise_at(points: &[(f64, f64)], tau: f64) -> f64 {
    let (first, last) = (points[0], points[points.len() - 1]);
    if tau <= first.0 {
        return first.1 * first.0 / tau;
    }
    if tau >= last.0 {
        return last.1 * tau / last.0;
    }
    let k = points.partition_point(|p| p.0 <= tau);
    let (a, b) = (points[k - 1], points[k]);
    let x = (tau / a.0).ln() / (b.0 / a.0).ln();
    (a.1.ln() + x * (b.1 / a.1).ln()).exp()
}

/// Least squares of `m ≈ c + a·exp(−t/T)` for one T: (c, a, SSE).
fn fit_at(m: &[f64], t: &[f64], tau: f64) -> (f64, f64, f64) {
    let n = m.len() as f64;
    let (mut sx, mut sxx, mut sy, mut sxy) = (0.0, 0.0, 0.0, 0.0);
    for (&y, &tj) in m.iter().zip(t) {
        let x = (-tj / tau).exp();
        sx += x;
        sxx += x * x;
        sy += y;
        sxy += x * y;
    }
    let det = n * sxx - sx * sx;
    if det.abs() <= f64::MIN_POSITIVE {
        return (sy / n, 0.0, f64::INFINITY);
    }
    let a = (n * sxy - sx * sy) / det;
    let c = (sy - a * sx) / n;
    let sse = m
        .iter()
        .zip(t)
        .map(|(&y, &tj)| (y - c - a * (-tj / tau).exp()).powi(2))
        .sum();
    (c, a, sse)
}

/// The best exponential for the window means `m` at times `t` (T between `lo` and `hi`).
fn fit_exponential(m: &[f64], t: &[f64], lo: f64, hi: f64) -> (f64, f64, f64) {
    let ln_lo = lo.ln();
    let step = (hi / lo).ln() / (GRID_POINTS - 1) as f64;
    let sse_at = |l: f64| fit_at(m, t, l.exp()).2;
    let best = (0..GRID_POINTS)
        .map(|i| (i, sse_at(ln_lo + i as f64 * step)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(0, |x| x.0);
    // golden section on ln T between the neighbours of the best grid point
    let (mut a, mut b) = (
        ln_lo + best.saturating_sub(1) as f64 * step,
        ln_lo + (best + 1).min(GRID_POINTS - 1) as f64 * step,
    );
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let (mut x1, mut x2) = (b - g * (b - a), a + g * (b - a));
    let (mut f1, mut f2) = (sse_at(x1), sse_at(x2));
    for _ in 0..40 {
        if f1 < f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - g * (b - a);
            f1 = sse_at(x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + g * (b - a);
            f2 = sse_at(x2);
        }
    }
    let tau = ((a + b) / 2.0).exp();
    let (c, amp, _) = fit_at(m, t, tau);
    (c, amp, tau)
}

/// The start compared with what follows at the largest significance: (its length, the
/// reference's span, the difference of the means, its z), all in s and the signal's unit.
type Departure = (f64, (f64, f64), f64, f64);

/// The start of the window means `m` (`wt` s each) against what follows, at every scale
/// (see the module's doc), with the noise `noise(τ)`: the most significant departure.
fn departure(m: &[f64], wt: f64, noise: &dyn Fn(f64) -> f64) -> Option<Departure> {
    let j = m.len();
    let total = j as f64 * wt;
    let mean = |a: usize, b: usize| m[a..b].iter().sum::<f64>() / (b - a) as f64;
    let z = |d: f64, var: f64| d.abs() / var.max(f64::MIN_POSITIVE).sqrt();
    // the first T/200 against the second half
    let wd = DETECT_WINDOWS as f64 * wt;
    let d = mean(0, DETECT_WINDOWS) - mean(j / 2, j);
    let var = noise(wd) + noise(total / 2.0) + 2.0 * noise(0.75 * total - 0.5 * wd);
    let mut best = (wd, ((j / 2) as f64 * wt, total), d, z(d, var));
    // the first k windows against [2k, 4k), k doubling up to an eighth of the record
    let mut k = DETECT_WINDOWS;
    while 4 * k <= j / 2 {
        let t = k as f64 * wt;
        let d = mean(0, k) - mean(2 * k, 4 * k);
        let var = noise(t) + noise(2.0 * t) + 2.0 * noise(2.5 * t);
        let zk = z(d, var);
        if zk > best.3 {
            best = (t, (2.0 * t, 4.0 * t), d, zk);
        }
        k *= 2;
    }
    best.3.is_finite().then_some(best)
}

/// The warm-up of `y` (samples `tau0` s apart), `None` when its start is within the noise.
pub fn find(y: &[f64], tau0: f64) -> Option<Fit> {
    let n = y.len();
    let w = (n / WARMUP_WINDOWS).max(MIN_WINDOW);
    let j = n / w;
    if j < 12 * DETECT_WINDOWS || tau0.is_nan() || tau0 <= 0.0 {
        return None;
    }
    let wt = w as f64 * tau0;
    let m: Vec<f64> = y
        .chunks_exact(w)
        .map(|c| c.iter().sum::<f64>() / w as f64)
        .collect();
    let total = n as f64 * tau0;
    let points = robust_avar(&m, wt);
    if points.is_empty() {
        return None;
    }
    let noise = |tau: f64| noise_at(&points, tau);
    let (start, reference, d0, z0) = departure(&m, wt, &noise)?;
    if z0 <= WARMUP_Z {
        return None;
    }
    let t: Vec<f64> = (0..j).map(|k| (k as f64 + 0.5) * wt).collect();
    let (level, amplitude, tau) = fit_exponential(&m, &t, wt, 10.0 * total);
    let noise_at_tau = noise(tau).sqrt();
    let constants = (amplitude.abs() / (WARMUP_RESIDUAL * noise_at_tau))
        .ln()
        .max(WARMUP_MIN_CONSTANTS);
    let skip = tau * constants;
    Some(Fit {
        start,
        reference,
        start_offset: d0,
        sigmas: z0,
        amplitude,
        tau,
        level,
        noise_at_tau,
        skip,
        left: amplitude.abs() * (-constants).exp(),
    })
}

/// The finding of one axis' warm-up in a record of `record` s.
pub fn finding(axis: Axis, f: &Fit, record: f64) -> Finding {
    let unit = axis.sensor.unit();
    let skip = f.skip.ceil();
    let short = if skip > MAX_SKIP_SHARE * record {
        format!(
            "; that leaves {:.0} s of this {:.0} s record: record longer (at least {:.0} s), or the long-τ terms stay out of reach",
            (record - skip).max(0.0),
            record,
            2.0 * skip
        )
    } else {
        String::new()
    };
    let mut fnd = Finding::new(
        Level::Warning,
        Kind::WarmUp,
        format!(
            "the first {:.1} s differ from the mean of t = {:.1} – {:.1} s by {:+.3e} {unit} ({:.0} σ of the noise): a drift, fitted as {:+.3e}·exp(−t / {:.0} s) {unit}; the Allan analysis takes it for random walk or ramp. Rerun with --skip-start {skip:.0} ({:.1} time constants; {:.1e} {unit} left, {:.0} % of the noise's Allan deviation at τ = {:.0} s){short}",
            f.start,
            f.reference.0,
            f.reference.1,
            f.start_offset,
            f.sigmas,
            f.amplitude,
            f.tau,
            skip / f.tau,
            f.left,
            100.0 * f.left / f.noise_at_tau,
            f.tau
        ),
    )
    .on(axis)
    .sized(f.amplitude.abs(), unit);
    fnd.time = Some(0.0);
    fnd.sample = Some(0);
    fnd.skip_start = Some(skip);
    fnd
}

#[cfg(test)]
mod tests {
    use super::*;

    const RNG_SEED: u64 = 0x0057_A710;

    /// White noise + random walk, per-sample σ `sd` and walk step `k` (sim's generator at
    /// a 1 s step, where the continuous and the per-sample figures are the same numbers).
    fn white_and_walk(seed: u64, n: usize, sd: f64, k: f64) -> Vec<f64> {
        sim::white_rw_axis(sd, k, 1.0, n, seed)
    }

    #[test]
    fn the_noise_interpolates_and_extrapolates_as_white_and_walk() {
        let p = [(1.0, 1.0), (4.0, 0.25)];
        const EXACT: f64 = 1e-12;
        assert!((noise_at(&p, 2.0) - 0.5).abs() < EXACT);
        assert!((noise_at(&p, 0.5) - 2.0).abs() < EXACT);
        assert!((noise_at(&p, 8.0) - 0.5).abs() < EXACT);
    }

    #[test]
    fn clean_records_stay_quiet() {
        // white noise, and white noise + random walk: no false alarm in 20 records each
        for rep in 0..20 {
            let y = white_and_walk(RNG_SEED + 2 * rep, 100_000, 0.1, 0.0);
            assert_eq!(find(&y, 0.01), None, "white {rep}");
            let y = white_and_walk(RNG_SEED + 2 * rep + 1, 100_000, 0.1, 2e-3);
            assert_eq!(find(&y, 0.02), None, "walk {rep}");
        }
    }

    #[test]
    fn an_exponential_warm_up_is_fitted_and_the_skip_outlasts_it() {
        let (n, tau0, sd, k) = (180_000usize, 0.01, 0.01, 2e-6);
        let clean = white_and_walk(RNG_SEED + 100, n, sd, k);
        let y: Vec<f64> = clean
            .iter()
            .enumerate()
            .map(|(i, v)| v + 0.02 * (-(i as f64 * tau0) / 100.0).exp())
            .collect();
        let f = find(&y, tau0).expect("warm-up");
        // the fitted exponential within 5 % (amplitude) and 10 % (time constant): window
        // means of 0.18 s carry 2e-3 of noise each, the drift starts at 0.02
        const AMP_REL_TOL: f64 = 0.05;
        const TAU_REL_TOL: f64 = 0.10;
        assert!((f.amplitude / 0.02 - 1.0).abs() < AMP_REL_TOL, "{f:?}");
        assert!((f.tau / 100.0 - 1.0).abs() < TAU_REL_TOL, "{f:?}");
        assert!(f.skip >= WARMUP_MIN_CONSTANTS * f.tau, "{f:?}");
        // what the skip leaves of the true drift is within the residual allowed
        let left = 0.02 * (-f.skip / 100.0).exp();
        assert!(
            left <= 1.5 * WARMUP_RESIDUAL * f.noise_at_tau,
            "{f:?}, left {left}"
        );
        // and the rerun sees no warm-up
        let k0 = (f.skip.ceil() / tau0) as usize;
        assert_eq!(find(&y[k0..], tau0), None);
    }
}
