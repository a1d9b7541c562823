//! The event list over blocks: a page of events in (time, id) order, merged from packed
//! rows.
//!
//! Two ways to a page, by the filter:
//!
//! - **By point** (one point, event time): the tail's events of the point (the blocks not
//!   segmented, read whole first), then the point's segments by their last time newest
//!   first (their first time oldest first), a few at a time (an event segmented between
//!   the two reads is listed once).
//! - **Through the blocks** (everything else): blocks in the page's direction, by their
//!   last time newest first (their first time oldest first), a few at a time; a block's
//!   node, causes and IV count skip it unread where the filter rules it out.
//!
//! Either way rows come in the order of a bound on the times they can hold (their last
//! time newest first, their first time oldest first), so an unpacked event is final, and handed out, once
//! no row still to read can hold an event before it in the page's order.

use std::cmp::Reverse;
use std::collections::HashSet;

use super::append::{id_and_data, read, refresh_names, tail_between};
use super::codec::{decode, Coded, NameId};
use super::History;
use super::{BLOCK_SPAN_MS, SEGMENT_SPAN_MS};
use crate::model::{quality_from_bits, EventKey, SourceTime};
use crate::query::{Cursor, Order, PointFilter, TimeBasis, MAX_PAGE_SIZE};
use crate::sql::row::{from_ms, to_ms};
use crate::sql::{Database, Param};
use crate::{Backend, EventCause, EventQuery, EventRecord, Page, StoreError};

/// Rows read by the first statement of a page; the next ones read what the rows read so
/// far say the rest of the page needs, up to [`MOST_ROWS`].
const FIRST_ROWS: i64 = 2;
const MOST_ROWS: i64 = 512;

/// One page of events matching `query`.
pub(crate) async fn query_events<D: Database>(
    db: &D,
    history: &History,
    query: &EventQuery,
) -> Result<Page<EventRecord>, StoreError> {
    if query.limit == 0 || query.limit > MAX_PAGE_SIZE {
        return Err(StoreError::InvalidQuery(format!(
            "page size {} out of range 1..={MAX_PAGE_SIZE}",
            query.limit
        )));
    }
    // Names another process stored since the copy was refreshed: only a filter that
    // names one needs them (an event's names are looked up as it is handed out).
    let names = &history.names;
    let unknown = |name: &String| names.id(name).is_none();
    let stale = match &query.point {
        Some(PointFilter::Prefix(prefix)) => !prefix.is_empty(),
        Some(PointFilter::Exact(name)) => unknown(name),
        None => false,
    } || query.node.as_ref().is_some_and(unknown);
    if stale {
        refresh_names(db, history).await?;
    }
    let Some(filter) = Filter::of(query, history) else {
        return Ok(Page {
            items: Vec::new(),
            next: None,
        });
    };
    if D::BACKEND == Backend::Postgres && history.newest_day().is_none() {
        let newest = db
            .rows(
                read("SELECT max(first_ms) FROM event_blocks", Vec::new()),
                |r| r.int(0),
            )
            .await?;
        history.saw_blocks(newest.into_iter().flatten());
    }
    let wanted = query.limit + 1;
    let events = match (&filter.points, query.time_basis) {
        (Points::One(point), TimeBasis::Source) => {
            by_point(db, history, &filter, *point, wanted).await?
        }
        _ => through_blocks(db, history, &filter, wanted).await?,
    };
    let mut items = Vec::with_capacity(events.len());
    for e in events {
        items.push(record(db, history, e).await?);
    }
    let more = items.len() > query.limit;
    items.truncate(query.limit);
    let next = if more {
        items.last().and_then(|e| {
            let t = match query.time_basis {
                TimeBasis::Source => e.event_time(),
                TimeBasis::Received => e.received_time,
            };
            e.id.map(|id| Cursor::new(to_ms(t), id))
        })
    } else {
        None
    };
    Ok(Page { items, next })
}

/// Which points a filter admits, as numbers.
#[derive(Debug)]
enum Points {
    Any,
    One(NameId),
    Some(HashSet<NameId>),
}

