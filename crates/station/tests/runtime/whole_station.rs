//! The parts of the thesis's station beyond RH2, RZZ and RDA, as dispatch sees them
//! through RDRT (IOA plan of examples/vsetin): the LOGO! boards RH1.2 and RZS2 behind their
//! concentrators, the S7-1500s of RH and RZS in DT on links of their own, the 6 kV by-pass
//! RS602 and the signalling equipment's universal source (TZ1 from RZZ, backup RZS1).

use std::time::Duration;

use station::runtime::StoreChoice;

use crate::harness::*;

const R6_Q3_CLOSED: u32 = 207;
const RS602_CLOSED: u32 = 208;
const TRANSFORMERS_6KV: u32 = 216;
const RH12_BUSBAR_LIVE: u32 = 331; // RH1.2's KHU3 (RH2's 291 + 40)
const RZS2_BUSBAR_LIVE: u32 = 451; // RZS2's KHU3 (RZZ's 391 + 60)
const UZ_FROM_RZZ: u32 = 346;
const UZ_FROM_RZS1: u32 = 347;
const UZ_OUTPUT: u32 = 348;
const RHDT_BUSBAR_LIVE: u32 = 502;
const RZSDT_BUSBAR_LIVE: u32 = 602;
const COMM_RH_DT: u32 = 34;
const COMM_RZS_DT: u32 = 35;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_whole_station_reaches_dispatch() {
    let runtime = start(vsetin_project(), StoreChoice::Disabled).await;
    runtime.advance(Duration::from_secs(2)).await.unwrap();
    links_up(&runtime).await;
    let dispatch = Dispatch::connect(rdrt_address(&runtime), 1, true).await;
    let on = |ioa: u32| {
        dispatch
            .last(ioa)
            .filter(|r| !r.invalid())
            .and_then(|r| r.on())
    };
    // Everything live and valid once RDA has put RZS on the mains: the DT links up.
    advance_until(
        &runtime,
        Duration::from_millis(200),
        "the whole station at dispatch",
        || {
            [
                RH12_BUSBAR_LIVE,
                RZS2_BUSBAR_LIVE,
                RHDT_BUSBAR_LIVE,
                RZSDT_BUSBAR_LIVE,
                UZ_FROM_RZZ,
                UZ_OUTPUT,
                R6_Q3_CLOSED,
            ]
            .into_iter()
            .all(|ioa| on(ioa) == Some(true))
                && on(COMM_RH_DT) == Some(false)
                && on(COMM_RZS_DT) == Some(false)
                && on(RS602_CLOSED) == Some(false)
        },
    )
    .await;

    // Dispatch opens QF1 of RH1.2 (2061) and of RZS2 (2181) through the concentrators.
    assert!(dispatch.single_command(2061, true, false).await);
    assert!(dispatch.single_command(2181, true, false).await);
    advance_until(
        &runtime,
        Duration::from_millis(100),
        "RH1.2 and RZS2 dead",
        || on(RH12_BUSBAR_LIVE) == Some(false) && on(RZS2_BUSBAR_LIVE) == Some(false),
    )
    .await;
    // ... and closes them again.
    assert!(dispatch.single_command(2062, true, false).await);
    assert!(dispatch.single_command(2182, true, false).await);
    advance_until(
        &runtime,
        Duration::from_millis(100),
        "RH1.2 and RZS2 back",
        || on(RH12_BUSBAR_LIVE) == Some(true) && on(RZS2_BUSBAR_LIVE) == Some(true),
    )
    .await;

    // R6 taken out for maintenance over the by-pass RS602: the interlock refuses the
    // by-pass while R6 feeds the transformers; dispatch sees each step.
    assert!(runtime.operate("close RS602").await.is_err());
    runtime.operate("open R6_Q3").await.unwrap();
    advance_until(
        &runtime,
        Duration::from_millis(100),
        "transformers without 6 kV",
        || {
            on(R6_Q3_CLOSED) == Some(false)
                && dispatch
                    .last(TRANSFORMERS_6KV)
                    .and_then(|r| r.real())
                    .is_some_and(|v| v < 1.0)
        },
    )
    .await;
    runtime.operate("close RS602").await.unwrap();
    advance_until(
        &runtime,
        Duration::from_millis(100),
        "transformers fed over the by-pass",
        || {
            on(RS602_CLOSED) == Some(true)
                && dispatch
                    .last(TRANSFORMERS_6KV)
                    .and_then(|r| r.real())
                    .is_some_and(|v| v > 5_900.0)
        },
    )
    .await;

    // The signalling supply: T1 (TZ1) lost, the universal source takes RZS1, and back.
    runtime.operate("supply-loss T1").await.unwrap();
    advance_until(
        &runtime,
        Duration::from_millis(100),
        "signalling equipment on RZS1",
        || {
            on(UZ_FROM_RZS1) == Some(true)
                && on(UZ_FROM_RZZ) == Some(false)
                && on(UZ_OUTPUT) == Some(true)
        },
    )
    .await;
    runtime.operate("clear supply-loss T1").await.unwrap();
    advance_until(
        &runtime,
        Duration::from_millis(100),
        "signalling equipment back on RZZ",
        || on(UZ_FROM_RZZ) == Some(true) && on(UZ_FROM_RZS1) == Some(false),
    )
    .await;

    // The DT board's DI module pulled: its points go invalid at dispatch.
    runtime.operate("module-pulled RHDT_DI").await.unwrap();
    advance_until(
        &runtime,
        Duration::from_millis(100),
        "RH in DT invalid",
        || dispatch.last(RHDT_BUSBAR_LIVE).is_some_and(|r| r.invalid()),
    )
    .await;
    runtime.shutdown().await;
}
