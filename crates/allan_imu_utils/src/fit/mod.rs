//! imu_utils' per-axis model fit (`FitAllanGyr` / `FitAllanAcc`, docs/upstream/imu_utils.md §4): the
//! acc-only point filter, the linear start point (`C …` line), the Ceres dogleg fit of the
//! log variance, and the values derived from the fitted parameters.

pub(crate) mod dogleg;
pub(crate) mod init;
pub(crate) mod model;

pub use model::Params;

/// imu_utils' rad→deg constant: 57.3, not 180/π (quirk 4, docs/upstream/imu_utils.md §0).
pub const IMU_UTILS_DEG_PER_RAD: f64 = 57.3;
/// Seconds per hour in the pseudo-deg/h gyro unit.
pub const SECONDS_PER_HOUR: f64 = 3600.0;
/// `getB`'s divisor sqrt(2 ln2 / π) as upstream spells it.
pub const IMU_UTILS_BIAS_FACTOR: f64 = 0.6642824703;
/// `findMinNum` / `findMinIndex` start their running minimum here (quirk 3).
pub const IMU_UTILS_MIN_START: f64 = 1000.0;

/// Which of upstream's two twin fit classes: `FitAllanGyr` (`Sensor::Gyro`: values in
/// pseudo-deg/h, no point filter) or `FitAllanAcc` (`Sensor::Acc`: values in m/s², the
/// `checkData` filter) — the workspace's one sensor type.
use bag2mat::Sensor;

/// Mirrors imu_utils `2cdda91` `FitAllanAcc::checkData` (docs/upstream/imu_utils.md §4.1, quirk 6): among
/// τ < 1 s points, each one that sets a new running maximum of σ² (starting from 0) is
/// dropped. Returns the kept (taus, variances).
pub fn acc_check_data(taus: &[f64], sigma2: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let mut data_tmp = 0.0;
    let mut kt = Vec::with_capacity(taus.len());
    let mut ks = Vec::with_capacity(taus.len());
    for (&t, &s) in taus.iter().zip(sigma2) {
        if t < 1.0 && data_tmp < s {
            data_tmp = s;
            continue;
        }
        kt.push(t);
        ks.push(s);
    }
    (kt, ks)
}

/// `findMinNum`: min over v, starting from 1000.0 (quirk 3).
pub fn find_min_num(v: &[f64]) -> f64 {
    let mut min = IMU_UTILS_MIN_START;
    for &x in v {
        min = if min < x { min } else { x };
    }
    min
}

/// `findMinIndex`: index of that min; ties → last index; 0 when nothing is below 1000.
pub fn find_min_index(v: &[f64]) -> usize {
    let mut min = IMU_UTILS_MIN_START;
    let mut idx = 0;
    for (i, &x) in v.iter().enumerate() {
        idx = if min < x { idx } else { i };
        min = if min < x { min } else { x };
    }
    idx
}

/// One axis fitted the way upstream does it.
#[derive(Debug, Clone)]
pub struct AxisFit {
    /// Gyro or acc class.
    pub sensor: Sensor,
    /// The signed linear-least-squares coefficients (printed `C …` line).
    pub start: [f64; 5],
    /// Fitted [Q, N, B, K, R] (signed).
    pub params: Params,
    /// Taus the fit used (the filtered ones for acc: upstream's `m_taus`).
    pub fit_taus: Vec<f64>,
    /// Mean-period frequency (Hz).
    pub freq: f64,
    /// Solver report.
    pub summary: dogleg::Summary,
}

impl AxisFit {
    /// Runs the fit on Allan variances `sigma2` at `taus`.
    pub fn fit(sensor: Sensor, taus: &[f64], sigma2: &[f64], freq: f64) -> AxisFit {
        let (fit_taus, fit_sigma2) = match sensor {
            Sensor::Gyro => (taus.to_vec(), sigma2.to_vec()),
            Sensor::Acc => acc_check_data(taus, sigma2),
        };
        let start = init::start_coefficients(&fit_sigma2, &fit_taus);
        let x0 = start.map(f64::abs);
        let problem = dogleg::Problem {
            taus: &fit_taus,
            sigma2: &fit_sigma2,
        };
        let (params, summary) = dogleg::solve(&problem, x0, &dogleg::Options::default());
        AxisFit {
            sensor,
            start,
            params,
            fit_taus,
            freq,
            summary,
        }
    }

