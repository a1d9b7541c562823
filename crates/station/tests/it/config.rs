//! `station::config`: real project folders in temp dirs; every semantic check asserts the
//! exact `line:col` and key of its error.

use std::net::SocketAddr;
use std::path::Path;
use std::time::Duration;

use iec60870::asdu::{CommonAddress, Ioa, TypeId};
use proptest::prelude::*;
use station::config::problem::{
    Conflict, Form, Reference, SchemaKind, TypeUse, Unique, Vocabulary,
};
use station::config::{
    CommandTarget, ConfigError, ConfigProblem, LineProtocol, LineSignal, LinkTarget, PointSource,
    Project, Transmission,
};

/// A project folder with `station.toml` = `toml` and the extra `files`.
fn folder(toml: &str, files: &[(&str, &str)]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("station.toml"), toml).unwrap();
    for (path, text) in files {
        let path = dir.path().join(path);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }
    dir
}

fn load(toml: &str, files: &[(&str, &str)]) -> Result<Project, Vec<ConfigError>> {
    let dir = folder(toml, files);
    Project::load(dir.path()).map_err(|e| e.into_errors())
}

fn errors(toml: &str, files: &[(&str, &str)]) -> Vec<ConfigError> {
    match load(toml, files) {
        Ok(_) => panic!("the project loaded:\n{toml}"),
        Err(errors) => errors,
    }
}

/// Asserts that an error at `line:col` with `key` and a message containing `message` is
/// among the errors.
#[track_caller]
fn expect(errors: &[ConfigError], line: usize, column: usize, key: &str, message: &str) {
    let listing: Vec<String> = errors.iter().map(|e| e.to_string()).collect();
    assert!(
        errors.iter().any(|e| e.line == line
            && e.column == column
            && e.key == key
            && e.message().contains(message)),
        "no error {line}:{column}: {key}: ...{message}... in\n{}",
        listing.join("\n")
    );
}

#[track_caller]
fn expect_only(
    toml: &str,
    files: &[(&str, &str)],
    line: usize,
    column: usize,
    key: &str,
    message: &str,
) {
    let errors = errors(toml, files);
    expect(&errors, line, column, key, message);
    assert_eq!(errors.len(), 1, "{errors:#?}");
}

const PLC: (&str, &str) = (
    "plc/main.st",
    "PROGRAM Main\nVAR_INPUT A : BOOL; END_VAR\nVAR X : REAL; END_VAR\nEND_PROGRAM\n",
);

#[test]
fn minimal_project_loads_with_defaults() {
    let dir = folder(
        r#"[station]
name = "Test"
time_zone = "Europe/Prague"

[[node]]
name = "A"
common_address = 1
sources = ["plc/main.st"]
[node.server]
port_offset = 3
[[node.task]]
name = "fast"
interval_ms = 50
programs = ["main"]
[[node.point]]
name = "P"
type = "M_ME_NC_1"
ioa = 1
source = "Main.X"
transmission = "cyclic"
cycle_ms = 1000
groups = [1, 16]
deadband = 0.5
[[node.command]]
name = "C"
type = "C_SC_NA_1"
ioa = 2
target = "Main.A"
"#,
        &[PLC],
    );
    let project = Project::load(dir.path()).unwrap();
    assert_eq!(project.folder, dir.path());
    let s = &project.station;
    assert_eq!(s.name, "Test");
    assert_eq!(s.time_zone, chrono_tz::Europe::Prague);
    assert_eq!(
        s.store,
        format!("sqlite:{}", dir.path().join("events.sqlite").display())
    );
    assert_eq!((s.retention_days, s.port_base), (60, 2404));
    assert_eq!(s.bind.to_string(), "127.0.0.1");
    assert_eq!(s.plant, None);
    let a = project.node("A").unwrap();
    assert_eq!(a.common_address, CommonAddress::new(1));
    assert_eq!(a.sources, vec![dir.path().join("plc/main.st")]);
    let server = a.server.as_ref().unwrap();
    assert!(server.allowed_clients.is_empty());
    // Time-tagged commands older than 30 s are refused unless the project says otherwise.
    assert_eq!(server.max_command_age, Some(Duration::from_secs(30)));
    assert_eq!(server.redundancy_groups.len(), 1);
    assert!(server.redundancy_groups[0].clients.is_empty());
    assert_eq!(
        a.server_address(s),
        Some("127.0.0.1:2407".parse::<SocketAddr>().unwrap())
    );
    assert_eq!(a.tasks[0].interval, Duration::from_millis(50));
    assert_eq!(a.tasks[0].watchdog, None);
    let p = &a.points[0];
    assert_eq!(points_iec::type_id(p.point_type), TypeId::M_ME_NC_1);
    assert_eq!(p.ioa, Ioa::from(1u8));
    assert_eq!(p.source, PointSource::Variable("Main.X".into()));
    assert_eq!(
        p.transmission,
        Transmission::Cyclic {
            period: Duration::from_millis(1000)
        }
    );
    assert_eq!(p.groups, vec![1, 16]);
    assert_eq!(p.deadband, Some(0.5));
    assert_eq!(
        a.commands[0].target,
        CommandTarget::Variable("Main.A".into())
    );
    assert!(!a.commands[0].select_required);

    let moved = project.with_port_base(3000);
    let a = moved.node("A").unwrap();
    assert_eq!(a.server_address(&moved.station).unwrap().port(), 3003);
}

