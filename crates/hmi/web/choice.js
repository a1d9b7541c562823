// Stanice web HMI — set-points chosen together (hmi.toml `[[choice]]`, docs/HMI.md): a
// mimic element with data-choice="ID" opens a dialog of one select per field, filled with
// the values now; the combination's rule is checked as the user picks ("Allowed colour
// combination." / "Forbidden colour combination!") and O.K. is offered only for an
// allowed one; the server checks it again and sends the set-points.
"use strict";

(function () {
  const $ = (id) => document.getElementById(id);
  let choices = new Map(); // id -> {choice, now}
  let open = null; // the choice being edited

  function values() {
    return [...$("choice-fields").querySelectorAll("select")].map((select) => Number(select.value));
  }

  function allowed(choice, picked) {
    const known = picked.every((v) => choice.options.some((o) => o.value === v));
    const distinct = !choice.distinct || new Set(picked).size === picked.length;
    return picked.length === choice.commands.length && known && distinct;
  }

  function judge() {
    const ok = allowed(open, values());
    $("choice-message").textContent = ok ? open.allowed : open.forbidden;
    $("choice-message").dataset.allowed = String(ok);
    $("choice-ok").disabled = !ok;
  }

  async function show(id) {
    try {
      const list = await HMI.api("/api/choices");
      choices = new Map(list.map((entry) => [entry.choice.id, entry]));
    } catch (error) {
      HMI.toast(`Cannot load the choices: ${error.message}`, true);
      return;
    }
    const entry = choices.get(id);
    if (!entry) return;
    open = entry.choice;
    $("choice-title").textContent = open.title;
    $("choice-outcome").textContent = "";
    $("choice-outcome").dataset.outcome = "";
    const fields = open.commands.map((command, index) => {
      const control = HMI.controls.get(command) || {};
      const label = open.labels[index] || control.description || command;
      const select = HMI.el(
        "select",
        { name: command, "data-field": String(index), onchange: judge },
        ...open.options.map((option) => HMI.el("option", { value: String(option.value), text: option.text })),
      );
      const now = entry.now[index];
      if (now !== null && now !== undefined) select.value = String(now);
      return HMI.el("label", {}, `${label} `, select);
    });
    $("choice-fields").replaceChildren(...fields);
    judge();
    $("choice-dialog").showModal();
  }

  async function confirm() {
    if (!open) return;
    const result = await HMI.post(`/api/choices/${encodeURIComponent(open.id)}`, { values: values() });
    const outcome = result.ok ? result.body.outcome : "refused";
    $("choice-outcome").dataset.outcome = outcome;
    $("choice-outcome").textContent = result.ok
      ? `${HMI.outcomeWords ? HMI.outcomeWords(outcome) : outcome}${result.body.detail ? `: ${result.body.detail}` : ""}`
      : result.body.error || result.body.detail || `HTTP ${result.status}`;
    if (result.ok && outcome === "executed") $("choice-dialog").close();
  }

  HMI.on("ready", () => {
    const box = $("mimic");
    box.addEventListener("click", (event) => {
      const element = event.target.closest("[data-choice]");
      if (element && box.contains(element)) show(element.getAttribute("data-choice"));
    });
    $("choice-ok").addEventListener("click", confirm);
    $("choice-cancel").addEventListener("click", () => $("choice-dialog").close());
    $("choice-form").addEventListener("submit", (event) => event.preventDefault());
  });

  HMI.choice = { show };
})();
