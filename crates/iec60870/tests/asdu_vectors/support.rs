//! Helpers of the ASDU vector tests: the 104 parameters, field builders, the decode,
//! compare and encode-back checks, and the CP56 time `T` of the derived vectors.

use iec60870::asdu::*;

pub(crate) const P104: AsduParams = AsduParams::IEC104;

pub(crate) fn ioa(value: u32) -> Ioa {
    Ioa::try_new(value).unwrap()
}

pub(crate) fn ca1() -> CommonAddress {
    CommonAddress::new(1)
}

pub(crate) fn cause(value: u8) -> Cause {
    Cause::new(value).unwrap()
}

pub(crate) fn cp56(bytes: [u8; 7]) -> Cp56Time2a {
    Cp56Time2a::from_bytes(bytes).unwrap()
}

/// Decodes, compares with the expected ASDU, and encodes back to the same bytes.
pub(crate) fn check(bytes: &[u8], params: &AsduParams, expected: &Asdu) {
    let decoded = Asdu::decode(bytes, params).unwrap();
    assert_eq!(&decoded, expected, "decoding {bytes:02X?}");
    let mut out = vec![0xEE]; // encode appends
    expected.encode(params, &mut out).unwrap();
    assert_eq!(&out[1..], bytes, "encoding {expected:?}");
    assert_eq!(expected.encoded_len(params), bytes.len());
}

/// Decodes and encodes back to the same bytes; returns the ASDU for field checks.
pub(crate) fn round_trip(bytes: &[u8], params: &AsduParams) -> Asdu {
    let decoded = Asdu::decode(bytes, params).unwrap();
    assert_eq!(decoded.to_bytes(params).unwrap(), bytes, "{decoded}");
    assert_eq!(decoded.encoded_len(params), bytes.len());
    decoded
}

/// CP56 2017-04-26 09:59:30.424 without flags, day of week 3 (Wednesday).
pub(crate) const T: [u8; 7] = [0xD8, 0x76, 0x3B, 0x09, 0x7A, 0x04, 0x11];

pub(crate) fn with_time(prefix: &[u8], suffix: &[u8]) -> Vec<u8> {
    let mut bytes = prefix.to_vec();
    bytes.extend_from_slice(suffix);
    bytes
}
