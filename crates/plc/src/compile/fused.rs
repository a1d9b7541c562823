//! Fused closures for the hot paths: integer operations whose operands are constants or
//! statically addressed variables read their operands inline instead of through another
//! closure, and one-index array accesses compute their address inline.

use super::{Cx, IFn};
use crate::check::{Lane, Res, Ty};
use crate::syntax::{BinOp, Expr, ExprKind, Literal};
use crate::vm::{Fault, Vm};

/// An operand read without a closure call.
#[derive(Clone, Copy)]
pub(crate) enum Opnd {
    /// Constant.
    K(i64),
    /// Integer cell relative to the frame.
    F(usize),
    /// Absolute integer cell.
    A(usize),
}

impl Opnd {
    #[inline(always)]
    pub(crate) fn get(self, vm: &Vm) -> Result<i64, Fault> {
        match self {
            Opnd::K(v) => Ok(v),
            Opnd::F(o) => vm.geti(vm.frame.i + o),
            Opnd::A(o) => vm.geti(o),
        }
    }
}

/// A compiled integer operand: inline or a closure.
pub(crate) enum Src {
    /// Inline.
    O(Opnd),
    /// Closure.
    E(IFn),
}

impl Cx<'_> {
    /// The expression as an inline operand, if it is an integer constant or a plain
    /// integer-lane variable whose implicit conversion (if any) does not change the value.
    pub(crate) fn simple_int(&self, e: &Expr) -> Option<Opnd> {
        let nat = self.c.ty(e.id);
        let fin = self.c.final_ty(e.id);
        if nat.lane() != Some(Lane::Int) || fin.lane() != Some(Lane::Int) {
            return None;
        }
        if nat != fin {
            let same = (nat.is_int() || nat.is_bits() || nat == Ty::Bool)
                && (fin.is_int() || fin.is_bits())
                && nat.converts_to(&fin);
            if !same {
                return None;
            }
        }
        match &e.kind {
            ExprKind::Literal(Literal::Int(v, _)) => i64::try_from(*v).ok().map(Opnd::K),
            ExprKind::Literal(Literal::Bool(b)) => Some(Opnd::K(i64::from(*b))),
            ExprKind::Literal(Literal::Time(v, _)) => i64::try_from(*v).ok().map(Opnd::K),
            ExprKind::Literal(Literal::Date(v) | Literal::Tod(v) | Literal::Dt(v)) => {
                Some(Opnd::K(*v))
            }
            ExprKind::Name { .. } => match self.c.res.get(&e.id)? {
                Res::Local(i) => {
                    let v = self.c.pou(self.pou?)?.vars.get(*i)?;
                    if v.kind == crate::syntax::VarKind::InOut {
                        return None;
                    }
                    Some(Opnd::F(v.offset.i))
                }
                Res::Global(g) => Some(Opnd::A(self.c.globals.get(*g)?.offset.i)),
                Res::EnumValue(v) => Some(Opnd::K(*v)),
                _ => None,
            },
            _ => None,
        }
    }

    /// An integer operand: inline when simple, else compiled.
    pub(crate) fn int_src(&mut self, e: &Expr) -> Option<Src> {
        if let Some(o) = self.simple_int(e) {
            return Some(Src::O(o));
        }
        match self.expr(e) {
            super::CE::I(f) => Some(Src::E(f)),
            _ => None,
        }
    }
}

macro_rules! fuse {
    ($a:expr, $b:expr, |$x:ident, $y:ident| $body:expr) => {
        match ($a, $b) {
            (Src::O(p), Src::O(q)) => Box::new(move |vm: &mut Vm| {
                let $x = p.get(vm)?;
                let $y = q.get(vm)?;
                Ok($body)
            }) as IFn,
            (Src::E(f), Src::O(q)) => Box::new(move |vm: &mut Vm| {
                let $x = f(vm)?;
                let $y = q.get(vm)?;
                Ok($body)
            }) as IFn,
            (Src::O(p), Src::E(g)) => Box::new(move |vm: &mut Vm| {
                let $x = p.get(vm)?;
                let $y = g(vm)?;
                Ok($body)
            }) as IFn,
            (Src::E(f), Src::E(g)) => Box::new(move |vm: &mut Vm| {
                let $x = f(vm)?;
                let $y = g(vm)?;
                Ok($body)
            }) as IFn,
        }
    };
}

