//! Frames, queries and replies of the EKM66 (spec §3, §4), sans-IO.
//!
//! Every message is an FT1.2 variable-length frame `68 L L 68 <L user octets> CS 16`,
//! CS the sum of the user octets modulo 256. The user octets start with the fixed prefix
//! `01 00` and the function code (0x01 status, 0x03 trip counters, 0x04 fault record).
//!
//! [`Deframer`] cuts frames out of a byte stream by their length octet (never by looking
//! for 0x16, which occurs in data, e.g. the year 22) and resynchronises on the next 0x68
//! after anything that does not validate. [`decode_reply`] checks a frame against the
//! query that was sent (spec §4.4) and decodes it with the offsets of a [`CodecConfig`].

use std::fmt;

use serde::{Deserialize, Serialize};

/// Start octet of a frame (both starts).
pub const START: u8 = 0x68;
/// End octet of a frame.
pub const END: u8 = 0x16;
/// The prefix of every query's user data (C and A in FT1.2 terms; EKM-A8).
pub const PREFIX: [u8; 2] = [0x01, 0x00];
/// Function code of the status query.
pub const FUNCTION_STATUS: u8 = 0x01;
/// Function code of the trip-counter query.
pub const FUNCTION_COUNTERS: u8 = 0x03;
/// Function code of the fault-record query.
pub const FUNCTION_FAULT: u8 = 0x04;
/// L of a fault record reply (23 octets, EKM-A4).
pub const FAULT_RECORD_LENGTH: u8 = 0x11;
/// L of an empty fault slot reply (12 octets).
pub const EMPTY_SLOT_LENGTH: u8 = 0x06;
/// Longest frame: L = 255.
pub const MAX_FRAME: usize = 255 + 6;

/// Why octets were not a frame, or a frame not the reply expected.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FrameError {
    /// Octets before a start octet were skipped.
    #[error("{0} octets of garbage before a start octet")]
    Garbage(usize),
    /// The two length octets differ.
    #[error("length octets differ ({0:#04x}, {1:#04x})")]
    LengthMismatch(u8, u8),
    /// The fourth octet is not the second start octet.
    #[error("no second start octet (found {0:#04x})")]
    NoSecondStart(u8),
    /// The checksum does not match.
    #[error("checksum {found:#04x}, expected {expected:#04x}")]
    Checksum {
        /// In the frame.
        found: u8,
        /// The sum of the user octets.
        expected: u8,
    },
    /// The octet at L + 5 is not 0x16.
    #[error("no end octet (found {0:#04x})")]
    NoEnd(u8),
    /// A frame was cut off (the line went quiet, the reply timed out).
    #[error("truncated frame: {have} of {want} octets")]
    Truncated {
        /// Octets received.
        have: usize,
        /// Octets the length octet announced.
        want: usize,
    },
}

/// Why a valid frame is not the reply to the query sent (spec §4.4).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ReplyError {
    /// The header (L) is not one expected for the query.
    #[error("L = {length:#04x} does not answer a {query} query")]
    UnexpectedLength {
        /// The frame's L.
        length: u8,
        /// The query sent.
        query: Query,
    },
    /// The counter octets are not a multiple of the counter width.
    #[error("{octets} counter octets are not a multiple of {width}")]
    CounterLength {
        /// L − 3.
        octets: usize,
        /// The configured width.
        width: usize,
    },
    /// A BCD time octet has a nibble above 9.
    #[error("invalid BCD octet {0:#04x}")]
    Bcd(u8),
    /// The reply is shorter than its layout's offsets (a layout misconfigured).
    #[error("field at offset {0} outside the frame")]
    Offset(usize),
    /// The function echo names another query: a late reply to an earlier query (a status
    /// reply is also a frame of L ≥ 3, which a counter query would otherwise take).
    #[error("function echo {function:#04x} answers another query than the {query} query")]
    OtherFunction {
        /// The echo at position 6.
        function: u8,
        /// The query sent.
        query: Query,
    },
}

/// Why octets are not a query (the simulator's side).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum QueryError {
    /// Not one of the three query shapes.
    #[error("not an EKM66 query: {0:02x?}")]
    Unknown(Vec<u8>),
}

/// The three queries of the master.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Query {
    /// Status (`68 03 03 68 01 00 01 02 16`).
    Status,
    /// Trip counters (`68 03 03 68 01 00 03 04 16`).
    Counters,
    /// One fault-stack entry by index.
    FaultRecord(u8),
}

