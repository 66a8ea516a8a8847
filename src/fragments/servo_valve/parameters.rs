//! The constants of the full servo valve and actuator, with their sources and reasons, and the
//! checks that reject physically absurd values by name at initialisation.

/// The vane motor's displacement \[m^3/rad\]: 10 cm^3/rad (63 cm^3/rev), from the torque budget
/// of [`ServoValveParameters::d_m`].
pub const D_M: f64 = 1e-5;
/// The LOES's identified displacement \[m^3/rad\] (0.5 L/rev), for which the valve's metering
/// was first sized: scaling the port width by `D_M / LOES_D_M` keeps `k_sv / D_m`, and so
/// `G_est`.
pub const LOES_D_M: f64 = 8.04e-5;
use super::super::orifice::OrificeFluid;
use crate::fragments::rules;
use crate::math::dual::Real;

/// How the power amplifier drives the torque motor's coil (`servo_valve.drive`).
///
/// The paper drives the coil from a "linear power operational amplifier": a voltage. The coil's
/// current then lags the command by `R_bob / L_bob`, which is the 65 1/s pole of `G_est`. Many
/// installations of two-stage valves use a current-feedback amplifier instead (the coil's
/// resistance drifts 0.4 %/K with its temperature, a current does not): the coil's lag moves
/// to the current loop's pole, far above the band, and `G_est` no longer describes the valve.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum CoilDrive {
    /// 1: the coil voltage is the command `e_in` (the paper's amplifier; reproduces `G_est`).
    Voltage,
    /// 2: a current-feedback amplifier: coil voltage `u = K_i (G_i e_in - i)`, limited to the
    /// compliance voltage `+-U_c`.
    Current,
}

