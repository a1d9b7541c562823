//! Spec §12: every test vector octet for octet, and the negative tests.

use devices::ekm66::codec::*;

const STATUS_QUERY: [u8; 9] = [0x68, 0x03, 0x03, 0x68, 0x01, 0x00, 0x01, 0x02, 0x16];
const COUNTERS_QUERY: [u8; 9] = [0x68, 0x03, 0x03, 0x68, 0x01, 0x00, 0x03, 0x04, 0x16];
const FAULT_QUERY_0: [u8; 10] = [0x68, 0x04, 0x04, 0x68, 0x01, 0x00, 0x04, 0x00, 0x05, 0x16];
const FAULT_QUERY_1: [u8; 10] = [0x68, 0x04, 0x04, 0x68, 0x01, 0x00, 0x04, 0x01, 0x06, 0x16];
const FAULT_QUERY_3: [u8; 10] = [0x68, 0x04, 0x04, 0x68, 0x01, 0x00, 0x04, 0x03, 0x08, 0x16];
const FAULT_QUERY_16: [u8; 10] = [0x68, 0x04, 0x04, 0x68, 0x01, 0x00, 0x04, 0x10, 0x15, 0x16];

const STATUS_20: [u8; 20] = [
    0x68, 0x0E, 0x0E, 0x68, 0x01, 0x00, 0x01, 0x01, 0x02, 0x02, 0x00, 0x00, 0x00, 0x00, 0x00, 0x38,
    0x22, 0x0C, 0x6D, 0x16,
];
const STATUS_21: [u8; 21] = [
    0x68, 0x0F, 0x0F, 0x68, 0x01, 0x00, 0x01, 0x00, 0x01, 0x02, 0x02, 0x00, 0x00, 0x00, 0x00, 0x00,
    0x38, 0x22, 0x0C, 0x6D, 0x16,
];
const COUNTERS_25: [u8; 25] = [
    0x68, 0x13, 0x13, 0x68, 0x01, 0x00, 0x03, 0x0A, 0x14, 0x1E, 0x28, 0x05, 0x00, 0x00, 0x00, 0x00,
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x6D, 0x16,
];
const FAULT_23: [u8; 23] = [
    0x68, 0x11, 0x11, 0x68, 0x01, 0x00, 0x04, 0x03, 0x03, 0x0A, 0x00, 0x07, 0x2A, 0x0F, 0x0E, 0x03,
    0x16, 0x3C, 0x00, 0x01, 0x03, 0xBC, 0x16,
];
const EMPTY_12: [u8; 12] = [
    0x68, 0x06, 0x06, 0x68, 0x01, 0x00, 0x04, 0x05, 0x00, 0x00, 0x0A, 0x16,
];

fn decode(query: Query, bytes: &[u8]) -> Result<Reply, String> {
    let frame = Frame::parse(bytes).map_err(|e| e.to_string())?;
    decode_reply(query, &frame, &CodecConfig::default()).map_err(|e| e.to_string())
}

fn expected_status() -> Status {
    Status {
        code: 1,
        position: 2,
        target: 2,
        direction: Direction::Stopped,
        time: TimeOfDay {
            hour: 12,
            minute: 34,
            second: 56,
        },
    }
}

fn expected_fault() -> FaultRecord {
    FaultRecord {
        index: 3,
        last_index: 10,
        time: FaultTime {
            year: 2022,
            month: 3,
            day: 14,
            time: TimeOfDay {
                hour: 15,
                minute: 42,
                second: 7,
            },
        },
        code: 0x3C,
        floor: 1,
        target: 3,
    }
}

#[test]
fn queries_octet_for_octet() {
    assert_eq!(Query::Status.encode(), STATUS_QUERY);
    assert_eq!(Query::Counters.encode(), COUNTERS_QUERY);
    assert_eq!(Query::FaultRecord(0).encode(), FAULT_QUERY_0);
    assert_eq!(Query::FaultRecord(1).encode(), FAULT_QUERY_1);
    assert_eq!(Query::FaultRecord(3).encode(), FAULT_QUERY_3);
    assert_eq!(Query::FaultRecord(0x10).encode(), FAULT_QUERY_16);
    // and back, as the simulator reads them
    for (bytes, query) in [
        (&STATUS_QUERY[..], Query::Status),
        (&COUNTERS_QUERY[..], Query::Counters),
        (&FAULT_QUERY_3[..], Query::FaultRecord(3)),
    ] {
        let frame = Frame::parse(bytes).unwrap();
        assert_eq!(Query::from_user_data(frame.user_data()).unwrap(), query);
    }
}

