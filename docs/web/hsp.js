// The hydraulic slewing plate in JavaScript: the model and its stiff integrators compiled to
// WebAssembly (hsp.wasm, built from the crate's src/web/ by `hsp web` and `hsp package`), behind a small API.
// A classic script (no modules, no build step), so that a page opened from the disk
// (file://) can use it; it defines the global `HSP` (and module.exports under Node).
//
//   const model = await HSP.load();                  // hsp.wasm beside this script
//   const sim = model.create({preset: "complete", settings: {"torsion_bar.k": 2500}});
//   sim.step(1e-3, {r: 0.1});                        // one communication step, inputs held
//   sim.run(1e-3, "r", [0, 0.1, 0.1], ["y_pot"]);     // several, r before each, y_pot after
//   sim.get(["y_pot", "theta_hub", "w_tip"]);         // -> Float64Array, SI units
//   sim.deflection(11, 5);                           // the plate's deflection on a grid [m]
//   model.parameterSet({preset, settings});          // the settings as an SSP 1.0 .ssv
//   sim.messages();  sim.reset();  sim.free();
//
// HSP.script is this script's own text, to run it in a Web Worker made from a Blob (a page opened
// from the disk cannot start a worker from a file); HSP.moduleBytes() fetches the module's bytes
// to hand to it (see docs/web/worker.js).
//
// Every call that fails throws an Error whose message is the FMU's own (it names the culprit);
// a failed step keeps the last good state.
(function hspScript(global) {
  "use strict";

  const encoder = new TextEncoder();
  const decoder = new TextDecoder();

  // Where this script came from: hsp.wasm is looked for beside it.
  const scriptUrl = typeof document !== "undefined" && document.currentScript
    ? document.currentScript.src : null;

  function base64Bytes(text) {
    if (typeof Buffer !== "undefined") return new Uint8Array(Buffer.from(text, "base64"));
    const raw = atob(text);
    const bytes = new Uint8Array(raw.length);
    for (let i = 0; i < raw.length; i++) bytes[i] = raw.charCodeAt(i);
    return bytes;
  }

  function loadScript(url) {
    return new Promise((resolve, reject) => {
      const s = document.createElement("script");
      s.src = url;
      s.onload = resolve;
      s.onerror = () => reject(new Error("could not load " + url));
      document.head.appendChild(s);
    });
  }

  // The module's bytes: fetched over HTTP(S); from a page opened from the disk, where browsers
  // refuse fetch(), from hsp.wasm.js (the same bytes as base64 in a script).
  async function wasmBytes(url) {
    if (url.startsWith("http:") || url.startsWith("https:")) {
      const response = await fetch(url);
      if (!response.ok) throw new Error(`could not load ${url}: HTTP ${response.status}`);
      return await response.arrayBuffer();
    }
    if (typeof global.HSP_WASM_BASE64 !== "string") await loadScript(url + ".js");
    return base64Bytes(global.HSP_WASM_BASE64);
  }

  class Model {
    constructor(instance) {
      this.exports = instance.exports;
      this.aborted = null;
      this.variables = JSON.parse(this.callText(() => this.exports.hsp_variables()));
      this.presets = JSON.parse(this.callText(() => this.exports.hsp_presets()));
      this.byName = new Map(this.variables.map((v) => [v.name, v]));
    }

    // Runs a call into the module; a trap (a panic: WebAssembly aborts) leaves the module
    // unusable and is reported with the panic's message.
    guard(f) {
      if (this.aborted) throw new Error("the model aborted earlier: " + this.aborted);
      try {
        return f();
      } catch (e) {
        if (e instanceof WebAssembly.RuntimeError) {
          let why = "";
          try { why = this.text(this.exports.hsp_panic_message()); } catch (_) { /* dead */ }
          this.aborted = why || String(e);
          throw new Error("the model aborted: " + this.aborted);
        }
        throw e;
      }
    }

    text(len) {
      const ptr = this.exports.hsp_text_ptr();
      return decoder.decode(new Uint8Array(this.exports.memory.buffer, ptr, len));
    }

    callText(f) {
      return this.guard(() => this.text(f()));
    }

    // Throws the module's message when a status is an error.
    check(status) {
      if (status >= 2) throw new Error(this.text(this.exports.hsp_text_len()));
      return status;
    }

    // A copy of `bytes` in the module's memory: [ptr, len] (free with hsp_dealloc).
    put(bytes) {
      const ptr = this.exports.hsp_alloc(bytes.length);
      new Uint8Array(this.exports.memory.buffer, ptr, bytes.length).set(bytes);
      return [ptr, bytes.length];
    }

    variable(name) {
      const v = this.byName.get(name);
      if (!v) throw new Error(`unknown variable '${name}'`);
      return v;
    }

    // A simulation of `preset` (a name from model.presets; default: the FMU's defaults) with
    // `settings` ({NAME: value}) over it, initialised at t = 0.
    create({ preset = "", settings = {} } = {}) {
      const [ptr, len] = this.put(encoder.encode(JSON.stringify({ preset, settings })));
      const handle = this.guard(() => {
        try {
          return this.exports.hsp_new(ptr, len);
        } finally {
          this.exports.hsp_dealloc(ptr, len);
        }
      });
      if (handle === 0) throw new Error(this.text(this.exports.hsp_text_len()));
      return new Simulation(this, handle);
    }

    // The settings of a run as an SSP 1.0 parameter set (.ssv text) the FMU applies alone (`hsp
    // run --ssv`, fmpy): the preset's settings with `settings` over them, typed as the FMU's
    // variables (the library's writer, the one `hsp ssp` and `hsp identify --out` use).
    parameterSet({ preset = "", settings = {}, name, description } = {}) {
      const [ptr, len] = this.put(encoder.encode(JSON.stringify({ preset, settings, name, description })));
      try {
        this.guard(() => this.check(this.exports.hsp_parameter_set(ptr, len)));
      } finally {
        this.exports.hsp_dealloc(ptr, len);
      }
      return this.text(this.exports.hsp_text_len());
    }
  }

  class Simulation {
    constructor(model, handle) {
      this.model = model;
      this.handle = handle;
      this.buffers = { vrs: [0, 0], out: [0, 0], in: [0, 0], done: [0, 0] };
    }

    get time() {
      return this.model.guard(() => this.model.exports.hsp_time(this.handle));
    }

    // Scratch memory in the module of at least `bytes`, reused from call to call.
    scratch(which, bytes) {
      const b = this.buffers[which];
      if (b[1] < bytes) {
        if (b[0]) this.model.exports.hsp_dealloc(b[0], b[1]);
        this.buffers[which] = [this.model.exports.hsp_alloc(bytes), bytes];
      }
      return this.buffers[which][0];
    }

    // Sets inputs or tunable parameters: {NAME: value}.
    set(values) {
      const m = this.model;
      for (const [name, value] of Object.entries(values)) {
        const vr = m.variable(name).valueReference;
        m.guard(() => m.check(m.exports.hsp_set_real(this.handle, vr, value)));
      }
    }

    // One communication step of h seconds with `inputs` ({NAME: value}) set first and held.
    // Returns true when the step logged a warning (see messages()).
    step(h, inputs) {
      if (inputs) this.set(inputs);
      const m = this.model;
      return m.guard(() => m.check(m.exports.hsp_step(this.handle, h))) === 1;
    }

    // Runs inputs.length communication steps of h seconds in one call: the Real input `input`
    // (a name) set to inputs[k] before step k, the Reals `names` read after every step. Returns
    // {values: Float64Array of steps rows of names.length values, steps, warned, error}: on a
    // failure `error` holds the message and the rows of the steps done before it are good.
    run(h, input, inputs, names) {
      const m = this.model;
      const vrs = names.map((n) => (typeof n === "number" ? n : m.variable(n).valueReference));
      const n = inputs.length, w = vrs.length;
      const pin = this.scratch("in", 8 * n);
      const pv = this.scratch("vrs", 4 * w);
      const po = this.scratch("out", 8 * n * w);
      const pd = this.scratch("done", 4);
      // Views made after every allocation: a growing memory detaches the older ones.
      const memory = m.exports.memory.buffer;
      new Float64Array(memory, pin, n).set(inputs);
      new Uint32Array(memory, pv, w).set(vrs);
      const status = m.guard(() => m.exports.hsp_run(this.handle, h, m.variable(input).valueReference,
        pin, n, pv, w, po, pd));
      const steps = new Uint32Array(m.exports.memory.buffer, pd, 1)[0];
      const values = new Float64Array(m.exports.memory.buffer, po, steps * w).slice();
      const error = status >= 2 ? m.text(m.exports.hsp_text_len()) : null;
      return { values, steps, warned: status === 1, error };
    }

    // The values of the Reals `names` (an array of names or of value references) [SI].
    get(names) {
      const m = this.model;
      const vrs = names.map((n) => (typeof n === "number" ? n : m.variable(n).valueReference));
      const n = vrs.length;
      const pv = this.scratch("vrs", 4 * n);
      const po = this.scratch("out", 8 * n);
      new Uint32Array(m.exports.memory.buffer, pv, n).set(vrs);
      m.guard(() => m.check(m.exports.hsp_get_reals(this.handle, pv, n, po)));
      return new Float64Array(m.exports.memory.buffer, po, n).slice();
    }

    // The plate's deflection relative to the hub [m] on an nx x ny grid (x from the root to the
    // tip, y across), row by row in y: out[i + nx j].
    deflection(nx, ny) {
      const m = this.model;
      const po = this.scratch("out", 8 * nx * ny);
      m.guard(() => m.check(m.exports.hsp_deflection(this.handle, nx, ny, po)));
      return new Float64Array(m.exports.memory.buffer, po, nx * ny).slice();
    }

    // What deflection() multiplies, to draw the plate at a time recorded earlier:
    // {coordinates: the value references of the plate's coordinates (n), map: Float64Array of
    // nx*ny rows of n, row i + nx j times the coordinates = the deflection there [m]}.
    deflectionMap(nx, ny) {
      const m = this.model;
      m.guard(() => m.check(m.exports.hsp_deflection_map(this.handle, nx, ny)));
      const { coordinates, map } = JSON.parse(m.text(m.exports.hsp_text_len()));
      return { coordinates, map: Float64Array.from(map) };
    }

    // The plate's length a and width b [m].
    plateSize() {
      const t = this.model.callText(() => this.model.exports.hsp_plate_size(this.handle));
      return t ? JSON.parse(t) : null;
    }

    // The validity monitors: [{variable, limit}] (the output and the largest magnitude it may
    // reach within the model's range).
    monitors() {
      return JSON.parse(this.model.callText(() => this.model.exports.hsp_monitors(this.handle)));
    }

    // The messages logged since the last call: [{status, category, message}].
    messages() {
      return JSON.parse(this.model.callText(() => this.model.exports.hsp_messages(this.handle)));
    }

    // Back to t = 0 with the same preset and settings.
    reset() {
      const m = this.model;
      m.guard(() => m.check(m.exports.hsp_reset(this.handle)));
    }

    free() {
      if (this.handle) {
        const m = this.model;
        for (const b of Object.values(this.buffers)) if (b[0]) m.exports.hsp_dealloc(b[0], b[1]);
        m.guard(() => m.exports.hsp_free(this.handle));
        this.handle = 0;
      }
    }
  }

  // The module's bytes: `source` as in load().
  async function moduleBytes(source) {
    if (source !== undefined && typeof source !== "string") return source;
    const url = source ?? (scriptUrl ? new URL("hsp.wasm", scriptUrl).href : "hsp.wasm");
    return wasmBytes(url);
  }

  // Loads the model: `source` is the .wasm's URL (default: hsp.wasm beside this script) or its
  // bytes (an ArrayBuffer or Uint8Array).
  async function load(source) {
    const bytes = await moduleBytes(source);
    const { instance } = await WebAssembly.instantiate(bytes, {});
    return new Model(instance);
  }

  // This script's text, run as it is here (defining the global HSP).
  const script = `(${hspScript})(globalThis);\n`;

  const HSP = { load, moduleBytes, script, Model, Simulation };
  if (typeof module !== "undefined" && module.exports) module.exports = HSP;
  else global.HSP = HSP;
})(typeof globalThis !== "undefined" ? globalThis : this);
