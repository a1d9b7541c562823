//! The frames of the published layouts: the request and response examples of the Modbus
//! Application Protocol Specification v1.1b3 (section 6, one per function code, and
//! section 7's exception), the CRC examples of the serial line guide v1.02, the MBAP
//! header of the TCP implementation guide; and what a server answers to each.

use std::time::Duration;

use modbus::pdu::{pack_bits, unpack_bits};
use modbus::rtu::{self, crc16, decode_frame, frame, RtuDeframer, RtuFrame};
use modbus::server::{answer, Outcome};
use modbus::tcp::{Adu, MbapDeframer, MbapError, MbapHeader, TcpServerConnection};
use modbus::{
    Answer, DataModel, ExceptionCode, Framing, ModelConfig, PduError, Request, Response, RtuSlave,
    Table, Units, Values, WriteEvent,
};
use serial_line::LineEndpoint as _;

/// (request PDU, the request, response PDU, the response) of section 6's examples.
fn spec_examples() -> Vec<(&'static [u8], Request, &'static [u8], Response)> {
    vec![
        // 6.1 Read Coils 20-38: 19 coils, CD 6B 05.
        (
            &[0x01, 0x00, 0x13, 0x00, 0x13],
            Request::read(Table::Coils, 19, 19),
            &[0x01, 0x03, 0xCD, 0x6B, 0x05],
            Response::ReadCoils(unpack_bits(&[0xCD, 0x6B, 0x05], 19)),
        ),
        // 6.2 Read Discrete Inputs 197-218: 22 inputs, AC DB 35.
        (
            &[0x02, 0x00, 0xC4, 0x00, 0x16],
            Request::read(Table::DiscreteInputs, 196, 22),
            &[0x02, 0x03, 0xAC, 0xDB, 0x35],
            Response::ReadDiscreteInputs(unpack_bits(&[0xAC, 0xDB, 0x35], 22)),
        ),
        // 6.3 Read Holding Registers 108-110: 555, 0, 100.
        (
            &[0x03, 0x00, 0x6B, 0x00, 0x03],
            Request::read(Table::HoldingRegisters, 107, 3),
            &[0x03, 0x06, 0x02, 0x2B, 0x00, 0x00, 0x00, 0x64],
            Response::ReadHoldingRegisters(vec![555, 0, 100]),
        ),
        // 6.4 Read Input Register 9: 10.
        (
            &[0x04, 0x00, 0x08, 0x00, 0x01],
            Request::read(Table::InputRegisters, 8, 1),
            &[0x04, 0x02, 0x00, 0x0A],
            Response::ReadInputRegisters(vec![10]),
        ),
        // 6.5 Write Single Coil 173 ON.
        (
            &[0x05, 0x00, 0xAC, 0xFF, 0x00],
            Request::WriteSingleCoil {
                address: 172,
                value: true,
            },
            &[0x05, 0x00, 0xAC, 0xFF, 0x00],
            Response::WriteSingleCoil {
                address: 172,
                value: true,
            },
        ),
        // 6.6 Write Single Register 2 = 3.
        (
            &[0x06, 0x00, 0x01, 0x00, 0x03],
            Request::WriteSingleRegister {
                address: 1,
                value: 3,
            },
            &[0x06, 0x00, 0x01, 0x00, 0x03],
            Response::WriteSingleRegister {
                address: 1,
                value: 3,
            },
        ),
        // 6.11 Write Multiple Coils 20-29: CD 01.
        (
            &[0x0F, 0x00, 0x13, 0x00, 0x0A, 0x02, 0xCD, 0x01],
            Request::WriteMultipleCoils {
                address: 19,
                values: vec![
                    true, false, true, true, false, false, true, true, true, false,
                ],
            },
            &[0x0F, 0x00, 0x13, 0x00, 0x0A],
            Response::WriteMultipleCoils {
                address: 19,
                count: 10,
            },
        ),
        // 6.12 Write Multiple Registers 2-3: 000A 0102.
        (
            &[0x10, 0x00, 0x01, 0x00, 0x02, 0x04, 0x00, 0x0A, 0x01, 0x02],
            Request::WriteMultipleRegisters {
                address: 1,
                values: vec![0x000A, 0x0102],
            },
            &[0x10, 0x00, 0x01, 0x00, 0x02],
            Response::WriteMultipleRegisters {
                address: 1,
                count: 2,
            },
        ),
        // 6.17 Read/Write Multiple Registers: read 4-9, write 15-17 with 00FF x3.
        (
            &[
                0x17, 0x00, 0x03, 0x00, 0x06, 0x00, 0x0E, 0x00, 0x03, 0x06, 0x00, 0xFF, 0x00, 0xFF,
                0x00, 0xFF,
            ],
            Request::ReadWriteMultipleRegisters {
                read_address: 3,
                read_count: 6,
                write_address: 14,
                values: vec![0xFF, 0xFF, 0xFF],
            },
            &[
                0x17, 0x0C, 0x00, 0xFE, 0x0A, 0xCD, 0x00, 0x01, 0x00, 0x03, 0x00, 0x0D, 0x00, 0xFF,
            ],
            Response::ReadWriteMultipleRegisters(vec![0xFE, 0x0ACD, 1, 3, 0x0D, 0xFF]),
        ),
    ]
}

