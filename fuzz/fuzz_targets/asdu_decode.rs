//! Decodes arbitrary bytes as an ASDU under several link parameter sets; whatever decodes
//! must re-encode, and the re-encoding must decode to the same ASDU and encode to the same
//! bytes again (decoding drops reserved bits, so the first encoding may differ from the
//! input, never from itself).
#![no_main]

use iec60870::asdu::{mirror_with_cause, Asdu, AsduError, AsduHeader, AsduParams, Cause};
use libfuzzer_sys::fuzz_target;

/// (COT, common address, IOA, maximum ASDU length)
const PARAMS: [(u8, u8, u8, usize); 5] = [
    (2, 2, 3, 249), // IEC 104
    (1, 1, 2, 253), // a common IEC 101 link
    (1, 1, 1, 255),
    (2, 1, 2, 255),
    (1, 2, 3, 64),
];

fn check(data: &[u8], params: &AsduParams) {
    let header = AsduHeader::decode(data, params);
    let mirrored = mirror_with_cause(data, params, Cause::UNKNOWN_TYPE, true);
    assert_eq!(header.is_ok(), mirrored.is_ok());
    if let Ok(mirrored) = mirrored {
        assert_eq!(mirrored.len(), data.len());
    }
    let Ok(asdu) = Asdu::decode(data, params) else {
        return;
    };
    let _ = asdu.to_string();
    if data.len() > params.max_asdu_len() {
        // Decoding is lenient about the link's maximum, encoding is not.
        assert!(matches!(
            asdu.to_bytes(params),
            Err(AsduError::TooLong { .. })
        ));
        return;
    }
    let first = asdu.to_bytes(params).expect("a decoded ASDU re-encodes");
    assert_eq!(first.len(), data.len());
    let again = Asdu::decode(&first, params).expect("a re-encoded ASDU decodes");
    // Compared through Debug as well as bytes: f32 NaN is not equal to itself.
    assert_eq!(format!("{again:?}"), format!("{asdu:?}"));
    assert_eq!(again.to_bytes(params).expect("encodes"), first);
}

fuzz_target!(|data: &[u8]| {
    for (cot, ca, ioa, max) in PARAMS {
        let params = AsduParams::try_new(cot, ca, ioa, max).expect("valid parameters");
        check(data, &params);
    }
});
