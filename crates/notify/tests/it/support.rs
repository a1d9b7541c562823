//! Shared by the tests: notices, configurations, webhook servers (the SMTP sink and free
//! ports are the workspace's `testkit`).

use std::collections::BTreeMap;
use std::net::SocketAddr;

use axum::Router;
use chrono::{DateTime, TimeZone, Utc};
use notify::{ChannelConfig, Notice, NotifyConfig, RuleConfig, Security, SmtpSettings};

pub(crate) fn t0() -> DateTime<Utc> {
    Utc.with_ymd_and_hms(2026, 3, 1, 8, 15, 0).unwrap()
}

pub(crate) fn notice(source: &str, class: &str) -> Notice {
    Notice {
        source: source.into(),
        class: class.into(),
        code: Some(17),
        title: "Porucha bezpečnostního okruhu".into(),
        text: "Rozpojen bezpečnostní okruh – dveře šachty ve 3. patře.\nKabina stojí.".into(),
        time: t0(),
        link: Some("https://stanice.example.cz/lifts/L3".into()),
    }
}

pub(crate) fn webhook(url: &str) -> ChannelConfig {
    toml::from_str(&format!(
        "kind = \"webhook\"\nurl = \"{url}\"\ntimeout_s = 5"
    ))
    .unwrap()
}

pub(crate) fn email(to: &[&str]) -> ChannelConfig {
    let to: Vec<String> = to.iter().map(|a| format!("\"{a}\"")).collect();
    toml::from_str(&format!("kind = \"email\"\nto = [{}]", to.join(", "))).unwrap()
}

pub(crate) fn smtp_plain(port: u16, timeout_s: u64) -> SmtpSettings {
    let mut smtp = SmtpSettings::new("127.0.0.1", "Stanice <stanice@example.cz>");
    smtp.security = Security::None;
    smtp.port = Some(port);
    smtp.timeout_s = timeout_s;
    smtp
}

pub(crate) fn config(
    smtp: Option<SmtpSettings>,
    channels: Vec<(&str, ChannelConfig)>,
    rules: Vec<RuleConfig>,
) -> NotifyConfig {
    let channels: BTreeMap<String, ChannelConfig> = channels
        .into_iter()
        .map(|(name, channel)| (name.to_owned(), channel))
        .collect();
    NotifyConfig::new(smtp, channels, rules)
}

pub(crate) fn rule(name: &str, channels: &[&str], quiet_period_s: u64) -> RuleConfig {
    let mut rule = RuleConfig::new(name, channels.iter().map(|c| (*c).to_owned()).collect());
    rule.quiet_period_s = quiet_period_s;
    rule
}

/// Serves `router` on a free loopback port; the server lives as long as the runtime.
pub(crate) async fn serve(router: Router) -> SocketAddr {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let address = listener.local_addr().unwrap();
    tokio::spawn(async move {
        axum::serve(listener, router).await.unwrap();
    });
    address
}
