//! Expressions and places (l-values).
//!
//! | file | what |
//! |------|------|
//! | `mod.rs` | an expression by kind, literals |
//! | `place.rs` | places: where a value lives, resolving an l-value |
//! | `access.rs` | loading from and storing into a place |
//! | `operator.rs` | unary and binary operators |
//! | `convert.rs` | conversions between types |
//! | `call.rs` | function calls, argument binding |
//! | `reference.rs` | `REF()`, addresses packed into an integer |

use super::{Cx, IFn, CE};
use crate::check::{Res, Ty};
use crate::diagnostics::{Code, Diagnostic};
use crate::stdlib::conv;
use crate::syntax::*;

mod access;
mod call;
mod convert;
mod operator;
mod place;
mod reference;

use operator::unary;

pub(crate) use call::{split_pre, Binder};
pub(crate) use convert::convert;
pub(crate) use operator::binary;
pub(crate) use place::{lvalue_name, Base, IdxSrc, Index1, Place, RangeCheck};
pub(crate) use reference::unpack;

pub(crate) fn konst_i(v: i64) -> IFn {
    Box::new(move |_| Ok(v))
}

impl Cx<'_> {
    pub(crate) fn error(&mut self, span: Span, msg: impl Into<String>) {
        self.diags
            .push(Diagnostic::error(Code::Unsupported, span, msg));
    }

    /// Compiles an expression including its implicit conversion.
    pub(crate) fn expr(&mut self, e: &Expr) -> CE {
        let v = self.expr_natural(e);
        match self.c.coerce.get(&e.id) {
            Some(to) => {
                let from = self.c.ty(e.id);
                convert(v, &from, &to.clone(), self.c)
            }
            None => v,
        }
    }

    fn expr_natural(&mut self, e: &Expr) -> CE {
        let ty = self.c.ty(e.id);
        match &e.kind {
            ExprKind::Literal(l) => literal(l, &ty),
            ExprKind::Name { .. }
            | ExprKind::Member(..)
            | ExprKind::Index(..)
            | ExprKind::Bit(..)
            | ExprKind::Part(..)
            | ExprKind::Deref(_)
            | ExprKind::Direct(_) => {
                match self.c.res.get(&e.id) {
                    Some(Res::EnumValue(v)) => return CE::I(konst_i(*v)),
                    Some(Res::Null) => return CE::I(konst_i(0)),
                    Some(Res::WStringLiteral(s)) => {
                        let s = s.clone();
                        return CE::S(Box::new(move |_| Ok(s.clone())));
                    }
                    _ => {}
                }
                match self.place(e) {
                    Some(p) => self.load(&p),
                    None => {
                        self.error(e.span, "cannot compile this access");
                        CE::I(konst_i(0))
                    }
                }
            }
            ExprKind::TypedEnum(..) => match self.c.res.get(&e.id) {
                Some(Res::EnumValue(v)) => CE::I(konst_i(*v)),
                _ => CE::I(konst_i(0)),
            },
            ExprKind::Unary(op, a) => {
                let v = self.expr(a);
                unary(*op, v, &ty)
            }
            ExprKind::Binary(op, a, b) => {
                if let Ok(f) = self.fused_natural(e, super::fused::Value) {
                    return CE::I(f);
                }
                if let Some((op, a, b, single)) = self.real_fusable(e) {
                    if let (Some(sa), Some(sb)) = (self.real_src(a), self.real_src(b)) {
                        if let Some(f) = super::fused::real_binary(op, sa, sb, single) {
                            return f;
                        }
                    }
                }
                let ta = self.c.final_ty(a.id);
                let tb = self.c.final_ty(b.id);
                let va = self.expr(a);
                let vb = self.expr(b);
                binary(*op, va, vb, &ta, &tb, &ty, e.span)
            }
            ExprKind::Call(_, args) => match self.c.res.get(&e.id).cloned() {
                Some(Res::CallBuiltin(crate::stdlib::Builtin::Ref)) => self.reference(args, e.span),
                Some(Res::CallBuiltin(b)) => self.builtin(&b, args, e),
                Some(Res::CallFunction(pid)) => {
                    let (call, result) = self.call_function(pid, args);
                    let Some(result) = result else {
                        return CE::I(Box::new(move |vm| {
                            call(vm)?;
                            Ok(0)
                        }));
                    };
                    match self.load(&result) {
                        CE::I(l) => CE::I(Box::new(move |vm| {
                            call(vm)?;
                            l(vm)
                        })),
                        CE::R(l) => CE::R(Box::new(move |vm| {
                            call(vm)?;
                            l(vm)
                        })),
                        CE::S(l) => CE::S(Box::new(move |vm| {
                            call(vm)?;
                            l(vm)
                        })),
                    }
                }
                _ => {
                    self.error(e.span, "cannot compile this call");
                    CE::I(konst_i(0))
                }
            },
        }
    }
}

pub(crate) fn contains_call(e: &Expr) -> bool {
    match &e.kind {
        ExprKind::Call(..) => true,
        ExprKind::Unary(_, a)
        | ExprKind::Member(a, _)
        | ExprKind::Bit(a, _)
        | ExprKind::Part(a, ..)
        | ExprKind::Deref(a) => contains_call(a),
        ExprKind::Binary(_, a, b) => contains_call(a) || contains_call(b),
        ExprKind::Index(a, ix) => contains_call(a) || ix.iter().any(contains_call),
        _ => false,
    }
}

fn literal(l: &Literal, ty: &Ty) -> CE {
    match l {
        Literal::Int(v, _) => {
            if ty.is_real() {
                let x = conv::fit_real(*v as f64, ty);
                CE::R(Box::new(move |_| Ok(x)))
            } else {
                CE::I(konst_i(*v as i64))
            }
        }
        Literal::Real(v, _) => {
            let x = conv::fit_real(*v, ty);
            CE::R(Box::new(move |_| Ok(x)))
        }
        Literal::Bool(b) => CE::I(konst_i(i64::from(*b))),
        Literal::String(s, _) => {
            let s = s.clone();
            CE::S(Box::new(move |_| Ok(s.clone())))
        }
        Literal::Time(v, _) => CE::I(konst_i(i64::try_from(*v).unwrap_or(i64::MAX))),
        Literal::Date(v) | Literal::Tod(v) | Literal::Dt(v) => CE::I(konst_i(*v)),
    }
}
