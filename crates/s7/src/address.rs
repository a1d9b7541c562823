//! Where data lives in an S7 PLC: memory areas, the byte and bit ranges the protocol
//! reads and writes, and the absolute addresses a user types (`DB1.DBW2:INT`, `M10.0`).
//!
//! Spellings taken (case-insensitive, an optional leading `%` as TIA Portal writes it):
//!
//! | Form | Meaning |
//! |---|---|
//! | `DB1.DBX0.3` | bit 3 of byte 0 of data block 1 |
//! | `DB1.DBB1`, `DB1.DBW2`, `DB1.DBD4` | byte, word, double word of data block 1 |
//! | `M10.0`, `MX10.0`; `MB10`, `MW20`, `MD24` | markers (flags) |
//! | `I0.1`, `IX0.1`; `IB0`, `IW2`, `ID4` | process inputs |
//! | `Q0.2`, `QX0.2`; `QB0`, `QW0`, `QD4` | process outputs |
//!
//! followed by an optional type, `:BOOL`, `:BYTE`, `:SINT`, `:WORD`, `:INT`, `:DWORD`,
//! `:DINT` or `:REAL`, of the address's size. Without one, a bit is a `BOOL` and bytes,
//! words and double words are unsigned. The German mnemonics (`E` inputs, `A` outputs)
//! are not taken.

use std::fmt;
use std::str::FromStr;

use thiserror::Error;

use crate::value::{Value, ValueError, ValueType};

/// The highest byte number an S7ANY item can address: the item carries a 24-bit bit
/// address, byte * 8 + bit.
pub const MAX_BYTE: u32 = 0x1F_FFFF;

/// A memory area of the PLC, with the data block's number for data blocks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Area {
    /// Process inputs (`I`, area code 0x81).
    Inputs,
    /// Process outputs (`Q`, area code 0x82).
    Outputs,
    /// Markers, also called flags or bit memory (`M`, area code 0x83).
    Markers,
    /// A data block (`DB`, area code 0x84) by number, 1..=65535.
    DataBlock(u16),
}

impl Area {
    /// The area code of process inputs in an S7ANY item.
    pub const INPUTS_CODE: u8 = 0x81;
    /// The area code of process outputs.
    pub const OUTPUTS_CODE: u8 = 0x82;
    /// The area code of markers.
    pub const MARKERS_CODE: u8 = 0x83;
    /// The area code of data blocks.
    pub const DATA_BLOCK_CODE: u8 = 0x84;

    /// The area code an S7ANY item carries.
    pub fn code(self) -> u8 {
        match self {
            Area::Inputs => Self::INPUTS_CODE,
            Area::Outputs => Self::OUTPUTS_CODE,
            Area::Markers => Self::MARKERS_CODE,
            Area::DataBlock(_) => Self::DATA_BLOCK_CODE,
        }
    }

    /// The DB number field of an S7ANY item: the block's number, 0 outside data blocks.
    pub fn db_number(self) -> u16 {
        match self {
            Area::DataBlock(number) => number,
            _ => 0,
        }
    }

    /// The area of an S7ANY item's area code and DB number; `None` for the areas this
    /// crate does not serve (timers, counters, peripheral I/O, instance data, local data)
    /// and for data block 0, which no PLC has.
    pub fn from_code(code: u8, db_number: u16) -> Option<Area> {
        match code {
            Self::INPUTS_CODE => Some(Area::Inputs),
            Self::OUTPUTS_CODE => Some(Area::Outputs),
            Self::MARKERS_CODE => Some(Area::Markers),
            Self::DATA_BLOCK_CODE if db_number != 0 => Some(Area::DataBlock(db_number)),
            _ => None,
        }
    }

    /// The area's letters without a block number: `I`, `Q`, `M`, `DB`.
    pub fn name(self) -> &'static str {
        match self {
            Area::Inputs => "I",
            Area::Outputs => "Q",
            Area::Markers => "M",
            Area::DataBlock(_) => "DB",
        }
    }
}

