//! Side-by-side benchmark: our IEC 104 server against c104 (lib60870-C), each in its own
//! process, read by the same client (ours), on loopback. Prints figures and ratios.
//!
//! ```text
//! cargo bench -p iec60870 --bench iec104_vs_c104            # all three figures
//! cargo bench -p iec60870 --bench iec104_vs_c104 -- --quick  # smaller sizes
//! cargo bench -p iec60870 --bench iec104_vs_c104 -- --only gi|events|memory
//! ```
//!
//! (a) time of a general interrogation of 100,000 points;
//! (b) spontaneous events per second from server to client;
//! (c) resident memory per idle started connection, 1,000 clients on one server.
//!
//! Our server runs as a child process of this binary (`--serve`), so both servers are
//! measured the same way. c104 is started from `tests/peer/c104_server.py`; when it is
//! not installed the c104 column says so and no ratio is printed.
// A benchmark harness, like a test, may stop on a broken set-up.
#![allow(
    clippy::expect_used,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing,
    // Tests and benchmarks measure and wait on the wall clock; the cores do not.
    clippy::disallowed_methods
)]
#![allow(missing_docs)]

use std::io::{BufRead, BufReader};
use std::net::SocketAddr;
use std::process::{Child, Command, Stdio};
use std::sync::Arc;
use std::time::{Duration, Instant};

use iec60870::apci::{encode_u_frame, UFunction};
use iec60870::asdu::{Cause, CommonAddress, Element, Ioa, Quality, TypeId};
use iec60870::cs104::client::{spawn_client, ClientConfig, ClientEvent};
use iec60870::cs104::server::{
    spawn_server, MonitorPoint, ProcessImage, ReadOnlyStation, ServerConfig, StationHandler,
};
use tokio::io::{AsyncReadExt, AsyncWriteExt};

struct Sizes {
    gi_points: u32,
    events: u32,
    connections: usize,
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(position) = args.iter().position(|arg| arg == "--serve") {
        serve(&args[position + 1..]);
        return;
    }
    let quick = args.iter().any(|arg| arg == "--quick");
    let only = args
        .iter()
        .position(|arg| arg == "--only")
        .and_then(|position| args.get(position + 1))
        .cloned();
    let sizes = if quick {
        Sizes {
            gi_points: 10_000,
            events: 20_000,
            connections: 200,
        }
    } else {
        Sizes {
            gi_points: 100_000,
            events: 100_000,
            connections: 1_000,
        }
    };
    let _ = rlimit::increase_nofile_limit(65_536);
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .enable_all()
        .build()
        .expect("runtime");
    runtime.block_on(run(sizes, only));
}

/// Child-process mode: our server with `points` float points; after the first client
/// starts, `events` spontaneous updates as fast as the event buffer takes them.
fn serve(args: &[String]) {
    let port: u16 = args[0].parse().expect("port");
    let points: u32 = args[1].parse().expect("points");
    let events: u32 = args[2].parse().expect("events");
    let max_connections: usize = args[3].parse().expect("max connections");
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .enable_all()
        .build()
        .expect("runtime");
    runtime.block_on(async move {
        let mut image = ProcessImage::new();
        for ioa in 1..=points {
            image
                .add_monitor(MonitorPoint {
                    ioa: Ioa::try_new(ioa).expect("ioa"),
                    event_type: TypeId::M_ME_NC_1,
                    groups: 0,
                    element: Element::Float {
                        value: ioa as f32,
                        quality: Quality::default(),
                    },
                    time: None,
                })
                .expect("point");
        }
        let started = Arc::new(tokio::sync::Notify::new());
        struct Starter(Arc<tokio::sync::Notify>);
        impl StationHandler for Starter {
            fn connection_changed(&self, _: &iec60870::outstation::Peer, _: bool, started: bool) {
                if started {
                    self.0.notify_one();
                }
            }
        }
        let handler: Arc<dyn StationHandler> = if events > 0 {
            Arc::new(Starter(Arc::clone(&started)))
        } else {
            Arc::new(ReadOnlyStation)
        };
        let mut config = ServerConfig::new(
            SocketAddr::from(([127, 0, 0, 1], port)),
            CommonAddress::new(1),
        );
        config.max_connections = max_connections;
        config.outstation.event_buffer_capacity = events as usize + 16;
        config.outstation.send_end_of_initialisation = false;
        let server = spawn_server(config, image, handler).await.expect("server");
        println!("{{\"event\":\"ready\"}}");
        if events > 0 {
            started.notified().await;
            for index in 0..events {
                let ioa = Ioa::try_new(index % points.max(1) + 1).expect("ioa");
                let element = Element::Float {
                    value: index as f32,
                    quality: Quality::default(),
                };
                server
                    .update_with_cause(ioa, element, None, Cause::SPONTANEOUS)
                    .expect("update");
                if index % 1024 == 0 {
                    tokio::task::yield_now().await;
                }
            }
        }
        std::future::pending::<()>().await;
    });
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Peer {
    Ours,
    C104,
}

impl Peer {
    fn name(self) -> &'static str {
        match self {
            Peer::Ours => "stanice",
            Peer::C104 => "c104 (lib60870-C)",
        }
    }
}

