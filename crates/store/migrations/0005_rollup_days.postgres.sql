-- Stanice event store, schema version 5 on PostgreSQL: the trend rollups partitioned by
-- day like the events, so that a closed day can be rewritten in key order, and each
-- minute's first and last value.
--
-- Why: a trend reads one point's minutes, (point, start_ms) in key order. The statement
-- trigger upserts each batch's minutes as the events come, all points of a minute
-- together, so in the heap a point's consecutive minutes lie a page or more apart: a
-- 60-day trend touched 86,400 pages (447 ms at 100 million events, where SQLite's
-- WITHOUT ROWID table, kept in key order, took 89 ms). A day partition that no longer
-- changes is CLUSTERed on its key once by the store's maintenance pass
-- (src/postgres/partitions.rs, `compact_closed_days`): then a day of a point is one or two
-- pages. Only that day's partition is locked while it is rewritten; a late event for it
-- afterwards is an ordinary upsert.
--
-- `trend_rollups_YYYYMMDD` holds the minutes starting that UTC day; `trend_rollups_default`
-- the minutes of days without a partition (as `events_default`). The day function makes a
-- day's rollup partition with its events' day, and retention drops both.
--
-- A minute also keeps its first and last value (by event time, then id: the order the
-- raw first/last query reads), so that a first/last trend of wide buckets reads the
-- rollups too instead of two seeks per bucket into the events (534 ms at 100 million).
-- The old minutes keep none (NULL): their first/last trends seek the events as before.

CREATE OR REPLACE FUNCTION stanice_day_partition(parent TEXT, day_start BIGINT) RETURNS BOOLEAN
LANGUAGE plpgsql AS $fn$
DECLARE
    part      TEXT   := parent || '_' || to_char(to_timestamp((day_start / 1000)::float8) AT TIME ZONE 'UTC', 'YYYYMMDD');
    day_end   BIGINT := day_start + 86400000;
    key       TEXT   := CASE parent WHEN 'events' THEN 'event_ms'
                                    WHEN 'trend_rollups' THEN 'start_ms'
                                    ELSE 'time_ms' END;
    -- Rollups are updated in place while their minutes fill: room on the page keeps the
    -- updates HOT (a partitioned parent cannot carry the setting; each day does).
    storage   TEXT   := CASE parent WHEN 'trend_rollups' THEN ' WITH (fillfactor = 70)'
                                    ELSE '' END;
