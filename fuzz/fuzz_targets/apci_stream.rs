//! Arbitrary bytes, cut at arbitrary points, into a controlled-station `Session`, with
//! timeouts, sends and redundancy calls interleaved. The session must never panic, never
//! exceed its k window and only ever transmit well-formed APDUs.
//!
//! The input is a program: the first byte picks k and w, then each op byte says what to
//! do next (its top two bits) and how much (the rest):
//! `00xxxxxx`/`01xxxxxx` feed the next 1..=128 input bytes, `10xxxxxx` advance the clock
//! by 0..=31.5 s and handle timeouts, `11xxxxxx` send an ASDU, jump to the next deadline,
//! deactivate or take the unacknowledged ASDUs.
#![no_main]

use std::time::{Duration, Instant};

use iec60870::apci::Deframer;
use iec60870::cs104::{ApciConfig, Role, Session};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&head, mut rest)) = data.split_first() else {
        return;
    };
    let mut config = ApciConfig::default();
    config.k = 1 + u16::from(head & 0x0F);
    config.w = 1 + u16::from(head >> 4) % config.k;
    config.max_unexpected_frames = u32::from(head >> 6);
    let t0 = Instant::now();
    let mut now = t0;
    let mut session = Session::new(config, Role::ControlledStation, t0);
    let mut out = Vec::new();
    let mut check = Deframer::new();

    while let Some((&op, tail)) = rest.split_first() {
        rest = tail;
        match op >> 6 {
            0 | 1 => {
                let n = (usize::from(op & 0x7F) + 1).min(rest.len());
                let (chunk, tail) = rest.split_at(n);
                session.handle_input(now, chunk);
                rest = tail;
            }
            2 => {
                now += Duration::from_millis(u64::from(op & 0x3F) * 500);
                session.handle_timeout(now);
            }
            _ => match op & 0x03 {
                0 => {
                    let len = usize::from(op >> 2 & 0x0F) * 16;
                    let _ = session.send_asdu(now, &vec![op; len]);
                }
                1 => {
                    if let Some(at) = session.poll_timeout() {
                        now = now.max(at);
                        session.handle_timeout(now);
                    }
                }
                2 => session.deactivate(),
                _ => {
                    let _ = session.take_unacknowledged();
                }
            },
        }
        out.clear();
        while session.poll_transmit(&mut out) {}
        // everything transmitted must frame cleanly
        let mut bytes = &out[..];
        while !bytes.is_empty() {
            let n = check.push(bytes);
            bytes = &bytes[n..];
            while let Some(frame) = check.next_frame() {
                assert!(frame.is_ok(), "session transmitted a malformed APDU");
            }
        }
        while session.poll_event().is_some() {}
        assert!(session.unacknowledged_count() <= usize::from(session.config().k));
    }
});
