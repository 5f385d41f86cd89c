//! How the IMU sits on the body a reference trajectory tracks, and its deterministic
//! errors: a rotation (IMU → body), a lever arm (the IMU's origin in the body frame), scale
//! and misalignment of each sensor (a symmetric I + S), and the gyro's g-sensitivity. A
//! moving `sim bag` applies them to the body's motion before the sensor's chain and noise,
//! so that the operating-noise analysis (`allan_kalibr --reference`) has something to
//! calibrate: what it should find is written with the reference ([`crate::reference_out`]).
//!
//! ```text
//! ω_I = R_BIᵀ ω_B                      f_I = R_BIᵀ [f_B + (ω̂̇_B + ω̂_B²) p]
//! gyro = (I + S_g) ω_I + G f_I         acc = (I + S_a) f_I
//! ```

use nalgebra::{Matrix3, Vector3};

use crate::motion::Motion;

/// The IMU's mounting and deterministic errors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mounting {
    /// Rotation IMU → body, R_BI.
    pub rotation: Matrix3<f64>,
    /// The IMU's origin in the body frame, m.
    pub lever: Vector3<f64>,
    /// Gyro scale and misalignment, S_g (symmetric).
    pub gyro_sm: Matrix3<f64>,
    /// Accelerometer scale and misalignment, S_a (symmetric).
    pub acc_sm: Matrix3<f64>,
    /// g-sensitivity G, rad/s per m/s².
    pub g_sens: Matrix3<f64>,
}

impl Default for Mounting {
    fn default() -> Self {
        Mounting {
            rotation: Matrix3::identity(),
            lever: Vector3::zeros(),
            gyro_sm: Matrix3::zeros(),
            acc_sm: Matrix3::zeros(),
            g_sens: Matrix3::zeros(),
        }
    }
}

/// The symmetric scale-and-misalignment matrix of `scale` (relative, on the diagonal as
/// s, −s/2, 0.7 s) and `misalignment` (rad, off the diagonal as m, −m/2, 0.7 m): every
/// axis and pair different, so that none hides behind another.
pub fn scale_misalignment(scale: f64, misalignment: f64) -> Matrix3<f64> {
    let (s, m) = (scale, misalignment);
    Matrix3::new(
        s,
        m,
        -0.5 * m,
        m,
        -0.5 * s,
        0.7 * m,
        -0.5 * m,
        0.7 * m,
        0.7 * s,
    )
}

impl Mounting {
    /// True when it changes nothing (the presets' bags stay byte-identical).
    pub fn is_identity(&self) -> bool {
        *self == Mounting::default()
    }

    /// The gyro and accelerometer readings of the IMU on the body moving as `motion` at
    /// time `t` (before the sensor's chain and noise).
    pub fn reading(&self, motion: Motion, t: f64) -> ([f64; 3], [f64; 3]) {
        let m = motion.sample(t);
        if self.is_identity() {
            return (m.gyro.into(), m.acc.into());
        }
        // the body's angular acceleration: a fourth-order central difference of the
        // closed-form rate (error ~h⁴·ω⁽⁵⁾, far below any noise)
        let h = 1e-3;
        let w = |s: f64| motion.sample(t + s).gyro;
        let wd = (w(-2.0 * h) - w(-h) * 8.0 + w(h) * 8.0 - w(2.0 * h)) / (12.0 * h);
        let hat = |v: Vector3<f64>| Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0);
        let rt = self.rotation.transpose();
        let w_i = rt * m.gyro;
        let f_i = rt * (m.acc + (hat(wd) + hat(m.gyro) * hat(m.gyro)) * self.lever);
        let gyro = (Matrix3::identity() + self.gyro_sm) * w_i + self.g_sens * f_i;
        let acc = (Matrix3::identity() + self.acc_sm) * f_i;
        (gyro.into(), acc.into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_identity_passes_the_motion_and_a_rotation_turns_it() {
        let m = Mounting::default();
        let x = Motion::Handheld.sample(3.0);
        assert_eq!(
            m.reading(Motion::Handheld, 3.0),
            (x.gyro.into(), x.acc.into())
        );
        let r = nalgebra::Rotation3::new(Vector3::new(0.0, 0.0, std::f64::consts::FRAC_PI_2))
            .into_inner();
        let m = Mounting {
            rotation: r,
            ..Mounting::default()
        };
        let (g, a) = m.reading(Motion::Handheld, 3.0);
        // the IMU's x is the body's y
        assert!((g[0] - x.gyro.y).abs() < 1e-12 && (a[0] - x.acc.y).abs() < 1e-12);
    }
}
