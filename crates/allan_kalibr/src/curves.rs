//! `allan_curves.csv`: `tau1`, the six `sig2` curves (as `ref_curves.csv` of the reference)
//! and the two axis averages `gen_chart` fits, one row per grid point, values in shortest
//! round-trip form, `NaN` for the m = 0 points.

use std::io::Write;

/// Header of the CSV (the reference's seven columns, then the two averages).
pub const HEADER: &str = "tau1,ax,ay,az,wx,wy,wz,acc_avg,gyro_avg";

/// A float in the CSV: shortest round-trip digits, `NaN`/`Inf`/`-Inf` like the reference.
pub fn csv_float(x: f64) -> String {
    if x.is_nan() {
        "NaN".into()
    } else if x.is_infinite() {
        if x > 0.0 { "Inf" } else { "-Inf" }.into()
    } else if x != 0.0 && (x.abs() < 1e-5 || x.abs() >= 1e16) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// Writes the CSV.
pub fn write_csv(
    w: &mut dyn Write,
    tau1: &[f64],
    sig2: &[Vec<f64>; 6],
    acc_avg: &[f64],
    gyro_avg: &[f64],
) -> std::io::Result<()> {
    writeln!(w, "{HEADER}")?;
    for i in 0..tau1.len() {
        let mut row = csv_float(tau1[i]);
        for c in sig2.iter().map(|c| c[i]).chain([acc_avg[i], gyro_avg[i]]) {
            row.push(',');
            row.push_str(&csv_float(c));
        }
        writeln!(w, "{row}")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_round_trip() {
        for x in [
            0.0,
            0.005,
            1.2345678901234567e-7,
            3.0000000000000004,
            89999.0,
            0.1,
        ] {
            let s = csv_float(x);
            assert_eq!(
                s.parse::<f64>().unwrap().to_bits(),
                x.to_bits(),
                "{x} -> {s}"
            );
        }
        assert_eq!(csv_float(f64::NAN), "NaN");
        assert_eq!(csv_float(0.0), "0");
    }
}
