//! Time stamps as ROS 1 writes them ([`RosTime`]: seconds and nanoseconds since the UNIX
//! epoch): the record time and `header.stamp` of every row, whatever the input. Its own
//! module, below every reader and the columns, so that none depends on the bag reader for it.

use std::fmt;

/// A ROS 1 time: seconds and nanoseconds since the UNIX epoch. All-zero bytes are the
/// default (`Zeroable`), so that columns of them are allocated zeroed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord, Hash, bytemuck::Zeroable)]
pub struct RosTime {
    /// Whole seconds.
    pub sec: u32,
    /// Nanoseconds, `0..1_000_000_000`.
    pub nsec: u32,
}

impl RosTime {
    /// From nanoseconds since the epoch. Saturates at the largest representable second.
    pub fn from_nanos(ns: u64) -> RosTime {
        let sec = (ns / 1_000_000_000).min(u32::MAX as u64) as u32;
        RosTime {
            sec,
            nsec: (ns % 1_000_000_000) as u32,
        }
    }

    /// Nanoseconds since the epoch.
    pub fn as_nanos(self) -> u64 {
        self.sec as u64 * 1_000_000_000 + self.nsec as u64
    }

    /// Seconds as a double, computed as `sec + 1e-9 * nsec`: the conversion of roscpp's
    /// `Time::toSec()` that kalibr_allan's bagconvert writes into the `t` column
    /// (docs/upstream/kalibr_allan.md §1). Other roundings differ in the last bit.
    pub fn to_sec(self) -> f64 {
        self.sec as f64 + 1e-9 * self.nsec as f64
    }

    /// The 8 bytes a bag stores: u32 sec then u32 nsec, little-endian.
    pub fn to_bytes(self) -> [u8; 8] {
        let mut b = [0u8; 8];
        b[..4].copy_from_slice(&self.sec.to_le_bytes());
        b[4..].copy_from_slice(&self.nsec.to_le_bytes());
        b
    }

    /// Reads the 8-byte bag form; `None` when `b` is not 8 bytes long.
    pub(crate) fn from_bytes(b: &[u8]) -> Option<RosTime> {
        if b.len() != 8 {
            return None;
        }
        Some(RosTime {
            sec: u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            nsec: u32::from_le_bytes([b[4], b[5], b[6], b[7]]),
        })
    }
}

impl fmt::Display for RosTime {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}.{:09}", self.sec, self.nsec)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ros_time_nanos_round_trip() {
        for ns in [
            0u64,
            1,
            999_999_999,
            1_000_000_000,
            1_600_000_899_995_000_000,
        ] {
            assert_eq!(RosTime::from_nanos(ns).as_nanos(), ns);
            assert_eq!(
                RosTime::from_bytes(&RosTime::from_nanos(ns).to_bytes()),
                Some(RosTime::from_nanos(ns))
            );
        }
    }

    #[test]
    fn to_sec_is_sec_plus_1e_minus_9_nsec() {
        let t = RosTime {
            sec: 1_600_000_000,
            nsec: 5_000_000,
        };
        assert_eq!(t.to_sec(), 1_600_000_000f64 + 1e-9 * 5_000_000f64);
    }
}
