//! `stanice stats thresholds`: the sorting lab's class limits from the shipped weighings,
//! as a teacher derives them before the lab.

use testkit::process::run_bounded;

use crate::support::*;

const WEIGHINGS: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../examples/sorting-lab/weighings.csv"
);

fn close(json: &serde_json::Value, expected: f64, tolerance: f64) -> bool {
    json.as_f64()
        .is_some_and(|value| (value - expected).abs() <= tolerance)
}

/// The shipped weighings reproduce table 5.1's 3-s columns at 99 % (the
/// sorting-lab thesis, section 12.3) and, at 95 % with 90 % coverage, the class
/// limits of section 12.4.
#[test]
fn stats_thresholds_reproduces_table_5_1_from_the_shipped_weighings() {
    let mut command = stanice();
    command.args(["stats", "thresholds", WEIGHINGS, "--json"]);
    let output = run_bounded(command, 30);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(json["weighings"], 128);
    assert_eq!(json["confidence"], 0.99);
    let balls = json["balls"].as_array().unwrap();
    assert_eq!(balls.len(), 8);
    let red_1 = &balls[0];
    assert_eq!(red_1["ball"], "red 1");
    assert_eq!(red_1["n"], 16);
    assert!(
        close(&red_1["mean_interval_g"]["lower"], 2.24, 0.01),
        "{red_1}"
    );
    assert!(
        close(&red_1["mean_interval_g"]["upper"], 2.34, 0.01),
        "{red_1}"
    );
    assert!(close(&red_1["sigma_upper_g"], 0.12, 0.01), "{red_1}");
    // blue 2: the table prints 0.07, its own interval says 0.080
    let blue_2 = &balls[5];
    assert_eq!(blue_2["ball"], "blue 2");
    assert!(close(&blue_2["sigma_upper_g"], 0.0813, 5e-4), "{blue_2}");
    // at 99 % coverage neighbouring colours overlap
    let limits = json["limits"].as_array().unwrap();
    assert_eq!(limits.len(), 3);
    assert!(limits
        .iter()
        .all(|limit| limit["gap_g"].as_f64().unwrap() < 0.0));

    let mut command = stanice();
    command.args([
        "stats",
        "thresholds",
        WEIGHINGS,
        "--confidence",
        "0.95",
        "--coverage",
        "90%",
        "--json",
    ]);
    let output = run_bounded(command, 30);
    assert!(output.status.success());
    let json: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let limits: Vec<f64> = json["limits"]
        .as_array()
        .unwrap()
        .iter()
        .map(|limit| limit["limit_g"].as_f64().unwrap())
        .collect();
    for (limit, expected) in limits.iter().zip([2.495, 2.892, 3.283]) {
        assert!((limit - expected).abs() <= 0.01, "{limits:?}");
    }
    assert!(
        close(&json["colours"][0]["union_g"]["lower"], 2.09, 0.01),
        "{json}"
    );
    assert!(json["reliability"]["expected"].as_f64().unwrap() > 0.99);
}

#[test]
fn stats_thresholds_prints_tables_and_writes_a_plot() {
    let plot = std::env::temp_dir().join(format!("stanice-cli-{}-limits.svg", std::process::id()));
    let mut command = stanice();
    command
        .args(["stats", "thresholds", WEIGHINGS, "--plot"])
        .arg(&plot);
    let output = run_bounded(command, 30);
    assert!(output.status.success());
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(
        text.contains("t(0.995; 15) = 2.9467, chi2(0.01; 15) = 5.2293"),
        "{text}"
    );
    assert!(text.contains("⟨2.240, 2.340⟩"), "{text}");
    assert!(
        text.contains("decision limits: 2.511 (red | yellow)"),
        "{text}"
    );
    assert!(
        text.contains("overlapping unions: red and yellow"),
        "{text}"
    );
    let svg = std::fs::read_to_string(&plot).unwrap();
    assert!(svg.starts_with("<svg"));
    assert_eq!(svg.matches("<path class=\"ball\"").count(), 8);
    let _ = std::fs::remove_file(&plot);
}

#[test]
fn stats_thresholds_names_the_line_of_a_ball_weighed_once() {
    let csv = write_source(
        "once.csv",
        "ball,weight_g\nred 1,2.29\nred 1,2.30\nblue 2,3.10\n",
    );
    let mut command = stanice();
    command.args(["stats", "thresholds"]).arg(&csv);
    let output = run_bounded(command, 30);
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("line 4: ball `blue 2` has 1 weighing(s)"),
        "{stderr}"
    );
    assert!(output.stdout.is_empty());
    let _ = std::fs::remove_file(&csv);
}
