//! The sans-IO client against the sans-IO server, no socket: splitting by PDU size,
//! parallel jobs, segmentation into small TPDUs, item errors, and how each end treats a
//! misbehaving peer.

use s7::cotp::{ConnectionParams, Tpdu, TpduSize};
use s7::pdu::{ErrorCode, Pdu, Request, Response};
use s7::split::WriteItem;
use s7::tpkt::{self, Deframer};
use s7::{
    Area, ClientConfig, ClientConnection, ClientEvent, ConnectionError, ItemError, Memory,
    ReadResult, Region, ServerConfig, ServerConnection, ServerEvent, Tsap, WriteEvent, WriteResult,
};

pub(crate) struct Pair {
    pub(crate) client: ClientConnection,
    pub(crate) server: ServerConnection,
    pub(crate) memory: Memory,
    /// Every S7 PDU the client sent, decoded, with its encoded length.
    pub(crate) client_pdus: Vec<(usize, Pdu)>,
    /// Every S7 PDU the server sent.
    pub(crate) server_pdus: Vec<(usize, Pdu)>,
    /// Every TPKT frame's length, client side and server side.
    pub(crate) client_frame_lens: Vec<usize>,
    pub(crate) server_frame_lens: Vec<usize>,
    pub(crate) client_events: Vec<ClientEvent>,
    pub(crate) server_events: Vec<ServerEvent>,
    /// The most jobs the client sent before the server answered any.
    pub(crate) max_burst: usize,
    /// A TPDU size to put into the client's connection request on its way.
    pub(crate) cr_tpdu_size: Option<TpduSize>,
    client_stream: Deframer,
    server_stream: Deframer,
    client_assembly: Vec<u8>,
    server_assembly: Vec<u8>,
}

/// Decodes the S7 PDUs in frames as a watcher on the wire would.
fn watch(
    stream: &mut Deframer,
    assembly: &mut Vec<u8>,
    frame: &[u8],
    into: &mut Vec<(usize, Pdu)>,
) {
    stream.push(frame);
    while let Some(payload) = stream.next_frame().unwrap() {
        if let Tpdu::Data { eot, payload, .. } = Tpdu::decode(&payload).unwrap() {
            assembly.extend_from_slice(&payload);
            if eot {
                let bytes = std::mem::take(assembly);
                into.push((bytes.len(), Pdu::decode(&bytes).unwrap()));
            }
        }
    }
}

impl Pair {
    pub(crate) fn new(client: ClientConfig, server: ServerConfig, memory: Memory) -> Pair {
        Pair {
            client: ClientConnection::new(client),
            server: ServerConnection::new(server),
            memory,
            client_pdus: Vec::new(),
            server_pdus: Vec::new(),
            client_frame_lens: Vec::new(),
            server_frame_lens: Vec::new(),
            client_events: Vec::new(),
            server_events: Vec::new(),
            max_burst: 0,
            cr_tpdu_size: None,
            client_stream: Deframer::new(),
            server_stream: Deframer::new(),
            client_assembly: Vec::new(),
            server_assembly: Vec::new(),
        }
    }

    /// Moves frames both ways until neither end has anything to send.
    pub(crate) fn run(&mut self) {
        let mut frame = Vec::new();
        loop {
            let mut moved = false;
            let jobs_before = self.client_pdus.len();
            while self.client.poll_transmit(&mut frame) {
                if let Some(size) = self.cr_tpdu_size.take() {
                    frame = rewrite_cr(&frame, size);
                }
                self.client_frame_lens.push(frame.len());
                watch(
                    &mut self.client_stream,
                    &mut self.client_assembly,
                    &frame,
                    &mut self.client_pdus,
                );
                self.server.handle_input(&frame, &mut self.memory);
                moved = true;
            }
            self.max_burst = self.max_burst.max(self.client_pdus.len() - jobs_before);
            while self.server.poll_transmit(&mut frame) {
                self.server_frame_lens.push(frame.len());
                watch(
                    &mut self.server_stream,
                    &mut self.server_assembly,
                    &frame,
                    &mut self.server_pdus,
                );
                self.client.handle_input(&frame);
                moved = true;
            }
            while let Some(event) = self.client.poll_event() {
                self.client_events.push(event);
            }
            while let Some(event) = self.server.poll_event() {
                self.server_events.push(event);
            }
            if !moved {
                return;
            }
        }
    }

