//! Modbus RTU (Modbus over Serial Line Specification and Implementation Guide v1.02,
//! section 2.5): the frame (address, PDU, CRC-16 low octet first), its times, a request
//! deframer for a slave, and the slave itself as a [`LineEndpoint`], sans-IO.
//!
//! A slave sees every frame on its line: requests for other slaves and their responses,
//! and noise. Requests are cut by the length their function code implies as soon as
//! their CRC holds (so an answer does not wait for the line to fall silent); anything else
//! is judged at the next line pause, when the silence the guide requires between frames
//! (3.5 characters; the drive loop's pause is longer, see `serial_line::io::drive`) says
//! the frame has ended: the octets since the last frame are one frame if their CRC holds,
//! or a request at their end is, or they are discarded.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use serial_line::{LineEndpoint, LineSettings, Parity};

use crate::model::DataModel;
use crate::server::{answer, Framing, Outcome};

/// The largest RTU frame: address, 253 octets of PDU, CRC.
pub const MAX_ADU: usize = 256;

/// The smallest: address, function code, CRC.
pub const MIN_ADU: usize = 4;

/// The CRC-16 of the serial line guide (polynomial 0xA001 reflected, initial 0xFFFF),
/// sent low octet first.
pub fn crc16(octets: &[u8]) -> u16 {
    let mut crc: u16 = 0xFFFF;
    for octet in octets {
        crc ^= u16::from(*octet);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xA001
            } else {
                crc >> 1
            };
        }
    }
    crc
}

/// Appends the frame of `pdu` for `unit`: address, PDU, CRC low then high.
pub fn encode_frame(unit: u8, pdu: &[u8], out: &mut Vec<u8>) {
    let start = out.len();
    out.push(unit);
    out.extend_from_slice(pdu);
    let crc = crc16(out.get(start..).unwrap_or_default());
    out.extend_from_slice(&crc.to_le_bytes());
}

/// The frame of `pdu` for `unit`.
pub fn frame(unit: u8, pdu: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(pdu.len() + 3);
    encode_frame(unit, pdu, &mut out);
    out
}

/// The unit and PDU of a whole frame whose CRC holds; `None` otherwise.
pub fn decode_frame(adu: &[u8]) -> Option<(u8, &[u8])> {
    if !(MIN_ADU..=MAX_ADU).contains(&adu.len()) {
        return None;
    }
    let (body, crc) = adu.split_at(adu.len() - 2);
    let received = u16::from_le_bytes([*crc.first()?, *crc.get(1)?]);
    if crc16(body) != received {
        return None;
    }
    let (&unit, pdu) = body.split_first()?;
    Some((unit, pdu))
}

/// A frame's unit and PDU.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RtuFrame {
    /// The slave address (0: broadcast).
    pub unit: u8,
    /// The PDU.
    pub pdu: Vec<u8>,
}

impl RtuFrame {
    /// The frame's octets with its CRC.
    pub fn to_bytes(&self) -> Vec<u8> {
        frame(self.unit, &self.pdu)
    }
}

/// The silence between two frames: 3.5 characters, 1.75 ms above 19200 Bd (guide
/// section 2.5.1.1).
pub fn frame_gap(line: &LineSettings) -> Duration {
    if line.baud > 19_200 {
        Duration::from_micros(1750)
    } else {
        line.bit_times(u64::from(line.bits_per_character()) * 7) / 2
    }
}

/// The longest pause inside a frame: 1.5 characters, 0.75 ms above 19200 Bd.
pub fn char_gap(line: &LineSettings) -> Duration {
    if line.baud > 19_200 {
        Duration::from_micros(750)
    } else {
        line.bit_times(u64::from(line.bits_per_character()) * 3) / 2
    }
}

/// The Modbus standard's line: 19200 Bd, 8 data bits, even parity, 1 stop bit.
pub const DEFAULT_LINE: LineSettings = LineSettings {
    baud: 19_200,
    parity: Parity::Even,
    stop_bits: 1,
};

