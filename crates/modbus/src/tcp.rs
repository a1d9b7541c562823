//! Modbus TCP: the MBAP header (Modbus Messaging on TCP/IP Implementation Guide v1.0b,
//! section 3.1.3), a deframer over the byte stream, and a server's connection, sans-IO.
//!
//! ```text
//! transaction id (2) | protocol id (2, 0 = Modbus) | length (2, unit id + PDU) | unit id (1) | PDU
//! ```

use thiserror::Error;

use crate::model::DataModel;
use crate::pdu::MAX_PDU;
use crate::server::{answer, Framing, Outcome};

/// Octets of the MBAP header, the unit id included.
pub const MBAP_LEN: usize = 7;

/// The largest length field: the unit id and the largest PDU.
const MAX_LENGTH: u16 = MAX_PDU as u16 + 1;

/// The header of a Modbus TCP ADU.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MbapHeader {
    /// Pairs a response with its request.
    pub transaction: u16,
    /// 0 for Modbus.
    pub protocol: u16,
    /// Octets that follow: the unit id and the PDU.
    pub length: u16,
    /// The unit the ADU is for (a gateway's serial slave, or 0xFF for the TCP device).
    pub unit: u8,
}

impl MbapHeader {
    /// The header of the first [`MBAP_LEN`] octets, `None` when there are fewer.
    pub fn decode(octets: &[u8]) -> Option<MbapHeader> {
        let field = |at: usize| -> Option<u16> {
            Some(u16::from_be_bytes([*octets.get(at)?, *octets.get(at + 1)?]))
        };
        Some(MbapHeader {
            transaction: field(0)?,
            protocol: field(2)?,
            length: field(4)?,
            unit: *octets.get(6)?,
        })
    }

    /// Appends the header's seven octets.
    pub fn encode(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.transaction.to_be_bytes());
        out.extend_from_slice(&self.protocol.to_be_bytes());
        out.extend_from_slice(&self.length.to_be_bytes());
        out.push(self.unit);
    }
}

/// One Modbus TCP ADU.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Adu {
    /// The transaction id.
    pub transaction: u16,
    /// The protocol id (0 for Modbus).
    pub protocol: u16,
    /// The unit id.
    pub unit: u8,
    /// The PDU.
    pub pdu: Vec<u8>,
}

impl Adu {
    /// Appends the ADU: header (its length from the PDU's) and PDU.
    pub fn encode(&self, out: &mut Vec<u8>) {
        MbapHeader {
            transaction: self.transaction,
            protocol: self.protocol,
            length: u16::try_from(self.pdu.len() + 1).unwrap_or(u16::MAX),
            unit: self.unit,
        }
        .encode(out);
        out.extend_from_slice(&self.pdu);
    }

    /// The ADU's octets.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(MBAP_LEN + self.pdu.len());
        self.encode(&mut out);
        out
    }
}

/// A stream whose framing is lost: TCP has no resynchronisation, the connection must end.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum MbapError {
    /// A length field that no ADU has: less than a unit id and a function code, or more
    /// than a unit id and the largest PDU.
    #[error("MBAP length {0} outside 2..=254")]
    Length(u16),
}

/// Cuts ADUs out of a TCP byte stream by the MBAP length field.
#[derive(Debug, Default, Clone)]
pub struct MbapDeframer {
    buffer: Vec<u8>,
}

impl MbapDeframer {
    /// An empty deframer.
    pub fn new() -> MbapDeframer {
        MbapDeframer::default()
    }

    /// Octets received.
    pub fn push(&mut self, octets: &[u8]) {
        self.buffer.extend_from_slice(octets);
    }

    /// Octets held that are not a whole ADU yet.
    pub fn buffered(&self) -> usize {
        self.buffer.len()
    }

    /// The next whole ADU; `Ok(None)` until one is there. After an error the stream
    /// cannot be read on (the deframer keeps returning it).
    pub fn next_frame(&mut self) -> Result<Option<Adu>, MbapError> {
        let Some(header) = MbapHeader::decode(&self.buffer) else {
            return Ok(None);
        };
        if !(2..=MAX_LENGTH).contains(&header.length) {
            return Err(MbapError::Length(header.length));
        }
        let total = MBAP_LEN - 1 + usize::from(header.length);
        if self.buffer.len() < total {
            return Ok(None);
        }
        let pdu = self
            .buffer
            .get(MBAP_LEN..total)
            .unwrap_or_default()
            .to_vec();
        self.buffer.drain(..total.min(self.buffer.len()));
        Ok(Some(Adu {
            transaction: header.transaction,
            protocol: header.protocol,
            unit: header.unit,
            pdu,
        }))
    }
}

/// Counts of a server connection.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TcpServerStats {
    /// ADUs received.
    pub requests: u64,
    /// Answers sent (responses and exceptions).
    pub answers: u64,
    /// ADUs of another protocol id, dropped.
    pub foreign: u64,
}

/// A Modbus TCP server's end of one connection, sans-IO: octets in, answer octets out.
///
/// After [`TcpServerConnection::handle_input`] the caller writes what
/// [`TcpServerConnection::poll_transmit`] gives, and closes the connection once
/// [`TcpServerConnection::error`] is set.
#[derive(Debug)]
pub struct TcpServerConnection {
    model: DataModel,
    deframer: MbapDeframer,
    transmit: Vec<u8>,
    error: Option<MbapError>,
    stats: TcpServerStats,
}

impl TcpServerConnection {
    /// A connection serving `model`.
    pub fn new(model: DataModel) -> TcpServerConnection {
        TcpServerConnection {
            model,
            deframer: MbapDeframer::new(),
            transmit: Vec::new(),
            error: None,
            stats: TcpServerStats::default(),
        }
    }

    /// Octets from the client: every whole request in them is answered. Poll
    /// [`TcpServerConnection::poll_transmit`] afterwards.
    pub fn handle_input(&mut self, octets: &[u8]) {
        if self.error.is_some() {
            return;
        }
        self.deframer.push(octets);
        loop {
            match self.deframer.next_frame() {
                Ok(Some(adu)) => self.handle_adu(adu),
                Ok(None) => break,
                Err(error) => {
                    tracing::debug!(%error, "closing the connection");
                    self.error = Some(error);
                    break;
                }
            }
        }
    }

    fn handle_adu(&mut self, adu: Adu) {
        self.stats.requests += 1;
        if adu.protocol != 0 {
            self.stats.foreign += 1;
            tracing::debug!(protocol = adu.protocol, "ADU of another protocol dropped");
            return;
        }
        tracing::trace!(unit = adu.unit, pdu = ?adu.pdu, "request");
        if let Outcome::Answer(pdu) = answer(&self.model, Framing::Tcp, adu.unit, &adu.pdu) {
            self.stats.answers += 1;
            Adu {
                transaction: adu.transaction,
                protocol: 0,
                unit: adu.unit,
                pdu,
            }
            .encode(&mut self.transmit);
        }
    }

    /// The octets to send now, if any.
    pub fn poll_transmit(&mut self) -> Option<Vec<u8>> {
        if self.transmit.is_empty() {
            None
        } else {
            Some(std::mem::take(&mut self.transmit))
        }
    }

    /// Why the connection must close, once it must.
    pub fn error(&self) -> Option<&MbapError> {
        self.error.as_ref()
    }

    /// The counts so far.
    pub fn stats(&self) -> TcpServerStats {
        self.stats
    }
}
