//! Availability under abuse: a client does not hammer a station that accepts and closes
//! at once; idle clients cannot hold every connection slot; a client put on standby by
//! someone else's STARTDT notices, says so and takes its connection back.

use std::net::{IpAddr, SocketAddr};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;

use iec60870::asdu::TypeId;
use iec60870::cs104::client::{spawn_client, ClientEvent};
use iec60870::cs104::server::{
    ProcessImage, ReadOnlyStation, RedundancyGroupConfig, RedundancyMode, ServerConfig,
    ServerHandle,
};
use iec60870::cs104::ApciConfig;

use crate::common::*;

fn localhost(last: u8) -> IpAddr {
    IpAddr::from([127, 0, 0, last])
}

fn image() -> ProcessImage {
    let mut image = ProcessImage::new();
    image
        .add_monitor(monitor(1, TypeId::M_ME_NB_1, 0, scaled(0)))
        .unwrap();
    image
}

#[tokio::test]
async fn a_station_that_accepts_and_closes_at_once_is_not_hammered() {
    init_logs();
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let address = listener.local_addr().unwrap();
    let accepted = Arc::new(AtomicUsize::new(0));
    let counter = Arc::clone(&accepted);
    let acceptor = tokio::spawn(async move {
        loop {
            if let Ok((stream, _)) = listener.accept().await {
                counter.fetch_add(1, Ordering::Relaxed);
                drop(stream);
            }
        }
    });
    let mut config = client_config(address);
    config.reconnect = true;
    // The defaults: 500 ms doubling up to 30 s, healthy after 10 s.
    let (client, _events) = spawn_client(config);
    tokio::time::sleep(Duration::from_secs(3)).await;
    client.close().await;
    acceptor.abort();
    // 0, 0.5, 1.5 s (then 3.5 s): the old client reconnected at once, thousands of times.
    let connects = accepted.load(Ordering::Relaxed);
    assert!((2..=4).contains(&connects), "{connects} connections in 3 s");
    // One warning, not one per attempt.
    let peer = address.to_string();
    assert_eq!(
        log_lines_with(&["connection ended at once", &peer]).len(),
        1,
        "{:#?}",
        log_lines_with(&[&peer])
    );
}

/// A server with 6 slots, 2 per address, 2 kept for the dispatch group (127.0.0.10), and
/// a STARTDT timeout of 500 ms for clients no group names.
async fn guarded_server() -> ServerHandle {
    let mut config: ServerConfig = server_config();
    config.listen = "0.0.0.0:0".parse().unwrap();
    config.max_connections = 6;
    config.max_connections_per_address = Some(2);
    config.reserved_per_group = 2;
    config.start_timeout = Some(Duration::from_millis(500));
    config.outstation.redundancy = RedundancyMode::GroupsByAddress(vec![
        RedundancyGroupConfig::new("dispatch", vec![localhost(10)]),
        RedundancyGroupConfig::catch_all("others"),
    ]);
    start_server(config, image(), Arc::new(ReadOnlyStation)).await
}

async fn connect_from(server: &ServerHandle, last: u8) -> RawPeer {
    let address: SocketAddr = (localhost(1), server.local_addr().port()).into();
    RawPeer::connect_with(address, Some(localhost(last)), ApciConfig::default()).await
}

