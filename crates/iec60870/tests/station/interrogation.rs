//! General interrogation: station and group, types without time tag, SQ = 1 packing, and a
//! 100 000-point image.

use std::collections::HashMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

use iec60870::asdu::{
    BinaryCounterReading, Cause, DoublePointState, Element, Quality, StepPosition, TypeId,
};
use iec60870::cs104::server::{ProcessImage, ReadOnlyStation};

use crate::common::*;

/// The mixed point set of the interrogation tests: (IOA, event type, groups, value).
pub(crate) fn mixed_image() -> ProcessImage {
    let good = Quality::GOOD;
    let mut image = ProcessImage::new();
    let mut add = |address: u32, event_type: TypeId, groups: u16, element: Element| {
        image
            .add_monitor(monitor(address, event_type, groups, element))
            .unwrap();
    };
    // Five consecutive single points (time-tagged events), 1..=3 in group 1.
    for address in 1..=5 {
        let groups = if address <= 3 { 0b1 } else { 0 };
        add(address, TypeId::M_SP_TB_1, groups, single(address % 2 == 0));
    }
    add(10, TypeId::M_DP_TB_1, 0b10, double(DoublePointState::On));
    add(11, TypeId::M_DP_NA_1, 0, double(DoublePointState::Off));
    add(
        20,
        TypeId::M_ST_NA_1,
        0,
        Element::StepPosition {
            position: StepPosition::new(-5, false).unwrap(),
            quality: good,
        },
    );
    add(
        30,
        TypeId::M_BO_TB_1,
        0,
        Element::Bitstring {
            bits: 0xDEAD_BEEF,
            quality: good,
        },
    );
    for (offset, raw) in [100i16, -200, 300].into_iter().enumerate() {
        let address = 40 + offset as u32;
        let groups = if address == 41 { 0b1 } else { 0 };
        add(
            address,
            TypeId::M_ME_NA_1,
            groups,
            Element::Normalized { raw, quality: good },
        );
    }
    add(50, TypeId::M_ME_TE_1, 0, scaled(-1234));
    add(
        60,
        TypeId::M_ME_NC_1,
        0,
        Element::Float {
            value: 50.02,
            quality: good,
        },
    );
    add(
        61,
        TypeId::M_ME_TF_1,
        0b10,
        Element::Float {
            value: -0.5,
            quality: good,
        },
    );
    add(
        70,
        TypeId::M_IT_NA_1,
        0b1,
        Element::IntegratedTotal(BinaryCounterReading::new(1000, 1).unwrap()),
    );
    add(
        71,
        TypeId::M_IT_TB_1,
        0b10,
        Element::IntegratedTotal(BinaryCounterReading::new(-7, 2).unwrap()),
    );
    image
}

/// IOA -> type expected in an interrogation answer, for the non-counter points.
fn expected_types() -> HashMap<u32, TypeId> {
    let mut types = HashMap::new();
    for address in 1..=5 {
        types.insert(address, TypeId::M_SP_NA_1);
    }
    types.insert(10, TypeId::M_DP_NA_1);
    types.insert(11, TypeId::M_DP_NA_1);
    types.insert(20, TypeId::M_ST_NA_1);
    types.insert(30, TypeId::M_BO_NA_1);
    for address in 40..=42 {
        types.insert(address, TypeId::M_ME_NA_1);
    }
    types.insert(50, TypeId::M_ME_NB_1);
    types.insert(60, TypeId::M_ME_NC_1);
    types.insert(61, TypeId::M_ME_NC_1);
    types
}

#[tokio::test]
async fn station_interrogation_returns_every_point_once_untagged() {
    init_logs();
    let image = mixed_image();
    let server = start_server(server_config(), image.clone(), Arc::new(ReadOnlyStation)).await;
    let mut client = Client::connect(server.local_addr()).await;

    let outcome = within(WAIT, "GI", client.handle.interrogate(20))
        .await
        .unwrap();
    assert!(outcome.positive && outcome.terminated, "{outcome:?}");

    let asdus = client
        .asdus_until(TypeId::C_IC_NA_1, Cause::ACTIVATION_TERMINATION, WAIT)
        .await;
    let first = asdus.first().unwrap();
    assert_eq!(
        (first.type_id, first.cot.cause, first.cot.negative),
        (TypeId::C_IC_NA_1, Cause::ACTIVATION_CON, false)
    );
    let data = &asdus[1..asdus.len() - 1];
    let expected = expected_types();
    let mut seen = HashMap::new();
    for (type_id, cause, object) in objects_of(data) {
        assert_eq!(
            cause,
            Cause::INTERROGATED_BY_STATION,
            "{type_id} {object:?}"
        );
        assert!(object.time.is_none(), "GI objects carry no time tag");
        let address = object.ioa.get();
        assert_eq!(expected.get(&address), Some(&type_id), "IOA {address}");
        assert!(
            seen.insert(address, object.element.clone()).is_none(),
            "IOA {address} twice"
        );
        let point = image.monitor(object.ioa).unwrap();
        assert_eq!(object.element, point.element, "IOA {address}");
    }
    assert_eq!(
        seen.len(),
        expected.len(),
        "every non-counter point exactly once"
    );

    // Runs of three or more consecutive addresses of one type are packed with SQ = 1.
    let single_points = data
        .iter()
        .find(|asdu| asdu.type_id == TypeId::M_SP_NA_1)
        .unwrap();
    assert!(single_points.sequence, "IOA 1..=5 go in one SQ=1 ASDU");
    assert_eq!(single_points.objects.len(), 5);
    let normalized = data
        .iter()
        .find(|asdu| asdu.type_id == TypeId::M_ME_NA_1)
        .unwrap();
    assert!(normalized.sequence && normalized.objects.len() == 3);
}

