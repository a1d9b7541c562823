//! Information objects: address, element and time tag, and the per-type element codec.

use std::fmt;

use super::element::{
    BinaryCounterReading, CommandQualifier, CounterInterrogationQualifier, DoublePointState,
    OutputCircuits, ProtectionQuality, Quality, QualityNoOverflow, QualityOctets,
    RegulatingStepState, SetpointQualifier, StartEvents, StepPosition,
};
use super::{AsduError, Ioa, RangeError, TimeTagKind, TypeId};
use crate::time::{Cp16Time2a, Cp24Time2a, Cp56Time2a};

/// The time tag that follows an element; the type identification says which one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TimeTag {
    /// CP24Time2a (types 2..19 of IEC 101).
    Cp24(Cp24Time2a),
    /// CP56Time2a (types 30..40, 58..64, 107, 126).
    Cp56(Cp56Time2a),
}

impl TimeTag {
    /// Which kind of tag this is.
    pub fn kind(&self) -> TimeTagKind {
        match self {
            TimeTag::Cp24(_) => TimeTagKind::Cp24,
            TimeTag::Cp56(_) => TimeTagKind::Cp56,
        }
    }

    /// The CP56Time2a, if this is one.
    pub fn as_cp56(&self) -> Option<&Cp56Time2a> {
        match self {
            TimeTag::Cp56(time) => Some(time),
            TimeTag::Cp24(_) => None,
        }
    }

    /// IV of either tag.
    pub fn is_invalid(&self) -> bool {
        match self {
            TimeTag::Cp24(time) => time.is_invalid(),
            TimeTag::Cp56(time) => time.is_invalid(),
        }
    }
}

impl From<Cp56Time2a> for TimeTag {
    fn from(time: Cp56Time2a) -> TimeTag {
        TimeTag::Cp56(time)
    }
}

impl From<Cp24Time2a> for TimeTag {
    fn from(time: Cp24Time2a) -> TimeTag {
        TimeTag::Cp24(time)
    }
}

impl fmt::Display for TimeTag {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TimeTag::Cp24(time) => time.fmt(f),
            TimeTag::Cp56(time) => time.fmt(f),
        }
    }
}

/// One information object: its address, its element and, for time-tagged types, its
/// time tag.
#[derive(Debug, Clone, PartialEq)]
pub struct InformationObject {
    /// Information object address.
    pub ioa: Ioa,
    /// The information element(s) of the object.
    pub element: Element,
    /// The time tag; `Some` exactly when the type's [`TypeId::time_tag`] is not `None`.
    pub time: Option<TimeTag>,
}

impl InformationObject {
    /// An object without time tag.
    pub fn new(ioa: Ioa, element: Element) -> InformationObject {
        InformationObject {
            ioa,
            element,
            time: None,
        }
    }

    /// An object with a time tag.
    pub fn with_time(ioa: Ioa, element: Element, time: impl Into<TimeTag>) -> InformationObject {
        InformationObject {
            ioa,
            element,
            time: Some(time.into()),
        }
    }
}

impl fmt::Display for InformationObject {
    /// `ioa=2000 DP OFF [iv nt sb bl] 2017-04-26 09:59:30.424 [IV]`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "ioa={} {}", self.ioa, self.element.short_name())?;
        let element = self.element.to_string();
        if !element.is_empty() {
            write!(f, " {element}")?;
        }
        if let Some(time) = &self.time {
            write!(f, " {time}")?;
        }
        Ok(())
    }
}

