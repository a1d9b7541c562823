//! Sessions, CSRF tokens and the login rate limit.
//!
//! A session is a random 256-bit token in an HttpOnly, SameSite=Strict cookie; each has
//! its own random CSRF token that every state-changing request must echo in the
//! `X-CSRF-Token` header (a forged cross-site form cannot read it). Sessions expire after
//! [`SESSION_IDLE`] without use. Failed logins are counted per client address and per
//! user name; after [`MAX_FAILURES`] within [`FAILURE_WINDOW`] further attempts are
//! refused for [`LOCKOUT`], whatever the password.

use std::collections::HashMap;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// A session ends after this long without a request.
pub const SESSION_IDLE: Duration = Duration::from_secs(8 * 3600);
/// Failed logins allowed within the window.
pub const MAX_FAILURES: u32 = 5;
/// The window failures are counted in.
pub const FAILURE_WINDOW: Duration = Duration::from_secs(60);
/// How long a client or user is locked out after too many failures.
pub const LOCKOUT: Duration = Duration::from_secs(60);

/// A logged-in user.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Session {
    /// User name.
    pub user: String,
    /// Permission level.
    pub level: u8,
    /// The token the session's requests must carry in `X-CSRF-Token`.
    pub csrf: String,
}

fn random_token() -> String {
    let mut bytes = [0u8; 32];
    rand::fill(&mut bytes);
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Compares two strings in time independent of where they differ.
pub fn constant_time_eq(a: &str, b: &str) -> bool {
    a.len() == b.len()
        && a.bytes()
            .zip(b.bytes())
            .fold(0u8, |acc, (x, y)| acc | (x ^ y))
            == 0
}

/// The live sessions.
#[derive(Debug, Default)]
pub struct Sessions {
    map: Mutex<HashMap<String, (Session, Instant)>>,
}

impl Sessions {
    /// Starts a session; returns its token.
    pub fn create(&self, user: &str, level: u8) -> (String, Session) {
        let token = random_token();
        let session = Session {
            user: user.to_owned(),
            level,
            csrf: random_token(),
        };
        let mut map = self.map.lock().unwrap_or_else(|p| p.into_inner());
        let now = Instant::now();
        map.retain(|_, (_, used)| now.duration_since(*used) < SESSION_IDLE);
        map.insert(token.clone(), (session.clone(), now));
        (token, session)
    }

    /// The session of a token, refreshed; `None` when unknown or expired.
    pub fn get(&self, token: &str) -> Option<Session> {
        let mut map = self.map.lock().unwrap_or_else(|p| p.into_inner());
        let now = Instant::now();
        let (session, used) = map.get_mut(token)?;
        if now.duration_since(*used) >= SESSION_IDLE {
            map.remove(token);
            return None;
        }
        *used = now;
        Some(session.clone())
    }

    /// Ends a session.
    pub fn remove(&self, token: &str) {
        self.map
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .remove(token);
    }

    /// Ends every session of a user (removed or demoted by an administrator).
    pub fn remove_user(&self, user: &str) {
        self.map
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .retain(|_, (s, _)| s.user != user);
    }
}

#[derive(Debug, Clone, Copy)]
struct Failures {
    count: u32,
    since: Instant,
    locked_until: Option<Instant>,
}

/// Counts failed logins per key (a client address, a user name).
#[derive(Debug, Default)]
pub struct LoginLimiter {
    map: Mutex<HashMap<String, Failures>>,
}

impl LoginLimiter {
    /// `Err(retry_after)` while `key` is locked out.
    pub fn check(&self, key: &str) -> Result<(), Duration> {
        let map = self.map.lock().unwrap_or_else(|p| p.into_inner());
        match map.get(key).and_then(|f| f.locked_until) {
            Some(until) if until > Instant::now() => Err(until - Instant::now()),
            _ => Ok(()),
        }
    }

    /// Records a failure of `key`.
    pub fn fail(&self, key: &str) {
        let mut map = self.map.lock().unwrap_or_else(|p| p.into_inner());
        let now = Instant::now();
        if map.len() > 100_000 {
            // Bounded memory under a flood of names: forget expired entries.
            map.retain(|_, f| now.duration_since(f.since) < FAILURE_WINDOW);
        }
        let entry = map.entry(key.to_owned()).or_insert(Failures {
            count: 0,
            since: now,
            locked_until: None,
        });
        if now.duration_since(entry.since) >= FAILURE_WINDOW {
            *entry = Failures {
                count: 0,
                since: now,
                locked_until: None,
            };
        }
        entry.count += 1;
        if entry.count >= MAX_FAILURES {
            entry.locked_until = Some(now + LOCKOUT);
        }
    }

    /// Forgets the failures of `key` after a successful login.
    pub fn succeed(&self, key: &str) {
        self.map
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .remove(key);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sessions_have_distinct_tokens_and_end() {
        let sessions = Sessions::default();
        let (a, sa) = sessions.create("op", 5);
        let (b, _) = sessions.create("op", 5);
        assert_ne!(a, b);
        assert_eq!(a.len(), 64);
        assert_eq!(sessions.get(&a), Some(sa));
        sessions.remove(&a);
        assert!(sessions.get(&a).is_none());
        sessions.remove_user("op");
        assert!(sessions.get(&b).is_none());
    }

    #[test]
    fn lockout_after_repeated_failures() {
        let limiter = LoginLimiter::default();
        for _ in 0..MAX_FAILURES - 1 {
            limiter.fail("127.0.0.1");
            assert!(limiter.check("127.0.0.1").is_ok());
        }
        limiter.fail("127.0.0.1");
        assert!(limiter.check("127.0.0.1").is_err());
        assert!(limiter.check("other").is_ok());
        limiter.succeed("127.0.0.1");
        assert!(limiter.check("127.0.0.1").is_ok());
    }

    #[test]
    fn constant_time_comparison() {
        assert!(constant_time_eq("abc", "abc"));
        assert!(!constant_time_eq("abc", "abd"));
        assert!(!constant_time_eq("abc", "abcd"));
    }
}
