//! Cause of transmission: the 6-bit cause, the P/N and T flags and the originator address.

use std::fmt;

use super::RangeError;

/// The 6-bit cause of transmission.
///
/// Every value 0..63 is representable, because a decoder must show non-standard causes
/// (seed logs carry COT 0 and COT 5 on commands). The associated constants are the causes
/// the standard defines.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Cause(u8);

/// Short names of the group interrogation causes 21..36, indexed by group - 1.
const GROUP_NAMES: [&str; 16] = [
    "inro1", "inro2", "inro3", "inro4", "inro5", "inro6", "inro7", "inro8", "inro9", "inro10",
    "inro11", "inro12", "inro13", "inro14", "inro15", "inro16",
];

/// Short names of the counter interrogation group causes 38..41, indexed by group - 1.
const COUNTER_GROUP_NAMES: [&str; 4] = ["reqco1", "reqco2", "reqco3", "reqco4"];

impl Cause {
    /// 1: periodic, cyclic.
    pub const PERIODIC: Cause = Cause(1);
    /// 2: background scan.
    pub const BACKGROUND: Cause = Cause(2);
    /// 3: spontaneous.
    pub const SPONTANEOUS: Cause = Cause(3);
    /// 4: initialised.
    pub const INITIALISED: Cause = Cause(4);
    /// 5: request or requested.
    pub const REQUEST: Cause = Cause(5);
    /// 6: activation.
    pub const ACTIVATION: Cause = Cause(6);
    /// 7: activation confirmation.
    pub const ACTIVATION_CON: Cause = Cause(7);
    /// 8: deactivation.
    pub const DEACTIVATION: Cause = Cause(8);
    /// 9: deactivation confirmation.
    pub const DEACTIVATION_CON: Cause = Cause(9);
    /// 10: activation termination.
    pub const ACTIVATION_TERMINATION: Cause = Cause(10);
    /// 11: return information caused by a remote command.
    pub const RETURN_REMOTE: Cause = Cause(11);
    /// 12: return information caused by a local command.
    pub const RETURN_LOCAL: Cause = Cause(12);
    /// 13: file transfer.
    pub const FILE_TRANSFER: Cause = Cause(13);
    /// 20: interrogated by station interrogation.
    pub const INTERROGATED_BY_STATION: Cause = Cause(20);
    /// 37: requested by general counter request.
    pub const REQUESTED_BY_GENERAL_COUNTER: Cause = Cause(37);
    /// 44: unknown type identification.
    pub const UNKNOWN_TYPE: Cause = Cause(44);
    /// 45: unknown cause of transmission.
    pub const UNKNOWN_CAUSE: Cause = Cause(45);
    /// 46: unknown common address of ASDU.
    pub const UNKNOWN_COMMON_ADDRESS: Cause = Cause(46);
    /// 47: unknown information object address.
    pub const UNKNOWN_OBJECT_ADDRESS: Cause = Cause(47);

    /// A cause 0..63.
    pub fn new(value: u8) -> Result<Cause, RangeError> {
        if value <= 63 {
            Ok(Cause(value))
        } else {
            Err(RangeError::new(
                "cause of transmission",
                value.into(),
                0,
                63,
            ))
        }
    }

    /// The cause from the low six bits of a COT octet (P/N and T are dropped).
    pub fn from_bits(octet: u8) -> Cause {
        Cause(octet & 0x3F)
    }

    /// The number 0..63.
    pub fn value(self) -> u8 {
        self.0
    }

    /// "Interrogated by group `group`" for groups 1..16 (causes 21..36).
    pub fn interrogated_by_group(group: u8) -> Option<Cause> {
        (1..=16).contains(&group).then(|| Cause(20 + group))
    }

    /// "Requested by counter interrogation group `group`" for groups 1..4 (38..41).
    pub fn requested_by_counter_group(group: u8) -> Option<Cause> {
        (1..=4).contains(&group).then(|| Cause(37 + group))
    }

    /// The interrogation group 1..16 of causes 21..36, `None` for any other cause.
    pub fn group(self) -> Option<u8> {
        (21..=36).contains(&self.0).then(|| self.0 - 20)
    }

    /// The counter group 1..4 of causes 38..41, `None` for any other cause.
    pub fn counter_group(self) -> Option<u8> {
        (38..=41).contains(&self.0).then(|| self.0 - 37)
    }

    /// Whether the cause answers an interrogation (20..36).
    pub fn is_interrogated(self) -> bool {
        (20..=36).contains(&self.0)
    }