BEGIN
    -- An event day's minutes go to a rollup day of their own.
    IF parent = 'events' THEN
        PERFORM stanice_day_partition('trend_rollups', day_start);
    END IF;
    IF to_regclass(quote_ident(part)) IS NOT NULL THEN
        RETURN false;
    END IF;
    -- Two stores creating the same day wait for each other, and the second finds it made.
    -- (The lock does not refresh this session's view of the catalogue: the other's table
    -- shows as the CREATE's duplicate_table.)
    PERFORM pg_advisory_xact_lock(hashtext(current_schema() || '.' || part));
    BEGIN
        EXECUTE format('CREATE TABLE %I (LIKE %I INCLUDING DEFAULTS)', part, parent) || storage;
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

-- The old table steps aside (its key's name is the new table's).
ALTER TABLE trend_rollups RENAME TO trend_rollups_v4;
ALTER TABLE trend_rollups_v4 RENAME CONSTRAINT trend_rollups_pkey TO trend_rollups_v4_pkey;

CREATE TABLE trend_rollups (
    point     TEXT COLLATE "C" NOT NULL,
    start_ms  BIGINT NOT NULL,           -- the minute's start
    first_ms  BIGINT NOT NULL,           -- the event time of its first value
    last_ms   BIGINT NOT NULL,           -- and of its last
    min_value DOUBLE PRECISION NOT NULL,
    max_value DOUBLE PRECISION NOT NULL,
    sum_value DOUBLE PRECISION NOT NULL,
    samples   BIGINT NOT NULL,
    invalid   BIGINT NOT NULL,           -- 1: a value of the minute was invalid (IV)
    first_value DOUBLE PRECISION,        -- the value at first_ms (the lowest id there);
    last_value  DOUBLE PRECISION,        -- at last_ms (the highest id); NULL: folded before 5
    PRIMARY KEY (point, start_ms)
) PARTITION BY RANGE (start_ms);
CREATE TABLE trend_rollups_default PARTITION OF trend_rollups DEFAULT WITH (fillfactor = 70);

-- A rollup day for every event day there is (the days made ahead included) ...
SELECT stanice_day_partition('trend_rollups',
           (extract(epoch FROM to_date(substr(c.relname, 8), 'YYYYMMDD')) * 1000)::BIGINT)
FROM pg_inherits i JOIN pg_class c ON c.oid = i.inhrelid
WHERE i.inhparent = 'events'::regclass AND c.relname ~ '^events_[0-9]+$' AND length(c.relname) = 15;

-- ... and the old rows in key order, so that every day starts out compact. Their first
-- and last values stay NULL: a first/last trend then seeks them in the events (src/sql/
-- select.rs), as before this version, until retention takes those days. (Looking them up
-- here took 150 s for the 10 million rollups of 10.6 million events: a start of the
-- station blocked that long, for values a query finds anyway.)
INSERT INTO trend_rollups
SELECT r.*, NULL, NULL FROM trend_rollups_v4 r ORDER BY r.point, r.start_ms;
DROP TABLE trend_rollups_v4;

-- The fold keeps the first and last values: a batch's own per minute, and against a
-- minute stored already the earlier first (on the same millisecond the stored one: it
-- has the lower id) and the later last (on the same millisecond the batch's).
CREATE OR REPLACE FUNCTION stanice_fold_rollups() RETURNS trigger
LANGUAGE plpgsql AS $fn$
BEGIN
    INSERT INTO trend_rollups (point, start_ms, first_ms, last_ms, min_value, max_value,
                               sum_value, samples, invalid, first_value, last_value)
    SELECT point, event_ms - (event_ms % 60000 + 60000) % 60000 AS start_ms,
           MIN(event_ms), MAX(event_ms), MIN(v), MAX(v), SUM(v), COUNT(*), MAX(quality & 1),
           (array_agg(v ORDER BY event_ms, id))[1],
           (array_agg(v ORDER BY event_ms DESC, id DESC))[1]
    FROM (SELECT point, event_ms, id, quality,
                 COALESCE(value_float, CAST(value_int AS DOUBLE PRECISION)) AS v
          FROM stored
          WHERE value_kind IN (1, 3, 4)
            AND (value_float IS NOT NULL OR value_int IS NOT NULL)) AS numeric_events
    GROUP BY point, 2
    -- Rows locked in key order: two writers folding into the same minutes wait for each
    -- other instead of deadlocking.
    ORDER BY point, 2
    ON CONFLICT (point, start_ms) DO UPDATE SET
        first_ms  = LEAST(trend_rollups.first_ms, EXCLUDED.first_ms),
        last_ms   = GREATEST(trend_rollups.last_ms, EXCLUDED.last_ms),
        min_value = LEAST(trend_rollups.min_value, EXCLUDED.min_value),
        max_value = GREATEST(trend_rollups.max_value, EXCLUDED.max_value),
        sum_value = trend_rollups.sum_value + EXCLUDED.sum_value,
        samples   = trend_rollups.samples + EXCLUDED.samples,
        invalid   = GREATEST(trend_rollups.invalid, EXCLUDED.invalid),
        first_value = CASE WHEN EXCLUDED.first_ms < trend_rollups.first_ms
                           THEN EXCLUDED.first_value ELSE trend_rollups.first_value END,
        last_value  = CASE WHEN EXCLUDED.last_ms >= trend_rollups.last_ms
                           THEN EXCLUDED.last_value ELSE trend_rollups.last_value END;
    RETURN NULL;
END
$fn$;
