//! The slewing flexible plate: sections 2.2, 3, 3.1 and 4 of the paper.
//!
//! A thin aluminium plate (Kirchhoff theory) fixed to a rigid hub on a gas bearing, deflection
//! written as the assumed-modes series of eq. 7, `w(x, y, t) = sum phi_n(x) psi_m(y) eta_nm(t)`,
//! with the beam functions of [`beam_functions`]. Two formulations share one representation,
//! [`PlateModel`] (generalised coordinates with mass and stiffness matrices and the vectors that
//! map the hub torque, the shaker forces and the sensors onto them):
//!
//! * [`paper`]: eqs. 18-21 of the paper with the errata of docs/model-notes.md (items 1-6) fixed.
//! * [`consistent`]: the Lagrangian of hub and plate (eq. 4 and eq. 5 in full).
//!
//! [`drag`] adds the air drag of the plate swept broadside, [`added_mass`] the air's added mass
//! (neither is in the paper).
//!
//! [`modes`] solves eq. 14 (natural frequencies) with a symmetric generalised eigen-solver;
//! [`add_plate`] turns a [`PlateModel`] into bond-graph fragments (modal I, C, R per coordinate,
//! the I's on the modes' absolute rates where the mass matrix couples the hub and the plate,
//! [`AbsoluteRates`]; TFs from the root-torque junction and from the shaker-force junctions to
//! the coordinates).
//!
//! Scope: the structure is symmetric, one arm on each side of the hub; the model keeps the
//! antisymmetric motion that a hub torque excites (both arms described by one set of
//! coordinates). A shaker force on one arm is projected onto that motion.

pub mod added_mass;
pub mod beam_functions;
pub mod consistent;
pub mod damping;
pub mod drag;
pub mod modes;
pub mod paper;

use nalgebra::{DMatrix, DVector};

use crate::bond_graph::{BondGraph, BondId, Domain, ElementId, Law, SignalId};
use crate::math::dual::Dual;

use super::hub::HubPorts;
use super::rules;

/// Most beam functions per direction (`plate.N`, `plate.M`): 20 x 20 = 400 modes. The beam
/// functions stay orthonormal to 1e-12 and the Ritz frequencies keep converging there
/// (`tests/plate_modes.rs`).
pub const MAX_FUNCTIONS: usize = 20;

/// Which plate model (`plate.formulation`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Formulation {
    /// Eqs. 18-21 of the paper (errata fixed): reproduces eq. 16.
    Paper,
    /// The consistent Lagrangian of hub and plate: energy-conserving, Kirchhoff energy in full.
    Consistent,
}

/// Root condition (`plate.root`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Root {
    /// The plate root moves with the hub, which is free on its gas bearing or driven through the
    /// torsion bar.
    Hub,
    /// The hub is locked (clamped root), as in the modal test of Fig. 10.
    Locked,
}

/// Number of accelerometer grid points along the plate (`x`).
pub const GRID_X: usize = 4;
/// Number of accelerometer grid points across the plate (`y`).
pub const GRID_Y: usize = 3;

/// Parameters of the plate and hub (SI units).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PlateParameters<S = f64> {
    pub formulation: Formulation,
    pub root: Root,
    /// Number of beam functions along the plate (`n`, bending).
    pub n: usize,
    /// Number of beam functions across the plate (`m`, "torsion" in the paper).
    pub m: usize,
    /// Young's modulus \[Pa\] (paper: 6.89e10).
    pub e: S,
    /// Density \[kg/m^3\] (paper: 2795).
    pub rho: S,
    /// Length from the hub axis to the tip \[m\] (paper: 1.41).
    pub a: S,
    /// Width \[m\] (paper's table: 0.4685, docs/model-notes.md, item 1).
    pub b: S,
    /// Thickness \[m\] (paper: 2.65e-3).
    pub h: S,
    /// Poisson's ratio (not in the paper; 0.3 reproduces eq. 16, docs/model-notes.md, item 1).
    pub nu: S,
    /// Structural damping ratio (not in the paper; 2 %, a bolted assembly: docs/model-notes.md,
    /// items 14 and 25): of every mode of hub, bar and plate with the motor clamped in the
    /// consistent formulation, of each plate mode in the paper's.
    pub zeta: S,
    /// Hub inertia `I_H` \[kg m^2\] (paper: 3.5).
    pub i_h: S,
    /// Drag coefficient of the plate face-on to the air \[-\] (`plate.Cd`; 0: no drag).
    pub cd: S,
    /// Density of the air \[kg/m^3\] (`plate.rho_air`).
    pub rho_air: S,
    /// Added-mass coefficient of the air, a multiple of strip theory \[-\] (`plate.Ca`;
    /// [`added_mass`]; 0: the plate in vacuum).
    pub ca: S,
    /// Shaker force points `(x1, y1)`, `(x2, y2)` \[m\].
    pub x1: S,
    pub y1: S,
    pub x2: S,
    pub y2: S,
}

impl<S: Copy> PlateParameters<S> {
    /// The parameters `f(self, other)` field by field, the others (choices, counts) `self`'s:
    /// the one list of the real fields, for carrying them in another scalar (a value and its
    /// derivative, [`crate::math::dual::Dual`]).
    pub fn zip<T: Copy, U>(
        &self,
        other: &PlateParameters<T>,
        f: impl Fn(S, T) -> U,
    ) -> PlateParameters<U> {
        PlateParameters {
            formulation: self.formulation,
            root: self.root,
            n: self.n,
            m: self.m,
            e: f(self.e, other.e),
            rho: f(self.rho, other.rho),
            a: f(self.a, other.a),
            b: f(self.b, other.b),
            h: f(self.h, other.h),
            nu: f(self.nu, other.nu),
            zeta: f(self.zeta, other.zeta),
            i_h: f(self.i_h, other.i_h),
            cd: f(self.cd, other.cd),
            rho_air: f(self.rho_air, other.rho_air),
            ca: f(self.ca, other.ca),
            x1: f(self.x1, other.x1),
            y1: f(self.y1, other.y1),
            x2: f(self.x2, other.x2),
            y2: f(self.y2, other.y2),
        }
    }

