//! Values as people type them (point lists, a test tool's `--value`, a gateway's mapping
//! file) turned into information elements of a given type: one reading of `ON`, `0.5`,
//! `0x1F` or `HIGHER` for every tool, IEC 104 and IEC 101 alike.

use super::{
    BinaryCounterReading, CommandQualifier, DoublePointState, Element, Quality,
    RegulatingStepState, SetpointQualifier, StepPosition, TypeId,
};

/// A value that does not fit the type it was given for; says what was expected.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct ValueError(String);

macro_rules! bail {
    ($($arg:tt)*) => {
        return Err(ValueError(format!($($arg)*)))
    };
}

type Result<T> = std::result::Result<T, ValueError>;

fn parse_bool(text: &str) -> Result<bool> {
    match text.trim().to_ascii_lowercase().as_str() {
        "1" | "on" | "true" => Ok(true),
        "0" | "off" | "false" | "" => Ok(false),
        other => bail!("'{other}' is not 0/1, ON/OFF or TRUE/FALSE"),
    }
}

fn parse_double(text: &str) -> Result<DoublePointState> {
    Ok(match text.trim().to_ascii_lowercase().as_str() {
        "0" | "intermediate" => DoublePointState::Intermediate,
        "1" | "off" | "open" | "" => DoublePointState::Off,
        "2" | "on" | "closed" | "close" => DoublePointState::On,
        "3" | "indeterminate" => DoublePointState::Indeterminate,
        other => bail!("'{other}' is not a double-point state (OFF/ON or 0..3)"),
    })
}

fn parse_u32(text: &str) -> Result<u32> {
    let text = text.trim();
    let parsed = match text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        Some(hex) => u32::from_str_radix(hex, 16),
        None if text.is_empty() => Ok(0),
        None => text.parse(),
    };
    parsed.map_err(|_| ValueError(format!("'{text}' is not a 32-bit number")))
}

fn parse_number<T: std::str::FromStr + Default>(text: &str, what: &str) -> Result<T> {
    let text = text.trim();
    if text.is_empty() {
        return Ok(T::default());
    }
    text.parse()
        .map_err(|_| ValueError(format!("'{text}' is not a valid {what}")))
}

/// A normalized value: a fraction with a decimal point (`0.335114`) or a raw integer
/// (`10981`), as gateways that put engineering integers in the field do (spec IEC-A4).
fn parse_normalized(text: &str) -> Result<i16> {
    let text = text.trim();
    if text.contains('.') || text.contains('e') {
        let fraction: f32 = parse_number(text, "normalized value")?;
        if !(-1.0..1.0).contains(&fraction) {
            bail!("normalized fraction {fraction} is outside -1 .. 1");
        }
        Ok(Element::normalized_raw(fraction))
    } else {
        parse_number(text, "normalized raw value (-32768..32767)")
    }
}

/// A monitor point's value of the given type (good quality; a time-tagged type reads as
/// its untagged twin).
pub fn parse_monitor(type_id: TypeId, text: &str) -> Result<Element> {
    let quality = Quality::default();
    let base = type_id.without_time().unwrap_or(type_id);
    Ok(match base {
        TypeId::M_SP_NA_1 => Element::SinglePoint {
            on: parse_bool(text)?,
            quality,
        },
        TypeId::M_DP_NA_1 => Element::DoublePoint {
            state: parse_double(text)?,
            quality,
        },
        TypeId::M_ST_NA_1 => {
            let value: i8 = parse_number(text, "step position (-64..63)")?;
            Element::StepPosition {
                position: StepPosition::new(value, false)
                    .map_err(|error| ValueError(error.to_string()))?,
                quality,
            }
        }
        TypeId::M_BO_NA_1 => Element::Bitstring {
            bits: parse_u32(text)?,
            quality,
        },
        TypeId::M_ME_NA_1 | TypeId::M_ME_ND_1 => Element::Normalized {
            raw: parse_normalized(text)?,
            quality,
        },
        TypeId::M_ME_NB_1 => Element::Scaled {
            value: parse_number(text, "scaled value (-32768..32767)")?,
            quality,
        },
        TypeId::M_ME_NC_1 => {
            let value: f32 = parse_number(text, "floating-point value")?;
            if !value.is_finite() {
                bail!("'{text}' is not a finite number");
            }
            Element::Float { value, quality }
        }
        TypeId::M_IT_NA_1 => Element::IntegratedTotal(
            BinaryCounterReading::new(parse_number(text, "counter value")?, 0)
                .map_err(|error| ValueError(error.to_string()))?,
        ),
        TypeId::M_PS_NA_1 => {
            let bits = parse_u32(text)?;
            Element::PackedSinglePoints {
                status: (bits & 0xFFFF) as u16,
                change: (bits >> 16) as u16,
                quality,
            }
        }
        other => bail!("{other} values cannot be given as text"),
    })
}

