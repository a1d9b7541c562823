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
        czech: "Zac.vol.provozu",
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
        czech: "Tlačítko otevíření dveří",
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
        czech: "AWM:T.otevr.dveri",
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
        czech: "EN81-pretizeno",
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
        czech: "Nouzovy Proud",
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
        czech: "Žádný start (pres SIS)",
    },
    FaultCode {
        code: 0x18,
        english: "Safety circuit (opened) while doors opening",
        czech: "B.obvod při otvirani",
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
        czech: "Chybný signál impuls-dolu",
    },
    FaultCode {
        code: 0x23,
        english: "Faulty correction signal",
        czech: "Chybný signál korekce",
    },
    FaultCode {
        code: 0x24,
        english: "Faulty correction signal — top",
        czech: "Chybný signál korekce-nahore",
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
        czech: "Chybny signal oba HKU+HKO",
    },
    FaultCode {
        code: 0x2B,
        english: "Wrong direction of rotation",
        czech: "Chybny smer otac",
    },
    FaultCode {
        code: 0x2C,
        english: "No stop signals",
        czech: "Zadne signaly zastaveni",
    },
    FaultCode {
        code: 0x2D,
        english: "Faulty pulse signal",
        czech: "Chybny signal impuls",
    },
    FaultCode {
        code: 0x30,
        english: "System start",
        czech: "Start systemu",
    },
    FaultCode {
        code: 0x31,
        english: "Correction run",
        czech: "Kor.stavu-jizda",
    },
    FaultCode {
        code: 0x32,
        english: "Call lock-out",
        czech: "Uzaver volani",
    },
    FaultCode {
        code: 0x33,
        english: "Overloaded",
        czech: "Pretizeno",
    },
    FaultCode {
        code: 0x34,
        english: "Landing-call lock-out",
        czech: "Uzaver vnej.vol.",
    },
    FaultCode {
        code: 0x35,
        english: "Full load",
        czech: "Plne zatizeni",
    },
    FaultCode {
        code: 0x36,
        english: "Light-grid stop",
        czech: "Svet.mriz-stop",
    },
    FaultCode {
        code: 0x37,
        english: "Evacuation",
        czech: "Evakuace",
    },
    FaultCode {
        code: 0x38,
        english: "Learning run",
        czech: "Ucebni jizda",
    },
    FaultCode {
        code: 0x39,
        english: "Shut-down",
        czech: "Uvedeni do klidu",
    },
    FaultCode {
        code: 0x3A,
        english: "Firefighter run",
        czech: "Pozarni jizda",
    },
    FaultCode {
        code: 0x3B,
        english: "Travel stopped by thermistor",
        czech: "Zast.jizdy term.",
    },
    FaultCode {
        code: 0x3C,
        english: "Door fault",
        czech: "Porucha dveri",
    },
    FaultCode {
        code: 0x3D,
        english: "Light-curtain fault",
        czech: "Poruch.svet.zav.",
    },
    FaultCode {
        code: 0x3E,
        english: "Light curtain permanently interrupted",
        czech: "Trvale svet.zav.",
    },
    FaultCode {
        code: 0x3F,
        english: "Landing door permanently open",
        czech: "Trvale otevr.sach.dveri",
    },
    FaultCode {
        code: 0x40,
        english: "Door-open button permanently pressed",
        czech: "Trvale tlac.otev.dveri",
    },
    FaultCode {
        code: 0x41,
        english: "No shaft data",
        czech: "Zadne udaje sachty",
    },
    FaultCode {
        code: 0x42,
        english: "Drive hanging (stuck)",
        czech: "Pohon visi",
    },
    FaultCode {
        code: 0x43,
        english: "Travel lock-out",
        czech: "Uzavěr jizdy",
    },
    FaultCode {
        code: 0x44,
        english: "Running-time monitoring",
        czech: "Kontr.doby behu",
    },
    FaultCode {
        code: 0x45,
        english: "Safety circuit SK1 open",
        czech: "B.obvod SK1 rozp",
    },
    FaultCode {
        code: 0x46,
        english: "Inspection",
        czech: "Inspekce",
    },
    FaultCode {
        code: 0x47,
        english: "Recall",
        czech: "Zpetne privolani",
    },
    FaultCode {
        code: 0x48,
        english: "Thermistor stop",
        czech: "Zastaveni term",
    },
    FaultCode {
        code: 0x49,
        english: "Re-levelling fault",
        czech: "Porucha doregul",
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
        czech: "Spoust.zruseno",
    },
    FaultCode {
        code: 0x4F,
        english: "EN 81 overloaded",
        czech: "EN81-pretizeno",
    },
    FaultCode {
        code: 0x50,
        english: "AWM: car light — stop",
        czech: "AWM-Kabin.svetlo-zastav.",
    },
    FaultCode {
        code: 0x51,
        english: "AWM: alarm shut-down — stop",
        czech: "AWM-Alarm odstaveni-zastav.",
    },
    FaultCode {
        code: 0x52,
        english: "AWM: door-open button — stop",
        czech: "AWM-Tl.otevr.dveri-zastav.",
    },
    FaultCode {
        code: 0x53,
        english: "AWM: safety-circuit error — AWM standstill",
        czech: "AWM-Chyba b.obvodu AWM-klid",
    },
    FaultCode {
        code: 0x54,
        english: "Operation on emergency power",
        czech: "Provoz s nouzovym napajenim",
    },
    FaultCode {
        code: 0x55,
        english: "Loading — standby",
        czech: "Nakladka-pohotovost",
    },
    FaultCode {
        code: 0x56,
        english: "Parameter-controlled shut-down",
        czech: "Para-uvvedeni do klidu",
    },
    FaultCode {
        code: 0x57,
        english: "Parameter error",
        czech: "Chyba parametru",
    },
    FaultCode {
        code: 0x58,
        english: "Fire case",
        czech: "Pripad pozaru",
    },
    FaultCode {
        code: 0x59,
        english: "Restricted call operation",
        czech: "Omezeny privol.provoz",
    },
    FaultCode {
        code: 0x5A,
        english: "No parameter",
        czech: "Zadny parametr",
    },
    FaultCode {
        code: 0x5B,
        english: "Rope replacement stop",
        czech: "Vymena lana stop",
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
        czech: "Vystraha lana",
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
