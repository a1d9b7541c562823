//! TLS (IEC 62351-3): mutual authentication with certificates made by the test.

use std::sync::Arc;
use std::time::Duration;

use iec60870::asdu::{Cause, TypeId};
use iec60870::cs104::client::{spawn_client, ClientConfig, ClientEvent};
use iec60870::cs104::server::ServerHandle;
use iec60870::cs104::tls::self_signed::{Authority, Usage};
use iec60870::cs104::tls::{
    client_config as tls_client_config, server_config as tls_server_config, server_name,
};
use tokio_rustls::rustls;

use crate::common::*;
use crate::interrogation::mixed_image;

struct Pki {
    ca: Authority,
    server: ServerHandle,
}

async fn tls_server() -> Pki {
    let ca = Authority::new("Stanice test CA").unwrap();
    let server_pem = ca
        .issue(&["localhost", "127.0.0.1"], Usage::Server)
        .unwrap();
    let mut config = server_config();
    config.tls = Some(tls_server_config(&server_pem).unwrap());
    let server = start_server(config, mixed_image(), Recorder::accepting()).await;
    Pki { ca, server }
}

fn tls_client(server: &ServerHandle, tls: Arc<rustls::ClientConfig>) -> ClientConfig {
    let mut config = client_config(server.local_addr());
    config.tls = Some((tls, server_name("localhost").unwrap()));
    config
}

/// Runs a client that must not get through: returns its events until it stopped.
async fn refused_client(config: ClientConfig) -> Vec<ClientEvent> {
    let (_handle, mut events) = spawn_client(config);
    let mut seen = Vec::new();
    within(WAIT, "the refused client to stop", async {
        while let Some(event) = events.recv().await {
            seen.push(event);
        }
    })
    .await;
    seen
}

#[tokio::test]
async fn tls_client_interrogates_a_tls_server() {
    init_logs();
    let pki = tls_server().await;
    let client_pem = pki
        .ca
        .issue(&["controlling-station"], Usage::Client)
        .unwrap();
    let config = tls_client(&pki.server, tls_client_config(&client_pem).unwrap());
    let mut client = Client::start(config).await;
    let outcome = within(WAIT, "GI over TLS", client.handle.interrogate(20))
        .await
        .unwrap();
    assert!(outcome.positive && outcome.terminated);
    let asdus = client
        .asdus_until(TypeId::C_IC_NA_1, Cause::ACTIVATION_TERMINATION, WAIT)
        .await;
    assert_eq!(objects_of(&asdus[1..asdus.len() - 1]).len(), 15);
    pki.server.update(ioa(60), scaled_float(1.5), None).unwrap();
    assert_eq!(client.next_asdu().await.cot.cause, Cause::SPONTANEOUS);
}

fn scaled_float(value: f32) -> iec60870::asdu::Element {
    iec60870::asdu::Element::Float {
        value,
        quality: iec60870::asdu::Quality::GOOD,
    }
}

#[tokio::test]
async fn tls_refuses_a_client_certificate_from_another_authority() {
    init_logs();
    let pki = tls_server().await;
    let rogue = Authority::new("Rogue CA").unwrap();
    // The client trusts the right CA for the server, but its own certificate is rogue.
    let mut client_pem = rogue
        .issue(&["controlling-station"], Usage::Client)
        .unwrap();
    client_pem.trust_anchors = pki.ca.certificate_pem().as_bytes().to_vec();
    let config = tls_client(&pki.server, tls_client_config(&client_pem).unwrap());
    let events = refused_client(config).await;
    assert!(!events.contains(&ClientEvent::Started), "{events:?}");
    assert!(matches!(
        events.last(),
        Some(ClientEvent::Disconnected { .. })
    ));
    wait_connections(&pki.server, 0).await;
}

#[tokio::test]
async fn tls_refuses_a_client_without_certificate() {
    init_logs();
    let pki = tls_server().await;
    let mut roots = rustls::RootCertStore::empty();
    for certificate in rustls_pemfile::certs(&mut pki.ca.certificate_pem().as_bytes()) {
        roots.add(certificate.unwrap()).unwrap();
    }
    let provider = Arc::new(rustls::crypto::ring::default_provider());
    let anonymous = rustls::ClientConfig::builder_with_provider(provider)
        .with_safe_default_protocol_versions()
        .unwrap()
        .with_root_certificates(roots)
        .with_no_client_auth();
    let config = tls_client(&pki.server, Arc::new(anonymous));
    let events = refused_client(config).await;
    assert!(!events.contains(&ClientEvent::Started), "{events:?}");
    wait_connections(&pki.server, 0).await;

    // Nor does a client that speaks plain IEC 104 to the TLS port get anywhere.
    let mut plain = RawPeer::connect(pki.server.local_addr()).await;
    plain
        .session
        .start_data_transfer(std::time::Instant::now())
        .unwrap();
    plain.flush().await;
    assert!(plain.wait_closed(WAIT).await);
    assert!(plain.next_asdu(Duration::ZERO).await.is_none());
}

#[tokio::test]
async fn tls_client_refuses_a_server_it_does_not_trust() {
    init_logs();
    let pki = tls_server().await;
    let other = Authority::new("Other CA").unwrap();
    let client_pem = other
        .issue(&["controlling-station"], Usage::Client)
        .unwrap();
    let config = tls_client(&pki.server, tls_client_config(&client_pem).unwrap());
    let events = refused_client(config).await;
    assert!(!events.contains(&ClientEvent::Started), "{events:?}");
}

#[tokio::test]
async fn requests_during_a_stalled_tls_handshake_fail_at_once() {
    init_logs();
    // A TCP server that never answers the ClientHello.
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let ca = Authority::new("Stanice test CA").unwrap();
    let client_pem = ca.issue(&["controlling-station"], Usage::Client).unwrap();
    let mut config = client_config(listener.local_addr().unwrap());
    config.apci.t0 = Duration::from_secs(30);
    config.tls = Some((
        tls_client_config(&client_pem).unwrap(),
        server_name("localhost").unwrap(),
    ));
    let (handle, _events) = spawn_client(config);
    let (_socket, _) = within(WAIT, "accept", listener.accept()).await.unwrap();
    let result = within(
        Duration::from_secs(1),
        "a request while connecting",
        handle.interrogate(20),
    )
    .await;
    assert_eq!(
        result.unwrap_err(),
        iec60870::cs104::client::ClientError::NotConnected
    );
    within(WAIT, "close while connecting", handle.close()).await;
}