/// The information element of one object, one variant per element family. The type
/// identification of the ASDU decides which variant is valid and which time tag the
/// object carries (see [`Element::family_matches`]).
#[derive(Debug, Clone, PartialEq)]
pub enum Element {
    /// SIQ (types 1, 2, 30).
    SinglePoint {
        /// SPI: ON when set.
        on: bool,
        /// Quality (no OV on the wire).
        quality: Quality,
    },
    /// DIQ (types 3, 4, 31).
    DoublePoint {
        /// DPI.
        state: DoublePointState,
        /// Quality (no OV on the wire).
        quality: Quality,
    },
    /// VTI + QDS (types 5, 6, 32).
    StepPosition {
        /// The position.
        position: StepPosition,
        /// Quality.
        quality: Quality,
    },
    /// BSI + QDS (types 7, 8, 33).
    Bitstring {
        /// 32 bits, little endian on the wire.
        bits: u32,
        /// Quality.
        quality: Quality,
    },
    /// NVA + QDS (types 9, 10, 34) or NVA alone (type 21, M_ME_ND_1, which has no quality
    /// on the wire: it decodes as [`Quality::GOOD`] and the quality is not sent).
    Normalized {
        /// The raw value; the fraction is `raw / 32768`, see [`Element::normalized_value`].
        raw: i16,
        /// Quality.
        quality: Quality,
    },
    /// SVA + QDS (types 11, 12, 35).
    Scaled {
        /// The scaled value.
        value: i16,
        /// Quality.
        quality: Quality,
    },
    /// R32 + QDS (types 13, 14, 36).
    Float {
        /// IEEE 754 single precision, little endian on the wire.
        value: f32,
        /// Quality.
        quality: Quality,
    },
    /// BCR (types 15, 16, 37).
    IntegratedTotal(BinaryCounterReading),
    /// SEP + CP16Time2a elapsed time (types 17, 38).
    ProtectionEvent {
        /// ES, event state (0 and 3 indeterminate).
        state: DoublePointState,
        /// EI, BL, SB, NT, IV of the SEP octet.
        quality: ProtectionQuality,
        /// Elapsed time.
        elapsed: Cp16Time2a,
    },
    /// SPE + QDP + CP16Time2a relay duration time (types 18, 39).
    ProtectionStartEvents {
        /// Start events.
        events: StartEvents,
        /// QDP.
        quality: ProtectionQuality,
        /// Relay duration time.
        duration: Cp16Time2a,
    },
    /// OCI + QDP + CP16Time2a relay operating time (types 19, 40).
    ProtectionOutputCircuit {
        /// Output circuit information.
        circuits: OutputCircuits,
        /// QDP.
        quality: ProtectionQuality,
        /// Relay operating time.
        operating_time: Cp16Time2a,
    },
    /// SCD + QDS (type 20): 16 single points and their change flags.
    PackedSinglePoints {
        /// ST, status of the 16 points (bit n = point n).
        status: u16,
        /// CD, change detection since the last report.
        change: u16,
        /// Quality.
        quality: Quality,
    },
    /// SCO (types 45, 58).
    SingleCommand {
        /// SCS: ON when set.
        on: bool,
        /// QU and S/E.
        qualifier: CommandQualifier,
    },
    /// DCO (types 46, 59). Only ON and OFF are permitted, but 0 and 3 decode so that the
    /// receiving station can refuse them.
    DoubleCommand {
        /// DCS.
        state: DoublePointState,
        /// QU and S/E.
        qualifier: CommandQualifier,
    },
    /// RCO (types 47, 60).
    RegulatingStep {
        /// RCS.
        state: RegulatingStepState,
        /// QU and S/E.
        qualifier: CommandQualifier,
    },
    /// NVA + QOS (types 48, 61).
    SetpointNormalized {
        /// Raw normalized value.
        raw: i16,
        /// QL and S/E.
        qualifier: SetpointQualifier,
    },
    /// SVA + QOS (types 49, 62).
    SetpointScaled {
        /// Scaled value.
        value: i16,
        /// QL and S/E.
        qualifier: SetpointQualifier,
    },
    /// R32 + QOS (types 50, 63).
    SetpointFloat {
        /// Value.
        value: f32,
        /// QL and S/E.
        qualifier: SetpointQualifier,
    },
    /// BSI (types 51, 64).
    BitstringCommand {
        /// 32 bits.
        bits: u32,
    },
    /// COI (type 70).
    EndOfInitialisation {
        /// Cause 0..127, see [`super::InitialisationCause`].
        cause: u8,
        /// Bit 7: initialised after a change of local parameters.
        after_parameter_change: bool,
    },
    /// QOI (type 100), see [`super::InterrogationQualifier`].
    Interrogation {
        /// 20 station, 21..36 group 1..16.
        qualifier: u8,
    },
    /// QCC (type 101), see [`super::CounterInterrogationQualifier`].
    CounterInterrogation {
        /// RQT 0..63.
        request: u8,
        /// FRZ 0..3.
        freeze: u8,
    },
    /// Read command (type 102): no element, only the address.
    Read,
    /// Clock synchronisation (type 103): the time is the element, the object's `time`
    /// stays `None`.
    ClockSync {
        /// The time to set (or, in the confirmation, the station's time).
        time: Cp56Time2a,
    },
    /// FBP (type 104): the fixed test pattern, 0x55AA when correct.
    Test {
        /// The pattern as received.
        pattern: u16,
    },
    /// QRP (type 105), see [`super::ResetProcessQualifier`].
    ResetProcess {
        /// 1 general reset, 2 reset of the event buffer.
        qualifier: u8,
    },
    /// CP16Time2a (type 106).
    DelayAcquisition {
        /// The delay.
        delay: Cp16Time2a,
    },
    /// TSC (type 107); its CP56Time2a is the object's `time`.
    TestWithTime {
        /// Test sequence counter.
        counter: u16,
    },
    /// NVA + QPM (type 110).
    ParameterNormalized {
        /// Raw normalized value.
        raw: i16,
        /// QPM, see [`super::ParameterQualifier`].
        qualifier: u8,
    },
    /// SVA + QPM (type 111).
    ParameterScaled {
        /// Scaled value.
        value: i16,
        /// QPM, see [`super::ParameterQualifier`].
        qualifier: u8,
    },
    /// R32 + QPM (type 112).
    ParameterFloat {
        /// Value.
        value: f32,
        /// QPM, see [`super::ParameterQualifier`].
        qualifier: u8,
    },
    /// QPA (type 113), see [`super::ParameterActivationQualifier`].
    ParameterActivation {
        /// QPA.
        qualifier: u8,
    },
    /// NOF + LOF + FRQ (type 120).
    FileReady {
        /// Name of file.
        file: u16,
        /// Length of file, 0..0xFFFFFF.
        length: u32,
        /// FRQ, see [`super::FileQualifier`].
        qualifier: u8,
    },
    /// NOF + NOS + LOF + SRQ (type 121).
    SectionReady {
        /// Name of file.
        file: u16,
        /// Name of section.
        section: u8,
        /// Length of section, 0..0xFFFFFF.
        length: u32,
        /// SRQ, see [`super::FileQualifier`].
        qualifier: u8,
    },
    /// NOF + NOS + SCQ (type 122).
    CallOrSelect {
        /// Name of file.
        file: u16,
        /// Name of section.
        section: u8,
        /// SCQ, see [`super::FileQualifier`].
        qualifier: u8,
    },
    /// NOF + NOS + LSQ + CHS (type 123).
    LastSegmentOrSection {
        /// Name of file.
        file: u16,
        /// Name of section.
        section: u8,
        /// LSQ, see [`super::FileQualifier`].
        qualifier: u8,
        /// CHS, checksum (sum modulo 256 of the section or file).
        checksum: u8,
    },
    /// NOF + NOS + AFQ (type 124).
    AckFileOrSection {
        /// Name of file.
        file: u16,
        /// Name of section.
        section: u8,
        /// AFQ, see [`super::FileQualifier`].
        qualifier: u8,
    },
    /// NOF + NOS + LOS + segment (type 125), variable length.
    Segment {
        /// Name of file.
        file: u16,
        /// Name of section.
        section: u8,
        /// The segment, at most 255 octets (and what fits the ASDU).
        data: Vec<u8>,
    },
    /// NOF + LOF + SOF (type 126); the creation time is the object's `time`.
    Directory {
        /// Name of file.
        file: u16,
        /// Length of file, 0..0xFFFFFF.
        length: u32,
        /// SOF, see [`super::FileQualifier`].
        status: u8,
    },
    /// NOF + range start + range stop (type 127, query log / request archive file).
    QueryLog {
        /// Name of file.
        file: u16,
        /// Range start time.
        start: Cp56Time2a,
        /// Range stop time.
        stop: Cp56Time2a,
    },
}

