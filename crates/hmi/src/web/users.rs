//! User administration for level 9 (docs/HMI.md, "Users"): the list (never a hash), add,
//! remove, change the level, reset a password, lock and unlock. Every change rewrites the
//! users file through [`crate::users::Users`] (the same argon2id hashing as `stanice
//! user`), ends the changed user's sessions, and is audited like a command: who, what,
//! when, in the HMI's store.

use std::sync::{Arc, RwLock};

use axum::extract::rejection::JsonRejection;
use axum::extract::{Path, State};
use axum::routing::{get, post};
use axum::{Json, Router};
use chrono::Utc;
use serde::Deserialize;
use serde_json::{json, Value};
use store::{Actor, CommandOutcome, CommandPhase, CommandRecord, PointValue};

use super::{AppError, AppState, LoggedIn, Writer};
use crate::users::{Users, MAX_LEVEL};
use crate::{HmiError, LogText};

pub(super) fn routes() -> Router<AppState> {
    Router::new()
        .route("/api/users", get(list).post(add))
        .route("/api/users/{name}", axum::routing::delete(remove))
        .route("/api/users/{name}/level", post(set_level))
        .route("/api/users/{name}/password", post(reset_password))
        .route("/api/users/{name}/lock", post(set_locked))
}

/// The level that administers users.
pub(super) const ADMIN_LEVEL: u8 = MAX_LEVEL;

fn require_admin(level: u8) -> Result<(), AppError> {
    if level < ADMIN_LEVEL {
        return Err(AppError::LevelTooLow {
            needed: ADMIN_LEVEL,
            has: level,
        });
    }
    Ok(())
}

/// The users as the page lists them: name, level, locked, start screen; no hash.
fn listing(users: &Users) -> Value {
    let list: Vec<Value> = users
        .names()
        .filter_map(|name| {
            users.record(name).map(|user| {
                json!({"name": name, "level": user.level, "locked": user.locked,
                       "start": user.start})
            })
        })
        .collect();
    json!(list)
}

