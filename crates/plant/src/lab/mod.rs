//! The four EDU-mod models of the PLC teaching lab: the hydraulic slide unit, the
//! crossroad, the mixing unit and the washing machine (the teaching-lab thesis,
//! docs/THESES.md, as restated in the lab-models spec; section numbers below are the
//! spec's, `LAB-Axx` its numbered interpretations).
//!
//! Each model is a [`Plant`] (named BOOL signals, one always-present I/O module named after
//! the model, a console language for faults) and a [`LabModel`] (the ERR LED, the error
//! record, the RESET button and the model state for tests and the mimic). [`open`] makes
//! one from its name and [`LabOptions`]; [`bindings`] gives its signals' direct addresses
//! in one of the three address [`Profile`]s; the crate's registry opens them with default
//! options under the same names.
//!
//! # Data flow
//!
//! ```text
//!   PLC outputs ──set_output──▶ commanded ──(broken actuator → FALSE)──▶ effective
//!                                   │                                       │
//!                     RESET rising edge (program-err=true)          model: apply at `now`
//!                                   │                         (TONs start/stop, recoverable
//!                                   ▼                          errors raised and cleared)
//!                            initial state ◀── RESET button, console `reset`   │
//!                                                                               ▼
//!   advance_to(t): fire every due instant in order ── motion TON expiries, then the 1-s flag
//!                                                      (levels, temperature, overflow)
//!                                                                               │
//!   PLC inputs ◀──read── (stuck on/off, wire-open → FALSE) ◀── sensors, buttons, ERR
//! ```
//!
//! # Timing rules
//!
//! - Time zero is power-on. The 1-s system flag (`System_S.R_EDGE_1SEC`) rises at every
//!   whole second of simulated time (1 s, 2 s, ...; not at 0): level and temperature steps
//!   happen exactly then, once per edge, whatever the time the valve opened within the
//!   second (as the thesis code does).
//! - Motion steps (slide, drum) use a TON: it starts when exactly one direction command
//!   becomes TRUE, expires one period later, moves one step and restarts at its expiry, so
//!   the first step comes one period after the command. The TON stops (and loses its
//!   elapsed time) when the command goes or both directions are commanded.
//! - The period of a running TON follows the speed bit (EM3, `otacky`) at once, measured
//!   from the TON's start: switching to the shorter period after it has already elapsed
//!   makes the step at the switch instant. Nothing else restarts (a TON's PT changed on the
//!   fly).
//! - When a motion expiry and a 1-s edge fall on the same instant, the motion step comes
//!   first.
//! - [`Plant::set_output`] takes effect at the current time. [`Plant::advance_to`] fires
//!   every due instant (TON expiries, 1-s edges) in order up to and including `t`, never
//!   overshooting one; [`Plant::next_event`] is the next such instant (while ERR blinks,
//!   also the half-second where the LED goes dark). States therefore do not depend on the
//!   step size (tested: 1 ms, 7 ms, 250 ms and event-to-event stepping).
//! - ERR blinks at 1 Hz, lit during [n s, n + 0.5 s) of every second (`LAB-A10`).
//!
//! # Errors
//!
//! | Model | Error ([`ErrorKind`]) | ERR | Recovery |
//! |---|---|---|---|
//! | slide | EM1 and EM2 together (`both-directions`): no motion | blinks | release one |
//! | slide | a step out of [K1, K4] (`overtravel`): all K1–K4 TRUE | steady | RESET, back at K1 |
//! | crossroad | `zel_spodek` with `zel_vrch` or `zel_chodci` (`conflicting-greens`) | off | when it ends |
//! | mixing | a tank above 84 L or the vessel above 253 L (`overflow`) | steady | RESET |
//! | washing | both drum directions (`both-directions`): the drum stops | blinks | release one |
//! | washing | the tub filled beyond 100 % (`overflow`) or water above 90 °C (`overheat`) | steady | RESET |
//!
//! A non-recoverable error freezes the model: commands are ignored and nothing moves (no
//! level, temperature or position change, no cooling) until RESET; a recoverable error
//! still open at that instant is closed then. [`LabModel::errors`] keeps every error since
//! power-on or the last RESET in order; a recoverable one that starts and ends at the same
//! instant (two outputs written one after the other in one scan) is not recorded. The
//! mixing unit's initial blinking (no solenoid yet, section 5.2) blinks ERR but is not an
//! error record.
//!
//! RESET (the [`LabModel::reset`] button, the console's `reset`, or a rising edge of the
//! program's `RESET` output when the option `program-err=true`, `LAB-A11`) puts the model
//! into its initial state and clears the record; console faults stay. Outputs still
//! commanded act again from the RESET instant.
//!
//! # Choices where the thesis is silent
//!
//! - `LAB-A1`: slide sensors K1–K4 at positions 1, 4, 7, 10 (option `sensors=2,4,7,9`: any
//!   four increasing positions in 1..10). A step that would leave [K1, K4] is overtravel;
//!   a step into an overtravel zone inside 1..10 moves the slide there first.
//! - `LAB-A2`: EM3 = 1 is the working feed (1 s/step), EM3 = 0 rapid traverse (0.5 s/step).
//! - `LAB-A3`: the crossroad's variable names are authoritative.
//! - `LAB-A5`: every level and temperature sensor is TRUE while the value ≥ its threshold,
//!   in both directions.
//! - `LAB-A6`: the washer fills and drains 5 %/s, net when both; overflow when the level
//!   would exceed 100 % (it stays at 100 %).
//! - `LAB-A7`: heating +1.5 °C per second from 0 °C, whatever the level (option
//!   `heating=level`: 1.5 × 100 / level °C per second, using the level before that
//!   second's fill/drain step; with an empty tub the heater does nothing, neither heats nor
//!   lets it cool); cooling −3 °C per second while the heater is off, clamped at 0 °C.
//! - `LAB-A8`: three address profiles ([`Profile`]); `Lab` follows the wiring pattern.
//! - `LAB-A9`: the drum animates 8 positions (option `drum=4`: the thesis's 4-state mask).
//! - `LAB-A10`: ERR blinks 1 Hz.
//! - `LAB-A11`: `ERR` and `RESET` are always signals of the plant; `bindings` lists them
//!   only with `program-err=true`, and the `RESET` output acts only then. `ERR` is TRUE
//!   while the LED blinks or is steady (including the mixing unit's initial blinking): the
//!   program reads what the panel shows.
//! - The mixing unit: within one second the fill valves act first, then SV4's transfer
//!   (min(6 L, level) from each tank into the vessel), then SV5 (−18 L, not below 0);
//!   overflow is judged on the result. Its initial blinking ends at the first instant any
//!   of SV1–SV5 is TRUE (a level, so one still commanded at RESET ends it at once).
//! - START is a plain button (console `press START`/`release START`) the models ignore; it
//!   is also given to the crossroad (the thesis has none there) so that every model has the
//!   same surface. The crossroad also has the EDUtech pedestrian push-button
//!   `tlacitko_chodci` (section 4.1).
//! - The crossroad's conflict record uses the *commanded* lights (a broken lamp does not
//!   hide a program's conflict); every other model sees a broken actuator as a FALSE
//!   command (its input terminal is dead).
//! - Addresses of START, ERR, RESET and `tlacitko_chodci` (the spec gives none): see
//!   [`bindings`].
//!
//! # Console
//!
//! `stuck SENSOR on|off`, `wire-open SENSOR` (reads FALSE), `broken ACTUATOR` (does nothing
//! whatever is commanded), `clear NAME`, `clear all`, `reset`, `press BUTTON`, `release
//! BUTTON`. Sensors are every signal the PLC reads (including START and ERR), actuators
//! every model output except RESET; names are matched without regard to case.

