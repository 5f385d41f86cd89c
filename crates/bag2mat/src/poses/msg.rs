//! The pose and odometry messages a reference trajectory comes in, decoded to a stamp, a
//! position and an orientation, in ROS 1 serialization and in CDR (ROS 2):
//!
//! * `geometry_msgs/PoseStamped`: header, pose (position, orientation);
//! * `geometry_msgs/PoseWithCovarianceStamped`: header, pose, its 6×6 covariance;
//! * `nav_msgs/Odometry`: header, `child_frame_id`, pose with covariance, twist (not read);
//! * `geometry_msgs/TransformStamped`: header, `child_frame_id`, translation, rotation.
//!
//! ROS 1 packs every field little-endian without padding, a string as a u32 length and its
//! bytes, and has `header.seq`. CDR (XCDR1, plain) starts with a 4-byte encapsulation header
//! (`00 01` little-endian, `00 00` big-endian), has no `seq`, writes a string as a u32
//! length counting a terminating NUL, and aligns each primitive to its size counted from
//! after the encapsulation header. Only what precedes the pose is walked; what follows it
//! (a covariance, a twist) is not read.

use crate::time::RosTime;

/// The message types read, by their ROS 1 name (the ROS 2 name has `/msg/` inserted).
pub const POSE_TYPES: [&str; 4] = [
    "geometry_msgs/PoseStamped",
    "geometry_msgs/PoseWithCovarianceStamped",
    "nav_msgs/Odometry",
    "geometry_msgs/TransformStamped",
];

/// Which of [`POSE_TYPES`] a channel carries (`pkg/msg/Type` and `pkg/Type` alike).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PoseType {
    /// `geometry_msgs/PoseStamped`.
    PoseStamped,
    /// `geometry_msgs/PoseWithCovarianceStamped`.
    PoseWithCovarianceStamped,
    /// `nav_msgs/Odometry`.
    Odometry,
    /// `geometry_msgs/TransformStamped`.
    TransformStamped,
}

impl PoseType {
    /// The type a channel's type name stands for, if it is one of ours.
    pub fn of(msg_type: &str) -> Option<PoseType> {
        let plain = msg_type.replacen("/msg/", "/", 1);
        Some(match plain.as_str() {
            "geometry_msgs/PoseStamped" => PoseType::PoseStamped,
            "geometry_msgs/PoseWithCovarianceStamped" => PoseType::PoseWithCovarianceStamped,
            "nav_msgs/Odometry" => PoseType::Odometry,
            "geometry_msgs/TransformStamped" => PoseType::TransformStamped,
            _ => return None,
        })
    }

    /// A `child_frame_id` string sits between the header and the pose.
    fn has_child_frame(self) -> bool {
        matches!(self, PoseType::Odometry | PoseType::TransformStamped)
    }
}

/// One decoded pose: `header.stamp`, position (m) and orientation `[x, y, z, w]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseMsg {
    /// `header.stamp`.
    pub stamp: RosTime,
    /// Position (translation), m.
    pub position: [f64; 3],
    /// Orientation (rotation) quaternion `[x, y, z, w]`, as recorded.
    pub orientation: [f64; 4],
}

/// How the payload is serialized.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wire {
    /// ROS 1.
    Ros1,
    /// CDR (ROS 2).
    Cdr,
}

/// A bounds-checked reader of one payload: ROS 1 (no alignment, little-endian) or CDR
/// (aligned from `origin`, either byte order).
struct Reader<'a> {
    data: &'a [u8],
    at: usize,
    origin: usize,
    align: bool,
    big: bool,
}

