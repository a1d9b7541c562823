//! Recursive-descent parser with error recovery. Never panics; nesting deeper than
//! [`MAX_DEPTH`] is a diagnostic, not a stack overflow.
//!
//! This file holds the entry points, the `Parser` state and its token cursor (look-ahead,
//! keywords and punctuation, errors, recovery between items, the nesting guard); the
//! grammar is in three parts:
//!
//! - `declarations.rs`: items (POUs, types, globals, configurations, resources), variable
//!   blocks and declarations, initial values, type references;
//! - `statements.rs`: statement lists and every statement;
//! - `expressions.rs`: operators, postfix chains, call arguments and primaries.

use super::ast::*;
use super::lexer::{lex, Tok, Token};
use super::source::{FileId, Span};
use crate::diagnostics::{Code, Diagnostic};

mod declarations;
mod expressions;
mod statements;

/// Maximum nesting of expressions and statements.
pub const MAX_DEPTH: u32 = 64;

/// Maximum depth of an expression tree (nesting plus left-associative operator, member
/// and index chains), so that later recursive stages cannot overflow the stack.
pub const MAX_TREE: u32 = 400;

/// Parses one file, appending nodes to `unit` (node ids continue from `unit.node_count`).
pub fn parse_into(
    file: FileId,
    text: &str,
    unit: &mut CompilationUnit,
    diags: &mut Vec<Diagnostic>,
) {
    let tokens = lex(file, text, diags);
    parse_tokens_into(tokens, unit, diags);
}

/// Parses the tokens of one file (from [`lex`]), appending nodes to `unit`.
pub fn parse_tokens_into(
    tokens: Vec<Token>,
    unit: &mut CompilationUnit,
    diags: &mut Vec<Diagnostic>,
) {
    let mut p = Parser {
        tokens,
        pos: 0,
        next_id: unit.node_count,
        diags,
        depth: 0,
        tree: 0,
    };
    while !p.at_eof() {
        let before = p.pos;
        match p.item() {
            Ok(mut items) => unit.items.append(&mut items),
            Err(()) => p.recover_top(),
        }
        if p.pos == before {
            p.bump();
        }
    }
    unit.node_count = p.next_id;
}

const RESERVED: [&str; 60] = [
    "IF",
    "THEN",
    "ELSIF",
    "ELSE",
    "END_IF",
    "CASE",
    "OF",
    "END_CASE",
    "FOR",
    "TO",
    "BY",
    "DO",
    "END_FOR",
    "WHILE",
    "END_WHILE",
    "REPEAT",
    "UNTIL",
    "END_REPEAT",
    "EXIT",
    "CONTINUE",
    "RETURN",
    "VAR",
    "VAR_INPUT",
    "VAR_OUTPUT",
    "VAR_IN_OUT",
    "VAR_TEMP",
    "VAR_GLOBAL",
    "VAR_EXTERNAL",
    "END_VAR",
    "PROGRAM",
    "END_PROGRAM",
    "FUNCTION",
    "END_FUNCTION",
    "FUNCTION_BLOCK",
    "END_FUNCTION_BLOCK",
    "TYPE",
    "END_TYPE",
    "STRUCT",
    "END_STRUCT",
    "ARRAY",
    "AND",
    "OR",
    "XOR",
    "NOT",
    "MOD",
    "AT",
    "CONSTANT",
    "RETAIN",
    "BEGIN",
    "END_REGION",
    "REGION",
    "VAR_STAT",
    "PERSISTENT",
    "NON_RETAIN",
    "CONFIGURATION",
    "END_CONFIGURATION",
    "RESOURCE",
    "END_RESOURCE",
    "TASK",
    "WITH",
];

struct Parser<'d> {
    tokens: Vec<Token>,
    pos: usize,
    next_id: u32,
    diags: &'d mut Vec<Diagnostic>,
    depth: u32,
    /// Extra tree depth of open left-associative chains.
    tree: u32,
}

type PResult<T> = Result<T, ()>;

fn describe(t: &Tok) -> String {
    match t {
        Tok::Ident(s) => format!("'{s}'"),
        Tok::HashIdent(s) => format!("'#{s}'"),
        Tok::DqString(s) => format!("\"{s}\""),
        Tok::SqString(s) => format!("'{s}'"),
        Tok::Int(v) => v.to_string(),
        Tok::Real(v) => v.to_string(),
        Tok::TypePrefix(s) => format!("{s}#"),
        Tok::Time(..) => "time literal".into(),
        Tok::Date(_) | Tok::Tod(_) | Tok::Dt(_) => "date literal".into(),
        Tok::Direct(s) => format!("%{s}"),
        Tok::Punct(p) => format!("'{p}'"),
        Tok::Eof => "end of file".into(),
    }
}

