//! S7comm PDUs (protocol id 0x32): the header, setup communication, read var and write
//! var, as carried in COTP data TPDUs.
//!
//! ```text
//! header   32 | ROSCTR | 00 00 | PDU ref(2) | param len(2) | data len(2) [| err class | err code]
//!          (ROSCTR 1 job and 7 userdata: 10 bytes; 2 ack and 3 ack_data: 12 with the error)
//! setup    F0 00 | max AmQ calling(2) | max AmQ called(2) | PDU size(2)
//! read     param: 04 | n | n x item spec        data (ack_data): n x data item
//! write    param: 05 | n | n x item spec        data (job): n x data item; ack_data: n x code
//! item     12 0A 10 | transport size | count(2) | DB(2) | area | bit address(3)
//! data     return code | transport size | length(2, bits or bytes) | data [| fill to even]
//! ```
//!
//! The fill byte follows every data item of odd length except the last. Decoding takes
//! what real PLCs and clients send (a job's item with a return code of 0x00, an error
//! item without data); it never panics, whatever the input.

use std::fmt;

use thiserror::Error;

use crate::address::{Area, Region, MAX_BYTE};
use crate::wire::{put_u24, Reader};

/// The first byte of every S7comm PDU.
pub const PROTOCOL_ID: u8 = 0x32;
/// The header of a job or userdata PDU.
pub const JOB_HEADER_LEN: usize = 10;
/// The header of an ack or ack_data PDU (with the error class and code).
pub const ACK_HEADER_LEN: usize = 12;
/// The function code and item count at the start of a read or write var parameter.
pub const VAR_PARAMETER_HEAD_LEN: usize = 2;
/// One S7ANY item specification.
pub const ITEM_SPEC_LEN: usize = 12;
/// A data item's return code, transport size and length.
pub const DATA_ITEM_HEADER_LEN: usize = 4;
/// The most items one read or write var PDU carries: what S7-300/400 CPUs take.
pub const MAX_ITEMS: usize = 20;

/// Function codes.
pub mod function {
    /// Read var.
    pub const READ_VAR: u8 = 0x04;
    /// Write var.
    pub const WRITE_VAR: u8 = 0x05;
    /// Setup communication.
    pub const SETUP_COMMUNICATION: u8 = 0xF0;
}

/// Message types (ROSCTR).
pub mod rosctr {
    /// A request.
    pub const JOB: u8 = 1;
    /// An acknowledgement without data.
    pub const ACK: u8 = 2;
    /// The answer to a job.
    pub const ACK_DATA: u8 = 3;
    /// Extended services (SZL, clock, blocks), not served here.
    pub const USER_DATA: u8 = 7;
}

/// The error class and code of an ack or ack_data header; class 0 is success.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ErrorCode {
    /// The class: 0x81 application relationship, 0x82 object definition, 0x83 no
    /// resources, 0x84 service processing, 0x85 supplies, 0x87 access.
    pub class: u8,
    /// The code within the class.
    pub code: u8,
}

impl ErrorCode {
    /// No error.
    pub const NONE: ErrorCode = ErrorCode { class: 0, code: 0 };
    /// A function this end does not implement.
    pub const FUNCTION_NOT_IMPLEMENTED: ErrorCode = ErrorCode {
        class: 0x81,
        code: 0x04,
    };
    /// A request, or its answer, larger than the negotiated PDU size.
    pub const PDU_SIZE: ErrorCode = ErrorCode {
        class: 0x85,
        code: 0x00,
    };
    /// A job before setup communication, or one that cannot be decoded.
    pub const INVALID_REQUEST: ErrorCode = ErrorCode {
        class: 0x84,
        code: 0x04,
    };

    /// Whether the header reports an error.
    pub fn is_error(&self) -> bool {
        self.class != 0 || self.code != 0
    }
}

/// `0x8104`, as Siemens documents them.
impl fmt::Display for ErrorCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:#04x}{:02x}", self.class, self.code)
    }
}

/// Setup communication, asked in a job and granted in its ack_data.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SetupCommunication {
    /// Jobs the calling end may have open at once.
    pub max_amq_calling: u16,
    /// Jobs the called end may have open at once.
    pub max_amq_called: u16,
    /// The largest S7 PDU either end sends, header included.
    pub pdu_size: u16,
}

