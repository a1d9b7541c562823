//! The client: alternate addresses, reconnection, time-outs, requests without a connection,
//! and acknowledgement of received events on a polite close.

use std::net::SocketAddr;
use std::sync::Arc;
use std::time::{Duration, Instant};

use iec60870::asdu::{Cause, CommandQualifier, Element, TypeId};
use iec60870::cs104::client::{spawn_client, ClientConfig, ClientError, ClientEvent};
use iec60870::cs104::server::{spawn_server, ProcessImage, ReadOnlyStation, ServerHandle};
use iec60870::cs104::{Role, Session, SessionEvent};

use crate::commands::{command_handler, command_image, NEVER};
use crate::common::*;

fn image() -> ProcessImage {
    let mut image = ProcessImage::new();
    image
        .add_monitor(monitor(1, TypeId::M_ME_NB_1, 0, scaled(0)))
        .unwrap();
    image
}

/// An address on which nobody listens.
async fn refusing_address() -> SocketAddr {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    listener.local_addr().unwrap()
}

async fn next_event(events: &mut tokio::sync::mpsc::Receiver<ClientEvent>) -> ClientEvent {
    within(WAIT, "a client event", events.recv())
        .await
        .expect("the client is running")
}

#[tokio::test]
async fn connects_to_the_second_address_when_the_first_refuses() {
    init_logs();
    let server = start_server(server_config(), image(), Arc::new(ReadOnlyStation)).await;
    let refused = refusing_address().await;
    let mut config = client_config(server.local_addr());
    config.addresses = vec![refused.to_string(), server.local_addr().to_string()];
    let (handle, mut events) = spawn_client(config);
    assert_eq!(
        next_event(&mut events).await,
        ClientEvent::Connected {
            peer: server.local_addr()
        }
    );
    assert_eq!(next_event(&mut events).await, ClientEvent::Started);
    let outcome = handle.read(ioa(1)).await.unwrap();
    assert!(outcome.positive);
}

/// Starts a server on `address`, retrying while the previous one still holds the port.
async fn restart_server(address: SocketAddr) -> ServerHandle {
    restart_server_with(address, image()).await
}

/// Starts a server serving `image` on `address`, retrying while the previous one still
/// holds the port.
pub(crate) async fn restart_server_with(address: SocketAddr, image: ProcessImage) -> ServerHandle {
    within(WAIT, "the port to be free again", async {
        loop {
            let mut config = server_config();
            config.listen = address;
            match spawn_server(config, image.clone(), Arc::new(ReadOnlyStation)).await {
                Ok(server) => return server,
                Err(_) => tokio::time::sleep(Duration::from_millis(20)).await,
            }
        }
    })
    .await
}

/// A client of the server at `address` that reconnects quickly (50-200 ms).
pub(crate) fn reconnecting_config(address: SocketAddr) -> ClientConfig {
    let mut config = client_config(address);
    config.reconnect = true;
    config.reconnect_delay = Duration::from_millis(50);
    config.reconnect_delay_max = Duration::from_millis(200);
    config
}

#[tokio::test]
async fn reconnects_after_the_server_restarts() {
    init_logs();
    let server = start_server(server_config(), image(), Arc::new(ReadOnlyStation)).await;
    let address = server.local_addr();
    let mut client = Client::start(reconnecting_config(address)).await;

    server.shutdown();
    within(WAIT, "the disconnection", async {
        loop {
            if let Some(ClientEvent::Disconnected { .. }) = client.events.recv().await {
                return;
            }
        }
    })
    .await;
    // While the server is away, requests fail at once.
    let refused = within(
        WAIT,
        "a request while disconnected",
        client.handle.read(ioa(1)),
    )
    .await;
    assert_eq!(refused.unwrap_err(), ClientError::NotConnected);

    let server = restart_server(address).await;
    client.wait_started().await;
    server.update(ioa(1), scaled(5), None).unwrap();
    assert_eq!(client.next_asdu().await.objects[0].element, scaled(5));
}

#[tokio::test]
async fn a_command_without_answer_times_out() {
    init_logs();
    let server = start_server(server_config(), command_image(), command_handler()).await;
    let mut config = client_config(server.local_addr());
    config.command_timeout = Duration::from_millis(300);
    let client = Client::start(config).await;
    let began = Instant::now();
    let result = within(
        WAIT,
        "the time-out",
        client.handle.command(
            TypeId::C_SC_NA_1,
            ioa(NEVER),
            Element::SingleCommand {
                on: true,
                qualifier: CommandQualifier::EXECUTE,
            },
            None,
        ),
    )
    .await;
    assert_eq!(
        result.unwrap_err(),
        ClientError::Timeout("the confirmation")
    );
    assert!(began.elapsed() >= Duration::from_millis(300));
    // While a request is open, the same request again is refused as busy.
    let command = || {
        client.handle.command(
            TypeId::C_SC_NA_1,
            ioa(NEVER),
            Element::SingleCommand {
                on: false,
                qualifier: CommandQualifier::EXECUTE,
            },
            None,
        )
    };
    let (first, second) = within(WAIT, "two commands", async {
        tokio::join!(command(), async {
            tokio::time::sleep(Duration::from_millis(50)).await;
            command().await
        })
    })
    .await;
    assert_eq!(first.unwrap_err(), ClientError::Timeout("the confirmation"));
    assert_eq!(second.unwrap_err(), ClientError::Busy);
    // The connection is still usable.
    assert!(client.handle.read(ioa(100)).await.unwrap().positive);
}

