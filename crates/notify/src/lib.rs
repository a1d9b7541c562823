//! Fault notification without logging in (spec `elevator-ekm66.md` §11, planned
//! extension 2): when a lift reports a new fault, the responsible technician gets an
//! e-mail and the firm's ticket system a webhook POST, without a flood, and every
//! attempt is recorded.
//!
//! # Layout
//!
//! - [`notice`]: [`Notice`], what happened (source, class, code, title, text, time, link).
//! - [`config`]: [`NotifyConfig`], the station project's `[node.notify]` table (SMTP
//!   server, named channels `email`/`webhook`, rules), serde with
//!   `deny_unknown_fields`, and its validation into [`ConfigError`]s naming the field.
//! - [`pattern`]: the glob patterns (`*`, `?`) rules select sources and classes with.
//! - [`policy`]: [`Policy`], sans-IO and clock-free: for a notice and `now`, one
//!   [`Decision`] per channel of every matching rule, send or suppressed (quiet period
//!   per rule, source and class; sliding-window rate limit per rule).
//! - [`delivery`]: [`Delivery`], the record of each attempt (sent, failed, suppressed,
//!   with the SMTP reply, the HTTP status, the error or the reason); the caller stores it.
//! - `email`, `webhook` (private): the senders, lettre's async SMTP transport and
//!   reqwest, both on tokio with rustls.
//! - [`notifier`]: [`Notifier`], policy plus senders, `notify` sending concurrently with
//!   time-outs; [`spawn_notifier`], the same as a task behind a bounded queue so the
//!   caller never waits for a slow server.
//!
//! # Data flow
//!
//! ```text
//! lift monitor: new fault -> Notice ---------------------> NotifierHandle::submit
//!                                  \                        | (queue full: Suppressed)
//!                                   \-> Notifier::notify <--/ (task)
//!   -> Policy::decide(notice, now) -> [Decision{rule, channel, Send | Suppressed}]
//!   -> Send: email (lettre, SMTP, one message per recipient)  \
//!            webhook (reqwest, POST JSON)                      > concurrently, time-outs
//!   -> [Delivery{time, rule, channel, kind, recipient, outcome, detail}]
//!   -> caller -> event store
//! ```
//!
//! The policy reads no clock: `clippy.toml` bans `Instant::now`, `SystemTime::now` and
//! chrono's `now` in this crate; `Notifier::notify` and `NotifierHandle::submit` read the
//! wall clock once each (marked), and their `*_at` forms take it as a parameter.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]

pub mod config;
pub mod delivery;
mod email;
pub mod notice;
pub mod notifier;
pub mod pattern;
pub mod policy;
mod webhook;

pub use config::{
    ChannelConfig, ChannelKind, ConfigError, NotifyConfig, RateLimit, RuleConfig, Security,
    SmtpSettings,
};
pub use delivery::{Delivery, Outcome};
pub use notice::Notice;
pub use notifier::{spawn_notifier, Notifier, NotifierError, NotifierHandle};
pub use pattern::Pattern;
pub use policy::{Decision, Policy, SuppressReason, Verdict};
pub use webhook::WebhookBody;
