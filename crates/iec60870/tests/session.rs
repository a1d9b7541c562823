//! APCI session scenarios on a virtual clock: a client and a server `Session` pumping
//! bytes into each other, or one `Session` against hand-made bytes ("raw peer").
//! Deterministic: time is a base `Instant` plus durations, nothing sleeps.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    missing_docs,
    // Tests and benchmarks measure and wait on the wall clock; the cores do not.
    clippy::disallowed_methods
)]

use std::time::{Duration, Instant};

use iec60870::apci::{
    encode_i_frame, encode_s_frame, encode_u_frame, Apci, Deframer, FrameError, FrameFormat,
    SeqNum, UFunction,
};
use iec60870::cs104::{
    ApciConfig, CloseReason, ControlError, Role, SendError, Session, SessionEvent, SessionState,
};

const SEC: Duration = Duration::from_secs(1);
const MS: Duration = Duration::from_millis(1);

// ---------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------

fn i_frame(ns: u16, nr: u16, asdu: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    encode_i_frame(SeqNum::new(ns), SeqNum::new(nr), asdu, &mut out).unwrap();
    out
}

fn s_frame(nr: u16) -> Vec<u8> {
    let mut out = Vec::new();
    encode_s_frame(SeqNum::new(nr), &mut out);
    out
}

fn u_frame(function: UFunction) -> Vec<u8> {
    let mut out = Vec::new();
    encode_u_frame(function, &mut out);
    out
}

fn i(ns: u16, nr: u16) -> Apci {
    Apci::I {
        send_seq: SeqNum::new(ns),
        recv_seq: SeqNum::new(nr),
    }
}

fn s(nr: u16) -> Apci {
    Apci::S {
        recv_seq: SeqNum::new(nr),
    }
}

fn u(function: UFunction) -> Apci {
    Apci::U(function)
}

/// Everything the session wants to transmit, decoded.
fn transmitted(session: &mut Session) -> Vec<Apci> {
    let mut bytes = Vec::new();
    while session.poll_transmit(&mut bytes) {}
    decode_all(&bytes)
}

fn decode_all(bytes: &[u8]) -> Vec<Apci> {
    let mut deframer = Deframer::new();
    let mut rest = bytes;
    let mut out = Vec::new();
    while !rest.is_empty() {
        let n = deframer.push(rest);
        rest = &rest[n..];
        while let Some(frame) = deframer.next_frame() {
            out.push(frame.expect("session transmitted a malformed frame").apci);
        }
    }
    assert_eq!(
        deframer.buffered(),
        0,
        "session transmitted a partial frame"
    );
    out
}

fn events(session: &mut Session) -> Vec<SessionEvent> {
    std::iter::from_fn(|| session.poll_event()).collect()
}

fn asdu(n: u32) -> Vec<u8> {
    // A recognisable payload of varying length (1..=249 octets).
    let mut v = n.to_le_bytes().to_vec();
    v.resize(4 + (n % 40) as usize, (n % 251) as u8);
    v
}

fn config(k: u16, w: u16) -> ApciConfig {
    let mut c = ApciConfig::default();
    c.k = k;
    c.w = w;
    c
}

/// A controlled station after STARTDT from a raw client, with the transmit and event
/// queues drained.
fn started_server(cfg: ApciConfig, t0: Instant) -> Session {
    let mut server = Session::new(cfg, Role::ControlledStation, t0);
    server.handle_input(t0, &u_frame(UFunction::StartDtAct));
    assert_eq!(transmitted(&mut server), vec![u(UFunction::StartDtCon)]);
    assert_eq!(events(&mut server), vec![SessionEvent::Started]);
    server
}

/// A controlling station after STARTDT answered by a raw server.
fn started_client(cfg: ApciConfig, t0: Instant) -> Session {
    let mut client = Session::new(cfg, Role::ControllingStation, t0);
    client.start_data_transfer(t0).unwrap();
    assert_eq!(transmitted(&mut client), vec![u(UFunction::StartDtAct)]);
    client.handle_input(t0, &u_frame(UFunction::StartDtCon));
    assert_eq!(events(&mut client), vec![SessionEvent::Started]);
    client
}

fn closed_reason(session: &Session) -> Option<CloseReason> {
    match session.state() {
        SessionState::Closed(reason) => Some(reason),
        _ => None,
    }
}

/// A client and a server session connected by a perfect, instantaneous wire.
struct Pair {
    base: Instant,
    now: Instant,
    client: Session,
    server: Session,
    client_events: Vec<SessionEvent>,
    server_events: Vec<SessionEvent>,
    /// Every frame on the wire, client to server and server to client.
    c2s: Vec<Apci>,
    s2c: Vec<Apci>,
}

impl Pair {
    fn new(client_cfg: ApciConfig, server_cfg: ApciConfig) -> Pair {
        let base = Instant::now();
        Pair {
            base,
            now: base,
            client: Session::new(client_cfg, Role::ControllingStation, base),
            server: Session::new(server_cfg, Role::ControlledStation, base),
            client_events: Vec::new(),
            server_events: Vec::new(),
            c2s: Vec::new(),
            s2c: Vec::new(),
        }
    }

    fn started(client_cfg: ApciConfig, server_cfg: ApciConfig) -> Pair {
        let mut pair = Pair::new(client_cfg, server_cfg);
        pair.client.start_data_transfer(pair.now).unwrap();
        pair.pump();
        assert_eq!(pair.client.state(), SessionState::Started);
        assert_eq!(pair.server.state(), SessionState::Started);
        pair.take_events();
        pair.c2s.clear();
        pair.s2c.clear();
        pair
    }

    /// Moves bytes both ways until neither side has anything to send.
    fn pump(&mut self) {
        let mut buf = Vec::new();
        loop {
            let mut moved = false;
            buf.clear();
            if self.client.poll_transmit(&mut buf) {
                self.c2s.extend(decode_all(&buf));
                self.server.handle_input(self.now, &buf);
                moved = true;
            }
            buf.clear();
            if self.server.poll_transmit(&mut buf) {
                self.s2c.extend(decode_all(&buf));
                self.client.handle_input(self.now, &buf);
                moved = true;
            }
            self.client_events.extend(events(&mut self.client));
            self.server_events.extend(events(&mut self.server));
            if !moved {
                break;
            }
        }
    }

    fn next_timeout(&self) -> Option<Instant> {
        [self.client.poll_timeout(), self.server.poll_timeout()]
            .into_iter()
            .flatten()
            .min()
    }

    /// Steps the clock to the next deadline of either side (if it is not after
    /// `limit`), handles it and pumps. Returns false when there is none.
    fn step_until(&mut self, limit: Instant) -> bool {
        match self.next_timeout() {
            Some(at) if at <= limit => {
                self.now = self.now.max(at);
                self.client.handle_timeout(self.now);
                self.server.handle_timeout(self.now);
                self.pump();
                true
            }
            _ => false,
        }
    }

    /// Advances the clock by `d`, handling every deadline on the way in order.
    fn advance(&mut self, d: Duration) {
        let limit = self.now + d;
        while self.step_until(limit) {}
        self.now = limit;
        self.client.handle_timeout(self.now);
        self.server.handle_timeout(self.now);
        self.pump();
    }

    fn elapsed(&self) -> Duration {
        self.now - self.base
    }

    fn take_events(&mut self) -> (Vec<SessionEvent>, Vec<SessionEvent>) {
        (
            std::mem::take(&mut self.client_events),
            std::mem::take(&mut self.server_events),
        )
    }
}

fn asdus(events: &[SessionEvent]) -> Vec<Vec<u8>> {
    events
        .iter()
        .filter_map(|e| match e {
            SessionEvent::Asdu(a) => Some(a.clone()),
            _ => None,
        })
        .collect()
}

// ---------------------------------------------------------------------------------------
// STARTDT / STOPDT
// ---------------------------------------------------------------------------------------

