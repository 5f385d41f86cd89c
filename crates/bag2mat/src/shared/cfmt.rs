//! C `printf` number formats that upstream text outputs depend on: `%g` at a given precision
//! (C++ iostream's default float output is `%g` with precision 6; imu_utils writes its curve
//! files with `setprecision(10)`), `%.16e` (OpenCV FileStorage) and glibc's spelling of
//! non-finite values (`-nan` when the sign bit is set, as 0/0 gives on x86). Rust has no
//! `%g`; its `{:e}`/`{:.N}` conversions round exactly like glibc (correctly rounded, ties on
//! the exact binary value), so only the layout is rebuilt here. One module for every crate
//! that writes upstream text.

/// glibc's text for a non-finite value.
fn non_finite(v: f64) -> &'static str {
    match (v.is_nan(), v.is_sign_negative()) {
        (true, true) => "-nan",
        (true, false) => "nan",
        (false, true) => "-inf",
        (false, false) => "inf",
    }
}

/// Appends a C exponent (`e+05`, `e-12`: sign and at least two digits).
fn push_exp(out: &mut String, exp: i32) {
    out.push('e');
    out.push(if exp < 0 { '-' } else { '+' });
    let a = exp.unsigned_abs();
    if a < 10 {
        out.push('0');
    }
    out.push_str(&a.to_string());
}

fn strip_zeros(s: &str) -> &str {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        s
    }
}

/// Appends C `printf("%.{prec}g", v)` (also `std::cout << setprecision(prec) << v`).
pub fn push_g(out: &mut String, v: f64, prec: usize) {
    if !v.is_finite() {
        out.push_str(non_finite(v));
        return;
    }
    if v == 0.0 {
        out.push_str(if v.is_sign_negative() { "-0" } else { "0" });
        return;
    }
    let p = prec.max(1);
    // The exponent X that decides the style is the one of v rounded to p significant digits.
    let sci = format!("{:.*e}", p - 1, v);
    let (mant, exp) = sci.split_once('e').unwrap_or((sci.as_str(), "0"));
    let x: i32 = exp.parse().unwrap_or(0);
    if x < -4 || x >= p as i32 {
        out.push_str(strip_zeros(mant));
        push_exp(out, x);
    } else {
        let fixed = format!("{:.*}", (p as i32 - 1 - x) as usize, v);
        out.push_str(strip_zeros(&fixed));
    }
}

/// C `printf("%.{prec}g", v)` as a new string.
pub fn g(v: f64, prec: usize) -> String {
    let mut s = String::new();
    push_g(&mut s, v, prec);
    s
}

/// iostream's default float output: `%g` with precision 6.
pub fn g6(v: f64) -> String {
    g(v, 6)
}

/// C `printf("%.16e", v)`.
pub fn e16(v: f64) -> String {
    if !v.is_finite() {
        return non_finite(v).to_string();
    }
    let s = format!("{v:.16e}");
    let (mant, exp) = s.split_once('e').unwrap_or((s.as_str(), "0"));
    let mut out = mant.to_string();
    push_exp(&mut out, exp.parse().unwrap_or(0));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Expected strings are what glibc's printf("%g") prints.
    #[test]
    fn g6_matches_printf() {
        let cases: &[(f64, &str)] = &[
            (0.0, "0"),
            (-0.0, "-0"),
            (1.0, "1"),
            (0.005, "0.005"),
            (1e-5, "1e-05"),
            (-1.2345e-7, "-1.2345e-07"),
            (123456.0, "123456"),
            (123456.4, "123456"),
            (1234567.0, "1.23457e+06"),
            (0.00012345678, "0.000123457"),
            (0.9999995, "1"),
            (19.99965, "19.9996"),
            (2.0 * std::f64::consts::PI, "6.28319"),
            (999999.5, "1e+06"),
            (1e100, "1e+100"),
            (1.6e9, "1.6e+09"),
            (14.000083333, "14.0001"),
            (f64::NAN, "nan"),
            (-f64::NAN, "-nan"),
            (f64::NEG_INFINITY, "-inf"),
        ];
        for (i, (x, want)) in cases.iter().enumerate() {
            assert_eq!(g6(*x), *want, "case {i}: x = {x:e}");
        }
    }

    // Reference values are quoted as upstream's %.17g dumps print them.
    #[allow(clippy::excessive_precision)]
    #[test]
    fn g10_and_e16_match_printf() {
        assert_eq!(g(0.0050000000006811922, 10), "0.005000000001");
        assert_eq!(g(87486.696734, 10), "87486.69673");
        assert_eq!(g(7653922105.2832031, 10), "7653922105");
        assert_eq!(g(76539221051.2832031, 10), "7.653922105e+10");
        assert_eq!(e16(0.41388663882331872), "4.1388663882331872e-01");
        assert_eq!(e16(3.0e9), "3.0000000000000000e+09");
        assert_eq!(e16(-1.5e-300), "-1.5000000000000001e-300");
    }
}