/// The transport size of an item specification: the element the count counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TransportSize {
    /// 0x01: bits.
    Bit,
    /// 0x02: bytes.
    Byte,
    /// 0x03: characters (bytes).
    Char,
    /// 0x04: words.
    Word,
    /// 0x05: INTs.
    Int,
    /// 0x06: double words.
    DWord,
    /// 0x07: DINTs.
    DInt,
    /// 0x08: REALs.
    Real,
    /// Another (timers, counters, dates): not served here.
    Other(u8),
}

impl TransportSize {
    /// From the wire.
    pub fn from_code(code: u8) -> TransportSize {
        match code {
            0x01 => TransportSize::Bit,
            0x02 => TransportSize::Byte,
            0x03 => TransportSize::Char,
            0x04 => TransportSize::Word,
            0x05 => TransportSize::Int,
            0x06 => TransportSize::DWord,
            0x07 => TransportSize::DInt,
            0x08 => TransportSize::Real,
            other => TransportSize::Other(other),
        }
    }

    /// To the wire.
    pub fn code(self) -> u8 {
        match self {
            TransportSize::Bit => 0x01,
            TransportSize::Byte => 0x02,
            TransportSize::Char => 0x03,
            TransportSize::Word => 0x04,
            TransportSize::Int => 0x05,
            TransportSize::DWord => 0x06,
            TransportSize::DInt => 0x07,
            TransportSize::Real => 0x08,
            TransportSize::Other(code) => code,
        }
    }

    /// Bytes per element, `None` for bits and the sizes not served.
    pub fn element_size(self) -> Option<u32> {
        match self {
            TransportSize::Byte | TransportSize::Char => Some(1),
            TransportSize::Word | TransportSize::Int => Some(2),
            TransportSize::DWord | TransportSize::DInt | TransportSize::Real => Some(4),
            TransportSize::Bit | TransportSize::Other(_) => None,
        }
    }

    /// The transport size a data item of this element type travels with in an answer.
    pub fn data_transport(self) -> DataTransport {
        match self {
            TransportSize::Bit => DataTransport::Bit,
            TransportSize::Int | TransportSize::DInt => DataTransport::Integer,
            TransportSize::Real => DataTransport::Real,
            TransportSize::Byte
            | TransportSize::Char
            | TransportSize::Word
            | TransportSize::DWord => DataTransport::Bytes,
            TransportSize::Other(_) => DataTransport::OctetString,
        }
    }
}

/// An S7ANY item specification (syntax id 0x10): what a read or write var item
/// addresses. Area and transport size stay as received so that a server can answer an
/// item it does not serve with a return code instead of refusing the whole job.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ItemSpec {
    /// The element type.
    pub transport_size: TransportSize,
    /// How many elements.
    pub count: u16,
    /// The data block number, 0 outside data blocks.
    pub db_number: u16,
    /// The area code (0x81 I, 0x82 Q, 0x83 M, 0x84 DB, others not served).
    pub area_code: u8,
    /// The bit address, byte * 8 + bit, 24 bits.
    pub bit_address: u32,
}

impl ItemSpec {
    /// The item for a region: a bit as one `Bit`, bytes as `Byte`s (how S7 clients read
    /// any size: the count is the byte count, and a long run can be cut anywhere).
    /// `None` for an invalid region or one of more than 65535 bytes.
    pub fn for_region(region: &Region) -> Option<ItemSpec> {
        region.validate().ok()?;
        if region.data_len() > u32::from(u16::MAX) {
            return None;
        }
        Some(ItemSpec::for_piece(region))
    }

    /// [`ItemSpec::for_region`] for a region already checked (a piece from
    /// [`crate::split`]); out-of-range fields saturate instead of failing.
    pub(crate) fn for_piece(region: &Region) -> ItemSpec {
        let area = region.area();
        match *region {
            Region::Bit { byte, bit, .. } => ItemSpec {
                transport_size: TransportSize::Bit,
                count: 1,
                db_number: area.db_number(),
                area_code: area.code(),
                bit_address: byte.saturating_mul(8).saturating_add(u32::from(bit & 7)),
            },
            Region::Bytes { start, len, .. } => ItemSpec {
                transport_size: TransportSize::Byte,
                count: u16::try_from(len).unwrap_or(u16::MAX),
                db_number: area.db_number(),
                area_code: area.code(),
                bit_address: start.saturating_mul(8),
            },
        }
    }