#[test]
fn startdt_handshake() {
    let mut pair = Pair::new(ApciConfig::default(), ApciConfig::default());
    assert_eq!(pair.client.state(), SessionState::Stopped);
    assert_eq!(pair.server.state(), SessionState::Stopped);
    assert_eq!(
        pair.server.send_asdu(pair.now, &[1]),
        Err(SendError::NotStarted)
    );
    assert!(!pair.server.can_send());

    pair.client.start_data_transfer(pair.now).unwrap();
    assert_eq!(pair.client.state(), SessionState::PendingStart);
    assert_eq!(
        pair.client.start_data_transfer(pair.now),
        Err(ControlError::InvalidState(SessionState::PendingStart))
    );
    assert_eq!(
        pair.client.send_asdu(pair.now, &[1]),
        Err(SendError::NotStarted)
    );
    pair.pump();

    assert_eq!(pair.c2s, vec![u(UFunction::StartDtAct)]);
    assert_eq!(pair.s2c, vec![u(UFunction::StartDtCon)]);
    assert_eq!(pair.client_events, vec![SessionEvent::Started]);
    assert_eq!(pair.server_events, vec![SessionEvent::Started]);
    assert!(pair.client.can_send());
    assert!(pair.server.can_send());

    // the server cannot start or stop data transfer
    assert_eq!(
        pair.server.start_data_transfer(pair.now),
        Err(ControlError::NotControllingStation)
    );
    assert_eq!(
        pair.server.stop_data_transfer(pair.now),
        Err(ControlError::NotControllingStation)
    );
}

#[test]
fn repeated_startdt_act_is_confirmed_without_a_second_event() {
    let t0 = Instant::now();
    let mut server = started_server(ApciConfig::default(), t0);
    server.handle_input(t0, &u_frame(UFunction::StartDtAct));
    assert_eq!(transmitted(&mut server), vec![u(UFunction::StartDtCon)]);
    assert_eq!(events(&mut server), vec![]);
    assert_eq!(server.state(), SessionState::Started);
}

#[test]
fn stopdt_without_outstanding_frames() {
    let mut pair = Pair::started(ApciConfig::default(), ApciConfig::default());
    pair.client.stop_data_transfer(pair.now).unwrap();
    assert_eq!(pair.client.state(), SessionState::PendingStop);
    assert_eq!(
        pair.client.send_asdu(pair.now, &[1]),
        Err(SendError::NotStarted)
    );
    pair.pump();
    assert_eq!(pair.c2s, vec![u(UFunction::StopDtAct)]);
    assert_eq!(pair.s2c, vec![u(UFunction::StopDtCon)]);
    assert_eq!(pair.client_events, vec![SessionEvent::Stopped]);
    assert_eq!(pair.server_events, vec![SessionEvent::Stopped]);
    assert_eq!(pair.client.state(), SessionState::Stopped);
    assert_eq!(pair.server.state(), SessionState::Stopped);

    // and started again on the same connection; sequence numbers continue
    pair.client.start_data_transfer(pair.now).unwrap();
    pair.pump();
    assert_eq!(pair.server.state(), SessionState::Started);
    assert_eq!(pair.client.state(), SessionState::Started);
}

/// IEC 60870-5-604 test 5.3.2.70: before STOPDT con the controlled station acknowledges
/// every received I frame with an S frame and waits for its own I frames to be
/// acknowledged.
#[test]
fn stopdt_with_outstanding_frames_raw_client() {
    let t0 = Instant::now();
    let mut server = started_server(ApciConfig::default(), t0);

    // the client sent three I frames, the server two
    for n in 0..3 {
        server.handle_input(t0, &i_frame(n, 0, &[0x64, n as u8]));
    }
    server.send_asdu(t0, b"a").unwrap();
    server.send_asdu(t0, b"b").unwrap();
    assert_eq!(transmitted(&mut server), vec![i(0, 3), i(1, 3)]);
    server.handle_input(t0, &i_frame(3, 0, &[0x64, 3]));
    events(&mut server);

    server.handle_input(t0, &u_frame(UFunction::StopDtAct));
    // S frame for everything received at once, no STOPDT con yet
    assert_eq!(transmitted(&mut server), vec![s(4)]);
    assert_eq!(server.state(), SessionState::PendingStop);
    assert_eq!(server.send_asdu(t0, b"c"), Err(SendError::NotStarted));
    assert!(!server.can_send());

    server.handle_input(t0 + SEC, &s_frame(1));
    assert_eq!(transmitted(&mut server), vec![]);
    assert_eq!(
        events(&mut server),
        vec![SessionEvent::Acknowledged { count: 1 }]
    );

    server.handle_input(t0 + 2 * SEC, &s_frame(2));
    assert_eq!(transmitted(&mut server), vec![u(UFunction::StopDtCon)]);
    assert_eq!(
        events(&mut server),
        vec![
            SessionEvent::Acknowledged { count: 1 },
            SessionEvent::Stopped
        ]
    );
    assert_eq!(server.state(), SessionState::Stopped);
}

#[test]
fn stopdt_pending_on_server_is_bounded_by_t1() {
    let t0 = Instant::now();
    let mut server = started_server(ApciConfig::default(), t0);
    server.send_asdu(t0, b"a").unwrap();
    transmitted(&mut server);
    server.handle_input(t0 + SEC, &u_frame(UFunction::StopDtAct));
    assert_eq!(transmitted(&mut server), vec![]);
    assert_eq!(server.poll_timeout(), Some(t0 + 15 * SEC));
    server.handle_timeout(t0 + 15 * SEC);
    assert_eq!(
        closed_reason(&server),
        Some(CloseReason::AcknowledgementTimeout {
            send_seq: SeqNum::ZERO
        })
    );
}

#[test]
fn i_frame_during_server_pending_stop_closes() {
    let t0 = Instant::now();
    let mut server = started_server(ApciConfig::default(), t0);
    server.send_asdu(t0, b"a").unwrap();
    server.handle_input(t0, &u_frame(UFunction::StopDtAct));
    server.handle_input(t0, &i_frame(0, 1, b"late"));
    assert_eq!(
        closed_reason(&server),
        Some(CloseReason::IFrameWhileStopped)
    );
}

#[test]
fn startdt_act_during_pending_stop_resumes() {
    let t0 = Instant::now();
    let mut server = started_server(ApciConfig::default(), t0);
    server.send_asdu(t0, b"a").unwrap();
    server.handle_input(t0, &u_frame(UFunction::StopDtAct));
    assert_eq!(server.state(), SessionState::PendingStop);
    transmitted(&mut server);
    server.handle_input(t0, &u_frame(UFunction::StartDtAct));
    assert_eq!(transmitted(&mut server), vec![u(UFunction::StartDtCon)]);
    assert_eq!(server.state(), SessionState::Started);
    assert_eq!(events(&mut server), vec![]);
    // acknowledging now does not produce a STOPDT con
    server.handle_input(t0, &s_frame(1));
    assert_eq!(transmitted(&mut server), vec![]);
}

#[test]
fn stopdt_pair_with_frames_in_flight() {
    let mut pair = Pair::started(ApciConfig::default(), ApciConfig::default());
    let sent: Vec<Vec<u8>> = (0..5).map(asdu).collect();
    for a in &sent {
        pair.server.send_asdu(pair.now, a).unwrap();
    }
    // the client sends a command too, then asks to stop before it has read anything
    pair.client.send_asdu(pair.now, b"cmd").unwrap();
    pair.client.stop_data_transfer(pair.now).unwrap();
    pair.pump();

    assert_eq!(asdus(&pair.client_events), sent);
    assert_eq!(asdus(&pair.server_events), vec![b"cmd".to_vec()]);
    assert_eq!(pair.client.state(), SessionState::Stopped);
    assert_eq!(pair.server.state(), SessionState::Stopped);
    assert!(pair.client_events.contains(&SessionEvent::Stopped));
    assert!(pair.server_events.contains(&SessionEvent::Stopped));
    // STOPDT con is the last thing the server sent, after the S frame for "cmd"
    assert_eq!(pair.s2c.last(), Some(&u(UFunction::StopDtCon)));
    assert!(pair.s2c.contains(&s(1)) || pair.s2c.iter().any(|f| *f == i(0, 1)));
    // no time was needed
    assert_eq!(pair.elapsed(), Duration::ZERO);
    assert_eq!(pair.client.unacknowledged_count(), 0);
    assert_eq!(pair.server.unacknowledged_count(), 0);
}

// ---------------------------------------------------------------------------------------
// t1
// ---------------------------------------------------------------------------------------

#[test]
fn t1_expires_when_i_frames_are_never_acknowledged() {
    let t0 = Instant::now();
    let mut server = started_server(ApciConfig::default(), t0);
    server.send_asdu(t0, b"x").unwrap();
    transmitted(&mut server);
    assert_eq!(server.poll_timeout(), Some(t0 + 15 * SEC));
    server.handle_timeout(t0 + 15 * SEC - MS);
    assert_eq!(server.state(), SessionState::Started);
    server.handle_timeout(t0 + 15 * SEC);
    let reason = CloseReason::AcknowledgementTimeout {
        send_seq: SeqNum::ZERO,
    };
    assert_eq!(closed_reason(&server), Some(reason.clone()));
    assert_eq!(
        events(&mut server),
        vec![SessionEvent::Closed(reason.clone())]
    );
    assert!(reason.to_string().contains("t1 expired"), "{reason}");
    assert_eq!(server.poll_timeout(), None);
    // the ASDU can still be taken for retransmission elsewhere
    assert_eq!(server.take_unacknowledged(), vec![b"x".to_vec()]);
}