impl fmt::Display for Query {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Query::Status => f.write_str("status"),
            Query::Counters => f.write_str("counters"),
            Query::FaultRecord(index) => write!(f, "fault record {index}"),
        }
    }
}

impl Query {
    /// The query's frame.
    pub fn encode(&self) -> Vec<u8> {
        match self {
            Query::Status => encode_frame(&[0x01, 0x00, FUNCTION_STATUS]),
            Query::Counters => encode_frame(&[0x01, 0x00, FUNCTION_COUNTERS]),
            Query::FaultRecord(index) => encode_frame(&[0x01, 0x00, FUNCTION_FAULT, *index]),
        }
    }

    /// A query from a frame's user octets (prefix, function, index).
    pub fn from_user_data(user: &[u8]) -> Result<Query, QueryError> {
        match user {
            [0x01, 0x00, FUNCTION_STATUS] => Ok(Query::Status),
            [0x01, 0x00, FUNCTION_COUNTERS] => Ok(Query::Counters),
            [0x01, 0x00, FUNCTION_FAULT, index] => Ok(Query::FaultRecord(*index)),
            other => Err(QueryError::Unknown(other.to_vec())),
        }
    }
}

/// The checksum of user octets: their sum modulo 256, as FT1.2's (the serial-line
/// crate's `octet_sum`).
pub use serial_line::octet_sum as checksum;

/// A frame around user octets; at most 255 are used (the rest is cut).
pub fn encode_frame(user: &[u8]) -> Vec<u8> {
    let user = user.get(..user.len().min(255)).unwrap_or_default();
    let length = u8::try_from(user.len()).unwrap_or(u8::MAX);
    let mut frame = Vec::with_capacity(user.len() + 6);
    frame.extend_from_slice(&[START, length, length, START]);
    frame.extend_from_slice(user);
    frame.push(checksum(user));
    frame.push(END);
    frame
}

/// A validated frame: the whole frame's octets (header to end octet).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Frame(Vec<u8>);

impl Frame {
    /// The frame's octets.
    pub fn as_bytes(&self) -> &[u8] {
        &self.0
    }

    /// L.
    pub fn length(&self) -> u8 {
        self.0.get(1).copied().unwrap_or(0)
    }

    /// The user octets (between the header and the checksum).
    pub fn user_data(&self) -> &[u8] {
        self.0
            .get(4..self.0.len().saturating_sub(2))
            .unwrap_or_default()
    }

    /// The octet at a 0-based frame position.
    pub fn octet(&self, position: usize) -> Result<u8, ReplyError> {
        self.0
            .get(position)
            .copied()
            .ok_or(ReplyError::Offset(position))
    }

    /// Validates one complete frame (exactly its octets).
    pub fn parse(bytes: &[u8]) -> Result<Frame, FrameError> {
        let mut deframer = Deframer::new();
        deframer.push(bytes);
        match deframer.next_frame() {
            Some(Ok(frame)) if deframer.buffered() == 0 => Ok(frame),
            Some(Ok(frame)) => Err(FrameError::Garbage(bytes.len() - frame.0.len())),
            Some(Err(error)) => Err(error),
            None => Err(deframer.abandon().unwrap_or(FrameError::Truncated {
                have: bytes.len(),
                want: 6,
            })),
        }
    }
}

/// Cuts frames out of a byte stream (spec §4.4): sync on 0x68, the header
/// `68 L L 68`, then exactly L + 2 more octets, checked. Anything that does not validate
/// drops its first octet and the search goes on from the next 0x68.
#[derive(Debug, Default, Clone)]
pub struct Deframer {
    buffer: Vec<u8>,
}

impl Deframer {
    /// An empty deframer.
    pub fn new() -> Deframer {
        Deframer::default()
    }

    /// Octets received.
    pub fn push(&mut self, bytes: &[u8]) {
        self.buffer.extend_from_slice(bytes);
    }

    /// Octets held (a partial frame).
    pub fn buffered(&self) -> usize {
        self.buffer.len()
    }

    /// Drops a partial frame (the line went quiet, a new query is sent); the error says
    /// what was dropped, `None` when nothing was held.
    pub fn abandon(&mut self) -> Option<FrameError> {
        if self.buffer.is_empty() {
            return None;
        }
        let have = self.buffer.len();
        let want = match self.buffer.as_slice() {
            [START, length, ..] => usize::from(*length) + 6,
            _ => 0,
        };
        self.buffer.clear();
        Some(if want > have {
            FrameError::Truncated { have, want }
        } else {
            FrameError::Garbage(have)
        })
    }

