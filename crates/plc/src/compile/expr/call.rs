//! Function calls and argument binding: inputs, VAR_IN_OUT by reference, outputs,
//! aggregates copied; bound directly into the callee or evaluated first.

use super::access::ValWriter;
use super::place::{Base, Place, RangeCheck};
use super::reference::{pack, unpack};
use super::{contains_call, convert};
use crate::check::{PouId, Res, Size, Ty};
use crate::compile::{AddrFn, Cx, CE};
use crate::syntax::*;
use crate::vm::{Fault, Flow, StmtFn, Vm};
use std::rc::Rc;

impl Cx<'_> {
    /// Compiles a call of a user FUNCTION: returns the call (args, body, outputs) and the
    /// absolute place of its result.
    pub(crate) fn call_function(&mut self, pid: PouId, args: &[Arg]) -> (StmtFn, Option<Place>) {
        let Some(pou) = self.c.pou(pid).cloned() else {
            return (Box::new(|_| Ok(Flow::Normal)), None);
        };
        let base = pou.base.unwrap_or_default();
        let id = pid.0;
        let has_args_calls = args.iter().any(|a| contains_call(&a.value));
        let (pre, post) = self.bind_args(&pou, args, !has_args_calls);
        let (direct, pre) = split_pre(pre);
        let call: StmtFn = if has_args_calls {
            // evaluate into temporaries first (a nested call may use the same frame)
            let pre = Rc::new(pre);
            Box::new(move |vm| {
                let mut vals = Vec::with_capacity(pre.len());
                for (get, _) in pre.iter() {
                    vals.push(get(vm)?);
                }
                vm.init(id, base)?;
                let saved = std::mem::replace(&mut vm.callee, base);
                let r = (|| {
                    for ((_, put), v) in pre.iter().zip(vals) {
                        put(vm, v)?;
                    }
                    vm.call(id, base)?;
                    for p in &post {
                        p(vm)?;
                    }
                    Ok(Flow::Normal)
                })();
                vm.callee = saved;
                r
            })
        } else {
            Box::new(move |vm| {
                vm.init(id, base)?;
                let saved = std::mem::replace(&mut vm.callee, base);
                let r = (|| {
                    for b in &direct {
                        b.run(vm)?;
                    }
                    for (get, put) in &pre {
                        let v = get(vm)?;
                        put(vm, v)?;
                    }
                    vm.call(id, base)?;
                    for p in &post {
                        p(vm)?;
                    }
                    Ok(Flow::Normal)
                })();
                vm.callee = saved;
                r
            })
        };
        let result = match &pou.ret {
            Some(t) if *t != Ty::Void => pou
                .vars
                .first()
                .map(|v| Place::abs(base.plus(v.offset), t.clone())),
            _ => None,
        };
        (call, result)
    }

    /// Argument binding for a call: `pre` = (evaluate in the caller, write into the callee),
    /// `post` = outputs and in-out copy-back. Callee variables are addressed relative to
    /// `vm.callee`, which the call sets (and restores) around the binding.
    pub(crate) fn bind_args(
        &mut self,
        pou: &crate::check::PouInfo,
        args: &[Arg],
        direct: bool,
    ) -> (Vec<Pre>, Vec<StmtFn>) {
        let mut pre: Vec<Pre> = Vec::new();
        let mut post: Vec<StmtFn> = Vec::new();
        let positional: Vec<usize> = pou
            .vars
            .iter()
            .enumerate()
            .filter(|(_, v)| matches!(v.kind, VarKind::Input | VarKind::InOut))
            .map(|(i, _)| i)
            .collect();
        let mut pos = 0;
        for a in args {
            let idx = match &a.name {
                Some(n) => match pou.var(&n.key) {
                    Some((i, _)) => i,
                    None => continue,
                },
                None => {
                    let Some(&i) = positional.get(pos) else {
                        continue;
                    };
                    pos += 1;
                    i
                }
            };
            let Some(v) = pou.vars.get(idx) else { continue };
            let target = Place {
                base: Base::Callee,
                range: RangeCheck::new(v.range, a.value.span, &v.name),
                ..Place::frame(v.offset, v.ty.clone())
            };
            if a.output {
                // callee output -> caller variable
                let Some(dst) = self.place(&a.value) else {
                    continue;
                };
                if v.ty.lane().is_none() {
                    let size = self.c.size_of(&v.ty);
                    let sa = target.addr();
                    let da = dst.addr();
                    post.push(Box::new(move |vm| {
                        let s = sa(vm)?;
                        let d = da(vm)?;
                        vm.copy(s, d, size)?;
                        Ok(Flow::Normal)
                    }));
                    continue;
                }
                let mut src = self.load(&target);
                if a.negated {
                    if let CE::I(f) = src {
                        src = CE::I(Box::new(move |vm| Ok(i64::from(f(vm)? == 0))));
                    }
                }
                let dt = dst.ty.clone();
                let src = convert(src, &v.ty, &dt, self.c);
                post.push(self.store(&dst, src));
                continue;
            }
            if v.kind == VarKind::InOut {
                // by reference: the callee's cells get the caller variable's address
                let Some(src) = self.place(&a.value) else {
                    continue;
                };
                if src.char_ix.is_some() {
                    self.error(
                        a.value.span,
                        "a character of a string cannot be passed to VAR_IN_OUT",
                    );
                    continue;
                }
                let sa = src.addr();
                let cell = v.offset.i;
                let bind: Rc<crate::vm::InitFn> = Rc::new(Box::new(move |vm| {
                    let at = sa(vm)?;
                    let b = vm.callee.i + cell;
                    vm.seti(b, at.i as i64)?;
                    vm.seti(b + 1, at.r as i64)?;
                    vm.seti(b + 2, at.s as i64)
                }));
                if direct {
                    pre.push(Pre::Direct(Binder::Code(Box::new(move |vm| {
                        bind(vm)?;
                        Ok(Flow::Normal)
                    }))));
                } else {
                    pre.push(Pre::Split((
                        Box::new(|_| Ok(crate::vm::Val::Int(0))),
                        Box::new(move |vm, _| bind(vm)),
                    )));
                }
                continue;
            }
            if v.ty.lane().is_none() {
                // aggregate input: copy
                let Some(src) = self.agg_source(&a.value) else {
                    continue;
                };
                let size = self.c.size_of(&v.ty);
                let ta = target.addr();
                pre.push(Pre::Split(ArgBind::agg(src, ta, size)));
                continue;
            }
            pre.push(self.arg_pre(&a.value, &target, direct));
        }
        (pre, post)
    }

    /// Stores an argument expression: inline operand when simple.
    fn arg_pre(&mut self, e: &Expr, target: &Place, direct: bool) -> Pre {
        if direct
            && target.base == Base::Callee
            && target.dynamic.is_none()
            && target.bit.is_none()
            && target.range.is_none()
        {
            if let Some(o) = self.simple_int(e) {
                return Pre::Direct(Binder::Inline(target.off.i, o));
            }
        }
        let get = self.expr(e);
        self.scalar_pre(get, target, direct)
    }

    fn scalar_pre(&self, get: CE, target: &Place, direct: bool) -> Pre {
        if direct {
            Pre::Direct(Binder::Code(self.store(target, get)))
        } else {
            Pre::Split(ArgBind::scalar(get, self.store_val(target)))
        }
    }

    /// Source address of an aggregate value: a place, or a function call's result.
    pub(crate) fn agg_source(&mut self, e: &Expr) -> Option<AddrFn> {
        if let ExprKind::Call(_, args) = &e.kind {
            if let Some(Res::CallFunction(pid)) = self.c.res.get(&e.id).cloned() {
                let (call, result) = self.call_function(pid, args);
                let a = result?.addr();
                return Some(Rc::new(move |vm: &mut Vm| {
                    call(vm)?;
                    a(vm)
                }));
            }
            return None;
        }
        Some(self.place(e)?.addr())
    }
}

