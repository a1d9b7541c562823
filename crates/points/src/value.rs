//! The typed value of a point.

use std::fmt;

/// A typed point value, as the point database holds it.
#[derive(Debug, Clone, PartialEq)]
pub enum PointValue {
    /// Single-point information or a single command (on/off).
    Bool(bool),
    /// Double-point information or a double command: 0 and 3 indeterminate, 1 off, 2 on.
    DoublePoint(u8),
    /// Step position, scaled value, integrated total or any other integer.
    Int(i64),
    /// Normalized or short floating-point value.
    Float(f64),
    /// Bitstring of 32 bits.
    Bits(u32),
    /// Free text (device messages, fault descriptions).
    Text(String),
}

impl fmt::Display for PointValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PointValue::Bool(b) => write!(f, "{}", if *b { "ON" } else { "OFF" }),
            PointValue::DoublePoint(0) => f.write_str("INTERMEDIATE"),
            PointValue::DoublePoint(1) => f.write_str("OFF"),
            PointValue::DoublePoint(2) => f.write_str("ON"),
            PointValue::DoublePoint(_) => f.write_str("INDETERMINATE"),
            PointValue::Int(i) => write!(f, "{i}"),
            PointValue::Float(x) => write!(f, "{x}"),
            PointValue::Bits(b) => write!(f, "0x{b:08X}"),
            PointValue::Text(t) => f.write_str(t),
        }
    }
}