/// Every physical constant of the full servo valve and actuator (SI units). The FMU names are
/// `servo_valve.<name>` with the names in brackets. Ranges quoted are those of two-stage
/// flapper-nozzle valves with mechanical feedback (docs/model.md, "The full servo valve").
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ServoValveParameters<S = f64> {
    /// Supply pressure \[Pa\] (`p_supply`): 140 bar, middle of the 70-210 bar range.
    pub p_supply: S,
    /// Tank (return) pressure \[Pa\] (`p_tank`): 0 (gauge).
    pub p_tank: S,
    /// Oil density \[kg/m^3\] (`rho`): ISO VG 32 mineral oil, 860 (range 850-870).
    pub rho: S,
    /// Effective bulk modulus \[Pa\] (`beta`): 1.4 GPa (oil without entrained air; range 0.7-1.6).
    pub beta: S,
    /// Discharge coefficient of every orifice \[-\] (`Cd`): 0.61, sharp-edged.
    pub cd: S,
    /// Laminar-transition pressure drop of the orifice law \[Pa\] (`dp_cr`): 0.05 bar, from
    /// `Re_cr` = 10 at the inlet orifice, rounded up (see [`crate::fragments::orifice`]).
    pub dp_cr: S,
    /// Coil resistance \[ohm\] (`R_bob`): 80, bottom of the 80-200 range.
    pub r_bob: S,
    /// Coil inductance \[H\] (`L_bob`): fitted to `G_est`, 1.252 H, so that the voltage-driven
    /// coil's lag `R_bob / L_bob` = 64 1/s is the identified 65 1/s pole. Above the 0.1-1 H of
    /// single coils: the two coils of a torque motor in series, at low frequency, reach it.
    pub l_bob: S,
    /// How the power amplifier drives the coil (`drive`): a current (a current-feedback
    /// amplifier, the default: without the coil's 65 1/s lag in the position loop the loop keeps
    /// its damping, docs/model.md) or a voltage (the paper's linear power operational
    /// amplifier, the setup of the `G_est` fit: [`ServoValveParameters::voltage_driven`]).
    pub drive: CoilDrive,
    /// Transconductance of the current-feedback amplifier \[A/V\] (`G_i`): 12.5 mA/V, the
    /// voltage drive's DC `1 / R_bob`, so that 10 V commands the rated 125 mA either way.
    pub g_i: S,
    /// Loop gain of the current-feedback amplifier \[V/A\] (`K_i`): the coil voltage per ampere of
    /// current error, `u = K_i (G_i e_in - i)`. 7.8 kV/A puts the current loop's pole
    /// `(R_bob + K_i) / L_bob` at 1.0 kHz (a servo amplifier's current loop, far above the
    /// valve's 120 Hz) and leaves a DC current error `R_bob / (R_bob + K_i)` of 1.0 %.
    pub k_i: S,
    /// Compliance voltage of the current-feedback amplifier \[V\] (`U_c`): the most voltage it
    /// can put across the coil, 12 V as the voltage amplifier's rail (a +-15 V supply less the
    /// output stage's headroom). It limits how fast the current can change, `U_c / L_bob`.
    pub u_c: S,
    /// Torque-motor force constant at the nozzle \[N/A\] (`k_phi`): fitted to `G_est` (it sets the
    /// loop gain), 0.1692 N/A: 10 V drive 125 mA, 21 mN, which the wire balances at 0.4 mm of
    /// spool travel, the full stroke.
    pub k_phi: S,
    /// Effective armature-flapper mass at the nozzle \[kg\] (`m_f`): 0.02 g, so that with
    /// `k_f + k_w` = 353 N/m the torque motor is at 670 Hz (range 500-1000 Hz).
    pub m_f: S,
    /// Flapper viscous friction \[N s/m\] (`b_f`): 0.06, torque-motor damping ratio
    /// `b_f / (2 sqrt((k_f + k_w) m_f))` = 0.36 (range 0.3-0.5).
    pub b_f: S,
    /// Flapper pivot (flexure tube, net of the magnetic spring) stiffness at the nozzle \[N/m\]
    /// (`k_f`): 300.
    pub k_f: S,
    /// Feedback-wire stiffness at the nozzle \[N/m\] (`k_w`): fitted to `G_est`, 53.41 N/m. Its
    /// share of the flapper stiffness sets the valve-stage pole
    /// `K_qp k_w / (A_s (k_f + k_w))`, the identified 753 1/s.
    pub k_w: S,
    /// Inlet orifice diameter, R1 = R2 \[m\] (`d_0`): 0.25 mm (range 0.2-0.3).
    pub d_0: S,
    /// Nozzle diameter \[m\] (`d_n`): 0.4 mm (range 0.3-0.5).
    pub d_n: S,
    /// Flapper-nozzle null gap \[m\] (`x_f0`): `d_0^2 / (4 d_n)` = 39 um (range 25-50), so that the
    /// nozzle curtain area equals the inlet area and the control pressures rest at `p_s / 2`.
    pub x_f0: S,
    /// Volume of each control chamber \[m^3\] (`V_H`): 0.1 cm^3 (spool end and its drilling).
    pub v_h: S,
    /// Spool diameter \[m\] (`d_s`): 5 mm (range 4-8).
    pub d_s: S,
    /// Spool mass \[kg\] (`m_v`): 3 g (range 2-10).
    pub m_v: S,
    /// Spool viscous friction \[N s/m\] (`b_v`): 1 (oil film on a 5 mm spool).
    pub b_v: S,
    /// Spool centring spring \[N/m\] (`k_v`): weak; the feedback wire positions the spool.
    pub k_v: S,
    /// Area gradient of each metering edge \[m\] (`w`): the full spool periphery `pi d_s`.
    pub w: S,
    /// Radial clearance of the spool \[m\] (`c_r`): 2.5 um; rounds the critical-centre null.
    pub c_r: S,
    /// Spool stroke \[m\] (`x_v_max`): +-0.4 mm (range 0.3-0.5), where the spool meets its end
    /// stops ([`super::limits::spool_stop_spring`]).
    pub x_v_max: S,
    /// Volume of each actuator chamber with its line \[m^3\] (`V_1`): 150 cm^3, half the swept
    /// volume of a +-90 deg vane stroke (`D_m pi / 2` = 126 cm^3) plus 25 cm^3 of line (0.5 m of
    /// 8 mm bore).
    pub v_1: S,
    /// Internal leakage resistance of the vane motor \[N s/m^5\] (`R_leak`): 1 L/min at 100 bar.
    pub r_leak: S,
    /// Vane motor displacement \[m^3/rad\] (`D_m`): 8.04e-5 (0.5 L/rev), the LOES's `D_m`.
    pub d_m: S,
    /// Rotor inertia \[kg m^2\] (`I_m`): the paper's `I_b`.
    pub i_m: S,
    /// Rotor viscous friction \[N m s/rad\] (`b_m`): 0.1 (vane seal drag); the fit does not
    /// depend on it.
    pub b_m: S,
    /// Coulomb (running) friction torque of the vane motor \[N m\] (`T_c`): 1.0, a running
    /// pressure of 1 bar over `D_m` ([`crate::fragments::vane_motor::friction`]; 0: none).
    pub t_c: S,
    /// Breakaway (static) friction torque \[N m\] (`T_s`): 1.5, a breakaway pressure of 1.5 bar;
    /// at least `T_c`.
    pub t_s: S,
    /// Stribeck speed \[rad/s\] (`omega_s`): 0.5, over which the friction falls from `T_s` to
    /// `T_c` (15 mm/s at the vane tips' 30 mm radius).
    pub omega_s: S,
}

