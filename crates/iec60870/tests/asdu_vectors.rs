//! ASDU codec against known bytes: the decoded logs of spec §7.3, one derived vector per
//! element family, hardening cases, display and packing.
#![allow(
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing,
    missing_docs,
    // Tests and benchmarks measure and wait on the wall clock; the cores do not.
    clippy::disallowed_methods
)]

use iec60870::asdu::*;

const P104: AsduParams = AsduParams::IEC104;

fn ioa(value: u32) -> Ioa {
    Ioa::try_new(value).unwrap()
}

fn ca1() -> CommonAddress {
    CommonAddress::new(1)
}

fn cause(value: u8) -> Cause {
    Cause::new(value).unwrap()
}

fn cp56(bytes: [u8; 7]) -> Cp56Time2a {
    Cp56Time2a::from_bytes(bytes).unwrap()
}

/// Decodes, compares with the expected ASDU, and encodes back to the same bytes.
fn check(bytes: &[u8], params: &AsduParams, expected: &Asdu) {
    let decoded = Asdu::decode(bytes, params).unwrap();
    assert_eq!(&decoded, expected, "decoding {bytes:02X?}");
    let mut out = vec![0xEE]; // encode appends
    expected.encode(params, &mut out).unwrap();
    assert_eq!(&out[1..], bytes, "encoding {expected:?}");
    assert_eq!(expected.encoded_len(params), bytes.len());
}

/// Decodes and encodes back to the same bytes; returns the ASDU for field checks.
fn round_trip(bytes: &[u8], params: &AsduParams) -> Asdu {
    let decoded = Asdu::decode(bytes, params).unwrap();
    assert_eq!(decoded.to_bytes(params).unwrap(), bytes, "{decoded}");
    assert_eq!(decoded.encoded_len(params), bytes.len());
    decoded
}

// ---- spec §7.3: double command, breaker close ----

const DP_TB_OFF: [u8; 17] = [
    0x1F, 0x01, 0x03, 0x00, 0x01, 0x00, 0xD0, 0x07, 0x00, 0x01, 0xD8, 0x76, 0xBB, 0x09, 0x1A, 0x04,
    0x11,
];
const DC_COT5: [u8; 10] = [0x2E, 0x01, 0x05, 0x00, 0x01, 0x00, 0x34, 0x08, 0x00, 0x02];
const DC_COT0: [u8; 10] = [0x2E, 0x01, 0x00, 0x00, 0x01, 0x00, 0x34, 0x08, 0x00, 0x02];
const DP_TB_ON: [u8; 17] = [
    0x1F, 0x01, 0x03, 0x00, 0x01, 0x00, 0xD0, 0x07, 0x00, 0x02, 0x93, 0x19, 0x80, 0x0A, 0x1A, 0x04,
    0x11,
];
const APDU_DP_TB_OFF: [u8; 23] = [
    0x68, 0x15, 0x00, 0x00, 0x00, 0x00, 0x1F, 0x01, 0x03, 0x00, 0x01, 0x00, 0xD0, 0x07, 0x00, 0x01,
    0xD8, 0x76, 0xBB, 0x09, 0x1A, 0x04, 0x11,
];

// ---- spec §7.3: single command, LOCAL then REMOTE ----

const DP_TB_OFF_2: [u8; 17] = [
    0x1F, 0x01, 0x03, 0x00, 0x01, 0x00, 0xD0, 0x07, 0x00, 0x01, 0x56, 0x64, 0xB9, 0x0D, 0x1A, 0x04,
    0x11,
];
const SC_COT5: [u8; 10] = [0x2D, 0x01, 0x05, 0x00, 0x01, 0x00, 0x36, 0x10, 0x00, 0x01];
const SC_COT0: [u8; 10] = [0x2D, 0x01, 0x00, 0x00, 0x01, 0x00, 0x36, 0x10, 0x00, 0x01];
const DP_TB_ON_2: [u8; 17] = [
    0x1F, 0x01, 0x03, 0x00, 0x01, 0x00, 0xD0, 0x07, 0x00, 0x02, 0x06, 0x60, 0xBB, 0x0D, 0x1A, 0x04,
    0x11,
];

// ---- spec §7.3: measured values, normalized ----

/// (ASDU, IOA, raw, normalized printed by the test tool)
const NORMALIZED: [([u8; 12], u32, i16, &str); 8] = [
    (
        [
            0x09, 0x01, 0x03, 0x00, 0x01, 0x00, 0x1C, 0x0C, 0x00, 0x00, 0x00, 0x00,
        ],
        3100,
        0,
        "0.000000",
    ),
    (
        [
            0x09, 0x01, 0x03, 0x00, 0x01, 0x00, 0x1C, 0x0C, 0x00, 0x64, 0x00, 0x00,
        ],
        3100,
        100,
        "0.003052",
    ),
    (
        [
            0x09, 0x01, 0x03, 0x00, 0x01, 0x00, 0x80, 0x0C, 0x00, 0x64, 0x00, 0x00,
        ],
        3200,
        100,
        "0.003052",
    ),
    (
        [
            0x09, 0x01, 0x03, 0x00, 0x01, 0x00, 0xE4, 0x0C, 0x00, 0x64, 0x00, 0x00,
        ],
        3300,
        100,
        "0.003052",
    ),
    (
        [
            0x09, 0x01, 0x03, 0x00, 0x01, 0x00, 0x4C, 0x04, 0x00, 0xE5, 0x2A, 0x00,
        ],
        1100,
        10981,
        "0.335114",
    ),
    (
        [
            0x09, 0x01, 0x03, 0x00, 0x01, 0x00, 0xB0, 0x04, 0x00, 0xEA, 0x2A, 0x00,
        ],
        1200,
        10986,
        "0.335266",
    ),
    (
        [
            0x09, 0x01, 0x03, 0x00, 0x01, 0x00, 0x14, 0x05, 0x00, 0xEC, 0x2A, 0x00,
        ],
        1300,
        10988,
        "0.335327",
    ),
    (
        [
            0x09, 0x01, 0x03, 0x00, 0x01, 0x00, 0x50, 0x14, 0x00, 0x32, 0x00, 0x00,
        ],
        5200,
        50,
        "0.001526",
    ),
];

// ---- spec §7.3: measured values, short float ----

const FLOAT_P: [u8; 14] = [
    0x0D, 0x01, 0x03, 0x00, 0x01, 0x00, 0x88, 0x13, 0x00, 0x0E, 0x81, 0xE8, 0x49, 0x00,
];
const FLOAT_P_AND_F: [u8; 22] = [
    0x0D, 0x02, 0x03, 0x00, 0x01, 0x00, 0x88, 0x13, 0x00, 0x06, 0x94, 0xE8, 0x49, 0x00, 0x50, 0x14,
    0x00, 0x0B, 0x00, 0x48, 0x42, 0x00,
];
const FLOAT_F: [u8; 14] = [
    0x0D, 0x01, 0x03, 0x00, 0x01, 0x00, 0x50, 0x14, 0x00, 0x06, 0x00, 0x48, 0x42, 0x00,
];

fn double_point_event(state: DoublePointState, time: [u8; 7]) -> Asdu {
    Asdu::new(TypeId::M_DP_TB_1, Cause::SPONTANEOUS, ca1()).with_object(
        InformationObject::with_time(
            ioa(2000),
            Element::DoublePoint {
                state,
                quality: Quality::GOOD,
            },
            cp56(time),
        ),
    )
}

