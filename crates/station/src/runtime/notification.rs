//! A node's notifications (`[node.notify]`): what its lifts report (a fault archived, a
//! board that stopped answering) reaches the service firm's technicians by e-mail and
//! its ticket system by webhook, without anyone logged in; the rules, quiet periods and
//! rate limits are the `notify` crate's. Every delivery, sent, failed or suppressed, is
//! recorded in the event store's `notifications`.
//!
//! ```text
//!  lift task --Notice--> Notifications::submit --> notify::spawn_notifier (queue, SMTP, webhook)
//!                                                        \--Delivery--> EventStore.notifications
//! ```

use std::sync::Arc;

use devices::ekm66::tables::{self, FaultGroup};
use notify::{Delivery, Notice, Notifier, NotifierHandle, NotifyConfig};
use tokio::sync::mpsc;

use crate::store::{EventStore, LiftFaultRecord, NotificationOutcome, NotificationRecord};

/// Notices waiting for the sender before new ones are recorded as suppressed.
const QUEUE: usize = 256;

/// The class of a notice for a board that stopped answering.
pub const COMM_LOST: &str = "comm-lost";

/// A node's notification sender (cheap to clone).
#[derive(Clone)]
pub struct Notifications {
    handle: NotifierHandle,
    records: mpsc::UnboundedSender<Delivery>,
}

impl std::fmt::Debug for Notifications {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Notifications").finish_non_exhaustive()
    }
}

impl Notifications {
    /// Starts the sender of `config` and the recorder of its deliveries.
    pub(crate) fn spawn(
        node: &str,
        config: NotifyConfig,
        store: Option<Arc<dyn EventStore>>,
    ) -> Result<Notifications, notify::NotifierError> {
        let notifier = Notifier::new(config)?;
        let (handle, mut deliveries, _task) = notify::spawn_notifier(notifier, QUEUE);
        let (records, mut immediate) = mpsc::unbounded_channel();
        let node = node.to_owned();
        tokio::spawn(async move {
            loop {
                let delivery = tokio::select! {
                    Some(delivery) = deliveries.recv() => delivery,
                    Some(delivery) = immediate.recv() => delivery,
                    else => break,
                };
                record(&node, store.as_deref(), delivery).await;
            }
        });
        Ok(Notifications { handle, records })
    }

    /// Hands a notice to the sender (never waits); what is decided at once (a full
    /// queue) is recorded too.
    pub fn submit(&self, notice: Notice) {
        for delivery in self.handle.submit(notice) {
            let _ = self.records.send(delivery);
        }
    }

    /// A fault archived from a lift's board.
    pub(crate) fn fault(&self, record: &LiftFaultRecord, description: &str) {
        let group = tables::fault_group(record.code);
        let board_time = record
            .board_time
            .map(|time| time.format("%Y-%m-%d %H:%M:%S").to_string())
            .unwrap_or_else(|| "not valid".to_owned());
        let text = format!(
            "Fault 0x{code:02X}: {english}\n\
             Porucha 0x{code:02X}: {czech}\n\
             Group: {group}\n\
             Lift: {lift}{description}, node {node}\n\
             Floor {floor}, target {target}\n\
             Board time: {board_time}\n\
             Archived: {received}",
            code = record.code,
            english = tables::fault_text(record.code),
            czech = tables::fault_text_czech(record.code),
            group = group_label(group),
            lift = record.lift,
            node = record.node,
            floor = record.floor,
            target = record.target,
            received = record.received_time.format("%Y-%m-%d %H:%M:%S UTC"),
        );
        self.submit(Notice {
            source: record.lift.clone(),
            class: group.key().to_owned(),
            code: Some(record.code.into()),
            title: format!(
                "fault 0x{:02X} {}",
                record.code,
                tables::fault_text(record.code)
            ),
            text,
            time: record.received_time,
            link: None,
        });
    }

    /// A lift's board stopped answering.
    pub(crate) fn comm_lost(
        &self,
        lift: &str,
        description: &str,
        time: chrono::DateTime<chrono::Utc>,
    ) {
        self.submit(Notice {
            source: lift.to_owned(),
            class: COMM_LOST.to_owned(),
            code: None,
            title: "controller board not answering".to_owned(),
            text: format!(
                "The controller board of lift {lift}{description} does not answer: its values are invalid until it does.\n\
                 Řídicí deska výtahu {lift} neodpovídá."
            ),
            time,
            link: None,
        });
    }
}

/// `Safety circuit broken during travel / Přerušení ...`: a group in both languages.
fn group_label(group: FaultGroup) -> String {
    format!("{} / {}", group.english(), group.czech())
}

async fn record(node: &str, store: Option<&dyn EventStore>, delivery: Delivery) {
    let outcome = match delivery.outcome {
        notify::Outcome::Sent => NotificationOutcome::Sent,
        notify::Outcome::Failed => NotificationOutcome::Failed,
        notify::Outcome::Suppressed => NotificationOutcome::Suppressed,
    };
    match outcome {
        NotificationOutcome::Failed => {
            tracing::warn!(%node, rule = %delivery.rule, recipient = %delivery.recipient, detail = %delivery.detail, "notification failed")
        }
        _ => {
            tracing::info!(%node, rule = %delivery.rule, recipient = %delivery.recipient, %outcome, detail = %delivery.detail, "notification")
        }
    }
    let Some(store) = store else {
        return;
    };
    let record = NotificationRecord {
        id: None,
        time: delivery.time,
        rule: delivery.rule,
        channel: delivery.kind.as_str().to_owned(),
        recipient: delivery.recipient,
        source: delivery.source,
        subject: delivery.subject,
        outcome,
        detail: delivery.detail,
    };
    if let Err(error) = store.append_notification(&record).await {
        tracing::error!(%node, %error, "notification not recorded");
    }
}
