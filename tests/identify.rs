//! `hsp identify` (docs/identify.md) on synthetic frequency responses of the complete system:
//! responses from `r` to `y_pot` and to `acc_tip` of the linearised model with known parameters
//! away from the defaults, each point multiplied by `1 + n` with `n` complex Gaussian noise of
//! 1 % RMS (`0.01 (a + j b) / sqrt 2`, `a`, `b` standard normal), written as the command's CSV,
//! fitted by the command from the defaults. The truths are the generating values, independent of
//! the fit. The paper's own identification (eq. 2) is run backwards from `G_est`'s closed-form
//! response.

#[path = "common/fmu.rs"]
mod fmu;

use std::path::{Path, PathBuf};
use std::process::Command;

use fmu::Fmu;
use hydraulic_slewing_plate::fmi2::ffi::Fmi2Status;
use hydraulic_slewing_plate::fmu::{Experiment, Values};
use hydraulic_slewing_plate::fragments::controller::ControllerParameters;
use hydraulic_slewing_plate::fragments::loes::LoesParameters;
use hydraulic_slewing_plate::fragments::servo_valve::g_est;
use hydraulic_slewing_plate::model::assembly::Assembled;
use hydraulic_slewing_plate::model::frf::{frequency_response, response_at};
use hydraulic_slewing_plate::model::paper::{
    G_EST_POLE_1, G_EST_POLE_2, PRINTED_C3, PRINTED_I_B, PRINTED_R7, TABLE1,
};
use hydraulic_slewing_plate::model::parameters::{set_by_name, Parameters};
use hydraulic_slewing_plate::model::variables::VARIABLES;
use serde_json::Value as Json;

/// The generating values of the three-parameter case, away from the defaults (1.4e9 Pa, 0.02,
/// 2500 N m/rad).
const TRUTH: [(&str, f64); 3] = [
    ("servo_valve.beta", 1.0e9),
    ("plate.zeta", 0.03),
    ("torsion_bar.k", 3200.0),
];

/// Points per response, log-spaced over 0.5 to 120 Hz (the band of the paper's Fig. 9b).
const POINTS: usize = 200;

#[path = "../tools/splitmix64.rs"]
mod splitmix64;

/// Standard normal numbers from a seed: splitmix64 and the Box–Muller transform.
struct Normal(splitmix64::SplitMix64);

