//! The name dictionary's copy in memory: node, point, origin and key-source names and
//! their numbers in `event_names`.
//!
//! Names are few (a station's points, its nodes and links) and never change their number,
//! so every query and append looks them up here; a number the copy does not know (written
//! by another process, or read before the copy caught up) is loaded from the table.

use std::collections::HashMap;
use std::sync::{Arc, RwLock};

use super::codec::NameId;

/// Names by number and numbers by name.
#[derive(Debug, Default)]
pub(crate) struct Names {
    inner: RwLock<Dictionary>,
}

#[derive(Debug, Default)]
struct Dictionary {
    by_name: HashMap<Arc<str>, NameId>,
    by_id: HashMap<NameId, Arc<str>>,
}

impl Names {
    /// The number of `name`, when known.
    pub(crate) fn id(&self, name: &str) -> Option<NameId> {
        self.read(|d| d.by_name.get(name).copied())
    }

    /// The name of `id`, when known.
    pub(crate) fn name(&self, id: NameId) -> Option<Arc<str>> {
        self.read(|d| d.by_id.get(&id).cloned())
    }

    /// Every known number whose name starts with `prefix` (byte-wise).
    pub(crate) fn ids_with_prefix(&self, prefix: &str) -> Vec<NameId> {
        self.read(|d| {
            d.by_name
                .iter()
                .filter(|(name, _)| name.starts_with(prefix))
                .map(|(_, &id)| id)
                .collect()
        })
    }

    /// Learns pairs read from the table.
    pub(crate) fn learn(&self, pairs: impl IntoIterator<Item = (NameId, String)>) {
        let mut d = match self.inner.write() {
            Ok(d) => d,
            Err(poisoned) => poisoned.into_inner(),
        };
        for (id, name) in pairs {
            let name: Arc<str> = Arc::from(name);
            d.by_name.insert(Arc::clone(&name), id);
            d.by_id.insert(id, name);
        }
    }

    fn read<T>(&self, f: impl FnOnce(&Dictionary) -> T) -> T {
        // A panic elsewhere while holding the lock leaves a dictionary that is still
        // whole (each insert is one map operation): keep using it.
        match self.inner.read() {
            Ok(d) => f(&d),
            Err(poisoned) => f(&poisoned.into_inner()),
        }
    }
}
