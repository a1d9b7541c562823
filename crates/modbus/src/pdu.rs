//! The protocol data unit: a function code and its data, the same on TCP and on a serial
//! line (Modbus Application Protocol Specification v1.1b3, sections 4-7).
//!
//! Requests are decoded as a server must (section 6's state diagrams): an unknown function
//! is exception 1, a quantity or byte count out of range exception 3 ([`PduError::exception`]);
//! the address range (exception 2) is the data model's to judge. Answers are decoded as a
//! client must: against the request they answer, so that a count, an echo or a function
//! that does not match is an error and not data.

use std::fmt;

use thiserror::Error;

use crate::model::{Table, Values};

/// The largest PDU: 253 octets (a serial line's 256-octet ADU less address and CRC).
pub const MAX_PDU: usize = 253;

/// Most coils or discrete inputs one read asks for (FC 1, 2).
pub const MAX_READ_BITS: u16 = 2000;
/// Most registers one read asks for (FC 3, 4, and the read part of FC 23).
pub const MAX_READ_REGISTERS: u16 = 125;
/// Most coils one write sets (FC 15).
pub const MAX_WRITE_COILS: u16 = 1968;
/// Most registers one write sets (FC 16).
pub const MAX_WRITE_REGISTERS: u16 = 123;
/// Most registers the write part of FC 23 sets.
pub const MAX_READ_WRITE_REGISTERS: u16 = 121;

/// A function code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct FunctionCode(pub u8);

impl FunctionCode {
    /// 1: read coils.
    pub const READ_COILS: FunctionCode = FunctionCode(1);
    /// 2: read discrete inputs.
    pub const READ_DISCRETE_INPUTS: FunctionCode = FunctionCode(2);
    /// 3: read holding registers.
    pub const READ_HOLDING_REGISTERS: FunctionCode = FunctionCode(3);
    /// 4: read input registers.
    pub const READ_INPUT_REGISTERS: FunctionCode = FunctionCode(4);
    /// 5: write single coil.
    pub const WRITE_SINGLE_COIL: FunctionCode = FunctionCode(5);
    /// 6: write single register.
    pub const WRITE_SINGLE_REGISTER: FunctionCode = FunctionCode(6);
    /// 15: write multiple coils.
    pub const WRITE_MULTIPLE_COILS: FunctionCode = FunctionCode(15);
    /// 16: write multiple registers.
    pub const WRITE_MULTIPLE_REGISTERS: FunctionCode = FunctionCode(16);
    /// 23: read/write multiple registers.
    pub const READ_WRITE_MULTIPLE_REGISTERS: FunctionCode = FunctionCode(23);

    /// The function codes this crate's servers carry out.
    pub const SUPPORTED: [FunctionCode; 9] = [
        Self::READ_COILS,
        Self::READ_DISCRETE_INPUTS,
        Self::READ_HOLDING_REGISTERS,
        Self::READ_INPUT_REGISTERS,
        Self::WRITE_SINGLE_COIL,
        Self::WRITE_SINGLE_REGISTER,
        Self::WRITE_MULTIPLE_COILS,
        Self::WRITE_MULTIPLE_REGISTERS,
        Self::READ_WRITE_MULTIPLE_REGISTERS,
    ];

    /// The function's name in the specification's words, lower case.
    pub fn name(self) -> &'static str {
        match self.0 {
            1 => "read coils",
            2 => "read discrete inputs",
            3 => "read holding registers",
            4 => "read input registers",
            5 => "write single coil",
            6 => "write single register",
            7 => "read exception status",
            8 => "diagnostics",
            11 => "get comm event counter",
            12 => "get comm event log",
            15 => "write multiple coils",
            16 => "write multiple registers",
            17 => "report server id",
            20 => "read file record",
            21 => "write file record",
            22 => "mask write register",
            23 => "read/write multiple registers",
            24 => "read FIFO queue",
            43 => "encapsulated interface transport",
            _ => "unknown function",
        }
    }
}

impl fmt::Display for FunctionCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "FC {} ({})", self.0, self.name())
    }
}

/// An exception code (section 7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ExceptionCode(pub u8);

