//! APDU layout, control fields and encoders.

use std::fmt;

use super::SeqNum;

/// The start byte of every APDU.
pub const START_BYTE: u8 = 0x68;
/// Length of the APCI: start byte, length byte and four control octets.
pub const APCI_LEN: usize = 6;
/// Smallest value of the length byte (control field only).
pub const MIN_LENGTH: u8 = 4;
/// Largest value of the length byte.
pub const MAX_LENGTH: u8 = 253;
/// Largest ASDU an I frame can carry (253 - 4).
pub const MAX_ASDU_LEN: usize = MAX_LENGTH as usize - MIN_LENGTH as usize;
/// Largest APDU on the wire (start and length bytes included).
pub const MAX_APDU_LEN: usize = MAX_LENGTH as usize + 2;

/// The function of a U frame. Exactly one function bit is set in a valid U frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum UFunction {
    /// STARTDT act: the controlling station asks to start data transfer.
    StartDtAct,
    /// STARTDT con: the controlled station confirms the start.
    StartDtCon,
    /// STOPDT act: the controlling station asks to stop data transfer.
    StopDtAct,
    /// STOPDT con: the controlled station confirms the stop.
    StopDtCon,
    /// TESTFR act: a test frame (either station, on idle).
    TestFrAct,
    /// TESTFR con: the answer to a test frame.
    TestFrCon,
}

impl UFunction {
    /// All six functions, in bit order.
    pub const ALL: [UFunction; 6] = [
        UFunction::StartDtAct,
        UFunction::StartDtCon,
        UFunction::StopDtAct,
        UFunction::StopDtCon,
        UFunction::TestFrAct,
        UFunction::TestFrCon,
    ];

    /// The function bit in control octet 1 (without the two format bits).
    pub const fn bit(self) -> u8 {
        match self {
            UFunction::StartDtAct => 0x04,
            UFunction::StartDtCon => 0x08,
            UFunction::StopDtAct => 0x10,
            UFunction::StopDtCon => 0x20,
            UFunction::TestFrAct => 0x40,
            UFunction::TestFrCon => 0x80,
        }
    }

    /// The function whose bit is `bit`, if `bit` is exactly one function bit.
    pub const fn from_bit(bit: u8) -> Option<UFunction> {
        match bit {
            0x04 => Some(UFunction::StartDtAct),
            0x08 => Some(UFunction::StartDtCon),
            0x10 => Some(UFunction::StopDtAct),
            0x20 => Some(UFunction::StopDtCon),
            0x40 => Some(UFunction::TestFrAct),
            0x80 => Some(UFunction::TestFrCon),
            _ => None,
        }
    }

    /// Whether this is an activation (`*Act`), which the peer must confirm within t1.
    pub const fn is_act(self) -> bool {
        matches!(
            self,
            UFunction::StartDtAct | UFunction::StopDtAct | UFunction::TestFrAct
        )
    }

    /// The standard's name, e.g. `STARTDT act`.
    pub const fn name(self) -> &'static str {
        match self {
            UFunction::StartDtAct => "STARTDT act",
            UFunction::StartDtCon => "STARTDT con",
            UFunction::StopDtAct => "STOPDT act",
            UFunction::StopDtCon => "STOPDT con",
            UFunction::TestFrAct => "TESTFR act",
            UFunction::TestFrCon => "TESTFR con",
        }
    }
}

impl fmt::Display for UFunction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The three APDU formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FrameFormat {
    /// Numbered information transfer; always carries an ASDU.
    I,
    /// Numbered supervisory (acknowledgement); no ASDU.
    S,
    /// Unnumbered control (STARTDT, STOPDT, TESTFR); no ASDU.
    U,
}

impl fmt::Display for FrameFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            FrameFormat::I => "I",
            FrameFormat::S => "S",
            FrameFormat::U => "U",
        })
    }
}

/// A decoded control field (the four octets after the length byte).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Apci {
    /// I format: numbered information transfer.
    I {
        /// N(S): the sequence number of this frame.
        send_seq: SeqNum,
        /// N(R): the sequence number the sender expects next (acknowledges all before).
        recv_seq: SeqNum,
    },
    /// S format: acknowledgement without data.
    S {
        /// N(R): acknowledges every I frame with N(S) before this number.
        recv_seq: SeqNum,
    },
    /// U format: link control.
    U(UFunction),
}

