//! Information elements and qualifiers (IEC 60870-5-101 §7.2.6), with their bit layouts.
//!
//! Value-carrying elements are small structs: those whose every bit pattern is valid have
//! public fields, those with a narrower range (step position, counter sequence number,
//! command qualifiers) have private fields and validated constructors. Pure qualifiers that
//! the [`super::Element`] carries as raw `u8` get named constants here.

use std::fmt;

use super::RangeError;

/// Bit 7 of every quality octet: IV, invalid.
const IV: u8 = 0x80;
/// Bit 6: NT, not topical.
const NT: u8 = 0x40;
/// Bit 5: SB, substituted.
const SB: u8 = 0x20;
/// Bit 4: BL, blocked.
const BL: u8 = 0x10;
/// Bit 0 of QDS: OV, overflow.
const OV: u8 = 0x01;

fn bit(set: bool, mask: u8) -> u8 {
    if set {
        mask
    } else {
        0
    }
}

/// Writes `name` in upper case when set, in lower case when clear, as test tools do.
fn write_flag(f: &mut fmt::Formatter<'_>, set: bool, name: &str) -> fmt::Result {
    if set {
        f.write_str(&name.to_ascii_uppercase())
    } else {
        f.write_str(name)
    }
}

/// Quality descriptor: IV, NT, SB, BL (all point types) and OV (measured values, QDS).
///
/// The point model's type: values cross between the protocol and the station's points
/// without conversion. SIQ and DIQ have no OV bit (bit 0 holds the value there):
/// `overflow` is not sent with single and double points and decodes as `false`.
pub use points::Quality;

/// How the quality flags sit in the protocol's octets (SIQ, DIQ, QDS, SEP, QDP).
pub trait QualityOctets {
    /// Decodes a QDS octet (bits 1-3 are reserved and ignored).
    fn from_qds(octet: u8) -> Quality;
    /// The QDS octet.
    fn to_qds(&self) -> u8;
    /// Decodes bits 4-7 (BL, SB, NT, IV) shared by SIQ, DIQ, QDS, SEP and QDP.
    fn from_status_bits(octet: u8) -> Quality;
    /// Bits 4-7 (BL, SB, NT, IV); OV is left out.
    fn status_bits(&self) -> u8;
}

impl QualityOctets for Quality {
    fn from_qds(octet: u8) -> Quality {
        Quality {
            overflow: octet & OV != 0,
            ..Self::from_status_bits(octet)
        }
    }

    fn to_qds(&self) -> u8 {
        self.status_bits() | bit(self.overflow, OV)
    }

    fn from_status_bits(octet: u8) -> Quality {
        Quality {
            invalid: octet & IV != 0,
            not_topical: octet & NT != 0,
            substituted: octet & SB != 0,
            blocked: octet & BL != 0,
            overflow: false,
        }
    }

    fn status_bits(&self) -> u8 {
        bit(self.invalid, IV)
            | bit(self.not_topical, NT)
            | bit(self.substituted, SB)
            | bit(self.blocked, BL)
    }
}

/// Double-point state (DPI of DIQ, DCS of DCO, ES of SEP): two bits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum DoublePointState {
    /// 0: intermediate (in motion) or, in a command, not permitted.
    Intermediate = 0,
    /// 1: determined OFF.
    Off = 1,
    /// 2: determined ON.
    On = 2,
    /// 3: indeterminate (faulty) or, in a command, not permitted.
    Indeterminate = 3,
}

impl DoublePointState {
    /// From the two low bits of an octet.
    pub fn from_bits(octet: u8) -> DoublePointState {
        match octet & 0x03 {
            0 => DoublePointState::Intermediate,
            1 => DoublePointState::Off,
            2 => DoublePointState::On,
            _ => DoublePointState::Indeterminate,
        }
    }

    /// The two bits.
    pub fn bits(self) -> u8 {
        self as u8
    }

    /// The state for a boolean: `true` is ON.
    pub fn from_on(on: bool) -> DoublePointState {
        if on {
            DoublePointState::On
        } else {
            DoublePointState::Off
        }
    }

