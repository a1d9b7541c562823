//! The event history in blocks: how a store keeps 300,000 events a second.
//!
//! # Why blocks
//!
//! A row per event with the event list's indexes costs one B-tree entry per index per
//! event, and with thousands of points the point and node entries land on random leaf
//! pages: measured without any client (one million rows by one `INSERT ... SELECT`,
//! 10,000 points), SQLite stored 762,000 rows/s with no index and 177,000 with the six
//! (point 1.55 µs, key 0.95 µs, node 0.88 µs per row), PostgreSQL 504,000 and 91,000. On
//! SQLite each commit also copies every leaf it touched into the write-ahead log: a batch
//! of 500 events over 10,000 points dirtied about 560 pages (2.2 MB of log for 500
//! events). So the history keeps events packed, many to a row, and indexes the rows.
//!
//! # Layout
//!
//! ```text
//!  append (a batch)                                   every pass (the tail holds 16
//!    | names -> numbers (event_names)                  events a point, or 262,144)
//!    | keys stored? (event_keys: runs of sequences)         |
//!    | ids (event_counter)                                   v
//!    v                                              event_segments: one point's events
//!  event_blocks: the batch's events of one minute,    of one hour from one pass, packed
//!  packed (codec), with their time spans, node,       (point, hour, part)
//!  causes and IV count; `segmented` = 0 (the tail)    trend_rollups: per point and minute
//!    one transaction: blocks + key runs                 (the same transaction: segments,
//!                                                        rollups, blocks segmented = 1)
//! ```
//!
//! - **`event_blocks`**: one row per minute of event time (and of received time) of an
//!   append, its events in id order packed by [`codec`]. Its spans (`first_ms`..`last_ms`,
//!   received alike) lie within one minute ([`BLOCK_SPAN_MS`]), so a scan for the events
//!   at or before a time starts a minute after it. The event list without a point reads
//!   blocks by their last time, newest (or oldest) first, and merges them
//!   ([`list`]): a page of the newest events reads a block or two. The block's node (when
//!   all its events are one node's), its causes (a bit each) and its IV count let a
//!   filtered list skip blocks without unpacking them.
//! - **`event_segments`**: the same events again, by point: when the unsegmented blocks
//!   hold 16 events a point (or 262,144 in all) the writer packs the tail per point and
//!   hour ([`SEGMENT_SPAN_MS`]: a point changing once a minute still fills a segment). A
//!   point's event list reads its segments (by their last time, like the blocks) and the
//!   tail; a trend reads the rollups, the segments holding the partial minutes at its
//!   ends, and the tail.
//! - **`trend_rollups`**: as before (schema version 4 and 5), folded by the pass in Rust
//!   from the same events instead of by a statement per batch.
//! - **`event_keys`**: the idempotent keys as runs (source, first and last sequence,
//!   first id): a batch of the recorder is one run, however many events it holds.
//! - **`event_names`**: node, point, origin and key-source names as numbers.
//!
//! The writer (one per store, behind a mutex) keeps the tail's events in memory, so a
//! pass packs them without reading them back; at open it reads the unsegmented blocks.
//! An event is written twice (block and segment), about 25 bytes each time.
//!
//! # Consistency
//!
//! A block is written once and changes only by retention. A pass turns blocks'
//! `segmented` on in the transaction that writes their segments and rollups (each
//! segment numbered, `part`, by the pass's smallest block id). A point's event list reads
//! the tail (the blocks not segmented) before the segments: an event segmented between
//! the two reads is read twice and listed once (by id), none is missed. A trend reads the
//! tail, the rollups and the segments in one snapshot (a read transaction), since a
//! rollup has no ids to tell a second reading by.
//!
//! Several writers may share a PostgreSQL store (ids are taken from `event_counter` a
//! range at a time, [`ID_RANGE`]; a pass flips only blocks still unsegmented, under an
//! advisory lock): ids then grow with insertion order within each writer.

pub(crate) mod codec;
#[cfg(feature = "database")]
pub(crate) mod names;
#[cfg(feature = "database")]
pub(crate) mod write;

