//! Fused closures for the hot paths: integer operations whose operands are constants or
//! statically addressed variables read their operands inline instead of through another
//! closure, and one-index array accesses compute their address inline.
//!
//! Operands come in three forms ([`Src`], [`RSrc`]): an inline leaf ([`Opnd`]: constant or
//! variable), an inline binary operation of two leaves that cannot fault ([`IBin`], [`RBin`]:
//! `i * i`, `x * 0.5`, `n > 3`), or a closure. A fused operation reads its operands without
//! a call when they are inline, and hands its result to a *sink* ([`ISink`], [`RSink`]): the
//! value itself (an expression closure), a store into a statically addressed variable
//! (`x := a + b` in one closure) or a branch (`IF a > b THEN` in one closure).

use super::expr::{Base, Index1, Place};
use super::stmt::{run_block, Wrap};
use super::{Cx, IFn, RFn};
use crate::check::{Lane, Res, Ty};
use crate::syntax::{BinOp, Expr, ExprKind, Literal};
use crate::vm::{Fault, Flow, StmtFn, Vm};
use std::rc::Rc;

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

/// An integer value computed inside a fused closure.
pub(crate) trait IGet: 'static {
    fn eval(&self, vm: &mut Vm) -> Result<i64, Fault>;
}

impl IGet for Opnd {
    #[inline(always)]
    fn eval(&self, vm: &mut Vm) -> Result<i64, Fault> {
        self.get(vm)
    }
}

impl IGet for IFn {
    #[inline(always)]
    fn eval(&self, vm: &mut Vm) -> Result<i64, Fault> {
        self(vm)
    }
}

impl IGet for IBin {
    #[inline(always)]
    fn eval(&self, vm: &mut Vm) -> Result<i64, Fault> {
        let x = self.a.get(vm)?;
        let y = self.b.get(vm)?;
        Ok(self.op.apply(x, y))
    }
}

impl IGet for Elem {
    #[inline(always)]
    fn eval(&self, vm: &mut Vm) -> Result<i64, Fault> {
        self.get(vm)
    }
}

/// An integer cell at a static offset plus one run-time index (`t[i].Q`, `a[i + 1]`).
pub(crate) struct IdxLoad {
    ix: Rc<Index1>,
    off: usize,
    /// Relative to the frame (else absolute).
    frame: bool,
}

impl IGet for IdxLoad {
    #[inline(always)]
    fn eval(&self, vm: &mut Vm) -> Result<i64, Fault> {
        let k = self.ix.eval(vm)?;
        let b = if self.frame { vm.frame.i } else { 0 };
        vm.geti(b + self.off + k * self.ix.stride.i)
    }
}

/// An integer operation that cannot fault, with its wrapping decided at compile time.
#[derive(Clone, Copy)]
pub(crate) enum IOp {
    Add(Wrap),
    Sub(Wrap),
    Mul(Wrap),
    Lt,
    Gt,
    Le,
    Ge,
    LtU,
    GtU,
    LeU,
    GeU,
    Eq,
    Ne,
    And,
    Or,
    Xor,
    /// Signed 32-bit (or narrower) division by a constant.
    DivK(ConstDiv, Wrap),
    /// Signed 32-bit (or narrower) remainder by a constant.
    RemK(ConstDiv, Wrap),
}

impl IOp {
    #[inline(always)]
    fn apply(self, x: i64, y: i64) -> i64 {
        match self {
            IOp::Add(w) => w.apply(x.wrapping_add(y)),
            IOp::Sub(w) => w.apply(x.wrapping_sub(y)),
            IOp::Mul(w) => w.apply(x.wrapping_mul(y)),
            IOp::Lt => i64::from(x < y),
            IOp::Gt => i64::from(x > y),
            IOp::Le => i64::from(x <= y),
            IOp::Ge => i64::from(x >= y),
            IOp::LtU => i64::from((x as u64) < (y as u64)),
            IOp::GtU => i64::from((x as u64) > (y as u64)),
            IOp::LeU => i64::from((x as u64) <= (y as u64)),
            IOp::GeU => i64::from((x as u64) >= (y as u64)),
            IOp::Eq => i64::from(x == y),
            IOp::Ne => i64::from(x != y),
            // BOOL AND/OR of side-effect-free operands: no short circuit needed
            IOp::And => x & y,
            IOp::Or => x | y,
            IOp::Xor => x ^ y,
            IOp::DivK(m, w) => w.apply(m.div(x)),
            IOp::RemK(m, w) => w.apply(m.rem(x)),
        }
    }