    /// The next frame or error; `None` when more octets are needed.
    pub fn next_frame(&mut self) -> Option<Result<Frame, FrameError>> {
        // Sync: everything before the first start octet is garbage.
        let start = self.buffer.iter().position(|octet| *octet == START);
        match start {
            None if self.buffer.is_empty() => return None,
            None => {
                let skipped = self.buffer.len();
                self.buffer.clear();
                return Some(Err(FrameError::Garbage(skipped)));
            }
            Some(0) => {}
            Some(skipped) => {
                self.buffer.drain(..skipped);
                return Some(Err(FrameError::Garbage(skipped)));
            }
        }
        let (first, second, third) = match self.buffer.as_slice() {
            [_, first, second, third, ..] => (*first, *second, *third),
            _ => return None,
        };
        if first != second {
            self.buffer.drain(..1);
            return Some(Err(FrameError::LengthMismatch(first, second)));
        }
        if third != START {
            self.buffer.drain(..1);
            return Some(Err(FrameError::NoSecondStart(third)));
        }
        let total = usize::from(first) + 6;
        let frame = self.buffer.get(..total)?;
        let user = frame.get(4..total - 2).unwrap_or_default();
        let found = frame.get(total - 2).copied().unwrap_or(0);
        let end = frame.get(total - 1).copied().unwrap_or(0);
        let expected = checksum(user);
        let error = if found != expected {
            Some(FrameError::Checksum { found, expected })
        } else if end != END {
            Some(FrameError::NoEnd(end))
        } else {
            None
        };
        if let Some(error) = error {
            self.buffer.drain(..1);
            return Some(Err(error));
        }
        let frame: Vec<u8> = self.buffer.drain(..total).collect();
        Some(Ok(Frame(frame)))
    }
}

/// Where the status reply's fields are (frame positions, 0-based), chosen by its L
/// (spec §4.1, EKM-A2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct StatusLayout {
    /// L of this layout's frames.
    pub length: u8,
    /// The status code.
    pub status: usize,
    /// The car position.
    pub position: usize,
    /// The target floor.
    pub target: usize,
    /// The direction of travel.
    pub direction: usize,
    /// The first of three time octets: second, minute, hour.
    pub time: usize,
}

impl StatusLayout {
    /// The adopted layout: 20 octets, L = 0x0E; status 7, position 8, target 9,
    /// direction 10, time 15–17.
    pub const ADOPTED: StatusLayout = StatusLayout {
        length: 0x0E,
        status: 7,
        position: 8,
        target: 9,
        direction: 10,
        time: 15,
    };
    /// The alternative reading of the printed positions: 21 octets, L = 0x0F; status 8,
    /// position 9, target 10, direction 11, time 16–18.
    pub const ALTERNATIVE: StatusLayout = StatusLayout {
        length: 0x0F,
        status: 8,
        position: 9,
        target: 10,
        direction: 11,
        time: 16,
    };

    /// Octets in this layout's frames.
    pub fn frame_len(&self) -> usize {
        usize::from(self.length) + 6
    }
}

/// Where the fault record's fields are (spec §4.3, frame positions).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct FaultLayout {
    /// The index of the record read.
    pub index: usize,
    /// The index of the last record stored.
    pub last_index: usize,
    /// Second, minute, hour, day, month, year (six octets).
    pub time: usize,
    /// The fault code.
    pub code: usize,
    /// The floor the car was at.
    pub floor: usize,
    /// The target floor.
    pub target: usize,
}

impl FaultLayout {
    /// The positions of spec §4.3.
    pub const SPEC: FaultLayout = FaultLayout {
        index: 8,
        last_index: 9,
        time: 11,
        code: 17,
        floor: 19,
        target: 20,
    };
}

/// How the direction octet is coded (EKM-A6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct DirectionCoding {
    /// The value for a car at rest.
    pub stopped: u8,
    /// The value for travel up.
    pub up: u8,
    /// The value for travel down.
    pub down: u8,
}

impl Default for DirectionCoding {
    fn default() -> Self {
        DirectionCoding {
            stopped: 0,
            up: 1,
            down: 2,
        }
    }
}

/// The direction of travel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Direction {
    /// At rest.
    Stopped,
    /// Up.
    Up,
    /// Down.
    Down,
    /// A value the coding does not know.
    Unknown(u8),
}

