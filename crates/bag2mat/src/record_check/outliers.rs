//! Spikes: a sample (or a few in a row) far off its neighbours. An Allan curve cannot show
//! one — a single 1e6 rad/s sample in 360,000 lifts the whole curve as a white noise 33,000×
//! the truth, which the fit then "describes" — but the time domain can: the samples' own
//! short-term noise is the robust scale of the first differences (1.4826 × their median
//! absolute deviation, √2 × the per-sample σ of white noise), and a sample more than
//! [`OUTLIER_Z`] of it from the median of its neighbours, in a run of at most
//! [`MAX_SPIKE_LEN`] such samples, is a spike. A step or a motion moves the neighbours' median
//! with it and is not one.

use super::{Axis, Finding, Kind, Level, secs, stamp_text};

/// A spike is this many robust standard deviations of the samples' short-term noise off its
/// neighbours (Gaussian noise reaches 12 σ with probability 4e-33 per sample).
pub const OUTLIER_Z: f64 = 12.0;
/// At most this many samples in a row are one spike (more is a step or a motion).
pub const MAX_SPIKE_LEN: usize = 4;
/// Neighbours on each side whose median is a sample's local level.
const NEIGHBOURS: usize = 8;
/// Standard deviations per median absolute deviation of a Gaussian.
const MAD_TO_SIGMA: f64 = 1.4826;
/// The 99th percentile of |x| of a Gaussian in standard deviations (the scale when more than
/// half the differences are zero: a coarsely quantised sensor).
const P99_SIGMAS: f64 = 2.576;

/// One spike.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spike {
    /// Its first sample.
    pub start: usize,
    /// Samples in it.
    pub len: usize,
    /// Its largest departure from the local level (signed), in the signal's unit.
    pub excess: f64,
    /// That in robust standard deviations of the samples' noise.
    pub sigmas: f64,
    /// The local level (median of the neighbours).
    pub level: f64,
}

fn median(v: &mut [f64]) -> f64 {
    let k = v.len() / 2;
    *v.select_nth_unstable_by(k, f64::total_cmp).1
}

/// First differences the robust scale is taken over at most (evenly spread: the scale of
/// 2.9 M differences is that of a quarter million to a fraction of a percent).
const SCALE_DIFFERENCES: usize = 1 << 18;

/// The robust per-sample σ of `y`'s short-term noise (from its first differences), 0 when
/// it has none.
pub fn noise_scale(y: &[f64]) -> f64 {
    if y.len() < 3 {
        return 0.0;
    }
    let stride = (y.len() - 1).div_ceil(SCALE_DIFFERENCES).max(1);
    let mut d: Vec<f64> = (0..y.len() - 1)
        .step_by(stride)
        .map(|i| y[i + 1] - y[i])
        .collect();
    let m = median(&mut d);
    let mut dev: Vec<f64> = d.iter().map(|x| (x - m).abs()).collect();
    let mad = median(&mut dev);
    let s = if mad > 0.0 {
        MAD_TO_SIGMA * mad
    } else {
        let k = ((dev.len() * 99) / 100).min(dev.len() - 1);
        *dev.select_nth_unstable_by(k, f64::total_cmp).1 / P99_SIGMAS
    };
    if s.is_finite() {
        s / std::f64::consts::SQRT_2
    } else {
        0.0
    }
}

fn local_level(y: &[f64], j: usize) -> f64 {
    let lo = j.saturating_sub(NEIGHBOURS);
    let hi = (j + NEIGHBOURS + 1).min(y.len());
    let mut w: Vec<f64> = (lo..hi).filter(|&i| i != j).map(|i| y[i]).collect();
    median(&mut w)
}