impl Reader<'_> {
    fn take(&mut self, n: usize, what: &str) -> Result<&[u8], String> {
        if self.align {
            let rel = self.at - self.origin;
            self.at = self.origin + rel.div_ceil(n.min(8)) * n.min(8);
        }
        let end = self.at.checked_add(n).filter(|&e| e <= self.data.len());
        let Some(end) = end else {
            return Err(format!(
                "message of {} bytes ends inside its {what}",
                self.data.len()
            ));
        };
        let s = &self.data[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn u32(&mut self, what: &str) -> Result<u32, String> {
        let b: [u8; 4] = self
            .take(4, what)?
            .try_into()
            .map_err(|_| what.to_string())?;
        Ok(if self.big {
            u32::from_be_bytes(b)
        } else {
            u32::from_le_bytes(b)
        })
    }

    fn f64(&mut self, what: &str) -> Result<f64, String> {
        let b: [u8; 8] = self
            .take(8, what)?
            .try_into()
            .map_err(|_| what.to_string())?;
        Ok(if self.big {
            f64::from_be_bytes(b)
        } else {
            f64::from_le_bytes(b)
        })
    }

    /// Skips a string (its length, its bytes; CDR's length counts the NUL).
    fn skip_string(&mut self, what: &str) -> Result<(), String> {
        let n = self.u32(what)? as usize;
        let saved = self.align;
        self.align = false;
        self.take(n, what)?;
        self.align = saved;
        Ok(())
    }
}

/// Decodes the stamp and pose of a message of type `ty` serialized as `wire`.
pub fn decode(ty: PoseType, wire: Wire, data: &[u8]) -> Result<PoseMsg, String> {
    let mut r = match wire {
        Wire::Ros1 => Reader {
            data,
            at: 0,
            origin: 0,
            align: false,
            big: false,
        },
        Wire::Cdr => {
            let big = match data.get(..2) {
                Some([0, 1]) => false,
                Some([0, 0]) => true,
                Some([a, b]) => {
                    return Err(format!(
                        "unsupported CDR encapsulation {a:02x} {b:02x} (plain CDR 00 00 or 00 01 expected)"
                    ));
                }
                _ => return Err("CDR message shorter than its encapsulation header".into()),
            };
            Reader {
                data,
                at: 4,
                origin: 4,
                align: true,
                big,
            }
        }
    };
    if data.len() < r.at {
        return Err("CDR message shorter than its encapsulation header".into());
    }
    if wire == Wire::Ros1 {
        r.u32("header.seq")?;
    }
    let sec = r.u32("header.stamp")?;
    let nsec = r.u32("header.stamp")?;
    r.skip_string("header.frame_id")?;
    if ty.has_child_frame() {
        r.skip_string("child_frame_id")?;
    }
    let mut position = [0.0; 3];
    for v in position.iter_mut() {
        *v = r.f64("position")?;
    }
    let mut orientation = [0.0; 4];
    for v in orientation.iter_mut() {
        *v = r.f64("orientation")?;
    }
    if nsec >= 1_000_000_000 {
        return Err(format!("header.stamp nanoseconds {nsec} ≥ 1e9"));
    }
    Ok(PoseMsg {
        stamp: RosTime { sec, nsec },
        position,
        orientation,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The test's own writer of the ROS 1 and CDR layouts (module docs), field by field.
    fn encode(ty: PoseType, wire: Wire, big: bool, m: &PoseMsg, frame: &str) -> Vec<u8> {
        let mut out = Vec::new();
        let origin = if wire == Wire::Cdr { 4 } else { 0 };
        if wire == Wire::Cdr {
            out.extend_from_slice(if big { &[0, 0, 0, 0] } else { &[0, 1, 0, 0] });
        }
        let pad = |out: &mut Vec<u8>, n: usize| {
            if wire == Wire::Cdr {
                while !(out.len() - origin).is_multiple_of(n) {
                    out.push(0);
                }
            }
        };
        let u32w = |out: &mut Vec<u8>, v: u32| {
            pad(out, 4);
            out.extend_from_slice(&if big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            });
        };
        let f64w = |out: &mut Vec<u8>, v: f64| {
            pad(out, 8);
            out.extend_from_slice(&if big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            });
        };
        let strw = |out: &mut Vec<u8>, s: &str| {
            if wire == Wire::Cdr {
                u32w(out, s.len() as u32 + 1);
                out.extend_from_slice(s.as_bytes());
                out.push(0);
            } else {
                u32w(out, s.len() as u32);
                out.extend_from_slice(s.as_bytes());
            }
        };
        if wire == Wire::Ros1 {
            u32w(&mut out, 7);
        }
        u32w(&mut out, m.stamp.sec);
        u32w(&mut out, m.stamp.nsec);
        strw(&mut out, frame);
        if ty.has_child_frame() {
            strw(&mut out, "child");
        }
        for v in m.position {
            f64w(&mut out, v);
        }
        for v in m.orientation {
            f64w(&mut out, v);
        }
        // what follows the pose (covariance, twist) is not read
        if matches!(ty, PoseType::PoseWithCovarianceStamped | PoseType::Odometry) {
            for k in 0..36 {
                f64w(&mut out, k as f64);
            }
        }
        out
    }

    #[test]
    fn every_type_decodes_in_ros1_and_both_cdr_byte_orders() {
        let m = PoseMsg {
            stamp: RosTime {
                sec: 1_700_000_123,
                nsec: 456_789_012,
            },
            position: [1.5, -2.25, 3.125],
            orientation: [0.1, -0.2, 0.3, 0.9273618495495703],
        };
        for name in POSE_TYPES {
            let ty = PoseType::of(name).unwrap();
            let ros2 = name.replacen('/', "/msg/", 1);
            assert_eq!(PoseType::of(&ros2), Some(ty));
            // frame ids of every length modulo 8 move the CDR padding
            for frame in ["", "a", "map", "vicon/body", "0123456"] {
                for (wire, big) in [(Wire::Ros1, false), (Wire::Cdr, false), (Wire::Cdr, true)] {
                    let bytes = encode(ty, wire, big, &m, frame);
                    assert_eq!(
                        decode(ty, wire, &bytes),
                        Ok(m),
                        "{name} {wire:?} big {big} frame {frame:?}"
                    );
                    // cut inside the pose: an error, never a panic
                    let cut = &bytes[..bytes.len().min(40)];
                    assert!(decode(ty, wire, cut).is_err(), "{name} {wire:?} cut");
                }
            }
        }
        assert_eq!(PoseType::of("sensor_msgs/Imu"), None);
        assert!(decode(PoseType::PoseStamped, Wire::Cdr, &[1, 2]).is_err());
    }
}
