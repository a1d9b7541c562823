//! Sparkplug data types (Sparkplug 3.0, section 6.4.16) and the typed values an edge node
//! publishes, with their place in a metric.

use crate::payload::MetricValue;

/// A metric's data type code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum DataType {
    /// Signed 8-bit integer.
    Int8 = 1,
    /// Signed 16-bit integer.
    Int16 = 2,
    /// Signed 32-bit integer.
    Int32 = 3,
    /// Signed 64-bit integer.
    Int64 = 4,
    /// Unsigned 8-bit integer.
    UInt8 = 5,
    /// Unsigned 16-bit integer.
    UInt16 = 6,
    /// Unsigned 32-bit integer.
    UInt32 = 7,
    /// Unsigned 64-bit integer.
    UInt64 = 8,
    /// 32-bit floating point.
    Float = 9,
    /// 64-bit floating point.
    Double = 10,
    /// Boolean.
    Boolean = 11,
    /// UTF-8 string.
    String = 12,
    /// Milliseconds since the Unix epoch.
    DateTime = 13,
    /// UTF-8 text.
    Text = 14,
}

impl DataType {
    /// The type of a code, if it is one an edge node of a station uses.
    pub fn from_code(code: u32) -> Option<DataType> {
        use DataType::*;
        Some(match code {
            1 => Int8,
            2 => Int16,
            3 => Int32,
            4 => Int64,
            5 => UInt8,
            6 => UInt16,
            7 => UInt32,
            8 => UInt64,
            9 => Float,
            10 => Double,
            11 => Boolean,
            12 => String,
            13 => DateTime,
            14 => Text,
            _ => return None,
        })
    }

    /// Its code.
    pub fn code(self) -> u32 {
        self as u32
    }

    /// `value` as a metric value of this type (integers wrapped to the type's width as
    /// Sparkplug encodes them, in two's complement), or `None` when the value's family
    /// does not fit the type.
    pub fn encode(self, value: &Value) -> Option<MetricValue> {
        use DataType::*;
        Some(match (self, value) {
            (Boolean, Value::Bool(b)) => MetricValue::BooleanValue(*b),
            (Int8 | Int16 | Int32 | UInt8 | UInt16 | UInt32, Value::Int(i)) => {
                MetricValue::IntValue(*i as u32)
            }
            (Int64 | UInt64 | DateTime, Value::Int(i)) => MetricValue::LongValue(*i as u64),
            (Float, Value::Float(x)) => MetricValue::FloatValue(*x as f32),
            (Double, Value::Float(x)) => MetricValue::DoubleValue(*x),
            (String | Text, Value::Text(t)) => MetricValue::StringValue(t.clone()),
            _ => return None,
        })
    }

    /// A metric value read as this type: integers sign-extended from the type's width.
    pub fn decode(self, value: &MetricValue) -> Option<Value> {
        use DataType::*;
        Some(match (self, value) {
            (Boolean, MetricValue::BooleanValue(b)) => Value::Bool(*b),
            (Int8, MetricValue::IntValue(i)) => Value::Int(i64::from(*i as u8 as i8)),
            (Int16, MetricValue::IntValue(i)) => Value::Int(i64::from(*i as u16 as i16)),
            (Int32, MetricValue::IntValue(i)) => Value::Int(i64::from(*i as i32)),
            (UInt8, MetricValue::IntValue(i)) => Value::Int(i64::from(*i as u8)),
            (UInt16, MetricValue::IntValue(i)) => Value::Int(i64::from(*i as u16)),
            (UInt32, MetricValue::IntValue(i)) => Value::Int(i64::from(*i)),
            (Int64 | UInt64 | DateTime, MetricValue::LongValue(l)) => Value::Int(*l as i64),
            (Float, MetricValue::FloatValue(x)) => Value::Float(f64::from(*x)),
            (Double, MetricValue::DoubleValue(x)) => Value::Float(*x),
            (String | Text, MetricValue::StringValue(t)) => Value::Text(t.clone()),
            _ => return None,
        })
    }
}

/// A value as an edge node holds it, before it takes its metric's type.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// Boolean.
    Bool(bool),
    /// Any integer type.
    Int(i64),
    /// Float or Double.
    Float(f64),
    /// String or Text.
    Text(String),
}

/// The quality a metric carries in its `Quality` property (Sparkplug 3.0: an Int32 of
/// 0 bad, 192 good, 500 stale).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum QualityCode {
    /// The value cannot be trusted (its source failed).
    Bad,
    /// Good.
    Good,
    /// The value was not refreshed: the last known one.
    Stale,
}

impl QualityCode {
    /// The property's key.
    pub const PROPERTY: &'static str = "Quality";

    /// Its Int32 value.
    pub fn code(self) -> i32 {
        match self {
            QualityCode::Bad => 0,
            QualityCode::Good => 192,
            QualityCode::Stale => 500,
        }
    }

    /// The quality of a code.
    pub fn from_code(code: i32) -> Option<QualityCode> {
        match code {
            0 => Some(QualityCode::Bad),
            192 => Some(QualityCode::Good),
            500 => Some(QualityCode::Stale),
            _ => None,
        }
    }
}
