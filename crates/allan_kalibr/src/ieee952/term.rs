//! One identity per noise term: [`NoiseTerm`] names a coefficient of the model the estimator
//! fits (the five IEEE 952 power laws, the Gauss–Markov bias of IEEE 952 Annex C, the
//! vibration lines), and [`TERMS`] holds each term's facts once — its symbol, its name (the
//! field name `sim`'s spec and truth files use), its unit in terms of the sensor's, the
//! slope of its Allan deviation, its Allan variance per unit coefficient and its PSD.
//!
//! Coefficient arrays (`[_; TERM_COUNT]`) are indexed by a term (`coef[NoiseTerm::WhiteNoise]`),
//! so adding a term is a row of [`TERMS`], a variant, and the matches the compiler points at.

use bag2mat::Sensor;
use std::f64::consts::PI;

/// Lines the model can hold (the strongest the PSD finds).
pub const LINE_SLOTS: usize = 3;
/// The model's coefficients: the five IEEE 952 power laws, the Gauss–Markov bias, then up to
/// [`LINE_SLOTS`] vibration lines.
pub const TERM_COUNT: usize = 6 + LINE_SLOTS;

/// A term of the model: one coefficient of the fit, one field of `sim`'s truth.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum NoiseTerm {
    /// Quantization Q (white PM): AVAR 3Q²/τ², coefficient Q².
    Quantization,
    /// White noise density N (white FM, angle/velocity random walk): AVAR N²/τ.
    WhiteNoise,
    /// Bias instability B (flicker FM): AVAR (2 ln2/π)·B² (its floor).
    BiasInstability,
    /// Random walk K (random-walk FM, rate random walk): AVAR K²τ/3.
    RandomWalk,
    /// Rate ramp R: AVAR R²τ²/2.
    Ramp,
    /// Gauss–Markov (exponentially correlated) bias σ with a correlation time T (a shape).
    GaussMarkov,
    /// Vibration line (IEEE 952's sinusoidal noise) in slot k < [`LINE_SLOTS`], coefficient
    /// A²; its shape comes from the PSD.
    Line(usize),
}

/// The Allan variance of a term per unit coefficient.
#[derive(Clone, Copy, Debug)]
pub enum AvarBasis {
    /// A power law of τ alone: the basis function g(τ), AVAR = c·g(τ).
    PowerLaw(fn(f64) -> f64),
    /// A shape with parameters of its own (the Gauss–Markov time, a line's frequency and
    /// width): `fit::basis_at` evaluates it with the fit's shapes.
    Shaped,
}

/// The one-sided PSD (U²/Hz) of a term (IEEE 952 Annex C's two-sided
/// densities, doubled).
#[derive(Clone, Copy, Debug)]
pub enum PsdForm {
    /// The density of coefficient c at frequency f (Hz), sample period τ₀ (s): `(c, f, τ₀)`.
    Density(fn(f64, f64, f64) -> f64),
    /// A shape with parameters of its own (the Gauss–Markov time, a resonance's poles):
    /// `psd::model_psd` evaluates it.
    Shaped,
    /// No spectral density (a deterministic ramp).
    None,
}

/// The facts of one term (a row of [`TERMS`]).
#[derive(Clone, Copy, Debug)]
pub struct TermFacts {
    /// The term.
    pub term: NoiseTerm,
    /// Its IEEE 952 symbol as the section prints it (`Q`, `N`, … `G`, `L1`…).
    pub symbol: &'static str,
    /// Its field name in `sim`'s spec and truth files (`white_noise`, `random_walk`, …).
    pub name: &'static str,
    /// Its unit for a sensor (U the signal's unit): U·s, U/√Hz, U, U·√Hz, U/s, U, U.
    pub unit: fn(Sensor) -> &'static str,
    /// Log-log slope of its Allan deviation where it dominates (NaN: a bump, not a line).
    pub adev_slope: f64,
    /// FM power-law α whose EDF a point it dominates takes (R, a deterministic ramp, is given
    /// RW FM's; the Gauss–Markov bias, flat around its peak, flicker FM's; a line, white FM's:
    /// its bump and ripples come with the white noise's EDF, the wider interval for a nearly
    /// deterministic estimate).
    pub alpha: i32,
    /// Its Allan variance per unit coefficient.
    pub avar: AvarBasis,
    /// Its PSD.
    pub psd: PsdForm,
}