    /// `Some(true)` for ON, `Some(false)` for OFF, `None` for the two undetermined states.
    pub fn as_on(self) -> Option<bool> {
        match self {
            DoublePointState::On => Some(true),
            DoublePointState::Off => Some(false),
            _ => None,
        }
    }
}

impl fmt::Display for DoublePointState {
    /// `OFF`, `ON`, `INTERMEDIATE`, `INDETERMINATE`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            DoublePointState::Intermediate => "INTERMEDIATE",
            DoublePointState::Off => "OFF",
            DoublePointState::On => "ON",
            DoublePointState::Indeterminate => "INDETERMINATE",
        })
    }
}

/// Value with transient state indication (VTI): a step position -64..63 and whether the
/// equipment is in transient state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct StepPosition {
    value: i8,
    transient: bool,
}

impl StepPosition {
    /// A position -64..63.
    pub fn new(value: i8, transient: bool) -> Result<StepPosition, RangeError> {
        if (-64..=63).contains(&value) {
            Ok(StepPosition { value, transient })
        } else {
            Err(RangeError::new("step position", value.into(), -64, 63))
        }
    }

    /// The position -64..63.
    pub fn value(&self) -> i8 {
        self.value
    }

    /// Whether the equipment is in transient state (bit 7).
    pub fn is_transient(&self) -> bool {
        self.transient
    }

    /// Decodes a VTI octet: bits 0-6 a two's complement value, bit 7 transient.
    pub fn from_vti(octet: u8) -> StepPosition {
        // Shift the 7-bit value to the top and back to sign-extend bit 6.
        let value = i8::from_le_bytes([octet << 1]) >> 1;
        StepPosition {
            value,
            transient: octet & 0x80 != 0,
        }
    }

    /// The VTI octet.
    pub fn to_vti(&self) -> u8 {
        let [low] = self.value.to_le_bytes();
        (low & 0x7F) | bit(self.transient, 0x80)
    }
}

impl fmt::Display for StepPosition {
    /// `-3` or `12 transient`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.value)?;
        if self.transient {
            f.write_str(" transient")?;
        }
        Ok(())
    }
}

/// Binary counter reading (BCR): a signed 32-bit count, a sequence number 0..31 and the
/// flags CY (carry), CA (counter adjusted) and IV (invalid).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct BinaryCounterReading {
    value: i32,
    sequence: u8,
    carry: bool,
    adjusted: bool,
    invalid: bool,
}

impl BinaryCounterReading {
    /// Octets on the wire.
    pub const LEN: usize = 5;

    /// A reading with sequence number 0..31 and all flags clear.
    pub fn new(value: i32, sequence: u8) -> Result<BinaryCounterReading, RangeError> {
        if sequence > 31 {
            return Err(RangeError::new(
                "counter sequence number",
                sequence.into(),
                0,
                31,
            ));
        }
        Ok(BinaryCounterReading {
            value,
            sequence,
            carry: false,
            adjusted: false,
            invalid: false,
        })
    }

    /// Sets or clears CY (the counter overflowed in the period).
    #[must_use]
    pub fn with_carry(mut self, carry: bool) -> Self {
        self.carry = carry;
        self
    }

    /// Sets or clears CA (the counter was adjusted in the period).
    #[must_use]
    pub fn with_adjusted(mut self, adjusted: bool) -> Self {
        self.adjusted = adjusted;
        self
    }

    /// Sets or clears IV (the reading is invalid).
    #[must_use]
    pub fn with_invalid(mut self, invalid: bool) -> Self {
        self.invalid = invalid;
        self
    }

    /// The count.
    pub fn value(&self) -> i32 {
        self.value
    }

    /// Sequence number 0..31.
    pub fn sequence(&self) -> u8 {
        self.sequence
    }

    /// CY, carry.
    pub fn is_carry(&self) -> bool {
        self.carry
    }

    /// CA, counter adjusted.
    pub fn is_adjusted(&self) -> bool {
        self.adjusted
    }

