// The interactive page: checks the controls, hands the run to the simulation thread (a Web Worker,
// docs/web/worker.js) and draws what comes back. The page's own thread never steps the model, and
// a redraw costs the same at any length of run (each plot keeps a fixed number of pixel columns),
// so Pause, Reset and the controls answer at once.
// What it shows and measures is kept in `window.hspPage` (read by tests/python/test_web.py).
"use strict";

const STEP = 1e-3; // communication step [s]
const DEG = 180 / Math.PI;
const GRID = [21, 7]; // the plate's deflection grid, along and across
// The plate's coordinates are kept every plateEvery steps, at most this many times in a run (to
// draw the plate at any time of it: the time cursor).
const PLATE_FRAMES = 6000;
// A plate whose largest deflection in the run stays below this [m] is at rest: drawn as it is.
const AT_REST = 1e-6;

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

// status(text, kind): kind "" (running), "ok", "warning" or "error".
function status(text, kind) {
  const s = $("status");
  s.textContent = text;
  s.className = kind || "";
}

// ---------------------------------------------------------------- controls

const CONTROLS = ["preset", "angle", "t_start", "duration", "A1", "A2", "bar_k", "zeta", "D_m", "stop",
  "F1", "F2", "shaker_f"];
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

// A switch's value for the run: the parameter panel's, else the preset's.
function switchValue(name) {
  const row = page.panel.get(name);
  if (!row) return presetValue(name);
  return row.v.type === "Boolean" ? row.input.value === "true" : Number(row.input.value);
}

// The variable that sizes the motor: the full servo valve's or the LOES's.
function motorVariable() {
  const hydraulics = switchValue("hydraulics.model");
  return hydraulics === 1 || hydraulics === "Loes" ? "loes.D_m" : "servo_valve.D_m";
}

// The motor displacement control at the motor variable's value [cm³/rad] (6 digits shown, the
// exact value kept behind them: a preset's D_m runs as the preset has it).
function showMotor() {
  const name = motorVariable();
  const row = page.panel.get(name);
  const x = row && row.input.dataset.si !== undefined ? Number(row.input.dataset.si) : presetValue(name);
  $("D_m").value = +(x * 1e6).toPrecision(6);
  $("D_m").dataset.si = String(x);
  $("D_m").dataset.shown = $("D_m").value;
  page.motor = name;
}

// After a switch of the panel: the shakers shown for a motor not coupled to the hub, the motor
// control on the motor the hydraulics have, the panel's rows of the controls not edited.
function syncSwitches() {
  $("shakers").hidden = !shaken();
  if (page.motor !== motorVariable()) showMotor();
  flagControlled();
}

// Fills the plant and command controls from the preset.
function loadPreset() {
  fillPanel();
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
  showMotor();
  for (const id of ["F1", "F2", "shaker_f"]) $(id).value = 0;
  for (const id of NUMBERS) delete $(id).dataset.raw;
  syncSwitches();
}

