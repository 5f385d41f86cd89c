//! Integration tests of bag2mat: parity with the real bagconvert on the reference bags,
//! round trips through our writer and reader, the real ROS and MATLAB-format tools reading
//! what we write, and the command line as a user runs it.

mod cli;
mod common;
mod damaged_logs;
mod damaged_mcap;
mod duplicated_rows;
mod info_report;
mod logs;
mod phone_exports;
mod poses;
mod real_tools;
mod reference;
mod ros1_damage_and_outputs;
mod ros2;
mod ros2_damage_and_outputs;
mod roundtrip;
mod two_sensors;
mod unit_physics;
mod warmup_power;
