//! Native code for loops: a Cranelift JIT behind the closure compiler.
//!
//! # Why
//! The closure tree pays an indirect call per statement and keeps every variable in
//! memory; a tight ST loop (a bubble sort, 1,000 timers per scan) ran 9-27 times slower
//! than the same algorithm in Rust. Loops are where a scan spends its time, so every FOR,
//! WHILE and REPEAT statement whose whole body is in the subset below is compiled to
//! machine code; anything else (and any loop on a host Cranelift does not support) keeps
//! its closures. The two produce the same results, faults and memory: the conformance
//! suite runs every program both ways ([`crate::compile::CompileOptions::jit`]).
//!
//! # Subset
//! Integer-lane and REAL/LREAL values; variables of the POU and globals (scalars, struct
//! fields, FB instance variables, array elements with any number of run-time indices, bit
//! access `x.3`); literals and enumeration values; the arithmetic, comparison and logical
//! operators and the implicit conversions between numbers; assignments, IF, CASE, FOR,
//! WHILE, REPEAT, EXIT, CONTINUE, RETURN; calls of user FUNCTIONs and FB instances (also
//! elements of arrays of instances) and of the standard FBs written in ST, inlined (the
//! timers and edges too: the closures run their native bodies, which are tested against
//! these ST bodies; inlined, they cost less than a call), `__NOW()`. Not in it: strings, calls
//! of built-in functions, the VAR_IN_OUT of the POU the loop is in, partial access
//! (`.%B1`), `^`, direct addresses, `**`, TIME×REAL; a loop with any of these runs as
//! closures (the lowering refuses the node, `lower::Unsupported`).
//!
//! # Calls
//! A call is inlined into the loop's function, mirroring the closures step by step: the
//! FB instance's address (its index checked), the arguments in order with their
//! subrange checks (all evaluated first when one of them calls something), a FUNCTION's
//! whole static frame set to its initial values (before the arguments are evaluated, or
//! between evaluating and storing them), a FB's VAR_TEMP set to theirs, the body
//! (RETURN jumps to its end; its loops tick the same budget), then the outputs (`=>`)
//! and the result. The callee's variables are cells like any other: a FUNCTION's frame
//! and an instance at a static address may live in registers for the whole loop, an
//! instance selected at run time (`fbs[i]`) is addressed through a pointer computed once
//! per call. VAR_IN_OUT are bound at compile time to the places of the actual arguments
//! (an array element's index evaluated and checked when the call binds it, as the
//! closures do): the callee reads and writes the caller's cells directly, and its
//! reference cells, which only the callee reads, are not written. IEC 61131-3 forbids
//! recursion; inlining stops at 16 nested calls or 2,000 statements per loop all the
//! same (closures beyond). Faults in a callee carry the callee's position.
//!
//! # Data flow
//! ```text
//! loop statement ──lower.rs──► Cranelift IR (one function) ──► machine code (JITModule)
//!                               + extents + fault sites                │
//! Vm ──► entry check (extents within the lanes) ──► JitCtx ──► call ───┘ ──► code:
//!        0 normal, 3 RETURN, -k fault site k (value in JitCtx.fault_value)
//! ```
//! Scalars addressed statically (counters, accumulators, `a[3]`) live in registers for
//! the whole loop and are written back on every way out, faults included; cells that an
//! indexed access may also reach stay in memory.
//!
//! Elements of one-dimensional arrays of scalars indexed by `v + k` (`v` a register
//! cell) are stored to memory at once, but their values are remembered where every path
//! loaded or stored them: reading `a[j]` again reuses the value until a store that may
//! reach the same cell (any store but one to `a[j + k']` with another `k'` of the same
//! `j`, or through a VAR_IN_OUT, or a call's return). A FOR loop stepped by a constant
//! carries such values into the next iteration (`a[j + 1]` becomes `a[j]`); the index is
//! checked before every use all the same, so a value loaded for the first iteration
//! at a clamped address is never used out of bounds. An IF with one arm of up to four
//! assignments of simple values (a swap) runs without branches: the new values are
//! selected by the condition and stored (unchanged memory written with its own value);
//! if that arm could fault or call, the next attempt keeps the branch. A FOR loop whose
//! body has no loops and calls and leaves its counter alone gets a second copy without
//! the checks of the indices `i + k` over its counter and without the budget's test
//! (the budget still counts down): a test before the loop picks it when the first and
//! the last value of the counter (and the one past it) are values of its type, every
//! `i + k` is within its bounds at both ends, and the budget holds `|end - first| + 1`
//! iterations; otherwise the checked copy runs and faults where the closures would.
//! Attempts: a loop
//! is lowered again when the first try learnt what to keep in memory, which IF needs its
//! branch or what to carry; the last attempt does neither of the latter.
//!
//! # Safety
//! This module is the one place in the project with `unsafe` code: calling the generated
//! function. The generated code touches only cells
//! inside the extents that [`JitLoop::run`] checks against the lanes before the call; run-time
//! indices are checked against their declared bounds in the generated code (a fault
//! otherwise), so every address stays inside a checked extent. An address computed once
//! for an inlined call (an instance `fbs[i]`, a VAR_IN_OUT bound to `a[j]`) is built from
//! such checked indices, and the whole array it points into is in the extents; a
//! VAR_IN_OUT is only bound to an actual of exactly the parameter's type, so the callee
//! reaches no cell outside it. The lanes are not resized
//! while the code runs (it calls nothing that could).
#![allow(unsafe_code)]

