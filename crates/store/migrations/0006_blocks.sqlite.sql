-- Stanice event store, schema version 6 on SQLite: the event history in blocks (the
-- crate's `history` module says why and how). Events are packed many to a row: a block
-- per minute of an append (event_blocks), and again per point and hour by the writer's
-- passes (event_segments); the idempotent keys are kept as runs of sequences
-- (event_keys); names are numbered (event_names). trend_rollups stays as it is, folded by
-- the passes.
--
-- The rows of `events` are moved into blocks by the program right after this step (SQL
-- cannot pack them), in id order with their ids, and the table is then dropped; the
-- rollups are folded again from them on the way (the minutes of schema version 4 get
-- their first and last value).

CREATE TABLE event_names (
    id   INTEGER PRIMARY KEY,
    name TEXT NOT NULL UNIQUE
);

CREATE TABLE event_blocks (
    id                INTEGER PRIMARY KEY,  -- its smallest event id
    events            INTEGER NOT NULL,
    first_ms          INTEGER NOT NULL,     -- event times, within one minute
    last_ms           INTEGER NOT NULL,
    first_received_ms INTEGER NOT NULL,     -- received times, within one minute
    last_received_ms  INTEGER NOT NULL,
    node              INTEGER,              -- every event's node, when they are one node's
    causes            INTEGER NOT NULL,     -- bit 1 << cause code per cause present
    invalid           INTEGER NOT NULL,     -- events with IV set
    segmented         INTEGER NOT NULL,     -- 1: its events are in event_segments
    data              BLOB    NOT NULL      -- the events, packed (history::codec)
);

-- The event list reads blocks by their last time, newest first, or by their first time,
-- oldest first (each index ends in the id: the keyset of its pages).
CREATE INDEX event_blocks_last           ON event_blocks (last_ms);
CREATE INDEX event_blocks_first          ON event_blocks (first_ms);
CREATE INDEX event_blocks_last_received  ON event_blocks (last_received_ms);
CREATE INDEX event_blocks_first_received ON event_blocks (first_received_ms);
-- The "invalid only" view stays fast however rare invalid events are.
CREATE INDEX event_blocks_last_invalid   ON event_blocks (last_ms) WHERE invalid > 0;
CREATE INDEX event_blocks_first_invalid  ON event_blocks (first_ms) WHERE invalid > 0;
CREATE INDEX event_blocks_tail     ON event_blocks (id) WHERE segmented = 0;

CREATE TABLE event_segments (
    point    INTEGER NOT NULL,
    start_ms INTEGER NOT NULL,  -- the hour
    part     INTEGER NOT NULL,  -- the pass: its smallest block id
    first_ms INTEGER NOT NULL,
    last_ms  INTEGER NOT NULL,
    events   INTEGER NOT NULL,
    data     BLOB    NOT NULL,
    PRIMARY KEY (point, start_ms, part)
) WITHOUT ROWID;

-- A point's event list reads its segments by their last time, newest first, or by their
-- first time, oldest first.
CREATE INDEX event_segments_last  ON event_segments (point, last_ms);
CREATE INDEX event_segments_first ON event_segments (point, first_ms);

CREATE TABLE event_keys (
    source    INTEGER NOT NULL,  -- the key source's name
    first_seq INTEGER NOT NULL,
    last_seq  INTEGER NOT NULL,
    first_id  INTEGER NOT NULL,  -- sequence first_seq + i has id first_id + i
    PRIMARY KEY (source, first_seq)
) WITHOUT ROWID;

-- The id of the next event: ids are never reused, even after every block is purged.
CREATE TABLE event_counter (next_id INTEGER NOT NULL);
INSERT INTO event_counter (next_id)
SELECT COALESCE((SELECT MAX(seq) FROM sqlite_sequence WHERE name = 'events'), 0) + 1;
