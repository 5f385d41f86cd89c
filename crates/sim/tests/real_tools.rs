//! `sim bag` output read by Debian's tools: `rosbag info --yaml`, `rosbag check`, and every
//! message through the python rosbag API, compared exactly with an in-process replay.

use crate::common::{SEED, START, ok};
use sim::Motion;
use sim::quat_from_matrix;
use sim::{NoiseGenerator, Preset};
use std::process::Command;

/// Debian's interpreter (the one that sees python3-rosbag).
const PYTHON: &str = "/usr/bin/python3";

fn run(cmd: &mut Command) -> (bool, String, String) {
    match cmd.output() {
        Ok(o) => (
            o.status.success(),
            String::from_utf8_lossy(&o.stdout).into_owned(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        ),
        Err(e) => (
            false,
            String::new(),
            format!("cannot run {cmd:?}: {e} (scripts/test.sh installs python3-rosbag)"),
        ),
    }
}

const DUMP: &str = r#"
import sys, rosbag
b = rosbag.Bag(sys.argv[1])
for topic, m, t in b.read_messages():
    assert topic == 'imu', topic
    assert t == m.header.stamp, (t, m.header.stamp)
    assert m.header.seq == 0 and m.header.frame_id == 'base_link'
    assert list(m.orientation_covariance) == [0.0]*9 and list(m.angular_velocity_covariance) == [0.0]*9 and list(m.linear_acceleration_covariance) == [0.0]*9
    o, w, a = m.orientation, m.angular_velocity, m.linear_acceleration
    print(t.to_nsec(), *[repr(v) for v in (o.x, o.y, o.z, o.w, w.x, w.y, w.z, a.x, a.y, a.z)])
"#;

#[test]
fn rosbag_tools_accept_sim_bags_and_read_the_values_written() {
    let d = tempfile::tempdir().unwrap();
    for (motion, compression) in [("static", "none"), ("ellipse", "lz4"), ("ellipse", "bz2")] {
        let name = format!("{motion}_{compression}.bag");
        ok(
            d.path(),
            &[
                "bag",
                "-o",
                &name,
                "--duration",
                "5",
                "--motion",
                motion,
                "--compression",
                compression,
                "--seed",
                SEED,
                "--start-time",
                START,
                "-q",
            ],
        );
        let path = d.path().join(&name);
        let (s, info, err) = run(Command::new("rosbag").arg("info").arg("--yaml").arg(&path));
        assert!(s, "{name}: rosbag info failed: {err}");
        let n = sim::message_count(200.0, 5.0);
        for needle in [
            format!("messages: {n}"),
            format!("compression: {compression}"),
            "md5: 6a62c6daae103f4ff57a132d6f95cec2".to_string(),
            "topic: imu".to_string(),
            "type: sensor_msgs/Imu".to_string(),
        ] {
            assert!(
                info.contains(&needle),
                "{name}: rosbag info lacks {needle:?}:\n{info}"
            );
        }
        let (s, out, err) = run(Command::new("rosbag").arg("check").arg(&path));
        assert!(s, "{name}: rosbag check failed: {out}{err}");

        let (s, out, err) = run(Command::new(PYTHON).arg("-c").arg(DUMP).arg(&path));
        assert!(s, "{name}: python rosbag read failed: {err}");
        let lines: Vec<&str> = out.lines().collect();
        assert_eq!(lines.len() as u64, n, "{name}: messages read by python");
        // Oracle: the same model and noise replayed here.
        let model = if motion == "static" {
            Motion::Static
        } else {
            Motion::Ellipse
        };
        let mut g = NoiseGenerator::new(
            Preset::Medium.params().discretize(0.005),
            SEED.parse().unwrap(),
        );
        let mut t = 0.0f64;
        for (i, line) in lines.iter().enumerate() {
            let m = if model == Motion::Static {
                model.sample(0.0)
            } else {
                model.sample(t)
            };
            let (mut w, mut a): ([f64; 3], [f64; 3]) = (m.gyro.into(), m.acc.into());
            g.apply(&mut w, &mut a);
            let q = quat_from_matrix(&m.r_wb);
            let expected: Vec<f64> =
                vec![q[1], q[2], q[3], q[0], w[0], w[1], w[2], a[0], a[1], a[2]];
            let f: Vec<&str> = line.split(' ').collect();
            let ns: u64 = f[0].parse().unwrap();
            assert_eq!(
                ns,
                START.parse::<u64>().unwrap() * 1_000_000_000 + (t * 1e9).round() as u64,
                "{name}: stamp of message {i}"
            );
            let got: Vec<f64> = f[1..].iter().map(|x| x.parse().unwrap()).collect();
            assert_eq!(
                got, expected,
                "{name}: message {i} (orientation xyzw, gyro, acc)"
            );
            t += 0.005;
        }
    }
}
