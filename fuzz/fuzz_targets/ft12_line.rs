//! Arbitrary line octets, cut at arbitrary points, into the FT1.2 deframer, a primary
//! polling three secondaries, a secondary and one end of a balanced link, with clock
//! jumps and line pauses between the chunks. Nothing may panic; every frame the deframer yields must encode back to
//! the octets it came from; the primary may only ever transmit frames that deframe.
//!
//! The first byte picks the address field size; then each op byte says what to do
//! (its top two bits) and how much (the rest): `00`/`01` feed the next 1..=128 bytes,
//! `10` advance the clock by 0..=630 ms, `11` signal a line pause.
#![no_main]

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use iec60870::ft12::*;
use libfuzzer_sys::fuzz_target;

struct Quiet(VecDeque<Vec<u8>>);

impl SecondaryApplication for Quiet {
    fn link_reset(&mut self, _function: PrimaryFunction) {}
    fn user_data(&mut self, _asdu: &[u8], _broadcast: bool) -> bool {
        true
    }
    fn has_class1(&self) -> bool {
        !self.0.is_empty()
    }
    fn class1(&mut self) -> Option<Vec<u8>> {
        self.0.pop_front()
    }
    fn class2(&mut self) -> Option<Vec<u8>> {
        Some(vec![0x09, 0x81, 0x02, 0x01, 0x01, 0x94, 0x00, 0x00])
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&head, mut rest)) = data.split_first() else {
        return;
    };
    let size = match head % 3 {
        0 => AddressSize::None,
        1 => AddressSize::One,
        _ => AddressSize::Two,
    };
    let t0 = Instant::now();
    let mut now = t0;
    let mut primary = Primary::new(
        PrimaryConfig {
            address_size: size,
            ..PrimaryConfig::default()
        },
        t0,
    );
    for address in [0u16, 1, 2] {
        let _ = primary.add_station(address);
    }
    let _ = primary.send(1, vec![0x14, 0x81, 0x14, 0x01, 0x01, 0xA0, 0x02, 0x07]);
    let mut secondary = Secondary::new(SecondaryConfig {
        address_size: size,
        address: if size == AddressSize::None { 0 } else { 1 },
        single_character: head & 0x80 != 0,
        class1_on_class2_request: head & 0x40 != 0,
    });
    let mut app = Quiet(
        (0..3u8)
            .map(|n| vec![0x01, 0x81, 0x01, 0x01, 0xA0, n])
            .collect(),
    );
    let mut deframer = Deframer::new(size);
    let mut balanced = Balanced::new(
        BalancedConfig {
            address_size: size,
            ..BalancedConfig::new(1, head & 0x20 != 0)
        },
        t0,
    );
    let mut balanced_sent: Vec<u8> = Vec::new();
    while let Some((&op, tail)) = rest.split_first() {
        rest = tail;
        match op >> 6 {
            0 | 1 => {
                let take = usize::from(op & 0x7F) + 1;
                let (chunk, tail) = rest.split_at(take.min(rest.len()));
                rest = tail;
                primary.handle_bytes(now, chunk);
                balanced.handle_bytes(now, chunk);
                deframer.push(chunk);
                while let Some(next) = deframer.next_frame() {
                    let Ok(frame) = next else { continue };
                    let bytes = frame.to_bytes(size).expect("a received frame encodes");
                    let mut again = Deframer::new(size);
                    again.push(&bytes);
                    assert_eq!(again.next_frame(), Some(Ok(frame.clone())));
                    if let Some(answer) = secondary.handle(&frame, &mut app) {
                        answer.to_bytes(size).expect("an answer encodes");
                    }
                }
            }
            2 => {
                now += Duration::from_millis(u64::from(op & 0x3F) * 10);
                primary.handle_timeout(now);
                balanced.handle_timeout(now);
                if op & 0x01 != 0 {
                    balanced.send(vec![0x64, 0x01, 0x06, 0x01, 0x00, 0x00, 0x14]);
                }
            }
            _ => {
                primary.handle_line_pause(now);
                balanced.handle_line_pause(now);
                deframer.abandon_partial();
            }
        }
        while let Some(bytes) = balanced.poll_transmit(now) {
            balanced_sent.clear();
            balanced_sent.extend_from_slice(&bytes);
            let mut check = Deframer::new(size);
            check.push(&balanced_sent);
            assert!(
                matches!(check.next_frame(), Some(Ok(_))),
                "the balanced end sent a broken frame"
            );
        }
        while balanced.poll_event().is_some() {}
        while let Some(bytes) = primary.poll_transmit(now) {
            let mut check = Deframer::new(size);
            check.push(&bytes);
            assert!(
                matches!(check.next_frame(), Some(Ok(_))),
                "the primary sent a broken frame"
            );
            assert!(check.next_frame().is_none());
        }
        while primary.poll_event().is_some() {}
        if let Some(deadline) = primary.next_deadline() {
            assert!(deadline >= t0);
        }
    }
});
