//! Where a station's events go, as written in `station.toml`, on the command line and in
//! the HMI's options: parsed here once, for the project loader (which resolves a relative
//! SQLite path against the project folder) and for opening the store alike.

use std::fmt;
use std::path::{Path, PathBuf};

/// A store address: `sqlite:PATH` (also `sqlite://PATH`), `sqlite::memory:`, or
/// `postgres://...` / `postgresql://...`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum StoreUrl {
    /// A SQLite database file (created when missing).
    SqliteFile(PathBuf),
    /// A private in-memory SQLite database.
    SqliteMemory,
    /// A PostgreSQL database, with the URL as given (its password included: see
    /// [`StoreUrl::redacted`] before showing it).
    Postgres(String),
}

/// Why a text is no store address.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("`{text}` is not sqlite:PATH, sqlite::memory: or postgres://...: {reason}")]
pub struct StoreUrlError {
    /// The text, its password hidden.
    pub text: String,
    /// What is wrong.
    pub reason: String,
}

impl StoreUrl {
    /// Parses a store address.
    pub fn parse(text: &str) -> Result<StoreUrl, StoreUrlError> {
        let text = text.trim();
        if let Some(rest) = text.strip_prefix("sqlite:") {
            let path = rest.strip_prefix("//").unwrap_or(rest);
            return match path {
                "" => Err(StoreUrlError {
                    text: text.to_owned(),
                    reason: "no database path after sqlite:".to_owned(),
                }),
                ":memory:" => Ok(StoreUrl::SqliteMemory),
                path => Ok(StoreUrl::SqliteFile(PathBuf::from(path))),
            };
        }
        if text.starts_with("postgres://") || text.starts_with("postgresql://") {
            return Ok(StoreUrl::Postgres(text.to_owned()));
        }
        let reason = match text.split_once(':') {
            Some((scheme, _)) if !scheme.is_empty() => format!("unknown scheme {scheme:?}"),
            _ => "no scheme".to_owned(),
        };
        Err(StoreUrlError {
            text: redact(text),
            reason,
        })
    }

    /// The same address with a relative SQLite path taken from `folder`.
    pub fn resolved_in(self, folder: &Path) -> StoreUrl {
        match self {
            StoreUrl::SqliteFile(path) if path.is_relative() => {
                StoreUrl::SqliteFile(folder.join(path))
            }
            other => other,
        }
    }

    /// The address as text, with a PostgreSQL password replaced by `***`.
    pub fn redacted(&self) -> String {
        match self {
            StoreUrl::Postgres(url) => redact(url),
            other => other.to_string(),
        }
    }
}

/// The canonical text (`sqlite:PATH`, `sqlite::memory:`, the PostgreSQL URL as given),
/// which [`StoreUrl::parse`] reads back.
impl fmt::Display for StoreUrl {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StoreUrl::SqliteFile(path) => write!(f, "sqlite:{}", path.display()),
            StoreUrl::SqliteMemory => f.write_str("sqlite::memory:"),
            StoreUrl::Postgres(url) => f.write_str(url),
        }
    }
}

/// The URL with the password part of `user:password@` replaced by `***`.
pub(crate) fn redact(url: &str) -> String {
    let Some((scheme, rest)) = url.split_once("://") else {
        return url.to_owned();
    };
    let (authority, tail) = match rest.find('/') {
        Some(i) => rest.split_at(i),
        None => (rest, ""),
    };
    match authority.rsplit_once('@') {
        Some((userinfo, host)) => match userinfo.split_once(':') {
            Some((user, _)) => format!("{scheme}://{user}:***@{host}{tail}"),
            None => url.to_owned(),
        },
        None => url.to_owned(),
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_form_and_round_trips() {
        for (text, url) in [
            (
                "sqlite:events.sqlite",
                StoreUrl::SqliteFile("events.sqlite".into()),
            ),
            (
                "sqlite:///tmp/x.db",
                StoreUrl::SqliteFile("/tmp/x.db".into()),
            ),
            ("sqlite::memory:", StoreUrl::SqliteMemory),
            (
                "postgres://u:p@h/db",
                StoreUrl::Postgres("postgres://u:p@h/db".into()),
            ),
        ] {
            let parsed = StoreUrl::parse(text).unwrap();
            assert_eq!(parsed, url);
            assert_eq!(StoreUrl::parse(&parsed.to_string()).unwrap(), url);
        }
        assert!(StoreUrl::parse("sqlite:").is_err());
        let error = StoreUrl::parse("mysql://u:secret@h/db").unwrap_err();
        assert!(!error.to_string().contains("secret"), "{error}");
        assert_eq!(
            StoreUrl::Postgres("postgres://u:secret@h/db".into()).redacted(),
            "postgres://u:***@h/db"
        );
    }

    #[test]
    fn relative_sqlite_paths_resolve_in_the_folder() {
        let folder = Path::new("/p");
        assert_eq!(
            StoreUrl::parse("sqlite:e.db").unwrap().resolved_in(folder),
            StoreUrl::SqliteFile("/p/e.db".into())
        );
        assert_eq!(
            StoreUrl::parse("sqlite:/abs.db")
                .unwrap()
                .resolved_in(folder),
            StoreUrl::SqliteFile("/abs.db".into())
        );
        assert_eq!(
            StoreUrl::SqliteMemory.resolved_in(folder),
            StoreUrl::SqliteMemory
        );
    }
}
