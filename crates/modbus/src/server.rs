//! What a server answers to one request PDU, the same for TCP and serial lines but for
//! the unit id's meaning ([`Framing`]).

use crate::model::DataModel;
use crate::pdu::{Answer, ExceptionCode, FunctionCode, Request};

/// The ADU a PDU travels in, which decides what a unit id means to a server.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Framing {
    /// Modbus TCP: the MBAP header. A unit id the model does not serve is answered with
    /// exception 0x0B (gateway target device failed to respond), as a gateway would.
    Tcp,
    /// Modbus RTU: address, PDU, CRC-16. A unit id the model does not serve is another
    /// slave's and is not answered; unit 0 is a broadcast (writes carried out, nothing
    /// answered).
    Rtu,
}

/// How one request was dealt with.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Outcome {
    /// The answer PDU to send: a response or an exception.
    Answer(Vec<u8>),
    /// A serial line's broadcast, carried out (if a valid write) and not answered.
    Broadcast,
    /// Another unit's request on a serial line, not answered.
    NotOurs,
    /// Not a request (no function code, or an exception-range function code): not
    /// answered.
    Ignored,
}

/// Answers the request `pdu` addressed to `unit` from `model`: the state diagrams of the
/// application protocol's section 6 (function, then quantities, then addresses, then
/// execution), with the unit id as `framing` reads it.
pub fn answer(model: &DataModel, framing: Framing, unit: u8, pdu: &[u8]) -> Outcome {
    let Some(&function) = pdu.first() else {
        return Outcome::Ignored;
    };
    if function >= 0x80 {
        return Outcome::Ignored;
    }
    if framing == Framing::Rtu && unit == 0 {
        if let Ok(request) = Request::decode(pdu) {
            model.execute_broadcast(&request);
        }
        return Outcome::Broadcast;
    }
    let function = FunctionCode(function);
    let answer = if !model.serves(unit) {
        if framing == Framing::Rtu {
            return Outcome::NotOurs;
        }
        Answer::Exception(ExceptionCode::GATEWAY_TARGET_FAILED)
    } else {
        match Request::decode(pdu) {
            Ok(request) => match model.execute(unit, &request) {
                Ok(response) => Answer::Response(response),
                Err(code) => Answer::Exception(code),
            },
            Err(error) => match error.exception() {
                Some(code) => Answer::Exception(code),
                None => return Outcome::Ignored,
            },
        }
    };
    let mut out = Vec::new();
    answer.encode(function, &mut out);
    Outcome::Answer(out)
}
