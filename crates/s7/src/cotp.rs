//! COTP, the ISO 8073 connection-oriented transport in class 0 as ISO-on-TCP uses it: a
//! connection request and its confirm carrying the TSAPs and the TPDU size, data TPDUs
//! carrying the S7 PDUs, and disconnect and error TPDUs that end a connection.
//!
//! ```text
//! CR/CC: LI | E0/D0 | dst-ref(2) | src-ref(2) | class | params: C0 size, C1 calling, C2 called
//! DT:    LI=2 | F0 | EOT(0x80) + TPDU number | payload (a segment of an S7 PDU)
//! DR:    LI | 80 | dst-ref(2) | src-ref(2) | reason
//! ER:    LI | 70 | dst-ref(2) | cause
//! ```
//!
//! LI, the length indicator, counts the header bytes after itself.

use thiserror::Error;

use crate::tsap::Tsap;
use crate::wire::Reader;

/// TPDU codes (high nibble of the second byte).
pub mod code {
    /// Connection request.
    pub const CONNECTION_REQUEST: u8 = 0xE0;
    /// Connection confirm.
    pub const CONNECTION_CONFIRM: u8 = 0xD0;
    /// Disconnect request.
    pub const DISCONNECT_REQUEST: u8 = 0x80;
    /// Disconnect confirm.
    pub const DISCONNECT_CONFIRM: u8 = 0xC0;
    /// Data.
    pub const DATA: u8 = 0xF0;
    /// TPDU error.
    pub const ERROR: u8 = 0x70;
}

/// Parameter codes of connection TPDUs.
pub mod parameter {
    /// TPDU size, one byte: log2 of the size.
    pub const TPDU_SIZE: u8 = 0xC0;
    /// The calling (client's) TSAP.
    pub const CALLING_TSAP: u8 = 0xC1;
    /// The called (server's) TSAP.
    pub const CALLED_TSAP: u8 = 0xC2;
}

/// The end-of-TSDU mark of a data TPDU: the last segment of an S7 PDU.
pub const EOT: u8 = 0x80;
/// A data TPDU's header with its length indicator.
pub const DATA_HEADER_LEN: usize = 3;

/// The largest TPDU an end takes, header included: 2 to the power of its code, 7..=13.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TpduSize(u8);

impl TpduSize {
    /// 128 bytes: the size when a connection TPDU names none.
    pub const DEFAULT: TpduSize = TpduSize(7);
    /// 1024 bytes: what S7 clients ask, larger than any S7 PDU.
    pub const S7: TpduSize = TpduSize(10);

    /// The size of a parameter value, `None` outside 7..=13 (128..=8192 bytes).
    pub fn from_code(code: u8) -> Option<TpduSize> {
        (7..=13).contains(&code).then_some(TpduSize(code))
    }

    /// The parameter value.
    pub fn code(self) -> u8 {
        self.0
    }

    /// The size in bytes.
    pub fn bytes(self) -> usize {
        1usize << self.0
    }
}

/// The fixed part and the parameters of a connection request or confirm.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConnectionParams {
    /// The destination reference: 0 in a request, the requester's source reference in a
    /// confirm.
    pub dst_ref: u16,
    /// The sender's reference for the connection.
    pub src_ref: u16,
    /// Class and options: 0 for ISO-on-TCP.
    pub class: u8,
    /// The TPDU size asked or granted, if named.
    pub tpdu_size: Option<TpduSize>,
    /// The client's TSAP.
    pub calling_tsap: Option<Tsap>,
    /// The server's TSAP.
    pub called_tsap: Option<Tsap>,
}

