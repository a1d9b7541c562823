//! The checksum of FT1.2 and of devices framed like it.

/// The arithmetic sum modulo 256 of `octets`: the check octet of FT1.2 frames (IEC
/// 60870-5-1, over control field, address and user data) and of devices that frame their
/// messages the FT1.2 way (the EKM66 lift board, over its user octets). Which octets a
/// protocol sums is the protocol's business.
pub fn octet_sum(octets: &[u8]) -> u8 {
    octets
        .iter()
        .fold(0u8, |sum, octet| sum.wrapping_add(*octet))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sum_modulo_256() {
        assert_eq!(octet_sum(&[]), 0);
        assert_eq!(octet_sum(&[0x53, 0x01]), 0x54);
        assert_eq!(octet_sum(&[0xFF, 0x02]), 0x01);
    }
}