async fn list(State(state): State<AppState>, user: LoggedIn) -> Result<Json<Value>, AppError> {
    require_admin(user.session.level)?;
    let users = state.users.read().unwrap_or_else(|p| p.into_inner());
    Ok(Json(listing(&users)))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct NewUser {
    name: String,
    level: u8,
    password: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct NewLevel {
    level: u8,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct NewPassword {
    password: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct NewLock {
    locked: bool,
}

/// A change of the users file, run off the async workers (argon2 hashing, file writes).
type Change = Box<dyn FnOnce(&mut Users) -> Result<(), AppError> + Send>;

/// Checks the administrator, applies `change` to the users (and their file), ends the
/// sessions of `name` when `end_sessions`, audits `what` and answers the new list.
async fn administer(
    state: &AppState,
    admin: &Writer,
    name: &str,
    what: String,
    end_sessions: bool,
    change: Change,
) -> Result<Json<Value>, AppError> {
    require_admin(admin.0.session.level)?;
    let users: Arc<RwLock<Users>> = Arc::clone(&state.users);
    let changed = tokio::task::spawn_blocking(move || {
        let mut users = users.write().unwrap_or_else(|p| p.into_inner());
        change(&mut users).map(|()| listing(&users))
    })
    .await
    .map_err(|_| AppError::BadValue("the users file could not be changed"))?;
    let listing = match changed {
        Ok(listing) => listing,
        Err(error) => {
            tracing::warn!(admin = %LogText(admin.user()), user = %LogText(name), error = %LogText(&error.to_string()), "user administration refused");
            return Err(error);
        }
    };
    if end_sessions {
        state.sessions.remove_user(name);
    }
    tracing::info!(admin = %LogText(admin.user()), user = %LogText(name), %what, "user administration");
    state.station.recorder().command(CommandRecord {
        id: None,
        time: Utc::now(),
        actor: Actor::User(admin.user().to_owned()),
        node: state.audit_node.clone(),
        point: format!("user:{name}"),
        ioa: None,
        value: PointValue::Text(what.clone()),
        phase: CommandPhase::Execute,
        outcome: CommandOutcome::Executed,
        detail: what,
    });
    Ok(Json(listing))
}

/// The users file's refusals as answers: an unknown user 404, the last administrator
/// 409, anything else (a bad name, a short password) 400.
fn refused(error: HmiError) -> AppError {
    AppError::BadParameter {
        name: "user",
        message: error.to_string(),
    }
}

fn known(users: &Users, name: &str) -> Result<(), AppError> {
    users.record(name).map(|_| ()).ok_or(AppError::NotFound)
}

fn keep_administrator(users: &Users, name: &str, what: &str) -> Result<(), AppError> {
    users
        .keep_an_administrator(name, what)
        .map_err(|error| AppError::Combination(error.to_string()))
}

async fn add(
    State(state): State<AppState>,
    admin: Writer,
    body: Result<Json<NewUser>, JsonRejection>,
) -> Result<Json<Value>, AppError> {
    require_admin(admin.0.session.level)?;
    let Json(new) = body.map_err(AppError::body("bad user request: "))?;
    let what = format!("user `{}` added with level {}", new.name, new.level);
    let name = new.name.clone();
    administer(
        &state,
        &admin,
        &name,
        what,
        false,
        Box::new(move |users| {
            users
                .add(&new.name, new.level, &new.password)
                .map_err(refused)
        }),
    )
    .await
}

async fn remove(
    State(state): State<AppState>,
    admin: Writer,
    Path(name): Path<String>,
) -> Result<Json<Value>, AppError> {
    let what = format!("user `{name}` removed");
    let target = name.clone();
    administer(
        &state,
        &admin,
        &name,
        what,
        true,
        Box::new(move |users| {
            known(users, &target)?;
            keep_administrator(users, &target, "removed")?;
            users.remove(&target).map_err(refused)
        }),
    )
    .await
}

async fn set_level(
    State(state): State<AppState>,
    admin: Writer,
    Path(name): Path<String>,
    body: Result<Json<NewLevel>, JsonRejection>,
) -> Result<Json<Value>, AppError> {
    require_admin(admin.0.session.level)?;
    let Json(new) = body.map_err(AppError::body("bad level request: "))?;
    let what = format!("user `{name}` set to level {}", new.level);
    let target = name.clone();
    administer(
        &state,
        &admin,
        &name,
        what,
        true,
        Box::new(move |users| {
            known(users, &target)?;
            if new.level < MAX_LEVEL {
                keep_administrator(users, &target, "demoted")?;
            }
            users.set_level(&target, new.level).map_err(refused)
        }),
    )
    .await
}

async fn reset_password(
    State(state): State<AppState>,
    admin: Writer,
    Path(name): Path<String>,
    body: Result<Json<NewPassword>, JsonRejection>,
) -> Result<Json<Value>, AppError> {
    require_admin(admin.0.session.level)?;
    let Json(new) = body.map_err(AppError::body("bad password request: "))?;
    let what = format!("password of user `{name}` reset");
    let target = name.clone();
    administer(
        &state,
        &admin,
        &name,
        what,
        true,
        Box::new(move |users| {
            known(users, &target)?;
            users.passwd(&target, &new.password, None).map_err(refused)
        }),
    )
    .await
}

async fn set_locked(
    State(state): State<AppState>,
    admin: Writer,
    Path(name): Path<String>,
    body: Result<Json<NewLock>, JsonRejection>,
) -> Result<Json<Value>, AppError> {
    require_admin(admin.0.session.level)?;
    let Json(new) = body.map_err(AppError::body("bad lock request: "))?;
    let what = if new.locked {
        format!("user `{name}` locked")
    } else {
        format!("user `{name}` unlocked")
    };
    let target = name.clone();
    administer(
        &state,
        &admin,
        &name,
        what,
        new.locked,
        Box::new(move |users| {
            known(users, &target)?;
            if new.locked {
                keep_administrator(users, &target, "locked")?;
            }
            users.set_locked(&target, new.locked).map_err(refused)
        }),
    )
    .await
}
