//! Cutting APDUs out of a TCP byte stream.

use super::frame::{parse, Frame, FrameError, MAX_APDU_LEN};

/// Accumulates TCP bytes and yields complete APDUs.
///
/// The buffer is bounded: [`Deframer::push`] accepts at most as many bytes as fit under
/// the limit and says how many it took. Drain complete frames with
/// [`Deframer::next_frame`] after each push; what stays buffered is then less than one
/// APDU (at most 254 bytes), so the next push always has room. Consumed bytes are
/// compacted away on the next push, so the buffer never grows past its limit and no
/// allocation happens after the first push.
///
/// Over TCP an APDU boundary, once lost, cannot be found again (0x68 may occur in any
/// ASDU), so the first [`FrameError`] is final: the deframer keeps it
/// ([`Deframer::error`]), yields no further frames and accepts no further bytes. The
/// connection must be closed.
#[derive(Debug, Clone)]
pub struct Deframer {
    buf: Vec<u8>,
    pos: usize,
    limit: usize,
    error: Option<FrameError>,
}

impl Default for Deframer {
    fn default() -> Self {
        Self::new()
    }
}

impl Deframer {
    /// The default buffer limit in bytes.
    pub const DEFAULT_LIMIT: usize = 4096;

    /// A deframer with the default buffer limit.
    pub fn new() -> Self {
        Self::with_limit(Self::DEFAULT_LIMIT)
    }

    /// A deframer whose buffer holds at most `limit` bytes (raised to 255, one maximal
    /// APDU, if smaller).
    pub fn with_limit(limit: usize) -> Self {
        Deframer {
            buf: Vec::new(),
            pos: 0,
            limit: limit.max(MAX_APDU_LEN),
            error: None,
        }
    }

    /// Appends as many of `bytes` as fit under the limit and returns how many were taken.
    ///
    /// Returns 0 after an error. Call [`Deframer::next_frame`] until it returns `None`
    /// before pushing the rest.
    pub fn push(&mut self, bytes: &[u8]) -> usize {
        if self.error.is_some() {
            return 0;
        }
        if self.pos >= self.buf.len() {
            self.buf.clear();
            self.pos = 0;
        } else if self.pos > 0 {
            self.buf.drain(..self.pos);
            self.pos = 0;
        }
        let room = self.limit.saturating_sub(self.buf.len());
        let taken = bytes.len().min(room);
        if let Some(accepted) = bytes.get(..taken) {
            self.buf.extend_from_slice(accepted);
        }
        taken
    }

    /// The next complete APDU, `None` when more bytes are needed (or after an error), or
    /// the error that makes the stream unusable.
    ///
    /// Errors are reported as soon as the offending byte is buffered: a wrong start byte
    /// does not wait for a length, a bad length does not wait for the body.
    pub fn next_frame(&mut self) -> Option<Result<Frame<'_>, FrameError>> {
        if self.error.is_some() {
            return None;
        }
        let (buf, pos) = (&self.buf, &mut self.pos);
        match parse(buf.get(*pos..)?) {
            Ok(None) => None,
            Ok(Some((frame, used))) => {
                *pos += used;
                Some(Ok(frame))
            }
            Err(error) => {
                self.error = Some(error);
                Some(Err(error))
            }
        }
    }

    /// Bytes buffered but not yet returned as frames.
    pub fn buffered(&self) -> usize {
        self.buf.len().saturating_sub(self.pos)
    }

    /// The error that stopped this deframer, if any.
    pub fn error(&self) -> Option<FrameError> {
        self.error
    }

    /// Forgets buffered bytes and any error, for reuse on a new connection.
    pub fn reset(&mut self) {
        self.buf.clear();
        self.pos = 0;
        self.error = None;
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::indexing_slicing)]
mod tests {
    use super::*;
    use crate::apci::{encode_i_frame, encode_s_frame, encode_u_frame, Apci, SeqNum, UFunction};

    fn sample_stream() -> (Vec<u8>, Vec<Apci>) {
        let mut out = Vec::new();
        let mut expected = Vec::new();
        encode_u_frame(UFunction::StartDtAct, &mut out);
        expected.push(Apci::U(UFunction::StartDtAct));
        for i in 0..20u16 {
            let asdu: Vec<u8> = (0..(i as u8 * 12 + 1)).collect();
            encode_i_frame(SeqNum::new(i), SeqNum::new(100 + i), &asdu, &mut out).unwrap();
            expected.push(Apci::I {
                send_seq: SeqNum::new(i),
                recv_seq: SeqNum::new(100 + i),
            });
            if i % 3 == 0 {
                encode_s_frame(SeqNum::new(i), &mut out);
                expected.push(Apci::S {
                    recv_seq: SeqNum::new(i),
                });
            }
        }
        (out, expected)
    }

