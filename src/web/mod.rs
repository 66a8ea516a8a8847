//! The browser build: the model and its integrators behind a small API for JavaScript, compiled to
//! `wasm32-unknown-unknown` (`hsp web` and `hsp package` build it beside the interactive page, `docs/web/`).
//!
//! It is a thin layer over the version-neutral FMU core ([`crate::fmu`]), as the FMI 2.0 and
//! 3.0 layers are: a [`Simulation`] is a co-simulation [`Instance`] of the assembled model, so the
//! browser runs exactly what the FMU runs, with the same checks of every setting, the same
//! validity monitors, the same refusal of non-finite results and the same messages. What it adds
//! is what a page needs and FMI has no call for: presets and settings by name, the messages kept
//! for the page to show, and the plate's deflected shape on a grid ([`Simulation::deflection`]).
//!
//! - `mod.rs` (this file): [`Simulation`], plain Rust, tested natively (`tests/web.rs`).
//! - `wasm.rs`: the `extern "C"` functions the `.wasm` exports (compiled only for WebAssembly).
//!
//! The JavaScript side is `docs/web/hsp.js` (the API) and `docs/web/index.html` with its scripts (the page, started by `page.js`).

use std::cell::RefCell;
use std::rc::Rc;

use nalgebra::DMatrix;

use crate::fmu::instance::{Instance, Vocabulary};
use crate::fmu::logging::{LogSink, Logger};
use crate::fmu::{FmuModel, Interface, Kind, Status, Value};
use crate::fragments::plate::PlateModel;
use crate::fragments::validity::Monitor;
use crate::model::parameters::parse_setting;
use crate::model::presets;
use crate::model::variables::{position, SHOWN, VARIABLES};
use crate::model::HydraulicSlewingPlate;

#[cfg(target_family = "wasm")]
pub mod wasm;

/// How the core names things in its messages, for the browser (there is no FMI function to
/// name: messages start with the API call).
static VOCABULARY: Vocabulary = Vocabulary {
    fatal: "fatal",
    free_instance: "free",
    fmu_state: "state",
    can_get_and_set_fmu_state: "canGetAndSetFMUState",
};

/// One message of the model or the core (a validity monitor tripping, a refused setting, a
/// discarded step).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Message {
    /// `"ok"`, `"warning"`, `"discard"`, `"error"` or `"fatal"`.
    pub status: &'static str,
    /// The log category (`logStatusWarning`, ...).
    pub category: String,
    pub message: String,
}

fn status_name(status: Status) -> &'static str {
    match status {
        Status::Ok => "ok",
        Status::Warning => "warning",
        Status::Discard => "discard",
        Status::Error => "error",
        Status::Fatal => "fatal",
    }
}

/// The messages of one simulation, shared between its logger and the simulation.
#[derive(Clone, Default)]
struct Inbox(Rc<RefCell<Vec<Message>>>);

impl LogSink for Inbox {
    fn send(&self, status: Status, category: &str, message: &str) {
        self.0.borrow_mut().push(Message {
            status: status_name(status),
            category: category.to_string(),
            message: message.to_string(),
        });
    }
}

/// The plate's deflection on a grid: per grid point, its displacement per unit plate coordinate.
struct DeflectionGrid {
    nx: usize,
    ny: usize,
    /// `(nx ny) x n_plate`: row `i + nx j` is the point `(a i / (nx - 1), b j / (ny - 1))`.
    map: DMatrix<f64>,
    /// The value references of the plate's coordinates (`x.plate.C[k].q`), read to draw it.
    coordinates: Vec<u32>,
    /// Their values (allocated once).
    eta: Vec<f64>,
}

/// One simulation: a co-simulation instance of the model, set up from a preset and settings,
/// initialised at t = 0 and stepped by communication steps.
///
/// Every call that fails returns the core's message, which names the culprit. As in FMI, a
/// refused call (a step size that is not positive, a fixed parameter set during the run) leaves
/// the instance in the error state, with the time and values of its last good step; only
/// [`Simulation::reset`] goes on from there. A step the model cannot complete is discarded and
/// keeps the last good state too.
pub struct Simulation {
    instance: Instance<HydraulicSlewingPlate>,
    inbox: Inbox,
    /// The preset and settings it was made from, for [`Simulation::reset`].
    preset: String,
    settings: Vec<(String, String)>,
    grid: Option<DeflectionGrid>,
}

