//! The reference sorting program's reliability on the whole simulated lab: 1,000
//! automatic sortings from power-on (initialisation, batching, weighing 3 s, routing by
//! the deflector cascade), the program behind the supervisor on the soft PLC, each on a
//! mechanism seeded anew (the balls' order, the deflectors at power-on, the balance's
//! errors). Prints the confusion matrix per colour (true colour x the colour of the
//! shaft the ball ended in), the share of sortings with all eight balls right, the
//! supervisor's refusals and the simulated and wall time.
//!
//!     cargo bench -p sorting --bench mechanism [-- SORTINGS]
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use sorting::rig::mechanism_reliability;

fn main() {
    let sortings: u64 = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(1000);
    let build = || {
        Ok((
            sorting::programs::reference_sorter().unwrap(),
            sorting::programs::supervisor().unwrap(),
        ))
    };
    #[allow(clippy::disallowed_methods, reason = "a benchmark's wall time")]
    let started = std::time::Instant::now();
    let report = mechanism_reliability(sortings, 1, build).unwrap();
    let wall = started.elapsed();
    println!(
        "{sortings} automatic sortings of the eight balls, reference program, seeds 1..{sortings}:"
    );
    print!("{}", report.confusion.table());
    println!(
        "all eight right: {} of {} sortings ({:.2} %); unfinished: {}; supervisor refusals and lock-outs: {}",
        report.all_right,
        report.sortings,
        100.0 * report.all_right as f64 / report.sortings.max(1) as f64,
        report.unfinished,
        report.supervisor_events
    );
    let simulated = report.mean_time.as_secs_f64() * sortings as f64;
    println!(
        "mean sorting {:.1} s simulated; {:.1} s wall for {:.0} s simulated ({:.0}x real time)",
        report.mean_time.as_secs_f64(),
        wall.as_secs_f64(),
        simulated,
        simulated / wall.as_secs_f64().max(1e-9)
    );
}