// Whether the plate is driven by the shakers alone (the motor is not coupled to the hub).
function shaken() {
  return switchValue("hydraulics.motor_coupled") === false;
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

// ---------------------------------------------------------------- the parameter panel

// The model's parameters as its variable table declares them (read from the module, which has it
// from modelDescription.xml through build.rs): grouped as the XML groups them, each in its
// display unit, with its range, the preset's value and its description. `page.panel` maps a
// parameter's name to its row {v, tr, input}.

// The variables the controls on the left set, and the control that sets each.
function controlled() {
  return {
    "reference.angle": "angle", "reference.t_start": "t_start", "reference.duration": "duration",
    "controller.A1": "A1", "controller.A2": "A2", "torsion_bar.k": "bar_k", "plate.zeta": "zeta",
    [motorVariable()]: "D_m",
  };
}

// The unit a variable is shown in: its display unit, else its unit ("" for 1).
function unitOf(v) {
  const u = v.displayUnit ? v.displayUnit.name : v.unit;
  return u && u !== "1" ? u : "";
}

// A value in the variable's unit as the text shown for it (in its display unit, 12 digits).
function shownText(v, x) {
  if (typeof x !== "number" || v.type !== "Real") return String(x);
  const d = v.displayUnit;
  return String(+(d ? x * d.factor + d.offset : x).toPrecision(12));
}

// A number typed in the display unit, in the variable's unit (15 digits: 210 bar is 2.1e7 Pa).
function fromDisplay(v, y) {
  const d = v.displayUnit;
  return d ? +((y - d.offset) / d.factor).toPrecision(15) : y;
}

function buildPanel() {
  const groups = new Map();
  for (const v of page.model.variables.filter((x) => x.causality === "parameter")) {
    const g = v.group || "parameters";
    if (!groups.has(g)) groups.set(g, []);
    groups.get(g).push(v);
  }
  page.panel = new Map();
  const box = $("parameter-groups");
  box.textContent = "";
  for (const [group, vars] of groups) {
    const details = document.createElement("details");
    details.dataset.group = group;
    details.innerHTML = `<summary>${escapeHtml(group)} (${vars.length})</summary><table><thead><tr>` +
      "<th>parameter</th><th>value</th><th>unit</th><th>range</th><th>preset</th></tr></thead><tbody></tbody></table>";
    const body = details.querySelector("tbody");
    for (const v of vars) {
      const tr = document.createElement("tr");
      tr.dataset.name = v.name;
      let input;
      if (v.type === "Boolean" || v.type === "Enumeration") {
        input = document.createElement("select");
        const options = v.type === "Boolean"
          ? [["true", "true"], ["false", "false"]]
          : v.items.map((i) => [String(i.value), `${i.value} = ${i.name}`]);
        for (const [value, text] of options) input.add(new Option(text, value));
      } else {
        input = document.createElement("input");
        input.type = "text";
        input.inputMode = "decimal";
      }
      input.name = v.name;
      input.setAttribute("aria-label", v.name);
      input.addEventListener("change", () => {
        syncSwitches();
        start();
      });
      const range = v.type === "Boolean" || v.type === "Enumeration" ? "" :
        `${v.min === null ? "−∞" : shownText(v, v.min)} … ${v.max === null ? "∞" : shownText(v, v.max)}`;
      tr.innerHTML = `<td><code>${escapeHtml(v.name)}</code><div class="desc">${escapeHtml(v.description)}</div></td>` +
        `<td class="value"></td><td class="unit">${escapeHtml(unitOf(v))}</td><td class="num range">${range}</td>` +
        "<td class=\"num preset\"></td>";
      tr.querySelector("td.value").appendChild(input);
      body.appendChild(tr);
      page.panel.set(v.name, { v, tr, input });
    }
    box.appendChild(details);
  }
}

// Shows `x` (in the variable's unit) in a row, remembering the exact value behind the text.
function showInPanel(row, x) {
  row.input.value = shownText(row.v, x);
  row.input.dataset.si = String(x);
  row.input.dataset.shown = row.input.value;
  row.input.removeAttribute("aria-invalid");
  row.input.title = "";
}

// The panel at the chosen preset's values.
function fillPanel() {
  for (const [name, row] of page.panel) {
    const x = presetValue(name);
    showInPanel(row, x);
    row.tr.querySelector("td.preset").textContent = row.input.tagName === "SELECT"
      ? row.input.selectedOptions[0]?.textContent ?? String(x) : row.input.value;
    row.tr.classList.remove("changed");
  }
}

// The panel's rows of the variables the controls set: shown, not edited.
function flagControlled() {
  const ctl = controlled();
  for (const [name, row] of page.panel) {
    row.input.disabled = !!ctl[name];
    if (ctl[name]) row.input.title = `set by the control '${ctl[name]}' on the left`;
  }
}

// A value from the address (in the variable's unit) put into its row; what it cannot take is
// returned, to be refused by name.
function setPanel(row, raw) {
  const { v, input } = row;
  if (input.tagName === "SELECT") {
    if ([...input.options].some((o) => o.value === raw)) {
      input.value = raw;
      return [];
    }
    return [`${v.name} '${raw}' in the address is not one of ${[...input.options].map((o) => o.value).join(", ")}`];
  }
  const x = raw.trim() === "" ? NaN : Number(raw);
  if (Number.isFinite(x)) showInPanel(row, x);
  else input.value = raw; // named when the run is checked
  return [];
}

// The controls' values shown in their rows of the panel.
function showControlled(settings) {
  const ctl = controlled();
  for (const [name, row] of page.panel) {
    if (ctl[name] && name in settings) showInPanel(row, settings[name]);
  }
}

// The panel's settings that differ from the preset's: {NAME: value in the variable's unit}.
// What a row cannot take (no number, beyond the model's min or max) is pushed to `problems`,
// named with its parameter.
function readPanel(problems) {
  const settings = {};
  const ctl = controlled();
  for (const [name, row] of page.panel) {
    const { v, input, tr } = row;
    tr.classList.remove("changed");
    input.removeAttribute("aria-invalid");
    if (ctl[name]) continue;
    const text = input.value.trim();
    const unit = unitOf(v) ? ` ${unitOf(v)}` : "";
    let value;
    let problem = null;
    if (v.type === "Boolean") value = text === "true";
    else if (v.type === "Enumeration") value = Number(text);
    else if (text === input.dataset.shown) value = Number(input.dataset.si);
    else if (text === "") problem = "empty: a number is needed";
    else if (!Number.isFinite(Number(text))) problem = `'${text}' is not a number`;
    else if (v.type === "Integer" && !Number.isInteger(Number(text))) problem = `${text} is not an integer`;
    else value = v.type === "Integer" ? Number(text) : fromDisplay(v, Number(text));
    if (!problem && v.type !== "Boolean" && v.type !== "Enumeration") {
      if (v.min !== null && value < v.min) {
        problem = `${text}${unit} is below the model's minimum of ${shownText(v, v.min)}${unit}`;
      } else if (v.max !== null && value > v.max) {
        problem = `${text}${unit} is above the model's maximum of ${shownText(v, v.max)}${unit}`;
      }
    }
    if (problem) {
      input.setAttribute("aria-invalid", "");
      input.title = `${name}: ${problem}`;
      problems.push(`${name} (${v.description.split(/[;(]/)[0].trim()}): ${problem}`);
      continue;
    }
    if (value !== presetValue(name)) {
      settings[name] = value;
      tr.classList.add("changed");
    }
  }
  return settings;
}

// The run the controls ask for: {request: {preset, settings over it}, stop, command, ...}.
// Throws an Error naming every field the page cannot take.
function readControls() {
  const problems = [];
  const v = {};
  for (const id of NUMBERS) v[id] = readNumber(id, problems);
  const panel = readPanel(problems);
  if (problems.length) throw new Error(`Not run: ${problems.join("; ")}.`);
  page.panelSettings = panel;
  const command = radio("command");
  const settings = {
    ...panel,
    "reference.angle": command === "move" ? v.angle / DEG : 0,
    "reference.t_start": v.t_start,
    "reference.duration": v.duration,
    "controller.A1": v.A1,
    "controller.A2": v.A2,
    "torsion_bar.k": v.bar_k,
    "plate.zeta": v.zeta,
  };
  const motor = $("D_m");
  settings[motorVariable()] = motor.value === motor.dataset.shown ? Number(motor.dataset.si) : v.D_m * 1e-6;
  showControlled(settings);
  const shaker = shaken() && (v.F1 !== 0 || v.F2 !== 0)
    ? { F1: v.F1, F2: v.F2, f: v.shaker_f, tStart: v.t_start } : null;
  return {
    shaker,
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
    if (!page.panel.has(key) && !known.includes(key)) {
      problems.push(`'${key}' in the address is not a setting of the page (${known.join(", ")}) nor a parameter of the model`);
    }
  }
  if (q.has("preset")) {
    const name = q.get("preset");
    if (page.model.presets.some((p) => p.name === name)) $("preset").value = name;
    else problems.push(`preset '${name}' in the address is not one of the presets (${page.model.presets.map((p) => p.name).join(", ")})`);
  }
  loadPreset();
  // The switches first: they decide which variables the controls set.
  for (const [name, row] of page.panel) {
    if (q.has(name) && row.input.tagName === "SELECT") problems.push(...setPanel(row, q.get(name)));
  }
  syncSwitches();
  const ctl = controlled();
  for (const key of q.keys()) {
    if (ctl[key]) problems.push(`'${key}' in the address is set by the page's control '${ctl[key]}'`);
  }
  for (const id of NUMBERS) {
    if (!q.has(id)) continue;
    const raw = q.get(id);
    $(id).value = raw;
    if ($(id).value === "" && raw !== "") $(id).dataset.raw = raw; // the browser dropped it
  }
  for (const [name, row] of page.panel) {
    if (q.has(name) && !ctl[name] && row.input.tagName !== "SELECT") problems.push(...setPanel(row, q.get(name)));
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
  // The parameters of the panel that differ from the preset's, in SI units, every digit kept.
  for (const [name, value] of Object.entries(page.panelSettings || {})) q.set(name, String(value));
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
  set("download-ssv", "disabled", !results);
  set("cursor-live", "disabled", page.cursor === null);
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
    { canvas: "plot-loop", unit: "V", series: [
      { label: "reference", name: "controller.reference", dash: [5, 3] },
      { label: "y_pot", name: "y_pot" }] },
    { canvas: "plot-angles", unit: "deg", series: [
      { label: "motor", name: "theta_motor", factor: DEG },
      { label: "hub", name: "theta_hub", factor: DEG }] },
    { canvas: "plot-tip", unit: "mm", series: [{ label: "w_tip", name: "w_tip", factor: 1e3 }] },
    { canvas: "plot-pressures", unit: "bar", series: pressures },
  ];
}

// The plot's frame within its canvas; the legend is in the band above the frame (T), outside
// the data.
const PLOT_MARGIN = { L: 52, R: 8, T: 24, B: 30 };

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
    for (const w of deflectionOf(run, eta)) if (Math.abs(w) > run.wGrid) run.wGrid = Math.abs(w);
  }
  if (batch.eta) run.eta = batch.eta;
  run.time = batch.time;
  run.stepMs = batch.stepMs;
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