/// A command element of the given type, select or execute, with the qualifier QU (0..31;
/// for set-points QL 0..127).
pub fn parse_command(type_id: TypeId, text: &str, select: bool, qualifier: u8) -> Result<Element> {
    let command_qualifier = || {
        CommandQualifier::new(qualifier, select)
            .map_err(|error| ValueError(format!("qualifier: {error}")))
    };
    let setpoint_qualifier = || {
        SetpointQualifier::new(qualifier, select)
            .map_err(|error| ValueError(format!("qualifier: {error}")))
    };
    Ok(match type_id {
        TypeId::C_SC_NA_1 | TypeId::C_SC_TA_1 => Element::SingleCommand {
            on: parse_bool(text)?,
            qualifier: command_qualifier()?,
        },
        TypeId::C_DC_NA_1 | TypeId::C_DC_TA_1 => {
            // The DCS numbers are the standard's, not a boolean: 1 is OFF and 2 is ON; 0
            // and 3 are "not permitted" (IEC 60870-5-101, 7.2.6.16).
            let state = match text.trim().to_ascii_lowercase().as_str() {
                "" => bail!("a double command needs a value: ON or OFF (DCS 2 or 1)"),
                other => parse_double(other)?,
            };
            if !matches!(state, DoublePointState::On | DoublePointState::Off) {
                bail!(
                    "'{}' is DCS {}, which IEC 60870-5-101 (7.2.6.16) does not permit in a \
                     double command: give ON or OFF (DCS 2 = ON, DCS 1 = OFF)",
                    text.trim(),
                    state as u8
                );
            }
            Element::DoubleCommand {
                state,
                qualifier: command_qualifier()?,
            }
        }
        TypeId::C_RC_NA_1 | TypeId::C_RC_TA_1 => {
            let state = match text.trim().to_ascii_lowercase().as_str() {
                "1" | "lower" | "down" => RegulatingStepState::Lower,
                "2" | "higher" | "up" => RegulatingStepState::Higher,
                other => bail!("'{other}' is not LOWER (1) or HIGHER (2)"),
            };
            Element::RegulatingStep {
                state,
                qualifier: command_qualifier()?,
            }
        }
        TypeId::C_SE_NA_1 | TypeId::C_SE_TA_1 => Element::SetpointNormalized {
            raw: parse_normalized(text)?,
            qualifier: setpoint_qualifier()?,
        },
        TypeId::C_SE_NB_1 | TypeId::C_SE_TB_1 => Element::SetpointScaled {
            value: parse_number(text, "scaled value (-32768..32767)")?,
            qualifier: setpoint_qualifier()?,
        },
        TypeId::C_SE_NC_1 | TypeId::C_SE_TC_1 => {
            let value: f32 = parse_number(text, "floating-point value")?;
            if !value.is_finite() {
                bail!("'{text}' is not a finite number");
            }
            Element::SetpointFloat {
                value,
                qualifier: setpoint_qualifier()?,
            }
        }
        TypeId::C_BO_NA_1 | TypeId::C_BO_TA_1 => {
            if select {
                bail!("bit-string commands have no select step");
            }
            Element::BitstringCommand {
                bits: parse_u32(text)?,
            }
        }
        other => bail!("{other} is not a command type"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalized_accepts_fraction_and_raw() {
        assert_eq!(parse_normalized("0.335114").unwrap(), 10981);
        assert_eq!(parse_normalized("10981").unwrap(), 10981);
        assert!(parse_normalized("1.5").is_err());
    }

    #[test]
    fn commands_parse_and_refuse() {
        assert!(matches!(
            parse_command(TypeId::C_DC_NA_1, "ON", false, 0).unwrap(),
            Element::DoubleCommand {
                state: DoublePointState::On,
                ..
            }
        ));
        assert!(matches!(
            parse_command(TypeId::C_DC_NA_1, "off", false, 0).unwrap(),
            Element::DoubleCommand {
                state: DoublePointState::Off,
                ..
            }
        ));
        // The DCS numbers: 1 = OFF, 2 = ON; 0 and 3 refused naming the rule.
        assert!(matches!(
            parse_command(TypeId::C_DC_NA_1, "2", false, 0).unwrap(),
            Element::DoubleCommand {
                state: DoublePointState::On,
                ..
            }
        ));
        for refused in ["0", "3", ""] {
            let error = parse_command(TypeId::C_DC_NA_1, refused, false, 0)
                .unwrap_err()
                .to_string();
            assert!(error.contains("ON or OFF"), "{refused}: {error}");
        }
        assert!(parse_command(TypeId::C_DC_NA_1, "3", false, 0)
            .unwrap_err()
            .to_string()
            .contains("7.2.6.16"));
        assert!(parse_command(TypeId::C_SC_NA_1, "1", true, 32).is_err());
        assert!(parse_command(TypeId::M_SP_NA_1, "1", false, 0).is_err());
        assert!(parse_command(TypeId::C_SE_NC_1, "nan", false, 0).is_err());
    }

    proptest::proptest! {
        /// Any text, any type: a value or an error, never a panic.
        #[test]
        fn any_text_is_read_or_refused(text in ".{0,24}", type_byte in 0u8..=255, select: bool, qualifier in 0u8..=255) {
            if let Some(type_id) = TypeId::from_u8(type_byte) {
                let _ = parse_monitor(type_id, &text);
                let _ = parse_command(type_id, &text, select, qualifier);
            }
        }

        /// A normalized value written as its fraction reads back to the same raw value.
        #[test]
        fn normalized_fraction_round_trips(raw: i16) {
            let text = format!("{:.9}", Element::normalized_value(raw));
            proptest::prop_assert_eq!(parse_normalized(&text).unwrap(), raw);
        }

        /// Scaled values and 32-bit strings in decimal and hexadecimal read back exactly.
        #[test]
        fn integers_round_trip(value: i16, bits: u32) {
            proptest::prop_assert_eq!(
                parse_monitor(TypeId::M_ME_NB_1, &value.to_string()).unwrap(),
                Element::Scaled { value, quality: Quality::default() }
            );
            proptest::prop_assert_eq!(parse_u32(&format!("0x{bits:X}")).unwrap(), bits);
            proptest::prop_assert_eq!(parse_u32(&bits.to_string()).unwrap(), bits);
        }
    }
}
