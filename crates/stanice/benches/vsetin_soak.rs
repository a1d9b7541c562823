//! A soak of the Vsetín station: many simulated days at speed with random faults and
//! process kills, printing resident memory over time and its slope, the events dispatch
//! received against the events the station stored, and the commands dispatch had
//! confirmed against the commands the station audited.
//!
//! ```text
//! cargo bench -p stanice --bench vsetin_soak [-- --days 30 --speed 2000 --cycle-ms 250
//!                                                --kill-every-hours 120 --seed 1
//!                                                --event-buffer N --store-cache-mib N]
//! ```
//!
//! The station runs as `stanice run` in a child process (all 23 nodes, SQLite store in a
//! temporary folder) on a simulated clock `--speed` times the wall clock; the bench is its
//! dispatch: an IEC 104 client of RDRT that records every spontaneous event and sends a
//! command every simulated 10 minutes (breaker QF1 of RH2 opened and closed in turn, a
//! lighting window set-point of a lamp board). Every simulated 20 minutes on average a
//! random fault goes in on the station's console (mains lost, a module pulled, a supply
//! unit failed, a link cut, a generator that fails to start, a PLC stopped) and is cleared
//! after a random while. Every `--kill-every-hours` simulated hours the process is killed
//! (`kill -9`) and started again from the simulated time it had reached.
//!
//! The PLC tasks run every `--cycle-ms` simulated milliseconds instead of the project's 10
//! and 100 ms (the project is copied and its `interval_ms` raised): at the configured
//! cycles a simulated day takes hours of this 2-core machine, and a soak looks for what
//! grows or gets lost over simulated time, not for the PLC's timing. 250 ms still sees
//! every 500 ms command pulse; 500 ms (the figures in README.md, 30 days in 22 minutes)
//! may miss a pulse that starts on a cycle, which changes what the plant does, not what
//! is counted.
//!
//! `--event-buffer N` sets every server's `event_buffer` (events kept per redundancy group
//! no client takes; the project's default is 100,000): RDRT's redundancy groups for the
//! HMI, ED, MRS and service have no client in the soak and fill their buffers, which is
//! most of the memory a process life gains (the heap profile in the closing note of the
//! scale-out issue); with a small buffer they are full within the first simulated day.
//! `--store-cache-mib N` bounds the SQLite store's page caches (`sqlite:PATH?cache_mib=N`):
//! the rest of that growth, 64 MiB by default, filled at some 70 KB per simulated hour.
//!
//! What it prints: the resident set of the station process at every simulated 6 hours,
//! the slope of each process life's resident set over simulated time (least squares,
//! after its first simulated day), the events dispatch received spontaneously and how
//! many of them the store lacks (and how close to a kill those were), and the commands:
//! sent, confirmed positively, audited as executed, audited twice.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::collections::HashMap;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use chrono::{DateTime, NaiveDateTime, TimeZone, Utc};
use iec60870::asdu::{
    Asdu, Cause, CommandQualifier, CommonAddress, Element, Ioa, SetpointQualifier, TimeTag, TypeId,
};
use iec60870::cs104::client::{spawn_client, ClientConfig, ClientEvent, ClientHandle};
use station::store::{open_store, CommandOutcome, CommandQuery, EventQuery, EventStore};
use testkit::process::resident_and_cpu;

/// The soak's settings, from the command line.
struct Settings {
    days: f64,
    speed: f64,
    cycle_ms: u64,
    kill_every_hours: f64,
    seed: u64,
    event_buffer: Option<u64>,
    store_cache_mib: Option<u32>,
}

