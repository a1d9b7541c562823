//! RETAIN and PERSISTENT variables saved to and restored from a file.

use super::{Plc, PlcError};
use std::path::Path;

impl Plc {
    /// Writes RETAIN and PERSISTENT variables to `path` atomically (temporary file, then
    /// rename). One `path = value` line each, values in IEC literal syntax.
    pub fn save_retain(&self, path: &Path) -> Result<(), PlcError> {
        let mut text = String::new();
        for l in self.leaves() {
            if l.retain || l.persistent {
                let kind = if l.persistent { "PERSISTENT" } else { "RETAIN" };
                let v = self.format_leaf(&l).unwrap_or_default();
                text.push_str(&format!("{kind} {} = {v}\n", l.path));
            }
        }
        let tmp = path.with_extension("tmp");
        std::fs::write(&tmp, text)?;
        std::fs::rename(&tmp, path)?;
        Ok(())
    }

    /// Restores variables saved by [`Plc::save_retain`]. With `persistent_only`, only
    /// PERSISTENT values are applied (cold start, program download). Unknown paths and
    /// values that no longer fit their type are skipped; returns how many were restored.
    pub fn load_retain(&mut self, path: &Path, persistent_only: bool) -> Result<usize, PlcError> {
        let text = std::fs::read_to_string(path)?;
        let mut n = 0;
        for line in text.lines() {
            let Some((kind, rest)) = line.split_once(' ') else {
                continue;
            };
            let Some((p, v)) = rest.split_once(" = ") else {
                continue;
            };
            if persistent_only && kind != "PERSISTENT" {
                continue;
            }
            if let Ok(l) = self.leaf(p) {
                if (l.retain || l.persistent) && self.write(p, v).is_ok() {
                    n += 1;
                }
            }
        }
        Ok(n)
    }
}