    /// The region the item addresses, or the return code a server answers an item it
    /// cannot serve with: an unknown area or data block 0 does not exist (0x0A), an
    /// unknown transport size or several bits at once are not supported (0x06), a byte
    /// item at a bit offset or of no elements is out of range (0x05).
    pub fn region(&self) -> Result<Region, ReturnCode> {
        let area = Area::from_code(self.area_code, self.db_number)
            .ok_or(ReturnCode::ObjectDoesNotExist)?;
        let byte = self.bit_address >> 3;
        match self.transport_size {
            TransportSize::Bit if self.count == 1 => Ok(Region::Bit {
                area,
                byte,
                // Masked to three bits, so the cast keeps the value.
                bit: (self.bit_address & 7) as u8,
            }),
            TransportSize::Bit => Err(ReturnCode::TypeNotSupported),
            size => {
                let element = size.element_size().ok_or(ReturnCode::TypeNotSupported)?;
                if self.bit_address & 7 != 0 || self.count == 0 {
                    return Err(ReturnCode::AddressOutOfRange);
                }
                let region = Region::Bytes {
                    area,
                    start: byte,
                    len: u32::from(self.count) * element,
                };
                region
                    .validate()
                    .map_err(|_| ReturnCode::AddressOutOfRange)?;
                Ok(region)
            }
        }
    }

    fn encode(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&[0x12, 0x0A, 0x10, self.transport_size.code()]);
        out.extend_from_slice(&self.count.to_be_bytes());
        out.extend_from_slice(&self.db_number.to_be_bytes());
        out.push(self.area_code);
        put_u24(out, self.bit_address.min(MAX_BYTE * 8 + 7));
    }

    fn decode(reader: &mut Reader<'_>) -> Result<ItemSpec, PduError> {
        let specification_type = reader.u8().ok_or(PduError::Truncated)?;
        let length = reader.u8().ok_or(PduError::Truncated)?;
        let body = reader
            .take(usize::from(length))
            .ok_or(PduError::Truncated)?;
        let mut body = Reader::new(body);
        let syntax_id = body.u8().ok_or(PduError::Truncated)?;
        if specification_type != 0x12 || length != 0x0A || syntax_id != 0x10 {
            return Err(PduError::UnsupportedItem {
                specification_type,
                length,
                syntax_id,
            });
        }
        let truncated = PduError::Truncated;
        Ok(ItemSpec {
            transport_size: TransportSize::from_code(body.u8().ok_or(truncated)?),
            count: body.u16().ok_or(truncated)?,
            db_number: body.u16().ok_or(truncated)?,
            area_code: body.u8().ok_or(truncated)?,
            bit_address: body.u24().ok_or(truncated)?,
        })
    }
}

/// The return code of a data item.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ReturnCode {
    /// 0x00: what a job's write items carry.
    Reserved,
    /// 0x01.
    HardwareFault,
    /// 0x03.
    AccessDenied,
    /// 0x05: the address is beyond the area or block.
    AddressOutOfRange,
    /// 0x06.
    TypeNotSupported,
    /// 0x07: the data does not match the item (a write of the wrong length).
    TypeInconsistent,
    /// 0x0A: no such area or data block.
    ObjectDoesNotExist,
    /// 0xFF.
    Success,
    /// Another code.
    Other(u8),
}

impl ReturnCode {
    /// From the wire.
    pub fn from_code(code: u8) -> ReturnCode {
        match code {
            0x00 => ReturnCode::Reserved,
            0x01 => ReturnCode::HardwareFault,
            0x03 => ReturnCode::AccessDenied,
            0x05 => ReturnCode::AddressOutOfRange,
            0x06 => ReturnCode::TypeNotSupported,
            0x07 => ReturnCode::TypeInconsistent,
            0x0A => ReturnCode::ObjectDoesNotExist,
            0xFF => ReturnCode::Success,
            other => ReturnCode::Other(other),
        }
    }

