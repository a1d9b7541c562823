//! Redundancy: `deactivate` and `take_unacknowledged`, switch-over to another connection.

use std::time::Instant;

use iec60870::apci::UFunction;
use iec60870::cs104::{ApciConfig, CloseReason, SendError, SessionEvent, SessionState};

use crate::support::*;

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
