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
  const screenCache = new Map(); // id -> Promise of the screen's markup (fetched once)
  let svgRoot = null;
  let bound = new Map(); // point name -> [elements]
  let linkElements = [];
  let commandElements = [];
  let showing = null;
  let changes = new Map(); // point name -> {value, at: Date of the last change seen here, or null}

  // ------------------------------------------------------------------ loading a screen
  // The server checks every screen file and writes it again with only what is safe and
  // needed (crates/mimic-svg): no script, foreignObject, event handler, link other than a
  // `#` link, javascript:/data: URL or SMIL that would set one; markup that the HTML
  // parser reads as the XML parser would. So the page puts it in with the HTML parser,
  // which is several times quicker than DOMParser plus a second pass over every element
  // here (a screen of 10,000 elements: about 100 ms against 400-550 ms); the
  // Content-Security-Policy (no inline scripts) is the second line.
  const SVG_NS = "http://www.w3.org/2000/svg";

  /** The screen's markup, fetched once per page (a failed fetch is tried again next time). */
  function fetchScreen(id) {
    let promise = screenCache.get(id);
    if (!promise) {
      const path = `/api/screens/${encodeURIComponent(id)}`;
      // The screen early.js asked for while the page loaded, once; else a request now.
      const early = window.STANICE_EARLY && window.STANICE_EARLY.screen;
      if (early && early.id === id) {
        window.STANICE_EARLY.screen = null;
        promise = early.response.then((response) => HMI.body(HMI.admit(response, path)));
      } else {
        promise = HMI.api(path);
      }
      screenCache.set(id, promise);
      promise.catch(() => screenCache.delete(id));
    }
    return promise;
  }
  // app.js asks for the screen of the address while the session and the lists load.
  HMI.prefetchScreen = (id) => fetchScreen(id).catch(() => {});

  async function show(id) {
    performance.mark("hmi:screen-open", { detail: id });
    showing = id;
    const box = document.getElementById("mimic");
    if (!id) {
      box.replaceChildren(HMI.el("p", { class: "muted", text: "No screens are configured." }));
      return;
    }
    let text;
    box.setAttribute("aria-busy", "true");
    try {
      text = await fetchScreen(id);
    } catch (error) {
      if (showing === id) box.replaceChildren(HMI.el("p", { class: "muted", text: `Cannot load screen ${id}: ${error.message}` }));
      return;
    } finally {
      box.removeAttribute("aria-busy");
    }
    if (showing !== id) return; // the user went elsewhere meanwhile
    performance.mark("hmi:screen-fetched");
    const holder = document.createElement("div");
    holder.innerHTML = text;
    const root = holder.firstElementChild;
    if (!root || root.namespaceURI !== SVG_NS || root.localName !== "svg") {
      box.replaceChildren(HMI.el("p", { class: "muted", text: `Screen ${id} is not valid SVG.` }));
      return;
    }
    performance.mark("hmi:screen-parsed");
    // While the page loads, the live connection's first snapshot is usually on its way:
    // waiting for it (at most 1.5 s) draws the screen once, with its values, instead of
    // drawing 10,000 elements as unknown and then again.
    if (HMI.firstSnapshotArrived) {
      await Promise.race([HMI.firstSnapshot, new Promise((resolve) => setTimeout(resolve, 1500))]);
      if (showing !== id) return;
    }
    svgRoot = root;
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
    const hint = HMI.el("span", { class: "hint", text: "drag or scroll to move, pinch to zoom" });
    box.replaceChildren(banner, HMI.el("div", { class: "mimic-tools" }, hint, zoom), svgRoot);
    performance.mark("hmi:screen-inserted");
    index();
    performance.mark("hmi:screen-indexed");
    refreshAll();
    fitReadable();
    // Performance marks for measuring a screen's fill (crates/hmi/benches/live.rs): drawn
    // now; filled once every bound point shows a valid value (noteFilled).
    performance.mark("hmi:screen-drawn", { detail: id });
    filledMarked = false;
    noteFilled();
    const screen = HMI.screens.find((s) => s.id === id);
    if (screen) document.title = `${screen.title} — ${HMI.session.title || "Stanice HMI"}`;
  }

  // ------------------------------------------------------------------ phones
  // On a narrow screen the drawing is not fitted to the width (a 1200-unit screen fitted to
  // 390 px draws 13-px labels at 4 px): it is drawn at the scale where its smallest text is
  // 12 px, panned inside its box by scrolling (touch) or dragging (mouse), and zoomed by
  // the browser's pinch zoom. The Fit/1:1 toggle is for wide screens only.
  const PHONE = window.matchMedia("(max-width: 760px)");
  const READABLE_PX = 12;
  function fitReadable() {
    const box = document.getElementById("mimic");
    const zoom = document.getElementById("mimic-zoom");
    const hint = box.querySelector(".mimic-tools .hint");
    const phone = PHONE.matches;
    box.classList.toggle("readable", phone);
    if (zoom) zoom.hidden = phone;
    if (hint) hint.hidden = !phone;
    if (!svgRoot) return;
    if (!phone) {
      svgRoot.style.width = "";
      return;
    }
    const viewBox = svgRoot.viewBox && svgRoot.viewBox.baseVal;
    const width = viewBox && viewBox.width ? viewBox.width : svgRoot.getBBox().width;
    let smallest = Infinity;
    for (const text of svgRoot.querySelectorAll("text")) {
      if (!text.textContent.trim() && !text.hasAttribute("data-text") && !text.hasAttribute("data-link-status")) continue;
      const size = parseFloat(getComputedStyle(text).fontSize);
      if (size > 0 && size < smallest) smallest = size;
    }
    const scale = Number.isFinite(smallest) ? Math.max(1, READABLE_PX / smallest) : 1;
    // A hair over, so that rounding never draws 11.99 px.
    svgRoot.style.width = `${Math.ceil(width * scale * 1.01)}px`;
  }
  PHONE.addEventListener("change", fitReadable);

  // Dragging the drawing with a mouse moves it inside its box; a drag is not a click.
  let panned = false;
  function panning(box) {
    let start = null;
    box.addEventListener("pointerdown", (event) => {
      panned = false;
      if (event.pointerType !== "mouse" || event.button !== 0) return;
      if (box.scrollWidth <= box.clientWidth && box.scrollHeight <= box.clientHeight) return;
      start = { x: event.clientX, y: event.clientY, left: box.scrollLeft, top: box.scrollTop };
    });
    box.addEventListener("pointermove", (event) => {
      if (!start) return;
      const dx = event.clientX - start.x;
      const dy = event.clientY - start.y;
      if (!panned && Math.hypot(dx, dy) < 6) return;
      panned = true;
      box.classList.add("panning");
      box.scrollLeft = start.left - dx;
      box.scrollTop = start.top - dy;
    });
    const end = () => {
      start = null;
      box.classList.remove("panning");
      // The click that ends a drag comes right after pointerup: forget the drag after it.
      setTimeout(() => {
        panned = false;
      }, 0);
    };
    box.addEventListener("pointerup", end);
    box.addEventListener("pointercancel", end);
  }

  function index() {
    bound = new Map();
    bindingsOf = new WeakMap();
    geometry = new WeakMap();
    // The elements' bindings, read once: a redraw runs only these. One selector query per
    // kind of binding finds the elements that have it (matched natively), so a screen of
    // 10,000 elements is indexed with one attribute lookup per binding there is, not one
    // per kind per element (90,000 lookups: ~100 ms of a fresh page's fill, ~25 warm).
    // Binding kinds go in BINDINGS order, so each element's list keeps that order.
    for (const binding of BINDINGS) {
      for (const element of svgRoot.querySelectorAll(`[${binding.attribute}]`)) {
        const name = element.getAttribute(binding.attribute);
        if (!name) continue;
        let own = bindingsOf.get(element);
        if (!own) bindingsOf.set(element, (own = []));
        own.push({ binding, name });
        let list = bound.get(name);
        if (!list) bound.set(name, (list = []));
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
  let bindingsOf = new WeakMap(); // element -> [{binding, name}], from index()
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
    for (const { binding, name } of bindingsOf.get(element) || []) {
      const point = HMI.points.get(name);
      binding.apply(element, point);
      invalid = invalid || HMI.isInvalid(point);
    }
    // Before the live connection first opened (the page is loading) nothing is marked
    // lost: the values are not known yet, the banner says so, and a screen of thousands of
    // blinking elements would only slow the first values down. A connection that closes
    // later marks everything.
    if (invalid && wasOpen !== null) element.setAttribute("data-invalid", "true");
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
    applied = new Map();
    for (const [name, list] of bound) {
      applied.set(name, drawnAs(HMI.points.get(name)));
      for (const element of list) refresh(element);
    }
    refreshLink();
    showDialogState();
    showFaceplate();
  }

  // Live updates are coalesced. A point message only notes the point's name; after the
  // live connection's message (one or a batch of many, batch=1) the names it brought are
  // applied at once when they are few (at most LONE: a lone change shows without waiting
  // for a frame, whatever else is pending) or while the DOM work done outside animation
  // frames within the current frame interval is under IMMEDIATE_BUDGET_MS. The rest wait
  // for the next animation frame, each point once with its latest value, and a frame
  // applies them in the order they came for at most FRAME_BUDGET_MS, leaving the others to
  // the frames after it: a burst of thousands never holds the page's main thread for
  // longer than a frame (drawing the changed elements comes on top), so a change that
  // arrives meanwhile is not queued behind it. A point whose value and validity are those
  // already drawn is skipped.
  const FRAME_MS = 16;
  const SMALL_BATCH = 64;
  const LONE = 16;
  const IMMEDIATE_BUDGET_MS = 3;
  const FRAME_BUDGET_MS = 6;
  let pending = new Set(); // point names changed and not yet applied, in the order they came
  let fresh = new Set(); // the names the current live message brought
  let flushQueued = false;
  let pendingAll = false; // everything to redraw (snapshot, link, connection)
  let frame = null; // the requested animation frame, if one is
  let immediateSpent = 0; // ms of immediate applies in the frame interval since immediateFrom
  let immediateFrom = -Infinity;
  let applied = new Map(); // point name -> what its elements show ("value|invalid")

  /** Values are numbers, booleans, strings or null; a bit string may come as an array. */
  function sameValue(a, b) {
    return a === b || (typeof a === "object" && a !== null && JSON.stringify(a) === JSON.stringify(b));
  }

  // What a point's elements show: its value and validity, compared without building a
  // string per update.
  function drawnAs(point) {
    return point ? { value: point.value, invalid: HMI.isInvalid(point) } : null;
  }
  function drawnSame(drawn, point) {
    if (drawn === undefined) return false;
    if (drawn === null || !point) return drawn === null && !point;
    return drawn.invalid === HMI.isInvalid(point) && sameValue(drawn.value, point.value);
  }

  // Whether the "screen filled" mark was set for the screen shown; until then, after each
  // apply, whether every bound point is drawn with a valid value (a pass over the points
  // per apply, only until the screen has filled once).
  let filledMarked = false;
  function noteFilled() {
    if (filledMarked || !svgRoot) return;
    for (const name of bound.keys()) {
      const drawn = applied.get(name);
      if (!drawn || drawn.invalid) return;
    }
    filledMarked = true;
    performance.mark("hmi:screen-filled", { detail: svgRoot.getAttribute("data-screen") });
  }

  /** Redraws the elements of one point (skipped when drawn as it is). */
  function applyName(name) {
    const point = HMI.points.get(name);
    const drawn = applied.get(name);
    if (drawnSame(drawn, point)) return;
    if (drawn && point) {
      drawn.value = point.value;
      drawn.invalid = HMI.isInvalid(point);
    } else {
      applied.set(name, drawnAs(point));
    }
    for (const element of bound.get(name) || []) refresh(element);
  }

  /** What depends on these points besides their elements: the dialog, the faceplate, the fill mark. */
  function afterApplying(names) {
    if (dialogState && names.has(dialogState.statePoint)) showDialogState();
    if (faceplateState && faceplateState.names.some((name) => names.has(name))) showFaceplate();
    noteFilled();
  }

  /** Redraws the elements of these points (each once; skipped when drawn as they are). */
  function applyNames(names) {
    if (!svgRoot) return;
    for (const name of names) applyName(name);
    afterApplying(names);
  }

  function applyPending() {
    frame = null;
    if (!svgRoot) {
      pending = new Set();
      return;
    }
    if (pendingAll) {
      // The link or the connection changed: every element's validity may have; the
      // comparison in applyName still skips the ones drawn as they are. (All at once: it
      // happens on a reconnection, not 10,000 times a second.)
      pendingAll = false;
      for (const name of bound.keys()) pending.add(name);
      refreshLink();
      if (dialogState) pending.add(dialogState.statePoint);
      if (faceplateState) pending.add(faceplateState.names[0]);
      const names = pending;
      pending = new Set();
      applyNames(names);
      return;
    }
    applyUntil(pending, performance.now() + FRAME_BUDGET_MS);
    if (pending.size > 0) applySoon();
  }

  /**
   * Applies `names` in their order until `deadline` (checked every SMALL_BATCH names),
   * each taken out of `pending`; what depends on them follows once.
   */
  function applyUntil(names, deadline) {
    const done = new Set();
    for (const name of names) {
      if (done.size % SMALL_BATCH === SMALL_BATCH - 1 && performance.now() >= deadline) break;
      pending.delete(name);
      applyName(name);
      done.add(name);
    }
    afterApplying(done);
  }

  // The next frame, or FRAME_MS at the latest: a browser may hold animation frames back
  // (headless, occluded), and a value must not wait for them.
  let timer = null;
  function applySoon() {
    if (frame !== null) return;
    const run = () => {
      cancelAnimationFrame(frame);
      clearTimeout(timer);
      applyPending();
    };
    frame = requestAnimationFrame(run);
    timer = setTimeout(run, FRAME_MS);
  }

  /**
   * After a live message: its names now, in the order they came, when they are few or
   * while the frame interval's immediate budget lasts (checked every SMALL_BATCH names);
   * the rest at the next frames. A change in a burst of thousands then mostly shows at
   * once instead of waiting up to a frame, and the budget keeps the page's frames for
   * drawing.
   */
  function flush() {
    flushQueued = false;
    const names = fresh;
    fresh = new Set();
    const start = performance.now();
    if (start - immediateFrom >= FRAME_MS) {
      immediateFrom = start;
      immediateSpent = 0;
    }
    if (!pendingAll && svgRoot && (names.size <= LONE || immediateSpent < IMMEDIATE_BUDGET_MS)) {
      applyUntil(names, start + Math.max(0, IMMEDIATE_BUDGET_MS - immediateSpent));
      immediateSpent += performance.now() - start;
    }
    if (pending.size > 0 || pendingAll) applySoon();
  }

  function scheduleApply(name) {
    pending.add(name);
    fresh.add(name);
    if (!flushQueued) {
      flushQueued = true;
      // A microtask runs once the live message's handler is done: a batch is one flush.
      queueMicrotask(flush);
    }
  }

  function noteChange(point) {
    const change = changes.get(point.name);
    if (!change) changes.set(point.name, { value: point.value, at: null });
    else if (!sameValue(change.value, point.value)) {
      // In place: 10,000 updates a second make no garbage here.
      change.value = point.value;
      change.at = new Date();
    }
  }

  HMI.on("point", (point) => {
    noteChange(point);
    if (!svgRoot) return;
    if (!bound.has(point.name) && !(dialogState && dialogState.statePoint === point.name) &&
        !(faceplateState && faceplateState.names.includes(point.name))) return;
    scheduleApply(point.name);
  });
  function redrawAll() {
    pendingAll = true;
    applySoon();
  }
  // A snapshot (on connecting, and again when this browser fell behind) redraws only the
  // points whose value or validity differs from what is drawn.
  HMI.on("snapshot", () => {
    for (const point of HMI.points.values()) {
      noteChange(point);
      if (bound.has(point.name) && !drawnSame(applied.get(point.name), point)) pending.add(point.name);
    }
    applySoon();
  });
  HMI.on("link", redrawAll);
  let wasOpen = null;
  HMI.on("connection", (open) => {
    if (open === wasOpen) return;
    wasOpen = open;
    redrawAll();
  });

  HMI.pages.screen = {
    show,
    hide() {
      showing = null;
      closeFaceplate();
    },
  };

  // ------------------------------------------------------------------ controls
  const dialog = () => document.getElementById("control-dialog");
  let dialogState = null; // {control, element, value, statePoint, busy}

  /** The words of a command's values: the element's data-on-label/data-off-label, else
   * the words of the state point's element (data-on/data-off), else ON/OFF. */
  function valueChoices(control, element) {
    const fixed = element.getAttribute("data-command-value");
    const type = control.type || "";
    const onLabel = element.getAttribute("data-on-label") || "ON";
    const offLabel = element.getAttribute("data-off-label") || "OFF";
    if (fixed !== null) {
      const value = Number(fixed);
      const label =
        element.getAttribute("data-label") ||
        (type.startsWith("C_SC") || type.startsWith("C_DC") || type.startsWith("C_RC") ? (value ? onLabel : offLabel) : fixed);
      return { kind: "fixed", options: [{ value, label }] };
    }
    if (type.startsWith("C_SC")) {
      return { kind: "choice", options: [{ value: 1, label: onLabel }, { value: 0, label: offLabel }] };
    }
    if (type.startsWith("C_DC") || type.startsWith("C_RC")) {
      return { kind: "choice", options: [{ value: 2, label: onLabel }, { value: 1, label: offLabel }] };
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
    target.textContent = `${point.description || point.name}: ${valueInWords(point)}${HMI.isInvalid(point) ? " (not valid now)" : ""}`;
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
    document.getElementById("control-name").textContent = `${name} (IOA ${control.ioa}, ${typeWords(control.type)})`;
    showDialogState();

    const fieldset = document.getElementById("control-values");
    const legend = HMI.el("legend", { text: "What to do" });
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

  /** The value chosen, in the dialog's words: the option's label, hh:mm, or the number with its unit. */
  function valueLabel(value) {
    const option = dialogState.choices.options.find((o) => o.value === value);
    if (option) return option.label;
    if (dialogState.choices.kind === "minutes") return `${HMI.pad(Math.floor(value / 60))}:${HMI.pad(value % 60)}`;
    const unit = dialogState.element.getAttribute("data-unit");
    return unit ? `${HMI.formatNumber(value)} ${unit}` : HMI.formatNumber(value);
  }

  /** What the command does, for the dialog's sentences: the element's label or the command's description. */
  function commandWords() {
    const { control, element } = dialogState;
    return element.getAttribute("data-label") || control.description || control.command;
  }

  /** The question before executing: hmi.toml's `confirm` for a command of one meaning, else built from the words. */
  function question(value) {
    const { control, choices } = dialogState;
    const label = valueLabel(value);
    if (choices.kind === "fixed") return control.confirm || (label.endsWith("?") ? label : `${label}?`);
    if (choices.kind === "choice") {
      const what = control.description || control.command;
      return control.confirm ? `${control.confirm} — ${label}` : `${what}: ${label}?`;
    }
    const what = commandWords();
    return control.confirm ? `${control.confirm} — set to ${label}` : `${what}: set to ${label}?`;
  }

  /** The outcome's subject: what was done, in words. */
  function doneWords(value) {
    const { choices } = dialogState;
    const label = valueLabel(value);
    if (choices.kind === "fixed") return label.replace(/\?$/, "");
    if (choices.kind === "choice") return `${commandWords()}: ${label}`;
    return `${commandWords()} set to ${label}`;
  }

  function toConfirm() {
    const value = chosenValue();
    if (value === null) {
      HMI.toast("Choose the value to send.", true);
      return;
    }
    dialogState.value = value;
    const { control } = dialogState;
    document.getElementById("control-confirm").textContent = question(value);
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
    const subject = doneWords(value);
    outcome.textContent =
      word === "error" ? `${subject}: failed — ${body.error || body.detail || `the HMI answered ${result.status}`}` : `${subject}: ${HMI.outcomeWords(word)}`;
    detail.textContent = body.detail || "";
    dialogState.busy = false;
    document.querySelector("#control-step-result button").focus();
  }

  function close() {
    if (dialog().open) dialog().close();
    dialogState = null;
  }

  // ------------------------------------------------------------------ the faceplate
  // A click on a bound element (one without data-command, which opens the control
  // dialog) opens the faceplate of its point(s): name and description, the value in
  // words, the quality in words, the time tag with date and zone, the source, the last
  // change seen, and the commands whose state point it is. It stays open, following the
  // value live, until closed (its button or Esc).
  //
  // The commands of a point: the elements of this screen with data-command whose
  // data-state-point (or data-point) names the point, as buttons opening their control
  // dialog; then the controls of hmi.toml whose `local_point` is the point (refused while
  // it says local), named.
  let faceplateState = null; // {element, names: [point names]}
  const faceplate = () => document.getElementById("faceplate");

  const TYPE_WORDS = {
    M_SP: "single point",
    M_DP: "double point",
    M_ST: "step position",
    M_BO: "bitstring",
    M_ME_NA: "measured value, normalised",
    M_ME_NB: "measured value, scaled",
    M_ME_NC: "measured value, floating point",
    M_IT: "integrated total (counter)",
    C_SC: "single command",
    C_DC: "double command",
    C_RC: "regulating step command",
    C_SE_NA: "setpoint, normalised",
    C_SE_NB: "setpoint, scaled",
    C_SE_NC: "setpoint, floating point",
  };
  /** The IEC type in words, with its mnemonic. */
  function typeWords(type) {
    if (!type) return "unknown type";
    const key = Object.keys(TYPE_WORDS).find((prefix) => type.startsWith(prefix));
    return key ? `${TYPE_WORDS[key]} (${type})` : type;
  }

  const QUALITY_WORDS = { IV: "invalid", NT: "not topical", SB: "substituted", BL: "blocked", OV: "overflow" };
  /** The quality in words: good, or the flags set, with why the HMI does not trust it. */
  function qualityWords(point) {
    if (!point) return "unknown point";
    if (!HMI.wsOpen) return "not current: no connection to the HMI server";
    if (!HMI.link.up) return "invalid: the station link is down";
    if (point.value === null || point.value === undefined) return "invalid: no value received yet";
    const flags = (point.quality || []).map((flag) => QUALITY_WORDS[flag] || flag);
    if (point.invalid && !flags.includes("invalid")) flags.unshift("invalid");
    return flags.length ? flags.join(", ") : "good";
  }

  /** A time with its date and zone, e.g. 2026-11-27 13:55:03.120 UTC+01:00 (Europe/Prague). */
  function timeWithZone(time) {
    const d = time instanceof Date ? time : new Date(time);
    if (Number.isNaN(d.getTime())) return String(time);
    const minutes = -d.getTimezoneOffset();
    const sign = minutes < 0 ? "-" : "+";
    const offset = `UTC${sign}${HMI.pad(Math.floor(Math.abs(minutes) / 60))}:${HMI.pad(Math.abs(minutes) % 60)}`;
    let zone = "";
    try {
      zone = Intl.DateTimeFormat().resolvedOptions().timeZone || "";
    } catch (error) {
      /* the offset says enough */
    }
    return `${HMI.formatTime(d, true)} ${offset}${zone ? ` (${zone})` : ""}`;
  }

  /** An element of this screen that words `name`'s values (data-on/data-off, data-unit, data-map). */
  function wordingElement(name, preferred) {
    const words = (element) =>
      element &&
      element.getAttribute("data-text") === name &&
      ["data-on", "data-off", "data-unit", "data-map"].some((a) => element.getAttribute(a));
    if (words(preferred)) return preferred;
    return (bound.get(name) || []).find(words) || null;
  }

  /** A point's value in words: the screen's words for it, else on/off, open/closed/between/faulty, or the number with its unit. */
  function valueInWords(point, preferred) {
    if (!point || point.value === null || point.value === undefined) return "no value";
    const element = wordingElement(point.name, preferred);
    if (element) {
      const text = textOf(element, point);
      if (text !== "") return text;
    }
    if (typeof point.value === "boolean") return point.value ? "on" : "off";
    if (point.type && point.type.startsWith("M_DP")) {
      return ["between (intermediate position)", "open (off)", "closed (on)", "faulty (indeterminate)"][point.value] || "faulty";
    }
    return HMI.formatValue(point.value, point.type);
  }

  /** The point names an element shows, in the order of BINDINGS, each once. */
  function pointNames(element) {
    const names = [];
    for (const binding of BINDINGS) {
      const name = element.getAttribute(binding.attribute);
      if (name && !names.includes(name)) names.push(name);
    }
    return names;
  }

  function commandsOf(name) {
    const onScreen = svgRoot
      ? [...svgRoot.querySelectorAll("[data-command]")].filter(
          (element) => element.getAttribute("data-state-point") === name || element.getAttribute("data-point") === name,
        )
      : [];
    const interlocked = [...HMI.controls.values()].filter((control) => control.local_point === name);
    return { onScreen, interlocked };
  }

  function faceplateSection(name) {
    const point = HMI.points.get(name);
    const change = changes.get(name);
    const facts = HMI.el("dl", { class: "facts" });
    const fact = (term, text, key) => facts.append(HMI.el("dt", { text: term }), HMI.el("dd", { text, "data-fact": key }));
    const preferred = faceplateState && faceplateState.element;
    fact("Value", valueInWords(point, preferred), "value");
    fact("Quality", qualityWords(point), "quality");
    fact("Time tag", point && point.time ? timeWithZone(point.time) : "none (the station sent no time tag)", "time");
    fact("Last change", change && change.at ? timeWithZone(change.at) : "not since this page connected", "changed");
    fact(
      "Source",
      point ? `station ${HMI.link.address || "—"}, IOA ${point.ioa}, ${typeWords(point.type)}` : "not in points.csv",
      "source",
    );
    const { onScreen, interlocked } = commandsOf(name);
    const commands = HMI.el("div", { class: "faceplate-commands", "data-fact": "commands" });
    for (const element of onScreen) {
      const control = HMI.controls.get(element.getAttribute("data-command"));
      const label = element.getAttribute("data-label") || (control && control.description) || element.getAttribute("data-command");
      commands.append(
        HMI.el("button", {
          type: "button",
          class: "secondary",
          text: label,
          disabled: !(control && control.allowed),
          title: control && !control.allowed ? `needs level ${control.level}` : "",
          onclick: () => openControl(element),
        }),
      );
    }
    for (const control of interlocked) {
      commands.append(HMI.el("div", { class: "muted", text: `${control.description || control.command}: refused while this says local` }));
    }
    if (!commands.children.length) commands.append(HMI.el("span", { class: "muted", text: "none" }));
    facts.append(HMI.el("dt", { text: "Commands" }), HMI.el("dd", {}, commands));
    return HMI.el(
      "section",
      { "data-point-name": name },
      HMI.el("h4", { text: point && point.description ? point.description : name }),
      HMI.el("p", { class: "muted", text: name }),
      facts,
    );
  }

  function showFaceplate() {
    if (!faceplateState) return;
    const body = document.getElementById("faceplate-body");
    const focused = document.activeElement && body.contains(document.activeElement);
    body.replaceChildren(...faceplateState.names.map(faceplateSection));
    if (focused) document.getElementById("faceplate-close").focus();
  }

  function openFaceplate(element) {
    const names = pointNames(element);
    if (!names.length) return;
    faceplateState = { element, names };
    const point = HMI.points.get(names[0]);
    document.getElementById("faceplate-title").textContent = point && point.description ? point.description : names[0];
    showFaceplate();
    if (!faceplate().open) faceplate().show();
    faceplate().dataset.point = names[0];
    if (info) info.hidden = true;
  }

  function closeFaceplate() {
    faceplateState = null;
    if (faceplate() && faceplate().open) faceplate().close();
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
    panning(box);
    box.addEventListener("click", (event) => {
      if (panned) return; // the end of a drag, not a click
      const element = event.target.closest("[data-command]");
      if (element && box.contains(element)) {
        openControl(element);
        return;
      }
      const shown = event.target.closest(BOUND);
      if (shown && svgRoot && svgRoot.contains(shown)) openFaceplate(shown);
    });
    box.addEventListener("keydown", (event) => {
      if (event.key !== "Enter" && event.key !== " ") return;
      const element = event.target.closest("[data-command]");
      if (element && box.contains(element)) {
        event.preventDefault();
        openControl(element);
      }
    });
    document.getElementById("faceplate-close").addEventListener("click", closeFaceplate);
    document.addEventListener("keydown", (event) => {
      if (event.key === "Escape" && faceplateState && !dialog().open) closeFaceplate();
    });
    document.getElementById("control-next").addEventListener("click", toConfirm);
    document.getElementById("control-execute").addEventListener("click", execute);
    for (const button of document.querySelectorAll("#control-dialog [data-close]")) button.addEventListener("click", close);
    dialog().addEventListener("close", () => {
      dialogState = null;
    });
    document.getElementById("control-form").addEventListener("submit", (event) => event.preventDefault());
  });

  HMI.mimic = { refreshAll, openControl, openFaceplate, closeFaceplate };
})();