#[test]
fn spec_double_point_events() {
    let off = double_point_event(
        DoublePointState::Off,
        [0xD8, 0x76, 0xBB, 0x09, 0x1A, 0x04, 0x11],
    );
    check(&DP_TB_OFF, &P104, &off);
    let time = off.objects[0].time.unwrap();
    let time = time.as_cp56().unwrap();
    assert_eq!(time.to_string(), "2017-04-26 09:59:30.424 [IV]");
    assert_eq!(time.day_of_week(), 0);
    assert!(time.is_invalid() && !time.is_summer_time());

    let on = double_point_event(
        DoublePointState::On,
        [0x93, 0x19, 0x80, 0x0A, 0x1A, 0x04, 0x11],
    );
    check(&DP_TB_ON, &P104, &on);
    assert_eq!(
        on.objects[0].time.unwrap().to_string(),
        "2017-04-26 10:00:06.547 [IV]"
    );

    let off2 = double_point_event(
        DoublePointState::Off,
        [0x56, 0x64, 0xB9, 0x0D, 0x1A, 0x04, 0x11],
    );
    check(&DP_TB_OFF_2, &P104, &off2);
    assert_eq!(
        off2.objects[0].time.unwrap().to_string(),
        "2017-04-26 13:57:25.686 [IV]"
    );
    let on2 = double_point_event(
        DoublePointState::On,
        [0x06, 0x60, 0xBB, 0x0D, 0x1A, 0x04, 0x11],
    );
    check(&DP_TB_ON_2, &P104, &on2);
    assert_eq!(
        on2.objects[0].time.unwrap().to_string(),
        "2017-04-26 13:59:24.582 [IV]"
    );

    // The full APDU of the first line carries this ASDU after the 6-octet APCI.
    assert_eq!(usize::from(APDU_DP_TB_OFF[1]), 4 + DP_TB_OFF.len());
    assert_eq!(&APDU_DP_TB_OFF[6..], &DP_TB_OFF);
}

#[test]
fn spec_commands_with_non_standard_causes() {
    for (bytes, cause_value) in [(DC_COT5, 5), (DC_COT0, 0)] {
        let expected = Asdu::new(TypeId::C_DC_NA_1, cause(cause_value), ca1()).with_object(
            InformationObject::new(
                ioa(2100),
                Element::DoubleCommand {
                    state: DoublePointState::On,
                    qualifier: CommandQualifier::EXECUTE,
                },
            ),
        );
        check(&bytes, &P104, &expected);
    }
    for (bytes, cause_value) in [(SC_COT5, 5), (SC_COT0, 0)] {
        let expected = Asdu::new(TypeId::C_SC_NA_1, cause(cause_value), ca1()).with_object(
            InformationObject::new(
                ioa(4150),
                Element::SingleCommand {
                    on: true,
                    qualifier: CommandQualifier::EXECUTE,
                },
            ),
        );
        check(&bytes, &P104, &expected);
    }
    let cot0 = Asdu::decode(&DC_COT0, &P104).unwrap();
    assert_eq!(cot0.cot.cause.name(), "not defined");
    assert_eq!(
        cot0.to_string(),
        "C_DC_NA_1 (46) [sq=0 n=1] cot=not defined(0) [tst pn] oa=0 ca=1\n  ioa=2100 DCO ON execute qu=0"
    );
}

#[test]
fn spec_normalized_values() {
    for (bytes, address, raw, fraction) in NORMALIZED {
        let expected = Asdu::new(TypeId::M_ME_NA_1, Cause::SPONTANEOUS, ca1()).with_object(
            InformationObject::new(
                ioa(address),
                Element::Normalized {
                    raw,
                    quality: Quality::GOOD,
                },
            ),
        );
        check(&bytes, &P104, &expected);
        assert_eq!(format!("{:.6}", Element::normalized_value(raw)), fraction);
    }
    let u = Asdu::decode(&NORMALIZED[4].0, &P104).unwrap();
    assert_eq!(
        u.objects[0].element.to_string(),
        "0x2AE5 (0.335114) [iv nt sb bl ov]"
    );
    assert_eq!(Element::normalized_raw(0.335_114), 10981);
}

fn float_object(address: u32, bits: u32) -> InformationObject {
    InformationObject::new(
        ioa(address),
        Element::Float {
            value: f32::from_bits(bits),
            quality: Quality::GOOD,
        },
    )
}

#[test]
fn spec_float_values() {
    let p = Asdu::new(TypeId::M_ME_NC_1, Cause::SPONTANEOUS, ca1())
        .with_object(float_object(5000, 0x49E8_810E));
    check(&FLOAT_P, &P104, &p);
    let Element::Float { value, .. } = p.objects[0].element else {
        unreachable!()
    };
    assert_eq!(f64::from(value), 1_904_673.75); // exact in f32
    assert_eq!(
        p.objects[0].element.to_string(),
        "1904673.75 [iv nt sb bl ov]"
    );

    let both = Asdu::new(TypeId::M_ME_NC_1, Cause::SPONTANEOUS, ca1())
        .with_object(float_object(5000, 0x49E8_9406))
        .with_object(float_object(5200, 0x4248_000B));
    check(&FLOAT_P_AND_F, &P104, &both);
    assert_eq!(
        both.to_string(),
        "M_ME_NC_1 (13) [sq=0 n=2] cot=spont(3) [tst pn] oa=0 ca=1\n  \
         ioa=5000 R32 1905280.75 [iv nt sb bl ov]\n  \
         ioa=5200 R32 50.000042 [iv nt sb bl ov]"
    );

    let f = Asdu::new(TypeId::M_ME_NC_1, Cause::SPONTANEOUS, ca1())
        .with_object(float_object(5200, 0x4248_0006));
    check(&FLOAT_F, &P104, &f);
    assert_eq!(
        f.objects[0].element.to_string(),
        "50.000023 [iv nt sb bl ov]"
    );
}

#[test]
fn display_matches_the_analyser_style() {
    let asdu = Asdu::decode(&DP_TB_OFF, &P104).unwrap();
    assert_eq!(
        asdu.to_string(),
        "M_DP_TB_1 (31) [sq=0 n=1] cot=spont(3) [tst pn] oa=0 ca=1\n  \
         ioa=2000 DP OFF [iv nt sb bl] 2017-04-26 09:59:30.424 [IV]"
    );
    let negative = Asdu::new(
        TypeId::C_SC_NA_1,
        Cot::new(Cause::UNKNOWN_CAUSE).negative().test(),
        ca1(),
    )
    .with_object(InformationObject::new(
        ioa(4150),
        Element::SingleCommand {
            on: true,
            qualifier: CommandQualifier::SELECT,
        },
    ));
    assert_eq!(
        negative.to_string(),
        "C_SC_NA_1 (45) [sq=0 n=1] cot=unknown cause(45) [TST PN] oa=0 ca=1\n  \
         ioa=4150 SCO ON select qu=0"
    );
}

// ---- derived vectors, one per element family (standard encodings) ----

/// CP56 2017-04-26 09:59:30.424 without flags, day of week 3 (Wednesday).
const T: [u8; 7] = [0xD8, 0x76, 0x3B, 0x09, 0x7A, 0x04, 0x11];

