-- Stanice event store, schema version 3 on SQLite: the idempotent key of an event (the
-- source's identity and its sequence number, both NULL for an event without one), so a
-- batch written again after a crash between its commit and its acknowledgement stores
-- nothing twice (INSERT OR IGNORE). SQLite keeps one table per record kind; PostgreSQL
-- partitions them by day (0003_partitions.postgres.sql).

ALTER TABLE events ADD COLUMN source_id  TEXT;
ALTER TABLE events ADD COLUMN source_seq INTEGER;
-- NULL keys never collide: events without a key are all kept.
CREATE UNIQUE INDEX events_key ON events (source_id, source_seq);
