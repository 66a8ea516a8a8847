// The interactive page: builds a simulation from the controls, steps it in slices on the main
// thread (a slice per animation frame, so the page stays responsive), and draws the results.
// What it shows and measures is kept in `window.hspPage` (read by tests/python/test_web.py).
"use strict";

const STEP = 1e-3; // communication step [s]
const DEG = 180 / Math.PI;
const GRID = [21, 7]; // the plate's deflection grid, along and across
const SLICE_MS = 12; // stepping per slice when running as fast as possible
const CHUNK = 200; // communication steps per call into the module
const DRAW_MS = 250; // running as fast as possible, the plots are redrawn at most this often

// The outputs recorded at every communication point [SI], and how they are shown.
const RECORDED = [
  "controller.reference", "y_pot", "theta_motor", "theta_hub", "w_tip", "p_load",
  "servo_valve.p_1", "servo_valve.p_2", "controller.e_out",
  "plate.w_tip_ratio", "plate.stress", "torsion_bar.stress", "hub.omega_ratio",
];

const $ = (id) => document.getElementById(id);

const page = {
  model: null,
  sim: null,
  run: null, // the run in progress: {samples, ...}
  timing: { start: performance.now() },
  runs: 0,
  error: null,
  dirty: false,
  drawn: 0, // when the plots were last drawn
};
window.hspPage = page;

function status(text, isError) {
  const s = $("status");
  s.textContent = text;
  s.classList.toggle("error", !!isError);
}

// ---------------------------------------------------------------- controls

const CONTROLS = ["preset", "angle", "t_start", "duration", "A1", "A2", "bar_k", "zeta", "D_m", "stop"];

function radio(name) {
  return document.querySelector(`input[name="${name}"]:checked`).value;
}

function setRadio(name, value) {
  const input = document.querySelector(`input[name="${name}"][value="${value}"]`);
  if (input) input.checked = true;
}

// The value of a variable under the chosen preset: the preset's setting, else the start value.
function presetValue(name) {
  const preset = page.model.presets.find((p) => p.name === $("preset").value);
  if (preset && name in preset.settings) return preset.settings[name];
  return page.model.variable(name).start;
}

// The variable that sizes the motor: the full servo valve's or the LOES's.
function motorVariable() {
  const hydraulics = presetValue("hydraulics.model");
  return hydraulics === 1 || hydraulics === "Loes" ? "loes.D_m" : "servo_valve.D_m";
}

// Fills the plant and command controls from the preset.
function loadPreset() {
  const preset = page.model.presets.find((p) => p.name === $("preset").value);
  $("preset-description").textContent = preset ? `${preset.description} (paper: ${preset.paper})` : "";
  const angle = presetValue("reference.angle");
  $("angle").value = +(angle * DEG).toFixed(6) || 30;
  setRadio("command", angle === 0 ? "step" : "move");
  $("t_start").value = presetValue("reference.t_start");
  $("duration").value = presetValue("reference.duration");
  $("A1").value = presetValue("controller.A1");
  $("A2").value = presetValue("controller.A2");
  $("bar_k").value = presetValue("torsion_bar.k");
  $("zeta").value = presetValue("plate.zeta");
  $("D_m").value = +(presetValue(motorVariable()) * 1e6).toPrecision(6);
}

// The settings the controls ask for, over the preset.
function settings() {
  const number = (id) => {
    const v = Number($(id).value);
    if (!Number.isFinite(v)) throw new Error(`${$(id).name}: '${$(id).value}' is not a number`);
    return v;
  };
  const command = radio("command");
  const s = {
    "reference.angle": command === "move" ? number("angle") / DEG : 0,
    "reference.t_start": number("t_start"),
    "reference.duration": number("duration"),
    "controller.A1": number("A1"),
    "controller.A2": number("A2"),
    "torsion_bar.k": number("bar_k"),
    "plate.zeta": number("zeta"),
  };
  s[motorVariable()] = number("D_m") * 1e-6;
  return s;
}

