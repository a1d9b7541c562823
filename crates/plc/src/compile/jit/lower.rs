//! Lowering of one loop statement to Cranelift IR, mirroring the closure compiler's
//! semantics operation by operation (wrapping, conversions, evaluation order, faults).

use super::{ctx_offset, Extents, FaultSite, JitEngine, JitLoop};
use crate::check::{Lane, PouId, Res, Size, Ty};
use crate::compile::expr::contains_call;
use crate::compile::expr::lvalue_name;
use crate::compile::Cx;
use crate::syntax::{
    Arg, BinOp, CaseLabel, Expr, ExprKind, Init, Item, Literal, PouKind, Span, Stmt, StmtKind,
    UnOp, VarKind,
};
use cranelift_codegen::ir::condcodes::{FloatCC, IntCC};
use cranelift_codegen::ir::{types, AbiParam, Block, InstBuilder, MemFlagsData, Type, Value};
use cranelift_frontend::{FunctionBuilder, Variable};
use std::collections::{HashMap, HashSet};
use std::rc::Rc;

/// Why a loop stays with the closures (not an error: the closures handle everything).
#[derive(Debug)]
struct Unsupported;

type L<T> = Result<T, Unsupported>;

/// A statically addressed cell: lane, frame-relative or absolute, offset in the lane.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
struct CellKey {
    real: bool,
    frame: bool,
    off: usize,
}

/// Cells that indexed accesses reach (never kept in registers).
#[derive(Clone, Copy, Debug)]
struct Region {
    frame: bool,
    start: Size,
    len: Size,
}

impl Region {
    fn contains(&self, k: CellKey) -> bool {
        let (start, len) = if k.real {
            (self.start.r, self.len.r)
        } else {
            (self.start.i, self.len.i)
        };
        self.frame == k.frame && k.off >= start && k.off - start < len
    }
}

/// One run-time index of a place.
#[derive(Clone)]
struct DynIndex<'e> {
    expr: &'e Expr,
    lo: i64,
    hi: i64,
    stride: Size,
}

/// Byte addresses computed at run time (an element of an array of FB instances, an
/// array element passed to VAR_IN_OUT): `off` is relative to them, `region` holds the
/// cells they may point into.
#[derive(Clone, Copy)]
struct Ptrs {
    ints: Value,
    reals: Value,
}

/// Where a value lives, resolved statically as far as possible.
#[derive(Clone)]
struct JPlace<'e> {
    frame: bool,
    off: Size,
    /// Set: `off` is relative to these addresses, not to the frame or the lanes.
    ptr: Option<Ptrs>,
    /// Run-time indices, in evaluation order.
    dynamic: Vec<DynIndex<'e>>,
    /// The outermost aggregate an index selects in (set with the first run-time index).
    region: Option<Region>,
    ty: Ty,
    bit: Option<u32>,
    /// The type of the cell a bit is taken from (its sign bit is kept on stores).
    bit_owner: Ty,
    range: Option<(i64, i64)>,
}

impl JPlace<'_> {
    /// Whether the cell is in the REAL lane (a bit of an integer is not).
    fn real(&self) -> bool {
        self.bit.is_none() && self.ty.lane() == Some(Lane::Real)
    }
}

/// A value in a register.
#[derive(Clone, Copy)]
enum JV {
    I(Value),
    R(Value),
}

/// An index expression over a register cell: `v`, `v + k` or `v - k` (as `k`), at one
/// version (count of assignments) of the cell.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
struct IndexKey {
    cell: CellKey,
    version: u32,
    k: i64,
}

/// An index already checked against `lo..hi` where the check dominates the code being
/// emitted: its offset from `lo` is reused without a second check.
#[derive(Clone, Copy)]
struct Checked {
    key: IndexKey,
    lo: i64,
    hi: i64,
    /// The offset from `lo` is `rel + bias`.
    rel: Value,
    bias: i64,
}

/// A callee inlined into the loop: its variables live at `base` (a FUNCTION's static
/// frame, the FB instance), its VAR_IN_OUT are the places of the actual arguments, and
/// RETURN jumps to `ret`, the end of its body.
struct Frame {
    pou: PouId,
    base: JPlace<'static>,
    inouts: HashMap<usize, JPlace<'static>>,
    /// None while the initial values of a FUNCTION's frame are written.
    ret: Option<Block>,
}

/// Statements and calls one loop may inline in all before it stays with the closures.
const INLINE_BUDGET: usize = 2_000;
/// Nested calls deeper than this stay with the closures.
const INLINE_DEPTH: usize = 16;

/// A variable of the callee whose frame or instance is at `base`.
fn callee_var(base: &JPlace<'static>, v: &crate::check::VarInfo) -> JPlace<'static> {
    JPlace {
        frame: base.frame,
        off: base.off.plus(v.offset),
        ptr: base.ptr,
        dynamic: Vec::new(),
        region: base.region,
        ty: v.ty.clone(),
        bit: None,
        bit_owner: Ty::Void,
        range: v.range,
    }
}

/// Statements in `stmts`, nested ones included (the size of an inlined body).
fn stmt_count(stmts: &[Stmt]) -> usize {
    stmts
        .iter()
        .map(|s| {
            1 + match &s.kind {
                StmtKind::If(arms, els) => {
                    arms.iter().map(|(_, b)| stmt_count(b)).sum::<usize>()
                        + els.as_deref().map_or(0, stmt_count)
                }
                StmtKind::Case(_, arms, els) => {
                    arms.iter().map(|(_, b)| stmt_count(b)).sum::<usize>()
                        + els.as_deref().map_or(0, stmt_count)
                }
                StmtKind::For { body, .. }
                | StmtKind::While(_, body)
                | StmtKind::Repeat(body, _) => stmt_count(body),
                _ => 0,
            }
        })
        .sum()
}

/// The loop targets of EXIT and CONTINUE.
struct LoopTargets {
    exit: Block,
    next: Block,
    /// The known elements at each CONTINUE (they meet at `next`).
    continued: Vec<Vec<Elem>>,
}

/// An element of a one-dimensional array of scalars selected by an index `v + k` over a
/// register cell (see [`IndexKey`]): the array (lane, frame or absolute, first cell and
/// length in its lane, lower bound) and the index.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
struct ElemAt {
    real: bool,
    frame: bool,
    start: usize,
    len: usize,
    lo: i64,
    hi: i64,
    key: IndexKey,
}

impl ElemAt {
    /// Whether a store to `self` may change the cell of `other`. Two such arrays are the
    /// same or disjoint; in one array, indices over the same value of the same cell
    /// with different `k` are different elements when neither wraps onto the other
    /// (`exact`: at least 16 bits and `|k| <= 1000`, both checked within the bounds).
    fn may_alias(&self, exact: bool, other: &Elem) -> bool {
        let o = &other.at;
        if self.real != o.real || self.frame != o.frame {
            return false;
        }
        let disjoint = self.start.saturating_add(self.len) <= o.start
            || o.start.saturating_add(o.len) <= self.start;
        if disjoint {
            return false;
        }
        let same_array = self.start == o.start && self.len == o.len && self.lo == o.lo;
        let same_value = self.key.cell == o.key.cell && self.key.version == o.key.version;
        !(same_array && same_value && exact && other.exact && self.key.k != o.key.k)
    }
}

/// The value an element of memory is known to hold at the point of emission (loaded or
/// stored there, on every path to it): loads of it reuse the value. Stores are not
/// delayed (memory always holds the value); a store to memory the element may share a
/// cell with forgets it.
#[derive(Clone, Copy, Debug)]
struct Elem {
    at: ElemAt,
    exact: bool,
    value: Value,
}

/// The elements known on every path: those with the same value in each list.
fn meet(lists: &[Vec<Elem>]) -> Vec<Elem> {
    let Some((first, rest)) = lists.split_first() else {
        return Vec::new();
    };
    first
        .iter()
        .copied()
        .filter(|e| {
            rest.iter()
                .all(|l| l.iter().any(|o| o.at == e.at && o.value == e.value))
        })
        .collect()
}

/// An element carried from one iteration of a FOR loop to the next: `a[i + k]` of the
/// next iteration is `a[i + k + step]` of this one. `at.key` names the index at the
/// start of the body; `ity` is the type of the index expression (its wrapping).
#[derive(Clone, PartialEq, Debug)]
struct Carry {
    at: ElemAt,
    ity: Ty,
}

/// What one attempt at lowering a loop may use; later attempts learn from earlier ones.
#[derive(Default, Clone)]
struct Plan {
    /// Cells an indexed access may reach: never in registers.
    excluded: HashSet<CellKey>,
    /// IF statements (by address) whose branch-free form would fault or call: branches.
    branchy: HashSet<usize>,
    /// Per FOR statement (by address): the elements carried between its iterations.
    carry: HashMap<usize, Vec<Carry>>,
    /// Per FOR statement (by address): the indices over its counter its body checks.
    proven: HashMap<usize, Vec<Bound>>,
    /// FOR statements whose body changes the counter: no copy without checks.
    unversioned: HashSet<usize>,
    /// Whether `carry` and `proven` were learnt (they are learnt once).
    carry_learnt: bool,
    /// The last attempt: no branch-free IF, no carried elements.
    plain: bool,
}

/// A FOR loop being lowered (outside inlined callees): its counter's cell and version
/// in the body, and the elements over it the body loads.
struct ForCtx {
    id: usize,
    cell: CellKey,
    version: u32,
    used: Vec<Carry>,
    bounds: Vec<Bound>,
}

/// An index `i + k` over a FOR counter the body checks against `lo..=hi` (both within
/// the index type).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
struct Bound {
    k: i64,
    lo: i64,
    hi: i64,
}

/// A FOR loop's parts both of its copies use.
struct ForParts<'e> {
    s: &'e Stmt,
    p: JPlace<'e>,
    vt: Ty,
    cur0: Value,
    end: Value,
    step: Value,
    sign: Option<bool>,
    /// Stepped without saturation (see [`Lower::for_loop`]).
    fixed: bool,
    step_k: i64,
    id: usize,
    cell: CellKey,
    /// The counter's register, when the loop may carry elements and skip checks.
    counter: Option<Variable>,
    carried: Vec<(Carry, Variable)>,
}

/// Whether a loop body has no loops and no calls (nothing else ticks the budget).
fn plain_body(stmts: &[Stmt]) -> bool {
    stmts.iter().all(|s| match &s.kind {
        StmtKind::Empty | StmtKind::Exit | StmtKind::Continue | StmtKind::Return => true,
        StmtKind::Assign(t, v) => !contains_call(t) && !contains_call(v),
        StmtKind::If(arms, els) => {
            arms.iter().all(|(c, b)| !contains_call(c) && plain_body(b))
                && els.as_deref().is_none_or(plain_body)
        }
        StmtKind::Case(sel, arms, els) => {
            !contains_call(sel)
                && arms.iter().all(|(_, b)| plain_body(b))
                && els.as_deref().is_none_or(plain_body)
        }
        _ => false,
    })
}

/// Attempts at lowering one loop before it stays with the closures.
const ATTEMPTS: usize = 5;

