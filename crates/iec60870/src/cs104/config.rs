//! APCI parameters of an IEC 104 connection: k, w and the timers t0-t3.

use std::fmt;
use std::time::Duration;

/// APCI parameters (IEC 60870-5-104 clause 9.6), one set per connection.
///
/// Defaults are the standard's: k = 12, w = 8, t0 = 30 s, t1 = 15 s, t2 = 10 s,
/// t3 = 20 s. Check a configuration with [`ApciConfig::validate`] and
/// [`ApciConfig::warnings`] before use; [`crate::cs104::Session::new`] clamps values it
/// cannot work with instead of failing.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub struct ApciConfig {
    /// Maximum number of sent I frames not yet acknowledged (1..=32767). At k the sender
    /// stops until an acknowledgement arrives.
    pub k: u16,
    /// Acknowledge received I frames at the latest after w of them (1..=k). The standard
    /// recommends w <= 2/3 k.
    pub w: u16,
    /// t0: time-out of connection establishment. Used by the TCP connect code, not by
    /// the session.
    pub t0: Duration,
    /// t1: time-out for the acknowledgement of a sent I frame, and for the confirmation
    /// of a sent STARTDT, STOPDT or TESTFR act. Expiry closes the connection.
    pub t1: Duration,
    /// t2: time-out after which received I frames are acknowledged with an S frame when
    /// no data is sent that would carry the acknowledgement. Must be below t1.
    pub t2: Duration,
    /// t3: idle time (nothing received) after which a TESTFR act is sent.
    pub t3: Duration,
    /// How many well-formed but unexpected U frames (a function of the other role, or a
    /// confirmation nobody asked for) are ignored before the connection is closed.
    /// 0 closes on the first one. Malformed frames always close at once.
    pub max_unexpected_frames: u32,
}

impl Default for ApciConfig {
    fn default() -> Self {
        ApciConfig {
            k: 12,
            w: 8,
            t0: Duration::from_secs(30),
            t1: Duration::from_secs(15),
            t2: Duration::from_secs(10),
            t3: Duration::from_secs(20),
            max_unexpected_frames: 8,
        }
    }
}

/// The largest k: sequence numbers count modulo 32768, so at most 32767 frames can be
/// outstanding without ambiguity.
pub const MAX_K: u16 = 32767;

/// An invalid [`ApciConfig`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ConfigError {
    /// k is 0 or above 32767.
    #[error("k = {0} is out of range 1..=32767")]
    KOutOfRange(u16),
    /// w is 0 or above k.
    #[error("w = {w} is out of range 1..=k (k = {k})")]
    WOutOfRange {
        /// The configured w.
        w: u16,
        /// The configured k.
        k: u16,
    },
    /// A timer is zero.
    #[error("timer {0} must not be zero")]
    ZeroTimer(Timer),
    /// t2 is not below t1: the peer would time out before we acknowledge.
    #[error("t2 ({t2:?}) must be below t1 ({t1:?})")]
    T2NotBelowT1 {
        /// The configured t1.
        t1: Duration,
        /// The configured t2.
        t2: Duration,
    },
}

/// A questionable but workable [`ApciConfig`] value.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum ConfigWarning {
    /// w is above the recommended 2/3 k: the peer stalls at a full window more often
    /// while waiting for our acknowledgement.
    WAboveTwoThirdsK {
        /// The configured w.
        w: u16,
        /// The configured k.
        k: u16,
    },
}

impl fmt::Display for ConfigWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ConfigWarning::WAboveTwoThirdsK { w, k } => {
                write!(f, "w = {w} is above the recommended 2/3 of k = {k}")
            }
        }
    }
}

/// The four APCI timers, for messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Timer {
    /// Connection establishment.
    T0,
    /// Acknowledgement of sent frames.
    T1,
    /// Acknowledgement of received frames.
    T2,
    /// Idle test.
    T3,
}

impl fmt::Display for Timer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Timer::T0 => "t0",
            Timer::T1 => "t1",
            Timer::T2 => "t2",
            Timer::T3 => "t3",
        })
    }
}

impl ApciConfig {
    /// Checks the hard rules: k in 1..=32767, w in 1..=k, no zero timer, t2 < t1.
    ///
    /// Recommendations that do not prevent operation are in [`ApciConfig::warnings`].
    pub fn validate(&self) -> Result<(), ConfigError> {
        if self.k == 0 || self.k > MAX_K {
            return Err(ConfigError::KOutOfRange(self.k));
        }
        if self.w == 0 || self.w > self.k {
            return Err(ConfigError::WOutOfRange {
                w: self.w,
                k: self.k,
            });
        }
        for (timer, value) in [
            (Timer::T0, self.t0),
            (Timer::T1, self.t1),
            (Timer::T2, self.t2),
            (Timer::T3, self.t3),
        ] {
            if value.is_zero() {
                return Err(ConfigError::ZeroTimer(timer));
            }
        }
        if self.t2 >= self.t1 {
            return Err(ConfigError::T2NotBelowT1 {
                t1: self.t1,
                t2: self.t2,
            });
        }
        Ok(())
    }

    /// Recommendations this configuration does not follow (empty when all is well).
    pub fn warnings(&self) -> Vec<ConfigWarning> {
        let mut warnings = Vec::new();
        // w <= 2/3 k  <=>  3w <= 2k
        if u32::from(self.w) * 3 > u32::from(self.k) * 2 {
            warnings.push(ConfigWarning::WAboveTwoThirdsK {
                w: self.w,
                k: self.k,
            });
        }
        warnings
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_standard_values_and_valid() {
        let c = ApciConfig::default();
        assert_eq!((c.k, c.w), (12, 8));
        assert_eq!(c.t0, Duration::from_secs(30));
        assert_eq!(c.t1, Duration::from_secs(15));
        assert_eq!(c.t2, Duration::from_secs(10));
        assert_eq!(c.t3, Duration::from_secs(20));
        assert_eq!(c.validate(), Ok(()));
        assert!(c.warnings().is_empty());
    }

    #[test]
    fn hard_rules() {
        let ok = ApciConfig::default();
        let with = |f: fn(&mut ApciConfig)| {
            let mut c = ok.clone();
            f(&mut c);
            c.validate()
        };
        assert_eq!(with(|c| c.k = 0), Err(ConfigError::KOutOfRange(0)));
        assert_eq!(with(|c| c.k = 32768), Err(ConfigError::KOutOfRange(32768)));
        assert_eq!(
            with(|c| {
                c.k = 32767;
                c.w = 100;
            }),
            Ok(())
        );
        assert_eq!(
            with(|c| c.w = 0),
            Err(ConfigError::WOutOfRange { w: 0, k: 12 })
        );
        assert_eq!(
            with(|c| c.w = 13),
            Err(ConfigError::WOutOfRange { w: 13, k: 12 })
        );
        assert_eq!(
            with(|c| c.t3 = Duration::ZERO),
            Err(ConfigError::ZeroTimer(Timer::T3))
        );
        assert_eq!(
            with(|c| c.t2 = c.t1),
            Err(ConfigError::T2NotBelowT1 {
                t1: Duration::from_secs(15),
                t2: Duration::from_secs(15)
            })
        );
    }

    #[test]
    fn w_above_two_thirds_k_is_only_a_warning() {
        let c = ApciConfig {
            w: 9,
            ..ApciConfig::default()
        };
        assert_eq!(c.validate(), Ok(()));
        assert_eq!(
            c.warnings(),
            vec![ConfigWarning::WAboveTwoThirdsK { w: 9, k: 12 }]
        );
        assert!(c.warnings()[0].to_string().contains("2/3"));
    }
}