    /// The parameters `f(self)` field by field ([`PlateParameters::zip`]).
    pub fn map<U>(&self, f: impl Fn(S) -> U) -> PlateParameters<U> {
        self.zip(self, |a, _| f(a))
    }
}

/// The FMU's start values (`plate.*`, `hub.I_H`): the paper's plate, 3 x 5 modes, in the
/// consistent formulation on its hub (`tests/model_description.rs` checks that they agree).
impl Default for PlateParameters {
    fn default() -> Self {
        PlateParameters {
            formulation: Formulation::Consistent,
            root: Root::Hub,
            n: 3,
            m: 5,
            e: 6.89e10,
            rho: 2795.0,
            a: 1.41,
            b: 0.4685,
            h: 2.65e-3,
            nu: 0.3,
            zeta: 0.02,
            i_h: 3.5,
            cd: 1.2,
            rho_air: 1.2,
            ca: 1.0,
            x1: 1.3,
            y1: 0.1,
            x2: 0.7,
            y2: 0.35,
        }
    }
}

impl PlateParameters<Dual> {
    /// Flexural rigidity `D = E h^3 / (12 (1 - nu^2))` \[N m\], with its derivative.
    pub fn rigidity(&self) -> Dual {
        self.e * powi(self.h, 3) / (12.0 * (1.0 - self.nu * self.nu))
    }
    /// Mass per unit area `m = rho h` \[kg/m^2\], with its derivative.
    pub fn areal_mass(&self) -> Dual {
        self.rho * self.h
    }
    /// `I_P = int int m x^2 dx dy` of one arm about the hub axis \[kg m^2\], with its
    /// derivative.
    pub fn i_p(&self) -> Dual {
        self.areal_mass() * self.b * powi(self.a, 3) / 3.0
    }
    /// `I = I_H + 2 I_P` (section 3), with its derivative.
    pub fn hub_total_inertia(&self) -> Dual {
        self.i_h + 2.0 * self.i_p()
    }
    /// The 4 x 3 accelerometer grid over one arm ([`PlateParameters::accelerometer_points`]),
    /// with the points' derivatives.
    pub fn accelerometer_points(&self) -> Vec<(Dual, Dual)> {
        let mut v = Vec::new();
        for i in 1..=GRID_X {
            for j in 1..=GRID_Y {
                v.push((
                    i as f64 * self.a / GRID_X as f64,
                    (2 * j - 1) as f64 * self.b / (2 * GRID_Y) as f64,
                ));
            }
        }
        v
    }
}

/// `x^n` with its derivative `n x^(n-1) dx`, the value `f64::powi`'s (the `f64` model's bits).
pub fn powi(x: Dual, n: i32) -> Dual {
    Dual::new(x.v.powi(n), f64::from(n) * x.v.powi(n - 1) * x.d)
}

/// A beam function's `k`-th derivative at `xi` with its derivative along `xi`'s,
/// `phi^(k)(xi) + phi^(k+1)(xi) dxi ε`.
pub fn beam_value(phi: &beam_functions::BeamFunction, k: u32, xi: Dual) -> Dual {
    let slope = if xi.d == 0.0 {
        0.0
    } else {
        phi.derivative(k + 1, xi.v) * xi.d
    };
    Dual::new(phi.derivative(k, xi.v), slope)
}

impl PlateParameters {
    /// Flexural rigidity `D = E h^3 / (12 (1 - nu^2))` \[N m\].
    pub fn rigidity(&self) -> f64 {
        self.map(Dual::from).rigidity().v
    }
    /// Mass per unit area `m = rho h` \[kg/m^2\].
    pub fn areal_mass(&self) -> f64 {
        self.map(Dual::from).areal_mass().v
    }
    /// `I_P = int int m x^2 dx dy` of one arm about the hub axis \[kg m^2\].
    pub fn i_p(&self) -> f64 {
        self.map(Dual::from).i_p().v
    }
    /// `I = I_H + 2 I_P` (section 3).
    pub fn hub_total_inertia(&self) -> f64 {
        self.map(Dual::from).hub_total_inertia().v
    }
    /// The 4 x 3 accelerometer grid over one arm, numbered along `y` first: point
    /// `k = 3 (i - 1) + j` is at `x = i a / 4`, `y = (2 j - 1) b / 6` (so `acc[11]` is the tip
    /// centre of eq. 22).
    pub fn accelerometer_points(&self) -> Vec<(f64, f64)> {
        let points = self.map(Dual::from).accelerometer_points();
        points.into_iter().map(|(x, y)| (x.v, y.v)).collect()
    }

