//! Named parameter sets: the paper's configurations, one place for `hsp run --preset NAME`, the
//! tests and the README.
//!
//! A preset is a list of `NAME=VALUE` settings of FMU parameters, applied over the start values
//! (a user's `--set` comes after it and wins). Every preset states the whole configuration
//! (hydraulic model, coupling, plate formulation, root, amplifier limit, drive, move, drag), so it
//! means the same thing whatever the FMU's defaults are; the parameters it does not name (gains,
//! plate, valve constants) keep their values. [`COMPLETE`] is the FMU's default.
//!
//! | preset | paper | what |
//! | --- | --- | --- |
//! | `complete` | Fig. 8 | full servo valve driving hub and plate (consistent formulation) through the torsion bar, hub free, the 30 deg move |
//! | `complete-hub-locked` | Fig. 8, Fig. 10 | the same with the hub locked (the motor twists the bar) |
//! | `servo-valve-motor` | Fig. 2b | full servo valve on the motor alone: the setup of the `G_est` fit |
//! | `loes-motor` | eq. 1, eq. 2 | the LOES on the motor alone, linear amplifier: the identification |
//! | `paper-eq16` | eq. 16 | the paper's plate formulation on its hub: eq. 16's frequencies |
//! | `paper-fig9b` | Fig. 9b, Table 1 | the LOES driving hub and the paper's plate, linear amplifier |
//! | `paper-fig10` | Fig. 10 | the paper's plate clamped at the root, shaken by F1/F2; the LOES motor alone |
//!
//! The two presets of the complete system (`complete`, `complete-hub-locked`) use the default
//! design's current-feedback coil drive and load-pressure feedback (docs/model.md, "The default
//! loop's damping"); every other preset uses the paper's voltage drive (`servo_valve.drive = 1`,
//! where the full valve is in) and eq. 1's controller without pressure feedback
//! (`controller.k_pl = 0`). The complete system's presets have the air's added mass
//! (`plate.Ca = 1`) and the vane motor's seal friction (the defaults); the paper's presets leave
//! the air out (`plate.Ca = 0`), and `servo-valve-motor`, the setup of the `G_est` fit, the
//! friction (`servo_valve.T_c = T_s = 0`: the paper's motor has viscous friction only).
//!
//! The time-domain presets of the complete system use the consistent plate formulation and the
//! command generator's move; the presets that reproduce a result of the paper use the paper's
//! formulation (which is what reproduces eq. 16 and Table 1) and switch the generator and the
//! air drag off, so that `r` alone drives them as in the paper.

use crate::fmu::{Kind, Values};

use super::parameters::set_by_name;
use super::variables::VARIABLES;

/// A named parameter set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Preset {
    /// The name for `--preset`.
    pub name: &'static str,
    /// Where the configuration is in the paper.
    pub paper: &'static str,
    /// One line on what it is.
    pub description: &'static str,
    /// `(NAME, VALUE)` settings of FMU parameters.
    pub settings: &'static [(&'static str, &'static str)],
}

/// The FMU's default: the paper's complete system.
pub const COMPLETE: &str = "complete";

/// The default move of the command generator, 30 degrees in radians (`reference.angle`).
const MOVE_30_DEG: &str = "0.5235987755982988";

/// The load-pressure feedback gain of the complete system's presets \[V/Pa\]
/// (`controller.k_pl`, [`crate::fragments::controller::DEFAULT_K_PL`]).
const PRESSURE_FEEDBACK: &str = "5e-8";

/// The structural damping ratio of the presets that reproduce the paper (and of the motor-alone
/// setups): 1 %, the value the paper's results were first reproduced with (docs/model-notes.md).
const PAPER_ZETA: &str = "0.01";

