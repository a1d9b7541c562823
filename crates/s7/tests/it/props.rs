//! Property tests: codec round trips, decoders total over arbitrary and mutated bytes,
//! splitting within the PDU size, and reads through both sans-IO ends giving memory back.

use proptest::prelude::*;

use s7::cotp::{ConnectionParams, Tpdu, TpduSize};
use s7::pdu::{
    DataItem, DataTransport, ErrorCode, ItemSpec, Pdu, Request, Response, ReturnCode,
    SetupCommunication, TransportSize, MAX_ITEMS,
};
use s7::split::{self, WriteItem};
use s7::{
    Address, Area, ClientConfig, Memory, Region, ServerConfig, Tsap, Value, ValueType, Width,
};

use crate::pair::Pair;

fn arb_item_spec() -> impl Strategy<Value = ItemSpec> {
    (
        any::<u8>(),
        any::<u16>(),
        any::<u16>(),
        any::<u8>(),
        0u32..=0xFF_FFFF,
    )
        .prop_map(
            |(size, count, db_number, area_code, bit_address)| ItemSpec {
                transport_size: TransportSize::from_code(size),
                count,
                db_number,
                area_code,
                bit_address,
            },
        )
}

fn arb_data_item() -> impl Strategy<Value = DataItem> {
    (
        any::<u8>(),
        any::<u8>(),
        proptest::collection::vec(any::<u8>(), 0..40),
    )
        .prop_map(|(code, transport, data)| DataItem {
            return_code: ReturnCode::from_code(code),
            transport: DataTransport::from_code(transport),
            data,
        })
}

fn arb_setup() -> impl Strategy<Value = SetupCommunication> {
    (any::<u16>(), any::<u16>(), any::<u16>()).prop_map(|(calling, called, pdu_size)| {
        SetupCommunication {
            max_amq_calling: calling,
            max_amq_called: called,
            pdu_size,
        }
    })
}

fn arb_error() -> impl Strategy<Value = ErrorCode> {
    (any::<u8>(), any::<u8>()).prop_map(|(class, code)| ErrorCode { class, code })
}

fn arb_other_function() -> impl Strategy<Value = u8> {
    any::<u8>().prop_filter("not a decoded function", |function| {
        !matches!(function, 0x04 | 0x05 | 0xF0)
    })
}

fn bytes(max: usize) -> impl Strategy<Value = Vec<u8>> {
    proptest::collection::vec(any::<u8>(), 0..max)
}

fn arb_request() -> impl Strategy<Value = Request> {
    prop_oneof![
        arb_setup().prop_map(Request::SetupCommunication),
        proptest::collection::vec(arb_item_spec(), 0..25).prop_map(Request::ReadVar),
        proptest::collection::vec((arb_item_spec(), arb_data_item()), 0..12)
            .prop_map(Request::WriteVar),
        (arb_other_function(), bytes(20), bytes(20)).prop_map(|(function, parameter, data)| {
            Request::Other {
                function,
                parameter,
                data,
            }
        }),
    ]
}

fn arb_response() -> impl Strategy<Value = Response> {
    prop_oneof![
        Just(Response::None),
        arb_setup().prop_map(Response::SetupCommunication),
        proptest::collection::vec(arb_data_item(), 0..25).prop_map(Response::ReadVar),
        proptest::collection::vec(any::<u8>().prop_map(ReturnCode::from_code), 0..25)
            .prop_map(Response::WriteVar),
        (arb_other_function(), bytes(20), bytes(20)).prop_map(|(function, parameter, data)| {
            Response::Other {
                function,
                parameter,
                data,
            }
        }),
    ]
}

fn arb_pdu() -> impl Strategy<Value = Pdu> {
    prop_oneof![
        (any::<u16>(), arb_request()).prop_map(|(pdu_ref, request)| Pdu::Job { pdu_ref, request }),
        (any::<u16>(), arb_error()).prop_map(|(pdu_ref, error)| Pdu::Ack { pdu_ref, error }),
        (any::<u16>(), arb_error(), arb_response()).prop_map(|(pdu_ref, error, response)| {
            Pdu::AckData {
                pdu_ref,
                error,
                response,
            }
        }),
        (any::<u16>(), bytes(30), bytes(30)).prop_map(|(pdu_ref, parameter, data)| {
            Pdu::UserData {
                pdu_ref,
                parameter,
                data,
            }
        }),
    ]
}

fn arb_tsap() -> impl Strategy<Value = Option<Tsap>> {
    proptest::option::of(bytes(12).prop_map(|bytes| Tsap::from_bytes(&bytes)))
}

fn arb_connection_params() -> impl Strategy<Value = ConnectionParams> {
    (
        any::<u16>(),
        any::<u16>(),
        any::<u8>(),
        proptest::option::of((7u8..=13).prop_map(|code| TpduSize::from_code(code).unwrap())),
        arb_tsap(),
        arb_tsap(),
    )
        .prop_map(
            |(dst_ref, src_ref, class, tpdu_size, calling_tsap, called_tsap)| ConnectionParams {
                dst_ref,
                src_ref,
                class,
                tpdu_size,
                calling_tsap,
                called_tsap,
            },
        )
}