    /// Every numeric value with the FMU variable it is (`plate.<name>`, `hub.I_H`).
    pub fn named(&self) -> [(&'static str, f64); 17] {
        [
            ("plate.N", self.n as f64),
            ("plate.M", self.m as f64),
            ("plate.E", self.e),
            ("plate.rho", self.rho),
            ("plate.a", self.a),
            ("plate.b", self.b),
            ("plate.h", self.h),
            ("plate.nu", self.nu),
            ("plate.zeta", self.zeta),
            ("hub.I_H", self.i_h),
            ("plate.x1", self.x1),
            ("plate.y1", self.y1),
            ("plate.x2", self.x2),
            ("plate.y2", self.y2),
            ("plate.Cd", self.cd),
            ("plate.rho_air", self.rho_air),
            ("plate.Ca", self.ca),
        ]
    }

    /// Checks the values a model can be built from: each against the model description's rules
    /// ([`rules`]), then the relation the XML cannot state, the excitation and measurement points
    /// on the plate. The error names the FMU variable.
    pub fn validate(&self) -> Result<(), String> {
        rules::check_all(&self.named())?;
        for (k, x, y) in [(1, self.x1, self.y1), (2, self.x2, self.y2)] {
            if !(0.0..=self.a).contains(&x) || !(0.0..=self.b).contains(&y) {
                return Err(format!(
                    "plate.x{k}, plate.y{k}: the point ({x}, {y}) is not on the plate (0..{}, 0..{})",
                    self.a, self.b
                ));
            }
        }
        Ok(())
    }
}

/// The displacement of a point `(x, y)` per unit generalised coordinate
/// ([`PlateModel::with_displacements`]).
pub type DisplacementMap = Box<dyn Fn(f64, f64) -> DVector<f64>>;

/// [`DisplacementMap`] in dual numbers: the point and the displacements with their derivatives.
pub type DualDisplacementMap = Box<dyn Fn(Dual, Dual) -> DVector<Dual>>;

/// A plate model in generalised coordinates `q`: the hub angle first when the root is the hub,
/// then the plate coordinates. Kinetic energy `q' M q / 2`, strain energy `q' K q / 2`.
#[derive(Clone, Debug)]
pub struct PlateModel {
    /// Whether coordinate 0 is the hub angle `theta` \[rad\].
    pub hub: bool,
    /// Label `(n, m)` of each plate coordinate (the dominant beam-function product).
    pub labels: Vec<(usize, usize)>,
    /// Mass matrix (over all coordinates).
    pub mass: DMatrix<f64>,
    /// Stiffness matrix (over all coordinates; the hub row and column are zero).
    pub stiffness: DMatrix<f64>,
    /// Damping resistance of each plate coordinate (an R per mode), `2 zeta sqrt(K_jj M_jj)`.
    pub damping: Vec<f64>,
    /// The derivative of each entry of `damping` along the parameter the model is built for
    /// (exact sensitivities, [`PlateModel::for_parameters`]: `zeta`, `K_jj` and `M_jj` moving);
    /// zeros as built from parameters in `f64`, which is every model but a sensitivity's.
    pub damping_derivative: Vec<f64>,
    /// Generalised force per unit root torque (the torsion-bar torque on the hub).
    pub torque: DVector<f64>,
    /// Generalised forces per unit shaker force F1, F2.
    pub forces: [DVector<f64>; 2],
    /// `w_tip` per unit coordinate: the deflection at `x = a`, `y = b/2` relative to the hub
    /// frame (eq. 22).
    pub tip: DVector<f64>,
    /// The bending stress at the plate's surface at [`PlateModel::stress_point`] per unit
    /// coordinate, `sigma_x = E h (w_xx + nu w_yy) / (2 (1 - nu^2))` \[Pa\] (see
    /// [`stress_row`]).
    pub stress: DVector<f64>,
    /// Where `stress` is taken, `(x, y)` \[m\]: on the centre line at the clamped root, or, for
    /// pinned-free shapes (whose curvature vanishes at the root), at the section where the first
    /// shape bends most.
    pub stress_point: (f64, f64),
    /// Displacement of each accelerometer point per unit coordinate, including the rigid
    /// rotation `x theta` (what an accelerometer on the slewing plate measures).
    pub accelerometers: Vec<DVector<f64>>,
    /// The quadrature points of the air drag (none without drag).
    pub drag: Vec<drag::DragPoint>,
    /// The modal dashpots of the structure's damping ([`damping`]), in place of the R of the
    /// coordinates they span (`damping` is zero for those); set by the assembly, which knows the
    /// bar.
    pub dashpots: Vec<damping::ModalDashpot>,
    /// Typical magnitudes of the plate's states, scaling the integrator's absolute tolerance.
    pub nominal: PlateNominal,
    /// The derivatives of `mass`, `stiffness` and the vectors along the parameter the model is
    /// built for (exact sensitivities); zeros as built from parameters in `f64`.
    pub derivative: PlateDerivative,
}

/// The derivatives of a [`PlateModel`]'s matrices and vectors along the parameter the model is
/// built for ([`PlateModel::for_parameters`]), each the shape of the field it is named after:
/// `dM/dp`, `dK/dp`, and so on.
#[derive(Clone, Debug, PartialEq)]
pub struct PlateDerivative {
    pub mass: DMatrix<f64>,
    pub stiffness: DMatrix<f64>,
    pub torque: DVector<f64>,
    pub forces: [DVector<f64>; 2],
    pub tip: DVector<f64>,
    pub stress: DVector<f64>,
    pub accelerometers: Vec<DVector<f64>>,
}

/// A plate model's constants in dual numbers, as [`paper::build`] and [`consistent::build`]
/// compute them: the values the `f64` model's to the bit, the derivatives along the parameter
/// seeded in [`PlateParameters<Dual>`]. [`DualModel::split`] makes the [`PlateModel`].
pub(crate) struct DualModel {
    pub hub: bool,
    pub labels: Vec<(usize, usize)>,
    pub mass: DMatrix<Dual>,
    pub stiffness: DMatrix<Dual>,
    pub damping: Vec<Dual>,
    pub torque: DVector<Dual>,
    pub forces: [DVector<Dual>; 2],
    pub tip: DVector<Dual>,
    pub stress: DVector<Dual>,
    pub stress_point: (f64, f64),
    pub accelerometers: Vec<DVector<Dual>>,
}

impl DualModel {
    /// The [`PlateModel`]: values, and derivatives in [`PlateModel::derivative`] (the damping's
    /// in [`PlateModel::damping_derivative`]).
    pub fn split(self, p: &PlateParameters<Dual>) -> PlateModel {
        let value = |v: &DVector<Dual>| v.map(|x| x.v);
        let slope = |v: &DVector<Dual>| v.map(|x| x.d);
        PlateModel {
            hub: self.hub,
            labels: self.labels,
            mass: self.mass.map(|x| x.v),
            stiffness: self.stiffness.map(|x| x.v),
            damping: self.damping.iter().map(|x| x.v).collect(),
            damping_derivative: self.damping.iter().map(|x| x.d).collect(),
            torque: value(&self.torque),
            forces: [value(&self.forces[0]), value(&self.forces[1])],
            tip: value(&self.tip),
            stress: value(&self.stress),
            stress_point: self.stress_point,
            accelerometers: self.accelerometers.iter().map(value).collect(),
            drag: Vec::new(),
            dashpots: Vec::new(),
            nominal: PlateNominal::of(&p.map(|x| x.v)),
            derivative: PlateDerivative {
                mass: self.mass.map(|x| x.d),
                stiffness: self.stiffness.map(|x| x.d),
                torque: slope(&self.torque),
                forces: [slope(&self.forces[0]), slope(&self.forces[1])],
                tip: slope(&self.tip),
                stress: slope(&self.stress),
                accelerometers: self.accelerometers.iter().map(slope).collect(),
            },
        }
    }
}

/// A zero in dual numbers (`DMatrix::from_element`, as `Dual` has no `nalgebra` zero).
pub(crate) const ZERO: Dual = Dual::new(0.0, 0.0);

/// Typical magnitudes of the plate's states, stated by [`add_plate`] on the elements that own
/// them ([`BondGraph::set_nominal`]). They scale the absolute tolerance of the FMU's integrator
/// and of an importer's (Model Exchange, `rtol × nominal`).
///
/// The lowest plate coordinate gets the scalar magnitudes below; a coordinate `j` of higher
/// frequency gets them scaled by [`PlateModel::mode_scale`] `s_j = ω_1/ω_j`: its displacement by
/// `s_j²`, its momentum by `s_j`. That keeps the tolerance of every coordinate at the same
/// acceleration `ω_j² q_j`, which is what the accelerometers measure (a uniform 1 mm let the
/// error of a 200 Hz mode pass into `acc_tip` 4·10⁴ times amplified against the first mode's;
/// docs/model-exchange.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlateNominal {
    /// The lowest plate coordinate's displacement \[m\]: 1 mm.
    pub displacement: f64,
    /// The lowest plate coordinate's momentum: the arm's mass `m a b` moving at 0.1 m/s
    /// \[kg m/s\].
    pub momentum: f64,
    /// A momentum where the mass matrix couples the hub and the modes (consistent formulation,
    /// [`AbsoluteRates`]): the modal momentum, or the hub's at 1 mrad/s if larger; the hub's,
    /// and the lowest plate coordinate's.
    pub field_momentum: f64,
}