fn with_time(prefix: &[u8], suffix: &[u8]) -> Vec<u8> {
    let mut bytes = prefix.to_vec();
    bytes.extend_from_slice(suffix);
    bytes
}

#[test]
fn single_points_sequence() {
    // Station points 281..283 answering a GI: SQ=1, n=3, COT 20.
    let bytes = [
        0x01, 0x83, 0x14, 0x00, 0x01, 0x00, 0x19, 0x01, 0x00, 0x01, 0x00, 0x81,
    ];
    let asdu = round_trip(&bytes, &P104);
    assert!(asdu.sequence);
    assert_eq!(asdu.cot.cause, Cause::INTERROGATED_BY_STATION);
    let addresses: Vec<u32> = asdu.objects.iter().map(|o| o.ioa.get()).collect();
    assert_eq!(addresses, [281, 282, 283]);
    assert_eq!(
        asdu.objects[2].element,
        Element::SinglePoint {
            on: true,
            quality: Quality::INVALID
        }
    );
    assert_eq!(
        asdu.to_string().lines().nth(3).unwrap(),
        "  ioa=283 SP ON [IV nt sb bl]"
    );
}

#[test]
fn single_point_with_cp56() {
    let bytes = with_time(
        &[0x1E, 0x01, 0x03, 0x00, 0x01, 0x00, 0x19, 0x01, 0x00, 0x31],
        &T,
    );
    let asdu = round_trip(&bytes, &P104);
    let object = &asdu.objects[0];
    assert_eq!(
        object.element,
        Element::SinglePoint {
            on: true,
            quality: Quality {
                substituted: true,
                blocked: true,
                ..Quality::GOOD
            }
        }
    );
    let time = object.time.unwrap();
    assert_eq!(time.as_cp56().unwrap().day_of_week(), 3);
    assert_eq!(time.to_string(), "2017-04-26 09:59:30.424");
}

#[test]
fn step_position() {
    let bytes = [
        0x05, 0x01, 0x03, 0x00, 0x01, 0x00, 0x10, 0x00, 0x00, 0xFB, 0x01,
    ];
    let asdu = round_trip(&bytes, &P104);
    let Element::StepPosition { position, quality } = asdu.objects[0].element else {
        panic!()
    };
    assert_eq!((position.value(), position.is_transient()), (-5, true));
    assert!(quality.overflow);
    let tagged = with_time(
        &[
            0x20, 0x01, 0x03, 0x00, 0x01, 0x00, 0x10, 0x00, 0x00, 0x3F, 0x00,
        ],
        &T,
    );
    round_trip(&tagged, &P104);
}

#[test]
fn bitstrings() {
    let bytes = [
        0x07, 0x01, 0x03, 0x00, 0x01, 0x00, 0x20, 0x00, 0x00, 0x78, 0x56, 0x34, 0x12, 0x00,
    ];
    let asdu = round_trip(&bytes, &P104);
    assert_eq!(
        asdu.objects[0].element,
        Element::Bitstring {
            bits: 0x1234_5678,
            quality: Quality::GOOD
        }
    );
    round_trip(
        &with_time(
            &[
                0x21, 0x01, 0x03, 0x00, 0x01, 0x00, 0x20, 0x00, 0x00, 1, 2, 3, 4, 0x80,
            ],
            &T,
        ),
        &P104,
    );
    let command = [
        0x33, 0x01, 0x06, 0x00, 0x01, 0x00, 0x20, 0x00, 0x00, 0x78, 0x56, 0x34, 0x12,
    ];
    let asdu = round_trip(&command, &P104);
    assert_eq!(
        asdu.objects[0].element,
        Element::BitstringCommand { bits: 0x1234_5678 }
    );
    round_trip(
        &with_time(
            &[
                0x40, 0x01, 0x06, 0x00, 0x01, 0x00, 0x20, 0x00, 0x00, 1, 2, 3, 4,
            ],
            &T,
        ),
        &P104,
    );
}

#[test]
fn measured_values_all_kinds() {
    // Scaled -100 with OV and IV.
    let scaled = [
        0x0B, 0x01, 0x03, 0x00, 0x01, 0x00, 0x10, 0x00, 0x00, 0x9C, 0xFF, 0x81,
    ];
    let asdu = round_trip(&scaled, &P104);
    let Element::Scaled { value, quality } = asdu.objects[0].element else {
        panic!()
    };
    assert_eq!(value, -100);
    assert!(quality.invalid && quality.overflow);
    // Normalized and scaled and float with CP56.
    round_trip(
        &with_time(
            &[
                0x22, 0x01, 0x03, 0x00, 0x01, 0x00, 0x10, 0x00, 0x00, 0xE5, 0x2A, 0x00,
            ],
            &T,
        ),
        &P104,
    );
    round_trip(
        &with_time(
            &[
                0x23, 0x01, 0x03, 0x00, 0x01, 0x00, 0x10, 0x00, 0x00, 0x9C, 0xFF, 0x00,
            ],
            &T,
        ),
        &P104,
    );
    let float_tagged = with_time(
        &[
            0x24, 0x01, 0x03, 0x00, 0x01, 0x00, 0x88, 0x13, 0x00, 0x0E, 0x81, 0xE8, 0x49, 0x00,
        ],
        &T,
    );
    let asdu = round_trip(&float_tagged, &P104);
    assert_eq!(asdu.type_id, TypeId::M_ME_TF_1);
    // M_ME_ND_1 has no quality descriptor.
    let no_quality = [
        0x15, 0x02, 0x14, 0x00, 0x01, 0x00, 0x4C, 0x04, 0x00, 0xE5, 0x2A, 0xB0, 0x04, 0x00, 0xEA,
        0x2A,
    ];
    let asdu = round_trip(&no_quality, &P104);
    assert_eq!(
        asdu.objects[1].element,
        Element::Normalized {
            raw: 10986,
            quality: Quality::GOOD
        }
    );
}

#[test]
fn integrated_totals() {
    let bytes = [
        0x0F, 0x01, 0x25, 0x00, 0x01, 0x00, 0x00, 0x10, 0x00, 0x39, 0x30, 0x00, 0x00, 0x63,
    ];
    let asdu = round_trip(&bytes, &P104);
    assert_eq!(asdu.cot.cause, Cause::REQUESTED_BY_GENERAL_COUNTER);
    let Element::IntegratedTotal(reading) = asdu.objects[0].element else {
        panic!()
    };
    assert_eq!(reading.value(), 12345);
    assert_eq!(reading.sequence(), 3);
    assert!(reading.is_carry() && reading.is_adjusted() && !reading.is_invalid());
    round_trip(
        &with_time(
            &[
                0x25, 0x01, 0x03, 0x00, 0x01, 0x00, 0x00, 0x10, 0x00, 1, 0, 0, 0, 0x80,
            ],
            &T,
        ),
        &P104,
    );
}

