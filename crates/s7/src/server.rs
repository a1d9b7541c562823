//! The server end of one connection, sans-IO: a simulated PLC's side of what an S7
//! client (a LOGO!, an HMI, this crate's client) asks.
//!
//! ```text
//! CR, any TSAPs      -> CC (TPDU size min(asked, 1024), TSAPs echoed); Connected
//! setup comm.        -> granted min(asked, max_pdu_size), min(asked, max_jobs); Negotiated
//! read var           -> one data item per item, from Memory; an item it cannot serve
//!                       answered by its return code (0x0A no such area or DB,
//!                       0x05 out of range, 0x06 type), the others served
//! write var          -> into Memory, a bit alone; a return code per item; Write event
//!                       per item written
//! other functions    -> ack_data with error 0x8104 (S7: function not supported by this PLC)
//! a job or answer larger than the PDU size -> ack_data with error 0x8500
//! an undecodable job -> ack with error 0x8404 while the reference can be read;
//!                       after MAX_BAD_PDUS of them, or any bad frame: Closed
//! ```
//!
//! The server accepts every connection type in the called TSAP (PG, OP, S7 basic,
//! others) and any rack and slot: a LOGO! sends its configured TSAPs (the
//! railway-station thesis, section 3.3), tools send 0x03xx, HMIs 0x02xx. Userdata PDUs
//! (SZL, clock, block functions) get no answer.
//!
//! Memory is passed into each call, so that several connections can share one image
//! under a lock held only while a call runs.

use std::collections::VecDeque;

use crate::address::Area;
use crate::cotp::{ConnectionParams, Tpdu, TpduSize};
use crate::link::{ConnectionError, Incoming, Link};
use crate::memory::Memory;
use crate::pdu::{
    rosctr, DataItem, ErrorCode, ItemSpec, Pdu, Request, Response, ReturnCode, SetupCommunication,
    PROTOCOL_ID,
};
use crate::tsap::Tsap;
use crate::wire::hex;

/// Undecodable or out-of-turn PDUs a server answers before it closes the connection.
pub const MAX_BAD_PDUS: u32 = 8;

/// What a server grants.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub struct ServerConfig {
    /// The largest PDU size granted: 240 as a LOGO! or S7-1200, 480 as an S7-300,
    /// 960 as an S7-1500.
    pub max_pdu_size: u16,
    /// The most jobs a client may have open at once.
    pub max_jobs: u16,
}

/// A PDU size of 240 and three jobs at once: an S7-1200 or LOGO! profile.
impl Default for ServerConfig {
    fn default() -> Self {
        ServerConfig {
            max_pdu_size: 240,
            max_jobs: 3,
        }
    }
}

/// A write by a client, after it went into memory.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct WriteEvent {
    /// The area written.
    pub area: Area,
    /// The first byte written.
    pub start: u32,
    /// For a bit write, the bit; only that bit changed.
    pub bit: Option<u8>,
    /// The bytes written; for a bit, one byte, 0 or 1.
    pub data: Vec<u8>,
}

impl WriteEvent {
    /// Bytes written (1 for a bit).
    pub fn size(&self) -> usize {
        self.data.len()
    }

    /// One line of JSON: `{"area": "DB", "db": 1, "start": 4, "size": 2, "data": "00ff"}`,
    /// with `"bit": 3` for a bit write and no `db` outside data blocks; data in hex.
    pub fn to_json(&self) -> String {
        let mut json = format!("{{\"area\": \"{}\"", self.area.name());
        if let Area::DataBlock(number) = self.area {
            json.push_str(&format!(", \"db\": {number}"));
        }
        json.push_str(&format!(", \"start\": {}", self.start));
        if let Some(bit) = self.bit {
            json.push_str(&format!(", \"bit\": {bit}"));
        }
        json.push_str(&format!(
            ", \"size\": {}, \"data\": \"{}\"}}",
            self.size(),
            hex(&self.data)
        ));
        json
    }
}

/// What the server tells its caller.
#[derive(Debug, Clone, PartialEq)]
pub enum ServerEvent {
    /// A client connected, with these TSAPs.
    Connected {
        /// The client's TSAP.
        calling_tsap: Option<Tsap>,
        /// The TSAP the client asked for (this server's).
        called_tsap: Option<Tsap>,
    },
    /// Setup communication granted.
    Negotiated {
        /// The PDU size granted.
        pdu_size: u16,
        /// Jobs open at once granted.
        max_jobs: u16,
    },
    /// A client wrote.
    Write(WriteEvent),
    /// The connection ended.
    Closed(ConnectionError),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    AwaitingRequest,
    AwaitingSetup,
    Ready { pdu_size: u16 },
    Closed,
}

impl State {
    fn name(self) -> &'static str {
        match self {
            State::AwaitingRequest => "awaiting the connection request",
            State::AwaitingSetup => "awaiting setup communication",
            State::Ready { .. } => "connected",
            State::Closed => "closed",
        }
    }
}

