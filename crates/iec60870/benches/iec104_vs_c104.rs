//! Side-by-side benchmark: our IEC 104 server against c104 (lib60870-C), each in its own
//! process, read by the same client (ours), on loopback. Prints figures and ratios.
//!
//! ```text
//! cargo bench -p iec60870 --bench iec104_vs_c104            # all three figures
//! cargo bench -p iec60870 --bench iec104_vs_c104 -- --quick  # smaller sizes
//! ```
//!
//! (a) time of a general interrogation of 100,000 points;
//! (b) spontaneous events per second from server to client;
//! (c) resident memory per idle started connection, 1,000 clients on one server.
//!
//! Our server runs as a child process of this binary (`--serve`), so both servers are
//! measured the same way. c104 is started from `tests/peer/c104_server.py`; when it is
//! not installed the c104 column says so and no ratio is printed.

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
    let sizes = if quick {
        Sizes { gi_points: 10_000, events: 20_000, connections: 200 }
    } else {
        Sizes { gi_points: 100_000, events: 100_000, connections: 1_000 }
    };
    let _ = rlimit::increase_nofile_limit(65_536);
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .enable_all()
        .build()
        .expect("runtime");
    runtime.block_on(run(sizes));
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
                    element: Element::Float { value: ioa as f32, quality: Quality::default() },
                    time: None,
                })
                .expect("point");
        }
        let started = Arc::new(tokio::sync::Notify::new());
        struct Starter(Arc<tokio::sync::Notify>);
        impl StationHandler for Starter {
            fn connection_changed(&self, _: SocketAddr, _: bool, started: bool) {
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
        config.event_buffer_capacity = events as usize + 16;
        config.send_end_of_initialisation = false;
        let server = spawn_server(config, image, handler).await.expect("server");
        println!("{{\"event\":\"ready\"}}");
        if events > 0 {
            started.notified().await;
            for index in 0..events {
                let ioa = Ioa::try_new(index % points.max(1) + 1).expect("ioa");
                let element = Element::Float { value: index as f32, quality: Quality::default() };
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

fn repository_root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Starts a server process and waits for its ready line.
fn start_server(peer: Peer, port: u16, points: u32, events: u32, connections: usize) -> Option<Child> {
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
            let script = repository_root().join("tests/peer/c104_server.py");
            if !script.exists() {
                return None;
            }
            let mut command = Command::new("python3");
            command
                .arg(script)
                .args(["--host", "127.0.0.1", "--port", &port.to_string(), "--ca", "1"])
                .args(["--points", &points.to_string(), "--point-type", "M_ME_NC_1"]);
            if events > 0 {
                command.args(["--spontaneous-count", &events.to_string(), "--spontaneous-rate", "0"]);
            }
            if connections > 0 {
                command.args(["--max-connections", &(connections + 16).to_string()]);
            }
            command
        }
    };
    let mut child = command
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
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
    tokio::time::timeout(Duration::from_secs(10), wait).await.unwrap_or(false)
}

/// (a) seconds for a station interrogation of `points` points, and the objects counted.
async fn measure_gi(peer: Peer, port: u16, points: u32) -> Option<(f64, u64)> {
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
    let mut finished = None;
    let outcome = loop {
        tokio::select! {
            result = &mut gi, if finished.is_none() => { finished = Some(result); }
            event = events.recv() => match event {
                Some(ClientEvent::Asdu(asdu)) => {
                    if asdu.cot.cause == Cause::INTERROGATED_BY_STATION {
                        objects += asdu.objects.len() as u64;
                    }
                    if asdu.type_id == TypeId::C_IC_NA_1 && asdu.cot.cause == Cause::ACTIVATION_TERMINATION {
                        break Some(began.elapsed().as_secs_f64());
                    }
                }
                Some(_) => {}
                None => break None,
            },
            () = tokio::time::sleep(Duration::from_secs(120)) => break None,
        }
    };
    client.close().await;
    stop(child);
    outcome.map(|seconds| (seconds, objects))
}

/// (b) events per second received, from the first to the last of `count`.
async fn measure_events(peer: Peer, port: u16, count: u32) -> Option<f64> {
    let child = start_server(peer, port, 100, count, 0)?;
    let (client, mut events) = spawn_client(client_config(port));
    if !wait_started(&mut events).await {
        stop(child);
        return None;
    }
    let mut received = 0u64;
    let mut first: Option<Instant> = None;
    let result = loop {
        let event = tokio::time::timeout(Duration::from_secs(30), events.recv()).await;
        match event {
            Ok(Some(ClientEvent::Asdu(asdu))) if asdu.cot.cause == Cause::SPONTANEOUS => {
                let now = Instant::now();
                first.get_or_insert(now);
                received += asdu.objects.len() as u64;
                if received >= u64::from(count) {
                    let seconds = first.map_or(0.0, |first| now.duration_since(first).as_secs_f64());
                    break Some(received as f64 / seconds.max(1e-9));
                }
            }
            Ok(Some(_)) => {}
            _ => break None,
        }
    };
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

/// (c) KiB of resident memory per idle started connection.
async fn measure_memory(peer: Peer, port: u16, connections: usize) -> Option<f64> {
    let child = start_server(peer, port, 100, 0, connections)?;
    let pid = child.id();
    tokio::time::sleep(Duration::from_millis(500)).await;
    let before = resident_kib(pid)?;
    let address = SocketAddr::from(([127, 0, 0, 1], port));
    let mut streams = Vec::with_capacity(connections);
    let mut startdt = Vec::new();
    encode_u_frame(UFunction::StartDtAct, &mut startdt);
    for _ in 0..connections {
        let Ok(mut stream) = tokio::net::TcpStream::connect(address).await else { break };
        if stream.write_all(&startdt).await.is_err() {
            break;
        }
        let mut confirmation = [0u8; 6];
        let read = tokio::time::timeout(Duration::from_secs(5), stream.read_exact(&mut confirmation)).await;
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
    if opened < connections {
        eprintln!("  {}: only {opened} of {connections} connections were accepted", peer.name());
        return None;
    }
    Some(after.saturating_sub(before) as f64 / connections as f64)
}

fn ratio_line(label: &str, ours: Option<f64>, theirs: Option<f64>, higher_is_better: bool) {
    match (ours, theirs) {
        (Some(ours), Some(theirs)) if ours > 0.0 && theirs > 0.0 => {
            let advantage = if higher_is_better { ours / theirs } else { theirs / ours };
            println!("  ratio {label}: stanice is {advantage:.2}x {}", if advantage >= 1.0 { "better" } else { "worse" });
        }
        _ => println!("  ratio {label}: not available (a side did not run)"),
    }
}

async fn run(sizes: Sizes) {
    println!("IEC 104 benchmark, stanice vs c104 (lib60870-C), loopback, separate server processes");
    let mut port = 24_500u16;
    let mut next_port = || {
        port += 1;
        port
    };

    println!("(a) general interrogation of {} M_ME_NC_1 points", sizes.gi_points);
    let mut gi = [None, None];
    for (slot, peer) in [Peer::Ours, Peer::C104].into_iter().enumerate() {
        let result = measure_gi(peer, next_port(), sizes.gi_points).await;
        match result {
            Some((seconds, objects)) => println!(
                "  {:<20} {seconds:8.3} s  {objects} objects  {:10.0} objects/s",
                peer.name(),
                objects as f64 / seconds
            ),
            None => println!("  {:<20} did not run", peer.name()),
        }
        gi[slot] = result.map(|(seconds, _)| seconds);
    }
    ratio_line("GI time", gi[0], gi[1], false);

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

    println!("(c) resident memory per idle started connection, {} clients", sizes.connections);
    let mut memory = [None, None];
    for (slot, peer) in [Peer::Ours, Peer::C104].into_iter().enumerate() {
        let kib = measure_memory(peer, next_port(), sizes.connections).await;
        match kib {
            Some(kib) => println!("  {:<20} {kib:8.1} KiB/connection", peer.name()),
            None => println!("  {:<20} did not run", peer.name()),
        }
        memory[slot] = kib;
    }
    ratio_line("memory/connection", memory[0], memory[1], false);
}
