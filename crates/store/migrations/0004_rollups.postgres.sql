-- Stanice event store, schema version 4 on PostgreSQL: trend rollups. For every point with
-- numeric values (value kinds 1 bool, 3 int, 4 float) and every minute holding values,
-- the first and last event time, the minimum, maximum, sum and count of the values and
-- whether any was invalid (IV). A trend of 60 days then reads at most 86,400 rows of a
-- point, however many events it has (src/sql/select.rs, `trend_sql`).
--
-- The database keeps them itself: a statement trigger on `events` folds the rows each
-- INSERT stored (its transition table: the recorder's COPY-staged batch, a single append;
-- rows left out by ON CONFLICT DO NOTHING are not in it) into their minutes, in the same
-- transaction. Rows the day-partition function moves out of the DEFAULT partition are
-- inserted into the partition itself and are not folded again. Existing events are
-- folded here once. Retention deletes old rollups point by point (src/sql/mod.rs).

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
-- Room on each page for the updates of a minute's later values: they change no key, so
-- PostgreSQL keeps them on the page (HOT) without a new index entry.
) WITH (fillfactor = 70);

INSERT INTO trend_rollups (point, start_ms, first_ms, last_ms, min_value, max_value,
                           sum_value, samples, invalid)
SELECT point, event_ms - (event_ms % 60000 + 60000) % 60000 AS start_ms,
       MIN(event_ms), MAX(event_ms), MIN(v), MAX(v), SUM(v), COUNT(*), MAX(quality & 1)
FROM (SELECT point, event_ms, quality,
             COALESCE(value_float, CAST(value_int AS DOUBLE PRECISION)) AS v
      FROM events
      WHERE value_kind IN (1, 3, 4) AND (value_float IS NOT NULL OR value_int IS NOT NULL))
     AS numeric_events
GROUP BY point, 2;

CREATE FUNCTION stanice_fold_rollups() RETURNS trigger
LANGUAGE plpgsql AS $fn$
BEGIN
    INSERT INTO trend_rollups (point, start_ms, first_ms, last_ms, min_value, max_value,
                               sum_value, samples, invalid)
    SELECT point, event_ms - (event_ms % 60000 + 60000) % 60000 AS start_ms,
           MIN(event_ms), MAX(event_ms), MIN(v), MAX(v), SUM(v), COUNT(*), MAX(quality & 1)
    FROM (SELECT point, event_ms, quality,
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
        invalid   = GREATEST(trend_rollups.invalid, EXCLUDED.invalid);
    RETURN NULL;
END
$fn$;

CREATE TRIGGER events_rollup AFTER INSERT ON events
    REFERENCING NEW TABLE AS stored
    FOR EACH STATEMENT EXECUTE FUNCTION stanice_fold_rollups();