#[tokio::test]
async fn requests_fail_fast_without_a_started_connection() {
    init_logs();
    // Nobody listens: the client backs off between attempts.
    let mut config = client_config(refusing_address().await);
    config.reconnect = true;
    config.reconnect_delay = Duration::from_secs(2);
    let (handle, _events) = spawn_client(config);
    let result = within(
        Duration::from_secs(1),
        "NotConnected",
        handle.interrogate(20),
    )
    .await;
    assert_eq!(result.unwrap_err(), ClientError::NotConnected);
    handle.close().await;
    assert_eq!(
        handle.interrogate(20).await.unwrap_err(),
        ClientError::Stopped
    );

    // A server that accepts the connection but never confirms STARTDT.
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let mut config = client_config(listener.local_addr().unwrap());
    config.apci.t1 = Duration::from_secs(1);
    let (handle, mut events) = spawn_client(config);
    let (_socket, _) = within(WAIT, "accept", listener.accept()).await.unwrap();
    assert!(matches!(
        next_event(&mut events).await,
        ClientEvent::Connected { .. }
    ));
    let result = within(WAIT, "NotConnected", handle.interrogate(20)).await;
    assert_eq!(result.unwrap_err(), ClientError::NotConnected);
    // t1 closes the connection that was never confirmed.
    match next_event(&mut events).await {
        ClientEvent::Disconnected { reason } => assert!(reason.contains("t1"), "{reason}"),
        other => panic!("unexpected {other:?}"),
    }
}

#[tokio::test]
async fn a_request_open_when_the_connection_drops_fails_with_disconnected() {
    init_logs();
    let handler = command_handler();
    let server = start_server(server_config(), command_image(), handler.clone()).await;
    let client = Client::connect(server.local_addr()).await;
    let handle = client.handle.clone();
    let pending = tokio::spawn(async move {
        handle
            .command(
                TypeId::C_SC_NA_1,
                ioa(NEVER),
                Element::SingleCommand {
                    on: true,
                    qualifier: CommandQualifier::EXECUTE,
                },
                None,
            )
            .await
    });
    eventually(WAIT, "the command to reach the handler", || {
        handler.commands().len() == 1
    })
    .await;
    server.shutdown();
    let result = within(WAIT, "the failure", pending).await.unwrap();
    assert_eq!(result.unwrap_err(), ClientError::Disconnected);
}

#[tokio::test]
async fn a_polite_close_acknowledges_what_was_received() {
    init_logs();
    let server = start_server(server_config(), image(), Arc::new(ReadOnlyStation)).await;
    // Standard timers: on its own the client would acknowledge only after w = 8 frames or
    // t2 = 10 s.
    let mut config = client_config(server.local_addr());
    config.apci = iec60870::cs104::ApciConfig::default();
    let mut first = Client::start(config.clone()).await;
    for value in 1..=3 {
        server.update(ioa(1), scaled(value), None).unwrap();
        assert_eq!(first.next_asdu().await.objects[0].element, scaled(value));
    }
    assert_eq!(server.stats().groups[0].retransmit_queued, 3);
    within(WAIT, "close", first.handle.close()).await;
    // close() returns once the connection is closed: the events channel ends.
    assert!(within(WAIT, "the end of events", first.events.recv())
        .await
        .is_none());
    wait_connections(&server, 0).await;
    assert_eq!(
        server.stats().groups[0].retransmit_queued,
        0,
        "the close did not acknowledge"
    );

    let mut second = Client::start(config).await;
    server.update(ioa(1), scaled(4), None).unwrap();
    let asdu = second.next_asdu().await;
    assert_eq!(asdu.cot.cause, Cause::SPONTANEOUS);
    assert_eq!(asdu.objects.len(), 1);
    assert_eq!(
        asdu.objects[0].element,
        scaled(4),
        "events retransmitted to the next client"
    );
}