// The controls as URL parameters and back, so that a configuration can be linked to.
function fromQuery() {
  const q = new URLSearchParams(location.search);
  if (q.has("preset")) $("preset").value = q.get("preset");
  loadPreset();
  for (const id of CONTROLS) if (id !== "preset" && q.has(id)) $(id).value = q.get(id);
  if (q.has("command")) setRadio("command", q.get("command"));
  if (q.has("speed")) setRadio("speed", q.get("speed"));
}

// ---------------------------------------------------------------- the run

function newRun() {
  const stop = Number($("stop").value);
  if (!(stop > 0)) throw new Error(`stop time: '${$("stop").value}' is not a positive number`);
  if (page.sim) page.sim.free();
  page.sim = null;
  const request = { preset: $("preset").value, settings: settings() };
  const sim = page.model.create(request);
  page.sim = sim;
  const command = radio("command");
  const [kPot] = sim.get(["controller.k_pot"]);
  const run = {
    id: ++page.runs,
    request,
    stop,
    steps: Math.round(stop / STEP),
    command,
    // A step of r: the potentiometer voltage of the angle, from t_start.
    kPot, // the potentiometer's gain [V/rad]
    rStep: command === "step" ? kPot * Number($("angle").value) / DEG : 0,
    tStart: Number($("t_start").value),
    samples: { t: [] },
    inputs: [], // r of each step, as set before it
    messages: [],
    monitors: sim.monitors(),
    plate: sim.plateSize(),
    speed: radio("speed"),
    started: performance.now(),
    paused: 0,
    stepMs: 0, // wall time spent stepping
    done: false,
    failed: null,
    exaggeration: 0,
  };
  run.peak = {}; // the largest magnitude of each recorded output so far
  for (const name of RECORDED) {
    run.samples[name] = [];
    run.peak[name] = 0;
  }
  page.run = run;
  record(run);
  return run;
}

// The point the simulation is at (its initial point, when a run starts).
function record(run) {
  const v = page.sim.get(RECORDED);
  run.time = page.sim.time;
  run.samples.t.push(run.time);
  RECORDED.forEach((name, k) => {
    run.samples[name].push(v[k]);
    run.peak[name] = Math.max(run.peak[name], Math.abs(v[k]));
  });
}

// The input r of the coming step.
function reference(run, t) {
  if (run.command === "slider") return Number($("r").value);
  if (run.command === "step") return t >= run.tStart - 1e-12 ? run.rStep : 0;
  return 0;
}

// Steps until the run's time reaches `until` or `budgetMs` of wall time is spent, CHUNK steps
// per call into the module (r for each step computed before, the outputs of each read after).
function advance(run, until, budgetMs) {
  const t0 = performance.now();
  if (!run.stepping) {
    // The run's wall clock starts with its first step (making the model and drawing the empty
    // plots come before).
    run.stepping = true;
    run.started = t0;
  }
  const width = RECORDED.length;
  let k = run.samples.t.length - 1;
  while (k < run.steps && k * STEP < until - 1e-12) {
    const wanted = Math.ceil((until - k * STEP) / STEP - 1e-9);
    const n = Math.max(1, Math.min(CHUNK, run.steps - k, wanted));
    const inputs = new Float64Array(n);
    const times = new Float64Array(n);
    let t = run.time;
    for (let i = 0; i < n; i++) {
      inputs[i] = reference(run, t);
      t += STEP; // the FMU's own time after the step (the same sum)
      times[i] = t;
    }
    const done = page.sim.run(STEP, "r", inputs, RECORDED);
    for (let i = 0; i < done.steps; i++) {
      run.inputs.push(inputs[i]);
      run.samples.t.push(times[i]);
      for (let j = 0; j < width; j++) {
        const v = done.values[i * width + j];
        run.samples[RECORDED[j]].push(v);
        const a = Math.abs(v);
        if (a > run.peak[RECORDED[j]]) run.peak[RECORDED[j]] = a;
      }
    }
    if (done.steps > 0) run.time = times[done.steps - 1];
    k += done.steps;
    if (done.warned || done.error) collectMessages(run);
    if (done.error) {
      run.failed = done.error;
      break;
    }
    if (performance.now() - t0 > budgetMs) break;
  }
  run.stepMs += performance.now() - t0;
  if (k >= run.steps || run.failed) finish(run);
}

