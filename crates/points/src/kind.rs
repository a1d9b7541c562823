//! The kind of value a point holds, the time stamp it is sent with, and the range and
//! precision each kind allows.
//!
//! The kinds are the value families of IEC 60870-5 monitor information (the protocol the
//! station reports upward in), so a value the database accepts is always one the node can
//! send: it is checked against its kind's range and quantized to the kind's wire
//! precision on entry (a normalized value to 2⁻¹⁵, a short float to `f32`), and
//! "unchanged" means "unchanged on the wire". Which protocol type a (kind, stamp) pair is
//! sent as is the protocol adapter's business.

use std::fmt;

use crate::PointValue;

/// The value family of a point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PointKind {
    /// Single-point information: on or off.
    Single,
    /// Double-point information: 0 intermediate, 1 off, 2 on, 3 indeterminate.
    Double,
    /// Step position (a tap changer): -64..=63.
    Step,
    /// A bitstring of 32 bits.
    Bitstring,
    /// A normalized measured value: -1..=1 in steps of 2⁻¹⁵.
    Normalized,
    /// A scaled measured value: a 16-bit signed integer.
    Scaled,
    /// A short floating-point measured value (`f32`).
    Float,
    /// An integrated total (a counter): a 32-bit signed integer.
    Total,
}

impl PointKind {
    /// Whether the kind is a measured value (a deadband applies).
    pub fn is_measurement(self) -> bool {
        matches!(
            self,
            PointKind::Normalized | PointKind::Scaled | PointKind::Float
        )
    }

    /// Whether the kind's values are numbers (a storage deadband or rate limit applies):
    /// measurements, step positions and integrated totals.
    pub fn is_numeric(self) -> bool {
        self.is_measurement() || matches!(self, PointKind::Step | PointKind::Total)
    }

    /// The value a point holds before its first update: the kind's zero.
    pub fn initial(self) -> PointValue {
        match self {
            PointKind::Single => PointValue::Bool(false),
            PointKind::Double => PointValue::DoublePoint(0),
            PointKind::Step | PointKind::Scaled | PointKind::Total => PointValue::Int(0),
            PointKind::Normalized | PointKind::Float => PointValue::Float(0.0),
            PointKind::Bitstring => PointValue::Bits(0),
        }
    }

    /// Checks a value against the kind's range and quantizes it to the kind's wire
    /// precision; the reason when it does not fit.
    pub fn check(self, value: PointValue) -> Result<PointValue, &'static str> {
        match (self, value) {
            (PointKind::Single, v @ PointValue::Bool(_)) => Ok(v),
            (PointKind::Double, PointValue::DoublePoint(d)) if d <= 3 => {
                Ok(PointValue::DoublePoint(d))
            }
            (PointKind::Double, PointValue::DoublePoint(_)) => {
                Err("double point state must be 0..=3")
            }
            (PointKind::Step, PointValue::Int(i)) if (-64..=63).contains(&i) => {
                Ok(PointValue::Int(i))
            }
            (PointKind::Step, PointValue::Int(_)) => Err("step position must be -64..=63"),
            (PointKind::Scaled, PointValue::Int(i)) if i16::try_from(i).is_ok() => {
                Ok(PointValue::Int(i))
            }
            (PointKind::Scaled, PointValue::Int(_)) => Err("scaled value must be -32768..=32767"),
            (PointKind::Total, PointValue::Int(i)) if i32::try_from(i).is_ok() => {
                Ok(PointValue::Int(i))
            }
            (PointKind::Total, PointValue::Int(_)) => {
                Err("integrated total must fit 32 bits signed")
            }
            (PointKind::Bitstring, v @ PointValue::Bits(_)) => Ok(v),
            (PointKind::Normalized, PointValue::Float(x)) if (-1.0..=1.0).contains(&x) => Ok(
                PointValue::Float(normalized::from_raw(normalized::to_raw(x))),
            ),
            (PointKind::Normalized, PointValue::Float(_)) => Err("normalized value must be -1..=1"),
            (PointKind::Float, PointValue::Float(x))
                if x.is_finite() && x.abs() <= f64::from(f32::MAX) =>
            {
                // In range: the cast rounds to the nearest f32.
                #[allow(clippy::cast_possible_truncation)]
                let single = x as f32;
                Ok(PointValue::Float(f64::from(single)))
            }
            (PointKind::Float, PointValue::Float(_)) => {
                Err("short float must be finite and within the f32 range")
            }
            _ => Err("wrong value kind for the type"),
        }
    }

    /// What the kind is called in messages.
    pub fn name(self) -> &'static str {
        match self {
            PointKind::Single => "single point",
            PointKind::Double => "double point",
            PointKind::Step => "step position",
            PointKind::Bitstring => "bitstring",
            PointKind::Normalized => "normalized value",
            PointKind::Scaled => "scaled value",
            PointKind::Float => "short float",
            PointKind::Total => "integrated total",
        }
    }
}

