//! `sensor_msgs/Imu`: the ROS 1 serialized layout, its md5 and its full message definition.
//!
//! The layout is fixed apart from `header.frame_id`, so encoding and decoding are written by
//! hand (docs/formats.md §5.1): little-endian, no alignment padding, strings as a u32 length
//! plus bytes, fixed arrays without a length prefix. The definition text is genpy's
//! `_full_text`, assembled from the four vendored `.msg` files exactly as genpy does (§5.3),
//! and tested byte for byte against it.

use std::sync::LazyLock;

use crate::cursor::Cursor;
use crate::time::RosTime;

/// The smallest payload a decodable `sensor_msgs/Imu` has (ROS 1: 16 header bytes and 37
/// doubles; CDR: 4 encapsulation bytes, the stamp, an empty frame_id and 37 aligned doubles):
/// a part of `bytes` bytes holds at most `bytes / MIN_IMU_PAYLOAD` rows, whatever its index
/// says.
pub const MIN_IMU_PAYLOAD: u64 = 16 + 37 * 8;

/// The ROS type name.
pub const TYPE: &str = "sensor_msgs/Imu";
/// The ROS 1 md5 of `sensor_msgs/Imu` (genpy's `Imu._md5sum`).
pub const MD5: &str = "6a62c6daae103f4ff57a132d6f95cec2";

const IMU_MSG: &str = include_str!("../msg/sensor_msgs_Imu.msg");
/// The dependencies in genpy's order, with the raw text of each `.msg` file.
const DEPENDENCIES: [(&str, &str); 3] = [
    (
        "std_msgs/Header",
        include_str!("../msg/std_msgs_Header.msg"),
    ),
    (
        "geometry_msgs/Quaternion",
        include_str!("../msg/geometry_msgs_Quaternion.msg"),
    ),
    (
        "geometry_msgs/Vector3",
        include_str!("../msg/geometry_msgs_Vector3.msg"),
    ),
];

static DEFINITION_TEXT: LazyLock<String> = LazyLock::new(|| {
    // genpy: the message text, then each dependency after a blank line, a line of 80 '=' and
    // `MSG: pkg/Type`. Trailing newlines are stripped from every file; nothing else is trimmed
    // (several lines end in spaces that are part of the text the md5 of readers is built on).
    let mut text = IMU_MSG.trim_end_matches('\n').to_string();
    for (name, body) in DEPENDENCIES {
        text.push_str("\n\n");
        text.push_str(&"=".repeat(80));
        text.push_str("\nMSG: ");
        text.push_str(name);
        text.push('\n');
        text.push_str(body.trim_end_matches('\n'));
    }
    text
});

/// The full message definition written into a bag's connection record (2571 bytes).
pub fn definition() -> &'static str {
    &DEFINITION_TEXT
}

/// One `sensor_msgs/Imu` message. Vectors are `[x, y, z]`, the quaternion `[x, y, z, w]`,
/// covariances row-major 3×3. Units as in ROS: rad/s and m/s².
#[derive(Debug, Clone, PartialEq)]
pub struct Imu {
    /// `header.seq`.
    pub seq: u32,
    /// `header.stamp`: the sensor's time of the sample.
    pub stamp: RosTime,
    /// `header.frame_id`.
    pub frame_id: String,
    /// Orientation quaternion `[x, y, z, w]`.
    pub orientation: [f64; 4],
    /// Orientation covariance; `[0] = -1` means "no orientation".
    pub orientation_covariance: [f64; 9],
    /// Angular velocity, rad/s.
    pub angular_velocity: [f64; 3],
    /// Angular velocity covariance.
    pub angular_velocity_covariance: [f64; 9],
    /// Linear acceleration (specific force), m/s².
    pub linear_acceleration: [f64; 3],
    /// Linear acceleration covariance.
    pub linear_acceleration_covariance: [f64; 9],
}

