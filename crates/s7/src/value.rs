//! Typed values at an address: the types a user names after an address (`:INT`), the
//! values parsed from text, and their big-endian memory image (S7 stores every number
//! most significant byte first).

use std::fmt;
use std::num::IntErrorKind;
use std::str::FromStr;

use thiserror::Error;

/// The type of a value in PLC memory: the elementary types of IEC 61131-3 that fit one
/// bit, byte, word or double word.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ValueType {
    /// One bit.
    Bool,
    /// Unsigned 8 bits.
    Byte,
    /// Signed 8 bits.
    SInt,
    /// Unsigned 16 bits.
    Word,
    /// Signed 16 bits.
    Int,
    /// Unsigned 32 bits.
    DWord,
    /// Signed 32 bits.
    DInt,
    /// IEEE 754 single precision.
    Real,
}

impl ValueType {
    /// Every type, in the order of the suffix list in error messages.
    pub const ALL: [ValueType; 8] = [
        ValueType::Bool,
        ValueType::Byte,
        ValueType::SInt,
        ValueType::Word,
        ValueType::Int,
        ValueType::DWord,
        ValueType::DInt,
        ValueType::Real,
    ];

    /// Bytes of memory a value takes (a `Bool` travels as one byte, 0 or 1).
    pub fn size(self) -> usize {
        match self {
            ValueType::Bool | ValueType::Byte | ValueType::SInt => 1,
            ValueType::Word | ValueType::Int => 2,
            ValueType::DWord | ValueType::DInt | ValueType::Real => 4,
        }
    }

    /// The name as written after an address, upper case (`INT`).
    pub fn name(self) -> &'static str {
        match self {
            ValueType::Bool => "BOOL",
            ValueType::Byte => "BYTE",
            ValueType::SInt => "SINT",
            ValueType::Word => "WORD",
            ValueType::Int => "INT",
            ValueType::DWord => "DWORD",
            ValueType::DInt => "DINT",
            ValueType::Real => "REAL",
        }
    }
}

impl fmt::Display for ValueType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A type name that is none of [`ValueType::ALL`].
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("unknown type {0:?}: expected BOOL, BYTE, SINT, WORD, INT, DWORD, DINT or REAL")]
pub struct UnknownValueType(pub String);

impl FromStr for ValueType {
    type Err = UnknownValueType;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        ValueType::ALL
            .into_iter()
            .find(|value_type| value_type.name().eq_ignore_ascii_case(text.trim()))
            .ok_or_else(|| UnknownValueType(text.to_owned()))
    }
}

/// A value read from or written to PLC memory.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    /// `BOOL`.
    Bool(bool),
    /// `BYTE`, unsigned.
    Byte(u8),
    /// `SINT`.
    SInt(i8),
    /// `WORD`, unsigned.
    Word(u16),
    /// `INT`.
    Int(i16),
    /// `DWORD`, unsigned.
    DWord(u32),
    /// `DINT`.
    DInt(i32),
    /// `REAL`.
    Real(f32),
}

/// Text or bytes that are no value of the type asked.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum ValueError {
    /// Not `true`, `false`, `1` or `0`.
    #[error("{0:?} is not a BOOL: expected true, false, 1 or 0")]
    NotABool(String),
    /// Not a number at all.
    #[error("{text:?} is not a number of type {value_type}")]
    NotANumber {
        /// The text given.
        text: String,
        /// The type asked.
        value_type: ValueType,
    },
    /// A number the type cannot hold.
    #[error("{text} is out of range for {value_type}")]
    OutOfRange {
        /// The text given.
        text: String,
        /// The type asked.
        value_type: ValueType,
    },
    /// Memory bytes of another length than the type's.
    #[error("{value_type} takes {expected} bytes, got {got}")]
    WrongLength {
        /// The type asked.
        value_type: ValueType,
        /// Its size.
        expected: usize,
        /// The bytes given.
        got: usize,
    },
}

impl Value {
    /// The value's type.
    pub fn value_type(&self) -> ValueType {
        match self {
            Value::Bool(_) => ValueType::Bool,
            Value::Byte(_) => ValueType::Byte,
            Value::SInt(_) => ValueType::SInt,
            Value::Word(_) => ValueType::Word,
            Value::Int(_) => ValueType::Int,
            Value::DWord(_) => ValueType::DWord,
            Value::DInt(_) => ValueType::DInt,
            Value::Real(_) => ValueType::Real,
        }
    }

