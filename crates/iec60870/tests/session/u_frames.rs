//! U frames of the wrong role, TESTFR in every state, and t3 keep-alive.

use std::time::Instant;

use iec60870::apci::{FrameFormat, UFunction};
use iec60870::cs104::{ApciConfig, CloseReason, Role, Session, SessionState};

use crate::support::*;

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