/// Element families: one per [`Element`] variant, several type identifications each.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Family {
    SinglePoint,
    DoublePoint,
    StepPosition,
    Bitstring,
    Normalized,
    Scaled,
    Float,
    IntegratedTotal,
    ProtectionEvent,
    ProtectionStartEvents,
    ProtectionOutputCircuit,
    PackedSinglePoints,
    SingleCommand,
    DoubleCommand,
    RegulatingStep,
    SetpointNormalized,
    SetpointScaled,
    SetpointFloat,
    BitstringCommand,
    EndOfInitialisation,
    Interrogation,
    CounterInterrogation,
    Read,
    ClockSync,
    Test,
    ResetProcess,
    DelayAcquisition,
    TestWithTime,
    ParameterNormalized,
    ParameterScaled,
    ParameterFloat,
    ParameterActivation,
    FileReady,
    SectionReady,
    CallOrSelect,
    LastSegmentOrSection,
    AckFileOrSection,
    Segment,
    Directory,
    QueryLog,
}

fn family_of(type_id: TypeId) -> Family {
    use TypeId::*;
    match type_id {
        M_SP_NA_1 | M_SP_TA_1 | M_SP_TB_1 => Family::SinglePoint,
        M_DP_NA_1 | M_DP_TA_1 | M_DP_TB_1 => Family::DoublePoint,
        M_ST_NA_1 | M_ST_TA_1 | M_ST_TB_1 => Family::StepPosition,
        M_BO_NA_1 | M_BO_TA_1 | M_BO_TB_1 => Family::Bitstring,
        M_ME_NA_1 | M_ME_TA_1 | M_ME_TD_1 | M_ME_ND_1 => Family::Normalized,
        M_ME_NB_1 | M_ME_TB_1 | M_ME_TE_1 => Family::Scaled,
        M_ME_NC_1 | M_ME_TC_1 | M_ME_TF_1 => Family::Float,
        M_IT_NA_1 | M_IT_TA_1 | M_IT_TB_1 => Family::IntegratedTotal,
        M_EP_TA_1 | M_EP_TD_1 => Family::ProtectionEvent,
        M_EP_TB_1 | M_EP_TE_1 => Family::ProtectionStartEvents,
        M_EP_TC_1 | M_EP_TF_1 => Family::ProtectionOutputCircuit,
        M_PS_NA_1 => Family::PackedSinglePoints,
        C_SC_NA_1 | C_SC_TA_1 => Family::SingleCommand,
        C_DC_NA_1 | C_DC_TA_1 => Family::DoubleCommand,
        C_RC_NA_1 | C_RC_TA_1 => Family::RegulatingStep,
        C_SE_NA_1 | C_SE_TA_1 => Family::SetpointNormalized,
        C_SE_NB_1 | C_SE_TB_1 => Family::SetpointScaled,
        C_SE_NC_1 | C_SE_TC_1 => Family::SetpointFloat,
        C_BO_NA_1 | C_BO_TA_1 => Family::BitstringCommand,
        M_EI_NA_1 => Family::EndOfInitialisation,
        C_IC_NA_1 => Family::Interrogation,
        C_CI_NA_1 => Family::CounterInterrogation,
        C_RD_NA_1 => Family::Read,
        C_CS_NA_1 => Family::ClockSync,
        C_TS_NA_1 => Family::Test,
        C_RP_NA_1 => Family::ResetProcess,
        C_CD_NA_1 => Family::DelayAcquisition,
        C_TS_TA_1 => Family::TestWithTime,
        P_ME_NA_1 => Family::ParameterNormalized,
        P_ME_NB_1 => Family::ParameterScaled,
        P_ME_NC_1 => Family::ParameterFloat,
        P_AC_NA_1 => Family::ParameterActivation,
        F_FR_NA_1 => Family::FileReady,
        F_SR_NA_1 => Family::SectionReady,
        F_SC_NA_1 => Family::CallOrSelect,
        F_LS_NA_1 => Family::LastSegmentOrSection,
        F_AF_NA_1 => Family::AckFileOrSection,
        F_SG_NA_1 => Family::Segment,
        F_DR_TA_1 => Family::Directory,
        F_SC_NB_1 => Family::QueryLog,
    }
}

impl Element {
    /// Whether this is the select step of a select-before-operate command (S/E = 1 in
    /// the qualifier of SCO, DCO, RCO or QOS); false for every other element.
    pub fn is_select(&self) -> bool {
        match self {
            Element::SingleCommand { qualifier, .. }
            | Element::DoubleCommand { qualifier, .. }
            | Element::RegulatingStep { qualifier, .. } => qualifier.is_select(),
            Element::SetpointNormalized { qualifier, .. }
            | Element::SetpointScaled { qualifier, .. }
            | Element::SetpointFloat { qualifier, .. } => qualifier.is_select(),
            _ => false,
        }
    }

    /// The same command as an execute (S/E = 0): a select and its execute compare equal
    /// after this.
    pub fn as_execute(&self) -> Element {
        let mut element = self.clone();
        match &mut element {
            Element::SingleCommand { qualifier, .. }
            | Element::DoubleCommand { qualifier, .. }
            | Element::RegulatingStep { qualifier, .. } => {
                *qualifier = CommandQualifier::from_bits(qualifier.bits() & 0x7F);
            }
            Element::SetpointNormalized { qualifier, .. }
            | Element::SetpointScaled { qualifier, .. }
            | Element::SetpointFloat { qualifier, .. } => {
                *qualifier = SetpointQualifier::from_bits(qualifier.bits() & 0x7F);
            }
            _ => {}
        }
        element
    }

    /// The monitor value a command leaves behind once carried out, good quality: what a
    /// station returns as the command's return information on a point of the matching
    /// family (single command -> single point, set-point -> measured value, ...). `None`
    /// for a regulating step (the new position is the device's) and for what is not a
    /// command.
    pub fn commanded_value(&self) -> Option<Element> {
        let quality = Quality::GOOD;
        Some(match self {
            Element::SingleCommand { on, .. } => Element::SinglePoint { on: *on, quality },
            Element::DoubleCommand { state, .. } => Element::DoublePoint {
                state: *state,
                quality,
            },
            Element::SetpointNormalized { raw, .. } => Element::Normalized { raw: *raw, quality },
            Element::SetpointScaled { value, .. } => Element::Scaled {
                value: *value,
                quality,
            },
            Element::SetpointFloat { value, .. } => Element::Float {
                value: *value,
                quality,
            },
            Element::BitstringCommand { bits } => Element::Bitstring {
                bits: *bits,
                quality,
            },
            _ => return None,
        })
    }

