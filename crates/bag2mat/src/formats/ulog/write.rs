//! A ULog writer, for tests and benchmarks: the definitions, subscriptions, data, dropout
//! and sync messages of the format, and [`imu_log`], a log of the IMU topics PX4 writes
//! (with their real field layouts) that pyulog reads.

use std::io::{self, Write};

/// Writes a ULog file message by message.
pub struct Writer<W: Write> {
    w: W,
}

impl<W: Write> Writer<W> {
    /// The file header (version 1, start time `start_us`) and a flag-bits message.
    pub fn new(mut w: W, start_us: u64) -> io::Result<Writer<W>> {
        w.write_all(super::MAGIC)?;
        w.write_all(&[1])?;
        w.write_all(&start_us.to_le_bytes())?;
        let mut me = Writer { w };
        me.message(b'B', &[0u8; 40])?;
        Ok(me)
    }

    /// One message: size, type, body.
    pub fn message(&mut self, ty: u8, body: &[u8]) -> io::Result<()> {
        let n = u16::try_from(body.len())
            .map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "ULog message over 64 KiB"))?;
        self.w.write_all(&n.to_le_bytes())?;
        self.w.write_all(&[ty])?;
        self.w.write_all(body)
    }

    /// A format: `name:type field;…`.
    pub fn format(&mut self, text: &str) -> io::Result<()> {
        self.message(b'F', text.as_bytes())
    }

    /// An information message: `key` is `type name` (`char[5] sys_name`).
    pub fn info(&mut self, key: &str, value: &[u8]) -> io::Result<()> {
        let mut b = vec![key.len() as u8];
        b.extend_from_slice(key.as_bytes());
        b.extend_from_slice(value);
        self.message(b'I', &b)
    }

    /// Subscribes message id `id` to instance `multi_id` of format `name`.
    pub fn add(&mut self, multi_id: u8, id: u16, name: &str) -> io::Result<()> {
        let mut b = vec![multi_id];
        b.extend_from_slice(&id.to_le_bytes());
        b.extend_from_slice(name.as_bytes());
        self.message(b'A', &b)
    }

    /// A data message of subscription `id` (`payload` starts with the timestamp).
    pub fn data(&mut self, id: u16, payload: &[u8]) -> io::Result<()> {
        let mut b = Vec::with_capacity(payload.len() + 2);
        b.extend_from_slice(&id.to_le_bytes());
        b.extend_from_slice(payload);
        self.message(b'D', &b)
    }

    /// A dropout of `ms` milliseconds.
    pub fn dropout(&mut self, ms: u16) -> io::Result<()> {
        self.message(b'O', &ms.to_le_bytes())
    }

    /// A sync marker.
    pub fn sync(&mut self) -> io::Result<()> {
        self.message(b'S', &super::SYNC)
    }

    /// The underlying writer.
    pub fn finish(mut self) -> io::Result<W> {
        self.w.flush()?;
        Ok(self.w)
    }
}

/// PX4's `sensor_combined` (v1.14 field layout).
pub const SENSOR_COMBINED: &str = "sensor_combined:uint64_t timestamp;float[3] gyro_rad;uint32_t gyro_integral_dt;int32_t accelerometer_timestamp_relative;float[3] accelerometer_m_s2;uint32_t accelerometer_integral_dt;uint8_t accelerometer_clipping;uint8_t gyro_clipping;uint8_t accel_calibration_count;uint8_t gyro_calibration_count;";
/// PX4's `sensor_gyro`.
pub const SENSOR_GYRO: &str = "sensor_gyro:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float x;float y;float z;float temperature;uint32_t error_count;uint8_t[3] clip_counter;uint8_t samples;";
/// PX4's `sensor_accel`.
pub const SENSOR_ACCEL: &str = "sensor_accel:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float x;float y;float z;float temperature;uint32_t error_count;uint8_t[3] clip_counter;uint8_t samples;";
/// PX4's `vehicle_imu`.
pub const VEHICLE_IMU: &str = "vehicle_imu:uint64_t timestamp;uint64_t timestamp_sample;uint32_t accel_device_id;uint32_t gyro_device_id;float[3] delta_angle;float[3] delta_velocity;uint16_t delta_angle_dt;uint16_t delta_velocity_dt;uint8_t delta_angle_clipping;uint8_t delta_velocity_clipping;uint8_t accel_calibration_count;uint8_t gyro_calibration_count;";
/// PX4's `sensor_gyro_fifo` (fields in the logger's size order, padded to 8 bytes; the
/// logger writes messages without the trailing padding).
pub const SENSOR_GYRO_FIFO: &str = "sensor_gyro_fifo:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float dt;float scale;int16_t[32] x;int16_t[32] y;int16_t[32] z;uint8_t samples;uint8_t rotation;uint8_t[2] _padding0;";
/// PX4's `sensor_accel_fifo`.
pub const SENSOR_ACCEL_FIFO: &str = "sensor_accel_fifo:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float dt;float scale;int16_t[32] x;int16_t[32] y;int16_t[32] z;uint8_t samples;uint8_t rotation;uint8_t[2] _padding0;";

