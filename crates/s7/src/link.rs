//! The ISO transport under both ends: TPKT frames cut from the stream, COTP data TPDUs
//! joined into S7 PDUs and S7 PDUs cut into data TPDUs of the negotiated TPDU size; and
//! [`ConnectionError`], why a connection ended.

use std::collections::VecDeque;

use thiserror::Error;

use crate::cotp::{self, CotpError, Tpdu, TpduSize};
use crate::pdu::{ErrorCode, Pdu, PduError};
use crate::tpkt::{self, Deframer, TpktError};

/// The longest S7 PDU either end reassembles from data TPDUs: far above any PDU size a
/// PLC negotiates (960 at most), and a cap on what a peer can make this end buffer.
pub const MAX_ASSEMBLED_PDU: usize = 8192;

/// Why a connection ended. Both ends close on any of these: each leaves the stream in a
/// state no later byte can repair, or the peer in one no later answer can.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum ConnectionError {
    /// A TPKT frame that cannot be.
    #[error(transparent)]
    Tpkt(#[from] TpktError),
    /// A COTP TPDU that cannot be decoded.
    #[error(transparent)]
    Cotp(#[from] CotpError),
    /// An S7 PDU that cannot be decoded where no answer can report it.
    #[error(transparent)]
    Pdu(#[from] PduError),
    /// Data TPDUs adding up to more than [`MAX_ASSEMBLED_PDU`] bytes.
    #[error("an S7 PDU of more than {max} bytes", max = MAX_ASSEMBLED_PDU)]
    PduTooLong,
    /// The peer closed the TCP connection, or confirmed a disconnect.
    #[error("the peer closed the connection")]
    PeerClosed,
    /// The peer sent a disconnect request (or refused the connection with one).
    #[error("the peer disconnected (reason {reason:#04x})")]
    Disconnected {
        /// The DR's reason.
        reason: u8,
    },
    /// The peer sent a TPDU error.
    #[error("the peer rejected a TPDU (cause {cause:#04x})")]
    Rejected {
        /// The ER's cause.
        cause: u8,
    },
    /// A TPDU out of turn, e.g. data before the connection confirm.
    #[error("unexpected COTP {got} while {state}")]
    UnexpectedTpdu {
        /// What arrived.
        got: &'static str,
        /// What the connection was waiting for.
        state: &'static str,
    },
    /// An S7 PDU out of turn, e.g. a job sent to a client.
    #[error("unexpected S7 {got} while {state}")]
    UnexpectedPdu {
        /// What arrived.
        got: &'static str,
        /// What the connection was waiting for.
        state: &'static str,
    },
    /// The PLC refused setup communication.
    #[error("the PLC refused setup communication: error {0}")]
    SetupRefused(ErrorCode),
    /// The PLC granted a PDU size too small for any read or write.
    #[error("the PLC granted a PDU size of {0} bytes, below the minimum of {min}", min = crate::split::MIN_PDU_SIZE)]
    PduSizeTooSmall(u16),
    /// An answer whose items do not match the job (count or function).
    #[error("an answer that does not match its job (reference {pdu_ref})")]
    MismatchedAnswer {
        /// The reference.
        pdu_ref: u16,
    },
    /// More misbehaviour than an end tolerates: answers to no job, or undecodable jobs.
    #[error("too many bad PDUs from the peer ({0})")]
    TooManyBadPdus(u32),
}

impl ConnectionError {
    pub(crate) fn unexpected_tpdu(tpdu: &Tpdu, state: &'static str) -> ConnectionError {
        ConnectionError::UnexpectedTpdu {
            got: tpdu_name(tpdu),
            state,
        }
    }
}

fn tpdu_name(tpdu: &Tpdu) -> &'static str {
    match tpdu {
        Tpdu::ConnectionRequest(_) => "connection request",
        Tpdu::ConnectionConfirm(_) => "connection confirm",
        Tpdu::DisconnectRequest { .. } => "disconnect request",
        Tpdu::DisconnectConfirm { .. } => "disconnect confirm",
        Tpdu::Data { .. } => "data",
        Tpdu::Error { .. } => "TPDU error",
    }
}

/// What the transport hands up.
#[derive(Debug)]
pub(crate) enum Incoming {
    /// A connection TPDU (CR, CC, DR, DC, ER).
    Control(Tpdu),
    /// A complete S7 PDU, its data TPDUs joined.
    Data(Vec<u8>),
}

/// One connection's transport state.
#[derive(Debug)]
pub(crate) struct Link {
    deframer: Deframer,
    assembly: Vec<u8>,
    /// The largest TPDU the peer takes, header included.
    tpdu_size: TpduSize,
    transmit: VecDeque<Vec<u8>>,
}

impl Link {
    pub(crate) fn new() -> Link {
        Link {
            deframer: Deframer::new(),
            assembly: Vec::new(),
            tpdu_size: TpduSize::DEFAULT,
            transmit: VecDeque::new(),
        }
    }

    pub(crate) fn set_tpdu_size(&mut self, size: TpduSize) {
        self.tpdu_size = size;
    }

    pub(crate) fn push(&mut self, bytes: &[u8]) {
        self.deframer.push(bytes);
    }

    /// The next TPDU or complete S7 PDU received, `None` until one is complete.
    pub(crate) fn next_incoming(&mut self) -> Result<Option<Incoming>, ConnectionError> {
        while let Some(frame) = self.deframer.next_frame()? {
            tracing::trace!(target: "s7::tpkt", len = frame.len(), "frame received");
            let tpdu = Tpdu::decode(&frame)?;
            match tpdu {
                Tpdu::Data { eot, payload, .. } => {
                    if self.assembly.len() + payload.len() > MAX_ASSEMBLED_PDU {
                        return Err(ConnectionError::PduTooLong);
                    }
                    self.assembly.extend_from_slice(&payload);
                    if eot {
                        return Ok(Some(Incoming::Data(std::mem::take(&mut self.assembly))));
                    }
                }
                control => {
                    tracing::debug!(target: "s7::cotp", tpdu = ?control, "received");
                    return Ok(Some(Incoming::Control(control)));
                }
            }
        }
        Ok(None)
    }

    /// Queues a connection TPDU.
    pub(crate) fn send_control(&mut self, tpdu: &Tpdu) -> Result<(), ConnectionError> {
        tracing::debug!(target: "s7::cotp", ?tpdu, "sending");
        let mut payload = Vec::new();
        tpdu.encode(&mut payload)?;
        let mut frame = Vec::with_capacity(payload.len() + tpkt::HEADER_LEN);
        tpkt::encode(&payload, &mut frame)?;
        self.transmit.push_back(frame);
        Ok(())
    }

    /// Queues an S7 PDU in as many data TPDUs as the peer's TPDU size needs.
    pub(crate) fn send_pdu(&mut self, pdu: &Pdu) -> Result<(), ConnectionError> {
        tracing::trace!(target: "s7::pdu", ?pdu, "sending");
        let bytes = pdu.to_bytes()?;
        let segment_len = self.tpdu_size.bytes() - cotp::DATA_HEADER_LEN;
        let mut segments = bytes.chunks(segment_len).peekable();
        if segments.peek().is_none() {
            return Ok(());
        }
        while let Some(segment) = segments.next() {
            let tpdu = Tpdu::Data {
                eot: segments.peek().is_none(),
                number: 0,
                payload: segment.to_vec(),
            };
            let mut payload = Vec::with_capacity(segment.len() + cotp::DATA_HEADER_LEN);
            tpdu.encode(&mut payload)?;
            let mut frame = Vec::with_capacity(payload.len() + tpkt::HEADER_LEN);
            tpkt::encode(&payload, &mut frame)?;
            self.transmit.push_back(frame);
        }
        Ok(())
    }

    /// The next frame to send.
    pub(crate) fn poll_transmit(&mut self) -> Option<Vec<u8>> {
        self.transmit.pop_front()
    }
}