    /// Divisor from the internal unit to the reported one (gyro: pseudo-deg/h → rad/s).
    fn unit_div(&self) -> f64 {
        match self.sensor {
            Sensor::Gyro => IMU_UTILS_DEG_PER_RAD * SECONDS_PER_HOUR,
            Sensor::Acc => 1.0,
        }
    }

    /// Fitted Allan deviation at each tau (`calcSimDeviation`), internal units.
    pub fn sim(&self, taus: &[f64]) -> Vec<f64> {
        taus.iter()
            .map(|&t| model::deviation(&self.params, t))
            .collect()
    }

    /// `getBiasInstability`: the clamped minimum of the fitted deviation over the fit taus
    /// (quirk 2: a floor, not a random walk), in rad/s or m/s².
    pub fn bias_instability(&self) -> f64 {
        let v = find_min_num(&self.sim(&self.fit_taus));
        match self.sensor {
            Sensor::Gyro => v / (IMU_UTILS_DEG_PER_RAD * SECONDS_PER_HOUR),
            Sensor::Acc => v,
        }
    }

    /// `getWhiteNoise`: sqrt(freq)·fitted deviation at τ = 1 s (quirk 1: discrete, all terms).
    pub fn white_noise(&self) -> f64 {
        let v = self.freq.sqrt() * model::variance(&self.params, 1.0).sqrt();
        match self.sensor {
            Sensor::Gyro => v / (IMU_UTILS_DEG_PER_RAD * SECONDS_PER_HOUR),
            Sensor::Acc => v,
        }
    }

    /// Gyro print 1: `getB()/(57.3·3600)`, |B|/0.6642824703 in rad/s.
    pub fn gyro_b_line_value(&self) -> f64 {
        let b = self.params[2];
        ((b * b).sqrt() / IMU_UTILS_BIAS_FACTOR) / (IMU_UTILS_DEG_PER_RAD * SECONDS_PER_HOUR)
    }

    /// Gyro print 3 (quirk 5): `sqrt(freq)·getN()·60/57.3` with `getN = |N|/60`; labelled
    /// rad/s, actually rad/h.
    pub fn gyro_n_line_value(&self) -> f64 {
        let n = self.params[1];
        self.freq.sqrt() * ((n * n).sqrt() / 60.0) * 60.0 / IMU_UTILS_DEG_PER_RAD
    }

    /// Corrected reading (docs/upstream/imu_utils.md §7): continuous white-noise density |N| in SI units
    /// (rad/s/√Hz, m/s²/√Hz).
    pub fn continuous_white_noise(&self) -> f64 {
        self.params[1].abs() / self.unit_div()
    }

    /// Corrected reading: bias random walk √3·|K| (rad/s²/√Hz, m/s³/√Hz), Kalibr's τ = 3 rule.
    pub fn continuous_random_walk(&self) -> f64 {
        3f64.sqrt() * self.params[3].abs() / self.unit_div()
    }

    /// Corrected reading: bias instability |B|/0.664 (rad/s, m/s²).
    pub fn continuous_bias_instability(&self) -> f64 {
        self.params[2].abs() / IMU_UTILS_BIAS_FACTOR / self.unit_div()
    }

