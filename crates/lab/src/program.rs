//! A student's program: ST files compiled together, the one PROGRAM they hold (or the one
//! named), diagnostics rendered `file:line:col` as every other tool of the project does.

use std::path::{Path, PathBuf};

use plc::syntax::PouKind;
use plc::{Compiled, SourceMap};

/// A compiled student program, ready to run.
pub struct Program {
    /// The PROGRAM run.
    pub main: String,
    /// What was compiled.
    pub compiled: Compiled,
    /// The sources, for diagnostics.
    pub sources: SourceMap,
    /// The warnings, rendered.
    pub warnings: Vec<String>,
}

impl std::fmt::Debug for Program {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Program")
            .field("main", &self.main)
            .finish_non_exhaustive()
    }
}

/// Why a program cannot run.
#[derive(Debug, thiserror::Error)]
pub enum ProgramError {
    /// A file cannot be read or is not text.
    #[error("{0}")]
    Read(String),
    /// The compiler refused it: every diagnostic, rendered.
    #[error("{}", .0.join("\n"))]
    Compile(Vec<String>),
    /// No PROGRAM in the files.
    #[error("the files hold no PROGRAM")]
    NoProgram,
    /// Several PROGRAMs and no `--main`.
    #[error("the files hold several PROGRAMs ({}): name the one to run with --main", .0.join(", "))]
    SeveralPrograms(Vec<String>),
    /// `--main` names no PROGRAM of the files.
    #[error("no PROGRAM `{name}` in the files (they hold: {})", .programs.join(", "))]
    NoSuchProgram {
        /// The name given.
        name: String,
        /// The PROGRAMs there are.
        programs: Vec<String>,
    },
}

impl ProgramError {
    /// The first line of the error, for a table's cell.
    pub fn summary(&self) -> String {
        match self {
            ProgramError::Compile(diagnostics) => diagnostics
                .first()
                .and_then(|d| d.lines().next())
                .unwrap_or("does not compile")
                .to_owned(),
            other => other.to_string(),
        }
    }
}

/// Reads `files` (ST sources).
pub fn read_files(files: &[PathBuf]) -> Result<Vec<(String, String)>, ProgramError> {
    files
        .iter()
        .map(|file| {
            let bytes = std::fs::read(file).map_err(|error| {
                ProgramError::Read(format!("cannot read {}: {error}", file.display()))
            })?;
            let text = plc::syntax::decode(&bytes).map_err(|error| {
                ProgramError::Read(format!(
                    "{}:{}:{}: error: {error}",
                    file.display(),
                    error.line,
                    error.col
                ))
            })?;
            Ok((file.display().to_string(), text.to_owned()))
        })
        .collect()
}

/// The `.st` files of a folder (not its subfolders), sorted.
pub fn st_files(folder: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(folder)?
        .filter_map(Result::ok)
        .map(|entry| entry.path())
        .filter(|path| path.is_file() && is_st(path))
        .collect();
    files.sort();
    Ok(files)
}

/// Whether `path` names a Structured Text file.
pub fn is_st(path: &Path) -> bool {
    path.extension()
        .is_some_and(|extension| extension.eq_ignore_ascii_case("st"))
}

impl Program {
    /// Compiles `sources` (name, text) and picks the PROGRAM to run: `main`, or the only
    /// one there is.
    pub fn compile(
        sources: &[(String, String)],
        main: Option<&str>,
    ) -> Result<Program, ProgramError> {
        let (map, result) = plc::build(sources);
        let compiled = result.map_err(|diagnostics| {
            ProgramError::Compile(diagnostics.iter().map(|d| d.render(&map)).collect())
        })?;
        let programs: Vec<String> = compiled
            .checked
            .pous
            .iter()
            .filter(|pou| pou.kind == PouKind::Program && !pou.stdlib)
            .map(|pou| pou.name.clone())
            .collect();
        let main = match main {
            Some(name) => programs
                .iter()
                .find(|program| program.eq_ignore_ascii_case(name))
                .cloned()
                .ok_or_else(|| ProgramError::NoSuchProgram {
                    name: name.to_owned(),
                    programs: programs.clone(),
                })?,
            None => match programs.as_slice() {
                [] => return Err(ProgramError::NoProgram),
                [only] => only.clone(),
                several => return Err(ProgramError::SeveralPrograms(several.to_vec())),
            },
        };
        let warnings = compiled
            .checked
            .warnings
            .iter()
            .map(|w| w.render(&map))
            .collect();
        Ok(Program {
            main,
            compiled,
            sources: map,
            warnings,
        })
    }

    /// Reads and compiles `files`.
    pub fn load(files: &[PathBuf], main: Option<&str>) -> Result<Program, ProgramError> {
        Program::compile(&read_files(files)?, main)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn source(text: &str) -> Vec<(String, String)> {
        vec![("p.st".to_owned(), text.to_owned())]
    }

    #[test]
    fn the_only_program_or_the_named_one() {
        let one = source("PROGRAM Main VAR x : INT; END_VAR x := x + 1; END_PROGRAM");
        assert_eq!(Program::compile(&one, None).unwrap().main, "Main");
        let two = source(
            "PROGRAM A VAR x : INT; END_VAR x := 1; END_PROGRAM\nPROGRAM B VAR y : INT; END_VAR y := 1; END_PROGRAM",
        );
        let error = Program::compile(&two, None).unwrap_err();
        assert!(error.to_string().contains("A, B"), "{error}");
        assert_eq!(Program::compile(&two, Some("b")).unwrap().main, "B");
        assert!(matches!(
            Program::compile(&two, Some("C")),
            Err(ProgramError::NoSuchProgram { .. })
        ));
        let none = source("FUNCTION F : INT F := 1; END_FUNCTION");
        assert!(matches!(
            Program::compile(&none, None),
            Err(ProgramError::NoProgram)
        ));
    }

    #[test]
    fn compile_errors_are_rendered_with_file_line_col() {
        let bad = source("PROGRAM Main\nx := 1;\nEND_PROGRAM");
        let error = Program::compile(&bad, None).unwrap_err();
        assert!(
            error.summary().starts_with("p.st:2:"),
            "{}",
            error.summary()
        );
    }
}
