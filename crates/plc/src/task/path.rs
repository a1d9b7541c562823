//! Variables by path (`Main.lights[3].Q`): the scalar leaves of the memory image, reading
//! and writing them by value or as IEC literals.

use super::io::{direct_path, direct_ty};
use super::{format_value, parse_value, Plc, PlcError};
use crate::check::{Checked, PouId, Size, Ty};
use crate::syntax::PouKind;
use crate::vm::Val;

/// A scalar variable reached by path.
#[derive(Debug, Clone, PartialEq)]
pub struct Leaf {
    /// `Main.lights[3].Q`
    pub path: String,
    /// Type.
    pub ty: Ty,
    /// Absolute address.
    pub addr: Size,
    /// Declared RETAIN (or inside a RETAIN variable).
    pub retain: bool,
    /// Declared PERSISTENT.
    pub persistent: bool,
}

impl Plc {
    /// Every scalar variable: globals by name, program variables as `Prog.var`, arrays and
    /// structs element by element, FB instances variable by variable.
    pub fn leaves(&self) -> Vec<Leaf> {
        let c = &self.compiled.checked;
        let mut out = Vec::new();
        for g in &c.globals {
            push_leaves(
                c,
                &g.name,
                &g.ty,
                g.offset,
                g.retain,
                g.persistent,
                &mut out,
            );
        }
        for p in &c.pous {
            if p.kind != PouKind::Program || p.stdlib {
                continue;
            }
            let Some(base) = p.base else { continue };
            for v in &p.vars {
                if matches!(
                    v.kind,
                    crate::syntax::VarKind::External | crate::syntax::VarKind::InOut
                ) {
                    continue;
                }
                push_leaves(
                    c,
                    &format!("{}.{}", p.name, v.name),
                    &v.ty,
                    base.plus(v.offset),
                    v.retain,
                    v.persistent,
                    &mut out,
                );
            }
        }
        out
    }

    /// Variables of one program instance.
    pub fn program_leaves(&self, program: &str) -> Result<Vec<Leaf>, PlcError> {
        let c = &self.compiled.checked;
        let pid = c
            .pou_index
            .get(&program.to_uppercase())
            .copied()
            .filter(|p| c.pou(*p).map(|p| p.kind) == Some(PouKind::Program))
            .ok_or_else(|| self.unknown_program(program))?;
        let prefix = format!(
            "{}.",
            c.pou(pid).map(|p| p.name.clone()).unwrap_or_default()
        );
        Ok(self
            .leaves()
            .into_iter()
            .filter(|l| l.path.starts_with(&prefix))
            .collect())
    }

