//! Issue 19's numbered defects in allan_kalibr's outputs and messages (the reader's are in
//! bag2mat's tests), each kept fixed by the test named after it.

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

use bag2mat::mat::{DataImu, write_data_imu};

/// Slows every step of an output commit (bag2mat's test hook), as a slow file system would.
const SLOW_COMMIT_MS: &str = "400";

/// A small .mat of white noise at 100 Hz (seeded LCG), `n` rows.
fn noise_mat(path: &Path, n: usize, seed: u64) {
    let mut d = DataImu::with_capacity(n);
    let mut s: u64 = seed;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    for i in 0..n {
        d.push([
            1.7e9 + i as f64 * 0.01,
            next(),
            next(),
            9.81 + next(),
            next() * 1e-3,
            next() * 1e-3,
            next() * 1e-3,
        ]);
    }
    write_data_imu(path, &d).unwrap();
}

fn kalibr(input: &Path, out: &Path, delay: Option<&str>) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_allan_kalibr"));
    c.arg(input)
        .args(["--update-rate", "100", "-q", "-o"])
        .arg(out)
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
fn defect_19_5_all_or_none_across_concurrent_runs_and_a_kill() {
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