function collectMessages(run) {
  for (const m of page.sim.messages()) run.messages.push(m);
}

function finish(run) {
  if (run.done) return;
  run.done = true;
  collectMessages(run);
  run.wallMs = performance.now() - run.started - run.paused;
}

// Running as fast as possible, the model steps in slices of SLICE_MS, each a task of its own
// (posted through a MessageChannel, which does not wait for the next frame as a timer would), so
// that input and drawing get their turn between slices; at real time it steps in the animation
// frame, up to the wall-clock time since the run started.
const pumpChannel = new MessageChannel();
let pumpPosted = false;
pumpChannel.port1.onmessage = () => {
  pumpPosted = false;
  const run = page.run;
  if (!run || run.pausedAt || run.done || run.speed !== "fast") return;
  advance(run, run.stop, SLICE_MS);
  page.dirty = true;
  if (run.done || performance.now() - page.drawn > DRAW_MS) requestFrame();
  if (!run.done) pump();
};
function pump() {
  if (!pumpPosted) {
    pumpPosted = true;
    pumpChannel.port2.postMessage(0);
  }
}

let frameRequested = false;
function frame() {
  frameRequested = false;
  const run = page.run;
  if (!run) return;
  if (!run.pausedAt && !run.done && run.speed !== "fast") {
    if (!run.stepping) {
      run.stepping = true;
      run.started = performance.now();
    }
    const wall = (performance.now() - run.started - run.paused) / 1000;
    advance(run, Math.min(wall, run.stop), 30);
    page.dirty = true;
  }
  if (page.dirty) {
    page.dirty = false;
    draw(run);
    page.drawn = performance.now();
  }
  if (!run.done && !run.pausedAt && run.speed !== "fast") requestFrame();
}

function requestFrame() {
  if (!frameRequested) {
    frameRequested = true;
    requestAnimationFrame(frame);
  }
}

// Goes on with the run at its speed.
function go() {
  const run = page.run;
  if (!run || run.done || run.pausedAt) return;
  if (run.speed === "fast") pump();
  requestFrame();
}

function start() {
  try {
    page.error = null;
    newRun();
    status("Running…");
    draw(page.run);
    go();
  } catch (e) {
    page.error = e.message;
    page.run = null;
    status(e.message, true);
  }
}

// ---------------------------------------------------------------- drawing

const COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e"];