    pub(crate) fn connect(&mut self) -> (u16, u16) {
        self.run();
        match self.client_events.first() {
            Some(ClientEvent::Connected { pdu_size, max_jobs }) => (*pdu_size, *max_jobs),
            other => panic!("not connected: {other:?}"),
        }
    }

    pub(crate) fn read(&mut self, regions: Vec<Region>) -> Vec<ReadResult> {
        let id = self.client.read(regions).unwrap();
        self.run();
        self.client_events
            .iter()
            .find_map(|event| match event {
                ClientEvent::ReadDone { id: done, results } if *done == id => Some(results.clone()),
                _ => None,
            })
            .expect("the read finished")
    }

    pub(crate) fn write(&mut self, items: Vec<WriteItem>) -> Vec<WriteResult> {
        let id = self.client.write(items).unwrap();
        self.run();
        self.client_events
            .iter()
            .find_map(|event| match event {
                ClientEvent::WriteDone { id: done, results } if *done == id => {
                    Some(results.clone())
                }
                _ => None,
            })
            .expect("the write finished")
    }

    pub(crate) fn read_jobs(&self) -> usize {
        self.client_pdus
            .iter()
            .filter(|(_, pdu)| {
                matches!(
                    pdu,
                    Pdu::Job {
                        request: Request::ReadVar(_),
                        ..
                    }
                )
            })
            .count()
    }
}

fn rewrite_cr(frame: &[u8], size: TpduSize) -> Vec<u8> {
    let Tpdu::ConnectionRequest(params) = Tpdu::decode(&frame[4..]).unwrap() else {
        return frame.to_vec();
    };
    let mut payload = Vec::new();
    Tpdu::ConnectionRequest(ConnectionParams {
        tpdu_size: Some(size),
        ..params
    })
    .encode(&mut payload)
    .unwrap();
    let mut out = Vec::new();
    tpkt::encode(&payload, &mut out).unwrap();
    out
}

pub(crate) fn memory_with_db1(size: usize) -> Memory {
    let mut memory = Memory::default();
    memory.add_data_block(1, size).unwrap();
    memory
}

fn db1(start: u32, len: u32) -> Region {
    Region::Bytes {
        area: Area::DataBlock(1),
        start,
        len,
    }
}

#[test]
fn the_server_grants_the_smaller_pdu_size_and_job_count() {
    let mut client = ClientConfig::default();
    client.pdu_size = 960;
    client.max_jobs = 8;
    let mut pair = Pair::new(client, ServerConfig::default(), Memory::default());
    assert_eq!(pair.connect(), (240, 3));
    assert_eq!(pair.server.pdu_size(), Some(240));
    assert!(matches!(
        pair.server_events.as_slice(),
        [
            ServerEvent::Connected { .. },
            ServerEvent::Negotiated {
                pdu_size: 240,
                max_jobs: 3
            }
        ]
    ));

    let mut server = ServerConfig::default();
    server.max_pdu_size = 960;
    let mut pair = Pair::new(ClientConfig::default(), server, Memory::default());
    assert_eq!(pair.connect(), (480, 3));
}

#[test]
fn thirty_words_split_into_jobs_that_fit_240_come_back_in_order() {
    let mut memory = memory_with_db1(100);
    for index in 0..30u16 {
        let at = usize::from(index) * 2;
        memory.area_mut(Area::DataBlock(1)).unwrap()[at..at + 2]
            .copy_from_slice(&(1000 + index).to_be_bytes());
    }
    let mut pair = Pair::new(ClientConfig::default(), ServerConfig::default(), memory);
    pair.connect();
    let regions: Vec<Region> = (0..30).map(|index| db1(index * 2, 2)).collect();
    let results = pair.read(regions);
    let values: Vec<u16> = results
        .into_iter()
        .map(|result| u16::from_be_bytes(result.unwrap().try_into().unwrap()))
        .collect();
    assert_eq!(values, (1000..1030).collect::<Vec<u16>>());
    // (240 - 12) / 12 = 19 items per job: two jobs.
    assert_eq!(pair.read_jobs(), 2);
    for (len, _) in pair.client_pdus.iter().chain(&pair.server_pdus) {
        assert!(*len <= 240, "a PDU of {len} bytes");
    }
    // Both went out before the first answer: parallel jobs.
    assert_eq!(pair.max_burst, 2);
}

