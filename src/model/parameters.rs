//! The typed parameter set of the FMU, read from its variable values, and the checks that the
//! XML's `min`/`max` cannot express (strictly positive physical constants).

use crate::fmu::logging::Short;
use crate::fmu::variables::{check_value, Value, Values};
use crate::fmu::{Causality, Experiment, Kind};
use crate::fragments::controller::ControllerParameters;
use crate::fragments::loes::LoesParameters;
use crate::fragments::plate::{Formulation, PlateParameters, Root, MAX_FUNCTIONS};
use crate::fragments::reference::MoveParameters;
use crate::fragments::servo_valve::{CoilDrive, ServoValveParameters};
use crate::fragments::validity::Limits;
use crate::solver::{Atol, Method, SolverOptions};

use super::assembly::Assembled;
use super::variables::{idx, VARIABLES};

/// Which hydraulic model drives the rotor (`hydraulics.model`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HydraulicsModel {
    /// The low-order equivalent system of Fig. 3 and eq. 1 (`hydraulics.model = 1`).
    Loes,
    /// The full servo valve of Fig. 2b, BG1-BG3 (`hydraulics.model = 2`).
    ServoValve,
}

/// Every parameter of the FMU, typed.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameters {
    pub hydraulics: HydraulicsModel,
    /// Whether the motor drives the hub through the torsion bar (`hydraulics.motor_coupled`).
    pub motor_coupled: bool,
    pub loes: LoesParameters,
    pub servo_valve: ServoValveParameters,
    pub controller: ControllerParameters,
    /// The command generator's move (`reference.*`).
    pub reference: MoveParameters,
    /// The material limits of the validity monitors and the bar's diameter.
    pub limits: Limits,
    /// The plate and hub (`plate.*`, `hub.I_H`).
    pub plate: PlateParameters,
    /// Torsion-bar stiffness \[N m/rad\] (`torsion_bar.k`).
    pub torsion_bar_k: f64,
    /// Torsion-bar structural damping ratio \[-\] (`torsion_bar.zeta`).
    pub torsion_bar_zeta: f64,
    pub method: Method,
    pub rtol: f64,
    /// Absolute tolerance as a fraction of each state's nominal value.
    pub atol: f64,
    pub max_step: f64,
    pub max_steps: u64,
    /// Co-simulation: let steps run past communication points while the inputs are unchanged
    /// (`solver.dense_output`).
    pub dense_output: bool,
    /// The experiment's stop time, if the importer gave one: no step goes past it.
    pub stop_time: Option<f64>,
}

/// Parameters that must be strictly positive (the XML says `min="0"`, which admits zero).
const POSITIVE: &[usize] = &[
    idx::LOES_C3,
    idx::LOES_I_B,
    idx::LOES_R7,
    idx::LOES_D_M,
    idx::LOES_K_SV,
    idx::CONTROLLER_K_POT,
    idx::CONTROLLER_E_MAX,
    idx::SERVO_VALVE_P_SUPPLY,
    idx::SERVO_VALVE_RHO,
    idx::SERVO_VALVE_BETA,
    idx::SERVO_VALVE_CD,
    idx::SERVO_VALVE_DP_CR,
    idx::SERVO_VALVE_R_BOB,
    idx::SERVO_VALVE_L_BOB,
    idx::SERVO_VALVE_K_PHI,
    idx::SERVO_VALVE_M_F,
    idx::SERVO_VALVE_B_F,
    idx::SERVO_VALVE_K_F,
    idx::SERVO_VALVE_K_W,
    idx::SERVO_VALVE_D_0,
    idx::SERVO_VALVE_D_N,
    idx::SERVO_VALVE_X_F0,
    idx::SERVO_VALVE_V_H,
    idx::SERVO_VALVE_D_S,
    idx::SERVO_VALVE_M_V,
    idx::SERVO_VALVE_B_V,
    idx::SERVO_VALVE_K_V,
    idx::SERVO_VALVE_W,
    idx::SERVO_VALVE_C_R,
    idx::SERVO_VALVE_X_V_MAX,
    idx::SERVO_VALVE_V_1,
    idx::SERVO_VALVE_R_LEAK,
    idx::SERVO_VALVE_D_M,
    idx::SERVO_VALVE_I_M,
    idx::SERVO_VALVE_B_M,
    idx::SOLVER_RTOL,
    idx::SOLVER_ATOL,
    idx::SOLVER_MAX_STEP,
    idx::PLATE_E,
    idx::PLATE_RHO,
    idx::PLATE_A,
    idx::PLATE_B,
    idx::PLATE_H,
    idx::TORSION_BAR_K,
    idx::TORSION_BAR_D,
    idx::TORSION_BAR_TAU_Y,
    idx::PLATE_SIGMA_Y,
    idx::REFERENCE_DURATION,
];

