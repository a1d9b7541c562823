//! What happened: the notice a caller hands to the policy and the notifier.

use chrono::{DateTime, SecondsFormat, Utc};
use serde::{Deserialize, Serialize};

/// One thing worth telling someone about, e.g. a new fault of a lift.
///
/// The caller decides what a notice is: the lift monitor makes one per new fault record
/// (not per poll), with `class` its own fault class key, so that rules can select and
/// the quiet period can group by it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Notice {
    /// What reports it, e.g. the lift's name `"L3"`; rules match it with glob patterns.
    pub source: String,
    /// The class key, e.g. `"safety-circuit"`, `"door"`, `"comm-lost"`; rules match it
    /// with glob patterns, the quiet period is per (rule, source, class).
    pub class: String,
    /// The device's own code (an EKM66 fault code), when there is one.
    pub code: Option<u32>,
    /// One line; the e-mail subject is `[source] title`.
    pub title: String,
    /// The body, any number of lines of UTF-8 (Czech texts included).
    pub text: String,
    /// When it happened.
    pub time: DateTime<Utc>,
    /// A link to the web HMI's page about it.
    pub link: Option<String>,
}

impl Notice {
    /// The e-mail subject and the delivery record's subject: `[source] title`.
    pub fn subject(&self) -> String {
        format!("[{}] {}", self.source, self.title)
    }

    /// The plain-text body of the e-mail: the text, then time, code and link.
    pub fn body(&self) -> String {
        let mut body = String::new();
        body.push_str(self.text.trim_end());
        body.push_str("\n\n");
        body.push_str(&format!("Source: {}\n", self.source));
        body.push_str(&format!("Class: {}\n", self.class));
        if let Some(code) = self.code {
            body.push_str(&format!("Code: {code}\n"));
        }
        body.push_str(&format!(
            "Time: {} UTC\n",
            self.time.format("%Y-%m-%d %H:%M:%S")
        ));
        if let Some(link) = &self.link {
            body.push_str(&format!("Link: {link}\n"));
        }
        body
    }

    /// The time as RFC 3339 (`2026-03-01T08:15:00Z`), as the webhook sends it.
    pub fn time_rfc3339(&self) -> String {
        self.time.to_rfc3339_opts(SecondsFormat::AutoSi, true)
    }
}
