//! The packaged FMI 3.0 FMU works with an independent importer, the Rust `fmi` crate (0.8,
//! feature `fmi3`).
//!
//! The test loads `fmu/fmi3/HydraulicSlewingPlate.fmu` (building both FMUs with `hsp package` if it
//! is missing) and proves that
//! * the crate's parser accepts the FMI 3.0 `modelDescription.xml`: version, instantiation token
//!   (the FMI 2.0 GUID), model identifier, the arrays;
//! * a co-simulation instance created and stepped by the crate gives, step by step and to the
//!   bit, what the FMI 2.0 interface of the same library gives in-process for the same
//!   experiment (the LOES step of eq. 1 and the complete system's default step), the
//!   accelerometer array included.
//!
//! The crate has no FMU-state functions for FMI 3.0 (they are compiled out in 0.8); the Python
//! suite tests FMI 3.0 state serialisation across processes.
//!
//! fmi-schema 0.8 (the crate's parser, the newest release) does not read all of FMI 3.0's
//! `modelDescription.xml` and refuses what it does not know: it spells two attributes of
//! `<BaseUnit>` `a` and `k` where the FMI 3.0 schema (`fmi3Unit.xsd`) has `A` (ampere) and `K`
//! (kelvin), and its `<Float64>` lacks `unit` and `displayUnit`. The test therefore hands the
//! crate a copy of the FMU whose XML differs in exactly these (checked below); fmpy's validation
//! of the unchanged FMU (tests/python/test_fmi3.py) answers for the original.

#[path = "common/packaged.rs"]
mod packaged;

use std::path::PathBuf;

use fmi::fmi3::import::Fmi3Import;
use fmi::fmi3::{CoSimulation, Common, Fmi3Model, GetSet};
use fmi::traits::FmiImport;
use hydraulic_slewing_plate::fmi2::ffi::{Fmi2CallbackFunctions, Fmi2Status, FMI2_CO_SIMULATION};
use hydraulic_slewing_plate::fmi2_exports as f2;
use hydraulic_slewing_plate::fmu::Kind;
use hydraulic_slewing_plate::model::presets;
use hydraulic_slewing_plate::model::variables::{vr, GUID, MODEL_IDENTIFIER, VARIABLES};

/// Communication step [s].
const H: f64 = 1e-3;

/// The packaged FMU, built from these sources (rebuilt by `hsp package` when missing or stale).
fn fmu_path() -> PathBuf {
    packaged::fresh_fmu(packaged::Version::Fmi3)
}

/// The FMI 3.0 XML as fmi-schema 0.8 reads it: `A=` of `<BaseUnit>` as `a=`, and `unit="..."`,
/// `displayUnit="..."` and `nominal="..."` (valid FMI 3.0 the crate does not know) left out of
/// `<Float64>` (see the module doc).
fn crate_dialect(xml: &str) -> String {
    // Every attribute named A is BaseUnit's, which is all the renaming may touch.
    let places: Vec<usize> = xml.match_indices(" A=\"").map(|(i, _)| i).collect();
    assert!(
        !places.is_empty(),
        "no ampere in the units any more: drop this part"
    );
    for &i in &places {
        let element = &xml[xml[..i].rfind('<').unwrap()..i];
        assert!(
            element == "<BaseUnit" || element.starts_with("<BaseUnit "),
            "A= outside BaseUnit: {element}"
        );
    }
    let mut out = String::with_capacity(xml.len());
    for line in xml.replace(" A=\"", " a=\"").lines() {
        let mut line = line.to_string();
        if line.trim_start().starts_with("<Float64 ") {
            for attribute in [" unit=\"", " displayUnit=\"", " nominal=\""] {
                if let Some(start) = line.find(attribute) {
                    let end = start
                        + attribute.len()
                        + line[start + attribute.len()..].find('"').unwrap()
                        + 1;
                    line.replace_range(start..end, "");
                }
            }
        }
        out.push_str(&line);
        out.push('\n');
    }
    out
}

