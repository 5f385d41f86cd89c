//! ULog's format definitions (`F` messages): the fields of each format, and where each
//! scalar of a (nested) format lies in a data message, read without copying.

use std::collections::HashMap;

/// One field of a format: its type, array length (1 for a scalar) and name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Field {
    /// `float`, `uint64_t`, or another format's name.
    pub ty: String,
    /// Array length, 1 for a scalar.
    pub len: usize,
    /// Name.
    pub name: String,
}

/// The bytes of a scalar type, or `None` for a nested format.
pub(super) fn scalar_size(ty: &str) -> Option<usize> {
    Some(match ty {
        "int8_t" | "uint8_t" | "bool" | "char" => 1,
        "int16_t" | "uint16_t" => 2,
        "int32_t" | "uint32_t" | "float" => 4,
        "int64_t" | "uint64_t" | "double" => 8,
        _ => return None,
    })
}

/// The largest array length a format may declare (pyulog refuses larger ones; a message
/// holds at most 65,535 bytes anyway).
pub(super) const MAX_ARRAY: usize = 0xFFFF;

/// A name as the format writes them: printable, without spaces or separators.
fn name_like(s: &str) -> bool {
    !s.is_empty()
        && s.bytes()
            .all(|b| b.is_ascii_graphic() && !matches!(b, b':' | b';' | b'[' | b']'))
}

/// Parses a format message's text `name:type field;…` (`None`: not a definition — a damaged
/// text, an array longer than [`MAX_ARRAY`]).
pub(super) fn parse_format(text: &str) -> Option<(String, Vec<Field>)> {
    let (name, rest) = text.split_once(':')?;
    if !name_like(name) {
        return None;
    }
    let mut fields = Vec::new();
    for f in rest.split(';').filter(|f| !f.trim().is_empty()) {
        let (ty, fname) = f.trim().rsplit_once(' ')?;
        let (ty, len) = match ty.split_once('[') {
            Some((t, n)) => (t, n.strip_suffix(']')?.parse().ok()?),
            None => (ty, 1),
        };
        if !(name_like(ty) && name_like(fname)) || len == 0 || len > MAX_ARRAY {
            return None;
        }
        fields.push(Field {
            ty: ty.to_string(),
            len,
            name: fname.to_string(),
        });
    }
    Some((name.to_string(), fields))
}

/// A scalar's place in a message: byte offset and type.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Slot {
    offset: usize,
    ty: Scalar,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

impl Scalar {
    fn of(ty: &str) -> Option<Scalar> {
        Some(match ty {
            "int8_t" => Scalar::I8,
            "uint8_t" | "bool" | "char" => Scalar::U8,
            "int16_t" => Scalar::I16,
            "uint16_t" => Scalar::U16,
            "int32_t" => Scalar::I32,
            "uint32_t" => Scalar::U32,
            "int64_t" => Scalar::I64,
            "uint64_t" => Scalar::U64,
            "float" => Scalar::F32,
            "double" => Scalar::F64,
            _ => return None,
        })
    }
}

impl Slot {
    /// The `N` bytes of the value, or `None` past the end of `data`.
    fn bytes<const N: usize>(&self, data: &[u8]) -> Option<[u8; N]> {
        data.get(self.offset..)?.first_chunk::<N>().copied()
    }

    /// The value as f64, or `None` past the end of `data`. (Read for every field of every
    /// sample: plain little-endian loads, no cursor.)
    pub(super) fn get(&self, data: &[u8]) -> Option<f64> {
        Some(match self.ty {
            Scalar::I8 => i8::from_le_bytes(self.bytes(data)?).into(),
            Scalar::U8 => u8::from_le_bytes(self.bytes(data)?).into(),
            Scalar::I16 => i16::from_le_bytes(self.bytes(data)?).into(),
            Scalar::U16 => u16::from_le_bytes(self.bytes(data)?).into(),
            Scalar::I32 => i32::from_le_bytes(self.bytes(data)?).into(),
            Scalar::U32 => u32::from_le_bytes(self.bytes(data)?).into(),
            Scalar::I64 => i64::from_le_bytes(self.bytes(data)?) as f64,
            Scalar::U64 => u64::from_le_bytes(self.bytes(data)?) as f64,
            Scalar::F32 => f32::from_le_bytes(self.bytes(data)?).into(),
            Scalar::F64 => f64::from_le_bytes(self.bytes(data)?),
        })
    }

