//! The config files users copy, one renderer per consumer, from [`ConfigValues`] and the
//! file's [`Provenance`]: every file names the input, the tool and version and the time it
//! was written, states each key's unit and what its number is (the consumer's convention,
//! with the source it was read from), the record's rate, and the caveats of its values;
//! numbers are written in scientific notation that reads back bit for bit
//! ([`crate::yaml::yaml_sci`]; float32 for the flight stacks' parameters, which are float32),
//! always with whitespace before a comment. A value a consumer cannot take (no value, or a
//! per-sample form without the record's rate) is left out with a comment saying why, never
//! written as a guess; so is a rate key when the rate is unknown.
//!
//! * Kalibr `imu.yaml` layout (PyYAML), OpenVINS `kalibr_imu_chain.yaml`, VINS and ORB-SLAM3
//!   settings (`%YAML:1.0`, OpenCV `FileStorage`; ORB-SLAM3's `IMU.Frequency` an integer,
//!   which its legacy settings reader requires), Basalt's calibration noise members (JSON,
//!   a fragment to merge into `value0`: cereal looks members up by name, so the `_` members
//!   saying what the file is are ignored), PX4 EKF2 (QGroundControl's `.params`: comment
//!   lines, then `Vehicle-Id Component-Id Name Value Type` tab-separated, type 9 = float),
//!   ArduPilot EKF3 (`.param`, `NAME,VALUE` as Mission Planner writes and MAVProxy /
//!   pymavlink read, comments on lines of their own), GTSAM (YAML with each covariance a 3×3
//!   nested list, for `PreintegrationCombinedParams`' setters).

use std::fmt::Write as _;

use super::SensorValue;
use super::values::{AxisValue, inline_note, key_note};
use super::{ConfigValues, Consumer, ConsumerId, Origin, Provenance, Quantity, consumer};
use crate::yaml::{yaml_float, yaml_sci, yaml_str};

/// Comment lines are wrapped at this width (the text after `# `).
const WRAP: usize = 96;

/// The file for consumer `id` from `v`, written by `prov`; `rostopic` for the consumers that
/// name the topic (Kalibr, OpenVINS).
pub fn render(id: ConsumerId, v: &ConfigValues, prov: &Provenance, rostopic: &str) -> String {
    let c = consumer(id);
    match id {
        ConsumerId::Kalibr => kalibr(c, v, prov, rostopic),
        ConsumerId::OpenVins => openvins(c, v, prov, rostopic),
        ConsumerId::Vins => vins(c, v, prov),
        ConsumerId::OrbSlam3 => orbslam3(c, v, prov),
        ConsumerId::Basalt => basalt(c, v, prov),
        ConsumerId::Px4 => px4(c, v, prov),
        ConsumerId::ArduPilot => ardupilot(c, v, prov),
        ConsumerId::Gtsam => gtsam(c, v, prov),
    }
}