/// Every preset, the default first.
pub const PRESETS: &[Preset] = &[
    Preset {
        name: COMPLETE,
        paper: "Fig. 8",
        description: "full servo valve driving the hub and plate (consistent formulation) through \
                      the torsion bar, hub free, amplifier limit on, a 30 deg minimum-jerk move \
                      over 2 s (the FMU's defaults)",
        settings: &[
            ("hydraulics.model", "2"),
            ("hydraulics.motor_coupled", "true"),
            ("plate.formulation", "2"),
            ("plate.root", "1"),
            ("controller.saturation", "true"),
            ("controller.external", "false"),
            ("controller.k_pl", PRESSURE_FEEDBACK),
            ("servo_valve.drive", "2"),
            ("reference.angle", MOVE_30_DEG),
            ("plate.Cd", "1.2"),
            ("plate.Ca", "1"),
            ("plate.zeta", "0.02"),
        ],
    },
    Preset {
        name: "complete-hub-locked",
        paper: "Fig. 8, Fig. 10",
        description: "the complete system with the hub locked: the motor twists the torsion bar \
                      against a clamped plate root (consistent formulation, the 30 deg move)",
        settings: &[
            ("hydraulics.model", "2"),
            ("hydraulics.motor_coupled", "true"),
            ("plate.formulation", "2"),
            ("plate.root", "2"),
            ("controller.saturation", "true"),
            ("controller.external", "false"),
            ("controller.k_pl", PRESSURE_FEEDBACK),
            ("servo_valve.drive", "2"),
            ("reference.angle", MOVE_30_DEG),
            ("plate.Cd", "1.2"),
            ("plate.Ca", "1"),
            ("plate.zeta", "0.02"),
        ],
    },
    Preset {
        name: "servo-valve-motor",
        paper: "Fig. 2b",
        description: "full servo valve on the motor alone (the setup of the G_est fit), no move: \
                      r drives it; the plate is driven by F1 and F2 only",
        settings: &[
            ("hydraulics.model", "2"),
            ("hydraulics.motor_coupled", "false"),
            ("plate.formulation", "2"),
            ("plate.root", "1"),
            ("controller.saturation", "true"),
            ("controller.external", "false"),
            ("controller.k_pl", "0"),
            ("servo_valve.drive", "1"),
            ("servo_valve.T_c", "0"),
            ("servo_valve.T_s", "0"),
            ("reference.angle", "0"),
            ("plate.Cd", "0"),
            ("plate.Ca", "0"),
            ("plate.zeta", PAPER_ZETA),
        ],
    },
    Preset {
        name: "loes-motor",
        paper: "eq. 1, eq. 2",
        description: "the LOES on the motor alone with the linear amplifier of eq. 1, no move: \
                      the paper's identification setup (G_est)",
        settings: &[
            ("hydraulics.model", "1"),
            ("hydraulics.motor_coupled", "false"),
            ("plate.formulation", "1"),
            ("plate.root", "1"),
            ("controller.saturation", "false"),
            ("controller.external", "false"),
            ("controller.k_pl", "0"),
            ("servo_valve.drive", "1"),
            ("reference.angle", "0"),
            ("plate.Cd", "0"),
            ("plate.Ca", "0"),
            ("plate.zeta", PAPER_ZETA),
        ],
    },
    Preset {
        name: "paper-eq16",
        paper: "eq. 16",
        description: "the paper's plate formulation (eqs. 18-21) on its hub: the natural \
                      frequencies of eq. 16 (hsp modes); the LOES motor runs alone, no move",
        settings: &[
            ("hydraulics.model", "1"),
            ("hydraulics.motor_coupled", "false"),
            ("plate.formulation", "1"),
            ("plate.root", "1"),
            ("controller.saturation", "false"),
            ("controller.external", "false"),
            ("controller.k_pl", "0"),
            ("servo_valve.drive", "1"),
            ("reference.angle", "0"),
            ("plate.Cd", "0"),
            ("plate.Ca", "0"),
            ("plate.zeta", PAPER_ZETA),
        ],
    },
    Preset {
        name: "paper-fig9b",
        paper: "Fig. 9b, Table 1",
        description: "the LOES driving the hub and the paper's plate formulation through the \
                      torsion bar, linear amplifier, no move (the FRF from r to the tip \
                      acceleration, Table 1)",
        settings: &[
            ("hydraulics.model", "1"),
            ("hydraulics.motor_coupled", "true"),
            ("plate.formulation", "1"),
            ("plate.root", "1"),
            ("controller.saturation", "false"),
            ("controller.external", "false"),
            ("controller.k_pl", "0"),
            ("servo_valve.drive", "1"),
            ("reference.angle", "0"),
            ("plate.Cd", "0"),
            ("plate.Ca", "0"),
            ("plate.zeta", PAPER_ZETA),
        ],
    },
    Preset {
        name: "paper-fig10",
        paper: "Fig. 10",
        description: "the paper's plate formulation clamped at the root (hub locked) and shaken \
                      by F1, F2; the LOES motor runs alone, no move",
        settings: &[
            ("hydraulics.model", "1"),
            ("hydraulics.motor_coupled", "false"),
            ("plate.formulation", "1"),
            ("plate.root", "2"),
            ("controller.saturation", "false"),
            ("controller.external", "false"),
            ("controller.k_pl", "0"),
            ("servo_valve.drive", "1"),
            ("reference.angle", "0"),
            ("plate.Cd", "0"),
            ("plate.Ca", "0"),
            ("plate.zeta", PAPER_ZETA),
        ],
    },
];

