//! Values typed by people (point files, `--value`) turned into information elements.

use anyhow::{bail, Context};
use iec60870::asdu::{
    BinaryCounterReading, CommandQualifier, DoublePointState, Element, Quality,
    RegulatingStepState, SetpointQualifier, StepPosition, TypeId,
};

fn parse_bool(text: &str) -> anyhow::Result<bool> {
    match text.trim().to_ascii_lowercase().as_str() {
        "1" | "on" | "true" => Ok(true),
        "0" | "off" | "false" | "" => Ok(false),
        other => bail!("'{other}' is not 0/1, ON/OFF or TRUE/FALSE"),
    }
}

fn parse_double(text: &str) -> anyhow::Result<DoublePointState> {
    Ok(match text.trim().to_ascii_lowercase().as_str() {
        "0" | "intermediate" => DoublePointState::Intermediate,
        "1" | "off" | "open" | "" => DoublePointState::Off,
        "2" | "on" | "closed" | "close" => DoublePointState::On,
        "3" | "indeterminate" => DoublePointState::Indeterminate,
        other => bail!("'{other}' is not a double-point state (OFF/ON or 0..3)"),
    })
}

fn parse_u32(text: &str) -> anyhow::Result<u32> {
    let text = text.trim();
    let parsed = match text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        Some(hex) => u32::from_str_radix(hex, 16),
        None if text.is_empty() => Ok(0),
        None => text.parse(),
    };
    parsed.with_context(|| format!("'{text}' is not a 32-bit number"))
}

fn parse_number<T: std::str::FromStr + Default>(text: &str, what: &str) -> anyhow::Result<T> {
    let text = text.trim();
    if text.is_empty() {
        return Ok(T::default());
    }
    text.parse()
        .map_err(|_| anyhow::anyhow!("'{text}' is not a valid {what}"))
}

/// A normalized value: a fraction with a decimal point (`0.335114`) or a raw integer
/// (`10981`), as gateways that put engineering integers in the field do (spec IEC-A4).
fn parse_normalized(text: &str) -> anyhow::Result<i16> {
    let text = text.trim();
    if text.contains('.') || text.contains('e') {
        let fraction: f64 = parse_number(text, "normalized value")?;
        if !(-1.0..1.0).contains(&fraction) {
            bail!("normalized fraction {fraction} is outside -1 .. 1");
        }
        Ok((fraction * 32768.0).round().clamp(-32768.0, 32767.0) as i16)
    } else {
        parse_number(text, "normalized raw value (-32768..32767)")
    }
}

/// The initial value of a monitor point of the given type.
pub(crate) fn parse_element(type_id: TypeId, text: &str) -> anyhow::Result<Element> {
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
                    .map_err(|error| anyhow::anyhow!("{error}"))?,
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
                .map_err(|error| anyhow::anyhow!("{error}"))?,
        ),
        TypeId::M_PS_NA_1 => {
            let bits = parse_u32(text)?;
            Element::PackedSinglePoints {
                status: (bits & 0xFFFF) as u16,
                change: (bits >> 16) as u16,
                quality,
            }
        }
        other => bail!("{other} points cannot be given in a point file"),
    })
}

/// A command element of the given type.
pub(crate) fn parse_command(
    type_id: TypeId,
    text: &str,
    select: bool,
    qualifier: u8,
) -> anyhow::Result<Element> {
    let command_qualifier = || {
        CommandQualifier::new(qualifier, select)
            .map_err(|error| anyhow::anyhow!("--qualifier: {error}"))
    };
    let setpoint_qualifier = || {
        SetpointQualifier::new(qualifier, select)
            .map_err(|error| anyhow::anyhow!("--qualifier: {error}"))
    };
    Ok(match type_id {
        TypeId::C_SC_NA_1 | TypeId::C_SC_TA_1 => Element::SingleCommand {
            on: parse_bool(text)?,
            qualifier: command_qualifier()?,
        },
        TypeId::C_DC_NA_1 | TypeId::C_DC_TA_1 => {
            let state = parse_double(text)?;
            if !matches!(state, DoublePointState::On | DoublePointState::Off) {
                bail!("a double command is OFF (1) or ON (2)");
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
        assert!(parse_command(TypeId::C_DC_NA_1, "0", false, 0).is_err());
        assert!(parse_command(TypeId::C_SC_NA_1, "1", true, 32).is_err());
        assert!(parse_command(TypeId::M_SP_NA_1, "1", false, 0).is_err());
        assert!(parse_command(TypeId::C_SE_NC_1, "nan", false, 0).is_err());
    }
}
