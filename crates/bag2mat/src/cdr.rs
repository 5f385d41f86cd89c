//! `sensor_msgs/msg/Imu` in CDR, the ROS 2 serialization (XCDR1, plain CDR encapsulation).
//!
//! Layout (docs/formats.md §9.2): a 4-byte encapsulation header (`00 01 00 00` little-endian,
//! `00 00 00 00` big-endian), then `header.stamp` (`int32 sec`, `uint32 nanosec`: ROS 2 has
//! no `seq`), `header.frame_id` (`uint32` length counting the terminating NUL, the bytes, the
//! NUL), zero padding to a multiple of 8 **counted from after the encapsulation header**,
//! and the 37 doubles of the body in the ROS 1 order. The decoder reads straight into the
//! same [`ImuSample`] the ROS 1 codec fills, so both feed the same columns.

use crate::error::Error;
use crate::imu_msg::{BODY_DOUBLES, Imu, ImuSample};
use crate::time::RosTime;

/// The ROS 2 type name.
pub const TYPE: &str = "sensor_msgs/msg/Imu";
/// The ROS 2 type-description hash of `sensor_msgs/msg/Imu` (REP 2011 `RIHS01`), as ROS 2
/// Iron and later record it in `type_description_hash`.
pub const TYPE_HASH: &str =
    "RIHS01_7d9a00ff131080897a5ec7e26e315954b8eae3353c3f995c55faf71574000b5b";
/// The serialization format name rosbag2 stores (`serialization_format`, MCAP
/// `message_encoding`).
pub const ENCODING: &str = "cdr";
/// The schema encoding of a ROS 2 `.msg` definition in MCAP.
pub const SCHEMA_ENCODING: &str = "ros2msg";

/// The `ros2msg` definition: Imu's fields, then each dependency after a line of 80 `=` and
/// `MSG: pkg/Type`, as rosbag2 and the MCAP ROS 2 tooling concatenate them. Field lines only:
/// readers need the structure, not the comments.
pub fn definition() -> String {
    let sep = format!("{}\n", "=".repeat(80));
    let mut s = String::from(
        "std_msgs/Header header\n\
         geometry_msgs/Quaternion orientation\n\
         float64[9] orientation_covariance\n\
         geometry_msgs/Vector3 angular_velocity\n\
         float64[9] angular_velocity_covariance\n\
         geometry_msgs/Vector3 linear_acceleration\n\
         float64[9] linear_acceleration_covariance\n",
    );
    for (name, body) in [
        (
            "std_msgs/Header",
            "builtin_interfaces/Time stamp\nstring frame_id\n",
        ),
        ("builtin_interfaces/Time", "int32 sec\nuint32 nanosec\n"),
        (
            "geometry_msgs/Quaternion",
            "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
        ),
        ("geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n"),
    ] {
        s.push_str(&sep);
        s.push_str("MSG: ");
        s.push_str(name);
        s.push('\n');
        s.push_str(body);
    }
    s
}

/// Encapsulation header of little-endian plain CDR.
const CDR_LE: [u8; 4] = [0, 1, 0, 0];
/// Encapsulation header of big-endian plain CDR.
const CDR_BE: [u8; 4] = [0, 0, 0, 0];

/// Byte order of a CDR payload.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Endian {
    /// `00 01` encapsulation: little-endian (what every ROS 2 machine writes).
    Little,
    /// `00 00` encapsulation: big-endian.
    Big,
}

fn bad(what: String) -> Error {
    Error::BadMessage { what }
}

/// Offset (within the payload, after the 4-byte header) where the doubles start.
fn body_offset(frame_len_with_nul: usize) -> usize {
    (12 + frame_len_with_nul).div_ceil(8) * 8
}

