//! Lumped parametric-vibration model of the mesh: the relative rotation along the line of action
//! (1 DOF), optionally with each gear's translation on its bearings along the line of action
//! (3 DOFs), or a drivetrain with elastic gear bodies (hub and rim), shafts, motor and load
//! ([`structure`]), driven by the periodic mesh stiffness k(θ) — the stiffness currency from
//! the LTCA, the explicit FE, ISO 6336, the potential-energy method or a user table.
//!
//! # Equations (rigid pair; [`structure`] generalizes them to M q̈ + C q̇ + K q = F l − g W)
//! p = r_b1θ₁ − r_b2θ₂ is the dynamic transmission error along the line of action; with rigid
//! shafts the torsional 2-DOF reduces exactly to it (torque drive: m_e = I₁I₂/(I₁r_b2² + I₂r_b1²);
//! driver at prescribed speed: m_e = I₂/r_b2²). y₁, y₂ are the bearing translations along the
//! line of action (model (c)); δ = p + y₁ − y₂ is the mesh deflection.
//! ```text
//! m_e p̈ = F − W,   m₁ÿ₁ + c₁ẏ₁ + k₁y₁ = −W,   m₂ÿ₂ + c₂ẏ₂ + k₂y₂ = W,    F = T / r_b2
//! W = k(θ) f(δ − e(θ)) + c δ̇,   θ = Ω₁ t (driver roll angle),   c = 2 ζ √(k̄ m_e)
//! f(u) = u           u > 0         drive-side contact
//!      = 0           −j ≤ u ≤ 0   tooth separation (backlash j)
//!      = u + j       u < −j        back-side contact
//! ```
//! e(θ) is the unloaded transmission error (relief). The viscous mesh damper acts also while the
//! teeth are apart (the usual lumped-model convention, Kahraman & Singh 1990); it is small.
//! The explicit FE's lumped twin puts it where the FE's dashpot is instead, on the hub-to-hub
//! transmission error while the teeth touch ([`DampingSite::HubTransmissionError`]).
//! With a [`MeshModel::force_law`] (the LTCA's W(θ, δ), [`crate::stiffness::ForceLaw`]) the
//! elastic force k(θ) f(δ − e(θ)) is replaced by W(θ, δ) on the drive flanks and −W(ρ − θ,
//! −(δ + j)) on the back flanks: the stiffness grows with the load as the LTCA's does. With a
//! [`MeshModel::back_force_law`] (the LTCA of the back flanks under the reversed torque) the
//! back flanks carry −W_b(θ, −δ) instead, their gap in the law's first contact: right where the
//! mirror is not (backlash shifts it, asymmetric flanks break it).
//! Integration: classical Runge–Kutta 4 with an integer number of steps per mesh period, so every
//! step lands on the same stiffness samples and the periodic steady state is detected from the
//! state at period boundaries (Poincaré map); an adaptive Dormand–Prince 5(4) integration
//! ([`reference_periods`]) is the reference it is checked against, also across the kinks of the
//! backlash law. [`schemes`] measures where fixed-step schemes fail.
//!
//! # Stability (Floquet)
//! Of the model as integrated ([`periodic_orbit`]): the period-one orbit x* = P(x*) of the
//! one-period map P, found by damped Newton shooting, and the eigenvalues of ∂P/∂x at it (central
//! differences) — separation, back flanks and the force law included. Of the linearized drive
//! flanks ([`floquet_multipliers`]):
//! for the linear model (no separation, no TE, no load) the monodromy matrix Φ over one mesh
//! period T_m, from the unit initial states, has eigenvalues λ (the Floquet multipliers); the
//! motion is parametrically unstable when max |λ| > 1. For k = k̄(1 + ε cos Ω_m t) the first
//! instability region lies around Ω_m = 2ω_n with edges Ω_m ≈ 2ω_n(1 ± ε/4) for small ε
//! (Mathieu equation; Nayfeh & Mook, *Nonlinear Oscillations*, §5.2).

pub mod schemes;
pub mod structure;

use nalgebra::DMatrix;

pub use structure::{
    DrivetrainSpec, GearBody, Mode, RimTranslation, Shaft, SpringDamping, Structure, Tangent,
    MAX_DOFS,
};

use crate::stiffness::{ForceLaw, MeshStiffness, PeriodicTable};

/// How the pair is driven: the boundary condition of the relative coordinate p. (The case file
/// and the command line spell it alike: `torque`, `speed`.)
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum Drive {
    /// Both gears free, input and load torques: the torsional 2-DOF reduces exactly to p with
    /// m_e = I₁I₂/(I₁r_b2² + I₂r_b1²).
    #[default]
    Torque,
    /// The driver turns at the prescribed speed, as in the explicit FE: m = I₂/r_b2².
    Speed,
}

impl Drive {
    /// The effective mass of p for gear inertias I₁, I₂ [kg·m²] and base radii r_b1, r_b2 [m].
    pub fn effective_mass(self, inertias: [f64; 2], base_radii: [f64; 2]) -> f64 {
        let ([i1, i2], [rb1, rb2]) = (inertias, base_radii);
        match self {
            Drive::Torque => i1 * i2 / (i1 * rb2 * rb2 + i2 * rb1 * rb1),
            Drive::Speed => i2 / (rb2 * rb2),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Drive::Torque => "torque",
            Drive::Speed => "speed",
        }
    }
}

/// The mesh force law of the lumped model.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum ForceLawKind {
    /// The LTCA's own W(θ, δ), tabulated from first contact to 8.3 × the design torque
    /// ([`crate::stiffness::ForceLaw`]): load-dependent stiffness, loaded contact ratio and
    /// contact loss of relieved tips. Only the `ltca` stiffness source has it; the others give
    /// one k(θ) and stay linear.
    #[default]
    LoadDependent,
    /// W = k(θ)(δ − e(θ)) with the secant k(θ) at the design torque: right at that torque only.
    Secant,
}

impl ForceLawKind {
    pub fn name(self) -> &'static str {
        match self {
            ForceLawKind::LoadDependent => "load-dependent",
            ForceLawKind::Secant => "secant",
        }
    }
}

/// Where the viscous mesh damper acts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DampingSite {
    /// On the mesh deflection, W = … + c δ̇, also while the teeth are apart (the usual
    /// lumped-model convention, Kahraman & Singh 1990).
    #[default]
    MeshDeflection,
    /// On the hub-to-hub transmission error, a force c ḣ along h, only while a flank touches
    /// (W ≠ 0): the explicit FE's dashpot on the driven hub against the DTE rate, which the FE's
    /// lumped twin must carry where the FE carries it. With elastic bodies the hubs move more
    /// in the mesh mode than the mesh deflection does (the driver's rim follows the driven gear
    /// through its body's twist), so the same c damps the mesh mode more here: 1.29 × on the
    /// paper pair, driver at speed (c sized on the hub-to-hub stiffness gives the mode ζ here,
    /// ζ/1.29 on the mesh deflection).
    HubTransmissionError,
}

