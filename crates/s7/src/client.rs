//! The client end of one connection, sans-IO: bytes in, bytes and events out.
//!
//! ```text
//! new(config)          -> CR (TSAPs, TPDU size 1024)
//! CC                   -> setup communication job (PDU size asked, parallel jobs asked)
//! setup ack_data       -> Connected { pdu_size: min(asked, granted), max_jobs }
//! read(regions)        -> OperationId; split into jobs by the PDU size (crate::split)
//! write(items)         -> OperationId; likewise
//!   jobs go out while fewer than max_jobs are open; each ack_data is matched by its PDU
//!   reference, its items put back in the caller's order
//! all jobs answered    -> ReadDone / WriteDone { id, one result per item }
//! DR, ER, bad frames   -> Closed(error); nothing more is sent
//! ```
//!
//! Reads and writes may be asked before the connection is up; they go out once setup
//! communication is done. The client reads no clock: a caller that wants a timeout keeps
//! it itself (the tokio adapter does).

use std::collections::{BTreeMap, VecDeque};
use std::fmt;

use thiserror::Error;

use crate::address::Region;
use crate::cotp::{ConnectionParams, Tpdu, TpduSize};
use crate::link::{ConnectionError, Incoming, Link};
use crate::pdu::{function, ErrorCode, Pdu, Request, Response, ReturnCode, SetupCommunication};
use crate::split::{self, Batch, RequestError, WriteItem, MIN_PDU_SIZE};
use crate::tsap::Tsaps;

/// Answers to no open job tolerated before the client gives up on the connection.
const MAX_STRAY_ANSWERS: u32 = 3;

/// How a client connects.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub struct ClientConfig {
    /// The TSAP pair.
    pub tsaps: Tsaps,
    /// The PDU size asked in setup communication; the PLC grants this or less (a LOGO!
    /// or S7-1200 240, an S7-1500 960).
    pub pdu_size: u16,
    /// Jobs asked to be open at once; the PLC may grant fewer.
    pub max_jobs: u16,
}

impl ClientConfig {
    /// The defaults with these TSAPs.
    pub fn new(tsaps: Tsaps) -> ClientConfig {
        ClientConfig {
            tsaps,
            ..ClientConfig::default()
        }
    }
}

/// Rack 0, slot 1; a PDU size of 480; three jobs at once.
impl Default for ClientConfig {
    fn default() -> Self {
        ClientConfig {
            tsaps: Tsaps::default(),
            pdu_size: 480,
            max_jobs: 3,
        }
    }
}

/// Names one read or write until its results come.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct OperationId(u64);

impl fmt::Display for OperationId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "#{}", self.0)
    }
}

/// Why one item of a read or write failed; the other items of the same call stand.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum ItemError {
    /// The PLC answered the item with this return code.
    #[error("the PLC answered {0}")]
    Refused(ReturnCode),
    /// The PLC refused the whole job the item travelled in.
    #[error("the PLC refused the job: error {0}")]
    JobRefused(ErrorCode),
    /// The PLC answered with another amount of data than asked.
    #[error("the PLC answered {got} bytes where {expected} were asked")]
    Length {
        /// Bytes asked.
        expected: usize,
        /// Bytes answered.
        got: usize,
    },
}

/// What a read gives per item: the bytes (one byte, 0 or 1, for a bit).
pub type ReadResult = Result<Vec<u8>, ItemError>;
/// What a write gives per item.
pub type WriteResult = Result<(), ItemError>;

/// What the client tells its caller.
#[derive(Debug, Clone, PartialEq)]
pub enum ClientEvent {
    /// Setup communication is done: reads and writes go out.
    Connected {
        /// The PDU size in force.
        pdu_size: u16,
        /// Jobs open at once.
        max_jobs: u16,
    },
    /// A read finished: one result per region, in the order asked.
    ReadDone {
        /// The read.
        id: OperationId,
        /// The results.
        results: Vec<ReadResult>,
    },
    /// A write finished: one result per item, in the order asked.
    WriteDone {
        /// The write.
        id: OperationId,
        /// The results.
        results: Vec<WriteResult>,
    },
    /// The connection ended; open reads and writes end with it, unanswered.
    Closed(ConnectionError),
}

