//! Spontaneous events and the event buffer of a redundancy group.

use std::sync::Arc;
use std::time::Duration;

use iec60870::asdu::{Cause, Cp56Time2a, Element, TimeTag, TypeId};
use iec60870::cs104::server::{OverflowPolicy, ProcessImage, ReadOnlyStation};

use crate::common::*;

fn event_image() -> ProcessImage {
    let mut image = ProcessImage::new();
    image
        .add_monitor(monitor(1, TypeId::M_SP_TB_1, 0, single(false)))
        .unwrap();
    image
        .add_monitor(monitor(2, TypeId::M_ME_NB_1, 0, scaled(0)))
        .unwrap();
    image
        .add_monitor(monitor(3, TypeId::M_ME_TE_1, 0, scaled(0)))
        .unwrap();
    image
}

fn time(minute: u8, millisecond: u16) -> Cp56Time2a {
    Cp56Time2a::new(26, 3, 14, 9, minute, millisecond).unwrap()
}

#[tokio::test]
async fn update_is_sent_spontaneously_with_its_time_tag() {
    init_logs();
    let server = start_server(server_config(), event_image(), Arc::new(ReadOnlyStation)).await;
    let mut client = Client::connect(server.local_addr()).await;

    let tag = time(7, 31_415).with_summer_time(true);
    server.update(ioa(1), single(true), Some(tag)).unwrap();
    let asdu = client.next_asdu().await;
    assert_eq!(asdu.type_id, TypeId::M_SP_TB_1);
    assert_eq!(asdu.cot.cause, Cause::SPONTANEOUS);
    assert!(!asdu.cot.negative && !asdu.cot.test);
    assert_eq!(asdu.common_address, ca());
    assert_eq!(asdu.objects.len(), 1);
    assert_eq!(asdu.objects[0].ioa, ioa(1));
    assert_eq!(asdu.objects[0].element, single(true));
    assert_eq!(asdu.objects[0].time, Some(TimeTag::Cp56(tag)));

    // Without a time, a time-tagged type is stamped with the server's clock (UTC).
    let before = chrono::Utc::now().naive_utc();
    server.update(ioa(3), scaled(42), None).unwrap();
    let asdu = client.next_asdu().await;
    let after = chrono::Utc::now().naive_utc();
    assert_eq!(asdu.type_id, TypeId::M_ME_TE_1);
    let stamped = asdu.objects[0]
        .time
        .as_ref()
        .and_then(TimeTag::as_cp56)
        .copied();
    let stamped = stamped.expect("a CP56 time tag").to_naive().unwrap();
    let slack = chrono::Duration::milliseconds(5);
    assert!(
        stamped >= before - slack && stamped <= after + slack,
        "{stamped} not within {before}..{after}"
    );

    // An untagged type is sent without time; the image holds the newest value.
    server.update(ioa(2), scaled(-9), Some(tag)).unwrap();
    let asdu = client.next_asdu().await;
    assert_eq!(asdu.type_id, TypeId::M_ME_NB_1);
    assert_eq!(asdu.objects[0].time, None);
    assert_eq!(server.get(ioa(2)).unwrap().element, scaled(-9));

    // Another cause is kept.
    server
        .update_with_cause(ioa(2), scaled(5), None, Cause::RETURN_REMOTE)
        .unwrap();
    assert_eq!(client.next_asdu().await.cot.cause, Cause::RETURN_REMOTE);

    // Unknown points and mistyped values are refused.
    assert!(server.update(ioa(999), scaled(1), None).is_err());
    assert!(server.update(ioa(2), single(true), None).is_err());
}

#[tokio::test]
async fn ten_thousand_rapid_updates_arrive_in_order() {
    init_logs();
    let server = start_server(server_config(), event_image(), Arc::new(ReadOnlyStation)).await;
    let mut client = Client::connect(server.local_addr()).await;

    for value in 0..10_000i16 {
        // Alternate two points so that order across points is checked too.
        let address = if value % 2 == 0 { 2 } else { 3 };
        server.update(ioa(address), scaled(value), None).unwrap();
    }
    let objects = within(
        Duration::from_secs(20),
        "10 000 events",
        client.spontaneous_objects(10_000),
    )
    .await;
    for (index, (type_id, object)) in objects.iter().enumerate() {
        let expected_address = if index % 2 == 0 { 2 } else { 3 };
        assert_eq!(object.ioa.get(), expected_address, "event {index}");
        assert_eq!(object.element, scaled(index as i16), "event {index}");
        let expected_type = if expected_address == 2 {
            TypeId::M_ME_NB_1
        } else {
            TypeId::M_ME_TE_1
        };
        assert_eq!(*type_id, expected_type);
    }
    assert!(client
        .try_next_asdu(Duration::from_millis(100))
        .await
        .is_none());
}

#[tokio::test]
async fn events_buffered_while_nobody_is_connected_are_delivered_in_order() {
    init_logs();
    let server = start_server(server_config(), event_image(), Arc::new(ReadOnlyStation)).await;
    let tags: Vec<Cp56Time2a> = (0..20).map(|n| time(n, 1000 * u16::from(n))).collect();
    for (n, tag) in tags.iter().enumerate() {
        server
            .update(ioa(1), single(n % 2 == 0), Some(*tag))
            .unwrap();
    }
    assert_eq!(server.stats().groups[0].queued, 20);

    let mut client = Client::connect(server.local_addr()).await;
    let objects = client.spontaneous_objects(20).await;
    for (n, (type_id, object)) in objects.iter().enumerate() {
        assert_eq!(*type_id, TypeId::M_SP_TB_1);
        assert_eq!(object.element, single(n % 2 == 0));
        assert_eq!(object.time, Some(TimeTag::Cp56(tags[n])), "event {n}");
    }
    eventually(WAIT, "the buffer to empty", || {
        let group = &server.stats().groups[0];
        group.queued == 0 && group.retransmit_queued == 0
    })
    .await;
}