impl Default for Imu {
    fn default() -> Self {
        Imu {
            seq: 0,
            stamp: RosTime::default(),
            frame_id: String::new(),
            orientation: [0.0; 4],
            orientation_covariance: [0.0; 9],
            angular_velocity: [0.0; 3],
            angular_velocity_covariance: [0.0; 9],
            linear_acceleration: [0.0; 3],
            linear_acceleration_covariance: [0.0; 9],
        }
    }
}

/// Doubles after `frame_id`, in the order ROS 1 and CDR both serialize them: orientation (4),
/// its covariance (9), angular velocity (3), its covariance (9), linear acceleration (3), its
/// covariance (9).
pub(crate) const BODY_DOUBLES: usize = 37;
/// Serialized size of everything after `frame_id`.
const BODY_LEN: usize = BODY_DOUBLES * 8;
/// Index of `angular_velocity.x` among the body doubles.
const GYRO_AT: usize = 13;
/// Index of `linear_acceleration.x` among the body doubles.
const ACC_AT: usize = 25;

/// A message whose bytes do not decode as `sensor_msgs/Imu`; the library reports it as
/// [`crate::Error::BadMessage`] (this module stays below the error type).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct BadMessage(pub String);

/// The part of a message the analysers need, decoded without allocating.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuSample {
    /// `header.seq`.
    pub seq: u32,
    /// `header.stamp`.
    pub stamp: RosTime,
    /// Angular velocity, rad/s.
    pub gyro: [f64; 3],
    /// Linear acceleration, m/s².
    pub acc: [f64; 3],
}

impl Imu {
    /// Serialized length in bytes: 312 + the length of `frame_id`.
    pub fn encoded_len(&self) -> usize {
        16 + self.frame_id.len() + BODY_LEN
    }

    /// The [`BODY_DOUBLES`] body values in serialization order (ROS 1 and CDR alike).
    pub(crate) fn body(&self) -> impl Iterator<Item = f64> + '_ {
        self.orientation
            .iter()
            .chain(&self.orientation_covariance)
            .chain(&self.angular_velocity)
            .chain(&self.angular_velocity_covariance)
            .chain(&self.linear_acceleration)
            .chain(&self.linear_acceleration_covariance)
            .copied()
    }

    /// A message from its header fields and its body, `body(i)` being double `i` of
    /// [`Imu::body`]'s order.
    pub(crate) fn from_body(
        seq: u32,
        stamp: RosTime,
        frame_id: &[u8],
        body: impl Fn(usize) -> f64,
    ) -> Imu {
        let mut d = [0.0f64; BODY_DOUBLES];
        for (i, v) in d.iter_mut().enumerate() {
            *v = body(i);
        }
        let mut imu = Imu {
            seq,
            stamp,
            frame_id: String::from_utf8_lossy(frame_id).into_owned(),
            ..Imu::default()
        };
        imu.orientation.copy_from_slice(&d[0..4]);
        imu.orientation_covariance.copy_from_slice(&d[4..13]);
        imu.angular_velocity.copy_from_slice(&d[13..16]);
        imu.angular_velocity_covariance.copy_from_slice(&d[16..25]);
        imu.linear_acceleration.copy_from_slice(&d[25..28]);
        imu.linear_acceleration_covariance
            .copy_from_slice(&d[28..37]);
        imu
    }

    /// Appends the ROS 1 serialization of `self` to `out`.
    pub fn encode(&self, out: &mut Vec<u8>) {
        out.reserve(self.encoded_len());
        out.extend_from_slice(&self.seq.to_le_bytes());
        out.extend_from_slice(&self.stamp.sec.to_le_bytes());
        out.extend_from_slice(&self.stamp.nsec.to_le_bytes());
        out.extend_from_slice(&(self.frame_id.len() as u32).to_le_bytes());
        out.extend_from_slice(self.frame_id.as_bytes());
        for v in self.body() {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }

    /// Decodes a whole message; errors if `data` is not exactly one Imu.
    pub fn decode(data: &[u8]) -> Result<Imu, BadMessage> {
        let (head, frame_id, body) = split(data)?;
        Ok(Imu::from_body(head.0, head.1, frame_id, |i| {
            f64_at(body, i)
        }))
    }
}

