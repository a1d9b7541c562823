//! The character format and speed of a serial line, the times they imply, and what a port
//! may refuse of them.

use std::fmt;
use std::str::FromStr;
use std::time::Duration;

use thiserror::Error;

/// Parity of a character.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Parity {
    /// Even parity: FT1.2's format.
    Even,
    /// Odd parity.
    Odd,
    /// No parity bit (not FT1.2, but met on terminal servers, converters and
    /// pseudo-terminals).
    None,
}

/// A parity name other than even, odd or none (or e, o, n).
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("parity {0:?}: expected even, odd or none")]
pub struct ParityError(pub String);

impl FromStr for Parity {
    type Err = ParityError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        match text.to_ascii_lowercase().as_str() {
            "even" | "e" => Ok(Parity::Even),
            "odd" | "o" => Ok(Parity::Odd),
            "none" | "n" => Ok(Parity::None),
            _ => Err(ParityError(text.to_owned())),
        }
    }
}

impl fmt::Display for Parity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Parity::Even => "even",
            Parity::Odd => "odd",
            Parity::None => "none",
        })
    }
}

/// Line settings no line takes.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum SettingsError {
    /// A speed outside [`LineSettings::MIN_BAUD`]..=[`LineSettings::MAX_BAUD`].
    #[error(
        "baud rate {0} outside {min}..={max}",
        min = LineSettings::MIN_BAUD,
        max = LineSettings::MAX_BAUD
    )]
    Baud(u32),
    /// Stop bits other than 1 or 2.
    #[error("{0} stop bits: expected 1 or 2")]
    StopBits(u8),
}

/// The serial settings of a line: 8 data bits, a parity and 1 or 2 stop bits at a speed.
/// FT1.2 and the EKM66 board send 8E1 (11 bits a character); stop bits are configurable,
/// as some devices want two.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct LineSettings {
    /// Bits per second, 1200 to 115200.
    pub baud: u32,
    /// Parity.
    pub parity: Parity,
    /// Stop bits, 1 or 2.
    pub stop_bits: u8,
}

impl Default for LineSettings {
    fn default() -> Self {
        LineSettings::new(9600)
    }
}

impl LineSettings {
    /// The slowest speed accepted.
    pub const MIN_BAUD: u32 = 1200;
    /// The fastest speed accepted.
    pub const MAX_BAUD: u32 = 115_200;
    /// Data bits of every character.
    pub const DATA_BITS: u8 = 8;
    /// The line idle time required between frames and after a frame error, in bit times
    /// (FT1.2's 33; devices framed like FT1.2 keep it).
    pub const IDLE_BITS: u32 = 33;
    /// How far a port's reported speed may be from the asked one and still count as
    /// kept, in per mille. A driver reports the rate its divisor reaches (Linux's
    /// `tty_encode_baud_rate`), a fraction of a percent off for some speeds on some
    /// adapters; the two ends of an asynchronous line still understand each other
    /// within some 2 %.
    pub const BAUD_TOLERANCE_PER_MILLE: u32 = 20;

    /// 8E1 at `baud`.
    pub fn new(baud: u32) -> LineSettings {
        LineSettings {
            baud,
            parity: Parity::Even,
            stop_bits: 1,
        }
    }

    /// Checks speed and stop bits.
    pub fn validate(&self) -> Result<(), SettingsError> {
        if !(Self::MIN_BAUD..=Self::MAX_BAUD).contains(&self.baud) {
            return Err(SettingsError::Baud(self.baud));
        }
        if !(1..=2).contains(&self.stop_bits) {
            return Err(SettingsError::StopBits(self.stop_bits));
        }
        Ok(())
    }

    /// Bits on the line for one octet: start, 8 data, parity, stop.
    pub fn bits_per_character(&self) -> u32 {
        1 + u32::from(Self::DATA_BITS)
            + u32::from(self.parity != Parity::None)
            + u32::from(self.stop_bits)
    }

    /// The time of `bits` bit times.
    pub fn bit_times(&self, bits: u64) -> Duration {
        let baud = u64::from(self.baud.max(1));
        Duration::from_nanos(bits.saturating_mul(1_000_000_000) / baud)
    }

    /// The time `octets` take on the line.
    pub fn transmit_time(&self, octets: usize) -> Duration {
        let octets = u64::try_from(octets).unwrap_or(u64::MAX);
        self.bit_times(octets.saturating_mul(u64::from(self.bits_per_character())))
    }

    /// The idle time between frames and after an error: 33 bit times.
    pub fn idle_time(&self) -> Duration {
        self.bit_times(u64::from(Self::IDLE_BITS))
    }

