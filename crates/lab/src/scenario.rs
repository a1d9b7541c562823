//! Scenarios as data: what happens to a model during a run (buttons, faults) and what
//! the student's program must hold, in a TOML file a teacher writes.
//!
//! ```toml
//! model = "mixing"              # the model the scenario is for
//! profile = "model"             # address profile (the command line's --profile wins)
//! duration = "10m"              # simulated time (the command line's --duration wins)
//! scan = "10ms"                 # the PLC's cycle
//!
//! [options]                     # the model's options (LAB-A1, A7, A9, A11)
//! program-err = "true"
//!
//! [[input]]                     # a console line of the model at a simulated time
//! at = "1s"
//! do = "press START"
//!
//! [[fault]]                     # a fault injected at `at`, cleared at `until` (optional)
//! at = "2m"
//! do = "stuck H1 off"
//! until = "3m"
//!
//! [[property]]                  # exactly one of never, always, eventually, repeats
//! name = "no tank above 84 L"
//! never = "tank1 > 84 OR tank2 > 84 OR tank3 > 84"
//! after = "0s"                  # checked from (optional)
//!
//! [[property]]
//! name = "a cycle completes within 90 s"
//! repeats = "SV5"               # must rise at least once in every `within`
//! within = "90s"
//! ```
//!
//! Every model error (a collision, an overtravel, an overflow, an overheat, conflicting
//! greens) fails a run whatever the properties say; properties add what the model cannot
//! know (a cycle time, a level never reached). Conditions are [`Condition`]s over the
//! model's signals and state. Errors name the file, line and column.

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Duration;

use serde::Deserialize;

use crate::condition::{Condition, ConditionError};

/// A scenario, parsed (its conditions are resolved when a run starts, against the
/// model's names).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Scenario {
    /// Where it was read from (for messages).
    pub source: String,
    /// The model it is for.
    pub model: Option<String>,
    /// The address profile it was written for.
    pub profile: Option<String>,
    /// Simulated time to run.
    pub duration: Option<Duration>,
    /// The PLC's cycle.
    pub scan: Option<Duration>,
    /// Model options (`key = "value"`).
    pub options: Vec<(String, String)>,
    /// Console lines at times: inputs and faults (with their clearing), in time order.
    pub events: Vec<TimedLine>,
    /// What must hold.
    pub properties: Vec<PropertySpec>,
}

/// A console line of the model at a simulated time.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TimedLine {
    /// When.
    pub at: Duration,
    /// The line (`press START`, `stuck H1 off`, `clear H1`).
    pub line: String,
    /// Whether it is an injected fault (reported as such).
    pub fault: bool,
}

/// A property as written: its condition's text, resolved when the run starts.
#[derive(Debug, Clone, PartialEq)]
pub struct PropertySpec {
    /// Its name in reports.
    pub name: String,
    /// What kind of rule.
    pub rule: RuleKind,
    /// The condition's text.
    pub condition: String,
    /// Where the condition is written (`file:line:col`), for errors.
    pub at: String,
    /// Checked from this simulated time on.
    pub after: Duration,
    /// For `eventually` and `repeats`: the window.
    pub within: Option<Duration>,
}

/// The rules a property may state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RuleKind {
    /// The condition never holds.
    Never,
    /// The condition always holds.
    Always,
    /// The condition holds at some time within `within` after `after`.
    Eventually,
    /// The condition rises at least once in every `within` after `after`.
    Repeats,
}

impl RuleKind {
    /// Its key in the file.
    pub fn key(self) -> &'static str {
        match self {
            RuleKind::Never => "never",
            RuleKind::Always => "always",
            RuleKind::Eventually => "eventually",
            RuleKind::Repeats => "repeats",
        }
    }
}

/// A property ready to be checked: its condition resolved against a model's names.
#[derive(Debug, Clone, PartialEq)]
pub struct Property {
    /// As written.
    pub spec: PropertySpec,
    /// The condition.
    pub condition: Condition,
}

