//! Trends over the history: the rollups of the whole minutes inside the range (folded
//! by the database per bucket), and the events of the partial minutes at the range's ends
//! and of the tail (not yet rolled up) unpacked and folded here, all read in one snapshot.

use std::collections::BTreeMap;

use super::append::{read, refresh_names, tail_between};
use super::codec::{decode, Coded};
use super::write::span_start;
use super::{History, SEGMENT_SPAN_MS};
use crate::sql::row::{from_ms, to_ms, Columns, OwnedRow};
use crate::sql::{Database, Param};
use crate::{Backend, StoreError, TrendBucket, TrendMode, TrendQuery, ROLLUP_SPAN_MS};

/// One bucket being folded. Its ends are ranked by (time, id) and keep their value; a
/// rollup's minute has no id and ranks before the events of its millisecond, for
/// the first and the last value alike (a pass holds only events with higher ids than
/// the passes before it, so the tail's are newer).
#[derive(Debug, Clone, Copy)]
struct Fold {
    first: (i64, i64, f64),
    last: (i64, i64, f64),
    min: f64,
    max: f64,
    sum: f64,
    count: u64,
    invalid: bool,
}

impl Fold {
    fn merge(&mut self, other: &Fold) {
        if (other.first.0, other.first.1) < (self.first.0, self.first.1) {
            self.first = other.first;
        }
        if (other.last.0, other.last.1) > (self.last.0, self.last.1) {
            self.last = other.last;
        }
        self.min = self.min.min(other.min);
        self.max = self.max.max(other.max);
        self.sum += other.sum;
        self.count += other.count;
        self.invalid |= other.invalid;
    }

    fn of_event(e: &Coded, v: f64) -> Fold {
        let t = e.event_ms();
        Fold {
            first: (t, e.id, v),
            last: (t, e.id, v),
            min: v,
            max: v,
            sum: v,
            count: 1,
            invalid: e.invalid(),
        }
    }
}

/// `query` over the history (checked by the caller: buckets in range, `from < to`).
pub(crate) async fn query_trend<D: Database>(
    db: &D,
    history: &History,
    query: &TrendQuery,
) -> Result<Vec<TrendBucket>, StoreError> {
    if history.names.id(&query.point).is_none() {
        refresh_names(db, history).await?;
    }
    let Some(point) = history.names.id(&query.point) else {
        return Ok(Vec::new());
    };
    let (from, to) = (to_ms(query.from), to_ms(query.to));
    let width = query.bucket_ms();
    let rollups = query.rollup_span_ms().map(|span| {
        let inner_from = (from + span - 1).div_euclid(span) * span;
        let inner_to = (to.div_euclid(span) * span).max(inner_from);
        (inner_from, inner_to)
    });
    // The ranges read event by event: the partial minutes at the ends, or all of it.
    let raw: Vec<(i64, i64)> = match rollups {
        Some((inner_from, inner_to)) => vec![(from, inner_from.min(to)), (inner_to.max(from), to)],
        None => vec![(from, to)],
    };
    let p = |n: usize| Param::int(0).placeholder(D::BACKEND, n);
    let mut segment_params = vec![Param::int(i64::from(point))];
    let mut ranges = Vec::new();
    for (i, &(start, end)) in raw.iter().enumerate() {
        ranges.push(format!(
            "(start_ms >= {} AND start_ms < {})",
            p(2 + 2 * i),
            p(3 + 2 * i)
        ));
        segment_params.extend([
            Param::int(span_start(start, SEGMENT_SPAN_MS)),
            Param::int(end),
        ]);
    }
    let mut statements = vec![
        tail_between::<D>(from, to - 1),
        read(
            &format!(
                "SELECT data FROM event_segments WHERE point = {} AND ({})",
                p(1),
                ranges.join(" OR ")
            ),
            segment_params,
        ),
    ];
    if let Some((inner_from, inner_to)) = rollups {
        statements.push(rollup_sql::<D>(
            &query.point,
            query.mode,
            from,
            width,
            inner_from,
            inner_to,
        ));
    }
    let mut answers = db.snapshot(statements).await?.into_iter();
    let (tail, segments) = (
        answers.next().unwrap_or_default(),
        answers.next().unwrap_or_default(),
    );
    let mut buckets: BTreeMap<i64, Fold> = BTreeMap::new();
    for row in answers.next().unwrap_or_default() {
        let (bucket, fold) = rollup_fold(&row)?;
        buckets.insert(bucket, fold);
    }
    let bucket_of = |t: i64| match rollups {
        // Inside the whole minutes a value counts where its minute's start does, as the
        // minute's rollup would.
        Some((inner_from, inner_to)) if t >= inner_from && t < inner_to => {
            (span_start(t, ROLLUP_SPAN_MS) - from) / width
        }
        _ => (t - from) / width,
    };
    let mut fold_event = |e: &Coded| {
        let t = e.event_ms();
        let Some(v) = e.numeric() else { return };
        if e.point != point || t < from || t >= to {
            return;
        }
        let fold = Fold::of_event(e, v);
        buckets
            .entry(bucket_of(t))
            .and_modify(|f| f.merge(&fold))
            .or_insert(fold);
    };
    for row in &segments {
        for e in decode(&row.blob(0)?.unwrap_or_default())? {
            let t = e.event_ms();
            // Of a segment's minute, only what no rollup read covers.
            if raw.iter().any(|&(start, end)| t >= start && t < end) {
                fold_event(&e);
            }
        }
    }
    for row in &tail {
        for e in decode(&row.blob(1)?.unwrap_or_default())? {
            fold_event(&e);
        }
    }
    buckets
        .into_values()
        .map(|f| bucket(f, query.mode))
        .collect()
}

