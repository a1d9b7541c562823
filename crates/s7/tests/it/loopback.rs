//! Client and server over loopback TCP: every item kind written and read back, bit
//! writes, splitting at PDU 240, large items, item errors on a usable connection, any
//! connection type, shared memory across connections, a bad frame closing only its own
//! connection, timeouts. Ports come from binding 127.0.0.1:0; nothing waits on a clock
//! except the timeout test, which waits on a server that never answers.

use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::mpsc;
use tokio::task::JoinHandle;

use s7::io::{serve, Client, ClientError, ServeEvent, SharedMemory};
use s7::pdu::ReturnCode;
use s7::split::WriteItem;
use s7::{
    Address, Area, ClientConfig, ConnectionError, ItemError, Memory, Region, ServerConfig,
    ServerEvent, Tsap, Tsaps, Value,
};

const TIMEOUT: Duration = Duration::from_secs(10);

struct Server {
    addr: SocketAddr,
    memory: SharedMemory,
    events: mpsc::Receiver<ServeEvent>,
    task: JoinHandle<()>,
}

impl Drop for Server {
    fn drop(&mut self) {
        self.task.abort();
    }
}

impl Server {
    async fn start(memory: Memory, config: ServerConfig) -> Server {
        let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
        let addr = listener.local_addr().unwrap();
        let memory = Arc::new(Mutex::new(memory));
        let (sender, events) = mpsc::channel(1024);
        let task = tokio::spawn(serve(listener, Arc::clone(&memory), config, sender));
        Server {
            addr,
            memory,
            events,
            task,
        }
    }

    async fn connect(&self) -> Client {
        Client::connect(self.addr, ClientConfig::default(), TIMEOUT)
            .await
            .unwrap()
    }

    /// The next event matching `wanted`, skipping others.
    async fn next_event(&mut self, wanted: impl Fn(&ServerEvent) -> bool) -> ServeEvent {
        loop {
            let event = tokio::time::timeout(TIMEOUT, self.events.recv())
                .await
                .expect("an event in time")
                .expect("the server runs");
            if wanted(&event.event) {
                return event;
            }
        }
    }

    fn memory(&self) -> std::sync::MutexGuard<'_, Memory> {
        self.memory.lock().unwrap()
    }
}

fn station_memory() -> Memory {
    let mut memory = Memory::default();
    memory.add_data_block(1, 1200).unwrap();
    memory.add_data_block(2, 64).unwrap();
    memory
}

fn address(text: &str) -> Address {
    text.parse().unwrap()
}

#[tokio::test]
async fn every_item_kind_is_written_and_read_back() {
    let server = Server::start(station_memory(), ServerConfig::default()).await;
    let client = server.connect().await;
    assert_eq!(client.negotiated().pdu_size, 240);
    let items: Vec<(Address, &str)> = [
        ("DB1.DBX0.3", "true"),
        ("DB1.DBB1", "200"),
        ("DB1.DBW2", "65535"),
        ("DB1.DBD4", "4000000000"),
        ("DB1.DBW8:INT", "-1234"),
        ("DB1.DBD10:DINT", "-123456789"),
        ("DB1.DBD14:REAL", "3.25"),
        ("DB1.DBB18:SINT", "-5"),
        ("MB10", "17"),
        ("MW20", "4660"),
        ("MD24", "305419896"),
        ("M30.7", "true"),
        ("IX0.1", "true"),
        ("IB1", "9"),
        ("IW2", "258"),
        ("Q0.2", "true"),
        ("QB1", "1"),
        ("QW2", "772"),
    ]
    .into_iter()
    .map(|(text, value)| (address(text), value))
    .collect();
    let writes: Vec<(Address, Value)> = items
        .iter()
        .map(|(address, text)| (*address, address.parse_value(text).unwrap()))
        .collect();
    let written = client.write_values(&writes).await.unwrap();
    assert!(written.iter().all(Result::is_ok), "{written:?}");

    let addresses: Vec<Address> = items.iter().map(|(address, _)| *address).collect();
    let read = client.read_values(&addresses).await.unwrap();
    for ((address, text), value) in items.iter().zip(read) {
        assert_eq!(value.unwrap().to_string(), *text, "{address}");
    }
    // And in memory, where a PLC program would see them.
    let memory = server.memory();
    assert_eq!(memory.area(Area::DataBlock(1)).unwrap()[0], 0b0000_1000);
    assert_eq!(
        memory.get(&address("DB1.DBD14:REAL")).unwrap(),
        Value::Real(3.25)
    );
    assert_eq!(memory.area(Area::Markers).unwrap()[20..22], [0x12, 0x34]);
    assert_eq!(memory.area(Area::Inputs).unwrap()[0], 0b10);
    assert_eq!(memory.area(Area::Outputs).unwrap()[0], 0b100);
}