/// Translation of each gear along the line of action on its bearings (model (c)). The
/// translations across the line of action are left out: a frictionless spur mesh force has no
/// component there, so they are neither excited nor coupled (an exact reduction, not a
/// simplification).
#[derive(Debug, Clone, PartialEq)]
pub struct Bearings {
    /// Translating mass of each gear (blank and its share of the shaft) [kg].
    pub mass: [f64; 2],
    /// Bearing stiffness along the line of action [N/m].
    pub stiffness: [f64; 2],
    /// Bearing damping [N·s/m].
    pub damping: [f64; 2],
}

/// Static deflections (plus backlash and unloaded TE) beyond which a response counts as
/// diverged: a DTE a thousand times the static one (millimetres on a pair deflecting a few
/// µm) is past any tooth's height, and no bounded steady state gets there.
pub const DIVERGENCE_DEFLECTIONS: f64 = 1e3;

/// The lumped mesh model: the nonlinear mesh in a linear [`Structure`] — 1 DOF (p), 3 DOFs
/// (p, y₁, y₂) with [`Bearings`], or a drivetrain with elastic gear bodies and shafts.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshModel {
    /// The linear structure around the mesh (masses, shafts, bodies, bearings).
    pub structure: Structure,
    /// Mesh stiffness k(θ) and unloaded transmission error e(θ) along the line of action.
    pub mesh: MeshStiffness,
    /// Viscous mesh damping c [N·s/m].
    pub damping: f64,
    /// Where the damper acts ([`DampingSite`]).
    pub damping_site: DampingSite,
    /// Static mesh force F = T/r_b2 [N].
    pub force: f64,
    /// Backlash j along the line of action [m]; `None`: no separation (linear contact).
    pub backlash: Option<f64>,
    /// Where the back flanks' own k and e are read (see [`MeshModel::mesh_force`]):
    /// `Some(ρ)`: at the mirrored angle ρ − θ; `None`: at θ, with e a positional error.
    pub back_reflection: Option<f64>,
    /// The load-dependent force law W(θ, δ) of the flanks (θ from the same origin as `mesh`);
    /// `None`: the secant law k(θ)(δ − e(θ)) of `mesh`, linear in δ. `mesh` stays the secant at
    /// the design load (the mean stiffness of the damping ratio and the natural frequency).
    pub force_law: Option<ForceLaw>,
    /// The back flanks' own force law W_b(θ, δ_b) (the LTCA of the back flanks under the
    /// reversed torque, at the drive law's positions θ; δ_b = −δ, its first contact the whole
    /// back gap, backlash and relief): when set, it replaces the mirror of `back_reflection` and
    /// the backlash j on the back flanks.
    pub back_force_law: Option<ForceLaw>,
}

/// State of the lumped model: the structure's coordinates q [m] and their velocities [m/s]
/// (the first [`Structure::dofs`] entries; the rest stay 0).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct State {
    pub q: [f64; MAX_DOFS],
    pub v: [f64; MAX_DOFS],
}

impl From<(f64, f64)> for State {
    /// The first coordinate and its rate (p, ṗ for a rigid pair), the others at rest.
    fn from((p, v): (f64, f64)) -> Self {
        let mut s = State::default();
        s.q[0] = p;
        s.v[0] = v;
        s
    }
}

impl State {
    /// self + h·d, component-wise.
    fn add_scaled(&self, h: f64, d: &State) -> State {
        State {
            q: std::array::from_fn(|i| self.q[i] + h * d.q[i]),
            v: std::array::from_fn(|i| self.v[i] + h * d.v[i]),
        }
    }

    /// Component `i` of the flattened state (q then v, [`MAX_DOFS`] each).
    fn component(&self, i: usize) -> f64 {
        if i < MAX_DOFS {
            self.q[i]
        } else {
            self.v[i - MAX_DOFS]
        }
    }

    fn component_mut(&mut self, i: usize) -> &mut f64 {
        if i < MAX_DOFS {
            &mut self.q[i]
        } else {
            &mut self.v[i - MAX_DOFS]
        }
    }

    fn unit(i: usize) -> State {
        let mut s = State::default();
        *s.component_mut(i) = 1.0;
        s
    }
}

impl MeshModel {
    /// Damping coefficient for a damping ratio ζ at the mean stiffness: c = 2ζ√(k̄ m_e), m_e
    /// the rigid pair's effective mass ([`Structure::effective_mass`]).
    pub fn damping_from_ratio(&self, ratio: f64) -> f64 {
        2.0 * ratio * (self.mesh.mean() * self.structure.effective_mass).sqrt()
    }

    /// The rigid pair's effective mass under the model's drive [kg].
    pub fn effective_mass(&self) -> f64 {
        self.structure.effective_mass
    }

    /// Natural frequency of the mesh mode at the mean stiffness [rad/s]: √(k̄/m_e) for a rigid
    /// pair on rigid bearings, else the structure's mode with the most mesh strain energy.
    pub fn natural_frequency(&self) -> f64 {
        self.structure.mesh_mode(self.mesh.mean()).frequency
    }

    /// Damping ratio of the mesh mode at the mean stiffness, to first order in the damping:
    /// ζ = (φᵀCφ + c (sᵀφ)²) / (2ω φᵀMφ), φ the undamped mode, C the structure's damping, s
    /// the damper's direction (g on the mesh deflection, h on the hubs' TE, [`DampingSite`]).
    /// For a rigid pair c = 2ζ√(k̄ m_e) gives back ζ; with elastic bodies each site sees its own
    /// share of the mode.
    pub fn mesh_mode_damping_ratio(&self) -> f64 {
        let s = &self.structure;
        let mode = s.mesh_mode(self.mesh.mean());
        let phi = nalgebra::DVector::from_vec(mode.shape);
        let direction = match self.damping_site {
            DampingSite::MeshDeflection => &s.mesh_direction,
            DampingSite::HubTransmissionError => &s.te_direction,
        };
        let dissipation =
            phi.dot(&(&s.damping * &phi)) + self.damping * direction.dot(&phi).powi(2);
        dissipation / (2.0 * mode.frequency * phi.dot(&(&s.mass * &phi)))
    }

    /// Indices of the flattened state that move: the structure's coordinates and their rates.
    fn active_components(&self) -> Vec<usize> {
        let n = self.structure.dofs;
        (0..n).chain(MAX_DOFS..MAX_DOFS + n).collect()
    }

    /// Undamped natural frequencies [rad/s] of the linear model at mesh stiffness k, ascending.
    pub fn mode_frequencies(&self, mesh_stiffness: f64) -> Vec<f64> {
        self.structure
            .modes(mesh_stiffness)
            .iter()
            .map(|m| m.frequency)
            .collect()
    }

    /// Mesh deflection along the line of action δ = gᵀq [m] (p + y₁ − y₂ for a rigid pair on
    /// bearings).
    pub fn mesh_deflection(&self, s: &State) -> f64 {
        self.structure.mesh_of(&s.q)
    }

    /// The transmission error the model reports, hub to hub along the line of action [m]: p for
    /// a rigid pair; with elastic bodies it holds their twist, as the LTCA's and the FE's do.
    pub fn transmission_error(&self, s: &State) -> f64 {
        self.structure.te_of(&s.q) + self.force * self.structure.te_per_force
    }

