//! The decoded logs of spec §7.3 (double and single commands, normalized and short
//! float measured values) and the analyser-style display.

use iec60870::asdu::*;

use crate::support::*;

// ---- spec §7.3: double command, breaker close ----

pub(crate) const DP_TB_OFF: [u8; 17] = [
    0x1F, 0x01, 0x03, 0x00, 0x01, 0x00, 0xD0, 0x07, 0x00, 0x01, 0xD8, 0x76, 0xBB, 0x09, 0x1A, 0x04,
    0x11,
];
pub(crate) const DC_COT5: [u8; 10] = [0x2E, 0x01, 0x05, 0x00, 0x01, 0x00, 0x34, 0x08, 0x00, 0x02];
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
pub(crate) const SC_COT5: [u8; 10] = [0x2D, 0x01, 0x05, 0x00, 0x01, 0x00, 0x36, 0x10, 0x00, 0x01];
const SC_COT0: [u8; 10] = [0x2D, 0x01, 0x00, 0x00, 0x01, 0x00, 0x36, 0x10, 0x00, 0x01];
const DP_TB_ON_2: [u8; 17] = [
    0x1F, 0x01, 0x03, 0x00, 0x01, 0x00, 0xD0, 0x07, 0x00, 0x02, 0x06, 0x60, 0xBB, 0x0D, 0x1A, 0x04,
    0x11,
];

// ---- spec §7.3: measured values, normalized ----

/// (ASDU, IOA, raw, normalized printed by the test tool)
pub(crate) const NORMALIZED: [([u8; 12], u32, i16, &str); 8] = [
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
pub(crate) const FLOAT_P_AND_F: [u8; 22] = [
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