#[test]
fn section_6_examples_encode_and_decode_both_ways() {
    for (request_pdu, request, response_pdu, response) in spec_examples() {
        assert_eq!(
            Request::decode(request_pdu),
            Ok(request.clone()),
            "{request}"
        );
        assert_eq!(request.to_pdu().unwrap(), request_pdu, "{request}");
        let answer = Answer::decode(&request, response_pdu).unwrap();
        assert_eq!(answer, Answer::Response(response.clone()), "{request}");
        let mut encoded = Vec::new();
        answer.encode(request.function(), &mut encoded);
        assert_eq!(encoded, response_pdu, "{request}");
    }
    // The spec's coil states read in its own words: coils 27-20 are CD = 1100 1101.
    assert_eq!(
        unpack_bits(&[0xCD], 8),
        [true, false, true, true, false, false, true, true]
    );
    assert_eq!(
        pack_bits(&unpack_bits(&[0xCD, 0x6B, 0x05], 19)),
        [0xCD, 0x6B, 0x05]
    );
}

#[test]
fn the_section_6_examples_answered_by_a_server_holding_the_specs_values() {
    let model = DataModel::default();
    model
        .write(
            1,
            Table::Coils,
            19,
            &Values::Bits(unpack_bits(&[0xCD, 0x6B, 0x05], 19)),
        )
        .unwrap();
    model
        .write(
            1,
            Table::DiscreteInputs,
            196,
            &Values::Bits(unpack_bits(&[0xAC, 0xDB, 0x35], 22)),
        )
        .unwrap();
    model
        .write(
            1,
            Table::HoldingRegisters,
            107,
            &Values::Registers(vec![555, 0, 100]),
        )
        .unwrap();
    model
        .write(1, Table::InputRegisters, 8, &Values::Registers(vec![10]))
        .unwrap();
    model
        .write(
            1,
            Table::HoldingRegisters,
            3,
            &Values::Registers(vec![0xFE, 0x0ACD, 1, 3, 0x0D, 0xFF]),
        )
        .unwrap();
    let mut events = model.subscribe();
    for (request_pdu, request, response_pdu, _) in spec_examples() {
        let Outcome::Answer(got) = answer(&model, Framing::Tcp, 1, request_pdu) else {
            panic!("no answer to {request}");
        };
        if request.function().0 == 15 {
            // The coils written are the ones read first: the answer is the echo.
            assert_eq!(got, response_pdu);
        } else {
            assert_eq!(got, response_pdu, "{request}");
        }
    }
    let written: Vec<WriteEvent> = std::iter::from_fn(|| events.try_recv().ok()).collect();
    assert_eq!(
        written
            .iter()
            .map(|event| (event.table, event.address, event.count()))
            .collect::<Vec<_>>(),
        [
            (Table::Coils, 172, 1),
            (Table::HoldingRegisters, 1, 1),
            (Table::Coils, 19, 10),
            (Table::HoldingRegisters, 1, 2),
            (Table::HoldingRegisters, 14, 3),
        ]
    );
    assert_eq!(written[3].values, Values::Registers(vec![0x000A, 0x0102]));
}

