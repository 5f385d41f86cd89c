//! C++ iostream number formatting, to write the upstream text layouts byte for byte:
//! the default `%g`-like format with 6 significant digits, and fixed with N decimals
//! (spec §8 item 3). Rust has no `%g`, hence this module.

use std::fmt::Write;

/// Append `x` as C++ `std::ostream << double` prints it with the default precision 6
/// (`%g`: shortest of fixed/scientific, trailing zeros removed, exponent of at least two
/// digits, `-0` kept).
pub fn push_g(out: &mut String, x: f64) {
    push_g_prec(out, x, 6);
}

/// `%g` with `prec` significant digits (prec ≥ 1).
pub fn push_g_prec(out: &mut String, x: f64, prec: usize) {
    if x.is_nan() {
        out.push_str(if x.is_sign_negative() { "-nan" } else { "nan" });
        return;
    }
    if x.is_infinite() {
        out.push_str(if x < 0.0 { "-inf" } else { "inf" });
        return;
    }
    if x == 0.0 {
        out.push_str(if x.is_sign_negative() { "-0" } else { "0" });
        return;
    }
    // Scientific rendering with prec significant digits gives the (rounded) exponent.
    let sci = format!("{:.*e}", prec - 1, x);
    let (mant, exp) = sci
        .split_once('e')
        .expect("Rust's {:e} always has an exponent");
    let exp: i32 = exp.parse().expect("Rust's exponent is an integer");
    if exp < -4 || exp >= prec as i32 {
        out.push_str(strip_zeros(mant));
        out.push('e');
        out.push(if exp < 0 { '-' } else { '+' });
        let _ = write!(out, "{:02}", exp.abs());
    } else {
        let decimals = (prec as i32 - 1 - exp).max(0) as usize;
        let fixed = format!("{:.*}", decimals, x);
        out.push_str(strip_zeros(&fixed));
    }
}

fn strip_zeros(s: &str) -> &str {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        s
    }
}

/// `%g` (6 significant digits) as a new string.
pub fn g(x: f64) -> String {
    let mut s = String::new();
    push_g(&mut s, x);
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_printf_g() {
        // Expected strings are what C's printf("%g") prints (C++ ostream default).
        let cases: &[(f64, &str)] = &[
            (0.0, "0"),
            (-0.0, "-0"),
            (1.0, "1"),
            (20.0, "20"),
            (0.005, "0.005"),
            (1e-5, "1e-05"),
            (-1.2345e-7, "-1.2345e-07"),
            (123456.0, "123456"),
            (1234567.0, "1.23457e+06"),
            (0.0001, "0.0001"),
            (0.00012345678, "0.000123457"),
            (9.81, "9.81"),
            (0.999999, "0.999999"),
            (0.9999995, "1"),
            (19.99965, "19.9996"),
            (-1.48044, "-1.48044"),
            (2.0 * std::f64::consts::PI, "6.28319"),
            (999999.5, "1e+06"),
            (1e100, "1e+100"),
        ];
        for (i, (x, exp)) in cases.iter().enumerate() {
            assert_eq!(g(*x), *exp, "case {i}: x = {x:e}");
        }
    }
}