impl<S: Copy> ServoValveParameters<S> {
    /// The parameters `f(self, other)` field by field, the others (choices, counts) `self`'s:
    /// the one list of the real fields, for carrying them in another scalar (a value and its
    /// derivative, [`crate::math::dual::Dual`]).
    pub fn zip<T: Copy, U>(
        &self,
        other: &ServoValveParameters<T>,
        f: impl Fn(S, T) -> U,
    ) -> ServoValveParameters<U> {
        ServoValveParameters {
            p_supply: f(self.p_supply, other.p_supply),
            p_tank: f(self.p_tank, other.p_tank),
            rho: f(self.rho, other.rho),
            beta: f(self.beta, other.beta),
            cd: f(self.cd, other.cd),
            dp_cr: f(self.dp_cr, other.dp_cr),
            r_bob: f(self.r_bob, other.r_bob),
            l_bob: f(self.l_bob, other.l_bob),
            drive: self.drive,
            g_i: f(self.g_i, other.g_i),
            k_i: f(self.k_i, other.k_i),
            u_c: f(self.u_c, other.u_c),
            k_phi: f(self.k_phi, other.k_phi),
            m_f: f(self.m_f, other.m_f),
            b_f: f(self.b_f, other.b_f),
            k_f: f(self.k_f, other.k_f),
            k_w: f(self.k_w, other.k_w),
            d_0: f(self.d_0, other.d_0),
            d_n: f(self.d_n, other.d_n),
            x_f0: f(self.x_f0, other.x_f0),
            v_h: f(self.v_h, other.v_h),
            d_s: f(self.d_s, other.d_s),
            m_v: f(self.m_v, other.m_v),
            b_v: f(self.b_v, other.b_v),
            k_v: f(self.k_v, other.k_v),
            w: f(self.w, other.w),
            c_r: f(self.c_r, other.c_r),
            x_v_max: f(self.x_v_max, other.x_v_max),
            v_1: f(self.v_1, other.v_1),
            r_leak: f(self.r_leak, other.r_leak),
            d_m: f(self.d_m, other.d_m),
            i_m: f(self.i_m, other.i_m),
            b_m: f(self.b_m, other.b_m),
            t_c: f(self.t_c, other.t_c),
            t_s: f(self.t_s, other.t_s),
            omega_s: f(self.omega_s, other.omega_s),
        }
    }

    /// The same valve and motor without the motor's Coulomb and breakaway friction: the motor
    /// sliding, the linearisation the margin, `hsp linearize` and `hsp frf` use
    /// ([`crate::fragments::vane_motor::friction`]).
    pub fn sliding(&self) -> Self
    where
        S: From<f64>,
    {
        ServoValveParameters {
            t_c: S::from(0.0),
            t_s: S::from(0.0),
            ..self.clone()
        }
    }

    /// The parameters `f(self)` field by field ([`ServoValveParameters::zip`]).
    pub fn map<U>(&self, f: impl Fn(S) -> U) -> ServoValveParameters<U> {
        self.zip(self, |a, _| f(a))
    }
}

impl ServoValveParameters {
    /// The defaults with the paper's voltage drive: the setup whose direct path is fitted to
    /// `G_est` (the coil's lag is its 65 1/s pole).
    pub fn voltage_driven() -> Self {
        ServoValveParameters {
            drive: CoilDrive::Voltage,
            ..Self::default()
        }
        .sliding()
    }
}

impl Default for ServoValveParameters {
    fn default() -> Self {
        let d_0: f64 = 0.25e-3;
        let d_n = 0.4e-3;
        let d_s = 5e-3;
        ServoValveParameters {
            p_supply: 140e5,
            p_tank: 0.0,
            rho: 860.0,
            beta: 1.4e9,
            cd: 0.61,
            dp_cr: 5e3,
            r_bob: 80.0,
            l_bob: 1.252,
            drive: CoilDrive::Current,
            g_i: 0.0125,
            k_i: 7.8e3,
            u_c: 12.0,
            k_phi: 0.1692,
            m_f: 2e-5,
            b_f: 0.06,
            k_f: 300.0,
            k_w: 53.41,
            d_0,
            d_n,
            x_f0: d_0 * d_0 / (4.0 * d_n),
            v_h: 1e-7,
            d_s,
            m_v: 3e-3,
            b_v: 1.0,
            k_v: 200.0,
            w: std::f64::consts::PI * d_s * D_M / LOES_D_M,
            c_r: 2.5e-6,
            x_v_max: 4e-4,
            v_1: 4.1e-5,
            r_leak: 100e5 / (1e-3 / 60.0),
            d_m: D_M,
            i_m: 1e-4,
            b_m: 0.1,
            t_c: 1.0,
            t_s: 1.5,
            omega_s: 0.5,
        }
    }
}

