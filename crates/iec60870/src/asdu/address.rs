//! Common address of ASDU and information object address.

use std::fmt;

use super::{AsduParams, RangeError};

/// Common address of ASDU (station or sector address), 1 or 2 octets on the wire.
///
/// 0 is not used by the standard; the broadcast (global) address is 0xFF with one octet
/// and 0xFFFF with two. Values that do not fit the link's field size are refused when
/// encoding.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct CommonAddress(u16);

impl CommonAddress {
    /// A common address.
    pub const fn new(value: u16) -> CommonAddress {
        CommonAddress(value)
    }

    /// The number.
    pub const fn get(self) -> u16 {
        self.0
    }

    /// The broadcast address for the link's field size: 0xFF or 0xFFFF.
    pub fn broadcast(params: &AsduParams) -> CommonAddress {
        if params.common_address_size() == 1 {
            CommonAddress(0xFF)
        } else {
            CommonAddress(0xFFFF)
        }
    }

    /// Whether this is the broadcast address for the link's field size.
    pub fn is_broadcast(self, params: &AsduParams) -> bool {
        self == Self::broadcast(params)
    }
}

impl From<u16> for CommonAddress {
    fn from(value: u16) -> CommonAddress {
        CommonAddress(value)
    }
}

impl From<u8> for CommonAddress {
    fn from(value: u8) -> CommonAddress {
        CommonAddress(value.into())
    }
}

impl From<CommonAddress> for u16 {
    fn from(address: CommonAddress) -> u16 {
        address.0
    }
}

impl fmt::Display for CommonAddress {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// Information object address, 1, 2 or 3 octets on the wire (0..0xFFFFFF).
///
/// 0 means "irrelevant" (used by station-wide commands such as C_IC_NA_1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct Ioa(u32);

impl Ioa {
    /// The largest address (three octets).
    pub const MAX: Ioa = Ioa(0xFF_FFFF);

    /// Address 0, "irrelevant", used by station-wide commands.
    pub const IRRELEVANT: Ioa = Ioa(0);

    /// An address 0..0xFFFFFF.
    pub fn try_new(value: u32) -> Result<Ioa, RangeError> {
        if value <= Self::MAX.0 {
            Ok(Ioa(value))
        } else {
            Err(RangeError::new(
                "information object address",
                value.into(),
                0,
                Self::MAX.0.into(),
            ))
        }
    }

    /// The number.
    pub const fn get(self) -> u32 {
        self.0
    }

    /// The address `offset` places further on, `None` past 0xFFFFFF. Used for the
    /// consecutive addresses of an SQ = 1 ASDU.
    pub fn checked_add(self, offset: u32) -> Option<Ioa> {
        self.0
            .checked_add(offset)
            .filter(|value| *value <= Self::MAX.0)
            .map(Ioa)
    }
}

impl TryFrom<u32> for Ioa {
    type Error = RangeError;

    fn try_from(value: u32) -> Result<Ioa, RangeError> {
        Ioa::try_new(value)
    }
}

impl From<u16> for Ioa {
    fn from(value: u16) -> Ioa {
        Ioa(value.into())
    }
}

impl From<u8> for Ioa {
    fn from(value: u8) -> Ioa {
        Ioa(value.into())
    }
}

impl From<Ioa> for u32 {
    fn from(ioa: Ioa) -> u32 {
        ioa.0
    }
}

impl fmt::Display for Ioa {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}
