// The interactive page's life cycle: checks the controls, hands the run to the simulation thread
// (a Web Worker, docs/web/worker.js), records what comes back and redraws the page; and the
// wiring of the controls. The page's own thread never steps the model, and a redraw costs the
// same at any length of run (each plot keeps a fixed number of pixel columns), so Pause, Reset
// and the controls answer at once.
// The page's other jobs are in classic scripts that share these globals, loaded before this one
// by index.html: controls.js (the controls, the parameter panel, the address), plots.js,
// plate.js, status.js (the status, monitors and messages) and export.js (the downloads).
// What it shows and measures is kept in `window.hspPage` (read by tests/python/test_web.py).
"use strict";

const STEP = 1e-3; // communication step [s]
const DEG = 180 / Math.PI;
const GRID = [21, 7]; // the plate's deflection grid, along and across
// The plate's coordinates are kept every plateEvery steps, at most this many times in a run (to
// draw the plate at any time of it: the time cursor shows the nearest kept frame, 5 ms apart in
// the default 5 s run). The worker reads them there only: read after every step they cost the
// run a quarter of its speed.
const PLATE_FRAMES = 1000;

// The outputs recorded at every communication point [SI], and how they are shown.
const RECORDED = [
  "controller.reference", "y_pot", "theta_motor", "theta_hub", "w_tip", "p_load",
  "servo_valve.p_1", "servo_valve.p_2", "controller.e_out",
  "plate.w_tip_ratio", "plate.stress", "torsion_bar.stress", "hub.omega_ratio",
];

// The messages that are not "ok": validity warnings, discarded steps, errors.
const ALERTS = ["warning", "discard", "error", "fatal"];
// Running as fast as possible, the page is redrawn at most this often [ms] (the drawing's thread
// is the browser's to share with the simulation's); at real time, at every animation frame.
const DRAW_MS = 250;

const $ = (id) => document.getElementById(id);

// An integer with its thousands separated by commas (not toLocaleString: its first call loads
// the locale's data, tens of milliseconds before the first run can start).
function grouped(n) {
  return String(n).replace(/\B(?=(\d{3})+(?!\d))/g, ",");
}

function escapeHtml(s) {
  return s.replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" })[c]);
}

const page = {
  model: null, // the variable table and the presets, from the worker
  worker: null,
  run: null, // the run on screen: the one in progress, or the last one
  timing: { start: performance.now() },
  runs: 0,
  error: null, // why the controls' settings were not run
  dirty: false,
  drawn: 0, // when the page was last drawn
  panel: new Map(), // the parameter panel's rows by parameter name
  panelSettings: {}, // the panel's settings of the last run asked for
  motor: null, // the motor variable the motor control is on
  layout: {}, // each plot's frame, legend and span as last drawn
  view: null, // the plots' zoom {x0, x1} [s], or null: the whole run
  cursor: null, // the time cursor [s], or null: following the run
  drag: null, // a zoom being dragged {canvas, t0, t1}
  readout: null, // the hover readout last shown
};
window.hspPage = page;

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