impl fmt::Display for PointKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The time stamp a point's changes are sent with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TimeStamp {
    /// None: the receiver stamps the time it received the value.
    None,
    /// Minutes, seconds and milliseconds only (CP24Time2a in IEC 60870-5).
    Short,
    /// The full date and time (CP56Time2a).
    Full,
}

/// How a point is declared: its value family, the stamp its changes carry and whether
/// its quality is sent (only a normalized value may go without: IEC's M_ME_ND_1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct PointType {
    /// The value family.
    pub kind: PointKind,
    /// The time stamp sent with each change.
    pub stamp: TimeStamp,
    /// Whether the quality descriptor is sent.
    pub with_quality: bool,
}

impl PointType {
    /// A type of `kind` sent with `stamp` and its quality.
    pub const fn new(kind: PointKind, stamp: TimeStamp) -> PointType {
        PointType {
            kind,
            stamp,
            with_quality: true,
        }
    }
}

impl fmt::Display for PointType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.kind.name())?;
        match self.stamp {
            TimeStamp::None => {}
            TimeStamp::Short => f.write_str(" with short time stamp")?,
            TimeStamp::Full => f.write_str(" with time stamp")?,
        }
        if !self.with_quality {
            f.write_str(" without quality")?;
        }
        Ok(())
    }
}

/// The normalized value's scale: a fraction of full scale in 2⁻¹⁵ steps, the one place
/// the station converts between the fraction and the 16-bit raw value (IEC 60870-5-101
/// §7.2.6.6: `raw / 32768`, with `+1.0` saturating to `32767`).
pub mod normalized {
    /// Full scale of the raw value.
    const FULL_SCALE: f64 = 32768.0;

    /// `round(x * 32768)` clamped to the i16 range (NaN gives 0).
    pub fn to_raw(x: f64) -> i16 {
        let scaled = (x * FULL_SCALE).round();
        if scaled.is_nan() {
            return 0;
        }
        // The clamp makes the cast exact.
        #[allow(clippy::cast_possible_truncation)]
        let raw = scaled.clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16;
        raw
    }

    /// The fraction of full scale a raw value stands for.
    pub fn from_raw(raw: i16) -> f64 {
        f64::from(raw) / FULL_SCALE
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn normalized_full_scale_saturates_and_quantizes() {
        assert_eq!(normalized::to_raw(1.0), 32767);
        assert_eq!(normalized::to_raw(-1.0), -32768);
        assert_eq!(normalized::to_raw(f64::NAN), 0);
        assert_eq!(normalized::from_raw(-32768), -1.0);
        assert_eq!(
            PointKind::Normalized.check(PointValue::Float(0.5)),
            Ok(PointValue::Float(0.5))
        );
        assert!(PointKind::Normalized.check(PointValue::Float(1.5)).is_err());
    }

    proptest! {
        /// A checked value checks to itself: quantizing is idempotent, so a value read
        /// back from the wire is "unchanged".
        #[test]
        fn check_is_idempotent(x in -1.0f64..=1.0, f in -1e30f64..1e30, i in -64i64..=63) {
            for (kind, value) in [
                (PointKind::Normalized, PointValue::Float(x)),
                (PointKind::Float, PointValue::Float(f)),
                (PointKind::Step, PointValue::Int(i)),
                (PointKind::Scaled, PointValue::Int(i * 500)),
            ] {
                let once = kind.check(value).expect("in range");
                prop_assert_eq!(kind.check(once.clone()), Ok(once));
            }
        }
    }
}
