//! The plants a project can name (`plant = "..."` in `station.toml`), found by name so
//! that the runtime, the CLI and the HMI never name a plant themselves: adding a plant (a
//! lab model, the ball sorter, a lift) is one entry here.

use crate::core::Plant;

/// Where a plant starts: the simulated clock's start as Unix seconds (the sun, the
/// calendar and the weekly programs of the plant follow it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlantStart {
    /// Unix seconds of simulated time zero.
    pub unix_secs: i64,
}

/// The plants by name: the Vsetín station, the teaching-lab models
/// ([`crate::lab::MODELS`], opened with default options) and the sorting lab's ball
/// sorter (seed 0).
pub const PLANTS: &[&str] = &[
    "vsetin",
    "slide",
    "crossroad",
    "mixing",
    "washing",
    "sorter",
];

/// A new plant of the given name, or `None` for a name [`PLANTS`] does not hold.
pub fn open(name: &str, start: PlantStart) -> Option<Box<dyn Plant + Send>> {
    match name {
        "vsetin" => {
            let config = crate::vsetin::StationConfig {
                start_unix_secs: start.unix_secs,
                ..crate::vsetin::StationConfig::default()
            };
            Some(Box::new(crate::vsetin::VsetinPlant::with_config(config)))
        }
        "sorter" => Some(Box::new(crate::sorter::SorterPlant::new(
            crate::sorter::SorterConfig::default(),
        ))),
        name if crate::lab::MODELS.contains(&name) => {
            crate::lab::open_plant(name, &crate::lab::LabOptions::default()).ok()
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_listed_plant_opens_and_others_do_not() {
        for name in PLANTS {
            let plant = open(name, PlantStart { unix_secs: 0 });
            assert!(
                plant.is_some_and(|plant| !plant.signals().is_empty()),
                "{name}"
            );
        }
        assert!(open("nonexistent", PlantStart { unix_secs: 0 }).is_none());
    }

    #[test]
    fn every_lab_model_is_listed_and_opens_as_that_model() {
        for model in crate::lab::MODELS {
            assert!(PLANTS.contains(model), "{model}");
            let plant = open(model, PlantStart { unix_secs: 0 }).unwrap();
            assert!(plant.modules().iter().any(|m| m.name == *model), "{model}");
        }
    }
}
