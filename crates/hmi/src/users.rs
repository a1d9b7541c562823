//! The users file: names, permission levels 0..=9 and argon2id password hashes.
//!
//! `users.toml` holds `[users.NAME] level = 5, hash = "$argon2id$..."` and optionally
//! `start = "lifts"`, the screen the browser opens after login (lift spec 10: a start
//! window per account; a mimic's screen id or a page: `lifts`, `faults`, `mobile`,
//! `events`, ...). It is written
//! atomically (temporary file, then rename). Verification always runs one argon2
//! computation, also for unknown names, so timing does not tell which names exist.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use argon2::password_hash::{PasswordHash, PasswordHasher, PasswordVerifier, SaltString};
use argon2::Argon2;
use serde::{Deserialize, Serialize};

use crate::HmiError;

/// The highest permission level.
pub const MAX_LEVEL: u8 = 9;

/// One user.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UserRecord {
    /// Permission level 0..=9 (0: read-only).
    pub level: u8,
    /// PHC string of the argon2id hash.
    pub hash: String,
    /// The screen the browser opens after login (a screen id or a page name); `None`:
    /// the first screen.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start: Option<String>,
}

#[derive(Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct UsersFile {
    #[serde(default)]
    users: BTreeMap<String, UserRecord>,
}

/// The users, as loaded from their file.
#[derive(Debug, Clone)]
pub struct Users {
    path: PathBuf,
    users: BTreeMap<String, UserRecord>,
    /// Hash verified for unknown names, so that they cost as much as known ones.
    decoy: String,
}

fn hash(password: &str) -> Result<String, HmiError> {
    let mut salt_bytes = [0u8; 16];
    rand::fill(&mut salt_bytes);
    let salt =
        SaltString::encode_b64(&salt_bytes).map_err(|e| HmiError::Users(format!("salt: {e}")))?;
    Argon2::default()
        .hash_password(password.as_bytes(), &salt)
        .map(|h| h.to_string())
        .map_err(|e| HmiError::Users(format!("hashing: {e}")))
}

/// Whether a name can be a user's: 1-64 ASCII letters, digits, '.', '-', '_'.
pub fn valid_name(name: &str) -> bool {
    !name.is_empty()
        && name.len() <= 64
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '-' | '_'))
}

/// Whether a start screen can be one: 1-64 ASCII letters, digits, '-', '_', '/'
/// (`lifts`, `rh2`, `lift/L1`).
pub fn valid_start(start: &str) -> bool {
    !start.is_empty()
        && start.len() <= 64
        && start
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '/'))
}

impl Users {
    /// Loads `path`; a missing file is an empty user list.
    pub fn load(path: &Path) -> Result<Users, HmiError> {
        let users = match std::fs::read_to_string(path) {
            Ok(text) => {
                let file: UsersFile = toml::from_str(&text)
                    .map_err(|e| HmiError::Users(format!("{}: {}", path.display(), e.message())))?;
                for (name, user) in &file.users {
                    if !valid_name(name)
                        || user.level > MAX_LEVEL
                        || user.start.as_deref().is_some_and(|s| !valid_start(s))
                    {
                        return Err(HmiError::Users(format!(
                            "{}: user `{name}`: bad name, level or start screen",
                            path.display()
                        )));
                    }
                }
                file.users
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => BTreeMap::new(),
            Err(e) => return Err(HmiError::Users(format!("{}: {e}", path.display()))),
        };
        Ok(Users {
            path: path.to_path_buf(),
            users,
            decoy: hash("not a password of anybody")?,
        })
    }

    /// The names and levels.
    pub fn list(&self) -> impl Iterator<Item = (&str, u8)> {
        self.users.iter().map(|(n, u)| (n.as_str(), u.level))
    }

    /// The names.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.users.keys().map(String::as_str)
    }

    /// A user's record.
    pub fn record(&self, name: &str) -> Option<&UserRecord> {
        self.users.get(name)
    }

    /// A user's start screen, if the users file gives one.
    pub fn start(&self, name: &str) -> Option<&str> {
        self.users.get(name).and_then(|u| u.start.as_deref())
    }

    /// Sets (or, with `None`, clears) a user's start screen.
    pub fn set_start(&mut self, name: &str, start: Option<&str>) -> Result<(), HmiError> {
        if let Some(start) = start {
            if !valid_start(start) {
                return Err(HmiError::Users(format!(
                    "`{start}`: a start screen is 1-64 letters, digits, '-', '_', '/'"
                )));
            }
        }
        let user = self
            .users
            .get_mut(name)
            .ok_or_else(|| HmiError::Users(format!("no user `{name}`")))?;
        user.start = start.map(str::to_owned);
        self.save()
    }

