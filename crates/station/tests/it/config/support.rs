//! Helpers of the config tests: a project folder in a temp dir, loading it, asserting an
//! error's `line:col`, key and message; the PLC source and the two-node project the topics
//! build on.

use station::config::{ConfigError, Project};

/// A project folder with `station.toml` = `toml` and the extra `files`.
pub(crate) fn folder(toml: &str, files: &[(&str, &str)]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("station.toml"), toml).unwrap();
    for (path, text) in files {
        let path = dir.path().join(path);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }
    dir
}

pub(crate) fn load(toml: &str, files: &[(&str, &str)]) -> Result<Project, Vec<ConfigError>> {
    let dir = folder(toml, files);
    Project::load(dir.path()).map_err(|e| e.into_errors())
}

pub(crate) fn errors(toml: &str, files: &[(&str, &str)]) -> Vec<ConfigError> {
    match load(toml, files) {
        Ok(_) => panic!("the project loaded:\n{toml}"),
        Err(errors) => errors,
    }
}

/// Asserts that an error at `line:col` with `key` and a message containing `message` is
/// among the errors.
#[track_caller]
pub(crate) fn expect(errors: &[ConfigError], line: usize, column: usize, key: &str, message: &str) {
    let listing: Vec<String> = errors.iter().map(|e| e.to_string()).collect();
    assert!(
        errors.iter().any(|e| e.line == line
            && e.column == column
            && e.key == key
            && e.message().contains(message)),
        "no error {line}:{column}: {key}: ...{message}... in\n{}",
        listing.join("\n")
    );
}

#[track_caller]
pub(crate) fn expect_only(
    toml: &str,
    files: &[(&str, &str)],
    line: usize,
    column: usize,
    key: &str,
    message: &str,
) {
    let errors = errors(toml, files);
    expect(&errors, line, column, key, message);
    assert_eq!(errors.len(), 1, "{errors:#?}");
}

pub(crate) const PLC: (&str, &str) = (
    "plc/main.st",
    "PROGRAM Main\nVAR_INPUT A : BOOL; END_VAR\nVAR X : REAL; END_VAR\nEND_PROGRAM\n",
);

pub(crate) const TWO_NODES: &str = r#"[station]
name = "X"
time_zone = "UTC"
[[node]]
name = "Low"
common_address = 2
[node.server]
port_offset = 1
[[node.point]]
name = "P"
type = "M_SP_NA_1"
ioa = 10
source = "M.P"
[[node.command]]
name = "C"
type = "C_SC_NA_1"
ioa = 20
target = "M.C"
[[node]]
name = "Top"
common_address = 1
"#;