#[test]
fn one_job_at_a_time_when_one_is_granted() {
    let mut server = ServerConfig::default();
    server.max_jobs = 1;
    let mut pair = Pair::new(ClientConfig::default(), server, memory_with_db1(1000));
    assert_eq!(pair.connect(), (240, 1));
    let results = pair.read(vec![db1(0, 1000)]);
    assert_eq!(results, vec![Ok(vec![0; 1000])]);
    assert_eq!(pair.max_burst, 1);
}

#[test]
fn a_thousand_bytes_are_read_and_written_in_pieces() {
    let mut pair = Pair::new(
        ClientConfig::default(),
        ServerConfig::default(),
        memory_with_db1(1200),
    );
    pair.connect();
    let data: Vec<u8> = (0..1000u32).map(|i| (i * 7 % 251) as u8).collect();
    let written = pair.write(vec![WriteItem {
        region: db1(100, 1000),
        data: data.clone(),
    }]);
    assert_eq!(written, vec![Ok(())]);
    assert_eq!(
        &pair.memory.area(Area::DataBlock(1)).unwrap()[100..1100],
        &data[..]
    );
    let read = pair.read(vec![db1(100, 1000)]);
    assert_eq!(read, vec![Ok(data.clone())]);
    // 222 bytes per read job at 240 (240 - 18), 212 per write job (240 - 28).
    assert_eq!(pair.read_jobs(), 5);
    for (len, _) in pair.client_pdus.iter().chain(&pair.server_pdus) {
        assert!(*len <= 240, "a PDU of {len} bytes");
    }
    // The server reported each piece of the write, together the whole run.
    let writes: Vec<&WriteEvent> = pair
        .server_events
        .iter()
        .filter_map(|event| match event {
            ServerEvent::Write(write) => Some(write),
            _ => None,
        })
        .collect();
    assert_eq!(writes.len(), 5);
    assert_eq!(writes[0].start, 100);
    assert_eq!(writes[0].size(), 212);
    let joined: Vec<u8> = writes.iter().flat_map(|write| write.data.clone()).collect();
    assert_eq!(joined, data);
}

#[test]
fn small_tpdus_segment_pdus_both_ways() {
    let mut pair = Pair::new(
        ClientConfig::default(),
        ServerConfig::default(),
        memory_with_db1(400),
    );
    pair.cr_tpdu_size = Some(TpduSize::DEFAULT);
    pair.connect();
    let data: Vec<u8> = (0..200u8).collect();
    assert_eq!(
        pair.write(vec![WriteItem {
            region: db1(0, 200),
            data: data.clone()
        }]),
        vec![Ok(())]
    );
    assert_eq!(pair.read(vec![db1(0, 200)]), vec![Ok(data)]);
    // 128-byte TPDUs: every frame at most 128 + the TPKT header, and the 200-byte PDUs
    // needed two each.
    for len in pair.client_frame_lens.iter().chain(&pair.server_frame_lens) {
        assert!(*len <= 128 + 4, "a frame of {len} bytes");
    }
    assert!(
        pair.client_frame_lens
            .iter()
            .filter(|len| **len == 132)
            .count()
            >= 1
    );
    assert!(
        pair.server_frame_lens
            .iter()
            .filter(|len| **len == 132)
            .count()
            >= 1
    );
}

#[test]
fn items_the_server_cannot_serve_fail_alone() {
    let mut pair = Pair::new(
        ClientConfig::default(),
        ServerConfig::default(),
        memory_with_db1(10),
    );
    pair.connect();
    let results = pair.read(vec![
        db1(0, 2),
        Region::Bytes {
            area: Area::DataBlock(99),
            start: 0,
            len: 2,
        },
        db1(9, 2),
        Region::Bit {
            area: Area::Markers,
            byte: 1023,
            bit: 7,
        },
        Region::Bit {
            area: Area::Markers,
            byte: 1024,
            bit: 0,
        },
    ]);
    assert_eq!(
        results,
        vec![
            Ok(vec![0, 0]),
            Err(ItemError::Refused(s7::pdu::ReturnCode::ObjectDoesNotExist)),
            Err(ItemError::Refused(s7::pdu::ReturnCode::AddressOutOfRange)),
            Ok(vec![0]),
            Err(ItemError::Refused(s7::pdu::ReturnCode::AddressOutOfRange)),
        ]
    );
    assert!(pair.client.is_connected());
}

