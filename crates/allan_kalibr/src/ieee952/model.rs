//! The model the fit is linear in: each term's basis function of τ (the five IEEE 952 power
//! laws of the term table, [`super::term`], the Gauss–Markov bump, the flicker floor's lower
//! corner and the vibration lines' exact sampled shapes), the shapes that parameterise them,
//! and the model's AVAR at τ.

use super::term::NoiseTerm::{self, BiasInstability, GaussMarkov, Ramp, RandomWalk, WhiteNoise};
pub use super::term::{FLICKER_AVAR, LINE_SLOTS, TERM_COUNT};

/// Basis function g(τ) of an IEEE 952 power law: AVAR = Σ c_j g_j(τ) (0 for the shaped
/// terms, whose shape needs its parameters: [`basis_at`]).
pub fn basis(t: NoiseTerm, tau: f64) -> f64 {
    t.power_law_avar(tau)
}

/// Allan variance of a first-order Gauss–Markov bias of unit variance and correlation time
/// `t` (IEEE 952 Annex C, exponentially correlated noise, with q_c² = 2σ²/T):
/// (2T/τ)·[1 − (T/2τ)(3 − 4e^(−τ/T) + e^(−2τ/T))] — a random walk (2τ/3T) for τ ≪ T, white
/// noise (2T/τ) for τ ≫ T, a bump of 0.38·σ² at τ ≈ 1.9T in between. 0 for a NaN `t`.
pub fn gm_basis(tau: f64, t: f64) -> f64 {
    if !is_positive(t) {
        return 0.0;
    }
    let x = tau / t;
    if x < 1e-3 {
        // the series, where the bracket cancels: 2x/3 − x²/2 + …
        return 2.0 * x / 3.0 - x * x / 2.0;
    }
    (2.0 / x) * (1.0 - (3.0 - 4.0 * (-x).exp() + (-2.0 * x).exp()) / (2.0 * x))
}

/// Share of the flicker floor reached at τ = x·T_lo by a flicker bias whose 1/f spectrum
/// stops at a shortest correlation time T_lo: a sum of Gauss–Markov biases with
/// correlation times spread uniformly in log T from T_lo up (A. van der Ziel's construction
/// of 1/f noise, which is also how `sim` generates it). Its Allan variance is
/// (B²/π)·∫_{T_lo}^∞ g(τ/T) d ln T with g = [`gm_basis`]; the integral over all T is 2 ln 2, the
/// flat floor (2 ln2/π)·B², so
///
/// ```text
/// ψ(x) = (1/2 ln2)·∫_0^x g(s) ds/s  →  x/(3 ln2) for x ≪ 1 (a random walk),
///                                       1 − 1/(x·ln2) for x ≫ 1 (a slow roll-off)
/// ```
///
/// The roll-off towards short τ is slow (2 % below the floor at x = 40): where the floor
/// meets white noise, a flat-floor fit of such a curve trades the missing flicker for
/// white noise and reports N low by about a percent (measured on `sim`'s STIM300-like
/// accelerometer, its floor corner at 20 s). Tabulated once, Simpson on ln s.
pub fn flicker_band(x: f64) -> f64 {
    use std::sync::OnceLock;
    static TABLE: OnceLock<Vec<f64>> = OnceLock::new();
    if !is_positive(x) {
        return 0.0;
    }
    if x < BAND_TABLE.0 {
        // the series of the integral: 2x/3 − x²/4 + O(x³)
        return (2.0 * x / 3.0 - x * x / 4.0) / (2.0 * std::f64::consts::LN_2);
    }
    if x >= BAND_TABLE.1 {
        // ∫_x^∞ g(s) ds/s = 2/x − 3/(2x²) + O(e^(−x)/x)
        return 1.0 - (2.0 / x - 1.5 / (x * x)) / (2.0 * std::f64::consts::LN_2);
    }
    let (l0, l1) = (BAND_TABLE.0.ln(), BAND_TABLE.1.ln());
    let h = (l1 - l0) / BAND_TABLE_CELLS as f64;
    let table = TABLE.get_or_init(|| {
        let f = |l: f64| gm_basis(l.exp(), 1.0);
        let mut v = Vec::with_capacity(BAND_TABLE_CELLS + 1);
        let x0 = BAND_TABLE.0;
        let mut acc = 2.0 * x0 / 3.0 - x0 * x0 / 4.0;
        v.push(acc);
        for i in 0..BAND_TABLE_CELLS {
            let a = l0 + i as f64 * h;
            acc += h / 6.0 * (f(a) + 4.0 * f(a + 0.5 * h) + f(a + h));
            v.push(acc);
        }
        v.iter()
            .map(|a| a / (2.0 * std::f64::consts::LN_2))
            .collect()
    });
    let u = (x.ln() - l0) / h;
    let i = (u.floor() as usize).min(BAND_TABLE_CELLS - 1);
    let w = u - i as f64;
    table[i] * (1.0 - w) + table[i + 1] * w
}

