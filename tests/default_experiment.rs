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
//!
//! What such a change may move is bounded by the second test: every output of the default
//! experiment at the FMU's own tolerances stays within 1e-6 of its range of the same run at
//! tolerances of 1e-10 (relative) and 1e-12 (absolute, of the nominals).

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

/// The default experiment at the FMU's tolerances (`solver.rtol` 1e-6, `solver.atol` 1e-8 of
/// the nominals) against the same run at 1e-10 and 1e-12: every output within 1e-6 of its range
/// over the run (the solver's error, which a change of formulation or method must keep there).
#[test]
fn the_default_experiment_is_within_1e_6_of_a_tight_run() {
    let fmu = packaged::fresh_fmu(packaged::Version::Fmi2);
    let got = packaged::csv_columns(&packaged::run_csv(&fmu, &[]));
    let tight = packaged::csv_columns(&packaged::run_csv(
        &fmu,
        &["--tolerance", "1e-10", "--set", "solver.atol=1e-12"],
    ));
    assert_eq!(got.len(), tight.len());
    let mut worst = (0.0, String::new());
    for ((name, a), (tight_name, b)) in got.iter().zip(&tight) {
        assert_eq!(name, tight_name);
        assert_eq!(a.len(), b.len(), "{name}: the runs' points differ");
        let lo = b.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = b.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let error = a
            .iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        let relative = if hi > lo { error / (hi - lo) } else { error };
        if relative > worst.0 {
            worst = (relative, name.clone());
        }
    }
    println!(
        "largest difference: {:.2e} of the range of {}",
        worst.0, worst.1
    );
    assert!(
        worst.0 < 1e-6,
        "{} differs by {:e} of its range",
        worst.1,
        worst.0
    );
}