impl ExceptionCode {
    /// 1: the function code is not one the server carries out.
    pub const ILLEGAL_FUNCTION: ExceptionCode = ExceptionCode(1);
    /// 2: the address range is not the server's.
    pub const ILLEGAL_DATA_ADDRESS: ExceptionCode = ExceptionCode(2);
    /// 3: a value in the request is not allowed (a quantity, a byte count, a coil value).
    pub const ILLEGAL_DATA_VALUE: ExceptionCode = ExceptionCode(3);
    /// 4: the server failed while carrying the request out.
    pub const SERVER_DEVICE_FAILURE: ExceptionCode = ExceptionCode(4);
    /// 5: accepted, a long operation under way.
    pub const ACKNOWLEDGE: ExceptionCode = ExceptionCode(5);
    /// 6: busy with a long operation.
    pub const SERVER_DEVICE_BUSY: ExceptionCode = ExceptionCode(6);
    /// 8: a file record failed its consistency check.
    pub const MEMORY_PARITY_ERROR: ExceptionCode = ExceptionCode(8);
    /// 10 (0x0A): a gateway has no path to the unit.
    pub const GATEWAY_PATH_UNAVAILABLE: ExceptionCode = ExceptionCode(0x0A);
    /// 11 (0x0B): a gateway's target unit did not answer; this crate's TCP server answers
    /// it for a unit id it does not serve.
    pub const GATEWAY_TARGET_FAILED: ExceptionCode = ExceptionCode(0x0B);

    /// The exception's name in the specification's words, lower case.
    pub fn name(self) -> &'static str {
        match self.0 {
            1 => "illegal function",
            2 => "illegal data address",
            3 => "illegal data value",
            4 => "server device failure",
            5 => "acknowledge",
            6 => "server device busy",
            8 => "memory parity error",
            0x0A => "gateway path unavailable",
            0x0B => "gateway target device failed to respond",
            _ => "unknown exception",
        }
    }
}

impl fmt::Display for ExceptionCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} (code {})", self.name(), self.0)
    }
}

/// A request of one of the supported function codes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Request {
    /// FC 1, 2, 3 or 4 by the table: `count` entries from `address`.
    Read {
        /// The table read.
        table: Table,
        /// The first entry.
        address: u16,
        /// How many.
        count: u16,
    },
    /// FC 5.
    WriteSingleCoil {
        /// The coil.
        address: u16,
        /// On or off.
        value: bool,
    },
    /// FC 6.
    WriteSingleRegister {
        /// The holding register.
        address: u16,
        /// Its new value.
        value: u16,
    },
    /// FC 15.
    WriteMultipleCoils {
        /// The first coil.
        address: u16,
        /// The values from there on.
        values: Vec<bool>,
    },
    /// FC 16.
    WriteMultipleRegisters {
        /// The first holding register.
        address: u16,
        /// The values from there on.
        values: Vec<u16>,
    },
    /// FC 23: the write is carried out before the read.
    ReadWriteMultipleRegisters {
        /// The first holding register read.
        read_address: u16,
        /// How many are read.
        read_count: u16,
        /// The first holding register written.
        write_address: u16,
        /// The values written from there on.
        values: Vec<u16>,
    },
}

/// A response to a request of one of the supported function codes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Response {
    /// FC 1: the coils' states.
    ReadCoils(Vec<bool>),
    /// FC 2: the discrete inputs' states.
    ReadDiscreteInputs(Vec<bool>),
    /// FC 3: the holding registers.
    ReadHoldingRegisters(Vec<u16>),
    /// FC 4: the input registers.
    ReadInputRegisters(Vec<u16>),
    /// FC 5, the request's echo.
    WriteSingleCoil {
        /// The coil.
        address: u16,
        /// Its state.
        value: bool,
    },
    /// FC 6, the request's echo.
    WriteSingleRegister {
        /// The register.
        address: u16,
        /// Its value.
        value: u16,
    },
    /// FC 15: where and how many.
    WriteMultipleCoils {
        /// The first coil.
        address: u16,
        /// How many were written.
        count: u16,
    },
    /// FC 16: where and how many.
    WriteMultipleRegisters {
        /// The first register.
        address: u16,
        /// How many were written.
        count: u16,
    },
    /// FC 23: the registers read.
    ReadWriteMultipleRegisters(Vec<u16>),
}