    /// The scalar at `path` (`Main.lights[3].Q`, `counter`, `Main.m[1, 2]`).
    pub fn leaf(&self, path: &str) -> Result<Leaf, PlcError> {
        let c = &self.compiled.checked;
        let segs = split_path(path).ok_or_else(|| PlcError::UnknownPath(path.into()))?;
        let mut it = segs.into_iter();
        let unknown = || PlcError::UnknownPath(path.to_string());
        let (first, first_idx) = it.next().ok_or_else(unknown)?;
        let key = first.to_uppercase();
        let (mut ty, mut addr, retain, persistent, mut pending_idx) =
            if let Some(&g) = c.global_index.get(&key) {
                let g = c.globals.get(g).ok_or_else(unknown)?;
                (g.ty.clone(), g.offset, g.retain, g.persistent, first_idx)
            } else {
                let pid = c.pou_index.get(&key).copied().ok_or_else(unknown)?;
                let p = c.pou(pid).ok_or_else(unknown)?;
                let base = p
                    .base
                    .filter(|_| p.kind == PouKind::Program)
                    .ok_or_else(unknown)?;
                let (name, idx) = it.next().ok_or_else(unknown)?;
                let (_, v) = p
                    .var(&name.to_uppercase())
                    .filter(|(_, v)| v.kind != crate::syntax::VarKind::InOut)
                    .ok_or_else(unknown)?;
                (
                    v.ty.clone(),
                    base.plus(v.offset),
                    v.retain,
                    v.persistent,
                    idx,
                )
            };
        loop {
            for ix in pending_idx.drain(..) {
                let Ty::Array(a) = &ty else {
                    return Err(unknown());
                };
                if ix.len() != a.dims.len() {
                    return Err(unknown());
                }
                let mut lin = 0usize;
                for (v, (lo, hi)) in ix.iter().zip(&a.dims) {
                    if v < lo || v > hi {
                        return Err(unknown());
                    }
                    lin = lin * usize::try_from(hi - lo + 1).unwrap_or(0)
                        + usize::try_from(v - lo).unwrap_or(0);
                }
                addr = addr.plus(a.elem_size.times(lin));
                ty = a.elem.clone();
            }
            let Some((name, idx)) = it.next() else { break };
            let k = name.to_uppercase();
            let (off, t) = match &ty {
                Ty::Struct(id) => {
                    let f = c
                        .types
                        .struct_def(*id)
                        .and_then(|d| d.fields.iter().find(|f| f.key == k))
                        .ok_or_else(unknown)?;
                    (f.offset, f.ty.clone())
                }
                Ty::Fb(id) => {
                    let (_, v) = c
                        .pou(*id)
                        .and_then(|p| p.var(&k))
                        .filter(|(_, v)| v.kind != crate::syntax::VarKind::InOut)
                        .ok_or_else(unknown)?;
                    (v.offset, v.ty.clone())
                }
                _ => return Err(unknown()),
            };
            addr = addr.plus(off);
            ty = t;
            pending_idx = idx;
        }
        if ty.lane().is_none() {
            return Err(PlcError::NotScalar(path.to_string()));
        }
        Ok(Leaf {
            path: path.to_string(),
            ty,
            addr,
            retain,
            persistent,
        })
    }

    /// Reads a scalar resolved once with [`Plc::leaf`]: the fast path for runtimes that
    /// copy the same variables every cycle.
    pub fn read_leaf(&self, l: &Leaf) -> Result<Val, PlcError> {
        let bad = || PlcError::UnknownPath(l.path.clone());
        Ok(match l.ty.lane() {
            Some(crate::check::Lane::Real) => Val::Real(self.vm.getr(l.addr.r).map_err(|_| bad())?),
            Some(crate::check::Lane::Str) => Val::Str(self.vm.gets(l.addr.s).map_err(|_| bad())?),
            _ => Val::Int(self.vm.geti(l.addr.i).map_err(|_| bad())?),
        })
    }

    /// Writes a scalar resolved once with [`Plc::leaf`]. The value must be of the leaf's
    /// lane (integers, BOOL and times as [`Val::Int`], reals as [`Val::Real`]); integers
    /// are wrapped to the variable's type, as an assignment in ST would.
    pub fn write_leaf(&mut self, l: &Leaf, v: Val) {
        let v = match v {
            Val::Int(x) => Val::Int(l.ty.wrap(x)),
            other => other,
        };
        let _ = match v {
            Val::Int(x) => self.vm.seti(l.addr.i, x),
            Val::Real(x) => self.vm.setr(l.addr.r, x),
            Val::Str(x) => self.vm.sets(l.addr.s, x),
        };
    }

    /// Reads a scalar by path, or the process image by direct address (`%QX1.3`).
    pub fn read(&self, path: &str) -> Result<Val, PlcError> {
        if let Some(d) = direct_path(path) {
            let d = d?;
            return Ok(Val::Int(self.vm.io_read(d.area, d.byte, d.bit, d.bits)));
        }
        let l = self.leaf(path)?;
        self.read_leaf(&l)
    }

    pub(super) fn format_leaf(&self, l: &Leaf) -> Result<String, PlcError> {
        let v = self.read_leaf(l)?;
        Ok(format_value(&self.compiled.checked, &l.ty, &v))
    }

    /// Reads a scalar by path as an IEC literal (`TRUE`, `T#5s`, `'text'`).
    pub fn read_text(&self, path: &str) -> Result<String, PlcError> {
        if let Some(d) = direct_path(path) {
            let d = d?;
            let v = Val::Int(self.vm.io_read(d.area, d.byte, d.bit, d.bits));
            return Ok(format_value(&self.compiled.checked, &direct_ty(&d), &v));
        }
        let l = self.leaf(path)?;
        self.format_leaf(&l)
    }

