//! The record of each attempt, sent, failed or suppressed, for the caller to store.

use chrono::{DateTime, Utc};
use serde::{Deserialize, Serialize};

use crate::config::ChannelKind;

/// What became of one notification to one recipient.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Outcome {
    /// The SMTP server accepted the message, or the webhook answered 2xx.
    Sent,
    /// Refused, unreachable, timed out, or a non-2xx answer.
    Failed,
    /// Not attempted: quiet period, rate limit or a full queue.
    Suppressed,
}

impl Outcome {
    /// `"sent"`, `"failed"` or `"suppressed"`.
    pub fn as_str(self) -> &'static str {
        match self {
            Outcome::Sent => "sent",
            Outcome::Failed => "failed",
            Outcome::Suppressed => "suppressed",
        }
    }
}

impl std::fmt::Display for Outcome {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// One attempt (or non-attempt) to notify one recipient; the station stores these in its
/// event store.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Delivery {
    /// When it was decided (the `now` of the notification).
    pub time: DateTime<Utc>,
    /// The rule's name.
    pub rule: String,
    /// The channel's name.
    pub channel: String,
    /// The channel's kind.
    pub kind: ChannelKind,
    /// The e-mail address, or the webhook's URL.
    pub recipient: String,
    /// The notice's source.
    pub source: String,
    /// The notice's subject, `[source] title`.
    pub subject: String,
    /// Sent, failed or suppressed.
    pub outcome: Outcome,
    /// The SMTP server's reply (`250 ...`), the HTTP status (`HTTP 200 OK`), the error,
    /// or the reason of the suppression (`quiet period until ...`, `queue full`).
    pub detail: String,
}

/// An error and its sources, `outer: inner: innermost`, for a delivery's detail.
pub(crate) fn error_chain(error: &dyn std::error::Error) -> String {
    let mut text = error.to_string();
    let mut source = error.source();
    while let Some(inner) = source {
        let inner_text = inner.to_string();
        if !text.contains(&inner_text) {
            text.push_str(": ");
            text.push_str(&inner_text);
        }
        source = inner.source();
    }
    text
}