/// Appends the CDR serialization of `imu` (without `seq`, which ROS 2 does not have).
/// Fails when the stamp does not fit ROS 2's `int32 sec` (after 2038-01-19).
pub fn encode(imu: &Imu, endian: Endian, out: &mut Vec<u8>) -> Result<(), Error> {
    let sec = i32::try_from(imu.stamp.sec).map_err(|_| {
        bad(format!(
            "header.stamp {} does not fit ROS 2's int32 seconds",
            imu.stamp
        ))
    })?;
    let start = out.len();
    let id = imu.frame_id.as_bytes();
    let body_at = body_offset(id.len() + 1);
    out.reserve(4 + body_at + BODY_DOUBLES * 8);
    macro_rules! put {
        ($v:expr) => {
            match endian {
                Endian::Little => out.extend_from_slice(&$v.to_le_bytes()),
                Endian::Big => out.extend_from_slice(&$v.to_be_bytes()),
            }
        };
    }
    out.extend_from_slice(match endian {
        Endian::Little => &CDR_LE,
        Endian::Big => &CDR_BE,
    });
    put!(sec);
    put!(imu.stamp.nsec);
    put!((id.len() + 1) as u32);
    out.extend_from_slice(id);
    out.push(0);
    out.resize(start + 4 + body_at, 0);
    for v in imu.body() {
        put!(v);
    }
    Ok(())
}

/// The parts of a CDR Imu: byte order, stamp, frame_id bytes and the 37-double body.
struct Split<'a> {
    endian: Endian,
    stamp: RosTime,
    /// Only the whole-message decoder (the tests' round trips) reads it.
    #[cfg(test)]
    frame_id: &'a [u8],
    body: &'a [u8],
}

fn split(data: &[u8]) -> Result<Split<'_>, Error> {
    if data.len() < 4 + 12 {
        return Err(bad(format!(
            "CDR Imu of {} bytes is shorter than its header",
            data.len()
        )));
    }
    let endian = match [data[0], data[1]] {
        [0, 1] => Endian::Little,
        [0, 0] => Endian::Big,
        [a, b] => {
            return Err(bad(format!(
                "unsupported CDR encapsulation {a:02x} {b:02x} (plain CDR 00 00 or 00 01 expected)"
            )));
        }
    };
    let p = &data[4..];
    let u32_at = |o: usize| {
        let b = [p[o], p[o + 1], p[o + 2], p[o + 3]];
        match endian {
            Endian::Little => u32::from_le_bytes(b),
            Endian::Big => u32::from_be_bytes(b),
        }
    };
    let sec = u32_at(0) as i32;
    let nsec = u32_at(4);
    if sec < 0 || nsec >= 1_000_000_000 {
        return Err(bad(format!(
            "CDR Imu header.stamp {sec} s {nsec} ns is not a time after 1970"
        )));
    }
    let id_len = u32_at(8) as usize;
    let body_at = body_offset(id_len);
    let body = p
        .get(body_at..)
        .filter(|b| b.len() >= BODY_DOUBLES * 8 && id_len <= p.len())
        .ok_or_else(|| {
            bad(format!(
                "CDR Imu of {} bytes is too short for its frame_id length {id_len} (at least {} bytes expected)",
                data.len(),
                4 + body_at as u64 + BODY_DOUBLES as u64 * 8
            ))
        })?;
    // The length counts the terminating NUL; a writer that leaves it out still decodes.
    #[cfg(test)]
    let frame_id = {
        let id = &p[12..12 + id_len];
        id.strip_suffix(&[0]).unwrap_or(id)
    };
    Ok(Split {
        endian,
        stamp: RosTime {
            sec: sec as u32,
            nsec,
        },
        #[cfg(test)]
        frame_id,
        body: &body[..BODY_DOUBLES * 8],
    })
}

fn f64_at(body: &[u8], i: usize, endian: Endian) -> f64 {
    let mut b = [0u8; 8];
    b.copy_from_slice(&body[8 * i..8 * i + 8]);
    match endian {
        Endian::Little => f64::from_le_bytes(b),
        Endian::Big => f64::from_be_bytes(b),
    }
}