impl Settings {
    fn from_args() -> Settings {
        let args: Vec<String> = std::env::args().collect();
        let value = |name: &str| {
            args.iter()
                .position(|a| a == name)
                .and_then(|i| args.get(i + 1))
                .cloned()
        };
        Settings {
            days: value("--days").and_then(|v| v.parse().ok()).unwrap_or(30.0),
            speed: value("--speed")
                .and_then(|v| v.parse().ok())
                .unwrap_or(2000.0),
            cycle_ms: value("--cycle-ms")
                .and_then(|v| v.parse().ok())
                .unwrap_or(250),
            kill_every_hours: value("--kill-every-hours")
                .and_then(|v| v.parse().ok())
                .unwrap_or(120.0),
            seed: value("--seed").and_then(|v| v.parse().ok()).unwrap_or(1),
            event_buffer: value("--event-buffer").and_then(|v| v.parse().ok()),
            store_cache_mib: value("--store-cache-mib").and_then(|v| v.parse().ok()),
        }
    }
}

/// A small deterministic random source (xorshift): the same seed gives the same soak.
struct Random(u64);

impl Random {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    /// Uniform in `0..n`.
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n.max(1)
    }

    /// Exponentially distributed with this mean (a Poisson process's gaps).
    fn exponential(&mut self, mean: f64) -> f64 {
        let u = (self.next() >> 11) as f64 / (1u64 << 53) as f64;
        -mean * (1.0 - u).max(f64::MIN_POSITIVE).ln()
    }
}

/// The faults and their clearing lines, as the station's console takes them.
fn random_fault(random: &mut Random) -> (String, String) {
    const SUPPLIES: [&str; 2] = ["T1", "T2"];
    const MODULES: [&str; 3] = ["RDRT_P6", "RDRT_P9", "RH2_LOGO"];
    const LINKS: [&str; 5] = ["RDRT/ROV03", "RDRT/RH", "RH1.1/RH2", "RZS1/RDA", "RDRT/OR"];
    const PLCS: [&str; 3] = ["ROV07", "RH-DT", "RZZ"];
    match random.below(6) {
        0 => {
            let supply = SUPPLIES[random.below(2) as usize];
            (
                format!("supply-loss {supply}"),
                format!("clear supply-loss {supply}"),
            )
        }
        1 => {
            let module = MODULES[random.below(3) as usize];
            (
                format!("module-pulled {module}"),
                format!("clear module-pulled {module}"),
            )
        }
        2 => {
            let link = LINKS[random.below(5) as usize];
            (format!("link-cut {link}"), format!("link-restore {link}"))
        }
        3 => (
            "generator-fail-to-start".to_owned(),
            "clear generator-fail-to-start".to_owned(),
        ),
        4 => {
            let node = PLCS[random.below(3) as usize];
            (format!("plc-stop {node}"), format!("plc-start {node}"))
        }
        _ => {
            let unit = ["RDRT_G24", "RH2_G110.2"][random.below(2) as usize];
            (
                format!("supply-unit-fault {unit}"),
                format!("clear supply-unit-fault {unit}"),
            )
        }
    }
}

/// Copies the project folder (files and sub-folders) with every PLC task's
/// `interval_ms` below `cycle_ms` raised to it and, given one, every server's
/// `event_buffer` set.
fn copy_project(from: &Path, to: &Path, cycle_ms: u64, event_buffer: Option<u64>) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_project(&entry.path(), &target, cycle_ms, event_buffer);
        } else if entry.file_name() == "station.toml" {
            let text = std::fs::read_to_string(entry.path()).unwrap();
            let raised: Vec<String> = text
                .lines()
                .map(|line| match line.trim().strip_prefix("interval_ms = ") {
                    Some(ms) if ms.parse::<u64>().is_ok_and(|ms| ms < cycle_ms) => {
                        format!("interval_ms = {cycle_ms}")
                    }
                    _ => match event_buffer {
                        Some(events) if line.trim() == "[node.server]" => {
                            format!("{line}\nevent_buffer = {events}")
                        }
                        _ => line.to_owned(),
                    },
                })
                .collect();
            std::fs::write(&target, raised.join("\n")).unwrap();
        } else {
            std::fs::copy(entry.path(), &target).unwrap();
        }
    }
}

/// The station process: its stdin (the console) and its stdout lines.
struct Station {
    child: Child,
    console: ChildStdin,
    lines: mpsc::Receiver<String>,
}