impl<S: Real> ServoValveParameters<S> {
    /// The fluid constants of the orifice law.
    pub fn fluid(&self) -> OrificeFluid<S> {
        OrificeFluid {
            cd: self.cd,
            rho: self.rho,
            dp_cr: self.dp_cr,
        }
    }

    /// Spool end area `pi d_s^2 / 4` \[m^2\].
    pub fn spool_area(&self) -> S {
        S::cst(std::f64::consts::PI) * self.d_s * self.d_s / 4.0
    }

    /// Stiffness of the spool end stops' contact spring \[N/m\]
    /// ([`super::limits::stop_stiffness`] of the spool area and the supply-to-tank pressure).
    pub fn stop_stiffness(&self) -> S {
        super::limits::stop_stiffness(self.spool_area(), self.p_supply - self.p_tank, self.x_v_max)
    }

    /// Null flow gain of the four-way stage `Cd w sqrt((p_s - p_t)/rho)` \[m^2/s\].
    pub fn flow_gain(&self) -> S {
        self.cd * self.w * ((self.p_supply - self.p_tank) / self.rho).sqrt()
    }
}

impl ServoValveParameters {
    /// Every constant with the FMU variable it is (`servo_valve.<name>`), in the order of the
    /// model description.
    pub fn named(&self) -> [(&'static str, f64); 35] {
        [
            ("servo_valve.p_supply", self.p_supply),
            ("servo_valve.p_tank", self.p_tank),
            ("servo_valve.rho", self.rho),
            ("servo_valve.beta", self.beta),
            ("servo_valve.Cd", self.cd),
            ("servo_valve.dp_cr", self.dp_cr),
            ("servo_valve.R_bob", self.r_bob),
            ("servo_valve.L_bob", self.l_bob),
            ("servo_valve.G_i", self.g_i),
            ("servo_valve.K_i", self.k_i),
            ("servo_valve.U_c", self.u_c),
            ("servo_valve.k_phi", self.k_phi),
            ("servo_valve.m_f", self.m_f),
            ("servo_valve.b_f", self.b_f),
            ("servo_valve.k_f", self.k_f),
            ("servo_valve.k_w", self.k_w),
            ("servo_valve.d_0", self.d_0),
            ("servo_valve.d_n", self.d_n),
            ("servo_valve.x_f0", self.x_f0),
            ("servo_valve.V_H", self.v_h),
            ("servo_valve.d_s", self.d_s),
            ("servo_valve.m_v", self.m_v),
            ("servo_valve.b_v", self.b_v),
            ("servo_valve.k_v", self.k_v),
            ("servo_valve.w", self.w),
            ("servo_valve.c_r", self.c_r),
            ("servo_valve.x_v_max", self.x_v_max),
            ("servo_valve.V_1", self.v_1),
            ("servo_valve.R_leak", self.r_leak),
            ("servo_valve.D_m", self.d_m),
            ("servo_valve.I_m", self.i_m),
            ("servo_valve.b_m", self.b_m),
            ("servo_valve.T_c", self.t_c),
            ("servo_valve.T_s", self.t_s),
            ("servo_valve.omega_s", self.omega_s),
        ]
    }

    /// Checks every constant against the model description's rules ([`rules`]), then the
    /// relations the XML cannot state: the tank below the supply, the breakaway friction at least
    /// the running friction. The error names the FMU variable, e.g. `servo_valve.p_supply`.
    pub fn validate(&self) -> Result<(), String> {
        rules::check_all(&self.named())?;
        if self.p_tank >= self.p_supply {
            return Err(format!(
                "servo_valve.p_tank: the tank pressure must be below the supply pressure ({} Pa), got {} Pa",
                self.p_supply, self.p_tank
            ));
        }
        if self.t_s < self.t_c {
            return Err(format!(
                "servo_valve.T_s: the breakaway friction torque must be at least the running \
                 torque servo_valve.T_c = {} N m, got {} N m",
                self.t_c, self.t_s
            ));
        }
        Ok(())
    }
}