/// `max_command_age_ms`: milliseconds, or "off" for no limit; another word is refused
/// at its position.
#[test]
fn the_maximum_command_delay_is_set_or_turned_off() {
    let project = |age: &str| {
        format!(
            "[station]\nname = \"T\"\ntime_zone = \"UTC\"\n[[node]]\nname = \"A\"\n\
             common_address = 1\n[node.server]\nport_offset = 0\nmax_command_age_ms = {age}\n"
        )
    };
    let age = |text: &str| {
        load(&project(text), &[])
            .unwrap()
            .node("A")
            .unwrap()
            .server
            .as_ref()
            .unwrap()
            .max_command_age
    };
    assert_eq!(age("5000"), Some(Duration::from_secs(5)));
    assert_eq!(age("\"off\""), None);
    expect_only(
        &project("\"never\""),
        &[],
        9,
        22,
        "node[0].server.max_command_age_ms",
        "\"off\" (no limit)",
    );
}

#[test]
fn station_only_loads() {
    let project = load(
        "[station]\nname = \"X\"\ntime_zone = \"UTC\"\nstore = \"postgres://u@h/db\"\n",
        &[],
    )
    .unwrap();
    assert!(project.nodes.is_empty());
    assert_eq!(project.station.store, "postgres://u@h/db");
}

#[test]
fn vsetin_example_loads() {
    let project = match Project::load(&testkit::projects::vsetin()) {
        Ok(p) => p,
        Err(e) => panic!("{e}"),
    };
    assert_eq!(project.station.name, "Vsetín");
    let names: Vec<&str> = project.nodes.iter().map(|n| n.name.as_str()).collect();
    assert_eq!(&names[..6], ["RDRT", "RH1.1", "RH2", "RZS1", "RZZ", "RDA"]);
    assert_eq!(names.len(), 6 + 13);
    assert!(names.contains(&"ROV12") && names.contains(&"OR"));

    let rh2 = project.node("RH2").unwrap();
    let single: Vec<u32> = rh2
        .points
        .iter()
        .filter(|p| points_iec::type_id(p.point_type) == TypeId::M_SP_TB_1)
        .map(|p| p.ioa.get())
        .collect();
    assert_eq!(single, (281..=298).collect::<Vec<_>>());
    let meter: Vec<u32> = rh2
        .points
        .iter()
        .filter(|p| points_iec::type_id(p.point_type) == TypeId::M_ME_TF_1)
        .map(|p| p.ioa.get())
        .collect();
    assert_eq!(meter, [271, 272, 273, 274]);
    let commands: Vec<(u32, TypeId)> = rh2
        .commands
        .iter()
        .map(|c| (c.ioa.get(), c.type_id))
        .collect();
    assert_eq!(
        commands,
        [(2021, TypeId::C_SC_NA_1), (2022, TypeId::C_SC_NA_1)]
    );
    assert_eq!(
        rh2.commands[0].target,
        CommandTarget::Variable("RH2Logic.Cmd_VypnoutQF1".into())
    );
    assert_eq!(rh2.tasks[0].programs, ["RH2Logic"]);

    // RH1.1 republishes RH2 whole (same IOAs) beside its own link status point 280.
    let rh11 = project.node("RH1.1").unwrap();
    assert_eq!(rh11.points.len(), 23);
    assert_eq!(rh11.points[0].source, PointSource::LinkStatus("RH2".into()));
    assert_eq!(rh11.link("RH2").unwrap().republish, Some(0));
    assert_eq!(
        rh11.points[1].source,
        PointSource::Link {
            link: "RH2".into(),
            ioa: 281
        }
    );
    assert_eq!(
        rh11.commands[1].target,
        CommandTarget::Link {
            link: "RH2".into(),
            ioa: Ioa::from(2022u16)
        }
    );
    let link = rh11.link("RH2").unwrap();
    assert_eq!(link.target, LinkTarget::Node("RH2".into()));
    assert_eq!(link.common_address, rh2.common_address);
    assert!(link.interrogate_on_start && link.clock_sync);
    let rh2_address = project.link_address(link).unwrap();
    assert_eq!(Some(rh2_address), rh2.server_address(&project.station));

    let rdrt = project.node("RDRT").unwrap();
    assert_eq!(
        rdrt.server_address(&project.station),
        Some("127.0.0.1:2404".parse().unwrap())
    );
    let status = rdrt.point("COMM_RH").unwrap();
    assert_eq!(status.source, PointSource::LinkStatus("RH".into()));
    // Transitive republishing: RH2's points reach RDRT through RH1.1 at their thesis IOAs,
    // RZZ's through RZS1 shifted by 100, lighting board k at 10000 + 100 k.
    assert_eq!(rdrt.point("RH2_V1_FA1_Zapnut").unwrap().ioa.get(), 281);
    assert_eq!(
        rdrt.point("RH2_V1_FA1_Zapnut").unwrap().source,
        PointSource::Link {
            link: "RH".into(),
            ioa: 281
        }
    );
    assert_eq!(rdrt.point("RZZ_V1_FA1_Zapnut").unwrap().ioa.get(), 381);
    assert_eq!(rdrt.point("ROV05_Osv_Zap").unwrap().ioa.get(), 10_511);
    assert_eq!(rdrt.point("OR_Energie_kWh").unwrap().ioa.get(), 11_332);
    let forwarded: Vec<u32> = rdrt
        .commands
        .iter()
        .filter(|c| c.name.starts_with("RH2_"))
        .map(|c| c.ioa.get())
        .collect();
    assert_eq!(forwarded, [2021, 2022]);
    assert_eq!(rdrt.points.len(), 416);
    assert_eq!(
        rdrt.point("COMM_HMI").unwrap().source,
        PointSource::ClientStatus("hmi".into())
    );
    assert_eq!(
        rdrt.link("RH").unwrap().status_point.as_deref(),
        Some("COMM_RH")
    );

    // --port-base moves every server, and the links follow
    let moved = project.clone().with_port_base(12000);
    let rdrt = moved.node("RDRT").unwrap();
    assert_eq!(rdrt.server_address(&moved.station).unwrap().port(), 12000);
    let link = moved.node("RH1.1").unwrap().link("RH2").unwrap();
    assert_eq!(moved.link_address(link).unwrap().port(), 12002);
}

