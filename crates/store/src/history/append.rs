//! An append: names, stored keys, ids, blocks and (when due) a pass, written in one
//! transaction by the backend.

use std::collections::{BTreeMap, HashMap, HashSet};

use super::codec::{decode, NameId};
use super::write::{blocks, number, pass, EventNames, HistoryWrite, KeyRun, Tail};
use super::{History, WriterState};
use crate::sql::row::key_sequence;
use crate::sql::{Access, Database, Param, Statement};
use crate::{EventRecord, RecordId, StoreError};

/// Appends checked, non-empty `events`: ids in their order.
pub(crate) async fn append<D: Database>(
    db: &D,
    history: &History,
    events: &[EventRecord],
) -> Result<Vec<RecordId>, StoreError> {
    let mut writer = history.writer.lock().await;
    match append_once(db, history, &mut writer, events).await {
        // Another writer of the same database segmented part of this one's tail: the
        // tail is read again and the batch written once more (nothing of it was stored).
        Err(StoreError::Conflict(what)) => {
            tracing::debug!(%what, "an append met another writer's pass: written again");
            append_once(db, history, &mut writer, events).await
        }
        done => done,
    }
}

/// One try of [`append`], under the writer's lock.
async fn append_once<D: Database>(
    db: &D,
    history: &History,
    writer: &mut Option<WriterState>,
    events: &[EventRecord],
) -> Result<Vec<RecordId>, StoreError> {
    if writer.is_none() {
        *writer = Some(load(db, history).await?);
    }
    let Some(state) = writer.as_mut() else {
        return Err(StoreError::Closed);
    };
    learn_names(db, history, events).await?;
    let names = &history.names;
    let id = |name: &str| names.id(name).unwrap_or(0);
    let stored = stored_keys(db, history, state, events).await?;
    let first_id = match state.reserved {
        Some((next, end)) if end - next >= events.len() as i64 => next,
        _ => {
            let count = events.len().max(super::ID_RANGE);
            match db.reserve_ids(count).await? {
                Some(first) => {
                    state.reserved = Some((first, first + count as i64));
                    first
                }
                None => state.next_id,
            }
        }
    };
    let numbered = number(
        events,
        |e| EventNames {
            node: id(&e.node),
            point: id(&e.point),
            origin: id(&e.origin),
            key_source: e.key.as_ref().map(|k| id(&k.source)),
        },
        &stored,
        first_id,
    );
    let new_blocks = blocks(&numbered.new);
    for (row, events) in &new_blocks {
        state.tail.add(row.id, events);
    }
    let pass = if history.pass_every_append || state.tail.wants_pass() {
        pass(&state.tail, |point| names.name(point))
    } else {
        None
    };
    let passed = pass.is_some();
    let newest = new_blocks.iter().map(|(row, _)| row.first_ms).max();
    let write = HistoryWrite {
        next_id: numbered.next_id,
        blocks: new_blocks.into_iter().map(|(row, _)| row).collect(),
        keys: numbered.keys.clone(),
        pass,
    };
    if let Err(error) = db.write_history(write).await {
        // Nothing was stored: the state is read again at the next append (the tail as
        // stored, and what another writer may have changed).
        *writer = None;
        return Err(error);
    }
    history.saw_blocks(newest);
    state.next_id = state.next_id.max(numbered.next_id);
    if let Some((_, end)) = state.reserved {
        state.reserved = Some((numbered.next_id, end));
    }
    for run in &numbered.keys {
        let largest = state
            .largest_sequence
            .entry(run.source)
            .or_insert(run.last_seq);
        *largest = (*largest).max(run.last_seq);
    }
    if passed {
        state.tail = Tail::default();
    }
    Ok(numbered.ids)
}

/// The writer's state as stored: the event counter and the tail.
async fn load<D: Database>(db: &D, history: &History) -> Result<WriterState, StoreError> {
    refresh_names(db, history).await?;
    let next_id = db
        .rows(read("SELECT next_id FROM event_counter", Vec::new()), |r| {
            r.need_int(0)
        })
        .await?
        .into_iter()
        .next()
        .unwrap_or(1);
    let mut tail = Tail::default();
    for (id, data) in db.rows(read(TAIL_BLOCKS, Vec::new()), id_and_data).await? {
        tail.add(id, &decode(&data)?);
    }
    Ok(WriterState {
        next_id,
        reserved: None,
        tail,
        largest_sequence: HashMap::new(),
    })
}

/// The blocks not yet segmented, by id.
pub(crate) const TAIL_BLOCKS: &str =
    "SELECT id, data FROM event_blocks WHERE segmented = 0 ORDER BY id";

/// The blocks not yet segmented holding event times in `low..=high`: what a query of
/// those times reads of the tail (a trend of last month reads none of today's tail).
pub(crate) fn tail_between<D: Database>(low: i64, high: i64) -> Statement {
    let p = |n: usize| Param::int(0).placeholder(D::BACKEND, n);
    read(
        &format!(
            "SELECT id, data FROM event_blocks \
             WHERE segmented = 0 AND last_ms >= {} AND first_ms <= {} ORDER BY id",
            p(1),
            p(2)
        ),
        vec![Param::int(low), Param::int(high)],
    )
}

/// A block's (or segment's) id and packed events.
pub(crate) fn id_and_data(r: &dyn crate::sql::row::Columns) -> Result<(i64, Vec<u8>), StoreError> {
    Ok((r.need_int(0)?, r.blob(1)?.unwrap_or_default()))
}

