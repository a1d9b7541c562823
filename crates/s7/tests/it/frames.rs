//! Frame vectors written from the protocol description (RFC 1006, ISO 8073 class 0, the
//! S7comm field layout), encoded and decoded, and the errors of each decoder.

use s7::cotp::{ConnectionParams, CotpError, Tpdu, TpduSize};
use s7::pdu::{
    DataItem, DataTransport, ErrorCode, ItemSpec, Pdu, PduError, Request, Response, ReturnCode,
    SetupCommunication, TransportSize,
};
use s7::tpkt::{self, Deframer, TpktError};
use s7::{Area, ClientConfig, ClientConnection, Region, Tsap, Tsaps};

/// The connection request of a client to rack 0, slot 1: TPDU size 1024, calling TSAP
/// 0x0100, called TSAP 0x0301.
const CONNECTION_REQUEST: [u8; 22] = [
    0x03, 0x00, 0x00, 0x16, // TPKT
    0x11, 0xE0, 0x00, 0x00, 0x00, 0x01, 0x00, // LI 17, CR, dst 0, src 1, class 0
    0xC0, 0x01, 0x0A, // TPDU size 2^10
    0xC1, 0x02, 0x01, 0x00, // calling TSAP
    0xC2, 0x02, 0x03, 0x01, // called TSAP
];

/// A PLC's confirm of it.
const CONNECTION_CONFIRM: [u8; 22] = [
    0x03, 0x00, 0x00, 0x16, 0x11, 0xD0, 0x00, 0x01, 0x00, 0x01, 0x00, 0xC0, 0x01, 0x0A, 0xC1, 0x02,
    0x01, 0x00, 0xC2, 0x02, 0x03, 0x01,
];

/// Setup communication asking 3 parallel jobs each way and a PDU of 480, reference 1.
const SETUP_JOB: [u8; 25] = [
    0x03, 0x00, 0x00, 0x19, // TPKT
    0x02, 0xF0, 0x80, // DT, EOT
    0x32, 0x01, 0x00, 0x00, 0x00, 0x01, 0x00, 0x08, 0x00, 0x00, // job, ref 1, param 8
    0xF0, 0x00, 0x00, 0x03, 0x00, 0x03, 0x01, 0xE0,
];

/// An S7-1200's answer: a PDU of 240.
const SETUP_ACK: [u8; 27] = [
    0x03, 0x00, 0x00, 0x1B, 0x02, 0xF0, 0x80, // TPKT, DT
    0x32, 0x03, 0x00, 0x00, 0x00, 0x01, 0x00, 0x08, 0x00, 0x00, 0x00, 0x00, // ack_data
    0xF0, 0x00, 0x00, 0x03, 0x00, 0x03, 0x00, 0xF0,
];

/// Read var of DB1.DBW2 as two bytes, reference 2.
const READ_DB1_DBW2: [u8; 24] = [
    0x32, 0x01, 0x00, 0x00, 0x00, 0x02, 0x00, 0x0E, 0x00, 0x00, // job, param 14
    0x04, 0x01, // read var, one item
    0x12, 0x0A, 0x10, 0x02, 0x00, 0x02, 0x00, 0x01, 0x84, 0x00, 0x00,
    0x10, // byte x2, DB1, 2.0
];

/// Its answer: 0x1234.
const READ_DB1_DBW2_ACK: [u8; 20] = [
    0x32, 0x03, 0x00, 0x00, 0x00, 0x02, 0x00, 0x02, 0x00, 0x06, 0x00, 0x00, // ack_data
    0x04, 0x01, // read var, one item
    0xFF, 0x04, 0x00, 0x10, 0x12, 0x34, // success, bytes, 16 bits
];

/// Write var of M10.3 := 1 as a bit, reference 3.
const WRITE_M10_3: [u8; 29] = [
    0x32, 0x01, 0x00, 0x00, 0x00, 0x03, 0x00, 0x0E, 0x00, 0x05, // job, param 14, data 5
    0x05, 0x01, // write var, one item
    0x12, 0x0A, 0x10, 0x01, 0x00, 0x01, 0x00, 0x00, 0x83, 0x00, 0x00, 0x53, // bit, M, 10.3
    0x00, 0x03, 0x00, 0x01, 0x01, // bit, length 1, value 1
];

