//! The IEC 103 ASDU codec against hand-assembled frames of the spec's session (§6) and
//! the standard's layouts, every truncation, and property tests: any ASDU round-trips,
//! any octets decode or fail without panicking.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    // Instant::now only as the base of the tests' own clock.
    clippy::disallowed_methods
)]

use iec60870::iec103::*;
use iec60870::time::{Cp32Time2a, Cp56Time2a};
use proptest::prelude::*;

fn cp32() -> Cp32Time2a {
    Cp32Time2a::new(8, 28, 32_666).unwrap().with_invalid(true)
}

fn cp56() -> Cp56Time2a {
    Cp56Time2a::from_bytes([0xD8, 0x76, 0xBB, 0x09, 0x1A, 0x04, 0x11]).unwrap()
}

/// (name, direction, octets, expected) of the messages of the spec's session.
fn vectors() -> Vec<(&'static str, Direction, Vec<u8>, Asdu)> {
    let mut identification = vec![0x05, 0x81, 0x04, 0x01, 0xA0, 0x03, 0x02];
    identification.extend_from_slice(b"REF630 11.3.");
    // SQ = 0, nine measurands (VSQ 0x09): one object, one FUN/INF, as relays send it.
    let mut measurands = vec![0x09, 0x09, 0x02, 0x01, 0x01, 0x94];
    for word in [0x3558u16, 0x3558, 0x3558, 0x6AA8, 0x6AA8, 0x6AA8, 0, 0, 0] {
        measurands.extend_from_slice(&word.to_le_bytes());
    }
    let mut time_sync = vec![0x06, 0x81, 0x08, 0xFF, 0xFF, 0x00];
    time_sync.extend_from_slice(&cp56().to_bytes());
    let mut breaker = vec![0x01, 0x81, 0x09, 0x01, 0x01, 0xA0, 0x02];
    breaker.extend_from_slice(&cp32().to_bytes());
    breaker.push(0x02);
    vec![
        (
            "identification after reset CU",
            Direction::Monitor,
            identification,
            Asdu::new(
                5,
                Cause::RESET_CU,
                1,
                160,
                INF_RESET_CU,
                Body::Identification {
                    col: 2,
                    text: *b"REF630 1",
                    software: *b"1.3.",
                },
            ),
        ),
        (
            "GI initiation, scan 2",
            Direction::Control,
            vec![0x07, 0x81, 0x09, 0x01, 0xFF, 0x00, 0x02],
            Asdu::new(
                7,
                Cause::GENERAL_INTERROGATION,
                1,
                FUN_GLOBAL,
                0,
                Body::GiInitiation { scn: 2 },
            ),
        ),
        (
            "GI termination, scan 2",
            Direction::Monitor,
            vec![0x08, 0x81, 0x0A, 0x01, 0xFF, 0x00, 0x02],
            Asdu::new(
                8,
                Cause::GI_TERMINATION,
                1,
                FUN_GLOBAL,
                0,
                Body::GiTermination { scn: 2 },
            ),
        ),
        (
            "breaker ON in the GI, clock unsynchronised",
            Direction::Monitor,
            breaker,
            Asdu::new(
                1,
                Cause::GENERAL_INTERROGATION,
                1,
                1,
                160,
                Body::TimeTagged {
                    dpi: 2,
                    time: cp32(),
                    sin: 2,
                },
            ),
        ),
        (
            "measurands II, rated current and voltage",
            Direction::Monitor,
            measurands,
            Asdu {
                header: Header {
                    type_id: 9,
                    vsq: 0x09,
                    cause: Cause::CYCLIC,
                    common_address: 1,
                    fun: 1,
                    inf: INF_MEASURANDS_II,
                },
                body: Body::Measurands(
                    [0x3558u16, 0x3558, 0x3558, 0x6AA8, 0x6AA8, 0x6AA8, 0, 0, 0]
                        .into_iter()
                        .map(Measurand::from_word)
                        .collect(),
                ),
            },
        ),
        (
            "general command breaker ON, RII 7",
            Direction::Control,
            vec![0x14, 0x81, 0x14, 0x01, 0x01, 0xA0, 0x02, 0x07],
            Asdu::new(
                20,
                Cause::COMMAND_ACK,
                1,
                1,
                160,
                Body::GeneralCommand { dco: 2, rii: 7 },
            ),
        ),
        (
            "broadcast time synchronisation",
            Direction::Control,
            time_sync,
            Asdu::new(
                6,
                Cause::TIME_SYNC,
                0xFF,
                FUN_GLOBAL,
                0,
                Body::TimeSync { time: cp56() },
            ),
        ),
    ]
}