mod addresses;
mod crossroad;
mod engine;
mod mixing;
mod slide;
mod washing;

use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;

use crate::core::{Plant, SimTime, Value};
use crossroad::Crossroad;
use engine::LabPlant;
use mixing::Mixing;
use slide::Slide;
use washing::Washing;

/// The models, by the names [`open`], [`bindings`] and the registry take.
pub const MODELS: &[&str] = &["slide", "crossroad", "mixing", "washing"];

/// Which column of the address tables a binding follows (`LAB-A8`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Profile {
    /// The model documentation's addresses (`Yb.n` → `QXb.n`, `Xb.n` → `IXb.n`).
    #[default]
    Model,
    /// The lab wiring by the pattern of section 2 (slide EM1–EM3 = `QX2.0`–`QX2.2`, SV4 =
    /// `QX24.1`, SV5 = `QX24.0`, `voda_100` = `IX84.3`).
    Lab,
    /// The lab column exactly as printed (slide `QX0.0`–`QX0.2`, SV4 `QX24.0`, SV5
    /// `QX24.1`, `voda_100` `IX83.3`).
    LabPrinted,
}

impl Profile {
    /// Every profile.
    pub const ALL: [Profile; 3] = [Profile::Model, Profile::Lab, Profile::LabPrinted];

