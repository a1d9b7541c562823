//! Property tests: every valid request and answer round-trips through its encoding, RTU
//! frames through their CRC (a flipped bit never passes), ADUs through the MBAP deframer
//! however the stream is cut, a server's answer decodes as the answer to its request;
//! arbitrary octets never panic a decoder or a server.

use modbus::rtu::{decode_frame, frame, RtuDeframer};
use modbus::server::{answer, Outcome};
use modbus::tcp::{Adu, MbapDeframer};
use modbus::{Answer, DataModel, ExceptionCode, Framing, Request, Response, Table};
use proptest::prelude::*;

fn table() -> impl Strategy<Value = Table> {
    prop::sample::select(Table::ALL.to_vec())
}

fn request() -> impl Strategy<Value = Request> {
    prop_oneof![
        (table(), any::<u16>(), 1u16..=125).prop_map(|(t, a, c)| Request::read(t, a, c)),
        (any::<u16>(), 1u16..=2000).prop_map(|(a, c)| Request::read(Table::Coils, a, c)),
        (any::<u16>(), any::<bool>())
            .prop_map(|(address, value)| Request::WriteSingleCoil { address, value }),
        (any::<u16>(), any::<u16>())
            .prop_map(|(address, value)| Request::WriteSingleRegister { address, value }),
        (any::<u16>(), prop::collection::vec(any::<bool>(), 1..=1968))
            .prop_map(|(address, values)| Request::WriteMultipleCoils { address, values }),
        (any::<u16>(), prop::collection::vec(any::<u16>(), 1..=123))
            .prop_map(|(address, values)| Request::WriteMultipleRegisters { address, values }),
        (
            any::<u16>(),
            1u16..=125,
            any::<u16>(),
            prop::collection::vec(any::<u16>(), 1..=121)
        )
            .prop_map(|(read_address, read_count, write_address, values)| {
                Request::ReadWriteMultipleRegisters {
                    read_address,
                    read_count,
                    write_address,
                    values,
                }
            }),
    ]
}

/// A request and a valid response to it.
fn exchange() -> impl Strategy<Value = (Request, Response)> {
    request().prop_flat_map(|request| {
        let response: BoxedStrategy<Response> = match &request {
            Request::Read { table, count, .. } => {
                let count = usize::from(*count);
                match table {
                    Table::Coils => prop::collection::vec(any::<bool>(), count)
                        .prop_map(Response::ReadCoils)
                        .boxed(),
                    Table::DiscreteInputs => prop::collection::vec(any::<bool>(), count)
                        .prop_map(Response::ReadDiscreteInputs)
                        .boxed(),
                    Table::HoldingRegisters => prop::collection::vec(any::<u16>(), count)
                        .prop_map(Response::ReadHoldingRegisters)
                        .boxed(),
                    Table::InputRegisters => prop::collection::vec(any::<u16>(), count)
                        .prop_map(Response::ReadInputRegisters)
                        .boxed(),
                }
            }
            Request::WriteSingleCoil { address, value } => Just(Response::WriteSingleCoil {
                address: *address,
                value: *value,
            })
            .boxed(),
            Request::WriteSingleRegister { address, value } => {
                Just(Response::WriteSingleRegister {
                    address: *address,
                    value: *value,
                })
                .boxed()
            }
            Request::WriteMultipleCoils { address, values } => Just(Response::WriteMultipleCoils {
                address: *address,
                count: values.len() as u16,
            })
            .boxed(),
            Request::WriteMultipleRegisters { address, values } => {
                Just(Response::WriteMultipleRegisters {
                    address: *address,
                    count: values.len() as u16,
                })
                .boxed()
            }
            Request::ReadWriteMultipleRegisters { read_count, .. } => {
                prop::collection::vec(any::<u16>(), usize::from(*read_count))
                    .prop_map(Response::ReadWriteMultipleRegisters)
                    .boxed()
            }
        };
        (Just(request), response)
    })
}

