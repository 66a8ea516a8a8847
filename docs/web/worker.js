// The page's simulation thread: the model (hsp.js over hsp.wasm) stepped in a Web Worker, so that
// the page's own thread only draws and answers its controls at once, however long the run.
//
// A classic script defining the function hspWorker; page.js starts the worker from a Blob made of
// hsp.js's text (HSP.script) and this function's (a page opened from the disk cannot start a
// worker from a file, but it can from a Blob), and hands it the module's bytes. The messages:
//
//   page -> worker  {type: "load", bytes}
//                   {type: "start", id, request, names, step, stop, grid, command, rStep, tStart,
//                    r, speed, shaker, plateEvery}  a new run (the one before it is dropped);
//                                                shaker: null or {F1, F2, f, tStart} (the forces)
//                   {type: "ssv", id, request, name, description}  the settings as an .ssv
//                   {type: "pause"}, {type: "resume"}, {type: "stop"}
//                   {type: "speed", speed}      "realtime" or "fast"
//                   {type: "r", value}          the slider's r, for the coming steps
//   worker -> page  {type: "ready", variables, presets}
//                   {type: "started", id, kPot, monitors, plate, map, batch}
//                                                map: deflectionMap(grid) or {error}
//                   {type: "ssv", id, text, error}
//                   {type: "data", id, batch}
//                   {type: "paused", id, time}  the run is stopped at `time`
//                   {type: "refused", id, message}
//                   {type: "fatal", message}    the module could not be loaded, or it aborted
//
// A batch is what the run did since the last one: t, the input r set before each step (inputs),
// the recorded outputs after each step (values, row by row), the messages logged, the plate's
// coordinates every plateEvery steps (frames, with their times frameT) and at the last point
// (eta), the shakers' forces F1, F2 of each step when they drive the run (forces), and the
// run's state (time, stepMs, done, failed).
function hspWorker(scope) {
  "use strict";

  const CHUNK = 200; // communication steps per call into the module
  const SLICE_MS = 10; // stepping between two looks at the page's messages
  const TICK_MS = 8; // at real time: the pause between two slices

  let model = null;
  let sim = null;
  let run = null;
  let scheduled = false;

  const post = (message, transfer) => scope.postMessage(message, transfer || []);

  // Running as fast as possible, the slices follow each other as tasks posted through a
  // MessageChannel (a timer would wait), so that the page's messages get their turn between two.
  const channel = new MessageChannel();
  channel.port1.onmessage = tick;

  function schedule() {
    if (!run || run.pausedAt || run.done || scheduled) return;
    scheduled = true;
    if (run.speed === "fast") channel.port2.postMessage(0);
    else setTimeout(tick, TICK_MS);
  }

  function tick() {
    scheduled = false;
    if (!run || run.pausedAt || run.done) return;
    if (!run.stepping) {
      run.stepping = true;
      run.started = performance.now();
    }
    let until = run.stop;
    if (run.speed !== "fast") {
      until = Math.min(run.stop, (performance.now() - run.started - run.paused) / 1000);
    }
    try {
      advance(until, SLICE_MS);
    } catch (e) {
      // The module aborted (a panic): the run ends with its message.
      run.failed = e.message;
      run.done = true;
    }
    flush();
    schedule();
  }

  function newBatch() {
    return { t: [], inputs: [], values: [], messages: [], frames: [], frameT: [], forces: [], eta: null };
  }

  function concat(chunks) {
    const out = new Float64Array(chunks.reduce((n, c) => n + c.length, 0));
    let at = 0;
    for (const c of chunks) {
      out.set(c, at);
      at += c.length;
    }
    return out;
  }

  // The batch as a message's payload (its arrays transferred, not copied).
  function payload(batch) {
    const out = {
      t: concat(batch.t), inputs: concat(batch.inputs), values: concat(batch.values),
      frames: concat(batch.frames), frameT: Float64Array.from(batch.frameT),
      forces: concat(batch.forces), eta: batch.eta,
      messages: batch.messages, time: run.time, stepMs: run.stepMs, done: run.done,
      failed: run.failed,
    };
    const transfer = [out.t.buffer, out.inputs.buffer, out.values.buffer, out.frames.buffer,
      out.frameT.buffer, out.forces.buffer];
    return [out, transfer];
  }

  function flush() {
    const [batch, transfer] = payload(run.batch);
    run.batch = newBatch();
    post({ type: "data", id: run.id, batch }, transfer);
  }

  // The input r of the coming step from time t.
  function reference(t) {
    if (run.command === "slider") return run.r;
    if (run.command === "step") return t >= run.tStart - 1e-12 ? run.rStep : 0;
    return 0;
  }

  // The shakers' forces [F1, F2] on the step from time t: F_i sin(2 pi f (t - tStart)) from
  // tStart (f = 0: a constant force from tStart).
  function forces(t) {
    const s = run.shaker;
    if (t < s.tStart - 1e-12) return [0, 0];
    const wave = s.f > 0 ? Math.sin(2 * Math.PI * s.f * (t - s.tStart)) : 1;
    return [s.F1 * wave, s.F2 * wave];
  }

  // The plate's coordinates now into the batch: a kept frame (at time t) or only the latest.
  function plateNow(b, t) {
    const eta = sim.get(run.coordinates);
    if (t !== null) {
      b.frames.push(eta);
      b.frameT.push(t);
    }
    b.eta = eta;
  }

  // Steps until the run's time reaches `until` or `budgetMs` of wall time is spent, CHUNK steps
  // per call into the module (r for each step computed before, the outputs of each read after).
  function advance(until, budgetMs) {
    const t0 = performance.now();
    const b = run.batch;
    while (run.k < run.steps && run.k * run.step < until - 1e-12) {
      const wanted = Math.ceil((until - run.k * run.step) / run.step - 1e-9);
      // A call ends at the next kept frame of the plate (its coordinates are read there alone,
      // not after every step); with the shakers on, one step per call: their forces are set
      // before each.
      const frame = run.coordinates.length ? run.plateEvery - (run.k % run.plateEvery) : CHUNK;
      const n = run.shaker ? 1 : Math.max(1, Math.min(CHUNK, run.steps - run.k, wanted, frame));
      if (run.shaker) {
        const f = forces(run.time);
        sim.set({ F1: f[0], F2: f[1] });
        b.forces.push(Float64Array.from(f));
      }
      const inputs = new Float64Array(n);
      const times = new Float64Array(n);
      let t = run.time;
      for (let i = 0; i < n; i++) {
        inputs[i] = reference(t);
        t += run.step; // the FMU's own time after the step (the same sum)
        times[i] = t;
      }
      const done = sim.run(run.step, "r", inputs, run.read);
      if (done.steps > 0) {
        b.t.push(times.subarray(0, done.steps));
        b.inputs.push(inputs.subarray(0, done.steps));
        b.values.push(done.values);
        run.time = times[done.steps - 1];
      }
      run.k += done.steps;
      if (done.steps > 0 && run.coordinates.length && run.k % run.plateEvery === 0) {
        plateNow(b, run.time);
      }
      if (done.warned || done.error) b.messages.push(...sim.messages());
      if (done.error) {
        run.failed = done.error;
        break;
      }
      if (performance.now() - t0 > budgetMs) break;
    }
    // The plate at the latest point, if that was no kept frame (the live drawing).
    if (run.coordinates.length && run.k % run.plateEvery !== 0) plateNow(b, null);
    run.stepMs += performance.now() - t0;
    if (run.k >= run.steps || run.failed) {
      run.done = true;
      b.messages.push(...sim.messages());
    }
  }

  function drop() {
    if (sim) sim.free();
    sim = null;
    run = null;
  }

  const handlers = {
    async load(m) {
      try {
        model = await HSP.load(m.bytes);
        post({ type: "ready", variables: model.variables, presets: model.presets });
      } catch (e) {
        post({ type: "fatal", message: e.message });
      }
    },
    start(m) {
      drop();
      try {
        sim = model.create(m.request);
        const [kPot] = sim.get(["controller.k_pot"]);
        // The plate's coordinates are read with the outputs at every step, to draw the plate at
        // any recorded time (the map times them); a plate the variables do not show is said so.
        let map;
        try {
          map = sim.deflectionMap(m.grid[0], m.grid[1]);
        } catch (e) {
          map = { error: e.message, coordinates: [] };
        }
        run = {
          ...m, kPot, rStep: m.command === "step" ? kPot * m.angle : 0,
          steps: Math.round(m.stop / m.step), k: 0, time: sim.time, stepMs: 0, paused: 0,
          pausedAt: 0, stepping: false, done: false, failed: null, batch: newBatch(),
          coordinates: map.coordinates,
          read: m.names.map((name) => model.variable(name).valueReference),
        };
        // The initial point.
        run.batch.t.push(new Float64Array([run.time]));
        run.batch.values.push(sim.get(run.names));
        if (run.coordinates.length) {
          const eta = sim.get(run.coordinates);
          run.batch.frames.push(eta);
          run.batch.frameT.push(run.time);
          run.batch.eta = eta.slice();
        }
        const [batch, transfer] = payload(run.batch);
        run.batch = newBatch();
        post({ type: "started", id: run.id, kPot, rStep: run.rStep, monitors: sim.monitors(),
          plate: sim.plateSize(), map, batch }, transfer);
      } catch (e) {
        const id = m.id;
        drop();
        post({ type: "refused", id, message: e.message });
        return;
      }
      schedule();
    },
    ssv(m) {
      try {
        post({ type: "ssv", id: m.id, text: model.parameterSet(m) });
      } catch (e) {
        post({ type: "ssv", id: m.id, error: e.message });
      }
    },
    pause() {
      if (!run || run.done || run.pausedAt) return;
      run.pausedAt = performance.now();
      post({ type: "paused", id: run.id, time: run.time });
    },
    resume() {
      if (!run || !run.pausedAt) return;
      if (run.stepping) run.paused += performance.now() - run.pausedAt;
      run.pausedAt = 0;
      schedule();
    },
    stop() {
      drop();
    },
    speed(m) {
      if (!run) return;
      run.speed = m.speed;
      schedule();
    },
    r(m) {
      if (run) run.r = m.value;
    },
  };

  scope.onmessage = (e) => {
    try {
      handlers[e.data.type](e.data);
    } catch (err) {
      post({ type: "fatal", message: err.message });
    }
  };
}
