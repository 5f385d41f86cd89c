//! Benchmark input: a long synthetic IMU recording (white noise σ/√Δt plus a bias random
//! walk σ_b·√Δt per sample, the Kalibr model; gravity on acc z), written as an uncompressed
//! bag (topic `imu`, record time = header stamp) and/or a bagconvert-layout `.mat`.
//!
//! `cargo run --release -p allan_kalibr --example synth_bag -- OUT.bag [HOURS] [RATE] [--mat OUT.mat]`
//! (defaults: 4 h at 200 Hz). Not part of the tests; the workspace's `sim` crate is the
//! general simulator.

use std::path::PathBuf;

use bag2mat::BagWriter;
use bag2mat::Imu;
use bag2mat::{Compression, RosTime};
use bag2mat::{DataImu, write_data_imu};

/// Seed of the generator (fixed: the benchmark input is reproducible).
const SEED: u64 = 0x4a11_ba9c;
/// Continuous-time noise of the synthetic sensor (p1's values).
const SIGMA_W: f64 = 0.03;
const SIGMA_B: f64 = 1e-4;
const T0_NS: u64 = 1_600_000_000_000_000_000;

struct Rng(u64);
impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        (((z ^ (z >> 31)) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut pos = Vec::new();
    let mut mat: Option<PathBuf> = None;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        if a == "--mat" {
            mat = it.next().map(PathBuf::from);
        } else {
            pos.push(a.clone());
        }
    }
    let bag = pos.first().map(PathBuf::from);
    let hours: f64 = pos.get(1).map(|s| s.parse()).transpose()?.unwrap_or(4.0);
    let rate: f64 = pos.get(2).map(|s| s.parse()).transpose()?.unwrap_or(200.0);
    let n = (hours * 3600.0 * rate).round() as usize;
    let dt = 1.0 / rate;
    let mut rng = Rng(SEED);
    let mut bias = [0.0; 6];
    let mut writer = match &bag {
        Some(p) if p.to_string_lossy() != "-" => Some(BagWriter::create(
            &bag2mat::shared::output::Outputs::direct(),
            p,
            Compression::None,
        )?),
        _ => None,
    };
    let conn = writer.as_mut().map(|w| w.add_imu_connection("imu"));
    let mut data = mat.as_ref().map(|_| DataImu::with_capacity(n));
    let mut msg = Imu {
        frame_id: "imu_link".into(),
        ..Imu::default()
    };
    for i in 0..n {
        let mut v = [0.0; 6];
        for (a, val) in v.iter_mut().enumerate() {
            bias[a] += SIGMA_B * dt.sqrt() * rng.normal();
            *val = bias[a] + SIGMA_W / dt.sqrt() * rng.normal();
        }
        v[2] += 9.81;
        let t = RosTime::from_nanos(T0_NS + (i as f64 * dt * 1e9).round() as u64);
        if let (Some(w), Some(c)) = (writer.as_mut(), conn) {
            msg.seq = i as u32;
            msg.stamp = t;
            msg.linear_acceleration = [v[0], v[1], v[2]];
            msg.angular_velocity = [v[3], v[4], v[5]];
            w.write_imu(c, t, &msg)?;
        }
        if let Some(d) = data.as_mut() {
            d.push([t.to_sec(), v[0], v[1], v[2], v[3], v[4], v[5]]);
        }
    }
    if let Some(w) = writer {
        w.finish()?;
    }
    if let (Some(p), Some(d)) = (mat, data) {
        write_data_imu(&bag2mat::shared::output::Outputs::direct(), &p, &d)?;
    }
    eprintln!("{n} samples at {rate} Hz ({hours} h)");
    Ok(())
}
