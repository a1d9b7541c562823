//! Expressions and places (l-values).

use super::{AddrFn, Cx, IFn, RFn, SFn, CE};
use crate::check::{Lane, PouId, Res, Size, Ty};
use crate::diagnostics::{Code, Diagnostic};
use crate::stdlib::{conv, string};
use crate::syntax::*;
use crate::vm::{DirectAddress, Fault, FaultKind, Flow, StmtFn, Vm};
use std::rc::Rc;

#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Base {
    Frame,
    Abs,
    /// The instance or frame of the POU being called (`vm.callee`).
    Callee,
    /// Through the VAR_IN_OUT reference stored at this frame-relative integer cell.
    Indirect(usize),
}

/// Where a value lives.
#[derive(Clone)]
pub(crate) struct Place {
    pub(crate) base: Base,
    pub(crate) off: Size,
    pub(crate) dynamic: Option<AddrFn>,
    pub(crate) ty: Ty,
    /// A bit (`.%X3`) or a part (`.%B1`) of the integer cell at this place.
    pub(crate) bit: Option<BitField>,
    pub(crate) direct: Option<DirectAddress>,
    /// The single run-time index of a one-index access on a static base (fast path).
    pub(crate) index1: Option<Rc<Index1>>,
    /// Subrange bounds checked on stores, with the span of the access for the fault.
    pub(crate) range: Option<Rc<RangeCheck>>,
    /// A single character `s[i]` of the STRING/WSTRING at this place (1-based).
    pub(crate) char_ix: Option<Rc<CharIndex>>,
}

/// Bits `shift .. shift + width` of an integer cell holding a value of type `owner`.
#[derive(Clone, Debug)]
pub(crate) struct BitField {
    pub(crate) shift: u32,
    pub(crate) width: u32,
    pub(crate) owner: Ty,
}

impl BitField {
    /// Bits `shift ..` of a value of type `ty`, which is itself the field `outer` of a
    /// cell if given (`w.%D1.%B0`, `w.%B1.%X3`).
    fn inside(outer: Option<BitField>, ty: &Ty, shift: u32, width: u32) -> BitField {
        match outer {
            Some(o) => BitField {
                shift: o.shift.saturating_add(shift),
                width,
                owner: o.owner,
            },
            None => BitField {
                shift,
                width,
                owner: ty.clone(),
            },
        }
    }

    fn mask(&self) -> i64 {
        if self.width >= 64 {
            -1
        } else {
            (1i64 << self.width) - 1
        }
    }

    /// The field of the cell value `cell`.
    fn get(&self, cell: i64) -> i64 {
        cell.checked_shr(self.shift).unwrap_or(0) & self.mask()
    }

    /// `cell` with the field replaced by `x`, kept in the owner's range (a bit or part
    /// written into the top of an INT makes it negative, as the bits say).
    fn set(&self, cell: i64, x: i64) -> i64 {
        let m = self.mask().checked_shl(self.shift).unwrap_or(0);
        let v = (cell & !m) | ((x & self.mask()).checked_shl(self.shift).unwrap_or(0) & m);
        self.owner.wrap(v)
    }
}

/// The index of a character of a string: `s[i]`, 1-based, checked against the current
/// length.
pub(crate) struct CharIndex {
    f: IFn,
    span: Span,
    /// WSTRING (16-bit characters) rather than STRING (8-bit).
    wide: bool,
}

impl CharIndex {
    /// The byte range of the character in `s`, or the fault.
    fn locate(&self, s: &str, i: i64) -> Result<(usize, usize), Fault> {
        let hit = usize::try_from(i)
            .ok()
            .and_then(|k| k.checked_sub(1))
            .and_then(|k| s.char_indices().nth(k));
        match hit {
            Some((at, c)) => Ok((at, at + c.len_utf8())),
            None => Err(FaultKind::StringIndex {
                span: self.span,
                index: i,
                len: crate::stdlib::string::len(s),
            }
            .into()),
        }
    }

    /// The character code at `i`.
    fn get(&self, vm: &mut Vm, at: usize) -> Result<i64, Fault> {
        let i = (self.f)(vm)?;
        let s = vm.gets_ref(at)?;
        let (a, b) = self.locate(s, i)?;
        let c = s.get(a..b).and_then(|t| t.chars().next()).unwrap_or('\0');
        Ok(i64::from(u32::from(c) & self.mask()))
    }

    /// Replaces the character at `i` by the one with code `x`.
    fn set(&self, vm: &mut Vm, at: usize, x: i64) -> Result<(), Fault> {
        let i = (self.f)(vm)?;
        let code = u32::try_from(x & i64::from(self.mask())).unwrap_or(0);
        let c = char::from_u32(code).unwrap_or('\u{FFFD}');
        let s = vm.strs.get_mut(at).ok_or_else(Fault::memory)?;
        let (a, b) = self.locate(s, i)?;
        let mut buf = [0u8; 4];
        s.replace_range(a..b, c.encode_utf8(&mut buf));
        Ok(())
    }

    fn mask(&self) -> u32 {
        if self.wide {
            0xFFFF
        } else {
            0xFF
        }
    }
}

/// A subrange check on stores: bounds, where and what is written.
pub(crate) struct RangeCheck {
    pub(crate) lo: i64,
    pub(crate) hi: i64,
    pub(crate) span: Span,
    pub(crate) name: Rc<str>,
}

