//! The three ways a server forms redundancy groups (as lib60870 names them): one group
//! for every client, a group per connection, groups by client address; with two and
//! three clients, the take-over warning, and no connection closed by another's STARTDT.

use std::sync::Arc;
use std::time::Duration;

use iec60870::asdu::{Cause, Element, TypeId};
use iec60870::cs104::server::{
    ReadOnlyStation, RedundancyGroupConfig, RedundancyMode, ServerHandle,
};
use iec60870::cs104::ApciConfig;

use crate::common::*;
use crate::redundancy::{image, localhost};

const QUIET: Duration = Duration::from_millis(300);

async fn server(mode: RedundancyMode) -> ServerHandle {
    let mut config = server_config();
    config.listen = "0.0.0.0:0".parse().unwrap();
    config.outstation.redundancy = mode;
    start_server(config, image(), Arc::new(ReadOnlyStation)).await
}

async fn peer_from(server: &ServerHandle, last: u8) -> RawPeer {
    let address = (localhost(1), server.local_addr().port()).into();
    RawPeer::connect_with(address, Some(localhost(last)), ApciConfig::default()).await
}

/// The next scaled value a peer receives spontaneously.
async fn next_value(peer: &mut RawPeer) -> i16 {
    let asdu = peer.expect_asdu().await;
    assert_eq!(asdu.cot.cause, Cause::SPONTANEOUS, "{asdu}");
    match asdu.objects[0].element {
        Element::Scaled { value, .. } => value,
        ref other => panic!("unexpected {other:?}"),
    }
}

/// Receives spontaneous values until `value` (values the previous connection of the
/// group left unacknowledged come first: a take-over retransmits them).
async fn receive_until(peer: &mut RawPeer, value: i16) {
    while next_value(peer).await != value {}
}

/// Whether a started peer still gets answers: a station interrogation is confirmed.
async fn answers_requests(peer: &mut RawPeer) -> bool {
    peer.send(&interrogation(20)).await;
    let answers = peer
        .asdus_until(TypeId::C_IC_NA_1, Cause::ACTIVATION_TERMINATION)
        .await;
    answers
        .iter()
        .any(|asdu| asdu.cot.cause == Cause::ACTIVATION_CON && !asdu.cot.negative)
}

#[tokio::test]
async fn connection_is_group_three_masters_each_get_every_event_and_none_is_disturbed() {
    init_logs();
    let server = server(RedundancyMode::ConnectionIsGroup).await;
    let mut peers = Vec::new();
    for last in [1, 1, 2] {
        let mut peer = peer_from(&server, last).await;
        peer.start().await;
        peers.push(peer);
    }
    wait_connections(&server, 3).await;
    for value in 1..=3 {
        server.update(ioa(1), scaled(value), None).unwrap();
        for peer in &mut peers {
            assert_eq!(next_value(peer).await, value);
        }
    }
    // The first master's next I frame is answered: nobody's STARTDT closed or muted it.
    for peer in &mut peers {
        assert!(answers_requests(peer).await);
        assert!(!peer.is_closed());
    }
    assert!(log_lines_with(&["take-over", &peers[0].local.to_string()]).is_empty());
    // Each connection has its own buffer; a closed connection's buffer goes with it.
    assert_eq!(server.stats().groups.len(), 3);
    drop(peers.pop());
    wait_connections(&server, 2).await;
    eventually(WAIT, "the closed connection's group to go", || {
        server.stats().groups.len() == 2
    })
    .await;
}

#[tokio::test]
async fn connection_is_group_buffers_for_a_connection_until_it_starts_but_not_before_it_came() {
    init_logs();
    let server = server(RedundancyMode::ConnectionIsGroup).await;
    server.update(ioa(1), scaled(1), None).unwrap();
    let mut peer = peer_from(&server, 1).await;
    wait_connections(&server, 1).await;
    server.update(ioa(1), scaled(2), None).unwrap();
    peer.start().await;
    assert_eq!(next_value(&mut peer).await, 2);
    assert!(peer.next_asdu(QUIET).await.is_none());
}

#[tokio::test]
async fn single_group_second_start_takes_over_with_a_warning_naming_both_peers() {
    init_logs();
    let server = server(RedundancyMode::SingleGroup).await;
    let mut first = peer_from(&server, 1).await;
    first.start().await;
    server.update(ioa(1), scaled(1), None).unwrap();
    assert_eq!(next_value(&mut first).await, 1);

    let mut second = peer_from(&server, 2).await;
    second.start().await;
    server.update(ioa(1), scaled(2), None).unwrap();
    receive_until(&mut second, 2).await;
    assert!(
        first.next_asdu(QUIET).await.is_none(),
        "the standby got data"
    );
    let (first_address, second_address) = (first.local.to_string(), second.local.to_string());
    eventually(WAIT, "the take-over warning", || {
        !log_lines_with(&["WARN", "take-over", &first_address, &second_address]).is_empty()
    })
    .await;

    // A third master takes it again; the second is told nothing and stays connected.
    let mut third = peer_from(&server, 3).await;
    third.start().await;
    server.update(ioa(1), scaled(3), None).unwrap();
    receive_until(&mut third, 3).await;
    assert!(second.next_asdu(QUIET).await.is_none());
    assert!(!second.is_closed() && !first.is_closed());
    let third_address = third.local.to_string();
    eventually(WAIT, "the second take-over warning", || {
        !log_lines_with(&["take-over", &second_address, &third_address]).is_empty()
    })
    .await;
}

#[tokio::test]
async fn groups_by_address_take_over_only_within_a_group() {
    init_logs();
    let server = server(RedundancyMode::GroupsByAddress(vec![
        RedundancyGroupConfig::new("centre-a", vec![localhost(1)]),
        RedundancyGroupConfig::new("centre-b", vec![localhost(2)]),
    ]))
    .await;
    let mut a_main = peer_from(&server, 1).await;
    a_main.start().await;
    let mut b = peer_from(&server, 2).await;
    b.start().await;
    server.update(ioa(1), scaled(1), None).unwrap();
    assert_eq!(next_value(&mut a_main).await, 1);
    assert_eq!(next_value(&mut b).await, 1);

    // Centre A's standby takes over A's data; centre B keeps its own.
    let mut a_standby = peer_from(&server, 1).await;
    a_standby.start().await;
    server.update(ioa(1), scaled(2), None).unwrap();
    receive_until(&mut a_standby, 2).await;
    assert_eq!(next_value(&mut b).await, 2);
    assert!(a_main.next_asdu(QUIET).await.is_none());
    assert!(answers_requests(&mut b).await);

    // A client no group names is refused.
    let mut stranger = peer_from(&server, 9).await;
    assert!(stranger.wait_closed(WAIT).await);
}

#[tokio::test]
async fn groups_by_address_without_groups_is_a_configuration_error() {
    let mut config = server_config();
    config.outstation.redundancy = RedundancyMode::GroupsByAddress(Vec::new());
    let error = iec60870::cs104::server::spawn_server(config, image(), Arc::new(ReadOnlyStation))
        .await
        .unwrap_err();
    assert!(error.to_string().contains("at least one group"), "{error}");
}
