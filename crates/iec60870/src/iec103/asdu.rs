//! The IEC 103 ASDU codec: header, the standard ("compatible") messages of both
//! directions, generic services passed through.

use std::fmt;

use thiserror::Error;

use super::cause::Cause;
use super::measurand::Measurand;
use crate::time::{Cp32Time2a, Cp56Time2a, TimeError};

/// Which way an ASDU travels: some type identifications mean different things in each
/// (6 time synchronisation, 10 generic data).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Direction {
    /// From the protection equipment (the secondary) to the control system.
    Monitor,
    /// From the control system to the protection equipment.
    Control,
}

/// The function type of the global functions (GI, time synchronisation).
pub const FUN_GLOBAL: u8 = 255;
/// The function type of generic services.
pub const FUN_GENERIC: u8 = 254;
/// Identification INF: reset of the frame count bit.
pub const INF_RESET_FCB: u8 = 2;
/// Identification INF: reset of the communication unit.
pub const INF_RESET_CU: u8 = 3;
/// Identification INF: start / restart.
pub const INF_START_RESTART: u8 = 4;
/// Identification INF: power on.
pub const INF_POWER_ON: u8 = 5;
/// Measurands II: the standard set IL1, IL2, IL3, UL1, UL2, UL3, P, Q, f.
pub const INF_MEASURANDS_II: u8 = 148;
/// Generic services INF: read all headings / entries ... (244 = generic GI data).
pub const INF_GENERIC_GI: u8 = 245;

/// What comes before the information elements.
///
/// ```text
/// TYP | VSQ | COT | CA | FUN | INF | elements
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Header {
    /// Type identification.
    pub type_id: u8,
    /// Variable structure qualifier (SQ bit 7, number of elements bits 6..0).
    pub vsq: u8,
    /// Cause of transmission.
    pub cause: Cause,
    /// Common address of ASDU (the device's address; 255 broadcast).
    pub common_address: u8,
    /// Function type.
    pub fun: u8,
    /// Information number.
    pub inf: u8,
}

impl Header {
    /// Octets of the header.
    pub const LEN: usize = 6;
}

/// One disturbance record in ASDU 23.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct RecordedDisturbance {
    /// Fault number.
    pub fan: u16,
    /// Status of fault (bit 0 TP trip, 1 TM transmitted, 2 TEST, 3 OTEV other event).
    pub sof: u8,
    /// When the fault was recorded.
    pub time: Cp56Time2a,
}

/// A tag of ASDU 29: a binary signal's state at a position of the record.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct DisturbanceTag {
    /// Function type.
    pub fun: u8,
    /// Information number.
    pub inf: u8,
    /// Double point: 1 OFF, 2 ON.
    pub dpi: u8,
}