/// The value reference of the variable `name`.
pub fn value_reference(name: &str) -> Option<u32> {
    position(name).map(|i| VARIABLES[i].value_reference)
}

impl Simulation {
    /// A simulation of `preset` (a name from [`presets::PRESETS`]; empty: the FMU's defaults)
    /// with `settings` (`NAME`, `VALUE` as text, as `hsp run --set`) applied over it, initialised
    /// at t = 0. The error names the culprit setting.
    pub fn new(preset: &str, settings: &[(String, String)]) -> Result<Self, String> {
        let inbox = Inbox::default();
        let logger = Logger::new(Box::new(inbox.clone()), false);
        let instance = Instance::new(
            "create",
            &VOCABULARY,
            "browser",
            HydraulicSlewingPlate::GUID,
            None,
            logger,
            Interface::CoSimulation,
        )
        .map_err(|(_, message)| message)?;
        let mut sim = Simulation {
            instance,
            inbox,
            preset: preset.to_string(),
            settings: settings.to_vec(),
            grid: None,
        };
        sim.start()?;
        Ok(sim)
    }

    /// Applies the preset and settings to the fresh instance and initialises it.
    fn start(&mut self) -> Result<(), String> {
        let mut all: Vec<(String, String)> = Vec::new();
        if !self.preset.is_empty() {
            let p = presets::preset(&self.preset)?;
            all.extend(
                p.settings
                    .iter()
                    .map(|(n, v)| (n.to_string(), v.to_string())),
            );
        }
        all.extend(self.settings.iter().cloned());
        for (name, text) in &all {
            let (index, value) = parse_setting(name, text)?;
            let var = &VARIABLES[index];
            let type_name = var.kind.value_type();
            self.call("create", |i| {
                i.set(type_name, &[var.value_reference], vec![value])
            })?;
        }
        self.call("create", |i| i.setup_experiment(None, 0.0, None))?;
        self.call("create", |i| i.enter_initialization_mode())?;
        self.call("create", |i| i.exit_initialization_mode())?;
        self.grid = None;
        Ok(())
    }

    /// Runs one core call as `function`; a status worse than a warning becomes the error with
    /// the message the core logged.
    fn call(
        &mut self,
        function: &'static str,
        f: impl FnOnce(&mut Instance<HydraulicSlewingPlate>) -> Status,
    ) -> Result<Status, String> {
        self.instance.begin_call(function);
        let before = self.inbox.0.borrow().len();
        let status = f(&mut self.instance);
        if status <= Status::Warning {
            return Ok(status);
        }
        let messages = self.inbox.0.borrow();
        Err(messages[before..]
            .iter()
            .rev()
            .find(|m| m.status != "ok" && m.status != "warning")
            .map(|m| m.message.clone())
            .unwrap_or_else(|| format!("{function}: {}", status_name(status))))
    }

    /// Back to t = 0 with the same preset and settings.
    pub fn reset(&mut self) -> Result<(), String> {
        self.call("reset", |i| i.reset())?;
        self.start()
    }

    /// The simulated time \[s\].
    pub fn time(&self) -> f64 {
        self.instance.time()
    }

    /// Sets an input (`r`, `e_in`, `F1`, `F2`) or a tunable parameter by value reference, with
    /// the FMU's checks.
    pub fn set_real(&mut self, value_reference: u32, value: f64) -> Result<(), String> {
        self.call("set", |i| {
            i.set("Real", &[value_reference], vec![Value::Real(value)])
        })
        .map(|_| ())
    }

    /// One communication step of `h` seconds with the inputs held. `Ok(true)` when it logged a
    /// warning (a validity monitor tripped; the step itself is fine, as FMI's `OK` with a
    /// warning message). A discarded step keeps the last good state.
    pub fn step(&mut self, h: f64) -> Result<bool, String> {
        let t = self.instance.time();
        let before = self.inbox.0.borrow().len();
        self.call("step", |i| i.do_step(t, h))?;
        let warned = self.inbox.0.borrow()[before..]
            .iter()
            .any(|m| m.status == "warning");
        Ok(warned)
    }

