//! The remote ping-pong-ball sorting lab (the sorting-lab thesis): a PLC weighs each
//! ball on a Sartorius balance and routes it by weight into the shaft of its colour.
//!
//! The crate holds the lab's statistics, the classification of a weight into a colour,
//! the reliability of sorting measured on the simulated balance, and the lab itself on
//! one simulated clock: the supervisor and the sorting program on the soft PLC driving
//! the mechanism (`plant::sorter`).
//!
//! # Layout
//!
//! - [`classify`]: FC1, a weight to a colour by the printed limits (with their gaps) or
//!   the default contiguous ones (BS-A7).
//! - [`programs`]: the supervisor and the reference sorting program, built in.
//! - [`rig`]: the sorting PLC (10-ms scans) behind the supervisor (30-ms scans, sampling
//!   its commands) driving the mechanism; the supervisor's refusals and lock-outs as
//!   events; automatic sortings and their reliability over seeded mechanisms.
//! - [`trial`]: a student's program tried behind the supervisor: the report of
//!   `stanice sorting run` and of the web HMI's Program page.
//! - `hmi_trial` (feature `hmi`): that trial behind the web HMI's `ProgramTrial`, and
//!   the student's program loaded into the running lab's node (the station's
//!   `ProgramLoader`).
//! - [`reliability`]: seeded sortings of the eight balls on the simulated balance, a
//!   confusion matrix per colour.
//! - [`statistics`]: from weighings to class limits (the sorting-lab thesis,
//!   section 12): the sample statistics of each ball, the confidence interval of its mean
//!   and the upper bound of its scatter, coverage intervals, the colours' unions, the
//!   decision limits between neighbouring colours and the sorting reliability to expect;
//!   a hand-written SVG plot for teaching.
//!   - [`statistics::samples`]: the weighings as CSV (`ball,weight_g`), read and written.
//!   - [`statistics::quantile`]: confidence and coverage levels; the Student t,
//!     chi-square and normal quantiles (statrs).
//!   - [`statistics::estimate`]: one ball's n, mean, S, the interval of μ and σ's upper
//!     bound (formulas 5.1-5.4); synthetic samples with a given mean and S.
//!   - [`statistics::limits`]: coverage intervals, colour unions, decision limits,
//!     reliability.
//!   - [`statistics::plot`]: the balls' normal densities and the limits as SVG.
//!
//! # Data flow
//!
//! ```text
//! CSV text --samples::Samples::from_csv--> Samples (ball -> weighings, lines kept for errors)
//!   --estimate::BallStatistics::estimate(confidence)--> per ball: n, X̄, S, ⟨μ_d, μ_h⟩, σ_upper
//!   --limits::Thresholds::derive(coverage, outer limits)-->
//!        per ball: coverage ⟨μ_d − z·σ_upper, μ_h + z·σ_upper⟩
//!        per colour: union of its balls' coverage, ordered by mean
//!        limits: midway between neighbouring unions; decision interval per colour
//!        reliability: P(a weighing of the ball falls in its colour's decision interval)
//!   --> `stanice stats thresholds` (table or JSON) and plot::svg (densities and limits)
//! ```
//!
//! Nothing here reads a clock, a file or a terminal: text in, values and text out.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]

pub mod classify;
#[cfg(feature = "hmi")]
pub mod hmi_trial;
pub mod programs;
pub mod reliability;
pub mod rig;
pub mod statistics;
pub mod trial;
