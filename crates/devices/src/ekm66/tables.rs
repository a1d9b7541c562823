//! The status codes (spec Appendix A) and fault codes (Appendix B) with their English
//! and Czech texts, and the colour class of each status (spec §5, EKM-A5).

use std::borrow::Cow;
use std::fmt;

use serde::{Deserialize, Serialize};

/// The background colour of a status in the UI (spec §5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum ColourClass {
    /// Everything in order.
    Green,
    /// A warning, or a technician's intervention in progress.
    Orange,
    /// A fault: the lift is probably out of service.
    Red,
}

impl fmt::Display for ColourClass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ColourClass::Green => "green",
            ColourClass::Orange => "orange",
            ColourClass::Red => "red",
        })
    }
}

/// One status code of Appendix A.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StatusCode {
    /// The code.
    pub code: u8,
    /// English text.
    pub english: &'static str,
    /// The board's Czech text.
    pub czech: &'static str,
    /// The proposed colour class.
    pub class: ColourClass,
}

/// One fault code of Appendix B.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FaultCode {
    /// The code.
    pub code: u8,
    /// English text.
    pub english: &'static str,
    /// The board's Czech text.
    pub czech: &'static str,
}

/// The 53 status codes of Appendix A, in code order.
pub const STATUS_CODES: &[StatusCode] = &[
    StatusCode {
        code: 1,
        english: "Fully ready for operation",
        czech: "Plně připraven k provozu.",
        class: ColourClass::Green,
    },
    StatusCode {
        code: 2,
        english: "Lift attendant operation",
        czech: "Výtahový řidič",
        class: ColourClass::Orange,
    },
    StatusCode {
        code: 3,
        english: "Station (floor) correction",
        czech: "Korekce stanice",
        class: ColourClass::Green,
    },
    StatusCode {
        code: 4,
        english: "Fully ready for operation (duplicate of 1)",
        czech: "Plně připraven k provozu",
        class: ColourClass::Green,
    },
    StatusCode {
        code: 5,
        english: "Start of (free) call operation",
        czech: "Zač.vol.provozu",
        class: ColourClass::Green,
    },
    StatusCode {
        code: 6,
        english: "SIS error",
        czech: "SIS-chyba",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 7,
        english: "Re-levelling",
        czech: "Doregulace",
        class: ColourClass::Green,
    },
    StatusCode {
        code: 8,
        english: "Loading time",
        czech: "Čas nakládky",
        class: ColourClass::Green,
    },
    StatusCode {
        code: 9,
        english: "Call lock-out",
        czech: "Uzávěr volání",
        class: ColourClass::Orange,
    },
    StatusCode {
        code: 10,
        english: "Overloaded",
        czech: "Přetíženo",
        class: ColourClass::Orange,
    },
    StatusCode {
        code: 11,
        english: "Landing-call lock-out",
        czech: "Uzávěr vnější volby",
        class: ColourClass::Orange,
    },
    StatusCode {
        code: 12,
        english: "Fully loaded",
        czech: "Plně zatíženo",
        class: ColourClass::Green,
    },
    StatusCode {
        code: 13,
        english: "Start-up run",
        czech: "Spouštěcí jízda",
        class: ColourClass::Green,
    },
    StatusCode {
        code: 14,
        english: "Parking run",
        czech: "Parkovací jízda",
        class: ColourClass::Green,
    },
    StatusCode {
        code: 15,
        english: "Warm-up run",
        czech: "Zahřívací jízda",
        class: ColourClass::Green,
    },
    StatusCode {
        code: 17,
        english: "Priority run",
        czech: "Přednostní jízda",
        class: ColourClass::Orange,
    },
    StatusCode {
        code: 18,
        english: "Light-curtain fault",
        czech: "Chyba světelné závory",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 19,
        english: "Door fault",
        czech: "Chyba dveří",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 20,
        english: "Shut down (out of service)!",
        czech: "Uvedení do klidu!",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 21,
        english: "Learning (teach-in) run",
        czech: "Učební jízda",
        class: ColourClass::Orange,
    },
    StatusCode {
        code: 22,
        english: "Evacuation",
        czech: "Evakuace",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 23,
        english: "Fire case",
        czech: "Případ požáru",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 24,
        english: "Firefighter run",
        czech: "Požární jízda",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 25,
        english: "Thermistor error",
        czech: "chyba term",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 26,
        english: "Parameter-controlled shut-down",
        czech: "Para-Uvedení do klidu",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 27,
        english: "Start-up run error",
        czech: "Chyba spouštěcí j.",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 29,
        english: "Light curtain interrupted!",
        czech: "Světelná závora!",
        class: ColourClass::Orange,
    },
    StatusCode {
        code: 30,
        english: "Landing (shaft) doors",
        czech: "Šachetní dveře",
        class: ColourClass::Orange,
    },
    StatusCode {
        code: 31,
        english: "Door-open button",
        czech: "Tlačítko otevření dveří",
        class: ColourClass::Orange,
    },
    StatusCode {
        code: 32,
        english: "AWM: car light",
        czech: "AWM:K. světlo",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 33,
        english: "AWM: alarm shut-down",
        czech: "AWM:O. alarm",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 34,
        english: "AWM: door-open button",
        czech: "AWM:T.otevř.dveří",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 35,
        english: "AWM: safety-circuit fault",
        czech: "AWM:C.bezp.obvodu",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 36,
        english: "Stop: light curtain",
        czech: "Stop svět závora",
        class: ColourClass::Orange,
    },
    StatusCode {
        code: 37,
        english: "No shaft (data)",
        czech: "Žádná šachta",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 38,
        english: "Drive hanging (stuck)",
        czech: "Pohon visí",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 39,
        english: "SK2 test stop",
        czech: "SK2-Test-stop",
        class: ColourClass::Orange,
    },
    StatusCode {
        code: 40,
        english: "A3 test stop",
        czech: "A3-Test-stop",
        class: ColourClass::Orange,
    },
    StatusCode {
        code: 41,
        english: "EN 81 overloaded",
        czech: "EN81-přetíženo",
        class: ColourClass::Orange,
    },
    StatusCode {
        code: 42,
        english: "Travel lock-out",
        czech: "Uzávěr jízdy",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 43,
        english: "Running-time error",
        czech: "Chyba doby běhu",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 44,
        english: "Safety circuit (open)",
        czech: "Bezpečnostní obvod",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 45,
        english: "SK0 fault",
        czech: "SK0-porucha",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 46,
        english: "Inspection",
        czech: "Inspekce",
        class: ColourClass::Orange,
    },
    StatusCode {
        code: 47,
        english: "Recall",
        czech: "Zpětné přivolání",
        class: ColourClass::Orange,
    },
    StatusCode {
        code: 48,
        english: "Thermistor stop 2",
        czech: "Termistor Stop 2",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 49,
        english: "Thermistor stop 1",
        czech: "Termistor Stop 1",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 50,
        english: "Emergency power",
        czech: "Nouzový proud",
        class: ColourClass::Orange,
    },
    StatusCode {
        code: 51,
        english: "Parameter error",
        czech: "Chyba parametru",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 52,
        english: "Rope replacement stop",
        czech: "Výměna lana stop",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 53,
        english: "Rope service-life stop",
        czech: "Stop životnost lana",
        class: ColourClass::Red,
    },
    StatusCode {
        code: 54,
        english: "Rope tension",
        czech: "Napětí lana",
        class: ColourClass::Orange,
    },
    StatusCode {
        code: 55,
        english: "Rope warning",
        czech: "Výstraha lano",
        class: ColourClass::Orange,
    },
];