#[test]
fn exceptions_in_the_specs_order_function_value_address() {
    let model = DataModel::default();
    let exception = |pdu: &[u8]| match answer(&model, Framing::Tcp, 1, pdu) {
        Outcome::Answer(answer) => answer,
        other => panic!("{other:?}"),
    };
    // Section 7's example: FC 01 answered 81 02 (coils beyond the table).
    assert_eq!(exception(&[0x01, 0x27, 0x10, 0x00, 0x01]), [0x81, 0x02]);
    // 1: an unknown function, and the serial-line-only ones this server does not do.
    assert_eq!(exception(&[0x2A]), [0xAA, 0x01]);
    assert_eq!(exception(&[0x07]), [0x87, 0x01]);
    assert_eq!(exception(&[0x16, 0, 1, 0, 2, 0, 3]), [0x96, 0x01]);
    // 3: quantities 0 and beyond the limits, a byte count that does not fit, a coil value.
    assert_eq!(exception(&[0x03, 0, 0, 0, 0]), [0x83, 0x03]);
    assert_eq!(exception(&[0x03, 0, 0, 0, 126]), [0x83, 0x03]);
    assert_eq!(exception(&[0x01, 0, 0, 0x07, 0xD1]), [0x81, 0x03]);
    assert_eq!(exception(&[0x0F, 0, 0, 0, 100, 1, 0xFF]), [0x8F, 0x03]);
    assert_eq!(exception(&[0x10, 0, 0, 0x80, 0x00, 0]), [0x90, 0x03]);
    assert_eq!(exception(&[0x05, 0, 1, 0x12, 0x34]), [0x85, 0x03]);
    assert_eq!(
        exception(&[0x17, 0, 0, 0, 1, 0, 0, 0, 1, 3, 0, 0]),
        [0x97, 0x03]
    );
    // 3 before 2: a bad quantity far outside the table is a bad value first.
    assert_eq!(exception(&[0x03, 0xFF, 0xFF, 0, 200]), [0x83, 0x03]);
    // 2: the last entry is 9999.
    assert_eq!(exception(&[0x03, 0x27, 0x10, 0, 1]), [0x83, 0x02]);
    assert_eq!(exception(&[0x03, 0x27, 0x0F, 0, 1]), [0x03, 0x02, 0, 0]);
    assert_eq!(exception(&[0x03, 0x27, 0x0F, 0, 2]), [0x83, 0x02]);
    assert_eq!(exception(&[0x06, 0x27, 0x10, 0, 1]), [0x86, 0x02]);
    // FC 23 with its read range outside writes nothing.
    assert_eq!(
        exception(&[0x17, 0x27, 0x10, 0, 1, 0, 5, 0, 1, 2, 0x12, 0x34]),
        [0x97, 0x02]
    );
    assert_eq!(
        model.read(1, Table::HoldingRegisters, 5, 1),
        Ok(Values::Registers(vec![0]))
    );
    // Not requests: nothing is answered.
    assert_eq!(answer(&model, Framing::Tcp, 1, &[]), Outcome::Ignored);
    assert_eq!(
        answer(&model, Framing::Tcp, 1, &[0x83, 0x02]),
        Outcome::Ignored
    );
    assert_eq!(
        PduError::UnsupportedFunction(0x2A).exception(),
        Some(ExceptionCode::ILLEGAL_FUNCTION)
    );
    assert_eq!(
        ExceptionCode::ILLEGAL_DATA_ADDRESS.to_string(),
        "illegal data address (code 2)"
    );
}

