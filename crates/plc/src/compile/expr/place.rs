//! Places (l-values): where a value lives — frame, absolute, callee, through a
//! VAR_IN_OUT reference — with its run-time index, bit or part, character and subrange
//! check; resolving a variable, member, index, bit or dereference to one.

use super::konst_i;
use super::reference::unpack;
use crate::check::{Res, Size, Ty};
use crate::compile::{AddrFn, Cx, IFn, CE};
use crate::diagnostics::{Code, Diagnostic};
use crate::syntax::*;
use crate::vm::{DirectAddress, Fault, FaultKind, Vm};
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
    pub(super) fn get(&self, cell: i64) -> i64 {
        cell.checked_shr(self.shift).unwrap_or(0) & self.mask()
    }

    /// `cell` with the field replaced by `x`, kept in the owner's range (a bit or part
    /// written into the top of an INT makes it negative, as the bits say).
    pub(super) fn set(&self, cell: i64, x: i64) -> i64 {
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
    pub(super) fn get(&self, vm: &mut Vm, at: usize) -> Result<i64, Fault> {
        let i = (self.f)(vm)?;
        let s = vm.gets_ref(at)?;
        let (a, b) = self.locate(s, i)?;
        let c = s.get(a..b).and_then(|t| t.chars().next()).unwrap_or('\0');
        Ok(i64::from(u32::from(c) & self.mask()))
    }

    /// Replaces the character at `i` by the one with code `x`.
    pub(super) fn set(&self, vm: &mut Vm, at: usize, x: i64) -> Result<(), Fault> {
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
    Inline(crate::compile::fused::Opnd, i64, crate::compile::stmt::Wrap),
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

/// A run-time array index: value, bounds, stride and its span for faults.
type IndexPart = (IFn, i64, i64, usize, Span);

impl Cx<'_> {
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
            return Some(IdxSrc::Inline(o, 0, crate::compile::stmt::Wrap::of(&t)));
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
        Some(IdxSrc::Inline(o, k, crate::compile::stmt::Wrap::of(&t)))
    }
}
