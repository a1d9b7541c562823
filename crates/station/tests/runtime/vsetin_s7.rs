//! `examples/vsetin-s7`: the LOGO! boards report to their S7-1500 concentrators over S7
//! connections (the railway-station thesis, section 3.3). A breaker change at the
//! simulated LOGO! of RH2 reaches dispatch over IEC 104 through RH1.1's S7 server and
//! RDRT, and a dispatch command reaches the LOGO!'s output through the concentrator's
//! markers; the board's S7 connection lost, its points are invalid at dispatch. RH1.2 and
//! RZS2 do the same on the connections with ID 100.

use std::time::Duration;

use station::config::Project;
use station::runtime::StoreChoice;

use crate::harness::*;

const RDRT_CA: u16 = 1;

fn project() -> Project {
    let project = Project::load(&testkit::projects::example("vsetin-s7"))
        .unwrap_or_else(|errors| panic!("{errors}"));
    // Every port (IEC 104 and S7) is port_base + an offset; the S7 servers' are the last.
    let ports = project
        .nodes
        .iter()
        .flat_map(|node| {
            node.server
                .iter()
                .map(|s| s.port_offset)
                .chain(node.s7_server.iter().map(|s| s.port_offset))
        })
        .max()
        .unwrap_or(0)
        + 1;
    project.with_port_base(free_port_range(ports))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_logo_on_s7_reports_to_dispatch_and_takes_its_commands() {
    let runtime = start(project(), StoreChoice::Disabled).await;
    runtime.advance(Duration::from_secs(1)).await.unwrap();
    links_up(&runtime).await;
    let dispatch = Dispatch::connect(rdrt_address(&runtime), RDRT_CA, true).await;
    // The boards connect to their concentrators; their values reach dispatch valid.
    advance_until(
        &runtime,
        Duration::from_millis(100),
        "RH2's values at dispatch",
        || {
            dispatch.last(280).and_then(|r| r.on()) == Some(false)
                && dispatch
                    .last(291)
                    .is_some_and(|r| r.on() == Some(true) && !r.invalid())
                && dispatch
                    .last(381)
                    .is_some_and(|r| r.on() == Some(true) && !r.invalid())
                && dispatch.last(401).is_some_and(|r| !r.invalid())
                // RH1.2 and RZS2 on the connections with ID 100 (TSAP 0100)
                && dispatch.last(320).and_then(|r| r.on()) == Some(false)
                && dispatch
                    .last(331)
                    .is_some_and(|r| r.on() == Some(true) && !r.invalid())
                && dispatch.last(440).and_then(|r| r.on()) == Some(false)
                && dispatch.last(451).is_some_and(|r| !r.invalid())
        },
    )
    .await;

    // A breaker change at the LOGO!: FA1.1 trips; RH1.1's marker, then dispatch.
    runtime.operate("breaker-tripped RH2_FA1.1").await.unwrap();
    advance_until(
        &runtime,
        Duration::from_millis(100),
        "FA1.1 open at dispatch",
        || dispatch.last(282).and_then(|r| r.on()) == Some(false),
    )
    .await;

    // Dispatch opens QF1 (IOA 2021): RH1.1's M24.0, read by the LOGO!, which drives the
    // trip coil; the busbar voltage (KHU3, M21.2) comes back up as lost.
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
    assert!(!feeder_closed, "the LOGO! opened QF1");
    // The same through RH1.2's markers (M34.0, IOA 2061).
    assert!(dispatch.single_command(2061, true, false).await);
    advance_until(
        &runtime,
        Duration::from_millis(100),
        "RH1.2's busbar voltage lost",
        || dispatch.last(331).and_then(|r| r.on()) == Some(false),
    )
    .await;

    // The board's S7 connection lost: COMM_RH2 at dispatch, RH2's points invalid.
    for device in &runtime.node("RH2").unwrap().devices {
        device.stop();
    }
    advance_until(
        &runtime,
        Duration::from_millis(100),
        "RH2 lost at dispatch",
        || {
            dispatch.last(280).and_then(|r| r.on()) == Some(true)
                && dispatch.last(291).is_some_and(|r| r.invalid())
        },
    )
    .await;
    runtime.shutdown().await;
}