    /// Runs `inputs.len()` communication steps of `h` seconds, the Real input `input` set to
    /// `inputs[k]` before step `k`, and reads the Reals `value_references` after each step into
    /// row `k` of `out` (`inputs.len()` rows of `value_references.len()` values): what the page
    /// does at every point, in one call. Returns the number of steps done (rows filled) and how
    /// the run ended: `Ok(true)` when a step logged a warning; on an error the rows before it
    /// are good.
    pub fn run(
        &mut self,
        h: f64,
        input: u32,
        inputs: &[f64],
        value_references: &[u32],
        out: &mut [f64],
    ) -> (usize, Result<bool, String>) {
        let width = value_references.len();
        if out.len() != inputs.len() * width {
            return (
                0,
                Err(format!(
                    "run: {} steps of {width} values need {} places, got {}",
                    inputs.len(),
                    inputs.len() * width,
                    out.len()
                )),
            );
        }
        let mut warned = false;
        for (k, (&u, row)) in inputs
            .iter()
            .zip(out.chunks_exact_mut(width.max(1)))
            .enumerate()
        {
            let step = self
                .set_real(input, u)
                .and_then(|_| self.step(h))
                .and_then(|w| {
                    self.get_reals(value_references, &mut row[..width])
                        .map(|_| w)
                });
            match step {
                Ok(w) => warned |= w,
                Err(e) => return (k, Err(e)),
            }
        }
        (inputs.len(), Ok(warned))
    }

    /// Reads Reals by value reference into `out`.
    pub fn get_reals(&mut self, value_references: &[u32], out: &mut [f64]) -> Result<(), String> {
        if value_references.len() != out.len() {
            return Err(format!(
                "get: {} value references but room for {} values",
                value_references.len(),
                out.len()
            ));
        }
        let real = |v: &Value| match v {
            Value::Real(x) => *x,
            _ => f64::NAN,
        };
        self.call("get", |i| i.get("Real", value_references, out, real))
            .map(|_| ())
    }

    /// The messages logged since the last call (and forgets them).
    pub fn take_messages(&mut self) -> Vec<Message> {
        std::mem::take(&mut *self.inbox.0.borrow_mut())
    }

    /// The plate's size `(a, b)` \[m\].
    pub fn plate_size(&self) -> Option<(f64, f64)> {
        let p = self.instance.model().parameters()?;
        Some((p.plate.a, p.plate.b))
    }

    /// The validity monitors of the built model: each one's output variable and the largest
    /// magnitude it may reach within the model's range (the FMU warns once when it goes beyond).
    pub fn monitors(&self) -> Vec<(&'static str, f64)> {
        let Some(p) = self.instance.model().parameters() else {
            return Vec::new();
        };
        Monitor::ALL
            .iter()
            .map(|m| (m.variable(), m.limit(&p.limits)))
            .collect()
    }

    /// The plate's deflection relative to the hub \[m\] on an `nx` x `ny` grid over the plate
    /// (`x` along the arm from the root, `y` across it), row by row in `y`: `out[i + nx j]` at
    /// `(a i / (nx - 1), b j / (ny - 1))`. From the plate coordinates at the current time and the
    /// formulation's shape functions; the hub's rigid rotation is left out.
    pub fn deflection(&mut self, nx: usize, ny: usize, out: &mut [f64]) -> Result<(), String> {
        if nx < 2 || ny < 2 || out.len() != nx * ny {
            return Err(format!(
                "deflection: a grid of at least 2 x 2 points with room for each, got {nx} x {ny} and {}",
                out.len()
            ));
        }
        let mut grid = match self.grid.take() {
            Some(g) if g.nx == nx && g.ny == ny => g,
            _ => self.deflection_grid(nx, ny)?,
        };
        let read = self.get_reals(&grid.coordinates, &mut grid.eta);
        if read.is_ok() {
            for (k, w) in out.iter_mut().enumerate() {
                *w = (0..grid.eta.len())
                    .map(|c| grid.map[(k, c)] * grid.eta[c])
                    .sum();
            }
        }
        self.grid = Some(grid);
        read
    }