/// The information elements of an ASDU, by type.
#[derive(Debug, Clone, PartialEq)]
pub enum Body {
    /// 1: time-tagged message.
    TimeTagged {
        /// Double point: 1 OFF, 2 ON (0 and 3 transient/indeterminate).
        dpi: u8,
        /// When.
        time: Cp32Time2a,
        /// Supplementary information (the scan number in a GI, the RII of an ack).
        sin: u8,
    },
    /// 2: time-tagged message with relative time.
    TimeTaggedRelative {
        /// Double point.
        dpi: u8,
        /// Relative time in ms since the start of the fault.
        ret: u16,
        /// Fault number.
        fan: u16,
        /// When.
        time: Cp32Time2a,
        /// Supplementary information.
        sin: u8,
    },
    /// 3 (measurands I) and 9 (measurands II): measurands in the device's order.
    Measurands(Vec<Measurand>),
    /// 4: time-tagged measurand with relative time (e.g. a fault location).
    TimeTaggedMeasurand {
        /// Short-circuit location or value (IEEE 754 single).
        value: f32,
        /// Relative time.
        ret: u16,
        /// Fault number.
        fan: u16,
        /// When.
        time: Cp32Time2a,
    },
    /// 5: identification.
    Identification {
        /// Compatibility level.
        col: u8,
        /// Eight ASCII characters (manufacturer).
        text: [u8; 8],
        /// Four octets of manufacturer's software identification.
        software: [u8; 4],
    },
    /// 6: time synchronisation (both directions).
    TimeSync {
        /// The time.
        time: Cp56Time2a,
    },
    /// 7: initiation of general interrogation.
    GiInitiation {
        /// Scan number.
        scn: u8,
    },
    /// 8: termination of general interrogation.
    GiTermination {
        /// Scan number of the interrogation it ends.
        scn: u8,
    },
    /// 10: generic data (both directions), passed through after RII and NGD.
    GenericData {
        /// Return information identifier.
        rii: u8,
        /// Number of generic data sets with the COUNT and CONT bits.
        ngd: u8,
        /// The data sets as received.
        data: Vec<u8>,
    },
    /// 11: generic identification, passed through after RII.
    GenericIdentification {
        /// Return information identifier.
        rii: u8,
        /// Generic identification number, number of descriptive elements and the
        /// elements, as received.
        data: Vec<u8>,
    },
    /// 20: general command.
    GeneralCommand {
        /// Double command: 1 OFF, 2 ON.
        dco: u8,
        /// Return information identifier, repeated in the acknowledgement's SIN.
        rii: u8,
    },
    /// 21: generic command.
    GenericCommand {
        /// Return information identifier.
        rii: u8,
        /// Generic identification numbers (group, entry) with their kind of description.
        items: Vec<(u16, u8)>,
    },
    /// 23: list of recorded disturbances.
    DisturbanceList(Vec<RecordedDisturbance>),
    /// 24: order for disturbance data transmission.
    DisturbanceOrder {
        /// Type of order.
        too: u8,
        /// Type of disturbance values.
        tov: u8,
        /// Fault number.
        fan: u16,
        /// Actual channel.
        acc: u8,
    },
    /// 25: acknowledgement for disturbance data transmission.
    DisturbanceAck {
        /// Type of order (the acknowledgement's kind).
        too: u8,
        /// Type of disturbance values.
        tov: u8,
        /// Fault number.
        fan: u16,
        /// Actual channel.
        acc: u8,
    },
    /// 26: ready for transmission of disturbance data.
    DisturbanceReady {
        /// Type of disturbance values.
        tov: u8,
        /// Fault number.
        fan: u16,
        /// Number of grid faults.
        nof: u16,
        /// Number of channels.
        noc: u8,
        /// Number of elements of a channel.
        noe: u16,
        /// Interval between elements in microseconds.
        int: u16,
        /// Time of the first element.
        time: Cp32Time2a,
    },
    /// 27: ready for transmission of a channel.
    ChannelReady {
        /// Type of disturbance values.
        tov: u8,
        /// Fault number.
        fan: u16,
        /// Actual channel.
        acc: u8,
        /// Rated primary value.
        rpv: f32,
        /// Rated secondary value.
        rsv: f32,
        /// Reference factor.
        rfa: f32,
    },
    /// 28: ready for transmission of tags.
    TagsReady {
        /// Fault number.
        fan: u16,
    },
    /// 29: transmission of tags.
    Tags {
        /// Fault number.
        fan: u16,
        /// Tag position (the element number the states apply from).
        tap: u16,
        /// The tags.
        tags: Vec<DisturbanceTag>,
    },
    /// 30: transmission of disturbance values.
    DisturbanceValues {
        /// Type of disturbance values.
        tov: u8,
        /// Fault number.
        fan: u16,
        /// Actual channel.
        acc: u8,
        /// Number of the first element.
        nfe: u16,
        /// Single disturbance values.
        values: Vec<i16>,
    },
    /// 31: end of transmission.
    EndOfTransmission {
        /// Type of order.
        too: u8,
        /// Type of disturbance values.
        tov: u8,
        /// Fault number.
        fan: u16,
        /// Actual channel.
        acc: u8,
    },
    /// A type this codec does not take apart: the elements as received.
    Other(Vec<u8>),
}

/// An IEC 103 ASDU.
#[derive(Debug, Clone, PartialEq)]
pub struct Asdu {
    /// Type, VSQ, cause, common address, FUN, INF.
    pub header: Header,
    /// The elements.
    pub body: Body,
}

