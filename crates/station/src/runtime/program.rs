//! Loading a program into a running node's soft PLC, as an engineering tool downloads one
//! to a PLC in the field: a remote lab's student runs a program on the lab itself (the
//! sorting lab's SORTER node, behind its supervisor), and puts the lab's own back after.
//!
//! ```text
//!  ProgramLoader::download(node, ProgramDownload { files, keep, tasks })
//!     -> the node's config with the tasks' programs replaced
//!     -> simulation thread: compile + bind the new PLC (errors: the old one runs on)
//!                           stop the old PLC (outputs safe, the stop recorded)
//!                           swap; cold start at the next step; `plc-program` event
//!  ProgramLoader::restore(node) -> the same with the project's own files and tasks
//! ```
//!
//! The download is a cold start: the new program's variables start from their initial
//! values, `[node.set]` and the node's tables are applied again, retained values are not
//! carried over (a program of another shape has no place for them). The node's points,
//! commands and I/O bindings stay as the project declares them, so a program must have
//! the variables they name; one that does not is refused with the binding that failed.

use std::sync::{mpsc, Arc};

use tokio::sync::oneshot;

use super::simulation::{SimRequest, Simulation};
use super::RuntimeError;
use crate::config::Project;

/// A new program for a running node.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ProgramDownload {
    /// The new files (name, text).
    pub files: Vec<(String, String)>,
    /// The project's source files of the node that stay (by file name, `interface.st`),
    /// compiled before the new files.
    pub keep: Vec<String>,
    /// Tasks whose programs change: (task, its PROGRAMs in order). The other tasks run
    /// what the project says.
    pub tasks: Vec<(String, Vec<String>)>,
    /// Who loads it, for the record.
    pub by: String,
}

/// What was loaded.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProgramLoaded {
    /// The node.
    pub node: String,
    /// The files compiled, in order.
    pub files: Vec<String>,
    /// Each task with its programs.
    pub tasks: Vec<(String, Vec<String>)>,
}

/// Loads programs into the running nodes, from any task or thread (`Clone`, `Send`).
#[derive(Clone)]
pub struct ProgramLoader {
    project: Arc<Project>,
    simulation: mpsc::Sender<SimRequest>,
}

impl std::fmt::Debug for ProgramLoader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ProgramLoader")
            .field("station", &self.project.station.name)
            .finish_non_exhaustive()
    }
}

impl ProgramLoader {
    pub(crate) fn new(project: Project, simulation: mpsc::Sender<SimRequest>) -> ProgramLoader {
        ProgramLoader {
            project: Arc::new(project),
            simulation,
        }
    }

    /// The project whose nodes it loads.
    pub fn project(&self) -> &Project {
        &self.project
    }

    /// Loads `download` into `node` (see the module's description). A program that does
    /// not compile is [`RuntimeError::Plc`] with its diagnostics `file:line:col`; one
    /// that lacks what the project binds, [`RuntimeError::Setup`]; either way the node
    /// runs on as it did.
    pub async fn download(
        &self,
        node: &str,
        download: ProgramDownload,
    ) -> Result<ProgramLoaded, RuntimeError> {
        let mut config = self
            .project
            .node(node)
            .cloned()
            .ok_or_else(|| RuntimeError::Setup(format!("no node `{node}` in the project")))?;
        if download.files.is_empty() {
            return Err(RuntimeError::Setup("no files to load".to_owned()));
        }
        for (task, programs) in &download.tasks {
            let Some(found) = config.tasks.iter_mut().find(|t| &t.name == task) else {
                return Err(RuntimeError::Setup(format!(
                    "node `{node}` has no task `{task}`"
                )));
            };
            found.programs.clone_from(programs);
        }
        let mut files = Vec::new();
        for keep in &download.keep {
            let path = config
                .sources
                .iter()
                .find(|path| path.file_name().is_some_and(|name| name == keep.as_str()))
                .ok_or_else(|| {
                    RuntimeError::Setup(format!("node `{node}` has no source file `{keep}`"))
                })?;
            let text = std::fs::read_to_string(path).map_err(|error| {
                RuntimeError::Setup(format!("cannot read {}: {error}", path.display()))
            })?;
            files.push((path.display().to_string(), text));
        }
        files.extend(download.files.iter().cloned());
        let names: Vec<String> = files.iter().map(|(name, _)| name.clone()).collect();
        let tasks: Vec<(String, Vec<String>)> = config
            .tasks
            .iter()
            .map(|task| (task.name.clone(), task.programs.clone()))
            .collect();
        let description = format!(
            "loaded by {}: {}; {}",
            download.by,
            names.join(", "),
            describe_tasks(&tasks)
        );
        self.load(config, files, description).await?;
        Ok(ProgramLoaded {
            node: node.to_owned(),
            files: names,
            tasks,
        })
    }

    /// Loads the project's own program into `node` again (after a student's).
    pub async fn restore(&self, node: &str, by: &str) -> Result<ProgramLoaded, RuntimeError> {
        let config = self
            .project
            .node(node)
            .cloned()
            .ok_or_else(|| RuntimeError::Setup(format!("no node `{node}` in the project")))?;
        let names: Vec<String> = config
            .sources
            .iter()
            .map(|path| path.display().to_string())
            .collect();
        let tasks: Vec<(String, Vec<String>)> = config
            .tasks
            .iter()
            .map(|task| (task.name.clone(), task.programs.clone()))
            .collect();
        let description = format!(
            "the project's program restored by {by}: {}; {}",
            names.join(", "),
            describe_tasks(&tasks)
        );
        // No files: the simulation reads the project's.
        self.load(config, Vec::new(), description).await?;
        Ok(ProgramLoaded {
            node: node.to_owned(),
            files: names,
            tasks,
        })
    }

    async fn load(
        &self,
        config: crate::config::NodeConfig,
        files: Vec<(String, String)>,
        description: String,
    ) -> Result<(), RuntimeError> {
        let (reply, answer) = oneshot::channel();
        self.simulation
            .send(SimRequest::With(Box::new(move |sim: &mut Simulation| {
                let _ = reply.send(sim.load_program(&config, files, description));
            })))
            .map_err(|_| RuntimeError::Stopped)?;
        answer.await.map_err(|_| RuntimeError::Stopped)?
    }
}

/// `task main: Sorter` for the record.
fn describe_tasks(tasks: &[(String, Vec<String>)]) -> String {
    tasks
        .iter()
        .map(|(task, programs)| format!("task {task}: {}", programs.join(", ")))
        .collect::<Vec<_>>()
        .join("; ")
}
