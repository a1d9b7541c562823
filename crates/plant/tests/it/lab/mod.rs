//! The teaching-lab models: bindings, each model's checklist of the spec's section 8,
//! step-size independence and random operation sequences.

mod bindings;
mod console;
mod crossroad;
mod mixing;
mod prop;
mod slide;
mod timing;
mod washing;

use std::time::Duration;

use plant::lab::{open, ErrLed, ErrorKind, LabModel, LabOptions};
use plant::Value;

/// A model boxed as [`open`] gives it.
type Model = Box<dyn LabModel + Send>;

/// Milliseconds.
fn ms(x: u64) -> Duration {
    Duration::from_millis(x)
}

/// Seconds.
fn s(x: u64) -> Duration {
    Duration::from_secs(x)
}

/// Opens a model with `key=value` options.
fn model(name: &str, options: &[(&str, &str)]) -> Model {
    let pairs: Vec<(String, String)> = options
        .iter()
        .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
        .collect();
    open(name, &LabOptions::parse(&pairs).unwrap()).unwrap()
}

/// Drives an output.
fn set(m: &mut Model, name: &str, v: bool) {
    m.set_output(name, Value::Bool(v)).unwrap();
}

/// Reads a digital signal.
fn get(m: &Model, name: &str) -> bool {
    m.bool(name).unwrap()
}

/// Advances to an absolute time.
fn at(m: &mut Model, t: Duration) {
    m.advance_to(t).unwrap();
}

/// A value of [`LabModel::state`].
fn state(m: &Model, key: &str) -> Value {
    m.state()
        .into_iter()
        .find(|(k, _)| *k == key)
        .unwrap_or_else(|| panic!("no state `{key}`"))
        .1
}

/// A REAL value of [`LabModel::state`].
fn num(m: &Model, key: &str) -> f64 {
    state(m, key).as_real().unwrap()
}

/// A BOOL value of [`LabModel::state`].
fn flag(m: &Model, key: &str) -> bool {
    state(m, key).as_bool().unwrap()
}

/// The kinds of the errors recorded, with their recoverability and whether cleared.
fn kinds(m: &Model) -> Vec<(ErrorKind, bool, bool)> {
    m.errors()
        .iter()
        .map(|e| (e.kind, e.recoverable, e.cleared.is_some()))
        .collect()
}

/// No error recorded and ERR dark.
fn assert_no_error(m: &Model) {
    assert!(m.errors().is_empty(), "{:?}", m.errors());
    assert_eq!(m.err_led(), ErrLed::Off);
}

/// Runs `m` with a controller until `until`: the controller is called at time zero and
/// after every model event or wake-up it asks for (its return value, an absolute time),
/// like a PLC scanning with zero cycle time exactly when something changes.
fn run(m: &mut Model, until: Duration, mut controller: impl FnMut(&mut Model) -> Option<Duration>) {
    let mut wake = controller(m);
    while m.now() < until {
        let mut t = m.next_event().unwrap_or(until).min(until);
        if let Some(w) = wake.filter(|w| *w > m.now()) {
            t = t.min(w);
        }
        m.advance_to(t).unwrap();
        wake = controller(m);
    }
}
