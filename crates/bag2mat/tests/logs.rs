//! Logs from outside ROS (issue 20): every reader checked against an independent one on the
//! same file — pyulog for ULog (on our writer's log and on pyulog's own rewrite of it),
//! pymavlink's DFReader for DataFlash, pandas for the CSV layouts — sample for sample, bit
//! for bit; and the text reader's rules (columns, units, damage) as a user meets them.

use std::path::{Path, PathBuf};
use std::process::Command;

use bag2mat::test_tools::{run_ok, venv_python, workspace};
use bag2mat::{ImuSeries, ReadOptions, TopicSelector, read_imu_topics};

use crate::common::run;

fn bag2mat() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bag2mat"))
}

/// One topic as the independent reader gives it: rows `record_ns stamp_ns gx gy gz ax ay az`
/// (or one column of a CSV), as printed.
struct Theirs {
    topic: String,
    rows: Vec<Vec<String>>,
}

/// Runs tests/py/read_logs.py in the venv; its `# topic N` blocks and `%` lines.
fn independent(args: &[&str]) -> (Vec<Theirs>, Vec<String>) {
    let script = workspace().join("crates/bag2mat/tests/py/read_logs.py");
    let out = run_ok(Command::new(venv_python()).arg(script).args(args));
    let mut topics: Vec<Theirs> = Vec::new();
    let mut other = Vec::new();
    for line in out.lines() {
        if let Some(h) = line.strip_prefix("# ") {
            let topic = h.rsplit_once(' ').unwrap().0.to_string();
            topics.push(Theirs {
                topic,
                rows: Vec::new(),
            });
        } else if let Some(o) = line.strip_prefix("% ") {
            other.push(o.to_string());
        } else {
            let v: Vec<String> = line.split(' ').map(str::to_string).collect();
            topics.last_mut().unwrap().rows.push(v);
        }
    }
    (topics, other)
}

/// Same number, bit for bit (NaN: both NaN).
fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || a.is_nan() && b.is_nan()
}

/// Every Imu topic of `path` read by us equals the independent reader's, sample for sample.
fn assert_same_rows(path: &Path, theirs: &[Theirs]) -> Vec<ImuSeries> {
    let sel = TopicSelector {
        topics: vec![],
        all_imu: true,
        preferred: None,
    };
    let ours = read_imu_topics(path, &sel, &ReadOptions { quiet: true }).unwrap();
    let names: Vec<&str> = ours.series.iter().map(|s| s.topic.as_str()).collect();
    let want: Vec<&str> = theirs.iter().map(|t| t.topic.as_str()).collect();
    assert_eq!(names, want, "{}", path.display());
    for (s, t) in ours.series.iter().zip(theirs) {
        assert_eq!(s.len(), t.rows.len(), "{}", s.topic);
        for (i, r) in t.rows.iter().enumerate() {
            let g = s.gyro_at(i);
            let a = s.acc_at(i);
            assert_eq!(r.len(), 8);
            assert_eq!(r[0].parse::<u64>().unwrap(), s.record_time[i].as_nanos());
            assert_eq!(r[1].parse::<u64>().unwrap(), s.stamp[i].as_nanos());
            let mine = [g[0], g[1], g[2], a[0], a[1], a[2]];
            for k in 0..6 {
                let t: f64 = r[k + 2].parse().unwrap();
                assert!(
                    same(mine[k], t),
                    "{} row {i} column {k}: ours {} theirs {t}",
                    s.topic,
                    mine[k],
                );
            }
        }
    }
    ours.series
}

fn write_ulog(path: &Path, seconds: f64, dropout: Option<u16>) {
    let spec = bag2mat::test_tools::UlogImuSpec {
        seconds,
        rate: 250.0,
        instances: 2,
        dropout_ms: dropout,
        seed: 7,
    };
    let f = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    bag2mat::test_tools::ulog_imu_log(f, &spec).unwrap();
}