/// x range of the [`flicker_band`] table (outside it, two-term series accurate to 1e-7).
const BAND_TABLE: (f64, f64) = (1e-2, 10.0);
/// Cells of the table: linear interpolation in ln x errs by < 2e-6.
const BAND_TABLE_CELLS: usize = 2048;

/// A vibration line of the model: its shape, known from the PSD (the `psd` module); its
/// coefficient A² is fitted. The Allan variance per unit A² is the sampled sinusoid's
/// (bandwidth 0) or the sampled resonance's (the `lines` module), at m = τ/τ₀.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineShape {
    /// Frequency, Hz.
    pub frequency: f64,
    /// −3 dB bandwidth, Hz (0: a sinusoid).
    pub bandwidth: f64,
    /// Standard error of the bandwidth as the PSD measured it, Hz (0 or NaN: none known);
    /// the terms' intervals carry it.
    pub bandwidth_se: f64,
    /// Sample period, s.
    pub tau0: f64,
    /// A² as the PSD measured it (for the range's start rule; a resonance's coefficient).
    pub psd_amp2: f64,
    /// Record length, s (a resonance's estimate has about 2πB·T degrees of freedom).
    pub record: f64,
}

impl LineShape {
    /// Whether the line's coefficient is held at the PSD's instead of fitted. Not today:
    /// the PSD's A² is a few percent off for a resonance (its peak is as noisy as any bin),
    /// far more than the short-τ points' precision, while the Allan bump pins A² once the
    /// points it dominates carry their own variance ([`LineShape::edf`]); kept as the one
    /// switch should a record need it.
    pub(crate) fn fixed(&self) -> bool {
        false
    }

    /// Degrees of freedom of the line's own Allan variance estimate (∞ for a sinusoid,
    /// whose estimate is deterministic up to the noise's cross term).
    pub(crate) fn edf(&self) -> f64 {
        if self.bandwidth > 0.0 {
            (2.0 * std::f64::consts::PI * self.bandwidth * self.record).max(1.0)
        } else {
            f64::INFINITY
        }
    }

    /// Allan variance per unit A² at τ.
    pub(crate) fn avar(&self, tau: f64) -> f64 {
        let m = tau / self.tau0;
        if self.bandwidth == 0.0 {
            crate::ieee952::lines::sinusoid_avar(m, self.frequency * self.tau0)
        } else {
            let (a, b) =
                crate::ieee952::lines::resonance_poles(self.frequency, self.bandwidth, self.tau0);
            0.5 * crate::ieee952::lines::resonance_avar(m.round().max(1.0) as usize, a, b)
        }
    }
}

/// The shape parameters of the non-power-law terms: the Gauss–Markov correlation time, the
/// flicker floor's lower corner (see `flicker_band`) and the lines.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shapes {
    /// Correlation time of the Gauss–Markov bias, s (NaN: not in the model).
    pub gm_t: f64,
    /// Shortest correlation time of the flicker floor, s (0: a flat floor, IEEE 952's B).
    pub b_lo: f64,
    /// The lines of the [`NoiseTerm::Line`] coefficients, by slot (None: that slot is empty).
    pub lines: LineSlots,
}

/// The model's line slots ([`LINE_SLOTS`] of them, written out: rustc 1.9x mis-handles the
/// constant in this field's type inside struct-update closures).
pub type LineSlots = [Option<LineShape>; 3];
const _: () = assert!(LINE_SLOTS == 3);

impl Shapes {
    /// The IEEE 952 power laws alone.
    pub const FLAT: Shapes = Shapes {
        gm_t: f64::NAN,
        b_lo: 0.0,
        lines: [None; 3],
    };

    /// The power laws with the lines `lines`.
    pub(crate) fn with_lines(lines: LineSlots) -> Shapes {
        Shapes {
            lines,
            ..Shapes::FLAT
        }
    }

