//! E-mail against aiosmtpd on loopback, and against a refused port.

use std::time::{Duration, Instant};

use notify::{Notifier, Outcome};

use crate::support::{config, email, notice, rule, smtp_plain, t0};
use testkit::ports::free_port;
use testkit::smtp::{smtp_peer_available, SmtpSink};

#[tokio::test]
async fn delivers_czech_plain_text_mail() {
    if !smtp_peer_available() {
        return;
    }
    let sink = SmtpSink::start();
    let mut notifier = Notifier::new(config(
        Some(smtp_plain(sink.port, 10)),
        vec![(
            "technicians",
            email(&["novak@example.cz", "Jana Dvořáková <dvorakova@example.cz>"]),
        )],
        vec![rule("lift-faults", &["technicians"], 600)],
    ))
    .unwrap();

    let deliveries = notifier
        .notify_at(&notice("L3", "safety-circuit"), t0())
        .await;
    assert_eq!(deliveries.len(), 2, "{deliveries:#?}");
    for delivery in &deliveries {
        assert_eq!(delivery.outcome, Outcome::Sent, "{delivery:#?}");
        assert!(delivery.detail.starts_with("250"), "{}", delivery.detail);
        assert_eq!(delivery.kind.as_str(), "email");
        assert_eq!(delivery.rule, "lift-faults");
        assert_eq!(delivery.channel, "technicians");
        assert_eq!(delivery.source, "L3");
        assert_eq!(delivery.subject, "[L3] Porucha bezpečnostního okruhu");
        assert_eq!(delivery.time, t0());
    }
    assert_eq!(deliveries[0].recipient, "novak@example.cz");

    let mut mails = sink.wait_for(2);
    mails.sort_by_key(|mail| mail["rcpt_tos"][0].as_str().unwrap().to_owned());
    assert_eq!(
        mails[0]["rcpt_tos"],
        serde_json::json!(["dvorakova@example.cz"])
    );
    assert_eq!(
        mails[1]["rcpt_tos"],
        serde_json::json!(["novak@example.cz"])
    );
    for mail in &mails {
        assert_eq!(mail["mail_from"], "stanice@example.cz");
        assert_eq!(mail["subject"], "[L3] Porucha bezpečnostního okruhu");
        assert_eq!(mail["content_type"], "text/plain");
        assert_eq!(mail["charset"], "utf-8");
        // Mail lines end in CRLF on the wire.
        let body = mail["body"].as_str().unwrap().replace("\r\n", "\n");
        assert!(
            body.contains("Rozpojen bezpečnostní okruh – dveře šachty ve 3. patře.\nKabina stojí."),
            "{body}"
        );
        assert!(body.contains("Code: 17"), "{body}");
        assert!(body.contains("Time: 2026-03-01 08:15:00 UTC"), "{body}");
        assert!(
            body.contains("Link: https://stanice.example.cz/lifts/L3"),
            "{body}"
        );
    }
    assert!(mails[0]["to"].as_str().unwrap().contains("Dvořáková"));
}

#[tokio::test]
async fn refused_connection_is_a_failed_delivery_within_the_timeout() {
    let port = free_port(); // nobody listens on it
    let mut notifier = Notifier::new(config(
        Some(smtp_plain(port, 3)),
        vec![("technicians", email(&["novak@example.cz"]))],
        vec![rule("lift-faults", &["technicians"], 600)],
    ))
    .unwrap();
    let started = Instant::now();
    let deliveries = notifier.notify_at(&notice("L3", "door"), t0()).await;
    assert!(started.elapsed() < Duration::from_secs(4));
    assert_eq!(deliveries.len(), 1);
    assert_eq!(deliveries[0].outcome, Outcome::Failed);
    assert!(!deliveries[0].detail.is_empty());
    eprintln!("refused: {}", deliveries[0].detail);
}

#[tokio::test]
async fn silent_server_times_out() {
    // Accepts the connection but never greets: the time-out must end the attempt.
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    let mut notifier = Notifier::new(config(
        Some(smtp_plain(port, 1)),
        vec![("technicians", email(&["novak@example.cz"]))],
        vec![rule("lift-faults", &["technicians"], 600)],
    ))
    .unwrap();
    let started = Instant::now();
    let deliveries = notifier.notify_at(&notice("L3", "door"), t0()).await;
    assert!(
        started.elapsed() < Duration::from_secs(3),
        "{:?}",
        started.elapsed()
    );
    assert_eq!(deliveries[0].outcome, Outcome::Failed);
    assert!(
        deliveries[0].detail.contains("timed out") || deliveries[0].detail.contains("time"),
        "{}",
        deliveries[0].detail
    );
    drop(listener);
}
