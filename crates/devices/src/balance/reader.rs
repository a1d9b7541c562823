//! The balance's reader, sans-IO: octets and time in, records and the balance's
//! silence out. A serial line (unlike the thesis's DP/RS 232C gateway, which fills a
//! 15-octet window with no time consistency) delivers the records in order, so they are
//! cut at each LF: the 15 octets before and including it are one record, parsed with
//! every check of [`super::record::parse`]. Fewer octets before an LF (a record joined
//! mid-way when the line was opened) or a record that fails a check is an
//! [`ReaderEvent::Illegal`], counted, never a reading.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use serial_line::{LineEndpoint, LineSettings, Parity};

use super::record::{parse, Reading, RecordError, RECORD_LEN};

/// The balance's line as the thesis set it: 1200 Bd, 7 data bits and an unused parity
/// position, read as 8 data bits without parity (the masked bit 7 is that position).
pub const BALANCE_LINE: LineSettings = LineSettings {
    baud: 1200,
    parity: Parity::None,
    stop_bits: 1,
};

/// How long without a legal record the balance counts as silent (it sends 2-4 a
/// second in automatic output).
pub const SILENCE: Duration = Duration::from_secs(2);

/// What the reader saw.
#[derive(Debug, Clone, PartialEq)]
pub enum ReaderEvent {
    /// A legal record.
    Record(Reading),
    /// A record that is not legal (never a reading), and why.
    Illegal(IllegalRecord),
    /// No legal record for [`SILENCE`] (`false`), or one again after that (`true`).
    Answering(bool),
}

/// Why octets up to an LF were not a record.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum IllegalRecord {
    /// Fewer than 15 octets before the LF.
    #[error("{0} octets up to the LF, a record has 15")]
    Short(usize),
    /// The record failed a check.
    #[error("{0}")]
    Record(#[from] RecordError),
}

/// A balance reader.
#[derive(Debug)]
pub struct BalanceReader {
    line: LineSettings,
    silence: Duration,
    pending: Vec<u8>,
    events: VecDeque<ReaderEvent>,
    last_record: Option<Instant>,
    answering: bool,
    started: Instant,
    records: u64,
    illegal: u64,
}

/// Octets kept while waiting for an LF: a line of noise without one is dropped.
const MAX_PENDING: usize = 64;

impl BalanceReader {
    /// A reader of a balance on `line`, started at `now`.
    pub fn new(line: LineSettings, now: Instant) -> BalanceReader {
        BalanceReader {
            line,
            silence: SILENCE,
            pending: Vec::with_capacity(MAX_PENDING),
            events: VecDeque::new(),
            last_record: None,
            answering: false,
            started: now,
            records: 0,
            illegal: 0,
        }
    }

    /// The next event.
    pub fn poll_event(&mut self) -> Option<ReaderEvent> {
        self.events.pop_front()
    }

    /// Legal records so far.
    pub fn records(&self) -> u64 {
        self.records
    }

    /// Illegal records so far.
    pub fn illegal(&self) -> u64 {
        self.illegal
    }

    fn record_end(&mut self, now: Instant) {
        let len = self.pending.len();
        let result = match self.pending.get(len.saturating_sub(RECORD_LEN)..) {
            Some(tail) if len >= RECORD_LEN => {
                let mut window = [0u8; RECORD_LEN];
                window.copy_from_slice(tail);
                parse(&window).map_err(IllegalRecord::from)
            }
            _ => Err(IllegalRecord::Short(len)),
        };
        self.pending.clear();
        match result {
            Ok(reading) => {
                self.records += 1;
                self.last_record = Some(now);
                if !self.answering {
                    self.answering = true;
                    self.events.push_back(ReaderEvent::Answering(true));
                }
                self.events.push_back(ReaderEvent::Record(reading));
            }
            Err(illegal) => {
                self.illegal += 1;
                tracing::debug!(%illegal, "illegal balance record");
                self.events.push_back(ReaderEvent::Illegal(illegal));
            }
        }
    }
}

