//! The sans-IO APCI state machine of one IEC 104 connection.
//!
//! A [`Session`] takes TCP bytes and [`Instant`]s and hands out bytes to write, events
//! and its next deadline. It never reads a clock or a socket. A driver loop:
//!
//! ```text
//! loop {
//!     on bytes from the socket:   session.handle_input(now, bytes)
//!     on session.poll_timeout():  session.handle_timeout(now)
//!     on a user request:          session.send_asdu(now, asdu) / start_data_transfer(now) ...
//!     then, every time:           while session.poll_transmit(&mut buf) { write buf }
//!                                 while let Some(event) = session.poll_event() { ... }
//! }
//! ```
//!
//! ASDUs are opaque byte payloads here.
//!
//! # Behaviour
//!
//! **Sequence numbers** start at 0 on every connection. A received I frame must carry
//! N(S) = V(R), else the connection closes ([`CloseReason::SequenceMismatch`]; a peer
//! starting at 1 is logged as such). An N(R), in an I or S frame, acknowledges every sent
//! I frame before it and must lie in `[oldest unacknowledged, V(S)]` modulo 32768, else
//! the connection closes ([`CloseReason::BadAcknowledgement`]).
//!
//! **Flow control.** At most k sent I frames are unacknowledged
//! ([`SendError::WindowFull`] beyond). Received I frames are acknowledged by an S frame
//! once w of them are unacknowledged (checked in [`Session::poll_transmit`], so frames
//! that arrived in one read are acknowledged by one S frame) or when t2, started by the
//! first unacknowledged one, expires; every sent I frame carries V(R) and counts as the
//! acknowledgement.
//!
//! **t1** runs from the transmission of the oldest unacknowledged I frame: when it is
//! acknowledged and others remain, the deadline becomes the next oldest frame's
//! transmission time plus t1; when none remain it stops. t1 also runs for each STARTDT,
//! STOPDT or TESTFR act until its confirmation. Any t1 expiry closes the connection.
//! **t3**: after t3 without receiving any frame a TESTFR act is sent (in every state);
//! t3 is disarmed until the next frame arrives. A TESTFR act is answered at once in every
//! state.
//!
//! **STARTDT / STOPDT.** The connection starts stopped. I frames are accepted only while
//! started (the controlling station also accepts them while its STOPDT act is pending:
//! the controlled station may send until it has received the act); otherwise the
//! connection closes ([`CloseReason::IFrameWhileStopped`]). S frames are accepted while
//! started or stopping, and in any other state only while our own I frames are
//! outstanding (after [`Session::deactivate`], or from a peer that confirmed a stop
//! early): an S frame that can acknowledge nothing closes the connection
//! ([`CloseReason::SFrameWhileStopped`]), as lib60870's controlled station does.
//!
//! The controlled station answers STARTDT act with STARTDT con and emits
//! [`SessionEvent::Started`] (a repeated act while started is confirmed again without an
//! event; an act while a stop is pending cancels the stop and is confirmed). On STOPDT
//! act it stops sending new I frames, acknowledges every received I frame with an S
//! frame at once, waits until all its own I frames are acknowledged and only then sends
//! STOPDT con and emits [`SessionEvent::Stopped`] (IEC 60870-5-604 test 5.3.2.70). I
//! frames received while waiting close the connection. While its STOPDT act is pending,
//! the controlling station acknowledges each received I frame at once, so that the
//! controlled station can complete the stop quickly.
//!
//! **U frames for the other role** (a controlled station receiving STARTDT con or STOPDT
//! con, a controlling station receiving STARTDT act or STOPDT act) and confirmations
//! nobody asked for (STARTDT con while not starting, TESTFR con without a pending act)
//! are well-formed but out of place. lib60870 ignores them; the standard defines no
//! reaction. They are ignored with a warning and counted, and once more than
//! [`ApciConfig::max_unexpected_frames`] were seen the connection closes
//! ([`CloseReason::TooManyUnexpectedFrames`]). They do restart t3: the peer is alive.
//!
//! **Malformed frames** close at once with [`CloseReason::Frame`]: over TCP there is no
//! resynchronisation.
//!
//! **Redundancy.** [`Session::deactivate`] stops a controlled station's connection
//! locally without sending any U frame (an unsolicited STOPDT would make clients loop
//! reconnecting), and [`Session::take_unacknowledged`] hands out the ASDUs sent but not
//! yet acknowledged, in order, to be retransmitted on the newly started connection.

use std::collections::VecDeque;
use std::fmt;
use std::time::{Duration, Instant};

use tracing::{debug, info, warn};