#[tokio::test]
async fn a_connected_but_stopped_client_does_not_drain_the_buffer() {
    init_logs();
    let server = start_server(server_config(), event_image(), Arc::new(ReadOnlyStation)).await;
    let mut peer = RawPeer::connect(server.local_addr()).await;
    wait_connections(&server, 1).await;
    server.update(ioa(2), scaled(1), None).unwrap();
    server.update(ioa(2), scaled(2), None).unwrap();
    assert!(peer.next_asdu(Duration::from_millis(200)).await.is_none());
    assert_eq!(server.stats().groups[0].queued, 2);
    peer.start().await;
    let asdu = peer.expect_asdu().await;
    assert_eq!(
        asdu.objects
            .iter()
            .map(|o| o.element.clone())
            .collect::<Vec<_>>(),
        vec![scaled(1), scaled(2)]
    );
}

#[tokio::test]
async fn overflow_drop_oldest_keeps_the_newest_and_counts_the_dropped() {
    init_logs();
    let mut config = server_config();
    config.outstation.event_buffer_capacity = 10;
    config.outstation.overflow_policy = OverflowPolicy::DropOldest;
    let server = start_server(config, event_image(), Arc::new(ReadOnlyStation)).await;
    for value in 0..25 {
        server.update(ioa(2), scaled(value), None).unwrap();
    }
    let stats = server.stats();
    assert_eq!(stats.groups[0].queued, 10);
    assert_eq!(stats.groups[0].dropped, 15);

    let mut client = Client::connect(server.local_addr()).await;
    let values: Vec<Element> = client
        .spontaneous_objects(10)
        .await
        .into_iter()
        .map(|(_, object)| object.element)
        .collect();
    assert_eq!(values, (15..25).map(scaled).collect::<Vec<_>>());
    assert!(client
        .try_next_asdu(Duration::from_millis(100))
        .await
        .is_none());
    assert_eq!(server.stats().groups[0].dropped, 15);
}

#[tokio::test]
async fn overflow_drop_newest_keeps_the_oldest() {
    init_logs();
    let mut config = server_config();
    config.outstation.event_buffer_capacity = 10;
    config.outstation.overflow_policy = OverflowPolicy::DropNewest;
    let server = start_server(config, event_image(), Arc::new(ReadOnlyStation)).await;
    for value in 0..25 {
        server.update(ioa(2), scaled(value), None).unwrap();
    }
    assert_eq!(server.stats().groups[0].dropped, 15);
    let mut client = Client::connect(server.local_addr()).await;
    let values: Vec<Element> = client
        .spontaneous_objects(10)
        .await
        .into_iter()
        .map(|(_, object)| object.element)
        .collect();
    assert_eq!(values, (0..10).map(scaled).collect::<Vec<_>>());
}

#[tokio::test]
async fn end_of_initialisation_goes_to_the_first_started_connection() {
    init_logs();
    let mut config = server_config();
    config.outstation.send_end_of_initialisation = true;
    let server = start_server(config, event_image(), Arc::new(ReadOnlyStation)).await;
    let mut client = Client::connect(server.local_addr()).await;
    let asdu = client.next_asdu().await;
    assert_eq!(asdu.type_id, TypeId::M_EI_NA_1);
    assert_eq!(asdu.cot.cause, Cause::INITIALISED);
    client.handle.close().await;
    wait_connections(&server, 0).await;
    // Not again to the next connection.
    let mut client = Client::connect(server.local_addr()).await;
    assert!(client
        .try_next_asdu(Duration::from_millis(200))
        .await
        .is_none());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn concurrent_updates_of_one_point_end_where_the_image_ends() {
    init_logs();
    let server = start_server(server_config(), event_image(), Arc::new(ReadOnlyStation)).await;
    let mut client = Client::connect(server.local_addr()).await;
    for round in 0..5 {
        let writers: Vec<_> = (0..2i16)
            .map(|writer| {
                let server = server.clone();
                std::thread::spawn(move || {
                    for value in 0..1_000i16 {
                        server
                            .update(ioa(2), scaled(value * 2 + writer), None)
                            .unwrap();
                    }
                })
            })
            .collect();
        for writer in writers {
            writer.join().unwrap();
        }
        let objects = client.spontaneous_objects(2_000).await;
        let last = objects.last().unwrap().1.element.clone();
        assert_eq!(last, server.get(ioa(2)).unwrap().element, "round {round}");
        // Each writer's own updates stay in order.
        for writer in 0..2i16 {
            let mine: Vec<i16> = objects
                .iter()
                .filter_map(|(_, object)| match object.element {
                    iec60870::asdu::Element::Scaled { value, .. } if value % 2 == writer => {
                        Some(value)
                    }
                    _ => None,
                })
                .collect();
            assert!(mine.windows(2).all(|pair| pair[0] < pair[1]));
            assert_eq!(mine.len(), 1_000);
        }
    }
}
