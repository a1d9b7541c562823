//! Our client against our TCP server on loopback: every function code, exceptions 1, 2
//! and 3, unit ids, several clients on one model, and against raw peers that stay
//! silent, lose a request or answer for another unit: the timeout, the repeat, the
//! mismatch; a connection the server closed is reopened.

use std::sync::atomic::AtomicUsize;
use std::sync::Arc;
use std::time::Duration;

use modbus::{ClientError, DataModel, ExceptionCode, Framing, ModelConfig, Table, Units, Values};
use serial_line::io::LineListener;

use crate::support::*;

const LONG: Duration = Duration::from_secs(10);

fn unit_1() -> DataModel {
    DataModel::new(ModelConfig::new(Units::Single(1)))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_function_code_over_tcp() {
    let model = unit_1();
    let (address, _server) = tcp_server(model.clone()).await;
    let mut client = tcp_client(address, LONG, 0).await;
    every_function_code(&mut client, &model, 1).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn exceptions_over_tcp() {
    let (address, _server) = tcp_server(unit_1()).await;
    let mut client = tcp_client(address, LONG, 0).await;
    exceptions_1_and_2(&mut client, 1).await;
    // 3: what our client refuses to send, sent raw.
    assert_eq!(raw_tcp(address, 1, &[0x03, 0, 0, 0, 0]).await, [0x83, 0x03]);
    assert_eq!(
        raw_tcp(address, 1, &[0x05, 0, 0, 0x12, 0x34]).await,
        [0x85, 0x03]
    );
    // The tokio-modbus decoder's panic (FC 15, quantity 100 in one octet) is exception 3
    // here, and the server serves on.
    assert_eq!(
        raw_tcp(address, 1, &[0x0F, 0, 0, 0, 100, 1, 0xFF]).await,
        [0x8F, 0x03]
    );
    assert_eq!(raw_tcp(address, 1, &[0x2A]).await, [0xAA, 0x01]);
    assert_eq!(
        client.read(1, Table::Coils, 0, 1).await.unwrap(),
        Values::Bits(vec![false])
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn unit_ids_over_tcp() {
    let (address, _server) = tcp_server(unit_1()).await;
    let mut client = tcp_client(address, LONG, 0).await;
    let error = client
        .read(2, Table::HoldingRegisters, 0, 1)
        .await
        .unwrap_err();
    assert!(
        matches!(
            error,
            ClientError::Exception {
                unit: 2,
                code: ExceptionCode::GATEWAY_TARGET_FAILED,
                ..
            }
        ),
        "{error}"
    );
    assert!(error
        .to_string()
        .contains("gateway target device failed to respond"));

    // Per unit: each its own tables, on one connection.
    let model = DataModel::new(ModelConfig::new(Units::PerUnit(vec![1, 2])));
    let (address, _server) = tcp_server(model.clone()).await;
    let mut client = tcp_client(address, LONG, 0).await;
    client.write_registers(1, 0, &[11]).await.unwrap();
    client.write_registers(2, 0, &[22]).await.unwrap();
    assert_eq!(
        client.read(1, Table::HoldingRegisters, 0, 1).await.unwrap(),
        Values::Registers(vec![11])
    );
    assert_eq!(
        client.read(2, Table::HoldingRegisters, 0, 1).await.unwrap(),
        Values::Registers(vec![22])
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn clients_share_one_model() {
    let model = DataModel::default();
    let (address, _server) = tcp_server(model.clone()).await;
    let mut first = tcp_client(address, LONG, 0).await;
    let mut second = tcp_client(address, LONG, 0).await;
    first.write_coils(9, 5, &[true, true]).await.unwrap();
    assert_eq!(
        second.read(9, Table::Coils, 5, 2).await.unwrap(),
        Values::Bits(vec![true, true])
    );
    // Without a unit setting, every unit id reads the same tables.
    assert_eq!(
        second.read(255, Table::Coils, 5, 2).await.unwrap(),
        Values::Bits(vec![true, true])
    );
}

async fn raw_tcp_peer(misbehaviour: Misbehaviour) -> (String, Arc<AtomicUsize>, Task) {
    let listener = LineListener::bind("127.0.0.1:0").await.unwrap();
    let address = listener.local_addr().unwrap().to_string();
    let requests = Arc::new(AtomicUsize::new(0));
    let counted = Arc::clone(&requests);
    let task = tokio::spawn(async move {
        let line = listener.accept().await.unwrap();
        let mut peer = raw_peer(line.stream, Framing::Tcp, unit_1(), misbehaviour, counted);
        let _ = (&mut peer.0).await;
    });
    (address, requests, Task(task))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_silent_server_times_out_naming_the_peer_and_the_time() {
    let (address, requests, _peer) = raw_tcp_peer(Misbehaviour::Silent).await;
    let mut client = tcp_client(address.parse().unwrap(), Duration::from_millis(200), 1).await;
    let error = client.call(1, &read_ten()).await.unwrap_err();
    assert!(
        matches!(
            error,
            ClientError::Timeout {
                attempts: 2,
                unit: 1,
                ..
            }
        ),
        "{error}"
    );
    assert_eq!(attempts(&requests, 2).await, 2);
    assert_eq!(
        error.to_string(),
        format!("no answer from unit 1 on tcp {address} within 200ms (2 attempts)")
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_lost_request_is_repeated() {
    let (address, requests, _peer) = raw_tcp_peer(Misbehaviour::DropFirst).await;
    // The first attempt must time out; the repeat has all the time it needs.
    let mut client = tcp_client(address.parse().unwrap(), Duration::from_secs(2), 1).await;
    let values = client
        .read(1, Table::HoldingRegisters, 0, 10)
        .await
        .unwrap();
    assert_eq!(values, Values::Registers(vec![0; 10]));
    assert_eq!(attempts(&requests, 2).await, 2);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_answer_for_another_unit_is_not_taken() {
    let (address, requests, _peer) = raw_tcp_peer(Misbehaviour::OtherUnit).await;
    let mut client = tcp_client(address.parse().unwrap(), LONG, 1).await;
    let error = client.call(1, &read_ten()).await.unwrap_err();
    assert!(
        matches!(error, ClientError::Protocol { unit: 1, .. }),
        "{error}"
    );
    assert!(error.to_string().contains("another unit"), "{error}");
    assert_eq!(attempts(&requests, 2).await, 2);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_connection_the_server_closed_is_reopened() {
    let model = DataModel::default();
    let (address, server) = tcp_server(model.clone()).await;
    let mut client = tcp_client(address, LONG, 1).await;
    client.write_registers(1, 0, &[5]).await.unwrap();
    drop(server);
    // The same address again (the listener's port is free once its task is gone).
    let mut restarted = None;
    for _ in 0..100 {
        match tokio::net::TcpListener::bind(address).await {
            Ok(listener) => {
                let model = model.clone();
                restarted = Some(Task(tokio::spawn(async move {
                    modbus::io::serve_tcp(listener, model).await.unwrap();
                })));
                break;
            }
            Err(_) => tokio::time::sleep(Duration::from_millis(20)).await,
        }
    }
    let _restarted = restarted.expect("the port is free again within 2 s");
    assert_eq!(
        client.read(1, Table::HoldingRegisters, 0, 1).await.unwrap(),
        Values::Registers(vec![5])
    );
}
