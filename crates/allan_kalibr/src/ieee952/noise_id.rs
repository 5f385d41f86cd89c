//! Power-law noise identification at one cluster size: which α (S_y ∝ f^α) dominates.
//!
//! Primary method (W. J. Riley and C. A. Greenhall, "Power law noise identification using the
//! lag 1 autocorrelation", EFTF 2004): take the phase series decimated by m (x\[0\], x\[m\], …),
//! remove a quadratic (frequency offset and drift), then repeat: r1 = lag-1 autocorrelation,
//! δ = r1/(1 + r1); stop when δ < 0.25 or after d = 2 differences; p = −round(2δ) − 2d and
//! α = p + 2 (phase data), clamped to the Allan range −2..=2. The paper requires at least 30
//! decimated points (N/m ≥ 30, N phase points); with this rule our α equals Stable32's at all 13 such τ of the GPS file.
//!
//! Fallback with fewer than 30 points: the Barnes B1 bias function, B1 = (standard variance of
//! the ⌊n/m⌋ cluster means) / (normal Allan variance of the same clusters), compared with its
//! theoretical value for μ = 1, 0, −1, −2 (α = −μ − 1), boundaries at the geometric means of
//! neighbouring theoretical values. μ = −2 covers both α = 1 and α = 2 (telling them apart
//! needs the modified Allan variance ratio R(n), not computed here): we report α = 1.
//! With fewer than [`MIN_B1_CLUSTERS`] clusters nothing is identified.

use super::oadev::Phase;

/// Decimated points needed by the lag-1 method.
pub const MIN_LAG1_POINTS: usize = 30;
/// Clusters needed by the B1 fallback.
pub const MIN_B1_CLUSTERS: usize = 4;
/// Largest number of differences for the Allan variance (d = 2).
const D_MAX: u32 = 2;

/// How α was obtained.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IdMethod {
    /// Lag-1 autocorrelation (≥ 30 decimated points).
    Lag1,
    /// Barnes B1 ratio (fewer points).
    B1,
    /// Not identified (too few clusters).
    None,
}

/// Result of noise identification at one m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseId {
    /// Identified α (2 white PM, 1 flicker PM, 0 white FM, −1 flicker FM, −2 random-walk FM).
    pub alpha: Option<i32>,
    /// Method used.
    pub method: IdMethod,
}

/// Decimated points the lag-1 method looks at, at most: the middle stretch of that length
/// (α is a property of the noise, not of the record length; 2¹⁴ points give r1 to ±0.008,
/// far inside the decision steps of 0.25 in δ). Keeps the identification O(2¹⁴) per τ
/// instead of O(n/m).
pub const MAX_ID_POINTS: usize = 1 << 14;

/// Identifies the dominant power-law noise at cluster size m.
pub fn identify(phase: &Phase, m: usize) -> NoiseId {
    identify_on(phase.x(), m)
}

/// [`identify`] on any phase-like series (n + 1 points; an offset or a linear trend in it
/// does not matter, a quadratic is removed first): e.g. imu_utils' θ.
pub fn identify_on(x: &[f64], m: usize) -> NoiseId {
    let n = x.len().saturating_sub(1);
    if m == 0 || m > n {
        return NoiseId {
            alpha: None,
            method: IdMethod::None,
        };
    }
    let total = n / m + 1;
    if total > MAX_ID_POINTS {
        let skip = (total - MAX_ID_POINTS) / 2;
        let dec: Vec<f64> = x
            .iter()
            .skip(skip * m)
            .step_by(m)
            .take(MAX_ID_POINTS)
            .copied()
            .collect();
        return NoiseId {
            alpha: Some(lag1_alpha(dec)),
            method: IdMethod::Lag1,
        };
    }
    let dec: Vec<f64> = x.iter().step_by(m).copied().collect();
    // N/m ≥ 30 with N = n + 1 phase points (Stable32 switches to B1 at GPS m = 8192, N/m = 29.4)
    if (n + 1) / m >= MIN_LAG1_POINTS {
        return NoiseId {
            alpha: Some(lag1_alpha(dec)),
            method: IdMethod::Lag1,
        };
    }
    let clusters = n / m;
    if clusters >= MIN_B1_CLUSTERS {
        return NoiseId {
            alpha: Some(b1_alpha(&dec[..=clusters])),
            method: IdMethod::B1,
        };
    }
    NoiseId {
        alpha: None,
        method: IdMethod::None,
    }
}

fn lag1_alpha(mut z: Vec<f64>) -> i32 {
    detrend_quadratic(&mut z);
    let mut d = 0u32;
    loop {
        let r1 = lag1_acf(&z);
        let delta = r1 / (1.0 + r1);
        if delta < 0.25 || d >= D_MAX {
            let p = -(2.0 * delta).round() as i32 - 2 * d as i32;
            return (p + 2).clamp(-2, 2);
        }
        z = z.windows(2).map(|w| w[1] - w[0]).collect();
        d += 1;
    }
}

/// Lag-1 autocorrelation of z around its mean.
fn lag1_acf(z: &[f64]) -> f64 {
    let mean = z.iter().sum::<f64>() / z.len() as f64;
    let (mut num, mut den) = (0.0, 0.0);
    for (i, &v) in z.iter().enumerate() {
        let c = v - mean;
        den += c * c;
        if i + 1 < z.len() {
            num += c * (z[i + 1] - mean);
        }
    }
    if den > 0.0 { num / den } else { 0.0 }
}

