// The lab mimic: the model's front panel (SVG, LEDs as two-state images), its buttons,
// speed control and a logic-analyser time-line of every signal. Reads /api/state every
// 100 ms and /api/timeline incrementally; sends /api/control. `window.LAB` holds what
// the page shows, for tests.
"use strict";

const SVG = "http://www.w3.org/2000/svg";
const LAB = (window.LAB = {
  state: null,
  channels: [],
  changes: [],
  next: 0,
  violations: [],
  view: { start: 0, window: 30, follow: true },
  built: null,
});

function svg(tag, attrs, parent) {
  const el = document.createElementNS(SVG, tag);
  for (const [k, v] of Object.entries(attrs || {})) el.setAttribute(k, v);
  (parent || document.getElementById("panel")).appendChild(el);
  return el;
}

function text(x, y, content, cls) {
  const t = svg("text", { x, y, "text-anchor": "middle", class: cls || "" });
  t.textContent = content;
  return t;
}

// A LED: an id, a colour, a label under it.
function led(id, x, y, colour, label, r) {
  svg("circle", { id: `led-${id}`, cx: x, cy: y, r: r || 10, class: `led ${colour} off`, "data-on": "0" });
  if (label) text(x, y + (r || 10) + 14, label, "caption");
}

function setLed(id, on) {
  const el = document.getElementById(`led-${id}`);
  if (!el) return;
  el.classList.toggle("on", !!on);
  el.classList.toggle("off", !on);
  el.dataset.on = on ? "1" : "0";
}

function errLed(x, y) {
  led("ERR", x, y, "red", "ERR", 12);
}

