//! Points a project does not write but a device brings: a lift's signals, a profiled
//! device's. Each is named `DEVICE.SIGNAL` at the device's `ioa_base` plus the signal's
//! offset; names and IOAs still have to be free and are checked like written ones.

use super::*;

/// The names and IOAs the node's points already use, for the generated ones to avoid.
pub(in crate::config) struct TakenPoints<'a> {
    pub(in crate::config) names: &'a mut HashSet<String>,
    pub(in crate::config) ioas: &'a mut HashMap<Ioa, String>,
}

/// One point a device brings.
pub(in crate::config) struct GeneratedPoint {
    pub(in crate::config) name: String,
    pub(in crate::config) base: Ioa,
    pub(in crate::config) offset: u32,
    pub(in crate::config) point_type: PointType,
    pub(in crate::config) source: PointSource,
    pub(in crate::config) storage: points::StorageRule,
    pub(in crate::config) description: String,
}

impl Ctx<'_> {
    /// The point, with its name and IOA taken; `None` (reported at the device's `name`
    /// or `ioa_base`) when either is taken already or the IOA is out of range: the
    /// device's other points are then not checked (one message, not one per signal).
    pub(in crate::config) fn generated_point(
        &mut self,
        point: GeneratedPoint,
        node: &str,
        taken: &mut TakenPoints<'_>,
        at: &dyn Fn(&'static str) -> Vec<Seg>,
    ) -> Option<PointConfig> {
        if !taken.names.insert(point.name.clone()) {
            self.err(
                &at("name"),
                ConfigProblem::Duplicate {
                    what: Unique::PointName,
                    value: point.name.clone(),
                    other: node.to_owned(),
                },
            );
        }
        let Some(address) = shifted(point.base, point.offset) else {
            self.err(
                &at("ioa_base"),
                ConfigProblem::OutOfRange {
                    what: "IOA",
                    value: i64::from(point.base.get()) + i64::from(point.offset),
                    min: 1,
                    max: Some(Ioa::MAX.get().into()),
                },
            );
            return None;
        };
        if let Some(other) = taken.ioas.get(&address) {
            self.err(
                &at("ioa_base"),
                ConfigProblem::Duplicate {
                    what: Unique::PointIoa,
                    value: address.to_string(),
                    other: other.clone(),
                },
            );
            return None;
        }
        taken.ioas.insert(address, point.name.clone());
        Some(PointConfig {
            name: point.name,
            point_type: point.point_type,
            ioa: address,
            source: point.source,
            transmission: Transmission::Spontaneous,
            groups: Vec::new(),
            deadband: None,
            invalid_when: None,
            scaling: None,
            storage: point.storage,
            description: point.description,
        })
    }
}
