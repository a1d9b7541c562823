//! The ASDU: header, decoding, encoding and display.

use std::fmt;

use super::object::{decode_element, encode_element, Reader};
use super::{
    AsduError, AsduParams, Cause, CommonAddress, Cot, InformationObject, Ioa, TimeTagKind, TypeId,
};

/// The fixed part of an ASDU, decodable whatever the type identification, so that a
/// station can answer an unknown type (COT 44), cause (45) or common address (46) by
/// mirroring the request.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct AsduHeader {
    /// The type identification octet as received (it may be undefined).
    pub type_byte: u8,
    /// SQ: one address for a sequence of elements.
    pub sequence: bool,
    /// Number of objects (SQ = 0) or elements (SQ = 1), 0..127.
    pub count: u8,
    /// Cause of transmission.
    pub cot: Cot,
    /// Common address.
    pub common_address: CommonAddress,
}

impl AsduHeader {
    /// Octets of the header for the link: type, VSQ, COT and common address.
    pub fn header_len(params: &AsduParams) -> usize {
        params.header_len()
    }

    /// The type identification, `None` when the standard does not define `type_byte`.
    pub fn type_id(&self) -> Option<TypeId> {
        TypeId::from_u8(self.type_byte)
    }

    /// Decodes the header from the start of `bytes` (the objects are not looked at).
    pub fn decode(bytes: &[u8], params: &AsduParams) -> Result<AsduHeader, AsduError> {
        let header_len = params.header_len();
        let header = bytes.get(..header_len).ok_or(AsduError::Truncated {
            needed: header_len,
            available: bytes.len(),
        })?;
        let mut reader = Reader::new(header, header_len);
        let [type_byte, vsq, cot_octet] = reader.take()?;
        let originator = if params.cot_size() == 2 {
            let [originator] = reader.take()?;
            originator
        } else {
            0
        };
        let common_address = if params.common_address_size() == 2 {
            u16::from_le_bytes(reader.take()?)
        } else {
            let [low] = reader.take()?;
            low.into()
        };
        Ok(AsduHeader {
            type_byte,
            sequence: vsq & 0x80 != 0,
            count: vsq & 0x7F,
            cot: Cot::from_octets(cot_octet, originator),
            common_address: CommonAddress::new(common_address),
        })
    }

    /// Appends the header octets. Fails when the common address or originator do not fit
    /// the link's fields, or `count` exceeds 127.
    pub fn encode(&self, params: &AsduParams, out: &mut Vec<u8>) -> Result<(), AsduError> {
        if self.count > 127 {
            return Err(AsduError::TooManyObjects(self.count.into()));
        }
        check_header_fields(&self.cot, self.common_address, params)?;
        out.push(self.type_byte);
        out.push(self.count | if self.sequence { 0x80 } else { 0 });
        out.push(self.cot.octet());
        if params.cot_size() == 2 {
            out.push(self.cot.originator);
        }
        let [low, high] = self.common_address.get().to_le_bytes();
        out.push(low);
        if params.common_address_size() == 2 {
            out.push(high);
        }
        Ok(())
    }
}

fn check_header_fields(
    cot: &Cot,
    common_address: CommonAddress,
    params: &AsduParams,
) -> Result<(), AsduError> {
    if common_address.get() > params.max_common_address() {
        return Err(AsduError::CommonAddressTooLarge {
            address: common_address,
            size: params.common_address_size(),
        });
    }
    if params.cot_size() == 1 && cot.originator != 0 {
        return Err(AsduError::OriginatorNotEncodable(cot.originator));
    }
    Ok(())
}

impl fmt::Display for AsduHeader {
    /// `M_DP_TB_1 (31) [sq=0 n=1] cot=spont(3) [tst pn] oa=0 ca=1`; an undefined type
    /// shows as `unknown (22)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.type_id() {
            Some(type_id) => write!(f, "{type_id} ({})", self.type_byte)?,
            None => write!(f, "unknown ({})", self.type_byte)?,
        }
        write!(
            f,
            " [sq={} n={}] cot={} ca={}",
            u8::from(self.sequence),
            self.count,
            self.cot,
            self.common_address
        )
    }
}

