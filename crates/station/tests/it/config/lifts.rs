//! Lifts: their errors at their place, and the points a lift brings.

use iec60870::asdu::TypeId;

use super::support::*;

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