/// The 75 fault codes of Appendix B, in code order.
pub const FAULT_CODES: &[FaultCode] = &[
    FaultCode {
        code: 0x01,
        english: "Log destroyed (fault log corrupted)",
        czech: "Protokol zničen",
    },
    FaultCode {
        code: 0x02,
        english: "Log cleared",
        czech: "Protokol vymazán",
    },
    FaultCode {
        code: 0x03,
        english: "Clock set",
        czech: "Hodiny nastaveny",
    },
    FaultCode {
        code: 0x04,
        english: "Parameterisation (parameters changed)",
        czech: "Parametrizace",
    },
    FaultCode {
        code: 0x05,
        english: "System error",
        czech: "Systémová chyba",
    },
    FaultCode {
        code: 0x10,
        english: "No start",
        czech: "Žádný Start",
    },
    FaultCode {
        code: 0x11,
        english: "Safety circuit (opened) during travel",
        czech: "B.obvod v jízdě",
    },
    FaultCode {
        code: 0x12,
        english: "Hard stop",
        czech: "Tvrdé zastavení",
    },
    FaultCode {
        code: 0x13,
        english: "Running time exceeded — fast speed",
        czech: "Doba běhu rychle",
    },
    FaultCode {
        code: 0x14,
        english: "Running time exceeded — slow speed",
        czech: "Doba běhu pomalu",
    },
    FaultCode {
        code: 0x15,
        english: "Running time exceeded — re-levelling",
        czech: "Doba běhu doreg.",
    },
    FaultCode {
        code: 0x16,
        english: "Stopping error",
        czech: "Chyba zastavení",
    },
    FaultCode {
        code: 0x17,
        english: "No start (via SIS)",
        czech: "Žádný start (přes SIS)",
    },
    FaultCode {
        code: 0x18,
        english: "Safety circuit (opened) while doors opening",
        czech: "B.obvod při otevírání",
    },
    FaultCode {
        code: 0x20,
        english: "Faulty stop signal",
        czech: "Chybný signál zastavení",
    },
    FaultCode {
        code: 0x21,
        english: "Faulty pulse signal — up",
        czech: "Chybný signál impuls-nahoru",
    },
    FaultCode {
        code: 0x22,
        english: "Faulty pulse signal — down",
        czech: "Chybný signál impuls-dolů",
    },
    FaultCode {
        code: 0x23,
        english: "Faulty correction signal",
        czech: "Chybný signál korekce",
    },
    FaultCode {
        code: 0x24,
        english: "Faulty correction signal — top",
        czech: "Chybný signál korekce-nahoře",
    },
    FaultCode {
        code: 0x25,
        english: "Faulty correction signal — bottom",
        czech: "Chybný signál korekce-dole",
    },
    FaultCode {
        code: 0x26,
        english: "Faulty signal — both corrections",
        czech: "Chybný signál obě Korekce",
    },
    FaultCode {
        code: 0x27,
        english: "Faulty signal HKU",
        czech: "Chybný signál HKU",
    },
    FaultCode {
        code: 0x28,
        english: "Faulty signal HKO",
        czech: "Chybný signál HKO",
    },
    FaultCode {
        code: 0x29,
        english: "Faulty signal HKI",
        czech: "Chybný signál HKI",
    },
    FaultCode {
        code: 0x2A,
        english: "Faulty signal — both HKU and HKO",
        czech: "Chybný signál oba HKU+HKO",
    },
    FaultCode {
        code: 0x2B,
        english: "Wrong direction of rotation",
        czech: "Chybný směr otáč.",
    },
    FaultCode {
        code: 0x2C,
        english: "No stop signals",
        czech: "Žádné signály zastavení",
    },
    FaultCode {
        code: 0x2D,
        english: "Faulty pulse signal",
        czech: "Chybný signál impuls",
    },
    FaultCode {
        code: 0x30,
        english: "System start",
        czech: "Start systému",
    },
    FaultCode {
        code: 0x31,
        english: "Correction run",
        czech: "Kor.stavu-jízda",
    },
    FaultCode {
        code: 0x32,
        english: "Call lock-out",
        czech: "Uzávěr volání",
    },
    FaultCode {
        code: 0x33,
        english: "Overloaded",
        czech: "Přetíženo",
    },
    FaultCode {
        code: 0x34,
        english: "Landing-call lock-out",
        czech: "Uzávěr vněj.vol.",
    },
    FaultCode {
        code: 0x35,
        english: "Full load",
        czech: "Plné zatížení",
    },
    FaultCode {
        code: 0x36,
        english: "Light-grid stop",
        czech: "Svět.mříž-stop",
    },
    FaultCode {
        code: 0x37,
        english: "Evacuation",
        czech: "Evakuace",
    },
    FaultCode {
        code: 0x38,
        english: "Learning run",
        czech: "Učební jízda",
    },
    FaultCode {
        code: 0x39,
        english: "Shut-down",
        czech: "Uvedení do klidu",
    },
    FaultCode {
        code: 0x3A,
        english: "Firefighter run",
        czech: "Požární jízda",
    },
    FaultCode {
        code: 0x3B,
        english: "Travel stopped by thermistor",
        czech: "Zast.jízdy term.",
    },
    FaultCode {
        code: 0x3C,
        english: "Door fault",
        czech: "Porucha dveří",
    },
    FaultCode {
        code: 0x3D,
        english: "Light-curtain fault",
        czech: "Poruch.svět.záv.",
    },
    FaultCode {
        code: 0x3E,
        english: "Light curtain permanently interrupted",
        czech: "Trvale svět.záv.",
    },
    FaultCode {
        code: 0x3F,
        english: "Landing door permanently open",
        czech: "Trvale otevř.šach.dveře",
    },
    FaultCode {
        code: 0x40,
        english: "Door-open button permanently pressed",
        czech: "Trvale tlač.otev.dveří",
    },
    FaultCode {
        code: 0x41,
        english: "No shaft data",
        czech: "Žádné údaje šachty",
    },
    FaultCode {
        code: 0x42,
        english: "Drive hanging (stuck)",
        czech: "Pohon visí",
    },
    FaultCode {
        code: 0x43,
        english: "Travel lock-out",
        czech: "Uzávěr jízdy",
    },
    FaultCode {
        code: 0x44,
        english: "Running-time monitoring",
        czech: "Kontr.doby běhu",
    },
    FaultCode {
        code: 0x45,
        english: "Safety circuit SK1 open",
        czech: "B.obvod SK1 rozp.",
    },
    FaultCode {
        code: 0x46,
        english: "Inspection",
        czech: "Inspekce",
    },
    FaultCode {
        code: 0x47,
        english: "Recall",
        czech: "Zpětné přivolání",
    },
    FaultCode {
        code: 0x48,
        english: "Thermistor stop",
        czech: "Zastavení term.",
    },
    FaultCode {
        code: 0x49,
        english: "Re-levelling fault",
        czech: "Porucha doregul.",
    },
    FaultCode {
        code: 0x4A,
        english: "SIS fault",
        czech: "SIS-porucha",
    },
    FaultCode {
        code: 0x4B,
        english: "SIS test stop",
        czech: "SIS-test-zastav.",
    },
    FaultCode {
        code: 0x4C,
        english: "SK2 test stop",
        czech: "SK2-test-zastav.",
    },
    FaultCode {
        code: 0x4D,
        english: "SK0 fault",
        czech: "SK0-porucha",
    },
    FaultCode {
        code: 0x4E,
        english: "Start-up cancelled",
        czech: "Spoušt.zrušeno",
    },
    FaultCode {
        code: 0x4F,
        english: "EN 81 overloaded",
        czech: "EN81-přetíženo",
    },
    FaultCode {
        code: 0x50,
        english: "AWM: car light — stop",
        czech: "AWM-Kabin.světlo-zastav.",
    },
    FaultCode {
        code: 0x51,
        english: "AWM: alarm shut-down — stop",
        czech: "AWM-Alarm odstavení-zastav.",
    },
    FaultCode {
        code: 0x52,
        english: "AWM: door-open button — stop",
        czech: "AWM-Tl.otevř.dveří-zastav.",
    },
    FaultCode {
        code: 0x53,
        english: "AWM: safety-circuit error — AWM standstill",
        czech: "AWM-Chyba b.obvodu AWM-klid",
    },
    FaultCode {
        code: 0x54,
        english: "Operation on emergency power",
        czech: "Provoz s nouzovým napájením",
    },
    FaultCode {
        code: 0x55,
        english: "Loading — standby",
        czech: "Nakládka-pohotovost",
    },
    FaultCode {
        code: 0x56,
        english: "Parameter-controlled shut-down",
        czech: "Para-uvedení do klidu",
    },
    FaultCode {
        code: 0x57,
        english: "Parameter error",
        czech: "Chyba parametru",
    },
    FaultCode {
        code: 0x58,
        english: "Fire case",
        czech: "Případ požáru",
    },
    FaultCode {
        code: 0x59,
        english: "Restricted call operation",
        czech: "Omezený přivol.provoz",
    },
    FaultCode {
        code: 0x5A,
        english: "No parameter",
        czech: "Žádný parametr",
    },
    FaultCode {
        code: 0x5B,
        english: "Rope replacement stop",
        czech: "Výměna lana stop",
    },
    FaultCode {
        code: 0x5C,
        english: "Rope service-life stop",
        czech: "Stop životnost lana",
    },
    FaultCode {
        code: 0x5D,
        english: "Rope tension",
        czech: "Napětí lana",
    },
    FaultCode {
        code: 0x5E,
        english: "Rope warning",
        czech: "Výstraha lana",
    },
];