#[derive(Debug)]
enum State {
    AwaitingConfirm,
    AwaitingSetup { pdu_ref: u16 },
    Ready { pdu_size: u16, max_jobs: u16 },
    Closed,
}

impl State {
    fn name(&self) -> &'static str {
        match self {
            State::AwaitingConfirm => "awaiting the connection confirm",
            State::AwaitingSetup { .. } => "awaiting setup communication",
            State::Ready { .. } => "connected",
            State::Closed => "closed",
        }
    }
}

#[derive(Debug)]
enum Asked {
    Read(Vec<Region>),
    Write(Vec<WriteItem>),
}

#[derive(Debug)]
enum Operation {
    Read {
        results: Vec<ReadResult>,
        open_jobs: usize,
    },
    Write {
        results: Vec<WriteResult>,
        open_jobs: usize,
    },
}

#[derive(Debug)]
struct Job {
    operation: OperationId,
    batch: Batch,
    request: Request,
}

#[derive(Debug)]
struct OpenJob {
    operation: OperationId,
    batch: Batch,
    function: u8,
}

/// The client end of one connection.
#[derive(Debug)]
pub struct ClientConnection {
    config: ClientConfig,
    link: Link,
    state: State,
    next_pdu_ref: u16,
    next_operation: u64,
    /// Asked before the connection was up.
    waiting: VecDeque<(OperationId, Asked)>,
    operations: BTreeMap<OperationId, Operation>,
    jobs: VecDeque<Job>,
    open_jobs: BTreeMap<u16, OpenJob>,
    events: VecDeque<ClientEvent>,
    stray_answers: u32,
}

impl ClientConnection {
    /// A connection that starts with its connection request: poll
    /// [`ClientConnection::poll_transmit`] and send it.
    pub fn new(config: ClientConfig) -> ClientConnection {
        let mut client = ClientConnection {
            link: Link::new(),
            state: State::AwaitingConfirm,
            next_pdu_ref: 1,
            next_operation: 1,
            waiting: VecDeque::new(),
            operations: BTreeMap::new(),
            jobs: VecDeque::new(),
            open_jobs: BTreeMap::new(),
            events: VecDeque::new(),
            stray_answers: 0,
            config,
        };
        let request = Tpdu::ConnectionRequest(ConnectionParams {
            dst_ref: 0,
            // Any non-zero reference: one connection per client.
            src_ref: 1,
            class: 0,
            tpdu_size: Some(TpduSize::S7),
            calling_tsap: Some(client.config.tsaps.local.clone()),
            called_tsap: Some(client.config.tsaps.remote.clone()),
        });
        if let Err(error) = client.link.send_control(&request) {
            client.close(error);
        }
        client
    }

    /// The PDU size in force once connected.
    pub fn pdu_size(&self) -> Option<u16> {
        match self.state {
            State::Ready { pdu_size, .. } => Some(pdu_size),
            _ => None,
        }
    }

    /// Whether setup communication is done and the connection not closed.
    pub fn is_connected(&self) -> bool {
        matches!(self.state, State::Ready { .. })
    }

    /// Whether the connection ended.
    pub fn is_closed(&self) -> bool {
        matches!(self.state, State::Closed)
    }

    /// Asks to read `regions`. Poll transmits and events afterwards.
    pub fn read(&mut self, regions: Vec<Region>) -> Result<OperationId, RequestError> {
        split::validate_reads(&regions)?;
        self.submit(Asked::Read(regions))
    }

    /// Asks to write `items`; a bit is written alone, its byte's other bits untouched.
    /// Poll transmits and events afterwards.
    pub fn write(&mut self, items: Vec<WriteItem>) -> Result<OperationId, RequestError> {
        split::validate_writes(&items)?;
        self.submit(Asked::Write(items))
    }

