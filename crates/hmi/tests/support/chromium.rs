//! The HMI's page in a headless Chromium: the workspace's browser support
//! (`testkit::chromium`) and a wait that shows the HMI's state when it times out. Included
//! by `#[path]` in tests/browser.rs and tests/lifts.rs.
// Each including test uses a part of it.
#![allow(dead_code, unused_imports)]

use std::time::Duration;

use fantoccini::Client;
pub(crate) use testkit::chromium::{browser_available, click, js, Driver, WAIT};

/// What the HMI's page shows, for a wait's failure message: its URL and screen, the live
/// link, toasts and messages.
const PAGE_STATE: &str =
    "JSON.stringify({url: location.href, current: document.body.dataset.current, \
     ws: window.HMI && HMI.wsOpen, link: window.HMI && HMI.link, \
     toasts: [...document.querySelectorAll('.toast')].map(t => t.textContent), \
     message: (document.getElementById('login-message') || {}).textContent, \
     faults: (document.getElementById('faults-total') || {}).textContent, \
     faultsMessage: (document.getElementById('faults-message') || {}).textContent})";

/// Waits until a JavaScript expression is truthy; fails with `what` (and the page's state)
/// after [`WAIT`]. Returns how long it took.
pub(crate) async fn until(client: &Client, expression: &str, what: &str) -> Duration {
    testkit::chromium::until_or_show(client, expression, what, PAGE_STATE).await
}