/// The model-specific check of a value being set (type and range are checked before).
pub fn check(index: usize, value: &Value) -> Result<(), String> {
    if POSITIVE.contains(&index) {
        if let Value::Real(v) = value {
            if *v <= 0.0 {
                return Err(format!(
                    "{}: must be positive, got {v}",
                    VARIABLES[index].name
                ));
            }
        }
    }
    Ok(())
}

impl Parameters {
    /// Reads the parameters from the FMU's values; the tolerance of `fmi2SetupExperiment`, when
    /// given, overrides `solver.rtol`.
    pub fn from_values(values: &Values, experiment: &Experiment) -> Result<Self, String> {
        for &i in POSITIVE {
            check(i, values.get(i))?;
        }
        check_magnitudes(values)?;
        let hydraulics = match values.integer(idx::HYDRAULICS_MODEL) {
            1 => HydraulicsModel::Loes,
            2 => HydraulicsModel::ServoValve,
            other => {
                return Err(format!(
                    "hydraulics.model: {other} is not a hydraulic model (1 = LOES, 2 = full servo valve)"
                ))
            }
        };
        let method = match values.integer(idx::SOLVER_METHOD) {
            1 => Method::Rodas5P,
            2 => Method::Radau5,
            other => {
                return Err(format!(
                    "solver.method: {other} is not a method (1 = Rodas5P, 2 = Radau5)"
                ))
            }
        };
        let max_steps = values.integer(idx::SOLVER_MAX_STEPS);
        if max_steps < 1 {
            return Err(format!(
                "solver.max_steps: must be at least 1, got {max_steps}"
            ));
        }
        let formulation = match values.integer(idx::PLATE_FORMULATION) {
            1 => Formulation::Paper,
            2 => Formulation::Consistent,
            other => {
                return Err(format!(
                    "plate.formulation: {other} is not a formulation (1 = paper, 2 = consistent)"
                ))
            }
        };
        let root = match values.integer(idx::PLATE_ROOT) {
            1 => Root::Hub,
            2 => Root::Locked,
            other => {
                return Err(format!(
                    "plate.root: {other} is not a root condition (1 = hub, 2 = locked)"
                ))
            }
        };
        let count = |i: usize, name: &str| -> Result<usize, String> {
            let v = values.integer(i);
            if (1..=MAX_FUNCTIONS as i32).contains(&v) {
                Ok(v as usize)
            } else {
                Err(format!("{name}: must be in 1..={MAX_FUNCTIONS}, got {v}"))
            }
        };
        let plate = PlateParameters {
            formulation,
            root,
            n: count(idx::PLATE_N, "plate.N")?,
            m: count(idx::PLATE_M, "plate.M")?,
            e: values.real(idx::PLATE_E),
            rho: values.real(idx::PLATE_RHO),
            a: values.real(idx::PLATE_A),
            b: values.real(idx::PLATE_B),
            h: values.real(idx::PLATE_H),
            nu: values.real(idx::PLATE_NU),
            zeta: values.real(idx::PLATE_ZETA),
            i_h: values.real(idx::HUB_I_H),
            cd: values.real(idx::PLATE_CD),
            rho_air: values.real(idx::PLATE_RHO_AIR),
            x1: values.real(idx::PLATE_X1),
            y1: values.real(idx::PLATE_Y1),
            x2: values.real(idx::PLATE_X2),
            y2: values.real(idx::PLATE_Y2),
        };
        plate.validate()?;
        let parameters = Parameters {
            hydraulics,
            motor_coupled: values.boolean(idx::HYDRAULICS_MOTOR_COUPLED),
            loes: LoesParameters {
                c3: values.real(idx::LOES_C3),
                i_b: values.real(idx::LOES_I_B),
                r7: values.real(idx::LOES_R7),
                d_m: values.real(idx::LOES_D_M),
                k_sv: values.real(idx::LOES_K_SV),
            },
            servo_valve: ServoValveParameters {
                p_supply: values.real(idx::SERVO_VALVE_P_SUPPLY),
                p_tank: values.real(idx::SERVO_VALVE_P_TANK),
                rho: values.real(idx::SERVO_VALVE_RHO),
                beta: values.real(idx::SERVO_VALVE_BETA),
                cd: values.real(idx::SERVO_VALVE_CD),
                dp_cr: values.real(idx::SERVO_VALVE_DP_CR),
                r_bob: values.real(idx::SERVO_VALVE_R_BOB),
                l_bob: values.real(idx::SERVO_VALVE_L_BOB),
                drive: CoilDrive::from_code(values.integer(idx::SERVO_VALVE_DRIVE))?,
                g_i: values.real(idx::SERVO_VALVE_G_I),
                k_i: values.real(idx::SERVO_VALVE_K_I),
                u_c: values.real(idx::SERVO_VALVE_U_C),
                k_phi: values.real(idx::SERVO_VALVE_K_PHI),
                m_f: values.real(idx::SERVO_VALVE_M_F),
                b_f: values.real(idx::SERVO_VALVE_B_F),
                k_f: values.real(idx::SERVO_VALVE_K_F),
                k_w: values.real(idx::SERVO_VALVE_K_W),
                d_0: values.real(idx::SERVO_VALVE_D_0),
                d_n: values.real(idx::SERVO_VALVE_D_N),
                x_f0: values.real(idx::SERVO_VALVE_X_F0),
                v_h: values.real(idx::SERVO_VALVE_V_H),
                d_s: values.real(idx::SERVO_VALVE_D_S),
                m_v: values.real(idx::SERVO_VALVE_M_V),
                b_v: values.real(idx::SERVO_VALVE_B_V),
                k_v: values.real(idx::SERVO_VALVE_K_V),
                w: values.real(idx::SERVO_VALVE_W),
                c_r: values.real(idx::SERVO_VALVE_C_R),
                x_v_max: values.real(idx::SERVO_VALVE_X_V_MAX),
                v_1: values.real(idx::SERVO_VALVE_V_1),
                r_leak: values.real(idx::SERVO_VALVE_R_LEAK),
                d_m: values.real(idx::SERVO_VALVE_D_M),
                i_m: values.real(idx::SERVO_VALVE_I_M),
                b_m: values.real(idx::SERVO_VALVE_B_M),
            },
            controller: ControllerParameters {
                a1: values.real(idx::CONTROLLER_A1),
                a2: values.real(idx::CONTROLLER_A2),
                k_pot: values.real(idx::CONTROLLER_K_POT),
                e_max: values.real(idx::CONTROLLER_E_MAX),
                saturation: values.boolean(idx::CONTROLLER_SATURATION),
                external: values.boolean(idx::CONTROLLER_EXTERNAL),
            },
            reference: MoveParameters {
                angle: values.real(idx::REFERENCE_ANGLE),
                t_start: values.real(idx::REFERENCE_T_START),
                duration: values.real(idx::REFERENCE_DURATION),
            },
            limits: Limits {
                plate_sigma_y: values.real(idx::PLATE_SIGMA_Y),
                bar_d: values.real(idx::TORSION_BAR_D),
                bar_tau_y: values.real(idx::TORSION_BAR_TAU_Y),
            },
            plate,
            torsion_bar_k: values.real(idx::TORSION_BAR_K),
            torsion_bar_zeta: values.real(idx::TORSION_BAR_ZETA),
            method,
            rtol: experiment
                .tolerance
                .unwrap_or(values.real(idx::SOLVER_RTOL)),
            atol: values.real(idx::SOLVER_ATOL),
            max_step: values.real(idx::SOLVER_MAX_STEP),
            max_steps: max_steps as u64,
            dense_output: values.boolean(idx::SOLVER_DENSE_OUTPUT),
            stop_time: experiment.stop_time,
        };
        parameters.check_derived(values)?;
        Ok(parameters)
    }