/// `I`, `Q`, `M` or `DB1`.
impl fmt::Display for Area {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Area::DataBlock(number) => write!(f, "DB{number}"),
            other => f.write_str(other.name()),
        }
    }
}

/// What one protocol item reads or writes: a single bit, or a run of bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Region {
    /// One bit; written alone, the other bits of its byte untouched.
    Bit {
        /// The area.
        area: Area,
        /// The byte number.
        byte: u32,
        /// The bit number in the byte, 0..=7.
        bit: u8,
    },
    /// `len` bytes from byte `start`.
    Bytes {
        /// The area.
        area: Area,
        /// The first byte.
        start: u32,
        /// How many bytes, at least one.
        len: u32,
    },
}

/// A region no S7ANY item can address.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum RegionError {
    /// A bit number above 7.
    #[error("bit number {0} is above 7")]
    BitOutOfRange(u8),
    /// Zero bytes.
    #[error("an empty byte range")]
    Empty,
    /// Bytes past [`MAX_BYTE`].
    #[error("bytes {start}..{end} reach past byte {max}", end = u64::from(*start) + u64::from(*len), max = MAX_BYTE)]
    BeyondAddressSpace {
        /// The first byte.
        start: u32,
        /// How many bytes.
        len: u32,
    },
}

impl Region {
    /// The region's area.
    pub fn area(&self) -> Area {
        match *self {
            Region::Bit { area, .. } | Region::Bytes { area, .. } => area,
        }
    }

    /// The first byte number.
    pub fn start(&self) -> u32 {
        match *self {
            Region::Bit { byte, .. } => byte,
            Region::Bytes { start, .. } => start,
        }
    }

    /// Bytes of data the region travels as: one for a bit (0 or 1).
    pub fn data_len(&self) -> u32 {
        match *self {
            Region::Bit { .. } => 1,
            Region::Bytes { len, .. } => len,
        }
    }

    /// Whether an S7ANY item can address the region.
    pub fn validate(&self) -> Result<(), RegionError> {
        match *self {
            Region::Bit { byte, bit, .. } => {
                if bit > 7 {
                    Err(RegionError::BitOutOfRange(bit))
                } else if byte > MAX_BYTE {
                    Err(RegionError::BeyondAddressSpace {
                        start: byte,
                        len: 1,
                    })
                } else {
                    Ok(())
                }
            }
            Region::Bytes { start, len, .. } => {
                if len == 0 {
                    Err(RegionError::Empty)
                } else if u64::from(start) + u64::from(len) - 1 > u64::from(MAX_BYTE) {
                    Err(RegionError::BeyondAddressSpace { start, len })
                } else {
                    Ok(())
                }
            }
        }
    }
}

/// `DB1.DBX0.3`, `M10.0`; `DB1 bytes 0..1000`.
impl fmt::Display for Region {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Region::Bit { area, byte, bit } => match area {
                Area::DataBlock(number) => write!(f, "DB{number}.DBX{byte}.{bit}"),
                other => write!(f, "{}{byte}.{bit}", other.name()),
            },
            Region::Bytes { area, start, len } => {
                write!(
                    f,
                    "{area} bytes {start}..{}",
                    u64::from(start) + u64::from(len)
                )
            }
        }
    }
}

/// How much memory an address covers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Width {
    /// One bit, by number 0..=7 (`X`, or no letter with a bit number).
    Bit(u8),
    /// One byte (`B`).
    Byte,
    /// Two bytes (`W`).
    Word,
    /// Four bytes (`D`).
    DWord,
}

impl Width {
    /// Bytes of memory: one for a bit's byte.
    pub fn size(self) -> u32 {
        match self {
            Width::Bit(_) | Width::Byte => 1,
            Width::Word => 2,
            Width::DWord => 4,
        }
    }

    /// The type an address of this width has without a suffix.
    pub fn default_type(self) -> ValueType {
        match self {
            Width::Bit(_) => ValueType::Bool,
            Width::Byte => ValueType::Byte,
            Width::Word => ValueType::Word,
            Width::DWord => ValueType::DWord,
        }
    }

