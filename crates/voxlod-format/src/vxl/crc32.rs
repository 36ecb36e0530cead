//! The container's checksum: CRC-32/ISO-HDLC, the CRC of zlib, gzip and PNG (reflected
//! polynomial `0xEDB88320`, initial value and final XOR `0xFFFFFFFF`, check value
//! `crc32(b"123456789") == 0xCBF43926`), computed by the `crc32fast` crate.

/// The CRC-32 of `bytes`.
pub fn crc32(bytes: &[u8]) -> u32 {
    crc32fast::hash(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Bit at a time, straight from the definition.
    fn crc32_bitwise(bytes: &[u8]) -> u32 {
        let mut crc = !0u32;
        for &b in bytes {
            crc ^= b as u32;
            for _ in 0..8 {
                crc = if crc & 1 != 0 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
            }
        }
        !crc
    }

    #[test]
    fn catalogue_check_values() {
        // The CRC catalogue's check value, the empty input, and zlib's crc32(b"a").
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
        assert_eq!(crc32(b"a"), 0xE8B7_BE43);
    }

    proptest! {
        #[test]
        fn equals_the_bitwise_definition(bytes in proptest::collection::vec(any::<u8>(), 0..200)) {
            prop_assert_eq!(crc32(&bytes), crc32_bitwise(&bytes));
        }
    }
}
