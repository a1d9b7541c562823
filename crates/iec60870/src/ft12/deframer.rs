//! Cutting FT1.2 frames out of a serial byte stream.

use thiserror::Error;

use super::frame::{
    checksum, AddressSize, Control, Frame, END, MAX_FRAME_LEN, SINGLE_CHARACTER, START_FIXED,
    START_VARIABLE,
};

/// Accumulates line octets and yields frames, resynchronising after anything broken.
///
/// Unlike TCP, a serial line loses and garbles octets, and a frame boundary can be found
/// again: every frame begins with one of three start characters. Whatever is not a valid
/// frame is reported once as a [`DeframeError`] (the link layer then keeps the line idle
/// for 33 bit times before it transmits, and a primary lets its timer run out and
/// repeats) and skipped up to the next start character after the broken frame's first
/// octet, so a valid frame hidden behind noise or inside a garbled one is still found.
///
/// The buffer never holds more than one maximal frame plus what one push brings;
/// [`Deframer::push`] takes everything, and a partial frame never waits for more than
/// its own length. When the line has been idle for longer than a frame may pause
/// (IEC 60870-5-1 allows no gap inside a frame), the adapter calls
/// [`Deframer::abandon_partial`].
#[derive(Debug, Clone)]
pub struct Deframer {
    address_size: AddressSize,
    buf: Vec<u8>,
}

/// Why octets were skipped.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum DeframeError {
    /// Octets that begin no frame.
    #[error("{octets} octets of line noise")]
    Noise {
        /// How many were skipped.
        octets: usize,
    },
    /// The two length octets of a variable frame differ.
    #[error("variable frame with two different lengths {first} and {second}")]
    LengthMismatch {
        /// The first L.
        first: u8,
        /// The second L.
        second: u8,
    },
    /// L is too small to hold the control field and the address.
    #[error("variable frame length {length} too short for control field and address")]
    LengthTooShort {
        /// The length octet.
        length: u8,
    },
    /// The fourth octet of a variable frame is not the second start character 0x68.
    #[error("variable frame without its second start character (found {found:#04x})")]
    SecondStartMissing {
        /// The octet found instead.
        found: u8,
    },
    /// The checksum does not match.
    #[error("checksum {received:#04x} where the frame sums to {computed:#04x}")]
    Checksum {
        /// The octet received.
        received: u8,
        /// The sum of the frame's octets.
        computed: u8,
    },
    /// The last octet is not the end character 0x16.
    #[error("frame ends with {found:#04x} instead of 0x16")]
    EndMissing {
        /// The octet found instead.
        found: u8,
    },
    /// A frame was cut off by a pause on the line.
    #[error("frame broken off after {octets} octets")]
    Incomplete {
        /// The octets received.
        octets: usize,
    },
}

enum Scan {
    /// The buffer holds a complete frame of this many octets, or a broken one.
    Frame(usize, Frame),
    Broken(DeframeError),
    NeedMore,
}

impl Deframer {
    /// A deframer for a line with this address field size.
    pub fn new(address_size: AddressSize) -> Deframer {
        Deframer {
            address_size,
            buf: Vec::with_capacity(2 * MAX_FRAME_LEN),
        }
    }

    /// The address field size.
    pub fn address_size(&self) -> AddressSize {
        self.address_size
    }

    /// Appends received octets. Call [`Deframer::next_frame`] until it returns `None`.
    pub fn push(&mut self, bytes: &[u8]) {
        self.buf.extend_from_slice(bytes);
    }

    /// Whether part of a frame is buffered.
    pub fn has_partial(&self) -> bool {
        !self.buf.is_empty()
    }

    /// Drops a partial frame after a pause on the line; reports it if there was one.
    pub fn abandon_partial(&mut self) -> Option<DeframeError> {
        if self.buf.is_empty() {
            return None;
        }
        let octets = self.buf.len();
        self.buf.clear();
        Some(DeframeError::Incomplete { octets })
    }

    /// The next frame, `None` when more octets are needed, or an error for octets that
    /// were skipped.
    pub fn next_frame(&mut self) -> Option<Result<Frame, DeframeError>> {
        let noise = self
            .buf
            .iter()
            .position(|octet| matches!(*octet, START_FIXED | START_VARIABLE | SINGLE_CHARACTER))
            .unwrap_or(self.buf.len());
        if noise > 0 {
            self.buf.drain(..noise);
            return Some(Err(DeframeError::Noise { octets: noise }));
        }
        match self.scan() {
            Scan::NeedMore => None,
            Scan::Frame(len, frame) => {
                self.buf.drain(..len);
                Some(Ok(frame))
            }
            Scan::Broken(error) => {
                // Skip the start character only: a good frame may begin inside the broken
                // one (a lost octet shifts everything after it).
                self.buf.drain(..1);
                Some(Err(error))
            }
        }
    }

