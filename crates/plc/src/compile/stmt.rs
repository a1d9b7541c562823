//! Statements.

use super::expr::konst_i;
use super::{Cx, IFn, CE};
use crate::check::{Lane, PouId, Res, Size};
use crate::syntax::*;
use crate::vm::{Fault, FaultKind, Flow, StmtFn, Vm};

/// Runs statements in order until one does not finish normally.
#[inline]
pub(crate) fn run_block(block: &[StmtFn], vm: &mut Vm) -> Result<Flow, Fault> {
    for s in block {
        let f = s(vm)?;
        if f != Flow::Normal {
            return Ok(f);
        }
    }
    Ok(Flow::Normal)
}

#[inline]
fn tick(vm: &mut Vm, span: Span) -> Result<(), Fault> {
    if vm.budget == 0 {
        return Err(Fault::from(FaultKind::LoopBudget(span)));
    }
    vm.budget -= 1;
    Ok(())
}

/// A FOR loop over a local counter with a constant step and no subrange.
struct LocalFor {
    set_from: StmtFn,
    to: IFn,
    /// Frame-relative cell of the counter.
    o: usize,
    step: i64,
    wrap: Wrap,
    span: Span,
    /// The body cannot write the counter ([`MayWrite`]): the next value is
    /// computed from the current one without reading the cell back.
    kept: bool,
    /// The body never touches the loop budget ([`leaf_body`]).
    leaf: bool,
}

impl LocalFor {
    #[inline(always)]
    fn run(
        &self,
        vm: &mut Vm,
        body: impl Fn(&mut Vm) -> Result<Flow, Fault>,
    ) -> Result<Flow, Fault> {
        let (o, step) = (self.o, self.step);
        (self.set_from)(vm)?;
        let end = (self.to)(vm)?;
        let mut cur = vm.geti(vm.frame.i + o)?;
        // a leaf body does not use the budget: it is counted down here and stored once
        let mut left = vm.budget;
        let r = (|| {
            while !((step >= 0 && cur > end) || (step < 0 && cur < end)) {
                if self.leaf {
                    if left == 0 {
                        return Err(Fault::from(FaultKind::LoopBudget(self.span)));
                    }
                    left -= 1;
                } else {
                    tick(vm, self.span)?;
                }
                match body(vm)? {
                    Flow::Exit => return Ok(Flow::Normal),
                    Flow::Return => return Ok(Flow::Return),
                    _ => {}
                }
                // the body may have changed the variable (unless it cannot: then the cell
                // holds `cur`, which is inside the counter's type while the body runs)
                let at = vm.frame.i + o;
                let now = if self.kept { cur } else { vm.geti(at)? };
                cur = now.saturating_add(step);
                vm.seti(at, self.wrap.apply(cur))?;
            }
            Ok(Flow::Normal)
        })();
        if self.leaf {
            vm.budget = left;
        }
        r
    }
}

/// Whether running `stmts` never touches the loop budget: no loops, no calls other than
/// built-in functions and FBs with a native body.
fn leaf_body(c: &crate::check::Checked, stmts: &[Stmt]) -> bool {
    fn expr(c: &crate::check::Checked, e: &Expr) -> bool {
        let sub = |x: &Expr| expr(c, x);
        match &e.kind {
            ExprKind::Call(callee, args) => {
                let native = match c.res.get(&e.id) {
                    Some(Res::CallBuiltin(_)) => true,
                    Some(Res::CallFb(p)) => c
                        .pou(*p)
                        .is_some_and(|p| crate::stdlib::timers::NativeFb::of(p).is_some()),
                    _ => false,
                };
                native && sub(callee) && args.iter().all(|a| sub(&a.value))
            }
            ExprKind::Member(b, _)
            | ExprKind::Deref(b)
            | ExprKind::Bit(b, _)
            | ExprKind::Part(b, ..)
            | ExprKind::Unary(_, b) => sub(b),
            ExprKind::Index(b, ix) => sub(b) && ix.iter().all(sub),
            ExprKind::Binary(_, a, b) => sub(a) && sub(b),
            ExprKind::Literal(_)
            | ExprKind::Name { .. }
            | ExprKind::TypedEnum(..)
            | ExprKind::Direct(_) => true,
        }
    }
    stmts.iter().all(|s| match &s.kind {
        StmtKind::Assign(t, v) => expr(c, t) && expr(c, v),
        StmtKind::Call(x) => expr(c, x),
        StmtKind::If(arms, els) => {
            arms.iter().all(|(x, b)| expr(c, x) && leaf_body(c, b))
                && els.as_ref().is_none_or(|b| leaf_body(c, b))
        }
        StmtKind::Case(sel, arms, els) => {
            expr(c, sel)
                && arms.iter().all(|(_, b)| leaf_body(c, b))
                && els.as_ref().is_none_or(|b| leaf_body(c, b))
        }
        StmtKind::For { .. } | StmtKind::While(..) | StmtKind::Repeat(..) => false,
        StmtKind::Exit | StmtKind::Continue | StmtKind::Return | StmtKind::Empty => true,
    })
}

