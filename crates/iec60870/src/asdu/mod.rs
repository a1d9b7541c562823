//! The application layer of IEC 60870-5-101/104: the ASDU codec, sans-IO.
//!
//! # Layout
//!
//! | Module | Content |
//! |---|---|
//! | [`crate::time`] | CP56Time2a, CP24Time2a, CP16Time2a (outside this module: the 103 layer uses them too) |
//! | `type_id` | [`TypeId`]: the 67 type identifications by mnemonic, their time tag, element size, direction, tagged/untagged counterparts |
//! | `cause` | [`Cause`] (any 6-bit value, named constants for the standard ones) and [`Cot`] (cause, P/N, T, originator) |
//! | `address` | [`CommonAddress`] and [`Ioa`] |
//! | `element` | information elements and qualifiers with their bit layouts: [`Quality`], [`DoublePointState`], [`StepPosition`], [`BinaryCounterReading`], [`CommandQualifier`], .. |
//! | `object` | [`InformationObject`] = [`Ioa`] + [`Element`] + optional [`TimeTag`], and the per-type element codec |
//! | `params` | [`AsduParams`]: the field sizes of a link (COT, common address, IOA) and its maximum ASDU length |
//! | `frame` | [`AsduHeader`] (decodable for unknown types), [`Asdu`] decode/encode/display, [`mirror_with_cause`], [`object_len`] |
//! | `pack` | [`pack_objects`]: fills ASDUs up to the length and object limits, with SQ = 1 for runs of consecutive addresses |
//! | [`text`] | values as people type them (`ON`, `0.5`, `0x1F`, `HIGHER`) read into elements of a given type, for point lists and tools |
//!
//! # Wire format
//!
//! ```text
//! type id | VSQ (SQ bit 7, count bits 0-6) | COT (cause 0-5, P/N 6, T 7) [| originator]
//!         | common address (1-2 octets, LE) | objects
//! object (SQ = 0): IOA (1-3 octets, LE) element [time tag]      repeated count times
//! objects (SQ = 1): IOA of the first, then count × (element [time tag]), addresses +1 each
//! ```
//!
//! # Strictness
//!
//! Decoding is strict about structure and lenient about meaning: the VSQ count times the
//! element size must match the payload exactly, time tags and CP16 durations must have
//! fields in range, but any cause 0..63, any qualifier value and command states that the
//! standard forbids (DCS 0 and 3) decode, so that a station can answer them with a
//! negative confirmation and a test tool can display them. Reserved bits are ignored when
//! decoding and sent as zero.
//!
//! Nothing here panics on peer input: every read is bounds-checked and returns
//! [`AsduError`].
//!
//! # Example
//!
//! ```
//! use iec60870::asdu::*;
//!
//! // A double command ON to IOA 2100, activation, common address 1 (IEC 104 sizes).
//! let bytes = [0x2E, 0x01, 0x06, 0x00, 0x01, 0x00, 0x34, 0x08, 0x00, 0x02];
//! let params = AsduParams::IEC104;
//! let command = Asdu::decode(&bytes, &params)?;
//! assert_eq!(command.type_id, TypeId::C_DC_NA_1);
//! assert_eq!(command.cot.cause, Cause::ACTIVATION);
//! let object = command.objects.first().expect("one object");
//! assert_eq!(object.ioa.get(), 2100);
//! assert!(matches!(
//!     object.element,
//!     Element::DoubleCommand { state: DoublePointState::On, .. }
//! ));
//!
//! // Confirm it by mirroring the request with COT 7.
//! let confirmation = mirror_with_cause(&bytes, &params, Cause::ACTIVATION_CON, false)?;
//! assert_eq!(confirmation[2], 7);
//!
//! // Build and encode the resulting indication.
//! let time = Cp56Time2a::new(17, 4, 26, 9, 59, 30_424)?;
//! let event = Asdu::new(TypeId::M_DP_TB_1, Cause::RETURN_REMOTE, CommonAddress::new(1))
//!     .with_object(InformationObject::with_time(
//!         Ioa::from(2000u16),
//!         Element::DoublePoint { state: DoublePointState::On, quality: Quality::GOOD },
//!         time,
//!     ));
//! let mut out = Vec::new();
//! event.encode(&params, &mut out)?;
//! assert_eq!(out.len(), 17);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod address;
mod cause;
mod element;
mod frame;
mod object;
mod pack;
mod params;
pub mod text;
mod type_id;

pub use address::{CommonAddress, Ioa};
pub use cause::{Cause, Cot};
pub use element::{
    BinaryCounterReading, CommandQualifier, CounterInterrogationQualifier, DoublePointState,
    FileQualifier, InitialisationCause, InterrogationQualifier, OutputCircuits,
    ParameterActivationQualifier, ParameterQualifier, ProtectionQuality, Quality, QualityOctets,
    RegulatingStepState, ResetProcessQualifier, SetpointQualifier, StartEvents, StepPosition,
};
pub use frame::{mirror_with_cause, object_len, Asdu, AsduHeader};
pub use object::{Element, InformationObject, TimeTag};
pub use pack::{pack_objects, Packer};
pub use params::AsduParams;
pub use type_id::{ParseTypeIdError, TimeTagKind, TypeId};

