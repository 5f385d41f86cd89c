//! What the Allan analysis assumes and a record may break: a stationary signal sampled at one
//! rate without gaps.
//!
//! * **Warm-up or drift at the start** ([`warmup`]): the mean of each window of the first
//!   part of the record is compared with the mean of the second half. Under the fitted noise
//!   model the difference has variance ≈ σ²(w) + σ²(T/2) + 2σ²(Δ) (σ² the model's Allan
//!   variance, w the window, Δ the distance to the reference: the two means' own noise and
//!   how far the bias may wander in between). A warm-up raises the whole record's long-τ
//!   Allan variance too, and the fit takes it for random walk; so at long τ σ² is the
//!   smaller of the model's and the second half's own (measured on its window means,
//!   extrapolated as a random walk). A first window beyond [`WARMUP_Z`] of that is
//!   reported, with its size and how long the excess lasts; `--skip-start` drops it.
//!
//! Gaps and rate changes are found by `bag2mat::timing`, the workspace's one place for them
//! (the section reports what it found; the analysers cut a broken record before).

/// A window whose mean is this many standard deviations from the rest is not noise.
pub const WARMUP_Z: f64 = 5.0;
/// The excess lasts while windows stay beyond this many standard deviations.
pub const WARMUP_END_Z: f64 = 3.0;
/// A warm-up or drift at the start of one axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Warmup {
    /// Mean of the first window minus the mean of the second half (signal unit).
    pub size: f64,
    /// How many standard deviations of the noise that is.
    pub sigmas: f64,
    /// How long the excess lasts, s (windows beyond [`WARMUP_END_Z`]).
    pub duration: f64,
}

/// What the warm-up check needs of a record: the means of the windows of its first third
/// and the mean of its second half (small, so it can be taken while the samples are at hand
/// and judged once the noise model is fitted).
#[derive(Clone, Debug, PartialEq)]
pub struct StartStats {
    /// Samples per window.
    pub window: usize,
    /// Sample period, s.
    pub tau0: f64,
    /// Samples in the record.
    pub n: usize,
    /// Mean of each window of the first third.
    pub means: Vec<f64>,
    /// Mean of the second half.
    pub reference: f64,
    /// Means of the windows of the second half (its own noise, see [`warmup`]).
    pub tail: Vec<f64>,
}

impl StartStats {
    /// From the running sum `cum(k)` = Σ_{i<k} y_i of a record of `n` samples (the windows are
    /// T/200, at least 10 samples). `None` for records too short to tell.
    pub fn from_cumsum(n: usize, tau0: f64, cum: impl Fn(usize) -> f64) -> Option<StartStats> {
        let window = ((n / 200).max(10)).min(n / 6);
        if window == 0 || n < 60 {
            return None;
        }
        let mean = |a: usize, b: usize| (cum(b) - cum(a)) / (b - a) as f64;
        let windows = (n / 3) / window;
        Some(StartStats {
            window,
            tau0,
            n,
            means: (0..windows)
                .map(|j| mean(j * window, (j + 1) * window))
                .collect(),
            reference: mean(n / 2, n),
            tail: (0..(n - n / 2) / window)
                .map(|j| mean(n / 2 + j * window, n / 2 + (j + 1) * window))
                .collect(),
        })
    }

    /// From the samples (window sums taken directly, no copy of the record).
    pub fn from_samples(y: &[f64], tau0: f64) -> Option<StartStats> {
        let n = y.len();
        let window = ((n / 200).max(10)).min(n / 6);
        if window == 0 || n < 60 {
            return None;
        }
        let mean = |a: usize, b: usize| y[a..b].iter().sum::<f64>() / (b - a) as f64;
        Some(StartStats {
            window,
            tau0,
            n,
            means: (0..(n / 3) / window)
                .map(|j| mean(j * window, (j + 1) * window))
                .collect(),
            reference: mean(n / 2, n),
            tail: (0..(n - n / 2) / window)
                .map(|j| mean(n / 2 + j * window, n / 2 + (j + 1) * window))
                .collect(),
        })
    }
}