#[test]
fn ulog_topics_match_pyulog_bit_for_bit_also_on_pyulogs_own_rewrite() {
    let dir = tempfile::tempdir().unwrap();
    let ours = dir.path().join("flight.ulg");
    write_ulog(&ours, 30.0, Some(60));
    let rewritten = dir.path().join("rewritten.ulg");
    let _ = independent(&[
        "ulog-rewrite",
        ours.to_str().unwrap(),
        rewritten.to_str().unwrap(),
    ]);
    assert_ne!(
        std::fs::read(&ours).unwrap(),
        std::fs::read(&rewritten).unwrap(),
        "pyulog's writer lays the file out its own way"
    );
    for f in [&ours, &rewritten] {
        let (theirs, other) = independent(&["ulog", f.to_str().unwrap()]);
        assert_eq!(theirs.len(), 6, "{:?}", other);
        let series = assert_same_rows(f, &theirs);
        // the dropout the log records is a loss, and pyulog counts the same one
        assert!(other.contains(&"dropouts 1 60".to_string()), "{other:?}");
        let note = bag2mat::shared::note::texts(&series[0].notes);
        assert!(
            note.contains("1 dropout totalling 60 ms"),
            "{}: {note}",
            f.display()
        );
        // the gap it leaves is found where the analysers look for gaps
        let tm = bag2mat::analyse_timing(&bag2mat::ns_of_times(&series[0].record_time));
        assert_eq!(tm.gaps.len(), 1, "{tm:?}");
    }
}

/// Issue 20: PX4's raw FIFO topics (`sensor_gyro_fifo`, `sensor_accel_fifo`: up to 32
/// int16 samples a message with `dt` and `scale`) are read sample by sample, equal to
/// pyulog's decode of the same messages expanded at `dt` (the newest at
/// `timestamp_sample`), on our writer's log and on pyulog's rewrite of it; `bag2mat info`
/// lists them with the samples' rate.
#[test]
fn ulog_fifo_topics_are_read_sample_by_sample_like_pyulogs_decode() {
    let dir = tempfile::tempdir().unwrap();
    let ours = dir.path().join("fifo.ulg");
    let f = std::io::BufWriter::new(std::fs::File::create(&ours).unwrap());
    bag2mat::test_tools::ulog_fifo_log(f, 20.0, 800.0, 6, 3).unwrap();
    let rewritten = dir.path().join("rewritten.ulg");
    let _ = independent(&[
        "ulog-rewrite",
        ours.to_str().unwrap(),
        rewritten.to_str().unwrap(),
    ]);
    for f in [&ours, &rewritten] {
        let (theirs, other) = independent(&["ulog", f.to_str().unwrap()]);
        let names: Vec<&str> = theirs.iter().map(|t| t.topic.as_str()).collect();
        assert_eq!(
            names,
            ["sensor_accel_fifo", "sensor_gyro_fifo"],
            "{other:?}"
        );
        let series = assert_same_rows(f, &theirs);
        for s in &series {
            // every sample of the 20 s at 800 Hz, none lost, evenly spaced
            assert_eq!(s.len(), 16_000, "{}", s.topic);
            let tm = bag2mat::analyse_timing(&bag2mat::ns_of_times(&s.stamp));
            assert!(tm.gaps.is_empty(), "{}: {tm:?}", s.topic);
            let rate = tm.nominal_rate().unwrap();
            assert!((rate - 800.0).abs() < 0.01, "{}: {rate}", s.topic);
        }
    }
    let out = bag2mat::info(&ours, true).unwrap().text(&ours);
    for topic in ["sensor_gyro_fifo", "sensor_accel_fifo"] {
        let line = out
            .lines()
            .find(|l| l.contains(topic))
            .unwrap_or_else(|| panic!("{out}"));
        assert!(line.contains("16000") && line.contains("800.0"), "{line}");
    }
}

#[test]
fn ulog_topics_are_chosen_like_bag_topics_and_convert() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("f.ulg");
    write_ulog(&log, 4.0, None);
    let (ok, out, err) = run(bag2mat().arg("info").arg(&log));
    assert!(ok, "{err}");
    for t in [
        "sensor_combined",
        "sensor_gyro:1",
        "sensor_accel:0",
        "vehicle_imu",
        "vehicle_status",
    ] {
        assert!(out.contains(t), "{t}: {out}");
    }
    assert!(out.contains("PX4 ULog"), "{out}");
    let csv = dir.path().join("g1.csv");
    let (ok, _, err) = run(bag2mat()
        .arg(&log)
        .args(["--topic", "sensor_gyro:1", "-o"])
        .arg(&csv));
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let row: Vec<&str> = text.lines().nth(1).unwrap().split(',').collect();
    assert_eq!(&row[1..4], ["NaN", "NaN", "NaN"], "a gyro topic has no acc");
    let (ok, _, err) = run(bag2mat().arg(&log).args(["--topic", "vehicle_status"]));
    assert!(!ok && err.contains("carries px4/vehicle_status"), "{err}");
    let (ok, _, err) = run(bag2mat().arg(&log).args(["--topic", "sensor_gyro:7"]));
    assert!(
        !ok && err.contains("sensor_gyro:1"),
        "lists the topics: {err}"
    );
}