    /// Whether a value of `value_type` fits this width exactly.
    pub fn holds(self, value_type: ValueType) -> bool {
        match self {
            Width::Bit(_) => value_type == ValueType::Bool,
            _ => value_type != ValueType::Bool && value_type.size() as u32 == self.size(),
        }
    }

    fn letter(self) -> char {
        match self {
            Width::Bit(_) => 'X',
            Width::Byte => 'B',
            Width::Word => 'W',
            Width::DWord => 'D',
        }
    }

    fn describe(self) -> &'static str {
        match self {
            Width::Bit(_) => "a bit",
            Width::Byte => "a byte",
            Width::Word => "a word",
            Width::DWord => "a double word",
        }
    }
}

/// An absolute address with the type of its value, as a user types it: `DB1.DBW2:INT`.
///
/// Parse with [`str::parse`]; [`Display`](fmt::Display) gives the canonical spelling
/// back (upper case, `M10.0` for `mx10.0`, no suffix where the type is the width's
/// default).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Address {
    area: Area,
    byte: u32,
    width: Width,
    value_type: ValueType,
}

impl Address {
    /// An address of `width` at `byte` of `area` holding `value_type`.
    pub fn new(
        area: Area,
        byte: u32,
        width: Width,
        value_type: ValueType,
    ) -> Result<Address, AddressErrorKind> {
        if let Width::Bit(bit) = width {
            if bit > 7 {
                return Err(AddressErrorKind::BitOutOfRange(u64::from(bit)));
            }
        }
        if u64::from(byte) + u64::from(width.size()) - 1 > u64::from(MAX_BYTE) {
            return Err(AddressErrorKind::ByteTooLarge(u64::from(byte)));
        }
        if !width.holds(value_type) {
            return Err(AddressErrorKind::TypeMismatch { width, value_type });
        }
        Ok(Address {
            area,
            byte,
            width,
            value_type,
        })
    }

    /// The area.
    pub fn area(&self) -> Area {
        self.area
    }

    /// The (first) byte number.
    pub fn byte(&self) -> u32 {
        self.byte
    }

    /// Bit, byte, word or double word.
    pub fn width(&self) -> Width {
        self.width
    }

    /// The type of the value at the address.
    pub fn value_type(&self) -> ValueType {
        self.value_type
    }

    /// The memory the address covers, as the protocol reads and writes it.
    pub fn region(&self) -> Region {
        match self.width {
            Width::Bit(bit) => Region::Bit {
                area: self.area,
                byte: self.byte,
                bit,
            },
            width => Region::Bytes {
                area: self.area,
                start: self.byte,
                len: width.size(),
            },
        }
    }

    /// The value in bytes read from [`Address::region`].
    pub fn decode(&self, bytes: &[u8]) -> Result<Value, ValueError> {
        Value::from_bytes(self.value_type, bytes)
    }

    /// The bytes to write to [`Address::region`] for `value`, which must be of the
    /// address's size (an `INT` may go to a `WORD` address, a `REAL` to a `DWORD`).
    pub fn encode(&self, value: &Value) -> Result<Vec<u8>, AddressErrorKind> {
        if self.width.holds(value.value_type()) {
            Ok(value.to_bytes())
        } else {
            Err(AddressErrorKind::TypeMismatch {
                width: self.width,
                value_type: value.value_type(),
            })
        }
    }

    /// Parses `text` as a value of the address's type.
    pub fn parse_value(&self, text: &str) -> Result<Value, ValueError> {
        Value::parse(self.value_type, text)
    }
}

impl fmt::Display for Address {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.area, self.width) {
            (Area::DataBlock(number), Width::Bit(bit)) => {
                write!(f, "DB{number}.DBX{}.{bit}", self.byte)?;
            }
            (Area::DataBlock(number), width) => {
                write!(f, "DB{number}.DB{}{}", width.letter(), self.byte)?;
            }
            (area, Width::Bit(bit)) => write!(f, "{}{}.{bit}", area.name(), self.byte)?,
            (area, width) => write!(f, "{}{}{}", area.name(), width.letter(), self.byte)?,
        }
        if self.value_type != self.width.default_type() {
            write!(f, ":{}", self.value_type)?;
        }
        Ok(())
    }
}

