//! How far a value can be trusted, and when its source says it happened.

use std::fmt;

use chrono::{DateTime, Utc};

/// Quality descriptor: IV, NT, SB, BL (every point) and OV (measured values and totals).
///
/// These are the flags of IEC 60870-5-101 §7.2.6.3; the protocol crate writes them into
/// its SIQ, DIQ and QDS octets (single and double points have no OV bit there: `overflow`
/// is not sent with them and decodes as `false`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Quality {
    /// IV: the value is invalid (e.g. the source failed).
    pub invalid: bool,
    /// NT: not topical, the value was not updated successfully at the last refresh.
    pub not_topical: bool,
    /// SB: substituted by an operator or an automatic source.
    pub substituted: bool,
    /// BL: blocked for transmission.
    pub blocked: bool,
    /// OV: overflow, the value is beyond its predefined range.
    pub overflow: bool,
}

impl Quality {
    /// All flags clear.
    pub const GOOD: Quality = Quality {
        invalid: false,
        not_topical: false,
        substituted: false,
        blocked: false,
        overflow: false,
    };

    /// Only IV set, as used for bulk invalidation when a source fails.
    pub const INVALID: Quality = Quality {
        invalid: true,
        not_topical: false,
        substituted: false,
        blocked: false,
        overflow: false,
    };

    /// Whether no flag is set.
    pub fn is_good(&self) -> bool {
        *self == Self::GOOD
    }

    /// The names of the flags that are set, in the standard's order (`IV NT SB BL OV`):
    /// how every tool and screen of the project lists a quality.
    pub fn set_flags(&self) -> Vec<&'static str> {
        [
            (self.invalid, "IV"),
            (self.not_topical, "NT"),
            (self.substituted, "SB"),
            (self.blocked, "BL"),
            (self.overflow, "OV"),
        ]
        .into_iter()
        .filter_map(|(set, name)| set.then_some(name))
        .collect()
    }

    /// Writes `[iv nt sb bl]` or, with `with_overflow`, `[iv nt sb bl ov]`: lower case
    /// clear, upper case set, as protocol test tools print a quality.
    pub fn write_flags(&self, f: &mut fmt::Formatter<'_>, with_overflow: bool) -> fmt::Result {
        f.write_str("[")?;
        write_flag(f, self.invalid, "iv")?;
        f.write_str(" ")?;
        write_flag(f, self.not_topical, "nt")?;
        f.write_str(" ")?;
        write_flag(f, self.substituted, "sb")?;
        f.write_str(" ")?;
        write_flag(f, self.blocked, "bl")?;
        if with_overflow {
            f.write_str(" ")?;
            write_flag(f, self.overflow, "ov")?;
        }
        f.write_str("]")
    }
}

/// Writes `name` in upper case when set, in lower case when clear.
fn write_flag(f: &mut fmt::Formatter<'_>, set: bool, name: &str) -> fmt::Result {
    if set {
        f.write_str(&name.to_ascii_uppercase())
    } else {
        f.write_str(name)
    }
}

impl fmt::Display for Quality {
    /// `[iv nt sb bl ov]`: lower case clear, upper case set.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.write_flags(f, true)
    }
}

/// The instant a source stamped a value with, and whether the stamp itself is invalid
/// (the source's clock was not synchronised or failed, or its local time could not
/// exist): an IEC time tag read under the link's zone policy, a device's own clock.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SourceTime {
    /// The time, UTC.
    pub time: DateTime<Utc>,
    /// The stamp's IV bit.
    pub invalid: bool,
}

impl SourceTime {
    /// A valid stamp at `time` (the station itself detected the change).
    pub fn at(time: DateTime<Utc>) -> SourceTime {
        SourceTime {
            time,
            invalid: false,
        }
    }
}