// The panels, one per model: build once, update on every state.
const PANELS = {
  slide: {
    build() {
      text(320, 30, "Hydraulic slide unit");
      for (let i = 1; i <= 10; i++) led(`pos-${i}`, 40 + (i - 1) * 60, 130, "yellow", String(i));
      svg("rect", { id: "slide-carriage", x: 20, y: 80, width: 40, height: 26, rx: 4, fill: "#6b7280" });
      [["K1", 1], ["K2", 4], ["K3", 7], ["K4", 10]].forEach(([k, p]) => led(k, 40 + (p - 1) * 60, 200, "green", k));
      [["EM1", "forward"], ["EM2", "back"], ["EM3", "feed"]].forEach(([name, what], i) =>
        led(name, 120 + i * 120, 290, "amber", `${name} ${what}`));
      errLed(560, 290);
    },
    update(s) {
      const position = s.state.position || 1;
      for (let i = 1; i <= 10; i++) setLed(`pos-${i}`, (s.state.leds >> (i - 1)) & 1);
      document.getElementById("slide-carriage").setAttribute("x", 20 + (position - 1) * 60);
      ["K1", "K2", "K3", "K4", "EM1", "EM2", "EM3"].forEach((n) => setLed(n, s.signals[n]));
    },
  },
  crossroad: {
    build() {
      text(320, 30, "Crossroad");
      const heads = [
        ["lower", 140, [["cerv_spodek", "red"], ["oran_spodek", "amber"], ["zel_spodek", "green"]]],
        ["upper", 320, [["cerv_vrch", "red"], ["oran_vrch", "amber"], ["zel_vrch", "green"]]],
        ["pedestrians", 500, [["cerv_chodci", "red"], ["zel_chodci", "green"]]],
      ];
      for (const [name, x, lamps] of heads) {
        svg("rect", { x: x - 30, y: 60, width: 60, height: 40 + lamps.length * 60, rx: 8, fill: "#111827" });
        lamps.forEach(([signal, colour], i) => led(signal, x, 90 + i * 60, colour, null, 20));
        text(x, 90 + lamps.length * 60 + 30, name);
      }
      errLed(600, 330);
    },
    update(s) {
      for (const n of ["cerv_spodek", "oran_spodek", "zel_spodek", "cerv_vrch", "oran_vrch", "zel_vrch", "cerv_chodci", "zel_chodci"])
        setLed(n, s.signals[n]);
    },
  },
  mixing: {
    build() {
      text(320, 22, "Mixing unit");
      const tanks = [
        [1, 40, [["H3", 10], ["H2", 42], ["H1", 84]], "SV1"],
        [2, 220, [["H5", 10], ["H4", 84]], "SV2"],
        [3, 400, [["H8", 10], ["H7", 42], ["H6", 84]], "SV3"],
      ];
      for (const [n, x, sensors, valve] of tanks) {
        svg("rect", { x, y: 60, width: 100, height: 126, class: "tank" });
        svg("rect", { id: `liquid-${n}`, x, y: 186, width: 100, height: 0, class: "liquid" });
        text(x + 50, 200, `tank ${n}`, "caption");
        for (const [h, level] of sensors) led(h, x + 120, 186 - (level / 84) * 126, "green", h, 7);
        led(valve, x + 50, 44, "amber", null, 8);
        text(x + 80, 48, valve, "caption");
      }
      led("SV4", 300, 214, "amber", null, 8);
      text(335, 218, "SV4", "caption");
      svg("rect", { x: 200, y: 228, width: 200, height: 100, class: "tank" });
      svg("rect", { id: "liquid-vessel", x: 200, y: 328, width: 200, height: 0, class: "liquid" });
      text(300, 345, "mixing vessel", "caption");
      led("SV5", 430, 320, "amber", "SV5", 8);
      led("MIX", 480, 260, "yellow", "MIX", 10);
      errLed(590, 300);
    },
    update(s) {
      for (const [n, key] of [[1, "tank1"], [2, "tank2"], [3, "tank3"]]) {
        const h = Math.min(1.1, (s.state[key] || 0) / 84) * 126;
        const el = document.getElementById(`liquid-${n}`);
        el.setAttribute("y", 186 - h);
        el.setAttribute("height", h);
      }
      const v = Math.min(1.1, (s.state.vessel || 0) / 253) * 100;
      const vessel = document.getElementById("liquid-vessel");
      vessel.setAttribute("y", 328 - v);
      vessel.setAttribute("height", v);
      ["H1", "H2", "H3", "H4", "H5", "H6", "H7", "H8", "SV1", "SV2", "SV3", "SV4", "SV5"].forEach((n) => setLed(n, s.signals[n]));
      // The MIX LED blinks while the mixer runs.
      setLed("MIX", s.signals.MIX && s.t % 1 < 0.5);
    },
  },
  washing: {
    build() {
      text(320, 24, "Washing machine");
      svg("circle", { cx: 200, cy: 180, r: 110, fill: "#d1d5db", stroke: "#111" });
      for (let i = 0; i < 8; i++) {
        const a = (i / 8) * 2 * Math.PI - Math.PI / 2;
        led(`drum-${i}`, 200 + 90 * Math.cos(a), 180 + 90 * Math.sin(a), "yellow", null, 9);
      }
      led("voda_100", 200, 150, "green", "100 %", 8);
      led("voda_50", 200, 205, "green", "50 %", 8);
      [["teplota_90", "90 °C"], ["teplota_60", "60 °C"], ["teplota_40", "40 °C"], ["teplota_30", "30 °C"]].forEach(([n, l], i) =>
        led(n, 380, 70 + i * 55, "red", l, 8));
      [["buben_vpravo", "drum →"], ["buben_vlevo", "drum ←"], ["otacky", "spin"], ["topeni", "heating"], ["napousteni", "water"], ["cerpadlo", "pump"]].forEach(([n, l], i) =>
        led(n, 500, 50 + i * 48, "amber", l, 8));
      text(200, 320, "", "caption").id = "washing-readout";
      errLed(600, 330);
    },
    update(s) {
      for (let i = 0; i < 8; i++) setLed(`drum-${i}`, s.state.drum === i);
      ["voda_50", "voda_100", "teplota_30", "teplota_40", "teplota_60", "teplota_90",
        "buben_vpravo", "buben_vlevo", "otacky", "topeni", "napousteni", "cerpadlo"].forEach((n) => setLed(n, s.signals[n]));
      document.getElementById("washing-readout").textContent =
        `level ${(s.state.level || 0).toFixed(0)} %, ${(s.state.temperature || 0).toFixed(1)} °C`;
    },
  },
};

