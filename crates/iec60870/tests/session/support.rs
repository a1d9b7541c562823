//! Helpers of the session tests: frame builders and decoders, started sessions on a
//! raw peer, and `Pair`, a client and a server session on a perfect wire.

use std::time::{Duration, Instant};

use iec60870::apci::{
    encode_i_frame, encode_s_frame, encode_u_frame, Apci, Deframer, SeqNum, UFunction,
};
use iec60870::cs104::{ApciConfig, CloseReason, Role, Session, SessionEvent, SessionState};

pub(crate) const SEC: Duration = Duration::from_secs(1);
pub(crate) const MS: Duration = Duration::from_millis(1);

pub(crate) fn i_frame(ns: u16, nr: u16, asdu: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    encode_i_frame(SeqNum::new(ns), SeqNum::new(nr), asdu, &mut out).unwrap();
    out
}

pub(crate) fn s_frame(nr: u16) -> Vec<u8> {
    let mut out = Vec::new();
    encode_s_frame(SeqNum::new(nr), &mut out);
    out
}

pub(crate) fn u_frame(function: UFunction) -> Vec<u8> {
    let mut out = Vec::new();
    encode_u_frame(function, &mut out);
    out
}

pub(crate) fn i(ns: u16, nr: u16) -> Apci {
    Apci::I {
        send_seq: SeqNum::new(ns),
        recv_seq: SeqNum::new(nr),
    }
}

pub(crate) fn s(nr: u16) -> Apci {
    Apci::S {
        recv_seq: SeqNum::new(nr),
    }
}

pub(crate) fn u(function: UFunction) -> Apci {
    Apci::U(function)
}

/// Everything the session wants to transmit, decoded.
pub(crate) fn transmitted(session: &mut Session) -> Vec<Apci> {
    let mut bytes = Vec::new();
    while session.poll_transmit(&mut bytes) {}
    decode_all(&bytes)
}

pub(crate) fn decode_all(bytes: &[u8]) -> Vec<Apci> {
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

pub(crate) fn events(session: &mut Session) -> Vec<SessionEvent> {
    std::iter::from_fn(|| session.poll_event()).collect()
}

pub(crate) fn asdu(n: u32) -> Vec<u8> {
    // A recognisable payload of varying length (1..=249 octets).
    let mut v = n.to_le_bytes().to_vec();
    v.resize(4 + (n % 40) as usize, (n % 251) as u8);
    v
}

pub(crate) fn config(k: u16, w: u16) -> ApciConfig {
    let mut c = ApciConfig::default();
    c.k = k;
    c.w = w;
    c
}

/// A controlled station after STARTDT from a raw client, with the transmit and event
/// queues drained.
pub(crate) fn started_server(cfg: ApciConfig, t0: Instant) -> Session {
    let mut server = Session::new(cfg, Role::ControlledStation, t0);
    server.handle_input(t0, &u_frame(UFunction::StartDtAct));
    assert_eq!(transmitted(&mut server), vec![u(UFunction::StartDtCon)]);
    assert_eq!(events(&mut server), vec![SessionEvent::Started]);
    server
}

/// A controlling station after STARTDT answered by a raw server.
pub(crate) fn started_client(cfg: ApciConfig, t0: Instant) -> Session {
    let mut client = Session::new(cfg, Role::ControllingStation, t0);
    client.start_data_transfer(t0).unwrap();
    assert_eq!(transmitted(&mut client), vec![u(UFunction::StartDtAct)]);
    client.handle_input(t0, &u_frame(UFunction::StartDtCon));
    assert_eq!(events(&mut client), vec![SessionEvent::Started]);
    client
}

pub(crate) fn closed_reason(session: &Session) -> Option<CloseReason> {
    match session.state() {
        SessionState::Closed(reason) => Some(reason),
        _ => None,
    }
}

/// A client and a server session connected by a perfect, instantaneous wire.
pub(crate) struct Pair {
    pub(crate) base: Instant,
    pub(crate) now: Instant,
    pub(crate) client: Session,
    pub(crate) server: Session,
    pub(crate) client_events: Vec<SessionEvent>,
    pub(crate) server_events: Vec<SessionEvent>,
    /// Every frame on the wire, client to server and server to client.
    pub(crate) c2s: Vec<Apci>,
    pub(crate) s2c: Vec<Apci>,
}

impl Pair {
    pub(crate) fn new(client_cfg: ApciConfig, server_cfg: ApciConfig) -> Pair {
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

    pub(crate) fn started(client_cfg: ApciConfig, server_cfg: ApciConfig) -> Pair {
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
    pub(crate) fn pump(&mut self) {
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

    pub(crate) fn next_timeout(&self) -> Option<Instant> {
        [self.client.poll_timeout(), self.server.poll_timeout()]
            .into_iter()
            .flatten()
            .min()
    }

    /// Steps the clock to the next deadline of either side (if it is not after
    /// `limit`), handles it and pumps. Returns false when there is none.
    pub(crate) fn step_until(&mut self, limit: Instant) -> bool {
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
    pub(crate) fn advance(&mut self, d: Duration) {
        let limit = self.now + d;
        while self.step_until(limit) {}
        self.now = limit;
        self.client.handle_timeout(self.now);
        self.server.handle_timeout(self.now);
        self.pump();
    }

    pub(crate) fn elapsed(&self) -> Duration {
        self.now - self.base
    }

    pub(crate) fn take_events(&mut self) -> (Vec<SessionEvent>, Vec<SessionEvent>) {
        (
            std::mem::take(&mut self.client_events),
            std::mem::take(&mut self.server_events),
        )
    }
}

pub(crate) fn asdus(events: &[SessionEvent]) -> Vec<Vec<u8>> {
    events
        .iter()
        .filter_map(|e| match e {
            SessionEvent::Asdu(a) => Some(a.clone()),
            _ => None,
        })
        .collect()
}