#[test]
fn dataflash_imu_and_batches_match_pymavlink_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("00000042.BIN");
    let f = std::io::BufWriter::new(std::fs::File::create(&log).unwrap());
    bag2mat::test_tools::dataflash_imu_log(f, 12.0, 200.0, 3).unwrap();
    let (theirs, _) = independent(&["dataflash", log.to_str().unwrap()]);
    let names: Vec<&str> = theirs.iter().map(|t| t.topic.as_str()).collect();
    assert_eq!(names, ["IMU:0", "IMU:1", "ISB_ACC", "ISB_GYR"]);
    let series = assert_same_rows(&log, &theirs);
    // the last batch of each sensor stops short of the others' count: said on each, with
    // the samples it lacks as a bound (the log may have stopped before writing them)
    for s in &series[2..4] {
        let notes = bag2mat::shared::note::texts(&s.notes);
        assert!(
            notes.contains(&format!("up to 32 messages on '{}' were lost", s.topic)),
            "{notes}"
        );
    }
}

/// A EuRoC/ASL `data.csv` with the decimal forms real datasets hold (17 digits, exponents,
/// integers, a negative zero).
fn write_euroc(dir: &Path, rows: usize) -> PathBuf {
    let imu = dir.join("mav0/imu0");
    std::fs::create_dir_all(&imu).unwrap();
    std::fs::create_dir_all(dir.join("mav0/cam0")).unwrap();
    std::fs::write(
        dir.join("mav0/cam0/data.csv"),
        "#timestamp [ns],filename\n1403636579763555584,1403636579763555584.png\n",
    )
    .unwrap();
    let mut s = String::from(
        "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\r\n",
    );
    for i in 0..rows {
        let x = i as f64;
        s.push_str(&format!(
            "{},{},{:e},-0.0,{:.17},{},{}\r\n",
            1_403_636_579_758_555_392u64 + 5_000_000 * i as u64,
            (x * 0.37).sin() * 1e-2,
            (x * 0.11).cos() * 3e-5,
            8.147_691_708_333_333 + x * 1e-9,
            i % 7,
            -0.375_921_583_333_333_3 / (x + 1.0)
        ));
    }
    std::fs::write(imu.join("data.csv"), s).unwrap();
    std::fs::write(
        imu.join("sensor.yaml"),
        "sensor_type: imu\ncomment: VI-Sensor IMU (ADIS16448) noise model\nT_BS:\n  cols: 4\n  rows: 4\n  data: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]\nrate_hz: 200\ngyroscope_noise_density: 1.6968e-04     # [ rad / s / sqrt(Hz) ]\ngyroscope_random_walk: 1.9393e-05\naccelerometer_noise_density: 2.0000e-3\naccelerometer_random_walk: 3.0000e-3\n",
    )
    .unwrap();
    imu.join("data.csv")
}

#[test]
fn euroc_file_folder_and_root_read_the_same_decimals_as_pandas() {
    let dir = tempfile::tempdir().unwrap();
    let csv = write_euroc(dir.path(), 3000);
    let cols = [
        "#timestamp [ns]",
        "w_RS_S_x [rad s^-1]",
        "w_RS_S_y [rad s^-1]",
        "w_RS_S_z [rad s^-1]",
        "a_RS_S_x [m s^-2]",
        "a_RS_S_y [m s^-2]",
        "a_RS_S_z [m s^-2]",
    ];
    let mut args = vec!["csv", csv.to_str().unwrap()];
    args.extend(cols);
    let (theirs, _) = independent(&args);
    for input in [
        csv.clone(),
        dir.path().join("mav0/imu0"),
        dir.path().to_path_buf(),
    ] {
        let r = read_imu_topics(
            &input,
            &TopicSelector::one("imu0"),
            &ReadOptions { quiet: true },
        )
        .unwrap_or_else(|e| panic!("{}: {e}", input.display()));
        let s = &r.series[0];
        assert_eq!(s.topic, "imu0");
        assert_eq!(s.len(), 3000);
        for i in 0..s.len() {
            assert_eq!(s.stamp[i].as_nanos().to_string(), theirs[0].rows[i][0]);
            let v = [s.gyro_at(i), s.acc_at(i)].concat();
            for k in 0..6 {
                let t: f64 = theirs[k + 1].rows[i][0].parse().unwrap();
                assert!(
                    same(v[k], t),
                    "row {i} {}: ours {} pandas {t}",
                    cols[k + 1],
                    v[k]
                );
            }
        }
        let notes = bag2mat::shared::note::texts(&s.notes);
        assert!(
            notes.contains("sensor.yaml states gyroscope_noise_density 0.00016968"),
            "{notes}"
        );
    }
}