fn arb_tpdu() -> impl Strategy<Value = Tpdu> {
    prop_oneof![
        arb_connection_params().prop_map(Tpdu::ConnectionRequest),
        arb_connection_params().prop_map(Tpdu::ConnectionConfirm),
        (any::<u16>(), any::<u16>(), any::<u8>()).prop_map(|(dst_ref, src_ref, reason)| {
            Tpdu::DisconnectRequest {
                dst_ref,
                src_ref,
                reason,
            }
        }),
        (any::<u16>(), any::<u16>())
            .prop_map(|(dst_ref, src_ref)| Tpdu::DisconnectConfirm { dst_ref, src_ref }),
        (any::<bool>(), 0u8..128, bytes(100)).prop_map(|(eot, number, payload)| Tpdu::Data {
            eot,
            number,
            payload
        }),
        (any::<u16>(), any::<u8>()).prop_map(|(dst_ref, cause)| Tpdu::Error { dst_ref, cause }),
    ]
}

fn arb_area() -> impl Strategy<Value = Area> {
    prop_oneof![
        Just(Area::Inputs),
        Just(Area::Outputs),
        Just(Area::Markers),
        (1u16..=u16::MAX).prop_map(Area::DataBlock),
    ]
}

fn arb_region(max_len: u32) -> impl Strategy<Value = Region> {
    prop_oneof![
        (arb_area(), 0u32..5000, 0u8..8).prop_map(|(area, byte, bit)| Region::Bit {
            area,
            byte,
            bit
        }),
        (arb_area(), 0u32..5000, 1..=max_len).prop_map(|(area, start, len)| Region::Bytes {
            area,
            start,
            len
        }),
    ]
}

/// Pieces of every batch, in order, must tile each item exactly once, in item order.
fn assert_tiles(batches: &[split::Batch], regions: &[Region]) {
    let mut next = vec![0u32; regions.len()];
    let mut last_item = 0;
    for batch in batches {
        assert!(!batch.pieces.is_empty());
        assert!(batch.pieces.len() <= MAX_ITEMS);
        for piece in &batch.pieces {
            assert!(piece.item >= last_item, "pieces out of order");
            last_item = piece.item;
            let region = regions[piece.item];
            assert_eq!(piece.offset, next[piece.item], "a gap or an overlap");
            assert_eq!(piece.region.area(), region.area());
            assert_eq!(piece.region.start(), region.start() + piece.offset);
            if let Region::Bit { .. } = region {
                assert_eq!(piece.region, region);
            }
            next[piece.item] += piece.region.data_len();
        }
    }
    for (item, region) in regions.iter().enumerate() {
        assert_eq!(next[item], region.data_len(), "item {item} not covered");
    }
}