/// Octets one object of `type_id` adds to an ASDU: IOA + element + time tag with
/// `sequence == false`, element + time tag only with `sequence == true` (the single IOA of
/// an SQ = 1 ASDU is counted in neither). For F_SG_NA_1 this is the length with an empty
/// segment: add the segment's data length.
pub fn object_len(type_id: TypeId, params: &AsduParams, sequence: bool) -> usize {
    let element = type_id.element_len().unwrap_or(4);
    if sequence {
        element
    } else {
        usize::from(params.ioa_size()) + element
    }
}

/// Copies a received ASDU, changing only its cause and P/N bit (T and the originator
/// address are kept, so that the reply reaches the station that asked). Used to confirm
/// commands (COT 7, 9, 10) and to refuse them (COT 44..47 with `negative`), whatever the
/// type identification.
pub fn mirror_with_cause(
    raw_asdu: &[u8],
    params: &AsduParams,
    cause: Cause,
    negative: bool,
) -> Result<Vec<u8>, AsduError> {
    let header = AsduHeader::decode(raw_asdu, params)?;
    let cot = Cot {
        cause,
        negative,
        ..header.cot
    };
    let mut out = raw_asdu.to_vec();
    if let Some(octet) = out.get_mut(2) {
        *octet = cot.octet();
    }
    Ok(out)
}

/// An application service data unit: one type identification, one cause, one common
/// address and 1..127 information objects.
///
/// With `sequence == true` (SQ = 1) the objects must have consecutive addresses; they are
/// sent as one address followed by the elements. Decoding SQ = 1 gives every object its
/// own address (base + index).
#[derive(Debug, Clone, PartialEq)]
pub struct Asdu {
    /// Type identification of all objects.
    pub type_id: TypeId,
    /// SQ.
    pub sequence: bool,
    /// Cause of transmission.
    pub cot: Cot,
    /// Common address.
    pub common_address: CommonAddress,
    /// The objects, in wire order.
    pub objects: Vec<InformationObject>,
}

impl Asdu {
    /// An empty ASDU (SQ = 0); add objects with [`Asdu::push`] or [`Asdu::with_object`].
    pub fn new(type_id: TypeId, cot: impl Into<Cot>, common_address: CommonAddress) -> Asdu {
        Asdu {
            type_id,
            sequence: false,
            cot: cot.into(),
            common_address,
            objects: Vec::new(),
        }
    }

    /// Adds an object.
    pub fn push(&mut self, object: InformationObject) -> &mut Asdu {
        self.objects.push(object);
        self
    }

    /// The ASDU with one more object.
    #[must_use]
    pub fn with_object(mut self, object: InformationObject) -> Asdu {
        self.objects.push(object);
        self
    }

    /// The ASDU with SQ set or cleared.
    #[must_use]
    pub fn with_sequence(mut self, sequence: bool) -> Asdu {
        self.sequence = sequence;
        self
    }

    /// The header this ASDU encodes to (the count saturates at 255; encoding refuses
    /// more than 127 objects).
    pub fn header(&self) -> AsduHeader {
        AsduHeader {
            type_byte: self.type_id.value(),
            sequence: self.sequence,
            count: u8::try_from(self.objects.len()).unwrap_or(u8::MAX),
            cot: self.cot,
            common_address: self.common_address,
        }
    }

