//! The controlling station's link kept up for its owner (`cs104::link`): what the observer
//! is told on start, data, loss, cut, restore and stop.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use iec60870::asdu::{Asdu, TypeId};
use iec60870::cs104::client::ClientHandle;
use iec60870::cs104::link::{Link, LinkDown, LinkObserver};
use iec60870::cs104::server::{ProcessImage, ReadOnlyStation};
use tokio::sync::mpsc;

use crate::common::*;

/// What the observer saw, in order.
#[derive(Debug, Clone, PartialEq)]
enum Seen {
    Started,
    Down(LinkDown),
    /// A monitor value of IOA 1 (scaled).
    Value(i16),
    Period,
}

struct Recording {
    seen: mpsc::UnboundedSender<Seen>,
    period: Option<Duration>,
    /// The client handed to `started`, to check it is the link's.
    client: Mutex<Option<ClientHandle>>,
}

impl LinkObserver for Recording {
    fn started(&self, client: &ClientHandle) {
        *self.client.lock().unwrap() = Some(client.clone());
        let _ = self.seen.send(Seen::Started);
    }

    fn down(&self, why: &LinkDown) {
        let _ = self.seen.send(Seen::Down(why.clone()));
    }

    fn asdu(&self, asdu: &Asdu) {
        if asdu.type_id == TypeId::M_ME_NB_1 {
            for object in &asdu.objects {
                if let iec60870::asdu::Element::Scaled { value, .. } = object.element {
                    let _ = self.seen.send(Seen::Value(value));
                }
            }
        }
    }

    fn period(&self) -> Option<Duration> {
        self.period
    }

    fn every_period(&self, _client: &ClientHandle) {
        let _ = self.seen.send(Seen::Period);
    }
}

fn image() -> ProcessImage {
    let mut image = ProcessImage::new();
    image
        .add_monitor(monitor(1, TypeId::M_ME_NB_1, 0, scaled(7)))
        .unwrap();
    image
}

fn recording(period: Option<Duration>) -> (Arc<Recording>, mpsc::UnboundedReceiver<Seen>) {
    let (seen, receiver) = mpsc::unbounded_channel();
    let observer = Arc::new(Recording {
        seen,
        period,
        client: Mutex::new(None),
    });
    (observer, receiver)
}

/// The next thing seen that is not a periodic call.
async fn next(seen: &mut mpsc::UnboundedReceiver<Seen>, what: &str) -> Seen {
    within(WAIT, what, async {
        loop {
            match seen.recv().await.expect("the link runs") {
                Seen::Period => continue,
                other => return other,
            }
        }
    })
    .await
}

#[tokio::test]
async fn start_data_cut_restore_and_stop_reach_the_observer_in_order() {
    init_logs();
    let server = start_server(server_config(), image(), Arc::new(ReadOnlyStation)).await;
    let mut config = client_config(server.local_addr());
    config.interrogate_on_start = true;
    let (observer, mut seen) = recording(None);
    let link = Link::spawn(config, observer.clone());

    assert_eq!(next(&mut seen, "the start").await, Seen::Started);
    assert_eq!(
        next(&mut seen, "the interrogated value").await,
        Seen::Value(7)
    );
    assert!(link.is_up());
    assert!(link.client().is_some());
    assert!(observer.client.lock().unwrap().is_some());
    server.update(ioa(1), scaled(8), None).unwrap();
    assert_eq!(next(&mut seen, "a spontaneous value").await, Seen::Value(8));

    link.cut();
    assert_eq!(next(&mut seen, "the cut").await, Seen::Down(LinkDown::Cut));
    assert!(!link.is_up());
    assert!(link.client().is_none(), "no client while cut");
    // A cut link stays cut: the value changes, nothing arrives until the restore.
    server.update(ioa(1), scaled(9), None).unwrap();
    link.restore();
    assert_eq!(
        next(&mut seen, "the start after the restore").await,
        Seen::Started
    );
    assert_eq!(
        next(&mut seen, "the value after the restore").await,
        Seen::Value(9)
    );

    link.stop();
    within(WAIT, "the link's connection to close", async {
        while server.stats().connections > 0 {
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
    })
    .await;
    assert!(!link.is_up());
    assert!(link.client().is_none());
    // A stop is not a loss: nothing more is reported, and the link does not come back.
    let after = tokio::time::timeout(Duration::from_millis(300), seen.recv()).await;
    assert!(after.is_err(), "reported after the stop: {after:?}");
    assert_eq!(
        server.stats().accepted,
        2,
        "one connection, one after the restore"
    );
}

#[tokio::test]
async fn a_lost_connection_is_reported_once_and_the_client_comes_back() {
    init_logs();
    let server = start_server(server_config(), image(), Arc::new(ReadOnlyStation)).await;
    let address = server.local_addr();
    let (observer, mut seen) = recording(Some(Duration::from_millis(20)));
    let link = Link::spawn(crate::client::reconnecting_config(address), observer);
    assert_eq!(next(&mut seen, "the start").await, Seen::Started);
    // The periodic duty runs while started.
    within(WAIT, "a periodic call", async {
        while seen.recv().await != Some(Seen::Period) {}
    })
    .await;

    server.shutdown();
    match next(&mut seen, "the loss").await {
        Seen::Down(LinkDown::Lost(_)) => {}
        other => panic!("expected the loss, saw {other:?}"),
    }
    assert!(!link.is_up());
    let _server = crate::client::restart_server_with(address, image()).await;
    assert_eq!(
        next(&mut seen, "the start after the restart").await,
        Seen::Started
    );
    assert!(link.is_up());
}