/// Compiles the loop statement `s` of the POU `cx` compiles, or `None` when any part of
/// it is outside the JIT subset.
pub(crate) fn lower_loop(cx: &mut Cx<'_>, engine: &Rc<JitEngine>, s: &Stmt) -> Option<JitLoop> {
    let mut plan = Plan::default();
    // A cell first kept in a register may turn out to be reachable by an indexed access
    // found later in the loop; an IF lowered without branches may turn out to need one
    // (a fault); the elements worth carrying between iterations are known once the body
    // was lowered: later attempts use what earlier ones found. The last is plain.
    for n in 0..ATTEMPTS {
        plan.plain = plan.plain || n + 1 == ATTEMPTS;
        match attempt(cx, engine, s, &plan) {
            Ok(Attempt::Done(l)) => return Some(l),
            Ok(Attempt::Retry(p)) => plan = p,
            Err(Unsupported) => return None,
        }
    }
    None
}

enum Attempt {
    Done(JitLoop),
    Retry(Plan),
}

fn attempt(cx: &mut Cx<'_>, engine: &Rc<JitEngine>, s: &Stmt, plan: &Plan) -> L<Attempt> {
    let ptr = engine.pointer_type().ok_or(Unsupported)?;
    let frontend = engine.frontend_config().ok_or(Unsupported)?;
    if ptr != types::I64 {
        return Err(Unsupported);
    }
    let mut ctx = engine.ctx.try_borrow_mut().map_err(|_| Unsupported)?;
    let mut fctx = engine.fctx.try_borrow_mut().map_err(|_| Unsupported)?;
    // a context cleared after an earlier attempt has lost the host's convention
    ctx.func.signature.call_conv = frontend.default_call_conv;
    ctx.func.signature.params.push(AbiParam::new(ptr));
    ctx.func.signature.returns.push(AbiParam::new(types::I64));
    let result = {
        let mut b = FunctionBuilder::new(&mut ctx.func, &mut fctx);
        let entry = b.create_block();
        b.append_block_params_for_function_params(entry);
        b.switch_to_block(entry);
        let ctxp = *b.block_params(entry).first().ok_or(Unsupported)?;
        let flags = MemFlagsData::trusted();
        let ints = b.ins().load(ptr, flags, ctxp, ctx_offset::INTS);
        let reals = b.ins().load(ptr, flags, ctxp, ctx_offset::REALS);
        let frame_i = b.ins().load(types::I64, flags, ctxp, ctx_offset::FRAME_I);
        let frame_r = b.ins().load(types::I64, flags, ctxp, ctx_offset::FRAME_R);
        let now = b.ins().load(types::I64, flags, ctxp, ctx_offset::NOW);
        let budget0 = b.ins().load(types::I64, flags, ctxp, ctx_offset::BUDGET);
        let fi = b.ins().ishl_imm_s(frame_i, 3);
        let frame_ints = b.ins().iadd(ints, fi);
        let fr = b.ins().ishl_imm_s(frame_r, 3);
        let frame_reals = b.ins().iadd(reals, fr);
        let budget = b.declare_var(types::I64);
        b.def_var(budget, budget0);
        let prologue = b.create_block();
        b.ins().jump(prologue, &[]);
        let body = b.create_block();
        let exit = b.create_block();
        b.append_block_param(exit, types::I64);
        b.switch_to_block(body);
        let mut lw = Lower {
            cx,
            b,
            ctxp,
            ints,
            reals,
            frame_ints,
            frame_reals,
            now,
            budget,
            exit,
            vars: HashMap::new(),
            order: Vec::new(),
            dirty: HashSet::new(),
            plan,
            elems: Vec::new(),
            select_failed: Vec::new(),
            fors: Vec::new(),
            carry_seen: HashMap::new(),
            bounds_seen: HashMap::new(),
            version_failed: Vec::new(),
            regions: Vec::new(),
            extents: Extents::default(),
            faults: Vec::new(),
            loops: Vec::new(),
            versions: HashMap::new(),
            checked: Vec::new(),
            frames: Vec::new(),
            inline_budget: INLINE_BUDGET,
        };
        let lowered = lw.stmt(s);
        match lowered {
            Ok(()) => {
                let zero = lw.b.ins().iconst(types::I64, 0);
                lw.b.ins().jump(exit, &[zero.into()]);
                lw.finish(prologue, body);
                let conflicts: Vec<CellKey> = lw
                    .order
                    .iter()
                    .copied()
                    .filter(|k| lw.regions.iter().any(|r| r.contains(*k)))
                    .collect();
                let next = lw.next_plan(conflicts);
                let Lower {
                    extents, faults, b, ..
                } = lw;
                b.finalize(frontend);
                Ok((next, extents, faults))
            }
            Err(e) => Err(e),
        }
    };
    let (next, extents, faults) = match result {
        Ok(r) => r,
        Err(e) => {
            // an abandoned function leaves the builder context mid-way
            ctx.clear();
            *fctx = cranelift_frontend::FunctionBuilderContext::new();
            return Err(e);
        }
    };
    if let Some(next) = next {
        ctx.clear();
        return Ok(Attempt::Retry(next));
    }
    let code = engine.finish(&mut ctx).ok_or(Unsupported)?;
    Ok(Attempt::Done(JitLoop {
        code,
        extents,
        faults: faults.into_boxed_slice(),
        fallback: None,
        _engine: Rc::clone(engine),
    }))
}

struct Lower<'a, 'b, 'x> {
    cx: &'a mut Cx<'b>,
    b: FunctionBuilder<'a>,
    ctxp: Value,
    ints: Value,
    reals: Value,
    frame_ints: Value,
    frame_reals: Value,
    now: Value,
    budget: Variable,
    exit: Block,
    /// Cells kept in registers, in order of first use.
    vars: HashMap<CellKey, Variable>,
    order: Vec<CellKey>,
    /// Cells written (stored back on the way out).
    dirty: HashSet<CellKey>,
    plan: &'x Plan,
    /// Elements whose values are known here (see [`Elem`]).
    elems: Vec<Elem>,
    /// IF statements lowered without branches that needed one.
    select_failed: Vec<usize>,
    /// FOR loops being lowered, innermost last.
    fors: Vec<ForCtx>,
    /// Per FOR loop: the elements over its counter known at the end of an iteration,
    /// as they are named in the next one.
    carry_seen: HashMap<usize, Vec<Carry>>,
    /// Per FOR loop: the indices over its counter its body checks.
    bounds_seen: HashMap<usize, Vec<Bound>>,
    /// FOR loops whose copy without checks turned out to change the counter.
    version_failed: Vec<usize>,
    regions: Vec<Region>,
    extents: Extents,
    faults: Vec<FaultSite>,
    loops: Vec<LoopTargets>,
    /// Assignments so far per register cell (in emission order).
    versions: HashMap<CellKey, u32>,
    /// Index checks valid at the point of emission: scoped like the dominator tree
    /// (truncated after a branch, emptied inside a loop).
    checked: Vec<Checked>,
    /// Callees being inlined, innermost last.
    frames: Vec<Frame>,
    /// Statements still allowed to be inlined.
    inline_budget: usize,
}

const DAY: i64 = 86_400_000_000_000;

fn flags() -> MemFlagsData {
    MemFlagsData::trusted()
}

/// Byte offset of a cell as an immediate.
fn byte_off(cell: usize) -> L<i32> {
    cell.checked_mul(8)
        .and_then(|b| i32::try_from(b).ok())
        .ok_or(Unsupported)
}

/// The bytes of `cells` cells, as an immediate.
fn stride_bytes(cells: usize) -> L<i64> {
    cells
        .checked_mul(8)
        .and_then(|b| i64::try_from(b).ok())
        .ok_or(Unsupported)
}

fn is_u64(t: &Ty) -> bool {
    matches!(t, Ty::ULInt | Ty::LWord)
}

fn timey(t: &Ty) -> bool {
    matches!(t, Ty::Time | Ty::LTime | Ty::Tod | Ty::Dt | Ty::Date)
}

/// Plain integers: the value is the number (no time scaling).
fn plain_int(t: &Ty) -> bool {
    t.is_int() || t.is_bits() || *t == Ty::Bool || matches!(t, Ty::Enum(_))
}

/// Whether evaluating `e` may fault (then AND/OR of BOOL must short-circuit as the
/// closures do).
fn may_fault(e: &Expr) -> bool {
    match &e.kind {
        ExprKind::Binary(BinOp::Div | BinOp::Mod, ..) | ExprKind::Index(..) => true,
        ExprKind::Call(..) | ExprKind::Deref(_) => true,
        ExprKind::Binary(_, a, b) => may_fault(a) || may_fault(b),
        ExprKind::Unary(_, a)
        | ExprKind::Member(a, _)
        | ExprKind::Bit(a, _)
        | ExprKind::Part(a, ..) => may_fault(a),
        _ => false,
    }
}

/// Whether `e` is cheap enough to evaluate whether or not it is needed: names, members,
/// elements, literals, `+`, `-` and comparisons of such.
fn simple(e: &Expr) -> bool {
    match &e.kind {
        ExprKind::Literal(_) | ExprKind::Name { .. } => true,
        ExprKind::Member(a, _) => simple(a),
        ExprKind::Index(a, ix) => simple(a) && ix.iter().all(simple),
        ExprKind::Unary(UnOp::Neg | UnOp::Plus, a) => simple(a),
        ExprKind::Binary(
            BinOp::Add
            | BinOp::Sub
            | BinOp::Lt
            | BinOp::Gt
            | BinOp::Le
            | BinOp::Ge
            | BinOp::Eq
            | BinOp::Ne,
            a,
            b,
        ) => simple(a) && simple(b),
        _ => false,
    }
}

impl<'e> Lower<'_, '_, '_> {
    // ---- places ----------------------------------------------------------------

