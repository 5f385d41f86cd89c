//! The sensor's signal chain applied to the true motion, not only to its noise.
//!
//! A MEMS IMU samples everything it feels at its internal rate, low-pass filters it and
//! decimates to the output data rate ([`crate::noise::model::Chain`]). The noise generator
//! passes the white noise through that chain; this module passes the motion through the
//! same chain, so a moving bag from a profile with a digital low-pass filter shows the
//! filter's attenuation and group delay, as the real sensor's output does (a 2nd-order
//! Butterworth at f_c delays slow motion by √2/(2π·f_c): 9.8 ms for the BMI088 gyro's
//! 23 Hz). The chain is linear, so filtering motion and noise apart and adding them is the
//! same as filtering their sum; the slow bias terms are added after the filter in both.
//!
//! Output sample n at time t keeps the last of the D internal samples at
//! t − (D − 1 − k)/f_i, k = 0..D (the averaging filter: their mean), as the noise chain
//! does. Before the first output sample the filter is run over its impulse response's
//! length of earlier internal samples (the analytic motions are defined for t < 0), so the
//! output is the filter's steady response from sample 0. Without a filter the output is
//! the motion at t itself (sub-sampling), and a static IMU is not touched: the presets'
//! bags stay byte-identical.

use crate::noise::filter::{Biquad, impulse_response};
use crate::noise::model::{Filter, ImuModel, ResolvedChain};
use bag2mat::Sensor;

use crate::error::Result;

/// One sensor's three axes through its chain.
#[derive(Debug, Clone)]
enum Path {
    /// No filter: the output is the motion at the output instant.
    Pass,
    /// Mean of the D internal samples.
    Average { chain: ResolvedChain },
    /// The three axes' biquads; `primed` once the burn-in has run.
    Butterworth {
        chain: ResolvedChain,
        filters: [Biquad; 3],
        burn_in: usize,
        primed: bool,
    },
}

impl Path {
    fn new(chain: ResolvedChain) -> Self {
        match chain.filter {
            Filter::None => Path::Pass,
            Filter::Average => Path::Average { chain },
            Filter::Butterworth2 { cutoff_hz } => Path::Butterworth {
                chain,
                filters: [Biquad::butterworth(cutoff_hz, chain.internal_rate); 3],
                burn_in: impulse_response(&chain).len(),
                primed: false,
            },
        }
    }

    /// The output at time `t` of the signal `x(τ)`.
    fn output(&mut self, t: f64, x: &mut impl FnMut(f64) -> [f64; 3]) -> [f64; 3] {
        match self {
            Path::Pass => x(t),
            Path::Average { chain } => {
                let d = chain.decimation;
                let mut sum = [0.0; 3];
                for k in 0..d {
                    let v = x(internal_time(t, chain, k));
                    for (s, v) in sum.iter_mut().zip(v) {
                        *s += v;
                    }
                }
                sum.map(|s| s / d as f64)
            }
            Path::Butterworth {
                chain,
                filters,
                burn_in,
                primed,
            } => {
                let step = |filters: &mut [Biquad; 3], v: [f64; 3]| {
                    [
                        filters[0].step(v[0]),
                        filters[1].step(v[1]),
                        filters[2].step(v[2]),
                    ]
                };
                if !*primed {
                    // The burn_in internal samples before this output's first one.
                    let first = internal_time(t, chain, 0);
                    for j in (1..=*burn_in).rev() {
                        step(filters, x(first - j as f64 / chain.internal_rate));
                    }
                    *primed = true;
                }
                let mut last = [0.0; 3];
                for k in 0..chain.decimation {
                    last = step(filters, x(internal_time(t, chain, k)));
                }
                last
            }
        }
    }
}

/// The k-th of the D internal sample times that end at the output time `t`.
#[inline]
fn internal_time(t: f64, chain: &ResolvedChain, k: usize) -> f64 {
    t - (chain.decimation - 1 - k) as f64 / chain.internal_rate
}

/// Both sensors' chains, applied to the motion sample by sample.
#[derive(Debug, Clone)]
pub struct MotionChain {
    gyro: Path,
    acc: Path,
}

impl MotionChain {
    /// The chains of `model` at `rate` Hz, or `None` when neither sensor has a filter (the
    /// motion then reaches the output unchanged and needs no work).
    pub fn new(model: &ImuModel, rate: f64) -> Result<Option<Self>> {
        let path =
            |s: Sensor| -> Result<Path> { Ok(Path::new(model.sensor(s).chain.resolve(s, rate)?)) };
        let (gyro, acc) = (path(Sensor::Gyro)?, path(Sensor::Acc)?);
        Ok(match (&gyro, &acc) {
            (Path::Pass, Path::Pass) => None,
            _ => Some(MotionChain { gyro, acc }),
        })
    }