/// Writes `text` to a file and reads it with the given flags through the binary's `info`.
fn info(dir: &Path, name: &str, text: &str, flags: &[&str]) -> (bool, String, String) {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    run(bag2mat().arg("info").arg(&p).args(flags))
}

#[test]
fn text_logs_name_columns_and_units_or_say_what_to_add() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let rows = |f: &dyn Fn(usize) -> String| (0..500).map(f).collect::<String>();
    // header with units in brackets, TSV
    let tsv = format!(
        "time [s]\tgx [deg/s]\tgy [deg/s]\tgz [deg/s]\tax [g]\tay [g]\taz [g]\n{}",
        rows(&|i| format!("{}\t1\t0\t-1\t0\t0\t1\n", i as f64 * 0.01))
    );
    let p = d.join("a.tsv");
    std::fs::write(&p, &tsv).unwrap();
    let s = bag2mat::read_imu_series(&p, "imu", &ReadOptions { quiet: true }).unwrap();
    assert_eq!(s.gyro_at(3), [1f64.to_radians(), 0.0, -(1f64.to_radians())]);
    assert_eq!(s.acc_at(3)[2], bag2mat::STANDARD_GRAVITY);
    assert_eq!(s.record_time[100].as_nanos(), 1_000_000_000);
    // no header: --columns, whitespace, raw counts with a scale
    let raw = rows(&|i| format!("  {}   164  -164 0  2048 0   0\n", 1000 * i));
    let (ok, out, err) = info(d, "raw.txt", &raw, &[]);
    assert!(
        !ok && err.contains("no header line") && err.contains("--columns"),
        "{out}{err}"
    );
    let flags = [
        "--columns",
        "t_us,gx,gy,gz,ax,ay,az",
        "--gyro-unit",
        "deg/s",
        "--gyro-scale",
        "16.4",
        "--acc-unit",
        "g",
        "--acc-scale",
        "2048",
    ];
    let (ok, out, err) = info(d, "raw.txt", &raw, &flags);
    assert!(ok, "{err}");
    assert!(out.contains("1000.000") && out.contains("   500 "), "{out}");
    assert!(out.contains("raw counts, 16.4 LSB per deg/s"), "{out}");
    // ambiguity and missing units are errors that say what to add
    for (text, needle) in [
        ("t,gx,gyro_x,gy,gz,ax,ay,az\n", "both look like gyro x"),
        ("time,gx,gy,gz,ax,ay,az\n", "give --time-unit"),
        ("t_s,gx,gy,gz,ax,ay,az\n", "about 1 g"),
        ("t_s,gx,gy,gz,ax,ay\n", "2 of its three axis columns"),
        ("gx,gy,gz,ax,ay,az\n", "give the sample rate"),
    ] {
        let n = text.trim_end().split(',').count();
        let body = rows(&|i| {
            let mut v = vec![format!("{}", i as f64 * 0.01)];
            v.extend((1..n).map(|k| {
                if k == n - 1 {
                    "1.0".into()
                } else {
                    "0.001".to_string()
                }
            }));
            v.join(",") + "\n"
        });
        let (ok, _, err) = info(d, "amb.csv", &format!("{text}{body}"), &[]);
        assert!(!ok && err.contains(needle), "{text}: {err}");
    }
    // no time column: --rate
    let body = rows(&|_| "0.001,0,0,0,0,9.8\n".to_string());
    let (ok, out, err) = info(
        d,
        "norate.csv",
        &format!("gx,gy,gz,ax,ay,az\n{body}"),
        &["--rate", "400"],
    );
    assert!(ok && out.contains("400.000"), "{out}{err}");
}