/// 2 ln2/π: the AVAR of bias instability B is this times B².
pub const FLICKER_AVAR: f64 = 2.0 * std::f64::consts::LN_2 / PI;

/// A line slot's row (the slots differ only in their symbol).
const fn line(k: usize, symbol: &'static str) -> TermFacts {
    TermFacts {
        term: NoiseTerm::Line(k),
        symbol,
        name: "lines",
        unit: Sensor::unit,
        adev_slope: f64::NAN,
        alpha: 0,
        avar: AvarBasis::Shaped,
        psd: PsdForm::Shaped,
    }
}

/// Every term's facts, in coefficient order ([`NoiseTerm::index`]).
pub const TERMS: [TermFacts; TERM_COUNT] = [
    TermFacts {
        term: NoiseTerm::Quantization,
        symbol: "Q",
        name: "quantization",
        unit: Sensor::q_unit,
        adev_slope: -1.0,
        alpha: 2,
        avar: AvarBasis::PowerLaw(|tau| 3.0 / (tau * tau)),
        psd: PsdForm::Density(|c, f, tau0| 8.0 * c * (PI * f * tau0).sin().powi(2) / tau0),
    },
    TermFacts {
        term: NoiseTerm::WhiteNoise,
        symbol: "N",
        name: "white_noise",
        unit: Sensor::n_unit,
        adev_slope: -0.5,
        alpha: 0,
        avar: AvarBasis::PowerLaw(|tau| 1.0 / tau),
        psd: PsdForm::Density(|c, _, _| 2.0 * c),
    },
    TermFacts {
        term: NoiseTerm::BiasInstability,
        symbol: "B",
        name: "bias_instability",
        unit: Sensor::unit,
        adev_slope: 0.0,
        alpha: -1,
        avar: AvarBasis::PowerLaw(|_| FLICKER_AVAR),
        psd: PsdForm::Density(|c, f, _| c / (PI * f)),
    },
    TermFacts {
        term: NoiseTerm::RandomWalk,
        symbol: "K",
        name: "random_walk",
        unit: Sensor::k_unit,
        adev_slope: 0.5,
        alpha: -2,
        avar: AvarBasis::PowerLaw(|tau| tau / 3.0),
        psd: PsdForm::Density(|c, f, _| c / (2.0 * PI * PI * f * f)),
    },
    TermFacts {
        term: NoiseTerm::Ramp,
        symbol: "R",
        name: "rate_ramp",
        unit: Sensor::r_unit,
        adev_slope: 1.0,
        alpha: -2,
        avar: AvarBasis::PowerLaw(|tau| tau * tau / 2.0),
        psd: PsdForm::None,
    },
    TermFacts {
        term: NoiseTerm::GaussMarkov,
        symbol: "G",
        name: "gauss_markov",
        unit: Sensor::unit,
        adev_slope: f64::NAN,
        alpha: -1,
        avar: AvarBasis::Shaped,
        psd: PsdForm::Shaped,
    },
    line(0, "L1"),
    line(1, "L2"),
    line(2, "L3"),
];

impl NoiseTerm {
    /// Every term, in coefficient order.
    pub const ALL: [NoiseTerm; TERM_COUNT] = {
        let mut all = [NoiseTerm::Quantization; TERM_COUNT];
        let mut j = 0;
        while j < TERM_COUNT {
            all[j] = TERMS[j].term;
            j += 1;
        }
        all
    };
    /// The five IEEE 952 power laws (Q, N, B, K, R).
    pub const POWER_LAWS: [NoiseTerm; 5] = [
        NoiseTerm::Quantization,
        NoiseTerm::WhiteNoise,
        NoiseTerm::BiasInstability,
        NoiseTerm::RandomWalk,
        NoiseTerm::Ramp,
    ];
    /// The line slots.
    pub const LINES: [NoiseTerm; LINE_SLOTS] = {
        let mut l = [NoiseTerm::Line(0); LINE_SLOTS];
        let mut k = 0;
        while k < LINE_SLOTS {
            l[k] = NoiseTerm::Line(k);
            k += 1;
        }
        l
    };

