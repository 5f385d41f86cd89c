//! Integration tests of allan_imu_utils: parity with the upstream reference outputs in
//! `testdata/` (reference.rs) and the command line as a user runs it (cli.rs).

mod cli;
mod common;
mod fit_reference;
mod reference;
