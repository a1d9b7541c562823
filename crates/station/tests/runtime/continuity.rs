//! No event lost: an upper link cut for ten minutes of plant time, and a switch-over
//! between two dispatch connections of one redundancy group.

use std::time::Duration;

use iec60870::asdu::{CommonAddress, Element, TimeTag};
use iec60870::cs104::client::{spawn_client, ClientConfig, ClientEvent};
use iec60870::time::TimeZonePolicy;
use station::runtime::StoreChoice;
use station::store::{EventQuery, Order};

use crate::harness::*;

/// (value, time tag in ms since the epoch) of a single point received with a CP56 tag.
fn value_and_time(r: &Received) -> (bool, i64) {
    let Some(TimeTag::Cp56(tag)) = r.time else {
        panic!("no CP56 time tag: {r:?}")
    };
    let zone = TimeZonePolicy::Zone(chrono_tz::Europe::Prague);
    let time = zone.from_cp56(&tag).unwrap().time.timestamp_millis();
    (r.on().unwrap(), time)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_link_cut_for_ten_minutes_loses_no_event_and_keeps_their_time_tags() {
    let runtime = start(vsetin_project(), StoreChoice::Url("sqlite::memory:".into())).await;
    runtime.advance(Duration::from_secs(1)).await.unwrap();
    links_up(&runtime).await;
    let dispatch = Dispatch::connect(rdrt_address(&runtime), 1, true).await;
    // RH2's value known (valid) at dispatch first, so that the IV below is the cut's.
    eventually("RH2's value valid at dispatch", || {
        dispatch.last(282).is_some_and(|r| !r.invalid())
    })
    .await;

    // The cable between RH1.1 and the RH2 board is pulled.
    runtime.operate("link-cut RH1.1/RH2").await.unwrap();
    let link = runtime.link("RH1.1", "RH2").unwrap().clone();
    eventually("the link is down", || !link.is_up()).await;
    eventually("dispatch sees RH2's points invalid", || {
        dispatch.last(282).is_some_and(|r| r.invalid())
    })
    .await;

    // Ten minutes of plant time: breaker FA1.1 trips and is reclosed every 30 s.
    for i in 0..20 {
        let operation = if i % 2 == 0 {
            "breaker-tripped RH2_FA1.1"
        } else {
            "clear breaker-tripped RH2_FA1.1"
        };
        runtime.operate(operation).await.unwrap();
        runtime.advance(Duration::from_secs(30)).await.unwrap();
    }
    // Nothing of it reached the dispatch while the link was down.
    assert!(dispatch.last(282).unwrap().invalid());

    runtime.operate("link-restore RH1.1/RH2").await.unwrap();
    eventually("the link is up again", || link.is_up()).await;
    // RH2 recorded each change with its own time: that is what must arrive.
    runtime.recorder().flush().await;
    let at_board = runtime
        .store()
        .unwrap()
        .query_events(
            &EventQuery::default()
                .with_node("RH2")
                .with_point("RH2_V1_FA1.1")
                .with_order(Order::OldestFirst)
                .with_limit(1000),
        )
        .await
        .unwrap();
    let expected: Vec<(bool, i64)> = at_board
        .items
        .iter()
        .filter(|e| e.received_time > runtime.clock().start() + chrono::Duration::milliseconds(500))
        .map(|e| {
            let station::store::PointValue::Bool(on) = e.value else {
                panic!("{e:?}")
            };
            (on, e.event_time().timestamp_millis())
        })
        .collect();
    assert_eq!(expected.len(), 20, "{expected:?}");
    eventually("every event reached the dispatch", || {
        let got: Vec<(bool, i64)> = dispatch
            .of(282)
            .iter()
            .filter(|r| r.cause == 3 && !r.invalid())
            .map(value_and_time)
            .collect();
        got.ends_with(&expected)
    })
    .await;
    // The events are in the order they happened, each with its original time tag.
    let got: Vec<(bool, i64)> = dispatch
        .of(282)
        .iter()
        .filter(|r| r.cause == 3 && !r.invalid())
        .map(value_and_time)
        .collect();
    let replay = &got[got.len() - 20..];
    assert!(replay.windows(2).all(|w| w[0].1 < w[1].1), "{replay:?}");
    assert!(replay.windows(2).all(|w| w[0].0 != w[1].0), "{replay:?}");
    runtime.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn two_dispatch_connections_switch_over_without_loss() {
    let runtime = start(vsetin_project(), StoreChoice::Disabled).await;
    runtime.advance(Duration::from_secs(1)).await.unwrap();
    links_up(&runtime).await;
    let address = rdrt_address(&runtime);

    // Dispatch A: started, receives.
    let active = Dispatch::connect(address, 1, false).await;
    // Dispatch B: connected in the same redundancy group, on standby.
    let mut config = ClientConfig::new(address.to_string(), CommonAddress::new(1));
    config.start_on_connect = false;
    let (standby, mut standby_events) = spawn_client(config);
    let standby_log = std::sync::Arc::new(std::sync::Mutex::new(Vec::<(u32, bool)>::new()));
    {
        let log = std::sync::Arc::clone(&standby_log);
        tokio::spawn(async move {
            while let Some(event) = standby_events.recv().await {
                if let ClientEvent::Asdu(asdu) = event {
                    for object in &asdu.objects {
                        if let Element::SinglePoint { on, .. } = object.element {
                            log.lock().unwrap().push((object.ioa.get(), on));
                        }
                    }
                }
            }
        });
    }
    eventually("two connections", || {
        runtime
            .node("RDRT")
            .unwrap()
            .server
            .as_ref()
            .unwrap()
            .stats()
            .connections
            == 2
    })
    .await;

    // Events while A is active: B gets nothing.
    let mut sequence = Vec::new();
    for i in 0..10 {
        let on = i % 2 == 1;
        let operation = if on {
            "clear breaker-tripped RH2_FA1.2"
        } else {
            "breaker-tripped RH2_FA1.2"
        };
        runtime.operate(operation).await.unwrap();
        runtime.advance(Duration::from_secs(1)).await.unwrap();
        sequence.push(on);
    }
    eventually("A has the ten events", || {
        dispatch_values(&active, 283).ends_with(&sequence)
    })
    .await;
    assert!(
        standby_log.lock().unwrap().is_empty(),
        "the standby got data"
    );

    // A's link dies; B takes over; events continue meanwhile.
    active.client.close().await;
    let mut after = Vec::new();
    for i in 0..10 {
        let on = i % 2 == 1;
        let operation = if on {
            "clear breaker-tripped RH2_FA1.2"
        } else {
            "breaker-tripped RH2_FA1.2"
        };
        runtime.operate(operation).await.unwrap();
        runtime.advance(Duration::from_secs(1)).await.unwrap();
        after.push(on);
        if i == 4 {
            standby.start_data_transfer().await.unwrap();
        }
    }
    eventually("B has every event after the switch-over, in order", || {
        let got: Vec<bool> = standby_log
            .lock()
            .unwrap()
            .iter()
            .filter(|(ioa, _)| *ioa == 283)
            .map(|(_, on)| *on)
            .collect();
        got == after
    })
    .await;
    standby.close().await;
    runtime.shutdown().await;
}

fn dispatch_values(dispatch: &Dispatch, ioa: u32) -> Vec<bool> {
    dispatch
        .of(ioa)
        .iter()
        .filter(|r| r.cause == 3 && !r.invalid())
        .filter_map(Received::on)
        .collect()
}
