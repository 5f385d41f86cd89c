//! Integration tests of `sim`: the built binary run as a user would (cli), and its bags read
//! by Debian's real rosbag tools (real_tools). Tools are never skipped: a missing tool fails
//! (scripts/test.sh installs them).

mod cli;
mod common;
mod real_sensors;
mod real_tools;
mod refusals;
