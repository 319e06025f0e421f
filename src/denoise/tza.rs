//! The `.tza` tensor archive of Open Image Denoise's trained weights: a header (magic `0x41D7`,
//! version 2.x, the table's offset), the tensors' data, then a table naming each tensor with its
//! dimensions, layout (`"x"` for a bias, `"oihw"` for a convolution's weights), data type
//! (`f`: f32, `h`: f16) and data offset. Every value is little-endian. Parsing checks every
//! offset and length against the file, so a truncated or corrupt archive is an error, never a
//! panic.

use std::collections::HashMap;

/// The archive's magic number (its first two bytes).
const MAGIC: u16 = 0x41D7;

/// The one major version this parser reads.
const MAJOR_VERSION: u8 = 2;

/// One named tensor, its values widened to f32.
#[derive(Clone, Debug, PartialEq)]
pub struct Tensor {
    /// The dimensions, outermost first (`[O, I, H, W]` for `oihw`).
    pub dims: Vec<usize>,
    /// The layout, one letter a dimension (`"x"`, `"oihw"`).
    pub layout: String,
    /// The values in `layout` order.
    pub values: Vec<f32>,
}

/// Why an archive could not be read.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum TzaError {
    /// The first two bytes are not `0x41D7`.
    #[error("not a tensor archive (magic {0:#06x}, expected 0x41d7)")]
    BadMagic(u16),
    /// A major version other than 2.
    #[error("tensor archive version {0}.{1} is not supported (expected 2.x)")]
    Version(u8, u8),
    /// A read past the end of the file.
    #[error("tensor archive truncated: {what} at byte {at} needs {len} bytes of {size}")]
    Truncated {
        /// What was being read.
        what: String,
        /// Where.
        at: usize,
        /// How many bytes it needed.
        len: usize,
        /// The file's size.
        size: usize,
    },
    /// A tensor whose table entry makes no sense.
    #[error("tensor archive: tensor '{name}': {problem}")]
    Tensor {
        /// The tensor's name.
        name: String,
        /// What is wrong.
        problem: String,
    },
}

/// A cursor over the archive's bytes whose every read is bounds-checked.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, len: usize, what: &str) -> Result<&'a [u8], TzaError> {
        let end = self.at.checked_add(len).filter(|&e| e <= self.bytes.len());
        let Some(end) = end else {
            return Err(TzaError::Truncated {
                what: what.to_string(),
                at: self.at,
                len,
                size: self.bytes.len(),
            });
        };
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn u8(&mut self, what: &str) -> Result<u8, TzaError> {
        Ok(self.take(1, what)?[0])
    }

    fn u16(&mut self, what: &str) -> Result<u16, TzaError> {
        let b = self.take(2, what)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }

    fn u32(&mut self, what: &str) -> Result<u32, TzaError> {
        let b = self.take(4, what)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    fn u64(&mut self, what: &str) -> Result<u64, TzaError> {
        let b = self.take(8, what)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(u64::from_le_bytes(a))
    }
}

/// Every tensor of the archive `bytes`, by name.
pub fn parse(bytes: &[u8]) -> Result<HashMap<String, Tensor>, TzaError> {
    let mut r = Reader { bytes, at: 0 };
    let magic = r.u16("the magic number")?;
    if magic != MAGIC {
        return Err(TzaError::BadMagic(magic));
    }
    let (major, minor) = (r.u8("the version")?, r.u8("the version")?);
    if major != MAJOR_VERSION {
        return Err(TzaError::Version(major, minor));
    }
    let table = r.u64("the table offset")?;
    r.at = usize::try_from(table).unwrap_or(usize::MAX);
    let count = r.u32("the tensor count")?;
    let mut tensors = HashMap::new();
    for _ in 0..count {
        let name_len = r.u16("a tensor name's length")? as usize;
        let name = String::from_utf8_lossy(r.take(name_len, "a tensor name")?).into_owned();
        let bad = |problem: String| TzaError::Tensor {
            name: name.clone(),
            problem,
        };
        let ndims = r.u8("a tensor's rank")? as usize;
        let mut dims = Vec::with_capacity(ndims);
        for _ in 0..ndims {
            dims.push(r.u32("a tensor's dimensions")? as usize);
        }
        let layout = String::from_utf8_lossy(r.take(ndims, "a tensor's layout")?).into_owned();
        let kind = r.u8("a tensor's data type")?;
        let offset = r.u64("a tensor's data offset")?;
        let elements = dims
            .iter()
            .try_fold(1usize, |n, &d| n.checked_mul(d))
            .ok_or_else(|| bad(format!("dimensions {dims:?} overflow")))?;
        let width = match kind {
            b'f' => 4,
            b'h' => 2,
            other => {
                return Err(bad(format!(
                    "data type '{}' is not f (f32) or h (f16)",
                    other as char
                )));
            }
        };
        let mut data = Reader {
            bytes,
            at: usize::try_from(offset).unwrap_or(usize::MAX),
        };
        let raw = data.take(
            elements
                .checked_mul(width)
                .ok_or_else(|| bad("size overflows".into()))?,
            &format!("tensor '{name}'"),
        )?;
        let values = match kind {
            b'f' => raw
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect(),
            _ => raw
                .chunks_exact(2)
                .map(|b| f16_to_f32(u16::from_le_bytes([b[0], b[1]])))
                .collect(),
        };
        tensors.insert(
            name.clone(),
            Tensor {
                dims,
                layout,
                values,
            },
        );
    }
    Ok(tensors)
}

