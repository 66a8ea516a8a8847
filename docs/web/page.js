// The interactive page: checks the controls, hands the run to the simulation thread (a Web Worker,
// docs/web/worker.js) and draws what comes back. The page's own thread never steps the model, and
// a redraw costs the same at any length of run (each plot keeps a fixed number of pixel columns),
// so Pause, Reset and the controls answer at once.
// What it shows and measures is kept in `window.hspPage` (read by tests/python/test_web.py).
"use strict";

const STEP = 1e-3; // communication step [s]
const DEG = 180 / Math.PI;
const GRID = [21, 7]; // the plate's deflection grid, along and across

// The outputs recorded at every communication point [SI], and how they are shown.
const RECORDED = [
  "controller.reference", "y_pot", "theta_motor", "theta_hub", "w_tip", "p_load",
  "servo_valve.p_1", "servo_valve.p_2", "controller.e_out",
  "plate.w_tip_ratio", "plate.stress", "torsion_bar.stress", "hub.omega_ratio",
];

// The messages that are not "ok": validity warnings, discarded steps, errors.
const ALERTS = ["warning", "discard", "error", "fatal"];
const SHOWN_MESSAGES = 200; // the messages listed under the plate (the latest)
// Running as fast as possible, the page is redrawn at most this often [ms] (the drawing's thread
// is the browser's to share with the simulation's); at real time, at every animation frame.
const DRAW_MS = 250;

const $ = (id) => document.getElementById(id);

const page = {
  model: null, // the variable table and the presets, from the worker
  worker: null,
  run: null, // the run on screen: the one in progress, or the last one
  timing: { start: performance.now() },
  runs: 0,
  error: null, // why the controls' settings were not run
  dirty: false,
  drawn: 0, // when the page was last drawn
};
window.hspPage = page;

// status(text, kind): kind "" (running), "ok", "warning" or "error".
function status(text, kind) {
  const s = $("status");
  s.textContent = text;
  s.className = kind || "";
}

// ---------------------------------------------------------------- controls

const CONTROLS = ["preset", "angle", "t_start", "duration", "A1", "A2", "bar_k", "zeta", "D_m", "stop"];
const NUMBERS = CONTROLS.filter((id) => id !== "preset");

function radio(name) {
  return document.querySelector(`input[name="${name}"]:checked`).value;
}

function radioValues(name) {
  return [...document.querySelectorAll(`input[name="${name}"]`)].map((i) => i.value);
}

function setRadio(name, value) {
  const input = document.querySelector(`input[name="${name}"][value="${value}"]`);
  if (input) input.checked = true;
}

// The control's name as its label shows it ("Error amplifier A1").
function fieldName(input) {
  const label = input.closest("label");
  const span = label && label.querySelector("span");
  return (span ? span.textContent : input.name).replace(/\s+/g, " ").trim();
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
  for (const id of NUMBERS) delete $(id).dataset.raw;
}

// The number in a field, or why it is not one the page accepts: text that is no number (typed,
// or from the address), an empty field, or a value beyond the field's min and max (index.html's
// attributes are the page's limits; the model checks its own ranges when the run is made).
function readNumber(id, problems) {
  const input = $(id);
  const name = fieldName(input);
  let problem = null;
  if (input.validity.badInput || (input.value === "" && input.dataset.raw)) {
    problem = input.dataset.raw ? `'${input.dataset.raw}' is not a number` : "what is typed is not a number";
  } else if (input.value.trim() === "") {
    problem = "empty: a number is needed";
  } else if (input.validity.rangeUnderflow) {
    problem = `${input.value} is below the page's limit of ${input.min}`;
  } else if (input.validity.rangeOverflow) {
    problem = `${input.value} is above the page's limit of ${input.max}`;
  }
  const v = Number(input.value);
  if (!problem && !Number.isFinite(v)) problem = `'${input.value}' is not a finite number`;
  input.toggleAttribute("aria-invalid", !!problem);
  input.title = problem ? `${name}: ${problem}` : "";
  if (problem) problems.push(`${name}: ${problem}`);
  return v;
}