#[test]
fn t1_follows_the_oldest_unacknowledged_frame() {
    let t0 = Instant::now();
    let mut server = started_server(ApciConfig::default(), t0);
    server.send_asdu(t0, b"a").unwrap();
    server.send_asdu(t0 + 5 * SEC, b"b").unwrap();
    transmitted(&mut server);
    assert_eq!(server.poll_timeout(), Some(t0 + 15 * SEC));
    // acknowledging "a" moves t1 to b's transmission + t1
    server.handle_input(t0 + 10 * SEC, &s_frame(1));
    assert_eq!(server.poll_timeout(), Some(t0 + 20 * SEC));
    // acknowledging "b" stops t1: only t3 (restarted by the S frame) remains
    server.handle_input(t0 + 12 * SEC, &s_frame(2));
    assert_eq!(server.poll_timeout(), Some(t0 + 32 * SEC));
    assert_eq!(server.state(), SessionState::Started);
}

#[test]
fn t1_expires_waiting_for_startdt_con() {
    let t0 = Instant::now();
    let mut client = Session::new(ApciConfig::default(), Role::ControllingStation, t0);
    client.start_data_transfer(t0).unwrap();
    assert_eq!(transmitted(&mut client), vec![u(UFunction::StartDtAct)]);
    assert_eq!(client.poll_timeout(), Some(t0 + 15 * SEC));
    client.handle_timeout(t0 + 15 * SEC);
    assert_eq!(
        closed_reason(&client),
        Some(CloseReason::ConfirmationTimeout(UFunction::StartDtAct))
    );
}

#[test]
fn t1_expires_waiting_for_stopdt_con() {
    let t0 = Instant::now();
    let mut client = started_client(ApciConfig::default(), t0);
    client.stop_data_transfer(t0 + SEC).unwrap();
    client.handle_timeout(t0 + 16 * SEC);
    assert_eq!(
        closed_reason(&client),
        Some(CloseReason::ConfirmationTimeout(UFunction::StopDtAct))
    );
}

#[test]
fn t1_expires_waiting_for_testfr_con_also_while_stopped() {
    for role in [Role::ControlledStation, Role::ControllingStation] {
        let t0 = Instant::now();
        let mut session = Session::new(ApciConfig::default(), role, t0);
        assert_eq!(session.poll_timeout(), Some(t0 + 20 * SEC));
        session.handle_timeout(t0 + 20 * SEC);
        assert_eq!(transmitted(&mut session), vec![u(UFunction::TestFrAct)]);
        assert_eq!(session.poll_timeout(), Some(t0 + 35 * SEC));
        session.handle_timeout(t0 + 35 * SEC);
        assert_eq!(
            closed_reason(&session),
            Some(CloseReason::ConfirmationTimeout(UFunction::TestFrAct)),
            "{role}"
        );
    }
}

#[test]
fn pair_closes_when_server_never_confirms_startdt() {
    // a "server" that is really a second client: it ignores STARTDT act as unexpected
    let mut pair = Pair::new(ApciConfig::default(), ApciConfig::default());
    pair.server = Session::new(ApciConfig::default(), Role::ControllingStation, pair.base);
    pair.client.start_data_transfer(pair.now).unwrap();
    pair.pump();
    pair.advance(15 * SEC);
    assert_eq!(
        closed_reason(&pair.client),
        Some(CloseReason::ConfirmationTimeout(UFunction::StartDtAct))
    );
}

// ---------------------------------------------------------------------------------------
// t2, w and piggy-backed acknowledgement
// ---------------------------------------------------------------------------------------

#[test]
fn t2_acknowledges_when_there_is_nothing_to_send() {
    let mut pair = Pair::started(ApciConfig::default(), ApciConfig::default());
    pair.server.send_asdu(pair.now, b"one").unwrap();
    pair.pump();
    assert_eq!(pair.s2c, vec![i(0, 0)]);
    assert_eq!(pair.c2s, vec![], "no acknowledgement before t2");
    pair.advance(10 * SEC - MS);
    assert_eq!(pair.c2s, vec![]);
    pair.advance(MS);
    assert_eq!(pair.c2s, vec![s(1)], "S frame exactly at t2");
    assert_eq!(pair.server.unacknowledged_count(), 0);
    assert_eq!(
        pair.server_events,
        vec![SessionEvent::Acknowledged { count: 1 }]
    );
}

#[test]
fn t2_runs_from_the_first_unacknowledged_frame() {
    let mut pair = Pair::started(ApciConfig::default(), ApciConfig::default());
    pair.server.send_asdu(pair.now, b"one").unwrap();
    pair.pump();
    pair.advance(4 * SEC);
    pair.server.send_asdu(pair.now, b"two").unwrap();
    pair.pump();
    pair.advance(6 * SEC);
    assert_eq!(pair.c2s, vec![s(2)]);
    assert_eq!(pair.elapsed(), 10 * SEC);
}

#[test]
fn sent_i_frame_carries_the_acknowledgement_and_cancels_t2() {
    let mut pair = Pair::started(ApciConfig::default(), ApciConfig::default());
    pair.server.send_asdu(pair.now, b"data").unwrap();
    pair.pump();
    pair.advance(5 * SEC);
    pair.client.send_asdu(pair.now, b"command").unwrap();
    pair.pump();
    assert_eq!(pair.c2s, vec![i(0, 1)]);
    assert_eq!(pair.server.unacknowledged_count(), 0);
    // the server acknowledges the command at its t2; the client sends no S frame at all
    pair.advance(20 * SEC);
    assert!(!pair.c2s.iter().any(|f| f.format() == FrameFormat::S));
    assert!(pair.s2c.contains(&s(1)));
}

#[test]
fn w_received_frames_are_acknowledged_at_once() {
    let mut pair = Pair::started(ApciConfig::default(), ApciConfig::default());
    for n in 0..7 {
        pair.server.send_asdu(pair.now, &asdu(n)).unwrap();
        pair.pump();
    }
    assert_eq!(pair.c2s, vec![], "7 < w: waiting for t2");
    pair.server.send_asdu(pair.now, &asdu(7)).unwrap();
    pair.pump();
    assert_eq!(pair.c2s, vec![s(8)], "w = 8 reached");
    assert_eq!(pair.elapsed(), Duration::ZERO);
}

#[test]
fn acknowledge_received_sends_an_s_frame_at_once() {
    let t0 = Instant::now();
    let mut client = started_client(ApciConfig::default(), t0);
    for n in 0..3u16 {
        client.handle_input(t0, &i_frame(n, 0, &[n as u8]));
    }
    assert_eq!(transmitted(&mut client), vec![], "3 < w: waiting for t2");
    assert_eq!(client.poll_timeout(), Some(t0 + 10 * SEC));
    client.acknowledge_received();
    assert_eq!(transmitted(&mut client), vec![s(3)]);
    assert_eq!(client.poll_timeout(), Some(t0 + 20 * SEC), "t2 stopped");
    client.acknowledge_received();
    assert_eq!(
        transmitted(&mut client),
        vec![],
        "nothing left to acknowledge"
    );
    client.handle_input(t0, &i_frame(3, 0, &[3]));
    client.close(CloseReason::LocalRequest);
    client.acknowledge_received();
    assert_eq!(transmitted(&mut client), vec![]);
}

#[test]
fn frames_read_together_get_one_acknowledgement() {
    let t0 = Instant::now();
    let mut client = started_client(ApciConfig::default(), t0);
    let mut bytes = Vec::new();
    for n in 0..20u16 {
        bytes.extend(i_frame(n, 0, &[n as u8]));
    }
    client.handle_input(t0, &bytes);
    assert_eq!(transmitted(&mut client), vec![s(20)]);
    assert_eq!(asdus(&events(&mut client)).len(), 20);
}

