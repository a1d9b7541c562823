// Stanice web HMI — the application core (index.html).
//
// Loaded first; mimic.js, events.js, alarms.js, trends.js and lifts.js add their pages to the HMI
// object below, and HMI.start() runs once every script is in (they are all `defer`).
//
//   - HMI.api / HMI.post: JSON requests; a 401 goes back to the login page; every POST
//     carries the session's CSRF token (header X-CSRF-Token).
//   - the live WebSocket /api/live: a snapshot, then point, link, alarm and command
//     messages; reconnects with a growing back-off. While it is closed, or while the
//     station link is down, every value counts as invalid (and blinks on the mimics).
//   - navigation: #screen/ID for a mimic, #events, #alarms, #trends; lifts.js adds the
//     lift screens (#lifts, #lift/NAME, #faults, #figures, #mobile) when hmi.toml has
//     lifts. After login the user's start screen (users.toml `start`) opens.
//
// Live messages (HMI.receive): the server's side is one Rust enum, hmi::live::LiveMessage
// (crates/hmi/src/live.rs), whose doc comment gives each message's fields. In short, each
// frame is one JSON object named by "type":
//   snapshot  {link: {up, address}, points: [Point], alarms: [Alarm]}: replaces everything;
//             first on every socket, again when this browser fell behind
//   point     {name, ioa, iec_type, description, value, invalid, quality, time}: one point
//             ("type" names the message, so the point's IEC type travels as iec_type)
//   link      {up, address}: the station link
//   alarm     {id, point, text, priority, raised, cleared, acknowledged, shelved_until,
//             active, needs_acknowledgement}: one alarm changed
//   command   {user, command, value, outcome}: someone's control and its outcome
// A new message is a new variant there and a new case here.
"use strict";

