//! The classification of a weight into a colour (the sorting-lab thesis, section 8.3,
//! FC1): four bands of grams, anything else (an empty pan, two balls, a gap between
//! bands) 0, "none of the above".
//!
//! Two sets of limits: the thesis's as printed (inclusive, with 0.01 g gaps between the
//! bands, read off a plot: 2.505 g falls in none, BS-A7) and the default contiguous ones
//! (thresholds midway in the gaps, 2.505, 2.915 and 3.305 g, outer limits 2.0 and 4.0 g).

use serde::Serialize;

/// A ball's colour, numbered as FC1 returns it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Colour {
    /// 1
    Red,
    /// 2
    Yellow,
    /// 3
    Blue,
    /// 4
    Green,
}

impl Colour {
    /// The four, lightest first.
    pub const ALL: [Colour; 4] = [Colour::Red, Colour::Yellow, Colour::Blue, Colour::Green];

    /// FC1's integer (1-4).
    pub fn code(self) -> u8 {
        match self {
            Colour::Red => 1,
            Colour::Yellow => 2,
            Colour::Blue => 3,
            Colour::Green => 4,
        }
    }

    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Colour::Red => "red",
            Colour::Yellow => "yellow",
            Colour::Blue => "blue",
            Colour::Green => "green",
        }
    }

    /// The colour of a ball named like `red 1` (its first word).
    pub fn of_ball(name: &str) -> Option<Colour> {
        let first = name.split_whitespace().next()?;
        Colour::ALL
            .into_iter()
            .find(|colour| colour.name().eq_ignore_ascii_case(first))
    }
}

/// The classification limits.
#[derive(Debug, Clone, PartialEq)]
pub enum ClassLimits {
    /// Inclusive bands as printed: red 2.0-2.50, yellow 2.51-2.91, blue 2.92-3.30,
    /// green 3.31-4.0 g.
    Printed,
    /// Contiguous bands: `lower <= w < t1` red, `t1 <= w < t2` yellow, `t2 <= w < t3`
    /// blue, `t3 <= w <= upper` green.
    Contiguous {
        /// The lower outer limit.
        lower: f64,
        /// The three thresholds between neighbours, ascending.
        thresholds: [f64; 3],
        /// The upper outer limit.
        upper: f64,
    },
}

impl ClassLimits {
    /// BS-A7's default: thresholds 2.505, 2.915 and 3.305 g within 2.0 and 4.0 g.
    pub const DEFAULT: ClassLimits = ClassLimits::Contiguous {
        lower: 2.0,
        thresholds: [2.505, 2.915, 3.305],
        upper: 4.0,
    };

    /// The colour of `weight_g`, or `None` (FC1's 0).
    pub fn classify(&self, weight_g: f64) -> Option<Colour> {
        if !weight_g.is_finite() {
            return None;
        }
        // Compared in whole milligrams: the balance's record has three decimals, and
        // 2.50 must not miss the band 2.0-2.50 by a rounding error.
        let mg = (weight_g * 1000.0).round();
        let g = |limit: f64| (limit * 1000.0).round();
        match self {
            ClassLimits::Printed => [
                (Colour::Red, 2.00, 2.50),
                (Colour::Yellow, 2.51, 2.91),
                (Colour::Blue, 2.92, 3.30),
                (Colour::Green, 3.31, 4.00),
            ]
            .into_iter()
            .find(|(_, low, high)| g(*low) <= mg && mg <= g(*high))
            .map(|(colour, _, _)| colour),
            ClassLimits::Contiguous {
                lower,
                thresholds,
                upper,
            } => {
                if mg < g(*lower) || mg > g(*upper) {
                    return None;
                }
                let above = thresholds.iter().filter(|t| mg >= g(**t)).count();
                Colour::ALL.get(above).copied()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_printed_limits_give_the_spec_vectors() {
        let vectors = [
            (1.99, None),
            (2.00, Some(Colour::Red)),
            (2.50, Some(Colour::Red)),
            (2.505, None),
            (2.51, Some(Colour::Yellow)),
            (2.91, Some(Colour::Yellow)),
            (2.92, Some(Colour::Blue)),
            (3.30, Some(Colour::Blue)),
            (3.31, Some(Colour::Green)),
            (4.00, Some(Colour::Green)),
            (4.01, None),
            (5.3, None),
        ];
        for (weight, colour) in vectors {
            assert_eq!(ClassLimits::Printed.classify(weight), colour, "{weight} g");
        }
    }

    #[test]
    fn the_default_limits_leave_no_gap() {
        let limits = ClassLimits::DEFAULT;
        assert_eq!(limits.classify(2.504), Some(Colour::Red));
        assert_eq!(limits.classify(2.505), Some(Colour::Yellow));
        assert_eq!(limits.classify(2.914), Some(Colour::Yellow));
        assert_eq!(limits.classify(2.915), Some(Colour::Blue));
        assert_eq!(limits.classify(3.305), Some(Colour::Green));
        assert_eq!(limits.classify(4.0), Some(Colour::Green));
        assert_eq!(limits.classify(1.999), None);
        assert_eq!(limits.classify(5.3), None);
        assert_eq!(limits.classify(f64::NAN), None);
        assert_eq!(Colour::of_ball("Blue 2"), Some(Colour::Blue));
        assert_eq!(Colour::Green.code(), 4);
    }
}