    /// IV, invalid.
    pub fn is_invalid(&self) -> bool {
        self.invalid
    }

    /// Decodes the five octets: count little endian, then SQ bits 0-4, CY 5, CA 6, IV 7.
    pub fn from_bytes(bytes: [u8; 5]) -> BinaryCounterReading {
        let [a, b, c, d, flags] = bytes;
        BinaryCounterReading {
            value: i32::from_le_bytes([a, b, c, d]),
            sequence: flags & 0x1F,
            carry: flags & 0x20 != 0,
            adjusted: flags & 0x40 != 0,
            invalid: flags & 0x80 != 0,
        }
    }

    /// The five octets.
    pub fn to_bytes(&self) -> [u8; 5] {
        let [a, b, c, d] = self.value.to_le_bytes();
        let flags = self.sequence
            | bit(self.carry, 0x20)
            | bit(self.adjusted, 0x40)
            | bit(self.invalid, 0x80);
        [a, b, c, d, flags]
    }
}

impl fmt::Display for BinaryCounterReading {
    /// `12345 sq=3 [cy ca iv]`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} sq={} [", self.value, self.sequence)?;
        write_flag(f, self.carry, "cy")?;
        f.write_str(" ")?;
        write_flag(f, self.adjusted, "ca")?;
        f.write_str(" ")?;
        write_flag(f, self.invalid, "iv")?;
        f.write_str("]")
    }
}

/// Quality descriptor of protection events (QDP, and bits 3-7 of SEP): EI plus the four
/// status flags.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ProtectionQuality {
    /// EI: the elapsed (or relay) time is invalid.
    pub elapsed_invalid: bool,
    /// BL, SB, NT, IV as in [`Quality`] (`overflow` is not used and decodes `false`).
    pub quality: Quality,
}

impl ProtectionQuality {
    /// Decodes bits 3-7 of a QDP or SEP octet.
    pub fn from_bits(octet: u8) -> ProtectionQuality {
        ProtectionQuality {
            elapsed_invalid: octet & 0x08 != 0,
            quality: Quality::from_status_bits(octet),
        }
    }

    /// Bits 3-7.
    pub fn bits(&self) -> u8 {
        bit(self.elapsed_invalid, 0x08) | self.quality.status_bits()
    }
}

impl fmt::Display for ProtectionQuality {
    /// `[ei iv nt sb bl]`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("[")?;
        write_flag(f, self.elapsed_invalid, "ei")?;
        f.write_str(" ")?;
        write_flag(f, self.quality.invalid, "iv")?;
        f.write_str(" ")?;
        write_flag(f, self.quality.not_topical, "nt")?;
        f.write_str(" ")?;
        write_flag(f, self.quality.substituted, "sb")?;
        f.write_str(" ")?;
        write_flag(f, self.quality.blocked, "bl")?;
        f.write_str("]")
    }
}

/// Displays a quality without OV, for SIQ/DIQ-style elements.
pub(crate) struct QualityNoOverflow(pub(crate) Quality);

impl fmt::Display for QualityNoOverflow {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.write_flags(f, false)
    }
}

/// Start events of protection equipment (SPE).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct StartEvents {
    /// GS: general start of operation.
    pub general: bool,
    /// SL1: start of operation phase L1.
    pub l1: bool,
    /// SL2: start of operation phase L2.
    pub l2: bool,
    /// SL3: start of operation phase L3.
    pub l3: bool,
    /// SIE: start of operation IE (earth current).
    pub earth: bool,
    /// SRD: start of operation in reverse direction.
    pub reverse: bool,
}

impl StartEvents {
    /// Decodes an SPE octet (bits 6-7 reserved).
    pub fn from_bits(octet: u8) -> StartEvents {
        StartEvents {
            general: octet & 0x01 != 0,
            l1: octet & 0x02 != 0,
            l2: octet & 0x04 != 0,
            l3: octet & 0x08 != 0,
            earth: octet & 0x10 != 0,
            reverse: octet & 0x20 != 0,
        }
    }