impl Apci {
    /// The format of this control field.
    pub const fn format(&self) -> FrameFormat {
        match self {
            Apci::I { .. } => FrameFormat::I,
            Apci::S { .. } => FrameFormat::S,
            Apci::U(_) => FrameFormat::U,
        }
    }

    /// Encodes the four control octets.
    pub const fn encode(&self) -> [u8; 4] {
        match *self {
            Apci::I { send_seq, recv_seq } => {
                let [s1, s2] = seq_octets(send_seq);
                let [r1, r2] = seq_octets(recv_seq);
                [s1, s2, r1, r2]
            }
            Apci::S { recv_seq } => {
                let [r1, r2] = seq_octets(recv_seq);
                [0x01, 0x00, r1, r2]
            }
            Apci::U(function) => [function.bit() | 0x03, 0x00, 0x00, 0x00],
        }
    }

    /// Decodes the four control octets.
    ///
    /// Strict about the bits the standard fixes (IEC 60870-5-104 5.1; spec 2.4), because
    /// over TCP a violated fixed bit is the only early sign of a desynchronised stream:
    ///
    /// - I format: bit 1 of octet 3 must be 0.
    /// - S format: octet 1 must be exactly `0x01`, octet 2 must be 0, bit 1 of octet 3
    ///   must be 0. (lib60870 ignores S frames whose octet 1 is not `0x01`; we reject
    ///   them, since ignoring an acknowledgement silently would only move the failure
    ///   to a t1 timeout.)
    /// - U format: exactly one of the six function bits, octets 2-4 all zero.
    pub const fn decode(control: [u8; 4]) -> Result<Apci, FrameError> {
        let [c1, c2, c3, c4] = control;
        if c1 & 0x01 == 0 {
            if c3 & 0x01 != 0 {
                return Err(FrameError::ReservedBitsSet(control));
            }
            Ok(Apci::I {
                send_seq: seq_from_octets(c1, c2),
                recv_seq: seq_from_octets(c3, c4),
            })
        } else if c1 & 0x02 == 0 {
            if c1 != 0x01 || c2 != 0 || c3 & 0x01 != 0 {
                return Err(FrameError::ReservedBitsSet(control));
            }
            Ok(Apci::S {
                recv_seq: seq_from_octets(c3, c4),
            })
        } else {
            if c2 != 0 || c3 != 0 || c4 != 0 {
                return Err(FrameError::ReservedBitsSet(control));
            }
            match UFunction::from_bit(c1 & 0xFC) {
                Some(function) => Ok(Apci::U(function)),
                None => Err(FrameError::InvalidUFunction(c1)),
            }
        }
    }
}

impl fmt::Display for Apci {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Apci::I { send_seq, recv_seq } => write!(f, "I(N(S)={send_seq}, N(R)={recv_seq})"),
            Apci::S { recv_seq } => write!(f, "S(N(R)={recv_seq})"),
            Apci::U(function) => write!(f, "U({function})"),
        }
    }
}

/// A sequence number as two octets: 7 bits shifted left by one, then 8 bits.
const fn seq_octets(seq: SeqNum) -> [u8; 2] {
    let v = seq.value() << 1;
    v.to_le_bytes()
}

const fn seq_from_octets(lo: u8, hi: u8) -> SeqNum {
    SeqNum::new(((hi as u16) << 7) | ((lo as u16) >> 1))
}

/// A TLS record (alert 0x15, handshake 0x16) where an APDU belongs: the peer speaks TLS
/// (IEC 62351-3) and this side does not, a mistake worth naming.
fn tls_hint(byte: u8) -> &'static str {
    match byte {
        0x15 | 0x16 => ": the peer speaks TLS (configure TLS on this side)",
        _ => "",
    }
}

