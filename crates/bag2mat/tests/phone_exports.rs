//! Phone and spreadsheet exports read without `--columns`, each written here by hand from
//! its app's documented format: phyphox's CSV (`"Time (s)","Gyroscope x (rad/s)",…`, also
//! its "semicolon, decimal comma" choice and its newer `"X (rad/s)"` headers) and Sensor
//! Logger's (`time,seconds_elapsed,z,y,x`: ns since the epoch, s, axes in z, y, x order,
//! the sensor in the file's name); and the units a header writes honoured with `--columns`.

use std::fmt::Write as _;
use std::path::Path;

use bag2mat::{ImuSeries, ReadOptions, TopicSelector};

/// Seeded rates and accelerations (SplitMix64, bell-shaped): `n` rows of gyro and acc.
fn samples(n: usize, seed: u64) -> Vec<([f64; 3], [f64; 3])> {
    let mut st = seed;
    let mut z = || bag2mat::test_tools::synthetic_noise(&mut st);
    (0..n)
        .map(|_| {
            let g = [z() * 0.02, z() * 0.02, z() * 0.02];
            let a = [z() * 0.05, z() * 0.05, 9.80665 + z() * 0.05];
            (g, a)
        })
        .collect()
}

fn read(path: &Path, opts: &bag2mat::InputOptions) -> ImuSeries {
    bag2mat::read_imu_topics_with(
        path,
        &TopicSelector::default(),
        &ReadOptions { quiet: true },
        opts,
    )
    .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
    .series
    .remove(0)
}

/// phyphox writes every number as `%.9E` (`-1.004321940E-1`); the value a field holds is
/// what its text says.
fn phyphox_number(x: f64) -> String {
    format!("{x:.9E}")
}

fn value(text: &str) -> f64 {
    text.replace(',', ".").parse().unwrap()
}

#[test]
fn phyphox_exports_are_read_without_columns_in_every_delimiter_and_decimal_mark() {
    let dir = tempfile::tempdir().unwrap();
    let rows = samples(3000, 41);
    // (file, delimiter, decimal comma, header of the gyro columns)
    let cases = [
        ("comma.csv", ",", false, "Gyroscope {} (rad/s)"),
        ("tab.csv", "\t", false, "Gyroscope {} (rad/s)"),
        (
            "semicolon_decimal_comma.csv",
            ";",
            true,
            "Gyroscope {} (rad/s)",
        ),
        ("newer.csv", ",", false, "{} (rad/s)"),
    ];
    for (name, d, comma, gyro_header) in cases {
        let mut s = String::new();
        let head: Vec<String> = std::iter::once("\"Time (s)\"".to_string())
            .chain(["x", "y", "z"].map(|a| {
                let a = if gyro_header.starts_with("{}") {
                    a.to_uppercase()
                } else {
                    a.to_string()
                };
                format!("\"{}\"", gyro_header.replace("{}", &a))
            }))
            .chain(std::iter::once("\"Absolute (rad/s)\"".to_string()))
            .collect();
        writeln!(s, "{}", head.join(d)).unwrap();
        let mut texts: Vec<[String; 4]> = Vec::new();
        for (i, (g, _)) in rows.iter().enumerate() {
            let abs = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
            let mut f: Vec<String> = [i as f64 / 100.0, g[0], g[1], g[2], abs]
                .iter()
                .map(|&x| phyphox_number(x))
                .collect();
            if comma {
                f.iter_mut().for_each(|x| *x = x.replace('.', ","));
            }
            texts.push([f[0].clone(), f[1].clone(), f[2].clone(), f[3].clone()]);
            writeln!(s, "{}", f.join(d)).unwrap();
        }
        let p = dir.path().join(name);
        std::fs::write(&p, s).unwrap();
        // before: the decimal-comma file was refused as no table, the newer headers needed
        // --columns
        let got = read(&p, &Default::default());
        assert_eq!(got.len(), rows.len(), "{name}");
        assert_eq!(got.absent_sensor(), Some(bag2mat::Sensor::Acc), "{name}");
        for (i, t) in texts.iter().enumerate() {
            let want_ns = (value(&t[0]) * 1e9).round() as u64;
            assert_eq!(got.stamp[i].as_nanos(), want_ns, "{name} row {i}");
            for k in 0..3 {
                assert_eq!(
                    got.gyro[k][i].to_bits(),
                    value(&t[k + 1]).to_bits(),
                    "{name} row {i} axis {k}"
                );
            }
        }
    }
}

