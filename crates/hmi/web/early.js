// The page's first requests, made before its other scripts load: the live connection and
// the screen the address names. Loaded first and not deferred (a few lines), so the
// server builds the snapshot and sends the drawing while the browser still loads and
// compiles the rest; app.js adopts the socket (and the messages it brought meanwhile)
// and mimic.js the screen's response. Measured by crates/hmi/benches/live.rs: a fresh
// page's connection opened and its screen fetched some 100 ms sooner.
"use strict";
window.STANICE_EARLY = (() => {
  const early = { socket: null, messages: [], screen: null };
  try {
    const scheme = window.location.protocol === "https:" ? "wss:" : "ws:";
    // batch=1: the messages waiting at the server come together, as one JSON array.
    early.socket = new WebSocket(`${scheme}//${window.location.host}/api/live?batch=1`);
    early.keep = (event) => early.messages.push(event);
    early.socket.addEventListener("message", early.keep);
  } catch (error) {
    early.socket = null; // app.js connects as it does on every reconnection
  }
  const screen = /^#screen\/([^/]+)$/.exec(window.location.hash);
  if (screen) {
    const id = decodeURIComponent(screen[1]);
    early.screen = { id, response: fetch(`/api/screens/${encodeURIComponent(id)}`) };
  }
  return early;
})();
