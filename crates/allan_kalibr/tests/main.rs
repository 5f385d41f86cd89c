//! Integration tests of allan_kalibr: parity with the real kalibr_allan outputs in
//! `testdata/` (reference.rs), the binary run as a user would (cli.rs) and its IEEE 952 side:
//! other tools' curves, warm-up and gap checks (ieee952.rs); the studies of the IEEE 952
//! estimator on simulated and real data (studies.rs, the long ones `#[ignore]`d).

mod check;
mod cli;
mod common;
mod consumers;
mod files;
mod front;
mod ieee952;
mod integrated_deltas;
mod logs;
mod operating;
mod outputs_and_messages;
mod plan;
mod record_checks;
mod reference;
mod several_topics;
mod studies;
mod uncertainty;
