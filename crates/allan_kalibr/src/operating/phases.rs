//! The record by flight (or drive) phase: a spectrogram of the signal, each window called
//! still, vibrating in place or moving, the windows joined into phases, and each phase's
//! operating density and lines — the lines a multicopter's rotors put in move with the
//! throttle, and a user asks which of them reach the estimator in which phase.
//!
//! A window ([`WINDOW_S`] long, half-overlapping, Hann) is **moving** when the signal below
//! the band's lower edge carries, beyond the window's own noise floor, more than a static
//! sensor's drift (an RMS above [`MOVING_RATE`] rad/s or [`MOVING_ACC`] m/s², the record
//! check's motion thresholds, over the three axes);
//! among the others it is **still** when the power above the edge is within
//! [`STILL_VIBRATION`] times the quietest windows' (their 10th percentile) and no frequency
//! there stands [`LINE_RATIO`] times above the quietest windows' (a rotor's line), else
//! **vibrating** (motors on, on the ground). Runs shorter than [`MIN_PHASE_WINDOWS`] join
//! the phase before them. The longest still stretch, when long enough
//! ([`STILL_MIN_S`]), gives a static IEEE 952 value ([`still_analysis`]).

use bag2mat::Sensor;
use rustfft::num_complex::Complex;

use super::band;
use crate::ieee952::imu::{ImuAnalysis, ImuCurves};

/// Spectrogram window, s (a power of two of samples nearest below).
pub const WINDOW_S: f64 = 2.0;
/// A window moves when its low band's RMS exceeds this, rad/s (the record check's ~3 °/s).
pub const MOVING_RATE: f64 = 0.05;
/// … or this, m/s² (the record check's 1° of tilt).
pub const MOVING_ACC: f64 = 0.15;
/// A window is still when its high band's power is within this factor of the quietest.
pub const STILL_VIBRATION: f64 = 3.0;
/// A resting window is vibrating when a frequency above the edge, averaged over
/// ±[`LINE_SMOOTH_WINDOWS`] windows, is this many times the quietest resting windows' there
/// (a rotor's line; with ~7 degrees of freedom the noise alone passes it once in ~10⁸ bins).
pub const LINE_RATIO: f64 = 8.0;
/// Windows either side averaged for the line test.
pub const LINE_SMOOTH_WINDOWS: usize = 2;
/// Shortest phase, windows.
pub const MIN_PHASE_WINDOWS: usize = 4;
/// The shortest still stretch that gives a static value, s (the IEEE 952 fit's N is
/// resolved in a minute at IMU rates).
pub const STILL_MIN_S: f64 = 60.0;
/// The most phases reported (the longest kept).
pub const MAX_PHASES: usize = 24;

/// What a window, and a phase, is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PhaseKind {
    /// At rest: little motion, little vibration.
    Still,
    /// Not moving, but vibrating above the quietest windows (motors on, on the ground).
    Vibrating,
    /// Moving.
    Moving,
}

impl PhaseKind {
    /// The word for it.
    pub fn name(self) -> &'static str {
        match self {
            PhaseKind::Still => "still",
            PhaseKind::Vibrating => "vibrating",
            PhaseKind::Moving => "moving",
        }
    }
}

/// A sensor's spectrogram: the PSD summed over its axes per window.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Spectrogram {
    /// Window step, s.
    pub step: f64,
    /// Window length, s.
    pub window: f64,
    /// Frequencies, Hz.
    pub freq: Vec<f64>,
    /// Per sensor, per window, the PSD (unit²/Hz, summed over the axes).
    pub sensors: Vec<(Sensor, Vec<Vec<f64>>)>,
}

/// One axis of a phase.
#[derive(Debug, Clone, PartialEq)]
pub struct PhaseAxis {
    /// Sensor.
    pub sensor: Sensor,
    /// Axis.
    pub axis: usize,
    /// N_op with its interval (NaN: too short).
    pub n: (f64, f64, f64),
    /// The lines in the band: frequency, amplitude.
    pub lines: Vec<(f64, f64)>,
}

/// A phase.
#[derive(Debug, Clone, PartialEq)]
pub struct Phase {
    /// What it is.
    pub kind: PhaseKind,
    /// First sample (of the analysed series).
    pub start: usize,
    /// One past the last.
    pub end: usize,
    /// Its axes.
    pub axes: Vec<PhaseAxis>,
}