    /// The profile's name (`model`, `lab`, `lab-printed`).
    pub fn name(&self) -> &'static str {
        match self {
            Profile::Model => "model",
            Profile::Lab => "lab",
            Profile::LabPrinted => "lab-printed",
        }
    }
}

impl fmt::Display for Profile {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Profile {
    type Err = LabError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Profile::ALL
            .into_iter()
            .find(|p| p.name() == s.trim())
            .ok_or_else(|| LabError::Option {
                key: "profile".to_owned(),
                reason: format!("`{s}` is not a profile; use model, lab or lab-printed"),
            })
    }
}

/// One signal of a model and its direct address in a profile.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Binding {
    /// The signal's name (the spec's variable name).
    pub signal: String,
    /// The direct address without `%`: `QX2.0`, `IX10.2`.
    pub address: String,
}

/// One option key: the models it applies to and what it takes.
struct OptionKey {
    key: &'static str,
    models: &'static [&'static str],
    allowed: &'static str,
    valid: fn(&str) -> bool,
}

const OPTION_KEYS: &[OptionKey] = &[
    OptionKey {
        key: "sensors",
        models: &["slide"],
        allowed: "four increasing positions in 1..10 separated by commas (default 1,4,7,10; e.g. 2,4,7,9)",
        valid: |v| parse_sensors(v).is_some(),
    },
    OptionKey {
        key: "drum",
        models: &["washing"],
        allowed: "8 (default) or 4",
        valid: |v| matches!(v, "8" | "4"),
    },
    OptionKey {
        key: "heating",
        models: &["washing"],
        allowed: "constant (default) or level",
        valid: |v| matches!(v, "constant" | "level"),
    },
    OptionKey {
        key: "program-err",
        models: &["slide", "crossroad", "mixing", "washing"],
        allowed: "true or false (default)",
        valid: |v| matches!(v, "true" | "false"),
    },
];

/// Four increasing positions in 1..=10, as `a,b,c,d`.
fn parse_sensors(v: &str) -> Option<[u8; 4]> {
    let mut out = [0u8; 4];
    let mut parts = v.split(',');
    for slot in out.iter_mut() {
        *slot = parts.next()?.trim().parse().ok()?;
    }
    if parts.next().is_some() {
        return None;
    }
    let increasing = out.windows(2).all(|w| matches!(w, [a, b] if a < b));
    let in_range = out.iter().all(|p| (1..=10).contains(p));
    (increasing && in_range).then_some(out)
}

/// Model options as `key=value` text (`LAB-A1`, `A7`, `A9`, `A11`):
///
/// | Key | Model | Values |
/// |---|---|---|
/// | `sensors` | slide | four increasing positions of K1–K4 in 1..10 (default `1,4,7,10`) |
/// | `drum` | washing | `8` drum positions (default) or `4` (the thesis's mask) |
/// | `heating` | washing | `constant` +1.5 °C/s (default) or `level` (scaled by 100/level) |
/// | `program-err` | all | `true`: `ERR` and `RESET` are bound and `RESET` acts (default `false`) |
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct LabOptions {
    values: BTreeMap<String, String>,
}

