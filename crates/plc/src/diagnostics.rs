//! Diagnostics: a code, a severity, a primary label, secondary labels and notes.
//!
//! Rendered as `file:line:col: error: message`, the source line with carets under the
//! span, then indented labels, notes and `= code: E0102`. Every [`Code`] has a page
//! (`docs/diagnostics/CODE.md`, [`Code::page`]) shown by `stanice plc explain CODE`.

use crate::syntax::{SourceMap, Span};
use std::fmt;

/// How bad a diagnostic is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Severity {
    /// Informational.
    Note,
    /// The program still compiles.
    Warning,
    /// The program does not compile.
    Error,
}

impl fmt::Display for Severity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Severity::Note => "note",
            Severity::Warning => "warning",
            Severity::Error => "error",
        })
    }
}

/// Declares [`Code`] from one table, so that the enum, [`Code::ALL`], the code strings
/// and the documentation pages (`docs/diagnostics/CODE.md`, embedded) cannot drift: a
/// code without a page does not compile.
macro_rules! codes {
    ($( $(#[$doc:meta])* $name:ident = $code:literal, )*) => {
        /// Every diagnostic the compiler and runtime emit has one code.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        #[non_exhaustive]
        pub enum Code {
            $( $(#[$doc])* $name, )*
        }

        impl Code {
            /// Every code, in the order of the table (by number).
            pub const ALL: &'static [Code] = &[$(Code::$name),*];

            /// The stable code string, e.g. `E0201`.
            pub fn as_str(self) -> &'static str {
                match self {
                    $(Code::$name => $code,)*
                }
            }

            /// The name of the variant, e.g. `TypeMismatch`.
            pub fn name(self) -> &'static str {
                match self {
                    $(Code::$name => stringify!($name),)*
                }
            }

            /// The documentation page (Markdown): what the diagnostic means, a wrong
            /// example and its fix. Shown by `stanice plc explain CODE`.
            pub fn page(self) -> &'static str {
                match self {
                    $(Code::$name => include_str!(concat!("../docs/diagnostics/", $code, ".md")),)*
                }
            }
        }
    };
}

codes! {
    /// A character that starts no token.
    UnexpectedCharacter = "E0001",
    /// A comment or string that never ends.
    Unterminated = "E0002",
    /// A malformed literal (number, time, date).
    BadLiteral = "E0003",
    /// The parser expected something else.
    Syntax = "E0004",
    /// A name that is declared nowhere in scope.
    Undeclared = "E0101",
    /// A name declared twice in one scope.
    Duplicate = "E0102",
    /// A type name that is not known.
    UnknownType = "E0103",
    /// Operand or value types that do not fit.
    TypeMismatch = "E0201",
    /// Wrong number, names or kinds of call arguments.
    WrongArguments = "E0202",
    /// Assignment to something that is not a variable, or to a constant or input.
    NotAssignable = "E0203",
    /// A constant expression was required.
    NotConstant = "E0204",
    /// A POU calls itself, directly or indirectly (IEC 61131-3 forbids recursion).
    Recursion = "E0205",
    /// A construct that is not supported yet.
    Unsupported = "E0301",
    /// A run-time fault: division by zero, array bounds, NULL dereference, watchdog.
    RuntimeFault = "E0401",
    /// A local variable that is never used (warning).
    UnusedVariable = "W0001",
}

impl Code {
    /// What the diagnostic means: the first paragraph of its [page](Code::page).
    pub fn explanation(self) -> &'static str {
        self.page()
            .split("\n\n")
            .map(str::trim)
            .find(|p| !p.is_empty() && !p.starts_with('#'))
            .unwrap_or("")
    }

    /// The code for `text`: the code string as diagnostics print it (`E0201`) or the
    /// variant name (`TypeMismatch`), in any case.
    pub fn parse(text: &str) -> Result<Code, UnknownCode> {
        let t = text.trim();
        Code::ALL
            .iter()
            .copied()
            .find(|c| c.as_str().eq_ignore_ascii_case(t) || c.name().eq_ignore_ascii_case(t))
            .ok_or_else(|| UnknownCode(text.to_string()))
    }
}

impl fmt::Display for Code {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for Code {
    type Err = UnknownCode;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Code::parse(s)
    }
}

/// A text that names no [`Code`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("no diagnostic code '{0}'")]
pub struct UnknownCode(pub String);

/// A labelled span.
#[derive(Debug, Clone, PartialEq)]
pub struct Label {
    /// Where.
    pub span: Span,
    /// What about it.
    pub message: String,
}

/// One diagnostic.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnostic {
    /// Code.
    pub code: Code,
    /// Severity.
    pub severity: Severity,
    /// Headline.
    pub message: String,
    /// Main location.
    pub primary: Span,
    /// Other relevant places.
    pub secondary: Vec<Label>,
    /// Free-form notes.
    pub notes: Vec<String>,
}

