//! The two yaml files, written in OpenCV `cv::FileStorage` layout (docs/upstream/imu_utils.md §5.3) so that
//! VINS-style loaders (`cv::FileStorage`) read them: `%YAML:1.0`, `---`, 3-space indent,
//! reals as `%.16e` (or `%d.` for exact ints, `.Nan`, `.Inf`), strings bare or quoted by
//! OpenCV's rules.
//!
//! [`YamlMode::Compat`] is upstream's `<name>_imu_param.yaml` byte for byte (quirks 1, 2, 12:
//! discrete `*_n`, curve-floor `*_w`, `" rad/s"` unit strings). [`YamlMode::Continuous`] is
//! `<name>_imu_param_continuous.yaml`: the same fit read correctly (docs/upstream/imu_utils.md §7) —
//! continuous white-noise density |N|, random walk √3·|K| (Kalibr's units), bias instability
//! |B|/0.664 — with the units spelled out.

use std::fmt::Write as _;

use crate::analysis::Analysis;

/// Which reading of the fit a yaml file carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum YamlMode {
    /// Upstream's values and layout.
    Compat,
    /// Continuous-time values with explicit units.
    Continuous,
}

impl YamlMode {
    /// File name for an IMU name.
    pub fn file_name(self, name: &str) -> String {
        match self {
            YamlMode::Compat => format!("{name}_imu_param.yaml"),
            YamlMode::Continuous => format!("{name}_imu_param_continuous.yaml"),
        }
    }
}

/// OpenCV's real format (`icvFloatToString` + YAML emitter): exact ints `%d.`, else `%.16e`.
pub fn real(v: f64) -> String {
    if v.is_nan() {
        return ".Nan".into();
    }
    if v.is_infinite() {
        return if v > 0.0 {
            ".Inf".into()
        } else {
            "-.Inf".into()
        };
    }
    let r = v.round_ties_even();
    if r == v && r >= i32::MIN as f64 && r <= i32::MAX as f64 {
        return format!("{}.", r as i32);
    }
    bag2mat::shared::cfmt::e16(v)
}

/// OpenCV's string rule: bare unless empty, starting with a space, a digit or `+ - .`, or
/// containing a character outside alphanumerics, `_`, space, `-`, `(`, `)`, `/`, `+`, `;`.
pub fn string(s: &str) -> String {
    let first = s.chars().next();
    let needs_quotes = match first {
        None => true,
        Some(c) => {
            c == ' '
                || c.is_ascii_digit()
                || matches!(c, '+' | '-' | '.')
                || s.chars().any(|c| {
                    !(c.is_ascii_alphanumeric()
                        || matches!(c, '_' | ' ' | '-' | '(' | ')' | '/' | '+' | ';'))
                })
        }
    };
    if !needs_quotes {
        return s.to_string();
    }
    let mut q = String::with_capacity(s.len() + 2);
    q.push('"');
    for c in s.chars() {
        if matches!(c, '\\' | '\'' | '"') {
            q.push('\\');
        }
        q.push(c);
    }
    q.push('"');
    q
}

/// Per-axis (first key, second key, …) values of one sensor block.
struct Block<'a> {
    sensor: &'a str,
    unit: String,
    keys: Vec<&'a str>,
    /// values[axis][key], axis = x, y, z.
    values: [Vec<f64>; 3],
}

fn push_block(out: &mut String, b: &Block<'_>) {
    let _ = writeln!(out, "{}:", b.sensor);
    let _ = writeln!(out, "   unit: {}", string(&b.unit));
    let _ = writeln!(out, "   avg-axis:");
    for (k, key) in b.keys.iter().enumerate() {
        let avg = (b.values[0][k] + b.values[1][k] + b.values[2][k]) / 3.0;
        let _ = writeln!(out, "      {key}: {}", real(avg));
    }
    for (a, axis) in ["x-axis", "y-axis", "z-axis"].iter().enumerate() {
        let _ = writeln!(out, "   {axis}:");
        for (k, key) in b.keys.iter().enumerate() {
            let _ = writeln!(out, "      {key}: {}", real(b.values[a][k]));
        }
    }
}

/// What the continuous file (this project's, not upstream's) says besides the fit: `#`
/// lines after its `---` (the tool, version, input and time, caveats) and the record's rate.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Extra {
    /// Comment lines.
    pub comments: Vec<String>,
    /// The record's rate, Hz (the stamps' nominal rate, not imu_utils' mean period).
    pub rate: Option<f64>,
}

