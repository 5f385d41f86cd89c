//! Reading the config files users have, as their consumers read them, for `check`: every
//! `key: value` with its path of parent keys (YAML, also OpenCV's `%YAML:1.0` files), a
//! Basalt calibration JSON, QGroundControl's `.params` (`Vehicle-Id Component-Id Name Value
//! Type`, tab-separated) and ArduPilot's `.param` (`NAME,VALUE` or `NAME VALUE`). Lenient on
//! purpose: a file need not be whole or valid for its noise keys to be found, and a value a
//! consumer would not read as a number is kept with the reason (a `#` right after it, a
//! quoted number, YAML 1.1's `1e-3` that PyYAML reads as a string), for `check` to say.
//! Which consumer a file is for follows from its keys.

use std::collections::BTreeMap;

use super::ConsumerId;

/// One value of a file.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Entry {
    /// The key with its parents, `/`-joined (`imu0/update_rate`, `value0/gyro_noise_std`).
    pub path: String,
    /// The text as written (the first element of a list).
    pub raw: String,
    /// The number, or why the consumer would not read one.
    pub value: Result<f64, String>,
    /// Line number (1-based; 0 for JSON).
    pub line: usize,
}

/// What a file is.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Kind {
    /// A consumer's config.
    Consumer(ConsumerId),
    /// imu_utils' `<name>_imu_param.yaml` (discrete `*_n`, the bias-instability floor as
    /// `*_w`), or this project's continuous reading of it.
    ImuUtils {
        /// `<name>_imu_param_continuous.yaml`.
        continuous: bool,
    },
}

/// A config file read.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct File {
    /// What it is (`None`: no consumer's keys found).
    pub kind: Option<Kind>,
    /// Its values, in file order.
    pub entries: Vec<Entry>,
}

impl File {
    /// The entry at `path`.
    pub(crate) fn get(&self, path: &str) -> Option<&Entry> {
        self.entries.iter().find(|e| e.path == path)
    }
}

/// Reads `text` (file name `name`, for the extension).
pub(crate) fn read(name: &str, text: &str) -> File {
    let trimmed = text.trim_start();
    let entries = if trimmed.starts_with('{') {
        json_entries(text)
    } else if is_qgc_params(text) {
        qgc_entries(text)
    } else if name.ends_with(".param") || is_name_value(text) {
        name_value_entries(text)
    } else {
        yaml_entries(text)
    };
    File {
        kind: kind_of(&entries),
        entries,
    }
}

/// The consumer whose keys the entries hold.
fn kind_of(entries: &[Entry]) -> Option<Kind> {
    let has = |p: &str| entries.iter().any(|e| e.path == p);
    let ends = |p: &str| entries.iter().any(|e| e.path.ends_with(p));
    if entries.iter().any(|e| e.path.starts_with("EKF2_")) {
        return Some(Kind::Consumer(ConsumerId::Px4));
    }
    if entries.iter().any(|e| e.path.starts_with("EK3_")) {
        return Some(Kind::Consumer(ConsumerId::ArduPilot));
    }
    if ends("gyro_noise_std") || ends("accel_noise_std") {
        return Some(Kind::Consumer(ConsumerId::Basalt));
    }
    if has("gyroscopeCovariance") || has("accelerometerCovariance") {
        return Some(Kind::Consumer(ConsumerId::Gtsam));
    }
    if has("IMU.NoiseGyro") || has("IMU.NoiseAcc") {
        return Some(Kind::Consumer(ConsumerId::OrbSlam3));
    }
    if has("Gyr/avg-axis/gyr_n") || has("Acc/avg-axis/acc_n") {
        return Some(Kind::ImuUtils {
            continuous: has("convention"),
        });
    }
    if has("acc_n") || has("gyr_n") {
        return Some(Kind::Consumer(ConsumerId::Vins));
    }
    if has("gyroscope_noise_density") || has("accelerometer_noise_density") {
        return Some(Kind::Consumer(ConsumerId::Kalibr));
    }
    // Kalibr's imu chain (imu0:, imu1: …), as OpenVINS reads it
    if entries
        .iter()
        .any(|e| e.path.starts_with("imu") && e.path.ends_with("/gyroscope_noise_density"))
    {
        return Some(Kind::Consumer(ConsumerId::OpenVins));
    }
    None
}

/// A YAML number as C's `strtod` (OpenCV) reads it, with YAML's `.nan`, `.inf` spellings.
fn number(t: &str) -> Option<f64> {
    match t.to_ascii_lowercase().as_str() {
        ".nan" => return Some(f64::NAN),
        ".inf" | "+.inf" => return Some(f64::INFINITY),
        "-.inf" => return Some(f64::NEG_INFINITY),
        _ => {}
    }
    let ok = !t.is_empty()
        && t.chars()
            .all(|c| c.is_ascii_digit() || matches!(c, '.' | 'e' | 'E' | '+' | '-'));
    if ok { t.parse().ok() } else { None }
}

