//! Information elements to point values and back, and point addresses to IOAs.

use iec60870::asdu::{
    BinaryCounterReading, DoublePointState, Element, Ioa, RangeError, RegulatingStepState,
    StepPosition, TimeTag, TypeId,
};
use iec60870::time::TimeZonePolicy;
use points::{normalized, PointKind, PointType, PointValue, Quality, SourceTime};

use crate::types::point_type;

/// An element that does not fit the type it came with, or a type no point has.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("element {element} does not fit type {type_id}")]
pub struct ElementMismatch {
    /// The type.
    pub type_id: TypeId,
    /// The element's short name.
    pub element: &'static str,
}

/// The IOA of a point's address (addresses over 24 bits are refused when a project is
/// loaded; here they are a range error).
pub fn ioa(address: u32) -> Result<Ioa, RangeError> {
    Ioa::try_new(address)
}

/// The information element of a value (and its quality) for a point of `point_type`.
/// Step positions are sent not transient; integrated totals with sequence number 0, IV
/// from the quality's IV and CY from its OV. A value that does not fit the type gives the
/// type's zero with IV set rather than a panic.
pub fn to_element(point_type: PointType, value: &PointValue, quality: Quality) -> Element {
    let kind = point_type.kind;
    let (value, quality) = match kind.check(value.clone()) {
        Ok(v) => (v, quality),
        Err(_) => (
            kind.initial(),
            Quality {
                invalid: true,
                ..quality
            },
        ),
    };
    let q = quality;
    // SIQ and DIQ have no OV bit.
    let sp_quality = Quality {
        overflow: false,
        ..q
    };
    let invalid = || Element::SinglePoint {
        on: false,
        quality: Quality::INVALID,
    };
    match (kind, value) {
        (PointKind::Single, PointValue::Bool(on)) => Element::SinglePoint {
            on,
            quality: sp_quality,
        },
        (PointKind::Double, PointValue::DoublePoint(d)) => Element::DoublePoint {
            state: DoublePointState::from_bits(d),
            quality: sp_quality,
        },
        (PointKind::Step, PointValue::Int(i)) => Element::StepPosition {
            position: i8::try_from(i)
                .ok()
                .and_then(|v| StepPosition::new(v, false).ok())
                .unwrap_or_default(),
            quality: q,
        },
        (PointKind::Bitstring, PointValue::Bits(bits)) => Element::Bitstring { bits, quality: q },
        (PointKind::Normalized, PointValue::Float(x)) => Element::Normalized {
            raw: normalized::to_raw(x),
            quality: q,
        },
        (PointKind::Scaled, PointValue::Int(i)) => Element::Scaled {
            value: i16::try_from(i).unwrap_or_default(),
            quality: q,
        },
        (PointKind::Float, PointValue::Float(x)) => {
            // Checked to be within the f32 range.
            #[allow(clippy::cast_possible_truncation)]
            let value = x as f32;
            Element::Float { value, quality: q }
        }
        (PointKind::Total, PointValue::Int(i)) => {
            BinaryCounterReading::new(i32::try_from(i).unwrap_or_default(), 0)
                .map(|r| r.with_invalid(quality.invalid).with_carry(quality.overflow))
                .map_or_else(|_| invalid(), Element::IntegratedTotal)
        }
        // Unreachable after `check`; kept total.
        _ => invalid(),
    }
}