    /// Its rate [m/s].
    pub fn transmission_error_rate(&self, s: &State) -> f64 {
        self.structure.te_of(&s.v)
    }

    /// The highest natural frequency the integration must resolve: at the largest mesh
    /// stiffness, the secant's or, with a force law, the largest slope of its knots (adding
    /// stiffness never lowers an eigenvalue, so this bounds every contact state the law
    /// tabulates, separation included; past its last knot the law keeps that knot's slope).
    pub fn highest_frequency(&self) -> f64 {
        let law = [&self.force_law, &self.back_force_law]
            .into_iter()
            .flatten()
            .fold(0.0, |m, law| law.max_slope().max(m));
        *self
            .mode_frequencies(self.mesh.max().max(law))
            .last()
            .expect("at least one mode")
    }

    /// Elastic mesh force at mesh deflection δ (≥ 0 on the drive side, < 0 on the back side).
    /// Drive flanks: W = W_d(θ, δ), the secant law k(θ)(δ − e(θ)) while δ > e(θ), or the
    /// [`MeshModel::force_law`]. Back flanks, once the backlash j is taken up: with
    /// [`MeshModel::back_reflection`] ρ, the back flanks are the drive flanks of the mirrored
    /// pair (symmetric teeth and relief: mirroring about the centre line swaps the flanks and
    /// turns θ into ρ − θ), so they carry the drive flanks' law at ρ − θ with the approach
    /// −(δ + j): W = −W_d(ρ − θ, −(δ + j)); for the secant law that is k_b (δ + j + e_b) while
    /// δ + j + e_b < 0, with k_b = k(ρ − θ), e_b = e(ρ − θ) (the relief widens the gap). Without
    /// it, the drive side's law reads e as a positional error (shifting both flanks alike):
    /// W = −W_d(θ, 2e(θ) − δ − j).
    pub fn mesh_force(&self, theta: f64, deflection: f64) -> f64 {
        let drive = self.drive_force(theta, deflection);
        match self.backlash {
            None => drive,
            Some(_) if drive > 0.0 => drive,
            Some(j) => {
                let back = match (&self.back_force_law, self.back_reflection) {
                    (Some(law), _) => law.force(theta, -deflection),
                    (None, Some(rho)) => self.drive_force(rho - theta, -(deflection + j)),
                    (None, None) => {
                        let e = self.mesh.unloaded_te.at(theta);
                        self.drive_force(theta, 2.0 * e - deflection - j)
                    }
                };
                -back.max(0.0)
            }
        }
    }

    /// The drive flanks' force at approach δ: the force law, or the secant law (which goes on
    /// into tension below first contact; [`MeshModel::mesh_force`] decides what that means).
    fn drive_force(&self, theta: f64, deflection: f64) -> f64 {
        match &self.force_law {
            Some(law) if self.backlash.is_some() => law.force(theta, deflection),
            Some(law) => {
                let first = law.first_contact(theta);
                if deflection > first {
                    law.force(theta, deflection)
                } else {
                    // The no-separation model: the law's first-contact slope into tension.
                    law.force_and_slope(theta, first + 1e-12).1 * (deflection - first)
                }
            }
            None => self.mesh.stiffness.at(theta) * (deflection - self.mesh.unloaded_te.at(theta)),
        }
    }

    /// [`MeshModel::mesh_force`] and its slope dW/dδ [N/m], for the variational equation: the
    /// one-sided slope at a kink where a flank carries load; where no flank does (W = 0: apart,
    /// or exactly at a first contact, as on an unloaded orbit that stays on the switch) the mean
    /// of both sides' slopes, by a central difference over ±1e-12 m.
    pub fn mesh_force_and_slope(&self, theta: f64, deflection: f64) -> (f64, f64) {
        let (force, slope) = self.loaded_force_and_slope(theta, deflection);
        if force != 0.0 {
            return (force, slope);
        }
        const STEP: f64 = 1e-12;
        let plus = self.mesh_force(theta, deflection + STEP);
        let minus = self.mesh_force(theta, deflection - STEP);
        (force, (plus - minus) / (2.0 * STEP))
    }

    /// [`MeshModel::mesh_force_and_slope`] with the one-sided slopes of the loaded flank.
    fn loaded_force_and_slope(&self, theta: f64, deflection: f64) -> (f64, f64) {
        let drive = self.drive_force_and_slope(theta, deflection);
        match self.backlash {
            None => drive,
            Some(_) if drive.0 > 0.0 => drive,
            Some(j) => {
                // W = −W_b(…, −δ …): dW/dδ = +W_b′.
                let (back, slope) = match (&self.back_force_law, self.back_reflection) {
                    (Some(law), _) => law.force_and_slope(theta, -deflection),
                    (None, Some(rho)) => self.drive_force_and_slope(rho - theta, -(deflection + j)),
                    (None, None) => {
                        let e = self.mesh.unloaded_te.at(theta);
                        self.drive_force_and_slope(theta, 2.0 * e - deflection - j)
                    }
                };
                match back > 0.0 {
                    true => (-back, slope),
                    false => (-0.0, 0.0),
                }
            }
        }
    }

    /// [`MeshModel::drive_force`] and its slope.
    fn drive_force_and_slope(&self, theta: f64, deflection: f64) -> (f64, f64) {
        match &self.force_law {
            Some(law) if self.backlash.is_some() => law.force_and_slope(theta, deflection),
            Some(law) => {
                let first = law.first_contact(theta);
                if deflection > first {
                    law.force_and_slope(theta, deflection)
                } else {
                    let slope = law.force_and_slope(theta, first + 1e-12).1;
                    (slope * (deflection - first), slope)
                }
            }
            None => {
                let k = self.mesh.stiffness.at(theta);
                (k * (deflection - self.mesh.unloaded_te.at(theta)), k)
            }
        }
    }

    /// The mesh damper's coefficients on g and on h at this state (c on its site; the hub
    /// site's only while a flank touches, [`DampingSite`]).
    fn damper(&self, elastic_force: f64) -> [f64; 2] {
        match self.damping_site {
            DampingSite::MeshDeflection => [self.damping, 0.0],
            DampingSite::HubTransmissionError => {
                let touching = elastic_force != 0.0 || self.backlash.is_none();
                [0.0, f64::from(touching) * self.damping]
            }
        }
    }

    /// Whether the vector field is continuous across every contact switch (the force law and
    /// the secant law are; the hub site's damper switches on and off with the contact): then
    /// the variational equation gives the period map's exact Jacobian, with no saltation.
    fn continuous_field(&self) -> bool {
        self.damping_site == DampingSite::MeshDeflection || self.backlash.is_none()
    }

    /// The time derivative ([`MeshModel::derivative`]) and its Jacobian over the active
    /// components (q then v, 2n × 2n) at roll angle θ.
    fn derivative_and_jacobian(&self, theta: f64, s: &State, jacobian: &mut Tangent) -> State {
        let (elastic, slope) = self.mesh_force_and_slope(theta, self.structure.mesh_of(&s.q));
        let (d, dampers) = self.derivative_under(elastic, s);
        self.structure.state_jacobian(slope, dampers, jacobian);
        d
    }