impl Station {
    fn start(
        project: &Path,
        store: &str,
        port_base: u16,
        speed: f64,
        at: DateTime<Utc>,
    ) -> Station {
        let mut child = Command::new(env!("CARGO_BIN_EXE_stanice"))
            .arg("run")
            .arg(project)
            .args(["--store", store, "--log", "error"])
            .args(["--port-base", &port_base.to_string()])
            .args(["--speed", &speed.to_string()])
            .args(["--start", &at.to_rfc3339()])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let console = child.stdin.take().unwrap();
        let stdout = child.stdout.take().unwrap();
        let (sender, lines) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines() {
                let Ok(line) = line else { break };
                if sender.send(line).is_err() {
                    break;
                }
            }
        });
        Station {
            child,
            console,
            lines,
        }
    }

    /// Types a console line.
    fn type_line(&mut self, line: &str) {
        let _ = writeln!(self.console, "{line}");
        let _ = self.console.flush();
    }

    /// Asks for the status and returns the simulated time it reports (`None` when the
    /// process does not answer within `within`).
    fn simulated_time(&mut self, within: Duration) -> Option<DateTime<Utc>> {
        while self.lines.try_recv().is_ok() {}
        self.type_line("status");
        let deadline = Instant::now() + within;
        while let Some(left) = deadline.checked_duration_since(Instant::now()) {
            let line = self.lines.recv_timeout(left).ok()?;
            if let Some(rest) = line.strip_prefix("simulated time ") {
                let text = rest.get(..19)?;
                let naive = NaiveDateTime::parse_from_str(text, "%Y-%m-%d %H:%M:%S").ok()?;
                return Some(Utc.from_utc_datetime(&naive));
            }
        }
        None
    }

    fn kill(mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }

    /// Stops it as an operator does (SIGTERM): the store is written and closed.
    fn stop(mut self) {
        let _ = Command::new("kill")
            .args(["-TERM", &self.child.id().to_string()])
            .status();
        let deadline = Instant::now() + Duration::from_secs(60);
        while Instant::now() < deadline {
            if let Ok(Some(_)) = self.child.try_wait() {
                return;
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        self.kill();
    }
}

/// A spontaneous event as dispatch received it: IOA and its time tag's minute and
/// millisecond (a time tag in local time differs from UTC by whole hours only).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct Seen {
    ioa: u32,
    minute: u8,
    millisecond: u16,
}

fn spontaneous(asdu: &Asdu) -> Vec<Seen> {
    if !matches!(
        asdu.cot.cause,
        Cause::SPONTANEOUS | Cause::RETURN_REMOTE | Cause::RETURN_LOCAL
    ) {
        return Vec::new();
    }
    asdu.objects
        .iter()
        .filter_map(|object| match object.time {
            Some(TimeTag::Cp56(time)) if !time.is_invalid() => Some(Seen {
                ioa: object.ioa.get(),
                minute: time.minute(),
                millisecond: time.millisecond(),
            }),
            _ => None,
        })
        .collect()
}

/// The least-squares slope of `(x, y)` points, `None` for fewer than 3.
fn slope(points: &[(f64, f64)]) -> Option<f64> {
    if points.len() < 3 {
        return None;
    }
    let n = points.len() as f64;
    let mean_x = points.iter().map(|p| p.0).sum::<f64>() / n;
    let mean_y = points.iter().map(|p| p.1).sum::<f64>() / n;
    let covariance: f64 = points.iter().map(|p| (p.0 - mean_x) * (p.1 - mean_y)).sum();
    let variance: f64 = points.iter().map(|p| (p.0 - mean_x).powi(2)).sum();
    (variance > 0.0).then(|| covariance / variance)
}

/// What the commands did, from dispatch's side.
#[derive(Default)]
struct Commands {
    sent: u64,
    confirmed: u64,
    refused: u64,
    failed: u64,
}

