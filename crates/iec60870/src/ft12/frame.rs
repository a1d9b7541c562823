//! FT1.2 frames (IEC 60870-5-1 and -2): fixed length, variable length and the single
//! character, with their control field.

use std::fmt;

use thiserror::Error;

/// Start of a fixed-length frame.
pub const START_FIXED: u8 = 0x10;
/// Start of a variable-length frame (sent twice, around the two length octets).
pub const START_VARIABLE: u8 = 0x68;
/// End of fixed- and variable-length frames.
pub const END: u8 = 0x16;
/// The single-character acknowledgement.
pub const SINGLE_CHARACTER: u8 = 0xE5;
/// The largest value of the length octet L: control field, link address and ASDU.
pub const MAX_LENGTH_FIELD: usize = 255;
/// The longest frame: `68 L L 68`, L octets, checksum and end (6 + 255).
pub const MAX_FRAME_LEN: usize = 6 + MAX_LENGTH_FIELD;

/// The size of the link address field: a per-line setting (IEC 101: 0, 1 or 2 octets;
/// IEC 103: 1 octet).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AddressSize {
    /// No address: balanced point-to-point links.
    None,
    /// One octet, broadcast 255.
    One,
    /// Two octets little-endian, broadcast 65535.
    Two,
}

impl AddressSize {
    /// The number of octets.
    pub fn octets(self) -> usize {
        match self {
            AddressSize::None => 0,
            AddressSize::One => 1,
            AddressSize::Two => 2,
        }
    }

    /// The broadcast address of this size (all ones), `None` without an address field.
    pub fn broadcast(self) -> Option<u16> {
        match self {
            AddressSize::None => None,
            AddressSize::One => Some(0xFF),
            AddressSize::Two => Some(0xFFFF),
        }
    }

    /// The size for a number of octets.
    pub fn from_octets(octets: u8) -> Option<AddressSize> {
        match octets {
            0 => Some(AddressSize::None),
            1 => Some(AddressSize::One),
            2 => Some(AddressSize::Two),
            _ => None,
        }
    }

    /// Whether `address` fits this field.
    pub fn fits(self, address: u16) -> bool {
        match self {
            AddressSize::None => address == 0,
            AddressSize::One => address <= 0xFF,
            AddressSize::Two => true,
        }
    }
}

/// Function codes of frames from the primary station (PRM = 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PrimaryFunction {
    /// 0: reset of remote link (103: reset of communication unit).
    ResetRemoteLink,
    /// 1: reset of user process.
    ResetUserProcess,
    /// 2: test function for link (balanced).
    TestLink,
    /// 3: user data, send/confirm.
    UserDataConfirmed,
    /// 4: user data, send/no reply (broadcast).
    UserDataNoReply,
    /// 7: reset of frame count bit (IEC 103).
    ResetFcb,
    /// 8: request for access demand.
    RequestAccessDemand,
    /// 9: request status of link.
    RequestLinkStatus,
    /// 10: request user data class 1.
    RequestClass1,
    /// 11: request user data class 2.
    RequestClass2,
    /// Any other code (5, 6, 12-15: reserved).
    Other(u8),
}

impl PrimaryFunction {
    /// The 4-bit function code.
    pub fn code(self) -> u8 {
        match self {
            PrimaryFunction::ResetRemoteLink => 0,
            PrimaryFunction::ResetUserProcess => 1,
            PrimaryFunction::TestLink => 2,
            PrimaryFunction::UserDataConfirmed => 3,
            PrimaryFunction::UserDataNoReply => 4,
            PrimaryFunction::ResetFcb => 7,
            PrimaryFunction::RequestAccessDemand => 8,
            PrimaryFunction::RequestLinkStatus => 9,
            PrimaryFunction::RequestClass1 => 10,
            PrimaryFunction::RequestClass2 => 11,
            PrimaryFunction::Other(code) => code & 0x0F,
        }
    }

