//! The I/O surface and the fault API: names, types, errors, parsing.

use std::collections::BTreeSet;

use plant::{
    Action, DeviceKind, Direction, Fault, Plant, PlantError, Value, ValueKind, VsetinPlant,
};

use crate::{get, set};

#[test]
fn signal_names_are_unique_and_cover_the_rh2_tag_list() {
    let p = VsetinPlant::new();
    let names: BTreeSet<&str> = p.signals().iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names.len(), p.signals().len());
    // Spec §6.1 (truncated names completed).
    let mut rh2 = vec![
        "RH2_V1_FA1_Zapnut",
        "RH2_V1_FA1.1",
        "RH2_V1_FA1.2",
        "RH2_V1_FA1.3",
        "RH2_V1_FA1.4",
        "RH2_V1_FA1.5",
        "RH2_P1_FA110.0",
        "RH2_P1_FA110.1",
        "RH2_P1_FA110.2",
        "RH2_P1_KHU1_Napeti_na_privodu",
        "RH2_P1_KHU3_Napeti_na_pripojeni",
        "RH2_P1_SA1_Mistne",
        "RH2_P1_SA1_Dalkove",
        "RH2_P1_FU1_Pretavena_pojistka",
        "RH2_P1_FV1_Prepetova_ochrana",
        "RH2_P1_KHVRH2_Havarijni_vypnuti",
        "RH2_P1_FV110_Prepetova_ochrana",
        "RH2_P1_G110.2_Napeti_zdroje",
    ];
    let spare: Vec<String> = (1..=14).map(|i| format!("RH2_RezervaVstup{i}")).collect();
    rh2.extend(spare.iter().map(String::as_str));
    for n in &rh2 {
        let info = p
            .signals()
            .iter()
            .find(|s| s.name == *n)
            .unwrap_or_else(|| panic!("{n}"));
        assert_eq!(info.direction, Direction::Input);
        assert_eq!(info.kind, ValueKind::Bool);
        assert_eq!(info.module, "RH2_LOGO");
        assert!(!info.description.is_empty());
    }
    for n in rh2 {
        let rzz = n.replacen("RH2", "RZZ", 2);
        assert!(names.contains(rzz.as_str()), "{rzz}");
    }
    let outputs: Vec<&str> = p
        .signals()
        .iter()
        .filter(|s| s.direction == Direction::Output)
        .map(|s| s.name.as_str())
        .collect();
    assert_eq!(outputs.len(), 2 * 4 + 3 + 13);
    assert_eq!(p.outputs().len(), outputs.len());
    assert_eq!(p.inputs().len() + outputs.len(), p.signals().len());
    println!("{} signals ({} outputs)", p.signals().len(), outputs.len());
}

#[test]
fn api_errors() {
    let mut p = VsetinPlant::new();
    assert_eq!(
        p.read("NOPE"),
        Err(PlantError::UnknownSignal("NOPE".into()))
    );
    assert_eq!(
        p.set_output("RH2_QF1_Zapnut", Value::Bool(true)),
        Err(PlantError::NotAnOutput("RH2_QF1_Zapnut".into()))
    );
    assert!(matches!(
        p.set_output("RH2_QF1_Zap", Value::Real(1.0)),
        Err(PlantError::WrongType {
            expected: ValueKind::Bool,
            got: ValueKind::Real,
            ..
        })
    ));
    assert!(matches!(p.bool("RH2_U"), Err(PlantError::WrongType { .. })));
    assert!(matches!(
        p.real("RH2_QF1_Zapnut"),
        Err(PlantError::WrongType { .. })
    ));
    assert!(matches!(
        p.inject(Fault::SupplyLoss("T3".into())),
        Err(PlantError::UnknownDevice { kind: "supply", .. })
    ));
    assert!(p.inject(Fault::StuckOpen("XX".into())).is_err());
    assert!(
        p.inject(Fault::FuseBlown("RH2_FV1".into())).is_err(),
        "an arrester is not a fuse"
    );
    assert!(p.inject(Fault::EmergencyOff("RZS1".into())).is_err());
    assert!(p.active_faults().is_empty());
    p.advance(std::time::Duration::from_secs(5)).unwrap();
    assert!(matches!(
        p.advance_to(std::time::Duration::from_secs(1)),
        Err(PlantError::TimeWentBackwards { .. })
    ));
}