pub use crate::time::{Cp16Time2a, Cp24Time2a, Cp56Time2a, TimeError};

/// A value outside the range its field can carry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("{what} {value} outside {min}..={max}")]
pub struct RangeError {
    /// What the value is.
    pub what: &'static str,
    /// The value given.
    pub value: i64,
    /// Smallest allowed value.
    pub min: i64,
    /// Largest allowed value.
    pub max: i64,
}

impl RangeError {
    /// A range error for `what`.
    pub fn new(what: &'static str, value: i64, min: i64, max: i64) -> RangeError {
        RangeError {
            what,
            value,
            min,
            max,
        }
    }
}

/// Why an ASDU could not be decoded or encoded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum AsduError {
    /// Fewer octets than the header or an object needs.
    #[error("ASDU truncated: {needed} octets needed, {available} available")]
    Truncated {
        /// Octets needed up to the end of the field being read.
        needed: usize,
        /// Octets of the ASDU.
        available: usize,
    },
    /// The type identification is not defined by the standard. The header is still
    /// decodable with [`AsduHeader::decode`], to answer with COT 44.
    #[error("unknown type identification {0}")]
    UnknownTypeId(u8),
    /// The VSQ count is 0.
    #[error("ASDU has no information objects")]
    NoObjects,
    /// More than 127 objects (the 7-bit VSQ count).
    #[error("{0} information objects, at most 127 fit one ASDU")]
    TooManyObjects(usize),
    /// The payload is shorter than the VSQ count × element size.
    #[error("VSQ announces {count} objects needing {expected} octets, the ASDU has {actual}")]
    ObjectCountMismatch {
        /// The VSQ count.
        count: u8,
        /// Octets the whole ASDU should have.
        expected: usize,
        /// Octets it has.
        actual: usize,
    },
    /// Octets left over after the last object.
    #[error("{0} trailing octets after the last information object")]
    TrailingBytes(usize),
    /// SQ = 1 whose addresses would run past 0xFFFFFF, or past the IOA field size.
    #[error("SQ=1 from IOA {base} with {count} elements overflows the address range")]
    IoaOverflow {
        /// The first address.
        base: u32,
        /// The VSQ count.
        count: u8,
    },
    /// SQ = 1 for a type whose elements have no fixed size (F_SG_NA_1).
    #[error("SQ=1 is not possible for {0}")]
    SequenceNotAllowed(TypeId),
    /// A time tag or CP16 duration with a field out of range.
    #[error("invalid time: {0}")]
    Time(#[from] crate::time::TimeError),
    /// Encoding: an element whose family does not match the type identification.
    #[error("IOA {ioa}: element does not belong to {type_id}")]
    ElementMismatch {
        /// The ASDU's type.
        type_id: TypeId,
        /// The offending object.
        ioa: Ioa,
    },
    /// Encoding: time tag missing, superfluous or of the wrong kind for the type.
    #[error("IOA {ioa}: time tag does not match {type_id}")]
    TimeTagMismatch {
        /// The ASDU's type.
        type_id: TypeId,
        /// The offending object.
        ioa: Ioa,
    },
    /// Encoding: SQ = 1 with addresses that are not consecutive.
    #[error("SQ=1 needs consecutive addresses: expected IOA {expected}, found {found}")]
    NotConsecutive {
        /// The address that should follow.
        expected: u32,
        /// The address found.
        found: Ioa,
    },
    /// Encoding: an address that does not fit the link's IOA field.
    #[error("IOA {ioa} does not fit {size} octet(s)")]
    IoaTooLarge {
        /// The address.
        ioa: Ioa,
        /// The link's IOA size.
        size: u8,
    },
    /// Encoding: a common address that does not fit the link's field.
    #[error("common address {address} does not fit {size} octet(s)")]
    CommonAddressTooLarge {
        /// The address.
        address: CommonAddress,
        /// The link's common address size.
        size: u8,
    },
    /// Encoding: an originator address other than 0 on a link with a one-octet COT.
    #[error("originator address {0} cannot be sent with a one-octet COT")]
    OriginatorNotEncodable(u8),
    /// Encoding: the ASDU would be longer than the link allows.
    #[error("ASDU of {len} octets exceeds the maximum of {max}")]
    TooLong {
        /// Octets the ASDU would have.
        len: usize,
        /// The link's maximum.
        max: usize,
    },
    /// Encoding: an element value outside its field.
    #[error(transparent)]
    Range(#[from] RangeError),
    /// [`AsduParams::try_new`] with an unsupported field size or length.
    #[error("invalid ASDU parameter {field}: {value}")]
    InvalidParams {
        /// Which parameter.
        field: &'static str,
        /// The value given.
        value: usize,
    },
}
