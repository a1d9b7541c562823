//! The configuration as the station project embeds it, and its validation.

use notify::{ChannelConfig, ConfigError, Notifier, NotifierError, NotifyConfig, Security};
use serde::Deserialize;

const EXAMPLE: &str = r#"
[node.notify.smtp]
host = "smtp.example.cz"
port = 587
security = "starttls"
user = "stanice"
password_env = "STANICE_TEST_SMTP_PASSWORD_SET"
from = "Stanice <stanice@example.cz>"
timeout_s = 20

[node.notify.channel.technicians]
kind = "email"
to = ["novak@example.cz", "Jana Dvořáková <dvorakova@example.cz>"]

[node.notify.channel.tickets]
kind = "webhook"
url = "https://tickets.example.cz/api/hook"
headers = { Authorization = "Bearer 0123" }
timeout_s = 10

[[node.notify.rule]]
name = "lift-faults"
sources = ["L*"]
classes = ["safety-circuit", "door"]
channels = ["technicians", "tickets"]
quiet_period_s = 900
rate_limit = { max = 10, per_s = 3600 }

[[node.notify.rule]]
name = "comm"
classes = ["comm-lost"]
channels = ["tickets"]
"#;

#[derive(Deserialize)]
struct Project {
    node: Node,
}

#[derive(Deserialize)]
struct Node {
    notify: NotifyConfig,
}

fn parse(text: &str) -> Result<NotifyConfig, toml::de::Error> {
    toml::from_str::<Project>(text).map(|project| project.node.notify)
}

#[test]
fn example_parses_validates_and_builds() {
    let config = parse(EXAMPLE).unwrap();
    config.validate().unwrap();
    let smtp = config.smtp.as_ref().unwrap();
    assert_eq!(smtp.security, Security::Starttls);
    assert_eq!(smtp.port(), 587);
    assert_eq!(config.channels.len(), 2);
    assert_eq!(config.rules.len(), 2);
    assert_eq!(config.rules[1].quiet_period_s, 600);
    assert!(config.rules[1].sources.is_empty());
    assert!(matches!(
        config.channels["tickets"],
        ChannelConfig::Webhook { timeout_s: 10, .. }
    ));

    // The password comes from the environment when the notifier is built.
    let missing = Notifier::new(config.clone()).unwrap_err();
    assert!(
        matches!(&missing, NotifierError::Config(errors)
            if errors == &[ConfigError::PasswordEnvMissing { var: "STANICE_TEST_SMTP_PASSWORD_SET".into() }]),
        "{missing}"
    );
    // No other test of this binary reads this variable.
    std::env::set_var("STANICE_TEST_SMTP_PASSWORD_SET", "secret");
    Notifier::new(config).unwrap();
}

#[test]
fn unknown_fields_are_refused() {
    let error = parse("[node.notify.smtp]\nhost = \"h\"\nfrom = \"a@b.cz\"\nsecurty = \"tls\"")
        .unwrap_err();
    assert!(error.to_string().contains("securty"), "{error}");
    let error =
        parse("[node.notify.channel.x]\nkind = \"email\"\nto = [\"a@b.cz\"]\ncc = []").unwrap_err();
    assert!(error.to_string().contains("cc"), "{error}");
    let error = parse("[[node.notify.rule]]\nname = \"r\"\nchannels = []\nquiet = 5").unwrap_err();
    assert!(error.to_string().contains("quiet"), "{error}");
    let error = parse("[node.notify.channel.x]\nkind = \"sms\"\nto = [\"1\"]").unwrap_err();
    assert!(error.to_string().contains("sms"), "{error}");
}

#[test]
fn validation_names_the_field() {
    let config = parse(
        r#"
[node.notify.channel.mail]
kind = "email"
to = []

[node.notify.channel.bad]
kind = "email"
to = ["not an address"]

[node.notify.channel.hook]
kind = "webhook"
url = "ftp://example.cz/x"
headers = { "Bad Header" = "x" }
timeout_s = 0

[node.notify.channel.hook2]
kind = "webhook"
url = "not a url"

[[node.notify.rule]]
name = "r"
channels = ["mail", "sms"]
rate_limit = { max = 0, per_s = 60 }

[[node.notify.rule]]
name = "r"
channels = []
"#,
    )
    .unwrap();
    let errors = config.validate().unwrap_err();
    let texts: Vec<String> = errors.iter().map(ToString::to_string).collect();
    let expect = [
        "notify.channel.bad: an e-mail channel needs notify.smtp",
        "notify.channel.bad.to: bad e-mail address `not an address`",
        "notify.channel.hook: url: bad URL `ftp://example.cz/x`: scheme `ftp` is not http or https",
        "notify.channel.hook: headers: bad header `Bad Header`",
        "notify.channel.hook.timeout_s: timeout_s must be at least 1",
        "notify.channel.hook2: url: bad URL `not a url`",
        "notify.channel.mail: to: empty recipient list",
        "notify.rule `r`: channels: unknown channel `sms`",
        "notify.rule `r`: rate_limit: max and per_s must be at least 1",
        "notify.rule `r`: name: used twice",
        "notify.rule `r`: channels: empty",
    ];
    for expected in expect {
        assert!(
            texts.iter().any(|text| text.starts_with(expected)),
            "missing {expected:?} in {texts:#?}"
        );
    }
    assert!(errors.contains(&ConfigError::UnknownChannel {
        rule: "r".into(),
        channel: "sms".into()
    }));
    assert!(matches!(Notifier::new(config), Err(NotifierError::Config(e)) if e == errors));
}

#[test]
fn smtp_settings_are_checked() {
    let config = parse(
        "[node.notify.smtp]\nhost = \"\"\nfrom = \"nobody\"\npassword = \"x\"\npassword_env = \"Y\"\ntimeout_s = 0",
    )
    .unwrap();
    let errors = config.validate().unwrap_err();
    assert!(errors.contains(&ConfigError::EmptyHost));
    assert!(errors.contains(&ConfigError::PasswordTwice));
    assert!(errors.contains(&ConfigError::PasswordWithoutUser));
    assert!(errors.iter().any(
        |e| matches!(e, ConfigError::BadAddress { field, .. } if field == "notify.smtp.from")
    ));
    assert!(errors.iter().any(
        |e| matches!(e, ConfigError::ZeroTimeout { field } if field == "notify.smtp.timeout_s")
    ));
}
