// Stanice web HMI — the event list: value changes and commands from the HMI's own event
// store and the station's command audit (GET /api/events: the commands of every IEC 104
// client, dispatch's included, when the HMI reads the station's store), newest first,
// filtered by time, point (name or prefix*), kind and user, paged with the server's `next`
// cursor over any length of history. Columns: time, kind, point, value, origin (the HMI
// user, or the client's address in the station's audit), outcome, reason (a refusal in
// the station's words).
"use strict";

(function () {
  const PAGE_SIZE = 50;
  let cursors = [null]; // the cursor of each page seen; cursors[i] loads page i
  let page = 0;
  let next = null;
  let loading = false;
  let shown = false;
  let refreshTimer = null;

  const form = () => document.getElementById("event-filter");

  /** A datetime-local value (local time) as RFC 3339. */
  function rfc3339(local) {
    if (!local) return null;
    const date = new Date(local);
    return Number.isNaN(date.getTime()) ? null : date.toISOString();
  }

  function query(cursor) {
    const f = form();
    const parameters = new URLSearchParams();
    const from = rfc3339(f.from.value);
    const to = rfc3339(f.to.value);
    if (from) parameters.set("from", from);
    if (to) parameters.set("to", to);
    if (f.point.value.trim()) parameters.set("point", f.point.value.trim());
    if (f.kind.value) parameters.set("kind", f.kind.value);
    if (f.user.value.trim()) parameters.set("user", f.user.value.trim());
    if (cursor) parameters.set("cursor", cursor);
    parameters.set("limit", String(PAGE_SIZE));
    return `/api/events?${parameters}`;
  }

  function outcomeClass(outcome) {
    if (!outcome) return "";
    const word = String(outcome).toLowerCase();
    return word === "executed" ? "outcome-executed" : "outcome-bad";
  }

  function row(event) {
    const point = HMI.points.get(event.point) || HMI.controls.get(event.point);
    const type = point && point.type;
    const isCommand = event.kind === "command";
    const value = event.invalid ? `${HMI.formatValue(event.value, type)} (invalid)` : isCommand ? String(event.value) : HMI.formatValue(event.value, type);
    const description = point && point.description ? point.description : "";
    return HMI.el(
      "tr",
      { "data-kind": event.kind, "data-id": event.id },
      HMI.el("td", { class: "time", text: HMI.formatTime(event.time, true) }),
      HMI.el("td", { class: isCommand ? "kind-command" : "", text: isCommand ? "command" : "value" }),
      HMI.el("td", { title: `IOA ${event.ioa}${description ? ` — ${description}` : ""}`, text: event.point }),
      HMI.el("td", { class: event.invalid ? "invalid" : "", text: value }),
      HMI.el("td", { class: "origin", title: event.source === "station" ? "from the station's command audit" : "", text: event.origin || event.user || "" }),
      HMI.el("td", { class: outcomeClass(event.outcome), title: event.detail || "", text: event.outcome || "" }),
      HMI.el("td", { class: "reason", text: event.reason || (event.outcome === "executed" ? "" : event.detail || "") }),
    );
  }

  async function load(index) {
    if (loading) return;
    loading = true;
    const body = document.querySelector("#event-table tbody");
    const section = document.getElementById("page-events");
    section.setAttribute("aria-busy", "true");
    try {
      const result = await HMI.api(query(cursors[index]));
      page = index;
      next = result.next || null;
      cursors = cursors.slice(0, index + 1);
      if (next) cursors.push(next);
      const items = result.items || [];
      const note = document.getElementById("events-note");
      note.textContent = result.note ? `Note: ${result.note}.` : "";
      note.hidden = !result.note;
      if (items.length) body.replaceChildren(...items.map(row));
      else body.replaceChildren(HMI.el("tr", {}, HMI.el("td", { colspan: "7", class: "muted", text: "No events match." })));
      document.getElementById("events-page").textContent = `page ${page + 1}${items.length ? `, ${items.length} event(s)` : ""}`;
    } catch (error) {
      body.replaceChildren(
        HMI.el("tr", {}, HMI.el("td", { colspan: "7", class: "muted", text: `Cannot load events: ${error.message}` })),
      );
      next = null;
    } finally {
      loading = false;
      section.removeAttribute("aria-busy");
      section.dataset.loaded = String(Date.now());
      document.getElementById("events-older").disabled = !next;
      document.getElementById("events-newer").disabled = page === 0;
      document.getElementById("events-newest").disabled = page === 0;
    }
  }

  /** The newest page follows the station while shown and not bounded by "to". */
  function refreshSoon() {
    if (!shown || page !== 0 || form().to.value) return;
    clearTimeout(refreshTimer);
    refreshTimer = setTimeout(() => load(0), 700);
  }

  HMI.on("ready", () => {
    const f = form();
    f.addEventListener("submit", (event) => {
      event.preventDefault();
      cursors = [null];
      load(0);
    });
    f.addEventListener("reset", () => {
      setTimeout(() => {
        cursors = [null];
        load(0);
      });
    });
    document.getElementById("events-older").addEventListener("click", () => next && load(page + 1));
    document.getElementById("events-newer").addEventListener("click", () => page > 0 && load(page - 1));
    document.getElementById("events-newest").addEventListener("click", () => load(0));
  });
  HMI.on("command", refreshSoon);

  let poll = null;
  HMI.pages.events = {
    show() {
      shown = true;
      load(page);
      clearInterval(poll);
      poll = setInterval(refreshSoon, 10000);
    },
    hide() {
      shown = false;
      clearInterval(poll);
    },
  };
})();
