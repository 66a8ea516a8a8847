//! The `nominal` of each continuous state in both model descriptions is what
//! `fmi2GetNominalsOfContinuousStates` and `fmi3GetNominalsOfContinuousStates` return after
//! initialisation with the default parameters (1 for the states the default configuration does
//! not have), bit for bit. `modelDescription/update.py` writes them from
//! `modelDescription/model_structure.json`, which `tests/model_structure.rs` writes.

#[path = "common/fmu.rs"]
mod fmu;

use std::ffi::{c_void, CString};
use std::os::raw::c_char;

use fmu::Fmu;
use hydraulic_slewing_plate::fmi2::ffi::Fmi2Status;
use hydraulic_slewing_plate::fmi2_exports::fmi2GetNominalsOfContinuousStates;
use hydraulic_slewing_plate::fmi3::ffi::*;
use hydraulic_slewing_plate::fmi3_exports::*;
use hydraulic_slewing_plate::model::variables::{CONTINUOUS_STATES, GUID, VARIABLES};

// The project's one reader of the XML.
#[path = "../tools/model_description.rs"]
#[allow(dead_code)]
mod model_description;

const NX: usize = CONTINUOUS_STATES.len();

unsafe extern "C" fn quiet3(_: *mut c_void, _: Fmi3Status, _: *const c_char, _: *const c_char) {}

/// The nominals the FMI 2.0 XML declares, in the order of the states.
fn fmi2_xml_nominals() -> Vec<f64> {
    let text = std::fs::read_to_string("modelDescription/modelDescription.xml").unwrap();
    let md = model_description::ModelDescription::parse(&text).unwrap();
    CONTINUOUS_STATES
        .iter()
        .map(|&(x, _)| {
            let v = &md.variables[x];
            assert_eq!(v.name, VARIABLES[x].name);
            let nominal = v.nominal.as_deref();
            nominal
                .unwrap_or_else(|| panic!("{} declares no nominal", v.name))
                .parse()
                .unwrap()
        })
        .collect()
}

/// The nominals the FMI 3.0 XML declares, in the order of the states.
fn fmi3_xml_nominals() -> Vec<f64> {
    let text = std::fs::read_to_string("modelDescription/fmi3/modelDescription.xml").unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    CONTINUOUS_STATES
        .iter()
        .map(|&(x, _)| {
            let name = VARIABLES[x].name;
            let node = doc
                .descendants()
                .find(|n| n.has_tag_name("Float64") && n.attribute("name") == Some(name))
                .unwrap_or_else(|| panic!("{name} is not in the FMI 3.0 XML"));
            node.attribute("nominal")
                .unwrap_or_else(|| panic!("{name} declares no nominal in FMI 3.0"))
                .parse()
                .unwrap()
        })
        .collect()
}

fn fmi2_nominals() -> Vec<f64> {
    let f = Fmu::model_exchange();
    assert_eq!(f.init(0.0), Fmi2Status::Ok);
    let mut n = vec![f64::NAN; NX];
    let s = unsafe { fmi2GetNominalsOfContinuousStates(f.c, n.as_mut_ptr(), NX) };
    assert_eq!(s, Fmi2Status::Ok);
    n
}

fn fmi3_nominals() -> Vec<f64> {
    unsafe {
        let token = CString::new(GUID).unwrap();
        let c = fmi3InstantiateModelExchange(
            c"nominals".as_ptr(),
            token.as_ptr(),
            std::ptr::null(),
            0,
            0,
            std::ptr::null_mut(),
            Some(quiet3),
        );
        assert!(!c.is_null());
        assert_eq!(
            fmi3EnterInitializationMode(c, 0, 0.0, 0.0, 0, 0.0),
            Fmi3Status::Ok
        );
        assert_eq!(fmi3ExitInitializationMode(c), Fmi3Status::Ok);
        let mut n = vec![f64::NAN; NX];
        assert_eq!(
            fmi3GetNominalsOfContinuousStates(c, n.as_mut_ptr(), NX),
            Fmi3Status::Ok
        );
        fmi3FreeInstance(c);
        n
    }
}

/// Bit for bit, with the first difference named.
fn assert_same(what: &str, got: &[f64], declared: &[f64]) {
    for (k, (g, d)) in got.iter().zip(declared).enumerate() {
        assert_eq!(
            g.to_bits(),
            d.to_bits(),
            "{what}: {} returns {g:e}, the XML declares {d:e}",
            VARIABLES[CONTINUOUS_STATES[k].0].name
        );
    }
    assert_eq!(got.len(), declared.len());
}

#[test]
fn xml_nominals_are_what_both_interfaces_return_with_the_default_parameters() {
    let declared = fmi2_xml_nominals();
    // The default model's own nominals are not all 1 (else the test would prove little).
    assert!(declared.iter().any(|&n| n != 1.0));
    assert_same("FMI 3.0 XML", &fmi3_xml_nominals(), &declared);
    assert_same(
        "fmi2GetNominalsOfContinuousStates",
        &fmi2_nominals(),
        &declared,
    );
    assert_same(
        "fmi3GetNominalsOfContinuousStates",
        &fmi3_nominals(),
        &declared,
    );
}
