// Stanice web HMI — user administration (level 9): the users of users.toml with their
// level, lock and start screen (GET /api/users; never a hash), and forms to add a user,
// change a level, reset a password, lock or unlock and remove (POST /api/users,
// /api/users/{name}/level, /password, /lock; DELETE /api/users/{name}). The server keeps at
// least one unlocked level-9 user and audits every change; its refusal is shown as given.
"use strict";

(function () {
  const ADMIN_LEVEL = 9;
  let shown = false;

  function message(text, bad) {
    const element = document.getElementById("users-message");
    element.textContent = text;
    element.classList.toggle("error", Boolean(bad));
    document.getElementById("page-users").dataset.message = text;
  }

  async function change(request, done) {
    const response = await HMI.request(request.path, { method: request.method || "POST", body: request.body === undefined ? {} : request.body });
    let body = {};
    try {
      body = await response.json();
    } catch (error) {
      /* empty body */
    }
    if (!response.ok) {
      message(`Refused: ${body.error || `HTTP ${response.status}`}`, true);
      return;
    }
    message(done, false);
    render(body);
  }

  function userRow(user) {
    const name = encodeURIComponent(user.name);
    const level = HMI.el("select", { "aria-label": `Level of ${user.name}`, class: "user-level" });
    for (let l = 0; l <= ADMIN_LEVEL; l += 1) level.append(HMI.el("option", { value: String(l), selected: l === user.level, text: String(l) }));
    level.addEventListener("change", () =>
      change({ path: `/api/users/${name}/level`, body: { level: Number(level.value) } }, `${user.name} is now level ${level.value}.`),
    );
    const password = HMI.el("input", { type: "password", class: "user-password", autocomplete: "new-password", minlength: "8", placeholder: "new password", "aria-label": `New password of ${user.name}` });
    const reset = HMI.el("button", { type: "button", class: "secondary user-reset", text: "Reset password" });
    reset.addEventListener("click", () => {
      const value = password.value;
      password.value = "";
      change({ path: `/api/users/${name}/password`, body: { password: value } }, `The password of ${user.name} was reset.`);
    });
    const lock = HMI.el("button", { type: "button", class: "secondary user-lock", text: user.locked ? "Unlock" : "Lock" });
    lock.addEventListener("click", () =>
      change({ path: `/api/users/${name}/lock`, body: { locked: !user.locked } }, `${user.name} is ${user.locked ? "unlocked" : "locked"}.`),
    );
    const remove = HMI.el("button", { type: "button", class: "secondary user-remove", text: "Remove" });
    remove.addEventListener("click", () => {
      if (!window.confirm(`Remove user ${user.name}?`)) return;
      change({ path: `/api/users/${name}`, method: "DELETE" }, `${user.name} was removed.`);
    });
    return HMI.el(
      "tr",
      { "data-user": user.name, "data-locked": String(user.locked) },
      HMI.el("td", { class: "user-name", text: user.name }),
      HMI.el("td", {}, level),
      HMI.el("td", { class: "user-state", text: user.locked ? "locked" : "active" }),
      HMI.el("td", { text: user.start || "—" }),
      HMI.el("td", { class: "user-actions" }, password, reset, lock, remove),
    );
  }

  function render(users) {
    const body = document.querySelector("#users-table tbody");
    body.replaceChildren(...users.map(userRow));
    document.getElementById("page-users").dataset.loaded = String(Date.now());
  }

  async function load() {
    try {
      render(await HMI.api("/api/users"));
    } catch (error) {
      message(`Cannot load the users: ${error.message}`, true);
    }
  }

  HMI.on("ready", () => {
    document.getElementById("nav-users").hidden = !(HMI.session && HMI.session.level >= ADMIN_LEVEL);
    const form = document.getElementById("user-add");
    form.addEventListener("submit", (event) => {
      event.preventDefault();
      const body = { name: form.name.value.trim(), level: Number(form.level.value), password: form.password.value };
      form.password.value = "";
      change({ path: "/api/users", body }, `${body.name} was added at level ${body.level}.`).then(() => {
        if (!document.getElementById("users-message").classList.contains("error")) form.name.value = "";
      });
    });
  });

  HMI.pages.users = {
    show() {
      shown = true;
      message("", false);
      load();
    },
    hide() {
      shown = false;
    },
  };
  HMI.users = { reload: () => shown && load() };
})();
