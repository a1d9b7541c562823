//! Hardening: truncated, inconsistent and oversize ASDUs, unknown types, out-of-range
//! times, broadcast addresses and the object lengths.

use iec60870::asdu::*;

use crate::spec::{DC_COT5, DP_TB_OFF, FLOAT_P_AND_F, NORMALIZED, SC_COT5};
use crate::support::*;

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
