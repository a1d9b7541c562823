//! Retention over the history: the events before a cutoff go, exactly.
//!
//! Whole blocks and segments before it are deleted; the few that hold events on both
//! sides (a block's minute or a segment's hour holding the cutoff) are written
//! again without the old ones. The writer's state is dropped and read again at the next
//! append (a block of its tail may have gone or changed).

use super::append::read;
use super::codec::decode;
use super::write::{block_row, span_start, HistoryWrite, Pass, SegmentRow};
use super::{History, BLOCK_SPAN_MS, SEGMENT_SPAN_MS};
use crate::sql::{delete_older, Database, Param};
use crate::StoreError;

/// Deletes the events with an event time before `cutoff_ms`; how many went.
pub(crate) async fn purge<D: Database>(
    db: &D,
    history: &History,
    cutoff_ms: i64,
) -> Result<u64, StoreError> {
    let mut writer = history.writer.lock().await;
    *writer = None;
    let p = |n: usize| Param::int(0).placeholder(D::BACKEND, n);
    let whole = db
        .rows(
            read(
                &format!(
                    "SELECT CAST(COALESCE(SUM(events), 0) AS BIGINT) FROM event_blocks \
                     WHERE last_ms < {}",
                    p(1)
                ),
                vec![Param::int(cutoff_ms)],
            ),
            |r| r.need_int(0),
        )
        .await?
        .into_iter()
        .next()
        .unwrap_or(0);
    delete_older(db, "event_blocks", "last_ms", cutoff_ms).await?;
    let mut gone = u64::try_from(whole).unwrap_or(0);
    // The blocks holding the cutoff: their times lie within a span.
    let straddling = db
        .rows(
            read(
                &format!(
                    "SELECT id, segmented, data FROM event_blocks \
                     WHERE last_ms >= {} AND last_ms < {} AND first_ms < {}",
                    p(1),
                    p(2),
                    p(3)
                ),
                vec![
                    Param::int(cutoff_ms),
                    Param::int(cutoff_ms.saturating_add(BLOCK_SPAN_MS)),
                    Param::int(cutoff_ms),
                ],
            ),
            |r| {
                Ok((
                    r.need_int(0)?,
                    r.need_int(1)? != 0,
                    r.blob(2)?.unwrap_or_default(),
                ))
            },
        )
        .await?;
    for (id, segmented, data) in straddling {
        let events = decode(&data)?;
        let kept: Vec<_> = events
            .iter()
            .filter(|e| e.event_ms() >= cutoff_ms)
            .cloned()
            .collect();
        gone += (events.len() - kept.len()) as u64;
        db.execute(
            format!("DELETE FROM event_blocks WHERE id = {}", p(1)),
            vec![Param::int(id)],
        )
        .await?;
        if let Some(mut row) = block_row(&kept) {
            row.segmented = segmented;
            db.write_history(HistoryWrite {
                blocks: vec![row],
                ..HistoryWrite::default()
            })
            .await?;
        }
    }
    purge_segments(db, cutoff_ms).await?;
    Ok(gone)
}

/// Deletes the segments' events before `cutoff_ms`, point by point (the segments are
/// keyed by point first).
async fn purge_segments<D: Database>(db: &D, cutoff_ms: i64) -> Result<(), StoreError> {
    let points = db
        .rows(
            read(
                "WITH RECURSIVE points (point) AS ( \
                     SELECT MIN(point) FROM event_segments \
                     UNION ALL \
                     SELECT (SELECT MIN(s.point) FROM event_segments s WHERE s.point > p.point) \
                     FROM points p WHERE p.point IS NOT NULL) \
                 SELECT point FROM points WHERE point IS NOT NULL",
                Vec::new(),
            ),
            |r| r.need_int(0),
        )
        .await?;
    let hour = span_start(cutoff_ms, SEGMENT_SPAN_MS);
    let p = |n: usize| Param::int(0).placeholder(D::BACKEND, n);
    for point in points {
        db.execute(
            format!(
                "DELETE FROM event_segments WHERE point = {} AND start_ms < {}",
                p(1),
                p(2)
            ),
            vec![Param::int(point), Param::int(hour)],
        )
        .await?;
        if hour == cutoff_ms {
            continue;
        }
        let straddling = db
            .rows(
                read(
                    &format!(
                        "SELECT part, data FROM event_segments \
                         WHERE point = {} AND start_ms = {}",
                        p(1),
                        p(2)
                    ),
                    vec![Param::int(point), Param::int(hour)],
                ),
                |r| Ok((r.need_int(0)?, r.blob(1)?.unwrap_or_default())),
            )
            .await?;
        for (part, data) in straddling {
            let events = decode(&data)?;
            let kept: Vec<_> = events
                .iter()
                .filter(|e| e.event_ms() >= cutoff_ms)
                .cloned()
                .collect();
            if kept.len() == events.len() {
                continue;
            }
            db.execute(
                format!(
                    "DELETE FROM event_segments WHERE point = {} AND start_ms = {} AND part = {}",
                    p(1),
                    p(2),
                    p(3)
                ),
                vec![Param::int(point), Param::int(hour), Param::int(part)],
            )
            .await?;
            if let (Some(first), Some(last)) = (kept.first(), kept.last()) {
                let segment = SegmentRow {
                    point: u32::try_from(point).unwrap_or(0),
                    start_ms: hour,
                    part,
                    first_ms: first.event_ms(),
                    last_ms: last.event_ms(),
                    events: i64::try_from(kept.len()).unwrap_or(i64::MAX),
                    data: super::codec::encode(&kept),
                };
                db.write_history(HistoryWrite {
                    pass: Some(Pass {
                        part,
                        segments: vec![segment],
                        ..Pass::default()
                    }),
                    ..HistoryWrite::default()
                })
                .await?;
            }
        }
    }
    Ok(())
}
