//! A fleet of simulated lifts polled by one station node, at the spec's rates (status
//! every second, trip counters every minute, EKM66-A7): what one monitoring box can
//! watch.
//!
//! ```text
//! cargo bench -p station --bench lift_fleet [-- --lifts 200 --seconds 30 --faults 400]
//! ```
//!
//! The boards run in a child process (this program again, `--boards`), each an EKM66
//! simulator behind its own TCP listener on loopback, as RS-232-to-Ethernet converters
//! would be; the node polls them with `tcp = ...` lifts, so that the CPU time and memory
//! printed are the node's alone. Measured:
//!
//! - **poll cycle per lift**: the window divided by the status replies each lift got (the
//!   spec's period is 1 s; more means the node cannot keep up), p50/p99/max over the lifts,
//!   and the line errors;
//! - **fault latency**: a fault injected on a board (the child's console) until it is in
//!   the archive (committed to SQLite and broadcast), and until an IEC 104 client of the
//!   node (where the HMI and dispatch read it) receives the lift's `faults` point;
//!   p50/p99/max over `--faults` injections spread over the lifts. The HMI's own hop, its
//!   client to the browser's DOM, is `cargo bench -p hmi --bench live`.
//! - **CPU and memory of the node**: user + system time over the window as a share of
//!   one core, and the resident set (now and peak).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::collections::HashMap;
use std::io::{BufRead, Write};
use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use devices::ekm66::io::{run_simulator, EndpointAction, LineListener};
use devices::ekm66::simulator::{Simulator, SimulatorConfig};
use iec60870::asdu::CommonAddress;
use iec60870::cs104::client::{spawn_client, ClientConfig, ClientEvent};
use station::config::Project;
use station::runtime::{Pacing, Runtime, RuntimeOptions, StoreChoice};
use testkit::ports::free_port;
use testkit::projects::{LiftBoard, LiftFleet};
use tokio::sync::mpsc;

