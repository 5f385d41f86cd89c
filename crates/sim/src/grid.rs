//! Sample-time grids. Upstream builds its grids by accumulating a step in a loop; the count
//! and the last time depend on the float type, so both accumulations are reproduced
//! (docs/upstream/vio_data_simulation.md §4, §8 item 1), next to an exact integer-index grid.

/// How sample times are generated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Grid {
    /// `for (double t = 0; t < end; t += 1.0/rate)` — vio_data_simulation `ros_version`
    /// `gener_alldata.cpp`: 4 h at 200 Hz gives 2 880 001 samples, the last at
    /// 14399.99999916 s.
    AccumulatedF64,
    /// `for (float t = 0; t < end;) { …; t += 1.0/rate; }` — vio_data_simulation `master`
    /// `gener_alldata.cpp` (t is `float`, the sum is done in double and rounded back):
    /// 20 s at 200 Hz gives 4001 samples (t₂₀₀ = 0.999999, t₄₀₀₀ = 19.99965), at 30 Hz 600.
    AccumulatedF32,
    /// t_i = i/rate for i = 0..=round(end·rate): the inclusive end point, no drift.
    Exact,
}

/// Iterator over the times of a grid on [0, end].
#[derive(Debug, Clone)]
pub struct GridIter {
    grid: Grid,
    rate: f64,
    end: f64,
    i: u64,
    n_exact: u64,
    t64: f64,
    t32: f32,
}

impl Grid {
    /// Times of this grid from 0 to `end` (s) at `rate` (Hz).
    pub fn times(self, end: f64, rate: f64) -> GridIter {
        GridIter {
            grid: self,
            rate,
            end,
            i: 0,
            n_exact: (end * rate).round() as u64,
            t64: 0.0,
            t32: 0.0,
        }
    }
}

impl Iterator for GridIter {
    type Item = f64;
    fn next(&mut self) -> Option<f64> {
        let step = 1.0 / self.rate;
        match self.grid {
            Grid::AccumulatedF64 => {
                let t = self.t64;
                if t < self.end {
                    self.t64 += step;
                    Some(t)
                } else {
                    None
                }
            }
            Grid::AccumulatedF32 => {
                let t = self.t32;
                if (t as f64) < self.end {
                    self.t32 = (t as f64 + step) as f32;
                    Some(t as f64)
                } else {
                    None
                }
            }
            Grid::Exact => {
                let i = self.i;
                if i <= self.n_exact {
                    self.i += 1;
                    Some(i as f64 / self.rate)
                } else {
                    None
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quirk_01_ros_version_double_accumulation_counts_2880001() {
        // docs/upstream/vio_data_simulation.md §4: 4 h at 200 Hz, double accumulation ⇒ 2 880 001 messages, last t just
        // below 14400 (14399.99999916).
        let mut n = 0u64;
        let mut last = 0.0;
        for t in Grid::AccumulatedF64.times(14400.0, 200.0) {
            n += 1;
            last = t;
        }
        assert_eq!(n, 2_880_001);
        assert!((last - 14399.99999916).abs() < 1e-8, "last t = {last:.10}");
        // The 2 h txt tool: 1 440 000 lines (docs/upstream/vio_data_simulation.md §4).
        assert_eq!(Grid::AccumulatedF64.times(7200.0, 200.0).count(), 1_440_000);
    }

    #[test]
    fn quirk_02_master_float_grid() {
        // docs/upstream/vio_data_simulation.md §8 item 1: 4001 IMU samples, t₂₀₀ = 0.999999, t₄₀₀₀ = 19.99965; 600 frames at
        // 30 Hz with t₁ = 0.033333335.
        let t: Vec<f64> = Grid::AccumulatedF32.times(20.0, 200.0).collect();
        assert_eq!(t.len(), 4001);
        assert!((t[200] - 0.999999).abs() < 5e-7, "t200 = {}", t[200]);
        assert!((t[4000] - 19.99965).abs() < 5e-6, "t4000 = {}", t[4000]);
        let c: Vec<f64> = Grid::AccumulatedF32.times(20.0, 30.0).collect();
        assert_eq!(c.len(), 600);
        assert_eq!(format!("{:.9}", c[1]), "0.033333335");
    }

    #[test]
    fn exact_grid_includes_the_end() {
        let t: Vec<f64> = Grid::Exact.times(20.0, 200.0).collect();
        assert_eq!(t.len(), 4001);
        assert_eq!(t[4000], 20.0);
    }
}
