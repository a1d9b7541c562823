//! The PLC teaching lab (the teaching-lab thesis: four EDU-mod models, a slide unit, a
//! crossroad, a mixing unit and a washing machine, simulated for students who write
//! Structured Text without the hardware): a student's program runs on the soft PLC
//! against a model of `plant::lab` on the simulated clock, at any speed, and a scenario
//! decides whether it did its task.
//!
//! ```text
//!  student's *.st --program::Program (compile, the one PROGRAM or --main)--+
//!                                                                          v
//!  scenario.toml --scenario::Scenario (lines at times, properties)--> run::Session
//!                                                                          |  scan by scan:
//!      plant::lab model (profile's addresses: K1 -> %IX0.0, EM1 <- %QX0.0) |  model <-> PLC image
//!                                                                          v
//!                          report::Report (verdict, violations with time and outputs)
//!                                                                          |
//!                          grade: a folder of submissions -> CSV and HTML table
//! ```
//!
//! - [`program`]: compiling a student's files and picking the PROGRAM.
//! - [`project`]: a lab project, several models with their programs served together.
//! - [`scenario`]: the TOML a teacher writes (inputs over time, faults, properties).
//! - [`condition`]: the ST-like conditions of properties over the model's names.
//! - [`run`]: the coupled run (one scan: model, scenario lines, inputs, PLC, outputs,
//!   checks) and its speed.
//! - [`report`]: what a run came to, as text and JSON.
//! - [`grade`]: a class's folder graded against one scenario.
//! - [`serve`]: the web mimic: the front panel, buttons, speed control, time-line.
//! - [`timeline`]: every change of a run, for a mimic's logic-analyser view.
//!
//! Model errors (a collision, an overtravel, an overflow, an overheat, conflicting
//! greens) always fail a run; a scenario's properties add what the model cannot know.

#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]
#![cfg_attr(test, allow(clippy::unwrap_used, clippy::expect_used, clippy::panic))]

pub mod condition;
pub mod grade;
pub mod program;
pub mod project;
pub mod report;
pub mod run;
pub mod scenario;
pub mod serve;
pub mod timeline;

pub use program::{Program, ProgramError};
pub use report::{Report, Violation, ViolationKind};
pub use run::{RunError, RunSettings, Session, Speed};
pub use scenario::{Scenario, ScenarioError};
