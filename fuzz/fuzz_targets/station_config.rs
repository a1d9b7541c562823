//! Arbitrary bytes as a project file (`station.toml`): loading must never panic, whatever
//! the syntax, types or cross-references; every problem is a `ConfigError`.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let folder = Path::new("/nonexistent-stanice-fuzz");
    let _ = station::config::Project::parse(folder, &folder.join("station.toml"), &text);
});
