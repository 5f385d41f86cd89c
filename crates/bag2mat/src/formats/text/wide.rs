//! The text reader's SIMD row scanner (x86-64 with AVX2, BMI1/2 and LZCNT, found at run
//! time). Per field: one 32-byte load at its start classifies its bytes (digits, a point, a
//! leading minus) and finds its end; the 32 bytes that end where the field ends, with the
//! bytes before the point moved up over it (a blend with the load one byte earlier), turn
//! its at most 19 digits into an integer in one multiply-add tree; [`super::decimal`]
//! rounds it. It takes only the plainest lines — a single-byte delimiter, every read field
//! `-?digits[.digits]` with at most 19 digits, an integer time, the line ending straight
//! after the last read column — and hands every other line to [`super::body::fast_row`], so
//! it gives what `fast_row` gives, bit for bit, or nothing. [`rows`] reads plain lines one
//! after another straight into the range's slot (no call per line); [`rows2`] reads two
//! ranges so, a line of each at a time, field by field side by side: each field starts where
//! the one before it ended, so one line is a chain of dependent loads, and two independent
//! chains keep the CPU busier (12 % less time on one core than one line at a time).
//! Why: issue 20's benchmark (a 4 h EuRoC CSV against pandas), where fast-float2's
//! byte-at-a-time scan of 17-digit decimals was most of the time.

use super::body::{Col, Cursor};
use super::layout::{Delim, Layout};
#[cfg(test)]
use crate::rows::Row;

/// Bytes a field may take with its delimiter: one load holds it, and a line reads at most
/// this per column from its start.
const FIELD_WINDOW: usize = 32;
/// Bytes before a field's end its right-aligned loads reach back (32, and one more for the
/// bytes before the point): a range's first line is left to `fast_row`.
const READ_BEHIND: usize = FIELD_WINDOW + 1;
/// Digits one u64 holds whatever they are (10^19 < 2^64).
const MAX_DIGITS: u32 = 19;

/// True when the scanner runs here and can read this layout's lines.
pub(super) fn usable(lay: &Layout) -> bool {
    let Delim::Byte(d) = lay.delim else {
        return false;
    };
    // a delimiter that can be part of a number or a quote would need the slow path anyway
    let plain = !(d.is_ascii_digit() || matches!(d, b'.' | b'-' | b'"' | b'\n' | b'\r'));
    plain && simd()
}

#[cfg(target_arch = "x86_64")]
fn simd() -> bool {
    std::is_x86_feature_detected!("avx2")
        && std::is_x86_feature_detected!("bmi1")
        && std::is_x86_feature_detected!("bmi2")
        && std::is_x86_feature_detected!("lzcnt")
}

#[cfg(not(target_arch = "x86_64"))]
fn simd() -> bool {
    false
}