/// One COTP TPDU.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Tpdu {
    /// CR, from the client.
    ConnectionRequest(ConnectionParams),
    /// CC, the server's acceptance.
    ConnectionConfirm(ConnectionParams),
    /// DR: the connection ends (or is refused).
    DisconnectRequest {
        /// The receiver's reference.
        dst_ref: u16,
        /// The sender's reference.
        src_ref: u16,
        /// Why.
        reason: u8,
    },
    /// DC, the answer to a DR.
    DisconnectConfirm {
        /// The receiver's reference.
        dst_ref: u16,
        /// The sender's reference.
        src_ref: u16,
    },
    /// DT: a segment of an S7 PDU.
    Data {
        /// The last segment.
        eot: bool,
        /// The TPDU number (7 bits, 0 in class 0).
        number: u8,
        /// The segment.
        payload: Vec<u8>,
    },
    /// ER: the peer rejected a TPDU.
    Error {
        /// The receiver's reference.
        dst_ref: u16,
        /// The reject cause.
        cause: u8,
    },
}

/// A TPDU that cannot be decoded or encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum CotpError {
    /// Fewer bytes than the header needs.
    #[error("truncated COTP TPDU")]
    Truncated,
    /// A length indicator too short for its TPDU type.
    #[error("COTP length indicator {0} is too short")]
    BadLengthIndicator(u8),
    /// A TPDU code class 0 does not have.
    #[error("unknown COTP TPDU code {0:#04x}")]
    UnknownTpdu(u8),
    /// A parameter running past the header.
    #[error("COTP parameter {0:#04x} runs past the header")]
    BadParameter(u8),
    /// A TPDU size parameter outside 7..=13.
    #[error("COTP TPDU size code {0:#04x} outside 0x07..=0x0d")]
    BadTpduSize(u8),
    /// A header or parameter too long to encode.
    #[error("COTP header too long to encode")]
    TooLong,
}

impl Tpdu {
    /// A TPDU from the payload of one TPKT frame.
    pub fn decode(bytes: &[u8]) -> Result<Tpdu, CotpError> {
        let mut reader = Reader::new(bytes);
        let length_indicator = reader.u8().ok_or(CotpError::Truncated)?;
        let header = reader
            .take(usize::from(length_indicator))
            .ok_or(CotpError::Truncated)?;
        let payload = reader.rest();
        let mut header = Reader::new(header);
        let tpdu_code = header
            .u8()
            .ok_or(CotpError::BadLengthIndicator(length_indicator))?;
        let short = CotpError::BadLengthIndicator(length_indicator);
        // CR and CC carry the credit in the low nibble; class 0 has none, so only the
        // high nibble names the TPDU.
        match tpdu_code & 0xF0 {
            code::CONNECTION_REQUEST | code::CONNECTION_CONFIRM => {
                let dst_ref = header.u16().ok_or(short)?;
                let src_ref = header.u16().ok_or(short)?;
                let class = header.u8().ok_or(short)?;
                let mut params = ConnectionParams {
                    dst_ref,
                    src_ref,
                    class,
                    tpdu_size: None,
                    calling_tsap: None,
                    called_tsap: None,
                };
                while let Some(parameter_code) = header.u8() {
                    let len = header.u8().ok_or(CotpError::BadParameter(parameter_code))?;
                    let value = header
                        .take(usize::from(len))
                        .ok_or(CotpError::BadParameter(parameter_code))?;
                    match parameter_code {
                        parameter::TPDU_SIZE => {
                            let &[size_code] = value else {
                                return Err(CotpError::BadParameter(parameter_code));
                            };
                            params.tpdu_size = Some(
                                TpduSize::from_code(size_code)
                                    .ok_or(CotpError::BadTpduSize(size_code))?,
                            );
                        }
                        parameter::CALLING_TSAP => {
                            params.calling_tsap = Some(Tsap::from_bytes(value))
                        }
                        parameter::CALLED_TSAP => {
                            params.called_tsap = Some(Tsap::from_bytes(value))
                        }
                        // Other parameters (checksum, version, additional options) mean
                        // nothing to class 0 over TCP.
                        _ => {}
                    }
                }
                Ok(if tpdu_code & 0xF0 == code::CONNECTION_REQUEST {
                    Tpdu::ConnectionRequest(params)
                } else {
                    Tpdu::ConnectionConfirm(params)
                })
            }
            code::DATA => {
                let number_and_eot = header.u8().ok_or(short)?;
                Ok(Tpdu::Data {
                    eot: number_and_eot & EOT != 0,
                    number: number_and_eot & 0x7F,
                    payload: payload.to_vec(),
                })
            }
            code::DISCONNECT_REQUEST => Ok(Tpdu::DisconnectRequest {
                dst_ref: header.u16().ok_or(short)?,
                src_ref: header.u16().ok_or(short)?,
                reason: header.u8().ok_or(short)?,
            }),
            code::DISCONNECT_CONFIRM => Ok(Tpdu::DisconnectConfirm {
                dst_ref: header.u16().ok_or(short)?,
                src_ref: header.u16().ok_or(short)?,
            }),
            code::ERROR => Ok(Tpdu::Error {
                dst_ref: header.u16().ok_or(short)?,
                cause: header.u8().ok_or(short)?,
            }),
            _ => Err(CotpError::UnknownTpdu(tpdu_code)),
        }
    }