impl Diagnostic {
    /// An error at `span`.
    pub fn error(code: Code, span: Span, message: impl Into<String>) -> Self {
        Diagnostic {
            code,
            severity: Severity::Error,
            message: message.into(),
            primary: span,
            secondary: Vec::new(),
            notes: Vec::new(),
        }
    }

    /// A warning at `span`.
    pub fn warning(code: Code, span: Span, message: impl Into<String>) -> Self {
        Diagnostic {
            severity: Severity::Warning,
            ..Diagnostic::error(code, span, message)
        }
    }

    /// Adds a secondary label.
    #[must_use]
    pub fn with_label(mut self, span: Span, message: impl Into<String>) -> Self {
        self.secondary.push(Label {
            span,
            message: message.into(),
        });
        self
    }

    /// Adds a note.
    #[must_use]
    pub fn with_note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(note.into());
        self
    }

    /// Whether this is an error.
    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }

    /// The first line: `file:line:col: error: message`.
    pub fn headline(&self, sources: &SourceMap) -> String {
        format!(
            "{}: {}: {}",
            sources.location(self.primary),
            self.severity,
            self.message
        )
    }

    /// The full rendering: the headline `file:line:col: error: message`, then secondary
    /// labels, notes and the error code on indented lines.
    pub fn render(&self, sources: &SourceMap) -> String {
        let mut out = self.headline(sources);
        out.push_str(&snippet(sources, self.primary));
        for label in &self.secondary {
            out.push_str(&format!(
                "\n  {}: {}",
                sources.location(label.span),
                label.message
            ));
        }
        for note in &self.notes {
            out.push_str(&format!("\n  = note: {note}"));
        }
        out.push_str(&format!("\n  = code: {}", self.code.as_str()));
        out
    }
}

/// The source line of `span` with carets under the spanned characters (first line only).
fn snippet(sources: &SourceMap, span: Span) -> String {
    let Some(file) = sources.file(span.file) else {
        return String::new();
    };
    let lc = sources.line_col(span);
    if lc.line == 0 {
        return String::new();
    }
    let Some(line) = file.text.lines().nth(lc.line - 1) else {
        return String::new();
    };
    let line = line.trim_end_matches('\r');
    let start = lc.col.saturating_sub(1);
    let width = sources
        .snippet(span)
        .lines()
        .next()
        .map(|s| s.chars().count())
        .unwrap_or(1)
        .clamp(1, line.chars().count().saturating_sub(start).max(1));
    let number = lc.line.to_string();
    let pad = " ".repeat(number.len());
    let prefix: String = line
        .chars()
        .take(start)
        .map(|c| if c == '\t' { '\t' } else { ' ' })
        .collect();
    format!(
        "\n{pad} |\n{number} | {line}\n{pad} | {prefix}{}",
        "^".repeat(width)
    )
}

/// A list of diagnostics gathered by one stage.
#[derive(Debug, Clone, Default)]
pub struct Diagnostics(pub Vec<Diagnostic>);

impl Diagnostics {
    /// Appends one.
    pub fn push(&mut self, d: Diagnostic) {
        self.0.push(d);
    }
    /// Whether any is an error.
    pub fn has_errors(&self) -> bool {
        self.0.iter().any(Diagnostic::is_error)
    }
    /// Renders all, one per line group.
    pub fn render(&self, sources: &SourceMap) -> String {
        self.0
            .iter()
            .map(|d| d.render(sources))
            .collect::<Vec<_>>()
            .join("\n")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_code_has_a_page_with_its_sections() {
        for code in Code::ALL {
            let page = code.page();
            let title = format!("# {}: ", code.as_str());
            assert!(
                page.starts_with(&title),
                "{code}: page starts with '{title}'"
            );
            assert!(page.contains(&format!("({})", code.name())), "{code}");
            for section in ["## Example of the mistake", "## How to fix it"] {
                assert!(page.contains(section), "{code}: no '{section}'");
            }
            assert!(!code.explanation().is_empty(), "{code}");
            assert_eq!(Code::parse(code.as_str()).ok(), Some(*code));
            assert_eq!(Code::parse(&code.as_str().to_lowercase()).ok(), Some(*code));
            assert_eq!(Code::parse(&code.name().to_uppercase()).ok(), Some(*code));
        }
        assert!(Code::parse("E9999").is_err());
    }

    #[test]
    fn every_page_in_the_folder_belongs_to_a_code() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/diagnostics");
        let mut files = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let name = entry.unwrap().file_name().into_string().unwrap();
            let stem = name.strip_suffix(".md").unwrap();
            let code = Code::parse(stem).unwrap();
            assert_eq!(code.as_str(), stem, "{name}: spelled as the code prints");
            files += 1;
        }
        assert_eq!(files, Code::ALL.len());
    }

    #[test]
    fn codes_are_unique_and_in_order() {
        let codes: Vec<&str> = Code::ALL.iter().map(|c| c.as_str()).collect();
        let mut sorted = codes.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(codes, sorted);
    }
}