/// A fused integer operation, for operators without faults and non-time operand types.
/// `operand` is the (common) operand type, `result` the result type.
pub(crate) fn int_binary(
    op: BinOp,
    a: Src,
    b: Src,
    operand: &Ty,
    result: &Ty,
    span: crate::syntax::Span,
) -> Option<IFn> {
    use BinOp::*;
    let u64cmp = matches!(operand, Ty::ULInt | Ty::LWord);
    let t = result.clone();
    let zero = move || -> Fault { crate::vm::FaultKind::DivisionByZero(span).into() };
    if let (Div | Mod, Src::O(Opnd::K(d)), true) = (op, &b, t.bits() <= 32 && t.is_signed_int()) {
        if let Some(m) = ConstDiv::new(*d) {
            let rem = op == Mod;
            return Some(match a {
                Src::O(p) => Box::new(move |vm: &mut Vm| {
                    let x = p.get(vm)?;
                    Ok(t.wrap(if rem { m.rem(x) } else { m.div(x) }))
                }),
                Src::E(f) => Box::new(move |vm: &mut Vm| {
                    let x = f(vm)?;
                    Ok(t.wrap(if rem { m.rem(x) } else { m.div(x) }))
                }),
            });
        }
    }
    Some(match op {
        // 32-bit division is several times faster than 64-bit on common CPUs
        Div if t.bits() <= 32 && t.is_signed_int() => fuse!(a, b, |x, y| {
            if y == 0 {
                return Err(zero());
            }
            t.wrap(i64::from((x as i32).wrapping_div(y as i32)))
        }),
        Mod if t.bits() <= 32 && t.is_signed_int() => fuse!(a, b, |x, y| {
            if y == 0 {
                return Err(zero());
            }
            t.wrap(i64::from((x as i32).wrapping_rem(y as i32)))
        }),
        Div if !u64cmp => fuse!(a, b, |x, y| {
            if y == 0 {
                return Err(zero());
            }
            t.wrap(x.wrapping_div(y))
        }),
        Mod if !u64cmp => fuse!(a, b, |x, y| {
            if y == 0 {
                return Err(zero());
            }
            t.wrap(x.wrapping_rem(y))
        }),
        Add => match t {
            Ty::DInt => fuse!(a, b, |x, y| i64::from(x.wrapping_add(y) as i32)),
            Ty::Int => fuse!(a, b, |x, y| i64::from(x.wrapping_add(y) as i16)),
            Ty::LInt | Ty::ULInt | Ty::LWord => fuse!(a, b, |x, y| x.wrapping_add(y)),
            _ => fuse!(a, b, |x, y| t.wrap(x.wrapping_add(y))),
        },
        Sub => match t {
            Ty::DInt => fuse!(a, b, |x, y| i64::from(x.wrapping_sub(y) as i32)),
            Ty::Int => fuse!(a, b, |x, y| i64::from(x.wrapping_sub(y) as i16)),
            _ => fuse!(a, b, |x, y| t.wrap(x.wrapping_sub(y))),
        },
        Mul => match t {
            Ty::DInt => fuse!(a, b, |x, y| i64::from(x.wrapping_mul(y) as i32)),
            _ => fuse!(a, b, |x, y| t.wrap(x.wrapping_mul(y))),
        },
        Lt if u64cmp => fuse!(a, b, |x, y| i64::from((x as u64) < (y as u64))),
        Gt if u64cmp => fuse!(a, b, |x, y| i64::from((x as u64) > (y as u64))),
        Le if u64cmp => fuse!(a, b, |x, y| i64::from((x as u64) <= (y as u64))),
        Ge if u64cmp => fuse!(a, b, |x, y| i64::from((x as u64) >= (y as u64))),
        Lt => fuse!(a, b, |x, y| i64::from(x < y)),
        Gt => fuse!(a, b, |x, y| i64::from(x > y)),
        Le => fuse!(a, b, |x, y| i64::from(x <= y)),
        Ge => fuse!(a, b, |x, y| i64::from(x >= y)),
        Eq => fuse!(a, b, |x, y| i64::from(x == y)),
        Ne => fuse!(a, b, |x, y| i64::from(x != y)),
        Xor => fuse!(a, b, |x, y| x ^ y),
        _ => return None,
    })
}