const HMI = (window.HMI = {
  session: null, // {user, level, csrf, title}
  points: new Map(), // name -> Point (docs/HMI.md)
  // Settles with the first snapshot of the live connection: a screen opened while the
  // page loads is drawn once, with its values (mimic.js), not invalid and then again.
  firstSnapshot: null,
  firstSnapshotArrived: null,
  link: { up: false, address: "" },
  wsOpen: false,
  controls: new Map(), // command name -> {command, ioa, type, level, select, confirm, allowed, description}
  screens: [], // [{id, title}]
  alarms: new Map(), // id -> Alarm
  pages: {}, // name -> {show(argument), hide()}
  current: null, // {page, argument}
  clockOffset: 0, // station clock minus browser clock (ms), from live time tags
  listeners: {},
  errors: [], // uncaught script errors of this page (the browser tests expect none)

  // ------------------------------------------------------------------ events between parts
  on(type, handler) {
    (this.listeners[type] = this.listeners[type] || []).push(handler);
  },
  emit(type, data) {
    for (const handler of this.listeners[type] || []) {
      try {
        handler(data);
      } catch (error) {
        console.error(`handler of ${type}`, error);
      }
    }
  },

  // ------------------------------------------------------------------ HTTP
  async request(path, options = {}) {
    const init = { credentials: "same-origin", headers: {}, ...options };
    if (init.body !== undefined && typeof init.body !== "string") {
      init.body = JSON.stringify(init.body);
      init.headers["Content-Type"] = "application/json";
    }
    if (init.method && init.method !== "GET" && this.session) {
      init.headers["X-CSRF-Token"] = this.session.csrf;
    }
    return this.admit(await fetch(path, init), path);
  },
  /** A response to `path` as request() answers it: a 401 (the session ended) goes to the login page. */
  admit(response, path) {
    if (response.status === 401 && path !== "/api/login") {
      window.location.replace("/login");
      throw new Error("not logged in");
    }
    return response;
  },
  /** GET (or any method) returning the JSON body; throws Error(message) on HTTP errors. */
  async api(path, options) {
    return this.body(await this.request(path, options));
  },
  /** A response's body (JSON or text); throws Error(message) on HTTP errors. */
  async body(response) {
    let body = null;
    const type = response.headers.get("Content-Type") || "";
    if (type.includes("json")) body = await response.json();
    else body = await response.text();
    if (!response.ok) {
      const error = new Error((body && body.error) || `HTTP ${response.status}`);
      error.status = response.status;
      error.body = body;
      throw error;
    }
    return body;
  },
  /** POST with a JSON body; resolves to {status, body} whatever the status (the caller decides). */
  async post(path, body) {
    const response = await this.request(path, { method: "POST", body: body === undefined ? {} : body });
    let parsed = {};
    try {
      parsed = await response.json();
    } catch (error) {
      /* empty body */
    }
    return { status: response.status, ok: response.ok, body: parsed };
  },

  // ------------------------------------------------------------------ formatting
  /** Whether a point's value cannot be trusted now. */
  isInvalid(point) {
    return !this.wsOpen || !this.link.up || !point || point.invalid || point.value === null || point.value === undefined;
  },
  /** on/off/between/faulty for single and double points, the number otherwise. */
  valueWord(point) {
    if (!point || point.value === null || point.value === undefined) return "";
    const value = point.value;
    if (typeof value === "boolean") return value ? "on" : "off";
    if (point.type && point.type.startsWith("M_DP")) return ["between", "off", "on", "faulty"][value] || "faulty";
    return String(value);
  },
  formatNumber(value, digits) {
    if (typeof value !== "number" || !Number.isFinite(value)) return String(value);
    if (digits !== undefined && digits !== null && digits !== "") return value.toFixed(Number(digits));
    if (Number.isInteger(value)) return String(value);
    return String(Math.round(value * 1000) / 1000);
  },
  /** A value for people: ON/OFF, the double-point state, or the number. */
  formatValue(value, type) {
    if (value === null || value === undefined) return "—";
    if (typeof value === "boolean") return value ? "ON" : "OFF";
    if (type && type.startsWith("M_DP")) return ["between", "OFF", "ON", "faulty"][value] || String(value);
    if (typeof value === "number") return this.formatNumber(value);
    return String(value);
  },
  /**
   * A command someone sent, in words for a notice to the other users: its description
   * ("open QF1") with the state sent ("on"/"off") or the number set; never a raw value.
   */
  commandSummary(name, value) {
    const control = this.controls.get(name);
    const what = (control && control.description) || name;
    const type = (control && control.type) || "";
    if (type.startsWith("C_SC") || type.startsWith("C_DC")) {
      const on = type.startsWith("C_DC") ? value === 2 : value === true || value === 1;
      return `${what}: ${on ? "on" : "off"}`;
    }
    if (typeof value === "number") return `${what} set to ${this.formatNumber(value)}`;
    return what;
  },
  pad(n, width = 2) {
    return String(n).padStart(width, "0");
  },
  /** Local date and time with seconds, e.g. 2025-06-16 11:02:03. */
  formatTime(time, withMillis) {
    if (!time) return "—";
    const d = time instanceof Date ? time : new Date(time);
    if (Number.isNaN(d.getTime())) return String(time);
    const p = this.pad;
    let text = `${d.getFullYear()}-${p(d.getMonth() + 1)}-${p(d.getDate())} ${p(d.getHours())}:${p(d.getMinutes())}:${p(d.getSeconds())}`;
    if (withMillis) text += `.${p(d.getMilliseconds(), 3)}`;
    return text;
  },
  /** The station's "now" (its simulated clock may run apart from this browser's). */
  now() {
    return Date.now() + this.clockOffset;
  },
  el(tag, attributes = {}, ...children) {
    const element = document.createElement(tag);
    for (const [key, value] of Object.entries(attributes)) {
      if (value === undefined || value === null || value === false) continue;
      if (key === "class") element.className = value;
      else if (key === "text") element.textContent = value;
      else if (key.startsWith("on") && typeof value === "function") element.addEventListener(key.slice(2), value);
      else element.setAttribute(key, value === true ? "" : value);
    }
    for (const child of children) {
      if (child === null || child === undefined) continue;
      element.append(child instanceof Node ? child : document.createTextNode(String(child)));
    }
    return element;
  },
  toast(text, isError, milliseconds = 6000) {
    const box = document.getElementById("toasts");
    if (!box) return;
    const toast = this.el("div", { class: isError ? "toast error" : "toast", role: "status", text });
    box.append(toast);
    while (box.children.length > 5) box.firstChild.remove();
    setTimeout(() => toast.remove(), milliseconds);
  },

  // ------------------------------------------------------------------ live connection
  ws: null,
  wsAttempts: 0,
  wsTimer: null,
  connect() {
    clearTimeout(this.wsTimer);
    // The first time, the socket early.js opened while the page loaded, with the
    // messages it brought meanwhile; later (a reconnection) a new one.
    const early = window.STANICE_EARLY;
    let socket = early && early.socket;
    const brought = socket ? early.messages : [];
    if (socket) {
      socket.removeEventListener("message", early.keep);
      early.socket = null;
    } else {
      const scheme = window.location.protocol === "https:" ? "wss:" : "ws:";
      try {
        // batch=1: the messages waiting at the server come together, as one JSON array.
        socket = new WebSocket(`${scheme}//${window.location.host}/api/live?batch=1`);
      } catch (error) {
        this.scheduleReconnect();
        return;
      }
    }
    this.ws = socket;
    const opened = () => {
      this.wsAttempts = 0;
      performance.mark("hmi:live-open");
    };
    const message = (event) => {
      if (performance.getEntriesByName("hmi:live-message").length === 0) performance.mark("hmi:live-message");
      let parsed;
      try {
        parsed = JSON.parse(event.data);
      } catch (error) {
        return;
      }
      if (Array.isArray(parsed)) for (const one of parsed) this.receive(one);
      else this.receive(parsed);
    };
    const closed = () => {
      if (this.ws !== socket) return;
      this.ws = null;
      this.setOpen(false);
      this.scheduleReconnect();
    };
    socket.addEventListener("open", opened);
    socket.addEventListener("message", message);
    socket.addEventListener("close", closed);
    socket.addEventListener("error", () => {
      /* the close event follows */
    });
    // An adopted socket may have opened, brought messages or closed already.
    if (socket.readyState === WebSocket.OPEN) opened();
    for (const event of brought) message(event);
    if (socket.readyState === WebSocket.CLOSED) closed();
  },
  scheduleReconnect() {
    this.wsAttempts += 1;
    // 0.5 s, 1 s, 2 s, 4 s, 8 s, then every 10 s; a little jitter so that many browsers
    // do not come back in step after an HMI restart.
    const delay = Math.min(10000, 500 * 2 ** Math.min(this.wsAttempts - 1, 5)) * (0.8 + Math.random() * 0.4);
    document.body.dataset.reconnectMs = String(Math.round(delay));
    this.wsTimer = setTimeout(async () => {
      // A refused upgrade looks like any closed socket: after a few failures check the
      // session (a 401 goes to the login page).
      if (this.wsAttempts >= 3) {
        try {
          await this.api("/api/session");
        } catch (error) {
          /* still offline */
        }
      }
      this.connect();
    }, delay);
  },
  setOpen(open) {
    this.wsOpen = open;
    document.body.classList.toggle("ws-down", !open);
    this.showLink();
    this.emit("connection", open);
  },
  receive(message) {
    switch (message.type) {
      case "snapshot": {
        performance.mark("hmi:snapshot");
        if (this.firstSnapshotArrived) {
          this.firstSnapshotArrived();
          this.firstSnapshotArrived = null;
        }
        this.points.clear();
        for (const point of message.points || []) this.points.set(point.name, point);
        if (message.link) this.link = { ...this.link, ...message.link };
        if (Array.isArray(message.alarms)) {
          this.alarms.clear();
          for (const alarm of message.alarms) this.alarms.set(alarm.id, alarm);
        } else {
          this.loadAlarms();
        }
        // The names' list (thousands of <option>s) waits for an idle moment: the
        // screen's values come first.
        if (window.requestIdleCallback) requestIdleCallback(() => this.fillPointNames(), { timeout: 3000 });
        else setTimeout(() => this.fillPointNames(), 500);
        this.setOpen(true);
        this.emit("snapshot", message);
        this.emit("alarms", null);
        break;
      }
      case "point": {
        // The message's own fields are the point's; its "type" key is the message type,
        // so keep the IEC type the point had. Updated in place: 10,000 updates a second
        // make no garbage here.
        let point = this.points.get(message.name);
        if (!point) {
          point = {};
          this.points.set(message.name, point);
        }
        for (const key in message) if (key !== "type") point[key] = message[key];
        if (message.point_type) point.type = message.point_type;
        if (point.time && !point.invalid) {
          const offset = Date.parse(point.time) - Date.now();
          if (Number.isFinite(offset) && Math.abs(offset - this.clockOffset) > 3000) this.clockOffset = offset;
        }
        this.emit("point", point);
        break;
      }
      case "link": {
        this.link = { ...this.link, up: Boolean(message.up) };
        if (message.address) this.link.address = message.address;
        this.showLink();
        this.emit("link", this.link);
        break;
      }
      case "alarm": {
        const { type, ...alarm } = message;
        this.alarms.set(alarm.id, alarm);
        this.emit("alarm", alarm);
        this.emit("alarms", alarm);
        break;
      }
      case "command": {
        this.emit("command", message);
        if (this.session && message.user !== this.session.user) {
          this.toast(`${message.user}: ${this.commandSummary(message.command, message.value)} — ${this.outcomeWords(message.outcome)}`);
        }
        break;
      }
      default:
        break;
    }
  },
  async loadAlarms() {
    try {
      const list = await this.api("/api/alarms");
      this.alarms.clear();
      for (const alarm of list) this.alarms.set(alarm.id, alarm);
      this.emit("alarms", null);
    } catch (error) {
      /* shown as no alarms */
    }
  },
  showLink() {
    const indicator = document.getElementById("link");
    const text = document.getElementById("link-text");
    let state;
    let words;
    if (!this.wsOpen) {
      state = "offline";
      words = "HMI server offline";
    } else if (this.link.up) {
      state = "up";
      words = "station link up";
    } else {
      state = "down";
      words = "station link DOWN";
    }
    indicator.dataset.state = state;
    text.textContent = words;
    indicator.title = this.link.address ? `Station ${this.link.address}` : "Station link";
    document.body.classList.toggle("link-down", this.wsOpen && !this.link.up);
  },
  fillPointNames() {
    const list = document.getElementById("point-names");
    if (!list) return;
    // Again after every snapshot: only when the names changed (thousands of options).
    if (list.children.length === this.points.size + this.controls.size) return;
    const names = [...this.points.keys(), ...this.controls.keys()].sort();
    list.replaceChildren(...names.map((name) => this.el("option", { value: name })));
  },

  // ------------------------------------------------------------------ command outcomes
  outcomeWords(outcome) {
    switch (outcome) {
      case "executed":
        return "executed: the station confirmed the command";
      case "refused":
        return "refused by the station (negative confirmation)";
      case "refused-local":
        return "refused: the device is in local mode";
      case "refused-permission":
        return "refused: your permission level does not allow this control";
      case "refused-authority":
        return "refused: the control authority is not with this HMI (take it on the supply screen)";
      case "sent":
        return "sent to the station (outcome recorded separately)";
      case "timed-out":
        return "timed out: the station did not confirm in time";
      case "no-link":
        return "not sent: no link to the station";
      default:
        return outcome ? String(outcome) : "unknown outcome";
    }
  },

  // ------------------------------------------------------------------ navigation
  route() {
    const hash = decodeURIComponent(window.location.hash.replace(/^#/, ""));
    let [page, ...rest] = hash.split("/");
    let argument = rest.join("/");
    if (!page || !this.pages[page]) {
      // No screens but lifts (a lift-service HMI): the fleet list is the first page.
      page = !this.screens.length && this.pages.lifts ? "lifts" : "screen";
      argument = "";
    }
    if (page === "screen" && !this.screens.some((s) => s.id === argument)) {
      argument = this.screens.length ? this.screens[0].id : "";
    }
    if (this.current && this.current.page !== page && this.pages[this.current.page].hide) {
      this.pages[this.current.page].hide();
    }
    for (const section of document.querySelectorAll("main > .page")) {
      section.hidden = section.id !== `page-${page}`;
    }
    this.current = { page, argument };
    document.body.dataset.current = page === "screen" ? `screen/${argument}` : page;
    for (const link of document.querySelectorAll("#nav a")) {
      const target = link.getAttribute("href").slice(1);
      link.classList.toggle("current", target === document.body.dataset.current);
      if (target === document.body.dataset.current) link.setAttribute("aria-current", "page");
      else link.removeAttribute("aria-current");
    }
    document.body.classList.remove("nav-open");
    document.getElementById("nav-toggle").setAttribute("aria-expanded", "false");
    this.pages[page].show(argument);
  },

  // ------------------------------------------------------------------ start
  async start() {
    performance.mark("hmi:start");
    // The live connection and the screen the address names start at once, beside the
    // session: the snapshot and the drawing travel while the page sets itself up (without
    // a session the upgrade is refused, and the session's 401 goes to the login page).
    this.firstSnapshot = new Promise((resolve) => {
      this.firstSnapshotArrived = resolve;
    });
    this.connect();
    const screen = /^#screen\/([^/]+)$/.exec(window.location.hash);
    if (screen && this.prefetchScreen) this.prefetchScreen(decodeURIComponent(screen[1]));
    // The session and the lists at once: one round trip before the first page, not two.
    const lists = Promise.all([
      this.api("/api/screens").catch(() => []),
      this.api("/api/controls").catch(() => []),
      this.api("/api/lifts").catch(() => null),
    ]);
    try {
      this.session = await this.api("/api/session");
    } catch (error) {
      if (error.status !== 401) this.toast(`Cannot load the session: ${error.message}`, true);
      return;
    }
    const title = this.session.title || "Stanice HMI";
    document.title = `${title} — Stanice HMI`;
    document.getElementById("title").textContent = title;
    document.getElementById("user-name").textContent = this.session.user;
    document.getElementById("user-level").textContent = `level ${this.session.level}`;
    document.body.dataset.level = String(this.session.level);
    document.getElementById("logout").addEventListener("click", async () => {
      try {
        await this.post("/api/logout");
      } finally {
        window.location.replace("/login");
      }
    });
    const toggle = document.getElementById("nav-toggle");
    toggle.addEventListener("click", () => {
      const open = document.body.classList.toggle("nav-open");
      toggle.setAttribute("aria-expanded", String(open));
    });
    this.showLink();

    const [screens, controls, lifts] = await lists;
    this.liftConfig = lifts; // lifts.js builds the lift screens from it
    this.screens = screens;
    for (const control of controls) this.controls.set(control.command, control);
    const list = document.getElementById("nav-screens");
    list.replaceChildren(
      ...screens.map((screen) =>
        this.el("li", {}, this.el("a", { href: `#screen/${encodeURIComponent(screen.id)}`, text: screen.title })),
      ),
    );
    window.addEventListener("hashchange", () => this.route());
    this.emit("ready", null);
    // The user's start screen (users.toml `start`, lift spec 10) when the address names
    // no page: a mimic's screen id or a page (lifts, faults, mobile, events, ...).
    const start = this.session.start;
    if (start && !window.location.hash) {
      const target = screens.some((s) => s.id === start) ? `screen/${start}` : start;
      if (this.pages[target.split("/")[0]]) history.replaceState(null, "", `#${target}`);
    }
    this.route();
    document.body.dataset.ready = "true";
  },
});

window.addEventListener("error", (event) => HMI.errors.push(String(event.message || event.error)));
window.addEventListener("unhandledrejection", (event) => {
  const reason = event.reason && event.reason.message ? event.reason.message : String(event.reason);
  // A request cut short by leaving for the login page is no error.
  if (reason !== "not logged in") HMI.errors.push(reason);
});

document.addEventListener("DOMContentLoaded", () => {
  if (document.body.dataset.page === "app") HMI.start();
});