#[test]
fn the_sessions_messages_decode_and_encode_octet_for_octet() {
    for (name, direction, octets, expected) in vectors() {
        let decoded = Asdu::decode(&octets, direction).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(decoded, expected, "{name}");
        assert_eq!(expected.to_bytes().unwrap(), octets, "{name}");
    }
}

/// Measurands and disturbance lists are sent with SQ = 0 (VSQ = the count), and read
/// with the SQ bit set too, as some stations send them.
#[test]
fn element_lists_are_sent_with_sq_0_and_read_with_either() {
    let (_, _, octets, expected) = vectors()
        .into_iter()
        .find(|(name, ..)| name.starts_with("measurands"))
        .unwrap();
    assert_eq!(octets[1], 0x09, "nine measurands, SQ = 0");
    let mut with_sq = octets.clone();
    with_sq[1] = 0x89;
    let decoded = Asdu::decode(&with_sq, Direction::Monitor).unwrap();
    assert_eq!(decoded.body, expected.body);
    // Re-encoded, it goes out with SQ = 0 whatever it came with.
    assert_eq!(decoded.to_bytes().unwrap(), octets);
}

#[test]
fn every_truncation_and_every_extension_is_an_error() {
    for (name, direction, octets, _) in vectors() {
        for len in 0..octets.len() {
            assert!(
                Asdu::decode(&octets[..len], direction).is_err(),
                "{name} cut to {len} octets"
            );
        }
        let mut longer = octets.clone();
        longer.push(0);
        assert!(
            Asdu::decode(&longer, direction).is_err(),
            "{name} with an extra octet"
        );
    }
}

#[test]
fn what_test_tools_show() {
    let (_, _, octets, _) = &vectors()[0];
    let identification = Asdu::decode(octets, Direction::Monitor).unwrap();
    assert_eq!(
        identification.identification_text().unwrap(),
        "REF630 11.3."
    );
    assert_eq!(
        identification.to_string(),
        "ASDU 5 RCU (4) CA 1 FUN 160 INF 3 Comp: 2 String: >REF630 11.3.<"
    );
    let (_, _, octets, _) = &vectors()[3];
    assert_eq!(
        Asdu::decode(octets, Direction::Monitor)
            .unwrap()
            .to_string(),
        "ASDU 1 GI (9) CA 1 FUN 1 INF 160 On 08:28:32.666 [IV] SIN 2"
    );
    let (_, _, octets, _) = &vectors()[4];
    let measurands = Asdu::decode(octets, Direction::Monitor).unwrap();
    let Body::Measurands(values) = &measurands.body else {
        panic!("measurands")
    };
    let multiples: Vec<String> = values
        .iter()
        .zip([2.4, 2.4, 2.4, 1.2, 1.2, 1.2, 2.4, 2.4, 1.2])
        .map(|(value, limit)| format!("{:.2}", value.to_physical(limit)))
        .collect();
    assert_eq!(
        multiples,
        ["1.00", "1.00", "1.00", "1.00", "1.00", "1.00", "0.00", "0.00", "0.00"]
    );
}

#[test]
fn disturbance_transfer_layouts() {
    let ready = Asdu::new(
        26,
        Cause::DISTURBANCE_DATA,
        1,
        160,
        0,
        Body::DisturbanceReady {
            tov: 1,
            fan: 7,
            nof: 1,
            noc: 4,
            noe: 400,
            int: 1000,
            time: cp32(),
        },
    );
    let octets = ready.to_bytes().unwrap();
    assert_eq!(
        octets,
        [
            0x1A, 0x81, 0x1F, 0x01, 0xA0, 0x00, 0x00, 0x01, 0x07, 0x00, 0x01, 0x00, 0x04, 0x90,
            0x01, 0xE8, 0x03, 0x9A, 0x7F, 0x9C, 0x08
        ]
    );
    let values = Asdu::new(
        30,
        Cause::DISTURBANCE_DATA,
        1,
        160,
        0,
        Body::DisturbanceValues {
            tov: 1,
            fan: 7,
            acc: 1,
            nfe: 0,
            values: vec![0, 1000, -1000],
        },
    );
    assert_eq!(
        values.to_bytes().unwrap(),
        [
            0x1E, 0x81, 0x1F, 0x01, 0xA0, 0x00, 0x00, 0x01, 0x07, 0x00, 0x01, 0x03, 0x00, 0x00,
            0x00, 0x00, 0xE8, 0x03, 0x18, 0xFC
        ]
    );
    for asdu in [ready, values] {
        let octets = asdu.to_bytes().unwrap();
        assert_eq!(Asdu::decode(&octets, Direction::Monitor).unwrap(), asdu);
    }
}

