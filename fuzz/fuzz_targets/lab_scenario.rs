//! Arbitrary text as a teaching-lab scenario: parsed (TOML, durations, properties), its
//! conditions resolved against a model's names and evaluated, its console lines played on
//! the model at their times. Nothing may panic; errors are values.
#![no_main]

use std::time::Duration;

use lab::Scenario;
use libfuzzer_sys::fuzz_target;
use plant::lab::LabOptions;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(scenario) = Scenario::parse("fuzz.toml", text) else {
        return;
    };
    let model_name = scenario
        .model
        .as_deref()
        .filter(|m| plant::lab::MODELS.contains(m))
        .unwrap_or("slide");
    let Ok(options) = LabOptions::parse(&scenario.options) else {
        return;
    };
    let Ok(mut model) = plant::lab::open(model_name, &options) else {
        return;
    };
    let mut names: Vec<String> = model.signals().iter().map(|s| s.name.clone()).collect();
    names.extend(model.state().into_iter().map(|(n, _)| n.to_owned()));
    let resolve = |name: &str| names.iter().position(|n| n.eq_ignore_ascii_case(name));
    let known = || names.clone();
    let values: Vec<f64> = (0..names.len()).map(|i| i as f64 - 3.0).collect();
    for property in &scenario.properties {
        if let Ok(property) = property.resolve(&resolve, &known) {
            let _ = property.condition.holds(&values);
        }
    }
    for event in &scenario.events {
        let at = event.at.min(Duration::from_secs(3600));
        if at >= model.now() {
            let _ = model.advance_to(at);
        }
        let _ = model.console(&event.line);
    }
});