#[test]
fn unit_ids_on_tcp_and_on_a_serial_line() {
    let model = DataModel::new(ModelConfig::new(Units::Single(7)));
    let read = Request::read(Table::HoldingRegisters, 0, 1)
        .to_pdu()
        .unwrap();
    // TCP: another unit id is answered 0x0B, as a gateway would.
    assert_eq!(
        answer(&model, Framing::Tcp, 8, &read),
        Outcome::Answer(vec![0x83, 0x0B])
    );
    assert!(
        matches!(answer(&model, Framing::Tcp, 7, &read), Outcome::Answer(pdu) if pdu[0] == 0x03)
    );
    // RTU: another slave's request is not answered, broadcast writes are carried out.
    assert_eq!(answer(&model, Framing::Rtu, 8, &read), Outcome::NotOurs);
    let write = Request::WriteSingleRegister {
        address: 4,
        value: 99,
    }
    .to_pdu()
    .unwrap();
    let mut events = model.subscribe();
    assert_eq!(answer(&model, Framing::Rtu, 0, &write), Outcome::Broadcast);
    assert_eq!(
        model.read(7, Table::HoldingRegisters, 4, 1),
        Ok(Values::Registers(vec![99]))
    );
    assert_eq!(events.try_recv().unwrap().unit, 0);
    // A broadcast read is nothing.
    assert_eq!(answer(&model, Framing::Rtu, 0, &read), Outcome::Broadcast);
    assert!(events.try_recv().is_err());

    // Per unit: separate tables.
    let per_unit = DataModel::new(ModelConfig::new(Units::PerUnit(vec![1, 2])));
    per_unit
        .execute(
            1,
            &Request::WriteSingleCoil {
                address: 0,
                value: true,
            },
        )
        .unwrap();
    assert_eq!(
        per_unit.read(1, Table::Coils, 0, 1),
        Ok(Values::Bits(vec![true]))
    );
    assert_eq!(
        per_unit.read(2, Table::Coils, 0, 1),
        Ok(Values::Bits(vec![false]))
    );
    assert_eq!(
        per_unit.execute(3, &Request::read(Table::Coils, 0, 1)),
        Err(ExceptionCode::GATEWAY_TARGET_FAILED)
    );
    // A broadcast reaches every unit.
    per_unit.execute_broadcast(&Request::WriteSingleCoil {
        address: 5,
        value: true,
    });
    for unit in [1, 2] {
        assert_eq!(
            per_unit.read(unit, Table::Coils, 5, 1),
            Ok(Values::Bits(vec![true]))
        );
    }
}

#[test]
fn the_tables_are_ten_thousand_zeroed_entries_each() {
    let model = DataModel::default();
    assert_eq!(model.size(), 10_000);
    for table in Table::ALL {
        let values = model.read(1, table, 0, 10_000).unwrap();
        assert_eq!(values.len(), 10_000);
        match values {
            Values::Bits(bits) => assert!(bits.iter().all(|bit| !bit)),
            Values::Registers(registers) => assert!(registers.iter().all(|r| *r == 0)),
        }
        assert!(model.read(1, table, 9_999, 2).is_err());
    }
    // The server's side may write the read-only tables.
    model
        .write(1, Table::InputRegisters, 9_999, &Values::Registers(vec![7]))
        .unwrap();
    assert!(model
        .write(1, Table::InputRegisters, 0, &Values::Bits(vec![true]))
        .is_err());
    assert_eq!("discrete".parse::<Table>(), Ok(Table::DiscreteInputs));
    assert_eq!(
        "holding-registers".parse::<Table>(),
        Ok(Table::HoldingRegisters)
    );
    assert!("registers".parse::<Table>().is_err());
}

/// The serial line guide's CRC example (appendix B: 02 07 -> 0x1241, sent 41 12) and the
/// read of ten registers every Modbus tool shows, 01 03 00 00 00 0A C5 CD.
#[test]
fn rtu_crc_examples_of_the_serial_line_guide() {
    assert_eq!(crc16(&[0x02, 0x07]), 0x1241);
    assert_eq!(frame(0x02, &[0x07]), [0x02, 0x07, 0x41, 0x12]);
    const READ_TEN: [u8; 8] = [0x01, 0x03, 0x00, 0x00, 0x00, 0x0A, 0xC5, 0xCD];
    let pdu = Request::read(Table::HoldingRegisters, 0, 10)
        .to_pdu()
        .unwrap();
    assert_eq!(frame(1, &pdu), READ_TEN);
    assert_eq!(decode_frame(&READ_TEN), Some((1, &pdu[..])));
    let mut broken = READ_TEN;
    broken[7] ^= 0x01;
    assert_eq!(decode_frame(&broken), None);
    assert_eq!(decode_frame(&READ_TEN[..3]), None);
}