    fn scan(&self) -> Scan {
        let address_octets = self.address_size.octets();
        let Some(&start) = self.buf.first() else {
            return Scan::NeedMore;
        };
        match start {
            SINGLE_CHARACTER => Scan::Frame(1, Frame::SingleCharacter),
            START_FIXED => {
                let len = 4 + address_octets;
                let Some(frame) = self.buf.get(..len) else {
                    return Scan::NeedMore;
                };
                let body = frame.get(1..len - 2).unwrap_or_default();
                if let Some(error) = check_tail(frame, body) {
                    return Scan::Broken(error);
                }
                let (control, address) = split_control(body, self.address_size);
                Scan::Frame(len, Frame::Fixed { control, address })
            }
            _ => {
                let Some(header) = self.buf.get(..4) else {
                    return match self.buf.get(1..) {
                        Some(&[first, second]) if first != second => {
                            Scan::Broken(DeframeError::LengthMismatch { first, second })
                        }
                        _ => Scan::NeedMore,
                    };
                };
                let (first, second, start_again) = match header {
                    [_, first, second, start_again] => (*first, *second, *start_again),
                    _ => return Scan::NeedMore,
                };
                if first != second {
                    return Scan::Broken(DeframeError::LengthMismatch { first, second });
                }
                if start_again != START_VARIABLE {
                    return Scan::Broken(DeframeError::SecondStartMissing { found: start_again });
                }
                let length = usize::from(first);
                if length < 1 + address_octets {
                    return Scan::Broken(DeframeError::LengthTooShort { length: first });
                }
                let len = 6 + length;
                let Some(frame) = self.buf.get(..len) else {
                    return Scan::NeedMore;
                };
                let body = frame.get(4..4 + length).unwrap_or_default();
                if let Some(error) = check_tail(frame, body) {
                    return Scan::Broken(error);
                }
                let (control, address) = split_control(body, self.address_size);
                let asdu = body.get(1 + address_octets..).unwrap_or_default().to_vec();
                Scan::Frame(
                    len,
                    Frame::Variable {
                        control,
                        address,
                        asdu,
                    },
                )
            }
        }
    }
}

/// Checks the checksum and end character that close `frame` over `body`.
fn check_tail(frame: &[u8], body: &[u8]) -> Option<DeframeError> {
    let [.., received, end] = frame else {
        return Some(DeframeError::Incomplete {
            octets: frame.len(),
        });
    };
    let computed = checksum(body);
    if *received != computed {
        return Some(DeframeError::Checksum {
            received: *received,
            computed,
        });
    }
    if *end != END {
        return Some(DeframeError::EndMissing { found: *end });
    }
    None
}