    /// Quantization |Q|/√3 (rad, m/s) and rate ramp √2·|R| (rad/s², m/s³).
    pub fn continuous_quantization_and_ramp(&self) -> (f64, f64) {
        (
            self.params[0].abs() / 3f64.sqrt() / self.unit_div(),
            2f64.sqrt() * self.params[4].abs() / self.unit_div(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// docs/upstream/imu_utils.md §6 quirk 3: nothing below 1000 → the min is 1000 and the index 0.
    #[test]
    fn quirk_03_min_starts_at_1000() {
        assert_eq!(find_min_num(&[2000.0, 1500.0]), 1000.0);
        assert_eq!(find_min_index(&[2000.0, 1500.0]), 0);
        assert_eq!(
            find_min_index(&[5.0, 3.0, 3.0, 4.0]),
            2,
            "ties go to the last index"
        );
    }

    fn fixed(sensor: Sensor, params: Params, fit_taus: Vec<f64>, freq: f64) -> AxisFit {
        let summary = dogleg::Summary {
            termination: dogleg::Termination::Convergence,
            attempts: 0,
            accepted: 0,
            initial_cost: 0.0,
            final_cost: 0.0,
        };
        AxisFit {
            sensor,
            start: params,
            params,
            fit_taus,
            freq,
            summary,
        }
    }

    /// Quirk 1: `*_n` is the whole fitted ADEV at τ = 1 s times √freq (discrete), not |N|.
    #[test]
    fn quirk_01_white_noise_is_discrete_and_uses_all_terms() {
        let p = [0.0, 0.03, 0.0, 0.0, 0.0];
        let f = fixed(Sensor::Acc, p, vec![1.0], 200.0);
        assert_eq!(f.white_noise(), 200f64.sqrt() * 0.03);
        assert_eq!(f.continuous_white_noise(), 0.03);
        let f = fixed(Sensor::Acc, [0.0, 0.03, 0.01, 0.0, 0.0], vec![1.0], 200.0);
        assert_eq!(
            f.white_noise(),
            200f64.sqrt() * (0.03f64 * 0.03 + 0.01 * 0.01).sqrt()
        );
    }

    /// Quirk 2: `*_w` is the minimum of the fitted deviation over the fit taus, not √3·|K|.
    #[test]
    fn quirk_02_w_is_the_curve_minimum() {
        let p = [0.0, 0.03, 0.0, 0.001, 0.0];
        let taus = vec![1.0, 100.0, 900.0, 10_000.0];
        let f = fixed(Sensor::Acc, p, taus.clone(), 100.0);
        let min = taus
            .iter()
            .map(|&t| model::deviation(&p, t))
            .fold(f64::MAX, f64::min);
        assert_eq!(f.bias_instability(), min);
        assert_eq!(f.continuous_random_walk(), 3f64.sqrt() * 0.001);
    }

    /// Quirks 4 and 5: gyro values go through 57.3 (not 180/π); the first "White Noise" line
    /// is √freq·|N|/57.3 (rad/h, N only).
    #[test]
    fn quirk_04_05_gyro_units() {
        let p = [1.0, 6000.0, 300.0, 1.0, 0.5];
        let f = fixed(Sensor::Gyro, p, vec![0.01, 1.0, 100.0], 200.0);
        assert_eq!(
            f.gyro_n_line_value(),
            200f64.sqrt() * (6000.0 / 60.0) * 60.0 / 57.3
        );
        assert_eq!(
            f.gyro_b_line_value(),
            300.0 / 0.6642824703 / (57.3 * 3600.0)
        );
        assert_eq!(
            f.white_noise(),
            200f64.sqrt() * model::variance(&p, 1.0).sqrt() / (57.3 * 3600.0)
        );
    }

    /// Quirk 6: only τ < 1 points that set a new running max are dropped.
    #[test]
    fn quirk_06_acc_check_data() {
        let taus = [0.1, 0.2, 0.3, 0.5, 1.0, 2.0];
        let s2 = [5.0, 4.0, 6.0, 1.0, 9.0, 8.0];
        let (t, s) = acc_check_data(&taus, &s2);
        assert_eq!(t, vec![0.2, 0.5, 1.0, 2.0]);
        assert_eq!(s, vec![4.0, 1.0, 9.0, 8.0]);
    }
}
