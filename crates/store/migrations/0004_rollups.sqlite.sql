-- Stanice event store, schema version 4 on SQLite: trend rollups. For every point with
-- numeric values (value kinds 1 bool, 3 int, 4 float) and every minute holding values,
-- the first and last event time, the minimum, maximum, sum and count of the values and
-- whether any was invalid (IV). A trend of 60 days then reads at most 86,400 rows of a
-- point, however many events it has (src/sql/select.rs, `trend_sql`).
--
-- The writer folds each batch of events it stores into them, in the same transaction and
-- in one statement over the batch's new rows (src/sqlite.rs, `FOLD_ROLLUPS`): an event
-- ignored as a duplicate of its key is not folded twice. Existing events are folded here
-- once.

CREATE TABLE trend_rollups (
    point     TEXT    NOT NULL,
    start_ms  INTEGER NOT NULL,     -- the minute's start
    first_ms  INTEGER NOT NULL,     -- the event time of its first value
    last_ms   INTEGER NOT NULL,     -- and of its last
    min_value REAL    NOT NULL,
    max_value REAL    NOT NULL,
    sum_value REAL    NOT NULL,
    samples   INTEGER NOT NULL,
    invalid   INTEGER NOT NULL,     -- 1: a value of the minute was invalid (IV)
    PRIMARY KEY (point, start_ms)
) WITHOUT ROWID;                    -- a point's minutes side by side: a trend reads one range

INSERT INTO trend_rollups (point, start_ms, first_ms, last_ms, min_value, max_value,
                           sum_value, samples, invalid)
SELECT point, event_ms - (event_ms % 60000 + 60000) % 60000 AS start_ms,
       MIN(event_ms), MAX(event_ms), MIN(v), MAX(v), SUM(v), COUNT(*), MAX(quality & 1)
FROM (SELECT point, event_ms, quality,
             COALESCE(value_float, CAST(value_int AS REAL)) AS v
      FROM events
      WHERE value_kind IN (1, 3, 4) AND (value_float IS NOT NULL OR value_int IS NOT NULL))
GROUP BY point, start_ms;