#[tokio::test]
async fn group_interrogation_returns_only_the_group_with_its_cause() {
    init_logs();
    let server = start_server(server_config(), mixed_image(), Arc::new(ReadOnlyStation)).await;
    let mut client = Client::connect(server.local_addr()).await;

    for (qualifier, cause, mut addresses) in [
        (21u8, 21u8, vec![1u32, 2, 3, 41]),
        (22, 22, vec![10, 61]),
        (36, 36, vec![]),
    ] {
        let outcome = within(WAIT, "group GI", client.handle.interrogate(qualifier))
            .await
            .unwrap();
        assert!(outcome.positive && outcome.terminated, "{outcome:?}");
        let asdus = client
            .asdus_until(TypeId::C_IC_NA_1, Cause::ACTIVATION_TERMINATION, WAIT)
            .await;
        assert_eq!(asdus[0].cot.cause, Cause::ACTIVATION_CON);
        let termination = asdus.last().unwrap();
        assert_eq!(
            termination.objects[0].element,
            Element::Interrogation { qualifier }
        );
        let mut got: Vec<u32> = objects_of(&asdus[1..asdus.len() - 1])
            .into_iter()
            .map(|(type_id, got_cause, object)| {
                assert_eq!(got_cause.value(), cause, "qualifier {qualifier}");
                assert!(type_id.time_tag() == iec60870::asdu::TimeTagKind::None);
                object.ioa.get()
            })
            .collect();
        got.sort_unstable();
        addresses.sort_unstable();
        assert_eq!(got, addresses, "qualifier {qualifier}");
    }

    // An undefined qualifier is refused.
    let outcome = within(WAIT, "GI 19", client.handle.interrogate(19))
        .await
        .unwrap();
    assert!(!outcome.positive);
}

#[tokio::test]
async fn interrogation_of_100000_points_streams_every_object() {
    init_logs();
    const SINGLE: u32 = 50_000;
    const FLOAT: u32 = 30_000;
    const DOUBLE: u32 = 20_000;
    let mut image = ProcessImage::new();
    for address in 1..=SINGLE {
        image
            .add_monitor(monitor(
                address,
                TypeId::M_SP_TB_1,
                0,
                single(address % 3 == 0),
            ))
            .unwrap();
    }
    for address in SINGLE + 1..=SINGLE + FLOAT {
        let element = Element::Float {
            value: address as f32,
            quality: Quality::GOOD,
        };
        image
            .add_monitor(monitor(address, TypeId::M_ME_NC_1, 0, element))
            .unwrap();
    }
    for address in SINGLE + FLOAT + 1..=SINGLE + FLOAT + DOUBLE {
        image
            .add_monitor(monitor(
                address,
                TypeId::M_DP_NA_1,
                0,
                double(DoublePointState::On),
            ))
            .unwrap();
    }
    let server = start_server(server_config(), image, Arc::new(ReadOnlyStation)).await;
    let mut config = client_config(server.local_addr());
    config.command_timeout = Duration::from_secs(30);
    let mut client = Client::start(config).await;

    let began = Instant::now();
    let handle = client.handle.clone();
    let gi = tokio::spawn(async move { handle.interrogate(20).await });
    let asdus = client
        .asdus_until(
            TypeId::C_IC_NA_1,
            Cause::ACTIVATION_TERMINATION,
            Duration::from_secs(30),
        )
        .await;
    let outcome = within(WAIT, "the GI outcome", gi).await.unwrap().unwrap();
    assert!(outcome.positive && outcome.terminated);
    let elapsed = began.elapsed();

    let mut seen = vec![false; (SINGLE + FLOAT + DOUBLE + 1) as usize];
    let mut count = 0usize;
    for asdu in &asdus[1..asdus.len() - 1] {
        assert_eq!(asdu.cot.cause, Cause::INTERROGATED_BY_STATION);
        assert!(asdu.sequence, "consecutive addresses are packed with SQ=1");
        let expected_type = match asdu.objects[0].ioa.get() {
            a if a <= SINGLE => TypeId::M_SP_NA_1,
            a if a <= SINGLE + FLOAT => TypeId::M_ME_NC_1,
            _ => TypeId::M_DP_NA_1,
        };
        assert_eq!(asdu.type_id, expected_type);
        for object in &asdu.objects {
            let slot = &mut seen[object.ioa.get() as usize];
            assert!(!*slot, "{} twice", object.ioa);
            *slot = true;
            count += 1;
        }
    }
    assert_eq!(count, 100_000);
    // Full SQ=1 ASDUs but for the last of each type: ceil(50 000 / 127) + ceil(30 000 /
    // 48) + ceil(20 000 / 127) = 394 + 625 + 158 data ASDUs, with ACT_CON and ACT_TERM.
    assert_eq!(asdus.len(), 394 + 625 + 158 + 2, "poorly packed");
    assert!(elapsed < Duration::from_secs(30), "GI took {elapsed:?}");
}