impl PlateNominal {
    pub fn of(p: &PlateParameters) -> Self {
        let momentum = p.areal_mass() * p.a * p.b * 0.1;
        PlateNominal {
            displacement: 1e-3,
            momentum,
            field_momentum: momentum.max(1e-3 * p.hub_total_inertia()),
        }
    }
}

impl PlateModel {
    /// The model of a parameter set.
    pub fn new(p: &PlateParameters) -> Result<Self, String> {
        Self::for_parameters(&p.map(Dual::from))
    }

    /// The model of a parameter set in dual numbers: the values those of [`PlateModel::new`] to
    /// the bit, the derivatives along the seeded parameter in [`PlateModel::derivative`],
    /// [`PlateModel::damping_derivative`] and the drag points'.
    ///
    /// # Errors
    ///
    /// Invalid values, and, in the consistent formulation, clamped-plate modes too close to
    /// differentiate ([`crate::eigen::derivative::symmetric_eigen_derivative`]) when a
    /// derivative is seeded.
    pub fn for_parameters(p: &PlateParameters<Dual>) -> Result<Self, String> {
        let (mut model, map) = Self::dual_displacements(p)?;
        model.drag = drag::drag_points(p, &model, map);
        Ok(model)
    }

    /// The model of a parameter set (without its drag points) and the map from a point
    /// `(x, y)` of the plate \[m\] to its displacement per unit coordinate \[m\] (the rigid
    /// rotation `x theta` of the hub coordinate included): what draws the deflected plate from
    /// the coordinates.
    pub fn with_displacements(p: &PlateParameters) -> Result<(Self, DisplacementMap), String> {
        let (model, map) = Self::dual_displacements(&p.map(Dual::from))?;
        let map = move |x: f64, y: f64| map(Dual::from(x), Dual::from(y)).map(|s| s.v);
        Ok((model, Box::new(map)))
    }

    /// [`PlateModel::with_displacements`] in dual numbers.
    fn dual_displacements(
        p: &PlateParameters<Dual>,
    ) -> Result<(Self, DualDisplacementMap), String> {
        p.map(|x| x.v).validate()?;
        Ok(match p.formulation {
            Formulation::Paper => {
                let (model, map) = paper::build(p);
                (model.split(p), Box::new(map))
            }
            Formulation::Consistent => {
                let (model, map) = consistent::build(p)?;
                (model.split(p), map)
            }
        })
    }

    /// Number of coordinates.
    pub fn dim(&self) -> usize {
        self.mass.nrows()
    }

    /// Index of the first plate coordinate (1 with a hub, 0 without).
    pub fn first_plate(&self) -> usize {
        usize::from(self.hub)
    }

    /// The frequency of each plate coordinate relative to the lowest, inverted:
    /// `s_j = ω_min/ω_j ≤ 1` with `ω_j² = K_jj/M_jj` (the coordinate's own Rayleigh quotient:
    /// its natural frequency when the mass matrix is diagonal, an estimate of it when the
    /// consistent formulation couples the hub). Indexed by plate coordinate (0 = the first).
    /// What [`PlateNominal`]'s magnitudes are scaled by.
    pub fn mode_scale(&self) -> Vec<f64> {
        let first = self.first_plate();
        let omega_sq: Vec<f64> = (first..self.dim())
            .map(|k| self.stiffness[(k, k)] / self.mass[(k, k)])
            .collect();
        let lowest = omega_sq.iter().copied().fold(f64::INFINITY, f64::min);
        omega_sq.iter().map(|&w| (lowest / w).sqrt()).collect()
    }

    /// The mass matrix with its derivative, `M + dM ε`.
    pub fn mass_dual(&self) -> DMatrix<Dual> {
        self.mass.zip_map(&self.derivative.mass, Dual::new)
    }

    /// The stiffness matrix with its derivative, `K + dK ε`.
    pub fn stiffness_dual(&self) -> DMatrix<Dual> {
        self.stiffness
            .zip_map(&self.derivative.stiffness, Dual::new)
    }