/// A copy of the FMU with its XML in [`crate_dialect`]; every other entry is the same.
fn with_schema_workaround(fmu: &std::path::Path) -> PathBuf {
    use std::io::{Read, Write};
    let mut archive = zip::ZipArchive::new(std::fs::File::open(fmu).unwrap()).unwrap();
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fmi3-crate-workaround.fmu");
    let mut writer = zip::ZipWriter::new(std::fs::File::create(&out).unwrap());
    let options = zip::write::SimpleFileOptions::default();
    for i in 0..archive.len() {
        let mut entry = archive.by_index(i).unwrap();
        let name = entry.name().to_string();
        let mut bytes = Vec::new();
        entry.read_to_end(&mut bytes).unwrap();
        if name == "modelDescription.xml" {
            bytes = crate_dialect(&String::from_utf8(bytes).unwrap()).into_bytes();
        }
        writer.start_file(name, options).unwrap();
        writer.write_all(&bytes).unwrap();
    }
    writer.finish().unwrap();
    out
}

fn value_reference(name: &str) -> u32 {
    VARIABLES
        .iter()
        .find(|v| v.name == name)
        .unwrap_or_else(|| panic!("no variable {name}"))
        .value_reference
}

/// A preset's value, typed as its variable.
enum Setting {
    Boolean(bool),
    Int32(i32),
    /// An Enumeration: FMI 3.0 sets it through fmi3SetInt64.
    Int64(i64),
    Float64(f64),
}

/// The settings of a preset as (value reference, value).
fn preset_settings(name: &str) -> Vec<(u32, Setting)> {
    presets::preset(name)
        .unwrap()
        .settings
        .iter()
        .map(|(n, v)| {
            let var = VARIABLES.iter().find(|x| x.name == *n).unwrap();
            let value = match var.kind {
                Kind::Boolean { .. } => Setting::Boolean(*v == "true"),
                Kind::Integer { .. } => Setting::Int32(v.parse().unwrap()),
                Kind::Enumeration { .. } => Setting::Int64(v.parse().unwrap()),
                _ => Setting::Float64(v.parse().unwrap()),
            };
            (value_reference(n), value)
        })
        .collect()
}

/// Outputs after each step: y_pot, theta_motor, theta_hub, the 12 accelerometers (as bits).
type Trace = Vec<Vec<u64>>;

const SCALARS: [u32; 3] = [vr::Y_POT, vr::THETA_MOTOR, vr::THETA_HUB];

/// The experiment through the `fmi` crate and the FMI 3.0 FMU.
fn run_fmi3(import: &Fmi3Import, preset: &str, r: f64, steps: usize) -> Trace {
    let mut inst = import
        .instantiate_cs("fmi3-crate", false, false, false, false, &[])
        .expect("fmi3InstantiateCoSimulation");
    for (vr, value) in preset_settings(preset) {
        match value {
            Setting::Boolean(b) => inst.set_boolean(&[vr], &[b]),
            Setting::Int32(i) => inst.set_int32(&[vr], &[i]),
            Setting::Int64(i) => inst.set_int64(&[vr], &[i]),
            Setting::Float64(x) => inst.set_float64(&[vr], &[x]),
        }
        .unwrap_or_else(|e| panic!("setting vr {vr}: {e:?}"));
    }
    inst.enter_initialization_mode(None, 0.0, None)
        .expect("fmi3EnterInitializationMode");
    inst.set_float64(&[vr::R], &[r]).expect("fmi3SetFloat64(r)");
    inst.exit_initialization_mode()
        .expect("fmi3ExitInitializationMode");
    let acc = value_reference("acc[1]");
    let mut trace = Vec::new();
    for k in 0..steps {
        let (mut event, mut terminate, mut early, mut last) = (true, true, true, 0.0);
        inst.do_step(
            k as f64 * H,
            H,
            true,
            &mut event,
            &mut terminate,
            &mut early,
            &mut last,
        )
        .unwrap_or_else(|e| panic!("fmi3DoStep at step {k}: {e:?}"));
        assert!(!event && !terminate && !early);
        assert_eq!(
            last,
            k as f64 * H + H,
            "lastSuccessfulTime is the end of the step"
        );
        let mut v = [0.0; 3];
        inst.get_float64(&SCALARS, &mut v).expect("fmi3GetFloat64");
        let mut a = [0.0; 12];
        // One value reference, twelve values: the accelerometer array.
        inst.get_float64(&[acc], &mut a)
            .expect("fmi3GetFloat64(acc)");
        trace.push(v.iter().chain(&a).map(|x: &f64| x.to_bits()).collect());
    }
    inst.terminate().expect("fmi3Terminate");
    trace
}

