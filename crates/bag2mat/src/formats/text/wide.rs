//! The text reader's SIMD row scanner (x86-64 with AVX2, found at run time): the ends,
//! digits and decimal points of a line's first 192 bytes as bit masks, in one pass, its
//! digits turned into an integer sixteen at a time, and the value rounded by
//! [`super::decimal`]. It takes only the plainest lines — a single-byte delimiter, every
//! read field `-?digits[.digits]` with at most 19 digits, an integer time, the line ending
//! straight after the last read column — and hands every other line to
//! [`super::body::fast_row`], so it gives what `fast_row` gives, bit for bit, or nothing.
//! Why: issue 20's benchmark (a 4 h EuRoC CSV against pandas), where fast-float2's
//! byte-at-a-time scan of 17-digit decimals was most of the time.

use super::body::Col;
use super::layout::{Delim, Layout};
use crate::rows::Row;

/// Bytes of a line the scanner looks at, in 32-byte steps: its fields must end inside
/// them, and a line nearer the end of its range is left to `fast_row`.
const ROW_WINDOW: usize = 192;
/// Bytes before a field's start a 16-byte digit window may reach back: a range's first row
/// is left to `fast_row`.
const READ_BEHIND: usize = 16;
/// Digits one u64 holds whatever they are (10^19 < 2^64).
const MAX_DIGITS: u32 = 19;

/// True when the scanner runs here and can read this layout's lines.
pub(super) fn usable(lay: &Layout) -> bool {
    let Delim::Byte(d) = lay.delim else {
        return false;
    };
    // a delimiter that can be part of a number or a quote would need the slow path anyway
    let plain = !(d.is_ascii_digit() || matches!(d, b'.' | b'-' | b'"' | b'\n' | b'\r'));
    plain && avx2()
}

#[cfg(target_arch = "x86_64")]
fn avx2() -> bool {
    std::is_x86_feature_detected!("avx2")
        && std::is_x86_feature_detected!("bmi1")
        && std::is_x86_feature_detected!("lzcnt")
}

#[cfg(not(target_arch = "x86_64"))]
fn avx2() -> bool {
    false
}

