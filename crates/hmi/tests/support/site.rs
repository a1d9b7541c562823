//! The Vsetín station (every node, the plant, in real time) and its web HMI connected to
//! the top controller, as `stanice demo` runs them: the site of the HMI's browser tests.
//! Included by `#[path]`.
#![allow(dead_code)]

use std::net::SocketAddr;
use std::path::PathBuf;

use chrono::{DateTime, Utc};
use hmi::{Hmi, HmiOptions};
use iec60870::time::TimeZonePolicy;
use station::config::Project;
use station::runtime::{Pacing, Runtime, RuntimeOptions, StoreChoice};
use testkit::ports::free_port_range;
use testkit::projects::vsetin;

/// The Vsetín station (every node, the plant) and its web HMI, as `stanice demo` runs them.
pub(crate) struct Site {
    pub(crate) runtime: Option<Runtime>,
    pub(crate) hmi: Option<Hmi>,
    pub(crate) url: String,
}

impl Site {
    /// The site with the Vsetín screens as they are.
    pub(crate) async fn start(start: DateTime<Utc>, speed: f64) -> Site {
        Site::start_with(start, speed, vsetin().join("hmi")).await
    }

    /// The site serving the screens folder `screens` (points.csv of Vsetín's top node).
    pub(crate) async fn start_with(start: DateTime<Utc>, speed: f64, screens: PathBuf) -> Site {
        let folder = vsetin();
        let project = Project::load(&folder)
            .unwrap_or_else(|e| panic!("{:?}", e.errors()))
            .with_port_base(free_port_range(23));
        let zone = project.station.time_zone;
        let runtime = Runtime::start(
            project,
            RuntimeOptions {
                nodes: Vec::new(),
                pacing: Pacing::RealTime { speed },
                start,
                store: StoreChoice::Disabled,
                device_kinds: station::device::DeviceKinds::builtin(),
            },
        )
        .await
        .unwrap();
        let top = runtime.project().top_node().unwrap().clone();
        let server = runtime
            .node(&top.name)
            .and_then(|node| node.server.as_ref())
            .unwrap()
            .local_addr();
        let hmi = Hmi::start(HmiOptions {
            screens: screens.clone(),
            users: screens.join("users.toml"),
            connect: vec![server.to_string()],
            common_address: top.common_address,
            listen: SocketAddr::from(([127, 0, 0, 1], 0)),
            store: Some("sqlite::memory:".into()),
            zone: TimeZonePolicy::Zone(zone),
            // None: the screens folder's hmi.toml names the address the station's group
            // "hmi" takes (127.0.0.2), so the operator below may operate, as with the
            // README's standalone `stanice hmi --screens examples/vsetin/hmi` (it could
            // not: the station refused it, cause 7).
            local_address: None,
            archive: None,
        })
        .await
        .unwrap();
        let url = format!("http://{}", hmi.address);
        Site {
            runtime: Some(runtime),
            hmi: Some(hmi),
            url,
        }
    }

    pub(crate) fn hmi(&self) -> &Hmi {
        self.hmi.as_ref().unwrap()
    }

    /// A line of the demo's console (`breaker-tripped RH2_FA1.1`, ...).
    pub(crate) async fn operate(&self, line: &str) {
        self.runtime
            .as_ref()
            .unwrap()
            .operate(line)
            .await
            .unwrap_or_else(|e| panic!("{line}: {e}"));
    }

    pub(crate) async fn stop(mut self) {
        if let Some(hmi) = self.hmi.take() {
            hmi.shutdown().await;
        }
        if let Some(runtime) = self.runtime.take() {
            runtime.shutdown().await;
        }
    }
}
