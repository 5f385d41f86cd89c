//! Kalibr's `imu.yaml` as kalibr_allan writes it (ethz-asl/kalibr working_directory/imu.yaml
//! layout; docs/upstream/kalibr_allan.md §5, docs/noise_terms.md §2/§4): the four
//! continuous-time values, `rostopic` and `update_rate`, under a header naming the tool, the
//! input ([`crate::consumers::Provenance`]) and where the IEEE 952 file is. The numbers' YAML
//! spelling is [`crate::yaml`]'s.

use std::fmt::Write as _;

use crate::yaml::{key_line, yaml_float, yaml_str};

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