#[tokio::test]
async fn interrogation_keeps_order_with_spontaneous_events_and_is_refused_while_running() {
    init_logs();
    let mut image = ProcessImage::new();
    for address in 1..=5_000 {
        image
            .add_monitor(monitor(address, TypeId::M_ME_NB_1, 0, scaled(0)))
            .unwrap();
    }
    let server = start_server(server_config(), image, Arc::new(ReadOnlyStation)).await;
    let mut peer = RawPeer::connect(server.local_addr()).await;
    peer.start().await;
    peer.send(&interrogation(20)).await;
    // A second GI while the first runs gets a negative confirmation.
    peer.send(&interrogation(20)).await;
    // An event during the GI: the newest value must win over what the GI sends before it.
    server.update(ioa(4_000), scaled(77), None).unwrap();

    let asdus = peer
        .asdus_until(TypeId::C_IC_NA_1, Cause::ACTIVATION_TERMINATION)
        .await;
    let confirmations: Vec<bool> = asdus
        .iter()
        .filter(|asdu| asdu.type_id == TypeId::C_IC_NA_1 && asdu.cot.cause == Cause::ACTIVATION_CON)
        .map(|asdu| asdu.cot.negative)
        .collect();
    assert_eq!(confirmations, vec![false, true]);
    let mut last_value_of_4000 = None;
    let mut spontaneous = 0;
    let mut interrogated = 0;
    for (_, cause, object) in objects_of(&asdus) {
        if object.ioa.get() == 4_000 {
            last_value_of_4000 = Some(object.element.clone());
        }
        if cause == Cause::SPONTANEOUS {
            spontaneous += 1;
        } else if cause == Cause::INTERROGATED_BY_STATION {
            interrogated += 1;
        }
    }
    assert_eq!((spontaneous, interrogated), (1, 5_000));
    assert_eq!(last_value_of_4000, Some(scaled(77)));
}

#[tokio::test]
async fn a_running_interrogation_can_be_deactivated() {
    init_logs();
    let mut image = ProcessImage::new();
    for address in 1..=20_000 {
        image
            .add_monitor(monitor(address, TypeId::M_SP_NA_1, 0, single(false)))
            .unwrap();
    }
    let server = start_server(server_config(), image, Arc::new(ReadOnlyStation)).await;
    let mut peer = RawPeer::connect(server.local_addr()).await;
    peer.start().await;
    peer.send(&interrogation(20)).await;
    let confirmation = peer.expect_asdu().await;
    assert_eq!(confirmation.cot.cause, Cause::ACTIVATION_CON);
    let mut deactivation = interrogation(20);
    deactivation.cot.cause = Cause::DEACTIVATION;
    peer.send(&deactivation).await;
    // Data already in flight may still come, then the DEACT_CON, and no ACT_TERM.
    let asdus = peer
        .asdus_until(TypeId::C_IC_NA_1, Cause::DEACTIVATION_CON)
        .await;
    let answer = asdus.last().unwrap();
    assert!(!answer.cot.negative);
    let delivered: usize = asdus.iter().map(|asdu| asdu.objects.len()).sum();
    assert!(delivered < 20_000, "the interrogation was not stopped");
    while let Some(asdu) = peer.next_asdu(Duration::from_millis(200)).await {
        assert_ne!(asdu.cot.cause, Cause::ACTIVATION_TERMINATION, "{asdu}");
    }
    // Deactivating when nothing runs: negative DEACT_CON.
    peer.send(&deactivation).await;
    let answer = peer.expect_asdu().await;
    assert_eq!(answer.cot.cause, Cause::DEACTIVATION_CON);
    assert!(answer.cot.negative);
}
