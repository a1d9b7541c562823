//! Derived vectors, one per element family, in the standard encodings: points, measured
//! values, totals, protection, commands, system information, parameters, file transfer.

use iec60870::asdu::*;

use crate::support::*;

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
