//! The live WebSocket `/api/live`: one task per browser, subscribed to the station's
//! broadcast of [`LiveMessage`]s; a snapshot first, and again whenever the browser lags.
//!
//! `/api/live?batch=1` (what the HMI's own page asks for): the messages waiting when one is
//! sent go with it, as one JSON array per frame (at most [`BATCH`]); a lone message goes at
//! once as an array of one. A browser handling 10,000 updates a second then parses a few
//! hundred frames, not 10,000. Without it, one message per frame as before.
//!
//! Batched frames are paced: one at most every [`PACE`]. A message arriving after a quiet
//! while goes at once; during a burst the messages gather for the rest of the pace. The
//! burst of a thousand changes a station's link delivers over some 20 ms would otherwise
//! leave as hundreds of frames of one to three messages each, and every frame costs the
//! browser an IPC hop and a task: a change behind them (the live bench's measured point)
//! reached the page up to 20 ms after the HMI had it.

use axum::extract::ws::{CloseFrame, Message, WebSocket, WebSocketUpgrade};
use axum::extract::{RawQuery, State};
use axum::response::Response;
use axum::routing::get;
use axum::Router;
use tokio::sync::broadcast::error::{RecvError, TryRecvError};
use tokio::sync::broadcast::Receiver;

use super::{AppError, AppState, LoggedIn, SameOrigin, MAX_WS_MESSAGE};
use crate::live::LiveMessage;
use crate::LogText;

pub(super) fn routes() -> Router<AppState> {
    Router::new().route("/api/live", get(live))
}

/// The close code of a socket whose session ended.
const SESSION_ENDED: u16 = 4001;

/// The most messages in one batched frame.
const BATCH: usize = 1_000;

/// The least time between two batched frames to one browser (see the module doc).
const PACE: std::time::Duration = std::time::Duration::from_millis(2);

// The extractors run in order: an upgrade request at all, from this HMI's origin, of a
// live session.
async fn live(
    State(state): State<AppState>,
    RawQuery(query): RawQuery,
    upgrade: WebSocketUpgrade,
    _: SameOrigin,
    user: LoggedIn,
) -> Result<Response, AppError> {
    let batch = query
        .as_deref()
        .is_some_and(|q| q.split('&').any(|pair| pair == "batch=1"));
    let ended = state.sessions.open_socket(&user.token).map_err(|refusal| {
        tracing::warn!(peer = %user.peer, user = %LogText(&user.session.user), %refusal, "WebSocket refused");
        AppError::Socket(refusal)
    })?;
    Ok(upgrade
        .max_message_size(MAX_WS_MESSAGE)
        .on_upgrade(move |socket| stream(socket, state, ended, batch)))
}

async fn send(socket: &mut WebSocket, message: &LiveMessage) -> bool {
    socket
        .send(Message::Text(message.to_text().into()))
        .await
        .is_ok()
}

/// Feeds one browser until it goes away or its session ends (`ended` then reports an
/// error: the session's sender is gone).
async fn stream(
    mut socket: WebSocket,
    state: AppState,
    mut ended: tokio::sync::watch::Receiver<()>,
    batch: bool,
) {
    // Subscribe before the snapshot, so nothing falls between them.
    let mut updates = state.station.subscribe();
    if !send(&mut socket, &LiveMessage::snapshot(&state.station)).await {
        return;
    }
    let mut last_sent = tokio::time::Instant::now();
    loop {
        tokio::select! {
            update = updates.recv() => match update {
                Ok(text) => {
                    let (frame, lagged) = if batch {
                        tokio::time::sleep_until(last_sent + PACE).await;
                        gather(text, &mut updates)
                    } else {
                        (text, false)
                    };
                    if socket.send(Message::Text(frame.into())).await.is_err() {
                        return;
                    }
                    last_sent = tokio::time::Instant::now();
                    if lagged && !send(&mut socket, &LiveMessage::snapshot(&state.station)).await {
                        return;
                    }
                }
                Err(RecvError::Lagged(_)) => {
                    // Too slow a browser: start it over from a fresh snapshot.
                    if !send(&mut socket, &LiveMessage::snapshot(&state.station)).await {
                        return;
                    }
                }
                Err(RecvError::Closed) => return,
            },
            _ = ended.changed() => {
                let close = CloseFrame { code: SESSION_ENDED, reason: "session ended".into() };
                let _ = socket.send(Message::Close(Some(close))).await;
                return;
            }
            incoming = socket.recv() => match incoming {
                Some(Ok(Message::Close(_))) | None | Some(Err(_)) => return,
                Some(Ok(_)) => {}
            },
        }
    }
}

/// `first` and the messages already waiting after it (at most [`BATCH`] in all), as one
/// JSON array; and whether the browser lagged meanwhile (a snapshot must follow).
fn gather(first: String, updates: &mut Receiver<String>) -> (String, bool) {
    let mut frame = String::with_capacity(first.len() * 8);
    frame.push('[');
    frame.push_str(&first);
    let mut lagged = false;
    for _ in 1..BATCH {
        match updates.try_recv() {
            Ok(text) => {
                frame.push(',');
                frame.push_str(&text);
            }
            Err(TryRecvError::Lagged(_)) => {
                lagged = true;
                break;
            }
            Err(TryRecvError::Empty | TryRecvError::Closed) => break,
        }
    }
    frame.push(']');
    (frame, lagged)
}