#[test]
fn fault_text_round_trip() {
    let all = [
        Fault::SupplyLoss("T1".into()),
        Fault::GeneratorFailToStart,
        Fault::StuckClosed("RDA_KM1".into()),
        Fault::StuckOpen("ROV01_KM1".into()),
        Fault::BreakerTripped("RH2_FA1.3".into()),
        Fault::LampFailure("OR".into()),
        Fault::FuseBlown("RZS1_FU1".into()),
        Fault::SurgeArresterTripped("RDRT_FV24".into()),
        Fault::EmergencyOff("RZZ".into()),
        Fault::DoorOpen("RDRT_T2".into()),
        Fault::SupplyUnitFault("RH2_G110.2".into()),
        Fault::NetworkSwitchFault("RDRT_ABB".into()),
        Fault::ModulePulled("RDRT_P9".into()),
        Fault::CommunicationLost("RH2_LOGO".into()),
    ];
    assert_eq!(all.len(), Fault::keywords().len());
    let mut p = VsetinPlant::new();
    for f in &all {
        let text = f.to_string();
        assert_eq!(&text.parse::<Fault>().unwrap(), f, "{text}");
        p.inject(f.clone()).unwrap_or_else(|e| panic!("{f}: {e}"));
    }
    assert_eq!(p.active_faults().len(), all.len());
    p.clear_all();
    assert!(p.active_faults().is_empty());
    for bad in [
        "",
        "stuck-open",
        "supply-loss a b",
        "explode T1",
        "generator-fail-to-start X",
    ] {
        assert!(
            matches!(bad.parse::<Fault>(), Err(PlantError::BadFault(_))),
            "{bad}"
        );
    }
}

#[test]
fn indication_contacts() {
    let mut p = VsetinPlant::new();
    assert!(get(&p, "RH2_P1_G110.2_Napeti_zdroje"));
    assert!(get(&p, "RDRT_G230_OK"));
    assert!(get(&p, "RDRT_Switch_ABB_OK"));
    assert!(!get(&p, "RDRT_Switch_Korenix_Porucha"));
    p.inject(Fault::SupplyUnitFault("RH2_G110.2".into()))
        .unwrap();
    p.inject(Fault::SupplyUnitFault("RDRT_G230".into()))
        .unwrap();
    p.inject(Fault::NetworkSwitchFault("RDRT_ABB".into()))
        .unwrap();
    p.inject(Fault::NetworkSwitchFault("RDRT_KORENIX".into()))
        .unwrap();
    p.inject(Fault::SurgeArresterTripped("RH2_FV110".into()))
        .unwrap();
    p.inject(Fault::DoorOpen("RDRT_VN".into())).unwrap();
    p.inject(Fault::DoorOpen("ROV11".into())).unwrap();
    assert!(!get(&p, "RH2_P1_G110.2_Napeti_zdroje"));
    assert!(!get(&p, "RDRT_G230_OK"));
    assert!(!get(&p, "RDRT_Switch_ABB_OK"));
    assert!(get(&p, "RDRT_Switch_Korenix_Porucha"));
    assert!(get(&p, "RH2_P1_FV110_Prepetova_ochrana"));
    assert!(get(&p, "RDRT_Dvere_VN"));
    assert!(!get(&p, "RDRT_Dvere_NN"));
    assert!(get(&p, "ROV11_Dvere"));
    // Module p9 pulled: points 1..10 of the TC700 become invalid; p6 (doors) stays.
    p.inject(Fault::ModulePulled("RDRT_P9".into())).unwrap();
    assert!(!p.read("RDRT_FV230").unwrap().valid);
    assert!(p.read("RDRT_Dvere_VN").unwrap().valid);
    set(&mut p, "RH2_QF1_Vyp", false);
}

#[test]
#[ignore = "prints the signal list: cargo test -p plant print_signals -- --ignored --nocapture"]
fn print_signals() {
    print!(
        "{}",
        plant::signal_table_markdown(VsetinPlant::new().signals())
    );
}

/// Expands the patterns of the crate docs' signal table.
fn expand(pat: &str) -> Vec<String> {
    if let Some(start) = pat.find('{') {
        let end = start + pat[start..].find('}').unwrap();
        let (head, key, tail) = (&pat[..start], &pat[start + 1..end], &pat[end + 1..]);
        let subs: Vec<String> = match key {
            "B" => ["RH2", "RZZ", "RH12", "RZS2"].map(String::from).to_vec(),
            "D" => ["RHDT", "RZSDT"].map(String::from).to_vec(),
            "L" => plant::lighting_boards(),
            range => {
                let (a, b) = range.split_once("..").unwrap();
                (a.parse::<u32>().unwrap()..=b.parse().unwrap())
                    .map(|i| i.to_string())
                    .collect()
            }
        };
        subs.iter()
            .flat_map(|s| expand(&format!("{head}{s}{tail}")))
            .collect()
    } else {
        vec![pat.to_string()]
    }
}