impl LabOptions {
    /// Validates the keys and values (for any model; [`open`] and [`bindings`] check that
    /// each key applies to the model). Unknown keys, bad values and a key given twice are
    /// errors naming the key and what it allows.
    pub fn parse(pairs: &[(String, String)]) -> Result<LabOptions, LabError> {
        let mut values = BTreeMap::new();
        for (key, value) in pairs {
            let key = key.trim();
            let value = value.trim();
            let Some(spec) = OPTION_KEYS.iter().find(|k| k.key == key) else {
                let known: Vec<&str> = OPTION_KEYS.iter().map(|k| k.key).collect();
                return Err(LabError::Option {
                    key: key.to_owned(),
                    reason: format!("unknown option; the options are {}", known.join(", ")),
                });
            };
            if !(spec.valid)(value) {
                return Err(LabError::Option {
                    key: key.to_owned(),
                    reason: format!("`{value}` is not allowed; use {}", spec.allowed),
                });
            }
            if values.insert(key.to_owned(), value.to_owned()).is_some() {
                return Err(LabError::Option {
                    key: key.to_owned(),
                    reason: "given twice".to_owned(),
                });
            }
        }
        Ok(LabOptions { values })
    }

    /// The value given for `key`, if any.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.values.get(key).map(String::as_str)
    }

    /// Fails on a key that does not apply to `model`.
    fn check_for(&self, model: &str) -> Result<(), LabError> {
        for key in self.values.keys() {
            if let Some(spec) = OPTION_KEYS.iter().find(|k| k.key == key) {
                if !spec.models.contains(&model) {
                    let takes: Vec<&str> = OPTION_KEYS
                        .iter()
                        .filter(|k| k.models.contains(&model))
                        .map(|k| k.key)
                        .collect();
                    return Err(LabError::Option {
                        key: key.clone(),
                        reason: format!(
                            "applies to the {} model only; the {model} model takes {}",
                            spec.models.join(", "),
                            takes.join(", ")
                        ),
                    });
                }
            }
        }
        Ok(())
    }

    /// `program-err=true`: ERR and RESET bound, the RESET output acts (`LAB-A11`).
    pub(crate) fn program_err(&self) -> bool {
        self.get("program-err") == Some("true")
    }

    /// The slide's sensor positions (`LAB-A1`).
    pub(crate) fn sensors(&self) -> [u8; 4] {
        self.get("sensors")
            .and_then(parse_sensors)
            .unwrap_or([1, 4, 7, 10])
    }

    /// The washer's drum positions (`LAB-A9`).
    pub(crate) fn drum_positions(&self) -> u8 {
        if self.get("drum") == Some("4") {
            4
        } else {
            8
        }
    }

    /// The washer heats by 1.5 × 100 / level (`LAB-A7`).
    pub(crate) fn heating_by_level(&self) -> bool {
        self.get("heating") == Some("level")
    }
}

/// Errors of [`open`], [`bindings`] and [`LabOptions::parse`].
#[derive(Debug, thiserror::Error, Clone, PartialEq, Eq)]
pub enum LabError {
    /// No model has this name.
    #[error("unknown lab model `{0}`; the models are {models}", models = MODELS.join(", "))]
    UnknownModel(String),
    /// An option key or value not allowed.
    #[error("option `{key}`: {reason}")]
    Option {
        /// The key.
        key: String,
        /// What is wrong and what is allowed.
        reason: String,
    },
}

/// A new model with the given options.
pub fn open(model: &str, options: &LabOptions) -> Result<Box<dyn LabModel + Send>, LabError> {
    if !MODELS.contains(&model) {
        return Err(LabError::UnknownModel(model.to_owned()));
    }
    options.check_for(model)?;
    match model {
        "slide" => Ok(Box::new(LabPlant::<Slide>::new(options))),
        "crossroad" => Ok(Box::new(LabPlant::<Crossroad>::new(options))),
        "mixing" => Ok(Box::new(LabPlant::<Mixing>::new(options))),
        "washing" => Ok(Box::new(LabPlant::<Washing>::new(options))),
        _ => Err(LabError::UnknownModel(model.to_owned())),
    }
}

/// The same as [`open`], as a plain [`Plant`] for the registry.
pub(crate) fn open_plant(
    model: &str,
    options: &LabOptions,
) -> Result<Box<dyn Plant + Send>, LabError> {
    if !MODELS.contains(&model) {
        return Err(LabError::UnknownModel(model.to_owned()));
    }
    options.check_for(model)?;
    match model {
        "slide" => Ok(Box::new(LabPlant::<Slide>::new(options))),
        "crossroad" => Ok(Box::new(LabPlant::<Crossroad>::new(options))),
        "mixing" => Ok(Box::new(LabPlant::<Mixing>::new(options))),
        "washing" => Ok(Box::new(LabPlant::<Washing>::new(options))),
        _ => Err(LabError::UnknownModel(model.to_owned())),
    }
}

