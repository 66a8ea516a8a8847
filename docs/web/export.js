// Taking results away: the run as CSV, its settings as JSON, a file downloaded, and the link to
// the settings copied. (The settings as an SSP parameter set, .ssv, are written by the worker.)
// A classic script of the page (no modules: a page opened from the disk cannot load them); it
// shares the page's globals, and index.html loads it before page.js, which defines the shared
// state (`page`, `$`, the constants) and starts the page.
"use strict";

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