    /// The operation `a op b` with operands of type `operand` and result of type
    /// `result`, if it cannot fault (the same results as [`int_binary`] and the generic
    /// operators for these types).
    fn of(op: BinOp, operand: &Ty, result: &Ty, b: Opnd) -> Option<IOp> {
        use BinOp::*;
        let u = matches!(operand, Ty::ULInt | Ty::LWord);
        let w = Wrap::of(result);
        let small_signed = result.bits() <= 32 && result.is_signed_int();
        Some(match op {
            Add => IOp::Add(w),
            Sub => IOp::Sub(w),
            Mul => IOp::Mul(w),
            Lt if u => IOp::LtU,
            Gt if u => IOp::GtU,
            Le if u => IOp::LeU,
            Ge if u => IOp::GeU,
            Lt => IOp::Lt,
            Gt => IOp::Gt,
            Le => IOp::Le,
            Ge => IOp::Ge,
            Eq => IOp::Eq,
            Ne => IOp::Ne,
            And => IOp::And,
            Or => IOp::Or,
            Xor => IOp::Xor,
            Div | Mod if small_signed => {
                let Opnd::K(d) = b else { return None };
                let m = ConstDiv::new(d)?;
                if op == Div {
                    IOp::DivK(m, w)
                } else {
                    IOp::RemK(m, w)
                }
            }
            _ => return None,
        })
    }
}

/// `a op b` of two inline operands that cannot fault, computed inline.
#[derive(Clone, Copy)]
pub(crate) struct IBin {
    op: IOp,
    a: Opnd,
    b: Opnd,
}

/// A compiled integer operand: inline or a closure.
pub(crate) enum Src {
    /// Inline.
    O(Opnd),
    /// Inline binary operation.
    B(IBin),
    /// Closure.
    E(IFn),
}

/// Where a fused integer computation delivers its value.
pub(crate) trait ISink {
    type Out;
    fn build<G: Fn(&mut Vm) -> Result<i64, Fault> + 'static>(self, g: G) -> Self::Out;
}

/// The value itself: an expression closure.
pub(crate) struct Value;

impl ISink for Value {
    type Out = IFn;
    #[inline(always)]
    fn build<G: Fn(&mut Vm) -> Result<i64, Fault> + 'static>(self, g: G) -> IFn {
        Box::new(g)
    }
}

/// A store into a statically addressed integer variable (no subrange, no bit, no I/O):
/// `x := <expression>` as one closure.
#[derive(Clone, Copy)]
pub(crate) struct StoreI {
    /// Cell, relative to the frame or absolute.
    pub(crate) off: usize,
    /// Relative to the frame.
    pub(crate) frame: bool,
}

impl ISink for StoreI {
    type Out = StmtFn;
    #[inline(always)]
    fn build<G: Fn(&mut Vm) -> Result<i64, Fault> + 'static>(self, g: G) -> StmtFn {
        let StoreI { off, frame } = self;
        Box::new(move |vm| {
            let x = g(vm)?;
            let at = if frame { vm.frame.i + off } else { off };
            vm.seti(at, x)?;
            Ok(Flow::Normal)
        })
    }
}

/// `IF cond THEN ... ELSE ... END_IF` with the condition computed inline.
pub(crate) struct Branch {
    pub(crate) then: Vec<StmtFn>,
    pub(crate) els: Vec<StmtFn>,
}

impl ISink for Branch {
    type Out = StmtFn;
    #[inline(always)]
    fn build<G: Fn(&mut Vm) -> Result<i64, Fault> + 'static>(self, g: G) -> StmtFn {
        let Branch { then, els } = self;
        if els.is_empty() {
            return Box::new(move |vm| {
                if g(vm)? != 0 {
                    run_block(&then, vm)
                } else {
                    Ok(Flow::Normal)
                }
            });
        }
        Box::new(move |vm| {
            if g(vm)? != 0 {
                run_block(&then, vm)
            } else {
                run_block(&els, vm)
            }
        })
    }
}

#[inline(always)]
fn build2<P, Q, S, F>(p: P, q: Q, sink: S, f: F) -> S::Out
where
    P: IGet,
    Q: IGet,
    S: ISink,
    F: Fn(i64, i64) -> Result<i64, Fault> + 'static,
{
    sink.build(move |vm| {
        let x = p.eval(vm)?;
        let y = q.eval(vm)?;
        f(x, y)
    })
}