impl fmt::Display for Direction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Direction::Stopped => f.write_str("stopped"),
            Direction::Up => f.write_str("up"),
            Direction::Down => f.write_str("down"),
            Direction::Unknown(value) => write!(f, "unknown({value})"),
        }
    }
}

impl DirectionCoding {
    /// Decodes an octet.
    pub fn decode(&self, value: u8) -> Direction {
        if value == self.stopped {
            Direction::Stopped
        } else if value == self.up {
            Direction::Up
        } else if value == self.down {
            Direction::Down
        } else {
            Direction::Unknown(value)
        }
    }

    /// Encodes a direction.
    pub fn encode(&self, direction: Direction) -> u8 {
        match direction {
            Direction::Stopped => self.stopped,
            Direction::Up => self.up,
            Direction::Down => self.down,
            Direction::Unknown(value) => value,
        }
    }
}

/// How time and date octets are coded (EKM-A6).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum TimeEncoding {
    /// Plain binary (default).
    #[default]
    Binary,
    /// Two BCD digits per octet.
    Bcd,
}

impl TimeEncoding {
    /// Decodes one octet.
    pub fn decode(&self, octet: u8) -> Result<u8, ReplyError> {
        match self {
            TimeEncoding::Binary => Ok(octet),
            TimeEncoding::Bcd => {
                let (high, low) = (octet >> 4, octet & 0x0F);
                if high > 9 || low > 9 {
                    Err(ReplyError::Bcd(octet))
                } else {
                    Ok(high * 10 + low)
                }
            }
        }
    }

    /// Encodes one value (BCD keeps the last two decimal digits).
    pub fn encode(&self, value: u8) -> u8 {
        match self {
            TimeEncoding::Binary => value,
            TimeEncoding::Bcd => {
                let value = value % 100;
                ((value / 10) << 4) | (value % 10)
            }
        }
    }
}

/// Width of one trip counter (EKM-A3).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum CounterWidth {
    /// One octet per floor, as printed (default).
    #[default]
    One,
    /// Two octets, little-endian.
    Two,
    /// Four octets, little-endian.
    Four,
}

impl CounterWidth {
    /// Octets per counter.
    pub fn octets(&self) -> usize {
        match self {
            CounterWidth::One => 1,
            CounterWidth::Two => 2,
            CounterWidth::Four => 4,
        }
    }

    /// The width of 1, 2 or 4 octets.
    pub fn from_octets(octets: u8) -> Option<CounterWidth> {
        match octets {
            1 => Some(CounterWidth::One),
            2 => Some(CounterWidth::Two),
            4 => Some(CounterWidth::Four),
            _ => None,
        }
    }

    /// The largest value a counter holds.
    pub fn max(&self) -> u32 {
        match self {
            CounterWidth::One => u32::from(u8::MAX),
            CounterWidth::Two => u32::from(u16::MAX),
            CounterWidth::Four => u32::MAX,
        }
    }
}

/// The decoders of one installation: which layouts are accepted and how fields are
/// coded. Both ends of a line must agree.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct CodecConfig {
    /// The status layouts accepted, each chosen by its L; default the adopted and the
    /// alternative layout (EKM-A2).
    pub status_layouts: Vec<StatusLayout>,
    /// The fault record's positions.
    pub fault_layout: FaultLayout,
    /// Octets per trip counter.
    pub counter_width: CounterWidth,
    /// The direction octet's values.
    pub direction: DirectionCoding,
    /// Binary or BCD time and date.
    pub time: TimeEncoding,
    /// The year of a date octet 0.
    pub year_base: u16,
}

impl Default for CodecConfig {
    fn default() -> Self {
        CodecConfig {
            status_layouts: vec![StatusLayout::ADOPTED, StatusLayout::ALTERNATIVE],
            fault_layout: FaultLayout::SPEC,
            counter_width: CounterWidth::One,
            direction: DirectionCoding::default(),
            time: TimeEncoding::Binary,
            year_base: 2000,
        }
    }
}

/// The board's time of day.
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize,
)]
pub struct TimeOfDay {
    /// Hour.
    pub hour: u8,
    /// Minute.
    pub minute: u8,
    /// Second.
    pub second: u8,
}

impl fmt::Display for TimeOfDay {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:02}:{:02}:{:02}", self.hour, self.minute, self.second)
    }
}

