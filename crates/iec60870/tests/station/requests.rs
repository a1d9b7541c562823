//! Read, clock synchronisation, test command, counter interrogation, reset process.

use std::sync::Arc;

use iec60870::asdu::{BinaryCounterReading, Cause, Cp56Time2a, Element, TimeTag, TypeId};
use iec60870::cs104::server::StationHandler;

use crate::common::*;
use crate::interrogation::mixed_image;

#[tokio::test]
async fn read_answers_with_the_value_and_cause_5() {
    init_logs();
    let server = start_server(
        server_config(),
        mixed_image(),
        Arc::new(iec60870::cs104::server::ReadOnlyStation),
    )
    .await;
    let client = Client::connect(server.local_addr()).await;

    // A point never updated: its untagged type, no time.
    let outcome = client.handle.read(ioa(60)).await.unwrap();
    assert!(outcome.positive, "{outcome:?}");
    let answer = &outcome.responses[0];
    assert_eq!(answer.type_id, TypeId::M_ME_NC_1);
    assert_eq!(
        (answer.cot.cause, answer.cot.negative),
        (Cause::REQUEST, false)
    );
    assert_eq!(answer.objects[0].ioa, ioa(60));
    assert_eq!(
        answer.objects[0].element,
        server.get(ioa(60)).unwrap().element
    );

    // A time-tagged point after an update: the event type with the update's time.
    let time = Cp56Time2a::new(26, 2, 3, 4, 5, 6_007).unwrap();
    server.update(ioa(2), single(false), Some(time)).unwrap();
    let outcome = client.handle.read(ioa(2)).await.unwrap();
    let answer = &outcome.responses[0];
    assert_eq!(answer.type_id, TypeId::M_SP_TB_1);
    assert_eq!(answer.cot.cause, Cause::REQUEST);
    assert_eq!(answer.objects[0].element, single(false));
    assert_eq!(answer.objects[0].time, Some(TimeTag::Cp56(time)));

    // A value set with a time on a type without time tag is still answered.
    server
        .set(
            ioa(20),
            server.get(ioa(20)).unwrap().element,
            Some(TimeTag::Cp56(time)),
        )
        .unwrap();
    let outcome = client.handle.read(ioa(20)).await.unwrap();
    assert!(outcome.positive, "{outcome:?}");
    assert_eq!(outcome.responses[0].type_id, TypeId::M_ST_NA_1);

    // Unknown address: the request mirrored with cause 47.
    let outcome = client.handle.read(ioa(4242)).await.unwrap();
    assert!(!outcome.positive);
    assert_eq!(outcome.cause, Cause::UNKNOWN_OBJECT_ADDRESS);
    assert_eq!(outcome.responses[0].type_id, TypeId::C_RD_NA_1);
}

#[tokio::test]
async fn clock_sync_reaches_the_handler_and_is_confirmed() {
    init_logs();
    let handler = Recorder::accepting();
    let server = start_server(server_config(), mixed_image(), handler.clone()).await;
    let client = Client::connect(server.local_addr()).await;
    let time = Cp56Time2a::new(26, 6, 30, 23, 59, 59_999).unwrap();
    let outcome = client.handle.clock_sync(time).await.unwrap();
    assert!(outcome.positive);
    assert_eq!(outcome.cause, Cause::ACTIVATION_CON);
    assert_eq!(outcome.responses[0].type_id, TypeId::C_CS_NA_1);
    assert_eq!(handler.clock_syncs.lock().unwrap().clone(), vec![time]);

    // A station that refuses the time answers negatively.
    let refusing = Arc::new(Recorder {
        accept_clock_sync: false,
        ..Arc::into_inner(Recorder::accepting()).unwrap()
    });
    let server = start_server(server_config(), mixed_image(), refusing.clone()).await;
    let client = Client::connect(server.local_addr()).await;
    let outcome = client.handle.clock_sync(time).await.unwrap();
    assert!(!outcome.positive);
    assert_eq!(refusing.clock_syncs.lock().unwrap().len(), 1);
}

