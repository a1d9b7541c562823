//! The event history on PostgreSQL: an append's key runs and blocks by one statement
//! over arrays, a pass's segments by binary COPY and its rollups by one statement over
//! arrays, snapshots as
//! REPEATABLE READ transactions, and the move of the rows of schema version 5 into
//! blocks.
//!
//! Several processes may share a store: ids come from `event_counter` a batch at a time,
//! names are added with `ON CONFLICT DO NOTHING`, and a pass turns its blocks' `segmented`
//! on under an advisory lock and only where it is still off: a writer that finds one of
//! its blocks segmented by another (which read it as its own tail at open) writes
//! nothing and reads its tail again.

use std::collections::HashMap;
use std::sync::Arc;

use deadpool_postgres::{Object, Transaction};
use tokio_postgres::binary_copy::BinaryCopyInWriter;
use tokio_postgres::types::Type;
use tokio_postgres::{GenericClient, IsolationLevel};

use super::partitions::History as Day;
use super::PostgresStore;
use crate::history::codec::NameId;
use crate::history::write::{self, EventNames, HistoryWrite};
use crate::sql::row::{event_from_row, Cell, OwnedRow, EVENT_COLUMNS};
use crate::sql::{Database, Statement};
use crate::StoreError;

/// Advisory lock of a pass: two writers' passes never interleave.
const PASS_LOCK: i64 = 0x5354_414E_4943_4532; // "STANICE2"

/// Rows of a day of `events` moved per pass by [`move_rows_into_blocks`].
const ROWS_PER_MOVE: i64 = 65_536;

/// An append's key runs and blocks, in one statement over arrays: a live append is one
/// round trip (a COPY in a transaction took four: BEGIN, COPY, the keys, COMMIT).
pub(super) const INSERT_BLOCKS: &str = "WITH keys AS ( \
         INSERT INTO event_keys (source, first_seq, last_seq, first_id) \
         SELECT * FROM unnest($1::int8[], $2::int8[], $3::int8[], $4::int8[])) \
     INSERT INTO event_blocks (id, events, first_ms, last_ms, first_received_ms, \
         last_received_ms, node, causes, invalid, segmented, data) \
     SELECT * FROM unnest($5::int8[], $6::int4[], $7::int8[], $8::int8[], $9::int8[], \
         $10::int8[], $11::int8[], $12::int8[], $13::int4[], $14::int2[], $15::bytea[])";

const COPY_SEGMENTS: &str = "COPY event_segments (point, start_ms, part, first_ms, last_ms, \
     events, data) FROM STDIN (FORMAT binary)";

const SEGMENT_TYPES: [Type; 7] = [
    Type::INT8,
    Type::INT8,
    Type::INT8,
    Type::INT8,
    Type::INT8,
    Type::INT4,
    Type::BYTEA,
];

/// Merges a pass's minutes into `trend_rollups`, in key order (two writers wait for each
/// other instead of deadlocking): against a minute stored already the earlier first value
/// (on the same millisecond the stored one: a pass holds only events with higher ids than
/// the passes before it) and the later last value (on the same millisecond the pass's).
const MERGE_ROLLUPS: &str = "INSERT INTO trend_rollups (point, start_ms, first_ms, last_ms, \
     min_value, max_value, sum_value, samples, invalid, first_value, last_value) \
     SELECT * FROM unnest($1::text[], $2::int8[], $3::int8[], $4::int8[], $5::float8[], \
                          $6::float8[], $7::float8[], $8::int8[], $9::int8[], $10::float8[], \
                          $11::float8[]) \
     ORDER BY 1, 2 \
     ON CONFLICT (point, start_ms) DO UPDATE SET \
         first_ms  = LEAST(trend_rollups.first_ms, EXCLUDED.first_ms), \
         last_ms   = GREATEST(trend_rollups.last_ms, EXCLUDED.last_ms), \
         min_value = LEAST(trend_rollups.min_value, EXCLUDED.min_value), \
         max_value = GREATEST(trend_rollups.max_value, EXCLUDED.max_value), \
         sum_value = trend_rollups.sum_value + EXCLUDED.sum_value, \
         samples   = trend_rollups.samples + EXCLUDED.samples, \
         invalid   = GREATEST(trend_rollups.invalid, EXCLUDED.invalid), \
         first_value = CASE WHEN EXCLUDED.first_ms < trend_rollups.first_ms \
                              OR trend_rollups.first_value IS NULL \
                            THEN EXCLUDED.first_value ELSE trend_rollups.first_value END, \
         last_value  = CASE WHEN EXCLUDED.last_ms >= trend_rollups.last_ms \
                              OR trend_rollups.last_value IS NULL \
                            THEN EXCLUDED.last_value ELSE trend_rollups.last_value END";