    /// The kinetic energy as one-port inertias on the coordinates' absolute rates
    /// ([`AbsoluteRates`]); `None` if the plate coordinates' mass matrix is not diagonal.
    pub fn absolute_rates(&self) -> Option<AbsoluteRates> {
        self.absolute_rates_dual().map(|r| AbsoluteRates {
            hub: r.hub.map(|x| x.v),
            masses: r.masses.iter().map(|x| x.v).collect(),
            ratios: r.ratios.iter().map(|x| x.v).collect(),
        })
    }

    /// [`PlateModel::absolute_rates`] with the derivatives of `I_r`, `D_jj` and `c_j` (from
    /// [`PlateDerivative::mass`]).
    pub fn absolute_rates_dual(&self) -> Option<AbsoluteRates<Dual>> {
        let first = self.first_plate();
        let n = self.dim();
        let mass = self.mass_dual();
        let plate_diagonal = (first..n).all(|i| (first..n).all(|j| i == j || mass[(i, j)] == 0.0));
        if !plate_diagonal {
            return None;
        }
        let masses: Vec<Dual> = (first..n).map(|j| mass[(j, j)]).collect();
        let ratios: Vec<Dual> = if self.hub {
            (first..n).map(|j| mass[(0, j)] / mass[(j, j)]).collect()
        } else {
            vec![ZERO; n - first]
        };
        // I_r = M_00 - sum_j M_0j^2 / M_jj, the Schur complement of the plate block: positive
        // as M is positive definite.
        let hub = self.hub.then(|| {
            (first..n).fold(mass[(0, 0)], |i, j| {
                i - mass[(0, j)] * mass[(0, j)] / mass[(j, j)]
            })
        });
        Some(AbsoluteRates {
            hub,
            masses,
            ratios,
        })
    }

    /// The hub's one-port inertia: `I_r` of [`AbsoluteRates`] (the whole `M_00` when the
    /// plate does not couple to the hub, the paper formulation), with its derivative.
    pub fn hub_one_port(&self) -> Option<Dual> {
        self.absolute_rates_dual().and_then(|r| r.hub)
    }
}

/// The kinetic energy of hub and plate on one-port inertias, for a mass matrix that couples
/// the plate coordinates to the hub only (`M = [I_t b'; b D]`, `D` diagonal: the consistent
/// formulation's clamped modes, [`consistent`]). With the *absolute modal rates*
/// `u_j = eta_j' + c_j theta'`, `c_j = b_j / D_jj` (the mode's rate plus the share of the
/// rigid rotation it projects on),
///
/// `T = q' M q / 2 = I_r theta'^2 / 2 + sum_j D_jj u_j^2 / 2`, `I_r = I_t - sum_j b_j^2 / D_jj`.
///
/// Each term is a one-port I: the hub's on the hub's rate, mode j's on `u_j`, a 0-junction
/// whose inflows are `eta_j'` and `c_j theta'` (a TF from the hub). The momenta are those of
/// the I-field `p = M q'` for the modes (`D_jj u_j = b_j theta' + D_jj eta_j'`), `I_r theta'`
/// for the hub. The equations are the I-field's (the same Lagrangian), but each mode's rate
/// `eta_j' = p_j / D_jj - c_j p_hub / I_r` reads only its own momentum and the hub's, where
/// `M^-1 p` reads every momentum: the Jacobian keeps the plate's modes in blocks of their own
/// joined at the hub (the structured LU, `solver::linalg`), and a right-hand side costs
/// `O(n)` instead of `O(n^2)`.
#[derive(Clone, Debug, PartialEq)]
pub struct AbsoluteRates<S = f64> {
    /// `I_r` \[kg m^2\], with the hub.
    pub hub: Option<S>,
    /// `D_jj` per plate coordinate.
    pub masses: Vec<S>,
    /// `c_j = b_j / D_jj` per plate coordinate (zero without the hub).
    pub ratios: Vec<S>,
}

/// The bending stress at the surface of the plate at `(x, y)` per unit amplitude of each
/// beam-function product `phi_n(x/a) psi_m(y/b)`, in the order `j = N (m - 1) + n`: Kirchhoff's
/// `sigma_x = E h (w_xx + nu w_yy) / (2 (1 - nu^2))` \[Pa per m of amplitude\], the largest
/// normal stress through the thickness (at the face the deflection points away from; the other
/// face carries its opposite).
pub fn stress_row(
    p: &PlateParameters<Dual>,
    phis: &[beam_functions::BeamFunction],
    psis: &[beam_functions::BeamFunction],
    (x, y): (Dual, Dual),
) -> DVector<Dual> {
    let scale = p.e * p.h / (2.0 * (1.0 - p.nu * p.nu));
    let (xi, eta) = (x / p.a, y / p.b);
    DVector::from_fn(phis.len() * psis.len(), |j, _| {
        let (phi, psi) = (&phis[j % phis.len()], &psis[j / phis.len()]);
        let w_xx = beam_value(phi, 2, xi) / (p.a * p.a) * beam_value(psi, 0, eta);
        let w_yy = beam_value(phi, 0, xi) * beam_value(psi, 2, eta) / (p.b * p.b);
        scale * (w_xx + p.nu * w_yy)
    })
}

/// The section `x / a` where the beam function `phi` has its largest curvature `|phi''|`
/// (on a grid of 2000 intervals: a monitoring point, not a root to converge).
pub fn most_bent_section(phi: &beam_functions::BeamFunction) -> f64 {
    (0..=2000)
        .map(|i| i as f64 / 2000.0)
        .max_by(|&a, &b| {
            phi.derivative(2, a)
                .abs()
                .total_cmp(&phi.derivative(2, b).abs())
        })
        .unwrap_or(0.0)
}

/// Handles into the plate fragment.
#[derive(Clone, Debug)]
pub struct PlatePorts {
    /// The 1-junction of each plate coordinate (common flow `d eta / dt`).
    pub junctions: Vec<ElementId>,
    /// `w_tip` \[m\] (eq. 22).
    pub w_tip: SignalId,
    /// `acc_tip` \[m/s^2\], the second derivative of `w_tip`.
    pub acc_tip: SignalId,
    /// The bending stress at [`PlateModel::stress_point`] \[Pa\] (`<prefix>.stress`).
    pub stress: SignalId,
    /// The accelerometers \[m/s^2\].
    pub acc: Vec<SignalId>,
}

