//! The e-mail sender: lettre's async SMTP transport on tokio with rustls.

use std::time::Duration;

use lettre::message::header::ContentType;
use lettre::message::Mailbox;
use lettre::transport::smtp::authentication::Credentials;
use lettre::{AsyncSmtpTransport, AsyncTransport, Message, Tokio1Executor};

use crate::config::{ConfigError, Security, SmtpSettings};
use crate::delivery::error_chain;
use crate::notice::Notice;
use crate::notifier::NotifierError;

/// Sends one plain-text message per recipient through the configured server.
pub(crate) struct EmailSender {
    transport: AsyncSmtpTransport<Tokio1Executor>,
    from: Mailbox,
    timeout: Duration,
}

impl EmailSender {
    /// The transport for `settings` (validated); reads `password_env`.
    pub(crate) fn new(settings: &SmtpSettings) -> Result<EmailSender, NotifierError> {
        let from = settings
            .from
            .parse::<Mailbox>()
            .map_err(|error| ConfigError::BadAddress {
                field: "notify.smtp.from".into(),
                address: settings.from.clone(),
                reason: error.to_string(),
            })?;
        let builder = match settings.security {
            Security::None => {
                AsyncSmtpTransport::<Tokio1Executor>::builder_dangerous(settings.host.as_str())
            }
            Security::Starttls => {
                AsyncSmtpTransport::<Tokio1Executor>::starttls_relay(&settings.host)
                    .map_err(|error| NotifierError::Smtp(error_chain(&error)))?
            }
            Security::Tls => AsyncSmtpTransport::<Tokio1Executor>::relay(&settings.host)
                .map_err(|error| NotifierError::Smtp(error_chain(&error)))?,
        };
        let mut builder = builder
            .port(settings.port())
            .timeout(Some(settings.timeout()));
        if let Some(user) = &settings.user {
            let password = settings.password()?.unwrap_or_default();
            builder = builder.credentials(Credentials::new(user.clone(), password));
        }
        Ok(EmailSender {
            transport: builder.build(),
            from,
            timeout: settings.timeout(),
        })
    }

    /// Sends `notice` to `to`: `Ok` with the server's reply (`250 ...`), or `Err` with
    /// what went wrong. Bounded by the time-out.
    pub(crate) async fn send(&self, notice: &Notice, to: &str) -> Result<String, String> {
        let to = to
            .parse::<Mailbox>()
            .map_err(|error| format!("bad address: {error}"))?;
        let message = Message::builder()
            .from(self.from.clone())
            .to(to)
            .subject(notice.subject())
            .header(ContentType::TEXT_PLAIN)
            .body(notice.body())
            .map_err(|error| format!("cannot build the message: {}", error_chain(&error)))?;
        match tokio::time::timeout(self.timeout, self.transport.send(message)).await {
            Ok(Ok(response)) => {
                let text: Vec<&str> = response.message().collect();
                Ok(format!("{} {}", response.code(), text.join(" ")))
            }
            Ok(Err(error)) => Err(error_chain(&error)),
            Err(_) => Err(format!("timed out after {} s", self.timeout.as_secs())),
        }
    }
}