use super::config::{ApciConfig, MAX_K};
use crate::apci::{
    encode_i_frame, encode_s_frame, encode_u_frame, Apci, Deframer, Frame, FrameError, SeqNum,
    UFunction, MAX_ASDU_LEN,
};

/// Which end of the connection this session is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Role {
    /// The controlling station (master, TCP client): starts and stops data transfer.
    ControllingStation,
    /// The controlled station (outstation, TCP server): answers STARTDT and STOPDT.
    ControlledStation,
}

impl fmt::Display for Role {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Role::ControllingStation => "controlling station",
            Role::ControlledStation => "controlled station",
        })
    }
}

/// The state of data transfer on a connection.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SessionState {
    /// No user data may be sent or received (the initial state).
    Stopped,
    /// Controlling station: STARTDT act sent, waiting for STARTDT con.
    PendingStart,
    /// Data transfer is running.
    Started,
    /// Controlling station: STOPDT act sent, waiting for STOPDT con. Controlled station:
    /// STOPDT act received, waiting for its I frames to be acknowledged.
    PendingStop,
    /// The connection is finished; the socket must be closed.
    Closed(CloseReason),
}

impl fmt::Display for SessionState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SessionState::Stopped => f.write_str("stopped"),
            SessionState::PendingStart => f.write_str("starting"),
            SessionState::Started => f.write_str("started"),
            SessionState::PendingStop => f.write_str("stopping"),
            SessionState::Closed(reason) => write!(f, "closed: {reason}"),
        }
    }
}

/// Why a connection was closed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum CloseReason {
    /// [`Session::close`] was called by the local user.
    #[error("closed on local request")]
    LocalRequest,
    /// The peer closed the TCP connection (reported by the driver).
    #[error("peer closed the connection")]
    PeerClosed,
    /// The transport failed (reported by the driver).
    #[error("transport error: {0}")]
    Io(std::io::ErrorKind),
    /// The received byte stream is not valid APCI framing.
    #[error("malformed APDU: {0}")]
    Frame(#[from] FrameError),
    /// A received I frame's N(S) is not the expected V(R).
    #[error("received I frame with N(S) = {received}, expected {expected}")]
    SequenceMismatch {
        /// Our V(R).
        expected: SeqNum,
        /// The frame's N(S).
        received: SeqNum,
    },
    /// A received N(R) acknowledges frames we never sent or that were already
    /// acknowledged.
    #[error(
        "received N(R) = {received} outside [{oldest_unacknowledged}, {next_send}] \
         (oldest unacknowledged, next to send)"
    )]
    BadAcknowledgement {
        /// The N(R) received.
        received: SeqNum,
        /// The sequence number of our oldest unacknowledged I frame.
        oldest_unacknowledged: SeqNum,
        /// Our V(S).
        next_send: SeqNum,
    },
    /// An I frame arrived while data transfer was not started.
    #[error("I frame received while data transfer is not started")]
    IFrameWhileStopped,
    /// An S frame arrived while data transfer was stopped and nothing was outstanding.
    #[error("S frame received while data transfer is stopped and nothing is outstanding")]
    SFrameWhileStopped,
    /// t1 expired before our I frame `send_seq` was acknowledged.
    #[error("t1 expired waiting for the acknowledgement of I frame N(S) = {send_seq}")]
    AcknowledgementTimeout {
        /// N(S) of the oldest unacknowledged I frame.
        send_seq: SeqNum,
    },
    /// t1 expired before the confirmation of a U act frame we sent.
    #[error("t1 expired waiting for the confirmation of {0}")]
    ConfirmationTimeout(UFunction),
    /// More well-formed but unexpected U frames arrived than
    /// [`ApciConfig::max_unexpected_frames`] allows.
    #[error("{count} unexpected U frames received, the last was {last}")]
    TooManyUnexpectedFrames {
        /// How many were received.
        count: u32,
        /// The last one.
        last: UFunction,
    },
}

impl CloseReason {
    /// Whether the close was caused by the peer's protocol behaviour (as opposed to a
    /// local request or the transport).
    pub fn is_protocol_error(&self) -> bool {
        !matches!(
            self,
            CloseReason::LocalRequest | CloseReason::PeerClosed | CloseReason::Io(_)
        )
    }
}

/// Something the user of a [`Session`] must react to.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SessionEvent {
    /// The ASDU of a received I frame; ASDUs come in sequence order, each exactly once.
    Asdu(Vec<u8>),
    /// Data transfer started. Controlled station: a STARTDT act was received and
    /// confirmed (redundancy logic makes this the active connection). Controlling
    /// station: STARTDT con was received.
    Started,
    /// Data transfer stopped: STOPDT con was sent (controlled) or received (controlling).
    Stopped,
    /// `count` of our I frames were acknowledged; the window has room again.
    Acknowledged {
        /// How many I frames were newly acknowledged.
        count: usize,
    },
    /// The connection is finished; close the socket. Always the last event.
    Closed(CloseReason),
}