/// The TCP implementation guide's header: transaction, protocol 0, length (unit id and
/// PDU), unit id; the same read as above with unit 0xFF.
#[test]
fn mbap_header_layout() {
    const ADU: [u8; 12] = [
        0x00, 0x2A, 0x00, 0x00, 0x00, 0x06, 0xFF, 0x03, 0x00, 0x00, 0x00, 0x0A,
    ];
    let header = MbapHeader::decode(&ADU).unwrap();
    assert_eq!(
        header,
        MbapHeader {
            transaction: 42,
            protocol: 0,
            length: 6,
            unit: 0xFF
        }
    );
    let adu = Adu {
        transaction: 42,
        protocol: 0,
        unit: 0xFF,
        pdu: Request::read(Table::HoldingRegisters, 0, 10)
            .to_pdu()
            .unwrap(),
    };
    assert_eq!(adu.to_bytes(), ADU);
    let mut deframer = MbapDeframer::new();
    deframer.push(&ADU[..5]);
    assert_eq!(deframer.next_frame(), Ok(None));
    deframer.push(&ADU[5..]);
    deframer.push(&ADU);
    assert_eq!(deframer.next_frame(), Ok(Some(adu.clone())));
    assert_eq!(deframer.next_frame(), Ok(Some(adu)));
    assert_eq!(deframer.next_frame(), Ok(None));
    // A length no ADU has loses the stream.
    deframer.push(&[0, 1, 0, 0, 0x01, 0x00, 1]);
    assert_eq!(deframer.next_frame(), Err(MbapError::Length(256)));
}

#[test]
fn a_tcp_connection_answers_each_request_and_closes_on_a_broken_length() {
    let model = DataModel::default();
    let mut connection = TcpServerConnection::new(model);
    let request = |transaction: u16, protocol: u16, pdu: Vec<u8>| {
        Adu {
            transaction,
            protocol,
            unit: 1,
            pdu,
        }
        .to_bytes()
    };
    let read = Request::read(Table::Coils, 0, 3).to_pdu().unwrap();
    let mut input = request(1, 0, read.clone());
    input.extend(request(2, 0, vec![0x2A]));
    // Another protocol's ADU is dropped without an answer.
    input.extend(request(3, 7, read.clone()));
    for octet in &input {
        connection.handle_input(std::slice::from_ref(octet));
    }
    let out = connection.poll_transmit().unwrap();
    let mut deframer = MbapDeframer::new();
    deframer.push(&out);
    let first = deframer.next_frame().unwrap().unwrap();
    assert_eq!((first.transaction, first.pdu), (1, vec![0x01, 0x01, 0x00]));
    let second = deframer.next_frame().unwrap().unwrap();
    assert_eq!((second.transaction, second.pdu), (2, vec![0xAA, 0x01]));
    assert_eq!(deframer.next_frame(), Ok(None));
    assert_eq!(connection.stats().foreign, 1);
    assert!(connection.error().is_none());
    connection.handle_input(&[0, 4, 0, 0, 0, 0, 1]);
    assert_eq!(connection.error(), Some(&MbapError::Length(0)));
    assert_eq!(connection.poll_transmit(), None);
}

#[test]
fn rtu_deframer_cuts_by_length_and_resynchronises_at_pauses() {
    let read = frame(
        1,
        &Request::read(Table::HoldingRegisters, 0, 10)
            .to_pdu()
            .unwrap(),
    );
    let write = frame(
        2,
        &Request::WriteMultipleRegisters {
            address: 1,
            values: vec![1, 2, 3],
        }
        .to_pdu()
        .unwrap(),
    );
    let mut deframer = RtuDeframer::new();
    // Two requests back to back, octet by octet: each is cut by its length.
    let mut frames = Vec::new();
    for octet in read.iter().chain(&write) {
        deframer.push(std::slice::from_ref(octet));
        frames.extend(std::iter::from_fn(|| deframer.next_frame()));
    }
    assert_eq!(frames.iter().map(|f| f.unit).collect::<Vec<_>>(), [1, 2]);
    assert_eq!(deframer.handle_pause(), None);

    // Another slave's response (not a request by length) and then, before the pause,
    // a request: the request is found at the end of the run.
    let response = frame(3, &[0x03, 0x04, 0x00, 0x01, 0x00, 0x02]);
    deframer.push(&response);
    assert_eq!(deframer.next_frame(), None);
    deframer.push(&read);
    assert_eq!(deframer.next_frame(), None);
    assert_eq!(
        deframer.handle_pause(),
        Some(RtuFrame {
            unit: 1,
            pdu: read[1..6].to_vec()
        })
    );
    // Alone before a pause, the response is a frame (of unit 3) too.
    deframer.push(&response);
    assert_eq!(deframer.handle_pause().map(|f| f.unit), Some(3));
    // Noise is discarded at the pause, and the next request is read again.
    deframer.push(&[0x01, 0x03, 0xAA, 0xBB]);
    assert_eq!(deframer.next_frame(), None);
    deframer.push(&[0xCC, 0xDD, 0xEE, 0xFF]);
    assert_eq!(deframer.next_frame(), None);
    assert_eq!(deframer.handle_pause(), None);
    assert_eq!(deframer.stats().discarded, 1);
    deframer.push(&read);
    assert_eq!(deframer.next_frame().map(|f| f.unit), Some(1));
    // More than a frame's 256 octets without a pause: bounded, judged at the pause.
    for _ in 0..100 {
        deframer.push(&[0x55; 10]);
        assert_eq!(deframer.next_frame(), None);
    }
    assert!(deframer.buffered() <= 2 * rtu::MAX_ADU);
    assert_eq!(deframer.handle_pause(), None);
    deframer.push(&read);
    assert_eq!(deframer.next_frame().map(|f| f.unit), Some(1));
    // A request at the end of a long run of noise is still found at the pause.
    deframer.push(&[0x55; 1000]);
    deframer.push(&read);
    assert_eq!(deframer.next_frame(), None);
    assert_eq!(deframer.handle_pause().map(|f| f.unit), Some(1));
}