/// Whether the statements of a POU may write one of its local variables (conservative):
/// an assignment or FOR counter rooted at it, at a VAR_IN_OUT (which may refer to it), at
/// a program's or FB instance's member (`Main.i`, `g.i`: maybe the running instance) or
/// a dereference; a call with an argument mentioning any of these (VAR_IN_OUT, `=>`); a
/// call of a user FUNCTION or FB (its body may write `Main.i`).
struct MayWrite<'a> {
    c: &'a crate::check::Checked,
    /// The POU's variables.
    vars: &'a [crate::check::VarInfo],
    /// The variable.
    r: &'a Res,
}

impl MayWrite<'_> {
    fn block(&self, stmts: &[Stmt]) -> bool {
        stmts.iter().any(|s| self.stmt(s))
    }

    fn stmt(&self, s: &Stmt) -> bool {
        let e = |x: &Expr| self.expr(x);
        match &s.kind {
            StmtKind::Assign(t, v) => self.rooted(t) || e(t) || e(v),
            StmtKind::Call(x) => e(x),
            StmtKind::If(arms, els) => {
                arms.iter().any(|(x, b)| e(x) || self.block(b))
                    || els.as_ref().is_some_and(|b| self.block(b))
            }
            StmtKind::Case(sel, arms, els) => {
                e(sel)
                    || arms.iter().any(|(_, b)| self.block(b))
                    || els.as_ref().is_some_and(|b| self.block(b))
            }
            StmtKind::For {
                var,
                from,
                to,
                by,
                body,
            } => {
                self.rooted(var)
                    || e(var)
                    || e(from)
                    || e(to)
                    || by.as_ref().is_some_and(&e)
                    || self.block(body)
            }
            StmtKind::While(x, b) | StmtKind::Repeat(b, x) => e(x) || self.block(b),
            StmtKind::Exit | StmtKind::Continue | StmtKind::Return | StmtKind::Empty => false,
        }
    }

    /// The variable itself or a VAR_IN_OUT of the POU.
    fn names_it(&self, e: &Expr) -> bool {
        match self.c.res.get(&e.id) {
            Some(r) if r == self.r => true,
            Some(Res::Local(i)) => self.vars.get(*i).is_none_or(|v| v.kind == VarKind::InOut),
            _ => false,
        }
    }

    /// A call of a user FUNCTION or FB: its body may write a program's variable through
    /// the program's name.
    fn user_call(&self, call: &Expr) -> bool {
        match self.c.res.get(&call.id) {
            Some(Res::CallFb(p) | Res::CallFunction(p)) => self.c.pou(*p).is_none_or(|p| !p.stdlib),
            Some(Res::CallBuiltin(_)) => false,
            _ => true,
        }
    }

    /// `P.x` of a program, or `inst.x` of an FB instance (which may be the one running).
    fn program_member(&self, b: &Expr) -> bool {
        matches!(self.c.res.get(&b.id), Some(Res::Program(_)))
            || matches!(self.c.ty(b.id), crate::check::Ty::Fb(_))
    }

    /// Whether an l-value designates (part of) the variable, or might.
    fn rooted(&self, t: &Expr) -> bool {
        match &t.kind {
            ExprKind::Name { .. } => self.names_it(t),
            ExprKind::Member(b, _) => self.program_member(b) || self.rooted(b),
            ExprKind::Bit(b, _) | ExprKind::Part(b, ..) | ExprKind::Index(b, _) => self.rooted(b),
            ExprKind::Deref(_) => true,
            ExprKind::Literal(_)
            | ExprKind::Unary(..)
            | ExprKind::Binary(..)
            | ExprKind::Call(..)
            | ExprKind::TypedEnum(..)
            | ExprKind::Direct(_) => false,
        }
    }

    /// Whether evaluating `e` may write the variable: a call whose arguments mention it.
    fn expr(&self, e: &Expr) -> bool {
        let sub = |x: &Expr| self.expr(x);
        match &e.kind {
            ExprKind::Call(callee, args) => {
                self.user_call(e) || args.iter().any(|a| self.mentions(&a.value)) || sub(callee)
            }
            // reading writes nothing
            ExprKind::Member(b, _)
            | ExprKind::Deref(b)
            | ExprKind::Bit(b, _)
            | ExprKind::Part(b, ..)
            | ExprKind::Unary(_, b) => sub(b),
            ExprKind::Index(b, ix) => sub(b) || ix.iter().any(sub),
            ExprKind::Binary(_, a, b) => sub(a) || sub(b),
            ExprKind::Literal(_)
            | ExprKind::Name { .. }
            | ExprKind::TypedEnum(..)
            | ExprKind::Direct(_) => false,
        }
    }

    /// Whether the variable (or a VAR_IN_OUT) is named anywhere in `e`.
    fn mentions(&self, e: &Expr) -> bool {
        let sub = |x: &Expr| self.mentions(x);
        match &e.kind {
            ExprKind::Name { .. } => self.names_it(e),
            ExprKind::Call(callee, args) => sub(callee) || args.iter().any(|a| sub(&a.value)),
            ExprKind::Member(b, _) => self.program_member(b) || sub(b),
            ExprKind::Deref(_) => true,
            ExprKind::Bit(b, _) | ExprKind::Part(b, ..) | ExprKind::Unary(_, b) => sub(b),
            ExprKind::Index(b, ix) => sub(b) || ix.iter().any(sub),
            ExprKind::Binary(_, a, b) => sub(a) || sub(b),
            ExprKind::Literal(_) | ExprKind::TypedEnum(..) | ExprKind::Direct(_) => false,
        }
    }
}