    /// The time derivative with the elastic mesh force W(θ, δ) given, and the dampers'
    /// coefficients [c_g, c_h] it used.
    #[inline]
    fn derivative_under(&self, elastic: f64, s: &State) -> (State, [f64; 2]) {
        let structure = &self.structure;
        let [c_mesh, c_hub] = self.damper(elastic);
        let w = elastic + c_mesh * structure.mesh_of(&s.v);
        let hub = c_hub * structure.te_of(&s.v);
        let mut d = State {
            q: s.v,
            v: [0.0; MAX_DOFS],
        };
        structure.accelerations(&s.q, &s.v, self.force, [w, hub], &mut d.v);
        (d, [c_mesh, c_hub])
    }

    /// The mesh deflection δ under the static force F at roll angle θ: the model's quasi-static
    /// approach along the line of action (W(θ, δ) = F).
    pub fn quasi_static_deflection(&self, theta: f64) -> f64 {
        match &self.force_law {
            Some(law) if self.force > 0.0 => law.deflection_under(theta, self.force),
            _ => self.mesh.unloaded_te.at(theta) + self.force / self.mesh.stiffness.at(theta),
        }
    }

    /// The quasi-static state at roll angle θ: the mesh at [`MeshModel::quasi_static_deflection`]
    /// carrying F, the structure deflected statically, at rest.
    pub fn quasi_static_state(&self, theta: f64) -> State {
        State {
            q: self
                .structure
                .static_coordinates(self.force, self.quasi_static_deflection(theta)),
            v: [0.0; MAX_DOFS],
        }
    }

    /// The quasi-static transmission error at θ (hub to hub, [`MeshModel::transmission_error`]):
    /// the model's STE, what the LTCA gives at the same torque.
    pub fn quasi_static_transmission_error(&self, theta: f64) -> f64 {
        self.transmission_error(&self.quasi_static_state(theta))
    }

    /// The largest excursion of the mesh deflection from the static state the model stands for
    /// [m]: [`DIVERGENCE_DEFLECTIONS`] × (the static deflection F/k̄, plus the backlash and the
    /// unloaded TE's largest value; at least 1 µm). Farther than that a response has grown
    /// without bound (in practice a linear parametric instability, with too little damping to
    /// hold it).
    pub fn divergence_bound(&self) -> f64 {
        let te = self
            .mesh
            .unloaded_te
            .values
            .iter()
            .fold(0.0f64, |m, e| m.max(e.abs()));
        // At least 1 µm as the scale, so an unloaded model (F = 0) has a bound too: 1 mm.
        let scale = (self.force / self.mesh.mean()).abs() + self.backlash.unwrap_or(0.0).abs() + te;
        DIVERGENCE_DEFLECTIONS * scale.max(1e-6)
    }

    /// Whether `state` has left the model's range or is not finite ([`DivergenceCheck`]). In a
    /// loop, build the check once with [`MeshModel::divergence_check`].
    pub fn has_diverged(&self, state: &State) -> bool {
        self.divergence_check().diverged(state)
    }

    /// The static state and each coordinate's bound, computed once (a linear solve) for the
    /// checks of a run's periods or steps.
    pub fn divergence_check(&self) -> DivergenceCheck {
        let reference = self.static_state();
        let mesh_bound = self.divergence_bound();
        DivergenceCheck {
            dofs: self.structure.dofs,
            bounds: std::array::from_fn(|i| {
                mesh_bound.max(DIVERGENCE_DEFLECTIONS * reference.q[i].abs())
            }),
            reference,
        }
    }

    /// The static state under F at the mean stiffness (TE and backlash left out): the mesh at
    /// δ = F/k̄ (for bearings y₁ = −F/k_b1, y₂ = F/k_b2).
    pub fn static_state(&self) -> State {
        State {
            q: self
                .structure
                .static_coordinates(self.force, self.force / self.mesh.mean()),
            v: [0.0; MAX_DOFS],
        }
    }

    /// Time derivative of the state at roll angle θ: M q̈ + C q̇ + K q = F l − g W,
    /// W = k(θ) f(δ − e(θ)) + c δ̇, δ = gᵀq (for a rigid pair on bearings:
    /// m_e p̈ = F − W, m₁ÿ₁ + c₁ẏ₁ + k₁y₁ = −W, m₂ÿ₂ + c₂ẏ₂ + k₂y₂ = W).
    /// (W is the mesh force on the driven gear along the line of action; the driver takes −W.)
    pub fn derivative(&self, theta: f64, s: &State) -> State {
        let elastic = self.mesh_force(theta, self.structure.mesh_of(&s.q));
        self.derivative_under(elastic, s).0
    }

    /// The linear model of the Floquet analysis: no load, no TE, no separation; with a force
    /// law, the tangent stiffness dW/dδ about the quasi-static state under F (what small
    /// vibrations about the loaded mesh feel), sampled as finely as the law.
    pub(crate) fn linearized(&self) -> MeshModel {
        let stiffness = match &self.force_law {
            Some(law) => PeriodicTable::from_fn(self.mesh.period(), law.knots.len(), |theta| {
                law.force_and_slope(theta, self.quasi_static_deflection(theta))
                    .1
            }),
            None => self.mesh.stiffness.clone(),
        };
        MeshModel {
            backlash: None,
            force: 0.0,
            mesh: MeshStiffness {
                stiffness,
                unloaded_te: PeriodicTable::constant(self.mesh.period(), 0.0),
                ..self.mesh.clone()
            },
            force_law: None,
            back_force_law: None,
            ..self.clone()
        }
    }
}

/// Whether a state has left the model's range: a coordinate farther from the static state than
/// [`MeshModel::divergence_bound`] or [`DIVERGENCE_DEFLECTIONS`] × its own static value (a soft
/// bearing's or shaft's bounded resonance is not divergence), or a value not finite.
#[derive(Debug, Clone, Copy)]
pub struct DivergenceCheck {
    dofs: usize,
    reference: State,
    bounds: [f64; MAX_DOFS],
}

impl DivergenceCheck {
    pub fn diverged(&self, state: &State) -> bool {
        let n = self.dofs;
        let finite = state.q[..n]
            .iter()
            .chain(&state.v[..n])
            .all(|x| x.is_finite());
        !finite || (0..n).any(|i| !((state.q[i] - self.reference.q[i]).abs() <= self.bounds[i]))
    }
}

/// Classical Runge–Kutta step of length h from time t, for ṡ = f(t, s).
pub fn rk4_step(f: impl Fn(f64, &State) -> State, t: f64, s: &State, h: f64) -> State {
    let k1 = f(t, s);
    let k2 = f(t + 0.5 * h, &s.add_scaled(0.5 * h, &k1));
    let k3 = f(t + 0.5 * h, &s.add_scaled(0.5 * h, &k2));
    let k4 = f(t + h, &s.add_scaled(h, &k3));
    State {
        q: std::array::from_fn(|i| {
            s.q[i] + h / 6.0 * (k1.q[i] + 2.0 * k2.q[i] + 2.0 * k3.q[i] + k4.q[i])
        }),
        v: std::array::from_fn(|i| {
            s.v[i] + h / 6.0 * (k1.v[i] + 2.0 * k2.v[i] + 2.0 * k3.v[i] + k4.v[i])
        }),
    }
}

