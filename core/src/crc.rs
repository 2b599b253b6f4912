//! The CRC-32 that checks every image in the settings store (settings, coordinate data,
//! records and page headers).

/// CRC-32 (IEEE, reflected, polynomial 0xEDB88320), bitwise: the store checks a few
/// hundred bytes at boot and at each save, where a table's speed would not show.
pub fn crc32(data: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in data {
        crc ^= u32::from(b);
        for _ in 0..8 {
            let lsb = crc & 1;
            crc >>= 1;
            if lsb != 0 {
                crc ^= 0xEDB8_8320;
            }
        }
    }
    !crc
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc_matches_the_standard_check_value() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
    }
}