/// Why octets are not an ASDU.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum DecodeError {
    /// Fewer than the six header octets.
    #[error("ASDU of {0} octets is shorter than its 6-octet header")]
    TooShort(usize),
    /// The elements end early.
    #[error("type {type_id}: elements end at octet {at}, {needed} more needed")]
    Truncated {
        /// The type.
        type_id: u8,
        /// Where the elements ended.
        at: usize,
        /// Octets missing.
        needed: usize,
    },
    /// Octets after the last element.
    #[error("type {type_id}: {extra} octets after the last element")]
    TrailingOctets {
        /// The type.
        type_id: u8,
        /// How many.
        extra: usize,
    },
    /// The element count does not fit the type.
    #[error("type {type_id}: {count} elements where {expected}")]
    Count {
        /// The type.
        type_id: u8,
        /// The count found.
        count: usize,
        /// What the type allows.
        expected: &'static str,
    },
    /// A time tag with a field out of range.
    #[error("type {type_id}: {error}")]
    Time {
        /// The type.
        type_id: u8,
        /// The tag's problem.
        error: TimeError,
    },
}

/// Why an ASDU cannot be encoded.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum EncodeError {
    /// More elements than VSQ can count or the type allows.
    #[error("type {type_id}: {count} elements, at most {max}")]
    TooMany {
        /// The type.
        type_id: u8,
        /// The count.
        count: usize,
        /// The maximum.
        max: usize,
    },
}

/// Bounds-checked reading of the elements.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    type_id: u8,
}

impl<'a> Reader<'a> {
    fn take(&mut self, count: usize) -> Result<&'a [u8], DecodeError> {
        let end = self.at.saturating_add(count);
        let slice = self.bytes.get(self.at..end).ok_or(DecodeError::Truncated {
            type_id: self.type_id,
            at: self.at,
            needed: end.saturating_sub(self.bytes.len()),
        })?;
        self.at = end;
        Ok(slice)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], DecodeError> {
        let slice = self.take(N)?;
        let mut array = [0u8; N];
        array.copy_from_slice(slice);
        Ok(array)
    }

    fn u8(&mut self) -> Result<u8, DecodeError> {
        Ok(u8::from_le_bytes(self.array()?))
    }

    fn u16(&mut self) -> Result<u16, DecodeError> {
        Ok(u16::from_le_bytes(self.array()?))
    }

    fn i16(&mut self) -> Result<i16, DecodeError> {
        Ok(i16::from_le_bytes(self.array()?))
    }

    fn f32(&mut self) -> Result<f32, DecodeError> {
        Ok(f32::from_le_bytes(self.array()?))
    }

    fn cp32(&mut self) -> Result<Cp32Time2a, DecodeError> {
        let type_id = self.type_id;
        Cp32Time2a::from_bytes(self.array()?).map_err(|error| DecodeError::Time { type_id, error })
    }

    fn cp56(&mut self) -> Result<Cp56Time2a, DecodeError> {
        let type_id = self.type_id;
        Cp56Time2a::from_bytes(self.array()?).map_err(|error| DecodeError::Time { type_id, error })
    }

    fn rest(&mut self) -> Vec<u8> {
        let rest = self.bytes.get(self.at..).unwrap_or_default().to_vec();
        self.at = self.bytes.len();
        rest
    }

    fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.at)
    }

    fn finish(self) -> Result<(), DecodeError> {
        match self.remaining() {
            0 => Ok(()),
            extra => Err(DecodeError::TrailingOctets {
                type_id: self.type_id,
                extra,
            }),
        }
    }
}

impl Asdu {
    /// An ASDU with VSQ 0x81 (one element), the common case.
    pub fn new(
        type_id: u8,
        cause: Cause,
        common_address: u8,
        fun: u8,
        inf: u8,
        body: Body,
    ) -> Asdu {
        Asdu {
            header: Header {
                type_id,
                vsq: 0x81,
                cause,
                common_address,
                fun,
                inf,
            },
            body,
        }
    }