    /// To the wire.
    pub fn code(self) -> u8 {
        match self {
            ReturnCode::Reserved => 0x00,
            ReturnCode::HardwareFault => 0x01,
            ReturnCode::AccessDenied => 0x03,
            ReturnCode::AddressOutOfRange => 0x05,
            ReturnCode::TypeNotSupported => 0x06,
            ReturnCode::TypeInconsistent => 0x07,
            ReturnCode::ObjectDoesNotExist => 0x0A,
            ReturnCode::Success => 0xFF,
            ReturnCode::Other(code) => code,
        }
    }
}

/// `0x0a (object does not exist)`.
impl fmt::Display for ReturnCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let meaning = match self {
            ReturnCode::Reserved => "reserved",
            ReturnCode::HardwareFault => "hardware fault",
            ReturnCode::AccessDenied => "access denied",
            ReturnCode::AddressOutOfRange => "address out of range",
            ReturnCode::TypeNotSupported => "data type not supported",
            ReturnCode::TypeInconsistent => "data type inconsistent",
            ReturnCode::ObjectDoesNotExist => "object does not exist",
            ReturnCode::Success => "success",
            ReturnCode::Other(_) => "unknown",
        };
        write!(f, "{:#04x} ({meaning})", self.code())
    }
}

/// The transport size of a data item, which also says how its length counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DataTransport {
    /// 0x00: no data (an item in error).
    Null,
    /// 0x03: bits; the length counts bits.
    Bit,
    /// 0x04: bytes, words, double words; the length counts bits.
    Bytes,
    /// 0x05: integers; the length counts bits.
    Integer,
    /// 0x07: reals; the length counts bytes.
    Real,
    /// 0x09: an octet string; the length counts bytes.
    OctetString,
    /// Another; taken as counting bytes.
    Other(u8),
}

impl DataTransport {
    /// From the wire.
    pub fn from_code(code: u8) -> DataTransport {
        match code {
            0x00 => DataTransport::Null,
            0x03 => DataTransport::Bit,
            0x04 => DataTransport::Bytes,
            0x05 => DataTransport::Integer,
            0x07 => DataTransport::Real,
            0x09 => DataTransport::OctetString,
            other => DataTransport::Other(other),
        }
    }

    /// To the wire.
    pub fn code(self) -> u8 {
        match self {
            DataTransport::Null => 0x00,
            DataTransport::Bit => 0x03,
            DataTransport::Bytes => 0x04,
            DataTransport::Integer => 0x05,
            DataTransport::Real => 0x07,
            DataTransport::OctetString => 0x09,
            DataTransport::Other(code) => code,
        }
    }

    fn counts_bits(self) -> bool {
        matches!(
            self,
            DataTransport::Bit | DataTransport::Bytes | DataTransport::Integer
        )
    }

    /// The length field for `byte_len` bytes of data; a single bit is length 1.
    fn length_field(self, byte_len: usize) -> Option<u16> {
        let field = match self {
            DataTransport::Bit if byte_len == 1 => 1,
            transport if transport.counts_bits() => byte_len.checked_mul(8)?,
            _ => byte_len,
        };
        u16::try_from(field).ok()
    }

    /// Bytes of data behind a length field.
    fn byte_len(self, length_field: u16) -> usize {
        if self.counts_bits() {
            usize::from(length_field).div_ceil(8)
        } else {
            usize::from(length_field)
        }
    }
}

/// A data item: a value read (ack_data of read var) or to write (job of write var).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct DataItem {
    /// Success or why not; [`ReturnCode::Reserved`] in a write job.
    pub return_code: ReturnCode,
    /// How the data travels.
    pub transport: DataTransport,
    /// The data, one byte (0 or 1) for a bit.
    pub data: Vec<u8>,
}

impl DataItem {
    /// A failed item: its code and no data.
    pub fn error(return_code: ReturnCode) -> DataItem {
        DataItem {
            return_code,
            transport: DataTransport::Null,
            data: Vec::new(),
        }
    }

    fn encode(&self, out: &mut Vec<u8>) -> Result<(), PduError> {
        let length = self
            .transport
            .length_field(self.data.len())
            .ok_or(PduError::TooLong)?;
        out.extend_from_slice(&[self.return_code.code(), self.transport.code()]);
        out.extend_from_slice(&length.to_be_bytes());
        out.extend_from_slice(&self.data);
        Ok(())
    }