    /// What [`Simulation::deflection`] multiplies, for a page that draws the plate at any time
    /// of a run it recorded: the value references of the plate's coordinates (`x.plate.C[k].q`,
    /// `n` of them) and the `(nx ny) x n` matrix, row by row, whose row `i + nx j` times the
    /// coordinates is the deflection at grid point `(i, j)` \[m\].
    pub fn deflection_map(&mut self, nx: usize, ny: usize) -> Result<(Vec<u32>, Vec<f64>), String> {
        if nx < 2 || ny < 2 {
            return Err(format!(
                "deflection: a grid of at least 2 x 2 points, got {nx} x {ny}"
            ));
        }
        let grid = self.deflection_grid(nx, ny)?;
        let map = (0..nx * ny)
            .flat_map(|k| (0..grid.eta.len()).map(move |c| (k, c)))
            .map(|(k, c)| grid.map[(k, c)])
            .collect();
        Ok((grid.coordinates, map))
    }

    fn deflection_grid(&self, nx: usize, ny: usize) -> Result<DeflectionGrid, String> {
        let p = &self
            .instance
            .model()
            .parameters()
            .ok_or("deflection: the model is not built")?
            .plate;
        let (model, displacement) = PlateModel::with_displacements(p)?;
        let first = model.first_plate();
        let n = model.dim() - first;
        let declared: Vec<u32> = (1..)
            .map_while(|k| value_reference(&format!("x.plate.C[{k}].q")))
            .collect();
        if n > declared.len() {
            return Err(format!(
                "deflection: the plate has {n} coordinates, the variables show the first {}",
                declared.len()
            ));
        }
        let mut map = DMatrix::zeros(nx * ny, n);
        for j in 0..ny {
            for i in 0..nx {
                let x = p.a * i as f64 / (nx - 1) as f64;
                let y = p.b * j as f64 / (ny - 1) as f64;
                let d = displacement(x, y);
                for c in 0..n {
                    map[(i + nx * j, c)] = d[first + c];
                }
            }
        }
        Ok(DeflectionGrid {
            nx,
            ny,
            map,
            coordinates: declared[..n].to_vec(),
            eta: vec![0.0; n],
        })
    }
}

/// The variable table as JSON for the page: name, value reference, causality, variability,
/// type, unit, description, start, min and max (as `modelDescription.xml` has them), the group
/// the XML puts it in and its display unit (`{name, factor, offset}` or null, from [`SHOWN`]),
/// and an Enumeration's items (`[{name, value, description}]`).
pub fn variables_json() -> serde_json::Value {
    VARIABLES
        .iter()
        .zip(SHOWN.iter())
        .map(|(v, shown)| {
            let (start, min, max) = match v.kind {
                Kind::Real { start, min, max } => (
                    start.map(Into::into),
                    min.map(Into::into),
                    max.map(Into::into),
                ),
                Kind::Integer { start, min, max } => (
                    start.map(Into::into),
                    min.map(Into::into),
                    max.map(Into::into),
                ),
                Kind::Enumeration { start, declared } => (
                    start.map(Into::into),
                    declared.items.iter().map(|i| i.value).min().map(Into::into),
                    declared.items.iter().map(|i| i.value).max().map(Into::into),
                ),
                Kind::Boolean { start } => (start.map(Into::into), None, None),
                Kind::String { start } => (start.map(Into::into), None, None),
            };
            let start: Option<serde_json::Value> = start;
            let items: Option<Vec<serde_json::Value>> = match v.kind {
                Kind::Enumeration { declared, .. } => Some(
                    declared
                        .items
                        .iter()
                        .map(|i| {
                            serde_json::json!({
                                "name": i.name, "value": i.value, "description": i.description
                            })
                        })
                        .collect(),
                ),
                _ => None,
            };
            let display_unit = shown.display_unit.map(
                |d| serde_json::json!({"name": d.name, "factor": d.factor, "offset": d.offset}),
            );
            serde_json::json!({
                "name": v.name,
                "valueReference": v.value_reference,
                "causality": v.causality.xml_name(),
                "variability": v.variability.xml_name(),
                "group": shown.group,
                "displayUnit": display_unit,
                "items": items,
                "type": v.kind.type_name(),
                "unit": v.unit,
                "description": v.description,
                "start": start,
                "min": min.unwrap_or(serde_json::Value::Null),
                "max": max.unwrap_or(serde_json::Value::Null),
            })
        })
        .collect()
}