#[test]
fn status_reply_adopted_layout() {
    assert_eq!(
        decode(Query::Status, &STATUS_20),
        Ok(Reply::Status(expected_status()))
    );
    let encoded = encode_reply(
        &Reply::Status(expected_status()),
        StatusLayout::ADOPTED,
        &CodecConfig::default(),
        0,
    );
    assert_eq!(encoded, STATUS_20);
}

#[test]
fn status_reply_alternative_layout() {
    assert_eq!(
        decode(Query::Status, &STATUS_21),
        Ok(Reply::Status(expected_status()))
    );
    let encoded = encode_reply(
        &Reply::Status(expected_status()),
        StatusLayout::ALTERNATIVE,
        &CodecConfig::default(),
        0,
    );
    assert_eq!(encoded, STATUS_21);
    // Switched off, the 21-octet frame is refused.
    let mut adopted_only = CodecConfig::default();
    adopted_only.status_layouts = vec![StatusLayout::ADOPTED];
    let frame = Frame::parse(&STATUS_21).unwrap();
    assert_eq!(
        decode_reply(Query::Status, &frame, &adopted_only),
        Err(ReplyError::UnexpectedLength {
            length: 0x0F,
            query: Query::Status
        })
    );
}

#[test]
fn counters_reply() {
    let mut expected = vec![10, 20, 30, 40, 5];
    expected.resize(16, 0);
    assert_eq!(
        decode(Query::Counters, &COUNTERS_25),
        Ok(Reply::Counters(expected.clone()))
    );
    let encoded = encode_reply(
        &Reply::Counters(expected),
        StatusLayout::ADOPTED,
        &CodecConfig::default(),
        0,
    );
    assert_eq!(encoded, COUNTERS_25);
}

#[test]
fn counters_of_two_and_four_octets() {
    let mut config = CodecConfig::default();
    config.counter_width = CounterWidth::Two;
    let frame = Frame::parse(&COUNTERS_25).unwrap();
    let mut expected = vec![0x140A, 0x281E, 0x0005];
    expected.resize(8, 0);
    assert_eq!(
        decode_reply(Query::Counters, &frame, &config),
        Ok(Reply::Counters(expected))
    );
    config.counter_width = CounterWidth::Four;
    assert_eq!(
        decode_reply(Query::Counters, &frame, &config),
        Ok(Reply::Counters(vec![0x281E140A, 5, 0, 0]))
    );
    // 17 octets do not split into counters of two.
    let odd = encode_frame(&[0x01, 0x00, 0x03, 1, 2, 3]);
    config.counter_width = CounterWidth::Two;
    assert_eq!(
        decode_reply(Query::Counters, &Frame::parse(&odd).unwrap(), &config),
        Err(ReplyError::CounterLength {
            octets: 3,
            width: 2
        })
    );
    // A counter reply with no counters at all (L = 3) is valid and empty.
    let none = encode_frame(&[0x01, 0x00, 0x03]);
    assert_eq!(
        decode_reply(Query::Counters, &Frame::parse(&none).unwrap(), &config),
        Ok(Reply::Counters(vec![]))
    );
}

#[test]
fn fault_record_reply_with_0x16_inside() {
    assert_eq!(
        decode(Query::FaultRecord(3), &FAULT_23),
        Ok(Reply::Fault(expected_fault()))
    );
    let encoded = encode_reply(
        &Reply::Fault(expected_fault()),
        StatusLayout::ADOPTED,
        &CodecConfig::default(),
        3,
    );
    assert_eq!(encoded, FAULT_23);
    // Delivered through the deframer octet by octet: the 0x16 (year 22) at position 16
    // does not end the frame.
    let mut deframer = Deframer::new();
    for (n, octet) in FAULT_23.iter().enumerate() {
        deframer.push(&[*octet]);
        let next = deframer.next_frame();
        if n + 1 < FAULT_23.len() {
            assert!(next.is_none(), "frame cut at octet {n}");
        } else {
            assert_eq!(next.unwrap().unwrap().as_bytes(), FAULT_23);
        }
    }
}

#[test]
fn empty_slot_reply() {
    assert_eq!(
        decode(Query::FaultRecord(5), &EMPTY_12),
        Ok(Reply::EmptySlot { index: 5 })
    );
    let encoded = encode_reply(
        &Reply::EmptySlot { index: 5 },
        StatusLayout::ADOPTED,
        &CodecConfig::default(),
        5,
    );
    assert_eq!(encoded, EMPTY_12);
}