/// Decodes stamp, gyro and acc (`seq` is 0: ROS 2 has none) without allocating.
pub(crate) fn decode_sample(data: &[u8]) -> Result<ImuSample, Error> {
    let s = split(data)?;
    Ok(ImuSample::from_body(0, s.stamp, |i| {
        f64_at(s.body, i, s.endian)
    }))
}

/// Decodes a whole message (`seq` = 0).
#[cfg(test)]
pub fn decode(data: &[u8]) -> Result<Imu, Error> {
    let s = split(data)?;
    Ok(Imu::from_body(0, s.stamp, s.frame_id, |i| {
        f64_at(s.body, i, s.endian)
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(frame: &str) -> Imu {
        Imu {
            seq: 0,
            stamp: RosTime {
                sec: 1_700_000_000,
                nsec: 123_456_789,
            },
            frame_id: frame.into(),
            orientation: [0.1, 0.2, 0.3, 0.9],
            orientation_covariance: [-1.0, 0., 0., 0., 0., 0., 0., 0., 2.5],
            angular_velocity: [1e-300, -0.0, 3.5],
            angular_velocity_covariance: [0.5; 9],
            linear_acceleration: [0.25, -9.81, 1e10],
            linear_acceleration_covariance: [0.125; 9],
        }
    }

    /// The layout written out by hand for frame "imu": header, stamp, length 4 ("imu\0"),
    /// 16 bytes so far after the encapsulation, so the doubles start at 16 (no padding);
    /// for "imu_link" (9 with NUL) they start at 24 after 3 bytes of padding.
    #[test]
    fn layout_by_hand() {
        let mut b = Vec::new();
        encode(&sample("imu"), Endian::Little, &mut b).unwrap();
        assert_eq!(&b[..4], &[0, 1, 0, 0]);
        assert_eq!(&b[4..8], &1_700_000_000i32.to_le_bytes());
        assert_eq!(&b[8..12], &123_456_789u32.to_le_bytes());
        assert_eq!(&b[12..16], &4u32.to_le_bytes());
        assert_eq!(&b[16..20], b"imu\0");
        assert_eq!(&b[20..28], &0.1f64.to_le_bytes());
        assert_eq!(b.len(), 4 + 16 + 296);
        let mut b = Vec::new();
        encode(&sample("imu_link"), Endian::Little, &mut b).unwrap();
        assert_eq!(&b[16..25], b"imu_link\0");
        assert_eq!(&b[25..28], &[0, 0, 0]);
        assert_eq!(&b[28..36], &0.1f64.to_le_bytes());
        assert_eq!(b.len(), 4 + 24 + 296);
    }

    #[test]
    fn both_byte_orders_round_trip() {
        for frame in ["", "i", "imu", "base_link", "a_longer_frame_name"] {
            for e in [Endian::Little, Endian::Big] {
                let imu = sample(frame);
                let mut b = Vec::new();
                encode(&imu, e, &mut b).unwrap();
                assert_eq!(decode(&b).unwrap(), imu, "{frame:?} {e:?}");
                let s = decode_sample(&b).unwrap();
                assert_eq!(
                    (s.stamp, s.gyro, s.acc),
                    (imu.stamp, imu.angular_velocity, imu.linear_acceleration)
                );
            }
        }
    }

    #[test]
    fn bad_payloads_are_errors() {
        let mut b = Vec::new();
        encode(&sample("imu"), Endian::Little, &mut b).unwrap();
        for len in [0, 3, 15, 16, b.len() - 1] {
            assert!(decode_sample(&b[..len]).is_err(), "len {len}");
        }
        let mut pl = b.clone();
        pl[1] = 3; // PL_CDR_LE
        assert!(decode_sample(&pl).is_err());
        let mut huge = b.clone();
        huge[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(decode_sample(&huge).is_err());
        let late = Imu {
            stamp: RosTime {
                sec: u32::MAX,
                nsec: 0,
            },
            ..sample("x")
        };
        assert!(encode(&late, Endian::Little, &mut Vec::new()).is_err());
    }
}
