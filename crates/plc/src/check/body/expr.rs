//! Expressions: literals, names, operators, and the types they take from a hint (IEC
//! implicit conversions).

use super::*;

impl BodyCx<'_> {
    pub(super) fn expr(&mut self, e: &Expr, hint: Option<&Ty>) -> Ty {
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
        let mut known: Vec<&str> = self
            .pou
            .and_then(|p| self.c.pou(p))
            .map(|p| p.vars.iter().map(|v| v.name.as_str()).collect())
            .unwrap_or_default();
        known.extend(self.c.globals.iter().map(|g| g.name.as_str()));
        let suggestion = crate::suggest::closest(&ident.name, known.iter().copied());
        let diagnostic = Diagnostic::error(
            Code::Undeclared,
            e.span,
            format!("undeclared name '{}'", ident.name),
        );
        self.diags.push(match suggestion {
            Some(name) => diagnostic.with_note(format!("did you mean `{name}`?")),
            None => diagnostic,
        });
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