/// Writes a log of PX4's raw FIFO topics: `sensor_gyro_fifo` and `sensor_accel_fifo`
/// (instance 0 each) at `rate` Hz for `seconds`, `per_msg` samples a message (every third
/// message one fewer, as a FIFO read that came early), int16 noise around a level with
/// PX4's scales (2000 °/s and 16 g full range), and `vehicle_status` once a second.
pub fn fifo_log<W: Write>(w: W, seconds: f64, rate: f64, per_msg: u8, seed: u64) -> io::Result<W> {
    let mut u = Writer::new(w, 0)?;
    u.info("char[5] sys_name", b"PX4_t")?;
    for f in [SENSOR_GYRO_FIFO, SENSOR_ACCEL_FIFO, VEHICLE_STATUS] {
        u.format(f)?;
    }
    u.add(0, 0, "sensor_gyro_fifo")?;
    u.add(0, 1, "sensor_accel_fifo")?;
    u.add(0, 2, "vehicle_status")?;
    let mut state = seed;
    let mut noise = || crate::formats::synthetic_noise(&mut state);
    let dt_us = 1e6 / rate;
    let total = (seconds * rate) as u64;
    let scales = [
        (2000.0f64.to_radians() / 32767.0) as f32,
        (16.0 * 9.80665 / 32767.0) as f32,
    ];
    let (mut done, mut msg, mut next_status) = (0u64, 0u64, 0u64);
    let t0 = 10_000_000f64;
    let mut b = Vec::with_capacity(240);
    while done < total {
        let n = if msg % 3 == 2 {
            per_msg.saturating_sub(1)
        } else {
            per_msg
        };
        let n = (n.clamp(1, 32) as u64).min(total - done) as u8;
        // the newest sample's time
        let newest = (t0 + (done + n as u64 - 1) as f64 * dt_us).round() as u64;
        for (id, scale) in [(0u16, scales[0]), (1u16, scales[1])] {
            let mut xyz = [[0i16; 32]; 3];
            for k in 0..n as usize {
                for (a, col) in xyz.iter_mut().enumerate() {
                    let level = if id == 1 && a == 2 { -2005.0 } else { 0.0 };
                    col[k] = (level + 40.0 * noise()).round() as i16;
                }
            }
            b.clear();
            b.extend_from_slice(&(newest + 200).to_le_bytes());
            b.extend_from_slice(&newest.to_le_bytes());
            b.extend_from_slice(&(0x0024_0000u32 + id as u32).to_le_bytes());
            b.extend_from_slice(&(dt_us as f32).to_le_bytes());
            b.extend_from_slice(&scale.to_le_bytes());
            for col in &xyz {
                for v in col {
                    b.extend_from_slice(&v.to_le_bytes());
                }
            }
            // samples, rotation; PX4's logger leaves the trailing padding out (pyulog
            // takes a longer message for a corrupt one)
            b.extend_from_slice(&[n, 0]);
            u.data(id, &b)?;
        }
        if newest >= next_status {
            b.clear();
            b.extend_from_slice(&newest.to_le_bytes());
            b.extend_from_slice(&[1, 2]);
            u.data(2, &b)?;
            next_status = newest + 1_000_000;
        }
        done += n as u64;
        msg += 1;
    }
    u.finish()
}

/// A topic the tools do not read as Imu.
pub const VEHICLE_STATUS: &str = "vehicle_status:uint64_t timestamp;uint8_t arming_state;uint8_t nav_state;uint8_t[6] _padding0;";

/// What [`imu_log`] writes.
#[derive(Debug, Clone, Copy)]
pub struct ImuLogSpec {
    /// Length, s.
    pub seconds: f64,
    /// Rate of every IMU topic, Hz (vehicle_imu at half of it).
    pub rate: f64,
    /// `sensor_gyro`/`sensor_accel` instances.
    pub instances: u8,
    /// A dropout of this many ms half way through (its samples are not written), if any.
    pub dropout_ms: Option<u16>,
    /// Seed of the samples' noise.
    pub seed: u64,
}

