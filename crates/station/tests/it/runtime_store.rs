//! The station runtime records into either backend: a board run alone, a command from a
//! controlling station, and what the store then holds — on SQLite and on PostgreSQL.

use std::time::Duration;

use iec60870::asdu::{CommandQualifier, CommonAddress, Element, Ioa, TypeId};
use iec60870::cs104::client::{spawn_client, ClientConfig, ClientEvent};
use station::config::Project;
use station::runtime::{Pacing, Runtime, RuntimeOptions, StoreChoice};
use station::store::{CommandOutcome, CommandQuery, EventQuery};

async fn board_records_a_command_and_its_effects(store_url: String) {
    let project = Project::load(&testkit::projects::vsetin()).unwrap();
    let base = testkit::ports::free_port();
    // RH2 listens on port_base + 2; the other nodes do not run here.
    let project = project.with_port_base(base.saturating_sub(2).max(1024));
    let runtime = Runtime::start(
        project,
        RuntimeOptions {
            nodes: vec!["RH2".into()],
            pacing: Pacing::Manual,
            start: chrono::Utc::now(),
            store: StoreChoice::Url(store_url),
            device_kinds: station::device::DeviceKinds::builtin(),
        },
    )
    .await
    .unwrap();
    runtime.advance(Duration::from_secs(1)).await.unwrap();
    let address = runtime
        .node("RH2")
        .unwrap()
        .server
        .as_ref()
        .unwrap()
        .local_addr();
    let (client, mut events) = spawn_client(ClientConfig::new(
        address.to_string(),
        CommonAddress::new(21),
    ));
    loop {
        match tokio::time::timeout(Duration::from_secs(10), events.recv()).await {
            Ok(Some(ClientEvent::Started)) => break,
            Ok(Some(_)) => {}
            other => panic!("no start: {other:?}"),
        }
    }
    let outcome = client
        .command(
            TypeId::C_SC_NA_1,
            Ioa::try_new(2021).unwrap(),
            Element::SingleCommand {
                on: true,
                qualifier: CommandQualifier::EXECUTE,
            },
            None,
        )
        .await
        .unwrap();
    assert!(outcome.positive);
    runtime.advance(Duration::from_secs(1)).await.unwrap();
    runtime.recorder().flush().await;
    let store = runtime.store().unwrap();
    let commands = store
        .query_commands(&CommandQuery::default())
        .await
        .unwrap()
        .items;
    assert_eq!(commands.len(), 1, "{commands:?}");
    assert_eq!(commands[0].node, "RH2");
    assert_eq!(commands[0].point, "RH2_VypnoutQF1");
    assert_eq!(commands[0].outcome, CommandOutcome::Executed);
    assert!(commands[0].actor.name().starts_with("127.0.0.1:"));
    let busbar = store
        .query_events(&EventQuery::default().with_point("RH2_P1_KHU3_Napeti_na_pripojeni"))
        .await
        .unwrap()
        .items;
    // Newest first: the busbar lost its voltage after QF1 opened, and was live at start.
    assert_eq!(busbar.len(), 2, "{busbar:?}");
    assert_eq!(busbar[0].value, station::store::PointValue::Bool(false));
    client.close().await;
    runtime.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn runtime_records_into_sqlite() {
    let dir = tempfile::tempdir().unwrap();
    let url = format!("sqlite:{}", dir.path().join("events.db").display());
    board_records_a_command_and_its_effects(url).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn runtime_records_into_postgresql() {
    let Some(url) = crate::pg::postgres_url("runtime_records_into_postgresql") else {
        return;
    };
    let (schema, store_url) = crate::pg::postgres_schema(&url, "runtime").await;
    board_records_a_command_and_its_effects(store_url).await;
    if let Ok(admin) = crate::pg::admin(&url).await {
        let _ = admin
            .batch_execute(&format!("DROP SCHEMA IF EXISTS {schema} CASCADE"))
            .await;
    }
}
