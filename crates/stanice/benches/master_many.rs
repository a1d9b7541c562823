//! A master node supervising many outstations: resident memory and CPU of the `stanice`
//! process, with a general interrogation of every outstation on connect and spontaneous
//! traffic after.
//!
//! ```text
//! cargo bench -p stanice --bench master_many [-- --outstations 1000 --points 200 --rate 1 --seconds 30]
//! ```
//!
//! This process runs the outstations: N IEC 104 servers of this workspace, each with P
//! measured values, on loopback ports of their own. It writes a project whose one node,
//! MASTER, has a link to each (`address = "127.0.0.1:PORT"`, a status point, every point
//! declared with `source = "link:L{i}/{ioa}"`), and starts `stanice run PROJECT --store
//! none` as a child process. It waits (bounded) until every outstation has a connection
//! and the master has interrogated them all, then has each outstation change RATE points
//! a second and samples the child's resident set (`/proc/PID/status` VmRSS) and CPU time
//! (`/proc/PID/stat` utime + stime) while it runs.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::fmt::Write as _;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use testkit::process::resident_and_cpu;

use iec60870::asdu::{CommonAddress, Element, Ioa, Quality, TypeId};
use iec60870::cs104::server::{
    spawn_server, MonitorPoint, ProcessImage, ReadOnlyStation, ServerConfig, ServerHandle,
};

struct Options {
    outstations: u32,
    points: u32,
    rate: u32,
    seconds: u64,
}

fn options() -> Options {
    let args: Vec<String> = std::env::args().collect();
    let value = |name: &str, default: u64| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .and_then(|v| v.parse().ok())
            .unwrap_or(default)
    };
    Options {
        outstations: u32::try_from(value("--outstations", 1000)).unwrap(),
        points: u32::try_from(value("--points", 200)).unwrap(),
        rate: u32::try_from(value("--rate", 1)).unwrap(),
        seconds: value("--seconds", 30),
    }
}

fn float(value: f32) -> Element {
    Element::Float {
        value,
        quality: Quality::GOOD,
    }
}

/// The project: one node with a link to every outstation and every point declared.
fn project(servers: &[ServerHandle], points: u32) -> String {
    let mut toml = String::from(
        "[station]\nname = \"many outstations\"\ntime_zone = \"UTC\"\n\n[[node]]\nname = \"MASTER\"\ncommon_address = 1\n\n",
    );
    for (i, server) in servers.iter().enumerate() {
        let _ = write!(
            toml,
            "[[node.link]]\nname = \"L{i}\"\naddress = \"{}\"\ncommon_address = {}\nclock_sync = false\nstatus_point = \"COMM_{i}\"\n\n",
            server.local_addr(),
            i + 2
        );
    }
    for i in 0..servers.len() {
        let base = (i as u32 + 1) * 1_000;
        let _ = write!(
            toml,
            "[[node.point]]\nname = \"COMM_{i}\"\ntype = \"M_SP_NA_1\"\nioa = {base}\n\n"
        );
        for ioa in 1..=points {
            let _ = write!(
                toml,
                "[[node.point]]\nname = \"O{i}_P{ioa}\"\ntype = \"M_ME_NC_1\"\nioa = {}\nsource = \"link:L{i}/{ioa}\"\n\n",
                base + ioa
            );
        }
    }
    toml
}

fn main() {
    let options = options();
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap()
        .block_on(run(options));
}

