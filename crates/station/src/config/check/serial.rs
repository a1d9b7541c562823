//! The settings every serial master shares (IEC 101/103 lines and lift boards): speed
//! and character format, time-outs and retries, each checked with its key.

use super::*;

/// The serial keys of a table as read.
pub(in crate::config) struct SerialKeys<'a> {
    pub(in crate::config) baud: Option<i64>,
    pub(in crate::config) parity: Option<&'a str>,
    pub(in crate::config) stop_bits: Option<i64>,
}

impl Ctx<'_> {
    /// The line settings (9600 8E1 unless set), each key checked at `at(key)`; what the
    /// codec's own validation adds is reported at `whole`.
    pub(in crate::config) fn serial_settings(
        &mut self,
        keys: SerialKeys<'_>,
        at: &dyn Fn(&'static str) -> Vec<Seg>,
        whole: &[Seg],
    ) -> iec60870::ft12::LineSettings {
        type Settings = iec60870::ft12::LineSettings;
        let mut settings = Settings::new(9600);
        // Speed and stop bits are checked here, as ranges with their keys; the codec's own
        // validation below then only catches what it adds later.
        let baud = self.integer_in(
            keys.baud,
            "baud rate",
            Settings::MIN_BAUD.into()..=Settings::MAX_BAUD.into(),
            &at("baud"),
        );
        let stop_bits = self.integer_in(keys.stop_bits, "stop_bits", 1..=2, &at("stop_bits"));
        if let Some(baud) = baud.and_then(|b| u32::try_from(b).ok()) {
            settings.baud = baud;
        }
        if let Some(stop_bits) = stop_bits.and_then(|s| u8::try_from(s).ok()) {
            settings.stop_bits = stop_bits;
        }
        if let Some(parity) = keys.parity {
            match parity.parse() {
                Ok(parity) => settings.parity = parity,
                Err(_) => self.err(
                    &at("parity"),
                    ConfigProblem::UnknownValue {
                        what: Vocabulary::Parity,
                        value: parity.to_owned(),
                    },
                ),
            }
        }
        if let Err(detail) = settings.validate() {
            self.err(
                whole,
                ConfigProblem::Invalid {
                    detail: detail.to_string(),
                },
            );
        }
        settings
    }

    /// A given integer within `range`, or `None` (reported at `path` when given and
    /// outside).
    pub(in crate::config) fn integer_in(
        &mut self,
        value: Option<i64>,
        what: &'static str,
        range: std::ops::RangeInclusive<i64>,
        path: &[Seg],
    ) -> Option<i64> {
        let value = value?;
        if range.contains(&value) {
            Some(value)
        } else {
            self.err(
                path,
                ConfigProblem::OutOfRange {
                    what,
                    value,
                    min: *range.start(),
                    max: Some(*range.end()),
                },
            );
            None
        }
    }

    /// Milliseconds within `range` (the key's name in messages), `default` when not
    /// given or outside (then reported).
    pub(in crate::config) fn millis_in(
        &mut self,
        value: Option<i64>,
        default: i64,
        range: std::ops::RangeInclusive<i64>,
        path: &[Seg],
    ) -> Duration {
        let what = match path.last() {
            Some(K(key)) => key,
            _ => "milliseconds",
        };
        let given = self.integer_in(value, what, range, path);
        Duration::from_millis(given.unwrap_or(default).unsigned_abs())
    }

    /// Repeats of an unanswered request, 0..=10.
    pub(in crate::config) fn retries_in(
        &mut self,
        value: Option<i64>,
        default: u8,
        path: &[Seg],
    ) -> u8 {
        self.integer_in(value, "retries", 0..=10, path)
            .and_then(|retries| u8::try_from(retries).ok())
            .unwrap_or(default)
    }
}