    fn submit(&mut self, asked: Asked) -> Result<OperationId, RequestError> {
        if self.is_closed() {
            return Err(RequestError::Closed);
        }
        let id = OperationId(self.next_operation);
        self.next_operation += 1;
        match self.state {
            State::Ready { pdu_size, .. } => {
                self.plan(id, asked, pdu_size);
                self.send_jobs();
            }
            _ => self.waiting.push_back((id, asked)),
        }
        Ok(id)
    }

    /// Splits an operation into jobs and queues them.
    fn plan(&mut self, id: OperationId, asked: Asked, pdu_size: u16) {
        let (batches, operation) = match &asked {
            Asked::Read(regions) => (
                split::split_reads(regions, pdu_size),
                Operation::Read {
                    results: regions
                        .iter()
                        .map(|region| Ok(vec![0; region.data_len() as usize]))
                        .collect(),
                    open_jobs: 0,
                },
            ),
            Asked::Write(items) => (
                split::split_writes(items, pdu_size),
                Operation::Write {
                    results: vec![Ok(()); items.len()],
                    open_jobs: 0,
                },
            ),
        };
        // The items were checked when asked and the PDU size at setup, so splitting
        // cannot fail; were it to, the connection is in no state to go on.
        let batches = match batches {
            Ok(batches) => batches,
            Err(_) => return self.close(ConnectionError::PduSizeTooSmall(pdu_size)),
        };
        let mut operation = operation;
        match &mut operation {
            Operation::Read { open_jobs, .. } | Operation::Write { open_jobs, .. } => {
                *open_jobs = batches.len();
            }
        }
        for batch in batches {
            let request = match &asked {
                Asked::Read(_) => split::read_request(&batch),
                Asked::Write(items) => split::write_request(&batch, items),
            };
            self.jobs.push_back(Job {
                operation: id,
                batch,
                request,
            });
        }
        self.operations.insert(id, operation);
        // Nothing to ask (an empty list): done at once.
        self.finish_if_done(id);
    }

    /// Sends queued jobs while fewer than the granted number are open.
    fn send_jobs(&mut self) {
        let State::Ready { max_jobs, .. } = self.state else {
            return;
        };
        while self.open_jobs.len() < usize::from(max_jobs) {
            let Some(job) = self.jobs.pop_front() else {
                return;
            };
            let pdu_ref = self.take_pdu_ref();
            let function = match job.request {
                Request::WriteVar(_) => function::WRITE_VAR,
                _ => function::READ_VAR,
            };
            let pdu = Pdu::Job {
                pdu_ref,
                request: job.request,
            };
            if let Err(error) = self.link.send_pdu(&pdu) {
                return self.close(error);
            }
            self.open_jobs.insert(
                pdu_ref,
                OpenJob {
                    operation: job.operation,
                    batch: job.batch,
                    function,
                },
            );
        }
    }

    /// A reference no open job has (there are only ever a few open).
    fn take_pdu_ref(&mut self) -> u16 {
        loop {
            let pdu_ref = self.next_pdu_ref;
            self.next_pdu_ref = self.next_pdu_ref.wrapping_add(1);
            if !self.open_jobs.contains_key(&pdu_ref) {
                return pdu_ref;
            }
        }
    }

