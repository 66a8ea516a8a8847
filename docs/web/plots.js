// The plots: each curve kept per pixel column (Trace), drawn over the run or a zoom with the
// previous run dimmed under it, its legend, ticks and time cursor; the hover readout, the zoom
// and the time cursor set on a plot (wirePlot).
// A classic script of the page (no modules: a page opened from the disk cannot load them); it
// shares the page's globals, and index.html loads it before page.js, which defines the shared
// state (`page`, `$`, the constants) and starts the page.
"use strict";

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

// The time the plate is drawn at: the time cursor's, or the run's latest (following the run).
function cursorTime(run) {
  const last = run.samples.t.last();
  return page.cursor === null ? last : Math.min(page.cursor, last);
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