/// An IEEE 754 half-precision value widened to f32 exactly (subnormals, infinities and NaN
/// included).
pub fn f16_to_f32(h: u16) -> f32 {
    let sign = ((h >> 15) as u32) << 31;
    let exp = ((h >> 10) & 0x1f) as u32;
    let mant = (h & 0x3ff) as u32;
    let bits = match (exp, mant) {
        (0, 0) => sign,
        (0, m) => {
            // A subnormal half is m * 2^-24, a normal f32.
            let magnitude = m as f32 * 2f32.powi(-24);
            return if sign == 0 { magnitude } else { -magnitude };
        }
        (0x1f, m) => sign | 0x7f80_0000 | (m << 13),
        (e, m) => sign | ((e + 127 - 15) << 23) | (m << 13),
    };
    f32::from_bits(bits)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tensor's table entry and data: name, dims, layout, type, raw data.
    type Entry<'a> = (&'a str, &'a [u32], &'a str, u8, Vec<u8>);

    /// An archive of `tensors` as the format lays it out: header, data, table.
    fn build(tensors: &[Entry]) -> Vec<u8> {
        let mut out = vec![0u8; 12];
        out[0..2].copy_from_slice(&MAGIC.to_le_bytes());
        out[2] = 2;
        let mut offsets = Vec::new();
        for (_, _, _, _, data) in tensors {
            offsets.push(out.len() as u64);
            out.extend_from_slice(data);
        }
        let table = out.len() as u64;
        out[4..12].copy_from_slice(&table.to_le_bytes());
        out.extend_from_slice(&(tensors.len() as u32).to_le_bytes());
        for ((name, dims, layout, kind, _), offset) in tensors.iter().zip(offsets) {
            out.extend_from_slice(&(name.len() as u16).to_le_bytes());
            out.extend_from_slice(name.as_bytes());
            out.push(dims.len() as u8);
            for d in *dims {
                out.extend_from_slice(&d.to_le_bytes());
            }
            out.extend_from_slice(layout.as_bytes());
            out.push(*kind);
            out.extend_from_slice(&offset.to_le_bytes());
        }
        out
    }

    fn f32_bytes(v: &[f32]) -> Vec<u8> {
        v.iter().flat_map(|x| x.to_le_bytes()).collect()
    }

    #[test]
    fn reads_f32_and_f16_tensors_by_name() {
        // 1.0, -2.0, 0.5 and 65504 (the largest half) in f16.
        let half: Vec<u8> = [0x3c00u16, 0xc000, 0x3800, 0x7bff]
            .iter()
            .flat_map(|h| h.to_le_bytes())
            .collect();
        let bytes = build(&[
            ("conv.weight", &[1, 1, 2, 2], "oihw", b'h', half),
            ("conv.bias", &[1], "x", b'f', f32_bytes(&[0.25])),
        ]);
        let t = parse(&bytes).expect("a valid archive");
        let w = &t["conv.weight"];
        assert_eq!(w.dims, vec![1, 1, 2, 2]);
        assert_eq!(w.layout, "oihw");
        assert_eq!(w.values, vec![1.0, -2.0, 0.5, 65504.0]);
        assert_eq!(t["conv.bias"].values, vec![0.25]);
    }

    #[test]
    fn halves_widen_exactly() {
        assert_eq!(f16_to_f32(0x0001), 2f32.powi(-24));
        assert_eq!(f16_to_f32(0x8001), -(2f32.powi(-24)));
        assert_eq!(f16_to_f32(0x7c00), f32::INFINITY);
        assert!(f16_to_f32(0x7e00).is_nan());
        assert_eq!(f16_to_f32(0x3555), 0.333_251_95);
    }

    #[test]
    fn a_bad_magic_or_version_is_an_error() {
        let mut bytes = build(&[("b", &[1], "x", b'f', f32_bytes(&[1.0]))]);
        bytes[0] = 0;
        assert!(matches!(parse(&bytes), Err(TzaError::BadMagic(_))));
        let mut bytes = build(&[("b", &[1], "x", b'f', f32_bytes(&[1.0]))]);
        bytes[2] = 1;
        assert_eq!(parse(&bytes), Err(TzaError::Version(1, 0)));
    }

    #[test]
    fn every_truncation_is_an_error_not_a_panic() {
        let bytes = build(&[
            ("w", &[2, 1, 1, 1], "oihw", b'f', f32_bytes(&[1.0, 2.0])),
            ("b", &[2], "x", b'f', f32_bytes(&[3.0, 4.0])),
        ]);
        assert!(parse(&bytes).is_ok());
        for len in 0..bytes.len() {
            assert!(parse(&bytes[..len]).is_err(), "{len} bytes parsed");
        }
    }

    #[test]
    fn data_past_the_end_or_an_unknown_type_is_an_error() {
        let mut bytes = build(&[("b", &[1_000_000], "x", b'f', f32_bytes(&[1.0]))]);
        assert!(matches!(parse(&bytes), Err(TzaError::Truncated { .. })));
        bytes = build(&[("b", &[1], "x", b'd', f32_bytes(&[1.0]))]);
        assert!(matches!(parse(&bytes), Err(TzaError::Tensor { .. })));
    }

    #[test]
    fn the_bundled_weights_parse() {
        for (bytes, first) in [
            (super::super::weights::FULL, 32),
            (super::super::weights::SMALL, 32),
        ] {
            let t = parse(bytes).expect("the bundled archive");
            assert_eq!(t["enc_conv0.weight"].dims, vec![first, 9, 3, 3]);
            assert_eq!(t["dec_conv0.weight"].dims[0], 3);
        }
    }
}
