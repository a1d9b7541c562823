//! Values up and commands down the controller hierarchy RH2 -> RH1.1 -> RDRT -> dispatch.

use std::time::Duration;

use station::runtime::StoreChoice;
use station::store::{CommandOutcome, CommandQuery, EventQuery};

use crate::harness::*;

const RDRT_CA: u16 = 1;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn dispatch_reads_the_board_through_two_concentrators() {
    let runtime = start(vsetin_project(), StoreChoice::Disabled).await;
    runtime.advance(Duration::from_secs(1)).await.unwrap();
    links_up(&runtime).await;
    let dispatch = Dispatch::connect(rdrt_address(&runtime), RDRT_CA, true).await;
    eventually("the GI answer holds IOA 298", || {
        dispatch.last(298).is_some()
    })
    .await;
    // The plant's steady state: FA breakers closed, voltage present, SA1 in remote,
    // no fuse or arrester fault, no emergency off. (Links that came up while the GI ran
    // may still bring values in: wait for them to settle.)
    let expected = [
        (281, true),
        (282, true),
        (290, true),
        (291, true),
        (292, false),
        (293, true),
        (294, false),
        (296, false),
        (298, true),
    ];
    let settled = || {
        expected.iter().all(|(ioa, value)| {
            dispatch
                .last(*ioa)
                .is_some_and(|r| r.on() == Some(*value) && !r.invalid())
        })
    };
    eventually("the board's values at dispatch", settled).await;
    // Nothing invalid was sent after the values arrived.
    for (ioa, value) in expected {
        let got = dispatch.last(ioa).unwrap();
        assert_eq!(got.on(), Some(value), "IOA {ioa}: {got:?}");
    }
    // The link status point of RDRT reports RH1.1 reachable.
    assert_eq!(dispatch.last(32).unwrap().on(), Some(false));
    runtime.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_command_opens_the_feeder_and_the_change_comes_back_up() {
    let runtime = start(vsetin_project(), StoreChoice::Url("sqlite::memory:".into())).await;
    runtime.advance(Duration::from_secs(1)).await.unwrap();
    links_up(&runtime).await;
    let dispatch = Dispatch::connect(rdrt_address(&runtime), RDRT_CA, true).await;
    // The GI may answer before RH1.1's link has brought RH2's values up: then the busbar
    // voltage comes invalid (IV, not yet known) and its value follows; wait for it.
    eventually("the busbar voltage live and valid at dispatch", || {
        dispatch
            .last(291)
            .is_some_and(|r| r.on() == Some(true) && !r.invalid())
    })
    .await;

    // Open QF1 (IOA 2021): confirmed through RH1.1 and RH2, executed by the LOGO! logic.
    assert!(dispatch.single_command(2021, true, false).await);
    advance_until(
        &runtime,
        Duration::from_millis(100),
        "busbar voltage lost",
        || dispatch.last(291).and_then(|r| r.on()) == Some(false),
    )
    .await;
    let feeder_closed = runtime
        .with_simulation(|sim| sim.plant().unwrap().bool("RH2_QF1_Zapnut").unwrap())
        .await
        .unwrap();
    assert!(!feeder_closed);

    // Close it again (the pulse of the first command has ended, so the edge is new).
    assert!(dispatch.single_command(2022, true, false).await);
    advance_until(
        &runtime,
        Duration::from_millis(100),
        "busbar voltage back",
        || dispatch.last(291).and_then(|r| r.on()) == Some(true),
    )
    .await;

    // The audit at every level names the peer and the outcome.
    runtime.recorder().flush().await;
    let store = runtime.store().unwrap();
    let commands = store
        .query_commands(&CommandQuery::default())
        .await
        .unwrap();
    let nodes: Vec<&str> = commands.items.iter().map(|c| c.node.as_str()).collect();
    for node in ["RDRT", "RH1.1", "RH2"] {
        assert_eq!(
            nodes.iter().filter(|n| **n == node).count(),
            2,
            "two commands audited at {node}: {nodes:?}"
        );
    }
    assert!(commands
        .items
        .iter()
        .all(|c| c.outcome == CommandOutcome::Executed));
    let events = store
        .query_events(&EventQuery::default().with_point_prefix("RH2_P1_KHU3"))
        .await
        .unwrap();
    assert!(events.items.len() >= 6, "{} events", events.items.len());
    runtime.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_board_in_local_mode_refuses_remote_commands() {
    let runtime = start(vsetin_project(), StoreChoice::Url("sqlite::memory:".into())).await;
    runtime.advance(Duration::from_secs(1)).await.unwrap();
    links_up(&runtime).await;
    let dispatch = Dispatch::connect(rdrt_address(&runtime), RDRT_CA, true).await;
    runtime.operate("selector RH2 local").await.unwrap();
    advance_until(
        &runtime,
        Duration::from_millis(100),
        "SA1 local reported",
        || dispatch.last(292).and_then(|r| r.on()) == Some(true),
    )
    .await;
    assert!(!dispatch.single_command(2021, true, false).await);
    runtime.advance(Duration::from_secs(2)).await.unwrap();
    let feeder_closed = runtime
        .with_simulation(|sim| sim.plant().unwrap().bool("RH2_QF1_Zapnut").unwrap())
        .await
        .unwrap();
    assert!(feeder_closed, "QF1 must stay closed");
    runtime.recorder().flush().await;
    let commands = runtime
        .store()
        .unwrap()
        .query_commands(&CommandQuery::default())
        .await
        .unwrap();
    let at_board = commands.items.iter().find(|c| c.node == "RH2").unwrap();
    assert_eq!(at_board.outcome, CommandOutcome::RefusedLocalMode);
    let at_top = commands.items.iter().find(|c| c.node == "RDRT").unwrap();
    assert_eq!(at_top.outcome, CommandOutcome::Refused);
    assert!(at_top.detail.contains("refused by RH"), "{}", at_top.detail);
    runtime.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_pulled_module_invalidates_its_points_up_to_dispatch() {
    let runtime = start(vsetin_project(), StoreChoice::Disabled).await;
    runtime.advance(Duration::from_secs(1)).await.unwrap();
    links_up(&runtime).await;
    let dispatch = Dispatch::connect(rdrt_address(&runtime), RDRT_CA, true).await;
    // RH2's values known (valid) at dispatch first, so that the IV below is the pull's.
    eventually("RH2's values valid at dispatch", || {
        (281..=298).all(|ioa| dispatch.last(ioa).is_some_and(|r| !r.invalid()))
    })
    .await;
    runtime.operate("module-pulled RH2_LOGO").await.unwrap();
    advance_until(
        &runtime,
        Duration::from_millis(100),
        "IV on every RH2 point",
        || (281..=298).all(|ioa| dispatch.last(ioa).is_some_and(|r| r.invalid())),
    )
    .await;
    runtime
        .operate("clear module-pulled RH2_LOGO")
        .await
        .unwrap();
    advance_until(&runtime, Duration::from_millis(100), "valid again", || {
        (281..=298).all(|ioa| dispatch.last(ioa).is_some_and(|r| !r.invalid()))
    })
    .await;
    runtime.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn hmi_local_mode_blocks_dispatch_commands_but_not_the_hmi() {
    let runtime = start(vsetin_project(), StoreChoice::Url("sqlite::memory:".into())).await;
    runtime.advance(Duration::from_secs(1)).await.unwrap();
    links_up(&runtime).await;
    let address = rdrt_address(&runtime);
    let dispatch = Dispatch::connect(address, RDRT_CA, true).await;
    eventually("the HMI link reported down", || {
        dispatch.last(40).and_then(|r| r.on()) == Some(true)
    })
    .await;
    let hmi = Dispatch::connect_from(address, RDRT_CA, true, Some([127, 0, 0, 2].into())).await;
    // Its link-failure point (SP 40) clears when the HMI connects; ED's (38) stays set.
    eventually("the HMI link reported up", || {
        dispatch.last(40).and_then(|r| r.on()) == Some(false)
    })
    .await;
    assert_eq!(dispatch.last(38).and_then(|r| r.on()), Some(true));

    // The HMI-local command is accepted only over the HMI's link.
    assert!(!dispatch.single_command(2001, true, false).await);
    assert!(hmi.single_command(2001, true, false).await);
    advance_until(&runtime, Duration::from_millis(100), "SP 21 set", || {
        dispatch.last(21).and_then(|r| r.on()) == Some(true)
    })
    .await;
    // Now the dispatch is refused, the HMI still commands the station.
    assert!(!dispatch.single_command(2021, true, false).await);
    assert!(hmi.single_command(2021, true, false).await);
    advance_until(
        &runtime,
        Duration::from_millis(100),
        "QF1 opened by the HMI",
        || hmi.last(291).and_then(|r| r.on()) == Some(false),
    )
    .await;
    // HMI local off: the dispatch has control again.
    assert!(hmi.single_command(2001, false, false).await);
    runtime.advance(Duration::from_millis(300)).await.unwrap();
    assert!(dispatch.single_command(2022, true, false).await);

    runtime.recorder().flush().await;
    let commands = runtime
        .store()
        .unwrap()
        .query_commands(&CommandQuery::default().with_node("RDRT"))
        .await
        .unwrap()
        .items;
    let refused: Vec<_> = commands
        .iter()
        .filter(|c| c.outcome != CommandOutcome::Executed)
        .map(|c| (c.point.as_str(), c.outcome, c.detail.as_str()))
        .collect();
    assert_eq!(refused.len(), 2, "{refused:?}");
    assert!(refused
        .iter()
        .any(|(point, outcome, detail)| *point == "RDRT_HMI_Mistne"
            && *outcome == CommandOutcome::Refused
            && detail.contains("accepted only from hmi")));
    assert!(refused
        .iter()
        .any(|(point, outcome, detail)| *point == "RH2_VypnoutQF1"
            && *outcome == CommandOutcome::RefusedLocalMode
            && detail.contains("RDRTIO.PovelyBlokovany")));
    runtime.shutdown().await;
}
