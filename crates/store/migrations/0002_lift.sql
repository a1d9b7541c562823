-- Stanice event store, schema version 2: the lift fault archive and the notification
-- record, for SQLite and PostgreSQL alike (the words in braces are the column types,
-- src/sql/schema.rs). Times are milliseconds since the Unix epoch in 64-bit integers, as in
-- version 1.

-- Records of lift boards' fault stacks (lift spec 4.3), kept for years: retention never
-- purges this table.
CREATE TABLE lift_faults (
    id          {id},              -- the archive's order
    node        {name} NOT NULL,   -- the station node watching the lift
    lift        {name} NOT NULL,
    stack_index {int2} NOT NULL,   -- slot in the board's fault stack, 0..=255
    code        {int2} NOT NULL,   -- fault code (Appendix B), 0..=255
    floor       {int2} NOT NULL,
    target      {int2} NOT NULL,
    -- The time of occurrence as the board's clock wrote it, which has no zone: its
    -- wall-clock reading taken as if it were UTC, never converted. NULL when the board
    -- sent an impossible date.
    board_ms    {int8},
    received_ms {int8} NOT NULL,   -- when the station archived it (UTC)
    -- What time filters and the board-time order use: board_ms, else the received time
    -- (its UTC wall clock, on the same scale as board_ms).
    filed_ms    {int8} NOT NULL
);

-- The archive of one lift by board time (the HMI's default view), and of all lifts.
CREATE INDEX lift_faults_lift_time     ON lift_faults (lift, filed_ms, id);
CREATE INDEX lift_faults_time          ON lift_faults (filed_ms, id);
-- The newest N records of a lift in archive order: a restarted monitor rebuilds its
-- archive cursor from them.
CREATE INDEX lift_faults_lift_id       ON lift_faults (lift, id);
CREATE INDEX lift_faults_received_time ON lift_faults (received_ms, id);

-- Every e-mail or webhook call a notification rule made or held back; purged with the
-- command audit.
CREATE TABLE notifications (
    id        {id},
    time_ms   {int8} NOT NULL,
    rule      {name} NOT NULL,   -- the rule that matched
    channel   {name} NOT NULL,   -- email, webhook
    recipient TEXT   NOT NULL,   -- address or URL
    source    {name} NOT NULL,   -- what it is about (the lift's name)
    subject   TEXT   NOT NULL,
    outcome   {int2} NOT NULL,   -- NotificationOutcome::code: 1 sent, 2 failed, 3 suppressed
    detail    TEXT   NOT NULL    -- SMTP reply, HTTP status, why suppressed
);

-- Newest first, plain and per source; retention by time.
CREATE INDEX notifications_time        ON notifications (time_ms, id);
CREATE INDEX notifications_source_time ON notifications (source, time_ms, id);