    /// Whether coefficient j is a fitted term here (a line slot only when it holds a line
    /// whose A² is fitted, [`LineShape::fixed`]).
    pub(crate) fn has(&self, j: usize) -> bool {
        match NoiseTerm::at(j) {
            NoiseTerm::Line(k) => self.lines[k].is_some_and(|l| !l.fixed()),
            _ => true,
        }
    }

    /// The coefficients of the fixed lines (0 elsewhere).
    pub(crate) fn fixed_coef(&self) -> [f64; TERM_COUNT] {
        let mut c = [0.0; TERM_COUNT];
        for (k, l) in self.lines.iter().enumerate() {
            if let Some(l) = l
                && l.fixed()
            {
                c[NoiseTerm::Line(k)] = l.psd_amp2;
            }
        }
        c
    }
}

/// Basis function of coefficient j at τ with the shapes `s`.
pub fn basis_at(j: usize, tau: f64, s: &Shapes) -> f64 {
    term_basis_at(NoiseTerm::at(j), tau, s)
}

/// Basis function of term `t` at τ with the shapes `s`.
pub fn term_basis_at(t: NoiseTerm, tau: f64, s: &Shapes) -> f64 {
    match t {
        GaussMarkov => gm_basis(tau, s.gm_t),
        BiasInstability if s.b_lo > 0.0 => FLICKER_AVAR * flicker_band(tau / s.b_lo),
        NoiseTerm::Line(k) => s.lines[k].map_or(0.0, |l| l.avar(tau)),
        _ => basis(t, tau),
    }
}

/// The coefficients of the power laws that stand in, at τ, for the shaped terms in the
/// covariance of the AVAR points: each shaped term's AVAR goes to the power law of its
/// local slope there (a random walk where it rises like one, white noise where it falls,
/// flicker in between). [`crate::ieee952::avar_cov`] has covariances of power laws only; the EDF of
/// a bump's shoulder is that of the power law it resembles.
pub(in crate::ieee952) fn effective_coef(
    c: &[f64; TERM_COUNT],
    s: &Shapes,
    tau: f64,
) -> [f64; TERM_COUNT] {
    let mut e = *c;
    e[GaussMarkov] = 0.0;
    let spread = |e: &mut [f64; TERM_COUNT], a: f64, shape: &dyn Fn(f64) -> f64| {
        let slope = ((shape(tau * SLOPE_STEP) / shape(tau / SLOPE_STEP)).ln()
            / (2.0 * SLOPE_STEP.ln()))
        .clamp(-1.0, 1.0);
        let t = if slope >= 0.5 {
            RandomWalk
        } else if slope <= -0.5 {
            WhiteNoise
        } else {
            BiasInstability
        };
        e[t] += a / basis(t, tau);
    };
    if s.b_lo > 0.0 && c[BiasInstability] != 0.0 {
        e[BiasInstability] = 0.0;
        let a = c[BiasInstability] * term_basis_at(BiasInstability, tau, s);
        spread(&mut e, a, &|t| term_basis_at(BiasInstability, t, s));
    }
    if c[GaussMarkov] != 0.0 && s.gm_t > 0.0 {
        let a = c[GaussMarkov] * gm_basis(tau, s.gm_t);
        spread(&mut e, a, &|t| gm_basis(t, s.gm_t));
    }
    // a line's share of a point's variance: as white noise of the same Allan variance (its
    // sinusoid's estimate varies less; the covariance errs on the wide side there)
    for l in NoiseTerm::LINES {
        if c[l] != 0.0 {
            e[WhiteNoise] += c[l].max(0.0) * term_basis_at(l, tau, s) / basis(WhiteNoise, tau);
            e[l] = 0.0;
        }
    }
    // a ramp is deterministic, but its estimate at a τ carries the noise's cross term with
    // it: as the random walk of the same Allan variance there, so that an R read off the
    // longest points is as uncertain as those points are (issue 18.5)
    if c[Ramp] > 0.0 {
        e[RandomWalk] += c[Ramp] * basis(Ramp, tau) / basis(RandomWalk, tau);
    }
    e
}

/// Half-width (as a factor) of the local-slope difference in [`effective_coef`].
const SLOPE_STEP: f64 = 1.1;

/// `v > 0` (false for NaN), spelled out so that NaN handling is visible at the call sites.
pub(in crate::ieee952) fn is_positive(v: f64) -> bool {
    v > 0.0
}