/// A read statement.
pub(crate) fn read(sql: &str, params: Vec<Param>) -> Statement {
    Statement {
        access: Access::Read,
        sql: sql.to_owned(),
        params,
    }
}

/// Loads the names the copy does not know.
pub(crate) async fn refresh_names<D: Database>(
    db: &D,
    history: &History,
) -> Result<(), StoreError> {
    // All of them, not those above the largest known: another writer's names may have
    // numbers below ours (names are a few thousand rows at most).
    let pairs = db
        .rows(read("SELECT id, name FROM event_names", Vec::new()), |r| {
            let id = r.need_int(0)?;
            let id = NameId::try_from(id)
                .map_err(|_| StoreError::Corrupt(format!("name number {id}")))?;
            Ok((id, r.need_text(1)?))
        })
        .await?;
    history.names.learn(pairs);
    Ok(())
}

/// Makes sure every name of the batch has a number.
async fn learn_names<D: Database>(
    db: &D,
    history: &History,
    events: &[EventRecord],
) -> Result<(), StoreError> {
    let mut missing: HashSet<&str> = HashSet::new();
    for e in events {
        let key = e.key.as_ref().map(|k| k.source.as_str());
        for name in [e.node.as_str(), e.point.as_str(), e.origin.as_str()]
            .into_iter()
            .chain(key)
        {
            if history.names.id(name).is_none() {
                missing.insert(name);
            }
        }
    }
    if missing.is_empty() {
        return Ok(());
    }
    let pairs = db
        .name_ids(missing.into_iter().map(str::to_owned).collect())
        .await?;
    history.names.learn(pairs);
    Ok(())
}

/// The stored ids of the batch's keys that are stored already.
async fn stored_keys<D: Database>(
    db: &D,
    history: &History,
    state: &mut WriterState,
    events: &[EventRecord],
) -> Result<HashMap<(NameId, i64), i64>, StoreError> {
    let mut ranges: BTreeMap<NameId, (i64, i64)> = BTreeMap::new();
    for key in events.iter().filter_map(|e| e.key.as_ref()) {
        let Some(source) = history.names.id(&key.source) else {
            continue;
        };
        let seq = key_sequence(key.sequence);
        let range = ranges.entry(source).or_insert((seq, seq));
        *range = (range.0.min(seq), range.1.max(seq));
    }
    let mut stored = HashMap::new();
    for (source, (low, high)) in ranges {
        let largest = match state.largest_sequence.get(&source) {
            Some(&largest) => largest,
            None => {
                let largest = largest_sequence(db, source).await?;
                state.largest_sequence.insert(source, largest);
                largest
            }
        };
        if low > largest {
            continue; // all new: the recorder's case
        }
        let runs = runs_between(db, source, low, high).await?;
        for key in events.iter().filter_map(|e| e.key.as_ref()) {
            if history.names.id(&key.source) != Some(source) {
                continue;
            }
            let seq = key_sequence(key.sequence);
            let i = runs.partition_point(|r| r.first_seq <= seq);
            if let Some(run) = i.checked_sub(1).and_then(|i| runs.get(i)) {
                if seq <= run.last_seq {
                    stored.insert((source, seq), run.first_id + (seq - run.first_seq));
                }
            }
        }
    }
    Ok(stored)
}

/// The largest stored sequence of `source` (-1 when none: sequences start at 0).
async fn largest_sequence<D: Database>(db: &D, source: NameId) -> Result<i64, StoreError> {
    let p = Param::int(0).placeholder(D::BACKEND, 1);
    let rows = db
        .rows(
            read(
                &format!(
                    "SELECT last_seq FROM event_keys WHERE source = {p} \
                     ORDER BY first_seq DESC LIMIT 1"
                ),
                vec![Param::int(i64::from(source))],
            ),
            |r| r.need_int(0),
        )
        .await?;
    Ok(rows.into_iter().next().unwrap_or(-1))
}

/// The runs of `source` holding a sequence in `low..=high`, by first sequence. Runs do
/// not overlap, so at most one starts before `low` and reaches it.
async fn runs_between<D: Database>(
    db: &D,
    source: NameId,
    low: i64,
    high: i64,
) -> Result<Vec<KeyRun>, StoreError> {
    let b = |n: usize| Param::int(0).placeholder(D::BACKEND, n);
    let (s, lo, hi) = (b(1), b(2), b(3));
    let sql = format!(
        "SELECT first_seq, last_seq, first_id FROM ( \
             SELECT first_seq, last_seq, first_id FROM event_keys \
             WHERE source = {s} AND first_seq < {lo} ORDER BY first_seq DESC LIMIT 1) AS before \
         WHERE last_seq >= {lo} \
         UNION ALL \
         SELECT first_seq, last_seq, first_id FROM event_keys \
         WHERE source = {s} AND first_seq >= {lo} AND first_seq <= {hi} \
         ORDER BY 1"
    );
    db.rows(
        read(
            &sql,
            vec![
                Param::int(i64::from(source)),
                Param::int(low),
                Param::int(high),
            ],
        ),
        |r| {
            Ok(KeyRun {
                source: 0,
                first_seq: r.need_int(0)?,
                last_seq: r.need_int(1)?,
                first_id: r.need_int(2)?,
            })
        },
    )
    .await
}
