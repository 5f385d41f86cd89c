//! Kalibr's `imu.yaml` (ethz-asl/kalibr working_directory/imu.yaml layout; docs/upstream/kalibr_allan.md
//! §5, docs/noise_terms.md §2/§4): the four continuous-time values, `rostopic` and `update_rate`.
//!
//! Values are written with the shortest decimal that parses back to the same f64, always
//! with a decimal point so YAML 1.1 readers (PyYAML, which Kalibr uses) see a float; NaN
//! (an empty fit window upstream) is written as `.nan`. The IEEE 952 section's files write
//! their noise values in scientific notation instead ([`yaml_sci`]): the shortest digits
//! that read back to the same f64, a `.` in the mantissa and a signed two-digit exponent
//! (`1.6263488241019355e-08`), the one spelling that YAML 1.1 (PyYAML: `1e-08` and `1.5e3`
//! are strings there), YAML 1.2, OpenCV's `FileStorage` (a real, not an integer) and JSON
//! all read as the same number. A value never runs into its comment ([`key_line`]).

use std::fmt::Write as _;

/// The values that go into imu.yaml.
#[derive(Debug, Clone, PartialEq)]
pub struct ImuYaml {
    /// m/s²/√Hz.
    pub accelerometer_noise_density: f64,
    /// m/s³/√Hz.
    pub accelerometer_random_walk: f64,
    /// rad/s/√Hz.
    pub gyroscope_noise_density: f64,
    /// rad/s²/√Hz.
    pub gyroscope_random_walk: f64,
    /// The IMU topic.
    pub rostopic: String,
    /// Hz.
    pub update_rate: f64,
    /// A sensor the topic does not carry: its keys are left out, and a comment says so.
    pub absent: Option<bag2mat::Sensor>,
}

/// A float as YAML 1.1 reads it back bit-for-bit: shortest round-trip digits, a `.` always
/// present, `.nan` / `.inf` / `-.inf` for non-finite values.
pub(crate) fn yaml_float(x: f64) -> String {
    if x.is_nan() {
        return ".nan".into();
    }
    if x.is_infinite() {
        return if x > 0.0 { ".inf" } else { "-.inf" }.into();
    }
    // Display never uses exponent notation and prints the shortest round-trip digits.
    let s = format!("{x}");
    if s.contains('.') { s } else { format!("{s}.0") }
}

/// A float in scientific notation that YAML 1.1 and 1.2, OpenCV's `FileStorage` and JSON read
/// back bit for bit as a real: the shortest round-trip mantissa with a `.`, then `e`, a sign
/// and at least two exponent digits (`1.0e+02`, `-2.5e-07`); `.nan` / `.inf` / `-.inf` for
/// non-finite values (YAML only: the JSON writer leaves those out).
pub(crate) fn yaml_sci(x: f64) -> String {
    if !x.is_finite() {
        return yaml_float(x);
    }
    // `{:e}` prints the shortest round-trip digits: "1.6263488241019355e-8", "2e2", "0e0"
    let s = format!("{x:e}");
    let (mantissa, exponent) = s.split_once('e').unwrap_or((&s, "0"));
    let e: i32 = exponent.parse().unwrap_or(0);
    let point = if mantissa.contains('.') { "" } else { ".0" };
    let sign = if e < 0 { '-' } else { '+' };
    format!("{mantissa}{point}e{sign}{:02}", e.unsigned_abs())
}

/// A topic string as a YAML plain scalar when safe, otherwise single-quoted.
pub(crate) fn yaml_str(s: &str) -> String {
    let plain = !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "/_-.".contains(c))
        && !s.starts_with(['-', '.']);
    if plain {
        s.to_owned()
    } else {
        format!("'{}'", s.replace('\'', "''"))
    }
}

/// One `key: value   #comment` line of the imu.yaml layout (aligned columns). A value that
/// fills its column still gets a space before the `#`: YAML starts a comment only after
/// whitespace, and `0.000000016263488241019355#Bias …` is one string to PyYAML.
pub(crate) fn key_line(key: &str, value: &str, comment: &str) -> String {
    format!("{:<29}{:<23} #{comment}\n", format!("{key}:"), value)
}

/// What became of the IEEE 952 section's `kalibr_imu_ieee952.yaml` in the run that writes an
/// imu.yaml (its header points the user there only when it exists).
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum SectionFile {
    /// Written beside imu.yaml.
    Written,
    /// Not computed, with the reason (a record that is not static, one too short, …).
    NotComputed(String),
    /// `--compat-only`.
    CompatOnly,
}