// The run the controls ask for, handed to the worker.
function newRun(asked) {
  const steps = Math.round(asked.stop / STEP);
  const plateEvery = Math.max(1, Math.ceil(steps / PLATE_FRAMES));
  const fullValve = motorVariable() === "servo_valve.D_m";
  const run = {
    id: ++page.runs,
    request: asked.request,
    stop: asked.stop,
    steps,
    command: asked.command,
    tStart: asked.tStart,
    shaker: asked.shaker,
    plateEvery,
    address: location.href,
    speed: radio("speed"),
    fullValve,
    samples: { t: new Series() },
    inputs: new Series(), // r of each step, as set before it
    forces: new Series(), // with the shakers: F1, F2 of each step, as set before it
    frames: new Series(), // the plate's coordinates every plateEvery steps, frame after frame
    frameT: new Series(), // their times
    eta: null, // the plate's coordinates at the last point
    wGrid: 0, // the largest |deflection| over the grid in the frames so far [m]
    peak: {}, // the largest magnitude of each recorded output so far
    messages: [],
    alerts: 0, // the messages that are not "ok"
    plots: plotSpecs(fullValve).map((p) => {
      const canvas = $(p.canvas);
      const columns = canvas.width - PLOT_MARGIN.L - PLOT_MARGIN.R;
      return { canvas, unit: p.unit, traces: p.series.map((s) => new Trace(s, columns, asked.stop)) };
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
    r: Number($("r").value), speed: run.speed, shaker: run.shaker, plateEvery,
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
  for (let i = 0; i < batch.forces.length; i++) run.forces.push(batch.forces[i]);
  const n = run.map && run.map.coordinates ? run.map.coordinates.length : 0;
  for (let f = 0; n && f < batch.frameT.length; f++) {
    const eta = batch.frames.subarray(f * n, (f + 1) * n);
    for (let c = 0; c < n; c++) run.frames.push(eta[c]);
    run.frameT.push(batch.frameT[f]);
    run.wGrid = Math.max(run.wGrid, largestDeflection(run, eta));
  }
  if (batch.eta) run.eta = batch.eta;
  run.time = batch.time;
  run.stepMs = batch.stepMs;
  if (batch.failed) run.failed = batch.failed;
  if (batch.done) run.done = true;
  page.dirty = true;
  requestFrame();
}

// The recorded run as plain arrays (for tests and the bench): {samples: {t, NAME...}, inputs,
// forces (F1, F2 of each step in turn, with the shakers)}.
page.recorded = (run = page.run) => {
  if (!run) return { samples: null, inputs: null };
  const samples = {};
  for (const [name, series] of Object.entries(run.samples)) samples[name] = series.array();
  return { samples, inputs: run.inputs.array(), forces: run.forces.array() };
};

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
    run.map = m.map;
    receive(run, m.batch);
  } else if (m.type === "data") {
    receive(run, m.batch);
  } else if (m.type === "paused") {
    // The worker has stopped stepping: the Pause has acted.
    page.timing.pauseActed = performance.now();
    page.timing.pausedAt = m.time;
  } else if (m.type === "ssv") {
    if (m.error) status(`The parameter set could not be written: ${m.error}`, "error");
    else download(`hsp-run-${run.id}-${run.request.preset}.ssv`, "application/xml", m.text);
    page.ssv = m.text || m.error;
    return;
  } else if (m.type === "refused") {
    refuse(m.message, run.previous);
  }
  syncControls();
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
  if (previous) previous.previous = null; // one run back is kept (the overlay), not all of them
  page.run = newRun(asked);
  page.run.previous = previous; // on screen until the new one draws, then overlaid
  page.cursor = null;
  if (page.view && page.view.x0 >= asked.stop) page.view = null;
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

// ---------------------------------------------------------------- drawing

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

function draw(run) {
  if (!run || !run.samples.t.length) return;
  if (run === page.run && !page.error) markStale(null);
  const prev = $("overlay").checked && run.previous && run.previous.samples.t.length ? run.previous : null;
  for (const p of run.plots) plot(p, run, prev);
  const cursor = $("cursor");
  if (Number(cursor.max) !== run.stop) cursor.max = run.stop;
  if (page.cursor === null) cursor.value = run.samples.t.last();
  $("cursor-value").textContent = `t = ${cursorTime(run).toFixed(3)} s${page.cursor === null ? " (following the run)" : ""}`;
  $("view-note").textContent = page.view ? `· zoomed on ${format(page.view.x0)} s to ${format(page.view.x1)} s.` : "";
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

function redraw() {
  page.dirty = true;
  requestFrame();
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
  $("download-ssv").addEventListener("click", () => {
    const run = page.run;
    page.worker.postMessage({
      type: "ssv", id: run.id, preset: run.request.preset, settings: run.request.settings,
      name: `hsp-run-${run.id}-${run.request.preset}`,
      description: `The browser page's run ${run.id}: preset ${run.request.preset} with the page's settings over it ` +
        `(stop time ${run.stop} s, ${STEP * 1e3} ms communication steps; ${settingsInput(run)})`,
    });
  });
  $("copy-link").addEventListener("click", copyLink);
  $("overlay").addEventListener("change", redraw);
  $("cursor").addEventListener("input", () => {
    page.cursor = Number($("cursor").value);
    syncControls();
    redraw();
  });
  $("cursor-live").addEventListener("click", () => {
    page.cursor = null;
    syncControls();
    redraw();
  });
  for (const p of document.querySelectorAll(".plots canvas")) wirePlot(p);
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
  buildPanel();
  $("stop-note").textContent = `Up to ${$("stop").max} s: the page keeps every point of the run ` +
    `(${grouped(Math.round($("stop").max / STEP + 1))} at most, ${RECORDED.length + 2} numbers each).`;
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
