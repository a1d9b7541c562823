//! What the loopback, pseudo-terminal and interoperability tests share: our servers
//! started on loopback and on a pseudo-terminal, the line a pseudo-terminal keeps, raw
//! peers that misbehave on purpose, and the exchange of every function code.

use std::net::SocketAddr;
use std::pin::Pin;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;

use modbus::io::{serve_rtu, serve_tcp};
use modbus::rtu::{decode_frame, frame, RtuDeframer};
use modbus::server::{answer, Outcome};
use modbus::tcp::{Adu, MbapDeframer};
use modbus::{
    Client, ClientConfig, ClientError, DataModel, ExceptionCode, Framing, LineSettings, Parity,
    Request, RtuSlave, Table, Values, WriteEvent,
};
use serial_line::io::{LineStream, Transport};
use tokio::io::{AsyncReadExt as _, AsyncWriteExt as _};
use tokio::net::TcpListener;
use tokio::task::JoinHandle;

/// A pseudo-terminal keeps no parity: 19200 Bd 8N1.
pub(crate) const PTY_LINE: LineSettings = LineSettings {
    baud: 19_200,
    parity: Parity::None,
    stop_bits: 1,
};

/// A task aborted when dropped.
pub(crate) struct Task(pub(crate) JoinHandle<()>);

impl Drop for Task {
    fn drop(&mut self) {
        self.0.abort();
    }
}

/// Our TCP server on a free loopback port.
pub(crate) async fn tcp_server(model: DataModel) -> (SocketAddr, Task) {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let address = listener.local_addr().unwrap();
    let task = tokio::spawn(async move {
        serve_tcp(listener, model).await.unwrap();
    });
    (address, Task(task))
}

/// Our RTU slave on a new pseudo-terminal pair: the path of the other end.
pub(crate) async fn rtu_slave(model: DataModel) -> (String, Task) {
    let line = Transport::Pty.open().await.unwrap();
    let path = line.pty_path.clone().unwrap();
    let task = tokio::spawn(async move {
        // The whole line moves in: it holds the other end open.
        let line = line;
        let mut slave = RtuSlave::new(model, PTY_LINE);
        let end = serve_rtu(line.stream, &mut slave).await;
        panic!("the slave stopped: {end:?}");
    });
    (path, Task(task))
}

pub(crate) fn config(framing: Framing, timeout: Duration, retries: u8) -> ClientConfig {
    let mut config = match framing {
        Framing::Tcp => ClientConfig::tcp(),
        Framing::Rtu => ClientConfig::rtu(PTY_LINE),
    };
    config.timeout = timeout;
    config.retries = retries;
    config
}

/// Our client on TCP.
pub(crate) async fn tcp_client(address: SocketAddr, timeout: Duration, retries: u8) -> Client {
    Client::open(
        Transport::Connect(address.to_string()),
        config(Framing::Tcp, timeout, retries),
    )
    .await
    .unwrap()
}

/// Our client on a pseudo-terminal's path, as on a serial port.
pub(crate) async fn rtu_client(path: &str, timeout: Duration, retries: u8) -> Client {
    Client::open(
        Transport::Serial {
            path: path.to_owned(),
            line: PTY_LINE,
        },
        config(Framing::Rtu, timeout, retries),
    )
    .await
    .unwrap()
}