/// The model's signals with their direct addresses in `profile`, in the order of the
/// spec's tables, then `tlacitko_chodci` (crossroad), `START` (always), and `ERR` and
/// `RESET` (only with `program-err=true`).
///
/// The spec gives no address for these; the choice: model profile `tlacitko_chodci` =
/// `IX0.0`, `START` = `IX1.0`, `ERR` = `IX1.1`, `RESET` = `QX1.0`; both lab profiles
/// `tlacitko_chodci` = `IX10.2` (the first lab input, free on the crossroad), `START` =
/// `IX11.0`, `ERR` = `IX11.1`, `RESET` = `QX11.0`.
pub fn bindings(
    model: &str,
    profile: Profile,
    options: &LabOptions,
) -> Result<Vec<Binding>, LabError> {
    if !MODELS.contains(&model) {
        return Err(LabError::UnknownModel(model.to_owned()));
    }
    options.check_for(model)?;
    addresses::table(model, profile, options.program_err())
        .ok_or_else(|| LabError::UnknownModel(model.to_owned()))
}

/// What the red ERR LED does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrLed {
    /// Dark.
    Off,
    /// Blinking at 1 Hz: a recoverable error (or the mixing unit's initial state).
    Blinking,
    /// Lit steadily: a non-recoverable error, only RESET leaves it.
    Steady,
}

/// What went wrong.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ErrorKind {
    /// Both directions commanded (slide EM1 + EM2, washer drum right + left): recoverable.
    BothDirections,
    /// The slide stepped out of [K1, K4]: non-recoverable.
    Overtravel,
    /// A tank, the mixing vessel or the washer's tub overflowed: non-recoverable.
    Overflow,
    /// The washer's water above 90 °C: non-recoverable.
    Overheat,
    /// The crossroad's lower green together with the upper or pedestrian green: recorded
    /// only (ERR stays off), cleared when it ends.
    ConflictingGreens,
}

impl ErrorKind {
    /// The kind's name (`both-directions`, `overtravel`, `overflow`, `overheat`,
    /// `conflicting-greens`).
    pub fn name(&self) -> &'static str {
        match self {
            ErrorKind::BothDirections => "both-directions",
            ErrorKind::Overtravel => "overtravel",
            ErrorKind::Overflow => "overflow",
            ErrorKind::Overheat => "overheat",
            ErrorKind::ConflictingGreens => "conflicting-greens",
        }
    }

    /// Whether the kind lights ERR (the crossroad's conflict does not: the real model has
    /// no such logic).
    fn lights_err(&self) -> bool {
        !matches!(self, ErrorKind::ConflictingGreens)
    }
}

impl fmt::Display for ErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One error of a model.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelError {
    /// When it began.
    pub time: SimTime,
    /// What it is.
    pub kind: ErrorKind,
    /// Recoverable (ERR blinks, clears when the cause goes) or not (ERR steady, until RESET).
    pub recoverable: bool,
    /// What happened, e.g. `tank 2 above 84 L (90 L)`.
    pub detail: String,
    /// When a recoverable error's cause went; `None` while active.
    pub cleared: Option<SimTime>,
}

impl fmt::Display for ModelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:.3} s {}: {}",
            self.time.as_secs_f64(),
            self.kind,
            self.detail
        )?;
        if let Some(cleared) = self.cleared {
            write!(f, " (cleared at {:.3} s)", cleared.as_secs_f64())?;
        }
        Ok(())
    }
}

