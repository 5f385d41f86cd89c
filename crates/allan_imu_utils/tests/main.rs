//! Integration tests of allan_imu_utils: parity with the upstream reference outputs in
//! `testdata/` (fit_reference.rs: the fit alone on upstream's variances; reference.rs: whole
//! runs on the four bags), the command line as a user runs it (cli.rs) and on other tools'
//! Allan curves (curves.rs).

// `!(err <= tol)` is deliberate: it also fails on NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
#![allow(clippy::needless_range_loop)]

mod cli;
mod common;
mod curves;
mod files;
mod fit_reference;
mod front;
mod integrated_deltas;
mod limits_and_messages;
mod logs;
mod record_checks;
mod reference;
mod ros2;
mod several_topics;
mod stop_rule;
