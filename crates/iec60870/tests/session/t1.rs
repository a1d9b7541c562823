//! t1: unacknowledged I frames and unconfirmed STARTDT, STOPDT and TESTFR close the connection.

use std::time::Instant;

use iec60870::apci::{SeqNum, UFunction};
use iec60870::cs104::{ApciConfig, CloseReason, Role, Session, SessionEvent, SessionState};

use crate::support::*;

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