/// A fault's time of occurrence as the board stores it (not checked against the
/// calendar: the archive keeps what the board said).
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize,
)]
pub struct FaultTime {
    /// Year (year base + octet).
    pub year: u16,
    /// Month.
    pub month: u8,
    /// Day.
    pub day: u8,
    /// Time of day.
    pub time: TimeOfDay,
}

impl fmt::Display for FaultTime {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:04}-{:02}-{:02} {}",
            self.year, self.month, self.day, self.time
        )
    }
}

/// The status reply.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Status {
    /// The status code (Appendix A).
    pub code: u8,
    /// The car position (raw floor number).
    pub position: u8,
    /// The target floor of the current trip.
    pub target: u8,
    /// The direction of travel.
    pub direction: Direction,
    /// The board's time of day.
    pub time: TimeOfDay,
}

/// One fault-stack entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct FaultRecord {
    /// The index of this record.
    pub index: u8,
    /// The index of the last record stored when this one was read.
    pub last_index: u8,
    /// When the fault happened.
    pub time: FaultTime,
    /// The fault code (Appendix B).
    pub code: u8,
    /// The floor the car was at.
    pub floor: u8,
    /// The target floor (during travel).
    pub target: u8,
}

/// A decoded reply.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Reply {
    /// The status reply.
    Status(Status),
    /// The trip counters, floor 1 first.
    Counters(Vec<u32>),
    /// A stored fault.
    Fault(FaultRecord),
    /// An empty fault slot (the index is the one echoed at position 7).
    EmptySlot {
        /// The index echoed.
        index: u8,
    },
}

fn time_octets(frame: &Frame, start: usize, config: &CodecConfig) -> Result<TimeOfDay, ReplyError> {
    let octet = |offset: usize| config.time.decode(frame.octet(start + offset)?);
    Ok(TimeOfDay {
        second: octet(0)?,
        minute: octet(1)?,
        hour: octet(2)?,
    })
}

/// Decodes a valid frame as the reply to `query` (spec §4.4): the header must be one
/// expected for the query (status: a configured layout's L; counters: any L ≥ 3;
/// fault record: L 0x11 or 0x06). Prefix and function echo are not checked (EKM-A8).
pub fn decode_reply(
    query: Query,
    frame: &Frame,
    config: &CodecConfig,
) -> Result<Reply, ReplyError> {
    let length = frame.length();
    let unexpected = ReplyError::UnexpectedLength { length, query };
    // The header first (spec §4.4), then the function echo: EKM-A8 leaves the echo
    // undocumented, so an octet that is no function code is ignored; one that is another
    // query's function code is that query's (late) reply.
    let (expected, length_fits) = match query {
        Query::Status => (
            FUNCTION_STATUS,
            config
                .status_layouts
                .iter()
                .any(|layout| layout.length == length),
        ),
        Query::Counters => (FUNCTION_COUNTERS, length >= 3),
        Query::FaultRecord(_) => (
            FUNCTION_FAULT,
            length == EMPTY_SLOT_LENGTH || length == FAULT_RECORD_LENGTH,
        ),
    };
    if !length_fits {
        return Err(unexpected);
    }
    if let Ok(function) = frame.octet(6) {
        if function != expected
            && [FUNCTION_STATUS, FUNCTION_COUNTERS, FUNCTION_FAULT].contains(&function)
        {
            return Err(ReplyError::OtherFunction { function, query });
        }
    }
    match query {
        Query::Status => {
            let layout = config
                .status_layouts
                .iter()
                .find(|layout| layout.length == length)
                .ok_or(unexpected)?;
            Ok(Reply::Status(Status {
                code: frame.octet(layout.status)?,
                position: frame.octet(layout.position)?,
                target: frame.octet(layout.target)?,
                direction: config.direction.decode(frame.octet(layout.direction)?),
                time: time_octets(frame, layout.time, config)?,
            }))
        }
        Query::Counters => {
            if length < 3 {
                return Err(unexpected);
            }
            let octets = frame.user_data().get(3..).unwrap_or_default();
            let width = config.counter_width.octets();
            if octets.len() % width != 0 {
                return Err(ReplyError::CounterLength {
                    octets: octets.len(),
                    width,
                });
            }
            Ok(Reply::Counters(
                octets
                    .chunks(width)
                    .map(|chunk| {
                        chunk
                            .iter()
                            .rev()
                            .fold(0u32, |value, octet| (value << 8) | u32::from(*octet))
                    })
                    .collect(),
            ))
        }
        Query::FaultRecord(_) if length == EMPTY_SLOT_LENGTH => Ok(Reply::EmptySlot {
            index: frame.octet(7)?,
        }),
        Query::FaultRecord(_) if length == FAULT_RECORD_LENGTH => {
            let layout = &config.fault_layout;
            let date = |offset: usize| config.time.decode(frame.octet(layout.time + offset)?);
            Ok(Reply::Fault(FaultRecord {
                index: frame.octet(layout.index)?,
                last_index: frame.octet(layout.last_index)?,
                time: FaultTime {
                    time: time_octets(frame, layout.time, config)?,
                    day: date(3)?,
                    month: date(4)?,
                    year: config.year_base.saturating_add(u16::from(date(5)?)),
                },
                code: frame.octet(layout.code)?,
                floor: frame.octet(layout.floor)?,
                target: frame.octet(layout.target)?,
            }))
        }
        Query::FaultRecord(_) => Err(unexpected),
    }
}