/// Indices `i` with |y[i+1] − y[i]| > `limit` (or not comparable: NaN), in order: blocks
/// of [`SCAN_BLOCK`] differences are screened by their largest in 8 independent lanes (so the
/// compiler vectorises the pass), and only a block that holds one is looked at again.
fn large_differences(y: &[f64], limit: f64) -> Vec<usize> {
    const L: usize = 8;
    let mut out = Vec::new();
    let n = y.len();
    let mut start = 0;
    while start + 1 < n {
        let end = (start + SCAN_BLOCK).min(n - 1);
        let (a, b) = (&y[start..end], &y[start + 1..end + 1]);
        let mut mx = [0.0f64; L];
        let (ca, ra) = a.as_chunks::<L>();
        let (cb, rb) = b.as_chunks::<L>();
        for (x, z) in ca.iter().zip(cb) {
            for l in 0..L {
                // a NaN difference makes the lane NaN, which is not ≤ limit below
                let d = (z[l] - x[l]).abs();
                mx[l] = if d > mx[l] || d.is_nan() { d } else { mx[l] };
            }
        }
        let tail = ra.iter().zip(rb).map(|(x, z)| (z - x).abs());
        let screened = mx
            .iter()
            .copied()
            .chain(tail)
            .any(|d| d > limit || d.is_nan());
        if screened {
            out.extend((start..end).filter(|&i| {
                let d = (y[i + 1] - y[i]).abs();
                d > limit || d.is_nan()
            }));
        }
        start = end;
    }
    out
}

/// Differences per block of [`large_differences`].
const SCAN_BLOCK: usize = 4096;

/// The median of `y[a..b]` (clipped), `None` when empty.
fn median_of(y: &[f64], a: usize, b: usize) -> Option<f64> {
    let b = b.min(y.len());
    (a < b).then(|| median(&mut y[a..b].to_vec()))
}

/// The spikes of `y`, in order, and the robust σ of its short-term noise
/// ([`noise_scale`]).
pub fn find(y: &[f64]) -> (Vec<Spike>, f64) {
    let sigma = noise_scale(y);
    (spikes(y, sigma), sigma)
}

fn spikes(y: &[f64], sigma: f64) -> Vec<Spike> {
    let n = y.len();
    if sigma <= 0.0 || n < 2 * NEIGHBOURS {
        return Vec::new();
    }
    let limit = OUTLIER_Z * sigma;
    // candidates: the samples a spike of up to MAX_SPIKE_LEN could span around every large
    // first difference
    let mut candidates: Vec<usize> = Vec::new();
    for i in large_differences(y, limit) {
        let lo = (i + 1).saturating_sub(MAX_SPIKE_LEN);
        let hi = (i + MAX_SPIKE_LEN).min(n - 1);
        let from = candidates.last().map_or(lo, |&l| lo.max(l + 1));
        candidates.extend(from..=hi);
    }
    let flagged: Vec<usize> = candidates
        .into_iter()
        .filter(|&j| (y[j] - local_level(y, j)).abs() > limit)
        .collect();
    // runs of flagged samples that return to the level they left
    let mut out = Vec::new();
    let mut k = 0;
    while k < flagged.len() {
        let mut end = k + 1;
        while end < flagged.len() && flagged[end] == flagged[end - 1] + 1 {
            end += 1;
        }
        let (s, e) = (flagged[k], flagged[end - 1] + 1);
        k = end;
        if e - s > MAX_SPIKE_LEN {
            continue;
        }
        let before = median_of(y, s.saturating_sub(NEIGHBOURS), s);
        let after = median_of(y, e, e + NEIGHBOURS);
        let level = match (before, after) {
            (Some(b), Some(a)) if (b - a).abs() > limit => continue, // a step
            (Some(b), Some(a)) => 0.5 * (a + b),
            (Some(x), None) | (None, Some(x)) => x,
            (None, None) => continue,
        };
        let big = (s..e)
            .map(|j| y[j] - level)
            .max_by(|a, b| a.abs().total_cmp(&b.abs()))
            .expect("a sample");
        out.push(Spike {
            start: s,
            len: e - s,
            excess: big,
            sigmas: big.abs() / sigma,
            level,
        });
    }
    out
}

/// `y` with every spike replaced by its local level (for the checks that average: warm-up,
/// motion).
pub fn patched(y: &[f64], spikes: &[Spike]) -> Vec<f64> {
    let mut v = y.to_vec();
    for s in spikes {
        for x in &mut v[s.start..s.start + s.len] {
            *x = s.level;
        }
    }
    v
}

