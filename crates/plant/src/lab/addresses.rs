//! The address tables of the four models (the teaching-lab thesis, sections 3.4, 4.2, 5.3
//! and 6.3 of the lab-models spec), both printed columns, and the lab wiring pattern of
//! section 2 (`LAB-A8`).
//!
//! The tables keep the printed columns as printed (`Y0.5`, `X83.3`); [`Profile::Lab`]
//! derives its addresses from the model column through the pattern
//!
//! | Model documentation | Lab wiring |
//! |---|---|
//! | `Y0.0`–`Y0.3` | `Y2.0`–`Y2.3` |
//! | `Y0.4`–`Y0.7` | `Y24.0`–`Y24.3` |
//! | `X0.0`–`X0.3` | `X10.2`–`X10.5` |
//! | `X0.4`–`X0.7` | `X84.0`–`X84.3` |
//!
//! which differs from the printed lab column in exactly three places: slide EM1–EM3
//! (printed `Y0.0`–`Y0.2`), mixing SV4/SV5 (printed `Y24.0`/`Y24.1`, swapped) and washing
//! `voda_100` (printed `X83.3`). A direct address is written IEC style without `%`: `Yb.n`
//! → `QXb.n`, `Xb.n` → `IXb.n`.

use super::{Binding, Profile};

/// One row of a printed I/O table: the variable and its two printed addresses.
struct Row {
    signal: &'static str,
    model: &'static str,
    lab: &'static str,
}

const fn row(signal: &'static str, model: &'static str, lab: &'static str) -> Row {
    Row { signal, model, lab }
}

/// Section 3.4.
const SLIDE: &[Row] = &[
    row("EM1", "Y0.0", "Y0.0"),
    row("EM2", "Y0.1", "Y0.1"),
    row("EM3", "Y0.2", "Y0.2"),
    row("K1", "X0.0", "X10.2"),
    row("K2", "X0.1", "X10.3"),
    row("K3", "X0.2", "X10.4"),
    row("K4", "X0.3", "X10.5"),
];

/// Section 4.2.
const CROSSROAD: &[Row] = &[
    row("cerv_spodek", "Y0.0", "Y2.0"),
    row("oran_spodek", "Y0.1", "Y2.1"),
    row("zel_spodek", "Y0.2", "Y2.2"),
    row("cerv_vrch", "Y0.3", "Y2.3"),
    row("oran_vrch", "Y0.4", "Y24.0"),
    row("zel_vrch", "Y0.5", "Y24.1"),
    row("cerv_chodci", "Y0.6", "Y24.2"),
    row("zel_chodci", "Y0.7", "Y24.3"),
];

/// Section 5.3.
const MIXING: &[Row] = &[
    row("SV1", "Y0.0", "Y2.0"),
    row("SV2", "Y0.1", "Y2.1"),
    row("SV3", "Y0.2", "Y2.2"),
    row("SV4", "Y0.5", "Y24.0"),
    row("SV5", "Y0.4", "Y24.1"),
    row("MIX", "Y0.6", "Y24.2"),
    row("H1", "X0.3", "X10.5"),
    row("H2", "X0.2", "X10.4"),
    row("H3", "X0.1", "X10.3"),
    row("H4", "X0.0", "X10.2"),
    row("H5", "X0.7", "X84.3"),
    row("H6", "X0.4", "X84.0"),
    row("H7", "X0.5", "X84.1"),
    row("H8", "X0.6", "X84.2"),
];

/// Section 6.3.
const WASHING: &[Row] = &[
    row("buben_vpravo", "Y0.0", "Y2.0"),
    row("buben_vlevo", "Y0.1", "Y2.1"),
    row("otacky", "Y0.2", "Y2.2"),
    row("topeni", "Y0.4", "Y24.0"),
    row("napousteni", "Y0.5", "Y24.1"),
    row("cerpadlo", "Y0.6", "Y24.2"),
    row("teplota_90", "X0.0", "X10.2"),
    row("teplota_60", "X0.1", "X10.3"),
    row("teplota_40", "X0.2", "X10.4"),
    row("teplota_30", "X0.3", "X10.5"),
    row("voda_50", "X0.6", "X84.2"),
    row("voda_100", "X0.7", "X83.3"),
];