/// Label ranges and body of a CASE arm.
type CaseArm = (Vec<(i64, i64)>, Vec<StmtFn>);

/// The address of a function-block instance, computed inline where possible.
enum InstAddr {
    Frame(Size),
    Abs(Size),
    FrameIndexed(Size, std::rc::Rc<super::expr::Index1>),
    AbsIndexed(Size, std::rc::Rc<super::expr::Index1>),
    Dyn(super::AddrFn),
}

impl InstAddr {
    fn of(p: &super::expr::Place) -> InstAddr {
        use super::expr::Base;
        let plain = p.bit.is_none() && p.direct.is_none();
        match (p.base, &p.dynamic, &p.index1) {
            (Base::Frame, None, None) if plain => InstAddr::Frame(p.off),
            (Base::Abs, None, None) if plain => InstAddr::Abs(p.off),
            (Base::Frame, Some(_), Some(ix)) if plain => InstAddr::FrameIndexed(p.off, ix.clone()),
            (Base::Abs, Some(_), Some(ix)) if plain => InstAddr::AbsIndexed(p.off, ix.clone()),
            _ => InstAddr::Dyn(p.addr()),
        }
    }

    #[inline(always)]
    fn get(&self, vm: &mut Vm) -> Result<Size, Fault> {
        match self {
            InstAddr::Frame(o) => Ok(vm.frame.plus(*o)),
            InstAddr::Abs(o) => Ok(*o),
            InstAddr::FrameIndexed(o, ix) => {
                let k = ix.eval(vm)?;
                Ok(vm.frame.plus(*o).plus(ix.stride.times(k)))
            }
            InstAddr::AbsIndexed(o, ix) => {
                let k = ix.eval(vm)?;
                Ok(o.plus(ix.stride.times(k)))
            }
            InstAddr::Dyn(a) => a(vm),
        }
    }
}

/// Where a FOR control variable lives.
enum Cell {
    Frame(usize),
    Abs(usize),
    Dyn(super::AddrFn),
}

impl Cell {
    #[inline(always)]
    fn get(&self, vm: &mut Vm) -> Result<i64, Fault> {
        match self {
            Cell::Frame(o) => vm.geti(vm.frame.i + o),
            Cell::Abs(o) => vm.geti(*o),
            Cell::Dyn(a) => {
                let at = a(vm)?;
                vm.geti(at.i)
            }
        }
    }
    #[inline(always)]
    fn set(&self, vm: &mut Vm, v: i64) -> Result<(), Fault> {
        match self {
            Cell::Frame(o) => vm.seti(vm.frame.i + o, v),
            Cell::Abs(o) => vm.seti(*o, v),
            Cell::Dyn(a) => {
                let at = a(vm)?;
                vm.seti(at.i, v)
            }
        }
    }
}

fn nop() -> StmtFn {
    Box::new(|_| Ok(Flow::Normal))
}