/// Whether PyYAML (YAML 1.1) reads `t` as a number: an int, or a float with a `.` (and a
/// signed exponent); `1e-3` and `1.5e3` are strings there.
pub(crate) fn yaml11_number(t: &str) -> bool {
    let s = t.strip_prefix(['-', '+']).unwrap_or(t);
    if s.chars().all(|c| c.is_ascii_digit()) && !s.is_empty() {
        return true;
    }
    let (m, e) = match s.split_once(['e', 'E']) {
        Some((m, e)) => (m, Some(e)),
        None => (s, None),
    };
    let digits = |x: &str| x.chars().all(|c| c.is_ascii_digit());
    let mantissa = match m.split_once('.') {
        Some((a, b)) => digits(a) && digits(b) && !(a.is_empty() && b.is_empty()),
        None => false,
    };
    let exp = e.is_none_or(|e| e.len() > 1 && e.starts_with(['-', '+']) && digits(&e[1..]));
    mantissa && exp || matches!(s.to_ascii_lowercase().as_str(), ".nan" | ".inf")
}

/// The value text of a `key: value` line and whether a `#` followed it without whitespace
/// (then YAML reads value and comment as one string).
fn value_text(rest: &str) -> (String, Option<String>) {
    let rest = rest.trim();
    // a comment starts at a `#` at the start or after whitespace, outside quotes
    let mut quote = None;
    let mut prev_space = true;
    for (i, c) in rest.char_indices() {
        match quote {
            Some(q) if c == q => quote = None,
            Some(_) => {}
            None if c == '"' || c == '\'' => quote = Some(c),
            None if c == '#' && prev_space => return (rest[..i].trim().to_string(), None),
            None => {}
        }
        prev_space = c.is_whitespace();
    }
    // no comment; a `#` glued to a value is reported
    if let Some(i) = rest.find('#')
        && quote.is_none()
        && !rest.starts_with(['"', '\''])
    {
        let v = rest[..i].trim().to_string();
        return (
            rest.to_string(),
            Some(format!(
                "the value runs into its comment ({:?}): YAML starts a comment only after a space, so it reads {:?} as one string",
                rest.chars().take(40).collect::<String>(),
                v
            )),
        );
    }
    (rest.to_string(), None)
}

/// Every `key: value` of a YAML text (also OpenCV's), by indentation: a key's path is its
/// parents' keys and its own. A flow list's first number stands for the list (`[[a, 0, 0],
/// …]`: GTSAM's covariances, Basalt's arrays in YAML).
fn yaml_entries(text: &str) -> Vec<Entry> {
    let mut out = Vec::new();
    let mut stack: Vec<(usize, String)> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let body = line.trim_end();
        let t = body.trim_start();
        if t.is_empty()
            || t.starts_with('#')
            || t.starts_with('%')
            || t == "---"
            || t.starts_with("- ")
        {
            continue;
        }
        let indent = body.len() - t.len();
        let Some((key, rest)) = t.split_once(':') else {
            continue;
        };
        if key.contains(' ') && !key.starts_with(['"', '\'']) {
            continue;
        }
        let key = key.trim().trim_matches(['"', '\'']).to_string();
        while stack.last().is_some_and(|(d, _)| *d >= indent) {
            stack.pop();
        }
        let path = stack
            .iter()
            .map(|(_, k)| k.as_str())
            .chain([key.as_str()])
            .collect::<Vec<_>>()
            .join("/");
        let rest = rest.trim();
        if rest.is_empty() || rest.starts_with('#') {
            stack.push((indent, key));
            continue;
        }
        // a tag (!!opencv-matrix) opens a block like an empty value
        if rest.starts_with("!!") {
            stack.push((indent, key));
            continue;
        }
        let (raw, glued) = value_text(rest);
        let first = raw
            .trim_start_matches(['[', ' '])
            .split([',', ']'])
            .next()
            .unwrap_or("")
            .trim()
            .to_string();
        let candidate = if raw.starts_with('[') {
            first
        } else {
            raw.clone()
        };
        let value = match glued {
            Some(why) => Err(why),
            None if candidate.starts_with(['"', '\'']) => Err(format!(
                "{candidate} is quoted: a string, not a number, to every YAML reader"
            )),
            None => number(&candidate).ok_or_else(|| format!("{candidate:?} is not a number")),
        };
        out.push(Entry {
            path,
            raw: candidate,
            value,
            line: i + 1,
        });
    }
    out
}

/// QGroundControl's `.params`: five tab-separated columns on a line that is not a comment.
fn is_qgc_params(text: &str) -> bool {
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .any(|l| l.split('\t').count() == 5)
}

