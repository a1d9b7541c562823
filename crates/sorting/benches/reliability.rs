//! The sorter's reliability over seeded sortings of the eight balls on the simulated
//! balance (the scatter of the sorting-lab thesis's table 5.1), with the confusion
//! matrix per colour: weighed at 3 s (the thesis's choice) and at 15 s, by the default
//! contiguous limits (BS-A7) and by the printed ones with their gaps.
//!
//!     cargo bench -p sorting --bench reliability
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::time::Duration;

use sorting::classify::ClassLimits;
use sorting::reliability::simulate;

fn main() {
    let sortings = 8000;
    for (what, after) in [
        ("3 s", Duration::from_secs(3)),
        ("15 s", Duration::from_secs(15)),
    ] {
        for (name, limits) in [
            ("default limits", ClassLimits::DEFAULT),
            ("printed limits", ClassLimits::Printed),
        ] {
            println!("weighed {what} after landing, {name}:");
            print!("{}", simulate(sortings, 1, after, &limits).table());
            println!();
        }
    }
}