// The run the controls ask for: {request: {preset, settings over it}, stop, command, ...}.
// Throws an Error naming every field the page cannot take.
function readControls() {
  const problems = [];
  const v = {};
  for (const id of NUMBERS) v[id] = readNumber(id, problems);
  if (problems.length) throw new Error(`Not run: ${problems.join("; ")}.`);
  const command = radio("command");
  const settings = {
    "reference.angle": command === "move" ? v.angle / DEG : 0,
    "reference.t_start": v.t_start,
    "reference.duration": v.duration,
    "controller.A1": v.A1,
    "controller.A2": v.A2,
    "torsion_bar.k": v.bar_k,
    "plate.zeta": v.zeta,
  };
  settings[motorVariable()] = v.D_m * 1e-6;
  return {
    request: { preset: $("preset").value, settings },
    stop: v.stop,
    command,
    angle: v.angle / DEG, // the step of r: the potentiometer voltage of this angle
    tStart: v.t_start,
  };
}

// The controls from the address (`?preset=loes-motor&A1=3`, as docs/web.md lists): what it asks
// for that the page has not (an unknown name or value) is returned, to be refused by name.
function fromQuery() {
  const q = new URLSearchParams(location.search);
  const problems = [];
  const known = [...CONTROLS, "command", "speed"];
  for (const key of q.keys()) {
    if (!known.includes(key)) problems.push(`'${key}' in the address is not a setting of the page (${known.join(", ")})`);
  }
  if (q.has("preset")) {
    const name = q.get("preset");
    if (page.model.presets.some((p) => p.name === name)) $("preset").value = name;
    else problems.push(`preset '${name}' in the address is not one of the presets (${page.model.presets.map((p) => p.name).join(", ")})`);
  }
  loadPreset();
  for (const id of NUMBERS) {
    if (!q.has(id)) continue;
    const raw = q.get(id);
    $(id).value = raw;
    if ($(id).value === "" && raw !== "") $(id).dataset.raw = raw; // the browser dropped it
  }
  for (const name of ["command", "speed"]) {
    if (!q.has(name)) continue;
    const value = q.get(name);
    if (radioValues(name).includes(value)) setRadio(name, value);
    else problems.push(`${name} '${value}' in the address is not one of ${radioValues(name).join(", ")}`);
  }
  return problems;
}

// The controls as the address (the names fromQuery reads), written back into the browser's
// address bar, so that a copied link opens the page with these settings and runs them.
function address() {
  const q = new URLSearchParams();
  q.set("preset", $("preset").value);
  q.set("command", radio("command"));
  for (const id of NUMBERS) q.set(id, $(id).value);
  q.set("speed", radio("speed"));
  return "?" + q.toString();
}

function writeAddress() {
  history.replaceState(null, "", address());
  $("link").value = location.href;
}

// The controls that follow the run's state: the slider only with its command, Pause only while
// a run goes on (and "Resume" only while it is paused).
function syncControls() {
  const run = page.run;
  const live = !!run && !run.done && !page.error;
  const results = !!run && run.samples.t.length > 0;
  // Written only when they change (a write makes the browser lay the page out again).
  const set = (id, key, value) => { if ($(id)[key] !== value) $(id)[key] = value; };
  set("r", "disabled", radio("command") !== "slider");
  set("pause", "disabled", !live);
  set("pause", "textContent", live && run.pausedAt ? "Resume" : "Pause");
  set("download-csv", "disabled", !results);
  set("download-json", "disabled", !results);
}

// ---------------------------------------------------------------- the run

// A growing array of doubles, in blocks that are never copied (so that adding a point costs the
// same at any length of run).
class Series {
  constructor() {
    this.blocks = [];
    this.length = 0;
  }

  push(v) {
    const at = this.length % Series.BLOCK;
    if (at === 0) this.blocks.push(new Float64Array(Series.BLOCK));
    this.blocks[this.blocks.length - 1][at] = v;
    this.length++;
  }

  last() {
    return this.at(this.length - 1);
  }

  at(i) {
    return this.blocks[Math.floor(i / Series.BLOCK)][i % Series.BLOCK];
  }

  array() {
    const out = new Array(this.length);
    for (let i = 0; i < this.length; i++) out[i] = this.at(i);
    return out;
  }
}
Series.BLOCK = 16384;

// One curve of a plot, kept as what a redraw needs: per pixel column of the time axis, the
// first, lowest, highest and last value that falls in it. Adding a point costs the same at any
// length of run, and so does drawing.
class Trace {
  constructor({ label, name, factor = 1, dash = null }, columns, xmax) {
    Object.assign(this, { label, name, factor, dash, columns, xmax });
    const n = columns + 1;
    this.count = new Uint32Array(n);
    this.first = new Float64Array(n);
    this.min = new Float64Array(n);
    this.max = new Float64Array(n);
    this.last = new Float64Array(n);
    this.lo = Infinity;
    this.hi = -Infinity;
  }