/// `f(a, b)` into `sink`, operands read inline where possible.
fn mk<S, F>(a: Src, b: Src, sink: S, f: F) -> S::Out
where
    S: ISink,
    F: Fn(i64, i64) -> Result<i64, Fault> + 'static,
{
    match (a, b) {
        (Src::O(p), Src::O(q)) => build2(p, q, sink, f),
        (Src::O(p), Src::B(q)) => build2(p, q, sink, f),
        (Src::O(p), Src::E(q)) => build2(p, q, sink, f),
        (Src::B(p), Src::O(q)) => build2(p, q, sink, f),
        (Src::B(p), Src::B(q)) => build2(p, q, sink, f),
        (Src::B(p), Src::E(q)) => build2(p, q, sink, f),
        (Src::E(p), Src::O(q)) => build2(p, q, sink, f),
        (Src::E(p), Src::B(q)) => build2(p, q, sink, f),
        (Src::E(p), Src::E(q)) => build2(p, q, sink, f),
    }
}

/// `f(a)` into `sink`.
fn mk1<S, F>(a: Src, sink: S, f: F) -> S::Out
where
    S: ISink,
    F: Fn(i64) -> i64 + 'static,
{
    match a {
        Src::O(p) => sink.build(move |vm| Ok(f(p.get(vm)?))),
        Src::B(p) => sink.build(move |vm| Ok(f(p.eval(vm)?))),
        Src::E(p) => sink.build(move |vm| Ok(f(p(vm)?))),
    }
}

