//! The bytes of a block: a run of events packed into one blob.
//!
//! A block (one append's events of a minute, in `event_blocks`) and a segment (one point's
//! events of a minute, in `event_segments`) hold their events in this one format. Names
//! (node, point, origin, key source) are numbers of the store's name dictionary
//! ([`NameId`]), times are deltas, integers are LEB128 varints (zigzag where they may be
//! negative): an event of a live stream takes 20 to 30 bytes instead of a row of 16
//! columns and five index entries.
//!
//! ```text
//! block   = version:u8 (1) count:varint event*
//! event   = id:zigzag(id - previous id; the first: id)
//!           node:varint point:varint origin:varint ioa:varint (0: none, else ioa + 1)
//!           value quality:u8 cause:u8
//!           received:zigzag(ms - previous event's received ms; the first: ms)
//!           source:u8 (0 none, 1 valid, 2 invalid) [zigzag(source ms - received ms)]
//!           key:varint (0: none, else source name + 1) [sequence:varint]
//! value   = kind:u8 (the stored value kind: 1 bool, 2 double point, 3 int, 4 float,
//!           5 bits, 6 text) then u8 | u8 | zigzag | f64 little-endian | varint |
//!           length:varint utf-8
//! ```
//!
//! Written here by hand, not by serde with a binary format: the format is part of the
//! stored data and must never change with a crate's version, and decoding is on every
//! query's path (a `Vec` of [`Coded`] with no per-field allocation but text values).

use points::PointValue;

use crate::StoreError;

/// The format version a block starts with.
const VERSION: u8 = 1;

/// A number in the store's name dictionary (`event_names`).
pub(crate) type NameId = u32;

/// One event as a block keeps it: names as dictionary numbers, times in milliseconds.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Coded {
    pub(crate) id: i64,
    pub(crate) node: NameId,
    pub(crate) point: NameId,
    pub(crate) origin: NameId,
    pub(crate) ioa: Option<u32>,
    pub(crate) value: PointValue,
    /// [`crate::quality_to_bits`].
    pub(crate) quality: u8,
    /// [`crate::EventCause::code`].
    pub(crate) cause: u8,
    pub(crate) received_ms: i64,
    /// The source time stamp and its IV bit.
    pub(crate) source: Option<(i64, bool)>,
    /// The idempotent key: the source's name and the sequence number.
    pub(crate) key: Option<(NameId, u64)>,
}

// Without the backends only the fuzz target's decoding is used.
#[cfg_attr(not(feature = "database"), allow(dead_code))]
impl Coded {
    /// The event time ([`crate::EventRecord::event_time`]).
    pub(crate) fn event_ms(&self) -> i64 {
        match self.source {
            Some((ms, false)) => ms,
            _ => self.received_ms,
        }
    }

    /// The value as a trend reads it (booleans, integers and floats but NaN: a value
    /// that is no number has no place on a chart), if it has one.
    pub(crate) fn numeric(&self) -> Option<f64> {
        match self.value {
            PointValue::Bool(b) => Some(f64::from(u8::from(b))),
            // Integers beyond 2^53 round, as the SQL `CAST(value_int AS REAL)` did.
            #[allow(clippy::cast_precision_loss)]
            PointValue::Int(i) => Some(i as f64),
            PointValue::Float(x) if !x.is_nan() => Some(x),
            _ => None,
        }
    }

    /// IV set.
    pub(crate) fn invalid(&self) -> bool {
        self.quality & 1 != 0
    }
}

/// Packs `events` (at most `u32::MAX`) into a block.
#[cfg_attr(not(feature = "database"), allow(dead_code))]
pub(crate) fn encode(events: &[Coded]) -> Vec<u8> {
    let mut out = Vec::with_capacity(8 + events.len() * 28);
    out.push(VERSION);
    put_varint(&mut out, events.len() as u64);
    let (mut previous_id, mut previous_received) = (0i64, 0i64);
    for e in events {
        put_zigzag(&mut out, e.id.wrapping_sub(previous_id));
        previous_id = e.id;
        put_varint(&mut out, u64::from(e.node));
        put_varint(&mut out, u64::from(e.point));
        put_varint(&mut out, u64::from(e.origin));
        put_varint(&mut out, e.ioa.map_or(0, |a| u64::from(a) + 1));
        put_value(&mut out, &e.value);
        out.push(e.quality);
        out.push(e.cause);
        put_zigzag(&mut out, e.received_ms.wrapping_sub(previous_received));
        previous_received = e.received_ms;
        match e.source {
            None => out.push(0),
            Some((ms, invalid)) => {
                out.push(if invalid { 2 } else { 1 });
                put_zigzag(&mut out, ms.wrapping_sub(e.received_ms));
            }
        }
        match e.key {
            None => out.push(0),
            Some((source, sequence)) => {
                put_varint(&mut out, u64::from(source) + 1);
                put_varint(&mut out, sequence);
            }
        }
    }
    out
}