  add(x, value) {
    const v = value * this.factor;
    const c = Math.max(0, Math.min(this.columns, Math.round(this.columns * x / this.xmax)));
    if (this.count[c]++ === 0) {
      this.first[c] = this.min[c] = this.max[c] = this.last[c] = v;
    } else {
      if (v < this.min[c]) this.min[c] = v;
      if (v > this.max[c]) this.max[c] = v;
      this.last[c] = v;
    }
    if (Number.isFinite(v)) {
      if (v < this.lo) this.lo = v;
      if (v > this.hi) this.hi = v;
    }
  }
}

// The plots: their canvases and curves (the pressures' depend on the hydraulics).
function plotSpecs(fullValve) {
  const pressures = [{ label: "p_load", name: "p_load", factor: 1e-5 }];
  if (fullValve) {
    pressures.unshift({ label: "p1", name: "servo_valve.p_1", factor: 1e-5 },
      { label: "p2", name: "servo_valve.p_2", factor: 1e-5 });
  }
  return [
    { canvas: "plot-loop", series: [
      { label: "reference", name: "controller.reference", dash: [5, 3] },
      { label: "y_pot", name: "y_pot" }] },
    { canvas: "plot-angles", series: [
      { label: "motor", name: "theta_motor", factor: DEG },
      { label: "hub", name: "theta_hub", factor: DEG }] },
    { canvas: "plot-tip", series: [{ label: "w_tip", name: "w_tip", factor: 1e3 }] },
    { canvas: "plot-pressures", series: pressures },
  ];
}

const PLOT_MARGIN = { L: 52, R: 8, T: 8, B: 30 };

// The run the controls ask for, handed to the worker.
function newRun(asked) {
  const steps = Math.round(asked.stop / STEP);
  const fullValve = motorVariable() === "servo_valve.D_m";
  const run = {
    id: ++page.runs,
    request: asked.request,
    stop: asked.stop,
    steps,
    command: asked.command,
    tStart: asked.tStart,
    address: location.href,
    speed: radio("speed"),
    fullValve,
    samples: { t: new Series() },
    inputs: new Series(), // r of each step, as set before it
    peak: {}, // the largest magnitude of each recorded output so far
    messages: [],
    alerts: 0, // the messages that are not "ok"
    plots: plotSpecs(fullValve).map((p) => {
      const canvas = $(p.canvas);
      const columns = canvas.width - PLOT_MARGIN.L - PLOT_MARGIN.R;
      return { canvas, traces: p.series.map((s) => new Trace(s, columns, asked.stop)) };
    }),
    started: false, // the worker made the simulation
    pausedAt: 0,
    pausedMs: 0,
    time: 0,
    stepMs: 0, // wall time the worker spent stepping
    done: false,
    failed: null,
    exaggeration: 0,
  };
  for (const name of RECORDED) {
    run.samples[name] = new Series();
    run.peak[name] = 0;
  }
  page.worker.postMessage({
    type: "start", id: run.id, request: run.request, names: RECORDED, step: STEP, stop: run.stop,
    grid: GRID, command: run.command, angle: asked.angle, tStart: asked.tStart,
    r: Number($("r").value), speed: run.speed,
  });
  return run;
}

// What the worker did: recorded, and the traces of the plots extended.
function receive(run, batch) {
  const width = RECORDED.length;
  const { t, values, inputs } = batch;
  for (let i = 0; i < inputs.length; i++) run.inputs.push(inputs[i]);
  const traces = run.plots.flatMap((p) => p.traces).map((tr) => [tr, RECORDED.indexOf(tr.name)]);
  for (let i = 0; i < t.length; i++) {
    run.samples.t.push(t[i]);
    for (let j = 0; j < width; j++) {
      const v = values[i * width + j];
      run.samples[RECORDED[j]].push(v);
      const a = Math.abs(v);
      if (a > run.peak[RECORDED[j]]) run.peak[RECORDED[j]] = a;
    }
    for (const [tr, j] of traces) tr.add(t[i], values[i * width + j]);
  }
  for (const m of batch.messages) {
    run.messages.push(m);
    if (ALERTS.includes(m.status)) run.alerts++;
  }
  run.time = batch.time;
  run.stepMs = batch.stepMs;
  run.deflection = batch.deflection;
  run.deflectionError = batch.deflectionError;
  if (batch.failed) run.failed = batch.failed;
  if (batch.done) run.done = true;
  page.dirty = true;
  requestFrame();
}

