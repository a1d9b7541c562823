//! The Vsetín station as one process per node: resident memory and CPU of each.
//!
//! ```text
//! cargo bench -p stanice --bench vsetin_processes [-- --seconds 30]
//! ```
//!
//! Starts `stanice run examples/vsetin --node NAME --store none` for every node of the
//! project, each a process of its own on loopback (the links between them go over TCP, as
//! between hosts; the ports are moved to a free range), waits until the top node (RDRT,
//! dispatch's) accepts connections, lets the station run for SECONDS, and prints each
//! process's resident set (`/proc/PID/status` VmRSS) and CPU share over that time
//! (`/proc/PID/stat` utime + stime).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::net::TcpStream;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use testkit::process::resident_and_cpu;

/// The project's node names, in the order of station.toml (`name = "..."` after each
/// `[[node]]` header).
fn node_names(toml: &str) -> Vec<String> {
    let mut names = Vec::new();
    let mut in_node = false;
    for line in toml.lines() {
        let line = line.trim();
        if line.starts_with("[[") || line.starts_with('[') {
            in_node = line == "[[node]]";
            continue;
        }
        if in_node {
            if let Some(name) = line
                .strip_prefix("name = \"")
                .and_then(|rest| rest.strip_suffix('"'))
            {
                names.push(name.to_owned());
                in_node = false;
            }
        }
    }
    names
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seconds: u64 = args
        .iter()
        .position(|a| a == "--seconds")
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(30);
    let project = testkit::repository_root().join("examples/vsetin");
    let names = node_names(&std::fs::read_to_string(project.join("station.toml")).unwrap());
    assert!(names.len() >= 20, "nodes of Vsetín: {names:?}");
    // The project's ports are port_base + 0..=22 (RDRT at +0): a free range of 23.
    let port_base = testkit::ports::free_port_range(23);
    let mut children: Vec<(String, Child)> = names
        .iter()
        .map(|name| {
            let child = Command::new(env!("CARGO_BIN_EXE_stanice"))
                .arg("run")
                .arg(&project)
                .args(["--node", name, "--store", "none", "--log", "warn"])
                .args(["--port-base", &port_base.to_string()])
                .stdin(Stdio::piped())
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .unwrap();
            (name.clone(), child)
        })
        .collect();
    let started = Instant::now();
    let deadline = started + Duration::from_secs(120);
    while TcpStream::connect(("127.0.0.1", port_base)).is_err() {
        for (name, child) in &mut children {
            if let Ok(Some(status)) = child.try_wait() {
                panic!("node {name} ended: {status}");
            }
        }
        assert!(Instant::now() < deadline, "RDRT never accepted");
        std::thread::sleep(Duration::from_millis(100));
    }
    println!(
        "Vsetín as {} processes, one per node (RDRT accepting {:.1} s after the start); {seconds} s of the station at speed 1:",
        children.len(),
        started.elapsed().as_secs_f64()
    );
    let before: Vec<Option<(u64, u64)>> = children
        .iter()
        .map(|(_, child)| resident_and_cpu(child.id()))
        .collect();
    let measured = Instant::now();
    std::thread::sleep(Duration::from_secs(seconds));
    let elapsed = measured.elapsed().as_secs_f64();
    let ticks_per_second = 100.0; // USER_HZ on Linux
    let mut total_rss = 0;
    for ((name, child), before) in children.iter().zip(&before) {
        let (Some((_, cpu_before)), Some((rss, cpu_after))) =
            (before, resident_and_cpu(child.id()))
        else {
            println!("  {name:<8} ended during the measurement");
            continue;
        };
        total_rss += rss;
        println!(
            "  {name:<8} resident {:>6.1} MB  CPU {:>5.1} % of one core",
            rss as f64 / 1024.0,
            (cpu_after - cpu_before) as f64 / ticks_per_second / elapsed * 100.0
        );
    }
    println!("  all      resident {:>6.1} MB", total_rss as f64 / 1024.0);
    for (_, child) in &mut children {
        let _ = Command::new("kill")
            .args(["-TERM", &child.id().to_string()])
            .status();
    }
    for (_, child) in &mut children {
        let _ = child.wait();
    }
}
