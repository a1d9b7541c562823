//! One server connection: a tokio task that drives two sans-IO cores over a socket, the
//! APCI [`Session`] (frames, windows, timers) and the outstation's [`LinkCore`]
//! (answers, interrogation, commands, the group's events).
//!
//! Each turn of the loop hands the session's events to the link core, lets the core fill
//! the send window, writes what the session has to send, and waits for the socket, the
//! next protocol deadline, the group's news (while started) or a command outcome.

use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Instant;

use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};
use tokio::sync::watch;
use tracing::Instrument;

use crate::cs104::session::{Role, Session, SessionEvent};
use crate::outstation::{LinkCore, LinkLayer};

use super::Shared;

/// Bytes read from the socket at a time.
const READ_BUFFER: usize = 1024;

/// IEC 104's link layer for the outstation's core: the APCI session's k window and its
/// unacknowledged I frames.
impl LinkLayer for Session {
    fn can_send(&self) -> bool {
        Session::can_send(self)
    }

    fn send_asdu(&mut self, now: Instant, asdu: &[u8]) -> bool {
        match Session::send_asdu(self, now, asdu) {
            Ok(()) => true,
            Err(error) => {
                tracing::debug!(%error, "could not send");
                false
            }
        }
    }

    fn unconfirmed(&self) -> usize {
        self.unacknowledged_count()
    }

    fn hand_over(&mut self) -> usize {
        self.deactivate();
        self.take_unacknowledged().len()
    }

    fn take_back(&mut self) {
        self.reactivate();
    }
}

/// Serves one accepted (and, with TLS, handshaken) connection until it ends.
pub(super) async fn run<S>(
    shared: Arc<Shared>,
    id: u64,
    slot: &super::admission::Slot,
    peer: SocketAddr,
    stream: S,
    shutdown: watch::Receiver<bool>,
) where
    S: AsyncRead + AsyncWrite + Unpin + Send + 'static,
{
    let span = tracing::info_span!("iec104_connection", %peer, id);
    async move {
        let Some(mut core) = shared.outstation.open_link(id, peer.into()) else {
            // The accept loop checked that a group takes the client; the groups by
            // address are fixed, so this does not happen.
            tracing::warn!("no redundancy group takes this client");
            return;
        };
        tracing::info!(group = %core.group_name(), "client connected");
        let now = tokio::time::Instant::now();
        // A named group's standby may wait for its STARTDT as long as it likes.
        let start_deadline = shared
            .config
            .start_timeout
            .filter(|_| !slot.is_named())
            .map(|timeout| now + timeout);
        let mut session = Session::new(
            shared.config.apci.clone(),
            Role::ControlledStation,
            now.into_std(),
        );
        let reason = drive(
            &shared,
            slot,
            &mut core,
            &mut session,
            start_deadline,
            stream,
            shutdown,
        )
        .await;
        core.close(&session);
        tracing::info!(%reason, "connection closed");
    }
    .instrument(span)
    .await
}

/// The connection's loop; returns why it ended.
async fn drive<S>(
    shared: &Shared,
    slot: &super::admission::Slot,
    core: &mut LinkCore,
    session: &mut Session,
    mut start_deadline: Option<tokio::time::Instant>,
    stream: S,
    mut shutdown: watch::Receiver<bool>,
) -> String
where
    S: AsyncRead + AsyncWrite + Unpin + Send + 'static,
{
    let (mut reader, mut writer) = tokio::io::split(stream);
    let mut input = vec![0u8; READ_BUFFER];
    let mut output = Vec::new();
    let changes = core.changes();
    loop {
        // Read before the core looks at its group, so that a change from now on ends the
        // wait below (no lost wake-up between the look and the wait).
        let seen = changes.version();
        let now = tokio::time::Instant::now().into_std();
        core.check_still_active(session);
        while let Some(event) = session.poll_event() {
            match event {
                SessionEvent::Asdu(asdu) => core.handle_asdu(now, asdu),
                SessionEvent::Started => {
                    start_deadline = None;
                    slot.started();
                    core.start();
                }
                SessionEvent::Stopped => core.stop(session),
                SessionEvent::Acknowledged { .. } => core.acknowledged(session),
                SessionEvent::Closed(reason) => return reason.to_string(),
            }
        }
        if let Some(reason) = core.close_reason() {
            return reason;
        }
        core.fill(now, session);
        while session.poll_transmit(&mut output) {}
        if !output.is_empty() {
            tracing::trace!(tx = ?format_args!("{output:02X?}"), "raw");
            if let Err(error) = writer.write_all(&output).await {
                return format!("write failed: {error}");
            }
            output.clear();
        }
        if let Some(start_deadline) = start_deadline {
            if start_deadline <= tokio::time::Instant::now() {
                return format!(
                    "no STARTDT within {:.1} s of connecting: the slot is given back",
                    shared
                        .config
                        .start_timeout
                        .unwrap_or_default()
                        .as_secs_f64()
                );
            }
        }
        let deadline = session
            .poll_timeout()
            .map(tokio::time::Instant::from_std)
            .into_iter()
            .chain(start_deadline)
            .min();
        let follows_group = core.follows_group();
        let awaits_commands = core.awaits_commands();
        tokio::select! {
            read = reader.read(&mut input) => match read {
                Ok(0) => return "closed by the client".to_owned(),
                Ok(count) => {
                    let now = tokio::time::Instant::now().into_std();
                    let bytes = input.get(..count).unwrap_or_default();
                    // The raw-bytes layer of the protocol log (APCI and ASDU log at debug).
                    tracing::trace!(rx = ?format_args!("{bytes:02X?}"), "raw");
                    session.handle_input(now, bytes);
                }
                Err(error) => return format!("read failed: {error}"),
            },
            () = sleep_until(deadline) => {
                session.handle_timeout(tokio::time::Instant::now().into_std());
            }
            () = changes.changed(seen), if follows_group => {}
            () = std::future::poll_fn(|context| core.poll_commands(context)), if awaits_commands => {}
            _ = shutdown.changed() => return "server shut down".to_owned(),
            () = slot.evicted() => {
                return "evicted for a newcomer: the table was full and this connection never started data transfer".to_owned();
            }
        }
    }
}

async fn sleep_until(deadline: Option<tokio::time::Instant>) {
    match deadline {
        Some(deadline) => tokio::time::sleep_until(deadline).await,
        None => std::future::pending().await,
    }
}