impl Cx<'_> {
    /// The statements of a block; consecutive integer moves (`t := a[j]; a[j] := a[j + 1];
    /// a[j + 1] := t;`) run as one closure.
    pub(crate) fn block(&mut self, stmts: &[Stmt]) -> Vec<StmtFn> {
        let mut out = Vec::new();
        let mut moves: Vec<Move> = Vec::new();
        for s in stmts {
            if matches!(s.kind, StmtKind::Empty) {
                continue;
            }
            if let StmtKind::Assign(target, value) = &s.kind {
                if let Some(m) = self.int_move(target, value) {
                    moves.push(m);
                    continue;
                }
            }
            flush_moves(&mut moves, &mut out);
            out.push(self.stmt(s));
        }
        flush_moves(&mut moves, &mut out);
        out
    }

    fn cond(&mut self, e: &Expr) -> IFn {
        match self.expr(e) {
            CE::I(f) => f,
            _ => konst_i(0),
        }
    }

    fn stmt(&mut self, s: &Stmt) -> StmtFn {
        if matches!(
            s.kind,
            StmtKind::For { .. } | StmtKind::While(..) | StmtKind::Repeat(..)
        ) {
            if let Some(engine) = self.jit.clone() {
                if let Some(mut l) = super::jit::lower_loop(self, &engine, s) {
                    if l.needs_fallback() {
                        self.jit = None;
                        l.fallback = Some(self.stmt(s));
                        self.jit = Some(engine);
                    }
                    return Box::new(move |vm| l.run(vm));
                }
            }
        }
        match &s.kind {
            StmtKind::Assign(target, value) => {
                let tt = self.c.ty(target.id);
                if tt.lane().is_none() {
                    // aggregate copy
                    let size = self.c.size_of(&tt);
                    let (Some(dst), Some(src)) = (self.place(target), self.agg_source(value))
                    else {
                        self.error(s.span, "cannot compile this assignment");
                        return nop();
                    };
                    let da = dst.addr();
                    return Box::new(move |vm| {
                        let from = src(vm)?;
                        let to = da(vm)?;
                        vm.copy(from, to, size)?;
                        Ok(Flow::Normal)
                    });
                }
                if let Some(append) = self.concat_append(target, value) {
                    return append;
                }
                if let Some(copy) = self.int_copy(target, value) {
                    return copy;
                }
                let Some(p) = self.place(target) else {
                    self.error(target.span, "cannot compile this assignment target");
                    return nop();
                };
                let plain = matches!(p.base, super::expr::Base::Frame | super::expr::Base::Abs)
                    && p.dynamic.is_none()
                    && p.index1.is_none()
                    && p.bit.is_none()
                    && p.direct.is_none()
                    && p.range.is_none()
                    && p.char_ix.is_none();
                let frame = p.base == super::expr::Base::Frame;
                let vlane = self.c.final_ty(value.id).lane();
                match (plain, p.ty.lane(), vlane) {
                    (true, Some(Lane::Int), Some(Lane::Int)) => {
                        let off = p.off.i;
                        return self.int_into(value, super::fused::StoreI { off, frame });
                    }
                    (true, Some(Lane::Real), Some(Lane::Real)) => {
                        let off = p.off.r;
                        return self.real_into(value, super::fused::StoreR { off, frame });
                    }
                    _ => {}
                }
                let v = self.expr(value);
                self.store(&p, v)
            }
            StmtKind::Call(e) => self.call_stmt(e),
            StmtKind::If(arms, els) => {
                if let [(c, b)] = arms.as_slice() {
                    let els_moves = match els {
                        Some(e) => self.moves_of(e),
                        None => Some(Vec::new()),
                    };
                    if let (Some(then), Some(els)) = (self.moves_of(b), els_moves) {
                        let sink = BranchMoves {
                            then: then.into_boxed_slice(),
                            els: els.into_boxed_slice(),
                        };
                        return self.int_into(c, sink);
                    }
                    let then = self.block(b);
                    let els = els.as_ref().map(|b| self.block(b)).unwrap_or_default();
                    return self.int_into(c, super::fused::Branch { then, els });
                }
                let arms: Vec<(IFn, Vec<StmtFn>)> = arms
                    .iter()
                    .map(|(c, b)| (self.cond(c), self.block(b)))
                    .collect();
                let els = els.as_ref().map(|b| self.block(b)).unwrap_or_default();
                Box::new(move |vm| {
                    for (c, b) in &arms {
                        if c(vm)? != 0 {
                            return run_block(b, vm);
                        }
                    }
                    run_block(&els, vm)
                })
            }
            StmtKind::Case(sel, arms, els) => {
                let sel = self.cond(sel);
                let mut table: Vec<CaseArm> = Vec::new();
                for (labels, body) in arms {
                    let mut ranges = Vec::new();
                    for l in labels {
                        match l {
                            CaseLabel::Value(e) => match self.const_value(e) {
                                Some(v) => ranges.push((v, v)),
                                None => self.error(e.span, "CASE label must be a constant"),
                            },
                            CaseLabel::Range(a, b) => {
                                match (self.const_value(a), self.const_value(b)) {
                                    (Some(x), Some(y)) => ranges.push((x, y)),
                                    _ => self.error(a.span, "CASE range must be constant"),
                                }
                            }
                        }
                    }
                    table.push((ranges, self.block(body)));
                }
                let els = els.as_ref().map(|b| self.block(b)).unwrap_or_default();
                Box::new(move |vm| {
                    let v = sel(vm)?;
                    for (ranges, body) in &table {
                        if ranges.iter().any(|(lo, hi)| v >= *lo && v <= *hi) {
                            return run_block(body, vm);
                        }
                    }
                    run_block(&els, vm)
                })
            }
            StmtKind::For {
                var,
                from,
                to,
                by,
                body,
            } => {
                let Some(p) = self.place(var).filter(|p| p.char_ix.is_none()) else {
                    self.error(var.span, "cannot compile FOR variable");
                    return nop();
                };
                let vt = p.ty.clone();
                let from_v = self.expr(from);
                let set_from = self.store(&p, from_v);
                let to = self.cond(to);
                let by_const = match by.as_ref() {
                    None => Some(1),
                    Some(b) => match self.simple_int(b) {
                        Some(super::fused::Opnd::K(k)) => Some(k),
                        _ => None,
                    },
                };
                let by = by
                    .as_ref()
                    .map(|b| self.cond(b))
                    .unwrap_or_else(|| konst_i(1));
                let cell = match (p.base, &p.dynamic, &p.bit, p.direct) {
                    (super::expr::Base::Frame, None, None, None) if p.index1.is_none() => {
                        Cell::Frame(p.off.i)
                    }
                    (super::expr::Base::Abs, None, None, None) if p.index1.is_none() => {
                        Cell::Abs(p.off.i)
                    }
                    _ => Cell::Dyn(p.addr()),
                };
                let body_ast = body.as_slice();
                let body = self.block(body);
                let span = s.span;
                // a subrange counter: every value the body runs with is checked; the
                // step past the end is not stored if it leaves the subrange (the counter
                // keeps its last value, IEC leaves it implementation-defined)
                let range = p.range.clone();
                if let (Cell::Frame(o), Some(step), None) = (&cell, by_const, &range) {
                    // the common case: a local counter and a constant step
                    let vars = self
                        .pou
                        .and_then(|p| self.c.pou(p))
                        .map(|p| p.vars.as_slice());
                    let kept = match (self.c.res.get(&var.id), vars) {
                        (Some(r @ Res::Local(_)), Some(vars)) => {
                            !MayWrite { c: self.c, vars, r }.block(body_ast)
                        }
                        _ => false,
                    };
                    let lp = LocalFor {
                        set_from,
                        to,
                        o: *o,
                        step,
                        wrap: Wrap::of(&vt),
                        span,
                        kept,
                        leaf: leaf_body(self.c, body_ast),
                    };
                    let mut body = body;
                    if body.len() == 1 {
                        if let Some(one) = body.pop() {
                            // one statement: called directly
                            return Box::new(move |vm| lp.run(vm, |vm| one(vm)));
                        }
                    }
                    return Box::new(move |vm| lp.run(vm, |vm| run_block(&body, vm)));
                }
                Box::new(move |vm| {
                    set_from(vm)?;
                    let end = to(vm)?;
                    let step = by(vm)?;
                    let mut cur = cell.get(vm)?;
                    loop {
                        if (step >= 0 && cur > end) || (step < 0 && cur < end) {
                            break;
                        }
                        tick(vm, span)?;
                        match run_block(&body, vm)? {
                            Flow::Exit => return Ok(Flow::Normal),
                            Flow::Return => return Ok(Flow::Return),
                            _ => {}
                        }
                        // the body may have changed the variable
                        cur = cell.get(vm)?.saturating_add(step);
                        if let Some(r) = &range {
                            if !r.contains(cur) {
                                if (step >= 0 && cur > end) || (step < 0 && cur < end) {
                                    break;
                                }
                                return Err(r.fault(cur));
                            }
                        }
                        cell.set(vm, vt.wrap(cur))?;
                    }
                    Ok(Flow::Normal)
                })
            }
            StmtKind::While(c, body) => {
                let c = self.cond(c);
                let body = self.block(body);
                let span = s.span;
                Box::new(move |vm| {
                    while c(vm)? != 0 {
                        tick(vm, span)?;
                        match run_block(&body, vm)? {
                            Flow::Exit => break,
                            Flow::Return => return Ok(Flow::Return),
                            _ => {}
                        }
                    }
                    Ok(Flow::Normal)
                })
            }
            StmtKind::Repeat(body, c) => {
                let c = self.cond(c);
                let body = self.block(body);
                let span = s.span;
                Box::new(move |vm| {
                    loop {
                        tick(vm, span)?;
                        match run_block(&body, vm)? {
                            Flow::Exit => break,
                            Flow::Return => return Ok(Flow::Return),
                            _ => {}
                        }
                        if c(vm)? != 0 {
                            break;
                        }
                    }
                    Ok(Flow::Normal)
                })
            }
            StmtKind::Exit => Box::new(|_| Ok(Flow::Exit)),
            StmtKind::Continue => Box::new(|_| Ok(Flow::Continue)),
            StmtKind::Return => Box::new(|_| Ok(Flow::Return)),
            StmtKind::Empty => nop(),
        }
    }

    /// `s := CONCAT(s, a, b, ...)` appends in place instead of copying `s`.
    fn concat_append(&mut self, target: &Expr, value: &Expr) -> Option<StmtFn> {
        let ExprKind::Call(_, args) = &value.kind else {
            return None;
        };
        if !matches!(
            self.c.res.get(&value.id),
            Some(Res::CallBuiltin(crate::stdlib::Builtin::Concat))
        ) {
            return None;
        }
        let first = args.first()?;
        let (ExprKind::Name { .. }, ExprKind::Name { .. }) = (&target.kind, &first.value.kind)
        else {
            return None;
        };
        let same = self.c.res.get(&target.id)? == self.c.res.get(&first.value.id)?;
        if !same || first.name.is_some() {
            return None;
        }
        let p = self.place(target)?;
        let max = match p.ty {
            crate::check::Ty::String(n) | crate::check::Ty::WString(n) => n as usize,
            _ => return None,
        };
        let rest: Vec<Part> = args
            .iter()
            .skip(1)
            .map(|a| match (&a.value.kind, self.expr(&a.value)) {
                // a literal's value is its text (STRING to STRING: no conversion)
                (ExprKind::Literal(Literal::String(s, _)), CE::S(_))
                    if self.c.final_ty(a.value.id) == self.c.ty(a.value.id) =>
                {
                    Some(Part::K(s.clone()))
                }
                (_, CE::S(f)) => Some(Part::E(f)),
                _ => None,
            })
            .collect::<Option<_>>()?;
        let addr = match (p.base, &p.dynamic, &p.bit, p.direct, &p.char_ix) {
            (super::expr::Base::Frame, None, None, None, None) => SAddr::F(p.off.s),
            (super::expr::Base::Abs, None, None, None, None) => SAddr::A(p.off.s),
            _ => SAddr::D(p.addr()),
        };
        if rest.len() == 1 {
            let part = rest.into_iter().next()?;
            return Some(Box::new(move |vm| {
                match &part {
                    Part::K(k) => append(addr.cell(vm)?, k, max),
                    Part::E(f) => {
                        let v = f(vm)?;
                        append(addr.cell(vm)?, &v, max);
                    }
                }
                Ok(Flow::Normal)
            }));
        }
        Some(Box::new(move |vm| {
            // every argument first (one may read the target), then the appends
            let mut vals = Vec::with_capacity(rest.len());
            for part in &rest {
                if let Part::E(f) = part {
                    vals.push(f(vm)?);
                }
            }
            let cell = addr.cell(vm)?;
            let mut vals = vals.into_iter();
            for part in &rest {
                match part {
                    Part::K(k) => append(cell, k, max),
                    Part::E(_) => {
                        if let Some(v) = vals.next() {
                            append(cell, &v, max);
                        }
                    }
                }
            }
            Ok(Flow::Normal)
        }))
    }

    /// `x := y` between integer locals and fast array elements (no conversion, no
    /// subrange): one closure without inner calls.
    fn int_copy(&mut self, target: &Expr, value: &Expr) -> Option<StmtFn> {
        self.int_move(target, value).map(Move::stmt)
    }

    /// The statements as integer moves, if they all are.
    fn moves_of(&mut self, stmts: &[Stmt]) -> Option<Vec<Move>> {
        stmts
            .iter()
            .filter(|s| !matches!(s.kind, StmtKind::Empty))
            .map(|s| match &s.kind {
                StmtKind::Assign(target, value) => self.int_move(target, value),
                _ => None,
            })
            .collect()
    }

    /// `x := y` between integer locals and fast array elements, if it is one.
    fn int_move(&mut self, target: &Expr, value: &Expr) -> Option<Move> {
        let tt = self.c.ty(target.id);
        if tt.lane() != Some(crate::check::Lane::Int) || self.c.final_ty(value.id) != tt {
            return None;
        }
        let val = match self.simple_int(value) {
            Some(o) => MVal::O(o),
            None => MVal::E(self.elem_int(value)?),
        };
        let dst = match &target.kind {
            ExprKind::Name { .. } => {
                let p = self.place(target)?;
                if p.base != super::expr::Base::Frame
                    || p.dynamic.is_some()
                    || p.range.is_some()
                    || p.bit.is_some()
                    || p.direct.is_some()
                {
                    return None;
                }
                MDst::F(p.off.i)
            }
            ExprKind::Index(..) => MDst::E(self.elem_int(target)?),
            _ => return None,
        };
        Some(Move { dst, val })
    }

    /// Value of a constant CASE label.
    pub(crate) fn const_value(&mut self, e: &Expr) -> Option<i64> {
        match &e.kind {
            ExprKind::Literal(Literal::Int(v, _)) => Some(*v as i64),
            ExprKind::Literal(Literal::Bool(b)) => Some(i64::from(*b)),
            ExprKind::Unary(UnOp::Neg, a) => self.const_value(a).map(|v| -v),
            _ => match self.c.res.get(&e.id) {
                Some(Res::EnumValue(v)) => Some(*v),
                _ => {
                    // constant variables: evaluate their initialiser
                    let var = match self.c.res.get(&e.id) {
                        Some(Res::Local(i)) => self
                            .pou
                            .and_then(|p| self.c.pou(p))
                            .and_then(|p| p.vars.get(*i)),
                        Some(Res::Global(g)) => self.c.globals.get(*g),
                        _ => None,
                    };
                    match var {
                        Some(v) if v.constant => match &v.init {
                            Some(Init::Expr(x)) => {
                                let x = x.clone();
                                self.const_value(&x)
                            }
                            _ => Some(0),
                        },
                        _ => None,
                    }
                }
            },
        }
    }

    fn call_stmt(&mut self, e: &Expr) -> StmtFn {
        let ExprKind::Call(callee, args) = &e.kind else {
            return nop();
        };
        match self.c.res.get(&e.id).cloned() {
            Some(Res::CallFb(pid)) => self.fb_call(pid, callee, args),
            Some(Res::CallFunction(pid)) => self.call_function(pid, args).0,
            Some(Res::CallBuiltin(_)) => match self.expr(e) {
                CE::I(f) => Box::new(move |vm| f(vm).map(|_| Flow::Normal)),
                CE::R(f) => Box::new(move |vm| f(vm).map(|_| Flow::Normal)),
                CE::S(f) => Box::new(move |vm| f(vm).map(|_| Flow::Normal)),
            },
            _ => nop(),
        }
    }

    fn fb_call(&mut self, pid: PouId, callee: &Expr, args: &[Arg]) -> StmtFn {
        let Some(pou) = self.c.pou(pid).cloned() else {
            return nop();
        };
        let Some(inst) = self.place(callee) else {
            self.error(callee.span, "cannot compile this instance");
            return nop();
        };
        let addr = std::rc::Rc::new(InstAddr::of(&inst));
        let needs_temps = args.iter().any(|a| super::expr::contains_call(&a.value));
        let (pre, post) = self.bind_args(&pou, args, !needs_temps);
        let (direct, split) = super::expr::split_pre(pre);
        let id = pid.0;
        if split.is_empty() && post.is_empty() {
            if let Some(call) = native_fb_call(&pou, &addr, &direct) {
                return call;
            }
        }
        if split.is_empty() && post.is_empty() {
            // the common case: inputs only
            return Box::new(move |vm| {
                let base = addr.get(vm)?;
                let saved = std::mem::replace(&mut vm.callee, base);
                let r = (|| {
                    for b in &direct {
                        b.run(vm)?;
                    }
                    vm.call(id, base)
                })();
                vm.callee = saved;
                r.map(|_| Flow::Normal)
            });
        }
        Box::new(move |vm| {
            let base = addr.get(vm)?;
            let saved = vm.callee;
            let mut vals = Vec::new();
            for (get, _) in &split {
                vals.push(get(vm)?);
            }
            vm.callee = base;
            let r = (|| {
                for b in &direct {
                    b.run(vm)?;
                }
                for ((_, put), v) in split.iter().zip(vals) {
                    put(vm, v)?;
                }
                vm.call(id, base)?;
                vm.callee = base;
                for p in &post {
                    p(vm)?;
                    vm.callee = base;
                }
                Ok(Flow::Normal)
            })();
            vm.callee = saved;
            r
        })
    }
}