    /// Short name as protocol analysers print it: "spont", "act", "actcon", "inrogen",
    /// "inro3", "reqcogen", "unknown type", .. "not defined" for 0 and "reserved" for the
    /// numbers the standard leaves free.
    pub fn name(self) -> &'static str {
        match self.0 {
            0 => "not defined",
            1 => "per/cyc",
            2 => "back",
            3 => "spont",
            4 => "init",
            5 => "req",
            6 => "act",
            7 => "actcon",
            8 => "deact",
            9 => "deactcon",
            10 => "actterm",
            11 => "retrem",
            12 => "retloc",
            13 => "file",
            20 => "inrogen",
            21..=36 => GROUP_NAMES
                .get(usize::from(self.0 - 21))
                .copied()
                .unwrap_or("inro"),
            37 => "reqcogen",
            38..=41 => COUNTER_GROUP_NAMES
                .get(usize::from(self.0 - 38))
                .copied()
                .unwrap_or("reqco"),
            44 => "unknown type",
            45 => "unknown cause",
            46 => "unknown common address",
            47 => "unknown object address",
            48..=63 => "special use",
            _ => "reserved",
        }
    }
}

impl TryFrom<u8> for Cause {
    type Error = RangeError;

    fn try_from(value: u8) -> Result<Self, RangeError> {
        Cause::new(value)
    }
}

impl From<Cause> for u8 {
    fn from(cause: Cause) -> u8 {
        cause.0
    }
}

impl fmt::Display for Cause {
    /// `spont(3)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}({})", self.name(), self.0)
    }
}

/// The whole cause-of-transmission field: cause, P/N, T and originator address.
///
/// With a one-octet COT field (some 101 links) the originator is not on the wire: it
/// decodes as 0 and must be 0 to encode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Cot {
    /// The cause.
    pub cause: Cause,
    /// P/N: negative confirmation of a requested action.
    pub negative: bool,
    /// T: test, generated only to test the equipment.
    pub test: bool,
    /// Originator address (0 when unused or not on the wire).
    pub originator: u8,
}

impl Cot {
    /// A positive, non-test COT with originator 0.
    pub fn new(cause: Cause) -> Cot {
        Cot {
            cause,
            negative: false,
            test: false,
            originator: 0,
        }
    }

    /// The same COT with P/N set.
    #[must_use]
    pub fn negative(mut self) -> Cot {
        self.negative = true;
        self
    }

    /// The same COT with T set.
    #[must_use]
    pub fn test(mut self) -> Cot {
        self.test = true;
        self
    }

    /// The same COT with this originator address.
    #[must_use]
    pub fn with_originator(mut self, originator: u8) -> Cot {
        self.originator = originator;
        self
    }

    /// The first COT octet: cause in bits 0-5, P/N in bit 6, T in bit 7.
    pub fn octet(&self) -> u8 {
        self.cause.value() | if self.negative { 0x40 } else { 0 } | if self.test { 0x80 } else { 0 }
    }

    /// Splits the first COT octet; `originator` comes from the second octet if any.
    pub fn from_octets(first: u8, originator: u8) -> Cot {
        Cot {
            cause: Cause::from_bits(first),
            negative: first & 0x40 != 0,
            test: first & 0x80 != 0,
            originator,
        }
    }
}

impl From<Cause> for Cot {
    fn from(cause: Cause) -> Cot {
        Cot::new(cause)
    }
}

impl fmt::Display for Cot {
    /// `spont(3) [tst pn] oa=0`: lower case clear, upper case set.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} [{} {}] oa={}",
            self.cause,
            if self.test { "TST" } else { "tst" },
            if self.negative { "PN" } else { "pn" },
            self.originator
        )
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]
mod tests {
    use super::*;

    #[test]
    fn names() {
        assert_eq!(Cause::SPONTANEOUS.to_string(), "spont(3)");
        assert_eq!(Cause::new(0).unwrap().name(), "not defined");
        assert_eq!(Cause::interrogated_by_group(1).unwrap().name(), "inro1");
        assert_eq!(Cause::interrogated_by_group(16).unwrap().value(), 36);
        assert_eq!(Cause::interrogated_by_group(17), None);
        assert_eq!(Cause::new(36).unwrap().group(), Some(16));
        assert_eq!(
            Cause::requested_by_counter_group(4).unwrap().name(),
            "reqco4"
        );
        assert_eq!(Cause::UNKNOWN_TYPE.name(), "unknown type");
        assert!(Cause::new(64).is_err());
        for n in 0..=63 {
            assert!(!Cause::new(n).unwrap().name().is_empty());
        }
    }

    #[test]
    fn octet_layout() {
        let cot = Cot::new(Cause::ACTIVATION_CON).negative().test();
        assert_eq!(cot.octet(), 0xC7);
        assert_eq!(Cot::from_octets(0xC7, 9), cot.with_originator(9));
        assert_eq!(cot.to_string(), "actcon(7) [TST PN] oa=0");
    }
}
