//! One FT1.2 primary polling 31 protection relays on one simulated 19200 Bd line.
//!
//! ```text
//! cargo bench -p iec60870 --bench ft12_polling
//! ```
//!
//! The line is timed as a real one would be (11 bits a character, 33 bit times of idle
//! before every frame, the relay answering as soon as the idle time allows), on a
//! virtual clock, so a cycle of 31 relays is measured in line time without waiting for
//! it. Printed:
//!
//! - the poll cycle time (every relay asked for class 2 and answered with its
//!   measurands, ASDU 9 with nine values), against the line's theoretical minimum for
//!   the same octets and idle times, as a ratio (1.00 = no time lost by the primary);
//! - the same with one relay dead (each of its attempts costs a response timeout, but
//!   only once per retry interval);
//! - CPU time per relay poll (primary, secondaries and the line model together) and the
//!   share of one core the primary would need to keep the line busy.
#![allow(
    clippy::expect_used,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::disallowed_methods
)]
#![allow(missing_docs)]

use std::time::{Duration, Instant};

use iec60870::ft12::*;
use iec60870::iec103::{Asdu, Body, Cause, Measurand, INF_MEASURANDS_II};

const RELAYS: u16 = 31;
const BAUD: u32 = 19200;
const CYCLES: u64 = 200;

/// A relay answering every class 2 poll with its nine measurands (ASDU 9, INF 148).
struct Measurands {
    address: u8,
}

impl SecondaryApplication for Measurands {
    fn link_reset(&mut self, _function: PrimaryFunction) {}
    fn user_data(&mut self, _asdu: &[u8], _broadcast: bool) -> bool {
        true
    }
    fn has_class1(&self) -> bool {
        false
    }
    fn class1(&mut self) -> Option<Vec<u8>> {
        None
    }
    fn class2(&mut self) -> Option<Vec<u8>> {
        // Measurands II as the REF630 sends them: 1.0 x rated current, 1.0 x rated voltage.
        let values = [2.4, 2.4, 2.4, 1.2, 1.2, 1.2, 2.4, 2.4, 1.2]
            .iter()
            .enumerate()
            .map(|(index, limit)| {
                Measurand::from_physical(if index < 6 { 1.0 } else { 0.0 }, *limit)
            })
            .collect();
        Asdu::new(
            9,
            Cause::CYCLIC,
            self.address,
            1,
            INF_MEASURANDS_II,
            Body::Measurands(values),
        )
        .to_bytes()
        .ok()
    }
}

fn line(dead: Option<u16>) -> SimulatedLine {
    let start = Instant::now();
    let settings = LineSettings::new(BAUD);
    let mut primary = Primary::new(
        PrimaryConfig {
            line: settings,
            response_timeout: Duration::from_millis(100),
            retries: 1,
            failed_retry_interval: Duration::from_secs(30),
            ..PrimaryConfig::default()
        },
        start,
    );
    for address in 1..=RELAYS {
        primary.add_station(address).unwrap();
    }
    let mut line = SimulatedLine::new(primary, start, settings.idle_time());
    for address in 1..=RELAYS {
        line.attach(
            Secondary::new(SecondaryConfig::new(address)),
            Box::new(Measurands {
                address: u8::try_from(address).unwrap(),
            }),
        );
    }
    if let Some(address) = dead {
        line.set_alive(address, false);
    }
    line
}

/// Steps until every live relay has been polled `cycles` more times; returns the virtual
/// time taken and the CPU time spent.
fn run_cycles(line: &mut SimulatedLine, cycles: u64, live: &[u16]) -> (Duration, Duration) {
    let polls = |line: &mut SimulatedLine| -> Vec<u64> {
        live.iter()
            .map(|address| line.primary().stats(*address).unwrap().class2_polls)
            .collect()
    };
    let before = polls(line);
    let virtual_start = line.now();
    let cpu_start = Instant::now();
    for _ in 0..10_000_000u64 {
        line.step();
        while line.primary().poll_event().is_some() {}
        let now = polls(line);
        if now
            .iter()
            .zip(&before)
            .all(|(now, before)| *now >= before + cycles)
        {
            break;
        }
    }
    (line.now() - virtual_start, cpu_start.elapsed())
}

fn main() {
    let settings = LineSettings::new(BAUD);
    let request_octets = 5;
    let answer_octets = 8 + 6 + 2 * 9;
    let per_relay =
        settings.transmit_time(request_octets + answer_octets) + settings.idle_time() * 2;
    let minimum = per_relay * u32::from(RELAYS);
    println!(
        "FT1.2 polling benchmark: {RELAYS} relays on one {settings} line, class 2 polls answered with ASDU 9 (9 measurands)"
    );
    println!(
        "line minimum per relay: request {request_octets} + answer {answer_octets} octets + 2 x 33 bit idle = {:.2} ms",
        per_relay.as_secs_f64() * 1e3
    );

    let all: Vec<u16> = (1..=RELAYS).collect();
    let mut healthy = line(None);
    run_cycles(&mut healthy, 1, &all); // start-up: status and reset of every relay
    let (elapsed, cpu) = run_cycles(&mut healthy, CYCLES, &all);
    let cycle = elapsed / u32::try_from(CYCLES).unwrap();
    println!(
        "poll cycle, all answering:  {:8.2} ms   theoretical minimum {:8.2} ms   ratio {:.3}",
        cycle.as_secs_f64() * 1e3,
        minimum.as_secs_f64() * 1e3,
        cycle.as_secs_f64() / minimum.as_secs_f64()
    );
    let polls = CYCLES * u64::from(RELAYS);
    let cpu_per_poll = cpu / u32::try_from(polls).unwrap();
    println!(
        "CPU per relay poll:         {:8.2} us   ({:.4} % of one core to keep the line busy)",
        cpu_per_poll.as_secs_f64() * 1e6,
        100.0 * cpu.as_secs_f64() / elapsed.as_secs_f64()
    );

    let live: Vec<u16> = (1..RELAYS).collect();
    let mut one_dead = line(Some(RELAYS));
    run_cycles(&mut one_dead, 1, &live);
    let (elapsed, _) = run_cycles(&mut one_dead, CYCLES, &live);
    let cycle_dead = elapsed / u32::try_from(CYCLES).unwrap();
    let minimum_live = per_relay * u32::from(RELAYS - 1);
    println!(
        "poll cycle, relay {RELAYS} dead:    {:8.2} ms   minimum for the 30 live {:8.2} ms   ratio {:.3} (retry of the dead one every 30 s, 2 attempts of 100 ms)",
        cycle_dead.as_secs_f64() * 1e3,
        minimum_live.as_secs_f64() * 1e3,
        cycle_dead.as_secs_f64() / minimum_live.as_secs_f64()
    );
}