/// How long a request frame is by its first octets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Length {
    /// The whole frame's length.
    Known(usize),
    /// More octets are needed to tell.
    NeedMore,
    /// A function code whose request length is not known here: judged at the pause.
    Unknown,
}

/// The length of the request frame starting `adu`, by its function code (application
/// protocol section 6; the serial-line-only functions too, to answer them exception 1
/// at once).
fn request_length(adu: &[u8]) -> Length {
    let Some(&function) = adu.get(1) else {
        return Length::NeedMore;
    };
    let counted = |at: usize, fixed: usize| match adu.get(at) {
        Some(count) => Length::Known(fixed + usize::from(*count)),
        None => Length::NeedMore,
    };
    match function {
        1..=6 | 8 => Length::Known(8),
        7 | 11 | 12 | 17 => Length::Known(4),
        15 | 16 => counted(6, 9),
        20 | 21 => counted(2, 5),
        22 => Length::Known(10),
        23 => counted(10, 13),
        24 => Length::Known(6),
        43 => match adu.get(2) {
            Some(14) => Length::Known(7),
            Some(_) => Length::Unknown,
            None => Length::NeedMore,
        },
        _ => Length::Unknown,
    }
}

/// Counts of a deframer and a slave.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RtuStats {
    /// Frames with a good CRC.
    pub frames: u64,
    /// Octets runs discarded at a pause (a bad CRC, noise, a frame too long).
    pub discarded: u64,
    /// Answers sent.
    pub answered: u64,
    /// Broadcasts carried out.
    pub broadcasts: u64,
    /// Frames for other units (and other slaves' responses), not answered.
    pub other_units: u64,
    /// Frames that were our own last answer read back (an RS-485 adapter's echo).
    pub echoes: u64,
}

/// Cuts request frames out of a serial line's octets: by length and CRC as they come,
/// and at each line pause by CRC (see the module's doc).
#[derive(Debug, Default, Clone)]
pub struct RtuDeframer {
    buffer: Vec<u8>,
    /// The octets since the last frame are no request by length (another slave's
    /// response, noise): they wait for the pause.
    wait_for_pause: bool,
    stats: RtuStats,
}

impl RtuDeframer {
    /// An empty deframer.
    pub fn new() -> RtuDeframer {
        RtuDeframer::default()
    }

    /// Octets received. Of a run longer than a frame only the last frame's worth is
    /// kept, where a request may still end at the pause.
    pub fn push(&mut self, octets: &[u8]) {
        self.buffer.extend_from_slice(octets);
        if self.buffer.len() > 2 * MAX_ADU {
            let excess = self.buffer.len() - MAX_ADU;
            self.buffer.drain(..excess);
            self.wait_for_pause = true;
        }
    }

    /// The next request frame cut by its length, if a whole one with a good CRC is at
    /// the start of the octets held.
    pub fn next_frame(&mut self) -> Option<RtuFrame> {
        if self.wait_for_pause {
            return None;
        }
        match request_length(&self.buffer) {
            Length::Known(length) if self.buffer.len() >= length => {
                let candidate = self.buffer.get(..length)?;
                match decode_frame(candidate) {
                    Some((unit, pdu)) => {
                        let frame = RtuFrame {
                            unit,
                            pdu: pdu.to_vec(),
                        };
                        self.buffer.drain(..length);
                        self.stats.frames += 1;
                        return Some(frame);
                    }
                    None => self.wait_for_pause = true,
                }
            }
            _ if self.buffer.len() > MAX_ADU => self.wait_for_pause = true,
            _ => {}
        }
        None
    }

    /// The line fell silent: the octets held end here. Returns them as a frame if their
    /// CRC holds, or the request at their end if one does; they are dropped either way.
    pub fn handle_pause(&mut self) -> Option<RtuFrame> {
        let octets = std::mem::take(&mut self.buffer);
        self.wait_for_pause = false;
        if octets.is_empty() {
            return None;
        }
        let found = decode_frame(&octets).or_else(|| {
            // A request right after another frame without its silence (another slave's
            // response in the same run of octets).
            (1..octets.len()).find_map(|start| {
                let tail = octets.get(start..)?;
                match request_length(tail) {
                    Length::Known(length) if length == tail.len() => decode_frame(tail),
                    _ => None,
                }
            })
        });
        match found {
            Some((unit, pdu)) => {
                self.stats.frames += 1;
                Some(RtuFrame {
                    unit,
                    pdu: pdu.to_vec(),
                })
            }
            None => {
                self.stats.discarded += 1;
                None
            }
        }
    }

