//! The notifier: the policy plus the senders. `notify` decides, sends concurrently (each
//! attempt bounded by its channel's time-out) and returns a [`Delivery`] per recipient;
//! [`spawn_notifier`] runs it as a task behind a bounded queue.

use std::collections::BTreeMap;
use std::sync::Arc;

use chrono::{DateTime, Utc};
use futures_util::future::{join_all, BoxFuture, FutureExt};
use tokio::sync::mpsc;
use tokio::task::JoinHandle;

use crate::config::{ChannelConfig, ChannelKind, ConfigError, NotifyConfig};
use crate::delivery::{error_chain, Delivery, Outcome};
use crate::email::EmailSender;
use crate::notice::Notice;
use crate::policy::{Decision, Policy, SuppressReason, Verdict};
use crate::webhook::WebhookSender;

/// Why a notifier could not be built.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum NotifierError {
    /// The configuration is invalid (all errors found).
    #[error("invalid notification configuration: {}", join_errors(.0))]
    Config(Vec<ConfigError>),
    /// The SMTP transport could not be set up.
    #[error("SMTP transport: {0}")]
    Smtp(String),
    /// The HTTP client could not be set up.
    #[error("HTTP client: {0}")]
    Http(String),
}

impl From<ConfigError> for NotifierError {
    fn from(error: ConfigError) -> NotifierError {
        NotifierError::Config(vec![error])
    }
}

fn join_errors(errors: &[ConfigError]) -> String {
    errors
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join("; ")
}

/// A configured channel.
enum Channel {
    Email { to: Vec<String> },
    Webhook(WebhookSender),
}

/// Decides with its [`Policy`] and delivers by e-mail and webhook.
pub struct Notifier {
    config: Arc<NotifyConfig>,
    policy: Policy,
    email: Option<EmailSender>,
    channels: BTreeMap<String, Channel>,
}

impl std::fmt::Debug for Notifier {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Notifier")
            .field("channels", &self.channels.keys().collect::<Vec<_>>())
            .field("policy", &self.policy)
            .finish_non_exhaustive()
    }
}

impl Notifier {
    /// Validates `config`, reads the SMTP password from the environment when
    /// `password_env` is given, and sets up the transports (no connection is made yet).
    pub fn new(config: NotifyConfig) -> Result<Notifier, NotifierError> {
        config.validate().map_err(NotifierError::Config)?;
        let email = match &config.smtp {
            Some(smtp) => Some(EmailSender::new(smtp)?),
            None => None,
        };
        let client = reqwest::Client::builder()
            .build()
            .map_err(|error| NotifierError::Http(error_chain(&error)))?;
        let mut channels = BTreeMap::new();
        for (name, channel) in &config.channels {
            let channel = match channel {
                ChannelConfig::Email { to } => Channel::Email { to: to.clone() },
                ChannelConfig::Webhook {
                    url,
                    headers,
                    timeout_s,
                } => Channel::Webhook(WebhookSender::new(
                    name,
                    client.clone(),
                    url,
                    headers,
                    *timeout_s,
                )?),
            };
            channels.insert(name.clone(), channel);
        }
        Ok(Notifier {
            policy: Policy::new(&config.rules),
            config: Arc::new(config),
            email,
            channels,
        })
    }

    /// The configuration in effect.
    pub fn config(&self) -> &NotifyConfig {
        &self.config
    }

    /// [`Notifier::notify_at`] now (the wall clock).
    pub async fn notify(&mut self, notice: &Notice) -> Vec<Delivery> {
        #[allow(clippy::disallowed_methods)] // the adapter's one clock read
        let now = Utc::now();
        self.notify_at(notice, now).await
    }

    /// Decides for `notice` at `now` and delivers: every send concurrently, each bounded
    /// by its channel's time-out. One [`Delivery`] per recipient of every matching rule's
    /// channels, sent, failed or suppressed, in rule and channel order; empty when no
    /// rule matches. Failures are deliveries, never errors or panics.
    pub async fn notify_at(&mut self, notice: &Notice, now: DateTime<Utc>) -> Vec<Delivery> {
        let decisions = self.policy.decide(notice, now);
        let this = &*self;
        let attempts: Vec<BoxFuture<'_, Delivery>> = decisions
            .iter()
            .flat_map(|decision| this.attempts(decision, notice, now))
            .collect();
        join_all(attempts).await
    }

    /// The attempts of one decision: one per recipient.
    fn attempts<'a>(
        &'a self,
        decision: &'a Decision,
        notice: &'a Notice,
        now: DateTime<Utc>,
    ) -> Vec<BoxFuture<'a, Delivery>> {
        let Some(channel) = self.channels.get(&decision.channel) else {
            // Validation rules this out; record rather than panic.
            let record = record(now, decision, ChannelKind::Webhook, "", notice);
            return vec![
                async move { record(Outcome::Failed, "channel not configured".into()) }.boxed(),
            ];
        };
        match channel {
            Channel::Email { to } => to
                .iter()
                .map(|recipient| {
                    let record = record(now, decision, ChannelKind::Email, recipient, notice);
                    async move {
                        match &decision.verdict {
                            Verdict::Suppressed(reason) => {
                                record(Outcome::Suppressed, reason.to_string())
                            }
                            Verdict::Send => match &self.email {
                                None => record(Outcome::Failed, "no SMTP server".into()),
                                Some(email) => {
                                    let result = email.send(notice, recipient).await;
                                    outcome(record, result, decision, recipient)
                                }
                            },
                        }
                    }
                    .boxed()
                })
                .collect(),
            Channel::Webhook(sender) => {
                let url = sender_url(&self.config, &decision.channel);
                let record = record(now, decision, ChannelKind::Webhook, &url, notice);
                vec![async move {
                    match &decision.verdict {
                        Verdict::Suppressed(reason) => {
                            record(Outcome::Suppressed, reason.to_string())
                        }
                        Verdict::Send => {
                            let result = sender.send(notice, &decision.rule).await;
                            outcome(record, result, decision, &url)
                        }
                    }
                }
                .boxed()]
            }
        }
    }
}

