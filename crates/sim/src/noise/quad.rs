//! Small quadrature helpers for the truth integrals (Gauss–Legendre, 16 nodes per panel).

/// Gauss–Legendre nodes and weights on [−1, 1], 16 points (positive half; symmetric).
const GL16_X: [f64; 8] = [
    0.095_012_509_837_637_44,
    0.281_603_550_779_258_9,
    0.458_016_777_657_227_4,
    0.617_876_244_402_643_8,
    0.755_404_408_355_003,
    0.865_631_202_387_831_8,
    0.944_575_023_073_232_6,
    0.989_400_934_991_649_9,
];
const GL16_W: [f64; 8] = [
    0.189_450_610_455_068_5,
    0.182_603_415_044_923_6,
    0.169_156_519_395_002_5,
    0.149_595_988_816_576_7,
    0.124_628_971_255_533_9,
    0.095_158_511_682_492_78,
    0.062_253_523_938_647_89,
    0.027_152_459_411_754_09,
];

/// ∫_a^b f by 16-point Gauss–Legendre.
pub fn gauss_legendre<F: Fn(f64) -> f64>(f: &F, a: f64, b: f64) -> f64 {
    let (c, h) = (0.5 * (a + b), 0.5 * (b - a));
    let mut s = 0.0;
    for (x, w) in GL16_X.iter().zip(&GL16_W) {
        s += w * (f(c - h * x) + f(c + h * x));
    }
    s * h
}

/// ∫_a^b f over `panels` equal panels.
pub fn gauss_legendre_panels<F: Fn(f64) -> f64>(f: F, a: f64, b: f64, panels: usize) -> f64 {
    let h = (b - a) / panels as f64;
    (0..panels)
        .map(|i| gauss_legendre(&f, a + i as f64 * h, a + (i + 1) as f64 * h))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integrates_polynomials_exactly_and_weights_sum_to_two() {
        let w: f64 = 2.0 * GL16_W.iter().sum::<f64>();
        assert!((w - 2.0).abs() < 1e-14, "{w}");
        // Exact to degree 31.
        let v = gauss_legendre(&|x: f64| x.powi(30), -1.0, 1.0);
        assert!((v - 2.0 / 31.0).abs() < 1e-14, "{v}");
        let s = gauss_legendre_panels(|x: f64| x.sin(), 0.0, std::f64::consts::PI, 8);
        assert!((s - 2.0).abs() < 1e-14, "{s}");
    }
}