/// The status code's entry, `None` for a code not in Appendix A (16, 28, …).
pub fn status_code(code: u8) -> Option<&'static StatusCode> {
    STATUS_CODES.iter().find(|entry| entry.code == code)
}

/// The fault code's entry, `None` for a code not in Appendix B.
pub fn fault_code(code: u8) -> Option<&'static FaultCode> {
    FAULT_CODES.iter().find(|entry| entry.code == code)
}

/// The English text of a status; unknown codes read "unknown status (n)".
pub fn status_text(code: u8) -> Cow<'static, str> {
    status_code(code).map_or_else(
        || Cow::Owned(format!("unknown status ({code})")),
        |entry| Cow::Borrowed(entry.english),
    )
}

/// The Czech text of a status; unknown codes read "neznámý stav (n)".
pub fn status_text_czech(code: u8) -> Cow<'static, str> {
    status_code(code).map_or_else(
        || Cow::Owned(format!("neznámý stav ({code})")),
        |entry| Cow::Borrowed(entry.czech),
    )
}

/// The English text of a fault; unknown codes read "unknown fault 0xNN".
pub fn fault_text(code: u8) -> Cow<'static, str> {
    fault_code(code).map_or_else(
        || Cow::Owned(format!("unknown fault 0x{code:02X}")),
        |entry| Cow::Borrowed(entry.english),
    )
}