/// The yaml text for `mode`: upstream's file as upstream writes it; the continuous one with
/// `extra` (its `update_rate` the record's rate, else imu_utils' own).
pub fn yaml_text(an: &Analysis, name: &str, mode: YamlMode, extra: &Extra) -> String {
    let comments = &extra.comments;
    let mut out = String::from("%YAML:1.0\n---\n");
    if mode == YamlMode::Continuous {
        for c in comments {
            let _ = writeln!(out, "# {c}");
        }
    }
    out.push_str("type: IMU\n");
    let _ = writeln!(out, "name: {}", string(name));
    let blocks = match mode {
        YamlMode::Compat => {
            let v = |base: usize| {
                [0, 1, 2].map(|k| {
                    vec![
                        an.fits[base + k].white_noise(),
                        an.fits[base + k].bias_instability(),
                    ]
                })
            };
            [
                Block {
                    sensor: "Gyr",
                    unit: " rad/s".into(),
                    keys: vec!["gyr_n", "gyr_w"],
                    values: v(0),
                },
                Block {
                    sensor: "Acc",
                    unit: " m/s^2".into(),
                    keys: vec!["acc_n", "acc_w"],
                    values: v(3),
                },
            ]
        }
        YamlMode::Continuous => {
            let _ = writeln!(
                out,
                "convention: \"continuous-time noise densities (Kalibr / OpenVINS / ORB-SLAM3); fit of imu_utils read as |N|, sqrt(3)|K|, |B|/0.664\""
            );
            let _ = writeln!(
                out,
                "update_rate: {}",
                real(extra.rate.unwrap_or(an.axes[0].freq))
            );
            let v = |base: usize| {
                [0, 1, 2].map(|k| {
                    let f = &an.fits[base + k];
                    vec![
                        f.continuous_white_noise(),
                        f.continuous_random_walk(),
                        f.continuous_bias_instability(),
                    ]
                })
            };
            [
                Block {
                    sensor: "Gyr",
                    unit: "gyr_n: rad / s / sqrt(Hz), gyr_w: rad / s^2 / sqrt(Hz), gyr_bias_instability: rad / s".into(),
                    keys: vec!["gyr_n", "gyr_w", "gyr_bias_instability"],
                    values: v(0),
                },
                Block {
                    sensor: "Acc",
                    unit: "acc_n: m / s^2 / sqrt(Hz), acc_w: m / s^3 / sqrt(Hz), acc_bias_instability: m / s^2".into(),
                    keys: vec!["acc_n", "acc_w", "acc_bias_instability"],
                    values: v(3),
                },
            ]
        }
    };
    if let Some(s) = an.absent {
        let _ = writeln!(
            out,
            "# The topic carries no {}: its block is left out.",
            s.name()
        );
    }
    for b in &blocks {
        if b.sensor == "Gyr" && an.present(0) || b.sensor == "Acc" && an.present(3) {
            push_block(&mut out, b);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Examples of docs/upstream/imu_utils.md §5.3 (verified there against OpenCV 4.6).
    #[test]
    fn opencv_number_and_string_rules() {
        assert_eq!(real(0.0), "0.");
        assert_eq!(real(-0.0), "0.");
        assert_eq!(real(1000.0), "1000.");
        assert_eq!(real(0.5), "5.0000000000000000e-01");
        assert_eq!(real(3.0e9), "3.0000000000000000e+09");
        assert_eq!(real(f64::NAN), ".Nan");
        assert_eq!(real(f64::NEG_INFINITY), "-.Inf");
        assert_eq!(string("16448"), "\"16448\"");
        assert_eq!(string("A3"), "A3");
        assert_eq!(string("my imu"), "my imu");
        assert_eq!(string(" rad/s"), "\" rad/s\"");
        assert_eq!(string("a:b"), "\"a:b\"");
        assert_eq!(string(""), "\"\"");
    }

    /// The continuous file's numbers, OpenCV's `%.16e`, read back by OpenCV itself
    /// (`cv2.FileStorage`, what VINS-style loaders use) bit for bit, from 1e-12 to 1e3, with
    /// the file's `#` comment lines after its `---`.
    #[test]
    fn opencv_reads_the_continuous_numbers_from_1e_12_to_1e3() {
        let mut values = vec![1e-12, 1e3, 200.0, 1.0];
        let mut x = 1.3e-12_f64;
        while x < 1e3 {
            values.push(x * std::f64::consts::E);
            x *= 9.7;
        }
        let mut text = String::from("%YAML:1.0\n---\n# a comment line, as the file has\n");
        for (i, v) in values.iter().enumerate() {
            text.push_str(&format!("v{i}: {}\n", real(*v)));
        }
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("c.yaml");
        std::fs::write(&f, text).unwrap();
        let o = std::process::Command::new("/usr/bin/python3")
            .arg("-c")
            .arg(format!(
                "import cv2; fs = cv2.FileStorage('{}', cv2.FILE_STORAGE_READ); print(' '.join(repr(fs.getNode('v%d' % i).real()) for i in range({})))",
                f.display(),
                values.len()
            ))
            .output()
            .expect("python3 with OpenCV (scripts/test.sh installs it)");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let got: Vec<f64> = String::from_utf8_lossy(&o.stdout)
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect();
        assert_eq!(got, values);
    }

    /// Quirk 12: the leading space of upstream's unit strings makes OpenCV quote them.
    #[test]
    fn quirk_12_quoted_unit_strings() {
        assert_eq!(string(" m/s^2"), "\" m/s^2\"");
    }
}
