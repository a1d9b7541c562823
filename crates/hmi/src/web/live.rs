//! The live WebSocket `/api/live`: one task per browser, subscribed to the station's
//! broadcast of [`LiveMessage`]s; a snapshot first, and again whenever the browser lags.

use axum::extract::ws::{CloseFrame, Message, WebSocket, WebSocketUpgrade};
use axum::extract::State;
use axum::response::Response;
use axum::routing::get;
use axum::Router;
use tokio::sync::broadcast::error::RecvError;

use super::{AppError, AppState, LoggedIn, SameOrigin, MAX_WS_MESSAGE};
use crate::live::LiveMessage;
use crate::LogText;

pub(super) fn routes() -> Router<AppState> {
    Router::new().route("/api/live", get(live))
}

/// The close code of a socket whose session ended.
const SESSION_ENDED: u16 = 4001;

// The extractors run in order: an upgrade request at all, from this HMI's origin, of a
// live session.
async fn live(
    State(state): State<AppState>,
    upgrade: WebSocketUpgrade,
    _: SameOrigin,
    user: LoggedIn,
) -> Result<Response, AppError> {
    let ended = state.sessions.open_socket(&user.token).map_err(|refusal| {
        tracing::warn!(peer = %user.peer, user = %LogText(&user.session.user), %refusal, "WebSocket refused");
        AppError::Socket(refusal)
    })?;
    Ok(upgrade
        .max_message_size(MAX_WS_MESSAGE)
        .on_upgrade(move |socket| stream(socket, state, ended)))
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
) {
    // Subscribe before the snapshot, so nothing falls between them.
    let mut updates = state.station.subscribe();
    if !send(&mut socket, &LiveMessage::snapshot(&state.station)).await {
        return;
    }
    loop {
        tokio::select! {
            update = updates.recv() => match update {
                Ok(text) => {
                    if socket.send(Message::Text(text.into())).await.is_err() {
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
