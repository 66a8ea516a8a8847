// The plate: its deflection on the grid from the model's modal coordinates, drawn at the time
// cursor in a top view (the arm bent, exaggerated) and a face view (the deflection's colour map).
// A classic script of the page (no modules: a page opened from the disk cannot load them); it
// shares the page's globals, and index.html loads it before page.js, which defines the shared
// state (`page`, `$`, the constants) and starts the page.
"use strict";

// A plate whose largest deflection in the run stays below this [m] is at rest: drawn as it is.
const AT_REST = 1e-6;

// The deflection [m] at the grid's point k of the plate's coordinates `eta`: row k of the model's
// map (from Simulation::deflection_map) times them, summed in the model's order.
function deflectionAt(map, eta, k) {
  const n = eta.length;
  let w = 0;
  for (let c = 0; c < n; c++) w += map[k * n + c] * eta[c];
  return w;
}

// The deflection on the grid [m] of the plate's coordinates `eta`.
function deflectionOf(run, eta) {
  const { map } = run.map;
  const out = new Float64Array(map.length / eta.length);
  for (let k = 0; k < out.length; k++) out[k] = deflectionAt(map, eta, k);
  return out;
}

// The largest |deflection| on the grid [m] of the coordinates `eta` (nothing allocated: the
// page takes it of every frame it receives, for the face view's fixed colour scale).
function largestDeflection(run, eta) {
  const { map } = run.map;
  let largest = 0;
  for (let k = 0, points = map.length / eta.length; k < points; k++) {
    largest = Math.max(largest, Math.abs(deflectionAt(map, eta, k)));
  }
  return largest;
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
