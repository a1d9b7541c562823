// Stanice web HMI — the operator lease of a remote lab (hmi.toml `[lease]`, docs/HMI.md):
// the bar in the header says who controls the lab and offers Take control, Release and
// (to administrators) Revoke; the Booking page books slots on the lab's grid and lists
// the bookings. The state comes from GET /api/lease, polled every second (a lease that
// runs out, by its slot or idle time, is over at the server's next answer); the camera
// panel beside the mimic shows the hmi.toml `camera` picture.
"use strict";

(function () {
  let view = null; // the last GET /api/lease
  let timer = null;

  const $ = (id) => document.getElementById(id);

  function time(text) {
    if (!text) return "";
    const date = new Date(text);
    // With its zone: a booking's time is read by people in other places.
    return date.toLocaleString(undefined, {
      year: "numeric",
      month: "2-digit",
      day: "2-digit",
      hour: "2-digit",
      minute: "2-digit",
      timeZoneName: "short",
    });
  }

  function render() {
    if (!view) return;
    const lease = view.lease;
    let words;
    if (!lease) words = "control: free";
    else if (view.yours) words = `control: you, until ${time(lease.ends && lease.ends < lease.idle_until ? lease.ends : lease.idle_until)}`;
    else words = `control: ${lease.holder} — you observe`;
    if (!lease && view.current_booking && !view.can_take) words = `booked by ${view.current_booking.user} — you observe`;
    $("lease-text").textContent = words;
    $("lease-take").hidden = !view.can_take || view.yours;
    $("lease-release").hidden = !view.yours;
    $("lease-revoke").hidden = !view.can_revoke || view.yours;
    document.body.dataset.lease = view.yours ? "yours" : lease ? "other" : "free";
    $("lease-state").textContent = words;
    renderBookings();
  }

  function renderBookings() {
    const body = $("booking-table").querySelector("tbody");
    const rows = view.bookings.map((booking) => {
      const mine = booking.user === HMI.session.user;
      const admin = view.can_revoke !== undefined && HMI.session.level >= 9;
      const cancel =
        mine || admin
          ? HMI.el("button", {
              type: "button",
              class: "secondary cancel",
              text: "Cancel",
              onclick: () => act(`/api/bookings/${booking.id}/cancel`),
            })
          : "";
      return HMI.el(
        "tr",
        { "data-booking": booking.id, class: mine ? "mine" : "" },
        HMI.el("td", { text: time(booking.start) }),
        HMI.el("td", { text: time(booking.end) }),
        HMI.el("td", { text: booking.user }),
        HMI.el("td", {}, cancel),
      );
    });
    body.replaceChildren(...rows);
  }

  async function refresh() {
    try {
      view = await HMI.api("/api/lease");
      render();
    } catch (error) {
      /* the next poll tries again */
    }
  }

  async function act(path, body) {
    const result = await HMI.post(path, body);
    if (!result.ok) HMI.toast(result.body.error || `HTTP ${result.status}`, true);
    else view = result.body;
    render();
    return result;
  }

  function fillForm() {
    const form = $("booking-form");
    const slot = view ? view.slot_minutes : 30;
    const slots = view ? view.max_slots : 4;
    const options = [];
    for (let minute = 0; minute < 24 * 60; minute += slot) {
      const label = `${String(Math.floor(minute / 60)).padStart(2, "0")}:${String(minute % 60).padStart(2, "0")}`;
      options.push(HMI.el("option", { value: String(minute), text: label }));
    }
    form.slot.replaceChildren(...options);
    form.slots.replaceChildren(
      ...Array.from({ length: slots }, (_, i) => HMI.el("option", { value: String(i + 1), text: `${i + 1} × ${slot} min` })),
    );
    if (!form.day.value) form.day.value = new Date().toISOString().slice(0, 10);
  }

  HMI.on("ready", async () => {
    if (HMI.session.camera) {
      $("camera").src = HMI.session.camera;
      $("camera-panel").hidden = false;
    }
    if (!HMI.session.lease) return;
    $("lease-bar").hidden = false;
    $("nav-lease").hidden = false;
    $("lease-take").addEventListener("click", () => act("/api/lease"));
    $("lease-release").addEventListener("click", () => act("/api/lease/release"));
    $("lease-revoke").addEventListener("click", () => act("/api/lease/revoke"));
    $("booking-form").addEventListener("submit", (event) => {
      event.preventDefault();
      const form = event.target;
      const slot = view ? view.slot_minutes : 30;
      // The grid is UTC's (slots from midnight UTC).
      const start = new Date(`${form.day.value}T00:00:00Z`);
      start.setUTCMinutes(Number(form.slot.value));
      const end = new Date(start.getTime() + Number(form.slots.value) * slot * 60000);
      act("/api/bookings", { start: start.toISOString(), end: end.toISOString() });
    });
    await refresh();
    fillForm();
    timer = setInterval(refresh, 1000);
  });

  HMI.pages.lease = {
    show() {
      if (view) fillForm();
      refresh();
    },
    hide() {},
  };
  window.addEventListener("beforeunload", () => clearInterval(timer));
})();