    /// Its coefficient's index.
    pub const fn index(self) -> usize {
        match self {
            NoiseTerm::Quantization => 0,
            NoiseTerm::WhiteNoise => 1,
            NoiseTerm::BiasInstability => 2,
            NoiseTerm::RandomWalk => 3,
            NoiseTerm::Ramp => 4,
            NoiseTerm::GaussMarkov => 5,
            NoiseTerm::Line(k) => {
                assert!(k < LINE_SLOTS, "line slot out of range");
                6 + k
            }
        }
    }

    /// The term of coefficient `j` (< [`TERM_COUNT`]).
    pub const fn at(j: usize) -> NoiseTerm {
        NoiseTerm::ALL[j]
    }

    /// Its facts (its row of [`TERMS`]).
    pub const fn facts(self) -> TermFacts {
        TERMS[self.index()]
    }

    /// Its IEEE 952 symbol.
    pub const fn symbol(self) -> &'static str {
        self.facts().symbol
    }

    /// Its field name in `sim`'s files.
    pub const fn name(self) -> &'static str {
        self.facts().name
    }

    /// Its unit for `sensor`.
    pub fn unit(self, sensor: Sensor) -> &'static str {
        (self.facts().unit)(sensor)
    }

    /// One of the five IEEE 952 power laws.
    pub const fn is_power_law(self) -> bool {
        matches!(self.facts().avar, AvarBasis::PowerLaw(_))
    }

    /// A vibration line.
    pub const fn is_line(self) -> bool {
        matches!(self, NoiseTerm::Line(_))
    }

    /// Its power-law Allan variance per unit coefficient at τ (0 for a shaped term, whose
    /// basis needs its shape: `fit::basis_at`).
    pub fn power_law_avar(self, tau: f64) -> f64 {
        match self.facts().avar {
            AvarBasis::PowerLaw(g) => g(tau),
            AvarBasis::Shaped => 0.0,
        }
    }

    /// Its PSD with coefficient `c` at `f` Hz, sample period `tau0` (None for a shaped
    /// term or one without a density).
    pub fn density(self, c: f64, f: f64, tau0: f64) -> Option<f64> {
        match self.facts().psd {
            PsdForm::Density(s) => Some(s(c, f, tau0)),
            PsdForm::Shaped | PsdForm::None => None,
        }
    }
}

impl<T> std::ops::Index<NoiseTerm> for [T; TERM_COUNT] {
    type Output = T;
    fn index(&self, t: NoiseTerm) -> &T {
        &self[t.index()]
    }
}

impl<T> std::ops::IndexMut<NoiseTerm> for [T; TERM_COUNT] {
    fn index_mut(&mut self, t: NoiseTerm) -> &mut T {
        &mut self[t.index()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_is_in_coefficient_order() {
        for (j, f) in TERMS.iter().enumerate() {
            assert_eq!(f.term.index(), j, "{}", f.symbol);
            assert_eq!(NoiseTerm::at(j), f.term);
        }
        assert_eq!(NoiseTerm::POWER_LAWS.map(|t| t.is_power_law()), [true; 5]);
    }

    #[test]
    fn power_law_slopes_match_their_avar() {
        // the ADEV slope stated in the table is the one its AVAR basis has
        const SLOPE_TOL: f64 = 1e-12;
        for t in NoiseTerm::POWER_LAWS {
            let (a, b) = (t.power_law_avar(1.0), t.power_law_avar(10.0));
            let slope = 0.5 * (b / a).log10();
            assert!((slope - t.facts().adev_slope).abs() < SLOPE_TOL, "{t:?}");
        }
    }
}
