// Stanice web HMI — mimic screens and the control dialog.
//
// A screen is an SVG file served by /api/screens/ID, put inline into the page. Its
// elements are bound to points by attributes (docs/HMI.md, "SVG bindings"). Each kind of
// binding is one entry of BINDINGS below: the attribute that names the point, the other
// attributes it reads, and how it applies a value; a new kind is a new entry.
//
//   data-point="NAME"       value: data-value = on/off (single), off/on/between/faulty
//                           (double) or the number; the stylesheet colours by it
//   data-energised="NAME"   state class: class "energised" while the single point is TRUE
//   data-text="NAME"        text: the text becomes the value (data-unit, data-digits; data-on/
//                           data-off for single points, data-map="0:start;1:mains" for numbers)
//   data-visible="NAME"     visibility: shown while the point is on (TRUE, double point on,
//                           a number other than 0), or while its value word is
//                           data-visible-when ("off", "between", "4", ...); shown while unknown
//   data-level="NAME"       level: a <rect> filled to the value's share of data-min..data-max
//                           (default 0..100), from the bottom (data-level-from="bottom", "top",
//                           "left" or "right"): tank levels, bar graphs
//   data-position="NAME"    position: moved by the value's share of data-min..data-max along
//                           the vector data-dx, data-dy (user units, default 0 0): lift cars,
//                           gates, conveyor loads
//   data-rotate="NAME"      rotation: turned to data-angle-min..data-angle-max degrees (default
//                           0..360) for data-min..data-max, about data-cx, data-cy (default
//                           the element's centre): valves, dials, fans
//   data-command="NAME"     a click opens the control dialog (data-command-value: the value sent;
//                           data-command-format="minutes": a setpoint entered as hh:mm)
//   data-link-status        shows the station link (data-value up/down; a <text> says so)
//
// Level, position and rotation read a number: TRUE is 1, FALSE 0, a double point 0..3; the
// share is clamped to 0..1; an unknown value leaves the drawing where it was. Position and
// rotation compose on one element (moved, then turned in place) with its own transform.
//
// Every bound element gets data-invalid="true" while any of its points is invalid, the
// station link is down or the live connection is closed: the stylesheet makes it blink.
"use strict";