    fn resolve(&mut self, e: &'e Expr) -> L<JPlace<'e>> {
        let c = self.cx.c;
        match &e.kind {
            ExprKind::Name { .. } => match c.res.get(&e.id) {
                Some(Res::Local(i)) => {
                    let v = c
                        .pou(self.cx.pou.ok_or(Unsupported)?)
                        .and_then(|p| p.vars.get(*i))
                        .ok_or(Unsupported)?;
                    if let Some(f) = self.frames.last() {
                        // a variable of an inlined callee
                        if v.kind == VarKind::InOut {
                            let mut p = f.inouts.get(i).cloned().ok_or(Unsupported)?;
                            p.ty = v.ty.clone();
                            p.range = v.range;
                            return Ok(p);
                        }
                        return Ok(callee_var(&f.base, v));
                    }
                    if v.kind == VarKind::InOut {
                        return Err(Unsupported);
                    }
                    Ok(JPlace {
                        frame: true,
                        off: v.offset,
                        ptr: None,
                        dynamic: Vec::new(),
                        region: None,
                        ty: v.ty.clone(),
                        bit: None,
                        bit_owner: Ty::Void,
                        range: v.range,
                    })
                }
                Some(Res::Global(g)) => {
                    let v = c.globals.get(*g).ok_or(Unsupported)?;
                    Ok(JPlace {
                        frame: false,
                        off: v.offset,
                        ptr: None,
                        dynamic: Vec::new(),
                        region: None,
                        ty: v.ty.clone(),
                        bit: None,
                        bit_owner: Ty::Void,
                        range: v.range,
                    })
                }
                _ => Err(Unsupported),
            },
            ExprKind::Member(base, _) => {
                // another program's variables may alias this frame: closures only
                if matches!(c.res.get(&base.id), Some(Res::Program(_))) {
                    return Err(Unsupported);
                }
                let mut p = self.resolve(base)?;
                if p.bit.is_some() {
                    return Err(Unsupported);
                }
                let (off, ty, range) = match (&p.ty, c.res.get(&e.id)) {
                    (Ty::Struct(id), Some(Res::Field(i))) => {
                        let f = c
                            .types
                            .struct_def(*id)
                            .and_then(|d| d.fields.get(*i))
                            .ok_or(Unsupported)?;
                        (f.offset, f.ty.clone(), f.range)
                    }
                    (Ty::Fb(_), Some(Res::PouVar(pid, i))) => {
                        let v = c
                            .pou(*pid)
                            .and_then(|p| p.vars.get(*i))
                            .ok_or(Unsupported)?;
                        (v.offset, v.ty.clone(), v.range)
                    }
                    _ => return Err(Unsupported),
                };
                p.off = p.off.plus(off);
                p.ty = ty;
                p.range = range;
                Ok(p)
            }
            ExprKind::Bit(base, bit) => {
                let mut p = self.resolve(base)?;
                if p.bit.is_some() || p.ty.lane() != Some(Lane::Int) || *bit > 63 {
                    return Err(Unsupported);
                }
                p.range = None;
                p.bit = Some(*bit);
                p.bit_owner = p.ty.clone();
                p.ty = Ty::Bool;
                Ok(p)
            }
            ExprKind::Index(base, idx) => {
                let mut p = self.resolve(base)?;
                if p.bit.is_some() {
                    return Err(Unsupported);
                }
                let Ty::Array(a) = p.ty.clone() else {
                    return Err(Unsupported);
                };
                if idx.len() != a.dims.len() {
                    return Err(Unsupported);
                }
                let mut strides = vec![1usize; a.dims.len()];
                let mut acc = 1usize;
                for (k, (lo, hi)) in a.dims.iter().enumerate().rev() {
                    if let Some(s) = strides.get_mut(k) {
                        *s = acc;
                    }
                    acc = acc.saturating_mul(usize::try_from(hi - lo + 1).unwrap_or(0));
                }
                let mut static_lin = 0usize;
                let mut fresh: Vec<DynIndex<'e>> = Vec::new();
                for ((ix, (lo, hi)), stride) in idx.iter().zip(a.dims.iter()).zip(strides.iter()) {
                    if let ExprKind::Literal(Literal::Int(v, _)) = &ix.kind {
                        let v = i64::try_from(*v).map_err(|_| Unsupported)?;
                        if v < *lo || v > *hi {
                            return Err(Unsupported);
                        }
                        static_lin += usize::try_from(v - lo).map_err(|_| Unsupported)? * stride;
                        continue;
                    }
                    fresh.push(DynIndex {
                        expr: ix,
                        lo: *lo,
                        hi: *hi,
                        stride: a.elem_size.times(*stride),
                    });
                }
                if !fresh.is_empty() && p.region.is_none() {
                    p.region = Some(Region {
                        frame: p.frame,
                        start: p.off,
                        len: c.size_of(&p.ty),
                    });
                }
                p.off = p.off.plus(a.elem_size.times(static_lin));
                // the new indices are evaluated before the earlier ones, as the closures do
                fresh.append(&mut p.dynamic);
                p.dynamic = fresh;
                p.ty = a.elem.clone();
                p.range = a.elem_range;
                Ok(p)
            }
            _ => Err(Unsupported),
        }
    }

    /// The register of a statically addressed cell kept in one, if it is.
    fn var_of(&mut self, p: &JPlace<'_>) -> Option<Variable> {
        if !p.dynamic.is_empty() || p.ptr.is_some() {
            return None;
        }
        let real = p.real();
        let key = CellKey {
            real,
            frame: p.frame,
            off: if real { p.off.r } else { p.off.i },
        };
        if self.plan.excluded.contains(&key) {
            return None;
        }
        if let Some(v) = self.vars.get(&key) {
            return Some(*v);
        }
        let v = self
            .b
            .declare_var(if real { types::F64 } else { types::I64 });
        self.vars.insert(key, v);
        self.order.push(key);
        Some(v)
    }

    /// Records the cells an access may touch (checked on entry) and returns the byte
    /// address of the place's cell (index faults included) as base + immediate offset.
    fn address(&mut self, p: &JPlace<'e>) -> L<(Value, i32)> {
        let real = p.real();
        let one = if real {
            Size { i: 0, r: 1, s: 0 }
        } else {
            Size { i: 1, r: 0, s: 0 }
        };
        match p.region {
            Some(r) if !p.dynamic.is_empty() || p.ptr.is_some() => {
                self.regions.push(r);
                self.extents.cover(r.frame, r.start, r.start.plus(r.len));
            }
            _ if p.ptr.is_some() => return Err(Unsupported),
            _ => self.extents.cover(p.frame, p.off, p.off.plus(one)),
        }
        let base = match (p.ptr, p.frame, real) {
            (Some(d), _, false) => d.ints,
            (Some(d), _, true) => d.reals,
            (None, true, false) => self.frame_ints,
            (None, true, true) => self.frame_reals,
            (None, false, false) => self.ints,
            (None, false, true) => self.reals,
        };
        let mut off = byte_off(if real { p.off.r } else { p.off.i })?;
        if p.dynamic.is_empty() {
            return Ok((base, off));
        }
        let mut lin: Option<Value> = None;
        for d in &p.dynamic {
            let (rel, bias) = self.index_rel(d)?;
            let bytes = stride_bytes(if real { d.stride.r } else { d.stride.i })?;
            // a constant part of the offset goes into the immediate
            off = bias
                .checked_mul(bytes)
                .and_then(|b| i32::try_from(b).ok())
                .and_then(|b| off.checked_add(b))
                .ok_or(Unsupported)?;
            let part = self.b.ins().imul_imm_s(rel, bytes);
            lin = Some(match lin {
                None => part,
                Some(l) => self.b.ins().iadd(l, part),
            });
        }
        let lin = lin.ok_or(Unsupported)?;
        Ok((self.b.ins().iadd(base, lin), off))
    }

    /// The offset of an index from its lower bound, checked against its bounds unless a
    /// check of the same value dominates this code.
    /// Returned as a value and a constant to add to it.
    fn index_rel(&mut self, d: &DynIndex<'e>) -> L<(Value, i64)> {
        let key = self.index_key(d.expr);
        let known = key.and_then(|key| {
            self.checked
                .iter()
                .find(|c| c.key == key && c.lo == d.lo && c.hi == d.hi)
                .map(|c| (c.rel, c.bias))
        });
        match known {
            Some(rel) => Ok(rel),
            None => Ok((self.checked_index(d, key)?, 0)),
        }
    }

    /// Evaluates an index, checks it against its bounds (a fault outside) and returns
    /// its offset from the lower bound.
    fn checked_index(&mut self, d: &DynIndex<'e>, key: Option<IndexKey>) -> L<Value> {
        {
            let JV::I(v) = self.expr(d.expr)? else {
                return Err(Unsupported);
            };
            let rel = self.b.ins().iadd_imm_s(v, d.lo.wrapping_neg());
            let span = u64::try_from(d.hi - d.lo).map_err(|_| Unsupported)?;
            let out = self.b.ins().icmp_imm_s(
                IntCC::UnsignedGreaterThan,
                rel,
                i64::try_from(span).map_err(|_| Unsupported)?,
            );
            self.fault_if(
                out,
                FaultSite::Index {
                    span: d.expr.span,
                    lo: d.lo,
                    hi: d.hi,
                },
                Some(v),
            );
            if let Some(key) = key {
                self.note_bound(d, key);
                self.checked.push(Checked {
                    key,
                    lo: d.lo,
                    hi: d.hi,
                    rel,
                    bias: 0,
                });
            }
            Ok(rel)
        }
    }

    /// Notes an index over a FOR counter being lowered, checked in its body, for the
    /// copy without checks (only an index whose bounds are values of its type).
    fn note_bound(&mut self, d: &DynIndex<'e>, key: IndexKey) {
        let Some((tmin, tmax)) = self.cx.c.ty(d.expr.id).int_range() else {
            return;
        };
        let inside = tmin <= i128::from(d.lo) && i128::from(d.hi) <= tmax;
        if !inside || key.k.unsigned_abs() > 1000 {
            return;
        }
        let b = Bound {
            k: key.k,
            lo: d.lo,
            hi: d.hi,
        };
        for f in self.fors.iter_mut() {
            if f.cell == key.cell && f.version == key.version && !f.bounds.contains(&b) {
                f.bounds.push(b);
            }
        }
    }

    /// The key of an index expression `v`, `v + k` or `v - k` over a register cell
    /// without conversions, if it is one.
    fn index_key(&mut self, e: &'e Expr) -> Option<IndexKey> {
        let c = self.cx.c;
        let (name, k) = match &e.kind {
            ExprKind::Name { .. } => (e, 0),
            ExprKind::Binary(op @ (BinOp::Add | BinOp::Sub), a, b) => {
                let ExprKind::Literal(Literal::Int(k, _)) = &b.kind else {
                    return None;
                };
                if c.coerce.contains_key(&b.id) || !matches!(a.kind, ExprKind::Name { .. }) {
                    return None;
                }
                let k = i64::try_from(*k).ok()?;
                (
                    &**a,
                    if *op == BinOp::Sub {
                        k.checked_neg()?
                    } else {
                        k
                    },
                )
            }
            _ => return None,
        };
        if c.coerce.contains_key(&e.id) || c.coerce.contains_key(&name.id) {
            return None;
        }
        let p = self.resolve(name).ok()?;
        if p.real() || p.bit.is_some() || p.ty.lane() != Some(Lane::Int) {
            return None;
        }
        self.var_of(&p)?;
        let cell = CellKey {
            real: false,
            frame: p.frame,
            off: p.off.i,
        };
        Some(IndexKey {
            cell,
            version: self.versions.get(&cell).copied().unwrap_or(0),
            k,
        })
    }

    /// Loads the cell of a place (the whole cell for a bit access).
    fn load_cell(&mut self, p: &JPlace<'e>) -> L<Value> {
        let ty = if p.real() { types::F64 } else { types::I64 };
        if let Some(v) = self.var_of(p) {
            self.address(p)?;
            return Ok(self.b.use_var(v));
        }
        let elem = self.elem_at(p);
        // the index is checked even when the value is known: a carried value may have
        // been loaded for an index outside the bounds
        let (base, off) = self.address(p)?;
        let Some((at, exact, ity)) = elem else {
            return Ok(self.b.ins().load(ty, flags(), base, off));
        };
        if exact {
            for f in self.fors.iter_mut() {
                let named = Carry {
                    at,
                    ity: ity.clone(),
                };
                if f.cell == at.key.cell && f.version == at.key.version && !f.used.contains(&named)
                {
                    f.used.push(named);
                }
            }
        }
        if let Some(e) = self.elems.iter().find(|e| e.at == at) {
            return Ok(e.value);
        }
        let value = self.b.ins().load(ty, flags(), base, off);
        self.elems.push(Elem { at, exact, value });
        Ok(value)
    }

    /// The element a place names, if it is one whose value can be known (see
    /// [`ElemAt`]), whether different `k` are different elements, and the index type.
    fn elem_at(&mut self, p: &JPlace<'e>) -> Option<(ElemAt, bool, Ty)> {
        if p.ptr.is_some() || p.bit.is_some() || p.dynamic.len() != 1 {
            return None;
        }
        let d = p.dynamic.first()?;
        let r = p.region?;
        let real = p.real();
        let (stride, other, off, start, len) = if real {
            (d.stride.r, d.stride.i, p.off.r, r.start.r, r.len.r)
        } else {
            (d.stride.i, d.stride.r, p.off.i, r.start.i, r.len.i)
        };
        if stride != 1 || other != 0 || d.stride.s != 0 || off != start || r.frame != p.frame {
            return None;
        }
        let key = self.index_key(d.expr)?;
        let ity = self.cx.c.ty(d.expr.id);
        let exact = key.k.unsigned_abs() <= 1000 && ity.bits() >= 16 && ity.bits() <= 64;
        let at = ElemAt {
            real,
            frame: p.frame,
            start,
            len,
            lo: d.lo,
            hi: d.hi,
            key,
        };
        Some((at, exact, ity))
    }

    /// Loads the element `carry` names for the counter value `counter` (its index
    /// `counter + k` wrapped to the index type), from the first element when that index
    /// is outside the bounds: the value is then never used, as every use of it checks
    /// the index first.
    fn clamped_load(&mut self, carry: &Carry, counter: Value, k: i64) -> L<Value> {
        let at = carry.at;
        let x = self.b.ins().iadd_imm_s(counter, k);
        let x = self.wrap(&carry.ity, x);
        let rel = self.b.ins().iadd_imm_s(x, at.lo.wrapping_neg());
        let span = at
            .hi
            .checked_sub(at.lo)
            .filter(|n| *n >= 0)
            .ok_or(Unsupported)?;
        let out = self
            .b
            .ins()
            .icmp_imm_s(IntCC::UnsignedGreaterThan, rel, span);
        let zero = self.b.ins().iconst(types::I64, 0);
        let rel = self.b.ins().select(out, zero, rel);
        let bytes = self.b.ins().imul_imm_s(rel, 8);
        let cell = |n: usize| {
            if at.real {
                Size { i: 0, r: n, s: 0 }
            } else {
                Size { i: n, r: 0, s: 0 }
            }
        };
        let r = Region {
            frame: at.frame,
            start: cell(at.start),
            len: cell(at.len),
        };
        self.regions.push(r);
        self.extents.cover(r.frame, r.start, r.start.plus(r.len));
        let base = self.base_of(CellKey {
            real: at.real,
            frame: at.frame,
            off: 0,
        });
        let addr = self.b.ins().iadd(base, bytes);
        let ty = if at.real { types::F64 } else { types::I64 };
        Ok(self.b.ins().load(ty, flags(), addr, byte_off(at.start)?))
    }

    fn load(&mut self, p: &JPlace<'e>) -> L<JV> {
        let v = self.load_cell(p)?;
        if let Some(bit) = p.bit {
            let s = self.b.ins().sshr_imm_s(v, i64::from(bit));
            return Ok(JV::I(self.b.ins().band_imm_s(s, 1)));
        }
        Ok(if p.real() { JV::R(v) } else { JV::I(v) })
    }

    /// Stores an evaluated value (range already checked) into a place.
    fn store(&mut self, p: &JPlace<'e>, v: JV) -> L<()> {
        let v = match (v, p.real()) {
            (JV::I(v), false) => v,
            (JV::R(v), true) => v,
            _ => return Err(Unsupported),
        };
        let var = self.var_of(p);
        let elem = if var.is_none() { self.elem_at(p) } else { None };
        let (base, off) = self.address(p)?;
        let v = match p.bit {
            Some(bit) => {
                let old = match var {
                    Some(var) => self.b.use_var(var),
                    None => self.b.ins().load(types::I64, flags(), base, off),
                };
                let m = 1i64 << bit;
                let set = self.b.ins().bor_imm_s(old, m);
                let clear = self.b.ins().band_imm_s(old, !m);
                let bits = self.b.ins().select(v, set, clear);
                // the top bit of an INT is its sign, as the closures keep it
                let owner = p.bit_owner.clone();
                self.wrap(&owner, bits)
            }
            None => v,
        };
        match var {
            Some(var) => {
                self.b.def_var(var, v);
                let real = p.real();
                let key = CellKey {
                    real,
                    frame: p.frame,
                    off: if real { p.off.r } else { p.off.i },
                };
                self.dirty.insert(key);
                *self.versions.entry(key).or_insert(0) += 1;
            }
            None => {
                self.b.ins().store(flags(), v, base, off);
                match elem {
                    Some((at, exact, _)) => {
                        self.elems.retain(|e| !at.may_alias(exact, e));
                        self.elems.push(Elem {
                            at,
                            exact,
                            value: v,
                        });
                    }
                    // any other cell may be one of the elements
                    None => self.elems.clear(),
                }
            }
        }
        Ok(())
    }

    /// Checks a value stored into a subrange place.
    fn range_check(&mut self, v: Value, range: Option<(i64, i64)>, span: Span, name: &str) {
        let Some((lo, hi)) = range else { return };
        let below = self.b.ins().icmp_imm_s(IntCC::SignedLessThan, v, lo);
        let above = self.b.ins().icmp_imm_s(IntCC::SignedGreaterThan, v, hi);
        let out = self.b.ins().bor(below, above);
        self.fault_if(
            out,
            FaultSite::Range {
                span,
                name: Rc::from(name),
                lo,
                hi,
            },
            Some(v),
        );
    }

    // ---- control ---------------------------------------------------------------

    /// Leaves with fault `site` when `cond` holds.
    fn fault_if(&mut self, cond: Value, site: FaultSite, value: Option<Value>) {
        let k = self.faults.len() as i64;
        self.faults.push(site);
        let bad = self.b.create_block();
        let ok = self.b.create_block();
        self.b.set_cold_block(bad);
        self.b.ins().brif(cond, bad, &[], ok, &[]);
        self.b.switch_to_block(bad);
        if let Some(v) = value {
            self.b
                .ins()
                .store(flags(), v, self.ctxp, ctx_offset::FAULT_VALUE);
        }
        let code = self.b.ins().iconst(types::I64, -(k + 1));
        self.b.ins().jump(self.exit, &[code.into()]);
        self.b.switch_to_block(ok);
    }

    /// Ends the current block with a jump and goes on in a fresh (unreachable) one.
    fn jump_away(&mut self, to: Block, code: Option<i64>) {
        match code {
            Some(c) => {
                let v = self.b.ins().iconst(types::I64, c);
                self.b.ins().jump(to, &[v.into()]);
            }
            None => {
                self.b.ins().jump(to, &[]);
            }
        }
        let dead = self.b.create_block();
        self.b.switch_to_block(dead);
    }

    /// One iteration of the loop budget.
    fn tick(&mut self, span: Span) {
        let left = self.b.use_var(self.budget);
        let none = self.b.ins().icmp_imm_s(IntCC::Equal, left, 0);
        self.fault_if(none, FaultSite::LoopBudget(span), None);
        let left = self.b.use_var(self.budget);
        let less = self.b.ins().iadd_imm_s(left, -1);
        self.b.def_var(self.budget, less);
    }

    /// The exit block (register cells written back) and the prologue (register cells
    /// loaded), emitted once the body is known.
    fn finish(&mut self, prologue: Block, body: Block) {
        self.b.switch_to_block(self.exit);
        let code = self.b.block_params(self.exit).first().copied();
        for key in self.order.clone() {
            if !self.dirty.contains(&key) {
                continue;
            }
            let Some(&var) = self.vars.get(&key) else {
                continue;
            };
            let v = self.b.use_var(var);
            let base = self.base_of(key);
            if let Ok(off) = byte_off(key.off) {
                self.b.ins().store(flags(), v, base, off);
            }
        }
        let left = self.b.use_var(self.budget);
        self.b
            .ins()
            .store(flags(), left, self.ctxp, ctx_offset::BUDGET);
        match code {
            Some(c) => self.b.ins().return_(&[c]),
            None => self
                .b
                .ins()
                .trap(cranelift_codegen::ir::TrapCode::unwrap_user(1)),
        };
        self.b.switch_to_block(prologue);
        for key in self.order.clone() {
            let Some(&var) = self.vars.get(&key) else {
                continue;
            };
            let base = self.base_of(key);
            let ty = if key.real { types::F64 } else { types::I64 };
            if let Ok(off) = byte_off(key.off) {
                let v = self.b.ins().load(ty, flags(), base, off);
                self.b.def_var(var, v);
            }
        }
        self.b.ins().jump(body, &[]);
        self.b.seal_all_blocks();
    }

    fn base_of(&self, k: CellKey) -> Value {
        match (k.frame, k.real) {
            (true, false) => self.frame_ints,
            (true, true) => self.frame_reals,
            (false, false) => self.ints,
            (false, true) => self.reals,
        }
    }

    // ---- statements ------------------------------------------------------------

    fn block(&mut self, stmts: &'e [Stmt]) -> L<()> {
        for s in stmts {
            self.stmt(s)?;
        }
        Ok(())
    }

    fn cond(&mut self, e: &'e Expr) -> L<Value> {
        match self.expr(e)? {
            JV::I(v) => Ok(v),
            JV::R(_) => Err(Unsupported),
        }
    }

    /// One arm of an IF or CASE: `body` when `cond` holds, then on to `merge`; the code
    /// goes on in the block for the next arm.
    /// The elements known at the end of the arm are added to `ends`.
    fn arm(
        &mut self,
        cond: Value,
        body: &'e [Stmt],
        merge: Block,
        ends: &mut Vec<Vec<Elem>>,
    ) -> L<()> {
        let then = self.b.create_block();
        let next = self.b.create_block();
        self.b.ins().brif(cond, then, &[], next, &[]);
        self.b.switch_to_block(then);
        // checks inside the arm do not hold after it
        let scope = self.checked.len();
        let known = self.elems.clone();
        self.block(body)?;
        self.checked.truncate(scope);
        ends.push(std::mem::replace(&mut self.elems, known));
        self.b.ins().jump(merge, &[]);
        self.b.switch_to_block(next);
        Ok(())
    }

    fn stmt(&mut self, s: &'e Stmt) -> L<()> {
        match &s.kind {
            StmtKind::Empty => Ok(()),
            StmtKind::Assign(target, value) => {
                let p = self.resolve(target)?;
                if p.ty.lane().is_none() || p.ty.lane() == Some(Lane::Str) {
                    return Err(Unsupported);
                }
                let v = self.expr(value)?;
                if let (JV::I(x), Some(_)) = (v, p.range) {
                    self.range_check(x, p.range, target.span, &lvalue_name(target));
                }
                self.store(&p, v)
            }
            StmtKind::Call(e) => self.call(e),
            StmtKind::If(arms, els) => {
                if let ([(c, body)], None) = (arms.as_slice(), els) {
                    if self.select_if(s, c, body)? {
                        return Ok(());
                    }
                }
                let merge = self.b.create_block();
                let scope = self.checked.len();
                let mut ends = Vec::new();
                for (c, body) in arms {
                    let c = self.cond(c)?;
                    self.arm(c, body, merge, &mut ends)?;
                }
                if let Some(els) = els {
                    self.block(els)?;
                }
                self.checked.truncate(scope);
                ends.push(std::mem::take(&mut self.elems));
                self.elems = meet(&ends);
                self.b.ins().jump(merge, &[]);
                self.b.switch_to_block(merge);
                Ok(())
            }
            StmtKind::Case(sel, arms, els) => {
                let v = self.cond(sel)?;
                let merge = self.b.create_block();
                let mut ends = Vec::new();
                for (labels, body) in arms {
                    let mut hit: Option<Value> = None;
                    for l in labels {
                        let (lo, hi) = match l {
                            CaseLabel::Value(e) => {
                                let k = self.cx.const_value(e).ok_or(Unsupported)?;
                                (k, k)
                            }
                            CaseLabel::Range(a, b) => (
                                self.cx.const_value(a).ok_or(Unsupported)?,
                                self.cx.const_value(b).ok_or(Unsupported)?,
                            ),
                        };
                        let h = if lo == hi {
                            self.b.ins().icmp_imm_s(IntCC::Equal, v, lo)
                        } else {
                            let a = self
                                .b
                                .ins()
                                .icmp_imm_s(IntCC::SignedGreaterThanOrEqual, v, lo);
                            let b = self.b.ins().icmp_imm_s(IntCC::SignedLessThanOrEqual, v, hi);
                            self.b.ins().band(a, b)
                        };
                        hit = Some(match hit {
                            None => h,
                            Some(x) => self.b.ins().bor(x, h),
                        });
                    }
                    let Some(hit) = hit else { continue };
                    self.arm(hit, body, merge, &mut ends)?;
                }
                if let Some(els) = els {
                    let arm = self.checked.len();
                    self.block(els)?;
                    self.checked.truncate(arm);
                }
                ends.push(std::mem::take(&mut self.elems));
                self.elems = meet(&ends);
                self.b.ins().jump(merge, &[]);
                self.b.switch_to_block(merge);
                Ok(())
            }
            StmtKind::For {
                var,
                from,
                to,
                by,
                body,
            } => self.for_loop(s, var, from, to, by.as_ref(), body),
            StmtKind::While(c, body) => {
                let head = self.b.create_block();
                let body_b = self.b.create_block();
                let after = self.b.create_block();
                self.b.ins().jump(head, &[]);
                let outer = std::mem::take(&mut self.checked);
                // the head is reached from the body too
                self.elems.clear();
                self.b.switch_to_block(head);
                let c = self.cond(c)?;
                self.b.ins().brif(c, body_b, &[], after, &[]);
                self.b.switch_to_block(body_b);
                self.tick(s.span);
                self.loops.push(LoopTargets {
                    exit: after,
                    next: head,
                    continued: Vec::new(),
                });
                let r = self.block(body);
                self.loops.pop();
                r?;
                self.b.ins().jump(head, &[]);
                self.checked = outer;
                self.elems.clear();
                self.b.switch_to_block(after);
                Ok(())
            }
            StmtKind::Repeat(body, c) => {
                let body_b = self.b.create_block();
                let test = self.b.create_block();
                let after = self.b.create_block();
                self.b.ins().jump(body_b, &[]);
                let outer = std::mem::take(&mut self.checked);
                self.elems.clear();
                self.b.switch_to_block(body_b);
                self.tick(s.span);
                self.loops.push(LoopTargets {
                    exit: after,
                    next: test,
                    continued: Vec::new(),
                });
                let r = self.block(body);
                self.loops.pop();
                r?;
                // CONTINUE jumps to the test from inside the body
                self.checked.clear();
                self.elems.clear();
                self.b.ins().jump(test, &[]);
                self.b.switch_to_block(test);
                let c = self.cond(c)?;
                self.b.ins().brif(c, after, &[], body_b, &[]);
                self.checked = outer;
                self.elems.clear();
                self.b.switch_to_block(after);
                Ok(())
            }
            StmtKind::Exit => {
                let to = self.loops.last().map(|l| l.exit).ok_or(Unsupported)?;
                self.jump_away(to, None);
                Ok(())
            }
            StmtKind::Continue => {
                let known = self.elems.clone();
                let l = self.loops.last_mut().ok_or(Unsupported)?;
                l.continued.push(known);
                let to = l.next;
                self.jump_away(to, None);
                Ok(())
            }
            StmtKind::Return => {
                match self.frames.last().map(|f| f.ret) {
                    // the end of the inlined callee's body
                    Some(Some(ret)) => self.jump_away(ret, None),
                    Some(None) => return Err(Unsupported),
                    None => self.jump_away(self.exit, Some(3)),
                }
                Ok(())
            }
        }
    }

    /// A FOR loop. A counter in a register stepped by a constant carries the elements
    /// over it that the plan names from one iteration to the next (`a[i + 1]` of one is
    /// `a[i]` of the next): loaded before the first iteration, the value known at the end
    /// of an iteration (else loaded there) for the next. A body without loops and calls
    /// whose indices over the counter the plan names gets a second copy without their
    /// checks and without the budget's test, run when a test before the loop shows that
    /// no iteration could fault there (see [`Lower::fast_guard`]).
    fn for_loop(
        &mut self,
        s: &'e Stmt,
        var: &'e Expr,
        from: &'e Expr,
        to: &'e Expr,
        by: Option<&'e Expr>,
        body: &'e [Stmt],
    ) -> L<()> {
        let p = self.resolve(var)?;
        if !p.dynamic.is_empty()
            || p.bit.is_some()
            || p.range.is_some()
            || p.ty.lane() != Some(Lane::Int)
        {
            return Err(Unsupported);
        }
        let vt = p.ty.clone();
        let f = self.expr(from)?;
        self.store(&p, f)?;
        let end = self.cond(to)?;
        let konst = match by {
            None => Some(1),
            Some(b) => match &b.kind {
                ExprKind::Literal(Literal::Int(v, _)) => i64::try_from(*v).ok(),
                _ => None,
            },
        };
        let (step, sign) = match by {
            None => (self.b.ins().iconst(types::I64, 1), Some(true)),
            Some(b) => {
                let v = self.cond(b)?;
                (v, konst.map(|k| k >= 0))
            }
        };
        let JV::I(cur0) = self.load(&p)? else {
            return Err(Unsupported);
        };
        // a counter of 32 bits or less stepped by a constant below 2^31 cannot leave the
        // i64 range: no saturation needed
        let narrow = vt.bits() <= 32 && (vt.is_int() || vt.is_bits());
        let small_step = konst.is_some_and(|k| k.unsigned_abs() < 1 << 31);
        // the counter's value in the body is then the previous one plus the step
        let id = s as *const Stmt as usize;
        let cell = CellKey {
            real: false,
            frame: p.frame,
            off: p.off.i,
        };
        let counter = if !self.plan.plain && self.frames.is_empty() && narrow && small_step {
            self.var_of(&p)
        } else {
            None
        };
        let carrying = counter.is_some();
        let step_k = konst.unwrap_or(0);
        let mut carried: Vec<(Carry, Variable)> = Vec::new();
        if carrying {
            for c in self.plan.carry.get(&id).cloned().unwrap_or_default() {
                let var = self
                    .b
                    .declare_var(if c.at.real { types::F64 } else { types::I64 });
                let v = self.clamped_load(&c, cur0, c.at.key.k)?;
                self.b.def_var(var, v);
                carried.push((c, var));
            }
        }
        let bounds: Vec<Bound> = match counter {
            Some(_) if step_k != 0 && plain_body(body) && !self.plan.unversioned.contains(&id) => {
                self.plan.proven.get(&id).cloned().unwrap_or_default()
            }
            _ => Vec::new(),
        };
        let parts = ForParts {
            s,
            p,
            vt,
            cur0,
            end,
            step,
            sign,
            fixed: narrow && small_step,
            step_k,
            id,
            cell,
            counter,
            carried,
        };
        let after = self.b.create_block();
        let outer = std::mem::take(&mut self.checked);
        match (counter, bounds.is_empty()) {
            (Some(_), false) => {
                let ok = self.fast_guard(&parts, &bounds)?;
                let fast = self.b.create_block();
                let slow = self.b.create_block();
                self.b.ins().brif(ok, fast, &[], slow, &[]);
                self.b.switch_to_block(fast);
                if !self.for_copy(&parts, Some(&bounds), body, after)? {
                    // the body changes the counter: its values are not those tested
                    self.version_failed.push(id);
                }
                self.b.switch_to_block(slow);
                self.for_copy(&parts, None, body, after)?;
            }
            _ => {
                self.for_copy(&parts, None, body, after)?;
            }
        }
        self.checked = outer;
        self.elems.clear();
        self.b.switch_to_block(after);
        Ok(())
    }

    /// Whether no iteration of the loop could fault at an index of `bounds` or exhaust
    /// the budget, tested before the loop: the counter runs from its first value to the
    /// end (both within its type, the value past the end too; the body does not change
    /// it), each `i + k` stays within
    /// `lo..=hi` at both ends (so nowhere between, and never wraps), and the budget holds
    /// at least `|end - first| + 1` iterations.
    fn fast_guard(&mut self, f: &ForParts<'e>, bounds: &[Bound]) -> L<Value> {
        let (tmin, tmax) = f.vt.int_range().ok_or(Unsupported)?;
        let tmin = i64::try_from(tmin).map_err(|_| Unsupported)?;
        let tmax = i64::try_from(tmax).map_err(|_| Unsupported)?;
        let (first, last) = if f.step_k > 0 {
            (f.cur0, f.end)
        } else {
            (f.end, f.cur0)
        };
        // the value past the end is a value of the type too (stored without wrapping)
        let tmin = tmin.checked_sub(f.step_k.min(0)).ok_or(Unsupported)?;
        let tmax = tmax.checked_sub(f.step_k.max(0)).ok_or(Unsupported)?;
        let ge = self
            .b
            .ins()
            .icmp_imm_s(IntCC::SignedGreaterThanOrEqual, f.end, tmin);
        let le = self
            .b
            .ins()
            .icmp_imm_s(IntCC::SignedLessThanOrEqual, f.end, tmax);
        let mut ok = self.b.ins().band(ge, le);
        for bd in bounds {
            let lo_at = self.b.ins().iadd_imm_s(first, bd.k);
            let hi_at = self.b.ins().iadd_imm_s(last, bd.k);
            let a = self
                .b
                .ins()
                .icmp_imm_s(IntCC::SignedGreaterThanOrEqual, lo_at, bd.lo);
            let b = self
                .b
                .ins()
                .icmp_imm_s(IntCC::SignedLessThanOrEqual, hi_at, bd.hi);
            let both = self.b.ins().band(a, b);
            ok = self.b.ins().band(ok, both);
        }
        let span = self.b.ins().isub(last, first);
        let need = self.b.ins().iadd_imm_s(span, 1);
        let left = self.b.use_var(self.budget);
        let none = self
            .b
            .ins()
            .icmp_imm_s(IntCC::SignedLessThanOrEqual, need, 0);
        let enough = self
            .b
            .ins()
            .icmp(IntCC::UnsignedGreaterThanOrEqual, left, need);
        let budget = self.b.ins().bor(none, enough);
        Ok(self.b.ins().band(ok, budget))
    }

    /// One copy of a FOR loop from its first value (`fast`: the indices of `bounds`
    /// unchecked, the budget not tested), leaving to `after`. Returns whether the body
    /// left the counter alone.
    fn for_copy(
        &mut self,
        f: &ForParts<'e>,
        fast: Option<&[Bound]>,
        body: &'e [Stmt],
        after: Block,
    ) -> L<bool> {
        let (cell, id) = (f.cell, f.id);
        let head = self.b.create_block();
        let cur = self.b.append_block_param(head, types::I64);
        let body_b = self.b.create_block();
        let next = self.b.create_block();
        self.b.ins().jump(head, &[f.cur0.into()]);
        // checks made before the loop may not hold for later iterations
        self.checked.clear();
        self.elems.clear();
        self.b.switch_to_block(head);
        let past_up = self.b.ins().icmp(IntCC::SignedGreaterThan, cur, f.end);
        let past_down = self.b.ins().icmp(IntCC::SignedLessThan, cur, f.end);
        let done = match f.sign {
            Some(true) => past_up,
            Some(false) => past_down,
            None => {
                let up = self
                    .b
                    .ins()
                    .icmp_imm_s(IntCC::SignedGreaterThanOrEqual, f.step, 0);
                self.b.ins().select(up, past_up, past_down)
            }
        };
        self.b.ins().brif(done, after, &[], body_b, &[]);
        self.b.switch_to_block(body_b);
        let version = self.versions.get(&cell).copied().unwrap_or(0);
        match (fast, f.counter) {
            (Some(bounds), Some(counter)) => {
                let left = self.b.use_var(self.budget);
                let less = self.b.ins().iadd_imm_s(left, -1);
                self.b.def_var(self.budget, less);
                // `i + k - lo`, the constant folded into the addresses
                let j = self.b.use_var(counter);
                for bd in bounds {
                    self.checked.push(Checked {
                        key: IndexKey {
                            cell,
                            version,
                            k: bd.k,
                        },
                        lo: bd.lo,
                        hi: bd.hi,
                        rel: j,
                        bias: bd.k.checked_sub(bd.lo).ok_or(Unsupported)?,
                    });
                }
            }
            _ => self.tick(f.s.span),
        }
        for (c, var) in &f.carried {
            let at = ElemAt {
                key: IndexKey {
                    cell,
                    version,
                    k: c.at.key.k,
                },
                ..c.at
            };
            let value = self.b.use_var(*var);
            self.elems.push(Elem {
                at,
                exact: true,
                value,
            });
        }
        let carrying = f.counter.is_some();
        if carrying {
            self.fors.push(ForCtx {
                id,
                cell,
                version,
                used: Vec::new(),
                bounds: Vec::new(),
            });
        }
        self.loops.push(LoopTargets {
            exit: after,
            next,
            continued: Vec::new(),
        });
        let r = self.block(body);
        let targets = self.loops.pop();
        let ctx = if carrying { self.fors.pop() } else { None };
        r?;
        self.checked.clear();
        self.b.ins().jump(next, &[]);
        self.b.switch_to_block(next);
        let mut ends = targets.map(|t| t.continued).unwrap_or_default();
        ends.push(std::mem::take(&mut self.elems));
        self.elems = meet(&ends);
        let JV::I(now) = self.load(&f.p)? else {
            return Err(Unsupported);
        };
        let latch_version = self.versions.get(&cell).copied().unwrap_or(0);
        if carrying {
            // the next iteration's `a[i + k]` is this one's `a[i + k + step]`
            for (c, var) in &f.carried {
                let k = c.at.key.k.checked_add(f.step_k).ok_or(Unsupported)?;
                let at = ElemAt {
                    key: IndexKey {
                        cell,
                        version: latch_version,
                        k,
                    },
                    ..c.at
                };
                let value = match self.elems.iter().find(|e| e.at == at) {
                    Some(e) => e.value,
                    None => self.clamped_load(c, now, k)?,
                };
                self.b.def_var(*var, value);
            }
            if let Some(ctx) = ctx {
                let step_k = f.step_k;
                let worth: Vec<Carry> = self
                    .elems
                    .iter()
                    .filter(|e| {
                        e.exact && e.at.key.cell == cell && e.at.key.version == latch_version
                    })
                    .filter_map(|e| {
                        let k = e.at.key.k.checked_sub(step_k)?;
                        ctx.used
                            .iter()
                            .find(|u| {
                                u.at.key.k == k
                                    && u.at
                                        == ElemAt {
                                            key: u.at.key,
                                            ..e.at
                                        }
                            })
                            .cloned()
                    })
                    .collect();
                self.carry_seen.insert(ctx.id, worth);
                self.bounds_seen.insert(ctx.id, ctx.bounds);
            }
        }
        let stepped = if f.fixed {
            self.b.ins().iadd(now, f.step)
        } else {
            self.saturating_add(now, f.step)
        };
        let wrapped = match fast {
            // the guard keeps every value up to the one past the end within the type
            Some(_) if f.fixed => stepped,
            _ => self.wrap(&f.vt, stepped),
        };
        self.store(&f.p, JV::I(wrapped))?;
        self.b.ins().jump(head, &[stepped.into()]);
        Ok(latch_version == version)
    }

    /// An IF with one arm of assignments, without branches: each value and the old one
    /// of its target, the new one selected by the condition, stored (memory that keeps
    /// its value is written all the same). Only when the values are simple and call
    /// nothing, the targets are plain cells or elements (no subrange, no bit); when the
    /// arm would check an index the condition has not, it faults: the next attempt
    /// lowers this IF with branches. Returns whether it did.
    fn select_if(&mut self, s: &'e Stmt, cond: &'e Expr, body: &'e [Stmt]) -> L<bool> {
        let id = s as *const Stmt as usize;
        if std::env::var("NOSEL").is_ok()
            || self.plan.plain
            || self.plan.branchy.contains(&id)
            || body.is_empty()
            || body.len() > 4
        {
            return Ok(false);
        }
        let mut places = Vec::with_capacity(body.len());
        for st in body {
            let StmtKind::Assign(target, value) = &st.kind else {
                return Ok(false);
            };
            if !simple(value) || !simple(target) {
                return Ok(false);
            }
            let p = self.resolve(target)?;
            if p.bit.is_some()
                || p.range.is_some()
                || p.ptr.is_some()
                || !matches!(p.ty.lane(), Some(Lane::Int | Lane::Real))
            {
                return Ok(false);
            }
            places.push((p, value));
        }
        let c = self.cond(cond)?;
        let faults = self.faults.len();
        for (p, value) in places {
            let new = self.expr(value)?;
            let old = self.load(&p)?;
            let x = match (new, old) {
                (JV::I(n), JV::I(o)) => JV::I(self.b.ins().select(c, n, o)),
                (JV::R(n), JV::R(o)) => JV::R(self.b.ins().select(c, n, o)),
                _ => return Err(Unsupported),
            };
            self.store(&p, x)?;
        }
        if self.faults.len() != faults {
            self.select_failed.push(id);
        }
        Ok(true)
    }

    /// The plan for the next attempt, if this one should not be kept.
    fn next_plan(&self, conflicts: Vec<CellKey>) -> Option<Plan> {
        let mut p = self.plan.clone();
        p.branchy.extend(self.select_failed.iter().copied());
        p.unversioned.extend(self.version_failed.iter().copied());
        if !conflicts.is_empty() {
            p.excluded.extend(conflicts);
            return Some(p);
        }
        if !self.select_failed.is_empty() {
            return Some(p);
        }
        if !self.version_failed.is_empty() {
            return Some(p);
        }
        let learnt = self.carry_seen.values().any(|v| !v.is_empty())
            || self.bounds_seen.values().any(|v| !v.is_empty());
        if !p.plain && !p.carry_learnt && learnt {
            p.carry = self.carry_seen.clone();
            p.proven = self.bounds_seen.clone();
            p.carry_learnt = true;
            return Some(p);
        }
        None
    }

    /// A call statement: a FUNCTION or a FB instance, inlined.
    fn call(&mut self, e: &'e Expr) -> L<()> {
        let c = self.cx.c;
        let ExprKind::Call(callee, args) = &e.kind else {
            return Err(Unsupported);
        };
        match c.res.get(&e.id) {
            Some(Res::CallFunction(pid)) => self.call_function(*pid, args).map(|_| ()),
            // the standard timers and edges too: their ST bodies (which their native
            // bodies are tested against) inline to less than a call costs
            Some(Res::CallFb(pid)) => self.call_fb(*pid, callee, args),
            _ => Err(Unsupported),
        }
    }

    /// A call of a user FB instance, inlined: the instance's address, the arguments, the
    /// VAR_TEMP initial values, the body, the outputs (`=>`), in the closures' order.
    fn call_fb(&mut self, pid: PouId, callee: &'e Expr, args: &'e [Arg]) -> L<()> {
        let c = self.cx.c;
        let pou = c.pou(pid).ok_or(Unsupported)?;
        if pou.kind != PouKind::FunctionBlock {
            return Err(Unsupported);
        }
        let inst = self.resolve(callee)?;
        if inst.bit.is_some() || inst.ty != Ty::Fb(pid) {
            return Err(Unsupported);
        }
        let base = self.materialize(inst)?;
        let inouts = self.bind_args(pid, &base, args, false)?;
        self.inline_body(pid, &base, inouts, true)?;
        self.outputs(pid, &base, args)
    }

    /// A call of a user FUNCTION, inlined into its static frame: the arguments and the
    /// frame's initial values, the body, the outputs (`=>`); then the result, if any.
    fn call_function(&mut self, pid: PouId, args: &'e [Arg]) -> L<Option<JV>> {
        let c = self.cx.c;
        let pou = c.pou(pid).ok_or(Unsupported)?;
        if pou.kind != PouKind::Function {
            return Err(Unsupported);
        }
        let base = JPlace {
            frame: false,
            off: pou.base.ok_or(Unsupported)?,
            ptr: None,
            dynamic: Vec::new(),
            region: None,
            ty: Ty::Void,
            bit: None,
            bit_owner: Ty::Void,
            range: None,
        };
        let inouts = self.bind_args(pid, &base, args, true)?;
        self.inline_body(pid, &base, inouts, false)?;
        self.outputs(pid, &base, args)?;
        match &pou.ret {
            Some(t) if *t != Ty::Void => {
                let v = pou.vars.first().ok_or(Unsupported)?;
                let p = callee_var(&base, v);
                if !matches!(p.ty.lane(), Some(Lane::Int | Lane::Real)) {
                    return Err(Unsupported);
                }
                self.load(&p).map(Some)
            }
            _ => Ok(None),
        }
    }

    /// Binds the arguments of a call of `pid` whose variables are at `base`, as
    /// `Cx::bind_args` and the call closures do: inputs stored with their subrange
    /// checks, VAR_IN_OUT bound to the places of the actual arguments (evaluated now,
    /// index checks included). When an argument calls something, every input is
    /// evaluated first and stored afterwards; a FUNCTION's frame gets its initial values
    /// (`function`) before the stores, and before the evaluation otherwise.
    fn bind_args(
        &mut self,
        pid: PouId,
        base: &JPlace<'static>,
        args: &'e [Arg],
        function: bool,
    ) -> L<HashMap<usize, JPlace<'static>>> {
        let c = self.cx.c;
        let pou = c.pou(pid).ok_or(Unsupported)?;
        let split = args.iter().any(|a| contains_call(&a.value));
        let positional: Vec<usize> = pou
            .vars
            .iter()
            .enumerate()
            .filter(|(_, v)| matches!(v.kind, VarKind::Input | VarKind::InOut))
            .map(|(i, _)| i)
            .collect();
        let mut pos = 0;
        let mut targets = Vec::with_capacity(args.len());
        for a in args {
            let idx = match &a.name {
                Some(n) => pou.var(&n.key).map(|(i, _)| i).ok_or(Unsupported)?,
                None => {
                    let i = *positional.get(pos).ok_or(Unsupported)?;
                    pos += 1;
                    i
                }
            };
            let v = pou.vars.get(idx).ok_or(Unsupported)?;
            if !matches!(v.ty.lane(), Some(Lane::Int | Lane::Real)) && v.kind != VarKind::InOut {
                return Err(Unsupported);
            }
            targets.push((a, v));
        }
        let mut values: Vec<Option<JV>> = Vec::new();
        if split {
            for (a, v) in &targets {
                values.push(if a.output || v.kind == VarKind::InOut {
                    None
                } else {
                    Some(self.expr(&a.value)?)
                });
            }
        }
        if function {
            let frame = Frame {
                pou: pid,
                base: base.clone(),
                inouts: HashMap::new(),
                ret: None,
            };
            self.in_frame(frame, |lw| lw.init_vars(pid, base, false))?;
        }
        let mut inouts = HashMap::new();
        for (k, (a, v)) in targets.iter().enumerate() {
            if a.output {
                continue;
            }
            if v.kind == VarKind::InOut {
                let p = self.resolve(&a.value)?;
                // the callee's view of the actual must cover exactly the actual's cells
                if p.bit.is_some() || p.ty != v.ty {
                    return Err(Unsupported);
                }
                let p = self.materialize(p)?;
                let i = pou.var(&v.key).map(|(i, _)| i).ok_or(Unsupported)?;
                inouts.insert(i, p);
                continue;
            }
            let x = match values.get(k).copied().flatten() {
                Some(x) => x,
                None => self.expr(&a.value)?,
            };
            if let (JV::I(x), Some(_)) = (x, v.range) {
                self.range_check(x, v.range, a.value.span, &v.name);
            }
            self.store(&callee_var(base, v), x)?;
        }
        Ok(inouts)
    }

