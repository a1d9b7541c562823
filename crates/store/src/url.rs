//! Where a station's events go, as written in `station.toml`, on the command line and in
//! the HMI's options: parsed here once, for the project loader (which resolves a relative
//! SQLite path against the project folder) and for opening the store alike.

use std::fmt;
use std::path::{Path, PathBuf};

/// A store address: `sqlite:PATH` (also `sqlite://PATH`), with `?cache_mib=N` the
/// most memory its page caches take; `sqlite::memory:`; or `postgres://...` /
/// `postgresql://...`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum StoreUrl {
    /// A SQLite database file (created when missing).
    SqliteFile {
        /// The file.
        path: PathBuf,
        /// The most MiB the store's page caches take (`?cache_mib=N`, 1..=[`MAX_CACHE_MIB`]);
        /// `None`: 64 MiB for the writer and 2 MiB for each of its two readers. A small
        /// gateway sets a few: the page cache is what a long-running station's memory
        /// grows by until it is full.
        cache_mib: Option<u32>,
    },
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

/// The largest `cache_mib` of a SQLite address.
pub const MAX_CACHE_MIB: u32 = 65_536;

impl StoreUrl {
    /// A SQLite file with the default page caches.
    pub fn sqlite_file(path: impl Into<PathBuf>) -> StoreUrl {
        StoreUrl::SqliteFile {
            path: path.into(),
            cache_mib: None,
        }
    }

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
                path => {
                    let (path, cache_mib) =
                        sqlite_parameters(path).map_err(|reason| StoreUrlError {
                            text: text.to_owned(),
                            reason,
                        })?;
                    Ok(StoreUrl::SqliteFile {
                        path: PathBuf::from(path),
                        cache_mib,
                    })
                }
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
            StoreUrl::SqliteFile { path, cache_mib } if path.is_relative() => {
                StoreUrl::SqliteFile {
                    path: folder.join(path),
                    cache_mib,
                }
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
            StoreUrl::SqliteFile {
                path,
                cache_mib: None,
            } => write!(f, "sqlite:{}", path.display()),
            StoreUrl::SqliteFile {
                path,
                cache_mib: Some(mib),
            } => write!(f, "sqlite:{}?cache_mib={mib}", path.display()),
            StoreUrl::SqliteMemory => f.write_str("sqlite::memory:"),
            StoreUrl::Postgres(url) => f.write_str(url),
        }
    }
}

/// A SQLite path and its parameters (`PATH?cache_mib=N`): the path, and the cache's MiB.
fn sqlite_parameters(text: &str) -> Result<(&str, Option<u32>), String> {
    let Some((path, query)) = text.split_once('?') else {
        return Ok((text, None));
    };
    if path.is_empty() {
        return Err("no database path after sqlite:".to_owned());
    }
    let mut cache_mib = None;
    for pair in query.split('&') {
        match pair.split_once('=') {
            Some(("cache_mib", n)) => {
                cache_mib = Some(
                    n.parse::<u32>()
                        .ok()
                        .filter(|n| (1..=MAX_CACHE_MIB).contains(n))
                        .ok_or_else(|| {
                            format!("cache_mib is 1 to {MAX_CACHE_MIB} (MiB), not {n:?}")
                        })?,
                );
            }
            _ => return Err(format!("{pair:?} is no SQLite parameter (cache_mib=N)")),
        }
    }
    Ok((path, cache_mib))
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
                StoreUrl::sqlite_file("events.sqlite"),
            ),
            ("sqlite:///tmp/x.db", StoreUrl::sqlite_file("/tmp/x.db")),
            (
                "sqlite:x.db?cache_mib=4",
                StoreUrl::SqliteFile {
                    path: "x.db".into(),
                    cache_mib: Some(4),
                },
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
        for bad in [
            "sqlite:x.db?cache_mib=0",
            "sqlite:x.db?cache_mib=65537",
            "sqlite:x.db?cache_mib=a",
            "sqlite:x.db?cache=4",
            "sqlite:?cache_mib=4",
        ] {
            let error = StoreUrl::parse(bad).unwrap_err();
            assert!(
                error.reason.contains("cache") || error.reason.contains("path"),
                "{error}"
            );
        }
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
            StoreUrl::parse("sqlite:e.db?cache_mib=2")
                .unwrap()
                .resolved_in(folder),
            StoreUrl::SqliteFile {
                path: "/p/e.db".into(),
                cache_mib: Some(2),
            }
        );
        assert_eq!(
            StoreUrl::parse("sqlite:/abs.db")
                .unwrap()
                .resolved_in(folder),
            StoreUrl::sqlite_file("/abs.db")
        );
        assert_eq!(
            StoreUrl::SqliteMemory.resolved_in(folder),
            StoreUrl::SqliteMemory
        );
    }
}
