//! Arbitrary bytes as a packed block of the event history (a row of `event_blocks` or
//! `event_segments` read back from a database file someone edited or a disk that lied):
//! unpacking gives the events or an error, never a panic, an overflow or an allocation
//! the bytes do not pay for.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(events) = store::decode_event_block(data) {
        // The smallest event takes 12 bytes: a count beyond that was refused.
        assert!(events <= data.len() / 12 + 1);
    }
});
