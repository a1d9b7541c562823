//! The lab's two programs, built into the binary: the supervisor (the S7-200's
//! protection, loaded locally, never from a student) and the reference sorting program.
//! The files are `examples/sorting-lab/plc/`; students start from the second.

use lab::program::{Program, ProgramError};

/// `supervisor.st`: the blocks of section 5 and the supervisor's PROGRAM.
pub const SUPERVISOR: &str = include_str!("../../../examples/sorting-lab/plc/supervisor.st");

/// `sorter.st`: the reference sorting program of section 8.
pub const REFERENCE_SORTER: &str = include_str!("../../../examples/sorting-lab/plc/sorter.st");

/// The supervisor, compiled (its PROGRAM is `Supervisor`).
pub fn supervisor() -> Result<Program, ProgramError> {
    Program::compile(
        &[("supervisor.st".to_owned(), SUPERVISOR.to_owned())],
        Some("Supervisor"),
    )
}

/// The reference sorting program, compiled.
pub fn reference_sorter() -> Result<Program, ProgramError> {
    Program::compile(
        &[("sorter.st".to_owned(), REFERENCE_SORTER.to_owned())],
        None,
    )
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