    /// Decodes an ASDU travelling in `direction`.
    pub fn decode(bytes: &[u8], direction: Direction) -> Result<Asdu, DecodeError> {
        let [type_id, vsq, cause, common_address, fun, inf] = match bytes.get(..Header::LEN) {
            Some(&[a, b, c, d, e, f]) => [a, b, c, d, e, f],
            _ => return Err(DecodeError::TooShort(bytes.len())),
        };
        let header = Header {
            type_id,
            vsq,
            cause: Cause(cause),
            common_address,
            fun,
            inf,
        };
        let mut reader = Reader {
            bytes: bytes.get(Header::LEN..).unwrap_or_default(),
            at: 0,
            type_id,
        };
        let count = usize::from(vsq & 0x7F);
        let body = match (type_id, direction) {
            (1, Direction::Monitor) => Body::TimeTagged {
                dpi: reader.u8()?,
                time: reader.cp32()?,
                sin: reader.u8()?,
            },
            (2, Direction::Monitor) => Body::TimeTaggedRelative {
                dpi: reader.u8()?,
                ret: reader.u16()?,
                fan: reader.u16()?,
                time: reader.cp32()?,
                sin: reader.u8()?,
            },
            (3 | 9, Direction::Monitor) => {
                // ASDU 9 counts its measurands in VSQ; ASDU 3 is one information object
                // of 1, 2 or 4 values (its four variants), counted by the length.
                let values_len = reader.remaining() / 2;
                let fits = match type_id {
                    9 => values_len == count && count > 0,
                    _ => (1..=4).contains(&values_len),
                };
                if !fits || reader.remaining() % 2 != 0 {
                    return Err(DecodeError::Count {
                        type_id,
                        count: values_len,
                        expected: if type_id == 9 {
                            "the VSQ count of two-octet measurands"
                        } else {
                            "1 to 4 two-octet measurands"
                        },
                    });
                }
                let mut values = Vec::with_capacity(values_len);
                for _ in 0..values_len {
                    values.push(Measurand::from_word(reader.u16()?));
                }
                Body::Measurands(values)
            }
            (4, Direction::Monitor) => Body::TimeTaggedMeasurand {
                value: reader.f32()?,
                ret: reader.u16()?,
                fan: reader.u16()?,
                time: reader.cp32()?,
            },
            (5, Direction::Monitor) => Body::Identification {
                col: reader.u8()?,
                text: reader.array()?,
                software: reader.array()?,
            },
            (6, _) => Body::TimeSync {
                time: reader.cp56()?,
            },
            (7, Direction::Control) => Body::GiInitiation { scn: reader.u8()? },
            (8, Direction::Monitor) => Body::GiTermination { scn: reader.u8()? },
            (10, _) => Body::GenericData {
                rii: reader.u8()?,
                ngd: reader.u8()?,
                data: reader.rest(),
            },
            (11, Direction::Monitor) => Body::GenericIdentification {
                rii: reader.u8()?,
                data: reader.rest(),
            },
            (20, Direction::Control) => Body::GeneralCommand {
                dco: reader.u8()?,
                rii: reader.u8()?,
            },
            (21, Direction::Control) => {
                let rii = reader.u8()?;
                let nog = reader.u8()?;
                let mut items = Vec::with_capacity(usize::from(nog));
                for _ in 0..nog {
                    items.push((reader.u16()?, reader.u8()?));
                }
                Body::GenericCommand { rii, items }
            }
            (23, Direction::Monitor) => {
                let mut records = Vec::with_capacity(count);
                for _ in 0..count {
                    records.push(RecordedDisturbance {
                        fan: reader.u16()?,
                        sof: reader.u8()?,
                        time: reader.cp56()?,
                    });
                }
                Body::DisturbanceList(records)
            }
            (24, Direction::Control) => Body::DisturbanceOrder {
                too: reader.u8()?,
                tov: reader.u8()?,
                fan: reader.u16()?,
                acc: reader.u8()?,
            },
            (25, Direction::Control) => Body::DisturbanceAck {
                too: reader.u8()?,
                tov: reader.u8()?,
                fan: reader.u16()?,
                acc: reader.u8()?,
            },
            (26, Direction::Monitor) => {
                reader.u8()?; // not used
                Body::DisturbanceReady {
                    tov: reader.u8()?,
                    fan: reader.u16()?,
                    nof: reader.u16()?,
                    noc: reader.u8()?,
                    noe: reader.u16()?,
                    int: reader.u16()?,
                    time: reader.cp32()?,
                }
            }
            (27, Direction::Monitor) => {
                reader.u8()?; // not used
                Body::ChannelReady {
                    tov: reader.u8()?,
                    fan: reader.u16()?,
                    acc: reader.u8()?,
                    rpv: reader.f32()?,
                    rsv: reader.f32()?,
                    rfa: reader.f32()?,
                }
            }
            (28, Direction::Monitor) => {
                reader.take(2)?; // not used
                Body::TagsReady { fan: reader.u16()? }
            }
            (29, Direction::Monitor) => {
                let fan = reader.u16()?;
                let not = reader.u8()?;
                let tap = reader.u16()?;
                let mut tags = Vec::with_capacity(usize::from(not));
                for _ in 0..not {
                    tags.push(DisturbanceTag {
                        fun: reader.u8()?,
                        inf: reader.u8()?,
                        dpi: reader.u8()?,
                    });
                }
                Body::Tags { fan, tap, tags }
            }
            (30, Direction::Monitor) => {
                reader.u8()?; // not used
                let tov = reader.u8()?;
                let fan = reader.u16()?;
                let acc = reader.u8()?;
                let ndv = reader.u8()?;
                let nfe = reader.u16()?;
                let mut values = Vec::with_capacity(usize::from(ndv));
                for _ in 0..ndv {
                    values.push(reader.i16()?);
                }
                Body::DisturbanceValues {
                    tov,
                    fan,
                    acc,
                    nfe,
                    values,
                }
            }
            (31, Direction::Monitor) => Body::EndOfTransmission {
                too: reader.u8()?,
                tov: reader.u8()?,
                fan: reader.u16()?,
                acc: reader.u8()?,
            },
            _ => Body::Other(reader.rest()),
        };
        reader.finish()?;
        Ok(Asdu { header, body })
    }