    /// The integrator's options for the assembled model: the absolute tolerance scaled by each
    /// state's nominal value, since the states span many decades (rad, kg m^2/s, m^3).
    pub fn solver_options(&self, system: &Assembled) -> SolverOptions {
        SolverOptions {
            method: self.method,
            rtol: self.rtol,
            atol: Atol::Vector(system.nominal().iter().map(|n| n * self.atol).collect()),
            max_step: self.max_step,
            max_steps: self.max_steps,
            ..SolverOptions::default()
        }
    }
}

/// The magnitudes a parameter or derived quantity may have, in SI units. The model's largest
/// constant is the bulk modulus (about 1e9 Pa), its smallest the chamber compliances (about
/// 1e-17 m^5/N); nothing physical in it comes near 1e-50 or 1e50. Inside this window the model's
/// products and squares (energies, Jacobian entries) stay far inside double precision's range
/// (1e-308 to 1e308); outside it they overflow or underflow, and the model would fail somewhere
/// that cannot name the cause.
pub const MAGNITUDES: std::ops::RangeInclusive<f64> = 1e-50..=1e50;

/// Every nonzero Real parameter within [`MAGNITUDES`]; the error names it.
fn check_magnitudes(values: &Values) -> Result<(), String> {
    for (i, var) in VARIABLES.iter().enumerate() {
        if var.causality != Causality::Parameter {
            continue;
        }
        if let Value::Real(v) = values.get(i) {
            if *v != 0.0 && !MAGNITUDES.contains(&v.abs()) {
                return Err(format!(
                    "{}: {} is physically absurd: |value| must lie between {} and {} in SI units",
                    var.name,
                    Short(*v),
                    Short(*MAGNITUDES.start()),
                    Short(*MAGNITUDES.end())
                ));
            }
        }
    }
    Ok(())
}