    /// Takes received bytes. Poll transmits and events afterwards.
    pub fn handle_input(&mut self, bytes: &[u8]) {
        if self.is_closed() {
            return;
        }
        self.link.push(bytes);
        while !self.is_closed() {
            let result = match self.link.next_incoming() {
                Ok(None) => return,
                Ok(Some(incoming)) => self.handle_incoming(incoming),
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
    pub fn poll_event(&mut self) -> Option<ClientEvent> {
        self.events.pop_front()
    }

    fn handle_incoming(&mut self, incoming: Incoming) -> Result<(), ConnectionError> {
        match incoming {
            Incoming::Control(tpdu) => self.handle_control(tpdu),
            Incoming::Data(bytes) => {
                if matches!(self.state, State::AwaitingConfirm) {
                    return Err(ConnectionError::UnexpectedTpdu {
                        got: "data",
                        state: self.state.name(),
                    });
                }
                let pdu = Pdu::decode(&bytes)?;
                tracing::trace!(target: "s7::pdu", ?pdu, "received");
                self.handle_pdu(pdu)
            }
        }
    }

    fn handle_control(&mut self, tpdu: Tpdu) -> Result<(), ConnectionError> {
        match (&self.state, tpdu) {
            (State::AwaitingConfirm, Tpdu::ConnectionConfirm(params)) => {
                self.link.set_tpdu_size(
                    params
                        .tpdu_size
                        .unwrap_or(TpduSize::DEFAULT)
                        .min(TpduSize::S7),
                );
                let pdu_ref = self.take_pdu_ref();
                let setup = Pdu::Job {
                    pdu_ref,
                    request: Request::SetupCommunication(SetupCommunication {
                        max_amq_calling: self.config.max_jobs.max(1),
                        max_amq_called: self.config.max_jobs.max(1),
                        pdu_size: self.config.pdu_size,
                    }),
                };
                self.link.send_pdu(&setup)?;
                self.state = State::AwaitingSetup { pdu_ref };
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

    fn handle_pdu(&mut self, pdu: Pdu) -> Result<(), ConnectionError> {
        match (&self.state, pdu) {
            (
                State::AwaitingSetup { pdu_ref },
                Pdu::AckData {
                    pdu_ref: answered,
                    error,
                    response,
                },
            ) if *pdu_ref == answered => {
                if error.is_error() {
                    return Err(ConnectionError::SetupRefused(error));
                }
                let Response::SetupCommunication(granted) = response else {
                    return Err(ConnectionError::MismatchedAnswer { pdu_ref: answered });
                };
                self.connected(granted)
            }
            (
                State::AwaitingSetup { pdu_ref },
                Pdu::Ack {
                    pdu_ref: answered,
                    error,
                },
            ) if *pdu_ref == answered => Err(ConnectionError::SetupRefused(error)),
            (
                State::Ready { .. },
                Pdu::AckData {
                    pdu_ref,
                    error,
                    response,
                },
            ) => self.handle_answer(pdu_ref, error, Some(response)),
            (State::Ready { .. }, Pdu::Ack { pdu_ref, error }) => {
                self.handle_answer(pdu_ref, error, None)
            }
            (state, Pdu::Job { .. }) => Err(ConnectionError::UnexpectedPdu {
                got: "job",
                state: state.name(),
            }),
            (state, Pdu::UserData { .. }) => Err(ConnectionError::UnexpectedPdu {
                got: "userdata",
                state: state.name(),
            }),
            (state, _) => Err(ConnectionError::UnexpectedPdu {
                got: "answer to no job",
                state: state.name(),
            }),
        }
    }

    fn connected(&mut self, granted: SetupCommunication) -> Result<(), ConnectionError> {
        // A PLC granting more than asked is taken at the smaller size: this end's
        // buffers were sized for what it asked.
        let pdu_size = granted.pdu_size.min(self.config.pdu_size);
        if pdu_size < MIN_PDU_SIZE {
            return Err(ConnectionError::PduSizeTooSmall(pdu_size));
        }
        let max_jobs = granted.max_amq_calling.min(self.config.max_jobs).max(1);
        tracing::debug!(target: "s7::pdu", pdu_size, max_jobs, "setup communication done");
        self.state = State::Ready { pdu_size, max_jobs };
        self.events
            .push_back(ClientEvent::Connected { pdu_size, max_jobs });
        while let Some((id, asked)) = self.waiting.pop_front() {
            self.plan(id, asked, pdu_size);
        }
        self.send_jobs();
        Ok(())
    }

    fn handle_answer(
        &mut self,
        pdu_ref: u16,
        error: ErrorCode,
        response: Option<Response>,
    ) -> Result<(), ConnectionError> {
        let Some(job) = self.open_jobs.remove(&pdu_ref) else {
            // An answer to a job this end never sent, or sent twice: tolerated a few
            // times (a PLC repeating itself), then the connection is not trusted.
            self.stray_answers += 1;
            tracing::warn!(target: "s7::pdu", pdu_ref, "answer to no open job");
            if self.stray_answers > MAX_STRAY_ANSWERS {
                return Err(ConnectionError::TooManyBadPdus(self.stray_answers));
            }
            return Ok(());
        };
        let operation_id = job.operation;
        let Some(operation) = self.operations.get_mut(&operation_id) else {
            return Ok(());
        };
        let pieces = &job.batch.pieces;
        match (operation, job.function, response) {
            (Operation::Read { results, open_jobs }, function::READ_VAR, response) => {
                let items = match response {
                    _ if error.is_error() => None,
                    Some(Response::ReadVar(items)) if items.len() == pieces.len() => Some(items),
                    _ => return Err(ConnectionError::MismatchedAnswer { pdu_ref }),
                };
                for (index, piece) in pieces.iter().enumerate() {
                    let outcome = match items.as_ref().and_then(|items| items.get(index)) {
                        None => Err(ItemError::JobRefused(error)),
                        Some(item) if item.return_code != ReturnCode::Success => {
                            Err(ItemError::Refused(item.return_code))
                        }
                        Some(item) => Ok(&item.data),
                    };
                    let Some(slot) = results.get_mut(piece.item) else {
                        continue;
                    };
                    let Ok(buffer) = slot else {
                        // The item already failed in another piece.
                        continue;
                    };
                    let expected = piece.region.data_len() as usize;
                    let start = piece.offset as usize;
                    match outcome {
                        Ok(data) if data.len() == expected => {
                            if let Some(target) = buffer.get_mut(start..start + expected) {
                                target.copy_from_slice(data);
                            }
                        }
                        Ok(data) => {
                            *slot = Err(ItemError::Length {
                                expected,
                                got: data.len(),
                            })
                        }
                        Err(item_error) => *slot = Err(item_error),
                    }
                }
                *open_jobs = open_jobs.saturating_sub(1);
            }
            (Operation::Write { results, open_jobs }, function::WRITE_VAR, response) => {
                let codes = match response {
                    _ if error.is_error() => None,
                    Some(Response::WriteVar(codes)) if codes.len() == pieces.len() => Some(codes),
                    _ => return Err(ConnectionError::MismatchedAnswer { pdu_ref }),
                };
                for (index, piece) in pieces.iter().enumerate() {
                    let outcome = match codes.as_ref().and_then(|codes| codes.get(index)) {
                        None => Err(ItemError::JobRefused(error)),
                        Some(ReturnCode::Success) => Ok(()),
                        Some(code) => Err(ItemError::Refused(*code)),
                    };
                    if let (Some(slot @ Ok(())), Err(item_error)) =
                        (results.get_mut(piece.item), outcome)
                    {
                        *slot = Err(item_error);
                    }
                }
                *open_jobs = open_jobs.saturating_sub(1);
            }
            _ => return Err(ConnectionError::MismatchedAnswer { pdu_ref }),
        }
        self.finish_if_done(operation_id);
        self.send_jobs();
        Ok(())
    }

    fn finish_if_done(&mut self, id: OperationId) {
        let done = match self.operations.get(&id) {
            Some(Operation::Read { open_jobs, .. } | Operation::Write { open_jobs, .. }) => {
                *open_jobs == 0
            }
            None => false,
        };
        if !done {
            return;
        }
        match self.operations.remove(&id) {
            Some(Operation::Read { results, .. }) => {
                self.events.push_back(ClientEvent::ReadDone { id, results });
            }
            Some(Operation::Write { results, .. }) => {
                self.events
                    .push_back(ClientEvent::WriteDone { id, results });
            }
            None => {}
        }
    }

    fn close(&mut self, error: ConnectionError) {
        tracing::debug!(target: "s7::cotp", %error, "connection closed");
        self.state = State::Closed;
        self.waiting.clear();
        self.operations.clear();
        self.jobs.clear();
        self.open_jobs.clear();
        self.events.push_back(ClientEvent::Closed(error));
    }
}
