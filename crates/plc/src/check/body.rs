//! Checking of statements, expressions and initial values.

use super::*;
use crate::stdlib::{self, Builtin};
use std::collections::HashSet;

pub(super) fn check_bodies(
    c: &mut Checked,
    type_inits: &[(Init, Ty)],
    diags: &mut Vec<Diagnostic>,
) {
    let mut calls: HashMap<PouId, Vec<(PouId, Span)>> = HashMap::new();
    // initial values of TYPE declarations and STRUCT members, once, before the variables
    // that share them
    let member_inits: Vec<(Init, Ty)> = c
        .types
        .structs
        .iter()
        .flat_map(|s| &s.fields)
        .filter_map(|f| Some((f.init.clone()?, f.ty.clone())))
        .collect();
    for (init, ty) in type_inits.iter().chain(&member_inits) {
        let mut bc = BodyCx {
            c,
            diags,
            pou: None,
            loops: 0,
            calls: Vec::new(),
            used: HashSet::new(),
            stmt_call: None,
        };
        bc.init(init, ty);
    }
    // globals' initial values
    for gi in 0..c.globals.len() {
        let (init, ty) = match c.globals.get(gi) {
            Some(g) => (g.init.clone(), g.ty.clone()),
            None => continue,
        };
        if let Some(init) = init {
            let mut bc = BodyCx {
                c,
                diags,
                pou: None,
                loops: 0,
                calls: Vec::new(),
                used: HashSet::new(),
                stmt_call: None,
            };
            bc.init(&init, &ty);
        }
    }
    for pi in 0..c.pous.len() {
        let id = PouId(pi);
        let Some(item) = c.pous.get(pi).map(|p| p.item) else {
            continue;
        };
        let Some(Item::Pou(pou)) = c.unit.items.get(item).cloned() else {
            continue;
        };
        let vars = c.pous.get(pi).map(|p| p.vars.clone()).unwrap_or_default();
        let mut bc = BodyCx {
            c,
            diags,
            pou: Some(id),
            loops: 0,
            calls: Vec::new(),
            used: HashSet::new(),
            stmt_call: None,
        };
        for v in &vars {
            if let Some(init) = &v.init {
                if v.kind == VarKind::External {
                    continue;
                }
                bc.init(init, &v.ty);
            }
        }
        bc.stmts(&pou.body);
        let used = std::mem::take(&mut bc.used);
        let is_stdlib = bc.c.pou(id).is_some_and(|p| p.stdlib);
        if !is_stdlib {
            for (i, v) in vars.iter().enumerate() {
                let local = matches!(v.kind, VarKind::Local | VarKind::Temp | VarKind::Static);
                let result_var = pou.kind == PouKind::Function && i == 0;
                if local
                    && !result_var
                    && !used.contains(&i)
                    && !v.name.starts_with('_')
                    && v.at.is_none()
                {
                    bc.diags.push(Diagnostic::warning(
                        Code::UnusedVariable,
                        v.span,
                        format!("variable '{}' is declared but never used", v.name),
                    ));
                }
            }
        }
        let found = std::mem::take(&mut bc.calls);
        calls.insert(id, found);
    }
    // recursion: a cycle in the call graph of functions and FB bodies
    let mut state: HashMap<PouId, u8> = HashMap::new();
    // in declaration order, so the same program always reports the same call
    let mut ids: Vec<PouId> = calls.keys().copied().collect();
    ids.sort_by_key(|id| id.0);
    let mut reported = HashSet::new();
    for id in ids {
        detect_cycle(
            id,
            &calls,
            &mut state,
            &mut Vec::new(),
            diags,
            c,
            &mut reported,
        );
    }
}

fn detect_cycle(
    id: PouId,
    calls: &HashMap<PouId, Vec<(PouId, Span)>>,
    state: &mut HashMap<PouId, u8>,
    stack: &mut Vec<PouId>,
    diags: &mut Vec<Diagnostic>,
    c: &Checked,
    reported: &mut HashSet<PouId>,
) {
    match state.get(&id) {
        Some(2) => return,
        Some(1) => return,
        _ => {}
    }
    if stack.len() > 1000 {
        return;
    }
    state.insert(id, 1);
    stack.push(id);
    for (callee, span) in calls.get(&id).map(Vec::as_slice).unwrap_or(&[]) {
        if state.get(callee) == Some(&1) {
            if reported.insert(*callee) {
                let name = c.pou(*callee).map(|p| p.name.clone()).unwrap_or_default();
                diags.push(Diagnostic::error(
                    Code::Recursion,
                    *span,
                    format!("recursive call of '{name}' (IEC 61131-3 forbids recursion)"),
                ));
            }
        } else {
            detect_cycle(*callee, calls, state, stack, diags, c, reported);
        }
    }
    stack.pop();
    state.insert(id, 2);
}

struct BodyCx<'a> {
    c: &'a mut Checked,
    diags: &'a mut Vec<Diagnostic>,
    pou: Option<PouId>,
    loops: u32,
    calls: Vec<(PouId, Span)>,
    /// Variables of the POU that are referenced.
    used: HashSet<usize>,
    /// The call being checked as a statement (a function without a result may be one).
    stmt_call: Option<crate::syntax::NodeId>,
}

/// The value of an integer literal, also negated (`-5`).
fn int_literal(e: &Expr) -> Option<i128> {
    match &e.kind {
        ExprKind::Literal(Literal::Int(v, _)) => Some(*v),
        ExprKind::Unary(UnOp::Neg, a) => int_literal(a).map(|v| -v),
        ExprKind::Unary(UnOp::Plus, a) => int_literal(a),
        _ => None,
    }
}

fn is_untyped_literal(e: &Expr) -> bool {
    matches!(
        e.kind,
        ExprKind::Literal(Literal::Int(_, None)) | ExprKind::Literal(Literal::Real(_, None))
    )
}