async fn send_command(client: &ClientHandle, n: u64, random: &mut Random, commands: &mut Commands) {
    commands.sent += 1;
    let result = if n % 2 == 0 {
        // RH2's QF1: open (2021) and close (2022) in turn.
        let ioa = if n % 4 == 0 { 2021 } else { 2022 };
        client
            .command(
                TypeId::C_SC_NA_1,
                Ioa::try_new(ioa).unwrap(),
                Element::SingleCommand {
                    on: true,
                    qualifier: CommandQualifier::EXECUTE,
                },
                None,
            )
            .await
    } else {
        // A lamp board's window 1 switch-on time, minutes after midnight.
        let board = 1 + random.below(12);
        client
            .command(
                TypeId::C_SE_NB_1,
                Ioa::try_new(10061 + 100 * board as u32).unwrap(),
                Element::SetpointScaled {
                    value: (960 + random.below(240)) as i16,
                    qualifier: SetpointQualifier::EXECUTE,
                },
                None,
            )
            .await
    };
    match result {
        Ok(outcome) if outcome.positive => commands.confirmed += 1,
        Ok(_) => commands.refused += 1,
        Err(_) => commands.failed += 1,
    }
}

fn main() {
    let settings = Settings::from_args();
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    runtime.block_on(soak(settings));
}

