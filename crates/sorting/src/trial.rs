//! A sorting program tried as a student tries it before booking the lab: compiled with
//! the lab's interface, put behind the built-in supervisor, and left to sort the
//! simulated mechanism (seeded, with faults if asked); the report says where every ball
//! went, every refusal and lock-out of the supervisor, and whether it passed: every ball
//! in its colour's shaft, every sorting finished, the supervisor never stepping in. One
//! report for `stanice sorting run` and the web HMI's Program page.

use std::time::Duration;

use lab::program::{Program, ProgramError};
use plant::sorter::SorterConfig;
use plant::Plant as _;
use serde::Serialize;

use crate::classify::Colour;
use crate::rig::{Rig, RigError, RigSettings, SortingOutcome, SupervisorAction};

/// What to try.
#[derive(Debug, Clone)]
pub struct Trial {
    /// The mechanism's seed.
    pub seed: u64,
    /// Sortings one after another.
    pub sortings: u32,
    /// The colours of shafts 1-4.
    pub colours: [u8; 4],
    /// The longest a sorting may take (simulated).
    pub limit: Duration,
    /// Mechanism console faults at the start (`miss Sn5`).
    pub faults: Vec<String>,
    /// Actuators whose next command pulse is lost.
    pub lost_pulses: Vec<String>,
}

impl Default for Trial {
    fn default() -> Trial {
        Trial {
            seed: 1,
            sortings: 1,
            colours: [1, 2, 3, 4],
            limit: Duration::from_secs(300),
            faults: Vec::new(),
            lost_pulses: Vec::new(),
        }
    }
}

/// The trial's outcome.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrialReport {
    /// The mechanism's seed.
    pub seed: u64,
    /// The colours of shafts 1-4.
    pub colours: [u8; 4],
    /// Each sorting.
    pub sortings: Vec<SortingOutcome>,
    /// Every ball in its colour's shaft, every sorting finished, no supervisor event.
    pub passed: bool,
}

/// A student's files (name, text) compiled with the lab's interface.
pub fn compile(files: Vec<(String, String)>, main: Option<&str>) -> Result<Program, ProgramError> {
    crate::programs::sorting_program(files, main)
}

impl Trial {
    /// Runs `program` behind the built-in supervisor.
    pub fn run(&self, program: Program) -> Result<TrialReport, RigError> {
        let supervisor = crate::programs::supervisor().map_err(|e| RigError::Plc {
            plc: "supervisor",
            message: e.to_string(),
        })?;
        let settings = RigSettings {
            mechanism: SorterConfig {
                seed: self.seed,
                ..SorterConfig::default()
            },
            ..RigSettings::default()
        };
        let mut rig = Rig::new(program, supervisor, settings)?;
        for line in &self.faults {
            rig.plant_mut().console(line)?;
        }
        for actuator in &self.lost_pulses {
            rig.lose_next_pulse(actuator)?;
        }
        let mut sortings = Vec::new();
        for _ in 0..self.sortings.max(1) {
            sortings.push(rig.automatic_sorting(self.colours, self.limit)?);
        }
        let passed = sortings
            .iter()
            .all(|s| s.finished && s.events.is_empty() && right(s, self.colours) == s.shafts.len());
        Ok(TrialReport {
            seed: self.seed,
            colours: self.colours,
            sortings,
            passed,
        })
    }
}

fn colour_name(code: u8) -> &'static str {
    Colour::ALL
        .iter()
        .find(|c| c.code() == code)
        .map_or("none", |c| c.name())
}

/// The balls of `outcome` in the shaft of their colour.
pub fn right(outcome: &SortingOutcome, colours: [u8; 4]) -> usize {
    outcome
        .shafts
        .iter()
        .filter(|(ball, shaft)| {
            let shaft_colour = usize::from(*shaft)
                .checked_sub(1)
                .and_then(|k| colours.get(k))
                .copied();
            Colour::of_ball(ball).map(Colour::code) == shaft_colour
        })
        .count()
}

impl TrialReport {
    /// The report in words.
    pub fn text(&self) -> String {
        let report = self;
        let mut out = format!(
            "mechanism seed {}; shafts 1-4: {}\n",
            report.seed,
            report
                .colours
                .iter()
                .map(|c| colour_name(*c))
                .collect::<Vec<_>>()
                .join(", ")
        );
        for (n, sorting) in report.sortings.iter().enumerate() {
            out.push_str(&format!(
                "sorting {}: {} in {:.1} s (simulated); {} of {} balls in their colour's shaft\n",
                n + 1,
                if sorting.finished {
                    "finished"
                } else {
                    "NOT finished"
                },
                sorting.took.as_secs_f64(),
                right(sorting, report.colours),
                sorting.shafts.len()
            ));
            for (ball, shaft) in &sorting.shafts {
                let place = match shaft {
                    0 => "in no shaft".to_owned(),
                    k => format!(
                        "shaft {k} ({})",
                        colour_name(
                            report
                                .colours
                                .get(usize::from(*k) - 1)
                                .copied()
                                .unwrap_or(0)
                        )
                    ),
                };
                out.push_str(&format!("  {ball:<9} {place}\n"));
            }
            for event in &sorting.events {
                out.push_str(&format!(
                    "  {:>9.3} s  supervisor: {} {}: {}\n",
                    event.at.as_secs_f64(),
                    event.actuator,
                    match event.action {
                        SupervisorAction::Refused => "refused",
                        SupervisorAction::LockedOut => "locked out",
                    },
                    event.rule
                ));
            }
        }
        out.push_str(if report.passed {
            "PASSED\n"
        } else {
            "FAILED: a ball astray, a sorting unfinished or the supervisor stepped in\n"
        });
        out
    }
}
