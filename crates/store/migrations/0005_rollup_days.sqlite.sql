-- Stanice event store, schema version 5 on SQLite: each trend minute keeps its first and
-- last value (by event time, then id: the order the raw first/last query reads), so that
-- a first/last trend of wide buckets reads the rollups instead of two seeks per bucket
-- into the events. The old minutes get theirs from the events by one seek each; the
-- writer's fold keeps them from now on (src/sqlite.rs, `FOLD_ROLLUPS`).
--
-- (Version 5 also partitions PostgreSQL's rollups by day, so that closed days can be
-- rewritten in key order; SQLite's WITHOUT ROWID table is kept in key order by its
-- B-tree already.)

ALTER TABLE trend_rollups ADD COLUMN first_value REAL;  -- the value at first_ms (lowest id)
ALTER TABLE trend_rollups ADD COLUMN last_value  REAL;  -- the value at last_ms (highest id)

UPDATE trend_rollups SET
    first_value = (SELECT COALESCE(e.value_float, CAST(e.value_int AS REAL)) FROM events e
                   WHERE e.point = trend_rollups.point AND e.event_ms = trend_rollups.first_ms
                     AND e.value_kind IN (1, 3, 4)
                     AND (e.value_float IS NOT NULL OR e.value_int IS NOT NULL)
                   ORDER BY e.id LIMIT 1),
    last_value  = (SELECT COALESCE(e.value_float, CAST(e.value_int AS REAL)) FROM events e
                   WHERE e.point = trend_rollups.point AND e.event_ms = trend_rollups.last_ms
                     AND e.value_kind IN (1, 3, 4)
                     AND (e.value_float IS NOT NULL OR e.value_int IS NOT NULL)
                   ORDER BY e.id DESC LIMIT 1);
