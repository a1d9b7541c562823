//! 15-bit sequence numbers N(S) and N(R).

use std::fmt;

/// A 15-bit IEC 104 sequence number, N(S) or N(R), counting modulo 32768.
///
/// Arithmetic wraps from 32767 to 0. Sequence numbers have no total order; compare them
/// relative to a base with [`SeqNum::distance`] or [`SeqNum::is_within`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct SeqNum(u16);

/// A value above [`SeqNum::MAX`] was given where a sequence number was expected.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("sequence number {0} is out of range 0..=32767")]
pub struct SeqNumError(pub u16);

impl SeqNum {
    /// The modulus of the sequence number space: 2^15.
    pub const MODULUS: u16 = 1 << 15;
    /// The largest sequence number, 32767.
    pub const MAX: SeqNum = SeqNum(Self::MODULUS - 1);
    /// Sequence number 0, where every connection starts.
    pub const ZERO: SeqNum = SeqNum(0);

    /// Builds a sequence number, reducing `value` modulo 32768 (the top bit is dropped).
    ///
    /// Use [`SeqNum::try_new`] to reject out-of-range values instead.
    pub const fn new(value: u16) -> Self {
        SeqNum(value & (Self::MODULUS - 1))
    }

    /// Builds a sequence number, rejecting values above 32767.
    pub const fn try_new(value: u16) -> Result<Self, SeqNumError> {
        if value < Self::MODULUS {
            Ok(SeqNum(value))
        } else {
            Err(SeqNumError(value))
        }
    }

    /// The numeric value, 0..=32767.
    pub const fn value(self) -> u16 {
        self.0
    }

    /// The following sequence number (32767 wraps to 0).
    #[must_use]
    pub const fn next(self) -> Self {
        self.add(1)
    }

    /// This sequence number advanced by `n`, modulo 32768.
    #[must_use]
    pub const fn add(self, n: u16) -> Self {
        SeqNum::new(self.0.wrapping_add(n))
    }

    /// How many steps forward it takes to get from `self` to `to`, modulo 32768
    /// (0..=32767). `SeqNum::new(32766).distance(SeqNum::new(1)) == 3`.
    pub const fn distance(self, to: SeqNum) -> u16 {
        to.0.wrapping_sub(self.0) & (Self::MODULUS - 1)
    }

    /// Whether `self` lies in the inclusive window `[start, end]` walking forward from
    /// `start`, across the 32767 -> 0 wrap. `start == end` is a window of one number.
    pub const fn is_within(self, start: SeqNum, end: SeqNum) -> bool {
        start.distance(self) <= start.distance(end)
    }
}

impl TryFrom<u16> for SeqNum {
    type Error = SeqNumError;

    fn try_from(value: u16) -> Result<Self, Self::Error> {
        SeqNum::try_new(value)
    }
}

impl From<SeqNum> for u16 {
    fn from(seq: SeqNum) -> u16 {
        seq.0
    }
}

impl fmt::Display for SeqNum {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(&self.0, f)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::indexing_slicing)]
mod tests {
    use super::*;

    #[test]
    fn new_reduces_modulo() {
        assert_eq!(SeqNum::new(32768).value(), 0);
        assert_eq!(SeqNum::new(32769).value(), 1);
        assert_eq!(SeqNum::new(65535).value(), 32767);
        assert_eq!(SeqNum::try_new(32768), Err(SeqNumError(32768)));
        assert_eq!(SeqNum::try_from(32767).map(SeqNum::value), Ok(32767));
    }

    #[test]
    fn next_wraps() {
        assert_eq!(SeqNum::MAX.next(), SeqNum::ZERO);
        assert_eq!(SeqNum::new(5).next().value(), 6);
        assert_eq!(SeqNum::new(32760).add(10).value(), 2);
    }

    #[test]
    fn distance_across_wrap() {
        assert_eq!(SeqNum::new(32766).distance(SeqNum::new(1)), 3);
        assert_eq!(SeqNum::new(1).distance(SeqNum::new(1)), 0);
        assert_eq!(SeqNum::new(1).distance(SeqNum::new(0)), 32767);
        assert_eq!(SeqNum::ZERO.distance(SeqNum::MAX), 32767);
    }

    #[test]
    fn window_membership_across_wrap() {
        let start = SeqNum::new(32765);
        let end = SeqNum::new(2);
        for v in [32765, 32766, 32767, 0, 1, 2] {
            assert!(SeqNum::new(v).is_within(start, end), "{v}");
        }
        for v in [3, 100, 32764] {
            assert!(!SeqNum::new(v).is_within(start, end), "{v}");
        }
        assert!(SeqNum::new(7).is_within(SeqNum::new(7), SeqNum::new(7)));
        assert!(!SeqNum::new(8).is_within(SeqNum::new(7), SeqNum::new(7)));
    }
}
