//! Address tables of the three profiles against the spec's printed tables (sections 3.4,
//! 4.2, 5.3, 6.3) and the wiring pattern of section 2 (`LAB-A8`).

use plant::lab::{bindings, Binding, LabError, LabOptions, Profile, MODELS};

fn options(pairs: &[(&str, &str)]) -> LabOptions {
    let pairs: Vec<(String, String)> = pairs
        .iter()
        .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
        .collect();
    LabOptions::parse(&pairs).unwrap()
}

fn table(model: &str, profile: Profile) -> Vec<(String, String)> {
    bindings(model, profile, &LabOptions::default())
        .unwrap()
        .into_iter()
        .map(|Binding { signal, address }| (signal, address))
        .collect()
}

fn address(model: &str, profile: Profile, signal: &str) -> String {
    table(model, profile)
        .into_iter()
        .find(|(s, _)| s == signal)
        .unwrap_or_else(|| panic!("{model} has no {signal}"))
        .1
}

fn pairs(rows: &[(&str, &str)]) -> Vec<(String, String)> {
    rows.iter()
        .map(|(s, a)| ((*s).to_owned(), (*a).to_owned()))
        .collect()
}

#[test]
fn slide_tables() {
    assert_eq!(
        table("slide", Profile::Model),
        pairs(&[
            ("EM1", "QX0.0"),
            ("EM2", "QX0.1"),
            ("EM3", "QX0.2"),
            ("K1", "IX0.0"),
            ("K2", "IX0.1"),
            ("K3", "IX0.2"),
            ("K4", "IX0.3"),
            ("START", "IX1.0"),
        ])
    );
    assert_eq!(
        table("slide", Profile::Lab),
        pairs(&[
            ("EM1", "QX2.0"),
            ("EM2", "QX2.1"),
            ("EM3", "QX2.2"),
            ("K1", "IX10.2"),
            ("K2", "IX10.3"),
            ("K3", "IX10.4"),
            ("K4", "IX10.5"),
            ("START", "IX11.0"),
        ])
    );
    // As printed: EM1-EM3 keep Y0.0-Y0.2 in the lab column.
    assert_eq!(address("slide", Profile::LabPrinted, "EM1"), "QX0.0");
    assert_eq!(address("slide", Profile::LabPrinted, "EM3"), "QX0.2");
    assert_eq!(address("slide", Profile::LabPrinted, "K4"), "IX10.5");
}

#[test]
fn crossroad_tables() {
    for (signal, model, lab) in [
        ("cerv_spodek", "QX0.0", "QX2.0"),
        ("oran_spodek", "QX0.1", "QX2.1"),
        ("zel_spodek", "QX0.2", "QX2.2"),
        ("cerv_vrch", "QX0.3", "QX2.3"),
        ("oran_vrch", "QX0.4", "QX24.0"),
        ("zel_vrch", "QX0.5", "QX24.1"),
        ("cerv_chodci", "QX0.6", "QX24.2"),
        ("zel_chodci", "QX0.7", "QX24.3"),
        ("tlacitko_chodci", "IX0.0", "IX10.2"),
    ] {
        assert_eq!(address("crossroad", Profile::Model, signal), model);
        assert_eq!(address("crossroad", Profile::Lab, signal), lab);
        assert_eq!(address("crossroad", Profile::LabPrinted, signal), lab);
    }
    assert_eq!(table("crossroad", Profile::Model).len(), 10);
}

