//! A plain decimal `w · 10^-k` (an integer of at most 19 digits, k fraction digits) to the
//! nearest f64, ties to even — the value every correct parser (fast-float2, Rust's `parse`)
//! gives — for the SIMD row reader ([`super::wide`]), which has already found the digits.
//!
//! Three cases: Clinger's fast path, where `w` and `10^k` are both exact in f64 (`w < 2^53`,
//! `k ≤ 22`), so one IEEE division is the correctly rounded quotient; an integer (`u64 as
//! f64` rounds correctly); else the quotient from a 128-bit reciprocal of `10^k` (Lemire's
//! method restricted to these exponents). The reciprocal is rounded up by less than one, so
//! the top 128 bits of the product are the true quotient's floor or one above it: a true tie
//! shows exactly as one half below the mantissa, and only then (or within a unit of a tie)
//! is the rounding undecided: [`to_f64`] gives `None` and the caller parses the text with
//! fast-float2. The round bit is as often set as not, so the tie test is one comparison,
//! not a branch on it (a branch there mispredicted on every other value that takes this
//! path, such as each of EuRoC's 18-digit accelerometer z readings).

/// The largest fraction length with a reciprocal (10^27 < 2^90 keeps the long division in
/// u128).
pub(super) const MAX_FRACTION_DIGITS: usize = 27;

/// Powers of ten exact in f64 (Clinger's fast path).
const EXACT_POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// `(ceil(2^n / 10^k), n)` with `n` chosen so that the first lies in (2^127, 2^128), for
/// k ≥ 1, by long division one bit at a time (compile time only).
const fn reciprocal(k: u32) -> (u128, u32) {
    let d = 10u128.pow(k);
    let n = 127 + (128 - d.leading_zeros());
    let (mut rem, mut q) = (0u128, 0u128);
    let mut i = n as i32;
    while i >= 0 {
        rem = (rem << 1) | (i == n as i32) as u128;
        if rem >= d {
            rem -= d;
            // the quotient is below 2^128: its set bits are all below 128
            q |= 1 << i;
        }
        i -= 1;
    }
    (q + (rem != 0) as u128, n)
}

/// The reciprocal of `10^k` as its high and low 64 bits, and its `n`.
const RECIPROCALS: [(u64, u64, u32); MAX_FRACTION_DIGITS + 1] = {
    let mut t = [(0u64, 0u64, 0u32); MAX_FRACTION_DIGITS + 1];
    let mut k = 1;
    while k <= MAX_FRACTION_DIGITS {
        let (r, n) = reciprocal(k as u32);
        t[k] = ((r >> 64) as u64, r as u64, n);
        k += 1;
    }
    t
};

/// `(-1)^neg · w · 10^-k` correctly rounded, or `None` where the reciprocal cannot decide
/// (an exact half, or `k` past [`MAX_FRACTION_DIGITS`]).
#[inline(always)]
pub(super) fn to_f64(w: u64, k: usize, neg: bool) -> Option<f64> {
    let v = if w < (1u64 << 53) && k < EXACT_POW10.len() {
        // w < 2^53 converts exactly, also through i64 (one instruction, where u64 takes a
        // branch on its top bit)
        w as i64 as f64 / EXACT_POW10[k]
    } else if k == 0 || w == 0 {
        // an integer; or a zero with more fraction digits than an exact power has
        w as f64
    } else {
        let &(r_hi, r_lo, n) = RECIPROCALS.get(k)?;
        // w normalised to [2^63, 2^64) times r in (2^127, 2^128): the top 128 of its 192
        // bits, in [2^126, 2^128)
        let lz = w.leading_zeros();
        let w = u128::from(w << lz);
        let p = w * u128::from(r_hi) + ((w * u128::from(r_lo)) >> 64);
        let (hi, lo) = ((p >> 64) as u64, p as u64);
        // the 54 bits from the top one (53 and the round bit) end 9 or 10 bits into `hi`
        let s = 10 - hi.leading_zeros();
        let top54 = hi >> s;
        let round = top54 & 1;
        let rest = (hi & ((1u64 << s) - 1)) | lo;
        // round bit set and nothing below it: undecided (one comparison, see the module doc)
        if (rest | (round ^ 1)) == 0 {
            return None;
        }
        let mut m = (top54 >> 1) + round;
        let mut e = (64 + s) as i32 + 65 - n as i32 - lz as i32;
        if m == 1u64 << 53 {
            m >>= 1;
            e += 1;
        }
        // w < 2^64 and k ≤ 27: the value is a normal double, e + 1075 in 1..2047
        f64::from_bits(((e + 52 + 1023) as u64) << 52 | (m & ((1u64 << 52) - 1)))
    };
    // the sign as a bit: `-v` behind a branch on a random sign mispredicts
    Some(f64::from_bits(v.to_bits() | u64::from(neg) << 63))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether `w · 10^-k` lies exactly halfway between two doubles: it is then a dyadic
    /// rational `q / 2^k` (`5^k` divides `w`) whose odd part has 54 significant bits.
    fn is_tie(w: u64, k: usize) -> bool {
        let p = 5u128.pow(k as u32);
        let w = u128::from(w);
        if w == 0 || w % p != 0 {
            return false;
        }
        let q = w / p;
        let odd = q >> q.trailing_zeros();
        128 - odd.leading_zeros() == 54
    }

    /// Seeded decimals of every length and fraction length against Rust's own parser (the
    /// slow, obviously correct reference), bit for bit; the halfway cases must refuse.
    #[test]
    fn every_decimal_rounds_as_rusts_parser_does() {
        const CASES: u64 = 400_000;
        let mut st = 0x2026_1206_u64;
        let mut decided = 0;
        for _ in 0..CASES {
            st = st
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let digits = 1 + (st >> 59) as usize % 19;
            let w = (st >> 3) % 10u64.pow(digits as u32);
            let k = (st >> 40) as usize % (MAX_FRACTION_DIGITS + 1);
            let neg = st & 1 == 1;
            let text = format!("{}{w}e-{k}", if neg { "-" } else { "" });
            let want: f64 = text.parse().unwrap();
            match to_f64(w, k, neg) {
                Some(got) => {
                    assert_eq!(got.to_bits(), want.to_bits(), "{text}");
                    decided += 1;
                }
                // refusing is allowed only on a true tie: the reciprocal's floor is exact
                // there (see the module doc), so any other refusal is a bug
                None => assert!(is_tie(w, k), "{text} refused but is no tie"),
            }
        }
        // ties are rare (a 54-bit odd part after dividing out 5^k), but the seed has some
        assert!(
            decided < CASES && decided > CASES - CASES / 1000,
            "{decided} decided"
        );
        // 2^53 + 1 is halfway between two doubles: the reciprocal refuses, the caller parses
        assert_eq!(to_f64(90_071_992_547_409_930, 1, false), None);
        // just past it: decided, up
        let w = 90_071_992_547_409_931;
        assert_eq!(
            to_f64(w, 1, false),
            Some("9007199254740993.1".parse().unwrap())
        );
        // the largest integer, the smallest value, and 0.999…9 (19 nines), whose mantissa
        // rounds up to the next power of two
        let nines = 9_999_999_999_999_999_999;
        for (w, k) in [(u64::MAX, 0), (nines, 27), (1, 27), (nines, 19)] {
            let want: f64 = format!("{w}e-{k}").parse().unwrap();
            assert_eq!(to_f64(w, k, false), Some(want));
        }
        assert_eq!(
            to_f64(0, 5, true).map(f64::to_bits),
            Some((-0.0f64).to_bits())
        );
    }
}