    /// The body of `pid` inlined with its variables at `base`; a FB's VAR_TEMP get their
    /// initial values first (`fb`).
    fn inline_body(
        &mut self,
        pid: PouId,
        base: &JPlace<'static>,
        inouts: HashMap<usize, JPlace<'static>>,
        fb: bool,
    ) -> L<()> {
        let c = self.cx.c;
        let pou = c.pou(pid).ok_or(Unsupported)?;
        let Some(Item::Pou(decl)) = c.unit.items.get(pou.item) else {
            return Err(Unsupported);
        };
        // IEC 61131-3 forbids recursion (the checker rejects it); the depth and the
        // budget bound the code all the same
        if self.frames.len() >= INLINE_DEPTH || self.frames.iter().any(|f| f.pou == pid) {
            return Err(Unsupported);
        }
        self.inline_budget = self
            .inline_budget
            .checked_sub(stmt_count(&decl.body) + 1)
            .ok_or(Unsupported)?;
        let ret = self.b.create_block();
        let frame = Frame {
            pou: pid,
            base: base.clone(),
            inouts,
            ret: Some(ret),
        };
        let scope = self.checked.len();
        self.in_frame(frame, |lw| {
            if fb {
                lw.init_vars(pid, base, true)?;
            }
            lw.block(&decl.body)
        })?;
        self.b.ins().jump(ret, &[]);
        self.b.switch_to_block(ret);
        // a RETURN may have skipped index checks made in the body, and stores
        self.checked.truncate(scope);
        self.elems.clear();
        Ok(())
    }