    fn decode(reader: &mut Reader<'_>) -> Result<DataItem, PduError> {
        let return_code = ReturnCode::from_code(reader.u8().ok_or(PduError::Truncated)?);
        let transport = DataTransport::from_code(reader.u8().ok_or(PduError::Truncated)?);
        let length = reader.u16().ok_or(PduError::Truncated)?;
        let data = reader
            .take(transport.byte_len(length))
            .ok_or(PduError::Truncated)?;
        Ok(DataItem {
            return_code,
            transport,
            data: data.to_vec(),
        })
    }
}

/// What a job asks.
#[derive(Debug, Clone, PartialEq)]
pub enum Request {
    /// Setup communication: the client's wishes.
    SetupCommunication(SetupCommunication),
    /// Read var: the items to read.
    ReadVar(Vec<ItemSpec>),
    /// Write var: items and their data.
    WriteVar(Vec<(ItemSpec, DataItem)>),
    /// Another function, kept raw.
    Other {
        /// The function code.
        function: u8,
        /// The parameter after the function code.
        parameter: Vec<u8>,
        /// The data.
        data: Vec<u8>,
    },
}

/// What an ack_data answers.
#[derive(Debug, Clone, PartialEq)]
pub enum Response {
    /// No parameter: an error answer.
    None,
    /// Setup communication: what was granted.
    SetupCommunication(SetupCommunication),
    /// Read var: one data item per item asked, in order.
    ReadVar(Vec<DataItem>),
    /// Write var: one return code per item written, in order.
    WriteVar(Vec<ReturnCode>),
    /// Another function, kept raw.
    Other {
        /// The function code.
        function: u8,
        /// The parameter after the function code.
        parameter: Vec<u8>,
        /// The data.
        data: Vec<u8>,
    },
}

/// One S7comm PDU.
#[derive(Debug, Clone, PartialEq)]
pub enum Pdu {
    /// ROSCTR 1: a request.
    Job {
        /// Matches the answer to the request.
        pdu_ref: u16,
        /// What is asked.
        request: Request,
    },
    /// ROSCTR 2: an acknowledgement without data, with an error or without.
    Ack {
        /// The job's reference.
        pdu_ref: u16,
        /// The error, [`ErrorCode::NONE`] if none.
        error: ErrorCode,
    },
    /// ROSCTR 3: the answer to a job.
    AckData {
        /// The job's reference.
        pdu_ref: u16,
        /// The error, [`ErrorCode::NONE`] if none.
        error: ErrorCode,
        /// The answer.
        response: Response,
    },
    /// ROSCTR 7: extended services, kept raw.
    UserData {
        /// The reference.
        pdu_ref: u16,
        /// The parameter.
        parameter: Vec<u8>,
        /// The data.
        data: Vec<u8>,
    },
}

/// A PDU that cannot be decoded or encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum PduError {
    /// Fewer bytes than the header or its lengths promise.
    #[error("truncated S7 PDU")]
    Truncated,
    /// Not 0x32.
    #[error("S7 protocol id {0:#04x}, expected 0x32")]
    BadProtocolId(u8),
    /// A message type other than 1, 2, 3 or 7.
    #[error("unknown S7 message type (ROSCTR) {0}")]
    UnknownRosctr(u8),
    /// Bytes after the parameter and data the header announces.
    #[error("{0} bytes after the S7 PDU")]
    TrailingBytes(usize),
    /// A parameter of the wrong length for its function.
    #[error("S7 parameter of function {function:#04x} has a bad length {len}")]
    BadParameter {
        /// The function code.
        function: u8,
        /// The parameter's length.
        len: usize,
    },
    /// Data in an answer without a parameter.
    #[error("S7 data without a parameter")]
    UnexpectedData,
    /// An item specification other than S7ANY (syntax id 0x10).
    #[error("unsupported S7 item: specification {specification_type:#04x}, length {length}, syntax id {syntax_id:#04x}")]
    UnsupportedItem {
        /// 0x12 for variable specifications.
        specification_type: u8,
        /// The length byte (0x0A for S7ANY).
        length: u8,
        /// The addressing syntax.
        syntax_id: u8,
    },
    /// A missing fill byte between data items.
    #[error("missing fill byte after an odd-length S7 data item")]
    MissingFill,
    /// More than 255 items, or a length over 65535.
    #[error("S7 PDU too long to encode")]
    TooLong,
}

