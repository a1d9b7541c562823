//! The checks of what the history keeps: the station's defaults (`[station]`
//! `store_deadband_percent`, `store_min_interval_ms`) and a point's own
//! (`store_deadband`, `store_deadband_percent`, `store_min_interval_ms`). A deadband or a
//! rate limit thins out numbers only, so a point's own needs a numeric type; a station
//! default has no unit, hence no absolute deadband there. Each point's rule is its own
//! settings over the station's defaults ([`points::StorageRule::or`]).

use super::*;
use points::{Deadband, StorageRule};

/// A storage rate limit's allowed range: up to a day.
const MAX_STORE_INTERVAL_MS: i64 = 86_400_000;

impl Ctx<'_> {
    /// The station's default storage rule.
    pub(in crate::config) fn station_storage(&mut self, raw: &RawStation) -> StorageRule {
        let mut rule = StorageRule::default();
        if let Some(percent) = raw.store_deadband_percent {
            if let Some(band) = self.storage_band(
                &[K("station"), K("store_deadband_percent")],
                "store_deadband_percent",
                percent,
            ) {
                rule.deadband = Some(Deadband::Percent(band));
            }
        }
        if let Some(ms) = raw.store_min_interval_ms {
            rule.min_interval =
                self.storage_interval(&[K("station"), K("store_min_interval_ms")], ms);
        }
        rule
    }

    /// A written point's own storage rule (without the station's defaults).
    pub(in crate::config) fn point_storage(
        &mut self,
        entry: Entry,
        point: &RawPoint,
        point_type: PointType,
        type_id: TypeId,
    ) -> StorageRule {
        let mut rule = StorageRule::default();
        let keys = [
            ("store_deadband", point.store_deadband.is_some()),
            (
                "store_deadband_percent",
                point.store_deadband_percent.is_some(),
            ),
            (
                "store_min_interval_ms",
                point.store_min_interval_ms.is_some(),
            ),
        ];
        if !point_type.kind.is_numeric() {
            for (key, given) in keys {
                if given {
                    self.err(
                        &entry.key(key),
                        ConfigProblem::WrongType {
                            type_id: type_id.to_string(),
                            usage: TypeUse::Storage,
                        },
                    );
                }
            }
            return rule;
        }
        match (point.store_deadband, point.store_deadband_percent) {
            (Some(_), Some(_)) => self.err(
                &entry.key("store_deadband_percent"),
                Conflict::StoreDeadbands,
            ),
            (Some(absolute), None) => {
                rule.deadband = self
                    .storage_band(&entry.key("store_deadband"), "store_deadband", absolute)
                    .map(Deadband::Absolute);
            }
            (None, Some(percent)) => {
                rule.deadband = self
                    .storage_band(
                        &entry.key("store_deadband_percent"),
                        "store_deadband_percent",
                        percent,
                    )
                    .map(Deadband::Percent);
            }
            (None, None) => {}
        }
        if let Some(ms) = point.store_min_interval_ms {
            rule.min_interval = self.storage_interval(&entry.key("store_min_interval_ms"), ms);
        }
        rule
    }

    /// A deadband: finite and not negative.
    fn storage_band(&mut self, path: &[Seg], what: &'static str, band: f64) -> Option<f64> {
        if band >= 0.0 && band.is_finite() {
            Some(band)
        } else {
            self.err(
                path,
                ConfigProblem::InvalidNumber {
                    what,
                    value: band.to_string(),
                    expected: "a finite value >= 0",
                },
            );
            None
        }
    }

    /// A storage rate limit: 1 ms up to a day.
    fn storage_interval(&mut self, path: &[Seg], ms: i64) -> Option<Duration> {
        if (1..=MAX_STORE_INTERVAL_MS).contains(&ms) {
            Some(Duration::from_millis(ms.unsigned_abs()))
        } else {
            self.err(
                path,
                ConfigProblem::OutOfRange {
                    what: "store_min_interval_ms",
                    value: ms,
                    min: 1,
                    max: Some(MAX_STORE_INTERVAL_MS),
                },
            );
            None
        }
    }
}

/// Every point's rule: its own settings over the station's `default`.
pub(in crate::config) fn apply_station_storage(nodes: &mut [NodeConfig], default: StorageRule) {
    for point in nodes.iter_mut().flat_map(|node| node.points.iter_mut()) {
        point.storage = point.storage.or(default);
    }
}
