//! Arbitrary octets into the IEC 103 ASDU decoder, both directions. Nothing may panic;
//! whatever decodes must encode again to octets that decode to the same ASDU, and its
//! analyser line must render.
#![no_main]

use iec60870::iec103::{Asdu, Direction};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    for direction in [Direction::Monitor, Direction::Control] {
        if let Ok(asdu) = Asdu::decode(data, direction) {
            let _ = asdu.to_string();
            let again = asdu.to_bytes().expect("a decoded ASDU encodes");
            assert_eq!(Asdu::decode(&again, direction).as_ref(), Ok(&asdu));
        }
    }
});
