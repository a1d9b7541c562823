//! Statements: assignments, control flow, calls as statements, and places written to
//! (l-values).

use super::*;

impl BodyCx<'_> {
    pub(super) fn stmts(&mut self, body: &[Stmt]) {
        for s in body {
            self.stmt(s);
        }
    }

    fn cond(&mut self, e: &Expr) {
        let t = self.expr(e, Some(&Ty::Bool));
        if t != Ty::Bool && t != Ty::Void {
            let n = self.name(&t);
            self.err(
                Code::TypeMismatch,
                e.span,
                format!("type mismatch: condition must be BOOL, found {n}"),
            );
        }
    }

    fn stmt(&mut self, s: &Stmt) {
        match &s.kind {
            StmtKind::Assign(target, value) => {
                let tt = self.lvalue(target);
                let vt = self.expr(value, Some(&tt));
                if matches!(vt, Ty::Fb(_)) || matches!(tt, Ty::Fb(_)) {
                    self.err(
                        Code::TypeMismatch,
                        s.span,
                        "function block instances cannot be assigned",
                    );
                    return;
                }
                // constant values outside a subrange are rejected at compile time
                let range = match self.c.res.get(&target.id) {
                    Some(Res::Local(i)) => self
                        .pou
                        .and_then(|p| self.c.pou(p))
                        .and_then(|p| p.vars.get(*i))
                        .and_then(|v| v.range),
                    Some(Res::Global(g)) => self.c.globals.get(*g).and_then(|v| v.range),
                    _ => match &target.kind {
                        ExprKind::Index(base, _) => match self.c.ty(base.id) {
                            Ty::Array(a) => a.elem_range,
                            _ => None,
                        },
                        _ => None,
                    },
                };
                if let (Some((lo, hi)), ExprKind::Literal(Literal::Int(v, _))) =
                    (range, &value.kind)
                {
                    if *v < i128::from(lo) || *v > i128::from(hi) {
                        self.err(
                            Code::TypeMismatch,
                            value.span,
                            format!("value {v} is outside the subrange {lo}..{hi}"),
                        );
                    }
                }
                if !self.coerce_to(value, &vt, &tt, "value") {
                    // point at the declaration of the target variable
                    let decl = match self.c.res.get(&target.id) {
                        Some(Res::Local(i)) => self
                            .pou
                            .and_then(|p| self.c.pou(p))
                            .and_then(|p| p.vars.get(*i))
                            .map(|v| (v.span, v.name.clone())),
                        Some(Res::Global(g)) => {
                            self.c.globals.get(*g).map(|v| (v.span, v.name.clone()))
                        }
                        _ => None,
                    };
                    if let (Some((span, name)), Some(last)) = (decl, self.diags.last_mut()) {
                        let ty = self.c.type_name(&tt);
                        *last = last
                            .clone()
                            .with_label(span, format!("'{name}' is declared as {ty} here"));
                    }
                }
            }
            StmtKind::Call(e) => {
                self.expr_stmt_call(e);
            }
            StmtKind::If(arms, els) => {
                for (c, b) in arms {
                    self.cond(c);
                    self.stmts(b);
                }
                if let Some(b) = els {
                    self.stmts(b);
                }
            }
            StmtKind::Case(sel, arms, els) => {
                let st = self.expr(sel, None);
                if !(st.is_int() || st.is_bits() || matches!(st, Ty::Enum(_)) || st == Ty::Void) {
                    let n = self.name(&st);
                    self.err(Code::TypeMismatch, sel.span, format!("type mismatch: CASE selector must be an integer or enumeration, found {n}"));
                }
                for (labels, body) in arms {
                    for l in labels {
                        let es: Vec<&Expr> = match l {
                            CaseLabel::Value(e) => vec![e],
                            CaseLabel::Range(a, b) => vec![a, b],
                        };
                        for e in es {
                            let lt = self.expr(e, Some(&st));
                            if lt != Ty::Void
                                && st != Ty::Void
                                && Ty::common(&lt, &st).is_none()
                                && lt != st
                            {
                                let (a, b) = (self.name(&lt), self.name(&st));
                                self.err(Code::TypeMismatch, e.span, format!("type mismatch: CASE label of type {a} for a selector of type {b}"));
                            }
                        }
                    }
                    self.stmts(body);
                }
                if let Some(b) = els {
                    self.stmts(b);
                }
            }
            StmtKind::For {
                var,
                from,
                to,
                by,
                body,
            } => {
                let vt = self.lvalue(var);
                if !vt.is_int() && vt != Ty::Void {
                    let n = self.name(&vt);
                    self.err(
                        Code::TypeMismatch,
                        var.span,
                        format!(
                            "type mismatch: FOR control variable must be an integer, found {n}"
                        ),
                    );
                }
                for e in [Some(from), Some(to), by.as_ref()].into_iter().flatten() {
                    let t = self.expr(e, Some(&vt));
                    if vt.is_int() {
                        self.coerce_to(e, &t, &vt, "FOR bound");
                    }
                }
                self.loops += 1;
                self.stmts(body);
                self.loops -= 1;
            }
            StmtKind::While(c, body) => {
                self.cond(c);
                self.loops += 1;
                self.stmts(body);
                self.loops -= 1;
            }
            StmtKind::Repeat(body, c) => {
                self.loops += 1;
                self.stmts(body);
                self.loops -= 1;
                self.cond(c);
            }
            StmtKind::Exit | StmtKind::Continue => {
                if self.loops == 0 {
                    let w = if matches!(s.kind, StmtKind::Exit) {
                        "EXIT"
                    } else {
                        "CONTINUE"
                    };
                    self.err(Code::Syntax, s.span, format!("{w} outside of a loop"));
                }
            }
            StmtKind::Return | StmtKind::Empty => {}
        }
    }

    fn expr_stmt_call(&mut self, e: &Expr) {
        let ExprKind::Call(callee, args) = &e.kind else {
            self.expr(e, None);
            return;
        };
        // FB instance call?
        let ct = self.callee_instance_type(callee);
        if let Some(Ty::Fb(id)) = ct {
            self.c.res.insert(e.id, Res::CallFb(id));
            self.call_args(id, args, e.span, true);
            self.set(e, Ty::Void);
            self.calls.push((id, e.span));
            return;
        }
        self.stmt_call = Some(e.id);
        self.expr(e, None);
        self.stmt_call = None;
    }

    /// Type of a callee expression if it designates a variable (FB instance).
    fn callee_instance_type(&mut self, callee: &Expr) -> Option<Ty> {
        if let ExprKind::Name { ident, .. } = &callee.kind {
            let is_var = self
                .pou
                .and_then(|p| self.c.pou(p))
                .and_then(|p| p.var(&ident.key))
                .is_some()
                || self.c.global_index.contains_key(&ident.key);
            if !is_var {
                return None;
            }
        }
        let t = self.expr(callee, None);
        Some(t)
    }

    pub(super) fn lvalue(&mut self, e: &Expr) -> Ty {
        let t = self.expr(e, None);
        match &e.kind {
            ExprKind::Name { ident, .. } => match self.c.res.get(&e.id) {
                Some(Res::Local(i)) => {
                    let v = self
                        .pou
                        .and_then(|p| self.c.pou(p))
                        .and_then(|p| p.vars.get(*i));
                    if v.map(|v| v.constant).unwrap_or(false) {
                        self.err(
                            Code::NotAssignable,
                            e.span,
                            format!("cannot assign to constant '{}'", ident.name),
                        );
                    }
                }
                Some(Res::Global(i)) => {
                    if self.c.globals.get(*i).map(|v| v.constant).unwrap_or(false) {
                        self.err(
                            Code::NotAssignable,
                            e.span,
                            format!("cannot assign to constant '{}'", ident.name),
                        );
                    }
                }
                None => {}
                _ => self.err(
                    Code::NotAssignable,
                    e.span,
                    format!("'{}' is not a variable", ident.name),
                ),
            },
            ExprKind::Member(..)
            | ExprKind::Index(..)
            | ExprKind::Bit(..)
            | ExprKind::Part(..)
            | ExprKind::Deref(_)
            | ExprKind::Direct(_) => {}
            _ => self.err(
                Code::NotAssignable,
                e.span,
                "the left side of an assignment must be a variable",
            ),
        }
        t
    }
}