(function () {
  const screenCache = new Map(); // id -> SVG text
  let svgRoot = null;
  let bound = new Map(); // point name -> [elements]
  let linkElements = [];
  let commandElements = [];
  let showing = null;

  // ------------------------------------------------------------------ loading a screen
  /**
   * Drops anything that could run code: the files are configuration, not programs.
   * Runs on the parsed, inert document (DOMParser: no scripts run, nothing loads), before
   * any node is imported into the page.
   */
  const ACTIVE = "script, foreignObject, iframe, object, embed, handler, listener";
  // SMIL can rewrite an attribute after sanitising: <set attributeName="href" to="javascript:…">.
  const ANIMATION = "set, animate, animateTransform, animateMotion, animateColor, discard";
  function dangerousUrl(value) {
    // Browsers ignore control characters and spaces inside a scheme ("java\tscript:").
    const compact = value.replace(/[\u0000-\u0020\u007f-\u009f]/g, "").toLowerCase();
    return /^(javascript|vbscript|data):/.test(compact) || compact.includes("javascript:");
  }
  function sanitise(svg) {
    for (const bad of svg.querySelectorAll(ACTIVE)) bad.remove();
    for (const animation of svg.querySelectorAll(ANIMATION)) {
      const target = (animation.getAttribute("attributeName") || "").trim().toLowerCase();
      const values = ["to", "from", "values", "by"].map((a) => animation.getAttribute(a) || "");
      if (target === "href" || target.endsWith(":href") || target.startsWith("on") || values.some(dangerousUrl)) {
        animation.remove();
      }
    }
    for (const element of [svg, ...svg.querySelectorAll("*")]) {
      for (const attribute of [...element.attributes]) {
        const name = attribute.name.toLowerCase();
        const value = attribute.value.trim().toLowerCase();
        if (name.startsWith("on")) element.removeAttribute(attribute.name);
        else if ((name === "href" || name.endsWith(":href")) && !value.startsWith("#")) element.removeAttribute(attribute.name);
        else if (dangerousUrl(attribute.value)) element.removeAttribute(attribute.name);
      }
    }
    return svg;
  }

  async function show(id) {
    showing = id;
    const box = document.getElementById("mimic");
    if (!id) {
      box.replaceChildren(HMI.el("p", { class: "muted", text: "No screens are configured." }));
      return;
    }
    let text = screenCache.get(id);
    if (text === undefined) {
      box.setAttribute("aria-busy", "true");
      try {
        text = await HMI.api(`/api/screens/${encodeURIComponent(id)}`);
        screenCache.set(id, text);
      } catch (error) {
        box.replaceChildren(HMI.el("p", { class: "muted", text: `Cannot load screen ${id}: ${error.message}` }));
        return;
      } finally {
        box.removeAttribute("aria-busy");
      }
      if (showing !== id) return; // the user went elsewhere meanwhile
    }
    const parsed = new DOMParser().parseFromString(text, "image/svg+xml");
    const root = parsed.documentElement;
    if (!root || root.nodeName !== "svg" || parsed.querySelector("parsererror")) {
      box.replaceChildren(HMI.el("p", { class: "muted", text: `Screen ${id} is not valid SVG.` }));
      return;
    }
    // Sanitised while still inert, then imported: no unsanitised node enters the page.
    svgRoot = document.importNode(sanitise(root), true);
    svgRoot.removeAttribute("width");
    svgRoot.removeAttribute("height");
    svgRoot.setAttribute("data-screen", id);
    svgRoot.setAttribute("role", "img");
    const banner = HMI.el("div", { class: "mimic-banner", id: "mimic-banner" });
    const natural = box.classList.contains("natural");
    const zoom = HMI.el("button", {
      type: "button",
      class: "secondary",
      id: "mimic-zoom",
      title: "Fit the screen to the width, or show it at its natural size (scroll to move)",
      text: natural ? "Fit" : "1:1",
      onclick: () => {
        const now = box.classList.toggle("natural");
        zoom.textContent = now ? "Fit" : "1:1";
        localStorage.setItem("stanice.mimic", now ? "natural" : "fit");
      },
    });
    box.replaceChildren(banner, HMI.el("div", { class: "mimic-tools" }, zoom), svgRoot);
    index();
    refreshAll();
    const screen = HMI.screens.find((s) => s.id === id);
    if (screen) document.title = `${screen.title} — ${HMI.session.title || "Stanice HMI"}`;
  }

  function index() {
    bound = new Map();
    geometry = new WeakMap();
    for (const element of svgRoot.querySelectorAll(BOUND)) {
      for (const binding of BINDINGS) {
        const name = element.getAttribute(binding.attribute);
        if (!name) continue;
        if (!bound.has(name)) bound.set(name, []);
        const list = bound.get(name);
        if (!list.includes(element)) list.push(element);
      }
    }
    linkElements = [...svgRoot.querySelectorAll("[data-link-status]")];
    commandElements = [...svgRoot.querySelectorAll("[data-command]")];
    for (const element of commandElements) {
      const control = HMI.controls.get(element.getAttribute("data-command"));
      const allowed = Boolean(control && control.allowed);
      element.classList.toggle("disabled", !allowed);
      element.setAttribute("aria-disabled", String(!allowed));
      element.setAttribute("tabindex", "0");
      element.setAttribute("role", "button");
      if (control) {
        const label = element.getAttribute("data-label") || control.description || control.command;
        element.setAttribute("aria-label", allowed ? label : `${label} (needs level ${control.level})`);
      }
    }
  }

  // ------------------------------------------------------------------ bindings
  /** A point's value as a number: TRUE 1, FALSE 0, a double point 0..3; null if unknown. */
  function numberOf(point) {
    if (!point || point.value === null || point.value === undefined) return null;
    if (typeof point.value === "boolean") return point.value ? 1 : 0;
    const value = Number(point.value);
    return Number.isFinite(value) ? value : null;
  }

  function attributeNumber(element, name, fallback) {
    const text = element.getAttribute(name);
    if (text === null || text.trim() === "") return fallback;
    const value = Number(text);
    return Number.isFinite(value) ? value : fallback;
  }

  /** The value's share of data-min..data-max, clamped to 0..1; null if unknown. */
  function share(element, point) {
    const value = numberOf(point);
    if (value === null) return null;
    const min = attributeNumber(element, "data-min", 0);
    const max = attributeNumber(element, "data-max", 100);
    if (max === min) return value >= max ? 1 : 0;
    return Math.min(1, Math.max(0, (value - min) / (max - min)));
  }

  function setValueWord(element, point) {
    const word = HMI.valueWord(point);
    if (word === "") element.removeAttribute("data-value");
    else element.setAttribute("data-value", word);
  }

  // The drawing as the file has it, per element, taken when the element first moves.
  let geometry = new WeakMap(); // element -> {transform, x, y, width, height, cx, cy, translate, rotate}
  function drawn(element) {
    let g = geometry.get(element);
    if (!g) {
      const number = (name) => attributeNumber(element, name, 0);
      g = {
        transform: element.getAttribute("transform") || "",
        x: number("x"),
        y: number("y"),
        width: number("width"),
        height: number("height"),
        translate: null,
        rotate: null,
      };
      let box = { x: 0, y: 0, width: 0, height: 0 };
      try {
        box = element.getBBox();
      } catch (error) {
        /* not rendered: the centre defaults to 0 0 */
      }
      g.cx = attributeNumber(element, "data-cx", box.x + box.width / 2);
      g.cy = attributeNumber(element, "data-cy", box.y + box.height / 2);
      geometry.set(element, g);
    }
    return g;
  }

  /** The element's own transform with the moves of its position and rotation bindings. */
  function place(element, g) {
    const parts = [];
    if (g.translate) parts.push(`translate(${g.translate[0]} ${g.translate[1]})`);
    if (g.transform) parts.push(g.transform);
    if (g.rotate !== null) parts.push(`rotate(${g.rotate} ${g.cx} ${g.cy})`);
    if (parts.length) element.setAttribute("transform", parts.join(" "));
    else element.removeAttribute("transform");
  }

  /**
   * The kinds of binding. `attribute` names the point; `reads` lists the other attributes
   * the kind reads (documentation, and what a screen author may set); `apply(element,
   * point)` shows the point's current value (null/undefined if unknown). An element may
   * carry several kinds; it is invalid while any of its points is.
   */
  const BINDINGS = [
    {
      kind: "value",
      attribute: "data-point",
      reads: [],
      apply: setValueWord,
    },
    {
      kind: "text",
      attribute: "data-text",
      reads: ["data-unit", "data-digits", "data-on", "data-off", "data-map"],
      apply(element, point) {
        element.textContent = textOf(element, point);
        if (!element.hasAttribute("data-point")) setValueWord(element, point);
      },
    },
    {
      kind: "state class",
      attribute: "data-energised",
      reads: [],
      apply(element, point) {
        element.classList.toggle("energised", Boolean(point && point.value === true));
      },
    },
    {
      kind: "visibility",
      attribute: "data-visible",
      reads: ["data-visible-when"],
      apply(element, point) {
        const when = element.getAttribute("data-visible-when");
        const value = numberOf(point);
        let shown = true; // unknown: shown, and blinking as invalid
        if (value !== null) shown = when !== null ? HMI.valueWord(point) === when.trim() : isOn(point, value);
        element.setAttribute("visibility", shown ? "visible" : "hidden");
        element.setAttribute("data-shown", String(shown));
      },
    },
    {
      kind: "level",
      attribute: "data-level",
      reads: ["data-min", "data-max", "data-level-from"],
      apply(element, point) {
        const fraction = share(element, point);
        if (fraction === null) return;
        const g = drawn(element);
        const from = (element.getAttribute("data-level-from") || "bottom").trim();
        if (from === "left" || from === "right") {
          const width = g.width * fraction;
          element.setAttribute("x", String(from === "left" ? g.x : g.x + g.width - width));
          element.setAttribute("width", String(width));
        } else {
          const height = g.height * fraction;
          element.setAttribute("y", String(from === "top" ? g.y : g.y + g.height - height));
          element.setAttribute("height", String(height));
        }
        element.setAttribute("data-share", String(fraction));
      },
    },
    {
      kind: "position",
      attribute: "data-position",
      reads: ["data-min", "data-max", "data-dx", "data-dy"],
      apply(element, point) {
        const fraction = share(element, point);
        if (fraction === null) return;
        const g = drawn(element);
        g.translate = [attributeNumber(element, "data-dx", 0) * fraction, attributeNumber(element, "data-dy", 0) * fraction];
        place(element, g);
        element.setAttribute("data-share", String(fraction));
      },
    },
    {
      kind: "rotation",
      attribute: "data-rotate",
      reads: ["data-min", "data-max", "data-angle-min", "data-angle-max", "data-cx", "data-cy"],
      apply(element, point) {
        const fraction = share(element, point);
        if (fraction === null) return;
        const g = drawn(element);
        const from = attributeNumber(element, "data-angle-min", 0);
        const to = attributeNumber(element, "data-angle-max", 360);
        g.rotate = from + (to - from) * fraction;
        place(element, g);
        element.setAttribute("data-share", String(fraction));
      },
    },
  ];
  const BOUND = BINDINGS.map((binding) => `[${binding.attribute}]`).join(", ");

  /** "On" for visibility: TRUE, a double point on (2), any other number but 0. */
  function isOn(point, value) {
    if (point.type && point.type.startsWith("M_DP")) return value === 2;
    return value !== 0;
  }

  // ------------------------------------------------------------------ showing values
  function textOf(element, point) {
    if (!point || point.value === null || point.value === undefined) return "???";
    const value = point.value;
    if (typeof value === "boolean") {
      const on = element.getAttribute("data-on");
      const off = element.getAttribute("data-off");
      return value ? (on !== null ? on : "ON") : off !== null ? off : "OFF";
    }
    const map = element.getAttribute("data-map");
    if (map) {
      for (const entry of map.split(";")) {
        const [key, ...words] = entry.split(":");
        if (key.trim() === String(value)) return words.join(":").trim();
      }
    }
    let text = typeof value === "number" ? HMI.formatNumber(value, element.getAttribute("data-digits")) : HMI.formatValue(value, point.type);
    if (point.type && point.type.startsWith("M_DP")) text = HMI.formatValue(value, point.type);
    const unit = element.getAttribute("data-unit");
    return unit ? `${text} ${unit}` : text;
  }

  /** Recomputes one element from every point it names. */
  function refresh(element) {
    let invalid = false;
    for (const binding of BINDINGS) {
      const name = element.getAttribute(binding.attribute);
      if (name === null) continue;
      const point = HMI.points.get(name);
      binding.apply(element, point);
      invalid = invalid || HMI.isInvalid(point);
    }
    if (invalid) element.setAttribute("data-invalid", "true");
    else element.removeAttribute("data-invalid");
  }

  function refreshLink() {
    for (const element of linkElements) {
      const up = HMI.wsOpen && HMI.link.up;
      element.setAttribute("data-value", up ? "up" : "down");
      if (element.tagName.toLowerCase() === "text") {
        element.textContent = !HMI.wsOpen ? "HMI offline" : up ? "link up" : "link DOWN";
      }
    }
    const banner = document.getElementById("mimic-banner");
    if (banner) {
      banner.textContent = !HMI.wsOpen
        ? "No connection to the HMI server — values are not current (reconnecting…)"
        : "Station link down — every value is invalid";
    }
  }

  function refreshAll() {
    if (!svgRoot) return;
    for (const list of bound.values()) for (const element of list) refresh(element);
    refreshLink();
  }

  HMI.on("point", (point) => {
    if (!svgRoot) return;
    for (const element of bound.get(point.name) || []) refresh(element);
    if (dialogState && dialogState.statePoint === point.name) showDialogState();
  });
  HMI.on("snapshot", refreshAll);
  HMI.on("link", refreshAll);
  HMI.on("connection", refreshAll);

  HMI.pages.screen = {
    show,
    hide() {
      showing = null;
    },
  };

  // ------------------------------------------------------------------ controls
  const dialog = () => document.getElementById("control-dialog");
  let dialogState = null; // {control, element, value, statePoint, busy}

  function valueChoices(control, element) {
    const fixed = element.getAttribute("data-command-value");
    const type = control.type || "";
    const onLabel = element.getAttribute("data-on-label") || "ON";
    const offLabel = element.getAttribute("data-off-label") || "OFF";
    if (fixed !== null) {
      const value = Number(fixed);
      const label = type.startsWith("C_SC") || type.startsWith("C_DC") ? (value ? onLabel : offLabel) : fixed;
      return { kind: "fixed", options: [{ value, label: `${fixed} — ${label}` }] };
    }
    if (type.startsWith("C_SC")) {
      return { kind: "choice", options: [{ value: 1, label: `1 — ${onLabel}` }, { value: 0, label: `0 — ${offLabel}` }] };
    }
    if (type.startsWith("C_DC") || type.startsWith("C_RC")) {
      return { kind: "choice", options: [{ value: 2, label: `2 — ${onLabel}` }, { value: 1, label: `1 — ${offLabel}` }] };
    }
    return { kind: element.getAttribute("data-command-format") === "minutes" ? "minutes" : "number", options: [] };
  }

  function showDialogState() {
    const target = document.getElementById("control-state");
    if (!dialogState || !dialogState.statePoint) {
      target.textContent = "—";
      return;
    }
    const point = HMI.points.get(dialogState.statePoint);
    if (!point) {
      target.textContent = "—";
      return;
    }
    const value = HMI.formatValue(point.value, point.type);
    target.textContent = `${point.description || point.name}: ${value}${HMI.isInvalid(point) ? " (invalid)" : ""}`;
  }

  function step(name) {
    for (const id of ["value", "confirm", "result"]) {
      document.getElementById(`control-step-${id}`).hidden = id !== name;
    }
    dialog().dataset.step = name;
  }

  function openControl(element) {
    const name = element.getAttribute("data-command");
    const control = HMI.controls.get(name);
    if (!control) {
      HMI.toast(`${name}: no such command in points.csv`, true);
      return;
    }
    if (!control.allowed) {
      HMI.toast(
        `${control.description || name}: not permitted — level ${control.level} needed, you have level ${HMI.session.level}.`,
        true,
      );
      return;
    }
    const choices = valueChoices(control, element);
    dialogState = {
      control,
      element,
      choices,
      statePoint: element.getAttribute("data-point") || element.getAttribute("data-state-point"),
      value: choices.options.length ? choices.options[0].value : null,
    };
    const label = element.getAttribute("data-label");
    document.getElementById("control-title").textContent = label || control.description || name;
    document.getElementById("control-description").textContent = label && control.description ? control.description : "";
    document.getElementById("control-name").textContent = `${name} (IOA ${control.ioa}, ${control.type})`;
    showDialogState();

    const fieldset = document.getElementById("control-values");
    const legend = HMI.el("legend", { text: "Value to send" });
    const inputs = [];
    if (choices.kind === "fixed" || choices.kind === "choice") {
      choices.options.forEach((option, i) => {
        const input = HMI.el("input", {
          type: "radio",
          name: "control-value",
          value: String(option.value),
          checked: i === 0,
          disabled: choices.kind === "fixed",
        });
        inputs.push(HMI.el("label", {}, input, option.label));
      });
    } else if (choices.kind === "minutes") {
      inputs.push(HMI.el("label", {}, "Time ", HMI.el("input", { type: "time", name: "control-number", required: true, value: "00:00" })));
    } else {
      inputs.push(HMI.el("label", {}, "Value ", HMI.el("input", { type: "number", name: "control-number", step: "any", required: true, value: "0" })));
    }
    fieldset.replaceChildren(legend, ...inputs);
    step("value");
    if (!dialog().open) dialog().showModal();
    const first = fieldset.querySelector("input:not([disabled])") || document.getElementById("control-next");
    first.focus();
  }

  function chosenValue() {
    const { choices } = dialogState;
    if (choices.kind === "fixed") return choices.options[0].value;
    if (choices.kind === "choice") {
      const checked = document.querySelector('#control-values input[name="control-value"]:checked');
      return checked ? Number(checked.value) : null;
    }
    const input = document.querySelector('#control-values input[name="control-number"]');
    if (!input || input.value === "") return null;
    if (choices.kind === "minutes") {
      const [h, m] = input.value.split(":").map(Number);
      return h * 60 + m;
    }
    const value = Number(input.value);
    return Number.isFinite(value) ? value : null;
  }

  function valueLabel(value) {
    const option = dialogState.choices.options.find((o) => o.value === value);
    if (option) return option.label;
    if (dialogState.choices.kind === "minutes") return `${HMI.pad(Math.floor(value / 60))}:${HMI.pad(value % 60)} (${value} min)`;
    return String(value);
  }

  function toConfirm() {
    const value = chosenValue();
    if (value === null) {
      HMI.toast("Choose the value to send.", true);
      return;
    }
    dialogState.value = value;
    const { control } = dialogState;
    const what = control.description || control.command;
    document.getElementById("control-confirm").textContent = control.confirm
      ? `${control.confirm} (value ${valueLabel(value)})`
      : `Send “${what}” with value ${valueLabel(value)}?`;
    document.getElementById("control-sbo").hidden = !control.select;
    step("confirm");
    document.getElementById("control-execute").focus();
  }

  async function execute() {
    if (!dialogState || dialogState.busy) return;
    dialogState.busy = true;
    const { control, value } = dialogState;
    const outcome = document.getElementById("control-outcome");
    const detail = document.getElementById("control-detail");
    outcome.dataset.outcome = "pending";
    outcome.textContent = control.select ? "Selecting and executing…" : "Sending…";
    detail.textContent = "";
    step("result");
    let result;
    try {
      result = await HMI.post("/api/command", { command: control.command, value });
    } catch (error) {
      result = { status: 0, body: { outcome: "error", detail: error.message } };
    }
    const body = result.body || {};
    const word = body.outcome || (result.status === 403 ? "refused-permission" : "error");
    outcome.dataset.outcome = word;
    outcome.textContent =
      word === "error" ? `Failed: ${body.error || body.detail || `HTTP ${result.status}`}` : `${control.command} = ${value}: ${HMI.outcomeWords(word)}`;
    detail.textContent = body.detail || "";
    dialogState.busy = false;
    document.querySelector("#control-step-result button").focus();
  }

  function close() {
    if (dialog().open) dialog().close();
    dialogState = null;
  }

  // ------------------------------------------------------------------ point information
  // Hovering (or touching) a bound element shows its point: name, description, value,
  // quality and time tag.
  let info = null;
  function pointInfo(event) {
    const element = event.target.closest && event.target.closest(BOUND);
    if (!element || !svgRoot || !svgRoot.contains(element)) {
      if (info) info.hidden = true;
      return;
    }
    const name = BINDINGS.map((binding) => element.getAttribute(binding.attribute)).find(Boolean);
    const point = HMI.points.get(name);
    if (!info) {
      info = HMI.el("div", { id: "point-info", role: "tooltip" });
      document.body.append(info);
    }
    const quality = !point ? "unknown point" : HMI.isInvalid(point) ? `invalid${point.quality && point.quality.length ? ` (${point.quality.join(" ")})` : ""}` : (point.quality || []).join(" ") || "good";
    info.replaceChildren(
      HMI.el("strong", { text: name }),
      HMI.el("div", { class: "muted", text: point ? `${point.description || ""} — IOA ${point.ioa}, ${point.type || ""}` : "" }),
      HMI.el("div", { text: `value ${point ? HMI.formatValue(point.value, point.type) : "—"}, ${quality}` }),
      HMI.el("div", { class: "muted", text: point && point.time ? `time tag ${HMI.formatTime(point.time, true)}` : "no time tag" }),
    );
    info.hidden = false;
    const x = Math.min(event.clientX + 14, window.innerWidth - info.offsetWidth - 8);
    const y = event.clientY + 16 + info.offsetHeight > window.innerHeight ? event.clientY - info.offsetHeight - 12 : event.clientY + 16;
    info.style.left = `${Math.max(4, x)}px`;
    info.style.top = `${Math.max(4, y)}px`;
  }

  HMI.on("ready", () => {
    const box = document.getElementById("mimic");
    box.addEventListener("pointermove", pointInfo);
    box.addEventListener("pointerleave", () => {
      if (info) info.hidden = true;
    });
    box.classList.toggle("natural", localStorage.getItem("stanice.mimic") === "natural");
    box.addEventListener("click", (event) => {
      const element = event.target.closest("[data-command]");
      if (element && box.contains(element)) openControl(element);
    });
    box.addEventListener("keydown", (event) => {
      if (event.key !== "Enter" && event.key !== " ") return;
      const element = event.target.closest("[data-command]");
      if (element && box.contains(element)) {
        event.preventDefault();
        openControl(element);
      }
    });
    document.getElementById("control-next").addEventListener("click", toConfirm);
    document.getElementById("control-execute").addEventListener("click", execute);
    for (const button of document.querySelectorAll("#control-dialog [data-close]")) button.addEventListener("click", close);
    dialog().addEventListener("close", () => {
      dialogState = null;
    });
    document.getElementById("control-form").addEventListener("submit", (event) => event.preventDefault());
  });

  HMI.mimic = { refreshAll, openControl };
})();
