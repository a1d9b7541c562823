//! Faults the test, the CLI or the HMI can inject into the plant, and hand operations.

use std::fmt;
use std::str::FromStr;

use crate::core::PlantError;

/// An injectable fault. Device names are those of the signal table in the crate docs.
/// Every fault stays active until cleared.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Fault {
    /// Loss of a supply: `TNS_USTI`, `TNS_VALMEZ` (6 kV lines from the traction
    /// substations), `UTILITY` (distribution connection), `T1`, `T2` (transformer out of
    /// service, i.e. mains loss on that transformer).
    SupplyLoss(String),
    /// The diesel generator cranks but does not start (`RDA_DA_Porucha` after the start delay).
    GeneratorFailToStart,
    /// A breaker or contactor jammed/welded closed: it closes at once and ignores commands.
    StuckClosed(String),
    /// A breaker or contactor jammed open (or burnt coil): it opens at once and ignores commands.
    StuckOpen(String),
    /// A breaker tripped by its own protection. Clearing recloses a manual breaker (FA) by
    /// hand; a motorised QF stays open until closed by its coil.
    BreakerTripped(String),
    /// Lamp circuit of a lighting board (`ROV01`..`ROV12`, `OR`) broken: no current flows,
    /// so the feedback relay `PrRele` drops.
    LampFailure(String),
    /// A fuse blown (`RH2_FU1`, `ROV03_FU1`...). A lighting board's FU1 also cuts its lamps.
    FuseBlown(String),
    /// A surge arrester's indication contact tripped (`RH2_FV1`, `RDRT_FV230`...).
    SurgeArresterTripped(String),
    /// Emergency-off button of a board pressed and latched (`RH2`, `RZZ`, `RDA`).
    EmergencyOff(String),
    /// A door open (`ROV01`..`ROV12`, `OR`, `RDRT_NN`, `RDRT_VN`, `RDRT_T1`, `RDRT_T2`).
    DoorOpen(String),
    /// An auxiliary power-supply unit failed (`RH2_G110.2`, `RZZ_G110.2`, `RDRT_G230`,
    /// `RDRT_G110`, `RDRT_G24`).
    SupplyUnitFault(String),
    /// A network switch reports a fault (`RDRT_ABB`, `RDRT_KORENIX`, `RDRT_SIEMENS`).
    NetworkSwitchFault(String),
    /// An I/O or communication module pulled or dead (`RH2_LOGO`, `ROV05_PLC`, `RDRT_P9`...):
    /// its inputs become unavailable (invalid) and its outputs de-energise.
    ModulePulled(String),
    /// The link to a module lost (its communication module pulled, a cable cut): its
    /// inputs become unavailable (invalid) but the field keeps running on its last outputs.
    CommunicationLost(String),
}

const KINDS: &[(&str, bool)] = &[
    ("supply-loss", true),
    ("generator-fail-to-start", false),
    ("stuck-closed", true),
    ("stuck-open", true),
    ("breaker-tripped", true),
    ("lamp-failure", true),
    ("fuse-blown", true),
    ("surge-arrester", true),
    ("emergency-off", true),
    ("door-open", true),
    ("supply-unit-fault", true),
    ("network-switch-fault", true),
    ("module-pulled", true),
    ("communication-lost", true),
];