async function control(body) {
  await fetch("api/control", { method: "POST", headers: { "content-type": "application/json" }, body: JSON.stringify(body) });
}

function button(label, id, down, up) {
  const b = document.createElement("button");
  b.textContent = label;
  b.id = id;
  if (up) {
    b.addEventListener("pointerdown", () => control({ console: down }));
    b.addEventListener("pointerup", () => control({ console: up }));
    b.addEventListener("pointerleave", (e) => { if (e.buttons) control({ console: up }); });
    // keyboard and assistive technology: a click is a press and a release
    b.addEventListener("click", (e) => {
      if (e.detail === 0) control({ console: down }).then(() => setTimeout(() => control({ console: up }), 300));
    });
  } else {
    b.addEventListener("click", () => control({ console: down }));
  }
  document.getElementById("buttons").appendChild(b);
  return b;
}

function buildButtons(s) {
  if ("START" in s.signals) button("START", "button-start", "press START", "release START");
  if (s.model === "crossroad") button("Pedestrian button", "button-pedestrian", "press tlacitko_chodci", "release tlacitko_chodci");
  button("RESET", "button-reset", "reset");
  const input = document.createElement("input");
  input.id = "console";
  input.placeholder = "console: stuck K3 off, broken SV1, clear all";
  input.size = 32;
  input.addEventListener("keydown", (e) => {
    if (e.key === "Enter" && input.value.trim()) {
      control({ console: input.value.trim() });
      input.value = "";
    }
  });
  document.getElementById("buttons").appendChild(input);
}

function showState(s) {
  LAB.state = s;
  if (LAB.built !== s.model) {
    const panel = PANELS[s.model];
    document.getElementById("panel").innerHTML = "";
    panel.build();
    buildButtons(s);
    document.getElementById("title").textContent = `Stanice lab: ${s.model}`;
    LAB.built = s.model;
  }
  PANELS[s.model].update(s);
  const err = document.getElementById("led-ERR");
  setLed("ERR", s.err_lit);
  err.dataset.err = s.err_led;
  document.getElementById("clock").textContent =
    `t = ${s.t.toFixed(3)} s, ${s.scans} scans${s.paused ? " (paused)" : ""}`;
  for (const b of document.querySelectorAll("#speed button")) {
    const active = s.paused ? b.id === "pause" : b.dataset.speed === s.speed;
    b.classList.toggle("active", active);
  }
  const errors = s.errors.filter((e) => e.cleared === null);
  document.getElementById("status").textContent = s.stopped
    ? "The program stopped on a run-time fault (see the violations)."
    : errors.length ? errors.map((e) => `${e.kind}: ${e.detail}`).join("; ") : "";
}

async function pollState() {
  try {
    const r = await fetch("api/state");
    if (r.ok) showState(await r.json());
  } catch (_) { /* the server went away: keep the last picture */ }
  setTimeout(pollState, 100);
}

async function pollTimeline() {
  try {
    const r = await fetch(`api/timeline?from=${LAB.next}`);
    if (r.ok) {
      const t = await r.json();
      LAB.channels = t.channels;
      LAB.changes.push(...t.changes);
      LAB.next = t.next;
      if (t.violations.length !== LAB.violations.length) showViolations(t.violations);
      drawTimeline();
    }
  } catch (_) { /* keep what we have */ }
  setTimeout(pollTimeline, 300);
}

function showViolations(list) {
  LAB.violations = list;
  const ol = document.getElementById("violations");
  ol.innerHTML = "";
  for (const v of list) {
    const li = document.createElement("li");
    const what = v.property ? `property "${v.property}"` : v.kind.name || v.kind.type;
    li.textContent = `${v.time_s.toFixed(3)} s ${what}: ${v.detail}`;
    li.dataset.t = v.time_s;
    li.addEventListener("click", () => goTo(v.time_s));
    ol.appendChild(li);
  }
}