mod lower;

use crate::check::Size;
use crate::syntax::Span;
use crate::vm::{Fault, FaultKind, Flow, StmtFn, Vm};
use cranelift_codegen::settings::{self, Configurable};
use cranelift_jit::{JITBuilder, JITModule};
use cranelift_module::Module;
use std::cell::RefCell;
use std::rc::Rc;

pub(crate) use lower::lower_loop;

/// The machine-code side shared by every compiled loop of one program: the module owns
/// the code and is freed when the last loop referring to it is dropped.
pub(crate) struct JitEngine {
    module: RefCell<Option<JITModule>>,
    ctx: RefCell<cranelift_codegen::Context>,
    fctx: RefCell<cranelift_frontend::FunctionBuilderContext>,
    next: std::cell::Cell<u32>,
    /// Loops compiled so far.
    pub(crate) compiled: std::cell::Cell<usize>,
}

impl JitEngine {
    /// An engine for the host, or `None` where Cranelift does not support it.
    pub(crate) fn host() -> Option<Rc<JitEngine>> {
        let mut flags = settings::builder();
        flags.set("opt_level", "speed").ok()?;
        flags.set("use_colocated_libcalls", "false").ok()?;
        flags.set("is_pic", "false").ok()?;
        let isa = cranelift_native::builder()
            .ok()?
            .finish(settings::Flags::new(flags))
            .ok()?;
        let module = JITModule::new(JITBuilder::with_isa(
            isa,
            cranelift_module::default_libcall_names(),
        ));
        let ctx = module.make_context();
        Some(Rc::new(JitEngine {
            module: RefCell::new(Some(module)),
            ctx: RefCell::new(ctx),
            fctx: RefCell::new(cranelift_frontend::FunctionBuilderContext::new()),
            next: std::cell::Cell::new(0),
            compiled: std::cell::Cell::new(0),
        }))
    }

    /// The pointer type of the host.
    fn pointer_type(&self) -> Option<cranelift_codegen::ir::Type> {
        Some(
            self.module
                .borrow()
                .as_ref()?
                .target_config()
                .pointer_type(),
        )
    }

    /// What the frontend needs to know of the host.
    fn frontend_config(&self) -> Option<cranelift_codegen::isa::TargetFrontendConfig> {
        Some(self.module.borrow().as_ref()?.target_config())
    }