/// Decodes a monitor element received with `type_id` into a point value, its quality and
/// source time. The CP56Time2a is read in `zone`; a CP24Time2a cannot be placed without a
/// reference and gives no source time. Step positions lose their transient bit;
/// integrated totals map IV to IV and CY to OV.
pub fn from_element(
    type_id: TypeId,
    element: &Element,
    time: Option<&TimeTag>,
    zone: TimeZonePolicy,
) -> Result<(PointValue, Quality, Option<SourceTime>), ElementMismatch> {
    let mismatch = || ElementMismatch {
        type_id,
        element: element.short_name(),
    };
    let kind = point_type(type_id).ok_or_else(mismatch)?.kind;
    if !element.family_matches(type_id) {
        return Err(mismatch());
    }
    let (value, quality) = match (kind, element) {
        (PointKind::Single, Element::SinglePoint { on, quality }) => {
            (PointValue::Bool(*on), *quality)
        }
        (PointKind::Double, Element::DoublePoint { state, quality }) => {
            (PointValue::DoublePoint(state.bits()), *quality)
        }
        (PointKind::Step, Element::StepPosition { position, quality }) => {
            (PointValue::Int(i64::from(position.value())), *quality)
        }
        (PointKind::Bitstring, Element::Bitstring { bits, quality }) => {
            (PointValue::Bits(*bits), *quality)
        }
        (PointKind::Normalized, Element::Normalized { raw, quality }) => {
            (PointValue::Float(normalized::from_raw(*raw)), *quality)
        }
        (PointKind::Scaled, Element::Scaled { value, quality }) => {
            (PointValue::Int(i64::from(*value)), *quality)
        }
        (PointKind::Float, Element::Float { value, quality }) => {
            (PointValue::Float(f64::from(*value)), *quality)
        }
        (PointKind::Total, Element::IntegratedTotal(r)) => (
            PointValue::Int(i64::from(r.value())),
            Quality {
                invalid: r.is_invalid(),
                overflow: r.is_carry(),
                ..Quality::GOOD
            },
        ),
        _ => return Err(mismatch()),
    };
    let source_time = time
        .and_then(TimeTag::as_cp56)
        .and_then(|tag| zone.from_cp56(tag));
    Ok((value, quality, source_time))
}

/// The value of a command element, and the qualifier of its output (QU of SCO, DCO and
/// RCO: 0 the target's own, 1 short pulse, 2 long pulse, 3 persistent): ON/OFF as a
/// single or double point, a regulating step as +1 (higher) or -1 (lower), set-points as
/// their value (a normalized one as its fraction), a bitstring as its bits. `None` for an
/// element that carries no value to write (a not-permitted double or step state, a
/// monitor or system element).
pub fn command_value(element: &Element) -> Option<(PointValue, Option<u8>)> {
    Some(match element {
        Element::SingleCommand { on, qualifier } => {
            (PointValue::Bool(*on), Some(qualifier.qualifier()))
        }
        Element::DoubleCommand { state, qualifier } => match state {
            DoublePointState::On | DoublePointState::Off => (
                PointValue::DoublePoint(state.bits()),
                Some(qualifier.qualifier()),
            ),
            _ => return None,
        },
        Element::RegulatingStep { state, qualifier } => match state {
            RegulatingStepState::Higher => (PointValue::Int(1), Some(qualifier.qualifier())),
            RegulatingStepState::Lower => (PointValue::Int(-1), Some(qualifier.qualifier())),
            _ => return None,
        },
        Element::SetpointNormalized { raw, .. } => {
            (PointValue::Float(normalized::from_raw(*raw)), None)
        }
        Element::SetpointScaled { value, .. } => (PointValue::Int(i64::from(*value)), None),
        Element::SetpointFloat { value, .. } => (PointValue::Float(f64::from(*value)), None),
        Element::BitstringCommand { bits } => (PointValue::Bits(*bits), None),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use iec60870::asdu::{CommandQualifier, SetpointQualifier};

    #[test]
    fn command_elements_carry_their_value_and_output_qualifier() {
        let long = CommandQualifier::new(CommandQualifier::QU_LONG_PULSE, false).unwrap();
        let cases = [
            (
                Element::SingleCommand {
                    on: true,
                    qualifier: long,
                },
                Some((PointValue::Bool(true), Some(2))),
            ),
            (
                Element::DoubleCommand {
                    state: DoublePointState::Off,
                    qualifier: CommandQualifier::EXECUTE,
                },
                Some((PointValue::DoublePoint(1), Some(0))),
            ),
            (
                Element::DoubleCommand {
                    state: DoublePointState::Indeterminate,
                    qualifier: CommandQualifier::EXECUTE,
                },
                None,
            ),
            (
                Element::RegulatingStep {
                    state: RegulatingStepState::Lower,
                    qualifier: CommandQualifier::EXECUTE,
                },
                Some((PointValue::Int(-1), Some(0))),
            ),
            (
                Element::SetpointNormalized {
                    raw: -16384,
                    qualifier: SetpointQualifier::new(0, false).unwrap(),
                },
                Some((PointValue::Float(-0.5), None)),
            ),
            (
                Element::BitstringCommand { bits: 0xA5 },
                Some((PointValue::Bits(0xA5), None)),
            ),
            (
                Element::SinglePoint {
                    on: true,
                    quality: Quality::GOOD,
                },
                None,
            ),
        ];
        for (element, expected) in cases {
            assert_eq!(command_value(&element), expected, "{element:?}");
        }
    }
}