/// The server end of one connection.
#[derive(Debug)]
pub struct ServerConnection {
    config: ServerConfig,
    link: Link,
    state: State,
    events: VecDeque<ServerEvent>,
    bad_pdus: u32,
}

impl ServerConnection {
    /// A connection waiting for its connection request.
    pub fn new(config: ServerConfig) -> ServerConnection {
        ServerConnection {
            config,
            link: Link::new(),
            state: State::AwaitingRequest,
            events: VecDeque::new(),
            bad_pdus: 0,
        }
    }

    /// Whether the connection ended: the caller closes the socket.
    pub fn is_closed(&self) -> bool {
        self.state == State::Closed
    }

    /// The PDU size granted, once setup communication is done.
    pub fn pdu_size(&self) -> Option<u16> {
        match self.state {
            State::Ready { pdu_size } => Some(pdu_size),
            _ => None,
        }
    }

    /// Takes received bytes, serving jobs from and into `memory`. Poll transmits and
    /// events afterwards.
    pub fn handle_input(&mut self, bytes: &[u8], memory: &mut Memory) {
        if self.is_closed() {
            return;
        }
        self.link.push(bytes);
        while !self.is_closed() {
            let result = match self.link.next_incoming() {
                Ok(None) => return,
                Ok(Some(Incoming::Control(tpdu))) => self.handle_control(tpdu),
                Ok(Some(Incoming::Data(pdu))) => self.handle_data(&pdu, memory),
                Err(error) => Err(error),
            };
            if let Err(error) = result {
                self.close(error);
            }
        }
    }

    /// The TCP connection ended. Poll events afterwards.
    pub fn handle_eof(&mut self) {
        if !self.is_closed() {
            self.close(ConnectionError::PeerClosed);
        }
    }

    /// The next frame to send, into `out` (cleared first); `false` when there is none.
    pub fn poll_transmit(&mut self, out: &mut Vec<u8>) -> bool {
        out.clear();
        match self.link.poll_transmit() {
            Some(frame) => {
                out.extend_from_slice(&frame);
                true
            }
            None => false,
        }
    }

    /// The next event.
    pub fn poll_event(&mut self) -> Option<ServerEvent> {
        self.events.pop_front()
    }

    fn close(&mut self, error: ConnectionError) {
        tracing::debug!(target: "s7::cotp", %error, "connection closed");
        self.state = State::Closed;
        self.events.push_back(ServerEvent::Closed(error));
    }

    fn handle_control(&mut self, tpdu: Tpdu) -> Result<(), ConnectionError> {
        match (self.state, tpdu) {
            (State::AwaitingRequest, Tpdu::ConnectionRequest(request)) => {
                let tpdu_size = request
                    .tpdu_size
                    .unwrap_or(TpduSize::DEFAULT)
                    .min(TpduSize::S7);
                self.link
                    .send_control(&Tpdu::ConnectionConfirm(ConnectionParams {
                        dst_ref: request.src_ref,
                        // Any non-zero reference: the TCP connection tells connections apart.
                        src_ref: 1,
                        class: 0,
                        tpdu_size: Some(tpdu_size),
                        calling_tsap: request.calling_tsap.clone(),
                        called_tsap: request.called_tsap.clone(),
                    }))?;
                self.link.set_tpdu_size(tpdu_size);
                self.state = State::AwaitingSetup;
                self.events.push_back(ServerEvent::Connected {
                    calling_tsap: request.calling_tsap,
                    called_tsap: request.called_tsap,
                });
                Ok(())
            }
            (_, Tpdu::DisconnectRequest { reason, .. }) => {
                Err(ConnectionError::Disconnected { reason })
            }
            (_, Tpdu::DisconnectConfirm { .. }) => Err(ConnectionError::PeerClosed),
            (_, Tpdu::Error { cause, .. }) => Err(ConnectionError::Rejected { cause }),
            (state, other) => Err(ConnectionError::unexpected_tpdu(&other, state.name())),
        }
    }

    /// Counts a bad PDU; past the cap the connection closes.
    fn bad_pdu(&mut self, error: ConnectionError) -> Result<(), ConnectionError> {
        self.bad_pdus += 1;
        tracing::warn!(target: "s7::pdu", %error, count = self.bad_pdus, "bad PDU from the client");
        if self.bad_pdus > MAX_BAD_PDUS {
            Err(ConnectionError::TooManyBadPdus(self.bad_pdus))
        } else {
            Ok(())
        }
    }

    fn answer(&mut self, pdu: &Pdu) -> Result<(), ConnectionError> {
        tracing::trace!(target: "s7::pdu", ?pdu, "answering");
        self.link.send_pdu(pdu)
    }

