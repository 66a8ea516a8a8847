//! The rules of the FMI contract that FMI 2.0 and FMI 3.0 share, written once against the
//! [`Driver`] of `common/driver.rs` and run through the C ABI of each version (`<rule>::fmi2`,
//! `<rule>::fmi3`): a rule broken in one version fails that version's run only. The defects an
//! outside fuzzing campaign found (issue 24, N1, N3, N4) are reproduced here as they were
//! reported.

#[path = "common/driver.rs"]
mod driver;

use driver::{blob, find_key, payload, Driver, Kind, St, V2, V3};
use hydraulic_slewing_plate::fmu::FmuModel;
use hydraulic_slewing_plate::model::HydraulicSlewingPlate;

/// Reads every Real: none may come back OK and non-finite. Returns how many came back Discard,
/// with the message of the first.
fn no_non_finite_ok<D: Driver>(f: &D, context: &str) -> (usize, String) {
    let mut discarded = 0;
    let mut first = String::new();
    let log_before = f.log().len();
    for (name, s, v) in f.every_real() {
        assert!(
            s != St::Ok || v.is_finite(),
            "{}: {context}: {name} = {v} returned OK",
            D::PREFIX
        );
        assert!(
            matches!(s, St::Ok | St::Discard | St::Error),
            "{}: {context}: reading {name} gave {s:?}: {}",
            D::PREFIX,
            f.last()
        );
        if s == St::Discard {
            discarded += 1;
        }
    }
    if discarded > 0 {
        first = f.log()[log_before].1.clone();
    }
    (discarded, first)
}

fn state_count() -> usize {
    <HydraulicSlewingPlate as FmuModel>::continuous_states().len()
}

both_versions!(
    huge_accepted_states_never_give_ok_with_non_finite_values,
    /// N1 (447 hits in Model Exchange fuzzing): a finite but huge continuous state is accepted,
    /// and the values it makes non-finite (1e160 in a state gives energy = inf, 1e308 gives
    /// y_pot = inf) are refused by every getter with Discard and a message naming the variable
    /// and the state that made it so.
    fn rule<D: Driver>() {
        let n = state_count();
        let mut seen_energy = false;
        for huge in [1e160, 1e308] {
            for k in 0..n {
                let f = D::new(Kind::ModelExchange);
                assert_eq!(f.init(0.0), St::Ok, "{}", f.last());
                assert_eq!(f.enter_continuous_time_mode(), St::Ok, "{}", f.last());
                let (s, mut x) = f.continuous_states(n);
                assert_eq!(s, St::Ok);
                x[k] = huge;
                assert_eq!(f.set_continuous_states(&x), St::Ok, "{}", f.last());
                let (discarded, message) = no_non_finite_ok(&f, &format!("x[{k}] = {huge:e}"));
                if discarded > 0 {
                    assert!(
                        message.contains("is not finite") && message.contains("x["),
                        "{}: x[{k}] = {huge:e}: {message}",
                        D::PREFIX
                    );
                }
                if huge == 1e160 && f.get_real("energy").0 == St::Discard {
                    seen_energy = true;
                    let m = f.last();
                    assert!(m.contains("energy = inf"), "{m}");
                    assert!(
                        m.contains(&format!("x[{k}]")),
                        "the state that made it so: {m}"
                    );
                }
            }
        }
        assert!(seen_energy, "no state of 1e160 made the energy overflow");
    }
);

both_versions!(
    a_discarded_step_never_gives_ok_with_non_finite_values,
    /// N1: after a step discarded with the saturation off and r = 1e308, no getter hands out a
    /// non-finite value with OK.
    fn rule<D: Driver>() {
        let f = D::new(Kind::CoSimulation);
        assert_eq!(f.set_boolean("controller.saturation", false), St::Ok);
        assert_eq!(f.init(0.0), St::Ok, "{}", f.last());
        assert_eq!(f.set_real("r", 1e308), St::Ok);
        assert_eq!(f.step(0.0, 1e-3), St::Discard, "{}", f.last());
        no_non_finite_ok(&f, "after the discarded step");
    }
);

