//! Trends downsampled in the store: one point's numeric values over a time range, folded
//! into at most so many buckets (one per pixel column of a chart), each with its minimum,
//! maximum and mean, so that 60 days of a measurement every few seconds (a million
//! rows) reach a chart as a few thousand numbers.

use chrono::{DateTime, Utc};

/// The most buckets one trend query may ask for.
pub const MAX_TREND_BUCKETS: usize = 20_000;

/// The span the store keeps rollups of: per point and minute, the first and last time and
/// value, min, max, sum, count and IV of its values, folded by the history's passes
/// (schema versions 4 to 6). One span only: each rollup row costs every append that
/// opens it (a point changing every few minutes opens one per event), and a year of
/// minutes (525,600 rows of a point changing every minute) still reads in a fraction of a
/// second.
pub const ROLLUP_SPAN_MS: i64 = 60_000;

/// An aggregated bucket at least this many rollup spans wide is read from the rollups:
/// its edges then move by less than a quarter of its width (to the minutes' starts).
const SPANS_PER_BUCKET: i64 = 4;

/// How a trend query folds a bucket.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub enum TrendMode {
    /// Every value of the bucket: min, max, mean, count (exact extremes). Buckets of four
    /// minutes or more are read from the store's minute rollups (a cost that grows with
    /// the range's minutes, not its events: see [`TrendQuery::rollup_span_ms`]); narrower
    /// ones from every event of the range.
    #[default]
    Aggregate,
    /// The bucket's first and last value. Buckets of four minutes or more are read from
    /// the rollups, which keep each minute's first and last value (schema version 5):
    /// the bucket's `min`/`max`/`avg`/`count` are then exact as in
    /// [`TrendMode::Aggregate`]. Narrower ones are folded from every event of the range,
    /// exact as well.
    FirstLast,
}

/// A trend query: `point`'s numeric values (bool as 0/1, integers, floats) with an event
/// time in `from..to`, in `buckets` equal slices of the range.
#[derive(Debug, Clone, PartialEq)]
pub struct TrendQuery {
    /// The point's name.
    pub point: String,
    /// The start of the range (inclusive).
    pub from: DateTime<Utc>,
    /// The end of the range (exclusive).
    pub to: DateTime<Utc>,
    /// How many slices the range is cut into (1..=[`MAX_TREND_BUCKETS`]).
    pub buckets: usize,
    /// How a slice is folded.
    pub mode: TrendMode,
}

impl TrendQuery {
    /// A query of `point` over `from..to` in `buckets` slices.
    pub fn new(
        point: impl Into<String>,
        from: DateTime<Utc>,
        to: DateTime<Utc>,
        buckets: usize,
    ) -> TrendQuery {
        TrendQuery {
            point: point.into(),
            from,
            to,
            buckets,
            mode: TrendMode::Aggregate,
        }
    }

    /// The query with `mode`.
    pub fn with_mode(mut self, mode: TrendMode) -> TrendQuery {
        self.mode = mode;
        self
    }

    /// The rollup span a trend is read from: [`ROLLUP_SPAN_MS`] when it fits four times
    /// into a bucket; `None` for narrower buckets (every event of the range read). A minute is counted whole in the
    /// bucket its start falls in, so with rollups a bucket covers whole minutes and its
    /// width varies by one (43 or 44 minutes for 60 days in 2,000 buckets); the range's
    /// ends stay exact (the partial minutes there are read from the events), and each
    /// bucket's `first_time`/`last_time` (and first/last values) are its values' own.
    pub fn rollup_span_ms(&self) -> Option<i64> {
        (self.bucket_ms() >= SPANS_PER_BUCKET * ROLLUP_SPAN_MS).then_some(ROLLUP_SPAN_MS)
    }

    /// The width of one bucket in milliseconds (at least 1).
    pub fn bucket_ms(&self) -> i64 {
        let span = (self.to - self.from).num_milliseconds().max(1);
        let buckets = i64::try_from(self.buckets.max(1)).unwrap_or(i64::MAX);
        // Rounded up, so that `buckets` slices cover the whole range.
        ((span + buckets - 1) / buckets).max(1)
    }
}

/// One slice of a trend: what the point's values did in it. Only slices with at least one
/// value are returned.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrendBucket {
    /// The event time of the slice's first value.
    pub first_time: DateTime<Utc>,
    /// The event time of the slice's last value.
    pub last_time: DateTime<Utc>,
    /// The slice's first value ([`TrendMode::FirstLast`]; `None` when aggregated).
    pub first: Option<f64>,
    /// The slice's last value ([`TrendMode::FirstLast`]; `None` when aggregated).
    pub last: Option<f64>,
    /// The smallest value.
    pub min: f64,
    /// The largest value.
    pub max: f64,
    /// The mean of the values.
    pub avg: f64,
    /// How many values fell in the slice.
    pub count: u64,
    /// Whether any value of the slice was invalid (IV).
    pub invalid: bool,
}
