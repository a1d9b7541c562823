//! The configuration: SMTP server, channels, rules; deserialized from the station
//! project's `[node.notify]` table and validated into typed errors naming the field.
//!
//! ```toml
//! [node.notify.smtp]
//! host = "smtp.example.cz"
//! port = 587
//! security = "starttls"          # none | starttls | tls
//! user = "stanice"
//! password_env = "STANICE_SMTP_PASSWORD"   # or: password = "..."
//! from = "Stanice <stanice@example.cz>"
//! timeout_s = 20
//!
//! [node.notify.channel.technicians]
//! kind = "email"
//! to = ["novak@example.cz", "Jana Dvořáková <dvorakova@example.cz>"]
//!
//! [node.notify.channel.tickets]
//! kind = "webhook"
//! url = "https://tickets.example.cz/api/hook"
//! headers = { Authorization = "Bearer 0123" }
//! timeout_s = 10
//!
//! [[node.notify.rule]]
//! name = "lift-faults"
//! sources = ["L*"]                 # default: every source
//! classes = ["safety-circuit", "door"]   # default: every class
//! channels = ["technicians", "tickets"]
//! quiet_period_s = 900             # default 600
//! rate_limit = { max = 10, per_s = 3600 }  # default: none
//! ```

use std::collections::{BTreeMap, BTreeSet};
use std::time::Duration;

use lettre::message::Mailbox;
use reqwest::header::{HeaderName, HeaderValue};
use reqwest::Url;
use serde::{Deserialize, Serialize};

use crate::pattern::Pattern;

/// The default SMTP and webhook time-out, seconds.
pub const DEFAULT_TIMEOUT_S: u64 = 20;
/// The default quiet period of a rule, seconds.
pub const DEFAULT_QUIET_PERIOD_S: u64 = 600;

/// Everything the notifier needs: the `[node.notify]` table.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[non_exhaustive]
pub struct NotifyConfig {
    /// The SMTP server; required when any channel is an e-mail channel.
    #[serde(default)]
    pub smtp: Option<SmtpSettings>,
    /// The channels by name (`[node.notify.channel.NAME]`).
    #[serde(default, rename = "channel")]
    pub channels: BTreeMap<String, ChannelConfig>,
    /// The rules (`[[node.notify.rule]]`), each evaluated for every notice.
    #[serde(default, rename = "rule")]
    pub rules: Vec<RuleConfig>,
}

/// How the SMTP connection is secured.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Security {
    /// Plain text (a relay on the local network or loopback only).
    None,
    /// Plain connection upgraded by STARTTLS, which is required (port 587).
    #[default]
    Starttls,
    /// TLS from the first octet (port 465).
    Tls,
}

impl Security {
    /// The usual port of the mode: 25, 587 or 465.
    pub fn default_port(self) -> u16 {
        match self {
            Security::None => 25,
            Security::Starttls => 587,
            Security::Tls => 465,
        }
    }
}

/// The SMTP server (`[node.notify.smtp]`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[non_exhaustive]
pub struct SmtpSettings {
    /// Host name (also the name its TLS certificate must carry).
    pub host: String,
    /// Port; by default that of `security` (25, 587, 465).
    #[serde(default)]
    pub port: Option<u16>,
    /// Transport security; STARTTLS by default.
    #[serde(default)]
    pub security: Security,
    /// Login user, when the server wants authentication.
    #[serde(default)]
    pub user: Option<String>,
    /// The password in the file (prefer `password_env`).
    #[serde(default)]
    pub password: Option<String>,
    /// The name of an environment variable holding the password.
    #[serde(default)]
    pub password_env: Option<String>,
    /// The sender, `"Name <address>"` or `"address"`.
    pub from: String,
    /// Time-out of one delivery (connect, dialogue), seconds.
    #[serde(default = "default_timeout_s")]
    pub timeout_s: u64,
}