fn arg(name: &str, default: u64) -> u64 {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn percentile<T: Copy + Ord>(sorted: &[T], p: f64) -> T {
    let index = ((sorted.len() as f64 - 1.0) * p).round() as usize;
    sorted[index.min(sorted.len() - 1)]
}

fn main() {
    if std::env::args().any(|a| a == "--boards") {
        boards(usize::try_from(arg("--boards", 200)).unwrap());
        return;
    }
    // `cargo bench` passes --bench; nothing else of libtest applies.
    let lifts = usize::try_from(arg("--lifts", 200)).unwrap();
    let seconds = arg("--seconds", 30);
    let faults = usize::try_from(arg("--faults", 400)).unwrap();
    tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .unwrap()
        .block_on(node(lifts, seconds, faults));
}

/// The child: `lifts` boards, each behind a listener; prints the ports as one line, then
/// takes `fault LIFT CODE` lines on standard input.
fn boards(lifts: usize) {
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .enable_all()
        .build()
        .unwrap();
    runtime.block_on(async move {
        let mut ports = Vec::new();
        let mut consoles = Vec::new();
        for lift in 0..lifts {
            let listener = LineListener::bind("127.0.0.1:0").await.unwrap();
            ports.push(listener.local_addr().unwrap().port());
            let (operations, mut inbox) = mpsc::unbounded_channel::<EndpointAction<Simulator>>();
            consoles.push(operations);
            let mut config = SimulatorConfig::default();
            config.floors = LiftFleet::floors(lift);
            config.seed = lift as u64;
            config.stack_size = 64;
            config.fault_probability = 0.0;
            tokio::spawn(async move {
                let mut board = Simulator::new(config, Instant::now());
                loop {
                    let Ok(line) = listener.accept().await else {
                        return;
                    };
                    let _ = run_simulator(line.stream, &mut board, &mut inbox, |_| {
                        ControlFlow::Continue(())
                    })
                    .await;
                }
            });
        }
        println!("{}", serde_json::to_string(&ports).unwrap());
        std::io::stdout().flush().unwrap();
        let (lines, mut input) = mpsc::unbounded_channel::<String>();
        std::thread::spawn(move || {
            for line in std::io::stdin().lock().lines() {
                let Ok(line) = line else { return };
                if lines.send(line).is_err() {
                    return;
                }
            }
        });
        while let Some(line) = input.recv().await {
            let words: Vec<&str> = line.split_whitespace().collect();
            if let ["fault", lift, code] = words.as_slice() {
                let lift: usize = lift.parse().unwrap();
                let code = u8::from_str_radix(code, 16).unwrap();
                let _ = consoles[lift].send(Box::new(move |board: &mut Simulator| {
                    board.inject_fault(code);
                }));
            }
        }
    });
}

/// CPU seconds (user + system) of this process.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap();
    // The fields after the command name, which is in parentheses.
    let rest = &stat[stat.rfind(')').unwrap() + 2..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = fields[11].parse::<f64>().unwrap() + fields[12].parse::<f64>().unwrap();
    ticks / 100.0
}

/// (resident, peak resident) in MiB.
fn memory_mib() -> (f64, f64) {
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    let field = |name: &str| {
        status
            .lines()
            .find(|l| l.starts_with(name))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(0.0)
            / 1024.0
    };
    (field("VmRSS:"), field("VmHWM:"))
}

async fn node(lifts: usize, seconds: u64, faults: usize) {
    let mut child = std::process::Command::new(std::env::current_exe().unwrap())
        .args(["--boards", &lifts.to_string()])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut console = child.stdin.take().unwrap();
    let mut first = String::new();
    std::io::BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    let ports: Vec<u16> = serde_json::from_str(&first).unwrap();

    let dir = tempfile::tempdir().unwrap();
    let fleet = LiftFleet {
        time_zone: "Europe/Prague".to_owned(),
        port_base: free_port(),
        boards: ports.iter().map(|port| LiftBoard::Tcp(*port)).collect(),
    };
    fleet.write(dir.path());
    let project = Project::load(dir.path()).unwrap_or_else(|e| panic!("{e}"));
    let runtime = Runtime::start(
        project,
        RuntimeOptions {
            pacing: Pacing::RealTime { speed: 1.0 },
            store: StoreChoice::Project,
            ..RuntimeOptions::default()
        },
    )
    .await
    .unwrap();
    let handles: Vec<_> = runtime.nodes()[0].lifts.clone();
    let started = Instant::now();
    while handles
        .iter()
        .any(|lift| lift.counts().status_replies() == 0)
    {
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "not every lift answered"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    println!(
        "{lifts} lifts polled by one node (status every 1 s, counters every 60 s), boards in a child process over TCP on loopback"
    );

    // Poll cycle, CPU and memory over the window.
    let replies_before: Vec<u64> = handles
        .iter()
        .map(|l| l.counts().status_replies())
        .collect();
    let errors_before: u64 = handles.iter().map(|l| l.counts().line_errors()).sum();
    let cpu_before = cpu_seconds();
    let window_start = Instant::now();
    tokio::time::sleep(Duration::from_secs(seconds)).await;
    let window = window_start.elapsed();
    let cpu = cpu_seconds() - cpu_before;
    let mut cycles: Vec<Duration> = handles
        .iter()
        .zip(&replies_before)
        .map(|(lift, before)| {
            let replies = lift.counts().status_replies() - before;
            window / u32::try_from(replies.max(1)).unwrap()
        })
        .collect();
    cycles.sort();
    let errors: u64 = handles
        .iter()
        .map(|l| l.counts().line_errors())
        .sum::<u64>()
        - errors_before;
    let (rss, peak) = memory_mib();
    println!(
        "poll cycle per lift over {:.0} s: p50 {:.3} s, p99 {:.3} s, max {:.3} s; line errors {errors}",
        window.as_secs_f64(),
        percentile(&cycles, 0.5).as_secs_f64(),
        percentile(&cycles, 0.99).as_secs_f64(),
        cycles.last().unwrap().as_secs_f64()
    );
    println!(
        "node CPU {:.1} % of one core ({:.2} ms per lift-second); memory {rss:.1} MiB resident, {peak:.1} MiB peak",
        100.0 * cpu / window.as_secs_f64(),
        1000.0 * cpu / window.as_secs_f64() / lifts as f64
    );

    // Fault latency: to the archive, and to an IEC 104 client of the node.
    let (client, mut events) = spawn_client(ClientConfig::new(
        format!("127.0.0.1:{}", fleet.port_base),
        CommonAddress::new(1),
    ));
    loop {
        match tokio::time::timeout(Duration::from_secs(20), events.recv()).await {
            Ok(Some(ClientEvent::Started)) => break,
            Ok(Some(_)) => {}
            other => panic!("no client: {other:?}"),
        }
    }
    let _client = client;
    let mut archived = runtime.archived_faults();
    let faults_ioa: HashMap<u32, usize> = (0..lifts)
        .map(|lift| {
            (
                LiftFleet::ioa_base(lift) + points::LiftSignal::Faults.offset(),
                lift,
            )
        })
        .collect();
    let mut injected: HashMap<usize, Instant> = HashMap::new();
    let mut to_archive = Vec::new();
    let mut to_client = Vec::new();
    // Injected and not yet seen by the IEC 104 client (set with `injected`: the client
    // may see the point change before the broadcast is read here).
    let mut waiting_client: HashMap<usize, Instant> = HashMap::new();
    let mut next = 0usize;
    let mut tick = tokio::time::interval(Duration::from_millis(20));
    let deadline = Instant::now() + Duration::from_secs(120);
    while (to_archive.len() < faults || to_client.len() < faults) && Instant::now() < deadline {
        tokio::select! {
            _ = tick.tick() => {
                // One fault at a time per lift: the next lift without one in flight.
                if next < faults {
                    let lift = next % lifts;
                    if !injected.contains_key(&lift) && !waiting_client.contains_key(&lift) {
                        writeln!(console, "fault {lift} 3C").unwrap();
                        console.flush().unwrap();
                        let now = Instant::now();
                        injected.insert(lift, now);
                        waiting_client.insert(lift, now);
                        next += 1;
                    }
                }
            }
            record = archived.recv() => {
                let record = record.unwrap();
                let lift: usize = record.lift[1..].parse().unwrap();
                if let Some(t0) = injected.remove(&lift) {
                    to_archive.push(t0.elapsed());
                }
            }
            event = events.recv() => {
                if let Some(ClientEvent::Asdu(asdu)) = event {
                    for object in &asdu.objects {
                        if let Some(lift) = faults_ioa.get(&object.ioa.get()) {
                            if let Some(t0) = waiting_client.remove(lift) {
                                to_client.push(t0.elapsed());
                            }
                        }
                    }
                }
            }
        }
    }
    to_archive.sort();
    to_client.sort();
    let ms = |d: Duration| d.as_secs_f64() * 1000.0;
    println!(
        "fault on the board -> archived (SQLite commit): {} faults, p50 {:.0} ms, p99 {:.0} ms, max {:.0} ms",
        to_archive.len(),
        ms(percentile(&to_archive, 0.5)),
        ms(percentile(&to_archive, 0.99)),
        ms(*to_archive.last().unwrap())
    );
    println!(
        "fault on the board -> IEC 104 client (HMI, dispatch): {} faults, p50 {:.0} ms, p99 {:.0} ms, max {:.0} ms",
        to_client.len(),
        ms(percentile(&to_client, 0.5)),
        ms(percentile(&to_client, 0.99)),
        ms(*to_client.last().unwrap())
    );
    println!("(a fault is read in the cycle after it happens: the 1 s status period bounds both)");
    drop(console);
    runtime.shutdown().await;
    let _ = child.kill();
    let _ = child.wait();
}
