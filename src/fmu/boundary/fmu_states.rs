//! The FMU-state functions of the C API, the same in FMI 2.0 and FMI 3.0 but for their names:
//! get (into a new state or one handed back to be overwritten), set, free, the serialised size,
//! serialise and deserialise. Each checks the FMU-state pointer it is handed (a NULL, a freed
//! state or an instance pointer are refused with a message naming the argument).

use super::super::fmu_state::SavedState;
use super::super::instance::Instance;
use super::super::{FmuModel, Status};
use super::{slice, with_instance, Handle};

/// The FMU state behind `state`, or an error naming the argument when it is NULL or not an FMU
/// state of this library (freed already, say, or an instance pointer).
///
/// # Safety
/// `state` is NULL or points to at least 8 readable bytes.
unsafe fn fmu_state<'a, M: FmuModel>(
    inst: &mut Instance<M>,
    state: Handle,
) -> Result<&'a mut SavedState<M::State>, Status> {
    let ptr = state as *mut SavedState<M::State>;
    let argument = inst.vocabulary().fmu_state;
    if state.is_null() {
        Err(inst.refuse(&format!("argument '{argument}' is NULL")))
    // SAFETY: non-null, at least 8 readable bytes by this function's contract.
    } else if !unsafe { SavedState::is_saved_state(ptr) } {
        Err(inst.refuse(&format!(
            "argument '{argument}' is not an FMU state of this FMU (freed already?)"
        )))
    } else {
        // SAFETY: the magic number says this is a live FMU state of this library, made by
        // `Box::into_raw` below; the importer hands it to one call at a time.
        Ok(unsafe { &mut *ptr })
    }
}

/// The checks of an FMU-state call ([`Instance::check_fmu_state_call`]), then the FMU state
/// behind `state`.
///
/// # Safety
/// As [`fmu_state`].
unsafe fn checked_state<'a, M: FmuModel>(
    inst: &mut Instance<M>,
    state: Handle,
) -> Result<&'a mut SavedState<M::State>, Status> {
    inst.check_fmu_state_call()?;
    // SAFETY: as this function's contract.
    unsafe { fmu_state(inst, state) }
}

/// What [`get`] and [`free`] check before they touch `*state`: the slot is not NULL and the
/// instance may use FMU states now; then the call is logged.
fn open_slot<M: FmuModel>(
    inst: &mut Instance<M>,
    function: &'static str,
    state: *mut Handle,
) -> Result<(), Status> {
    if state.is_null() {
        let argument = inst.vocabulary().fmu_state;
        return Err(inst.refuse(&format!("argument '{argument}' is NULL")));
    }
    inst.check_fmu_state_call()?;
    inst.log_call(|| format!("{function}()"));
    Ok(())
}

/// Saves the instance into a new FMU state at `*state`, or into the one `*state` holds (handed
/// back to be overwritten, FMI 2.0.4 2.1.8).
///
/// # Safety
/// `c` as for [`with_instance`]; `state` NULL or writable, `*state` NULL or an FMU state of this
/// library.
pub unsafe fn get<M: FmuModel>(c: Handle, function: &'static str, state: *mut Handle) -> Status {
    // SAFETY: as this function's contract.
    unsafe {
        with_instance::<M>(c, function, |inst| {
            if let Err(s) = open_slot(inst, function, state) {
                return s;
            }
            if (*state).is_null() {
                *state = Box::into_raw(Box::new(inst.save())) as Handle;
            } else {
                match fmu_state(inst, *state) {
                    Ok(old) => *old = inst.save(),
                    Err(s) => return s,
                }
            }
            Status::Ok
        })
    }
}

/// Restores the FMU state `state`.
///
/// # Safety
/// `c` as for [`with_instance`]; `state` NULL or from [`get`] or [`deserialize`] of this FMU.
pub unsafe fn set<M: FmuModel>(c: Handle, function: &'static str, state: Handle) -> Status {
    // SAFETY: as this function's contract.
    unsafe {
        with_instance::<M>(c, function, |inst| {
            let saved = match checked_state(inst, state) {
                Ok(saved) => saved,
                Err(s) => return s,
            };
            inst.log_call(|| format!("{function}()"));
            inst.restore(saved)
        })
    }
}

