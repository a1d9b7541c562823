//! Code generation: the checked AST to *closure-compiled* code.
//!
//! Every expression becomes a boxed closure specialised for its lane and type
//! ([`IFn`] for integer-lane values, [`RFn`] for reals, [`SFn`] for strings) and every
//! statement a [`StmtFn`]. Types, resolution and conversions were decided by the checker,
//! so closures do no type dispatch at run time: an `INT` addition is one closure calling
//! its two operand closures, adding and wrapping to 16 bits. Variable accesses with a
//! static address (the common case) are a single bounds-checked load relative to the
//! current instance frame.
//!
//! Why closures and not a bytecode loop: ST programs are small and branchy; a closure tree
//! has no decode/dispatch overhead per operation, specialises per type at compile time, is
//! memory-safe without `unsafe`, and is far simpler to get right than a register
//! allocator.
//!
//! Hot paths are fused (`fused.rs`): integer and REAL operations read operands that are
//! constants, statically addressed variables or an inline operation of two such leaves
//! that cannot fault (`i * i`, `x * 0.5`, `n > 3`) without a call, and deliver their
//! result into a *sink*: the value, a store into a statically addressed variable
//! (`x := a + b` is one closure) or a branch (`IF a > b THEN` is one closure). One-index
//! array accesses (`a[i]`, `a[i + 1]`, `t[i].Q`) compute their cell inline, and on local
//! arrays indexed by a local (`fused::Elem`) load, store, compare and copy in one
//! closure; runs of integer moves (`t := a[j]; a[j] := a[j + 1]; a[j + 1] := t`), alone
//! or as the branches of an IF, are one closure; 32-bit DIV/MOD by a constant multiply
//! instead of dividing; FOR loops over a local counter with a constant step run a
//! specialised loop that calls a one-statement body directly, keeps the counter in a
//! register when the body cannot write it and the loop budget when the body cannot use
//! it; FB instance addresses and constant FB arguments avoid closure calls;
//! `s := CONCAT(s, ...)` appends in place; TON/TOF/TP/R_TRIG/F_TRIG run native bodies
//! over the instance's cells, called directly when every argument is an inline operand.
//! `Result<Flow, Fault>` is two words, returned in registers.
//!
//! Loops go further: every FOR, WHILE and REPEAT statement whose body is in the subset
//! of `jit` (integer and REAL values, arrays, structs, FB variables, the standard timers
//! and edges, calls of user FUNCTIONs and FBs, inlined) is compiled to machine code by Cranelift, with its counters and
//! accumulators in registers; the closures remain the reference semantics, the code for
//! everything else, and the fallback where the host has no Cranelift backend
//! ([`CompileOptions::jit`], `STANICE_PLC_JIT=0`). The conformance suite and a property
//! test of random loop programs run both ways and compare every variable and fault.
//!
//! Measured with `cargo bench -p plc --bench st_vs_native` (release, a shared 2-core VM,
//! load average about 1.2), time per scan, ST vs the same algorithm in Rust, in one run
//! (figures vary by about 30% between runs on this VM; the ratios much less):
//!
//! | program | ST | ST, closures only | native | ratio |
//! |---|---|---|---|---|
//! | integer loop, 100k iterations | 0.10 ms | 0.51 ms | 0.12 ms | 0.8x (closures 4.3x) |
//! | LREAL loop, 100k iterations | 0.15 ms | 0.39 ms | 0.15 ms | 1.0x (closures 2.7x) |
//! | bubble sort of 200 DINTs, new data every scan | 18 us | 201 us | 31 us | 0.6x (closures 6.6x) |
//! | 1,000 TON instances per scan | 1.3 us | 8.0 us | 0.7 us | 1.7x (closures 11x) |
//! | string building, 100 CONCATs (closures) | 2.4 us | 2.4 us | 1.3 us | 1.8x |
//! | 10k calls of FUNCTIONs and a FB with VAR_IN_OUT | 28 us | 1.26 ms | 20 us | 1.4x (closures 62x) |
//!
//! The sort's swap is branch-free in the JIT (`select`) and branchy in Rust, which
//! mispredicts on new data; on the same array every call Rust took 5.6 us (3.1x).
//! Building a program costs about 0.4 ms more with the JIT (0.46 ms instead of 0.07 ms
//! per benchmark program): Cranelift compiles each loop when the program is built (some
//! twice, with what the first attempt learnt).

