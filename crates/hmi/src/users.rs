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
    /// A locked user cannot log in (the record and its hash stay, for unlocking).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub locked: bool,
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
        // A locked user costs one verification like anybody, and gets no level.
        let (record_hash, level) = match self.users.get(name) {
            Some(user) => (user.hash.as_str(), (!user.locked).then_some(user.level)),
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
                locked: false,
            },
        );
        self.save()
    }

    /// Removes a user (the command line may remove anybody; the HMI's administration
    /// asks [`Users::keep_an_administrator`] first).
    pub fn remove(&mut self, name: &str) -> Result<(), HmiError> {
        if self.users.remove(name).is_none() {
            return Err(HmiError::Users(format!("no user `{name}`")));
        }
        self.save()
    }

    /// Sets a user's level; never demotes the last unlocked level-9 user.
    pub fn set_level(&mut self, name: &str, level: u8) -> Result<(), HmiError> {
        if level > MAX_LEVEL {
            return Err(HmiError::Users(format!(
                "level {level} is above {MAX_LEVEL}"
            )));
        }
        if !self.users.contains_key(name) {
            return Err(HmiError::Users(format!("no user `{name}`")));
        }
        if level < MAX_LEVEL {
            self.keep_an_administrator(name, "demoted")?;
        }
        if let Some(user) = self.users.get_mut(name) {
            user.level = level;
        }
        self.save()
    }

    /// Locks or unlocks a user; never locks the last unlocked level-9 user.
    pub fn set_locked(&mut self, name: &str, locked: bool) -> Result<(), HmiError> {
        if !self.users.contains_key(name) {
            return Err(HmiError::Users(format!("no user `{name}`")));
        }
        if locked {
            self.keep_an_administrator(name, "locked")?;
        }
        if let Some(user) = self.users.get_mut(name) {
            user.locked = locked;
        }
        self.save()
    }

    /// Refuses a change that would leave nobody unlocked at level 9 to administer the
    /// users (`name` is the user about to be `what`).
    pub fn keep_an_administrator(&self, name: &str, what: &str) -> Result<(), HmiError> {
        let others = self
            .users
            .iter()
            .filter(|(other, user)| {
                other.as_str() != name && user.level == MAX_LEVEL && !user.locked
            })
            .count();
        let is_administrator = self
            .users
            .get(name)
            .is_some_and(|user| user.level == MAX_LEVEL && !user.locked);
        if is_administrator && others == 0 {
            return Err(HmiError::Users(format!(
                "`{name}` is the last unlocked level-{MAX_LEVEL} user and cannot be {what}"
            )));
        }
        Ok(())
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

    #[test]
    fn locking_and_levels_keep_an_administrator() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("users.toml");
        let mut users = Users::load(&path).unwrap();
        users.add("admin", 9, "long enough").unwrap();
        users.add("novak", 3, "long enough").unwrap();
        // The only administrator: never demoted or locked.
        assert!(users.set_level("admin", 8).is_err());
        assert!(users.set_locked("admin", true).is_err());
        assert!(users.keep_an_administrator("admin", "removed").is_err());
        assert!(users.keep_an_administrator("novak", "removed").is_ok());
        assert!(users.set_level("novak", 10).is_err());
        users.set_level("novak", 9).unwrap();
        // Two now: either may go.
        users.set_locked("admin", true).unwrap();
        assert_eq!(users.verify("admin", "long enough"), None, "locked");
        assert!(
            users.set_locked("novak", true).is_err(),
            "novak is the last unlocked one"
        );
        let reloaded = Users::load(&path).unwrap();
        assert!(reloaded.record("admin").unwrap().locked);
        assert_eq!(reloaded.verify("novak", "long enough"), Some(9));
        users.set_locked("admin", false).unwrap();
        assert_eq!(users.verify("admin", "long enough"), Some(9));
        assert!(!std::fs::read_to_string(&path).unwrap().contains("locked"));
    }
}