    /// The fraction of a normalized value: `raw / 32768`, in -1.0 ..= 1 - 2^-15
    /// (0x2AE5 = 10981 gives 0.335114). The scale is the point model's
    /// ([`points::normalized`]), written once.
    pub fn normalized_value(raw: i16) -> f32 {
        // Exact: a 16-bit raw value over a power of two fits an f32's 24-bit mantissa.
        #[allow(clippy::cast_possible_truncation)]
        let fraction = points::normalized::from_raw(raw) as f32;
        fraction
    }

    /// The raw normalized value closest to a fraction, saturating at -1.0 and 1 - 2^-15.
    pub fn normalized_raw(fraction: f32) -> i16 {
        points::normalized::to_raw(f64::from(fraction))
    }

    fn family(&self) -> Family {
        match self {
            Element::SinglePoint { .. } => Family::SinglePoint,
            Element::DoublePoint { .. } => Family::DoublePoint,
            Element::StepPosition { .. } => Family::StepPosition,
            Element::Bitstring { .. } => Family::Bitstring,
            Element::Normalized { .. } => Family::Normalized,
            Element::Scaled { .. } => Family::Scaled,
            Element::Float { .. } => Family::Float,
            Element::IntegratedTotal(_) => Family::IntegratedTotal,
            Element::ProtectionEvent { .. } => Family::ProtectionEvent,
            Element::ProtectionStartEvents { .. } => Family::ProtectionStartEvents,
            Element::ProtectionOutputCircuit { .. } => Family::ProtectionOutputCircuit,
            Element::PackedSinglePoints { .. } => Family::PackedSinglePoints,
            Element::SingleCommand { .. } => Family::SingleCommand,
            Element::DoubleCommand { .. } => Family::DoubleCommand,
            Element::RegulatingStep { .. } => Family::RegulatingStep,
            Element::SetpointNormalized { .. } => Family::SetpointNormalized,
            Element::SetpointScaled { .. } => Family::SetpointScaled,
            Element::SetpointFloat { .. } => Family::SetpointFloat,
            Element::BitstringCommand { .. } => Family::BitstringCommand,
            Element::EndOfInitialisation { .. } => Family::EndOfInitialisation,
            Element::Interrogation { .. } => Family::Interrogation,
            Element::CounterInterrogation { .. } => Family::CounterInterrogation,
            Element::Read => Family::Read,
            Element::ClockSync { .. } => Family::ClockSync,
            Element::Test { .. } => Family::Test,
            Element::ResetProcess { .. } => Family::ResetProcess,
            Element::DelayAcquisition { .. } => Family::DelayAcquisition,
            Element::TestWithTime { .. } => Family::TestWithTime,
            Element::ParameterNormalized { .. } => Family::ParameterNormalized,
            Element::ParameterScaled { .. } => Family::ParameterScaled,
            Element::ParameterFloat { .. } => Family::ParameterFloat,
            Element::ParameterActivation { .. } => Family::ParameterActivation,
            Element::FileReady { .. } => Family::FileReady,
            Element::SectionReady { .. } => Family::SectionReady,
            Element::CallOrSelect { .. } => Family::CallOrSelect,
            Element::LastSegmentOrSection { .. } => Family::LastSegmentOrSection,
            Element::AckFileOrSection { .. } => Family::AckFileOrSection,
            Element::Segment { .. } => Family::Segment,
            Element::Directory { .. } => Family::Directory,
            Element::QueryLog { .. } => Family::QueryLog,
        }
    }

    /// Whether this element may be carried by an ASDU of `type_id` (e.g. a
    /// [`Element::DoublePoint`] by M_DP_NA_1, M_DP_TA_1 and M_DP_TB_1).
    pub fn family_matches(&self, type_id: TypeId) -> bool {
        self.family() == family_of(type_id)
    }

    /// The quality descriptor for monitor elements that carry one.
    pub fn quality(&self) -> Option<Quality> {
        match self {
            Element::SinglePoint { quality, .. }
            | Element::DoublePoint { quality, .. }
            | Element::StepPosition { quality, .. }
            | Element::Bitstring { quality, .. }
            | Element::Normalized { quality, .. }
            | Element::Scaled { quality, .. }
            | Element::Float { quality, .. }
            | Element::PackedSinglePoints { quality, .. } => Some(*quality),
            Element::ProtectionEvent { quality, .. }
            | Element::ProtectionStartEvents { quality, .. }
            | Element::ProtectionOutputCircuit { quality, .. } => Some(quality.quality),
            _ => None,
        }
    }

    /// A short tag of the element kind for log lines: `SP`, `DP`, `NVA`, `SCO`, `QOI`, ...
    pub fn short_name(&self) -> &'static str {
        match self {
            Element::SinglePoint { .. } => "SP",
            Element::DoublePoint { .. } => "DP",
            Element::StepPosition { .. } => "ST",
            Element::Bitstring { .. } => "BO",
            Element::Normalized { .. } => "NVA",
            Element::Scaled { .. } => "SVA",
            Element::Float { .. } => "R32",
            Element::IntegratedTotal(_) => "BCR",
            Element::ProtectionEvent { .. } => "SEP",
            Element::ProtectionStartEvents { .. } => "SPE",
            Element::ProtectionOutputCircuit { .. } => "OCI",
            Element::PackedSinglePoints { .. } => "SCD",
            Element::SingleCommand { .. } => "SCO",
            Element::DoubleCommand { .. } => "DCO",
            Element::RegulatingStep { .. } => "RCO",
            Element::SetpointNormalized { .. } => "SE-NVA",
            Element::SetpointScaled { .. } => "SE-SVA",
            Element::SetpointFloat { .. } => "SE-R32",
            Element::BitstringCommand { .. } => "BSI",
            Element::EndOfInitialisation { .. } => "COI",
            Element::Interrogation { .. } => "QOI",
            Element::CounterInterrogation { .. } => "QCC",
            Element::Read => "READ",
            Element::ClockSync { .. } => "CLOCK",
            Element::Test { .. } => "FBP",
            Element::ResetProcess { .. } => "QRP",
            Element::DelayAcquisition { .. } => "DELAY",
            Element::TestWithTime { .. } => "TSC",
            Element::ParameterNormalized { .. } => "P-NVA",
            Element::ParameterScaled { .. } => "P-SVA",
            Element::ParameterFloat { .. } => "P-R32",
            Element::ParameterActivation { .. } => "QPA",
            Element::FileReady { .. } => "FR",
            Element::SectionReady { .. } => "SR",
            Element::CallOrSelect { .. } => "SCQ",
            Element::LastSegmentOrSection { .. } => "LS",
            Element::AckFileOrSection { .. } => "AF",
            Element::Segment { .. } => "SG",
            Element::Directory { .. } => "DIR",
            Element::QueryLog { .. } => "LOG",
        }
    }

    /// Octets of this element and the type's time tag on the wire, without the IOA:
    /// [`TypeId::element_len`] for a matching type, except that segments vary.
    pub(crate) fn wire_len(&self, type_id: TypeId) -> usize {
        match self {
            Element::Segment { data, .. } => 4 + data.len() + type_id.time_tag().len(),
            _ => type_id.element_len().unwrap_or(4),
        }
    }
}