    /// The gyro and accelerometer outputs at output time `t` of the true signals
    /// `gyro(τ)` and `acc(τ)`, called in increasing `t` on the output grid.
    pub fn output(
        &mut self,
        t: f64,
        mut gyro: impl FnMut(f64) -> [f64; 3],
        mut acc: impl FnMut(f64) -> [f64; 3],
    ) -> ([f64; 3], [f64; 3]) {
        (self.gyro.output(t, &mut gyro), self.acc.output(t, &mut acc))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::noise::model::{AxisModel, Chain, SensorModel};
    use std::f64::consts::PI;

    /// Agreement of the streaming chain with the slow reference: both run the same
    /// arithmetic in the same order, so only the time arguments' rounding differs.
    const SAME_ARITHMETIC_TOL: f64 = 1e-12;
    /// A projection over 1600 samples of a steady sinusoid: rounding only.
    const GAIN_TOL: f64 = 1e-9;

    fn model(gyro: Chain, acc: Chain) -> ImuModel {
        let still = || AxisModel::ideal(0.0, 0.0);
        ImuModel {
            label: "test".into(),
            gyro: SensorModel {
                chain: gyro,
                axes: [still(), still(), still()],
            },
            acc: SensorModel {
                chain: acc,
                axes: [still(), still(), still()],
            },
        }
    }

    fn butter(fi: f64, fc: f64) -> Chain {
        Chain {
            internal_rate_hz: Some(fi),
            filter: Filter::Butterworth2 { cutoff_hz: fc },
        }
    }

    fn sines(t: f64) -> [f64; 3] {
        [
            (2.0 * PI * 0.5 * t).sin(),
            (2.0 * PI * 7.0 * t).cos(),
            1.0 + (2.0 * PI * 31.0 * t).sin(),
        ]
    }

    #[test]
    fn without_a_filter_the_motion_is_untouched() {
        let sub_sampled = Chain {
            internal_rate_hz: Some(1000.0),
            filter: Filter::None,
        };
        assert!(
            MotionChain::new(&model(sub_sampled, Chain::DIRECT), 200.0)
                .unwrap()
                .is_none()
        );
    }

    /// The slow, obvious version: the whole internal-rate sequence from the first burn-in
    /// sample, filtered, then every D-th value kept.
    #[test]
    fn streaming_chain_equals_filtering_the_whole_internal_sequence() {
        let (rate, fi, fc) = (200.0, 2000.0, 23.0);
        let m = model(butter(fi, fc), Chain::DIRECT);
        let mut mc = MotionChain::new(&m, rate).unwrap().unwrap();
        let chain = m.gyro.chain.resolve(Sensor::Gyro, rate).unwrap();
        let (d, burn) = (chain.decimation, impulse_response(&chain).len());
        let n_out = 400;
        let t0 = 3.0;
        let first = t0 - (d - 1) as f64 / fi;
        let mut f = [Biquad::butterworth(fc, fi); 3];
        let mut reference = Vec::new();
        for j in 0..burn + n_out * d {
            let tau = first + (j as f64 - burn as f64) / fi;
            let v = sines(tau);
            let y = [f[0].step(v[0]), f[1].step(v[1]), f[2].step(v[2])];
            if j >= burn && (j - burn) % d == d - 1 {
                reference.push(y);
            }
        }
        for (i, r) in reference.iter().enumerate() {
            let t = t0 + i as f64 / rate;
            let (g, a) = mc.output(t, sines, sines);
            assert_eq!(a, sines(t), "the accelerometer has no filter here");
            for k in 0..3 {
                assert!(
                    (g[k] - r[k]).abs() <= SAME_ARITHMETIC_TOL,
                    "sample {i} axis {k}: {} vs {}",
                    g[k],
                    r[k]
                );
            }
        }
    }

    /// A sinusoid comes out scaled by |H(f)|: the transfer function of the noise model's
    /// filter, seen on the motion (its delay is checked from the command line, on a moving
    /// bag, in `tests/real_sensors.rs`).
    #[test]
    fn a_sinusoid_comes_out_with_the_filters_gain() {
        let (rate, fi, fc) = (400.0, 3200.0, 50.0);
        let m = model(Chain::DIRECT, butter(fi, fc));
        let mc = MotionChain::new(&m, rate).unwrap().unwrap();
        let filter = Biquad::butterworth(fc, fi);
        for f in [1.0, 20.0, 50.0, 120.0] {
            let mut mc = mc.clone();
            let x = move |t: f64| [(2.0 * PI * f * t).sin(); 3];
            // The amplitude of the output by projection on sin and cos over whole periods
            // (4 s at 400 Hz: exact for these frequencies, none of them 0 or Nyquist).
            let n = (rate * 4.0) as usize;
            let (mut ps, mut pc) = (0.0, 0.0);
            for i in 0..n {
                let t = i as f64 / rate;
                let y = mc.output(t, sines, x).1[0];
                ps += y * (2.0 * PI * f * t).sin();
                pc += y * (2.0 * PI * f * t).cos();
            }
            let amplitude = 2.0 / n as f64 * ps.hypot(pc);
            let gain = filter.gain2(f / fi).sqrt();
            assert!(
                (amplitude - gain).abs() < GAIN_TOL,
                "f {f} Hz: amplitude {amplitude}, |H| {gain}"
            );
        }
        // And the averaging filter: the mean over the D samples of one output.
        let avg = Chain {
            internal_rate_hz: Some(2000.0),
            filter: Filter::Average,
        };
        let mut mc2 = MotionChain::new(&model(avg, Chain::DIRECT), 200.0)
            .unwrap()
            .unwrap();
        let t = 1.234;
        let (g, _) = mc2.output(t, sines, sines);
        let mean: f64 = (0..10)
            .map(|k| sines(t - (9 - k) as f64 / 2000.0)[1])
            .sum::<f64>()
            / 10.0;
        assert!((g[1] - mean).abs() < SAME_ARITHMETIC_TOL);
    }
}
