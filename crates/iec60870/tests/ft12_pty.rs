//! The FT1.2 primary and secondary over a real pseudo-terminal pair and over TCP, with
//! the tokio line driver: what a serial cable between two programs does.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

use std::collections::VecDeque;
use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use iec60870::ft12::io::{drive, DriveEnd, LineListener, Transport};
use iec60870::ft12::*;
use tokio::sync::mpsc;

/// A secondary application with a fixed queue of class 1 data.
struct Events {
    class1: VecDeque<Vec<u8>>,
    received: Vec<Vec<u8>>,
}

impl SecondaryApplication for Events {
    fn link_reset(&mut self, _function: PrimaryFunction) {}
    fn user_data(&mut self, asdu: &[u8], _broadcast: bool) -> bool {
        self.received.push(asdu.to_vec());
        true
    }
    fn has_class1(&self) -> bool {
        !self.class1.is_empty()
    }
    fn class1(&mut self) -> Option<Vec<u8>> {
        self.class1.pop_front()
    }
    fn class2(&mut self) -> Option<Vec<u8>> {
        None
    }
}

impl TimedApplication for Events {
    fn handle_timeout(&mut self, _now: Instant) {}
    fn next_deadline(&self) -> Option<Instant> {
        None
    }
}

fn station() -> SecondaryStation<Events> {
    SecondaryStation::new(
        LineSettings::new(19200),
        Secondary::new(SecondaryConfig::new(1)),
        Events {
            class1: (0..20u8)
                .map(|n| vec![0x01, 0x81, 0x01, 0x01, 0xA0, n])
                .collect(),
            received: Vec::new(),
        },
    )
}

fn primary() -> Primary {
    let mut primary = Primary::new(
        PrimaryConfig {
            line: LineSettings::new(19200),
            response_timeout: Duration::from_millis(500),
            retries: 3,
            poll_interval: Duration::from_millis(20),
            ..PrimaryConfig::default()
        },
        tokio::time::Instant::now().into_std(),
    );
    primary.add_station(1).unwrap();
    primary
        .send(1, vec![0x07, 0x81, 0x09, 0x01, 0xFF, 0x00, 0x05])
        .unwrap();
    primary
}

/// Runs the primary until all 20 events and the confirmation of the user data arrived
/// (or 30 s passed: a failure, never a wait that decides the result).
async fn poll_all(line: iec60870::ft12::io::OpenLine) -> Vec<Vec<u8>> {
    let mut primary = primary();
    let (_keep, mut actions) = mpsc::unbounded_channel();
    let mut data = Vec::new();
    let mut confirmed = false;
    let end = tokio::time::timeout(
        Duration::from_secs(30),
        drive(line.stream, &mut primary, &mut actions, |primary| {
            while let Some(event) = primary.poll_event() {
                if let PrimaryEvent::Exchange {
                    request, answer, ..
                } = event
                {
                    match answer {
                        Answer::UserData(asdu) => data.push(asdu),
                        Answer::Ack if request == PrimaryFunction::UserDataConfirmed => {
                            confirmed = true
                        }
                        _ => {}
                    }
                }
            }
            if data.len() == 20 && confirmed {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        }),
    )
    .await
    .expect("all data within 30 s")
    .expect("no I/O error");
    assert_eq!(end, DriveEnd::Stopped);
    data
}

fn expected() -> Vec<Vec<u8>> {
    (0..20u8)
        .map(|n| vec![0x01, 0x81, 0x01, 0x01, 0xA0, n])
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn primary_and_secondary_over_a_pseudo_terminal() {
    let secondary_line = Transport::Pty.open().await.expect("a pty pair");
    let path = secondary_line.pty_path.clone().expect("pty path");
    let secondary = tokio::spawn(async move {
        let mut station = station();
        let (_keep, mut actions) = mpsc::unbounded_channel();
        let _ = drive(secondary_line.stream, &mut station, &mut actions, |_| {
            ControlFlow::Continue(())
        })
        .await;
    });
    // A pseudo-terminal keeps no parity: 8N1, or the port refuses FT1.2's 8E1.
    let primary_line = Transport::Serial {
        path,
        line: LineSettings {
            parity: Parity::None,
            ..LineSettings::new(19200)
        },
    }
    .open()
    .await
    .expect("open the pty as a serial port");
    assert_eq!(poll_all(primary_line).await, expected());
    secondary.abort();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn primary_and_secondary_over_tcp() {
    let listener = LineListener::bind("127.0.0.1:0").await.expect("bind");
    let address = listener.local_addr().expect("address").to_string();
    let secondary = tokio::spawn(async move {
        let line = listener.accept().await.expect("a peer");
        let mut station = station();
        let (_keep, mut actions) = mpsc::unbounded_channel();
        let _ = drive(line.stream, &mut station, &mut actions, |_| {
            ControlFlow::Continue(())
        })
        .await;
    });
    let line = Transport::Connect(address).open().await.expect("connect");
    assert_eq!(poll_all(line).await, expected());
    secondary.abort();
}