    /// Compiles the function in `ctx` and returns its entry, or `None` on any error.
    fn finish(&self, ctx: &mut cranelift_codegen::Context) -> Option<LoopFn> {
        let mut guard = self.module.borrow_mut();
        let module = guard.as_mut()?;
        let n = self.next.get();
        self.next.set(n.wrapping_add(1));
        let name = format!("st_loop_{n}");
        let id = module
            .declare_function(&name, cranelift_module::Linkage::Local, &ctx.func.signature)
            .ok();
        let defined = id.and_then(|id| module.define_function(id, ctx).ok().map(|_| id));
        module.clear_context(ctx);
        let id = defined?;
        module.finalize_definitions().ok()?;
        let code = module.get_finalized_function(id);
        self.compiled.set(self.compiled.get() + 1);
        // SAFETY: the function was declared with the signature `LoopFn` describes
        // (one pointer parameter, one i64 result, the host's C calling convention).
        Some(unsafe { std::mem::transmute::<*const u8, LoopFn>(code) })
    }
}

impl Drop for JitEngine {
    fn drop(&mut self) {
        if let Some(m) = self.module.get_mut().take() {
            // SAFETY: the engine is dropped when the last `JitLoop` holding it is, so no
            // function of the module can be called any more.
            unsafe { m.free_memory() };
        }
    }
}

/// The generated function: takes the context, returns 0 (normal), 3 (RETURN) or
/// `-(k + 1)` for fault site `k`.
type LoopFn = unsafe extern "C" fn(*mut JitCtx) -> i64;

/// What the generated code reads and writes besides the memory lanes. `repr(C)`: the
/// generated code addresses the fields by the offsets in [`ctx_offset`].
#[repr(C)]
pub(crate) struct JitCtx {
    ints: *mut i64,
    reals: *mut f64,
    frame_i: i64,
    frame_r: i64,
    now: i64,
    budget: u64,
    fault_value: i64,
}

/// Byte offsets of the [`JitCtx`] fields.
mod ctx_offset {
    pub(super) const INTS: i32 = 0;
    pub(super) const REALS: i32 = 8;
    pub(super) const FRAME_I: i32 = 16;
    pub(super) const FRAME_R: i32 = 24;
    pub(super) const NOW: i32 = 32;
    pub(super) const BUDGET: i32 = 40;
    pub(super) const FAULT_VALUE: i32 = 48;
}

const _: () = {
    assert!(std::mem::size_of::<*mut i64>() == 8);
    assert!(std::mem::offset_of!(JitCtx, fault_value) == ctx_offset::FAULT_VALUE as usize);
    assert!(std::mem::offset_of!(JitCtx, budget) == ctx_offset::BUDGET as usize);
    assert!(std::mem::offset_of!(JitCtx, now) == ctx_offset::NOW as usize);
    assert!(std::mem::offset_of!(JitCtx, frame_r) == ctx_offset::FRAME_R as usize);
    assert!(std::mem::offset_of!(JitCtx, frame_i) == ctx_offset::FRAME_I as usize);
    assert!(std::mem::offset_of!(JitCtx, reals) == ctx_offset::REALS as usize);
    assert!(std::mem::offset_of!(JitCtx, ints) == ctx_offset::INTS as usize);
};

/// A place in the code that can fault; the value (index, stored value) comes in
/// [`JitCtx::fault_value`].
#[derive(Clone)]
pub(crate) enum FaultSite {
    DivisionByZero(Span),
    Index {
        span: Span,
        lo: i64,
        hi: i64,
    },
    Range {
        span: Span,
        name: Rc<str>,
        lo: i64,
        hi: i64,
    },
    LoopBudget(Span),
}

impl FaultSite {
    fn fault(&self, value: i64) -> Fault {
        match self {
            FaultSite::DivisionByZero(s) => FaultKind::DivisionByZero(*s),
            FaultSite::Index { span, lo, hi } => FaultKind::IndexOutOfRange {
                span: *span,
                index: value,
                lo: *lo,
                hi: *hi,
            },
            FaultSite::Range { span, name, lo, hi } => FaultKind::RangeError {
                span: *span,
                name: name.to_string(),
                value,
                lo: *lo,
                hi: *hi,
            },
            FaultSite::LoopBudget(s) => FaultKind::LoopBudget(*s),
        }
        .into()
    }
}

