//! The lab models' console: faults on sensors and actuators, buttons, reset, the listing
//! of operations, status lines and the error messages.

use plant::lab::ErrLed;
use plant::PlantError;

use super::{at, get, model, ms, num, s, set};

#[test]
fn stuck_and_wire_open_sensors() {
    let mut m = model("slide", &[]);
    assert!(get(&m, "K1"));
    m.console("stuck K1 off").unwrap();
    assert!(!get(&m, "K1"));
    m.console("stuck k2 ON").unwrap();
    assert!(get(&m, "K2"));
    m.console("clear K1").unwrap();
    assert!(get(&m, "K1"));
    m.console("wire-open K1").unwrap();
    assert!(!get(&m, "K1"));
    // A fault replaces the one before on the same signal.
    m.console("stuck K1 on").unwrap();
    assert!(get(&m, "K1"));
    m.console("clear all").unwrap();
    assert!(get(&m, "K1"));
    assert!(!get(&m, "K2"));
    // ERR can be faulted too: the program reads it.
    m.console("stuck ERR on").unwrap();
    assert!(get(&m, "ERR"));
    assert_eq!(m.err_led(), ErrLed::Off);
}

#[test]
fn a_broken_actuator_does_nothing_whatever_is_commanded() {
    let mut m = model("slide", &[]);
    m.console("broken EM1").unwrap();
    set(&mut m, "EM1", true);
    assert!(get(&m, "EM1"), "the PLC's output reads back as written");
    at(&mut m, s(3));
    assert_eq!(num(&m, "position"), 1.0);
    // Repaired: acts from that instant, first step a period later.
    m.console("clear EM1").unwrap();
    at(&mut m, ms(3499));
    assert_eq!(num(&m, "position"), 1.0);
    at(&mut m, ms(3500));
    assert_eq!(num(&m, "position"), 2.0);
    // A broken valve ends neither the mixing unit's blinking nor fills anything.
    let mut m = model("mixing", &[]);
    m.console("broken SV1").unwrap();
    set(&mut m, "SV1", true);
    at(&mut m, s(5));
    assert_eq!(num(&m, "tank1"), 0.0);
    assert_eq!(m.err_led(), ErrLed::Blinking);
}

#[test]
fn buttons_press_and_release() {
    let mut m = model("washing", &[]);
    assert!(!get(&m, "START"));
    m.console("press START").unwrap();
    assert!(get(&m, "START"));
    // The model ignores it.
    at(&mut m, s(2));
    assert_eq!(num(&m, "level"), 0.0);
    m.console("release start").unwrap();
    assert!(!get(&m, "START"));
    let mut c = model("crossroad", &[]);
    c.console("press tlacitko_chodci").unwrap();
    assert!(get(&c, "tlacitko_chodci"));
    c.console("stuck tlacitko_chodci off").unwrap();
    assert!(!get(&c, "tlacitko_chodci"));
}

#[test]
fn reset_by_console() {
    let mut m = model("washing", &[]);
    set(&mut m, "napousteni", true);
    at(&mut m, s(21));
    assert_eq!(m.err_led(), ErrLed::Steady);
    set(&mut m, "napousteni", false);
    m.console("stuck voda_50 on").unwrap();
    m.console("reset").unwrap();
    assert_eq!(m.err_led(), ErrLed::Off);
    assert_eq!(num(&m, "level"), 0.0);
    assert!(m.errors().is_empty());
    // Console faults survive RESET.
    assert!(get(&m, "voda_50"));
}

