//! Type identification: the first octet of an ASDU.

use std::fmt;
use std::str::FromStr;

/// Which time tag the objects of a type carry after their element.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TimeTagKind {
    /// No time tag (C_CS_NA_1 carries its time as the element itself).
    None,
    /// Three-octet CP24Time2a (101 only).
    Cp24,
    /// Seven-octet CP56Time2a.
    Cp56,
}

impl TimeTagKind {
    /// Octets of the tag on the wire: 0, 3 or 7.
    pub fn len(self) -> usize {
        match self {
            TimeTagKind::None => 0,
            TimeTagKind::Cp24 => 3,
            TimeTagKind::Cp56 => 7,
        }
    }

    /// Whether there is no tag (zero length).
    pub fn is_empty(self) -> bool {
        self == TimeTagKind::None
    }
}

/// Type identification, named by the mnemonics of IEC 60870-5-101/104.
///
/// `M_` monitor direction, `C_` control direction, `P_` parameters, `F_` file transfer;
/// `_NA_`.. without time tag, `_TA_` with CP24Time2a (101), `_TB_`.. with CP56Time2a.
#[allow(non_camel_case_types)]
#[repr(u8)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum TypeId {
    /// Single-point information.
    M_SP_NA_1 = 1,
    /// Single-point information with CP24Time2a.
    M_SP_TA_1 = 2,
    /// Double-point information.
    M_DP_NA_1 = 3,
    /// Double-point information with CP24Time2a.
    M_DP_TA_1 = 4,
    /// Step position information.
    M_ST_NA_1 = 5,
    /// Step position information with CP24Time2a.
    M_ST_TA_1 = 6,
    /// Bitstring of 32 bits.
    M_BO_NA_1 = 7,
    /// Bitstring of 32 bits with CP24Time2a.
    M_BO_TA_1 = 8,
    /// Measured value, normalized.
    M_ME_NA_1 = 9,
    /// Measured value, normalized, with CP24Time2a.
    M_ME_TA_1 = 10,
    /// Measured value, scaled.
    M_ME_NB_1 = 11,
    /// Measured value, scaled, with CP24Time2a.
    M_ME_TB_1 = 12,
    /// Measured value, short floating point.
    M_ME_NC_1 = 13,
    /// Measured value, short floating point, with CP24Time2a.
    M_ME_TC_1 = 14,
    /// Integrated totals.
    M_IT_NA_1 = 15,
    /// Integrated totals with CP24Time2a.
    M_IT_TA_1 = 16,
    /// Event of protection equipment with CP24Time2a.
    M_EP_TA_1 = 17,
    /// Packed start events of protection equipment with CP24Time2a.
    M_EP_TB_1 = 18,
    /// Packed output circuit information of protection equipment with CP24Time2a.
    M_EP_TC_1 = 19,
    /// Packed single-point information with status change detection.
    M_PS_NA_1 = 20,
    /// Measured value, normalized, without quality descriptor.
    M_ME_ND_1 = 21,
    /// Single-point information with CP56Time2a.
    M_SP_TB_1 = 30,
    /// Double-point information with CP56Time2a.
    M_DP_TB_1 = 31,
    /// Step position information with CP56Time2a.
    M_ST_TB_1 = 32,
    /// Bitstring of 32 bits with CP56Time2a.
    M_BO_TB_1 = 33,
    /// Measured value, normalized, with CP56Time2a.
    M_ME_TD_1 = 34,
    /// Measured value, scaled, with CP56Time2a.
    M_ME_TE_1 = 35,
    /// Measured value, short floating point, with CP56Time2a.
    M_ME_TF_1 = 36,
    /// Integrated totals with CP56Time2a.
    M_IT_TB_1 = 37,
    /// Event of protection equipment with CP56Time2a.
    M_EP_TD_1 = 38,
    /// Packed start events of protection equipment with CP56Time2a.
    M_EP_TE_1 = 39,
    /// Packed output circuit information of protection equipment with CP56Time2a.
    M_EP_TF_1 = 40,
    /// Single command.
    C_SC_NA_1 = 45,
    /// Double command.
    C_DC_NA_1 = 46,
    /// Regulating step command.
    C_RC_NA_1 = 47,
    /// Set-point command, normalized value.
    C_SE_NA_1 = 48,
    /// Set-point command, scaled value.
    C_SE_NB_1 = 49,
    /// Set-point command, short floating point value.
    C_SE_NC_1 = 50,
    /// Bitstring of 32 bits command.
    C_BO_NA_1 = 51,
    /// Single command with CP56Time2a.
    C_SC_TA_1 = 58,
    /// Double command with CP56Time2a.
    C_DC_TA_1 = 59,
    /// Regulating step command with CP56Time2a.
    C_RC_TA_1 = 60,
    /// Set-point command, normalized value, with CP56Time2a.
    C_SE_TA_1 = 61,
    /// Set-point command, scaled value, with CP56Time2a.
    C_SE_TB_1 = 62,
    /// Set-point command, short floating point value, with CP56Time2a.
    C_SE_TC_1 = 63,
    /// Bitstring of 32 bits command with CP56Time2a.
    C_BO_TA_1 = 64,
    /// End of initialisation.
    M_EI_NA_1 = 70,
    /// Interrogation command.
    C_IC_NA_1 = 100,
    /// Counter interrogation command.
    C_CI_NA_1 = 101,
    /// Read command.
    C_RD_NA_1 = 102,
    /// Clock synchronisation command.
    C_CS_NA_1 = 103,
    /// Test command (101; IEC 104 uses C_TS_TA_1).
    C_TS_NA_1 = 104,
    /// Reset process command.
    C_RP_NA_1 = 105,
    /// Delay acquisition command (101).
    C_CD_NA_1 = 106,
    /// Test command with CP56Time2a.
    C_TS_TA_1 = 107,
    /// Parameter of measured value, normalized.
    P_ME_NA_1 = 110,
    /// Parameter of measured value, scaled.
    P_ME_NB_1 = 111,
    /// Parameter of measured value, short floating point.
    P_ME_NC_1 = 112,
    /// Parameter activation.
    P_AC_NA_1 = 113,
    /// File ready.
    F_FR_NA_1 = 120,
    /// Section ready.
    F_SR_NA_1 = 121,
    /// Call directory, select file, call file, call section.
    F_SC_NA_1 = 122,
    /// Last section, last segment.
    F_LS_NA_1 = 123,
    /// Acknowledge file, acknowledge section.
    F_AF_NA_1 = 124,
    /// Segment.
    F_SG_NA_1 = 125,
    /// Directory.
    F_DR_TA_1 = 126,
    /// Query log, request archive file.
    F_SC_NB_1 = 127,
}