impl Cx<'_> {
    /// Whether `e`'s implicit conversion (if any) keeps the integer value as it is.
    fn int_unconverted(&self, e: &Expr) -> bool {
        let nat = self.c.ty(e.id);
        let fin = self.c.final_ty(e.id);
        if nat.lane() != Some(Lane::Int) || fin.lane() != Some(Lane::Int) {
            return false;
        }
        nat == fin
            || ((nat.is_int() || nat.is_bits() || nat == Ty::Bool)
                && (fin.is_int() || fin.is_bits())
                && nat.converts_to(&fin))
    }

    /// The expression as an inline operand, if it is an integer constant or a plain
    /// integer-lane variable whose implicit conversion (if any) does not change the value.
    pub(crate) fn simple_int(&self, e: &Expr) -> Option<Opnd> {
        if !self.int_unconverted(e) {
            return None;
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

    /// The expression as an inline binary operation: two inline operands, an operator
    /// that cannot fault, no conversion that changes the value.
    pub(crate) fn inline_bin(&self, e: &Expr) -> Option<IBin> {
        let ExprKind::Binary(op, a, b) = &e.kind else {
            return None;
        };
        if !self.int_unconverted(e) {
            return None;
        }
        let (ta, tb) = (self.c.final_ty(a.id), self.c.final_ty(b.id));
        if ta.lane() != Some(Lane::Int) || tb.lane() != Some(Lane::Int) || timey(&ta) || timey(&tb)
        {
            return None;
        }
        let (pa, pb) = (self.simple_int(a)?, self.simple_int(b)?);
        let op = IOp::of(*op, &ta, &self.c.ty(e.id), pb)?;
        Some(IBin { op, a: pa, b: pb })
    }

    /// An integer operand: inline when simple, else compiled.
    pub(crate) fn int_src(&mut self, e: &Expr) -> Option<Src> {
        if let Some(o) = self.simple_int(e) {
            return Some(Src::O(o));
        }
        if let Some(b) = self.inline_bin(e) {
            return Some(Src::B(b));
        }
        match self.expr(e) {
            super::CE::I(f) => Some(Src::E(f)),
            _ => None,
        }
    }

    /// An integer expression (with its implicit conversion) delivered into `sink`, fused
    /// where the shape allows: the same values and faults as [`Cx::expr`].
    pub(crate) fn int_into<S: ISink>(&mut self, e: &Expr, sink: S) -> S::Out {
        if let Some(o) = self.simple_int(e) {
            return sink.build(move |vm| o.get(vm));
        }
        if let Some(b) = self.inline_bin(e) {
            return sink.build(move |vm| b.eval(vm));
        }
        let place_expr = matches!(e.kind, ExprKind::Index(..) | ExprKind::Member(..))
            && self.c.final_ty(e.id) == self.c.ty(e.id)
            && !matches!(
                self.c.res.get(&e.id),
                Some(Res::EnumValue(_) | Res::WStringLiteral(_))
            );
        if place_expr {
            // as in Cx::expr: the place, loaded
            let Some(p) = self.place(e) else {
                self.error(e.span, "cannot compile this access");
                return sink.build(|_| Ok(0));
            };
            return self.load_into(&p, sink);
        }
        let sink = match self.fused_binary(e, sink) {
            Ok(out) => return out,
            Err(sink) => sink,
        };
        match self.expr(e) {
            super::CE::I(f) => sink.build(move |vm| f(vm)),
            _ => sink.build(|_| Ok(0)),
        }
    }

    /// The integer value at a place into `sink`: the same value and faults as
    /// [`Cx::load`], one-index accesses without an inner call.
    fn load_into<S: ISink>(&self, p: &Place, sink: S) -> S::Out {
        let plain = p.char_ix.is_none()
            && p.direct.is_none()
            && p.bit.is_none()
            && p.ty.lane() == Some(Lane::Int);
        if plain {
            if let Some(el) = Elem::of(p) {
                return sink.build(move |vm| el.get(vm));
            }
            if let (Some(ix), Base::Frame | Base::Abs) = (p.index1.clone(), p.base) {
                let l = IdxLoad {
                    ix,
                    off: p.off.i,
                    frame: p.base == Base::Frame,
                };
                return sink.build(move |vm| l.eval(vm));
            }
        }
        match self.load(p) {
            super::CE::I(f) => sink.build(move |vm| f(vm)),
            _ => sink.build(|_| Ok(0)),
        }
    }

    /// The fused forms of a binary expression without conversion into `sink`; the sink
    /// back if there is none.
    fn fused_binary<S: ISink>(&mut self, e: &Expr, sink: S) -> Result<S::Out, S> {
        if self.c.final_ty(e.id) != self.c.ty(e.id) {
            return Err(sink);
        }
        self.fused_natural(e, sink)
    }

    /// The fused forms of a binary expression (its natural value, before any implicit
    /// conversion) into `sink`; the sink back if there is none.
    pub(crate) fn fused_natural<S: ISink>(&mut self, e: &Expr, sink: S) -> Result<S::Out, S> {
        let ExprKind::Binary(op, a, b) = &e.kind else {
            return Err(sink);
        };
        let ty = self.c.ty(e.id);
        let ta = self.c.final_ty(a.id);
        let tb = self.c.final_ty(b.id);
        let cmp = matches!(
            op,
            BinOp::Lt | BinOp::Gt | BinOp::Le | BinOp::Ge | BinOp::Eq | BinOp::Ne
        );
        if cmp
            && ta == tb
            && ta.lane() == Some(Lane::Int)
            && self.c.ty(a.id) == ta
            && self.c.ty(b.id) == tb
        {
            if let (Some(ea), Some(eb)) = (self.elem_int(a), self.elem_int(b)) {
                return elem_cmp(*op, ea, eb, matches!(ta, Ty::ULInt | Ty::LWord), sink);
            }
        }
        let fusable = matches!(
            op,
            BinOp::Add
                | BinOp::Div
                | BinOp::Mod
                | BinOp::Sub
                | BinOp::Mul
                | BinOp::Lt
                | BinOp::Gt
                | BinOp::Le
                | BinOp::Ge
                | BinOp::Eq
                | BinOp::Ne
                | BinOp::Xor
        ) && ta.lane() == Some(Lane::Int)
            && tb.lane() == Some(Lane::Int)
            && !timey(&ta)
            && !timey(&tb)
            && (self.simple_int(a).is_some() || self.simple_int(b).is_some());
        if fusable {
            if let (Some(sa), Some(sb)) = (self.int_src(a), self.int_src(b)) {
                return int_binary(*op, sa, sb, &ta, &ty, e.span, sink);
            }
            return Err(sink);
        }
        if cmp
            && ta.is_real()
            && ta == tb
            && (self.simple_real(a).is_some() || self.simple_real(b).is_some())
        {
            if let (Some(sa), Some(sb)) = (self.real_src(a), self.real_src(b)) {
                return Ok(real_cmp(*op, sa, sb, sink));
            }
        }
        Err(sink)
    }
}

/// Date and time types (their arithmetic is not fused).
pub(crate) fn timey(t: &Ty) -> bool {
    matches!(t, Ty::Time | Ty::LTime | Ty::Tod | Ty::Dt | Ty::Date)
}

macro_rules! fuse {
    ($a:expr, $b:expr, $sink:expr, |$x:ident, $y:ident| $body:expr) => {
        mk(
            $a,
            $b,
            $sink,
            move |$x: i64, $y: i64| -> Result<i64, Fault> { Ok($body) },
        )
    };
}

/// A fused integer operation, for operators without faults and non-time operand types.
/// `operand` is the (common) operand type, `result` the result type. The sink back if
/// the operator has no fused form.
pub(crate) fn int_binary<S: ISink>(
    op: BinOp,
    a: Src,
    b: Src,
    operand: &Ty,
    result: &Ty,
    span: crate::syntax::Span,
    sink: S,
) -> Result<S::Out, S> {
    use BinOp::*;
    let u64cmp = matches!(operand, Ty::ULInt | Ty::LWord);
    let t = result.clone();
    let zero = move || -> Fault { crate::vm::FaultKind::DivisionByZero(span).into() };
    if let (Div | Mod, Src::O(Opnd::K(d)), true) = (op, &b, t.bits() <= 32 && t.is_signed_int()) {
        if let Some(m) = ConstDiv::new(*d) {
            let w = Wrap::of(&t);
            return Ok(if op == Mod {
                mk1(a, sink, move |x| w.apply(m.rem(x)))
            } else {
                mk1(a, sink, move |x| w.apply(m.div(x)))
            });
        }
    }
    // BOOL AND/OR without short circuit only when the right operand has no effects
    if matches!(op, And | Or) && matches!(b, Src::E(_)) {
        return Err(sink);
    }
    Ok(match op {
        // 32-bit division is several times faster than 64-bit on common CPUs
        Div if t.bits() <= 32 && t.is_signed_int() => fuse!(a, b, sink, |x, y| {
            if y == 0 {
                return Err(zero());
            }
            t.wrap(i64::from((x as i32).wrapping_div(y as i32)))
        }),
        Mod if t.bits() <= 32 && t.is_signed_int() => fuse!(a, b, sink, |x, y| {
            if y == 0 {
                return Err(zero());
            }
            t.wrap(i64::from((x as i32).wrapping_rem(y as i32)))
        }),
        Div if !u64cmp => fuse!(a, b, sink, |x, y| {
            if y == 0 {
                return Err(zero());
            }
            t.wrap(x.wrapping_div(y))
        }),
        Mod if !u64cmp => fuse!(a, b, sink, |x, y| {
            if y == 0 {
                return Err(zero());
            }
            t.wrap(x.wrapping_rem(y))
        }),
        Add => match t {
            Ty::DInt => fuse!(a, b, sink, |x, y| i64::from(x.wrapping_add(y) as i32)),
            Ty::Int => fuse!(a, b, sink, |x, y| i64::from(x.wrapping_add(y) as i16)),
            Ty::LInt | Ty::ULInt | Ty::LWord => fuse!(a, b, sink, |x, y| x.wrapping_add(y)),
            _ => fuse!(a, b, sink, |x, y| t.wrap(x.wrapping_add(y))),
        },
        Sub => match t {
            Ty::DInt => fuse!(a, b, sink, |x, y| i64::from(x.wrapping_sub(y) as i32)),
            Ty::Int => fuse!(a, b, sink, |x, y| i64::from(x.wrapping_sub(y) as i16)),
            _ => fuse!(a, b, sink, |x, y| t.wrap(x.wrapping_sub(y))),
        },
        Mul => match t {
            Ty::DInt => fuse!(a, b, sink, |x, y| i64::from(x.wrapping_mul(y) as i32)),
            _ => fuse!(a, b, sink, |x, y| t.wrap(x.wrapping_mul(y))),
        },
        Lt if u64cmp => fuse!(a, b, sink, |x, y| i64::from((x as u64) < (y as u64))),
        Gt if u64cmp => fuse!(a, b, sink, |x, y| i64::from((x as u64) > (y as u64))),
        Le if u64cmp => fuse!(a, b, sink, |x, y| i64::from((x as u64) <= (y as u64))),
        Ge if u64cmp => fuse!(a, b, sink, |x, y| i64::from((x as u64) >= (y as u64))),
        Lt => fuse!(a, b, sink, |x, y| i64::from(x < y)),
        Gt => fuse!(a, b, sink, |x, y| i64::from(x > y)),
        Le => fuse!(a, b, sink, |x, y| i64::from(x <= y)),
        Ge => fuse!(a, b, sink, |x, y| i64::from(x >= y)),
        Eq => fuse!(a, b, sink, |x, y| i64::from(x == y)),
        Ne => fuse!(a, b, sink, |x, y| i64::from(x != y)),
        Xor => fuse!(a, b, sink, |x, y| x ^ y),
        _ => return Err(sink),
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

/// A real value computed inside a fused closure.
pub(crate) trait RGet: 'static {
    fn eval(&self, vm: &mut Vm) -> Result<f64, Fault>;
}

impl RGet for ROpnd {
    #[inline(always)]
    fn eval(&self, vm: &mut Vm) -> Result<f64, Fault> {
        self.get(vm)
    }
}

impl RGet for RFn {
    #[inline(always)]
    fn eval(&self, vm: &mut Vm) -> Result<f64, Fault> {
        self(vm)
    }
}

/// Real arithmetic (no faults: IEC 60559).
#[derive(Clone, Copy)]
pub(crate) enum ROp {
    Add,
    Sub,
    Mul,
    Div,
}

/// `a op b` of two inline real operands, rounded to REAL if `single`.
#[derive(Clone, Copy)]
pub(crate) struct RBin {
    op: ROp,
    a: ROpnd,
    b: ROpnd,
    single: bool,
}

impl RGet for RBin {
    #[inline(always)]
    fn eval(&self, vm: &mut Vm) -> Result<f64, Fault> {
        let x = self.a.get(vm)?;
        let y = self.b.get(vm)?;
        let r = match self.op {
            ROp::Add => x + y,
            ROp::Sub => x - y,
            ROp::Mul => x * y,
            ROp::Div => x / y,
        };
        Ok(if self.single { f64::from(r as f32) } else { r })
    }
}

/// A compiled real operand.
pub(crate) enum RSrc {
    /// Inline.
    O(ROpnd),
    /// Inline binary operation.
    B(RBin),
    /// Closure.
    E(RFn),
}

/// Where a fused real computation delivers its value.
pub(crate) trait RSink {
    type Out;
    fn build<G: Fn(&mut Vm) -> Result<f64, Fault> + 'static>(self, g: G) -> Self::Out;
}

impl RSink for Value {
    type Out = RFn;
    #[inline(always)]
    fn build<G: Fn(&mut Vm) -> Result<f64, Fault> + 'static>(self, g: G) -> RFn {
        Box::new(g)
    }
}

/// A store into a statically addressed real variable.
#[derive(Clone, Copy)]
pub(crate) struct StoreR {
    /// Cell, relative to the frame or absolute.
    pub(crate) off: usize,
    /// Relative to the frame.
    pub(crate) frame: bool,
}

impl RSink for StoreR {
    type Out = StmtFn;
    #[inline(always)]
    fn build<G: Fn(&mut Vm) -> Result<f64, Fault> + 'static>(self, g: G) -> StmtFn {
        let StoreR { off, frame } = self;
        Box::new(move |vm| {
            let x = g(vm)?;
            let at = if frame { vm.frame.r + off } else { off };
            vm.setr(at, x)?;
            Ok(Flow::Normal)
        })
    }
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

    /// The expression as an inline real arithmetic operation of two inline operands of
    /// its own type, without conversion.
    pub(crate) fn inline_rbin(&self, e: &Expr) -> Option<RBin> {
        let ExprKind::Binary(op, a, b) = &e.kind else {
            return None;
        };
        let ty = self.c.ty(e.id);
        if !ty.is_real() || self.c.final_ty(e.id) != ty {
            return None;
        }
        let (ta, tb) = (self.c.final_ty(a.id), self.c.final_ty(b.id));
        if ta != ty || tb != ty {
            return None;
        }
        let op = match op {
            BinOp::Add => ROp::Add,
            BinOp::Sub => ROp::Sub,
            BinOp::Mul => ROp::Mul,
            BinOp::Div => ROp::Div,
            _ => return None,
        };
        Some(RBin {
            op,
            a: self.simple_real(a)?,
            b: self.simple_real(b)?,
            single: ty == Ty::Real,
        })
    }

    /// A real operand: inline when simple, else compiled.
    pub(crate) fn real_src(&mut self, e: &Expr) -> Option<RSrc> {
        if let Some(o) = self.simple_real(e) {
            return Some(RSrc::O(o));
        }
        if let Some(b) = self.inline_rbin(e) {
            return Some(RSrc::B(b));
        }
        match self.expr(e) {
            super::CE::R(f) => Some(RSrc::E(f)),
            _ => None,
        }
    }

    /// A real expression (with its implicit conversion) delivered into `sink`, fused where
    /// the shape allows: the same values as [`Cx::expr`].
    pub(crate) fn real_into<S: RSink>(&mut self, e: &Expr, sink: S) -> S::Out {
        if let Some(o) = self.simple_real(e) {
            return sink.build(move |vm| o.get(vm));
        }
        if let Some(b) = self.inline_rbin(e) {
            return sink.build(move |vm| b.eval(vm));
        }
        let unconverted = self.c.final_ty(e.id) == self.c.ty(e.id);
        if let Some((op, a, b, single)) = self.real_fusable(e).filter(|_| unconverted) {
            if let (Some(op), Some(sa), Some(sb)) = (rop(op), self.real_src(a), self.real_src(b)) {
                return real_arith(op, sa, sb, single, sink);
            }
        }
        match self.expr(e) {
            super::CE::R(f) => sink.build(move |vm| f(vm)),
            _ => sink.build(|_| Ok(0.0)),
        }
    }

    /// `a op b` as a fused real operation: operator, operands and REAL rounding, if the
    /// shape allows (operands of one real type, one of them inline).
    pub(crate) fn real_fusable<'e>(
        &self,
        e: &'e Expr,
    ) -> Option<(BinOp, &'e Expr, &'e Expr, bool)> {
        let ExprKind::Binary(op, a, b) = &e.kind else {
            return None;
        };
        let ty = self.c.ty(e.id);
        let ta = self.c.final_ty(a.id);
        let tb = self.c.final_ty(b.id);
        let ok = ta.is_real()
            && ta == tb
            && !matches!(
                op,
                BinOp::Pow | BinOp::Mod | BinOp::And | BinOp::Or | BinOp::Xor
            )
            && (self.simple_real(a).is_some() || self.simple_real(b).is_some());
        if !ok {
            return None;
        }
        let single = if ty.is_real() {
            ty == Ty::Real
        } else {
            ta == Ty::Real
        };
        Some((*op, a, b, single))
    }
}