// ---------------------------------------------------------------------------------------
// syntax and type errors

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

// ---------------------------------------------------------------------------------------
// semantic checks

#[test]
fn unknown_time_zone() {
    expect_only(
        "[station]\nname = \"X\"\ntime_zone = \"Europe/Vsetin\"\n",
        &[],
        3,
        13,
        "station.time_zone",
        "unknown time zone",
    );
}

#[test]
fn retention_zero() {
    expect_only(
        "[station]\nname = \"X\"\ntime_zone = \"UTC\"\nretention_days = 0\n",
        &[],
        4,
        18,
        "station.retention_days",
        "at least 1",
    );
}

#[test]
fn common_address_zero_and_broadcast() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 0
[[node]]
name = "B"
common_address = 65535
"#;
    let errors = errors(toml, &[]);
    expect(
        &errors,
        6,
        18,
        "node[0].common_address",
        "outside 1..=65534",
    );
    expect(
        &errors,
        9,
        18,
        "node[1].common_address",
        "outside 1..=65534",
    );
    assert_eq!(errors.len(), 2);
}

#[test]
fn duplicate_node_names() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
[[node]]
name = "A"
common_address = 2
"#;
    expect_only(toml, &[], 8, 8, "node[1].name", "duplicate node name `A`");
}

#[test]
fn duplicate_ioas_of_points_and_commands() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
[[node.point]]
name = "P1"
type = "M_SP_NA_1"
ioa = 5
source = "M.A"
[[node.point]]
name = "P2"
type = "M_SP_NA_1"
ioa = 5
source = "M.B"
[[node.command]]
name = "C1"
type = "C_SC_NA_1"
ioa = 5
target = "M.C"
[[node.command]]
name = "C2"
type = "C_DC_NA_1"
ioa = 5
target = "M.D"
"#;
    let errors = errors(toml, &[]);
    expect(
        &errors,
        15,
        7,
        "node[0].point[1].ioa",
        "also used by point `P1`",
    );
    // A command on a point's address clashes too (one object per address at most
    // controlling stations).
    expect(
        &errors,
        20,
        7,
        "node[0].command[0].ioa",
        "also the address of point `P1`",
    );
    expect(
        &errors,
        25,
        7,
        "node[0].command[1].ioa",
        "also the address of point `P1`",
    );
    assert_eq!(errors.len(), 3, "{errors:#?}");
}

#[test]
fn ioa_out_of_range() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
[[node.point]]
name = "P1"
type = "M_SP_NA_1"
ioa = 16777216
source = "M.A"
"#;
    expect_only(
        toml,
        &[],
        10,
        7,
        "node[0].point[0].ioa",
        "outside 1..=16777215",
    );
}

#[test]
fn point_and_command_types() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
[[node.point]]
name = "P1"
type = "C_SC_NA_1"
ioa = 1
source = "M.A"
[[node.point]]
name = "P2"
type = "M_XX_NA_1"
ioa = 2
source = "M.A"
[[node.command]]
name = "C1"
type = "M_SP_NA_1"
ioa = 3
target = "M.C"
"#;
    let errors = errors(toml, &[]);
    expect(
        &errors,
        9,
        8,
        "node[0].point[0].type",
        "C_SC_NA_1 is not a type a point can be declared with",
    );
    expect(
        &errors,
        14,
        8,
        "node[0].point[1].type",
        "unknown type `M_XX_NA_1`",
    );
    expect(
        &errors,
        19,
        8,
        "node[0].command[0].type",
        "M_SP_NA_1 is not a command type",
    );
    assert_eq!(errors.len(), 3, "{errors:#?}");
}

#[test]
fn link_references_to_unknown_links() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
[[node.point]]
name = "P1"
type = "M_SP_NA_1"
ioa = 1
source = "link:B/7"
[[node.point]]
name = "P2"
type = "M_SP_NA_1"
ioa = 2
source = "link:B"
[[node.command]]
name = "C1"
type = "C_SC_NA_1"
ioa = 3
target = "link:B/8"
"#;
    let errors = errors(toml, &[]);
    expect(
        &errors,
        11,
        10,
        "node[0].point[0].source",
        "node `A` has no link `B`",
    );
    expect(
        &errors,
        16,
        10,
        "node[0].point[1].source",
        "not of the form link:LINK/IOA",
    );
    expect(
        &errors,
        21,
        10,
        "node[0].command[0].target",
        "node `A` has no link `B`",
    );
    assert_eq!(errors.len(), 3, "{errors:#?}");
}

const TWO_NODES: &str = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "Low"
common_address = 2
[node.server]
port_offset = 1
[[node.point]]
name = "P"
type = "M_SP_NA_1"
ioa = 10
source = "M.P"
[[node.command]]
name = "C"
type = "C_SC_NA_1"
ioa = 20
target = "M.C"
[[node]]
name = "Top"
common_address = 1
"#;

#[test]
fn link_to_unknown_node_or_itself() {
    let toml = format!(
        "{TWO_NODES}{}",
        r#"[[node.link]]
name = "L1"
node = "Nowhere"
[[node.link]]
name = "L2"
node = "Top"
"#
    );
    let errors = errors(&toml, &[]);
    expect(&errors, 24, 8, "node[1].link[0].node", "no node `Nowhere`");
    expect(
        &errors,
        27,
        8,
        "node[1].link[1].node",
        "cannot link to itself",
    );
    assert_eq!(errors.len(), 2, "{errors:#?}");
}