// Scrolls the time-line so that `t` is in the middle, and stops following.
function goTo(t) {
  LAB.view.follow = false;
  document.getElementById("follow").checked = false;
  LAB.view.start = Math.max(0, t - LAB.view.window / 2);
  document.getElementById("scroll").value = LAB.view.start;
  drawTimeline();
}

function drawTimeline() {
  const canvas = document.getElementById("timeline");
  const ctx = canvas.getContext("2d");
  const now = LAB.state ? LAB.state.t : 0;
  const w = LAB.view.window;
  const scroll = document.getElementById("scroll");
  scroll.max = Math.max(0, now - w);
  if (LAB.view.follow) LAB.view.start = Math.max(0, now - w);
  const start = LAB.view.start;
  const channels = LAB.channels.map((c, i) => ({ ...c, i })).filter((c) => c.name !== "err_lit");
  const rowH = 18, left = 110, width = canvas.width - left - 10;
  canvas.height = Math.max(60, channels.length * rowH + 30);
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  ctx.font = "12px system-ui, sans-serif";
  const x = (t) => left + ((t - start) / w) * width;
  // per channel: its value at `start` and its changes in the window
  const byChannel = channels.map(() => []);
  const before = channels.map(() => null);
  const index = new Map(channels.map((c, k) => [c.i, k]));
  let max = channels.map(() => 1);
  for (const c of LAB.changes) {
    const k = index.get(c.channel);
    if (k === undefined) continue;
    max[k] = Math.max(max[k], Math.abs(c.value));
    if (c.t <= start) before[k] = c.value;
    else if (c.t <= start + w) byChannel[k].push(c);
  }
  channels.forEach((c, k) => {
    const y0 = 10 + k * rowH;
    ctx.fillStyle = c.kind === "output" ? "#b45309" : c.kind === "input" ? "#15803d" : "#1d4ed8";
    ctx.fillText(c.name, 4, y0 + 12);
    const level = (v) => y0 + rowH - 4 - (v / max[k]) * (rowH - 8);
    ctx.strokeStyle = ctx.fillStyle;
    ctx.beginPath();
    let v = before[k] ?? 0;
    ctx.moveTo(left, level(v));
    for (const ch of byChannel[k]) {
      ctx.lineTo(x(ch.t), level(v));
      v = ch.value;
      ctx.lineTo(x(ch.t), level(v));
    }
    ctx.lineTo(x(Math.min(now, start + w)), level(v));
    ctx.stroke();
  });
  ctx.strokeStyle = "#dc2626";
  for (const v of LAB.violations) {
    if (v.time_s < start || v.time_s > start + w) continue;
    ctx.beginPath();
    ctx.moveTo(x(v.time_s), 0);
    ctx.lineTo(x(v.time_s), canvas.height);
    ctx.stroke();
  }
  ctx.fillStyle = "#374151";
  ctx.fillText(`${start.toFixed(1)} s`, left, canvas.height - 4);
  ctx.fillText(`${(start + w).toFixed(1)} s`, canvas.width - 70, canvas.height - 4);
  LAB.view.shown = { start, end: start + w, violations: LAB.violations.filter((v) => v.time_s >= start && v.time_s <= start + w).length };
}

document.getElementById("speed").addEventListener("click", (e) => {
  const b = e.target.closest("button");
  if (!b) return;
  if (b.dataset.speed) control({ speed: b.dataset.speed });
  else control(b.dataset.control);
});
document.getElementById("window").addEventListener("change", (e) => {
  LAB.view.window = Number(e.target.value);
  drawTimeline();
});
document.getElementById("scroll").addEventListener("input", (e) => {
  LAB.view.follow = false;
  document.getElementById("follow").checked = false;
  LAB.view.start = Number(e.target.value);
  drawTimeline();
});
document.getElementById("follow").addEventListener("change", (e) => {
  LAB.view.follow = e.target.checked;
  drawTimeline();
});

pollState();
pollTimeline();
