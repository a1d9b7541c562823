//! Initial values: of variables, TYPE declarations and STRUCT members, array
//! initializers with their repetition counts.

use super::*;

impl BodyCx<'_> {
    pub(super) fn init(&mut self, init: &Init, ty: &Ty) {
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
}

/// Where an initial value is written.
fn init_span(init: &Init) -> Span {
    match init {
        Init::Expr(e) => e.span,
        Init::Array(_, span) | Init::Struct(_, span) | Init::Default(span) => *span,
    }
}
