//! Expressions: binary operators by precedence, unary operators, postfix chains (members,
//! indexes, calls, partial access), call arguments and primaries; bounded by
//! [`MAX_TREE`](super::MAX_TREE).

use super::{PResult, Parser, MAX_TREE, RESERVED};
use crate::syntax::ast::*;
use crate::syntax::lexer::Tok;
use crate::syntax::source::Span;

impl Parser<'_> {
    pub(super) fn expr(&mut self) -> PResult<Expr> {
        self.enter()?;
        let r = self.binary(0);
        self.depth -= 1;
        r
    }

    fn binop(&self) -> Option<(BinOp, u8)> {
        // precedence: OR 1, XOR 2, AND 3, = <> 4, < > <= >= 5, + - 6, * / MOD 7, ** 8
        Some(match self.tok() {
            Tok::Ident(s) => match s.to_ascii_uppercase().as_str() {
                "OR" => (BinOp::Or, 1),
                "XOR" => (BinOp::Xor, 2),
                "AND" => (BinOp::And, 3),
                "MOD" => (BinOp::Mod, 7),
                _ => return None,
            },
            Tok::Punct(p) => match *p {
                "&" => (BinOp::And, 3),
                "=" => (BinOp::Eq, 4),
                "<>" => (BinOp::Ne, 4),
                "<" => (BinOp::Lt, 5),
                ">" => (BinOp::Gt, 5),
                "<=" => (BinOp::Le, 5),
                ">=" => (BinOp::Ge, 5),
                "+" => (BinOp::Add, 6),
                "-" => (BinOp::Sub, 6),
                "*" => (BinOp::Mul, 7),
                "/" => (BinOp::Div, 7),
                "**" => (BinOp::Pow, 8),
                _ => return None,
            },
            _ => return None,
        })
    }

    fn binary(&mut self, min: u8) -> PResult<Expr> {
        let mut lhs = self.unary()?;
        let mut chain = 0u32;
        let r = self.binary_chain(&mut lhs, min, &mut chain);
        self.tree -= chain;
        r.map(|()| lhs)
    }

    /// One more level of a left-deep tree.
    fn grow(&mut self, chain: &mut u32) -> PResult<()> {
        *chain += 1;
        self.tree += 1;
        if self.tree + self.depth > MAX_TREE {
            return self.error(
                "expression too long or too deeply nested; split it with intermediate variables",
            );
        }
        Ok(())
    }

    fn binary_chain(&mut self, lhs: &mut Expr, min: u8, chain: &mut u32) -> PResult<()> {
        while let Some((op, prec)) = self.binop() {
            if prec < min {
                break;
            }
            self.grow(chain)?;
            self.bump();
            // all binary operators are left-associative in IEC 61131-3 (** included)
            self.enter()?;
            let rhs = self.binary(prec + 1);
            self.depth -= 1;
            let rhs = rhs?;
            let span = lhs.span.to(rhs.span);
            let left = std::mem::replace(
                lhs,
                Expr {
                    id: NodeId(0),
                    kind: ExprKind::Literal(Literal::Bool(false)),
                    span,
                },
            );
            *lhs = Expr {
                id: self.id(),
                kind: ExprKind::Binary(op, Box::new(left), Box::new(rhs)),
                span,
            };
        }
        Ok(())
    }

    fn unary(&mut self) -> PResult<Expr> {
        let start = self.span();
        let op = if self.eat_p("-") {
            Some(UnOp::Neg)
        } else if self.eat_p("+") {
            Some(UnOp::Plus)
        } else if self.eat_kw("NOT") {
            Some(UnOp::Not)
        } else {
            None
        };
        match op {
            Some(op) => {
                self.enter()?;
                // NOT binds tighter than comparisons but looser than **: parse a power operand
                let inner = self.unary_operand();
                self.depth -= 1;
                let inner = inner?;
                // fold -literal into the literal
                if op == UnOp::Neg {
                    if let ExprKind::Literal(Literal::Int(v, None)) = &inner.kind {
                        return Ok(Expr {
                            id: inner.id,
                            kind: ExprKind::Literal(Literal::Int(-*v, None)),
                            span: start.to(inner.span),
                        });
                    }
                    if let ExprKind::Literal(Literal::Real(v, None)) = &inner.kind {
                        return Ok(Expr {
                            id: inner.id,
                            kind: ExprKind::Literal(Literal::Real(-*v, None)),
                            span: start.to(inner.span),
                        });
                    }
                }
                let span = start.to(inner.span);
                Ok(Expr {
                    id: self.id(),
                    kind: ExprKind::Unary(op, Box::new(inner)),
                    span,
                })
            }
            None => self.unary_operand(),
        }
    }

    /// Operand of a unary operator: a postfix expression followed by any `**` chain.
    fn unary_operand(&mut self) -> PResult<Expr> {
        if self.is_p("-") || self.is_p("+") || self.is_kw("NOT") {
            return self.unary();
        }
        let mut lhs = self.postfix()?;
        let mut chain = 0u32;
        while self.is_p("**") {
            if let Err(()) = self.grow(&mut chain) {
                self.tree -= chain;
                return Err(());
            }
            self.bump();
            let rhs = self.postfix_or_unary()?;
            let span = lhs.span.to(rhs.span);
            lhs = Expr {
                id: self.id(),
                kind: ExprKind::Binary(BinOp::Pow, Box::new(lhs), Box::new(rhs)),
                span,
            };
        }
        self.tree -= chain;
        Ok(lhs)
    }

    fn postfix_or_unary(&mut self) -> PResult<Expr> {
        if self.is_p("-") || self.is_p("+") || self.is_kw("NOT") {
            self.enter()?;
            let r = self.unary();
            self.depth -= 1;
            r
        } else {
            self.postfix()
        }
    }

    /// A variable path (for FOR control variables).
    pub(super) fn primary_path(&mut self) -> PResult<Expr> {
        self.postfix()
    }

    fn postfix(&mut self) -> PResult<Expr> {
        let e = self.primary()?;
        let mut chain = 0u32;
        let r = self.postfix_chain(e, &mut chain);
        self.tree -= chain;
        r
    }

    fn postfix_chain(&mut self, mut e: Expr, chain: &mut u32) -> PResult<Expr> {
        loop {
            if self.is_p(".") || self.is_p("[") || self.is_p("^") || self.is_p("(") {
                self.grow(chain)?;
            }
            if self.is_p(".") {
                self.bump();
                let span = self.span();
                match self.tok().clone() {
                    Tok::Direct(d)
                        if d.starts_with('X') || d.chars().all(|c| c.is_ascii_digit()) =>
                    {
                        self.bump();
                        let bit: u32 = d.trim_start_matches('X').parse().unwrap_or(0);
                        let s = e.span.to(span);
                        e = Expr {
                            id: self.id(),
                            kind: ExprKind::Bit(Box::new(e), bit),
                            span: s,
                        };
                    }
                    Tok::Int(v) => {
                        self.bump();
                        let s = e.span.to(span);
                        e = Expr {
                            id: self.id(),
                            kind: ExprKind::Bit(Box::new(e), u32::try_from(v).unwrap_or(u32::MAX)),
                            span: s,
                        };
                    }
                    Tok::Direct(d) if partial_access(&d).is_some() => {
                        self.bump();
                        let ((width, index), bit) = partial_access(&d).unwrap_or(((8, 0), None));
                        let s = e.span.to(span);
                        e = Expr {
                            id: self.id(),
                            kind: ExprKind::Part(Box::new(e), width, index),
                            span: s,
                        };
                        // `%B1.1`: the lexer keeps a dot before a digit in the address
                        // (`%IX0.3`), so a bare bit index after a part comes in the same
                        // token (RuSTy's `d.%D1.%W1.%B1.1`).
                        if let Some(bit) = bit {
                            e = Expr {
                                id: self.id(),
                                kind: ExprKind::Bit(Box::new(e), bit),
                                span: s,
                            };
                        }
                    }
                    _ => {
                        let name = self.ident()?;
                        let s = e.span.to(name.span);
                        e = Expr {
                            id: self.id(),
                            kind: ExprKind::Member(Box::new(e), name),
                            span: s,
                        };
                    }
                }
            } else if self.is_p("[") {
                self.bump();
                let mut idx = vec![self.expr()?];
                while self.eat_p(",") {
                    idx.push(self.expr()?);
                }
                self.expect_p("]")?;
                let s = e.span.to(self.prev_span());
                e = Expr {
                    id: self.id(),
                    kind: ExprKind::Index(Box::new(e), idx),
                    span: s,
                };
            } else if self.is_p("^") {
                self.bump();
                let s = e.span.to(self.prev_span());
                e = Expr {
                    id: self.id(),
                    kind: ExprKind::Deref(Box::new(e)),
                    span: s,
                };
            } else if self.is_p("(")
                && matches!(
                    e.kind,
                    ExprKind::Name { .. }
                        | ExprKind::Member(..)
                        | ExprKind::Index(..)
                        | ExprKind::Deref(_)
                )
            {
                self.bump();
                let args = self.args()?;
                let s = e.span.to(self.prev_span());
                e = Expr {
                    id: self.id(),
                    kind: ExprKind::Call(Box::new(e), args),
                    span: s,
                };
            } else {
                return Ok(e);
            }
        }
    }

    fn args(&mut self) -> PResult<Vec<Arg>> {
        let mut args = Vec::new();
        if self.eat_p(")") {
            return Ok(args);
        }
        loop {
            let negated = self.is_kw("NOT")
                && matches!(self.tok_at(1), Tok::Ident(_) | Tok::HashIdent(_))
                && matches!(self.tok_at(2), Tok::Punct("=>"));
            if negated {
                self.bump();
            }
            let named = matches!(
                self.tok(),
                Tok::Ident(_) | Tok::HashIdent(_) | Tok::DqString(_)
            ) && matches!(self.tok_at(1), Tok::Punct(":=" | "=>"));
            if named {
                let name = self.ident()?;
                let output = self.is_p("=>");
                self.bump();
                if output && (self.is_p(",") || self.is_p(")")) {
                    // `Q =>` with nothing bound: nothing to do
                } else {
                    let value = self.expr()?;
                    args.push(Arg {
                        name: Some(name),
                        output,
                        negated,
                        value,
                    });
                }
            } else {
                let value = self.expr()?;
                args.push(Arg {
                    name: None,
                    output: false,
                    negated: false,
                    value,
                });
            }
            if !self.eat_p(",") {
                break;
            }
        }
        self.expect_p(")")?;
        Ok(args)
    }

    fn primary(&mut self) -> PResult<Expr> {
        let span = self.span();
        let lit = |p: &mut Self, l: Literal| {
            p.bump();
            Ok(Expr {
                id: p.id(),
                kind: ExprKind::Literal(l),
                span,
            })
        };
        match self.tok().clone() {
            Tok::Int(v) => lit(
                self,
                Literal::Int(i128::try_from(v).unwrap_or(i128::MAX), None),
            ),
            Tok::Real(v) => lit(self, Literal::Real(v, None)),
            Tok::SqString(s) => lit(self, Literal::String(s, false)),
            Tok::Time(ns, long) => lit(self, Literal::Time(ns, long)),
            Tok::Date(v) => lit(self, Literal::Date(v)),
            Tok::Tod(v) => lit(self, Literal::Tod(v)),
            Tok::Dt(v) => lit(self, Literal::Dt(v)),
            Tok::Direct(d) => {
                self.bump();
                Ok(Expr {
                    id: self.id(),
                    kind: ExprKind::Direct(d),
                    span,
                })
            }
            Tok::TypePrefix(ty) => {
                self.bump();
                let neg = self.eat_p("-");
                let vspan = self.span();
                let kind = match self.tok().clone() {
                    Tok::Int(v) => {
                        let v = i128::try_from(v).unwrap_or(i128::MAX);
                        if ty == "REAL" || ty == "LREAL" {
                            Literal::Real(if neg { -(v as f64) } else { v as f64 }, Some(ty))
                        } else {
                            Literal::Int(if neg { -v } else { v }, Some(ty))
                        }
                    }
                    Tok::Real(v) => Literal::Real(if neg { -v } else { v }, Some(ty)),
                    Tok::Ident(s) if ty == "BOOL" && s.eq_ignore_ascii_case("TRUE") => {
                        Literal::Bool(true)
                    }
                    Tok::Ident(s) if ty == "BOOL" && s.eq_ignore_ascii_case("FALSE") => {
                        Literal::Bool(false)
                    }
                    Tok::SqString(s) => Literal::String(s, ty.starts_with('W')),
                    Tok::DqString(s) => Literal::String(s, true),
                    _ => return self.expected("a literal value after the type prefix"),
                };
                self.bump();
                let _ = vspan;
                Ok(Expr {
                    id: self.id(),
                    kind: ExprKind::Literal(kind),
                    span: span.to(self.prev_span()),
                })
            }
            Tok::DqString(s) => {
                self.bump();
                Ok(Expr {
                    id: self.id(),
                    kind: ExprKind::Name {
                        ident: Ident::new(s, span),
                        quoted: true,
                    },
                    span,
                })
            }
            Tok::HashIdent(s) => {
                self.bump();
                Ok(Expr {
                    id: self.id(),
                    kind: ExprKind::Name {
                        ident: Ident::new(s, span),
                        quoted: false,
                    },
                    span,
                })
            }
            Tok::Ident(s) => {
                let up = s.to_ascii_uppercase();
                if up == "TRUE" {
                    return lit(self, Literal::Bool(true));
                }
                if up == "FALSE" {
                    return lit(self, Literal::Bool(false));
                }
                // MOD(a, b) in function form
                let fn_form = matches!(up.as_str(), "MOD" | "AND" | "OR" | "XOR")
                    && matches!(self.tok_at(1), Tok::Punct("("));
                if RESERVED.contains(&up.as_str()) && !fn_form {
                    return self.expected("an expression");
                }
                self.bump();
                // Enum typed value: Color#Red lexes as Ident("Color") HashIdent("Red")
                if let Tok::HashIdent(v) = self.tok().clone() {
                    let vspan = self.span();
                    if vspan.start == span.end {
                        self.bump();
                        return Ok(Expr {
                            id: self.id(),
                            kind: ExprKind::TypedEnum(
                                Ident::new(s, span),
                                Ident::new(
                                    v,
                                    Span {
                                        start: vspan.start + 1,
                                        ..vspan
                                    },
                                ),
                            ),
                            span: span.to(vspan),
                        });
                    }
                }
                Ok(Expr {
                    id: self.id(),
                    kind: ExprKind::Name {
                        ident: Ident::new(s, span),
                        quoted: false,
                    },
                    span,
                })
            }
            Tok::Punct("(") => {
                self.bump();
                let e = self.expr()?;
                self.expect_p(")")?;
                Ok(e)
            }
            _ => self.expected("an expression"),
        }
    }
}

/// `B1`, `W0`, `D1`, `L0` after `.%`, optionally followed by a bit index (`B1.1`): the
/// width in bits of the part and its index, and the bit.
fn partial_access(d: &str) -> Option<((u32, u32), Option<u32>)> {
    match d.split_once('.') {
        None => Some((partial_width(d)?, None)),
        Some((part, bit)) => {
            if bit.is_empty() || !bit.chars().all(|c| c.is_ascii_digit()) {
                return None;
            }
            Some((partial_width(part)?, Some(bit.parse().unwrap_or(u32::MAX))))
        }
    }
}

/// `B1`, `W0`, `D1`, `L0` after `.%`: the width in bits of the part and its index.
fn partial_width(d: &str) -> Option<(u32, u32)> {
    let mut chars = d.chars();
    let width = match chars.next()? {
        'B' | 'b' => 8,
        'W' | 'w' => 16,
        'D' | 'd' => 32,
        'L' | 'l' => 64,
        _ => return None,
    };
    let digits = chars.as_str();
    if digits.is_empty() || !digits.chars().all(|c| c.is_ascii_digit()) {
        return None;
    }
    Some((width, digits.parse().unwrap_or(u32::MAX)))
}
