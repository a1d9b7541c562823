//! Scan jitter: how late each scan of a 10 ms cyclic task starts against its schedule,
//! in real time. Run: `cargo bench -p plc --bench scan_jitter` (10,000 scans, about
//! 100 s) or `... --bench scan_jitter -- --scans 1000` for a shorter run.
//!
//! The task runs two programs: the railway-station lighting function block of the
//! Vsetín example (astronomical clock, time windows, switch-on delay) and 1000 TON/TOF
//! timers pulsing with different periods, counted by typed counters. The driver is the
//! loop a host runs: ask the PLC when its next scan is due ([`plc::Plc::next_due`]),
//! sleep until then (`std::thread::sleep`), read the clock and run the cycle. A scan's
//! *lateness* is the monotonic time at which it starts minus the time it was due (the
//! runtime's own schedule: a scan that starts a whole interval late makes it skip the
//! missed slots, as in the station). Prints p50, p99 and max of the lateness, of the scan
//! times and the slots skipped; it asserts nothing about time.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::disallowed_methods,
    clippy::indexing_slicing
)]

use plc::task::{ClockReading, TaskConfig};
use std::time::{Duration, Instant};

/// The lighting function block, as the Vsetín example project ships it.
const LIGHTING_FB: &str = include_str!("../../../examples/vsetin/plc/osvetleni.st");
/// One instance of it wired to globals (program `Main`).
const LIGHTING: &str = include_str!("../tests/programs/railway_lighting.st");
/// 1000 pulse generators (a TON that restarts itself through a TOF), counted.
const TIMERS: &str = "PROGRAM Timers
VAR
    on : ARRAY[1..1000] OF TON;
    off : ARRAY[1..1000] OF TOF;
    pulses : CTU_DINT;
    i : INT;
    n : DINT;
END_VAR
n := 0;
FOR i := 1 TO 1000 DO
    on[i](IN := NOT off[i].Q, PT := INT_TO_TIME(10 + (i MOD 50) * 10));
    off[i](IN := on[i].Q, PT := T#20ms);
    IF on[i].Q THEN n := n + 1; END_IF
END_FOR
pulses(CU := n > 0, RESET := pulses.CV > 1000000, PV := 1000000);
END_PROGRAM";

const INTERVAL_NS: i64 = 10_000_000;
/// 2024-06-21 12:00 UTC, so the lighting block runs its daytime logic.
const UTC_BASE_NS: i64 = 1_718_971_200_000_000_000;

fn scans_from_args() -> usize {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == "--scans")
        .and_then(|i| args.get(i + 1))
        .map_or(10_000, |n| {
            n.parse()
                .unwrap_or_else(|_| panic!("--scans wants a number, not {n}"))
        })
}

/// The `q`-quantile of sorted values (nearest rank).
fn quantile(sorted: &[i64], q: f64) -> i64 {
    let rank = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len());
    sorted[rank - 1]
}

fn us(ns: i64) -> f64 {
    ns as f64 / 1e3
}

fn main() {
    let scans = scans_from_args();
    let (sources, r) = plc::build(&[
        ("osvetleni.st".into(), LIGHTING_FB.into()),
        ("railway_lighting.st".into(), LIGHTING.into()),
        ("timers.st".into(), TIMERS.into()),
    ]);
    let compiled = r.unwrap_or_else(|d| {
        panic!(
            "{}",
            d.iter()
                .map(|d| d.render(&sources))
                .collect::<Vec<_>>()
                .join("\n")
        )
    });
    let jit_loops = compiled.jit_loops;
    let mut p = plc::Plc::new(compiled, sources);
    p.add_task(TaskConfig::cyclic("main", INTERVAL_NS, &["Main", "Timers"]))
        .unwrap();
    println!(
        "scan jitter: {scans} scans of a {} ms task (lighting FB + 1000 TON/TOF), \
         {jit_loops} loop(s) as machine code; about {:.0} s",
        INTERVAL_NS / 1_000_000,
        scans as f64 * INTERVAL_NS as f64 / 1e9
    );
    let t0 = Instant::now();
    let reading = |at: Instant| {
        let mono = i64::try_from(at.duration_since(t0).as_nanos()).unwrap();
        ClockReading {
            monotonic_ns: mono,
            utc_ns: UTC_BASE_NS + mono,
            utc_offset_ns: 7_200_000_000_000,
        }
    };
    let mut late = Vec::with_capacity(scans);
    let mut run = Vec::with_capacity(scans);
    let mut skipped = 0;
    while late.len() < scans {
        let due = p.next_due().expect("the task stopped");
        let due_at = t0 + Duration::from_nanos(u64::try_from(due).unwrap());
        let now = Instant::now();
        if due_at > now {
            std::thread::sleep(due_at - now);
        }
        let start = Instant::now();
        let faults = p.run_cycle(reading(start));
        let end = Instant::now();
        assert!(faults.is_empty(), "{faults:?}");
        late.push(i64::try_from(start.duration_since(due_at).as_nanos()).unwrap());
        // a scan that starts a whole interval late makes the runtime skip the missed slots
        skipped += (p.next_due().expect("the task stopped") - due) / INTERVAL_NS - 1;
        run.push(i64::try_from(end.duration_since(start).as_nanos()).unwrap());
    }
    late.sort_unstable();
    run.sort_unstable();
    println!(
        "start lateness: p50 {:.1} us, p99 {:.1} us, max {:.1} us",
        us(quantile(&late, 0.5)),
        us(quantile(&late, 0.99)),
        us(quantile(&late, 1.0))
    );
    println!(
        "scan time:      p50 {:.1} us, p99 {:.1} us, max {:.1} us",
        us(quantile(&run, 0.5)),
        us(quantile(&run, 0.99)),
        us(quantile(&run, 1.0))
    );
    println!(
        "scans {}, slots skipped after a late start {skipped}, pulses counted {}",
        late.len(),
        p.read_text("Timers.pulses.CV").unwrap()
    );
}