mod builtins;
mod expr;
pub(crate) use expr::unpack;
mod fused;
mod jit;
mod stmt;

use crate::check::{Checked, PouId, Size, Ty};
use crate::diagnostics::Diagnostic;
use crate::syntax::{Init, Item, PouKind, Span, VarKind};
use crate::vm::{Code, CompiledPou, Fault, InitFn, StmtFn, Vm};
use std::rc::Rc;

/// Integer-lane expression.
pub type IFn = Box<dyn Fn(&mut Vm) -> Result<i64, Fault>>;
/// Real-lane expression.
pub type RFn = Box<dyn Fn(&mut Vm) -> Result<f64, Fault>>;
/// String-lane expression.
pub type SFn = Box<dyn Fn(&mut Vm) -> Result<String, Fault>>;
/// Address computation (absolute).
pub type AddrFn = Rc<dyn Fn(&mut Vm) -> Result<Size, Fault>>;

/// A compiled scalar expression.
pub enum CE {
    /// Integer lane.
    I(IFn),
    /// Real lane.
    R(RFn),
    /// String lane.
    S(SFn),
}

/// A checked and compiled program, ready for [`crate::task::Plc`].
pub struct Compiled {
    /// Declarations, layout and side tables.
    pub checked: Checked,
    /// Code of every POU.
    pub code: Rc<Code>,
    /// Initialises the global variables (absolute addresses, frame 0).
    pub global_init: Rc<InitFn>,
    /// How many loops run as machine code ([`CompileOptions::jit`]).
    pub jit_loops: usize,
}

/// How a program is compiled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CompileOptions {
    /// Compile loops to machine code where the host supports it (see `compile::jit`);
    /// off, every statement runs as closures. On by default unless the environment
    /// variable `STANICE_PLC_JIT` is `0`.
    pub jit: bool,
}

impl Default for CompileOptions {
    fn default() -> Self {
        CompileOptions {
            jit: std::env::var("STANICE_PLC_JIT").map_or(true, |v| v.trim() != "0"),
        }
    }
}

/// Compiles a checked program with the default options.
pub fn compile(checked: Checked) -> Result<Compiled, Vec<Diagnostic>> {
    compile_with(checked, CompileOptions::default())
}

/// Compiles a checked program.
pub fn compile_with(
    checked: Checked,
    options: CompileOptions,
) -> Result<Compiled, Vec<Diagnostic>> {
    let jit = if options.jit {
        jit::JitEngine::host()
    } else {
        None
    };
    let mut pous = Vec::new();
    let mut diags = Vec::new();
    let global_init;
    {
        let mut cx = Cx {
            c: &checked,
            pou: None,
            diags: &mut diags,
            jit: jit.clone(),
        };
        let mut ops = Vec::new();
        for g in &checked.globals {
            let at = InitTarget::new(&g.name, g.span, g.range);
            cx.init_value(&g.ty, g.init.as_ref(), g.offset, &at, &mut ops);
        }
        global_init = seq_init(ops);
        for (i, p) in checked.pous.iter().enumerate() {
            let mut cx = Cx {
                c: &checked,
                pou: Some(PouId(i)),
                diags: cx.diags,
                jit: jit.clone(),
            };
            let mut ops = Vec::new();
            let mut temps = Vec::new();
            for v in &p.vars {
                if matches!(v.kind, VarKind::External | VarKind::InOut) {
                    continue;
                }
                let at = InitTarget::new(&format!("{}.{}", p.name, v.name), v.span, v.range);
                cx.init_value(&v.ty, v.init.as_ref(), v.offset, &at, &mut ops);
                // IEC 61131-3: VAR_TEMP starts at its initial value on every call (a
                // function's whole frame already does)
                if v.kind == VarKind::Temp && p.kind != PouKind::Function {
                    cx.init_value(&v.ty, v.init.as_ref(), v.offset, &at, &mut temps);
                }
            }
            let init = seq_init(ops);
            let body = match checked.unit.items.get(p.item) {
                Some(Item::Pou(pou)) => cx.block(&pou.body),
                _ => Vec::new(),
            };
            let body: StmtFn = match crate::stdlib::timers::native_body(p) {
                Some(native) => native,
                None if temps.is_empty() => Box::new(move |vm| stmt::run_block(&body, vm)),
                None => {
                    let temps = seq_init(temps);
                    Box::new(move |vm| {
                        temps(vm)?;
                        stmt::run_block(&body, vm)
                    })
                }
            };
            pous.push(CompiledPou { body, init });
        }
    }
    if diags.iter().any(Diagnostic::is_error) {
        return Err(diags);
    }
    Ok(Compiled {
        checked,
        code: Rc::new(Code { pous }),
        global_init: Rc::new(global_init),
        jit_loops: jit.as_ref().map_or(0, |j| j.compiled.get()),
    })
}