#[test]
fn peer_acknowledging_only_at_w_never_stalls_the_sender() {
    // k = 12, w = 8 on both sides: the receiver only acknowledges every 8th frame, and
    // the sender must never have to wait for t2.
    let mut pair = Pair::started(ApciConfig::default(), ApciConfig::default());
    let total = 5_000u32;
    let mut next = 0u32;
    let mut stalls = 0;
    while next < total {
        while next < total && pair.server.can_send() {
            pair.server.send_asdu(pair.now, &asdu(next)).unwrap();
            next += 1;
        }
        if !pair.server.can_send() {
            stalls += 1;
            assert_eq!(
                pair.server.send_asdu(pair.now, &[1]),
                Err(SendError::WindowFull)
            );
        }
        pair.pump();
    }
    assert!(stalls > 0, "the window filled up");
    assert_eq!(pair.elapsed(), Duration::ZERO, "no waiting for t2");
    let got = asdus(&pair.client_events);
    assert_eq!(got.len(), total as usize);
    assert!(got.iter().enumerate().all(|(n, a)| *a == asdu(n as u32)));
    // the client only sent acknowledgements, none of them forced by t2
    assert!(pair.c2s.iter().all(|f| f.format() == FrameFormat::S));
}

#[test]
fn raw_peer_acknowledging_exactly_every_w_frames_never_stalls() {
    // The receiver acknowledges after exactly 8 frames, never earlier, never by t2:
    // with k = 12 the sender must keep going without any time passing.
    let t0 = Instant::now();
    let mut server = started_server(ApciConfig::default(), t0);
    let mut next = 0u32;
    let mut received = 0u32;
    while next < 2_000 {
        let before = next;
        while server.can_send() {
            server.send_asdu(t0, &asdu(next)).unwrap();
            next += 1;
        }
        assert!(next > before, "stalled at {next} with {received} received");
        for frame in transmitted(&mut server) {
            assert_eq!(frame, i((received % 32768) as u16, 0));
            received += 1;
            if received % 8 == 0 {
                server.handle_input(t0, &s_frame((received % 32768) as u16));
            }
        }
    }
    assert_eq!(server.state(), SessionState::Started);
}

// ---------------------------------------------------------------------------------------
// k window
// ---------------------------------------------------------------------------------------

#[test]
fn k_window_stalls_and_resumes_after_an_s_frame() {
    let t0 = Instant::now();
    let mut server = started_server(ApciConfig::default(), t0);
    for n in 0..12 {
        assert!(server.can_send());
        server.send_asdu(t0, &asdu(n)).unwrap();
    }
    assert!(!server.can_send());
    assert_eq!(server.send_asdu(t0, b"13th"), Err(SendError::WindowFull));
    assert_eq!(server.unacknowledged_count(), 12);
    assert_eq!(transmitted(&mut server).len(), 12);

    server.handle_input(t0 + SEC, &s_frame(5));
    assert_eq!(
        events(&mut server),
        vec![SessionEvent::Acknowledged { count: 5 }]
    );
    assert_eq!(server.unacknowledged_count(), 7);
    for n in 12..17 {
        server.send_asdu(t0 + SEC, &asdu(n)).unwrap();
    }
    assert_eq!(server.send_asdu(t0 + SEC, b"x"), Err(SendError::WindowFull));
    let frames = transmitted(&mut server);
    assert_eq!(frames.first(), Some(&i(12, 0)));
    assert_eq!(frames.last(), Some(&i(16, 0)));
}

#[test]
fn k_of_one_is_stop_and_wait() {
    let mut pair = Pair::started(config(1, 1), config(1, 1));
    for n in 0..50 {
        pair.server.send_asdu(pair.now, &asdu(n)).unwrap();
        assert_eq!(
            pair.server.send_asdu(pair.now, b"x"),
            Err(SendError::WindowFull)
        );
        pair.pump();
    }
    assert_eq!(asdus(&pair.client_events).len(), 50);
}

#[test]
fn invalid_window_configuration_is_clamped() {
    let t0 = Instant::now();
    let mut session = Session::new(config(0, 0), Role::ControlledStation, t0);
    assert_eq!((session.config().k, session.config().w), (1, 1));
    let session2 = Session::new(config(40_000, 50_000), Role::ControlledStation, t0);
    assert_eq!((session2.config().k, session2.config().w), (32767, 32767));
    session.handle_input(t0, &u_frame(UFunction::StartDtAct));
    session.send_asdu(t0, b"a").unwrap();
    assert_eq!(session.send_asdu(t0, b"b"), Err(SendError::WindowFull));
}

// ---------------------------------------------------------------------------------------
// Sequence numbers
// ---------------------------------------------------------------------------------------

#[test]
fn sequence_numbers_wrap_around_32767() {
    let mut pair = Pair::started(ApciConfig::default(), ApciConfig::default());
    let server_total = 40_000u32;
    let client_total = 33_500u32;
    let (mut sn, mut cn) = (0u32, 0u32);
    while sn < server_total || cn < client_total {
        while sn < server_total && pair.server.can_send() {
            pair.server.send_asdu(pair.now, &asdu(sn)).unwrap();
            sn += 1;
        }
        while cn < client_total && pair.client.can_send() {
            pair.client.send_asdu(pair.now, &asdu(cn)).unwrap();
            cn += 1;
        }
        pair.pump();
        // keep the wire logs small
        pair.c2s.clear();
        pair.s2c.clear();
    }
    pair.advance(10 * SEC);
    let got_client = asdus(&pair.client_events);
    let got_server = asdus(&pair.server_events);
    assert_eq!(got_client.len(), server_total as usize);
    assert_eq!(got_server.len(), client_total as usize);
    assert!(got_client
        .iter()
        .enumerate()
        .all(|(n, a)| *a == asdu(n as u32)));
    assert!(got_server
        .iter()
        .enumerate()
        .all(|(n, a)| *a == asdu(n as u32)));
    assert_eq!(
        pair.server.send_seq(),
        SeqNum::new((server_total % 32768) as u16)
    );
    assert_eq!(
        pair.client.recv_seq(),
        SeqNum::new((server_total % 32768) as u16)
    );
    assert_eq!(
        pair.client.send_seq(),
        SeqNum::new((client_total % 32768) as u16)
    );
    assert_eq!(pair.server.unacknowledged_count(), 0);
    assert_eq!(pair.client.unacknowledged_count(), 0);
    assert_eq!(pair.client.state(), SessionState::Started);
    assert_eq!(pair.server.state(), SessionState::Started);
}

/// Drives a raw client against a server until the server's V(S) is `target`, acking
/// everything. Returns the server.
fn server_at_send_seq(target: u32, t0: Instant) -> Session {
    let mut cfg = ApciConfig::default();
    cfg.k = 100;
    cfg.w = 50;
    let mut server = started_server(cfg, t0);
    let mut sent = 0u32;
    while sent < target {
        let batch = (target - sent).min(100);
        for _ in 0..batch {
            server.send_asdu(t0, &[1]).unwrap();
        }
        sent += batch;
        server.handle_input(t0, &s_frame((sent % 32768) as u16));
    }
    transmitted(&mut server);
    events(&mut server);
    server
}

#[test]
fn acknowledgement_window_is_checked_across_the_wrap() {
    let t0 = Instant::now();
    // V(S) = 32766; send 4 frames: 32766, 32767, 0, 1 -> V(S) = 2
    let mut server = server_at_send_seq(32766, t0);
    assert_eq!(server.send_seq(), SeqNum::new(32766));
    for _ in 0..4 {
        server.send_asdu(t0, &[2]).unwrap();
    }
    assert_eq!(server.send_seq(), SeqNum::new(2));
    transmitted(&mut server);
    // N(R) = 0 acknowledges 32766 and 32767
    server.handle_input(t0, &s_frame(0));
    assert_eq!(
        events(&mut server),
        vec![SessionEvent::Acknowledged { count: 2 }]
    );
    assert_eq!(server.unacknowledged_count(), 2);
    // N(R) = 0 again is fine (acknowledges nothing new)
    server.handle_input(t0, &s_frame(0));
    assert_eq!(events(&mut server), vec![]);
    // N(R) = 2 = V(S) acknowledges all
    server.handle_input(t0, &s_frame(2));
    assert_eq!(
        events(&mut server),
        vec![SessionEvent::Acknowledged { count: 2 }]
    );
    assert_eq!(server.state(), SessionState::Started);

    // now N(R) = 32767 lies behind the window: close
    server.handle_input(t0, &s_frame(32767));
    assert_eq!(
        closed_reason(&server),
        Some(CloseReason::BadAcknowledgement {
            received: SeqNum::new(32767),
            oldest_unacknowledged: SeqNum::new(2),
            next_send: SeqNum::new(2),
        })
    );
}

#[test]
fn acknowledgement_beyond_v_s_across_the_wrap_closes() {
    let t0 = Instant::now();
    let mut server = server_at_send_seq(32767, t0);
    server.send_asdu(t0, &[1]).unwrap(); // N(S) 32767, V(S) = 0
    server.handle_input(t0, &s_frame(1)); // one beyond V(S)
    assert_eq!(
        closed_reason(&server),
        Some(CloseReason::BadAcknowledgement {
            received: SeqNum::new(1),
            oldest_unacknowledged: SeqNum::new(32767),
            next_send: SeqNum::new(0),
        })
    );
}