/// The Czech text of a fault; unknown codes read "neznámá porucha 0xNN".
pub fn fault_text_czech(code: u8) -> Cow<'static, str> {
    fault_code(code).map_or_else(
        || Cow::Owned(format!("neznámá porucha 0x{code:02X}")),
        |entry| Cow::Borrowed(entry.czech),
    )
}

/// The colour classes of the statuses: spec §5's proposal with per-code overrides
/// (EKM-A5). Unknown codes are orange.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct StatusColours {
    overrides: Vec<(u8, ColourClass)>,
}

impl StatusColours {
    /// Gives a code another class.
    pub fn set(&mut self, code: u8, class: ColourClass) {
        self.overrides.retain(|(known, _)| *known != code);
        self.overrides.push((code, class));
    }

    /// The class of a status code.
    pub fn class(&self, code: u8) -> ColourClass {
        self.overrides
            .iter()
            .find(|(known, _)| *known == code)
            .map(|(_, class)| *class)
            .or_else(|| status_code(code).map(|entry| entry.class))
            .unwrap_or(ColourClass::Orange)
    }
}

/// What a status says about the lift's service, for the service figures
/// ([`super::figures`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LiftMode {
    /// Available to passengers: idle, travelling, doors, loading, a passenger at the
    /// doors, a momentary overload, a warning that does not stop the lift.
    NormalService,
    /// Not available because of a fault: a blocked or shut-down lift, the safety
    /// circuit open, a stop by a monitor (thermistor, running time, rope, AWM). A
    /// stoppage that may need a technician.
    OutOfService,
    /// A technician's work: inspection, teach-in run, test stops.
    Inspection,
    /// A special or restricted operation that is neither a fault nor a technician's
    /// work: attendant operation, call lock-outs, priority and recall runs, emergency
    /// power, fire operation. Not available to ordinary calls.
    Other,
    /// A code not in Appendix A (16, 28, …), no status yet or no communication.
    Unknown,
}