/// Writes an append's blocks and key runs: one statement (one round trip, atomic alone).
pub(super) async fn write_blocks(
    client: &impl GenericClient,
    statement: &tokio_postgres::Statement,
    w: &HistoryWrite,
) -> Result<(), StoreError> {
    let keys = |f: fn(&write::KeyRun) -> i64| w.keys.iter().map(f).collect::<Vec<i64>>();
    let blocks = |f: fn(&write::BlockRow) -> i64| w.blocks.iter().map(f).collect::<Vec<i64>>();
    let small = |f: fn(&write::BlockRow) -> i64| {
        w.blocks
            .iter()
            .map(|b| i32::try_from(f(b)).unwrap_or(i32::MAX))
            .collect::<Vec<i32>>()
    };
    let nodes: Vec<Option<i64>> = w.blocks.iter().map(|b| b.node.map(i64::from)).collect();
    let segmented: Vec<i16> = w.blocks.iter().map(|b| i16::from(b.segmented)).collect();
    let data: Vec<&[u8]> = w.blocks.iter().map(|b| b.data.as_slice()).collect();
    client
        .execute(
            statement,
            &[
                &keys(|k| i64::from(k.source)),
                &keys(|k| k.first_seq),
                &keys(|k| k.last_seq),
                &keys(|k| k.first_id),
                &blocks(|b| b.id),
                &small(|b| b.events),
                &blocks(|b| b.first_ms),
                &blocks(|b| b.last_ms),
                &blocks(|b| b.first_received_ms),
                &blocks(|b| b.last_received_ms),
                &nodes,
                &blocks(|b| b.causes),
                &small(|b| b.invalid),
                &segmented,
                &data,
            ],
        )
        .await?;
    Ok(())
}

/// Writes a pass (segments, rollups, its blocks turned segmented) in the open
/// transaction `tx`.
pub(super) async fn write_pass(tx: &Transaction<'_>, w: &HistoryWrite) -> Result<(), StoreError> {
    let Some(pass) = &w.pass else {
        return Ok(());
    };
    tx.execute("SELECT pg_advisory_xact_lock($1)", &[&PASS_LOCK])
        .await?;
    if !pass.blocks.is_empty() {
        let flipped = tx
            .execute(
                "UPDATE event_blocks SET segmented = 1 \
                 WHERE id = ANY($1::int8[]) AND segmented = 0",
                &[&pass.blocks],
            )
            .await?;
        if flipped != pass.blocks.len() as u64 {
            return Err(StoreError::Conflict(format!(
                "{} of the {} blocks of a pass were segmented by another writer",
                pass.blocks.len() as u64 - flipped,
                pass.blocks.len()
            )));
        }
    }
    if !pass.segments.is_empty() {
        let copy = tx.prepare_cached(COPY_SEGMENTS).await?;
        let sink = tx.copy_in(&copy).await?;
        let mut writer = std::pin::pin!(BinaryCopyInWriter::new(sink, &SEGMENT_TYPES));
        for g in &pass.segments {
            let point = i64::from(g.point);
            let events = i32::try_from(g.events).unwrap_or(i32::MAX);
            writer
                .as_mut()
                .write(&[
                    &point,
                    &g.start_ms,
                    &g.part,
                    &g.first_ms,
                    &g.last_ms,
                    &events,
                    &g.data,
                ])
                .await?;
        }
        writer.as_mut().finish().await?;
    }
    if !pass.rollups.is_empty() {
        let r = &pass.rollups;
        let points: Vec<&str> = r.iter().map(|r| &*r.point).collect();
        let ints = |f: fn(&write::RollupRow) -> i64| r.iter().map(f).collect::<Vec<i64>>();
        let reals = |f: fn(&write::RollupRow) -> f64| r.iter().map(f).collect::<Vec<f64>>();
        let merge = tx.prepare_cached(MERGE_ROLLUPS).await?;
        tx.execute(
            &merge,
            &[
                &points,
                &ints(|r| r.start_ms),
                &ints(|r| r.first_ms),
                &ints(|r| r.last_ms),
                &reals(|r| r.min),
                &reals(|r| r.max),
                &reals(|r| r.sum),
                &ints(|r| r.samples),
                &ints(|r| i64::from(r.invalid)),
                &reals(|r| r.first_value),
                &reals(|r| r.last_value),
            ],
        )
        .await?;
    }
    Ok(())
}

