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
    /// A local variable that is never used (warning).
    UnusedVariable,
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
            Code::UnusedVariable => "W0001",
        }
    }
}

impl Code {
    /// What the error means and how to fix it (the per-code documentation page).
    pub fn explanation(self) -> &'static str {
        match self {
            Code::UnexpectedCharacter => "A character that cannot start any token of Structured Text, e.g. `@` or `?` outside a string or comment.",
            Code::Unterminated => "A comment `(* ... *)`, `/* ... */`, a pragma `{ ... }` or a string literal is not closed before the end of the line or file.",
            Code::BadLiteral => "A literal is malformed or does not fit its type: `T#5x` (unknown unit), `16#G1`, `SINT#300`, `D#2024-13-01`.",
            Code::Syntax => "The parser expected a different token. The message names what was expected and what was found; the position is where the parser gave up.",
            Code::Undeclared => "A variable, function, type, task or program name that is declared nowhere in scope. Names are case-insensitive; globals need VAR_GLOBAL (and may be named in VAR_EXTERNAL).",
            Code::Duplicate => "The same name is declared twice in one scope (variables of a POU, fields of a struct, POUs and types of the project).",
            Code::UnknownType => "A type name that is neither elementary, a TYPE declaration, nor a function block.",
            Code::TypeMismatch => "Operand or value types do not fit. IEC 61131-3 converts implicitly only to wider types (INT -> DINT -> LINT, INT -> REAL, REAL -> LREAL, ...); narrowing needs an explicit conversion such as DINT_TO_INT.",
            Code::WrongArguments => "A call has the wrong number, names or kinds of arguments: an unknown parameter name, `:=` on an output, `=>` on an input, too many positional arguments, a missing VAR_IN_OUT, or a function-block call used as an expression.",
            Code::NotAssignable => "The target of an assignment (or an output / in-out binding) is not a variable: a constant, an expression, an enumeration value, a program name, or an in-out member of another instance.",
            Code::NotConstant => "A constant is required: array bounds, string lengths, enumeration values, CASE labels, task INTERVAL/PRIORITY.",
            Code::Recursion => "A function calls itself directly or indirectly, or a function block contains an instance of itself. IEC 61131-3 forbids recursion; each function has one static frame.",
            Code::Unsupported => "A construct this compiler does not support yet (pointers, string indexing).",
            Code::UnusedVariable => "A VAR/VAR_TEMP variable of a POU is never read or written. Remove it, or start its name with `_` to keep it deliberately.",
            Code::RuntimeFault => "The task was stopped at run time: integer division by zero, array index out of range, or the per-cycle loop budget was exhausted (endless loop), or the watchdog tripped.",
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