impl LiftMode {
    /// All modes, in order.
    pub const ALL: [LiftMode; 5] = [
        LiftMode::NormalService,
        LiftMode::OutOfService,
        LiftMode::Inspection,
        LiftMode::Other,
        LiftMode::Unknown,
    ];

    /// A stable key for JSON and configuration.
    pub fn key(self) -> &'static str {
        match self {
            LiftMode::NormalService => "normal-service",
            LiftMode::OutOfService => "out-of-service",
            LiftMode::Inspection => "inspection",
            LiftMode::Other => "other",
            LiftMode::Unknown => "unknown",
        }
    }

    /// English label.
    pub fn english(self) -> &'static str {
        match self {
            LiftMode::NormalService => "In service",
            LiftMode::OutOfService => "Out of service",
            LiftMode::Inspection => "Inspection",
            LiftMode::Other => "Special operation",
            LiftMode::Unknown => "Unknown",
        }
    }

    /// Czech label.
    pub fn czech(self) -> &'static str {
        match self {
            LiftMode::NormalService => "V provozu",
            LiftMode::OutOfService => "Mimo provoz",
            LiftMode::Inspection => "Inspekce",
            LiftMode::Other => "Zvláštní provoz",
            LiftMode::Unknown => "Neznámý",
        }
    }
}