/// A server's answer to a request: a response or an exception.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Answer {
    /// The request was carried out.
    Response(Response),
    /// It was not, and this is why.
    Exception(ExceptionCode),
}

/// A PDU that is not a valid request, or an answer that does not answer its request.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[non_exhaustive]
pub enum PduError {
    /// No function code.
    #[error("empty PDU")]
    Empty,
    /// A function code that is not one of the supported ones.
    #[error("function code {0} is not supported")]
    UnsupportedFunction(u8),
    /// A PDU of another length than its function and counts imply.
    #[error("FC {function}: {length} octets, expected {expected}")]
    Length {
        /// The function code.
        function: u8,
        /// The PDU's length.
        length: usize,
        /// The length its function and counts imply.
        expected: usize,
    },
    /// A quantity outside what the function allows.
    #[error("FC {function}: quantity {count} outside 1..={max}")]
    Quantity {
        /// The function code.
        function: u8,
        /// The quantity asked.
        count: usize,
        /// The function's maximum.
        max: u16,
    },
    /// A byte count that does not fit the quantity.
    #[error("FC {function}: byte count {byte_count}, expected {expected}")]
    ByteCount {
        /// The function code.
        function: u8,
        /// The byte count in the PDU.
        byte_count: u8,
        /// The one the quantity implies.
        expected: usize,
    },
    /// A coil value other than 0xFF00 (on) and 0x0000 (off).
    #[error("coil value {0:#06x}: expected 0xff00 or 0x0000")]
    CoilValue(u16),
    /// An answer of another function than the request's.
    #[error("answer of FC {got} to a request of FC {expected}")]
    FunctionMismatch {
        /// The request's function.
        expected: u8,
        /// The answer's.
        got: u8,
    },
    /// An answer whose echo, count or address is not the request's.
    #[error("FC {function}: the answer's {what} is not the request's")]
    EchoMismatch {
        /// The function code.
        function: u8,
        /// What differs.
        what: &'static str,
    },
}

impl PduError {
    /// The exception a server answers for a request that failed to decode so: 1 for an
    /// unsupported function, 3 for the rest; `None` when nothing must be answered (no
    /// function code).
    pub fn exception(&self) -> Option<ExceptionCode> {
        match self {
            PduError::Empty => None,
            PduError::UnsupportedFunction(_) => Some(ExceptionCode::ILLEGAL_FUNCTION),
            _ => Some(ExceptionCode::ILLEGAL_DATA_VALUE),
        }
    }
}

/// The octets `bits` packed eight to an octet, the first in the lowest bit, the last
/// octet's unused bits zero.
pub fn pack_bits(bits: &[bool]) -> Vec<u8> {
    let mut out = vec![0u8; bits.len().div_ceil(8)];
    for (i, bit) in bits.iter().enumerate() {
        if *bit {
            if let Some(octet) = out.get_mut(i / 8) {
                *octet |= 1 << (i % 8);
            }
        }
    }
    out
}

/// The first `count` bits of packed octets (missing octets read as zeros).
pub fn unpack_bits(octets: &[u8], count: usize) -> Vec<bool> {
    (0..count)
        .map(|i| {
            octets
                .get(i / 8)
                .is_some_and(|octet| octet >> (i % 8) & 1 == 1)
        })
        .collect()
}

fn u16_at(bytes: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_be_bytes([*bytes.get(at)?, *bytes.get(at + 1)?]))
}

/// The big-endian registers of `octets` (an odd last octet ignored).
fn registers(octets: &[u8]) -> Vec<u16> {
    octets
        .chunks_exact(2)
        .map(|pair| {
            u16::from_be_bytes([
                pair.first().copied().unwrap_or(0),
                pair.get(1).copied().unwrap_or(0),
            ])
        })
        .collect()
}

fn push_u16(out: &mut Vec<u8>, value: u16) {
    out.extend_from_slice(&value.to_be_bytes());
}

/// A count as the u8 byte count of a PDU; a validated request never comes near 255.
fn byte_count(count: usize) -> u8 {
    u8::try_from(count).unwrap_or(u8::MAX)
}