// The time span the plots show: the zoom (page.view) or the whole run.
function viewRange(run) {
  return page.view ? [page.view.x0, page.view.x1] : [0, run.stop];
}

// A trace of `run`'s recorded points over [x0, x1] in `columns` pixel columns (for a zoom, and
// for the previous run overlaid); the cost is the points in the span.
function traceOver(run, spec, x0, x1, columns) {
  const values = run.samples[spec.name];
  if (!values) return null;
  const tr = new Trace(spec, columns, x1 - x0);
  const t = run.samples.t, n = Math.min(t.length, values.length);
  const i0 = Math.max(0, Math.floor(x0 / STEP) - 1), i1 = Math.min(n - 1, Math.ceil(x1 / STEP) + 1);
  for (let i = i0; i <= i1; i++) {
    const x = t.at(i);
    if (x >= x0 && x <= x1) tr.add(x - x0, values.at(i));
  }
  return tr;
}

// The previous run's traces of a plot over the span (kept: that run does not change).
function previousTraces(prev, p, x0, x1, columns) {
  const key = `${p.canvas.id} ${x0} ${x1} ${columns}`;
  prev.overlayCache = prev.overlayCache || new Map();
  if (!prev.overlayCache.has(key)) {
    prev.overlayCache.set(key, p.traces.map((tr) => traceOver(prev, tr, x0, x1, columns)));
  }
  return prev.overlayCache.get(key);
}

