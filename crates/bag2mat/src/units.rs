//! The units an IMU log's columns may be stated in (a text log's header, a flag, a known
//! layout), their names and their factors to SI.
//!
//! A leaf of their own: the text reader parses them (`crate::formats::text`) and the record
//! check names the unit that explains an implausible figure (`crate::record_check::units`),
//! so neither reaches into the other for them.

/// Standard gravity, m/s² (the `g` unit; CGPM 1901).
pub const STANDARD_GRAVITY: f64 = 9.80665;

/// Unit of a time column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TimeUnit {
    /// Seconds.
    S,
    /// Milliseconds.
    Ms,
    /// Microseconds.
    Us,
    /// Nanoseconds.
    Ns,
}

impl TimeUnit {
    /// Nanoseconds per unit.
    pub(crate) fn nanos(self) -> u64 {
        match self {
            TimeUnit::S => 1_000_000_000,
            TimeUnit::Ms => 1_000_000,
            TimeUnit::Us => 1_000,
            TimeUnit::Ns => 1,
        }
    }
    /// The name.
    pub(crate) fn name(self) -> &'static str {
        match self {
            TimeUnit::S => "s",
            TimeUnit::Ms => "ms",
            TimeUnit::Us => "us",
            TimeUnit::Ns => "ns",
        }
    }
    /// From a flag or header text.
    pub(crate) fn parse(s: &str) -> Result<TimeUnit, UnknownUnit> {
        match unit_key(s).as_str() {
            "s" | "sec" | "secs" | "second" | "seconds" => Ok(TimeUnit::S),
            "ms" | "msec" => Ok(TimeUnit::Ms),
            "us" | "µs" | "usec" => Ok(TimeUnit::Us),
            "ns" | "nsec" => Ok(TimeUnit::Ns),
            _ => Err(UnknownUnit(format!(
                "'{s}' is not a time unit (s, ms, us, ns)"
            ))),
        }
    }
}

/// Unit text that names none of the units a column can be in (what was given, and the
/// units there are).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub(crate) struct UnknownUnit(String);

/// Unit of the gyroscope columns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GyroUnit {
    /// rad/s.
    RadS,
    /// deg/s.
    DegS,
}

impl GyroUnit {
    /// rad/s per unit.
    pub(crate) fn si(self) -> f64 {
        match self {
            GyroUnit::RadS => 1.0,
            GyroUnit::DegS => std::f64::consts::PI / 180.0,
        }
    }
    /// The name.
    pub(crate) fn name(self) -> &'static str {
        match self {
            GyroUnit::RadS => "rad/s",
            GyroUnit::DegS => "deg/s",
        }
    }
    /// From a flag or header text.
    pub(crate) fn parse(s: &str) -> Result<GyroUnit, UnknownUnit> {
        match unit_key(s).as_str() {
            "rad/s" | "rads^-1" | "rad*s^-1" | "rads-1" | "radps" => Ok(GyroUnit::RadS),
            "deg/s" | "°/s" | "dps" | "degs^-1" | "degps" => Ok(GyroUnit::DegS),
            _ => Err(UnknownUnit(format!(
                "'{s}' is not a gyroscope unit (rad/s, deg/s)"
            ))),
        }
    }
}

/// Unit of the accelerometer columns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AccUnit {
    /// m/s².
    Ms2,
    /// Standard gravity.
    G,
    /// Thousandths of standard gravity.
    Mg,
}

impl AccUnit {
    /// m/s² per unit.
    pub(crate) fn si(self) -> f64 {
        match self {
            AccUnit::Ms2 => 1.0,
            AccUnit::G => STANDARD_GRAVITY,
            AccUnit::Mg => STANDARD_GRAVITY * 1e-3,
        }
    }
    /// The name.
    pub(crate) fn name(self) -> &'static str {
        match self {
            AccUnit::Ms2 => "m/s^2",
            AccUnit::G => "g",
            AccUnit::Mg => "mg",
        }
    }
    /// From a flag or header text.
    pub(crate) fn parse(s: &str) -> Result<AccUnit, UnknownUnit> {
        match unit_key(s).as_str() {
            "m/s^2" | "m/s2" | "ms^-2" | "m*s^-2" | "ms-2" | "m/s/s" | "mps2" => Ok(AccUnit::Ms2),
            "g" => Ok(AccUnit::G),
            "mg" => Ok(AccUnit::Mg),
            _ => Err(UnknownUnit(format!(
                "'{s}' is not an accelerometer unit (m/s^2, g, mg)"
            ))),
        }
    }
}

/// A unit's text without spaces, lower case (`rad s^-1` → `rads^-1`).
fn unit_key(s: &str) -> String {
    s.chars()
        .filter(|c| !c.is_whitespace())
        .flat_map(char::to_lowercase)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_parse_from_headers_and_flags() {
        assert_eq!(GyroUnit::parse("rad s^-1"), Ok(GyroUnit::RadS));
        assert_eq!(GyroUnit::parse("deg/s"), Ok(GyroUnit::DegS));
        assert_eq!(AccUnit::parse("m s^-2"), Ok(AccUnit::Ms2));
        assert_eq!(AccUnit::parse("mg"), Ok(AccUnit::Mg));
        assert_eq!(TimeUnit::parse("ns"), Ok(TimeUnit::Ns));
        assert!(AccUnit::parse("furlong").is_err());
    }
}
