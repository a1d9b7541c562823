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

/// What kind of device a fault or hand operation names: the set its name is looked up in
/// ([`crate::VsetinPlant::device_names`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum DeviceKind {
    /// A supply: a 6 kV line, the utility connection, a transformer.
    Supply,
    /// A breaker or a contactor.
    SwitchingDevice,
    /// A breaker (motorised QF or manual FA).
    Breaker,
    /// A lighting board.
    LightingBoard,
    /// A fuse with an indication contact.
    Fuse,
    /// A surge arrester with an indication contact.
    SurgeArrester,
    /// A board with an emergency-off button.
    EmergencyOffBoard,
    /// A door with a contact.
    Door,
    /// An auxiliary power-supply unit.
    SupplyUnit,
    /// A network switch with a fault contact.
    NetworkSwitch,
    /// An I/O or communication module.
    Module,
    /// A board with a local/remote selector or a remote-enable switch.
    SelectorBoard,
}

impl DeviceKind {
    /// What the kind is called in messages ("breaker or contactor").
    pub fn label(self) -> &'static str {
        match self {
            DeviceKind::Supply => "supply",
            DeviceKind::SwitchingDevice => "breaker or contactor",
            DeviceKind::Breaker => "breaker",
            DeviceKind::LightingBoard => "lighting board",
            DeviceKind::Fuse => "fuse",
            DeviceKind::SurgeArrester => "surge arrester",
            DeviceKind::EmergencyOffBoard => "board with emergency off",
            DeviceKind::Door => "door",
            DeviceKind::SupplyUnit => "supply unit",
            DeviceKind::NetworkSwitch => "network switch",
            DeviceKind::Module => "module",
            DeviceKind::SelectorBoard => "board with a selector",
        }
    }
}

impl fmt::Display for DeviceKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.label())
    }
}

/// The text form of one fault or hand operation, for help texts: what a person types and
/// which device names it takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub struct OperationSyntax {
    /// The first word (`stuck-open`, `selector`).
    pub keyword: &'static str,
    /// The whole form with placeholders (`selector BOARD local|remote`).
    pub usage: &'static str,
    /// The kind of device the placeholder names, if it takes one.
    pub device: Option<DeviceKind>,
    /// A fault (stays until cleared) rather than a hand operation.
    pub fault: bool,
}

const fn fault_syntax(
    keyword: &'static str,
    usage: &'static str,
    device: Option<DeviceKind>,
) -> OperationSyntax {
    OperationSyntax {
        keyword,
        usage,
        device,
        fault: true,
    }
}

const fn action_syntax(
    keyword: &'static str,
    usage: &'static str,
    device: Option<DeviceKind>,
) -> OperationSyntax {
    OperationSyntax {
        keyword,
        usage,
        device,
        fault: false,
    }
}

/// Every fault and hand operation, in the order help texts list them.
const SYNTAX: &[OperationSyntax] = &[
    fault_syntax("supply-loss", "supply-loss NAME", Some(DeviceKind::Supply)),
    fault_syntax("generator-fail-to-start", "generator-fail-to-start", None),
    fault_syntax(
        "stuck-closed",
        "stuck-closed NAME",
        Some(DeviceKind::SwitchingDevice),
    ),
    fault_syntax(
        "stuck-open",
        "stuck-open NAME",
        Some(DeviceKind::SwitchingDevice),
    ),
    fault_syntax(
        "breaker-tripped",
        "breaker-tripped NAME",
        Some(DeviceKind::Breaker),
    ),
    fault_syntax(
        "lamp-failure",
        "lamp-failure BOARD",
        Some(DeviceKind::LightingBoard),
    ),
    fault_syntax("fuse-blown", "fuse-blown NAME", Some(DeviceKind::Fuse)),
    fault_syntax(
        "surge-arrester",
        "surge-arrester NAME",
        Some(DeviceKind::SurgeArrester),
    ),
    fault_syntax(
        "emergency-off",
        "emergency-off BOARD",
        Some(DeviceKind::EmergencyOffBoard),
    ),
    fault_syntax("door-open", "door-open NAME", Some(DeviceKind::Door)),
    fault_syntax(
        "supply-unit-fault",
        "supply-unit-fault NAME",
        Some(DeviceKind::SupplyUnit),
    ),
    fault_syntax(
        "network-switch-fault",
        "network-switch-fault NAME",
        Some(DeviceKind::NetworkSwitch),
    ),
    fault_syntax(
        "module-pulled",
        "module-pulled MODULE",
        Some(DeviceKind::Module),
    ),
    fault_syntax(
        "communication-lost",
        "communication-lost MODULE",
        Some(DeviceKind::Module),
    ),
    action_syntax(
        "selector",
        "selector BOARD local|remote",
        Some(DeviceKind::SelectorBoard),
    ),
    action_syntax(
        "manual-switch",
        "manual-switch BOARD on|off",
        Some(DeviceKind::LightingBoard),
    ),
    action_syntax("close", "close NAME", Some(DeviceKind::Breaker)),
    action_syntax("open", "open NAME", Some(DeviceKind::Breaker)),
    action_syntax("illuminance", "illuminance LUX|auto", None),
];

/// Every fault and hand operation with the kind of device it names.
pub fn operation_syntax() -> &'static [OperationSyntax] {
    SYNTAX
}