    /// The function of a 4-bit code.
    pub fn from_code(code: u8) -> PrimaryFunction {
        match code & 0x0F {
            0 => PrimaryFunction::ResetRemoteLink,
            1 => PrimaryFunction::ResetUserProcess,
            2 => PrimaryFunction::TestLink,
            3 => PrimaryFunction::UserDataConfirmed,
            4 => PrimaryFunction::UserDataNoReply,
            7 => PrimaryFunction::ResetFcb,
            8 => PrimaryFunction::RequestAccessDemand,
            9 => PrimaryFunction::RequestLinkStatus,
            10 => PrimaryFunction::RequestClass1,
            11 => PrimaryFunction::RequestClass2,
            other => PrimaryFunction::Other(other),
        }
    }

    /// Whether this function goes to the broadcast address without an answer.
    pub fn is_broadcast(self) -> bool {
        matches!(self, PrimaryFunction::UserDataNoReply)
    }

    /// Whether the frame count bit is valid (FCV = 1) for this function: the
    /// send/confirm and request/respond services that a repeat must not execute twice.
    pub fn uses_fcb(self) -> bool {
        matches!(
            self,
            PrimaryFunction::TestLink
                | PrimaryFunction::UserDataConfirmed
                | PrimaryFunction::RequestClass1
                | PrimaryFunction::RequestClass2
        )
    }
}

/// Function codes of frames from the secondary station (PRM = 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SecondaryFunction {
    /// 0: positive acknowledgement.
    Ack,
    /// 1: negative acknowledgement, message not accepted, link busy.
    NackBusy,
    /// 8: user data (the answer to a request for class data).
    UserData,
    /// 9: negative acknowledgement, requested data not available.
    NackNoData,
    /// 11: status of link or access demand.
    LinkStatus,
    /// 14: link service not functioning.
    NotFunctioning,
    /// 15: link service not implemented.
    NotImplemented,
    /// Any other code.
    Other(u8),
}

impl SecondaryFunction {
    /// The 4-bit function code.
    pub fn code(self) -> u8 {
        match self {
            SecondaryFunction::Ack => 0,
            SecondaryFunction::NackBusy => 1,
            SecondaryFunction::UserData => 8,
            SecondaryFunction::NackNoData => 9,
            SecondaryFunction::LinkStatus => 11,
            SecondaryFunction::NotFunctioning => 14,
            SecondaryFunction::NotImplemented => 15,
            SecondaryFunction::Other(code) => code & 0x0F,
        }
    }

    /// The function of a 4-bit code.
    pub fn from_code(code: u8) -> SecondaryFunction {
        match code & 0x0F {
            0 => SecondaryFunction::Ack,
            1 => SecondaryFunction::NackBusy,
            8 => SecondaryFunction::UserData,
            9 => SecondaryFunction::NackNoData,
            11 => SecondaryFunction::LinkStatus,
            14 => SecondaryFunction::NotFunctioning,
            15 => SecondaryFunction::NotImplemented,
            other => SecondaryFunction::Other(other),
        }
    }
}

/// The control field C.
///
/// ```text
/// bit     7         6     5            4            3..0
/// primary RES/DIR   1     FCB          FCV          function
/// second. RES/DIR   0     ACD          DFC          function
/// ```
///
/// Bit 7 is reserved (0) in unbalanced transmission and the direction bit DIR in
/// balanced transmission (1 from the controlling station, 0 from the controlled one).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Control(u8);

impl Control {
    /// A control field from its octet.
    pub fn from_octet(octet: u8) -> Control {
        Control(octet)
    }

    /// A primary control field.
    pub fn primary(function: PrimaryFunction, fcb: bool, fcv: bool) -> Control {
        Control(0x40 | (u8::from(fcb) << 5) | (u8::from(fcv) << 4) | function.code())
    }

