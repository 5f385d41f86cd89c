//! The truth beside every bag: `<bag>.truth.yaml` (the model: every term per axis in
//! continuous time with units, its discrete values at the output rate, the chain) and
//! `<bag>.truth.csv` (the exact Allan deviation of the generated sequence per sensor and
//! axis, total and per term, on the dense grid of [`super::truth::tau_grid`]).
//!
//! The yaml's `model` section is a valid `--noise-spec`, so `sim bag --noise-spec
//! imu.bag.truth.yaml` regenerates the same model. Both files are written atomically through
//! bag2mat's output helper.
//!
//! CSV columns: `m` (cluster size), `tau_s`, then `gyro_x … acc_z` (total Allan deviation,
//! rad/s and m/s²), then `<sensor>_<axis>_<term>` for every term that is on for that sensor
//! (its own Allan deviation; the totals are the root-sum-square of these, plus the ramp ×
//! warm-up cross term when both deterministic terms are on).

use bag2mat::Sensor;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::filter::{Biquad, autocorrelation, enbw, impulse_response};
use super::model::{AXES, AxisModel, BiasInstability, Filter, ImuModel, ResolvedChain, Warmup};
use super::truth::{AxisTruth, TERM_NAMES, TermAvar, WIDROW_MIN, tau_grid};
use crate::error::{Result, SimError};
use allan_kalibr::NoiseTerm;

/// What the truth describes.
#[derive(Debug, Clone)]
pub struct TruthInfo<'a> {
    /// The bag the noise went into.
    pub bag: &'a Path,
    /// The model.
    pub model: &'a ImuModel,
    /// Output rate, Hz.
    pub rate: f64,
    /// Messages (samples per axis).
    pub samples: usize,
    /// RNG seed.
    pub seed: u64,
    /// Motion model name (the truth describes the noise; a moving IMU adds its motion, through
    /// the sensor's chain).
    pub motion: &'a str,
}

/// `<bag>.truth.yaml` and `<bag>.truth.csv`.
pub fn paths(bag: &Path) -> (PathBuf, PathBuf) {
    let mut y = bag.as_os_str().to_owned();
    y.push(".truth.yaml");
    let mut c = bag.as_os_str().to_owned();
    c.push(".truth.csv");
    (PathBuf::from(y), PathBuf::from(c))
}