fn rop(op: BinOp) -> Option<ROp> {
    Some(match op {
        BinOp::Add => ROp::Add,
        BinOp::Sub => ROp::Sub,
        BinOp::Mul => ROp::Mul,
        BinOp::Div => ROp::Div,
        _ => return None,
    })
}

#[inline(always)]
fn rbuild2<P, Q, S, F>(p: P, q: Q, sink: S, f: F) -> S::Out
where
    P: RGet,
    Q: RGet,
    S: RSink,
    F: Fn(f64, f64) -> f64 + 'static,
{
    sink.build(move |vm| {
        let x = p.eval(vm)?;
        let y = q.eval(vm)?;
        Ok(f(x, y))
    })
}

fn rmk<S: RSink, F: Fn(f64, f64) -> f64 + 'static>(a: RSrc, b: RSrc, sink: S, f: F) -> S::Out {
    match (a, b) {
        (RSrc::O(p), RSrc::O(q)) => rbuild2(p, q, sink, f),
        (RSrc::O(p), RSrc::B(q)) => rbuild2(p, q, sink, f),
        (RSrc::O(p), RSrc::E(q)) => rbuild2(p, q, sink, f),
        (RSrc::B(p), RSrc::O(q)) => rbuild2(p, q, sink, f),
        (RSrc::B(p), RSrc::B(q)) => rbuild2(p, q, sink, f),
        (RSrc::B(p), RSrc::E(q)) => rbuild2(p, q, sink, f),
        (RSrc::E(p), RSrc::O(q)) => rbuild2(p, q, sink, f),
        (RSrc::E(p), RSrc::B(q)) => rbuild2(p, q, sink, f),
        (RSrc::E(p), RSrc::E(q)) => rbuild2(p, q, sink, f),
    }
}