#[test]
fn bcd_time_and_year_base() {
    let mut config = CodecConfig::default();
    config.time = TimeEncoding::Bcd;
    config.year_base = 1990;
    let record = expected_fault();
    let mut moved = record;
    moved.time.year = 2022;
    let bytes = encode_reply(&Reply::Fault(moved), StatusLayout::ADOPTED, &config, 3);
    // BCD: 07 42 15 14 03 (2022 - 1990 = 32)
    assert_eq!(&bytes[11..17], &[0x07, 0x42, 0x15, 0x14, 0x03, 0x32]);
    let frame = Frame::parse(&bytes).unwrap();
    assert_eq!(
        decode_reply(Query::FaultRecord(3), &frame, &config),
        Ok(Reply::Fault(moved))
    );
    // An octet that is no BCD refuses the reply.
    let binary = Frame::parse(&FAULT_23).unwrap();
    assert_eq!(
        decode_reply(Query::FaultRecord(3), &binary, &config),
        Err(ReplyError::Bcd(0x2A))
    );
}

#[test]
fn direction_coding_is_configurable() {
    let mut config = CodecConfig::default();
    let mut bytes = STATUS_20;
    bytes[10] = 1;
    bytes[18] = bytes[18].wrapping_add(1);
    let decode_with = |bytes: &[u8], config: &CodecConfig| match decode_reply(
        Query::Status,
        &Frame::parse(bytes).unwrap(),
        config,
    ) {
        Ok(Reply::Status(status)) => status.direction,
        other => panic!("{other:?}"),
    };
    assert_eq!(decode_with(&bytes, &config), Direction::Up);
    config.direction = DirectionCoding {
        stopped: 0,
        up: 2,
        down: 1,
    };
    assert_eq!(decode_with(&bytes, &config), Direction::Down);
    bytes[10] = 7;
    bytes[18] = bytes[18].wrapping_add(6);
    assert_eq!(decode_with(&bytes, &config), Direction::Unknown(7));
}

// ---- negative tests (spec §12) ----

#[test]
fn wrong_second_length_octet() {
    let mut bytes = STATUS_20;
    bytes[2] = 0x0F;
    assert_eq!(
        Frame::parse(&bytes),
        Err(FrameError::LengthMismatch(0x0E, 0x0F))
    );
}

#[test]
fn wrong_checksum() {
    let mut bytes = FAULT_23;
    bytes[21] = 0xBD;
    assert_eq!(
        Frame::parse(&bytes),
        Err(FrameError::Checksum {
            found: 0xBD,
            expected: 0xBC
        })
    );
    // A changed data octet is caught by the same sum.
    let mut bytes = STATUS_20;
    bytes[7] = 0x06;
    assert!(matches!(
        Frame::parse(&bytes),
        Err(FrameError::Checksum { .. })
    ));
}

#[test]
fn missing_end_octet() {
    let mut bytes = EMPTY_12;
    bytes[11] = 0x00;
    assert_eq!(Frame::parse(&bytes), Err(FrameError::NoEnd(0x00)));
    // Cut off before the end: truncated, never a frame.
    assert_eq!(
        Frame::parse(&EMPTY_12[..11]),
        Err(FrameError::Truncated { have: 11, want: 12 })
    );
}

#[test]
fn header_of_another_reply_type() {
    let config = CodecConfig::default();
    let fault = Frame::parse(&FAULT_23).unwrap();
    let status = Frame::parse(&STATUS_20).unwrap();
    let empty = Frame::parse(&EMPTY_12).unwrap();
    assert_eq!(
        decode_reply(Query::Status, &fault, &config),
        Err(ReplyError::UnexpectedLength {
            length: 0x11,
            query: Query::Status
        })
    );
    assert_eq!(
        decode_reply(Query::Status, &empty, &config),
        Err(ReplyError::UnexpectedLength {
            length: 0x06,
            query: Query::Status
        })
    );
    assert_eq!(
        decode_reply(Query::FaultRecord(3), &status, &config),
        Err(ReplyError::UnexpectedLength {
            length: 0x0E,
            query: Query::FaultRecord(3)
        })
    );
    // Counters: any L >= 3 (EKM-A3), so only a shorter frame is refused.
    let short = Frame::parse(&encode_frame(&[0x01, 0x00])).unwrap();
    assert_eq!(
        decode_reply(Query::Counters, &short, &config),
        Err(ReplyError::UnexpectedLength {
            length: 2,
            query: Query::Counters
        })
    );
}