    /// Octets held.
    pub fn buffered(&self) -> usize {
        self.buffer.len()
    }

    /// The counts so far.
    pub fn stats(&self) -> RtuStats {
        self.stats
    }
}

/// How many answers may wait for their turn: a master that sends faster than it reads
/// the answers loses the rest.
const MAX_QUEUED: usize = 4;

/// A Modbus RTU slave on a serial line, sans-IO: serves `model` for the unit ids it
/// serves, answers each request one frame gap after it ended.
///
/// A [`LineEndpoint`]: `serial_line::io::drive` runs it on a serial port, a
/// pseudo-terminal or TCP (RTU over TCP, a terminal server's port); a test runs it on a
/// virtual clock.
#[derive(Debug)]
pub struct RtuSlave {
    model: DataModel,
    line: LineSettings,
    deframer: RtuDeframer,
    /// Answers and when they may be sent.
    queue: VecDeque<(Instant, Vec<u8>)>,
    /// The last answer sent, to recognise its echo.
    last_sent: Option<Vec<u8>>,
    stats: RtuStats,
}

impl RtuSlave {
    /// A slave serving `model` on a line of `line`'s settings.
    pub fn new(model: DataModel, line: LineSettings) -> RtuSlave {
        RtuSlave {
            model,
            line,
            deframer: RtuDeframer::new(),
            queue: VecDeque::new(),
            last_sent: None,
            stats: RtuStats::default(),
        }
    }

    /// The model served.
    pub fn model(&self) -> &DataModel {
        &self.model
    }

    /// The counts so far.
    pub fn stats(&self) -> RtuStats {
        let deframer = self.deframer.stats();
        RtuStats {
            frames: deframer.frames,
            discarded: deframer.discarded,
            ..self.stats
        }
    }

    fn handle_frame(&mut self, now: Instant, frame: RtuFrame) {
        if let Some(sent) = self.last_sent.take() {
            if decode_frame(&sent).is_some_and(|(unit, pdu)| unit == frame.unit && pdu == frame.pdu)
            {
                self.stats.echoes += 1;
                return;
            }
        }
        tracing::trace!(unit = frame.unit, pdu = ?frame.pdu, "request");
        match answer(&self.model, Framing::Rtu, frame.unit, &frame.pdu) {
            Outcome::Answer(pdu) => {
                if self.queue.len() < MAX_QUEUED {
                    self.queue
                        .push_back((now + frame_gap(&self.line), self::frame(frame.unit, &pdu)));
                }
            }
            Outcome::Broadcast => self.stats.broadcasts += 1,
            Outcome::NotOurs | Outcome::Ignored => self.stats.other_units += 1,
        }
    }
}

impl LineEndpoint for RtuSlave {
    fn handle_bytes(&mut self, now: Instant, bytes: &[u8]) {
        self.deframer.push(bytes);
        while let Some(frame) = self.deframer.next_frame() {
            self.handle_frame(now, frame);
        }
    }

    fn handle_line_pause(&mut self, now: Instant) {
        if let Some(frame) = self.deframer.handle_pause() {
            self.handle_frame(now, frame);
        }
    }

    fn handle_timeout(&mut self, _now: Instant) {}

    fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>> {
        let (due, _) = self.queue.front()?;
        if *due > now {
            return None;
        }
        let (_, octets) = self.queue.pop_front()?;
        self.stats.answered += 1;
        self.last_sent = Some(octets.clone());
        Some(octets)
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.queue.front().map(|(due, _)| *due)
    }

    fn line(&self) -> LineSettings {
        self.line
    }
}