/// Why a mnemonic could not be parsed into a [`TypeId`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown type identification mnemonic {0:?}")]
pub struct ParseTypeIdError(pub String);

use TypeId::*;

impl TypeId {
    /// Every type identification, in numeric order.
    pub const ALL: &'static [TypeId] = &[
        M_SP_NA_1, M_SP_TA_1, M_DP_NA_1, M_DP_TA_1, M_ST_NA_1, M_ST_TA_1, M_BO_NA_1, M_BO_TA_1,
        M_ME_NA_1, M_ME_TA_1, M_ME_NB_1, M_ME_TB_1, M_ME_NC_1, M_ME_TC_1, M_IT_NA_1, M_IT_TA_1,
        M_EP_TA_1, M_EP_TB_1, M_EP_TC_1, M_PS_NA_1, M_ME_ND_1, M_SP_TB_1, M_DP_TB_1, M_ST_TB_1,
        M_BO_TB_1, M_ME_TD_1, M_ME_TE_1, M_ME_TF_1, M_IT_TB_1, M_EP_TD_1, M_EP_TE_1, M_EP_TF_1,
        C_SC_NA_1, C_DC_NA_1, C_RC_NA_1, C_SE_NA_1, C_SE_NB_1, C_SE_NC_1, C_BO_NA_1, C_SC_TA_1,
        C_DC_TA_1, C_RC_TA_1, C_SE_TA_1, C_SE_TB_1, C_SE_TC_1, C_BO_TA_1, M_EI_NA_1, C_IC_NA_1,
        C_CI_NA_1, C_RD_NA_1, C_CS_NA_1, C_TS_NA_1, C_RP_NA_1, C_CD_NA_1, C_TS_TA_1, P_ME_NA_1,
        P_ME_NB_1, P_ME_NC_1, P_AC_NA_1, F_FR_NA_1, F_SR_NA_1, F_SC_NA_1, F_LS_NA_1, F_AF_NA_1,
        F_SG_NA_1, F_DR_TA_1, F_SC_NB_1,
    ];

    /// The type with this number, `None` for numbers the standard does not define.
    pub fn from_u8(value: u8) -> Option<TypeId> {
        // ALL is sorted, so a binary search finds the number without a 256-entry table.
        Self::ALL
            .binary_search_by_key(&value, |t| *t as u8)
            .ok()
            .and_then(|index| Self::ALL.get(index).copied())
    }

    /// The number on the wire.
    pub fn value(self) -> u8 {
        self as u8
    }

    /// The standard mnemonic, e.g. `"M_SP_NA_1"`.
    pub fn mnemonic(self) -> &'static str {
        match self {
            M_SP_NA_1 => "M_SP_NA_1",
            M_SP_TA_1 => "M_SP_TA_1",
            M_DP_NA_1 => "M_DP_NA_1",
            M_DP_TA_1 => "M_DP_TA_1",
            M_ST_NA_1 => "M_ST_NA_1",
            M_ST_TA_1 => "M_ST_TA_1",
            M_BO_NA_1 => "M_BO_NA_1",
            M_BO_TA_1 => "M_BO_TA_1",
            M_ME_NA_1 => "M_ME_NA_1",
            M_ME_TA_1 => "M_ME_TA_1",
            M_ME_NB_1 => "M_ME_NB_1",
            M_ME_TB_1 => "M_ME_TB_1",
            M_ME_NC_1 => "M_ME_NC_1",
            M_ME_TC_1 => "M_ME_TC_1",
            M_IT_NA_1 => "M_IT_NA_1",
            M_IT_TA_1 => "M_IT_TA_1",
            M_EP_TA_1 => "M_EP_TA_1",
            M_EP_TB_1 => "M_EP_TB_1",
            M_EP_TC_1 => "M_EP_TC_1",
            M_PS_NA_1 => "M_PS_NA_1",
            M_ME_ND_1 => "M_ME_ND_1",
            M_SP_TB_1 => "M_SP_TB_1",
            M_DP_TB_1 => "M_DP_TB_1",
            M_ST_TB_1 => "M_ST_TB_1",
            M_BO_TB_1 => "M_BO_TB_1",
            M_ME_TD_1 => "M_ME_TD_1",
            M_ME_TE_1 => "M_ME_TE_1",
            M_ME_TF_1 => "M_ME_TF_1",
            M_IT_TB_1 => "M_IT_TB_1",
            M_EP_TD_1 => "M_EP_TD_1",
            M_EP_TE_1 => "M_EP_TE_1",
            M_EP_TF_1 => "M_EP_TF_1",
            C_SC_NA_1 => "C_SC_NA_1",
            C_DC_NA_1 => "C_DC_NA_1",
            C_RC_NA_1 => "C_RC_NA_1",
            C_SE_NA_1 => "C_SE_NA_1",
            C_SE_NB_1 => "C_SE_NB_1",
            C_SE_NC_1 => "C_SE_NC_1",
            C_BO_NA_1 => "C_BO_NA_1",
            C_SC_TA_1 => "C_SC_TA_1",
            C_DC_TA_1 => "C_DC_TA_1",
            C_RC_TA_1 => "C_RC_TA_1",
            C_SE_TA_1 => "C_SE_TA_1",
            C_SE_TB_1 => "C_SE_TB_1",
            C_SE_TC_1 => "C_SE_TC_1",
            C_BO_TA_1 => "C_BO_TA_1",
            M_EI_NA_1 => "M_EI_NA_1",
            C_IC_NA_1 => "C_IC_NA_1",
            C_CI_NA_1 => "C_CI_NA_1",
            C_RD_NA_1 => "C_RD_NA_1",
            C_CS_NA_1 => "C_CS_NA_1",
            C_TS_NA_1 => "C_TS_NA_1",
            C_RP_NA_1 => "C_RP_NA_1",
            C_CD_NA_1 => "C_CD_NA_1",
            C_TS_TA_1 => "C_TS_TA_1",
            P_ME_NA_1 => "P_ME_NA_1",
            P_ME_NB_1 => "P_ME_NB_1",
            P_ME_NC_1 => "P_ME_NC_1",
            P_AC_NA_1 => "P_AC_NA_1",
            F_FR_NA_1 => "F_FR_NA_1",
            F_SR_NA_1 => "F_SR_NA_1",
            F_SC_NA_1 => "F_SC_NA_1",
            F_LS_NA_1 => "F_LS_NA_1",
            F_AF_NA_1 => "F_AF_NA_1",
            F_SG_NA_1 => "F_SG_NA_1",
            F_DR_TA_1 => "F_DR_TA_1",
            F_SC_NB_1 => "F_SC_NB_1",
        }
    }

    /// The meaning in English, e.g. "single-point information with time tag CP56Time2a".
    pub fn description(self) -> &'static str {
        match self {
            M_SP_NA_1 => "single-point information",
            M_SP_TA_1 => "single-point information with time tag CP24Time2a",
            M_DP_NA_1 => "double-point information",
            M_DP_TA_1 => "double-point information with time tag CP24Time2a",
            M_ST_NA_1 => "step position information",
            M_ST_TA_1 => "step position information with time tag CP24Time2a",
            M_BO_NA_1 => "bitstring of 32 bits",
            M_BO_TA_1 => "bitstring of 32 bits with time tag CP24Time2a",
            M_ME_NA_1 => "measured value, normalized value",
            M_ME_TA_1 => "measured value, normalized value with time tag CP24Time2a",
            M_ME_NB_1 => "measured value, scaled value",
            M_ME_TB_1 => "measured value, scaled value with time tag CP24Time2a",
            M_ME_NC_1 => "measured value, short floating point value",
            M_ME_TC_1 => "measured value, short floating point value with time tag CP24Time2a",
            M_IT_NA_1 => "integrated totals",
            M_IT_TA_1 => "integrated totals with time tag CP24Time2a",
            M_EP_TA_1 => "event of protection equipment with time tag CP24Time2a",
            M_EP_TB_1 => "packed start events of protection equipment with time tag CP24Time2a",
            M_EP_TC_1 => {
                "packed output circuit information of protection equipment with time tag CP24Time2a"
            }
            M_PS_NA_1 => "packed single-point information with status change detection",
            M_ME_ND_1 => "measured value, normalized value without quality descriptor",
            M_SP_TB_1 => "single-point information with time tag CP56Time2a",
            M_DP_TB_1 => "double-point information with time tag CP56Time2a",
            M_ST_TB_1 => "step position information with time tag CP56Time2a",
            M_BO_TB_1 => "bitstring of 32 bits with time tag CP56Time2a",
            M_ME_TD_1 => "measured value, normalized value with time tag CP56Time2a",
            M_ME_TE_1 => "measured value, scaled value with time tag CP56Time2a",
            M_ME_TF_1 => "measured value, short floating point value with time tag CP56Time2a",
            M_IT_TB_1 => "integrated totals with time tag CP56Time2a",
            M_EP_TD_1 => "event of protection equipment with time tag CP56Time2a",
            M_EP_TE_1 => "packed start events of protection equipment with time tag CP56Time2a",
            M_EP_TF_1 => {
                "packed output circuit information of protection equipment with time tag CP56Time2a"
            }
            C_SC_NA_1 => "single command",
            C_DC_NA_1 => "double command",
            C_RC_NA_1 => "regulating step command",
            C_SE_NA_1 => "set-point command, normalized value",
            C_SE_NB_1 => "set-point command, scaled value",
            C_SE_NC_1 => "set-point command, short floating point value",
            C_BO_NA_1 => "bitstring of 32 bits command",
            C_SC_TA_1 => "single command with time tag CP56Time2a",
            C_DC_TA_1 => "double command with time tag CP56Time2a",
            C_RC_TA_1 => "regulating step command with time tag CP56Time2a",
            C_SE_TA_1 => "set-point command, normalized value with time tag CP56Time2a",
            C_SE_TB_1 => "set-point command, scaled value with time tag CP56Time2a",
            C_SE_TC_1 => "set-point command, short floating point value with time tag CP56Time2a",
            C_BO_TA_1 => "bitstring of 32 bits command with time tag CP56Time2a",
            M_EI_NA_1 => "end of initialisation",
            C_IC_NA_1 => "interrogation command",
            C_CI_NA_1 => "counter interrogation command",
            C_RD_NA_1 => "read command",
            C_CS_NA_1 => "clock synchronisation command",
            C_TS_NA_1 => "test command",
            C_RP_NA_1 => "reset process command",
            C_CD_NA_1 => "delay acquisition command",
            C_TS_TA_1 => "test command with time tag CP56Time2a",
            P_ME_NA_1 => "parameter of measured value, normalized value",
            P_ME_NB_1 => "parameter of measured value, scaled value",
            P_ME_NC_1 => "parameter of measured value, short floating point value",
            P_AC_NA_1 => "parameter activation",
            F_FR_NA_1 => "file ready",
            F_SR_NA_1 => "section ready",
            F_SC_NA_1 => "call directory, select file, call file, call section",
            F_LS_NA_1 => "last section, last segment",
            F_AF_NA_1 => "acknowledge file, acknowledge section",
            F_SG_NA_1 => "segment",
            F_DR_TA_1 => "directory",
            F_SC_NB_1 => "query log, request archive file",
        }
    }

    /// Which time tag follows each element of this type.
    pub fn time_tag(self) -> TimeTagKind {
        match self {
            M_SP_TA_1 | M_DP_TA_1 | M_ST_TA_1 | M_BO_TA_1 | M_ME_TA_1 | M_ME_TB_1 | M_ME_TC_1
            | M_IT_TA_1 | M_EP_TA_1 | M_EP_TB_1 | M_EP_TC_1 => TimeTagKind::Cp24,
            M_SP_TB_1 | M_DP_TB_1 | M_ST_TB_1 | M_BO_TB_1 | M_ME_TD_1 | M_ME_TE_1 | M_ME_TF_1
            | M_IT_TB_1 | M_EP_TD_1 | M_EP_TE_1 | M_EP_TF_1 | C_SC_TA_1 | C_DC_TA_1 | C_RC_TA_1
            | C_SE_TA_1 | C_SE_TB_1 | C_SE_TC_1 | C_BO_TA_1 | C_TS_TA_1 | F_DR_TA_1 => {
                TimeTagKind::Cp56
            }
            _ => TimeTagKind::None,
        }
    }

    /// Process information in monitor direction (1..40) and end of initialisation (70).
    pub fn is_monitor(self) -> bool {
        matches!(self.value(), 1..=40 | 70)
    }

    /// Process information in control direction: the commands 45..64.
    pub fn is_command(self) -> bool {
        matches!(self.value(), 45..=64)
    }

    /// System information in control direction, 100..107 (interrogation, read, clock
    /// synchronisation, test, reset process, delay acquisition).
    pub fn is_system_command(self) -> bool {
        matches!(self.value(), 100..=107)
    }

    /// Parameters in control direction, 110..113.
    pub fn is_parameter(self) -> bool {
        matches!(self.value(), 110..=113)
    }

    /// File transfer, 120..127 (both directions).
    pub fn is_file_transfer(self) -> bool {
        matches!(self.value(), 120..=127)
    }

    /// Whether the standard allows SQ = 1 (one address, consecutive elements) for this
    /// type: the monitor types without time tag, and the file directory. The codec decodes
    /// SQ = 1 for any fixed-size type, as established stacks do; this is what a sender
    /// should restrict itself to.
    pub fn allows_sequence(self) -> bool {
        matches!(
            self,
            M_SP_NA_1
                | M_DP_NA_1
                | M_ST_NA_1
                | M_BO_NA_1
                | M_ME_NA_1
                | M_ME_NB_1
                | M_ME_NC_1
                | M_IT_NA_1
                | M_PS_NA_1
                | M_ME_ND_1
                | F_DR_TA_1
        )
    }

    /// Octets of one element including its time tag, without the IOA; `None` for
    /// F_SG_NA_1, whose segment length is carried in the element.
    pub fn element_len(self) -> Option<usize> {
        let base = match self {
            M_SP_NA_1 | M_SP_TA_1 | M_SP_TB_1 | M_DP_NA_1 | M_DP_TA_1 | M_DP_TB_1 => 1,
            M_ST_NA_1 | M_ST_TA_1 | M_ST_TB_1 => 2,
            M_BO_NA_1 | M_BO_TA_1 | M_BO_TB_1 => 5,
            M_ME_NA_1 | M_ME_TA_1 | M_ME_TD_1 | M_ME_NB_1 | M_ME_TB_1 | M_ME_TE_1 => 3,
            M_ME_NC_1 | M_ME_TC_1 | M_ME_TF_1 => 5,
            M_IT_NA_1 | M_IT_TA_1 | M_IT_TB_1 => 5,
            M_EP_TA_1 | M_EP_TD_1 => 3,
            M_EP_TB_1 | M_EP_TE_1 | M_EP_TC_1 | M_EP_TF_1 => 4,
            M_PS_NA_1 => 5,
            M_ME_ND_1 => 2,
            C_SC_NA_1 | C_SC_TA_1 | C_DC_NA_1 | C_DC_TA_1 | C_RC_NA_1 | C_RC_TA_1 => 1,
            C_SE_NA_1 | C_SE_TA_1 | C_SE_NB_1 | C_SE_TB_1 => 3,
            C_SE_NC_1 | C_SE_TC_1 => 5,
            C_BO_NA_1 | C_BO_TA_1 => 4,
            M_EI_NA_1 | C_IC_NA_1 | C_CI_NA_1 | C_RP_NA_1 | P_AC_NA_1 => 1,
            C_RD_NA_1 => 0,
            C_CS_NA_1 => 7,
            C_TS_NA_1 | C_CD_NA_1 | C_TS_TA_1 => 2,
            P_ME_NA_1 | P_ME_NB_1 => 3,
            P_ME_NC_1 => 5,
            F_FR_NA_1 => 6,
            F_SR_NA_1 => 7,
            F_SC_NA_1 | F_AF_NA_1 => 4,
            F_LS_NA_1 => 5,
            F_SG_NA_1 => return None,
            F_DR_TA_1 => 6,
            F_SC_NB_1 => 16,
        };
        Some(base + self.time_tag().len())
    }

    /// The counterpart without time tag (M_SP_TB_1 -> M_SP_NA_1, C_SC_TA_1 -> C_SC_NA_1),
    /// as a general interrogation must answer with untagged types. A type without time tag
    /// returns itself; types that exist only with a time tag (protection events, C_TS_TA_1,
    /// F_DR_TA_1) return `None`.
    pub fn without_time(self) -> Option<TypeId> {
        Some(match self {
            M_SP_TA_1 | M_SP_TB_1 => M_SP_NA_1,
            M_DP_TA_1 | M_DP_TB_1 => M_DP_NA_1,
            M_ST_TA_1 | M_ST_TB_1 => M_ST_NA_1,
            M_BO_TA_1 | M_BO_TB_1 => M_BO_NA_1,
            M_ME_TA_1 | M_ME_TD_1 => M_ME_NA_1,
            M_ME_TB_1 | M_ME_TE_1 => M_ME_NB_1,
            M_ME_TC_1 | M_ME_TF_1 => M_ME_NC_1,
            M_IT_TA_1 | M_IT_TB_1 => M_IT_NA_1,
            C_SC_TA_1 => C_SC_NA_1,
            C_DC_TA_1 => C_DC_NA_1,
            C_RC_TA_1 => C_RC_NA_1,
            C_SE_TA_1 => C_SE_NA_1,
            C_SE_TB_1 => C_SE_NB_1,
            C_SE_TC_1 => C_SE_NC_1,
            C_BO_TA_1 => C_BO_NA_1,
            other if other.time_tag() == TimeTagKind::None => other,
            _ => return None,
        })
    }

    /// The counterpart with CP56Time2a (M_SP_NA_1 and M_SP_TA_1 -> M_SP_TB_1, M_ME_ND_1 ->
    /// M_ME_TD_1, M_EP_TA_1 -> M_EP_TD_1, C_SC_NA_1 -> C_SC_TA_1). A CP56 type returns
    /// itself; types without a tagged counterpart return `None`.
    pub fn with_cp56(self) -> Option<TypeId> {
        Some(match self {
            M_SP_NA_1 | M_SP_TA_1 => M_SP_TB_1,
            M_DP_NA_1 | M_DP_TA_1 => M_DP_TB_1,
            M_ST_NA_1 | M_ST_TA_1 => M_ST_TB_1,
            M_BO_NA_1 | M_BO_TA_1 => M_BO_TB_1,
            M_ME_NA_1 | M_ME_TA_1 | M_ME_ND_1 => M_ME_TD_1,
            M_ME_NB_1 | M_ME_TB_1 => M_ME_TE_1,
            M_ME_NC_1 | M_ME_TC_1 => M_ME_TF_1,
            M_IT_NA_1 | M_IT_TA_1 => M_IT_TB_1,
            M_EP_TA_1 => M_EP_TD_1,
            M_EP_TB_1 => M_EP_TE_1,
            M_EP_TC_1 => M_EP_TF_1,
            C_SC_NA_1 => C_SC_TA_1,
            C_DC_NA_1 => C_DC_TA_1,
            C_RC_NA_1 => C_RC_TA_1,
            C_SE_NA_1 => C_SE_TA_1,
            C_SE_NB_1 => C_SE_TB_1,
            C_SE_NC_1 => C_SE_TC_1,
            C_BO_NA_1 => C_BO_TA_1,
            other if other.time_tag() == TimeTagKind::Cp56 => other,
            _ => return None,
        })
    }
}