/// Why [`Session::send_asdu`] refused an ASDU.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum SendError {
    /// Data transfer is not started (or is stopping).
    #[error("data transfer is not started")]
    NotStarted,
    /// k I frames are unacknowledged; wait for [`SessionEvent::Acknowledged`].
    #[error("k unacknowledged I frames are outstanding")]
    WindowFull,
    /// The ASDU is longer than 249 octets.
    #[error("ASDU of {0} octets exceeds the maximum of 249")]
    TooLong(usize),
    /// The ASDU is empty; an I frame must carry at least one octet.
    #[error("empty ASDU")]
    Empty,
    /// The connection is closed.
    #[error("the connection is closed")]
    Closed,
}

/// Why a STARTDT or STOPDT request was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ControlError {
    /// Only the controlling station starts and stops data transfer.
    #[error("only the controlling station starts and stops data transfer")]
    NotControllingStation,
    /// The request does not fit the current state.
    #[error("not possible while the connection is {0}")]
    InvalidState(SessionState),
}

/// Counters of one connection. Frames and bytes "sent" are those queued for and
/// handed out by [`Session::poll_transmit`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct SessionStats {
    /// Bytes given to [`Session::handle_input`].
    pub bytes_received: u64,
    /// Bytes handed out by [`Session::poll_transmit`].
    pub bytes_sent: u64,
    /// Valid frames received (all formats).
    pub frames_received: u64,
    /// Frames sent (all formats).
    pub frames_sent: u64,
    /// I frames received.
    pub i_frames_received: u64,
    /// I frames sent.
    pub i_frames_sent: u64,
    /// S frames received.
    pub s_frames_received: u64,
    /// S frames sent.
    pub s_frames_sent: u64,
    /// U frames received.
    pub u_frames_received: u64,
    /// U frames sent.
    pub u_frames_sent: u64,
    /// TESTFR act and con frames received (included in the U frame count).
    pub test_frames_received: u64,
    /// TESTFR act and con frames sent (included in the U frame count).
    pub test_frames_sent: u64,
    /// Unexpected U frames received and ignored.
    pub unexpected_frames_received: u64,
}

/// The sans-IO APCI state machine of one IEC 104 connection. See the
/// [module documentation](self) for the behaviour.
#[derive(Debug)]
pub struct Session {
    deframer: Deframer,
    core: Core,
}

/// A sent I frame kept until acknowledged, with its ASDU inline (no allocation).
#[derive(Clone)]
struct SentFrame {
    seq: SeqNum,
    sent_at: Instant,
    len: u8,
    asdu: [u8; MAX_ASDU_LEN],
}

impl SentFrame {
    fn asdu(&self) -> &[u8] {
        self.asdu.get(..usize::from(self.len)).unwrap_or_default()
    }
}

impl fmt::Debug for SentFrame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SentFrame")
            .field("seq", &self.seq)
            .field("sent_at", &self.sent_at)
            .field("len", &self.len)
            .finish()
    }
}

/// The deadlines kept in the timer table. The t1 deadline of sent I frames is not in the
/// table: it derives from the oldest unacknowledged frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Deadline {
    /// t1 for a STARTDT or STOPDT act (the function is in `pending_control`).
    Control,
    /// t1 for a TESTFR act.
    TestFr,
    /// t2: acknowledge received I frames.
    Ack,
    /// t3: idle, send TESTFR act.
    Idle,
}

const DEADLINES: usize = 4;

#[derive(Debug)]
struct Core {
    config: ApciConfig,
    role: Role,
    state: SessionState,
    /// V(S): the N(S) of the next I frame we send.
    v_s: SeqNum,
    /// The N(S) of our oldest unacknowledged I frame (= the last N(R) received).
    v_a: SeqNum,
    /// V(R): the N(S) we expect next.
    v_r: SeqNum,
    /// Received I frames not yet acknowledged.
    recv_unacked: u32,
    /// Copies of sent, unacknowledged I frames, oldest first.
    sent: VecDeque<SentFrame>,
    timers: [Option<Instant>; DEADLINES],
    /// The STARTDT or STOPDT act waiting for confirmation (controlling station).
    pending_control: Option<UFunction>,
    /// Whether completing a controlled station's pending stop emits `Stopped` (not when
    /// the stop was requested on a connection already deactivated locally).
    announce_stop: bool,
    /// A controlled station's connection stopped locally by a redundancy switch-over
    /// ([`Session::deactivate`]), which its peer does not know of: it may be taken back
    /// ([`Session::reactivate`]), and a STOPDT from its peer is still announced.
    deactivated_locally: bool,
    unexpected: u32,
    tx: Vec<u8>,
    events: VecDeque<SessionEvent>,
    stats: SessionStats,
}

