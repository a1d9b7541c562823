//! The `[mqtt]` table of station.toml: what it takes, and its mistakes reported at
//! file:line:col.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use station::config::Project;

fn project(mqtt: &str) -> String {
    format!(
        r#"[station]
name = "plant"
time_zone = "UTC"

[[node]]
name = "N1"
common_address = 1

{mqtt}"#
    )
}

#[test]
fn the_mqtt_table_is_read_with_its_settings() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("ca.pem"), "-----BEGIN CERTIFICATE-----\n").unwrap();
    let file = dir.path().join("station.toml");
    let loaded = Project::parse(
        dir.path(),
        &file,
        &project(
            "[mqtt]\nurl = \"mqtts://broker:8883\"\nca = \"ca.pem\"\nusername = \"st\"\npassword = \"pw\"\nprimary_host = \"scada\"\ngroup = \"g1\"\nredundancy_group = \"scada-hosts\"\n",
        ),
    )
    .unwrap();
    let mqtt = loaded.mqtt.unwrap();
    assert_eq!(mqtt.url, "mqtts://broker:8883");
    assert_eq!(mqtt.ca, Some(dir.path().join("ca.pem")));
    assert_eq!(mqtt.username.as_deref(), Some("st"));
    assert_eq!(mqtt.password.as_deref(), Some("pw"));
    assert_eq!(mqtt.primary_host.as_deref(), Some("scada"));
    assert_eq!(mqtt.group.as_deref(), Some("g1"));
    assert_eq!(mqtt.redundancy_group.as_deref(), Some("scada-hosts"));
    let without = Project::parse(dir.path(), &file, &project("")).unwrap();
    assert_eq!(without.mqtt, None);
}

#[test]
fn mistakes_in_the_mqtt_table_are_reported_where_they_are() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("station.toml");
    let errors = Project::parse(
        dir.path(),
        &file,
        &project(
            "[mqtt]\nurl = \"http://broker\"\nca = \"missing.pem\"\npassword = \"pw\"\nprimary_host = \"a/b\"\n",
        ),
    )
    .unwrap_err()
    .to_string();
    let file = file.display();
    for expected in [
        format!("{file}:10:7: error: mqtt.url: `http://broker` is not an MQTT broker URL"),
        format!("{file}:11:6: error: mqtt.ca: file"),
        format!("{file}:12:12: error: mqtt.password:"),
        format!("{file}:13:16: error: mqtt.primary_host: `a/b` cannot be a Sparkplug id"),
    ] {
        assert!(errors.contains(&expected), "{expected}\nin\n{errors}");
    }
    let errors = Project::parse(
        dir.path(),
        &dir.path().join("station.toml"),
        &project("[mqtt]\nurl = \"mqtt://broker\"\nca = \"x.pem\"\nkeepalive = 3\n"),
    )
    .unwrap_err()
    .to_string();
    assert!(errors.contains("keepalive"), "{errors}");
}