#[inline(always)]
fn rcbuild2<P, Q, S, F>(p: P, q: Q, sink: S, f: F) -> S::Out
where
    P: RGet,
    Q: RGet,
    S: ISink,
    F: Fn(f64, f64) -> bool + 'static,
{
    sink.build(move |vm| {
        let x = p.eval(vm)?;
        let y = q.eval(vm)?;
        Ok(i64::from(f(x, y)))
    })
}

fn rcmk<S: ISink, F: Fn(f64, f64) -> bool + 'static>(a: RSrc, b: RSrc, sink: S, f: F) -> S::Out {
    match (a, b) {
        (RSrc::O(p), RSrc::O(q)) => rcbuild2(p, q, sink, f),
        (RSrc::O(p), RSrc::B(q)) => rcbuild2(p, q, sink, f),
        (RSrc::O(p), RSrc::E(q)) => rcbuild2(p, q, sink, f),
        (RSrc::B(p), RSrc::O(q)) => rcbuild2(p, q, sink, f),
        (RSrc::B(p), RSrc::B(q)) => rcbuild2(p, q, sink, f),
        (RSrc::B(p), RSrc::E(q)) => rcbuild2(p, q, sink, f),
        (RSrc::E(p), RSrc::O(q)) => rcbuild2(p, q, sink, f),
        (RSrc::E(p), RSrc::B(q)) => rcbuild2(p, q, sink, f),
        (RSrc::E(p), RSrc::E(q)) => rcbuild2(p, q, sink, f),
    }
}