fn combination(g: &mut BondGraph, name: String, terms: Vec<(Dual, SignalId)>) -> SignalId {
    if terms.is_empty() {
        g.add_constant(name, 0.0)
    } else {
        g.add_sum(name, &terms)
    }
}

/// Adds the plate under `prefix`.
///
/// * `hub`: the hub fragment (`None` when the root is locked), with its one-port inertia
///   ([`PlateModel::hub_one_port`]). Where the mass matrix couples the hub and the plate, each
///   mode's I `<prefix>.I[j]` sits on a 0-junction `<prefix>.I[j].rate` fed by the mode's
///   junction and, through a TF `<prefix>.I[j].hub_tf`, by the hub's ([`AbsoluteRates`]).
/// * `root`: the 0-junction whose common effort is the root torque (the torsion bar), if any;
///   it is bonded to the hub junction and, through TFs of modulus `torque[j]`, to each plate
///   coordinate that the torque drives directly (the paper formulation).
/// * `forces`: the shaker force signals F1, F2 (MSe into 0-junctions, TFs to the coordinates).
/// * `twist`: the torsion bar's twist junction (flow: motor speed less hub speed), through which
///   the modal dashpots see the hub's rate relative to the motor; `None` without the bar.
pub fn add_plate(
    g: &mut BondGraph,
    prefix: &str,
    model: &PlateModel,
    hub: Option<&HubPorts>,
    root: Option<ElementId>,
    twist: Option<ElementId>,
    forces: [SignalId; 2],
) -> PlatePorts {
    assert_eq!(model.hub, hub.is_some(), "hub fragment and model disagree");
    let n = model.dim();
    let first = model.first_plate();
    let np = n - first;
    let scale = model.mode_scale();
    // coordinate junctions: hub junction, then one per plate coordinate
    let mut coord = Vec::with_capacity(n);
    if let Some(h) = hub {
        coord.push(h.junction);
    }
    for j in 0..np {
        coord.push(g.add_one(format!("{prefix}.mode[{}]", j + 1)));
    }
    // inertias: one-port I's on the absolute rates, a bond per coordinate whose effort is the
    // rate of its momentum
    let rates = model
        .absolute_rates_dual()
        .expect("the plate coordinates' mass matrix must be diagonal");
    let moves = |x: Dual| x.v != 0.0 || x.d != 0.0;
    // Coupled to the hub, the momenta are the I-field's (hub and modes together), and so are
    // their magnitudes.
    let coupled = rates.ratios.iter().any(|&c| c.v != 0.0);
    let momentum = if coupled {
        model.nominal.field_momentum
    } else {
        model.nominal.momentum
    };
    let mut inertia_bonds: Vec<BondId> = Vec::with_capacity(n);
    if let Some(h) = hub {
        let bond = h.inertia_bond.expect("hub with a one-port inertia");
        if coupled {
            let inertia = g.bonds()[bond.index()].to;
            g.set_nominal(inertia, &[momentum]);
        }
        inertia_bonds.push(bond);
    }
    for j in 0..np {
        let i = g.add_i(format!("{prefix}.I[{}]", j + 1), rates.masses[j]);
        g.set_nominal(i, &[momentum * scale[j]]);
        g.set_domains(i, &[Domain::Translation]);
        let c = rates.ratios[j];
        if !moves(c) {
            inertia_bonds.push(g.bond(coord[first + j], i));
        } else {
            // u_j = eta_j' + c_j theta': a 0-junction fed by the mode, giving -c_j theta' to the
            // hub through a TF (port 1 on the 0-junction: its flow is -c_j times the hub's),
            // which takes back the torque -c_j dp_j/dt
            let node = g.add_zero(format!("{prefix}.I[{}].rate", j + 1));
            g.bond(coord[first + j], node);
            let tf = g.add_tf(format!("{prefix}.I[{}].hub_tf", j + 1), -c);
            g.bond(node, tf);
            g.bond(tf, coord[0]);
            inertia_bonds.push(g.bond(node, i));
        }
    }
    // stiffness and damping per plate coordinate
    let mut c_elems = Vec::with_capacity(np);
    for j in 0..np {
        let k = Dual::new(
            model.stiffness[(first + j, first + j)],
            model.derivative.stiffness[(first + j, first + j)],
        );
        for i in 0..n {
            assert!(
                i == first + j || model.stiffness[(i, first + j)] == 0.0,
                "plate stiffness must be diagonal in the model's coordinates"
            );
        }
        let c = g.add_c(format!("{prefix}.C[{}]", j + 1), 1.0 / k);
        g.set_nominal(c, &[model.nominal.displacement * scale[j] * scale[j]]);
        g.set_domains(c, &[Domain::Translation]);
        g.bond(coord[first + j], c);
        c_elems.push(c);
        // An R of zero resistance but a derivative stays (its sensitivity), adding no state.
        let resistance = Dual::new(model.damping[j], model.damping_derivative[j]);
        if resistance.v > 0.0 || resistance.d != 0.0 {
            let r = g.add_r(format!("{prefix}.R[{}]", j + 1), resistance);
            g.bond(coord[first + j], r);
        }
    }
    // root torque
    if let Some(node) = root {
        for (i, &c) in coord.iter().enumerate() {
            let t = Dual::new(model.torque[i], model.derivative.torque[i]);
            if i == 0 && model.hub && t.v == 1.0 && t.d == 0.0 {
                g.bond(node, c);
            } else if moves(t) {
                let tf = g.add_tf(format!("{prefix}.root_tf[{}]", i), t);
                g.bond(node, tf);
                g.bond(tf, c);
            }
        }
    }
    // shaker forces
    for (k, (&f, (s, ds))) in forces
        .iter()
        .zip(model.forces.iter().zip(&model.derivative.forces))
        .enumerate()
    {
        let se = g.add_se(format!("{prefix}.F{}", k + 1), f);
        let node = g.add_zero(format!("{prefix}.F{}.point", k + 1));
        g.bond(se, node);
        for (i, &c) in coord.iter().enumerate() {
            let modulus = Dual::new(s[i], ds[i]);
            if moves(modulus) {
                let tf = g.add_tf(format!("{prefix}.F{}_tf[{}]", k + 1, i), modulus);
                g.bond(node, tf);
                g.bond(tf, c);
            }
        }
    }
    // structural damping on the structure's modes: per mode a 0-junction whose flow is the modal
    // rate, and a linear R
    for (i, d) in model.dashpots.iter().enumerate() {
        let node = g.add_zero(format!("{prefix}.damping[{}].mode", i + 1));
        let r = g.add_r(format!("{prefix}.damping[{}]", i + 1), d.resistance);
        g.bond(node, r);
        for (j, &cj) in coord.iter().enumerate() {
            let (junction, modulus) = match twist {
                // The hub's rate relative to the motor: minus the twist rate.
                Some(t) if j == 0 && model.hub => (t, -d.velocity[0]),
                _ => (cj, d.velocity[j]),
            };
            if moves(modulus) {
                let tf = g.add_tf(format!("{prefix}.damping[{}]_tf[{j}]", i + 1), modulus);
                g.bond(node, tf);
                g.bond(tf, junction);
            }
        }
    }
    // air drag: per quadrature point a 0-junction whose flow is the point's velocity, and the
    // quadratic R
    for (k, d) in model.drag.iter().enumerate() {
        let node = g.add_zero(format!("{prefix}.drag[{}].point", k + 1));
        let r = g.add_r(
            format!("{prefix}.drag[{}]", k + 1),
            Law::Nonlinear(drag::nonlinear_law(d.coefficient)),
        );
        g.bond(node, r);
        for (i, &cj) in coord.iter().enumerate() {
            if moves(d.velocity[i]) {
                let tf = g.add_tf(format!("{prefix}.drag[{}]_tf[{i}]", k + 1), d.velocity[i]);
                g.bond(node, tf);
                g.bond(tf, cj);
            }
        }
    }
    // sensors: accelerations from the efforts on the inertia bonds (the momenta's rates: hub
    // theta'' = dp_hub / I_r, mode eta_j'' = dp_j / D_jj - c_j theta''), displacements from the
    // C states and the hub angle
    let efforts: Vec<SignalId> = inertia_bonds
        .iter()
        .enumerate()
        .map(|(i, &b)| g.add_effort_sensor(format!("{prefix}.dp[{i}]"), b))
        .collect();
    let qs: Vec<SignalId> = c_elems
        .iter()
        .enumerate()
        .map(|(j, &c)| g.add_state_sensor(format!("{prefix}.eta[{}]", j + 1), c))
        .collect();
    let acc_of = |g: &mut BondGraph, name: String, s: &DVector<Dual>| {
        // a = s' q'' = (s_0 - sum_j c_j s_j) theta'' + sum_j s_j dp_j / D_jj
        let mut w = DVector::from_element(n, ZERO);
        for j in 0..np {
            w[first + j] = s[first + j] / rates.masses[j];
        }
        if let Some(i_r) = rates.hub {
            let hub_share = (0..np).fold(s[0], |a, j| a - rates.ratios[j] * s[first + j]);
            w[0] = hub_share / i_r;
        }
        let terms = (0..n)
            .filter(|&i| moves(w[i]))
            .map(|i| (w[i], efforts[i]))
            .collect();
        combination(g, name, terms)
    };
    let dual = |v: &DVector<f64>, d: &DVector<f64>| v.zip_map(d, Dual::new);
    let tip = dual(&model.tip, &model.derivative.tip);
    let acc_tip = acc_of(g, format!("{prefix}.acc_tip"), &tip);
    let acc = model
        .accelerometers
        .iter()
        .zip(&model.derivative.accelerometers)
        .enumerate()
        .map(|(k, (s, ds))| acc_of(g, format!("{prefix}.acc[{}]", k + 1), &dual(s, ds)))
        .collect();
    let on_states = |g: &mut BondGraph, name: String, s: &DVector<Dual>| {
        let terms = (0..np)
            .filter(|&j| moves(s[first + j]))
            .map(|j| (s[first + j], qs[j]))
            .collect();
        combination(g, name, terms)
    };
    let w_tip = on_states(g, format!("{prefix}.w_tip"), &tip);
    let stress = dual(&model.stress, &model.derivative.stress);
    let stress = on_states(g, format!("{prefix}.stress"), &stress);
    PlatePorts {
        junctions: coord[first..].to_vec(),
        w_tip,
        acc_tip,
        stress,
        acc,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model(formulation: Formulation) -> PlateModel {
        let p = PlateParameters {
            formulation,
            ..PlateParameters::default()
        };
        PlateModel::new(&p).unwrap()
    }

    /// The one-port inertias on the absolute rates carry the consistent formulation's kinetic
    /// energy `q' M q / 2` (with the air's added mass), and their momenta are the I-field's
    /// `M q'` for the modes: at random rates, to rounding.
    #[test]
    fn absolute_rates_carry_the_mass_matrix() {
        let model = model(Formulation::Consistent);
        let r = model.absolute_rates().expect("the plate block is diagonal");
        let (n, first) = (model.dim(), model.first_plate());
        // The modes the rotation projects on (uniform across the arm) ride on the hub.
        assert!(model.hub && r.ratios.iter().filter(|&&c| c != 0.0).count() >= 3);
        let i_r = r.hub.unwrap();
        assert!(i_r > 0.0 && i_r < model.mass[(0, 0)]);
        let mut seed = 0.3f64;
        for _ in 0..10 {
            let v = DVector::from_fn(n, |_, _| {
                seed = (seed * 997.0 + 0.123).fract();
                seed - 0.5
            });
            let full = 0.5 * (v.transpose() * &model.mass * &v)[(0, 0)];
            let u: Vec<f64> = (0..n - first)
                .map(|j| v[first + j] + r.ratios[j] * v[0])
                .collect();
            let split = 0.5 * i_r * v[0] * v[0]
                + (0..n - first)
                    .map(|j| 0.5 * r.masses[j] * u[j] * u[j])
                    .sum::<f64>();
            assert!((split - full).abs() <= 1e-12 * full, "{split} vs {full}");
            let p_field = &model.mass * &v;
            for j in 0..n - first {
                let p = r.masses[j] * u[j];
                assert!((p - p_field[first + j]).abs() <= 1e-12 * p_field.amax());
            }
        }
    }

    /// The model built along a seeded parameter: its values are the `f64` model's bits, in
    /// both formulations and root conditions, for every parameter.
    fn seeded(p: &PlateParameters, seed: impl Fn(&mut PlateParameters<Dual>)) -> PlateModel {
        let mut dual = p.map(Dual::from);
        seed(&mut dual);
        let model = PlateModel::for_parameters(&dual).unwrap();
        let plain = PlateModel::new(p).unwrap();
        assert_eq!(model.mass, plain.mass);
        assert_eq!(model.stiffness, plain.stiffness);
        assert_eq!(model.damping, plain.damping);
        assert_eq!(model.forces, plain.forces);
        assert_eq!(model.tip, plain.tip);
        assert_eq!(model.stress, plain.stress);
        assert_eq!(model.accelerometers, plain.accelerometers);
        model
    }

    fn configurations() -> Vec<PlateParameters> {
        let mut all = Vec::new();
        for formulation in [Formulation::Paper, Formulation::Consistent] {
            for root in [Root::Hub, Root::Locked] {
                all.push(PlateParameters {
                    formulation,
                    root,
                    ..PlateParameters::default()
                });
            }
        }
        all
    }

    /// `K` is `E` times a matrix of the others (`D = E h^3 / (12 (1 - nu^2))`, and the clamped
    /// plate's modes, eigenvectors of `S K S`, do not move with `E`): `dK/dE = K / E`, `dM/dE =
    /// 0`, and the stress `E h (...)` per unit coordinate `sigma / E`; the shapes' vectors stay
    /// (to the eigen-solver's round-off in the consistent formulation's modes).
    #[test]
    fn along_e_the_stiffness_is_k_over_e() {
        for p in configurations() {
            let what = format!("{:?} {:?}", p.formulation, p.root);
            let m = seeded(&p, |d| d.e.d = 1.0);
            for (name, value, derivative) in [
                ("K", &m.stiffness, &m.derivative.stiffness),
                (
                    "sigma",
                    &DMatrix::from_column_slice(m.dim(), 1, m.stress.as_slice()),
                    &{ DMatrix::from_column_slice(m.dim(), 1, m.derivative.stress.as_slice()) },
                ),
            ] {
                let expect = value / p.e;
                let miss = (derivative - &expect).amax();
                assert!(
                    miss <= 1e-9 * expect.amax(),
                    "{what}: d{name}/dE off by {miss:e}"
                );
            }
            // (The hub's coupling to the modes moves by the modes' round-off.)
            let mass = m.derivative.mass.amax() * p.e / m.mass.amax();
            assert!(mass <= 1e-9, "{what}: M moves with E by {mass:e}");
            // The vectors of shapes: exactly still in the paper's closed forms, to the
            // eigen-solver's round-off in the consistent one's modes.
            let tip = m.derivative.tip.amax() * p.e / m.tip.amax();
            assert!(tip <= 1e-9, "{what}: the tip moves with E by {tip:e}");
        }
    }

    /// Along `h`: `D ∝ h^3` and `m ∝ h`. In the paper's formulation each mode's `k` and `m`
    /// are those closed forms (`dk/dh = 3 k / h`; `dm/dh = m / h` without air), and the hub's
    /// inertia `I_H + 2 I_P` gains `2 I_P / h`. Along `I_H` only `M_00` moves, by 1.
    #[test]
    fn along_h_and_i_h_the_closed_forms() {
        let p = PlateParameters {
            formulation: Formulation::Paper,
            ca: 0.0,
            ..PlateParameters::default()
        };
        let m = seeded(&p, |d| d.h.d = 1.0);
        let k3 = &m.stiffness * (3.0 / p.h);
        assert!((&m.derivative.stiffness - &k3).amax() <= 1e-12 * k3.amax());
        for j in 1..m.dim() {
            let expect = m.mass[(j, j)] / p.h;
            assert!((m.derivative.mass[(j, j)] - expect).abs() <= 1e-14 * expect);
        }
        let expect = 2.0 * p.i_p() / p.h;
        assert!((m.derivative.mass[(0, 0)] - expect).abs() <= 1e-14 * expect);
        for p in configurations() {
            let m = seeded(&p, |d| d.i_h.d = 1.0);
            let mut expect = DMatrix::zeros(m.dim(), m.dim());
            if m.hub {
                expect[(0, 0)] = 1.0;
            }
            assert_eq!(m.derivative.mass, expect);
            assert_eq!(m.derivative.stiffness.amax(), 0.0);
        }
    }

    /// Along every other parameter the model keeps its values' bits (`seeded`).
    #[test]
    fn a_seeded_model_keeps_the_values() {
        for p in configurations() {
            seeded(&p, |d| d.rho.d = 1.0);
            seeded(&p, |d| d.nu.d = 1.0);
            seeded(&p, |d| d.a.d = 1.0);
            seeded(&p, |d| d.b.d = 1.0);
            seeded(&p, |d| d.ca.d = 1.0);
            seeded(&p, |d| d.x1.d = 1.0);
        }
    }

    /// The paper formulation's mass matrix is diagonal: the hub keeps `I_H + 2 I_P` and no mode
    /// rides on it.
    #[test]
    fn the_paper_plate_needs_no_absolute_rates() {
        let model = model(Formulation::Paper);
        let r = model.absolute_rates().unwrap();
        assert!(r.ratios.iter().all(|&c| c == 0.0));
        assert_eq!(r.hub, Some(model.mass[(0, 0)]));
    }
}
