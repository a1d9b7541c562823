//! The I/O image: direct addresses (`%IX0.0`, `%QW2`, `%MD20`), the variables declared
//! `AT` them, copying inputs in and outputs out around a cycle.

use super::{parse_value, Plc, PlcError};
use crate::check::{Size, Ty};
use crate::syntax::PouKind;
use crate::vm::{DirectAddress, Val};

impl Plc {
    /// The value of a literal for a direct address, by the address's size.
    pub(super) fn direct_value(
        &self,
        d: DirectAddress,
        text: &str,
    ) -> Result<(DirectAddress, i64), PlcError> {
        match parse_value(&self.compiled.checked, &direct_ty(&d), text)? {
            Val::Int(x) => Ok((d, x)),
            _ => Err(PlcError::BadValue {
                text: text.to_string(),
                ty: self.compiled.checked.type_name(&direct_ty(&d)),
            }),
        }
    }

    /// Writes the process image and every variable declared `AT` an overlapping address.
    pub(super) fn write_io(&mut self, d: &DirectAddress, x: i64) {
        self.vm.io_write(d.area, d.byte, d.bit, d.bits, x);
        for (a, ty, b) in &self.io_bindings {
            if overlaps(b, d) {
                let v = self.vm.io_read(b.area, b.byte, b.bit, b.bits);
                let _ = self.vm.seti(a.i, ty.wrap(v));
            }
        }
    }

    pub(super) fn collect_io_bindings(&self) -> Vec<(Size, Ty, DirectAddress)> {
        let c = &self.compiled.checked;
        let mut out = Vec::new();
        for g in &c.globals {
            if let Some(d) = g.at.as_deref().and_then(DirectAddress::parse) {
                out.push((g.offset, g.ty.clone(), d));
            }
        }
        for p in &c.pous {
            if p.kind != PouKind::Program {
                continue;
            }
            let Some(base) = p.base else { continue };
            for v in &p.vars {
                if let Some(d) = v.at.as_deref().and_then(DirectAddress::parse) {
                    out.push((base.plus(v.offset), v.ty.clone(), d));
                }
            }
        }
        out
    }

    pub(super) fn sync_inputs(&mut self) {
        for (a, ty, d) in &self.io_bindings {
            if d.area == 'I' || d.area == 'M' {
                let v = self.vm.io_read(d.area, d.byte, d.bit, d.bits);
                let _ = self.vm.seti(a.i, ty.wrap(v));
            }
        }
    }

    pub(super) fn sync_outputs(&mut self) {
        for (a, _, d) in &self.io_bindings {
            if d.area == 'Q' || d.area == 'M' {
                if let Ok(v) = self.vm.geti(a.i) {
                    self.vm.io_write(d.area, d.byte, d.bit, d.bits, v);
                }
            }
        }
    }

    /// Sets an input (or marker) in the process image by direct address (`%IX0.3`,
    /// `IW4`). Takes effect at the start of the next cycle.
    pub fn set_io(&mut self, address: &str, value: i64) -> Result<(), PlcError> {
        let d = DirectAddress::parse(address.trim_start_matches('%'))
            .ok_or_else(|| PlcError::BadAddress(address.to_string()))?;
        self.vm.io_write(d.area, d.byte, d.bit, d.bits, value);
        Ok(())
    }

    /// Reads the process image by direct address (`%QX0.0`, `%QW2`).
    pub fn get_io(&self, address: &str) -> Result<i64, PlcError> {
        let d = DirectAddress::parse(address.trim_start_matches('%'))
            .ok_or_else(|| PlcError::BadAddress(address.to_string()))?;
        Ok(self.vm.io_read(d.area, d.byte, d.bit, d.bits))
    }
}

/// A direct address written as a path (`%QX1.3`, any case): `None` for variable paths.
pub(super) fn direct_path(path: &str) -> Option<Result<DirectAddress, PlcError>> {
    let rest = path.trim().strip_prefix('%')?;
    Some(
        DirectAddress::parse(&rest.to_ascii_uppercase())
            .ok_or_else(|| PlcError::BadAddress(path.to_string())),
    )
}

/// The type of a direct address by its size.
pub(super) fn direct_ty(d: &DirectAddress) -> Ty {
    match d.bits {
        1 => Ty::Bool,
        8 => Ty::Byte,
        16 => Ty::Word,
        32 => Ty::DWord,
        _ => Ty::LWord,
    }
}

/// Canonical spelling: `%QX1.3`, `%MW10`.
pub(super) fn direct_key(d: &DirectAddress) -> String {
    match d.bits {
        1 => format!("%{}X{}.{}", d.area, d.byte, d.bit),
        n => {
            let size = match n {
                8 => 'B',
                16 => 'W',
                32 => 'D',
                _ => 'L',
            };
            format!("%{}{size}{}", d.area, d.byte)
        }
    }
}

/// Whether two direct addresses share a bit.
fn overlaps(a: &DirectAddress, b: &DirectAddress) -> bool {
    if a.area != b.area {
        return false;
    }
    let end = |d: &DirectAddress| d.byte + (d.bits as usize / 8).max(1);
    if a.byte >= end(b) || b.byte >= end(a) {
        return false;
    }
    !(a.bits == 1 && b.bits == 1 && a.bit != b.bit)
}