/// One period of the periodic steady state.
#[derive(Debug, Clone, PartialEq)]
pub struct SteadyState {
    /// Mesh periods integrated until the state repeated (with [`settle`]: the shooting's too).
    pub periods: usize,
    pub converged: bool,
    /// The state at the start of the recorded period (θ = 0).
    pub start: State,
    /// Samples over one mesh period: the DTE ([`MeshModel::transmission_error`]) [m], its rate [m/s], the
    /// elastic mesh force [N].
    pub displacement: Vec<f64>,
    pub velocity: Vec<f64>,
    pub mesh_force: Vec<f64>,
    /// Whether the mesh force was zero (teeth apart) anywhere in the period.
    pub separated: bool,
    /// The response grew without bound ([`MeshModel::has_diverged`]) in period `periods`; the
    /// samples are not a steady state then.
    pub diverged: bool,
}

impl SteadyState {
    /// The largest elastic mesh force over the recorded period over `static_force`: the
    /// dynamic factor.
    pub fn dynamic_factor(&self, static_force: f64) -> f64 {
        self.mesh_force
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max)
            / static_force
    }
}

/// Integrates at driver speed Ω₁ (rad/s) from `initial` until the state at period boundaries
/// repeats to `tolerance` (relative to the static deflection), at most `max_periods`.
pub fn steady_state(
    model: &MeshModel,
    driver_speed: f64,
    steps_per_period: usize,
    initial: impl Into<State>,
    tolerance: f64,
    max_periods: usize,
) -> SteadyState {
    let static_deflection = (model.force / model.mesh.mean()).abs().max(1e-30);
    let divergence = model.divergence_check();
    let mut state = initial.into();
    let mut out = SteadyState {
        periods: 0,
        converged: false,
        start: state,
        displacement: vec![0.0; steps_per_period],
        velocity: vec![0.0; steps_per_period],
        mesh_force: vec![0.0; steps_per_period],
        separated: false,
        diverged: false,
    };
    let omega_scale = model.highest_frequency().max(driver_speed);
    // The mesh force of the period kept only, from its angles and deflections (an evaluation
    // of the law per step saved in every other period).
    let mut samples = vec![(0.0, 0.0); steps_per_period];
    let mesh_forces = |out: &mut SteadyState, samples: &[(f64, f64)]| {
        for (force, &(theta, deflection)) in out.mesh_force.iter_mut().zip(samples) {
            *force = model.mesh_force(theta, deflection);
        }
    };
    for period in 1..=max_periods {
        let start = state;
        state = integrate_period(
            model,
            driver_speed,
            steps_per_period,
            start,
            |j, theta, s| {
                out.displacement[j] = model.transmission_error(s);
                out.velocity[j] = model.transmission_error_rate(s);
                samples[j] = (theta, model.mesh_deflection(s));
            },
        );
        out.periods = period;
        out.start = start;
        if divergence.diverged(&state) {
            out.diverged = true;
            mesh_forces(&mut out, &samples);
            return out;
        }
        let change = (0..model.structure.dofs)
            .map(|i| {
                (state.q[i] - start.q[i])
                    .abs()
                    .max((state.v[i] - start.v[i]).abs() / omega_scale)
            })
            .fold(0.0, f64::max);
        if change < tolerance * static_deflection {
            out.converged = true;
            break;
        }
    }
    mesh_forces(&mut out, &samples);
    out.separated = model.backlash.is_some() && out.mesh_force.iter().any(|f| *f <= 0.0);
    out
}

/// The change of the state over a period at which [`settle`] tries to jump to the period-one
/// orbit, of the static deflection: small enough that the one-period map is close to linear
/// about it (its second-order terms are ~1e-6 of the state).
pub const SHOOTING_START: f64 = 1e-3;

/// The largest multiplier of an orbit [`settle`] jumps to: one that the motion approaches by at
/// least 0.1 % per period (closer to 1 the free vibration hardly decays, and plain
/// integration's verdict stands).
pub const SHOOTING_MAX_MULTIPLIER: f64 = 0.999;

/// The steady state of [`steady_state`], reached faster, and the period-one orbit it lies on
/// (`None` where it did not settle on one). Integrated period by period from `initial`; once a
/// period changes the state by less than [`SHOOTING_START`] of the static deflection, shooting
/// ([`periodic_orbit`], tolerance `tolerance`) finds the orbit the motion is heading for. It is
/// taken only if it is what forward integration converges to: stable with a margin
/// (|λ| ≤ [`SHOOTING_MAX_MULTIPLIER`]), and no farther from the state than the linear map lets
/// the state still travel, 2|Δ|/(1 − |λ|) with Δ the last period's change (so on a hysteresis
/// branch the continuation keeps its branch). Then one period integrated from it must come back
/// to `tolerance`, else the integration goes on. Where it settles, diverges or runs out without
/// an orbit, the last period is integrated again by [`steady_state`] (which records it and
/// decides, as it would have). The result is the same steady state to `tolerance`; `periods`
/// counts every period integrated, the shooting's included ([`PeriodicOrbit::periods`]).
pub fn settle(
    model: &MeshModel,
    driver_speed: f64,
    steps_per_period: usize,
    initial: State,
    tolerance: f64,
    max_periods: usize,
) -> (SteadyState, Option<PeriodicOrbit>) {
    let static_deflection = (model.force / model.mesh.mean()).abs().max(1e-30);
    // steady_state's measure of a period's change.
    let omega_scale = model.highest_frequency().max(driver_speed);
    let distance = |a: &State, b: &State| {
        (0..model.structure.dofs)
            .map(|i| {
                (a.q[i] - b.q[i])
                    .abs()
                    .max((a.v[i] - b.v[i]).abs() / omega_scale)
            })
            .fold(0.0, f64::max)
    };
    let divergence = model.divergence_check();
    let mut state = initial;
    let (mut periods, mut shooting_periods) = (0, 0);
    let mut tried = false;
    while periods + 1 < max_periods {
        let start = state;
        state = integrate_period(model, driver_speed, steps_per_period, start, |_, _, _| {});
        let change = distance(&state, &start);
        if !change.is_finite()
            || divergence.diverged(&state)
            || change < tolerance * static_deflection
        {
            // steady_state integrates this period again, records it and decides.
            state = start;
            break;
        }
        periods += 1;
        if tried || change > SHOOTING_START * static_deflection {
            continue;
        }
        tried = true;
        let Some(orbit) = periodic_orbit(model, driver_speed, steps_per_period, state, tolerance)
        else {
            continue;
        };
        shooting_periods = orbit.periods;
        let rho = orbit.max_multiplier();
        if rho <= SHOOTING_MAX_MULTIPLIER
            && distance(&orbit.start, &state) <= 2.0 * change / (1.0 - rho)
        {
            let landed = steady_state(
                model,
                driver_speed,
                steps_per_period,
                orbit.start,
                tolerance,
                1,
            );
            if landed.converged {
                return (
                    SteadyState {
                        periods: periods + shooting_periods + 1,
                        ..landed
                    },
                    Some(orbit),
                );
            }
        }
    }
    let rest = steady_state(
        model,
        driver_speed,
        steps_per_period,
        state,
        tolerance,
        max_periods - periods,
    );
    let orbit = match rest.converged {
        true => periodic_orbit(model, driver_speed, steps_per_period, rest.start, tolerance),
        false => None,
    };
    let orbit_periods = orbit.as_ref().map_or(0, |o| o.periods);
    (
        SteadyState {
            periods: periods + shooting_periods + rest.periods + orbit_periods,
            ..rest
        },
        orbit,
    )
}