impl Session {
    /// A session for a TCP connection just established at `now`: stopped, sequence
    /// numbers at 0, t3 running.
    ///
    /// The configuration should have passed [`ApciConfig::validate`]; values the session
    /// cannot work with are clamped (k to 1..=32767, w to 1..=k) with a warning.
    pub fn new(config: ApciConfig, role: Role, now: Instant) -> Session {
        let mut config = config;
        let k = config.k.clamp(1, MAX_K);
        let w = config.w.clamp(1, k);
        if (k, w) != (config.k, config.w) {
            warn!(
                k = config.k,
                w = config.w,
                clamped_k = k,
                clamped_w = w,
                "invalid APCI window parameters clamped"
            );
        }
        config.k = k;
        config.w = w;
        let t3 = config.t3;
        let mut core = Core {
            // Grown on first send: an idle connection keeps no window buffer (each
            // slot holds a whole ASDU, about 280 octets).
            sent: VecDeque::new(),
            config,
            role,
            state: SessionState::Stopped,
            v_s: SeqNum::ZERO,
            v_a: SeqNum::ZERO,
            v_r: SeqNum::ZERO,
            recv_unacked: 0,
            timers: [None; DEADLINES],
            pending_control: None,
            announce_stop: true,
            deactivated_locally: false,
            unexpected: 0,
            tx: Vec::new(),
            events: VecDeque::new(),
            stats: SessionStats::default(),
        };
        core.set_timer(Deadline::Idle, deadline(now, t3));
        Session {
            deframer: Deframer::new(),
            core,
        }
    }

    /// Processes bytes read from the TCP connection at `now`.
    ///
    /// Afterwards call [`Session::poll_transmit`] (answers, acknowledgements),
    /// [`Session::poll_event`] (ASDUs, state changes, close) and
    /// [`Session::poll_timeout`] (t3 restarted, t2 started). Ignored once closed; on a
    /// framing or protocol error the session closes and the rest of `bytes` is dropped.
    pub fn handle_input(&mut self, now: Instant, bytes: &[u8]) {
        if self.core.is_closed() {
            return;
        }
        self.core.stats.bytes_received += bytes.len() as u64;
        let mut rest = bytes;
        loop {
            let taken = self.deframer.push(rest);
            rest = rest.get(taken..).unwrap_or_default();
            while let Some(result) = self.deframer.next_frame() {
                match result {
                    Ok(frame) => self.core.on_frame(now, frame),
                    Err(error) => self.core.close(CloseReason::Frame(error)),
                }
                if self.core.is_closed() {
                    return;
                }
            }
            if rest.is_empty() {
                return;
            }
            if taken == 0 {
                // Cannot happen: the deframer holds less than one APDU after draining and
                // has room for at least one. Fail closed rather than spin.
                let error = self
                    .deframer
                    .error()
                    .unwrap_or(FrameError::LengthTooLong(0));
                self.core.close(CloseReason::Frame(error));
                return;
            }
        }
    }

    /// Handles expired timers; call it at or after [`Session::poll_timeout`] (calling it
    /// early does nothing).
    ///
    /// t1 expiry closes the connection; t2 expiry queues an S frame; t3 expiry queues a
    /// TESTFR act. Afterwards call [`Session::poll_transmit`], [`Session::poll_event`] and
    /// [`Session::poll_timeout`].
    pub fn handle_timeout(&mut self, now: Instant) {
        self.core.handle_timeout(now);
    }

    /// Appends the bytes to write to the socket to `out` and returns whether there were
    /// any. Call after every other method until it returns `false`.
    ///
    /// Received I frames that reached w unacknowledged are acknowledged here, so that one
    /// S frame covers everything read so far. Returns `false` once closed (bytes still
    /// queued then are dropped).
    pub fn poll_transmit(&mut self, out: &mut Vec<u8>) -> bool {
        self.core.poll_transmit(out)
    }

    /// The next instant at which [`Session::handle_timeout`] must be called: the earliest
    /// running t1, t2 or t3 deadline. `None` when closed.
    pub fn poll_timeout(&self) -> Option<Instant> {
        self.core.poll_timeout()
    }

    /// The next event, oldest first. Call after every other method until `None`.
    pub fn poll_event(&mut self) -> Option<SessionEvent> {
        self.core.events.pop_front()
    }

