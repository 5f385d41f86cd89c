//! What a whole ULog message is, type by type, and how a walk past damage finds the next
//! one: a ULog has no checksum and its sync markers are rare (PX4 writes one now and then,
//! some logs none), so every message is checked against what its type holds — a data message
//! against its subscription's format size (the sizes pyulog accepts), a definition against its
//! text, an information message against its declared type — and damage is passed at the
//! first position from which [`CHAIN`] messages in a row are whole.

use super::format::{Formats, parse_format, scalar_size};
use super::{SYNC, Subs};

/// Whole messages in a row that make a position a message boundary after damage.
pub(super) const CHAIN: usize = 3;
/// A message type of the format whose size pyulog skips an unknown type by (larger or zero
/// is damage: it steps a byte instead).
const MAX_UNKNOWN_SIZE: u16 = 10_000;

/// The message at an offset.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Frame {
    /// A whole message: type and size (its body follows the 3 header bytes).
    Whole(u8, u16),
    /// The file ends inside the message (or its header).
    Cut,
    /// Not a message its type allows (damage, or a type the format does not have).
    Bad,
}

/// What checking a message needs: the bytes, the subscriptions and formats so far, each
/// channel's data sizes, and where the flag bits may be.
pub(super) struct Ctx<'a> {
    pub(super) bytes: &'a [u8],
    pub(super) subs: &'a Subs,
    pub(super) formats: &'a Formats,
    /// Each channel's data sizes (without the message id), `None`: no format size known.
    pub(super) sizes: &'a [Option<(usize, usize)>],
    /// Ids a subscription moved from another channel, with that channel: a chain of
    /// messages accepts their data when it fits either (the subscription may be damaged).
    pub(super) rebound: &'a [(u16, u32)],
}

/// The header at `at`: size and type, if the file holds it.
#[inline]
pub(super) fn header(bytes: &[u8], at: u64) -> Option<(u16, u8)> {
    let a = usize::try_from(at).ok()?;
    let h = bytes.get(a..a.checked_add(3)?)?;
    Some((u16::from_le_bytes([h[0], h[1]]), h[2]))
}

/// The body of the message at `at` of `size` bytes, if the file holds it.
#[inline]
pub(super) fn body(bytes: &[u8], at: u64, size: usize) -> Option<&[u8]> {
    let a = usize::try_from(at).ok()?.checked_add(3)?;
    bytes.get(a..a.checked_add(size)?)
}