    pub(super) fn get_u64(&self, data: &[u8]) -> Option<u64> {
        match self.ty {
            Scalar::U64 => Some(u64::from_le_bytes(self.bytes(data)?)),
            Scalar::I64 => u64::try_from(i64::from_le_bytes(self.bytes(data)?)).ok(),
            Scalar::U32 => Some(u32::from_le_bytes(self.bytes(data)?).into()),
            _ => None,
        }
    }
}

/// Formats by name, and the flattened scalar slots of each (`gyro_rad[1]`, `a.b`).
pub(super) struct Formats {
    pub(super) defs: HashMap<String, Vec<Field>>,
}

/// The most bytes a message's data can hold (its size is a u16, the message id takes 2).
const MAX_DATA: usize = u16::MAX as usize - 2;

impl Formats {
    /// Every scalar of a format with its flattened name; `None` when a nested format is
    /// missing or the format is larger than a message can be (a damaged array length never
    /// sizes memory: the size is checked before any slot is made).
    pub(super) fn slots(&self, name: &str) -> Option<HashMap<String, Slot>> {
        if self.size(name, 0)? > MAX_DATA {
            return None;
        }
        let mut out = HashMap::new();
        self.flatten(name, "", 0, &mut out, 0)?;
        Some(out)
    }

    /// The bytes a format takes (saturating: an absurd size is absurd, not a wrap).
    fn size(&self, name: &str, depth: usize) -> Option<usize> {
        if depth > 16 {
            return None;
        }
        let mut n = 0usize;
        for f in self.defs.get(name)? {
            let one = match scalar_size(&f.ty) {
                Some(s) => s,
                None => self.size(&f.ty, depth + 1)?,
            };
            n = n.saturating_add(one.saturating_mul(f.len));
        }
        Some(n)
    }

    /// The sizes a data message of format `name` may have (without its message id), as
    /// pyulog takes them: the whole format, or without its trailing `_padding` fields (PX4's
    /// logger leaves them out). `None`: not a format a message can hold.
    pub(super) fn data_sizes(&self, name: &str) -> Option<(usize, usize)> {
        let max = self.size(name, 0)?;
        if max > MAX_DATA {
            return None;
        }
        let mut min = max;
        for f in self.defs.get(name)?.iter().rev() {
            match scalar_size(&f.ty) {
                Some(s) if f.name.starts_with("_padding") => min -= s * f.len,
                _ => break,
            }
        }
        Some((min, max))
    }

    fn flatten(
        &self,
        name: &str,
        prefix: &str,
        base: usize,
        out: &mut HashMap<String, Slot>,
        depth: usize,
    ) -> Option<usize> {
        if depth > 16 {
            return None;
        }
        let mut off = base;
        for fld in self.defs.get(name)? {
            for k in 0..fld.len {
                let n = if fld.len > 1 {
                    format!("{prefix}{}[{k}]", fld.name)
                } else {
                    format!("{prefix}{}", fld.name)
                };
                match Scalar::of(&fld.ty) {
                    Some(ty) => {
                        out.insert(n, Slot { offset: off, ty });
                        off += scalar_size(&fld.ty)?;
                    }
                    None => {
                        off = self.flatten(&fld.ty, &format!("{n}."), off, out, depth + 1)?;
                    }
                }
            }
        }
        Some(off)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_parse_and_flatten() {
        let (n, f) = parse_format(
            "sensor_combined:uint64_t timestamp;float[3] gyro_rad;uint8_t[2] _padding0;",
        )
        .unwrap();
        assert_eq!(n, "sensor_combined");
        assert_eq!(
            f[1],
            Field {
                ty: "float".into(),
                len: 3,
                name: "gyro_rad".into()
            }
        );
        let mut defs = HashMap::new();
        defs.insert(n.clone(), f);
        defs.insert(
            "outer".into(),
            parse_format("outer:uint64_t timestamp;sensor_combined[2] s;")
                .unwrap()
                .1,
        );
        let fm = Formats { defs };
        let s = fm.slots("outer").unwrap();
        assert_eq!(s["s[1].gyro_rad[2]"].offset, 8 + 22 + 8 + 8);
        assert!(fm.slots("missing").is_none());
    }
}