    /// A secondary control field.
    pub fn secondary(function: SecondaryFunction, acd: bool, dfc: bool) -> Control {
        Control((u8::from(acd) << 5) | (u8::from(dfc) << 4) | function.code())
    }

    /// The same with the direction bit (balanced transmission) set or cleared.
    pub fn with_dir(self, dir: bool) -> Control {
        Control((self.0 & 0x7F) | (u8::from(dir) << 7))
    }

    /// The octet.
    pub fn octet(self) -> u8 {
        self.0
    }

    /// PRM: the frame comes from the primary (initiating) station.
    pub fn is_primary(self) -> bool {
        self.0 & 0x40 != 0
    }

    /// Bit 7: RES (unbalanced) or DIR (balanced).
    pub fn dir(self) -> bool {
        self.0 & 0x80 != 0
    }

    /// FCB of a primary frame.
    pub fn fcb(self) -> bool {
        self.is_primary() && self.0 & 0x20 != 0
    }

    /// FCV of a primary frame.
    pub fn fcv(self) -> bool {
        self.is_primary() && self.0 & 0x10 != 0
    }

    /// ACD of a secondary frame: class 1 data waiting.
    pub fn acd(self) -> bool {
        !self.is_primary() && self.0 & 0x20 != 0
    }

    /// DFC of a secondary frame: further messages may overflow the secondary.
    pub fn dfc(self) -> bool {
        !self.is_primary() && self.0 & 0x10 != 0
    }

    /// The 4-bit function code.
    pub fn code(self) -> u8 {
        self.0 & 0x0F
    }

    /// The function of a primary frame.
    pub fn primary_function(self) -> PrimaryFunction {
        PrimaryFunction::from_code(self.0)
    }

    /// The function of a secondary frame.
    pub fn secondary_function(self) -> SecondaryFunction {
        SecondaryFunction::from_code(self.0)
    }
}

impl fmt::Display for Control {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.is_primary() {
            write!(
                f,
                "PRM {:?} FCB {} FCV {}",
                self.primary_function(),
                u8::from(self.fcb()),
                u8::from(self.fcv())
            )
        } else {
            write!(
                f,
                "SEC {:?} ACD {} DFC {}",
                self.secondary_function(),
                u8::from(self.acd()),
                u8::from(self.dfc())
            )
        }
    }
}

/// One FT1.2 frame.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Frame {
    /// `10 C A CS 16`: link control, requests and short answers.
    Fixed {
        /// Control field.
        control: Control,
        /// Link address (0 without an address field).
        address: u16,
    },
    /// `68 L L 68 C A ASDU CS 16`: user data.
    Variable {
        /// Control field.
        control: Control,
        /// Link address (0 without an address field).
        address: u16,
        /// The ASDU.
        asdu: Vec<u8>,
    },
    /// `E5`: acknowledgement, or "no data" in place of a fixed frame.
    SingleCharacter,
}

impl Frame {
    /// The control field, `None` for the single character.
    pub fn control(&self) -> Option<Control> {
        match self {
            Frame::Fixed { control, .. } | Frame::Variable { control, .. } => Some(*control),
            Frame::SingleCharacter => None,
        }
    }

    /// The link address, `None` for the single character.
    pub fn address(&self) -> Option<u16> {
        match self {
            Frame::Fixed { address, .. } | Frame::Variable { address, .. } => Some(*address),
            Frame::SingleCharacter => None,
        }
    }

    /// The number of octets on the line.
    pub fn encoded_len(&self, address_size: AddressSize) -> usize {
        match self {
            Frame::Fixed { .. } => 4 + address_size.octets(),
            Frame::Variable { asdu, .. } => 7 + address_size.octets() + asdu.len(),
            Frame::SingleCharacter => 1,
        }
    }