impl Pdu {
    /// The PDU reference.
    pub fn pdu_ref(&self) -> u16 {
        match *self {
            Pdu::Job { pdu_ref, .. }
            | Pdu::Ack { pdu_ref, .. }
            | Pdu::AckData { pdu_ref, .. }
            | Pdu::UserData { pdu_ref, .. } => pdu_ref,
        }
    }

    /// Decodes one PDU, exactly: trailing bytes are an error.
    pub fn decode(bytes: &[u8]) -> Result<Pdu, PduError> {
        let mut reader = Reader::new(bytes);
        let protocol_id = reader.u8().ok_or(PduError::Truncated)?;
        if protocol_id != PROTOCOL_ID {
            return Err(PduError::BadProtocolId(protocol_id));
        }
        let message_type = reader.u8().ok_or(PduError::Truncated)?;
        if !matches!(
            message_type,
            rosctr::JOB | rosctr::ACK | rosctr::ACK_DATA | rosctr::USER_DATA
        ) {
            return Err(PduError::UnknownRosctr(message_type));
        }
        let _reserved = reader.u16().ok_or(PduError::Truncated)?;
        let pdu_ref = reader.u16().ok_or(PduError::Truncated)?;
        let parameter_len = reader.u16().ok_or(PduError::Truncated)?;
        let data_len = reader.u16().ok_or(PduError::Truncated)?;
        let error = if matches!(message_type, rosctr::ACK | rosctr::ACK_DATA) {
            ErrorCode {
                class: reader.u8().ok_or(PduError::Truncated)?,
                code: reader.u8().ok_or(PduError::Truncated)?,
            }
        } else {
            ErrorCode::NONE
        };
        let parameter = reader
            .take(usize::from(parameter_len))
            .ok_or(PduError::Truncated)?;
        let data = reader
            .take(usize::from(data_len))
            .ok_or(PduError::Truncated)?;
        if !reader.is_empty() {
            return Err(PduError::TrailingBytes(reader.rest().len()));
        }
        match message_type {
            rosctr::JOB => Ok(Pdu::Job {
                pdu_ref,
                request: decode_request(parameter, data)?,
            }),
            // An ack carries no parameter or data; what a peer puts there means nothing.
            rosctr::ACK => Ok(Pdu::Ack { pdu_ref, error }),
            rosctr::ACK_DATA => Ok(Pdu::AckData {
                pdu_ref,
                error,
                response: decode_response(parameter, data)?,
            }),
            _ => Ok(Pdu::UserData {
                pdu_ref,
                parameter: parameter.to_vec(),
                data: data.to_vec(),
            }),
        }
    }

    /// Appends the encoded PDU.
    pub fn encode(&self, out: &mut Vec<u8>) -> Result<(), PduError> {
        let mut parameter = Vec::new();
        let mut data = Vec::new();
        let (message_type, pdu_ref, error) = match self {
            Pdu::Job { pdu_ref, request } => {
                encode_request(request, &mut parameter, &mut data)?;
                (rosctr::JOB, *pdu_ref, None)
            }
            Pdu::Ack { pdu_ref, error } => (rosctr::ACK, *pdu_ref, Some(*error)),
            Pdu::AckData {
                pdu_ref,
                error,
                response,
            } => {
                encode_response(response, &mut parameter, &mut data)?;
                (rosctr::ACK_DATA, *pdu_ref, Some(*error))
            }
            Pdu::UserData {
                pdu_ref,
                parameter: user_parameter,
                data: user_data,
            } => {
                parameter.extend_from_slice(user_parameter);
                data.extend_from_slice(user_data);
                (rosctr::USER_DATA, *pdu_ref, None)
            }
        };
        let parameter_len = u16::try_from(parameter.len()).map_err(|_| PduError::TooLong)?;
        let data_len = u16::try_from(data.len()).map_err(|_| PduError::TooLong)?;
        out.extend_from_slice(&[PROTOCOL_ID, message_type, 0, 0]);
        out.extend_from_slice(&pdu_ref.to_be_bytes());
        out.extend_from_slice(&parameter_len.to_be_bytes());
        out.extend_from_slice(&data_len.to_be_bytes());
        if let Some(error) = error {
            out.extend_from_slice(&[error.class, error.code]);
        }
        out.extend_from_slice(&parameter);
        out.extend_from_slice(&data);
        Ok(())
    }