/// The rollups of the whole minutes `inner_from..inner_to`, folded per bucket, with each
/// bucket's first and last value from the minutes that hold them.
fn rollup_sql<D: Database>(
    point: &str,
    mode: TrendMode,
    from: i64,
    width: i64,
    inner_from: i64,
    inner_to: i64,
) -> crate::sql::Statement {
    let p = |n: usize| Param::int(0).placeholder(D::BACKEND, n);
    let name = Param::text("").placeholder(D::BACKEND, 1);
    let value_at = |time: &str, kept: &str| {
        format!(
            "(SELECT r.{kept} FROM trend_rollups r WHERE r.point = {name} \
               AND r.start_ms = agg.{time} - (agg.{time} % 60000 + 60000) % 60000)"
        )
    };
    // A bucket's first and last value: on PostgreSQL the least (greatest) of the pairs
    // [time, value] of its minutes (arrays compare element by element; a lookup per
    // bucket started a scan in every day partition: 37 ms for 2,000 buckets, and
    // `array_agg(... ORDER BY ...)` sorts per bucket: 127 ms at 100 million events); on
    // SQLite, which has neither, a key lookup per bucket into the minute holding it (a
    // few microseconds each).
    let (inner_ends, ends) = match (mode, D::BACKEND) {
        (TrendMode::Aggregate, _) => (
            "",
            "CAST(NULL AS DOUBLE PRECISION), CAST(NULL AS DOUBLE PRECISION)".to_owned(),
        ),
        (TrendMode::FirstLast, Backend::Postgres) => (
            ", min(ARRAY[CAST(first_ms AS DOUBLE PRECISION), first_value]) AS first_pair, \
               max(ARRAY[CAST(last_ms AS DOUBLE PRECISION), last_value]) AS last_pair",
            "first_pair[2], last_pair[2]".to_owned(),
        ),
        (TrendMode::FirstLast, Backend::Sqlite) => (
            "",
            format!(
                "{}, {}",
                value_at("first_ms", "first_value"),
                value_at("last_ms", "last_value")
            ),
        ),
    };
    let sql = format!(
        "SELECT bucket, first_ms, last_ms, min_v, max_v, sum_v, n, iv, {ends} FROM ( \
           SELECT CAST((start_ms - {from_p}) / {width_p} AS BIGINT) AS bucket, \
                  CAST(MIN(first_ms) AS BIGINT) AS first_ms, \
                  CAST(MAX(last_ms) AS BIGINT) AS last_ms, MIN(min_value) AS min_v, \
                  MAX(max_value) AS max_v, SUM(sum_value) AS sum_v, \
                  CAST(SUM(samples) AS BIGINT) AS n, CAST(MAX(invalid) AS BIGINT) AS iv \
                  {inner_ends} \
           FROM trend_rollups \
           WHERE point = {name} AND start_ms >= {lo} AND start_ms < {hi} \
           GROUP BY 1) AS agg ORDER BY bucket",
        from_p = p(2),
        width_p = p(3),
        lo = p(4),
        hi = p(5),
    );
    read(
        &sql,
        vec![
            Param::text(point),
            Param::int(from),
            Param::int(width),
            Param::int(inner_from),
            Param::int(inner_to),
        ],
    )
}

/// A bucket of rollups as read by [`rollup_sql`].
fn rollup_fold(r: &OwnedRow) -> Result<(i64, Fold), StoreError> {
    let real = |i: usize| -> Result<f64, StoreError> {
        r.real(i)?
            .ok_or_else(|| StoreError::Corrupt("a trend bucket without values".to_owned()))
    };
    let (first_ms, last_ms) = (r.need_int(1)?, r.need_int(2)?);
    let (min, max) = (real(3)?, real(4)?);
    let invalid = r.need_int(7)? != 0;
    // Minutes folded before schema version 5 kept no first and last value; every
    // minute is folded again when version 6 moves the events into blocks, so none is
    // left: the extremes stand in should one be.
    let first = r.real(8)?.unwrap_or(min);
    let last = r.real(9)?.unwrap_or(max);
    Ok((
        r.need_int(0)?,
        Fold {
            first: (first_ms, i64::MIN, first),
            last: (last_ms, i64::MIN, last),
            min,
            max,
            sum: real(5)?,
            count: u64::try_from(r.need_int(6)?).unwrap_or(0),
            invalid,
        },
    ))
}

/// The bucket a fold answers (the first and last value with [`TrendMode::FirstLast`]).
fn bucket(f: Fold, mode: TrendMode) -> Result<TrendBucket, StoreError> {
    #[allow(clippy::cast_precision_loss)]
    let avg = f.sum / f.count.max(1) as f64;
    let ends = mode == TrendMode::FirstLast;
    Ok(TrendBucket {
        first_time: from_ms(f.first.0)?,
        last_time: from_ms(f.last.0)?,
        first: ends.then_some(f.first.2),
        last: ends.then_some(f.last.2),
        min: f.min,
        max: f.max,
        avg,
        count: f.count,
        invalid: f.invalid,
    })
}