/// Of the parameters a derived quantity comes from, the one farthest (in decades) from its start
/// value: the likely culprit when the quantity is out of range.
fn culprit(values: &Values, from: &[usize]) -> String {
    let decades = |i: usize| match (values.get(i), VARIABLES[i].kind) {
        (Value::Real(v), Kind::Real { start: Some(s), .. }) if *v != 0.0 && s != 0.0 => {
            (v.abs() / s.abs()).log10().abs()
        }
        _ => 0.0,
    };
    let worst = from
        .iter()
        .copied()
        .max_by(|&a, &b| decades(a).total_cmp(&decades(b)))
        .unwrap_or(from[0]);
    let others: Vec<&str> = from
        .iter()
        .filter(|&&i| i != worst)
        .map(|&i| VARIABLES[i].name)
        .collect();
    let mut text = format!("{} = {}", VARIABLES[worst].name, Short(values.real(worst)));
    if !others.is_empty() {
        text += &format!(" (with {})", others.join(", "));
    }
    text
}

impl Parameters {
    /// Checks the quantities the model derives from several parameters: masses, stiffnesses,
    /// compliances, the plate's frequency scale and the hydraulic energies at supply pressure
    /// must be finite, positive and within [`MAGNITUDES`]. The error names the parameter farthest
    /// from its default among those the quantity comes from.
    fn check_derived(&self, values: &Values) -> Result<(), String> {
        self.servo_valve.validate()?;
        self.reference.validate()?;
        let pl = &self.plate;
        let sv = &self.servo_valve;
        let rigidity = pl.e * pl.h.powi(3) / (12.0 * (1.0 - pl.nu * pl.nu));
        let derived: [(&str, f64, &[usize]); 8] = [
            (
                "the plate's mass rho a b h",
                pl.rho * pl.a * pl.b * pl.h,
                &[idx::PLATE_RHO, idx::PLATE_A, idx::PLATE_B, idx::PLATE_H],
            ),
            (
                "the plate's flexural rigidity E h^3 / (12 (1 - nu^2))",
                rigidity,
                &[idx::PLATE_E, idx::PLATE_H, idx::PLATE_NU],
            ),
            (
                "the hub's total inertia I_H + 2 I_P",
                pl.hub_total_inertia(),
                &[
                    idx::HUB_I_H,
                    idx::PLATE_RHO,
                    idx::PLATE_H,
                    idx::PLATE_A,
                    idx::PLATE_B,
                ],
            ),
            (
                "the plate's frequency scale sqrt(D / (rho h)) / a^2",
                (rigidity / pl.areal_mass()).sqrt() / (pl.a * pl.a),
                &[idx::PLATE_E, idx::PLATE_H, idx::PLATE_RHO, idx::PLATE_A],
            ),
            (
                "the control-chamber compliance V_H / beta",
                sv.v_h / sv.beta,
                &[idx::SERVO_VALVE_V_H, idx::SERVO_VALVE_BETA],
            ),
            (
                "the actuator-chamber compliance V_1 / beta",
                sv.v_1 / sv.beta,
                &[idx::SERVO_VALVE_V_1, idx::SERVO_VALVE_BETA],
            ),
            (
                "the hydraulic energy at supply pressure p_s^2 (V_1 + V_H) / beta",
                sv.p_supply * sv.p_supply * (sv.v_1 + sv.v_h) / sv.beta,
                &[
                    idx::SERVO_VALVE_P_SUPPLY,
                    idx::SERVO_VALVE_V_1,
                    idx::SERVO_VALVE_V_H,
                    idx::SERVO_VALVE_BETA,
                ],
            ),
            (
                "the spool's null flow gain Cd w sqrt((p_s - p_t) / rho)",
                sv.flow_gain(),
                &[
                    idx::SERVO_VALVE_CD,
                    idx::SERVO_VALVE_W,
                    idx::SERVO_VALVE_P_SUPPLY,
                    idx::SERVO_VALVE_P_TANK,
                    idx::SERVO_VALVE_RHO,
                ],
            ),
        ];
        for (what, v, from) in derived {
            if !(v.is_finite() && MAGNITUDES.contains(&v)) {
                return Err(format!(
                    "{}: {what} = {} is not finite, positive and between {} and {} (SI)",
                    culprit(values, from),
                    Short(v),
                    Short(*MAGNITUDES.start()),
                    Short(*MAGNITUDES.end())
                ));
            }
        }
        Ok(())
    }
}

/// Sets a variable by its name from text (`--set loes.C3=6e-11`), with the FMU's own checks.
pub fn set_by_name(values: &mut Values, name: &str, text: &str) -> Result<(), String> {
    let index = VARIABLES
        .iter()
        .position(|v| v.name == name)
        .ok_or_else(|| format!("unknown variable '{name}'"))?;
    let var = &VARIABLES[index];
    if !var.settable_before_initialization() {
        return Err(format!("'{name}' is not a parameter or input"));
    }
    let value = match var.kind {
        Kind::Real { .. } => Value::Real(
            text.parse()
                .map_err(|_| format!("{name}: '{text}' is not a number"))?,
        ),
        Kind::Integer { .. } => Value::Integer(
            text.parse()
                .map_err(|_| format!("{name}: '{text}' is not an integer"))?,
        ),
        Kind::Boolean { .. } => Value::Boolean(match text {
            "true" | "1" => true,
            "false" | "0" => false,
            _ => return Err(format!("{name}: '{text}' is not true or false")),
        }),
        Kind::String { .. } => Value::String(text.to_string()),
    };
    check_value(var, &value)?;
    check(index, &value)?;
    values.set(index, value);
    Ok(())
}
