//! What a run came to: the verdict, every violation with its simulated time and the
//! program's outputs at that moment, each property's count; as text for a student's
//! terminal and as JSON for tools.

use std::fmt::Write as _;

use serde::Serialize;

/// What was violated.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case", tag = "type", content = "name")]
pub enum ViolationKind {
    /// A model error (`overtravel`, `overflow`, `overheat`, `both-directions`,
    /// `conflicting-greens`).
    Model(String),
    /// A property of the scenario.
    Property,
    /// The program stopped on a run-time fault (division by zero, an index out of range).
    PlcFault,
}

impl ViolationKind {
    /// A short name: the model error's, `property` or `plc-fault`.
    pub fn name(&self) -> &str {
        match self {
            ViolationKind::Model(name) => name,
            ViolationKind::Property => "property",
            ViolationKind::PlcFault => "plc-fault",
        }
    }
}

/// One violation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Violation {
    /// Simulated time, seconds since power-on.
    pub time_s: f64,
    /// What.
    pub kind: ViolationKind,
    /// The property's name, for a property.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub property: Option<String>,
    /// In words.
    pub detail: String,
    /// The program's outputs at that moment, as the model had them (signal, value).
    pub outputs: Vec<(String, String)>,
}

impl Violation {
    /// One line: `12.500 s overtravel: ... [EM1=1 EM2=0 EM3=0]`.
    pub fn line(&self) -> String {
        let what = match &self.property {
            Some(name) => format!("property `{name}`"),
            None => self.kind.name().to_owned(),
        };
        let outputs: Vec<String> = self
            .outputs
            .iter()
            .map(|(signal, value)| format!("{signal}={value}"))
            .collect();
        format!(
            "{:>10.3} s  {what}: {}  [outputs {}]",
            self.time_s,
            self.detail,
            outputs.join(" ")
        )
    }
}

/// A property's outcome.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PropertyOutcome {
    /// Its name.
    pub name: String,
    /// `never`, `always`, `eventually`, `repeats`.
    pub rule: String,
    /// Its condition.
    pub condition: String,
    /// How often it was violated.
    pub violations: u64,
}

/// A run's report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Report {
    /// The model.
    pub model: String,
    /// The address profile.
    pub profile: String,
    /// The PROGRAM run.
    pub program: String,
    /// Simulated seconds run.
    pub simulated_s: f64,
    /// PLC scans run.
    pub scans: u64,
    /// Wall-clock seconds the run took.
    pub wall_s: f64,
    /// Simulated time over wall-clock time.
    pub speedup: f64,
    /// No violation.
    pub passed: bool,
    /// Violations in all.
    pub violations_total: u64,
    /// The first hundred violations.
    pub violations: Vec<Violation>,
    /// Each property of the scenario.
    pub properties: Vec<PropertyOutcome>,
    /// The faults the scenario injected (`time line`).
    pub faults_injected: Vec<String>,
}

impl Report {
    /// The first violation, if any.
    pub fn first_violation(&self) -> Option<&Violation> {
        self.violations.first()
    }

    /// The report for a terminal.
    pub fn text(&self) -> String {
        let mut out = String::new();
        let _ = writeln!(
            out,
            "{} on {} (profile {}): {:.1} s simulated in {} scans, {:.2} s ({:.0}x real time)",
            self.program,
            self.model,
            self.profile,
            self.simulated_s,
            self.scans,
            self.wall_s,
            self.speedup
        );
        for fault in &self.faults_injected {
            let _ = writeln!(out, "  fault injected at {fault}");
        }
        for violation in &self.violations {
            let _ = writeln!(out, "{}", violation.line());
        }
        let unlisted = self
            .violations_total
            .saturating_sub(self.violations.len() as u64);
        if unlisted > 0 {
            let _ = writeln!(out, "  ... and {unlisted} more violation(s)");
        }
        for property in &self.properties {
            let mark = if property.violations == 0 {
                "ok"
            } else {
                "FAILED"
            };
            let _ = writeln!(
                out,
                "  {mark:>6}  {} ({} {}){}",
                property.name,
                property.rule,
                property.condition,
                if property.violations > 0 {
                    format!(": {} violation(s)", property.violations)
                } else {
                    String::new()
                }
            );
        }
        let _ = writeln!(
            out,
            "{}",
            if self.passed {
                "PASSED: no model error, every property held".to_owned()
            } else {
                format!("FAILED: {} violation(s)", self.violations_total)
            }
        );
        out
    }
}