/// The DTE ([`MeshModel::transmission_error`]) over `periods` whole mesh periods from `start` (θ = 0), `steps_per_period` samples
/// each: the record a spectrum of a non-periodic (sub-harmonic, quasi-periodic) response needs.
pub fn record_periods(
    model: &MeshModel,
    driver_speed: f64,
    steps_per_period: usize,
    start: State,
    periods: usize,
) -> Vec<f64> {
    let mut record = Vec::with_capacity(periods * steps_per_period);
    let mut state = start;
    for _ in 0..periods {
        state = integrate_period(model, driver_speed, steps_per_period, state, |_, _, s| {
            record.push(model.transmission_error(s))
        });
    }
    record
}

/// Floquet multipliers' largest modulus of the linear model (no separation, no TE) at driver
/// speed Ω₁: eigenvalues of the monodromy matrix over one mesh period (2n×2n for the structure's n
/// coordinates), columns from the unit initial states.
pub fn floquet_max_multiplier(
    model: &MeshModel,
    driver_speed: f64,
    steps_per_period: usize,
) -> f64 {
    largest_modulus(&floquet_multipliers(model, driver_speed, steps_per_period))
}

/// The largest |λ| of a set of Floquet multipliers.
pub fn largest_modulus(multipliers: &[nalgebra::Complex<f64>]) -> f64 {
    multipliers.iter().map(|l| l.norm()).fold(0.0, f64::max)
}

/// The Floquet multipliers λ of the linear model at driver speed Ω₁: the eigenvalues of the
/// monodromy matrix over one mesh period.
pub fn floquet_multipliers(
    model: &MeshModel,
    driver_speed: f64,
    steps_per_period: usize,
) -> Vec<nalgebra::Complex<f64>> {
    linear_floquet_multipliers(&model.linearized(), driver_speed, steps_per_period)
}

/// [`floquet_multipliers`] of a model already [`MeshModel::linearized`]: the linearization
/// (the law's tangent about the quasi-static state at every position) does not depend on the
/// speed, so a sweep or a map makes it once.
pub fn linear_floquet_multipliers(
    linear: &MeshModel,
    driver_speed: f64,
    steps_per_period: usize,
) -> Vec<nalgebra::Complex<f64>> {
    let active = linear.active_components();
    let n = active.len();
    let mut monodromy = DMatrix::zeros(n, n);
    for (column, &i) in active.iter().enumerate() {
        let end = integrate_period(
            linear,
            driver_speed,
            steps_per_period,
            State::unit(i),
            |_, _, _| {},
        );
        for (row, &j) in active.iter().enumerate() {
            monodromy[(row, column)] = end.component(j);
        }
    }
    monodromy.complex_eigenvalues().iter().copied().collect()
}

/// The one-period map P of the model as it is integrated — load, unloaded TE, force law,
/// separation and back flanks included — at `x` (θ = 0), and its Jacobian ∂P/∂x there, in the
/// balanced coordinates (q, v/ω) over the active components (ω the highest natural frequency;
/// same eigenvalues). Where the vector field is continuous across the contact switches
/// ([`MeshModel::continuous_field`]: W is, a flank's force starting from zero, and a damper
/// that acts always), the variational equation integrated alongside ([`period_map_variational`]):
/// the exact derivative of the RK4 map, at about the cost of one period. Else (the hub site's
/// damper switches with the contact, a jump the variational equation misses) central
/// differences of [`integrate_period`] ([`period_map_differences`]).
fn period_map_jacobian(
    model: &MeshModel,
    driver_speed: f64,
    steps_per_period: usize,
    x: State,
) -> (State, DMatrix<f64>) {
    match model.continuous_field() {
        true => period_map_variational(model, driver_speed, steps_per_period, x),
        false => period_map_differences(model, driver_speed, steps_per_period, x),
    }
}

/// P(x) and ∂P/∂x by the variational equation: with every RK4 stage k_i = f(x_i) also
/// K_i = A(x_i)(Φ + c_i h K_{i−1}), A = ∂f/∂x ([`MeshModel::derivative_and_jacobian`]), and
/// Φ ← Φ + h/6 (K₁ + 2K₂ + 2K₃ + K₄) from Φ = I: the derivative of the RK4 map itself (RK4 is
/// linear in its stages). With W continuous a path crossing a switch needs no saltation
/// (Leine & Nijmeijer 2004, *Dynamics and Bifurcations of Non-Smooth Mechanical Systems*,
/// ch. 3), and the kinks' one-sided slopes are the derivative.
pub fn period_map_variational(
    model: &MeshModel,
    driver_speed: f64,
    steps_per_period: usize,
    x: State,
) -> (State, DMatrix<f64>) {
    let n = model.structure.dofs;
    let m = 2 * n;
    let h = model.mesh.period() / driver_speed / steps_per_period as f64;
    let mut phi: Tangent = [[0.0; 2 * MAX_DOFS]; 2 * MAX_DOFS];
    for (i, row) in phi.iter_mut().enumerate().take(m) {
        row[i] = 1.0;
    }
    let stages = std::cell::RefCell::new([[[0.0; 2 * MAX_DOFS]; 2 * MAX_DOFS]; 4]);
    let stage = std::cell::Cell::new(0);
    let derivative = |t: f64, s: &State| {
        let i = stage.get();
        stage.set(i + 1);
        model.derivative_and_jacobian(driver_speed * t, s, &mut stages.borrow_mut()[i])
    };
    let mut state = x;
    let mut k: [Tangent; 4] = [[[0.0; 2 * MAX_DOFS]; 2 * MAX_DOFS]; 4];
    let mut shifted: Tangent = [[0.0; 2 * MAX_DOFS]; 2 * MAX_DOFS];
    for j in 0..steps_per_period {
        stage.set(0);
        state = rk4_step(derivative, j as f64 * h, &state, h);
        let a = stages.borrow();
        for (i, fraction) in [0.0, 0.5, 0.5, 1.0].into_iter().enumerate() {
            for r in 0..m {
                for c in 0..m {
                    shifted[r][c] = match i {
                        0 => phi[r][c],
                        _ => phi[r][c] + fraction * h * k[i - 1][r][c],
                    };
                }
            }
            for r in 0..m {
                for c in 0..m {
                    k[i][r][c] = (0..m).map(|l| a[i][r][l] * shifted[l][c]).sum();
                }
            }
        }
        for r in 0..m {
            for c in 0..m {
                phi[r][c] +=
                    h / 6.0 * (k[0][r][c] + 2.0 * k[1][r][c] + 2.0 * k[2][r][c] + k[3][r][c]);
            }
        }
    }
    let omega = model.highest_frequency();
    let jacobian = DMatrix::from_fn(m, m, |r, c| {
        let balance = match (r < n, c < n) {
            (true, false) => omega,
            (false, true) => 1.0 / omega,
            _ => 1.0,
        };
        phi[r][c] * balance
    });
    (state, jacobian)
}