/// An event query in numbers.
#[derive(Debug)]
struct Filter {
    basis: TimeBasis,
    order: Order,
    /// The page's times, both inclusive, the cursor and the range applied.
    low: i64,
    high: i64,
    after: Option<(i64, i64)>,
    points: Points,
    node: Option<NameId>,
    /// Bits `1 << code` of the causes admitted; 0: every cause.
    causes: i64,
    invalid_only: bool,
}

impl Filter {
    /// The filter of `query`; `None` when it can match nothing (a name never stored).
    fn of(query: &EventQuery, history: &History) -> Option<Filter> {
        let names = &history.names;
        let points = match &query.point {
            None => Points::Any,
            Some(PointFilter::Exact(name)) => Points::One(names.id(name)?),
            Some(PointFilter::Prefix(prefix)) if prefix.is_empty() => Points::Any,
            Some(PointFilter::Prefix(prefix)) => {
                let ids: HashSet<NameId> = names.ids_with_prefix(prefix).into_iter().collect();
                if ids.is_empty() {
                    return None;
                }
                Points::Some(ids)
            }
        };
        let node = match &query.node {
            None => None,
            Some(name) => Some(names.id(name)?),
        };
        let mut low = query.from.map_or(i64::MIN, to_ms);
        let mut high = query.to.map_or(i64::MAX, |t| to_ms(t).saturating_sub(1));
        let after = query.after.map(|c| (c.time_ms, c.id));
        match (query.order, after) {
            (Order::NewestFirst, Some((t, _))) => high = high.min(t),
            (Order::OldestFirst, Some((t, _))) => low = low.max(t),
            (_, None) => {}
        }
        if low > high {
            return None;
        }
        Some(Filter {
            basis: query.time_basis,
            order: query.order,
            low,
            high,
            after,
            points,
            node,
            causes: query
                .causes
                .iter()
                .fold(0, |bits, c| bits | 1i64 << (c.code() & 31)),
            invalid_only: query.invalid_only,
        })
    }

    fn time(&self, e: &Coded) -> i64 {
        match self.basis {
            TimeBasis::Source => e.event_ms(),
            TimeBasis::Received => e.received_ms,
        }
    }

    /// The event's place in the page's order: smaller comes first.
    fn rank(&self, e: &Coded) -> (i64, i64) {
        let key = (self.time(e), e.id);
        match self.order {
            Order::OldestFirst => key,
            Order::NewestFirst => (-key.0.max(i64::MIN + 1), -key.1),
        }
    }

    fn admits(&self, e: &Coded) -> bool {
        let t = self.time(e);
        if t < self.low || t > self.high {
            return false;
        }
        if let Some(after) = self.after {
            let key = (t, e.id);
            let beyond = match self.order {
                Order::NewestFirst => key < after,
                Order::OldestFirst => key > after,
            };
            if !beyond {
                return false;
            }
        }
        let point = match &self.points {
            Points::Any => true,
            Points::One(p) => e.point == *p,
            Points::Some(set) => set.contains(&e.point),
        };
        point
            && self.node.is_none_or(|n| e.node == n)
            && (self.causes == 0 || self.causes & (1i64 << (e.cause & 31)) != 0)
            && (!self.invalid_only || e.invalid())
    }
}

/// Events unpacked but not yet handed out, and those handed out.
struct Merge<'a> {
    filter: &'a Filter,
    pending: Vec<Coded>,
    out: Vec<Coded>,
    wanted: usize,
    /// Rows unpacked and events of them the filter admitted, for the size of the next
    /// read.
    rows: usize,
    admitted: usize,
}