/// A call of a standard FB with a native body ([`crate::stdlib::timers`]) whose arguments
/// are all inline operands: the arguments are written into the instance and the native
/// body runs on it directly, without the generic binding and call machinery.
fn native_fb_call(
    pou: &crate::check::PouInfo,
    addr: &std::rc::Rc<InstAddr>,
    direct: &[super::expr::Binder],
) -> Option<StmtFn> {
    let binds: Vec<(usize, super::fused::Opnd)> = direct
        .iter()
        .map(|b| match b {
            super::expr::Binder::Inline(off, o) => Some((*off, *o)),
            super::expr::Binder::Code(_) => None,
        })
        .collect::<Option<_>>()?;
    let fb = crate::stdlib::timers::NativeFb::of(pou)?;
    let binds = binds.into_boxed_slice();
    // the instance's integer base, computed for the address's shape (the other lanes
    // are not needed: these FBs have integer cells only)
    Some(match &**addr {
        InstAddr::Frame(o) => {
            let o = o.i;
            native_call(move |vm| Ok(vm.frame.i + o), binds, fb)
        }
        InstAddr::Abs(o) => {
            let o = o.i;
            native_call(move |_| Ok(o), binds, fb)
        }
        InstAddr::FrameIndexed(o, ix) => {
            let (o, ix) = (o.i, std::rc::Rc::clone(ix));
            native_call(
                move |vm| {
                    let k = ix.eval(vm)?;
                    Ok(vm.frame.i + o + ix.stride.i.saturating_mul(k))
                },
                binds,
                fb,
            )
        }
        InstAddr::AbsIndexed(o, ix) => {
            let (o, ix) = (o.i, std::rc::Rc::clone(ix));
            native_call(
                move |vm| {
                    let k = ix.eval(vm)?;
                    Ok(o + ix.stride.i.saturating_mul(k))
                },
                binds,
                fb,
            )
        }
        InstAddr::Dyn(a) => {
            let a = std::rc::Rc::clone(a);
            native_call(move |vm| Ok(a(vm)?.i), binds, fb)
        }
    })
}