/// Unpacks a block; a malformed one is [`StoreError::Corrupt`], never a panic.
pub(crate) fn decode(bytes: &[u8]) -> Result<Vec<Coded>, StoreError> {
    let mut r = Reader { bytes, at: 0 };
    let version = r.u8()?;
    if version != VERSION {
        return Err(corrupt(format!(
            "block format {version}, expected {VERSION}"
        )));
    }
    let count = r.varint()?;
    // The smallest event takes 12 bytes: a count beyond that is a lie, not an allocation.
    if count > (bytes.len() / 12) as u64 + 1 {
        return Err(corrupt(format!(
            "block of {count} events in {} bytes",
            bytes.len()
        )));
    }
    let mut events = Vec::with_capacity(usize::try_from(count).unwrap_or(0));
    let (mut previous_id, mut previous_received) = (0i64, 0i64);
    for _ in 0..count {
        let id = previous_id.wrapping_add(r.zigzag()?);
        previous_id = id;
        let node = r.name()?;
        let point = r.name()?;
        let origin = r.name()?;
        let ioa = match r.varint()? {
            0 => None,
            n => Some(u32::try_from(n - 1).map_err(|_| corrupt(format!("IOA {}", n - 1)))?),
        };
        let value = r.value()?;
        let quality = r.u8()?;
        let cause = r.u8()?;
        let received_ms = previous_received.wrapping_add(r.zigzag()?);
        previous_received = received_ms;
        let source = match r.u8()? {
            0 => None,
            flag @ (1 | 2) => Some((received_ms.wrapping_add(r.zigzag()?), flag == 2)),
            other => return Err(corrupt(format!("source time flag {other}"))),
        };
        let key = match r.varint()? {
            0 => None,
            n => {
                let source = NameId::try_from(n - 1)
                    .map_err(|_| corrupt(format!("key source name {}", n - 1)))?;
                Some((source, r.varint()?))
            }
        };
        events.push(Coded {
            id,
            node,
            point,
            origin,
            ioa,
            value,
            quality,
            cause,
            received_ms,
            source,
            key,
        });
    }
    if r.at != bytes.len() {
        return Err(corrupt(format!(
            "{} bytes after the last event",
            bytes.len() - r.at
        )));
    }
    Ok(events)
}

fn corrupt(what: String) -> StoreError {
    StoreError::Corrupt(format!("event block: {what}"))
}

fn put_varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v & 0x7F) as u8 | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

fn put_zigzag(out: &mut Vec<u8>, v: i64) {
    put_varint(out, ((v << 1) ^ (v >> 63)) as u64);
}