/// `text` wrapped into lines of at most [`WRAP`] characters (a longer word on its own).
pub(crate) fn wrap(text: &str) -> Vec<String> {
    let mut lines = Vec::new();
    let mut line = String::new();
    for w in text.split_whitespace() {
        if !line.is_empty() && line.chars().count() + 1 + w.chars().count() > WRAP {
            lines.push(std::mem::take(&mut line));
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(w);
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}

/// Appends `text` as `# ` comment lines, wrapped.
fn comment(o: &mut String, text: &str) {
    for l in wrap(text) {
        let _ = writeln!(o, "# {l}");
    }
}

/// Appends a file's header lines as comments, wrapped, but the provenance line whole (one
/// line to find and compare: "Written by … on … from …").
fn comments(o: &mut String, lines: &[String], prov: &Provenance) {
    let whole = prov.line();
    for l in lines {
        if *l == whole {
            let _ = writeln!(o, "# {l}");
        } else {
            comment(o, l);
        }
    }
}

/// What each key of `c` holds and how it follows from N and K, one sentence per key.
fn units(c: &Consumer) -> String {
    let keys: Vec<String> = c
        .keys
        .iter()
        .map(|k| {
            format!(
                "{} [{}] = {}",
                k.name,
                k.unit,
                c.form.formula(k.quantity.is_walk())
            )
        })
        .collect();
    format!("Units and convention: {}.", keys.join("; "))
}

/// The consumer-specific sentence on what it does with the numbers.
fn convention(c: &Consumer) -> &'static str {
    match c.id {
        ConsumerId::Kalibr => {
            "CONTINUOUS-TIME noise densities and random walks; Kalibr discretises them with update_rate."
        }
        ConsumerId::OpenVins => {
            "CONTINUOUS-TIME noise densities and random walks, as Kalibr states them; OpenVINS discretises them with each IMU period. T_i_b is identity (the IMU is the body frame)."
        }
        ConsumerId::Vins => {
            "VINS takes PER-SAMPLE standard deviations at the IMU's rate (its comments say \"standard deviation\"; its preintegration adds the noise per sample without a rate): the continuous N and K times sqrt(rate). A Kalibr value put here unconverted makes VINS trust the IMU sqrt(rate) times too much."
        }
        ConsumerId::OrbSlam3 => {
            "CONTINUOUS-TIME values; ORB-SLAM3 discretises them with IMU.Frequency (noise times sqrt(f), walk divided by sqrt(f))."
        }
        ConsumerId::Basalt => {
            "CONTINUOUS-TIME, per axis [x, y, z]: accel_noise_std and gyro_noise_std are noise densities (Basalt's discrete sigma = value * sqrt(imu_update_rate)); accel_bias_std and gyro_bias_std are bias random walks. A fragment: merge these value0 members into the value0 object of your Basalt calibration JSON (cereal looks members up by name, so the members starting with _ are ignored)."
        }
        ConsumerId::Px4 => {
            "PX4's EKF2 takes each as a standard deviation per EKF prediction step (EKF2_PREDICT_US, default 10000 us): the continuous N and K divided by sqrt(0.01 s). With another EKF2_PREDICT_US, scale every value by sqrt(0.01 s / step). PX4's defaults are 5-50x larger: they also cover vibration, clipping and model error; a static record's figures are a lower bound, not a tuning."
        }
        ConsumerId::ArduPilot => {
            "ArduPilot's EKF3 takes each as a standard deviation per EKF step (EKF_TARGET_DT, 12 ms; 12.5 ms on a 400 Hz loop): the continuous N and K divided by sqrt(0.012 s). ArduPilot's defaults are 5-50x larger: they also cover vibration and model error; a static record's figures are a lower bound, not a tuning."
        }
        ConsumerId::Gtsam => {
            "GTSAM's PreintegrationCombinedParams takes continuous-time covariances (the densities squared) and discretises them itself (measurements Sigma/dt, bias random walk Sigma*dt). In Python: p = gtsam.PreintegrationCombinedParams.MakeSharedU(9.81); p.setGyroscopeCovariance(np.array(d['gyroscopeCovariance'])), likewise setAccelerometerCovariance, setBiasOmegaCovariance, setBiasAccCovariance (d = yaml.safe_load of this file). integrationCovariance models the integration's own error, not the IMU's: it is not written."
        }
    }
}

/// The header every file carries, as plain lines (the caller adds its comment marker).
fn header(c: &Consumer, v: &ConfigValues, prov: &Provenance, title: &str) -> Vec<String> {
    let mut h = vec![title.to_string(), prov.line()];
    h.push(match v.origin {
        Origin::Measured if c.id == ConsumerId::Basalt => {
            "Values: the IEEE 952 fit of the overlapping Allan deviation, each axis its own (resolved, else its 95 % upper bound). Static data give optimistic values: inflate before use.".into()
        }
        Origin::Measured => {
            "Values: the IEEE 952 fit of the overlapping Allan deviation, the largest of the three axes. Static data give optimistic values: inflate before use.".into()
        }
        Origin::Datasheet => {
            "Values: FROM A DATASHEET, NOT MEASURED (allan_kalibr plan): what the part is specified to be, not what yours is. Measure it (allan_kalibr on a static record) before trusting them.".into()
        }
    });
    h.push(convention(c).to_string());
    h.push(units(c));
    h.push(format!("Convention read from: {}.", c.sources.join("; ")));
    h.push(prov.rate_line());
    h.extend(v.comments.iter().cloned());
    for k in &c.keys {
        h.extend(key_note(k.name, v.get(k.quantity)));
    }
    h
}

/// The consumer's number for `q`, or why there is none.
fn number(
    c: &Consumer,
    v: &ConfigValues,
    q: Quantity,
    rate: Option<f64>,
) -> Result<(f64, SensorValue), String> {
    let key = c.key(q).name;
    let Some(sv) = v.get(q) else {
        return Err(format!(
            "{key}: left out (no {} figure: {}).",
            q.sensor().name(),
            "the sensor was not analysed, or nothing is known of it"
        ));
    };
    match c.form.from_continuous(sv.value, rate) {
        Some(x) => Ok((x, sv)),
        None => Err(format!(
            "{key}: left out: it is per sample at the IMU's rate, which is unknown (give --rate HZ)."
        )),
    }
}

/// Out-of-range notes for the flight stacks' documented parameter ranges.
fn range_note(c: &Consumer, q: Quantity, x: f64) -> Option<String> {
    let k = c.key(q);
    let (lo, hi) = k.range?;
    (x < lo || x > hi).then(|| {
        format!(
            "{} = {} is outside the range {} documents ({} .. {} {}): its ground station may refuse or clamp it; check the value after loading.",
            k.name,
            f32_text(x),
            c.name,
            lo,
            hi,
            k.unit
        )
    })
}

/// A float32 parameter value: the shortest digits that read back as the same float32.
fn f32_text(x: f64) -> String {
    format!("{:e}", x as f32)
}

fn kalibr(c: &Consumer, v: &ConfigValues, prov: &Provenance, rostopic: &str) -> String {
    let mut o = String::new();
    comments(
        &mut o,
        &header(
            c,
            v,
            prov,
            "IMU noise model for Kalibr (imu.yaml). This is the file to give Kalibr; allan_kalibr's imu.yaml reproduces kalibr_allan's.",
        ),
        prov,
    );
    let rate = prov.rate.hz();
    let labels = [
        "Noise density (continuous-time)  [m/s^2/sqrt(Hz)]",
        "Bias random walk                  [m/s^3/sqrt(Hz)]",
        "Noise density (continuous-time)  [rad/s/sqrt(Hz)]",
        "Bias random walk                  [rad/s^2/sqrt(Hz)]",
    ];
    for (q, label) in Quantity::ALL.into_iter().zip(labels) {
        if q == Quantity::AccNoise {
            o.push_str("#Accelerometers\n");
        }
        if q == Quantity::GyroNoise {
            o.push_str("#Gyroscopes\n");
        }
        match number(c, v, q, rate) {
            Ok((x, sv)) => o.push_str(&crate::yaml::key_line(
                c.key(q).name,
                &yaml_sci(x),
                &format!("{label}{}", inline_note(Some(sv))),
            )),
            Err(why) => comment(&mut o, &why),
        }
    }
    o.push_str(&crate::yaml::key_line(
        "rostopic",
        &yaml_str(rostopic),
        "the IMU ROS topic",
    ));
    match rate {
        Some(r) => o.push_str(&crate::yaml::key_line(
            "update_rate",
            &yaml_float(r),
            "Hz (for discretization of the values above)",
        )),
        None => comment(
            &mut o,
            "update_rate: left out, the record's rate is unknown; Kalibr needs it: add update_rate: <your IMU's rate in Hz>.",
        ),
    }
    o
}

fn openvins(c: &Consumer, v: &ConfigValues, prov: &Provenance, rostopic: &str) -> String {
    let mut o = String::from("%YAML:1.0\n\n");
    comments(
        &mut o,
        &header(c, v, prov, "OpenVINS kalibr_imu_chain.yaml."),
        prov,
    );
    let rate = prov.rate.hz();
    let mut left_out = Vec::new();
    let mut lines = String::new();
    for (q, what) in Quantity::ALL.into_iter().zip([
        "accel white noise",
        "accel bias diffusion",
        "gyro white noise",
        "gyro bias diffusion",
    ]) {
        match number(c, v, q, rate) {
            Ok((x, sv)) => {
                let _ = writeln!(
                    lines,
                    "  {}: {}   # [ {} ] ({what}){}",
                    c.key(q).name,
                    yaml_sci(x),
                    q.unit(),
                    inline_note(Some(sv))
                );
            }
            Err(why) => left_out.push(why),
        }
    }
    for why in &left_out {
        comment(&mut o, why);
    }
    o.push_str("\nimu0:\n  T_i_b:\n");
    for r in 0..4 {
        let row: Vec<&str> = (0..4).map(|c| if r == c { "1.0" } else { "0.0" }).collect();
        let _ = writeln!(o, "    - [{}]", row.join(", "));
    }
    o.push_str(&lines);
    let _ = writeln!(o, "  rostopic: {}", yaml_str(rostopic));
    o.push_str("  time_offset: 0.0\n");
    match rate {
        Some(r) => {
            let _ = writeln!(o, "  update_rate: {}   # [Hz]", yaml_float(r));
        }
        None => o.push_str(
            "  # update_rate: left out, the record's rate is unknown (OpenVINS needs it)\n",
        ),
    }
    o.push_str("  model: \"kalibr\"\n");
    o
}

fn vins(c: &Consumer, v: &ConfigValues, prov: &Provenance) -> String {
    let mut o = String::from("%YAML:1.0\n");
    comments(
        &mut o,
        &header(c, v, prov, "VINS-Mono / VINS-Fusion IMU parameters."),
        prov,
    );
    let rate = prov.rate.hz();
    // VINS' own order and comments (config/euroc/euroc_config.yaml)
    for (q, what) in [
        (
            Quantity::AccNoise,
            "accelerometer measurement noise standard deviation",
        ),
        (
            Quantity::GyroNoise,
            "gyroscope measurement noise standard deviation",
        ),
        (
            Quantity::AccWalk,
            "accelerometer bias random walk noise standard deviation",
        ),
        (
            Quantity::GyroWalk,
            "gyroscope bias random walk noise standard deviation",
        ),
    ] {
        match number(c, v, q, rate) {
            Ok((x, sv)) => {
                let _ = writeln!(
                    o,
                    "{}: {}   # {what} [{}] per sample at {} Hz{}",
                    c.key(q).name,
                    yaml_sci(x),
                    c.key(q).unit,
                    rate.map_or("?".into(), |r| format!("{r}")),
                    inline_note(Some(sv))
                );
            }
            Err(why) => comment(&mut o, &why),
        }
    }
    o.push_str("g_norm: 9.81   # gravity magnitude [m/s^2]\n");
    o
}

fn orbslam3(c: &Consumer, v: &ConfigValues, prov: &Provenance) -> String {
    let mut o = String::from("%YAML:1.0\n");
    comments(
        &mut o,
        &header(c, v, prov, "ORB-SLAM3 IMU noise settings."),
        prov,
    );
    let rate = prov.rate.hz();
    for q in [
        Quantity::GyroNoise,
        Quantity::AccNoise,
        Quantity::GyroWalk,
        Quantity::AccWalk,
    ] {
        match number(c, v, q, rate) {
            Ok((x, sv)) => {
                let _ = writeln!(
                    o,
                    "{}: {}   # [{}]{}",
                    c.key(q).name,
                    yaml_sci(x),
                    c.key(q).unit,
                    inline_note(Some(sv))
                );
            }
            Err(why) => comment(&mut o, &why),
        }
    }
    match rate {
        Some(r) => {
            let f = r.round();
            let note = if f == r {
                String::new()
            } else {
                format!(
                    " (the record's {r} Hz, rounded: ORB-SLAM3's legacy settings reader takes an integer)"
                )
            };
            let _ = writeln!(o, "IMU.Frequency: {}   # [Hz]{note}", f as i64);
        }
        None => comment(
            &mut o,
            "IMU.Frequency: left out, the record's rate is unknown (ORB-SLAM3 needs it, as an integer).",
        ),
    }
    o
}

/// A JSON number (finite; non-finite values are never written).
fn json_num(x: f64) -> String {
    yaml_sci(x)
}

fn json_str(s: &str) -> String {
    let mut o = String::from("\"");
    for ch in s.chars() {
        match ch {
            '"' => o.push_str("\\\""),
            '\\' => o.push_str("\\\\"),
            ch if (ch as u32) < 0x20 => {
                let _ = write!(o, "\\u{:04x}", ch as u32);
            }
            ch => o.push(ch),
        }
    }
    o.push('"');
    o
}

fn basalt(c: &Consumer, v: &ConfigValues, prov: &Provenance) -> String {
    // the provenance and the rate have members of their own
    let head: Vec<String> = header(c, v, prov, "Basalt calibration noise fields.")
        .into_iter()
        .filter(|l| *l != prov.line() && *l != prov.rate_line())
        .collect();
    let mut bounds = Vec::new();
    let mut fields = Vec::new();
    let mut left_out = Vec::new();
    // Basalt's member order: accel_noise_std, gyro_noise_std, accel_bias_std, gyro_bias_std
    for q in [
        Quantity::AccNoise,
        Quantity::GyroNoise,
        Quantity::AccWalk,
        Quantity::GyroWalk,
    ] {
        let k = c.key(q).name;
        match v.axes(q) {
            Some(axes) => {
                for (i, a) in axes.iter().enumerate() {
                    if a.upper_bound {
                        bounds.push(format!("{k}[{i}]: 95 % upper bound"));
                    }
                }
                let vals: Vec<String> =
                    axes.iter().map(|a: &AxisValue| json_num(a.value)).collect();
                fields.push((k, vals.join(", ")));
            }
            None => left_out.push(k),
        }
    }
    let mut o = String::from("{\n  \"value0\": {\n");
    let _ = writeln!(o, "    \"_convention\": {},", json_str(&head.join(" ")));
    let _ = writeln!(o, "    \"_written_by\": {},", json_str(&prov.line()));
    let _ = writeln!(o, "    \"_record_rate\": {},", json_str(&prov.rate_line()));
    if !left_out.is_empty() {
        let _ = writeln!(
            o,
            "    \"_left_out\": {},",
            json_str(&format!(
                "no value for every axis of {}: the merge keeps yours",
                left_out.join(", ")
            ))
        );
    }
    let _ = write!(
        o,
        "    \"_not_resolved\": [{}]",
        bounds
            .iter()
            .map(|b| json_str(b))
            .collect::<Vec<_>>()
            .join(", ")
    );
    if let Some(r) = prov.rate.hz() {
        let _ = write!(o, ",\n    \"imu_update_rate\": {}", json_num(r));
    }
    for (k, vals) in fields {
        let _ = write!(o, ",\n    \"{k}\": [{vals}]");
    }
    o.push_str("\n  }\n}\n");
    o
}

/// A row of a flight stack's parameter file: its key, its value and the notes before it.
type Row = (String, String, Vec<String>);

/// The rows of a flight stack's parameter file, and why a key is left out.
fn parameters(c: &Consumer, v: &ConfigValues, prov: &Provenance) -> (Vec<Row>, Vec<String>) {
    let mut rows = Vec::new();
    let mut left_out = Vec::new();
    for q in Quantity::ALL {
        match number(c, v, q, prov.rate.hz()) {
            Ok((x, _)) => {
                // a bound is said in the header; here what a ground station may do with it
                let notes: Vec<String> = range_note(c, q, x).into_iter().collect();
                rows.push((c.key(q).name.to_string(), f32_text(x), notes));
            }
            Err(why) => left_out.push(why),
        }
    }
    (rows, left_out)
}

fn px4(c: &Consumer, v: &ConfigValues, prov: &Provenance) -> String {
    let mut o = String::new();
    comments(
        &mut o,
        &header(
            c,
            v,
            prov,
            "PX4 EKF2 IMU noise parameters, QGroundControl .params format (load with Parameters > Tools > Load from file): comment lines, then Vehicle-Id, Component-Id, Name, Value, Type (9 = float), tab-separated.",
        ),
        prov,
    );
    let (rows, left_out) = parameters(c, v, prov);
    for why in &left_out {
        comment(&mut o, why);
    }
    o.push_str("#\n# Vehicle-Id Component-Id Name Value Type\n");
    for (k, x, notes) in rows {
        for n in notes {
            comment(&mut o, &n);
        }
        let _ = writeln!(o, "1\t1\t{k}\t{x}\t9");
    }
    o
}

fn ardupilot(c: &Consumer, v: &ConfigValues, prov: &Provenance) -> String {
    let mut o = String::new();
    comments(
        &mut o,
        &header(
            c,
            v,
            prov,
            "ArduPilot EKF3 IMU noise parameters, .param format (NAME,VALUE per line, as Mission Planner writes it; MAVProxy: param load FILE).",
        ),
        prov,
    );
    let (rows, left_out) = parameters(c, v, prov);
    for why in &left_out {
        comment(&mut o, why);
    }
    for (k, x, notes) in rows {
        for n in notes {
            comment(&mut o, &n);
        }
        let _ = writeln!(o, "{k},{x}");
    }
    o
}

fn gtsam(c: &Consumer, v: &ConfigValues, prov: &Provenance) -> String {
    let mut o = String::new();
    comments(
        &mut o,
        &header(
            c,
            v,
            prov,
            "GTSAM PreintegrationCombinedParams IMU covariances.",
        ),
        prov,
    );
    for q in [
        Quantity::GyroNoise,
        Quantity::AccNoise,
        Quantity::GyroWalk,
        Quantity::AccWalk,
    ] {
        match number(c, v, q, prov.rate.hz()) {
            Ok((x, sv)) => {
                let (d, z) = (yaml_sci(x), yaml_sci(0.0));
                let _ = writeln!(
                    o,
                    "{}: [[{d}, {z}, {z}], [{z}, {d}, {z}], [{z}, {z}, {d}]]   # [{}] = {}{}",
                    c.key(q).name,
                    c.key(q).unit,
                    c.form.formula(q.is_walk()),
                    inline_note(Some(sv))
                );
            }
            Err(why) => comment(&mut o, &why),
        }
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::consumers::{CONSUMERS, RecordRate};

    fn prov(rate: RecordRate) -> Provenance {
        Provenance {
            tool: "allan_kalibr 0.0.0".into(),
            input: "x.bag, topic /imu".into(),
            written: "2025-01-01T00:00:00Z".into(),
            rate,
        }
    }

    /// Every comment character starts a comment: preceded by whitespace or at a line start
    /// (YAML's rule), so no value runs into its comment.
    #[test]
    fn every_hash_starts_a_comment() {
        let v = ConfigValues::plain(
            [
                Some(1.2345678901234567e-12),
                Some(9.87654321e-9),
                Some(3.3e-7),
                Some(1e3),
            ],
            Origin::Measured,
        );
        for c in &CONSUMERS {
            if c.id == ConsumerId::Basalt {
                continue;
            }
            let text = render(c.id, &v, &prov(RecordRate::Measured(200.0)), "/imu");
            for l in text.lines() {
                if let Some(i) = l.find('#') {
                    assert!(
                        i == 0 || l[..i].ends_with(char::is_whitespace),
                        "{}: {l}",
                        c.file
                    );
                }
            }
        }
    }

    /// An unknown rate leaves the rate keys and VINS' per-sample values out, saying why.
    #[test]
    fn an_unknown_rate_is_left_out_and_said() {
        let v = ConfigValues::plain(
            [Some(2e-3), Some(3e-5), Some(1.7e-4), Some(2e-6)],
            Origin::Measured,
        );
        let p = prov(RecordRate::Unknown("the curves do not say it".into()));
        let kalibr = render(ConsumerId::Kalibr, &v, &p, "/imu");
        assert!(
            !kalibr.lines().any(|l| l.starts_with("update_rate")),
            "{kalibr}"
        );
        assert!(kalibr.contains("# update_rate: left out"), "{kalibr}");
        let vins = render(ConsumerId::Vins, &v, &p, "/imu");
        assert!(!vins.lines().any(|l| l.starts_with("acc_n")), "{vins}");
        assert!(vins.contains("unknown (give --rate HZ)"), "{vins}");
        let orb = render(ConsumerId::OrbSlam3, &v, &p, "/imu");
        assert!(
            !orb.lines().any(|l| l.starts_with("IMU.Frequency")),
            "{orb}"
        );
        let basalt = render(ConsumerId::Basalt, &v, &p, "/imu");
        assert!(!basalt.contains("\"imu_update_rate\""), "{basalt}");
        // the flight stacks and GTSAM do not need it
        assert!(render(ConsumerId::Px4, &v, &p, "").contains("EKF2_GYR_NOISE\t"));
    }

    #[test]
    fn datasheet_values_say_so() {
        let v = ConfigValues::plain([Some(2e-3), None, Some(1.7e-4), None], Origin::Datasheet);
        for c in &CONSUMERS {
            let text = render(c.id, &v, &prov(RecordRate::Given(100.0)), "/imu");
            assert!(
                text.contains("FROM A DATASHEET, NOT MEASURED"),
                "{}",
                c.file
            );
        }
    }
}