#[test]
fn protection_equipment() {
    // M_EP_TD_1: SEP = ON + EI, elapsed 1000 ms.
    let event = with_time(
        &[
            0x26, 0x01, 0x03, 0x00, 0x01, 0x00, 0x10, 0x00, 0x00, 0x0A, 0xE8, 0x03,
        ],
        &T,
    );
    let asdu = round_trip(&event, &P104);
    let Element::ProtectionEvent {
        state,
        quality,
        elapsed,
    } = asdu.objects[0].element
    else {
        panic!()
    };
    assert_eq!(state, DoublePointState::On);
    assert!(quality.elapsed_invalid);
    assert_eq!(elapsed.millisecond(), 1000);
    // M_EP_TE_1: general start + L1, QDP IV.
    let starts = with_time(
        &[
            0x27, 0x01, 0x03, 0x00, 0x01, 0x00, 0x10, 0x00, 0x00, 0x03, 0x80, 0x64, 0x00,
        ],
        &T,
    );
    let asdu = round_trip(&starts, &P104);
    let Element::ProtectionStartEvents {
        events, quality, ..
    } = asdu.objects[0].element
    else {
        panic!()
    };
    assert!(events.general && events.l1 && !events.l2);
    assert!(quality.quality.invalid);
    // M_EP_TF_1: general command to the output circuit.
    let output = with_time(
        &[
            0x28, 0x01, 0x03, 0x00, 0x01, 0x00, 0x10, 0x00, 0x00, 0x01, 0x00, 0x32, 0x00,
        ],
        &T,
    );
    round_trip(&output, &P104);
    // A CP16 elapsed time out of range is refused.
    let mut bad = event.clone();
    bad[10] = 0x60;
    bad[11] = 0xEA;
    assert!(matches!(Asdu::decode(&bad, &P104), Err(AsduError::Time(_))));
}

#[test]
fn cp24_types_on_a_101_link() {
    let params = AsduParams::IEC101_DEFAULT;
    // M_SP_TA_1, COT 1 octet, CA 1 octet, IOA 2 octets: IOA 1000, ON, minute 59 30.424 s.
    let bytes = [0x02, 0x01, 0x03, 0x01, 0xE8, 0x03, 0x01, 0xD8, 0x76, 0x3B];
    let asdu = round_trip(&bytes, &params);
    let object = &asdu.objects[0];
    assert_eq!(object.ioa.get(), 1000);
    assert_eq!(object.time.unwrap().to_string(), "59:30.424");
    // M_EP_TA_1 with CP16 and CP24.
    round_trip(
        &[
            0x11, 0x01, 0x03, 0x01, 0xE8, 0x03, 0x01, 0x10, 0x00, 0xD8, 0x76, 0x3B,
        ],
        &params,
    );
    // M_ME_TC_1.
    round_trip(
        &[
            0x0E, 0x01, 0x03, 0x01, 0xE8, 0x03, 0x00, 0x00, 0x48, 0x42, 0x00, 0xD8, 0x76, 0x3B,
        ],
        &params,
    );
}

#[test]
fn packed_single_points() {
    let bytes = [
        0x14, 0x01, 0x14, 0x00, 0x01, 0x00, 0x00, 0x20, 0x00, 0xFF, 0x00, 0x01, 0x00, 0x00,
    ];
    let asdu = round_trip(&bytes, &P104);
    assert_eq!(
        asdu.objects[0].element,
        Element::PackedSinglePoints {
            status: 0x00FF,
            change: 0x0001,
            quality: Quality::GOOD
        }
    );
}

#[test]
fn commands() {
    // C_RC_NA_1: select, next step higher.
    let asdu = round_trip(
        &[0x2F, 0x01, 0x06, 0x00, 0x01, 0x00, 0x10, 0x00, 0x00, 0x82],
        &P104,
    );
    assert_eq!(
        asdu.objects[0].element,
        Element::RegulatingStep {
            state: RegulatingStepState::Higher,
            qualifier: CommandQualifier::SELECT
        }
    );
    // C_SE_NA_1 select 0x2AE5, C_SE_NB_1 execute -100, C_SE_NC_1 execute 50.0.
    let asdu = round_trip(
        &[
            0x30, 0x01, 0x06, 0x00, 0x01, 0x00, 0x10, 0x00, 0x00, 0xE5, 0x2A, 0x80,
        ],
        &P104,
    );
    assert_eq!(
        asdu.objects[0].element,
        Element::SetpointNormalized {
            raw: 10981,
            qualifier: SetpointQualifier::SELECT
        }
    );
    round_trip(
        &[
            0x31, 0x01, 0x06, 0x00, 0x01, 0x00, 0x10, 0x00, 0x00, 0x9C, 0xFF, 0x00,
        ],
        &P104,
    );
    let asdu = round_trip(
        &[
            0x32, 0x01, 0x06, 0x00, 0x01, 0x00, 0x10, 0x00, 0x00, 0x00, 0x00, 0x48, 0x42, 0x00,
        ],
        &P104,
    );
    assert_eq!(
        asdu.objects[0].element,
        Element::SetpointFloat {
            value: 50.0,
            qualifier: SetpointQualifier::EXECUTE
        }
    );
    // C_SC_TA_1: ON, short pulse, execute, with CP56.
    let asdu = round_trip(
        &with_time(
            &[0x3A, 0x01, 0x06, 0x00, 0x01, 0x00, 0x36, 0x10, 0x00, 0x05],
            &T,
        ),
        &P104,
    );
    assert_eq!(
        asdu.objects[0].element,
        Element::SingleCommand {
            on: true,
            qualifier: CommandQualifier::new(CommandQualifier::QU_SHORT_PULSE, false).unwrap()
        }
    );
    for type_byte in [0x3B, 0x3C] {
        round_trip(
            &with_time(
                &[
                    type_byte, 0x01, 0x06, 0x00, 0x01, 0x00, 0x34, 0x08, 0x00, 0x81,
                ],
                &T,
            ),
            &P104,
        );
    }
    for type_byte in [0x3D, 0x3E] {
        round_trip(
            &with_time(
                &[
                    type_byte, 0x01, 0x06, 0x00, 0x01, 0x00, 0x34, 0x08, 0x00, 1, 2, 3,
                ],
                &T,
            ),
            &P104,
        );
    }
    round_trip(
        &with_time(
            &[
                0x3F, 0x01, 0x06, 0x00, 0x01, 0x00, 0x34, 0x08, 0x00, 0, 0, 0x48, 0x42, 0x80,
            ],
            &T,
        ),
        &P104,
    );
    // DCS 0 and 3 are not permitted but must decode, for the server to refuse them.
    let asdu = round_trip(
        &[0x2E, 0x01, 0x06, 0x00, 0x01, 0x00, 0x34, 0x08, 0x00, 0x03],
        &P104,
    );
    assert_eq!(
        asdu.objects[0].element,
        Element::DoubleCommand {
            state: DoublePointState::Indeterminate,
            qualifier: CommandQualifier::EXECUTE
        }
    );
}