fn seq_init(ops: Vec<InitFn>) -> InitFn {
    Box::new(move |vm| {
        for op in &ops {
            op(vm)?;
        }
        Ok(())
    })
}

pub(crate) struct Cx<'a> {
    pub(crate) c: &'a Checked,
    pub(crate) pou: Option<PouId>,
    pub(crate) diags: &'a mut Vec<Diagnostic>,
    /// Compiles loops to machine code when set.
    pub(crate) jit: Option<Rc<jit::JitEngine>>,
}

impl Cx<'_> {
    /// Initialisation of a value of `ty` at frame-relative `off`.
    pub(crate) fn init_value(
        &mut self,
        ty: &Ty,
        init: Option<&Init>,
        off: Size,
        at: &InitTarget,
        ops: &mut Vec<InitFn>,
    ) {
        match ty {
            Ty::Struct(id) => {
                let Some(def) = self.c.types.struct_def(*id) else {
                    return;
                };
                let overrides = match init {
                    Some(Init::Struct(f, _)) => f.as_slice(),
                    _ => &[],
                };
                for f in &def.fields {
                    let given = overrides
                        .iter()
                        .find(|(n, _)| n.key == f.key)
                        .map(|(_, i)| i.clone());
                    // `(inner := (b := 5))` keeps what the field's declaration gives `a`
                    let merged = crate::check::merge_init(given, f.init.clone());
                    let i = merged.as_ref();
                    let fat = InitTarget::new(&format!("{}.{}", at.name, f.name), at.span, f.range);
                    self.init_value(&f.ty, i, off.plus(f.offset), &fat, ops);
                }
            }
            Ty::Array(a) => {
                let n = a.len();
                let mut elems: Vec<Option<&Init>> = Vec::new();
                if let Some(Init::Array(items, _)) = init {
                    for (count, v) in items {
                        let k = match count.as_ref().map(|c| &c.kind) {
                            Some(crate::syntax::ExprKind::Literal(
                                crate::syntax::Literal::Int(k, _),
                            )) => usize::try_from(*k).unwrap_or(0),
                            Some(_) => 1,
                            None => 1,
                        };
                        // `n()`: those elements start as any other of their type
                        let v = match v {
                            Init::Default(_) => None,
                            v => Some(v),
                        };
                        for _ in 0..k.min(n.saturating_sub(elems.len())) {
                            elems.push(v);
                        }
                    }
                }
                let simple = a.elem.is_elementary() || matches!(a.elem, Ty::Enum(_));
                if simple && elems.is_empty() && a.elem_init.is_none() {
                    let size = a.elem_size.times(n);
                    let default = match a.elem_range {
                        Some((lo, _)) => lo,
                        None => self.default_int(&a.elem),
                    };
                    ops.push(Box::new(move |vm| {
                        let b = vm.frame.plus(off);
                        fill(vm, b, size, default)
                    }));
                    return;
                }
                for k in 0..n {
                    let init = elems.get(k).copied().flatten().or(a.elem_init.as_ref());
                    let eat = InitTarget::new(
                        &format!("{}[{}]", at.name, elem_index(a, k)),
                        at.span,
                        a.elem_range,
                    );
                    self.init_value(&a.elem, init, off.plus(a.elem_size.times(k)), &eat, ops);
                }
            }
            Ty::Fb(id) => {
                let id = id.0;
                ops.push(Box::new(move |vm| {
                    let f = vm.frame.plus(off);
                    vm.init(id, f)
                }));
                if let Some(Init::Struct(fields, _)) = init {
                    let pou = self.c.pou(PouId(id)).cloned();
                    for (name, i) in fields {
                        if let Some((_, v)) = pou.as_ref().and_then(|p| p.var(&name.key)) {
                            let vat = InitTarget::new(
                                &format!("{}.{}", at.name, v.name),
                                at.span,
                                v.range,
                            );
                            self.init_value(&v.ty.clone(), Some(i), off.plus(v.offset), &vat, ops);
                        }
                    }
                }
            }
            Ty::Void => {}
            _ => {
                let mut place = expr::Place::frame(off, ty.clone());
                let span = match init {
                    Some(Init::Expr(e)) => e.span,
                    _ => at.span,
                };
                place.range = expr::RangeCheck::new(at.range, span, &at.name);
                let value = match init {
                    Some(Init::Expr(e)) => self.expr(e),
                    _ => match ty.lane() {
                        Some(crate::check::Lane::Real) => CE::R(Box::new(|_| Ok(0.0))),
                        Some(crate::check::Lane::Str) => CE::S(Box::new(|_| Ok(String::new()))),
                        _ => {
                            // the default of a subrange is its lower bound
                            let d = match at.range {
                                Some((lo, _)) => lo,
                                None => self.default_int(ty),
                            };
                            CE::I(Box::new(move |_| Ok(d)))
                        }
                    },
                };
                let st = self.store(&place, value);
                ops.push(Box::new(move |vm| st(vm).map(|_| ())));
            }
        }
    }

    fn default_int(&self, ty: &Ty) -> i64 {
        match ty {
            Ty::Enum(id) => self
                .c
                .types
                .enum_def(*id)
                .and_then(|d| d.values.first())
                .map(|v| v.1)
                .unwrap_or(0),
            _ => 0,
        }
    }
}

