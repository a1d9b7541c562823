//! TPKT (RFC 1006): how ISO transport packets travel over a TCP byte stream.
//!
//! ```text
//! +---------+----------+----------------+----------------------+
//! | version | reserved | length (16 bit)| COTP TPDU            |
//! | 3       | 0        | incl. header   | length - 4 bytes     |
//! +---------+----------+----------------+----------------------+
//! ```
//!
//! TCP carries no boundaries, so a [`Deframer`] buffers what arrives and cuts frames at
//! their length. A wrong version or an impossible length leaves no way to find the next
//! frame: the connection closes.

use thiserror::Error;

/// The only TPKT version.
pub const VERSION: u8 = 3;
/// Version, reserved byte and length.
pub const HEADER_LEN: usize = 4;
/// The shortest frame: the header and a COTP data TPDU header (3 bytes).
pub const MIN_FRAME_LEN: usize = HEADER_LEN + 3;
/// The 16-bit length field's limit.
pub const MAX_FRAME_LEN: usize = 0xFFFF;

/// A TPKT frame that cannot be.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum TpktError {
    /// A version other than 3: not ISO-on-TCP, or the stream lost its framing.
    #[error("TPKT version {0}, expected 3")]
    BadVersion(u8),
    /// A length shorter than a header and the smallest TPDU.
    #[error("TPKT length {0} is shorter than the minimum of 7")]
    BadLength(u16),
    /// A payload too long for the 16-bit length.
    #[error("{0} bytes do not fit a TPKT frame (at most 65531)")]
    TooLong(usize),
}

/// Appends `payload` framed as one TPKT.
pub fn encode(payload: &[u8], out: &mut Vec<u8>) -> Result<(), TpktError> {
    let total = payload.len() + HEADER_LEN;
    let length = u16::try_from(total).map_err(|_| TpktError::TooLong(payload.len()))?;
    out.extend_from_slice(&[VERSION, 0]);
    out.extend_from_slice(&length.to_be_bytes());
    out.extend_from_slice(payload);
    Ok(())
}

/// Cuts TPKT frames out of a byte stream.
#[derive(Debug, Default, Clone)]
pub struct Deframer {
    buffer: Vec<u8>,
}

impl Deframer {
    /// An empty deframer.
    pub fn new() -> Deframer {
        Deframer::default()
    }

    /// Appends received bytes.
    pub fn push(&mut self, bytes: &[u8]) {
        self.buffer.extend_from_slice(bytes);
    }

    /// Bytes received and not yet returned in a frame.
    pub fn buffered(&self) -> usize {
        self.buffer.len()
    }

    /// The payload (the TPDU) of the next complete frame, `None` until one is complete.
    /// After an error the stream cannot be resynchronised: drop the connection.
    pub fn next_frame(&mut self) -> Result<Option<Vec<u8>>, TpktError> {
        let Some(header) = self.buffer.get(..HEADER_LEN) else {
            if let Some(&version) = self.buffer.first() {
                if version != VERSION {
                    return Err(TpktError::BadVersion(version));
                }
            }
            return Ok(None);
        };
        let &[version, _reserved, high, low] = header else {
            return Ok(None);
        };
        if version != VERSION {
            return Err(TpktError::BadVersion(version));
        }
        let length = u16::from_be_bytes([high, low]);
        let frame_len = usize::from(length);
        if frame_len < MIN_FRAME_LEN {
            return Err(TpktError::BadLength(length));
        }
        if self.buffer.len() < frame_len {
            return Ok(None);
        }
        let payload = self
            .buffer
            .get(HEADER_LEN..frame_len)
            .map(<[u8]>::to_vec)
            .unwrap_or_default();
        self.buffer.drain(..frame_len);
        Ok(Some(payload))
    }
}
