//! Kalibr's `imu.yaml` (ethz-asl/kalibr working_directory/imu.yaml layout; docs/upstream/kalibr_allan.md
//! §5, docs/noise_terms.md §2/§4): the four continuous-time values, `rostopic` and `update_rate`.
//!
//! Values are written with the shortest decimal that parses back to the same f64, always
//! with a decimal point so YAML 1.1 readers (PyYAML, which Kalibr uses) see a float; NaN
//! (an empty fit window upstream) is written as `.nan`.

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

/// One `key: value   #comment` line of the imu.yaml layout (aligned columns).
pub(crate) fn key_line(key: &str, value: &str, comment: &str) -> String {
    format!("{:<29}{:<24}#{comment}\n", format!("{key}:"), value)
}

impl ImuYaml {
    /// The file text of the kalibr_allan-compatible run. `source` (input file name) goes
    /// into a comment.
    pub(crate) fn render(&self, source: &str) -> String {
        let first = format!("IMU noise model for Kalibr, written by allan_kalibr from {source}");
        self.render_with(&[
            &first,
            "(rpng/kalibr_allan method: non-overlapping Allan deviation, averaged axes,",
            " -1/2 line read at tau = 1 s, +1/2 line read at tau = 3 s).",
            "These are CONTINUOUS-TIME values (noise densities and random walks);",
            "Kalibr discretises them with update_rate. Values from static data are",
            "optimistic: users commonly inflate them (x10 or more) before use.",
            ".nan means the fit window was empty (Allan minimum too close to the end).",
            "For Kalibr, prefer kalibr_imu_ieee952.yaml beside this file (the IEEE 952 fit,",
            "every value within what the data support); this one reproduces kalibr_allan.",
        ])
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
        let text = y.render("x.bag");
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