/// The slave on a virtual clock: the answer waits for the frame gap after the request
/// (3.5 characters: 2.005 ms at 19200 Bd 8E1), an unknown function is answered at the
/// pause, another unit and a bad CRC are not answered, its own echo is ignored.
#[test]
fn rtu_slave_answers_after_the_frame_gap() {
    let model = DataModel::new(ModelConfig::new(Units::Single(1)));
    let line = rtu::DEFAULT_LINE;
    assert_eq!(rtu::frame_gap(&line), Duration::from_nanos(2_005_208));
    assert_eq!(
        rtu::frame_gap(&serial_line::LineSettings::new(115_200)),
        Duration::from_micros(1750)
    );
    let mut slave = RtuSlave::new(model, line);
    let t0 = tokio::time::Instant::now().into_std();
    slave.handle_bytes(t0, &frame(1, &[0x06, 0x00, 0x05, 0x12, 0x34]));
    assert_eq!(slave.poll_transmit(t0), None);
    let due = slave.next_deadline().unwrap();
    assert_eq!(due - t0, rtu::frame_gap(&line));
    let answer = slave.poll_transmit(due).unwrap();
    assert_eq!(answer, frame(1, &[0x06, 0x00, 0x05, 0x12, 0x34]));
    assert_eq!(slave.next_deadline(), None);
    // The answer read back (an RS-485 echo) is not a request.
    let t1 = due + Duration::from_millis(3);
    slave.handle_bytes(t1, &answer);
    assert_eq!(slave.next_deadline(), None);
    assert_eq!(slave.stats().echoes, 1);
    // An unknown function: its length is not known, the pause ends it.
    let t2 = t1 + Duration::from_millis(10);
    slave.handle_bytes(t2, &frame(1, &[0x41, 0x01, 0x02]));
    assert_eq!(slave.next_deadline(), None);
    slave.handle_line_pause(t2 + Duration::from_millis(50));
    let due = slave.next_deadline().unwrap();
    assert_eq!(slave.poll_transmit(due), Some(frame(1, &[0xC1, 0x01])));
    // Another unit, a bad CRC: silence.
    let t3 = due + Duration::from_millis(10);
    slave.handle_bytes(t3, &frame(2, &[0x03, 0, 0, 0, 1]));
    let mut bad = frame(1, &[0x03, 0, 0, 0, 1]);
    bad[7] ^= 0xFF;
    slave.handle_line_pause(t3 + Duration::from_millis(50));
    slave.handle_bytes(t3 + Duration::from_millis(60), &bad);
    slave.handle_line_pause(t3 + Duration::from_millis(120));
    assert_eq!(slave.next_deadline(), None);
    let stats = slave.stats();
    assert_eq!(stats.other_units, 1);
    assert_eq!(stats.discarded, 1);
    assert_eq!(stats.answered, 2);
}