#[test]
fn crate_docs_list_every_signal() {
    let lib = include_str!("../../src/lib.rs");
    let table = &lib[lib.find("# Signal table").unwrap()..lib.find("# Faults").unwrap()];
    let mut documented = BTreeSet::new();
    for row in table.lines().filter(|l| l.starts_with("//! | `")) {
        let first = row.trim_start_matches("//! |").split(" | ").next().unwrap();
        for pat in first.split(", ") {
            let pat = pat.trim().trim_matches('`');
            for name in expand(pat) {
                assert!(documented.insert(name.clone()), "{name} documented twice");
            }
        }
    }
    let p = VsetinPlant::new();
    let actual: BTreeSet<String> = p.signals().iter().map(|s| s.name.clone()).collect();
    let missing: Vec<_> = actual.difference(&documented).collect();
    let extra: Vec<_> = documented.difference(&actual).collect();
    assert!(
        missing.is_empty() && extra.is_empty(),
        "undocumented {missing:?}, not existing {extra:?}"
    );
    let inputs = p
        .signals()
        .iter()
        .filter(|s| s.direction == Direction::Input)
        .count();
    let count = format!(
        "That is {inputs} inputs and {} outputs.",
        actual.len() - inputs
    );
    assert!(table.contains(&count), "{count}");
    let md = plant::signal_table_markdown(p.signals());
    assert_eq!(md.lines().count(), actual.len() + 2);
}

/// Every operation that names a device has devices to name, and each of its names
/// resolves to itself.
#[test]
fn every_operation_lists_the_names_it_takes() {
    let p = VsetinPlant::new();
    for syntax in plant::operation_syntax() {
        let Some(kind) = syntax.device else { continue };
        let names = p.device_names(kind);
        assert!(!names.is_empty(), "{} takes no name", syntax.keyword);
        for name in &names {
            assert_eq!(p.resolve_device(kind, name).as_ref(), Ok(name));
        }
    }
    assert!(p
        .device_names(DeviceKind::Breaker)
        .contains(&"RH2_QF1".to_owned()));
    assert!(p
        .device_names(DeviceKind::SwitchingDevice)
        .contains(&"RDA_KM2".to_owned()));
}

/// A newcomer types `close QF1` or `module-pulled p9`: a unique short name (first or last
/// words of the full name, any case) is accepted; an ambiguous one lists the candidates.
#[test]
fn short_device_names_resolve_when_unique() {
    let mut p = VsetinPlant::new();
    assert_eq!(
        p.operate(Action::Close("QF1".into())),
        Err(PlantError::AmbiguousDevice {
            kind: "breaker",
            name: "QF1".into(),
            candidates: [
                "RH11_QF1",
                "RH12_QF1",
                "RH2_QF1",
                "RHDT_QF1",
                "RZS2_QF1",
                "RZSDT_QF1",
                "RZZ_QF1",
            ]
            .map(String::from)
            .to_vec(),
        })
    );
    let message = p
        .operate(Action::Close("QF1".into()))
        .unwrap_err()
        .to_string();
    assert!(message.contains("RH2_QF1, RHDT_QF1"), "{message}");

    p.inject(Fault::ModulePulled("p9".into())).unwrap();
    p.inject(Fault::BreakerTripped("RH11".into())).unwrap();
    p.inject(Fault::EmergencyOff("rzz".into())).unwrap();
    assert_eq!(
        p.active_faults(),
        vec![
            Fault::BreakerTripped("RH11_QF1".into()),
            Fault::EmergencyOff("RZZ".into()),
            Fault::ModulePulled("RDRT_P9".into()),
        ]
    );
    p.clear(&Fault::ModulePulled("RDRT_p9".into())).unwrap();
    p.clear(&Fault::BreakerTripped("rh11_qf1".into())).unwrap();
    assert_eq!(p.active_faults(), vec![Fault::EmergencyOff("RZZ".into())]);

    // RH2's QF1 by its door pushbutton, in local, by the unique `RH2_QF1`.
    p.operate(Action::SetSelector {
        board: "rh2".into(),
        remote: false,
    })
    .unwrap();
    p.operate(Action::Open("rh2_qf1".into())).unwrap();
    p.advance(std::time::Duration::from_secs(1)).unwrap();
    let qf1 = p
        .switching_devices()
        .into_iter()
        .find(|d| d.name == "RH2_QF1")
        .unwrap();
    assert!(!qf1.closed, "{qf1}");
    assert_eq!(qf1.to_string(), "RH2_QF1 open");

    assert!(matches!(
        p.inject(Fault::StuckOpen("KM9".into())),
        Err(PlantError::UnknownDevice { .. })
    ));
    assert!(matches!(
        p.inject(Fault::StuckOpen("KM2".into())),
        Err(PlantError::AmbiguousDevice { ref candidates, .. })
            if candidates.contains(&"RDA_KM2".to_owned()) && candidates.contains(&"OR_KM2".to_owned())
    ));
}

/// The transfer as the console's `status` shows it.
#[test]
fn transfer_state_reads_the_rda_contactors_and_the_generator() {
    let p = VsetinPlant::new();
    let transfer = p.transfer();
    assert!(!transfer.mains_closed && !transfer.generator_closed);
    assert_eq!(
        transfer.to_string(),
        "RZS on neither source (RDA_KM1 open, RDA_KM2 open), busbar dead, generator stopped"
    );
}