/// Binds inline arguments into the instance at `base` and runs the native body.
fn native_call<G>(
    base: G,
    binds: Box<[(usize, super::fused::Opnd)]>,
    fb: crate::stdlib::timers::NativeFb,
) -> StmtFn
where
    G: Fn(&mut Vm) -> Result<usize, Fault> + 'static,
{
    Box::new(move |vm| {
        let b = base(vm)?;
        for (off, o) in binds.iter() {
            let x = o.get(vm)?;
            vm.seti(b + off, x)?;
        }
        fb.run(vm, b)?;
        Ok(Flow::Normal)
    })
}

/// An appended CONCAT argument.
enum Part {
    /// A literal.
    K(String),
    /// Anything else.
    E(super::SFn),
}

/// The string cell an in-place CONCAT appends to.
enum SAddr {
    /// Frame-relative.
    F(usize),
    /// Absolute.
    A(usize),
    /// Computed.
    D(super::AddrFn),
}

impl SAddr {
    #[inline(always)]
    fn cell<'v>(&self, vm: &'v mut Vm) -> Result<&'v mut String, Fault> {
        let at = match self {
            SAddr::F(o) => vm.frame.s + o,
            SAddr::A(o) => *o,
            SAddr::D(a) => a(vm)?.s,
        };
        vm.strs.get_mut(at).ok_or_else(Fault::memory)
    }
}