#[test]
fn system_information() {
    // M_EI_NA_1: local power on, COT 4.
    let asdu = round_trip(
        &[0x46, 0x01, 0x04, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00],
        &P104,
    );
    assert_eq!(
        asdu.objects[0].element,
        Element::EndOfInitialisation {
            cause: InitialisationCause::LOCAL_POWER_ON,
            after_parameter_change: false
        }
    );
    round_trip(
        &[0x46, 0x01, 0x04, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x82],
        &P104,
    );
    // C_IC_NA_1: station interrogation, activation.
    let asdu = round_trip(
        &[0x64, 0x01, 0x06, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x14],
        &P104,
    );
    assert_eq!(
        asdu.objects[0].element,
        Element::Interrogation {
            qualifier: InterrogationQualifier::STATION
        }
    );
    assert_eq!(
        asdu.to_string(),
        "C_IC_NA_1 (100) [sq=0 n=1] cot=act(6) [tst pn] oa=0 ca=1\n  ioa=0 QOI 20 (station)"
    );
    // C_CI_NA_1: general request, freeze without reset.
    let asdu = round_trip(
        &[0x65, 0x01, 0x06, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x45],
        &P104,
    );
    assert_eq!(
        asdu.objects[0].element,
        Element::CounterInterrogation {
            request: CounterInterrogationQualifier::REQUEST_GENERAL,
            freeze: CounterInterrogationQualifier::FREEZE
        }
    );
    // C_RD_NA_1: only the address.
    let asdu = round_trip(
        &[0x66, 0x01, 0x05, 0x00, 0x01, 0x00, 0xD0, 0x07, 0x00],
        &P104,
    );
    assert_eq!(asdu.objects[0].element, Element::Read);
    assert_eq!(asdu.to_string().lines().nth(1).unwrap(), "  ioa=2000 READ");
    // C_CS_NA_1: the time is the element.
    let asdu = round_trip(
        &with_time(&[0x67, 0x01, 0x06, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00], &T),
        &P104,
    );
    assert_eq!(asdu.objects[0].time, None);
    assert_eq!(
        asdu.objects[0].element,
        Element::ClockSync { time: cp56(T) }
    );
    // C_TS_NA_1 with the fixed pattern 0x55AA.
    let asdu = round_trip(
        &[
            0x68, 0x01, 0x06, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0xAA, 0x55,
        ],
        &P104,
    );
    assert_eq!(asdu.objects[0].element, Element::Test { pattern: 0x55AA });
    // C_RP_NA_1, C_CD_NA_1.
    round_trip(
        &[0x69, 0x01, 0x06, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x01],
        &P104,
    );
    let asdu = round_trip(
        &[
            0x6A, 0x01, 0x06, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0xE8, 0x03,
        ],
        &P104,
    );
    assert_eq!(asdu.objects[0].element.to_string(), "1.000 s");
    // C_TS_TA_1: counter then CP56 in `time`.
    let asdu = round_trip(
        &with_time(
            &[
                0x6B, 0x01, 0x06, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x34, 0x12,
            ],
            &T,
        ),
        &P104,
    );
    assert_eq!(
        asdu.objects[0].element,
        Element::TestWithTime { counter: 0x1234 }
    );
    assert_eq!(asdu.objects[0].time, Some(TimeTag::Cp56(cp56(T))));
}

#[test]
fn parameters() {
    let asdu = round_trip(
        &[
            0x6E, 0x01, 0x06, 0x00, 0x01, 0x00, 0x10, 0x00, 0x00, 0x64, 0x00, 0x01,
        ],
        &P104,
    );
    assert_eq!(
        asdu.objects[0].element,
        Element::ParameterNormalized {
            raw: 100,
            qualifier: ParameterQualifier::THRESHOLD
        }
    );
    round_trip(
        &[
            0x6F, 0x01, 0x06, 0x00, 0x01, 0x00, 0x10, 0x00, 0x00, 0x64, 0x00, 0x44,
        ],
        &P104,
    );
    round_trip(
        &[
            0x70, 0x01, 0x06, 0x00, 0x01, 0x00, 0x10, 0x00, 0x00, 0x00, 0x00, 0x48, 0x42, 0x83,
        ],
        &P104,
    );
    let asdu = round_trip(
        &[0x71, 0x01, 0x06, 0x00, 0x01, 0x00, 0x10, 0x00, 0x00, 0x03],
        &P104,
    );
    assert_eq!(
        asdu.objects[0].element,
        Element::ParameterActivation {
            qualifier: ParameterActivationQualifier::CYCLIC_TRANSMISSION
        }
    );
    let qpm = ParameterQualifier::from_bits(0x44);
    assert_eq!(qpm.kind(), ParameterQualifier::HIGH_LIMIT);
    assert!(qpm.local_change && !qpm.not_in_operation);
}

#[test]
fn file_transfer() {
    let head = [0x00, 0x0D, 0x00, 0x01, 0x00, 0x10, 0x00, 0x00];
    let vector = |type_byte: u8, count: u8, body: &[u8]| {
        let mut bytes = vec![type_byte, count];
        bytes.extend_from_slice(&head[1..]);
        bytes.extend_from_slice(body);
        bytes
    };
    // F_FR_NA_1: file 1, 10000 octets, positive.
    let asdu = round_trip(
        &vector(0x78, 1, &[0x01, 0x00, 0x10, 0x27, 0x00, 0x00]),
        &P104,
    );
    assert_eq!(
        asdu.objects[0].element,
        Element::FileReady {
            file: 1,
            length: 10000,
            qualifier: 0
        }
    );
    // F_SR_NA_1: section 2 of 300 octets, not ready.
    let asdu = round_trip(
        &vector(0x79, 1, &[0x01, 0x00, 0x02, 0x2C, 0x01, 0x00, 0x80]),
        &P104,
    );
    assert_eq!(
        asdu.objects[0].element,
        Element::SectionReady {
            file: 1,
            section: 2,
            length: 300,
            qualifier: FileQualifier::NEGATIVE
        }
    );
    // F_SC_NA_1: request section.
    round_trip(&vector(0x7A, 1, &[0x01, 0x00, 0x02, 0x06]), &P104);
    // F_LS_NA_1: last segment, checksum 0x5A.
    let asdu = round_trip(&vector(0x7B, 1, &[0x01, 0x00, 0x02, 0x03, 0x5A]), &P104);
    assert_eq!(
        asdu.objects[0].element,
        Element::LastSegmentOrSection {
            file: 1,
            section: 2,
            qualifier: FileQualifier::SECTION_TRANSFER_DONE,
            checksum: 0x5A
        }
    );
    // F_AF_NA_1: negative ack of the section with error "checksum failed".
    let asdu = round_trip(&vector(0x7C, 1, &[0x01, 0x00, 0x02, 0x24]), &P104);
    let Element::AckFileOrSection { qualifier, .. } = asdu.objects[0].element else {
        panic!()
    };
    assert_eq!(
        FileQualifier::action(qualifier),
        FileQualifier::NACK_SECTION
    );
    assert_eq!(FileQualifier::error(qualifier), 2);
    // F_SG_NA_1: three octets of data; two segments in one ASDU.
    let asdu = round_trip(
        &vector(0x7D, 1, &[0x01, 0x00, 0x02, 0x03, 0xAA, 0xBB, 0xCC]),
        &P104,
    );
    assert_eq!(
        asdu.objects[0].element,
        Element::Segment {
            file: 1,
            section: 2,
            data: vec![0xAA, 0xBB, 0xCC]
        }
    );
    round_trip(
        &vector(
            0x7D,
            2,
            &[
                0x01, 0x00, 0x02, 0x01, 0xAA, 0x11, 0x00, 0x00, 0x02, 0x00, 0x01, 0x02, 0xBB, 0xCC,
            ],
        ),
        &P104,
    );
    // A segment whose LOS runs past the end is truncated, not read out of bounds.
    assert!(matches!(
        Asdu::decode(&vector(0x7D, 1, &[0x01, 0x00, 0x02, 0x09, 0xAA]), &P104),
        Err(AsduError::Truncated { .. })
    ));
    // F_DR_TA_1 with SQ=1: two directory entries, the second the last file.
    let mut directory = vec![0x7E, 0x82];
    directory.extend_from_slice(&head[1..]);
    directory.extend_from_slice(&[0x01, 0x00, 0x10, 0x27, 0x00, 0x00]);
    directory.extend_from_slice(&T);
    directory.extend_from_slice(&[0x02, 0x00, 0x2C, 0x01, 0x00, FileQualifier::LAST_FILE]);
    directory.extend_from_slice(&T);
    let asdu = round_trip(&directory, &P104);
    assert_eq!(asdu.objects[1].ioa.get(), 17);
    assert_eq!(
        asdu.objects[1].element,
        Element::Directory {
            file: 2,
            length: 300,
            status: FileQualifier::LAST_FILE
        }
    );
    // F_SC_NB_1: query log from T to T.
    let mut query = vector(0x7F, 1, &[0x01, 0x00]);
    query.extend_from_slice(&T);
    query.extend_from_slice(&T);
    let asdu = round_trip(&query, &P104);
    assert_eq!(
        asdu.objects[0].element,
        Element::QueryLog {
            file: 1,
            start: cp56(T),
            stop: cp56(T)
        }
    );
}

