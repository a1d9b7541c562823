//! Calls of functions and function block instances: arguments bound to parameters,
//! `REF()`.

use super::*;
use crate::stdlib::{self, Builtin};

impl BodyCx<'_> {
    pub(super) fn call(&mut self, e: &Expr, callee: &Expr, args: &[Arg], hint: Option<&Ty>) -> Ty {
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

    pub(super) fn call_args(&mut self, pid: PouId, args: &[Arg], span: Span, is_fb: bool) {
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