    /// Decodes one ASDU that fills `bytes` exactly.
    ///
    /// Errors: [`AsduError::Truncated`] for a short header (or an SQ = 1 ASDU without room
    /// for its address), [`AsduError::UnknownTypeId`], [`AsduError::NoObjects`],
    /// [`AsduError::ObjectCountMismatch`] when the payload is shorter than the VSQ count
    /// needs, [`AsduError::TrailingBytes`] when it is longer, [`AsduError::IoaOverflow`]
    /// for SQ = 1 running past the address range, [`AsduError::Time`] for time fields out
    /// of range. The link's [`AsduParams::max_asdu_len`] is not enforced here (the
    /// framing layer bounds what arrives); [`Asdu::encode`] enforces it.
    pub fn decode(bytes: &[u8], params: &AsduParams) -> Result<Asdu, AsduError> {
        let header = AsduHeader::decode(bytes, params)?;
        let header_len = params.header_len();
        let type_id = header
            .type_id()
            .ok_or(AsduError::UnknownTypeId(header.type_byte))?;
        if header.count == 0 {
            return Err(AsduError::NoObjects);
        }
        let payload = bytes.get(header_len..).unwrap_or_default();
        let ioa_size = usize::from(params.ioa_size());
        let count = usize::from(header.count);
        if header.sequence && payload.len() < ioa_size {
            return Err(AsduError::Truncated {
                needed: header_len + ioa_size,
                available: bytes.len(),
            });
        }
        match type_id.element_len() {
            Some(element_len) => {
                let expected = if header.sequence {
                    ioa_size + count * element_len
                } else {
                    count * (ioa_size + element_len)
                };
                if payload.len() < expected {
                    return Err(AsduError::ObjectCountMismatch {
                        count: header.count,
                        expected: header_len + expected,
                        actual: bytes.len(),
                    });
                }
                if payload.len() > expected {
                    return Err(AsduError::TrailingBytes(payload.len() - expected));
                }
            }
            None if header.sequence => return Err(AsduError::SequenceNotAllowed(type_id)),
            None => {}
        }

        let mut reader = Reader::new(payload, bytes.len());
        // Bounded by 127 whatever the input says.
        let mut objects = Vec::with_capacity(count);
        if header.sequence {
            let base = read_ioa(&mut reader, params)?;
            let last = u32::from(header.count) - 1;
            if base
                .checked_add(last)
                .is_none_or(|ioa| ioa.get() > params.max_ioa())
            {
                return Err(AsduError::IoaOverflow {
                    base: base.get(),
                    count: header.count,
                });
            }
            for offset in 0..u32::from(header.count) {
                let (element, time) = decode_element(type_id, &mut reader)?;
                let ioa = base.checked_add(offset).unwrap_or(base);
                objects.push(InformationObject { ioa, element, time });
            }
        } else {
            for _ in 0..count {
                let ioa = read_ioa(&mut reader, params)?;
                let (element, time) = decode_element(type_id, &mut reader)?;
                objects.push(InformationObject { ioa, element, time });
            }
        }
        if reader.remaining() > 0 {
            return Err(AsduError::TrailingBytes(reader.remaining()));
        }
        Ok(Asdu {
            type_id,
            sequence: header.sequence,
            cot: header.cot,
            common_address: header.common_address,
            objects,
        })
    }

    /// Octets this ASDU encodes to (assuming it is valid).
    pub fn encoded_len(&self, params: &AsduParams) -> usize {
        let ioa_size = usize::from(params.ioa_size());
        let elements: usize = self
            .objects
            .iter()
            .map(|object| object.element.wire_len(self.type_id))
            .sum();
        let addresses = if self.sequence {
            ioa_size
        } else {
            ioa_size * self.objects.len()
        };
        params.header_len() + addresses + elements
    }

