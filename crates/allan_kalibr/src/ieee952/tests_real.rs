//! Real-IMU curves (`testdata/real_curves`: DJI A3, DJI N3, Bosch BMI160, written by
//! imu_utils from 2–3.3 h static recordings).

use super::curves_in::{self, Options};
use super::imu::Sensor;
use super::{Analysis, Config, analyse_curve};

pub(super) const REAL: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../testdata/real_curves");

/// (folder, record length in s from its launch file, see the folder's README).
pub(super) const IMUS: [(&str, f64); 3] = [("A3", 7200.0), ("N3", 7200.0), ("BMI160", 12000.0)];

pub(super) fn analyse_imu_dir(name: &str, duration: f64, cfg: &Config) -> Vec<(Sensor, Analysis)> {
    let c = curves_in::read(
        &[std::path::PathBuf::from(format!("{REAL}/{name}"))],
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

pub(super) fn print_row(imu: &str, sensor: Sensor, axis: usize, a: &Analysis) {
    let f = a.fit.as_ref();
    let t = |x: &super::Term| {
        format!(
            "{:.3e} [{:.2e},{:.2e}] {:?}",
            x.value, x.lo, x.hi, x.verdict
        )
    };
    let r = |x: Option<super::region::Reading>| {
        x.map_or("-".into(), |x| {
            format!("{:.3e} [{:.2e},{:.2e}] {:?}", x.value, x.lo, x.hi, x.kind)
        })
    };
    println!(
        "{imu:6} {:4} {}: {} | range {:?} chi2/dof {:.3} delta {:.4} misfit {:.3} pts {}\n      N {}\n      B {}\n      K {}\n      Q {}  R {}\n      region N {}  B {}  K {}",
        sensor.name(),
        ["x", "y", "z"][axis],
        a.verdict,
        f.map(|f| f.tau_range),
        f.map_or(f64::NAN, |f| f.chi2_per_dof),
        f.map_or(f64::NAN, |f| f.delta),
        f.map_or(f64::NAN, |f| f.max_misfit),
        f.map_or(0, |f| f.points),
        t(&a.terms.n),
        t(&a.terms.b),
        t(&a.terms.k),
        t(&a.terms.q),
        t(&a.terms.r),
        r(a.region.n),
        r(a.region.b),
        r(a.region.k),
    );
}

#[test]
#[ignore = "development table; --ignored --nocapture"]
fn real_curves_table() {
    for (name, d) in IMUS {
        for (i, (s, a)) in analyse_imu_dir(name, d, &Config::default())
            .iter()
            .enumerate()
        {
            print_row(name, *s, i % 3, a);
        }
    }
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

#[test]
#[ignore = "development: residuals of one axis (REAL_AXIS=N3:acc:x); --ignored --nocapture"]
fn real_curve_residuals() {
    let spec = std::env::var("REAL_AXIS").unwrap_or("N3:acc:x".into());
    let f: Vec<&str> = spec.split(':').collect();
    let d = IMUS.iter().find(|x| x.0 == f[0]).unwrap().1;
    let all = analyse_imu_dir(f[0], d, &Config::default());
    let k = if f[1] == "gyr" { 0 } else { 3 } + "xyz".find(f[2]).unwrap();
    let (s, a) = &all[k];
    print_row(f[0], *s, k % 3, a);
    if let Some(fit) = &a.fit {
        println!("coef {:?}", fit.coef);
    }
    for p in &a.curve {
        println!(
            "{:>10.4} {:.4e} [{:.3e},{:.3e}] model {:.4e} ratio {:+.3} {}",
            p.tau,
            p.adev,
            p.lo95,
            p.hi95,
            p.model,
            p.model / p.adev - 1.0,
            if p.in_range { "*" } else { "" }
        );
    }
}
