//! I and S frames in the wrong state (stopped, or a STOPDT pending).

use std::time::Instant;

use iec60870::apci::UFunction;
use iec60870::cs104::{ApciConfig, CloseReason, Role, Session, SessionEvent, SessionState};

use crate::support::*;

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