#[test]
fn one_octet_fields() {
    let params = AsduParams::try_new(1, 1, 1, 200).unwrap();
    let bytes = [0x01, 0x82, 0x03, 0x07, 0xFE, 0x01, 0x00];
    let asdu = round_trip(&bytes, &params);
    assert_eq!(asdu.common_address.get(), 7);
    assert_eq!(asdu.objects[1].ioa.get(), 0xFF);
    // SQ=1 past the one-octet address range.
    let past = [0x01, 0x83, 0x03, 0x07, 0xFE, 0x01, 0x00, 0x00];
    assert_eq!(
        Asdu::decode(&past, &params),
        Err(AsduError::IoaOverflow {
            base: 0xFE,
            count: 3
        })
    );
    // The originator octet is present with COT 2.
    let params = AsduParams::try_new(2, 1, 2, 200).unwrap();
    let asdu = round_trip(&[0x2D, 0x01, 0x86, 0x09, 0x05, 0x36, 0x10, 0x81], &params);
    assert_eq!(
        asdu.cot,
        Cot::new(Cause::ACTIVATION).test().with_originator(9)
    );
}

// ---- hardening ----

#[test]
fn truncated_header() {
    for len in 0..6 {
        assert_eq!(
            Asdu::decode(&DP_TB_OFF[..len], &P104),
            Err(AsduError::Truncated {
                needed: 6,
                available: len
            })
        );
        assert!(AsduHeader::decode(&DP_TB_OFF[..len], &P104).is_err());
    }
}

#[test]
fn every_truncation_is_an_error() {
    let vectors: [&[u8]; 4] = [&DP_TB_OFF, &FLOAT_P_AND_F, &DC_COT5, &NORMALIZED[4].0];
    for bytes in vectors {
        for len in 0..bytes.len() {
            assert!(Asdu::decode(&bytes[..len], &P104).is_err(), "{len}");
        }
    }
}

#[test]
fn count_size_mismatch() {
    // VSQ says 2 objects, there is one.
    let mut bytes = NORMALIZED[1].0;
    bytes[1] = 0x02;
    assert_eq!(
        Asdu::decode(&bytes, &P104),
        Err(AsduError::ObjectCountMismatch {
            count: 2,
            expected: 18,
            actual: 12
        })
    );
    // VSQ says 1, there are 2.
    let mut two = FLOAT_P_AND_F;
    two[1] = 0x01;
    assert_eq!(Asdu::decode(&two, &P104), Err(AsduError::TrailingBytes(8)));
    // Count 0.
    let mut none = DC_COT5;
    none[1] = 0x00;
    assert_eq!(Asdu::decode(&none, &P104), Err(AsduError::NoObjects));
}

#[test]
fn sequence_too_short_for_its_address() {
    let bytes = [0x01, 0x81, 0x14, 0x00, 0x01, 0x00, 0x19, 0x01];
    assert_eq!(
        Asdu::decode(&bytes, &P104),
        Err(AsduError::Truncated {
            needed: 9,
            available: 8
        })
    );
    // Address present but the elements are missing.
    let bytes = [0x01, 0x83, 0x14, 0x00, 0x01, 0x00, 0x19, 0x01, 0x00, 0x01];
    assert!(matches!(
        Asdu::decode(&bytes, &P104),
        Err(AsduError::ObjectCountMismatch { count: 3, .. })
    ));
    // Addresses past 0xFFFFFF.
    let bytes = [
        0x01, 0x82, 0x14, 0x00, 0x01, 0x00, 0xFF, 0xFF, 0xFF, 0x01, 0x00,
    ];
    assert_eq!(
        Asdu::decode(&bytes, &P104),
        Err(AsduError::IoaOverflow {
            base: 0xFF_FFFF,
            count: 2
        })
    );
    // SQ=1 is impossible for variable-length segments.
    let bytes = [
        0x7D, 0x81, 0x0D, 0x00, 0x01, 0x00, 0x10, 0x00, 0x00, 0x01, 0x00, 0x02, 0x00,
    ];
    assert_eq!(
        Asdu::decode(&bytes, &P104),
        Err(AsduError::SequenceNotAllowed(TypeId::F_SG_NA_1))
    );
}

#[test]
fn trailing_bytes() {
    let mut bytes = DC_COT5.to_vec();
    bytes.push(0x00);
    assert_eq!(
        Asdu::decode(&bytes, &P104),
        Err(AsduError::TrailingBytes(1))
    );
    let mut segment = vec![
        0x7D, 0x01, 0x0D, 0x00, 0x01, 0x00, 0x10, 0x00, 0x00, 0x01, 0x00, 0x02, 0x01, 0xAA,
    ];
    assert!(Asdu::decode(&segment, &P104).is_ok());
    segment.extend_from_slice(&[1, 2]);
    assert_eq!(
        Asdu::decode(&segment, &P104),
        Err(AsduError::TrailingBytes(2))
    );
}