/// The preset of this name; the error lists the known names.
pub fn preset(name: &str) -> Result<&'static Preset, String> {
    PRESETS.iter().find(|p| p.name == name).ok_or_else(|| {
        let names: Vec<&str> = PRESETS.iter().map(|p| p.name).collect();
        format!("unknown preset '{name}' (known: {})", names.join(", "))
    })
}

/// Applies the preset `name` to `values` with the FMU's own checks.
pub fn apply(values: &mut Values, name: &str) -> Result<(), String> {
    for (var, value) in preset(name)?.settings {
        set_by_name(values, var, value).map_err(|e| format!("preset '{name}': {e}"))?;
    }
    Ok(())
}

/// The presets as JSON: `[{"name", "paper", "description", "settings": {NAME: value}}]` with
/// values typed as the FMU variables are (a boolean, an integer, or a number with a decimal
/// point for a Real), for importers such as the Python tests.
pub fn presets_json() -> serde_json::Value {
    let typed = |name: &str, v: &str| -> serde_json::Value {
        let kind = super::variables::position(name).map(|i| VARIABLES[i].kind);
        match (kind, v) {
            (_, "true") => true.into(),
            (_, "false") => false.into(),
            (Some(Kind::Real { .. }), _) => v.parse::<f64>().map_or_else(|_| v.into(), Into::into),
            _ => v
                .parse::<i64>()
                .map(Into::into)
                .or_else(|_| v.parse::<f64>().map(Into::into))
                .unwrap_or_else(|_| v.into()),
        }
    };
    PRESETS
        .iter()
        .map(|p| {
            let settings: serde_json::Map<String, serde_json::Value> = p
                .settings
                .iter()
                .map(|(n, v)| (n.to_string(), typed(n, v)))
                .collect();
            serde_json::json!({
                "name": p.name,
                "paper": p.paper,
                "description": p.description,
                "settings": settings,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fmu::Experiment;
    use crate::model::parameters::{HydraulicsModel, Parameters};

    #[test]
    fn every_preset_applies_and_names_are_unique() {
        for (i, p) in PRESETS.iter().enumerate() {
            let mut values = Values::from_start(&VARIABLES);
            apply(&mut values, p.name).unwrap();
            Parameters::from_values(&values, &Experiment::default()).unwrap();
            assert!(PRESETS[..i].iter().all(|q| q.name != p.name), "{}", p.name);
        }
    }

    #[test]
    fn the_fmu_defaults_are_the_complete_preset() {
        let start = Values::from_start(&VARIABLES);
        let mut values = start.clone();
        apply(&mut values, COMPLETE).unwrap();
        let e = Experiment::default();
        assert_eq!(
            Parameters::from_values(&values, &e).unwrap(),
            Parameters::from_values(&start, &e).unwrap()
        );
    }

    #[test]
    fn the_loes_motor_preset_is_the_identification_setup() {
        let mut values = Values::from_start(&VARIABLES);
        apply(&mut values, "loes-motor").unwrap();
        let p = Parameters::from_values(&values, &Experiment::default()).unwrap();
        assert_eq!(p.hydraulics, HydraulicsModel::Loes);
        assert!(!p.motor_coupled && !p.controller.saturation && !p.controller.external);
    }

    #[test]
    fn unknown_preset_is_named_with_the_known_ones() {
        let e = apply(&mut Values::from_start(&VARIABLES), "fig9").unwrap_err();
        assert!(e.contains("'fig9'") && e.contains("loes-motor"), "{e}");
    }

    #[test]
    fn json_values_are_typed() {
        let j = presets_json();
        assert_eq!(j[0]["name"], COMPLETE);
        assert_eq!(j[0]["settings"]["hydraulics.model"], 2);
        assert_eq!(j[0]["settings"]["hydraulics.motor_coupled"], true);
        // A Real is a float even where the text is an integer.
        assert!(j[1 + 2]["settings"]["plate.Cd"].is_f64());
    }
}
