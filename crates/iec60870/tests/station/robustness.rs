//! Misbehaving peers are disconnected, with the reason logged, while a well-behaved client
//! on the same server keeps its data.

use std::net::{IpAddr, SocketAddr};
use std::sync::Arc;
use std::time::{Duration, Instant};

use iec60870::apci::{encode_i_frame, SeqNum};
use iec60870::asdu::{Cause, TypeId};
use iec60870::cs104::server::{
    ProcessImage, ReadOnlyStation, RedundancyGroupConfig, RedundancyMode, ServerHandle,
};
use iec60870::cs104::ApciConfig;

use crate::common::*;

fn image() -> ProcessImage {
    let mut image = ProcessImage::new();
    for address in 1..=10 {
        image
            .add_monitor(monitor(address, TypeId::M_ME_NB_1, 0, scaled(0)))
            .unwrap();
    }
    image
}

/// A server with short timers and two redundancy groups: the well-behaved client
/// connects from 127.0.0.1, the abusive peers from 127.0.0.2. (In one group, an abusive
/// peer that sends STARTDT would rightly take the data over from the good client.)
async fn fast_server() -> ServerHandle {
    let mut config = server_config();
    config.apci = fast_apci();
    config.outstation.redundancy = RedundancyMode::GroupsByAddress(vec![
        RedundancyGroupConfig::new("operator", vec![IpAddr::from([127, 0, 0, 1])]),
        RedundancyGroupConfig::catch_all("others"),
    ]);
    start_server(config, image(), Arc::new(ReadOnlyStation)).await
}

/// A raw peer from 127.0.0.2.
async fn abuser(server: SocketAddr) -> RawPeer {
    RawPeer::connect_with(
        server,
        Some(IpAddr::from([127, 0, 0, 2])),
        ApciConfig::default(),
    )
    .await
}

/// The good client still gets events and can interrogate.
async fn still_served(server: &ServerHandle, client: &mut Client, value: i16) {
    server.update(ioa(1), scaled(value), None).unwrap();
    let asdu = client.next_asdu().await;
    assert_eq!(asdu.cot.cause, Cause::SPONTANEOUS);
    assert_eq!(asdu.objects[0].element, scaled(value));
    let outcome = within(WAIT, "GI", client.handle.interrogate(20))
        .await
        .unwrap();
    assert!(outcome.positive && outcome.terminated);
    let asdus = client
        .asdus_until(TypeId::C_IC_NA_1, Cause::ACTIVATION_TERMINATION, WAIT)
        .await;
    assert_eq!(objects_of(&asdus[1..asdus.len() - 1]).len(), 10);
}

fn i_frame(asdu: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    encode_i_frame(SeqNum::ZERO, SeqNum::ZERO, asdu, &mut out).unwrap();
    out
}

