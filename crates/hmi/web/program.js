// Stanice web HMI — a student's program (hmi.toml `[program]`, docs/HMI.md): the files
// chosen (or the text typed) go to POST /api/program/check, whose diagnostics are shown
// `file:line:col` as the compiler wrote them, or to POST /api/program/run, whose report
// (where every ball went, every refusal and lock-out of the supervisor) is shown as text.
// Where the lab itself runs here (session `program_live`), "Load into the lab" sends the
// program to POST /api/program/load (the lab's node runs it behind the supervisor) and
// "Restore the lab's program" to POST /api/program/restore; both need the operator lease.
"use strict";

(function () {
  const $ = (id) => document.getElementById(id);

  /** The files to send: the chosen files, else the typed text. */
  async function files() {
    const chosen = [...$("program-form").files.files];
    if (chosen.length) {
      return Promise.all(chosen.map(async (file) => ({ name: file.name, text: await file.text() })));
    }
    const text = $("program-text").value;
    return text.trim() ? [{ name: $("program-name").value.trim() || "program.st", text }] : [];
  }

  function show(verdict, words, diagnostics, report) {
    $("program-verdict").dataset.verdict = verdict;
    $("program-verdict").textContent = words;
    $("program-diagnostics").textContent = (diagnostics || []).join("\n\n");
    $("program-report").textContent = report || "";
  }

  async function send(path) {
    const list = await files();
    if (!list.length) {
      show("none", "Choose a file or type a program first.", [], "");
      return;
    }
    const seed = Number($("program-form").seed.value) || 0;
    show("pending", path.endsWith("run") ? "Running the trial…" : "Checking…", [], "");
    const result = await HMI.post(path, { files: list, seed });
    if (!result.ok) {
      show("error", result.body.error || `HTTP ${result.status}`, [], "");
      return;
    }
    const check = path.endsWith("run") ? result.body.check : result.body;
    if (!check.ok) {
      show("refused", "The program does not compile:", check.diagnostics, "");
      return;
    }
    if (!path.endsWith("run")) {
      show("compiles", `It compiles (PROGRAM ${check.main}).`, check.diagnostics, "");
      return;
    }
    const report = result.body.report;
    show(
      report.passed ? "passed" : "failed",
      report.passed ? "Passed: every ball in its colour's shaft, the supervisor never stepped in." : "Not yet: see the report.",
      check.diagnostics,
      report.text,
    );
  }

  /** The lab itself: load the program into it, or put its own back. */
  async function live(path) {
    const restoring = path.endsWith("restore");
    const list = restoring ? [] : await files();
    if (!restoring && !list.length) {
      show("none", "Choose a file or type a program first.", [], "");
      return;
    }
    if (restoring && !window.confirm("Stop the program on the lab and run the lab's own again?")) return;
    show("pending", restoring ? "Restoring the lab's program…" : "Loading into the lab…", [], "");
    const result = await HMI.post(path, restoring ? {} : { files: list });
    if (!result.ok) {
      show("error", result.body.detail || result.body.error || `HTTP ${result.status}`, [], "");
      return;
    }
    if (restoring) {
      show("loaded", result.body.text, [], "");
      return;
    }
    if (!result.body.check.ok) {
      show("refused", "The program does not compile:", result.body.check.diagnostics, "");
      return;
    }
    if (!result.body.loaded) {
      show("refused", `Not loaded: ${result.body.error}`, result.body.check.diagnostics, "");
      return;
    }
    show("loaded", result.body.loaded.text, result.body.check.diagnostics, "");
  }

  HMI.on("ready", () => {
    if (!HMI.session.program) return;
    $("nav-program").hidden = false;
    $("program-check").addEventListener("click", () => send("/api/program/check"));
    $("program-run").addEventListener("click", () => send("/api/program/run"));
    if (HMI.session.program_live) {
      $("program-load").hidden = false;
      $("program-restore").hidden = false;
      $("program-load").addEventListener("click", () => live("/api/program/load"));
      $("program-restore").addEventListener("click", () => live("/api/program/restore"));
    }
  });

  HMI.pages.program = { show() {}, hide() {} };
})();