// A line plot of `series` ([{label, x, y}]) over [0, xmax] on `canvas`.
function plot(canvas, series, xmax) {
  const ctx = canvas.getContext("2d");
  const W = canvas.width, H = canvas.height;
  const L = 52, R = 8, T = 8, B = 22;
  ctx.clearRect(0, 0, W, H);
  let lo = Infinity, hi = -Infinity;
  for (const s of series) for (const v of s.y) if (Number.isFinite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
  if (!(hi > lo)) { const c = Number.isFinite(lo) ? lo : 0; lo = c - 1; hi = c + 1; }
  const pad = 0.06 * (hi - lo); lo -= pad; hi += pad;
  const px = (x) => L + (W - L - R) * x / xmax;
  const py = (y) => T + (H - T - B) * (hi - y) / (hi - lo);
  ctx.font = "11px sans-serif";
  ctx.strokeStyle = "#ccc"; ctx.fillStyle = "#444"; ctx.lineWidth = 1;
  for (const y of ticks(lo, hi, 5)) {
    ctx.beginPath(); ctx.moveTo(L, py(y)); ctx.lineTo(W - R, py(y)); ctx.stroke();
    ctx.textAlign = "right"; ctx.fillText(format(y), L - 4, py(y) + 4);
  }
  for (const x of ticks(0, xmax, 6)) {
    ctx.textAlign = "center"; ctx.fillText(format(x), px(x), H - 6);
  }
  ctx.strokeStyle = "#888"; ctx.strokeRect(L, T, W - L - R, H - T - B);
  series.forEach((s, k) => {
    ctx.strokeStyle = s.colour || COLOURS[k % COLOURS.length];
    ctx.lineWidth = 1.5;
    ctx.setLineDash(s.dash || []);
    ctx.beginPath();
    // At most four vertices per pixel column (its first, lowest, highest and last value), so
    // that a long run draws as fast as a short one and keeps its extremes.
    let column = -1, first = 0, cmin = 0, cmax = 0, last = 0;
    const flush = () => {
      for (const v of first <= last ? [first, cmin, cmax, last] : [first, cmax, cmin, last]) {
        ctx.lineTo(column, py(v));
      }
    };
    const n = Math.min(s.x.length, s.y.length);
    for (let i = 0; i < n; i++) {
      const c = Math.round(px(s.x[i])), v = s.y[i];
      if (c !== column) {
        if (column >= 0) flush(); else ctx.moveTo(c, py(v));
        column = c; first = cmin = cmax = last = v;
      } else { cmin = Math.min(cmin, v); cmax = Math.max(cmax, v); last = v; }
    }
    if (column >= 0) flush();
    ctx.stroke();
    ctx.setLineDash([]);
    ctx.fillStyle = ctx.strokeStyle;
    ctx.textAlign = "left";
    ctx.fillText(s.label, L + 8 + 110 * k, T + 14);
  });
}

function ticks(lo, hi, n) {
  const span = (hi - lo) / n;
  const mag = Math.pow(10, Math.floor(Math.log10(span)));
  const step = [1, 2, 5, 10].map((f) => f * mag).find((s) => s >= span) || span;
  const out = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + 1e-9 * step; v += step) out.push(Math.abs(v) < 1e-12 * step ? 0 : v);
  return out;
}

function format(v) {
  const a = Math.abs(v);
  if (a === 0) return "0";
  if (a >= 1e4 || a < 1e-3) return v.toExponential(1);
  return String(+v.toPrecision(4));
}

function scaled(run, name, factor) {
  return run.samples[name].map((v) => v * factor);
}

function draw(run) {
  if (!run) return;
  const t = run.samples.t;
  const xmax = run.stop;
  plot($("plot-loop"), [
    { label: "reference", x: t, y: run.samples["controller.reference"], dash: [5, 3] },
    { label: "y_pot", x: t, y: run.samples.y_pot },
  ], xmax);
  plot($("plot-angles"), [
    { label: "motor", x: t, y: scaled(run, "theta_motor", DEG) },
    { label: "hub", x: t, y: scaled(run, "theta_hub", DEG) },
  ], xmax);
  plot($("plot-tip"), [{ label: "w_tip", x: t, y: scaled(run, "w_tip", 1e3) }], xmax);
  const fullValve = motorVariable() === "servo_valve.D_m";
  $("pressure-caption").textContent = fullValve
    ? "Motor chamber pressures p1, p2 and load pressure [bar]" : "Load pressure [bar]";
  const pressures = [{ label: "p_load", x: t, y: scaled(run, "p_load", 1e-5) }];
  if (fullValve) {
    pressures.unshift({ label: "p1", x: t, y: scaled(run, "servo_valve.p_1", 1e-5) },
      { label: "p2", x: t, y: scaled(run, "servo_valve.p_2", 1e-5) });
  }
  plot($("plot-pressures"), pressures, xmax);
  drawPlate(run);
  drawMonitors(run);
  drawMessages(run);
  drawSummary(run);
  showStatus(run);
  if (!page.timing.firstResult && t.length > 1) {
    page.timing.firstResult = performance.now();
  }
  // The finished run is on screen (tests wait for this, not only for the run's end).
  if (run.done) run.shown = true;
}

