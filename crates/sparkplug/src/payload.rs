//! The Sparkplug B payload (`org.eclipse.tahu.protobuf.Payload`, proto2), written as prost
//! messages from the Sparkplug 3.0 specification with the field numbers of the published
//! `sparkplug_b.proto`. Only what an edge node of a station uses is modelled: data sets,
//! templates and extensions are left out, and prost skips their fields when it meets them
//! (a host's NCMD carrying one still decodes).

use prost::Message;

/// Why bytes are not a Sparkplug payload.
#[derive(Debug, thiserror::Error)]
#[error("not a Sparkplug B payload: {0}")]
pub struct DecodeError(#[from] prost::DecodeError);

/// A Sparkplug B payload.
#[derive(Clone, PartialEq, Message)]
pub struct Payload {
    /// Milliseconds since the Unix epoch (UTC) when the payload was made.
    #[prost(uint64, optional, tag = "1")]
    pub timestamp: Option<u64>,
    /// The metrics.
    #[prost(message, repeated, tag = "2")]
    pub metrics: Vec<Metric>,
    /// The sequence number, 0..=255 (none in NDEATH and commands).
    #[prost(uint64, optional, tag = "3")]
    pub seq: Option<u64>,
    /// A UUID describing the body.
    #[prost(string, optional, tag = "4")]
    pub uuid: Option<String>,
    /// An opaque body.
    #[prost(bytes = "vec", optional, tag = "5")]
    pub body: Option<Vec<u8>>,
}

impl Payload {
    /// Decodes a payload received from the network.
    pub fn decode_bytes(bytes: &[u8]) -> Result<Payload, DecodeError> {
        Ok(Payload::decode(bytes)?)
    }

    /// The payload's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        self.encode_to_vec()
    }
}

/// One metric of a payload.
#[derive(Clone, PartialEq, Message)]
pub struct Metric {
    /// Its name (in births and in data without aliases).
    #[prost(string, optional, tag = "1")]
    pub name: Option<String>,
    /// Its alias, given in the birth.
    #[prost(uint64, optional, tag = "2")]
    pub alias: Option<u64>,
    /// Milliseconds since the Unix epoch (UTC) of the value.
    #[prost(uint64, optional, tag = "3")]
    pub timestamp: Option<u64>,
    /// Its data type code ([`crate::DataType`]).
    #[prost(uint32, optional, tag = "4")]
    pub datatype: Option<u32>,
    /// A value from the past (store and forward).
    #[prost(bool, optional, tag = "5")]
    pub is_historical: Option<bool>,
    /// A value not to be stored by hosts.
    #[prost(bool, optional, tag = "6")]
    pub is_transient: Option<bool>,
    /// No value.
    #[prost(bool, optional, tag = "7")]
    pub is_null: Option<bool>,
    /// Metadata (multi-part files and the like).
    #[prost(message, optional, tag = "8")]
    pub metadata: Option<MetaData>,
    /// Its properties (`Quality`, ...).
    #[prost(message, optional, tag = "9")]
    pub properties: Option<PropertySet>,
    /// The value.
    #[prost(oneof = "MetricValue", tags = "10, 11, 12, 13, 14, 15, 16")]
    pub value: Option<MetricValue>,
}

/// A metric's value, by the field its data type uses (signed integers are sent as their
/// two's complement in the unsigned fields).
#[derive(Clone, PartialEq, prost::Oneof)]
pub enum MetricValue {
    /// Int8, Int16, Int32, UInt8, UInt16, UInt32.
    #[prost(uint32, tag = "10")]
    IntValue(u32),
    /// Int64, UInt64, DateTime.
    #[prost(uint64, tag = "11")]
    LongValue(u64),
    /// Float.
    #[prost(float, tag = "12")]
    FloatValue(f32),
    /// Double.
    #[prost(double, tag = "13")]
    DoubleValue(f64),
    /// Boolean.
    #[prost(bool, tag = "14")]
    BooleanValue(bool),
    /// String, Text, UUID.
    #[prost(string, tag = "15")]
    StringValue(String),
    /// Bytes, File.
    #[prost(bytes = "vec", tag = "16")]
    BytesValue(Vec<u8>),
}

/// A metric's metadata.
#[derive(Clone, PartialEq, Message)]
pub struct MetaData {
    /// Part of a multi-part value.
    #[prost(bool, optional, tag = "1")]
    pub is_multi_part: Option<bool>,
    /// The content's MIME type.
    #[prost(string, optional, tag = "2")]
    pub content_type: Option<String>,
    /// Size in bytes.
    #[prost(uint64, optional, tag = "3")]
    pub size: Option<u64>,
    /// Sequence of a multi-part value.
    #[prost(uint64, optional, tag = "4")]
    pub seq: Option<u64>,
    /// File name.
    #[prost(string, optional, tag = "5")]
    pub file_name: Option<String>,
    /// File type.
    #[prost(string, optional, tag = "6")]
    pub file_type: Option<String>,
    /// MD5 of the content.
    #[prost(string, optional, tag = "7")]
    pub md5: Option<String>,
    /// Free text.
    #[prost(string, optional, tag = "8")]
    pub description: Option<String>,
}

/// Properties of a metric: keys and values in step.
#[derive(Clone, PartialEq, Message)]
pub struct PropertySet {
    /// The keys.
    #[prost(string, repeated, tag = "1")]
    pub keys: Vec<String>,
    /// The values, one per key.
    #[prost(message, repeated, tag = "2")]
    pub values: Vec<PropertyValue>,
}

impl PropertySet {
    /// The value of `key`, if set.
    pub fn get(&self, key: &str) -> Option<&PropertyValue> {
        self.keys
            .iter()
            .position(|k| k == key)
            .and_then(|index| self.values.get(index))
    }
}

/// A list of property sets.
#[derive(Clone, PartialEq, Message)]
pub struct PropertySetList {
    /// The sets.
    #[prost(message, repeated, tag = "1")]
    pub propertyset: Vec<PropertySet>,
}

/// One property's value.
#[derive(Clone, PartialEq, Message)]
pub struct PropertyValue {
    /// Its data type code.
    #[prost(uint32, optional, tag = "1")]
    pub r#type: Option<u32>,
    /// No value.
    #[prost(bool, optional, tag = "2")]
    pub is_null: Option<bool>,
    /// The value.
    #[prost(oneof = "PropertyValueKind", tags = "3, 4, 5, 6, 7, 8, 9, 10")]
    pub value: Option<PropertyValueKind>,
}

/// A property's value, by the field its data type uses.
#[derive(Clone, PartialEq, prost::Oneof)]
pub enum PropertyValueKind {
    /// Int8..Int32, UInt8..UInt32.
    #[prost(uint32, tag = "3")]
    IntValue(u32),
    /// Int64, UInt64, DateTime.
    #[prost(uint64, tag = "4")]
    LongValue(u64),
    /// Float.
    #[prost(float, tag = "5")]
    FloatValue(f32),
    /// Double.
    #[prost(double, tag = "6")]
    DoubleValue(f64),
    /// Boolean.
    #[prost(bool, tag = "7")]
    BooleanValue(bool),
    /// String, Text.
    #[prost(string, tag = "8")]
    StringValue(String),
    /// A nested set.
    #[prost(message, tag = "9")]
    PropertysetValue(PropertySet),
    /// A list of sets.
    #[prost(message, tag = "10")]
    PropertysetsValue(PropertySetList),
}
