//! What one append writes: the batch's events numbered and packed into blocks, the runs
//! of its keys, and, when the tail has grown enough, a pass (segments and rollups).
//!
//! Pure functions over the batch and the writer's state; the backend writes the result in
//! one transaction ([`HistoryWrite`]), and the state changes only once it is committed.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::sync::Arc;

use super::codec::{encode, Coded, NameId};
use super::{BLOCK_SPAN_MS, PASS_EVENTS, PASS_EVENTS_PER_POINT, SEGMENT_SPAN_MS};
use crate::model::quality_to_bits;
use crate::sql::row::{key_sequence, to_ms};
use crate::EventRecord;
use crate::ROLLUP_SPAN_MS;

/// A row of `event_blocks`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct BlockRow {
    pub(crate) id: i64,
    pub(crate) events: i64,
    pub(crate) first_ms: i64,
    pub(crate) last_ms: i64,
    pub(crate) first_received_ms: i64,
    pub(crate) last_received_ms: i64,
    /// The node of every event, when they are one node's.
    pub(crate) node: Option<NameId>,
    /// A bit `1 << code` for each cause present.
    pub(crate) causes: i64,
    /// How many events have IV set.
    pub(crate) invalid: i64,
    /// Its events are in segments (a block rewritten by retention keeps its flag).
    pub(crate) segmented: bool,
    pub(crate) data: Vec<u8>,
}

/// A row of `event_keys`: sequences `first_seq..=last_seq` of `source` stored with ids
/// `first_id..`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct KeyRun {
    pub(crate) source: NameId,
    pub(crate) first_seq: i64,
    pub(crate) last_seq: i64,
    pub(crate) first_id: i64,
}

/// A row of `event_segments`: one point's events of one hour from one pass.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SegmentRow {
    pub(crate) point: NameId,
    pub(crate) start_ms: i64,
    pub(crate) part: i64,
    pub(crate) first_ms: i64,
    pub(crate) last_ms: i64,
    pub(crate) events: i64,
    pub(crate) data: Vec<u8>,
}

/// A minute of a point's numeric values, to be merged into `trend_rollups`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct RollupRow {
    /// The point's name (`trend_rollups` is keyed by name).
    pub(crate) point: Arc<str>,
    pub(crate) start_ms: i64,
    pub(crate) first_ms: i64,
    pub(crate) last_ms: i64,
    pub(crate) min: f64,
    pub(crate) max: f64,
    pub(crate) sum: f64,
    pub(crate) samples: i64,
    pub(crate) invalid: bool,
    pub(crate) first_value: f64,
    pub(crate) last_value: f64,
}

/// A pass: the tail's events by point and minute.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct Pass {
    /// The pass's number: its smallest block id.
    pub(crate) part: i64,
    /// The blocks it segments.
    pub(crate) blocks: Vec<i64>,
    pub(crate) segments: Vec<SegmentRow>,
    pub(crate) rollups: Vec<RollupRow>,
}

/// Everything one append writes, in one transaction.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct HistoryWrite {
    /// The id the next event gets, after this write.
    pub(crate) next_id: i64,
    pub(crate) blocks: Vec<BlockRow>,
    pub(crate) keys: Vec<KeyRun>,
    pub(crate) pass: Option<Pass>,
}

/// The events not yet segmented, as the writer keeps them.
#[derive(Debug, Clone, Default)]
pub(crate) struct Tail {
    pub(crate) blocks: Vec<i64>,
    pub(crate) events: Vec<Coded>,
    pub(crate) points: HashSet<NameId>,
}

impl Tail {
    pub(crate) fn add(&mut self, block: i64, events: &[Coded]) {
        self.blocks.push(block);
        self.points.extend(events.iter().map(|e| e.point));
        self.events.extend_from_slice(events);
    }

    /// Whether the tail is worth a pass: [`PASS_EVENTS_PER_POINT`] events a point on
    /// average, or [`PASS_EVENTS`] in all.
    pub(crate) fn wants_pass(&self) -> bool {
        self.events.len() >= PASS_EVENTS
            || (!self.events.is_empty()
                && self.events.len() >= PASS_EVENTS_PER_POINT * self.points.len())
    }
}

