//! Linear float data for others to check: arrays written in NumPy's `.npy` format (version
//! 1.0, little-endian `f32`, C order), which `numpy.load` reads directly. Reports write images'
//! linear values beside their 8-bit PNGs this way.
//!
//! ```
//! let bytes = voxlod_eval::npy::encode_f32(&[2, 3], &[0.0, 1.0, 2.0, 3.0, 4.0, 5.0])?;
//! assert!(bytes.starts_with(b"\x93NUMPY\x01\x00"));
//! assert_eq!(bytes.len() % 64, (6 * 4) % 64); // header padded to 64 bytes, then the data
//! let (shape, data) = voxlod_eval::npy::decode_f32(&bytes)?;
//! assert_eq!((shape, data[5]), (vec![2, 3], 5.0));
//! # Ok::<(), voxlod_eval::Error>(())
//! ```

use crate::{Error, Result};

const MAGIC: &[u8] = b"\x93NUMPY\x01\x00";

/// A named array of linear `f32` values with its shape (C order: the last index fastest).
#[derive(Clone, Debug, PartialEq)]
pub struct FloatArray {
    /// File stem: letters, digits, `-`, `_`.
    pub name: String,
    /// Dimensions, e.g. `[height, width]` or `[height, width, 3]`.
    pub shape: Vec<usize>,
    /// `shape.iter().product()` values.
    pub data: Vec<f32>,
}

/// The `.npy` bytes of `data` with `shape`. Errors when the shape does not hold the data.
pub fn encode_f32(shape: &[usize], data: &[f32]) -> Result<Vec<u8>> {
    if shape.iter().product::<usize>() != data.len() {
        return Err(Error::ArrayShape { shape: shape.to_vec(), values: data.len() });
    }
    let dims: String = match shape {
        [n] => format!("({n},)"),
        _ => format!("({})", shape.iter().map(usize::to_string).collect::<Vec<_>>().join(", ")),
    };
    let dict = format!("{{'descr': '<f4', 'fortran_order': False, 'shape': {dims}, }}");
    // Magic (8) + header length (2) + dict + padding + '\n', a multiple of 64.
    let unpadded = MAGIC.len() + 2 + dict.len() + 1;
    let header_len = dict.len() + 1 + (64 - unpadded % 64) % 64;
    let mut out = Vec::with_capacity(MAGIC.len() + 2 + header_len + 4 * data.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&(header_len as u16).to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out.resize(MAGIC.len() + 2 + header_len - 1, b' ');
    out.push(b'\n');
    for v in data {
        out.extend_from_slice(&v.to_le_bytes());
    }
    Ok(out)
}

/// Reads back what [`encode_f32`] writes (version 1.0, `<f4`, C order): the shape and values.
pub fn decode_f32(bytes: &[u8]) -> Result<(Vec<usize>, Vec<f32>)> {
    let bad = |why: &str| Error::Npy { why: why.into() };
    if !bytes.starts_with(MAGIC) || bytes.len() < MAGIC.len() + 2 {
        return Err(bad("not a version 1.0 .npy file"));
    }
    let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = bytes.get(10..10 + len).ok_or_else(|| bad("truncated header"))?;
    let header = std::str::from_utf8(header).map_err(|_| bad("header is not UTF-8"))?;
    if !header.contains("'descr': '<f4'") || !header.contains("'fortran_order': False") {
        return Err(bad("not little-endian f32 in C order"));
    }
    let dims = header
        .split_once("'shape': (")
        .and_then(|(_, rest)| rest.split_once(')'))
        .ok_or_else(|| bad("no shape"))?
        .0;
    let shape = dims
        .split(',')
        .map(str::trim)
        .filter(|d| !d.is_empty())
        .map(|d| d.parse::<usize>().map_err(|_| bad("bad shape")))
        .collect::<Result<Vec<_>>>()?;
    let body = &bytes[10 + len..];
    let n: usize = shape.iter().product();
    if body.len() != 4 * n {
        return Err(bad("data length does not match the shape"));
    }
    let data = body.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
    Ok((shape, data))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_and_aligns_the_header() {
        for shape in [vec![0], vec![7], vec![3, 5], vec![2, 4, 3]] {
            let n: usize = shape.iter().product();
            let data: Vec<f32> = (0..n).map(|i| i as f32 * 0.5 - 1.0).collect();
            let bytes = encode_f32(&shape, &data).unwrap();
            assert_eq!((bytes.len() - 4 * n) % 64, 0, "{shape:?}");
            assert_eq!(bytes[bytes.len() - 4 * n - 1], b'\n');
            assert_eq!(decode_f32(&bytes).unwrap(), (shape, data));
        }
        // NumPy's own header for a (2, 3) float32 array, byte for byte.
        let bytes = encode_f32(&[2, 3], &[0.0; 6]).unwrap();
        let header = std::str::from_utf8(&bytes[10..128]).unwrap();
        assert_eq!(
            header.trim_end(),
            "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }"
        );
        assert!(encode_f32(&[2, 3], &[0.0; 5]).is_err());
        assert!(decode_f32(b"PNG").is_err());
    }
}