async fn run(options: Options) {
    let started = Instant::now();
    let mut servers = Vec::new();
    for i in 0..options.outstations {
        let mut image = ProcessImage::new();
        for ioa in 1..=options.points {
            image
                .add_monitor(MonitorPoint {
                    ioa: Ioa::try_new(ioa).unwrap(),
                    event_type: TypeId::M_ME_NC_1,
                    groups: 0,
                    element: float(ioa as f32),
                    time: None,
                })
                .unwrap();
        }
        let common_address = CommonAddress::new(u16::try_from(i + 2).unwrap());
        let server = spawn_server(
            ServerConfig::new("127.0.0.1:0".parse().unwrap(), common_address),
            image,
            Arc::new(ReadOnlyStation),
        )
        .await
        .unwrap();
        servers.push(server);
    }
    let dir = tempfile::tempdir().unwrap();
    let toml = project(&servers, options.points);
    std::fs::write(dir.path().join("station.toml"), &toml).unwrap();
    println!(
        "master with {} outstations of {} points ({} points at the master, station.toml {:.1} MB); outstations up in {:.1} s",
        options.outstations,
        options.points,
        options.outstations * (options.points + 1),
        toml.len() as f64 / 1e6,
        started.elapsed().as_secs_f64()
    );

    let launched = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_stanice"))
        .arg("run")
        .arg(dir.path())
        .args(["--store", "none", "--log", "warn"])
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let pid = child.id();
    // Every outstation connected with data transfer started (STARTDT: the master's
    // general interrogation follows at once).
    let deadline = Instant::now() + Duration::from_secs(300);
    loop {
        let connected = servers
            .iter()
            .filter(|server| server.stats().groups.iter().any(|group| group.has_active))
            .count();
        if connected == servers.len() {
            break;
        }
        if let Ok(Some(status)) = child.try_wait() {
            panic!("stanice ended: {status}");
        }
        assert!(
            Instant::now() < deadline,
            "{connected} of {} outstations connected after 300 s",
            servers.len()
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let connected_after = launched.elapsed();
    let (rss_connected, _) = resident_and_cpu(pid).unwrap_or_default();
    println!(
        "  every outstation connected and started {:.1} s after the master's start; resident {:.1} MB",
        connected_after.as_secs_f64(),
        rss_connected as f64 / 1024.0
    );

    // Spontaneous traffic: RATE changes per outstation per second, spread over the second.
    let running = Arc::new(AtomicBool::new(true));
    let sent = Arc::new(AtomicU64::new(0));
    let traffic = {
        let running = Arc::clone(&running);
        let sent = Arc::clone(&sent);
        let servers = servers.clone();
        let (rate, points) = (options.rate, options.points);
        tokio::spawn(async move {
            let steps = 10u32;
            let mut round = 0u32;
            let mut tick = tokio::time::interval(Duration::from_millis(100));
            while running.load(Ordering::Relaxed) {
                tick.tick().await;
                for (i, server) in servers.iter().enumerate() {
                    // This tenth of a second's share of the outstation's changes.
                    let share = rate * (round % steps + 1) / steps - rate * (round % steps) / steps;
                    for k in 0..share {
                        let ioa = 1 + (round * rate + k + i as u32) % points;
                        if server
                            .update(Ioa::try_new(ioa).unwrap(), float(round as f32), None)
                            .is_ok()
                        {
                            sent.fetch_add(1, Ordering::Relaxed);
                        }
                    }
                }
                round += 1;
            }
        })
    };
    let ticks_per_second = 100.0; // USER_HZ on Linux
    let (_, cpu_start) = resident_and_cpu(pid).unwrap();
    let measured = Instant::now();
    let mut samples = Vec::new();
    for _ in 0..options.seconds.div_ceil(5) {
        tokio::time::sleep(Duration::from_secs(5)).await;
        let (rss, cpu) = resident_and_cpu(pid).unwrap();
        samples.push((measured.elapsed().as_secs_f64(), rss, cpu));
    }
    running.store(false, Ordering::Relaxed);
    let _ = traffic.await;
    let (seconds, rss_end, cpu_end) = *samples.last().unwrap();
    let cpu_percent = (cpu_end - cpu_start) as f64 / ticks_per_second / seconds * 100.0;
    println!(
        "  {:.0} spontaneous changes/s for {:.0} s: master CPU {:.1} % of one core, resident {:.1} MB (samples: {})",
        sent.load(Ordering::Relaxed) as f64 / seconds,
        seconds,
        cpu_percent,
        rss_end as f64 / 1024.0,
        samples
            .iter()
            .map(|(t, rss, _)| format!("{t:.0} s {:.1} MB", *rss as f64 / 1024.0))
            .collect::<Vec<_>>()
            .join(", ")
    );
    // What the master did not take: events not yet sent by the outstations, ASDUs sent
    // and not yet acknowledged (the master acknowledges every w = 8 frames or after t2),
    // events lost to full buffers.
    let (queued, unacknowledged, dropped) = servers
        .iter()
        .flat_map(|server| server.stats().groups)
        .fold((0, 0, 0), |(queued, unacknowledged, dropped), group| {
            (
                queued + group.queued,
                unacknowledged + group.retransmit_queued,
                dropped + group.dropped,
            )
        });
    println!(
        "  at the end: {queued} events not yet sent by the outstations, {unacknowledged} ASDUs sent and not yet acknowledged, {dropped} lost to full buffers"
    );
    let _ = Command::new("kill")
        .args(["-TERM", &pid.to_string()])
        .status();
    let _ = child.wait();
    for server in &servers {
        server.shutdown();
    }
}
