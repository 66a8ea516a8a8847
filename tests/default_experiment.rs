//! The default experiment of the README (`hsp run`: the complete system, the 30 deg
//! minimum-jerk move over 2 s, 6 s at 5 ms communication steps, through the packaged FMU's C
//! ABI) gives the same CSV to the byte as the committed reference
//! `tests/reference/default_experiment.csv`. The FMI-LS-REF result both FMUs ship
//! (`extra/org.fmi-standard.fmi-ls-ref/HydraulicSlewingPlate_out.csv`, every output in the
//! Reference FMUs' layout, written by `hsp package`'s own run) holds the same values in the
//! columns both files have: `tests/python/test_ecosystem.py` checks it against this file to the
//! bit (docs/ecosystem.md).
//!
//! The reference is a regression value, not an independent one: the CSV of the day the FMU core
//! was restructured (issue 24), kept so that a refactoring that changes any result by one bit is
//! seen. A change to the model or solver that changes results on purpose regenerates it with
//! `hsp run --no-plot --csv tests/reference/default_experiment.csv` and says why in the commit.

#[path = "common/packaged.rs"]
mod packaged;

#[test]
fn the_default_experiment_is_byte_identical_to_the_reference() {
    let fmu = packaged::fresh_fmu(packaged::Version::Fmi2);
    let got = packaged::run_csv(&fmu, &[]);
    let reference = std::fs::read(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/reference/default_experiment.csv"),
    )
    .unwrap();
    assert_eq!(got.len(), reference.len(), "the CSV's length differs");
    if let Some(at) = got.iter().zip(&reference).position(|(a, b)| a != b) {
        let line = reference[..at].iter().filter(|&&b| b == b'\n').count() + 1;
        panic!("the CSV differs from the reference first at byte {at}, line {line}");
    }
}