fn put_value(out: &mut Vec<u8>, value: &PointValue) {
    match value {
        PointValue::Bool(b) => out.extend([1, u8::from(*b)]),
        PointValue::DoublePoint(d) => out.extend([2, *d]),
        PointValue::Int(i) => {
            out.push(3);
            put_zigzag(out, *i);
        }
        PointValue::Float(x) => {
            out.push(4);
            out.extend(x.to_le_bytes());
        }
        PointValue::Bits(b) => {
            out.push(5);
            put_varint(out, u64::from(*b));
        }
        PointValue::Text(t) => {
            out.push(6);
            put_varint(out, t.len() as u64);
            out.extend(t.as_bytes());
        }
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], StoreError> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&end| end <= self.bytes.len())
            .ok_or_else(|| corrupt(format!("cut short at byte {}", self.at)))?;
        let taken = self.bytes.get(self.at..end).unwrap_or_default();
        self.at = end;
        Ok(taken)
    }

    fn u8(&mut self) -> Result<u8, StoreError> {
        Ok(self.take(1)?.first().copied().unwrap_or(0))
    }

    fn varint(&mut self) -> Result<u64, StoreError> {
        let mut v = 0u64;
        for shift in (0..64).step_by(7) {
            let byte = self.u8()?;
            let bits = u64::from(byte & 0x7F);
            if shift == 63 && bits > 1 {
                return Err(corrupt("varint beyond 64 bits".to_owned()));
            }
            v |= bits << shift;
            if byte & 0x80 == 0 {
                return Ok(v);
            }
        }
        Err(corrupt("varint beyond 64 bits".to_owned()))
    }

    fn zigzag(&mut self) -> Result<i64, StoreError> {
        let v = self.varint()?;
        Ok((v >> 1) as i64 ^ -((v & 1) as i64))
    }

    fn name(&mut self) -> Result<NameId, StoreError> {
        let v = self.varint()?;
        NameId::try_from(v).map_err(|_| corrupt(format!("name {v}")))
    }

    fn value(&mut self) -> Result<PointValue, StoreError> {
        Ok(match self.u8()? {
            1 => PointValue::Bool(self.u8()? != 0),
            2 => PointValue::DoublePoint(self.u8()?),
            3 => PointValue::Int(self.zigzag()?),
            4 => {
                let mut le = [0u8; 8];
                le.copy_from_slice(self.take(8)?);
                PointValue::Float(f64::from_le_bytes(le))
            }
            5 => {
                let v = self.varint()?;
                PointValue::Bits(u32::try_from(v).map_err(|_| corrupt(format!("bits {v}")))?)
            }
            6 => {
                let n = self.varint()?;
                let n = usize::try_from(n).map_err(|_| corrupt(format!("text of {n} bytes")))?;
                let text = std::str::from_utf8(self.take(n)?)
                    .map_err(|_| corrupt("text not UTF-8".to_owned()))?;
                PointValue::Text(text.to_owned())
            }
            kind => return Err(corrupt(format!("value kind {kind}"))),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn value() -> impl Strategy<Value = PointValue> {
        prop_oneof![
            any::<bool>().prop_map(PointValue::Bool),
            (0u8..4).prop_map(PointValue::DoublePoint),
            any::<i64>().prop_map(PointValue::Int),
            any::<f64>()
                .prop_filter("NaN never equals itself", |x| !x.is_nan())
                .prop_map(PointValue::Float),
            any::<u32>().prop_map(PointValue::Bits),
            ".{0,40}".prop_map(PointValue::Text),
        ]
    }

    fn coded() -> impl Strategy<Value = Coded> {
        (
            (any::<i64>(), any::<u32>(), any::<u32>(), any::<u32>()),
            (
                proptest::option::of(any::<u32>()),
                value(),
                any::<u8>(),
                1u8..8,
            ),
            any::<i64>(),
            proptest::option::of((any::<i64>(), any::<bool>())),
            proptest::option::of((0u32..u32::MAX, any::<u64>())),
        )
            .prop_map(
                |(
                    (id, node, point, origin),
                    (ioa, value, quality, cause),
                    received_ms,
                    source,
                    key,
                )| {
                    Coded {
                        id,
                        node,
                        point,
                        origin,
                        ioa,
                        value,
                        quality,
                        cause,
                        received_ms,
                        source,
                        key,
                    }
                },
            )
    }

    proptest! {
        #[test]
        fn a_block_decodes_to_what_was_encoded(events in proptest::collection::vec(coded(), 0..40)) {
            prop_assert_eq!(decode(&encode(&events)).unwrap(), events);
        }

        #[test]
        fn any_bytes_decode_to_events_or_an_error(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
            let _ = decode(&bytes);
        }

        #[test]
        fn a_cut_or_extended_block_is_an_error(events in proptest::collection::vec(coded(), 1..10), cut in 1usize..20) {
            let bytes = encode(&events);
            let short = &bytes[..bytes.len().saturating_sub(cut)];
            prop_assert!(decode(short).is_err());
            let mut long = bytes.clone();
            long.push(0);
            prop_assert!(decode(&long).is_err());
        }
    }

    #[test]
    fn a_live_event_takes_about_twenty_bytes() {
        let base = Coded {
            id: 1_000_000,
            node: 3,
            point: 4_000,
            origin: 3,
            ioa: Some(4_000),
            value: PointValue::Float(230.25),
            quality: 0,
            cause: 1,
            received_ms: 1_780_000_000_000,
            source: Some((1_780_000_000_000 - 12, false)),
            key: Some((9, 123_456_789)),
        };
        let events: Vec<Coded> = (0..500)
            .map(|i| Coded {
                id: base.id + i,
                received_ms: base.received_ms + i / 300,
                key: Some((9, 123_456_789 + i as u64)),
                ..base.clone()
            })
            .collect();
        let bytes = encode(&events);
        assert!(bytes.len() < 500 * 30, "{} bytes", bytes.len());
        assert_eq!(decode(&bytes).unwrap(), events);
    }

    /// The fuzz smoke's seed (scripts/fuzz-smoke.sh), byte by byte.
    #[test]
    fn the_layout_is_as_documented() {
        let bytes = [
            1, 2, // version, two events
            0x14, 1, 2, 1, 0, // id 10, node 1, point 2, origin 1, no IOA
            4, 0, 0, 0, 0, 0, 0, 0x24, 0x40, // float 10.0
            0, 1, 0xd0, 0x0f, // quality, cause, received 1000
            1, 0x17, 0, // a valid source time 12 ms earlier; no key
            2, 1, 3, 1, 0x2b, // id 11, node 1, point 3, origin 1, IOA 42
            6, 2, b'o', b'k', 1, 3, 2, 0, // text "ok", IV, cause 3, received 1001
            4, 7, // key: source 3, sequence 7
        ];
        let events = decode(&bytes).unwrap();
        assert_eq!(events.len(), 2);
        assert_eq!(
            (events[0].id, events[0].value.clone(), events[0].event_ms()),
            (10, PointValue::Float(10.0), 988)
        );
        assert_eq!(
            (
                events[1].id,
                events[1].ioa,
                events[1].received_ms,
                events[1].key
            ),
            (11, Some(42), 1001, Some((3, 7)))
        );
        assert!(events[1].invalid());
        assert_eq!(encode(&events), bytes);
    }

    #[test]
    fn a_wrong_version_or_a_lying_count_is_refused() {
        assert!(decode(&[2, 0]).is_err());
        assert!(decode(&[1, 0xFF, 0xFF, 0xFF, 0x0F]).is_err());
        assert_eq!(decode(&[1, 0]).unwrap(), Vec::new());
        assert!(decode(&[]).is_err());
    }
}
