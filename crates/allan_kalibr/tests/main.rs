//! Integration tests of allan_kalibr: parity with the real kalibr_allan outputs in
//! `testdata/` (reference.rs) and the binary run as a user would (cli.rs).

mod cli;
mod common;
mod consumers;
mod reference;