    /// Appends the ASDU's octets. The VSQ of element lists (9, 23) is the count with
    /// SQ = 0: one information object (one FUN/INF) holding that many elements, as relays
    /// and masters in the field send and expect them (ABB's and Beckhoff's manuals; an
    /// independent master drops the connection on SQ = 1). Decoding accepts both. The
    /// others are sent as given in the header.
    pub fn encode(&self, out: &mut Vec<u8>) -> Result<(), EncodeError> {
        let header = &self.header;
        let vsq = match &self.body {
            Body::Measurands(values) if header.type_id == 9 => {
                count_in_vsq(header.type_id, values.len(), 127)?
            }
            Body::DisturbanceList(records) => count_in_vsq(header.type_id, records.len(), 127)?,
            _ => header.vsq,
        };
        out.extend_from_slice(&[
            header.type_id,
            vsq,
            header.cause.0,
            header.common_address,
            header.fun,
            header.inf,
        ]);
        match &self.body {
            Body::TimeTagged { dpi, time, sin } => {
                out.push(*dpi);
                time.encode(out);
                out.push(*sin);
            }
            Body::TimeTaggedRelative {
                dpi,
                ret,
                fan,
                time,
                sin,
            } => {
                out.push(*dpi);
                out.extend_from_slice(&ret.to_le_bytes());
                out.extend_from_slice(&fan.to_le_bytes());
                time.encode(out);
                out.push(*sin);
            }
            Body::Measurands(values) => {
                for value in values {
                    out.extend_from_slice(&value.word().to_le_bytes());
                }
            }
            Body::TimeTaggedMeasurand {
                value,
                ret,
                fan,
                time,
            } => {
                out.extend_from_slice(&value.to_le_bytes());
                out.extend_from_slice(&ret.to_le_bytes());
                out.extend_from_slice(&fan.to_le_bytes());
                time.encode(out);
            }
            Body::Identification {
                col,
                text,
                software,
            } => {
                out.push(*col);
                out.extend_from_slice(text);
                out.extend_from_slice(software);
            }
            Body::TimeSync { time } => time.encode(out),
            Body::GiInitiation { scn } | Body::GiTermination { scn } => out.push(*scn),
            Body::GenericData { rii, ngd, data } => {
                out.extend_from_slice(&[*rii, *ngd]);
                out.extend_from_slice(data);
            }
            Body::GenericIdentification { rii, data } => {
                out.push(*rii);
                out.extend_from_slice(data);
            }
            Body::GeneralCommand { dco, rii } => out.extend_from_slice(&[*dco, *rii]),
            Body::GenericCommand { rii, items } => {
                let nog = count_in_vsq(header.type_id, items.len(), 255)?;
                out.extend_from_slice(&[*rii, nog]);
                for (gin, kod) in items {
                    out.extend_from_slice(&gin.to_le_bytes());
                    out.push(*kod);
                }
            }
            Body::DisturbanceList(records) => {
                for record in records {
                    out.extend_from_slice(&record.fan.to_le_bytes());
                    out.push(record.sof);
                    record.time.encode(out);
                }
            }
            Body::DisturbanceOrder { too, tov, fan, acc }
            | Body::DisturbanceAck { too, tov, fan, acc }
            | Body::EndOfTransmission { too, tov, fan, acc } => {
                out.extend_from_slice(&[*too, *tov]);
                out.extend_from_slice(&fan.to_le_bytes());
                out.push(*acc);
            }
            Body::DisturbanceReady {
                tov,
                fan,
                nof,
                noc,
                noe,
                int,
                time,
            } => {
                out.extend_from_slice(&[0, *tov]);
                out.extend_from_slice(&fan.to_le_bytes());
                out.extend_from_slice(&nof.to_le_bytes());
                out.push(*noc);
                out.extend_from_slice(&noe.to_le_bytes());
                out.extend_from_slice(&int.to_le_bytes());
                time.encode(out);
            }
            Body::ChannelReady {
                tov,
                fan,
                acc,
                rpv,
                rsv,
                rfa,
            } => {
                out.extend_from_slice(&[0, *tov]);
                out.extend_from_slice(&fan.to_le_bytes());
                out.push(*acc);
                for value in [rpv, rsv, rfa] {
                    out.extend_from_slice(&value.to_le_bytes());
                }
            }
            Body::TagsReady { fan } => {
                out.extend_from_slice(&[0, 0]);
                out.extend_from_slice(&fan.to_le_bytes());
            }
            Body::Tags { fan, tap, tags } => {
                let not = count_in_vsq(header.type_id, tags.len(), 255)?;
                out.extend_from_slice(&fan.to_le_bytes());
                out.push(not);
                out.extend_from_slice(&tap.to_le_bytes());
                for tag in tags {
                    out.extend_from_slice(&[tag.fun, tag.inf, tag.dpi]);
                }
            }
            Body::DisturbanceValues {
                tov,
                fan,
                acc,
                nfe,
                values,
            } => {
                let ndv = count_in_vsq(header.type_id, values.len(), 255)?;
                out.extend_from_slice(&[0, *tov]);
                out.extend_from_slice(&fan.to_le_bytes());
                out.extend_from_slice(&[*acc, ndv]);
                out.extend_from_slice(&nfe.to_le_bytes());
                for value in values {
                    out.extend_from_slice(&value.to_le_bytes());
                }
            }
            Body::Other(data) => out.extend_from_slice(data),
        }
        Ok(())
    }

