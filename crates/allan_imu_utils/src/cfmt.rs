//! C/iostream number formats that upstream's output depends on: `%g` with a given precision
//! (iostream's default float format, precision 6, and `setprecision(10)` for the curve files),
//! `%.16e` (OpenCV FileStorage) and glibc's spelling of NaN/inf (`-nan` when the sign bit is
//! set, as 0/0 produces on x86). Rust's formatter rounds exactly like glibc (correctly rounded
//! decimal conversion, ties to even on the exact binary value), so only the layout is rebuilt.

/// glibc's text for a non-finite value (`nan`, `-nan`, `inf`, `-inf`).
fn non_finite(v: f64) -> &'static str {
    match (v.is_nan(), v.is_sign_negative()) {
        (true, true) => "-nan",
        (true, false) => "nan",
        (false, true) => "-inf",
        (false, false) => "inf",
    }
}

/// Splits Rust's `{:.*e}` output (`d.ddde-5`) into mantissa and decimal exponent.
fn sci_parts(v: f64, decimals: usize) -> (String, i32) {
    let s = format!("{:.*e}", decimals, v);
    let (mant, exp) = s.split_once('e').unwrap_or((s.as_str(), "0"));
    (mant.to_string(), exp.parse().unwrap_or(0))
}

/// Appends a C exponent (`e+05`, `e-12`, at least two digits).
fn push_exp(out: &mut String, exp: i32) {
    out.push('e');
    out.push(if exp < 0 { '-' } else { '+' });
    let a = exp.unsigned_abs();
    if a < 10 {
        out.push('0');
    }
    out.push_str(&a.to_string());
}

fn strip_trailing_zeros(s: &mut String) {
    if s.contains('.') {
        while s.ends_with('0') {
            s.pop();
        }
        if s.ends_with('.') {
            s.pop();
        }
    }
}

/// C `printf("%.{prec}g", v)`, which is also what `std::cout << v` prints with
/// `setprecision(prec)` and the default float field.
pub fn g(v: f64, prec: usize) -> String {
    if !v.is_finite() {
        return non_finite(v).to_string();
    }
    let p = prec.max(1);
    if v == 0.0 {
        return if v.is_sign_negative() {
            "-0".into()
        } else {
            "0".into()
        };
    }
    // The exponent X is the one of the value rounded to p significant digits.
    let (mant, x) = sci_parts(v, p - 1);
    if x < -4 || x >= p as i32 {
        let mut m = mant;
        strip_trailing_zeros(&mut m);
        push_exp(&mut m, x);
        m
    } else {
        let decimals = (p as i32 - 1 - x) as usize;
        let mut s = format!("{:.*}", decimals, v);
        strip_trailing_zeros(&mut s);
        s
    }
}

/// iostream default: `%g` with precision 6.
pub fn g6(v: f64) -> String {
    g(v, 6)
}

/// C `printf("%.16e", v)` for finite values (NaN/inf use glibc spelling).
pub fn e16(v: f64) -> String {
    if !v.is_finite() {
        return non_finite(v).to_string();
    }
    let (mut mant, x) = sci_parts(v, 16);
    push_exp(&mut mant, x);
    mant
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn g6_matches_iostream_examples_from_the_reference_stdout() {
        let cases: &[(f64, &str)] = &[
            (1.6e9, "1.6e+09"),
            (200.0, "200"),
            (0.005, "0.005"),
            (840.005, "840.005"),
            (14.000083333, "14.0001"),
            (0.2333347, "0.233335"),
            (2.47693e-05, "2.47693e-05"),
            (-0.0566799, "-0.0566799"),
            (6170.48, "6170.48"),
            (1000000.0, "1e+06"),
            (999999.5, "1e+06"),
            (123456.4, "123456"),
            (0.0001, "0.0001"),
            (0.00001, "1e-05"),
            (f64::NAN, "nan"),
            (-f64::NAN, "-nan"),
            (0.0, "0"),
        ];
        for (v, want) in cases {
            assert_eq!(g6(*v), *want, "value {v:e}");
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
