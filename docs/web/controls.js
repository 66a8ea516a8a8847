// The controls: the form on the left, the parameter panel (every parameter of the model, as
// its modelDescription.xml declares it) and the address (the settings in the page's URL); they
// decide the settings of a run (readControls) and follow the run's state (syncControls).
// A classic script of the page (no modules: a page opened from the disk cannot load them); it
// shares the page's globals, and index.html loads it before page.js, which defines the shared
// state (`page`, `$`, the constants) and starts the page.
"use strict";

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