#[tokio::test]
async fn a_bit_write_changes_only_its_bit() {
    let mut server = Server::start(station_memory(), ServerConfig::default()).await;
    server.memory().area_mut(Area::Markers).unwrap()[10] = 0xFF;
    let client = server.connect().await;
    let written = client
        .write_values(&[(address("M10.3"), Value::Bool(false))])
        .await
        .unwrap();
    assert_eq!(written, vec![Ok(())]);
    assert_eq!(server.memory().area(Area::Markers).unwrap()[10], 0xF7);
    let read = client.read_values(&[address("MB10")]).await.unwrap();
    assert_eq!(read, vec![Ok(Value::Byte(0xF7))]);
    client
        .write_values(&[(address("M10.3"), Value::Bool(true))])
        .await
        .unwrap();
    assert_eq!(server.memory().area(Area::Markers).unwrap()[10], 0xFF);

    let event = server
        .next_event(|event| matches!(event, ServerEvent::Write(_)))
        .await;
    let ServerEvent::Write(write) = event.event else {
        unreachable!()
    };
    assert_eq!(
        write.to_json(),
        r#"{"area": "M", "start": 10, "bit": 3, "size": 1, "data": "00"}"#
    );
}

#[tokio::test]
async fn thirty_items_split_at_pdu_240_come_back_in_order() {
    let server = Server::start(station_memory(), ServerConfig::default()).await;
    {
        let mut memory = server.memory();
        for index in 0..30u16 {
            memory
                .set(
                    &address(&format!("DB1.DBW{}:INT", index * 4)),
                    &Value::Int(-(index as i16) * 100),
                )
                .unwrap();
        }
    }
    let client = server.connect().await;
    let addresses: Vec<Address> = (0..30)
        .map(|index| address(&format!("DB1.DBW{}:INT", index * 4)))
        .collect();
    // 30 items do not fit one job of 240 bytes (12 + 30 * 12 = 372): the server refuses
    // a job larger than the PDU, so these results prove the split.
    let values = client.read_values(&addresses).await.unwrap();
    let expected: Vec<Result<Value, ItemError>> = (0..30i16)
        .map(|index| Ok(Value::Int(-index * 100)))
        .collect();
    assert_eq!(values, expected);

    let writes: Vec<(Address, Value)> = addresses
        .iter()
        .enumerate()
        .map(|(index, address)| (*address, Value::Int(index as i16)))
        .collect();
    let written = client.write_values(&writes).await.unwrap();
    assert_eq!(written, vec![Ok(()); 30]);
    let values = client.read_values(&addresses).await.unwrap();
    let expected: Vec<Result<Value, ItemError>> =
        (0..30i16).map(|index| Ok(Value::Int(index))).collect();
    assert_eq!(values, expected);
}

#[tokio::test]
async fn a_thousand_byte_read_and_write_are_split() {
    let server = Server::start(station_memory(), ServerConfig::default()).await;
    let pattern: Vec<u8> = (0..1000u32).map(|i| (i % 253) as u8).collect();
    server.memory().area_mut(Area::DataBlock(1)).unwrap()[..1000].copy_from_slice(&pattern);
    let client = server.connect().await;
    let region = Region::Bytes {
        area: Area::DataBlock(1),
        start: 0,
        len: 1000,
    };
    assert_eq!(
        client.read(vec![region]).await.unwrap(),
        vec![Ok(pattern.clone())]
    );
    let reversed: Vec<u8> = pattern.iter().rev().copied().collect();
    let written = client
        .write(vec![WriteItem {
            region: Region::Bytes {
                area: Area::DataBlock(1),
                start: 200,
                len: 1000,
            },
            data: reversed.clone(),
        }])
        .await
        .unwrap();
    assert_eq!(written, vec![Ok(())]);
    assert_eq!(
        &server.memory().area(Area::DataBlock(1)).unwrap()[200..1200],
        &reversed[..]
    );
}

#[tokio::test]
async fn an_unknown_db_is_answered_per_item_and_the_connection_stays_usable() {
    let server = Server::start(station_memory(), ServerConfig::default()).await;
    let client = server.connect().await;
    let read = client
        .read_values(&[
            address("DB99.DBW0"),
            address("DB2.DBW62"),
            address("DB2.DBW63"),
            address("DB1.DBB0"),
        ])
        .await
        .unwrap();
    assert_eq!(
        read,
        vec![
            Err(ItemError::Refused(ReturnCode::ObjectDoesNotExist)),
            Ok(Value::Word(0)),
            Err(ItemError::Refused(ReturnCode::AddressOutOfRange)),
            Ok(Value::Byte(0)),
        ]
    );
    let written = client
        .write_values(&[(address("DB99.DBX0.0"), Value::Bool(true))])
        .await
        .unwrap();
    assert_eq!(
        written,
        vec![Err(ItemError::Refused(ReturnCode::ObjectDoesNotExist))]
    );
    // Still connected.
    let read = client.read_values(&[address("DB2.DBB0")]).await.unwrap();
    assert_eq!(read, vec![Ok(Value::Byte(0))]);
}