#[test]
fn a_large_item_failing_in_one_piece_fails_whole() {
    let mut pair = Pair::new(
        ClientConfig::default(),
        ServerConfig::default(),
        memory_with_db1(300),
    );
    pair.connect();
    // Bytes 0..222 exist, 222..400 run past the block's 300 bytes.
    let results = pair.read(vec![db1(0, 400), db1(0, 1)]);
    assert_eq!(
        results,
        vec![
            Err(ItemError::Refused(s7::pdu::ReturnCode::AddressOutOfRange)),
            Ok(vec![0])
        ]
    );
}

#[test]
fn reads_asked_before_the_connection_is_up_go_out_after_setup() {
    let mut pair = Pair::new(
        ClientConfig::default(),
        ServerConfig::default(),
        memory_with_db1(4),
    );
    let id = pair.client.read(vec![db1(0, 4)]).unwrap();
    let empty = pair.client.read(vec![]).unwrap();
    pair.run();
    assert!(matches!(
        pair.client_events.first(),
        Some(ClientEvent::Connected { .. })
    ));
    // The empty read needs no job: it finishes as soon as it is planned.
    assert!(pair.client_events.contains(&ClientEvent::ReadDone {
        id: empty,
        results: vec![]
    }));
    assert!(pair.client_events.contains(&ClientEvent::ReadDone {
        id,
        results: vec![Ok(vec![0; 4])]
    }));
}

#[test]
fn the_server_accepts_any_connection_type_and_tsap_length() {
    for called in [
        Tsap::new(0x0101),
        Tsap::new(0x0201),
        Tsap::new(0x0301),
        Tsap::new(0x1002),
        Tsap::from_bytes(b"SIMATIC-ROOT"),
    ] {
        let tsaps = s7::Tsaps {
            local: Tsap::new(0x4D57),
            remote: called.clone(),
        };
        let mut pair = Pair::new(
            ClientConfig::new(tsaps),
            ServerConfig::default(),
            Memory::default(),
        );
        pair.connect();
        assert_eq!(
            pair.server_events.first(),
            Some(&ServerEvent::Connected {
                calling_tsap: Some(Tsap::new(0x4D57)),
                called_tsap: Some(called.clone()),
            })
        );
    }
}

/// A raw end that speaks frames by hand, for what a well-behaved client never sends.
fn frame(tpdu: &Tpdu) -> Vec<u8> {
    let mut payload = Vec::new();
    tpdu.encode(&mut payload).unwrap();
    let mut out = Vec::new();
    tpkt::encode(&payload, &mut out).unwrap();
    out
}

fn data(pdu: &Pdu) -> Vec<u8> {
    frame(&Tpdu::Data {
        eot: true,
        number: 0,
        payload: pdu.to_bytes().unwrap(),
    })
}

fn answers(server: &mut ServerConnection) -> Vec<Pdu> {
    let mut out = Vec::new();
    let mut pdus = Vec::new();
    let mut stream = Deframer::new();
    let mut assembly = Vec::new();
    let mut decoded = Vec::new();
    while server.poll_transmit(&mut out) {
        watch(&mut stream, &mut assembly, &out, &mut decoded);
    }
    pdus.extend(decoded.into_iter().map(|(_, pdu)| pdu));
    pdus
}

fn connection_request() -> Vec<u8> {
    frame(&Tpdu::ConnectionRequest(ConnectionParams {
        dst_ref: 0,
        src_ref: 7,
        class: 0,
        tpdu_size: None,
        calling_tsap: None,
        called_tsap: None,
    }))
}

