//! Each lab model with its reference program for one simulated hour at `--speed max`:
//! the speed-up over real time (the target is at least 1,000x) and scans per second.
//!
//!     cargo bench -p lab --bench hour
//!
//! Figures, not assertions: the machine's load decides them. The four models run one after
//! the other in one process, so their figures compare side by side.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::Path;
use std::time::{Duration, Instant};

use lab::run::DEFAULT_SCAN;
use lab::{Program, RunSettings, Session, Speed};
use plant::lab::{LabOptions, Profile};

fn main() {
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/lab");
    let hour = Duration::from_secs(3600);
    println!("model       simulated  wall s   speed-up   scans/s    violations");
    for model in plant::lab::MODELS {
        let program = Program::load(&[examples.join(format!("{model}.st"))], None).unwrap();
        let settings = RunSettings {
            model: (*model).to_owned(),
            profile: Profile::Model,
            options: LabOptions::default(),
            duration: hour,
            scan: DEFAULT_SCAN,
            speed: Speed::Max,
        };
        let started = Instant::now();
        let report = Session::new(program, settings, None)
            .unwrap()
            .run()
            .unwrap();
        let wall = started.elapsed().as_secs_f64();
        println!(
            "{model:<10}  {:>7.0} s  {wall:>6.3}  {:>8.0}x  {:>9.0}  {:>10}",
            report.simulated_s,
            report.simulated_s / wall,
            report.scans as f64 / wall,
            report.violations_total
        );
    }
}
