//! allan_imu_utils at its limits and in its messages: out of memory is an error, not an
//! abort; warnings are lowercase on stderr and errors plain; --skip-start and the flags that
//! need --curves are checked.

use std::process::{Command, Output};

use crate::cli::write_bag;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_allan_imu_utils"))
}

/// `allan_imu_utils ARGS` under an address-space limit of `kib` KiB (as `ulimit -v`).
fn limited(kib: u64, args: &[&str]) -> Output {
    Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -v {kib}; exec \"$0\" \"$@\"",))
        .arg(env!("CARGO_BIN_EXE_allan_imu_utils"))
        .args(args)
        .output()
        .unwrap()
}

fn s(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// Address-space limits tried, KiB: from what a small run needs down to just above what
/// the tool needs to start (about 22 MB; below that the loader and the thread stacks fail).
const LIMITS_KIB: [u64; 6] = [48_000, 40_000, 34_000, 30_000, 27_000, 24_000];

/// 7: out of memory is `allan_imu_utils: error: out of memory …`, exit 1 — not Rust's
/// `memory allocation of … failed` and SIGABRT — and leaves no output. The run is tried
/// under shrinking address-space limits: each ends whole, or in that error.
#[test]
fn out_of_memory_is_an_error_not_an_abort() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("m.bag");
    write_bag(&bag, 300_000, None);
    let mut failed = 0;
    for (k, kib) in LIMITS_KIB.iter().enumerate() {
        let out = dir.path().join(format!("out{k}"));
        let o = limited(
            *kib,
            &[
                bag.to_str().unwrap(),
                "--topic",
                "/imu",
                "-q",
                "--data-save-path",
                out.to_str().unwrap(),
            ],
        );
        let err = s(&o.stderr);
        if o.status.success() {
            continue;
        }
        failed += 1;
        assert_eq!(o.status.code(), Some(1), "{kib} KiB: {err}");
        assert!(
            err.lines()
                .last()
                .is_some_and(|l| l.starts_with("allan_imu_utils: error: out of memory")),
            "{kib} KiB: {err}"
        );
        assert!(
            !err.contains("memory allocation of") && !err.contains("panicked"),
            "{err}"
        );
        assert!(
            !out.exists(),
            "{kib} KiB: a failed run left its output directory"
        );
    }
    assert!(
        failed > 0,
        "no limit of {LIMITS_KIB:?} KiB ran out of memory"
    );
}

/// 9: a bag shorter than --max-time-min is said on stderr in plain words, never
/// `WARNING:` (and, since issue 41, as information: every ordinary run prints it); a
/// missing --curves path is described plainly (no "os error 2").
#[test]
fn warnings_are_lowercase_on_stderr_and_errors_plain() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("s.bag");
    write_bag(&bag, 12_000, None);
    let o = bin()
        .arg(&bag)
        .args(["--topic", "/imu", "--data-save-path"])
        .arg(dir.path().join("o"))
        .output()
        .unwrap();
    let (out, err) = (s(&o.stdout), s(&o.stderr));
    assert!(o.status.success(), "{err}");
    assert!(
        !out.contains("WARNING") && !err.contains("WARNING"),
        "{out}\n{err}"
    );
    assert!(
        err.lines()
            .any(|l| l.starts_with("bag ended after 12000 messages")),
        "{err}"
    );
    let o = bin()
        .args(["--curves", "/nonexistent/curves.csv"])
        .output()
        .unwrap();
    let err = s(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.starts_with("allan_imu_utils: error:") && !err.contains("os error"),
        "{err}"
    );
}

/// 10: `--skip-start` that leaves almost nothing of the record (29.9 s of 30 s) is an error,
/// not 10 samples analysed into plausible yaml; --duration, --units, --samples, --rate
/// without --curves are a usage error, not ignored.
#[test]
fn skip_start_and_curve_flags_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("t.bag");
    write_bag(&bag, 6000, None); // 30 s at 200 Hz
    let out = dir.path().join("o");
    let skip = |seconds: &str| {
        let o = bin()
            .arg(&bag)
            .args([
                "--topic",
                "/imu",
                "-q",
                "--skip-start",
                seconds,
                "--data-save-path",
            ])
            .arg(&out)
            .output()
            .unwrap();
        (o.status.code(), s(&o.stderr))
    };
    let (code, err) = skip("29.9");
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("--skip-start 29.9 leaves"), "{err}");
    assert!(!out.exists(), "{err}");
    // Dropping most of it is said as a warning.
    let (code, err) = skip("20");
    assert_eq!(code, Some(0), "{err}");
    assert!(
        err.lines()
            .any(|l| l.starts_with("warning: --skip-start 20 drops")),
        "{err}"
    );
    for flags in [
        &["--duration", "3600"][..],
        &["--units", "g"],
        &["--samples", "1000"],
        &["--rate", "200"],
    ] {
        let o = bin().arg(&bag).args(flags).output().unwrap();
        let err = s(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{flags:?}: {err}");
        assert!(
            err.contains("only appl") && err.contains("--curves"),
            "{flags:?}: {err}"
        );
    }
}
