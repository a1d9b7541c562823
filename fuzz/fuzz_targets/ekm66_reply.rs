//! Arbitrary line octets, cut at arbitrary points, into the EKM66 reply deframer and a
//! poller, with clock jumps and line pauses between the chunks. Nothing may panic;
//! every frame the deframer yields must validate again on its own and decode (or be
//! refused) as the reply to each query; the poller may only ever transmit queries.
//!
//! Each op byte says what to do (its top two bits) and how much (the rest): `00`/`01`
//! feed the next 1..=128 bytes, `10` advance the clock by 0..=630 ms, `11` a line pause.
#![no_main]

use std::time::{Duration, Instant};

use devices::ekm66::codec::{decode_reply, CodecConfig, CounterWidth, Deframer, Frame, Query, TimeEncoding};
use devices::ekm66::poller::{ArchiveCursor, Poller, PollerConfig};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut codec = CodecConfig::default();
    if let Some(first) = data.first() {
        codec.counter_width = [CounterWidth::One, CounterWidth::Two, CounterWidth::Four]
            [usize::from(first % 3)];
        if first & 0x80 != 0 {
            codec.time = TimeEncoding::Bcd;
        }
    }
    let start = Instant::now();
    let mut now = start;
    let mut config = PollerConfig::default();
    config.codec = codec.clone();
    let mut poller = Poller::new(config, ArchiveCursor::default(), now);
    let mut deframer = Deframer::new();
    let mut rest = data.get(1..).unwrap_or_default();
    while let Some((&op, tail)) = rest.split_first() {
        rest = tail;
        let amount = usize::from(op & 0x3F);
        match op >> 6 {
            0 | 1 => {
                let count = (usize::from(op & 0x7F) + 1).min(rest.len());
                let (chunk, tail) = rest.split_at(count);
                rest = tail;
                deframer.push(chunk);
                while let Some(next) = deframer.next_frame() {
                    if let Ok(frame) = next {
                        assert_eq!(Frame::parse(frame.as_bytes()).as_ref(), Ok(&frame));
                        for query in [Query::Status, Query::Counters, Query::FaultRecord(chunk.len() as u8)] {
                            let _ = decode_reply(query, &frame, &codec);
                        }
                    }
                }
                poller.handle_bytes(now, chunk);
            }
            2 => {
                now += Duration::from_millis(amount as u64 * 10);
                poller.handle_timeout(now);
            }
            _ => {
                deframer.abandon();
                poller.handle_line_pause(now);
            }
        }
        while let Some(query) = poller.poll_transmit(now) {
            let frame = Frame::parse(&query).expect("the poller sends frames");
            Query::from_user_data(frame.user_data()).expect("the poller sends queries");
        }
        while poller.poll_event().is_some() {}
        // The poller's deadline never lies in the past for long.
        if let Some(deadline) = poller.poll_timeout() {
            if deadline <= now {
                poller.handle_timeout(now);
            }
        }
    }
});
