// Stanice web HMI — the login page: posts the form as JSON to /api/login and goes to the
// application on success; says what went wrong otherwise (wrong name or password, or too
// many failures with the time to wait, counted down).
"use strict";

(function () {
  const form = document.getElementById("login-form");
  const button = document.getElementById("login-button");
  const message = document.getElementById("login-message");
  let countdown = null;

  function say(text, isError) {
    message.textContent = text;
    message.classList.toggle("error", Boolean(isError));
  }

  function lockFor(seconds) {
    clearInterval(countdown);
    let left = Math.max(1, Math.ceil(seconds));
    button.disabled = true;
    const tick = () => {
      if (left <= 0) {
        clearInterval(countdown);
        button.disabled = false;
        say("You may try again now.", false);
        return;
      }
      say(`Too many failed logins. Try again in ${left} s.`, true);
      left -= 1;
    };
    tick();
    countdown = setInterval(tick, 1000);
  }

  form.addEventListener("submit", async (event) => {
    event.preventDefault();
    const username = form.username.value.trim();
    const password = form.password.value;
    if (!username || !password) {
      say("Enter your user name and password.", true);
      return;
    }
    button.disabled = true;
    say("Logging in…", false);
    let response;
    try {
      response = await fetch("/api/login", {
        method: "POST",
        headers: { "Content-Type": "application/json" },
        credentials: "same-origin",
        body: JSON.stringify({ username, password }),
      });
    } catch (error) {
      button.disabled = false;
      say("The HMI server does not answer. Check the network and try again.", true);
      return;
    }
    let body = {};
    try { body = await response.json(); } catch (error) { /* not JSON */ }
    if (response.ok) {
      say(`Welcome, ${body.user || username}.`, false);
      window.location.replace("/");
      return;
    }
    form.password.value = "";
    if (response.status === 429) {
      lockFor(Number(body.retry_after_s) || 30);
      return;
    }
    button.disabled = false;
    if (response.status === 401) {
      say("Wrong user name or password.", true);
      form.password.focus();
    } else {
      say(body.error ? `Login failed: ${body.error}` : `Login failed (HTTP ${response.status}).`, true);
    }
  });
})();

// The public information pages, when the screens folder has them.
document.addEventListener("DOMContentLoaded", () => {
  fetch("/public/", { method: "HEAD", credentials: "same-origin" })
    .then((response) => {
      if (response.ok) document.getElementById("public").hidden = false;
    })
    .catch(() => {});
});
