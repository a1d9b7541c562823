//! The live WebSocket's batched frames (`/api/live?batch=1`) are paced: a burst of changes
//! the station's link delivers one by one over some tens of milliseconds reaches the
//! browser as a few frames, not as one frame per change (each frame costs the browser an
//! IPC hop and a task, and a change queued behind hundreds of them showed late), while a
//! change after a quiet while still goes at once.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

#[path = "support/http.rs"]
mod http_client;
use http_client::Client;
#[path = "support/outstation.rs"]
mod outstation;
use outstation::{float, float_outstation, hmi_of};

use std::time::{Duration, Instant};

use futures_util::StreamExt as _;
use iec60870::asdu::Ioa;
use serde_json::Value;

const POINTS: u32 = 1_000;
/// The HMI's least time between two batched frames (`web::live::PACE`).
const PACE: Duration = Duration::from_millis(2);

fn screens(dir: &std::path::Path) {
    let mut csv = String::from("ioa,type,name,description\n");
    for i in 1..=POINTS {
        csv.push_str(&format!("{i},M_ME_NC_1,P{i:04},measurement {i}\n"));
    }
    std::fs::write(dir.join("points.csv"), csv).unwrap();
    std::fs::write(dir.join("hmi.toml"), "title = \"frames\"\n").unwrap();
    let mut users = hmi::users::Users::load(&dir.join("users.toml")).unwrap();
    users.add("viewer", 0, "viewer-password").unwrap();
}

/// Every point message in a live frame (an array with batch=1).
fn points_in(frame: &Value) -> Vec<(String, f64)> {
    frame
        .as_array()
        .expect("batched frames are arrays")
        .iter()
        .filter(|message| message["type"] == "point")
        .map(|message| {
            (
                message["name"].as_str().unwrap().to_owned(),
                message["value"].as_f64().unwrap(),
            )
        })
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_trickling_burst_arrives_in_few_frames_and_a_lone_change_at_once() {
    let server = float_outstation(POINTS).await;
    let dir = tempfile::tempdir().unwrap();
    screens(dir.path());
    let hmi = hmi_of(&server, dir.path()).await;
    let viewer = Client::login(hmi.address, "viewer", "viewer-password").await;
    let mut request =
        tokio_tungstenite::tungstenite::client::IntoClientRequest::into_client_request(format!(
            "ws://{}/api/live?batch=1",
            hmi.address
        ))
        .unwrap();
    request
        .headers_mut()
        .insert("Cookie", viewer.cookie.parse().unwrap());
    let (mut socket, _) = tokio_tungstenite::connect_async(request).await.unwrap();
    let mut next = async || -> Value {
        let frame = tokio::time::timeout(Duration::from_secs(10), socket.next())
            .await
            .expect("a live frame in time")
            .unwrap()
            .unwrap();
        serde_json::from_str(frame.to_text().unwrap()).unwrap()
    };
    // The snapshot; the interrogation's values, in it or after it, until every point is
    // valid.
    let snapshot = next().await;
    assert_eq!(snapshot["type"], "snapshot");
    let mut valid: std::collections::HashSet<String> = snapshot["points"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|point| point["invalid"] == false && point["value"].is_number())
        .map(|point| point["name"].as_str().unwrap().to_owned())
        .collect();
    for _ in 0..10_000 {
        if valid.len() == POINTS as usize {
            break;
        }
        valid.extend(points_in(&next().await).into_iter().map(|(name, _)| name));
    }
    assert_eq!(valid.len(), POINTS as usize, "the interrogation's values");

    // A burst trickling in: each point changed once, one after another from a thread of
    // its own, until the browser has all of them.
    let started = Instant::now();
    let producer = {
        let server = server.clone();
        std::thread::spawn(move || {
            for i in 1..=POINTS {
                server
                    .update(Ioa::try_new(i).unwrap(), float(1.0), None)
                    .unwrap();
                std::thread::sleep(Duration::from_micros(50));
            }
        })
    };
    let mut changed = std::collections::HashSet::new();
    let mut frames = 0u32;
    for _ in 0..10_000 {
        if changed.len() == POINTS as usize {
            break;
        }
        let points = points_in(&next().await);
        frames += u32::from(!points.is_empty());
        changed.extend(
            points
                .into_iter()
                .filter(|(_, value)| *value == 1.0)
                .map(|(name, _)| name),
        );
    }
    let span = started.elapsed();
    producer.join().unwrap();
    assert_eq!(changed.len(), POINTS as usize, "every change arrived");
    // Frames leave at least PACE apart, all within the span (one more: a frame of the
    // interrogation's last values may have left just before it): however slow the
    // machine, no more than this. Unpaced, this trickle made a frame per millisecond.
    let most = (span.as_secs_f64() / PACE.as_secs_f64()).floor() as u32 + 2;
    assert!(
        frames <= most,
        "{frames} frames for {POINTS} changes over {span:?} (at most {most} at one per {PACE:?})"
    );
    assert!(frames >= 2, "{frames} frames: the burst was not trickling");

    // A lone change after a quiet while arrives alone, in a frame of its own.
    tokio::time::sleep(PACE * 5).await;
    server
        .update(Ioa::try_new(7).unwrap(), float(2.0), None)
        .unwrap();
    let lone = points_in(&next().await);
    assert_eq!(lone, [("P0007".to_owned(), 2.0)]);
    hmi.shutdown().await;
    server.shutdown();
}
