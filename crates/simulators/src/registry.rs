//! The simulated devices by name: one row per device a project (`simulate = "..."`) or the
//! CLI can run without the real one.

/// The protocol a simulated device answers on its line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Speaks {
    /// IEC 60870-5-103 (protection relays, a gateway's `[[node.line]] protocol = "iec103"`).
    Iec103,
    /// The Rekoba EKM66 lift controller's RS-232 protocol (`[[node.lift]]`).
    Ekm66,
}

impl Speaks {
    /// How the protocol is named in messages.
    pub fn name(self) -> &'static str {
        match self {
            Speaks::Iec103 => "IEC 60870-5-103",
            Speaks::Ekm66 => "EKM66",
        }
    }
}

/// A device that can be simulated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SimulatedDevice {
    /// Its name in a project (`simulate = "ref630"`) and on the command line.
    pub name: &'static str,
    /// The protocol it answers.
    pub speaks: Speaks,
    /// What it is.
    pub description: &'static str,
    /// The operations of its console (the station's console and the CLI simulator),
    /// one a line.
    pub console_help: &'static str,
}

/// The operations of the REF630's console ([`crate::ref630::Device::operate`]).
pub const REF630_HELP: &str = concat!(
    "  inject I U [P Q F]  measurands as multiples of rated: inject 1 1\n",
    "  local | remote      the relay's LOCAL/REMOTE switch (remote commands refused in LOCAL)\n",
    "  open | close        the breaker by hand\n",
    "  earth-switch on|off the earthing switch\n",
    "  truck test|service  the truck's position\n",
    "  fault               an earth fault: trip, breaker open, a disturbance record\n",
    "  restart             the relay restarts (its identification follows)\n",
    "  status              positions, LOCAL/REMOTE, clock\n",
);

/// Every device that can be simulated.
pub const SIMULATED: &[SimulatedDevice] = &[
    SimulatedDevice {
        name: "ref630",
        speaks: Speaks::Iec103,
        description: "ABB REF630 feeder protection relay (the gateway thesis)",
        console_help: REF630_HELP,
    },
    SimulatedDevice {
        name: "ekm66",
        speaks: Speaks::Ekm66,
        description: "Rekoba EKM66 lift controller board (the lift thesis)",
        console_help: devices::ekm66::console::HELP,
    },
];

/// The simulated device called `name`.
pub fn find(name: &str) -> Option<&'static SimulatedDevice> {
    SIMULATED.iter().find(|device| device.name == name)
}

/// The names of the simulated devices that speak `speaks`, for a message.
pub fn names(speaks: Speaks) -> Vec<&'static str> {
    SIMULATED
        .iter()
        .filter(|device| device.speaks == speaks)
        .map(|device| device.name)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_row_is_found_by_its_name_and_has_help() {
        for device in SIMULATED {
            assert_eq!(find(device.name), Some(device));
            assert!(device.console_help.lines().count() >= 3, "{}", device.name);
        }
        assert_eq!(names(Speaks::Iec103), ["ref630"]);
        assert_eq!(find("ref615"), None);
    }
}
