//! The per-sample chain of the real-sensor model (units and terms: [`super::model`]).
//!
//! Per axis and output sample n (Δt = 1/f_out, D internal samples per output sample):
//! 1. white noise at the internal rate, σ_w = N·√f_i per internal sample, through the
//!    low-pass filter; the output keeps the last of the D filtered samples (for the averaging
//!    filter, the mean of the D samples, drawn directly as one normal of σ_w/√D — the same
//!    distribution; without a filter the D − 1 discarded samples are not drawn);
//! 2. plus the bias random walk b_n, applied before its update (as vio_data_simulation does):
//!    b_{n+1} = b_n + K√Δt·e;
//! 3. plus each AR(1) component (flicker components, then Gauss–Markov biases), started from
//!    its stationary law: x_{n+1} = a·x_n + σ√(1 − a²)·e, a = e^(−Δt/T);
//! 4. plus the ramp R·nΔt and the warm-up A·e^(−nΔt/T);
//! 5. plus each line: a sinusoid A·sin(2πf₀nΔt + φ) with a uniform random phase φ, or a
//!    resonance, the continuous 2nd-order system ẍ + 2ζω₀ẋ + ω₀²x = q·w sampled exactly (the
//!    state (x, ẋ) advances by its transition matrix e^(AΔt) plus a normal innovation of
//!    covariance P − ΦPΦᵀ, P the stationary covariance diag(σ², ω₀²σ²), started from P), so
//!    that its autocovariance is the continuous one at the sample times.
//!
//! Then, in [`ImuNoise::apply`], the motion signal is added and the sum is quantised:
//! the integrated angle/velocity with step q = √12·Q (the rate is the difference of the
//! quantised increments over Δt; the rounding residual is carried, which is the same as
//! rounding the running integral, without its growth), then the value to the output LSB.
//!
//! Each axis has its own xoshiro256++ stream (seeded from `--seed` and the axis), so the six
//! axes are generated in parallel, in blocks, and the output does not depend on the number of
//! threads. The filter is run for its impulse-response length before the first sample (the
//! output is stationary from sample 0).

use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;

use super::filter::{Biquad, impulse_response};
use super::model::{Filter, ImuModel, ResolvedChain};
use crate::error::Result;
use bag2mat::Sensor;

/// Output samples generated per block and axis.
pub const BLOCK: usize = 8192;

/// The seed of one axis's stream: `seed` and the stream number mixed by SplitMix64's
/// increment (any fixed injective mixing would do; this one is documented and stable).
pub fn stream_seed(seed: u64, stream: u64) -> u64 {
    seed ^ (stream.wrapping_add(1)).wrapping_mul(0x9E37_79B9_7F4A_7C15)
}

#[derive(Debug, Clone)]
enum WhiteChain {
    /// One normal of this σ per output sample (no filter, or the averaging filter).
    Direct(f64),
    /// D normals of σ_w per output sample through the biquad.
    Biquad { sd: f64, d: usize, f: Biquad },
}

/// One line of an axis at the output rate (step 5 of the module docs).
#[derive(Debug, Clone)]
enum LineGen {
    /// A·sin(ω·n + φ).
    Sinusoid { amp: f64, omega: f64, phase: f64 },
    /// The resonance's state (x, ẋ), transition Φ and innovation factor L (lower triangle).
    Resonance {
        state: [f64; 2],
        phi: [[f64; 2]; 2],
        l: [f64; 3],
    },
}

impl LineGen {
    fn new(line: &super::model::Line, dt: f64, rng: &mut Xoshiro256PlusPlus) -> LineGen {
        let w0 = 2.0 * std::f64::consts::PI * line.frequency;
        if line.bandwidth == 0.0 {
            let u: f64 = rng.random();
            return LineGen::Sinusoid {
                amp: line.amplitude,
                omega: w0 * dt,
                phase: 2.0 * std::f64::consts::PI * u,
            };
        }
        let zeta = line.bandwidth / (2.0 * line.frequency);
        let (al, be) = (zeta * w0, w0 * (1.0 - zeta * zeta).sqrt());
        let e = (-al * dt).exp();
        let (sb, cb) = (be * dt).sin_cos();
        let phi = [
            [e * (cb + al / be * sb), e * sb / be],
            [-e * w0 * w0 / be * sb, e * (cb - al / be * sb)],
        ];
        let var = 0.5 * line.amplitude * line.amplitude;
        let p = [var, w0 * w0 * var];
        // Q = P − ΦPΦᵀ (P diagonal), and its Cholesky factor
        let q11 = p[0] - (phi[0][0] * phi[0][0] * p[0] + phi[0][1] * phi[0][1] * p[1]);
        let q21 = -(phi[1][0] * phi[0][0] * p[0] + phi[1][1] * phi[0][1] * p[1]);
        let q22 = p[1] - (phi[1][0] * phi[1][0] * p[0] + phi[1][1] * phi[1][1] * p[1]);
        let l11 = q11.max(0.0).sqrt();
        let l21 = if l11 > 0.0 { q21 / l11 } else { 0.0 };
        let l22 = (q22 - l21 * l21).max(0.0).sqrt();
        let state = [p[0].sqrt() * normal(rng), p[1].sqrt() * normal(rng)];
        LineGen::Resonance {
            state,
            phi,
            l: [l11, l21, l22],
        }
    }