    /// The encoded PDU in a new vector.
    pub fn to_bytes(&self) -> Result<Vec<u8>, PduError> {
        let mut out = Vec::new();
        self.encode(&mut out)?;
        Ok(out)
    }
}

fn decode_setup(function: u8, parameter: &[u8]) -> Result<SetupCommunication, PduError> {
    let bad = PduError::BadParameter {
        function,
        len: parameter.len(),
    };
    let mut reader = Reader::new(parameter);
    let _function = reader.u8().ok_or(bad)?;
    let _reserved = reader.u8().ok_or(bad)?;
    let setup = SetupCommunication {
        max_amq_calling: reader.u16().ok_or(bad)?,
        max_amq_called: reader.u16().ok_or(bad)?,
        pdu_size: reader.u16().ok_or(bad)?,
    };
    if !reader.is_empty() {
        return Err(bad);
    }
    Ok(setup)
}

fn encode_setup(setup: &SetupCommunication, parameter: &mut Vec<u8>) {
    parameter.extend_from_slice(&[function::SETUP_COMMUNICATION, 0]);
    parameter.extend_from_slice(&setup.max_amq_calling.to_be_bytes());
    parameter.extend_from_slice(&setup.max_amq_called.to_be_bytes());
    parameter.extend_from_slice(&setup.pdu_size.to_be_bytes());
}

/// The function code and item count of a read or write var parameter, and its items.
fn decode_var_head<'a>(function: u8, parameter: &'a [u8]) -> Result<(usize, Reader<'a>), PduError> {
    let mut reader = Reader::new(parameter);
    let _function = reader.u8().ok_or(PduError::Truncated)?;
    let count = reader.u8().ok_or(PduError::BadParameter {
        function,
        len: parameter.len(),
    })?;
    Ok((usize::from(count), reader))
}

fn decode_item_specs(
    function: u8,
    count: usize,
    reader: &mut Reader<'_>,
    parameter_len: usize,
) -> Result<Vec<ItemSpec>, PduError> {
    let items = (0..count)
        .map(|_| ItemSpec::decode(reader))
        .collect::<Result<Vec<_>, _>>()?;
    if !reader.is_empty() {
        return Err(PduError::BadParameter {
            function,
            len: parameter_len,
        });
    }
    Ok(items)
}

/// `count` data items with fill bytes between them.
fn decode_data_items(count: usize, data: &[u8]) -> Result<Vec<DataItem>, PduError> {
    let mut reader = Reader::new(data);
    let mut items = Vec::with_capacity(count.min(MAX_ITEMS * 2));
    for index in 0..count {
        let item = DataItem::decode(&mut reader)?;
        let last = index + 1 == count;
        if !last && item.data.len() % 2 == 1 {
            reader.u8().ok_or(PduError::MissingFill)?;
        }
        items.push(item);
    }
    if !reader.is_empty() {
        return Err(PduError::TrailingBytes(reader.rest().len()));
    }
    Ok(items)
}

fn encode_data_items<'a>(
    items: impl ExactSizeIterator<Item = &'a DataItem>,
    data: &mut Vec<u8>,
) -> Result<(), PduError> {
    let count = items.len();
    for (index, item) in items.enumerate() {
        item.encode(data)?;
        if index + 1 < count && item.data.len() % 2 == 1 {
            data.push(0);
        }
    }
    Ok(())
}

fn item_count(count: usize) -> Result<u8, PduError> {
    u8::try_from(count).map_err(|_| PduError::TooLong)
}