impl ImuSample {
    /// Seq, stamp, gyro and acc, `body(i)` being double `i` of [`Imu::body`]'s order.
    pub(crate) fn from_body(seq: u32, stamp: RosTime, body: impl Fn(usize) -> f64) -> ImuSample {
        ImuSample {
            seq,
            stamp,
            gyro: [body(GYRO_AT), body(GYRO_AT + 1), body(GYRO_AT + 2)],
            acc: [body(ACC_AT), body(ACC_AT + 1), body(ACC_AT + 2)],
        }
    }

    /// Decodes seq, stamp, gyro and acc from a serialized Imu, skipping the rest.
    pub(crate) fn decode(data: &[u8]) -> Result<ImuSample, BadMessage> {
        let ((seq, stamp), _, body) = split(data)?;
        Ok(ImuSample::from_body(seq, stamp, |i| f64_at(body, i)))
    }
}

type Head = (u32, RosTime);

/// Splits a serialized Imu into (seq, stamp), frame_id bytes and the fixed body.
fn split(data: &[u8]) -> Result<(Head, &[u8], &[u8]), BadMessage> {
    let mut c = Cursor::new(data);
    let head = (|| {
        Ok::<_, crate::cursor::CursorError>((
            c.le::<u32>("seq")?,
            c.le::<u32>("sec")?,
            c.le::<u32>("nsec")?,
            c.le::<u32>("frame_id length")?,
        ))
    })();
    let Ok((seq, sec, nsec, id_len)) = head else {
        return Err(BadMessage(format!(
            "Imu message of {} bytes is shorter than its header",
            data.len()
        )));
    };
    let id_len = id_len as usize;
    let expected = 16usize
        .checked_add(id_len)
        .and_then(|n| n.checked_add(BODY_LEN));
    if expected != Some(data.len()) {
        return Err(BadMessage(format!(
            "Imu message of {} bytes does not match its frame_id length {id_len} (expected {} bytes)",
            data.len(),
            16u64 + id_len as u64 + BODY_LEN as u64
        )));
    }
    let rest = c.rest();
    let stamp = RosTime { sec, nsec };
    Ok(((seq, stamp), &rest[..id_len], &rest[id_len..]))
}

/// Body double `i` (the body is [`BODY_LEN`] bytes: checked by [`split`]).
fn f64_at(body: &[u8], i: usize) -> f64 {
    let mut b = [0u8; 8];
    b.copy_from_slice(&body[8 * i..8 * i + 8]);
    f64::from_le_bytes(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn encode_decode_round_trip() {
        let imu = Imu {
            seq: 42,
            stamp: RosTime {
                sec: 1_600_000_000,
                nsec: 999_999_999,
            },
            frame_id: "base_link".into(),
            orientation: [0.1, 0.2, 0.3, 0.9],
            orientation_covariance: [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0],
            angular_velocity: [1e-300, -0.0, f64::MAX],
            angular_velocity_covariance: [-1.0; 9],
            linear_acceleration: [0.5, -9.81, 1e10],
            linear_acceleration_covariance: [0.25; 9],
        };
        let mut buf = Vec::new();
        imu.encode(&mut buf);
        assert_eq!(buf.len(), 312 + 9);
        assert_eq!(Imu::decode(&buf).unwrap(), imu);
        let s = ImuSample::decode(&buf).unwrap();
        assert_eq!(
            (s.seq, s.stamp, s.gyro, s.acc),
            (42, imu.stamp, imu.angular_velocity, imu.linear_acceleration)
        );
    }

    #[test]
    fn truncated_message_is_an_error() {
        let mut buf = Vec::new();
        Imu::default().encode(&mut buf);
        for len in [0, 15, 16, buf.len() - 1] {
            assert!(ImuSample::decode(&buf[..len]).is_err(), "len {len}");
        }
        buf.push(0);
        assert!(Imu::decode(&buf).is_err());
    }
}