/// A text that is no address, with the text.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("address {input:?}: {kind}")]
pub struct AddressError {
    /// The text given.
    pub input: String,
    /// What is wrong with it.
    pub kind: AddressErrorKind,
}

/// What is wrong with an address.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum AddressErrorKind {
    /// Nothing given.
    #[error("empty")]
    Empty,
    /// No `DB`, `M`, `I` or `Q` at the start.
    #[error("unknown area {0:?}: expected DB, M, I or Q (E and A are not taken)")]
    UnknownArea(String),
    /// `DB` without a number.
    #[error("a data block number must follow DB")]
    MissingDbNumber,
    /// `DB0`.
    #[error("data block 0 does not exist")]
    DbNumberZero,
    /// A data block number above 65535.
    #[error("data block number {0} is above 65535")]
    DbNumberTooLarge(u64),
    /// `DB1` not followed by `.DBX`, `.DBB`, `.DBW` or `.DBD`.
    #[error("expected .DBX, .DBB, .DBW or .DBD after the data block number")]
    MissingDbField,
    /// A width letter other than `X`, `B`, `W` or `D`.
    #[error("unknown size letter {0:?}: expected X, B, W or D")]
    UnknownWidth(char),
    /// No byte number.
    #[error("a byte number is missing")]
    MissingByte,
    /// A byte number past [`MAX_BYTE`] (for words and double words, their last byte).
    #[error("byte number {0} is beyond the address space (bytes 0..={max})", max = MAX_BYTE)]
    ByteTooLarge(u64),
    /// A bit address without `.bit`.
    #[error("a bit address needs a bit number: byte.bit, e.g. 10.0")]
    MissingBit,
    /// A bit number above 7.
    #[error("bit number {0} is above 7")]
    BitOutOfRange(u64),
    /// A `.bit` after a byte, word or double word address.
    #[error("only bit addresses (X, or no size letter) take a bit number")]
    UnexpectedBit,
    /// Characters after the address.
    #[error("unexpected {0:?} after the address")]
    Trailing(String),
    /// A suffix that is no type.
    #[error("unknown type {0:?}: expected BOOL, BYTE, SINT, WORD, INT, DWORD, DINT or REAL")]
    UnknownType(String),
    /// A type of another size than the address.
    #[error("{value_type} does not fit {}", width.describe())]
    TypeMismatch {
        /// The address's width.
        width: Width,
        /// The type given.
        value_type: ValueType,
    },
}

impl FromStr for Address {
    type Err = AddressError;

    fn from_str(input: &str) -> Result<Self, Self::Err> {
        parse_address(input).map_err(|kind| AddressError {
            input: input.to_owned(),
            kind,
        })
    }
}

