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
    assert_eq!(fault_text_czech(0x3C), "Porucha dveri");
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
