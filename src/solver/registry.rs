//! The registered methods: the crate's own (the `built_in!` list, one line each) and those added at run
//! time by [`register`]; the [`Method`] handle that names one; and the type-erased stepper the
//! driver holds, with the versioned saved form of an integrator.

use std::any::{Any, TypeId};
use std::sync::Mutex;

use serde::{Deserialize, Serialize};

use super::method::{check_non_negative, OdeMethod, Stepper};
use super::{OdeSystem, SolverError, SolverOptions, Stats};

/// A registered method, by its name (see [`OdeMethod::NAME`]). The crate's methods are the
/// constants below; [`register`] gives the handle of another. Serialised as its name.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Method(&'static str);

// The constants keep the names the methods had as enum variants.
#[allow(non_upper_case_globals)]
impl Method {
    /// Rosenbrock method Rodas5P (Steinebach 2023). Default. See [`super::rodas5p`].
    pub const Rodas5P: Method = Method(super::rodas5p::Rodas5P::NAME);
    /// Radau IIA, 3 stages, order 5 (Hairer & Wanner, RADAU5). See [`super::radau5`].
    pub const Radau5: Method = Method(super::radau5::Radau5::NAME);
    /// Rodas5P's step at a fixed step size, for real time: every call to `t_end` takes
    /// [`SolverOptions::substeps`] equal steps, none rejected, at a cost independent of the
    /// solution (see [`super::fixed`]). No error control: the tolerances only scale the error
    /// estimate it reports.
    pub const Rodas5PFixed: Method = Method(super::fixed::Rodas5PFixed::NAME);
    /// Rosenbrock-W method ROS34PW2 (Rang & Angermann 2005), order 3, with the Jacobian and W's
    /// LU kept across steps. See [`super::ros34pw2`].
    pub const Ros34pw2: Method = Method(super::ros34pw2::Ros34pw2::NAME);
    /// ROS34PW2's step at a fixed step size, for real time, W's LU kept across steps (see
    /// [`super::ros34pw2::Ros34pw2Fixed`]).
    pub const Ros34pw2Fixed: Method = Method(super::ros34pw2::Ros34pw2Fixed::NAME);

    /// Lower-case name as used on command lines ("rodas5p", "radau5", "rodas5p-fixed").
    pub fn name(self) -> &'static str {
        self.0
    }

    /// The handle of method `M`, registering it if it is not yet (see [`register`]).
    pub fn of<M: OdeMethod>() -> Result<Method, String> {
        register::<M>()
    }

    fn registration(self) -> Registration {
        find(self.0).unwrap_or_else(|| unreachable_registration(self.0))
    }
}

/// A `Method` is only made from a registration, which is never removed.
fn unreachable_registration(name: &str) -> Registration {
    panic!("method {name:?} is not registered")
}

impl std::fmt::Debug for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Method({})", self.0)
    }
}

impl std::str::FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let lower = s.to_ascii_lowercase();
        let all = registrations();
        all.iter()
            .find(|r| r.name == lower || r.aliases.contains(&lower.as_str()))
            .map(|r| Method(r.name))
            .ok_or_else(|| {
                let names: Vec<&str> = all.iter().map(|r| r.name).collect();
                let (last, rest) = names.split_last().unwrap_or((&"", &[]));
                format!(
                    "unknown method {s:?}; expected {} or {last}",
                    rest.join(", ")
                )
            })
    }
}

impl Serialize for Method {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.0)
    }
}

impl<'de> Deserialize<'de> for Method {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        find(&name)
            .map(|r| Method(r.name))
            .ok_or_else(|| serde::de::Error::custom(format!("unknown solver method {name:?}")))
    }
}

