//! The code tables of spec Appendix A and B.

use devices::ekm66::tables::*;

#[test]
fn fifty_three_status_codes_and_seventy_five_fault_codes() {
    assert_eq!(STATUS_CODES.len(), 53);
    assert_eq!(FAULT_CODES.len(), 75);
    // Codes are unique and in order.
    assert!(STATUS_CODES.windows(2).all(|w| w[0].code < w[1].code));
    assert!(FAULT_CODES.windows(2).all(|w| w[0].code < w[1].code));
    assert!(status_code(16).is_none() && status_code(28).is_none());
    assert_eq!(STATUS_CODES.last().unwrap().code, 55);
    assert_eq!(FAULT_CODES.last().unwrap().code, 0x5E);
}

#[test]
fn texts_and_classes() {
    assert_eq!(status_text(1), "Fully ready for operation");
    assert_eq!(status_text_czech(1), "Plně připraven k provozu.");
    assert_eq!(status_text(4), "Fully ready for operation (duplicate of 1)");
    assert_eq!(status_text(16), "unknown status (16)");
    assert_eq!(fault_text(0x3C), "Door fault");
    assert_eq!(fault_text_czech(0x3C), "Porucha dveří");
    assert_eq!(fault_text(0x06), "unknown fault 0x06");
    let mut colours = StatusColours::default();
    assert_eq!(colours.class(1), ColourClass::Green);
    assert_eq!(colours.class(18), ColourClass::Red);
    assert_eq!(colours.class(29), ColourClass::Orange);
    assert_eq!(colours.class(16), ColourClass::Orange);
    colours.set(29, ColourClass::Red);
    assert_eq!(colours.class(29), ColourClass::Red);
    assert_eq!(colours.class(30), ColourClass::Orange);
}

#[test]
fn every_status_code_has_a_mode_and_unknown_codes_are_unknown() {
    for entry in STATUS_CODES {
        assert_ne!(
            lift_mode(entry.code),
            LiftMode::Unknown,
            "status {}",
            entry.code
        );
        // A red status is out of service, except the fire operation.
        if entry.class == ColourClass::Red && !matches!(entry.code, 23 | 24) {
            assert_eq!(
                lift_mode(entry.code),
                LiftMode::OutOfService,
                "status {}",
                entry.code
            );
        }
    }
    for code in [0, 16, 28, 56, 255] {
        assert_eq!(lift_mode(code), LiftMode::Unknown);
    }
    assert_eq!(lift_mode(1), LiftMode::NormalService);
    assert_eq!(lift_mode(4), LiftMode::NormalService);
    assert_eq!(lift_mode(44), LiftMode::OutOfService);
    assert_eq!(lift_mode(20), LiftMode::OutOfService);
    assert_eq!(lift_mode(46), LiftMode::Inspection);
    assert_eq!(lift_mode(39), LiftMode::Inspection);
    assert_eq!(lift_mode(23), LiftMode::Other);
    assert_eq!(lift_mode(9), LiftMode::Other);
    // Every mode but Unknown has a status.
    for mode in LiftMode::ALL
        .into_iter()
        .filter(|m| *m != LiftMode::Unknown)
    {
        assert!(
            STATUS_CODES.iter().any(|e| lift_mode(e.code) == mode),
            "{mode}"
        );
    }
}

#[test]
fn door_states_from_the_status() {
    assert_eq!(door_state(19), Some(DoorState::Fault));
    assert_eq!(door_state(18), Some(DoorState::Fault));
    assert_eq!(door_state(31), Some(DoorState::Open));
    assert_eq!(door_state(29), Some(DoorState::Open));
    assert_eq!(door_state(30), Some(DoorState::PartlyOpen));
    assert_eq!(door_state(14), Some(DoorState::Closed));
    // "Ready" says nothing about the doors, nor an unknown code.
    assert_eq!(door_state(1), None);
    assert_eq!(door_state(16), None);
    // All four states of spec §9 occur.
    for state in [
        DoorState::Open,
        DoorState::Closed,
        DoorState::PartlyOpen,
        DoorState::Fault,
    ] {
        assert!(
            STATUS_CODES
                .iter()
                .any(|e| door_state(e.code) == Some(state)),
            "{state}"
        );
    }
    assert_eq!(DoorState::PartlyOpen.to_string(), "partly open");
}

#[test]
fn every_fault_code_has_a_group_and_every_group_a_code() {
    for entry in FAULT_CODES {
        assert!(FaultGroup::ALL.contains(&fault_group(entry.code)));
    }
    // Each group of the minimum fault log has at least one code of Appendix B (the
    // alarm button only through the AWM alarm stop 0x51).
    for group in FaultGroup::ALL {
        assert!(
            FAULT_CODES.iter().any(|e| fault_group(e.code) == group),
            "{group}"
        );
    }
    assert_eq!(fault_group(0x11), FaultGroup::SafetyCircuitInTravel);
    assert_eq!(fault_group(0x3C), FaultGroup::DoorSequence);
    assert_eq!(fault_group(0x3F), FaultGroup::DoorSequence);
    assert_eq!(fault_group(0x16), FaultGroup::StopOutsideDoorZone);
    assert_eq!(fault_group(0x10), FaultGroup::CannotStart);
    assert_eq!(fault_group(0x54), FaultGroup::MainPowerOff);
    assert_eq!(fault_group(0x46), FaultGroup::InspectionMode);
    assert_eq!(fault_group(0x51), FaultGroup::AlarmButton);
    assert_eq!(fault_group(0x01), FaultGroup::Other);
    assert_eq!(fault_group(0x06), FaultGroup::Other);
    let counts: Vec<usize> = FaultGroup::ALL
        .iter()
        .map(|g| {
            FAULT_CODES
                .iter()
                .filter(|e| fault_group(e.code) == *g)
                .count()
        })
        .collect();
    assert_eq!(counts.iter().sum::<usize>(), 75);
}

#[test]
fn fault_group_keys_and_labels() {
    let keys: Vec<&str> = FaultGroup::ALL.iter().map(|g| g.key()).collect();
    assert_eq!(
        keys,
        [
            "safety-circuit",
            "door-sequence",
            "outside-door-zone",
            "cannot-start",
            "main-power",
            "inspection",
            "alarm-button",
            "other"
        ]
    );
    for group in FaultGroup::ALL {
        assert_eq!(FaultGroup::from_key(group.key()), Some(group));
        assert_eq!(group.to_string(), group.key());
        assert!(!group.english().is_empty() && !group.czech().is_empty());
    }
    assert_eq!(FaultGroup::from_key("nope"), None);
    let modes: Vec<&str> = LiftMode::ALL.iter().map(|m| m.key()).collect();
    assert_eq!(
        modes,
        [
            "normal-service",
            "out-of-service",
            "inspection",
            "other",
            "unknown"
        ]
    );
}
