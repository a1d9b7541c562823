//! Our client against our RTU slave over a pseudo-terminal pair (the client opens the
//! other end's path as a serial port, 19200 Bd 8N1): every function code, exceptions 1,
//! 2 and 3, unit ids and broadcast, and against raw slaves that stay silent, lose a
//! request or answer as another unit.

use std::sync::atomic::AtomicUsize;
use std::sync::Arc;
use std::time::Duration;

use modbus::{ClientError, DataModel, Framing, ModelConfig, Request, Table, Units, Values};
use serial_line::io::Transport;

use crate::support::*;

const LONG: Duration = Duration::from_secs(10);

fn unit_1() -> DataModel {
    DataModel::new(ModelConfig::new(Units::Single(1)))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_function_code_over_a_pty() {
    let model = unit_1();
    let (path, _slave) = rtu_slave(model.clone()).await;
    let mut client = rtu_client(&path, LONG, 0).await;
    every_function_code(&mut client, &model, 1).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn exceptions_over_a_pty() {
    let (path, _slave) = rtu_slave(unit_1()).await;
    let mut client = rtu_client(&path, LONG, 0).await;
    exceptions_1_and_2(&mut client, 1).await;
    drop(client);
    // 3: what our client refuses to send, sent raw.
    let answer = raw_rtu(&path, 1, &[0x03, 0, 0, 0, 0], LONG).await;
    assert_eq!(answer, Some((1, vec![0x83, 0x03])));
    let answer = raw_rtu(&path, 1, &[0x0F, 0, 0, 0, 100, 1, 0xFF], LONG).await;
    assert_eq!(answer, Some((1, vec![0x8F, 0x03])));
    // 1 for a function whose request length the slave cannot know: judged at the pause.
    let answer = raw_rtu(&path, 1, &[0x41, 1, 2, 3], LONG).await;
    assert_eq!(answer, Some((1, vec![0xC1, 0x01])));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn another_units_request_is_not_answered_and_broadcasts_are_carried_out() {
    let model = unit_1();
    let (path, _slave) = rtu_slave(model.clone()).await;
    let mut client = rtu_client(&path, Duration::from_millis(300), 0).await;
    let error = client.read(2, Table::Coils, 0, 1).await.unwrap_err();
    assert!(
        matches!(
            error,
            ClientError::Timeout {
                unit: 2,
                attempts: 1,
                ..
            }
        ),
        "{error}"
    );
    assert!(error.to_string().contains(&path), "{error}");
    // The slave still answers its own unit after the other's request. (A serial port is
    // opened exclusively: one client at a time.)
    drop(client);
    let mut client = rtu_client(&path, LONG, 0).await;
    assert_eq!(
        client.read(1, Table::Coils, 0, 1).await.unwrap(),
        Values::Bits(vec![false])
    );
    drop(client);
    let mut events = model.subscribe();
    let write = Request::WriteSingleRegister {
        address: 3,
        value: 33,
    };
    let answer = raw_rtu(
        &path,
        0,
        &write.to_pdu().unwrap(),
        Duration::from_millis(300),
    )
    .await;
    assert_eq!(answer, None, "a broadcast is not answered");
    let event = tokio::time::timeout(LONG, events.recv())
        .await
        .unwrap()
        .unwrap();
    assert_eq!((event.unit, event.address), (0, 3));
    assert_eq!(
        model.read(1, Table::HoldingRegisters, 3, 1),
        Ok(Values::Registers(vec![33]))
    );
}

async fn raw_rtu_peer(misbehaviour: Misbehaviour) -> (String, Arc<AtomicUsize>, Task) {
    let line = Transport::Pty.open().await.unwrap();
    let path = line.pty_path.clone().unwrap();
    let requests = Arc::new(AtomicUsize::new(0));
    let counted = Arc::clone(&requests);
    let task = tokio::spawn(async move {
        let mut line = line;
        let stream = std::mem::replace(&mut line.stream, Box::pin(tokio::io::empty()));
        let mut peer = raw_peer(stream, Framing::Rtu, unit_1(), misbehaviour, counted);
        let _ = (&mut peer.0).await;
        drop(line);
    });
    (path, requests, Task(task))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_silent_slave_times_out_naming_the_port_and_the_time() {
    let (path, requests, _peer) = raw_rtu_peer(Misbehaviour::Silent).await;
    let mut client = rtu_client(&path, Duration::from_millis(200), 2).await;
    let error = client.call(1, &read_ten()).await.unwrap_err();
    assert!(
        matches!(error, ClientError::Timeout { attempts: 3, .. }),
        "{error}"
    );
    assert_eq!(attempts(&requests, 3).await, 3);
    assert_eq!(
        error.to_string(),
        format!("no answer from unit 1 on serial {path} 19200 Bd 8N1 within 200ms (3 attempts)")
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_lost_rtu_request_is_repeated() {
    let (path, requests, _peer) = raw_rtu_peer(Misbehaviour::DropFirst).await;
    let mut client = rtu_client(&path, Duration::from_secs(2), 1).await;
    assert_eq!(
        client.read(1, Table::InputRegisters, 0, 4).await.unwrap(),
        Values::Registers(vec![0; 4])
    );
    assert_eq!(attempts(&requests, 2).await, 2);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_rtu_answer_from_another_unit_is_not_taken() {
    let (path, requests, _peer) = raw_rtu_peer(Misbehaviour::OtherUnit).await;
    let mut client = rtu_client(&path, LONG, 1).await;
    let error = client.call(1, &read_ten()).await.unwrap_err();
    assert!(
        matches!(error, ClientError::Protocol { unit: 1, .. }),
        "{error}"
    );
    assert_eq!(attempts(&requests, 2).await, 2);
}