    /// Sends `asdu` (1..=249 octets) in an I frame at `now`, which also acknowledges
    /// every I frame received so far. Starts t1 if no other frame was unacknowledged.
    ///
    /// Afterwards call [`Session::poll_transmit`] and [`Session::poll_timeout`].
    pub fn send_asdu(&mut self, now: Instant, asdu: &[u8]) -> Result<(), SendError> {
        self.core.send_asdu(now, asdu)
    }

    /// Whether [`Session::send_asdu`] would accept an ASDU now: data transfer started
    /// and fewer than k I frames unacknowledged.
    pub fn can_send(&self) -> bool {
        self.core.state == SessionState::Started && self.core.window() < self.core.config.k
    }

    /// Controlling station: sends STARTDT act and waits (t1) for STARTDT con, which
    /// emits [`SessionEvent::Started`]. Only from [`SessionState::Stopped`].
    ///
    /// Afterwards call [`Session::poll_transmit`] and [`Session::poll_timeout`].
    pub fn start_data_transfer(&mut self, now: Instant) -> Result<(), ControlError> {
        self.core
            .request_control(now, SessionState::Stopped, UFunction::StartDtAct)
    }

    /// Controlling station: sends STOPDT act and waits (t1) for STOPDT con, which emits
    /// [`SessionEvent::Stopped`]. Only from [`SessionState::Started`]. No further ASDU
    /// can be sent; received I frames keep arriving and are acknowledged at once.
    ///
    /// Afterwards call [`Session::poll_transmit`] and [`Session::poll_timeout`].
    pub fn stop_data_transfer(&mut self, now: Instant) -> Result<(), ControlError> {
        self.core
            .request_control(now, SessionState::Started, UFunction::StopDtAct)
    }

    /// Controlled station, redundancy switch-over: another connection of the group was
    /// started, so this one goes to [`SessionState::Stopped`] locally, without sending
    /// any U frame (an unsolicited STOPDT would make the client loop reconnecting).
    ///
    /// Then hand the unacknowledged ASDUs to the new connection with
    /// [`Session::take_unacknowledged`]. Acknowledgements the peer still sends here are
    /// accepted; an I frame from the peer now closes this connection. Does nothing on a
    /// controlling station, nor while a STOPDT requested by the peer is pending (its
    /// STOPDT con is still owed). No event is emitted.
    pub fn deactivate(&mut self) {
        self.core.deactivate();
    }

    /// Controlled station, redundancy switch-back: the connection that took the group
    /// over went away, so this one, deactivated by [`Session::deactivate`] and never
    /// stopped by its peer, is started again locally (no U frame: its peer still
    /// believes it started). Returns whether it was; does nothing otherwise.
    pub fn reactivate(&mut self) -> bool {
        self.core.reactivate()
    }

    /// Removes and returns the ASDUs sent but not yet acknowledged, oldest first, to
    /// retransmit on the new active connection of a redundancy group. Works in every
    /// state, including after close.
    ///
    /// The sequence-number window is unchanged: the peer may still acknowledge those
    /// frames here, and [`Session::unacknowledged_count`] still counts them, but t1 no
    /// longer runs for them.
    pub fn take_unacknowledged(&mut self) -> Vec<Vec<u8>> {
        self.core
            .sent
            .drain(..)
            .map(|frame| frame.asdu().to_vec())
            .collect()
    }

    /// Acknowledges at once every I frame received so far: queues an S frame carrying
    /// V(R) if any received I frame is not yet acknowledged (does nothing otherwise, nor
    /// once closed), and stops t2.
    ///
    /// Call it before closing a connection politely, so that what the application has
    /// already received is not retransmitted by the peer to the next connection (a
    /// controlled station keeps unacknowledged events for its redundancy group). Then
    /// call [`Session::poll_transmit`] and write the bytes out *before*
    /// [`Session::close`], which drops whatever is still queued.
    pub fn acknowledge_received(&mut self) {
        if !self.core.is_closed() {
            self.core.send_ack();
        }
    }

    /// Closes the session (local request, peer closed, transport error): emits
    /// [`SessionEvent::Closed`] and drops queued bytes. Unacknowledged ASDUs stay
    /// available to [`Session::take_unacknowledged`]. Does nothing if already closed.
    pub fn close(&mut self, reason: CloseReason) {
        self.core.close(reason);
    }

    /// The current state.
    pub fn state(&self) -> SessionState {
        self.core.state.clone()
    }

    /// Whether the session is closed.
    pub fn is_closed(&self) -> bool {
        self.core.is_closed()
    }

    /// The role given at creation.
    pub fn role(&self) -> Role {
        self.core.role
    }

    /// The configuration in use (after clamping).
    pub fn config(&self) -> &ApciConfig {
        &self.core.config
    }

    /// How many sent I frames are unacknowledged (the occupied part of the k window).
    pub fn unacknowledged_count(&self) -> usize {
        usize::from(self.core.window())
    }