/// The one-sided Hann-windowed PSD of each window of `y` (mean removed per window).
fn stft(y: &[f64], len: usize, hop: usize, rate: f64) -> Vec<Vec<f64>> {
    if y.len() < len {
        return Vec::new();
    }
    let fft = rustfft::FftPlanner::new().plan_fft_forward(len);
    let w: Vec<f64> = (0..len)
        .map(|i| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / len as f64).cos())
        .collect();
    let u: f64 = w.iter().map(|x| x * x).sum();
    (0..=(y.len() - len) / hop)
        .map(|j| {
            let seg = &y[j * hop..j * hop + len];
            let m = seg.iter().sum::<f64>() / len as f64;
            let mut buf: Vec<Complex<f64>> = seg
                .iter()
                .zip(&w)
                .map(|(v, w)| Complex::new((v - m) * w, 0.0))
                .collect();
            fft.process(&mut buf);
            (1..=len / 2)
                .map(|k| buf[k].norm_sqr() * 2.0 / (rate * u))
                .collect()
        })
        .collect()
}

/// The spectrogram of the `raw` signal and the phases (module docs); each phase's density
/// on the `analysed` series (the residual, or the signal) above `split` Hz.
pub fn phases(
    raw: &[&[f64]; 6],
    analysed: &[&[f64]; 6],
    absent: Option<Sensor>,
    rate: f64,
    split: f64,
    user_band: Option<(f64, f64)>,
) -> (Spectrogram, Vec<Phase>) {
    let mut len = 64usize;
    while (len * 2) as f64 <= WINDOW_S * rate {
        len *= 2;
    }
    let hop = len / 2;
    let freq: Vec<f64> = (1..=len / 2)
        .map(|k| k as f64 * rate / len as f64)
        .collect();
    let mut sensors = Vec::new();
    for (base, sensor) in [(0, Sensor::Gyro), (3, Sensor::Acc)] {
        if absent == Some(sensor) {
            continue;
        }
        let per: Vec<Vec<Vec<f64>>> = (0..3)
            .map(|i| stft(raw[base + i], len, hop, rate))
            .collect();
        let windows = per[0].len();
        let sum: Vec<Vec<f64>> = (0..windows)
            .map(|j| {
                (0..freq.len())
                    .map(|k| per.iter().map(|p| p[j][k]).sum())
                    .collect()
            })
            .collect();
        sensors.push((sensor, sum));
    }
    let spec = Spectrogram {
        step: hop as f64 / rate,
        window: len as f64 / rate,
        freq,
        sensors,
    };
    let windows = spec.sensors.first().map_or(0, |s| s.1.len());
    if windows == 0 {
        return (spec, Vec::new());
    }
    let df = rate / len as f64;
    let power = |s: &Vec<Vec<f64>>, j: usize, low: bool| -> f64 {
        spec.freq
            .iter()
            .zip(&s[j])
            .filter(|(f, _)| if low { **f < split } else { **f >= split })
            .map(|(_, p)| p * df)
            .sum()
    };
    let find = |sensor: Sensor| spec.sensors.iter().find(|s| s.0 == sensor).map(|s| &s.1);
    // the power below the edge beyond the window's own noise floor (its median density
    // above the edge, carried down): the noise alone gives about zero
    let excess = |s: &Vec<Vec<f64>>, j: usize| -> f64 {
        let mut hi: Vec<f64> = spec
            .freq
            .iter()
            .zip(&s[j])
            .filter(|(f, _)| **f >= split)
            .map(|(_, p)| *p)
            .collect();
        let floor = if hi.is_empty() {
            0.0
        } else {
            let k = hi.len() / 2;
            *hi.select_nth_unstable_by(k, f64::total_cmp).1
        };
        let low = spec.freq.iter().filter(|f| **f < split).count() as f64;
        (power(s, j, true) - floor * low * df).max(0.0)
    };
    let moving: Vec<bool> = (0..windows)
        .map(|j| {
            find(Sensor::Gyro).is_some_and(|s| excess(s, j).sqrt() > MOVING_RATE)
                || find(Sensor::Acc).is_some_and(|s| excess(s, j).sqrt() > MOVING_ACC)
        })
        .collect();
    let vib_src = find(Sensor::Acc).or(find(Sensor::Gyro));
    let vib: Vec<f64> = (0..windows)
        .map(|j| vib_src.map_or(0.0, |s| power(s, j, false)))
        .collect();
    let mut quiet: Vec<f64> = (0..windows)
        .filter(|&j| !moving[j])
        .map(|j| vib[j])
        .collect();
    let quiet = if quiet.is_empty() {
        f64::NAN
    } else {
        let k = quiet.len() / 10;
        *quiet.select_nth_unstable_by(k, f64::total_cmp).1
    };
    // a line that comes and goes: each bin above the edge, averaged over
    // ±LINE_SMOOTH_WINDOWS windows, against the quietest tenth of the resting windows there
    let line_ratio: Vec<f64> = match vib_src {
        Some(s) => {
            let rest: Vec<usize> = (0..windows).filter(|&j| !moving[j]).collect();
            let smooth = |j: usize, k: usize| {
                let (a, b) = (
                    j.saturating_sub(LINE_SMOOTH_WINDOWS),
                    (j + LINE_SMOOTH_WINDOWS).min(windows - 1),
                );
                (a..=b).map(|i| s[i][k]).sum::<f64>() / (b - a + 1) as f64
            };
            let bins: Vec<usize> = (0..spec.freq.len())
                .filter(|&k| spec.freq[k] >= split)
                .collect();
            let reference: Vec<f64> = bins
                .iter()
                .map(|&k| {
                    let mut v: Vec<f64> = rest.iter().map(|&j| smooth(j, k)).collect();
                    if v.is_empty() {
                        return f64::INFINITY;
                    }
                    let q = v.len() / 10;
                    *v.select_nth_unstable_by(q, f64::total_cmp).1
                })
                .collect();
            (0..windows)
                .map(|j| {
                    bins.iter()
                        .zip(&reference)
                        .map(|(&k, r)| smooth(j, k) / r.max(f64::MIN_POSITIVE))
                        .fold(0.0, f64::max)
                })
                .collect()
        }
        None => vec![0.0; windows],
    };
    let kind: Vec<PhaseKind> = (0..windows)
        .map(|j| {
            if moving[j] {
                PhaseKind::Moving
            } else if vib[j] <= STILL_VIBRATION * quiet && line_ratio[j] <= LINE_RATIO {
                PhaseKind::Still
            } else {
                PhaseKind::Vibrating
            }
        })
        .collect();
    // runs of windows, short ones joined to the one before
    let mut runs: Vec<(PhaseKind, usize, usize)> = Vec::new();
    for (j, k) in kind.iter().enumerate() {
        match runs.last_mut() {
            Some(r) if r.0 == *k => r.2 = j + 1,
            _ => runs.push((*k, j, j + 1)),
        }
    }
    let mut merged: Vec<(PhaseKind, usize, usize)> = Vec::new();
    for r in runs {
        match merged.last_mut() {
            Some(m) if r.2 - r.1 < MIN_PHASE_WINDOWS || m.0 == r.0 => m.2 = r.2,
            _ => merged.push(r),
        }
    }
    if merged.len() > 1 && merged[0].2 - merged[0].1 < MIN_PHASE_WINDOWS {
        let first = merged.remove(0);
        merged[0].1 = first.1;
    }
    if merged.len() > MAX_PHASES {
        merged.sort_by_key(|r| std::cmp::Reverse(r.2 - r.1));
        merged.truncate(MAX_PHASES);
        merged.sort_by_key(|r| r.1);
    }
    let n = analysed.iter().map(|s| s.len()).max().unwrap_or(0);
    let phases = merged
        .into_iter()
        .map(|(kind, a, b)| {
            let start = a * hop;
            let end = if b == windows {
                n
            } else {
                (b * hop + hop).min(n)
            };
            let mut axes = Vec::new();
            for (i, sensor, axis) in super::AXES {
                if absent == Some(sensor) || analysed[i].len() < end {
                    continue;
                }
                let r = band::analyse(&band::BandInput {
                    y: &analysed[i][start..end],
                    rate,
                    spline_err: None,
                    band: user_band,
                    lo_min: split,
                });
                axes.push(match r {
                    Ok(b) => PhaseAxis {
                        sensor,
                        axis,
                        n: (b.n, b.lo, b.hi),
                        lines: b
                            .lines
                            .iter()
                            .filter(|l| l.in_band)
                            .map(|l| (l.line.frequency, l.line.amplitude))
                            .collect(),
                    },
                    Err(_) => PhaseAxis {
                        sensor,
                        axis,
                        n: (f64::NAN, f64::NAN, f64::NAN),
                        lines: Vec::new(),
                    },
                });
            }
            Phase {
                kind,
                start,
                end,
                axes,
            }
        })
        .collect();
    (spec, phases)
}

/// The IEEE 952 analysis of the longest still phase of `cols` (the six section series of
/// the analysed samples), when it lasts [`STILL_MIN_S`]: with its start and end, s from the
/// first analysed sample.
pub fn still_analysis(
    cols: &[&[f64]; 6],
    absent: Option<Sensor>,
    rate: f64,
    phases: &[Phase],
) -> Option<(ImuAnalysis, f64, f64)> {
    let p = phases
        .iter()
        .filter(|p| p.kind == PhaseKind::Still)
        .max_by_key(|p| p.end - p.start)?;
    if ((p.end - p.start) as f64) < STILL_MIN_S * rate {
        return None;
    }
    let s: [&[f64]; 6] = std::array::from_fn(|i| &cols[i][p.start..p.end.min(cols[i].len())]);
    let cfg = crate::ieee952::Config::default();
    let c = ImuCurves::from_samples_of(s, absent, rate, &cfg).ok()?;
    Some((
        c.finish(Vec::new(), &cfg),
        p.start as f64 / rate,
        p.end as f64 / rate,
    ))
}