/// Runs `statements` in one REPEATABLE READ transaction: one snapshot for all.
pub(super) async fn snapshot(
    conn: &mut Object,
    statements: &[Statement],
) -> Result<Vec<Vec<OwnedRow>>, StoreError> {
    let tx = conn
        .build_transaction()
        .isolation_level(IsolationLevel::RepeatableRead)
        .read_only(true)
        .start()
        .await?;
    let mut out = Vec::with_capacity(statements.len());
    for run in statements {
        let stmt = tx.prepare_cached(&run.sql).await?;
        let rows = tx.query(&stmt, &super::sql_params(&run.params)).await?;
        let mut read = Vec::with_capacity(rows.len());
        for row in &rows {
            let mut cells = Vec::with_capacity(row.len());
            for (i, column) in row.columns().iter().enumerate() {
                let ty = column.type_();
                cells.push(if *ty == Type::INT2 {
                    row.try_get::<_, Option<i16>>(i)?
                        .map_or(Cell::Null, |v| Cell::Int(i64::from(v)))
                } else if *ty == Type::INT4 {
                    row.try_get::<_, Option<i32>>(i)?
                        .map_or(Cell::Null, |v| Cell::Int(i64::from(v)))
                } else if *ty == Type::INT8 {
                    row.try_get::<_, Option<i64>>(i)?
                        .map_or(Cell::Null, Cell::Int)
                } else if *ty == Type::FLOAT8 {
                    row.try_get::<_, Option<f64>>(i)?
                        .map_or(Cell::Null, Cell::Real)
                } else if *ty == Type::BYTEA {
                    row.try_get::<_, Option<Vec<u8>>>(i)?
                        .map_or(Cell::Null, Cell::Blob)
                } else if *ty == Type::BOOL {
                    row.try_get::<_, Option<bool>>(i)?
                        .map_or(Cell::Null, |v| Cell::Int(i64::from(v)))
                } else {
                    row.try_get::<_, Option<String>>(i)?
                        .map_or(Cell::Null, Cell::Text)
                });
            }
            read.push(OwnedRow(cells));
        }
        out.push(read);
    }
    tx.commit().await?;
    Ok(out)
}

/// Moves the rows of `events` (schema version 5 and before) into blocks, segments and
/// rollups with their ids and keys: a day partition per transaction, which drops it (an
/// interrupted move goes on at the next open), read in (time, id) order through its
/// index; the rollups are folded again from the events (emptied before the first day).
/// Then `events`, its trigger function and its id sequence go.
pub(super) async fn move_rows_into_blocks(store: &PostgresStore) -> Result<(), StoreError> {
    let mut conn = super::checkout(&store.pool).await?;
    let legacy: Option<String> = conn
        .query_one("SELECT to_regclass('events')::text", &[])
        .await?
        .try_get(0)?;
    if legacy.is_none() {
        return Ok(());
    }
    let days: Vec<String> = conn
        .query(
            "SELECT c.relname::text FROM pg_inherits i JOIN pg_class c ON c.oid = i.inhrelid \
             WHERE i.inhparent = 'events'::regclass ORDER BY 1",
            &[],
        )
        .await?
        .iter()
        .map(|r| r.try_get(0))
        .collect::<Result<_, _>>()?;
    let blocks_stored: bool = conn
        .query_one("SELECT EXISTS (SELECT 1 FROM event_blocks)", &[])
        .await?
        .try_get(0)?;
    if !blocks_stored {
        conn.batch_execute("TRUNCATE trend_rollups").await?;
    }
    let mut moved = 0u64;
    for day in days {
        moved += move_day(store, &mut conn, &day).await?;
    }
    conn.batch_execute("DROP TABLE events CASCADE; DROP FUNCTION IF EXISTS stanice_fold_rollups()")
        .await?;
    if moved > 0 {
        tracing::info!(events = moved, "moved the events into blocks (schema 6)");
    }
    Ok(())
}

