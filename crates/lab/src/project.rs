//! A lab project: several models, each with a student's program, served together (a
//! teacher's bench of the lab's four models, or one student's solutions of all tasks).
//!
//! ```toml
//! [[model]]
//! model = "slide"                          # slide, crossroad, mixing, washing
//! program = ["slide.st"]                   # ST files, relative to the project file
//! main = "Slide"                           # optional: the PROGRAM when the files hold several
//! profile = "model"                        # optional: model, lab, lab-printed
//! scenario = "scenarios/slide.toml"        # optional: its lines and properties
//! options = { sensors = "2,4,7,9" }        # optional: the model's options
//! title = "Slide unit, the reference"      # optional: the index's text
//! ```

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::scenario::ScenarioError;

/// One model of a project.
#[derive(Debug, Clone, PartialEq)]
pub struct ProjectModel {
    /// What the index shows.
    pub title: String,
    /// The model.
    pub model: String,
    /// The program's files (resolved against the project's folder).
    pub program: Vec<PathBuf>,
    /// The PROGRAM to run.
    pub main: Option<String>,
    /// The address profile (text, parsed by the caller).
    pub profile: Option<String>,
    /// A scenario file (resolved).
    pub scenario: Option<PathBuf>,
    /// The model's options.
    pub options: Vec<(String, String)>,
}

/// A lab project file.
#[derive(Debug, Clone, PartialEq)]
pub struct LabProject {
    /// Its models, in the file's order.
    pub models: Vec<ProjectModel>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawProject {
    model: Vec<RawModel>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawModel {
    model: String,
    program: Vec<String>,
    main: Option<String>,
    profile: Option<String>,
    scenario: Option<String>,
    #[serde(default)]
    options: BTreeMap<String, toml::Value>,
    title: Option<String>,
}

impl LabProject {
    /// Reads the project file at `path`.
    pub fn load(path: &Path) -> Result<LabProject, ScenarioError> {
        let text = std::fs::read_to_string(path).map_err(|error| ScenarioError::Read {
            path: path.display().to_string(),
            error,
        })?;
        let folder = path.parent().unwrap_or(Path::new("."));
        LabProject::parse(&path.display().to_string(), folder, &text)
    }

    /// Parses a project's text; `source` names it in messages, `folder` resolves its
    /// files.
    pub fn parse(source: &str, folder: &Path, text: &str) -> Result<LabProject, ScenarioError> {
        let raw: RawProject = toml::from_str(text).map_err(|error| {
            let at = error.span().map_or_else(
                || source.to_owned(),
                |span| {
                    let before = text.get(..span.start).unwrap_or(text);
                    let line = before.matches('\n').count() + 1;
                    let column = before
                        .rsplit('\n')
                        .next()
                        .map_or(1, |l| l.chars().count() + 1);
                    format!("{source}:{line}:{column}")
                },
            );
            ScenarioError::Invalid(format!("{at}: {}", error.message()))
        })?;
        if raw.model.is_empty() {
            return Err(ScenarioError::Invalid(format!(
                "{source}: no [[model]] in the project"
            )));
        }
        let models = raw
            .model
            .into_iter()
            .enumerate()
            .map(|(n, model)| {
                if model.program.is_empty() {
                    return Err(ScenarioError::Invalid(format!(
                        "{source}: model {} (`{}`) names no program file",
                        n + 1,
                        model.model
                    )));
                }
                Ok(ProjectModel {
                    title: model.title.unwrap_or_else(|| {
                        format!("{}: {}", model.model, model.program.join(", "))
                    }),
                    program: model.program.iter().map(|file| folder.join(file)).collect(),
                    main: model.main,
                    profile: model.profile,
                    scenario: model.scenario.map(|file| folder.join(file)),
                    options: model
                        .options
                        .into_iter()
                        .map(|(key, value)| {
                            let text = match value {
                                toml::Value::String(text) => text,
                                other => other.to_string(),
                            };
                            (key, text)
                        })
                        .collect(),
                    model: model.model,
                })
            })
            .collect::<Result<_, _>>()?;
        Ok(LabProject { models })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_project_reads_back_with_its_files_resolved() {
        let text = "[[model]]\nmodel = \"slide\"\nprogram = [\"slide.st\"]\n\n[[model]]\nmodel = \"mixing\"\nprogram = [\"a.st\", \"b.st\"]\nprofile = \"lab\"\noptions = { program-err = true }\ntitle = \"Mixing\"\n";
        let project = LabProject::parse("lab.toml", Path::new("/x"), text).unwrap();
        assert_eq!(project.models.len(), 2);
        assert_eq!(project.models[0].title, "slide: slide.st");
        assert_eq!(
            project.models[1].program,
            vec![PathBuf::from("/x/a.st"), PathBuf::from("/x/b.st")]
        );
        assert_eq!(
            project.models[1].options,
            vec![("program-err".into(), "true".into())]
        );
        let error = LabProject::parse(
            "lab.toml",
            Path::new("/x"),
            "[[model]]\nmodel = \"slide\"\nprogramme = []\n",
        )
        .unwrap_err();
        assert!(error.to_string().starts_with("lab.toml:3:1:"), "{error}");
        assert!(LabProject::parse("lab.toml", Path::new("/x"), "").is_err());
    }
}
