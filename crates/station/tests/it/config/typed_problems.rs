//! Typed problems: a program matches on what is wrong, not on the message's words.

use station::config::problem::{
    Conflict, Form, Reference, SchemaKind, TypeUse, Unique, Vocabulary,
};
use station::config::{ConfigError, ConfigProblem, Project};

use super::support::*;

/// The problems of `toml` (with `files`), without their places.
fn problems(toml: &str, files: &[(&str, &str)]) -> Vec<ConfigProblem> {
    errors(toml, files).into_iter().map(|e| e.problem).collect()
}

const ONE_NODE: &str =
    "[station]\nname = \"X\"\ntime_zone = \"UTC\"\n[[node]]\nname = \"A\"\ncommon_address = 1\n";

#[test]
fn unknown_references_are_typed_by_what_they_name() {
    let toml = format!(
        "{TWO_NODES}{}",
        r#"[[node.link]]
name = "L1"
node = "Ghost"
[[node.link]]
name = "L2"
node = "Low"
[[node.point]]
name = "Q"
type = "M_SP_NA_1"
ioa = 1
source = "link:L2/99"
[[node.command]]
name = "K"
type = "C_SC_NA_1"
ioa = 2
target = "link:Gone/20"
[[node.command]]
name = "F"
type = "C_SC_NA_1"
ioa = 3
target = "M.F"
feedback = "Nope"
"#
    );
    let problems = problems(&toml, &[]);
    assert!(
        problems.contains(&ConfigProblem::Unknown {
            what: Reference::Node,
            name: "Ghost".into(),
            within: String::new(),
        }),
        "{problems:#?}"
    );
    assert!(problems.contains(&ConfigProblem::Unknown {
        what: Reference::LowerPoint,
        name: "99".into(),
        within: "Low".into(),
    }));
    assert!(problems.contains(&ConfigProblem::Unknown {
        what: Reference::Link,
        name: "Gone".into(),
        within: "Top".into(),
    }));
    assert!(problems.contains(&ConfigProblem::Unknown {
        what: Reference::Point,
        name: "Nope".into(),
        within: "Top".into(),
    }));
    assert!(
        problems
            .iter()
            .all(|p| matches!(p, ConfigProblem::Unknown { .. })),
        "{problems:#?}"
    );
}

#[test]
fn duplicates_are_typed_with_the_value_and_its_first_holder() {
    let toml = format!(
        "{ONE_NODE}{}",
        r#"[[node.point]]
name = "P"
type = "M_SP_NA_1"
ioa = 5
source = "M.A"
[[node.point]]
name = "P"
type = "M_SP_NA_1"
ioa = 5
source = "M.B"
[[node]]
name = "A"
common_address = 2
"#
    );
    let errors = errors(&toml, &[]);
    let duplicates: Vec<(&str, Unique, &str, &str)> = errors
        .iter()
        .filter_map(|e| match &e.problem {
            ConfigProblem::Duplicate { what, value, other } => {
                Some((e.key.as_str(), *what, value.as_str(), other.as_str()))
            }
            _ => None,
        })
        .collect();
    assert_eq!(
        duplicates,
        [
            ("node[0].point[1].name", Unique::PointName, "P", "A"),
            ("node[0].point[1].ioa", Unique::PointIoa, "5", "P"),
            ("node[1].name", Unique::NodeName, "A", "node[0]"),
        ],
        "{errors:#?}"
    );
    assert_eq!(errors.len(), 3, "{errors:#?}");
}

#[test]
fn out_of_range_values_carry_value_and_bounds() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
retention_days = 0
[[node]]
name = "A"
common_address = 70000
[[node.point]]
name = "P"
type = "M_SP_NA_1"
ioa = 0
source = "M.A"
groups = [17]
"#;
    let problems = problems(toml, &[]);
    assert_eq!(
        problems,
        [
            ConfigProblem::OutOfRange {
                what: "retention_days",
                value: 0,
                min: 1,
                max: None,
            },
            ConfigProblem::OutOfRange {
                what: "common address",
                value: 70000,
                min: 1,
                max: Some(65534),
            },
            ConfigProblem::OutOfRange {
                what: "IOA",
                value: 0,
                min: 1,
                max: Some(16_777_215),
            },
            ConfigProblem::OutOfRange {
                what: "interrogation group",
                value: 17,
                min: 1,
                max: Some(16),
            },
        ]
    );
    // the common address keeps its note on the reserved values
    assert_eq!(
        problems[1].to_string(),
        "common address 70000 is outside 1..=65534 (0 is unused, 65535 is broadcast)"
    );
}

