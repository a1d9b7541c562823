//! Property tests: replies round-trip through encode and decode; the deframer never
//! panics on arbitrary octets and finds a valid frame after any garbage.

use devices::ekm66::codec::*;
use proptest::prelude::*;

fn time_of_day() -> impl Strategy<Value = TimeOfDay> {
    (0u8..24, 0u8..60, 0u8..60).prop_map(|(hour, minute, second)| TimeOfDay {
        hour,
        minute,
        second,
    })
}

fn config() -> impl Strategy<Value = (CodecConfig, StatusLayout)> {
    (
        prop_oneof![
            Just(CounterWidth::One),
            Just(CounterWidth::Two),
            Just(CounterWidth::Four)
        ],
        prop_oneof![Just(TimeEncoding::Binary), Just(TimeEncoding::Bcd)],
        1900u16..2100,
        any::<bool>(),
    )
        .prop_map(|(width, time, year_base, alternative)| {
            let mut config = CodecConfig::default();
            config.counter_width = width;
            config.time = time;
            config.year_base = year_base;
            let layout = if alternative {
                StatusLayout::ALTERNATIVE
            } else {
                StatusLayout::ADOPTED
            };
            (config, layout)
        })
}

fn reply(width: CounterWidth, year_base: u16) -> impl Strategy<Value = (Query, Reply)> {
    let status = (any::<u8>(), any::<u8>(), any::<u8>(), 0u8..3, time_of_day()).prop_map(
        |(code, position, target, direction, time)| {
            let direction =
                [Direction::Stopped, Direction::Up, Direction::Down][direction as usize];
            (
                Query::Status,
                Reply::Status(Status {
                    code,
                    position,
                    target,
                    direction,
                    time,
                }),
            )
        },
    );
    let max = width.max();
    let count = 252 / width.octets();
    let counters = prop::collection::vec(0..=max, 0..count)
        .prop_map(|counters| (Query::Counters, Reply::Counters(counters)));
    let fault = (
        any::<u8>(),
        any::<u8>(),
        0u16..100,
        1u8..13,
        1u8..32,
        time_of_day(),
        any::<u8>(),
        any::<u8>(),
        any::<u8>(),
    )
        .prop_map(
            move |(index, last_index, year, month, day, time, code, floor, target)| {
                (
                    Query::FaultRecord(index),
                    Reply::Fault(FaultRecord {
                        index,
                        last_index,
                        time: FaultTime {
                            year: year_base + year,
                            month,
                            day,
                            time,
                        },
                        code,
                        floor,
                        target,
                    }),
                )
            },
        );
    let empty =
        any::<u8>().prop_map(|index| (Query::FaultRecord(index), Reply::EmptySlot { index }));
    prop_oneof![status, counters, fault, empty]
}

proptest! {
    #[test]
    fn replies_round_trip(
        ((config, layout), (query, reply)) in config().prop_flat_map(|(config, layout)| {
            let width = config.counter_width;
            let base = config.year_base;
            (Just((config, layout)), reply(width, base))
        })
    ) {
        let index = match query { Query::FaultRecord(index) => index, _ => 0 };
        let bytes = encode_reply(&reply, layout, &config, index);
        let frame = Frame::parse(&bytes).unwrap();
        prop_assert_eq!(decode_reply(query, &frame, &config), Ok(reply));
    }

    #[test]
    fn queries_round_trip(index in any::<u8>()) {
        for query in [Query::Status, Query::Counters, Query::FaultRecord(index)] {
            let frame = Frame::parse(&query.encode()).unwrap();
            prop_assert_eq!(Query::from_user_data(frame.user_data()), Ok(query));
        }
    }

    #[test]
    fn deframer_never_panics(chunks in prop::collection::vec(prop::collection::vec(any::<u8>(), 0..80), 0..20)) {
        let mut deframer = Deframer::new();
        let mut total = 0usize;
        for chunk in &chunks {
            total += chunk.len();
            deframer.push(chunk);
            while let Some(next) = deframer.next_frame() {
                if let Ok(frame) = next {
                    // Whatever it returns is a frame that validates on its own.
                    prop_assert_eq!(Frame::parse(frame.as_bytes()), Ok(frame.clone()));
                }
            }
            prop_assert!(deframer.buffered() <= total);
        }
        deframer.abandon();
        prop_assert_eq!(deframer.buffered(), 0);
    }

    #[test]
    fn deframer_resynchronises_after_garbage(
        garbage in prop::collection::vec(any::<u8>(), 0..300),
        index in any::<u8>(),
        chunk in 1usize..30,
    ) {
        // Whatever precedes it, a valid frame is found once the garbage is dropped:
        // either by the deframer itself, or after the line pause that abandons a
        // partial frame a false header announced.
        let frame = encode_reply(&Reply::EmptySlot { index }, StatusLayout::ADOPTED, &CodecConfig::default(), index);
        let mut stream = garbage.clone();
        stream.extend_from_slice(&frame);
        let mut deframer = Deframer::new();
        let mut found = false;
        for piece in stream.chunks(chunk) {
            deframer.push(piece);
            while let Some(next) = deframer.next_frame() {
                if next.as_ref().is_ok_and(|f| f.as_bytes() == frame.as_slice()) {
                    found = true;
                }
            }
        }
        if !found {
            // A false header waits for octets beyond the stream: the pause drops it and
            // the frame, sent again, is found.
            deframer.abandon();
            deframer.push(&frame);
            prop_assert_eq!(deframer.next_frame(), Some(Ok(Frame::parse(&frame).unwrap())));
        }
    }
}

#[test]
fn resynchronises_inside_a_false_header() {
    // A false start whose header holds (68 03 03 68) but whose frame fails: the real
    // frame starting inside it is still found.
    let real = Query::Status.encode();
    let mut stream = vec![0x68, 0x03, 0x03];
    stream.extend_from_slice(&real);
    let mut deframer = Deframer::new();
    deframer.push(&stream);
    let mut frames = Vec::new();
    while let Some(next) = deframer.next_frame() {
        if let Ok(frame) = next {
            frames.push(frame.as_bytes().to_vec());
        }
    }
    assert_eq!(frames, vec![real]);
}