/// The finding of one axis' spikes (`t`: the stamps, ns); `dropped` when `--drop-outliers`
/// drops them.
pub fn findings(axis: Axis, spikes: &[Spike], t: &[i64], dropped: bool) -> Option<Finding> {
    let big = spikes
        .iter()
        .max_by(|a, b| a.excess.abs().total_cmp(&b.excess.abs()))?;
    let unit = axis.sensor.unit();
    let t0 = t[0];
    let list: Vec<String> = spikes
        .iter()
        .take(super::clock::MAX_LISTED)
        .map(|s| {
            format!(
                "sample {} at t = {:.3} s (stamp {}): {:+.3e} {unit} off its neighbours, {:.0} σ of the noise{}",
                s.start,
                secs(t[s.start] - t0),
                stamp_text(t[s.start]),
                s.excess,
                s.sigmas,
                if s.len > 1 {
                    format!(", {} samples", s.len)
                } else {
                    String::new()
                }
            )
        })
        .collect();
    let samples: usize = spikes.iter().map(|s| s.len).sum();
    let text = format!(
        "{} spike(s) ({samples} sample(s)): {}{}; {}",
        spikes.len(),
        list.join("; "),
        if spikes.len() > super::clock::MAX_LISTED {
            "; …"
        } else {
            ""
        },
        if dropped {
            "dropped from the analysis (--drop-outliers)".to_string()
        } else {
            "an Allan curve cannot show a spike, but it raises every N (a white noise spread over the whole curve) and the fit takes it for noise; rerun with --drop-outliers to drop it".to_string()
        }
    );
    Some(
        Finding::new(
            if dropped { Level::Note } else { Level::Warning },
            Kind::Outlier,
            text,
        )
        .on(axis)
        .at(secs(t[big.start] - t0), big.start)
        .sized(big.excess.abs(), unit),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand::rngs::StdRng;
    use rand_distr::{Distribution, StandardNormal};

    const RNG_SEED: u64 = 0x5_91CE;

    fn white(n: usize, sd: f64, seed: u64) -> Vec<f64> {
        let mut rng = StdRng::seed_from_u64(seed);
        (0..n)
            .map(|_| {
                let z: f64 = StandardNormal.sample(&mut rng);
                sd * z
            })
            .collect()
    }

    #[test]
    fn white_noise_has_no_spike_and_its_scale_is_its_sigma() {
        let y = white(200_000, 0.3, RNG_SEED);
        assert!(find(&y).0.is_empty());
        // the robust scale of 200,000 samples is within 1 % of σ
        const SCALE_REL_TOL: f64 = 0.01;
        assert!((noise_scale(&y) / 0.3 - 1.0).abs() < SCALE_REL_TOL);
    }

    #[test]
    fn one_spike_and_a_short_run_are_found_a_step_is_not() {
        let mut y = white(50_000, 1e-3, RNG_SEED + 1);
        y[20_000] = 1e6;
        for v in &mut y[30_000..30_003] {
            *v -= 0.5;
        }
        for v in &mut y[40_000..] {
            *v += 1.0;
        }
        let s = find(&y).0;
        assert_eq!(s.len(), 2, "{s:?}");
        assert_eq!((s[0].start, s[0].len), (20_000, 1));
        assert!((s[0].excess - 1e6).abs() < 1.0);
        assert_eq!((s[1].start, s[1].len), (30_000, 3));
        let p = patched(&y, &s);
        assert!(p[20_000].abs() < 0.01 && p[30_001].abs() < 0.01);
    }

    #[test]
    fn the_screened_scan_finds_what_the_plain_one_does() {
        let mut y = white(10_000, 1.0, RNG_SEED + 2);
        for (i, v) in [
            (0usize, 30.0),
            (4095, -40.0),
            (4096, 50.0),
            (8191, 20.0),
            (9998, 25.0),
        ] {
            y[i] = v;
        }
        let limit = 10.0;
        let plain: Vec<usize> = (0..y.len() - 1)
            .filter(|&i| (y[i + 1] - y[i]).abs() > limit)
            .collect();
        assert!(!plain.is_empty());
        assert_eq!(large_differences(&y, limit), plain);
    }

    #[test]
    fn a_coarsely_quantised_axis_is_judged_on_its_steps() {
        // most differences 0, a few ±1 LSB: no spike
        let y: Vec<f64> = (0..10_000)
            .map(|i| if i % 37 == 0 { 0.01 } else { 0.0 })
            .collect();
        assert!(find(&y).0.is_empty());
    }
}
