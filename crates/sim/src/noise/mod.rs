//! IMU noise parameters and the continuous ↔ discrete conversions — the one place in the
//! workspace that owns them (analysers and comparisons call these functions).
//!
//! # Units and conventions
//! Continuous-time parameters (Kalibr, OpenVINS, ORB-SLAM3, vio_data_simulation `param.h`):
//!
//! | parameter | symbol | unit |
//! | --- | --- | --- |
//! | gyro white-noise density | σ_g | rad/s/√Hz (= rad/√s) |
//! | gyro bias random walk | σ_bg | rad/s²/√Hz (= rad/s/√s) |
//! | acc white-noise density | σ_a | m/s²/√Hz (= m/s/√s) |
//! | acc bias random walk | σ_ba | m/s³/√Hz (= m/s²/√s) |
//!
//! At a sample period Δt = 1/f (seconds) the per-sample (discrete) standard deviations are
//! ```text
//! white noise:      σ_d  = σ / √Δt  = σ·√f     (std of the noise on one sample: rad/s, m/s²)
//! bias random walk: σ_bd = σ_b · √Δt = σ_b/√f  (std of one bias increment: rad/s, m/s²)
//! ```
//! (docs/noise_terms.md §3). [`NoiseGenerator`] applies them exactly as vio_data_simulation's
//! `addIMUnoise` does (docs/upstream/vio_data_simulation.md §3): measurement += σ_d·n + b (the bias *before*
//! its update), then b += σ_bd·n'; twelve standard normals per sample in the order
//! gyro white (x, y, z), acc white, gyro bias step, acc bias step; initial biases zero.
//! Unlike upstream (a fresh `std::random_device` per call, not reproducible) one persistent
//! generator seeded from `--seed` is used, so equal seeds give equal data.
//!
//! # Real sensors (issue 9)
//! The ideal model above is what the presets use, byte for byte. Real sensors have more:
//! * [`model`]: every IEEE 952 term per axis (N, K, B, Gauss–Markov, R, Q, LSB, warm-up) in
//!   continuous time, and the sensor's chain (internal rate, low-pass, decimation);
//! * [`spec`]: the `--noise-spec` YAML file; [`profiles`]: datasheet sensors;
//! * [`filter`]: the digital low-pass and the per-sample σ it leaves (σ_d² = N²·f_i·Σh²);
//! * [`flicker`]: 1/f bias noise as log-spaced Gauss–Markov processes;
//! * [`generate`]: the per-sample chain, per-axis streams, parallel blocks;
//! * [`truth`]: the exact Allan variance of the generated sequence, term by term;
//!   [`psd`]: the spectral integrals and closed forms it is checked against;
//!   [`truth_file`]: `<bag>.truth.yaml` and `<bag>.truth.csv`.

pub(crate) mod filter;
pub(crate) mod flicker;
pub(crate) mod generate;
pub(crate) mod model;
pub(crate) mod profiles;
#[cfg(test)]
pub(crate) mod psd;
#[cfg(test)]
pub(crate) mod quad;
pub(crate) mod spec;
pub(crate) mod truth;
pub(crate) mod truth_file;

#[cfg(test)]
mod tests_stat;

use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, StandardNormal};

/// Seed used when the user gives none (any fixed value; documented in the CLI help).
pub const DEFAULT_SEED: u64 = 1;

/// Per-sample white-noise std from a continuous density: σ_d = σ/√Δt.
/// `sigma` in unit/√Hz, `dt` in s; result in unit.
pub fn white_to_discrete(sigma: f64, dt: f64) -> f64 {
    sigma / dt.sqrt()
}

/// Continuous white-noise density from a per-sample std: σ = σ_d·√Δt (inverse of
/// [`white_to_discrete`]).
pub fn white_to_continuous(sigma_d: f64, dt: f64) -> f64 {
    sigma_d * dt.sqrt()
}

/// Per-sample bias increment std from a continuous random-walk strength: σ_bd = σ_b·√Δt.
/// `sigma_b` in unit/s/√Hz, `dt` in s; result in unit.
pub fn random_walk_to_discrete(sigma_b: f64, dt: f64) -> f64 {
    sigma_b * dt.sqrt()
}