#[tokio::test]
async fn idle_clients_cannot_take_the_slots_of_a_configured_control_centre() {
    init_logs();
    let server = guarded_server().await;
    // Idle clients that never start, from four addresses, three connections each.
    let mut idle = Vec::new();
    for last in 2..=5 {
        for _ in 0..3 {
            idle.push(connect_from(&server, last).await);
        }
    }
    // Only 4 of the 6 slots are open to them (2 are kept for dispatch), at most 2 each.
    eventually(WAIT, "the extra idle clients to be refused", || {
        server.stats().connections == 4 && server.stats().refused == 8
    })
    .await;
    // Dispatch still gets its main and its standby connection in.
    let mut main = connect_from(&server, 10).await;
    main.start().await;
    let mut standby = connect_from(&server, 10).await;
    wait_connections(&server, 6).await;
    // The idle clients are closed when their STARTDT timeout runs out; the standby of
    // the named group is not, though it never starts.
    for peer in &mut idle {
        if !peer.is_closed() {
            assert!(peer.wait_closed(WAIT).await, "an idle client kept its slot");
        }
    }
    wait_connections(&server, 2).await;
    standby.pump_for(Duration::from_millis(700)).await;
    assert!(!standby.is_closed());
    assert!(!log_lines_with(&["no STARTDT within 0.5 s"]).is_empty());
    // The refusals were logged once per kind, not once per connection.
    assert_eq!(
        log_lines_with(&[
            "connection refused",
            "connections from this address already"
        ])
        .len(),
        1
    );
    // A client that starts in time keeps its slot.
    let mut prompt = connect_from(&server, 6).await;
    prompt.start().await;
    prompt.pump_for(Duration::from_millis(700)).await;
    assert!(!prompt.is_closed());
    main.pump_for(Duration::from_millis(10)).await;
}

#[tokio::test]
async fn a_client_put_on_standby_by_another_start_notices_and_takes_its_connection_back() {
    init_logs();
    let mut config = server_config();
    config.outstation.redundancy = RedundancyMode::SingleGroup;
    let server = start_server(config, image(), Arc::new(ReadOnlyStation)).await;
    let mut client_config = client_config(server.local_addr());
    client_config.reconnect = true;
    client_config.reconnect_delay = Duration::from_millis(50);
    client_config.standby_probe = Some(Duration::from_millis(300));
    client_config.command_timeout = Duration::from_millis(500);
    let mut client = Client::start(client_config).await;
    server.update(ioa(1), scaled(1), None).unwrap();
    assert_eq!(client.next_asdu().await.objects[0].ioa, ioa(1));

    // Someone on the same group starts data transfer: the data go to them.
    let mut intruder = RawPeer::connect(server.local_addr()).await;
    intruder.start().await;
    server.update(ioa(1), scaled(2), None).unwrap();
    intruder.expect_asdu().await;

    // The client notices within probe + timeout, reports the link lost (so its users
    // show values invalid, not stale values as live), connects again and takes over.
    let reason = within(WAIT, "the client to notice its standby", async {
        loop {
            match client.events.recv().await {
                Some(ClientEvent::Disconnected { reason }) => return reason,
                Some(_) => {}
                None => panic!("client stopped"),
            }
        }
    })
    .await;
    assert!(
        reason.contains("standby probe") || reason.contains("closed by the server"),
        "{reason}"
    );
    client.wait_started().await;
    server.update(ioa(1), scaled(3), None).unwrap();
    let asdu = within(WAIT, "data after the take-back", async {
        loop {
            let asdu = client.next_asdu().await;
            if asdu.type_id == TypeId::M_ME_NB_1 {
                return asdu;
            }
        }
    })
    .await;
    assert_eq!(asdu.objects[0].ioa, ioa(1));
}

#[tokio::test]
async fn a_quiet_started_connection_is_probed_and_stays() {
    init_logs();
    let server = start_server(server_config(), image(), Arc::new(ReadOnlyStation)).await;
    let mut config = client_config(server.local_addr());
    config.standby_probe = Some(Duration::from_millis(100));
    config.command_timeout = Duration::from_millis(500);
    let mut client = Client::start(config).await;
    // Several probe rounds, answered by the station, none of them surfacing as data.
    let quiet = tokio::time::timeout(Duration::from_millis(1000), async {
        client.events.recv().await
    })
    .await;
    assert!(quiet.is_err(), "unexpected {quiet:?}");
    server.update(ioa(1), scaled(4), None).unwrap();
    assert_eq!(client.next_asdu().await.objects[0].ioa, ioa(1));
}
