//! Points and commands: IOAs, types, transmission, deadbands, interrogation groups, sources,
//! pulses, initial values, `invalid_when` and set-point ranges.

use super::support::*;

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

/// What the history keeps: a point's own deadband and rate limit over the station's
/// defaults, which reach every numeric point without its own (written or brought by a
/// lift); a binary point keeps every change.
#[test]
fn storage_rules_of_points_over_the_station_defaults() {
    use points::{Deadband, StorageRule};
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
store_deadband_percent = 0.5
store_min_interval_ms = 1000
[[node]]
name = "A"
common_address = 1
[[node.point]]
name = "U"
type = "M_ME_NC_1"
ioa = 1
source = "M.U"
store_deadband = 0.2
[[node.point]]
name = "C"
type = "M_IT_NA_1"
ioa = 2
source = "M.C"
store_min_interval_ms = 60000
[[node.point]]
name = "I"
type = "M_ME_NB_1"
ioa = 3
source = "M.I"
[[node.point]]
name = "Q"
type = "M_SP_NA_1"
ioa = 4
source = "M.Q"
"#;
    let project = load(toml, &[]).unwrap();
    let rule = |name: &str| {
        project.nodes[0]
            .points
            .iter()
            .find(|p| p.name == name)
            .unwrap()
            .storage
    };
    let second = std::time::Duration::from_secs(1);
    assert_eq!(
        rule("U"),
        StorageRule::default()
            .with_deadband(Deadband::Absolute(0.2))
            .with_min_interval(second)
    );
    assert_eq!(
        rule("C"),
        StorageRule::default()
            .with_deadband(Deadband::Percent(0.5))
            .with_min_interval(std::time::Duration::from_secs(60))
    );
    assert_eq!(
        rule("I"),
        StorageRule::default()
            .with_deadband(Deadband::Percent(0.5))
            .with_min_interval(second)
    );
    assert_eq!(project.station.storage, rule("I"));
}

#[test]
fn storage_rules_that_cannot_be() {
    let toml = r#"[station]
name = "X"
time_zone = "UTC"
store_min_interval_ms = 0
[[node]]
name = "A"
common_address = 1
[[node.point]]
name = "Q"
type = "M_SP_TB_1"
ioa = 1
source = "M.A"
store_min_interval_ms = 1000
[[node.point]]
name = "U"
type = "M_ME_NC_1"
ioa = 2
source = "M.U"
store_deadband = 0.2
store_deadband_percent = 1
[[node.point]]
name = "I"
type = "M_ME_NB_1"
ioa = 3
source = "M.I"
store_deadband_percent = -1
"#;
    let errors = errors(toml, &[]);
    expect(
        &errors,
        4,
        25,
        "station.store_min_interval_ms",
        "store_min_interval_ms 0 is outside 1..=86400000",
    );
    expect(
        &errors,
        13,
        25,
        "node[0].point[0].store_min_interval_ms",
        "thins out numbers",
    );
    expect(
        &errors,
        20,
        26,
        "node[0].point[1].store_deadband_percent",
        "either store_deadband (absolute) or store_deadband_percent",
    );
    expect(
        &errors,
        26,
        26,
        "node[0].point[2].store_deadband_percent",
        "store_deadband_percent must be a finite value >= 0",
    );
    assert_eq!(errors.len(), 4, "{errors:#?}");
}
