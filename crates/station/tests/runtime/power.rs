//! The automatic transfer of board RDA as the dispatch sees it: mains loss, the generator
//! started and loaded after its voltage settled, back to the mains on restoration, and the
//! two sources never joined.

use std::time::Duration;

use plant::Plant;
use station::runtime::StoreChoice;

use crate::harness::*;

/// RDA points at the top controller (IOA plan of examples/vsetin).
const KM1_CLOSED: u32 = 401;
const KM2_CLOSED: u32 = 402;
const GENERATOR_READY: u32 = 410;
const ON_MAINS: u32 = 414;
const ON_GENERATOR: u32 = 415;
const RZS_DEAD: u32 = 416;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn mains_loss_transfers_to_the_generator_and_back_without_joining_sources() {
    let runtime = start(vsetin_project(), StoreChoice::Disabled).await;
    runtime.advance(Duration::from_secs(2)).await.unwrap();
    links_up(&runtime).await;
    let dispatch = Dispatch::connect(rdrt_address(&runtime), 1, true).await;
    eventually("RDA on mains at dispatch", || {
        dispatch.last(ON_MAINS).and_then(|r| r.on()) == Some(true)
            && dispatch.last(KM1_CLOSED).and_then(|r| r.on()) == Some(true)
    })
    .await;

    let lost_at = runtime.clock().now();
    runtime.operate("supply-loss UTILITY").await.unwrap();
    advance_until(
        &runtime,
        Duration::from_millis(500),
        "RZS fed by the generator",
        || dispatch.last(ON_GENERATOR).and_then(|r| r.on()) == Some(true),
    )
    .await;
    let transferred_after = runtime.clock().now() - lost_at;
    // Confirmation of the loss (1 s), generator start (5 s) and voltage build-up, settling
    // (the plant's 6 s, the PLC's 10 s), then KM2: between 15 and 25 s of plant time.
    assert!(
        (Duration::from_secs(15)..=Duration::from_secs(25)).contains(&transferred_after),
        "{transferred_after:?}"
    );
    assert_eq!(dispatch.last(KM2_CLOSED).unwrap().on(), Some(true));
    assert_eq!(dispatch.last(KM1_CLOSED).unwrap().on(), Some(false));
    assert_eq!(dispatch.last(GENERATOR_READY).unwrap().on(), Some(true));
    // The dispatch saw the RZS busbar dead in between, and the events in plant order.
    let dead: Vec<bool> = dispatch
        .of(RZS_DEAD)
        .iter()
        .filter_map(Received::on)
        .collect();
    assert!(dead.ends_with(&[true, false]), "{dead:?}");

    runtime.operate("clear supply-loss UTILITY").await.unwrap();
    let restored_at = runtime.clock().now();
    advance_until(
        &runtime,
        Duration::from_secs(1),
        "back on the mains",
        || {
            dispatch.last(ON_MAINS).and_then(|r| r.on()) == Some(true)
                && dispatch.last(KM1_CLOSED).and_then(|r| r.on()) == Some(true)
        },
    )
    .await;
    let returned_after = runtime.clock().now() - restored_at;
    assert!(
        returned_after >= Duration::from_secs(60),
        "returned after {returned_after:?}, before the mains were stable for 60 s"
    );
    assert_eq!(dispatch.last(KM2_CLOSED).unwrap().on(), Some(false));
    // The generator cools down and stops.
    runtime.advance(Duration::from_secs(120)).await.unwrap();
    let (violations, safety, running) = runtime
        .with_simulation(|sim| {
            // The Vsetín plant's own safety record.
            let plant = sim
                .plant()
                .unwrap()
                .as_any()
                .downcast_ref::<plant::VsetinPlant>()
                .unwrap();
            (
                plant.source_violations(),
                plant.safety_log().len(),
                plant.bool("RDA_DA_Bezi").unwrap(),
            )
        })
        .await
        .unwrap();
    assert_eq!(violations, 0, "two sources joined");
    assert_eq!(safety, 0, "safety events");
    assert!(!running, "generator still running");
    runtime.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn local_control_keeps_working_with_every_upper_link_down() {
    let runtime = start(vsetin_project(), StoreChoice::Disabled).await;
    runtime.advance(Duration::from_secs(2)).await.unwrap();
    links_up(&runtime).await;
    // The whole concentration layer is cut off from the boards.
    for link in ["RH1.1/RH2", "RZS1/RZZ", "RZS1/RDA"] {
        runtime.operate(&format!("link-cut {link}")).await.unwrap();
    }
    // The transfer still works at the board, and the feeder opens by its door pushbutton.
    runtime.operate("supply-loss UTILITY").await.unwrap();
    runtime.operate("selector RH2 local").await.unwrap();
    runtime.advance(Duration::from_secs(1)).await.unwrap();
    runtime.operate("open RH2_QF1").await.unwrap();
    runtime.advance(Duration::from_secs(30)).await.unwrap();
    let (on_generator, feeder_closed) = runtime
        .with_simulation(|sim| {
            let plant = sim.plant().unwrap();
            (
                plant.bool("RDA_KM2_Zapnut").unwrap(),
                plant.bool("RH2_QF1_Zapnut").unwrap(),
            )
        })
        .await
        .unwrap();
    assert!(on_generator, "the RDA board transferred on its own");
    assert!(!feeder_closed, "local operation of QF1");
    runtime.shutdown().await;
}
