//! STARTDT and STOPDT: the handshakes, STOPDT with frames outstanding, a pending stop.

use std::time::{Duration, Instant};

use iec60870::apci::{SeqNum, UFunction};
use iec60870::cs104::{
    ApciConfig, CloseReason, ControlError, SendError, SessionEvent, SessionState,
};

use crate::support::*;

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