    /// Runs `f` with the callee `frame` innermost: names resolve in it, and the
    /// caller's loops are no targets of EXIT and CONTINUE.
    fn in_frame<T>(&mut self, frame: Frame, f: impl FnOnce(&mut Self) -> L<T>) -> L<T> {
        let pou = self.cx.pou.replace(frame.pou);
        let loops = std::mem::take(&mut self.loops);
        self.frames.push(frame);
        let r = f(self);
        self.frames.pop();
        self.loops = loops;
        self.cx.pou = pou;
        r
    }

    /// The outputs of a call (`q => x`, `NOT q => x`), after the body, in order.
    fn outputs(&mut self, pid: PouId, base: &JPlace<'static>, args: &'e [Arg]) -> L<()> {
        let c = self.cx.c;
        let pou = c.pou(pid).ok_or(Unsupported)?;
        for a in args.iter().filter(|a| a.output) {
            let name = a.name.as_ref().ok_or(Unsupported)?;
            let (_, v) = pou.var(&name.key).ok_or(Unsupported)?;
            let src = callee_var(base, v);
            if !matches!(src.ty.lane(), Some(Lane::Int | Lane::Real)) {
                return Err(Unsupported);
            }
            let mut x = self.load(&src)?;
            if a.negated {
                if let JV::I(i) = x {
                    let z = self.b.ins().icmp_imm_s(IntCC::Equal, i, 0);
                    x = JV::I(self.b.ins().uextend(types::I64, z));
                }
            }
            let dst = self.resolve(&a.value)?;
            if !matches!(dst.ty.lane(), Some(Lane::Int | Lane::Real)) {
                return Err(Unsupported);
            }
            let dt = dst.ty.clone();
            let x = self.convert(x, &v.ty, &dt)?;
            if let (JV::I(i), Some(_)) = (x, dst.range) {
                self.range_check(i, dst.range, a.value.span, &lvalue_name(&a.value));
            }
            self.store(&dst, x)?;
        }
        Ok(())
    }

