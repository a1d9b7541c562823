//! Webhooks against axum servers on loopback.

use axum::extract::State;
use axum::http::{HeaderMap, StatusCode};
use axum::routing::post;
use axum::{Json, Router};
use notify::{ChannelConfig, Notifier, Outcome};
use tokio::sync::mpsc;

use crate::support::{config, notice, rule, serve, t0, webhook};

/// A receiver that forwards each JSON body and its Authorization header.
pub(crate) async fn receiver() -> (
    String,
    mpsc::UnboundedReceiver<(serde_json::Value, Option<String>)>,
) {
    let (tx, rx) = mpsc::unbounded_channel();
    let router = Router::new()
        .route(
            "/hook",
            post(
                |State(tx): State<mpsc::UnboundedSender<(serde_json::Value, Option<String>)>>,
                 headers: HeaderMap,
                 Json(body): Json<serde_json::Value>| async move {
                    let auth = headers
                        .get("authorization")
                        .map(|v| v.to_str().unwrap().to_owned());
                    tx.send((body, auth)).unwrap();
                    StatusCode::NO_CONTENT
                },
            ),
        )
        .with_state(tx);
    let address = serve(router).await;
    (format!("http://{address}/hook"), rx)
}

#[tokio::test]
async fn posts_the_notice_as_json() {
    let (url, mut rx) = receiver().await;
    let channel: ChannelConfig = toml::from_str(&format!(
        "kind = \"webhook\"\nurl = \"{url}\"\nheaders = {{ Authorization = \"Bearer 0123\" }}"
    ))
    .unwrap();
    let mut notifier = Notifier::new(config(
        None,
        vec![("tickets", channel)],
        vec![rule("lift-faults", &["tickets"], 600)],
    ))
    .unwrap();
    let deliveries = notifier
        .notify_at(&notice("L3", "safety-circuit"), t0())
        .await;
    assert_eq!(deliveries.len(), 1);
    let delivery = &deliveries[0];
    assert_eq!(delivery.outcome, Outcome::Sent, "{delivery:#?}");
    assert_eq!(delivery.detail, "HTTP 204 No Content");
    assert_eq!(delivery.kind.as_str(), "webhook");
    assert_eq!(delivery.recipient, url);

    let (body, auth) = rx.recv().await.unwrap();
    assert_eq!(auth.as_deref(), Some("Bearer 0123"));
    assert_eq!(
        body,
        serde_json::json!({
            "source": "L3",
            "class": "safety-circuit",
            "code": 17,
            "title": "Porucha bezpečnostního okruhu",
            "text": "Rozpojen bezpečnostní okruh – dveře šachty ve 3. patře.\nKabina stojí.",
            "time": "2026-03-01T08:15:00Z",
            "link": "https://stanice.example.cz/lifts/L3",
            "rule": "lift-faults",
        })
    );
}

#[tokio::test]
async fn server_error_is_a_failed_delivery() {
    let router = Router::new().route(
        "/hook",
        post(|| async { (StatusCode::INTERNAL_SERVER_ERROR, "boom") }),
    );
    let address = serve(router).await;
    let mut notifier = Notifier::new(config(
        None,
        vec![("tickets", webhook(&format!("http://{address}/hook")))],
        vec![rule("lift-faults", &["tickets"], 600)],
    ))
    .unwrap();
    let deliveries = notifier.notify_at(&notice("L3", "door"), t0()).await;
    assert_eq!(deliveries.len(), 1);
    assert_eq!(deliveries[0].outcome, Outcome::Failed);
    assert_eq!(deliveries[0].detail, "HTTP 500 Internal Server Error");
}

#[tokio::test]
async fn unreachable_webhook_is_a_failed_delivery() {
    let port = testkit::ports::free_port();
    let mut notifier = Notifier::new(config(
        None,
        vec![("tickets", webhook(&format!("http://127.0.0.1:{port}/hook")))],
        vec![rule("lift-faults", &["tickets"], 600)],
    ))
    .unwrap();
    let deliveries = notifier.notify_at(&notice("L3", "door"), t0()).await;
    assert_eq!(deliveries[0].outcome, Outcome::Failed);
    assert!(!deliveries[0].detail.is_empty());
    eprintln!("unreachable: {}", deliveries[0].detail);
}