/// An argument binding: written directly into the callee (`vm.callee` set), or evaluated
/// first and written later.
pub(crate) enum Pre {
    /// Evaluate in the caller and store relative to `vm.callee`.
    Direct(Binder),
    /// Evaluate, keep, store.
    Split(ArgBind),
}

/// A direct argument binding.
pub(crate) enum Binder {
    /// Integer cell of the callee gets an inline operand.
    Inline(usize, crate::compile::fused::Opnd),
    /// Anything else.
    Code(StmtFn),
}

impl Binder {
    /// Runs the binding (`vm.callee` must be set).
    #[inline(always)]
    pub(crate) fn run(&self, vm: &mut Vm) -> Result<(), Fault> {
        match self {
            Binder::Inline(off, o) => {
                let x = o.get(vm)?;
                vm.seti(vm.callee.i + off, x)
            }
            Binder::Code(f) => f(vm).map(|_| ()),
        }
    }
}

/// Separates direct binders from split ones.
pub(crate) fn split_pre(pre: Vec<Pre>) -> (Vec<Binder>, Vec<ArgBind>) {
    let mut d = Vec::new();
    let mut s = Vec::new();
    for p in pre {
        match p {
            Pre::Direct(f) => d.push(f),
            Pre::Split(b) => s.push(b),
        }
    }
    (d, s)
}

/// How one argument is passed.
pub(crate) type ArgGet = Box<dyn Fn(&mut Vm) -> Result<crate::vm::Val, Fault>>;
/// Writes an evaluated argument into the callee.
pub(crate) type ArgPut = Box<dyn Fn(&mut Vm, crate::vm::Val) -> Result<(), Fault>>;

/// An argument binding: get in the caller, put into the callee.
pub(crate) type ArgBind = (ArgGet, ArgPut);

trait ArgBindExt {
    fn scalar(get: CE, put: ValWriter) -> ArgBind;
    fn agg(src: AddrFn, dst: AddrFn, size: Size) -> ArgBind;
}

impl ArgBindExt for ArgBind {
    fn scalar(get: CE, put: ValWriter) -> ArgBind {
        let g: ArgGet = match get {
            CE::I(f) => Box::new(move |vm| Ok(crate::vm::Val::Int(f(vm)?))),
            CE::R(f) => Box::new(move |vm| Ok(crate::vm::Val::Real(f(vm)?))),
            CE::S(f) => Box::new(move |vm| Ok(crate::vm::Val::Str(f(vm)?))),
        };
        (g, Box::new(move |vm, v| put(vm, v)))
    }
    fn agg(src: AddrFn, dst: AddrFn, size: Size) -> ArgBind {
        // the source address is taken in the caller; the copy happens on put
        (
            Box::new(move |vm| {
                let s = src(vm)?;
                Ok(crate::vm::Val::Int(pack(s)))
            }),
            Box::new(move |vm, v| {
                let crate::vm::Val::Int(p) = v else {
                    return Ok(());
                };
                let s = unpack(p);
                let d = dst(vm)?;
                vm.copy(s, d, size)
            }),
        )
    }
}
