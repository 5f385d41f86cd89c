//! The decoders of the IMU topics a ULog holds (see the parent module for which): how the
//! scalars of one topic's data message become rows.

use std::collections::HashMap;

use super::format::Slot;
use crate::rows::Row;

/// How the messages of one IMU topic become rows.
#[derive(Debug, Clone)]
pub(super) enum Decoder {
    Combined {
        gyro: [Slot; 3],
        acc: [Slot; 3],
    },
    Gyro {
        sample: Option<Slot>,
        v: [Slot; 3],
    },
    Accel {
        sample: Option<Slot>,
        v: [Slot; 3],
    },
    Deltas {
        sample: Option<Slot>,
        angle: [Slot; 3],
        angle_dt: Slot,
        vel: [Slot; 3],
        vel_dt: Slot,
    },
    Fifo {
        acc: bool,
        sample: Option<Slot>,
        dt: Slot,
        scale: Slot,
        samples: Slot,
        /// `x[k]`, `y[k]`, `z[k]` for k below the arrays' length (32 in PX4).
        v: [Vec<Slot>; 3],
    },
}

/// The slots `base[0]`, `base[1]`, … of an array field.
fn array(s: &HashMap<String, Slot>, base: &str) -> Vec<Slot> {
    (0..)
        .map_while(|k| s.get(&format!("{base}[{k}]")).copied())
        .collect()
}

/// The offset, ns, of sample `k` of `n` before the newest one, `dt_us` apart (rounded half
/// up, the same arithmetic as the pyulog cross-check's).
pub(super) fn fifo_offset_ns(n: usize, k: usize, dt_us: f64) -> u64 {
    (((n - 1 - k) as f64) * dt_us * 1000.0 + 0.5).floor() as u64
}

fn three(s: &HashMap<String, Slot>, base: &str) -> Option<[Slot; 3]> {
    let a = |k: usize| s.get(&format!("{base}[{k}]")).copied();
    Some([a(0)?, a(1)?, a(2)?])
}

fn xyz(s: &HashMap<String, Slot>) -> Option<[Slot; 3]> {
    Some([*s.get("x")?, *s.get("y")?, *s.get("z")?])
}

impl Decoder {
    pub(super) fn for_topic(name: &str, s: &HashMap<String, Slot>) -> Option<Decoder> {
        let sample = s.get("timestamp_sample").copied();
        match name {
            "sensor_combined" => Some(Decoder::Combined {
                gyro: three(s, "gyro_rad")?,
                acc: three(s, "accelerometer_m_s2")?,
            }),
            "sensor_gyro" => Some(Decoder::Gyro { sample, v: xyz(s)? }),
            "sensor_accel" => Some(Decoder::Accel { sample, v: xyz(s)? }),
            "sensor_gyro_fifo" | "sensor_accel_fifo" => {
                let v = [array(s, "x"), array(s, "y"), array(s, "z")];
                if v[0].is_empty() || v.iter().any(|a| a.len() != v[0].len()) {
                    return None;
                }
                Some(Decoder::Fifo {
                    acc: name == "sensor_accel_fifo",
                    sample,
                    dt: *s.get("dt")?,
                    scale: *s.get("scale")?,
                    samples: *s.get("samples")?,
                    v,
                })
            }
            "vehicle_imu" => Some(Decoder::Deltas {
                sample,
                angle: three(s, "delta_angle")?,
                angle_dt: *s.get("delta_angle_dt")?,
                vel: three(s, "delta_velocity")?,
                vel_dt: *s.get("delta_velocity_dt")?,
            }),
            _ => None,
        }
    }

    pub(super) fn msg_type(name: &str) -> String {
        format!("px4/{name}")
    }

    /// Rows a data message holds: 1, or a FIFO message's valid samples.
    pub(super) fn rows_in(&self, data: &[u8]) -> usize {
        match self {
            Decoder::Fifo { samples, v, .. } => samples
                .get(data)
                .map_or(0, |n| (n.max(0.0) as usize).min(v[0].len())),
            _ => 1,
        }
    }

    /// Every row of a data message logged at `t_ns` (`data` starts with the timestamp),
    /// each with its record time, or why not.
    pub(super) fn rows(
        &self,
        t_ns: u64,
        data: &[u8],
        mut out: impl FnMut(u64, Row),
    ) -> Result<(), &'static str> {
        let Decoder::Fifo {
            acc,
            sample,
            dt,
            scale,
            v,
            ..
        } = self
        else {
            out(t_ns, self.row(t_ns, data)?);
            return Ok(());
        };
        let short = "message shorter than its format";
        let n = self.rows_in(data);
        let dt = dt.get(data).ok_or(short)?;
        let scale = scale.get(data).ok_or(short)?;
        if n > 1 && (dt.is_nan() || dt <= 0.0) {
            return Err("a FIFO message with a zero dt");
        }
        let newest = sample
            .and_then(|s| s.get_u64(data))
            .map_or(t_ns, |us| us.saturating_mul(1000));
        let slots = v[0].iter().zip(&v[1]).zip(&v[2]).take(n);
        for (k, ((sx, sy), sz)) in slots.enumerate() {
            let mut x = [0.0; 3];
            for (x, s) in x.iter_mut().zip([sx, sy, sz]) {
                *x = s.get(data).ok_or(short)? * scale;
            }
            let off = fifo_offset_ns(n, k, dt);
            let nan = [f64::NAN; 3];
            let (gyro, acc) = if *acc { (nan, x) } else { (x, nan) };
            out(
                t_ns.saturating_sub(off),
                Row {
                    stamp: newest.saturating_sub(off),
                    gyro,
                    acc,
                },
            );
        }
        Ok(())
    }

    /// The row of a one-sample data message (`data` starts with the timestamp), or why not.
    fn row(&self, t_ns: u64, data: &[u8]) -> Result<Row, &'static str> {
        let v3 = |s: &[Slot; 3]| -> Result<[f64; 3], &'static str> {
            let mut v = [0.0; 3];
            for k in 0..3 {
                v[k] = s[k].get(data).ok_or("message shorter than its format")?;
            }
            Ok(v)
        };
        let stamp = |s: &Option<Slot>| -> u64 {
            s.and_then(|s| s.get_u64(data))
                .map_or(t_ns, |us| us.saturating_mul(1000))
        };
        let nan = [f64::NAN; 3];
        Ok(match self {
            Decoder::Combined { gyro, acc } => Row {
                stamp: t_ns,
                gyro: v3(gyro)?,
                acc: v3(acc)?,
            },
            Decoder::Gyro { sample, v } => Row {
                stamp: stamp(sample),
                gyro: v3(v)?,
                acc: nan,
            },
            Decoder::Accel { sample, v } => Row {
                stamp: stamp(sample),
                gyro: nan,
                acc: v3(v)?,
            },
            Decoder::Fifo { .. } => return Err("a FIFO message holds several rows"),
            Decoder::Deltas {
                sample,
                angle,
                angle_dt,
                vel,
                vel_dt,
            } => {
                let da = angle_dt
                    .get(data)
                    .ok_or("message shorter than its format")?;
                let dv = vel_dt.get(data).ok_or("message shorter than its format")?;
                if !(da > 0.0 && dv > 0.0) {
                    return Err("a delta with a zero dt");
                }
                let (a, v) = (v3(angle)?, v3(vel)?);
                Row {
                    stamp: stamp(sample),
                    gyro: a.map(|x| x / (da * 1e-6)),
                    acc: v.map(|x| x / (dv * 1e-6)),
                }
            }
        })
    }
}