/// Control field and address at the start of a frame body.
fn split_control(body: &[u8], address_size: AddressSize) -> (Control, u16) {
    let control = Control::from_octet(body.first().copied().unwrap_or_default());
    let address = match address_size {
        AddressSize::None => 0,
        AddressSize::One => u16::from(body.get(1).copied().unwrap_or_default()),
        AddressSize::Two => u16::from_le_bytes([
            body.get(1).copied().unwrap_or_default(),
            body.get(2).copied().unwrap_or_default(),
        ]),
    };
    (control, address)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ft12::frame::{PrimaryFunction, SecondaryFunction};

    fn drain(deframer: &mut Deframer) -> (Vec<Frame>, Vec<DeframeError>) {
        let mut frames = Vec::new();
        let mut errors = Vec::new();
        while let Some(next) = deframer.next_frame() {
            match next {
                Ok(frame) => frames.push(frame),
                Err(error) => errors.push(error),
            }
        }
        (frames, errors)
    }

    fn user_data() -> Frame {
        Frame::Variable {
            control: Control::secondary(SecondaryFunction::UserData, true, false),
            address: 1,
            asdu: vec![0x05, 0x81, 0x04, 0x01, 0xFF, 0x03, 0x02, b'R', b'E', b'F'],
        }
    }

    #[test]
    fn every_split_of_a_stream_gives_the_same_frames() {
        let frames = [
            Frame::Fixed {
                control: Control::primary(PrimaryFunction::RequestClass2, true, true),
                address: 1,
            },
            Frame::SingleCharacter,
            user_data(),
        ];
        let mut stream = Vec::new();
        for frame in &frames {
            frame
                .encode(AddressSize::One, &mut stream)
                .expect("encodes");
        }
        for split in 0..=stream.len() {
            let mut deframer = Deframer::new(AddressSize::One);
            let (head, tail) = stream.split_at(split);
            deframer.push(head);
            let (mut got, errors) = drain(&mut deframer);
            deframer.push(tail);
            let (rest, more_errors) = drain(&mut deframer);
            got.extend(rest);
            assert!(errors.is_empty() && more_errors.is_empty(), "split {split}");
            assert_eq!(got, frames, "split {split}");
            assert!(!deframer.has_partial());
        }
    }

    #[test]
    fn resynchronises_after_every_kind_of_broken_frame() {
        let good = user_data().to_bytes(AddressSize::One).expect("encodes");
        let mut bad_checksum = good.clone();
        let n = bad_checksum.len();
        bad_checksum[n - 2] ^= 0x01;
        let mut bad_end = good.clone();
        bad_end[n - 1] = 0x17;
        let mut bad_length = good.clone();
        bad_length[2] = bad_length[2].wrapping_add(1);
        let mut bad_second_start = good.clone();
        bad_second_start[3] = 0x69;
        let short_length = vec![0x68, 0x01, 0x01, 0x68, 0x08, 0x08, 0x16];
        let mut lost_octet = good.clone();
        lost_octet.remove(7);
        let fixed_bad_sum = vec![0x10, 0x49, 0x01, 0x00, 0x16];
        type Expected = fn(&DeframeError) -> bool;
        let cases: [(&str, Vec<u8>, Expected); 7] = [
            ("checksum", bad_checksum, |e| {
                matches!(e, DeframeError::Checksum { .. })
            }),
            ("end", bad_end, |e| {
                matches!(e, DeframeError::EndMissing { found: 0x17 })
            }),
            ("length", bad_length, |e| {
                matches!(e, DeframeError::LengthMismatch { .. })
            }),
            ("second start", bad_second_start, |e| {
                matches!(e, DeframeError::SecondStartMissing { found: 0x69 })
            }),
            ("short", short_length, |e| {
                matches!(e, DeframeError::LengthTooShort { length: 1 })
            }),
            ("lost octet", lost_octet, |e| {
                matches!(
                    e,
                    DeframeError::Checksum { .. } | DeframeError::EndMissing { .. }
                )
            }),
            ("fixed checksum", fixed_bad_sum, |e| {
                matches!(e, DeframeError::Checksum { .. })
            }),
        ];
        for (name, broken, expected) in cases {
            let mut deframer = Deframer::new(AddressSize::One);
            deframer.push(&[0x00, 0xFF]);
            deframer.push(&broken);
            deframer.push(&good);
            let (frames, errors) = drain(&mut deframer);
            assert_eq!(frames, vec![user_data()], "{name}: {errors:?}");
            assert_eq!(
                errors.first(),
                Some(&DeframeError::Noise { octets: 2 }),
                "{name}"
            );
            assert!(errors.get(1).is_some_and(expected), "{name}: {errors:?}");
            assert!(!deframer.has_partial(), "{name}");
        }
    }

    #[test]
    fn abandoned_partial_frame() {
        let mut deframer = Deframer::new(AddressSize::One);
        deframer.push(&[0x68, 0x09, 0x09, 0x68, 0x28]);
        assert!(deframer.next_frame().is_none());
        assert_eq!(
            deframer.abandon_partial(),
            Some(DeframeError::Incomplete { octets: 5 })
        );
        assert_eq!(deframer.abandon_partial(), None);
        deframer.push(&[0xE5]);
        assert_eq!(deframer.next_frame(), Some(Ok(Frame::SingleCharacter)));
    }

    #[test]
    fn address_sizes() {
        for size in [AddressSize::None, AddressSize::One, AddressSize::Two] {
            let address = match size {
                AddressSize::None => 0,
                AddressSize::One => 0xFE,
                AddressSize::Two => 0x1234,
            };
            let frame = Frame::Variable {
                control: Control::primary(PrimaryFunction::UserDataConfirmed, true, true),
                address,
                asdu: vec![0x64, 0x01, 0x06, 0x01, 0x00, 0x00, 0x14],
            };
            let mut deframer = Deframer::new(size);
            deframer.push(&frame.to_bytes(size).expect("encodes"));
            assert_eq!(deframer.next_frame(), Some(Ok(frame)));
        }
    }
}