#[test]
fn the_server_answers_bad_jobs_and_closes_after_too_many() {
    let mut memory = Memory::default();
    let mut server = ServerConnection::new(ServerConfig::default());
    server.handle_input(&connection_request(), &mut memory);
    let mut out = Vec::new();
    assert!(server.poll_transmit(&mut out));
    // A read before setup communication.
    let read = Pdu::Job {
        pdu_ref: 5,
        request: Request::ReadVar(vec![]),
    };
    server.handle_input(&data(&read), &mut memory);
    assert_eq!(
        answers(&mut server),
        vec![Pdu::Ack {
            pdu_ref: 5,
            error: ErrorCode::INVALID_REQUEST
        }]
    );
    assert!(!server.is_closed());
    // Setup, then a function the server does not offer (0x1A, request download): error 0x8104.
    server.handle_input(
        &data(&Pdu::Job {
            pdu_ref: 6,
            request: Request::SetupCommunication(s7::pdu::SetupCommunication {
                max_amq_calling: 1,
                max_amq_called: 1,
                pdu_size: 480,
            }),
        }),
        &mut memory,
    );
    server.handle_input(
        &data(&Pdu::Job {
            pdu_ref: 8,
            request: Request::Other {
                function: 0x1A,
                parameter: vec![0; 4],
                data: vec![],
            },
        }),
        &mut memory,
    );
    let pdus = answers(&mut server);
    assert_eq!(pdus.len(), 2);
    assert_eq!(
        pdus[1],
        Pdu::AckData {
            pdu_ref: 8,
            error: ErrorCode::FUNCTION_NOT_IMPLEMENTED,
            response: Response::None
        }
    );
    // Undecodable jobs: answered while the reference can be read, then the connection
    // closes.
    let garbage = frame(&Tpdu::Data {
        eot: true,
        number: 0,
        payload: vec![0x32, 0x01, 0, 0, 0, 9, 0, 0x40, 0, 0],
    });
    for _ in 0..s7::server::MAX_BAD_PDUS - 1 {
        server.handle_input(&garbage, &mut memory);
    }
    assert!(!server.is_closed());
    assert!(answers(&mut server)
        .iter()
        .all(|pdu| matches!(pdu, Pdu::Ack { pdu_ref: 9, .. })));
    server.handle_input(&garbage, &mut memory);
    server.handle_input(&garbage, &mut memory);
    assert!(server.is_closed());
    let closed = std::iter::from_fn(|| server.poll_event()).last();
    assert_eq!(
        closed,
        Some(ServerEvent::Closed(ConnectionError::TooManyBadPdus(
            s7::server::MAX_BAD_PDUS + 1
        )))
    );
}

#[test]
fn the_server_refuses_jobs_larger_than_the_pdu_size() {
    let mut memory = memory_with_db1(2000);
    let mut server = ServerConnection::new(ServerConfig::default());
    server.handle_input(&connection_request(), &mut memory);
    server.handle_input(
        &data(&Pdu::Job {
            pdu_ref: 1,
            request: Request::SetupCommunication(s7::pdu::SetupCommunication {
                max_amq_calling: 1,
                max_amq_called: 1,
                pdu_size: 240,
            }),
        }),
        &mut memory,
    );
    answers(&mut server);
    // 30 items: a 372-byte job. And one item whose answer would be 1018 bytes.
    let items = vec![s7::pdu::ItemSpec::for_region(&db1(0, 2)).unwrap(); 30];
    let big = vec![s7::pdu::ItemSpec::for_region(&db1(0, 1000)).unwrap()];
    for (pdu_ref, items) in [(2, items), (3, big)] {
        server.handle_input(
            &data(&Pdu::Job {
                pdu_ref,
                request: Request::ReadVar(items),
            }),
            &mut memory,
        );
        assert_eq!(
            answers(&mut server),
            vec![Pdu::AckData {
                pdu_ref,
                error: ErrorCode::PDU_SIZE,
                response: Response::None
            }]
        );
    }
    assert!(!server.is_closed());
}