/// Starts a server process and waits for its ready line.
fn start_server(
    peer: Peer,
    port: u16,
    points: u32,
    events: u32,
    connections: usize,
) -> Option<Child> {
    let mut command = match peer {
        Peer::Ours => {
            let mut command = Command::new(std::env::current_exe().ok()?);
            command.args([
                "--serve".to_owned(),
                port.to_string(),
                points.to_string(),
                events.to_string(),
                (connections + 16).to_string(),
            ]);
            command
        }
        Peer::C104 => {
            if !testkit::peers::peer_script("c104_server.py").exists() {
                return None;
            }
            let mut command = testkit::peers::c104("c104_server.py", port);
            command
                .args([
                    "--stdin",
                    "ignore",
                    "--max-seconds",
                    "600",
                    "--tick-rate-ms",
                    "50",
                ])
                .args([
                    "--points",
                    &points.to_string(),
                    "--points-type",
                    "M_ME_NC_1",
                ]);
            if events > 0 {
                // As fast as c104 takes them, once the client has started.
                command.args(["--spontaneous-count", &events.to_string()]);
                command.args(["--spontaneous-rate", "1e9", "--spontaneous-delay", "0"]);
            }
            // c104's server takes any number of clients by default.
            let _ = connections;
            command
        }
    };
    let mut child = command
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .ok()?;
    let stdout = child.stdout.take()?;
    let mut lines = BufReader::new(stdout).lines();
    let deadline = Instant::now() + Duration::from_secs(120);
    while Instant::now() < deadline {
        match lines.next() {
            Some(Ok(line)) if line.contains("\"ready\"") => {
                // Keep draining stdout so the child never blocks on a full pipe.
                std::thread::spawn(move || for _ in lines {});
                return Some(child);
            }
            Some(Ok(_)) => continue,
            _ => break,
        }
    }
    let _ = child.kill();
    None
}

fn stop(mut child: Child) {
    let _ = child.kill();
    let _ = child.wait();
}

fn client_config(port: u16) -> ClientConfig {
    let mut config = ClientConfig::new(format!("127.0.0.1:{port}"), CommonAddress::new(1));
    config.reconnect = false;
    config.command_timeout = Duration::from_secs(120);
    config.event_capacity = 100_000;
    config
}

async fn wait_started(events: &mut tokio::sync::mpsc::Receiver<ClientEvent>) -> bool {
    let wait = async {
        while let Some(event) = events.recv().await {
            match event {
                ClientEvent::Started => return true,
                ClientEvent::Disconnected { .. } => return false,
                _ => {}
            }
        }
        false
    };
    tokio::time::timeout(Duration::from_secs(10), wait)
        .await
        .unwrap_or(false)
}

