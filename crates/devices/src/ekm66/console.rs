//! The operations a person (or a test) performs on a simulated board: inject a fault,
//! hold a status, call the car, cut the cable. One list for `stanice lift simulate`'s
//! console and the station's simulated lifts (`lift L1 fault 3C`).

use super::simulator::Simulator;
use super::tables::status_text;

/// What the operations are, for a `help` line.
pub const HELP: &str = concat!(
    "  fault CODE        store a fault now, CODE in hex as in Appendix B: fault 3C\n",
    "  status CODE       show a status code (decimal, Appendix A) until `status auto`: status 18\n",
    "  status auto       back to the status the lift's operation gives\n",
    "  trip FLOOR        call the car to a floor\n",
    "  silent | answer   stop answering queries (a broken cable) | answer again\n",
    "  clear             clear the fault log\n",
    "  show              status, doors, fault stack"
);

fn parse_hex(word: &str) -> Option<u8> {
    let digits = word
        .strip_prefix("0x")
        .or_else(|| word.strip_prefix("0X"))
        .unwrap_or(word);
    u8::from_str_radix(digits, 16).ok()
}

/// Performs one operation (`words` as typed, e.g. `["fault", "3C"]`); what happened, or
/// why nothing did.
pub fn operate(simulator: &mut Simulator, words: &[&str]) -> Result<String, String> {
    match words {
        ["fault", code] => match parse_hex(code) {
            Some(code) => {
                let record = simulator.inject_fault(code);
                Ok(format!(
                    "injected fault 0x{:02X} at index {}",
                    record.code, record.index
                ))
            }
            None => Err(format!("not a fault code: {code} (hex, e.g. 3C)")),
        },
        ["status", "auto"] => {
            simulator.release_status();
            Ok("status from the lift's operation again".to_owned())
        }
        ["status", code] => match code.parse::<u8>() {
            Ok(code) => {
                simulator.hold_status(code);
                Ok(format!("holding status {code} {}", status_text(code)))
            }
            Err(_) => Err(format!("not a status code: {code} (decimal, e.g. 18)")),
        },
        ["trip", floor] => match floor.parse::<u8>() {
            Ok(floor) if simulator.request_trip(floor) => Ok(format!("called to floor {floor}")),
            _ => Err(format!(
                "no floor {floor} (1..={})",
                simulator.config().floors
            )),
        },
        ["silent"] => {
            simulator.set_silent(true);
            Ok("not answering".to_owned())
        }
        ["answer"] => {
            simulator.set_silent(false);
            Ok("answering".to_owned())
        }
        ["clear"] => {
            simulator.clear_log();
            Ok("fault log cleared".to_owned())
        }
        ["show"] => {
            let status = simulator.status();
            let memory = simulator.memory();
            let stored = memory.slots.iter().filter(|slot| slot.is_some()).count();
            // In words, not Rust structures ("last at slot Some(1)" was shown).
            let last = memory
                .last
                .map_or_else(|| "none".to_owned(), |slot| format!("slot {slot}"));
            let trips: Vec<String> = memory.counters.iter().map(u32::to_string).collect();
            Ok(format!(
                "status {} {}, floor {}, target {}, {}, doors {}, board time {} (the board's clock, no zone), {} faults stored, the last in {last}, trips per floor {}",
                status.code,
                status_text(status.code),
                status.position,
                status.target,
                status.direction,
                simulator.doors(),
                simulator.board_time().format("%Y-%m-%d %H:%M:%S"),
                stored,
                trips.join(" ")
            ))
        }
        _ => Err(format!(
            "unknown operation `{}`; the operations:\n{HELP}",
            words.join(" ")
        )),
    }
}