impl BodyCx<'_> {
    fn err(&mut self, code: Code, span: Span, msg: impl Into<String>) {
        self.diags.push(Diagnostic::error(code, span, msg));
    }
    fn set(&mut self, e: &Expr, t: Ty) -> Ty {
        if let Some(slot) = self.c.expr_ty.get_mut(e.id.0 as usize) {
            *slot = Some(t.clone());
        }
        t
    }
    fn name(&self, t: &Ty) -> String {
        self.c.type_name(t)
    }

    fn init(&mut self, init: &Init, ty: &Ty) {
        match init {
            // shared by every variable of a TYPE with an initial value (and by `a, b : T :=
            // v`): typed once, against the same type each time
            Init::Expr(e)
                if self
                    .c
                    .expr_ty
                    .get(e.id.0 as usize)
                    .is_some_and(Option::is_some) => {}
            Init::Expr(e) => {
                let t = self.expr(e, Some(ty));
                self.coerce_to(e, &t, ty, "initial value");
            }
            Init::Array(items, span) => match ty {
                Ty::Array(a) => {
                    let elem = a.elem.clone();
                    self.init_count(items, a.len());
                    for (count, v) in items {
                        if let Some(n) = count {
                            let t = self.expr(n, Some(&Ty::DInt));
                            if !t.is_int() {
                                self.err(
                                    Code::TypeMismatch,
                                    n.span,
                                    "repetition count must be an integer",
                                );
                            }
                        }
                        self.init(v, &elem);
                    }
                }
                _ => self.err(
                    Code::TypeMismatch,
                    *span,
                    format!("array initializer for a variable of type {}", self.name(ty)),
                ),
            },
            Init::Default(_) => {}
            Init::Struct(fields, span) => match ty {
                Ty::Struct(id) => {
                    let def = self.c.types.struct_def(*id).cloned();
                    for (name, v) in fields {
                        match def
                            .as_ref()
                            .and_then(|d| d.fields.iter().find(|f| f.key == name.key))
                        {
                            Some(f) => {
                                let ft = f.ty.clone();
                                self.init(v, &ft);
                            }
                            None => self.err(
                                Code::Undeclared,
                                name.span,
                                format!("no field '{}' in {}", name.name, self.name(ty)),
                            ),
                        }
                    }
                }
                Ty::Fb(id) => {
                    let pou = self.c.pou(*id).cloned();
                    for (name, v) in fields {
                        match pou
                            .as_ref()
                            .and_then(|p| p.var(&name.key))
                            .map(|(_, v)| v.ty.clone())
                        {
                            Some(ft) => self.init(v, &ft),
                            None => self.err(
                                Code::Undeclared,
                                name.span,
                                format!("no variable '{}' in {}", name.name, self.name(ty)),
                            ),
                        }
                    }
                }
                _ => self.err(
                    Code::TypeMismatch,
                    *span,
                    format!(
                        "structure initializer for a variable of type {}",
                        self.name(ty)
                    ),
                ),
            },
        }
    }

    /// Reports an array initializer that gives more values than the array has elements
    /// (counting `n(v)` as `n` values), at the first value that does not fit.
    fn init_count(&mut self, items: &[(Option<Expr>, Init)], capacity: usize) {
        let repeat = |count: &Option<Expr>| match count.as_ref().map(|c| &c.kind) {
            None => 1,
            Some(ExprKind::Literal(Literal::Int(k, _))) => {
                usize::try_from(*k).unwrap_or(usize::MAX)
            }
            // the parser only makes repetitions of integer literals
            Some(_) => 1,
        };
        let total = items
            .iter()
            .fold(0usize, |n, (count, _)| n.saturating_add(repeat(count)));
        if total <= capacity {
            return;
        }
        let mut given = 0usize;
        for (count, v) in items {
            given = given.saturating_add(repeat(count));
            if given > capacity {
                let at = match count {
                    Some(c) => c.span.to(init_span(v)),
                    None => init_span(v),
                };
                // an initializer shared by every variable of a TYPE is reported once
                if self
                    .diags
                    .iter()
                    .any(|d| d.primary == at && d.code == Code::TypeMismatch)
                {
                    return;
                }
                let values = if total == usize::MAX {
                    "more".to_string()
                } else {
                    total.to_string()
                };
                self.err(
                    Code::TypeMismatch,
                    at,
                    format!(
                        "too many initial values: {values} for an array of {capacity} element{}",
                        if capacity == 1 { "" } else { "s" }
                    ),
                );
                return;
            }
        }
    }

    /// Records an implicit conversion of `e` (natural type `from`) to `to`, or reports.
    fn coerce_to(&mut self, e: &Expr, from: &Ty, to: &Ty, what: &str) -> bool {
        if *from == Ty::Void || *to == Ty::Void {
            return true;
        }
        if from == to {
            return true;
        }
        let ok = match (from, to) {
            // enumerations read as integers (as CODESYS allows)
            (Ty::Enum(_), t) if t.is_int() => true,
            (Ty::Array(a), Ty::Array(b)) => {
                a.dims
                    .iter()
                    .map(|(l, h)| h - l)
                    .eq(b.dims.iter().map(|(l, h)| h - l))
                    && (a.elem == b.elem
                        || matches!((&a.elem, &b.elem), (Ty::String(_), Ty::String(_))))
            }
            _ => from.converts_to(to),
        };
        if ok {
            if from.is_elementary() && from != to {
                self.c.coerce.insert(e.id, to.clone());
            }
            true
        } else {
            let msg = format!(
                "type mismatch: {what} of type {} where {} is expected",
                self.name(from),
                self.name(to)
            );
            self.diags.push(
                Diagnostic::error(Code::TypeMismatch, e.span, msg)
                    .with_note("IEC 61131-3 converts implicitly only to wider types; use an explicit *_TO_* conversion"),
            );
            false
        }
    }

    // ------------------------------------------------------------------ statements

    fn stmts(&mut self, body: &[Stmt]) {
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

    fn lvalue(&mut self, e: &Expr) -> Ty {
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

    // ------------------------------------------------------------------ expressions

    fn expr(&mut self, e: &Expr, hint: Option<&Ty>) -> Ty {
        let t = self.expr_inner(e, hint);
        self.set(e, t)
    }

    fn literal(&mut self, e: &Expr, l: &Literal, hint: Option<&Ty>) -> Ty {
        match l {
            Literal::Int(v, Some(ty)) => {
                let t = Ty::elementary(ty).unwrap_or(Ty::DInt);
                if let Some((lo, hi)) = t.int_range() {
                    if *v < lo || *v > hi {
                        self.err(
                            Code::BadLiteral,
                            e.span,
                            format!("literal {v} is out of range for {t}"),
                        );
                    }
                } else if !t.is_real() && t != Ty::Bool {
                    self.err(
                        Code::BadLiteral,
                        e.span,
                        format!("{t}# cannot prefix an integer"),
                    );
                }
                t
            }
            Literal::Int(v, None) => {
                if let Some(h) = hint {
                    // for BOOL that is 0 and 1, FALSE and TRUE (IEC 61131-3 bit literals)
                    if let Some((lo, hi)) = h.int_range() {
                        if *v >= lo && *v <= hi {
                            return h.clone();
                        }
                    }
                    if h.is_real() {
                        return h.clone();
                    }
                }
                if *v >= i128::from(i32::MIN) && *v <= i128::from(i32::MAX) {
                    if let Some(h) = hint {
                        if h.is_int() || h.is_bits() {
                            // does not fit the hint: smallest type that holds it
                            return smallest_int(*v);
                        }
                    }
                    Ty::DInt
                } else {
                    smallest_int(*v)
                }
            }
            Literal::Real(_, Some(ty)) => {
                Ty::elementary(ty).filter(Ty::is_real).unwrap_or(Ty::LReal)
            }
            Literal::Real(_, None) => match hint {
                Some(Ty::Real) => Ty::Real,
                _ => Ty::LReal,
            },
            Literal::Bool(_) => Ty::Bool,
            Literal::String(s, wide) => {
                let n = u32::try_from(s.chars().count()).unwrap_or(65535).max(1);
                let len = match hint {
                    Some(Ty::String(h)) | Some(Ty::WString(h)) => (*h).max(n),
                    _ => n.max(DEFAULT_STRING_LEN),
                };
                if *wide {
                    Ty::WString(len)
                } else {
                    Ty::String(len)
                }
            }
            Literal::Time(_, long) => {
                if *long || hint == Some(&Ty::LTime) {
                    Ty::LTime
                } else {
                    Ty::Time
                }
            }
            Literal::Date(_) => Ty::Date,
            Literal::Tod(_) => Ty::Tod,
            Literal::Dt(_) => Ty::Dt,
        }
    }

    fn resolve_name(&mut self, e: &Expr, ident: &Ident, quoted: bool, hint: Option<&Ty>) -> Ty {
        if let Some(p) = self.pou.and_then(|p| self.c.pou(p)) {
            if let Some((i, v)) = p.var(&ident.key) {
                let t = v.ty.clone();
                if v.kind == VarKind::External {
                    if let Some(&g) = self.c.global_index.get(&ident.key) {
                        self.c.res.insert(e.id, Res::Global(g));
                        return t;
                    }
                }
                self.c.res.insert(e.id, Res::Local(i));
                self.used.insert(i);
                return t;
            }
        }
        if let Some(&g) = self.c.global_index.get(&ident.key) {
            let t = self
                .c
                .globals
                .get(g)
                .map(|g| g.ty.clone())
                .unwrap_or(Ty::Void);
            self.c.res.insert(e.id, Res::Global(g));
            return t;
        }
        if ident.key == "NULL" && !quoted {
            self.c.res.insert(e.id, Res::Null);
            return Ty::Ref(Rc::new(Ty::Void));
        }
        // enum values: prefer the hinted enum
        if let Some(Ty::Enum(eid)) = hint {
            if let Some(v) = self
                .c
                .types
                .enum_def(*eid)
                .and_then(|d| d.values.iter().find(|(n, _)| n.to_uppercase() == ident.key))
            {
                self.c.res.insert(e.id, Res::EnumValue(v.1));
                return Ty::Enum(*eid);
            }
        }
        for (i, d) in self.c.types.enums.iter().enumerate() {
            if let Some((_, v)) = d.values.iter().find(|(n, _)| n.to_uppercase() == ident.key) {
                self.c.res.insert(e.id, Res::EnumValue(*v));
                return Ty::Enum(EnumId(i));
            }
        }
        if let Some(&pid) = self.c.pou_index.get(&ident.key) {
            if self.c.pou(pid).map(|p| p.kind) == Some(PouKind::Program) {
                self.c.res.insert(e.id, Res::Program(pid));
                return Ty::Void;
            }
        }
        if quoted {
            self.c
                .res
                .insert(e.id, Res::WStringLiteral(ident.name.clone()));
            let n = u32::try_from(ident.name.chars().count())
                .unwrap_or(65535)
                .max(DEFAULT_STRING_LEN);
            return Ty::WString(n);
        }
        self.err(
            Code::Undeclared,
            e.span,
            format!("undeclared name '{}'", ident.name),
        );
        Ty::Void
    }

    fn expr_inner(&mut self, e: &Expr, hint: Option<&Ty>) -> Ty {
        match &e.kind {
            ExprKind::Literal(l) => self.literal(e, l, hint),
            ExprKind::Name { ident, quoted } => self.resolve_name(e, ident, *quoted, hint),
            ExprKind::TypedEnum(ty, v) => {
                let found = self
                    .c
                    .types
                    .enums
                    .iter()
                    .enumerate()
                    .find(|(_, d)| d.name.to_uppercase() == ty.key);
                match found {
                    Some((i, d)) => {
                        match d.values.iter().find(|(n, _)| n.to_uppercase() == v.key) {
                            Some((_, val)) => {
                                let val = *val;
                                self.c.res.insert(e.id, Res::EnumValue(val));
                                Ty::Enum(EnumId(i))
                            }
                            None => {
                                self.err(
                                    Code::Undeclared,
                                    v.span,
                                    format!("enumeration {} has no value '{}'", ty.name, v.name),
                                );
                                Ty::Void
                            }
                        }
                    }
                    None => {
                        self.err(
                            Code::UnknownType,
                            ty.span,
                            format!("unknown enumeration type '{}'", ty.name),
                        );
                        Ty::Void
                    }
                }
            }
            ExprKind::Direct(addr) => direct_type(addr).unwrap_or_else(|| {
                self.err(
                    Code::BadLiteral,
                    e.span,
                    format!("malformed direct address %{addr}"),
                );
                Ty::Void
            }),
            ExprKind::Member(base, field) => {
                let bt = self.expr(base, None);
                if let Some(Res::Program(pid)) = self.c.res.get(&base.id).cloned() {
                    let found = self
                        .c
                        .pou(pid)
                        .and_then(|p| p.var(&field.key))
                        .map(|(i, v)| (i, v.ty.clone()));
                    return match found {
                        Some((i, t)) => {
                            self.c.res.insert(e.id, Res::PouVar(pid, i));
                            t
                        }
                        None => {
                            self.err(
                                Code::Undeclared,
                                field.span,
                                format!("program has no variable '{}'", field.name),
                            );
                            Ty::Void
                        }
                    };
                }
                match &bt {
                    Ty::Struct(id) => {
                        let found = self
                            .c
                            .types
                            .struct_def(*id)
                            .and_then(|d| {
                                d.fields
                                    .iter()
                                    .enumerate()
                                    .find(|(_, f)| f.key == field.key)
                            })
                            .map(|(i, f)| (i, f.ty.clone()));
                        match found {
                            Some((i, t)) => {
                                self.c.res.insert(e.id, Res::Field(i));
                                t
                            }
                            None => {
                                let n = self.name(&bt);
                                self.err(
                                    Code::Undeclared,
                                    field.span,
                                    format!("{n} has no field '{}'", field.name),
                                );
                                Ty::Void
                            }
                        }
                    }
                    Ty::Fb(id) => {
                        let found = self
                            .c
                            .pou(*id)
                            .and_then(|p| p.var(&field.key))
                            .map(|(i, v)| (i, v.ty.clone(), v.kind));
                        match found {
                            Some((_, _, VarKind::InOut)) => {
                                self.err(Code::NotAssignable, field.span, format!("VAR_IN_OUT '{}' is a reference and cannot be accessed from outside the instance", field.name));
                                Ty::Void
                            }
                            Some((i, t, _)) => {
                                self.c.res.insert(e.id, Res::PouVar(*id, i));
                                t
                            }
                            None => {
                                let n = self.name(&bt);
                                self.err(
                                    Code::Undeclared,
                                    field.span,
                                    format!("function block {n} has no variable '{}'", field.name),
                                );
                                Ty::Void
                            }
                        }
                    }
                    Ty::Void => Ty::Void,
                    other => {
                        let n = self.name(other);
                        self.err(
                            Code::TypeMismatch,
                            field.span,
                            format!("type mismatch: {n} has no members"),
                        );
                        Ty::Void
                    }
                }
            }
            ExprKind::Bit(base, bit) => {
                let bt = self.expr(base, None);
                if bt == Ty::Void {
                    return Ty::Bool;
                }
                if !(bt.is_bits() || bt.is_int()) || *bit >= bt.bits() {
                    let n = self.name(&bt);
                    self.err(
                        Code::TypeMismatch,
                        e.span,
                        format!("bit {bit} does not exist in {n}"),
                    );
                }
                Ty::Bool
            }
            ExprKind::Part(base, width, index) => {
                let part = match width {
                    8 => Ty::Byte,
                    16 => Ty::Word,
                    32 => Ty::DWord,
                    _ => Ty::LWord,
                };
                let bt = self.expr(base, None);
                if bt == Ty::Void {
                    return part;
                }
                let fits = (bt.is_bits() || bt.is_int())
                    && *width < bt.bits()
                    && index.checked_mul(*width).is_some_and(|lo| lo < bt.bits());
                if !fits {
                    let n = self.name(&bt);
                    let letter = part_letter(*width);
                    self.err(
                        Code::TypeMismatch,
                        e.span,
                        format!("%{letter}{index} does not exist in {n}"),
                    );
                }
                part
            }
            ExprKind::Index(base, idx) => {
                let bt = self.expr(base, None);
                for i in idx {
                    let it = self.expr(i, Some(&Ty::DInt));
                    if !it.is_int() && !it.is_bits() && it != Ty::Void && !matches!(it, Ty::Enum(_))
                    {
                        let n = self.name(&it);
                        self.err(
                            Code::TypeMismatch,
                            i.span,
                            format!("type mismatch: array index must be an integer, found {n}"),
                        );
                    }
                }
                match &bt {
                    Ty::Array(a) => {
                        if a.dims.len() != idx.len() {
                            self.err(
                                Code::WrongArguments,
                                e.span,
                                format!(
                                    "array has {} dimension(s), {} index(es) given",
                                    a.dims.len(),
                                    idx.len()
                                ),
                            );
                        }
                        a.elem.clone()
                    }
                    // IEC 61131-3 3rd edition: one character, 1-based, as CHAR/WCHAR
                    Ty::String(_) | Ty::WString(_) => {
                        if idx.len() != 1 {
                            self.err(
                                Code::WrongArguments,
                                e.span,
                                format!("a string has one index, {} given", idx.len()),
                            );
                        }
                        if matches!(bt, Ty::WString(_)) {
                            Ty::Word
                        } else {
                            Ty::Byte
                        }
                    }
                    Ty::Void => Ty::Void,
                    other => {
                        let n = self.name(other);
                        self.err(
                            Code::TypeMismatch,
                            base.span,
                            format!("type mismatch: {n} is not an array"),
                        );
                        Ty::Void
                    }
                }
            }
            ExprKind::Deref(base) => match self.expr(base, None) {
                Ty::Ref(t) if *t != Ty::Void => (*t).clone(),
                Ty::Void => Ty::Void,
                other => {
                    let n = self.name(&other);
                    self.err(
                        Code::TypeMismatch,
                        e.span,
                        format!("type mismatch: ^ needs a REF_TO value, found {n}"),
                    );
                    Ty::Void
                }
            },
            ExprKind::Unary(op, a) => {
                let t = self.expr(a, hint);
                match op {
                    UnOp::Not => {
                        if t == Ty::Bool || t.is_bits() || t.is_int() || t == Ty::Void {
                            t
                        } else {
                            let n = self.name(&t);
                            self.err(
                                Code::TypeMismatch,
                                e.span,
                                format!("type mismatch: NOT applied to {n}"),
                            );
                            Ty::Void
                        }
                    }
                    UnOp::Neg | UnOp::Plus => {
                        if t.is_num() || t.is_duration() || t == Ty::Void {
                            t
                        } else {
                            let n = self.name(&t);
                            self.err(
                                Code::TypeMismatch,
                                e.span,
                                format!(
                                    "type mismatch: unary {} applied to {n}",
                                    if *op == UnOp::Neg { "-" } else { "+" }
                                ),
                            );
                            Ty::Void
                        }
                    }
                }
            }
            ExprKind::Binary(op, a, b) => self.binary(e, *op, a, b, hint),
            ExprKind::Call(callee, args) => self.call(e, callee, args, hint),
        }
    }

    fn binary(&mut self, e: &Expr, op: BinOp, a: &Expr, b: &Expr, hint: Option<&Ty>) -> Ty {
        let cmp = matches!(
            op,
            BinOp::Lt | BinOp::Gt | BinOp::Le | BinOp::Ge | BinOp::Eq | BinOp::Ne
        );
        let logic = matches!(op, BinOp::And | BinOp::Or | BinOp::Xor);
        let h = if cmp { None } else { hint };
        // an untyped literal takes the other operand's type; a real literal next to an
        // integer takes the expected REAL/LREAL of the whole expression
        let lit_hint = |other: &Ty, lit: &Expr| -> Ty {
            match (&lit.kind, h) {
                (ExprKind::Literal(Literal::Real(..)), Some(o))
                    if other.is_int() && o.is_real() =>
                {
                    o.clone()
                }
                _ => other.clone(),
            }
        };
        let (ta, tb) = if is_untyped_literal(a) && !is_untyped_literal(b) {
            let tb = self.expr(b, h);
            let hint = lit_hint(&tb, a);
            (self.expr(a, Some(&hint)), tb)
        } else {
            let ta = self.expr(a, h);
            let hint = lit_hint(&ta, b);
            (ta.clone(), self.expr(b, Some(&hint)))
        };
        let ta = if is_untyped_literal(a) && is_untyped_literal(b) && ta != tb {
            self.expr(a, Some(&tb))
        } else {
            ta
        };
        if ta == Ty::Void || tb == Ty::Void {
            return if cmp { Ty::Bool } else { Ty::Void };
        }
        let mismatch = |s: &mut Self| {
            let (x, y) = (s.name(&ta), s.name(&tb));
            s.err(
                Code::TypeMismatch,
                e.span,
                format!(
                    "type mismatch: operator {} cannot be applied to {x} and {y}",
                    op.symbol()
                ),
            );
            if cmp {
                Ty::Bool
            } else {
                Ty::Void
            }
        };
        // references: only (in)equality, of references to the same type or NULL
        if matches!(ta, Ty::Ref(_)) || matches!(tb, Ty::Ref(_)) {
            let same = ta.converts_to(&tb) || tb.converts_to(&ta);
            return if matches!(op, BinOp::Eq | BinOp::Ne) && same {
                Ty::Bool
            } else {
                mismatch(self)
            };
        }
        // time arithmetic
        if ta.is_time_like() || tb.is_time_like() {
            let r = match Ty::time_arith(op, &ta, &tb) {
                Some(t) => Some(t),
                _ if cmp => {
                    if let Some(c) = Ty::common(&ta, &tb) {
                        self.coerce_pair(a, &ta, b, &tb, &c);
                        return Ty::Bool;
                    }
                    None
                }
                _ => None,
            };
            return match r {
                Some(t) => t,
                None => mismatch(self),
            };
        }
        if cmp {
            if ta == tb {
                return Ty::Bool;
            }
            return match Ty::common(&ta, &tb) {
                Some(c) if ta.is_elementary() && tb.is_elementary() => {
                    self.coerce_pair(a, &ta, b, &tb, &c);
                    Ty::Bool
                }
                _ => mismatch(self),
            };
        }
        if logic {
            let ok = |t: &Ty| *t == Ty::Bool || t.is_bits() || t.is_int();
            if !ok(&ta) || !ok(&tb) {
                return mismatch(self);
            }
            return match Ty::common(&ta, &tb) {
                Some(c) => {
                    self.coerce_pair(a, &ta, b, &tb, &c);
                    c
                }
                None => mismatch(self),
            };
        }
        // arithmetic
        if op == BinOp::Pow {
            if !ta.is_num() || !tb.is_num() {
                return mismatch(self);
            }
            let r = if ta == Ty::Real && (tb.is_int() || tb == Ty::Real) {
                Ty::Real
            } else {
                Ty::LReal
            };
            self.coerce_pair(a, &ta, b, &tb, &r);
            return r;
        }
        if !(ta.is_num() || ta.is_bits()) || !(tb.is_num() || tb.is_bits()) {
            return mismatch(self);
        }
        if op == BinOp::Mod && (ta.is_real() || tb.is_real()) {
            return mismatch(self);
        }
        match Ty::common(&ta, &tb) {
            Some(c) => {
                self.coerce_pair(a, &ta, b, &tb, &c);
                c
            }
            None => mismatch(self),
        }
    }

    fn coerce_pair(&mut self, a: &Expr, ta: &Ty, b: &Expr, tb: &Ty, c: &Ty) {
        if ta != c && ta.is_elementary() {
            self.c.coerce.insert(a.id, c.clone());
        }
        if tb != c && tb.is_elementary() {
            self.c.coerce.insert(b.id, c.clone());
        }
    }

    fn call(&mut self, e: &Expr, callee: &Expr, args: &[Arg], hint: Option<&Ty>) -> Ty {
        let name = match &callee.kind {
            ExprKind::Name { ident, .. } => Some(ident.clone()),
            _ => None,
        };
        if let Some(ident) = &name {
            let is_var = self
                .pou
                .and_then(|p| self.c.pou(p))
                .and_then(|p| p.var(&ident.key))
                .is_some()
                && !matches!(self.pou.and_then(|p| self.c.pou(p)).map(|p| p.kind), Some(PouKind::Function) if self.pou.and_then(|p| self.c.pou(p)).and_then(|p| p.var(&ident.key)).map(|(i, _)| i) == Some(0));
            if !is_var && !self.c.global_index.contains_key(&ident.key) {
                if let Some(&pid) = self.c.pou_index.get(&ident.key) {
                    let kind = self.c.pou(pid).map(|p| p.kind);
                    if kind == Some(PouKind::Function) {
                        self.c.res.insert(e.id, Res::CallFunction(pid));
                        self.calls.push((pid, e.span));
                        self.call_args(pid, args, e.span, false);
                        let r = self
                            .c
                            .pou(pid)
                            .and_then(|p| p.ret.clone())
                            .unwrap_or(Ty::Void);
                        return r;
                    }
                    self.err(
                        Code::WrongArguments,
                        callee.span,
                        format!(
                            "'{}' is a {} and cannot be called like a function",
                            ident.name,
                            if kind == Some(PouKind::Program) {
                                "program"
                            } else {
                                "function block type; call an instance"
                            }
                        ),
                    );
                    return Ty::Void;
                }
                if ident.key == "REF" {
                    return self.reference(e, args);
                }
                if let Some(b) = stdlib::lookup(&ident.key) {
                    return self.builtin(e, ident, b, args, hint);
                }
                self.err(
                    Code::Undeclared,
                    callee.span,
                    format!("undeclared function '{}'", ident.name),
                );
                for a in args {
                    self.expr(&a.value, None);
                }
                return Ty::Void;
            }
        }
        let t = self.expr(callee, None);
        if let Ty::Fb(_) = t {
            self.err(Code::WrongArguments, e.span, "a function block call is a statement, not an expression; read its outputs as inst.Q");
        } else if t != Ty::Void {
            self.err(Code::WrongArguments, callee.span, "this is not a function");
        }
        Ty::Void
    }

    fn builtin(
        &mut self,
        e: &Expr,
        ident: &Ident,
        b: Builtin,
        args: &[Arg],
        hint: Option<&Ty>,
    ) -> Ty {
        if let Some(params) = stdlib::params(&b) {
            return self.named_builtin(e, ident, b, &params, args);
        }
        if let Some(a) = args.iter().find(|a| a.output) {
            self.err(
                Code::WrongArguments,
                a.value.span,
                format!("{} has no outputs", ident.name),
            );
            return Ty::Void;
        }
        // natural types first (untyped literals typed after the others)
        let mut tys: Vec<Ty> = vec![Ty::Void; args.len()];
        for (i, a) in args.iter().enumerate() {
            if !is_untyped_literal(&a.value) {
                if let Some(s) = tys.get_mut(i) {
                    *s = self.expr(&a.value, None);
                }
            }
        }
        let typed_hint = match &b {
            Builtin::Convert(Some(from), _)
            | Builtin::TruncTo(Some(from), _)
            | Builtin::BcdTo(Some(from), _)
            | Builtin::ToBcd(from, _) => Some(from.clone()),
            _ => tys
                .iter()
                .skip(usize::from(matches!(b, Builtin::Mux | Builtin::Sel)))
                .find(|t| **t != Ty::Void)
                .cloned()
                .or_else(|| hint.filter(|h| h.is_num() || h.is_bits()).cloned()),
        };
        for (i, a) in args.iter().enumerate() {
            if is_untyped_literal(&a.value) {
                let h = typed_hint.clone();
                if let Some(s) = tys.get_mut(i) {
                    *s = self.expr(&a.value, h.as_ref());
                }
            }
        }
        if tys.contains(&Ty::Void) {
            return Ty::Void;
        }
        if let Builtin::Arith(op @ (BinOp::Add | BinOp::Sub | BinOp::Mul | BinOp::Div)) = b {
            if tys.iter().any(Ty::is_time_like) {
                return self.time_function(e, ident, op, &tys);
            }
        }
        match stdlib::signature(&b, &tys) {
            Ok((params, ret)) => {
                for ((a, t), p) in args.iter().zip(&tys).zip(&params) {
                    // `SEL(0, a, b)`: the literal was typed like the other arguments first
                    let t = match &a.value.kind {
                        ExprKind::Literal(Literal::Int(0 | 1, None))
                            if *p == Ty::Bool && *t != Ty::Bool =>
                        {
                            &self.expr(&a.value, Some(&Ty::Bool))
                        }
                        _ => t,
                    };
                    if !self.coerce_to(&a.value, t, p, "argument") {
                        return Ty::Void;
                    }
                }
                self.c.res.insert(e.id, Res::CallBuiltin(b));
                ret
            }
            Err(msg) => {
                self.err(
                    Code::WrongArguments,
                    e.span,
                    format!("wrong arguments to {}: {msg}", ident.name),
                );
                Ty::Void
            }
        }
    }

    /// A built-in with named parameters and outputs ([`stdlib::params`]): `CONCAT_DT(YEAR
    /// := y, ...)`, `SPLIT_DT(IN := d, YEAR => y, ...)` or the same without names, in order.
    fn named_builtin(
        &mut self,
        e: &Expr,
        ident: &Ident,
        b: Builtin,
        params: &[stdlib::Param],
        args: &[Arg],
    ) -> Ty {
        use crate::stdlib::time::{self as t, Field};
        let is_stmt = self.stmt_call == Some(e.id);
        self.stmt_call = None;
        let fname = &ident.name;
        let mut ok = true;
        let mut given: Vec<usize> = Vec::new();
        // literal inputs, checked now: a wrong one would fault on every call
        let mut constants = t::Fields::default();
        let mut constant: Vec<(Field, Span)> = Vec::new();
        for (a, bound) in args.iter().zip(stdlib::bind_args(params, args)) {
            let at = a.name.as_ref().map_or(a.value.span, |n| n.span);
            let (i, p) = match bound.map(|i| (i, params.get(i))) {
                Ok((i, Some(p))) => (i, *p),
                Ok((_, None)) => continue,
                Err(err) => {
                    let msg = match &err {
                        stdlib::ArgError::Unknown(n) => {
                            format!("'{fname}' has no parameter '{n}'")
                        }
                        stdlib::ArgError::TooMany(n) => {
                            format!("too many arguments to '{fname}': it has {n} parameters")
                        }
                        stdlib::ArgError::NotOutput(n) => {
                            format!("'{n}' is an input of '{fname}', not an output")
                        }
                        stdlib::ArgError::NotInput(n) => {
                            format!("'{n}' is an output of '{fname}': bind it with '{n} =>'")
                        }
                        stdlib::ArgError::Twice(n) => {
                            format!("'{n}' of '{fname}' given more than once")
                        }
                        stdlib::ArgError::AfterNamed => {
                            "positional argument after named arguments".to_string()
                        }
                    };
                    self.err(Code::WrongArguments, at, msg);
                    ok = false;
                    if a.output {
                        self.lvalue(&a.value);
                    } else {
                        self.expr(&a.value, None);
                    }
                    continue;
                }
            };
            given.push(i);
            let name = p.name();
            if p.output {
                let t = self.lvalue(&a.value);
                if t == Ty::Void {
                    ok = false;
                    continue;
                }
                let (lo, hi) = p.field.map_or((0, 0), Field::range);
                let fits = t
                    .int_range()
                    .is_some_and(|(a, b)| a <= i128::from(lo) && i128::from(hi) <= b);
                if a.negated || !t.is_int() {
                    let tn = self.name(&t);
                    self.err(Code::TypeMismatch, a.value.span, format!("type mismatch: output '{name}' of {fname} is an integer (ANY_INT), bound to a variable of type {tn}"));
                    ok = false;
                } else if !fits {
                    let tn = self.name(&t);
                    self.err(Code::TypeMismatch, a.value.span, format!("type mismatch: output '{name}' of {fname} ({lo}..{hi}) does not fit a variable of type {tn}"));
                    ok = false;
                }
                continue;
            }
            match p.field {
                None => {
                    let want = match b {
                        Builtin::SplitParts(parts) => parts.ty(),
                        _ => Ty::Void,
                    };
                    let t = self.expr(&a.value, Some(&want));
                    ok &= t != Ty::Void
                        && self.coerce_to(&a.value, &t, &want, &format!("argument '{name}'"));
                }
                Some(field) => {
                    let t = self.expr(&a.value, None);
                    if t == Ty::Void {
                        ok = false;
                    } else if !t.is_int() {
                        let tn = self.name(&t);
                        self.err(Code::TypeMismatch, a.value.span, format!("type mismatch: argument '{name}' of {fname} of type {tn} where an integer (ANY_INT) is expected"));
                        ok = false;
                    } else if let Some(v) = int_literal(&a.value) {
                        let (lo, hi) = field.range();
                        if v < i128::from(lo) || v > i128::from(hi) {
                            self.err(
                                Code::TypeMismatch,
                                a.value.span,
                                format!("{name} {v} is outside {lo}..{hi}"),
                            );
                            ok = false;
                        }
                        constants.set(field, v);
                        constant.push((field, a.value.span));
                    }
                }
            }
        }
        // the day of a constant date (`CONCAT_DATE(2023, 2, 29)`)
        let known = |f| constant.iter().find(|(g, _)| *g == f).map(|(_, s)| *s);
        if let (true, Some(_), Some(_), Some(span)) = (
            ok,
            known(Field::Year),
            known(Field::Month),
            known(Field::Day),
        ) {
            let date = t::Fields {
                year: constants.year,
                month: constants.month,
                day: constants.day,
                ..t::Fields::default()
            };
            if let Err(err @ t::FieldsError::NoSuchDay { .. }) = t::concat(t::Parts::Date, &date) {
                self.err(Code::TypeMismatch, span, err.to_string());
                ok = false;
            }
        }
        let inputs: Vec<&str> = params
            .iter()
            .filter(|p| !p.output && !p.named_only)
            .map(stdlib::Param::name)
            .collect();
        let non_formal = !args.is_empty() && args.iter().all(|a| a.name.is_none());
        let required: Vec<&str> = params
            .iter()
            .enumerate()
            .filter(|(i, p)| p.required && !given.contains(i))
            .map(|(_, p)| p.name())
            .collect();
        if non_formal && args.len() < inputs.len() {
            // IEC 61131-3: a call without names gives every input, in order
            let missing = inputs.get(args.len()..).unwrap_or_default().join(", ");
            self.diags.push(
                Diagnostic::error(
                    Code::WrongArguments,
                    e.span,
                    format!(
                        "too few arguments to '{fname}': {} of {} input(s) given, missing {missing}",
                        args.len(),
                        inputs.len(),
                    ),
                )
                .with_note("with names (`YEAR := ...`) the time fields may be left out, at 0"),
            );
            ok = false;
        } else if ok && !required.is_empty() {
            self.err(
                Code::WrongArguments,
                e.span,
                format!("'{fname}' needs {}", required.join(", ")),
            );
            ok = false;
        }
        let ret = match b {
            Builtin::ConcatParts(parts) => parts.ty(),
            _ if is_stmt => Ty::Void,
            _ => {
                self.err(Code::WrongArguments, e.span, format!("'{fname}' has no result: call it as a statement and bind its outputs with `=>`"));
                return Ty::Void;
            }
        };
        if ok {
            self.c.res.insert(e.id, Res::CallBuiltin(b));
        }
        ret
    }

    /// `REF(x)`: the address of a variable (or of a member or element of one).
    fn reference(&mut self, e: &Expr, args: &[Arg]) -> Ty {
        let [arg] = args else {
            self.err(
                Code::WrongArguments,
                e.span,
                format!("REF takes one variable, got {} arguments", args.len()),
            );
            for a in args {
                self.expr(&a.value, None);
            }
            return Ty::Void;
        };
        if arg.name.is_some() || arg.output {
            self.err(
                Code::WrongArguments,
                arg.value.span,
                "REF takes one variable, without a parameter name",
            );
            return Ty::Void;
        }
        let t = self.expr(&arg.value, None);
        if t == Ty::Void {
            return Ty::Void;
        }
        // what has an address of its own: variables, members, elements (not bits, parts,
        // characters, I/O addresses or values)
        let mut root = &arg.value;
        let addressable = loop {
            match &root.kind {
                ExprKind::Name { .. } => {
                    break matches!(
                        self.c.res.get(&root.id),
                        Some(Res::Local(_) | Res::Global(_))
                    )
                }
                ExprKind::Member(b, _) => root = b,
                ExprKind::Index(b, _) if matches!(self.c.ty(b.id), Ty::Array(_)) => root = b,
                ExprKind::Deref(_) => break true,
                _ => break false,
            }
        };
        let program_member = matches!(&arg.value.kind, ExprKind::Member(b, _) if matches!(self.c.res.get(&b.id), Some(Res::Program(_))));
        if !addressable && !program_member {
            self.err(
                Code::NotAssignable,
                arg.value.span,
                "REF needs a variable, a member or an array element",
            );
            return Ty::Void;
        }
        if self.is_constant(&arg.value) {
            self.err(
                Code::NotAssignable,
                arg.value.span,
                "REF of a constant would let it be written",
            );
            return Ty::Void;
        }
        self.c.res.insert(e.id, Res::CallBuiltin(Builtin::Ref));
        Ty::Ref(Rc::new(t))
    }

    /// Whether an access designates (part of) a CONSTANT variable.
    fn is_constant(&self, e: &Expr) -> bool {
        match &e.kind {
            ExprKind::Name { .. } => match self.c.res.get(&e.id) {
                Some(Res::Local(i)) => self
                    .pou
                    .and_then(|p| self.c.pou(p))
                    .and_then(|p| p.vars.get(*i))
                    .is_some_and(|v| v.constant),
                Some(Res::Global(g)) => self.c.globals.get(*g).is_some_and(|v| v.constant),
                _ => false,
            },
            ExprKind::Member(b, _) | ExprKind::Index(b, _) => self.is_constant(b),
            _ => false,
        }
    }

    /// `ADD`, `SUB`, `MUL`, `DIV` of times: what the operators accept, folded left to
    /// right (`ADD(TOD, TIME, TIME)` is `TOD + TIME + TIME`).
    fn time_function(&mut self, e: &Expr, ident: &Ident, op: BinOp, tys: &[Ty]) -> Ty {
        let binary = matches!(op, BinOp::Sub | BinOp::Div);
        if tys.len() < 2 || (binary && tys.len() != 2) {
            let want = if binary { "2" } else { "at least 2" };
            self.err(
                Code::WrongArguments,
                e.span,
                format!(
                    "wrong arguments to {}: expects {want} arguments, got {}",
                    ident.name,
                    tys.len()
                ),
            );
            return Ty::Void;
        }
        let mut acc = tys.first().cloned().unwrap_or(Ty::Void);
        for t in tys.iter().skip(1) {
            match Ty::time_arith(op, &acc, t) {
                Some(r) => acc = r,
                None => {
                    let (x, y) = (self.name(&acc), self.name(t));
                    self.err(
                        Code::WrongArguments,
                        e.span,
                        format!(
                            "wrong arguments to {}: {x} {} {y} is not defined",
                            ident.name,
                            op.symbol()
                        ),
                    );
                    return Ty::Void;
                }
            }
        }
        self.c
            .res
            .insert(e.id, Res::CallBuiltin(Builtin::Arith(op)));
        acc
    }

    fn call_args(&mut self, pid: PouId, args: &[Arg], span: Span, is_fb: bool) {
        let Some(pou) = self.c.pou(pid).cloned() else {
            return;
        };
        let positional: Vec<usize> = pou
            .vars
            .iter()
            .enumerate()
            .filter(|(_, v)| matches!(v.kind, VarKind::Input | VarKind::InOut))
            .map(|(i, _)| i)
            .collect();
        let mut pos = 0usize;
        let mut seen_named = false;
        let mut assigned = HashSet::new();
        for a in args {
            let idx = match &a.name {
                Some(n) => {
                    seen_named = true;
                    match pou.var(&n.key) {
                        Some((i, v)) => {
                            let ok = if a.output {
                                v.kind == VarKind::Output
                                    && !(pou.kind == PouKind::Function && i == 0)
                            } else {
                                matches!(v.kind, VarKind::Input | VarKind::InOut)
                            };
                            if !ok {
                                let what = if a.output { "output" } else { "input" };
                                self.err(
                                    Code::WrongArguments,
                                    n.span,
                                    format!("'{}' is not an {what} of '{}'", n.name, pou.name),
                                );
                                self.expr(&a.value, None);
                                continue;
                            }
                            i
                        }
                        None => {
                            self.err(
                                Code::WrongArguments,
                                n.span,
                                format!("'{}' has no parameter '{}'", pou.name, n.name),
                            );
                            self.expr(&a.value, None);
                            continue;
                        }
                    }
                }
                None => {
                    if seen_named {
                        self.err(
                            Code::WrongArguments,
                            a.value.span,
                            "positional argument after named arguments",
                        );
                        self.expr(&a.value, None);
                        continue;
                    }
                    match positional.get(pos) {
                        Some(&i) => {
                            pos += 1;
                            i
                        }
                        None => {
                            self.err(
                                Code::WrongArguments,
                                a.value.span,
                                format!(
                                    "too many arguments to '{}': it has {} input(s)",
                                    pou.name,
                                    positional.len()
                                ),
                            );
                            self.expr(&a.value, None);
                            continue;
                        }
                    }
                }
            };
            if !assigned.insert((idx, a.output)) {
                self.err(
                    Code::WrongArguments,
                    a.value.span,
                    "parameter given more than once",
                );
            }
            let Some(v) = pou.vars.get(idx) else { continue };
            if a.output {
                let tt = self.lvalue(&a.value);
                let mut vt = v.ty.clone();
                if a.negated {
                    vt = Ty::Bool;
                }
                if tt != Ty::Void && !vt.converts_to(&tt) {
                    let (x, y) = (self.name(&vt), self.name(&tt));
                    self.err(Code::TypeMismatch, a.value.span, format!("type mismatch: output '{}' of type {x} bound to a variable of type {y}", v.name));
                }
            } else if v.kind == VarKind::InOut {
                let t = self.lvalue(&a.value);
                if t != Ty::Void && t != v.ty && !(t.is_string() && v.ty.is_string()) {
                    let (x, y) = (self.name(&t), self.name(&v.ty));
                    self.err(Code::TypeMismatch, a.value.span, format!("type mismatch: VAR_IN_OUT '{}' of type {y} needs a variable of the same type, found {x}", v.name));
                }
            } else {
                let t = self.expr(&a.value, Some(&v.ty));
                self.coerce_to(&a.value, &t, &v.ty, &format!("argument '{}'", v.name));
            }
        }
        // IEC 61131-3: a call without parameter names gives every input, in order
        // (`inst()` with no arguments at all is a call that leaves the inputs as they are)
        let non_formal = !args.is_empty() && args.iter().all(|a| a.name.is_none());
        if non_formal && pos < positional.len() {
            let missing: Vec<&str> = positional
                .iter()
                .skip(pos)
                .filter_map(|&i| pou.vars.get(i))
                .map(|v| v.name.as_str())
                .collect();
            self.diags.push(
                Diagnostic::error(
                    Code::WrongArguments,
                    span,
                    format!(
                        "too few arguments to '{}': {pos} of {} input(s) given, missing {}",
                        pou.name,
                        positional.len(),
                        missing.join(", ")
                    ),
                )
                .with_note("name the inputs (`x := ...`) to leave some at their initial values"),
            );
        }
        // every VAR_IN_OUT must be bound (a too short non-formal list is reported above)
        let too_few = non_formal && pos < positional.len();
        for (i, v) in pou.vars.iter().enumerate() {
            if v.kind == VarKind::InOut && !assigned.contains(&(i, false)) && !too_few {
                self.err(
                    Code::WrongArguments,
                    span,
                    format!("VAR_IN_OUT '{}' of '{}' must be given", v.name, pou.name),
                );
            }
        }
        let _ = is_fb;
    }
}

/// Where an initial value is written.
fn init_span(init: &Init) -> Span {
    match init {
        Init::Expr(e) => e.span,
        Init::Array(_, span) | Init::Struct(_, span) | Init::Default(span) => *span,
    }
}

fn smallest_int(v: i128) -> Ty {
    for t in [Ty::DInt, Ty::LInt, Ty::ULInt] {
        if let Some((lo, hi)) = t.int_range() {
            if v >= lo && v <= hi {
                return t;
            }
        }
    }
    Ty::LInt
}

/// Type of a direct address like `IX0.0`, `QW4`, `MD8`.
pub(crate) fn direct_type(addr: &str) -> Option<Ty> {
    let mut ch = addr.chars();
    let area = ch.next()?;
    if !matches!(area, 'I' | 'Q' | 'M') {
        return None;
    }
    let rest: String = ch.collect();
    let (size, nums) = match rest.chars().next() {
        Some(c) if c.is_ascii_digit() => ('X', rest.as_str()),
        Some(c) => (c, rest.get(1..).unwrap_or("")),
        None => return None,
    };
    let t = match size {
        'X' => Ty::Bool,
        'B' => Ty::Byte,
        'W' => Ty::Word,
        'D' => Ty::DWord,
        'L' => Ty::LWord,
        _ => return None,
    };
    let ok = nums
        .split('.')
        .all(|p| !p.is_empty() && p.chars().all(|c| c.is_ascii_digit()));
    if !ok || nums.is_empty() {
        return None;
    }
    Some(t)
}
