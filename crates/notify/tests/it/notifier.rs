//! Quiet period, rate limit and the queue, end to end through a webhook receiver.

use std::sync::Arc;

use axum::extract::State;
use axum::http::StatusCode;
use axum::routing::post;
use axum::{Json, Router};
use chrono::TimeDelta;
use notify::{spawn_notifier, Notifier, Outcome, RateLimit};
use tokio::sync::{mpsc, Semaphore};

use crate::support::{config, notice, rule, serve, t0, webhook};
use crate::webhook::receiver;

#[tokio::test]
async fn quiet_period_and_rate_limit() {
    let (url, mut rx) = receiver().await;
    let mut limited = rule("lift-faults", &["tickets"], 600);
    limited.rate_limit = Some(RateLimit {
        max: 2,
        per_s: 3600,
    });
    let mut notifier = Notifier::new(config(
        None,
        vec![("tickets", webhook(&url))],
        vec![limited],
    ))
    .unwrap();
    let at = |s: i64| t0() + TimeDelta::seconds(s);

    let steps = [
        (0, "L1", Outcome::Sent, ""),
        (
            10,
            "L1",
            Outcome::Suppressed,
            "quiet period until 2026-03-01T08:25:00Z",
        ),
        (20, "L2", Outcome::Sent, ""),
        (
            30,
            "L3",
            Outcome::Suppressed,
            "rate limit until 2026-03-01T09:15:00Z",
        ),
        (3600, "L3", Outcome::Sent, ""),
    ];
    for (s, source, outcome, detail) in steps {
        let deliveries = notifier.notify_at(&notice(source, "door"), at(s)).await;
        assert_eq!(deliveries.len(), 1);
        assert_eq!(
            deliveries[0].outcome, outcome,
            "at {s}: {:#?}",
            deliveries[0]
        );
        if outcome == Outcome::Suppressed {
            assert_eq!(deliveries[0].detail, detail);
        }
    }
    let mut received = Vec::new();
    while received.len() < 3 {
        received.push(rx.recv().await.unwrap().0["source"].clone());
    }
    assert_eq!(received, ["L1", "L2", "L3"]);
    assert!(rx.try_recv().is_err());
}

#[tokio::test]
async fn no_matching_rule_no_delivery() {
    let (url, _rx) = receiver().await;
    let mut lifts = rule("lifts", &["tickets"], 600);
    lifts.sources = vec![notify::Pattern::new("L*")];
    let mut notifier =
        Notifier::new(config(None, vec![("tickets", webhook(&url))], vec![lifts])).unwrap();
    assert!(notifier
        .notify_at(&notice("P1", "door"), t0())
        .await
        .is_empty());
}

#[tokio::test]
async fn full_queue_records_suppressed() {
    // The receiver holds each request until the test lets it go.
    let gate = Arc::new(Semaphore::new(0));
    let (arrived_tx, mut arrived) = mpsc::unbounded_channel::<String>();
    let router = Router::new()
        .route(
            "/hook",
            post(
                |State((gate, arrived)): State<(Arc<Semaphore>, mpsc::UnboundedSender<String>)>,
                 Json(body): Json<serde_json::Value>| async move {
                    arrived
                        .send(body["source"].as_str().unwrap().to_owned())
                        .unwrap();
                    gate.acquire().await.unwrap().forget();
                    StatusCode::OK
                },
            ),
        )
        .with_state((Arc::clone(&gate), arrived_tx));
    let address = serve(router).await;
    let notifier = Notifier::new(config(
        None,
        vec![("tickets", webhook(&format!("http://{address}/hook")))],
        vec![rule("lift-faults", &["tickets"], 0)],
    ))
    .unwrap();
    let (handle, mut deliveries, task) = spawn_notifier(notifier, 1);

    assert!(handle.submit(notice("L1", "door")).is_empty());
    assert_eq!(arrived.recv().await.unwrap(), "L1"); // the task is busy with L1
    assert!(handle.submit(notice("L2", "door")).is_empty()); // queued
    let refused = handle.submit_at(notice("L3", "door"), t0());
    assert_eq!(refused.len(), 1);
    assert_eq!(refused[0].outcome, Outcome::Suppressed);
    assert_eq!(refused[0].detail, "queue full");
    assert_eq!(refused[0].source, "L3");
    assert_eq!(refused[0].rule, "lift-faults");
    assert_eq!(refused[0].channel, "tickets");

    gate.add_permits(2);
    let first = deliveries.recv().await.unwrap();
    let second = deliveries.recv().await.unwrap();
    assert_eq!(
        (first.source.as_str(), first.outcome),
        ("L1", Outcome::Sent)
    );
    assert_eq!(
        (second.source.as_str(), second.outcome),
        ("L2", Outcome::Sent)
    );

    drop(handle);
    task.await.unwrap();
}