    /// Checks everything [`Asdu::encode`] checks, without encoding.
    pub fn validate(&self, params: &AsduParams) -> Result<(), AsduError> {
        if self.objects.is_empty() {
            return Err(AsduError::NoObjects);
        }
        if self.objects.len() > 127 {
            return Err(AsduError::TooManyObjects(self.objects.len()));
        }
        check_header_fields(&self.cot, self.common_address, params)?;
        if self.sequence && self.type_id.element_len().is_none() {
            return Err(AsduError::SequenceNotAllowed(self.type_id));
        }
        let wanted_time = self.type_id.time_tag();
        let mut expected_ioa = self.objects.first().map(|object| object.ioa.get());
        for object in &self.objects {
            if !object.element.family_matches(self.type_id) {
                return Err(AsduError::ElementMismatch {
                    type_id: self.type_id,
                    ioa: object.ioa,
                });
            }
            let time = object.time.as_ref().map(|time| time.kind());
            if time.unwrap_or(TimeTagKind::None) != wanted_time {
                return Err(AsduError::TimeTagMismatch {
                    type_id: self.type_id,
                    ioa: object.ioa,
                });
            }
            if object.ioa.get() > params.max_ioa() {
                return Err(AsduError::IoaTooLarge {
                    ioa: object.ioa,
                    size: params.ioa_size(),
                });
            }
            if self.sequence {
                if let Some(expected) = expected_ioa {
                    if object.ioa.get() != expected {
                        return Err(AsduError::NotConsecutive {
                            expected,
                            found: object.ioa,
                        });
                    }
                }
                expected_ioa = object.ioa.get().checked_add(1);
            }
        }
        let len = self.encoded_len(params);
        if len > params.max_asdu_len() {
            return Err(AsduError::TooLong {
                len,
                max: params.max_asdu_len(),
            });
        }
        Ok(())
    }

    /// Appends the encoded ASDU to `out`. On error `out` is left as it was.
    ///
    /// Checks: 1..127 objects, every element of the type's family with the type's time tag,
    /// consecutive addresses for SQ = 1, addresses and common address within the link's
    /// field sizes, originator 0 with a one-octet COT, element values within their fields,
    /// and the encoded length within [`AsduParams::max_asdu_len`].
    pub fn encode(&self, params: &AsduParams, out: &mut Vec<u8>) -> Result<(), AsduError> {
        self.validate(params)?;
        let start = out.len();
        out.reserve(self.encoded_len(params));
        let result = self.encode_unchecked(params, out);
        if result.is_err() {
            out.truncate(start);
        }
        result
    }

    /// Encodes into a new vector.
    pub fn to_bytes(&self, params: &AsduParams) -> Result<Vec<u8>, AsduError> {
        let mut out = Vec::with_capacity(self.encoded_len(params));
        self.encode(params, &mut out)?;
        Ok(out)
    }

    fn encode_unchecked(&self, params: &AsduParams, out: &mut Vec<u8>) -> Result<(), AsduError> {
        self.header().encode(params, out)?;
        for (index, object) in self.objects.iter().enumerate() {
            if index == 0 || !self.sequence {
                write_ioa(object.ioa, params, out);
            }
            encode_element(self.type_id, &object.element, out)?;
            match &object.time {
                Some(super::TimeTag::Cp24(time)) => time.encode(out),
                Some(super::TimeTag::Cp56(time)) => time.encode(out),
                None => {}
            }
        }
        Ok(())
    }
}

fn read_ioa(reader: &mut Reader<'_>, params: &AsduParams) -> Result<Ioa, AsduError> {
    let value = match params.ioa_size() {
        1 => {
            let [a] = reader.take()?;
            u32::from(a)
        }
        2 => u32::from(u16::from_le_bytes(reader.take()?)),
        _ => {
            let [a, b, c] = reader.take()?;
            u32::from_le_bytes([a, b, c, 0])
        }
    };
    // At most 24 bits were read, so this cannot fail; the fallback keeps it panic-free.
    Ok(Ioa::try_new(value).unwrap_or(Ioa::MAX))
}

fn write_ioa(ioa: Ioa, params: &AsduParams, out: &mut Vec<u8>) {
    let bytes = ioa.get().to_le_bytes();
    let size = usize::from(params.ioa_size());
    out.extend(bytes.iter().take(size));
}

impl fmt::Display for Asdu {
    /// A protocol-analyser log entry: the header line, then one line per object.
    ///
    /// ```text
    /// M_DP_TB_1 (31) [sq=0 n=1] cot=spont(3) [tst pn] oa=0 ca=1
    ///   ioa=2000 DP OFF [iv nt sb bl] 2017-04-26 09:59:30.424 [IV]
    /// ```
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.header().fmt(f)?;
        for object in &self.objects {
            write!(f, "\n  {object}")?;
        }
        Ok(())
    }
}
