//! Syntax: source files, lexer, parser and the AST.

pub mod ast;
pub mod lexer;
pub mod parser;
pub mod source;

pub use ast::*;
pub use source::{decode, FileId, LineCol, NotUtf8, SourceFile, SourceMap, Span};

use crate::diagnostics::Diagnostic;

/// Parses every file of `sources` into one compilation unit.
pub fn parse(sources: &SourceMap) -> (CompilationUnit, Vec<Diagnostic>) {
    let mut unit = CompilationUnit::default();
    let mut diags = Vec::new();
    for (id, file) in sources.files() {
        parser::parse_into(id, &file.text, &mut unit, &mut diags);
    }
    (unit, diags)
}