/// Its answer.
const WRITE_M10_3_ACK: [u8; 15] = [
    0x32, 0x03, 0x00, 0x00, 0x00, 0x03, 0x00, 0x02, 0x00, 0x01, 0x00, 0x00, 0x05, 0x01, 0xFF,
];

/// A read answer of three items: one byte (odd: a fill byte follows), a missing DB, a
/// word (last: no fill).
const READ_ACK_WITH_FILL: [u8; 29] = [
    0x32, 0x03, 0x00, 0x00, 0x00, 0x07, 0x00, 0x02, 0x00, 0x0F, 0x00, 0x00, // data 15
    0x04, 0x03, //
    0xFF, 0x04, 0x00, 0x08, 0xAA, 0x00, // one byte and its fill
    0x0A, 0x00, 0x00, 0x00, // object does not exist, no data
    0xFF, 0x04, 0x00, 0x08, 0xBB, // one byte, the last: no fill
];

fn tpkt_payload(frame: &[u8]) -> &[u8] {
    &frame[4..]
}

fn dt_payload(frame: &[u8]) -> &[u8] {
    &frame[7..]
}

#[test]
fn the_connection_request_for_rack_0_slot_1() {
    let tpdu = Tpdu::ConnectionRequest(ConnectionParams {
        dst_ref: 0,
        src_ref: 1,
        class: 0,
        tpdu_size: Some(TpduSize::S7),
        calling_tsap: Some(Tsap::new(0x0100)),
        called_tsap: Some(Tsap::new(0x0301)),
    });
    let mut payload = Vec::new();
    tpdu.encode(&mut payload).unwrap();
    let mut frame = Vec::new();
    tpkt::encode(&payload, &mut frame).unwrap();
    assert_eq!(frame, CONNECTION_REQUEST);
    assert_eq!(
        Tpdu::decode(tpkt_payload(&CONNECTION_REQUEST)).unwrap(),
        tpdu
    );

    // And it is what a client sends first.
    let mut client = ClientConnection::new(ClientConfig::new(Tsaps::rack_slot(0, 1)));
    let mut out = Vec::new();
    assert!(client.poll_transmit(&mut out));
    assert_eq!(out, CONNECTION_REQUEST);
    assert!(!client.poll_transmit(&mut out));
}

