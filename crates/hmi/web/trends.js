// Stanice web HMI — trends: up to 8 measurements (pens) over a time range
// (GET /api/trend?points=A,B, downsampled by the server to one bucket per pixel column),
// drawn on a <canvas> by the small chart below (no library). The address #trends/A,B opens
// those pens; the legend names each pen with its unit (its × removes it); "CSV" downloads
// the shown period as time,A,B. Each pen has its own value scale; the axis is the first's. Buttons pick the last 1 h / 1 d / 7 d;
// dragging across the chart zooms into the dragged range ("Zoom out" goes back); with
// "follow live" the newest values arriving over the WebSocket are appended.
//
// Measurements are sent on change (with a deadband), so a value holds until the next one:
// the line is drawn in steps, and invalid samples break it (marked in the "lost" colour).
"use strict";

(function () {
  const MARGIN = { left: 64, right: 18, top: 30, bottom: 40 };
  const TIME_STEPS = [1, 2, 5, 10, 15, 30, 60, 120, 300, 600, 900, 1800, 3600, 7200, 10800, 21600, 43200, 86400, 172800, 604800].map((s) => s * 1000);

  const COLOURS = ["#4fa3e0", "#f0a830", "#6cc070", "#e06c8c", "#b08de0", "#4fd0c8", "#d0d060", "#e0e0e0"];
  const MAX_PENS = 8;

  const state = {
    point: "", // the first pen
    pens: [], // point names, in the legend's order
    series: [], // [{point, unit, description, samples}] as the server answered
    csvUrl: "",
    from: 0,
    to: 0,
    samples: [], // [time_ms, value, invalid]
    zoomStack: [],
    drag: null, // {x0, x1}
    hover: null, // x in CSS pixels
    loading: false,
    error: "",
    shown: false,
  };
  let trendPoints = null; // [{name, description}]

  const canvas = () => document.getElementById("trend-canvas");
  const follow = () => document.getElementById("trend-follow");

  // ------------------------------------------------------------------ data
  async function trendList() {
    if (trendPoints) return trendPoints;
    // The configured trends if the server lists them; otherwise every measurement.
    let list;
    try {
      list = (await HMI.api("/api/trends")).map((t) => (typeof t === "string" ? { name: t } : { name: t.point || t.name, description: t.description }));
      trendPoints = list;
    } catch (error) {
      list = [...HMI.points.values()].filter((p) => p.type && p.type.startsWith("M_ME")).map((p) => ({ name: p.name }));
      if (list.length) trendPoints = list; // before the first snapshot: ask again later
    }
    for (const t of list) {
      const point = HMI.points.get(t.name);
      if (!t.description && point) t.description = point.description;
    }
    return list;
  }

  async function fillSelect() {
    const select = document.getElementById("trend-point");
    const list = await trendList();
    if (!state.pens.length && list[0]) state.pens = [list[0].name];
    const current = state.pens[0] || "";
    const option = (t, selected) => HMI.el("option", { value: t.name, selected, text: t.description ? `${t.name} — ${t.description}` : t.name });
    select.replaceChildren(...list.map((t) => option(t, t.name === current)));
    document.getElementById("trend-add").replaceChildren(
      HMI.el("option", { value: "", text: "add a pen…" }),
      ...list.filter((t) => !state.pens.includes(t.name)).map((t) => option(t, false)),
    );
    state.point = current;
  }

  // The address names the pens (#trends/A,B), so a trend can be bookmarked and sent.
  function pensChanged() {
    state.point = state.pens[0] || "";
    const hash = `#trends/${state.pens.map(encodeURIComponent).join(",")}`;
    if (window.location.hash !== hash) history.replaceState(null, "", hash);
    fillSelect().then(load);
  }

  function legend() {
    const element = document.getElementById("trend-legend");
    element.replaceChildren(
      ...state.pens.map((name, i) => {
        const series = state.series.find((s) => s.point === name) || {};
        const point = HMI.points.get(name);
        const description = series.description || (point && point.description) || "";
        const remove = HMI.el("button", { type: "button", class: "secondary trend-remove", title: `Remove ${name}`, text: "×" });
        remove.addEventListener("click", () => {
          state.pens = state.pens.filter((p) => p !== name);
          pensChanged();
        });
        return HMI.el(
          "li",
          { class: "trend-pen", "data-point": name },
          HMI.el("span", { class: "trend-swatch", style: `background:${COLOURS[i % COLOURS.length]}` }),
          HMI.el("span", { class: "trend-pen-name", text: name }),
          HMI.el("span", { class: "muted", text: `${description ? ` ${description}` : ""}${series.unit ? ` [${series.unit}]` : ""}` }),
          state.pens.length > 1 ? remove : "",
        );
      }),
    );
  }

  async function load() {
    if (!state.pens.length) {
      state.samples = [];
      state.series = [];
      state.error = "No measurement is configured for trends.";
      draw();
      return;
    }
    state.loading = true;
    draw();
    // One bucket per pixel column of the chart.
    const width = Math.max(100, Math.min(4000, Math.round((canvas().clientWidth || 1000) - MARGIN.left - MARGIN.right)));
    const parameters = new URLSearchParams({
      points: state.pens.join(","),
      from: new Date(state.from).toISOString(),
      to: new Date(state.to).toISOString(),
      width: String(width),
    });
    const key = () => `${state.pens.join(",")}|${state.from}|${state.to}`;
    const wanted = key();
    try {
      const result = await HMI.api(`/api/trend?${parameters}`);
      if (wanted !== key()) return; // superseded
      // [time_ms, value, invalid] or, for a bucket of several values, [..., min, max].
      const sample = (s) => [Number(s[0]), s[1] === null ? null : Number(s[1]), Boolean(s[2]), ...(s.length > 3 ? [Number(s[3]), Number(s[4])] : [])];
      state.series = (result.series || []).map((s) => ({ point: s.point, unit: s.unit || "", description: s.description || "", samples: (s.samples || []).map(sample) }));
      state.samples = state.series.length ? state.series[0].samples : [];
      state.unit = state.series.length ? state.series[0].unit : "";
      parameters.set("format", "csv");
      state.csvUrl = `/api/trend?${parameters}`;
      const link = document.getElementById("trend-csv");
      link.href = state.csvUrl;
      link.removeAttribute("aria-disabled");
      state.error = "";
    } catch (error) {
      state.samples = [];
      state.series = [];
      state.error = `Cannot load the trend: ${error.message}`;
    } finally {
      state.loading = false;
      legend();
      document.getElementById("page-trends").dataset.loaded = String(Date.now());
      draw();
    }
  }

  function setRange(seconds) {
    state.zoomStack = [];
    state.to = HMI.now();
    state.from = state.to - seconds * 1000;
    follow().checked = true;
    load();
  }

  // ------------------------------------------------------------------ scales
  function niceStep(span, count) {
    const raw = span / Math.max(1, count);
    const power = 10 ** Math.floor(Math.log10(raw));
    for (const m of [1, 2, 2.5, 5, 10]) if (m * power >= raw) return m * power;
    return 10 * power;
  }

  function valueRange(samples) {
    let lo = Infinity;
    let hi = -Infinity;
    for (const [, v] of samples) {
      if (v === null || !Number.isFinite(v)) continue;
      lo = Math.min(lo, v);
      hi = Math.max(hi, v);
    }
    if (!Number.isFinite(lo)) return [0, 1];
    if (lo === hi) {
      const pad = Math.abs(lo) * 0.1 || 1;
      return [lo - pad, hi + pad];
    }
    const pad = (hi - lo) * 0.08;
    return [lo - pad, hi + pad];
  }

  function timeLabel(ms, step) {
    const d = new Date(ms);
    const p = HMI.pad;
    const clock = step < 60000 ? `${p(d.getHours())}:${p(d.getMinutes())}:${p(d.getSeconds())}` : `${p(d.getHours())}:${p(d.getMinutes())}`;
    if (step >= 86400000) return `${d.getDate()}.${d.getMonth() + 1}.`;
    if (step >= 3600000 || state.to - state.from > 86400000) {
      if (d.getHours() === 0 && d.getMinutes() === 0) return `${d.getDate()}.${d.getMonth() + 1}.`;
    }
    return clock;
  }

  // ------------------------------------------------------------------ drawing
  function draw() {
    const c = canvas();
    if (!c || !state.shown) return;
    const ratio = window.devicePixelRatio || 1;
    const width = c.clientWidth;
    const height = c.clientHeight;
    if (!width || !height) return;
    if (c.width !== Math.round(width * ratio) || c.height !== Math.round(height * ratio)) {
      c.width = Math.round(width * ratio);
      c.height = Math.round(height * ratio);
    }
    const g = c.getContext("2d");
    g.setTransform(ratio, 0, 0, ratio, 0, 0);
    g.clearRect(0, 0, width, height);
    const style = getComputedStyle(document.documentElement);
    const colour = (name, fallback) => style.getPropertyValue(name).trim() || fallback;
    const text = colour("--text", "#ddd");
    const muted = colour("--muted", "#999");
    const gridColour = "rgba(255,255,255,0.08)";
    g.font = "12px system-ui, sans-serif";

    const plot = { x: MARGIN.left, y: MARGIN.top, w: width - MARGIN.left - MARGIN.right, h: height - MARGIN.top - MARGIN.bottom };
    if (plot.w < 40 || plot.h < 40) return;
    // Each pen: its samples in the range, the one in force at its start, its own scale.
    const pens = state.series.map((s, i) => {
      const inRange = s.samples.filter((x) => x[0] >= state.from && x[0] <= state.to);
      const before = [...s.samples].reverse().find((x) => x[0] < state.from);
      const series = before ? [before, ...inRange] : inRange;
      const extremes = series.flatMap((x) => (x.length > 3 ? [[x[0], x[3]], [x[0], x[4]]] : [x]));
      const [lo, hi] = valueRange(extremes);
      return { colour: COLOURS[i % COLOURS.length], inRange, series, lo, hi, yOf: (v) => plot.y + plot.h - ((v - lo) / (hi - lo)) * plot.h };
    });
    const first = pens[0] || { inRange: [], series: [], lo: 0, hi: 1, yOf: (v) => plot.y + plot.h - v * plot.h, colour: COLOURS[0] };
    const { inRange, lo, hi, yOf } = first;
    const xOf = (t) => plot.x + ((t - state.from) / (state.to - state.from)) * plot.w;

    // Title: the first pen, and how many more the legend names.
    const point = HMI.points.get(state.point);
    g.fillStyle = text;
    g.textAlign = "left";
    g.textBaseline = "alphabetic";
    const more = pens.length > 1 ? ` (+${pens.length - 1} pen${pens.length > 2 ? "s" : ""}, axis of the first)` : "";
    g.fillText(`${state.point}${point && point.description ? ` — ${point.description}` : ""}${more}`, plot.x, 18);
    g.textAlign = "right";
    g.fillStyle = muted;
    g.fillText(`${HMI.formatTime(state.from)} … ${HMI.formatTime(state.to)}`, plot.x + plot.w, 18);

    // Value grid and axis.
    const vStep = niceStep(hi - lo, Math.max(2, Math.floor(plot.h / 45)));
    g.strokeStyle = gridColour;
    g.lineWidth = 1;
    g.textAlign = "right";
    g.textBaseline = "middle";
    const digits = Math.max(0, -Math.floor(Math.log10(vStep)) + (vStep % 1 ? 1 : 0));
    for (let v = Math.ceil(lo / vStep) * vStep; v <= hi; v += vStep) {
      const y = Math.round(yOf(v)) + 0.5;
      g.beginPath();
      g.moveTo(plot.x, y);
      g.lineTo(plot.x + plot.w, y);
      g.stroke();
      g.fillStyle = muted;
      g.fillText(v.toFixed(Math.min(digits, 4)), plot.x - 6, y);
    }
    // Time grid and axis.
    const span = state.to - state.from;
    const tStep = TIME_STEPS.find((s) => span / s <= Math.max(2, plot.w / 95)) || TIME_STEPS[TIME_STEPS.length - 1];
    const zoneShift = new Date(state.from).getTimezoneOffset() * 60000; // ticks on local midnight and hours
    g.textAlign = "center";
    g.textBaseline = "top";
    for (let t = Math.ceil((state.from - zoneShift) / tStep) * tStep + zoneShift; t <= state.to; t += tStep) {
      const x = Math.round(xOf(t)) + 0.5;
      g.strokeStyle = gridColour;
      g.beginPath();
      g.moveTo(x, plot.y);
      g.lineTo(x, plot.y + plot.h);
      g.stroke();
      g.fillStyle = muted;
      g.fillText(timeLabel(t, tStep), x, plot.y + plot.h + 6);
    }
    g.strokeStyle = "rgba(255,255,255,0.3)";
    g.strokeRect(plot.x + 0.5, plot.y + 0.5, plot.w, plot.h);

    // The line, in steps, clipped to the plot.
    g.save();
    g.beginPath();
    g.rect(plot.x, plot.y, plot.w, plot.h);
    g.clip();
    const series = first.series;
    const end = Math.min(state.to, HMI.now());
    for (const pen of [...pens].reverse()) {
      // A bucket of several values: its min..max as a band behind the line.
      g.fillStyle = pen.colour;
      g.globalAlpha = 0.3;
      for (const [t, v, invalid, min, max] of pen.series) {
        if (min === undefined || v === null || invalid) continue;
        const y0 = pen.yOf(max);
        g.fillRect(xOf(Math.max(t, state.from)) - 0.5, y0, 1.5, Math.max(1, pen.yOf(min) - y0));
      }
      g.globalAlpha = 1;
      g.strokeStyle = pen.colour;
      g.lineWidth = 2;
      g.beginPath();
      let drawing = false;
      for (let i = 0; i < pen.series.length; i += 1) {
        const [t, v, invalid] = pen.series[i];
        const nextT = i + 1 < pen.series.length ? pen.series[i + 1][0] : end;
        if (v === null || invalid) {
          drawing = false;
          continue;
        }
        const x0 = xOf(Math.max(t, state.from));
        const x1 = xOf(Math.max(nextT, state.from));
        const y = pen.yOf(v);
        if (drawing) g.lineTo(x0, y);
        else g.moveTo(x0, y);
        g.lineTo(x1, y);
        drawing = true;
      }
      g.stroke();
    }
    // Invalid samples: a mark in the lost colour at the bottom.
    g.fillStyle = colour("--lost", "#f4f");
    for (const [t, v, invalid] of series) {
      if (invalid || v === null) g.fillRect(xOf(t) - 1, plot.y + plot.h - 6, 3, 6);
    }
    // Points where samples arrived (when few enough to see).
    if (inRange.length && inRange.length < plot.w / 6) {
      g.fillStyle = colour("--accent", "#4fa3e0");
      for (const [t, v, invalid] of inRange) {
        if (v === null || invalid) continue;
        g.beginPath();
        g.arc(xOf(t), yOf(v), 2.5, 0, Math.PI * 2);
        g.fill();
      }
    }
    g.restore();

    // Messages.
    g.textAlign = "center";
    g.textBaseline = "middle";
    g.fillStyle = muted;
    if (state.loading) g.fillText("loading…", plot.x + plot.w / 2, plot.y + plot.h / 2);
    else if (state.error) g.fillText(state.error, plot.x + plot.w / 2, plot.y + plot.h / 2);
    else if (!series.length) g.fillText("no values in this range", plot.x + plot.w / 2, plot.y + plot.h / 2);

    // Drag selection.
    if (state.drag) {
      const x0 = Math.max(plot.x, Math.min(state.drag.x0, state.drag.x1));
      const x1 = Math.min(plot.x + plot.w, Math.max(state.drag.x0, state.drag.x1));
      g.fillStyle = "rgba(79,163,224,0.18)";
      g.fillRect(x0, plot.y, x1 - x0, plot.h);
      g.strokeStyle = "rgba(79,163,224,0.8)";
      g.strokeRect(x0 + 0.5, plot.y + 0.5, x1 - x0, plot.h);
    }
    // Hover read-out.
    if (state.hover !== null && !state.drag && state.hover >= plot.x && state.hover <= plot.x + plot.w) {
      const t = state.from + ((state.hover - plot.x) / plot.w) * span;
      const at = [...series].reverse().find((s) => s[0] <= t);
      g.strokeStyle = "rgba(255,255,255,0.4)";
      g.beginPath();
      g.moveTo(Math.round(state.hover) + 0.5, plot.y);
      g.lineTo(Math.round(state.hover) + 0.5, plot.y + plot.h);
      g.stroke();
      const label = `${HMI.formatTime(t)}  ${at && at[1] !== null ? HMI.formatNumber(at[1]) : "—"}${at && at[2] ? " (invalid)" : ""}`;
      g.font = "12px system-ui, sans-serif";
      const w = g.measureText(label).width + 12;
      const x = Math.min(Math.max(state.hover - w / 2, plot.x), plot.x + plot.w - w);
      g.fillStyle = "rgba(20,24,28,0.92)";
      g.fillRect(x, plot.y + 4, w, 20);
      g.fillStyle = text;
      g.textAlign = "left";
      g.fillText(label, x + 6, plot.y + 14);
    }
    state.plot = plot;
    info(inRange);
  }

  function info(inRange) {
    const values = inRange.filter((s) => s[1] !== null && !s[2]).map((s) => s[1]);
    const element = document.getElementById("trend-info");
    if (!values.length) {
      element.textContent = "Drag across the chart to zoom into a time range.";
      return;
    }
    const min = Math.min(...values);
    const max = Math.max(...values);
    const mean = values.reduce((a, b) => a + b, 0) / values.length;
    element.textContent = `${inRange.length} sample(s); min ${HMI.formatNumber(min)}, max ${HMI.formatNumber(max)}, mean of samples ${HMI.formatNumber(mean)}. Drag across the chart to zoom.`;
  }

  // ------------------------------------------------------------------ zoom by dragging
  function localX(event) {
    const rect = canvas().getBoundingClientRect();
    return event.clientX - rect.left;
  }

  function pointerDown(event) {
    if (!state.plot) return;
    try {
      canvas().setPointerCapture(event.pointerId);
    } catch (error) {
      /* a synthetic event has no pointer to capture */
    }
    state.drag = { x0: localX(event), x1: localX(event) };
    draw();
  }
  function pointerMove(event) {
    if (state.drag) state.drag.x1 = localX(event);
    else state.hover = localX(event);
    draw();
  }
  function pointerUp() {
    const drag = state.drag;
    state.drag = null;
    if (!drag || !state.plot) return draw();
    const plot = state.plot;
    const a = Math.max(plot.x, Math.min(drag.x0, drag.x1));
    const b = Math.min(plot.x + plot.w, Math.max(drag.x0, drag.x1));
    if (b - a < 6) return draw();
    const span = state.to - state.from;
    const from = state.from + ((a - plot.x) / plot.w) * span;
    const to = state.from + ((b - plot.x) / plot.w) * span;
    if (to - from < 1000) return draw();
    state.zoomStack.push([state.from, state.to, follow().checked]);
    state.from = Math.round(from);
    state.to = Math.round(to);
    follow().checked = false;
    load();
  }

  // ------------------------------------------------------------------ live values
  HMI.on("point", (point) => {
    if (!state.shown || point.name !== state.point || !follow().checked) return;
    const time = point.time ? Date.parse(point.time) : HMI.now();
    state.samples.push([time, typeof point.value === "number" ? point.value : null, Boolean(point.invalid)]);
    const span = state.to - state.from;
    if (time > state.to) {
      state.to = time;
      state.from = time - span;
    }
    draw();
  });

  HMI.on("snapshot", () => {
    if (state.shown && !document.getElementById("trend-point").options.length) {
      fillSelect().then(load);
    }
  });

  HMI.on("ready", () => {
    document.getElementById("trend-point").addEventListener("change", (event) => {
      // The first pen; the others stay.
      state.pens = [event.target.value, ...state.pens.slice(1).filter((p) => p !== event.target.value)];
      pensChanged();
    });
    document.getElementById("trend-add").addEventListener("change", (event) => {
      const name = event.target.value;
      if (name && !state.pens.includes(name) && state.pens.length < MAX_PENS) {
        state.pens = [...state.pens, name];
        pensChanged();
      }
    });
    for (const button of document.querySelectorAll("#trend-form [data-range]")) {
      button.addEventListener("click", () => setRange(Number(button.dataset.range)));
    }
    document.getElementById("trend-back").addEventListener("click", () => {
      const previous = state.zoomStack.pop();
      if (previous) {
        [state.from, state.to] = previous;
        follow().checked = previous[2];
      } else {
        const span = state.to - state.from;
        state.from -= span / 2;
        state.to += span / 2;
      }
      load();
    });
    const c = canvas();
    c.addEventListener("pointerdown", pointerDown);
    c.addEventListener("pointermove", pointerMove);
    c.addEventListener("pointerup", pointerUp);
    c.addEventListener("pointercancel", () => {
      state.drag = null;
      draw();
    });
    c.addEventListener("pointerleave", () => {
      state.hover = null;
      if (!state.drag) draw();
    });
    window.addEventListener("resize", draw);
  });

  HMI.pages.trends = {
    async show(argument) {
      state.shown = true;
      // #trends/A,B: those pens (known points only, at most 8).
      if (argument) {
        const asked = argument.split(",").map((name) => name.trim()).filter((name) => name);
        const pens = [...new Set(asked)].slice(0, MAX_PENS);
        if (pens.length) state.pens = pens;
      }
      await fillSelect();
      if (!state.to) {
        state.to = HMI.now();
        state.from = state.to - 3600 * 1000;
      }
      load();
    },
    hide() {
      state.shown = false;
    },
  };
  HMI.trend = state;
})();