/// What the registry knows of a method: its names and how to make a fresh stepper. (How to save
/// and read one is in [`Saving`], apart, so that a program that never saves an integrator, the
/// browser page, carries no code for it.)
#[derive(Clone, Copy)]
struct Registration {
    name: &'static str,
    aliases: &'static [&'static str],
    type_id: fn() -> TypeId,
    fresh: fn(SolverOptions, f64, Vec<f64>, Stats) -> Box<dyn DynStepper>,
}

/// How to save, read and check a restored stepper of a registered method.
#[derive(Clone, Copy)]
struct Saving {
    name: &'static str,
    save: fn(&dyn Any) -> Result<Saved, String>,
    read: fn(Saved) -> Result<Box<dyn DynStepper>, String>,
    check: fn(&dyn Any, Pattern<'_>) -> Result<(), String>,
}

/// A system's structural Jacobian pattern ([`OdeSystem::jacobian_pattern`]).
type Pattern<'a> = Option<&'a [Vec<u32>]>;

fn saving<M: OdeMethod>() -> Saving {
    Saving {
        name: M::NAME,
        save: save::<M>,
        read: read::<M>,
        check: check::<M>,
    }
}

/// The driver's checks of a restored stepper of method `M` (`run` is its `Driven<M>`) that are
/// the method's: h, the maximum step where it bounds h, and the method's own state.
fn check<M: OdeMethod>(run: &dyn Any, pattern: Option<&[Vec<u32>]>) -> Result<(), String> {
    let s = &run
        .downcast_ref::<Driven<M>>()
        .ok_or_else(|| format!("not a stepper of {}", M::NAME))?
        .0;
    check_non_negative("h", s.h)?;
    M::check_restored(s, pattern)?;
    // The fixed-step (real-time) driver's h is the communication step over `substeps`, which
    // the maximum step does not bound: a state saved after a 1 s real-time step is valid.
    if M::H_WITHIN_MAX_STEP && s.h > s.options.max_step {
        return Err(format!(
            "its integrator's next step h = {} is above the maximum step {}",
            s.h, s.options.max_step
        ));
    }
    Ok(())
}

/// Checks a restored stepper (see [`check`]).
pub(crate) fn check_restored(
    run: &dyn DynStepper,
    pattern: Option<&[Vec<u32>]>,
) -> Result<(), String> {
    (saving_of(run.options().method.name())?.check)(run.as_any(), pattern)
}

fn registration<M: OdeMethod>() -> Registration {
    Registration {
        name: M::NAME,
        aliases: M::ALIASES,
        type_id: TypeId::of::<M>,
        fresh: |options, t, x, stats| {
            let state = M::fresh(&options, x.len());
            Box::new(Driven::<M>(Stepper {
                options,
                t,
                x,
                h: 0.0,
                stats,
                state,
            }))
        },
    }
}

/// The crate's methods, one line each (the registration of a method of this crate).
macro_rules! built_in {
    ($of:ident) => {
        [
            $of::<super::rodas5p::Rodas5P>(),
            $of::<super::radau5::Radau5>(),
            $of::<super::fixed::Rodas5PFixed>(),
            $of::<super::ros34pw2::Ros34pw2>(),
            $of::<super::ros34pw2::Ros34pw2Fixed>(),
        ]
    };
}

fn built_in() -> [Registration; 5] {
    built_in!(registration)
}

fn built_in_saving() -> [Saving; 5] {
    built_in!(saving)
}

/// The methods added by [`register`].
static REGISTERED: Mutex<Vec<Registration>> = Mutex::new(Vec::new());
/// How to save and read them.
static REGISTERED_SAVING: Mutex<Vec<Saving>> = Mutex::new(Vec::new());

fn saving_of(name: &str) -> Result<Saving, String> {
    built_in_saving()
        .into_iter()
        .find(|r| r.name == name)
        .or_else(|| {
            REGISTERED_SAVING
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .iter()
                .find(|r| r.name == name)
                .copied()
        })
        .ok_or_else(|| format!("the solver method {name:?} cannot be saved"))
}

fn registrations() -> Vec<Registration> {
    let mut all = built_in().to_vec();
    all.extend(REGISTERED.lock().unwrap_or_else(|e| e.into_inner()).iter());
    all
}

fn find(name: &str) -> Option<Registration> {
    built_in().into_iter().find(|r| r.name == name).or_else(|| {
        REGISTERED
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .iter()
            .find(|r| r.name == name)
            .copied()
    })
}

/// Registers method `M` at run time (the crate's own are registered already) and returns its
/// handle, for [`SolverOptions::method`]. Registering it again is harmless; another type under
/// a name already taken is refused.
pub fn register<M: OdeMethod>() -> Result<Method, String> {
    let mut registered = REGISTERED.lock().unwrap_or_else(|e| e.into_inner());
    let taken = built_in()
        .into_iter()
        .chain(registered.iter().copied())
        .find(|r| r.name == M::NAME || r.aliases.contains(&M::NAME));
    match taken {
        Some(r) if (r.type_id)() == TypeId::of::<M>() => Ok(Method(r.name)),
        Some(r) => Err(format!(
            "the method name {:?} is taken by another method ({:?})",
            M::NAME,
            r.name
        )),
        None => {
            registered.push(registration::<M>());
            REGISTERED_SAVING
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .push(saving::<M>());
            Ok(Method(M::NAME))
        }
    }
}

/// Every registered method: the crate's own, then those added by [`register`] (in the order
/// registered). The tests of every method run over this list.
pub fn methods() -> Vec<Method> {
    registrations().iter().map(|r| Method(r.name)).collect()
}

/// A fresh stepper of the method `options.method`, at (t, x), with the counters `stats`.
pub(crate) fn fresh(
    options: SolverOptions,
    t: f64,
    x: Vec<f64>,
    stats: Stats,
) -> Box<dyn DynStepper> {
    (options.method.registration().fresh)(options, t, x, stats)
}

/// A saved integrator: the shared point, then the method's state in its own format and that
/// format's version. The method is `options.method`.
#[derive(Serialize, Deserialize)]
pub(crate) struct Saved {
    pub options: SolverOptions,
    pub t: f64,
    pub x: Vec<f64>,
    pub h: f64,
    pub stats: Stats,
    /// [`OdeMethod::STATE_VERSION`] of the method that wrote `state`.
    pub state_version: u32,
    /// The method's state as the method wrote it (JSON text, read by the method once the version
    /// is checked).
    pub state: Box<serde_json::value::RawValue>,
}

/// Reads a saved stepper of method `M`, refusing a state of another format version.
fn read<M: OdeMethod>(saved: Saved) -> Result<Box<dyn DynStepper>, String> {
    if saved.state_version != M::STATE_VERSION {
        return Err(format!(
            "its {} solver state is of format version {}, this build reads version {}",
            M::NAME,
            saved.state_version,
            M::STATE_VERSION
        ));
    }
    let state: M::State = serde_json::from_slice(saved.state.get().as_bytes())
        .map_err(|e| format!("its {} solver state cannot be read: {e}", M::NAME))?;
    Ok(Box::new(Driven::<M>(Stepper {
        options: saved.options,
        t: saved.t,
        x: saved.x,
        h: saved.h,
        stats: saved.stats,
        state,
    })))
}

/// Reads a saved integrator (see [`Saved`]).
pub(crate) fn read_saved(saved: Saved) -> Result<Box<dyn DynStepper>, String> {
    (saving_of(saved.options.method.name())?.read)(saved)
}

/// The saved form of a stepper (see [`Saved`]).
pub(crate) fn save_stepper(run: &dyn DynStepper) -> Result<Saved, String> {
    (saving_of(run.options().method.name())?.save)(run.as_any())
}

/// Saves a stepper of method `M` (`run` is its `Driven<M>`).
fn save<M: OdeMethod>(run: &dyn Any) -> Result<Saved, String> {
    let s = &run
        .downcast_ref::<Driven<M>>()
        .ok_or_else(|| format!("not a stepper of {}", M::NAME))?
        .0;
    Ok(Saved {
        options: s.options.clone(),
        t: s.t,
        x: s.x.clone(),
        h: s.h,
        stats: s.stats,
        state_version: M::STATE_VERSION,
        state: serde_json::value::to_raw_value(&s.state)
            .map_err(|e| format!("cannot save the {} solver state: {e}", M::NAME))?,
    })
}

/// The driver's view of a stepper of any method.
pub(crate) trait DynStepper: Send {
    fn options(&self) -> &SolverOptions;
    fn t(&self) -> f64;
    fn x(&self) -> &[f64];
    fn h(&self) -> f64;
    fn set_h(&mut self, h: f64);
    fn stats(&self) -> &Stats;
    /// Replaces the point (t, x), returning the old x.
    fn set_point(&mut self, t: f64, x: Vec<f64>) -> Vec<f64>;
    fn set_options(&mut self, options: SolverOptions);
    fn advance(
        &mut self,
        sys: &dyn OdeSystem,
        t_end: f64,
        limit: f64,
        times: &[f64],
        out: &mut dyn FnMut(f64, &[f64]),
    ) -> Result<(), SolverError>;
    fn notify_discontinuity(&mut self);
    fn reset_state(&mut self, resized: bool);
    fn after_failure(&mut self);
    fn is_past(&self) -> bool;
    fn reached(&self) -> f64;
    fn error_estimate(&self) -> f64;
    fn clone_box(&self) -> Box<dyn DynStepper>;
    fn as_any(&self) -> &dyn Any;
    fn eq_dyn(&self, other: &dyn DynStepper) -> bool;
}

/// The stepper of method `M`.
struct Driven<M: OdeMethod>(Stepper<M::State>);

impl<M: OdeMethod> DynStepper for Driven<M> {
    fn options(&self) -> &SolverOptions {
        &self.0.options
    }
    fn t(&self) -> f64 {
        self.0.t
    }
    fn x(&self) -> &[f64] {
        &self.0.x
    }
    fn h(&self) -> f64 {
        self.0.h
    }
    fn set_h(&mut self, h: f64) {
        self.0.h = h;
    }
    fn stats(&self) -> &Stats {
        &self.0.stats
    }
    fn set_point(&mut self, t: f64, x: Vec<f64>) -> Vec<f64> {
        self.0.t = t;
        std::mem::replace(&mut self.0.x, x)
    }
    fn set_options(&mut self, options: SolverOptions) {
        self.0.options = options;
        M::options_changed(&mut self.0.state);
    }
    fn advance(
        &mut self,
        sys: &dyn OdeSystem,
        t_end: f64,
        limit: f64,
        times: &[f64],
        out: &mut dyn FnMut(f64, &[f64]),
    ) -> Result<(), SolverError> {
        M::advance(&mut self.0, sys, t_end, limit, times, out)
    }
    fn notify_discontinuity(&mut self) {
        M::notify_discontinuity(&mut self.0.state);
    }
    fn reset_state(&mut self, resized: bool) {
        M::reset(&mut self.0.state, resized);
    }
    fn after_failure(&mut self) {
        self.0.h = 0.0;
        M::after_failure(&mut self.0.state);
    }
    fn is_past(&self) -> bool {
        M::is_past(&self.0.state)
    }
    fn reached(&self) -> f64 {
        M::reached(&self.0)
    }
    fn error_estimate(&self) -> f64 {
        M::error_estimate(&self.0.state)
    }
    fn clone_box(&self) -> Box<dyn DynStepper> {
        Box::new(Driven::<M>(self.0.clone()))
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn eq_dyn(&self, other: &dyn DynStepper) -> bool {
        other
            .as_any()
            .downcast_ref::<Driven<M>>()
            .is_some_and(|o| o.0 == self.0)
    }
}