/// Removes the least-squares quadratic in the sample index.
fn detrend_quadratic(z: &mut [f64]) {
    let n = z.len();
    if n < 3 {
        return;
    }
    let c = (n - 1) as f64 / 2.0;
    let sc = n as f64;
    let t = |k: usize| (k as f64 - c) / sc;
    // normal equations in the basis 1, t, t²
    let mut a = [[0.0f64; 3]; 3];
    let mut b = [0.0f64; 3];
    for (k, &v) in z.iter().enumerate() {
        let tk = t(k);
        let basis = [1.0, tk, tk * tk];
        for i in 0..3 {
            b[i] += basis[i] * v;
            for j in 0..3 {
                a[i][j] += basis[i] * basis[j];
            }
        }
    }
    let coef = super::fit::solve_spd(&a.iter().map(|r| r.to_vec()).collect::<Vec<_>>(), &b);
    if let Some(coef) = coef {
        for (k, v) in z.iter_mut().enumerate() {
            let tk = t(k);
            *v -= coef[0] + coef[1] * tk + coef[2] * tk * tk;
        }
    }
}

/// B1 fallback on the decimated phase x\[0\], x\[m\], …, x\[Mm\] (M clusters).
fn b1_alpha(dec: &[f64]) -> i32 {
    let means: Vec<f64> = dec.windows(2).map(|w| w[1] - w[0]).collect(); // ∝ cluster means of y
    let mm = means.len();
    let mu_mean = means.iter().sum::<f64>() / mm as f64;
    let std_var = means.iter().map(|v| (v - mu_mean).powi(2)).sum::<f64>() / (mm - 1) as f64;
    let avar =
        means.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum::<f64>() / (2.0 * (mm - 1) as f64);
    if avar <= 0.0 {
        return 0;
    }
    let b1 = std_var / avar;
    // theoretical B1(M, μ) for μ = 1, 0, −1, −2 (descending B1)
    let nn = mm as f64;
    let theo = |mu: i32| -> f64 {
        if mu == 0 {
            nn * nn.ln() / (2.0 * (nn - 1.0) * 2f64.ln())
        } else {
            let muf = mu as f64;
            nn * (1.0 - nn.powf(muf)) / (2.0 * (nn - 1.0) * (1.0 - 2f64.powf(muf)))
        }
    };
    let mus = [1, 0, -1, -2];
    for w in mus.windows(2) {
        let boundary = (theo(w[0]) * theo(w[1])).sqrt();
        if b1 > boundary {
            return -w[0] - 1;
        }
    }
    1 // μ = −2: white or flicker PM; see module docs
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand::rngs::StdRng;
    use rand_distr::{Distribution, StandardNormal};

    const RNG_SEED: u64 = 0x1D_5EED;

    fn white(n: usize, rng: &mut StdRng) -> Vec<f64> {
        (0..n).map(|_| StandardNormal.sample(rng)).collect()
    }

    #[test]
    fn identifies_white_fm_white_pm_and_rw_fm() {
        let mut rng = StdRng::seed_from_u64(RNG_SEED);
        let n = 200_000;
        // white FM: y white
        let y = white(n, &mut rng);
        let ph = Phase::from_rate(&y, 1.0);
        for m in [1, 8, 64, 512] {
            assert_eq!(identify(&ph, m).alpha, Some(0), "white FM m={m}");
        }
        // white PM: x white ⇒ y = diff(x)
        let x = white(n + 1, &mut rng);
        let y: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
        let ph = Phase::from_rate(&y, 1.0);
        for m in [1, 8, 64] {
            assert_eq!(identify(&ph, m).alpha, Some(2), "white PM m={m}");
        }
        // random-walk FM: y = cumsum(white)
        let w = white(n, &mut rng);
        let y: Vec<f64> = w
            .iter()
            .scan(0.0, |s, v| {
                *s += v;
                Some(*s)
            })
            .collect();
        let ph = Phase::from_rate(&y, 1.0);
        for m in [1, 8, 64] {
            assert_eq!(identify(&ph, m).alpha, Some(-2), "RW FM m={m}");
        }
    }

    #[test]
    fn b1_fallback_on_few_clusters() {
        let mut rng = StdRng::seed_from_u64(RNG_SEED + 1);
        // 20 clusters of white FM and of RW FM, many trials: the majority vote must be right
        let (mut white_ok, mut rw_ok) = (0, 0);
        let trials = 40;
        for _ in 0..trials {
            let y = white(2000, &mut rng);
            let ph = Phase::from_rate(&y, 1.0);
            let id = identify(&ph, 100);
            assert_eq!(id.method, IdMethod::B1);
            white_ok += (id.alpha == Some(0)) as i32;
            let w = white(2000, &mut rng);
            let y: Vec<f64> = w
                .iter()
                .scan(0.0, |s, v| {
                    *s += v;
                    Some(*s)
                })
                .collect();
            let ph = Phase::from_rate(&y, 1.0);
            rw_ok += (identify(&ph, 100).alpha == Some(-2)) as i32;
        }
        assert!(white_ok > trials / 2, "white FM by B1: {white_ok}/{trials}");
        assert!(rw_ok > trials / 2, "RW FM by B1: {rw_ok}/{trials}");
        let y = white(30, &mut rng);
        assert_eq!(
            identify(&Phase::from_rate(&y, 1.0), 10).method,
            IdMethod::None
        );
    }
}