    /// The SPE octet.
    pub fn bits(&self) -> u8 {
        bit(self.general, 0x01)
            | bit(self.l1, 0x02)
            | bit(self.l2, 0x04)
            | bit(self.l3, 0x08)
            | bit(self.earth, 0x10)
            | bit(self.reverse, 0x20)
    }
}

impl fmt::Display for StartEvents {
    /// `[gs sl1 sl2 sl3 sie srd]`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("[")?;
        let flags = [
            (self.general, "gs"),
            (self.l1, "sl1"),
            (self.l2, "sl2"),
            (self.l3, "sl3"),
            (self.earth, "sie"),
            (self.reverse, "srd"),
        ];
        for (index, (set, name)) in flags.into_iter().enumerate() {
            if index > 0 {
                f.write_str(" ")?;
            }
            write_flag(f, set, name)?;
        }
        f.write_str("]")
    }
}

/// Output circuit information of protection equipment (OCI).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct OutputCircuits {
    /// GC: general command to output circuit.
    pub general: bool,
    /// CL1: command to output circuit phase L1.
    pub l1: bool,
    /// CL2: command to output circuit phase L2.
    pub l2: bool,
    /// CL3: command to output circuit phase L3.
    pub l3: bool,
}

impl OutputCircuits {
    /// Decodes an OCI octet (bits 4-7 reserved).
    pub fn from_bits(octet: u8) -> OutputCircuits {
        OutputCircuits {
            general: octet & 0x01 != 0,
            l1: octet & 0x02 != 0,
            l2: octet & 0x04 != 0,
            l3: octet & 0x08 != 0,
        }
    }

    /// The OCI octet.
    pub fn bits(&self) -> u8 {
        bit(self.general, 0x01) | bit(self.l1, 0x02) | bit(self.l2, 0x04) | bit(self.l3, 0x08)
    }
}

impl fmt::Display for OutputCircuits {
    /// `[gc cl1 cl2 cl3]`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("[")?;
        write_flag(f, self.general, "gc")?;
        f.write_str(" ")?;
        write_flag(f, self.l1, "cl1")?;
        f.write_str(" ")?;
        write_flag(f, self.l2, "cl2")?;
        f.write_str(" ")?;
        write_flag(f, self.l3, "cl3")?;
        f.write_str("]")
    }
}

/// Qualifier of command (QOC) of SCO, DCO and RCO: QU 0..31 in bits 2-6 and S/E in bit 7.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct CommandQualifier {
    qualifier: u8,
    select: bool,
}

impl CommandQualifier {
    /// Execute, no additional definition (QU 0).
    pub const EXECUTE: CommandQualifier = CommandQualifier {
        qualifier: 0,
        select: false,
    };
    /// Select, no additional definition (QU 0).
    pub const SELECT: CommandQualifier = CommandQualifier {
        qualifier: 0,
        select: true,
    };
    /// QU 0: no additional definition.
    pub const QU_NONE: u8 = 0;
    /// QU 1: short pulse duration.
    pub const QU_SHORT_PULSE: u8 = 1;
    /// QU 2: long pulse duration.
    pub const QU_LONG_PULSE: u8 = 2;
    /// QU 3: persistent output.
    pub const QU_PERSISTENT: u8 = 3;

    /// A qualifier with QU 0..31 and S/E (`true` = select).
    pub fn new(qualifier: u8, select: bool) -> Result<CommandQualifier, RangeError> {
        if qualifier > 31 {
            return Err(RangeError::new(
                "command qualifier QU",
                qualifier.into(),
                0,
                31,
            ));
        }
        Ok(CommandQualifier { qualifier, select })
    }

    /// QU 0..31.
    pub fn qualifier(&self) -> u8 {
        self.qualifier
    }

    /// S/E: `true` = select, `false` = execute.
    pub fn is_select(&self) -> bool {
        self.select
    }

    /// From the QU and S/E bits of a command octet (the state bits are ignored).
    pub fn from_bits(octet: u8) -> CommandQualifier {
        CommandQualifier {
            qualifier: (octet >> 2) & 0x1F,
            select: octet & 0x80 != 0,
        }
    }

