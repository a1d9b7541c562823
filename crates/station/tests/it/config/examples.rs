//! The example projects load with what they declare: Vsetín (nodes, points, commands,
//! transitive republishing, port base), the COM600 and the IEC 101 gateways.

use iec60870::asdu::{Ioa, TypeId};
use station::config::{CommandTarget, LineProtocol, LineSignal, LinkTarget, PointSource, Project};

#[test]
fn vsetin_example_loads() {
    let project = match Project::load(&testkit::projects::vsetin()) {
        Ok(p) => p,
        Err(e) => panic!("{e}"),
    };
    assert_eq!(project.station.name, "Vsetín");
    let names: Vec<&str> = project.nodes.iter().map(|n| n.name.as_str()).collect();
    assert_eq!(
        &names[..10],
        ["RDRT", "RH1.1", "RH2", "RH1.2", "RZS1", "RZZ", "RZS2", "RDA", "RH-DT", "RZS-DT"]
    );
    assert_eq!(names.len(), 10 + 13);
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
        CommandTarget::Variable("LogoBoard.Cmd_VypnoutQF1".into())
    );
    assert_eq!(rh2.tasks[0].programs, ["LogoBoard"]);

    // RH1.1 republishes RH2 whole (same IOAs) and RH1.2 shifted by 40, beside its own
    // I/O (201-216) and its link status points 280 and 320.
    let rh11 = project.node("RH1.1").unwrap();
    assert_eq!(rh11.points.len(), 14 + 2 * (1 + 22));
    assert_eq!(
        rh11.point("COMM_RH2").unwrap().source,
        PointSource::LinkStatus("RH2".into())
    );
    assert_eq!(rh11.link("RH2").unwrap().republish, Some(0));
    assert_eq!(rh11.link("RH1.2").unwrap().republish, Some(40));
    assert_eq!(
        rh11.point("RH2_V1_FA1_Zapnut").unwrap().source,
        PointSource::Link {
            link: "RH2".into(),
            ioa: 281
        }
    );
    assert_eq!(rh11.point("RH12_V1_FA1_Zapnut").unwrap().ioa.get(), 321);
    assert_eq!(
        rh11.point("RS602_Zapnut").unwrap().source,
        PointSource::Variable("RH11Concentrator.RS602_Zapnut".into())
    );
    let close_qf1 = rh11
        .commands
        .iter()
        .find(|c| c.name == "RH2_ZapnoutQF1")
        .unwrap();
    assert_eq!(
        close_qf1.target,
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
    // The whole station: RH1.2 and RZS2 through their concentrators, the DT boards on
    // links of their own, the by-pass and the signalling supply.
    for (name, ioa) in [
        ("RH12_V1_FA1_Zapnut", 321),
        ("COMM_RH12", 320),
        ("RZS2_V1_FA1_Zapnut", 441),
        ("COMM_RZS2", 440),
        ("RS602_Zapnut", 208),
        ("UZ_K2_Zapnut", 347),
        ("RHDT_QF1_Zapnut", 501),
        ("RZSDT_U", 611),
        ("COMM_RH_DT", 34),
        ("COMM_RZS_DT", 35),
    ] {
        assert_eq!(rdrt.point(name).unwrap().ioa.get(), ioa, "{name}");
    }
    let forwarded: Vec<u32> = rdrt
        .commands
        .iter()
        .filter(|c| c.name.starts_with("RH12_") || c.name.starts_with("RZS2_"))
        .map(|c| c.ioa.get())
        .collect();
    assert_eq!(forwarded, [2061, 2062, 2181, 2182]);
    assert_eq!(rdrt.points.len(), 416 + 14 + 13 + 2 * 23 + 2 * 8 + 2 + 1); // + 1: the dispatch link (IOA 42)
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