#[test]
fn truncated_frame_waits_and_is_abandoned() {
    let mut deframer = Deframer::new();
    deframer.push(&STATUS_20[..15]);
    assert!(deframer.next_frame().is_none());
    assert_eq!(
        deframer.abandon(),
        Some(FrameError::Truncated { have: 15, want: 20 })
    );
    // The next complete frame is read normally.
    deframer.push(&STATUS_20);
    assert_eq!(
        deframer.next_frame().unwrap().unwrap().as_bytes(),
        STATUS_20
    );
}

#[test]
fn frame_split_across_reads() {
    for split in 1..FAULT_23.len() {
        let mut deframer = Deframer::new();
        deframer.push(&FAULT_23[..split]);
        assert!(deframer.next_frame().is_none(), "split at {split}");
        deframer.push(&FAULT_23[split..]);
        assert_eq!(deframer.next_frame().unwrap().unwrap().as_bytes(), FAULT_23);
        assert!(deframer.next_frame().is_none());
    }
    // In three pieces, two frames back to back.
    let mut stream = STATUS_20.to_vec();
    stream.extend_from_slice(&EMPTY_12);
    let mut deframer = Deframer::new();
    let mut frames = Vec::new();
    for piece in stream.chunks(7) {
        deframer.push(piece);
        while let Some(Ok(frame)) = deframer.next_frame() {
            frames.push(frame.as_bytes().to_vec());
        }
    }
    assert_eq!(frames, vec![STATUS_20.to_vec(), EMPTY_12.to_vec()]);
}

#[test]
fn garbage_before_start_resynchronises_on_the_next_valid_frame() {
    // Garbage, then a false start (0x68 followed by a header that does not hold), then
    // a broken frame whose checksum fails, then the good frame.
    let mut stream = vec![0x00, 0x16, 0xFF, 0x68, 0x05, 0x07];
    let mut broken = FAULT_23;
    broken[12] ^= 0x01;
    stream.extend_from_slice(&broken[..]);
    stream.extend_from_slice(&FAULT_23);
    let mut deframer = Deframer::new();
    deframer.push(&stream);
    let mut errors = Vec::new();
    let frame = loop {
        match deframer.next_frame() {
            Some(Ok(frame)) => break frame,
            Some(Err(error)) => errors.push(error),
            None => panic!("no frame found; errors {errors:?}"),
        }
    };
    assert_eq!(frame.as_bytes(), FAULT_23);
    assert_eq!(errors.first(), Some(&FrameError::Garbage(3)));
    assert!(errors.contains(&FrameError::LengthMismatch(0x05, 0x07)));
    assert!(errors
        .iter()
        .any(|error| matches!(error, FrameError::Checksum { .. })));
    assert!(deframer.next_frame().is_none());
}

#[test]
fn a_0x68_inside_a_frame_is_not_a_start() {
    // Status 0x68 = 104 (unknown code) at position 7.
    let status = Status {
        code: 0x68,
        ..expected_status()
    };
    let bytes = encode_reply(
        &Reply::Status(status),
        StatusLayout::ADOPTED,
        &CodecConfig::default(),
        0,
    );
    let mut deframer = Deframer::new();
    deframer.push(&bytes);
    assert_eq!(
        deframer.next_frame(),
        Some(Ok(Frame::parse(&bytes).unwrap()))
    );
}

#[test]
fn a_late_reply_to_another_query_is_refused_by_its_function_echo() {
    // The status vector (L = 0x0E, echo 0x01) arriving while the counter query waits:
    // as counters it would be 11 plausible values.
    let error = decode(Query::Counters, &STATUS_20).unwrap_err();
    assert!(error.contains("answers another query"), "{error}");
    // The counter vector (echo 0x03) to a fault query, a fault record to a status query.
    assert!(decode(Query::FaultRecord(0), &COUNTERS_25).is_err());
    assert!(decode(Query::Status, &FAULT_23).is_err());
    // A board that echoes no function code (zeros, EKM-A8) is still understood.
    let mut quiet = COUNTERS_25;
    quiet[6] = 0x00;
    let sum = quiet[4..quiet.len() - 2]
        .iter()
        .fold(0u8, |sum, octet| sum.wrapping_add(*octet));
    let end = quiet.len() - 2;
    quiet[end] = sum;
    assert_eq!(
        decode(Query::Counters, &quiet).unwrap(),
        Reply::Counters(vec![10, 20, 30, 40, 5, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0])
    );
}
