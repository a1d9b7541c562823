//! Arbitrary octets as the Sartorius balance's line: every 15-octet window parsed as
//! the gateway's buffer would be (bit 7, LF resynchronisation, character classes), and
//! the whole input fed to the reader in pieces. Nothing may panic; a legal record must
//! format back to a record that parses to the same reading.
#![no_main]

use std::time::{Duration, Instant};

use devices::balance::reader::{BalanceReader, ReaderEvent, BALANCE_LINE};
use devices::balance::record::{format, parse, RECORD_LEN};
use libfuzzer_sys::fuzz_target;
use serial_line::LineEndpoint;

fuzz_target!(|data: &[u8]| {
    for window in data.windows(RECORD_LEN) {
        let mut array = [0u8; RECORD_LEN];
        array.copy_from_slice(window);
        if let Ok(reading) = parse(&array) {
            if reading.weight_g.abs() <= 999.999 {
                let again = parse(&format(reading.weight_g, reading.stable));
                assert_eq!(again.map(|r| r.stable), Ok(reading.stable));
            }
        }
    }
    let t0 = Instant::now();
    let mut reader = BalanceReader::new(BALANCE_LINE, t0);
    let mut now = t0;
    for chunk in data.chunks(7) {
        now += Duration::from_millis(u64::from(chunk.first().copied().unwrap_or(0)) * 20);
        reader.handle_bytes(now, chunk);
        reader.handle_timeout(now);
        while let Some(event) = reader.poll_event() {
            if let ReaderEvent::Record(reading) = event {
                assert!(reading.weight_g.is_finite());
            }
        }
    }
});
