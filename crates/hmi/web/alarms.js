// Stanice web HMI — alarms: the list (priority colours, sorting, filters, acknowledge,
// shelve for N minutes), the badge in the navigation, and the alarm sound.
//
// The sound is generated with the WebAudio API (no audio files): it plays while an
// unacknowledged, unshelved alarm of priority 1 or 2 is active and the sound is switched
// on (the bell in the header; the choice is kept in this browser). Browsers start audio
// only after a user gesture on the page, so the context is created on the first click.
"use strict";

(function () {
  const SHELVE_MINUTES = [15, 30, 60, 240, 480];
  let sortKey = "priority";
  let sortDir = "asc";
  let shown = false;

  function shelved(alarm) {
    return Boolean(alarm.shelved_until) && Date.parse(alarm.shelved_until) > HMI.now();
  }
  function unacknowledged(alarm) {
    return alarm.needs_acknowledgement !== false && !alarm.acknowledged && Boolean(alarm.raised);
  }
  /** As the server lists them: active, or cleared and still waiting for acknowledgement. */
  function listed(alarm) {
    return alarm.active || unacknowledged(alarm);
  }
  /** Time of day only for today, the date too otherwise. */
  function when(time) {
    if (!time) return "—";
    const text = HMI.formatTime(time);
    return text.slice(0, 10) === HMI.formatTime(new Date(HMI.now())).slice(0, 10) ? text.slice(11) : text;
  }
  function stateWords(alarm) {
    const words = [alarm.active ? "ACTIVE" : `cleared ${when(alarm.cleared)}`];
    if (unacknowledged(alarm)) words.push("unacknowledged");
    else if (alarm.acknowledged) words.push("acknowledged");
    if (shelved(alarm)) words.push(`shelved until ${when(alarm.shelved_until)}`);
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
      if (state !== "shelved" && state !== "" && shelved(alarm)) return false;
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

  /** Acknowledge / shelve buttons; a read-only user (level 0) watches only. */
  function actionsFor(alarm) {
    const actions = HMI.el("td", { class: "actions" });
    if (!HMI.session || HMI.session.level === 0) {
      actions.append(HMI.el("span", { class: "muted", title: "Your level (0) is read-only.", text: "read-only" }));
      return actions;
    }
    if (unacknowledged(alarm)) {
      actions.append(HMI.el("button", { type: "button", class: "ack", text: "Acknowledge", onclick: () => act(alarm, "acknowledge") }), " ");
    }
    if (shelved(alarm)) {
      actions.append(HMI.el("button", { type: "button", class: "secondary unshelve", text: "Unshelve", onclick: () => act(alarm, "shelve", { minutes: 0 }) }));
      return actions;
    }
    const select = HMI.el(
      "select",
      { "aria-label": "Shelve for minutes" },
      ...SHELVE_MINUTES.map((m) => HMI.el("option", { value: String(m), text: m < 60 ? `${m} min` : `${m / 60} h` })),
    );
    actions.append(
      HMI.el("button", { type: "button", class: "secondary shelve", text: "Shelve", onclick: () => act(alarm, "shelve", { minutes: Number(select.value) }) }),
      " ",
      select,
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
      alarm.priority, when(alarm.raised), alarm.text, alarm.point, stateWords(alarm),
      unacknowledged(alarm), shelved(alarm), HMI.session ? HMI.session.level : null,
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

  function badge() {
    const waiting = [...HMI.alarms.values()].filter((a) => listed(a) && !shelved(a));
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
        if (alarm.active && unacknowledged(alarm) && !shelved(alarm) && alarm.priority <= 2) {
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
    document.getElementById("alarm-ack-all").addEventListener("click", async () => {
      for (const alarm of visible().filter(unacknowledged)) await act(alarm, "acknowledge");
    });
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
    // Shelving ends by time: look again every half minute.
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
})();