/// A real operand read without a closure call.
#[derive(Clone, Copy)]
pub(crate) enum ROpnd {
    /// Constant.
    K(f64),
    /// Real cell relative to the frame.
    F(usize),
    /// Absolute real cell.
    A(usize),
}

impl ROpnd {
    #[inline(always)]
    pub(crate) fn get(self, vm: &Vm) -> Result<f64, Fault> {
        match self {
            ROpnd::K(v) => Ok(v),
            ROpnd::F(o) => vm.getr(vm.frame.r + o),
            ROpnd::A(o) => vm.getr(o),
        }
    }
}

/// A compiled real operand.
pub(crate) enum RSrc {
    /// Inline.
    O(ROpnd),
    /// Closure.
    E(super::RFn),
}

impl Cx<'_> {
    /// The expression as an inline real operand (same type, no conversion).
    pub(crate) fn simple_real(&self, e: &Expr) -> Option<ROpnd> {
        let nat = self.c.ty(e.id);
        let fin = self.c.final_ty(e.id);
        if !nat.is_real() || nat != fin {
            return None;
        }
        match &e.kind {
            ExprKind::Literal(Literal::Real(v, _)) => {
                Some(ROpnd::K(crate::stdlib::conv::fit_real(*v, &fin)))
            }
            ExprKind::Name { .. } => match self.c.res.get(&e.id)? {
                Res::Local(i) => {
                    let v = self.c.pou(self.pou?)?.vars.get(*i)?;
                    if v.kind == crate::syntax::VarKind::InOut {
                        return None;
                    }
                    Some(ROpnd::F(v.offset.r))
                }
                Res::Global(g) => Some(ROpnd::A(self.c.globals.get(*g)?.offset.r)),
                _ => None,
            },
            _ => None,
        }
    }

    /// A real operand: inline when simple, else compiled.
    pub(crate) fn real_src(&mut self, e: &Expr) -> Option<RSrc> {
        if let Some(o) = self.simple_real(e) {
            return Some(RSrc::O(o));
        }
        match self.expr(e) {
            super::CE::R(f) => Some(RSrc::E(f)),
            _ => None,
        }
    }
}

macro_rules! rfuse {
    ($a:expr, $b:expr, $ret:ty, |$x:ident, $y:ident| $body:expr) => {
        match ($a, $b) {
            (RSrc::O(p), RSrc::O(q)) => Box::new(move |vm: &mut Vm| {
                let $x = p.get(vm)?;
                let $y = q.get(vm)?;
                Ok($body)
            }) as $ret,
            (RSrc::E(f), RSrc::O(q)) => Box::new(move |vm: &mut Vm| {
                let $x = f(vm)?;
                let $y = q.get(vm)?;
                Ok($body)
            }) as $ret,
            (RSrc::O(p), RSrc::E(g)) => Box::new(move |vm: &mut Vm| {
                let $x = p.get(vm)?;
                let $y = g(vm)?;
                Ok($body)
            }) as $ret,
            (RSrc::E(f), RSrc::E(g)) => Box::new(move |vm: &mut Vm| {
                let $x = f(vm)?;
                let $y = g(vm)?;
                Ok($body)
            }) as $ret,
        }
    };
}

/// A fused real operation: arithmetic gives a real, comparisons a BOOL.
pub(crate) fn real_binary(op: BinOp, a: RSrc, b: RSrc, single: bool) -> Option<super::CE> {
    use super::{RFn, CE};
    use BinOp::*;
    let fit = move |x: f64| if single { f64::from(x as f32) } else { x };
    Some(match op {
        Add => CE::R(rfuse!(a, b, RFn, |x, y| fit(x + y))),
        Sub => CE::R(rfuse!(a, b, RFn, |x, y| fit(x - y))),
        Mul => CE::R(rfuse!(a, b, RFn, |x, y| fit(x * y))),
        Div => CE::R(rfuse!(a, b, RFn, |x, y| fit(x / y))),
        Lt => CE::I(rfuse!(a, b, IFn, |x, y| i64::from(x < y))),
        Gt => CE::I(rfuse!(a, b, IFn, |x, y| i64::from(x > y))),
        Le => CE::I(rfuse!(a, b, IFn, |x, y| i64::from(x <= y))),
        Ge => CE::I(rfuse!(a, b, IFn, |x, y| i64::from(x >= y))),
        Eq => CE::I(rfuse!(a, b, IFn, |x, y| i64::from(x == y))),
        Ne => CE::I(rfuse!(a, b, IFn, |x, y| i64::from(x != y))),
        _ => return None,
    })
}