/// Why bytes could not be framed or a control field decoded. Over TCP there is no
/// resynchronisation: each of these is fatal for the connection.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error)]
#[non_exhaustive]
pub enum FrameError {
    /// The first byte of an APDU is not 0x68.
    #[error("invalid start byte 0x{0:02X} (expected 0x68){hint}", hint = tls_hint(*.0))]
    InvalidStartByte(u8),
    /// The length byte is below 4 (no room for the control field).
    #[error("APDU length {0} is below the minimum of 4")]
    LengthTooShort(u8),
    /// The length byte is above 253.
    #[error("APDU length {0} is above the maximum of 253")]
    LengthTooLong(u8),
    /// An I frame of length 4: the I format always carries an ASDU (IEC 60870-5-104 5.1).
    #[error("I frame without ASDU (length 4)")]
    EmptyIFrame,
    /// An S or U frame followed by ASDU octets: those formats are exactly 4 octets long.
    #[error("{format} frame carries {len} unexpected ASDU octets")]
    UnexpectedAsdu {
        /// S or U.
        format: FrameFormat,
        /// The number of octets after the control field.
        len: usize,
    },
    /// A U frame with no function bit or more than one.
    #[error("U frame control octet 0x{0:02X} must carry exactly one function bit")]
    InvalidUFunction(u8),
    /// A bit the standard fixes to 0 (or to a given value) is wrong.
    #[error("reserved bits set in control field {:02X} {:02X} {:02X} {:02X}", .0[0], .0[1], .0[2], .0[3])]
    ReservedBitsSet([u8; 4]),
    /// [`Frame::decode`] got fewer bytes than the APDU announces.
    #[error("incomplete APDU: {needed} bytes needed, {available} available")]
    Incomplete {
        /// The total APDU length announced (or 2 when even the length byte is missing).
        needed: usize,
        /// The bytes given.
        available: usize,
    },
    /// [`Frame::decode`] got more bytes than one APDU.
    #[error("{0} bytes follow the APDU")]
    TrailingBytes(usize),
}

/// Why an APDU could not be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error)]
#[non_exhaustive]
pub enum EncodeError {
    /// An I frame needs an ASDU of at least one octet.
    #[error("an I frame needs a non-empty ASDU")]
    EmptyAsdu,
    /// The ASDU is longer than 249 octets.
    #[error("ASDU of {0} octets exceeds the maximum of 249")]
    AsduTooLong(usize),
    /// An S or U frame was given ASDU octets.
    #[error("{0} frames carry no ASDU")]
    AsduNotAllowed(FrameFormat),
}

/// One APDU: its control field and, for I frames, the ASDU octets (opaque here).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Frame<'a> {
    /// The decoded control field.
    pub apci: Apci,
    /// The ASDU octets (empty for S and U frames).
    pub asdu: &'a [u8],
}

