//! Commands forwarded to a lower station, and their answers as the receiving task meets
//! them.
//!
//! A concentrator forwards a command down an IEC 104 link; a gateway forwards one to an
//! IEC 101 outstation on a serial line. Either way the lower station's confirmation
//! (ACT_CON, or a negative mirror 44..47) becomes this node's, and its termination
//! (ACT_TERM) this node's termination. The task that reads the lower station's stream
//! reports both to [`CommandWatches::answered`] in the order it meets them, after it has
//! applied the data received before them: a forwarded command's return information is
//! published here before its termination.

use std::sync::{Mutex, MutexGuard, PoisonError};

use iec60870::asdu::{Asdu, Cause, Ioa, TypeId};
use tokio::sync::oneshot;

/// The forwarded commands whose answers a receiving task looks out for.
#[derive(Debug, Default)]
pub(crate) struct CommandWatches(Mutex<Vec<CommandWatch>>);

/// A forwarded command whose answers are looked out for.
#[derive(Debug)]
struct CommandWatch {
    type_id: TypeId,
    ioa: Ioa,
    confirmed: Option<oneshot::Sender<bool>>,
    terminated: Option<oneshot::Sender<()>>,
}

impl CommandWatch {
    /// Nothing left to report: each answer was passed on or its receiver is gone.
    fn abandoned(&self) -> bool {
        self.confirmed
            .as_ref()
            .is_none_or(oneshot::Sender::is_closed)
            && self
                .terminated
                .as_ref()
                .is_none_or(oneshot::Sender::is_closed)
    }
}

/// The answers of a forwarded command, as the receiving task meets them: its
/// confirmation (positive or not), then its termination.
#[derive(Debug)]
pub(crate) struct CommandAnswers {
    pub confirmed: oneshot::Receiver<bool>,
    pub terminated: oneshot::Receiver<()>,
}

impl CommandWatches {
    fn lock(&self) -> MutexGuard<'_, Vec<CommandWatch>> {
        self.0.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Watches for the answers of a command about to be sent: its type and the lower
    /// station's address.
    pub(crate) fn watch(&self, type_id: TypeId, ioa: Ioa) -> CommandAnswers {
        let (confirmed, confirmed_rx) = oneshot::channel();
        let (terminated, terminated_rx) = oneshot::channel();
        let mut commands = self.lock();
        commands.retain(|watch| !watch.abandoned());
        commands.push(CommandWatch {
            type_id,
            ioa,
            confirmed: Some(confirmed),
            terminated: Some(terminated),
        });
        CommandAnswers {
            confirmed: confirmed_rx,
            terminated: terminated_rx,
        }
    }

    /// Passes a command's answer from the lower station to whoever forwarded the command.
    pub(crate) fn answered(&self, asdu: &Asdu) {
        let Some(object) = asdu.objects.first() else {
            return;
        };
        let cause = asdu.cot.cause;
        let confirmation = cause == Cause::ACTIVATION_CON || (44..=47).contains(&cause.value());
        let termination = cause == Cause::ACTIVATION_TERMINATION;
        if !confirmation && !termination {
            return;
        }
        let mut commands = self.lock();
        for watch in commands
            .iter_mut()
            .filter(|watch| watch.type_id == asdu.type_id && watch.ioa == object.ioa)
        {
            if confirmation {
                if let Some(confirmed) = watch.confirmed.take() {
                    let _ = confirmed.send(!asdu.cot.negative && cause == Cause::ACTIVATION_CON);
                }
            } else if let Some(terminated) = watch.terminated.take() {
                let _ = terminated.send(());
            }
        }
        // Answered in full, or nobody waits any more (a taken sender counts as abandoned).
        commands.retain(|watch| !watch.abandoned());
    }

    /// Ends every watch: the lower station is gone, no answer will come (the receivers
    /// see their senders dropped).
    pub(crate) fn abandon_all(&self) {
        self.lock().clear();
    }
}