/// Appends `part` to `cell`, keeping at most `max` characters.
#[inline]
fn append(cell: &mut String, part: &str, max: usize) {
    // bytes >= characters: nothing to cut
    if cell.len() + part.len() <= max {
        cell.push_str(part);
        return;
    }
    let room = max.saturating_sub(cell.chars().count());
    cell.extend(part.chars().take(room));
}

/// Where an integer move writes.
#[derive(Clone, Copy)]
enum MDst {
    /// Frame-relative integer cell.
    F(usize),
    /// Fast array element.
    E(super::fused::Elem),
}

/// What an integer move reads.
#[derive(Clone, Copy)]
enum MVal {
    /// Inline operand.
    O(super::fused::Opnd),
    /// Fast array element.
    E(super::fused::Elem),
}

/// `x := y` between integer locals and fast array elements.
#[derive(Clone, Copy)]
struct Move {
    dst: MDst,
    val: MVal,
}

impl Move {
    #[inline(always)]
    fn run(&self, vm: &mut Vm) -> Result<(), Fault> {
        let x = match self.val {
            MVal::O(v) => v.get(vm)?,
            MVal::E(v) => v.get(vm)?,
        };
        match self.dst {
            MDst::F(o) => vm.seti(vm.frame.i + o, x),
            MDst::E(d) => d.set(vm, x),
        }
    }