proptest! {
    #[test]
    fn requests_round_trip(request in request()) {
        let pdu = request.to_pdu().unwrap();
        prop_assert!(pdu.len() <= modbus::pdu::MAX_PDU);
        prop_assert_eq!(Request::decode(&pdu), Ok(request));
    }

    #[test]
    fn answers_round_trip((request, response) in exchange(), code in 1u8..=0x7F) {
        for answer in [Answer::Response(response), Answer::Exception(ExceptionCode(code))] {
            let mut pdu = Vec::new();
            answer.encode(request.function(), &mut pdu);
            prop_assert!(pdu.len() <= modbus::pdu::MAX_PDU);
            prop_assert_eq!(Answer::decode(&request, &pdu), Ok(answer));
        }
    }

    #[test]
    fn a_servers_answer_is_an_answer_to_its_request(request in request(), unit in 0u8..=255) {
        let model = DataModel::default();
        let pdu = request.to_pdu().unwrap();
        match answer(&model, Framing::Tcp, unit, &pdu) {
            Outcome::Answer(got) => {
                let decoded = Answer::decode(&request, &got);
                prop_assert!(decoded.is_ok(), "{:?} -> {:?}: {:?}", request, got, decoded);
            }
            other => prop_assert!(false, "no answer: {:?}", other),
        }
    }

    #[test]
    fn rtu_frames_round_trip_and_a_flipped_bit_fails_the_crc(
        unit in any::<u8>(),
        pdu in prop::collection::vec(any::<u8>(), 1..=253),
        flip in any::<prop::sample::Index>(),
        bit in 0u8..8,
    ) {
        let octets = frame(unit, &pdu);
        prop_assert_eq!(decode_frame(&octets), Some((unit, &pdu[..])));
        let mut broken = octets.clone();
        let at = flip.index(broken.len());
        broken[at] ^= 1 << bit;
        prop_assert_eq!(decode_frame(&broken), None);
    }

    #[test]
    fn rtu_requests_are_cut_however_the_octets_come(
        requests in prop::collection::vec((1u8..=247, request()), 1..5),
        cuts in prop::collection::vec(1usize..20, 1..50),
    ) {
        let mut stream = Vec::new();
        for (unit, request) in &requests {
            stream.extend(frame(*unit, &request.to_pdu().unwrap()));
        }
        let mut deframer = RtuDeframer::new();
        let mut got = Vec::new();
        let mut rest = &stream[..];
        for cut in cuts.iter().cycle() {
            if rest.is_empty() {
                break;
            }
            let (piece, tail) = rest.split_at((*cut).min(rest.len()));
            deframer.push(piece);
            got.extend(std::iter::from_fn(|| deframer.next_frame()));
            rest = tail;
        }
        got.extend(deframer.handle_pause());
        let decoded: Vec<(u8, Request)> = got
            .into_iter()
            .map(|frame| (frame.unit, Request::decode(&frame.pdu).unwrap()))
            .collect();
        prop_assert_eq!(decoded, requests);
    }

    #[test]
    fn adus_are_cut_however_the_stream_comes(
        adus in prop::collection::vec(
            (any::<u16>(), any::<u8>(), prop::collection::vec(any::<u8>(), 1..=253)),
            1..5,
        ),
        cuts in prop::collection::vec(1usize..300, 1..30),
    ) {
        let adus: Vec<Adu> = adus
            .into_iter()
            .map(|(transaction, unit, pdu)| Adu { transaction, protocol: 0, unit, pdu })
            .collect();
        let stream: Vec<u8> = adus.iter().flat_map(Adu::to_bytes).collect();
        let mut deframer = MbapDeframer::new();
        let mut got = Vec::new();
        let mut rest = &stream[..];
        for cut in cuts.iter().cycle() {
            if rest.is_empty() {
                break;
            }
            let (piece, tail) = rest.split_at((*cut).min(rest.len()));
            deframer.push(piece);
            while let Some(adu) = deframer.next_frame().unwrap() {
                got.push(adu);
            }
            rest = tail;
        }
        prop_assert_eq!(got, adus);
    }

    #[test]
    fn arbitrary_octets_never_panic(octets in prop::collection::vec(any::<u8>(), 0..600)) {
        modbus::fuzz_decode(&octets, tokio::time::Instant::now().into_std());
    }

    #[test]
    fn arbitrary_request_pdus_are_answered_or_ignored(
        pdu in prop::collection::vec(any::<u8>(), 0..260),
    ) {
        let model = DataModel::default();
        match answer(&model, Framing::Tcp, 1, &pdu) {
            Outcome::Answer(got) => {
                prop_assert!(!got.is_empty() && got.len() <= modbus::pdu::MAX_PDU);
                prop_assert_eq!(got[0] & 0x7F, pdu[0]);
            }
            Outcome::Ignored => prop_assert!(pdu.is_empty() || pdu[0] >= 0x80),
            other => prop_assert!(false, "{:?}", other),
        }
    }
}