impl<'a> Frame<'a> {
    /// Decodes exactly one complete APDU (start byte included), e.g. from a capture.
    /// For a TCP byte stream use [`super::Deframer`].
    pub fn decode(apdu: &'a [u8]) -> Result<Frame<'a>, FrameError> {
        match parse(apdu)? {
            Some((frame, used)) if used == apdu.len() => Ok(frame),
            Some((_, used)) => Err(FrameError::TrailingBytes(apdu.len() - used)),
            None => Err(FrameError::Incomplete {
                needed: apdu.get(1).map_or(2, |&len| usize::from(len) + 2),
                available: apdu.len(),
            }),
        }
    }

    /// Appends the encoded APDU to `out`.
    pub fn encode(&self, out: &mut Vec<u8>) -> Result<(), EncodeError> {
        match self.apci {
            Apci::I { send_seq, recv_seq } => encode_i_frame(send_seq, recv_seq, self.asdu, out),
            Apci::S { recv_seq } if self.asdu.is_empty() => {
                encode_s_frame(recv_seq, out);
                Ok(())
            }
            Apci::U(function) if self.asdu.is_empty() => {
                encode_u_frame(function, out);
                Ok(())
            }
            other => Err(EncodeError::AsduNotAllowed(other.format())),
        }
    }
}

/// Appends an I frame with N(S) = `send`, N(R) = `recv` and the given ASDU (1..=249
/// octets) to `out`. Nothing is appended on error.
pub fn encode_i_frame(
    send: SeqNum,
    recv: SeqNum,
    asdu: &[u8],
    out: &mut Vec<u8>,
) -> Result<(), EncodeError> {
    if asdu.is_empty() {
        return Err(EncodeError::EmptyAsdu);
    }
    let length = match u8::try_from(asdu.len() + usize::from(MIN_LENGTH)) {
        Ok(len) if len <= MAX_LENGTH => len,
        _ => return Err(EncodeError::AsduTooLong(asdu.len())),
    };
    let control = Apci::I {
        send_seq: send,
        recv_seq: recv,
    }
    .encode();
    out.reserve(APCI_LEN + asdu.len());
    out.extend_from_slice(&[START_BYTE, length]);
    out.extend_from_slice(&control);
    out.extend_from_slice(asdu);
    Ok(())
}

/// Appends an S frame acknowledging every I frame before `recv` to `out`.
pub fn encode_s_frame(recv: SeqNum, out: &mut Vec<u8>) {
    let [c1, c2, c3, c4] = Apci::S { recv_seq: recv }.encode();
    out.extend_from_slice(&[START_BYTE, MIN_LENGTH, c1, c2, c3, c4]);
}

/// Appends a U frame with the given function to `out`.
pub fn encode_u_frame(function: UFunction, out: &mut Vec<u8>) {
    let [c1, c2, c3, c4] = Apci::U(function).encode();
    out.extend_from_slice(&[START_BYTE, MIN_LENGTH, c1, c2, c3, c4]);
}

/// Parses one APDU from the front of `buf`.
///
/// `Ok(None)`: more bytes are needed. Errors are reported as soon as the offending byte is
/// present (a wrong start byte with one byte buffered, a bad length with two), so garbage
/// is detected without waiting for more input.
pub(crate) fn parse(buf: &[u8]) -> Result<Option<(Frame<'_>, usize)>, FrameError> {
    let Some(&start) = buf.first() else {
        return Ok(None);
    };
    if start != START_BYTE {
        return Err(FrameError::InvalidStartByte(start));
    }
    let Some(&length) = buf.get(1) else {
        return Ok(None);
    };
    if length < MIN_LENGTH {
        return Err(FrameError::LengthTooShort(length));
    }
    if length > MAX_LENGTH {
        return Err(FrameError::LengthTooLong(length));
    }
    let total = usize::from(length) + 2;
    let Some(apdu) = buf.get(..total) else {
        return Ok(None);
    };
    let Some((header, asdu)) = apdu.split_first_chunk::<APCI_LEN>() else {
        return Ok(None);
    };
    let [_, _, c1, c2, c3, c4] = *header;
    let control = [c1, c2, c3, c4];
    let apci = Apci::decode(control)?;
    match apci.format() {
        FrameFormat::I if asdu.is_empty() => return Err(FrameError::EmptyIFrame),
        FrameFormat::S | FrameFormat::U if !asdu.is_empty() => {
            return Err(FrameError::UnexpectedAsdu {
                format: apci.format(),
                len: asdu.len(),
            })
        }
        _ => {}
    }
    Ok(Some((Frame { apci, asdu }, total)))
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::indexing_slicing)]
mod tests {
    use super::*;

    const STARTDT_ACT: [u8; 6] = [0x68, 0x04, 0x07, 0x00, 0x00, 0x00];
    const STARTDT_CON: [u8; 6] = [0x68, 0x04, 0x0B, 0x00, 0x00, 0x00];
    const STOPDT_ACT: [u8; 6] = [0x68, 0x04, 0x13, 0x00, 0x00, 0x00];
    const STOPDT_CON: [u8; 6] = [0x68, 0x04, 0x23, 0x00, 0x00, 0x00];
    const TESTFR_ACT: [u8; 6] = [0x68, 0x04, 0x43, 0x00, 0x00, 0x00];
    const TESTFR_CON: [u8; 6] = [0x68, 0x04, 0x83, 0x00, 0x00, 0x00];
    /// Spec 2.4: I frame N(S)=3, N(R)=7.
    const I_CONTROL_3_7: [u8; 4] = [0x06, 0x00, 0x0E, 0x00];
    /// Spec 2.4: S frame N(R)=5.
    const S_FRAME_5: [u8; 6] = [0x68, 0x04, 0x01, 0x00, 0x0A, 0x00];
    /// Spec 7.3: the first logged M_DP_TB_1 with N(S) = N(R) = 0.
    const M_DP_TB_1_APDU: [u8; 23] = [
        0x68, 0x15, 0x00, 0x00, 0x00, 0x00, 0x1F, 0x01, 0x03, 0x00, 0x01, 0x00, 0xD0, 0x07, 0x00,
        0x01, 0xD8, 0x76, 0xBB, 0x09, 0x1A, 0x04, 0x11,
    ];