#[test]
fn mixing_tables() {
    for (signal, model, lab, printed) in [
        ("SV1", "QX0.0", "QX2.0", "QX2.0"),
        ("SV3", "QX0.2", "QX2.2", "QX2.2"),
        ("SV4", "QX0.5", "QX24.1", "QX24.0"),
        ("SV5", "QX0.4", "QX24.0", "QX24.1"),
        ("MIX", "QX0.6", "QX24.2", "QX24.2"),
        ("H1", "IX0.3", "IX10.5", "IX10.5"),
        ("H3", "IX0.1", "IX10.3", "IX10.3"),
        ("H4", "IX0.0", "IX10.2", "IX10.2"),
        ("H5", "IX0.7", "IX84.3", "IX84.3"),
        ("H6", "IX0.4", "IX84.0", "IX84.0"),
        ("H8", "IX0.6", "IX84.2", "IX84.2"),
    ] {
        assert_eq!(address("mixing", Profile::Model, signal), model, "{signal}");
        assert_eq!(address("mixing", Profile::Lab, signal), lab, "{signal}");
        assert_eq!(
            address("mixing", Profile::LabPrinted, signal),
            printed,
            "{signal}"
        );
    }
    let signals: Vec<String> = table("mixing", Profile::Model)
        .into_iter()
        .map(|(s, _)| s)
        .collect();
    assert_eq!(
        signals,
        [
            "SV1", "SV2", "SV3", "SV4", "SV5", "MIX", "H1", "H2", "H3", "H4", "H5", "H6", "H7",
            "H8", "START"
        ]
    );
}

#[test]
fn washing_tables() {
    for (signal, model, lab, printed) in [
        ("buben_vpravo", "QX0.0", "QX2.0", "QX2.0"),
        ("otacky", "QX0.2", "QX2.2", "QX2.2"),
        ("topeni", "QX0.4", "QX24.0", "QX24.0"),
        ("napousteni", "QX0.5", "QX24.1", "QX24.1"),
        ("cerpadlo", "QX0.6", "QX24.2", "QX24.2"),
        ("teplota_90", "IX0.0", "IX10.2", "IX10.2"),
        ("teplota_30", "IX0.3", "IX10.5", "IX10.5"),
        ("voda_50", "IX0.6", "IX84.2", "IX84.2"),
        ("voda_100", "IX0.7", "IX84.3", "IX83.3"),
    ] {
        assert_eq!(
            address("washing", Profile::Model, signal),
            model,
            "{signal}"
        );
        assert_eq!(address("washing", Profile::Lab, signal), lab, "{signal}");
        assert_eq!(
            address("washing", Profile::LabPrinted, signal),
            printed,
            "{signal}"
        );
    }
}

#[test]
fn start_err_and_reset() {
    for model in MODELS {
        let plain = table(model, Profile::Model);
        assert_eq!(
            plain.last().unwrap(),
            &("START".to_owned(), "IX1.0".to_owned())
        );
        assert!(plain.iter().all(|(s, _)| s != "ERR" && s != "RESET"));
        let with = options(&[("program-err", "true")]);
        for (profile, start, err, reset) in [
            (Profile::Model, "IX1.0", "IX1.1", "QX1.0"),
            (Profile::Lab, "IX11.0", "IX11.1", "QX11.0"),
            (Profile::LabPrinted, "IX11.0", "IX11.1", "QX11.0"),
        ] {
            let t = bindings(model, profile, &with).unwrap();
            let tail: Vec<(&str, &str)> = t
                .iter()
                .rev()
                .take(3)
                .rev()
                .map(|b| (b.signal.as_str(), b.address.as_str()))
                .collect();
            assert_eq!(tail, [("START", start), ("ERR", err), ("RESET", reset)]);
        }
    }
}

#[test]
fn every_address_is_unique_within_a_profile() {
    let all = options(&[("program-err", "true")]);
    for model in MODELS {
        for profile in Profile::ALL {
            let t = bindings(model, profile, &all).unwrap();
            let mut addresses: Vec<&str> = t.iter().map(|b| b.address.as_str()).collect();
            addresses.sort_unstable();
            addresses.dedup();
            assert_eq!(addresses.len(), t.len(), "{model} {profile}");
        }
    }
}

#[test]
fn unknown_models_and_misplaced_options() {
    let e = bindings("lift", Profile::Model, &LabOptions::default()).unwrap_err();
    assert_eq!(e, LabError::UnknownModel("lift".to_owned()));
    assert_eq!(
        e.to_string(),
        "unknown lab model `lift`; the models are slide, crossroad, mixing, washing"
    );
    let e = bindings("mixing", Profile::Lab, &options(&[("sensors", "2,4,7,9")])).unwrap_err();
    assert!(
        matches!(&e, LabError::Option { key, .. } if key == "sensors"),
        "{e}"
    );
    assert!(bindings("slide", Profile::Lab, &options(&[("sensors", "2,4,7,9")])).is_ok());
}