    /// The ASDU's octets.
    pub fn to_bytes(&self) -> Result<Vec<u8>, EncodeError> {
        let mut out = Vec::new();
        self.encode(&mut out)?;
        Ok(out)
    }

    /// The identification text of ASDU 5 (8 characters and the 4 of the software id,
    /// as test tools show them: `REF630 11.3.`).
    pub fn identification_text(&self) -> Option<String> {
        match &self.body {
            Body::Identification { text, software, .. } => Some(
                text.iter()
                    .chain(software)
                    .map(|octet| match *octet {
                        0x20..=0x7E => char::from(*octet),
                        _ => '.',
                    })
                    .collect(),
            ),
            _ => None,
        }
    }
}

fn count_in_vsq(type_id: u8, count: usize, max: usize) -> Result<u8, EncodeError> {
    if count > max {
        return Err(EncodeError::TooMany {
            type_id,
            count,
            max,
        });
    }
    u8::try_from(count).map_err(|_| EncodeError::TooMany {
        type_id,
        count,
        max,
    })
}

/// The name of a type identification.
pub fn type_name(type_id: u8, direction: Direction) -> &'static str {
    match (type_id, direction) {
        (1, _) => "time-tagged message",
        (2, _) => "time-tagged message with relative time",
        (3, _) => "measurands I",
        (4, _) => "time-tagged measurands with relative time",
        (5, _) => "identification",
        (6, _) => "time synchronisation",
        (7, _) => "general interrogation",
        (8, _) => "termination of general interrogation",
        (9, _) => "measurands II",
        (10, _) => "generic data",
        (11, _) => "generic identification",
        (20, _) => "general command",
        (21, _) => "generic command",
        (23, _) => "list of recorded disturbances",
        (24, _) => "order for disturbance data transmission",
        (25, _) => "acknowledgement for disturbance data transmission",
        (26, _) => "ready for transmission of disturbance data",
        (27, _) => "ready for transmission of a channel",
        (28, _) => "ready for transmission of tags",
        (29, _) => "transmission of tags",
        (30, _) => "transmission of disturbance values",
        (31, _) => "end of transmission",
        _ => "unknown type",
    }
}

