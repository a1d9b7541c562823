-- Stanice event store, schema version 3 on PostgreSQL: `events` and `commands` become
-- RANGE-partitioned by day (UTC) on the event's time (`event_ms`, `commands.time_ms`),
-- and events carry an idempotent key (`source_id`, `source_seq`).
--
-- Partitions are named `events_YYYYMMDD` / `commands_YYYYMMDD`; a DEFAULT partition
-- (`events_default`, `commands_default`) takes a time that has no day partition (a source
-- clock years off). `stanice_day_partition` creates a day's partition, moving the rows of
-- that day out of the DEFAULT partition first (PostgreSQL refuses to attach a range the
-- DEFAULT partition holds rows of); the store calls it at open (today up to 7 days ahead),
-- for every new day an append meets, and from the retention task. Retention drops whole
-- partitions (src/postgres.rs).
--
-- An older database is converted in place: the old tables are renamed, a partition is
-- made for every day they hold, their rows are copied (ids kept) and the old tables go.

CREATE FUNCTION stanice_day_partition(parent TEXT, day_start BIGINT) RETURNS BOOLEAN
LANGUAGE plpgsql AS $fn$
DECLARE
    part      TEXT   := parent || '_' || to_char(to_timestamp((day_start / 1000)::float8) AT TIME ZONE 'UTC', 'YYYYMMDD');
    day_end   BIGINT := day_start + 86400000;
    key       TEXT   := CASE parent WHEN 'events' THEN 'event_ms' ELSE 'time_ms' END;
BEGIN
    IF to_regclass(quote_ident(part)) IS NOT NULL THEN
        RETURN false;
    END IF;
    -- Two stores creating the same day wait for each other, and the second finds it made.
    -- (The lock does not refresh this session's view of the catalogue: the other's table
    -- shows as the CREATE's duplicate_table.)
    PERFORM pg_advisory_xact_lock(hashtext(current_schema() || '.' || part));
    BEGIN
        EXECUTE format('CREATE TABLE %I (LIKE %I INCLUDING DEFAULTS)', part, parent);
    EXCEPTION WHEN duplicate_table THEN
        RETURN false;
    END;
    EXECUTE format(
        'WITH moved AS (DELETE FROM %I WHERE %I >= %s AND %I < %s RETURNING *) '
        'INSERT INTO %I SELECT * FROM moved',
        parent || '_default', key, day_start, key, day_end, part);
    EXECUTE format('ALTER TABLE %I ATTACH PARTITION %I FOR VALUES FROM (%s) TO (%s)',
        parent, part, day_start, day_end);
    RETURN true;
END
$fn$;

-- The old tables step aside (their indexes' names are the new tables').
ALTER TABLE events RENAME TO events_v2;
ALTER TABLE commands RENAME TO commands_v2;
DROP INDEX events_event_time, events_received_time, events_point_time, events_node_time,
    events_invalid_time, commands_time, commands_actor_time, commands_point_time,
    commands_outcome_time;

-- Ids come from sequences of their own (an identity column cannot be partitioned before
-- PostgreSQL 17), continuing the old tables' ids.
CREATE SEQUENCE event_ids;
SELECT setval('event_ids', coalesce((SELECT max(id) FROM events_v2), 0) + 1, false);
CREATE SEQUENCE command_ids;
SELECT setval('command_ids', coalesce((SELECT max(id) FROM commands_v2), 0) + 1, false);

CREATE TABLE events (
    id             BIGINT NOT NULL DEFAULT nextval('event_ids'),
    node           TEXT COLLATE "C" NOT NULL,
    point          TEXT COLLATE "C" NOT NULL,
    ioa            BIGINT,
    value_kind     SMALLINT NOT NULL,
    value_int      BIGINT,
    value_float    DOUBLE PRECISION,
    value_text     TEXT,
    quality        SMALLINT NOT NULL,
    source_ms      BIGINT,
    source_invalid BOOLEAN NOT NULL,
    received_ms    BIGINT NOT NULL,
    event_ms       BIGINT NOT NULL,
    cause          SMALLINT NOT NULL,
    origin         TEXT NOT NULL,
    source_id      TEXT COLLATE "C",   -- the idempotent key: the source's identity ...
    source_seq     BIGINT              -- ... and its sequence number (both NULL: no key)
) PARTITION BY RANGE (event_ms);
ALTER SEQUENCE event_ids OWNED BY events.id;
CREATE TABLE events_default PARTITION OF events DEFAULT;

-- The event list: newest first overall, by point (prefix), by node, invalid only, by cause;
-- trends by (point, event_ms). Retention needs none (it drops partitions).
CREATE INDEX events_event_time    ON events (event_ms, id);
CREATE INDEX events_received_time ON events (received_ms, id);
CREATE INDEX events_point_time    ON events (point, event_ms, id);
CREATE INDEX events_node_time     ON events (node, event_ms, id);
CREATE INDEX events_invalid_time  ON events (event_ms, id) WHERE (quality & 1) <> 0;
-- A unique index of a partitioned table must hold the partition key: a retried event has
-- the same time, so (source, sequence, time) is as good a key as (source, sequence).
CREATE UNIQUE INDEX events_key    ON events (source_id, source_seq, event_ms);

CREATE TABLE commands (
    id          BIGINT NOT NULL DEFAULT nextval('command_ids'),
    time_ms     BIGINT NOT NULL,
    actor_kind  SMALLINT NOT NULL,
    actor       TEXT COLLATE "C" NOT NULL,
    node        TEXT COLLATE "C" NOT NULL,
    point       TEXT COLLATE "C" NOT NULL,
    ioa         BIGINT,
    value_kind  SMALLINT NOT NULL,
    value_int   BIGINT,
    value_float DOUBLE PRECISION,
    value_text  TEXT,
    phase       SMALLINT NOT NULL,
    outcome     SMALLINT NOT NULL,
    detail      TEXT NOT NULL
) PARTITION BY RANGE (time_ms);
ALTER SEQUENCE command_ids OWNED BY commands.id;
CREATE TABLE commands_default PARTITION OF commands DEFAULT;

-- The command audit: by time, by user (actor), by point, by outcome.
CREATE INDEX commands_time         ON commands (time_ms, id);
CREATE INDEX commands_actor_time   ON commands (actor, time_ms, id);
CREATE INDEX commands_point_time   ON commands (point, time_ms, id);
CREATE INDEX commands_outcome_time ON commands (outcome, time_ms, id);

-- The old rows, each day into its partition.
SELECT stanice_day_partition('events', day)
FROM (SELECT DISTINCT floor(event_ms / 86400000.0)::BIGINT * 86400000 AS day FROM events_v2
      WHERE event_ms BETWEEN -2208988800000 AND 253402300799999) AS days;
INSERT INTO events (id, node, point, ioa, value_kind, value_int, value_float, value_text,
        quality, source_ms, source_invalid, received_ms, event_ms, cause, origin)
    SELECT id, node, point, ioa, value_kind, value_int, value_float, value_text,
        quality, source_ms, source_invalid, received_ms, event_ms, cause, origin
    FROM events_v2;
SELECT stanice_day_partition('commands', day)
FROM (SELECT DISTINCT floor(time_ms / 86400000.0)::BIGINT * 86400000 AS day FROM commands_v2
      WHERE time_ms BETWEEN -2208988800000 AND 253402300799999) AS days;
INSERT INTO commands SELECT * FROM commands_v2;
DROP TABLE events_v2, commands_v2;