impl Fault {
    /// The fault's keyword, as used by [`fmt::Display`] and [`FromStr`].
    pub fn keyword(&self) -> &'static str {
        match self {
            Fault::SupplyLoss(_) => "supply-loss",
            Fault::GeneratorFailToStart => "generator-fail-to-start",
            Fault::StuckClosed(_) => "stuck-closed",
            Fault::StuckOpen(_) => "stuck-open",
            Fault::BreakerTripped(_) => "breaker-tripped",
            Fault::LampFailure(_) => "lamp-failure",
            Fault::FuseBlown(_) => "fuse-blown",
            Fault::SurgeArresterTripped(_) => "surge-arrester",
            Fault::EmergencyOff(_) => "emergency-off",
            Fault::DoorOpen(_) => "door-open",
            Fault::SupplyUnitFault(_) => "supply-unit-fault",
            Fault::NetworkSwitchFault(_) => "network-switch-fault",
            Fault::ModulePulled(_) => "module-pulled",
            Fault::CommunicationLost(_) => "communication-lost",
        }
    }

    /// The device the fault is about, if any.
    pub fn device(&self) -> Option<&str> {
        match self {
            Fault::GeneratorFailToStart => None,
            Fault::SupplyLoss(d)
            | Fault::StuckClosed(d)
            | Fault::StuckOpen(d)
            | Fault::BreakerTripped(d)
            | Fault::LampFailure(d)
            | Fault::FuseBlown(d)
            | Fault::SurgeArresterTripped(d)
            | Fault::EmergencyOff(d)
            | Fault::DoorOpen(d)
            | Fault::SupplyUnitFault(d)
            | Fault::NetworkSwitchFault(d)
            | Fault::ModulePulled(d)
            | Fault::CommunicationLost(d) => Some(d),
        }
    }

    /// Every keyword with whether it takes a device name.
    pub fn keywords() -> &'static [(&'static str, bool)] {
        KINDS
    }
}

impl fmt::Display for Fault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.device() {
            Some(d) => write!(f, "{} {}", self.keyword(), d),
            None => f.write_str(self.keyword()),
        }
    }
}

impl FromStr for Fault {
    type Err = PlantError;

    /// Parses `keyword [DEVICE]`, e.g. `supply-loss T1`, `stuck-open RDA_KM2`,
    /// `generator-fail-to-start`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || PlantError::BadFault(s.to_string());
        let mut it = s.split_whitespace();
        let kw = it.next().ok_or_else(bad)?;
        let dev = it.next().map(str::to_string);
        if it.next().is_some() {
            return Err(bad());
        }
        let need = |d: Option<String>| d.ok_or_else(bad);
        Ok(match kw {
            "generator-fail-to-start" if dev.is_none() => Fault::GeneratorFailToStart,
            "supply-loss" => Fault::SupplyLoss(need(dev)?),
            "stuck-closed" => Fault::StuckClosed(need(dev)?),
            "stuck-open" => Fault::StuckOpen(need(dev)?),
            "breaker-tripped" => Fault::BreakerTripped(need(dev)?),
            "lamp-failure" => Fault::LampFailure(need(dev)?),
            "fuse-blown" => Fault::FuseBlown(need(dev)?),
            "surge-arrester" => Fault::SurgeArresterTripped(need(dev)?),
            "emergency-off" => Fault::EmergencyOff(need(dev)?),
            "door-open" => Fault::DoorOpen(need(dev)?),
            "supply-unit-fault" => Fault::SupplyUnitFault(need(dev)?),
            "network-switch-fault" => Fault::NetworkSwitchFault(need(dev)?),
            "module-pulled" => Fault::ModulePulled(need(dev)?),
            "communication-lost" => Fault::CommunicationLost(need(dev)?),
            _ => return Err(bad()),
        })
    }
}

/// What a person does in the field (not a fault).
#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    /// Turns a board's local/remote selector (`RH2`, `RZZ`, `RDA`) or a lighting board's
    /// remote-enable switch (`ROV01`..`ROV12`, `OR`).
    SetSelector {
        /// Board.
        board: String,
        /// `true` = remote (`Dalkove`).
        remote: bool,
    },
    /// The hard-wired 0/1 switch of a lighting board: drives the manual contactor KM2,
    /// which lights the lamps independently of the PLC.
    SetManualSwitch {
        /// Lighting board.
        board: String,
        /// Position 1.
        on: bool,
    },
    /// Closes a breaker by hand. A manual breaker (FA, `RH11_QF1`) closes at once; a
    /// motorised QF is closed by its door pushbutton, which works only with the board's
    /// selector in local, and takes the close time.
    Close(String),
    /// Opens a breaker by hand, as [`Action::Close`].
    Open(String),
    /// Forces the outdoor illuminance seen by every dusk sensor (lux), or `None` to follow
    /// the sun model again.
    SetIlluminance(Option<f64>),
}