function onWorkerMessage(e) {
  const m = e.data;
  if (m.type === "ready") {
    ready(m);
    return;
  }
  if (m.type === "fatal") {
    page.error = m.message;
    status(`The model stopped: ${m.message}`, "error");
    syncControls();
    return;
  }
  const run = page.run;
  if (!run || m.id !== run.id) return; // a run dropped since
  if (m.type === "started") {
    run.started = performance.now();
    run.kPot = m.kPot;
    run.rStep = m.rStep;
    run.monitors = m.monitors;
    run.plate = m.plate;
    receive(run, m.batch);
  } else if (m.type === "data") {
    receive(run, m.batch);
  } else if (m.type === "paused") {
    // The worker has stopped stepping: the Pause has acted.
    page.timing.pauseActed = performance.now();
    page.timing.pausedAt = m.time;
  } else if (m.type === "refused") {
    refuse(m.message, run.previous);
  }
  syncControls();
}

let frameRequested = false;
let frameTimer = 0;
function frame() {
  frameRequested = false;
  const run = page.run;
  if (!run || !page.dirty) return;
  page.dirty = false;
  draw(run);
  // The first points are drawn as soon as they come; the redraws after them at most every DRAW_MS.
  if (run.samples.t.length > 1) page.drawn = performance.now();
}

function requestFrame() {
  const run = page.run;
  const wait = run && run.speed === "fast" && !run.done ? page.drawn + DRAW_MS - performance.now() : 0;
  if (frameTimer && wait <= 0) {
    clearTimeout(frameTimer);
    frameTimer = 0;
  }
  if (frameRequested || frameTimer) return;
  if (wait > 0) {
    frameTimer = setTimeout(() => { frameTimer = 0; requestFrame(); }, wait);
    return;
  }
  frameRequested = true;
  requestAnimationFrame(frame);
}

// The controls' settings, run; or refused by name, the results on screen marked as not theirs.
function start() {
  let asked;
  try {
    asked = readControls();
  } catch (e) {
    refuse(e.message, page.run);
    return;
  }
  page.error = null;
  writeAddress();
  const previous = page.run && page.run.samples.t.length ? page.run : page.run && page.run.previous;
  page.run = newRun(asked);
  page.run.previous = previous; // on screen until the new one draws
  status("Running…", "");
  syncControls();
}

