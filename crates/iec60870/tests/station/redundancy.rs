//! Redundancy groups: standby connections, switch-over with retransmission, groups chosen
//! by client address, the allow-list and the connection cap.

use std::net::IpAddr;
use std::sync::Arc;
use std::time::Duration;

use iec60870::asdu::{Element, TypeId};
use iec60870::cs104::server::{
    ProcessImage, ReadOnlyStation, RedundancyGroupConfig, RedundancyMode,
};
use iec60870::cs104::ApciConfig;

use crate::common::*;

const QUIET: Duration = Duration::from_millis(300);
const STARTDT_ACT: [u8; 6] = [0x68, 0x04, 0x07, 0x00, 0x00, 0x00];

pub(crate) fn image() -> ProcessImage {
    let mut image = ProcessImage::new();
    image
        .add_monitor(monitor(1, TypeId::M_ME_NB_1, 0, scaled(0)))
        .unwrap();
    image
}

pub(crate) fn localhost(last: u8) -> IpAddr {
    IpAddr::from([127, 0, 0, last])
}

/// The scaled values of the objects of an ASDU.
fn values(asdu: &iec60870::asdu::Asdu) -> Vec<i16> {
    asdu.objects
        .iter()
        .map(|object| match object.element {
            Element::Scaled { value, .. } => value,
            ref other => panic!("unexpected {other:?}"),
        })
        .collect()
}

/// Values received by a peer until `count` have arrived.
async fn receive_values(peer: &mut RawPeer, count: usize) -> Vec<i16> {
    let mut got = Vec::new();
    while got.len() < count {
        got.extend(values(&peer.expect_asdu().await));
    }
    got
}

#[tokio::test]
async fn standby_gets_nothing_and_takes_over_with_retransmission() {
    init_logs();
    let server = start_server(server_config(), image(), Arc::new(ReadOnlyStation)).await;
    let address = server.local_addr();

    // A: started, never acknowledges.
    let mut a = RawPeer::connect_with(address, None, RawPeer::lazy_apci()).await;
    a.start().await;
    for value in 1..=3 {
        server.update(ioa(1), scaled(value), None).unwrap();
        assert_eq!(values(&a.expect_asdu().await), vec![value]);
    }
    // B: connected, not started: a standby connection gets no data.
    let mut b = RawPeer::connect(address).await;
    wait_connections(&server, 2).await;
    server.update(ioa(1), scaled(4), None).unwrap();
    assert_eq!(values(&a.expect_asdu().await), vec![4]);
    assert!(b.next_asdu(QUIET).await.is_none(), "standby got data");
    assert_eq!(server.stats().groups[0].retransmit_queued, 4);

    // B starts: it takes over, and gets first what A never acknowledged.
    b.start().await;
    for value in 5..=6 {
        server.update(ioa(1), scaled(value), None).unwrap();
    }
    assert_eq!(receive_values(&mut b, 6).await, vec![1, 2, 3, 4, 5, 6]);
    // A gets nothing more, and no STOPDT either (nor anything else unexpected).
    a.pump_for(QUIET).await;
    assert!(
        a.next_asdu(Duration::ZERO).await.is_none(),
        "A still gets data"
    );
    assert_eq!(a.unexpected_frames(), 0);
    assert!(!a.is_closed());
    assert!(server.stats().groups[0].has_active);

    // A stays usable as a standby and can take over again. (Its session still believes
    // it is started, as the server deactivated it silently: write the STARTDT act by hand.)
    a.write_raw(&STARTDT_ACT).await;
    a.pump_for(Duration::from_millis(50)).await;
    server.update(ioa(1), scaled(7), None).unwrap();
    // B acknowledged 1..=6 (w = 8 or t2) before losing the group? Not necessarily: what B
    // left unacknowledged comes back to A first, then 7.
    let mut got = receive_values(&mut a, 1).await;
    while got.last() != Some(&7) {
        got.extend(values(&a.expect_asdu().await));
    }
    assert!(got.windows(2).all(|pair| pair[0] < pair[1]), "{got:?}");
    assert!(b.next_asdu(QUIET).await.is_none());
    assert_eq!(b.unexpected_frames(), 0);
}