/// The settings of a request ([`parse_request`]) as one SSP 1.0 parameter set that the FMU
/// applies alone (no preset needed): the preset's settings, each replaced in place by the
/// request's setting of the same name, then the request's others, every value checked and
/// written as its variable's type reads it back (a Real as the shortest text of its double).
/// `name` and `description` go into the set. The error names the culprit setting.
pub fn parameter_set(
    preset: &str,
    settings: &[(String, String)],
    name: &str,
    description: &str,
) -> Result<String, String> {
    let mut all: Vec<(String, String)> = Vec::new();
    if !preset.is_empty() {
        let p = presets::preset(preset)?;
        all.extend(
            p.settings
                .iter()
                .map(|(n, v)| (n.to_string(), v.to_string())),
        );
    }
    for (n, v) in settings {
        match all.iter_mut().find(|(m, _)| m == n) {
            Some(slot) => slot.1 = v.clone(),
            None => all.push((n.clone(), v.clone())),
        }
    }
    let typed: Vec<(String, String)> = all
        .iter()
        .map(|(n, text)| {
            let (_, value) = parse_setting(n, text)?;
            let text = match value {
                Value::Real(x) => format!("{x:?}"),
                Value::Integer(i) => i.to_string(),
                Value::Boolean(b) => b.to_string(),
                Value::String(s) => s,
            };
            Ok((n.clone(), text))
        })
        .collect::<Result<_, String>>()?;
    crate::model::parameter_set::parameter_set_of(
        name,
        description,
        "the browser page (docs/web/page.js) from its run's settings",
        typed.iter().map(|(n, v)| (n.as_str(), v.as_str())),
    )
}

/// [`parameter_set`] of a request as [`parse_request`] reads it, with the set's `name` and
/// `description` beside (`{"preset", "settings", "name", "description"}`; the last two optional).
pub fn parameter_set_json(json: &str) -> Result<String, String> {
    let (preset, settings) = parse_request(json)?;
    let request: serde_json::Value =
        serde_json::from_str(json).map_err(|e| format!("the request is not JSON: {e}"))?;
    let text = |key: &str, default: &'static str| match request.get(key) {
        None | Some(serde_json::Value::Null) => Ok(default.to_string()),
        Some(serde_json::Value::String(s)) => Ok(s.clone()),
        Some(other) => Err(format!("{key}: {other} is not a text")),
    };
    let name = text("name", "browser-run")?;
    let description = text("description", "")?;
    parameter_set(&preset, &settings, &name, &description)
}

/// Reads a request to make a simulation, `{"preset": NAME, "settings": {NAME: VALUE, ...}}`
/// (both optional; a value is a number, a boolean or an enumeration item's name), as the preset
/// name and the settings as text for [`Simulation::new`].
pub fn parse_request(json: &str) -> Result<(String, Vec<(String, String)>), String> {
    let request: serde_json::Value =
        serde_json::from_str(json).map_err(|e| format!("the request is not JSON: {e}"))?;
    let preset = match request.get("preset") {
        None | Some(serde_json::Value::Null) => String::new(),
        Some(serde_json::Value::String(s)) => s.clone(),
        Some(other) => return Err(format!("preset: {other} is not a name")),
    };
    let mut settings = Vec::new();
    match request.get("settings") {
        None | Some(serde_json::Value::Null) => {}
        Some(serde_json::Value::Object(map)) => {
            for (name, value) in map {
                let text = match value {
                    serde_json::Value::Number(n) => n.to_string(),
                    serde_json::Value::Bool(b) => b.to_string(),
                    serde_json::Value::String(s) => s.clone(),
                    other => {
                        return Err(format!(
                            "{name}: {other} is not a number, a boolean or a name"
                        ))
                    }
                };
                settings.push((name.clone(), text));
            }
        }
        Some(other) => return Err(format!("settings: {other} is not an object of NAME: VALUE")),
    }
    Ok((preset, settings))
}