/// P(x) and ∂P/∂x by central differences of [`integrate_period`] (positions perturbed by 1e-5
/// of the static deflection, velocities by as much times ω). Where a perturbed path crosses a
/// contact switch the differences average the two sides' slopes (the saltation of a
/// piecewise-smooth system, to the perturbation's size).
pub fn period_map_differences(
    model: &MeshModel,
    driver_speed: f64,
    steps_per_period: usize,
    x: State,
) -> (State, DMatrix<f64>) {
    let active = model.active_components();
    let n = active.len();
    let scale = (model.force / model.mesh.mean()).abs().max(1e-9) * 1e-5;
    let omega = model.highest_frequency();
    let map = |s: State| integrate_period(model, driver_speed, steps_per_period, s, |_, _, _| {});
    let mut jacobian = DMatrix::zeros(n, n);
    for (column, &i) in active.iter().enumerate() {
        let h = if i < MAX_DOFS { scale } else { scale * omega };
        let end = |sign: f64| {
            let mut s = x;
            *s.component_mut(i) += sign * h;
            map(s)
        };
        let (plus, minus) = (end(1.0), end(-1.0));
        for (row, &j) in active.iter().enumerate() {
            let balance = match (j < MAX_DOFS, i < MAX_DOFS) {
                (true, false) => omega,
                (false, true) => 1.0 / omega,
                _ => 1.0,
            };
            jacobian[(row, column)] =
                (plus.component(j) - minus.component(j)) / (2.0 * h) * balance;
        }
    }
    (map(x), jacobian)
}

/// A period-one orbit of the integrated model and its Floquet multipliers.
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodicOrbit {
    /// The state at θ = 0 that returns to itself after one mesh period.
    pub start: State,
    /// Eigenvalues of the one-period map's Jacobian at `start`.
    pub multipliers: Vec<nalgebra::Complex<f64>>,
    /// Newton iterations the shooting took (0: `start` was given on the orbit).
    pub iterations: usize,
    /// Mesh periods the shooting integrated, counted as plain ones: a variational Jacobian as
    /// one, a differenced one as 2n + 1, each trial step as one.
    pub periods: usize,
}

impl PeriodicOrbit {
    /// The largest |λ| (> 1: the periodic response is unstable and the motion leaves it).
    pub fn max_multiplier(&self) -> f64 {
        largest_modulus(&self.multipliers)
    }
}

/// Shooting: the period-one orbit of the integrated model near `guess`, by Newton on
/// r(x) = P(x) − x = 0 with the Jacobian of [`period_map_jacobian`], stopped when the state
/// returns to `tolerance` of the static deflection (velocities over ω). It finds unstable orbits
/// too, which forward integration never settles on. The steps are damped (halved until |r|
/// falls, at most [`SHOOTING_HALVINGS`] times): near a contact switch or a multiplier close to
/// 1 the full Newton step overshoots. `None` when Newton does not converge in
/// [`SHOOTING_ITERATIONS`] or no damped step lowers |r| (no period-one orbit near the guess, or
/// a switch too sharp for the differences), or the motion leaves the model's range.
pub fn periodic_orbit(
    model: &MeshModel,
    driver_speed: f64,
    steps_per_period: usize,
    guess: State,
    tolerance: f64,
) -> Option<PeriodicOrbit> {
    let active = model.active_components();
    let n = active.len();
    let omega = model.highest_frequency();
    let static_deflection = (model.force / model.mesh.mean()).abs().max(1e-9);
    let divergence = model.divergence_check();
    let map = |s: State| integrate_period(model, driver_speed, steps_per_period, s, |_, _, _| {});
    // r in the balanced coordinates (q, v/ω), over the active components.
    let residual = |x: &State, end: &State| {
        nalgebra::DVector::from_iterator(
            n,
            active.iter().map(|&i| {
                let scale = if i < MAX_DOFS { 1.0 } else { 1.0 / omega };
                (end.component(i) - x.component(i)) * scale
            }),
        )
    };
    let moved = |x: &State, step: &nalgebra::DVector<f64>, alpha: f64| {
        let mut y = *x;
        for (k, &i) in active.iter().enumerate() {
            let scale = if i < MAX_DOFS { 1.0 } else { omega };
            *y.component_mut(i) -= alpha * step[k] * scale;
        }
        y
    };
    let jacobian_periods = match model.continuous_field() {
        true => 1,
        false => n + 1,
    };
    let mut periods = 0;
    let mut x = guess;
    for iteration in 0..=SHOOTING_ITERATIONS {
        let (end, jacobian) = period_map_jacobian(model, driver_speed, steps_per_period, x);
        periods += jacobian_periods;
        if divergence.diverged(&end) {
            return None;
        }
        let r = residual(&x, &end);
        if r.amax() <= tolerance * static_deflection {
            return Some(PeriodicOrbit {
                start: x,
                multipliers: jacobian.complex_eigenvalues().iter().copied().collect(),
                iterations: iteration,
                periods,
            });
        }
        let step = (jacobian - DMatrix::identity(n, n)).lu().solve(&r)?;
        let norm = r.norm();
        let mut alpha = 1.0;
        let mut accepted = None;
        for _ in 0..=SHOOTING_HALVINGS {
            let trial = moved(&x, &step, alpha);
            let end = map(trial);
            periods += 1;
            if !divergence.diverged(&end) && residual(&trial, &end).norm() < norm {
                accepted = Some(trial);
                break;
            }
            alpha *= 0.5;
        }
        x = accepted?;
    }
    None
}

/// Halvings of a Newton step [`periodic_orbit`] tries before it gives up.
pub const SHOOTING_HALVINGS: usize = 12;

/// Newton iterations of [`periodic_orbit`] before it gives up.
pub const SHOOTING_ITERATIONS: usize = 30;