/// Judges the start of a record against the Allan variance `model(τ)` of its fitted noise.
/// `None`: nothing beyond the noise.
pub fn warmup(st: &StartStats, model: &dyn Fn(f64) -> f64) -> Option<Warmup> {
    let total = st.n as f64 * st.tau0;
    let wt = st.window as f64 * st.tau0;
    let ref_center = 0.75 * total;
    let tail = tail_avar(st);
    // the fitted model, or the second half's own noise where that is smaller (a warm-up
    // raises the whole record's long-τ Allan variance, and a fit absorbs it as random walk)
    let noise = |tau: f64| match tail {
        Some((tau_t, v)) if tau >= tau_t => model(tau).min(v * tau / tau_t),
        _ => model(tau),
    };
    let z_of = |j: usize| -> (f64, f64) {
        let d = st.means[j] - st.reference;
        let center = (j as f64 + 0.5) * wt;
        let var = noise(wt) + noise(total / 2.0) + 2.0 * noise(ref_center - center);
        (d, d / var.max(f64::MIN_POSITIVE).sqrt())
    };
    let (d0, z0) = z_of(0);
    if z0.is_nan() || z0.abs() <= WARMUP_Z {
        return None;
    }
    let mut last = 0;
    for j in 1..st.means.len() {
        let (d, z) = z_of(j);
        if z.abs() > WARMUP_END_Z && d.signum() == d0.signum() {
            last = j;
        } else {
            break;
        }
    }
    Some(Warmup {
        size: d0,
        sigmas: z0.abs(),
        duration: (last + 1) as f64 * wt,
    })
}

/// Clusters the second half's own Allan variance is taken over at least (non-overlapping,
/// of window means): its EDF is then ≈ 9 for random walk, so it is rarely half the truth.
const TAIL_CLUSTERS: usize = 10;

/// The second half's non-overlapping Allan variance at its longest τ with
/// [`TAIL_CLUSTERS`] clusters: (τ, AVAR). [`warmup`] extrapolates it linearly in τ (a
/// random walk, the steepest ordinary growth: conservative for white and flicker noise).
fn tail_avar(st: &StartStats) -> Option<(f64, f64)> {
    let k = st.tail.len() / TAIL_CLUSTERS;
    if k == 0 {
        return None;
    }
    let means: Vec<f64> = st
        .tail
        .chunks_exact(k)
        .map(|c| c.iter().sum::<f64>() / k as f64)
        .collect();
    let avar = means.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum::<f64>()
        / (2.0 * (means.len() - 1) as f64);
    Some((k as f64 * st.window as f64 * st.tau0, avar))
}

/// Index of the first sample at or after `t[0] + seconds` (the `--skip-start` cut).
pub fn skip_index(t: &[f64], seconds: f64) -> usize {
    let Some(&t0) = t.first() else { return 0 };
    t.partition_point(|&x| x < t0 + seconds)
}

/// The fewest samples a `--skip-start` may leave: below this no Allan deviation reaches past
/// a few sample periods, and nothing can be fitted.
pub const SKIP_MIN_SAMPLES_LEFT: usize = 1000;
/// The smallest part of the record a `--skip-start` may leave (a skip that takes more is a
/// mistaken number, not a warm-up).
pub const SKIP_MIN_FRACTION_LEFT: f64 = 0.1;

