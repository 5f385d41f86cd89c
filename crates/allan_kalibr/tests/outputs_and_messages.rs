//! allan_kalibr's outputs and messages (the reader's are in bag2mat's tests): a run's files
//! are all there or none (concurrent runs, a kill mid-commit, a full disk), the flags are
//! checked, warnings go to stderr in lowercase.

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

/// Slows every step of an output commit (bag2mat's test hook), as a slow file system would.
const SLOW_COMMIT_MS: &str = "400";

use crate::cli::noise_mat_seeded as noise_mat;

fn kalibr(input: &Path, out: &Path, delay: Option<&str>) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_allan_kalibr"));
    c.arg(input)
        .args(["--update-rate", "100", "-q", "-o"])
        .arg(out)
        // the files say when they were written: one instant for every run, so that a
        // run's set is the same bytes whenever it is written
        .env("SOURCE_DATE_EPOCH", "1700000000")
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    if let Some(ms) = delay {
        c.env("BAG2MAT_TEST_COMMIT_DELAY_MS", ms);
    }
    c
}

/// Every file of a directory (name → bytes).
fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap_or_default(),
            )
        })
        .collect()
}

/// Hidden temporary paths (`.<name>.<pid>.<n>.tmp`, journals) in `dir`.
fn hidden(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.') && (n.contains(".tmp") || n.ends_with(".commit")))
        .collect()
}

