//! One bounds-checked reader over a byte slice: every fixed-width little-endian field a
//! binary format holds, read with the file offset it came from and a typed error when the
//! bytes run out or do not mean what the format says. The ULog and DataFlash readers parse
//! with it; a damaged length can never index past the data or size an allocation.

/// What went wrong reading bytes.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CursorError {
    /// Fewer bytes left than the field needs.
    #[error("at byte {offset}: {what} needs {need} bytes, {have} left")]
    Short {
        /// File offset of the field.
        offset: u64,
        /// Bytes the field needs.
        need: usize,
        /// Bytes left.
        have: usize,
        /// What was being read.
        what: &'static str,
    },
    /// The bytes are there but do not mean what the format says.
    #[error("at byte {offset}: {what}")]
    Invalid {
        /// File offset of the field.
        offset: u64,
        /// What is wrong.
        what: String,
    },
}

/// A fixed-width little-endian number.
pub trait Le: Sized + Copy {
    /// Its width in bytes.
    const SIZE: usize;
    /// From exactly `SIZE` bytes.
    fn from_le(b: &[u8]) -> Self;
}

macro_rules! le {
    ($($t:ty),*) => {$(
        impl Le for $t {
            const SIZE: usize = std::mem::size_of::<$t>();
            fn from_le(b: &[u8]) -> Self {
                let mut a = [0u8; std::mem::size_of::<$t>()];
                a.copy_from_slice(b);
                <$t>::from_le_bytes(a)
            }
        }
    )*};
}
le!(u8, i8, u16, i16, u32, i32, u64, i64, f32, f64);

/// A position in a byte slice that lies at file offset `base`.
#[derive(Debug, Clone)]
pub struct Cursor<'a> {
    data: &'a [u8],
    pos: usize,
    base: u64,
}

impl<'a> Cursor<'a> {
    /// At the start of `data`, which starts the file.
    pub fn new(data: &'a [u8]) -> Cursor<'a> {
        Cursor::at(data, 0)
    }

    /// At the start of `data`, which lies at file offset `base`.
    pub(crate) fn at(data: &'a [u8], base: u64) -> Cursor<'a> {
        Cursor { data, pos: 0, base }
    }

    /// File offset of the next byte.
    pub(crate) fn offset(&self) -> u64 {
        self.base + self.pos as u64
    }

    /// Index of the next byte in the slice.
    pub fn pos(&self) -> usize {
        self.pos
    }

    /// Bytes left.
    pub(crate) fn remaining(&self) -> usize {
        self.data.len() - self.pos
    }

    /// True when every byte was read.
    pub fn is_empty(&self) -> bool {
        self.remaining() == 0
    }

    /// The bytes not read yet.
    pub(crate) fn rest(&self) -> &'a [u8] {
        &self.data[self.pos..]
    }

    /// The error for a field whose bytes are there but wrong, at the current offset.
    pub(crate) fn invalid(&self, what: impl Into<String>) -> CursorError {
        CursorError::Invalid {
            offset: self.offset(),
            what: what.into(),
        }
    }

    /// The next `n` bytes.
    pub(crate) fn take(&mut self, n: usize, what: &'static str) -> Result<&'a [u8], CursorError> {
        if n > self.remaining() {
            return Err(CursorError::Short {
                offset: self.offset(),
                need: n,
                have: self.remaining(),
                what,
            });
        }
        let s = &self.data[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    /// Skips `n` bytes.
    pub(crate) fn skip(&mut self, n: usize, what: &'static str) -> Result<(), CursorError> {
        self.take(n, what).map(|_| ())
    }

    /// The next number.
    pub(crate) fn le<T: Le>(&mut self, what: &'static str) -> Result<T, CursorError> {
        self.take(T::SIZE, what).map(T::from_le)
    }

    /// The next `n` bytes as UTF-8 text.
    pub(crate) fn str(&mut self, n: usize, what: &'static str) -> Result<&'a str, CursorError> {
        let at = self.offset();
        let b = self.take(n, what)?;
        std::str::from_utf8(b).map_err(|e| CursorError::Invalid {
            offset: at,
            what: format!("{what} is not UTF-8 ({e})"),
        })
    }

    /// A sub-cursor over the next `n` bytes (which this one skips).
    pub fn sub(&mut self, n: usize, what: &'static str) -> Result<Cursor<'a>, CursorError> {
        let base = self.offset();
        self.take(n, what).map(|d| Cursor::at(d, base))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_numbers_and_refuses_past_the_end() {
        let b = [1u8, 0, 2, 0, 0, 0, 0, 0, 0, 0, 0xf0, 0x3f, b'h', b'i', 0xff];
        let mut c = Cursor::at(&b, 100);
        assert_eq!(c.le::<u16>("a").unwrap(), 1);
        assert_eq!(c.le::<u16>("b").unwrap(), 2);
        assert_eq!(c.offset(), 104);
        assert_eq!(c.le::<f64>("c").unwrap(), 1.0);
        assert_eq!(c.str(2, "d").unwrap(), "hi");
        assert_eq!(
            c.le::<u32>("e"),
            Err(CursorError::Short {
                offset: 114,
                need: 4,
                have: 1,
                what: "e"
            })
        );
        assert!(matches!(
            c.str(1, "f"),
            Err(CursorError::Invalid { offset: 114, .. })
        ));
        assert_eq!(c.remaining(), 0);
        let mut c = Cursor::new(&b);
        let mut s = c.sub(4, "s").unwrap();
        assert_eq!(s.le::<u32>("x").unwrap(), 0x0002_0001);
        assert!(s.is_empty() && c.offset() == 4);
        assert!(c.take(usize::MAX, "huge").is_err());
    }
}
