//! The character format and speed of a serial line, and the times they imply.

use std::fmt;
use std::str::FromStr;
use std::time::Duration;

/// Parity of a character.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Parity {
    /// Even parity: FT1.2's format.
    Even,
    /// Odd parity.
    Odd,
    /// No parity bit (not FT1.2, but met on terminal servers and converters).
    None,
}

impl FromStr for Parity {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        match text.to_ascii_lowercase().as_str() {
            "even" | "e" => Ok(Parity::Even),
            "odd" | "o" => Ok(Parity::Odd),
            "none" | "n" => Ok(Parity::None),
            other => Err(format!("parity {other:?}: expected even, odd or none")),
        }
    }
}

/// The serial settings of a line: FT1.2 sends 8 data bits, even parity and one stop
/// bit (11 bits a character); stop bits are configurable, as some devices want two.
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
    /// The line idle time required between frames and after a frame error, in bit times.
    pub const IDLE_BITS: u32 = 33;

    /// 8E1 at `baud`.
    pub fn new(baud: u32) -> LineSettings {
        LineSettings {
            baud,
            parity: Parity::Even,
            stop_bits: 1,
        }
    }

    /// Checks speed and stop bits.
    pub fn validate(&self) -> Result<(), String> {
        if !(Self::MIN_BAUD..=Self::MAX_BAUD).contains(&self.baud) {
            return Err(format!(
                "baud rate {} outside {}..={}",
                self.baud,
                Self::MIN_BAUD,
                Self::MAX_BAUD
            ));
        }
        if !(1..=2).contains(&self.stop_bits) {
            return Err(format!("{} stop bits: expected 1 or 2", self.stop_bits));
        }
        Ok(())
    }

    /// Bits on the line for one octet: start, 8 data, parity, stop.
    pub fn bits_per_character(&self) -> u32 {
        1 + 8 + u32::from(self.parity != Parity::None) + u32::from(self.stop_bits)
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
}

impl fmt::Display for LineSettings {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let parity = match self.parity {
            Parity::Even => 'E',
            Parity::Odd => 'O',
            Parity::None => 'N',
        };
        write!(f, "{} Bd 8{}{}", self.baud, parity, self.stop_bits)
    }
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
        assert!(LineSettings::new(600).validate().is_err());
        assert!(LineSettings {
            stop_bits: 3,
            ..LineSettings::new(9600)
        }
        .validate()
        .is_err());
        assert_eq!("even".parse::<Parity>(), Ok(Parity::Even));
    }
}