#[tokio::test]
async fn protocol_violations_close_only_the_offending_connection() {
    init_logs();
    let server = fast_server().await;
    let address = server.local_addr();
    let mut good = Client::connect(address).await;
    let gi = interrogation(20).to_bytes(&params()).unwrap();

    struct Case {
        what: &'static str,
        start_first: bool,
        bytes: Vec<u8>,
        reason: &'static str,
    }
    let cases = [
        Case {
            what: "garbage",
            start_first: false,
            bytes: b"GET / HTTP/1.1\r\nHost: x\r\n\r\n".to_vec(),
            reason: "invalid start byte 0x47",
        },
        Case {
            what: "oversize length",
            start_first: false,
            bytes: vec![0x68, 0xFE, 0x00, 0x00, 0x00, 0x00],
            reason: "above the maximum of 253",
        },
        Case {
            what: "length below 4",
            start_first: true,
            bytes: vec![0x68, 0x02, 0x01, 0x00],
            reason: "below the minimum of 4",
        },
        Case {
            what: "I frame before STARTDT",
            start_first: false,
            bytes: i_frame(&gi),
            reason: "I frame received while data transfer is not started",
        },
        Case {
            what: "S frame before STARTDT",
            start_first: false,
            bytes: vec![0x68, 0x04, 0x01, 0x00, 0x00, 0x00],
            reason: "S frame received while data transfer is stopped",
        },
        Case {
            what: "bad N(R)",
            start_first: true,
            bytes: vec![0x68, 0x04, 0x01, 0x00, 0x0A, 0x00],
            reason: "received N(R) = 5 outside",
        },
        Case {
            what: "wrong N(S)",
            start_first: true,
            bytes: {
                let mut out = Vec::new();
                encode_i_frame(SeqNum::new(3), SeqNum::ZERO, &gi, &mut out).unwrap();
                out
            },
            reason: "received I frame with N(S) = 3, expected 0",
        },
        Case {
            what: "two U functions at once",
            start_first: false,
            bytes: vec![0x68, 0x04, 0x07 | 0x40, 0x00, 0x00, 0x00],
            reason: "exactly one function bit",
        },
    ];
    for (index, case) in cases.iter().enumerate() {
        let mut peer = abuser(address).await;
        if case.start_first {
            peer.start().await;
        }
        peer.write_raw(&case.bytes).await;
        assert!(
            peer.wait_closed(WAIT).await,
            "{}: not disconnected",
            case.what
        );
        expect_close_logged(peer.local, case.reason).await;
        still_served(&server, &mut good, index as i16 + 100).await;
    }
    wait_connections(&server, 1).await;
}

#[tokio::test]
async fn a_truncated_frame_then_silence_is_closed_by_the_timers() {
    init_logs();
    let server = fast_server().await;
    let mut good = Client::connect(server.local_addr()).await;
    let mut peer = abuser(server.local_addr()).await;
    peer.start().await;
    let began = Instant::now();
    // Announces 14 octets, sends 3 of them, then nothing.
    peer.write_raw(&[0x68, 0x0E, 0x00, 0x00, 0x00]).await;
    assert!(peer.wait_closed(Duration::from_secs(4)).await);
    assert!(
        began.elapsed() >= Duration::from_millis(1_500),
        "{:?}",
        began.elapsed()
    );
    expect_close_logged(peer.local, "t1 expired").await;
    still_served(&server, &mut good, 7).await;
}

#[tokio::test]
async fn an_undecodable_asdu_does_not_kill_the_connection() {
    init_logs();
    let server = start_server(server_config(), image(), Arc::new(ReadOnlyStation)).await;
    let mut peer = RawPeer::connect(server.local_addr()).await;
    peer.start().await;
    // C_IC_NA_1 announcing two objects but carrying one.
    peer.send_asdu(&[100, 0x02, 0x06, 0x00, 0x01, 0x00, 0, 0, 0, 20])
        .await;
    // Shorter than a header.
    peer.send_asdu(&[100, 0x01]).await;
    // A time tag out of range (minute 61) in a clock synchronisation.
    peer.send_asdu(&[
        103, 0x01, 0x06, 0x00, 0x01, 0x00, 0, 0, 0, 0, 0, 61, 0, 1, 1, 26,
    ])
    .await;
    peer.send(&interrogation(20)).await;
    let asdus = peer
        .asdus_until(TypeId::C_IC_NA_1, Cause::ACTIVATION_TERMINATION)
        .await;
    // Whatever answered the malformed requests was negative.
    for asdu in asdus
        .iter()
        .filter(|asdu| asdu.type_id == TypeId::C_CS_NA_1)
    {
        assert!(asdu.cot.negative, "{asdu}");
    }
    let positive_confirmations = asdus
        .iter()
        .filter(|a| {
            a.type_id == TypeId::C_IC_NA_1
                && a.cot.cause == Cause::ACTIVATION_CON
                && !a.cot.negative
        })
        .count();
    assert_eq!(positive_confirmations, 1);
    assert_eq!(
        asdus
            .iter()
            .filter(|a| a.cot.cause == Cause::INTERROGATED_BY_STATION)
            .map(|a| a.objects.len())
            .sum::<usize>(),
        10
    );
    assert!(!peer.is_closed());
}