fn qgc_entries(text: &str) -> Vec<Entry> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.starts_with('#'))
        .filter_map(|(i, l)| {
            let c: Vec<&str> = l.trim_end_matches(['\r', '\n']).split('\t').collect();
            (c.len() == 5).then(|| Entry {
                path: c[2].trim().to_string(),
                raw: c[3].trim().to_string(),
                value: number(c[3].trim()).ok_or_else(|| format!("{:?} is not a number", c[3])),
                line: i + 1,
            })
        })
        .collect()
}

/// ArduPilot's `.param` (Mission Planner `NAME,VALUE`, MAVProxy `NAME VALUE`): every
/// non-comment line two fields.
fn is_name_value(text: &str) -> bool {
    let lines: Vec<&str> = text
        .lines()
        .map(|l| l.split('#').next().unwrap_or("").trim())
        .filter(|l| !l.is_empty())
        .collect();
    !lines.is_empty()
        && lines.iter().all(|l| {
            let f: Vec<&str> = l
                .split([',', ' ', '\t'])
                .filter(|f| !f.is_empty())
                .collect();
            f.len() == 2 && !f[0].ends_with(':')
        })
}

fn name_value_entries(text: &str) -> Vec<Entry> {
    text.lines()
        .enumerate()
        .filter_map(|(i, l)| {
            let l = l.split('#').next().unwrap_or("").trim();
            let f: Vec<&str> = l
                .split([',', ' ', '\t'])
                .filter(|f| !f.is_empty())
                .collect();
            (f.len() == 2).then(|| Entry {
                path: f[0].to_string(),
                raw: f[1].to_string(),
                value: number(f[1]).ok_or_else(|| format!("{:?} is not a number", f[1])),
                line: i + 1,
            })
        })
        .collect()
}

/// A JSON value, as far as `check` needs one.
#[derive(Debug)]
enum Json {
    Number(f64),
    Text(String),
    List(Vec<Json>),
    Map(Vec<(String, Json)>),
    Other,
}

impl<'de> serde::Deserialize<'de> for Json {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Json, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Json;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a JSON value")
            }
            fn visit_f64<E>(self, v: f64) -> Result<Json, E> {
                Ok(Json::Number(v))
            }
            fn visit_i64<E>(self, v: i64) -> Result<Json, E> {
                Ok(Json::Number(v as f64))
            }
            fn visit_u64<E>(self, v: u64) -> Result<Json, E> {
                Ok(Json::Number(v as f64))
            }
            fn visit_str<E>(self, v: &str) -> Result<Json, E> {
                Ok(Json::Text(v.to_string()))
            }
            fn visit_bool<E>(self, _: bool) -> Result<Json, E> {
                Ok(Json::Other)
            }
            fn visit_unit<E>(self) -> Result<Json, E> {
                Ok(Json::Other)
            }
            fn visit_none<E>(self) -> Result<Json, E> {
                Ok(Json::Other)
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut a: A) -> Result<Json, A::Error> {
                let mut v = Vec::new();
                while let Some(x) = a.next_element()? {
                    v.push(x);
                }
                Ok(Json::List(v))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, mut a: A) -> Result<Json, A::Error> {
                let mut v = Vec::new();
                while let Some((k, x)) = a.next_entry::<String, Json>()? {
                    v.push((k, x));
                }
                Ok(Json::Map(v))
            }
        }
        d.deserialize_any(V)
    }
}