fn count_u16(count: usize) -> u16 {
    u16::try_from(count).unwrap_or(u16::MAX)
}

const COIL_ON: u16 = 0xFF00;
const COIL_OFF: u16 = 0x0000;

fn check_quantity(function: u8, count: usize, max: u16) -> Result<(), PduError> {
    if count == 0 || count > usize::from(max) {
        return Err(PduError::Quantity {
            function,
            count,
            max,
        });
    }
    Ok(())
}

fn check_length(function: u8, pdu: &[u8], expected: usize) -> Result<(), PduError> {
    if pdu.len() != expected {
        return Err(PduError::Length {
            function,
            length: pdu.len(),
            expected,
        });
    }
    Ok(())
}

impl Request {
    /// A read of `count` entries of `table` from `address` (FC 1-4).
    pub fn read(table: Table, address: u16, count: u16) -> Request {
        Request::Read {
            table,
            address,
            count,
        }
    }

    /// The request's function code.
    pub fn function(&self) -> FunctionCode {
        match self {
            Request::Read { table, .. } => table.read_function(),
            Request::WriteSingleCoil { .. } => FunctionCode::WRITE_SINGLE_COIL,
            Request::WriteSingleRegister { .. } => FunctionCode::WRITE_SINGLE_REGISTER,
            Request::WriteMultipleCoils { .. } => FunctionCode::WRITE_MULTIPLE_COILS,
            Request::WriteMultipleRegisters { .. } => FunctionCode::WRITE_MULTIPLE_REGISTERS,
            Request::ReadWriteMultipleRegisters { .. } => {
                FunctionCode::READ_WRITE_MULTIPLE_REGISTERS
            }
        }
    }

    /// Checks the quantities against the function's limits (section 6): what a server
    /// would answer with exception 3.
    pub fn validate(&self) -> Result<(), PduError> {
        let function = self.function().0;
        match self {
            Request::Read { table, count, .. } => {
                check_quantity(function, usize::from(*count), table.max_read())
            }
            Request::WriteSingleCoil { .. } | Request::WriteSingleRegister { .. } => Ok(()),
            Request::WriteMultipleCoils { values, .. } => {
                check_quantity(function, values.len(), MAX_WRITE_COILS)
            }
            Request::WriteMultipleRegisters { values, .. } => {
                check_quantity(function, values.len(), MAX_WRITE_REGISTERS)
            }
            Request::ReadWriteMultipleRegisters {
                read_count, values, ..
            } => {
                check_quantity(function, usize::from(*read_count), MAX_READ_REGISTERS)?;
                check_quantity(function, values.len(), MAX_READ_WRITE_REGISTERS)
            }
        }
    }

    /// Appends the request's PDU to `out`; a request outside the function's limits is
    /// refused and nothing is appended.
    pub fn encode(&self, out: &mut Vec<u8>) -> Result<(), PduError> {
        self.validate()?;
        out.push(self.function().0);
        match self {
            Request::Read { address, count, .. } => {
                push_u16(out, *address);
                push_u16(out, *count);
            }
            Request::WriteSingleCoil { address, value } => {
                push_u16(out, *address);
                push_u16(out, if *value { COIL_ON } else { COIL_OFF });
            }
            Request::WriteSingleRegister { address, value } => {
                push_u16(out, *address);
                push_u16(out, *value);
            }
            Request::WriteMultipleCoils { address, values } => {
                let packed = pack_bits(values);
                push_u16(out, *address);
                push_u16(out, count_u16(values.len()));
                out.push(byte_count(packed.len()));
                out.extend_from_slice(&packed);
            }
            Request::WriteMultipleRegisters { address, values } => {
                push_u16(out, *address);
                push_u16(out, count_u16(values.len()));
                out.push(byte_count(values.len() * 2));
                for value in values {
                    push_u16(out, *value);
                }
            }
            Request::ReadWriteMultipleRegisters {
                read_address,
                read_count,
                write_address,
                values,
            } => {
                push_u16(out, *read_address);
                push_u16(out, *read_count);
                push_u16(out, *write_address);
                push_u16(out, count_u16(values.len()));
                out.push(byte_count(values.len() * 2));
                for value in values {
                    push_u16(out, *value);
                }
            }
        }
        Ok(())
    }

