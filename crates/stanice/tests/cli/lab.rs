//! `stanice lab` as a student and a teacher run it: `run` with its exit codes, text and
//! JSON; `grade` writing the table; `signals`; mistakes refused in words.

use std::path::{Path, PathBuf};

use testkit::process::run_bounded;

use crate::support::*;

fn repository() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn lab(args: &[&str]) -> std::process::Output {
    let mut command = stanice();
    command.current_dir(repository()).arg("lab").args(args);
    run_bounded(command, 120)
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn lab_run_exits_0_on_a_met_scenario_1_on_a_violation_2_on_a_compile_error() {
    let passed = lab(&[
        "run",
        "mixing",
        "--program",
        "examples/lab/mixing.st",
        "--scenario",
        "examples/lab/scenarios/mixing.toml",
        "--duration",
        "3m",
    ]);
    assert_eq!(
        passed.status.code(),
        Some(0),
        "{}{}",
        text(&passed.stdout),
        text(&passed.stderr)
    );
    assert!(
        text(&passed.stdout).contains("PASSED"),
        "{}",
        text(&passed.stdout)
    );

    let failed = lab(&[
        "run",
        "slide",
        "--program",
        "examples/lab/class/boris.st",
        "--duration",
        "20s",
    ]);
    assert_eq!(failed.status.code(), Some(1));
    let out = text(&failed.stdout);
    assert!(
        out.contains("5.000 s  overtravel:") && out.contains("EM1=1") && out.contains("FAILED"),
        "{out}"
    );

    let source = write_source(
        "broken_lab.st",
        "PROGRAM Broken\nEM1 := TRUE;\nEND_PROGRAM\n",
    );
    let broken = lab(&["run", "slide", "--program", source.to_str().unwrap()]);
    assert_eq!(broken.status.code(), Some(2));
    assert!(
        text(&broken.stderr).contains("broken_lab.st:2:"),
        "{}",
        text(&broken.stderr)
    );
}

#[test]
fn lab_run_json_reports_each_violation_with_time_and_outputs() {
    let output = lab(&[
        "run",
        "washing",
        "--program",
        "examples/lab/wrong/washing_overheat.st",
        "--duration",
        "70s",
        "--json",
    ]);
    assert_eq!(output.status.code(), Some(1));
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(report["passed"], false);
    assert_eq!(report["model"], "washing");
    let first = &report["violations"][0];
    assert_eq!(first["kind"]["name"], "overheat");
    assert_eq!(first["time_s"], 61.0);
    let outputs = first["outputs"].as_array().unwrap();
    assert!(
        outputs
            .iter()
            .any(|pair| pair[0] == "topeni" && pair[1] == "1"),
        "{first}"
    );
}

#[test]
fn lab_grade_writes_the_class_table() {
    let class = testkit::projects::folder(&[]);
    let examples = repository().join("examples/lab");
    std::fs::copy(examples.join("crossroad.st"), class.path().join("anna.st")).unwrap();
    std::fs::copy(
        examples.join("wrong/crossroad_no_interlock.st"),
        class.path().join("boris.st"),
    )
    .unwrap();
    let output = lab(&[
        "grade",
        "--scenario",
        "examples/lab/scenarios/crossroad.toml",
        class.path().to_str().unwrap(),
        "--duration",
        "60s",
    ]);
    assert!(output.status.success(), "{}", text(&output.stderr));
    let out = text(&output.stdout);
    assert!(out.contains("1 of 2 passed"), "{out}");
    let csv = std::fs::read_to_string(class.path().join("grades.csv")).unwrap();
    assert!(
        csv.lines().any(|l| l.starts_with("anna,passed,0,")),
        "{csv}"
    );
    assert!(
        csv.lines()
            .any(|l| l.starts_with("boris,failed,") && l.contains("conflicting-greens")),
        "{csv}"
    );
    let html = std::fs::read_to_string(class.path().join("grades.html")).unwrap();
    assert!(html.contains("<td>boris</td>"), "{html}");
}

#[test]
fn lab_signals_lists_the_profile_addresses() {
    let model = lab(&["signals", "washing"]);
    assert!(
        text(&model.stdout).contains("voda_100,%IX0.7,PLC input"),
        "{}",
        text(&model.stdout)
    );
    let wiring = lab(&["signals", "washing", "--profile", "lab"]);
    assert!(
        text(&wiring.stdout).contains("voda_100,%IX84.3,PLC input"),
        "{}",
        text(&wiring.stdout)
    );
    let printed = lab(&["signals", "washing", "--profile", "lab-printed"]);
    assert!(
        text(&printed.stdout).contains("voda_100,%IX83.3,PLC input"),
        "{}",
        text(&printed.stdout)
    );
}

#[test]
fn lab_mistakes_are_refused_in_words() {
    let unknown = lab(&["run", "elevator", "--program", "examples/lab/slide.st"]);
    assert!(!unknown.status.success());
    assert!(
        text(&unknown.stderr)
            .contains("no lab model `elevator` (the models: slide, crossroad, mixing, washing)"),
        "{}",
        text(&unknown.stderr)
    );
    let wrong_model = lab(&[
        "run",
        "slide",
        "--program",
        "examples/lab/slide.st",
        "--scenario",
        "examples/lab/scenarios/mixing.toml",
    ]);
    assert!(
        text(&wrong_model.stderr).contains("is for the model `mixing`, not `slide`"),
        "{}",
        text(&wrong_model.stderr)
    );
    let option = lab(&[
        "run",
        "slide",
        "--program",
        "examples/lab/slide.st",
        "--option",
        "sensors=3,2,7,9",
    ]);
    assert!(!option.status.success());
    assert!(
        text(&option.stderr).contains("sensors"),
        "{}",
        text(&option.stderr)
    );
}