// Settings the page or the model refused: the message, the culprit named, and the results on
// screen (`shown`, a finished or stopped run) marked as those of other settings.
function refuse(message, shown) {
  page.error = message;
  if (page.run && !page.run.done) page.worker.postMessage({ type: "stop" });
  page.run = shown && shown.samples.t.length ? shown : null;
  if (page.run && !page.run.done) page.run.halted = true;
  status(message, "error");
  markStale(page.run);
  syncControls();
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

// ---------------------------------------------------------------- drawing

const COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e"];

// A plot of its traces over [0, xmax], from their pixel columns.
function plot({ canvas, traces }, xmax) {
  const ctx = canvas.getContext("2d");
  const W = canvas.width, H = canvas.height;
  const { L, R, T, B } = PLOT_MARGIN;
  ctx.clearRect(0, 0, W, H);
  let lo = Math.min(...traces.map((tr) => tr.lo)), hi = Math.max(...traces.map((tr) => tr.hi));
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
    ctx.textAlign = "center"; ctx.fillText(format(x), px(x), H - B + 13);
  }
  ctx.fillText("time [s]", L + (W - L - R) / 2, H - 3);
  ctx.strokeStyle = "#888"; ctx.strokeRect(L, T, W - L - R, H - T - B);
  traces.forEach((tr, k) => {
    ctx.strokeStyle = COLOURS[k % COLOURS.length];
    ctx.lineWidth = 1.5;
    ctx.setLineDash(tr.dash || []);
    ctx.beginPath();
    // At most four vertices per pixel column (its first, lowest, highest and last value): the
    // extremes are kept, and the cost does not grow with the run.
    let started = false;
    for (let c = 0; c <= tr.columns; c++) {
      if (!tr.count[c]) continue;
      const x = L + c, first = tr.first[c], min = tr.min[c], max = tr.max[c], last = tr.last[c];
      if (!started) { ctx.moveTo(x, py(first)); started = true; }
      for (const v of first <= last ? [first, min, max, last] : [first, max, min, last]) ctx.lineTo(x, py(v));
    }
    ctx.stroke();
    ctx.setLineDash([]);
    ctx.fillStyle = ctx.strokeStyle;
    ctx.textAlign = "left";
    ctx.fillText(tr.label, L + 8 + 110 * k, T + 14);
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

function draw(run) {
  if (!run || !run.samples.t.length) return;
  if (run === page.run && !page.error) markStale(null);
  for (const p of run.plots) plot(p, run.stop);
  $("pressure-caption").textContent = run.fullValve
    ? "Motor chamber pressures p1, p2 and load pressure [bar]" : "Load pressure [bar]";
  drawPlate(run);
  drawMonitors(run);
  drawMessages(run);
  drawSummary(run);
  if (!page.error) showStatus(run);
  if (!page.timing.firstResult && run.samples.t.length > 1) {
    page.timing.firstResult = performance.now();
  }
  // The finished run is on screen (tests wait for this, not only for the run's end).
  if (run.done && !run.shown) {
    run.shown = true;
    run.wallMs = performance.now() - run.started - run.pausedMs;
    showStatus(run);
  }
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
  if (!run.deflection) {
    $("plate-caption").textContent = run.deflectionError || "";
    return;
  }
  const [a, b] = run.plate;
  const [nx, ny] = GRID;
  const w = run.deflection;
  const wmaxRun = Math.max(1e-9, run.peak.w_tip);
  const k = exaggeration(run, wmaxRun);
  const theta = run.samples.theta_hub.last();
  const thetaRef = run.samples["controller.reference"].last() / run.kPot;

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
  let wabs = 1e-12;
  for (const v of w) wabs = Math.max(wabs, Math.abs(v));
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
    `The plate at t = ${run.time.toFixed(3)} s, from its ${nx}×${ny}-point grid of the modal state`;
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

function escapeHtml(s) {
  return s.replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" })[c]);
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

// The recorded run as plain arrays (for tests and the bench): {samples: {t, NAME...}, inputs}.
page.recorded = (run = page.run) => {
  if (!run) return { samples: null, inputs: null };
  const samples = {};
  for (const [name, series] of Object.entries(run.samples)) samples[name] = series.array();
  return { samples, inputs: run.inputs.array() };
};

// ---------------------------------------------------------------- taking results away

// The run's recorded points as CSV: a header of the names with their units, then one row per
// communication point: the time, the input r set before the step that ended there (empty at
// t = 0), and the recorded outputs (SI units, every digit a double needs).
function csv(run) {
  const unit = (name) => page.model.variable(name).unit || "1";
  const header = ["time [s]", `r [${unit("r")}]`, ...RECORDED.map((n) => `${n} [${unit(n)}]`)];
  const columns = RECORDED.map((n) => run.samples[n]);
  const t = run.samples.t;
  const rows = [header.join(",")];
  for (let i = 0; i < t.length; i++) {
    const row = [t.at(i), i > 0 ? run.inputs.at(i - 1) : ""];
    for (const c of columns) row.push(c.at(i));
    rows.push(row.join(","));
  }
  return rows.join("\n") + "\n";
}

// The run's settings as JSON: the preset and the FMU's variables set over it (what `hsp run
// --preset P --set NAME=VALUE` takes), the stop time and communication step, how r was driven,
// and the page's address that runs it again.
function settingsJson(run) {
  const input = {
    move: "r = 0: the command generator's move (reference.*) drives the loop",
    step: `r steps from 0 to ${run.rStep} V at t = ${run.tStart} s`,
    slider: "r moved by hand: see the CSV's r column",
  }[run.command];
  return JSON.stringify({
    model: "HydraulicSlewingPlate", preset: run.request.preset, settings: run.request.settings,
    stop_time: run.stop, step_size: STEP, command: run.command, input_r: input,
    address: run.address, run: run.id, failed: run.failed,
  }, null, 2) + "\n";
}

function download(name, type, text) {
  const a = document.createElement("a");
  a.href = URL.createObjectURL(new Blob([text], { type }));
  a.download = name;
  document.body.appendChild(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
}

// Puts the address in the clipboard where the browser lets the page (not always from the disk),
// and shows it selected beside the button either way.
async function copyLink() {
  const link = $("link");
  link.value = location.href;
  link.select();
  page.copied = link.value;
  try {
    await navigator.clipboard.writeText(link.value);
    $("link-note").textContent = "Copied: the link opens the page with these settings and runs them.";
  } catch (e) {
    $("link-note").textContent = "Selected: copy it with Ctrl+C (the browser keeps the clipboard from this page).";
  }
}

// ---------------------------------------------------------------- wiring

// The slider's r, moved while a slider run goes on, is handed to the run; otherwise a move of
// the slider starts a new run.
function slide() {
  $("r-value").textContent = Number($("r").value).toFixed(2);
  const run = page.run;
  if (run && !run.done && !run.pausedAt && !page.error && run.command === "slider" &&
      radio("command") === "slider") {
    page.worker.postMessage({ type: "r", value: Number($("r").value) });
    return;
  }
  start();
}

function pause(event) {
  const run = page.run;
  if (!run || run.done || page.error) return;
  if (run.pausedAt) {
    run.pausedMs += performance.now() - run.pausedAt;
    run.pausedAt = 0;
    page.worker.postMessage({ type: "resume" });
  } else {
    run.pausedAt = performance.now();
    page.timing.pauseClicked = event.timeStamp;
    page.timing.pauseActed = 0;
    page.worker.postMessage({ type: "pause" });
  }
  syncControls();
  if (run.samples.t.length) showStatus(run);
}

// Back to the page as it opens (the preset "complete", its values, a 5 s run; the speed kept).
function reset() {
  $("preset").value = "complete";
  loadPreset();
  $("stop").value = $("stop").defaultValue;
  $("r").value = 0;
  $("r-value").textContent = "0.00";
  start();
}

function wire() {
  $("preset").addEventListener("change", () => { loadPreset(); start(); });
  for (const id of NUMBERS) {
    $(id).addEventListener("input", () => { delete $(id).dataset.raw; });
    $(id).addEventListener("change", start);
  }
  for (const input of document.querySelectorAll('input[name="command"]')) {
    input.addEventListener("change", start);
  }
  for (const input of document.querySelectorAll('input[name="speed"]')) {
    input.addEventListener("change", () => {
      const run = page.run;
      if (run) {
        run.speed = radio("speed");
        page.worker.postMessage({ type: "speed", speed: run.speed });
      }
      if (!page.error) writeAddress();
    });
  }
  $("r").addEventListener("input", slide);
  $("run").addEventListener("click", start);
  $("pause").addEventListener("click", pause);
  $("reset").addEventListener("click", reset);
  $("download-csv").addEventListener("click", () => {
    const run = page.run;
    download(`hsp-run-${run.id}-${run.request.preset}.csv`, "text/csv", csv(run));
  });
  $("download-json").addEventListener("click", () => {
    const run = page.run;
    download(`hsp-run-${run.id}-${run.request.preset}.json`, "application/json", settingsJson(run));
  });
  $("copy-link").addEventListener("click", copyLink);
}

// The worker has loaded the module: the controls are filled (from the address) and the first run
// starts, unless the address asks for what the page has not.
function ready({ variables, presets }) {
  page.timing.loaded = performance.now();
  const byName = new Map(variables.map((v) => [v.name, v]));
  page.model = {
    variables,
    presets,
    variable(name) {
      const v = byName.get(name);
      if (!v) throw new Error(`unknown variable '${name}'`);
      return v;
    },
  };
  for (const p of presets) {
    const option = document.createElement("option");
    option.value = p.name;
    option.textContent = p.name;
    $("preset").appendChild(option);
  }
  $("preset").value = "complete";
  $("stop-note").textContent = `Up to ${$("stop").max} s: the page keeps every point of the run ` +
    `(${Math.round($("stop").max / STEP + 1).toLocaleString("en")} at most, ${RECORDED.length + 2} numbers each).`;
  const problems = fromQuery();
  wire();
  if (problems.length) refuse(`Not run: ${problems.join("; ")}.`, null);
  else start();
}

// The simulation thread: hsp.js and worker.js's hspWorker from a Blob, the module's bytes handed
// over (a page from the disk reads them from hsp.wasm.js; over HTTP they are fetched).
async function main() {
  try {
    const source = `${HSP.script}(${hspWorker})(self);\n`;
    const url = URL.createObjectURL(new Blob([source], { type: "text/javascript" }));
    page.worker = new Worker(url);
    page.worker.onmessage = onWorkerMessage;
    page.worker.onerror = (e) => {
      page.error = e.message || "the simulation thread failed";
      status(`The simulation thread failed: ${page.error}`, "error");
    };
    const bytes = await HSP.moduleBytes();
    const buffer = bytes instanceof ArrayBuffer ? bytes : bytes.buffer;
    page.worker.postMessage({ type: "load", bytes: buffer }, [buffer]);
  } catch (e) {
    page.error = e.message;
    status(`The model could not be loaded: ${e.message}`, "error");
  }
}

main();
