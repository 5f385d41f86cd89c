//! `allan_curves.csv`: `tau1`, the six `sig2` curves (as `ref_curves.csv` of the reference)
//! and the two axis averages `gen_chart` fits, one row per grid point, values in shortest
//! round-trip form, `NaN` for the m = 0 points.

use std::io::Write;

/// Header of the CSV (the reference's seven columns, then the two averages).
pub const HEADER: &str = "tau1,ax,ay,az,wx,wy,wz,acc_avg,gyro_avg";

/// A float in the CSV: shortest round-trip digits, `NaN`/`Inf`/`-Inf` like the reference.
pub(crate) fn csv_float(x: f64) -> String {
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

/// Writes the CSV for a topic that may lack a sensor: that sensor's three columns and its
/// average are left out (the others keep their names, so readers by name still work).
pub(crate) fn write_csv_of(
    w: &mut dyn Write,
    tau1: &[f64],
    sig2: &[Vec<f64>; 6],
    acc_avg: &[f64],
    gyro_avg: &[f64],
    absent: Option<bag2mat::Sensor>,
) -> std::io::Result<()> {
    use bag2mat::Sensor;
    let names: Vec<&str> = HEADER.split(',').collect();
    // column k of the header (after tau1): ax ay az wx wy wz acc_avg gyro_avg
    let sensor_of = |k: usize| match k {
        0..=2 | 6 => Sensor::Acc,
        _ => Sensor::Gyro,
    };
    let cols: Vec<usize> = (0..8).filter(|&k| Some(sensor_of(k)) != absent).collect();
    let mut head = String::from(names[0]);
    for &k in &cols {
        head.push(',');
        head.push_str(names[k + 1]);
    }
    writeln!(w, "{head}")?;
    for i in 0..tau1.len() {
        let mut row = csv_float(tau1[i]);
        for &k in &cols {
            let v = match k {
                0..=5 => sig2[k][i],
                6 => acc_avg[i],
                _ => gyro_avg[i],
            };
            row.push(',');
            row.push_str(&csv_float(v));
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
