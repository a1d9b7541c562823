//! The lab's reference solutions pass their scenarios, the deliberately wrong programs
//! fail with the right violation, and a class folder grades into the expected table: the
//! real compiler, the real models, the shipped files of `examples/lab`.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::time::Duration;

use lab::grade::Verdict;
use lab::run::{DEFAULT_DURATION, DEFAULT_SCAN};
use lab::{Program, Report, RunSettings, Scenario, Session, Speed, ViolationKind};
use plant::lab::{LabOptions, Profile};

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/lab")
}

fn scenario(model: &str) -> Scenario {
    Scenario::load(&examples().join(format!("scenarios/{model}.toml"))).unwrap()
}

fn settings(model: &str, scenario: Option<&Scenario>) -> RunSettings {
    RunSettings {
        model: model.to_owned(),
        profile: Profile::Model,
        options: LabOptions::parse(&scenario.map(|s| s.options.clone()).unwrap_or_default())
            .unwrap(),
        duration: scenario
            .and_then(|s| s.duration)
            .unwrap_or(DEFAULT_DURATION),
        scan: scenario.and_then(|s| s.scan).unwrap_or(DEFAULT_SCAN),
        speed: Speed::Max,
    }
}

fn run(model: &str, file: &str, scenario: Option<&Scenario>) -> Report {
    let program = Program::load(&[examples().join(file)], None).unwrap();
    Session::new(program, settings(model, scenario), scenario)
        .unwrap()
        .run()
        .unwrap()
}

fn run_reference(model: &str) -> Report {
    let scenario = scenario(model);
    let report = run(model, &format!("{model}.st"), Some(&scenario));
    assert!(report.passed, "{}", report.text());
    report
}

#[test]
fn the_slide_reference_runs_100_cycles_without_error() {
    let report = run_reference("slide");
    assert!(report.simulated_s >= 100.0 * 17.01, "{}", report.text());
    assert!(report.properties.iter().all(|p| p.violations == 0));
}

#[test]
fn the_crossroad_reference_never_shows_conflicting_greens() {
    run_reference("crossroad");
}

#[test]
fn the_mixing_reference_fills_transfers_mixes_and_empties_without_error() {
    run_reference("mixing");
}

#[test]
fn the_washing_reference_runs_its_programme_without_error() {
    run_reference("washing");
}

/// The first violation of a wrong program against its model's scenario.
fn first_violation(model: &str, file: &str) -> (f64, ViolationKind, String) {
    let scenario = scenario(model);
    let report = run(model, file, Some(&scenario));
    assert!(!report.passed, "{file} passed:\n{}", report.text());
    let first = report.first_violation().unwrap();
    (first.time_s, first.kind.clone(), first.line())
}

#[test]
fn wrong_programs_fail_with_their_violation() {
    let (time, kind, line) = first_violation("slide", "class/boris.st");
    assert_eq!(kind, ViolationKind::Model("overtravel".into()), "{line}");
    // nine rapid steps to K4 at 4.5 s, the tenth commanded step is past it at 5.0 s
    assert!((time - 5.0).abs() < 1e-9, "{line}");
    assert!(line.contains("EM1=1"), "{line}");

    let (_, kind, line) = first_violation("slide", "class/carol.st");
    assert_eq!(
        kind,
        ViolationKind::Model("both-directions".into()),
        "{line}"
    );
    assert!(line.contains("EM1=1") && line.contains("EM2=1"), "{line}");

    let (time, kind, line) = first_violation("mixing", "wrong/mixing_overflow.st");
    assert_eq!(kind, ViolationKind::Model("overflow".into()), "{line}");
    // the valve opens at 0 s: 84 L at the 14th second, over at the 15th
    assert!((time - 15.0).abs() < 1e-9, "{line}");

    let (_, kind, line) = first_violation("crossroad", "wrong/crossroad_no_interlock.st");
    assert_eq!(
        kind,
        ViolationKind::Model("conflicting-greens".into()),
        "{line}"
    );

    // The scenario's property (never above 61.5 °C, at 42 s of heating) comes before the
    // model's own overheat (above 90 °C, at 61 s).
    let scenario = scenario("washing");
    let report = run("washing", "wrong/washing_overheat.st", Some(&scenario));
    let first = report.first_violation().unwrap();
    assert_eq!(
        first.property.as_deref(),
        Some("never above 61.5 °C"),
        "{}",
        first.line()
    );
    assert!((first.time_s - 42.0).abs() < 1e-9, "{}", first.line());
    let overheat = report
        .violations
        .iter()
        .find(|v| v.kind == ViolationKind::Model("overheat".into()))
        .unwrap();
    assert!((overheat.time_s - 61.0).abs() < 1e-9, "{}", overheat.line());
    assert!(overheat.line().contains("topeni=1"), "{}", overheat.line());
}

#[test]
fn an_injected_fault_shows_what_a_program_does_when_a_sensor_fails() {
    // K3 stuck off from 10 s: the first cycle already paused at K3 (6.0 s .. 11.0 s); in
    // the second the reference runs back at rapid traverse waiting for K3, which never
    // comes, past K1: K4 at 21.51 s, position 1 at 26.01 s, the next step at 26.51 s.
    let text = r#"
model = "slide"
duration = "60s"

[[fault]]
at = "10s"
do = "stuck K3 off"
until = "40s"
"#;
    let scenario = Scenario::parse("stuck.toml", text).unwrap();
    let report = run("slide", "slide.st", Some(&scenario));
    assert_eq!(report.faults_injected.len(), 2, "{}", report.text());
    let first = report.first_violation().unwrap();
    assert_eq!(
        first.kind,
        ViolationKind::Model("overtravel".into()),
        "{}",
        report.text()
    );
    assert!((first.time_s - 26.51).abs() < 1e-6, "{}", report.text());
}

