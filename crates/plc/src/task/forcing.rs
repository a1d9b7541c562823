//! Forcing: variables and direct addresses held at a value before and after the programs
//! of every cycle until released.

use super::io::{direct_key, direct_path};
use super::{parse_value, Plc, PlcError};
use crate::check::Size;
use crate::vm::{DirectAddress, Val};

impl Plc {
    /// Forces a variable: the value is applied before and after the programs of every
    /// cycle until [`Plc::release`].
    ///
    /// A direct address (`%IX0.0`, `%QX1.3`, `%MW10`) forces the process image: before
    /// the programs (so inputs and `AT` variables read the forced value) and after them,
    /// after the outputs were copied into the image (so programs cannot override it).
    /// After [`Plc::release`] the image keeps the forced value until the program (outputs,
    /// markers) or the field ([`Plc::set_io`], inputs) writes it again.
    pub fn force(&mut self, path: &str, text: &str) -> Result<(), PlcError> {
        if let Some(d) = direct_path(path) {
            let (d, x) = self.direct_value(d?, text)?;
            self.write_io(&d, x);
            self.io_forces.insert(direct_key(&d), (d, x));
            return Ok(());
        }
        let l = self.leaf(path)?;
        let v = parse_value(&self.compiled.checked, &l.ty, text)?;
        self.write_leaf(&l, v.clone());
        self.forces.insert(path.to_string(), (l.ty, l.addr, v));
        Ok(())
    }

    /// Releases a forced variable; returns whether it was forced.
    pub fn release(&mut self, path: &str) -> bool {
        if let Some(d) = direct_path(path) {
            return match d {
                Ok(d) => self.io_forces.remove(&direct_key(&d)).is_some(),
                Err(_) => false,
            };
        }
        self.forces.remove(path).is_some()
    }

    /// Forced paths and direct addresses (`%QX1.3`).
    pub fn forced(&self) -> Vec<String> {
        self.forces
            .keys()
            .chain(self.io_forces.keys())
            .cloned()
            .collect()
    }

    pub(super) fn apply_io_forces(&mut self) {
        if self.io_forces.is_empty() {
            return;
        }
        let forces: Vec<(DirectAddress, i64)> = self.io_forces.values().copied().collect();
        for (d, x) in forces {
            self.write_io(&d, x);
        }
    }

    pub(super) fn apply_forces(&mut self) {
        let forces: Vec<(Size, Val)> = self
            .forces
            .values()
            .map(|(_, a, v)| (*a, v.clone()))
            .collect();
        for (a, v) in forces {
            let _ = match v {
                Val::Int(x) => self.vm.seti(a.i, x),
                Val::Real(x) => self.vm.setr(a.r, x),
                Val::Str(x) => self.vm.sets(a.s, x),
            };
        }
    }
}