unsafe extern "C" fn quiet(
    _env: *mut std::ffi::c_void,
    _name: *const std::os::raw::c_char,
    _status: Fmi2Status,
    _category: *const std::os::raw::c_char,
    _message: *const std::os::raw::c_char,
) {
}

/// The same experiment through the FMI 2.0 functions of the library, in-process.
fn run_fmi2(preset: &str, r: f64, steps: usize) -> Trace {
    let callbacks = Fmi2CallbackFunctions::with_plain_logger(quiet, std::ptr::null_mut());
    let name = c"fmi2";
    let guid = std::ffi::CString::new(GUID).unwrap();
    unsafe {
        let c = f2::fmi2Instantiate(
            name.as_ptr(),
            FMI2_CO_SIMULATION,
            guid.as_ptr(),
            std::ptr::null(),
            &callbacks,
            0,
            0,
        );
        assert!(!c.is_null());
        for (vr, value) in preset_settings(preset) {
            let s = match value {
                Setting::Boolean(b) => f2::fmi2SetBoolean(c, &vr, 1, &i32::from(b)),
                Setting::Int32(i) => f2::fmi2SetInteger(c, &vr, 1, &i),
                Setting::Int64(i) => f2::fmi2SetInteger(c, &vr, 1, &(i as i32)),
                Setting::Float64(x) => f2::fmi2SetReal(c, &vr, 1, &x),
            };
            assert_eq!(s, Fmi2Status::Ok);
        }
        assert_eq!(
            f2::fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0),
            Fmi2Status::Ok
        );
        assert_eq!(f2::fmi2EnterInitializationMode(c), Fmi2Status::Ok);
        assert_eq!(f2::fmi2SetReal(c, &vr::R, 1, &r), Fmi2Status::Ok);
        assert_eq!(f2::fmi2ExitInitializationMode(c), Fmi2Status::Ok);
        let acc: Vec<u32> = (1..=12)
            .map(|k| value_reference(&format!("acc[{k}]")))
            .collect();
        let mut trace = Vec::new();
        for k in 0..steps {
            assert_eq!(f2::fmi2DoStep(c, k as f64 * H, H, 1), Fmi2Status::Ok);
            let mut v = [0.0; 15];
            assert_eq!(
                f2::fmi2GetReal(c, SCALARS.as_ptr(), 3, v.as_mut_ptr()),
                Fmi2Status::Ok
            );
            assert_eq!(
                f2::fmi2GetReal(c, acc.as_ptr(), 12, v[3..].as_mut_ptr()),
                Fmi2Status::Ok
            );
            trace.push(v.iter().map(|x| x.to_bits()).collect());
        }
        f2::fmi2FreeInstance(c);
        trace
    }
}

#[test]
fn fmi_crate_imports_the_fmi3_fmu_and_it_steps_as_the_fmi2_interface_does() {
    let fmu = with_schema_workaround(&fmu_path());
    let import: Fmi3Import = fmi::import::from_path(&fmu)
        .unwrap_or_else(|e| panic!("the fmi crate rejects {}: {e} ({e:?})", fmu.display()));
    let md = import.model_description();
    assert_eq!(md.fmi_version, "3.0");
    assert_eq!(md.instantiation_token, GUID);
    let cs = md.co_simulation.as_ref().expect("no <CoSimulation>");
    assert_eq!(cs.model_identifier, MODEL_IDENTIFIER);

    for (preset, r, steps) in [("loes-motor", 1.0, 300), ("complete", 2.0, 300)] {
        let three = run_fmi3(&import, preset, r, steps);
        let two = run_fmi2(preset, r, steps);
        assert_eq!(three.len(), two.len());
        for (k, (a, b)) in three.iter().zip(&two).enumerate() {
            assert_eq!(a, b, "{preset}: outputs differ after step {k}");
        }
        // The experiment did something: the motor moved.
        let theta = f64::from_bits(three[steps - 1][1]);
        assert!(theta.abs() > 1e-3, "{preset}: theta_motor = {theta}");
    }
}