    /// Appends the frame's octets.
    ///
    /// Fails if the address does not fit the field or the ASDU makes L exceed 255.
    pub fn encode(&self, address_size: AddressSize, out: &mut Vec<u8>) -> Result<(), EncodeError> {
        if let Some(address) = self.address() {
            if !address_size.fits(address) {
                return Err(EncodeError::AddressTooLarge {
                    address,
                    octets: address_size.octets(),
                });
            }
        }
        match self {
            Frame::SingleCharacter => out.push(SINGLE_CHARACTER),
            Frame::Fixed { control, address } => {
                let start = out.len();
                out.push(START_FIXED);
                out.push(control.octet());
                push_address(*address, address_size, out);
                let sum = checksum(out.get(start + 1..).unwrap_or_default());
                out.push(sum);
                out.push(END);
            }
            Frame::Variable {
                control,
                address,
                asdu,
            } => {
                let length = 1 + address_size.octets() + asdu.len();
                let length = u8::try_from(length).map_err(|_| EncodeError::TooLong {
                    asdu_len: asdu.len(),
                })?;
                out.extend_from_slice(&[START_VARIABLE, length, length, START_VARIABLE]);
                let start = out.len();
                out.push(control.octet());
                push_address(*address, address_size, out);
                out.extend_from_slice(asdu);
                let sum = checksum(out.get(start..).unwrap_or_default());
                out.push(sum);
                out.push(END);
            }
        }
        Ok(())
    }

    /// The frame's octets.
    pub fn to_bytes(&self, address_size: AddressSize) -> Result<Vec<u8>, EncodeError> {
        let mut out = Vec::with_capacity(self.encoded_len(address_size));
        self.encode(address_size, &mut out)?;
        Ok(out)
    }
}

impl fmt::Display for Frame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Frame::Fixed { control, address } => write!(f, "fixed A {address} {control}"),
            Frame::Variable {
                control,
                address,
                asdu,
            } => write!(
                f,
                "variable A {address} {control} ASDU {} octets",
                asdu.len()
            ),
            Frame::SingleCharacter => f.write_str("single character E5"),
        }
    }
}

fn push_address(address: u16, address_size: AddressSize, out: &mut Vec<u8>) {
    let [low, high] = address.to_le_bytes();
    match address_size {
        AddressSize::None => {}
        AddressSize::One => out.push(low),
        AddressSize::Two => out.extend_from_slice(&[low, high]),
    }
}

/// The FT1.2 checksum: the arithmetic sum modulo 256 of the octets (the serial-line
/// crate's, which devices framed like FT1.2 share).
pub use serial_line::octet_sum as checksum;