/// Formats a float like a protocol analyser: fixed point with up to six decimals and no
/// trailing zeros (1904673.75, 50.000042), scientific for very large or small magnitudes.
fn write_float(f: &mut fmt::Formatter<'_>, value: f32) -> fmt::Result {
    let magnitude = value.abs();
    if value == 0.0 || (1e-4..1e15).contains(&magnitude) {
        let fixed = format!("{value:.6}");
        let trimmed = fixed.trim_end_matches('0').trim_end_matches('.');
        f.write_str(trimmed)
    } else {
        write!(f, "{value:e}")
    }
}

/// `0x2AE5 (0.335114)`.
fn write_normalized(f: &mut fmt::Formatter<'_>, raw: i16) -> fmt::Result {
    let [low, high] = raw.to_le_bytes();
    write!(
        f,
        "0x{:04X} ({:.6})",
        u16::from_le_bytes([low, high]),
        Element::normalized_value(raw)
    )
}

fn on_off(on: bool) -> &'static str {
    if on {
        "ON"
    } else {
        "OFF"
    }
}

impl fmt::Display for Element {
    /// The value and its quality as a protocol analyser prints them: `ON [iv nt sb bl]`,
    /// `0x2AE5 (0.335114) [iv nt sb bl ov]`, `1904673.75 [iv nt sb bl ov]`,
    /// `ON execute qu=0`. [`Element::Read`] prints nothing.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Element::SinglePoint { on, quality } => {
                write!(f, "{} {}", on_off(*on), QualityNoOverflow(*quality))
            }
            Element::DoublePoint { state, quality } => {
                write!(f, "{state} {}", QualityNoOverflow(*quality))
            }
            Element::StepPosition { position, quality } => write!(f, "{position} {quality}"),
            Element::Bitstring { bits, quality } => write!(f, "0x{bits:08X} {quality}"),
            Element::Normalized { raw, quality } => {
                write_normalized(f, *raw)?;
                write!(f, " {quality}")
            }
            Element::Scaled { value, quality } => write!(f, "{value} {quality}"),
            Element::Float { value, quality } => {
                write_float(f, *value)?;
                write!(f, " {quality}")
            }
            Element::IntegratedTotal(reading) => reading.fmt(f),
            Element::ProtectionEvent {
                state,
                quality,
                elapsed,
            } => write!(f, "{state} {quality} elapsed {elapsed}"),
            Element::ProtectionStartEvents {
                events,
                quality,
                duration,
            } => write!(f, "{events} {quality} duration {duration}"),
            Element::ProtectionOutputCircuit {
                circuits,
                quality,
                operating_time,
            } => write!(f, "{circuits} {quality} operating {operating_time}"),
            Element::PackedSinglePoints {
                status,
                change,
                quality,
            } => write!(f, "status=0x{status:04X} change=0x{change:04X} {quality}"),
            Element::SingleCommand { on, qualifier } => {
                write!(f, "{} {qualifier}", on_off(*on))
            }
            Element::DoubleCommand { state, qualifier } => write!(f, "{state} {qualifier}"),
            Element::RegulatingStep { state, qualifier } => write!(f, "{state} {qualifier}"),
            Element::SetpointNormalized { raw, qualifier } => {
                write_normalized(f, *raw)?;
                write!(f, " {qualifier}")
            }
            Element::SetpointScaled { value, qualifier } => write!(f, "{value} {qualifier}"),
            Element::SetpointFloat { value, qualifier } => {
                write_float(f, *value)?;
                write!(f, " {qualifier}")
            }
            Element::BitstringCommand { bits } => write!(f, "0x{bits:08X}"),
            Element::EndOfInitialisation {
                cause,
                after_parameter_change,
            } => {
                let meaning = match cause {
                    0 => "local power on",
                    1 => "local manual reset",
                    2 => "remote reset",
                    _ => "other",
                };
                write!(f, "cause={cause} ({meaning})")?;
                if *after_parameter_change {
                    f.write_str(" after parameter change")?;
                }
                Ok(())
            }
            Element::Interrogation { qualifier } => match qualifier {
                20 => write!(f, "{qualifier} (station)"),
                21..=36 => write!(f, "{qualifier} (group {})", qualifier - 20),
                _ => write!(f, "{qualifier} (not defined)"),
            },
            Element::CounterInterrogation { request, freeze } => {
                write!(f, "rqt={request} frz={freeze}")
            }
            Element::Read => Ok(()),
            Element::ClockSync { time } => time.fmt(f),
            Element::Test { pattern } => write!(f, "0x{pattern:04X}"),
            Element::ResetProcess { qualifier } => write!(f, "{qualifier}"),
            Element::DelayAcquisition { delay } => delay.fmt(f),
            Element::TestWithTime { counter } => write!(f, "{counter}"),
            Element::ParameterNormalized { raw, qualifier } => {
                write_normalized(f, *raw)?;
                write!(f, " qpm=0x{qualifier:02X}")
            }
            Element::ParameterScaled { value, qualifier } => {
                write!(f, "{value} qpm=0x{qualifier:02X}")
            }
            Element::ParameterFloat { value, qualifier } => {
                write_float(f, *value)?;
                write!(f, " qpm=0x{qualifier:02X}")
            }
            Element::ParameterActivation { qualifier } => write!(f, "{qualifier}"),
            Element::FileReady {
                file,
                length,
                qualifier,
            } => write!(f, "file={file} length={length} frq=0x{qualifier:02X}"),
            Element::SectionReady {
                file,
                section,
                length,
                qualifier,
            } => write!(
                f,
                "file={file} section={section} length={length} srq=0x{qualifier:02X}"
            ),
            Element::CallOrSelect {
                file,
                section,
                qualifier,
            } => write!(f, "file={file} section={section} scq=0x{qualifier:02X}"),
            Element::LastSegmentOrSection {
                file,
                section,
                qualifier,
                checksum,
            } => write!(
                f,
                "file={file} section={section} lsq={qualifier} chs=0x{checksum:02X}"
            ),
            Element::AckFileOrSection {
                file,
                section,
                qualifier,
            } => write!(f, "file={file} section={section} afq=0x{qualifier:02X}"),
            Element::Segment {
                file,
                section,
                data,
            } => write!(f, "file={file} section={section} los={}", data.len()),
            Element::Directory {
                file,
                length,
                status,
            } => write!(f, "file={file} length={length} sof=0x{status:02X}"),
            Element::QueryLog { file, start, stop } => {
                write!(f, "file={file} from {start} to {stop}")
            }
        }
    }
}

