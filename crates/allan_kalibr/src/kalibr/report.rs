//! The text `SCRIPT_process_results.m` prints (docs/upstream/kalibr_allan.md §3.2), line for line, with
//! MATLAB's `fprintf` spelling of non-finite values (`NaN`, `Inf`, `-Inf`, not C's `nan`).

use super::chart_fit::ChartFit;

/// MATLAB `fprintf('%.<prec>f', x)`: fixed notation, `NaN` / `Inf` / `-Inf` when not finite.
pub(crate) fn matlab_fixed(x: f64, prec: usize) -> String {
    if x.is_nan() {
        "NaN".to_owned()
    } else if x.is_infinite() {
        if x > 0.0 { "Inf" } else { "-Inf" }.to_owned()
    } else {
        // Rust rounds the exact binary value half-to-even like glibc's printf.
        format!("{x:.prec$}")
    }
}

/// The four lines gen_chart prints for one sensor, in upstream order.
pub fn chart_lines(fit: &ChartFit) -> [String; 4] {
    [
        format!(
            "tau = {} | tauid1 = {}",
            matlab_fixed(fit.tau_at1, 2),
            fit.tauid1
        ),
        format!(
            "h_fit1 slope = {} | y-intercept = {}",
            matlab_fixed(-0.5, 4),
            matlab_fixed(fit.c1, 4)
        ),
        format!(
            "h_fit2 slope = {} | y-intercept = {}",
            matlab_fixed(0.5, 4),
            matlab_fixed(fit.c2, 4)
        ),
        format!(
            "tau = {} | tauid2 = {}",
            matlab_fixed(fit.tau_at2, 2),
            fit.tauid2
        ),
    ]
}

/// The four `name = value` lines of `=> final results` (`%.8f`).
pub fn final_lines(accel: &ChartFit, gyro: &ChartFit) -> [String; 4] {
    [
        format!(
            "accelerometer_noise_density = {}",
            matlab_fixed(accel.white, 8)
        ),
        format!(
            "accelerometer_random_walk   = {}",
            matlab_fixed(accel.bias, 8)
        ),
        format!(
            "gyroscope_noise_density     = {}",
            matlab_fixed(gyro.white, 8)
        ),
        format!(
            "gyroscope_random_walk       = {}",
            matlab_fixed(gyro.bias, 8)
        ),
    ]
}

/// The whole printed text of SCRIPT_process_results.m (interpreter warnings excluded), for a
/// topic that may lack a sensor: the absent sensor's chart and final lines are replaced by
/// one line saying it is absent (no figures for it).
pub(crate) fn full_text_of(
    accel: &ChartFit,
    gyro: &ChartFit,
    absent: Option<bag2mat::Sensor>,
) -> String {
    use bag2mat::Sensor;
    let absent_line =
        |s: Sensor| format!("=> {}: absent from this topic (not analysed)\n", s.name());
    let mut out = String::from("=> opening the mat file.\n");
    for (sensor, fit, what) in [
        (Sensor::Acc, accel, "accelerometer"),
        (Sensor::Gyro, gyro, "gyroscope"),
    ] {
        if absent == Some(sensor) {
            out.push_str(&absent_line(sensor));
            continue;
        }
        out.push_str(&format!("=> plotting {what}.\n"));
        for l in chart_lines(fit) {
            out.push_str(&l);
            out.push('\n');
        }
    }
    out.push_str("=> final results\n");
    for (k, l) in final_lines(accel, gyro).into_iter().enumerate() {
        let sensor = if k < 2 { Sensor::Acc } else { Sensor::Gyro };
        if absent != Some(sensor) {
            out.push_str(&l);
            out.push('\n');
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matlab_spelling_of_non_finite() {
        assert_eq!(matlab_fixed(f64::NAN, 8), "NaN");
        assert_eq!(matlab_fixed(f64::INFINITY, 4), "Inf");
        assert_eq!(matlab_fixed(f64::NEG_INFINITY, 4), "-Inf");
        assert_eq!(matlab_fixed(-0.5, 4), "-0.5000");
        assert_eq!(matlab_fixed(0.000143128596, 8), "0.00014313");
        assert_eq!(matlab_fixed(2.995, 2), "3.00"); // 2.995 is 2.99500000000000010658…
        assert_eq!(matlab_fixed(2.985, 2), "2.98"); // 2.985 is 2.98499999999999987566…
    }
}