#[test]
fn link_needs_exactly_one_of_node_and_address() {
    let toml = format!(
        "{TWO_NODES}{}",
        r#"[[node.link]]
name = "Both"
node = "Low"
address = "192.0.2.1:2404"
[[node.link]]
name = "Neither"
"#
    );
    let errors = errors(&toml, &[]);
    expect(&errors, 25, 11, "node[1].link[0].address", "not both");
    let neither = errors
        .iter()
        .find(|e| e.key == "node[1].link[1]")
        .unwrap_or_else(|| panic!("{errors:#?}"));
    assert!(neither.message().contains("needs node or address"));
    assert_eq!(neither.line, 26, "{errors:#?}");
    assert_eq!(errors.len(), 2, "{errors:#?}");
}

#[test]
fn link_with_address_and_common_address_loads() {
    let toml = format!(
        "{TWO_NODES}{}",
        r#"[[node.link]]
name = "Far"
address = "192.0.2.1:2404"
common_address = 9
"#
    );
    let project = load(&toml, &[]).unwrap();
    let link = &project.node("Top").unwrap().links[0];
    assert_eq!(
        link.target,
        LinkTarget::Address("192.0.2.1:2404".parse().unwrap())
    );
    assert_eq!(link.common_address, CommonAddress::new(9));
}

#[test]
fn link_ioas_must_exist_on_the_lower_node() {
    let toml = format!(
        "{TWO_NODES}{}",
        r#"[[node.link]]
name = "L"
node = "Low"
[[node.point]]
name = "Ok"
type = "M_SP_TB_1"
ioa = 10
source = "link:L/10"
[[node.point]]
name = "Bad"
type = "M_SP_TB_1"
ioa = 11
source = "link:L/11"
[[node.command]]
name = "Cmd"
type = "C_SC_NA_1"
ioa = 20
target = "link:L/10"
"#
    );
    let errors = errors(&toml, &[]);
    expect(
        &errors,
        34,
        10,
        "node[1].point[1].source",
        "serves no point with IOA 11",
    );
    expect(
        &errors,
        39,
        10,
        "node[1].command[0].target",
        "accepts no command with IOA 10",
    );
    assert_eq!(errors.len(), 2, "{errors:#?}");
}

#[test]
fn cycles_in_the_link_graph() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
[node.server]
port_offset = 0
[[node.link]]
name = "toB"
node = "B"
[[node]]
name = "B"
common_address = 2
[node.server]
port_offset = 1
[[node.link]]
name = "toA"
node = "A"
"#;
    expect_only(
        toml,
        &[],
        19,
        8,
        "node[1].link[0].node",
        "cycle: A -> B -> A",
    );
}

#[test]
fn same_port_offset() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
[node.server]
port_offset = 4
[[node]]
name = "B"
common_address = 2
[node.server]
port_offset = 4
"#;
    expect_only(
        toml,
        &[],
        13,
        15,
        "node[1].server.port_offset",
        "also used by node `A`",
    );
}

#[test]
fn cyclic_without_cycle_ms() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
[[node.point]]
name = "P"
type = "M_ME_NC_1"
ioa = 1
source = "M.A"
transmission = "cyclic"
"#;
    expect_only(
        toml,
        &[],
        12,
        16,
        "node[0].point[0].transmission",
        "needs cycle_ms",
    );
}

#[test]
fn deadband_on_a_non_measurement() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
[[node.point]]
name = "P"
type = "M_SP_TB_1"
ioa = 1
source = "M.A"
deadband = 0.5
"#;
    expect_only(
        toml,
        &[],
        12,
        12,
        "node[0].point[0].deadband",
        "measurement type",
    );
}

#[test]
fn interrogation_group_out_of_range() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
[[node.point]]
name = "P"
type = "M_SP_TB_1"
ioa = 1
source = "M.A"
groups = [1, 17]
"#;
    expect_only(
        toml,
        &[],
        12,
        14,
        "node[0].point[0].groups[1]",
        "outside 1..=16",
    );
}

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

#[test]
fn status_point_must_name_a_point() {
    let toml = format!(
        "{TWO_NODES}{}",
        r#"[[node.link]]
name = "L"
node = "Low"
status_point = "COMM_L"
"#
    );
    expect_only(
        &toml,
        &[],
        25,
        16,
        "node[1].link[0].status_point",
        "has no point `COMM_L`",
    );
}

#[test]
fn point_without_source() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
[[node.point]]
name = "P"
type = "M_SP_TB_1"
ioa = 1
"#;
    let errors = errors(toml, &[]);
    assert_eq!(errors.len(), 1, "{errors:#?}");
    assert_eq!(errors[0].key, "node[0].point[0]");
    assert!(errors[0].message().contains("missing source"));
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

// ---------------------------------------------------------------------------------------
// robustness

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("station.toml"), &bytes).unwrap();
        if let Err(errors) = Project::load(dir.path()) {
            prop_assert!(!errors.errors().is_empty());
            let _ = errors.to_string();
        }
    }

    #[test]
    fn mangled_example_never_panics(
        drop_lines in proptest::collection::vec(0usize..600, 0..8),
        cut in 0usize..20_000,
    ) {
        let original = std::fs::read_to_string(testkit::projects::vsetin().join("station.toml")).unwrap();
        let kept: String = original
            .lines()
            .enumerate()
            .filter(|(i, _)| !drop_lines.contains(i))
            .map(|(_, l)| format!("{l}\n"))
            .collect();
        let mut end = cut.min(kept.len());
        while !kept.is_char_boundary(end) {
            end -= 1;
        }
        let dir = folder(&kept[..end], &[]);
        std::fs::create_dir_all(dir.path().join("plc")).unwrap();
        std::fs::copy(
            testkit::projects::vsetin().join("plc/rh2_logic.st"),
            dir.path().join("plc/rh2_logic.st"),
        )
        .unwrap();
        if let Err(errors) = Project::load(dir.path()) {
            for e in errors.errors() {
                prop_assert!(e.line >= 1 && e.column >= 1, "{e}");
            }
        }
    }
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

// ---------------------------------------------------------------------------------------
// republishing, pulses, initial values, invalid_when