/// A cursor over the octets of an ASDU that never reads past the end.
pub(crate) struct Reader<'a> {
    rest: &'a [u8],
    /// Octets of the whole ASDU, for error reports.
    total: usize,
}

impl<'a> Reader<'a> {
    pub(crate) fn new(rest: &'a [u8], total: usize) -> Self {
        Reader { rest, total }
    }

    pub(crate) fn remaining(&self) -> usize {
        self.rest.len()
    }

    fn truncated(&self, wanted: usize) -> AsduError {
        AsduError::Truncated {
            needed: self.total - self.rest.len() + wanted,
            available: self.total,
        }
    }

    pub(crate) fn take<const N: usize>(&mut self) -> Result<[u8; N], AsduError> {
        let (head, tail) = self
            .rest
            .split_first_chunk::<N>()
            .ok_or(self.truncated(N))?;
        self.rest = tail;
        Ok(*head)
    }

    pub(crate) fn take_slice(&mut self, len: usize) -> Result<&'a [u8], AsduError> {
        let (head, tail) = self.rest.split_at_checked(len).ok_or(self.truncated(len))?;
        self.rest = tail;
        Ok(head)
    }
}

fn u24(bytes: [u8; 3]) -> u32 {
    let [a, b, c] = bytes;
    u32::from_le_bytes([a, b, c, 0])
}

fn u16le(bytes: [u8; 2]) -> u16 {
    u16::from_le_bytes(bytes)
}

fn i16le(bytes: [u8; 2]) -> i16 {
    i16::from_le_bytes(bytes)
}

