//! Transport service access points: which end of an ISO-on-TCP connection is which.
//!
//! An S7 client sends two TSAPs in its connection request: its own (the calling TSAP,
//! `0x0100` by default) and the PLC's (the called TSAP). The PLC's TSAP is two bytes:
//! the connection type in the high byte (1 PG, 2 OP, 3 S7 basic; others exist) and
//! `rack * 32 + slot` in the low byte, so `0x0301` is an S7 basic connection to the CPU
//! in rack 0, slot 1. LOGO! and S7-1200/1500 configured connections use agreed TSAP
//! pairs instead (the railway-station thesis, section 3.3): [`Tsaps`] parses them as
//! `LOCAL:REMOTE` in four hex digits each, `0100:0301`.

use std::fmt;
use std::str::FromStr;

use thiserror::Error;

use crate::wire::hex;

/// The connection types of the high byte of a PLC's TSAP.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ConnectionType {
    /// Programming device (1).
    Pg,
    /// Operator panel (2).
    Op,
    /// S7 basic communication (3), what this crate's client sends by default.
    S7Basic,
}

impl ConnectionType {
    /// The TSAP high byte.
    pub fn code(self) -> u8 {
        match self {
            ConnectionType::Pg => 1,
            ConnectionType::Op => 2,
            ConnectionType::S7Basic => 3,
        }
    }
}

/// A TSAP: two bytes from S7 devices, though the protocol allows other lengths (and a
/// server keeps whatever a client sent).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Tsap(Vec<u8>);

impl Tsap {
    /// The calling TSAP S7 clients send by default.
    pub const DEFAULT_LOCAL: u16 = 0x0100;

    /// A two-byte TSAP.
    pub fn new(value: u16) -> Tsap {
        Tsap(value.to_be_bytes().to_vec())
    }

    /// A TSAP of any length, as received.
    pub fn from_bytes(bytes: &[u8]) -> Tsap {
        Tsap(bytes.to_vec())
    }

    /// The TSAP of a PLC's CPU: connection type, then `rack * 32 + slot`.
    pub fn remote(connection_type: ConnectionType, rack: u8, slot: u8) -> Tsap {
        let position = rack.wrapping_mul(32).wrapping_add(slot);
        Tsap(vec![connection_type.code(), position])
    }

    /// The bytes as they travel.
    pub fn as_bytes(&self) -> &[u8] {
        &self.0
    }

    /// The value of a two-byte TSAP.
    pub fn as_u16(&self) -> Option<u16> {
        let array: [u8; 2] = self.0.as_slice().try_into().ok()?;
        Some(u16::from_be_bytes(array))
    }
}

/// Hex, four digits for a two-byte TSAP (`0301`).
impl fmt::Display for Tsap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&hex(&self.0))
    }
}

/// The pair a client connects with.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Tsaps {
    /// The client's own, the calling TSAP.
    pub local: Tsap,
    /// The PLC's, the called TSAP.
    pub remote: Tsap,
}

impl Tsaps {
    /// The default local TSAP and an S7 basic connection to the CPU at `rack`, `slot`.
    pub fn rack_slot(rack: u8, slot: u8) -> Tsaps {
        Tsaps {
            local: Tsap::new(Tsap::DEFAULT_LOCAL),
            remote: Tsap::remote(ConnectionType::S7Basic, rack, slot),
        }
    }
}

/// Rack 0, slot 1: an S7-300's CPU, and what S7-1200/1500 and LOGO! answer to.
impl Default for Tsaps {
    fn default() -> Self {
        Tsaps::rack_slot(0, 1)
    }
}

/// `0100:0301`.
impl fmt::Display for Tsaps {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.local, self.remote)
    }
}

/// A TSAP pair not written as `LOCAL:REMOTE` with four hex digits each.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("TSAPs {0:?}: expected LOCAL:REMOTE in four hex digits each, e.g. 0100:0301")]
pub struct TsapError(pub String);

impl FromStr for Tsaps {
    type Err = TsapError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let error = || TsapError(text.to_owned());
        let (local, remote) = text.trim().split_once(':').ok_or_else(error)?;
        let parse = |part: &str| {
            if part.len() == 4 && part.chars().all(|c| c.is_ascii_hexdigit()) {
                u16::from_str_radix(part, 16).ok().map(Tsap::new)
            } else {
                None
            }
        };
        Ok(Tsaps {
            local: parse(local).ok_or_else(error)?,
            remote: parse(remote).ok_or_else(error)?,
        })
    }
}