/// Every number of a JSON text by its path (a list's elements as `key[i]`, its first also
/// as `key`); a JSON text that does not parse gives one entry saying why.
fn json_entries(text: &str) -> Vec<Entry> {
    let doc: Json = match serde_saphyr::from_str(text) {
        Ok(d) => d,
        Err(e) => {
            return vec![Entry {
                path: String::new(),
                raw: String::new(),
                value: Err(format!("not JSON: {e}")),
                line: 0,
            }];
        }
    };
    let mut out = BTreeMap::new();
    fn walk(n: &Json, path: &str, out: &mut BTreeMap<String, Result<f64, String>>) {
        match n {
            Json::Number(x) => {
                out.insert(path.to_string(), Ok(*x));
            }
            Json::Text(s) => {
                out.insert(path.to_string(), Err(format!("{s:?} is a string")));
            }
            Json::List(v) => {
                for (i, x) in v.iter().enumerate() {
                    walk(x, &format!("{path}[{i}]"), out);
                }
                if let Some(Json::Number(x)) = v.first() {
                    out.insert(path.to_string(), Ok(*x));
                }
            }
            Json::Map(m) => {
                for (k, x) in m {
                    let p = if path.is_empty() {
                        k.clone()
                    } else {
                        format!("{path}/{k}")
                    };
                    walk(x, &p, out);
                }
            }
            Json::Other => {}
        }
    }
    walk(&doc, "", &mut out);
    out.into_iter()
        .map(|(path, value)| Entry {
            raw: match &value {
                Ok(x) => format!("{x:e}"),
                Err(_) => String::new(),
            },
            path,
            value,
            line: 0,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_each_format_and_knows_its_consumer() {
        let k = read(
            "imu.yaml",
            "#Accelerometers\naccelerometer_noise_density: 2.0e-03   #Noise density\ngyroscope_random_walk:       0.000000016263488241019355#Bias random walk\nupdate_rate: 200.0\n",
        );
        assert_eq!(k.kind, Some(Kind::Consumer(ConsumerId::Kalibr)));
        assert_eq!(
            k.get("accelerometer_noise_density").unwrap().value,
            Ok(2.0e-3)
        );
        let glued = &k.get("gyroscope_random_walk").unwrap().value;
        assert!(
            glued
                .as_ref()
                .unwrap_err()
                .contains("runs into its comment"),
            "{glued:?}"
        );
        let ov = read(
            "chain.yaml",
            "%YAML:1.0\nimu0:\n  T_i_b:\n    - [1.0, 0.0, 0.0, 0.0]\n  gyroscope_noise_density: 1.0e-04 # x\n  update_rate: 200.0\n",
        );
        assert_eq!(ov.kind, Some(Kind::Consumer(ConsumerId::OpenVins)));
        assert_eq!(ov.get("imu0/update_rate").unwrap().value, Ok(200.0));
        let vins = read(
            "v.yaml",
            "%YAML:1.0\nbody_T_cam0: !!opencv-matrix\n   rows: 4\n   data: [1, 0]\nacc_n: 0.08          # accelerometer\ngyr_w: \"2.0e-5\"\n",
        );
        assert_eq!(vins.kind, Some(Kind::Consumer(ConsumerId::Vins)));
        assert_eq!(vins.get("acc_n").unwrap().value, Ok(0.08));
        assert!(vins.get("gyr_w").unwrap().value.is_err());
        assert_eq!(vins.get("body_T_cam0/rows").unwrap().value, Ok(4.0));
        let px4 = read(
            "p.params",
            "# Onboard parameters\n1\t1\tEKF2_GYR_NOISE\t0.014999999664723873\t9\n",
        );
        assert_eq!(px4.kind, Some(Kind::Consumer(ConsumerId::Px4)));
        assert_eq!(
            px4.get("EKF2_GYR_NOISE")
                .unwrap()
                .value
                .as_ref()
                .map(|x| *x as f32),
            Ok(0.015f32)
        );
        let ap = read("a.param", "# x\nEK3_GYRO_P_NSE,0.015\nEK3_ACC_P_NSE 0.35\n");
        assert_eq!(ap.kind, Some(Kind::Consumer(ConsumerId::ArduPilot)));
        assert_eq!(ap.get("EK3_ACC_P_NSE").unwrap().value, Ok(0.35));
        let b = read(
            "b.json",
            "{\"value0\": {\"gyro_noise_std\": [1e-4, 2e-4, 3e-4], \"imu_update_rate\": 200}}",
        );
        assert_eq!(b.kind, Some(Kind::Consumer(ConsumerId::Basalt)));
        assert_eq!(b.get("value0/gyro_noise_std[2]").unwrap().value, Ok(3e-4));
        let iu = read(
            "x_imu_param.yaml",
            "%YAML:1.0\n---\ntype: IMU\nGyr:\n   unit: \" rad/s\"\n   avg-axis:\n      gyr_n: 2.1e-03\n      gyr_w: 3.0e-05\n",
        );
        assert_eq!(iu.kind, Some(Kind::ImuUtils { continuous: false }));
        assert_eq!(iu.get("Gyr/avg-axis/gyr_w").unwrap().value, Ok(3e-5));
        let g = read(
            "g.yaml",
            "gyroscopeCovariance: [[1.0e-08, 0.0, 0.0], [0.0, 1.0e-08, 0.0], [0.0, 0.0, 1.0e-08]]   # c\n",
        );
        assert_eq!(g.kind, Some(Kind::Consumer(ConsumerId::Gtsam)));
        assert_eq!(g.get("gyroscopeCovariance").unwrap().value, Ok(1e-8));
    }

    #[test]
    fn pyyaml_numbers() {
        for t in ["200", "200.0", "1.0e-03", "-2.5e-07", ".5", "1.", ".nan"] {
            assert!(yaml11_number(t), "{t}");
        }
        for t in ["1e-3", "1.5e3", "2e2", "abc", ""] {
            assert!(!yaml11_number(t), "{t}");
        }
    }
}