both_versions!(
    a_failed_initialization_never_gives_ok_with_non_finite_values,
    /// N1: after an initialisation that fails on non-finite outputs (the saturation off and r =
    /// 1e308), the instance is in the error state, where getters are allowed: none hands out a
    /// non-finite value with OK.
    fn rule<D: Driver>() {
        let f = D::new(Kind::CoSimulation);
        assert_eq!(f.set_boolean("controller.saturation", false), St::Ok);
        assert_eq!(f.set_real("r", 1e308), St::Ok);
        assert_eq!(f.init(0.0), St::Error, "{}", f.last());
        let (discarded, message) = no_non_finite_ok(&f, "after the failed initialisation");
        assert!(
            discarded > 0,
            "the failed initialisation left no non-finite value"
        );
        assert!(message.contains("error state"), "{message}");
    }
);

both_versions!(
    a_step_below_the_minimum_step_is_refused_with_its_size,
    /// N4 (1,532 hits): DoStep(0, 5e-324) was discarded as "step size 0e0 fell below the
    /// minimum 1e-14"; it is refused up front, naming its real size. Numbers in messages are in
    /// shortest round-trip form (1e-20, not 0.00000000000000000001).
    fn rule<D: Driver>() {
        for (h, shown) in [(5e-324, "5e-324"), (1e-20, "1e-20")] {
            let f = D::new(Kind::CoSimulation);
            assert_eq!(f.init(0.0), St::Ok);
            assert_eq!(f.step(0.0, h), St::Error);
            let m = f.last();
            let expected = format!(
                "{}DoStep: communicationStepSize {shown} is below the FMU's minimum step 1e-14",
                D::PREFIX
            );
            assert_eq!(m, expected);
        }
        // A step at the minimum is taken.
        let f = D::new(Kind::CoSimulation);
        assert_eq!(f.init(0.0), St::Ok);
        assert_eq!(f.step(0.0, 1e-14), St::Ok, "{}", f.last());
    }
);

both_versions!(
    a_restored_kept_step_must_be_as_long_as_its_step_size,
    /// N3: a crafted FMU state whose kept step (the step a co-simulation step ran past its
    /// communication point) is stretched to t1 = 1e300, checksum recomputed, was accepted, and
    /// the next 20 steps returned OK with the spool at 39 times its stroke. It is refused.
    fn rule<D: Driver>() {
        const STEP: f64 = 1e-3;
        let f = D::new(Kind::CoSimulation);
        assert_eq!(f.set_integer("hydraulics.model", 1), St::Ok);
        assert_eq!(f.set_boolean("controller.saturation", false), St::Ok);
        assert_eq!(f.set_boolean("hydraulics.motor_coupled", true), St::Ok);
        assert_eq!(f.set_boolean("solver.dense_output", true), St::Ok);
        assert_eq!(f.init(0.0), St::Ok);
        assert_eq!(f.set_real("r", 1.0), St::Ok);
        // Step with the inputs held until a state holds a kept step.
        let mut k = 0;
        let (saved, mut p) = loop {
            assert_eq!(f.step(k as f64 * STEP, STEP), St::Ok, "{}", f.last());
            k += 1;
            let (s, saved) = f.get_state();
            assert_eq!(s, St::Ok);
            let p = payload(&f.serialize(saved));
            // The kept step is in the state only while it is active.
            if find_key(&mut p.clone(), "ahead").is_some() {
                break (saved, p);
            }
            f.free_state(saved);
            assert!(k < 1000, "no kept step in 1 s");
        };
        find_key(&mut p, "ahead").unwrap()["t1"] = serde_json::json!(1e300);
        let (s, edited) = f.deserialize(&blob(&p));
        assert_eq!(s, St::Ok, "{}", f.last());
        assert_eq!(f.set_state(edited), St::Error);
        let m = f.last();
        assert!(m.starts_with(D::PREFIX), "{m}");
        assert!(m.contains("is not its step size h"), "{m}");
        f.free_state(edited);
        f.free_state(saved);
    }
);