    /// The move as a statement of its own.
    fn stmt(self) -> StmtFn {
        match (self.dst, self.val) {
            (MDst::F(o), MVal::O(v)) => Box::new(move |vm| {
                let x = v.get(vm)?;
                vm.seti(vm.frame.i + o, x)?;
                Ok(Flow::Normal)
            }),
            (MDst::F(o), MVal::E(v)) => Box::new(move |vm| {
                let x = v.get(vm)?;
                vm.seti(vm.frame.i + o, x)?;
                Ok(Flow::Normal)
            }),
            (MDst::E(d), MVal::O(v)) => Box::new(move |vm| {
                let x = v.get(vm)?;
                d.set(vm, x)?;
                Ok(Flow::Normal)
            }),
            (MDst::E(d), MVal::E(v)) => Box::new(move |vm| {
                let x = v.get(vm)?;
                d.set(vm, x)?;
                Ok(Flow::Normal)
            }),
        }
    }
}

/// `IF cond THEN <moves> ELSE <moves> END_IF` with the condition computed inline: one
/// closure for the whole statement.
struct BranchMoves {
    then: Box<[Move]>,
    els: Box<[Move]>,
}

impl super::fused::ISink for BranchMoves {
    type Out = StmtFn;
    fn build<G: Fn(&mut Vm) -> Result<i64, Fault> + 'static>(self, g: G) -> StmtFn {
        let BranchMoves { then, els } = self;
        Box::new(move |vm| {
            let run = if g(vm)? != 0 { &then } else { &els };
            for m in run.iter() {
                m.run(vm)?;
            }
            Ok(Flow::Normal)
        })
    }
}

/// Appends the pending moves to `out`: one statement, or one closure for a run of them.
fn flush_moves(moves: &mut Vec<Move>, out: &mut Vec<StmtFn>) {
    match moves.len() {
        0 => {}
        1 => out.extend(moves.drain(..).map(Move::stmt)),
        _ => {
            let run: Box<[Move]> = std::mem::take(moves).into_boxed_slice();
            out.push(Box::new(move |vm| {
                for m in run.iter() {
                    m.run(vm)?;
                }
                Ok(Flow::Normal)
            }));
        }
    }
}

/// Wrapping to an integer type's width, decided at compile time.
#[derive(Clone, Copy)]
pub(crate) enum Wrap {
    /// BOOL.
    Bool,
    /// Sign-extend from `64 - n` bits.
    Signed(u32),
    /// Zero-extend from `64 - n` bits.
    Unsigned(u32),
}

impl Wrap {
    pub(crate) fn of(t: &crate::check::Ty) -> Wrap {
        use crate::check::Ty;
        match t {
            Ty::Bool => Wrap::Bool,
            Ty::SInt => Wrap::Signed(56),
            Ty::Int => Wrap::Signed(48),
            Ty::DInt => Wrap::Signed(32),
            Ty::USInt | Ty::Byte => Wrap::Unsigned(56),
            Ty::UInt | Ty::Word => Wrap::Unsigned(48),
            Ty::UDInt | Ty::DWord => Wrap::Unsigned(32),
            _ => Wrap::Signed(0),
        }
    }
    #[inline(always)]
    pub(crate) fn apply(self, v: i64) -> i64 {
        match self {
            Wrap::Bool => i64::from(v != 0),
            Wrap::Signed(n) => v.wrapping_shl(n).wrapping_shr(n),
            Wrap::Unsigned(n) => ((v as u64).wrapping_shl(n).wrapping_shr(n)) as i64,
        }
    }
}