    /// Bits 2-7 of the command octet.
    pub fn bits(&self) -> u8 {
        (self.qualifier << 2) | bit(self.select, 0x80)
    }
}

impl fmt::Display for CommandQualifier {
    /// `execute qu=0` or `select qu=1`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let action = if self.select { "select" } else { "execute" };
        write!(f, "{action} qu={}", self.qualifier)
    }
}

/// Qualifier of set-point command (QOS): QL 0..127 in bits 0-6 and S/E in bit 7.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct SetpointQualifier {
    qualifier: u8,
    select: bool,
}

impl SetpointQualifier {
    /// Execute, QL 0 (default).
    pub const EXECUTE: SetpointQualifier = SetpointQualifier {
        qualifier: 0,
        select: false,
    };
    /// Select, QL 0 (default).
    pub const SELECT: SetpointQualifier = SetpointQualifier {
        qualifier: 0,
        select: true,
    };

    /// A qualifier with QL 0..127 and S/E (`true` = select).
    pub fn new(qualifier: u8, select: bool) -> Result<SetpointQualifier, RangeError> {
        if qualifier > 127 {
            return Err(RangeError::new(
                "set-point qualifier QL",
                qualifier.into(),
                0,
                127,
            ));
        }
        Ok(SetpointQualifier { qualifier, select })
    }

    /// QL 0..127.
    pub fn qualifier(&self) -> u8 {
        self.qualifier
    }

    /// S/E: `true` = select, `false` = execute.
    pub fn is_select(&self) -> bool {
        self.select
    }

    /// Decodes a QOS octet.
    pub fn from_bits(octet: u8) -> SetpointQualifier {
        SetpointQualifier {
            qualifier: octet & 0x7F,
            select: octet & 0x80 != 0,
        }
    }

    /// The QOS octet.
    pub fn bits(&self) -> u8 {
        self.qualifier | bit(self.select, 0x80)
    }
}

impl fmt::Display for SetpointQualifier {
    /// `execute ql=0` or `select ql=0`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let action = if self.select { "select" } else { "execute" };
        write!(f, "{action} ql={}", self.qualifier)
    }
}

/// Regulating step command state (RCS of RCO). 0 and 3 are not permitted but still
/// decode, so that the receiving station can refuse them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum RegulatingStepState {
    /// 0: not permitted.
    Reserved0 = 0,
    /// 1: next step lower.
    Lower = 1,
    /// 2: next step higher.
    Higher = 2,
    /// 3: not permitted.
    Reserved3 = 3,
}

impl RegulatingStepState {
    /// From the two low bits of an octet.
    pub fn from_bits(octet: u8) -> RegulatingStepState {
        match octet & 0x03 {
            0 => RegulatingStepState::Reserved0,
            1 => RegulatingStepState::Lower,
            2 => RegulatingStepState::Higher,
            _ => RegulatingStepState::Reserved3,
        }
    }

    /// The two bits.
    pub fn bits(self) -> u8 {
        self as u8
    }
}

impl fmt::Display for RegulatingStepState {
    /// `LOWER`, `HIGHER`, `NOT PERMITTED(0)`, `NOT PERMITTED(3)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            RegulatingStepState::Reserved0 => "NOT PERMITTED(0)",
            RegulatingStepState::Lower => "LOWER",
            RegulatingStepState::Higher => "HIGHER",
            RegulatingStepState::Reserved3 => "NOT PERMITTED(3)",
        })
    }
}

/// Qualifier of interrogation (QOI) of C_IC_NA_1, carried as a raw `u8` in
/// [`super::Element::Interrogation`]: 20 station interrogation, 21..36 groups 1..16.
pub struct InterrogationQualifier;

impl InterrogationQualifier {
    /// 20: station (general) interrogation.
    pub const STATION: u8 = 20;

    /// The QOI of group 1..16 (21..36).
    pub fn group(group: u8) -> Option<u8> {
        (1..=16).contains(&group).then(|| 20 + group)
    }

