//! Modbus TCP reads of 125 holding registers (FC 3, the most one request may ask for)
//! against our server (`modbus::io::serve_tcp`) and against pymodbus 3.16's
//! (`tests/peer/pymodbus_server.py`), side by side in one run: requests per second,
//! registers per second and their ratio. Both serve unit 1 with the same holding
//! registers (0..9 = 100..109) on loopback; the client is ours in both rows, one request
//! at a time, so the rows compare the servers.
//!
//!     cargo bench -p modbus --bench throughput
//!
//! `BENCH_SECONDS` (default 3) sets each row's measuring time, after a warm-up. Without
//! pymodbus the pymodbus row says so and the bench still measures ours.

#![allow(
    clippy::disallowed_methods, // a benchmark measures wall-clock time (Instant::now)
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    missing_docs
)]

use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::Command;
use std::time::{Duration, Instant};

use modbus::io::serve_tcp;
use modbus::{Client, ClientConfig, DataModel, ModelConfig, Table, Transport, Units, Values};
use testkit::peers::python_imports;
use testkit::ports::free_port;
use testkit::process::{start_until_line, Background};

/// Registers per request: FC 3's maximum.
const REGISTERS: u16 = 125;
const UNIT: u8 = 1;
/// Requests before a row's clock starts.
const WARM_UP: usize = 200;

fn seconds() -> Duration {
    Duration::from_secs_f64(
        std::env::var("BENCH_SECONDS")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(3.0),
    )
}

/// Holding registers 0..125 as both servers hold them.
fn expected() -> Values {
    Values::Registers(
        (0..REGISTERS)
            .map(|i| if i < 10 { 100 + i } else { 0 })
            .collect(),
    )
}

/// Requests per second of 125-register reads against `address` for `duration`, and the
/// mean round trip.
async fn measure(address: SocketAddr, duration: Duration) -> (f64, Duration) {
    let mut config = ClientConfig::tcp();
    config.timeout = Duration::from_secs(5);
    config.retries = 0;
    let mut client = Client::open(Transport::Connect(address.to_string()), config)
        .await
        .unwrap();
    let expected = expected();
    assert_eq!(
        client
            .read(UNIT, Table::HoldingRegisters, 0, REGISTERS)
            .await
            .unwrap(),
        expected
    );
    for _ in 0..WARM_UP {
        client
            .read(UNIT, Table::HoldingRegisters, 0, REGISTERS)
            .await
            .unwrap();
    }
    let start = Instant::now();
    let mut requests = 0u64;
    while start.elapsed() < duration {
        let values = client
            .read(UNIT, Table::HoldingRegisters, 0, REGISTERS)
            .await
            .unwrap();
        assert_eq!(values.len(), usize::from(REGISTERS));
        requests += 1;
    }
    let elapsed = start.elapsed();
    (
        requests as f64 / elapsed.as_secs_f64(),
        elapsed / u32::try_from(requests).unwrap(),
    )
}

/// pymodbus's server on a free loopback port, once it said `ready`; `None` when
/// python3 or pymodbus is missing.
fn pymodbus_server() -> Option<(Background, SocketAddr)> {
    if !python_imports("pymodbus.server") {
        return None;
    }
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/peer/pymodbus_server.py");
    let port = free_port();
    let mut command = Command::new("python3");
    command.arg(script).args(["--tcp", &port.to_string()]);
    let (server, _) = start_until_line(command, "ready");
    Some((server, SocketAddr::from(([127, 0, 0, 1], port))))
}

fn main() {
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    let duration = seconds();
    let row = |name: &str, (rate, round_trip): (f64, Duration)| {
        println!(
            "  {name:<12} {rate:>8.0} requests/s  {:>10.0} registers/s  ({:.0} us a round trip)",
            rate * f64::from(REGISTERS),
            round_trip.as_secs_f64() * 1e6
        );
    };
    println!(
        "Modbus TCP reads of {REGISTERS} holding registers (FC 3), {duration:?} each after \
         {WARM_UP} requests of warm-up, our client, one request at a time:"
    );
    let ours = runtime.block_on(async {
        let model = DataModel::new(ModelConfig::new(Units::Single(UNIT)));
        model
            .write(
                UNIT,
                Table::HoldingRegisters,
                0,
                &Values::Registers((100..110).collect()),
            )
            .unwrap();
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let address = listener.local_addr().unwrap();
        let server = tokio::spawn(serve_tcp(listener, model));
        let measured = measure(address, duration).await;
        server.abort();
        measured
    });
    row("our server", ours);
    match pymodbus_server() {
        Some((server, address)) => {
            let pymodbus = runtime.block_on(measure(address, duration));
            drop(server);
            row("pymodbus", pymodbus);
            println!("  ratio ours / pymodbus: {:.1}", ours.0 / pymodbus.0);
        }
        None => println!(
            "  pymodbus     skipped: python3 with pymodbus 3.16.1 not found \
             (scripts/install-test-deps.sh installs it)"
        ),
    }
}