/// Continuous random-walk strength from a per-sample bias increment std: σ_b = σ_bd/√Δt
/// (inverse of [`random_walk_to_discrete`]).
pub fn random_walk_to_continuous(sigma_bd: f64, dt: f64) -> f64 {
    sigma_bd / dt.sqrt()
}

/// IEEE 952 quantization Q (U·s) → the step of the integrated angle/velocity, q = √12·Q:
/// the rounding error of a uniform quantiser has variance q²/12 = Q², which gives the Allan
/// variance 3Q²/τ².
pub fn quantization_step(q: f64) -> f64 {
    q * 12f64.sqrt()
}

/// Allan deviation of white noise of density `sigma` (unit/√Hz) at averaging time `tau` (s):
/// σ_A(τ) = σ/√τ — the −½ slope line, which reads σ at τ = 1 s (IEEE 952 Annex C).
/// One axis of white noise `n` and random walk `k` (continuous), `len` samples `dt` apart,
/// from [`NoiseGenerator`] seeded with `seed`: its gyro x channel (the other channels' draws
/// are discarded). The tests' white-plus-random-walk series, made in one place.
pub fn white_rw_axis(n: f64, k: f64, dt: f64, len: usize, seed: u64) -> Vec<f64> {
    let c = ContinuousNoise {
        gyro_noise: n,
        gyro_bias_rw: k,
        acc_noise: 0.0,
        acc_bias_rw: 0.0,
    };
    let mut g = NoiseGenerator::new(c.discretize(dt), seed);
    (0..len)
        .map(|_| {
            let (mut gyro, mut acc) = ([0.0; 3], [0.0; 3]);
            g.apply(&mut gyro, &mut acc);
            gyro[0]
        })
        .collect()
}

#[cfg(test)]
pub fn adev_white(sigma: f64, tau: f64) -> f64 {
    sigma / tau.sqrt()
}

/// Allan deviation of a random walk of strength `sigma_b` (unit/s/√Hz) at `tau` (s):
/// σ_A(τ) = σ_b·√(τ/3) — the +½ slope line, which reads σ_b at τ = 3 s.
#[cfg(test)]
pub fn adev_random_walk(sigma_b: f64, tau: f64) -> f64 {
    sigma_b * (tau / 3.0).sqrt()
}

/// Continuous-time noise parameters of a 6-axis IMU (units in the module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContinuousNoise {
    /// σ_g, rad/s/√Hz.
    pub gyro_noise: f64,
    /// σ_bg, rad/s²/√Hz.
    pub gyro_bias_rw: f64,
    /// σ_a, m/s²/√Hz.
    pub acc_noise: f64,
    /// σ_ba, m/s³/√Hz.
    pub acc_bias_rw: f64,
}

/// Per-sample standard deviations at a given sample period (units in the module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiscreteNoise {
    /// Sample period Δt, s.
    pub dt: f64,
    /// Gyro white noise per sample, rad/s.
    pub gyro_noise: f64,
    /// Gyro bias increment per sample, rad/s.
    pub gyro_bias_step: f64,
    /// Acc white noise per sample, m/s².
    pub acc_noise: f64,
    /// Acc bias increment per sample, m/s².
    pub acc_bias_step: f64,
}

impl ContinuousNoise {
    /// No noise at all.
    pub const ZERO: Self = Self {
        gyro_noise: 0.0,
        gyro_bias_rw: 0.0,
        acc_noise: 0.0,
        acc_bias_rw: 0.0,
    };

    /// Discretise at sample period `dt` (s).
    pub fn discretize(&self, dt: f64) -> DiscreteNoise {
        DiscreteNoise {
            dt,
            gyro_noise: white_to_discrete(self.gyro_noise, dt),
            gyro_bias_step: random_walk_to_discrete(self.gyro_bias_rw, dt),
            acc_noise: white_to_discrete(self.acc_noise, dt),
            acc_bias_step: random_walk_to_discrete(self.acc_bias_rw, dt),
        }
    }

