//! The analysis' printed report: what was read and estimated, per axis the operating
//! density with its interval, the static value, the ratio and the breakdown, the lines,
//! the phases, what cannot be separated, and how much to inflate.

use std::fmt::Write as _;

use super::Operating;
use super::files::alias;

/// `x` with 3 significant digits in scientific notation (NaN as "-").
fn e(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.3e}")
    } else {
        "-".into()
    }
}

/// The report.
pub(crate) fn text(op: &Operating) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "=> Operating noise: the noise the estimator will see, continuous time, {} Hz, {} samples ({:.1} s){}",
        op.rate,
        op.samples,
        op.samples as f64 / op.rate,
        if op.reference.is_some() {
            ", against a reference trajectory"
        } else {
            ", from the signal alone (no reference)"
        }
    );
    if let Some(r) = &op.reference {
        let c = &r.calibration;
        let _ = writeln!(
            s,
            "   reference: {}, {} poses every {:.2} ms; its noise {:.2e} m, {:.2e} rad; spline knots every {:.2} ms ({})",
            r.what,
            r.poses,
            r.pose_dt * 1e3,
            r.noise.0,
            r.noise.1,
            r.knot_dt * 1e3,
            if r.knot_given {
                "given".to_string()
            } else {
                format!(
                    "chosen for the widest clean band; the spline's estimated error leaves the residual clean from {}",
                    r.candidates
                        .iter()
                        .map(|(h, f)| format!("{f:.2} Hz at {:.1} ms", h * 1e3))
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            }
        );
        if c.dt_observable {
            let _ = writeln!(
                s,
                "   time offset: {:+.3} ms ± {:.3} ms (the IMU sample stamped t is the reference at t + offset)",
                c.dt * 1e3,
                1.96 * c.dt_se * 1e3
            );
        } else {
            let _ = writeln!(
                s,
                "   time offset: not observable (the reference does not turn); taken as 0"
            );
        }
        let rg = super::reference::polar(&c.a_g);
        let angle = crate::spline::so3::log(&rg).norm();
        let _ = writeln!(
            s,
            "   IMU-to-reference rotation: {:.3}°; lever arm [{:.4}, {:.4}, {:.4}] m; gravity in the reference world [{:.3}, {:.3}, {:.3}] m/s²",
            angle.to_degrees(),
            c.lever.x,
            c.lever.y,
            c.lever.z,
            c.gravity_w.x,
            c.gravity_w.y,
            c.gravity_w.z
        );
        for (name, a, se) in [("gyro", &c.a_g, &c.a_g_se), ("acc", &c.a_a, &c.a_a_se)] {
            let sm = a * super::reference::polar(a).transpose() - nalgebra::Matrix3::identity();
            let excited = (0..9).all(|k| {
                super::calibrate::Calibration::excited(se[k], super::calibrate::PRIOR_SCALE)
            });
            if excited {
                let _ = writeln!(
                    s,
                    "   {name} scale [{:+.3} {:+.3} {:+.3}] %, misalignment [{:+.3} {:+.3} {:+.3}] mrad (± {:.3} %)",
                    100.0 * sm[(0, 0)],
                    100.0 * sm[(1, 1)],
                    100.0 * sm[(2, 2)],
                    1e3 * sm[(0, 1)],
                    1e3 * sm[(0, 2)],
                    1e3 * sm[(1, 2)],
                    196.0 * se.max()
                );
            } else {
                let _ = writeln!(
                    s,
                    "   {name} scale and misalignment: not excited by this motion (not estimated)"
                );
            }
        }
        let _ = writeln!(
            s,
            "   biases: knots every {:.1} s; residual per sample: gyro {}, acc {}; IMU stamp jitter {:.1} µs",
            c.bias_knot,
            e(c.sigma[0]),
            e(c.sigma[1]),
            r.jitter * 1e6
        );
    } else {
        let edge = |k: usize| op.motion_edge[k].map_or("-".into(), |v| format!("{v:.2} Hz"));
        let _ = writeln!(
            s,
            "   motion band (from the signal): gyro up to {}, acc up to {}",
            edge(0),
            edge(1)
        );
    }
    let _ = writeln!(s, "   static value: {}", op.static_source);
    for a in &op.axes {
        let b = &a.band;
        let lab = a.sensor.axis_label(a.axis);
        let st = a.static_n.map_or("-".into(), |v| {
            if v.bound {
                format!("< {}", e(v.value))
            } else {
                e(v.value)
            }
        });
        let ratio = a.ratio().map_or("-".into(), |(r, lo, hi)| {
            format!("{r:.2} [{lo:.2}, {hi:.2}]")
        });
        let _ = writeln!(
            s,
            "{lab:<7} N_op {} {} [95 %: {}, {}]  static {}  ratio {ratio}  band {:.2} – {:.1} Hz",
            e(b.n),
            a.sensor.n_unit(),
            e(b.lo),
            e(b.hi),
            st,
            b.band.0,
            b.band.1
        );
        let mut parts = format!("{:<7} floor {}, lines {}", "", e(b.floor_n), e(b.lines_n));
        if op.reference.is_some() {
            let _ = write!(
                parts,
                ", spline error {} (taken out), motion-correlated {} and time offset {} (calibrated away: what they add if not estimated), stamp jitter {}",
                e(b.spline_n),
                e(a.motion_n),
                e(a.offset_n),
                e(a.jitter_n)
            );
        }
        let _ = writeln!(s, "{parts}");
        let lines: Vec<String> = b
            .lines
            .iter()
            .filter(|l| l.in_band)
            .take(4)
            .map(|l| {
                let al = alias(l.line.frequency, op.estimator_rate).map_or(String::new(), |f| {
                    format!(", aliases to {f:.2} Hz at {} Hz", op.estimator_rate)
                });
                format!(
                    "{:.3} Hz A {} (adds {}{al})",
                    l.line.frequency,
                    e(l.line.amplitude),
                    e(l.density)
                )
            })
            .collect();
        if !lines.is_empty() {
            let _ = writeln!(s, "{:<7} lines: {}", "", lines.join("; "));
        }
    }
    if !op.phases.is_empty() {
        let _ = writeln!(s, "phases:");
        for (k, p) in op.phases.iter().enumerate() {
            let worst = p
                .axes
                .iter()
                .filter(|a| a.n.0.is_finite())
                .map(|a| format!("{} {}", a.sensor.axis_code(a.axis), e(a.n.0)))
                .collect::<Vec<_>>()
                .join(", ");
            let lines: Vec<String> = p
                .axes
                .iter()
                .flat_map(|a| a.lines.iter().map(|l| format!("{:.1} Hz", l.0)))
                .collect::<std::collections::BTreeSet<_>>()
                .into_iter()
                .take(6)
                .collect();
            let _ = writeln!(
                s,
                "  {:>2} {:<9} {:>8.1} – {:>8.1} s  N_op: {}{}",
                k + 1,
                p.kind.name(),
                p.start as f64 / op.rate,
                p.end as f64 / op.rate,
                if worst.is_empty() { "-".into() } else { worst },
                if lines.is_empty() {
                    String::new()
                } else {
                    format!("; lines {}", lines.join(", "))
                }
            );
        }
    }
    let _ = writeln!(s, "what this analysis cannot separate:");
    for c in &op.cannot_separate {
        let _ = writeln!(s, "  - {c}");
    }
    for n in &op.notes {
        let _ = writeln!(s, "note: {n}");
    }
    // how much to inflate: the largest axis per sensor, as the files carry it
    for sensor in [bag2mat::Sensor::Gyro, bag2mat::Sensor::Acc] {
        let best = op
            .axes
            .iter()
            .filter(|a| a.sensor == sensor)
            .max_by(|x, y| x.band.n.total_cmp(&y.band.n));
        let Some(a) = best else { continue };
        let st = op
            .axes
            .iter()
            .filter(|x| x.sensor == sensor)
            .filter_map(|x| x.static_n.map(|v| v.value))
            .fold(f64::NAN, f64::max);
        if st.is_finite() {
            let _ = writeln!(
                s,
                "inflate: {} noise density ×{:.2} (operating {} / static {} {})",
                sensor.name(),
                a.band.n / st,
                e(a.band.n),
                e(st),
                sensor.n_unit()
            );
        } else {
            let _ = writeln!(
                s,
                "operating {} noise density {} {} (no static value to compare with)",
                sensor.name(),
                e(a.band.n),
                sensor.n_unit()
            );
        }
    }
    if op.operating_an.is_some() {
        s.push_str("for the estimator: operating_kalibr_imu_ieee952.yaml (and the VINS, ORB-SLAM3, OpenVINS, Basalt files) carry the operating values as they are\n");
    }
    s
}