    /// Parses text as a value of `value_type`: `true`/`false`/`1`/`0` for `BOOL`
    /// (any case), decimal integers range-checked for the type (the unsigned types also
    /// take hex as `0x1F` or `16#1F`), finite decimal numbers for `REAL`.
    pub fn parse(value_type: ValueType, text: &str) -> Result<Value, ValueError> {
        let trimmed = text.trim();
        match value_type {
            ValueType::Bool => match trimmed.to_ascii_lowercase().as_str() {
                "true" | "1" => Ok(Value::Bool(true)),
                "false" | "0" => Ok(Value::Bool(false)),
                _ => Err(ValueError::NotABool(text.to_owned())),
            },
            ValueType::Real => {
                let not_a_number = || ValueError::NotANumber {
                    text: text.to_owned(),
                    value_type,
                };
                // f32's parser takes "inf" and "NaN"; a PLC value typed by a user is
                // finite, and JSON has no spelling for the others.
                if trimmed
                    .chars()
                    .any(|c| c.is_ascii_alphabetic() && c != 'e' && c != 'E')
                {
                    return Err(not_a_number());
                }
                let number: f32 = trimmed.parse().map_err(|_| not_a_number())?;
                if number.is_finite() {
                    Ok(Value::Real(number))
                } else {
                    Err(ValueError::OutOfRange {
                        text: text.to_owned(),
                        value_type,
                    })
                }
            }
            _ => {
                let integer = parse_integer(value_type, text, trimmed)?;
                let out_of_range = || ValueError::OutOfRange {
                    text: text.to_owned(),
                    value_type,
                };
                let value = match value_type {
                    ValueType::Byte => Value::Byte(integer.try_into().map_err(|_| out_of_range())?),
                    ValueType::SInt => Value::SInt(integer.try_into().map_err(|_| out_of_range())?),
                    ValueType::Word => Value::Word(integer.try_into().map_err(|_| out_of_range())?),
                    ValueType::Int => Value::Int(integer.try_into().map_err(|_| out_of_range())?),
                    ValueType::DWord => {
                        Value::DWord(integer.try_into().map_err(|_| out_of_range())?)
                    }
                    ValueType::DInt => Value::DInt(integer.try_into().map_err(|_| out_of_range())?),
                    ValueType::Bool | ValueType::Real => return Err(out_of_range()),
                };
                Ok(value)
            }
        }
    }

    /// The memory image, most significant byte first; a `Bool` is one byte, 0 or 1.
    pub fn to_bytes(&self) -> Vec<u8> {
        match *self {
            Value::Bool(bit) => vec![u8::from(bit)],
            Value::Byte(value) => vec![value],
            Value::SInt(value) => value.to_be_bytes().to_vec(),
            Value::Word(value) => value.to_be_bytes().to_vec(),
            Value::Int(value) => value.to_be_bytes().to_vec(),
            Value::DWord(value) => value.to_be_bytes().to_vec(),
            Value::DInt(value) => value.to_be_bytes().to_vec(),
            Value::Real(value) => value.to_be_bytes().to_vec(),
        }
    }

    /// The value of `value_type` in a memory image of exactly its size; any non-zero
    /// byte is a true `Bool`.
    pub fn from_bytes(value_type: ValueType, bytes: &[u8]) -> Result<Value, ValueError> {
        let wrong_length = || ValueError::WrongLength {
            value_type,
            expected: value_type.size(),
            got: bytes.len(),
        };
        let value = match value_type {
            ValueType::Bool => match bytes {
                [byte] => Value::Bool(*byte != 0),
                _ => return Err(wrong_length()),
            },
            ValueType::Byte => {
                Value::Byte(u8::from_be_bytes(array(bytes).ok_or_else(wrong_length)?))
            }
            ValueType::SInt => {
                Value::SInt(i8::from_be_bytes(array(bytes).ok_or_else(wrong_length)?))
            }
            ValueType::Word => {
                Value::Word(u16::from_be_bytes(array(bytes).ok_or_else(wrong_length)?))
            }
            ValueType::Int => {
                Value::Int(i16::from_be_bytes(array(bytes).ok_or_else(wrong_length)?))
            }
            ValueType::DWord => {
                Value::DWord(u32::from_be_bytes(array(bytes).ok_or_else(wrong_length)?))
            }
            ValueType::DInt => {
                Value::DInt(i32::from_be_bytes(array(bytes).ok_or_else(wrong_length)?))
            }
            ValueType::Real => {
                Value::Real(f32::from_be_bytes(array(bytes).ok_or_else(wrong_length)?))
            }
        };
        Ok(value)
    }
}

fn array<const N: usize>(bytes: &[u8]) -> Option<[u8; N]> {
    bytes.try_into().ok()
}

/// An integer of any S7 integer type, in a type wide enough for all of them; hex only for
/// the unsigned types, where a bit pattern is what the user means.
fn parse_integer(value_type: ValueType, text: &str, trimmed: &str) -> Result<i64, ValueError> {
    let unsigned = matches!(
        value_type,
        ValueType::Byte | ValueType::Word | ValueType::DWord
    );
    let hex = trimmed
        .strip_prefix("0x")
        .or_else(|| trimmed.strip_prefix("0X"))
        .or_else(|| trimmed.strip_prefix("16#"))
        .filter(|_| unsigned);
    let parsed = match hex {
        Some(digits) => i64::from_str_radix(digits, 16),
        None => trimmed.parse::<i64>(),
    };
    parsed.map_err(|error| match error.kind() {
        IntErrorKind::PosOverflow | IntErrorKind::NegOverflow => ValueError::OutOfRange {
            text: text.to_owned(),
            value_type,
        },
        _ => ValueError::NotANumber {
            text: text.to_owned(),
            value_type,
        },
    })
}

/// JSON-friendly: `true`/`false`, integers in decimal, reals in decimal without an
/// exponent; a non-finite real (only ever read from a PLC) is `null`, JSON having no
/// spelling for it.
impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Bool(value) => write!(f, "{value}"),
            Value::Byte(value) => write!(f, "{value}"),
            Value::SInt(value) => write!(f, "{value}"),
            Value::Word(value) => write!(f, "{value}"),
            Value::Int(value) => write!(f, "{value}"),
            Value::DWord(value) => write!(f, "{value}"),
            Value::DInt(value) => write!(f, "{value}"),
            Value::Real(value) if value.is_finite() => write!(f, "{value}"),
            Value::Real(_) => f.write_str("null"),
        }
    }
}