    /// V(S), the N(S) of the next I frame to send.
    pub fn send_seq(&self) -> SeqNum {
        self.core.v_s
    }

    /// V(R), the N(S) expected in the next received I frame.
    pub fn recv_seq(&self) -> SeqNum {
        self.core.v_r
    }

    /// Counters of frames and bytes.
    pub fn stats(&self) -> SessionStats {
        self.core.stats
    }
}

fn deadline(from: Instant, after: Duration) -> Option<Instant> {
    from.checked_add(after)
}

fn expired(deadline: Option<Instant>, now: Instant) -> bool {
    deadline.is_some_and(|at| at <= now)
}

impl Core {
    fn is_closed(&self) -> bool {
        matches!(self.state, SessionState::Closed(_))
    }

    fn window(&self) -> u16 {
        self.v_a.distance(self.v_s)
    }

    fn timer(&self, which: Deadline) -> Option<Instant> {
        self.timers.get(which as usize).copied().flatten()
    }

    fn set_timer(&mut self, which: Deadline, at: Option<Instant>) {
        if let Some(slot) = self.timers.get_mut(which as usize) {
            *slot = at;
        }
    }

    fn close(&mut self, reason: CloseReason) {
        if self.is_closed() {
            return;
        }
        if reason.is_protocol_error() {
            warn!(role = %self.role, %reason, "closing IEC 104 connection");
        } else {
            info!(role = %self.role, %reason, "closing IEC 104 connection");
        }
        self.state = SessionState::Closed(reason.clone());
        self.timers = [None; DEADLINES];
        self.pending_control = None;
        self.tx.clear();
        self.events.push_back(SessionEvent::Closed(reason));
    }

    fn poll_timeout(&self) -> Option<Instant> {
        if self.is_closed() {
            return None;
        }
        let t1 = self
            .sent
            .front()
            .and_then(|frame| deadline(frame.sent_at, self.config.t1));
        self.timers.iter().flatten().copied().chain(t1).min()
    }

    fn handle_timeout(&mut self, now: Instant) {
        if self.is_closed() {
            return;
        }
        if let Some(front) = self.sent.front() {
            if expired(deadline(front.sent_at, self.config.t1), now) {
                let send_seq = front.seq;
                self.close(CloseReason::AcknowledgementTimeout { send_seq });
                return;
            }
        }
        if expired(self.timer(Deadline::Control), now) {
            let function = self.pending_control.unwrap_or(UFunction::StartDtAct);
            self.close(CloseReason::ConfirmationTimeout(function));
            return;
        }
        if expired(self.timer(Deadline::TestFr), now) {
            self.close(CloseReason::ConfirmationTimeout(UFunction::TestFrAct));
            return;
        }
        if expired(self.timer(Deadline::Ack), now) {
            debug!(v_r = %self.v_r, "t2 expired, acknowledging");
            self.send_ack();
        }
        if expired(self.timer(Deadline::Idle), now) {
            self.set_timer(Deadline::Idle, None);
            if self.timer(Deadline::TestFr).is_none() {
                debug!("t3 expired, sending TESTFR act");
                self.send_u(UFunction::TestFrAct);
                self.set_timer(Deadline::TestFr, deadline(now, self.config.t1));
            }
        }
    }

    fn poll_transmit(&mut self, out: &mut Vec<u8>) -> bool {
        if self.is_closed() {
            self.tx.clear();
            return false;
        }
        let stopping_client =
            self.role == Role::ControllingStation && self.state == SessionState::PendingStop;
        if self.recv_unacked >= u32::from(self.config.w)
            || (stopping_client && self.recv_unacked > 0)
        {
            self.send_ack();
        }
        if self.tx.is_empty() {
            return false;
        }
        self.stats.bytes_sent += self.tx.len() as u64;
        if out.is_empty() {
            std::mem::swap(out, &mut self.tx);
        } else {
            out.extend_from_slice(&self.tx);
            self.tx.clear();
        }
        true
    }