/// The lowest Floquet frequency of the linear model at driver speed Ω₁ [rad/s]: the imaginary
/// part of the characteristic exponent μ = ln λ / T_m, which is fixed only modulo the mesh
/// frequency Ω_m = 2π/T_m; the branch nearest the mean-stiffness ω of the mesh mode is taken.
/// Inside an instability region (|λ| > 1, real λ) it locks to a multiple of Ω_m/2.
pub fn floquet_frequency(model: &MeshModel, driver_speed: f64, steps_per_period: usize) -> f64 {
    let period = model.mesh.period() / driver_speed;
    let mesh = std::f64::consts::TAU / period;
    let target = model.structure.mesh_mode(model.mesh.mean()).frequency;
    floquet_multipliers(model, driver_speed, steps_per_period)
        .iter()
        .map(|l| {
            let base = l.arg().abs() / period;
            // Branches ±base + n Ω_m: the one nearest the target.
            let n = (target / mesh).floor();
            [
                n * mesh + base,
                (n + 1.0) * mesh - base,
                n * mesh - base,
                (n + 1.0) * mesh + base,
            ]
            .into_iter()
            .filter(|w| *w >= 0.0)
            .min_by(|a, b| (a - target).abs().total_cmp(&(b - target).abs()))
            .unwrap_or(base)
        })
        .min_by(|a, b| (a - target).abs().total_cmp(&(b - target).abs()))
        .unwrap_or(f64::NAN)
}

/// RK4 over one mesh period in `steps` equal steps from `start` at θ = 0; `sample` sees the
/// state at the start of every step. Returns the state after the period. No divergence check:
/// [`steady_state`] makes it, per period.
pub fn integrate_period(
    model: &MeshModel,
    driver_speed: f64,
    steps: usize,
    start: State,
    mut sample: impl FnMut(usize, f64, &State),
) -> State {
    let h = model.mesh.period() / driver_speed / steps as f64;
    let mut state = start;
    let derivative = |t: f64, s: &State| model.derivative(driver_speed * t, s);
    for j in 0..steps {
        let t = j as f64 * h;
        sample(j, driver_speed * t, &state);
        state = rk4_step(derivative, t, &state, h);
    }
    state
}

/// A run-up (or run-down): the driver speed ramps linearly from `from` to `to` [rad/s] over
/// `duration` [s]; θ(t) = Ω₀t + ½αt². Fixed RK4 steps of at most 1/32 of the shortest natural
/// period and 1/64 of the shortest mesh period; at most `max_samples` evenly spaced steps are
/// recorded.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RunUp {
    pub time: Vec<f64>,
    /// Driver speed [rad/s].
    pub driver_speed: Vec<f64>,
    /// DTE ([`MeshModel::transmission_error`]) [m].
    pub displacement: Vec<f64>,
    /// Elastic mesh force [N].
    pub mesh_force: Vec<f64>,
    pub steps: usize,
    /// Time at which the response left the model's range ([`MeshModel::has_diverged`]); the
    /// run stops there.
    pub diverged_at: Option<f64>,
}

pub fn run_up(model: &MeshModel, from: f64, to: f64, duration: f64, max_samples: usize) -> RunUp {
    let alpha = (to - from) / duration;
    let fastest_mesh_period = model.mesh.period() / from.abs().max(to.abs()).max(1e-12);
    let natural_period = 2.0 * std::f64::consts::PI / model.highest_frequency();
    let h_max = (natural_period / 32.0).min(fastest_mesh_period / 64.0);
    let steps = (duration / h_max).ceil() as usize;
    let h = duration / steps as f64;
    let decimate = steps.div_ceil(max_samples.max(1)).max(1);
    let theta = |t: f64| from * t + 0.5 * alpha * t * t;
    let derivative = |t: f64, s: &State| model.derivative(theta(t), s);
    let divergence = model.divergence_check();
    let mut state = model.static_state();
    let mut out = RunUp {
        steps,
        ..RunUp::default()
    };
    for i in 0..=steps {
        let t = i as f64 * h;
        if i % decimate == 0 {
            out.time.push(t);
            out.driver_speed.push(from + alpha * t);
            out.displacement.push(model.transmission_error(&state));
            out.mesh_force
                .push(model.mesh_force(theta(t), model.mesh_deflection(&state)));
        }
        if i == steps {
            break;
        }
        state = rk4_step(derivative, t, &state, h);
        if divergence.diverged(&state) {
            out.diverged_at = Some(t + h);
            break;
        }
    }
    out
}

/// Reference integration with the adaptive Dormand–Prince 5(4) pair (Hairer, Nørsett & Wanner,
/// *Solving ODEs I*, §II.5): error control per step (relative `tolerance`), so steps shrink by
/// themselves at the kinks of the backlash law. Integrates `periods` mesh periods from `start`
/// at θ = 0 and returns the state at the end and the number of accepted steps.
pub fn reference_periods(
    model: &MeshModel,
    driver_speed: f64,
    start: impl Into<State>,
    periods: usize,
    tolerance: f64,
) -> (State, usize) {
    const C: [f64; 7] = [0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0];
    const A: [[f64; 6]; 7] = [
        [0.0; 6],
        [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
        [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
        [
            19372.0 / 6561.0,
            -25360.0 / 2187.0,
            64448.0 / 6561.0,
            -212.0 / 729.0,
            0.0,
            0.0,
        ],
        [
            9017.0 / 3168.0,
            -355.0 / 33.0,
            46732.0 / 5247.0,
            49.0 / 176.0,
            -5103.0 / 18656.0,
            0.0,
        ],
        [
            35.0 / 384.0,
            0.0,
            500.0 / 1113.0,
            125.0 / 192.0,
            -2187.0 / 6784.0,
            11.0 / 84.0,
        ],
    ];
    // First same as last: the 5th-order weights are the last stage's row.
    const B5: [f64; 7] = [A[6][0], A[6][1], A[6][2], A[6][3], A[6][4], A[6][5], 0.0];
    const B4: [f64; 7] = [
        5179.0 / 57600.0,
        0.0,
        7571.0 / 16695.0,
        393.0 / 640.0,
        -92097.0 / 339200.0,
        187.0 / 2100.0,
        1.0 / 40.0,
    ];
    let end = periods as f64 * model.mesh.period() / driver_speed;
    let rhs = |t: f64, s: &State| model.derivative(driver_speed * t, s);
    let scale_x = (model.force / model.mesh.mean()).abs().max(1e-12);
    let scale_v = scale_x * model.highest_frequency();
    let (mut t, mut y) = (0.0, start.into());
    let mut h = 0.01 * 2.0 * std::f64::consts::PI / model.highest_frequency();
    let mut accepted = 0;
    while t < end {
        h = h.min(end - t);
        let mut k = [State::default(); 7];
        for s in 0..7 {
            let mut ys = y;
            for (j, kj) in k.iter().enumerate().take(s) {
                ys = ys.add_scaled(h * A[s][j], kj);
            }
            k[s] = rhs(t + C[s] * h, &ys);
        }
        let (mut y5, mut err) = (y, State::default());
        for s in 0..7 {
            y5 = y5.add_scaled(h * B5[s], &k[s]);
            err = err.add_scaled(h * (B5[s] - B4[s]), &k[s]);
        }
        let e = (0..model.structure.dofs)
            .map(|i| {
                (err.q[i] / (scale_x * tolerance))
                    .abs()
                    .max((err.v[i] / (scale_v * tolerance)).abs())
            })
            .fold(0.0, f64::max);
        if e <= 1.0 {
            t += h;
            y = y5;
            accepted += 1;
        }
        h *= (0.9 * e.max(1e-10).powf(-0.2)).clamp(0.2, 5.0);
    }
    (y, accepted)
}
