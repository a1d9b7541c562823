//! Arbitrary octets as S7 over ISO-on-TCP: every decoder (S7comm PDU, COTP TPDU, the TPKT
//! deframer, address and TSAP text) and both connection state machines fed the bytes as a
//! stream, through `s7::fuzz_decode`. Nothing may panic, loop forever or grow without
//! bound.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    s7::fuzz_decode(data);
});