#[test]
fn missing_files_are_typed_with_their_path() {
    // station.toml itself: unreadable, with the operating system's reason
    let dir = tempfile::tempdir().unwrap();
    let errors = Project::load(dir.path()).unwrap_err().into_errors();
    assert!(
        matches!(
            &errors[0].problem,
            ConfigProblem::Unreadable {
                file: None,
                kind: std::io::ErrorKind::NotFound,
                ..
            }
        ),
        "{errors:#?}"
    );
    assert!(errors[0].message().starts_with("cannot read: "));

    // a file station.toml names
    let toml = format!("{ONE_NODE}sources = [\"plc/gone.st\"]\n");
    let dir = folder(&toml, &[]);
    let errors = Project::load(dir.path()).unwrap_err().into_errors();
    assert_eq!(
        errors.iter().map(|e| &e.problem).collect::<Vec<_>>(),
        [&ConfigProblem::FileNotFound {
            path: dir.path().join("plc/gone.st")
        }]
    );
}

#[test]
fn syntax_and_schema_errors_are_typed() {
    let syntax = problems("[station]\nname = \"X\"\ntime_zone = \"UTC\n", &[]);
    assert!(
        matches!(syntax.as_slice(), [ConfigProblem::Syntax { detail }] if !detail.is_empty()),
        "{syntax:#?}"
    );

    let schema = |toml: &str| match problems(toml, &[]).as_slice() {
        [ConfigProblem::Schema { kind, .. }] => kind.to_owned(),
        other => panic!("{other:#?}"),
    };
    assert_eq!(
        schema("[station]\nname = \"X\"\ntime_zone = \"UTC\"\nretention = 5\n"),
        SchemaKind::UnknownKey
    );
    assert_eq!(
        schema("[station]\nname = \"X\"\ntime_zone = \"UTC\"\nport_base = \"x\"\n"),
        SchemaKind::WrongType
    );
    assert_eq!(schema("[station]\nname = \"X\"\n"), SchemaKind::MissingKey);
}

#[test]
fn st_compile_errors_are_typed_with_the_compiler_code() {
    let toml = format!("{ONE_NODE}sources = [\"plc/main.st\"]\n");
    let errors = errors(
        &toml,
        &[(
            "plc/main.st",
            "PROGRAM Main\nVAR A : BOOL; END_VAR\nA := nope;\nEND_PROGRAM\n",
        )],
    );
    assert!(
        matches!(
            &errors[..],
            [ConfigError {
                problem: ConfigProblem::StDiagnostic { code: plc::Code::Undeclared, message, .. },
                ..
            }] if message.contains("nope")
        ),
        "{errors:#?}"
    );

    // a PLC variable the node names and the program lacks: an unknown reference
    let toml = format!(
        "{ONE_NODE}sources = [\"plc/main.st\"]\n[[node.point]]\nname = \"P\"\ntype = \"M_SP_NA_1\"\nioa = 1\nsource = \"Main.Typo\"\n"
    );
    assert_eq!(
        problems(&toml, &[PLC]),
        [ConfigProblem::UnknownVariable {
            name: "Main.Typo".into(),
            suggestion: String::new(),
        }]
    );
    // a near miss gets a "did you mean"
    let toml = toml.replace("Main.Typo", "Mian.X");
    assert_eq!(
        problems(&toml, &[PLC]),
        [ConfigProblem::UnknownVariable {
            name: "Mian.X".into(),
            suggestion: "; did you mean `Main.X`?".into(),
        }]
    );
}

#[test]
fn types_forms_conflicts_and_vocabularies_are_typed() {
    let toml = r#"[station]
name = "X"
time_zone = "Mars/Olympus"
bind = "localhost"
[[node]]
name = "A"
common_address = 1
[[node.point]]
name = "P"
type = "C_SC_NA_1"
ioa = 1
source = "M.A"
cycle_ms = 100
[[node.point]]
name = "D"
type = "M_SP_NA_1"
ioa = 2
source = "M.D"
deadband = 0.5
[[node.link]]
name = "L"
node = "A"
address = "10.0.0.1:2404"
"#;
    let problems = problems(toml, &[]);
    for expected in [
        ConfigProblem::UnknownValue {
            what: Vocabulary::TimeZone,
            value: "Mars/Olympus".into(),
        },
        ConfigProblem::Malformed {
            text: "localhost".into(),
            form: Form::IpAddress,
        },
        ConfigProblem::WrongType {
            type_id: "C_SC_NA_1".into(),
            usage: TypeUse::Point,
        },
        ConfigProblem::Conflict(Conflict::CycleWithoutCyclic),
        ConfigProblem::WrongType {
            type_id: "M_SP_NA_1".into(),
            usage: TypeUse::Deadband,
        },
        ConfigProblem::Conflict(Conflict::NodeAndAddress),
    ] {
        assert!(
            problems.contains(&expected),
            "{expected:?} not in {problems:#?}"
        );
    }
    assert_eq!(problems.len(), 6, "{problems:#?}");
}