    fn drain(d: &mut Deframer, into: &mut Vec<(Apci, usize)>) {
        while let Some(frame) = d.next_frame() {
            let frame = frame.unwrap();
            into.push((frame.apci, frame.asdu.len()));
        }
    }

    #[test]
    fn every_split_point_yields_the_same_frames() {
        let (stream, expected) = sample_stream();
        for chunk in [1, 2, 3, 5, 6, 7, 64, 255, 256, 1000, stream.len()] {
            let mut d = Deframer::new();
            let mut got = Vec::new();
            for piece in stream.chunks(chunk) {
                let mut rest = piece;
                while !rest.is_empty() {
                    let n = d.push(rest);
                    rest = &rest[n..];
                    drain(&mut d, &mut got);
                }
            }
            let apcis: Vec<Apci> = got.iter().map(|(a, _)| *a).collect();
            assert_eq!(apcis, expected, "chunk {chunk}");
            assert_eq!(d.buffered(), 0);
        }
    }

    #[test]
    fn buffer_is_bounded() {
        let (stream, expected) = sample_stream();
        let mut d = Deframer::with_limit(10);
        let mut got = Vec::new();
        let mut rest = &stream[..];
        let mut first = true;
        while !rest.is_empty() {
            let n = d.push(rest);
            if first {
                assert_eq!(n, MAX_APDU_LEN, "limit raised to one maximal APDU");
                first = false;
            }
            assert!(d.buffered() <= MAX_APDU_LEN);
            rest = &rest[n..];
            drain(&mut d, &mut got);
        }
        let apcis: Vec<Apci> = got.iter().map(|(a, _)| *a).collect();
        assert_eq!(apcis, expected);
    }

    #[test]
    fn garbage_after_valid_frames_is_an_error_after_the_frames() {
        let mut stream = Vec::new();
        encode_u_frame(UFunction::TestFrAct, &mut stream);
        encode_s_frame(SeqNum::new(3), &mut stream);
        stream.extend_from_slice(&[0x00, 0x68, 0x04]);
        let mut d = Deframer::new();
        d.push(&stream);
        assert_eq!(
            d.next_frame().unwrap().unwrap().apci,
            Apci::U(UFunction::TestFrAct)
        );
        assert_eq!(
            d.next_frame().unwrap().unwrap().apci,
            Apci::S {
                recv_seq: SeqNum::new(3)
            }
        );
        assert_eq!(
            d.next_frame(),
            Some(Err(FrameError::InvalidStartByte(0x00)))
        );
        assert_eq!(d.next_frame(), None);
        assert_eq!(d.push(&[0x68]), 0);
        assert_eq!(d.error(), Some(FrameError::InvalidStartByte(0x00)));
        d.reset();
        assert_eq!(d.error(), None);
        d.push(&[0x68, 0x04, 0x43, 0, 0, 0]);
        assert!(d.next_frame().unwrap().is_ok());
    }

    #[test]
    fn errors_are_reported_early() {
        let mut d = Deframer::new();
        d.push(&[0x68, 0xFF]);
        assert_eq!(d.next_frame(), Some(Err(FrameError::LengthTooLong(0xFF))));
        let mut d = Deframer::new();
        d.push(&[0x68, 0x02]);
        assert_eq!(d.next_frame(), Some(Err(FrameError::LengthTooShort(2))));
        let mut d = Deframer::new();
        d.push(&[0x68]);
        assert_eq!(d.next_frame(), None);
        d.push(&[0x04, 0x07, 0x00]);
        assert_eq!(d.next_frame(), None);
        d.push(&[0x00, 0x00]);
        assert_eq!(
            d.next_frame().unwrap().unwrap().apci,
            Apci::U(UFunction::StartDtAct)
        );
    }

    #[test]
    fn truncated_stream_waits() {
        let mut stream = Vec::new();
        encode_i_frame(SeqNum::ZERO, SeqNum::ZERO, &[1, 2, 3], &mut stream).unwrap();
        let mut d = Deframer::new();
        d.push(&stream[..stream.len() - 1]);
        assert_eq!(d.next_frame(), None);
        assert_eq!(d.buffered(), stream.len() - 1);
        assert_eq!(d.error(), None);
    }
}