    /// The line's value at sample `n`, then a step.
    #[inline]
    fn next(&mut self, n: u64, rng: &mut Xoshiro256PlusPlus) -> f64 {
        match self {
            LineGen::Sinusoid { amp, omega, phase } => *amp * (*omega * n as f64 + *phase).sin(),
            LineGen::Resonance { state, phi, l } => {
                let x = state[0];
                let (e1, e2) = (normal(rng), normal(rng));
                let s0 = phi[0][0] * state[0] + phi[0][1] * state[1] + l[0] * e1;
                let s1 = phi[1][0] * state[0] + phi[1][1] * state[1] + l[1] * e1 + l[2] * e2;
                *state = [s0, s1];
                x
            }
        }
    }
}

/// One axis's noise before quantization.
#[derive(Debug, Clone)]
pub struct AxisGenerator {
    rng: Xoshiro256PlusPlus,
    white: WhiteChain,
    rw_step: f64,
    rw: f64,
    ar1: Vec<(f64, f64, f64)>,
    ramp_step: f64,
    n: u64,
    warm: f64,
    warm_factor: f64,
    lines: Vec<LineGen>,
}

#[inline(always)]
fn normal(rng: &mut Xoshiro256PlusPlus) -> f64 {
    StandardNormal.sample(rng)
}

impl AxisGenerator {
    /// The generator of axis `a` behind `chain` at output period `dt`, on its own stream.
    pub fn new(a: &super::model::AxisModel, chain: &ResolvedChain, dt: f64, seed: u64) -> Self {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let sd_w = a.white_noise * chain.internal_rate.sqrt();
        let mut white = match chain.filter {
            Filter::None => WhiteChain::Direct(sd_w),
            Filter::Average => WhiteChain::Direct(sd_w / (chain.decimation as f64).sqrt()),
            Filter::Butterworth2 { cutoff_hz } => WhiteChain::Biquad {
                sd: sd_w,
                d: chain.decimation,
                f: Biquad::butterworth(cutoff_hz, chain.internal_rate),
            },
        };
        if let WhiteChain::Biquad { sd, f, .. } = &mut white {
            // Burn-in: the filter state reaches its stationary law.
            for _ in 0..impulse_response(chain).len() {
                f.step(*sd * normal(&mut rng));
            }
        }
        let mut ar1 = Vec::new();
        let comps = a
            .bias_instability
            .map(|bi| super::flicker::components(&bi))
            .unwrap_or_default();
        for (sigma, t) in comps
            .iter()
            .map(|c| (c.sigma, c.tau))
            .chain(a.gauss_markov.iter().map(|g| (g.sigma, g.tau)))
        {
            let coef = (-dt / t).exp();
            let innov = sigma * (1.0 - coef * coef).sqrt();
            let x0 = sigma * normal(&mut rng);
            ar1.push((coef, innov, x0));
        }
        let (warm, warm_factor) = match a.warmup {
            Some(w) => (w.amplitude(), (-dt / w.tau()).exp()),
            None => (0.0, 0.0),
        };
        // after every other draw of the set-up, so that a model without lines keeps its stream
        let lines = a
            .lines
            .iter()
            .map(|l| LineGen::new(l, dt, &mut rng))
            .collect();
        AxisGenerator {
            rng,
            white,
            rw_step: super::random_walk_to_discrete(a.random_walk, dt),
            rw: 0.0,
            ar1,
            ramp_step: a.rate_ramp * dt,
            n: 0,
            warm,
            warm_factor,
            lines,
        }
    }

