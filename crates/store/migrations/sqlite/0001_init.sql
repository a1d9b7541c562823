-- Stanice event store, SQLite schema version 1.
-- Times are milliseconds since the Unix epoch (UTC). Enum columns hold the stable codes
-- of the Rust enums (EventCause::code, CommandOutcome::code, ...).

CREATE TABLE events (
    id             INTEGER PRIMARY KEY AUTOINCREMENT,  -- never reused, even after purges
    node           TEXT    NOT NULL,
    point          TEXT    NOT NULL,
    ioa            INTEGER,
    value_kind     INTEGER NOT NULL,  -- 1 bool, 2 double point, 3 int, 4 float, 5 bits, 6 text
    value_int      INTEGER,
    value_float    REAL,
    value_text     TEXT,
    quality        INTEGER NOT NULL,  -- IV 1, NT 2, SB 4, BL 8, OV 16
    source_ms      INTEGER,           -- source time stamp, NULL when none
    source_invalid INTEGER NOT NULL,  -- the time tag's IV bit
    received_ms    INTEGER NOT NULL,
    event_ms       INTEGER NOT NULL,  -- source_ms when present and valid, else received_ms
    cause          INTEGER NOT NULL,
    origin         TEXT    NOT NULL
);

-- Keyset pagination by (time, id), plain and per point/node; retention by received time.
CREATE INDEX events_event_time    ON events (event_ms, id);
CREATE INDEX events_received_time ON events (received_ms, id);
CREATE INDEX events_point_time    ON events (point, event_ms, id);
CREATE INDEX events_node_time     ON events (node, event_ms, id);
-- The "invalid only" view (IV set) stays fast however rare invalid events are.
CREATE INDEX events_invalid_time  ON events (event_ms, id) WHERE (quality & 1) <> 0;

CREATE TABLE commands (
    id          INTEGER PRIMARY KEY AUTOINCREMENT,
    time_ms     INTEGER NOT NULL,
    actor_kind  INTEGER NOT NULL,  -- 1 user, 2 remote address
    actor       TEXT    NOT NULL,
    node        TEXT    NOT NULL,
    point       TEXT    NOT NULL,
    ioa         INTEGER,
    value_kind  INTEGER NOT NULL,
    value_int   INTEGER,
    value_float REAL,
    value_text  TEXT,
    phase       INTEGER NOT NULL,  -- 1 select, 2 execute
    outcome     INTEGER NOT NULL,
    detail      TEXT    NOT NULL
);

CREATE INDEX commands_time         ON commands (time_ms, id);
CREATE INDEX commands_actor_time   ON commands (actor, time_ms, id);
CREATE INDEX commands_point_time   ON commands (point, time_ms, id);
CREATE INDEX commands_outcome_time ON commands (outcome, time_ms, id);