impl SmtpSettings {
    /// Settings with the defaults: STARTTLS on its port, no login, 20 s time-out.
    pub fn new(host: impl Into<String>, from: impl Into<String>) -> SmtpSettings {
        SmtpSettings {
            host: host.into(),
            port: None,
            security: Security::default(),
            user: None,
            password: None,
            password_env: None,
            from: from.into(),
            timeout_s: DEFAULT_TIMEOUT_S,
        }
    }

    /// The port in effect.
    pub fn port(&self) -> u16 {
        self.port.unwrap_or_else(|| self.security.default_port())
    }

    /// The time-out in effect.
    pub fn timeout(&self) -> Duration {
        Duration::from_secs(self.timeout_s)
    }

    /// The password: from the file, or read from the environment variable `password_env`.
    pub fn password(&self) -> Result<Option<String>, ConfigError> {
        if let Some(password) = &self.password {
            return Ok(Some(password.clone()));
        }
        match &self.password_env {
            None => Ok(None),
            Some(var) => std::env::var(var)
                .map(Some)
                .map_err(|_| ConfigError::PasswordEnvMissing { var: var.clone() }),
        }
    }
}

fn default_timeout_s() -> u64 {
    DEFAULT_TIMEOUT_S
}

fn default_quiet_period_s() -> u64 {
    DEFAULT_QUIET_PERIOD_S
}

/// A channel: where a notification goes (`[node.notify.channel.NAME]`, `kind` selects).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
#[non_exhaustive]
pub enum ChannelConfig {
    /// E-mail through the `[node.notify.smtp]` server, one message per recipient.
    Email {
        /// Recipients, `"Name <address>"` or `"address"`; at least one.
        to: Vec<String>,
    },
    /// An HTTP POST of the notice as JSON.
    Webhook {
        /// `http://` or `https://` URL.
        url: String,
        /// Extra request headers (e.g. `Authorization`).
        #[serde(default)]
        headers: BTreeMap<String, String>,
        /// Time-out of one request, seconds.
        #[serde(default = "default_timeout_s")]
        timeout_s: u64,
    },
}

impl ChannelConfig {
    /// The kind, as the delivery record names it.
    pub fn kind(&self) -> ChannelKind {
        match self {
            ChannelConfig::Email { .. } => ChannelKind::Email,
            ChannelConfig::Webhook { .. } => ChannelKind::Webhook,
        }
    }

    /// The recipients of one notice: each e-mail address, or the webhook's URL.
    pub fn recipients(&self) -> Vec<String> {
        match self {
            ChannelConfig::Email { to } => to.clone(),
            ChannelConfig::Webhook { url, .. } => vec![url.clone()],
        }
    }
}

/// The kind of a channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ChannelKind {
    /// SMTP e-mail.
    Email,
    /// HTTP POST.
    Webhook,
}

impl ChannelKind {
    /// `"email"` or `"webhook"`.
    pub fn as_str(self) -> &'static str {
        match self {
            ChannelKind::Email => "email",
            ChannelKind::Webhook => "webhook",
        }
    }
}

impl std::fmt::Display for ChannelKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// At most `max` notifications of a rule within any `per_s` seconds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RateLimit {
    /// Notifications allowed per window (at least 1).
    pub max: u32,
    /// The window, seconds (at least 1).
    pub per_s: u64,
}

/// A rule (`[[node.notify.rule]]`): which notices go to which channels, how often.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[non_exhaustive]
pub struct RuleConfig {
    /// Unique name; delivery records carry it.
    pub name: String,
    /// Glob patterns of sources (`"L*"`); empty or absent: every source.
    #[serde(default)]
    pub sources: Vec<Pattern>,
    /// Glob patterns of classes; empty or absent: every class.
    #[serde(default)]
    pub classes: Vec<Pattern>,
    /// The channels' names; at least one.
    pub channels: Vec<String>,
    /// After a notification for (rule, source, class), further notices of that key are
    /// suppressed for this many seconds; 0: none. 600 by default.
    #[serde(default = "default_quiet_period_s")]
    pub quiet_period_s: u64,
    /// The rule's rate limit; none by default.
    #[serde(default)]
    pub rate_limit: Option<RateLimit>,
}