/// Fused real arithmetic into `sink`.
pub(crate) fn real_arith<S: RSink>(op: ROp, a: RSrc, b: RSrc, single: bool, sink: S) -> S::Out {
    let fit = move |x: f64| if single { f64::from(x as f32) } else { x };
    match op {
        ROp::Add => rmk(a, b, sink, move |x, y| fit(x + y)),
        ROp::Sub => rmk(a, b, sink, move |x, y| fit(x - y)),
        ROp::Mul => rmk(a, b, sink, move |x, y| fit(x * y)),
        ROp::Div => rmk(a, b, sink, move |x, y| fit(x / y)),
    }
}

/// A fused real comparison into `sink` (`op` must be a comparison).
pub(crate) fn real_cmp<S: ISink>(op: BinOp, a: RSrc, b: RSrc, sink: S) -> S::Out {
    use BinOp::*;
    match op {
        Lt => rcmk(a, b, sink, |x, y| x < y),
        Gt => rcmk(a, b, sink, |x, y| x > y),
        Le => rcmk(a, b, sink, |x, y| x <= y),
        Ge => rcmk(a, b, sink, |x, y| x >= y),
        Eq => rcmk(a, b, sink, |x, y| x == y),
        _ => rcmk(a, b, sink, |x, y| x != y),
    }
}