/// The text of a double point as protection tools print it.
pub fn dpi_text(dpi: u8) -> &'static str {
    match dpi & 0x03 {
        1 => "Off",
        2 => "On",
        0 => "transient",
        _ => "indeterminate",
    }
}

impl fmt::Display for Asdu {
    /// One line: `ASDU 1 GI (9) CA 1 FUN 1 INF 160 On 08:28:32.666 [IV] SIN 2`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let h = &self.header;
        write!(
            f,
            "ASDU {} {} ({}) CA {} FUN {} INF {}",
            h.type_id,
            h.cause.mnemonic(),
            h.cause.0,
            h.common_address,
            h.fun,
            h.inf
        )?;
        match &self.body {
            Body::TimeTagged { dpi, time, sin } => {
                write!(f, " {} {time} SIN {sin}", dpi_text(*dpi))
            }
            Body::TimeTaggedRelative {
                dpi,
                ret,
                fan,
                time,
                sin,
            } => write!(
                f,
                " {} {time} RET {ret} ms FAN {fan} SIN {sin}",
                dpi_text(*dpi)
            ),
            Body::Measurands(values) => {
                for value in values {
                    write!(f, " {value}")?;
                }
                Ok(())
            }
            Body::TimeTaggedMeasurand {
                value,
                ret,
                fan,
                time,
            } => write!(f, " {value} {time} RET {ret} ms FAN {fan}"),
            Body::Identification { col, .. } => write!(
                f,
                " Comp: {col} String: >{}<",
                self.identification_text().unwrap_or_default()
            ),
            Body::TimeSync { time } => write!(f, " {time}"),
            Body::GiInitiation { scn } | Body::GiTermination { scn } => write!(f, " SCN {scn}"),
            Body::GenericData { rii, ngd, data } => {
                write!(f, " RII {rii} NGD {ngd:#04x} {} octets", data.len())
            }
            Body::GenericIdentification { rii, data } => {
                write!(f, " RII {rii} {} octets", data.len())
            }
            Body::GeneralCommand { dco, rii } => write!(f, " {} RII {rii}", dpi_text(*dco)),
            Body::GenericCommand { rii, items } => {
                write!(f, " RII {rii}")?;
                for (gin, kod) in items {
                    write!(f, " GIN {:02X}.{:02X} KOD {kod}", gin & 0xFF, gin >> 8)?;
                }
                Ok(())
            }
            Body::DisturbanceList(records) => {
                for record in records {
                    write!(
                        f,
                        " [FAN {} SOF {:#04x} {}]",
                        record.fan, record.sof, record.time
                    )?;
                }
                Ok(())
            }
            Body::DisturbanceOrder { too, tov, fan, acc }
            | Body::DisturbanceAck { too, tov, fan, acc }
            | Body::EndOfTransmission { too, tov, fan, acc } => {
                write!(f, " TOO {too} TOV {tov} FAN {fan} ACC {acc}")
            }
            Body::DisturbanceReady {
                tov,
                fan,
                nof,
                noc,
                noe,
                int,
                time,
            } => write!(
                f,
                " TOV {tov} FAN {fan} NOF {nof} NOC {noc} NOE {noe} INT {int} us {time}"
            ),
            Body::ChannelReady {
                tov,
                fan,
                acc,
                rpv,
                rsv,
                rfa,
            } => write!(
                f,
                " TOV {tov} FAN {fan} ACC {acc} RPV {rpv} RSV {rsv} RFA {rfa}"
            ),
            Body::TagsReady { fan } => write!(f, " FAN {fan}"),
            Body::Tags { fan, tap, tags } => {
                write!(f, " FAN {fan} TAP {tap}")?;
                for tag in tags {
                    write!(f, " [{}/{} {}]", tag.fun, tag.inf, dpi_text(tag.dpi))?;
                }
                Ok(())
            }
            Body::DisturbanceValues {
                tov,
                fan,
                acc,
                nfe,
                values,
            } => write!(
                f,
                " TOV {tov} FAN {fan} ACC {acc} NFE {nfe} {} values",
                values.len()
            ),
            Body::Other(data) => write!(f, " {} octets", data.len()),
        }
    }
}
