//! Acknowledgement and flow control: t2, w, piggy-backed acknowledgement and the k window.

use std::time::{Duration, Instant};

use iec60870::apci::{FrameFormat, UFunction};
use iec60870::cs104::{
    ApciConfig, CloseReason, Role, SendError, Session, SessionEvent, SessionState,
};

use crate::support::*;

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