    /// The next `out.len()` output samples (noise before quantization).
    pub fn fill(&mut self, out: &mut [f64]) {
        let rng = &mut self.rng;
        for v in out.iter_mut() {
            let mut y = match &mut self.white {
                WhiteChain::Direct(sd) => *sd * normal(rng),
                WhiteChain::Biquad { sd, d, f } => {
                    let mut last = 0.0;
                    for _ in 0..*d {
                        last = f.step(*sd * normal(rng));
                    }
                    last
                }
            };
            if self.rw_step != 0.0 {
                y += self.rw;
                self.rw += self.rw_step * normal(rng);
            }
            for (a, c, x) in self.ar1.iter_mut() {
                y += *x;
                *x = *a * *x + *c * normal(rng);
            }
            if self.ramp_step != 0.0 {
                y += self.ramp_step * self.n as f64;
            }
            if self.warm != 0.0 {
                y += self.warm;
                self.warm *= self.warm_factor;
            }
            for l in self.lines.iter_mut() {
                y += l.next(self.n, rng);
            }
            self.n += 1;
            *v = y;
        }
    }
}

/// Quantization of one axis: the integrated value with step `q` (IEEE 952 Q), then the
/// output value to `lsb`.
#[derive(Debug, Clone, Copy)]
pub struct Quantizer {
    q: f64,
    dt: f64,
    residual: f64,
    lsb: f64,
}

impl Quantizer {
    /// `quantization` = Q (U·s), `resolution` = LSB (U); zero turns each off. The integral
    /// starts at a uniformly random phase within one step (a sensor switched on at an
    /// arbitrary angle).
    pub fn new(quantization: f64, resolution: f64, dt: f64, u01: f64) -> Self {
        let q = super::quantization_step(quantization);
        Quantizer {
            q,
            dt,
            residual: (u01 - 0.5) * q,
            lsb: resolution,
        }
    }

    /// The quantised output for the value `v` (U).
    #[inline]
    pub fn apply(&mut self, v: f64) -> f64 {
        let mut out = v;
        if self.q > 0.0 {
            // residual = ∫ − quantised ∫ before this sample; the new quantised increment is
            // round((residual + v·Δt)/q)·q.
            let inc = self.residual + v * self.dt;
            let k = (inc / self.q).round();
            let step = k * self.q;
            self.residual = inc - step;
            out = step / self.dt;
        }
        if self.lsb > 0.0 {
            out = (out / self.lsb).round() * self.lsb;
        }
        out
    }
}

/// The real-sensor noise of a whole IMU, sample by sample. A worker thread generates the
/// next blocks (the six axes in parallel) while the caller consumes the current one, so the
/// generation overlaps the bag writing.
pub struct ImuNoise {
    quant: Vec<Quantizer>,
    rx: std::sync::mpsc::Receiver<Vec<Vec<f64>>>,
    buf: Vec<Vec<f64>>,
    pos: usize,
}

/// Blocks generated ahead of the consumer.
const BLOCKS_AHEAD: usize = 2;

impl ImuNoise {
    /// The generator of `model` at `rate` Hz, seeded with `seed`.
    pub fn new(model: &ImuModel, rate: f64, seed: u64) -> Result<Self> {
        let dt = 1.0 / rate;
        let mut axes = Vec::with_capacity(6);
        let mut quant = Vec::with_capacity(6);
        for (si, s) in Sensor::BOTH.iter().enumerate() {
            let sm = model.sensor(*s);
            let chain = sm.chain.resolve(*s, rate)?;
            for (ai, a) in sm.axes.iter().enumerate() {
                let stream = (si * 3 + ai) as u64;
                let mut g = AxisGenerator::new(a, &chain, dt, stream_seed(seed, stream));
                let u: f64 = g.rng.random();
                quant.push(Quantizer::new(a.quantization, a.resolution, dt, u));
                axes.push(g);
            }
        }
        let (tx, rx) = std::sync::mpsc::sync_channel(BLOCKS_AHEAD);
        std::thread::spawn(move || {
            loop {
                let mut buf = vec![vec![0.0; BLOCK]; 6];
                axes.par_iter_mut()
                    .zip(buf.par_iter_mut())
                    .for_each(|(g, b)| g.fill(b));
                if tx.send(buf).is_err() {
                    break; // the consumer is gone
                }
            }
        });
        Ok(ImuNoise {
            quant,
            rx,
            buf: Vec::new(),
            pos: BLOCK,
        })
    }

