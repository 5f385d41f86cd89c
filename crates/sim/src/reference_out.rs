//! The reference trajectory a moving `sim bag` writes beside its bag (`--reference-out`):
//! the body's poses as a motion-capture system records them — at its own rate, on its own
//! clock (`--reference-offset`: the reference's clock runs ahead of the IMU's), with its own
//! white noise (`--reference-noise`) — as a TUM file, and `<reference>.truth.yaml`: what
//! was injected (the offset, the IMU's mounting and errors, the reference's rate and
//! noise) and the operating noise density the analysis should find, per axis:
//!
//! ```text
//! N_op² = σ²_white / f_s + Σ_lines A² / (2 f_s)
//! ```
//!
//! σ²_white the white noise's per-sample variance after the sensor's chain (N²·f_s without
//! a filter), each line's variance A²/2 (lines are added at the output): what an
//! estimator's discretisation σ_d = N·√f_s must carry. Terms below the analysis' band
//! (random walk, bias instability, Gauss–Markov, warm-up) are not counted, nor the
//! quantization Q and the LSB (the file says which of them the model has).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use bag2mat::Sensor;
use bag2mat::shared::output::Outputs;
use nalgebra::Vector3;
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, StandardNormal};

use crate::error::Result;
use crate::motion::Motion;
use crate::mounting::Mounting;
use crate::noise::model::ImuModel;

/// The reference's settings.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceOut {
    /// The TUM file.
    pub path: PathBuf,
    /// Its rate, Hz.
    pub rate: f64,
    /// Its clock's lead over the IMU's, s.
    pub offset: f64,
    /// Its white noise: position (m) and rotation (rad) per coordinate.
    pub noise: (f64, f64),
}

/// The noise's seed: the bag's, so one seed gives one record (a constant apart, so the
/// reference's stream is not the IMU's).
const SEED_SALT: u64 = 0x7265_6665_7265_6e63;

/// The operating density of each axis (module docs): gyro x y z, acc x y z.
pub fn expected_operating(model: &ImuModel, rate: f64) -> Result<[f64; 6]> {
    let mut out = [0.0; 6];
    for (k, sensor) in [Sensor::Gyro, Sensor::Acc].into_iter().enumerate() {
        let sm = model.sensor(sensor);
        let chain = sm.chain.resolve(sensor, rate)?;
        for (i, ax) in sm.axes.iter().enumerate() {
            let white = crate::noise::truth::FilteredWhite::new(ax.white_noise, &chain).r[0];
            let lines: f64 = ax
                .lines
                .iter()
                .map(|l| l.amplitude * l.amplitude / 2.0)
                .sum();
            out[3 * k + i] = ((white + lines) / rate).sqrt();
        }
    }
    Ok(out)
}

/// Writes the reference of `motion` over `[0, duration]` s and its truth file among
/// `outputs`; `start_ns` is the IMU's first stamp. Returns the two paths.
#[allow(clippy::too_many_arguments)]
pub fn write(
    outputs: &Outputs,
    r: &ReferenceOut,
    motion: Motion,
    mounting: &Mounting,
    model: &ImuModel,
    imu_rate: f64,
    duration: f64,
    start_ns: u64,
    seed: u64,
) -> Result<[PathBuf; 2]> {
    let mut rng = StdRng::seed_from_u64(seed ^ SEED_SALT);
    let mut n = || -> f64 { StandardNormal.sample(&mut rng) };
    let mut tum = String::from(
        "# t tx ty tz qx qy qz qw: the body's pose (body -> world), sim bag --reference-out\n",
    );
    let count = (duration * r.rate).floor() as i64;
    for j in 0..=count {
        let t = j as f64 / r.rate;
        let m = motion.sample(t);
        let p = m.p + Vector3::new(n(), n(), n()) * r.noise.0;
        let rot =
            m.r_wb * allan_kalibr::spline::so3::exp(&(Vector3::new(n(), n(), n()) * r.noise.1));
        let q = crate::rotation::quat_from_matrix(&rot);
        let ns = start_ns as i64 + ((t + r.offset) * 1e9).round() as i64;
        let _ = writeln!(
            tum,
            "{}.{:09} {:?} {:?} {:?} {:?} {:?} {:?} {:?}",
            ns.div_euclid(1_000_000_000),
            ns.rem_euclid(1_000_000_000),
            p.x,
            p.y,
            p.z,
            q[1],
            q[2],
            q[3],
            q[0]
        );
    }
    outputs.write_atomic(&r.path, |w| w.write_all(tum.as_bytes()))?;
    let truth = truth_path(&r.path);
    let text = truth_yaml(r, motion, mounting, model, imu_rate)?;
    outputs.write_atomic(&truth, |w| w.write_all(text.as_bytes()))?;
    Ok([r.path.clone(), truth])
}

