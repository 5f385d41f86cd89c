//! Two IMUs interleaved in one file are said to be two sensors, not blamed on the clock: a
//! CSV with a sensor column is refused until `--sensor-id` picks one (which then reads that
//! sensor's rows, sample for sample); without such a column, the record check finds the
//! rows alternating between two sensors and refuses the IEEE 952 section. Written with
//! numpy (an independent writer).

use std::path::Path;
use std::process::Command;

use bag2mat::test_tools::{run_ok, venv_python};
use bag2mat::{FindingKind, FindingLevel, ReadOptions, TopicSelector};

/// Two 200 Hz IMUs (their own biases and noise) one row each in turn, with the same stamps,
/// as `t,sensor_id,gx,…,az` (or without the id column); the rows of each are also written
/// alone to `<stem>_<id>.csv`.
fn two_imus(path: &Path, with_id: bool) {
    let script = format!(
        r#"
import numpy as np
rng = np.random.default_rng(11)
n, rate = 6000, 200.0
t = np.arange(n) / rate
rows, alone = [], {{}}
for sid, (gb, ab) in enumerate([([1e-3, -2e-3, 5e-4], [0.02, -0.01, 9.80665]),
                                  ([2e-2, 1.5e-2, -1e-2], [-0.05, 0.04, 9.70])]):
    g = rng.normal(0, 2e-4 * np.sqrt(rate), (n, 3)) + gb
    a = rng.normal(0, 2e-3 * np.sqrt(rate), (n, 3)) + ab
    alone[sid] = np.column_stack([t, g, a])
    rows.append(np.column_stack([t, np.full(n, sid), g, a]))
both = np.empty((2 * n, 8))
both[0::2], both[1::2] = rows[0], rows[1]
p = r"{path}"
if {with_id}:
    np.savetxt(p, both, delimiter=",", header="t,sensor_id,gx,gy,gz,ax,ay,az", comments="",
               fmt=["%.17g", "%d"] + ["%.17g"] * 6)
else:
    np.savetxt(p, np.delete(both, 1, axis=1), delimiter=",", header="t,gx,gy,gz,ax,ay,az",
               comments="", fmt="%.17g")
for sid, x in alone.items():
    np.savetxt(p[:-4] + f"_{{sid}}.csv", x, delimiter=",", header="t,gx,gy,gz,ax,ay,az",
               comments="", fmt="%.17g")
"#,
        path = path.display(),
        with_id = if with_id { "True" } else { "False" },
    );
    run_ok(Command::new(venv_python()).args(["-c", &script]));
}

fn opts(id: Option<&str>) -> bag2mat::InputOptions {
    bag2mat::InputOptions {
        time_unit: Some(bag2mat::TimeUnit::S),
        sensor_id: id.map(str::to_string),
        ..Default::default()
    }
}

fn read(path: &Path, id: Option<&str>) -> Result<bag2mat::ImuSeries, bag2mat::Error> {
    bag2mat::read_imu_topics_with(
        path,
        &TopicSelector::default(),
        &ReadOptions { quiet: true },
        &opts(id),
    )
    .map(|mut r| r.series.remove(0))
}

#[test]
fn a_csv_of_two_imus_with_a_sensor_column_is_two_sensors_and_one_is_picked() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("rig.csv");
    two_imus(&p, true);
    // before: read as one sensor at 400 Hz, the warning blaming the clock's resolution
    let e = read(&p, None).unwrap_err().to_string();
    assert!(
        e.contains(
            "the rows come from 2 sensors (column 'sensor_id' holds 0 (6000 rows), 1 (6000 rows))"
        ) && e.contains("pick one with --sensor-id 0"),
        "{e}"
    );
    for id in ["0", "1"] {
        let one = read(&p, Some(id)).unwrap();
        let alone = read(&dir.path().join(format!("rig_{id}.csv")), None).unwrap();
        assert_eq!(one.len(), alone.len());
        for i in 0..one.len() {
            assert_eq!(one.stamp[i], alone.stamp[i]);
            assert_eq!(one.gyro_at(i), alone.gyro_at(i), "sensor {id} row {i}");
            assert_eq!(one.acc_at(i), alone.acc_at(i), "sensor {id} row {i}");
        }
    }
    let e = read(&p, Some("7")).unwrap_err().to_string();
    assert!(
        e.contains("--sensor-id 7: column 'sensor_id' holds 0"),
        "{e}"
    );
    let e = read(&dir.path().join("rig_0.csv"), Some("0"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("the file has no column saying which sensor"),
        "{e}"
    );
}

#[test]
fn rows_alternating_between_two_imus_are_found_by_the_record_check() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("noid.csv");
    two_imus(&p, false);
    let info = bag2mat::info_with(&p, true, &opts(None)).unwrap();
    let f = &info.topics[0].findings;
    let two: Vec<_> = f
        .iter()
        .filter(|f| f.kind == FindingKind::Interleaved)
        .collect();
    assert!(
        two.len() == 1 && two[0].level == FindingLevel::Refusal,
        "{f:?}"
    );
    // the equal stamps are the two sensors', not the clock's resolution
    let eq = f
        .iter()
        .find(|f| f.kind == FindingKind::EqualStamps)
        .expect("equal stamps");
    assert!(
        !eq.text.contains("clock's resolution") && eq.text.contains("two sensors"),
        "{}",
        eq.text
    );
    // one sensor alone: neither
    let info = bag2mat::info_with(&dir.path().join("noid_0.csv"), true, &opts(None)).unwrap();
    assert!(
        !info.topics[0]
            .findings
            .iter()
            .any(|f| f.kind == FindingKind::Interleaved),
        "{:?}",
        info.topics[0].findings
    );
}
