//! Causes of transmission of IEC 60870-5-103 (one octet, no P/N or test bit).

use std::fmt;

/// A 103 cause of transmission: any octet, with the standard's values named.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Cause(pub u8);

impl Cause {
    /// 1: spontaneous.
    pub const SPONTANEOUS: Cause = Cause(1);
    /// 2: cyclic.
    pub const CYCLIC: Cause = Cause(2);
    /// 3: reset frame count bit.
    pub const RESET_FCB: Cause = Cause(3);
    /// 4: reset communication unit.
    pub const RESET_CU: Cause = Cause(4);
    /// 5: start / restart.
    pub const START_RESTART: Cause = Cause(5);
    /// 6: power on.
    pub const POWER_ON: Cause = Cause(6);
    /// 7: test mode.
    pub const TEST_MODE: Cause = Cause(7);
    /// 8: time synchronisation.
    pub const TIME_SYNC: Cause = Cause(8);
    /// 9: general interrogation.
    pub const GENERAL_INTERROGATION: Cause = Cause(9);
    /// 10: termination of general interrogation.
    pub const GI_TERMINATION: Cause = Cause(10);
    /// 11: local operation.
    pub const LOCAL_OPERATION: Cause = Cause(11);
    /// 12: remote operation.
    pub const REMOTE_OPERATION: Cause = Cause(12);
    /// 20: positive acknowledgement of command.
    pub const COMMAND_ACK: Cause = Cause(20);
    /// 21: negative acknowledgement of command.
    pub const COMMAND_NACK: Cause = Cause(21);
    /// 31: transmission of disturbance data.
    pub const DISTURBANCE_DATA: Cause = Cause(31);
    /// 40: positive acknowledgement of generic write command (control: generic write).
    pub const GENERIC_WRITE_ACK: Cause = Cause(40);
    /// 41: negative acknowledgement of generic write command.
    pub const GENERIC_WRITE_NACK: Cause = Cause(41);
    /// 42: valid data response to generic read command (control: generic read).
    pub const GENERIC_READ_VALID: Cause = Cause(42);
    /// 43: invalid data response to generic read command.
    pub const GENERIC_READ_INVALID: Cause = Cause(43);
    /// 44: generic write confirmation.
    pub const GENERIC_WRITE_CONFIRMATION: Cause = Cause(44);

    /// The standard's name, `None` for a value it does not define.
    pub fn name(self) -> Option<&'static str> {
        Some(match self.0 {
            1 => "spontaneous",
            2 => "cyclic",
            3 => "reset FCB",
            4 => "reset CU",
            5 => "start/restart",
            6 => "power on",
            7 => "test mode",
            8 => "time synchronisation",
            9 => "general interrogation",
            10 => "termination of GI",
            11 => "local operation",
            12 => "remote operation",
            20 => "command ack",
            21 => "command nack",
            31 => "disturbance data",
            40 => "generic write ack",
            41 => "generic write nack",
            42 => "generic read valid",
            43 => "generic read invalid",
            44 => "generic write confirmation",
            _ => return None,
        })
    }

    /// A short mnemonic for analyser lines (PCVDEW6 style: `Cycl.`, `GI`, `Spont`).
    pub fn mnemonic(self) -> &'static str {
        match self.0 {
            1 => "Spont",
            2 => "Cycl.",
            3 => "RFCB",
            4 => "RCU",
            5 => "W-Strt",
            6 => "C-Strt",
            7 => "Test",
            8 => "TSync",
            9 => "GI",
            10 => "GI-End",
            11 => "Local",
            12 => "Remote",
            20 => "Ack",
            21 => "Nack",
            31 => "Dist.",
            40..=44 => "Generic",
            _ => "?",
        }
    }
}

impl fmt::Display for Cause {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(name) => write!(f, "{name} ({})", self.0),
            None => write!(f, "unknown ({})", self.0),
        }
    }
}