fn file_name(p: &Path) -> String {
    p.file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Per-axis truths of a sensor.
fn sensor_truths(info: &TruthInfo<'_>, s: Sensor) -> Result<(ResolvedChain, Vec<AxisTruth>)> {
    let sm = info.model.sensor(s);
    let chain = sm.chain.resolve(s, info.rate)?;
    let dt = 1.0 / info.rate;
    let t = sm
        .axes
        .iter()
        .map(|a| AxisTruth::new(a, &chain, dt, info.samples))
        .collect();
    Ok((chain, t))
}

/// Shortest representation that reads back to the same f64 (the model round-trips exactly),
/// spelled so that YAML 1.1 parsers (PyYAML) see a float too: a '.' in the mantissa and a
/// signed exponent (`2.0e+2`, not `2e2`).
pub fn g(v: f64) -> String {
    if v == 0.0 {
        return "0.0".to_string();
    }
    let s = format!("{v:e}");
    let (mant, exp) = s.split_once('e').unwrap_or((&s, "0"));
    let mant = if mant.contains('.') {
        mant.to_string()
    } else {
        format!("{mant}.0")
    };
    let exp = if exp.starts_with('-') {
        exp.to_string()
    } else {
        format!("+{exp}")
    };
    format!("{mant}e{exp}")
}

fn axis_model_yaml(o: &mut String, s: Sensor, a: &AxisModel, indent: &str) {
    let u = |t: NoiseTerm| t.unit(s);
    let _ = writeln!(
        o,
        "{indent}white_noise: {}   # N [{}]",
        g(a.white_noise),
        u(NoiseTerm::WhiteNoise)
    );
    let _ = writeln!(
        o,
        "{indent}random_walk: {}   # K [{}]",
        g(a.random_walk),
        u(NoiseTerm::RandomWalk)
    );
    bias_instability_yaml(o, s, a.bias_instability, indent);
    let gm: Vec<String> = a
        .gauss_markov
        .iter()
        .map(|x| format!("{{sigma: {}, tau_s: {}}}", g(x.sigma), g(x.tau)))
        .collect();
    let _ = writeln!(
        o,
        "{indent}gauss_markov: [{}]   # first-order Gauss-Markov bias: sigma [{}], correlation time [s]",
        gm.join(", "),
        s.unit()
    );
    let _ = writeln!(
        o,
        "{indent}rate_ramp: {}   # R [{}]",
        g(a.rate_ramp),
        u(NoiseTerm::Ramp)
    );
    let _ = writeln!(
        o,
        "{indent}quantization: {}   # Q [{}], IEEE 952 (integrated value quantised with step sqrt(12)*Q)",
        g(a.quantization),
        u(NoiseTerm::Quantization)
    );
    let _ = writeln!(
        o,
        "{indent}resolution: {}   # output LSB [{}]",
        g(a.resolution),
        s.unit()
    );
    warmup_yaml(o, s, a.warmup, indent);
    let lines: Vec<String> = a
        .lines
        .iter()
        .map(|l| {
            format!(
                "{{frequency_hz: {}, amplitude: {}, bandwidth_hz: {}}}",
                g(l.frequency),
                g(l.amplitude),
                g(l.bandwidth)
            )
        })
        .collect();
    let _ = writeln!(
        o,
        "{indent}lines: [{}]   # vibration lines at the output: amplitude [{}] of A*sin(2*pi*f*t + phase); bandwidth_hz > 0: a 2nd-order resonance of that -3 dB width, rms A/sqrt(2)",
        lines.join(", "),
        s.unit()
    );
}
/// The `bias_instability:` line of [`axis_model_yaml`] (off: the keys with B = 0).
fn bias_instability_yaml(o: &mut String, s: Sensor, b: Option<BiasInstability>, indent: &str) {
    match b {
        Some(b) => {
            let _ = writeln!(
                o,
                "{indent}bias_instability: {{value: {}, tau_lo_s: {}, tau_hi_s: {}}}   # B [{}]; Allan floor 0.664*B between the corner times",
                g(b.b),
                g(b.tau_lo),
                g(b.tau_hi),
                s.unit()
            );
        }
        None => {
            let _ = writeln!(
                o,
                "{indent}bias_instability: {{value: 0.0, tau_lo_s: 1.0, tau_hi_s: 10.0}}   # off"
            );
        }
    }
}

/// The `warmup:` line of [`axis_model_yaml`], in the form the model has.
fn warmup_yaml(o: &mut String, s: Sensor, w: Option<Warmup>, indent: &str) {
    match w {
        Some(Warmup::Exponential { amplitude, tau }) => {
            let _ = writeln!(
                o,
                "{indent}warmup: {{amplitude: {}, tau_s: {}}}   # bias A*exp(-t/T) after power-on [{}]",
                g(amplitude),
                g(tau),
                s.unit()
            );
        }
        Some(Warmup::Thermal {
            temperature_rise,
            tau,
            sensitivity,
        }) => {
            let _ = writeln!(
                o,
                "{indent}warmup: {{temperature_rise_k: {}, tau_s: {}, bias_per_k: {}}}   # T(t) = T0 + dT*(1 - exp(-t/T)), bias sensitivity [{}/K]: A = {}",
                g(temperature_rise),
                g(tau),
                g(sensitivity),
                s.unit(),
                g(-sensitivity * temperature_rise)
            );
        }
        None => {
            let _ = writeln!(o, "{indent}warmup: {{amplitude: 0.0, tau_s: 1.0}}   # off");
        }
    }
}

/// The yaml text: the header, the units, the model (a valid `--noise-spec`), then what the
/// generator does per output sample.
pub fn yaml_text(info: &TruthInfo<'_>) -> Result<String> {
    let mut o = String::new();
    header_yaml(&mut o, info);
    let _ = writeln!(o, "units:");
    for s in Sensor::BOTH {
        let _ = writeln!(
            o,
            "  {}: {{white_noise: {}, random_walk: {}, bias_instability: {u}, gauss_markov_sigma: {u}, rate_ramp: {}, quantization: {}, resolution: {u}, warmup_amplitude: {u}, line_amplitude: {u}, allan_deviation: {u}}}",
            s.name(),
            NoiseTerm::WhiteNoise.unit(s),
            NoiseTerm::RandomWalk.unit(s),
            NoiseTerm::Ramp.unit(s),
            NoiseTerm::Quantization.unit(s),
            u = s.unit()
        );
    }
    model_yaml(&mut o, info.model);
    let dt = 1.0 / info.rate;
    let _ = writeln!(
        o,
        "discrete:   # what the generator does per output sample (period {} s)",
        g(dt)
    );
    for s in Sensor::BOTH {
        discrete_sensor_yaml(&mut o, info, s)?;
    }
    Ok(o)
}

/// The lines above `units:`: what the file is, the bag, the run.
fn header_yaml(o: &mut String, info: &TruthInfo<'_>) {
    let dt = 1.0 / info.rate;
    let (_, csv) = paths(info.bag);
    let _ = writeln!(
        o,
        "# sim truth: the noise model behind {} (continuous-time parameters with units), its\n\
         # discrete values at the output rate, and where its exact Allan deviation is.\n\
         # The 'model' section is a valid `sim bag --noise-spec`.",
        file_name(info.bag)
    );
    let _ = writeln!(o, "format: {}", super::spec::TRUTH_FORMAT);
    let _ = writeln!(o, "bag: {:?}", file_name(info.bag));
    let _ = writeln!(
        o,
        "curves: {:?}   # m, tau_s, Allan deviation per sensor and axis (total, then each term)",
        file_name(&csv)
    );
    let _ = writeln!(o, "label: {:?}", info.model.label);
    let _ = writeln!(o, "seed: {}", info.seed);
    let _ = writeln!(
        o,
        "motion: {}   # the truth is the noise; a moving IMU adds its motion (through the sensor's low-pass and decimation)",
        info.motion
    );
    let _ = writeln!(o, "output_rate_hz: {}", g(info.rate));
    let _ = writeln!(o, "samples: {}", info.samples);
    let _ = writeln!(
        o,
        "duration_s: {}   # samples / output rate",
        g(info.samples as f64 * dt)
    );
}

/// The `model:` section, a valid `--noise-spec`.
fn model_yaml(o: &mut String, model: &ImuModel) {
    let _ = writeln!(o, "model:");
    for s in Sensor::BOTH {
        let sm = model.sensor(s);
        let _ = writeln!(o, "  {}:", s.name());
        if let Some(r) = sm.chain.internal_rate_hz {
            let _ = writeln!(o, "    internal_rate_hz: {}", g(r));
        }
        let (kind, cutoff) = sm.chain.filter_spec();
        match cutoff {
            Some(c) => {
                let _ = writeln!(
                    o,
                    "    filter: {{kind: {kind}, cutoff_hz: {}}}   # 2nd-order Butterworth, bilinear, -3 dB at cutoff_hz, at the internal rate",
                    g(c)
                );
            }
            None => {
                let _ = writeln!(o, "    filter: {{kind: {kind}}}");
            }
        }
        let _ = writeln!(o, "    axes:");
        for (axis, a) in AXES.iter().zip(&sm.axes) {
            let _ = writeln!(o, "      {axis}:");
            axis_model_yaml(o, s, a, "        ");
        }
    }
}

/// One sensor of the `discrete:` section: its chain, then each axis.
fn discrete_sensor_yaml(o: &mut String, info: &TruthInfo<'_>, s: Sensor) -> Result<()> {
    let (chain, truths) = sensor_truths(info, s)?;
    let sm = info.model.sensor(s);
    let h = impulse_response(&chain);
    let _ = writeln!(o, "  {}:", s.name());
    let _ = writeln!(o, "    internal_rate_hz: {}", g(chain.internal_rate));
    let _ = writeln!(o, "    decimation: {}", chain.decimation);
    if let Filter::Butterworth2 { cutoff_hz } = chain.filter {
        let bq = Biquad::butterworth(cutoff_hz, chain.internal_rate);
        let _ = writeln!(
            o,
            "    filter_coefficients: {{b: [{}, {}, {}], a: [1.0, {}, {}]}}",
            g(bq.b[0]),
            g(bq.b[1]),
            g(bq.b[2]),
            g(bq.a[0]),
            g(bq.a[1])
        );
    }
    let _ = writeln!(
        o,
        "    impulse_response_energy: {}   # sum h^2 (internal rate)",
        g(autocorrelation(&h, 0))
    );
    let _ = writeln!(
        o,
        "    equivalent_noise_bandwidth_hz: {}   # one-sided; white per-sample variance = 2*N^2*ENBW",
        g(enbw(&chain))
    );
    let _ = writeln!(o, "    axes:");
    for ((axis, a), t) in AXES.iter().zip(&sm.axes).zip(&truths) {
        discrete_axis_yaml(o, info, s, axis, a, t);
    }
    Ok(())
}

/// One axis of the `discrete:` section: the random terms' per-sample figures, then
/// [`deterministic_axis_yaml`].
fn discrete_axis_yaml(
    o: &mut String,
    info: &TruthInfo<'_>,
    s: Sensor,
    axis: &str,
    a: &AxisModel,
    t: &AxisTruth,
) {
    let dt = 1.0 / info.rate;
    let u = s.unit();
    let _ = writeln!(o, "      {axis}:");
    let w = t.white();
    let _ = writeln!(
        o,
        "        white_per_sample_sigma: {}   # [{u}] sqrt(N^2 * f_internal * sum h^2): filtered and decimated",
        g(w.variance().sqrt())
    );
    let _ = writeln!(
        o,
        "        white_per_sample_sigma_naive: {}   # [{u}] N*sqrt(f_output), what an unfiltered sensor would give",
        g(super::white_to_discrete(a.white_noise, dt))
    );
    let _ = writeln!(
        o,
        "        white_noise_density_effective: {}   # [{}] sqrt(sum_k R(k) * dt): the -1/2 line at long tau, aliasing included",
        g((w.s0() * dt).sqrt()),
        NoiseTerm::WhiteNoise.unit(s)
    );
    let _ = writeln!(
        o,
        "        random_walk_step_sigma: {}   # [{u}] K*sqrt(dt), bias applied before its update",
        g(super::random_walk_to_discrete(a.random_walk, dt))
    );
    let comps = a
        .bias_instability
        .map(|b| super::flicker::components(&b))
        .unwrap_or_default();
    let cs: Vec<String> = comps
        .iter()
        .map(|c| format!("{{sigma: {}, tau_s: {}}}", g(c.sigma), g(c.tau)))
        .collect();
    let _ = writeln!(
        o,
        "        flicker_components: [{}]   # AR(1) x' = a*x + sigma*sqrt(1-a^2)*e, a = exp(-dt/tau_s)",
        cs.join(", ")
    );
    let _ = writeln!(
        o,
        "        rate_ramp_per_sample: {}   # [{u}] R*dt",
        g(a.rate_ramp * dt)
    );
    let _ = writeln!(
        o,
        "        quantization_step: {}   # [{}] sqrt(12)*Q on the integrated value",
        g(super::quantization_step(a.quantization)),
        NoiseTerm::Quantization.unit(s)
    );
    deterministic_axis_yaml(o, info, s, a, t);
}

/// The rest of one axis of the `discrete:` section: lines, warm-up, the Widrow ratios of the
/// rounding terms, the exact Allan deviation at 1 s.
fn deterministic_axis_yaml(
    o: &mut String,
    info: &TruthInfo<'_>,
    s: Sensor,
    a: &AxisModel,
    t: &AxisTruth,
) {
    let dt = 1.0 / info.rate;
    let u = s.unit();
    for l in &a.lines {
        let (pa, pb) = allan_kalibr::resonance_poles(l.frequency, l.bandwidth, dt);
        let _ = writeln!(
            o,
            "        line_{}hz: {{cycles_per_sample: {}, decay_per_sample: {}, radians_per_sample: {}}}   # nu0 = f*dt; a resonance's autocovariance (A^2/2)*exp(-a|k|)*(cos(b k) + (a/b) sin(b|k|))",
            g(l.frequency),
            g(l.frequency * dt),
            g(pa),
            g(pb)
        );
    }
    if let Some(wu) = a.warmup {
        let _ = writeln!(
            o,
            "        warmup_amplitude: {}   # [{u}] A",
            g(wu.amplitude())
        );
        let _ = writeln!(
            o,
            "        warmup_factor_per_sample: {}   # exp(-dt/T)",
            g((-dt / wu.tau()).exp())
        );
    }
    // Widrow ratios: how well the rounding errors are uniform and white.
    if let Some(r) = t.widrow_resolution() {
        let _ = writeln!(
            o,
            "        widrow_ratio_resolution: {}   # sd of the change per sample / LSB; >= 1: rounding error white (truth exact)",
            g(r)
        );
    }
    if let Some(r) = t.widrow_quantization() {
        let _ = writeln!(
            o,
            "        widrow_ratio_quantization: {}   # sd of the increment of the integrated value per sample / step",
            g(r)
        );
    }
    let m1 = (info.rate.round() as usize).max(1);
    if 2 * m1 <= info.samples {
        let _ = writeln!(
            o,
            "        allan_deviation_at_1s: {}   # [{u}] exact, from the curves file",
            g(t.avar(m1).sqrt())
        );
    }
}

/// The csv text.
pub fn csv_text(info: &TruthInfo<'_>) -> Result<String> {
    let dt = 1.0 / info.rate;
    let mut per_sensor = Vec::new();
    for s in Sensor::BOTH {
        let (_, t) = sensor_truths(info, s)?;
        // Terms on for this sensor (any axis): evaluate at m = 1 and at a long τ.
        let m_probe = [1usize, (info.samples / 4).max(1)];
        let on: Vec<usize> = (0..TERM_NAMES.len())
            .filter(|&k| {
                t.iter().any(|at| {
                    m_probe.iter().any(|&m| {
                        let v = at.terms(m).values()[k];
                        v.is_finite() && v > 0.0
                    })
                })
            })
            .collect();
        per_sensor.push((s, t, on));
    }
    let mut o = String::from("m,tau_s");
    for (s, _, _) in &per_sensor {
        for axis in AXES {
            let _ = write!(o, ",{}_{axis}", s.short());
        }
    }
    for (s, _, on) in &per_sensor {
        for axis in AXES {
            for &k in on {
                let _ = write!(o, ",{}_{axis}_{}", s.short(), TERM_NAMES[k]);
            }
        }
    }
    o.push('\n');
    for m in tau_grid(info.samples) {
        let _ = write!(o, "{m},{:.10e}", m as f64 * dt);
        let terms: Vec<Vec<TermAvar>> = per_sensor
            .iter()
            .map(|(_, t, _)| t.iter().map(|at| at.terms(m)).collect())
            .collect();
        for ts in &terms {
            for t in ts {
                let _ = write!(o, ",{:.10e}", t.total().sqrt());
            }
        }
        for (ts, (_, _, on)) in terms.iter().zip(&per_sensor) {
            for t in ts {
                let v = t.values();
                for &k in on {
                    let _ = write!(o, ",{:.10e}", v[k].sqrt());
                }
            }
        }
        o.push('\n');
    }
    Ok(o)
}

/// One line per axis whose quantization or LSB rounding is too coarse for its noise
/// (Widrow ratio below [`WIDROW_MIN`]): there the rounding error is not white and the
/// truth's Q/LSB rows are only approximate.
pub fn widrow_warnings(model: &ImuModel, rate: f64, samples: usize) -> Result<Vec<String>> {
    let mut out = Vec::new();
    let dt = 1.0 / rate;
    for s in Sensor::BOTH {
        let chain = model.sensor(s).chain.resolve(s, rate)?;
        for (axis, a) in AXES.iter().zip(&model.sensor(s).axes) {
            let t = AxisTruth::new(a, &chain, dt, samples);
            for (what, r) in [
                ("output LSB", t.widrow_resolution()),
                ("quantization step (sqrt(12)*Q)", t.widrow_quantization()),
            ] {
                if let Some(r) = r
                    && r < WIDROW_MIN
                {
                    out.push(format!(
                        "{} {axis}: the {what} is coarse for the noise that moves the value (Widrow ratio {r:.2} < {WIDROW_MIN}): the rounding error is not white and the truth's term for it is approximate",
                        s.name()
                    ));
                }
            }
        }
    }
    Ok(out)
}

/// Writes both files atomically beside the bag, among the run's `outputs`; returns their
/// paths.
pub fn write(
    outputs: &bag2mat::shared::output::Outputs,
    info: &TruthInfo<'_>,
) -> Result<[PathBuf; 2]> {
    let (yp, cp) = paths(info.bag);
    let y = yaml_text(info)?;
    let c = csv_text(info)?;
    outputs.write_atomic(&yp, |w| w.write_all(y.as_bytes()))?;
    outputs.write_atomic(&cp, |w| w.write_all(c.as_bytes()))?;
    Ok([yp, cp])
}

/// A truth curves file read back: τ and named columns.
#[derive(Debug, Clone)]
pub struct TruthCurves {
    /// τ, s.
    pub tau: Vec<f64>,
    /// Column name → values (Allan deviation).
    pub columns: std::collections::BTreeMap<String, Vec<f64>>,
}

impl TruthCurves {
    /// Mean over the three axes of a sensor's total deviation.
    pub fn sensor_mean(&self, s: Sensor) -> Option<Vec<f64>> {
        let cols: Option<Vec<&Vec<f64>>> = AXES
            .iter()
            .map(|a| self.columns.get(&format!("{}_{a}", s.short())))
            .collect();
        let cols = cols?;
        Some(
            (0..self.tau.len())
                .map(|i| cols.iter().map(|c| c[i]).sum::<f64>() / 3.0)
                .collect(),
        )
    }
}

/// Reads a `<bag>.truth.csv`.
pub fn read_curves(path: &Path) -> Result<TruthCurves> {
    let text = std::fs::read_to_string(path).map_err(|e| SimError::io(path, e))?;
    let bad = |msg: String| SimError::Input(format!("{}: {msg}", path.display()));
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    if header.len() < 3 || header[0] != "m" || header[1] != "tau_s" {
        return Err(bad(
            "not a sim truth curves file (header m,tau_s,...)".into()
        ));
    }
    let mut tau = Vec::new();
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); header.len() - 2];
    for (i, l) in lines.enumerate() {
        let f: Vec<&str> = l.split(',').collect();
        if f.len() != header.len() {
            return Err(bad(format!(
                "line {}: {} fields, expected {}",
                i + 2,
                f.len(),
                header.len()
            )));
        }
        tau.push(
            f[1].parse()
                .map_err(|_| bad(format!("line {}: bad tau", i + 2)))?,
        );
        for (c, v) in cols.iter_mut().zip(&f[2..]) {
            c.push(v.parse().unwrap_or(f64::NAN));
        }
    }
    Ok(TruthCurves {
        tau,
        columns: header[2..]
            .iter()
            .map(|h| h.to_string())
            .zip(cols)
            .collect(),
    })
}

/// Reads the model of a `<bag>.truth.yaml`.
pub fn read_model(path: &Path) -> Result<ImuModel> {
    let spec = super::spec::read(path)?;
    let mut m = super::spec::apply(&spec, Some(super::spec::zero_model("truth")), path)?;
    m.label = format!("truth {}", path.display());
    Ok(m)
}

#[cfg(test)]
mod tests {
    #[test]
    fn floats_are_yaml_1_1_floats_and_round_trip() {
        for (v, s) in [
            (200.0, "2.0e+2"),
            (4e-7, "4.0e-7"),
            (9.69627362219072e-6, "9.69627362219072e-6"),
            (0.0, "0.0"),
            (-1.5, "-1.5e+0"),
        ] {
            assert_eq!(super::g(v), s);
            assert_eq!(s.parse::<f64>().unwrap(), v);
        }
    }
}