    fn u_bytes(function: UFunction) -> Vec<u8> {
        let mut out = Vec::new();
        encode_u_frame(function, &mut out);
        out
    }

    #[test]
    fn u_frames_match_spec_vectors() {
        assert_eq!(u_bytes(UFunction::StartDtAct), STARTDT_ACT);
        assert_eq!(u_bytes(UFunction::StartDtCon), STARTDT_CON);
        assert_eq!(u_bytes(UFunction::StopDtAct), STOPDT_ACT);
        assert_eq!(u_bytes(UFunction::StopDtCon), STOPDT_CON);
        assert_eq!(u_bytes(UFunction::TestFrAct), TESTFR_ACT);
        assert_eq!(u_bytes(UFunction::TestFrCon), TESTFR_CON);
        for function in UFunction::ALL {
            let bytes = u_bytes(function);
            let frame = Frame::decode(&bytes).unwrap();
            assert_eq!(frame.apci, Apci::U(function));
            assert!(frame.asdu.is_empty());
        }
    }

    #[test]
    fn i_control_field_matches_spec_vector() {
        let apci = Apci::I {
            send_seq: SeqNum::new(3),
            recv_seq: SeqNum::new(7),
        };
        assert_eq!(apci.encode(), I_CONTROL_3_7);
        assert_eq!(Apci::decode(I_CONTROL_3_7), Ok(apci));
    }

    #[test]
    fn s_frame_matches_spec_vector() {
        let mut out = Vec::new();
        encode_s_frame(SeqNum::new(5), &mut out);
        assert_eq!(out, S_FRAME_5);
        let frame = Frame::decode(&S_FRAME_5).unwrap();
        assert_eq!(
            frame.apci,
            Apci::S {
                recv_seq: SeqNum::new(5)
            }
        );
    }

    #[test]
    fn logged_apdu_decodes() {
        let frame = Frame::decode(&M_DP_TB_1_APDU).unwrap();
        assert_eq!(
            frame.apci,
            Apci::I {
                send_seq: SeqNum::ZERO,
                recv_seq: SeqNum::ZERO
            }
        );
        assert_eq!(frame.asdu, &M_DP_TB_1_APDU[6..]);
        let mut out = Vec::new();
        encode_i_frame(SeqNum::ZERO, SeqNum::ZERO, frame.asdu, &mut out).unwrap();
        assert_eq!(out, M_DP_TB_1_APDU);
    }

    #[test]
    fn sequence_numbers_round_trip_at_extremes() {
        for (s, r) in [(0, 0), (127, 128), (32767, 32767), (128, 32767), (16384, 1)] {
            let apci = Apci::I {
                send_seq: SeqNum::new(s),
                recv_seq: SeqNum::new(r),
            };
            assert_eq!(Apci::decode(apci.encode()), Ok(apci));
            let s_apci = Apci::S {
                recv_seq: SeqNum::new(r),
            };
            assert_eq!(Apci::decode(s_apci.encode()), Ok(s_apci));
        }
        // 32767 << 1 = 0xFFFE
        assert_eq!(
            Apci::I {
                send_seq: SeqNum::MAX,
                recv_seq: SeqNum::ZERO
            }
            .encode(),
            [0xFE, 0xFF, 0x00, 0x00]
        );
    }

    #[test]
    fn u_frame_with_two_functions_is_rejected() {
        assert_eq!(
            Apci::decode([0x0F, 0, 0, 0]),
            Err(FrameError::InvalidUFunction(0x0F))
        );
        assert_eq!(
            Apci::decode([0x03, 0, 0, 0]),
            Err(FrameError::InvalidUFunction(0x03))
        );
        assert_eq!(
            Apci::decode([0xC3, 0, 0, 0]),
            Err(FrameError::InvalidUFunction(0xC3))
        );
    }

    #[test]
    fn u_frame_with_nonzero_octets_is_rejected() {
        for control in [[0x07, 1, 0, 0], [0x07, 0, 1, 0], [0x43, 0, 0, 0x80]] {
            assert_eq!(
                Apci::decode(control),
                Err(FrameError::ReservedBitsSet(control))
            );
        }
    }

