//! Malformed, truncated and large input: the close reasons and what is processed before.

use std::time::Instant;

use iec60870::apci::{FrameError, FrameFormat, UFunction};
use iec60870::cs104::{
    ApciConfig, CloseReason, Role, SendError, Session, SessionEvent, SessionState,
};

use crate::support::*;

#[test]
fn malformed_streams_close_with_the_reason() {
    let t0 = Instant::now();
    let cases: Vec<(&str, Vec<u8>, FrameError)> = vec![
        (
            "bad start",
            vec![0x67, 0x04, 0x07, 0, 0, 0],
            FrameError::InvalidStartByte(0x67),
        ),
        (
            "length 3",
            vec![0x68, 0x03, 0x07, 0, 0],
            FrameError::LengthTooShort(3),
        ),
        ("length 0", vec![0x68, 0x00], FrameError::LengthTooShort(0)),
        (
            "length 254",
            vec![0x68, 0xFE],
            FrameError::LengthTooLong(0xFE),
        ),
        (
            "length 255",
            vec![0x68, 0xFF],
            FrameError::LengthTooLong(0xFF),
        ),
        (
            "empty I",
            vec![0x68, 0x04, 0x00, 0, 0, 0],
            FrameError::EmptyIFrame,
        ),
        (
            "S with ASDU",
            vec![0x68, 0x05, 0x01, 0, 0, 0, 0x01],
            FrameError::UnexpectedAsdu {
                format: FrameFormat::S,
                len: 1,
            },
        ),
        (
            "U with ASDU",
            vec![0x68, 0x05, 0x07, 0, 0, 0, 0x01],
            FrameError::UnexpectedAsdu {
                format: FrameFormat::U,
                len: 1,
            },
        ),
        (
            "U two functions",
            vec![0x68, 0x04, 0x0F, 0, 0, 0],
            FrameError::InvalidUFunction(0x0F),
        ),
        (
            "U no function",
            vec![0x68, 0x04, 0x03, 0, 0, 0],
            FrameError::InvalidUFunction(0x03),
        ),
        (
            "U nonzero octet",
            vec![0x68, 0x04, 0x43, 0, 0, 1],
            FrameError::ReservedBitsSet([0x43, 0, 0, 1]),
        ),
        (
            "S octet 2",
            vec![0x68, 0x04, 0x01, 0x01, 0, 0],
            FrameError::ReservedBitsSet([0x01, 0x01, 0, 0]),
        ),
        (
            "valid then garbage",
            [
                u_frame(UFunction::TestFrAct),
                u_frame(UFunction::TestFrAct),
                vec![0x00],
            ]
            .concat(),
            FrameError::InvalidStartByte(0x00),
        ),
    ];
    for (name, bytes, error) in cases {
        for role in [Role::ControlledStation, Role::ControllingStation] {
            // whole, and byte by byte
            for split in [bytes.len(), 1] {
                let mut session = Session::new(ApciConfig::default(), role, t0);
                for chunk in bytes.chunks(split) {
                    session.handle_input(t0, chunk);
                }
                let reason = CloseReason::Frame(error);
                assert_eq!(closed_reason(&session), Some(reason.clone()), "{name}");
                let evs = events(&mut session);
                assert_eq!(
                    evs.last(),
                    Some(&SessionEvent::Closed(reason.clone())),
                    "{name}"
                );
                assert_eq!(
                    evs.iter()
                        .filter(|e| matches!(e, SessionEvent::Closed(_)))
                        .count(),
                    1
                );
                assert!(reason.to_string().starts_with("malformed APDU"), "{reason}");
                // dead: input, timeouts and sends are ignored
                session.handle_input(t0, &u_frame(UFunction::TestFrAct));
                session.handle_timeout(t0 + 3600 * SEC);
                assert_eq!(transmitted(&mut session), vec![]);
                assert_eq!(session.send_asdu(t0, b"x"), Err(SendError::Closed));
                assert_eq!(session.poll_timeout(), None);
                assert_eq!(events(&mut session), vec![]);
            }
        }
    }
}

#[test]
fn valid_frames_before_garbage_are_processed() {
    let t0 = Instant::now();
    let mut client = started_client(ApciConfig::default(), t0);
    let bytes = [
        i_frame(0, 0, b"a"),
        i_frame(1, 0, b"b"),
        vec![0x68, 0x04, 0x00, 0x00], // truncated I frame...
        vec![0x00, 0x00, 0xFF],       // ...that turns out to be empty, then garbage
    ]
    .concat();
    client.handle_input(t0, &bytes);
    let evs = events(&mut client);
    assert_eq!(asdus(&evs), vec![b"a".to_vec(), b"b".to_vec()]);
    assert_eq!(
        evs.last(),
        Some(&SessionEvent::Closed(CloseReason::Frame(
            FrameError::EmptyIFrame
        )))
    );
}

#[test]
fn truncated_stream_waits_without_closing() {
    let t0 = Instant::now();
    let mut client = started_client(ApciConfig::default(), t0);
    let frame = i_frame(0, 0, &[7; 200]);
    client.handle_input(t0, &frame[..150]);
    assert_eq!(client.state(), SessionState::Started);
    assert_eq!(events(&mut client), vec![]);
    client.handle_input(t0, &frame[150..]);
    assert_eq!(asdus(&events(&mut client)), vec![vec![7; 200]]);
}

#[test]
fn large_reads_are_processed_completely() {
    // more bytes in one call than the deframer buffers at once
    let t0 = Instant::now();
    let mut cfg = ApciConfig::default();
    cfg.w = 8;
    let mut client = started_client(cfg, t0);
    let mut bytes = Vec::new();
    for n in 0..1000u16 {
        bytes.extend(i_frame(n, 0, &[n as u8; 100]));
    }
    client.handle_input(t0, &bytes);
    assert_eq!(asdus(&events(&mut client)).len(), 1000);
    assert_eq!(client.stats().bytes_received, 6 + bytes.len() as u64);
}