impl<'a> Merge<'a> {
    fn new(filter: &'a Filter, wanted: usize) -> Merge<'a> {
        Merge {
            filter,
            pending: Vec::new(),
            out: Vec::new(),
            wanted,
            rows: 0,
            admitted: 0,
        }
    }

    fn add(&mut self, events: Vec<Coded>) {
        let before = self.pending.len();
        self.pending
            .extend(events.into_iter().filter(|e| self.filter.admits(e)));
        self.admitted += self.pending.len() - before;
    }

    /// How many rows the next read asks for: enough for the rest of the page by the
    /// rows read so far (twice that), at least twice the last read when they gave
    /// nothing.
    fn next_rows(&self, last: i64) -> i64 {
        let missing = self
            .wanted
            .saturating_sub(self.out.len() + self.pending.len())
            .max(1);
        let guess = match (2 * missing * self.rows).checked_div(self.admitted) {
            Some(rows) => i64::try_from(rows + 1).unwrap_or(MOST_ROWS),
            None => last.saturating_mul(4),
        };
        guess.clamp(FIRST_ROWS, MOST_ROWS)
    }

    /// Hands out the pending events that come before every event of the rows still to
    /// read (`final_before`: ranked before this, or all when `None`); true when the page
    /// is full.
    fn settle(&mut self, final_before: Option<(i64, i64)>) -> bool {
        let filter = self.filter;
        self.pending.sort_by_key(|e| Reverse(filter.rank(e)));
        while self.out.len() < self.wanted {
            let Some(e) = self.pending.last() else { break };
            if final_before.is_some_and(|bound| filter.rank(e) >= bound) {
                break;
            }
            if let Some(e) = self.pending.pop() {
                // An event read from the tail and again from its segment (a pass committed
                // between the two reads): the copies rank alike, so they come together.
                if self.out.last().is_none_or(|last| last.id != e.id) {
                    self.out.push(e);
                }
            }
        }
        self.out.len() >= self.wanted
    }
}

/// The rank an event at time `t` would have with the smallest (newest first: largest)
/// id: every event at `t` ranks at or after it.
fn rank_at(filter: &Filter, t: i64) -> (i64, i64) {
    match filter.order {
        Order::OldestFirst => (t, i64::MIN),
        Order::NewestFirst => (-t.max(i64::MIN + 1), i64::MIN),
    }
}

/// The ranges of a partition key (a block's first time, a segment's hour) a newest-first
/// page reads one after the other: on PostgreSQL first the days from the newest block's
/// (by the hint; newer ones are read too, the range is open above), so that a page of
/// the recent past reads a few day partitions instead of starting a scan in every one,
/// then the rest. One open range elsewhere (SQLite has no partitions).
fn windows<D: Database>(history: &History, filter: &Filter) -> Vec<(i64, i64)> {
    let floor = history.newest_day();
    let windowed = D::BACKEND == Backend::Postgres
        && filter.order == Order::NewestFirst
        && filter.basis == TimeBasis::Source
        && floor.is_some_and(|f| f <= filter.high && f > filter.low);
    match floor {
        Some(floor) if windowed => vec![(floor, i64::MAX), (i64::MIN, floor - 1)],
        _ => vec![(i64::MIN, i64::MAX)],
    }
}

/// A page through the blocks.
async fn through_blocks<D: Database>(
    db: &D,
    history: &History,
    filter: &Filter,
    wanted: usize,
) -> Result<Vec<Coded>, StoreError> {
    let (first, last) = match filter.basis {
        TimeBasis::Source => ("first_ms", "last_ms"),
        TimeBasis::Received => ("first_received_ms", "last_received_ms"),
    };
    // Newest first by the last time (a block holds nothing after it), oldest first by
    // the first time (nothing before it).
    let (key, direction, compare) = match filter.order {
        Order::NewestFirst => (last, "DESC", "<"),
        Order::OldestFirst => (first, "ASC", ">"),
    };
    let p = |n: usize| Param::int(0).placeholder(D::BACKEND, n);
    // A block's times lie within one span: its key is within a span of the range.
    let mut fixed = vec![
        filter.low,
        filter.high,
        filter.low.saturating_sub(BLOCK_SPAN_MS),
    ];
    fixed.push(filter.high.saturating_add(BLOCK_SPAN_MS));
    let mut conditions = vec![
        format!("{last} >= {}", p(1)),
        format!("{first} <= {}", p(2)),
        format!("{key} >= {}", p(3)),
        format!("{key} <= {}", p(4)),
    ];
    if filter.invalid_only {
        conditions.push("invalid > 0".to_owned());
    }
    if let Some(node) = filter.node {
        // (a block of several nodes' events has none: unpacked and filtered)
        fixed.push(i64::from(node));
        conditions.push(format!("(node = {} OR node IS NULL)", p(fixed.len())));
    }
    if filter.causes != 0 {
        fixed.push(filter.causes);
        conditions.push(format!("(causes & {}) <> 0", p(fixed.len())));
    }
    let n = fixed.len();
    let (w_lo, w_hi, k_time, k_id, limit) = (p(n + 1), p(n + 2), p(n + 3), p(n + 4), p(n + 5));
    conditions.push(format!("first_ms >= {w_lo} AND first_ms <= {w_hi}"));
    conditions.push(format!("({key}, id) {compare} ({k_time}, {k_id})"));
    let sql = format!(
        "SELECT id, {key}, data FROM event_blocks WHERE {} \
         ORDER BY {key} {direction}, id {direction} LIMIT {limit}",
        conditions.join(" AND "),
    );
    let mut merge = Merge::new(filter, wanted);
    let mut rows = FIRST_ROWS;
    let windows = windows::<D>(history, filter);
    for (w, &(low, high)) in windows.iter().enumerate() {
        let mut keyset = match filter.order {
            Order::NewestFirst => (i64::MAX, i64::MAX),
            Order::OldestFirst => (i64::MIN, i64::MIN),
        };
        loop {
            let mut bound: Vec<Param> = fixed.iter().copied().map(Param::int).collect();
            bound.extend([low, high, keyset.0, keyset.1, rows].map(Param::int));
            let blocks = db
                .rows(read(&sql, bound), |r| {
                    Ok((
                        r.need_int(0)?,
                        r.need_int(1)?,
                        r.blob(2)?.unwrap_or_default(),
                    ))
                })
                .await?;
            let exhausted = i64::try_from(blocks.len()).unwrap_or(0) < rows;
            for (id, time, data) in blocks {
                keyset = (time, id);
                merge.rows += 1;
                merge.add(decode(&data)?);
            }
            // What is still to read: the rest of this window, or the windows after it
            // (first times at most the next one's top: last times a span above).
            let bound = match (exhausted, windows.get(w + 1)) {
                (false, _) => Some(rank_at(filter, keyset.0)),
                (true, Some(&(_, next_high))) => {
                    Some(rank_at(filter, next_high.saturating_add(BLOCK_SPAN_MS - 1)))
                }
                (true, None) => None,
            };
            if merge.settle(bound) {
                return Ok(merge.out);
            }
            rows = merge.next_rows(rows);
            if exhausted {
                break;
            }
        }
    }
    Ok(merge.out)
}

/// A page of one point's events by event time: the tail, then its segments.
async fn by_point<D: Database>(
    db: &D,
    history: &History,
    filter: &Filter,
    point: NameId,
    wanted: usize,
) -> Result<Vec<Coded>, StoreError> {
    let mut merge = Merge::new(filter, wanted);
    // The tail first: an event segmented meanwhile is read again from its segment (and
    // listed once: the merge drops an id it just handed out), none is missed (segments
    // are never removed but by retention).
    let tail = db
        .rows(tail_between::<D>(filter.low, filter.high), id_and_data)
        .await?;
    for (_, data) in tail {
        merge.add(decode(&data)?);
    }
    merge.admitted = 0; // the tail says nothing of the segments' events a row
                        // Newest first by the last time (a segment holds nothing after it), oldest first by
                        // the first time; a segment's times lie within one aligned span.
    let p = |n: usize| Param::int(0).placeholder(D::BACKEND, n);
    let (key, direction, compare) = match filter.order {
        Order::NewestFirst => ("last_ms", "DESC", "<"),
        Order::OldestFirst => ("first_ms", "ASC", ">"),
    };
    let sql = format!(
        "SELECT {key}, start_ms, part, data FROM event_segments \
         WHERE point = {} AND {key} >= {} AND {key} <= {} AND last_ms >= {} AND first_ms <= {} \
           AND start_ms >= {} AND start_ms <= {} \
           AND ({key}, start_ms, part) {compare} ({}, {}, {}) \
         ORDER BY {key} {direction}, start_ms {direction}, part {direction} LIMIT {}",
        p(1),
        p(2),
        p(3),
        p(4),
        p(5),
        p(6),
        p(7),
        p(8),
        p(9),
        p(10),
        p(11)
    );
    let mut rows = FIRST_ROWS;
    let windows = windows::<D>(history, filter);
    for (w, &(low, high)) in windows.iter().enumerate() {
        let mut keyset = match filter.order {
            Order::NewestFirst => (i64::MAX, i64::MAX, i64::MAX),
            Order::OldestFirst => (i64::MIN, i64::MIN, i64::MIN),
        };
        loop {
            let params = vec![
                Param::int(i64::from(point)),
                Param::int(filter.low.saturating_sub(SEGMENT_SPAN_MS)),
                Param::int(filter.high.saturating_add(SEGMENT_SPAN_MS)),
                Param::int(filter.low),
                Param::int(filter.high),
                Param::int(low),
                Param::int(high),
                Param::int(keyset.0),
                Param::int(keyset.1),
                Param::int(keyset.2),
                Param::int(rows),
            ];
            let segments = db
                .rows(read(&sql, params), |r| {
                    Ok((
                        (r.need_int(0)?, r.need_int(1)?, r.need_int(2)?),
                        r.blob(3)?.unwrap_or_default(),
                    ))
                })
                .await?;
            let exhausted = i64::try_from(segments.len()).unwrap_or(0) < rows;
            for (key, data) in segments {
                keyset = key;
                merge.rows += 1;
                merge.add(decode(&data)?);
            }
            let bound = match (exhausted, windows.get(w + 1)) {
                (false, _) => Some(rank_at(filter, keyset.0)),
                (true, Some(&(_, next_high))) => Some(rank_at(
                    filter,
                    next_high.saturating_add(SEGMENT_SPAN_MS - 1),
                )),
                (true, None) => None,
            };
            if merge.settle(bound) {
                return Ok(merge.out);
            }
            rows = merge.next_rows(rows);
            if exhausted {
                break;
            }
        }
    }
    Ok(merge.out)
}

/// An event with its names.
async fn record<D: Database>(
    db: &D,
    history: &History,
    e: Coded,
) -> Result<EventRecord, StoreError> {
    let name = |id: NameId| history.names.name(id);
    let mut ids = [e.node, e.point, e.origin]
        .into_iter()
        .chain(e.key.map(|(source, _)| source));
    if ids.any(|id| name(id).is_none()) {
        refresh_names(db, history).await?;
    }
    let text = |id: NameId| -> Result<String, StoreError> {
        name(id)
            .map(|n| n.to_string())
            .ok_or_else(|| StoreError::Corrupt(format!("an event names number {id}, unknown")))
    };
    Ok(EventRecord {
        id: Some(e.id),
        node: text(e.node)?,
        point: text(e.point)?,
        ioa: e.ioa,
        value: e.value,
        quality: quality_from_bits(e.quality),
        source_time: e
            .source
            .map(|(ms, invalid)| {
                Ok::<_, StoreError>(SourceTime {
                    time: from_ms(ms)?,
                    invalid,
                })
            })
            .transpose()?,
        received_time: from_ms(e.received_ms)?,
        cause: EventCause::from_code(i16::from(e.cause))
            .ok_or_else(|| StoreError::Corrupt(format!("unknown cause {}", e.cause)))?,
        origin: text(e.origin)?,
        key: match e.key {
            Some((source, sequence)) => Some(EventKey {
                source: text(source)?,
                sequence,
            }),
            None => None,
        },
    })
}