impl RuleConfig {
    /// A rule for every source and class with the default quiet period, no rate limit.
    pub fn new(name: impl Into<String>, channels: Vec<String>) -> RuleConfig {
        RuleConfig {
            name: name.into(),
            sources: Vec::new(),
            classes: Vec::new(),
            channels,
            quiet_period_s: DEFAULT_QUIET_PERIOD_S,
            rate_limit: None,
        }
    }
}

/// A configuration error; its text names the field.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ConfigError {
    /// A rule names a channel that is not configured.
    #[error("notify.rule `{rule}`: channels: unknown channel `{channel}`")]
    UnknownChannel {
        /// The rule.
        rule: String,
        /// The channel it names.
        channel: String,
    },
    /// A rule lists no channel.
    #[error("notify.rule `{rule}`: channels: empty")]
    NoChannels {
        /// The rule.
        rule: String,
    },
    /// Two rules share a name.
    #[error("notify.rule `{rule}`: name: used twice")]
    DuplicateRule {
        /// The name.
        rule: String,
    },
    /// A rule has an empty name.
    #[error("notify.rule #{index}: name: empty")]
    EmptyRuleName {
        /// The rule's position, from 1.
        index: usize,
    },
    /// A rate limit of zero notifications or a zero window.
    #[error("notify.rule `{rule}`: rate_limit: max and per_s must be at least 1")]
    BadRateLimit {
        /// The rule.
        rule: String,
    },
    /// An e-mail channel without recipients.
    #[error("notify.channel.{channel}: to: empty recipient list")]
    EmptyRecipients {
        /// The channel.
        channel: String,
    },
    /// An address that is no mailbox.
    #[error("{field}: bad e-mail address `{address}`: {reason}")]
    BadAddress {
        /// `notify.smtp.from` or `notify.channel.NAME.to`.
        field: String,
        /// The text given.
        address: String,
        /// Why it is refused.
        reason: String,
    },
    /// An e-mail channel but no `[node.notify.smtp]`.
    #[error("notify.channel.{channel}: an e-mail channel needs notify.smtp")]
    NoSmtp {
        /// The channel.
        channel: String,
    },
    /// A webhook URL that does not parse or is not http(s).
    #[error("notify.channel.{channel}: url: bad URL `{url}`: {reason}")]
    BadUrl {
        /// The channel.
        channel: String,
        /// The text given.
        url: String,
        /// Why it is refused.
        reason: String,
    },
    /// A header name or value HTTP does not allow.
    #[error("notify.channel.{channel}: headers: bad header `{header}`")]
    BadHeader {
        /// The channel.
        channel: String,
        /// The header's name.
        header: String,
    },
    /// A zero time-out.
    #[error("{field}: timeout_s must be at least 1")]
    ZeroTimeout {
        /// `notify.smtp.timeout_s` or `notify.channel.NAME.timeout_s`.
        field: String,
    },
    /// An empty SMTP host.
    #[error("notify.smtp.host: empty")]
    EmptyHost,
    /// Both `password` and `password_env`.
    #[error("notify.smtp: password and password_env are exclusive")]
    PasswordTwice,
    /// A password without a user.
    #[error("notify.smtp.user: missing (a password is given)")]
    PasswordWithoutUser,
    /// `password_env` names a variable that is not set (or not UTF-8).
    #[error("notify.smtp.password_env: environment variable `{var}` is not set")]
    PasswordEnvMissing {
        /// The variable's name.
        var: String,
    },
}

impl NotifyConfig {
    /// A configuration from its parts.
    pub fn new(
        smtp: Option<SmtpSettings>,
        channels: BTreeMap<String, ChannelConfig>,
        rules: Vec<RuleConfig>,
    ) -> NotifyConfig {
        NotifyConfig {
            smtp,
            channels,
            rules,
        }
    }

