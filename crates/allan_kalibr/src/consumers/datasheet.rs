//! The units datasheets quote noise in, and the conversions to and from the continuous-time
//! N, K and B the analysis works in (rad/s and m/s² based, per √Hz): angle random walk (ARW,
//! °/√h), velocity random walk (VRW, m/s/√h), noise densities in °/s/√Hz and µg/√Hz, bias
//! instability in °/h and mg, and a gyro random walk in °/h/√h. A datasheet's "bias
//! instability" (in-run bias stability) is the minimum of its Allan deviation curve; IEEE
//! 952's coefficient B is that floor over 0.664 ([`crate::B_FLOOR_FACTOR`]).

use super::Quantity;

/// Standard gravity, m/s² (the g of µg and mg).
pub const G0: f64 = 9.806_65;
/// Degrees per radian.
const DEG: f64 = 180.0 / std::f64::consts::PI;

/// Gyro noise density from an angle random walk in °/√h: rad/s/√Hz = rad/√s = (°/√h)·(π/180)/60.
pub fn from_arw(deg_per_sqrt_h: f64) -> f64 {
    deg_per_sqrt_h / DEG / 60.0
}

/// The angle random walk, °/√h, of a gyro noise density in rad/s/√Hz.
pub fn to_arw(n: f64) -> f64 {
    n * DEG * 60.0
}

/// Gyro noise density from °/s/√Hz.
pub fn from_dps_density(deg_s_sqrt_hz: f64) -> f64 {
    deg_s_sqrt_hz / DEG
}

/// Accelerometer noise density from a velocity random walk in m/s/√h: m/s²/√Hz = (m/s/√h)/60.
pub fn from_vrw(m_s_per_sqrt_h: f64) -> f64 {
    m_s_per_sqrt_h / 60.0
}

/// The velocity random walk, m/s/√h, of an accelerometer noise density in m/s²/√Hz.
pub fn to_vrw(n: f64) -> f64 {
    n * 60.0
}

/// Accelerometer noise density from µg/√Hz.
pub fn from_ug_density(ug_sqrt_hz: f64) -> f64 {
    ug_sqrt_hz * 1e-6 * G0
}

/// A gyro bias instability (Allan floor) from °/h, in rad/s.
pub fn from_deg_per_h(deg_h: f64) -> f64 {
    deg_h / DEG / 3600.0
}

/// An accelerometer bias instability (Allan floor) from mg, in m/s².
pub fn from_mg(mg: f64) -> f64 {
    mg * 1e-3 * G0
}

/// A continuous value of `q` in the units datasheets quote: "0.58 °/√h (ARW)".
pub fn describe(q: Quantity, x: f64) -> String {
    match q {
        Quantity::GyroNoise => format!(
            "ARW {:.3} deg/sqrt(h), {:.3e} deg/s/sqrt(Hz)",
            to_arw(x),
            x * DEG
        ),
        Quantity::AccNoise => format!(
            "VRW {:.3e} m/s/sqrt(h), {:.1} ug/sqrt(Hz)",
            to_vrw(x),
            x / G0 * 1e6
        ),
        // rad/s/√s → °/h/√h: ° per rad, s per h, √s per √h
        Quantity::GyroWalk => format!("{:.3e} deg/h/sqrt(h)", x * DEG * 3600.0 * 60.0),
        Quantity::AccWalk => format!("{:.3e} ug/sqrt(s)", x / G0 * 1e6),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The conversions against figures worked by hand: 1 °/√h is (π/180)/60 rad/√s; a
    /// 0.005 °/s/√Hz gyro (datasheet) is 0.3 °/√h; 100 µg/√Hz is 9.80665e-4 m/s²/√Hz; a VRW of
    /// 0.06 m/s/√h is 1e-3 m/s²/√Hz; 10 °/h is 4.848e-5 rad/s.
    #[test]
    fn datasheet_units_by_hand() {
        let close = |a: f64, b: f64| (a / b - 1.0).abs() < 1e-12;
        assert!(close(from_arw(1.0), std::f64::consts::PI / 180.0 / 60.0));
        assert!(close(to_arw(from_dps_density(0.005)), 0.3));
        assert!(close(from_ug_density(100.0), 9.80665e-4));
        assert!(close(from_vrw(0.06), 1e-3));
        assert!(close(from_deg_per_h(10.0), 4.84813681109536e-5));
        assert!(close(from_mg(1.0), 9.80665e-3));
        assert!(close(to_vrw(from_vrw(0.123)), 0.123));
    }
}