/// Writes a log of PX4's IMU topics at `spec.rate`: `sensor_combined`, `spec.instances`
/// instances of `sensor_gyro` and `sensor_accel`, `vehicle_imu` (deltas over two samples),
/// and `vehicle_status` at 2 Hz, interleaved in time order as the logger writes them.
pub fn imu_log<W: Write>(w: W, spec: &ImuLogSpec) -> io::Result<W> {
    let mut u = Writer::new(w, 0)?;
    declare_imu_topics(&mut u, spec.instances)?;
    let mut state = spec.seed;
    let mut noise = || crate::formats::synthetic_noise(&mut state);
    let n = (spec.seconds * spec.rate) as u64;
    let dt_us = (1e6 / spec.rate).round() as u64;
    let t0 = 10_000_000u64;
    let status_every = (spec.rate / 2.0).round().max(1.0) as u64;
    let mut b = Vec::with_capacity(64);
    // the samples a dropout loses: those of its duration, half way through
    let lost = match spec.dropout_ms {
        Some(ms) => n / 2..n / 2 + (ms as f64 * 1e-3 * spec.rate).round() as u64,
        None => 0..0,
    };
    for i in 0..n {
        let t = t0 + i * dt_us;
        if lost.contains(&i) {
            if i == lost.start {
                u.dropout(spec.dropout_ms.unwrap_or(0))?;
                u.sync()?;
            }
            continue;
        }
        let gyro: [f32; 3] = std::array::from_fn(|_| (1e-3 * noise()) as f32);
        let acc: [f32; 3] =
            std::array::from_fn(|k| (if k == 2 { -9.81 } else { 0.0 } + 0.02 * noise()) as f32);
        combined_body(&mut b, t, gyro, acc, dt_us);
        u.data(0, &b)?;
        for k in 0..spec.instances {
            for (id, v) in [(1 + k as u16, gyro), (64 + k as u16, acc)] {
                let v = v.map(|x| x + (1e-4 * noise()) as f32);
                sensor_body(&mut b, t, k, v);
                u.data(id, &b)?;
            }
        }
        if i % 2 == 1 {
            vehicle_imu_body(&mut b, t, gyro, acc, dt_us);
            u.data(200, &b)?;
        }
        if i % status_every == 0 {
            b.clear();
            b.extend_from_slice(&t.to_le_bytes());
            b.extend_from_slice(&[1, 2, 0, 0, 0, 0, 0, 0]);
            u.data(201, &b)?;
        }
    }
    u.finish()
}

/// The formats and subscriptions of [`imu_log`]: sensor_combined (id 0), `instances` ×
/// sensor_gyro (1 + k) and sensor_accel (64 + k), vehicle_imu (200), vehicle_status (201).
fn declare_imu_topics<W: Write>(u: &mut Writer<W>, instances: u8) -> io::Result<()> {
    u.info("char[5] sys_name", b"PX4_t")?;
    for f in [
        SENSOR_COMBINED,
        SENSOR_GYRO,
        SENSOR_ACCEL,
        VEHICLE_IMU,
        VEHICLE_STATUS,
    ] {
        u.format(f)?;
    }
    u.add(0, 0, "sensor_combined")?;
    for k in 0..instances {
        u.add(k, 1 + k as u16, "sensor_gyro")?;
        u.add(k, 64 + k as u16, "sensor_accel")?;
    }
    u.add(0, 200, "vehicle_imu")?;
    u.add(0, 201, "vehicle_status")?;
    Ok(())
}

fn put_f32s(b: &mut Vec<u8>, v: &[f32]) {
    for x in v {
        b.extend_from_slice(&x.to_le_bytes());
    }
}

/// A sensor_combined message at `t` µs.
fn combined_body(b: &mut Vec<u8>, t: u64, gyro: [f32; 3], acc: [f32; 3], dt_us: u64) {
    b.clear();
    b.extend_from_slice(&t.to_le_bytes());
    put_f32s(b, &gyro);
    b.extend_from_slice(&(dt_us as u32).to_le_bytes());
    b.extend_from_slice(&0i32.to_le_bytes());
    put_f32s(b, &acc);
    b.extend_from_slice(&(dt_us as u32).to_le_bytes());
    b.extend_from_slice(&[0, 0, 1, 1]);
}

/// A sensor_gyro or sensor_accel message of instance `k` (logged 150 µs after `t`,
/// sampled 50·k µs before it).
fn sensor_body(b: &mut Vec<u8>, t: u64, k: u8, v: [f32; 3]) {
    b.clear();
    b.extend_from_slice(&(t + 150).to_le_bytes());
    b.extend_from_slice(&(t - 50 * k as u64).to_le_bytes());
    b.extend_from_slice(&(0x0024_0000u32 + k as u32).to_le_bytes());
    put_f32s(b, &v);
    put_f32s(b, &[35.5]);
    b.extend_from_slice(&0u32.to_le_bytes());
    b.extend_from_slice(&[0, 0, 0, 1]);
}

/// A vehicle_imu message: the deltas over two samples.
fn vehicle_imu_body(b: &mut Vec<u8>, t: u64, gyro: [f32; 3], acc: [f32; 3], dt_us: u64) {
    b.clear();
    b.extend_from_slice(&(t + 300).to_le_bytes());
    b.extend_from_slice(&t.to_le_bytes());
    b.extend_from_slice(&1u32.to_le_bytes());
    b.extend_from_slice(&2u32.to_le_bytes());
    let d = 2.0 * dt_us as f32 * 1e-6;
    put_f32s(b, &gyro.map(|x| x * d));
    put_f32s(b, &acc.map(|x| x * d));
    b.extend_from_slice(&(2 * dt_us as u16).to_le_bytes());
    b.extend_from_slice(&(2 * dt_us as u16).to_le_bytes());
    b.extend_from_slice(&[0, 0, 1, 1]);
}