/// Frees the FMU state at `*state` and sets `*state` to NULL (a NULL `*state` is ignored).
///
/// # Safety
/// `c` as for [`with_instance`]; `state` NULL or writable, `*state` NULL or an FMU state of this
/// library not used again after.
pub unsafe fn free<M: FmuModel>(c: Handle, function: &'static str, state: *mut Handle) -> Status {
    // SAFETY: as this function's contract.
    unsafe {
        with_instance::<M>(c, function, |inst| {
            if let Err(s) = open_slot(inst, function, state) {
                return s;
            }
            if !(*state).is_null() {
                match fmu_state(inst, *state) {
                    Ok(saved) => {
                        // Invalidated before it is dropped: a later use of the dangling pointer
                        // is refused while the memory is still ours.
                        saved.invalidate();
                        drop(Box::from_raw(saved as *mut SavedState<M::State>));
                    }
                    Err(s) => return s,
                }
                *state = std::ptr::null_mut();
            }
            Status::Ok
        })
    }
}

/// The size of the serialised form of `state`, into `*size`.
///
/// # Safety
/// `c` as for [`with_instance`]; `state` as for [`set`]; `size` NULL or writable.
pub unsafe fn serialized_size<M: FmuModel>(
    c: Handle,
    function: &'static str,
    state: Handle,
    size: *mut usize,
) -> Status {
    // SAFETY: as this function's contract.
    unsafe {
        with_instance::<M>(c, function, |inst| {
            if size.is_null() {
                return inst.refuse("argument 'size' is NULL");
            }
            let saved = match checked_state(inst, state) {
                Ok(saved) => saved,
                Err(s) => return s,
            };
            match saved.serialized() {
                Ok(bytes) => {
                    *size = bytes.len();
                    Status::Ok
                }
                Err(msg) => inst.refuse(&msg),
            }
        })
    }
}

/// Serialises `state` into the `size` bytes at `bytes`.
///
/// # Safety
/// `c` as for [`with_instance`]; `state` as for [`set`]; `bytes` NULL or `size` writable bytes.
pub unsafe fn serialize<M: FmuModel>(
    c: Handle,
    function: &'static str,
    state: Handle,
    bytes: *mut u8,
    size: usize,
) -> Status {
    // SAFETY: as this function's contract.
    unsafe {
        with_instance::<M>(c, function, |inst| {
            if bytes.is_null() {
                return inst.refuse("argument 'serializedState' is NULL");
            }
            let saved = match checked_state(inst, state) {
                Ok(saved) => saved,
                Err(s) => return s,
            };
            match saved.serialized() {
                Ok(data) if data.len() <= size => {
                    std::ptr::copy_nonoverlapping(data.as_ptr(), bytes, data.len());
                    Status::Ok
                }
                Ok(data) => {
                    let need = data.len();
                    inst.refuse(&format!(
                        "buffer of {size} bytes is too small, {need} needed"
                    ))
                }
                Err(msg) => inst.refuse(&msg),
            }
        })
    }
}

/// Deserialises the `size` bytes at `bytes` into a new FMU state at `*state`; the state is
/// checked as strictly as fresh input when it is restored.
///
/// # Safety
/// `c` as for [`with_instance`]; `bytes` NULL or `size` readable bytes; `state` NULL or
/// writable.
pub unsafe fn deserialize<M: FmuModel>(
    c: Handle,
    function: &'static str,
    bytes: *const u8,
    size: usize,
    state: *mut Handle,
) -> Status {
    // SAFETY: as this function's contract.
    unsafe {
        with_instance::<M>(c, function, |inst| {
            if state.is_null() || (bytes.is_null() && size > 0) {
                let argument = inst.vocabulary().fmu_state;
                return inst.refuse(&format!(
                    "argument 'serializedState' or '{argument}' is NULL"
                ));
            }
            if let Err(s) = inst.check_fmu_state_call() {
                return s;
            }
            let data = slice(bytes, size).unwrap_or_default();
            match SavedState::<M::State>::deserialize(data, M::GUID) {
                Ok(saved) => {
                    *state = Box::into_raw(Box::new(saved)) as Handle;
                    Status::Ok
                }
                Err(msg) => inst.refuse(&msg),
            }
        })
    }
}