/// A lab model: a [`Plant`] with the model's ERR LED, error record, RESET button and state.
pub trait LabModel: Plant {
    /// The model's name (one of [`MODELS`]).
    fn model(&self) -> &'static str;
    /// What the ERR LED does now.
    fn err_led(&self) -> ErrLed;
    /// Whether the ERR LED is lit now (blinking: lit during [n s, n + 0.5 s) of every
    /// second, `LAB-A10`).
    fn err_lit(&self) -> bool;
    /// Every error since start or the last RESET, in order (recoverable ones get
    /// `cleared` when their cause goes). The mixing unit's initial blinking "no solenoid
    /// yet" is not an error here.
    fn errors(&self) -> &[ModelError];
    /// The RESET button: initial state, all model variables cleared (also clears
    /// [`LabModel::errors`]). Console faults and the PLC's outputs stay.
    fn reset(&mut self);
    /// The model's state for tests, scenarios and the mimic, by stable lowercase names:
    /// slide `position` (1..10), `leds` (bit mask, bit 0 = position 1); mixing `tank1`,
    /// `tank2`, `tank3`, `vessel` (L), `mixing` (MIX on); washing `level` (%),
    /// `temperature` (°C), `drum` (0..7, or 0..3 with `drum=4`), `drum_turning`; the
    /// crossroad nothing extra. Every model adds `err` (ERR blinking or steady) and
    /// `err_lit`.
    fn state(&self) -> Vec<(&'static str, Value)>;
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opts(pairs: &[(&str, &str)]) -> Result<LabOptions, LabError> {
        let pairs: Vec<(String, String)> = pairs
            .iter()
            .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
            .collect();
        LabOptions::parse(&pairs)
    }

    #[test]
    fn sensors_parse() {
        assert_eq!(parse_sensors("1,4,7,10"), Some([1, 4, 7, 10]));
        assert_eq!(parse_sensors(" 2, 4 ,7,9"), Some([2, 4, 7, 9]));
        for bad in [
            "",
            "1,2,3",
            "1,2,3,4,5",
            "0,4,7,10",
            "1,4,7,11",
            "1,4,4,10",
            "4,1,7,10",
            "a,b,c,d",
        ] {
            assert_eq!(parse_sensors(bad), None, "{bad}");
        }
    }

    #[test]
    fn options_validate_keys_and_values() {
        let o = opts(&[("sensors", "2,4,7,9"), ("program-err", "true")]).unwrap();
        assert_eq!(o.get("sensors"), Some("2,4,7,9"));
        assert_eq!(o.sensors(), [2, 4, 7, 9]);
        assert!(o.program_err());
        assert_eq!(LabOptions::default().sensors(), [1, 4, 7, 10]);
        assert_eq!(LabOptions::default().drum_positions(), 8);
        assert!(!LabOptions::default().heating_by_level());

        let e = opts(&[("speed", "2")]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "option `speed`: unknown option; the options are sensors, drum, heating, program-err"
        );
        let e = opts(&[("drum", "6")]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "option `drum`: `6` is not allowed; use 8 (default) or 4"
        );
        let e = opts(&[("program-err", "yes")]).unwrap_err();
        assert!(
            matches!(&e, LabError::Option { key, .. } if key == "program-err"),
            "{e}"
        );
        let e = opts(&[("drum", "4"), ("drum", "8")]).unwrap_err();
        assert_eq!(e.to_string(), "option `drum`: given twice");

        let washing = opts(&[("drum", "4"), ("heating", "level")]).unwrap();
        assert!(washing.check_for("washing").is_ok());
        let e = washing.check_for("slide").unwrap_err();
        assert_eq!(
            e.to_string(),
            "option `drum`: applies to the washing model only; the slide model takes sensors, program-err"
        );
    }

    #[test]
    fn profiles_parse_and_print() {
        for p in Profile::ALL {
            assert_eq!(p.to_string().parse::<Profile>(), Ok(p));
        }
        assert_eq!(Profile::default(), Profile::Model);
        assert!("printed".parse::<Profile>().is_err());
    }

    #[test]
    fn error_kind_names() {
        let names: Vec<&str> = [
            ErrorKind::BothDirections,
            ErrorKind::Overtravel,
            ErrorKind::Overflow,
            ErrorKind::Overheat,
            ErrorKind::ConflictingGreens,
        ]
        .iter()
        .map(ErrorKind::name)
        .collect();
        assert_eq!(
            names,
            [
                "both-directions",
                "overtravel",
                "overflow",
                "overheat",
                "conflicting-greens"
            ]
        );
    }
}
