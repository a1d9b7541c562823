//! The drive loop around a protocol-free endpoint over TCP and a pseudo-terminal: octets
//! in and out, the line pause after a burst, actions from outside, the end of the stream.

use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use serial_line::io::{drive, DriveEnd, EndpointAction, LineListener, Transport};
use serial_line::{LineEndpoint, LineSettings, Parity};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::sync::mpsc;

/// Answers each burst of octets, once the line has paused, with the burst upper-cased;
/// counts the pauses.
struct Shout {
    line: LineSettings,
    burst: Vec<u8>,
    answer: Option<Vec<u8>>,
    pauses: usize,
}

impl Shout {
    fn new(line: LineSettings) -> Shout {
        Shout {
            line,
            burst: Vec::new(),
            answer: None,
            pauses: 0,
        }
    }
}

impl LineEndpoint for Shout {
    fn handle_bytes(&mut self, _now: Instant, bytes: &[u8]) {
        self.burst.extend_from_slice(bytes);
    }
    fn handle_line_pause(&mut self, _now: Instant) {
        self.pauses += 1;
        self.answer = Some(std::mem::take(&mut self.burst).to_ascii_uppercase());
    }
    fn handle_timeout(&mut self, _now: Instant) {}
    fn poll_transmit(&mut self, _now: Instant) -> Option<Vec<u8>> {
        self.answer.take()
    }
    fn next_deadline(&self) -> Option<Instant> {
        None
    }
    fn line(&self) -> LineSettings {
        self.line
    }
}

async fn read_exactly(stream: &mut (impl AsyncReadExt + Unpin), count: usize) -> Vec<u8> {
    let mut buf = vec![0; count];
    tokio::time::timeout(Duration::from_secs(10), stream.read_exact(&mut buf))
        .await
        .expect("an answer within 10 s")
        .expect("read");
    buf
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_endpoint_answers_after_the_pause_over_tcp_until_the_peer_closes() {
    let listener = LineListener::bind("127.0.0.1:0").await.unwrap();
    let address = listener.local_addr().unwrap().to_string();
    let (actions, mut inbox) = mpsc::unbounded_channel::<EndpointAction<Shout>>();
    let served = tokio::spawn(async move {
        let line = listener.accept().await.unwrap();
        let mut shout = Shout::new(LineSettings::new(115_200));
        let end = drive(line.stream, &mut shout, &mut inbox, |_| {
            ControlFlow::Continue(())
        })
        .await;
        (end.unwrap(), shout.pauses)
    });
    let mut peer = tokio::net::TcpStream::connect(&address).await.unwrap();
    peer.write_all(b"hello").await.unwrap();
    assert_eq!(read_exactly(&mut peer, 5).await, b"HELLO");
    // An action reaches the endpoint between two wake-ups.
    actions
        .send(Box::new(|shout: &mut Shout| {
            shout.answer = Some(b"!".to_vec());
        }))
        .unwrap();
    assert_eq!(read_exactly(&mut peer, 1).await, b"!");
    peer.write_all(b"again").await.unwrap();
    assert_eq!(read_exactly(&mut peer, 5).await, b"AGAIN");
    drop(peer);
    let (end, pauses) = served.await.unwrap();
    assert_eq!(end, DriveEnd::Closed);
    assert_eq!(pauses, 2);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_observer_stops_the_loop_over_a_pseudo_terminal() {
    let line = LineSettings {
        parity: Parity::None,
        ..LineSettings::new(9600)
    };
    let ours = Transport::Pty.open().await.unwrap();
    let path = ours.pty_path.clone().unwrap();
    let theirs = Transport::Serial { path, line }.open().await.unwrap();
    let (_keep, mut inbox) = mpsc::unbounded_channel::<EndpointAction<Shout>>();
    let served = tokio::spawn(async move {
        // The whole line moves in: it holds the pseudo-terminal's other end open.
        let ours = ours;
        let mut shout = Shout::new(line);
        drive(ours.stream, &mut shout, &mut inbox, |shout| {
            if shout.pauses == 1 {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        })
        .await
    });
    let mut stream = theirs.stream;
    stream.write_all(b"stop").await.unwrap();
    let end = tokio::time::timeout(Duration::from_secs(10), served)
        .await
        .expect("stopped within 10 s")
        .unwrap();
    assert_eq!(end.unwrap(), DriveEnd::Stopped);
}