#[test]
fn republish_maps_a_whole_lower_node_with_an_offset() {
    let toml = format!(
        "{TWO_NODES}{}",
        r#"[[node.link]]
name = "L"
node = "Low"
republish = { ioa_offset = 1000 }
"#
    );
    let project = load(&toml, &[]).unwrap();
    let top = project.node("Top").unwrap();
    let point = top.point("P").unwrap();
    assert_eq!(point.ioa.get(), 1010);
    assert_eq!(
        point.source,
        PointSource::Link {
            link: "L".into(),
            ioa: 10
        }
    );
    assert_eq!(top.commands.len(), 1);
    assert_eq!(top.commands[0].ioa.get(), 1020);
    assert_eq!(
        top.commands[0].target,
        CommandTarget::Link {
            link: "L".into(),
            ioa: Ioa::from(20u16)
        }
    );
    assert_eq!(top.link("L").unwrap().republish, Some(1000));
}

#[test]
fn republish_clashes_and_bad_offsets_name_the_link() {
    let toml = format!(
        "{TWO_NODES}{}",
        r#"[[node.point]]
name = "Own"
type = "M_SP_NA_1"
ioa = 10
[[node.link]]
name = "L"
node = "Low"
status_point = "Own"
republish = { ioa_offset = 0 }
"#
    );
    expect_only(
        &toml,
        &[],
        30,
        13,
        "node[1].link[0].republish",
        "lands on IOA 10, already used",
    );
    let toml = format!(
        "{TWO_NODES}{}",
        r#"[[node.link]]
name = "L"
node = "Low"
republish = { ioa_offset = -5 }
"#
    );
    expect_only(
        &toml,
        &[],
        25,
        13,
        "node[1].link[0].republish",
        "outside 0..=16777215",
    );
}

#[test]
fn pulse_initial_values_and_invalid_when_are_read() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
sources = ["plc/main.st"]
[node.set]
"Main.A" = "TRUE"
[[node.point]]
name = "P"
type = "M_SP_NA_1"
ioa = 1
source = "Main.A"
invalid_when = "Main.A"
[[node.command]]
name = "C"
type = "C_SC_NA_1"
ioa = 2
target = "Main.A"
pulse_ms = 250
[[node.command]]
name = "D"
type = "C_SC_NA_1"
ioa = 3
target = "Main.A"
pulse_ms = 0
"#;
    let errors = errors(toml, &[PLC]);
    expect(
        &errors,
        27,
        12,
        "node[0].command[1].pulse_ms",
        "outside 1..=3600000",
    );
    assert_eq!(errors.len(), 1, "{errors:#?}");
    let fixed = toml.replace("pulse_ms = 0", "pulse_ms = 1");
    let project = load(&fixed, &[PLC]).unwrap();
    let node = project.node("A").unwrap();
    assert_eq!(
        node.initial_values,
        [("Main.A".to_owned(), "TRUE".to_owned())]
    );
    assert_eq!(
        node.point("P").unwrap().invalid_when.as_deref(),
        Some("Main.A")
    );
    assert_eq!(
        node.commands[0].pulse,
        Some(std::time::Duration::from_millis(250))
    );
}

#[test]
fn command_groups_must_be_redundancy_groups_of_the_node() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
sources = ["plc/main.st"]
[node.server]
port_offset = 0
redundancy_groups = [{ name = "hmi", clients = ["127.0.0.2"] }, { name = "dispatch", refuse_commands_when = "Main.A" }]
[[node.command]]
name = "C"
type = "C_SC_NA_1"
ioa = 2
target = "Main.A"
from_groups = ["hmi", "scada"]
"#;
    expect_only(
        toml,
        &[PLC],
        16,
        23,
        "node[0].command[0].from_groups[1]",
        "no redundancy group `scada`",
    );
    let project = load(&toml.replace(", \"scada\"", ""), &[PLC]).unwrap();
    let node = project.node("A").unwrap();
    assert_eq!(node.commands[0].from_groups, ["hmi"]);
    let groups = &node.server.as_ref().unwrap().redundancy_groups;
    assert_eq!(groups[1].refuse_commands_when.as_deref(), Some("Main.A"));
}

// ---------------------------------------------------------------------------------------
// robustness: nothing panics, every problem is an error with a position

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(300))]

    #[test]
    fn arbitrary_text_never_panics(text in "\\PC{0,400}") {
        let folder = Path::new("/nonexistent");
        let _ = Project::parse(folder, &folder.join("station.toml"), &text);
    }

    #[test]
    fn mutated_example_never_panics_and_errors_have_positions(
        cuts in proptest::collection::vec((0usize..6000, 0usize..40, "\\PC{0,12}"), 1..4)
    ) {
        let original = std::fs::read_to_string(testkit::projects::vsetin().join("station.toml")).unwrap();
        let mut text: Vec<char> = original.chars().take(6000).collect();
        for (at, len, insert) in cuts {
            let at = at.min(text.len());
            let end = (at + len).min(text.len());
            text.splice(at..end, insert.chars());
        }
        let text: String = text.into_iter().collect();
        let folder = testkit::projects::vsetin();
        if let Err(errors) = Project::parse(&folder, &folder.join("station.toml"), &text) {
            let lines = text.lines().count().max(1);
            for error in errors.errors() {
                proptest::prop_assert!(error.line <= lines + 1, "{error}");
            }
        }
    }
}

#[test]
fn a_command_may_not_share_an_ioa_with_a_point() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "A"
common_address = 1
sources = ["plc/main.st"]
[[node.point]]
name = "P"
type = "M_SP_NA_1"
ioa = 7
source = "Main.A"
[[node.command]]
name = "C"
type = "C_SC_NA_1"
ioa = 7
target = "Main.A"
"#;
    expect_only(
        toml,
        &[PLC],
        16,
        7,
        "node[0].command[0].ioa",
        "also the address of point `P`",
    );
}

