//! What every file a run writes says about itself: the tool and its version, the input, when
//! it was written ([`Provenance`]), and the record's sample rate as far as it is known
//! ([`RecordRate`]) — which is what a consumer's `update_rate`-like key must carry, never the
//! spacing of another tool's curve points.

/// The record's sample rate, and how it is known.
#[derive(Clone, Debug, PartialEq)]
pub enum RecordRate {
    /// The nominal rate of the record's time stamps.
    Measured(f64),
    /// Given on the command line (`--rate`), the stamps agreeing or absent.
    Given(f64),
    /// The rate a curves file states or implies (its first τ is one sample), with how.
    Curves {
        /// Hz.
        rate: f64,
        /// How the file gives it.
        how: String,
    },
    /// Not known; why (the files leave their rate keys out and say so).
    Unknown(String),
}

impl RecordRate {
    /// The rate, Hz, when known.
    pub fn hz(&self) -> Option<f64> {
        match self {
            RecordRate::Measured(r) | RecordRate::Given(r) => Some(*r),
            RecordRate::Curves { rate, .. } => Some(*rate),
            RecordRate::Unknown(_) => None,
        }
    }

    /// "200 Hz, the nominal rate of the time stamps", for a file's header.
    pub fn describe(&self) -> String {
        // Display: the shortest digits that read back as the rate (200, 62.5)
        let hz = |r: f64| format!("{r}");
        match self {
            RecordRate::Measured(r) => {
                format!("{} Hz, the nominal rate of the time stamps", hz(*r))
            }
            RecordRate::Given(r) => format!("{} Hz, given with --rate", hz(*r)),
            RecordRate::Curves { rate, how } => format!("{} Hz, {how}", hz(*rate)),
            RecordRate::Unknown(why) => {
                format!("unknown ({why}); the rate keys are left out: give --rate HZ")
            }
        }
    }
}

/// Who wrote a file, from what, and when.
#[derive(Clone, Debug, PartialEq)]
pub struct Provenance {
    /// The tool and its version: "allan_kalibr 0.1.0".
    pub tool: String,
    /// The input: "imu.bag, topic /imu".
    pub input: String,
    /// When: UTC, RFC 3339 ([`utc_now`]).
    pub written: String,
    /// The record's sample rate.
    pub rate: RecordRate,
}

impl Provenance {
    /// The provenance of a file `tool` writes now from `input`.
    pub fn new(tool: &str, input: impl Into<String>, rate: RecordRate) -> Provenance {
        Provenance {
            tool: format!("{tool} {}", env!("CARGO_PKG_VERSION")),
            input: input.into(),
            written: utc_now(),
            rate,
        }
    }

    /// "Written by allan_kalibr 0.1.0 on 2025-01-01T12:00:00Z from imu.bag, topic /imu."
    pub fn line(&self) -> String {
        format!(
            "Written by {} on {} from {}.",
            self.tool, self.written, self.input
        )
    }

    /// "Record rate: 200 Hz, …".
    pub fn rate_line(&self) -> String {
        format!("Record rate: {}.", self.rate.describe())
    }
}

/// "imu.bag, topic /imu": the input a file names (the path as the user gave it).
pub fn input_text(path: &std::path::Path, topic: Option<&str>) -> String {
    match topic {
        Some(t) => format!("{}, topic {t}", path.display()),
        None => path.display().to_string(),
    }
}

/// The time now in UTC as RFC 3339 (`2025-01-01T12:00:00Z`); `SOURCE_DATE_EPOCH` (seconds
/// since 1970, the reproducible-builds convention) stands in for the clock when it is set.
pub fn utc_now() -> String {
    let secs = std::env::var("SOURCE_DATE_EPOCH")
        .ok()
        .and_then(|v| v.trim().parse::<i64>().ok())
        .unwrap_or_else(|| {
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_secs() as i64)
        });
    utc(secs)
}

/// Seconds since 1970 as an RFC 3339 UTC time (the proleptic Gregorian calendar; days to
/// year/month/day by H. Hinnant's `civil_from_days`).
fn utc(secs: i64) -> String {
    let days = secs.div_euclid(86_400);
    let rem = secs.rem_euclid(86_400);
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against dates whose epoch seconds are known (GNU `date -u -d @S` gives the same).
    #[test]
    fn utc_times_of_known_instants() {
        assert_eq!(utc(0), "1970-01-01T00:00:00Z");
        assert_eq!(utc(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(utc(1_700_000_000), "2023-11-14T22:13:20Z");
        assert_eq!(utc(4_107_542_399), "2100-02-28T23:59:59Z");
        assert_eq!(utc(-1), "1969-12-31T23:59:59Z");
    }

    /// A slow, obviously correct count of days against the fast formula, over 400 years.
    #[test]
    fn utc_dates_match_a_day_by_day_count() {
        let leap = |y: i64| (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
        let (mut y, mut m, mut d) = (1970i64, 1i64, 1i64);
        for day in 0..146_097i64 {
            let want = format!("{y:04}-{m:02}-{d:02}T00:00:00Z");
            assert_eq!(utc(day * 86_400), want);
            let len = match m {
                2 if leap(y) => 29,
                2 => 28,
                4 | 6 | 9 | 11 => 30,
                _ => 31,
            };
            d += 1;
            if d > len {
                d = 1;
                m += 1;
                if m > 12 {
                    m = 1;
                    y += 1;
                }
            }
        }
    }
}
