//! A student's program tried from the browser (a remote lab's `[program]` in hmi.toml):
//! uploaded, checked by the compiler with its diagnostics shown `file:line:col`, then run
//! against the lab's simulation, with what happened (the supervisor's refusals and
//! lock-outs among it) shown to the student.
//!
//! The HMI knows no lab: the application embedding it (the `stanice` binary) hands it a
//! [`ProgramTrial`] for the trial the folder names (`trial = "sorting"`), through
//! [`ServeConfig::trial`](crate::ServeConfig::trial). The trial's work runs on a blocking
//! thread, one at a time: a run takes a CPU for a second or two.
//!
//! Where the HMI runs in the station's process (`stanice run --hmi`) and `[program]`
//! names the lab's `node`, a trial can also load the program into the lab itself
//! ([`ProgramTrial::load`]: the running node's PLC, behind the same supervisor) and put
//! the lab's own program back ([`ProgramTrial::restore`]); only the holder of the operator
//! lease may, as only they control the lab.

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
    /// The station's node that runs students' programs on the lab itself (the sorting
    /// lab's `SORTER`); without it programs are only tried on a simulation.
    #[serde(default)]
    pub node: Option<String>,
    /// The node's task whose program a student's replaces (default `main`).
    #[serde(default = "default_task")]
    pub task: String,
}

fn default_task() -> String {
    "main".to_owned()
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

/// A boxed future a trial's live operations return.
pub type TrialFuture =
    std::pin::Pin<Box<dyn std::future::Future<Output = Result<serde_json::Value, String>> + Send>>;

/// A lab's trial of a program: what the application gives the HMI.
pub trait ProgramTrial: Send + Sync + std::fmt::Debug {
    /// Compiles `files` as the trial will.
    fn check(&self, files: &[SourceFile]) -> CheckReport;
    /// Runs `files` (with `seed` for the simulation), returning the report to show: a
    /// JSON object with at least `passed` (bool) and `text` (the report in words).
    fn run(&self, files: &[SourceFile], seed: u64) -> Result<serde_json::Value, String>;
    /// Whether [`ProgramTrial::load`] reaches the lab itself here.
    fn live(&self) -> bool {
        false
    }
    /// Loads `files` into the lab itself for `user`: a JSON object with at least `text`
    /// (what was loaded, in words), or why not (a compile error with its place).
    fn load(&self, _files: Vec<SourceFile>, _user: String) -> TrialFuture {
        Box::pin(async { Err(NOT_LIVE.to_owned()) })
    }
    /// Puts the lab's own program back, for `user`.
    fn restore(&self, _user: String) -> TrialFuture {
        Box::pin(async { Err(NOT_LIVE.to_owned()) })
    }
}

/// Why a trial loads nothing into the lab.
pub const NOT_LIVE: &str =
    "programs are only tried on a simulation here (the HMI runs apart from the station, or [program] names no node)";