/// The names an event refers to, as numbers (known to the caller for every name of the
/// batch).
pub(crate) struct EventNames {
    pub(crate) node: NameId,
    pub(crate) point: NameId,
    pub(crate) origin: NameId,
    pub(crate) key_source: Option<NameId>,
}

/// The batch numbered: `ids` answers every event of the batch (the stored one's for a key
/// stored already, or earlier in the batch); `new` are the events to store, in the
/// batch's order, with ids from `first_id` on.
pub(crate) struct Numbered {
    pub(crate) ids: Vec<i64>,
    pub(crate) new: Vec<Coded>,
    pub(crate) keys: Vec<KeyRun>,
    pub(crate) next_id: i64,
}

/// Numbers the batch: `names` gives each event's names, `stored` the id of a key stored
/// already.
pub(crate) fn number(
    events: &[EventRecord],
    names: impl Fn(&EventRecord) -> EventNames,
    stored: &HashMap<(NameId, i64), i64>,
    first_id: i64,
) -> Numbered {
    let mut next_id = first_id;
    let mut ids = Vec::with_capacity(events.len());
    let mut new = Vec::with_capacity(events.len());
    let mut in_batch: HashMap<(NameId, i64), i64> = HashMap::new();
    for e in events {
        let n = names(e);
        let key = n
            .key_source
            .zip(e.key.as_ref())
            .map(|(source, k)| (source, key_sequence(k.sequence)));
        if let Some(key) = key {
            if let Some(&id) = stored.get(&key).or_else(|| in_batch.get(&key)) {
                ids.push(id);
                continue;
            }
        }
        let id = next_id;
        next_id += 1;
        ids.push(id);
        if let Some(key) = key {
            in_batch.insert(key, id);
        }
        new.push(Coded {
            id,
            node: n.node,
            point: n.point,
            origin: n.origin,
            ioa: e.ioa,
            value: e.value.clone(),
            quality: quality_to_bits(e.quality),
            cause: u8::try_from(e.cause.code()).unwrap_or(0),
            received_ms: to_ms(e.received_time),
            source: e.source_time.map(|s| (to_ms(s.time), s.invalid)),
            key: key.map(|(source, seq)| (source, u64::try_from(seq).unwrap_or(0))),
        });
    }
    Numbered {
        ids,
        keys: runs_of(&new),
        new,
        next_id,
    }
}

/// The key runs of `new` (events in id order): consecutive events of one source whose
/// sequences and ids both go up by one.
pub(crate) fn runs_of(new: &[Coded]) -> Vec<KeyRun> {
    let mut keys: Vec<KeyRun> = Vec::new();
    for e in new {
        let Some((source, seq)) = e.key else { continue };
        let seq = key_sequence(seq);
        match keys.last_mut() {
            Some(run)
                if run.source == source
                    && run.last_seq.checked_add(1) == Some(seq)
                    && run.first_id + (run.last_seq - run.first_seq) + 1 == e.id =>
            {
                run.last_seq = seq;
            }
            _ => keys.push(KeyRun {
                source,
                first_seq: seq,
                last_seq: seq,
                first_id: e.id,
            }),
        }
    }
    keys
}

/// The start of the aligned `span` (a block's, a segment's, a rollup's) holding `ms`.
pub(crate) fn span_start(ms: i64, span: i64) -> i64 {
    ms - ms.rem_euclid(span)
}

/// The new events cut into blocks: one per minute of event time and minute of received
/// time, each in id order.
pub(crate) fn blocks(new: &[Coded]) -> Vec<(BlockRow, Vec<Coded>)> {
    let mut by_span: BTreeMap<(i64, i64), Vec<Coded>> = BTreeMap::new();
    for e in new {
        by_span
            .entry((
                span_start(e.event_ms(), BLOCK_SPAN_MS),
                span_start(e.received_ms, BLOCK_SPAN_MS),
            ))
            .or_default()
            .push(e.clone());
    }
    let mut out: Vec<(BlockRow, Vec<Coded>)> = by_span
        .into_values()
        .filter_map(|mut events| {
            events.sort_by_key(|e| e.id);
            Some((block_row(&events)?, events))
        })
        .collect();
    out.sort_by_key(|(row, _)| row.id);
    out
}