/// An integer array element `a[v + k]` of a local array indexed by a local integer
/// variable, read or written with one closure: index load, wrap, bounds check and the
/// element access inline.
#[derive(Clone, Copy)]
pub(crate) struct Elem {
    /// Frame-relative integer cell of the index variable.
    var: usize,
    /// Constant added to the index.
    k: i64,
    /// Wrapping of `v + k` to the index expression's type.
    wrap: super::stmt::Wrap,
    lo: i64,
    hi: i64,
    /// Integer cells per element.
    stride: usize,
    /// Frame-relative integer cell of the element at `lo`.
    off: usize,
    span: crate::syntax::Span,
}

impl Elem {
    /// The fast form of a place, if it has one.
    pub(crate) fn of(p: &super::expr::Place) -> Option<Elem> {
        use super::expr::{Base, IdxSrc};
        if p.base != Base::Frame
            || p.bit.is_some()
            || p.direct.is_some()
            || p.range.is_some()
            || p.ty.lane() != Some(Lane::Int)
        {
            return None;
        }
        let ix = p.index1.as_ref()?;
        let IdxSrc::Inline(Opnd::F(var), k, t) = &ix.f else {
            return None;
        };
        Some(Elem {
            var: *var,
            k: *k,
            wrap: super::stmt::Wrap::of(t),
            lo: ix.lo,
            hi: ix.hi,
            stride: ix.stride.i,
            off: p.off.i,
            span: ix.span,
        })
    }

    #[inline(always)]
    fn cell(&self, vm: &Vm) -> Result<usize, Fault> {
        let fi = vm.frame.i;
        let x = self
            .wrap
            .apply(vm.geti(fi + self.var)?.wrapping_add(self.k));
        if x < self.lo || x > self.hi {
            return Err(crate::vm::FaultKind::IndexOutOfRange {
                span: self.span,
                index: x,
                lo: self.lo,
                hi: self.hi,
            }
            .into());
        }
        Ok(fi + self.off + (x - self.lo) as usize * self.stride)
    }

    /// The element's value.
    #[inline(always)]
    pub(crate) fn get(&self, vm: &Vm) -> Result<i64, Fault> {
        vm.geti(self.cell(vm)?)
    }

    /// Stores into the element.
    #[inline(always)]
    pub(crate) fn set(&self, vm: &mut Vm, v: i64) -> Result<(), Fault> {
        let at = self.cell(vm)?;
        vm.seti(at, v)
    }
}

/// A comparison of two fast array elements (`a[j] > a[j + 1]`).
pub(crate) fn elem_cmp(op: BinOp, a: Elem, b: Elem, unsigned: bool) -> Option<IFn> {
    use BinOp::*;
    macro_rules! cmp {
        (|$x:ident, $y:ident| $body:expr) => {
            Box::new(move |vm: &mut Vm| {
                let $x = a.get(vm)?;
                let $y = b.get(vm)?;
                Ok(i64::from($body))
            }) as IFn
        };
    }
    Some(match op {
        Lt if unsigned => cmp!(|x, y| (x as u64) < (y as u64)),
        Gt if unsigned => cmp!(|x, y| (x as u64) > (y as u64)),
        Le if unsigned => cmp!(|x, y| (x as u64) <= (y as u64)),
        Ge if unsigned => cmp!(|x, y| (x as u64) >= (y as u64)),
        Lt => cmp!(|x, y| x < y),
        Gt => cmp!(|x, y| x > y),
        Le => cmp!(|x, y| x <= y),
        Ge => cmp!(|x, y| x >= y),
        Eq => cmp!(|x, y| x == y),
        Ne => cmp!(|x, y| x != y),
        _ => return None,
    })
}

