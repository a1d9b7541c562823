//! Arbitrary octets into the IEC 103 ASDU decoder, both directions. Nothing may panic;
//! whatever decodes must encode again to octets that decode and encode to the same
//! octets (compared as octets: a NaN in a float field is not equal to itself), and its
//! analyser line must render.
#![no_main]

use iec60870::iec103::{Asdu, Direction};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    for direction in [Direction::Monitor, Direction::Control] {
        if let Ok(asdu) = Asdu::decode(data, direction) {
            let _ = asdu.to_string();
            let again = asdu.to_bytes().expect("a decoded ASDU encodes");
            let decoded = Asdu::decode(&again, direction).expect("its encoding decodes");
            assert_eq!(decoded.to_bytes().expect("encodes"), again);
        }
    }
});
