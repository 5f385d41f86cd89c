//! The test support of sim's tests (each crate's is `tests/common.rs`): run the binary, temp dirs.

use std::path::Path;
use std::process::{Command, Output};

/// Fixed start time for reproducible bags.
pub const START: &str = "1700000000";
/// Seed used by the tests.
pub const SEED: &str = "12345";

pub fn sim() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sim"))
}

/// Run `sim args…` in `dir`; returns (success, stdout, stderr).
pub fn run_in(dir: &Path, args: &[&str]) -> (bool, String, String) {
    let out: Output = sim()
        .current_dir(dir)
        .args(args)
        .output()
        .expect("cannot start the sim binary");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Run and require success.
pub fn ok(dir: &Path, args: &[&str]) -> (String, String) {
    let (s, o, e) = run_in(dir, args);
    assert!(s, "sim {args:?} failed:\nstdout:\n{o}\nstderr:\n{e}");
    (o, e)
}