/// Decodes the element and time tag of one object of `type_id`.
pub(crate) fn decode_element(
    type_id: TypeId,
    reader: &mut Reader<'_>,
) -> Result<(Element, Option<TimeTag>), AsduError> {
    use TypeId::*;
    let element = match type_id {
        M_SP_NA_1 | M_SP_TA_1 | M_SP_TB_1 => {
            let [siq] = reader.take()?;
            Element::SinglePoint {
                on: siq & 0x01 != 0,
                quality: Quality::from_status_bits(siq),
            }
        }
        M_DP_NA_1 | M_DP_TA_1 | M_DP_TB_1 => {
            let [diq] = reader.take()?;
            Element::DoublePoint {
                state: DoublePointState::from_bits(diq),
                quality: Quality::from_status_bits(diq),
            }
        }
        M_ST_NA_1 | M_ST_TA_1 | M_ST_TB_1 => {
            let [vti, qds] = reader.take()?;
            Element::StepPosition {
                position: StepPosition::from_vti(vti),
                quality: Quality::from_qds(qds),
            }
        }
        M_BO_NA_1 | M_BO_TA_1 | M_BO_TB_1 => {
            let [a, b, c, d, qds] = reader.take()?;
            Element::Bitstring {
                bits: u32::from_le_bytes([a, b, c, d]),
                quality: Quality::from_qds(qds),
            }
        }
        M_ME_NA_1 | M_ME_TA_1 | M_ME_TD_1 => {
            let [a, b, qds] = reader.take()?;
            Element::Normalized {
                raw: i16le([a, b]),
                quality: Quality::from_qds(qds),
            }
        }
        M_ME_ND_1 => Element::Normalized {
            raw: i16le(reader.take()?),
            quality: Quality::GOOD,
        },
        M_ME_NB_1 | M_ME_TB_1 | M_ME_TE_1 => {
            let [a, b, qds] = reader.take()?;
            Element::Scaled {
                value: i16le([a, b]),
                quality: Quality::from_qds(qds),
            }
        }
        M_ME_NC_1 | M_ME_TC_1 | M_ME_TF_1 => {
            let [a, b, c, d, qds] = reader.take()?;
            Element::Float {
                value: f32::from_le_bytes([a, b, c, d]),
                quality: Quality::from_qds(qds),
            }
        }
        M_IT_NA_1 | M_IT_TA_1 | M_IT_TB_1 => {
            Element::IntegratedTotal(BinaryCounterReading::from_bytes(reader.take()?))
        }
        M_EP_TA_1 | M_EP_TD_1 => {
            let [sep] = reader.take()?;
            Element::ProtectionEvent {
                state: DoublePointState::from_bits(sep),
                quality: ProtectionQuality::from_bits(sep),
                elapsed: Cp16Time2a::from_bytes(reader.take()?)?,
            }
        }
        M_EP_TB_1 | M_EP_TE_1 => {
            let [spe, qdp] = reader.take()?;
            Element::ProtectionStartEvents {
                events: StartEvents::from_bits(spe),
                quality: ProtectionQuality::from_bits(qdp),
                duration: Cp16Time2a::from_bytes(reader.take()?)?,
            }
        }
        M_EP_TC_1 | M_EP_TF_1 => {
            let [oci, qdp] = reader.take()?;
            Element::ProtectionOutputCircuit {
                circuits: OutputCircuits::from_bits(oci),
                quality: ProtectionQuality::from_bits(qdp),
                operating_time: Cp16Time2a::from_bytes(reader.take()?)?,
            }
        }
        M_PS_NA_1 => {
            let [s0, s1, c0, c1, qds] = reader.take()?;
            Element::PackedSinglePoints {
                status: u16le([s0, s1]),
                change: u16le([c0, c1]),
                quality: Quality::from_qds(qds),
            }
        }
        C_SC_NA_1 | C_SC_TA_1 => {
            let [sco] = reader.take()?;
            Element::SingleCommand {
                on: sco & 0x01 != 0,
                qualifier: CommandQualifier::from_bits(sco),
            }
        }
        C_DC_NA_1 | C_DC_TA_1 => {
            let [dco] = reader.take()?;
            Element::DoubleCommand {
                state: DoublePointState::from_bits(dco),
                qualifier: CommandQualifier::from_bits(dco),
            }
        }
        C_RC_NA_1 | C_RC_TA_1 => {
            let [rco] = reader.take()?;
            Element::RegulatingStep {
                state: RegulatingStepState::from_bits(rco),
                qualifier: CommandQualifier::from_bits(rco),
            }
        }
        C_SE_NA_1 | C_SE_TA_1 => {
            let [a, b, qos] = reader.take()?;
            Element::SetpointNormalized {
                raw: i16le([a, b]),
                qualifier: SetpointQualifier::from_bits(qos),
            }
        }
        C_SE_NB_1 | C_SE_TB_1 => {
            let [a, b, qos] = reader.take()?;
            Element::SetpointScaled {
                value: i16le([a, b]),
                qualifier: SetpointQualifier::from_bits(qos),
            }
        }
        C_SE_NC_1 | C_SE_TC_1 => {
            let [a, b, c, d, qos] = reader.take()?;
            Element::SetpointFloat {
                value: f32::from_le_bytes([a, b, c, d]),
                qualifier: SetpointQualifier::from_bits(qos),
            }
        }
        C_BO_NA_1 | C_BO_TA_1 => Element::BitstringCommand {
            bits: u32::from_le_bytes(reader.take()?),
        },
        M_EI_NA_1 => {
            let [coi] = reader.take()?;
            Element::EndOfInitialisation {
                cause: coi & 0x7F,
                after_parameter_change: coi & 0x80 != 0,
            }
        }
        C_IC_NA_1 => {
            let [qualifier] = reader.take()?;
            Element::Interrogation { qualifier }
        }
        C_CI_NA_1 => {
            let [qcc] = reader.take()?;
            let (request, freeze) = CounterInterrogationQualifier::split(qcc);
            Element::CounterInterrogation { request, freeze }
        }
        C_RD_NA_1 => Element::Read,
        C_CS_NA_1 => Element::ClockSync {
            time: Cp56Time2a::from_bytes(reader.take()?)?,
        },
        C_TS_NA_1 => Element::Test {
            pattern: u16le(reader.take()?),
        },
        C_RP_NA_1 => {
            let [qualifier] = reader.take()?;
            Element::ResetProcess { qualifier }
        }
        C_CD_NA_1 => Element::DelayAcquisition {
            delay: Cp16Time2a::from_bytes(reader.take()?)?,
        },
        C_TS_TA_1 => Element::TestWithTime {
            counter: u16le(reader.take()?),
        },
        P_ME_NA_1 => {
            let [a, b, qualifier] = reader.take()?;
            Element::ParameterNormalized {
                raw: i16le([a, b]),
                qualifier,
            }
        }
        P_ME_NB_1 => {
            let [a, b, qualifier] = reader.take()?;
            Element::ParameterScaled {
                value: i16le([a, b]),
                qualifier,
            }
        }
        P_ME_NC_1 => {
            let [a, b, c, d, qualifier] = reader.take()?;
            Element::ParameterFloat {
                value: f32::from_le_bytes([a, b, c, d]),
                qualifier,
            }
        }
        P_AC_NA_1 => {
            let [qualifier] = reader.take()?;
            Element::ParameterActivation { qualifier }
        }
        F_FR_NA_1 => {
            let [f0, f1, l0, l1, l2, qualifier] = reader.take()?;
            Element::FileReady {
                file: u16le([f0, f1]),
                length: u24([l0, l1, l2]),
                qualifier,
            }
        }
        F_SR_NA_1 => {
            let [f0, f1, section, l0, l1, l2, qualifier] = reader.take()?;
            Element::SectionReady {
                file: u16le([f0, f1]),
                section,
                length: u24([l0, l1, l2]),
                qualifier,
            }
        }
        F_SC_NA_1 => {
            let [f0, f1, section, qualifier] = reader.take()?;
            Element::CallOrSelect {
                file: u16le([f0, f1]),
                section,
                qualifier,
            }
        }
        F_LS_NA_1 => {
            let [f0, f1, section, qualifier, checksum] = reader.take()?;
            Element::LastSegmentOrSection {
                file: u16le([f0, f1]),
                section,
                qualifier,
                checksum,
            }
        }
        F_AF_NA_1 => {
            let [f0, f1, section, qualifier] = reader.take()?;
            Element::AckFileOrSection {
                file: u16le([f0, f1]),
                section,
                qualifier,
            }
        }
        F_SG_NA_1 => {
            let [f0, f1, section, length] = reader.take()?;
            Element::Segment {
                file: u16le([f0, f1]),
                section,
                data: reader.take_slice(length.into())?.to_vec(),
            }
        }
        F_DR_TA_1 => {
            let [f0, f1, l0, l1, l2, status] = reader.take()?;
            Element::Directory {
                file: u16le([f0, f1]),
                length: u24([l0, l1, l2]),
                status,
            }
        }
        F_SC_NB_1 => Element::QueryLog {
            file: u16le(reader.take()?),
            start: Cp56Time2a::from_bytes(reader.take()?)?,
            stop: Cp56Time2a::from_bytes(reader.take()?)?,
        },
    };
    let time = match type_id.time_tag() {
        TimeTagKind::None => None,
        TimeTagKind::Cp24 => Some(TimeTag::Cp24(Cp24Time2a::from_bytes(reader.take()?)?)),
        TimeTagKind::Cp56 => Some(TimeTag::Cp56(Cp56Time2a::from_bytes(reader.take()?)?)),
    };
    Ok((element, time))
}

fn length24(what: &'static str, length: u32) -> Result<[u8; 3], RangeError> {
    if length > 0xFF_FFFF {
        return Err(RangeError::new(what, length.into(), 0, 0xFF_FFFF));
    }
    let [a, b, c, _] = length.to_le_bytes();
    Ok([a, b, c])
}

