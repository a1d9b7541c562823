//! Links between nodes over TLS with mutual authentication (IEC 62351-3): the lower
//! node's server requires a client certificate of the project's authority, the upper
//! node's link presents one and checks the server's.

use std::time::Duration;

use iec60870::asdu::CommonAddress;
use iec60870::cs104::client::{spawn_client, ClientConfig, ClientEvent};
use iec60870::cs104::tls::self_signed::{write, Authority, Usage};
use station::config::Project;
use station::runtime::StoreChoice;

use crate::harness::{eventually, free_port_range, links_up, project_folder, start};

const BOARD_ST: &str = "PROGRAM Board\nVAR Lamp : BOOL := TRUE; END_VAR\nEND_PROGRAM\n";

const STATION_TOML: &str = r#"
[station]
name = "TLS"
time_zone = "Europe/Prague"

[[node]]
name = "TOP"
common_address = 1
[node.server]
port_offset = 0
[[node.point]]
name = "Lamp"
type = "M_SP_TB_1"
ioa = 10
source = "link:BOARD/10"
[[node.link]]
name = "BOARD"
node = "BOARD"
tls = { certificate = "tls/top.pem", private_key = "tls/top.key", trust_anchors = "tls/top-ca.pem" }

[[node]]
name = "BOARD"
common_address = 21
sources = ["plc/board.st"]
[node.server]
port_offset = 1
tls = { certificate = "tls/board.pem", private_key = "tls/board.key", trust_anchors = "tls/board-ca.pem" }
[[node.task]]
name = "fast"
interval_ms = 10
programs = ["Board"]
[[node.point]]
name = "Lamp"
type = "M_SP_TB_1"
ioa = 10
source = "Board.Lamp"
"#;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn nodes_talk_over_mutually_authenticated_tls_and_refuse_plain_clients() {
    let dir = project_folder(&[("station.toml", STATION_TOML), ("plc/board.st", BOARD_ST)]);
    std::fs::create_dir_all(dir.path().join("tls")).unwrap();
    let authority = Authority::new("test station CA").unwrap();
    for node in ["top", "board"] {
        let pem = authority
            .issue(&["127.0.0.1", "localhost"], Usage::ServerAndClient)
            .unwrap();
        write(&pem, &dir.path().join("tls"), node).unwrap();
    }
    let project = Project::load(dir.path()).unwrap_or_else(|errors| panic!("{errors}"));
    let project = project.with_port_base(free_port_range(2));
    let top = project
        .node("TOP")
        .unwrap()
        .server_address(&project.station)
        .unwrap();
    let board = project
        .node("BOARD")
        .unwrap()
        .server_address(&project.station)
        .unwrap();
    let runtime = start(project, StoreChoice::Disabled).await;
    runtime.advance(Duration::from_millis(50)).await.unwrap();
    links_up(&runtime).await;
    // The value crossed the TLS link.
    let points = &runtime.node("TOP").unwrap().points;
    eventually("the lamp reaches TOP valid", || {
        points.point("Lamp").is_some_and(|p| {
            !p.quality.invalid && p.value == station::store::PointValue::Bool(true)
        })
    })
    .await;
    // TOP itself serves plain IEC 104 (dispatch-facing); BOARD does not talk to a client
    // without a certificate of the project's authority.
    for (address, served) in [(top, true), (board, false)] {
        let mut config = ClientConfig::new(address.to_string(), CommonAddress::new(1));
        config.reconnect = false;
        config.apci.t0 = Duration::from_secs(2);
        let (_client, mut events) = spawn_client(config);
        let started = tokio::time::timeout(Duration::from_secs(10), async {
            while let Some(event) = events.recv().await {
                match event {
                    ClientEvent::Started => return true,
                    ClientEvent::Disconnected { .. } => return false,
                    _ => {}
                }
            }
            false
        })
        .await
        .unwrap_or(false);
        assert_eq!(started, served, "{address}");
    }
    runtime.shutdown().await;
}