/// What the stats read over the history: event count, received-time span, commands.
#[cfg(feature = "database")]
pub(crate) const STATS: &str = "SELECT \
     (SELECT CAST(COALESCE(SUM(events), 0) AS BIGINT) FROM event_blocks), \
     (SELECT MIN(first_received_ms) FROM event_blocks), \
     (SELECT MAX(last_received_ms) FROM event_blocks), \
     (SELECT count(*) FROM commands)";

/// A block holds events of one such span of event time (and one of received time),
/// aligned to it: its first and last time are less than this apart.
#[cfg(feature = "database")]
pub(crate) const BLOCK_SPAN_MS: i64 = 60_000;

/// A segment holds one point's events of one such span (aligned) from one pass: a point
/// that changes once a minute still fills a segment with a pass's worth of its events.
#[cfg(feature = "database")]
pub(crate) const SEGMENT_SPAN_MS: i64 = 3_600_000;

/// A pass runs when the tail holds this many events a point on average (a point's
/// segment then holds that many) ...
#[cfg(feature = "database")]
pub(crate) const PASS_EVENTS_PER_POINT: usize = 16;

/// ... or this many events in all (the most a point's query or a trend unpacks from the
/// tail: about 20 ms).
#[cfg(feature = "database")]
pub(crate) const PASS_EVENTS: usize = 262_144;

#[cfg(feature = "database")]
pub(crate) mod append;
#[cfg(feature = "database")]
pub(crate) mod list;
#[cfg(feature = "database")]
pub(crate) mod purge;
#[cfg(feature = "database")]
pub(crate) mod trend;

#[cfg(feature = "database")]
use std::collections::HashMap;

/// A store's history: the name dictionary's copy and the writer's state.
#[cfg(feature = "database")]
#[derive(Debug)]
pub(crate) struct History {
    pub(crate) names: names::Names,
    /// `None` until the first append loads it (the counter and the tail).
    pub(crate) writer: tokio::sync::Mutex<Option<WriterState>>,
    /// Segment the tail after every append (tests: every event through the segments).
    pub(crate) pass_every_append: bool,
    /// The newest block's first time this store has seen (appended or read at the first
    /// query), `i64::MIN` before: where a newest-first page starts on PostgreSQL.
    pub(crate) newest_block_ms: std::sync::atomic::AtomicI64,
}

#[cfg(feature = "database")]
impl Default for History {
    fn default() -> History {
        History {
            names: names::Names::default(),
            writer: tokio::sync::Mutex::new(None),
            pass_every_append: false,
            newest_block_ms: std::sync::atomic::AtomicI64::new(i64::MIN),
        }
    }
}

#[cfg(feature = "database")]
impl History {
    /// The start of the UTC day of the newest block seen, if any.
    pub(crate) fn newest_day(&self) -> Option<i64> {
        let ms = self
            .newest_block_ms
            .load(std::sync::atomic::Ordering::Relaxed);
        (ms != i64::MIN).then(|| ms - ms.rem_euclid(86_400_000))
    }

    /// Notes blocks' first times seen.
    pub(crate) fn saw_blocks(&self, first_ms: impl IntoIterator<Item = i64>) {
        if let Some(newest) = first_ms.into_iter().max() {
            self.newest_block_ms
                .fetch_max(newest, std::sync::atomic::Ordering::Relaxed);
        }
    }
}

/// Ids a writer takes from a shared counter at once (PostgreSQL): one round trip per
/// this many events.
#[cfg(feature = "database")]
pub(crate) const ID_RANGE: usize = 65_536;

/// What the writer keeps between appends.
#[cfg(feature = "database")]
#[derive(Debug, Default)]
pub(crate) struct WriterState {
    /// The id the next event gets (SQLite: the store's counter).
    pub(crate) next_id: i64,
    /// Ids taken from a shared counter and not yet used, `next..end` (PostgreSQL).
    pub(crate) reserved: Option<(i64, i64)>,
    /// The events not yet segmented.
    pub(crate) tail: write::Tail,
    /// Per key source, the largest sequence stored (looked up once): a batch whose
    /// sequences all lie above it needs no lookup of stored keys.
    pub(crate) largest_sequence: HashMap<codec::NameId, i64>,
}