impl Normal {
    fn new(seed: u64) -> Normal {
        Normal(splitmix64::SplitMix64(seed))
    }
    fn next(&mut self) -> f64 {
        let (u, v) = (1.0 - self.0.uniform(), self.0.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
}

/// A fresh folder for one test's files.
fn folder(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("identify")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The responses from `r` to each of `outputs` of the model with `sets` applied to the FMU's
/// start values, with 1 % complex noise from `seed` (none for `None`), written as
/// `dir/OUTPUT.csv`; the `--frf` arguments for them.
fn synthetic(dir: &Path, sets: &[(&str, f64)], outputs: &[&str], seed: Option<u64>) -> Vec<String> {
    let mut values = Values::from_start(&VARIABLES);
    for (name, v) in sets {
        set_by_name(&mut values, name, &v.to_string()).unwrap();
    }
    let p = Parameters::from_values(&values, &Experiment::default()).unwrap();
    // The linearisation of `hsp frf` and `hsp identify`: at rest, the vane motor sliding.
    let system = Assembled::new(&p.sliding()).unwrap();
    let lin = system
        .compiled()
        .linearize(&system.initial_state(), system.inputs());
    let input = lin.input_names.iter().position(|n| n == "r").unwrap();
    let mut noise = seed.map(Normal::new);
    outputs
        .iter()
        .map(|output| {
            let o = lin.output_names.iter().position(|n| n == output).unwrap();
            let mut csv = String::from("f_Hz,re,im\n");
            for k in 0..POINTS {
                let f = 0.5 * (120.0f64 / 0.5).powf(k as f64 / (POINTS - 1) as f64);
                let mut h = response_at(&lin, input, o, f).unwrap();
                if let Some(n) = noise.as_mut() {
                    let (a, b) = (n.next(), n.next());
                    h *= nalgebra::Complex::new(
                        1.0 + 0.01 * a / 2f64.sqrt(),
                        0.01 * b / 2f64.sqrt(),
                    );
                }
                csv.push_str(&format!("{f:?},{:?},{:?}\n", h.re, h.im));
            }
            let file = dir.join(format!("{output}.csv"));
            std::fs::write(&file, csv).unwrap();
            format!("r:{output}:{}", file.display())
        })
        .collect()
}

/// `hsp identify --json` with `frfs`, `--fit` for each of `fit` and `extra` arguments: its JSON
/// and its standard error; panics, with the error, when the command fails.
fn identify(frfs: &[String], fit: &[&str], extra: &[&str]) -> (Json, String) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_hsp"));
    cmd.args(["identify", "--json"]);
    for f in frfs {
        cmd.args(["--frf", f]);
    }
    for f in fit {
        cmd.args(["--fit", f]);
    }
    let out = cmd.args(extra).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "hsp identify failed: {stderr}");
    (serde_json::from_slice(&out.stdout).unwrap(), stderr)
}

/// `hsp identify --json ARGS`, which must succeed: its JSON.
fn identify_json(args: &[&str]) -> Json {
    let out = Command::new(env!("CARGO_BIN_EXE_hsp"))
        .args(["identify", "--json"])
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// The 95 % interval of `name`, or `None` when the command gives none.
fn ci95(json: &Json, name: &str) -> Option<(f64, f64)> {
    let ci = &json["parameters"][name]["ci95"];
    ci.as_array()
        .map(|a| (a[0].as_f64().unwrap(), a[1].as_f64().unwrap()))
}

fn warnings(json: &Json) -> Vec<String> {
    json["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w.as_str().unwrap().to_string())
        .collect()
}

/// The three-parameter fit from the defaults: each truth inside its interval, each interval
/// narrower than ±5 % (the data determine them), no warning.
fn fit_three(dir: &Path, seed: u64, out: Option<&Path>) -> Json {
    let frfs = synthetic(dir, &TRUTH, &["y_pot", "acc_tip"], Some(seed));
    let fit: Vec<&str> = TRUTH.iter().map(|(n, _)| *n).collect();
    let out_arg = out.map(|p| p.display().to_string());
    let extra: Vec<&str> = match &out_arg {
        Some(p) => vec!["--out", p],
        None => vec![],
    };
    identify(&frfs, &fit, &extra).0
}

#[test]
fn synthetic_frfs_give_back_the_parameters_within_their_intervals() {
    let dir = folder("three");
    let json = fit_three(&dir, 1, None);
    assert!(warnings(&json).is_empty(), "{json:#}");
    // The plate's damping ratio and the bar's stiffness reach the model in dual numbers (the
    // structure's modal dashpots with the derivatives of its modes): no finite difference.
    for name in ["plate.zeta", "torsion_bar.k"] {
        assert_eq!(
            json["parameters"][name]["sensitivity"], "exact",
            "{name}: {json:#}"
        );
    }
    for (name, truth) in TRUTH {
        let (lo, hi) = ci95(&json, name).unwrap_or_else(|| panic!("{name}: no interval"));
        assert!(
            lo <= truth && truth <= hi,
            "{name}: {truth} not in [{lo}, {hi}]: {json:#}"
        );
        assert!(hi / lo < 1.1, "{name}: [{lo}, {hi}] is wide: {json:#}");
        let start = json["parameters"][name]["start"].as_f64().unwrap();
        assert!(
            start < lo || start > hi,
            "{name}: the start {start} is inside [{lo}, {hi}]"
        );
    }
}

/// The exact sensitivities and central differences (`--sensitivities central`) give the same
/// fit: the minimum does not depend on how its Jacobian was computed (to the optimiser's
/// tolerance, far inside the intervals), and the intervals, which come from the Jacobian at the
/// minimum, agree to the central differences' error (their step 1e-4 in `z`: 1e-8 relative
/// truncation, round-off 1e-16 / 1e-4 of a residual). The exact ones are what the report says
/// they are, and the central ones say why.
#[test]
fn exact_sensitivities_and_central_differences_give_the_same_fit() {
    let dir = folder("exact_central");
    let frfs = synthetic(&dir, &TRUTH, &["y_pot", "acc_tip"], Some(3));
    let fit: Vec<&str> = TRUTH.iter().map(|(n, _)| *n).collect();
    let (exact, _) = identify(&frfs, &fit, &[]);
    let (central, _) = identify(&frfs, &fit, &["--sensitivities", "central"]);
    assert_eq!(
        exact["parameters"]["servo_valve.beta"]["sensitivity"], "exact",
        "{exact:#}"
    );
    assert!(exact["derivatives"].as_u64().unwrap() > 0, "{exact:#}");
    for (name, _) in TRUTH {
        same_fit(
            &exact,
            &central,
            name,
            "--sensitivities central",
            (1e-3, 1e-4),
        );
    }
    assert_eq!(central["derivatives"].as_u64(), Some(0));
}

/// Asserts that the fits `exact` (exact sensitivities) and `central` (central differences, the
/// reason naming `why`) found the same value of `name` within `tolerance.0` of its interval's
/// width, and intervals of the same width within `tolerance.1` (relative).
fn same_fit(exact: &Json, central: &Json, name: &str, why: &str, tolerance: (f64, f64)) {
    assert_eq!(
        exact["parameters"][name]["sensitivity"], "exact",
        "{exact:#}"
    );
    let c = &central["parameters"][name];
    assert_eq!(c["sensitivity"], "central differences", "{central:#}");
    assert!(
        c["sensitivity_reason"].as_str().unwrap().contains(why),
        "{central:#}"
    );
    let value = |j: &Json| j["parameters"][name]["value"].as_f64().unwrap();
    let (lo, hi) = ci95(exact, name).unwrap();
    assert!(
        (value(exact) - value(central)).abs() < tolerance.0 * (hi - lo),
        "{name}: {} against {} (interval [{lo}, {hi}])",
        value(exact),
        value(central)
    );
    let (clo, chi) = ci95(central, name).unwrap();
    assert!(
        ((chi - clo) / (hi - lo) - 1.0).abs() < tolerance.1,
        "{name}: [{lo}, {hi}] against [{clo}, {chi}]"
    );
}

/// Exact data (no noise): the fit reaches the generating values to the sensitivities' accuracy,
/// an independent check of the optimiser and the residuals' definition.
#[test]
fn exact_frfs_give_back_the_generating_values() {
    let dir = folder("exact");
    let frfs = synthetic(&dir, &TRUTH, &["y_pot", "acc_tip"], None);
    let fit: Vec<&str> = TRUTH.iter().map(|(n, _)| *n).collect();
    let (json, _) = identify(&frfs, &fit, &[]);
    for (name, truth) in TRUTH {
        let v = json["parameters"][name]["value"].as_f64().unwrap();
        assert!(
            (v / truth - 1.0).abs() < 1e-6,
            "{name}: {v} against {truth}: {json:#}"
        );
    }
    assert!(json["cost"].as_f64().unwrap() < 1e-12, "{json:#}");
}

/// The written parameter set, applied value by value through the FMU's FMI 2.0 set calls (as an
/// SSP tool applies it), sets every parameter; after initialisation the FMU reads back each
/// fitted parameter as the fit's value, bit for bit.
#[test]
fn the_written_ssv_applied_through_the_fmu_gives_the_fitted_parameters_back() {
    let dir = folder("ssv");
    let ssv = dir.join("fitted.ssv");
    let json = fit_three(&dir, 2, Some(&ssv));
    let text = std::fs::read_to_string(&ssv).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let fmu = Fmu::new();
    let mut reals = Vec::new();
    let mut count = 0;
    for p in doc.descendants().filter(|n| n.has_tag_name("Parameter")) {
        let name = p.attribute("name").unwrap();
        let typed = p.children().find(|c| c.is_element()).unwrap();
        let value = typed.attribute("value").unwrap();
        let status = match typed.tag_name().name() {
            "Real" => {
                let v: f64 = value.parse().unwrap();
                reals.push((name.to_string(), v));
                fmu.set_real(name, v)
            }
            "Integer" => fmu.set_integer(name, value.parse().unwrap()),
            "Boolean" => fmu.set_boolean(name, value.parse().unwrap()),
            other => panic!("{name}: unexpected type {other}"),
        };
        assert_eq!(status, Fmi2Status::Ok, "{name} = {value}: {}", fmu.last());
        count += 1;
    }
    let parameters = VARIABLES
        .iter()
        .filter(|v| v.causality == hydraulic_slewing_plate::fmu::Causality::Parameter)
        .count();
    assert_eq!(
        count, parameters,
        "the set holds every parameter of the FMU"
    );
    assert_eq!(fmu.init(0.0), Fmi2Status::Ok, "{}", fmu.last());
    for (name, _) in TRUTH {
        let fitted = json["parameters"][name]["value"].as_f64().unwrap();
        let (_, in_set) = reals.iter().find(|(n, _)| n == name).unwrap();
        assert_eq!(in_set.to_bits(), fitted.to_bits(), "{name} in the .ssv");
        let (status, read) = fmu.get_real(name);
        assert_eq!(status, Fmi2Status::Ok);
        assert_eq!(
            read.to_bits(),
            fitted.to_bits(),
            "{name} read back from the FMU"
        );
    }
}

/// With the load-pressure feedback off the loop gain is `A1 A2`: data from r determine the
/// product, not the factors. The command says so and gives neither an interval.
#[test]
fn a_product_of_two_gains_is_reported_as_undetermined() {
    let dir = folder("product");
    let sets = [("controller.k_pl", 0.0), ("controller.A1", 2.5)];
    let frfs = synthetic(&dir, &sets, &["y_pot", "acc_tip"], Some(3));
    let (json, stderr) = identify(
        &frfs,
        &["controller.A1", "controller.A2"],
        &["--set", "controller.k_pl=0"],
    );
    let w = warnings(&json);
    assert!(
        w.iter().any(
            |w| w.contains("cannot separate controller.A1, controller.A2")
                && w.contains("undetermined")
        ),
        "{json:#}"
    );
    assert!(stderr.contains("cannot separate"), "{stderr}");
    for name in ["controller.A1", "controller.A2"] {
        assert_eq!(ci95(&json, name), None, "{name}: {json:#}");
    }
    let corr = json["correlations"][0][1].as_f64().unwrap();
    assert!(
        corr < -0.99,
        "ln A1 and ln A2 trade off: correlation {corr}"
    );
}

/// The plate's yield strength enters only the stress monitor, not the responses from r: the
/// command says the data do not see it, and still fits the bar's stiffness with an interval that
/// holds the truth.
#[test]
fn a_parameter_the_outputs_do_not_see_is_reported() {
    let dir = folder("unseen");
    let frfs = synthetic(&dir, &[("torsion_bar.k", 3200.0)], &["y_pot"], Some(4));
    let (json, _) = identify(&frfs, &["torsion_bar.k", "plate.sigma_y"], &[]);
    let w = warnings(&json);
    assert!(
        w.iter().any(|w| w.contains("do not see plate.sigma_y")),
        "{json:#}"
    );
    assert_eq!(ci95(&json, "plate.sigma_y"), None, "{json:#}");
    let (lo, hi) = ci95(&json, "torsion_bar.k").unwrap();
    assert!(lo <= 3200.0 && 3200.0 <= hi, "[{lo}, {hi}]");
    // Alone, it is reported the same way, and left at its start.
    let (json, _) = identify(&frfs, &["plate.sigma_y"], &[]);
    assert!(
        warnings(&json)[0].contains("do not see plate.sigma_y"),
        "{json:#}"
    );
    assert_eq!(ci95(&json, "plate.sigma_y"), None, "{json:#}");
    let p = &json["parameters"]["plate.sigma_y"];
    assert_eq!(p["value"], p["start"], "{json:#}");
}

/// Bad input is refused with an error naming the culprit.
#[test]
fn bad_input_is_refused_naming_the_culprit() {
    let dir = folder("bad");
    let frfs = synthetic(&dir, &[], &["y_pot"], None);
    let run = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_hsp"))
            .arg("identify")
            .args(args)
            .output()
            .unwrap();
        assert!(!out.status.success(), "{args:?} succeeded");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let file = frfs[0].trim_start_matches("r:y_pot:");
    let e = run(&[
        "--frf",
        &format!("r:nothing:{file}"),
        "--fit",
        "torsion_bar.k",
    ]);
    assert!(e.contains("'nothing' is not an output"), "{e}");
    let e = run(&["--frf", &frfs[0], "--fit", "torsion_bar.kk"]);
    assert!(e.contains("'torsion_bar.kk' is not a variable"), "{e}");
    let broken = dir.join("broken.csv");
    std::fs::write(&broken, "f_Hz,re\n1,2\n").unwrap();
    let e = run(&[
        "--frf",
        &format!("r:y_pot:{}", broken.display()),
        "--fit",
        "torsion_bar.k",
    ]);
    assert!(e.contains("no column 'im'"), "{e}");
    // Time series: each file refused with its culprit named.
    for (text, culprit) in [
        (
            "time,r,y_pot,nonsense\n0,0,0.1,1\n0.1,0,0.2,1\n",
            "column 'nonsense' is neither an input nor an output of the FMU",
        ),
        (
            "time,r,y_pot\n0,0,0.1\n0,0,0.2\n",
            "data row 2: time 0 is not finite and after",
        ),
    ] {
        let series = dir.join("series.csv");
        std::fs::write(&series, text).unwrap();
        let e = run(&[
            "--series",
            series.to_str().unwrap(),
            "--fit",
            "torsion_bar.k",
        ]);
        assert!(e.contains(culprit), "{e}");
    }
}

/// Over 20 noise seeds the 95 % intervals of the three-parameter fit hold the truth in 17 to 20
/// of them, for each parameter (the binomial 95 % range of a correct 95 % interval; 16 or fewer
/// has a probability of 1.6 %).
#[test]
fn intervals_cover_the_truth_in_17_to_20_of_20_noise_seeds() {
    let dir = folder("coverage");
    let mut covered = [0; TRUTH.len()];
    for seed in 100..120 {
        let json = fit_three(&dir, seed, None);
        for (k, (name, truth)) in TRUTH.iter().enumerate() {
            let (lo, hi) = ci95(&json, name).unwrap();
            covered[k] += usize::from(lo <= *truth && *truth <= hi);
        }
    }
    eprintln!(
        "covered in 20 seeds: {:?} of {:?}",
        covered,
        TRUTH.map(|t| t.0)
    );
    for (k, (name, _)) in TRUTH.iter().enumerate() {
        assert!(
            (17..=20).contains(&covered[k]),
            "{name}: covered in {} of 20",
            covered[k]
        );
    }
}

/// `--report DIR`: the page shows the fit's numbers as the JSON gives them, and a Bode plot of
/// each response (measured, start, fitted). The fitted residual's RMS is the noise's, 1 % (the
/// generating noise has E|n|^2 = 1e-4; 200 complex points, 400 real ones, make the RMS good to
/// 1/sqrt(800) = 3.5 %: the bound is ±12 %, 3.4 of that), the start's far above it.
#[test]
fn the_report_page_shows_the_fit_and_each_response() {
    let dir = folder("report");
    let frfs = synthetic(
        &dir,
        &[("torsion_bar.k", 3200.0)],
        &["y_pot", "acc_tip"],
        Some(5),
    );
    let report = dir.join("report");
    let (json, _) = identify(
        &frfs,
        &["torsion_bar.k"],
        &["--report", report.to_str().unwrap()],
    );
    let page = std::fs::read_to_string(report.join("index.md")).unwrap();
    let value = json["parameters"]["torsion_bar.k"]["value"]
        .as_f64()
        .unwrap();
    assert!(
        page.contains(&format!("| `torsion_bar.k` | 2.500000e3 | {value:.6e} |")),
        "{page}"
    );
    for (k, r) in json["responses"].as_array().unwrap().iter().enumerate() {
        let (before, after) = (
            r["rms_start"].as_f64().unwrap(),
            r["rms_fitted"].as_f64().unwrap(),
        );
        assert!((0.0088..0.0112).contains(&after), "{r}");
        assert!(before > 5.0 * after, "{r}");
        assert!(
            page.contains(&format!("| {before:.6e} | {after:.6e} |")),
            "{page}"
        );
        let svg = std::fs::read_to_string(report.join(format!("frf_{}.svg", k + 1))).unwrap();
        for legend in ["measured", "model at the start", "model fitted"] {
            assert!(svg.contains(legend), "frf_{}.svg: no {legend}", k + 1);
        }
        assert!(page.contains(&format!("](frf_{}.svg)", k + 1)), "{page}");
    }
}

/// The loop of eq. 1 closed with unity feedback around the identified `G_est(s) = 2.25e6 / (s
/// (s+65) (s+753))` (eq. 2, the paper's identification), from `r` to `y_pot`: `T = G_est / (1 +
/// G_est)` at [`POINTS`] log-spaced frequencies, with 1 % complex noise from `seed` (none for
/// `None`), written as `dir/g_est.csv`; the `--frf` argument for it.
fn g_est_closed_loop(dir: &Path, seed: Option<u64>) -> String {
    let mut noise = seed.map(Normal::new);
    let mut csv = String::from("f_Hz,re,im\n");
    for k in 0..POINTS {
        let f = 0.5 * (120.0f64 / 0.5).powf(k as f64 / (POINTS - 1) as f64);
        let g = g_est(2.0 * std::f64::consts::PI * f);
        let mut h = g / (g + 1.0);
        if let Some(n) = noise.as_mut() {
            let (a, b) = (n.next(), n.next());
            h *= nalgebra::Complex::new(1.0 + 0.01 * a / 2f64.sqrt(), 0.01 * b / 2f64.sqrt());
        }
        csv.push_str(&format!("{f:?},{:?},{:?}\n", h.re, h.im));
    }
    let file = dir.join("g_est.csv");
    std::fs::write(&file, csv).unwrap();
    format!("r:y_pot:{}", file.display())
}

/// The LOES parameters that set `G_est`'s poles and gain (`R7`: `1/(R7 C3)` = 65 + 753 s⁻¹;
/// `D_m`: `D_m²/(C3 I_b)` = 65 · 753 s⁻²; `k_sv`: the gain), their truths from the closed-form
/// derivation (`LoesParameters::from_g_est`, docs/model-notes.md item 7), and the fit's start:
/// the printed `R7` = 3.8e7 (poles at 135 and 364 rad/s), `D_m` and `k_sv` 1.5 and 0.6 times
/// theirs.
fn loes_case() -> ([(&'static str, f64); 3], Vec<String>) {
    let truth = LoesParameters::from_g_est(&ControllerParameters::default());
    let truths = [
        ("loes.R7", truth.r7),
        ("loes.D_m", truth.d_m),
        ("loes.k_sv", truth.k_sv),
    ];
    let start = [PRINTED_R7, 1.5 * truth.d_m, 0.6 * truth.k_sv];
    let mut extra = vec!["--preset".to_string(), "loes-motor".to_string()];
    for ((name, _), s) in truths.iter().zip(start) {
        extra.push("--set".into());
        extra.push(format!("{name}={s:?}"));
    }
    (truths, extra)
}

/// The paper's identification (eq. 2) run backwards: from the closed-loop response of `G_est`,
/// the LOES on the motor alone (preset `loes-motor`) gives back the parameters that set its poles
/// and gain. Exact data: each to 1e-6 (the issue asks 1e-3; the fit does better), so that the
/// poles `-65` and `-753` rad/s of the fitted `s² + s/(R7 C3) + D_m²/(C3 I_b)` come back too;
/// 1 % noise: each truth inside its interval, each interval within ±1 %.
#[test]
fn the_loes_parameters_come_back_from_a_response_of_eq_2() {
    let dir = folder("g_est");
    let (truths, extra) = loes_case();
    let extra: Vec<&str> = extra.iter().map(String::as_str).collect();
    let fit: Vec<&str> = truths.iter().map(|(n, _)| *n).collect();
    let (json, _) = identify(&[g_est_closed_loop(&dir, None)], &fit, &extra);
    assert!(warnings(&json).is_empty(), "{json:#}");
    let value = |json: &Json, name: &str| json["parameters"][name]["value"].as_f64().unwrap();
    // The LOES's constants reach the model in dual numbers: no finite difference.
    for (name, _) in truths {
        assert_eq!(json["parameters"][name]["sensitivity"], "exact", "{json:#}");
    }
    for (name, truth) in truths {
        let v = value(&json, name);
        assert!(
            (v / truth - 1.0).abs() < 1e-6,
            "{name}: {v} against {truth}: {json:#}"
        );
    }
    // The poles of the fitted loop, roots of s^2 + s / (R7 C3) + D_m^2 / (C3 I_b).
    let sum = 1.0 / (value(&json, "loes.R7") * PRINTED_C3);
    let product = value(&json, "loes.D_m").powi(2) / (PRINTED_C3 * PRINTED_I_B);
    let root = (sum * sum / 4.0 - product).sqrt();
    let poles = [sum / 2.0 - root, sum / 2.0 + root];
    for (pole, paper) in poles.iter().zip([G_EST_POLE_1, G_EST_POLE_2]) {
        assert!(
            (pole / paper - 1.0).abs() < 1e-6,
            "pole -{pole} against eq. 2's -{paper}"
        );
    }
    let (json, _) = identify(&[g_est_closed_loop(&dir, Some(1))], &fit, &extra);
    assert!(warnings(&json).is_empty(), "{json:#}");
    for (name, truth) in truths {
        let (lo, hi) = ci95(&json, name).unwrap_or_else(|| panic!("{name}: no interval"));
        assert!(
            lo <= truth && truth <= hi,
            "{name}: {truth} not in [{lo}, {hi}]: {json:#}"
        );
        assert!(hi / lo < 1.02, "{name}: [{lo}, {hi}] is wide: {json:#}");
    }
}

/// `G_est` has three numbers (two poles and a gain); the LOES has five constants. With the
/// chamber's `C3` fitted as well, the data cannot separate it from the others: the command names
/// the four and gives no interval (the paper keeps the printed `C3` and `I_b`).
#[test]
fn eq_2_cannot_separate_the_chamber_from_the_other_loes_constants() {
    let dir = folder("g_est_c3");
    let (truths, extra) = loes_case();
    let extra: Vec<&str> = extra.iter().map(String::as_str).collect();
    let mut fit: Vec<&str> = vec!["loes.C3"];
    fit.extend(truths.iter().map(|(n, _)| *n));
    let (json, _) = identify(&[g_est_closed_loop(&dir, Some(1))], &fit, &extra);
    assert!(
        warnings(&json).iter().any(|w| w
            .contains("cannot separate loes.C3, loes.R7, loes.D_m, loes.k_sv")
            && w.contains("undetermined")),
        "{json:#}"
    );
    for name in fit {
        assert_eq!(ci95(&json, name), None, "{name}: {json:#}");
    }
}

/// The worked case's data, `examples/data/table1_fig9b_peaks.csv`, is Table 1's second column
/// (the peaks of Fig. 9b) as `src/model/paper.rs` holds it, for the three bending modes (the
/// paper's model has no other peaks, docs/model-notes.md item 9), each with half a unit of its
/// last printed digit as its uncertainty.
#[test]
fn the_table_1_peaks_file_is_the_papers_table_1() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/data/table1_fig9b_peaks.csv");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("f_Hz,sigma_Hz"));
    let rows: Vec<(f64, f64)> = lines
        .map(|l| {
            let (f, s) = l.split_once(',').unwrap();
            (f.parse().unwrap(), s.parse().unwrap())
        })
        .collect();
    let bending: Vec<_> = TABLE1.iter().filter(|r| r.mode.1 == 1).collect();
    assert_eq!(rows.len(), bending.len());
    for ((f, sigma), row) in rows.iter().zip(bending) {
        assert_eq!(*f, row.fig9b.hz, "{row:?}");
        assert_eq!(*sigma, row.fig9b.half_unit(), "{row:?}");
    }
}

/// The worked case's fourth fit (docs/identify.md: the complete model, `hub.I_H`,
/// `torsion_bar.k` and `plate.E` to Table 1's peaks) has exact sensitivities throughout: its
/// first peak (4.99 Hz, the bar all but cut) is one whose Newton steps on `d|H|²/dω` stop a few
/// ulps short of settling, from the round-off of the stiff model's resolvent, and must be taken
/// as settled there (`frf::peak_derivative`), not answered with central differences.
#[test]
fn the_table_1_calibration_has_exact_sensitivities() {
    let peaks = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/data/table1_fig9b_peaks.csv");
    let json = identify_json(&[
        "--peaks",
        &format!("r:acc_tip:{}", peaks.display()),
        "--preset",
        "complete",
        "--set",
        "hub.I_H=0.01",
        "--set",
        "torsion_bar.k=100",
        "--fit",
        "hub.I_H:1e-3:10",
        "--fit",
        "torsion_bar.k:1:1e5",
        "--fit",
        "plate.E",
    ]);
    for name in ["hub.I_H", "torsion_bar.k", "plate.E"] {
        assert_eq!(json["parameters"][name]["sensitivity"], "exact", "{json:#}");
    }
}

/// `--peaks`: the resonance peaks of the paper's model (preset `paper-fig9b`) with the plate's
/// modulus at 7.2e10 Pa, found by `hsp frf`'s peak search on a fine grid, give the modulus back
/// from the paper's 6.89e10 to 1e-6, each model peak on its measured one; the variance is known
/// (`s^2 = 1`).
#[test]
fn peaks_of_a_known_model_give_back_its_parameter() {
    let dir = folder("peaks");
    let truth = 7.2e10;
    let mut values = Values::from_start(&VARIABLES);
    hydraulic_slewing_plate::model::presets::apply(&mut values, "paper-fig9b").unwrap();
    set_by_name(&mut values, "plate.E", &truth.to_string()).unwrap();
    let p = Parameters::from_values(&values, &Experiment::default()).unwrap();
    let system = Assembled::new(&p.sliding()).unwrap();
    let lin = system
        .compiled()
        .linearize(&system.initial_state(), system.inputs());
    let response = frequency_response(&lin, "r", "acc_tip", 1.0, 60.0, 20000).unwrap();
    assert_eq!(response.peaks.len(), 3, "{:?}", response.peaks);
    let mut csv = String::from("f_Hz,sigma_Hz\n");
    for (f, _) in &response.peaks {
        csv.push_str(&format!("{f:?},0.01\n"));
    }
    let file = dir.join("peaks.csv");
    std::fs::write(&file, csv).unwrap();
    let json = identify_json(&[
        "--preset",
        "paper-fig9b",
        "--fit",
        "plate.E",
        "--peaks",
        &format!("r:acc_tip:{}", file.display()),
    ]);
    assert!(warnings(&json).is_empty(), "{json:#}");
    let v = json["parameters"]["plate.E"]["value"].as_f64().unwrap();
    assert!(
        (v / truth - 1.0).abs() < 1e-6,
        "{v} against {truth}: {json:#}"
    );
    assert_eq!(json["variance"].as_f64(), Some(1.0), "{json:#}");
    let peaks = &json["peaks"][0];
    for (m, f) in peaks["fitted_Hz"]
        .as_array()
        .unwrap()
        .iter()
        .zip(&response.peaks)
    {
        assert!((m.as_f64().unwrap() / f.0 - 1.0).abs() < 1e-6, "{peaks}");
    }
}

/// A time series of the FMU (FMI 2.0 co-simulation, through its C entry points) with the
/// parameters `TRUTH`: the default move plus a chirp of `r` (0.1 V, 0.5 to 20 Hz over the 6 s),
/// `r` held over each 5 ms step, `y_pot` and `acc_tip` read at each point, each output with
/// Gaussian noise of 1 % of its RMS from `seed`; written as `dir/series.csv`.
fn series_of_the_fmu(dir: &Path, seed: u64) -> PathBuf {
    series_of_the_fmu_over(dir, seed, 1200)
}

/// [`series_of_the_fmu`] over `steps` of 5 ms, the chirp's sweep over the 6 s as there.
fn series_of_the_fmu_over(dir: &Path, seed: u64, steps: usize) -> PathBuf {
    let fmu = Fmu::new();
    for (name, v) in TRUTH {
        assert_eq!(fmu.set_real(name, v), Fmi2Status::Ok, "{}", fmu.last());
    }
    let (h, stop) = (0.005, 6.0);
    let r = |t: f64| {
        let (f0, f1) = (0.5, 20.0);
        0.1 * (2.0 * std::f64::consts::PI * (f0 * t + (f1 - f0) * t * t / (2.0 * stop))).sin()
    };
    assert_eq!(fmu.init(0.0), Fmi2Status::Ok, "{}", fmu.last());
    let mut rows: Vec<[f64; 4]> = Vec::new();
    for k in 0..=steps {
        let t = k as f64 * h;
        assert_eq!(fmu.set_real("r", r(t)), Fmi2Status::Ok);
        let y = ["y_pot", "acc_tip"].map(|n| fmu.get_real(n).1);
        rows.push([t, r(t), y[0], y[1]]);
        if k < steps {
            assert_eq!(fmu.step(t, h), Fmi2Status::Ok, "{}", fmu.last());
        }
    }
    let mut noise = Normal::new(seed);
    let rms: Vec<f64> = (2..4)
        .map(|c| (rows.iter().map(|r| r[c] * r[c]).sum::<f64>() / rows.len() as f64).sqrt())
        .collect();
    let mut csv = String::from("time,r,y_pot,acc_tip\n");
    for row in &rows {
        let y_pot = row[2] + 0.01 * rms[0] * noise.next();
        let acc_tip = row[3] + 0.01 * rms[1] * noise.next();
        csv.push_str(&format!(
            "{:?},{:?},{y_pot:?},{acc_tip:?}\n",
            row[0], row[1]
        ));
    }
    let file = dir.join("series.csv");
    std::fs::write(&file, csv).unwrap();
    file
}

/// `--series`: the default move plus a chirp of `r` with 1 % noise gives the three parameters
/// of the synthetic case back within their intervals, and the same as the frequency-response fit
/// (seed 1) within the interval of their difference (the two intervals' half-widths added in
/// quadrature: independent noise).
#[test]
fn a_time_series_gives_the_parameters_of_the_frf_fit() {
    let dir = folder("series");
    let file = series_of_the_fmu(&dir, 7);
    let fit: Vec<&str> = TRUTH.iter().map(|(n, _)| *n).collect();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_hsp"));
    cmd.args(["identify", "--json", "--series", file.to_str().unwrap()]);
    for f in &fit {
        cmd.args(["--fit", f]);
    }
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let series: Json = serde_json::from_slice(&out.stdout).unwrap();
    eprintln!("{series:#}");
    assert!(warnings(&series).is_empty(), "{series:#}");
    let frf = fit_three(&folder("series_frf"), 1, None);
    for (name, truth) in TRUTH {
        let (lo, hi) = ci95(&series, name).unwrap_or_else(|| panic!("{name}: no interval"));
        assert!(
            lo <= truth && truth <= hi,
            "{name}: {truth} not in [{lo}, {hi}]: {series:#}"
        );
        let (flo, fhi) = ci95(&frf, name).unwrap();
        let value = |j: &Json| j["parameters"][name]["value"].as_f64().unwrap().ln();
        let half = ((hi.ln() - lo.ln()).powi(2) + (fhi.ln() - flo.ln()).powi(2)).sqrt() / 2.0;
        assert!(
            (value(&series) - value(&frf)).abs() <= half,
            "{name}: series {} against FRF {}, difference beyond its interval ±{half} in ln",
            value(&series).exp(),
            value(&frf).exp()
        );
    }
}

/// `--series-sensitivities forward` (forward sensitivities of the simulation) against central
/// differences of the simulation, on the first second of the series above (`plate.zeta` set to
/// its truth, the other two fitted): the same minimum to the optimiser's tolerance, far inside
/// the intervals, and the same intervals to the central differences' error (the simulation's
/// tolerance 1e-6 over their step 1e-4: up to 1e-2 of a residual's sensitivity; 1e-3 asked,
/// 6e-6 measured without `--set plate.zeta`). Both intervals hold the truth.
#[test]
fn forward_sensitivities_and_central_differences_give_the_same_series_fit() {
    let dir = folder("series_forward");
    let file = series_of_the_fmu_over(&dir, 3, 200);
    let args = [
        "--series",
        file.to_str().unwrap(),
        "--fit",
        "servo_valve.beta",
        "--fit",
        "torsion_bar.k",
        "--set",
        "plate.zeta=0.03",
    ];
    let central = identify_json(&args);
    let forward = identify_json(&[&args[..], &["--series-sensitivities", "forward"]].concat());
    assert!(forward["derivatives"].as_u64().unwrap() > 0, "{forward:#}");
    assert_eq!(central["derivatives"].as_u64(), Some(0), "{central:#}");
    for (name, truth) in [TRUTH[0], TRUTH[2]] {
        let why = "--series-sensitivities forward";
        same_fit(&forward, &central, name, why, (1e-3, 1e-3));
        let (lo, hi) = ci95(&forward, name).unwrap();
        assert!(
            lo <= truth && truth <= hi,
            "{name}: {truth} not in [{lo}, {hi}]"
        );
    }
}

/// A fit that is not convex: the plate's modulus started 2.9x too high, where the response's
/// plate resonances sit on other measured peaks. One start ends away from the truth (on a local
/// minimum, or unconverged in its iterations); `--starts 6` (the start and 5 drawn in the box)
/// finds the truth within its interval, and lists the minima it saw.
#[test]
fn multi_start_finds_the_modulus_a_single_start_misses() {
    let dir = folder("starts");
    // the truth: the FMU's start value (the data are generated with no setting)
    let start = Values::from_start(&VARIABLES);
    let i = VARIABLES.iter().position(|v| v.name == "plate.E").unwrap();
    let truth = start.real(i);
    let frfs = synthetic(&dir, &[], &["acc_tip"], Some(3));
    let common = ["--set", "plate.E=2e11", "--max-iterations", "60"];
    let fit = ["plate.E:1e10:4e11"];
    let (single, _) = identify(&frfs, &fit, &common);
    let (multi, stderr) = identify(&frfs, &fit, &[&common[..], &["--starts", "6"]].concat());
    let value = |j: &Json| j["parameters"]["plate.E"]["value"].as_f64().unwrap();
    let (lo, hi) = ci95(&multi, "plate.E").expect("an interval");
    assert!(
        lo <= truth && truth <= hi,
        "truth {truth} outside [{lo}, {hi}]: {stderr}"
    );
    assert!(
        !(lo..=hi).contains(&value(&single)),
        "the single start ended at {} inside the interval: the case is convex",
        value(&single)
    );
    let (c1, c6) = (
        single["cost"].as_f64().unwrap(),
        multi["cost"].as_f64().unwrap(),
    );
    assert!(c1 > 10.0 * c6, "single-start cost {c1}, multi-start {c6}");
    // The starts: the configuration's first, each within the box, the best one's end is the fit.
    let starts = multi["starts"].as_array().unwrap();
    assert_eq!(starts.len(), 6);
    assert_eq!(starts[0]["start"]["plate.E"].as_f64(), Some(2e11));
    for s in starts {
        let e = s["start"]["plate.E"].as_f64().unwrap();
        assert!((1e10..=4e11).contains(&e), "{s}");
    }
    let minima = multi["minima"].as_array().unwrap();
    assert!(minima.len() >= 2, "one minimum only: {minima:?}");
    let best = &starts[minima[0]["start"].as_u64().unwrap() as usize];
    assert_eq!(best["value"]["plate.E"].as_f64(), Some(value(&multi)));
    assert_eq!(minima[0]["cost"].as_f64(), Some(c6));
}