impl Ctx<'_> {
    /// The channel a data message body (`id` then data) belongs to, when its data fits the
    /// channel's format size.
    #[inline]
    pub(super) fn data_channel(&self, body: &[u8]) -> Option<u32> {
        let id = u16::from_le_bytes([*body.first()?, *body.get(1)?]);
        self.fits(self.subs.get(id), body.len() - 2)
    }

    /// `ch`, when `data_len` bytes of data fit its format.
    #[inline]
    fn fits(&self, ch: u32, data_len: usize) -> Option<u32> {
        match self.sizes.get(ch as usize)? {
            Some((lo, hi)) => (*lo..=*hi).contains(&data_len).then_some(ch),
            None => Some(ch),
        }
    }

    /// The message at `at`, checked against its type.
    pub(super) fn frame(&self, at: u64) -> Frame {
        let Some((size, ty)) = header(self.bytes, at) else {
            return Frame::Cut;
        };
        let Some(b) = body(self.bytes, at, size as usize) else {
            return Frame::Cut;
        };
        if self.whole(at, ty, b) {
            Frame::Whole(ty, size)
        } else {
            Frame::Bad
        }
    }

    /// True when `b` is a body a message of type `ty` at `at` may have.
    fn whole(&self, at: u64, ty: u8, b: &[u8]) -> bool {
        match ty {
            b'D' => self.data_channel(b).is_some(),
            b'F' => std::str::from_utf8(b).ok().and_then(parse_format).is_some(),
            b'A' => {
                b.len() > 3
                    && std::str::from_utf8(&b[3..]).is_ok_and(|n| self.formats.defs.contains_key(n))
            }
            b'R' | b'O' => b.len() == 2,
            b'S' => b == SYNC,
            b'B' => at == super::HEADER_LEN as u64 && b.len() >= 40,
            b'I' | b'P' => key_value(b),
            b'M' | b'Q' => b.len() > 1 && key_value(&b[1..]),
            b'L' => b.len() >= 9 && level(b[0]) && text(&b[9..]),
            b'C' => b.len() >= 11 && level(b[0]) && text(&b[11..]),
            _ => false,
        }
    }

    /// True when `at` is a message boundary: the end of the file, or `CHAIN` messages follow
    /// (fewer when the file ends after them, or inside the next one) that are whole or may
    /// be: a data message of an id no subscription names or of a channel whose format it
    /// does not fit (a log whose subscription or format was lost has many), a subscription to
    /// a format not defined (its definition damaged), one of a re-bound id that fits either
    /// channel.
    pub(super) fn chain(&self, at: u64) -> bool {
        self.chain_from(at, false)
    }

    /// [`Ctx::chain`]; `strict`: the first message must be whole, as where a walk past damage
    /// lands.
    fn chain_from(&self, at: u64, strict: bool) -> bool {
        let len = self.bytes.len() as u64;
        let (mut p, mut seen, mut wholes) = (at, 0, 0);
        // the ids of the data messages that may be whole: a run of them alone must be one
        // topic's (whose format or subscription was lost), not bytes that happen to look so
        let mut ids: Option<Option<u16>> = None;
        for _ in 0..CHAIN {
            if p == len {
                return true;
            }
            let Some((size, ty)) = header(self.bytes, p) else {
                return seen > 0;
            };
            let Some(b) = body(self.bytes, p, size as usize) else {
                return seen > 0;
            };
            if self.whole(p, ty, b) || self.rebound_fits(b) {
                wholes += 1;
            } else {
                let maybe = match ty {
                    b'D' => b.len() >= 2,
                    b'A' => b.len() > 3 && b[3..].iter().all(|c| c.is_ascii_graphic()),
                    _ => false,
                };
                if !maybe || (strict && p == at) {
                    return false;
                }
                let id = (ty == b'D').then(|| u16::from_le_bytes([b[0], b[1]]));
                ids = match ids {
                    None => Some(id),
                    Some(x) if x == id && id.is_some() => Some(x),
                    Some(_) => Some(None),
                };
            }
            seen += 1;
            p += 3 + size as u64;
        }
        wholes > 0 || ids.is_some_and(|x| x.is_some())
    }

    /// A data body whose id a subscription moved, fitting the channel it was moved from.
    fn rebound_fits(&self, b: &[u8]) -> bool {
        b.len() >= 2 && {
            let id = u16::from_le_bytes([b[0], b[1]]);
            self.rebound
                .iter()
                .any(|&(i, old)| i == id && self.fits(old, b.len() - 2).is_some())
        }
    }

    /// The next position after `at` from which messages are whole again ([`Ctx::chain`]),
    /// or the end of the file.
    pub(super) fn resync(&self, at: u64) -> u64 {
        let len = self.bytes.len() as u64;
        let mut p = at + 1;
        while p < len {
            // cheap first: a type byte of the format, then the chain
            if let Some((_, ty)) = header(self.bytes, p)
                && super::IS_TYPE[ty as usize]
                && self.chain_from(p, true)
            {
                return p;
            }
            p += 1;
        }
        len
    }

    /// True when the unknown or damaged message at `at` (type `ty`, `size`) may be skipped
    /// by its size, as pyulog skips a type it does not know: a plausible size, and whole
    /// messages after it.
    pub(super) fn skippable(&self, at: u64, ty: u8, size: u16) -> bool {
        ty != 0 && size != 0 && size <= MAX_UNKNOWN_SIZE && self.chain(at + 3 + size as u64)
    }
}

fn level(b: u8) -> bool {
    (b'0'..=b'7').contains(&b)
}

/// Text of a log message: UTF-8 without control characters but tab and line ends.
fn text(b: &[u8]) -> bool {
    std::str::from_utf8(b).is_ok_and(|s| {
        !s.chars()
            .any(|c| c.is_control() && !matches!(c, '\t' | '\n' | '\r'))
    })
}

/// An information or parameter body: `key_len`, a key `type name`, and a value of the key's
/// type's size.
fn key_value(b: &[u8]) -> bool {
    let Some((&n, rest)) = b.split_first() else {
        return false;
    };
    let n = n as usize;
    let Some(key) = rest.get(..n).and_then(|k| std::str::from_utf8(k).ok()) else {
        return false;
    };
    let value = rest.len() - n;
    let Some((ty, name)) = key.split_once(' ') else {
        return false;
    };
    if name.is_empty() || !key.bytes().all(|c| c.is_ascii_graphic() || c == b' ') {
        return false;
    }
    let (base, count) = match ty.split_once('[') {
        Some((t, k)) => match k.strip_suffix(']').and_then(|k| k.parse::<usize>().ok()) {
            Some(k) => (t, k),
            None => return false,
        },
        None => (ty, 1),
    };
    scalar_size(base).is_some_and(|s| s.checked_mul(count) == Some(value))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn information_values_have_their_types_size() {
        let kv = |key: &str, value: &[u8]| {
            let mut b = vec![key.len() as u8];
            b.extend_from_slice(key.as_bytes());
            b.extend_from_slice(value);
            key_value(&b)
        };
        assert!(kv("char[5] sys_name", b"PX4_t"));
        assert!(kv("float IMU_GYRO_CUTOFF", &30f32.to_le_bytes()));
        assert!(!kv("char[5] sys_name", b"PX4_t\x00\x00"));
        assert!(!kv("float X", &[0u8; 3]));
        assert!(!kv("charx[5] sys_name", b"PX4_t"));
        assert!(!kv("float", &[0u8; 4]));
    }
}