impl fmt::Display for LiftMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.key())
    }
}

/// The service mode of a status code (Appendix A); unknown codes are
/// [`LiftMode::Unknown`].
///
/// Decided from the texts (the Czech originals where the English is thin) and the
/// colour classes of spec §5: every red code is out of service except the fire
/// operation; the orange codes split into passenger-caused moments (normal service), a
/// technician's work (inspection) and special operation (other).
pub fn lift_mode(status: u8) -> LiftMode {
    match status {
        // Ready (1, 4), floor correction (3: a correction run of normal operation), start
        // of call operation (5), re-levelling (7), loading time (8), fully loaded (12:
        // the car skips landing calls but serves its load), the automatic runs: start-up
        // (13), parking (14), warm-up (15).
        1 | 3 | 4 | 5 | 7 | 8 | 12 | 13 | 14 | 15 => LiftMode::NormalService,
        // Overloaded (10, 41 "EN 81 overloaded"): the car waits until the load is
        // reduced; a passenger-caused moment, the lift is in service.
        10 | 41 => LiftMode::NormalService,
        // A passenger at the doors: light curtain interrupted (29), landing doors
        // (30: a landing door not yet closed), door-open button (31), stop by the light
        // curtain (36). Their permanent forms are faults in Appendix B (0x3E, 0x3F, 0x40).
        29 | 30 | 31 | 36 => LiftMode::NormalService,
        // Rope tension (54) and rope warning (55): warnings, orange; the lift still runs
        // (the stops are 52 and 53).
        54 | 55 => LiftMode::NormalService,
        // Faults that stop the lift (all red): SIS error (6), light-curtain fault (18),
        // door fault (19), shut down (20), evacuation (22: passengers are being freed),
        // thermistor error (25), parameter-controlled shut-down (26), start-up run error
        // (27), the AWM stops (32-35: car light, alarm, door-open button, safety
        // circuit), no shaft data (37), drive hanging (38), travel lock-out (42),
        // running-time error (43), safety circuit open (44), SK0 fault (45), thermistor
        // stops (48, 49), parameter error (51), rope replacement and service-life stops
        // (52, 53).
        6
        | 18
        | 19
        | 20
        | 22
        | 25
        | 26
        | 27
        | 32..=35
        | 37
        | 38
        | 42
        | 43
        | 44
        | 45
        | 48
        | 49
        | 51
        | 52
        | 53 => LiftMode::OutOfService,
        // A technician at work: learning (teach-in) run (21), SK2 and A3 test stops (39,
        // 40: the EN 81 tests of the safety circuit and of unintended car movement),
        // inspection (46).
        21 | 39 | 40 | 46 => LiftMode::Inspection,
        // Special operation, no fault: lift attendant (2), call lock-out (9), landing-call
        // lock-out (11), priority run (17: key-switch exclusive use), recall (47),
        // emergency power (50). Fire case (23) and firefighter run (24) are red on the
        // panel but are no failure of the lift: counting a fire drill as a failure would
        // distort MTBF.
        2 | 9 | 11 | 17 | 47 | 50 | 23 | 24 => LiftMode::Other,
        _ => LiftMode::Unknown,
    }
}

/// The door state shown beside the car (spec §9: open, closed, partly open, door fault).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DoorState {
    /// Closed.
    Closed,
    /// Opening or closing, or not closed and not known to be fully open.
    PartlyOpen,
    /// Open.
    Open,
    /// A door fault.
    Fault,
}

impl fmt::Display for DoorState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            DoorState::Closed => "closed",
            DoorState::PartlyOpen => "partly open",
            DoorState::Open => "open",
            DoorState::Fault => "door fault",
        })
    }
}

/// The door state a status code implies, `None` when it says nothing about the doors
/// (spec §9 and EKM-A6: the protocol as known has no door octet, so the state is derived
/// from the status).
pub fn door_state(status: u8) -> Option<DoorState> {
    match status {
        // Door fault (19) and light-curtain fault (18: the doors' protective device; the
        // doors cannot close normally).
        18 | 19 => Some(DoorState::Fault),
        // Held open: loading time (8), light curtain interrupted (29), door-open button
        // (31), AWM stop on the door-open button (34), stop by the light curtain (36:
        // the closing doors reverse to open).
        8 | 29 | 31 | 34 | 36 => Some(DoorState::Open),
        // Landing (shaft) doors (30): a landing door is not closed and locked while the
        // car waits; not closed, not known to be fully open.
        30 => Some(DoorState::PartlyOpen),
        // Runs without passengers, which travel with closed doors: floor correction (3),
        // start-up (13), parking (14), warm-up (15) and learning (21) runs.
        3 | 13 | 14 | 15 | 21 => Some(DoorState::Closed),
        // Everything else: "ready" covers idle, travelling and door cycles alike; the
        // faults and special runs do not say where the doors are.
        _ => None,
    }
}

