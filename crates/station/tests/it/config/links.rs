//! Links between nodes and republishing: link targets, the lower node's IOAs, cycles, link
//! status points, and a lower node republished whole with an IOA offset.

use iec60870::asdu::{CommonAddress, Ioa};
use station::config::{CommandTarget, LinkTarget, PointSource};

use super::support::*;

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