// ---------------------------------------------------------------------------------------
// how many errors, PLC variables, encodings (issue 11)

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

#[test]
fn a_range_belongs_to_a_set_point_and_is_not_empty() {
    let project = |kind: &str, range: &str| {
        format!(
            r#"[station]
name = "Test"
time_zone = "Europe/Prague"

[[node]]
name = "A"
common_address = 1
sources = ["plc/main.st"]
[node.server]
port_offset = 3
[[node.task]]
name = "fast"
interval_ms = 50
programs = ["main"]
[[node.command]]
name = "C"
type = "{kind}"
ioa = 2
target = "Main.A"
range = {range}
"#
        )
    };
    expect_only(
        &project("C_SC_NA_1", "[0, 1]"),
        &[PLC],
        20,
        9,
        "node[0].command[0].range",
        "range applies to set-points, not C_SC_NA_1",
    );
    expect_only(
        &project("C_SE_NB_1", "[10, -10]"),
        &[PLC],
        20,
        9,
        "node[0].command[0].range",
        "range [10, -10] is empty",
    );
    let loaded = load(&project("C_SE_TB_1", "[0, 1439]"), &[PLC]).unwrap();
    assert_eq!(
        loaded.node("A").unwrap().commands[0].range,
        Some(0.0..=1439.0)
    );
}

#[test]
fn a_link_uses_tls_exactly_when_the_lower_server_requires_it() {
    let project = |server_tls: &str, link_tls: &str| {
        format!(
            r#"[station]
name = "Test"
time_zone = "Europe/Prague"

[[node]]
name = "TOP"
common_address = 1
[[node.link]]
name = "LOW"
node = "LOW"
{link_tls}
[[node]]
name = "LOW"
common_address = 2
[node.server]
port_offset = 1
{server_tls}
"#
        )
    };
    let tls = r#"tls = { certificate = "a.pem", private_key = "a.key", trust_anchors = "ca.pem" }"#;
    let files = [("a.pem", "x"), ("a.key", "x"), ("ca.pem", "x")];
    expect_only(
        &project(tls, ""),
        &files,
        10,
        8,
        "node[0].link[0].node",
        "node `LOW`'s server requires TLS: give the link tls",
    );
    expect_only(
        &project("", tls),
        &files,
        11,
        7,
        "node[0].link[0].tls",
        "node `LOW`'s server has no tls",
    );
    let loaded = load(&project(tls, tls), &files).unwrap();
    let link = &loaded.node("TOP").unwrap().links[0];
    assert!(link.tls.as_ref().unwrap().trust_anchors.ends_with("ca.pem"));
}

/// The COM600 example: a node with a simulated IEC 103 line, its device, line points and
/// commands.
#[test]
fn com600_gateway_example_loads() {
    let project = Project::load(&testkit::projects::vsetin().join("../com600-gateway")).unwrap();
    let node = &project.nodes[0];
    let line = &node.lines[0];
    assert_eq!(line.name, "relays");
    assert_eq!(line.devices[0].address, 1);
    assert_eq!(line.devices[0].local_indication, Some((1, 190)));
    let breaker = node.points.iter().find(|p| p.ioa.get() == 2000).unwrap();
    assert_eq!(
        breaker.source,
        PointSource::Line {
            line: "relays".into(),
            device: "REF630".into(),
            signal: LineSignal::Iec103 {
                fun: 1,
                inf: 160,
                index: None
            }
        }
    );
    let current = node.points.iter().find(|p| p.ioa.get() == 3100).unwrap();
    assert_eq!(current.scaling.map(|s| s.limit), Some(240.0));
    let status = node.points.iter().find(|p| p.ioa.get() == 9000).unwrap();
    assert_eq!(
        status.source,
        PointSource::DeviceStatus {
            line: "relays".into(),
            device: "REF630".into()
        }
    );
    let line_status = node.points.iter().find(|p| p.ioa.get() == 9001).unwrap();
    assert_eq!(
        line_status.source,
        PointSource::LineStatus {
            line: "relays".into()
        }
    );
    assert_eq!(line.status_point.as_deref(), Some("COMM_LINE"));
    let command = node.commands.iter().find(|c| c.ioa.get() == 2100).unwrap();
    assert_eq!(
        command.target,
        CommandTarget::Line {
            line: "relays".into(),
            device: "REF630".into(),
            fun: 1,
            inf: 160,
            value: None
        }
    );
    let remote_open = node.commands.iter().find(|c| c.ioa.get() == 4250).unwrap();
    assert!(matches!(
        remote_open.target,
        CommandTarget::Line {
            value: Some(false),
            ..
        }
    ));
}

/// The IEC 101 gateway example: its line, device and the forwarded command.
#[test]
fn iec101_gateway_example_loads() {
    let project = Project::load(&testkit::projects::vsetin().join("../iec101-gateway")).unwrap();
    let node = &project.nodes[0];
    let line = &node.lines[0];
    assert!(matches!(line.protocol, LineProtocol::Iec101(_)));
    assert_eq!(
        (line.devices[0].address, line.devices[0].common_address),
        (3, 7)
    );
    let command = node.commands.iter().find(|c| c.ioa.get() == 200).unwrap();
    assert_eq!(
        command.target,
        CommandTarget::LineObject {
            line: "rtus".into(),
            device: "RTU".into(),
            ioa: Ioa::try_new(4001).unwrap()
        }
    );
}

