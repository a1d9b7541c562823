//! The IEC 103 measurand element: a signed 13-bit fraction of a configured limit, with
//! overflow and error flags.

use std::fmt;

/// One measurand of ASDU 3 or 9 (two octets, little-endian).
///
/// ```text
/// bit 15..3  signed 13-bit value, value/4096 of the limit (-1.0 .. +4095/4096)
/// bit 2      reserved (0)
/// bit 1      ER: error, the value is invalid
/// bit 0      OV: overflow, the value was clamped at the limit
/// ```
///
/// The limit is a setting of the device (1.2 or 2.4 times the rated value by the
/// standard, any value on the REF630: MaxIL1, MaxUL1 ...), so the element only carries
/// the fraction; [`Measurand::to_physical`] and [`Measurand::from_physical`] take it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Measurand(u16);

/// The largest 13-bit value, 4095/4096 of the limit.
const MAX_RAW: i16 = 4095;
/// The smallest, -1.0 of the limit.
const MIN_RAW: i16 = -4096;

impl Measurand {
    /// The element of its two octets' value.
    pub fn from_word(word: u16) -> Measurand {
        Measurand(word & !0x0004)
    }

    /// The two octets' value.
    pub fn word(self) -> u16 {
        self.0
    }

    /// From the 13-bit value and the flags.
    pub fn new(raw13: i16, overflow: bool, error: bool) -> Measurand {
        let raw = raw13.clamp(MIN_RAW, MAX_RAW);
        // The 13-bit two's complement value sits in bits 15..3.
        let bits = u16::from_ne_bytes(raw.to_ne_bytes()) << 3;
        Measurand(bits | u16::from(error) << 1 | u16::from(overflow))
    }

    /// The value as a fraction of the limit, rounded to the nearest 1/4096, clamped to
    /// the range with OV set when it had to be (a value beyond the limit is sent as the
    /// limit with OV, as the REF630 does). Not-a-number gives ER.
    pub fn from_fraction(fraction: f64) -> Measurand {
        if fraction.is_nan() {
            return Measurand::new(0, false, true);
        }
        let scaled = (fraction * 4096.0).round();
        let overflow = scaled > f64::from(MAX_RAW) || scaled < f64::from(MIN_RAW);
        let raw = scaled.clamp(f64::from(MIN_RAW), f64::from(MAX_RAW));
        // In range after the clamp, so the cast is exact.
        #[allow(clippy::cast_possible_truncation)]
        Measurand::new(raw as i16, overflow, false)
    }

    /// A physical value measured against `limit` (the value at fraction 1.0).
    pub fn from_physical(value: f64, limit: f64) -> Measurand {
        if limit == 0.0 || !limit.is_finite() {
            return Measurand::new(0, false, true);
        }
        Measurand::from_fraction(value / limit)
    }

    /// The signed 13-bit value.
    pub fn raw13(self) -> i16 {
        i16::from_ne_bytes(self.0.to_ne_bytes()) >> 3
    }

    /// The value as a fraction of the limit.
    pub fn fraction(self) -> f64 {
        f64::from(self.raw13()) / 4096.0
    }

    /// The physical value for `limit`.
    pub fn to_physical(self, limit: f64) -> f64 {
        self.fraction() * limit
    }

    /// OV: the value was clamped at the limit.
    pub fn overflow(self) -> bool {
        self.0 & 0x0001 != 0
    }

    /// ER: the value is invalid.
    pub fn error(self) -> bool {
        self.0 & 0x0002 != 0
    }
}

impl fmt::Display for Measurand {
    /// The fraction with three decimals, then `OV` / `ER` when set.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:.3}", self.fraction())?;
        if self.overflow() {
            f.write_str(" OV")?;
        }
        if self.error() {
            f.write_str(" ER")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The derived examples of spec §4.6.
    #[test]
    fn spec_vectors() {
        let cases = [
            (1.0, 2.4, 1707, 0x3558),
            (0.8, 2.4, 1365, 0x2AA8),
            (1.0, 1.2, 3413, 0x6AA8),
            (0.9, 1.2, 3072, 0x6000),
        ];
        for (rated_multiple, limit, raw, word) in cases {
            let measurand = Measurand::from_physical(rated_multiple, limit);
            assert_eq!(measurand.raw13(), raw);
            assert_eq!(measurand.word(), word);
            assert!(!measurand.overflow() && !measurand.error());
            assert!((measurand.to_physical(limit) - rated_multiple).abs() < 0.001);
        }
        assert_eq!(
            Measurand::from_word(0x3558).word().to_le_bytes(),
            [0x58, 0x35]
        );
    }

    #[test]
    fn clamping_sets_overflow_and_negative_values_keep_their_sign() {
        let beyond = Measurand::from_physical(3.0, 2.4);
        assert!(beyond.overflow());
        assert_eq!(beyond.raw13(), 4095);
        let negative = Measurand::from_fraction(-0.5);
        assert_eq!(negative.raw13(), -2048);
        assert!(!negative.overflow());
        assert_eq!(Measurand::from_fraction(-1.5).raw13(), -4096);
        assert!(Measurand::from_fraction(f64::NAN).error());
        assert_eq!(Measurand::new(100, true, true).to_string(), "0.024 OV ER");
        for word in [0u16, 0xFFFF, 0x8000, 0x7FF8, 0x0003] {
            let measurand = Measurand::from_word(word);
            assert_eq!(
                Measurand::new(measurand.raw13(), measurand.overflow(), measurand.error()),
                measurand
            );
        }
    }
}
