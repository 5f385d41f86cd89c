//! The two sensors of a `sensor_msgs/Imu` message — gyroscope (`angular_velocity`, rad/s)
//! and accelerometer (`linear_acceleration`, m/s²) — with the names and units every tool of
//! the workspace prints: the signal's, and those of the IEEE 952 noise terms in continuous
//! time (Q, N, B, K, R).

/// The two sensors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Sensor {
    /// Gyroscope (rad/s).
    Gyro,
    /// Accelerometer (m/s²).
    Acc,
}

impl Sensor {
    /// Both, gyroscope first (the bag's column order).
    pub const BOTH: [Sensor; 2] = [Sensor::Gyro, Sensor::Acc];

    /// Short name used in column names (`gyro`, `acc`).
    pub fn short(self) -> &'static str {
        match self {
            Sensor::Gyro => "gyro",
            Sensor::Acc => "acc",
        }
    }

    /// Unit of N.
    pub fn n_unit(self) -> &'static str {
        match self {
            Sensor::Gyro => "rad/s/sqrt(Hz)",
            Sensor::Acc => "m/s^2/sqrt(Hz)",
        }
    }
    /// Unit of K.
    pub fn k_unit(self) -> &'static str {
        match self {
            Sensor::Gyro => "rad/s^2/sqrt(Hz)",
            Sensor::Acc => "m/s^3/sqrt(Hz)",
        }
    }
    /// Unit of the signal (and of B).
    pub fn unit(self) -> &'static str {
        match self {
            Sensor::Gyro => "rad/s",
            Sensor::Acc => "m/s^2",
        }
    }
    /// Unit of Q.
    pub fn q_unit(self) -> &'static str {
        match self {
            Sensor::Gyro => "rad",
            Sensor::Acc => "m/s",
        }
    }
    /// Unit of R.
    pub fn r_unit(self) -> &'static str {
        match self {
            Sensor::Gyro => "rad/s^2",
            Sensor::Acc => "m/s^3",
        }
    }
    /// The other sensor of an IMU.
    pub fn other(self) -> Sensor {
        match self {
            Sensor::Gyro => Sensor::Acc,
            Sensor::Acc => Sensor::Gyro,
        }
    }
    /// `gyroscope` / `accelerometer`.
    pub fn name(self) -> &'static str {
        match self {
            Sensor::Gyro => "gyroscope",
            Sensor::Acc => "accelerometer",
        }
    }
    /// Axis code of the curves CSV: `gx` … `az`.
    pub fn axis_code(self, axis: usize) -> &'static str {
        match self {
            Sensor::Gyro => ["gx", "gy", "gz"][axis],
            Sensor::Acc => ["ax", "ay", "az"][axis],
        }
    }
    /// Label in the printed section: `gyro x` … `acc z`.
    pub fn axis_label(self, axis: usize) -> &'static str {
        match self {
            Sensor::Gyro => ["gyro x", "gyro y", "gyro z"][axis],
            Sensor::Acc => ["acc x", "acc y", "acc z"][axis],
        }
    }
}