/// Every supported function code from the client to a server of `model` for `unit`:
/// writes read back, the server's own values read, FC 23, and an event per write.
pub(crate) async fn every_function_code(client: &mut Client, model: &DataModel, unit: u8) {
    let mut events = model.subscribe();
    // FC 5 and 15, read back by FC 1.
    client.write_coils(unit, 10, &[true]).await.unwrap();
    client
        .write_coils(
            unit,
            20,
            &[true, false, true, true, false, false, true, true, true],
        )
        .await
        .unwrap();
    assert_eq!(
        client.read(unit, Table::Coils, 10, 1).await.unwrap(),
        Values::Bits(vec![true])
    );
    assert_eq!(
        client.read(unit, Table::Coils, 19, 11).await.unwrap(),
        Values::Bits(vec![
            false, true, false, true, true, false, false, true, true, true, false
        ])
    );
    // FC 2: what the server's side set.
    model
        .write(
            unit,
            Table::DiscreteInputs,
            196,
            &Values::Bits(vec![false, true, true]),
        )
        .unwrap();
    assert_eq!(
        client
            .read(unit, Table::DiscreteInputs, 196, 3)
            .await
            .unwrap(),
        Values::Bits(vec![false, true, true])
    );
    // FC 6 and 16, read back by FC 3.
    client.write_registers(unit, 100, &[0xFFFF]).await.unwrap();
    client
        .write_registers(unit, 101, &[1, 2, 0x8000])
        .await
        .unwrap();
    assert_eq!(
        client
            .read(unit, Table::HoldingRegisters, 100, 4)
            .await
            .unwrap(),
        Values::Registers(vec![0xFFFF, 1, 2, 0x8000])
    );
    // FC 4.
    model
        .write(
            unit,
            Table::InputRegisters,
            8,
            &Values::Registers(vec![10, 11]),
        )
        .unwrap();
    assert_eq!(
        client
            .read(unit, Table::InputRegisters, 8, 2)
            .await
            .unwrap(),
        Values::Registers(vec![10, 11])
    );
    // FC 23: the write before the read, overlapping.
    assert_eq!(
        client
            .read_write_registers(unit, 100, 3, 102, &[7, 8])
            .await
            .unwrap(),
        [0xFFFF, 1, 7]
    );
    // The largest reads.
    assert_eq!(
        client
            .read(unit, Table::Coils, 0, 2000)
            .await
            .unwrap()
            .len(),
        2000
    );
    assert_eq!(
        client
            .read(unit, Table::HoldingRegisters, 9875, 125)
            .await
            .unwrap()
            .len(),
        125
    );
    let written: Vec<WriteEvent> = std::iter::from_fn(|| events.try_recv().ok()).collect();
    assert_eq!(
        written
            .iter()
            .map(|e| (e.unit, e.table, e.address, e.values.clone()))
            .collect::<Vec<_>>(),
        [
            (unit, Table::Coils, 10, Values::Bits(vec![true])),
            (
                unit,
                Table::Coils,
                20,
                Values::Bits(vec![
                    true, false, true, true, false, false, true, true, true
                ])
            ),
            (
                unit,
                Table::HoldingRegisters,
                100,
                Values::Registers(vec![0xFFFF])
            ),
            (
                unit,
                Table::HoldingRegisters,
                101,
                Values::Registers(vec![1, 2, 0x8000])
            ),
            (
                unit,
                Table::HoldingRegisters,
                102,
                Values::Registers(vec![7, 8])
            ),
        ]
    );
}

/// Exceptions 2 (our client reading past the table) and 1 (a function code the server
/// does not know).
pub(crate) async fn exceptions_1_and_2(client: &mut Client, unit: u8) {
    let error = client
        .read(unit, Table::HoldingRegisters, 9_999, 2)
        .await
        .unwrap_err();
    let ClientError::Exception { code, function, .. } = &error else {
        panic!("{error}");
    };
    assert_eq!(*code, ExceptionCode::ILLEGAL_DATA_ADDRESS);
    assert_eq!(function.0, 3);
    let text = error.to_string();
    assert!(text.contains("illegal data address (code 2)"), "{text}");
    assert!(text.contains(client.peer()), "{text}");
    let error = client.call_custom(unit, 0x41, &[1, 2]).await.unwrap_err();
    assert!(
        matches!(
            error,
            ClientError::Exception {
                code: ExceptionCode::ILLEGAL_FUNCTION,
                ..
            }
        ),
        "{error}"
    );
    // Our client does not send what it knows the server must refuse.
    assert!(matches!(
        client.read(unit, Table::HoldingRegisters, 0, 126).await,
        Err(ClientError::Request(_))
    ));
}

/// One raw Modbus TCP exchange: the answer PDU.
pub(crate) async fn raw_tcp(address: SocketAddr, unit: u8, pdu: &[u8]) -> Vec<u8> {
    let mut stream = tokio::net::TcpStream::connect(address).await.unwrap();
    let adu = Adu {
        transaction: 0x1234,
        protocol: 0,
        unit,
        pdu: pdu.to_vec(),
    };
    stream.write_all(&adu.to_bytes()).await.unwrap();
    let mut deframer = MbapDeframer::new();
    let mut buf = [0u8; 300];
    loop {
        let count = tokio::time::timeout(Duration::from_secs(10), stream.read(&mut buf))
            .await
            .expect("an answer within 10 s")
            .unwrap();
        assert!(count > 0, "closed without an answer");
        deframer.push(&buf[..count]);
        if let Some(answer) = deframer.next_frame().unwrap() {
            assert_eq!((answer.transaction, answer.unit), (0x1234, unit));
            return answer.pdu;
        }
    }
}