/// (a) a station interrogation of `points` points: seconds to its termination (None if
/// it never terminated: the server dropped part of its answer) and the objects counted.
async fn measure_gi(peer: Peer, port: u16, points: u32) -> Option<(Option<f64>, u64)> {
    let child = start_server(peer, port, points, 0, 0)?;
    let (client, mut events) = spawn_client(client_config(port));
    if !wait_started(&mut events).await {
        stop(child);
        return None;
    }
    let began = Instant::now();
    let gi = client.interrogate(20);
    tokio::pin!(gi);
    let mut objects = 0u64;
    let mut confirmed = false;
    let seconds = loop {
        tokio::select! {
            _ = &mut gi, if !confirmed => { confirmed = true; }
            event = tokio::time::timeout(Duration::from_secs(5), events.recv()) => match event {
                Ok(Some(ClientEvent::Asdu(asdu))) => {
                    if asdu.cot.cause == Cause::INTERROGATED_BY_STATION {
                        objects += asdu.objects.len() as u64;
                    }
                    if asdu.type_id == TypeId::C_IC_NA_1
                        && asdu.cot.cause == Cause::ACTIVATION_TERMINATION
                    {
                        break Some(began.elapsed().as_secs_f64());
                    }
                }
                Ok(Some(_)) => {}
                // Five seconds of silence or a lost connection: the answer is incomplete.
                Ok(None) | Err(_) => break None,
            },
        }
    };
    client.close().await;
    stop(child);
    Some((seconds, objects))
}

/// (b) events per second received, from the first to the last; stops at `count` or after
/// two seconds without events (a server that dropped events ends early, and says so).
async fn measure_events(peer: Peer, port: u16, count: u32) -> Option<f64> {
    let child = start_server(peer, port, 100, count, 0)?;
    let (client, mut events) = spawn_client(client_config(port));
    if !wait_started(&mut events).await {
        stop(child);
        return None;
    }
    let mut received = 0u64;
    let mut first: Option<Instant> = None;
    let mut last = Instant::now();
    loop {
        let silence = if first.is_some() { 2 } else { 30 };
        let event = tokio::time::timeout(Duration::from_secs(silence), events.recv()).await;
        match event {
            Ok(Some(ClientEvent::Asdu(asdu))) if asdu.cot.cause == Cause::SPONTANEOUS => {
                last = Instant::now();
                first.get_or_insert(last);
                received += asdu.objects.len() as u64;
                if received >= u64::from(count) {
                    break;
                }
            }
            Ok(Some(_)) => {}
            _ => break,
        }
    }
    if received < u64::from(count) {
        eprintln!("  {}: received {received} of {count} events", peer.name());
    }
    let result = first
        .filter(|_| received > 1)
        .map(|first| received as f64 / last.duration_since(first).as_secs_f64().max(1e-9));
    client.close().await;
    stop(child);
    result
}

fn resident_kib(pid: u32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    status
        .lines()
        .find(|line| line.starts_with("VmRSS:"))
        .and_then(|line| line.split_whitespace().nth(1))
        .and_then(|value| value.parse().ok())
}

/// (c) KiB of resident memory per idle started connection, and how many connections the
/// server accepted (at least one).
async fn measure_memory(peer: Peer, port: u16, connections: usize) -> Option<(f64, usize)> {
    let child = start_server(peer, port, 100, 0, connections)?;
    let pid = child.id();
    tokio::time::sleep(Duration::from_millis(500)).await;
    let before = resident_kib(pid)?;
    let address = SocketAddr::from(([127, 0, 0, 1], port));
    let mut streams = Vec::with_capacity(connections);
    let mut startdt = Vec::new();
    encode_u_frame(UFunction::StartDtAct, &mut startdt);
    for _ in 0..connections {
        let Ok(mut stream) = tokio::net::TcpStream::connect(address).await else {
            break;
        };
        if stream.write_all(&startdt).await.is_err() {
            break;
        }
        let mut confirmation = [0u8; 6];
        let read =
            tokio::time::timeout(Duration::from_secs(5), stream.read_exact(&mut confirmation))
                .await;
        if !matches!(read, Ok(Ok(_))) {
            break;
        }
        streams.push(stream);
    }
    tokio::time::sleep(Duration::from_secs(2)).await;
    let after = resident_kib(pid)?;
    let opened = streams.len();
    drop(streams);
    stop(child);
    if opened == 0 {
        return None;
    }
    Some((after.saturating_sub(before) as f64 / opened as f64, opened))
}

fn ratio_line(label: &str, ours: Option<f64>, theirs: Option<f64>, higher_is_better: bool) {
    match (ours, theirs) {
        (Some(ours), Some(theirs)) if ours > 0.0 && theirs > 0.0 => {
            let advantage = if higher_is_better {
                ours / theirs
            } else {
                theirs / ours
            };
            println!(
                "  ratio {label}: stanice is {advantage:.2}x {}",
                if advantage >= 1.0 { "better" } else { "worse" }
            );
        }
        _ => println!("  ratio {label}: not available (a side did not run)"),
    }
}

