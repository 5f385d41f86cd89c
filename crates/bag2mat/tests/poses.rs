//! Reference trajectories from bags another writer made: rosbags (pinned in the venv) writes
//! a ROS 1 bag and ROS 2 bag directories (mcap, sqlite3) with one topic of each pose type
//! bag2mat reads; every pose comes back exactly as written, with the header stamp or the
//! record time as asked, and a topic that is missing, not a pose, or not named among
//! several is an error that lists the bag's topics.

use std::path::Path;
use std::process::Command;

use bag2mat::test_tools::{run_ok, venv_python, workspace};
use bag2mat::{PoseOptions, TimeColumn, read_poses};

/// Messages per topic.
const N: usize = 40;

/// One topic as the script wrote it: its name, each pose (x y z qx qy qz qw) and each
/// message's header and record time (ns).
type Written = (String, Vec<[f64; 7]>, Vec<(i64, i64)>);

/// Writes `kind` (ros1, mcap, sqlite3) at `out` with the script; returns what it wrote.
fn write(kind: &str, out: &Path) -> Vec<Written> {
    let script = workspace().join("crates/bag2mat/tests/py/pose_bags.py");
    let text = run_ok(
        Command::new(venv_python())
            .arg(script)
            .arg(kind)
            .arg(out)
            .args(["--n", &N.to_string()]),
    );
    let mut topics: Vec<Written> = Vec::new();
    for line in text.lines() {
        let f: Vec<&str> = line.split_whitespace().collect();
        let v: Vec<f64> = f[3..].iter().map(|x| x.parse().unwrap()).collect();
        let t = (f[1].parse().unwrap(), f[2].parse().unwrap());
        match topics.iter_mut().find(|x| x.0 == f[0]) {
            Some(x) => {
                x.1.push(v.try_into().unwrap());
                x.2.push(t);
            }
            None => topics.push((f[0].to_string(), vec![v.try_into().unwrap()], vec![t])),
        }
    }
    topics
}

#[test]
fn pose_topics_written_by_rosbags_read_back_exactly_in_ros1_and_ros2() {
    let d = tempfile::tempdir().unwrap();
    for kind in ["ros1", "mcap", "sqlite3"] {
        let out = d.path().join(if kind == "ros1" { "p.bag" } else { kind });
        let truth = write(kind, &out);
        assert_eq!(truth.len(), 4, "{kind}: four topics");
        for (topic, rows, times) in &truth {
            for time in [TimeColumn::Header, TimeColumn::Record] {
                let s = read_poses(
                    &out,
                    &PoseOptions {
                        topic: Some(topic.clone()),
                        time,
                    },
                )
                .unwrap_or_else(|e| panic!("{kind} {topic}: {e}"));
                assert_eq!(s.len(), N, "{kind} {topic}");
                for (i, (r, t)) in rows.iter().zip(times).enumerate() {
                    let want_t = if time == TimeColumn::Header { t.0 } else { t.1 };
                    assert_eq!(s.t_ns[i], want_t, "{kind} {topic} {i} time");
                    assert_eq!(s.position[i], [r[0], r[1], r[2]], "{kind} {topic} {i}");
                    assert_eq!(
                        s.orientation[i],
                        [r[3], r[4], r[5], r[6]],
                        "{kind} {topic} {i}"
                    );
                }
                assert!(s.what.contains(topic.as_str()), "{}", s.what);
            }
        }
        // the other slash form, with a note
        let s = read_poses(
            &out,
            &PoseOptions {
                topic: Some("odom".into()),
                time: TimeColumn::Header,
            },
        )
        .unwrap();
        assert!(
            s.notes.iter().any(|n| n.text.contains("using '/odom'")),
            "{:?}",
            s.notes
        );
        // several pose topics and none named; a missing topic: errors listing the topics
        let e = read_poses(&out, &PoseOptions::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("several topics carry poses") && e.contains("/tf_body"),
            "{e}"
        );
        let e = read_poses(
            &out,
            &PoseOptions {
                topic: Some("/nope".into()),
                time: TimeColumn::Header,
            },
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("no topic '/nope'") && e.contains("/vicon/body"),
            "{e}"
        );
    }
}

#[test]
fn an_imu_topic_is_not_a_reference() {
    let bag = crate::common::case_bag("p3_short_61s");
    let e = read_poses(
        &bag,
        &PoseOptions {
            topic: Some("imu".into()),
            time: TimeColumn::Header,
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("carries sensor_msgs/Imu, not a pose"), "{e}");
    let e = read_poses(&bag, &PoseOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("no topic carries a pose"), "{e}");
}
