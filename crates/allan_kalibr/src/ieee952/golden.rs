//! Golden-section search for the minimum of a unimodal function of one variable: the
//! resonance fit of the PSD (`psd`) and the Gauss–Markov correlation time of the fit (`fit`)
//! both refine a grid's best point with it.

/// The minimum of a unimodal `f` on [a, b], golden-section search to `rel_tol` of the
/// interval.
pub(crate) fn golden_min(f: impl Fn(f64) -> f64, mut a: f64, mut b: f64, rel_tol: f64) -> f64 {
    const G: f64 = 0.618_033_988_749_894_8;
    let tol = rel_tol * (b - a).abs();
    let (mut x1, mut x2) = (b - G * (b - a), a + G * (b - a));
    let (mut f1, mut f2) = (f(x1), f(x2));
    while (b - a).abs() > tol {
        if f1 <= f2 {
            b = x2;
            (x2, f2) = (x1, f1);
            x1 = b - G * (b - a);
            f1 = f(x1);
        } else {
            a = x1;
            (x1, f1) = (x2, f2);
            x2 = a + G * (b - a);
            f2 = f(x2);
        }
    }
    0.5 * (a + b)
}
