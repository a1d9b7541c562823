//! `stanice sorting`: a sorting program behind the built-in supervisor against the
//! simulated mechanism, as a student runs it before booking the real lab.

use testkit::process::run_bounded;

use crate::support::*;

/// A student's first attempt: it holds gate S1 for good and drives both solenoids of
/// deflector 1 at once.
const CARELESS: &str = "
PROGRAM Careless
VAR
    cS1 AT %QX0.0 : BOOL;
    cS4 AT %QX0.3 : BOOL;
    cS5 AT %QX0.4 : BOOL;
END_VAR
    cS1 := Automatic;
    cS4 := Automatic;
    cS5 := Automatic;
END_PROGRAM
";

#[test]
fn the_reference_program_sorts_and_passes() {
    let mut command = stanice();
    command.args(["sorting", "run", "--seed", "3", "--json"]);
    let output = run_bounded(command, 120);
    assert!(
        output.status.success(),
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(json["passed"], true);
    let sorting = &json["sortings"][0];
    assert_eq!(sorting["finished"], true);
    assert_eq!(sorting["shafts"].as_array().unwrap().len(), 8);
    assert_eq!(sorting["events"].as_array().unwrap().len(), 0);
}

#[test]
fn a_careless_program_meets_the_supervisor_in_words() {
    let file = std::env::temp_dir().join(format!("stanice-careless-{}.st", std::process::id()));
    std::fs::write(&file, CARELESS).unwrap();
    let mut command = stanice();
    command.args(["sorting", "run", "--limit", "20s", "--program"]);
    command.arg(&file);
    let output = run_bounded(command, 60);
    let _ = std::fs::remove_file(&file);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(output.status.code(), Some(1), "{stdout}");
    assert!(stdout.contains("NOT finished"), "{stdout}");
    assert!(
        stdout.contains("supervisor: S1 locked out: on longer than MaxOnTime"),
        "{stdout}"
    );
    assert!(
        stdout.contains("supervisor: S5 refused: the opposed solenoid is on"),
        "{stdout}"
    );
    assert!(stdout.contains("FAILED"), "{stdout}");
}

#[test]
fn a_program_that_does_not_compile_is_shown_with_file_line_col() {
    let file = std::env::temp_dir().join(format!("stanice-broken-{}.st", std::process::id()));
    std::fs::write(&file, "PROGRAM Broken\nx := 1;\nEND_PROGRAM\n").unwrap();
    let mut command = stanice();
    command.args(["sorting", "run", "--program"]);
    command.arg(&file);
    let output = run_bounded(command, 30);
    let _ = std::fs::remove_file(&file);
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains(".st:2:"), "{stderr}");
}