    /// The request's PDU.
    pub fn to_pdu(&self) -> Result<Vec<u8>, PduError> {
        let mut out = Vec::new();
        self.encode(&mut out)?;
        Ok(out)
    }

    /// Decodes a request PDU as a server does; [`PduError::exception`] says what to answer
    /// for an error.
    pub fn decode(pdu: &[u8]) -> Result<Request, PduError> {
        let (&function, _) = pdu.split_first().ok_or(PduError::Empty)?;
        let field = |at: usize| u16_at(pdu, at).unwrap_or(0);
        let request = match function {
            1..=4 => {
                check_length(function, pdu, 5)?;
                let table = match function {
                    1 => Table::Coils,
                    2 => Table::DiscreteInputs,
                    3 => Table::HoldingRegisters,
                    _ => Table::InputRegisters,
                };
                Request::Read {
                    table,
                    address: field(1),
                    count: field(3),
                }
            }
            5 => {
                check_length(function, pdu, 5)?;
                let value = match field(3) {
                    COIL_ON => true,
                    COIL_OFF => false,
                    other => return Err(PduError::CoilValue(other)),
                };
                Request::WriteSingleCoil {
                    address: field(1),
                    value,
                }
            }
            6 => {
                check_length(function, pdu, 5)?;
                Request::WriteSingleRegister {
                    address: field(1),
                    value: field(3),
                }
            }
            15 => {
                let count = usize::from(u16_at(pdu, 3).ok_or(PduError::Length {
                    function,
                    length: pdu.len(),
                    expected: 6,
                })?);
                check_quantity(function, count, MAX_WRITE_COILS)?;
                let expected = count.div_ceil(8);
                let given = *pdu.get(5).ok_or(PduError::Length {
                    function,
                    length: pdu.len(),
                    expected: 6 + expected,
                })?;
                if usize::from(given) != expected {
                    return Err(PduError::ByteCount {
                        function,
                        byte_count: given,
                        expected,
                    });
                }
                check_length(function, pdu, 6 + expected)?;
                Request::WriteMultipleCoils {
                    address: field(1),
                    values: unpack_bits(pdu.get(6..).unwrap_or_default(), count),
                }
            }
            16 => {
                let count = usize::from(u16_at(pdu, 3).ok_or(PduError::Length {
                    function,
                    length: pdu.len(),
                    expected: 6,
                })?);
                check_quantity(function, count, MAX_WRITE_REGISTERS)?;
                let given = *pdu.get(5).ok_or(PduError::Length {
                    function,
                    length: pdu.len(),
                    expected: 6 + count * 2,
                })?;
                if usize::from(given) != count * 2 {
                    return Err(PduError::ByteCount {
                        function,
                        byte_count: given,
                        expected: count * 2,
                    });
                }
                check_length(function, pdu, 6 + count * 2)?;
                Request::WriteMultipleRegisters {
                    address: field(1),
                    values: registers(pdu.get(6..).unwrap_or_default()),
                }
            }
            23 => {
                let (Some(read_count), Some(write_count)) = (u16_at(pdu, 3), u16_at(pdu, 7)) else {
                    return Err(PduError::Length {
                        function,
                        length: pdu.len(),
                        expected: 10,
                    });
                };
                check_quantity(function, usize::from(read_count), MAX_READ_REGISTERS)?;
                let write_count = usize::from(write_count);
                check_quantity(function, write_count, MAX_READ_WRITE_REGISTERS)?;
                let given = *pdu.get(9).ok_or(PduError::Length {
                    function,
                    length: pdu.len(),
                    expected: 10 + write_count * 2,
                })?;
                if usize::from(given) != write_count * 2 {
                    return Err(PduError::ByteCount {
                        function,
                        byte_count: given,
                        expected: write_count * 2,
                    });
                }
                check_length(function, pdu, 10 + write_count * 2)?;
                Request::ReadWriteMultipleRegisters {
                    read_address: field(1),
                    read_count,
                    write_address: field(5),
                    values: registers(pdu.get(10..).unwrap_or_default()),
                }
            }
            other => return Err(PduError::UnsupportedFunction(other)),
        };
        if let Request::Read { table, count, .. } = &request {
            check_quantity(function, usize::from(*count), table.max_read())?;
        }
        Ok(request)
    }
}

