//! `stanice balance`: the reader against the simulator over a pseudo-terminal, as a
//! lab technician checks a balance before the sorting lab starts.

use testkit::process::{run_bounded, start_until_line};

use crate::support::*;

#[test]
fn balance_read_prints_the_simulators_records_over_a_pty() {
    let mut simulator = stanice();
    simulator.args([
        "balance",
        "simulate",
        "--pty",
        "--ball",
        "blue 1",
        "--seed",
        "3",
        "--duration",
        "60s",
    ]);
    let (_simulator, line) = start_until_line(simulator, "pty: ");
    let pty = line.trim().trim_start_matches("pty: ").to_owned();
    let mut read = stanice();
    read.args([
        "balance",
        "read",
        "--serial",
        &pty,
        "--json",
        "--duration",
        "3s",
    ]);
    let output = run_bounded(read, 30);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let records: Vec<serde_json::Value> = String::from_utf8_lossy(&output.stdout)
        .lines()
        .map(|line| serde_json::from_str(line).unwrap())
        .collect();
    // 3 a second for 3 s (and what the pty held before the reader came)
    assert!(records.len() >= 7, "{records:?}");
    let last = records.last().unwrap();
    // blue 1 weighs 3.090 g with a 3-s scatter of 0.027 g; never stable with a ball
    let weight = last["weight_g"].as_f64().unwrap();
    assert!((weight - 3.09).abs() < 0.3, "{last}");
    assert_eq!(last["stable"], false);
    assert!(last["time"].as_str().unwrap().ends_with('Z'), "{last}");
    let summary = String::from_utf8_lossy(&output.stderr);
    assert!(summary.contains("legal record(s), 0 illegal"), "{summary}");
}

#[test]
fn balance_read_without_a_balance_says_so_and_fails() {
    let mut read = stanice();
    read.args(["balance", "read", "--pty", "--duration", "3s"]);
    let output = run_bounded(read, 30);
    assert!(!output.status.success());
    assert!(
        String::from_utf8_lossy(&output.stderr).contains("0 legal record(s)"),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
}
