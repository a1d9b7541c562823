-- Stanice event store, schema version 5 on SQLite: each trend minute keeps its first and
-- last value (by event time, then id: the order the raw first/last query reads), so that
-- a first/last trend of wide buckets reads the rollups instead of two seeks per bucket
-- into the events. The writer's fold keeps them from now on (src/sqlite.rs,
-- `FOLD_ROLLUPS`). The old minutes keep none (NULL): a first/last trend seeks theirs in
-- the events, as before this version, until retention takes them; looking them all up
-- here would block the opening of a large store for minutes.
--
-- (Version 5 also partitions PostgreSQL's rollups by day, so that closed days can be
-- rewritten in key order; SQLite's WITHOUT ROWID table is kept in key order by its
-- B-tree already.)

ALTER TABLE trend_rollups ADD COLUMN first_value REAL;  -- the value at first_ms (lowest id)
ALTER TABLE trend_rollups ADD COLUMN last_value  REAL;  -- the value at last_ms (highest id)
