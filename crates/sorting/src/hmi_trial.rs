//! The sorting lab's program trial for the web HMI (hmi.toml `[program] trial =
//! "sorting"`, feature `hmi`): [`trial`](crate::trial) behind the HMI's
//! [`ProgramTrial`]; with the station in the same process and `[program] node`, also the
//! lab itself: the student's program loaded into that node's PLC, behind the supervisor
//! (`station::runtime::program`), and the lab's own program put back.
//!
//! One implementation for the `stanice` binary and the HMI's browser test, so that the
//! test drives what users run.

use std::path::Path;
use std::sync::Arc;

use hmi::trial::{CheckReport, ProgramTrial, SourceFile, TrialFuture, NOT_LIVE};
use station::runtime::program::{ProgramDownload, ProgramLoader};

use crate::trial::{compile, Trial};

/// The lab's interface to the HMI, compiled with every sorting program; the project's
/// copy stays in the node when a student's program is loaded.
pub const INTERFACE_FILE: &str = "interface.st";

/// The sorting lab's trial.
#[derive(Debug)]
pub struct SortingTrial {
    live: Option<LiveLab>,
}

/// Where a student's program runs on the lab itself.
#[derive(Debug, Clone)]
struct LiveLab {
    loader: ProgramLoader,
    node: String,
    task: String,
}

/// Why the trial a screens folder names cannot be offered.
#[derive(Debug, thiserror::Error)]
pub enum TrialSetupError {
    /// hmi.toml could not be read.
    #[error("{0}")]
    Config(#[from] hmi::HmiError),
    /// `[program] trial` names no trial this application offers.
    #[error("{file}: [program] trial {trial:?}: the trials are: sorting")]
    UnknownTrial {
        /// hmi.toml.
        file: String,
        /// The name given.
        trial: String,
    },
    /// `[program] node` names no node of the project.
    #[error("{file}: [program] node {node:?}: the project has no such node")]
    UnknownNode {
        /// hmi.toml.
        file: String,
        /// The name given.
        node: String,
    },
}

impl SortingTrial {
    /// The trial on a simulation only.
    pub fn simulated() -> SortingTrial {
        SortingTrial { live: None }
    }

    /// The trial that also loads programs into `node`'s task `task` through `loader`.
    pub fn live(loader: ProgramLoader, node: &str, task: &str) -> SortingTrial {
        SortingTrial {
            live: Some(LiveLab {
                loader,
                node: node.to_owned(),
                task: task.to_owned(),
            }),
        }
    }
}

fn pairs(files: &[SourceFile]) -> Vec<(String, String)> {
    files
        .iter()
        .map(|f| (f.name.clone(), f.text.clone()))
        .collect()
}

impl ProgramTrial for SortingTrial {
    fn check(&self, files: &[SourceFile]) -> CheckReport {
        match compile(pairs(files), None) {
            Ok(program) => CheckReport {
                ok: true,
                diagnostics: program.warnings.clone(),
                main: Some(program.main),
            },
            Err(lab::program::ProgramError::Compile(diagnostics)) => CheckReport {
                ok: false,
                diagnostics,
                main: None,
            },
            Err(other) => CheckReport {
                ok: false,
                diagnostics: vec![other.to_string()],
                main: None,
            },
        }
    }

    fn run(&self, files: &[SourceFile], seed: u64) -> Result<serde_json::Value, String> {
        let program = compile(pairs(files), None).map_err(|e| e.to_string())?;
        let report = Trial {
            seed,
            ..Trial::default()
        }
        .run(program)
        .map_err(|e| e.to_string())?;
        let mut json = serde_json::to_value(&report).map_err(|e| e.to_string())?;
        if let Some(object) = json.as_object_mut() {
            object.insert("text".into(), serde_json::Value::String(report.text()));
        }
        Ok(json)
    }

    fn live(&self) -> bool {
        self.live.is_some()
    }

    fn load(&self, files: Vec<SourceFile>, user: String) -> TrialFuture {
        let Some(live) = self.live.clone() else {
            return Box::pin(async { Err(NOT_LIVE.to_owned()) });
        };
        Box::pin(async move {
            let files = pairs(&files);
            let compiled = files.clone();
            // The PROGRAM the task is to run, as the trial finds it (the only one).
            let main = tokio::task::spawn_blocking(move || {
                compile(compiled, None).map(|program| program.main)
            })
            .await
            .map_err(|e| e.to_string())?
            .map_err(|e| e.to_string())?;
            let loaded = live
                .loader
                .download(
                    &live.node,
                    ProgramDownload {
                        files,
                        keep: vec![INTERFACE_FILE.to_owned()],
                        tasks: vec![(live.task.clone(), vec![main.clone()])],
                        by: user,
                    },
                )
                .await
                .map_err(|e| e.to_string())?;
            Ok(serde_json::json!({
                "node": loaded.node,
                "main": main,
                "files": loaded.files,
                "text": format!(
                    "PROGRAM {main} runs on the lab ({}, task {}) behind the supervisor: \
                     sort from the mimic; refusals and lock-outs appear among the events. \
                     \"Restore the lab's program\" puts the reference program back.",
                    live.node, live.task
                ),
            }))
        })
    }

    fn restore(&self, user: String) -> TrialFuture {
        let Some(live) = self.live.clone() else {
            return Box::pin(async { Err(NOT_LIVE.to_owned()) });
        };
        Box::pin(async move {
            let loaded = live
                .loader
                .restore(&live.node, &user)
                .await
                .map_err(|e| e.to_string())?;
            Ok(serde_json::json!({
                "node": loaded.node,
                "files": loaded.files,
                "text": format!("The lab's own program runs on {} again.", loaded.node),
            }))
        })
    }
}

/// The program trial a screens folder's `[program]` names, if it has one; with `loader`
/// (the station runs in this process) and `[program] node`, one that loads programs into
/// that node too.
pub fn trial_for(
    screens: &Path,
    loader: Option<ProgramLoader>,
) -> Result<Option<Arc<dyn ProgramTrial>>, TrialSetupError> {
    let config = hmi::config::HmiConfig::load(screens)?;
    let Some(program) = config.program.as_ref() else {
        return Ok(None);
    };
    let file = screens.join("hmi.toml").display().to_string();
    if program.trial != "sorting" {
        return Err(TrialSetupError::UnknownTrial {
            file,
            trial: program.trial.clone(),
        });
    }
    let trial = match (loader, &program.node) {
        (Some(loader), Some(node)) => {
            if loader.project().node(node).is_none() {
                return Err(TrialSetupError::UnknownNode {
                    file,
                    node: node.clone(),
                });
            }
            SortingTrial::live(loader, node, &program.task)
        }
        _ => SortingTrial::simulated(),
    };
    Ok(Some(Arc::new(trial)))
}
