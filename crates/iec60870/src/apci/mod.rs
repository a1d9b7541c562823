//! IEC 104 framing: the APCI.
//!
//! An APDU on the TCP stream is `0x68`, a length octet (4..=253) counting what follows,
//! four control octets and, for I frames only, an ASDU of 1..=249 octets. This module
//! knows nothing of the ASDU: it is an opaque byte payload here.
//!
//! - [`SeqNum`]: the 15-bit send and receive sequence numbers, wrapping at 32768.
//! - [`Apci`] and [`UFunction`]: the decoded control field of the I, S and U formats.
//! - [`Frame`] and the encoders [`encode_i_frame`], [`encode_s_frame`],
//!   [`encode_u_frame`].
//! - [`Deframer`]: cuts frames out of TCP bytes with a bounded buffer.
//!
//! # Decisions
//!
//! - **Fixed bits are checked.** A U frame must carry exactly one function bit and zero
//!   octets 2-4; an S frame must have octet 1 = `0x01` and octet 2 = 0; bit 1 of octet 3
//!   must be 0 in I and S frames. Anything else is [`FrameError::ReservedBitsSet`] or
//!   [`FrameError::InvalidUFunction`]. Over TCP a wrong fixed bit is the earliest sign of
//!   a desynchronised stream, and a silently ignored frame would surface later as a
//!   confusing timeout.
//! - **An I frame of length 4 is an error** ([`FrameError::EmptyIFrame`]): the standard
//!   defines the I format as always carrying an ASDU, and lib60870 closes on it too.
//! - **S and U frames with ASDU octets are errors** ([`FrameError::UnexpectedAsdu`]).
//! - **No resynchronisation.** 0x68 can appear inside any ASDU, so after the first error
//!   the stream is unusable and the connection must be closed.

mod deframer;
mod frame;
mod seq;

pub use deframer::Deframer;
pub use frame::{
    encode_i_frame, encode_s_frame, encode_u_frame, Apci, EncodeError, Frame, FrameError,
    FrameFormat, UFunction, APCI_LEN, MAX_APDU_LEN, MAX_ASDU_LEN, MAX_LENGTH, MIN_LENGTH,
    START_BYTE,
};
pub use seq::{SeqNum, SeqNumError};
