//! The points, the controls the user may see, and sending a command.

use axum::extract::rejection::JsonRejection;
use axum::extract::State;
use axum::routing::{get, post};
use axum::{Json, Router};
use chrono::Utc;
use serde::Deserialize;
use serde_json::{json, Value};
use store::{Actor, CommandOutcome, CommandPhase, CommandRecord, PointValue};

use super::{AppError, AppState, LoggedIn, Writer, SENT_DETAIL};
use crate::link::ControlOutcome;
use crate::LogText;

pub(super) fn routes() -> Router<AppState> {
    Router::new()
        .route("/api/points", get(points))
        .route("/api/controls", get(controls))
        .route("/api/command", post(command))
}

async fn points(State(state): State<AppState>, _: LoggedIn) -> Json<Value> {
    Json(
        json!({"link": crate::live::LinkState::of(&state.station), "points": state.station.points()}),
    )
}

async fn controls(State(state): State<AppState>, user: LoggedIn) -> Json<Value> {
    let config = state.station.config();
    let list: Vec<Value> = config
        .points
        .iter()
        .filter(|p| p.type_id.is_command())
        .map(|p| {
            let control = config.control(&p.name);
            json!({
                "command": p.name,
                "ioa": p.ioa,
                "type": p.type_id.to_string(),
                "description": p.description,
                "level": control.level,
                "select": control.select,
                "confirm": control.confirm,
                "local_point": control.local_point,
                "allowed": user.session.level >= control.level,
            })
        })
        .collect();
    Json(json!(list))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CommandRequest {
    command: String,
    value: Value,
}

/// A command's value as the station gets it: a boolean is 0 or 1.
fn command_value(value: &Value) -> Result<f64, AppError> {
    match value {
        Value::Bool(b) => Ok(f64::from(u8::from(*b))),
        Value::Number(n) => n
            .as_f64()
            .filter(|v| v.is_finite())
            .ok_or(AppError::BadValue("value is not a finite number")),
        _ => Err(AppError::BadValue("value must be a boolean or a number")),
    }
}

async fn command(
    State(state): State<AppState>,
    writer: Writer,
    body: Result<Json<CommandRequest>, JsonRejection>,
) -> Result<Json<Value>, AppError> {
    let Json(request) = body.map_err(AppError::body("bad command request: "))?;
    let value = command_value(&request.value)?;
    let (outcome, detail) = control(&state, &writer, &request.command, value).await?;
    Ok(Json(json!({"outcome": outcome, "detail": detail})))
}

/// Runs the control `name` with `value` for `writer`: its level, its control authority,
/// the operator lease, the write-ahead audit record, the station's answer (committed to
/// the audit before it is returned).
pub(super) async fn control(
    state: &AppState,
    writer: &Writer,
    name: &str,
    value: f64,
) -> Result<(ControlOutcome, String), AppError> {
    let (peer, user) = (writer.peer(), writer.user());
    let config = state.station.config();
    let Some(row) = config
        .points
        .iter()
        .find(|p| p.name == name && p.type_id.is_command())
    else {
        tracing::warn!(%peer, user = %LogText(user), command = %LogText(name), "unknown command refused");
        return Err(AppError::NoCommand(name.to_owned()));
    };
    let control = config.control(&row.name);
    if let Err(refused) = writer.require_level(control.level) {
        state.station.audit(
            user,
            &row.name,
            row.ioa,
            value,
            ControlOutcome::RefusedPermission,
            &refused.to_string(),
        );
        return Err(refused);
    }
    // The control authority, then (a lab with an operator lease) the lease: only its
    // holder controls, and the control renews it.
    let refusal = authority_refusal(state, &control)
        .map(|detail| (detail, "no control authority"))
        .or_else(|| lease_refusal(state, user).map(|detail| (detail, "no operator lease")));
    if let Some((detail, why)) = refusal {
        tracing::warn!(%peer, user = %LogText(user), command = %row.name, "control refused: {why}");
        state.station.audit(
            user,
            &row.name,
            row.ioa,
            value,
            ControlOutcome::RefusedAuthority,
            &detail,
        );
        state.station.recorder().flush().await;
        return Err(AppError::NoAuthority(detail));
    }
    // Write-ahead: the attempt is committed to the store before the command leaves, so
    // a command the station carried out is in the audit even if the HMI dies meanwhile.
    if let Some(store) = &state.store {
        let sent = CommandRecord {
            id: None,
            time: Utc::now(),
            actor: Actor::User(user.to_owned()),
            node: state.audit_node.clone(),
            point: row.name.clone(),
            ioa: Some(row.ioa),
            value: PointValue::Float(value),
            phase: CommandPhase::Execute,
            outcome: CommandOutcome::Failed,
            detail: SENT_DETAIL.to_owned(),
        };
        if let Err(e) = store.append_command(&sent).await {
            tracing::error!(error = %e, command = %row.name, "command not sent: its audit record cannot be written");
            return Err(AppError::AuditUnavailable);
        }
    }
    let (outcome, detail) = state.station.operate(user, &row.name, value).await;
    // The outcome's record is committed before the user hears of it.
    state.station.recorder().flush().await;
    Ok((outcome, detail))
}

/// Why `control` is refused for want of its control authority, if it is.
fn authority_refusal(state: &AppState, control: &crate::config::ControlConfig) -> Option<String> {
    let authority = control.authority.as_ref()?;
    let point = state.station.point(&authority.point);
    let held = point
        .as_ref()
        .is_some_and(|p| !p.invalid && p.value == json!(authority.state));
    if held {
        return None;
    }
    // In words, not raw values: a single point is on or off.
    let words = |value: &Value| match value {
        Value::Bool(true) => "on".to_owned(),
        Value::Bool(false) => "off".to_owned(),
        other => other.to_string(),
    };
    let now = match &point {
        Some(p) if !p.invalid => words(&p.value),
        _ => "unknown (invalid)".to_owned(),
    };
    let needed = words(&json!(authority.state));
    Some(match &authority.reason {
        Some(reason) => format!("{reason} ({} is {now})", authority.point),
        None => format!(
            "the control authority is not with this HMI ({} is {now}, {needed} needed)",
            authority.point
        ),
    })
}

/// Why `user`'s control is refused by the operator lease, if it is; a control of the
/// holder renews the lease.
pub(super) fn lease_refusal(state: &AppState, user: &str) -> Option<String> {
    let desk = state.lease.as_ref()?;
    let refused = desk
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .control(user, Utc::now())
        .err()?;
    Some(format!("operator lease: {refused}"))
}