#[test]
fn bad_n_r_closes() {
    let t0 = Instant::now();
    let mut server = started_server(ApciConfig::default(), t0);
    for n in 0..3 {
        server.send_asdu(t0, &asdu(n)).unwrap();
    }
    server.handle_input(t0, &s_frame(5));
    let reason = closed_reason(&server).unwrap();
    assert_eq!(
        reason,
        CloseReason::BadAcknowledgement {
            received: SeqNum::new(5),
            oldest_unacknowledged: SeqNum::new(0),
            next_send: SeqNum::new(3),
        }
    );
    assert!(reason.to_string().contains("N(R) = 5"), "{reason}");
    assert!(transmitted(&mut server).is_empty(), "queued bytes dropped");

    // going backwards closes too
    let mut server = started_server(ApciConfig::default(), t0);
    for n in 0..3 {
        server.send_asdu(t0, &asdu(n)).unwrap();
    }
    server.handle_input(t0, &s_frame(2));
    server.handle_input(t0, &s_frame(1));
    assert!(matches!(
        closed_reason(&server),
        Some(CloseReason::BadAcknowledgement { .. })
    ));

    // and in an I frame
    let mut server = started_server(ApciConfig::default(), t0);
    server.handle_input(t0, &i_frame(0, 1, b"x"));
    assert!(matches!(
        closed_reason(&server),
        Some(CloseReason::BadAcknowledgement { .. })
    ));
}

#[test]
fn n_s_mismatch_closes() {
    let t0 = Instant::now();
    // a peer that starts counting at 1
    let mut server = started_server(ApciConfig::default(), t0);
    server.handle_input(t0, &i_frame(1, 0, b"x"));
    assert_eq!(
        closed_reason(&server),
        Some(CloseReason::SequenceMismatch {
            expected: SeqNum::new(0),
            received: SeqNum::new(1),
        })
    );
    // a gap later on
    let mut client = started_client(ApciConfig::default(), t0);
    client.handle_input(t0, &i_frame(0, 0, b"a"));
    client.handle_input(t0, &i_frame(1, 0, b"b"));
    client.handle_input(t0, &i_frame(3, 0, b"d"));
    assert_eq!(
        closed_reason(&client),
        Some(CloseReason::SequenceMismatch {
            expected: SeqNum::new(2),
            received: SeqNum::new(3),
        })
    );
    let evs = events(&mut client);
    assert_eq!(asdus(&evs), vec![b"a".to_vec(), b"b".to_vec()]);
    assert!(matches!(evs.last(), Some(SessionEvent::Closed(_))));
    // a repeated frame
    let mut client = started_client(ApciConfig::default(), t0);
    client.handle_input(t0, &i_frame(0, 0, b"a"));
    client.handle_input(t0, &i_frame(0, 0, b"a"));
    assert!(matches!(
        closed_reason(&client),
        Some(CloseReason::SequenceMismatch { .. })
    ));
}

// ---------------------------------------------------------------------------------------
// Frames in the wrong state
// ---------------------------------------------------------------------------------------

#[test]
fn i_frame_while_stopped_closes() {
    let t0 = Instant::now();
    let mut server = Session::new(ApciConfig::default(), Role::ControlledStation, t0);
    server.handle_input(t0, &i_frame(0, 0, b"early"));
    assert_eq!(
        closed_reason(&server),
        Some(CloseReason::IFrameWhileStopped)
    );
    assert_eq!(
        events(&mut server),
        vec![SessionEvent::Closed(CloseReason::IFrameWhileStopped)]
    );

    // client: data before STARTDT con
    let mut client = Session::new(ApciConfig::default(), Role::ControllingStation, t0);
    client.start_data_transfer(t0).unwrap();
    client.handle_input(t0, &i_frame(0, 0, b"early"));
    assert_eq!(
        closed_reason(&client),
        Some(CloseReason::IFrameWhileStopped)
    );

    // after a completed STOPDT
    let mut client = started_client(ApciConfig::default(), t0);
    client.stop_data_transfer(t0).unwrap();
    client.handle_input(t0, &u_frame(UFunction::StopDtCon));
    assert_eq!(client.state(), SessionState::Stopped);
    client.handle_input(t0, &i_frame(0, 0, b"late"));
    assert_eq!(
        closed_reason(&client),
        Some(CloseReason::IFrameWhileStopped)
    );
}

#[test]
fn client_accepts_i_frames_while_its_stopdt_is_pending() {
    let t0 = Instant::now();
    let mut client = started_client(ApciConfig::default(), t0);
    client.stop_data_transfer(t0).unwrap();
    transmitted(&mut client);
    client.handle_input(t0, &i_frame(0, 0, b"in flight"));
    // acknowledged at once so the server can confirm the stop
    assert_eq!(transmitted(&mut client), vec![s(1)]);
    client.handle_input(t0, &u_frame(UFunction::StopDtCon));
    assert_eq!(
        events(&mut client),
        vec![
            SessionEvent::Asdu(b"in flight".to_vec()),
            SessionEvent::Stopped
        ]
    );
}

#[test]
fn s_frame_while_stopped_with_nothing_outstanding_closes() {
    let t0 = Instant::now();
    let mut server = Session::new(ApciConfig::default(), Role::ControlledStation, t0);
    server.handle_input(t0, &s_frame(0));
    assert_eq!(
        closed_reason(&server),
        Some(CloseReason::SFrameWhileStopped)
    );

    let mut client = Session::new(ApciConfig::default(), Role::ControllingStation, t0);
    client.handle_input(t0, &s_frame(0));
    assert_eq!(
        closed_reason(&client),
        Some(CloseReason::SFrameWhileStopped)
    );
}

// ---------------------------------------------------------------------------------------
// Redundancy: deactivate and take_unacknowledged
// ---------------------------------------------------------------------------------------

#[test]
fn deactivate_stops_silently_and_hands_over_unacknowledged_asdus() {
    let t0 = Instant::now();
    let mut server = started_server(ApciConfig::default(), t0);
    for n in 0..4 {
        server.send_asdu(t0, &asdu(n)).unwrap();
    }
    transmitted(&mut server);
    server.handle_input(t0, &s_frame(1));
    events(&mut server);

    server.deactivate();
    assert_eq!(server.state(), SessionState::Stopped);
    assert_eq!(transmitted(&mut server), vec![], "no unsolicited STOPDT");
    assert_eq!(events(&mut server), vec![]);
    assert_eq!(server.send_asdu(t0, b"x"), Err(SendError::NotStarted));

    let taken = server.take_unacknowledged();
    assert_eq!(taken, vec![asdu(1), asdu(2), asdu(3)]);
    assert!(server.take_unacknowledged().is_empty());
    assert_eq!(
        server.unacknowledged_count(),
        3,
        "the window still counts them"
    );
    assert_eq!(
        server.poll_timeout(),
        Some(t0 + 20 * SEC),
        "no t1 for taken frames"
    );

    // a late acknowledgement of the taken frames is accepted while stopped
    server.handle_input(t0, &s_frame(4));
    assert_eq!(server.state(), SessionState::Stopped);
    assert_eq!(
        events(&mut server),
        vec![SessionEvent::Acknowledged { count: 3 }]
    );

    // the client selects this connection again
    server.handle_input(t0, &u_frame(UFunction::StartDtAct));
    assert_eq!(transmitted(&mut server), vec![u(UFunction::StartDtCon)]);
    assert_eq!(events(&mut server), vec![SessionEvent::Started]);
    server.send_asdu(t0, b"more").unwrap();
    assert_eq!(transmitted(&mut server), vec![i(4, 0)]);
}

#[test]
fn redundancy_switch_over_retransmits_in_order() {
    // Two connections of one group; the client starts the second one.
    let mut first = Pair::started(ApciConfig::default(), ApciConfig::default());
    for n in 0..10 {
        first.server.send_asdu(first.now, &asdu(n)).unwrap();
    }
    // only part of it reached the client and got acknowledged before the link died
    let mut bytes = Vec::new();
    first.server.poll_transmit(&mut bytes);
    let frames_len: usize = (0..8).map(|n| 6 + asdu(n).len()).sum();
    first.client.handle_input(first.now, &bytes[..frames_len]);
    let mut ack = Vec::new();
    first.client.poll_transmit(&mut ack);
    first.server.handle_input(first.now, &ack);
    assert_eq!(first.server.unacknowledged_count(), 2);

    let mut second = Pair::started(ApciConfig::default(), ApciConfig::default());
    first.server.deactivate();
    for a in first.server.take_unacknowledged() {
        second.server.send_asdu(second.now, &a).unwrap();
    }
    second.pump();
    assert_eq!(asdus(&second.client_events), vec![asdu(8), asdu(9)]);
}

