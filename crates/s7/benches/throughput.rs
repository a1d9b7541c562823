//! S7 reads of 100 items (DB1.DBW0 .. DB1.DBW198, one `read_values` call, split into jobs
//! by the PDU size as the client does) against our server and against python-snap7's
//! (the Snap7 library's server), side by side in one run, as requests per second and
//! their ratio. Both serve DB1 on loopback; the client is ours in both rows, so the rows
//! compare the servers.
//!
//!     cargo bench -p s7 --bench throughput
//!
//! `BENCH_SECONDS` (default 3) sets each row's measuring time. Without python-snap7 the
//! snap7 row says so and the bench still measures ours.

#![allow(
    clippy::disallowed_methods, // a benchmark measures wall-clock time
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    missing_docs
)]

use std::io::{BufRead as _, BufReader};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use s7::io::{serve, Client};
use s7::{Address, ClientConfig, Memory, ServerConfig, Tsaps};

const ITEMS: usize = 100;
const DB_SIZE: usize = 400;

fn seconds() -> Duration {
    Duration::from_secs_f64(
        std::env::var("BENCH_SECONDS")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(3.0),
    )
}

fn items() -> Vec<Address> {
    (0..ITEMS)
        .map(|i| format!("DB1.DBW{}", 2 * i).parse().unwrap())
        .collect()
}

/// Requests per second of 100-item reads against `address` for `duration`, and what the
/// server granted (PDU size, jobs open at once).
async fn measure(address: SocketAddr, duration: Duration) -> (f64, s7::io::Negotiated) {
    let client = Client::connect(
        address,
        ClientConfig::new(Tsaps::rack_slot(0, 1)),
        Duration::from_secs(5),
    )
    .await
    .unwrap();
    let items = items();
    for _ in 0..20 {
        client.read_values(&items).await.unwrap();
    }
    let start = Instant::now();
    let mut requests = 0u64;
    while start.elapsed() < duration {
        let results = client.read_values(&items).await.unwrap();
        assert!(results.iter().all(Result::is_ok));
        requests += 1;
    }
    (
        requests as f64 / start.elapsed().as_secs_f64(),
        client.negotiated(),
    )
}

/// python-snap7's server, if it can be started: its process and address.
fn snap7_server() -> Option<(Child, SocketAddr)> {
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/peer/snap7_server.py");
    let mut child = Command::new("python3")
        .arg(script)
        .args(["--db", &format!("1:{DB_SIZE}")])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .ok()?;
    let mut line = String::new();
    BufReader::new(child.stdout.as_mut()?)
        .read_line(&mut line)
        .ok()?;
    let ready: serde_json::Value = serde_json::from_str(&line).ok()?;
    let port = u16::try_from(ready.get("port")?.as_u64()?).ok()?;
    Some((child, SocketAddr::from(([127, 0, 0, 1], port))))
}

fn main() {
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    let duration = seconds();
    let our_server = |max_jobs: u16| {
        runtime.block_on(async {
            let mut memory = Memory::default();
            memory.add_data_block(1, DB_SIZE).unwrap();
            let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
            let address = listener.local_addr().unwrap();
            let (events, mut received) = tokio::sync::mpsc::channel(1024);
            tokio::spawn(async move { while received.recv().await.is_some() {} });
            // the PDU an S7-300 grants, as python-snap7's server does
            let mut config = ServerConfig::default();
            config.max_pdu_size = 480;
            config.max_jobs = max_jobs;
            let server = tokio::spawn(serve(
                listener,
                Arc::new(Mutex::new(memory)),
                config,
                events,
            ));
            let measured = measure(address, duration).await;
            server.abort();
            measured
        })
    };
    let row = |name: &str, (rate, granted): (f64, s7::io::Negotiated)| {
        println!(
            "  {name:<26} {rate:>9.0} requests/s  ({:.0} items/s, PDU {}, {} jobs at once)",
            rate * ITEMS as f64,
            granted.pdu_size,
            granted.max_jobs
        );
    };
    println!("S7 reads of {ITEMS} items (DB1.DBW0..DBW198), {duration:?} each, our client:");
    let ours = our_server(3);
    row("our server", ours);
    let ours_one_job = our_server(1);
    row("our server, one job", ours_one_job);
    match snap7_server() {
        Some((mut child, address)) => {
            let snap7 = runtime.block_on(measure(address, duration));
            let _ = child.kill();
            let _ = child.wait();
            row("python-snap7", snap7);
            println!(
                "  ratio ours / snap7: {:.2} (one job at once each: {:.2})",
                ours.0 / snap7.0,
                ours_one_job.0 / snap7.0
            );
        }
        None => {
            println!("  python-snap7               not installed (scripts/install-test-deps.sh installs it)")
        }
    }
}