    fn send_asdu(&mut self, now: Instant, asdu: &[u8]) -> Result<(), SendError> {
        match self.state {
            SessionState::Started => {}
            SessionState::Closed(_) => return Err(SendError::Closed),
            _ => return Err(SendError::NotStarted),
        }
        let len = match u8::try_from(asdu.len()) {
            Ok(0) => return Err(SendError::Empty),
            Ok(len) if usize::from(len) <= MAX_ASDU_LEN => len,
            _ => return Err(SendError::TooLong(asdu.len())),
        };
        if self.window() >= self.config.k {
            return Err(SendError::WindowFull);
        }
        let mut copy = [0u8; MAX_ASDU_LEN];
        if let Some(dst) = copy.get_mut(..asdu.len()) {
            dst.copy_from_slice(asdu);
        }
        if encode_i_frame(self.v_s, self.v_r, asdu, &mut self.tx).is_err() {
            // Unreachable: the length was checked above.
            return Err(SendError::TooLong(asdu.len()));
        }
        debug!(n_s = %self.v_s, n_r = %self.v_r, len, "tx I");
        self.sent.push_back(SentFrame {
            seq: self.v_s,
            sent_at: now,
            len,
            asdu: copy,
        });
        self.v_s = self.v_s.next();
        self.recv_unacked = 0;
        self.set_timer(Deadline::Ack, None);
        self.stats.i_frames_sent += 1;
        self.stats.frames_sent += 1;
        Ok(())
    }

    fn request_control(
        &mut self,
        now: Instant,
        required: SessionState,
        act: UFunction,
    ) -> Result<(), ControlError> {
        if self.role != Role::ControllingStation {
            return Err(ControlError::NotControllingStation);
        }
        if self.state != required {
            return Err(ControlError::InvalidState(self.state.clone()));
        }
        self.send_u(act);
        self.state = if act == UFunction::StartDtAct {
            SessionState::PendingStart
        } else {
            SessionState::PendingStop
        };
        self.pending_control = Some(act);
        self.set_timer(Deadline::Control, deadline(now, self.config.t1));
        Ok(())
    }

    fn deactivate(&mut self) {
        if self.role != Role::ControlledStation {
            debug!("deactivate ignored on a controlling station");
            return;
        }
        if self.state == SessionState::Started {
            info!(
                unacknowledged = self.window(),
                "connection deactivated locally (redundancy switch-over)"
            );
            self.state = SessionState::Stopped;
            self.deactivated_locally = true;
        }
    }

    fn reactivate(&mut self) -> bool {
        if self.role != Role::ControlledStation
            || self.state != SessionState::Stopped
            || !self.deactivated_locally
        {
            return false;
        }
        info!("connection reactivated locally (redundancy switch-back)");
        self.deactivated_locally = false;
        self.state = SessionState::Started;
        true
    }

    /// Queues an S frame acknowledging everything received, if anything is unacknowledged.
    fn send_ack(&mut self) {
        if self.recv_unacked == 0 {
            self.set_timer(Deadline::Ack, None);
            return;
        }
        encode_s_frame(self.v_r, &mut self.tx);
        debug!(n_r = %self.v_r, "tx S");
        self.recv_unacked = 0;
        self.set_timer(Deadline::Ack, None);
        self.stats.s_frames_sent += 1;
        self.stats.frames_sent += 1;
    }

    fn send_u(&mut self, function: UFunction) {
        encode_u_frame(function, &mut self.tx);
        debug!(%function, "tx U");
        self.stats.u_frames_sent += 1;
        self.stats.frames_sent += 1;
        if matches!(function, UFunction::TestFrAct | UFunction::TestFrCon) {
            self.stats.test_frames_sent += 1;
        }
    }

    fn on_frame(&mut self, now: Instant, frame: Frame<'_>) {
        self.stats.frames_received += 1;
        self.set_timer(Deadline::Idle, deadline(now, self.config.t3));
        match frame.apci {
            Apci::I { send_seq, recv_seq } => {
                debug!(n_s = %send_seq, n_r = %recv_seq, len = frame.asdu.len(), "rx I");
                self.on_i_frame(now, send_seq, recv_seq, frame.asdu);
            }
            Apci::S { recv_seq } => {
                debug!(n_r = %recv_seq, "rx S");
                self.on_s_frame(recv_seq);
            }
            Apci::U(function) => {
                debug!(%function, "rx U");
                self.on_u_frame(function);
            }
        }
    }

    fn on_i_frame(&mut self, now: Instant, send_seq: SeqNum, recv_seq: SeqNum, asdu: &[u8]) {
        self.stats.i_frames_received += 1;
        let accepting = match self.state {
            SessionState::Started => true,
            SessionState::PendingStop => self.role == Role::ControllingStation,
            _ => false,
        };
        if !accepting {
            self.close(CloseReason::IFrameWhileStopped);
            return;
        }
        if send_seq != self.v_r {
            if self.v_r == SeqNum::ZERO
                && send_seq == SeqNum::new(1)
                && self.stats.i_frames_received == 1
            {
                warn!("peer started its send sequence at 1 instead of 0 (non-conformant)");
            }
            self.close(CloseReason::SequenceMismatch {
                expected: self.v_r,
                received: send_seq,
            });
            return;
        }
        if !self.acknowledge(recv_seq) {
            return;
        }
        self.v_r = self.v_r.next();
        self.recv_unacked += 1;
        if self.recv_unacked == 1 {
            self.set_timer(Deadline::Ack, deadline(now, self.config.t2));
        }
        self.events.push_back(SessionEvent::Asdu(asdu.to_vec()));
    }