impl LineEndpoint for BalanceReader {
    fn handle_bytes(&mut self, now: Instant, bytes: &[u8]) {
        for &byte in bytes {
            let byte = byte & 0x7F;
            self.pending.push(byte);
            if byte == b'\n' {
                self.record_end(now);
            } else if self.pending.len() > MAX_PENDING {
                self.pending.drain(..self.pending.len() - RECORD_LEN);
            }
        }
    }

    fn handle_line_pause(&mut self, _now: Instant) {}

    fn handle_timeout(&mut self, now: Instant) {
        let since = self.last_record.unwrap_or(self.started);
        if self.answering && now.saturating_duration_since(since) >= self.silence {
            self.answering = false;
            self.events.push_back(ReaderEvent::Answering(false));
        }
    }

    fn poll_transmit(&mut self, _now: Instant) -> Option<Vec<u8>> {
        // The balance's RxD is not connected: nothing is ever sent to it.
        None
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.answering
            .then(|| self.last_record.unwrap_or(self.started) + self.silence)
    }

    fn line(&self) -> LineSettings {
        self.line
    }
}

#[cfg(test)]
mod tests {
    use super::super::record::format;
    use super::*;

    fn events(reader: &mut BalanceReader) -> Vec<ReaderEvent> {
        std::iter::from_fn(|| reader.poll_event()).collect()
    }

    #[test]
    fn records_are_cut_at_lf_and_checked() {
        let t0 = tokio::time::Instant::now().into_std();
        let mut reader = BalanceReader::new(BALANCE_LINE, t0);
        // joined mid-record: the tail before the first LF is too short
        let mut bytes = b"345    \r\n".to_vec();
        bytes.extend_from_slice(&format(2.345, false));
        bytes.extend_from_slice(b"+   2,345    \r\n");
        // in two pieces
        reader.handle_bytes(t0, &bytes[..20]);
        reader.handle_bytes(t0, &bytes[20..]);
        assert_eq!(
            events(&mut reader),
            vec![
                ReaderEvent::Illegal(IllegalRecord::Short(9)),
                ReaderEvent::Answering(true),
                ReaderEvent::Record(Reading {
                    weight_g: 2.345,
                    stable: false
                }),
                ReaderEvent::Illegal(IllegalRecord::Record(RecordError::Illegal {
                    position: 6,
                    byte: b','
                })),
            ]
        );
        assert_eq!((reader.records(), reader.illegal()), (1, 2));
    }

    #[test]
    fn silence_and_return() {
        let t0 = tokio::time::Instant::now().into_std();
        let mut reader = BalanceReader::new(BALANCE_LINE, t0);
        reader.handle_bytes(t0, &format(1.0, true));
        let _ = events(&mut reader);
        assert_eq!(reader.next_deadline(), Some(t0 + SILENCE));
        reader.handle_timeout(t0 + SILENCE);
        assert_eq!(events(&mut reader), vec![ReaderEvent::Answering(false)]);
        assert_eq!(reader.next_deadline(), None);
        let t1 = t0 + Duration::from_secs(5);
        reader.handle_bytes(t1, &format(1.0, true));
        assert_eq!(events(&mut reader)[0], ReaderEvent::Answering(true));
    }

    #[test]
    fn noise_without_lf_is_bounded() {
        let t0 = tokio::time::Instant::now().into_std();
        let mut reader = BalanceReader::new(BALANCE_LINE, t0);
        reader.handle_bytes(t0, &[b'x'; 1000]);
        reader.handle_bytes(t0, &format(3.091, true));
        // the record's 15 octets follow the noise: the last 15 before the LF are whole
        assert!(events(&mut reader).contains(&ReaderEvent::Record(Reading {
            weight_g: 3.091,
            stable: true
        })));
    }
}
