//! Where problems are: [`ConfigError`] owns the place of one problem (file, line, column,
//! key path) and its [`ConfigProblem`] (what is wrong, typed, in `problem`);
//! [`ConfigErrors`] owns all problems of one load, capped per file.
//!
//! `Display` of a [`ConfigError`] is `file:line:col: error: key: message`, the message
//! being the problem's own `Display`.

use super::*;

/// One problem in a project: where it is and what it is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConfigError {
    /// The file.
    pub file: PathBuf,
    /// 1-based line; 0 when the problem has no position.
    pub line: usize,
    /// 1-based column in characters; 0 when the problem has no position.
    pub column: usize,
    /// Key path such as `node[2].point[5].ioa`; empty for syntax errors.
    pub key: String,
    /// What is wrong.
    pub problem: ConfigProblem,
}

impl ConfigError {
    pub(in crate::config) fn unpositioned(file: &Path, problem: ConfigProblem) -> ConfigError {
        ConfigError {
            file: file.to_path_buf(),
            line: 0,
            column: 0,
            key: String::new(),
            problem,
        }
    }

    /// What is wrong, as text (the problem's `Display`): the message part of
    /// `file:line:col: error: key: message`.
    pub fn message(&self) -> String {
        self.problem.to_string()
    }
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if self.line > 0 {
            write!(f, ":{}:{}", self.line, self.column)?;
        }
        f.write_str(": error: ")?;
        if !self.key.is_empty() {
            write!(f, "{}: ", self.key)?;
        }
        write!(f, "{}", self.problem)?;
        #[cfg(feature = "runtime")]
        if let ConfigProblem::StDiagnostic { excerpt, .. } = &self.problem {
            if !excerpt.is_empty() {
                write!(f, "\n{excerpt}")?;
            }
        }
        Ok(())
    }
}

impl std::error::Error for ConfigError {}

/// A UTF-8 byte-order mark (Windows editors write one); accepted at the start of an ST
/// source, as the PLC compiler accepts it.
pub(in crate::config) const BYTE_ORDER_MARK: &[u8] = b"\xEF\xBB\xBF";

/// The problem with a file that is not UTF-8, at its first invalid byte (line and column
/// in characters, as an editor shows them; after a byte-order mark). The PLC crate has
/// the same rule (`plc::syntax::decode`), but the loader also builds without it.
pub(in crate::config) fn not_utf8(file: &Path, bytes: &[u8]) -> ConfigError {
    let body = bytes.strip_prefix(BYTE_ORDER_MARK).unwrap_or(bytes);
    let valid = std::str::from_utf8(body)
        .err()
        .map_or(body.len(), |e| e.valid_up_to());
    let before = std::str::from_utf8(body.get(..valid).unwrap_or_default()).unwrap_or("");
    let (line, column) = line_col(before, before.len());
    let byte = body.get(valid).copied().unwrap_or(0);
    ConfigError {
        file: file.to_path_buf(),
        line,
        column,
        key: String::new(),
        problem: ConfigProblem::NotUtf8 { byte },
    }
}

/// Problems kept per file; later ones are only counted ([`ConfigErrors::omitted`]): past
/// the first few, a list of problems buries the ones that matter.
pub const MAX_ERRORS_PER_FILE: usize = 10;

/// All problems found in a project (at least one), in the order found: at most
/// [`MAX_ERRORS_PER_FILE`] per file, the rest counted.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub struct ConfigErrors {
    pub(in crate::config) errors: Vec<ConfigError>,
    pub(in crate::config) omitted: Vec<(PathBuf, usize)>,
}

impl ConfigErrors {
    pub(in crate::config) fn single(error: ConfigError) -> ConfigErrors {
        ConfigErrors {
            errors: vec![error],
            omitted: Vec::new(),
        }
    }

    /// The problems kept.
    pub fn errors(&self) -> &[ConfigError] {
        &self.errors
    }

    /// The problems kept, by value.
    pub fn into_errors(self) -> Vec<ConfigError> {
        self.errors
    }

    /// Per file, how many problems were found beyond the [`MAX_ERRORS_PER_FILE`] kept.
    pub fn omitted(&self) -> &[(PathBuf, usize)] {
        &self.omitted
    }

    /// Every problem found, kept or omitted.
    pub fn total(&self) -> usize {
        self.errors.len() + self.omitted.iter().map(|(_, n)| n).sum::<usize>()
    }
}

impl fmt::Display for ConfigErrors {
    /// One problem per line, then `file: ... and N more error(s)` per file with more.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, error) in self.errors.iter().enumerate() {
            if i > 0 {
                f.write_str("\n")?;
            }
            write!(f, "{error}")?;
        }
        for (file, count) in &self.omitted {
            write!(f, "\n{}: ... and {count} more error(s)", file.display())?;
        }
        Ok(())
    }
}