    /// Writes the initial values of the callee's variables at `base` as
    /// `Cx::init_value` does: a FUNCTION's whole frame, or a FB's VAR_TEMP (`temps`).
    /// Scalars and arrays of scalars without initialisers; anything else stays with the
    /// closures.
    fn init_vars(&mut self, pid: PouId, base: &JPlace<'static>, temps: bool) -> L<()> {
        let c = self.cx.c;
        let pou = c.pou(pid).ok_or(Unsupported)?;
        for v in &pou.vars {
            if matches!(v.kind, VarKind::External | VarKind::InOut)
                || (temps && v.kind != VarKind::Temp)
            {
                continue;
            }
            let place = callee_var(base, v);
            match &v.ty {
                Ty::Void => {}
                Ty::Array(a) => {
                    let simple = (a.elem.is_elementary() || matches!(a.elem, Ty::Enum(_)))
                        && matches!(a.elem.lane(), Some(Lane::Int | Lane::Real));
                    if !simple || v.init.is_some() || a.elem_init.is_some() || a.len() > 64 {
                        return Err(Unsupported);
                    }
                    let default = match a.elem_range {
                        Some((lo, _)) => lo,
                        None => self.cx.default_int(&a.elem),
                    };
                    for k in 0..a.len() {
                        let mut p = place.clone();
                        p.off = place.off.plus(a.elem_size.times(k));
                        p.ty = a.elem.clone();
                        p.range = None;
                        let x = if p.real() {
                            self.rconst(0.0)
                        } else {
                            self.iconst(default)
                        };
                        self.store(&p, x)?;
                    }
                }
                t if matches!(t.lane(), Some(Lane::Int | Lane::Real)) => {
                    let x = match &v.init {
                        Some(Init::Expr(e)) => {
                            let x = self.expr(e)?;
                            if let (JV::I(i), Some(_)) = (x, v.range) {
                                let name = format!("{}.{}", pou.name, v.name);
                                self.range_check(i, v.range, e.span, &name);
                            }
                            x
                        }
                        _ if place.real() => self.rconst(0.0),
                        _ => {
                            let d = match v.range {
                                Some((lo, _)) => lo,
                                None => self.cx.default_int(t),
                            };
                            self.iconst(d)
                        }
                    };
                    self.store(&place, x)?;
                }
                _ => return Err(Unsupported),
            }
        }
        Ok(())
    }