#[test]
fn i_frame_on_a_deactivated_connection_closes_it() {
    let t0 = Instant::now();
    let mut server = started_server(ApciConfig::default(), t0);
    server.handle_input(t0, &i_frame(0, 0, b"a"));
    server.deactivate();
    server.handle_input(t0, &i_frame(1, 0, b"b"));
    assert_eq!(
        closed_reason(&server),
        Some(CloseReason::IFrameWhileStopped)
    );
}

#[test]
fn deactivate_is_ignored_on_a_client_and_during_pending_stop() {
    let t0 = Instant::now();
    let mut client = started_client(ApciConfig::default(), t0);
    client.deactivate();
    assert_eq!(client.state(), SessionState::Started);

    let mut server = started_server(ApciConfig::default(), t0);
    server.send_asdu(t0, b"a").unwrap();
    server.handle_input(t0, &u_frame(UFunction::StopDtAct));
    server.deactivate();
    assert_eq!(server.state(), SessionState::PendingStop);
    transmitted(&mut server);
    server.handle_input(t0, &s_frame(1));
    assert_eq!(transmitted(&mut server), vec![u(UFunction::StopDtCon)]);
}

// ---------------------------------------------------------------------------------------
// U frames of the wrong role, TESTFR
// ---------------------------------------------------------------------------------------

#[test]
fn testfr_act_is_answered_in_every_state() {
    let t0 = Instant::now();
    for role in [Role::ControlledStation, Role::ControllingStation] {
        let mut session = Session::new(ApciConfig::default(), role, t0);
        session.handle_input(t0, &u_frame(UFunction::TestFrAct));
        assert_eq!(transmitted(&mut session), vec![u(UFunction::TestFrCon)]);
    }
    let mut server = started_server(ApciConfig::default(), t0);
    server.handle_input(t0, &u_frame(UFunction::TestFrAct));
    assert_eq!(transmitted(&mut server), vec![u(UFunction::TestFrCon)]);
    let stats = server.stats();
    assert_eq!(stats.test_frames_received, 1);
    assert_eq!(stats.test_frames_sent, 1);
}

#[test]
fn wrong_role_u_frames_are_ignored_then_capped() {
    let t0 = Instant::now();
    // controlled station receiving confirmations it never asked for
    let mut server = Session::new(ApciConfig::default(), Role::ControlledStation, t0);
    for function in [
        UFunction::StartDtCon,
        UFunction::StopDtCon,
        UFunction::TestFrCon,
    ] {
        server.handle_input(t0, &u_frame(function));
        assert_eq!(server.state(), SessionState::Stopped);
        assert_eq!(transmitted(&mut server), vec![]);
    }
    assert_eq!(server.stats().unexpected_frames_received, 3);

    // controlling station receiving activations
    let mut client = started_client(ApciConfig::default(), t0);
    for function in [
        UFunction::StartDtAct,
        UFunction::StopDtAct,
        UFunction::StartDtCon,
        UFunction::StopDtCon,
    ] {
        client.handle_input(t0, &u_frame(function));
        assert_eq!(client.state(), SessionState::Started, "{function}");
        assert_eq!(transmitted(&mut client), vec![]);
    }
    // 4 so far; the default cap tolerates 8
    for _ in 0..4 {
        client.handle_input(t0, &u_frame(UFunction::StartDtAct));
    }
    assert_eq!(client.state(), SessionState::Started);
    client.handle_input(t0, &u_frame(UFunction::StartDtAct));
    assert_eq!(
        closed_reason(&client),
        Some(CloseReason::TooManyUnexpectedFrames {
            count: 9,
            last: UFunction::StartDtAct
        })
    );
}

#[test]
fn unexpected_u_frames_close_at_once_with_a_cap_of_zero() {
    let t0 = Instant::now();
    let mut cfg = ApciConfig::default();
    cfg.max_unexpected_frames = 0;
    let mut server = Session::new(cfg, Role::ControlledStation, t0);
    server.handle_input(t0, &u_frame(UFunction::StartDtCon));
    assert_eq!(
        closed_reason(&server),
        Some(CloseReason::TooManyUnexpectedFrames {
            count: 1,
            last: UFunction::StartDtCon
        })
    );
}

#[test]
fn t3_sends_testfr_when_idle_and_any_frame_restarts_it() {
    let t0 = Instant::now();
    let mut server = started_server(ApciConfig::default(), t0);
    assert_eq!(server.poll_timeout(), Some(t0 + 20 * SEC));
    server.handle_input(t0 + 10 * SEC, &u_frame(UFunction::TestFrAct));
    transmitted(&mut server);
    assert_eq!(server.poll_timeout(), Some(t0 + 30 * SEC));
    server.handle_timeout(t0 + 30 * SEC);
    assert_eq!(transmitted(&mut server), vec![u(UFunction::TestFrAct)]);
    // t3 is disarmed while the TESTFR act is pending: only t1 remains
    assert_eq!(server.poll_timeout(), Some(t0 + 45 * SEC));
    server.handle_input(t0 + 31 * SEC, &u_frame(UFunction::TestFrCon));
    assert_eq!(server.poll_timeout(), Some(t0 + 51 * SEC));
    assert_eq!(server.state(), SessionState::Started);
}

#[test]
fn idle_pair_keeps_alive_with_test_frames() {
    let mut pair = Pair::started(ApciConfig::default(), ApciConfig::default());
    pair.advance(3600 * SEC);
    assert_eq!(pair.client.state(), SessionState::Started);
    assert_eq!(pair.server.state(), SessionState::Started);
    let acts = pair
        .c2s
        .iter()
        .chain(&pair.s2c)
        .filter(|f| **f == u(UFunction::TestFrAct))
        .count();
    let cons = pair
        .c2s
        .iter()
        .chain(&pair.s2c)
        .filter(|f| **f == u(UFunction::TestFrCon))
        .count();
    assert!(acts >= 3600 / 20, "{acts}");
    assert_eq!(acts, cons);
    assert!(pair
        .c2s
        .iter()
        .chain(&pair.s2c)
        .all(|f| f.format() == FrameFormat::U));
}

// ---------------------------------------------------------------------------------------
// Malformed input
// ---------------------------------------------------------------------------------------

#[test]
fn malformed_streams_close_with_the_reason() {
    let t0 = Instant::now();
    let cases: Vec<(&str, Vec<u8>, FrameError)> = vec![
        (
            "bad start",
            vec![0x67, 0x04, 0x07, 0, 0, 0],
            FrameError::InvalidStartByte(0x67),
        ),
        (
            "length 3",
            vec![0x68, 0x03, 0x07, 0, 0],
            FrameError::LengthTooShort(3),
        ),
        ("length 0", vec![0x68, 0x00], FrameError::LengthTooShort(0)),
        (
            "length 254",
            vec![0x68, 0xFE],
            FrameError::LengthTooLong(0xFE),
        ),
        (
            "length 255",
            vec![0x68, 0xFF],
            FrameError::LengthTooLong(0xFF),
        ),
        (
            "empty I",
            vec![0x68, 0x04, 0x00, 0, 0, 0],
            FrameError::EmptyIFrame,
        ),
        (
            "S with ASDU",
            vec![0x68, 0x05, 0x01, 0, 0, 0, 0x01],
            FrameError::UnexpectedAsdu {
                format: FrameFormat::S,
                len: 1,
            },
        ),
        (
            "U with ASDU",
            vec![0x68, 0x05, 0x07, 0, 0, 0, 0x01],
            FrameError::UnexpectedAsdu {
                format: FrameFormat::U,
                len: 1,
            },
        ),
        (
            "U two functions",
            vec![0x68, 0x04, 0x0F, 0, 0, 0],
            FrameError::InvalidUFunction(0x0F),
        ),
        (
            "U no function",
            vec![0x68, 0x04, 0x03, 0, 0, 0],
            FrameError::InvalidUFunction(0x03),
        ),
        (
            "U nonzero octet",
            vec![0x68, 0x04, 0x43, 0, 0, 1],
            FrameError::ReservedBitsSet([0x43, 0, 0, 1]),
        ),
        (
            "S octet 2",
            vec![0x68, 0x04, 0x01, 0x01, 0, 0],
            FrameError::ReservedBitsSet([0x01, 0x01, 0, 0]),
        ),
        (
            "valid then garbage",
            [
                u_frame(UFunction::TestFrAct),
                u_frame(UFunction::TestFrAct),
                vec![0x00],
            ]
            .concat(),
            FrameError::InvalidStartByte(0x00),
        ),
    ];
    for (name, bytes, error) in cases {
        for role in [Role::ControlledStation, Role::ControllingStation] {
            // whole, and byte by byte
            for split in [bytes.len(), 1] {
                let mut session = Session::new(ApciConfig::default(), role, t0);
                for chunk in bytes.chunks(split) {
                    session.handle_input(t0, chunk);
                }
                let reason = CloseReason::Frame(error);
                assert_eq!(closed_reason(&session), Some(reason.clone()), "{name}");
                let evs = events(&mut session);
                assert_eq!(
                    evs.last(),
                    Some(&SessionEvent::Closed(reason.clone())),
                    "{name}"
                );
                assert_eq!(
                    evs.iter()
                        .filter(|e| matches!(e, SessionEvent::Closed(_)))
                        .count(),
                    1
                );
                assert!(reason.to_string().starts_with("malformed APDU"), "{reason}");
                // dead: input, timeouts and sends are ignored
                session.handle_input(t0, &u_frame(UFunction::TestFrAct));
                session.handle_timeout(t0 + 3600 * SEC);
                assert_eq!(transmitted(&mut session), vec![]);
                assert_eq!(session.send_asdu(t0, b"x"), Err(SendError::Closed));
                assert_eq!(session.poll_timeout(), None);
                assert_eq!(events(&mut session), vec![]);
            }
        }
    }
}