#[test]
fn unknown_type_keeps_its_header() {
    let bytes = [0x16, 0x01, 0x06, 0x03, 0x01, 0x00, 0x00, 0x00, 0x00, 0x14];
    assert_eq!(
        Asdu::decode(&bytes, &P104),
        Err(AsduError::UnknownTypeId(22))
    );
    let header = AsduHeader::decode(&bytes, &P104).unwrap();
    assert_eq!(header.type_byte, 22);
    assert_eq!(header.type_id(), None);
    assert_eq!(header.cot, Cot::new(Cause::ACTIVATION).with_originator(3));
    assert_eq!(
        header.to_string(),
        "unknown (22) [sq=0 n=1] cot=act(6) [tst pn] oa=3 ca=1"
    );
    // The negative confirmation mirrors everything but the cause and P/N.
    let reply = mirror_with_cause(&bytes, &P104, Cause::UNKNOWN_TYPE, true).unwrap();
    assert_eq!(
        reply,
        [0x16, 0x01, 0x6C, 0x03, 0x01, 0x00, 0x00, 0x00, 0x00, 0x14]
    );
    // Also for a known type: COT 5 command refused with COT 45, T bit kept.
    let mut test_command = SC_COT5;
    test_command[2] |= 0x80;
    let reply = mirror_with_cause(&test_command, &P104, Cause::UNKNOWN_CAUSE, true).unwrap();
    assert_eq!(reply[2], 0x80 | 0x40 | 45);
    assert_eq!(&reply[3..], &test_command[3..]);
    let confirmation = mirror_with_cause(&SC_COT5, &P104, Cause::ACTIVATION_CON, false).unwrap();
    assert_eq!(
        Asdu::decode(&confirmation, &P104).unwrap().cot,
        Cot::new(Cause::ACTIVATION_CON)
    );
    assert!(mirror_with_cause(&bytes[..5], &P104, Cause::UNKNOWN_TYPE, true).is_err());
}

#[test]
fn time_fields_out_of_range() {
    let cases: [(usize, u8, &str); 5] = [
        (12, 0xBC, "minute"), // minute 60 with IV
        (13, 24, "hour"),
        (14, 0x00, "day"),
        (15, 13, "month"),
        (16, 100, "year"),
    ];
    for (offset, value, field) in cases {
        let mut bytes = DP_TB_OFF;
        bytes[offset] = value;
        match Asdu::decode(&bytes, &P104) {
            Err(AsduError::Time(TimeError::OutOfRange { field: found, .. })) => {
                assert_eq!(found, field);
            }
            other => panic!("{field}: {other:?}"),
        }
    }
    let mut bytes = DP_TB_OFF;
    bytes[10] = 0x60; // 60000 ms
    bytes[11] = 0xEA;
    assert!(matches!(
        Asdu::decode(&bytes, &P104),
        Err(AsduError::Time(TimeError::OutOfRange {
            field: "millisecond",
            ..
        }))
    ));
    // Day of week 0 and 7 are both fine.
    let mut bytes = DP_TB_OFF;
    bytes[14] = 0xFA;
    assert_eq!(
        Asdu::decode(&bytes, &P104).unwrap().objects[0]
            .time
            .unwrap()
            .as_cp56()
            .unwrap()
            .day_of_week(),
        7
    );
}

fn single_points(count: u32) -> Asdu {
    let mut asdu = Asdu::new(TypeId::M_SP_NA_1, Cause::SPONTANEOUS, ca1());
    for n in 0..count {
        asdu.push(InformationObject::new(
            ioa(100 + 2 * n),
            Element::SinglePoint {
                on: n % 2 == 0,
                quality: Quality::GOOD,
            },
        ));
    }
    asdu
}

#[test]
fn oversize_encode() {
    // 6 + 60 × 4 = 246 fits 249; 61 objects make 250.
    assert_eq!(single_points(60).to_bytes(&P104).unwrap().len(), 246);
    let mut out = vec![1, 2, 3];
    assert_eq!(
        single_points(61).encode(&P104, &mut out),
        Err(AsduError::TooLong { len: 250, max: 249 })
    );
    assert_eq!(out, [1, 2, 3], "a failed encode leaves the buffer alone");
    let params = AsduParams::try_new(2, 2, 3, 255).unwrap();
    assert!(single_points(61).to_bytes(&params).is_ok());
    // More than 127 objects never fit the VSQ, even with SQ=1.
    let mut many = Asdu::new(TypeId::M_SP_NA_1, Cause::SPONTANEOUS, ca1()).with_sequence(true);
    for n in 0..128 {
        many.push(InformationObject::new(
            ioa(n),
            Element::SinglePoint {
                on: true,
                quality: Quality::GOOD,
            },
        ));
    }
    assert_eq!(many.to_bytes(&P104), Err(AsduError::TooManyObjects(128)));
    many.objects.pop();
    assert_eq!(many.to_bytes(&P104).unwrap().len(), 6 + 3 + 127);
}

#[test]
fn encode_refuses_inconsistent_asdus() {
    let point = InformationObject::new(
        ioa(1),
        Element::SinglePoint {
            on: true,
            quality: Quality::GOOD,
        },
    );
    // Element of another family.
    let wrong = Asdu::new(TypeId::M_DP_NA_1, Cause::SPONTANEOUS, ca1()).with_object(point.clone());
    assert_eq!(
        wrong.to_bytes(&P104),
        Err(AsduError::ElementMismatch {
            type_id: TypeId::M_DP_NA_1,
            ioa: ioa(1)
        })
    );
    // Missing, superfluous and wrong time tags.
    let missing =
        Asdu::new(TypeId::M_SP_TB_1, Cause::SPONTANEOUS, ca1()).with_object(point.clone());
    assert!(matches!(
        missing.to_bytes(&P104),
        Err(AsduError::TimeTagMismatch { .. })
    ));
    let mut tagged = point.clone();
    tagged.time = Some(TimeTag::Cp56(cp56(T)));
    let superfluous = Asdu::new(TypeId::M_SP_NA_1, Cause::SPONTANEOUS, ca1()).with_object(tagged);
    assert!(matches!(
        superfluous.to_bytes(&P104),
        Err(AsduError::TimeTagMismatch { .. })
    ));
    let mut short = point.clone();
    short.time = Some(TimeTag::Cp24(Cp24Time2a::new(1, 2).unwrap()));
    let cp24 = Asdu::new(TypeId::M_SP_TB_1, Cause::SPONTANEOUS, ca1()).with_object(short);
    assert!(matches!(
        cp24.to_bytes(&P104),
        Err(AsduError::TimeTagMismatch { .. })
    ));
    // SQ=1 with a gap.
    let gap = single_points(2).with_sequence(true);
    assert_eq!(
        gap.to_bytes(&P104),
        Err(AsduError::NotConsecutive {
            expected: 101,
            found: ioa(102)
        })
    );
    // Empty.
    let empty = Asdu::new(TypeId::M_SP_NA_1, Cause::SPONTANEOUS, ca1());
    assert_eq!(empty.to_bytes(&P104), Err(AsduError::NoObjects));
    // Field sizes of a 101 link.
    let params = AsduParams::IEC101_DEFAULT;
    let mut far = point.clone();
    far.ioa = ioa(0x1_0000);
    let far = Asdu::new(TypeId::M_SP_NA_1, Cause::SPONTANEOUS, ca1()).with_object(far);
    assert!(matches!(
        far.to_bytes(&params),
        Err(AsduError::IoaTooLarge { size: 2, .. })
    ));
    let big_ca = Asdu::new(
        TypeId::M_SP_NA_1,
        Cause::SPONTANEOUS,
        CommonAddress::new(256),
    )
    .with_object(point.clone());
    assert!(matches!(
        big_ca.to_bytes(&params),
        Err(AsduError::CommonAddressTooLarge { size: 1, .. })
    ));
    let originator = Asdu::new(
        TypeId::M_SP_NA_1,
        Cot::new(Cause::SPONTANEOUS).with_originator(3),
        ca1(),
    )
    .with_object(point);
    assert_eq!(
        originator.to_bytes(&params),
        Err(AsduError::OriginatorNotEncodable(3))
    );
    // Element values beyond their fields.
    let qcc =
        Asdu::new(TypeId::C_CI_NA_1, Cause::ACTIVATION, ca1()).with_object(InformationObject::new(
            ioa(0),
            Element::CounterInterrogation {
                request: 64,
                freeze: 0,
            },
        ));
    assert!(matches!(qcc.to_bytes(&P104), Err(AsduError::Range(_))));
    let segment = Asdu::new(TypeId::F_SG_NA_1, Cause::FILE_TRANSFER, ca1()).with_object(
        InformationObject::new(
            ioa(0),
            Element::Segment {
                file: 1,
                section: 1,
                data: vec![0; 256],
            },
        ),
    );
    assert!(segment
        .to_bytes(&AsduParams::try_new(2, 2, 3, 255).unwrap())
        .is_err());
    let file = Asdu::new(TypeId::F_FR_NA_1, Cause::FILE_TRANSFER, ca1()).with_object(
        InformationObject::new(
            ioa(0),
            Element::FileReady {
                file: 1,
                length: 0x100_0000,
                qualifier: 0,
            },
        ),
    );
    let mut out = Vec::new();
    assert!(matches!(
        file.encode(&P104, &mut out),
        Err(AsduError::Range(_))
    ));
    assert!(out.is_empty(), "a failed encode leaves the buffer alone");
}