fn print_gi(peer: Peer, points: u32, result: Option<(Option<f64>, u64)>) {
    match result {
        Some((Some(seconds), objects)) => println!(
            "  {:<20} {points:>7} points {seconds:8.3} s  {objects} objects  {:10.0} objects/s",
            peer.name(),
            objects as f64 / seconds
        ),
        Some((None, objects)) => println!(
            "  {:<20} {points:>7} points  FAILED: no termination, {objects} objects arrived",
            peer.name()
        ),
        None => println!("  {:<20} {points:>7} points  did not run", peer.name()),
    }
}

async fn run(sizes: Sizes, only: Option<String>) {
    let wanted = |figure: &str| only.as_deref().is_none_or(|only| only == figure);
    println!(
        "IEC 104 benchmark, stanice vs c104 (lib60870-C), loopback, separate server processes"
    );
    let mut port = 24_500u16;
    let mut next_port = || {
        port += 1;
        port
    };

    // c104's server queues its whole GI answer into a 100-message queue and drops the
    // rest (tests/peer/README.md): the side-by-side ratio uses a size it answers whole.
    let comparable = 2_000;
    if wanted("gi") {
        println!("(a) general interrogation, M_ME_NC_1 points, read by our client");
        let ours_small = measure_gi(Peer::Ours, next_port(), comparable).await;
        print_gi(Peer::Ours, comparable, ours_small);
        let theirs_small = measure_gi(Peer::C104, next_port(), comparable).await;
        print_gi(Peer::C104, comparable, theirs_small);
        let time = |result: Option<(Option<f64>, u64)>| result.and_then(|(seconds, _)| seconds);
        ratio_line("GI time", time(ours_small), time(theirs_small), false);
        let ours_full = measure_gi(Peer::Ours, next_port(), sizes.gi_points).await;
        print_gi(Peer::Ours, sizes.gi_points, ours_full);
        let theirs_full = measure_gi(Peer::C104, next_port(), sizes.gi_points).await;
        print_gi(Peer::C104, sizes.gi_points, theirs_full);
        ratio_line(
            "GI time (full size)",
            time(ours_full),
            time(theirs_full),
            false,
        );
    }
    if wanted("events") {
        println!("(b) spontaneous events, {} M_ME_NC_1 updates", sizes.events);
        let mut rates = [None, None];
        for (slot, peer) in [Peer::Ours, Peer::C104].into_iter().enumerate() {
            let rate = measure_events(peer, next_port(), sizes.events).await;
            match rate {
                Some(rate) => println!("  {:<20} {rate:12.0} events/s", peer.name()),
                None => println!("  {:<20} did not run", peer.name()),
            }
            rates[slot] = rate;
        }
        ratio_line("events/s", rates[0], rates[1], true);
    }
    if !wanted("memory") {
        return;
    }
    println!("(c) resident memory per idle started connection");
    let theirs = measure_memory(Peer::C104, next_port(), sizes.connections).await;
    let ours = measure_memory(Peer::Ours, next_port(), sizes.connections).await;
    for (peer, result) in [(Peer::Ours, ours), (Peer::C104, theirs)] {
        match result {
            Some((kib, opened)) => println!(
                "  {:<20} {kib:8.1} KiB/connection with {opened} of {} clients accepted",
                peer.name(),
                sizes.connections
            ),
            None => println!("  {:<20} did not run", peer.name()),
        }
    }
    // Compare at the same number of connections when c104 accepted fewer.
    let (ours_same, theirs_same) = match (ours, theirs) {
        (Some((_, ours_opened)), Some((kib, opened))) if opened < ours_opened => {
            let again = measure_memory(Peer::Ours, next_port(), opened).await;
            if let Some((ours_kib, _)) = again {
                println!(
                    "  {:<20} {ours_kib:8.1} KiB/connection with {opened} clients (c104's limit)",
                    Peer::Ours.name()
                );
            }
            (again.map(|(kib, _)| kib), Some(kib))
        }
        _ => (ours.map(|(kib, _)| kib), theirs.map(|(kib, _)| kib)),
    };
    ratio_line("memory/connection", ours_same, theirs_same, false);
}
