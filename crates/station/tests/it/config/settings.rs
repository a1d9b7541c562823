//! The station and its nodes: a minimal project's defaults, a station without nodes, time
//! zone, retention, common addresses and node names.

use std::net::SocketAddr;
use std::time::Duration;

use iec60870::asdu::{CommonAddress, Ioa, TypeId};
use station::config::{CommandTarget, PointSource, Project, Transmission};

use super::support::*;

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
        Transmission::Cyclic(Duration::from_millis(1000))
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