    /// The group 1..16 a QOI asks for, `None` for station interrogation and unknown values.
    pub fn group_of(qualifier: u8) -> Option<u8> {
        (21..=36).contains(&qualifier).then(|| qualifier - 20)
    }

    /// Whether the QOI is one the standard defines (20..36).
    pub fn is_defined(qualifier: u8) -> bool {
        (20..=36).contains(&qualifier)
    }
}

/// Qualifier of counter interrogation (QCC) of C_CI_NA_1, carried as
/// [`super::Element::CounterInterrogation`] `{ request, freeze }`: RQT in bits 0-5,
/// FRZ in bits 6-7.
pub struct CounterInterrogationQualifier;

impl CounterInterrogationQualifier {
    /// RQT 0: no counter requested.
    pub const REQUEST_NONE: u8 = 0;
    /// RQT 5: general counter request (RQT 1..4 request counter groups 1..4).
    pub const REQUEST_GENERAL: u8 = 5;
    /// FRZ 0: read only (no freeze or reset).
    pub const FREEZE_READ: u8 = 0;
    /// FRZ 1: counter freeze without reset.
    pub const FREEZE: u8 = 1;
    /// FRZ 2: counter freeze with reset.
    pub const FREEZE_AND_RESET: u8 = 2;
    /// FRZ 3: counter reset.
    pub const RESET: u8 = 3;

    /// Splits a QCC octet into `(request, freeze)`.
    pub fn split(octet: u8) -> (u8, u8) {
        (octet & 0x3F, octet >> 6)
    }

    /// Joins RQT 0..63 and FRZ 0..3 into a QCC octet.
    pub fn join(request: u8, freeze: u8) -> Result<u8, RangeError> {
        if request > 63 {
            return Err(RangeError::new(
                "counter request RQT",
                request.into(),
                0,
                63,
            ));
        }
        if freeze > 3 {
            return Err(RangeError::new("counter freeze FRZ", freeze.into(), 0, 3));
        }
        Ok(request | (freeze << 6))
    }
}

/// Qualifier of reset process (QRP) of C_RP_NA_1, carried as a raw `u8`.
pub struct ResetProcessQualifier;

impl ResetProcessQualifier {
    /// 1: general reset of process.
    pub const GENERAL: u8 = 1;
    /// 2: reset of pending information with time tag of the event buffer.
    pub const EVENT_BUFFER: u8 = 2;
}

/// Cause of initialisation (COI) of M_EI_NA_1, carried as
/// [`super::Element::EndOfInitialisation`] `{ cause, after_parameter_change }`: cause in
/// bits 0-6, bit 7 set when initialised after a change of local parameters.
pub struct InitialisationCause;

impl InitialisationCause {
    /// 0: local power switched on.
    pub const LOCAL_POWER_ON: u8 = 0;
    /// 1: local manual reset.
    pub const LOCAL_MANUAL_RESET: u8 = 1;
    /// 2: remote reset.
    pub const REMOTE_RESET: u8 = 2;
}

/// Qualifier of parameter of measured values (QPM) of P_ME_NA_1/NB_1/NC_1, carried as a
/// raw `u8` in the element; this struct splits it into KPA (bits 0-5), LPC (bit 6) and
/// POP (bit 7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ParameterQualifier {
    kind: u8,
    /// LPC: local parameter change.
    pub local_change: bool,
    /// POP: parameter not in operation.
    pub not_in_operation: bool,
}

impl ParameterQualifier {
    /// KPA 1: threshold value.
    pub const THRESHOLD: u8 = 1;
    /// KPA 2: smoothing factor (filter time constant).
    pub const SMOOTHING: u8 = 2;
    /// KPA 3: low limit for transmission of measured values.
    pub const LOW_LIMIT: u8 = 3;
    /// KPA 4: high limit for transmission of measured values.
    pub const HIGH_LIMIT: u8 = 4;