impl ImuYaml {
    /// The file text of the kalibr_allan-compatible run: its first line names the tool, its
    /// version, the time and the input (`prov`); then what the numbers are and, as `section`
    /// says, where the IEEE 952 file is or why there is none.
    pub(crate) fn render(
        &self,
        prov: &crate::consumers::Provenance,
        section: &SectionFile,
    ) -> String {
        let first = format!(
            "IMU noise model for Kalibr, written by {} on {} from {}",
            prov.tool, prov.written, prov.input
        );
        let mut lines: Vec<String> = [
            first.as_str(),
            "(rpng/kalibr_allan method: non-overlapping Allan deviation, averaged axes,",
            " -1/2 line read at tau = 1 s, +1/2 line read at tau = 3 s).",
            "These are CONTINUOUS-TIME values (noise densities and random walks);",
            "Kalibr discretises them with update_rate. Values from static data are",
            "optimistic: users commonly inflate them (x10 or more) before use.",
            ".nan means the fit window was empty (Allan minimum too close to the end).",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        match section {
            SectionFile::Written => lines.extend([
                "For Kalibr, prefer kalibr_imu_ieee952.yaml beside this file (the IEEE 952 fit,"
                    .into(),
                "every value within what the data support); this one reproduces kalibr_allan."
                    .into(),
            ]),
            SectionFile::CompatOnly => lines.extend([
                "This run was --compat-only: no kalibr_imu_ieee952.yaml (the IEEE 952 fit, every"
                    .into(),
                "value within what the data support) was written; run without it for that file."
                    .into(),
            ]),
            SectionFile::NotComputed(why) => {
                lines.extend(crate::consumers::render::wrap(&format!(
                    "NO kalibr_imu_ieee952.yaml was written: {why}."
                )));
                lines.push(
                    "The numbers below are kalibr_allan's method applied as it is; they need not be noise figures."
                        .into(),
                );
            }
        }
        let refs: Vec<&str> = lines.iter().map(|s| s.as_str()).collect();
        self.render_with(&refs)
    }

    /// The file text after the given comment lines (each written as `# line`).
    pub(crate) fn render_with(&self, comments: &[&str]) -> String {
        let mut o = String::new();
        for c in comments {
            let _ = writeln!(o, "# {c}");
        }
        let absent = self.absent;
        let w = |o: &mut String, key: &str, v: String, c: &str| {
            let sensor = if key.starts_with("acc") {
                Some(bag2mat::Sensor::Acc)
            } else if key.starts_with("gyro") {
                Some(bag2mat::Sensor::Gyro)
            } else {
                None
            };
            if sensor.is_none() || sensor != absent {
                o.push_str(&key_line(key, &v, c));
            }
        };
        if let Some(s) = absent {
            let _ = writeln!(
                o,
                "# The topic carries no {}: its keys are left out (Kalibr needs all four; take them from another source).",
                s.name()
            );
        }
        if absent != Some(bag2mat::Sensor::Acc) {
            o.push_str("#Accelerometers\n");
        }
        w(
            &mut o,
            "accelerometer_noise_density",
            yaml_float(self.accelerometer_noise_density),
            "Noise density (continuous-time)  [m/s^2/sqrt(Hz)]",
        );
        w(
            &mut o,
            "accelerometer_random_walk",
            yaml_float(self.accelerometer_random_walk),
            "Bias random walk                  [m/s^3/sqrt(Hz)]",
        );
        if absent != Some(bag2mat::Sensor::Gyro) {
            o.push_str("#Gyroscopes\n");
        }
        w(
            &mut o,
            "gyroscope_noise_density",
            yaml_float(self.gyroscope_noise_density),
            "Noise density (continuous-time)  [rad/s/sqrt(Hz)]",
        );
        w(
            &mut o,
            "gyroscope_random_walk",
            yaml_float(self.gyroscope_random_walk),
            "Bias random walk                  [rad/s^2/sqrt(Hz)]",
        );
        w(
            &mut o,
            "rostopic",
            yaml_str(&self.rostopic),
            "the IMU ROS topic",
        );
        w(
            &mut o,
            "update_rate",
            yaml_float(self.update_rate),
            "Hz (for discretization of the values above)",
        );
        o
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn test_prov() -> crate::consumers::Provenance {
        crate::consumers::Provenance {
            tool: "allan_kalibr 0.0.0".into(),
            input: "x.bag".into(),
            written: "2025-01-01T00:00:00Z".into(),
            rate: crate::consumers::RecordRate::Measured(100.0),
        }
    }

    /// Values seen in the reference outputs and edge cases of the formatter.
    const SAMPLES: [f64; 8] = [
        0.032430110313947616,
        0.00014312859628127733,
        8.408017259259696e-5,
        1e-300,
        200.0,
        0.1 + 0.2,
        123456789.0,
        -2.5e-7,
    ];

    #[test]
    fn floats_round_trip_and_have_a_point() {
        for x in SAMPLES {
            let s = yaml_float(x);
            assert!(s.contains('.'), "{s}");
            assert!(!s.contains('e'), "{s}");
            assert_eq!(
                s.parse::<f64>().unwrap().to_bits(),
                x.to_bits(),
                "{x} -> {s}"
            );
        }
        assert_eq!(yaml_float(f64::NAN), ".nan");
        assert_eq!(yaml_float(200.0), "200.0");
    }

    /// A value of 24 characters or more (a navigation-grade random walk in decimal) ran into
    /// its comment (`0.000000016263488241019355#Bias random walk`): YAML starts a comment
    /// only after whitespace, so PyYAML read the value and the comment as one string.
    #[test]
    fn a_long_value_keeps_a_space_before_its_comment() {
        let y = ImuYaml {
            accelerometer_noise_density: 2.0e-3,
            accelerometer_random_walk: 3.0e-5,
            gyroscope_noise_density: 1.7e-5,
            gyroscope_random_walk: 1.6263488241019355e-8,
            rostopic: "/imu".into(),
            update_rate: 200.0,
            absent: None,
        };
        let text = y.render(&test_prov(), &SectionFile::Written);
        let line = text
            .lines()
            .find(|l| l.starts_with("gyroscope_random_walk:"))
            .unwrap();
        let (value, comment) = line.split_once('#').unwrap();
        assert!(
            value.ends_with(char::is_whitespace),
            "no space before the comment: {line}"
        );
        assert_eq!(
            value
                .split_once(':')
                .unwrap()
                .1
                .trim()
                .parse::<f64>()
                .unwrap(),
            1.6263488241019355e-8
        );
        assert!(comment.starts_with("Bias random walk"), "{line}");
    }

    /// PyYAML's YAML 1.1 float pattern (resolver.py): a `.` is required, and an exponent
    /// needs its sign; anything else is read as a string.
    fn yaml11_float(s: &str) -> bool {
        let (mantissa, exp) = match s.split_once(['e', 'E']) {
            Some((m, e)) => (m, Some(e)),
            None => (s, None),
        };
        let m = mantissa.strip_prefix(['-', '+']).unwrap_or(mantissa);
        let digits = |t: &str| t.chars().all(|c| c.is_ascii_digit() || c == '_');
        let mantissa_ok = match m.split_once('.') {
            Some((a, b)) => !a.is_empty() && digits(a) && digits(b),
            None => false,
        };
        let exp_ok = exp.is_none_or(|e| {
            e.len() > 1 && e.starts_with(['-', '+']) && e[1..].chars().all(|c| c.is_ascii_digit())
        });
        mantissa_ok && exp_ok
    }

    /// Values across the range the files carry (1e-12 to 1e3, and the extremes of f64):
    /// each reads back bit for bit, and as a float under YAML 1.1's rules.
    #[test]
    fn scientific_values_round_trip_and_are_yaml_floats() {
        let mut x = 1e-12_f64;
        let mut values = vec![
            0.0,
            -0.0,
            1.0,
            200.0,
            1e3,
            f64::MIN_POSITIVE,
            f64::MAX,
            -2.5e-7,
        ];
        values.extend(SAMPLES);
        while x < 1e3 {
            values.push(x);
            values.push(x * std::f64::consts::PI);
            x *= 7.3;
        }
        for v in values {
            let s = yaml_sci(v);
            assert!(yaml11_float(&s), "{v} -> {s}: not a YAML 1.1 float");
            assert_eq!(
                s.parse::<f64>().unwrap().to_bits(),
                v.to_bits(),
                "{v} -> {s}"
            );
        }
        assert_eq!(yaml_sci(200.0), "2.0e+02");
        assert_eq!(yaml_sci(1.6263488241019355e-8), "1.6263488241019355e-08");
        assert_eq!(yaml_sci(f64::NAN), ".nan");
        assert!(!yaml11_float("1e-08") && !yaml11_float("1.5e3"));
    }

    #[test]
    fn renders_every_kalibr_key_once() {
        let y = ImuYaml {
            accelerometer_noise_density: 0.03,
            accelerometer_random_walk: f64::NAN,
            gyroscope_noise_density: 0.02,
            gyroscope_random_walk: 1e-4,
            rostopic: "/imu/data".into(),
            update_rate: 100.0,
            absent: None,
        };
        let text = y.render(&test_prov(), &SectionFile::Written);
        for key in [
            "accelerometer_noise_density:",
            "accelerometer_random_walk:",
            "gyroscope_noise_density:",
            "gyroscope_random_walk:",
            "rostopic:",
            "update_rate:",
        ] {
            let lines: Vec<&str> = text.lines().filter(|l| l.starts_with(key)).collect();
            assert_eq!(lines.len(), 1, "{key} in\n{text}");
        }
        assert!(text.contains("accelerometer_random_walk:   .nan"));
        assert!(text.contains("rostopic:                    /imu/data"));
        assert!(text.contains("update_rate:                 100.0"));
        assert!(text.to_lowercase().contains("continuous-time"));
        assert!(text.contains("inflate"));
    }
}