#[test]
fn line_errors_name_their_place() {
    let toml = r#"[station]
name = "s"
time_zone = "UTC"
[[node]]
name = "G"
common_address = 1

[[node.line]]
name = "relays"
protocol = "iec102"
port = "/dev/ttyS0"
tcp = "10.0.0.1:4001"
baud = 300

[[node.line.device]]
name = "F1"
address = 0
status_point = "NOPE"

[[node.point]]
name = "A"
type = "M_ME_NC_1"
ioa = 1
source = "line:relays/F2/1/148/0"

[[node.point]]
name = "B"
type = "M_DP_NA_1"
ioa = 2
source = "line:relays/F1/1/300"

[[node.point]]
name = "C"
type = "M_SP_NA_1"
ioa = 3
source = "line:relays/F1/1/160"
measurand_limit = 10.0

[[node.command]]
name = "K"
type = "C_SE_NC_1"
ioa = 10
target = "line:other/F1/1/160"
"#;
    let errors = errors(toml, &[]);
    expect(
        &errors,
        10,
        12,
        "node[0].line[0].protocol",
        "\"iec103\" (protection relays) or \"iec101\" (outstations)",
    );
    expect(
        &errors,
        8,
        1,
        "node[0].line[0]",
        "exactly one of port, tcp and simulate",
    );
    expect(&errors, 13, 8, "node[0].line[0].baud", "baud rate 300");
    expect(
        &errors,
        17,
        11,
        "node[0].line[0].device[0].address",
        "outside 1..=254",
    );
    expect(
        &errors,
        24,
        10,
        "node[0].point[0].source",
        "line `relays` has no device `F2`",
    );
    expect(&errors, 30, 10, "node[0].point[1].source", "INF `300`");
    expect(
        &errors,
        37,
        19,
        "node[0].point[2].measurand_limit",
        "only for measurands",
    );
    expect(
        &errors,
        41,
        8,
        "node[0].command[0].type",
        "C_SC_NA_1 or C_DC_NA_1",
    );
    expect(
        &errors,
        43,
        10,
        "node[0].command[0].target",
        "no line `other`",
    );
}

/// An IEC 101 line: field sizes, a device's own common address, `line:LINE/DEVICE/IOA`
/// sources of any monitor type and commands forwarded as they come.
#[test]
fn iec101_lines_load_with_their_field_sizes_and_objects() {
    let toml = r#"[station]
name = "s"
time_zone = "UTC"
[[node]]
name = "G"
common_address = 1
[[node.line]]
name = "rtus"
protocol = "iec101"
tcp = "127.0.0.1:2401"
link_address_size = 2
cot_size = 2
common_address_size = 2
ioa_size = 3
[[node.line.device]]
name = "RTU1"
address = 3
common_address = 700
[[node.point]]
name = "Feeder"
type = "M_DP_TB_1"
ioa = 100
source = "line:rtus/RTU1/4001"
[[node.point]]
name = "Power"
type = "M_ME_NC_1"
ioa = 101
source = "line:rtus/RTU1/5000"
[[node.command]]
name = "Open"
type = "C_DC_NA_1"
ioa = 200
target = "line:rtus/RTU1/4101"
"#;
    let project = load(toml, &[]).unwrap();
    let node = &project.nodes[0];
    let line = &node.lines[0];
    let LineProtocol::Iec101(settings) = line.protocol else {
        panic!("an IEC 101 line: {:?}", line.protocol);
    };
    assert_eq!(settings.address_size, iec60870::ft12::AddressSize::Two);
    assert_eq!(
        (
            settings.params.cot_size(),
            settings.params.common_address_size(),
            settings.params.ioa_size()
        ),
        (2, 2, 3)
    );
    assert_eq!(line.devices[0].common_address, 700);
    assert_eq!(
        node.points[1].source,
        PointSource::Line {
            line: "rtus".into(),
            device: "RTU1".into(),
            signal: LineSignal::Iec101 { ioa: 5000 }
        }
    );
    assert_eq!(
        node.commands[0].target,
        CommandTarget::LineObject {
            line: "rtus".into(),
            device: "RTU1".into(),
            ioa: Ioa::try_new(4101).unwrap()
        }
    );
    // The default sizes: link address 1, COT 1, CA 1, IOA 2; CA = link address.
    let defaults = toml
        .replace(
            "link_address_size = 2\ncot_size = 2\ncommon_address_size = 2\nioa_size = 3\n",
            "",
        )
        .replace("common_address = 700\n", "");
    let project = load(&defaults, &[]).unwrap();
    let line = &project.nodes[0].lines[0];
    let LineProtocol::Iec101(settings) = line.protocol else {
        panic!("an IEC 101 line");
    };
    assert_eq!(settings.address_size, iec60870::ft12::AddressSize::One);
    assert_eq!(
        (
            settings.params.cot_size(),
            settings.params.common_address_size(),
            settings.params.ioa_size()
        ),
        (1, 1, 2)
    );
    assert_eq!(line.devices[0].common_address, 3);
}