async fn soak(settings: Settings) {
    let folder = tempfile::tempdir().unwrap();
    let project: PathBuf = folder.path().join("vsetin");
    copy_project(
        &testkit::repository_root().join("examples/vsetin"),
        &project,
        settings.cycle_ms,
        settings.event_buffer,
    );
    let store_url = format!(
        "sqlite:{}{}",
        folder.path().join("events.sqlite").display(),
        settings
            .store_cache_mib
            .map_or_else(String::new, |mib| format!("?cache_mib={mib}"))
    );
    let port_base = testkit::ports::free_port_range(23);
    let start = Utc.with_ymd_and_hms(2026, 1, 5, 6, 0, 0).unwrap();
    let end = start + chrono::Duration::seconds((settings.days * 86_400.0) as i64);
    let mut random = Random(settings.seed.max(1));
    println!(
        "Vsetín soak: {} simulated days from {} at speed {} (PLC tasks every {} ms), a kill -9 every {} simulated hours, seed {}, event buffers {}, store {}",
        settings.days,
        start.format("%Y-%m-%d %H:%M UTC"),
        settings.speed,
        settings.cycle_ms,
        settings.kill_every_hours,
        settings.seed,
        settings.event_buffer.map_or_else(
            || "as the project has them".to_owned(),
            |events| format!("of {events} events")
        ),
        store_url
    );

    let mut config = ClientConfig::new(format!("127.0.0.1:{port_base}"), CommonAddress::new(1));
    config.reconnect_delay = Duration::from_millis(200);
    config.reconnect_delay_max = Duration::from_secs(1);
    let (client, mut client_events) = spawn_client(config);
    let (seen_sender, mut seen_receiver) = tokio::sync::mpsc::unbounded_channel();
    tokio::spawn(async move {
        while let Some(event) = client_events.recv().await {
            if let ClientEvent::Asdu(asdu) = event {
                for seen in spontaneous(&asdu) {
                    let _ = seen_sender.send(seen);
                }
            }
        }
    });

    let wall = Instant::now();
    let mut station = Station::start(&project, &store_url, port_base, settings.speed, start);
    let mut now = start;
    let mut next_fault = start + minutes(random.exponential(20.0));
    let mut clears: Vec<(DateTime<Utc>, String)> = Vec::new();
    let mut next_command = start + chrono::Duration::minutes(10);
    let mut command_count = 0;
    let mut commands = Commands::default();
    let mut next_kill = start + hours(settings.kill_every_hours);
    let mut kills: Vec<DateTime<Utc>> = Vec::new();
    // Events received by dispatch, in order, and how many had come at each kill.
    let mut received: Vec<Seen> = Vec::new();
    let mut kill_marks: Vec<usize> = Vec::new();
    let mut next_sample = start;
    // Resident set per process life: (simulated hours since the soak's start, KB).
    let mut lives: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
    // Every sample, over the process lives (simulated hour, resident KB).
    let mut samples: Vec<(f64, f64)> = Vec::new();
    let mut life_start = start;
    let mut faults = 0;
    println!("  simulated time          resident    wall");
    while now < end {
        tokio::time::sleep(Duration::from_millis(500)).await;
        let Some(reported) = station.simulated_time(Duration::from_secs(30)) else {
            panic!("the station does not answer `status` (at {now})");
        };
        now = reported.max(now);
        if now >= next_sample {
            if let Some((rss, _)) = resident_and_cpu(station.child.id()) {
                let hour = (now - start).num_seconds() as f64 / 3600.0;
                samples.push((hour, rss as f64));
                if now - life_start >= chrono::Duration::days(1) {
                    lives.last_mut().unwrap().push((hour, rss as f64));
                }
                println!(
                    "  {}  {:>8.1} MB  {:>6.0} s",
                    now.format("%Y-%m-%d %H:%M UTC"),
                    rss as f64 / 1024.0,
                    wall.elapsed().as_secs_f64()
                );
            }
            next_sample = now + chrono::Duration::hours(6);
        }
        if now >= next_fault {
            let (fault, clear) = random_fault(&mut random);
            station.type_line(&fault);
            faults += 1;
            clears.push((now + minutes(2.0 + random.exponential(15.0)), clear));
            next_fault = now + minutes(random.exponential(20.0));
        }
        clears.retain(|(at, clear)| {
            if now >= *at {
                station.type_line(clear);
                false
            } else {
                true
            }
        });
        if now >= next_command {
            send_command(&client, command_count, &mut random, &mut commands).await;
            command_count += 1;
            next_command = now + chrono::Duration::minutes(10);
        }
        if now >= next_kill {
            let at = station
                .simulated_time(Duration::from_secs(30))
                .unwrap_or(now);
            station.kill();
            kills.push(at);
            // Where in the stream of received events the kill fell (those before it
            // drained now; more may still be in flight from before the kill).
            while let Ok(seen) = seen_receiver.try_recv() {
                received.push(seen);
            }
            kill_marks.push(received.len());
            // Faults do not survive a restart: the plant starts healthy.
            clears.clear();
            station = Station::start(&project, &store_url, port_base, settings.speed, at);
            now = at;
            life_start = at;
            lives.push(Vec::new());
            next_kill = at + hours(settings.kill_every_hours);
        }
    }
    station.type_line("clear all");
    let wall_seconds = wall.elapsed().as_secs_f64();
    station.stop();
    client.close().await;
    while let Ok(seen) = seen_receiver.try_recv() {
        received.push(seen);
    }

    // The store, after the last process stopped cleanly.
    let store = open_store(&store_url).await.unwrap();
    let mut stored: HashMap<Seen, u64> = HashMap::new();
    let mut stored_total = 0u64;
    let mut after = None;
    loop {
        let page = store
            .query_events(
                &EventQuery::default()
                    .with_node("RDRT")
                    .with_limit(10_000)
                    .with_after(after),
            )
            .await
            .unwrap();
        for event in &page.items {
            stored_total += 1;
            let (Some(ioa), Some(time)) = (event.ioa, event.source_time) else {
                continue;
            };
            let time = time.time;
            let seen = Seen {
                ioa,
                minute: chrono::Timelike::minute(&time) as u8,
                millisecond: (chrono::Timelike::second(&time) * 1000
                    + chrono::Timelike::nanosecond(&time) / 1_000_000)
                    as u16,
            };
            *stored.entry(seen).or_default() += 1;
        }
        after = page.next;
        if after.is_none() {
            break;
        }
    }
    let missing: Vec<usize> = (0..received.len())
        .filter(|&i| !stored.contains_key(&received[i]))
        .collect();
    // How far (in received events) each missing one came before the next kill.
    let before_kill: Vec<usize> = missing
        .iter()
        .filter_map(|&i| {
            kill_marks
                .iter()
                .find(|&&mark| mark >= i)
                .map(|mark| mark - i)
        })
        .collect();
    let audited = audited_commands(store.as_ref()).await;

    println!();
    println!(
        "{:.1} simulated days in {:.0} s of wall time ({:.0} x real time), {} faults, {} kill -9",
        (now - start).num_seconds() as f64 / 86_400.0,
        wall_seconds,
        (now - start).num_seconds() as f64 / wall_seconds,
        faults,
        kills.len()
    );
    println!("resident memory slope per process life (after its first simulated day):");
    let mut slopes = Vec::new();
    for (n, life) in lives.iter().enumerate() {
        if let Some(kb_per_hour) = slope(life) {
            slopes.push(kb_per_hour);
            println!(
                "  life {}: {:.2} KB per simulated hour over {:.0} simulated hours ({} samples)",
                n + 1,
                kb_per_hour,
                life.last().unwrap().0 - life.first().unwrap().0,
                life.len()
            );
        }
    }
    if slopes.is_empty() {
        println!(
            "  none: no process life lasted long enough for one (its samples after the first \
             simulated day; give --kill-every-hours more than 24)"
        );
    } else {
        println!(
            "  mean: {:.2} KB per simulated hour",
            slopes.iter().sum::<f64>() / slopes.len() as f64
        );
    }
    let resident = samples.iter().map(|sample| sample.1);
    if let (Some(least), Some(most)) =
        (resident.clone().reduce(f64::min), resident.reduce(f64::max))
    {
        println!(
            "resident memory over the whole run: {:.1} to {:.1} MB; slope over all {} samples \
             (across restarts) {}",
            least / 1024.0,
            most / 1024.0,
            samples.len(),
            slope(&samples).map_or_else(
                || "-".to_owned(),
                |kb_per_hour| format!("{kb_per_hour:.2} KB per simulated hour")
            )
        );
    }
    println!(
        "events: dispatch received {} spontaneously from RDRT; RDRT's store holds {} events; {} of the received are not in the store",
        received.len(),
        stored_total,
        missing.len()
    );
    if !missing.is_empty() {
        println!(
            "  of the missing, {} came within 200 events before a kill -9 (at most {} before \
             one), {} at other times",
            before_kill.iter().filter(|&&d| d <= 200).count(),
            before_kill.iter().max().copied().unwrap_or(0),
            missing.len() - before_kill.iter().filter(|&&d| d <= 200).count()
        );
    }
    println!(
        "commands: {} sent, {} confirmed, {} refused, {} failed (no answer, connection lost); audited as executed {}, audited more than once {}",
        commands.sent,
        commands.confirmed,
        commands.refused,
        commands.failed,
        audited.executed,
        audited.duplicated
    );
}

/// What the command audit holds.
struct Audited {
    executed: u64,
    duplicated: u64,
}

async fn audited_commands(store: &dyn EventStore) -> Audited {
    let mut executed = 0;
    let mut keys: HashMap<(String, i64, String), u64> = HashMap::new();
    let mut after = None;
    loop {
        let page = store
            .query_commands(
                &CommandQuery::default()
                    .with_node("RDRT")
                    .with_limit(10_000)
                    .with_after(after),
            )
            .await
            .unwrap();
        for command in &page.items {
            if command.outcome == CommandOutcome::Executed {
                executed += 1;
            }
            *keys
                .entry((
                    command.point.clone(),
                    command.time.timestamp_millis(),
                    format!("{:?}", command.outcome),
                ))
                .or_default() += 1;
        }
        after = page.next;
        if after.is_none() {
            break;
        }
    }
    Audited {
        executed,
        duplicated: keys.values().filter(|n| **n > 1).count() as u64,
    }
}

fn minutes(m: f64) -> chrono::Duration {
    chrono::Duration::milliseconds((m * 60_000.0) as i64)
}

fn hours(h: f64) -> chrono::Duration {
    chrono::Duration::milliseconds((h * 3_600_000.0) as i64)
}