#[test]
fn damaged_text_lines_are_counted_with_their_line_numbers_and_stamps_checked() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("# logger v2\nt_ms,gx,gy,gz,ax,ay,az\n");
    for i in 0..2000 {
        match i {
            700 => text.push_str("12,0.1,0.2\n"),
            900 => text.push_str("garbled,,,\n"),
            1000 => text.push_str(&format!("{},0,0,0,0,0,9.8\n", 10 * (i - 2))),
            1500 => text.push_str(&format!("{},0,0,0,0,0,9.8\n", 10 * (i - 1))),
            _ => text.push_str(&format!("{},0.001,0,0,0,0,9.8\n", 10 * i)),
        }
    }
    let (ok, out, err) = info(dir.path(), "d.csv", &text, &[]);
    assert!(ok, "{err}");
    // line numbers count the comment and the header: row i is on line i + 3
    assert!(
        out.contains("2 malformed lines skipped (first: line 703:"),
        "{out}"
    );
    assert!(
        out.contains("1 time stamp goes backwards (first at line 1003)"),
        "{out}"
    );
    assert!(
        out.contains("1 time stamp repeats the one before (first at line 1503)"),
        "{out}"
    );
    // past the limit the file is refused
    let bad: String = (0..100).map(|i| format!("{},x,y\n", i)).collect();
    let (ok, _, err) = info(dir.path(), "bad.csv", &format!("{text}{bad}"), &[]);
    assert!(
        !ok && err.contains("102 malformed lines")
            && err.contains("more than 21 of its 2100 lines"),
        "{err}"
    );
}

#[test]
fn npy_from_bag2mat_reads_back_bit_for_bit_and_unknown_files_name_every_format() {
    let dir = tempfile::tempdir().unwrap();
    let bag = crate::common::case_bag("p3_short_61s");
    let npy = dir.path().join("x.npy");
    let (ok, _, err) = run(bag2mat().arg(&bag).arg("imu").arg("-o").arg(&npy).arg("-q"));
    assert!(ok, "{err}");
    let from_bag = bag2mat::bag_to_data_imu(&bag, "imu", true).unwrap().data;
    let back = bag2mat::bag_to_data_imu(&npy, "imu", true).unwrap().data;
    assert_eq!(back.rows(), from_bag.rows());
    for c in 0..7 {
        for (a, b) in back.columns[c].iter().zip(&from_bag.columns[c]) {
            assert_eq!(a.to_bits(), b.to_bits(), "column {c}");
        }
    }
    let junk = dir.path().join("junk.dat");
    std::fs::write(&junk, [0u8, 1, 2, 3, 200, 100, 7, 0, 0]).unwrap();
    let (ok, _, err) = run(bag2mat().arg("info").arg(&junk));
    assert!(!ok);
    for f in [
        "ROS 1 bag",
        "EuRoC/ASL",
        "CSV/TSV",
        "PX4 ULog",
        "DataFlash",
        "NumPy",
    ] {
        assert!(err.contains(f), "{f}: {err}");
    }
}

#[test]
fn a_damaged_ulog_says_what_it_lost_and_keeps_the_rest() {
    use bag2mat::test_tools::{ULOG_SENSOR_COMBINED, ULOG_VEHICLE_IMU, UlogWriter};
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("damaged.ulg");
    let mut u = UlogWriter::new(Vec::new(), 0).unwrap();
    u.format(ULOG_SENSOR_COMBINED).unwrap();
    u.format(ULOG_VEHICLE_IMU).unwrap();
    u.add(0, 0, "sensor_combined").unwrap();
    u.add(0, 1, "vehicle_imu").unwrap();
    let combined = |t: u64| {
        let mut b = t.to_le_bytes().to_vec();
        b.extend([0u8; 12]); // gyro_rad
        b.extend([0u8; 8]);
        b.extend(9.81f32.to_le_bytes().repeat(3));
        b.extend([0u8; 8]);
        b
    };
    let deltas = |t: u64, dt: u16| {
        let mut b = t.to_le_bytes().to_vec();
        b.extend(t.to_le_bytes());
        b.extend([0u8; 8]);
        b.extend(0.01f32.to_le_bytes().repeat(6));
        b.extend(dt.to_le_bytes().repeat(2));
        b.extend([0u8; 4]);
        b
    };
    for i in 0..100u64 {
        u.data(0, &combined(1_000_000 + 5_000 * i)).unwrap();
        u.data(
            1,
            &deltas(1_000_000 + 5_000 * i, if i == 40 { 0 } else { 5_000 }),
        )
        .unwrap();
    }
    let mut bytes = u.finish().unwrap();
    // garbage, then the logger's sync marker and more data, then a message cut short
    bytes.extend([0xEE; 37]);
    let mut u = UlogWriter::new(Vec::new(), 0).unwrap();
    u.sync().unwrap();
    for i in 100..150u64 {
        u.data(0, &combined(1_000_000 + 5_000 * i)).unwrap();
    }
    let tail = u.finish().unwrap();
    bytes.extend(&tail[16 + 43..]); // without the second file header and flag bits
    bytes.extend([50, 0, b'D', 0, 0, 1, 2]);
    std::fs::write(&path, &bytes).unwrap();
    let r = read_imu_topics(
        &path,
        &TopicSelector {
            topics: vec![],
            all_imu: true,
            preferred: None,
        },
        &ReadOptions { quiet: true },
    )
    .unwrap();
    let combined = &r.series[0];
    assert_eq!(
        (combined.topic.as_str(), combined.len()),
        ("sensor_combined", 150)
    );
    let notes = bag2mat::shared::note::texts(&combined.notes);
    assert!(notes.contains("37 bytes in 1 stretch"), "{notes}");
    assert!(notes.contains("ends inside a message"), "{notes}");
    let deltas = &r.series[1];
    assert_eq!(deltas.len(), 99);
    let notes = bag2mat::shared::note::texts(&deltas.notes);
    assert!(
        notes.contains("'vehicle_imu': a delta with a zero dt; 1 message lost"),
        "{notes}"
    );
    assert_eq!(deltas.gyro[0][0], 0.01f32 as f64 / 5e-3);
}