impl fmt::Display for Request {
    /// `read holding registers 100..=109`, `write single coil 7 = true`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let range = |address: u16, count: usize| {
            let last = usize::from(address) + count.saturating_sub(1);
            if count == 1 {
                format!("{address}")
            } else {
                format!("{address}..={last}")
            }
        };
        let name = self.function().name();
        match self {
            Request::Read { address, count, .. } => {
                write!(f, "{name} {}", range(*address, usize::from(*count)))
            }
            Request::WriteSingleCoil { address, value } => write!(f, "{name} {address} = {value}"),
            Request::WriteSingleRegister { address, value } => {
                write!(f, "{name} {address} = {value}")
            }
            Request::WriteMultipleCoils { address, values } => {
                write!(f, "{name} {}", range(*address, values.len()))
            }
            Request::WriteMultipleRegisters { address, values } => {
                write!(f, "{name} {}", range(*address, values.len()))
            }
            Request::ReadWriteMultipleRegisters {
                read_address,
                read_count,
                write_address,
                values,
            } => write!(
                f,
                "{name}: write {}, read {}",
                range(*write_address, values.len()),
                range(*read_address, usize::from(*read_count))
            ),
        }
    }
}

impl Response {
    /// The response's function code.
    pub fn function(&self) -> FunctionCode {
        match self {
            Response::ReadCoils(_) => FunctionCode::READ_COILS,
            Response::ReadDiscreteInputs(_) => FunctionCode::READ_DISCRETE_INPUTS,
            Response::ReadHoldingRegisters(_) => FunctionCode::READ_HOLDING_REGISTERS,
            Response::ReadInputRegisters(_) => FunctionCode::READ_INPUT_REGISTERS,
            Response::WriteSingleCoil { .. } => FunctionCode::WRITE_SINGLE_COIL,
            Response::WriteSingleRegister { .. } => FunctionCode::WRITE_SINGLE_REGISTER,
            Response::WriteMultipleCoils { .. } => FunctionCode::WRITE_MULTIPLE_COILS,
            Response::WriteMultipleRegisters { .. } => FunctionCode::WRITE_MULTIPLE_REGISTERS,
            Response::ReadWriteMultipleRegisters(_) => FunctionCode::READ_WRITE_MULTIPLE_REGISTERS,
        }
    }

    /// The values a read returned (FC 1-4, 23); `None` for a write's echo.
    pub fn values(&self) -> Option<Values> {
        match self {
            Response::ReadCoils(bits) | Response::ReadDiscreteInputs(bits) => {
                Some(Values::Bits(bits.clone()))
            }
            Response::ReadHoldingRegisters(registers)
            | Response::ReadInputRegisters(registers)
            | Response::ReadWriteMultipleRegisters(registers) => {
                Some(Values::Registers(registers.clone()))
            }
            _ => None,
        }
    }

    /// Appends the response's PDU to `out`.
    pub fn encode(&self, out: &mut Vec<u8>) {
        out.push(self.function().0);
        match self {
            Response::ReadCoils(bits) | Response::ReadDiscreteInputs(bits) => {
                let packed = pack_bits(bits);
                out.push(byte_count(packed.len()));
                out.extend_from_slice(&packed);
            }
            Response::ReadHoldingRegisters(values)
            | Response::ReadInputRegisters(values)
            | Response::ReadWriteMultipleRegisters(values) => {
                out.push(byte_count(values.len() * 2));
                for value in values {
                    push_u16(out, *value);
                }
            }
            Response::WriteSingleCoil { address, value } => {
                push_u16(out, *address);
                push_u16(out, if *value { COIL_ON } else { COIL_OFF });
            }
            Response::WriteSingleRegister { address, value } => {
                push_u16(out, *address);
                push_u16(out, *value);
            }
            Response::WriteMultipleCoils { address, count }
            | Response::WriteMultipleRegisters { address, count } => {
                push_u16(out, *address);
                push_u16(out, *count);
            }
        }
    }
}

