//! Diagnostics: a code, a severity, a primary label, secondary labels and notes.
//!
//! Rendered as `file:line:col: error[E0102]: message` followed by indented labels and notes.

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

/// Every diagnostic the compiler and runtime emit has one code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Code {
    /// A character that starts no token.
    UnexpectedCharacter,
    /// A comment or string that never ends.
    Unterminated,
    /// A malformed literal (number, time, date).
    BadLiteral,
    /// The parser expected something else.
    Syntax,
    /// A name that is declared nowhere in scope.
    Undeclared,
    /// A name declared twice in one scope.
    Duplicate,
    /// A type name that is not known.
    UnknownType,
    /// Operand or value types that do not fit.
    TypeMismatch,
    /// Wrong number, names or kinds of call arguments.
    WrongArguments,
    /// Assignment to something that is not a variable, or to a constant or input.
    NotAssignable,
    /// A constant expression was required.
    NotConstant,
    /// A POU calls itself, directly or indirectly (IEC 61131-3 forbids recursion).
    Recursion,
    /// A construct that is not supported yet.
    Unsupported,
    /// A run-time fault: division by zero, array bounds, watchdog.
    RuntimeFault,
}

impl Code {
    /// The stable code string, e.g. `E0201`.
    pub fn as_str(self) -> &'static str {
        match self {
            Code::UnexpectedCharacter => "E0001",
            Code::Unterminated => "E0002",
            Code::BadLiteral => "E0003",
            Code::Syntax => "E0004",
            Code::Undeclared => "E0101",
            Code::Duplicate => "E0102",
            Code::UnknownType => "E0103",
            Code::TypeMismatch => "E0201",
            Code::WrongArguments => "E0202",
            Code::NotAssignable => "E0203",
            Code::NotConstant => "E0204",
            Code::Recursion => "E0205",
            Code::Unsupported => "E0301",
            Code::RuntimeFault => "E0401",
        }
    }
}

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

    /// The full rendering: headline, `[code]`, labels, notes, one per line.
    pub fn render(&self, sources: &SourceMap) -> String {
        let mut out = format!("{} [{}]", self.headline(sources), self.code.as_str());
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
        out
    }
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