#[test]
fn valid_frames_before_garbage_are_processed() {
    let t0 = Instant::now();
    let mut client = started_client(ApciConfig::default(), t0);
    let bytes = [
        i_frame(0, 0, b"a"),
        i_frame(1, 0, b"b"),
        vec![0x68, 0x04, 0x00, 0x00], // truncated I frame...
        vec![0x00, 0x00, 0xFF],       // ...that turns out to be empty, then garbage
    ]
    .concat();
    client.handle_input(t0, &bytes);
    let evs = events(&mut client);
    assert_eq!(asdus(&evs), vec![b"a".to_vec(), b"b".to_vec()]);
    assert_eq!(
        evs.last(),
        Some(&SessionEvent::Closed(CloseReason::Frame(
            FrameError::EmptyIFrame
        )))
    );
}

#[test]
fn truncated_stream_waits_without_closing() {
    let t0 = Instant::now();
    let mut client = started_client(ApciConfig::default(), t0);
    let frame = i_frame(0, 0, &[7; 200]);
    client.handle_input(t0, &frame[..150]);
    assert_eq!(client.state(), SessionState::Started);
    assert_eq!(events(&mut client), vec![]);
    client.handle_input(t0, &frame[150..]);
    assert_eq!(asdus(&events(&mut client)), vec![vec![7; 200]]);
}

#[test]
fn large_reads_are_processed_completely() {
    // more bytes in one call than the deframer buffers at once
    let t0 = Instant::now();
    let mut cfg = ApciConfig::default();
    cfg.w = 8;
    let mut client = started_client(cfg, t0);
    let mut bytes = Vec::new();
    for n in 0..1000u16 {
        bytes.extend(i_frame(n, 0, &[n as u8; 100]));
    }
    client.handle_input(t0, &bytes);
    assert_eq!(asdus(&events(&mut client)).len(), 1000);
    assert_eq!(client.stats().bytes_received, 6 + bytes.len() as u64);
}

#[test]
fn send_asdu_limits() {
    let t0 = Instant::now();
    let mut server = started_server(ApciConfig::default(), t0);
    assert_eq!(server.send_asdu(t0, &[]), Err(SendError::Empty));
    assert_eq!(
        server.send_asdu(t0, &[0; 250]),
        Err(SendError::TooLong(250))
    );
    assert_eq!(
        server.send_asdu(t0, &[0; 100_000]),
        Err(SendError::TooLong(100_000))
    );
    server.send_asdu(t0, &[0; 249]).unwrap();
    assert_eq!(server.unacknowledged_count(), 1);
}

#[test]
fn local_close_emits_one_event_and_keeps_unacknowledged() {
    let t0 = Instant::now();
    let mut server = started_server(ApciConfig::default(), t0);
    server.send_asdu(t0, b"a").unwrap();
    server.close(CloseReason::PeerClosed);
    server.close(CloseReason::LocalRequest);
    assert_eq!(
        events(&mut server),
        vec![SessionEvent::Closed(CloseReason::PeerClosed)]
    );
    assert_eq!(transmitted(&mut server), vec![]);
    assert_eq!(server.take_unacknowledged(), vec![b"a".to_vec()]);
    assert!(!server.can_send());
    assert_eq!(
        CloseReason::Io(std::io::ErrorKind::ConnectionReset).to_string(),
        "transport error: connection reset"
    );
}

#[test]
fn clock_going_backwards_and_huge_timers_do_not_panic() {
    let t0 = Instant::now();
    let mut cfg = ApciConfig::default();
    cfg.t1 = Duration::MAX;
    cfg.t2 = Duration::MAX;
    cfg.t3 = Duration::MAX;
    let mut server = started_server(cfg, t0);
    server.send_asdu(t0, b"a").unwrap();
    server.handle_input(t0, &i_frame(0, 0, b"b"));
    assert_eq!(
        server.poll_timeout(),
        None,
        "all deadlines beyond the end of time"
    );
    server.handle_timeout(t0);
    // an earlier `now` than before
    let mut server = started_server(ApciConfig::default(), t0 + 100 * SEC);
    server.send_asdu(t0 + 100 * SEC, b"a").unwrap();
    server.handle_timeout(t0);
    server.handle_input(t0, &s_frame(1));
    assert_eq!(server.state(), SessionState::Started);
}

#[test]
fn stats_count_frames_and_bytes() {
    let mut pair = Pair::started(ApciConfig::default(), ApciConfig::default());
    for n in 0..8 {
        pair.server.send_asdu(pair.now, &asdu(n)).unwrap();
    }
    pair.pump();
    let server = pair.server.stats();
    let client = pair.client.stats();
    assert_eq!(server.i_frames_sent, 8);
    assert_eq!(client.i_frames_received, 8);
    assert_eq!(client.s_frames_sent, 1);
    assert_eq!(server.s_frames_received, 1);
    assert_eq!(server.u_frames_received, 1); // STARTDT act
    assert_eq!(server.u_frames_sent, 1); // STARTDT con
    assert_eq!(server.frames_sent, 9);
    assert_eq!(client.frames_received, 9);
    assert_eq!(server.bytes_sent, client.bytes_received);
    assert_eq!(client.bytes_sent, server.bytes_received);
    let payload: u64 = (0..8).map(|n| 6 + asdu(n).len() as u64).sum();
    assert_eq!(server.bytes_sent, 6 + payload);
}

// ---------------------------------------------------------------------------------------
// Random interleavings (proptest) and random byte streams
// ---------------------------------------------------------------------------------------

mod random {
    use super::*;
    use proptest::prelude::*;

    #[derive(Debug, Clone)]
    enum Op {
        ClientSend,
        ServerSend,
        /// Deliver up to n bytes client -> server.
        DeliverC2S(usize),
        /// Deliver up to n bytes server -> client.
        DeliverS2C(usize),
        /// Advance the clock by n milliseconds.
        Advance(u64),
    }

    fn op() -> impl Strategy<Value = Op> {
        prop_oneof![
            3 => Just(Op::ClientSend),
            5 => Just(Op::ServerSend),
            4 => (1usize..600).prop_map(Op::DeliverC2S),
            4 => (1usize..600).prop_map(Op::DeliverS2C),
            2 => (0u64..4000).prop_map(Op::Advance),
        ]
    }

    struct Side {
        session: Session,
        wire_out: Vec<u8>,
        sent: Vec<Vec<u8>>,
        received: Vec<Vec<u8>>,
        k: usize,
    }

    impl Side {
        fn collect(&mut self) {
            let mut buf = Vec::new();
            while self.session.poll_transmit(&mut buf) {}
            self.wire_out.extend(buf);
            while let Some(event) = self.session.poll_event() {
                if let SessionEvent::Asdu(a) = event {
                    self.received.push(a);
                }
            }
        }