proptest! {
    #[test]
    fn pdus_round_trip(pdu in arb_pdu()) {
        let bytes = pdu.to_bytes().unwrap();
        prop_assert_eq!(Pdu::decode(&bytes).unwrap(), pdu);
    }

    #[test]
    fn tpdus_round_trip(tpdu in arb_tpdu()) {
        let mut bytes = Vec::new();
        tpdu.encode(&mut bytes).unwrap();
        prop_assert_eq!(Tpdu::decode(&bytes).unwrap(), tpdu);
    }

    #[test]
    fn decoders_never_panic_on_arbitrary_bytes(bytes in bytes(400)) {
        let _ = Pdu::decode(&bytes);
        let _ = Tpdu::decode(&bytes);
        s7::fuzz_decode(&bytes);
    }

    #[test]
    fn decoders_never_panic_on_mutated_frames(
        pdu in arb_pdu(),
        mutations in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..6),
        cut in any::<prop::sample::Index>(),
    ) {
        let mut bytes = pdu.to_bytes().unwrap();
        for (index, value) in mutations {
            let at = index.index(bytes.len());
            bytes[at] = value;
        }
        let _ = Pdu::decode(&bytes);
        let _ = Pdu::decode(&bytes[..cut.index(bytes.len() + 1)]);
        // The same bytes as a job on a connected server.
        let mut frame = Vec::new();
        let mut dt = vec![0x02, 0xF0, 0x80];
        dt.extend_from_slice(&bytes);
        s7::tpkt::encode(&dt, &mut frame).unwrap();
        let mut pair = Pair::new(ClientConfig::default(), ServerConfig::default(), Memory::default());
        pair.connect();
        pair.server.handle_input(&frame, &mut pair.memory);
        pair.client.handle_input(&frame);
        let mut out = Vec::new();
        while pair.server.poll_transmit(&mut out) {}
        while pair.client.poll_transmit(&mut out) {}
    }

    #[test]
    fn read_splitting_fits_the_pdu_size_both_ways(
        regions in proptest::collection::vec(arb_region(1500), 0..40),
        pdu_size in 64u16..=960,
    ) {
        let batches = split::split_reads(&regions, pdu_size).unwrap();
        assert_tiles(&batches, &regions);
        for (index, batch) in batches.iter().enumerate() {
            let job = split::read_job(batch, index as u16).to_bytes().unwrap();
            prop_assert!(job.len() <= usize::from(pdu_size), "job of {} bytes", job.len());
            let answer = Pdu::AckData {
                pdu_ref: 0,
                error: ErrorCode::NONE,
                response: Response::ReadVar(
                    batch
                        .pieces
                        .iter()
                        .map(|piece| DataItem {
                            return_code: ReturnCode::Success,
                            transport: DataTransport::Bytes,
                            data: vec![0; piece.region.data_len() as usize],
                        })
                        .collect(),
                ),
            }
            .to_bytes()
            .unwrap();
            prop_assert_eq!(answer.len(), split::read_answer_len(batch));
            prop_assert!(answer.len() <= usize::from(pdu_size), "answer of {} bytes", answer.len());
        }
    }

    #[test]
    fn write_splitting_fits_the_pdu_size_both_ways(
        regions in proptest::collection::vec(arb_region(1500), 0..30),
        pdu_size in 64u16..=960,
    ) {
        let items: Vec<WriteItem> = regions
            .iter()
            .map(|region| WriteItem {
                region: *region,
                data: vec![1; region.data_len() as usize],
            })
            .collect();
        let batches = split::split_writes(&items, pdu_size).unwrap();
        assert_tiles(&batches, &regions);
        for batch in &batches {
            let job = split::write_job(batch, &items, 0).to_bytes().unwrap();
            prop_assert!(job.len() <= usize::from(pdu_size), "job of {} bytes", job.len());
            let answer = Pdu::AckData {
                pdu_ref: 0,
                error: ErrorCode::NONE,
                response: Response::WriteVar(vec![ReturnCode::Success; batch.pieces.len()]),
            }
            .to_bytes()
            .unwrap();
            prop_assert_eq!(answer.len(), split::write_answer_len(batch));
            prop_assert!(answer.len() <= usize::from(pdu_size));
        }
    }

    #[test]
    fn reads_through_both_ends_give_memory_back(
        image in proptest::collection::vec(any::<u8>(), 2000),
        regions in proptest::collection::vec(
            prop_oneof![
                (0u32..2000, 0u8..8).prop_map(|(byte, bit)| Region::Bit { area: Area::DataBlock(1), byte, bit }),
                (0u32..2000, 1u32..600).prop_map(|(start, len)| Region::Bytes {
                    area: Area::DataBlock(1),
                    start,
                    len: len.min(2000 - start).max(1),
                }),
            ],
            0..30,
        ),
        max_pdu_size in 64u16..=960,
        max_jobs in 1u16..4,
    ) {
        let mut memory = Memory::default();
        memory.add_data_block(1, 2000).unwrap();
        memory.area_mut(Area::DataBlock(1)).unwrap().copy_from_slice(&image);
        let mut server = ServerConfig::default();
        server.max_pdu_size = max_pdu_size;
        server.max_jobs = max_jobs;
        let mut client = ClientConfig::default();
        client.pdu_size = 960;
        let mut pair = Pair::new(client, server, memory);
        pair.connect();
        let results = pair.read(regions.clone());
        for (region, result) in regions.iter().zip(results) {
            let expected = match *region {
                Region::Bit { byte, bit, .. } => vec![(image[byte as usize] >> bit) & 1],
                Region::Bytes { start, len, .. } => image[start as usize..(start + len) as usize].to_vec(),
            };
            prop_assert_eq!(result, Ok(expected));
        }
        for (len, _) in pair.client_pdus.iter().chain(&pair.server_pdus) {
            prop_assert!(*len <= usize::from(max_pdu_size));
        }
        prop_assert!(pair.max_burst <= usize::from(max_jobs));
    }

    #[test]
    fn addresses_display_and_parse_back(
        area in arb_area(),
        byte in 0u32..=0x1F_FFFB,
        width in prop_oneof![
            (0u8..8).prop_map(Width::Bit),
            Just(Width::Byte),
            Just(Width::Word),
            Just(Width::DWord),
        ],
        type_index in 0usize..8,
    ) {
        let value_type = ValueType::ALL[type_index];
        if let Ok(address) = Address::new(area, byte, width, value_type) {
            let text = address.to_string();
            prop_assert_eq!(text.parse::<Address>().unwrap(), address);
            prop_assert_eq!(text.to_lowercase().parse::<Address>().unwrap(), address);
        }
    }

    #[test]
    fn values_display_and_parse_back(
        value in prop_oneof![
            any::<bool>().prop_map(Value::Bool),
            any::<u8>().prop_map(Value::Byte),
            any::<i8>().prop_map(Value::SInt),
            any::<u16>().prop_map(Value::Word),
            any::<i16>().prop_map(Value::Int),
            any::<u32>().prop_map(Value::DWord),
            any::<i32>().prop_map(Value::DInt),
            any::<f32>().prop_filter("finite", |real| real.is_finite()).prop_map(Value::Real),
        ]
    ) {
        let text = value.to_string();
        prop_assert_eq!(Value::parse(value.value_type(), &text).unwrap(), value);
        prop_assert_eq!(Value::from_bytes(value.value_type(), &value.to_bytes()).unwrap(), value);
    }
}