#[test]
fn sensor_logger_exports_are_read_in_ns_with_their_axes_in_z_y_x_order() {
    let dir = tempfile::tempdir().unwrap();
    let rows = samples(2000, 42);
    let t0: u64 = 1_700_000_000_123_456_789;
    for (name, gyro) in [("Gyroscope.csv", true), ("TotalAcceleration.csv", false)] {
        let mut s = String::from("time,seconds_elapsed,z,y,x\n");
        for (i, (g, a)) in rows.iter().enumerate() {
            let v = if gyro { g } else { a };
            let t = t0 + i as u64 * 10_000_000;
            writeln!(s, "{t},{},{},{},{}", i as f64 * 0.01, v[2], v[1], v[0]).unwrap();
        }
        let p = dir.path().join(name);
        std::fs::write(&p, s).unwrap();
        // before: `time` without a unit and z,y,x named nothing: --columns needed
        let got = read(&p, &Default::default());
        assert_eq!(got.len(), rows.len(), "{name}");
        for (i, (g, a)) in rows.iter().enumerate() {
            assert_eq!(
                got.stamp[i].as_nanos(),
                t0 + i as u64 * 10_000_000,
                "{name}"
            );
            let (mine, want) = if gyro {
                (got.gyro_at(i), g)
            } else {
                (got.acc_at(i), a)
            };
            assert_eq!(mine, *want, "{name} row {i}");
        }
    }
    // another sensor's file says what to do
    let p = dir.path().join("Magnetometer.csv");
    std::fs::write(&p, "time,seconds_elapsed,z,y,x\n1,0,1,2,3\n2,0.01,1,2,3\n").unwrap();
    let e = bag2mat::read_imu_topics(&p, &TopicSelector::default(), &ReadOptions { quiet: true })
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("is not Gyroscope.csv, TotalAcceleration.csv"),
        "{e}"
    );
}

#[test]
fn the_units_a_header_writes_are_honoured_with_columns() {
    let dir = tempfile::tempdir().unwrap();
    let rows = samples(1500, 43);
    let mut s =
        String::from("stamp (ms),wx (deg/s),wy (deg/s),wz (deg/s),ax (g),ay (g),az (g),temp\n");
    for (i, (g, a)) in rows.iter().enumerate() {
        let deg = g.map(f64::to_degrees);
        let gs = a.map(|x| x / bag2mat::STANDARD_GRAVITY);
        writeln!(
            s,
            "{},{},{},{},{},{},{},25.0",
            i * 5,
            deg[0],
            deg[1],
            deg[2],
            gs[0],
            gs[1],
            gs[2]
        )
        .unwrap();
    }
    let p = dir.path().join("renamed.csv");
    std::fs::write(&p, s).unwrap();
    let opts = bag2mat::InputOptions {
        columns: Some("t,gx,gy,gz,ax,ay,az,_".into()),
        ..Default::default()
    };
    // before: the time's ms and the sensors' deg/s and g were dropped with the names
    let got = read(&p, &opts);
    assert_eq!(got.stamp[3].as_nanos() - got.stamp[2].as_nanos(), 5_000_000);
    let g = got.gyro_at(10);
    let a = got.acc_at(10);
    const UNIT_ROUND_TRIP: f64 = 1e-12; // a value through deg/s (or g) and back
    for k in 0..3 {
        assert!((g[k] - rows[10].0[k]).abs() < UNIT_ROUND_TRIP, "{g:?}");
        assert!(
            (a[k] - rows[10].1[k]).abs() < UNIT_ROUND_TRIP * 10.0,
            "{a:?}"
        );
    }
}