#[test]
fn the_client_answers_the_confirm_with_setup_communication_and_takes_the_grant() {
    let mut client = ClientConnection::new(ClientConfig::default());
    let mut out = Vec::new();
    assert!(client.poll_transmit(&mut out));
    client.handle_input(&CONNECTION_CONFIRM);
    assert!(client.poll_transmit(&mut out));
    assert_eq!(out, SETUP_JOB);
    assert_eq!(
        Pdu::decode(dt_payload(&SETUP_JOB)).unwrap(),
        Pdu::Job {
            pdu_ref: 1,
            request: Request::SetupCommunication(SetupCommunication {
                max_amq_calling: 3,
                max_amq_called: 3,
                pdu_size: 480
            })
        }
    );
    // The answer split across two reads of the socket.
    client.handle_input(&SETUP_ACK[..10]);
    assert_eq!(client.poll_event(), None);
    client.handle_input(&SETUP_ACK[10..]);
    assert_eq!(
        client.poll_event(),
        Some(s7::ClientEvent::Connected {
            pdu_size: 240,
            max_jobs: 3
        })
    );
    assert_eq!(client.pdu_size(), Some(240));

    // A read of DB1.DBW2 goes out as the vector's job (reference 2).
    client
        .read(vec![Region::Bytes {
            area: Area::DataBlock(1),
            start: 2,
            len: 2,
        }])
        .unwrap();
    assert!(client.poll_transmit(&mut out));
    assert_eq!(dt_payload(&out), READ_DB1_DBW2);
    let mut answer = Vec::new();
    tpkt::encode(
        &[&[0x02, 0xF0, 0x80][..], &READ_DB1_DBW2_ACK].concat(),
        &mut answer,
    )
    .unwrap();
    client.handle_input(&answer);
    match client.poll_event() {
        Some(s7::ClientEvent::ReadDone { results, .. }) => {
            assert_eq!(results, vec![Ok(vec![0x12, 0x34])]);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn setup_communication_vectors_round_trip() {
    let ack = Pdu::AckData {
        pdu_ref: 1,
        error: ErrorCode::NONE,
        response: Response::SetupCommunication(SetupCommunication {
            max_amq_calling: 3,
            max_amq_called: 3,
            pdu_size: 240,
        }),
    };
    assert_eq!(Pdu::decode(dt_payload(&SETUP_ACK)).unwrap(), ack);
    assert_eq!(ack.to_bytes().unwrap(), dt_payload(&SETUP_ACK));
}

#[test]
fn read_var_of_db1_dbw2() {
    let item = ItemSpec::for_region(&"DB1.DBW2".parse::<s7::Address>().unwrap().region()).unwrap();
    assert_eq!(
        item,
        ItemSpec {
            transport_size: TransportSize::Byte,
            count: 2,
            db_number: 1,
            area_code: 0x84,
            bit_address: 16
        }
    );
    let job = Pdu::Job {
        pdu_ref: 2,
        request: Request::ReadVar(vec![item]),
    };
    assert_eq!(job.to_bytes().unwrap(), READ_DB1_DBW2);
    assert_eq!(Pdu::decode(&READ_DB1_DBW2).unwrap(), job);

    let ack = Pdu::AckData {
        pdu_ref: 2,
        error: ErrorCode::NONE,
        response: Response::ReadVar(vec![DataItem {
            return_code: ReturnCode::Success,
            transport: DataTransport::Bytes,
            data: vec![0x12, 0x34],
        }]),
    };
    assert_eq!(ack.to_bytes().unwrap(), READ_DB1_DBW2_ACK);
    assert_eq!(Pdu::decode(&READ_DB1_DBW2_ACK).unwrap(), ack);
}

#[test]
fn write_var_of_a_single_bit() {
    let job = Pdu::Job {
        pdu_ref: 3,
        request: Request::WriteVar(vec![(
            ItemSpec::for_region(&Region::Bit {
                area: Area::Markers,
                byte: 10,
                bit: 3,
            })
            .unwrap(),
            DataItem {
                return_code: ReturnCode::Reserved,
                transport: DataTransport::Bit,
                data: vec![1],
            },
        )]),
    };
    assert_eq!(job.to_bytes().unwrap(), WRITE_M10_3);
    assert_eq!(Pdu::decode(&WRITE_M10_3).unwrap(), job);
    let ack = Pdu::AckData {
        pdu_ref: 3,
        error: ErrorCode::NONE,
        response: Response::WriteVar(vec![ReturnCode::Success]),
    };
    assert_eq!(ack.to_bytes().unwrap(), WRITE_M10_3_ACK);
    assert_eq!(Pdu::decode(&WRITE_M10_3_ACK).unwrap(), ack);
}

#[test]
fn data_items_of_odd_length_get_a_fill_byte_except_the_last() {
    let ack = Pdu::AckData {
        pdu_ref: 7,
        error: ErrorCode::NONE,
        response: Response::ReadVar(vec![
            DataItem {
                return_code: ReturnCode::Success,
                transport: DataTransport::Bytes,
                data: vec![0xAA],
            },
            DataItem::error(ReturnCode::ObjectDoesNotExist),
            DataItem {
                return_code: ReturnCode::Success,
                transport: DataTransport::Bytes,
                data: vec![0xBB],
            },
        ]),
    };
    assert_eq!(ack.to_bytes().unwrap(), READ_ACK_WITH_FILL);
    assert_eq!(Pdu::decode(&READ_ACK_WITH_FILL).unwrap(), ack);
    // Without the fill byte the items cannot be told apart.
    let mut missing_fill = READ_ACK_WITH_FILL.to_vec();
    missing_fill.remove(19);
    missing_fill[9] = 0x0E;
    assert!(Pdu::decode(&missing_fill).is_err());
}

#[test]
fn data_item_lengths_count_bits_or_bytes_by_transport_size() {
    // A REAL (0x07) and an octet string (0x09) count bytes, an integer (0x05) bits.
    let bytes = [
        0x32, 0x03, 0x00, 0x00, 0x00, 0x01, 0x00, 0x02, 0x00, 0x14, 0x00, 0x00, //
        0x04, 0x03, //
        0xFF, 0x07, 0x00, 0x04, 0x3F, 0x80, 0x00, 0x00, //
        0xFF, 0x09, 0x00, 0x02, 0x01, 0x02, //
        0xFF, 0x05, 0x00, 0x10, 0xFF, 0xFE,
    ];
    let Pdu::AckData {
        response: Response::ReadVar(items),
        ..
    } = Pdu::decode(&bytes).unwrap()
    else {
        panic!()
    };
    assert_eq!(items[0].transport, DataTransport::Real);
    assert_eq!(items[0].data, [0x3F, 0x80, 0, 0]);
    assert_eq!(items[1].data, [1, 2]);
    assert_eq!(items[2].transport, DataTransport::Integer);
    assert_eq!(items[2].data, [0xFF, 0xFE]);
}

#[test]
fn an_error_answer_without_parameter() {
    let bytes = [
        0x32, 0x03, 0x00, 0x00, 0x00, 0x09, 0x00, 0x00, 0x00, 0x00, 0x81, 0x04,
    ];
    let pdu = Pdu::decode(&bytes).unwrap();
    assert_eq!(
        pdu,
        Pdu::AckData {
            pdu_ref: 9,
            error: ErrorCode::FUNCTION_NOT_IMPLEMENTED,
            response: Response::None
        }
    );
    assert_eq!(ErrorCode::FUNCTION_NOT_IMPLEMENTED.to_string(), "0x8104");
}

#[test]
fn tpkt_frames_are_cut_from_a_stream() {
    let mut deframer = Deframer::new();
    deframer.push(&CONNECTION_REQUEST[..3]);
    assert_eq!(deframer.next_frame(), Ok(None));
    deframer.push(&CONNECTION_REQUEST[3..]);
    deframer.push(&CONNECTION_CONFIRM);
    deframer.push(&SETUP_JOB[..5]);
    assert_eq!(
        deframer.next_frame().unwrap().as_deref(),
        Some(tpkt_payload(&CONNECTION_REQUEST))
    );
    assert_eq!(
        deframer.next_frame().unwrap().as_deref(),
        Some(tpkt_payload(&CONNECTION_CONFIRM))
    );
    assert_eq!(deframer.next_frame(), Ok(None));
    assert_eq!(deframer.buffered(), 5);
}

#[test]
fn tpkt_errors() {
    let mut deframer = Deframer::new();
    deframer.push(&[0x04, 0x00, 0x00, 0x07, 0x02, 0xF0, 0x80]);
    assert_eq!(deframer.next_frame(), Err(TpktError::BadVersion(4)));
    // A wrong version is seen on its first byte, before a header is complete.
    let mut deframer = Deframer::new();
    deframer.push(b"G");
    assert_eq!(deframer.next_frame(), Err(TpktError::BadVersion(b'G')));
    let mut deframer = Deframer::new();
    deframer.push(&[0x03, 0x00, 0x00, 0x05, 0x00]);
    assert_eq!(deframer.next_frame(), Err(TpktError::BadLength(5)));
    let mut out = Vec::new();
    assert_eq!(
        tpkt::encode(&vec![0; 65_532], &mut out),
        Err(TpktError::TooLong(65_532))
    );
}

#[test]
fn cotp_data_disconnect_and_errors() {
    assert_eq!(
        Tpdu::decode(&[0x02, 0xF0, 0x80, 0x32]).unwrap(),
        Tpdu::Data {
            eot: true,
            number: 0,
            payload: vec![0x32]
        }
    );
    assert_eq!(
        Tpdu::decode(&[0x02, 0xF0, 0x00]).unwrap(),
        Tpdu::Data {
            eot: false,
            number: 0,
            payload: vec![]
        }
    );
    assert_eq!(
        Tpdu::decode(&[0x06, 0x80, 0x00, 0x01, 0x00, 0x02, 0x80]).unwrap(),
        Tpdu::DisconnectRequest {
            dst_ref: 1,
            src_ref: 2,
            reason: 0x80
        }
    );
    assert_eq!(
        Tpdu::decode(&[0x04, 0x70, 0x00, 0x01, 0x03]).unwrap(),
        Tpdu::Error {
            dst_ref: 1,
            cause: 3
        }
    );
    assert_eq!(Tpdu::decode(&[]), Err(CotpError::Truncated));
    assert_eq!(Tpdu::decode(&[0x05, 0xE0, 0x00]), Err(CotpError::Truncated));
    assert_eq!(
        Tpdu::decode(&[0x02, 0xE0, 0x00]),
        Err(CotpError::BadLengthIndicator(2))
    );
    assert_eq!(
        Tpdu::decode(&[0x02, 0x50, 0x00]),
        Err(CotpError::UnknownTpdu(0x50))
    );
    assert_eq!(
        Tpdu::decode(&[0x09, 0xE0, 0, 0, 0, 1, 0, 0xC0, 0x01, 0x0F]),
        Err(CotpError::BadTpduSize(0x0F))
    );
    assert_eq!(
        Tpdu::decode(&[0x09, 0xE0, 0, 0, 0, 1, 0, 0xC1, 0x04, 0x01]),
        Err(CotpError::BadParameter(0xC1))
    );
    // Parameters class 0 does not use are skipped.
    let Tpdu::ConnectionRequest(params) = Tpdu::decode(&[
        0x0C, 0xE0, 0, 0, 0, 1, 0, 0xC6, 0x01, 0x00, 0xC0, 0x01, 0x09,
    ])
    .unwrap() else {
        panic!()
    };
    assert_eq!(params.tpdu_size, TpduSize::from_code(9));
}

#[test]
fn pdu_errors() {
    assert_eq!(Pdu::decode(&[]), Err(PduError::Truncated));
    assert_eq!(
        Pdu::decode(&[0x33, 0x01]),
        Err(PduError::BadProtocolId(0x33))
    );
    assert_eq!(Pdu::decode(&[0x32, 0x05]), Err(PduError::UnknownRosctr(5)));
    let mut trailing = READ_DB1_DBW2.to_vec();
    trailing.push(0);
    assert_eq!(Pdu::decode(&trailing), Err(PduError::TrailingBytes(1)));
    assert_eq!(Pdu::decode(&READ_DB1_DBW2[..20]), Err(PduError::Truncated));
    // A symbolic (S7-1200 optimised) item, syntax id 0xB2, is not S7ANY.
    let mut symbolic = READ_DB1_DBW2.to_vec();
    symbolic[14] = 0xB2;
    assert_eq!(
        Pdu::decode(&symbolic),
        Err(PduError::UnsupportedItem {
            specification_type: 0x12,
            length: 0x0A,
            syntax_id: 0xB2
        })
    );
    // A parameter announcing two items and holding one.
    let mut short = READ_DB1_DBW2.to_vec();
    short[11] = 2;
    assert_eq!(Pdu::decode(&short), Err(PduError::Truncated));
    let too_many = Pdu::Job {
        pdu_ref: 0,
        request: Request::ReadVar(vec![
            ItemSpec::for_region(&Region::Bit {
                area: Area::Markers,
                byte: 0,
                bit: 0
            })
            .unwrap();
            256
        ]),
    };
    assert_eq!(too_many.to_bytes(), Err(PduError::TooLong));
}

#[test]
fn item_specs_a_server_cannot_serve_map_to_return_codes() {
    let item = |transport_size, count, area_code, db_number, bit_address| ItemSpec {
        transport_size,
        count,
        db_number,
        area_code,
        bit_address,
    };
    // Timers (0x1D) and counters (0x1C) are areas not served; DB0 does not exist.
    assert_eq!(
        item(TransportSize::Byte, 1, 0x1D, 0, 0).region(),
        Err(ReturnCode::ObjectDoesNotExist)
    );
    assert_eq!(
        item(TransportSize::Byte, 1, 0x84, 0, 0).region(),
        Err(ReturnCode::ObjectDoesNotExist)
    );
    assert_eq!(
        item(TransportSize::Other(0x1C), 1, 0x83, 0, 0).region(),
        Err(ReturnCode::TypeNotSupported)
    );
    assert_eq!(
        item(TransportSize::Bit, 2, 0x83, 0, 0).region(),
        Err(ReturnCode::TypeNotSupported)
    );
    assert_eq!(
        item(TransportSize::Word, 1, 0x83, 0, 3).region(),
        Err(ReturnCode::AddressOutOfRange)
    );
    assert_eq!(
        item(TransportSize::Real, 3, 0x84, 5, 80).region(),
        Ok(Region::Bytes {
            area: Area::DataBlock(5),
            start: 10,
            len: 12
        })
    );
    assert_eq!(
        item(TransportSize::Bit, 1, 0x81, 0, 83).region(),
        Ok(Region::Bit {
            area: Area::Inputs,
            byte: 10,
            bit: 3
        })
    );
}
