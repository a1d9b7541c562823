//! Error messages: `file:line:col: error: key: message`, syntax and schema errors at their
//! position, every problem reported, one error for an unclosed bracket and at most ten per
//! file (issue 11).

use station::config::{ConfigError, ConfigProblem, Project};

use super::support::*;

#[test]
fn syntax_error_has_position_and_display() {
    let toml = "[station]\nname = \"X\"\ntime_zone = \"UTC\n";
    let dir = folder(toml, &[]);
    let errors = Project::load(dir.path()).unwrap_err();
    let first = &errors.errors()[0];
    assert_eq!(first.line, 3);
    assert_eq!(first.key, "");
    let shown = errors.to_string();
    let file = dir.path().join("station.toml");
    assert!(
        shown.starts_with(&format!("{}:3:", file.display())),
        "{shown}"
    );
    assert!(shown.contains(": error: "), "{shown}");
}

#[test]
fn type_error_names_key_and_position() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
[[node.point]]
name = "P"
type = "M_SP_NA_1"
ioa = "many"
source = "Main.X"
"#;
    let errors = errors(toml, &[]);
    expect(&errors, 10, 7, "node[0].point[0].ioa", "invalid type");
    assert_eq!(errors.len(), 1);
}

#[test]
fn display_is_file_line_col_error_key_message() {
    let error = ConfigError {
        file: "p/station.toml".into(),
        line: 4,
        column: 9,
        key: "node[2].point[5].ioa".into(),
        problem: ConfigProblem::OutOfRange {
            what: "IOA",
            value: 0,
            min: 1,
            max: Some(16_777_215),
        },
    };
    assert_eq!(
        error.to_string(),
        "p/station.toml:4:9: error: node[2].point[5].ioa: IOA 0 is outside 1..=16777215"
    );
    assert_eq!(error.message(), "IOA 0 is outside 1..=16777215");
}

#[test]
fn unknown_key_is_refused() {
    let toml = "[station]\nname = \"X\"\ntime_zone = \"UTC\"\nretention = 5\n";
    let errors = errors(toml, &[]);
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert_eq!(errors[0].line, 4, "{errors:?}");
    assert!(errors[0].message().contains("retention"), "{errors:?}");
}

#[test]
fn missing_project_file() {
    let dir = tempfile::tempdir().unwrap();
    let errors = Project::load(dir.path()).unwrap_err();
    assert_eq!(errors.errors()[0].line, 0);
    assert!(errors
        .to_string()
        .contains("station.toml: error: cannot read"));
}

#[test]
fn every_problem_is_reported() {
    let toml = r#"[station]
name = "X"
time_zone = "Mars/Olympus"
retention_days = 0
[[node]]
name = "A"
common_address = 0
sources = ["nope.st"]
[[node]]
name = "A"
common_address = 1
"#;
    let errors = errors(toml, &[]);
    expect(&errors, 3, 13, "station.time_zone", "unknown");
    expect(&errors, 4, 18, "station.retention_days", "at least 1");
    expect(&errors, 7, 18, "node[0].common_address", "outside");
    expect(&errors, 8, 12, "node[0].sources[0]", "not found");
    expect(&errors, 10, 8, "node[1].name", "duplicate");
    assert_eq!(errors.len(), 5, "{errors:#?}");
}

#[test]
fn type_errors_deep_in_interleaved_arrays_of_tables() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
[[node.point]]
name = "P0"
type = "M_SP_NA_1"
ioa = 1
source = "M.A"
[[node.command]]
name = "C0"
type = "C_SC_NA_1"
ioa = 1
target = "M.C"
[[node.point]]
name = "P1"
type = "M_SP_NA_1"
ioa = 2
source = "M.A"
groups = ["one"]
[[node]]
name = "B"
common_address = 2
[node.server]
port_offset = "x"
"#;
    let errors = errors(toml, &[]);
    // serde stops at the first type error
    expect(
        &errors,
        22,
        11,
        "node[0].point[1].groups[0]",
        "invalid type",
    );
    assert_eq!(errors.len(), 1);
    let fixed = toml.replace("groups = [\"one\"]", "groups = [1]");
    let errors = self::errors(&fixed, &[]);
    expect(
        &errors,
        27,
        15,
        "node[1].server.port_offset",
        "invalid type",
    );
}

#[test]
fn missing_required_key_names_its_table() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
[[node.link]]
node = "B"
"#;
    let errors = errors(toml, &[]);
    assert_eq!(errors.len(), 1, "{errors:#?}");
    assert!(
        errors[0].message().contains("missing field `name`"),
        "{errors:#?}"
    );
    assert!(errors[0].key.starts_with("node[0]"), "{errors:#?}");
    assert!(errors[0].line >= 4, "{errors:#?}");
}

/// One unclosed `[` made the recovering parser report every later line (17,161 errors
/// for the Vsetín project): only the first syntax error is reported.
#[test]
fn one_unclosed_bracket_is_one_error() {
    let mut toml = String::from(
        "[station]\nname = \"X\"\ntime_zone = \"UTC\"\n[[node]]\nname = \"A\"\ncommon_address = 1\nsources = [\"plc/main.st\"\n",
    );
    for p in 0..50 {
        toml.push_str(&format!(
            "[[node.point]]\nname = \"P{p}\"\ntype = \"M_SP_NA_1\"\nioa = {}\nsource = \"Main.A\"\n",
            p + 1
        ));
    }
    let errors = errors(&toml, &[PLC]);
    assert_eq!(errors.len(), 1, "{errors:#?}");
    expect(&errors, 8, 1, "", "missing comma");

    let vsetin = std::fs::read_to_string(testkit::projects::vsetin().join("station.toml")).unwrap();
    let (line, _) = vsetin
        .lines()
        .enumerate()
        .find(|(_, l)| l.starts_with("sources = [") && l.ends_with(']'))
        .unwrap();
    let broken: Vec<String> = vsetin
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i == line {
                l.trim_end_matches(']').to_owned()
            } else {
                l.to_owned()
            }
        })
        .collect();
    let file = testkit::projects::vsetin().join("station.toml");
    let errors =
        Project::parse(&testkit::projects::vsetin(), &file, &broken.join("\n")).unwrap_err();
    assert_eq!(errors.errors().len(), 1, "{errors}");
    assert_eq!(errors.total(), 1);
}

/// Past ten problems in one file, the rest are counted, not listed.
#[test]
fn at_most_ten_errors_per_file_then_a_count() {
    let mut toml = String::from("[station]\nname = \"X\"\ntime_zone = \"UTC\"\n[[node]]\nname = \"A\"\ncommon_address = 1\n");
    for p in 0..15 {
        toml.push_str(&format!(
            "[[node.point]]\nname = \"P{p}\"\ntype = \"M_SP_NA_1\"\nioa = 7\nsource = \"M.A\"\n"
        ));
    }
    let dir = folder(&toml, &[]);
    let errors = Project::load(dir.path()).unwrap_err();
    assert_eq!(errors.errors().len(), 10);
    assert_eq!(errors.total(), 14);
    let file = dir.path().join("station.toml");
    assert_eq!(errors.omitted(), [(file.clone(), 4)]);
    // the first ten, in file order: point[1] is the first duplicate
    expect(
        errors.errors(),
        15,
        7,
        "node[0].point[1].ioa",
        "IOA 7 is also used",
    );
    assert!(
        errors
            .to_string()
            .ends_with(&format!("\n{}: ... and 4 more error(s)", file.display())),
        "{errors}"
    );
}