/// Appends the element octets (without IOA and time tag). The caller has checked that the
/// element's family matches the type; values that do not fit their field are an error.
pub(crate) fn encode_element(
    type_id: TypeId,
    element: &Element,
    out: &mut Vec<u8>,
) -> Result<(), AsduError> {
    let status = |on: bool, quality: &Quality| u8::from(on) | quality.status_bits();
    match element {
        Element::SinglePoint { on, quality } => out.push(status(*on, quality)),
        Element::DoublePoint { state, quality } => {
            out.push(state.bits() | quality.status_bits());
        }
        Element::StepPosition { position, quality } => {
            out.extend_from_slice(&[position.to_vti(), quality.to_qds()]);
        }
        Element::Bitstring { bits, quality } => {
            out.extend_from_slice(&bits.to_le_bytes());
            out.push(quality.to_qds());
        }
        Element::Normalized { raw, quality } => {
            out.extend_from_slice(&raw.to_le_bytes());
            // M_ME_ND_1 has no quality descriptor on the wire.
            if type_id != TypeId::M_ME_ND_1 {
                out.push(quality.to_qds());
            }
        }
        Element::Scaled { value, quality } => {
            out.extend_from_slice(&value.to_le_bytes());
            out.push(quality.to_qds());
        }
        Element::Float { value, quality } => {
            out.extend_from_slice(&value.to_le_bytes());
            out.push(quality.to_qds());
        }
        Element::IntegratedTotal(reading) => out.extend_from_slice(&reading.to_bytes()),
        Element::ProtectionEvent {
            state,
            quality,
            elapsed,
        } => {
            out.push(state.bits() | quality.bits());
            elapsed.encode(out);
        }
        Element::ProtectionStartEvents {
            events,
            quality,
            duration,
        } => {
            out.extend_from_slice(&[events.bits(), quality.bits()]);
            duration.encode(out);
        }
        Element::ProtectionOutputCircuit {
            circuits,
            quality,
            operating_time,
        } => {
            out.extend_from_slice(&[circuits.bits(), quality.bits()]);
            operating_time.encode(out);
        }
        Element::PackedSinglePoints {
            status,
            change,
            quality,
        } => {
            out.extend_from_slice(&status.to_le_bytes());
            out.extend_from_slice(&change.to_le_bytes());
            out.push(quality.to_qds());
        }
        Element::SingleCommand { on, qualifier } => out.push(u8::from(*on) | qualifier.bits()),
        Element::DoubleCommand { state, qualifier } => out.push(state.bits() | qualifier.bits()),
        Element::RegulatingStep { state, qualifier } => {
            out.push(state.bits() | qualifier.bits());
        }
        Element::SetpointNormalized { raw, qualifier } => {
            out.extend_from_slice(&raw.to_le_bytes());
            out.push(qualifier.bits());
        }
        Element::SetpointScaled { value, qualifier } => {
            out.extend_from_slice(&value.to_le_bytes());
            out.push(qualifier.bits());
        }
        Element::SetpointFloat { value, qualifier } => {
            out.extend_from_slice(&value.to_le_bytes());
            out.push(qualifier.bits());
        }
        Element::BitstringCommand { bits } => out.extend_from_slice(&bits.to_le_bytes()),
        Element::EndOfInitialisation {
            cause,
            after_parameter_change,
        } => {
            if *cause > 127 {
                return Err(
                    RangeError::new("cause of initialisation", (*cause).into(), 0, 127).into(),
                );
            }
            out.push(cause | if *after_parameter_change { 0x80 } else { 0 });
        }
        Element::Interrogation { qualifier } => out.push(*qualifier),
        Element::CounterInterrogation { request, freeze } => {
            out.push(CounterInterrogationQualifier::join(*request, *freeze)?);
        }
        Element::Read => {}
        Element::ClockSync { time } => time.encode(out),
        Element::Test { pattern } => out.extend_from_slice(&pattern.to_le_bytes()),
        Element::ResetProcess { qualifier } => out.push(*qualifier),
        Element::DelayAcquisition { delay } => delay.encode(out),
        Element::TestWithTime { counter } => out.extend_from_slice(&counter.to_le_bytes()),
        Element::ParameterNormalized { raw, qualifier } => {
            out.extend_from_slice(&raw.to_le_bytes());
            out.push(*qualifier);
        }
        Element::ParameterScaled { value, qualifier } => {
            out.extend_from_slice(&value.to_le_bytes());
            out.push(*qualifier);
        }
        Element::ParameterFloat { value, qualifier } => {
            out.extend_from_slice(&value.to_le_bytes());
            out.push(*qualifier);
        }
        Element::ParameterActivation { qualifier } => out.push(*qualifier),
        Element::FileReady {
            file,
            length,
            qualifier,
        } => {
            let length = length24("length of file", *length)?;
            out.extend_from_slice(&file.to_le_bytes());
            out.extend_from_slice(&length);
            out.push(*qualifier);
        }
        Element::SectionReady {
            file,
            section,
            length,
            qualifier,
        } => {
            let length = length24("length of section", *length)?;
            out.extend_from_slice(&file.to_le_bytes());
            out.push(*section);
            out.extend_from_slice(&length);
            out.push(*qualifier);
        }
        Element::CallOrSelect {
            file,
            section,
            qualifier,
        }
        | Element::AckFileOrSection {
            file,
            section,
            qualifier,
        } => {
            out.extend_from_slice(&file.to_le_bytes());
            out.extend_from_slice(&[*section, *qualifier]);
        }
        Element::LastSegmentOrSection {
            file,
            section,
            qualifier,
            checksum,
        } => {
            out.extend_from_slice(&file.to_le_bytes());
            out.extend_from_slice(&[*section, *qualifier, *checksum]);
        }
        Element::Segment {
            file,
            section,
            data,
        } => {
            let length = u8::try_from(data.len()).map_err(|_| {
                RangeError::new(
                    "length of segment",
                    data.len().try_into().unwrap_or(i64::MAX),
                    0,
                    255,
                )
            })?;
            out.extend_from_slice(&file.to_le_bytes());
            out.extend_from_slice(&[*section, length]);
            out.extend_from_slice(data);
        }
        Element::Directory {
            file,
            length,
            status,
        } => {
            let length = length24("length of file", *length)?;
            out.extend_from_slice(&file.to_le_bytes());
            out.extend_from_slice(&length);
            out.push(*status);
        }
        Element::QueryLog { file, start, stop } => {
            out.extend_from_slice(&file.to_le_bytes());
            start.encode(out);
            stop.encode(out);
        }
    }
    Ok(())
}