/// A started connection put on standby by another's STARTDT takes the group's data back
/// when that connection stops data transfer or goes away (its controlling station never
/// stopped, so it still waits for data); it got nothing again before.
#[tokio::test]
async fn a_connection_on_standby_takes_the_data_back_when_the_other_goes() {
    init_logs();
    let server = start_server(server_config(), image(), Arc::new(ReadOnlyStation)).await;
    let address = server.local_addr();
    // Values up to `last`: what the previous connection left unacknowledged comes first.
    async fn until(peer: &mut RawPeer, last: i16) -> Vec<i16> {
        let mut got = Vec::new();
        while got.last() != Some(&last) {
            got.extend(values(&peer.expect_asdu().await));
        }
        got
    }
    let mut a = RawPeer::connect(address).await;
    a.start().await;
    server.update(ioa(1), scaled(1), None).unwrap();
    assert_eq!(until(&mut a, 1).await, vec![1]);

    // B takes over: A is on standby.
    let mut b = RawPeer::connect(address).await;
    b.start().await;
    server.update(ioa(1), scaled(2), None).unwrap();
    until(&mut b, 2).await;
    assert!(a.next_asdu(QUIET).await.is_none(), "A on standby got data");

    // B stops data transfer: A gets the data again, without a STARTDT of its own.
    b.stop().await;
    server.update(ioa(1), scaled(3), None).unwrap();
    until(&mut a, 3).await;
    assert!(b.next_asdu(QUIET).await.is_none());

    // C takes over and then goes away (connection closed): A again.
    let mut c = RawPeer::connect(address).await;
    c.start().await;
    server.update(ioa(1), scaled(4), None).unwrap();
    until(&mut c, 4).await;
    drop(c);
    wait_connections(&server, 2).await;
    server.update(ioa(1), scaled(5), None).unwrap();
    until(&mut a, 5).await;
    assert_eq!(a.unexpected_frames(), 0);
}

#[tokio::test]
async fn switch_over_after_acknowledgement_does_not_repeat_events() {
    init_logs();
    let server = start_server(server_config(), image(), Arc::new(ReadOnlyStation)).await;
    let address = server.local_addr();
    let mut eager = ApciConfig::default();
    eager.w = 1;
    let mut a = RawPeer::connect_with(address, None, eager).await;
    a.start().await;
    for value in 1..=3 {
        server.update(ioa(1), scaled(value), None).unwrap();
    }
    assert_eq!(receive_values(&mut a, 3).await, vec![1, 2, 3]);
    a.flush().await;
    eventually(WAIT, "A's acknowledgement", || {
        server.stats().groups[0].retransmit_queued == 0
    })
    .await;

    let mut b = RawPeer::connect(address).await;
    b.start().await;
    server.update(ioa(1), scaled(4), None).unwrap();
    assert_eq!(values(&b.expect_asdu().await), vec![4]);
    assert!(a.next_asdu(QUIET).await.is_none());
}

#[tokio::test]
async fn stopdt_releases_the_group_and_events_wait_for_the_next_start() {
    init_logs();
    let server = start_server(server_config(), image(), Arc::new(ReadOnlyStation)).await;
    let mut a = RawPeer::connect(server.local_addr()).await;
    a.start().await;
    server.update(ioa(1), scaled(1), None).unwrap();
    assert_eq!(values(&a.expect_asdu().await), vec![1]);
    a.stop().await;
    eventually(WAIT, "the group to be released", || {
        !server.stats().groups[0].has_active
    })
    .await;
    server.update(ioa(1), scaled(2), None).unwrap();
    assert!(a.next_asdu(QUIET).await.is_none());
    assert_eq!(server.stats().groups[0].queued, 1);
    a.start().await;
    assert_eq!(values(&a.expect_asdu().await), vec![2]);
}

#[tokio::test]
async fn a_lost_connection_leaves_its_unacknowledged_events_to_the_next() {
    init_logs();
    let server = start_server(server_config(), image(), Arc::new(ReadOnlyStation)).await;
    let mut a = RawPeer::connect_with(server.local_addr(), None, RawPeer::lazy_apci()).await;
    a.start().await;
    for value in 1..=2 {
        server.update(ioa(1), scaled(value), None).unwrap();
    }
    assert_eq!(receive_values(&mut a, 2).await, vec![1, 2]);
    drop(a);
    wait_connections(&server, 0).await;
    server.update(ioa(1), scaled(3), None).unwrap();
    let mut b = RawPeer::connect(server.local_addr()).await;
    b.start().await;
    assert_eq!(receive_values(&mut b, 3).await, vec![1, 2, 3]);
}