/// Why a scenario cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// The file cannot be read.
    #[error("cannot read {path}: {error}")]
    Read {
        /// The file.
        path: String,
        /// Why.
        error: std::io::Error,
    },
    /// The file is not a scenario.
    #[error("{0}")]
    Invalid(String),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScenario {
    model: Option<String>,
    profile: Option<String>,
    duration: Option<toml::Spanned<String>>,
    scan: Option<toml::Spanned<String>>,
    #[serde(default)]
    options: BTreeMap<String, toml::Value>,
    #[serde(default)]
    input: Vec<RawLine>,
    #[serde(default)]
    fault: Vec<RawLine>,
    #[serde(default)]
    property: Vec<RawProperty>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLine {
    at: toml::Spanned<String>,
    #[serde(rename = "do")]
    line: String,
    until: Option<toml::Spanned<String>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawProperty {
    name: String,
    never: Option<toml::Spanned<String>>,
    always: Option<toml::Spanned<String>>,
    eventually: Option<toml::Spanned<String>>,
    repeats: Option<toml::Spanned<String>>,
    after: Option<toml::Spanned<String>>,
    within: Option<toml::Spanned<String>>,
}

/// 1-based line and column of byte `offset` in `text`.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = text.get(..offset).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    let column = before
        .rsplit('\n')
        .next()
        .map_or(1, |last| last.chars().count() + 1);
    (line, column)
}

impl Scenario {
    /// Reads the scenario file at `path`.
    pub fn load(path: &Path) -> Result<Scenario, ScenarioError> {
        let text = std::fs::read_to_string(path).map_err(|error| ScenarioError::Read {
            path: path.display().to_string(),
            error,
        })?;
        Scenario::parse(&path.display().to_string(), &text)
    }

    /// Parses a scenario's text; `source` names it in messages.
    pub fn parse(source: &str, text: &str) -> Result<Scenario, ScenarioError> {
        let raw: RawScenario = toml::from_str(text).map_err(|error| {
            let at = error
                .span()
                .map(|span| {
                    let (line, column) = line_col(text, span.start);
                    format!("{source}:{line}:{column}")
                })
                .unwrap_or_else(|| source.to_owned());
            ScenarioError::Invalid(format!("{at}: {}", error.message()))
        })?;
        let where_ = |span: std::ops::Range<usize>| {
            let (line, column) = line_col(text, span.start);
            format!("{source}:{line}:{column}")
        };
        let duration = |value: &toml::Spanned<String>| {
            parse_duration(value.get_ref()).map_err(|error| {
                ScenarioError::Invalid(format!("{}: {error}", where_(value.span())))
            })
        };
        let mut events = Vec::new();
        for (lines, fault) in [(&raw.input, false), (&raw.fault, true)] {
            for line in lines {
                let at = duration(&line.at)?;
                let words: Vec<&str> = line.line.split_whitespace().collect();
                if words.is_empty() {
                    return Err(ScenarioError::Invalid(format!(
                        "{}: `do` is empty",
                        where_(line.at.span())
                    )));
                }
                events.push(TimedLine {
                    at,
                    line: words.join(" "),
                    fault,
                });
                if let Some(until) = &line.until {
                    let until_time = duration(until)?;
                    if until_time <= at {
                        return Err(ScenarioError::Invalid(format!(
                            "{}: `until` must come after `at`",
                            where_(until.span())
                        )));
                    }
                    // What the fault acts on is its second word (`stuck H1 off`).
                    let Some(target) = words.get(1) else {
                        return Err(ScenarioError::Invalid(format!(
                            "{}: `until` needs a fault naming what it acts on (`stuck H1 off`)",
                            where_(until.span())
                        )));
                    };
                    events.push(TimedLine {
                        at: until_time,
                        line: format!("clear {target}"),
                        fault,
                    });
                }
            }
        }
        // Stable: lines at the same time keep the file's order.
        events.sort_by_key(|event| event.at);
        let mut properties = Vec::new();
        for property in &raw.property {
            let rules = [
                (RuleKind::Never, &property.never),
                (RuleKind::Always, &property.always),
                (RuleKind::Eventually, &property.eventually),
                (RuleKind::Repeats, &property.repeats),
            ];
            let given: Vec<_> = rules
                .iter()
                .filter_map(|(kind, condition)| condition.as_ref().map(|c| (*kind, c)))
                .collect();
            let [(rule, condition)] = given.as_slice() else {
                return Err(ScenarioError::Invalid(format!(
                    "{source}: property `{}` needs exactly one of never, always, eventually, repeats",
                    property.name
                )));
            };
            let within = property.within.as_ref().map(duration).transpose()?;
            let needs_within = matches!(rule, RuleKind::Eventually | RuleKind::Repeats);
            if needs_within != within.is_some() {
                return Err(ScenarioError::Invalid(format!(
                    "{}: property `{}`: `within` {} with `{}`",
                    where_(condition.span()),
                    property.name,
                    if needs_within {
                        "is needed"
                    } else {
                        "has no meaning"
                    },
                    rule.key()
                )));
            }
            if within.is_some_and(|w| w.is_zero()) {
                return Err(ScenarioError::Invalid(format!(
                    "{}: property `{}`: `within` must be longer than 0",
                    where_(condition.span()),
                    property.name
                )));
            }
            // The condition's text starts one character into its span (the quote).
            let mut span = condition.span();
            span.start += 1;
            properties.push(PropertySpec {
                name: property.name.clone(),
                rule: *rule,
                condition: condition.get_ref().clone(),
                at: where_(span),
                after: property
                    .after
                    .as_ref()
                    .map(duration)
                    .transpose()?
                    .unwrap_or_default(),
                within,
            });
        }
        let options = raw
            .options
            .iter()
            .map(|(key, value)| {
                let text = match value {
                    toml::Value::String(text) => text.clone(),
                    other => other.to_string(),
                };
                (key.clone(), text)
            })
            .collect();
        Ok(Scenario {
            source: source.to_owned(),
            model: raw.model,
            profile: raw.profile,
            duration: raw.duration.as_ref().map(duration).transpose()?,
            scan: raw.scan.as_ref().map(duration).transpose()?,
            options,
            events,
            properties,
        })
    }
}

impl PropertySpec {
    /// The property with its condition resolved against a model's names.
    pub fn resolve(
        &self,
        resolve: &dyn Fn(&str) -> Option<usize>,
        known: &dyn Fn() -> Vec<String>,
    ) -> Result<Property, ScenarioError> {
        let condition = Condition::parse(&self.condition, resolve, known).map_err(
            |ConditionError { column, message }| {
                ScenarioError::Invalid(format!(
                    "{} (column {column} of the condition): property `{}`: {message}",
                    self.at, self.name
                ))
            },
        )?;
        Ok(Property {
            spec: self.clone(),
            condition,
        })
    }
}

/// The longest simulated time a run takes: a year, far beyond any lab exercise.
const LONGEST: Duration = Duration::from_secs(366 * 86_400);

/// A duration as scenarios and the lab's command line write it: `500ms`, `1.5s`, `10m`,
/// `1h30m`, or a plain number of seconds.
pub fn parse_duration(text: &str) -> Result<Duration, String> {
    let text = text.trim();
    let seconds = |x: f64| -> Result<Duration, String> {
        if !x.is_finite() || x < 0.0 {
            return Err(format!("{text:?} is no duration: negative or not finite"));
        }
        Duration::try_from_secs_f64(x).map_err(|error| format!("{text:?}: {error}"))
    };
    let duration = if let Ok(x) = text.parse::<f64>() {
        seconds(x)?
    } else if let Some(x) = text
        .strip_suffix('s')
        .filter(|rest| !rest.ends_with('m'))
        .and_then(|rest| rest.trim().parse::<f64>().ok())
    {
        // humantime takes whole numbers only; a lab writes `0.5s` as often as `500ms`.
        seconds(x)?
    } else {
        humantime::parse_duration(text).map_err(|error| {
            format!("{text:?} is no duration ({error}): write e.g. 500ms, 1.5s, 10m or 1h30m")
        })?
    };
    if duration > LONGEST {
        return Err(format!("{text:?} is longer than the year a run may take"));
    }
    Ok(duration)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations() {
        assert_eq!(parse_duration("500ms"), Ok(Duration::from_millis(500)));
        assert_eq!(parse_duration("1.5s"), Ok(Duration::from_millis(1500)));
        assert_eq!(parse_duration("2"), Ok(Duration::from_secs(2)));
        assert_eq!(parse_duration("10m"), Ok(Duration::from_secs(600)));
        assert_eq!(parse_duration("1h30m"), Ok(Duration::from_secs(5400)));
        assert!(parse_duration("-1").is_err());
        assert!(parse_duration("soon").is_err());
        assert!(parse_duration("400days").is_err());
    }

    const TEXT: &str = r#"
model = "mixing"
duration = "2m"

[options]
program-err = true

[[input]]
at = "1s"
do = "press   START"

[[fault]]
at = "30s"
do = "stuck H1 off"
until = "40s"

[[property]]
name = "no overflow"
never = "tank1 > 84"

[[property]]
name = "cycles"
repeats = "SV5"
within = "90s"
after = "10s"
"#;

    #[test]
    fn a_scenario_reads_back() {
        let scenario = Scenario::parse("s.toml", TEXT).unwrap();
        assert_eq!(scenario.model.as_deref(), Some("mixing"));
        assert_eq!(scenario.duration, Some(Duration::from_secs(120)));
        assert_eq!(
            scenario.options,
            vec![("program-err".into(), "true".into())]
        );
        let lines: Vec<_> = scenario
            .events
            .iter()
            .map(|e| (e.at.as_secs(), e.line.as_str()))
            .collect();
        assert_eq!(
            lines,
            vec![(1, "press START"), (30, "stuck H1 off"), (40, "clear H1")]
        );
        assert_eq!(scenario.properties.len(), 2);
        assert_eq!(scenario.properties[0].at, "s.toml:19:10");
        assert_eq!(scenario.properties[1].rule, RuleKind::Repeats);
        assert_eq!(scenario.properties[1].after, Duration::from_secs(10));
    }

    #[test]
    fn mistakes_name_file_line_and_column() {
        let error = Scenario::parse("s.toml", "model = \"slide\"\nduraton = \"1m\"\n").unwrap_err();
        assert!(error.to_string().starts_with("s.toml:2:1:"), "{error}");
        let error = Scenario::parse("s.toml", "duration = \"soon\"\n").unwrap_err();
        assert!(error.to_string().starts_with("s.toml:1:12:"), "{error}");
        let both = "[[property]]\nname = \"x\"\nnever = \"ERR\"\nalways = \"ERR\"\n";
        assert!(Scenario::parse("s.toml", both)
            .unwrap_err()
            .to_string()
            .contains("exactly one"));
        let no_window = "[[property]]\nname = \"x\"\nrepeats = \"ERR\"\n";
        assert!(Scenario::parse("s.toml", no_window)
            .unwrap_err()
            .to_string()
            .contains("`within` is needed"));
        let early = "[[fault]]\nat = \"5s\"\ndo = \"stuck K1 on\"\nuntil = \"1s\"\n";
        assert!(Scenario::parse("s.toml", early)
            .unwrap_err()
            .to_string()
            .contains("after `at`"));
    }
}