    /// The place with its run-time indices evaluated (and checked) here, in their
    /// order: a static place as it is, any other as addresses computed now.
    fn materialize(&mut self, p: JPlace<'e>) -> L<JPlace<'static>> {
        let mut out = JPlace {
            frame: p.frame,
            off: p.off,
            ptr: p.ptr,
            dynamic: Vec::new(),
            region: p.region,
            ty: p.ty.clone(),
            bit: p.bit,
            bit_owner: p.bit_owner.clone(),
            range: p.range,
        };
        if p.dynamic.is_empty() {
            return Ok(out);
        }
        let r = p.region.ok_or(Unsupported)?;
        self.regions.push(r);
        self.extents.cover(r.frame, r.start, r.start.plus(r.len));
        let (mut ints, mut reals) = match p.ptr {
            Some(d) => (d.ints, d.reals),
            None if p.frame => (self.frame_ints, self.frame_reals),
            None => (self.ints, self.reals),
        };
        for d in &p.dynamic {
            let (rel, bias) = self.index_rel(d)?;
            let rel = if bias == 0 {
                rel
            } else {
                self.b.ins().iadd_imm_s(rel, bias)
            };
            if d.stride.i > 0 {
                let part = self.b.ins().imul_imm_s(rel, stride_bytes(d.stride.i)?);
                ints = self.b.ins().iadd(ints, part);
            }
            if d.stride.r > 0 {
                let part = self.b.ins().imul_imm_s(rel, stride_bytes(d.stride.r)?);
                reals = self.b.ins().iadd(reals, part);
            }
        }
        out.ptr = Some(Ptrs { ints, reals });
        Ok(out)
    }

    // ---- expressions -----------------------------------------------------------

    fn expr(&mut self, e: &'e Expr) -> L<JV> {
        let v = self.expr_natural(e)?;
        match self.cx.c.coerce.get(&e.id) {
            Some(to) => {
                let from = self.cx.c.ty(e.id);
                self.convert(v, &from, &to.clone())
            }
            None => Ok(v),
        }
    }

    fn iconst(&mut self, v: i64) -> JV {
        JV::I(self.b.ins().iconst(types::I64, v))
    }

    fn rconst(&mut self, v: f64) -> JV {
        JV::R(self.b.ins().f64const(v))
    }

    fn expr_natural(&mut self, e: &'e Expr) -> L<JV> {
        let c = self.cx.c;
        let ty = c.ty(e.id);
        match &e.kind {
            ExprKind::Literal(l) => match l {
                Literal::Int(v, _) => {
                    if ty.is_real() {
                        Ok(self.rconst(crate::stdlib::conv::fit_real(*v as f64, &ty)))
                    } else {
                        Ok(self.iconst(*v as i64))
                    }
                }
                Literal::Real(v, _) => Ok(self.rconst(crate::stdlib::conv::fit_real(*v, &ty))),
                Literal::Bool(b) => Ok(self.iconst(i64::from(*b))),
                Literal::Time(v, _) => Ok(self.iconst(i64::try_from(*v).unwrap_or(i64::MAX))),
                Literal::Date(v) | Literal::Tod(v) | Literal::Dt(v) => Ok(self.iconst(*v)),
                Literal::String(..) => Err(Unsupported),
            },
            ExprKind::Name { .. }
            | ExprKind::Member(..)
            | ExprKind::Index(..)
            | ExprKind::Bit(..) => {
                match c.res.get(&e.id) {
                    Some(Res::EnumValue(v)) => return Ok(self.iconst(*v)),
                    Some(Res::WStringLiteral(_)) => return Err(Unsupported),
                    _ => {}
                }
                let p = self.resolve(e)?;
                if !matches!(p.ty.lane(), Some(Lane::Int | Lane::Real)) {
                    return Err(Unsupported);
                }
                self.load(&p)
            }
            ExprKind::TypedEnum(..) => match c.res.get(&e.id) {
                Some(Res::EnumValue(v)) => Ok(self.iconst(*v)),
                _ => Ok(self.iconst(0)),
            },
            ExprKind::Unary(op, a) => {
                let v = self.expr(a)?;
                Ok(match (op, v) {
                    (UnOp::Plus, v) => v,
                    (UnOp::Neg, JV::I(x)) => {
                        let n = self.b.ins().ineg(x);
                        JV::I(self.wrap(&ty, n))
                    }
                    (UnOp::Neg, JV::R(x)) => JV::R(self.b.ins().fneg(x)),
                    (UnOp::Not, JV::I(x)) => {
                        if ty == Ty::Bool {
                            let z = self.b.ins().icmp_imm_s(IntCC::Equal, x, 0);
                            JV::I(self.b.ins().uextend(types::I64, z))
                        } else {
                            let n = self.b.ins().bnot(x);
                            JV::I(self.wrap(&ty, n))
                        }
                    }
                    (_, v) => v,
                })
            }
            ExprKind::Binary(op, a, b) => self.binary(*op, a, b, &ty, e.span),
            ExprKind::Call(_, args) => match c.res.get(&e.id) {
                // a FUNCTION without a result gives 0, as the closures do
                Some(Res::CallFunction(pid)) => match self.call_function(*pid, args)? {
                    Some(v) => Ok(v),
                    None => Ok(self.iconst(0)),
                },
                // the scan time, as the standard timers' bodies read it
                Some(Res::CallBuiltin(crate::stdlib::Builtin::Now)) if args.is_empty() => {
                    Ok(JV::I(self.now))
                }
                _ => Err(Unsupported),
            },
            _ => Err(Unsupported),
        }
    }

    fn binary(&mut self, op: BinOp, a: &'e Expr, b: &'e Expr, ty: &Ty, span: Span) -> L<JV> {
        use BinOp::*;
        let c = self.cx.c;
        let (ta, tb) = (c.final_ty(a.id), c.final_ty(b.id));
        if matches!(op, And | Or) && *ty == Ty::Bool && may_fault(b) {
            return self.short_circuit(op == And, a, b);
        }
        let va = self.expr(a)?;
        let vb = self.expr(b)?;
        let cmp = matches!(op, Lt | Gt | Le | Ge | Eq | Ne);
        match (va, vb) {
            (JV::I(x), JV::I(y)) => {
                if cmp {
                    let u = is_u64(&ta) || is_u64(&tb);
                    let cc = match (op, u) {
                        (Lt, false) => IntCC::SignedLessThan,
                        (Gt, false) => IntCC::SignedGreaterThan,
                        (Le, false) => IntCC::SignedLessThanOrEqual,
                        (Ge, false) => IntCC::SignedGreaterThanOrEqual,
                        (Lt, true) => IntCC::UnsignedLessThan,
                        (Gt, true) => IntCC::UnsignedGreaterThan,
                        (Le, true) => IntCC::UnsignedLessThanOrEqual,
                        (Ge, true) => IntCC::UnsignedGreaterThanOrEqual,
                        (Eq, _) => IntCC::Equal,
                        _ => IntCC::NotEqual,
                    };
                    let r = self.b.ins().icmp(cc, x, y);
                    return Ok(JV::I(self.b.ins().uextend(types::I64, r)));
                }
                if timey(&ta) || timey(&tb) {
                    let r = match op {
                        Add => self.b.ins().iadd(x, y),
                        Sub => self.b.ins().isub(x, y),
                        Mul => return Ok(JV::I(self.b.ins().imul(x, y))),
                        Div => return Ok(JV::I(self.sdiv(x, y, span, false)?)),
                        _ => return Err(Unsupported),
                    };
                    if *ty == Ty::Tod {
                        return Ok(JV::I(self.rem_euclid_day(r)));
                    }
                    return Ok(JV::I(r));
                }
                let u64op = is_u64(ty);
                let r = match op {
                    Add => self.b.ins().iadd(x, y),
                    Sub => self.b.ins().isub(x, y),
                    Mul => self.b.ins().imul(x, y),
                    Div | Mod => {
                        if u64op {
                            self.nonzero(y, span);
                            let r = if op == Div {
                                self.b.ins().udiv(x, y)
                            } else {
                                self.b.ins().urem(x, y)
                            };
                            return Ok(JV::I(r));
                        }
                        self.sdiv(x, y, span, op == Mod)?
                    }
                    And => return Ok(JV::I(self.b.ins().band(x, y))),
                    Or => return Ok(JV::I(self.b.ins().bor(x, y))),
                    Xor => return Ok(JV::I(self.b.ins().bxor(x, y))),
                    _ => return Err(Unsupported),
                };
                Ok(JV::I(self.wrap(ty, r)))
            }
            (JV::R(x), JV::R(y)) => {
                if cmp {
                    let cc = match op {
                        Lt => FloatCC::LessThan,
                        Gt => FloatCC::GreaterThan,
                        Le => FloatCC::LessThanOrEqual,
                        Ge => FloatCC::GreaterThanOrEqual,
                        Eq => FloatCC::Equal,
                        _ => FloatCC::NotEqual,
                    };
                    let r = self.b.ins().fcmp(cc, x, y);
                    return Ok(JV::I(self.b.ins().uextend(types::I64, r)));
                }
                let r = match op {
                    Add => self.b.ins().fadd(x, y),
                    Sub => self.b.ins().fsub(x, y),
                    Mul => self.b.ins().fmul(x, y),
                    Div => self.b.ins().fdiv(x, y),
                    _ => return Err(Unsupported),
                };
                Ok(JV::R(self.fit(ty, r)))
            }
            _ => Err(Unsupported),
        }
    }

    /// BOOL AND/OR whose right operand may fault: evaluated only when needed.
    fn short_circuit(&mut self, and: bool, a: &'e Expr, b: &'e Expr) -> L<JV> {
        let x = self.cond(a)?;
        let rhs = self.b.create_block();
        let merge = self.b.create_block();
        let r = self.b.append_block_param(merge, types::I64);
        if and {
            self.b.ins().brif(x, rhs, &[], merge, &[x.into()]);
        } else {
            self.b.ins().brif(x, merge, &[x.into()], rhs, &[]);
        }
        self.b.switch_to_block(rhs);
        let scope = self.checked.len();
        let known = self.elems.clone();
        let y = self.cond(b)?;
        self.checked.truncate(scope);
        let rhs_known = std::mem::take(&mut self.elems);
        self.elems = meet(&[known, rhs_known]);
        self.b.ins().jump(merge, &[y.into()]);
        self.b.switch_to_block(merge);
        Ok(JV::I(r))
    }

    fn nonzero(&mut self, y: Value, span: Span) {
        let z = self.b.ins().icmp_imm_s(IntCC::Equal, y, 0);
        self.fault_if(z, FaultSite::DivisionByZero(span), None);
    }

    /// Signed division or remainder with Rust's wrapping results (`MIN / -1 = MIN`,
    /// `MIN MOD -1 = 0`), after the division-by-zero fault.
    fn sdiv(&mut self, x: Value, y: Value, span: Span, rem: bool) -> L<Value> {
        self.nonzero(y, span);
        let minus_one = self.b.ins().icmp_imm_s(IntCC::Equal, y, -1);
        let one = self.b.ins().iconst(types::I64, 1);
        let safe = self.b.ins().select(minus_one, one, y);
        Ok(if rem {
            let r = self.b.ins().srem(x, safe);
            let zero = self.b.ins().iconst(types::I64, 0);
            self.b.ins().select(minus_one, zero, r)
        } else {
            let q = self.b.ins().sdiv(x, safe);
            let n = self.b.ins().ineg(x);
            self.b.ins().select(minus_one, n, q)
        })
    }

    fn rem_euclid_day(&mut self, r: Value) -> Value {
        let m = self.b.ins().srem_imm_s(r, DAY);
        let neg = self.b.ins().icmp_imm_s(IntCC::SignedLessThan, m, 0);
        let up = self.b.ins().iadd_imm_s(m, DAY);
        self.b.ins().select(neg, up, m)
    }

    /// `a + b` saturating at the i64 range.
    fn saturating_add(&mut self, a: Value, b: Value) -> Value {
        let sum = self.b.ins().iadd(a, b);
        // overflow when both operands have the sign the sum lacks
        let sa = self.b.ins().bxor(a, sum);
        let sb = self.b.ins().bxor(b, sum);
        let both = self.b.ins().band(sa, sb);
        let over = self.b.ins().icmp_imm_s(IntCC::SignedLessThan, both, 0);
        let up = self
            .b
            .ins()
            .icmp_imm_s(IntCC::SignedGreaterThanOrEqual, b, 0);
        let max = self.b.ins().iconst(types::I64, i64::MAX);
        let min = self.b.ins().iconst(types::I64, i64::MIN);
        let sat = self.b.ins().select(up, max, min);
        self.b.ins().select(over, sat, sum)
    }

    /// Wraps an integer to the width of `ty` (as [`Ty::wrap`]).
    fn wrap(&mut self, ty: &Ty, v: Value) -> Value {
        let ins = |b: &mut FunctionBuilder<'_>, narrow: Type, signed: bool| {
            let n = b.ins().ireduce(narrow, v);
            if signed {
                b.ins().sextend(types::I64, n)
            } else {
                b.ins().uextend(types::I64, n)
            }
        };
        match ty {
            Ty::Bool => {
                let nz = self.b.ins().icmp_imm_s(IntCC::NotEqual, v, 0);
                self.b.ins().uextend(types::I64, nz)
            }
            Ty::SInt => ins(&mut self.b, types::I8, true),
            Ty::Int => ins(&mut self.b, types::I16, true),
            Ty::DInt => ins(&mut self.b, types::I32, true),
            Ty::USInt | Ty::Byte => ins(&mut self.b, types::I8, false),
            Ty::UInt | Ty::Word => ins(&mut self.b, types::I16, false),
            Ty::UDInt | Ty::DWord => ins(&mut self.b, types::I32, false),
            _ => v,
        }
    }

