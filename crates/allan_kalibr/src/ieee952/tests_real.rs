//! The one real-curve study that reads the estimator's internals (the fit grid's thinning,
//! `fit::thin_to_grid`, and the local slopes of the region readings, `region::local_slopes`)
//! and so stays a unit test; the others are in `tests/studies/real.rs`.

use super::curves_in::{self, Options};
use super::{Analysis, Config, analyse_curve};
use bag2mat::Sensor;

/// (folder, record length in s from its launch file, see the folder's README).
const IMUS: [(&str, f64); 3] = [("A3", 7200.0), ("N3", 7200.0), ("BMI160", 12000.0)];

fn analyse_imu_dir(name: &str, duration: f64, cfg: &Config) -> Vec<(Sensor, Analysis)> {
    let c = curves_in::read(
        &[bag2mat::test_tools::testdata()
            .join("real_curves")
            .join(name)],
        &Options {
            duration: Some(duration),
            ..Options::default()
        },
    )
    .unwrap();
    let mut out = Vec::new();
    for s in &c.sensors {
        let basis = s.axes[0].basis(cfg.fit.per_octave);
        for a in &s.axes {
            out.push((s.sensor, analyse_curve(a, cfg, basis.as_ref())));
        }
    }
    out
}

#[test]
#[ignore = "development: local slopes; --ignored --nocapture"]
fn real_curves_slopes() {
    for (name, d) in IMUS {
        for (i, (s, a)) in analyse_imu_dir(name, d, &Config::default())
            .iter()
            .enumerate()
        {
            let ms: Vec<usize> = a.curve.iter().map(|p| p.m).collect();
            let idx = super::fit::thin_to_grid(&ms, 2);
            let tau: Vec<f64> = idx.iter().map(|&k| a.curve[k].tau).collect();
            let dev: Vec<f64> = idx.iter().map(|&k| a.curve[k].adev).collect();
            let sl = super::region::local_slopes(&tau, &dev);
            let line: Vec<String> = tau
                .iter()
                .zip(&sl)
                .map(|(t, s)| format!("{}:{:+.2}", super::short(*t), s))
                .collect();
            println!(
                "{name} {} {}: {}",
                s.name(),
                ["x", "y", "z"][i % 3],
                line.join(" ")
            );
        }
    }
}