impl Cx<'_> {
    /// `e` as a fast array element, if it is `a[v]`/`a[v ± k]` with a local array `a` and
    /// a local integer `v`, read without conversion.
    pub(crate) fn elem_int(&mut self, e: &Expr) -> Option<Elem> {
        let ExprKind::Index(base, idx) = &e.kind else {
            return None;
        };
        if self.c.ty(e.id) != self.c.final_ty(e.id) || idx.len() != 1 {
            return None;
        }
        // only shapes whose place() cannot report anything
        if !matches!(base.kind, ExprKind::Name { .. }) || self.simple_int(base).is_some() {
            return None;
        }
        let ix = idx.first()?;
        if matches!(ix.kind, ExprKind::Literal(_)) {
            return None;
        }
        match self.c.res.get(&base.id)? {
            Res::Local(i) => {
                let v = self.c.pou(self.pou?)?.vars.get(*i)?;
                if v.kind == crate::syntax::VarKind::InOut {
                    return None;
                }
            }
            _ => return None,
        }
        let p = self.place(e)?;
        Elem::of(&p)
    }
}

/// 32-bit signed division and remainder by a constant `d` (`|d| >= 2`) with a multiply
/// instead of a divide instruction (Lemire, Kaser, Kurz: "Faster remainder by direct
/// computation", 2019: exact for every 32-bit dividend). Same results as
/// `(x as i32).wrapping_div(d)` / `wrapping_rem(d)`.
#[derive(Clone, Copy)]
pub(crate) struct ConstDiv {
    m: u64,
    ud: u32,
    neg: bool,
}

impl ConstDiv {
    pub(crate) fn new(d: i64) -> Option<ConstDiv> {
        let d = i32::try_from(d).ok()?;
        let ud = d.unsigned_abs();
        if ud < 2 {
            return None;
        }
        Some(ConstDiv {
            m: (u64::MAX / u64::from(ud)).wrapping_add(1),
            ud,
            neg: d < 0,
        })
    }

    #[inline(always)]
    pub(crate) fn rem(self, x: i64) -> i64 {
        let x = x as i32;
        let low = self.m.wrapping_mul(u64::from(x.unsigned_abs()));
        let r = ((u128::from(low) * u128::from(self.ud)) >> 64) as i64;
        if x < 0 {
            -r
        } else {
            r
        }
    }

    #[inline(always)]
    pub(crate) fn div(self, x: i64) -> i64 {
        let x = x as i32;
        let q = ((u128::from(self.m) * u128::from(x.unsigned_abs())) >> 64) as i64;
        if (x < 0) != self.neg {
            -q
        } else {
            q
        }
    }
}

#[cfg(test)]
mod tests {
    use super::ConstDiv;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn const_div_matches_the_divide_instruction(x in any::<i32>(), d in any::<i32>()) {
            if let Some(m) = ConstDiv::new(i64::from(d)) {
                prop_assert_eq!(m.rem(i64::from(x)), i64::from(x.wrapping_rem(d)));
                prop_assert_eq!(m.div(i64::from(x)), i64::from(x.wrapping_div(d)));
            }
        }
    }

    #[test]
    fn const_div_edge_cases() {
        for d in [2, 3, 7, 10, 1000, -2, -7, i32::MAX, i32::MIN, i32::MIN + 1] {
            let m = ConstDiv::new(i64::from(d)).unwrap();
            for x in [
                0,
                1,
                -1,
                6,
                7,
                -7,
                i32::MAX,
                i32::MIN,
                i32::MIN + 1,
                d,
                d.wrapping_sub(1),
            ] {
                assert_eq!(
                    m.rem(i64::from(x)),
                    i64::from(x.wrapping_rem(d)),
                    "{x} % {d}"
                );
                assert_eq!(
                    m.div(i64::from(x)),
                    i64::from(x.wrapping_div(d)),
                    "{x} / {d}"
                );
            }
        }
        assert!(ConstDiv::new(1).is_none() && ConstDiv::new(-1).is_none());
        assert!(ConstDiv::new(0).is_none() && ConstDiv::new(1 << 40).is_none());
    }
}