#[tokio::test]
async fn the_server_survives_200_abusive_connections() {
    init_logs();
    let server = fast_server().await;
    let address = server.local_addr();
    let mut good = Client::connect(address).await;
    let junk: [&[u8]; 4] = [
        b"\x00\x01\x02\x03garbage",
        &[0x68, 0xFF],
        &[0x68, 0x04, 0x07, 0x00],
        &[0x68, 0x04, 0x43, 0x00, 0x00, 0x00, 0x99],
    ];
    for batch in 0..10 {
        let mut tasks = Vec::new();
        for index in 0..20 {
            let bytes = junk[(batch * 20 + index) % junk.len()].to_vec();
            tasks.push(tokio::spawn(async move {
                let mut peer = abuser(address).await;
                peer.write_raw(&bytes).await;
                // Half of them hang up at once, the others (sending invalid framing) wait
                // to be thrown out.
                if index % 2 == 0 {
                    drop(peer);
                } else {
                    assert!(peer.wait_closed(Duration::from_secs(4)).await);
                }
            }));
        }
        for task in tasks {
            within(Duration::from_secs(6), "an abusive peer", task)
                .await
                .unwrap();
        }
        still_served(&server, &mut good, batch as i16).await;
    }
    wait_connections(&server, 1).await;
    let stats = server.stats();
    assert_eq!(stats.accepted + stats.refused, 201);
    still_served(&server, &mut good, 1_000).await;
}

#[tokio::test]
async fn an_idle_client_is_closed_after_t3_plus_t1() {
    init_logs();
    let server = fast_server().await;
    let began = Instant::now();
    let mut silent = RawPeer::connect(server.local_addr()).await;
    // Neither STARTDT nor an answer to the TESTFR act the server sends after t3.
    assert!(
        silent.wait_closed(Duration::from_secs(4)).await,
        "idle client not closed"
    );
    let elapsed = began.elapsed();
    assert!(
        elapsed >= Duration::from_millis(1_800),
        "closed too early: {elapsed:?}"
    );
    expect_close_logged(silent.local, "t1 expired waiting for the confirmation of").await;

    // A client that answers the test frames but never starts stays connected.
    let mut polite = RawPeer::connect(server.local_addr()).await;
    polite.pump_for(Duration::from_millis(2_500)).await;
    assert!(!polite.is_closed());
    assert!(polite.session.stats().test_frames_received >= 2);
}

#[tokio::test]
async fn a_client_flooding_requests_without_acknowledging_is_closed() {
    init_logs();
    let server = fast_server().await;
    let mut good = Client::connect(server.local_addr()).await;
    let mut peer = abuser(server.local_addr()).await;
    peer.start().await;
    // 6,000 read requests (above the 4,096 answers the server queues), each numbered correctly, none acknowledging an answer: the
    // server's window shuts after k answers and the rest would pile up until t1.
    let read = [102u8, 0x01, 0x05, 0x00, 0x01, 0x00, 1, 0, 0];
    let mut flood = Vec::new();
    for number in 0..6_000u16 {
        encode_i_frame(SeqNum::new(number), SeqNum::ZERO, &read, &mut flood).unwrap();
    }
    peer.write_raw(&flood).await;
    expect_close_logged(peer.local, "without acknowledging").await;
    still_served(&server, &mut good, 77).await;
}

#[tokio::test]
async fn endless_malformed_asdus_close_the_connection() {
    init_logs();
    let server = fast_server().await;
    let mut good = Client::connect(server.local_addr()).await;
    let mut peer = abuser(server.local_addr()).await;
    peer.start().await;
    // A C_IC_NA_1 announcing two objects but carrying one, 100 times: each is ignored,
    // and past the tolerated number the connection is closed.
    let malformed = [100u8, 0x02, 0x06, 0x00, 0x01, 0x00, 0, 0, 0, 20];
    let mut frames = Vec::new();
    for number in 0..100u16 {
        encode_i_frame(SeqNum::new(number), SeqNum::ZERO, &malformed, &mut frames).unwrap();
    }
    peer.write_raw(&frames).await;
    expect_close_logged(peer.local, "malformed ASDUs received").await;
    still_served(&server, &mut good, 78).await;
}