fn parse_address(input: &str) -> Result<Address, AddressErrorKind> {
    let trimmed = input.trim();
    let trimmed = trimmed.strip_prefix('%').unwrap_or(trimmed);
    if trimmed.is_empty() {
        return Err(AddressErrorKind::Empty);
    }
    let (location, suffix) = match trimmed.split_once(':') {
        Some((location, suffix)) => (location.trim(), Some(suffix.trim())),
        None => (trimmed, None),
    };
    let upper = location.to_ascii_uppercase();
    let (area, rest) = if let Some(rest) = upper.strip_prefix("DB") {
        let (digits, rest) = split_digits(rest);
        if digits.is_empty() {
            return Err(AddressErrorKind::MissingDbNumber);
        }
        let number = parse_number(digits);
        let number = match u16::try_from(number) {
            Ok(0) => return Err(AddressErrorKind::DbNumberZero),
            Ok(number) => number,
            Err(_) => return Err(AddressErrorKind::DbNumberTooLarge(number)),
        };
        let rest = rest
            .strip_prefix(".DB")
            .ok_or(AddressErrorKind::MissingDbField)?;
        (Area::DataBlock(number), rest)
    } else {
        let mut chars = upper.chars();
        let area = match chars.next() {
            Some('M') => Area::Markers,
            Some('I') => Area::Inputs,
            Some('Q') => Area::Outputs,
            _ => {
                let (letters, _) = split_letters(&upper);
                return Err(AddressErrorKind::UnknownArea(letters.to_owned()));
            }
        };
        (area, chars.as_str())
    };
    // The size letter: mandatory inside a data block, optional (a bit) elsewhere.
    let (letter, rest) = match rest.chars().next() {
        Some(c) if c.is_ascii_alphabetic() => (Some(c), rest.get(1..).unwrap_or_default()),
        Some(_) if matches!(area, Area::DataBlock(_)) => {
            return Err(AddressErrorKind::MissingDbField)
        }
        _ => (None, rest),
    };
    let is_bit = match letter {
        None | Some('X') => true,
        Some('B' | 'W' | 'D') => false,
        Some(other) => return Err(AddressErrorKind::UnknownWidth(other)),
    };
    let (digits, rest) = split_digits(rest);
    if digits.is_empty() {
        return Err(match rest.chars().next() {
            None | Some('.') => AddressErrorKind::MissingByte,
            Some(_) => AddressErrorKind::Trailing(rest.to_owned()),
        });
    }
    let byte = parse_number(digits);
    let (bit, rest) = match rest.strip_prefix('.') {
        Some(after_dot) => {
            let (bit_digits, rest) = split_digits(after_dot);
            if bit_digits.is_empty() {
                return Err(AddressErrorKind::MissingBit);
            }
            (Some(parse_number(bit_digits)), rest)
        }
        None => (None, rest),
    };
    if !rest.is_empty() {
        return Err(AddressErrorKind::Trailing(rest.to_owned()));
    }
    let width = match (is_bit, bit, letter) {
        (true, Some(bit), _) => {
            let bit = u8::try_from(bit)
                .ok()
                .filter(|bit| *bit <= 7)
                .ok_or(AddressErrorKind::BitOutOfRange(bit))?;
            Width::Bit(bit)
        }
        (true, None, _) => return Err(AddressErrorKind::MissingBit),
        (false, Some(_), _) => return Err(AddressErrorKind::UnexpectedBit),
        (false, None, Some('B')) => Width::Byte,
        (false, None, Some('W')) => Width::Word,
        (false, None, _) => Width::DWord,
    };
    let byte = u32::try_from(byte)
        .ok()
        .filter(|byte| u64::from(*byte) + u64::from(width.size()) - 1 <= u64::from(MAX_BYTE))
        .ok_or(AddressErrorKind::ByteTooLarge(byte))?;
    let value_type = match suffix {
        None => width.default_type(),
        Some(name) => name
            .parse::<ValueType>()
            .map_err(|_| AddressErrorKind::UnknownType(name.to_owned()))?,
    };
    Address::new(area, byte, width, value_type)
}

/// Leading ASCII digits and the rest.
fn split_digits(text: &str) -> (&str, &str) {
    let end = text
        .find(|c: char| !c.is_ascii_digit())
        .unwrap_or(text.len());
    text.split_at_checked(end).unwrap_or((text, ""))
}

/// Leading ASCII letters and the rest.
fn split_letters(text: &str) -> (&str, &str) {
    let end = text
        .find(|c: char| !c.is_ascii_alphabetic())
        .unwrap_or(text.len());
    text.split_at_checked(end).unwrap_or((text, ""))
}

/// A run of ASCII digits as a number, saturating: a huge number is reported as too large,
/// not as a parse failure.
fn parse_number(digits: &str) -> u64 {
    digits.bytes().fold(0u64, |number, digit| {
        number
            .saturating_mul(10)
            .saturating_add(u64::from(digit.wrapping_sub(b'0')))
    })
}