fn decode_request(parameter: &[u8], data: &[u8]) -> Result<Request, PduError> {
    let Some(&function_code) = parameter.first() else {
        return Err(PduError::Truncated);
    };
    match function_code {
        function::SETUP_COMMUNICATION => Ok(Request::SetupCommunication(decode_setup(
            function_code,
            parameter,
        )?)),
        function::READ_VAR => {
            let (count, mut reader) = decode_var_head(function_code, parameter)?;
            let items = decode_item_specs(function_code, count, &mut reader, parameter.len())?;
            if !data.is_empty() {
                return Err(PduError::TrailingBytes(data.len()));
            }
            Ok(Request::ReadVar(items))
        }
        function::WRITE_VAR => {
            let (count, mut reader) = decode_var_head(function_code, parameter)?;
            let items = decode_item_specs(function_code, count, &mut reader, parameter.len())?;
            let values = decode_data_items(count, data)?;
            Ok(Request::WriteVar(items.into_iter().zip(values).collect()))
        }
        other => Ok(Request::Other {
            function: other,
            parameter: parameter.get(1..).unwrap_or_default().to_vec(),
            data: data.to_vec(),
        }),
    }
}

fn encode_request(
    request: &Request,
    parameter: &mut Vec<u8>,
    data: &mut Vec<u8>,
) -> Result<(), PduError> {
    match request {
        Request::SetupCommunication(setup) => encode_setup(setup, parameter),
        Request::ReadVar(items) => {
            parameter.extend_from_slice(&[function::READ_VAR, item_count(items.len())?]);
            for item in items {
                item.encode(parameter);
            }
        }
        Request::WriteVar(items) => {
            parameter.extend_from_slice(&[function::WRITE_VAR, item_count(items.len())?]);
            for (item, _) in items {
                item.encode(parameter);
            }
            encode_data_items(items.iter().map(|(_, value)| value), data)?;
        }
        Request::Other {
            function,
            parameter: raw_parameter,
            data: raw_data,
        } => {
            parameter.push(*function);
            parameter.extend_from_slice(raw_parameter);
            data.extend_from_slice(raw_data);
        }
    }
    Ok(())
}

fn decode_response(parameter: &[u8], data: &[u8]) -> Result<Response, PduError> {
    let Some(&function_code) = parameter.first() else {
        return if data.is_empty() {
            Ok(Response::None)
        } else {
            Err(PduError::UnexpectedData)
        };
    };
    match function_code {
        function::SETUP_COMMUNICATION => Ok(Response::SetupCommunication(decode_setup(
            function_code,
            parameter,
        )?)),
        function::READ_VAR | function::WRITE_VAR => {
            let (count, reader) = decode_var_head(function_code, parameter)?;
            if !reader.is_empty() {
                return Err(PduError::BadParameter {
                    function: function_code,
                    len: parameter.len(),
                });
            }
            if function_code == function::READ_VAR {
                Ok(Response::ReadVar(decode_data_items(count, data)?))
            } else {
                if data.len() != count {
                    return Err(if data.len() < count {
                        PduError::Truncated
                    } else {
                        PduError::TrailingBytes(data.len() - count)
                    });
                }
                Ok(Response::WriteVar(
                    data.iter().copied().map(ReturnCode::from_code).collect(),
                ))
            }
        }
        other => Ok(Response::Other {
            function: other,
            parameter: parameter.get(1..).unwrap_or_default().to_vec(),
            data: data.to_vec(),
        }),
    }
}

fn encode_response(
    response: &Response,
    parameter: &mut Vec<u8>,
    data: &mut Vec<u8>,
) -> Result<(), PduError> {
    match response {
        Response::None => {}
        Response::SetupCommunication(setup) => encode_setup(setup, parameter),
        Response::ReadVar(items) => {
            parameter.extend_from_slice(&[function::READ_VAR, item_count(items.len())?]);
            encode_data_items(items.iter(), data)?;
        }
        Response::WriteVar(codes) => {
            parameter.extend_from_slice(&[function::WRITE_VAR, item_count(codes.len())?]);
            data.extend(codes.iter().map(|code| code.code()));
        }
        Response::Other {
            function,
            parameter: raw_parameter,
            data: raw_data,
        } => {
            parameter.push(*function);
            parameter.extend_from_slice(raw_parameter);
            data.extend_from_slice(raw_data);
        }
    }
    Ok(())
}