#[tokio::test]
async fn any_connection_type_is_accepted() {
    let mut server = Server::start(station_memory(), ServerConfig::default()).await;
    for remote in [0x0101u16, 0x0201, 0x0301, 0x1002] {
        let tsaps = Tsaps {
            local: Tsap::new(0x0200),
            remote: Tsap::new(remote),
        };
        let client = Client::connect(server.addr, ClientConfig::new(tsaps), TIMEOUT)
            .await
            .unwrap();
        let read = client.read_values(&[address("MB0")]).await.unwrap();
        assert_eq!(read, vec![Ok(Value::Byte(0))]);
        let event = server
            .next_event(|event| matches!(event, ServerEvent::Connected { .. }))
            .await;
        assert_eq!(
            event.event,
            ServerEvent::Connected {
                calling_tsap: Some(Tsap::new(0x0200)),
                called_tsap: Some(Tsap::new(remote)),
            }
        );
    }
}

#[tokio::test]
async fn connections_share_memory_and_writes_are_reported() {
    let mut server = Server::start(station_memory(), ServerConfig::default()).await;
    let logo = server.connect().await;
    let scada = server.connect().await;
    logo.write(vec![WriteItem {
        region: Region::Bytes {
            area: Area::DataBlock(1),
            start: 4,
            len: 16,
        },
        data: (1..=16).collect(),
    }])
    .await
    .unwrap();
    let read = scada
        .read(vec![Region::Bytes {
            area: Area::DataBlock(1),
            start: 4,
            len: 16,
        }])
        .await
        .unwrap();
    assert_eq!(read, vec![Ok((1..=16).collect::<Vec<u8>>())]);
    let event = server
        .next_event(|event| matches!(event, ServerEvent::Write(_)))
        .await;
    let ServerEvent::Write(write) = event.event else {
        unreachable!()
    };
    assert_eq!(
        write.to_json(),
        r#"{"area": "DB", "db": 1, "start": 4, "size": 16, "data": "0102030405060708090a0b0c0d0e0f10"}"#
    );
}

#[tokio::test]
async fn a_bad_frame_closes_only_its_own_connection() {
    let mut server = Server::start(station_memory(), ServerConfig::default()).await;
    let good = server.connect().await;
    let mut bad = TcpStream::connect(server.addr).await.unwrap();
    bad.write_all(b"GET / HTTP/1.1\r\n\r\n").await.unwrap();
    // The server closes that socket: the read ends.
    let mut rest = Vec::new();
    tokio::time::timeout(TIMEOUT, bad.read_to_end(&mut rest))
        .await
        .expect("closed in time")
        .unwrap();
    assert!(rest.is_empty());
    let closed = server
        .next_event(|event| matches!(event, ServerEvent::Closed(ConnectionError::Tpkt(_))))
        .await;
    assert_eq!(closed.peer, bad.local_addr().unwrap());
    // The other connection goes on.
    let read = good.read_values(&[address("MB0")]).await.unwrap();
    assert_eq!(read, vec![Ok(Value::Byte(0))]);
}

#[tokio::test]
async fn a_dropped_client_closes_its_connection() {
    let mut server = Server::start(station_memory(), ServerConfig::default()).await;
    let client = server.connect().await;
    let clone = client.clone();
    drop(client);
    clone.read_values(&[address("MB0")]).await.unwrap();
    drop(clone);
    let closed = server
        .next_event(|event| matches!(event, ServerEvent::Closed(_)))
        .await;
    assert_eq!(
        closed.event,
        ServerEvent::Closed(ConnectionError::PeerClosed)
    );
}

#[tokio::test]
async fn connecting_times_out_when_nothing_answers() {
    // A listener that accepts (the kernel does) and never speaks.
    let silent = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = silent.local_addr().unwrap();
    let timeout = Duration::from_millis(200);
    let result = Client::connect(addr, ClientConfig::default(), timeout).await;
    assert!(
        matches!(result, Err(ClientError::Timeout(t)) if t == timeout),
        "{result:?}"
    );
}

#[tokio::test]
async fn a_refused_tcp_connection_is_an_io_error() {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    drop(listener);
    let result = Client::connect(addr, ClientConfig::default(), TIMEOUT).await;
    assert!(matches!(result, Err(ClientError::Io(_))), "{result:?}");
}

#[tokio::test]
async fn calls_after_the_server_went_away_fail_with_the_reason() {
    let server = Server::start(station_memory(), ServerConfig::default()).await;
    let client = server.connect().await;
    let addr = server.addr;
    drop(server);
    // The serve task's abort drops its connections: the socket closes under the client.
    let result = loop {
        match client.read_values(&[address("MB0")]).await {
            Ok(_) => tokio::task::yield_now().await,
            Err(error) => break error,
        }
    };
    assert!(
        matches!(
            result,
            ClientError::Closed(ConnectionError::PeerClosed) | ClientError::Io(_)
        ),
        "{result:?} from {addr}"
    );
}
