//! Node servers: the command age limit, port offsets, the redundancy groups commands come
//! from, and TLS of a link to a lower server.

use std::time::Duration;

use super::support::*;

/// A project of one node `A` whose server has these further lines.
fn one_server(lines: &str) -> String {
    format!(
        "[station]\nname = \"T\"\ntime_zone = \"UTC\"\n[[node]]\nname = \"A\"\n\
         common_address = 1\n[node.server]\nport_offset = 0\n{lines}\n"
    )
}

/// The server of node `A` of `one_server(lines)`.
fn server_of(lines: &str) -> station::config::ServerConfig {
    load(&one_server(lines), &[])
        .unwrap()
        .node("A")
        .unwrap()
        .server
        .clone()
        .unwrap()
}

/// `max_command_age_ms`: milliseconds, or "off" for no limit; another word is refused
/// at its position.
#[test]
fn the_maximum_command_delay_is_set_or_turned_off() {
    let project = |age: &str| one_server(&format!("max_command_age_ms = {age}"));
    let age = |text: &str| server_of(&format!("max_command_age_ms = {text}")).max_command_age;
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

/// `event_buffer`: the events kept per redundancy group, 100,000 unless given; zero,
/// negative and absurd sizes are refused at their position.
#[test]
fn the_event_buffer_is_sized_per_server() {
    let buffer = |lines: &str| server_of(lines).event_buffer;
    assert_eq!(buffer(""), station::config::DEFAULT_EVENT_BUFFER);
    assert_eq!(buffer("event_buffer = 5000"), 5000);
    for (text, column) in [("0", 16), ("-3", 16), ("20000000", 16)] {
        expect_only(
            &one_server(&format!("event_buffer = {text}")),
            &[],
            9,
            column,
            "node[0].server.event_buffer",
            "event_buffer",
        );
    }
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