    fn on_s_frame(&mut self, recv_seq: SeqNum) {
        self.stats.s_frames_received += 1;
        let accepting = matches!(
            self.state,
            SessionState::Started | SessionState::PendingStop
        ) || self.window() > 0;
        if !accepting {
            self.close(CloseReason::SFrameWhileStopped);
            return;
        }
        self.acknowledge(recv_seq);
    }

    /// Applies a received N(R). Returns false (after closing) when it is out of range.
    fn acknowledge(&mut self, recv_seq: SeqNum) -> bool {
        if !recv_seq.is_within(self.v_a, self.v_s) {
            self.close(CloseReason::BadAcknowledgement {
                received: recv_seq,
                oldest_unacknowledged: self.v_a,
                next_send: self.v_s,
            });
            return false;
        }
        let count = self.v_a.distance(recv_seq);
        if count == 0 {
            return true;
        }
        let oldest = self.v_a;
        self.v_a = recv_seq;
        while self
            .sent
            .front()
            .is_some_and(|frame| oldest.distance(frame.seq) < count)
        {
            self.sent.pop_front();
        }
        self.events.push_back(SessionEvent::Acknowledged {
            count: usize::from(count),
        });
        self.complete_pending_stop();
        true
    }

    /// Controlled station: sends STOPDT con once every sent I frame is acknowledged.
    fn complete_pending_stop(&mut self) {
        if self.role == Role::ControlledStation
            && self.state == SessionState::PendingStop
            && self.window() == 0
        {
            self.send_u(UFunction::StopDtCon);
            self.state = SessionState::Stopped;
            if self.announce_stop {
                self.events.push_back(SessionEvent::Stopped);
            }
        }
    }

    fn on_u_frame(&mut self, function: UFunction) {
        self.stats.u_frames_received += 1;
        if matches!(function, UFunction::TestFrAct | UFunction::TestFrCon) {
            self.stats.test_frames_received += 1;
        }
        match (function, self.role) {
            (UFunction::TestFrAct, _) => self.send_u(UFunction::TestFrCon),
            (UFunction::TestFrCon, _) => {
                if self.timer(Deadline::TestFr).is_some() {
                    self.set_timer(Deadline::TestFr, None);
                } else {
                    self.unexpected(function);
                }
            }
            (UFunction::StartDtAct, Role::ControlledStation) => {
                self.deactivated_locally = false;
                let was = std::mem::replace(&mut self.state, SessionState::Started);
                self.send_u(UFunction::StartDtCon);
                if was == SessionState::Stopped {
                    self.events.push_back(SessionEvent::Started);
                }
            }
            (UFunction::StopDtAct, Role::ControlledStation) => {
                // Acknowledge everything received before confirming (604 test 5.3.2.70).
                self.send_ack();
                if self.state != SessionState::PendingStop {
                    // A connection stopped locally is announced too: its link must stop
                    // waiting to take its group's data back.
                    self.announce_stop =
                        self.state == SessionState::Started || self.deactivated_locally;
                    self.deactivated_locally = false;
                    self.state = SessionState::PendingStop;
                }
                if self.window() > 0 {
                    debug!(
                        unacknowledged = self.window(),
                        "STOPDT act: waiting for acknowledgements before STOPDT con"
                    );
                }
                self.complete_pending_stop();
            }
            (UFunction::StartDtCon, Role::ControllingStation)
                if self.state == SessionState::PendingStart =>
            {
                self.pending_control = None;
                self.set_timer(Deadline::Control, None);
                self.state = SessionState::Started;
                self.events.push_back(SessionEvent::Started);
            }
            (UFunction::StopDtCon, Role::ControllingStation)
                if self.state == SessionState::PendingStop =>
            {
                self.pending_control = None;
                self.set_timer(Deadline::Control, None);
                self.state = SessionState::Stopped;
                self.events.push_back(SessionEvent::Stopped);
            }
            _ => self.unexpected(function),
        }
    }

    fn unexpected(&mut self, function: UFunction) {
        self.unexpected = self.unexpected.saturating_add(1);
        self.stats.unexpected_frames_received += 1;
        warn!(
            %function,
            role = %self.role,
            state = %self.state,
            count = self.unexpected,
            "unexpected U frame ignored"
        );
        if self.unexpected > self.config.max_unexpected_frames {
            self.close(CloseReason::TooManyUnexpectedFrames {
                count: self.unexpected,
                last: function,
            });
        }
    }
}