impl RangeCheck {
    pub(crate) fn new(bounds: Option<(i64, i64)>, span: Span, name: &str) -> Option<Rc<Self>> {
        bounds.map(|(lo, hi)| {
            Rc::new(RangeCheck {
                lo,
                hi,
                span,
                name: Rc::from(name),
            })
        })
    }

    /// Whether `x` is inside the bounds.
    #[inline(always)]
    pub(crate) fn contains(&self, x: i64) -> bool {
        x >= self.lo && x <= self.hi
    }

    /// The fault for `x` outside the bounds.
    #[cold]
    pub(crate) fn fault(&self, x: i64) -> Fault {
        FaultKind::RangeError {
            span: self.span,
            name: self.name.to_string(),
            value: x,
            lo: self.lo,
            hi: self.hi,
        }
        .into()
    }

    /// `x` if inside the bounds, else the fault.
    #[inline(always)]
    pub(crate) fn check(&self, x: i64) -> Result<i64, Fault> {
        if self.contains(x) {
            Ok(x)
        } else {
            Err(self.fault(x))
        }
    }
}

/// The source-like name of an l-value (`a[i]`, `s.level`, `Main.x`) for fault messages.
pub(crate) fn lvalue_name(e: &Expr) -> String {
    match &e.kind {
        ExprKind::Name { ident, .. } => ident.name.clone(),
        ExprKind::Member(b, f) => format!("{}.{}", lvalue_name(b), f.name),
        ExprKind::Bit(b, bit) => format!("{}.{bit}", lvalue_name(b)),
        ExprKind::Part(b, width, index) => {
            let letter = crate::syntax::part_letter(*width);
            format!("{}.%{letter}{index}", lvalue_name(b))
        }
        ExprKind::Index(b, idx) => {
            let ix: Vec<String> = idx
                .iter()
                .map(|i| match &i.kind {
                    ExprKind::Literal(Literal::Int(v, _)) => v.to_string(),
                    ExprKind::Name { .. } | ExprKind::Member(..) | ExprKind::Index(..) => {
                        lvalue_name(i)
                    }
                    _ => "..".to_string(),
                })
                .collect();
            format!("{}[{}]", lvalue_name(b), ix.join(", "))
        }
        ExprKind::Direct(d) => format!("%{d}"),
        _ => "?".to_string(),
    }
}

/// How the index value is computed.
pub(crate) enum IdxSrc {
    /// `var + k` (or a constant), wrapped to the index expression's type.
    Inline(super::fused::Opnd, i64, super::stmt::Wrap),
    /// Any expression.
    Expr(IFn),
}

/// One run-time array index: `cell = base + off + (value - lo) * stride` per lane.
pub(crate) struct Index1 {
    pub(crate) f: IdxSrc,
    pub(crate) lo: i64,
    pub(crate) hi: i64,
    pub(crate) stride: Size,
    pub(crate) span: Span,
}

impl Index1 {
    /// Offset (in elements times stride) for the current index value.
    #[inline(always)]
    pub(crate) fn eval(&self, vm: &mut Vm) -> Result<usize, Fault> {
        let v = match &self.f {
            IdxSrc::Inline(o, k, w) => {
                let x = o.get(vm)?;
                if *k == 0 {
                    x
                } else {
                    w.apply(x.wrapping_add(*k))
                }
            }
            IdxSrc::Expr(f) => f(vm)?,
        };
        if v < self.lo || v > self.hi {
            return Err(FaultKind::IndexOutOfRange {
                span: self.span,
                index: v,
                lo: self.lo,
                hi: self.hi,
            }
            .into());
        }
        Ok((v - self.lo) as usize)
    }
}

impl Place {
    pub(crate) fn frame(off: Size, ty: Ty) -> Place {
        Place {
            base: Base::Frame,
            off,
            dynamic: None,
            ty,
            bit: None,
            direct: None,
            index1: None,
            range: None,
            char_ix: None,
        }
    }
    pub(crate) fn abs(off: Size, ty: Ty) -> Place {
        Place {
            base: Base::Abs,
            ..Place::frame(off, ty)
        }
    }

    /// Absolute address of the value.
    pub(crate) fn addr(&self) -> AddrFn {
        let off = self.off;
        match (self.base, self.dynamic.clone()) {
            (Base::Frame, None) => Rc::new(move |vm: &mut Vm| Ok(vm.frame.plus(off))),
            (Base::Abs, None) => Rc::new(move |_: &mut Vm| Ok(off)),
            (Base::Frame, Some(d)) => Rc::new(move |vm: &mut Vm| {
                let x = d(vm)?;
                Ok(vm.frame.plus(off).plus(x))
            }),
            (Base::Abs, Some(d)) => Rc::new(move |vm: &mut Vm| Ok(off.plus(d(vm)?))),
            (Base::Callee, None) => Rc::new(move |vm: &mut Vm| Ok(vm.callee.plus(off))),
            (Base::Callee, Some(d)) => Rc::new(move |vm: &mut Vm| {
                let x = d(vm)?;
                Ok(vm.callee.plus(off).plus(x))
            }),
            (Base::Indirect(r), d) => Rc::new(move |vm: &mut Vm| {
                let b = vm.frame.i + r;
                let target = Size {
                    i: usize::try_from(vm.geti(b)?).map_err(|_| Fault::memory())?,
                    r: usize::try_from(vm.geti(b + 1)?).map_err(|_| Fault::memory())?,
                    s: usize::try_from(vm.geti(b + 2)?).map_err(|_| Fault::memory())?,
                };
                let x = match &d {
                    Some(d) => d(vm)?,
                    None => Size::default(),
                };
                Ok(target.plus(off).plus(x))
            }),
        }
    }
}