/// Waits for a run; panics unless it succeeded.
fn ok(c: Child) {
    let out = c.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Starts a run and waits until its commit begins (the test hook's line), then kills it.
fn kill_in_commit(mut cmd: Command) {
    let mut c = cmd.spawn().unwrap();
    let err = c.stderr.take().unwrap();
    for line in BufReader::new(err).lines() {
        if line.unwrap().contains("test hook: commit step") {
            break;
        }
    }
    c.kill().unwrap();
    c.wait().unwrap();
}

/// The output set of each of two different inputs, written alone.
struct Sets {
    dir: tempfile::TempDir,
    a: PathBuf,
    b: PathBuf,
    set_a: BTreeMap<String, Vec<u8>>,
    set_b: BTreeMap<String, Vec<u8>>,
}

fn sets() -> Sets {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("a")).unwrap();
    std::fs::create_dir_all(dir.path().join("b")).unwrap();
    let a = dir.path().join("a/imu.mat");
    let b = dir.path().join("b/imu.mat");
    noise_mat(&a, 6000, 0x5EED);
    noise_mat(&b, 6000, 0xBEEF);
    let (oa, ob) = (dir.path().join("out_a"), dir.path().join("out_b"));
    ok(kalibr(&a, &oa, None).spawn().unwrap());
    ok(kalibr(&b, &ob, None).spawn().unwrap());
    let (set_a, set_b) = (files(&oa), files(&ob));
    assert_eq!(
        set_a.keys().collect::<Vec<_>>(),
        set_b.keys().collect::<Vec<_>>()
    );
    assert!(
        set_a.iter().all(|(k, v)| set_b[k] != *v),
        "every output must differ between the inputs"
    );
    Sets {
        dir,
        a,
        b,
        set_a,
        set_b,
    }
}

/// The outputs in `dir` are one run's complete set (plus `extra` files left alone), with no
/// temporary path in it, nor (`settled`: no run was killed since the last one) beside it.
fn one_complete_set(s: &Sets, dir: &Path, extra: &[&str], settled: bool, what: &str) {
    let mut got = files(dir);
    for e in extra {
        assert!(got.remove(*e).is_some(), "{what}: {e} was not kept");
    }
    let which = if got == s.set_a {
        "a"
    } else if got == s.set_b {
        "b"
    } else {
        let mixed: Vec<String> = got
            .iter()
            .map(|(k, v)| {
                let from = if s.set_a.get(k) == Some(v) {
                    "a"
                } else if s.set_b.get(k) == Some(v) {
                    "b"
                } else {
                    "?"
                };
                format!("{k}:{from}")
            })
            .collect();
        panic!("{what}: not one run's complete set: {mixed:?}");
    };
    let _ = which;
    let parent = dir.parent().unwrap();
    assert!(hidden(dir).is_empty(), "{what}: {:?}", hidden(dir));
    if settled {
        assert!(hidden(parent).is_empty(), "{what}: {:?}", hidden(parent));
    }
}

/// 5: "all files or none" holds across two concurrent runs into one directory (new, holding
/// one run's outputs, holding another file too) with slow renames, and a run killed during
/// its commit leaves the old set or the new one, never a mix; the next run leaves no
/// temporary path behind.
#[test]
fn all_or_none_across_concurrent_runs_and_a_kill() {
    let s = sets();
    let root = s.dir.path();
    // Concurrent runs into a new directory, then into it again, then with a foreign file.
    let x = root.join("x");
    for (round, extra) in [(0, None), (1, None), (2, Some("notes.txt"))] {
        if let Some(e) = extra {
            std::fs::write(x.join(e), b"mine").unwrap();
        }
        let ca = kalibr(&s.a, &x, Some(SLOW_COMMIT_MS)).spawn().unwrap();
        let cb = kalibr(&s.b, &x, Some(SLOW_COMMIT_MS)).spawn().unwrap();
        ok(ca);
        ok(cb);
        let extra: Vec<&str> = extra.into_iter().collect();
        one_complete_set(&s, &x, &extra, true, &format!("concurrent round {round}"));
    }
    std::fs::remove_file(x.join("notes.txt")).unwrap();
    // Killed during its commit: into a new directory, over the other run's outputs.
    let y = root.join("y");
    kill_in_commit(kalibr(&s.a, &y, Some("3000")));
    assert!(!y.exists(), "a killed run left {y:?}");
    ok(kalibr(&s.a, &y, None).spawn().unwrap());
    one_complete_set(
        &s,
        &y,
        &[],
        true,
        "after a run killed before its directory was made",
    );
    kill_in_commit(kalibr(&s.b, &y, Some("3000")));
    one_complete_set(&s, &y, &[], false, "killed over the outputs of another run");
    ok(kalibr(&s.b, &y, None).spawn().unwrap());
    one_complete_set(&s, &y, &[], true, "the next run");
    // Killed half way through moving its files in beside a file that is not ours: the next
    // run finishes that commit first, and the directory ends whole.
    std::fs::write(y.join("notes.txt"), b"mine").unwrap();
    let mut cmd = kalibr(&s.a, &y, Some("300"));
    let mut c = cmd.spawn().unwrap();
    let err = c.stderr.take().unwrap();
    let mut steps = 0;
    for line in BufReader::new(err).lines() {
        if line.unwrap().contains("test hook: commit step") {
            steps += 1;
            if steps == 4 {
                break;
            }
        }
    }
    c.kill().unwrap();
    c.wait().unwrap();
    ok(kalibr(&s.b, &y, None).spawn().unwrap());
    one_complete_set(
        &s,
        &y,
        &["notes.txt"],
        true,
        "after a run killed mid-commit",
    );
}

/// `allan_kalibr ARGS` with files limited to `kib` KiB (`ulimit -f`, SIGXFSZ ignored): every
/// write past it fails as on a full disk.
fn small_disk(kib: u64, args: &[&str]) -> std::process::Output {
    Command::new("sh")
        .arg("-c")
        .arg(format!("trap '' XFSZ; ulimit -f {kib}; exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_allan_kalibr"))
        .args(args)
        .output()
        .unwrap()
}

/// File-size limits that fail the run at its outputs (the yaml, the curves CSV, a PNG; the
/// largest fits them all), KiB, for the 60 s record of the test.
const DISK_KIB: [u64; 8] = [2, 16, 64, 128, 256, 400, 700, 1200];

/// 9 and 10: a full disk (at whichever output) is one plain error — no raw
/// `ImageError(IoError(Custom {…}))`, no "os error" — and leaves no output directory and no
/// temporary path; a missing --curves path is described plainly.
#[test]
fn a_full_disk_is_a_plain_error_and_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let mat = dir.path().join("n.mat");
    noise_mat(&mat, 6000, 0x5EED);
    let (mut failures, mut png) = (0, false);
    for kib in DISK_KIB {
        let out = dir.path().join(format!("o{kib}"));
        let o = small_disk(
            kib,
            &[
                mat.to_str().unwrap(),
                "--update-rate",
                "100",
                "-q",
                "-o",
                out.to_str().unwrap(),
            ],
        );
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        if o.status.success() {
            continue;
        }
        failures += 1;
        assert_eq!(o.status.code(), Some(1), "{kib} KiB: {err}");
        let line = err.lines().last().unwrap_or("");
        png |= line.contains(".png:");
        assert!(
            line.starts_with("allan_kalibr: error: "),
            "{kib} KiB: {err}"
        );
        for raw in [
            "ImageError",
            "IoError",
            "Custom",
            "os error",
            "error: error",
        ] {
            assert!(!err.contains(raw), "{kib} KiB: {err}");
        }
        assert!(
            !out.exists(),
            "{kib} KiB: a failed run left its output directory"
        );
        assert!(
            hidden(dir.path()).is_empty(),
            "{kib} KiB: {:?}",
            hidden(dir.path())
        );
    }
    assert!(
        failures >= 3,
        "the limits {DISK_KIB:?} should fail several outputs"
    );
    assert!(png, "no limit of {DISK_KIB:?} failed a PNG");
    let o = Command::new(env!("CARGO_BIN_EXE_allan_kalibr"))
        .args(["--curves", "/nonexistent/curves.csv"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(!err.contains("os error"), "{err}");
}

/// 10: `--skip-start` that leaves almost nothing of the record (29.9 s of 30 s) is an error,
/// not 10 samples analysed into plausible yaml; --duration, --units, --samples without
/// --curves are a usage error, not ignored.
#[test]
fn skip_start_and_curve_flags_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let mat = dir.path().join("n.mat");
    noise_mat(&mat, 3000, 0x5EED); // 30 s at 100 Hz
    let out = dir.path().join("o");
    let o = Command::new(env!("CARGO_BIN_EXE_allan_kalibr"))
        .arg(&mat)
        .args(["--update-rate", "100", "--skip-start", "29.9", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("--skip-start 29.9 leaves"), "{err}");
    assert!(!out.exists());
    for flags in [
        &["--duration", "3600"][..],
        &["--units", "g"],
        &["--samples", "1000"],
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_allan_kalibr"))
            .arg(&mat)
            .args(flags)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{flags:?}: {err}");
        assert!(
            err.starts_with("allan_kalibr: error:") && err.contains("--curves"),
            "{flags:?}: {err}"
        );
    }
}

/// 9: a warm-up and a gap in the stamps are warned on stderr as lowercase `warning:` lines;
/// stdout (the report) holds no `WARNING:` and no warning line (it names them as findings).
#[test]
fn warnings_go_to_stderr_in_lowercase() {
    let dir = tempfile::tempdir().unwrap();
    let mat = dir.path().join("w.mat");
    bag2mat::write_data_imu(
        &bag2mat::shared::output::Outputs::direct(),
        &mat,
        &crate::ieee952::simulate(4, Some((0.02, 300.0)), Some((3000.0, 20.0))),
    )
    .unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_allan_kalibr"))
        .arg(&mat)
        .args(["-q", "-o"])
        .arg(dir.path().join("o"))
        .output()
        .unwrap();
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "{err}");
    assert!(
        !out.contains("WARNING") && !err.contains("WARNING"),
        "{out}\n{err}"
    );
    assert!(
        !out.lines().any(|l| l.trim_start().starts_with("warning")),
        "a warning on stdout: {out}"
    );
    for what in ["gap", "warm-up"] {
        assert!(
            err.lines()
                .any(|l| l.starts_with("warning: ") && l.contains(what)),
            "no warning about {what}: {err}"
        );
    }
}
