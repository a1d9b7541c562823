//! Random interleavings of a client and a server (proptest), and random byte streams that
//! must never make a session panic.

use std::time::{Duration, Instant};

use iec60870::apci::{encode_i_frame, encode_s_frame, encode_u_frame, SeqNum, UFunction};
use iec60870::cs104::{ApciConfig, Role, SendError, Session, SessionEvent, SessionState};
use proptest::prelude::*;

use crate::support::*;

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
