//! The nodes' PLC: ST sources and programs, compile errors and encodings in the ST files,
//! and the PLC variables station.toml names (the last two: issue 11).

use station::config::Project;

use super::support::*;

#[test]
fn missing_st_source() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
sources = ["plc/main.st", "plc/gone.st"]
"#;
    expect_only(toml, &[PLC], 7, 27, "node[0].sources[1]", "not found");
}

#[test]
fn program_not_in_sources() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
sources = ["plc/main.st"]
[[node.task]]
name = "t"
interval_ms = 10
programs = ["Main", "Other"]
"#;
    expect_only(
        toml,
        &[PLC],
        11,
        21,
        "node[0].task[0].programs[1]",
        "no PROGRAM `Other`",
    );
}

/// A variable the node's PLC does not have is reported at its value in station.toml,
/// wherever the project names one (it used to stop the runtime without a place).
#[test]
fn unknown_plc_variables_are_reported_at_their_value() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
sources = ["plc/main.st"]
[node.server]
port_offset = 0
redundancy_groups = [{ name = "all", refuse_commands_when = "Main.Blocked" }]
[[node.io]]
signal = "RH2_QF1_Zapnut"
variable = "Main.Feedback"
[[node.point]]
name = "P"
type = "M_SP_NA_1"
ioa = 1
source = "Main.Typo"
invalid_when = "Main.Bad"
[[node.point]]
name = "Fine"
type = "M_SP_NA_1"
ioa = 2
source = "main.a"
[[node.command]]
name = "C"
type = "C_SC_NA_1"
ioa = 3
target = "Main.Cmd"
remote_enable = "Other.A"
"#;
    let errors = errors(toml, &[PLC]);
    expect(
        &errors,
        10,
        61,
        "node[0].server.redundancy_groups[0].refuse_commands_when",
        "no variable 'Main.Blocked'",
    );
    expect(
        &errors,
        13,
        12,
        "node[0].io[0].variable",
        "no variable 'Main.Feedback'",
    );
    expect(
        &errors,
        18,
        10,
        "node[0].point[0].source",
        "no variable 'Main.Typo' in the node's PLC program",
    );
    expect(
        &errors,
        19,
        16,
        "node[0].point[0].invalid_when",
        "no variable 'Main.Bad'",
    );
    expect(
        &errors,
        29,
        10,
        "node[0].command[0].target",
        "no variable 'Main.Cmd'",
    );
    expect(
        &errors,
        30,
        17,
        "node[0].command[0].remote_enable",
        "no variable 'Other.A'",
    );
    assert_eq!(errors.len(), 6, "{errors:#?}");
}

/// The ST sources are compiled at load: their errors are reported at their place.
#[test]
fn st_compile_errors_are_reported_in_the_st_file() {
    let toml = "[station]\nname = \"X\"\ntime_zone = \"UTC\"\n[[node]]\nname = \"A\"\ncommon_address = 1\nsources = [\"plc/main.st\"]\n";
    let dir = folder(
        toml,
        &[(
            "plc/main.st",
            "PROGRAM Main\nVAR A : BOOL; END_VAR\nA := nope;\nEND_PROGRAM\n",
        )],
    );
    let errors = Project::load(dir.path()).unwrap_err().into_errors();
    assert_eq!(errors.len(), 1, "{errors:#?}");
    assert_eq!(errors[0].file, dir.path().join("plc/main.st"));
    assert_eq!((errors[0].line, errors[0].column), (3, 6), "{errors:#?}");
    assert!(errors[0].message().contains("nope"), "{errors:#?}");
}

/// An ST file in Latin-1 is refused at its first invalid byte; a UTF-8 byte-order mark
/// (Windows editors write one) is accepted.
#[test]
fn st_sources_must_be_utf8_and_may_start_with_a_byte_order_mark() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
sources = ["plc/main.st"]
[[node.task]]
name = "t"
interval_ms = 10
programs = ["Main"]
[[node.point]]
name = "P"
type = "M_SP_NA_1"
ioa = 1
source = "Main.A"
"#;
    let dir = folder(toml, &[]);
    let st = dir.path().join("plc/main.st");
    std::fs::create_dir_all(st.parent().unwrap()).unwrap();
    std::fs::write(
        &st,
        b"\xEF\xBB\xBFPROGRAM Main\nVAR A : BOOL; END_VAR\nEND_PROGRAM\n",
    )
    .unwrap();
    Project::load(dir.path()).unwrap_or_else(|errors| panic!("{errors}"));

    std::fs::write(
        &st,
        b"PROGRAM Main\nVAR A : BOOL; (* caf\xE9 *) END_VAR\nEND_PROGRAM\n",
    )
    .unwrap();
    let errors = Project::load(dir.path()).unwrap_err().into_errors();
    assert_eq!(errors.len(), 1, "{errors:#?}");
    let error = &errors[0];
    assert_eq!(error.file, st);
    assert_eq!((error.line, error.column), (2, 21));
    assert_eq!(
        error.to_string(),
        format!(
            "{}:2:21: error: not UTF-8 text: byte 0xE9 (save the file as UTF-8)",
            st.display()
        )
    );
}

/// A point may show a direct address of the process image (`%IX0.0`: an input, whatever
/// program runs); an address the image does not have is reported at the source.
#[test]
fn point_sources_may_be_image_addresses() {
    let toml = |source: &str| {
        format!(
            r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
sources = ["plc/main.st"]
[[node.point]]
name = "P"
type = "M_SP_NA_1"
ioa = 1
source = "{source}"
"#
        )
    };
    load(&toml("%IX0.0"), &[PLC]).unwrap_or_else(|errors| panic!("{errors:?}"));
    let errors = errors(&toml("%IX0.9"), &[PLC]);
    assert!(
        errors
            .iter()
            .any(|e| e.to_string().contains("node[0].point[0].source")),
        "{errors:?}"
    );
}
