//! Serial lines and their devices (IEC 103 and IEC 101): field sizes, line references,
//! one protocol's keys on the other's line, device status points, errors at their place.

use iec60870::asdu::Ioa;
use station::config::problem::Conflict;
use station::config::{CommandTarget, ConfigProblem, LineProtocol, LineSignal, PointSource};

use super::support::*;

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