impl TryFrom<u8> for TypeId {
    type Error = u8;

    /// Fails with the number itself when the standard does not define it.
    fn try_from(value: u8) -> Result<Self, u8> {
        Self::from_u8(value).ok_or(value)
    }
}

impl From<TypeId> for u8 {
    fn from(type_id: TypeId) -> u8 {
        type_id as u8
    }
}

impl FromStr for TypeId {
    type Err = ParseTypeIdError;

    /// Parses a mnemonic such as `"C_SC_NA_1"` (case-insensitive).
    fn from_str(text: &str) -> Result<Self, ParseTypeIdError> {
        Self::ALL
            .iter()
            .copied()
            .find(|t| t.mnemonic().eq_ignore_ascii_case(text.trim()))
            .ok_or_else(|| ParseTypeIdError(text.to_owned()))
    }
}

impl fmt::Display for TypeId {
    /// The mnemonic.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.mnemonic())
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]
mod tests {
    use super::*;

    #[test]
    fn numbers_and_mnemonics_round_trip() {
        assert_eq!(TypeId::ALL.len(), 67);
        assert!(TypeId::ALL.windows(2).all(|w| w[0] < w[1]));
        for &t in TypeId::ALL {
            assert_eq!(TypeId::from_u8(t.value()), Some(t));
            assert_eq!(t.mnemonic().parse::<TypeId>().unwrap(), t);
            assert_eq!(t.to_string(), t.mnemonic());
            assert!(!t.description().is_empty());
        }
        let defined = (0..=255u8)
            .filter(|n| TypeId::from_u8(*n).is_some())
            .count();
        assert_eq!(defined, 67);
        assert_eq!(TypeId::try_from(22), Err(22));
        assert!("X_YZ_NA_1".parse::<TypeId>().is_err());
    }

    #[test]
    fn time_counterparts_are_consistent() {
        for &t in TypeId::ALL {
            if let Some(untagged) = t.without_time() {
                assert_eq!(untagged.time_tag(), TimeTagKind::None, "{t}");
            }
            if let Some(tagged) = t.with_cp56() {
                assert_eq!(tagged.time_tag(), TimeTagKind::Cp56, "{t}");
                // M_ME_ND_1 shares M_ME_TD_1 with M_ME_NA_1, whose counterpart it is.
                if t.time_tag() == TimeTagKind::None && t != M_ME_ND_1 {
                    assert_eq!(tagged.without_time(), Some(t), "{t}");
                }
            }
        }
        assert_eq!(M_DP_TB_1.without_time(), Some(M_DP_NA_1));
        assert_eq!(M_EP_TD_1.without_time(), None);
    }

    #[test]
    fn directions() {
        assert!(M_DP_TB_1.is_monitor() && !M_DP_TB_1.is_command());
        assert!(C_BO_TA_1.is_command() && !C_IC_NA_1.is_command());
        assert!(C_IC_NA_1.is_system_command() && M_EI_NA_1.is_monitor());
    }
}