    #[test]
    fn s_frame_reserved_bits_are_rejected() {
        for control in [
            [0x05, 0, 0, 0],
            [0x01, 0x01, 0, 0],
            [0x01, 0, 0x01, 0],
            [0xF1, 0, 2, 0],
        ] {
            assert_eq!(
                Apci::decode(control),
                Err(FrameError::ReservedBitsSet(control))
            );
        }
    }

    #[test]
    fn i_frame_reserved_bit_is_rejected() {
        assert_eq!(
            Apci::decode([0x02, 0, 0x03, 0]),
            Err(FrameError::ReservedBitsSet([0x02, 0, 0x03, 0]))
        );
    }

    #[test]
    fn length_and_asdu_rules() {
        assert_eq!(
            Frame::decode(&[0x68, 0x04, 0x00, 0x00, 0x00, 0x00]),
            Err(FrameError::EmptyIFrame)
        );
        assert_eq!(
            Frame::decode(&[0x68, 0x05, 0x01, 0x00, 0x00, 0x00, 0xAA]),
            Err(FrameError::UnexpectedAsdu {
                format: FrameFormat::S,
                len: 1
            })
        );
        assert_eq!(
            Frame::decode(&[0x68, 0x06, 0x43, 0x00, 0x00, 0x00, 0xAA, 0xBB]),
            Err(FrameError::UnexpectedAsdu {
                format: FrameFormat::U,
                len: 2
            })
        );
        assert_eq!(
            Frame::decode(&[0x68, 0x03]),
            Err(FrameError::LengthTooShort(3))
        );
        assert_eq!(
            Frame::decode(&[0x68, 0xFE]),
            Err(FrameError::LengthTooLong(254))
        );
        assert_eq!(
            Frame::decode(&[0x69]),
            Err(FrameError::InvalidStartByte(0x69))
        );
        assert_eq!(
            Frame::decode(&[0x68, 0x04, 0x07]),
            Err(FrameError::Incomplete {
                needed: 6,
                available: 3
            })
        );
        assert_eq!(
            Frame::decode(&[0x68]),
            Err(FrameError::Incomplete {
                needed: 2,
                available: 1
            })
        );
        assert_eq!(
            Frame::decode(&[0x68, 0x04, 0x07, 0, 0, 0, 0x68]),
            Err(FrameError::TrailingBytes(1))
        );
    }

    #[test]
    fn encoder_limits() {
        let mut out = Vec::new();
        assert_eq!(
            encode_i_frame(SeqNum::ZERO, SeqNum::ZERO, &[], &mut out),
            Err(EncodeError::EmptyAsdu)
        );
        assert_eq!(
            encode_i_frame(SeqNum::ZERO, SeqNum::ZERO, &[0; 250], &mut out),
            Err(EncodeError::AsduTooLong(250))
        );
        assert!(out.is_empty());
        encode_i_frame(SeqNum::ZERO, SeqNum::ZERO, &[0; 249], &mut out).unwrap();
        assert_eq!(out.len(), 255);
        assert_eq!(out[1], 253);
        let frame = Frame::decode(&out).unwrap();
        assert_eq!(frame.asdu.len(), 249);
        let mut again = Vec::new();
        frame.encode(&mut again).unwrap();
        assert_eq!(again, out);
        let bad = Frame {
            apci: Apci::U(UFunction::TestFrAct),
            asdu: &[1],
        };
        assert_eq!(
            bad.encode(&mut again),
            Err(EncodeError::AsduNotAllowed(FrameFormat::U))
        );
    }

    #[test]
    fn every_control_field_decodes_or_errors_consistently() {
        // Exhaustive over octet 1 and a sample of the others: whatever decodes must
        // re-encode to the same octets.
        for c1 in 0..=255u8 {
            for rest in [
                [0u8, 0, 0],
                [1, 0, 0],
                [0, 2, 0],
                [0, 1, 0],
                [0xFF, 0xFE, 0xFF],
            ] {
                let control = [c1, rest[0], rest[1], rest[2]];
                if let Ok(apci) = Apci::decode(control) {
                    assert_eq!(apci.encode(), control, "{control:02X?}");
                }
            }
        }
    }
}