/// References in the other protocol's form, keys of the other protocol, sizes out of range.
#[test]
fn iec101_and_iec103_keys_and_references_are_not_mixed() {
    let toml = r#"[station]
name = "s"
time_zone = "UTC"
[[node]]
name = "G"
common_address = 1
[[node.line]]
name = "rtus"
protocol = "iec101"
simulate = "ref630"
ioa_size = 4
[[node.line.device]]
name = "RTU1"
address = 3
[[node.line]]
name = "relays"
protocol = "iec103"
port = "/dev/ttyS0"
cot_size = 2
[[node.line.device]]
name = "F1"
address = 1
common_address = 9
[[node.point]]
name = "A"
type = "M_SP_NA_1"
ioa = 1
source = "line:rtus/RTU1/1/160"
[[node.point]]
name = "B"
type = "M_SP_NA_1"
ioa = 2
source = "line:relays/F1/4001"
[[node.command]]
name = "K"
type = "C_SC_NA_1"
ioa = 10
target = "line:rtus/RTU1/4101=ON"
"#;
    let errors = errors(toml, &[]);
    let problem_at = |key: &str| {
        errors
            .iter()
            .find(|e| e.key == key)
            .map(|e| e.problem.clone())
            .unwrap_or_else(|| panic!("no error at {key} in {errors:#?}"))
    };
    assert_eq!(
        problem_at("node[0].line[0].simulate"),
        ConfigProblem::Conflict(Conflict::NotForProtocol {
            key: "simulate",
            protocol: "iec101"
        })
    );
    assert!(matches!(
        problem_at("node[0].line[0].ioa_size"),
        ConfigProblem::OutOfRange { value: 4, .. }
    ));
    assert_eq!(
        problem_at("node[0].line[1].cot_size"),
        ConfigProblem::Conflict(Conflict::NotForProtocol {
            key: "cot_size",
            protocol: "iec103"
        })
    );
    assert_eq!(
        problem_at("node[0].line[1].device[0].common_address"),
        ConfigProblem::Conflict(Conflict::NotForProtocol {
            key: "common_address",
            protocol: "iec103"
        })
    );
    assert!(matches!(
        problem_at("node[0].point[0].source"),
        ConfigProblem::Conflict(Conflict::LineRefProtocol {
            protocol: "iec101",
            ..
        })
    ));
    assert!(matches!(
        problem_at("node[0].point[1].source"),
        ConfigProblem::Conflict(Conflict::LineRefProtocol {
            protocol: "iec103",
            ..
        })
    ));
    assert!(matches!(
        problem_at("node[0].command[0].target"),
        ConfigProblem::Conflict(Conflict::NotForProtocol {
            key: "=ON/=OFF",
            ..
        })
    ));
    assert!(errors[0].to_string().contains("station.toml:"));
}

#[test]
fn a_device_status_point_must_exist() {
    let toml = r#"[station]
name = "s"
time_zone = "UTC"
[[node]]
name = "G"
common_address = 1
[[node.line]]
name = "relays"
protocol = "iec103"
simulate = "ref630"
[[node.line.device]]
name = "F1"
address = 1
status_point = "NOPE"
"#;
    expect_only(
        toml,
        &[],
        14,
        16,
        "node[0].line[0].device[0].status_point",
        "no point `NOPE`",
    );
}

// ---------------------------------------------------------------------------------------
// typed problems: a program matches on what is wrong, not on the message's words

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

const LIFT_PROJECT: &str = r#"[station]
name = "lifts"
time_zone = "UTC"

[[node]]
name = "MON"
common_address = 1

[[node.point]]
name = "L1.status"
type = "M_SP_NA_1"
ioa = 120
source = "Main.x"

[[node.lift]]
name = "L1"
floors = 4
ioa_base = 100
simulate = "ekm6"

[[node.lift]]
name = "L1"
floors = 70
ioa_base = 110
port = "/dev/ttyS0"
tcp = "10.0.0.1:4001"
status_layout = "wide"
counter_width = 3
fault_stack = 8
"#;

#[test]
fn lift_errors_name_their_place() {
    let errors = errors(LIFT_PROJECT, &[]);
    // The first lift: an unknown simulated board; its points clash with nothing.
    expect(
        &errors,
        19,
        12,
        "node[0].lift[0].simulate",
        "no simulated lift board `ekm6`",
    );
    // The second: its name, floors, transport, coding and a simulation-only key, and its
    // generated points overlapping the first lift's (110 + 6 = 106 is L1.not_answering)
    // and a written point's name.
    expect(
        &errors,
        22,
        8,
        "node[0].lift[1].name",
        "duplicate lift name `L1`",
    );
    expect(
        &errors,
        22,
        8,
        "node[0].lift[1].name",
        "duplicate point name `L1.status`",
    );
    expect(
        &errors,
        23,
        10,
        "node[0].lift[1].floors",
        "floors 70 is outside 2..=60",
    );
    expect(
        &errors,
        21,
        1,
        "node[0].lift[1]",
        "give exactly one of port, tcp and simulate",
    );
    expect(
        &errors,
        27,
        17,
        "node[0].lift[1].status_layout",
        "status layout `wide`",
    );
    expect(
        &errors,
        28,
        17,
        "node[0].lift[1].counter_width",
        "1, 2 or 4 octets",
    );
    expect(
        &errors,
        24,
        12,
        "node[0].lift[1].ioa_base",
        "IOA 110 is also used by point `L1.errors`",
    );
    // A generated point named like a written one.
    expect(
        &errors,
        16,
        8,
        "node[0].lift[0].name",
        "duplicate point name `L1.status`",
    );
}

#[test]
fn a_lift_brings_its_points() {
    let project = load(
        r#"[station]
name = "lifts"
time_zone = "UTC"

[[node]]
name = "MON"
common_address = 1

[[node.lift]]
name = "L2"
description = "goods lift"
floors = 3
ioa_base = 500
tcp = "127.0.0.1:4001"
counter_width = 2
time_coding = "bcd"
direction = [0, 2, 1]
"#,
        &[],
    )
    .unwrap();
    let node = &project.nodes[0];
    let names: Vec<(&str, u32, TypeId)> = node
        .points
        .iter()
        .map(|p| {
            (
                p.name.as_str(),
                p.ioa.get(),
                points_iec::type_id(p.point_type),
            )
        })
        .collect();
    assert_eq!(names.len(), 13 + 3);
    assert_eq!(names[0], ("L2.status", 500, TypeId::M_ME_TE_1));
    assert!(names.contains(&("L2.not_answering", 506, TypeId::M_SP_TB_1)));
    assert!(names.contains(&("L2.floor3_trips", 518, TypeId::M_IT_TB_1)));
    let lift = &node.lifts[0];
    assert_eq!(lift.floors, 3);
    assert_eq!(
        lift.transport,
        station::config::LiftTransport::Tcp("127.0.0.1:4001".into())
    );
    assert_eq!(lift.poller.codec.direction.up, 2);
    assert_eq!(lift.poller.codec.direction.down, 1);
}