impl Parser<'_> {
    fn tok(&self) -> &Tok {
        self.tokens
            .get(self.pos)
            .map(|t| &t.tok)
            .unwrap_or(&Tok::Eof)
    }
    fn tok_at(&self, k: usize) -> &Tok {
        self.tokens
            .get(self.pos + k)
            .map(|t| &t.tok)
            .unwrap_or(&Tok::Eof)
    }
    fn span(&self) -> Span {
        self.tokens
            .get(self.pos)
            .or_else(|| self.tokens.last())
            .map(|t| t.span)
            .unwrap_or_default()
    }
    fn prev_span(&self) -> Span {
        self.tokens
            .get(self.pos.saturating_sub(1))
            .map(|t| t.span)
            .unwrap_or_default()
    }
    fn at_eof(&self) -> bool {
        matches!(self.tok(), Tok::Eof)
    }
    fn bump(&mut self) {
        if self.pos < self.tokens.len() {
            self.pos += 1;
        }
    }
    fn id(&mut self) -> NodeId {
        let id = NodeId(self.next_id);
        self.next_id = self.next_id.saturating_add(1);
        id
    }
    fn is_kw(&self, kw: &str) -> bool {
        matches!(self.tok(), Tok::Ident(s) if s.eq_ignore_ascii_case(kw))
    }
    fn eat_kw(&mut self, kw: &str) -> bool {
        if self.is_kw(kw) {
            self.bump();
            true
        } else {
            false
        }
    }
    fn is_p(&self, p: &str) -> bool {
        matches!(self.tok(), Tok::Punct(q) if *q == p)
    }
    fn eat_p(&mut self, p: &str) -> bool {
        if self.is_p(p) {
            self.bump();
            true
        } else {
            false
        }
    }
    fn error<T>(&mut self, msg: impl Into<String>) -> PResult<T> {
        let span = self.span();
        self.diags.push(Diagnostic::error(Code::Syntax, span, msg));
        Err(())
    }
    fn expected<T>(&mut self, what: &str) -> PResult<T> {
        let found = describe(self.tok());
        self.error(format!("expected {what}, found {found}"))
    }
    fn expect_p(&mut self, p: &str) -> PResult<()> {
        if self.eat_p(p) {
            Ok(())
        } else {
            self.expected(&format!("'{p}'"))
        }
    }
    /// A `;` that ends a statement or declaration. When it is missing the error points
    /// at the end of what lacks it, not at the next token (often on the next line):
    /// that is where the `;` goes.
    fn expect_semicolon(&mut self, what: &str) -> PResult<()> {
        if self.eat_p(";") {
            return Ok(());
        }
        let found = describe(self.tok());
        let previous = self.prev_span();
        let next = self.span();
        // A character the lexer refused between the two is the real mistake, and is
        // reported already.
        let explained = self.diags.iter().any(|d| {
            d.primary.file == previous.file
                && (previous.end..=next.start).contains(&d.primary.start)
        });
        if explained {
            return Err(());
        }
        let at = Span {
            start: previous.end,
            ..previous
        };
        self.diags.push(Diagnostic::error(
            Code::Syntax,
            at,
            format!("expected ';' at the end of this {what}, found {found} after it"),
        ));
        Err(())
    }
    fn expect_kw(&mut self, kw: &str) -> PResult<()> {
        if self.eat_kw(kw) {
            Ok(())
        } else {
            self.expected(kw)
        }
    }
    fn ident(&mut self) -> PResult<Ident> {
        let span = self.span();
        match self.tok().clone() {
            Tok::Ident(s) if !RESERVED.contains(&s.to_ascii_uppercase().as_str()) => {
                self.bump();
                Ok(Ident::new(s, span))
            }
            Tok::DqString(s) | Tok::HashIdent(s) => {
                self.bump();
                Ok(Ident::new(s, span))
            }
            _ => self.expected("a name"),
        }
    }

    fn recover_top(&mut self) {
        while !self.at_eof() {
            if [
                "PROGRAM",
                "FUNCTION",
                "FUNCTION_BLOCK",
                "TYPE",
                "VAR_GLOBAL",
            ]
            .iter()
            .any(|k| self.is_kw(k))
            {
                return;
            }
            self.bump();
        }
    }

    fn enter(&mut self) -> PResult<()> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            self.depth -= 1;
            return self.error("nesting too deep");
        }
        Ok(())
    }
}
