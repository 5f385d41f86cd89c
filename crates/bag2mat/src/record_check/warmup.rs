//! A warm-up: a drift at the start of an axis that the Allan analysis would take for random
//! walk or ramp (it raises the long-τ curve).
//!
//! **Detection**, free of any fitted noise model: the mean of the first T/200 of the record
//! against the mean of its second half. The difference's variance is ≈ σ²(w) + σ²(T/2) +
//! 2σ²(Δ) (σ² the record's own Allan variance, w the window, Δ the distance between the two
//! means: their noise and how far the bias may wander in between), σ² measured on the second
//! half's window means (non-overlapping, at least [`TAIL_CLUSTERS`] clusters) and extrapolated
//! beyond its longest τ as a random walk (the steepest ordinary growth: conservative). A start
//! beyond [`WARMUP_Z`] of that is a warm-up.
//!
//! **Size and advice**: an exponential `c + a·exp(−t/T)` fitted by least squares to the
//! window means of the whole record (T by a log-grid search and golden-section refinement,
//! `c` and `a` linear). The advised `--skip-start` covers the decay until what is left is a
//! [`WARMUP_RESIDUAL`] of the noise's own Allan deviation at τ = T, and at least
//! [`WARMUP_MIN_CONSTANTS`] time constants, so that the rerun leaves no drift the analysis
//! could see.

use super::{Axis, Finding, Kind, Level};

/// A start this many standard deviations from the rest is not noise.
pub const WARMUP_Z: f64 = 5.0;
/// Window means over the record for the exponential fit (of at least 10 samples each).
pub const WARMUP_WINDOWS: usize = 1000;
/// Fine windows per detection window: the first T/200 of the record is compared.
const DETECT_WINDOWS: usize = 5;
/// Samples per window at least.
const MIN_WINDOW: usize = 10;
/// Clusters the second half's Allan variance is taken over at least (its EDF ≈ 9 for random
/// walk, so it is rarely half the truth).
pub const TAIL_CLUSTERS: usize = 10;
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
    /// Length of the start compared, s (T/200, or 50 samples at least).
    pub start: f64,
    /// Its mean minus the second half's mean, in the signal's unit.
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

/// The record's own Allan variance from its second half's window means: (τ, AVAR) at
/// octave cluster sizes, at least [`TAIL_CLUSTERS`] clusters each.
fn tail_avar(tail: &[f64], wt: f64) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    let mut c = 1;
    while tail.len() / c >= TAIL_CLUSTERS {
        let means: Vec<f64> = tail
            .chunks_exact(c)
            .map(|x| x.iter().sum::<f64>() / c as f64)
            .collect();
        let avar = means.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum::<f64>()
            / (2.0 * (means.len() - 1) as f64);
        if avar > 0.0 && avar.is_finite() {
            out.push((c as f64 * wt, avar));
        }
        c *= 2;
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
    let half = &m[j / 2..];
    let reference = half.iter().sum::<f64>() / half.len() as f64;
    let points = tail_avar(half, wt);
    if points.is_empty() {
        return None;
    }
    let noise = |tau: f64| noise_at(&points, tau);
    let first = m[..DETECT_WINDOWS].iter().sum::<f64>() / DETECT_WINDOWS as f64;
    let wd = DETECT_WINDOWS as f64 * wt;
    let d0 = first - reference;
    let var = noise(wd) + noise(total / 2.0) + 2.0 * noise(0.75 * total - 0.5 * wd);
    let z0 = d0 / var.max(f64::MIN_POSITIVE).sqrt();
    if z0.is_nan() || z0.abs() <= WARMUP_Z {
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
        start: wd,
        start_offset: d0,
        sigmas: z0.abs(),
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
            "the first {:.1} s differ from the second half by {:+.3e} {unit} ({:.0} σ of the noise): a drift, fitted as {:+.3e}·exp(−t / {:.0} s) {unit}; the Allan analysis takes it for random walk or ramp. Rerun with --skip-start {skip:.0} ({:.1} time constants; {:.1e} {unit} left, {:.0} % of the noise's Allan deviation at τ = {:.0} s){short}",
            f.start,
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