#[test]
fn acknowledge_received_queues_one_s_frame_only_when_needed() {
    let now = Instant::now();
    let mut server = Session::new(Default::default(), Role::ControlledStation, now);
    let mut client = Session::new(Default::default(), Role::ControllingStation, now);
    let mut wire = Vec::new();
    let mut pump = |from: &mut Session, to: &mut Session| {
        wire.clear();
        while from.poll_transmit(&mut wire) {}
        to.handle_input(now, &wire);
        wire.len()
    };
    client.start_data_transfer(now).unwrap();
    pump(&mut client, &mut server);
    pump(&mut server, &mut client);
    // Nothing received yet: nothing to acknowledge.
    client.acknowledge_received();
    assert_eq!(pump(&mut client, &mut server), 0);

    for payload in [b"a", b"b", b"c"] {
        server.send_asdu(now, payload).unwrap();
    }
    pump(&mut server, &mut client);
    assert_eq!(server.unacknowledged_count(), 3);
    client.acknowledge_received();
    assert_eq!(pump(&mut client, &mut server), 6, "one S frame");
    assert_eq!(server.unacknowledged_count(), 0);
    assert!(std::iter::from_fn(|| server.poll_event())
        .any(|event| event == SessionEvent::Acknowledged { count: 3 }));
    // Already acknowledged: nothing more.
    client.acknowledge_received();
    assert_eq!(pump(&mut client, &mut server), 0);
}

#[tokio::test]
async fn interrogation_and_clock_sync_on_start() {
    init_logs();
    let handler = Recorder::accepting();
    let server = start_server(server_config(), image(), handler.clone()).await;
    let mut config = client_config(server.local_addr());
    config.interrogate_on_start = true;
    config.clock_sync_on_start = true;
    let mut client = Client::start(config).await;
    let asdus = client
        .asdus_until(TypeId::C_IC_NA_1, Cause::ACTIVATION_TERMINATION, WAIT)
        .await;
    assert!(asdus
        .iter()
        .any(|asdu| asdu.type_id == TypeId::C_CS_NA_1 && asdu.cot.cause == Cause::ACTIVATION_CON));
    assert_eq!(
        asdus
            .iter()
            .filter(|asdu| asdu.cot.cause == Cause::INTERROGATED_BY_STATION)
            .count(),
        1
    );
    let synced = handler.clock_syncs.lock().unwrap().clone();
    assert_eq!(synced.len(), 1);
    let now = chrono::Utc::now().naive_utc();
    let delta = now - synced[0].to_naive().unwrap();
    assert!(delta.num_seconds().abs() < 5, "clock sync sent {delta} off");
}

#[tokio::test]
async fn without_reconnection_the_client_reports_that_it_gave_up() {
    init_logs();
    for count in [1, 2] {
        let mut addresses = Vec::new();
        for _ in 0..count {
            addresses.push(refusing_address().await.to_string());
        }
        let mut config = client_config(refusing_address().await);
        config.addresses = addresses;
        let (_handle, mut events) = spawn_client(config);
        match next_event(&mut events).await {
            ClientEvent::Disconnected { reason } => {
                assert!(reason.contains("cannot connect"), "{reason}")
            }
            other => panic!("unexpected {other:?}"),
        }
        assert!(within(WAIT, "the end", events.recv()).await.is_none());
    }
}

#[tokio::test]
async fn a_lagging_application_does_not_stall_requests() {
    init_logs();
    let server = start_server(server_config(), image(), Arc::new(ReadOnlyStation)).await;
    let mut config = client_config(server.local_addr());
    config.event_capacity = 16;
    config.command_timeout = Duration::from_millis(500);
    let mut client = Client::start(config).await;
    // 100 events that cannot share ASDUs (the cause alternates), none read for now.
    for value in 0..100 {
        let cause = if value % 2 == 0 {
            Cause::SPONTANEOUS
        } else {
            Cause::PERIODIC
        };
        server
            .update_with_cause(ioa(1), scaled(value), None, cause)
            .unwrap();
    }
    // Until the flow stops: the client passes 16 on, keeps as many, then stops reading,
    // and the server stops at k = 12 unacknowledged frames.
    within(WAIT, "the flow of events to stop", async {
        let mut last = usize::MAX;
        loop {
            let queued = server.stats().groups[0].queued;
            if queued == last && queued < 100 {
                return;
            }
            last = queued;
            tokio::time::sleep(Duration::from_millis(150)).await;
        }
    })
    .await;
    // A request still completes (answered, or timed out if the answer is behind what
    // the application has not read) instead of hanging.
    let result = within(
        WAIT,
        "a read while events pile up",
        client.handle.read(ioa(1)),
    )
    .await;
    match result {
        Ok(outcome) => assert!(outcome.positive),
        Err(error) => assert_eq!(error, ClientError::Timeout("the confirmation")),
    }
    // Nothing was lost, nothing reordered.
    let mut values = Vec::new();
    while values.len() < 100 {
        let asdu = client.next_asdu().await;
        if asdu.cot.cause == Cause::REQUEST {
            continue;
        }
        for object in asdu.objects {
            values.push(object.element);
        }
    }
    assert_eq!(values, (0..100).map(scaled).collect::<Vec<_>>());
}
