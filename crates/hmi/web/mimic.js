// Stanice web HMI — mimic screens and the control dialog.
//
// A screen is an SVG file served by /api/screens/ID, put inline into the page. Its
// elements are bound to points by attributes (docs/HMI.md, "SVG bindings"):
//
//   data-point="NAME"       data-value = on/off (single), off/on/between/faulty (double) or the number
//   data-energised="NAME"   class "energised" while the single point is TRUE
//   data-text="NAME"        the text becomes the value (data-unit, data-digits; data-on/data-off
//                           for single points, data-map="0:start;1:mains" for numbers)
//   data-command="NAME"     a click opens the control dialog (data-command-value: the value sent;
//                           data-command-format="minutes": a setpoint entered as hh:mm)
//   data-link-status        shows the station link (data-value up/down; a <text> says so)
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
    const add = (name, element) => {
      if (!name) return;
      if (!bound.has(name)) bound.set(name, []);
      const list = bound.get(name);
      if (!list.includes(element)) list.push(element);
    };
    for (const element of svgRoot.querySelectorAll("[data-point], [data-energised], [data-text]")) {
      add(element.getAttribute("data-point"), element);
      add(element.getAttribute("data-energised"), element);
      add(element.getAttribute("data-text"), element);
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
    const pointName = element.getAttribute("data-point");
    if (pointName !== null) {
      const point = HMI.points.get(pointName);
      const word = HMI.valueWord(point);
      if (word === "") element.removeAttribute("data-value");
      else element.setAttribute("data-value", word);
      invalid = invalid || HMI.isInvalid(point);
    }
    const energisedName = element.getAttribute("data-energised");
    if (energisedName !== null) {
      const point = HMI.points.get(energisedName);
      element.classList.toggle("energised", Boolean(point && point.value === true));
      invalid = invalid || HMI.isInvalid(point);
    }
    const textName = element.getAttribute("data-text");
    if (textName !== null) {
      const point = HMI.points.get(textName);
      element.textContent = textOf(element, point);
      if (pointName === null) {
        const word = HMI.valueWord(point);
        if (word === "") element.removeAttribute("data-value");
        else element.setAttribute("data-value", word);
      }
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
    const element = event.target.closest && event.target.closest("[data-point], [data-text], [data-energised]");
    if (!element || !svgRoot || !svgRoot.contains(element)) {
      if (info) info.hidden = true;
      return;
    }
    const name = element.getAttribute("data-point") || element.getAttribute("data-text") || element.getAttribute("data-energised");
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