#[test]
fn frames_that_break_the_stream_close_the_connection() {
    let mut memory = Memory::default();
    let mut server = ServerConnection::new(ServerConfig::default());
    server.handle_input(b"GET / HTTP/1.1\r\n", &mut memory);
    assert!(server.is_closed());
    assert_eq!(
        server.poll_event(),
        Some(ServerEvent::Closed(ConnectionError::Tpkt(
            s7::tpkt::TpktError::BadVersion(b'G')
        )))
    );
    // Data before the connection request.
    let mut server = ServerConnection::new(ServerConfig::default());
    server.handle_input(
        &[0x03, 0x00, 0x00, 0x08, 0x02, 0xF0, 0x80, 0x32],
        &mut memory,
    );
    assert!(server.is_closed());
}

#[test]
fn the_client_closes_on_a_disconnect_and_refuses_further_requests() {
    let mut pair = Pair::new(
        ClientConfig::default(),
        ServerConfig::default(),
        Memory::default(),
    );
    pair.connect();
    pair.client.handle_input(&frame(&Tpdu::DisconnectRequest {
        dst_ref: 1,
        src_ref: 1,
        reason: 0x80,
    }));
    assert!(pair.client.is_closed());
    assert_eq!(
        pair.client.poll_event(),
        Some(ClientEvent::Closed(ConnectionError::Disconnected {
            reason: 0x80
        }))
    );
    assert_eq!(
        pair.client.read(vec![db1(0, 1)]),
        Err(s7::RequestError::Closed)
    );
}

#[test]
fn the_client_reports_a_refused_job_on_every_item_and_closes_on_mismatched_answers() {
    let mut client = ClientConnection::new(ClientConfig::default());
    let mut out = Vec::new();
    while client.poll_transmit(&mut out) {}
    client.handle_input(&frame(&Tpdu::ConnectionConfirm(ConnectionParams {
        dst_ref: 1,
        src_ref: 1,
        class: 0,
        tpdu_size: Some(TpduSize::S7),
        calling_tsap: None,
        called_tsap: None,
    })));
    while client.poll_transmit(&mut out) {}
    client.handle_input(&data(&Pdu::AckData {
        pdu_ref: 1,
        error: ErrorCode::NONE,
        response: Response::SetupCommunication(s7::pdu::SetupCommunication {
            max_amq_calling: 1,
            max_amq_called: 1,
            pdu_size: 240,
        }),
    }));
    assert!(client.is_connected());
    let id = client.read(vec![db1(0, 2), db1(2, 2)]).unwrap();
    while client.poll_transmit(&mut out) {}
    let refused = ErrorCode {
        class: 0x85,
        code: 0x00,
    };
    client.handle_input(&data(&Pdu::AckData {
        pdu_ref: 2,
        error: refused,
        response: Response::None,
    }));
    let events: Vec<ClientEvent> = std::iter::from_fn(|| client.poll_event()).collect();
    assert_eq!(
        events.last(),
        Some(&ClientEvent::ReadDone {
            id,
            results: vec![
                Err(ItemError::JobRefused(refused)),
                Err(ItemError::JobRefused(refused))
            ]
        })
    );
    // A write answered as if it were a read.
    client
        .write(vec![WriteItem {
            region: db1(0, 1),
            data: vec![1],
        }])
        .unwrap();
    while client.poll_transmit(&mut out) {}
    client.handle_input(&data(&Pdu::AckData {
        pdu_ref: 3,
        error: ErrorCode::NONE,
        response: Response::ReadVar(vec![]),
    }));
    assert!(client.is_closed());
    assert_eq!(
        std::iter::from_fn(|| client.poll_event()).last(),
        Some(ClientEvent::Closed(ConnectionError::MismatchedAnswer {
            pdu_ref: 3
        }))
    );
}

#[test]
fn the_client_refuses_bad_requests_before_sending() {
    let mut client = ClientConnection::new(ClientConfig::default());
    assert!(matches!(
        client.read(vec![db1(0, 0)]),
        Err(s7::RequestError::Region { item: 0, .. })
    ));
    assert!(matches!(
        client.write(vec![WriteItem {
            region: db1(0, 2),
            data: vec![1]
        }]),
        Err(s7::RequestError::DataLength {
            item: 0,
            expected: 2,
            got: 1
        })
    ));
    assert!(matches!(
        client.write(vec![WriteItem {
            region: Region::Bit {
                area: Area::Markers,
                byte: 0,
                bit: 0
            },
            data: vec![2]
        }]),
        Err(s7::RequestError::BitValue { item: 0, value: 2 })
    ));
}