    /// Human-readable table of the parameters in both forms at rate `rate_hz`, printed by the
    /// binaries at start (the conversion users most often get wrong).
    pub fn describe(&self, rate_hz: f64) -> String {
        let d = self.discretize(1.0 / rate_hz);
        format!(
            "noise parameters (continuous time -> discrete at {rate_hz} Hz, dt = {dt} s):\n\
             \x20 gyro white noise  {:>10.4e} rad/s/sqrt(Hz)  -> {:>10.4e} rad/s per sample   (sigma/sqrt(dt))\n\
             \x20 gyro bias walk    {:>10.4e} rad/s^2/sqrt(Hz)-> {:>10.4e} rad/s per step     (sigma_b*sqrt(dt))\n\
             \x20 acc  white noise  {:>10.4e} m/s^2/sqrt(Hz)  -> {:>10.4e} m/s^2 per sample   (sigma/sqrt(dt))\n\
             \x20 acc  bias walk    {:>10.4e} m/s^3/sqrt(Hz)  -> {:>10.4e} m/s^2 per step     (sigma_b*sqrt(dt))",
            self.gyro_noise,
            d.gyro_noise,
            self.gyro_bias_rw,
            d.gyro_bias_step,
            self.acc_noise,
            d.acc_noise,
            self.acc_bias_rw,
            d.acc_bias_step,
            dt = d.dt,
        )
    }
}

impl DiscreteNoise {
    /// Back to continuous-time parameters (inverse of [`ContinuousNoise::discretize`]).
    pub fn to_continuous(self) -> ContinuousNoise {
        ContinuousNoise {
            gyro_noise: white_to_continuous(self.gyro_noise, self.dt),
            gyro_bias_rw: random_walk_to_continuous(self.gyro_bias_step, self.dt),
            acc_noise: white_to_continuous(self.acc_noise, self.dt),
            acc_bias_rw: random_walk_to_continuous(self.acc_bias_step, self.dt),
        }
    }
}

/// The seed's preset table (issue 2), continuous time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Preset {
    /// gyro 0.01, 1e-5; acc 0.01, 1e-4.
    Low,
    /// gyro 0.015, 5e-5; acc 0.019, 5e-4 — vio_data_simulation `ros_version` `param.h`.
    Medium,
    /// gyro 0.03, 1e-4; acc 0.03, 1e-3.
    High,
}

impl Preset {
    /// The preset's name, as `sim compare` names its folders.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Low => "low",
            Preset::Medium => "medium",
            Preset::High => "high",
        }
    }

    /// The preset's continuous-time parameters.
    pub fn params(self) -> ContinuousNoise {
        match self {
            Preset::Low => ContinuousNoise {
                gyro_noise: 0.01,
                gyro_bias_rw: 1e-5,
                acc_noise: 0.01,
                acc_bias_rw: 1e-4,
            },
            Preset::Medium => ContinuousNoise {
                gyro_noise: 0.015,
                gyro_bias_rw: 5e-5,
                acc_noise: 0.019,
                acc_bias_rw: 5e-4,
            },
            Preset::High => ContinuousNoise {
                gyro_noise: 0.03,
                gyro_bias_rw: 1e-4,
                acc_noise: 0.03,
                acc_bias_rw: 1e-3,
            },
        }
    }
}

/// vio_data_simulation `master` `param.h` (20 s trajectory run): gyro 0.015, 1e-5; acc 0.019,
/// 1e-4 (docs/upstream/vio_data_simulation.md §1). Used by `sim traj`/`sim spline` when no preset is given.
pub const MASTER_PARAMS: ContinuousNoise = ContinuousNoise {
    gyro_noise: 0.015,
    gyro_bias_rw: 1e-5,
    acc_noise: 0.019,
    acc_bias_rw: 1e-4,
};

/// One standard normal draw (ziggurat, rand_distr).
#[inline(always)]
fn normal(rng: &mut StdRng) -> f64 {
    StandardNormal.sample(rng)
}

/// Seeded noise source applying the `addIMUnoise` model (module doc) sample by sample.
pub struct NoiseGenerator {
    rng: StdRng,
    d: DiscreteNoise,
    gyro_bias: [f64; 3],
    acc_bias: [f64; 3],
}

impl NoiseGenerator {
    /// A generator for the given per-sample stds, seeded with `seed`, biases zero.
    pub fn new(d: DiscreteNoise, seed: u64) -> Self {
        Self {
            rng: StdRng::seed_from_u64(seed),
            d,
            gyro_bias: [0.0; 3],
            acc_bias: [0.0; 3],
        }
    }