/// The `--skip-start` cut of `t`, checked: an error when it leaves too little of the record
/// to analyse ([`SKIP_MIN_SAMPLES_LEFT`], [`SKIP_MIN_FRACTION_LEFT`]); else the index and,
/// when it drops more than half of the record, a warning to print.
pub fn checked_skip(t: &[f64], seconds: f64) -> Result<(usize, Option<String>), String> {
    if !(seconds >= 0.0 && seconds.is_finite()) {
        return Err(format!(
            "--skip-start must be a non-negative number of seconds, got {seconds}"
        ));
    }
    let k = skip_index(t, seconds);
    let left = t.len() - k;
    let span = t.last().zip(t.first()).map_or(0.0, |(b, a)| b - a);
    if left < SKIP_MIN_SAMPLES_LEFT || (left as f64) < SKIP_MIN_FRACTION_LEFT * t.len() as f64 {
        return Err(format!(
            "--skip-start {seconds} leaves {left} of {} samples ({:.1} s of a {:.1} s record): too little for an Allan analysis (at least {SKIP_MIN_SAMPLES_LEFT} samples and {:.0} % of the record)",
            t.len(),
            (span - seconds).max(0.0),
            span,
            100.0 * SKIP_MIN_FRACTION_LEFT
        ));
    }
    let warning = (2 * k > t.len()).then(|| {
        format!(
            "--skip-start {seconds} drops {k} of {} samples, more than half of the record",
            t.len()
        )
    });
    Ok((k, warning))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand::rngs::StdRng;
    use rand_distr::{Distribution, StandardNormal};

    const RNG_SEED: u64 = 0x0057_A710;

    #[test]
    fn skip_index_counts_the_samples_before_the_cut() {
        let t: Vec<f64> = (0..100_000).map(|i| i as f64 * 0.005).collect();
        assert_eq!(skip_index(&t, 50.0), 10_000);
        assert_eq!(skip_index(&t, 0.0), 0);
        assert_eq!(skip_index(&t, 1e9), t.len());
    }

    #[test]
    fn warmup_beyond_the_noise_only() {
        let mut rng = StdRng::seed_from_u64(RNG_SEED);
        let (n, tau0, sd) = (200_000usize, 0.01, 0.1);
        let white: Vec<f64> = (0..n)
            .map(|_| {
                let z: f64 = StandardNormal.sample(&mut rng);
                sd * z
            })
            .collect();
        // white noise N² = sd²·τ0
        let model = |tau: f64| sd * sd * tau0 / tau;
        let st = |y: &[f64]| StartStats::from_samples(y, tau0).unwrap();
        assert_eq!(
            warmup(&st(&white), &model),
            None,
            "white noise is stationary"
        );
        // an exponential warm-up of 0.05 (50 σ of a 10 s window mean) with a 60 s time constant
        let y: Vec<f64> = white
            .iter()
            .enumerate()
            .map(|(i, v)| v + 0.05 * (-(i as f64 * tau0) / 60.0).exp())
            .collect();
        let w = warmup(&st(&y), &model).expect("warm-up");
        assert!(w.size > 0.03 && w.sigmas > WARMUP_Z, "{w:?}");
        assert!(w.duration > 60.0 && w.duration < 600.0, "{w:?}");
    }

    /// White noise + random walk, per-sample σ `sd` and walk step `k`.
    fn white_and_walk(rng: &mut StdRng, n: usize, sd: f64, k: f64) -> Vec<f64> {
        let mut w = 0.0;
        (0..n)
            .map(|_| {
                let (a, b): (f64, f64) = (StandardNormal.sample(rng), StandardNormal.sample(rng));
                w += k * b;
                sd * a + w
            })
            .collect()
    }

    #[test]
    fn warmup_seen_through_a_fit_that_absorbed_it() {
        // a fit that took the warm-up for random walk (K six times the truth) must not hide
        // it; a clean record against the same inflated model stays quiet, and so do clean
        // records against their true model (no false alarm from the second half's noise)
        let (n, tau0, sd, k) = (100_000usize, 0.02, 0.1, 2e-3);
        let model_of = |kk: f64| move |tau: f64| sd * sd * tau0 / tau + kk * kk / tau0 * tau / 3.0;
        let mut rng = StdRng::seed_from_u64(RNG_SEED + 1);
        for rep in 0..20 {
            let y = white_and_walk(&mut rng, n, sd, k);
            let st = StartStats::from_samples(&y, tau0).unwrap();
            assert_eq!(warmup(&st, &model_of(k)), None, "clean record {rep}");
            if rep == 0 {
                let warm: Vec<f64> = y
                    .iter()
                    .enumerate()
                    .map(|(i, v)| v + 2.0 * (-(i as f64 * tau0) / 100.0).exp())
                    .collect();
                let st = StartStats::from_samples(&warm, tau0).unwrap();
                assert!(
                    warmup(&st, &model_of(6.0 * k)).is_some(),
                    "warm-up hidden by the inflated fit"
                );
            }
        }
    }
}