#[test]
fn unknown_names_and_lines_list_what_is_allowed() {
    let mut m = model("slide", &[]);
    let e = m.console("stuck K9 on").unwrap_err();
    assert_eq!(
        e.to_string(),
        "no sensor `K9`; the sensor names are K1, K2, K3, K4, START, ERR"
    );
    assert!(matches!(
        &e,
        PlantError::UnknownName { kind: "sensor", name, allowed } if name == "K9" && allowed.len() == 6
    ));
    let e = m.console("broken K1").unwrap_err();
    assert_eq!(
        e.to_string(),
        "no actuator `K1`; the actuator names are EM1, EM2, EM3"
    );
    let e = m.console("press EM1").unwrap_err();
    assert_eq!(e.to_string(), "no button `EM1`; the button names are START");
    let e = m.console("clear K1").unwrap_err();
    assert_eq!(
        e.to_string(),
        "no faulted signal `K1`; there is no faulted signal"
    );
    m.console("stuck K2 on").unwrap();
    let e = m.console("clear K1").unwrap_err();
    assert_eq!(
        e.to_string(),
        "no faulted signal `K1`; the faulted signal names are K2"
    );
    let e = model("crossroad", &[]).console("press chodci").unwrap_err();
    assert_eq!(
        e.to_string(),
        "no button `chodci`; the button names are tlacitko_chodci, START"
    );
    let e = m.console("stuck K1 maybe").unwrap_err();
    assert!(matches!(e, PlantError::BadConsoleLine { .. }), "{e}");
    let e = m.console("frobnicate").unwrap_err();
    assert_eq!(
        e.to_string(),
        "cannot read `frobnicate`; the operations are stuck SENSOR on|off, wire-open SENSOR, \
         broken ACTUATOR, clear NAME, clear all, reset, press BUTTON, release BUTTON"
    );
    for bad in [
        "",
        "   ",
        "reset now",
        "clear",
        "press",
        "stuck K1",
        "wire-open K1 K2",
    ] {
        assert!(
            matches!(m.console(bad), Err(PlantError::BadConsoleLine { .. })),
            "{bad:?}"
        );
    }
}

#[test]
fn console_operations_name_the_sensors_and_actuators() {
    let mut m = model("mixing", &[]);
    m.console("stuck H1 on").unwrap();
    let ops = m.console_operations();
    let usages: Vec<&str> = ops.iter().map(|o| o.usage).collect();
    assert_eq!(
        usages,
        [
            "stuck SENSOR on|off",
            "wire-open SENSOR",
            "broken ACTUATOR",
            "clear NAME",
            "clear all",
            "reset",
            "press BUTTON",
            "release BUTTON"
        ]
    );
    assert_eq!(
        ops[0].names,
        ["H1", "H2", "H3", "H4", "H5", "H6", "H7", "H8", "START", "ERR"]
    );
    assert_eq!(ops[0].names_kind.as_deref(), Some("sensor"));
    assert!(ops[0].fault);
    assert_eq!(ops[2].names, ["SV1", "SV2", "SV3", "SV4", "SV5", "MIX"]);
    assert_eq!(ops[3].names, ["H1"]);
    assert_eq!(ops[6].names, ["START"]);
    assert!(!ops[5].fault);
}

#[test]
fn status_describes_the_model() {
    let mut m = model("mixing", &[]);
    set(&mut m, "SV2", true);
    at(&mut m, s(3));
    m.console("wire-open H5").unwrap();
    m.console("press START").unwrap();
    let status = m.status();
    let line = |label: &str| {
        status
            .iter()
            .find(|l| l.label == label)
            .unwrap_or_else(|| panic!("no {label} in {status:?}"))
            .items
            .clone()
    };
    assert_eq!(
        line("mixing"),
        ["tanks 0 / 18 / 0 L", "vessel 0 L", "open SV2", "mixer off"]
    );
    assert_eq!(line("ERR"), ["off"]);
    assert_eq!(line("errors"), ["none"]);
    assert_eq!(line("faults"), ["wire-open H5"]);
    assert_eq!(line("buttons"), ["START pressed"]);

    let mut w = model("slide", &[]);
    set(&mut w, "EM1", true);
    set(&mut w, "EM2", true);
    at(&mut w, s(1));
    let status = w.status();
    assert_eq!(status[0].label, "slide");
    assert_eq!(status[0].items, ["position 1 (K1)", "stopped"]);
    assert_eq!(status[1].items, ["blinking"]);
    assert_eq!(
        status[2].items,
        ["0.000 s both-directions: EM1 and EM2 together at position 1"]
    );
}