/// The groups of the minimum fault log of remote lift monitoring (in the manner of
/// EN 81-28 / EN 627): what a service firm counts per lift. Serialised as its
/// [`FaultGroup::key`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum FaultGroup {
    /// The safety circuit broken during travel.
    SafetyCircuitInTravel,
    /// A door sequence fault (doors do not close, lock or open as they should).
    DoorSequence,
    /// The car stopped outside the door zone (passengers possibly trapped).
    StopOutsideDoorZone,
    /// The lift cannot start.
    CannotStart,
    /// The main power was off.
    MainPowerOff,
    /// Inspection mode.
    InspectionMode,
    /// The alarm button.
    AlarmButton,
    /// Everything else.
    Other,
}

impl FaultGroup {
    /// All groups, in order.
    pub const ALL: [FaultGroup; 8] = [
        FaultGroup::SafetyCircuitInTravel,
        FaultGroup::DoorSequence,
        FaultGroup::StopOutsideDoorZone,
        FaultGroup::CannotStart,
        FaultGroup::MainPowerOff,
        FaultGroup::InspectionMode,
        FaultGroup::AlarmButton,
        FaultGroup::Other,
    ];

    /// A stable kebab-case key (also the group's JSON form).
    pub fn key(self) -> &'static str {
        match self {
            FaultGroup::SafetyCircuitInTravel => "safety-circuit",
            FaultGroup::DoorSequence => "door-sequence",
            FaultGroup::StopOutsideDoorZone => "outside-door-zone",
            FaultGroup::CannotStart => "cannot-start",
            FaultGroup::MainPowerOff => "main-power",
            FaultGroup::InspectionMode => "inspection",
            FaultGroup::AlarmButton => "alarm-button",
            FaultGroup::Other => "other",
        }
    }

    /// The group of a key, `None` for another string.
    pub fn from_key(key: &str) -> Option<FaultGroup> {
        FaultGroup::ALL.into_iter().find(|group| group.key() == key)
    }

    /// English label.
    pub fn english(self) -> &'static str {
        match self {
            FaultGroup::SafetyCircuitInTravel => "Safety circuit broken during travel",
            FaultGroup::DoorSequence => "Door sequence fault",
            FaultGroup::StopOutsideDoorZone => "Stop outside the door zone",
            FaultGroup::CannotStart => "Lift cannot start",
            FaultGroup::MainPowerOff => "Main power off",
            FaultGroup::InspectionMode => "Inspection mode",
            FaultGroup::AlarmButton => "Alarm button",
            FaultGroup::Other => "Other",
        }
    }

    /// Czech label.
    pub fn czech(self) -> &'static str {
        match self {
            FaultGroup::SafetyCircuitInTravel => "Přerušení bezpečnostního obvodu za jízdy",
            FaultGroup::DoorSequence => "Porucha dveří",
            FaultGroup::StopOutsideDoorZone => "Zastavení mimo dveřní zónu",
            FaultGroup::CannotStart => "Výtah se nerozjede",
            FaultGroup::MainPowerOff => "Výpadek hlavního napájení",
            FaultGroup::InspectionMode => "Inspekce",
            FaultGroup::AlarmButton => "Tlačítko alarmu",
            FaultGroup::Other => "Ostatní",
        }
    }
}

impl fmt::Display for FaultGroup {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.key())
    }
}

impl Serialize for FaultGroup {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.key())
    }
}

impl<'de> Deserialize<'de> for FaultGroup {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let key = String::deserialize(deserializer)?;
        FaultGroup::from_key(&key)
            .ok_or_else(|| serde::de::Error::custom(format!("unknown fault group {key:?}")))
    }
}