/// The cells a compiled loop may touch: one past the highest cell per lane relative to
/// the frame, and the range of absolute (global) cells per lane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Extents {
    frame: Size,
    abs_start: Size,
    abs: Size,
}

impl Default for Extents {
    fn default() -> Self {
        Extents {
            frame: Size::default(),
            abs_start: Size {
                i: usize::MAX,
                r: usize::MAX,
                s: 0,
            },
            abs: Size::default(),
        }
    }
}

impl Extents {
    /// Covers the cells `start..end` (per lane; a lane with `start == end` is untouched).
    fn cover(&mut self, frame: bool, start: Size, end: Size) {
        if frame {
            self.frame.i = self.frame.i.max(end.i);
            self.frame.r = self.frame.r.max(end.r);
            return;
        }
        if end.i > start.i {
            self.abs_start.i = self.abs_start.i.min(start.i);
            self.abs.i = self.abs.i.max(end.i);
        }
        if end.r > start.r {
            self.abs_start.r = self.abs_start.r.min(start.r);
            self.abs.r = self.abs.r.max(end.r);
        }
    }

    /// Whether the absolute cells may be cells of the frame too (an FB instance declared
    /// as a global, its loop naming the global): then registers could hold two copies
    /// of one cell, and the loop runs as closures.
    fn aliased(&self, frame: Size) -> bool {
        let overlap = |f: usize, len: usize, a0: usize, a1: usize| {
            len > 0 && a1 > a0 && f < a1 && a0 < f.saturating_add(len)
        };
        overlap(frame.i, self.frame.i, self.abs_start.i, self.abs.i)
            || overlap(frame.r, self.frame.r, self.abs_start.r, self.abs.r)
    }

    /// Whether the loop names any absolute cell.
    pub(crate) fn has_abs(&self) -> bool {
        self.abs.i > 0 || self.abs.r > 0
    }
}

/// A loop compiled to machine code.
pub(crate) struct JitLoop {
    code: LoopFn,
    extents: Extents,
    faults: Box<[FaultSite]>,
    /// The same loop as closures, for a frame the absolute cells alias.
    pub(crate) fallback: Option<StmtFn>,
    /// Keeps the code alive.
    _engine: Rc<JitEngine>,
}

impl JitLoop {
    /// Whether the loop names absolute cells, which some frame could alias.
    pub(crate) fn needs_fallback(&self) -> bool {
        self.extents.has_abs()
    }

    /// Runs the loop on the current frame.
    pub(crate) fn run(&self, vm: &mut Vm) -> Result<Flow, Fault> {
        let fi = vm.frame.i.checked_add(self.extents.frame.i);
        let fr = vm.frame.r.checked_add(self.extents.frame.r);
        let inside = fi.is_some_and(|e| e <= vm.ints.len())
            && fr.is_some_and(|e| e <= vm.reals.len())
            && self.extents.abs.i <= vm.ints.len()
            && self.extents.abs.r <= vm.reals.len();
        if !inside {
            return Err(Fault::memory());
        }
        if self.extents.aliased(vm.frame) {
            return match &self.fallback {
                Some(f) => f(vm),
                None => Err(Fault::memory()),
            };
        }
        let mut ctx = JitCtx {
            ints: vm.ints.as_mut_ptr(),
            reals: vm.reals.as_mut_ptr(),
            frame_i: vm.frame.i as i64,
            frame_r: vm.frame.r as i64,
            now: vm.now,
            budget: vm.budget,
            fault_value: 0,
        };
        // SAFETY: see the module documentation: the extents were checked above, indexes
        // are checked by the code, and `ctx` outlives the call.
        let code = unsafe { (self.code)(&mut ctx) };
        vm.budget = ctx.budget;
        match code {
            0 => Ok(Flow::Normal),
            3 => Ok(Flow::Return),
            c if c < 0 => {
                let k = usize::try_from(-(c + 1)).unwrap_or(usize::MAX);
                Err(self
                    .faults
                    .get(k)
                    .map(|s| s.fault(ctx.fault_value))
                    .unwrap_or_else(Fault::memory))
            }
            _ => Err(Fault::memory()),
        }
    }
}
