//! Built-in functions: overloads by argument types, named parameters and outputs, the
//! time and date functions.

use super::*;
use crate::stdlib::{self, Builtin};

impl BodyCx<'_> {
    pub(super) fn builtin(
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
}