// The polyline of a trace: at most four vertices per pixel column (its first, lowest, highest and
// last value), so the extremes are kept and the cost does not grow with the run.
function strokeTrace(ctx, tr, x, py) {
  ctx.beginPath();
  let started = false;
  for (let c = 0; c <= tr.columns; c++) {
    if (!tr.count[c]) continue;
    const first = tr.first[c], min = tr.min[c], max = tr.max[c], last = tr.last[c];
    if (!started) { ctx.moveTo(x + c, py(first)); started = true; }
    for (const v of first <= last ? [first, min, max, last] : [first, max, min, last]) ctx.lineTo(x + c, py(v));
  }
  ctx.stroke();
}

// A plot of its traces over the view's span, the previous run's dimmed under them, the legend in
// the band above the frame, the time cursor and a zoom being dragged. What it laid out is kept in
// page.layout[canvas id] (for the hover readout and the tests).
function plot(p, run, prev) {
  const { canvas } = p;
  const ctx = canvas.getContext("2d");
  const W = canvas.width, H = canvas.height;
  const { L, R, T, B } = PLOT_MARGIN;
  const columns = W - L - R;
  const [x0, x1] = viewRange(run);
  const traces = page.view ? p.traces.map((tr) => traceOver(run, tr, x0, x1, columns)) : p.traces;
  const old = prev ? previousTraces(prev, p, x0, x1, columns).filter((tr) => tr && tr.lo <= tr.hi) : [];
  ctx.clearRect(0, 0, W, H);
  let lo = Math.min(...traces.map((tr) => tr.lo), ...old.map((tr) => tr.lo));
  let hi = Math.max(...traces.map((tr) => tr.hi), ...old.map((tr) => tr.hi));
  if (!(hi > lo)) { const c = Number.isFinite(lo) ? lo : 0; lo = c - 1; hi = c + 1; }
  const pad = 0.06 * (hi - lo); lo -= pad; hi += pad;
  const px = (x) => L + columns * (x - x0) / (x1 - x0);
  const py = (y) => T + (H - T - B) * (hi - y) / (hi - lo);
  ctx.font = "11px sans-serif";
  ctx.strokeStyle = "#ccc"; ctx.fillStyle = "#444"; ctx.lineWidth = 1;
  for (const y of ticks(lo, hi, 5)) {
    ctx.beginPath(); ctx.moveTo(L, py(y)); ctx.lineTo(W - R, py(y)); ctx.stroke();
    ctx.textAlign = "right"; ctx.fillText(format(y), L - 4, py(y) + 4);
  }
  for (const x of ticks(x0, x1, 6)) {
    ctx.textAlign = "center"; ctx.fillText(format(x), px(x), H - B + 13);
  }
  ctx.fillText(page.view ? `time [s] (zoomed: double-click for the whole run)` : "time [s]", L + columns / 2, H - 3);
  ctx.strokeStyle = "#888"; ctx.strokeRect(L, T, columns, H - T - B);
  ctx.save();
  ctx.beginPath(); ctx.rect(L, T, columns, H - T - B); ctx.clip();
  // The previous run, dimmed, under this one.
  ctx.globalAlpha = 0.3;
  old.forEach((tr) => {
    ctx.strokeStyle = COLOURS[p.traces.findIndex((t) => t.name === tr.name) % COLOURS.length];
    ctx.lineWidth = 1.5;
    ctx.setLineDash(tr.dash || []);
    strokeTrace(ctx, tr, L, py);
  });
  ctx.globalAlpha = 1;
  traces.forEach((tr, k) => {
    ctx.strokeStyle = COLOURS[k % COLOURS.length];
    ctx.lineWidth = 1.5;
    ctx.setLineDash(tr.dash || []);
    strokeTrace(ctx, tr, L, py);
  });
  ctx.setLineDash([]);
  // The time cursor.
  const cursor = cursorTime(run);
  if (page.cursor !== null && cursor >= x0 && cursor <= x1) {
    ctx.strokeStyle = "#ea580c"; ctx.lineWidth = 1.5;
    ctx.beginPath(); ctx.moveTo(px(cursor), T); ctx.lineTo(px(cursor), H - B); ctx.stroke();
  }
  // A zoom being dragged.
  if (page.drag && page.drag.canvas === canvas && page.drag.t1 !== undefined) {
    const a = px(Math.min(page.drag.t0, page.drag.t1)), b = px(Math.max(page.drag.t0, page.drag.t1));
    ctx.fillStyle = "rgba(37, 99, 235, 0.15)"; ctx.fillRect(a, T, b - a, H - T - B);
  }
  ctx.restore();
  // The legend, in the band above the frame: this run's curves, then the previous run's.
  const legend = [];
  let at = L;
  ctx.textAlign = "left"; ctx.font = "11px sans-serif";
  const entry = (label, colour, dash, alpha) => {
    const w = 18 + ctx.measureText(label).width;
    ctx.globalAlpha = alpha;
    ctx.strokeStyle = colour; ctx.lineWidth = 2; ctx.setLineDash(dash || []);
    ctx.beginPath(); ctx.moveTo(at, 10); ctx.lineTo(at + 14, 10); ctx.stroke(); ctx.setLineDash([]);
    ctx.fillStyle = alpha < 1 ? "#666" : colour; ctx.fillText(label, at + 17, 14);
    ctx.globalAlpha = 1;
    legend.push({ label, x: at, y: 2, w, h: 16 });
    at += w + 12;
  };
  traces.forEach((tr, k) => entry(tr.label, COLOURS[k % COLOURS.length], tr.dash, 1));
  if (old.length) entry(`dimmed: run ${prev.id} (the previous)`, "#888", null, 0.5);
  page.layout[canvas.id] = {
    frame: { x: L, y: T, w: columns, h: H - T - B }, legend, x0, x1, lo, hi,
    overlay: old.length ? prev.id : null,
  };
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

// The time the plate is drawn at: the time cursor's, or the run's latest (following the run).
function cursorTime(run) {
  const last = run.samples.t.last();
  return page.cursor === null ? last : Math.min(page.cursor, last);
}

// The deflection on the grid [m] of the plate's coordinates `eta`: the model's map (from
// Simulation::deflection_map) times them, summed in the model's order.
function deflectionOf(run, eta) {
  const { map } = run.map;
  const n = eta.length;
  const out = new Float64Array(map.length / n);
  for (let k = 0; k < out.length; k++) {
    let w = 0;
    for (let c = 0; c < n; c++) w += map[k * n + c] * eta[c];
    out[k] = w;
  }
  return out;
}

// The plate's coordinates at the time cursor (the nearest kept frame; the last point when the
// cursor follows the run), and the index of the recorded point at that time.
function plateAt(run) {
  const last = run.samples.t.length - 1;
  if (page.cursor === null || !run.frameT.length) return { eta: run.eta, i: last };
  const n = run.map.coordinates.length;
  const j = Math.max(0, Math.min(run.frameT.length - 1, Math.round(page.cursor / (run.plateEvery * STEP))));
  const eta = new Float64Array(n);
  for (let c = 0; c < n; c++) eta[c] = run.frames.at(j * n + c);
  return { eta, i: Math.max(0, Math.min(last, Math.round(run.frameT.at(j) / STEP))) };
}

// The 1-2-5 number at or above x.
function niceAbove(x) {
  const mag = Math.pow(10, Math.floor(Math.log10(x)));
  return [1, 2, 5, 10].map((f) => f * mag).find((v) => v >= x * (1 - 1e-12));
}

// The exaggeration of the drawn deflection: a 1-2-5 number that shows the largest deflection
// of the run so far at about a fifth of the plate's length; it only shrinks during a run. A plate
// at rest (its largest deflection under AT_REST) is drawn as it is: null.
function exaggeration(run, wmax) {
  if (wmax < AT_REST) return null;
  const [a] = run.plate;
  const wanted = 0.2 * a / wmax;
  const mag = Math.pow(10, Math.floor(Math.log10(wanted)));
  const k = [1, 2, 5].map((f) => f * mag).reverse().find((x) => x <= wanted) || mag;
  if (!run.exaggeration || k < run.exaggeration) run.exaggeration = k;
  return run.exaggeration;
}

function drawPlate(run) {
  if (!run.plate || !run.map) return;
  if (run.map.error) {
    $("plate-caption").textContent = run.map.error;
    return;
  }
  if (!run.eta) return;
  const [a, b] = run.plate;
  const [nx, ny] = GRID;
  const { eta, i: at } = plateAt(run);
  const t = run.samples.t.at(at);
  const w = deflectionOf(run, eta);
  const wmaxRun = Math.max(run.wGrid, run.peak.w_tip);
  const rest = wmaxRun < AT_REST;
  const k = exaggeration(run, wmaxRun) || 1;
  const theta = run.samples.theta_hub.at(at);
  const thetaRef = run.samples["controller.reference"].at(at) / run.kPot;

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
  ctx.fillText(`top view at t = ${t.toFixed(3)} s: hub ${format(theta * DEG)} deg, reference ${format(thetaRef * DEG)} deg (dashed)`, 8, 16);
  const exaggerated = rest
    ? `the plate is at rest: its largest deflection in the run is ${format(wmaxRun * 1e3)} mm (under ${AT_REST * 1e6} µm), drawn as it is`
    : `deflection drawn ×${k} (the plate is ${format(a)} m long)`;
  ctx.fillText(exaggerated, 8, 32);

  // Face view: the deflection over the plate on a colour scale fixed for the run (the 1-2-5
  // number at or above its largest deflection so far), its legend on the right.
  const face = $("plate-face"), fx = face.getContext("2d");
  const FW = face.width, FH = face.height;
  fx.clearRect(0, 0, FW, FH);
  const s = Math.min((FW - 130) / a, (FH - 50) / b);
  const x0 = 20, y0 = 30;
  const range = niceAbove(Math.max(wmaxRun, AT_REST));
  let wabs = 0;
  for (const v of w) wabs = Math.max(wabs, Math.abs(v));
  const colour = (v) => {
    const c = Math.round(255 * (1 - Math.min(1, Math.abs(v))));
    return v >= 0 ? `rgb(255,${c},${c})` : `rgb(${c},${c},255)`;
  };
  const cw = s * a / nx, ch = s * b / ny;
  for (let jj = 0; jj < ny; jj++) {
    for (let i = 0; i < nx; i++) {
      fx.fillStyle = colour(w[i + nx * jj] / range);
      fx.fillRect(x0 + i * cw, y0 + (ny - 1 - jj) * ch, cw + 0.5, ch + 0.5);
    }
  }
  fx.strokeStyle = "#333"; fx.strokeRect(x0, y0, s * a, s * b);
  // The colour scale's legend: +range (red) at the top, 0, -range (blue) at the bottom.
  const lx = x0 + s * a + 20, lh = Math.max(60, s * b);
  for (let y = 0; y < lh; y++) {
    fx.fillStyle = colour(1 - 2 * y / (lh - 1));
    fx.fillRect(lx, y0 + y, 14, 1.5);
  }
  fx.strokeRect(lx, y0, 14, lh);
  fx.fillStyle = "#333"; fx.font = "11px sans-serif"; fx.textAlign = "left";
  fx.fillText(`+${format(range * 1e3)} mm`, lx + 18, y0 + 8);
  fx.fillText("0", lx + 18, y0 + lh / 2 + 4);
  fx.fillText(`−${format(range * 1e3)} mm`, lx + 18, y0 + lh);
  fx.font = "11px sans-serif";
  fx.fillText(rest ? "face view (root on the left): the plate is at rest"
    : `face view (root on the left), scale fixed for the run: here up to ${format(wabs * 1e3)} mm`, 8, 16);
  $("plate-caption").textContent =
    `The plate at t = ${t.toFixed(3)} s, from its ${nx}×${ny}-point grid of the modal state`;
  page.plateView = { t, at, exaggeration: rest ? 1 : k, atRest: rest, label: exaggerated, scale: range, wmax: wabs,
    tip: w[(nx - 1) + nx * j] };
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

// The recorded run as plain arrays (for tests and the bench): {samples: {t, NAME...}, inputs,
// forces (F1, F2 of each step in turn, with the shakers)}.
page.recorded = (run = page.run) => {
  if (!run) return { samples: null, inputs: null };
  const samples = {};
  for (const [name, series] of Object.entries(run.samples)) samples[name] = series.array();
  return { samples, inputs: run.inputs.array(), forces: run.forces.array() };
};

// ---------------------------------------------------------------- taking results away

// The run's recorded points as CSV: a header of the names with their units, then one row per
// communication point: the time, the input r set before the step that ended there (empty at
// t = 0), and the recorded outputs (SI units, every digit a double needs).
function csv(run) {
  const unit = (name) => page.model.variable(name).unit || "1";
  const shaken = run.forces.length > 0;
  const forces = shaken ? [`F1 [${unit("F1")}]`, `F2 [${unit("F2")}]`] : [];
  const header = ["time [s]", `r [${unit("r")}]`, ...forces, ...RECORDED.map((n) => `${n} [${unit(n)}]`)];
  const columns = RECORDED.map((n) => run.samples[n]);
  const t = run.samples.t;
  const rows = [header.join(",")];
  for (let i = 0; i < t.length; i++) {
    const row = [t.at(i), i > 0 ? run.inputs.at(i - 1) : ""];
    if (shaken) row.push(i > 0 ? run.forces.at(2 * i - 2) : "", i > 0 ? run.forces.at(2 * i - 1) : "");
    for (const c of columns) row.push(c.at(i));
    rows.push(row.join(","));
  }
  return rows.join("\n") + "\n";
}

// How r drove the run, in words.
function settingsInput(run) {
  return {
    move: "r = 0: the command generator's move (reference.*) drives the loop",
    step: `r steps from 0 to ${run.rStep} V at t = ${run.tStart} s`,
    slider: "r moved by hand: see the CSV's r column",
  }[run.command];
}

// The run's settings as JSON: the preset and the FMU's variables set over it (what `hsp run
// --preset P --set NAME=VALUE` takes), the stop time and communication step, how r was driven,
// and the page's address that runs it again.
function settingsJson(run) {
  const input = settingsInput(run);
  return JSON.stringify({
    model: "HydraulicSlewingPlate", preset: run.request.preset, settings: run.request.settings,
    stop_time: run.stop, step_size: STEP, command: run.command, input_r: input,
    shakers: run.shaker ? `F1 = ${run.shaker.F1} N, F2 = ${run.shaker.F2} N, ` +
      (run.shaker.f > 0 ? `times sin(2 pi ${run.shaker.f} Hz (t - ${run.shaker.tStart} s))` : "constant") +
      ` from t = ${run.shaker.tStart} s: see the CSV's F1, F2 columns` : null,
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

function redraw() {
  page.dirty = true;
  requestFrame();
}

// The time under the pointer on a plot's canvas, or null outside its frame.
function timeAt(canvas, event) {
  const lay = page.layout[canvas.id];
  if (!lay) return null;
  const r = canvas.getBoundingClientRect();
  const f = ((event.clientX - r.left) * canvas.width / r.width - lay.frame.x) / lay.frame.w;
  if (f < 0 || f > 1) return null;
  return lay.x0 + f * (lay.x1 - lay.x0);
}

// Hover: the values of the plot's curves at the recorded point nearest the pointer's time
// (and the previous run's, overlaid); drag: a zoom on that span; click: the time cursor there;
// double-click: the whole run.
function wirePlot(canvas) {
  const box = $("readout");
  canvas.addEventListener("mousemove", (event) => {
    const t = timeAt(canvas, event);
    if (page.drag && page.drag.canvas === canvas && t !== null) {
      page.drag.t1 = t;
      redraw();
    }
    const run = page.run;
    const p = run && run.plots.find((q) => q.canvas === canvas);
    if (t === null || !p || !run.samples.t.length) {
      box.hidden = true;
      return;
    }
    const i = Math.max(0, Math.min(run.samples.t.length - 1, Math.round(t / STEP)));
    const ti = run.samples.t.at(i);
    const values = {};
    const lines = [`t = ${ti.toFixed(3)} s`];
    for (const tr of p.traces) {
      values[tr.label] = run.samples[tr.name].at(i) * tr.factor;
      lines.push(`${tr.label} ${format(values[tr.label])} ${p.unit}`);
    }
    const prev = page.layout[canvas.id] && page.layout[canvas.id].overlay ? run.previous : null;
    const previous = {};
    if (prev && i < prev.samples.t.length) {
      for (const tr of p.traces) {
        if (!prev.samples[tr.name]) continue;
        previous[tr.label] = prev.samples[tr.name].at(i) * tr.factor;
        lines.push(`  run ${prev.id}: ${tr.label} ${format(previous[tr.label])} ${p.unit}`);
      }
    }
    box.textContent = lines.join("\n");
    box.hidden = false;
    box.style.left = `${event.clientX + 14}px`;
    box.style.top = `${event.clientY + 14}px`;
    page.readout = { canvas: canvas.id, i, t: ti, values, previous };
  });
  canvas.addEventListener("mouseleave", () => { box.hidden = true; });
  canvas.addEventListener("mousedown", (event) => {
    const t = timeAt(canvas, event);
    if (t !== null) page.drag = { canvas, t0: t, x: event.clientX };
  });
  window.addEventListener("mouseup", (event) => {
    const drag = page.drag;
    if (!drag || drag.canvas !== canvas) return;
    page.drag = null;
    if (Math.abs(event.clientX - drag.x) > 4 && drag.t1 !== undefined && drag.t1 !== drag.t0) {
      page.view = { x0: Math.min(drag.t0, drag.t1), x1: Math.max(drag.t0, drag.t1) };
    } else if (page.run) {
      page.cursor = Math.max(0, Math.min(drag.t0, page.run.samples.t.last()));
      $("cursor").value = page.cursor;
    }
    syncControls();
    redraw();
  });
  canvas.addEventListener("dblclick", () => {
    page.view = null;
    redraw();
  });
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