/// The configured URL of a webhook channel.
fn sender_url(config: &NotifyConfig, channel: &str) -> String {
    match config.channels.get(channel) {
        Some(ChannelConfig::Webhook { url, .. }) => url.clone(),
        _ => String::new(),
    }
}

/// A delivery record waiting for its outcome and detail.
fn record(
    now: DateTime<Utc>,
    decision: &Decision,
    kind: ChannelKind,
    recipient: &str,
    notice: &Notice,
) -> impl FnOnce(Outcome, String) -> Delivery + Send + 'static {
    let (rule, channel) = (decision.rule.clone(), decision.channel.clone());
    let (recipient, source, subject) = (
        recipient.to_owned(),
        notice.source.clone(),
        notice.subject(),
    );
    move |outcome, detail| Delivery {
        time: now,
        rule,
        channel,
        kind,
        recipient,
        source,
        subject,
        outcome,
        detail,
    }
}

/// Logs and records the result of a send.
fn outcome(
    record: impl FnOnce(Outcome, String) -> Delivery,
    result: Result<String, String>,
    decision: &Decision,
    recipient: &str,
) -> Delivery {
    match result {
        Ok(detail) => {
            tracing::info!(rule = %decision.rule, channel = %decision.channel, %recipient, %detail, "notification sent");
            record(Outcome::Sent, detail)
        }
        Err(detail) => {
            tracing::warn!(rule = %decision.rule, channel = %decision.channel, %recipient, %detail, "notification failed");
            record(Outcome::Failed, detail)
        }
    }
}

/// The caller's side of a notifier running as a task ([`spawn_notifier`]).
#[derive(Debug, Clone)]
pub struct NotifierHandle {
    queue: mpsc::Sender<Notice>,
    config: Arc<NotifyConfig>,
    /// For the targets of a notice refused by a full queue (rules only, no state).
    rules: Arc<Policy>,
}

impl NotifierHandle {
    /// Queues `notice` without waiting; returns nothing when queued. When the queue is
    /// full, returns a suppressed delivery (detail `queue full`) for every recipient the
    /// notice would have gone to; when the task has ended, failed ones (`notifier
    /// stopped`). The caller stores them as it stores the task's deliveries.
    pub fn submit(&self, notice: Notice) -> Vec<Delivery> {
        #[allow(clippy::disallowed_methods)] // the adapter's clock read, for the records
        let now = Utc::now();
        self.submit_at(notice, now)
    }

    /// [`NotifierHandle::submit`] with the time of the records given.
    pub fn submit_at(&self, notice: Notice, now: DateTime<Utc>) -> Vec<Delivery> {
        let (outcome, detail, notice) = match self.queue.try_send(notice) {
            Ok(()) => return Vec::new(),
            Err(mpsc::error::TrySendError::Full(notice)) => (
                Outcome::Suppressed,
                SuppressReason::QueueFull.to_string(),
                notice,
            ),
            Err(mpsc::error::TrySendError::Closed(notice)) => {
                (Outcome::Failed, "notifier stopped".to_owned(), notice)
            }
        };
        tracing::warn!(source = %notice.source, title = %notice.title, %detail, "notice not queued");
        let mut deliveries = Vec::new();
        for (rule, channel) in self.rules.targets(&notice) {
            let Some(config) = self.config.channels.get(&channel) else {
                continue;
            };
            let decision = Decision {
                rule,
                channel,
                verdict: Verdict::Send,
            };
            for recipient in config.recipients() {
                let record = record(now, &decision, config.kind(), &recipient, &notice);
                deliveries.push(record(outcome, detail.clone()));
            }
        }
        deliveries
    }
}

/// Runs `notifier` as a task: notices come in through the returned handle's bounded
/// queue of `capacity` (at least 1), one at a time; every delivery goes out on the
/// returned receiver (bounded likewise: a caller that stops reading makes the queue fill
/// up, and further notices are recorded as suppressed). The task ends when every handle
/// is dropped and the queue is drained.
pub fn spawn_notifier(
    notifier: Notifier,
    capacity: usize,
) -> (NotifierHandle, mpsc::Receiver<Delivery>, JoinHandle<()>) {
    let capacity = capacity.max(1);
    let (queue, mut notices) = mpsc::channel::<Notice>(capacity);
    let (deliveries_tx, deliveries) = mpsc::channel::<Delivery>(capacity.saturating_mul(4));
    let handle = NotifierHandle {
        queue,
        config: Arc::clone(&notifier.config),
        rules: Arc::new(Policy::new(&notifier.config.rules)),
    };
    let mut notifier = notifier;
    let task = tokio::spawn(async move {
        while let Some(notice) = notices.recv().await {
            for delivery in notifier.notify(&notice).await {
                if deliveries_tx.send(delivery).await.is_err() {
                    tracing::debug!("delivery receiver dropped; record lost");
                }
            }
        }
    });
    (handle, deliveries, task)
}
