//! Statements: statement lists with error recovery, and every statement kind (assignments,
//! calls, IF, CASE, FOR, WHILE, REPEAT, EXIT, CONTINUE, RETURN).

use super::{PResult, Parser, RESERVED};
use crate::syntax::ast::*;
use crate::syntax::lexer::Tok;

impl Parser<'_> {
    fn at_any_kw(&self, ends: &[&str]) -> bool {
        ends.iter().any(|k| self.is_kw(k))
    }

    pub(super) fn stmts(&mut self, ends: &[&str]) -> PResult<Vec<Stmt>> {
        let mut out = Vec::new();
        while !self.at_eof() && !self.at_any_kw(ends) && !self.at_block_end() {
            let before = self.pos;
            match self.stmt() {
                Ok(s) => out.push(s),
                Err(()) => {
                    // recover: skip to the next ';' or block keyword
                    while !self.at_eof() && !self.is_p(";") && !self.at_any_kw(ends) {
                        if self.pos != before
                            && ["IF", "FOR", "WHILE", "REPEAT", "CASE"]
                                .iter()
                                .any(|k| self.is_kw(k))
                        {
                            break;
                        }
                        self.bump();
                    }
                    self.eat_p(";");
                }
            }
            if self.pos == before {
                self.bump();
            }
        }
        Ok(out)
    }

    /// A keyword that closes some block and can never start a statement.
    fn at_block_end(&self) -> bool {
        matches!(self.tok(), Tok::Ident(s) if {
            let u = s.to_ascii_uppercase();
            u.starts_with("END_") || u == "ELSE" || u == "ELSIF" || u == "UNTIL"
        })
    }

    fn stmt(&mut self) -> PResult<Stmt> {
        self.enter()?;
        let r = self.stmt_inner();
        self.depth -= 1;
        r
    }

    fn stmt_inner(&mut self) -> PResult<Stmt> {
        let start = self.span();
        let kind = if self.eat_p(";") {
            return Ok(Stmt {
                kind: StmtKind::Empty,
                span: start,
            });
        } else if self.eat_kw("REGION") {
            // SCL REGION name ... END_REGION: transparent
            while !self.at_eof() && self.span().start <= start.end + 200 && !self.is_stmt_start() {
                self.bump();
            }
            let body = self.stmts(&["END_REGION"])?;
            self.expect_kw("END_REGION")?;
            StmtKind::If(
                vec![(
                    Expr {
                        id: self.id(),
                        kind: ExprKind::Literal(Literal::Bool(true)),
                        span: start,
                    },
                    body,
                )],
                None,
            )
        } else if self.eat_kw("IF") {
            let mut arms = Vec::new();
            let c = self.expr()?;
            self.expect_kw("THEN")?;
            let b = self.stmts(&["ELSIF", "ELSE", "END_IF"])?;
            arms.push((c, b));
            let mut els = None;
            loop {
                if self.eat_kw("ELSIF") {
                    let c = self.expr()?;
                    self.expect_kw("THEN")?;
                    let b = self.stmts(&["ELSIF", "ELSE", "END_IF"])?;
                    arms.push((c, b));
                } else if self.eat_kw("ELSE") {
                    els = Some(self.stmts(&["END_IF"])?);
                } else {
                    break;
                }
            }
            self.expect_kw("END_IF")?;
            StmtKind::If(arms, els)
        } else if self.eat_kw("CASE") {
            let sel = self.expr()?;
            self.expect_kw("OF")?;
            let mut arms = Vec::new();
            let mut els = None;
            while !self.at_eof() && !self.is_kw("END_CASE") {
                if self.eat_kw("ELSE") {
                    els = Some(self.stmts(&["END_CASE"])?);
                    break;
                }
                let mut labels = Vec::new();
                loop {
                    let a = self.expr()?;
                    if self.eat_p("..") {
                        let b = self.expr()?;
                        labels.push(CaseLabel::Range(a, b));
                    } else {
                        labels.push(CaseLabel::Value(a));
                    }
                    if !self.eat_p(",") {
                        break;
                    }
                }
                self.expect_p(":")?;
                let body = self.case_body()?;
                arms.push((labels, body));
            }
            self.expect_kw("END_CASE")?;
            StmtKind::Case(sel, arms, els)
        } else if self.eat_kw("FOR") {
            let var = self.primary_path()?;
            self.expect_p(":=")?;
            let from = self.expr()?;
            self.expect_kw("TO")?;
            let to = self.expr()?;
            let by = if self.eat_kw("BY") {
                Some(self.expr()?)
            } else {
                None
            };
            self.expect_kw("DO")?;
            let body = self.stmts(&["END_FOR"])?;
            self.expect_kw("END_FOR")?;
            StmtKind::For {
                var,
                from,
                to,
                by,
                body,
            }
        } else if self.eat_kw("WHILE") {
            let c = self.expr()?;
            self.expect_kw("DO")?;
            let body = self.stmts(&["END_WHILE"])?;
            self.expect_kw("END_WHILE")?;
            StmtKind::While(c, body)
        } else if self.eat_kw("REPEAT") {
            let body = self.stmts(&["UNTIL"])?;
            self.expect_kw("UNTIL")?;
            let c = self.expr()?;
            self.expect_kw("END_REPEAT")?;
            StmtKind::Repeat(body, c)
        } else if self.eat_kw("EXIT") {
            StmtKind::Exit
        } else if self.eat_kw("CONTINUE") {
            StmtKind::Continue
        } else if self.eat_kw("RETURN") {
            StmtKind::Return
        } else {
            let target = self.expr()?;
            if self.eat_p(":=") {
                let value = self.expr()?;
                StmtKind::Assign(target, value)
            } else if matches!(target.kind, ExprKind::Call(..)) {
                StmtKind::Call(target)
            } else {
                return self.expected("':=' or a call");
            }
        };
        let span = start.to(self.prev_span());
        if !matches!(
            kind,
            StmtKind::Assign(..)
                | StmtKind::Call(_)
                | StmtKind::Exit
                | StmtKind::Continue
                | StmtKind::Return
        ) {
            self.eat_p(";");
        } else {
            self.expect_semicolon("statement")?;
        }
        Ok(Stmt { kind, span })
    }

    fn is_stmt_start(&self) -> bool {
        [
            "IF", "CASE", "FOR", "WHILE", "REPEAT", "EXIT", "RETURN", "CONTINUE",
        ]
        .iter()
        .any(|k| self.is_kw(k))
            || matches!(self.tok(), Tok::HashIdent(_) | Tok::DqString(_))
            || (matches!(self.tok(), Tok::Ident(_))
                && matches!(self.tok_at(1), Tok::Punct(":=" | "." | "[" | "(")))
    }

    /// Statements of a CASE arm: up to the next label (`expr :` / `expr ,` / `a..b :`), ELSE
    /// or END_CASE.
    fn case_body(&mut self) -> PResult<Vec<Stmt>> {
        let mut out = Vec::new();
        while !self.at_eof() && !self.is_kw("END_CASE") && !self.is_kw("ELSE") {
            if self.looks_like_case_label() {
                break;
            }
            let before = self.pos;
            match self.stmt() {
                Ok(s) => out.push(s),
                Err(()) => {
                    while !self.at_eof() && !self.is_p(";") && !self.is_kw("END_CASE") {
                        self.bump();
                    }
                    self.eat_p(";");
                }
            }
            if self.pos == before {
                self.bump();
            }
        }
        Ok(out)
    }

    fn looks_like_case_label(&self) -> bool {
        // scan a simple label: [-] literal/name/Type#Value (, ...)* (.. ...)? ':' but not ':='
        let mut k = 0;
        loop {
            if matches!(self.tok_at(k), Tok::Punct("-" | "+")) {
                k += 1;
            }
            match self.tok_at(k) {
                Tok::Int(_) | Tok::SqString(_) => k += 1,
                Tok::TypePrefix(_) => {
                    k += 1;
                    if matches!(self.tok_at(k), Tok::Punct("-")) {
                        k += 1;
                    }
                    k += 1;
                }
                Tok::Ident(s) if !RESERVED.contains(&s.to_ascii_uppercase().as_str()) => {
                    k += 1;
                    if matches!(self.tok_at(k), Tok::Punct("#")) {
                        k += 2;
                    }
                    // Type#Value lexes as Ident, then '#'? No: '#' is not a punct; the
                    // lexer produces HashIdent for `#Value`.
                    if matches!(self.tok_at(k), Tok::HashIdent(_)) {
                        k += 1;
                    }
                }
                Tok::HashIdent(_) | Tok::DqString(_) => k += 1,
                _ => return false,
            }
            match self.tok_at(k) {
                Tok::Punct(",") | Tok::Punct("..") => k += 1,
                Tok::Punct(":") => return true,
                _ => return false,
            }
        }
    }
}
