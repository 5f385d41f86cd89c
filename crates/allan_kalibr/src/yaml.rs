//! YAML as every file of this crate spells it (imu.yaml, the IEEE 952 files, the consumers'
//! configs; docs/upstream/kalibr_allan.md §5, docs/noise_terms.md §2/§4).
//!
//! Values are written with the shortest decimal that parses back to the same f64, always
//! with a decimal point so YAML 1.1 readers (PyYAML, which Kalibr uses) see a float; NaN
//! (an empty fit window upstream) is written as `.nan`. The IEEE 952 section's files write
//! their noise values in scientific notation instead ([`yaml_sci`]): the shortest digits
//! that read back to the same f64, a `.` in the mantissa and a signed two-digit exponent
//! (`1.6263488241019355e-08`), the one spelling that YAML 1.1 (PyYAML: `1e-08` and `1.5e3`
//! are strings there), YAML 1.2, OpenCV's `FileStorage` (a real, not an integer) and JSON
//! all read as the same number. A value never runs into its comment ([`key_line`]).
//!
//! A leaf: the files' writers (`crate::kalibr::imu_yaml`, `crate::consumers`) use it, it
//! uses none of them.

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
}