/// `<reference>.truth.yaml`.
pub fn truth_path(reference: &Path) -> PathBuf {
    let mut s = reference.as_os_str().to_owned();
    s.push(".truth.yaml");
    PathBuf::from(s)
}

fn truth_yaml(
    r: &ReferenceOut,
    motion: Motion,
    m: &Mounting,
    model: &ImuModel,
    rate: f64,
) -> Result<String> {
    let exp = expected_operating(model, rate)?;
    let mat = |x: &nalgebra::Matrix3<f64>| {
        format!(
            "[{}]",
            x.transpose()
                .iter()
                .map(|v| format!("{v:?}"))
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    let mut s = String::from(
        "# sim bag --reference-out: what was injected, and the operating noise density the analysis (allan_kalibr --reference) should find\nformat: sim-reference-truth-1\n",
    );
    let _ = writeln!(s, "motion: {}", motion.name());
    let _ = writeln!(s, "imu_rate_hz: {rate:?}");
    let _ = writeln!(s, "reference_rate_hz: {:?}", r.rate);
    let _ = writeln!(
        s,
        "# the IMU sample stamped t is the reference at t + time_offset"
    );
    let _ = writeln!(s, "time_offset_s: {:?}", r.offset);
    let _ = writeln!(s, "reference_noise_position_m: {:?}", r.noise.0);
    let _ = writeln!(s, "reference_noise_rotation_rad: {:?}", r.noise.1);
    let _ = writeln!(s, "# matrices row-major; rotation IMU -> body");
    let _ = writeln!(s, "rotation_body_from_imu: {}", mat(&m.rotation));
    let _ = writeln!(
        s,
        "lever_arm_m: [{:?}, {:?}, {:?}]",
        m.lever.x, m.lever.y, m.lever.z
    );
    let _ = writeln!(s, "gyro_scale_misalignment: {}", mat(&m.gyro_sm));
    let _ = writeln!(s, "acc_scale_misalignment: {}", mat(&m.acc_sm));
    let _ = writeln!(s, "gyro_g_sensitivity: {}", mat(&m.g_sens));
    let _ = writeln!(
        s,
        "# N_op^2 = white noise's per-sample variance after the chain / f_s + sum of the lines' A^2 / (2 f_s); not counted: random walk, bias instability, Gauss-Markov, warm-up (below the band), quantization Q and LSB"
    );
    for (k, sensor) in ["gyroscope", "accelerometer"].iter().enumerate() {
        let _ = writeln!(
            s,
            "{sensor}_operating_noise_density: [{:?}, {:?}, {:?}]",
            exp[3 * k],
            exp[3 * k + 1],
            exp[3 * k + 2]
        );
    }
    let axes: Vec<&crate::noise::model::AxisModel> = [Sensor::Gyro, Sensor::Acc]
        .iter()
        .flat_map(|x| model.sensor(*x).axes.iter())
        .collect();
    let mut present = Vec::new();
    if axes.iter().any(|a| a.quantization > 0.0) {
        present.push("quantization");
    }
    if axes.iter().any(|a| a.resolution > 0.0) {
        present.push("lsb");
    }
    let _ = writeln!(s, "model_terms_not_counted: [{}]", present.join(", "));
    Ok(s)
}