    /// Appends the TPDU (the payload of one TPKT frame).
    pub fn encode(&self, out: &mut Vec<u8>) -> Result<(), CotpError> {
        let mut header = Vec::with_capacity(32);
        match self {
            Tpdu::ConnectionRequest(params) | Tpdu::ConnectionConfirm(params) => {
                header.push(if matches!(self, Tpdu::ConnectionRequest(_)) {
                    code::CONNECTION_REQUEST
                } else {
                    code::CONNECTION_CONFIRM
                });
                header.extend_from_slice(&params.dst_ref.to_be_bytes());
                header.extend_from_slice(&params.src_ref.to_be_bytes());
                header.push(params.class);
                if let Some(size) = params.tpdu_size {
                    header.extend_from_slice(&[parameter::TPDU_SIZE, 1, size.code()]);
                }
                for (parameter_code, tsap) in [
                    (parameter::CALLING_TSAP, &params.calling_tsap),
                    (parameter::CALLED_TSAP, &params.called_tsap),
                ] {
                    if let Some(tsap) = tsap {
                        let len =
                            u8::try_from(tsap.as_bytes().len()).map_err(|_| CotpError::TooLong)?;
                        header.extend_from_slice(&[parameter_code, len]);
                        header.extend_from_slice(tsap.as_bytes());
                    }
                }
            }
            Tpdu::DisconnectRequest {
                dst_ref,
                src_ref,
                reason,
            } => {
                header.push(code::DISCONNECT_REQUEST);
                header.extend_from_slice(&dst_ref.to_be_bytes());
                header.extend_from_slice(&src_ref.to_be_bytes());
                header.push(*reason);
            }
            Tpdu::DisconnectConfirm { dst_ref, src_ref } => {
                header.push(code::DISCONNECT_CONFIRM);
                header.extend_from_slice(&dst_ref.to_be_bytes());
                header.extend_from_slice(&src_ref.to_be_bytes());
            }
            Tpdu::Data { eot, number, .. } => {
                header.push(code::DATA);
                header.push((number & 0x7F) | if *eot { EOT } else { 0 });
            }
            Tpdu::Error { dst_ref, cause } => {
                header.push(code::ERROR);
                header.extend_from_slice(&dst_ref.to_be_bytes());
                header.push(*cause);
            }
        }
        // 255 is reserved as a length indicator.
        let length_indicator = u8::try_from(header.len())
            .ok()
            .filter(|len| *len < 255)
            .ok_or(CotpError::TooLong)?;
        out.push(length_indicator);
        out.extend_from_slice(&header);
        if let Tpdu::Data { payload, .. } = self {
            out.extend_from_slice(payload);
        }
        Ok(())
    }
}
