// Stanice web HMI — the lift screens (docs/HMI.md, "Lift screens"; lift spec 9 and 10).
//
// Pages, each a section built here, shown by the navigation like the others:
//   #lifts        the fleet list: one row per lift of hmi.toml's [[lift]], status text on
//                 its colour class, floor, direction, doors, communication, last fault;
//                 filters by colour, text and communication alarm; a click opens the lift
//   #lift/NAME    the lift view of the thesis: status on its colour at the top, the car
//                 with its doors, current/target floor and direction, the car operating
//                 panel (display only: this HMI never controls a lift), trips per floor
//   #faults[/L]   the fault archive of the station's store: paged, sorted by a click on a
//                 column, filtered by lift, code, text (English or Czech) and date range,
//                 English and Czech texts, CSV export; reloads when NAME.faults changes
//   #figures      service figures of the fleet and each lift over 30 or 365 days
//   #mobile       the phone view (720 × 1520): no graphics, the important values and the
//                 fault list (Date, Time, Fault description)
//
// Live values are the points NAME.status, NAME.colour, NAME.position, ... of the live
// WebSocket (HMI.points); an invalid one blinks, as on the mimics. Everything from the
// server goes into the page as text (textContent), never as markup.
"use strict";

(function () {
  const PAGE_SIZE_DEFAULT = 25;
  const L = {
    config: null, // GET /api/lifts
    statuses: new Map(), // code -> {english, czech, class}
    faultCodes: new Map(), // code -> {hex, english, czech, group}
    lang: "en",
  };
  HMI.lifts = L;

  const DOORS = [
    ["unknown", "unknown", "neznámé"],
    ["closed", "closed", "zavřené"],
    ["partly-open", "partly open", "částečně otevřené"],
    ["open", "open", "otevřené"],
    ["fault", "door fault", "porucha dveří"],
  ];
  const DIRECTIONS = [
    ["stopped", "■", "stopped"],
    ["up", "▲", "up"],
    ["down", "▼", "down"],
  ];

  const lifts = () => (L.config && L.config.lifts) || [];
  const allowed = (element) => Boolean(L.config && L.config.allowed && L.config.allowed[element]);
  const findLift = (name) => lifts().find((lift) => lift.name === name);
  const el = (...args) => HMI.el(...args);
  const SVG = "http://www.w3.org/2000/svg";
  function svg(tag, attributes = {}, ...children) {
    const element = document.createElementNS(SVG, tag);
    for (const [key, value] of Object.entries(attributes)) {
      if (value === undefined || value === null) continue;
      if (key === "text") element.textContent = value;
      else element.setAttribute(key, value);
    }
    for (const child of children) if (child) element.append(child);
    return element;
  }

  function statusInfo(code) {
    const known = L.statuses.get(code);
    if (known) return known;
    return { english: `unknown status (${code})`, czech: `neznámý stav (${code})`, class: "orange" };
  }
  function faultInfo(code) {
    const known = L.faultCodes.get(code);
    if (known) return known;
    const hex = Number(code).toString(16).toUpperCase().padStart(2, "0");
    return { hex, english: `unknown fault 0x${hex}`, czech: `neznámá porucha 0x${hex}` };
  }

  /** A point's number (TRUE is 1), and whether it cannot be trusted now. */
  function reading(name, suffix) {
    const point = HMI.points.get(`${name}.${suffix}`);
    let value = point ? point.value : null;
    if (typeof value === "boolean") value = value ? 1 : 0;
    if (typeof value !== "number" || !Number.isFinite(value)) value = null;
    return { value, invalid: HMI.isInvalid(point) };
  }

  /** Everything the screens show of a lift, from its live points. */
  function liftState(lift) {
    const status = reading(lift.name, "status");
    const position = reading(lift.name, "position");
    const target = reading(lift.name, "target");
    const direction = reading(lift.name, "direction");
    const door = reading(lift.name, "door");
    const comm = reading(lift.name, "not_answering");
    const lastFault = reading(lift.name, "last_fault");
    const faults = reading(lift.name, "faults");
    const info = status.value === null ? null : statusInfo(status.value);
    const trips = [];
    for (let floor = 1; floor <= lift.floors; floor += 1) trips.push(reading(lift.name, `floor${floor}_trips`));
    return {
      status,
      info,
      colour: info ? info.class : "unknown",
      text: info ? (L.lang === "cs" ? info.czech : info.english) : "no status",
      position,
      target,
      direction,
      directionInfo: DIRECTIONS[direction.value] || ["unknown", "?", "unknown"],
      door,
      doorInfo: DOORS[door.value] || DOORS[0],
      commAlarm: comm.value === 1,
      comm,
      lastFault,
      faults,
      oos: reading(lift.name, "out_of_service"),
      inspection: reading(lift.name, "inspection"),
      trips,
      totalTrips: reading(lift.name, "trips"),
    };
  }

  function floorText(r) {
    return r.value === null ? "—" : String(r.value);
  }
  function lastFaultText(r) {
    if (r.value === null || r.value === 0) return "—";
    const info = faultInfo(r.value);
    return `${info.hex} ${L.lang === "cs" ? info.czech : info.english}`;
  }
  /** Marks an element as showing an invalid value (it blinks). */
  function mark(element, invalid) {
    if (invalid) element.setAttribute("data-invalid", "true");
    else element.removeAttribute("data-invalid");
    return element;
  }

  // ------------------------------------------------------------------ sections
  function section(id, ...children) {
    const element = el("section", { id: `page-${id}`, class: "page lifts", hidden: true }, ...children);
    document.getElementById("main").append(element);
    return element;
  }
  function refusedText(element) {
    return el("p", { class: "muted refused", text: `Your level does not reach this screen (${element}).` });
  }

  // ------------------------------------------------------------------ fleet list
  const fleet = { shown: false, pending: false };

  function buildFleet() {
    section(
      "lifts",
      el("h2", { text: "Lift fleet" }),
      el(
        "form",
        { id: "lift-filter", class: "filters" },
        el(
          "label",
          {},
          "Status colour",
          el(
            "select",
            { name: "colour" },
            el("option", { value: "", text: "all" }),
            el("option", { value: "green", text: "green (in order)" }),
            el("option", { value: "orange", text: "orange (attention)" }),
            el("option", { value: "red", text: "red (fault)" }),
          ),
        ),
        el("label", {}, "Text", el("input", { type: "search", name: "text", placeholder: "name, place, status", autocomplete: "off" })),
        el("label", { class: "check" }, el("input", { type: "checkbox", name: "comm" }), "communication alarm only"),
        el(
          "label",
          {},
          "Language",
          el("select", { name: "lang", id: "lift-lang" }, el("option", { value: "en", text: "English" }), el("option", { value: "cs", text: "Čeština" })),
        ),
      ),
      el("div", { class: "lift-summary", id: "lift-summary" }),
      el(
        "div",
        { class: "table-wrap" },
        el(
          "table",
          { id: "lift-table", class: "list" },
          el(
            "thead",
            {},
            el(
              "tr",
              {},
              ...["Lift", "Description", "Status", "Floor", "Dir.", "Doors", "Communication", "Last fault"].map((t) => el("th", { text: t })),
            ),
          ),
          el("tbody"),
        ),
      ),
      el("p", { id: "lift-empty", class: "muted", hidden: true, text: "No lift matches." }),
    );
    const form = document.getElementById("lift-filter");
    form.addEventListener("input", () => renderFleet());
    form.addEventListener("submit", (event) => event.preventDefault());
    form.lang.addEventListener("change", () => setLang(form.lang.value));
  }

  function fleetRow(lift) {
    const s = liftState(lift);
    const row = el(
      "tr",
      { "data-lift": lift.name, "data-class": s.colour, class: "lift-row", tabindex: "0", title: `Open ${lift.name}` },
      el("td", { class: "name" }, el("a", { href: `#lift/${encodeURIComponent(lift.name)}`, text: lift.name })),
      el("td", { text: lift.description || "" }),
      mark(el("td", { class: `lift-status cls-${s.colour}`, "data-class": s.colour, text: s.text }), s.status.invalid),
      mark(el("td", { class: "floor", text: floorText(s.position) }), s.position.invalid),
      mark(el("td", { class: `dir dir-${s.directionInfo[0]}`, title: s.directionInfo[2], text: s.directionInfo[1] }), s.direction.invalid),
      mark(el("td", { class: `door door-${s.doorInfo[0]}`, "data-door": s.doorInfo[0], text: L.lang === "cs" ? s.doorInfo[2] : s.doorInfo[1] }), s.door.invalid),
      mark(
        el("td", { class: s.commAlarm ? "comm alarm" : "comm", "data-alarm": String(s.commAlarm), text: s.commAlarm ? "NOT ANSWERING" : s.comm.value === null ? "—" : "ok" }),
        s.comm.invalid,
      ),
      el("td", { class: "last-fault", text: lastFaultText(s.lastFault) }),
    );
    row.addEventListener("click", (event) => {
      if (event.target.closest("a")) return;
      window.location.hash = `#lift/${encodeURIComponent(lift.name)}`;
    });
    row.addEventListener("keydown", (event) => {
      if (event.key === "Enter") window.location.hash = `#lift/${encodeURIComponent(lift.name)}`;
    });
    return { row, state: s };
  }

  function renderFleet() {
    if (!fleet.shown) return;
    const form = document.getElementById("lift-filter");
    const colour = form.colour.value;
    const text = form.text.value.trim().toLowerCase();
    const commOnly = form.comm.checked;
    const counts = { green: 0, orange: 0, red: 0, unknown: 0, comm: 0 };
    const rows = [];
    for (const lift of lifts()) {
      const { row, state } = fleetRow(lift);
      counts[state.colour] = (counts[state.colour] || 0) + 1;
      if (state.commAlarm) counts.comm += 1;
      if (colour && state.colour !== colour) continue;
      if (commOnly && !state.commAlarm) continue;
      if (text && ![lift.name, lift.description || "", state.text].some((t) => t.toLowerCase().includes(text))) continue;
      rows.push(row);
    }
    document.querySelector("#lift-table tbody").replaceChildren(...rows);
    document.getElementById("lift-empty").hidden = rows.length > 0;
    document
      .getElementById("lift-summary")
      .replaceChildren(
        el("span", { class: "pill cls-green", text: `${counts.green} green` }),
        el("span", { class: "pill cls-orange", text: `${counts.orange} orange` }),
        el("span", { class: "pill cls-red", text: `${counts.red} red` }),
        el("span", { class: counts.comm ? "pill comm-alarm" : "pill", text: `${counts.comm} not answering` }),
      );
  }

  // ------------------------------------------------------------------ lift view
  const view = { name: null };

  function buildLift() {
    section(
      "lift",
      el("div", { id: "lift-status", class: "lift-banner", "data-class": "unknown" }, el("span", { id: "lift-status-text" })),
      el(
        "div",
        { class: "lift-layout" },
        el(
          "nav",
          { class: "lift-side", "aria-label": "Lift windows" },
          el("h2", { id: "lift-title" }),
          el("p", { id: "lift-description", class: "muted" }),
          el("a", { href: "#lifts", class: "button-link", text: "◂ Fleet" }),
          el("a", { id: "lift-archive-link", href: "#faults", class: "button-link", text: "Fault archive" }),
          el("a", { href: "#mobile", class: "button-link", text: "Mobile view" }),
          el("a", { id: "lift-figures-link", href: "#figures", class: "button-link", text: "Service figures" }),
          el("dl", { class: "facts", id: "lift-facts" }),
        ),
        el(
          "div",
          { class: "lift-car-wrap" },
          el(
            "div",
            { class: "lift-travel" },
            el("div", {}, el("span", { class: "muted", text: "Floor " }), el("strong", { id: "lift-floor", text: "—" })),
            el("div", {}, el("span", { id: "lift-direction", class: "dir", text: "■" })),
            el("div", {}, el("span", { class: "muted", text: "Target " }), el("strong", { id: "lift-target", text: "—" })),
          ),
          carSvg(),
          el("p", { id: "lift-door-text", class: "muted" }),
        ),
        el("div", { class: "lift-panel-wrap" }, el("div", { id: "lift-panel", class: "cop", "aria-label": "Car operating panel (display only)" })),
      ),
      el("h3", { text: "Trips per floor" }),
      el("div", { id: "lift-trips", class: "bars" }),
      el("div", { id: "lift-figures-box" }),
    );
  }

  function carSvg() {
    return svg(
      "svg",
      { id: "lift-car", viewBox: "0 0 200 240", class: "lift-car", role: "img", "aria-label": "Car and doors" },
      svg("rect", { x: "10", y: "10", width: "180", height: "220", rx: "6", class: "shaft" }),
      svg("rect", { x: "30", y: "30", width: "140", height: "190", class: "car" }),
      svg("rect", { id: "lift-door-left", x: "30", y: "30", width: "70", height: "190", class: "leaf" }),
      svg("rect", { id: "lift-door-right", x: "100", y: "30", width: "70", height: "190", class: "leaf" }),
      svg("text", { id: "lift-door-mark", x: "100", y: "130", "text-anchor": "middle", class: "door-mark", text: "" }),
    );
  }

  function buildPanel(lift) {
    const panel = document.getElementById("lift-panel");
    const buttons = [];
    for (let floor = lift.floors; floor >= 1; floor -= 1) {
      buttons.push(el("span", { class: "cop-button", "data-floor": String(floor), text: String(floor) }));
    }
    panel.replaceChildren(
      el("div", { class: "cop-display", id: "cop-display", text: "—" }),
      el("div", { class: "cop-floors" }, ...buttons),
      el(
        "div",
        { class: "cop-keys" },
        el("span", { class: "cop-button door-open", title: "door open", text: "◂|▸" }),
        el("span", { class: "cop-button alarm", title: "alarm", text: "🔔" }),
        el("span", { class: "cop-key", title: "priority key", text: "⚿" }),
      ),
      el("p", { class: "muted small", text: "Display only: this HMI never controls the lift." }),
    );
  }

  function renderLift() {
    const lift = findLift(view.name);
    if (!lift) return;
    const s = liftState(lift);
    const banner = document.getElementById("lift-status");
    banner.dataset.class = s.colour;
    mark(banner, s.status.invalid);
    const code = s.status.value === null ? "" : ` (${s.status.value})`;
    document.getElementById("lift-status-text").textContent = `${lift.name}: ${s.text}${code}${s.commAlarm ? " — NOT ANSWERING" : ""}`;
    mark(document.getElementById("lift-floor"), s.position.invalid).textContent = floorText(s.position);
    mark(document.getElementById("lift-target"), s.target.invalid).textContent =
      s.directionInfo[0] === "stopped" || s.target.value === null ? "—" : String(s.target.value);
    const direction = mark(document.getElementById("lift-direction"), s.direction.invalid);
    direction.textContent = `${s.directionInfo[1]} ${s.directionInfo[2]}`;
    direction.className = `dir dir-${s.directionInfo[0]}`;
    const car = mark(document.getElementById("lift-car"), s.door.invalid);
    car.dataset.door = s.doorInfo[0];
    document.getElementById("lift-door-mark").textContent = s.doorInfo[0] === "fault" ? "!" : "";
    document.getElementById("lift-door-text").textContent = `Doors: ${L.lang === "cs" ? s.doorInfo[2] : s.doorInfo[1]}`;
    mark(document.getElementById("cop-display"), s.position.invalid).textContent = floorText(s.position);
    for (const button of document.querySelectorAll("#lift-panel .cop-button[data-floor]")) {
      button.classList.toggle("lit", s.position.value !== null && Number(button.dataset.floor) === s.position.value);
      button.classList.toggle("target", s.target.value !== null && s.directionInfo[0] !== "stopped" && Number(button.dataset.floor) === s.target.value);
    }
    const facts = document.getElementById("lift-facts");
    const yesNo = (r) => (r.value === null ? "—" : r.value ? "yes" : "no");
    facts.replaceChildren(
      el("dt", { text: "Communication" }),
      mark(el("dd", { class: s.commAlarm ? "alarm" : "", text: s.commAlarm ? "not answering" : "ok" }), s.comm.invalid),
      el("dt", { text: "Out of service" }),
      el("dd", { text: yesNo(s.oos) }),
      el("dt", { text: "Inspection" }),
      el("dd", { text: yesNo(s.inspection) }),
      el("dt", { text: "Last fault" }),
      el("dd", { text: lastFaultText(s.lastFault) }),
      el("dt", { text: "Faults archived" }),
      el("dd", { text: floorText(s.faults) }),
      el("dt", { text: "Trips" }),
      el("dd", { text: floorText(s.totalTrips) }),
    );
    renderTrips(s.trips);
  }

  function renderTrips(trips) {
    const box = document.getElementById("lift-trips");
    const max = Math.max(1, ...trips.map((t) => t.value || 0));
    box.replaceChildren(
      ...trips.map((trip, index) =>
        el(
          "div",
          { class: "bar-row", "data-floor": String(index + 1) },
          el("span", { class: "bar-label", text: `${index + 1}` }),
          el("span", { class: "bar-track" }, mark(el("span", { class: "bar", style: `width: ${((trip.value || 0) / max) * 100}%` }), trip.invalid)),
          el("span", { class: "bar-value", text: trip.value === null ? "—" : String(trip.value) }),
        ),
      ),
    );
  }

  function showLift(name) {
    const lift = findLift(name) || lifts()[0];
    const page = document.getElementById("page-lift");
    if (!allowed("lift")) {
      page.replaceChildren(refusedText("lift view"));
      return;
    }
    if (!lift) return;
    view.name = lift.name;
    document.getElementById("lift-title").textContent = lift.name;
    document.getElementById("lift-description").textContent = lift.description || "";
    const archiveLink = document.getElementById("lift-archive-link");
    archiveLink.href = `#faults/${encodeURIComponent(lift.name)}`;
    archiveLink.hidden = !allowed("archive") || !L.config.archive;
    document.getElementById("lift-figures-link").hidden = !allowed("figures") || !L.config.archive;
    buildPanel(lift);
    renderLift();
    const box = document.getElementById("lift-figures-box");
    box.replaceChildren();
    if (allowed("figures") && L.config.archive) {
      box.append(el("h3", { text: "Service figures (30 days)" }), el("div", { id: "lift-figures", class: "figures muted", text: "loading…" }));
      HMI.api(`/api/lifts/${encodeURIComponent(lift.name)}/figures?days=30`)
        .then((result) => {
          const target = document.getElementById("lift-figures");
          if (target && view.name === lift.name) target.replaceChildren(figureList(result.figures));
        })
        .catch((error) => {
          const target = document.getElementById("lift-figures");
          if (target) target.textContent = `Cannot load the figures: ${error.message}`;
        });
    }
  }

  // ------------------------------------------------------------------ fault archive
  const archive = {
    shown: false,
    offset: 0,
    limit: PAGE_SIZE_DEFAULT,
    sort: "board_time",
    desc: true,
    total: 0,
    loading: false,
    again: false,
    timer: null,
  };

  function buildArchive() {
    const columns = [
      ["board_time", "Date"],
      [null, "Time"],
      ["lift", "Lift"],
      ["code", "Code"],
      [null, "English", "col-en"],
      [null, "Czech", "col-cs"],
      ["floor", "Floor"],
      [null, "Target"],
      ["received", "Received"],
    ];
    section(
      "faults",
      el("h2", { text: "Fault archive" }),
      el(
        "form",
        { id: "fault-filter", class: "filters" },
        el("label", {}, "Lift", el("select", { name: "lift", id: "fault-lift" }, el("option", { value: "", text: "all" }))),
        el("label", {}, "Code (hex)", el("input", { type: "text", name: "code", size: "6", placeholder: "3C", autocomplete: "off" })),
        el("label", {}, "Text", el("input", { type: "search", name: "q", placeholder: "English or Czech", autocomplete: "off" })),
        el("label", {}, "From", el("input", { type: "date", name: "since" })),
        el("label", {}, "To", el("input", { type: "date", name: "until" })),
        el(
          "label",
          {},
          "Texts",
          el(
            "select",
            { name: "texts", id: "fault-texts" },
            el("option", { value: "both", text: "English + Czech" }),
            el("option", { value: "en", text: "English" }),
            el("option", { value: "cs", text: "Czech" }),
          ),
        ),
        el("label", {}, "Rows", el("select", { name: "limit" }, ...[10, 25, 50, 100].map((n) => el("option", { value: String(n), text: String(n), selected: n === PAGE_SIZE_DEFAULT })))),
        el("span", { class: "buttons" }, el("button", { type: "submit", text: "Show" }), el("button", { type: "reset", class: "secondary", text: "Clear" })),
        el("button", { type: "button", id: "faults-export", class: "secondary", text: "Export CSV" }),
      ),
      el("p", { id: "faults-message", class: "muted", hidden: true }),
      el(
        "div",
        { class: "table-wrap" },
        el(
          "table",
          { id: "fault-table", class: "list sortable", "data-texts": "both" },
          el("thead", {}, el("tr", {}, ...columns.map(([sort, title, cls]) => el("th", { "data-sort": sort || undefined, class: cls, text: title })))),
          el("tbody"),
        ),
      ),
      el(
        "div",
        { class: "pager" },
        el("button", { type: "button", id: "faults-first", class: "secondary", text: "⇤ First" }),
        el("button", { type: "button", id: "faults-prev", class: "secondary", text: "← Previous" }),
        el("span", { id: "faults-page", class: "muted" }),
        el("button", { type: "button", id: "faults-next", class: "secondary", text: "Next →" }),
        el("span", { id: "faults-total", class: "muted" }),
      ),
      el(
        "div",
        { id: "notifications", hidden: true },
        el("h3", { text: "Notifications sent" }),
        el(
          "div",
          { class: "table-wrap" },
          el(
            "table",
            { id: "notification-table", class: "list" },
            el("thead", {}, el("tr", {}, ...["Time", "Lift", "Rule", "Channel", "To", "Subject", "Outcome", "Detail"].map((title) => el("th", { text: title })))),
            el("tbody"),
          ),
        ),
      ),
    );
    const form = document.getElementById("fault-filter");
    form.addEventListener("submit", (event) => {
      event.preventDefault();
      archive.offset = 0;
      loadArchive();
      loadNotifications();
    });
    form.addEventListener("reset", () =>
      setTimeout(() => {
        archive.offset = 0;
        loadArchive();
      }),
    );
    form.lift.addEventListener("change", () => {
      archive.offset = 0;
      loadArchive();
    });
    form.limit.addEventListener("change", () => {
      archive.offset = 0;
      loadArchive();
    });
    form.texts.addEventListener("change", () => {
      document.getElementById("fault-table").dataset.texts = form.texts.value;
    });
    for (const th of document.querySelectorAll("#fault-table th[data-sort]")) {
      th.addEventListener("click", () => {
        const sort = th.dataset.sort;
        if (archive.sort === sort) archive.desc = !archive.desc;
        else {
          archive.sort = sort;
          archive.desc = sort === "board_time" || sort === "received";
        }
        archive.offset = 0;
        loadArchive();
      });
    }
    document.getElementById("faults-first").addEventListener("click", () => {
      archive.offset = 0;
      loadArchive();
    });
    document.getElementById("faults-prev").addEventListener("click", () => {
      archive.offset = Math.max(0, archive.offset - archive.limit);
      loadArchive();
    });
    document.getElementById("faults-next").addEventListener("click", () => {
      if (archive.offset + archive.limit < archive.total) archive.offset += archive.limit;
      loadArchive();
    });
    document.getElementById("faults-export").addEventListener("click", () => {
      // A link to the CSV: the browser downloads it (Content-Disposition: attachment).
      const link = el("a", { href: `/api/lifts/faults.csv?${archiveParameters(false)}`, download: "lift-faults.csv" });
      document.body.append(link);
      link.click();
      link.remove();
    });
  }

  /** The archive's query string from the filter form (and the page, unless for export). */
  function archiveParameters(withPage = true) {
    const form = document.getElementById("fault-filter");
    const parameters = new URLSearchParams();
    for (const name of ["lift", "code", "q", "since", "until"]) {
      const value = form[name].value.trim();
      if (value) parameters.set(name, value);
    }
    parameters.set("sort", archive.sort);
    parameters.set("desc", String(archive.desc));
    parameters.set("lang", L.lang);
    if (withPage) {
      archive.limit = Number(form.limit.value) || PAGE_SIZE_DEFAULT;
      parameters.set("offset", String(archive.offset));
      parameters.set("limit", String(archive.limit));
    }
    return parameters;
  }
  L.archiveParameters = archiveParameters;

  function faultRow(row) {
    return el(
      "tr",
      { "data-code": row.hex, "data-lift": row.lift, "data-id": row.id || "" },
      el("td", { class: "time", text: row.date || "—" }),
      el("td", { class: "time", text: row.time || "—" }),
      el("td", { text: row.lift }),
      el("td", { class: "code", text: row.hex }),
      el("td", { class: "col-en", text: row.english }),
      el("td", { class: "col-cs", text: row.czech }),
      el("td", { text: String(row.floor) }),
      el("td", { text: row.target ? String(row.target) : "—" }),
      el("td", { class: "time", text: HMI.formatTime(row.received) }),
    );
  }

  async function loadArchive() {
    const page = document.getElementById("page-faults");
    if (archive.loading) {
      archive.again = true;
      return;
    }
    archive.loading = true;
    page.setAttribute("aria-busy", "true");
    const body = document.querySelector("#fault-table tbody");
    const message = document.getElementById("faults-message");
    try {
      const result = await HMI.api(`/api/lifts/faults?${archiveParameters(true)}`);
      archive.total = result.total;
      body.replaceChildren(...result.rows.map(faultRow));
      message.hidden = result.rows.length > 0;
      message.textContent = "No faults match.";
      const pages = Math.max(1, Math.ceil(result.total / archive.limit));
      document.getElementById("faults-page").textContent = `page ${Math.floor(archive.offset / archive.limit) + 1} of ${pages}`;
      document.getElementById("faults-total").textContent = `${result.total} fault(s)`;
      page.dataset.total = String(result.total);
    } catch (error) {
      body.replaceChildren();
      message.hidden = false;
      message.textContent = `Cannot load the archive: ${error.message}`;
      archive.total = 0;
    } finally {
      for (const th of document.querySelectorAll("#fault-table th[data-sort]")) {
        if (th.dataset.sort === archive.sort) th.dataset.dir = archive.desc ? "desc" : "asc";
        else delete th.dataset.dir;
      }
      document.getElementById("faults-prev").disabled = archive.offset === 0;
      document.getElementById("faults-first").disabled = archive.offset === 0;
      document.getElementById("faults-next").disabled = archive.offset + archive.limit >= archive.total;
      archive.loading = false;
      page.removeAttribute("aria-busy");
      page.dataset.loaded = String(Date.now());
      if (archive.again) {
        archive.again = false;
        loadArchive();
      }
    }
  }

  /** The newest notifications (who was told of which lift's fault), with the archive. */
  async function loadNotifications() {
    const box = document.getElementById("notifications");
    if (!box) return;
    box.hidden = !allowed("notifications") || !L.config.archive;
    if (box.hidden) return;
    const form = document.getElementById("fault-filter");
    const parameters = new URLSearchParams({ limit: "20" });
    if (form && form.lift.value) parameters.set("lift", form.lift.value);
    try {
      const result = await HMI.api(`/api/lifts/notifications?${parameters}`);
      document.querySelector("#notification-table tbody").replaceChildren(
        ...result.rows.map((row) =>
          el(
            "tr",
            { "data-outcome": row.outcome },
            el("td", { class: "time", text: HMI.formatTime(row.time) }),
            el("td", { text: row.lift }),
            el("td", { text: row.rule }),
            el("td", { text: row.channel }),
            el("td", { text: row.recipient }),
            el("td", { text: row.subject }),
            el("td", { text: row.outcome }),
            el("td", { text: row.detail }),
          ),
        ),
      );
      box.dataset.total = String(result.total);
    } catch (error) {
      box.hidden = true;
    }
  }

  function showArchive(argument) {
    const page = document.getElementById("page-faults");
    if (!allowed("archive")) {
      page.replaceChildren(refusedText("fault archive"));
      return;
    }
    if (!L.config.archive) {
      document.getElementById("faults-message").hidden = false;
      document.getElementById("faults-message").textContent = "No archive: this HMI runs without the station's store.";
      return;
    }
    document.getElementById("faults-export").hidden = !allowed("export");
    const form = document.getElementById("fault-filter");
    if (argument && findLift(argument)) form.lift.value = argument;
    archive.offset = 0;
    loadArchive();
    loadNotifications();
  }

  /** A lift's fault counter changed: the archive (and the phone list) show it at once. */
  function faultsChanged(point) {
    if (!point || typeof point.name !== "string" || !point.name.endsWith(".faults")) return;
    const name = point.name.slice(0, -".faults".length);
    if (!findLift(name)) return;
    // Changes within 50 ms make one reload; a pending reload is not pushed back, so a
    // fleet whose counters change all the time still sees its archive every 50 ms.
    const form = document.getElementById("fault-filter");
    if (!form || !form.lift.value || form.lift.value === name) archive.changed = true;
    if (archive.timer) return;
    archive.timer = setTimeout(() => {
      archive.timer = null;
      if (archive.shown && archive.changed) {
        loadArchive();
        // The notice of a new fault goes out after it is archived: look again shortly.
        setTimeout(loadNotifications, 1000);
      }
      archive.changed = false;
      if (mobile.shown) loadMobileFaults();
    }, 50);
  }

  // ------------------------------------------------------------------ figures
  const figures = { days: 30 };

  function hours(seconds) {
    if (seconds === null || seconds === undefined) return "—";
    if (seconds < 3600) return `${Math.round(seconds / 60)} min`;
    return `${(seconds / 3600).toFixed(1)} h`;
  }
  function percent(value) {
    return value === null || value === undefined ? "—" : `${(value * 100).toFixed(2)} %`;
  }
  function fixed(value, digits = 1) {
    return typeof value === "number" && Number.isFinite(value) ? value.toFixed(digits) : "—";
  }

  function figureList(f) {
    const facts = [
      ["Availability", percent(f.availability)],
      ["Failures", String(f.failures)],
      ["Callbacks", String(f.callbacks)],
      ["Failures per year", fixed(f.failures_per_year ?? f.failures_per_lift_year)],
      ["Faults per year", fixed(f.faults_per_year ?? f.faults_per_lift_year)],
      ["Callbacks per year", fixed(f.callbacks_per_year ?? f.callbacks_per_lift_year)],
      ["MTBF", hours(f.mtbf)],
      ["MTTR", hours(f.mttr)],
      ["Out of service", hours(f.out_of_service)],
      ["Inspection", hours(f.inspection)],
      ["Trips", String(f.trips)],
      ["Door cycles", String(f.door_cycles)],
    ];
    if (f.trips_per_day !== undefined) facts.push(["Trips per day", fixed(f.trips_per_day)]);
    if (f.parking_floor !== undefined) facts.push(["Suggested parking floor", f.parking_floor === null ? "—" : String(f.parking_floor)]);
    const groups = Object.entries(f.faults_by_group || {});
    if (groups.length) facts.push(["Fault groups", groups.map(([group, count]) => `${group}: ${count}`).join(", ")]);
    return el("dl", { class: "facts" }, ...facts.flatMap(([name, value]) => [el("dt", { text: name }), el("dd", { text: value })]));
  }

  function buildFigures() {
    section(
      "figures",
      el("h2", { text: "Service figures" }),
      el(
        "div",
        { class: "filters" },
        el(
          "span",
          { class: "buttons" },
          el("button", { type: "button", "data-days": "30", text: "30 days" }),
          el("button", { type: "button", "data-days": "365", text: "365 days" }),
        ),
        el("span", { id: "figures-period", class: "muted" }),
      ),
      el("div", { id: "figures-fleet", class: "figures" }),
      el(
        "div",
        { class: "table-wrap" },
        el(
          "table",
          { id: "figures-table", class: "list" },
          el(
            "thead",
            {},
            el(
              "tr",
              {},
              ...["Lift", "Availability", "Failures", "Callbacks", "Faults/year", "MTBF", "MTTR", "Trips/day", "Door cycles", "Parking floor"].map((t) => el("th", { text: t })),
            ),
          ),
          el("tbody"),
        ),
      ),
    );
    for (const button of document.querySelectorAll("#page-figures [data-days]")) {
      button.addEventListener("click", () => {
        figures.days = Number(button.dataset.days);
        loadFigures();
      });
    }
  }

  async function loadFigures() {
    const page = document.getElementById("page-figures");
    const fleetBox = document.getElementById("figures-fleet");
    page.setAttribute("aria-busy", "true");
    try {
      const result = await HMI.api(`/api/lifts/figures?days=${figures.days}`);
      document.getElementById("figures-period").textContent = `${HMI.formatTime(result.period.from)} – ${HMI.formatTime(result.period.to)}`;
      fleetBox.replaceChildren(el("h3", { text: `Fleet (${result.fleet.lifts} lifts)` }), figureList(result.fleet));
      document.querySelector("#figures-table tbody").replaceChildren(
        ...result.lifts.map(({ name, figures: f, truncated }) =>
          el(
            "tr",
            { "data-lift": name },
            el("td", {}, el("a", { href: `#lift/${encodeURIComponent(name)}`, text: truncated ? `${name} (history cut)` : name })),
            el("td", { text: percent(f.availability) }),
            el("td", { text: String(f.failures) }),
            el("td", { text: String(f.callbacks) }),
            el("td", { text: fixed(f.faults_per_year) }),
            el("td", { text: hours(f.mtbf) }),
            el("td", { text: hours(f.mttr) }),
            el("td", { text: fixed(f.trips_per_day) }),
            el("td", { text: String(f.door_cycles) }),
            el("td", { text: f.parking_floor === null ? "—" : String(f.parking_floor) }),
          ),
        ),
      );
    } catch (error) {
      fleetBox.replaceChildren(el("p", { class: "muted", text: `Cannot load the figures: ${error.message}` }));
    } finally {
      page.removeAttribute("aria-busy");
      page.dataset.loaded = String(Date.now());
    }
  }

  // ------------------------------------------------------------------ mobile view
  const mobile = { shown: false };

  function buildMobile() {
    section(
      "mobile",
      el("h2", { text: "Lifts" }),
      el("div", { id: "mobile-lifts", class: "mobile-lifts" }),
      el("h3", { text: "Faults" }),
      el(
        "div",
        { class: "table-wrap" },
        el(
          "table",
          { id: "mobile-faults", class: "list" },
          el("thead", {}, el("tr", {}, el("th", { text: "Date" }), el("th", { text: "Time" }), el("th", { text: "Fault description" }))),
          el("tbody"),
        ),
      ),
    );
  }

  function renderMobile() {
    if (!mobile.shown) return;
    document.getElementById("mobile-lifts").replaceChildren(
      ...lifts().map((lift) => {
        const s = liftState(lift);
        return el(
          "a",
          { class: "mobile-lift", href: `#lift/${encodeURIComponent(lift.name)}`, "data-lift": lift.name, "data-class": s.colour },
          el("span", { class: "name", text: lift.name }),
          mark(el("span", { class: `lift-status cls-${s.colour}`, text: s.text }), s.status.invalid),
          mark(el("span", { class: "floor", text: `floor ${floorText(s.position)} ${s.directionInfo[1]}` }), s.position.invalid),
          el("span", { class: `door door-${s.doorInfo[0]}`, text: L.lang === "cs" ? s.doorInfo[2] : s.doorInfo[1] }),
          s.commAlarm ? el("span", { class: "comm alarm", "data-alarm": "true", text: "NOT ANSWERING" }) : null,
        );
      }),
    );
  }

  async function loadMobileFaults() {
    const body = document.querySelector("#mobile-faults tbody");
    if (!allowed("archive") || !L.config.archive) {
      body.replaceChildren(el("tr", {}, el("td", { colspan: "3", class: "muted", text: L.config.archive ? "Your level does not reach the archive." : "No archive." })));
      return;
    }
    try {
      const result = await HMI.api(`/api/lifts/faults?limit=22&lang=${L.lang}`);
      body.replaceChildren(
        ...result.rows.map((row) =>
          el(
            "tr",
            { "data-code": row.hex, "data-lift": row.lift },
            el("td", { class: "time", text: row.date || "—" }),
            el("td", { class: "time", text: row.time || "—" }),
            el("td", { text: `${row.lift}: ${row.text}` }),
          ),
        ),
      );
    } catch (error) {
      body.replaceChildren(el("tr", {}, el("td", { colspan: "3", class: "muted", text: `Cannot load the faults: ${error.message}` })));
    }
    document.getElementById("page-mobile").dataset.loaded = String(Date.now());
  }

  // ------------------------------------------------------------------ language, live updates
  function setLang(lang) {
    L.lang = lang === "cs" ? "cs" : "en";
    const select = document.getElementById("lift-lang");
    if (select) select.value = L.lang;
    renderFleet();
    if (view.name && HMI.current && HMI.current.page === "lift") renderLift();
    renderMobile();
    if (mobile.shown) loadMobileFaults();
  }

  let frame = null;
  function renderSoon() {
    if (frame !== null) return;
    frame = requestAnimationFrame(() => {
      frame = null;
      renderFleet();
      if (HMI.current && HMI.current.page === "lift") renderLift();
      renderMobile();
    });
  }
  HMI.on("point", (point) => {
    if (!L.config || !lifts().length) return;
    faultsChanged(point);
    renderSoon();
  });
  for (const type of ["snapshot", "link", "connection"]) HMI.on(type, renderSoon);

  HMI.on("ready", () => {
    const config = HMI.liftConfig;
    if (!config || !Array.isArray(config.lifts) || !config.lifts.length) return;
    L.config = config;
    for (const status of config.statuses || []) L.statuses.set(status.code, status);
    for (const fault of config.faults || []) L.faultCodes.set(fault.code, fault);
    buildFleet();
    buildLift();
    buildArchive();
    buildFigures();
    buildMobile();
    const select = document.getElementById("fault-lift");
    for (const lift of lifts()) select.append(el("option", { value: lift.name, text: lift.name }));
    const links = [];
    if (allowed("fleet")) links.push(["lifts", "Lifts"]);
    if (allowed("archive") && config.archive) links.push(["faults", "Fault archive"]);
    if (allowed("figures") && config.archive) links.push(["figures", "Figures"]);
    if (allowed("fleet")) links.push(["mobile", "Mobile"]);
    const nav = document.getElementById("nav-pages");
    nav.prepend(
      ...links.map(([page, title]) => el("li", { "data-lift-nav": page }, el("a", { href: `#${page}`, "data-page-link": page, text: title }))),
    );
    HMI.pages.lifts = {
      show() {
        fleet.shown = true;
        if (!allowed("fleet")) document.getElementById("page-lifts").replaceChildren(refusedText("fleet list"));
        else renderFleet();
      },
      hide() {
        fleet.shown = false;
      },
    };
    HMI.pages.lift = {
      show: showLift,
      hide() {
        view.name = null;
      },
    };
    HMI.pages.faults = {
      show(argument) {
        archive.shown = true;
        showArchive(argument);
      },
      hide() {
        archive.shown = false;
      },
    };
    HMI.pages.figures = {
      show() {
        if (!allowed("figures")) document.getElementById("page-figures").replaceChildren(refusedText("service figures"));
        else if (config.archive) loadFigures();
      },
    };
    HMI.pages.mobile = {
      show() {
        mobile.shown = true;
        if (!allowed("fleet")) {
          document.getElementById("page-mobile").replaceChildren(refusedText("mobile view"));
          return;
        }
        renderMobile();
        loadMobileFaults();
      },
      hide() {
        mobile.shown = false;
      },
    };
  });
})();