impl Answer {
    /// Appends the answer's PDU to `out`: a response, or `function | 0x80` and the
    /// exception code.
    pub fn encode(&self, function: FunctionCode, out: &mut Vec<u8>) {
        match self {
            Answer::Response(response) => response.encode(out),
            Answer::Exception(code) => {
                out.push(function.0 | 0x80);
                out.push(code.0);
            }
        }
    }

    /// Decodes the answer to `request`: the function, the counts and the echoes must be
    /// the request's.
    pub fn decode(request: &Request, pdu: &[u8]) -> Result<Answer, PduError> {
        let expected = request.function().0;
        let (&function, _) = pdu.split_first().ok_or(PduError::Empty)?;
        if function == expected | 0x80 {
            check_length(function, pdu, 2)?;
            return Ok(Answer::Exception(ExceptionCode(
                pdu.get(1).copied().unwrap_or(0),
            )));
        }
        if function != expected {
            return Err(PduError::FunctionMismatch {
                expected,
                got: function,
            });
        }
        let field = |at: usize| u16_at(pdu, at).unwrap_or(0);
        let echo = |what: &'static str| PduError::EchoMismatch { function, what };
        // A read's answer: a byte count and that many octets.
        let data = |octets: usize| -> Result<&[u8], PduError> {
            let given = *pdu.get(1).ok_or(PduError::Length {
                function,
                length: pdu.len(),
                expected: 2 + octets,
            })?;
            if usize::from(given) != octets {
                return Err(PduError::ByteCount {
                    function,
                    byte_count: given,
                    expected: octets,
                });
            }
            check_length(function, pdu, 2 + octets)?;
            Ok(pdu.get(2..).unwrap_or_default())
        };
        let response = match request {
            Request::Read { table, count, .. } => {
                let count = usize::from(*count);
                match table {
                    Table::Coils => {
                        Response::ReadCoils(unpack_bits(data(count.div_ceil(8))?, count))
                    }
                    Table::DiscreteInputs => {
                        Response::ReadDiscreteInputs(unpack_bits(data(count.div_ceil(8))?, count))
                    }
                    Table::HoldingRegisters => {
                        Response::ReadHoldingRegisters(registers(data(count * 2)?))
                    }
                    Table::InputRegisters => {
                        Response::ReadInputRegisters(registers(data(count * 2)?))
                    }
                }
            }
            Request::ReadWriteMultipleRegisters { read_count, .. } => {
                Response::ReadWriteMultipleRegisters(registers(data(usize::from(*read_count) * 2)?))
            }
            Request::WriteSingleCoil { address, value } => {
                check_length(function, pdu, 5)?;
                if field(1) != *address {
                    return Err(echo("address"));
                }
                let got = match field(3) {
                    COIL_ON => true,
                    COIL_OFF => false,
                    other => return Err(PduError::CoilValue(other)),
                };
                if got != *value {
                    return Err(echo("value"));
                }
                Response::WriteSingleCoil {
                    address: *address,
                    value: *value,
                }
            }
            Request::WriteSingleRegister { address, value } => {
                check_length(function, pdu, 5)?;
                if field(1) != *address {
                    return Err(echo("address"));
                }
                if field(3) != *value {
                    return Err(echo("value"));
                }
                Response::WriteSingleRegister {
                    address: *address,
                    value: *value,
                }
            }
            Request::WriteMultipleCoils { address, values } => {
                check_length(function, pdu, 5)?;
                if field(1) != *address {
                    return Err(echo("address"));
                }
                if usize::from(field(3)) != values.len() {
                    return Err(echo("quantity"));
                }
                Response::WriteMultipleCoils {
                    address: *address,
                    count: field(3),
                }
            }
            Request::WriteMultipleRegisters { address, values } => {
                check_length(function, pdu, 5)?;
                if field(1) != *address {
                    return Err(echo("address"));
                }
                if usize::from(field(3)) != values.len() {
                    return Err(echo("quantity"));
                }
                Response::WriteMultipleRegisters {
                    address: *address,
                    count: field(3),
                }
            }
        };
        Ok(Answer::Response(response))
    }
}
