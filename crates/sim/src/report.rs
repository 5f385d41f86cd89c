//! The text the binary prints (kept here so main.rs holds no formatting).

use crate::bag_sim::{BagConfig, BagSummary};
use crate::spline::{
    Fit, SELF_CHECK_ACC_TOL, SELF_CHECK_GYRO_TOL, SELF_CHECK_KNOT_TOL, self_check,
};
use crate::spline_sim::SplineSummary;
use std::fmt::Write;

/// Printed before `sim bag` starts: the model, time range and the noise parameters in both
/// forms.
pub fn bag_header(c: &BagConfig) -> String {
    let n = crate::bag_sim::message_count(c.rate, c.duration);
    format!(
        "sim bag: {} motion, {} Hz, {} s -> {} messages on topic '{}' (frame_id '{}'), start {}.{:09}, format {}, compression {}, seed {}\n{}",
        match c.motion {
            crate::motion::Motion::Static => "static",
            crate::motion::Motion::Ellipse => "ellipse",
        },
        c.rate,
        c.duration,
        n,
        c.topic,
        c.frame_id,
        c.start_ns / 1_000_000_000,
        c.start_ns % 1_000_000_000,
        c.format.name(),
        match c.format {
            crate::bag_sim::BagFormat::Mcap(m) if !m.name().is_empty() => m.name(),
            _ => c.compression.name(),
        },
        c.seed,
        c.model.describe(c.rate)
    )
}

/// Printed when `sim bag` is done.
pub fn bag_done(c: &BagConfig, s: &BagSummary) -> String {
    let t = |r: bag2mat::RosTime| format!("{}.{:09}", r.sec, r.nsec);
    let mut o = format!(
        "wrote {} ({} messages, {} .. {})",
        c.out.display(),
        s.messages,
        t(s.first),
        t(s.last)
    );
    for f in &s.truth {
        o.push_str(&format!("\nwrote {}", f.display()));
    }
    o
}

/// `sim spline` summary.
pub fn spline_summary(s: &SplineSummary) -> String {
    let mut o = String::new();
    let _ = writeln!(
        o,
        "poses: {}, knots: {} every {} s{}",
        s.poses,
        s.knots,
        s.knot_dt,
        if s.resampled {
            " (input resampled: accuracy bounded by the input rate)"
        } else {
            ""
        }
    );
    let _ = writeln!(
        o,
        "fit: {} iterations, max knot residual {:.3e} m / {:.3e} rad",
        s.fit.iterations, s.fit.max_pos_residual, s.fit.max_rot_residual
    );
    let _ = writeln!(
        o,
        "IMU samples: {} (bag: {} messages)",
        s.samples, s.bag.messages
    );
    if let Some((g, a)) = s.model_error {
        let _ = writeln!(
            o,
            "vs analytic model ({} knots trimmed at each end): max |d gyro| {g:.3e} rad/s, max |d acc| {a:.3e} m/s^2",
            crate::spline_sim::TRIM_KNOTS
        );
    }
    for f in &s.files {
        let _ = writeln!(o, "wrote {}", f.display());
    }
    o
}

/// Run the spline self-check (docs/upstream/vio_data_simulation.md §7.5) and format it; returns (text, passed).
pub fn spline_self_check(pose_rate: f64) -> crate::Result<(String, bool)> {
    let c = self_check(pose_rate, Fit::Interp, 10)?;
    let pass = c.max_gyro_err <= SELF_CHECK_GYRO_TOL
        && c.max_acc_err <= SELF_CHECK_ACC_TOL
        && c.max_knot_err < SELF_CHECK_KNOT_TOL;
    let mut o = String::new();
    let _ = writeln!(
        o,
        "spline self-check: analytic ellipse poses at {pose_rate} Hz on [0, 20] s, interp fit, IMU at knot and mid-knot times, 10 knots trimmed at each end"
    );
    let _ = writeln!(o, "  fit iterations      {}", c.fit.iterations);
    let _ = writeln!(
        o,
        "  max knot error      {:.3e}   (limit {SELF_CHECK_KNOT_TOL:e})",
        c.max_knot_err
    );
    let _ = writeln!(
        o,
        "  max |d gyro| rad/s  {:.3e}   (limit {SELF_CHECK_GYRO_TOL:e})",
        c.max_gyro_err
    );
    let _ = writeln!(
        o,
        "  max |d acc| m/s^2   {:.3e}   (limit {SELF_CHECK_ACC_TOL:e})",
        c.max_acc_err
    );
    let _ = writeln!(o, "  instants compared   {}", c.samples);
    let _ = writeln!(o, "  informative (spec 7.5 tiers, same comparison):");
    for (rate, fit, name) in [
        (200.0, Fit::Approx, "approx"),
        (30.0, Fit::Interp, "interp"),
        (10.0, Fit::Interp, "interp"),
    ] {
        let t = self_check(rate, fit, 10)?;
        let _ = writeln!(
            o,
            "    {name:<6} {rate:>5} Hz poses: max |d gyro| {:.3e} rad/s, max |d acc| {:.3e} m/s^2",
            t.max_gyro_err, t.max_acc_err
        );
    }
    let _ = writeln!(o, "{}", if pass { "PASS" } else { "FAIL" });
    Ok((o, pass))
}