/// Signals the spec gives no address (our choice, the same in both lab profiles).
const PUSH_BUTTON: Row = row("tlacitko_chodci", "X0.0", "X10.2");
const START: Row = row("START", "X1.0", "X11.0");
const ERR: Row = row("ERR", "X1.1", "X11.1");
const RESET: Row = row("RESET", "Y1.0", "Y11.0");

fn model_rows(model: &str) -> Option<&'static [Row]> {
    match model {
        "slide" => Some(SLIDE),
        "crossroad" => Some(CROSSROAD),
        "mixing" => Some(MIXING),
        "washing" => Some(WASHING),
        _ => None,
    }
}

/// The lab wiring of a model-documentation address by the pattern of section 2, or `None`
/// outside bytes `Y0`/`X0`.
fn lab_pattern(model_address: &str) -> Option<String> {
    let (area, rest) = model_address.split_at_checked(1)?;
    let bit: u8 = rest.strip_prefix("0.")?.parse().ok()?;
    match (area, bit) {
        ("Y", 0..=3) => Some(format!("Y2.{bit}")),
        ("Y", 4..=7) => Some(format!("Y24.{}", bit - 4)),
        ("X", 0..=3) => Some(format!("X10.{}", bit + 2)),
        ("X", 4..=7) => Some(format!("X84.{}", bit - 4)),
        _ => None,
    }
}

/// `Yb.n` → `QXb.n`, `Xb.n` → `IXb.n`.
fn iec(printed: &str) -> String {
    if let Some(rest) = printed.strip_prefix('Y') {
        format!("QX{rest}")
    } else if let Some(rest) = printed.strip_prefix('X') {
        format!("IX{rest}")
    } else {
        printed.to_owned()
    }
}

fn address(row: &Row, profile: Profile, patterned: bool) -> String {
    let printed = match profile {
        Profile::Model => row.model.to_owned(),
        Profile::Lab if patterned => lab_pattern(row.model).unwrap_or_else(|| row.lab.to_owned()),
        Profile::Lab | Profile::LabPrinted => row.lab.to_owned(),
    };
    iec(&printed)
}

/// The model's bindings in `profile` (see [`super::bindings`]), or `None` for an unknown
/// model.
pub(super) fn table(model: &str, profile: Profile, program_err: bool) -> Option<Vec<Binding>> {
    let rows = model_rows(model)?;
    let bind = |row: &Row, patterned: bool| Binding {
        signal: row.signal.to_owned(),
        address: address(row, profile, patterned),
    };
    let mut out: Vec<Binding> = rows.iter().map(|r| bind(r, true)).collect();
    if model == "crossroad" {
        out.push(bind(&PUSH_BUTTON, false));
    }
    out.push(bind(&START, false));
    if program_err {
        out.push(bind(&ERR, false));
        out.push(bind(&RESET, false));
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pattern_differs_from_the_printed_lab_column_exactly_at_lab_a8() {
        let mut differences = Vec::new();
        for (model, rows) in [
            ("slide", SLIDE),
            ("crossroad", CROSSROAD),
            ("mixing", MIXING),
            ("washing", WASHING),
        ] {
            for r in rows {
                let pattern = lab_pattern(r.model).unwrap();
                if pattern != r.lab {
                    differences.push(format!("{model} {} {} {pattern}", r.signal, r.lab));
                }
            }
        }
        assert_eq!(
            differences,
            [
                "slide EM1 Y0.0 Y2.0",
                "slide EM2 Y0.1 Y2.1",
                "slide EM3 Y0.2 Y2.2",
                "mixing SV4 Y24.0 Y24.1",
                "mixing SV5 Y24.1 Y24.0",
                "washing voda_100 X83.3 X84.3",
            ]
        );
        // The push-button's lab address follows the pattern too.
        assert_eq!(
            lab_pattern(PUSH_BUTTON.model).as_deref(),
            Some(PUSH_BUTTON.lab)
        );
    }

    #[test]
    fn pattern_and_iec_forms() {
        assert_eq!(lab_pattern("Y0.7").as_deref(), Some("Y24.3"));
        assert_eq!(lab_pattern("X0.4").as_deref(), Some("X84.0"));
        assert_eq!(lab_pattern("X1.0"), None);
        assert_eq!(lab_pattern("Z0.0"), None);
        assert_eq!(lab_pattern(""), None);
        assert_eq!(iec("Y24.1"), "QX24.1");
        assert_eq!(iec("X83.3"), "IX83.3");
    }
}