/// The row of the line at `text[pos..]` and the bytes it took with its line end, or `None`
/// (the line is for `fast_row`). Only where [`usable`] said so.
#[cfg(test)]
pub(super) fn row(text: &[u8], pos: usize, lay: &Layout, cols: &[Col]) -> Option<(Row, usize)> {
    #[cfg(target_arch = "x86_64")]
    {
        let Delim::Byte(d) = lay.delim else {
            return None;
        };
        debug_assert!(simd());
        // SAFETY: `usable` found the instructions on this CPU
        unsafe { x86::row(text, pos, lay, cols, d) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = (text, pos, lay, cols);
        None
    }
}

/// Reads the cursor's lines on while the scanner takes them, each into its slot, and stops
/// at the first line it leaves to `fast_row`, or at the end. Only where [`usable`] said so.
pub(super) fn rows(c: &mut Cursor, lay: &Layout, cols: &[Col]) {
    #[cfg(target_arch = "x86_64")]
    if let Delim::Byte(d) = lay.delim {
        debug_assert!(simd());
        // SAFETY: `usable` found the instructions on this CPU
        unsafe { x86::rows(c, lay, cols, d) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (c, lay, cols);
}

/// [`rows`] of two cursors, a line of each in turn, read field by field side by side; stops
/// when the scanner leaves a line of either to `fast_row` (or either ends), and says which
/// of them has a line it did not take.
pub(super) fn rows2(a: &mut Cursor, b: &mut Cursor, lay: &Layout, cols: &[Col]) -> (bool, bool) {
    #[cfg(target_arch = "x86_64")]
    if let Delim::Byte(d) = lay.delim {
        debug_assert!(simd());
        // SAFETY: `usable` found the instructions on this CPU
        return unsafe { x86::rows2(a, b, lay, cols, d) };
    }
    let _ = (a, b, lay, cols);
    (true, true)
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use super::super::body::{Col, Cursor, Order};
    use super::super::decimal::to_f64;
    use super::super::layout::Layout;
    use super::{FIELD_WINDOW, MAX_DIGITS, READ_BEHIND};
    #[cfg(test)]
    use crate::rows::Row;
    use crate::time::RosTime;

    /// 32 zero bytes, then 32 of all ones: the 32 bytes from `TAIL[q]` keep the last `q`
    /// lanes of a vector.
    static TAIL: [u8; 64] = {
        let mut t = [0u8; 64];
        let mut i = 32;
        while i < 64 {
            t[i] = 0xff;
            i += 1;
        }
        t
    };

    /// A number field: its digits as an integer, the count of digits after its point, and
    /// the rest of what the row needs of it.
    struct Number {
        w: u64,
        frac: u32,
        neg: bool,
        point: bool,
        /// Its bytes: the delimiter or line end follows.
        len: usize,
    }

    /// The last `q ≤ 32` lanes of an all-ones vector.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn tail(q: u32) -> __m256i {
        // SAFETY: q ≤ 32, so the 32 bytes from TAIL[q] are in TAIL
        unsafe { _mm256_loadu_si256(TAIL.as_ptr().add(q as usize).cast()) }
    }

    /// The number that starts at `at`, or `None` (not `-?digits[.digits]` of at most
    /// [`MAX_DIGITS`] digits followed by a byte that is none of them).
    ///
    /// # Safety
    /// The 32 bytes from `at` and the [`READ_BEHIND`] bytes before it are readable.
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt")]
    #[inline]
    unsafe fn number(at: *const u8) -> Option<Number> {
        let zero = _mm256_set1_epi8(b'0' as i8);
        // SAFETY: the caller's contract
        let x = unsafe { _mm256_loadu_si256(at.cast()) };
        let y = _mm256_sub_epi8(x, zero);
        let digit = _mm256_cmpeq_epi8(_mm256_min_epu8(y, _mm256_set1_epi8(9)), y);
        let dot = _mm256_cmpeq_epi8(x, _mm256_set1_epi8(b'.' as i8));
        // SAFETY: the caller's contract
        let neg = u32::from(unsafe { *at } == b'-');
        let num = _mm256_movemask_epi8(_mm256_or_si256(digit, dot)) as u32 | neg;
        // the field's length: its first byte that is no digit, point or leading minus
        let len = (!num).trailing_zeros();
        let points = _bzhi_u32(_mm256_movemask_epi8(dot) as u32, len);
        let point = u32::from(points != 0);
        // the sign and each point are lanes of their own, so this does not wrap; at most
        // MAX_DIGITS digits also bounds len below 32
        let digits = len - neg - point;
        // two points, no digit or too many: one branch (`|`, not `||`)
        if (points & points.wrapping_sub(1) != 0) | (digits.wrapping_sub(1) >= MAX_DIGITS) {
            return None;
        }
        let frac = if point == 1 {
            len - 1 - points.trailing_zeros()
        } else {
            0
        };
        // SAFETY: the field ends inside the 32 bytes from `at`, and the 33 bytes before its
        // end start at or after `at - READ_BEHIND`
        let (x1, x2) = unsafe {
            let end = at.add(len as usize);
            (
                _mm256_loadu_si256(end.sub(32).cast()),
                _mm256_loadu_si256(end.sub(33).cast()),
            )
        };
        // the field's digits right-aligned: the bytes after the point as they are, those
        // before it one lane up (over the point), the rest zero
        let after = tail(if point == 1 { frac } else { 32 });
        let r = _mm256_sub_epi8(_mm256_blendv_epi8(x2, x1, after), zero);
        let r = _mm256_and_si256(r, tail(digits));
        Some(Number {
            w: value(r),
            frac,
            neg: neg == 1,
            point: point == 1,
            len: len as usize,
        })
    }

    /// The integer of 32 lanes of digit values (0–9), of which only the last 19 may be
    /// non-zero.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn value(r: __m256i) -> u64 {
        // pairs (bytes × 10, 1), fours (× 100, 1), eights (× 10000, 1) of digits; the
        // eights of lanes 8–15, 16–23 and 24–31 make the number
        let twos = _mm256_maddubs_epi16(r, _mm256_set1_epi16(0x01_0a));
        let fours = _mm256_madd_epi16(twos, _mm256_set1_epi32(0x0001_0064));
        let fours = _mm256_packus_epi32(fours, fours);
        let eights = _mm256_madd_epi16(fours, _mm256_set1_epi32(0x0001_2710));
        let high = _mm256_extract_epi32::<1>(eights) as u32 as u64;
        let low = _mm_cvtsi128_si64(_mm256_extracti128_si256::<1>(eights)) as u64;
        (high * 100_000_000 + (low & 0xffff_ffff)) * 100_000_000 + (low >> 32)
    }

    /// What the loop does with one column's field.
    #[derive(Clone, Copy)]
    enum Field {
        Skip,
        Time,
        /// A value: column `dst` of the row (acc x y z, then gyro x y z), times `si`.
        Value {
            dst: usize,
            si: f64,
        },
    }

    /// The fields of a layout's columns, and the value columns none of them fills.
    fn fields(lay: &Layout, cols: &[Col]) -> (Vec<Field>, Vec<usize>) {
        let mut filled = [false; 6];
        let fields = cols
            .iter()
            .map(|c| match *c {
                Col::Skip => Field::Skip,
                Col::Time => Field::Time,
                Col::Acc(i) => {
                    filled[i] = true;
                    Field::Value {
                        dst: i,
                        si: lay.acc_si,
                    }
                }
                Col::Gyro(i) => {
                    filled[3 + i] = true;
                    Field::Value {
                        dst: 3 + i,
                        si: lay.gyro_si,
                    }
                }
            })
            .collect();
        let absent = (0..6).filter(|&c| !filled[c]).collect();
        (fields, absent)
    }

    /// Reads one field of a line, the one at `text[a..]`: its value to `put(dst, v)`, its
    /// time to `stamp`; returns where it ends, or `None` (the line is for fast_row).
    ///
    /// # Safety
    /// The CPU has AVX2, BMI1, BMI2 and LZCNT; the 32 bytes from `a` and the
    /// [`READ_BEHIND`] bytes before it are in `text`.
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt")]
    #[inline]
    unsafe fn field(
        text: &[u8],
        a: usize,
        field: Field,
        (d, ns_per_unit): (u8, u64),
        stamp: &mut u64,
        put: &mut impl FnMut(usize, f64),
    ) -> Option<usize> {
        // SAFETY (each use): the caller's contract
        let at = unsafe { text.as_ptr().add(a) };
        let len = match field {
            Field::Value { dst, si } => {
                let n = unsafe { number(at) }?;
                put(dst, to_f64(n.w, n.frac as usize, n.neg)? * si);
                n.len
            }
            Field::Time => {
                let n = unsafe { number(at) }?;
                if n.neg || n.point {
                    return None;
                }
                *stamp = n.w.checked_mul(ns_per_unit)?;
                n.len
            }
            Field::Skip => {
                let x = unsafe { _mm256_loadu_si256(at.cast()) };
                let is = |c: u8| _mm256_cmpeq_epi8(x, _mm256_set1_epi8(c as i8));
                let ends = _mm256_or_si256(_mm256_or_si256(is(d), is(b'\n')), is(b'\r'));
                let len = (_mm256_movemask_epi8(ends) as u32).trailing_zeros();
                // a field of 32 bytes or more is fast_row's, and so is a quote
                if len >= 32 || _bzhi_u32(_mm256_movemask_epi8(is(b'"')) as u32, len) != 0 {
                    return None;
                }
                len as usize
            }
        };
        Some(a + len)
    }

    /// After a line's last field (ending at `end`): the bytes the line from `pos` took with
    /// its line end, or `None` when more follows (fast_row reads it).
    ///
    /// # Safety
    /// `end + 1` is in `text` (as [`room_for`] leaves it after a line's last field).
    #[inline]
    unsafe fn line_end(text: &[u8], pos: usize, end: usize) -> Option<usize> {
        // SAFETY: the caller's contract
        match unsafe { (*text.get_unchecked(end), *text.get_unchecked(end + 1)) } {
            (b'\n', _) => Some(end + 1 - pos),
            (b'\r', b'\n') => Some(end + 2 - pos),
            _ => None,
        }
    }

    /// True when every field of a line from `pos` starts within `text` with room for the
    /// scanner's reads: each field starts within FIELD_WINDOW bytes of the one before.
    #[inline]
    fn room_for(text: &[u8], pos: usize, fields: &[Field]) -> bool {
        pos >= READ_BEHIND && pos + FIELD_WINDOW * fields.len() + 2 <= text.len()
    }

    /// Reads the line at `text[pos..]`: each value to `put(dst, v)`, and returns its stamp
    /// (0 without a time column) and the bytes it took with its line end; `None` leaves the
    /// line to fast_row (some values may have been put).
    ///
    /// # Safety
    /// The CPU has AVX2, BMI1, BMI2 and LZCNT.
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt")]
    #[inline]
    unsafe fn line(
        text: &[u8],
        pos: usize,
        fields: &[Field],
        dn: (u8, u64),
        mut put: impl FnMut(usize, f64),
    ) -> Option<(u64, usize)> {
        if !room_for(text, pos, fields) {
            return None;
        }
        let (mut stamp, mut a) = (0, pos);
        let last = fields.len() - 1;
        for (k, &f) in fields.iter().enumerate() {
            // SAFETY: a < pos + FIELD_WINDOW · k (each field took less than FIELD_WINDOW
            // bytes), so room_for leaves the 32 bytes from it in `text`; a ≥ READ_BEHIND
            let end = unsafe { field(text, a, f, dn, &mut stamp, &mut put) }?;
            // SAFETY (both): a field ends within FIELD_WINDOW bytes of its start, and
            // room_for leaves FIELD_WINDOW bytes per field and 2 more
            if k == last {
                return unsafe { line_end(text, pos, end) }.map(|took| (stamp, took));
            }
            if unsafe { *text.get_unchecked(end) } != dn.0 {
                return None;
            }
            a = end + 1;
        }
        None
    }

    /// [`line`] of two lines, field by field side by side (the first field of each, then
    /// the second of each, …): each line's fields form one chain of loads, and the CPU
    /// overlaps two independent chains where it could not overlap the fields of one.
    /// `None` when either is left to fast_row.
    ///
    /// # Safety
    /// As [`line`].
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt")]
    #[inline]
    unsafe fn line2(
        (ta, pa): (&[u8], usize),
        (tb, pb): (&[u8], usize),
        fields: &[Field],
        dn: (u8, u64),
        (mut put_a, mut put_b): (impl FnMut(usize, f64), impl FnMut(usize, f64)),
    ) -> Option<((u64, usize), (u64, usize))> {
        if !(room_for(ta, pa, fields) && room_for(tb, pb, fields)) {
            return None;
        }
        let (mut sa, mut sb) = (0, 0);
        let (mut a, mut b) = (pa, pb);
        let last = fields.len() - 1;
        for (k, &f) in fields.iter().enumerate() {
            // SAFETY: as in `line`, for each
            let ea = unsafe { field(ta, a, f, dn, &mut sa, &mut put_a) }?;
            let eb = unsafe { field(tb, b, f, dn, &mut sb, &mut put_b) }?;
            // SAFETY (each): a field ends within FIELD_WINDOW bytes of its start, and
            // room_for leaves FIELD_WINDOW bytes per field and 2 more
            if k == last {
                let took_a = unsafe { line_end(ta, pa, ea) }?;
                let took_b = unsafe { line_end(tb, pb, eb) }?;
                return Some(((sa, took_a), (sb, took_b)));
            }
            if unsafe { *ta.get_unchecked(ea) != dn.0 || *tb.get_unchecked(eb) != dn.0 } {
                return None;
            }
            (a, b) = (ea + 1, eb + 1);
        }
        None
    }

    /// See [`super::row`].
    ///
    /// # Safety
    /// As [`line`].
    #[cfg(test)]
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt")]
    pub(super) unsafe fn row(
        text: &[u8],
        pos: usize,
        lay: &Layout,
        cols: &[Col],
        d: u8,
    ) -> Option<(Row, usize)> {
        let (fields, _) = fields(lay, cols);
        let mut v = [f64::NAN; 6];
        let dn = (d, lay.time_unit.nanos());
        // SAFETY: the caller's contract
        let (stamp, took) = unsafe { line(text, pos, &fields, dn, |c, x| v[c] = x) }?;
        let row = Row {
            stamp,
            acc: [v[0], v[1], v[2]],
            gyro: [v[3], v[4], v[5]],
        };
        Some((row, took))
    }

    /// A cursor as the loops read and write it: raw pointers to its slot's columns (one
    /// bounds check for all rows), and its position and counts in registers, stored back by
    /// [`Sink::store`].
    struct Sink {
        dst: [*mut f64; 6],
        record_time: *mut RosTime,
        stamp: *mut RosTime,
        /// The next row, and the slot's room.
        i: usize,
        cap: usize,
        /// Where the next line starts in the cursor's text.
        pos: usize,
        line: u64,
        order: Order,
    }

    impl Sink {
        fn of(c: &mut Cursor) -> Sink {
            let slot = &mut c.out.slot;
            let cap = slot.cap();
            let [a0, a1, a2] = &mut slot.acc;
            let [g0, g1, g2] = &mut slot.gyro;
            let values = [a0, a1, a2, g0, g1, g2].map(|c| &mut **c);
            // every column has a row for each index below `cap`: the writes stay in them
            assert!(
                values.iter().all(|c| c.len() == cap) && slot.stamp.len() == cap,
                "a slot's columns differ in length"
            );
            Sink {
                dst: values.map(|c| c.as_mut_ptr()),
                record_time: slot.record_time.as_mut_ptr(),
                stamp: slot.stamp.as_mut_ptr(),
                i: c.out.got.filled,
                cap,
                pos: c.pos,
                line: c.line,
                order: c.out.got.order,
            }
        }

        fn full(&self) -> bool {
            self.i >= self.cap
        }

        /// Writes value column `c` of the next row.
        #[inline(always)]
        fn put(&self, c: usize, v: f64) {
            debug_assert!(self.i < self.cap);
            // SAFETY: i < cap (the loops check `full` first), and `of` checked the columns;
            // c < 6: `fields` makes each dst i or 3 + i of a sensor axis i < 3
            unsafe { *self.dst.get_unchecked(c).add(self.i) = v }
        }

        /// Completes the next row, whose line took `took` bytes: its stamp, and NaN in the
        /// `absent` columns.
        #[inline(always)]
        fn commit(&mut self, (t, took): (u64, usize), absent: &[usize]) {
            let time = RosTime::from_nanos(t);
            // SAFETY: as in `put`
            unsafe {
                for &c in absent {
                    *self.dst[c].add(self.i) = f64::NAN;
                }
                *self.record_time.add(self.i) = time;
                *self.stamp.add(self.i) = time;
            }
            self.i += 1;
            self.pos += took;
            self.line += 1;
            self.order.next(self.line, t);
        }

        /// Reads the next line of `text` into the next row if the scanner takes it.
        ///
        /// # Safety
        /// As [`line`]; the slot is not [`Sink::full`].
        #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt")]
        #[inline]
        unsafe fn next_line(
            &mut self,
            text: &[u8],
            fields: &[Field],
            dn: (u8, u64),
            absent: &[usize],
        ) -> bool {
            // SAFETY: the caller's contract
            match unsafe { line(text, self.pos, fields, dn, |k, v| self.put(k, v)) } {
                Some(r) => {
                    self.commit(r, absent);
                    true
                }
                None => false,
            }
        }

        fn store(self, c: &mut Cursor) {
            (c.pos, c.out.got.filled, c.line) = (self.pos, self.i, self.line);
            c.out.got.order = self.order;
        }
    }

    /// See [`super::rows`].
    ///
    /// # Safety
    /// As [`line`].
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt")]
    pub(super) unsafe fn rows(c: &mut Cursor, lay: &Layout, cols: &[Col], d: u8) {
        let (fields, absent) = fields(lay, cols);
        let dn = (d, lay.time_unit.nanos());
        let mut s = Sink::of(c);
        // SAFETY: the caller's contract; `full` is checked first
        while !s.full() && unsafe { s.next_line(c.text, &fields, dn, &absent) } {}
        s.store(c);
    }

    /// See [`super::rows2`].
    ///
    /// # Safety
    /// As [`line`].
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt")]
    pub(super) unsafe fn rows2(
        ca: &mut Cursor,
        cb: &mut Cursor,
        lay: &Layout,
        cols: &[Col],
        d: u8,
    ) -> (bool, bool) {
        let (fields, absent) = fields(lay, cols);
        let dn = (d, lay.time_unit.nanos());
        let (mut sa, mut sb) = (Sink::of(ca), Sink::of(cb));
        let (ta, tb) = (ca.text, cb.text);
        let stuck = loop {
            if sa.full() || sb.full() {
                break (sa.full(), sb.full());
            }
            let (a, b) = ((ta, sa.pos), (tb, sb.pos));
            let puts = (|k, v| sa.put(k, v), |k, v| sb.put(k, v));
            // SAFETY (each call): the caller's contract; neither slot is full
            match unsafe { line2(a, b, &fields, dn, puts) } {
                Some((ra, rb)) => {
                    sa.commit(ra, &absent);
                    sb.commit(rb, &absent);
                }
                None => {
                    // one of them (or both) is fast_row's: the other's line on its own
                    let a = unsafe { sa.next_line(ta, &fields, dn, &absent) };
                    let b = unsafe { sb.next_line(tb, &fields, dn, &absent) };
                    if !(a && b) {
                        break (!a, !b);
                    }
                }
            }
        };
        sa.store(ca);
        sb.store(cb);
        stuck
    }
}

#[cfg(test)]
mod tests {
    use super::super::body::{Chunk, Summary, columns, fast_row, parse_lines, parse_pair, room};
    use super::*;
    use crate::rows::Rows;

    /// Line ends after the test lines: room for the scanner's reads past a line's start.
    const PAD: usize = 16 * FIELD_WINDOW;

    /// A layout of the given columns, delimiter and scale.
    fn layout(d: u8, time: Option<usize>, gyro: [usize; 3], acc: [usize; 3]) -> Layout {
        Layout::for_test(Delim::Byte(d), time, (gyro, acc), (0.5, 1.0))
    }

    /// A seeded field: a plain decimal of any length where `plain`, else mostly one and
    /// sometimes a form the scanner must leave to fast_row (exponent, blank, sign, too many
    /// digits, text, empty, two points).
    fn field(st: &mut u64, plain: bool) -> String {
        *st = st
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let r = *st >> 33;
        let digits: String = (0..1 + r % if plain { 19 } else { 22 })
            .map(|i| char::from(b'0' + ((r >> (i % 20)) as u8 ^ i as u8) % 10))
            .collect();
        let cut = (r >> 7) as usize % (digits.len() + 1);
        let (int, frac) = digits.split_at(cut);
        let sign = if r & 1 == 1 { "-" } else { "" };
        match (r >> 12) % 16 {
            0 if !plain => format!("{sign}{int}e-{}", r % 30),
            1 if !plain => format!(" {sign}{int}.{frac}"),
            2 if !plain => format!("+{int}.{frac}"),
            3 if !plain => "nan".into(),
            4 if !plain => String::new(),
            8 if !plain => format!("{sign}{int}.{frac}.5"),
            5 => format!("{sign}{int}"),
            6 => format!("{sign}.{frac}"),
            7 => format!("{sign}{int}."),
            _ => format!("{sign}{int}.{frac}"),
        }
    }

    /// `n` seeded lines of `lay`'s columns after a 40-byte preamble, then room for the
    /// scanner's reads: every `odd`-th line of any fields (with now and then an extra
    /// column, a fractional time, a quote or a CRLF end), the others of plain fields.
    fn lines_text(lay: &Layout, st: &mut u64, n: usize, odd: usize) -> String {
        let cols = columns(lay);
        let mut text = "h\n".repeat(20);
        let d = match lay.delim {
            Delim::Byte(d) => char::from(d).to_string(),
            Delim::Whitespace(_) => unreachable!(),
        };
        for i in 0..n {
            let plain = i % odd != 0;
            let extra = !plain && i % 17 == 0;
            let mut line: Vec<String> = (0..cols.len() + usize::from(extra))
                .map(|_| field(st, plain))
                .collect();
            if let Some(t) = lay.time {
                line[t] = if !plain && i % 13 == 0 {
                    format!("{i}.5")
                } else {
                    format!("{}", 1_403_636_579_758_555_392 + i as u64 * 5_000_000)
                };
            }
            if !plain && i % 19 == 0 {
                line[0] = "\"q\"".into();
            }
            text += &line.join(&d);
            text += if i % 7 == 0 { "\r\n" } else { "\n" };
        }
        text + &"\n".repeat(PAD)
    }

    /// The layouts the tests read: time first, columns shuffled with one skipped, no time.
    fn layouts() -> [Layout; 3] {
        [
            layout(b',', Some(0), [1, 2, 3], [4, 5, 6]),
            layout(b';', Some(1), [4, 5, 6], [2, 7, 3]),
            layout(b'\t', None, [0, 1, 2], [3, 4, 5]),
        ]
    }

    /// The scanner gives what fast_row gives on every line it takes, bit for bit, and takes
    /// the plain ones (checked only where the instructions are found: elsewhere it is never
    /// used).
    #[test]
    fn the_wide_scanner_reads_what_fast_row_reads() {
        const LINES: usize = 60_000;
        if !simd() {
            eprintln!("no AVX2 here: the scanner is off and fast_row reads every line");
            return;
        }
        let mut st = 0x5EED_2026_u64;
        for lay in &layouts() {
            let cols = columns(lay);
            let text = lines_text(lay, &mut st, LINES, 1);
            let b = text.as_bytes();
            let (mut pos, mut took_wide, mut lines) = (40, 0, 0);
            while pos + PAD < b.len() {
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

    /// Runs of plain lines read straight into the slot ([`rows`]) between odd lines left to
    /// fast_row and the csv crate fill the range as reading line by line without the
    /// scanner does: the same rows bit for bit, line count, malformed lines and stamp order.
    #[test]
    fn runs_of_lines_fill_the_slot_as_reading_line_by_line_does() {
        const LINES: usize = 40_000;
        if !simd() {
            return;
        }
        let mut st = 0x2026_1207_u64;
        for lay in &layouts() {
            for odd in [2, 9, 500] {
                let text = lines_text(lay, &mut st, LINES, odd);
                let n = room(text.as_bytes());
                let (mut wide_rows, mut line_rows) = (Rows::zeroed(n), Rows::zeroed(n));
                let read = |rows: &mut Rows, wide: bool| {
                    let out = Chunk {
                        slot: rows.split(&[n]).remove(0),
                        ..Chunk::default()
                    };
                    parse_lines(text.as_bytes(), lay, wide, out).got
                };
                let (w, l) = (read(&mut wide_rows, true), read(&mut line_rows, false));
                assert!(w.filled > LINES / 2, "{} rows", w.filled);
                let what = format!("odd lines every {odd}");
                same_reading((&w, &wide_rows), (&l, &line_rows), &what);
            }
        }
    }

    /// Everything a range gave, rows included, to compare two ways of reading it.
    fn same_reading(a: (&Summary, &Rows), b: (&Summary, &Rows), what: &str) {
        let ((ga, ra), (gb, rb)) = (a, b);
        assert_eq!(
            (ga.filled, ga.lines, ga.bad, &ga.first_bad, ga.lost),
            (gb.filled, gb.lines, gb.bad, &gb.first_bad, gb.lost),
            "{what}"
        );
        let (oa, ob) = (ga.order, gb.order);
        let key = |o: super::super::body::Order| {
            (o.first, o.last, o.back, o.first_back, o.dup, o.first_dup)
        };
        assert_eq!(key(oa), key(ob), "{what}");
        for i in 0..ga.filled {
            let (x, y) = (ra.row(i), rb.row(i));
            assert_eq!(x.stamp, y.stamp, "{what}: row {i}");
            for c in 0..3 {
                assert_eq!(x.acc[c].to_bits(), y.acc[c].to_bits(), "{what}: row {i}");
                assert_eq!(x.gyro[c].to_bits(), y.gyro[c].to_bits(), "{what}: row {i}");
            }
            assert_eq!(ra.record_time[i], rb.record_time[i], "{what}: row {i}");
        }
    }

    /// Two ranges read side by side ([`parse_pair`]) give what each gives read alone with
    /// the scanner off: with odd lines at different places in each, one range much shorter
    /// than the other, and one empty.
    #[test]
    fn two_ranges_read_side_by_side_give_what_each_gives_alone() {
        const LINES: usize = 20_000;
        if !simd() {
            return;
        }
        let mut st = 0x2026_1208_u64;
        for lay in &layouts() {
            for (odd_a, odd_b, n_b) in [(2, 9, LINES), (500, 3, LINES), (7, 11, 40), (9, 5, 0)] {
                let a = lines_text(lay, &mut st, LINES, odd_a);
                let b = if n_b == 0 {
                    String::new()
                } else {
                    lines_text(lay, &mut st, n_b, odd_b)
                };
                let texts = [a.as_bytes(), b.as_bytes()];
                let mut pair_rows = texts.map(|t| Rows::zeroed(room(t)));
                let mut alone_rows = texts.map(|t| Rows::zeroed(room(t)));
                fn chunk<'r>(rows: &'r mut Rows, t: &[u8]) -> Chunk<'r> {
                    Chunk {
                        slot: rows.split(&[room(t)]).remove(0),
                        ..Chunk::default()
                    }
                }
                let [pa, pb] = &mut pair_rows;
                let (ga, gb) = parse_pair(
                    (texts[0], texts[1]),
                    lay,
                    (chunk(pa, texts[0]), chunk(pb, texts[1])),
                );
                let (ga, gb) = (ga.got, gb.got);
                let alone: Vec<Summary> = alone_rows
                    .iter_mut()
                    .zip(texts)
                    .map(|(r, t)| parse_lines(t, lay, false, chunk(r, t)).got)
                    .collect();
                assert!(ga.filled > LINES / 2, "{} rows", ga.filled);
                let what = format!("odd lines every {odd_a} and {odd_b}, {n_b} lines in b");
                same_reading((&ga, &pair_rows[0]), (&alone[0], &alone_rows[0]), &what);
                same_reading((&gb, &pair_rows[1]), (&alone[1], &alone_rows[1]), &what);
            }
        }
    }

    /// A EuRoC line, the benchmark's: taken by the scanner (not left to fast_row).
    #[test]
    fn the_wide_scanner_takes_euroc_lines() {
        if !simd() {
            return;
        }
        let lay = layout(b',', Some(0), [1, 2, 3], [4, 5, 6]);
        let line = concat!(
            "1403636579758555392,-0.00123456789012345,0.09913470151327790,",
            "-0.00032156565656565,0.01234567890123456,-0.01999999999999999,",
            "9.81234567890123457\n"
        );
        let text = format!("{}{line}{}", "#".repeat(READ_BEHIND), "\n".repeat(PAD));
        let (r, n) = row(text.as_bytes(), READ_BEHIND, &lay, &columns(&lay)).expect("taken");
        assert_eq!(n, line.len());
        assert_eq!(r.stamp, 1_403_636_579_758_555_392);
        assert_eq!(r.acc[2], "9.81234567890123457".parse::<f64>().unwrap());
        assert_eq!(r.gyro[0], -0.00123456789012345 * 0.5);
    }
}