/// Moves one day partition of `events`; how many events it held.
async fn move_day(store: &PostgresStore, conn: &mut Object, day: &str) -> Result<u64, StoreError> {
    let select = format!(
        "SELECT {EVENT_COLUMNS} FROM {day} WHERE (event_ms, id) > ($1::int8, $2::int8) \
         ORDER BY event_ms, id LIMIT $3::int8"
    );
    // The days of blocks first, outside the move's transaction (a day is made by a
    // statement of its own, which must not wait for the move's locks).
    let times: Vec<i64> = conn
        .query(
            &format!(
                "SELECT DISTINCT CAST(floor(event_ms / 86400000.0) * 86400000 AS BIGINT)                  FROM {day}"
            ),
            &[],
        )
        .await?
        .iter()
        .map(|r| r.try_get(0))
        .collect::<Result<_, _>>()?;
    store.make_days(conn, Day::Events, times).await?;
    let tx = conn.transaction().await?;
    let mut after = (i64::MIN, i64::MIN);
    let mut moved = 0u64;
    loop {
        let rows = tx
            .query(&select, &[&after.0, &after.1, &ROWS_PER_MOVE])
            .await?;
        if rows.is_empty() {
            break;
        }
        let events = rows
            .iter()
            .map(|r| event_from_row(r))
            .collect::<Result<Vec<_>, _>>()?;
        if let Some(e) = events.last() {
            after = (e.event_time().timestamp_millis(), e.id.unwrap_or(0));
        }
        let mut names: Vec<String> = events
            .iter()
            .flat_map(|e| {
                [e.node.clone(), e.point.clone(), e.origin.clone()]
                    .into_iter()
                    .chain(e.key.as_ref().map(|k| k.source.clone()))
            })
            .collect();
        names.sort_unstable();
        names.dedup();
        let numbers: HashMap<String, NameId> = store
            .name_ids(names)
            .await?
            .into_iter()
            .map(|(id, n)| (n, id))
            .collect();
        let number = |name: &str| numbers.get(name).copied().unwrap_or(0);
        let mut coded = Vec::with_capacity(events.len());
        for e in &events {
            let id = e.id.unwrap_or(0);
            let mut one = write::number(
                std::slice::from_ref(e),
                |e| EventNames {
                    node: number(&e.node),
                    point: number(&e.point),
                    origin: number(&e.origin),
                    key_source: e.key.as_ref().map(|k| number(&k.source)),
                },
                &HashMap::new(),
                id,
            );
            coded.append(&mut one.new);
        }
        coded.sort_by_key(|e| e.id);
        let mut tail = write::Tail::default();
        let mut blocks = Vec::new();
        for (row, events) in write::blocks(&coded) {
            tail.add(row.id, &events);
            blocks.push(row);
        }
        let by_id: HashMap<NameId, Arc<str>> = numbers
            .iter()
            .map(|(n, &id)| (id, Arc::from(n.as_str())))
            .collect();
        let write = HistoryWrite {
            next_id: 0,
            keys: write::runs_of(&coded),
            blocks,
            pass: write::pass(&tail, |id| by_id.get(&id).cloned()),
        };
        let insert = tx.prepare_cached(INSERT_BLOCKS).await?;
        write_blocks(&*tx, &insert, &write).await?;
        write_pass(&tx, &write).await?;
        moved += events.len() as u64;
    }
    tx.batch_execute(&format!("DROP TABLE {day}")).await?;
    tx.commit().await?;
    Ok(moved)
}