    /// The first of these settings a port did not keep: `kept` is what the port reports
    /// after they were applied, `kept_data_bits` its data bits. Speed within
    /// [`LineSettings::BAUD_TOLERANCE_PER_MILLE`] counts as kept.
    pub fn refused_by(&self, kept: &LineSettings, kept_data_bits: u8) -> Option<Refused> {
        let refused = |setting, asked: &dyn fmt::Display, kept: &dyn fmt::Display| {
            Some(Refused {
                setting,
                asked: asked.to_string(),
                kept: kept.to_string(),
            })
        };
        let off = u64::from(self.baud.abs_diff(kept.baud)) * 1000;
        if off > u64::from(self.baud) * u64::from(Self::BAUD_TOLERANCE_PER_MILLE) {
            return refused(Setting::Baud, &self.baud, &kept.baud);
        }
        if self.parity != kept.parity {
            return refused(Setting::Parity, &self.parity, &kept.parity);
        }
        if self.stop_bits != kept.stop_bits {
            return refused(Setting::StopBits, &self.stop_bits, &kept.stop_bits);
        }
        if kept_data_bits != Self::DATA_BITS {
            return refused(Setting::DataBits, &Self::DATA_BITS, &kept_data_bits);
        }
        None
    }
}

impl fmt::Display for LineSettings {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let parity = match self.parity {
            Parity::Even => 'E',
            Parity::Odd => 'O',
            Parity::None => 'N',
        };
        write!(
            f,
            "{} Bd {}{}{}",
            self.baud,
            Self::DATA_BITS,
            parity,
            self.stop_bits
        )
    }
}

/// One setting of a serial port.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Setting {
    /// The speed.
    Baud,
    /// The parity.
    Parity,
    /// The stop bits.
    StopBits,
    /// The data bits.
    DataBits,
}

impl fmt::Display for Setting {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Setting::Baud => "baud rate",
            Setting::Parity => "parity",
            Setting::StopBits => "stop bits",
            Setting::DataBits => "data bits",
        })
    }
}

/// A setting a port took without a word but kept at another value (a pseudo-terminal
/// keeps no parity; a driver may not do two stop bits or a speed).
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("the port refused {setting} {asked} (it kept {kept})")]
pub struct Refused {
    /// Which setting.
    pub setting: Setting,
    /// The value asked for.
    pub asked: String,
    /// The value the port kept.
    pub kept: String,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ft12_character_times() {
        let line = LineSettings::new(9600);
        assert_eq!(line.bits_per_character(), 11);
        // 9600 / 11 = 872.7 octets a second ("about 870").
        assert_eq!(line.transmit_time(1), Duration::from_nanos(1_145_833));
        assert_eq!(line.idle_time(), Duration::from_nanos(3_437_500));
        assert_eq!(line.to_string(), "9600 Bd 8E1");
        assert_eq!(
            LineSettings::new(600).validate(),
            Err(SettingsError::Baud(600))
        );
        assert_eq!(
            SettingsError::Baud(600).to_string(),
            "baud rate 600 outside 1200..=115200"
        );
        assert_eq!(
            LineSettings {
                stop_bits: 3,
                ..LineSettings::new(9600)
            }
            .validate(),
            Err(SettingsError::StopBits(3))
        );
    }

    #[test]
    fn parity_names() {
        assert_eq!("even".parse::<Parity>(), Ok(Parity::Even));
        assert_eq!("N".parse::<Parity>(), Ok(Parity::None));
        let error = "mark".parse::<Parity>().unwrap_err();
        assert_eq!(error, ParityError("mark".to_owned()));
        assert_eq!(
            error.to_string(),
            r#"parity "mark": expected even, odd or none"#
        );
        for parity in [Parity::Even, Parity::Odd, Parity::None] {
            assert_eq!(parity.to_string().parse::<Parity>(), Ok(parity));
        }
    }

    /// The read-back comparison on its own, for every setting: what a pseudo-terminal,
    /// a driver without two stop bits or a rounding divisor report.
    #[test]
    fn refused_settings_are_named() {
        let asked = LineSettings::new(19200);
        assert_eq!(asked.refused_by(&asked, 8), None);
        let pty = LineSettings {
            parity: Parity::None,
            ..asked
        };
        let refused = asked.refused_by(&pty, 8).unwrap();
        assert_eq!(refused.setting, Setting::Parity);
        assert_eq!(
            refused.to_string(),
            "the port refused parity even (it kept none)"
        );
        let one_stop = LineSettings {
            stop_bits: 2,
            ..asked
        };
        assert_eq!(
            one_stop.refused_by(&asked, 8).unwrap().to_string(),
            "the port refused stop bits 2 (it kept 1)"
        );
        assert_eq!(
            asked.refused_by(&asked, 7).unwrap().to_string(),
            "the port refused data bits 8 (it kept 7)"
        );
        let slower = LineSettings::new(9600);
        assert_eq!(
            asked.refused_by(&slower, 8).unwrap().to_string(),
            "the port refused baud rate 19200 (it kept 9600)"
        );
        // A divisor's rounding (an adapter that reaches 115384 Bd for 115200, 0.16 % off)
        // is no refusal; 2 % is the limit.
        let fast = LineSettings::new(115_200);
        let rounded = LineSettings::new(115_384);
        assert_eq!(fast.refused_by(&rounded, 8), None);
        assert_eq!(fast.refused_by(&LineSettings::new(117_504), 8), None);
        assert_eq!(
            fast.refused_by(&LineSettings::new(117_505), 8)
                .map(|r| r.setting),
            Some(Setting::Baud)
        );
    }
}