        fn send(&mut self, now: Instant, counter: &mut u32) {
            let payload = asdu(*counter);
            let can = self.session.can_send();
            match self.session.send_asdu(now, &payload) {
                Ok(()) => {
                    assert!(can);
                    *counter += 1;
                    self.sent.push(payload);
                }
                Err(SendError::WindowFull) => {
                    assert!(!can);
                    assert_eq!(self.session.unacknowledged_count(), self.k);
                }
                Err(e) => panic!("unexpected {e:?}"),
            }
        }
    }

    fn deliver(from: &mut Side, to: &mut Side, n: usize, now: Instant) {
        let n = n.min(from.wire_out.len());
        let chunk: Vec<u8> = from.wire_out.drain(..n).collect();
        to.session.handle_input(now, &chunk);
    }

    fn check(a: &Side, b: &Side) {
        assert!(a.session.unacknowledged_count() <= a.k);
        assert!(b.session.unacknowledged_count() <= b.k);
        // delivered in order, exactly once: what was received is a prefix of what was sent
        assert!(a.received.len() <= b.sent.len());
        assert_eq!(a.received[..], b.sent[..a.received.len()]);
        assert!(b.received.len() <= a.sent.len());
        assert_eq!(b.received[..], a.sent[..b.received.len()]);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        #[test]
        fn random_interleavings_deliver_everything_in_order(
            k in 1u16..16,
            w_frac in 1u16..=100,
            ops in proptest::collection::vec(op(), 1..300),
        ) {
            let w = (k * w_frac).div_ceil(100).clamp(1, k);
            let t0 = Instant::now();
            let mut now = t0;
            let mut client = Side {
                session: Session::new(config(k, w), Role::ControllingStation, t0),
                wire_out: Vec::new(), sent: Vec::new(), received: Vec::new(), k: k as usize,
            };
            let mut server = Side {
                session: Session::new(config(k, w), Role::ControlledStation, t0),
                wire_out: Vec::new(), sent: Vec::new(), received: Vec::new(), k: k as usize,
            };
            client.session.start_data_transfer(t0).unwrap();
            client.collect();
            deliver(&mut client, &mut server, usize::MAX, now);
            server.collect();
            deliver(&mut server, &mut client, usize::MAX, now);
            client.collect();
            prop_assert_eq!(client.session.state(), SessionState::Started);
            prop_assert_eq!(server.session.state(), SessionState::Started);

            let (mut c_counter, mut s_counter) = (0u32, 1_000_000u32);
            for op in ops {
                match op {
                    Op::ClientSend => client.send(now, &mut c_counter),
                    Op::ServerSend => server.send(now, &mut s_counter),
                    Op::DeliverC2S(n) => deliver(&mut client, &mut server, n, now),
                    Op::DeliverS2C(n) => deliver(&mut server, &mut client, n, now),
                    Op::Advance(ms) => {
                        now += Duration::from_millis(ms);
                        client.session.handle_timeout(now);
                        server.session.handle_timeout(now);
                    }
                }
                client.collect();
                server.collect();
                check(&client, &server);
                if client.session.is_closed() || server.session.is_closed() {
                    return Ok(());
                }
            }

            // settle: deliver everything and let t2 acknowledge the rest
            for _ in 0..4 {
                for _ in 0..50 {
                    deliver(&mut client, &mut server, usize::MAX, now);
                    server.collect();
                    deliver(&mut server, &mut client, usize::MAX, now);
                    client.collect();
                    if client.wire_out.is_empty() && server.wire_out.is_empty() {
                        break;
                    }
                }
                now += Duration::from_secs(10);
                client.session.handle_timeout(now);
                server.session.handle_timeout(now);
                client.collect();
                server.collect();
            }
            check(&client, &server);
            if !client.session.is_closed() && !server.session.is_closed() {
                prop_assert_eq!(&client.received, &server.sent);
                prop_assert_eq!(&server.received, &client.sent);
                prop_assert_eq!(client.session.unacknowledged_count(), 0);
                prop_assert_eq!(server.session.unacknowledged_count(), 0);
            }
        }
    }

    /// xorshift64*: deterministic, dependency-free.
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
        }

        fn below(&mut self, n: u64) -> u64 {
            self.next() % n
        }
    }

    /// A stream that is mostly plausible APCI with random damage.
    fn random_stream(rng: &mut Rng) -> Vec<u8> {
        let mut out = Vec::new();
        match rng.below(4) {
            0 => {
                let len = rng.below(64);
                out.extend((0..len).map(|_| rng.next() as u8));
            }
            _ => {
                let mut ns = 0u16;
                for _ in 0..rng.below(16) {
                    match rng.below(24) {
                        0..=3 => encode_u_frame(UFunction::ALL[rng.below(6) as usize], &mut out),
                        4..=5 => encode_s_frame(SeqNum::new(rng.below(3) as u16), &mut out),
                        6..=19 => {
                            let len = 1 + rng.below(30) as usize;
                            let asdu: Vec<u8> = (0..len).map(|_| rng.next() as u8).collect();
                            // mostly in sequence
                            let send = if rng.below(16) == 0 {
                                rng.below(3) as u16
                            } else {
                                ns
                            };
                            ns = send.wrapping_add(1);
                            let nr = SeqNum::new(rng.below(2) as u16);
                            encode_i_frame(SeqNum::new(send), nr, &asdu, &mut out).unwrap();
                        }
                        20 => {
                            out.extend([0x68, rng.next() as u8]);
                            let len = rng.below(10);
                            out.extend((0..len).map(|_| rng.next() as u8));
                        }
                        21 => {
                            out.extend([0x68, 4]);
                            out.extend((0..4).map(|_| rng.next() as u8));
                        }
                        22 => {
                            if !out.is_empty() {
                                let at = rng.below(out.len() as u64) as usize;
                                out[at] = rng.next() as u8;
                            }
                        }
                        _ => {
                            let keep = rng.below(out.len() as u64 + 1) as usize;
                            out.truncate(keep);
                        }
                    }
                }
            }
        }
        out
    }

    #[test]
    fn hundred_thousand_random_streams_never_panic() {
        let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
        let mut closed = 0u32;
        let mut asdus_seen = 0u64;
        let streams = 100_000;
        for n in 0..streams {
            let t0 = Instant::now();
            let mut now = t0;
            let role = if n % 2 == 0 {
                Role::ControlledStation
            } else {
                Role::ControllingStation
            };
            let mut cfg = ApciConfig::default();
            cfg.k = 1 + rng.below(4) as u16;
            cfg.w = 1 + rng.below(u64::from(cfg.k)) as u16;
            cfg.max_unexpected_frames = rng.below(3) as u32;
            let mut session = Session::new(cfg, role, t0);
            let mut stream = Vec::new();
            if rng.below(2) == 0 {
                // mostly start data transfer first, so that I frames get through
                if role == Role::ControllingStation {
                    session.start_data_transfer(t0).unwrap();
                    encode_u_frame(UFunction::StartDtCon, &mut stream);
                } else {
                    encode_u_frame(UFunction::StartDtAct, &mut stream);
                }
            }
            stream.extend(random_stream(&mut rng));
            let mut rest = &stream[..];
            let mut out = Vec::new();
            while !rest.is_empty() {
                let cut = 1 + rng.below(rest.len() as u64) as usize;
                session.handle_input(now, &rest[..cut]);
                rest = &rest[cut..];
                match rng.below(4) {
                    0 => {
                        now += Duration::from_millis(rng.below(25_000));
                        session.handle_timeout(now);
                    }
                    1 => {
                        let _ = session.send_asdu(now, &[1, 2, 3]);
                    }
                    2 => {
                        if let Some(at) = session.poll_timeout() {
                            now = now.max(at);
                            session.handle_timeout(now);
                        }
                    }
                    _ => {}
                }
                out.clear();
                while session.poll_transmit(&mut out) {}
                // whatever the session sends must be well-formed
                decode_all(&out);
                assert!(session.unacknowledged_count() <= usize::from(session.config().k));
            }
            let evs = events(&mut session);
            asdus_seen += asdus(&evs).len() as u64;
            let closes = evs
                .iter()
                .filter(|e| matches!(e, SessionEvent::Closed(_)))
                .count();
            if session.is_closed() {
                closed += 1;
                assert_eq!(closes, 1);
                assert!(matches!(evs.last(), Some(SessionEvent::Closed(_))));
            } else {
                assert_eq!(closes, 0);
            }
        }
        eprintln!("random streams: {closed} closed, {asdus_seen} ASDUs delivered");
        // sanity: the generator exercises both outcomes
        assert!(closed > 1000 && closed < streams, "{closed}");
        assert!(asdus_seen > 5_000, "{asdus_seen}");
    }
}
