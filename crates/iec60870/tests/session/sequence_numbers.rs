//! Sequence numbers: the wrap-around at 32767 and bad N(R) or N(S) closing the connection.

use std::time::Instant;

use iec60870::apci::SeqNum;
use iec60870::cs104::{ApciConfig, CloseReason, Session, SessionEvent, SessionState};

use crate::support::*;

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