// The exaggeration of the drawn deflection: a 1-2-5 number that shows the largest deflection
// of the run so far at about a fifth of the plate's length; it only grows during a run.
function exaggeration(run, wmax) {
  const [a] = run.plate;
  if (wmax > 0) {
    const wanted = 0.2 * a / wmax;
    const mag = Math.pow(10, Math.floor(Math.log10(wanted)));
    const k = [1, 2, 5].map((f) => f * mag).reverse().find((x) => x <= wanted) || mag;
    if (!run.exaggeration || k < run.exaggeration) run.exaggeration = k;
  }
  return run.exaggeration || 1;
}

function drawPlate(run) {
  if (!run.plate) return;
  const [a, b] = run.plate;
  const [nx, ny] = GRID;
  let w;
  try {
    w = page.sim.deflection(nx, ny);
  } catch (e) {
    $("plate-caption").textContent = e.message;
    return;
  }
  const wmaxRun = Math.max(1e-9, run.peak.w_tip);
  const k = exaggeration(run, wmaxRun);
  const theta = run.samples.theta_hub[run.samples.theta_hub.length - 1];
  const ref = run.samples["controller.reference"];
  const thetaRef = ref[ref.length - 1] / run.kPot;

  // Top view: the hub at the centre, the arm at the hub angle, bent in the plane of the slew by
  // the deflection of its centre line (exaggerated).
  const top = $("plate-top"), ctx = top.getContext("2d");
  const W = top.width, H = top.height;
  ctx.clearRect(0, 0, W, H);
  const scale = 0.8 * Math.min(W / 2, H) / a;
  const cx = W / 2, cy = H - 20;
  const toCanvas = (x, y) => [cx + scale * y, cy - scale * x]; // x up the page at angle 0
  const rotate = (x, y, phi) => [x * Math.cos(phi) - y * Math.sin(phi), x * Math.sin(phi) + y * Math.cos(phi)];
  const j = Math.floor(ny / 2);
  // The reference direction.
  ctx.strokeStyle = "#999"; ctx.setLineDash([6, 4]); ctx.beginPath();
  ctx.moveTo(...toCanvas(0, 0)); ctx.lineTo(...toCanvas(...rotate(a * 1.05, 0, -thetaRef))); ctx.stroke();
  ctx.setLineDash([]);
  // The undeformed arm (thin) and the deformed one (thick).
  ctx.strokeStyle = "#bbb"; ctx.lineWidth = 1; ctx.beginPath();
  ctx.moveTo(...toCanvas(0, 0)); ctx.lineTo(...toCanvas(...rotate(a, 0, -theta))); ctx.stroke();
  ctx.strokeStyle = COLOURS[0]; ctx.lineWidth = 4; ctx.beginPath();
  for (let i = 0; i < nx; i++) {
    const x = a * i / (nx - 1);
    const p = toCanvas(...rotate(x, -k * w[i + nx * j], -theta));
    if (i === 0) ctx.moveTo(...p); else ctx.lineTo(...p);
  }
  ctx.stroke();
  ctx.fillStyle = "#555"; ctx.beginPath(); ctx.arc(cx, cy, 7, 0, 2 * Math.PI); ctx.fill();
  ctx.font = "12px sans-serif"; ctx.textAlign = "left"; ctx.fillStyle = "#333";
  ctx.fillText(`top view: hub ${format(theta * DEG)} deg, reference ${format(thetaRef * DEG)} deg (dashed)`, 8, 16);
  ctx.fillText(`deflection drawn ×${k} (the plate is ${format(a)} m long)`, 8, 32);

  // Face view: the deflection over the plate, coloured (blue one way, red the other).
  const face = $("plate-face"), fx = face.getContext("2d");
  const FW = face.width, FH = face.height;
  fx.clearRect(0, 0, FW, FH);
  const s = Math.min((FW - 40) / a, (FH - 50) / b);
  const x0 = 20, y0 = 30;
  const wabs = Math.max(1e-12, ...w.map(Math.abs));
  const cw = s * a / nx, ch = s * b / ny;
  for (let jj = 0; jj < ny; jj++) {
    for (let i = 0; i < nx; i++) {
      const v = w[i + nx * jj] / wabs;
      const c = Math.round(255 * (1 - Math.abs(v)));
      fx.fillStyle = v >= 0 ? `rgb(255,${c},${c})` : `rgb(${c},${c},255)`;
      fx.fillRect(x0 + i * cw, y0 + (ny - 1 - jj) * ch, cw + 0.5, ch + 0.5);
    }
  }
  fx.strokeStyle = "#333"; fx.strokeRect(x0, y0, s * a, s * b);
  fx.fillStyle = "#333"; fx.font = "12px sans-serif"; fx.textAlign = "left";
  fx.fillText(`face view (root on the left): deflection, largest ${format(wabs * 1e3)} mm`, 8, 16);
  $("plate-caption").textContent =
    `The plate at t = ${page.sim.time.toFixed(3)} s, from its ${run.plate && nx}×${ny}-point grid of the modal state`;
}