/// One raw RTU exchange on a serial port (a pseudo-terminal's path): the answer's unit
/// and PDU, or `None` when nothing came within `within`.
pub(crate) async fn raw_rtu(
    path: &str,
    unit: u8,
    pdu: &[u8],
    within: Duration,
) -> Option<(u8, Vec<u8>)> {
    let line = Transport::Serial {
        path: path.to_owned(),
        line: PTY_LINE,
    }
    .open()
    .await
    .unwrap();
    let mut stream = line.stream;
    stream.write_all(&frame(unit, pdu)).await.unwrap();
    let mut got = Vec::new();
    let mut buf = [0u8; 300];
    let deadline = tokio::time::Instant::now() + within;
    loop {
        let read = tokio::time::timeout_at(deadline, stream.read(&mut buf)).await;
        let Ok(count) = read else {
            return None;
        };
        let count = count.unwrap();
        got.extend_from_slice(&buf[..count]);
        if let Some((unit, pdu)) = decode_frame(&got) {
            return Some((unit, pdu.to_vec()));
        }
    }
}

/// How a raw peer treats the requests it reads.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Misbehaviour {
    /// Never answers.
    Silent,
    /// Drops the first request, answers the others.
    DropFirst,
    /// Answers with another unit id.
    OtherUnit,
}

/// A raw peer on a line's stream: reads requests (MBAP or RTU), counts them, and answers
/// from `model` as `misbehaviour` says. The count is shared with the test.
pub(crate) fn raw_peer(
    mut stream: Pin<Box<dyn LineStream>>,
    framing: Framing,
    model: DataModel,
    misbehaviour: Misbehaviour,
    requests: Arc<AtomicUsize>,
) -> Task {
    Task(tokio::spawn(async move {
        let mut tcp = MbapDeframer::new();
        let mut rtu = RtuDeframer::new();
        let mut buf = [0u8; 512];
        loop {
            // RTU: the pause after a request ends it (the test's requests are whole).
            let read = tokio::time::timeout(Duration::from_millis(20), stream.read(&mut buf)).await;
            let frames: Vec<(u16, u8, Vec<u8>)> = match (framing, read) {
                (_, Ok(Ok(0))) | (_, Ok(Err(_))) => return,
                (Framing::Tcp, Ok(Ok(count))) => {
                    tcp.push(&buf[..count]);
                    std::iter::from_fn(|| tcp.next_frame().unwrap())
                        .map(|adu| (adu.transaction, adu.unit, adu.pdu))
                        .collect()
                }
                (Framing::Rtu, Ok(Ok(count))) => {
                    rtu.push(&buf[..count]);
                    std::iter::from_fn(|| rtu.next_frame())
                        .map(|frame| (0, frame.unit, frame.pdu))
                        .collect()
                }
                (Framing::Tcp, Err(_)) => Vec::new(),
                (Framing::Rtu, Err(_)) => rtu
                    .handle_pause()
                    .map(|frame| (0, frame.unit, frame.pdu))
                    .into_iter()
                    .collect(),
            };
            for (transaction, unit, pdu) in frames {
                let seen = requests.fetch_add(1, Ordering::SeqCst) + 1;
                let answer_unit = match misbehaviour {
                    Misbehaviour::Silent => continue,
                    Misbehaviour::DropFirst if seen == 1 => continue,
                    Misbehaviour::DropFirst => unit,
                    Misbehaviour::OtherUnit => unit.wrapping_add(1),
                };
                let Outcome::Answer(answer) = answer(&model, Framing::Tcp, unit, &pdu) else {
                    continue;
                };
                let octets = match framing {
                    Framing::Tcp => Adu {
                        transaction,
                        protocol: 0,
                        unit: answer_unit,
                        pdu: answer,
                    }
                    .to_bytes(),
                    Framing::Rtu => frame(answer_unit, &answer),
                };
                if stream.write_all(&octets).await.is_err() {
                    return;
                }
            }
        }
    }))
}

/// The requests a raw peer has read, once it has read `expected` (waited for at most
/// 10 s: the peer's task may run a moment after the client gave up).
pub(crate) async fn attempts(requests: &AtomicUsize, expected: usize) -> usize {
    let deadline = tokio::time::Instant::now() + Duration::from_secs(10);
    while requests.load(Ordering::SeqCst) < expected && tokio::time::Instant::now() < deadline {
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    requests.load(Ordering::SeqCst)
}

/// A read of ten holding registers from `unit` 1 with `Request`'s API.
pub(crate) fn read_ten() -> Request {
    Request::read(Table::HoldingRegisters, 0, 10)
}
