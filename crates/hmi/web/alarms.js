// Stanice web HMI — alarms: the list (priority colours, sorting, filters, acknowledge,
// shelve for a time or one-shot, out of service), the alarm line in the header of every
// page, the badge in the navigation, the alarm KPI report page (#alarm-report, against
// EEMUA 191) and the alarm sound.
//
// The sound is generated with the WebAudio API (no audio files): it plays while an
// unacknowledged, unshelved alarm of priority 1 or 2 is active and the sound is switched
// on (the bell in the header; the choice is kept in this browser). Browsers start audio
// only after a user gesture on the page, so the context is created on the first click.
"use strict";

(function () {
  const SHELVE_MINUTES = [15, 30, 60, 240, 480];
  /** Shelving and out of service need this level (the server's SHELVE_LEVEL). */
  const SHELVE_LEVEL = 5;
  let sortKey = "priority";
  let sortDir = "asc";
  let shown = false;

  /** Shelved: the server ends a timed shelve itself (within a second) and says so. */
  function shelved(alarm) {
    return Boolean(alarm.shelved);
  }
  function unacknowledged(alarm) {
    return alarm.needs_acknowledgement !== false && !alarm.acknowledged && Boolean(alarm.raised);
  }
  /** As the server lists them: active, waiting for acknowledgement, shelved or out of service. */
  function listed(alarm) {
    return alarm.active || unacknowledged(alarm) || shelved(alarm) || Boolean(alarm.out_of_service);
  }
  /** Calls for the operator: unacknowledged, not shelved, not suppressed, in service. */
  function calling(alarm) {
    return unacknowledged(alarm) && !shelved(alarm) && !alarm.suppressed && !alarm.out_of_service;
  }
  /** The zone's short name at `date` ("CET", "GMT+1"), as this browser shows times. */
  function zoneName(date) {
    try {
      const part = new Intl.DateTimeFormat("en-GB", { timeZoneName: "short" }).formatToParts(date).find((p) => p.type === "timeZoneName");
      return part ? part.value : "";
    } catch (error) {
      return "";
    }
  }
  /** Date, time and zone: 2026-11-27 13:05:02 CET. */
  function when(time) {
    if (!time) return "—";
    const date = new Date(time);
    return `${HMI.formatTime(date)} ${zoneName(date)}`.trim();
  }
  function stateWords(alarm) {
    const words = [alarm.active ? "ACTIVE" : `cleared ${when(alarm.cleared)}`];
    if (unacknowledged(alarm)) words.push("unacknowledged");
    else if (alarm.acknowledged && alarm.raised) words.push("acknowledged");
    if (shelved(alarm)) {
      words.push(alarm.oneshot ? "shelved until it returns to normal" : `shelved until ${when(alarm.shelved_until)}`);
      if (alarm.shelve_reason) words.push(`reason: ${alarm.shelve_reason}`);
    }
    if (alarm.suppressed) words.push("suppressed by design");
    if (alarm.out_of_service) words.push(`out of service (${alarm.out_of_service.user}: ${alarm.out_of_service.reason})`);
    if (alarm.consequence_of !== null && alarm.consequence_of !== undefined) {
      const link = HMI.alarms.get(alarm.consequence_of);
      words.push(`consequence of ${link ? link.text : "a lost link"}`);
    }
    return words.join(", ");
  }

  function visible() {
    const f = document.getElementById("alarm-filter");
    const maxPriority = Number(f.priority.value) || 9;
    const state = f.state.value;
    const text = f.text.value.trim().toLowerCase();
    return [...HMI.alarms.values()].filter((alarm) => {
      if (!listed(alarm)) return false;
      if (alarm.priority > maxPriority) return false;
      if (state === "unack" && !unacknowledged(alarm)) return false;
      if (state === "active" && !alarm.active) return false;
      if (state === "shelved" && !shelved(alarm)) return false;
      if (state === "suppressed" && !alarm.suppressed) return false;
      if (state === "out" && !alarm.out_of_service) return false;
      if (state === "system" && !alarm.system) return false;
      if ((state === "unack" || state === "active") && shelved(alarm)) return false;
      if (text && !`${alarm.text} ${alarm.point}`.toLowerCase().includes(text)) return false;
      return true;
    });
  }

  function compare(a, b) {
    const key = (alarm) => {
      switch (sortKey) {
        case "raised":
          return alarm.raised ? Date.parse(alarm.raised) : 0;
        case "text":
          return alarm.text.toLowerCase();
        case "point":
          return alarm.point.toLowerCase();
        case "state":
          return (alarm.active ? 0 : 2) + (unacknowledged(alarm) ? 0 : 1) + (shelved(alarm) ? 4 : 0);
        default:
          return alarm.priority;
      }
    };
    const x = key(a);
    const y = key(b);
    let order = x < y ? -1 : x > y ? 1 : 0;
    if (sortDir === "desc") order = -order;
    if (order === 0) order = (b.raised ? Date.parse(b.raised) : 0) - (a.raised ? Date.parse(a.raised) : 0);
    return order;
  }

  async function act(alarm, what, body) {
    const result = await HMI.post(`/api/alarms/${alarm.id}/${what}`, body);
    if (!result.ok) {
      HMI.toast(`${alarm.text}: ${what} failed — ${result.body.error || `HTTP ${result.status}`}`, true);
      return;
    }
    if (result.body && result.body.id !== undefined) {
      HMI.alarms.set(result.body.id, result.body);
      update();
    }
  }

  /** Acknowledge / shelve / out-of-service buttons; a read-only user (level 0) watches
   * only, and shelving and out of service need level SHELVE_LEVEL. */
  function actionsFor(alarm) {
    const actions = HMI.el("td", { class: "actions" });
    if (!HMI.session || HMI.session.level === 0) {
      actions.append(HMI.el("span", { class: "muted", title: "Your level (0) is read-only.", text: "read-only" }));
      return actions;
    }
    if (unacknowledged(alarm)) {
      actions.append(HMI.el("button", { type: "button", class: "ack", text: "Acknowledge", onclick: () => act(alarm, "acknowledge") }), " ");
    }
    if (HMI.session.level < SHELVE_LEVEL) return actions;
    const reasonField = HMI.el("input", { type: "text", class: "reason", maxlength: "200", placeholder: "reason", "aria-label": "Reason" });
    const reason = () => reasonField.value.trim() || undefined;
    if (alarm.out_of_service) {
      actions.append(HMI.el("button", { type: "button", class: "secondary in-service", text: "Back in service", onclick: () => act(alarm, "in-service", {}) }));
      return actions;
    }
    if (shelved(alarm)) {
      actions.append(HMI.el("button", { type: "button", class: "secondary unshelve", text: "Unshelve", onclick: () => act(alarm, "unshelve", {}) }));
      return actions;
    }
    const options = SHELVE_MINUTES.map((m) => HMI.el("option", { value: String(m), text: m < 60 ? `${m} min` : `${m / 60} h` }));
    if (alarm.active) options.push(HMI.el("option", { value: "oneshot", text: "until normal" }));
    const select = HMI.el("select", { "aria-label": "Shelve for" }, ...options);
    const shelve = () =>
      act(alarm, "shelve", select.value === "oneshot" ? { oneshot: true, reason: reason() } : { minutes: Number(select.value), reason: reason() });
    const outOfService = () => {
      if (!reason()) {
        HMI.toast(`${alarm.text}: say why in the reason field to take it out of service`, true);
        reasonField.focus();
        return;
      }
      act(alarm, "out-of-service", { reason: reason() });
    };
    actions.append(
      HMI.el("button", { type: "button", class: "secondary shelve", text: "Shelve", onclick: shelve }),
      " ",
      select,
      " ",
      reasonField,
      " ",
      HMI.el("button", { type: "button", class: "secondary out-of-service", text: "Out of service", onclick: outOfService }),
    );
    return actions;
  }

  function row(alarm) {
    const actions = actionsFor(alarm);
    const classes = [alarm.active ? "active" : "cleared", unacknowledged(alarm) ? "unack" : "", shelved(alarm) ? "shelved" : ""].join(" ").trim();
    return HMI.el(
      "tr",
      { class: classes, "data-priority": String(alarm.priority), "data-id": String(alarm.id), "data-point": alarm.point },
      HMI.el("td", { class: "pri", text: String(alarm.priority) }),
      HMI.el("td", { class: "time", title: HMI.formatTime(alarm.raised, true), text: when(alarm.raised) }),
      HMI.el("td", { class: "text", text: alarm.text }),
      HMI.el("td", { text: alarm.point }),
      HMI.el("td", { class: "state", text: stateWords(alarm) }),
      actions,
    );
  }

  // Rows are kept by alarm id and rebuilt only when what they show changed. Rebuilding the
  // whole table on every update lost the operator's work: a shelve time picked in a row's
  // list went back to 15 min, and a click that began on a button as another alarm arrived
  // ended on its replacement and did nothing.
  const rowsById = new Map();

  /** Everything a row shows; equal signatures need no new row. */
  function signature(alarm) {
    return JSON.stringify([
      alarm.priority, when(alarm.raised), alarm.text, alarm.point, stateWords(alarm), alarm.active,
      unacknowledged(alarm), shelved(alarm), Boolean(alarm.out_of_service), HMI.session ? HMI.session.level : null,
    ]);
  }

  function render() {
    const alarms = visible().sort(compare);
    const tbody = document.querySelector("#alarm-table tbody");
    const wanted = new Set(alarms.map((alarm) => alarm.id));
    for (const [id, kept] of rowsById) {
      if (!wanted.has(id)) {
        kept.element.remove();
        rowsById.delete(id);
      }
    }
    alarms.forEach((alarm, index) => {
      const sig = signature(alarm);
      let kept = rowsById.get(alarm.id);
      if (!kept || kept.sig !== sig) {
        const element = row(alarm);
        const oldSelect = kept && kept.element.querySelector("select");
        const newSelect = element.querySelector("select");
        if (oldSelect && newSelect) newSelect.value = oldSelect.value;
        const oldReason = kept && kept.element.querySelector("input.reason");
        const newReason = element.querySelector("input.reason");
        if (oldReason && newReason) newReason.value = oldReason.value;
        if (kept) kept.element.replaceWith(element);
        kept = { sig, element };
        rowsById.set(alarm.id, kept);
      }
      // Move only rows out of place, so a row being used stays put in the DOM.
      if (tbody.children[index] !== kept.element) tbody.insertBefore(kept.element, tbody.children[index] || null);
    });
    document.getElementById("alarm-empty").hidden = alarms.length > 0;
    for (const th of document.querySelectorAll("#alarm-table th[data-sort]")) {
      if (th.dataset.sort === sortKey) th.dataset.dir = sortDir;
      else delete th.dataset.dir;
    }
  }

  /** The alarm line: the calling alarm of the highest priority, newest first. */
  function alarmLine() {
    const line = document.getElementById("alarm-line");
    if (!line) return;
    const waiting = [...HMI.alarms.values()].filter(calling);
    waiting.sort((a, b) => a.priority - b.priority || Date.parse(b.raised) - Date.parse(a.raised));
    const top = waiting[0];
    const text = document.getElementById("alarm-line-text");
    const more = document.getElementById("alarm-line-more");
    const ack = document.getElementById("alarm-line-ack");
    line.dataset.priority = top ? String(top.priority) : "0";
    line.dataset.id = top ? String(top.id) : "";
    line.classList.toggle("active", Boolean(top && top.active));
    if (!top) {
      text.textContent = "No unacknowledged alarms";
      more.textContent = "";
      ack.hidden = true;
      return;
    }
    text.textContent = `P${top.priority}  ${when(top.raised)}  ${top.text} (${top.point}) — ${top.active ? "ACTIVE" : "cleared"}`;
    text.title = stateWords(top);
    more.textContent = waiting.length > 1 ? `+${waiting.length - 1} more` : "";
    ack.hidden = !HMI.session || HMI.session.level === 0;
    ack.onclick = () => act(top, "acknowledge");
  }

  function badge() {
    const waiting = [...HMI.alarms.values()].filter((a) => listed(a) && !shelved(a) && !a.suppressed && !a.out_of_service);
    const element = document.getElementById("alarm-count");
    element.hidden = waiting.length === 0;
    element.textContent = String(waiting.length);
    const top = waiting.reduce((best, a) => Math.min(best, a.priority), 9);
    element.dataset.priority = String(top);
    element.classList.toggle("unack", waiting.some(unacknowledged));
    element.title = `${waiting.length} alarm(s), highest priority ${top}`;
  }

  function update() {
    badge();
    alarmLine();
    sound.check();
    if (shown) render();
  }

  // ------------------------------------------------------------------ sound
  const sound = {
    enabled: localStorage.getItem("stanice.sound") !== "off",
    context: null,
    timer: null,
    priority: 0,
    ensureContext() {
      if (!this.context) {
        const Context = window.AudioContext || window.webkitAudioContext;
        if (!Context) return;
        this.context = new Context();
      }
      if (this.context.state === "suspended") this.context.resume().catch(() => {});
    },
    /** The highest priority (1 or 2) that calls for sound now, or 0. */
    wanted() {
      if (!this.enabled) return 0;
      let best = 0;
      for (const alarm of HMI.alarms.values()) {
        if (alarm.active && calling(alarm) && alarm.priority <= 2) {
          if (!best || alarm.priority < best) best = alarm.priority;
        }
      }
      return best;
    },
    beep(frequency, start, length) {
      const ctx = this.context;
      const oscillator = ctx.createOscillator();
      const gain = ctx.createGain();
      oscillator.type = "square";
      oscillator.frequency.value = frequency;
      gain.gain.setValueAtTime(0.0001, start);
      gain.gain.exponentialRampToValueAtTime(0.08, start + 0.01);
      gain.gain.setValueAtTime(0.08, start + length - 0.03);
      gain.gain.exponentialRampToValueAtTime(0.0001, start + length);
      oscillator.connect(gain).connect(ctx.destination);
      oscillator.start(start);
      oscillator.stop(start + length + 0.02);
    },
    /** Priority 1: a fast two-tone call; priority 2: a single slower tone. */
    pattern() {
      if (!this.context || this.context.state !== "running") return;
      const t = this.context.currentTime + 0.02;
      if (this.priority === 1) {
        this.beep(988, t, 0.16);
        this.beep(740, t + 0.2, 0.16);
      } else {
        this.beep(660, t, 0.25);
      }
    },
    check() {
      const priority = this.wanted();
      document.body.dataset.sound = priority ? `playing-p${priority}` : "silent";
      if (priority === this.priority) return;
      this.priority = priority;
      clearInterval(this.timer);
      this.timer = null;
      if (!priority) return;
      this.ensureContext();
      this.pattern();
      this.timer = setInterval(() => this.pattern(), priority === 1 ? 1000 : 2000);
    },
    toggle() {
      this.enabled = !this.enabled;
      localStorage.setItem("stanice.sound", this.enabled ? "on" : "off");
      const button = document.getElementById("sound");
      button.setAttribute("aria-pressed", String(this.enabled));
      button.title = this.enabled ? "Alarm sound on (click to mute)" : "Alarm sound off (click to switch on)";
      if (this.enabled) this.ensureContext();
      this.check();
    },
  };

  HMI.on("ready", () => {
    const button = document.getElementById("sound");
    button.setAttribute("aria-pressed", String(sound.enabled));
    button.addEventListener("click", () => sound.toggle());
    // Audio may start only after a gesture on the page.
    const unlock = () => {
      if (sound.enabled) sound.ensureContext();
    };
    document.addEventListener("pointerdown", unlock, { capture: true });
    document.addEventListener("keydown", unlock, { capture: true });

    const f = document.getElementById("alarm-filter");
    f.addEventListener("input", render);
    f.addEventListener("submit", (event) => event.preventDefault());
    document.getElementById("alarm-ack-all").hidden = HMI.session && HMI.session.level === 0;
    // "Acknowledge shown" asks first, naming how many: one click must not acknowledge a
    // flood unread.
    const ackDialog = document.getElementById("alarm-ack-dialog");
    let toAcknowledge = [];
    document.getElementById("alarm-ack-all").addEventListener("click", () => {
      toAcknowledge = visible().filter(unacknowledged);
      if (!toAcknowledge.length) {
        HMI.toast("No unacknowledged alarm is shown.");
        return;
      }
      document.getElementById("alarm-ack-question").textContent =
        `Acknowledge the ${toAcknowledge.length} unacknowledged alarm(s) shown?`;
      ackDialog.showModal();
    });
    document.getElementById("alarm-ack-cancel").addEventListener("click", () => ackDialog.close());
    document.getElementById("alarm-ack-confirm").addEventListener("click", async () => {
      ackDialog.close();
      for (const alarm of toAcknowledge) await act(alarm, "acknowledge");
      toAcknowledge = [];
    });
    report.init();
    for (const th of document.querySelectorAll("#alarm-table th[data-sort]")) {
      th.addEventListener("click", () => {
        if (sortKey === th.dataset.sort) sortDir = sortDir === "asc" ? "desc" : "asc";
        else {
          sortKey = th.dataset.sort;
          sortDir = sortKey === "raised" ? "desc" : "asc";
        }
        render();
      });
    }
    // The server ends shelves and tells; the clock only refreshes what is drawn.
    setInterval(update, 30000);
  });
  HMI.on("alarms", update);

  HMI.pages.alarms = {
    show() {
      shown = true;
      render();
    },
    hide() {
      shown = false;
    },
  };
  HMI.alarmSound = sound;

  // ------------------------------------------------------------------ KPI report
  /** The EEMUA 191 targets the report is measured against. */
  const report = {
    data: null,
    loading: false,
    form: () => document.getElementById("kpi-form"),
    /** A datetime-local value in this browser's zone. */
    local(ms) {
      const d = new Date(ms);
      const p = HMI.pad;
      return `${d.getFullYear()}-${p(d.getMonth() + 1)}-${p(d.getDate())}T${p(d.getHours())}:${p(d.getMinutes())}:${p(d.getSeconds())}`;
    },
    /** The span of the last quick choice, kept ending "now" each time the page opens;
     * null once the operator types a period of their own. */
    span: 86400,
    range(seconds) {
      this.span = seconds;
      // Counted by the server's receive time: end at the next whole minute of this clock.
      const to = Math.ceil((Date.now() + 1000) / 60000) * 60000;
      this.form().to.value = this.local(to);
      this.form().from.value = this.local(to - seconds * 1000);
    },
    init() {
      this.range(this.span);
      for (const field of [this.form().from, this.form().to]) {
        field.addEventListener("input", () => {
          this.span = null;
        });
      }
      this.form().addEventListener("submit", (event) => {
        event.preventDefault();
        this.load();
      });
      for (const button of this.form().querySelectorAll("[data-kpi-range]")) {
        button.addEventListener("click", () => {
          this.range(Number(button.dataset.kpiRange));
          this.load();
        });
      }
    },
    async load() {
      const from = new Date(this.form().from.value);
      const to = new Date(this.form().to.value);
      if (Number.isNaN(from.getTime()) || Number.isNaN(to.getTime()) || from >= to) {
        HMI.toast("Choose a period: from before to.", true);
        return;
      }
      this.loading = true;
      try {
        const query = `from=${encodeURIComponent(from.toISOString())}&to=${encodeURIComponent(to.toISOString())}`;
        this.data = await HMI.api(`/api/alarms/kpi?${query}`);
        this.draw();
      } catch (error) {
        HMI.toast(`Alarm report: ${error.message}`, true);
      } finally {
        this.loading = false;
      }
    },
    draw() {
      const k = this.data;
      const total = Object.values(k.priority_distribution).reduce((a, b) => a + b, 0);
      const share = (n) => (total ? `${((100 * n) / total).toFixed(0)} %` : "—");
      const high = k.priority_distribution["1"] || 0;
      const medium = k.priority_distribution["2"] || 0;
      const low = (k.priority_distribution["3"] || 0) + (k.priority_distribution["4"] || 0);
      const hours = (Date.parse(k.to) - Date.parse(k.from)) / 3600000;
      const floodMinutes = k.floods.reduce((sum, f) => sum + (Date.parse(f.end) - Date.parse(f.start)) / 60000, 0);
      const rate = k.alarms_per_hour;
      const rows = [
        ["Alarms per hour (average)", rate.toFixed(2), "< 6 very likely acceptable (about 1 per 10 min); > 30 very likely over-demanding",
          rate < 6 ? "ok" : rate <= 30 ? "manageable" : "over", rate < 6 ? "very likely acceptable" : rate <= 30 ? "manageable" : "very likely over-demanding"],
        ["Peak alarms per 10 min", String(k.peak_per_10min), "< 10", k.peak_per_10min < 10 ? "ok" : "over", k.peak_per_10min < 10 ? "met" : "not met"],
        ["Floods (≥ 10 alarms in 10 min)", `${k.floods.length} (${floodMinutes.toFixed(0)} min, ${hours > 0 ? ((100 * floodMinutes) / (hours * 60)).toFixed(1) : "0"} % of the time)`,
          "< 1 % of the time in flood", hours > 0 && floodMinutes / (hours * 60) < 0.01 ? "ok" : "over", hours > 0 && floodMinutes / (hours * 60) < 0.01 ? "met" : "not met"],
        ["Standing alarms (active > 24 h)", String(k.standing.length), "< 10", k.standing.length < 10 ? "ok" : "over", k.standing.length < 10 ? "met" : "not met"],
        ["Stale alarms (unacknowledged > 24 h)", String(k.stale.length), "0", k.stale.length === 0 ? "ok" : "over", k.stale.length === 0 ? "met" : "not met"],
        ["Priority high (1)", `${high} (${share(high)})`, "about 5 %", "info", "compare"],
        ["Priority medium (2)", `${medium} (${share(medium)})`, "about 15 %", "info", "compare"],
        ["Priority low (3, 4)", `${low} (${share(low)})`, "about 80 %", "info", "compare"],
      ];
      document.querySelector("#kpi-table tbody").replaceChildren(
        ...rows.map(([measure, value, target, status, words]) =>
          HMI.el("tr", { "data-status": status },
            HMI.el("td", { text: measure }), HMI.el("td", { class: "value", text: value }),
            HMI.el("td", { text: target }), HMI.el("td", { class: "assessment", text: words }))),
      );
      document.querySelector("#kpi-top tbody").replaceChildren(
        ...k.top.map((t) =>
          HMI.el("tr", { "data-priority": String(t.priority) },
            HMI.el("td", { text: String(t.count) }), HMI.el("td", { class: "pri", text: String(t.priority) }),
            HMI.el("td", { text: t.text }), HMI.el("td", { text: t.point }))),
      );
      const floods = document.getElementById("kpi-floods");
      floods.replaceChildren(
        ...(k.floods.length
          ? k.floods.map((f) => HMI.el("li", { text: `${when(f.start)} – ${when(f.end)}: ${f.count} alarms` }))
          : [HMI.el("li", { class: "muted", text: "No flood in this period." })]),
      );
      document.getElementById("kpi-period").textContent =
        `${when(k.from)} – ${when(k.to)}: ${k.alarms} alarm activation(s), counted by the HMI's receive time` +
        (k.from_store ? ` (before ${when(k.counted_since)}, the HMI's start, read from its event store)` : "");
    },
  };
  HMI.alarmReport = report;
  HMI.pages["alarm-report"] = {
    show() {
      if (report.span) report.range(report.span);
      report.load();
    },
  };
})();
