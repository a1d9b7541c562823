//! The lab's programs, built into the binary: the supervisor (the S7-200's protection,
//! loaded locally, never from a student), the interface between a sorting program and
//! the HMI (globals compiled with every sorting program) and the reference sorting
//! program. The files are `examples/sorting-lab/plc/`; students start from the last.

use lab::program::{Program, ProgramError};

/// `supervisor.st`: the blocks of section 5 and the supervisor's PROGRAM.
pub const SUPERVISOR: &str = include_str!("../../../examples/sorting-lab/plc/supervisor.st");

/// `sorter.st`: the reference sorting program of section 8.
pub const REFERENCE_SORTER: &str = include_str!("../../../examples/sorting-lab/plc/sorter.st");

/// `interface.st`: the globals between a sorting program and the HMI, compiled with
/// every sorting program.
pub const INTERFACE: &str = include_str!("../../../examples/sorting-lab/plc/interface.st");

/// The supervisor, compiled (its PROGRAM is `Supervisor`).
pub fn supervisor() -> Result<Program, ProgramError> {
    Program::compile(
        &[("supervisor.st".to_owned(), SUPERVISOR.to_owned())],
        Some("Supervisor"),
    )
}

/// The reference sorting program, compiled.
pub fn reference_sorter() -> Result<Program, ProgramError> {
    sorting_program(
        vec![("sorter.st".to_owned(), REFERENCE_SORTER.to_owned())],
        None,
    )
}

/// A sorting program's files (name, text) compiled with the lab's interface; its
/// PROGRAM is `main` or the only one.
pub fn sorting_program(
    mut files: Vec<(String, String)>,
    main: Option<&str>,
) -> Result<Program, ProgramError> {
    files.insert(0, ("interface.st".to_owned(), INTERFACE.to_owned()));
    Program::compile(&files, main)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_programs_compile_without_warnings() {
        let supervisor = supervisor().unwrap();
        assert_eq!(supervisor.main, "Supervisor");
        assert!(supervisor.warnings.is_empty(), "{:?}", supervisor.warnings);
        let sorter = reference_sorter().unwrap();
        assert_eq!(sorter.main, "Sorter");
        assert!(sorter.warnings.is_empty(), "{:?}", sorter.warnings);
    }
}