fn put(frame: &mut [u8], position: usize, value: u8) {
    if let Some(octet) = frame.get_mut(position) {
        *octet = value;
    }
}

/// Encodes a reply (the simulator's side; round trips in tests): undocumented octets
/// zero, the prefix `01 00` and the function code echoed. `query_index` is echoed at
/// position 7 of fault replies (EKM-A8). `layout` places the status fields.
pub fn encode_reply(
    reply: &Reply,
    layout: StatusLayout,
    config: &CodecConfig,
    query_index: u8,
) -> Vec<u8> {
    let time = |frame: &mut [u8], start: usize, t: TimeOfDay| {
        put(frame, start, config.time.encode(t.second));
        put(frame, start + 1, config.time.encode(t.minute));
        put(frame, start + 2, config.time.encode(t.hour));
    };
    let mut user = match reply {
        Reply::Status(status) => {
            let mut frame = vec![0u8; layout.frame_len()];
            put(&mut frame, layout.status, status.code);
            put(&mut frame, layout.position, status.position);
            put(&mut frame, layout.target, status.target);
            put(
                &mut frame,
                layout.direction,
                config.direction.encode(status.direction),
            );
            time(&mut frame, layout.time, status.time);
            put(&mut frame, 6, FUNCTION_STATUS);
            frame
        }
        Reply::Counters(counters) => {
            let width = config.counter_width.octets();
            let mut frame = vec![0u8; 7];
            put(&mut frame, 6, FUNCTION_COUNTERS);
            let room = 255usize.saturating_sub(3) / width;
            for counter in counters.iter().take(room) {
                let value = (*counter).min(config.counter_width.max());
                frame.extend_from_slice(value.to_le_bytes().get(..width).unwrap_or_default());
            }
            frame.extend_from_slice(&[0, 0]);
            frame
        }
        Reply::Fault(record) => {
            let fault = &config.fault_layout;
            let mut frame = vec![0u8; usize::from(FAULT_RECORD_LENGTH) + 6];
            put(&mut frame, 6, FUNCTION_FAULT);
            put(&mut frame, 7, query_index);
            put(&mut frame, fault.index, record.index);
            put(&mut frame, fault.last_index, record.last_index);
            time(&mut frame, fault.time, record.time.time);
            put(
                &mut frame,
                fault.time + 3,
                config.time.encode(record.time.day),
            );
            put(
                &mut frame,
                fault.time + 4,
                config.time.encode(record.time.month),
            );
            let year = record.time.year.saturating_sub(config.year_base);
            put(
                &mut frame,
                fault.time + 5,
                config.time.encode(u8::try_from(year).unwrap_or(u8::MAX)),
            );
            put(&mut frame, fault.code, record.code);
            put(&mut frame, fault.floor, record.floor);
            put(&mut frame, fault.target, record.target);
            frame
        }
        Reply::EmptySlot { index } => {
            let mut frame = vec![0u8; usize::from(EMPTY_SLOT_LENGTH) + 6];
            put(&mut frame, 6, FUNCTION_FAULT);
            put(&mut frame, 7, *index);
            frame
        }
    };
    // Header, prefix and trailer are written by encode_frame from the user octets.
    put(&mut user, 4, PREFIX[0]);
    put(&mut user, 5, PREFIX[1]);
    let end = user.len().saturating_sub(2);
    encode_frame(user.get(4..end).unwrap_or_default())
}
