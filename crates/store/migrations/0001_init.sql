-- Stanice event store, schema version 1, for SQLite and PostgreSQL alike: the words in
-- braces are the column types that differ between them (src/sql/schema.rs).
-- Times are milliseconds since the Unix epoch (UTC) in 64-bit integers, so both backends
-- compare and page identically. Enum columns hold the stable codes of the Rust enums
-- (EventCause::code, CommandOutcome::code, ...). Names ({name}) compare byte-wise (SQLite's
-- BINARY, PostgreSQL's "C" collation): the point prefix filter is a range scan on them.

CREATE TABLE events (
    id             {id},                -- never reused, even after purges
    node           {name} NOT NULL,
    point          {name} NOT NULL,
    ioa            {int8},
    value_kind     {int2} NOT NULL,     -- 1 bool, 2 double point, 3 int, 4 float, 5 bits, 6 text
    value_int      {int8},
    value_float    {float8},
    value_text     TEXT,
    quality        {int2} NOT NULL,     -- IV 1, NT 2, SB 4, BL 8, OV 16
    source_ms      {int8},              -- source time stamp, NULL when none
    source_invalid {bool} NOT NULL,     -- the time tag's IV bit
    received_ms    {int8} NOT NULL,
    event_ms       {int8} NOT NULL,     -- source_ms when present and valid, else received_ms
    cause          {int2} NOT NULL,
    origin         TEXT   NOT NULL
);

-- Keyset pagination by (time, id), plain and per point/node; retention by received time.
CREATE INDEX events_event_time    ON events (event_ms, id);
CREATE INDEX events_received_time ON events (received_ms, id);
CREATE INDEX events_point_time    ON events (point, event_ms, id);
CREATE INDEX events_node_time     ON events (node, event_ms, id);
-- The "invalid only" view (IV set) stays fast however rare invalid events are.
CREATE INDEX events_invalid_time  ON events (event_ms, id) WHERE (quality & 1) <> 0;

CREATE TABLE commands (
    id          {id},
    time_ms     {int8} NOT NULL,
    actor_kind  {int2} NOT NULL,  -- 1 user, 2 remote address
    actor       {name} NOT NULL,
    node        {name} NOT NULL,
    point       {name} NOT NULL,
    ioa         {int8},
    value_kind  {int2} NOT NULL,
    value_int   {int8},
    value_float {float8},
    value_text  TEXT,
    phase       {int2} NOT NULL,  -- 1 select, 2 execute
    outcome     {int2} NOT NULL,
    detail      TEXT   NOT NULL
);

CREATE INDEX commands_time         ON commands (time_ms, id);
CREATE INDEX commands_actor_time   ON commands (actor, time_ms, id);
CREATE INDEX commands_point_time   ON commands (point, time_ms, id);
CREATE INDEX commands_outcome_time ON commands (outcome, time_ms, id);