#[test]
fn a_run_does_not_depend_on_its_speed_or_report_layout() {
    let scenario = scenario("mixing");
    let mut short = settings("mixing", Some(&scenario));
    short.duration = Duration::from_secs(120);
    let program = || Program::load(&[examples().join("wrong/mixing_overflow.st")], None).unwrap();
    let fast = Session::new(program(), short.clone(), Some(&scenario))
        .unwrap()
        .run()
        .unwrap();
    short.speed = Speed::Times(1000.0);
    let paced = Session::new(program(), short, Some(&scenario))
        .unwrap()
        .run()
        .unwrap();
    assert_eq!(fast.violations, paced.violations);
    assert_eq!(fast.scans, paced.scans);
    let json = serde_json::to_value(&fast).unwrap();
    assert_eq!(json["passed"], false);
    assert_eq!(json["violations"][0]["kind"]["type"], "model");
    assert_eq!(json["violations"][0]["kind"]["name"], "overflow");
}

#[test]
fn the_lab_profile_runs_a_program_written_for_the_lab_wiring() {
    // The slide's reference with the lab's addresses (LAB-A8's pattern).
    let text = std::fs::read_to_string(examples().join("slide.st"))
        .unwrap()
        .replace("%QX0.0", "%QX2.0")
        .replace("%QX0.1", "%QX2.1")
        .replace("%QX0.2", "%QX2.2")
        .replace("%IX0.0", "%IX10.2")
        .replace("%IX0.2", "%IX10.4")
        .replace("%IX0.3", "%IX10.5");
    let program = Program::compile(&[("slide_lab.st".into(), text)], None).unwrap();
    let mut settings = settings("slide", None);
    settings.profile = Profile::Lab;
    settings.duration = Duration::from_secs(60);
    let report = Session::new(program, settings.clone(), None)
        .unwrap()
        .run()
        .unwrap();
    assert!(report.passed, "{}", report.text());
    // The same program against the model documentation's addresses never moves the slide
    // and so never fails, but never reaches K4 either: a property says so.
    let scenario = Scenario::parse(
        "k4.toml",
        "[[property]]\nname = \"reaches K4\"\neventually = \"K4\"\nwithin = \"10s\"\n",
    )
    .unwrap();
    let program = Program::load(&[examples().join("slide.st")], None).unwrap();
    let report = Session::new(program, settings, Some(&scenario))
        .unwrap()
        .run()
        .unwrap();
    assert!(!report.passed, "{}", report.text());
}

#[test]
fn the_example_class_grades_into_the_expected_table() {
    let scenario = scenario("slide");
    let mut settings = settings("slide", Some(&scenario));
    settings.duration = Duration::from_secs(120);
    let grades = lab::grade::grade(&examples().join("class"), &scenario, &settings, None).unwrap();
    let table: Vec<(&str, Verdict)> = grades
        .iter()
        .map(|g| (g.student.as_str(), g.verdict))
        .collect();
    assert_eq!(
        table,
        vec![
            ("anna", Verdict::Passed),
            ("boris", Verdict::Failed),
            ("carol", Verdict::Failed),
            ("dave", Verdict::DoesNotCompile),
            // two files compiled together: a FUNCTION_BLOCK and the PROGRAM
            ("erin", Verdict::Passed),
        ]
    );
    assert!(
        grades[1].first_violation.contains("overtravel"),
        "{:?}",
        grades[1]
    );
    assert!(
        grades[2].first_violation.contains("both-directions"),
        "{:?}",
        grades[2]
    );
    assert!(
        grades[3].diagnostics.contains("dave.st:8:"),
        "{:?}",
        grades[3]
    );
    let csv = lab::grade::csv(&grades).unwrap();
    assert!(
        csv.starts_with("student,verdict,violations,first violation,diagnostics"),
        "{csv}"
    );
    assert_eq!(
        csv.lines()
            .filter(|l| l.starts_with("anna,passed,0,"))
            .count(),
        1,
        "{csv}"
    );
    let html = lab::grade::html("slide <class>", &grades);
    assert!(html.contains("<title>slide &lt;class&gt;</title>"));
    assert!(html.contains("2 of 5 passed"));
}

#[test]
fn a_folder_of_loose_files_and_subfolders_is_a_class() {
    let class = tempfile::tempdir().unwrap();
    std::fs::copy(examples().join("slide.st"), class.path().join("zoe.st")).unwrap();
    std::fs::write(class.path().join("notes.txt"), "not ST").unwrap();
    std::fs::create_dir(class.path().join("empty")).unwrap();
    let found = lab::grade::submissions(class.path()).unwrap();
    assert_eq!(found.len(), 1);
    assert_eq!(found[0].student, "zoe");
}

#[test]
fn scenario_mistakes_are_refused_before_the_run() {
    let program = || Program::load(&[examples().join("slide.st")], None).unwrap();
    let unknown_name =
        Scenario::parse("bad.toml", "[[property]]\nname = \"x\"\nnever = \"EM9\"\n").unwrap();
    let error = Session::new(program(), settings("slide", None), Some(&unknown_name)).unwrap_err();
    assert!(error.to_string().contains("bad.toml:3:10"), "{error}");
    assert!(error.to_string().contains("EM9"), "{error}");
    let bad_line =
        Scenario::parse("bad.toml", "[[fault]]\nat = \"1s\"\ndo = \"stuck K9 on\"\n").unwrap();
    let error = Session::new(program(), settings("slide", None), Some(&bad_line)).unwrap_err();
    assert!(error.to_string().contains("stuck K9 on"), "{error}");
}