    /// Checks everything that can be checked without the network or the environment;
    /// all errors found, in file order (SMTP, channels, rules).
    pub fn validate(&self) -> Result<(), Vec<ConfigError>> {
        let mut errors = Vec::new();
        if let Some(smtp) = &self.smtp {
            validate_smtp(smtp, &mut errors);
        }
        for (name, channel) in &self.channels {
            validate_channel(name, channel, self.smtp.is_some(), &mut errors);
        }
        let mut names = BTreeSet::new();
        for (index, rule) in self.rules.iter().enumerate() {
            if rule.name.is_empty() {
                errors.push(ConfigError::EmptyRuleName { index: index + 1 });
            } else if !names.insert(rule.name.as_str()) {
                errors.push(ConfigError::DuplicateRule {
                    rule: rule.name.clone(),
                });
            }
            if rule.channels.is_empty() {
                errors.push(ConfigError::NoChannels {
                    rule: rule.name.clone(),
                });
            }
            for channel in &rule.channels {
                if !self.channels.contains_key(channel) {
                    errors.push(ConfigError::UnknownChannel {
                        rule: rule.name.clone(),
                        channel: channel.clone(),
                    });
                }
            }
            if let Some(limit) = rule.rate_limit {
                if limit.max == 0 || limit.per_s == 0 {
                    errors.push(ConfigError::BadRateLimit {
                        rule: rule.name.clone(),
                    });
                }
            }
        }
        if errors.is_empty() {
            Ok(())
        } else {
            Err(errors)
        }
    }
}

fn validate_smtp(smtp: &SmtpSettings, errors: &mut Vec<ConfigError>) {
    if smtp.host.trim().is_empty() {
        errors.push(ConfigError::EmptyHost);
    }
    if let Err(error) = smtp.from.parse::<Mailbox>() {
        errors.push(ConfigError::BadAddress {
            field: "notify.smtp.from".into(),
            address: smtp.from.clone(),
            reason: error.to_string(),
        });
    }
    if smtp.password.is_some() && smtp.password_env.is_some() {
        errors.push(ConfigError::PasswordTwice);
    }
    if (smtp.password.is_some() || smtp.password_env.is_some()) && smtp.user.is_none() {
        errors.push(ConfigError::PasswordWithoutUser);
    }
    if smtp.timeout_s == 0 {
        errors.push(ConfigError::ZeroTimeout {
            field: "notify.smtp.timeout_s".into(),
        });
    }
}

fn validate_channel(
    name: &str,
    channel: &ChannelConfig,
    have_smtp: bool,
    errors: &mut Vec<ConfigError>,
) {
    match channel {
        ChannelConfig::Email { to } => {
            if !have_smtp {
                errors.push(ConfigError::NoSmtp {
                    channel: name.into(),
                });
            }
            if to.is_empty() {
                errors.push(ConfigError::EmptyRecipients {
                    channel: name.into(),
                });
            }
            for address in to {
                if let Err(error) = address.parse::<Mailbox>() {
                    errors.push(ConfigError::BadAddress {
                        field: format!("notify.channel.{name}.to"),
                        address: address.clone(),
                        reason: error.to_string(),
                    });
                }
            }
        }
        ChannelConfig::Webhook {
            url,
            headers,
            timeout_s,
        } => {
            match Url::parse(url) {
                Ok(parsed) if matches!(parsed.scheme(), "http" | "https") => {}
                Ok(parsed) => errors.push(ConfigError::BadUrl {
                    channel: name.into(),
                    url: url.clone(),
                    reason: format!("scheme `{}` is not http or https", parsed.scheme()),
                }),
                Err(error) => errors.push(ConfigError::BadUrl {
                    channel: name.into(),
                    url: url.clone(),
                    reason: error.to_string(),
                }),
            }
            for (header, value) in headers {
                if HeaderName::from_bytes(header.as_bytes()).is_err()
                    || HeaderValue::from_str(value).is_err()
                {
                    errors.push(ConfigError::BadHeader {
                        channel: name.into(),
                        header: header.clone(),
                    });
                }
            }
            if *timeout_s == 0 {
                errors.push(ConfigError::ZeroTimeout {
                    field: format!("notify.channel.{name}.timeout_s"),
                });
            }
        }
    }
}