    /// Add the noise of the next sample to the clean `gyro` and `acc` and quantise.
    #[inline]
    pub fn apply(&mut self, gyro: &mut [f64; 3], acc: &mut [f64; 3]) {
        if self.pos == BLOCK {
            self.buf = self.rx.recv().expect("noise worker stopped");
            self.pos = 0;
        }
        let p = self.pos;
        for i in 0..3 {
            gyro[i] = self.quant[i].apply(gyro[i] + self.buf[i][p]);
            acc[i] = self.quant[3 + i].apply(acc[i] + self.buf[3 + i][p]);
        }
        self.pos += 1;
    }
}

/// `n` samples of one axis of `model` (sensor `s`, axis index `axis`), quantised, with a
/// constant true signal `signal` — what the bag carries for a static IMU. For tests and
/// studies.
pub fn axis_series(
    model: &ImuModel,
    s: Sensor,
    axis: usize,
    rate: f64,
    n: usize,
    seed: u64,
    signal: f64,
) -> Result<Vec<f64>> {
    let dt = 1.0 / rate;
    let sm = model.sensor(s);
    let chain = sm.chain.resolve(s, rate)?;
    let si = match s {
        Sensor::Gyro => 0,
        Sensor::Acc => 1,
    };
    let a = &sm.axes[axis];
    let mut g = AxisGenerator::new(a, &chain, dt, stream_seed(seed, (si * 3 + axis) as u64));
    let u: f64 = g.rng.random();
    let mut q = Quantizer::new(a.quantization, a.resolution, dt, u);
    let mut out = vec![0.0; n];
    g.fill(&mut out);
    for v in out.iter_mut() {
        *v = q.apply(signal + *v);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::noise::model::{AxisModel, Chain, SensorModel};

    fn model_with(gyro_x: AxisModel, chain: Chain) -> ImuModel {
        let mut m = ImuModel {
            label: "test".into(),
            gyro: SensorModel::uniform(AxisModel::default()),
            acc: SensorModel::uniform(AxisModel::default()),
        };
        m.gyro.chain = chain;
        m.gyro.axes[0] = gyro_x;
        m
    }

    #[test]
    fn series_is_deterministic_and_matches_the_block_generator() {
        let a = AxisModel {
            white_noise: 0.01,
            random_walk: 1e-4,
            rate_ramp: 1e-6,
            ..Default::default()
        };
        let chain = Chain {
            internal_rate_hz: Some(1000.0),
            filter: Filter::Butterworth2 { cutoff_hz: 40.0 },
        };
        let m = model_with(a, chain);
        let s1 = axis_series(&m, Sensor::Gyro, 0, 200.0, 20_000, 7, 0.0).unwrap();
        let s2 = axis_series(&m, Sensor::Gyro, 0, 200.0, 20_000, 7, 0.0).unwrap();
        assert_eq!(s1, s2);
        let mut imu = ImuNoise::new(&m, 200.0, 7).unwrap();
        for (i, v) in s1.iter().enumerate() {
            let (mut g, mut a) = ([0.0; 3], [0.0; 3]);
            imu.apply(&mut g, &mut a);
            assert_eq!(g[0], *v, "sample {i}");
        }
        let s3 = axis_series(&m, Sensor::Gyro, 0, 200.0, 100, 8, 0.0).unwrap();
        assert_ne!(s1[..100], s3[..]);
    }

    #[test]
    fn quantizer_outputs_multiples_of_the_steps_and_keeps_the_integral() {
        let dt = 0.01;
        let mut q = Quantizer::new(1e-3 / 12f64.sqrt(), 0.0, dt, 0.3);
        let step = 1e-3;
        let mut true_int = 0.0;
        let mut q_int = 0.0;
        for k in 0..10_000 {
            let v = 0.0123 + 0.05 * (k as f64 * 0.37).sin();
            let o = q.apply(v);
            true_int += v * dt;
            q_int += o * dt;
            let counts = o * dt / step;
            assert!(
                (counts - counts.round()).abs() < 1e-6,
                "not a multiple: {o}"
            );
            // The quantised integral never drifts from the true one by more than a step.
            assert!((true_int - q_int).abs() <= step, "k {k}");
        }
        let mut l = Quantizer::new(0.0, 0.25, dt, 0.5);
        assert_eq!(l.apply(1.13), 1.25);
        assert_eq!(l.apply(-0.1), -0.0);
    }
}