impl Action {
    /// A hand operation written as the console writes it (`selector RH2 local`,
    /// `manual-switch ROV01 on`, `close FA1`, `open FA1`, `illuminance 5`, `illuminance
    /// auto`); `None` when the line is no operation (it may be a fault).
    pub fn parse(text: &str) -> Option<Result<Action, PlantError>> {
        let words: Vec<&str> = text.split_whitespace().collect();
        let bad = || PlantError::BadFault(text.to_owned());
        Some(match words.as_slice() {
            ["selector", board, position] => match *position {
                "remote" => Ok(Action::SetSelector {
                    board: (*board).to_owned(),
                    remote: true,
                }),
                "local" => Ok(Action::SetSelector {
                    board: (*board).to_owned(),
                    remote: false,
                }),
                _ => Err(bad()),
            },
            ["manual-switch", board, position] => match *position {
                "on" => Ok(Action::SetManualSwitch {
                    board: (*board).to_owned(),
                    on: true,
                }),
                "off" => Ok(Action::SetManualSwitch {
                    board: (*board).to_owned(),
                    on: false,
                }),
                _ => Err(bad()),
            },
            ["close", name] => Ok(Action::Close((*name).to_owned())),
            ["open", name] => Ok(Action::Open((*name).to_owned())),
            ["illuminance", "auto"] => Ok(Action::SetIlluminance(None)),
            ["illuminance", lux] => match lux.parse::<f64>() {
                Ok(x) if x.is_finite() && x >= 0.0 => Ok(Action::SetIlluminance(Some(x))),
                _ => Err(bad()),
            },
            [first, ..]
                if ["selector", "manual-switch", "close", "open", "illuminance"]
                    .contains(first) =>
            {
                Err(bad())
            }
            _ => return None,
        })
    }
}

impl Fault {
    /// The kind of device [`Fault::device`] names.
    pub fn device_kind(&self) -> Option<DeviceKind> {
        SYNTAX
            .iter()
            .find(|syntax| syntax.fault && syntax.keyword == self.keyword())
            .and_then(|syntax| syntax.device)
    }

    /// The same fault on another device (no change for a fault without one).
    pub fn with_device(&self, device: String) -> Fault {
        match self {
            Fault::GeneratorFailToStart => Fault::GeneratorFailToStart,
            Fault::SupplyLoss(_) => Fault::SupplyLoss(device),
            Fault::StuckClosed(_) => Fault::StuckClosed(device),
            Fault::StuckOpen(_) => Fault::StuckOpen(device),
            Fault::BreakerTripped(_) => Fault::BreakerTripped(device),
            Fault::LampFailure(_) => Fault::LampFailure(device),
            Fault::FuseBlown(_) => Fault::FuseBlown(device),
            Fault::SurgeArresterTripped(_) => Fault::SurgeArresterTripped(device),
            Fault::EmergencyOff(_) => Fault::EmergencyOff(device),
            Fault::DoorOpen(_) => Fault::DoorOpen(device),
            Fault::SupplyUnitFault(_) => Fault::SupplyUnitFault(device),
            Fault::NetworkSwitchFault(_) => Fault::NetworkSwitchFault(device),
            Fault::ModulePulled(_) => Fault::ModulePulled(device),
            Fault::CommunicationLost(_) => Fault::CommunicationLost(device),
        }
    }
}

impl Action {
    /// The device the operation names and its kind, if any.
    pub fn device(&self) -> Option<(DeviceKind, &str)> {
        match self {
            Action::SetSelector { board, .. } => Some((DeviceKind::SelectorBoard, board)),
            Action::SetManualSwitch { board, .. } => Some((DeviceKind::LightingBoard, board)),
            Action::Close(name) | Action::Open(name) => Some((DeviceKind::Breaker, name)),
            Action::SetIlluminance(_) => None,
        }
    }

    /// The same operation on another device (no change for one without a device).
    pub fn with_device(&self, device: String) -> Action {
        match self {
            Action::SetSelector { remote, .. } => Action::SetSelector {
                board: device,
                remote: *remote,
            },
            Action::SetManualSwitch { on, .. } => Action::SetManualSwitch {
                board: device,
                on: *on,
            },
            Action::Close(_) => Action::Close(device),
            Action::Open(_) => Action::Open(device),
            Action::SetIlluminance(lux) => Action::SetIlluminance(*lux),
        }
    }
}

/// Finds the device a person means among `names`: the exact name; else the one name equal
/// to it in any case; else the one name whose `_`-separated words begin or end with its
/// words (`QF1` in `RH2_QF1`, `P9` in `RDRT_P9`, `RH11` in `RH11_QF1`), any case. Several
/// such names are an [`PlantError::AmbiguousDevice`] listing them, none an
/// [`PlantError::UnknownDevice`].
pub(crate) fn resolve_device(
    kind: DeviceKind,
    names: &[String],
    given: &str,
) -> Result<String, PlantError> {
    if names.iter().any(|name| name == given) {
        return Ok(given.to_owned());
    }
    let unique = |matches: Vec<&String>| -> Result<Option<String>, PlantError> {
        match matches.as_slice() {
            [] => Ok(None),
            [one] => Ok(Some((*one).clone())),
            _ => Err(PlantError::AmbiguousDevice {
                kind: kind.label(),
                name: given.to_owned(),
                candidates: matches.into_iter().cloned().collect(),
            }),
        }
    };
    let same_case_blind = names
        .iter()
        .filter(|name| name.eq_ignore_ascii_case(given))
        .collect();
    if let Some(name) = unique(same_case_blind)? {
        return Ok(name);
    }
    let words = |text: &str| -> Vec<String> {
        text.split('_')
            .map(str::to_ascii_uppercase)
            .collect::<Vec<_>>()
    };
    let wanted = words(given);
    let by_words = names
        .iter()
        .filter(|name| {
            let name = words(name);
            !given.is_empty()
                && wanted.len() < name.len()
                && (name.starts_with(&wanted) || name.ends_with(&wanted))
        })
        .collect();
    unique(by_words)?.ok_or_else(|| PlantError::UnknownDevice {
        kind: kind.label(),
        name: given.to_owned(),
    })
}
