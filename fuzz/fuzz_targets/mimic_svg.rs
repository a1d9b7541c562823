//! Arbitrary bytes as a mimic screen file: the cleaner answers markup or an error, never
//! panics; markup it writes is clean already (cleaning it again changes nothing) and no
//! tag in it is a script or foreign object or carries an event handler or a
//! `javascript:` URL.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(out) = mimic_svg::clean(text) else {
        return;
    };
    assert_eq!(mimic_svg::clean(&out).as_ref(), Ok(&out));
    for tag in mimic_svg::tags(&out) {
        assert!(!mimic_svg::tag_is_unsafe(tag), "{tag}");
    }
});