/// Seeded damage (bit flips, byte runs, cuts, inserted garbage) of every new format: each
/// variant reads or fails with an error, never a panic or a hang, and `info` agrees.
#[test]
fn damaged_logs_of_every_format_never_panic() {
    /// Variants per format (a few seconds in the test build).
    const VARIANTS: u64 = 300;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_ulog(&d.join("a.ulg"), 3.0, Some(20));
    let f = std::io::BufWriter::new(std::fs::File::create(d.join("a.bin")).unwrap());
    bag2mat::test_tools::dataflash_imu_log(f, 3.0, 200.0, 1).unwrap();
    let csv = write_euroc(&d.join("e"), 400);
    let (ok, _, err) = run(bag2mat()
        .arg(crate::common::case_bag("p3_short_61s"))
        .args(["imu", "-q", "-o"])
        .arg(d.join("a.npy")));
    assert!(ok, "{err}");
    let mut state = 0x2020_u64;
    let mut next = |n: u64| {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 33) % n.max(1)
    };
    let sel = TopicSelector {
        topics: vec![],
        all_imu: true,
        preferred: None,
    };
    for (name, src) in [
        ("a.ulg", d.join("a.ulg")),
        ("a.bin", d.join("a.bin")),
        ("a.npy", d.join("a.npy")),
        ("data.csv", csv),
    ] {
        let clean = std::fs::read(&src).unwrap();
        let (mut read, mut failed) = (0, 0);
        for v in 0..VARIANTS {
            let mut b = clean.clone();
            let at = next(b.len() as u64) as usize;
            match v % 4 {
                0 => b.truncate(at),
                1 => {
                    for _ in 0..1 + next(8) {
                        let i = next(b.len() as u64) as usize;
                        b[i] ^= 1 << next(8);
                    }
                }
                2 => {
                    let n = (1 + next(64) as usize).min(b.len() - at);
                    for x in &mut b[at..at + n] {
                        *x = next(256) as u8;
                    }
                }
                _ => {
                    let junk: Vec<u8> = (0..1 + next(40)).map(|_| next(256) as u8).collect();
                    b.splice(at..at, junk);
                }
            }
            let p = d.join(format!("v_{name}"));
            std::fs::write(&p, &b).unwrap();
            let t = std::time::Instant::now();
            match read_imu_topics(&p, &sel, &ReadOptions { quiet: true }) {
                Ok(r) => {
                    read += 1;
                    assert!(!r.series.is_empty());
                }
                Err(e) => {
                    failed += 1;
                    assert!(!e.to_string().is_empty());
                }
            }
            let _ = bag2mat::info(&p, true);
            assert!(
                t.elapsed().as_secs_f64() < 10.0,
                "{name} variant {v} took {:?}",
                t.elapsed()
            );
        }
        assert_eq!(read + failed, VARIANTS, "{name}");
    }
}