#[tokio::test]
async fn groups_chosen_by_client_address_each_get_every_event() {
    init_logs();
    let mut config = server_config();
    config.listen = "0.0.0.0:0".parse().unwrap();
    config.outstation.redundancy = RedundancyMode::GroupsByAddress(vec![
        RedundancyGroupConfig::new("one", vec![localhost(1)]),
        RedundancyGroupConfig::new("two", vec![localhost(2)]),
    ]);
    let server = start_server(config, image(), Arc::new(ReadOnlyStation)).await;
    let address = (localhost(1), server.local_addr().port()).into();
    let mut one = RawPeer::connect_with(address, Some(localhost(1)), ApciConfig::default()).await;
    let mut two = RawPeer::connect_with(address, Some(localhost(2)), ApciConfig::default()).await;
    one.start().await;
    two.start().await;
    for value in 1..=5 {
        server.update(ioa(1), scaled(value), None).unwrap();
    }
    assert_eq!(receive_values(&mut one, 5).await, vec![1, 2, 3, 4, 5]);
    assert_eq!(receive_values(&mut two, 5).await, vec![1, 2, 3, 4, 5]);
    let stats = server.stats();
    assert_eq!(stats.groups.len(), 2);
    assert!(stats.groups.iter().all(|group| group.has_active));

    // A client named by no group, with no catch-all group, is refused.
    let mut three = RawPeer::connect_with(address, Some(localhost(3)), ApciConfig::default()).await;
    assert!(three.wait_closed(WAIT).await);
    assert_eq!(server.stats().refused, 1);
}

#[tokio::test]
async fn allow_list_refuses_an_unlisted_client() {
    init_logs();
    let mut config = server_config();
    config.listen = "0.0.0.0:0".parse().unwrap();
    config.allowed_clients = vec![localhost(1)];
    let server = start_server(config, image(), Arc::new(ReadOnlyStation)).await;
    let address = (localhost(1), server.local_addr().port()).into();

    let mut intruder =
        RawPeer::connect_with(address, Some(localhost(2)), ApciConfig::default()).await;
    assert!(
        intruder.wait_closed(WAIT).await,
        "unlisted client not refused"
    );
    let mut friend =
        RawPeer::connect_with(address, Some(localhost(1)), ApciConfig::default()).await;
    friend.start().await;
    let stats = server.stats();
    assert_eq!(
        (stats.refused, stats.accepted, stats.connections),
        (1, 1, 1)
    );
}

#[tokio::test]
async fn connection_cap_refuses_the_extra_client() {
    init_logs();
    let mut config = server_config();
    config.max_connections = 2;
    let server = start_server(config, image(), Arc::new(ReadOnlyStation)).await;
    let mut first = RawPeer::connect(server.local_addr()).await;
    let _second = RawPeer::connect(server.local_addr()).await;
    wait_connections(&server, 2).await;
    let mut third = RawPeer::connect(server.local_addr()).await;
    assert!(third.wait_closed(WAIT).await, "extra client not refused");
    assert_eq!(server.stats().refused, 1);
    first.start().await;
    // A freed slot is usable again.
    drop(first);
    wait_connections(&server, 1).await;
    let mut fourth = RawPeer::connect(server.local_addr()).await;
    fourth.start().await;
    assert_eq!(server.stats().refused, 1);
    assert_eq!(server.stats().accepted, 3);
}

#[tokio::test]
async fn a_standby_connection_is_not_closed_for_frames_handed_over() {
    init_logs();
    let mut config = server_config();
    config.apci = fast_apci();
    let server = start_server(config, image(), Arc::new(ReadOnlyStation)).await;
    // A never acknowledges (t1 on the server is 1 s); B acknowledges promptly.
    let mut a = RawPeer::connect_with(server.local_addr(), None, RawPeer::lazy_apci()).await;
    a.start().await;
    server.update(ioa(1), scaled(1), None).unwrap();
    assert_eq!(values(&a.expect_asdu().await), vec![1]);
    let mut b = RawPeer::connect_with(server.local_addr(), None, fast_apci()).await;
    b.start().await;
    assert_eq!(receive_values(&mut b, 1).await, vec![1]);
    // Well past t1: A, now standby, answers the server's test frames and stays connected.
    let long = Duration::from_millis(1_500);
    tokio::join!(a.pump_for(long), b.pump_for(long));
    assert!(!a.is_closed(), "the standby connection was closed");
    assert!(!b.is_closed());
    assert_eq!(server.stats().connections, 2);
}
