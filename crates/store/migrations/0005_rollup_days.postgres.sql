-- Stanice event store, schema version 5 on PostgreSQL: the trend rollups partitioned by
-- day like the events, so that a closed day can be rewritten in key order.
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
    PRIMARY KEY (point, start_ms)
) PARTITION BY RANGE (start_ms);
CREATE TABLE trend_rollups_default PARTITION OF trend_rollups DEFAULT WITH (fillfactor = 70);

-- A rollup day for every event day there is (the days made ahead included) ...
SELECT stanice_day_partition('trend_rollups',
           (extract(epoch FROM to_date(substr(c.relname, 8), 'YYYYMMDD')) * 1000)::BIGINT)
FROM pg_inherits i JOIN pg_class c ON c.oid = i.inhrelid
WHERE i.inhparent = 'events'::regclass AND c.relname ~ '^events_[0-9]{8}$';

-- ... and the old rows in key order, so that every day starts out compact.
INSERT INTO trend_rollups SELECT * FROM trend_rollups_v4 ORDER BY point, start_ms;
DROP TABLE trend_rollups_v4;