    /// A qualifier of kind KPA 0..63 with LPC and POP clear.
    pub fn new(kind: u8) -> Result<ParameterQualifier, RangeError> {
        if kind > 63 {
            return Err(RangeError::new("parameter kind KPA", kind.into(), 0, 63));
        }
        Ok(ParameterQualifier {
            kind,
            local_change: false,
            not_in_operation: false,
        })
    }

    /// KPA 0..63.
    pub fn kind(&self) -> u8 {
        self.kind
    }

    /// Decodes a QPM octet.
    pub fn from_bits(octet: u8) -> ParameterQualifier {
        ParameterQualifier {
            kind: octet & 0x3F,
            local_change: octet & 0x40 != 0,
            not_in_operation: octet & 0x80 != 0,
        }
    }

    /// The QPM octet.
    pub fn bits(&self) -> u8 {
        self.kind | bit(self.local_change, 0x40) | bit(self.not_in_operation, 0x80)
    }
}

/// Qualifier of parameter activation (QPA) of P_AC_NA_1, carried as a raw `u8`.
pub struct ParameterActivationQualifier;

impl ParameterActivationQualifier {
    /// 1: act/deact of the previously loaded parameters (IOA 0).
    pub const LOADED_PARAMETERS: u8 = 1;
    /// 2: act/deact of the parameter of the addressed object.
    pub const OBJECT_PARAMETER: u8 = 2;
    /// 3: act/deact of persistent cyclic or periodic transmission of the addressed object.
    pub const CYCLIC_TRANSMISSION: u8 = 3;
}

/// File-transfer qualifiers, carried as raw `u8` in the file elements of
/// [`super::Element`].
///
/// - FRQ (file ready) and SRQ (section ready): bits 0-6 a value (0 = default), bit 7
///   negative confirmation (FRQ) or "not ready" (SRQ): see [`FileQualifier::NEGATIVE`].
/// - SCQ (select and call) and AFQ (acknowledge): bits 0-3 the action, bits 4-7 the error.
/// - LSQ (last section/segment): a value 1..4.
/// - SOF (status of file): bits 0-4 status, bit 5 LFD last file of the directory, bit 6
///   FOR name defines a subdirectory, bit 7 FA file transfer active.
pub struct FileQualifier;

impl FileQualifier {
    /// Bit 7 of FRQ/SRQ: negative confirmation / section not ready.
    pub const NEGATIVE: u8 = 0x80;
    /// SCQ action 1: select file.
    pub const SELECT_FILE: u8 = 1;
    /// SCQ action 2: request file.
    pub const REQUEST_FILE: u8 = 2;
    /// SCQ action 3: deactivate file.
    pub const DEACTIVATE_FILE: u8 = 3;
    /// SCQ action 4: delete file.
    pub const DELETE_FILE: u8 = 4;
    /// SCQ action 5: select section.
    pub const SELECT_SECTION: u8 = 5;
    /// SCQ action 6: request section.
    pub const REQUEST_SECTION: u8 = 6;
    /// SCQ action 7: deactivate section.
    pub const DEACTIVATE_SECTION: u8 = 7;
    /// LSQ 1: file transfer without deactivation.
    pub const FILE_TRANSFER_DONE: u8 = 1;
    /// LSQ 2: file transfer with deactivation.
    pub const FILE_TRANSFER_ABORTED: u8 = 2;
    /// LSQ 3: section transfer without deactivation.
    pub const SECTION_TRANSFER_DONE: u8 = 3;
    /// LSQ 4: section transfer with deactivation.
    pub const SECTION_TRANSFER_ABORTED: u8 = 4;
    /// AFQ 1: positive acknowledge of file transfer.
    pub const ACK_FILE: u8 = 1;
    /// AFQ 2: negative acknowledge of file transfer.
    pub const NACK_FILE: u8 = 2;
    /// AFQ 3: positive acknowledge of section transfer.
    pub const ACK_SECTION: u8 = 3;
    /// AFQ 4: negative acknowledge of section transfer.
    pub const NACK_SECTION: u8 = 4;
    /// SOF bit 5: last file of the directory.
    pub const LAST_FILE: u8 = 0x20;
    /// SOF bit 6: the name defines a subdirectory.
    pub const SUBDIRECTORY: u8 = 0x40;
    /// SOF bit 7: file transfer is active.
    pub const TRANSFER_ACTIVE: u8 = 0x80;

