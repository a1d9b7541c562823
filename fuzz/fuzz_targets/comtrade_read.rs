//! Arbitrary bytes as a COMTRADE `.cfg` + `.dat` pair (split at the first NUL, or all
//! `.cfg`) into the reader. Nothing may panic; a record that reads must write again to
//! files that read to the same record.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let (cfg, dat) = match data.iter().position(|byte| *byte == 0) {
        Some(split) => (&data[..split], &data[split + 1..]),
        None => (data, &[][..]),
    };
    let Ok(cfg) = std::str::from_utf8(cfg) else {
        return;
    };
    if let Ok(record) = comtrade::Record::read(cfg, dat) {
        if let (Ok(cfg), Ok(dat)) = (record.write_cfg(), record.write_dat()) {
            let again = comtrade::Record::read(&cfg, &dat).expect("a written record reads");
            assert_eq!(again.write_cfg().ok(), Some(cfg));
        }
    }
});