/// A frame that cannot be encoded.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum EncodeError {
    /// The link address does not fit the configured field.
    #[error("link address {address} does not fit a {octets}-octet address field")]
    AddressTooLarge {
        /// The address.
        address: u16,
        /// The field size.
        octets: usize,
    },
    /// Control field, address and ASDU exceed the 255 octets L can count.
    #[error("an ASDU of {asdu_len} octets does not fit an FT1.2 frame (L at most 255)")]
    TooLong {
        /// The ASDU length.
        asdu_len: usize,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fixed(control: Control, address: u16) -> Vec<u8> {
        Frame::Fixed { control, address }
            .to_bytes(AddressSize::One)
            .expect("encodes")
    }

    /// The derived frames of spec §6 for link address 1.
    #[test]
    fn fixed_frames_of_the_pcvdew6_session() {
        use PrimaryFunction as P;
        use SecondaryFunction as S;
        let cases: [(Control, [u8; 5]); 12] = [
            (
                Control::primary(P::ResetRemoteLink, false, false),
                [0x10, 0x40, 0x01, 0x41, 0x16],
            ),
            (
                Control::primary(P::RequestLinkStatus, false, false),
                [0x10, 0x49, 0x01, 0x4A, 0x16],
            ),
            (
                Control::primary(P::ResetFcb, false, false),
                [0x10, 0x47, 0x01, 0x48, 0x16],
            ),
            (
                Control::primary(P::RequestClass1, false, true),
                [0x10, 0x5A, 0x01, 0x5B, 0x16],
            ),
            (
                Control::primary(P::RequestClass1, true, true),
                [0x10, 0x7A, 0x01, 0x7B, 0x16],
            ),
            (
                Control::primary(P::RequestClass2, false, true),
                [0x10, 0x5B, 0x01, 0x5C, 0x16],
            ),
            (
                Control::primary(P::RequestClass2, true, true),
                [0x10, 0x7B, 0x01, 0x7C, 0x16],
            ),
            (
                Control::secondary(S::Ack, false, false),
                [0x10, 0x00, 0x01, 0x01, 0x16],
            ),
            (
                Control::secondary(S::Ack, true, false),
                [0x10, 0x20, 0x01, 0x21, 0x16],
            ),
            (
                Control::secondary(S::NackNoData, false, false),
                [0x10, 0x09, 0x01, 0x0A, 0x16],
            ),
            (
                Control::secondary(S::LinkStatus, false, false),
                [0x10, 0x0B, 0x01, 0x0C, 0x16],
            ),
            (
                Control::secondary(S::UserData, true, false),
                [0x10, 0x28, 0x01, 0x29, 0x16],
            ),
        ];
        for (control, bytes) in cases {
            assert_eq!(fixed(control, 1), bytes, "{control}");
        }
    }

    #[test]
    fn control_bits() {
        let c = Control::from_octet(0x7A);
        assert!(c.is_primary() && c.fcb() && c.fcv() && !c.acd() && !c.dfc());
        assert_eq!(c.primary_function(), PrimaryFunction::RequestClass1);
        let s = Control::from_octet(0x38);
        assert!(!s.is_primary() && s.acd() && s.dfc() && !s.fcb());
        assert_eq!(s.secondary_function(), SecondaryFunction::UserData);
        assert_eq!(
            Control::primary(PrimaryFunction::TestLink, true, true)
                .with_dir(true)
                .octet(),
            0xF2
        );
    }

    #[test]
    fn variable_frame_layout() {
        let frame = Frame::Variable {
            control: Control::secondary(SecondaryFunction::UserData, true, false),
            address: 1,
            asdu: vec![0x08, 0x81, 0x0A, 0x01, 0xFF, 0x00, 0x02],
        };
        let bytes = frame.to_bytes(AddressSize::One).expect("encodes");
        assert_eq!(
            bytes,
            [
                0x68, 0x09, 0x09, 0x68, 0x28, 0x01, 0x08, 0x81, 0x0A, 0x01, 0xFF, 0x00, 0x02, 0xBE,
                0x16
            ]
        );
        assert_eq!(bytes.len(), frame.encoded_len(AddressSize::One));
    }

    #[test]
    fn limits() {
        let too_long = Frame::Variable {
            control: Control::primary(PrimaryFunction::UserDataConfirmed, true, true),
            address: 1,
            asdu: vec![0; 254],
        };
        assert!(matches!(
            too_long.to_bytes(AddressSize::One),
            Err(EncodeError::TooLong { asdu_len: 254 })
        ));
        let longest = Frame::Variable {
            control: Control::primary(PrimaryFunction::UserDataConfirmed, true, true),
            address: 1,
            asdu: vec![0; 253],
        };
        assert_eq!(
            longest.to_bytes(AddressSize::One).expect("fits").len(),
            MAX_FRAME_LEN
        );
        assert!(Frame::Fixed {
            control: Control::from_octet(0x49),
            address: 256
        }
        .to_bytes(AddressSize::One)
        .is_err());
        let two = Frame::Fixed {
            control: Control::from_octet(0x49),
            address: 0x1234,
        }
        .to_bytes(AddressSize::Two)
        .expect("fits");
        assert_eq!(two, [0x10, 0x49, 0x34, 0x12, 0x8F, 0x16]);
    }
}