#[tokio::test]
async fn test_command_is_confirmed() {
    init_logs();
    let server = start_server(server_config(), mixed_image(), Recorder::accepting()).await;
    let client = Client::connect(server.local_addr()).await;
    let time = Cp56Time2a::new(26, 1, 1, 0, 0, 0).unwrap();
    let outcome = client.handle.test(0x1234, time).await.unwrap();
    assert!(outcome.positive && !outcome.terminated);
    let answer = &outcome.responses[0];
    assert_eq!(answer.type_id, TypeId::C_TS_TA_1);
    assert_eq!(answer.cot.cause, Cause::ACTIVATION_CON);
    assert_eq!(
        answer.objects[0].element,
        Element::TestWithTime { counter: 0x1234 }
    );
    assert_eq!(answer.objects[0].time, Some(TimeTag::Cp56(time)));
}

#[tokio::test]
async fn counter_interrogation_returns_the_counters() {
    init_logs();
    let server = start_server(server_config(), mixed_image(), Recorder::accepting()).await;
    let mut client = Client::connect(server.local_addr()).await;

    for (request, cause, addresses) in [
        (5u8, 37u8, vec![70u32, 71]),
        (1, 38, vec![70]),
        (2, 39, vec![71]),
        (3, 40, vec![]),
    ] {
        let outcome = client
            .handle
            .interrogate_counters(request, 0)
            .await
            .unwrap();
        assert!(outcome.positive && outcome.terminated, "{outcome:?}");
        let asdus = client
            .asdus_until(TypeId::C_CI_NA_1, Cause::ACTIVATION_TERMINATION, WAIT)
            .await;
        assert_eq!(asdus[0].type_id, TypeId::C_CI_NA_1);
        assert_eq!(asdus[0].cot.cause, Cause::ACTIVATION_CON);
        let objects = objects_of(&asdus[1..asdus.len() - 1]);
        let got: Vec<u32> = objects
            .iter()
            .map(|(_, _, object)| object.ioa.get())
            .collect();
        assert_eq!(got, addresses, "request {request}");
        for (type_id, got_cause, object) in objects {
            assert_eq!(type_id, TypeId::M_IT_NA_1);
            assert_eq!(got_cause.value(), cause);
            assert!(object.time.is_none());
        }
    }
    let counter = &objects_of(&client_counters(&mut client).await)[0].2;
    assert_eq!(
        counter.element,
        Element::IntegratedTotal(BinaryCounterReading::new(1000, 1).unwrap())
    );

    // An undefined request qualifier is refused.
    let outcome = client.handle.interrogate_counters(0, 0).await.unwrap();
    assert!(!outcome.positive);
}

async fn client_counters(client: &mut Client) -> Vec<iec60870::asdu::Asdu> {
    client.handle.interrogate_counters(1, 0).await.unwrap();
    let asdus = client
        .asdus_until(TypeId::C_CI_NA_1, Cause::ACTIVATION_TERMINATION, WAIT)
        .await;
    asdus[1..asdus.len() - 1].to_vec()
}

#[tokio::test]
async fn reset_process_is_decided_by_the_handler() {
    init_logs();
    let handler = Recorder::accepting();
    let server = start_server(server_config(), mixed_image(), handler.clone()).await;
    let client = Client::connect(server.local_addr()).await;
    for (qualifier, accepted) in [(1u8, true), (2, false)] {
        let asdu = request(
            TypeId::C_RP_NA_1,
            Cause::ACTIVATION,
            CA,
            0,
            Element::ResetProcess { qualifier },
        );
        let outcome = client.handle.send(asdu).await.unwrap();
        assert_eq!(outcome.positive, accepted, "qualifier {qualifier}");
        assert_eq!(outcome.cause, Cause::ACTIVATION_CON);
    }
    assert_eq!(handler.resets.lock().unwrap().clone(), vec![1, 2]);

    // The default handler refuses.
    struct Plain;
    impl StationHandler for Plain {}
    let server = start_server(server_config(), mixed_image(), Arc::new(Plain)).await;
    let client = Client::connect(server.local_addr()).await;
    let asdu = request(
        TypeId::C_RP_NA_1,
        Cause::ACTIVATION,
        CA,
        0,
        Element::ResetProcess { qualifier: 1 },
    );
    assert!(!client.handle.send(asdu).await.unwrap().positive);
}
