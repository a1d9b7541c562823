//! The webhook sender: an HTTP POST of the notice as JSON (reqwest with rustls).

use std::time::Duration;

use reqwest::header::{HeaderMap, HeaderName, HeaderValue};
use reqwest::{Client, Url};
use serde::Serialize;

use crate::config::ConfigError;
use crate::delivery::error_chain;
use crate::notice::Notice;

/// The JSON body a webhook receives.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct WebhookBody<'a> {
    /// The notice's source.
    pub source: &'a str,
    /// The notice's class.
    pub class: &'a str,
    /// The device's code.
    pub code: Option<u32>,
    /// The title.
    pub title: &'a str,
    /// The text.
    pub text: &'a str,
    /// When it happened, RFC 3339.
    pub time: String,
    /// Link to the web HMI.
    pub link: Option<&'a str>,
    /// The rule that sent it.
    pub rule: &'a str,
}

impl<'a> WebhookBody<'a> {
    /// The body for `notice` sent by `rule`.
    pub fn new(notice: &'a Notice, rule: &'a str) -> WebhookBody<'a> {
        WebhookBody {
            source: &notice.source,
            class: &notice.class,
            code: notice.code,
            title: &notice.title,
            text: &notice.text,
            time: notice.time_rfc3339(),
            link: notice.link.as_deref(),
            rule,
        }
    }
}

/// One webhook channel.
pub(crate) struct WebhookSender {
    client: Client,
    url: Url,
    headers: HeaderMap,
    timeout: Duration,
}

impl WebhookSender {
    /// The sender of channel `name` (validated); `client` is shared by all channels.
    pub(crate) fn new(
        name: &str,
        client: Client,
        url: &str,
        headers: &std::collections::BTreeMap<String, String>,
        timeout_s: u64,
    ) -> Result<WebhookSender, ConfigError> {
        let parsed = Url::parse(url).map_err(|error| ConfigError::BadUrl {
            channel: name.into(),
            url: url.into(),
            reason: error.to_string(),
        })?;
        let mut map = HeaderMap::new();
        for (header, value) in headers {
            let bad = || ConfigError::BadHeader {
                channel: name.into(),
                header: header.clone(),
            };
            let header_name = HeaderName::from_bytes(header.as_bytes()).map_err(|_| bad())?;
            let mut header_value = HeaderValue::from_str(value).map_err(|_| bad())?;
            header_value.set_sensitive(true);
            map.insert(header_name, header_value);
        }
        Ok(WebhookSender {
            client,
            url: parsed,
            headers: map,
            timeout: std::time::Duration::from_secs(timeout_s),
        })
    }

    /// Posts `notice`: `Ok("HTTP 200 OK")` for 2xx, `Err` with the status or the error.
    pub(crate) async fn send(&self, notice: &Notice, rule: &str) -> Result<String, String> {
        let request = self
            .client
            .post(self.url.clone())
            .headers(self.headers.clone())
            .timeout(self.timeout)
            .json(&WebhookBody::new(notice, rule));
        // The request's own time-out covers connect and body; this one also bounds the
        // name resolution.
        match tokio::time::timeout(self.timeout, request.send()).await {
            Ok(Ok(response)) => {
                let status = response.status();
                let detail = format!("HTTP {status}");
                if status.is_success() {
                    Ok(detail)
                } else {
                    Err(detail)
                }
            }
            Ok(Err(error)) if error.is_timeout() => {
                Err(format!("timed out after {} s", self.timeout.as_secs()))
            }
            Ok(Err(error)) => Err(error_chain(&error)),
            Err(_) => Err(format!("timed out after {} s", self.timeout.as_secs())),
        }
    }
}
