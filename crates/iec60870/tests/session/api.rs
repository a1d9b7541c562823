//! The session's API at its edges: `send_asdu`'s limits, a local close, a clock going backwards
//! and huge timers, and the statistics.

use std::time::{Duration, Instant};

use iec60870::cs104::{ApciConfig, CloseReason, SendError, SessionEvent, SessionState};

use crate::support::*;

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