fn any_cp32() -> impl Strategy<Value = Cp32Time2a> {
    (0u8..24, 0u8..60, 0u16..60_000, any::<bool>(), any::<bool>()).prop_map(|(h, m, ms, iv, su)| {
        Cp32Time2a::new(h, m, ms)
            .unwrap()
            .with_invalid(iv)
            .with_summer_time(su)
    })
}

fn any_cp56() -> impl Strategy<Value = Cp56Time2a> {
    (0u8..100, 1u8..13, 1u8..29, 0u8..24, 0u8..60, 0u16..60_000)
        .prop_map(|(y, mo, d, h, mi, ms)| Cp56Time2a::new(y, mo, d, h, mi, ms).unwrap())
}

/// Any body with its type and direction.
fn any_asdu() -> impl Strategy<Value = (Asdu, Direction)> {
    let bytes = || proptest::collection::vec(any::<u8>(), 0..40);
    let body = prop_oneof![
        (any::<u8>(), any_cp32(), any::<u8>()).prop_map(|(dpi, time, sin)| (
            1,
            Direction::Monitor,
            Body::TimeTagged { dpi, time, sin }
        )),
        (
            any::<u8>(),
            any::<u16>(),
            any::<u16>(),
            any_cp32(),
            any::<u8>()
        )
            .prop_map(|(dpi, ret, fan, time, sin)| (
                2,
                Direction::Monitor,
                Body::TimeTaggedRelative {
                    dpi,
                    ret,
                    fan,
                    time,
                    sin
                }
            )),
        proptest::collection::vec(any::<u16>().prop_map(Measurand::from_word), 1..60)
            .prop_map(|values| (9, Direction::Monitor, Body::Measurands(values))),
        proptest::collection::vec(any::<u16>().prop_map(Measurand::from_word), 1..5)
            .prop_map(|values| (3, Direction::Monitor, Body::Measurands(values))),
        (any::<u32>(), any::<u16>(), any::<u16>(), any_cp32()).prop_map(
            |(bits, ret, fan, time)| (
                4,
                Direction::Monitor,
                Body::TimeTaggedMeasurand {
                    value: f32::from_bits(bits & 0x7F7F_FFFF),
                    ret,
                    fan,
                    time
                }
            )
        ),
        (any::<u8>(), any::<[u8; 8]>(), any::<[u8; 4]>()).prop_map(|(col, text, software)| (
            5,
            Direction::Monitor,
            Body::Identification {
                col,
                text,
                software
            }
        )),
        any_cp56().prop_map(|time| (6, Direction::Control, Body::TimeSync { time })),
        any::<u8>().prop_map(|scn| (7, Direction::Control, Body::GiInitiation { scn })),
        any::<u8>().prop_map(|scn| (8, Direction::Monitor, Body::GiTermination { scn })),
        (any::<u8>(), any::<u8>(), bytes()).prop_map(|(rii, ngd, data)| (
            10,
            Direction::Monitor,
            Body::GenericData { rii, ngd, data }
        )),
        (any::<u8>(), bytes()).prop_map(|(rii, data)| (
            11,
            Direction::Monitor,
            Body::GenericIdentification { rii, data }
        )),
        (any::<u8>(), any::<u8>()).prop_map(|(dco, rii)| (
            20,
            Direction::Control,
            Body::GeneralCommand { dco, rii }
        )),
        (
            any::<u8>(),
            proptest::collection::vec((any::<u16>(), any::<u8>()), 0..20)
        )
            .prop_map(|(rii, items)| (
                21,
                Direction::Control,
                Body::GenericCommand { rii, items }
            )),
        proptest::collection::vec((any::<u16>(), any::<u8>(), any_cp56()), 0..20).prop_map(
            |records| (
                23,
                Direction::Monitor,
                Body::DisturbanceList(
                    records
                        .into_iter()
                        .map(|(fan, sof, time)| RecordedDisturbance { fan, sof, time })
                        .collect()
                )
            )
        ),
        (any::<u8>(), any::<u8>(), any::<u16>(), any::<u8>()).prop_map(|(too, tov, fan, acc)| (
            24,
            Direction::Control,
            Body::DisturbanceOrder { too, tov, fan, acc }
        )),
        (any::<u8>(), any::<u8>(), any::<u16>(), any::<u8>()).prop_map(|(too, tov, fan, acc)| (
            25,
            Direction::Control,
            Body::DisturbanceAck { too, tov, fan, acc }
        )),
        (
            any::<u8>(),
            any::<u16>(),
            any::<u16>(),
            any::<u8>(),
            any::<u16>(),
            any::<u16>(),
            any_cp32()
        )
            .prop_map(|(tov, fan, nof, noc, noe, int, time)| (
                26,
                Direction::Monitor,
                Body::DisturbanceReady {
                    tov,
                    fan,
                    nof,
                    noc,
                    noe,
                    int,
                    time
                }
            )),
        (
            any::<u8>(),
            any::<u16>(),
            any::<u8>(),
            -1e6f32..1e6,
            -1e6f32..1e6,
            -1e6f32..1e6
        )
            .prop_map(|(tov, fan, acc, rpv, rsv, rfa)| (
                27,
                Direction::Monitor,
                Body::ChannelReady {
                    tov,
                    fan,
                    acc,
                    rpv,
                    rsv,
                    rfa
                }
            )),
        any::<u16>().prop_map(|fan| (28, Direction::Monitor, Body::TagsReady { fan })),
        (
            any::<u16>(),
            any::<u16>(),
            proptest::collection::vec(any::<[u8; 3]>(), 0..30)
        )
            .prop_map(|(fan, tap, tags)| (
                29,
                Direction::Monitor,
                Body::Tags {
                    fan,
                    tap,
                    tags: tags
                        .into_iter()
                        .map(|[fun, inf, dpi]| DisturbanceTag { fun, inf, dpi })
                        .collect()
                }
            )),
        (
            any::<u8>(),
            any::<u16>(),
            any::<u8>(),
            any::<u16>(),
            proptest::collection::vec(any::<i16>(), 0..100)
        )
            .prop_map(|(tov, fan, acc, nfe, values)| (
                30,
                Direction::Monitor,
                Body::DisturbanceValues {
                    tov,
                    fan,
                    acc,
                    nfe,
                    values
                }
            )),
        (any::<u8>(), any::<u8>(), any::<u16>(), any::<u8>()).prop_map(|(too, tov, fan, acc)| (
            31,
            Direction::Monitor,
            Body::EndOfTransmission { too, tov, fan, acc }
        )),
        bytes().prop_map(|data| (200, Direction::Monitor, Body::Other(data))),
    ];
    (body, any::<u8>(), any::<u8>(), any::<u8>(), any::<u8>()).prop_map(
        |((type_id, direction, body), cause, common_address, fun, inf)| {
            let mut asdu = Asdu::new(type_id, Cause(cause), common_address, fun, inf, body);
            // Element lists get their VSQ from the count when encoded.
            asdu.header.vsq = match &asdu.body {
                Body::Measurands(values) if type_id == 9 => values.len() as u8,
                Body::DisturbanceList(records) => records.len() as u8,
                _ => 0x81,
            };
            (asdu, direction)
        },
    )
}

proptest! {
    #[test]
    fn any_asdu_round_trips((asdu, direction) in any_asdu()) {
        let octets = asdu.to_bytes().unwrap();
        prop_assert_eq!(Asdu::decode(&octets, direction).unwrap(), asdu);
    }

    #[test]
    fn any_octets_decode_or_fail_cleanly(octets in proptest::collection::vec(any::<u8>(), 0..300)) {
        for direction in [Direction::Monitor, Direction::Control] {
            if let Ok(asdu) = Asdu::decode(&octets, direction) {
                let _ = asdu.to_string();
                // What decodes re-encodes to octets that decode and encode the same
                // (octets, not values: a NaN float is not equal to itself).
                let again = asdu.to_bytes().unwrap();
                let decoded = Asdu::decode(&again, direction).unwrap();
                prop_assert_eq!(decoded.to_bytes().unwrap(), again);
            }
        }
    }
}