/// The row of the line at `text[pos..]` and the bytes it took with its line end, or `None`
/// (the line is for `fast_row`). Only where [`usable`] said so.
pub(super) fn row(text: &[u8], pos: usize, lay: &Layout, cols: &[Col]) -> Option<(Row, usize)> {
    #[cfg(target_arch = "x86_64")]
    {
        let Delim::Byte(d) = lay.delim else {
            return None;
        };
        debug_assert!(avx2());
        // SAFETY: `usable` found AVX2, BMI1 and LZCNT on this CPU
        unsafe { x86::row(text, pos, lay, cols, d) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = (text, pos, lay, cols);
        None
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use super::super::body::Col;
    use super::super::decimal::{POW10, to_f64};
    use super::super::layout::Layout;
    use super::{MAX_DIGITS, READ_BEHIND, ROW_WINDOW};
    use crate::rows::Row;

    /// The value of the `n ≤ 16` digits that end just before `end`.
    ///
    /// # Safety
    /// The 16 bytes before `end` are readable; the `n` before it are ASCII digits.
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn digits16(end: *const u8, n: u32) -> u64 {
        // SAFETY: the caller's contract
        let x = unsafe { _mm_loadu_si128(end.sub(16).cast()) };
        let v = _mm_sub_epi8(x, _mm_set1_epi8(b'0' as i8));
        let lane = _mm_setr_epi8(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
        // keep the last n lanes: the bytes before the digits count as leading zeros
        let v = _mm_and_si128(v, _mm_cmpgt_epi8(lane, _mm_set1_epi8(15 - n as i8)));
        let pairs = _mm_maddubs_epi16(
            v,
            _mm_setr_epi8(10, 1, 10, 1, 10, 1, 10, 1, 10, 1, 10, 1, 10, 1, 10, 1),
        );
        let fours = _mm_madd_epi16(pairs, _mm_setr_epi16(100, 1, 100, 1, 100, 1, 100, 1));
        let fours = _mm_packus_epi32(fours, fours);
        let eights = _mm_madd_epi16(
            fours,
            _mm_setr_epi16(10000, 1, 10000, 1, 10000, 1, 10000, 1),
        );
        let hi = _mm_cvtsi128_si32(eights) as u32 as u64;
        let lo = _mm_extract_epi32::<1>(eights) as u32 as u64;
        hi * 100_000_000 + lo
    }

    /// The value of the `n ≤ 19` digits that end just before `end`.
    ///
    /// # Safety
    /// As [`digits16`], and the `n` bytes before `end` are readable.
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn digits(end: *const u8, n: u32) -> u64 {
        // SAFETY: the caller's contract
        unsafe {
            if n <= 16 {
                return digits16(end, n);
            }
            let mut high = 0u64;
            for j in (17..=n as usize).rev() {
                high = high * 10 + u64::from(*end.sub(j) - b'0');
            }
            high * POW10[16] + digits16(end, 16)
        }
    }

    /// The masks of a row's first [`ROW_WINDOW`] bytes, bit i for byte i (one spare word
    /// of zeros so that 64 bits can be read from any position in the window).
    struct Masks {
        ends: [u64; 4],
        digits: [u64; 4],
        dots: [u64; 4],
        quotes: [u64; 4],
    }

    /// The 64 bits of `m` from bit `s` (< ROW_WINDOW) on.
    #[inline(always)]
    fn bits(m: &[u64; 4], s: usize) -> u64 {
        let w = s >> 6;
        let pair = u128::from(m[w + 1]) << 64 | u128::from(m[w]);
        (pair >> (s & 63)) as u64
    }

    /// See [`super::row`].
    ///
    /// # Safety
    /// The CPU has AVX2, BMI1 and LZCNT.
    // One body, like fast_row: the masks, the position and the row stay in registers.
    #[target_feature(enable = "avx2,bmi1,lzcnt")]
    pub(super) unsafe fn row(
        text: &[u8],
        pos: usize,
        lay: &Layout,
        cols: &[Col],
        d: u8,
    ) -> Option<(Row, usize)> {
        if pos < READ_BEHIND || pos + ROW_WINDOW + 1 > text.len() {
            return None;
        }
        let mut m = Masks {
            ends: [0; 4],
            digits: [0; 4],
            dots: [0; 4],
            quotes: [0; 4],
        };
        // the whole window at once: its masks do not wait on the fields before
        for j in 0..ROW_WINDOW / 32 {
            // SAFETY: pos + ROW_WINDOW ≤ text.len()
            let x = unsafe { _mm256_loadu_si256(text.as_ptr().add(pos + 32 * j).cast()) };
            let is = |c: u8| _mm256_cmpeq_epi8(x, _mm256_set1_epi8(c as i8));
            let ends = _mm256_or_si256(_mm256_or_si256(is(d), is(b'\n')), is(b'\r'));
            let y = _mm256_sub_epi8(x, _mm256_set1_epi8(b'0' as i8));
            let digit = _mm256_cmpeq_epi8(_mm256_min_epu8(y, _mm256_set1_epi8(9)), y);
            let half = 32 * (j & 1);
            let put = |v: __m256i| u64::from(_mm256_movemask_epi8(v) as u32) << half;
            m.ends[j >> 1] |= put(ends);
            m.digits[j >> 1] |= put(digit);
            m.dots[j >> 1] |= put(is(b'.'));
            m.quotes[j >> 1] |= put(is(b'"'));
        }
        let mut row = Row {
            stamp: 0,
            acc: [f64::NAN; 3],
            gyro: [f64::NAN; 3],
        };
        // s: the field's start in the window
        let mut s = 0;
        for (k, col) in cols.iter().enumerate() {
            if s >= ROW_WINDOW {
                return None;
            }
            let ends = bits(&m.ends, s);
            // the field is the window's s..s + e; a field of 32 bytes or more is fast_row's
            let e = ends.trailing_zeros();
            if e >= 32 {
                return None;
            }
            let field = (1u64 << e) - 1;
            if let Col::Skip = col {
                if bits(&m.quotes, s) & field != 0 {
                    return None;
                }
            } else {
                // SAFETY: in the window
                let at = unsafe { text.as_ptr().add(pos + s) };
                let neg = u32::from(unsafe { *at } == b'-');
                let body = field & !((1u64 << neg) - 1);
                let dots = bits(&m.dots, s) & body;
                if (bits(&m.digits, s) | dots) & body != body || dots & dots.wrapping_sub(1) != 0 {
                    return None;
                }
                let point = if dots == 0 { e } else { dots.trailing_zeros() };
                let int_len = point - neg;
                let frac_len = if dots == 0 { 0 } else { e - point - 1 };
                if int_len + frac_len == 0 || int_len + frac_len > MAX_DIGITS {
                    return None;
                }
                // SAFETY: every digit run ends in the window, and pos ≥ READ_BEHIND: the 16
                // bytes before either end are in `text`; the runs are digits (checked)
                let w = unsafe {
                    let end = at.add(e as usize);
                    if dots == 0 {
                        digits(end, int_len)
                    } else {
                        let int = match int_len {
                            0 => 0,
                            1 => u64::from(*at.add(point as usize - 1) - b'0'),
                            n => digits(at.add(point as usize), n),
                        };
                        int * POW10[frac_len as usize] + digits(end, frac_len)
                    }
                };
                match col {
                    Col::Time if neg == 0 && dots == 0 => {
                        row.stamp = w.checked_mul(lay.time_unit.nanos())?;
                    }
                    Col::Gyro(a) => {
                        row.gyro[*a] = to_f64(w, frac_len as usize, neg == 1)? * lay.gyro_si
                    }
                    Col::Acc(a) => {
                        row.acc[*a] = to_f64(w, frac_len as usize, neg == 1)? * lay.acc_si
                    }
                    _ => return None,
                }
            }
            let end = pos + s + e as usize;
            if k + 1 < cols.len() {
                if text[end] != d {
                    return None;
                }
                s += e as usize + 1;
            } else {
                // the line ends straight after the last column read, or fast_row reads it
                return match (text[end], text[end + 1]) {
                    (b'\n', _) => Some((row, end + 1 - pos)),
                    (b'\r', b'\n') => Some((row, end + 2 - pos)),
                    _ => None,
                };
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::super::body::{columns, fast_row};
    use super::*;

    /// A layout of the given columns, delimiter and scale.
    fn layout(d: u8, time: Option<usize>, gyro: [usize; 3], acc: [usize; 3]) -> Layout {
        Layout::for_test(Delim::Byte(d), time, (gyro, acc), (0.5, 1.0))
    }

    /// A seeded field: mostly plain decimals of every length, sometimes a form the scanner
    /// must leave to fast_row (exponent, blank, sign, too many digits, text, empty).
    fn field(st: &mut u64) -> String {
        *st = st
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let r = *st >> 33;
        let digits: String = (0..1 + r % 22)
            .map(|i| char::from(b'0' + ((r >> (i % 20)) as u8 ^ i as u8) % 10))
            .collect();
        let cut = (r >> 7) as usize % (digits.len() + 1);
        let (int, frac) = digits.split_at(cut);
        let sign = if r & 1 == 1 { "-" } else { "" };
        match (r >> 12) % 16 {
            0 => format!("{sign}{int}e-{}", r % 30),
            1 => format!(" {sign}{int}.{frac}"),
            2 => format!("+{int}.{frac}"),
            3 => "nan".into(),
            4 => String::new(),
            5 => format!("{sign}{int}"),
            6 => format!("{sign}.{frac}"),
            7 => format!("{sign}{int}."),
            _ => format!("{sign}{int}.{frac}"),
        }
    }

    /// The scanner gives what fast_row gives on every line it takes, bit for bit, and takes
    /// the plain ones (checked only where AVX2 is found: elsewhere it is never used).
    #[test]
    fn the_wide_scanner_reads_what_fast_row_reads() {
        const LINES: usize = 60_000;
        if !avx2() {
            eprintln!("no AVX2 here: the scanner is off and fast_row reads every line");
            return;
        }
        let mut st = 0x5EED_2026_u64;
        let lays = [
            layout(b',', Some(0), [1, 2, 3], [4, 5, 6]),
            layout(b';', Some(1), [4, 5, 6], [2, 7, 3]),
            layout(b'\t', None, [0, 1, 2], [3, 4, 5]),
        ];
        for lay in &lays {
            let cols = columns(lay);
            let mut text = "h\n".repeat(20);
            let d = char::from(match lay.delim {
                Delim::Byte(d) => d,
                Delim::Whitespace(_) => unreachable!(),
            });
            for i in 0..LINES {
                let n = cols.len() + usize::from(i % 17 == 0);
                let mut line: Vec<String> = (0..n).map(|_| field(&mut st)).collect();
                if let Some(t) = lay.time {
                    line[t] = if i % 13 == 0 {
                        format!("{i}.5")
                    } else {
                        format!("{}", 1_403_636_579_758_555_392 + i as u64 * 5_000_000)
                    };
                }
                if i % 19 == 0 {
                    line[0] = "\"q\"".into();
                }
                text += &line.join(&d.to_string());
                text += if i % 7 == 0 { "\r\n" } else { "\n" };
            }
            text += &"\n".repeat(ROW_WINDOW);
            let b = text.as_bytes();
            let (mut pos, mut took_wide, mut lines) = (40, 0, 0);
            while pos + ROW_WINDOW < b.len() {
                let slow = fast_row(&b[pos..], lay, &cols);
                let wide = row(b, pos, lay, &cols);
                if let Some((r, n)) = wide {
                    let (s, m) = slow.expect("the scanner took a line fast_row refuses");
                    assert_eq!(n, m);
                    assert_eq!(r.stamp, s.stamp);
                    for a in 0..3 {
                        assert_eq!(r.gyro[a].to_bits(), s.gyro[a].to_bits());
                        assert_eq!(r.acc[a].to_bits(), s.acc[a].to_bits());
                    }
                    took_wide += 1;
                }
                lines += 1;
                pos += b[pos..].iter().position(|&c| c == b'\n').unwrap() + 1;
            }
            assert!(lines >= LINES, "{lines}");
            // a line is plain when each of its read fields is (about 5 in 8 each)
            assert!(took_wide > 0, "no line taken by the scanner");
        }
    }

    /// A EuRoC line, the benchmark's: taken by the scanner (not left to fast_row).
    #[test]
    fn the_wide_scanner_takes_euroc_lines() {
        if !avx2() {
            return;
        }
        let lay = layout(b',', Some(0), [1, 2, 3], [4, 5, 6]);
        let line = concat!(
            "1403636579758555392,-0.00123456789012345,0.09913470151327790,",
            "-0.00032156565656565,0.01234567890123456,-0.01999999999999999,",
            "9.81234567890123457\n"
        );
        let text = format!("{}{line}{}", "#".repeat(16), "\n".repeat(ROW_WINDOW));
        let (r, n) = row(text.as_bytes(), 16, &lay, &columns(&lay)).expect("taken");
        assert_eq!(n, line.len());
        assert_eq!(r.stamp, 1_403_636_579_758_555_392);
        assert_eq!(r.acc[2], "9.81234567890123457".parse::<f64>().unwrap());
        assert_eq!(r.gyro[0], -0.00123456789012345 * 0.5);
    }
}
