//! The record of notifications: every e-mail or webhook call a notification rule made, or
//! decided not to make (lift spec 11, "fault notification without logging in"), so that
//! "was the technician told, and when?" has an answer ([`NotificationRecord`],
//! [`NotificationQuery`], newest first, answered as a [`crate::CountedPage`]).
//!
//! Retention purges it with the command audit ([`crate::EventStore::purge_older_than`]):
//! like the command audit it says who was told what, and a lift that keeps failing within a
//! quiet period adds a suppressed record each time.

use chrono::{DateTime, Utc};
use std::fmt;

use crate::model::RecordId;
use crate::query::DEFAULT_PAGE_SIZE;

/// What became of a notification.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum NotificationOutcome {
    /// Handed over: the SMTP server accepted the mail, the webhook answered 2xx.
    Sent,
    /// Tried and failed (SMTP refusal, HTTP error, no connection).
    Failed,
    /// Not tried on purpose: a quiet period or the rate limit held it back.
    Suppressed,
}

impl NotificationOutcome {
    /// Every outcome, in code order.
    pub const ALL: [NotificationOutcome; 3] = [
        NotificationOutcome::Sent,
        NotificationOutcome::Failed,
        NotificationOutcome::Suppressed,
    ];

    /// The stable stored code.
    pub fn code(self) -> i16 {
        match self {
            NotificationOutcome::Sent => 1,
            NotificationOutcome::Failed => 2,
            NotificationOutcome::Suppressed => 3,
        }
    }

    /// The outcome with this stored code, if any.
    pub fn from_code(code: i16) -> Option<NotificationOutcome> {
        NotificationOutcome::ALL
            .into_iter()
            .find(|o| o.code() == code)
    }
}

impl fmt::Display for NotificationOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            NotificationOutcome::Sent => "sent",
            NotificationOutcome::Failed => "failed",
            NotificationOutcome::Suppressed => "suppressed",
        })
    }
}

/// One notification sent, failed or suppressed.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct NotificationRecord {
    /// Assigned by the store: `None` on append (ignored), `Some` in query results.
    pub id: Option<RecordId>,
    /// When it was sent or suppressed, ms precision.
    pub time: DateTime<Utc>,
    /// The rule that matched.
    pub rule: String,
    /// The channel: `email` or `webhook`.
    pub channel: String,
    /// The e-mail address or the webhook's URL.
    pub recipient: String,
    /// What it is about, for example the lift's name.
    pub source: String,
    /// The subject line (or the webhook's summary).
    pub subject: String,
    /// What became of it.
    pub outcome: NotificationOutcome,
    /// The SMTP reply, the HTTP status, or why it was suppressed (quiet period, rate
    /// limit).
    pub detail: String,
}

/// A query over the notification record, newest first (by time, then id). Build it with
/// [`NotificationQuery::default`] and the `with_*` methods.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub struct NotificationQuery {
    /// Only notifications about this source.
    pub source: Option<String>,
    /// Rows of the result to skip.
    pub offset: u64,
    /// Rows to return at most, 1 to [`crate::MAX_PAGE_SIZE`].
    pub limit: u32,
}

impl Default for NotificationQuery {
    fn default() -> NotificationQuery {
        NotificationQuery {
            source: None,
            offset: 0,
            limit: u32::try_from(DEFAULT_PAGE_SIZE).unwrap_or(u32::MAX),
        }
    }
}

impl NotificationQuery {
    /// Only notifications about this source.
    pub fn with_source(mut self, source: impl Into<String>) -> Self {
        self.source = Some(source.into());
        self
    }
    /// Skip `offset` rows, return `limit` at most.
    pub fn with_page(mut self, offset: u64, limit: u32) -> Self {
        self.offset = offset;
        self.limit = limit;
        self
    }
}