/// The minimum-fault-log group of a fault code (Appendix B); codes not in Appendix B
/// are [`FaultGroup::Other`].
pub fn fault_group(code: u8) -> FaultGroup {
    match code {
        // Safety circuit opened during travel (0x11) and while the doors open (0x18: the
        // doors open in advance while the car still levels in the door zone); the
        // safety-circuit sections SK1 open (0x45) and SK0 fault (0x4D) and the AWM
        // safety-circuit stop (0x53), which the board reports when the circuit breaks.
        0x11 | 0x18 | 0x45 | 0x4D | 0x53 => FaultGroup::SafetyCircuitInTravel,
        // The doors do not go through their sequence: door fault (0x3C), light-grid stop
        // (0x36), light-curtain fault (0x3D), light curtain permanently interrupted
        // (0x3E), landing door permanently open (0x3F), door-open button permanently
        // pressed (0x40) and its AWM stop (0x52).
        0x36 | 0x3C..=0x40 | 0x52 => FaultGroup::DoorSequence,
        // The car stops where the board did not plan to: hard stop (0x12), the
        // running-time monitors (0x13-0x15, 0x44: the drive is cut wherever the car
        // is), stopping error (0x16), no stop signals (0x2C: the floor-zone signals were
        // missed), re-levelling fault (0x49: the car could not re-level into the zone).
        0x12..=0x16 | 0x2C | 0x44 | 0x49 => FaultGroup::StopOutsideDoorZone,
        // No start (0x10), no start via SIS (0x17), travel lock-out (0x43), start-up
        // cancelled (0x4E).
        0x10 | 0x17 | 0x43 | 0x4E => FaultGroup::CannotStart,
        // System start (0x30: the board came up, after the mains returned or a reset)
        // and operation on emergency power (0x54: the mains are off).
        0x30 | 0x54 => FaultGroup::MainPowerOff,
        // Inspection (0x46), learning run (0x38) and the SIS and SK2 test stops (0x4B,
        // 0x4C): a technician's work, the log's side of LiftMode::Inspection. (The time
        // in inspection comes from the status, 46.)
        0x38 | 0x46 | 0x4B | 0x4C => FaultGroup::InspectionMode,
        // AWM alarm shut-down (0x51): the alarm stopped the lift. Appendix B has no
        // plain "alarm button pressed" record; this is the only alarm entry.
        0x51 => FaultGroup::AlarmButton,
        // The rest: log and system records (0x01-0x05), the shaft signal faults
        // (0x20-0x2B, 0x2D), load and call lock-outs (0x31-0x35), evacuation, shut-down,
        // fire operation, thermistor stops (0x37, 0x39, 0x3A, 0x3B, 0x48), no shaft
        // data (0x41), drive hanging (0x42), recall (0x47), SIS fault (0x4A), EN 81
        // overload (0x4F), AWM car light (0x50), loading standby (0x55), parameters
        // (0x56, 0x57, 0x5A), fire case (0x58), restricted call operation (0x59), the
        // rope stops and warnings (0x5B-0x5E), and codes not in Appendix B.
        _ => FaultGroup::Other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Czech texts are written as Czech is, with its diacritics: the thesis printed
    /// most fault texts without them ("Porucha dveri"), as the board's display does.
    #[test]
    fn czech_texts_keep_their_diacritics() {
        // Stems that Czech never writes without diacritics.
        const UNACCENTED: &[&str] = &[
            "dveri",
            "jizd",
            "pretiz",
            "zadn",
            "privol",
            "signal",
            "chybny",
            "uzaver",
            "sachet",
            "sacht",
            "napaj",
            "nouzovy ",
            "nouzovym",
            "zastaveni",
            "svet.",
            "svetl",
            "pozar",
            "ucebni",
            "uvedeni",
            "vymena",
            "vystrah",
            "spoust",
            "zpetn",
            "nakladk",
            "otevr",
            "otac",
            "systemu",
            "visi",
            "behu",
            "pres ",
            "zatiz",
            "zac.",
            "mriz",
            "dolu",
            "nahore",
            "tlac",
        ];
        let texts = STATUS_CODES
            .iter()
            .map(|entry| entry.czech)
            .chain(FAULT_CODES.iter().map(|entry| entry.czech));
        for text in texts {
            let lower = text.to_lowercase();
            for stem in UNACCENTED {
                assert!(!lower.contains(stem), "{text:?} lacks diacritics ({stem})");
            }
        }
        assert_eq!(fault_text_czech(0x3C), "Porucha dveří");
    }
}