    /// Current biases (gyro, acc) — after the last update, like upstream's stored
    /// `imu_gyro_bias`.
    pub fn biases(&self) -> ([f64; 3], [f64; 3]) {
        (self.gyro_bias, self.acc_bias)
    }

    #[inline(always)]
    fn n(&mut self) -> f64 {
        normal(&mut self.rng)
    }

    /// Add noise to one sample in place. Mirrors vio_data_simulation `addIMUnoise`
    /// (`imu.cpp`, both branches; docs/upstream/vio_data_simulation.md §3): white noise plus the bias *before* its update, then
    /// the bias random-walk step; draw order n1 (gyro xyz), n2 (acc), n3 (gyro bias), n4.
    #[inline]
    pub fn apply(&mut self, gyro: &mut [f64; 3], acc: &mut [f64; 3]) {
        let d = self.d;
        // Draw order n1 (gyro white), n2 (acc white), n3, n4 — keep it: it defines the data.
        for (g, b) in gyro.iter_mut().zip(self.gyro_bias) {
            *g += d.gyro_noise * self.n() + b;
        }
        for (a, b) in acc.iter_mut().zip(self.acc_bias) {
            *a += d.acc_noise * self.n() + b;
        }
        let rng = &mut self.rng;
        for b in self.gyro_bias.iter_mut() {
            *b += d.gyro_bias_step * normal(rng);
        }
        for b in self.acc_bias.iter_mut() {
            *b += d.acc_bias_step * normal(rng);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Round trips are a multiply and a divide by the same √Δt: a few ulps.
    const ROUND_TRIP_REL_TOL: f64 = 1e-15;
    /// Statistical checks on N samples: the std estimate has relative std ≈ 1/√(2N).
    const STAT_REL_TOL: f64 = 0.01;
    const SEED: u64 = 42;
    /// The spec prints these stds with 3–4 significant digits (3.54e-6 for 3.5355e-6).
    const SPEC_3_DIGITS_REL_TOL: f64 = 2e-3;

    fn rel(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    #[test]
    #[allow(clippy::excessive_precision)] // the seed's number exactly as printed
    fn worked_number_from_the_seed() {
        // The seed's worked example: a per-sample std 0.20988682986301069 at 200 Hz is the
        // continuous density 0.01484124... rad/s/√Hz.
        let c = white_to_continuous(0.20988682986301069, 0.005);
        let expected = 0.014841240067788202;
        assert!(
            rel(c, expected) < ROUND_TRIP_REL_TOL,
            "expected {expected}, actual {c}"
        );
        assert!((c - 0.01484124).abs() < 1e-8, "leading digits: actual {c}");
    }

    #[test]
    fn field_md_examples() {
        // docs/noise_terms.md §3: σ = 0.03 at 200 Hz → 0.4243; σ_b = 1e-4 at 200 Hz → 7.07e-6;
        // at 100 Hz → 0.3 and 1e-5.
        let cases = [
            (0.03, 0.005, 0.42426406871192857, true),
            (1e-4, 0.005, 7.0710678118654756e-6, false),
            (0.03, 0.01, 0.3, true),
            (1e-4, 0.01, 1e-5, false),
        ];
        for (i, (s, dt, exp, white)) in cases.into_iter().enumerate() {
            let got = if white {
                white_to_discrete(s, dt)
            } else {
                random_walk_to_discrete(s, dt)
            };
            assert!(
                rel(got, exp) < 1e-12,
                "case {i}: expected {exp}, actual {got}, tol 1e-12"
            );
        }
    }

    #[test]
    fn spec_per_sample_stds_master_and_ros_version() {
        // docs/upstream/vio_data_simulation.md §3: master gyro 0.2121, acc 0.2687, bias steps 7.07e-7 and
        // 7.07e-6; ros_version bias steps 3.54e-6 and 3.54e-5 (4 significant digits).
        let m = MASTER_PARAMS.discretize(0.005);
        let r = Preset::Medium.params().discretize(0.005);
        let cases = [
            (m.gyro_noise, 0.2121),
            (m.acc_noise, 0.2687),
            (m.gyro_bias_step, 7.07e-7),
            (m.acc_bias_step, 7.07e-6),
            (r.gyro_bias_step, 3.54e-6),
            (r.acc_bias_step, 3.54e-5),
        ];
        for (i, (got, exp)) in cases.into_iter().enumerate() {
            assert!(
                rel(got, exp) < SPEC_3_DIGITS_REL_TOL,
                "case {i}: expected {exp}, actual {got}, tol {SPEC_3_DIGITS_REL_TOL} rel"
            );
        }
    }

    #[test]
    fn allan_lines_read_off_at_1_and_3_seconds() {
        // docs/noise_terms.md §2: the white line read at τ = 1 s gives σ, the random-walk line at τ = 3 s
        // gives σ_b; docs/upstream/vio_data_simulation.md §3's check for the static bag: ADEV(1 s) ≈ 0.015 rad/s.
        assert_eq!(adev_white(0.015, 1.0), 0.015);
        assert!(rel(adev_random_walk(5e-5, 3.0), 5e-5) < ROUND_TRIP_REL_TOL);
        assert!(rel(adev_white(0.02, 100.0), 0.002) < ROUND_TRIP_REL_TOL);
        assert!(rel(adev_random_walk(1e-4, 300.0), 1e-3) < ROUND_TRIP_REL_TOL);
    }

    /// Naive non-overlapping Allan deviation of rate samples `x` at cluster size `m`.
    fn adev_naive(x: &[f64], m: usize) -> f64 {
        let means: Vec<f64> = x
            .chunks_exact(m)
            .map(|c| c.iter().sum::<f64>() / m as f64)
            .collect();
        let s: f64 = means.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum();
        (s / (2.0 * (means.len() - 1) as f64)).sqrt()
    }

    /// ADEV estimate with K clusters has relative std ≈ 1/√(2(K−1)); 4 std.
    fn adev_tol(clusters: usize) -> f64 {
        4.0 / (2.0 * (clusters - 1) as f64).sqrt()
    }

    #[test]
    fn allan_deviation_of_generated_noise_matches_the_continuous_parameters() {
        // docs/upstream/vio_data_simulation.md §3 "Allan check for the port": ADEV(1 s) = σ for the white part and
        // ADEV(τ) = σ_b·√(τ/3) for the bias walk, when the generator discretises correctly.
        let rate = 200.0;
        let dt = 1.0 / rate;
        let white = ContinuousNoise {
            gyro_noise: 0.015,
            gyro_bias_rw: 0.0,
            acc_noise: 0.019,
            acc_bias_rw: 0.0,
        };
        let mut g = NoiseGenerator::new(white.discretize(dt), SEED);
        let n = 2000 * 200; // 2000 s
        let (mut gx, mut az) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for _ in 0..n {
            let (mut w, mut a) = ([0.0; 3], [0.0; 3]);
            g.apply(&mut w, &mut a);
            gx.push(w[0]);
            az.push(a[2]);
        }
        let tol = adev_tol(2000);
        for (name, x, sigma) in [("gyro", &gx, 0.015), ("acc", &az, 0.019)] {
            let got = adev_naive(x, 200);
            let exp = adev_white(sigma, 1.0);
            assert!(
                rel(got, exp) < tol,
                "{name} white ADEV(1 s): expected {exp}, actual {got}, tol {tol} rel"
            );
        }
        let walk = ContinuousNoise {
            gyro_noise: 0.0,
            gyro_bias_rw: 5e-5,
            acc_noise: 0.0,
            acc_bias_rw: 5e-4,
        };
        let mut g = NoiseGenerator::new(walk.discretize(dt), SEED + 1);
        let n = 8000 * 200; // 8000 s, τ = 20 s ⇒ 400 clusters
        let mut gy = Vec::with_capacity(n);
        for _ in 0..n {
            let (mut w, mut a) = ([0.0; 3], [0.0; 3]);
            g.apply(&mut w, &mut a);
            gy.push(w[1]);
        }
        let tol = adev_tol(400);
        let got = adev_naive(&gy, 20 * 200);
        let exp = adev_random_walk(5e-5, 20.0);
        assert!(
            rel(got, exp) < tol,
            "gyro bias walk ADEV(20 s): expected {exp}, actual {got}, tol {tol} rel"
        );
    }

    #[test]
    fn round_trips() {
        for &dt in &[1.0 / 100.0, 1.0 / 200.0, 1.0 / 400.0, 1e-3, 0.1] {
            for p in [Preset::Low, Preset::Medium, Preset::High] {
                let c = p.params();
                let back = c.discretize(dt).to_continuous();
                for (i, (a, b)) in [
                    (back.gyro_noise, c.gyro_noise),
                    (back.gyro_bias_rw, c.gyro_bias_rw),
                    (back.acc_noise, c.acc_noise),
                    (back.acc_bias_rw, c.acc_bias_rw),
                ]
                .into_iter()
                .enumerate()
                {
                    assert!(
                        rel(a, b) < ROUND_TRIP_REL_TOL,
                        "{p:?} dt {dt} field {i}: expected {b}, actual {a}"
                    );
                }
            }
            let x = 0.123;
            assert!(rel(white_to_discrete(white_to_continuous(x, dt), dt), x) < ROUND_TRIP_REL_TOL);
            assert!(
                rel(
                    random_walk_to_discrete(random_walk_to_continuous(x, dt), dt),
                    x
                ) < ROUND_TRIP_REL_TOL
            );
        }
    }

    #[test]
    fn generator_is_deterministic_and_has_the_right_stds() {
        let d = Preset::High.params().discretize(0.005);
        let mut a = NoiseGenerator::new(d, SEED);
        let mut b = NoiseGenerator::new(d, SEED);
        const N: usize = 100_000;
        let (mut s_g, mut s_a) = (0.0, 0.0);
        let mut prev_bias = a.biases();
        let (mut s_bg, mut s_ba) = (0.0, 0.0);
        for i in 0..N {
            let (mut g1, mut a1) = ([0.0; 3], [0.0, 0.0, 9.81]);
            let (mut g2, mut a2) = (g1, a1);
            a.apply(&mut g1, &mut a1);
            b.apply(&mut g2, &mut a2);
            assert_eq!(
                (g1, a1),
                (g2, a2),
                "sample {i}: same seed must give the same noise"
            );
            // Remove the (known) bias before its update to isolate the white part.
            s_g += (g1[0] - prev_bias.0[0]).powi(2);
            s_a += (a1[2] - 9.81 - prev_bias.1[2]).powi(2);
            let now = a.biases();
            s_bg += (now.0[1] - prev_bias.0[1]).powi(2);
            s_ba += (now.1[1] - prev_bias.1[1]).powi(2);
            prev_bias = now;
        }
        let n = N as f64;
        let cases = [
            ("gyro white", (s_g / n).sqrt(), d.gyro_noise),
            ("acc white", (s_a / n).sqrt(), d.acc_noise),
            ("gyro bias step", (s_bg / n).sqrt(), d.gyro_bias_step),
            ("acc bias step", (s_ba / n).sqrt(), d.acc_bias_step),
        ];
        for (name, got, exp) in cases {
            assert!(
                rel(got, exp) < STAT_REL_TOL,
                "{name}: expected {exp}, actual {got}, tol {STAT_REL_TOL} rel"
            );
        }
    }

    #[test]
    fn first_sample_carries_no_bias_and_bias_updates_after() {
        // docs/upstream/vio_data_simulation.md §3: initial biases are zero, so sample 0 is pure white noise; the bias applied
        // to sample k is the one accumulated from steps 0..k-1.
        let d = DiscreteNoise {
            dt: 0.005,
            gyro_noise: 0.0,
            gyro_bias_step: 1.0,
            acc_noise: 0.0,
            acc_bias_step: 1.0,
        };
        let mut g = NoiseGenerator::new(d, SEED);
        let (mut w, mut f) = ([0.0; 3], [0.0; 3]);
        g.apply(&mut w, &mut f);
        assert_eq!((w, f), ([0.0; 3], [0.0; 3]), "sample 0 must carry no bias");
        let (bg, ba) = g.biases();
        assert!(bg.iter().chain(ba.iter()).all(|&b| b != 0.0));
        let (mut w, mut f) = ([0.0; 3], [0.0; 3]);
        g.apply(&mut w, &mut f);
        assert_eq!(
            (w, f),
            (bg, ba),
            "sample 1 carries the bias after the first update"
        );
    }
}