    /// Writes a scalar once (the program may overwrite it in the next cycle). `text` is an
    /// IEC literal of the variable's type.
    ///
    /// A direct address (`%IX0.0`, `%QW2`, `%MD20`; the `%` is required) writes the
    /// process image (a BOOL, BYTE, WORD, DWORD or LWORD literal by the address's size)
    /// and the variables declared `AT` an overlapping address.
    pub fn write(&mut self, path: &str, text: &str) -> Result<(), PlcError> {
        if let Some(d) = direct_path(path) {
            let (d, x) = self.direct_value(d?, text)?;
            self.write_io(&d, x);
            return Ok(());
        }
        let l = self.leaf(path)?;
        let v = parse_value(&self.compiled.checked, &l.ty, text)?;
        self.write_leaf(&l, v);
        Ok(())
    }
}

type Seg = (String, Vec<Vec<i64>>);

pub(super) fn split_path(path: &str) -> Option<Vec<Seg>> {
    let mut out: Vec<Seg> = Vec::new();
    let mut rest = path.trim();
    while !rest.is_empty() {
        let end = rest.find(['.', '[']).unwrap_or(rest.len());
        let name = rest.get(..end)?.trim().to_string();
        rest = rest.get(end..)?;
        let mut idx = Vec::new();
        while let Some(r) = rest.strip_prefix('[') {
            let close = r.find(']')?;
            let inner = r.get(..close)?;
            let v: Option<Vec<i64>> = inner.split(',').map(|x| x.trim().parse().ok()).collect();
            idx.push(v?);
            rest = r.get(close + 1..)?;
        }
        let name = name.trim_start_matches('#').trim_matches('"').to_string();
        if name.is_empty() {
            return None;
        }
        out.push((name, idx));
        if let Some(r) = rest.strip_prefix('.') {
            rest = r;
        } else if !rest.is_empty() {
            return None;
        }
    }
    Some(out)
}

fn push_leaves(
    c: &Checked,
    path: &str,
    ty: &Ty,
    addr: Size,
    retain: bool,
    persistent: bool,
    out: &mut Vec<Leaf>,
) {
    match ty {
        Ty::Array(a) => {
            let n = a.len();
            for k in 0..n {
                // multi-dimensional index from linear k
                let mut rem = k;
                let mut idx = vec![0i64; a.dims.len()];
                for (d, (lo, hi)) in a.dims.iter().enumerate().rev() {
                    let span = usize::try_from(hi - lo + 1).unwrap_or(1).max(1);
                    if let Some(s) = idx.get_mut(d) {
                        *s = lo + (rem % span) as i64;
                    }
                    rem /= span;
                }
                let ix: Vec<String> = idx.iter().map(i64::to_string).collect();
                push_leaves(
                    c,
                    &format!("{path}[{}]", ix.join(", ")),
                    &a.elem,
                    addr.plus(a.elem_size.times(k)),
                    retain,
                    persistent,
                    out,
                );
            }
        }
        Ty::Struct(id) => {
            if let Some(d) = c.types.struct_def(*id) {
                for f in &d.fields {
                    push_leaves(
                        c,
                        &format!("{path}.{}", f.name),
                        &f.ty,
                        addr.plus(f.offset),
                        retain,
                        persistent,
                        out,
                    );
                }
            }
        }
        Ty::Fb(id) => {
            if let Some(p) = c.pou(PouId(id.0)) {
                for v in &p.vars {
                    if matches!(
                        v.kind,
                        crate::syntax::VarKind::External
                            | crate::syntax::VarKind::Temp
                            | crate::syntax::VarKind::InOut
                    ) {
                        continue;
                    }
                    push_leaves(
                        c,
                        &format!("{path}.{}", v.name),
                        &v.ty,
                        addr.plus(v.offset),
                        retain || v.retain,
                        persistent || v.persistent,
                        out,
                    );
                }
            }
        }
        Ty::Void => {}
        _ => out.push(Leaf {
            path: path.to_string(),
            ty: ty.clone(),
            addr,
            retain,
            persistent,
        }),
    }
}
