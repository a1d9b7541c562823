//! Prototype: can a block layout take 300,000 events/s on SQLite? (design measurement)
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
use rusqlite::{params, Connection};
use std::collections::HashMap;
use std::time::Instant;

fn varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}
fn zz(v: i64) -> u64 {
    ((v << 1) ^ (v >> 63)) as u64
}

struct Ev {
    point: String,
    node: String,
    value: f64,
    ms: i64,
    seq: u64,
}

fn main() {
    let path = "/tmp/proto.db";
    let _ = std::fs::remove_file(path);
    let _ = std::fs::remove_file("/tmp/proto.db-wal");
    let c = Connection::open(path).unwrap();
    c.query_row("PRAGMA journal_mode=WAL", [], |_| Ok(())).unwrap();
    c.execute_batch(
        "PRAGMA synchronous=NORMAL; PRAGMA cache_size=-65536;
        CREATE TABLE names (id INTEGER PRIMARY KEY, name TEXT UNIQUE);
        CREATE TABLE event_blocks (id INTEGER PRIMARY KEY, n INTEGER, min_ms INTEGER, max_ms INTEGER,
            min_rx INTEGER, max_rx INTEGER, causes INTEGER, invalid INTEGER, data BLOB);
        CREATE INDEX blocks_max ON event_blocks(max_ms);
        CREATE INDEX blocks_rx ON event_blocks(max_rx);
        CREATE TABLE key_runs (source TEXT, first_seq INTEGER, last_seq INTEGER, first_id INTEGER,
            PRIMARY KEY (source, first_seq)) WITHOUT ROWID;
        CREATE TABLE segments (point INTEGER, start_ms INTEGER, part INTEGER, first_ms, last_ms,
            min_v, max_v, sum_v, n, invalid, first_v, last_v, data BLOB,
            PRIMARY KEY (point, start_ms, part)) WITHOUT ROWID;",
    )
    .unwrap();
    let batch: usize = std::env::args().nth(1).map(|s| s.parse().unwrap()).unwrap_or(500);
    let total: usize = std::env::args().nth(2).map(|s| s.parse().unwrap()).unwrap_or(3_000_000);
    let seg_every: usize = std::env::args().nth(3).map(|s| s.parse().unwrap()).unwrap_or(300_000);
    let points = 10_000usize;
    let start_ms = 1_780_000_000_000i64;
    let events: Vec<Ev> = (0..total)
        .map(|i| {
            let p = (i * 7919) % points;
            Ev {
                point: format!("N{:02}_P{p}", p % 50),
                node: format!("N{:02}", p % 50),
                value: (i % 1000) as f64 * 0.25,
                ms: start_ms + (i as i64 * 1000) / 300_000,
                seq: i as u64,
            }
        })
        .collect();
    let mut dict: HashMap<String, i64> = HashMap::new();
    let mut next_id = 1i64;
    let mut pending: Vec<(i64, i64, i64, f64)> = Vec::new(); // point, id, ms, v
    let t0 = Instant::now();
    let mut seg_time = 0.0;
    let mut part = 0i64;
    for chunk in events.chunks(batch) {
        let tx = c.unchecked_transaction().unwrap();
        let mut data = Vec::with_capacity(chunk.len() * 24);
        let mut prev = 0i64;
        for e in chunk {
            let pid = match dict.get(&e.point) {
                Some(&id) => id,
                None => {
                    tx.execute("INSERT INTO names(name) VALUES (?1)", [&e.point]).unwrap();
                    tx.execute("INSERT OR IGNORE INTO names(name) VALUES (?1)", [&e.node]).unwrap();
                    let id = tx.last_insert_rowid();
                    dict.insert(e.point.clone(), id);
                    id
                }
            };
            varint(&mut data, pid as u64);
            varint(&mut data, 7); // node id
            varint(&mut data, pid as u64); // ioa
            data.push(4);
            data.extend_from_slice(&e.value.to_le_bytes());
            data.push(0); // quality
            data.push(3); // cause
            varint(&mut data, zz(e.ms - prev));
            varint(&mut data, 0); // received delta
            varint(&mut data, 1); // origin id
            prev = e.ms;
            pending.push((pid, next_id + (pending.len() as i64 % batch as i64), e.ms, e.value));
        }
        let (min_ms, max_ms) = (chunk.first().unwrap().ms, chunk.last().unwrap().ms);
        tx.prepare_cached("INSERT INTO event_blocks VALUES (?1,?2,?3,?4,?5,?6,?7,?8,?9)")
            .unwrap()
            .execute(params![next_id, chunk.len() as i64, min_ms, max_ms, min_ms, max_ms, 8, 0, data])
            .unwrap();
        tx.prepare_cached("INSERT INTO key_runs VALUES (?1,?2,?3,?4)")
            .unwrap()
            .execute(params!["live", chunk[0].seq as i64, chunk.last().unwrap().seq as i64, next_id])
            .unwrap();
        next_id += chunk.len() as i64;
        tx.commit().unwrap();
        if pending.len() >= seg_every {
            let s = Instant::now();
            let mut groups: HashMap<(i64, i64), Vec<(i64, i64, f64)>> = HashMap::new();
            for &(p, id, ms, v) in &pending {
                groups.entry((p, ms - ms.rem_euclid(60_000))).or_default().push((id, ms, v));
            }
            let tx = c.unchecked_transaction().unwrap();
            {
                let mut st = tx
                    .prepare_cached("INSERT INTO segments VALUES (?1,?2,?3,?4,?5,?6,?7,?8,?9,?10,?11,?12,?13)")
                    .unwrap();
                for ((p, minute), evs) in &groups {
                    let mut d = Vec::with_capacity(evs.len() * 14);
                    let (mut mn, mut mx, mut sum) = (f64::MAX, f64::MIN, 0.0);
                    let mut prev = *minute;
                    for &(id, ms, v) in evs {
                        varint(&mut d, id as u64);
                        varint(&mut d, zz(ms - prev));
                        prev = ms;
                        d.extend_from_slice(&v.to_le_bytes());
                        d.push(0);
                        mn = mn.min(v);
                        mx = mx.max(v);
                        sum += v;
                    }
                    st.execute(params![p, minute, part, evs[0].1, evs.last().unwrap().1, mn, mx, sum,
                        evs.len() as i64, 0, evs[0].2, evs.last().unwrap().2, d]).unwrap();
                }
            }
            tx.commit().unwrap();
            part += 1;
            pending.clear();
            seg_time += s.elapsed().as_secs_f64();
        }
    }
    let el = t0.elapsed().as_secs_f64();
    println!("batch {batch}: {:.0} events/s ({total} events, {el:.2} s, segments {seg_time:.2} s)", total as f64 / el);
}