    /// The level of a user whose password is right; `None` otherwise.
    pub fn verify(&self, name: &str, password: &str) -> Option<u8> {
        let (record_hash, level) = match self.users.get(name) {
            Some(user) => (user.hash.as_str(), Some(user.level)),
            None => (self.decoy.as_str(), None),
        };
        let parsed = PasswordHash::new(record_hash).ok()?;
        let ok = Argon2::default()
            .verify_password(password.as_bytes(), &parsed)
            .is_ok();
        if ok {
            level
        } else {
            None
        }
    }

    /// Adds a user (or fails if the name exists).
    pub fn add(&mut self, name: &str, level: u8, password: &str) -> Result<(), HmiError> {
        if !valid_name(name) {
            return Err(HmiError::Users(format!(
                "`{name}`: a user name is 1-64 letters, digits, '.', '-', '_'"
            )));
        }
        if level > MAX_LEVEL {
            return Err(HmiError::Users(format!(
                "level {level} is above {MAX_LEVEL}"
            )));
        }
        if password.chars().count() < 8 {
            return Err(HmiError::Users(
                "a password has at least 8 characters".into(),
            ));
        }
        if self.users.contains_key(name) {
            return Err(HmiError::Users(format!("user `{name}` exists")));
        }
        self.users.insert(
            name.to_owned(),
            UserRecord {
                level,
                hash: hash(password)?,
                start: None,
            },
        );
        self.save()
    }

    /// Removes a user.
    pub fn remove(&mut self, name: &str) -> Result<(), HmiError> {
        if self.users.remove(name).is_none() {
            return Err(HmiError::Users(format!("no user `{name}`")));
        }
        self.save()
    }

    /// Sets a user's password (and, optionally, level).
    pub fn passwd(
        &mut self,
        name: &str,
        password: &str,
        level: Option<u8>,
    ) -> Result<(), HmiError> {
        if password.chars().count() < 8 {
            return Err(HmiError::Users(
                "a password has at least 8 characters".into(),
            ));
        }
        let new_hash = hash(password)?;
        let user = self
            .users
            .get_mut(name)
            .ok_or_else(|| HmiError::Users(format!("no user `{name}`")))?;
        user.hash = new_hash;
        if let Some(level) = level {
            if level > MAX_LEVEL {
                return Err(HmiError::Users(format!(
                    "level {level} is above {MAX_LEVEL}"
                )));
            }
            user.level = level;
        }
        self.save()
    }

    fn save(&self) -> Result<(), HmiError> {
        let text = toml::to_string_pretty(&UsersFile {
            users: self.users.clone(),
        })
        .map_err(|e| HmiError::Users(e.to_string()))?;
        let temporary = self.path.with_extension("toml.tmp");
        let io = |e: std::io::Error| HmiError::Users(format!("{}: {e}", self.path.display()));
        std::fs::write(&temporary, text).map_err(io)?;
        std::fs::rename(&temporary, &self.path).map_err(io)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn add_verify_passwd_remove_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("users.toml");
        let mut users = Users::load(&path).unwrap();
        users.add("operator", 5, "correct horse").unwrap();
        assert!(users.add("operator", 5, "another one").is_err());
        assert!(users.add("bad name", 5, "long enough").is_err());
        assert!(users.add("short", 5, "short").is_err());
        assert!(users.add("high", 10, "long enough").is_err());
        let reloaded = Users::load(&path).unwrap();
        assert_eq!(reloaded.verify("operator", "correct horse"), Some(5));
        assert_eq!(reloaded.verify("operator", "wrong"), None);
        assert_eq!(reloaded.verify("nobody", "correct horse"), None);
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.contains("$argon2id$") && !text.contains("correct horse"));
        users.passwd("operator", "battery staple", Some(7)).unwrap();
        let reloaded = Users::load(&path).unwrap();
        assert_eq!(reloaded.verify("operator", "battery staple"), Some(7));
        users.remove("operator").unwrap();
        assert_eq!(Users::load(&path).unwrap().list().count(), 0);
    }

    #[test]
    fn start_screen_is_optional_and_kept() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("users.toml");
        // A users file of before the start screen still loads.
        let mut users = Users::load(&path).unwrap();
        users.add("servis", 9, "long enough").unwrap();
        assert!(!std::fs::read_to_string(&path).unwrap().contains("start"));
        assert_eq!(Users::load(&path).unwrap().start("servis"), None);
        users.set_start("servis", Some("lifts")).unwrap();
        assert!(users.set_start("servis", Some("<script>")).is_err());
        assert!(users.set_start("nobody", Some("lifts")).is_err());
        let reloaded = Users::load(&path).unwrap();
        assert_eq!(reloaded.start("servis"), Some("lifts"));
        assert_eq!(reloaded.verify("servis", "long enough"), Some(9));
        std::fs::write(
            &path,
            "[users.x]\nlevel = 1\nhash = \"h\"\nstart = \"a b\"\n",
        )
        .unwrap();
        assert!(Users::load(&path).is_err());
    }
}
