//! A student's program tried from the browser (a remote lab's `[program]` in hmi.toml):
//! uploaded, checked by the compiler with its diagnostics shown `file:line:col`, then run
//! against the lab's simulation, with what happened (the supervisor's refusals and
//! lock-outs among it) shown to the student.
//!
//! The HMI knows no lab: the application embedding it (the `stanice` binary) hands it a
//! [`ProgramTrial`] for the trial the folder names (`trial = "sorting"`), through
//! [`ServeConfig::trial`](crate::ServeConfig::trial). The trial's work runs on a blocking
//! thread, one at a time: a run takes a CPU for a second or two.

use serde::{Deserialize, Serialize};

/// `[program]` of `hmi.toml`.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProgramConfig {
    /// The trial the application offers (`sorting`: the sorting lab behind its
    /// supervisor).
    pub trial: String,
    /// The lowest level that may upload and try a program (default 5).
    #[serde(default = "default_level")]
    pub level: u8,
}

fn default_level() -> u8 {
    5
}

/// One uploaded file.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SourceFile {
    /// Its name (shown in the diagnostics).
    pub name: String,
    /// Its text.
    pub text: String,
}

/// What the compiler said.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct CheckReport {
    /// The program compiles.
    pub ok: bool,
    /// Errors and warnings, rendered `file:line:col: ...` with the source line.
    pub diagnostics: Vec<String>,
    /// The PROGRAM that would run.
    pub main: Option<String>,
}

/// A lab's trial of a program: what the application gives the HMI.
pub trait ProgramTrial: Send + Sync + std::fmt::Debug {
    /// Compiles `files` as the trial will.
    fn check(&self, files: &[SourceFile]) -> CheckReport;
    /// Runs `files` (with `seed` for the simulation), returning the report to show: a
    /// JSON object with at least `passed` (bool) and `text` (the report in words).
    fn run(&self, files: &[SourceFile], seed: u64) -> Result<serde_json::Value, String>;
}