/// What an initialiser writes: the name for faults (`Main.a[2]`), the declaration and
/// the subrange bounds, if any.
pub(crate) struct InitTarget {
    name: String,
    span: Span,
    range: Option<(i64, i64)>,
}

impl InitTarget {
    fn new(name: &str, span: Span, range: Option<(i64, i64)>) -> Self {
        InitTarget {
            name: name.to_string(),
            span,
            range,
        }
    }
}

/// The index of the `k`-th element (row-major) as written in ST: `3` or `1, 2`.
fn elem_index(a: &crate::check::ArrayTy, k: usize) -> String {
    let mut rem = k;
    let mut idx = vec![0i64; a.dims.len()];
    for (d, (lo, hi)) in a.dims.iter().enumerate().rev() {
        let span = usize::try_from(hi - lo + 1).unwrap_or(1).max(1);
        if let Some(s) = idx.get_mut(d) {
            *s = lo.saturating_add(i64::try_from(rem % span).unwrap_or(0));
        }
        rem /= span;
    }
    idx.iter()
        .map(i64::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

fn fill(vm: &mut Vm, b: Size, size: Size, default: i64) -> Result<(), Fault> {
    for k in 0..size.i {
        vm.seti(b.i + k, default)?;
    }
    for k in 0..size.r {
        vm.setr(b.r + k, 0.0)?;
    }
    for k in 0..size.s {
        vm.sets(b.s + k, String::new())?;
    }
    Ok(())
}