    fn handle_data(&mut self, bytes: &[u8], memory: &mut Memory) -> Result<(), ConnectionError> {
        if self.state == State::AwaitingRequest {
            return Err(ConnectionError::UnexpectedTpdu {
                got: "data",
                state: self.state.name(),
            });
        }
        let pdu = match Pdu::decode(bytes) {
            Ok(pdu) => pdu,
            Err(error) => {
                // A job whose header can be read gets an error answer, so that the
                // client is not left waiting; anything else is only counted.
                if let [PROTOCOL_ID, rosctr::JOB, _, _, high, low, ..] = bytes {
                    self.answer(&Pdu::Ack {
                        pdu_ref: u16::from_be_bytes([*high, *low]),
                        error: ErrorCode::INVALID_REQUEST,
                    })?;
                }
                return self.bad_pdu(error.into());
            }
        };
        tracing::trace!(target: "s7::pdu", ?pdu, "received");
        let (pdu_ref, request) = match pdu {
            Pdu::Job { pdu_ref, request } => (pdu_ref, request),
            Pdu::UserData { pdu_ref, .. } => {
                tracing::debug!(target: "s7::pdu", pdu_ref, "userdata not served");
                return Ok(());
            }
            Pdu::Ack { .. } | Pdu::AckData { .. } => {
                return self.bad_pdu(ConnectionError::UnexpectedPdu {
                    got: "answer",
                    state: "serving",
                })
            }
        };
        if let Request::SetupCommunication(asked) = request {
            return self.setup(pdu_ref, asked);
        }
        let State::Ready { pdu_size } = self.state else {
            self.answer(&Pdu::Ack {
                pdu_ref,
                error: ErrorCode::INVALID_REQUEST,
            })?;
            return self.bad_pdu(ConnectionError::UnexpectedPdu {
                got: "job before setup communication",
                state: self.state.name(),
            });
        };
        if bytes.len() > usize::from(pdu_size) {
            return self.answer(&error_answer(pdu_ref, ErrorCode::PDU_SIZE));
        }
        let answer = match request {
            Request::ReadVar(items) => read_answer(pdu_ref, &items, memory),
            Request::WriteVar(items) => self.write_answer(pdu_ref, items, memory),
            Request::Other { function, .. } => {
                tracing::debug!(target: "s7::pdu", function, "a function this server does not offer: answered with error 0x8104");
                error_answer(pdu_ref, ErrorCode::FUNCTION_NOT_IMPLEMENTED)
            }
            Request::SetupCommunication(_) => return Ok(()),
        };
        let fits = answer
            .to_bytes()
            .map(|encoded| encoded.len() <= usize::from(pdu_size))
            .unwrap_or(false);
        if fits {
            self.answer(&answer)
        } else {
            self.answer(&error_answer(pdu_ref, ErrorCode::PDU_SIZE))
        }
    }

    fn setup(&mut self, pdu_ref: u16, asked: SetupCommunication) -> Result<(), ConnectionError> {
        let pdu_size = asked.pdu_size.min(self.config.max_pdu_size);
        let max_jobs = asked.max_amq_calling.min(self.config.max_jobs).max(1);
        let granted = SetupCommunication {
            max_amq_calling: max_jobs,
            max_amq_called: max_jobs,
            pdu_size,
        };
        self.answer(&Pdu::AckData {
            pdu_ref,
            error: ErrorCode::NONE,
            response: Response::SetupCommunication(granted),
        })?;
        self.state = State::Ready { pdu_size };
        self.events
            .push_back(ServerEvent::Negotiated { pdu_size, max_jobs });
        Ok(())
    }

    fn write_answer(
        &mut self,
        pdu_ref: u16,
        items: Vec<(ItemSpec, DataItem)>,
        memory: &mut Memory,
    ) -> Pdu {
        let codes = items
            .into_iter()
            .map(|(spec, item)| {
                let region = match spec.region() {
                    Ok(region) => region,
                    Err(code) => return code,
                };
                match memory.write(&region, &item.data) {
                    Ok(()) => {
                        let bit = match region {
                            crate::address::Region::Bit { bit, .. } => Some(bit),
                            crate::address::Region::Bytes { .. } => None,
                        };
                        let data = match bit {
                            Some(_) => vec![u8::from(item.data.first().is_some_and(|b| *b != 0))],
                            None => item.data,
                        };
                        self.events.push_back(ServerEvent::Write(WriteEvent {
                            area: region.area(),
                            start: region.start(),
                            bit,
                            data,
                        }));
                        ReturnCode::Success
                    }
                    Err(code) => code,
                }
            })
            .collect();
        Pdu::AckData {
            pdu_ref,
            error: ErrorCode::NONE,
            response: Response::WriteVar(codes),
        }
    }
}

fn read_answer(pdu_ref: u16, items: &[ItemSpec], memory: &Memory) -> Pdu {
    let data = items
        .iter()
        .map(
            |spec| match spec.region().and_then(|region| memory.read(&region)) {
                Ok(data) => DataItem {
                    return_code: ReturnCode::Success,
                    transport: spec.transport_size.data_transport(),
                    data,
                },
                Err(code) => DataItem::error(code),
            },
        )
        .collect();
    Pdu::AckData {
        pdu_ref,
        error: ErrorCode::NONE,
        response: Response::ReadVar(data),
    }
}

fn error_answer(pdu_ref: u16, error: ErrorCode) -> Pdu {
    Pdu::AckData {
        pdu_ref,
        error,
        response: Response::None,
    }
}
