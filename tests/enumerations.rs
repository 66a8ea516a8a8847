//! The FMU's switches are FMI Enumerations (`<TypeDefinitions>`): `build.rs` writes a Rust enum
//! per type from the XML, the FMI 2.0 interface reaches them through `fmi2SetInteger` /
//! `fmi2GetInteger`, the FMI 3.0 interface through `fmi3SetInt64` / `fmi3GetInt64`, and a value
//! that is no item of the type is refused by name, through either.

#[path = "common/fmu.rs"]
mod fmu;
#[path = "common/fmu3.rs"]
mod fmu3;

use fmu::Fmu;
use fmu3::Fmu3;
use hydraulic_slewing_plate::fmi2::ffi::Fmi2Status;
use hydraulic_slewing_plate::fmi3::ffi::Fmi3Status;
use hydraulic_slewing_plate::fmi3_exports::{fmi3GetInt64, fmi3SetFloat64, fmi3SetInt64};
use hydraulic_slewing_plate::fmu::{Experiment, Kind, Values};
use hydraulic_slewing_plate::model::parameters::{set_by_name, HydraulicsModel, Parameters};
use hydraulic_slewing_plate::model::variables::{
    PlateFormulation, PlateRoot, ServoValveDrive, SolverMethod, VARIABLES,
};

const SWITCHES: [(&str, &str); 5] = [
    ("hydraulics.model", "HydraulicsModel"),
    ("solver.method", "SolverMethod"),
    ("plate.formulation", "PlateFormulation"),
    ("plate.root", "PlateRoot"),
    ("servo_valve.drive", "ServoValveDrive"),
];

#[test]
fn the_switches_are_enumerations_of_their_types() {
    for (name, ty) in SWITCHES {
        let v = VARIABLES.iter().find(|v| v.name == name).unwrap();
        let Kind::Enumeration { declared, .. } = v.kind else {
            panic!("{name} is a {}", v.kind.type_name());
        };
        assert_eq!(declared.name, ty);
    }
    // The generated enums: values, names and the items of the XML.
    assert_eq!(HydraulicsModel::try_from(1), Ok(HydraulicsModel::Loes));
    assert_eq!(HydraulicsModel::ServoValve.value(), 2);
    assert_eq!(HydraulicsModel::ServoValve.name(), "ServoValve");
    assert_eq!(SolverMethod::try_from(2), Ok(SolverMethod::Radau5));
    assert_eq!(PlateFormulation::Consistent.value(), 2);
    assert_eq!(PlateRoot::try_from(2), Ok(PlateRoot::Locked));
    assert_eq!(ServoValveDrive::Current.value(), 2);
    assert!(!ServoValveDrive::Voltage.description().is_empty());
    let err = PlateRoot::try_from(3).unwrap_err();
    assert!(err.contains("1 = Hub, 2 = Locked"), "{err}");
}

#[test]
fn set_by_name_takes_an_item_by_value_or_name_and_refuses_others() {
    let mut values = Values::from_start(&VARIABLES);
    set_by_name(&mut values, "plate.root", "Locked").unwrap();
    set_by_name(&mut values, "hydraulics.model", "1").unwrap();
    let p = Parameters::from_values(&values, &Experiment::default()).unwrap();
    assert_eq!(p.hydraulics, HydraulicsModel::Loes);
    let err = set_by_name(&mut values, "solver.method", "5").unwrap_err();
    assert!(
        err.starts_with("solver.method: 5 is not a SolverMethod"),
        "{err}"
    );
    let err = set_by_name(&mut values, "servo_valve.drive", "Amps").unwrap_err();
    assert!(err.contains("ServoValveDrive"), "{err}");
}

#[test]
fn fmi2_sets_and_gets_enumerations_as_integers_and_refuses_non_items_by_name() {
    let f = Fmu::new();
    assert_eq!(f.set_integer("hydraulics.model", 1), Fmi2Status::Ok);
    assert_eq!(f.setup(0.0), Fmi2Status::Ok);
    assert_eq!(f.enter(), Fmi2Status::Ok);
    assert_eq!(f.get_integer("hydraulics.model"), (Fmi2Status::Ok, 1));
    assert_eq!(f.exit(), Fmi2Status::Ok);
    // An error ends an instance's usefulness: a fresh one for the refusal.
    let f = Fmu::new();
    assert_eq!(f.set_integer("plate.root", 3), Fmi2Status::Error);
    let last = f.last();
    assert!(
        last.contains("plate.root") && last.contains("PlateRoot"),
        "{last}"
    );
}

#[test]
fn fmi3_sets_and_gets_enumerations_as_int64_and_refuses_non_items_by_name() {
    let vr = Fmu3::vr("solver.method");
    let mut got = 0i64;
    unsafe {
        let f = Fmu3::new();
        assert_eq!(fmi3SetInt64(f.c, &vr, 1, &2, 1), Fmi3Status::Ok);
        assert_eq!(f.enter(0.0), Fmi3Status::Ok);
        assert_eq!(fmi3GetInt64(f.c, &vr, 1, &mut got, 1), Fmi3Status::Ok);
        assert_eq!(got, 2);
        assert_eq!(f.exit(), Fmi3Status::Ok);
        // An error ends an instance's usefulness: a fresh one for each refusal.
        for bad in [0, 5, 1 << 40] {
            let f = Fmu3::new();
            assert_eq!(fmi3SetInt64(f.c, &vr, 1, &bad, 1), Fmi3Status::Error);
            let last = f.last();
            assert!(
                last.contains("solver.method") && last.contains("SolverMethod"),
                "{last}"
            );
        }
        // A Float64 is no Int64, and an Int64 setter reaches no Float64.
        let f = Fmu3::new();
        assert_eq!(fmi3SetFloat64(f.c, &vr, 1, &1.0, 1), Fmi3Status::Error);
        let f = Fmu3::new();
        let rtol = Fmu3::vr("solver.rtol");
        assert_eq!(fmi3SetInt64(f.c, &rtol, 1, &1, 1), Fmi3Status::Error);
    }
}
