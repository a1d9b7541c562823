//! `stanice iec104 decode`: APDUs (or bare ASDUs) from hex to a readable analysis.
//!
//! The hex may be split over arguments and contain spaces, colons or `0x` prefixes.
//! Several APDUs in a row are decoded one after another; a broken one is reported and
//! the decoder resynchronises on the next start byte, so one bad frame in a capture does
//! not hide the rest. Non-standard content (causes such as 0, unknown types) is shown,
//! not refused.

use std::process::ExitCode;

use anyhow::bail;
use clap::Args;
use iec60870::apci::{Apci, Frame};
use iec60870::asdu::{Asdu, AsduHeader, AsduParams};

/// Arguments of `stanice iec104 decode`.
#[derive(Args, Debug)]
pub(crate) struct DecodeArgs {
    /// Hex bytes, e.g. `68 04 07 00 00 00` or `680407000000`.
    #[arg(required = true, num_args = 1..)]
    hex: Vec<String>,
    /// The bytes are one bare ASDU (no APCI).
    #[arg(long)]
    asdu: bool,
    /// Octets of the cause of transmission (1 or 2).
    #[arg(long, default_value_t = 2)]
    cot_size: u8,
    /// Octets of the common address (1 or 2).
    #[arg(long, default_value_t = 2)]
    ca_size: u8,
    /// Octets of the information object address (1, 2 or 3).
    #[arg(long, default_value_t = 3)]
    ioa_size: u8,
    /// One JSON object per APDU (`offset`, `hex`, `apci`, `objects` as the client prints
    /// them, or `error`) instead of the analysis text.
    #[arg(long)]
    json: bool,
}

