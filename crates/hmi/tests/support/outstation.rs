//! An IEC 104 outstation of float measurements (IOA 1..=N, this workspace's server) and an
//! HMI connected to it on loopback, without a store: the live path's test and benchmark.
//! Included by `#[path]`.
#![allow(dead_code)]

use std::path::Path;
use std::sync::Arc;

use hmi::{Hmi, HmiOptions};
use iec60870::asdu::{CommonAddress, Element, Ioa, Quality, TypeId};
use iec60870::cs104::server::{
    spawn_server, MonitorPoint, ProcessImage, ReadOnlyStation, ServerConfig, ServerHandle,
};
use iec60870::time::TimeZonePolicy;

/// A good float value.
pub(crate) fn float(value: f32) -> Element {
    Element::Float {
        value,
        quality: Quality::GOOD,
    }
}

/// The outstation: `points` measured values at IOA 1 to `points`, all 0.0.
pub(crate) async fn float_outstation(points: u32) -> ServerHandle {
    let mut image = ProcessImage::new();
    for i in 1..=points {
        image
            .add_monitor(MonitorPoint {
                ioa: Ioa::try_new(i).unwrap(),
                event_type: TypeId::M_ME_NC_1,
                groups: 0,
                element: float(0.0),
                time: None,
            })
            .unwrap();
    }
    spawn_server(
        ServerConfig::new("127.0.0.1:0".parse().unwrap(), CommonAddress::new(1)),
        image,
        Arc::new(ReadOnlyStation),
    )
    .await
    .unwrap()
}

/// The HMI of the screens folder `screens` (its `users.toml` too), connected to `server`.
pub(crate) async fn hmi_of(server: &ServerHandle, screens: &Path) -> Hmi {
    Hmi::start(HmiOptions {
        screens: screens.to_path_buf(),
        users: screens.join("users.toml"),
        connect: vec![server.local_addr().to_string()],
        common_address: CommonAddress::new(1),
        listen: "127.0.0.1:0".parse().unwrap(),
        store: None,
        zone: TimeZonePolicy::Utc,
        local_address: None,
        archive: None,
    })
    .await
    .unwrap()
}
