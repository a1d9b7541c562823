//! Clock synchronisation from the dispatch side reaches every node, and the time tags of
//! the boards' events follow it.

use std::time::Duration;

use iec60870::asdu::TimeTag;
use iec60870::time::TimeZonePolicy;
use station::runtime::StoreChoice;

use crate::harness::*;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn dispatch_clock_sync_sets_every_node_and_the_boards_time_tags() {
    let runtime = start(vsetin_project(), StoreChoice::Disabled).await;
    runtime.advance(Duration::from_secs(1)).await.unwrap();
    links_up(&runtime).await;
    let rdrt = runtime
        .node("RDRT")
        .unwrap()
        .server
        .as_ref()
        .unwrap()
        .local_addr();
    let dispatch = Dispatch::connect(rdrt, 1, false).await;

    // The dispatch's clock is 1 h 23 min ahead of the station's.
    let zone = TimeZonePolicy::Zone(chrono_tz::Europe::Prague);
    let station_now = runtime.node("RH2").unwrap().points.clock().now();
    let dispatch_time = station_now + chrono::Duration::minutes(83);
    let outcome = dispatch
        .client
        .clock_sync(zone.to_cp56(dispatch_time))
        .await
        .unwrap();
    assert!(outcome.positive);
    for node in ["RDRT", "RH1.1", "RH2", "RZS1", "RDA", "ROV07"] {
        let clock = runtime.node(node).unwrap().points.clock();
        let skew = (clock.now() - dispatch_time).num_milliseconds().abs();
        assert!(skew <= 1, "{node} is {skew} ms off");
    }
    // An event at the board carries the synchronised time.
    runtime.operate("surge-arrester RH2_FV1").await.unwrap();
    advance_until(
        &runtime,
        Duration::from_millis(20),
        "the event arrives",
        || dispatch.last(295).and_then(|r| r.on()) == Some(true),
    )
    .await;
    let Some(TimeTag::Cp56(tag)) = dispatch.last(295).unwrap().time else {
        panic!("no time tag")
    };
    let tagged = zone.from_cp56(&tag).unwrap().time;
    let after_sync = (tagged - dispatch_time).num_milliseconds();
    assert!(
        (0..=100).contains(&after_sync),
        "tag {tagged} vs sync {dispatch_time}"
    );
    runtime.shutdown().await;
}
