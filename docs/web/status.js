// What the page says about the run: the status line, the mark on stale results, the validity
// monitors, the messages (and the alerts at the top) and the summary table.
// A classic script of the page (no modules: a page opened from the disk cannot load them); it
// shares the page's globals, and index.html loads it before page.js, which defines the shared
// state (`page`, `$`, the constants) and starts the page.
"use strict";

const SHOWN_MESSAGES = 200; // the messages listed under the plate (the latest)

// status(text, kind): kind "" (running), "ok", "warning" or "error".
function status(text, kind) {
  const s = $("status");
  s.textContent = text;
  s.className = kind || "";
}

// Marks the results on screen as not the controls' (or unmarks them, when `run` is null).
function markStale(run) {
  const stale = $("stale");
  $("results").classList.toggle("stale", !!run);
  stale.hidden = !run;
  if (run) {
    const t = run.samples.t.last();
    stale.textContent = `Stale: these results are run ${run.id}'s (preset ${run.request.preset}` +
      `${run.halted ? `, stopped at t = ${t.toFixed(3)} s` : ""}), not the settings in the controls, ` +
      "which were not run (see the message above).";
  }
}

function drawMonitors(run) {
  if (!run.monitors) return;
  const box = $("monitors");
  const names = {
    "plate.w_tip_ratio": "tip deflection / length",
    "plate.stress": "plate bending stress",
    "torsion_bar.stress": "torsion bar shear stress",
    "hub.omega_ratio": "hub speed / first bending frequency",
  };
  box.innerHTML = "<h2>Validity monitors (peak of the run / limit)</h2>" + run.monitors.map((m) => {
    const ratio = run.peak[m.variable] / m.limit;
    const tripped = ratio > 1;
    return `<div class="monitor${tripped ? " tripped" : ""}" data-variable="${m.variable}">
      <span>${names[m.variable] || m.variable}</span>
      <span class="bar"><span style="width:${Math.min(100, 100 * ratio).toFixed(1)}%"></span></span>
      <span class="ratio">${ratio.toFixed(3)}</span></div>`;
  }).join("");
}

// The messages: all of them (the latest SHOWN_MESSAGES) under the plate; the warnings and errors
// also at the top of the page, beside the status, where they are seen without scrolling.
function drawMessages(run) {
  const item = (m) => `<li class="${m.status}">${escapeHtml(m.message)}</li>`;
  const all = run.messages.slice(-SHOWN_MESSAGES).map(item);
  if (run.messages.length > SHOWN_MESSAGES) {
    all.unshift(`<li>(${run.messages.length - SHOWN_MESSAGES} earlier messages not listed)</li>`);
  }
  if (run.failed) all.push(`<li class="error">${escapeHtml(run.failed)}</li>`);
  $("messages").innerHTML = all.join("");
  const alerts = run.messages.filter((m) => ALERTS.includes(m.status));
  const box = $("alerts");
  box.hidden = alerts.length === 0;
  const more = alerts.length > 3 ? `<li>… ${alerts.length - 3} more, all listed under the plate</li>` : "";
  box.innerHTML = alerts.slice(0, 3).map(item).join("") + more;
}

function drawSummary(run) {
  const s = run.samples;
  const last = (name) => s[name].last();
  const peak = (name) => run.peak[name];
  const rows = [
    ["time", "t", `${last("t").toFixed(3)} s`, last("t")],
    ["motor angle", "theta_motor", `${(last("theta_motor") * DEG).toFixed(4)} deg`, last("theta_motor")],
    ["hub angle", "theta_hub", `${(last("theta_hub") * DEG).toFixed(4)} deg`, last("theta_hub")],
    ["potentiometer", "y_pot", `${last("y_pot").toFixed(6)} V`, last("y_pot")],
    ["tip deflection", "w_tip", `${(last("w_tip") * 1e3).toFixed(4)} mm`, last("w_tip")],
    ["peak |w_tip|", "peak_w_tip", `${(peak("w_tip") * 1e3).toFixed(4)} mm`, peak("w_tip")],
    ["peak |p_load|", "peak_p_load", `${(peak("p_load") * 1e-5).toFixed(4)} bar`, peak("p_load")],
    ["peak |e_out|", "peak_e_out", `${peak("controller.e_out").toFixed(4)} V`, peak("controller.e_out")],
  ];
  $("summary").tBodies[0].innerHTML = rows.map(([label, key, text, value]) =>
    `<tr data-key="${key}" data-value="${value}"><th>${label}</th><td>${text}</td></tr>`).join("");
}

function showStatus(run) {
  const simulated = run.samples.t.last();
  const warned = run.alerts > 0
    ? ` ${run.alerts} validity warning${run.alerts > 1 ? "s" : ""}: see below.` : "";
  const kind = run.alerts > 0 ? "warning" : "ok";
  if (run.failed) {
    status(`Stopped at t = ${simulated.toFixed(3)} s: ${run.failed}`, "error");
  } else if (run.shown) {
    const factor = (ms) => (ms > 0 ? `${(simulated / (ms / 1000)).toFixed(0)}×` : "–");
    status(`${simulated.toFixed(1)} s simulated in ${(run.wallMs / 1000).toFixed(2)} s of wall time ` +
      `(${run.speed === "fast" ? "as fast as possible" : "real time"}): ${factor(run.wallMs)} real time ` +
      `with drawing, the model alone ${factor(run.stepMs)} real time.${warned}`, kind);
  } else if (run.pausedAt) {
    status(`Paused at t = ${simulated.toFixed(2)} s of ${run.stop} s.${warned}`, run.alerts > 0 ? "warning" : "");
  } else {
    status(`Running: t = ${simulated.toFixed(2)} s of ${run.stop} s.${warned}`, run.alerts > 0 ? "warning" : "");
  }
}