/// A fused real operation: arithmetic gives a real, comparisons a BOOL.
pub(crate) fn real_binary(op: BinOp, a: RSrc, b: RSrc, single: bool) -> Option<super::CE> {
    use super::CE;
    use BinOp::*;
    Some(match op {
        Add | Sub | Mul | Div => CE::R(real_arith(rop(op)?, a, b, single, Value)),
        Lt | Gt | Le | Ge | Eq | Ne => CE::I(real_cmp(op, a, b, Value)),
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
    wrap: Wrap,
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
        let IdxSrc::Inline(Opnd::F(var), k, wrap) = &ix.f else {
            return None;
        };
        Some(Elem {
            var: *var,
            k: *k,
            wrap: *wrap,
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
        let v = vm.geti(fi + self.var)?;
        // a variable's value is already wrapped to its type (as in Index1::eval)
        let x = if self.k == 0 {
            v
        } else {
            self.wrap.apply(v.wrapping_add(self.k))
        };
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

/// A comparison of two fast array elements (`a[j] > a[j + 1]`) into `sink`.
pub(crate) fn elem_cmp<S: ISink>(
    op: BinOp,
    a: Elem,
    b: Elem,
    unsigned: bool,
    sink: S,
) -> Result<S::Out, S> {
    use BinOp::*;
    macro_rules! cmp {
        (|$x:ident, $y:ident| $body:expr) => {
            sink.build(move |vm: &mut Vm| {
                let $x = a.get(vm)?;
                let $y = b.get(vm)?;
                Ok(i64::from($body))
            })
        };
    }
    Ok(match op {
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
        _ => return Err(sink),
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