function drawMonitors(run) {
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

function drawMessages(run) {
  const list = $("messages");
  const all = run.messages.map((m) => `<li class="${m.status}">${escapeHtml(m.message)}</li>`);
  if (run.failed) all.push(`<li class="error">${escapeHtml(run.failed)}</li>`);
  list.innerHTML = all.join("");
}

function escapeHtml(s) {
  return s.replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" })[c]);
}

function drawSummary(run) {
  const s = run.samples;
  const last = (name) => s[name][s[name].length - 1];
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
  const simulated = run.samples.t[run.samples.t.length - 1];
  if (run.failed) {
    status(`Stopped at t = ${simulated.toFixed(3)} s: ${run.failed}`, true);
  } else if (run.done) {
    const factor = (ms) => (ms > 0 ? `${(simulated / (ms / 1000)).toFixed(0)}×` : "–");
    status(`${simulated.toFixed(1)} s simulated in ${(run.wallMs / 1000).toFixed(2)} s of wall time ` +
      `(${run.speed === "fast" ? "as fast as possible" : "real time"}): ${factor(run.wallMs)} real time ` +
      `with drawing, the model alone ${factor(run.stepMs)} real time.`);
  } else {
    status(`Running: t = ${simulated.toFixed(2)} s of ${run.stop} s`);
  }
}

// ---------------------------------------------------------------- wiring

function restart() {
  const run = page.run;
  if (run && !run.done && !run.pausedAt && run.command === "slider" && radio("command") === "slider") return;
  start();
}

function wire() {
  $("preset").addEventListener("change", () => { loadPreset(); start(); });
  for (const id of CONTROLS) if (id !== "preset") $(id).addEventListener("change", start);
  for (const input of document.querySelectorAll('input[name="command"]')) {
    input.addEventListener("change", () => {
      $("r").disabled = radio("command") !== "slider";
      start();
    });
  }
  for (const input of document.querySelectorAll('input[name="speed"]')) {
    input.addEventListener("change", () => {
      if (page.run) page.run.speed = radio("speed");
      go();
    });
  }
  $("r").addEventListener("input", () => {
    $("r-value").textContent = Number($("r").value).toFixed(2);
    restart();
  });
  $("run").addEventListener("click", start);
  $("pause").addEventListener("click", () => {
    const run = page.run;
    if (!run || run.done) return;
    if (run.pausedAt) {
      run.paused += performance.now() - run.pausedAt;
      run.pausedAt = 0;
      $("pause").textContent = "Pause";
      go();
    } else {
      run.pausedAt = performance.now();
      $("pause").textContent = "Resume";
    }
  });
  $("reset").addEventListener("click", () => {
    $("preset").value = "complete";
    loadPreset();
    $("stop").value = 5;
    start();
  });
}

async function main() {
  try {
    page.model = await HSP.load();
    page.timing.loaded = performance.now();
    for (const p of page.model.presets) {
      const option = document.createElement("option");
      option.value = p.name;
      option.textContent = p.name;
      $("preset").appendChild(option);
    }
    $("preset").value = "complete";
    fromQuery();
    $("r").disabled = radio("command") !== "slider";
    wire();
    start();
  } catch (e) {
    page.error = e.message;
    status(`The model could not be loaded: ${e.message}`, true);
  }
}

main();