pub(crate) fn run(args: &DecodeArgs) -> anyhow::Result<ExitCode> {
    let bytes = parse_hex(&args.hex.join(" "))?;
    let params = AsduParams::try_new(args.cot_size, args.ca_size, args.ioa_size, 255)
        .map_err(|error| anyhow::anyhow!("field sizes: {error}"))?;
    if args.json {
        let (lines, clean) = if args.asdu {
            let (value, clean) = asdu_json(&bytes, &params);
            (vec![value], clean)
        } else {
            apdus_json(&bytes, &params)
        };
        let lines: Vec<String> = lines.iter().map(serde_json::Value::to_string).collect();
        crate::console::print_lines(&lines);
        return Ok(if clean {
            ExitCode::SUCCESS
        } else {
            ExitCode::from(1)
        });
    }
    let mut out = String::new();
    let clean = if args.asdu {
        describe_asdu(&bytes, &params, &mut out)
    } else {
        describe_apdus(&bytes, &params, &mut out)
    };
    print!("{out}");
    Ok(if clean {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// Parses hex text, ignoring separators and `0x` prefixes.
pub(crate) fn parse_hex(text: &str) -> anyhow::Result<Vec<u8>> {
    let cleaned: String = text
        .replace("0x", " ")
        .replace("0X", " ")
        .chars()
        .filter(|c| !matches!(c, ' ' | ':' | ',' | '-' | '\n' | '\t' | '\r'))
        .collect();
    if cleaned.len() % 2 != 0 {
        bail!("odd number of hex digits");
    }
    let mut bytes = Vec::with_capacity(cleaned.len() / 2);
    for index in (0..cleaned.len()).step_by(2) {
        let pair = cleaned.get(index..index + 2).unwrap_or_default();
        let byte = u8::from_str_radix(pair, 16)
            .map_err(|_| anyhow::anyhow!("'{pair}' is not a hex byte"))?;
        bytes.push(byte);
    }
    if bytes.is_empty() {
        bail!("no bytes given");
    }
    Ok(bytes)
}

fn hex(bytes: &[u8]) -> String {
    bytes
        .iter()
        .map(|byte| format!("{byte:02X}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The bytes of the APDU `rest` starts with, as its length octet says (all of `rest`
/// when it is no complete APDU: the decoder then says why).
fn frame_at(rest: &[u8]) -> &[u8] {
    match rest.get(1).map(|length| usize::from(*length) + 2) {
        Some(length) if rest.first() == Some(&0x68) && rest.len() >= length => {
            rest.get(..length).unwrap_or(rest)
        }
        _ => rest,
    }
}

/// How far to skip after a broken APDU: to the next start byte, to resynchronise.
fn next_start(rest: &[u8]) -> usize {
    rest.iter()
        .skip(1)
        .position(|byte| *byte == 0x68)
        .map_or(rest.len(), |offset| offset + 1)
}

/// Writes the analysis of a run of APDUs; returns whether all were well formed.
pub(crate) fn describe_apdus(bytes: &[u8], params: &AsduParams, out: &mut String) -> bool {
    use std::fmt::Write;
    let mut clean = true;
    let mut position = 0usize;
    let mut number = 0usize;
    while position < bytes.len() {
        let rest = bytes.get(position..).unwrap_or_default();
        number += 1;
        let frame_bytes = frame_at(rest);
        let _ = writeln!(
            out,
            "APDU {number} at offset {position}: {}",
            hex(frame_bytes)
        );
        match Frame::decode(frame_bytes) {
            Ok(frame) => {
                match frame.apci {
                    Apci::I { send_seq, recv_seq } => {
                        let _ = writeln!(
                            out,
                            "  I-format  N(S)={} N(R)={}",
                            send_seq.value(),
                            recv_seq.value()
                        );
                    }
                    Apci::S { recv_seq } => {
                        let _ = writeln!(out, "  S-format  N(R)={}", recv_seq.value());
                    }
                    Apci::U(function) => {
                        let _ = writeln!(out, "  U-format  {function}");
                    }
                }
                if !frame.asdu.is_empty() && !describe_asdu(frame.asdu, params, out) {
                    clean = false;
                }
                position += frame_bytes.len();
            }
            Err(error) => {
                clean = false;
                let _ = writeln!(out, "  malformed: {error}");
                position += next_start(rest);
            }
        }
    }
    clean
}

/// The APDUs of `bytes` as JSON objects (as [`describe_apdus`] walks them, resynchronising
/// after a broken one); returns whether all were well formed.
fn apdus_json(bytes: &[u8], params: &AsduParams) -> (Vec<serde_json::Value>, bool) {
    use serde_json::json;
    let mut clean = true;
    let mut position = 0usize;
    let mut out = Vec::new();
    while position < bytes.len() {
        let rest = bytes.get(position..).unwrap_or_default();
        let frame_bytes = frame_at(rest);
        let mut line = json!({"offset": position, "hex": hex(frame_bytes)});
        match Frame::decode(frame_bytes) {
            Ok(frame) => {
                line["apci"] = match frame.apci {
                    Apci::I { send_seq, recv_seq } => json!({
                        "format": "I", "send_seq": send_seq.value(), "recv_seq": recv_seq.value()
                    }),
                    Apci::S { recv_seq } => json!({"format": "S", "recv_seq": recv_seq.value()}),
                    Apci::U(function) => json!({"format": "U", "function": function.to_string()}),
                };
                if !frame.asdu.is_empty() {
                    let (asdu, asdu_clean) = asdu_json(frame.asdu, params);
                    clean &= asdu_clean;
                    line["asdu"] = asdu;
                }
                position += frame_bytes.len();
            }
            Err(error) => {
                clean = false;
                line["error"] = json!(error.to_string());
                position += next_start(rest);
            }
        }
        out.push(line);
    }
    (out, clean)
}

/// One ASDU as JSON: its objects as the client prints them, or the error; and whether
/// it decoded cleanly.
fn asdu_json(bytes: &[u8], params: &AsduParams) -> (serde_json::Value, bool) {
    use serde_json::json;
    match Asdu::decode(bytes, params) {
        Ok(asdu) => {
            let objects: Vec<serde_json::Value> = asdu
                .objects
                .iter()
                .map(|object| {
                    let mut value = super::render::object_json(&asdu, object);
                    // Decoded from a log: no receipt of ours to tell.
                    if let Some(map) = value.as_object_mut() {
                        map.remove("received");
                    }
                    value
                })
                .collect();
            (
                json!({"type": asdu.type_id.mnemonic(), "cot": asdu.cot.cause.name(), "ca": asdu.common_address.get(), "objects": objects}),
                true,
            )
        }
        Err(error) => (
            json!({"error": error.to_string(), "hex": hex(bytes)}),
            false,
        ),
    }
}

/// Writes the analysis of one ASDU; returns whether it decoded cleanly.
pub(crate) fn describe_asdu(bytes: &[u8], params: &AsduParams, out: &mut String) -> bool {
    use std::fmt::Write;
    match Asdu::decode(bytes, params) {
        Ok(asdu) => {
            for line in asdu.to_string().lines() {
                let _ = writeln!(out, "  {line}");
            }
            true
        }
        Err(error) => {
            match AsduHeader::decode(bytes, params) {
                Ok(header) => {
                    let _ = writeln!(
                        out,
                        "  type {} sq={} n={} cot={} ca={}",
                        header.type_byte,
                        u8::from(header.sequence),
                        header.count,
                        header.cot.cause,
                        header.common_address
                    );
                }
                Err(_) => {
                    let _ = writeln!(out, "  ASDU too short for a header");
                }
            }
            let _ = writeln!(out, "  ASDU not decodable: {error}");
            false
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decodes_the_double_point_of_the_thesis_log() {
        let bytes =
            parse_hex("68 15 00 00 00 00 1F 01 03 00 01 00 D0 07 00 01 D8 76 BB 09 1A 04 11")
                .unwrap();
        let mut out = String::new();
        assert!(describe_apdus(&bytes, &AsduParams::IEC104, &mut out));
        assert!(out.contains("M_DP_TB_1"), "{out}");
        assert!(out.contains("2000"), "{out}");
    }

    #[test]
    fn reports_a_broken_frame_and_goes_on() {
        let bytes = parse_hex("68 04 07 00 00 FF 68 04 0B 00 00 00").unwrap();
        let mut out = String::new();
        assert!(!describe_apdus(&bytes, &AsduParams::IEC104, &mut out));
        assert!(out.contains("malformed"), "{out}");
        assert!(out.contains("U-format"), "{out}");
    }

    #[test]
    fn rejects_bad_hex() {
        assert!(parse_hex("6").is_err());
        assert!(parse_hex("zz").is_err());
        assert_eq!(parse_hex("0x68,0x04").unwrap(), vec![0x68, 0x04]);
    }
}
