//! Arbitrary octets as Modbus frames: a request PDU as a server decodes it, the answer to
//! a few requests as a client decodes it, an RTU frame's CRC, and both server connections
//! (Modbus TCP fed in two pieces, an RTU slave in 7-octet pieces with line pauses) on a
//! per-unit data model. Nothing may panic; whatever decodes must encode back to what
//! decodes the same (`modbus::fuzz_decode`).
#![no_main]

use std::time::Instant;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    modbus::fuzz_decode(data, Instant::now());
});