/// The row of a block of `events` (in id order; `None` when empty).
pub(crate) fn block_row(events: &[Coded]) -> Option<BlockRow> {
    let first = events.first()?;
    let mut row = BlockRow {
        id: events.iter().map(|e| e.id).min().unwrap_or(first.id),
        events: i64::try_from(events.len()).unwrap_or(i64::MAX),
        first_ms: i64::MAX,
        last_ms: i64::MIN,
        first_received_ms: i64::MAX,
        last_received_ms: i64::MIN,
        node: Some(first.node),
        causes: 0,
        invalid: 0,
        segmented: false,
        data: encode(events),
    };
    for e in events {
        let t = e.event_ms();
        row.first_ms = row.first_ms.min(t);
        row.last_ms = row.last_ms.max(t);
        row.first_received_ms = row.first_received_ms.min(e.received_ms);
        row.last_received_ms = row.last_received_ms.max(e.received_ms);
        if row.node != Some(e.node) {
            row.node = None;
        }
        row.causes |= 1i64 << (e.cause & 31);
        row.invalid += i64::from(e.invalid());
    }
    Some(row)
}

/// A pass over the tail: its events by point and hour ([`SEGMENT_SPAN_MS`]) into
/// segments, by point and minute into rollups (`name_of` gives a point's name).
pub(crate) fn pass(tail: &Tail, name_of: impl Fn(NameId) -> Option<Arc<str>>) -> Option<Pass> {
    let part = *tail.blocks.iter().min()?;
    let mut by_hour: BTreeMap<(NameId, i64), Vec<&Coded>> = BTreeMap::new();
    for e in &tail.events {
        by_hour
            .entry((e.point, span_start(e.event_ms(), SEGMENT_SPAN_MS)))
            .or_default()
            .push(e);
    }
    let mut segments = Vec::with_capacity(by_hour.len());
    let mut rollups = Vec::new();
    for ((point, start_ms), mut events) in by_hour {
        events.sort_by_key(|e| (e.event_ms(), e.id));
        let owned: Vec<Coded> = events.iter().map(|&e| e.clone()).collect();
        let (first_ms, last_ms) = (
            owned.first().map_or(start_ms, Coded::event_ms),
            owned.last().map_or(start_ms, Coded::event_ms),
        );
        if let Some(name) = name_of(point) {
            // Sorted by time: a minute's events lie together.
            for minute in owned.chunk_by(|a, b| {
                span_start(a.event_ms(), ROLLUP_SPAN_MS) == span_start(b.event_ms(), ROLLUP_SPAN_MS)
            }) {
                let start = minute
                    .first()
                    .map_or(start_ms, |e| span_start(e.event_ms(), ROLLUP_SPAN_MS));
                rollups.extend(rollup(Arc::clone(&name), start, minute));
            }
        }
        segments.push(SegmentRow {
            point,
            start_ms,
            part,
            first_ms,
            last_ms,
            events: i64::try_from(owned.len()).unwrap_or(i64::MAX),
            data: encode(&owned),
        });
    }
    Some(Pass {
        part,
        blocks: tail.blocks.clone(),
        segments,
        rollups,
    })
}