    /// The action (bits 0-3) of an SCQ or AFQ octet.
    pub fn action(octet: u8) -> u8 {
        octet & 0x0F
    }

    /// The error (bits 4-7) of an SCQ or AFQ octet: 0 default, 1 memory not available,
    /// 2 checksum failed, 3 unexpected communication service, 4 unexpected name of file,
    /// 5 unexpected name of section.
    pub fn error(octet: u8) -> u8 {
        octet >> 4
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]
mod tests {
    use super::*;

    #[test]
    fn quality_bits() {
        let q = Quality::from_qds(0xF1);
        assert!(q.invalid && q.not_topical && q.substituted && q.blocked && q.overflow);
        assert_eq!(q.to_qds(), 0xF1);
        assert_eq!(q.to_string(), "[IV NT SB BL OV]");
        assert_eq!(Quality::GOOD.to_string(), "[iv nt sb bl ov]");
        assert!(Quality::from_qds(0x0E).is_good()); // reserved bits ignored
        assert_eq!(Quality::from_status_bits(0x81), Quality::INVALID);
    }

    #[test]
    fn step_position_sign_extends() {
        for value in -64..=63i8 {
            for transient in [false, true] {
                let position = StepPosition::new(value, transient).unwrap();
                assert_eq!(StepPosition::from_vti(position.to_vti()), position);
            }
        }
        assert_eq!(StepPosition::from_vti(0x7F).value(), -1);
        assert_eq!(StepPosition::from_vti(0x40).value(), -64);
        assert_eq!(StepPosition::from_vti(0xBF).to_string(), "63 transient");
        assert!(StepPosition::new(64, false).is_err());
        assert!(StepPosition::new(-65, false).is_err());
    }

    #[test]
    fn counter_reading_layout() {
        let reading = BinaryCounterReading::new(-2, 31)
            .unwrap()
            .with_carry(true)
            .with_invalid(true);
        assert_eq!(reading.to_bytes(), [0xFE, 0xFF, 0xFF, 0xFF, 0xBF]);
        assert_eq!(
            BinaryCounterReading::from_bytes(reading.to_bytes()),
            reading
        );
        assert!(BinaryCounterReading::new(0, 32).is_err());
    }

    #[test]
    fn command_qualifiers() {
        let qoc = CommandQualifier::new(CommandQualifier::QU_LONG_PULSE, true).unwrap();
        assert_eq!(qoc.bits(), 0x88);
        assert_eq!(CommandQualifier::from_bits(0x88 | 0x02), qoc);
        assert!(CommandQualifier::new(32, false).is_err());
        let qos = SetpointQualifier::new(127, true).unwrap();
        assert_eq!(qos.bits(), 0xFF);
        assert!(SetpointQualifier::new(128, false).is_err());
    }

    #[test]
    fn protection_bits() {
        let q = ProtectionQuality::from_bits(0xF8);
        assert!(q.elapsed_invalid && q.quality.invalid && q.quality.blocked);
        assert_eq!(q.bits(), 0xF8);
        assert_eq!(q.to_string(), "[EI IV NT SB BL]");
        assert_eq!(StartEvents::from_bits(0x3F).bits(), 0x3F);
        assert_eq!(OutputCircuits::from_bits(0x0F).bits(), 0x0F);
    }

    #[test]
    fn counter_interrogation_qualifier() {
        assert_eq!(CounterInterrogationQualifier::join(5, 1).unwrap(), 0x45);
        assert_eq!(CounterInterrogationQualifier::split(0x45), (5, 1));
        assert!(CounterInterrogationQualifier::join(64, 0).is_err());
        assert!(CounterInterrogationQualifier::join(0, 4).is_err());
        assert_eq!(InterrogationQualifier::group(16), Some(36));
        assert_eq!(InterrogationQualifier::group_of(20), None);
    }
}