#[test]
fn broadcast_addresses() {
    assert_eq!(CommonAddress::broadcast(&P104).get(), 0xFFFF);
    assert_eq!(
        CommonAddress::broadcast(&AsduParams::IEC101_DEFAULT).get(),
        0xFF
    );
    assert!(CommonAddress::new(0xFFFF).is_broadcast(&P104));
    assert!(!CommonAddress::new(0xFF).is_broadcast(&P104));
    assert!(Ioa::try_new(0x100_0000).is_err());
    assert_eq!(Ioa::try_from(0xFF_FFFFu32).unwrap(), Ioa::MAX);
}

#[test]
fn object_lengths_match_the_pitfalls_table() {
    // Objects per 249-octet ASDU, from iec60870-pitfalls.md.
    let per_asdu = |type_id: TypeId, sequence: bool| {
        let room = 249 - 6 - if sequence { 3 } else { 0 };
        (room / object_len(type_id, &P104, sequence)).min(127)
    };
    assert_eq!(per_asdu(TypeId::M_SP_NA_1, false), 60);
    assert_eq!(per_asdu(TypeId::M_SP_NA_1, true), 127);
    assert_eq!(per_asdu(TypeId::M_ME_NC_1, false), 30);
    assert_eq!(per_asdu(TypeId::M_ME_NC_1, true), 48);
    assert_eq!(per_asdu(TypeId::M_SP_TB_1, false), 22);
    assert_eq!(per_asdu(TypeId::M_ME_TF_1, false), 16);
}

// ---- packing ----

fn float_points(addresses: impl IntoIterator<Item = u32>) -> Vec<InformationObject> {
    addresses
        .into_iter()
        .map(|address| {
            InformationObject::new(
                ioa(address),
                Element::Float {
                    value: address as f32,
                    quality: Quality::GOOD,
                },
            )
        })
        .collect()
}

fn unpack(asdus: &[Asdu], params: &AsduParams) -> Vec<InformationObject> {
    let mut objects = Vec::new();
    for asdu in asdus {
        let bytes = asdu.to_bytes(params).unwrap();
        assert!(bytes.len() <= params.max_asdu_len());
        objects.extend(Asdu::decode(&bytes, params).unwrap().objects);
    }
    objects
}

#[test]
fn packing_a_large_interrogation() {
    let gi = Cot::new(Cause::INTERROGATED_BY_STATION);
    let points: Vec<InformationObject> = (1..=100_000u32)
        .map(|n| {
            InformationObject::new(
                ioa(n),
                Element::SinglePoint {
                    on: n % 3 == 0,
                    quality: Quality::GOOD,
                },
            )
        })
        .collect();
    let started = std::time::Instant::now();
    let asdus: Vec<Asdu> =
        pack_objects(TypeId::M_SP_NA_1, gi, ca1(), points.clone(), &P104, true).collect();
    let elapsed = started.elapsed();
    assert_eq!(asdus.len(), 100_000usize.div_ceil(127));
    assert!(asdus.iter().all(|asdu| asdu.sequence));
    assert!(asdus[..asdus.len() - 1]
        .iter()
        .all(|a| a.objects.len() == 127));
    assert_eq!(unpack(&asdus, &P104), points);
    assert!(elapsed.as_secs() < 5, "packing took {elapsed:?}");

    // Without SQ: 60 per ASDU.
    let asdus: Vec<Asdu> =
        pack_objects(TypeId::M_SP_NA_1, gi, ca1(), points.clone(), &P104, false).collect();
    assert_eq!(asdus.len(), 100_000usize.div_ceil(60));
    assert!(asdus.iter().all(|asdu| !asdu.sequence));
    assert_eq!(unpack(&asdus, &P104), points);
}

#[test]
fn packing_mixed_runs() {
    let gi = Cot::new(Cause::INTERROGATED_BY_STATION);
    // Scattered addresses, a pair, a long run, more scatter, a run of 3.
    let mut addresses: Vec<u32> = vec![5, 9, 20, 21];
    addresses.extend(100..200);
    addresses.extend([300, 302, 304, 400, 401, 402]);
    let points = float_points(addresses.iter().copied());
    let asdus: Vec<Asdu> =
        pack_objects(TypeId::M_ME_NC_1, gi, ca1(), points.clone(), &P104, true).collect();
    assert_eq!(unpack(&asdus, &P104), points);
    let shapes: Vec<(bool, usize)> = asdus
        .iter()
        .map(|a| (a.sequence, a.objects.len()))
        .collect();
    assert_eq!(
        shapes,
        [
            (false, 4), // 5, 9, 20, 21: scattered and a pair
            (true, 48), // 100..=147
            (true, 48), // 148..=195
            (true, 4),  // 196..=199
            (false, 3), // 300, 302, 304
            (true, 3),  // 400..=402
        ]
    );
    // Every ASDU respects the limits and SQ=1 only holds consecutive runs.
    for asdu in &asdus {
        assert!(asdu.encoded_len(&P104) <= 249);
        assert!(asdu.objects.len() <= 127);
    }
    // Time-tagged types never use SQ=1.
    let tagged: Vec<InformationObject> = (1..=50)
        .map(|n| {
            InformationObject::with_time(
                ioa(n),
                Element::SinglePoint {
                    on: true,
                    quality: Quality::GOOD,
                },
                cp56(T),
            )
        })
        .collect();
    let asdus: Vec<Asdu> =
        pack_objects(TypeId::M_SP_TB_1, gi, ca1(), tagged.clone(), &P104, true).collect();
    assert!(asdus.iter().all(|a| !a.sequence));
    assert_eq!(
        asdus.iter().map(|a| a.objects.len()).collect::<Vec<_>>(),
        [22, 22, 6]
    );
    assert_eq!(unpack(&asdus, &P104), tagged);
    // Nothing in, nothing out.
    assert_eq!(
        pack_objects(TypeId::M_SP_NA_1, gi, ca1(), Vec::new(), &P104, true).count(),
        0
    );
}