/// The rollup of one point's events of one minute, sorted by (time, id); `None` when
/// none has a numeric value.
pub(crate) fn rollup(point: Arc<str>, start_ms: i64, events: &[Coded]) -> Option<RollupRow> {
    let mut row: Option<RollupRow> = None;
    for e in events {
        let Some(v) = e.numeric() else { continue };
        let t = e.event_ms();
        match &mut row {
            None => {
                row = Some(RollupRow {
                    point: Arc::clone(&point),
                    start_ms,
                    first_ms: t,
                    last_ms: t,
                    min: v,
                    max: v,
                    sum: v,
                    samples: 1,
                    invalid: e.invalid(),
                    first_value: v,
                    last_value: v,
                });
            }
            Some(r) => {
                // Sorted: the first stays, each later value is the last.
                r.last_ms = t;
                r.last_value = v;
                r.min = r.min.min(v);
                r.max = r.max.max(v);
                r.sum += v;
                r.samples += 1;
                r.invalid |= e.invalid();
            }
        }
    }
    row
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{EventKey, PointValue};
    use chrono::{TimeZone, Utc};

    fn event(point: &str, ms: i64, seq: Option<u64>) -> EventRecord {
        let at = Utc.timestamp_millis_opt(ms).single().unwrap();
        let e = EventRecord::new("N1", point, PointValue::Float(ms as f64), at);
        match seq {
            Some(s) => e.with_key(EventKey::new("rec", s)),
            None => e,
        }
    }

    fn names(e: &EventRecord) -> EventNames {
        EventNames {
            node: 1,
            point: if e.point == "A" { 2 } else { 3 },
            origin: 1,
            key_source: e.key.as_ref().map(|_| 4),
        }
    }

    #[test]
    fn a_batch_of_one_source_is_one_run_and_repeats_answer_the_stored_ids() {
        let batch: Vec<_> = (0..5)
            .map(|i| event("A", 1_000 + i, Some(10 + i as u64)))
            .collect();
        let n = number(&batch, names, &HashMap::new(), 100);
        assert_eq!(n.ids, vec![100, 101, 102, 103, 104]);
        assert_eq!(
            n.keys,
            vec![KeyRun {
                source: 4,
                first_seq: 10,
                last_seq: 14,
                first_id: 100
            }]
        );
        assert_eq!(n.next_id, 105);
        // Written again with one new event and a repeat inside the batch.
        let stored: HashMap<_, _> = (0..5).map(|i| ((4, 10 + i), 100 + i)).collect();
        let mut again = batch.clone();
        again.push(event("B", 2_000, Some(15)));
        again.push(event("B", 2_000, Some(15)));
        again.push(event("B", 2_001, None));
        let n = number(&again, names, &stored, 105);
        assert_eq!(n.ids, vec![100, 101, 102, 103, 104, 105, 105, 106]);
        assert_eq!(n.new.len(), 2);
        assert_eq!(
            n.keys,
            vec![KeyRun {
                source: 4,
                first_seq: 15,
                last_seq: 15,
                first_id: 105
            }]
        );
    }

    #[test]
    fn blocks_hold_one_minute_each_and_a_pass_one_point_hour_per_segment() {
        let batch = vec![
            event("A", 59_999, None),
            event("B", 60_000, None),
            event("A", 60_500, None),
            event("A", 1_000, None),
        ];
        let n = number(&batch, names, &HashMap::new(), 1);
        let blocks = blocks(&n.new);
        let spans: Vec<_> = blocks
            .iter()
            .map(|(b, _)| (b.id, b.first_ms, b.last_ms, b.events))
            .collect();
        assert_eq!(spans, vec![(1, 1_000, 59_999, 2), (2, 60_000, 60_500, 2)]);
        let mut tail = Tail::default();
        for (row, events) in &blocks {
            tail.add(row.id, events);
        }
        let pass = pass(&tail, |p| Some(Arc::from(format!("P{p}")))).unwrap();
        assert_eq!(pass.part, 1);
        let keys: Vec<_> = pass
            .segments
            .iter()
            .map(|s| (s.point, s.start_ms, s.events))
            .collect();
        assert_eq!(keys, vec![(2, 0, 3), (3, 0, 1)]);
        let minutes: Vec<_> = pass
            .rollups
            .iter()
            .map(|r| (r.point.to_string(), r.start_ms, r.samples))
            .collect();
        assert_eq!(
            minutes,
            [
                ("P2".to_owned(), 0, 2),
                ("P2".to_owned(), 60_000, 1),
                ("P3".to_owned(), 60_000, 1)
            ]
        );
        let first = &pass.rollups[0];
        assert_eq!(
            (
                first.first_ms,
                first.last_ms,
                first.first_value,
                first.last_value
            ),
            (1_000, 59_999, 1_000.0, 59_999.0)
        );
        assert_eq!((first.samples, first.sum), (2, 60_999.0));
    }
}
