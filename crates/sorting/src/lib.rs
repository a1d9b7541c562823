//! The remote ping-pong-ball sorting lab (the sorting-lab thesis): a PLC weighs each
//! ball on a Sartorius balance and routes it by weight into the shaft of its colour.
//!
//! For now the crate holds the lab's statistics; it will also hold the sorting lab's
//! other parts (the classification of a weight into a colour, batching and routing, the
//! mechanism's simulation), each a module of its own beside [`statistics`].
//!
//! # Layout
//!
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

pub mod statistics;
