//! `sim` refuses what it cannot do at once and in the house style: huge durations, bad
//! command lines.

use std::process::Stdio;
use std::time::{Duration, Instant};

use crate::common::sim;

/// Longer than any refusal takes; a run still going then spins.
const REFUSAL_TIMEOUT: Duration = Duration::from_secs(20);

/// (exit code, stderr) of `sim args…`, killed (None) after [`REFUSAL_TIMEOUT`].
fn code_within_timeout(dir: &std::path::Path, args: &[&str]) -> (Option<i32>, String) {
    let mut c = sim()
        .current_dir(dir)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        if let Some(s) = c.try_wait().unwrap() {
            let out = c.wait_with_output().unwrap();
            return (s.code(), String::from_utf8_lossy(&out.stderr).into_owned());
        }
        if start.elapsed() > REFUSAL_TIMEOUT {
            let _ = c.kill();
            let _ = c.wait();
            return (None, String::new());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// 6: a duration past what a bag can stamp (1e16, 1e17 s and more) is refused at once,
/// exit 2 with `sim: error:` — it used to spin forever (or overflow).
#[test]
fn huge_durations_are_refused_at_once() {
    let d = tempfile::tempdir().unwrap();
    for dur in ["1e16", "1e17", "1e19", "1e300"] {
        let (code, err) = code_within_timeout(d.path(), &["bag", "--duration", dur, "-o", "x.bag"]);
        assert_eq!(code, Some(2), "--duration {dur}: {err}");
        assert!(
            err.starts_with("sim: error:")
                && err.contains("--duration")
                && !err.contains("panicked"),
            "--duration {dur}: {err}"
        );
        assert!(!d.path().join("x.bag").exists());
    }
}

/// 9: `sim` alone says in one line that a command is needed (not its whole description
/// after `sim: error:`); a negative `--seed` or `--gyro-lpf` gets its own message, not
/// "unexpected argument"; `--gyro-warmup`'s usage shows the one form it takes (`A,T`).
#[test]
fn command_line_messages_follow_the_convention() {
    let d = tempfile::tempdir().unwrap();
    let (code, err) = code_within_timeout(d.path(), &[]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.starts_with("sim: error: a command is required"),
        "{err}"
    );
    assert!(
        !err.contains("vio_data_simulation") && err.lines().count() <= 3,
        "{err}"
    );
    for (args, flag) in [
        (&["bag", "--seed", "-1", "-o", "x.bag"][..], "--seed"),
        (&["bag", "--gyro-lpf", "-5", "-o", "x.bag"], "low-pass"),
        (&["bag", "--acc-lpf", "-5", "-o", "x.bag"], "low-pass"),
    ] {
        let (code, err) = code_within_timeout(d.path(), args);
        assert_eq!(code, Some(2), "{args:?}: {err}");
        assert!(
            err.starts_with("sim: error:")
                && err.contains(flag)
                && !err.contains("unexpected argument"),
            "{args:?}: {err}"
        );
    }
    let out = sim().args(["bag", "--help"]).output().unwrap();
    let help = String::from_utf8_lossy(&out.stdout);
    let line = help
        .lines()
        .find(|l| l.contains("--gyro-warmup"))
        .unwrap_or_else(|| panic!("{help}"));
    assert_eq!(line.trim(), "--gyro-warmup <A,T>", "{help}");
    let (code, err) = code_within_timeout(
        d.path(),
        &[
            "bag",
            "--gyro-warmup",
            "0.01,100",
            "--duration",
            "2",
            "-o",
            "w.bag",
            "-q",
        ],
    );
    assert_eq!(code, Some(0), "the form the usage shows is taken: {err}");
    let (code, err) =
        code_within_timeout(d.path(), &["bag", "--gyro-warmup", "0.01", "-o", "w2.bag"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("two comma-separated numbers"), "{err}");
}
