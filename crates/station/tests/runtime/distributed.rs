//! One project spread over two processes (here: two runtimes with their own clocks in one
//! test process), as a real deployment spreads nodes over machines: the board RH2 runs
//! alone, the concentrator and the top controller elsewhere; values, commands and time
//! cross between them over IEC 104.

use std::time::Duration;

use station::runtime::{Pacing, Runtime, RuntimeOptions, StoreChoice};

use crate::harness::*;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn nodes_in_two_processes_work_as_one_station() {
    let project = vsetin_project();
    let options = |nodes: &[&str]| RuntimeOptions {
        nodes: nodes.iter().map(|n| (*n).to_owned()).collect(),
        pacing: Pacing::Manual,
        start: default_start(),
        store: StoreChoice::Disabled,
        device_kinds: station::device::DeviceKinds::builtin(),
    };
    let board = Runtime::start(project.clone(), options(&["RH2"]))
        .await
        .unwrap();
    let upper = Runtime::start(project, options(&["RH1.1", "RDRT"]))
        .await
        .unwrap();
    assert!(board.node("RDRT").is_none() && upper.node("RH2").is_none());
    board.advance(Duration::from_secs(1)).await.unwrap();
    upper.advance(Duration::from_secs(1)).await.unwrap();
    eventually("RH1.1 reaches RH2 in the other process", || {
        upper.link("RH1.1", "RH2").is_some_and(|l| l.is_up())
    })
    .await;
    // The other process's clock was set by C_CS_NA_1 over the link, not shared memory.
    let rh11 = upper.node("RH1.1").unwrap().points.clock().now();
    let rh2 = board.node("RH2").unwrap().points.clock().now();
    assert!(
        (rh11 - rh2).num_milliseconds().abs() < 2_000,
        "{rh11} vs {rh2}"
    );

    let rdrt = upper
        .node("RDRT")
        .unwrap()
        .server
        .as_ref()
        .unwrap()
        .local_addr();
    let dispatch = Dispatch::connect(rdrt, 1, true).await;
    eventually("RH2's values at dispatch", || {
        dispatch
            .last(291)
            .is_some_and(|r| r.on() == Some(true) && !r.invalid())
    })
    .await;
    assert!(dispatch.single_command(2021, true, false).await);
    advance_until(
        &board,
        Duration::from_millis(100),
        "QF1 opened in the other process",
        || dispatch.last(291).and_then(|r| r.on()) == Some(false),
    )
    .await;
    // The board's process goes away: the upper one reports the loss and invalidates.
    board.shutdown().await;
    eventually("RH2 invalid at dispatch", || {
        dispatch.last(291).is_some_and(|r| r.invalid())
            && dispatch.last(280).and_then(|r| r.on()) == Some(true)
    })
    .await;
    upper.shutdown().await;
}
