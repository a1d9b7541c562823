-- Stanice event store, schema version 6 on PostgreSQL: nothing yet. SQLite moves its
-- events into blocks at this version (0006_blocks.sqlite.sql); PostgreSQL keeps a row
-- per event in its day partitions until its own step.
SELECT 1;