fn ty_is_u64(t: &Ty) -> bool {
    matches!(t, Ty::ULInt | Ty::LWord)
}

/// A run-time array index: value, bounds, stride and its span for faults.
type IndexPart = (IFn, i64, i64, usize, Span);

pub(crate) fn konst_i(v: i64) -> IFn {
    Box::new(move |_| Ok(v))
}

impl Cx<'_> {
    pub(crate) fn error(&mut self, span: Span, msg: impl Into<String>) {
        self.diags
            .push(Diagnostic::error(Code::Unsupported, span, msg));
    }

    fn var_place(&self, res: &Res) -> Option<Place> {
        match res {
            Res::Local(i) => {
                let p = self.c.pou(self.pou?)?;
                let v = p.vars.get(*i)?;
                if v.kind == VarKind::InOut {
                    return Some(Place {
                        base: Base::Indirect(v.offset.i),
                        ..Place::frame(Size::default(), v.ty.clone())
                    });
                }
                Some(Place::frame(v.offset, v.ty.clone()))
            }
            Res::Global(g) => {
                let v = self.c.globals.get(*g)?;
                Some(Place::abs(v.offset, v.ty.clone()))
            }
            _ => None,
        }
    }

    /// The place an l-value expression designates.
    pub(crate) fn place(&mut self, e: &Expr) -> Option<Place> {
        match &e.kind {
            ExprKind::Name { .. } => {
                let r = self.c.res.get(&e.id)?.clone();
                let mut p = self.var_place(&r)?;
                let range = match r {
                    Res::Local(i) => self.c.pou(self.pou?)?.vars.get(i)?.range,
                    Res::Global(g) => self.c.globals.get(g)?.range,
                    _ => None,
                };
                p.range = RangeCheck::new(range, e.span, &lvalue_name(e));
                Some(p)
            }
            ExprKind::Direct(d) => {
                let da = DirectAddress::parse(d)?;
                let mut p = Place::abs(Size::default(), self.c.ty(e.id));
                p.direct = Some(da);
                Some(p)
            }
            ExprKind::Member(base, _) => {
                let r = self.c.res.get(&e.id)?.clone();
                if let Some(Res::Program(pid)) = self.c.res.get(&base.id) {
                    let p = self.c.pou(*pid)?;
                    let Res::PouVar(_, i) = r else { return None };
                    let v = p.vars.get(i)?;
                    let mut place = Place::abs(p.base?.plus(v.offset), v.ty.clone());
                    place.range = RangeCheck::new(v.range, e.span, &lvalue_name(e));
                    return Some(place);
                }
                let mut bp = self.place(base)?;
                let (off, ty, range) = match (&bp.ty, r) {
                    (Ty::Struct(id), Res::Field(i)) => {
                        let f = self.c.types.struct_def(*id)?.fields.get(i)?;
                        (f.offset, f.ty.clone(), f.range)
                    }
                    (Ty::Fb(_), Res::PouVar(pid, i)) => {
                        let v = self.c.pou(pid)?.vars.get(i)?;
                        (v.offset, v.ty.clone(), v.range)
                    }
                    _ => return None,
                };
                bp.off = bp.off.plus(off);
                bp.ty = ty;
                bp.range = RangeCheck::new(range, e.span, &lvalue_name(e));
                Some(bp)
            }
            ExprKind::Bit(base, bit) => {
                let mut bp = self.place(base)?;
                if bp.char_ix.is_some() {
                    return None;
                }
                bp.range = None;
                bp.bit = Some(BitField::inside(bp.bit.take(), &bp.ty, *bit, 1));
                bp.ty = Ty::Bool;
                Some(bp)
            }
            ExprKind::Deref(reference) => {
                let CE::I(get) = self.expr(reference) else {
                    return None;
                };
                let span = e.span;
                let target: AddrFn = Rc::new(move |vm: &mut Vm| match get(vm)? {
                    0 => Err(FaultKind::NullReference(span).into()),
                    packed => Ok(unpack(packed - 1)),
                });
                let mut p = Place::abs(Size::default(), self.c.ty(e.id));
                p.dynamic = Some(target);
                Some(p)
            }
            ExprKind::Part(base, width, index) => {
                let mut bp = self.place(base)?;
                if bp.char_ix.is_some() {
                    return None;
                }
                bp.range = None;
                let shift = index.checked_mul(*width)?;
                bp.bit = Some(BitField::inside(bp.bit.take(), &bp.ty, shift, *width));
                bp.ty = self.c.ty(e.id);
                Some(bp)
            }
            ExprKind::Index(base, idx) => {
                let mut bp = self.place(base)?;
                bp.range = None;
                if let (Ty::String(_) | Ty::WString(_), None, [ix]) =
                    (&bp.ty, &bp.char_ix, idx.as_slice())
                {
                    let wide = matches!(bp.ty, Ty::WString(_));
                    let CE::I(f) = self.expr(ix) else { return None };
                    bp.char_ix = Some(Rc::new(CharIndex {
                        f,
                        span: ix.span,
                        wide,
                    }));
                    bp.ty = if wide { Ty::Word } else { Ty::Byte };
                    return Some(bp);
                }
                let Ty::Array(a) = bp.ty.clone() else {
                    return None;
                };
                // strides in elements
                let mut strides = vec![1usize; a.dims.len()];
                let mut acc = 1usize;
                for (k, (lo, hi)) in a.dims.iter().enumerate().rev() {
                    if let Some(s) = strides.get_mut(k) {
                        *s = acc;
                    }
                    acc = acc.saturating_mul(usize::try_from(hi - lo + 1).unwrap_or(0));
                }
                let mut static_lin = 0usize;
                let mut dyn_parts: Vec<IndexPart> = Vec::new();
                let mut inline_src: Option<IdxSrc> = None;
                for ((ix, (lo, hi)), stride) in idx.iter().zip(a.dims.iter()).zip(strides.iter()) {
                    if let ExprKind::Literal(Literal::Int(v, _)) = &ix.kind {
                        let v = *v as i64;
                        if v < *lo || v > *hi {
                            self.diags.push(Diagnostic::error(
                                Code::TypeMismatch,
                                ix.span,
                                format!("array index {v} out of range {lo}..{hi}"),
                            ));
                            return None;
                        }
                        static_lin += usize::try_from(v - lo).unwrap_or(0) * stride;
                        continue;
                    }
                    if idx.len() == 1 && bp.dynamic.is_none() {
                        if let Some(src) = self.inline_index(ix) {
                            inline_src = Some(src);
                            dyn_parts.push((konst_i(0), *lo, *hi, *stride, ix.span));
                            continue;
                        }
                    }
                    let CE::I(f) = self.expr(ix) else { return None };
                    dyn_parts.push((f, *lo, *hi, *stride, ix.span));
                }
                bp.off = bp.off.plus(a.elem_size.times(static_lin));
                if !dyn_parts.is_empty() {
                    let es = a.elem_size;
                    let prev = bp.dynamic.take();
                    bp.index1 = None;
                    let d: AddrFn = if dyn_parts.len() == 1 && prev.is_none() {
                        let (f, lo, hi, stride, span) = dyn_parts.pop()?;
                        let ix = Rc::new(Index1 {
                            f: inline_src.take().unwrap_or(IdxSrc::Expr(f)),
                            lo,
                            hi,
                            stride: es.times(stride),
                            span,
                        });
                        bp.index1 = Some(Rc::clone(&ix));
                        Rc::new(move |vm: &mut Vm| {
                            let k = ix.eval(vm)?;
                            Ok(ix.stride.times(k))
                        })
                    } else {
                        Rc::new(move |vm: &mut Vm| {
                            let mut lin = 0usize;
                            for (f, lo, hi, stride, span) in &dyn_parts {
                                let v = f(vm)?;
                                if v < *lo || v > *hi {
                                    return Err(FaultKind::IndexOutOfRange {
                                        span: *span,
                                        index: v,
                                        lo: *lo,
                                        hi: *hi,
                                    }
                                    .into());
                                }
                                lin += ((v - lo) as usize) * stride;
                            }
                            let base = match &prev {
                                Some(p) => p(vm)?,
                                None => Size::default(),
                            };
                            Ok(base.plus(es.times(lin)))
                        })
                    };
                    bp.dynamic = Some(d);
                }
                bp.ty = a.elem.clone();
                bp.range = RangeCheck::new(a.elem_range, e.span, &lvalue_name(e));
                Some(bp)
            }
            _ => None,
        }
    }

    /// An index of the form `var`, `var + k`, `var - k` or a constant, read inline.
    fn inline_index(&self, e: &Expr) -> Option<IdxSrc> {
        let t = self.c.final_ty(e.id);
        if let Some(o) = self.simple_int(e) {
            return Some(IdxSrc::Inline(o, 0, super::stmt::Wrap::of(&t)));
        }
        if self.c.coerce.contains_key(&e.id) {
            return None;
        }
        let ExprKind::Binary(op @ (BinOp::Add | BinOp::Sub), a, b) = &e.kind else {
            return None;
        };
        let o = self.simple_int(a)?;
        let ExprKind::Literal(Literal::Int(k, _)) = &b.kind else {
            return None;
        };
        let k = i64::try_from(*k).ok()?;
        let k = if *op == BinOp::Sub {
            k.checked_neg()?
        } else {
            k
        };
        Some(IdxSrc::Inline(o, k, super::stmt::Wrap::of(&t)))
    }

    /// Loads a scalar from a place.
    pub(crate) fn load(&self, p: &Place) -> CE {
        if let Some(ci) = p.char_ix.clone() {
            let a = p.addr();
            return CE::I(Box::new(move |vm| {
                let at = a(vm)?;
                ci.get(vm, at.s)
            }));
        }
        if let Some(d) = p.direct {
            return CE::I(Box::new(move |vm| {
                Ok(vm.io_read(d.area, d.byte, d.bit, d.bits))
            }));
        }
        if let Some(field) = p.bit.clone() {
            let a = p.addr();
            return CE::I(Box::new(move |vm| {
                let at = a(vm)?;
                Ok(field.get(vm.geti(at.i)?))
            }));
        }
        let off = p.off;
        if let Some(el) = super::fused::Elem::of(p) {
            return CE::I(Box::new(move |vm| el.get(vm)));
        }
        if let (Some(ix), Some(Lane::Int), Base::Frame | Base::Abs | Base::Callee) =
            (p.index1.clone(), p.ty.lane(), p.base)
        {
            return CE::I(match p.base {
                Base::Frame => Box::new(move |vm| {
                    let k = ix.eval(vm)?;
                    vm.geti(vm.frame.i + off.i + k * ix.stride.i)
                }),
                Base::Abs => Box::new(move |vm| {
                    let k = ix.eval(vm)?;
                    vm.geti(off.i + k * ix.stride.i)
                }),
                _ => Box::new(move |vm| {
                    let k = ix.eval(vm)?;
                    vm.geti(vm.callee.i + off.i + k * ix.stride.i)
                }),
            });
        }
        match (p.ty.lane(), p.base, p.dynamic.is_some()) {
            (Some(Lane::Int), Base::Frame, false) => {
                CE::I(Box::new(move |vm| vm.geti(vm.frame.i + off.i)))
            }
            (Some(Lane::Int), Base::Abs, false) => CE::I(Box::new(move |vm| vm.geti(off.i))),
            (Some(Lane::Int), Base::Callee, false) => {
                CE::I(Box::new(move |vm| vm.geti(vm.callee.i + off.i)))
            }
            (Some(Lane::Real), Base::Frame, false) => {
                CE::R(Box::new(move |vm| vm.getr(vm.frame.r + off.r)))
            }
            (Some(Lane::Real), Base::Abs, false) => CE::R(Box::new(move |vm| vm.getr(off.r))),
            (Some(Lane::Str), _, _) => {
                let a = p.addr();
                CE::S(Box::new(move |vm| {
                    let at = a(vm)?;
                    vm.gets(at.s)
                }))
            }
            (Some(Lane::Real), _, true) => {
                let a = p.addr();
                CE::R(Box::new(move |vm| {
                    let at = a(vm)?;
                    vm.getr(at.r)
                }))
            }
            _ => {
                let a = p.addr();
                CE::I(Box::new(move |vm| {
                    let at = a(vm)?;
                    vm.geti(at.i)
                }))
            }
        }
    }

    /// Stores a scalar value into a place (string truncation, bit insertion, I/O image).
    pub(crate) fn store(&self, p: &Place, v: CE) -> StmtFn {
        let off = p.off;
        let v = match (v, p.range.clone()) {
            (CE::I(f), Some(r)) => CE::I(Box::new(move |vm| r.check(f(vm)?))),
            (v, _) => v,
        };
        if let Some(ci) = p.char_ix.clone() {
            let a = p.addr();
            let CE::I(f) = v else {
                return Box::new(|_| Ok(Flow::Normal));
            };
            return Box::new(move |vm| {
                let x = f(vm)?;
                let at = a(vm)?;
                ci.set(vm, at.s, x)?;
                Ok(Flow::Normal)
            });
        }
        if let Some(d) = p.direct {
            let CE::I(f) = v else {
                return Box::new(|_| Ok(Flow::Normal));
            };
            return Box::new(move |vm| {
                let x = f(vm)?;
                vm.io_write(d.area, d.byte, d.bit, d.bits, x);
                Ok(Flow::Normal)
            });
        }
        if let Some(field) = p.bit.clone() {
            let a = p.addr();
            let CE::I(f) = v else {
                return Box::new(|_| Ok(Flow::Normal));
            };
            return Box::new(move |vm| {
                let x = f(vm)?;
                let at = a(vm)?;
                let old = vm.geti(at.i)?;
                let x = if field.width == 1 {
                    i64::from(x != 0)
                } else {
                    x
                };
                vm.seti(at.i, field.set(old, x))?;
                Ok(Flow::Normal)
            });
        }
        if let (Some(el), CE::I(_)) = (super::fused::Elem::of(p), &v) {
            let CE::I(f) = v else {
                return Box::new(|_| Ok(Flow::Normal));
            };
            return Box::new(move |vm| {
                let x = f(vm)?;
                el.set(vm, x)?;
                Ok(Flow::Normal)
            });
        }
        if let (Some(ix), CE::I(f), Base::Frame | Base::Abs) = (p.index1.clone(), &v, p.base) {
            let _ = f;
            let CE::I(f) = v else {
                return Box::new(|_| Ok(Flow::Normal));
            };
            let frame = p.base == Base::Frame;
            return Box::new(move |vm| {
                let x = f(vm)?;
                let k = ix.eval(vm)?;
                let b = if frame { vm.frame.i } else { 0 };
                vm.seti(b + off.i + k * ix.stride.i, x)?;
                Ok(Flow::Normal)
            });
        }
        match (v, p.base, p.dynamic.is_some()) {
            (CE::I(f), Base::Frame, false) => Box::new(move |vm| {
                let x = f(vm)?;
                vm.seti(vm.frame.i + off.i, x)?;
                Ok(Flow::Normal)
            }),
            (CE::I(f), Base::Callee, false) => Box::new(move |vm| {
                let x = f(vm)?;
                vm.seti(vm.callee.i + off.i, x)?;
                Ok(Flow::Normal)
            }),
            (CE::I(f), Base::Abs, false) => Box::new(move |vm| {
                let x = f(vm)?;
                vm.seti(off.i, x)?;
                Ok(Flow::Normal)
            }),
            (CE::I(f), _, _) => {
                let a = p.addr();
                Box::new(move |vm| {
                    let x = f(vm)?;
                    let at = a(vm)?;
                    vm.seti(at.i, x)?;
                    Ok(Flow::Normal)
                })
            }
            (CE::R(f), Base::Frame, false) => Box::new(move |vm| {
                let x = f(vm)?;
                vm.setr(vm.frame.r + off.r, x)?;
                Ok(Flow::Normal)
            }),
            (CE::R(f), _, _) => {
                let a = p.addr();
                Box::new(move |vm| {
                    let x = f(vm)?;
                    let at = a(vm)?;
                    vm.setr(at.r, x)?;
                    Ok(Flow::Normal)
                })
            }
            (CE::S(f), _, _) => {
                let a = p.addr();
                let max = match p.ty {
                    Ty::String(n) | Ty::WString(n) => n,
                    _ => u32::MAX,
                };
                Box::new(move |vm| {
                    let x = string::truncate(f(vm)?, max);
                    let at = a(vm)?;
                    vm.sets(at.s, x)?;
                    Ok(Flow::Normal)
                })
            }
        }
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

    /// `REF(x)`: the packed absolute address of `x` plus 1, so that 0 is NULL (and memory
    /// that starts zeroed starts NULL).
    fn reference(&mut self, args: &[Arg], span: Span) -> CE {
        let size = self.c.memory_size;
        if size.i > PACK_LIMIT || size.r > PACK_LIMIT || size.s > PACK_LIMIT {
            self.error(
                span,
                "the memory image is too large for references (2 M cells per lane)",
            );
            return CE::I(konst_i(0));
        }
        let Some(place) = args.first().and_then(|a| self.place(&a.value)) else {
            self.error(span, "cannot take the address of this");
            return CE::I(konst_i(0));
        };
        let addr = place.addr();
        CE::I(Box::new(move |vm| Ok(pack(addr(vm)?).wrapping_add(1))))
    }

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

    /// A writer for a place that takes an already evaluated value.
    pub(crate) fn store_val(&self, p: &Place) -> ValWriter {
        let a = p.addr();
        let max = match p.ty {
            Ty::String(n) | Ty::WString(n) => n,
            _ => u32::MAX,
        };
        let range = p.range.clone();
        Rc::new(move |vm, v| {
            let at = a(vm)?;
            match v {
                crate::vm::Val::Int(x) => {
                    if let Some(r) = &range {
                        r.check(x)?;
                    }
                    vm.seti(at.i, x)
                }
                crate::vm::Val::Real(x) => vm.setr(at.r, x),
                crate::vm::Val::Str(x) => vm.sets(at.s, string::truncate(x, max)),
            }
        })
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
    Inline(usize, super::fused::Opnd),
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
/// Writes an evaluated value into a place.
pub(crate) type ValWriter = Rc<dyn Fn(&mut Vm, crate::vm::Val) -> Result<(), Fault>>;

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

// An aggregate source address travels through `Val::Int` between get and put: lanes packed
// 21 bits each (memory images are far below 2 M cells per lane).
/// Cells per lane that [`pack`] can address.
const PACK_LIMIT: usize = 0x1F_FFFF;

pub(crate) fn pack(s: Size) -> i64 {
    ((s.i as i64) << 42) | ((s.r as i64 & 0x1F_FFFF) << 21) | (s.s as i64 & 0x1F_FFFF)
}
pub(crate) fn unpack(p: i64) -> Size {
    Size {
        i: (p >> 42) as usize,
        r: ((p >> 21) & 0x1F_FFFF) as usize,
        s: (p & 0x1F_FFFF) as usize,
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

/// Converts a value between types (implicit widening and `*_TO_*`).
pub(crate) fn convert(v: CE, from: &Ty, to: &Ty, c: &crate::check::Checked) -> CE {
    if from == to {
        return v;
    }
    let (from, to) = (from.clone(), to.clone());
    match v {
        CE::I(f) => match to.lane() {
            Some(Lane::Int) => {
                let same_repr = (from.is_int() || from.is_bits() || from == Ty::Bool)
                    && (to.is_int() || to.is_bits())
                    && from.converts_to(&to);
                if same_repr || (from.is_duration() && to.is_duration()) {
                    CE::I(f)
                } else {
                    CE::I(Box::new(move |vm| Ok(conv::int_to_int(f(vm)?, &from, &to))))
                }
            }
            Some(Lane::Real) => CE::R(Box::new(move |vm| {
                Ok(conv::fit_real(conv::int_to_f64(f(vm)?, &from), &to))
            })),
            Some(Lane::Str) => {
                let names: Option<Vec<(String, i64)>> = match &from {
                    Ty::Enum(id) => c.types.enum_def(*id).map(|d| d.values.clone()),
                    _ => None,
                };
                CE::S(Box::new(move |vm| {
                    let x = f(vm)?;
                    let n = names
                        .as_ref()
                        .and_then(|n| n.iter().find(|(_, v)| *v == x))
                        .map(|(n, _)| n.as_str());
                    Ok(conv::int_to_string(x, &from, n))
                }))
            }
            None => CE::I(f),
        },
        CE::R(f) => match to.lane() {
            Some(Lane::Int) => CE::I(Box::new(move |vm| Ok(conv::real_to_int(f(vm)?, &to)))),
            Some(Lane::Real) => CE::R(Box::new(move |vm| Ok(conv::fit_real(f(vm)?, &to)))),
            Some(Lane::Str) => {
                let single = from == Ty::Real;
                CE::S(Box::new(move |vm| {
                    Ok(crate::vm::format::real(f(vm)?, single))
                }))
            }
            None => CE::R(f),
        },
        CE::S(f) => match to.lane() {
            Some(Lane::Int) => CE::I(Box::new(move |vm| Ok(conv::string_to_int(&f(vm)?, &to)))),
            Some(Lane::Real) => CE::R(Box::new(move |vm| {
                Ok(conv::fit_real(conv::string_to_real(&f(vm)?), &to))
            })),
            _ => CE::S(f),
        },
    }
}

fn unary(op: UnOp, v: CE, ty: &Ty) -> CE {
    let ty = ty.clone();
    match (op, v) {
        (UnOp::Plus, v) => v,
        (UnOp::Neg, CE::I(f)) => CE::I(Box::new(move |vm| Ok(ty.wrap(f(vm)?.wrapping_neg())))),
        (UnOp::Neg, CE::R(f)) => CE::R(Box::new(move |vm| Ok(-f(vm)?))),
        (UnOp::Not, CE::I(f)) => {
            if ty == Ty::Bool {
                CE::I(Box::new(move |vm| Ok(i64::from(f(vm)? == 0))))
            } else {
                CE::I(Box::new(move |vm| Ok(ty.wrap(!f(vm)?))))
            }
        }
        (_, v) => v,
    }
}

const DAY: i64 = 86_400_000_000_000;

#[allow(clippy::too_many_arguments)]
pub(crate) fn binary(op: BinOp, a: CE, b: CE, ta: &Ty, tb: &Ty, ty: &Ty, span: Span) -> CE {
    use BinOp::*;
    let cmp = matches!(op, Lt | Gt | Le | Ge | Eq | Ne);
    match (a, b) {
        (CE::I(a), CE::I(b)) => {
            if cmp {
                let unsigned = ty_is_u64(ta) || ty_is_u64(tb);
                return CE::I(int_cmp(op, a, b, unsigned));
            }
            // time arithmetic
            let timey = |t: &Ty| matches!(t, Ty::Time | Ty::LTime | Ty::Tod | Ty::Dt | Ty::Date);
            if timey(ta) || timey(tb) {
                let tod = *ty == Ty::Tod;
                return CE::I(match op {
                    Add => Box::new(move |vm| {
                        let r = a(vm)?.wrapping_add(b(vm)?);
                        Ok(if tod { r.rem_euclid(DAY) } else { r })
                    }),
                    Sub => Box::new(move |vm| {
                        let r = a(vm)?.wrapping_sub(b(vm)?);
                        Ok(if tod { r.rem_euclid(DAY) } else { r })
                    }),
                    Mul => Box::new(move |vm| Ok(a(vm)?.wrapping_mul(b(vm)?))),
                    Div => Box::new(move |vm| {
                        let x = a(vm)?;
                        let y = b(vm)?;
                        if y == 0 {
                            return Err(Fault::from(FaultKind::DivisionByZero(span)));
                        }
                        Ok(x.wrapping_div(y))
                    }),
                    _ => Box::new(move |vm| a(vm)),
                });
            }
            let t = ty.clone();
            let u64op = ty_is_u64(ty);
            CE::I(match op {
                Add => match t {
                    Ty::LInt | Ty::ULInt | Ty::LWord => {
                        Box::new(move |vm| Ok(a(vm)?.wrapping_add(b(vm)?)))
                    }
                    Ty::DInt => {
                        Box::new(move |vm| Ok(i64::from((a(vm)?.wrapping_add(b(vm)?)) as i32)))
                    }
                    Ty::Int => {
                        Box::new(move |vm| Ok(i64::from((a(vm)?.wrapping_add(b(vm)?)) as i16)))
                    }
                    _ => Box::new(move |vm| Ok(t.wrap(a(vm)?.wrapping_add(b(vm)?)))),
                },
                Sub => match t {
                    Ty::DInt => {
                        Box::new(move |vm| Ok(i64::from((a(vm)?.wrapping_sub(b(vm)?)) as i32)))
                    }
                    _ => Box::new(move |vm| Ok(t.wrap(a(vm)?.wrapping_sub(b(vm)?)))),
                },
                Mul => Box::new(move |vm| Ok(t.wrap(a(vm)?.wrapping_mul(b(vm)?)))),
                Div => Box::new(move |vm| {
                    let x = a(vm)?;
                    let y = b(vm)?;
                    if y == 0 {
                        return Err(Fault::from(FaultKind::DivisionByZero(span)));
                    }
                    if u64op {
                        return Ok(((x as u64) / (y as u64)) as i64);
                    }
                    Ok(t.wrap(x.wrapping_div(y)))
                }),
                Mod => Box::new(move |vm| {
                    let x = a(vm)?;
                    let y = b(vm)?;
                    if y == 0 {
                        return Err(Fault::from(FaultKind::DivisionByZero(span)));
                    }
                    if u64op {
                        return Ok(((x as u64) % (y as u64)) as i64);
                    }
                    Ok(t.wrap(x.wrapping_rem(y)))
                }),
                And => Box::new(move |vm| {
                    let x = a(vm)?;
                    if x == 0 && t == Ty::Bool {
                        return Ok(0);
                    }
                    Ok(x & b(vm)?)
                }),
                Or => Box::new(move |vm| {
                    let x = a(vm)?;
                    if x == 1 && t == Ty::Bool {
                        return Ok(1);
                    }
                    Ok(x | b(vm)?)
                }),
                Xor => Box::new(move |vm| Ok(a(vm)? ^ b(vm)?)),
                Pow => Box::new(move |vm| Ok(t.wrap(crate::stdlib::numeric::ipow(a(vm)?, b(vm)?)))),
                _ => Box::new(move |vm| a(vm)),
            })
        }
        (CE::R(a), CE::R(b)) => {
            if cmp {
                return CE::I(match op {
                    Lt => Box::new(move |vm| Ok(i64::from(a(vm)? < b(vm)?))),
                    Gt => Box::new(move |vm| Ok(i64::from(a(vm)? > b(vm)?))),
                    Le => Box::new(move |vm| Ok(i64::from(a(vm)? <= b(vm)?))),
                    Ge => Box::new(move |vm| Ok(i64::from(a(vm)? >= b(vm)?))),
                    Eq => Box::new(move |vm| Ok(i64::from(a(vm)? == b(vm)?))),
                    _ => Box::new(move |vm| Ok(i64::from(a(vm)? != b(vm)?))),
                });
            }
            let single = *ty == Ty::Real;
            let fit = move |x: f64| if single { f64::from(x as f32) } else { x };
            CE::R(match op {
                Add => Box::new(move |vm| Ok(fit(a(vm)? + b(vm)?))),
                Sub => Box::new(move |vm| Ok(fit(a(vm)? - b(vm)?))),
                Mul => Box::new(move |vm| Ok(fit(a(vm)? * b(vm)?))),
                Div => Box::new(move |vm| Ok(fit(a(vm)? / b(vm)?))),
                Pow => Box::new(move |vm| Ok(fit(a(vm)?.powf(b(vm)?)))),
                _ => Box::new(move |vm| a(vm)),
            })
        }
        (CE::I(a), CE::R(b)) => {
            // TIME * REAL, TIME / REAL
            CE::I(match op {
                Mul => Box::new(move |vm| Ok((a(vm)? as f64 * b(vm)?).round() as i64)),
                Div => Box::new(move |vm| Ok((a(vm)? as f64 / b(vm)?).round() as i64)),
                _ => Box::new(move |vm| a(vm)),
            })
        }
        (CE::R(a), CE::I(b)) => CE::I(Box::new(move |vm| {
            Ok((a(vm)? * b(vm)? as f64).round() as i64)
        })),
        (CE::S(a), CE::S(b)) => CE::I(match op {
            Lt => Box::new(move |vm| Ok(i64::from(a(vm)? < b(vm)?))),
            Gt => Box::new(move |vm| Ok(i64::from(a(vm)? > b(vm)?))),
            Le => Box::new(move |vm| Ok(i64::from(a(vm)? <= b(vm)?))),
            Ge => Box::new(move |vm| Ok(i64::from(a(vm)? >= b(vm)?))),
            Eq => Box::new(move |vm| Ok(i64::from(a(vm)? == b(vm)?))),
            _ => Box::new(move |vm| Ok(i64::from(a(vm)? != b(vm)?))),
        }),
        (a, _) => a,
    }
}

fn int_cmp(op: BinOp, a: IFn, b: IFn, unsigned: bool) -> IFn {
    use BinOp::*;
    if unsigned {
        return match op {
            Lt => Box::new(move |vm| Ok(i64::from((a(vm)? as u64) < (b(vm)? as u64)))),
            Gt => Box::new(move |vm| Ok(i64::from((a(vm)? as u64) > (b(vm)? as u64)))),
            Le => Box::new(move |vm| Ok(i64::from((a(vm)? as u64) <= (b(vm)? as u64)))),
            Ge => Box::new(move |vm| Ok(i64::from((a(vm)? as u64) >= (b(vm)? as u64)))),
            Eq => Box::new(move |vm| Ok(i64::from(a(vm)? == b(vm)?))),
            _ => Box::new(move |vm| Ok(i64::from(a(vm)? != b(vm)?))),
        };
    }
    match op {
        Lt => Box::new(move |vm| Ok(i64::from(a(vm)? < b(vm)?))),
        Gt => Box::new(move |vm| Ok(i64::from(a(vm)? > b(vm)?))),
        Le => Box::new(move |vm| Ok(i64::from(a(vm)? <= b(vm)?))),
        Ge => Box::new(move |vm| Ok(i64::from(a(vm)? >= b(vm)?))),
        Eq => Box::new(move |vm| Ok(i64::from(a(vm)? == b(vm)?))),
        _ => Box::new(move |vm| Ok(i64::from(a(vm)? != b(vm)?))),
    }
}

#[allow(dead_code)]
fn unused(_: RFn, _: SFn) {}