    /// Rounds to REAL precision when `ty` is REAL (as `conv::fit_real`).
    fn fit(&mut self, ty: &Ty, v: Value) -> Value {
        if *ty == Ty::Real {
            let s = self.b.ins().fdemote(types::F32, v);
            self.b.ins().fpromote(types::F64, s)
        } else {
            v
        }
    }

    /// Implicit conversions (as `compile::expr::convert` for numbers).
    fn convert(&mut self, v: JV, from: &Ty, to: &Ty) -> L<JV> {
        if from == to {
            return Ok(v);
        }
        match (v, to.lane()) {
            (JV::I(x), Some(Lane::Int)) => {
                let same_repr = (from.is_int() || from.is_bits() || *from == Ty::Bool)
                    && (to.is_int() || to.is_bits())
                    && from.converts_to(to);
                if same_repr || (from.is_duration() && to.is_duration()) {
                    return Ok(JV::I(x));
                }
                if plain_int(from) && plain_int(to) {
                    return Ok(JV::I(self.wrap(to, x)));
                }
                Err(Unsupported)
            }
            (JV::I(x), Some(Lane::Real)) => {
                if !plain_int(from) {
                    return Err(Unsupported);
                }
                let f = if is_u64(from) {
                    self.b.ins().fcvt_from_uint(types::F64, x)
                } else {
                    self.b.ins().fcvt_from_sint(types::F64, x)
                };
                Ok(JV::R(self.fit(to, f)))
            }
            (JV::R(x), Some(Lane::Int)) => {
                if *to == Ty::Bool {
                    let z = self.b.ins().f64const(0.0);
                    let ne = self.b.ins().fcmp(FloatCC::NotEqual, x, z);
                    return Ok(JV::I(self.b.ins().uextend(types::I64, ne)));
                }
                if !plain_int(to) || is_u64(to) {
                    return Err(Unsupported);
                }
                let r = self.b.ins().nearest(x);
                let i = self.b.ins().fcvt_to_sint_sat(types::I64, r);
                Ok(JV::I(self.wrap(to, i)))
            }
            (JV::R(x), Some(Lane::Real)) => Ok(JV::R(self.fit(to, x))),
            _ => Err(Unsupported),
        }
    }
}
