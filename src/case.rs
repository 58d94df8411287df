//! Case files: the TOML schema (engineering units in key names), conversion to SI, validation,
//! and the embedded default case.
//!
//! Conversion happens here, once: `*_mm` → m, `*_um` → m, `*_deg` → rad, `*_gpa` → Pa,
//! `*_rpm` → rad/s. Unknown keys are errors that name the key and its line (serde
//! `deny_unknown_fields`). After parsing, [`Case`] checks the numbers and builds the checked
//! [`GearPair`] and every relief variant, so a case that loads is a case the numerics can use.

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::path::Path;
use thiserror::Error;

use crate::explicit::body::ExplicitMaterial;
use crate::explicit::far::FarBody;
use crate::explicit::pair::{Ramp, Start};
use crate::explicit::scene::{FeSettings, FineTeeth, MassScalingMode, Scene, TimeStep};
use crate::fe::{MassLumping, PlaneState};
use crate::geometry::{
    BasicRack, FlankModification, FlankReliefSpec, GearPair, GearSpec, GeometryError, PairSpec,
    ReliefShape, ReliefSpec, ReliefStart,
};
use crate::ltca::body::BodyMaterial;
use crate::lumped::{Drive, ForceLawKind};
use crate::mesh::ToothLayout;

/// The seed paper's pair, embedded in the binary and used when no case file is given.
pub const EMBEDDED_DEFAULT: &str = include_str!("../data/cases/paper36.toml");
/// How the embedded case is named in messages and outputs.
pub const EMBEDDED_SOURCE: &str = "<embedded paper36>";

#[derive(Debug, Error)]
pub enum CaseError {
    #[error("cannot read case file {path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("case file {path}: {message}")]
    Parse { path: String, message: String },
    #[error("case file {path}: {parameter} = {value} is invalid: {limit}")]
    Invalid {
        path: String,
        parameter: String,
        value: String,
        limit: String,
    },
    #[error("case file {path}: {source}")]
    Geometry {
        path: String,
        #[source]
        source: GeometryError,
    },
    #[error("--set {key}: {message}")]
    Override { key: String, message: String },
    #[error("case file {path}: relief_variant \"{variant}\": {source}")]
    Relief {
        path: String,
        variant: String,
        #[source]
        source: GeometryError,
    },
}

// ---------------------------------------------------------------------------------------------
// The file schema (engineering units).
// ---------------------------------------------------------------------------------------------

/// A case file as written (engineering units).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaseFile {
    /// Short name used in output folder names.
    pub name: String,
    #[serde(default)]
    pub description: String,
    pub tool: ToolSection,
    pub gear1: GearSection,
    pub gear2: GearSection,
    #[serde(default)]
    pub pair: PairSection,
    #[serde(default)]
    pub material: MaterialSection,
    #[serde(default, rename = "operating_point")]
    pub operating_points: Vec<OperatingPointSection>,
    #[serde(default = "default_relief_variants", rename = "relief_variant")]
    pub relief_variants: Vec<ReliefVariantSection>,
    #[serde(default)]
    pub contact: ContactSection,
    #[serde(default)]
    pub mesh: MeshSection,
    #[serde(default)]
    pub fe: FeSection,
    #[serde(default)]
    pub lumped: LumpedSection,
    #[serde(default, rename = "scene")]
    pub scenes: Vec<SceneSection>,
}

/// The lumped parametric-vibration model (`geardyn sweep`, `geardyn stability`); the command
/// line overrides stiffness source, drive and damping ratio.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LumpedSection {
    /// Stiffness source: "ltca" (the case's FE LTCA of `relief`, default the first relief variant), "pe" (potential energy),
    /// "iso" (ISO 6336-1 c_γα, constant), or a CSV file (path relative to the case file) with
    /// columns roll_angle_deg, mesh_stiffness_n_per_m and optionally unloaded_te_um.
    #[serde(default = "default_stiffness_source")]
    pub stiffness: String,
    /// "torque" (both gears free under input and load torque) or "speed" (driver at the prescribed
    /// speed, as in the explicit FE).
    #[serde(default)]
    pub drive: Drive,
    /// Mesh damping ratio ζ: c = 2ζ√(k̄ m_e).
    #[serde(default = "default_damping_ratio")]
    pub damping_ratio: f64,
    /// Mesh damping as a coefficient c [N·s/m] instead of a ratio (overrides `damping_ratio`).
    pub mesh_damping_n_s_per_m: Option<f64>,
    /// Rotary inertias of the gears with what turns with them [kg·mm²]; default: ρ b ∫r² dA of
    /// the gear bodies.
    pub inertia_kg_mm2: Option<[f64; 2]>,
    /// Translation of each gear along the line of action on its bearings (two coordinates more).
    #[serde(default)]
    pub bearings: bool,
    /// Bearing (support) stiffness of each gear along the line of action [N/m].
    #[serde(default = "default_bearing_stiffness")]
    pub bearing_stiffness_n_per_m: [f64; 2],
    /// Damping ratio of each gear on its bearings: c_i = 2ζ_b√(k_i m_i).
    #[serde(default = "default_bearing_damping_ratio")]
    pub bearing_damping_ratio: f64,
    /// Translating mass of each gear [kg]; default: ρ b A of the gear bodies.
    pub gear_mass_kg: Option<[f64; 2]>,
    /// "elastic" (default): each gear as hub and rim with its body's torsional compliance
    /// between bore and root circle, the inertia where it sits; a hub-to-hub stiffness (ltca or
    /// an FE CSV) loses that twist, k′ = 1/(1/k − c_b), and the bodies carry it
    /// (validation/frequencies: rigid gears put the mesh mode 10 % low with both gears free).
    /// "rigid": one inertia per gear behind the whole stiffness.
    #[serde(default)]
    pub bodies: BodyModel,
    /// Elastic bodies only: each rim's sway on its held bore along the line of action (a static
    /// FE of the body reduced onto the rim's translation, one coordinate per gear, its
    /// compliance taken out of a hub-to-hub stiffness as the twist is). "auto" (default): where
    /// it moves the pair's mesh mode by more than 0.5 % (on an unequal pair a large gear's
    /// sway mixes with the mesh mode: +8.6 % without it on 17/53, +3.5 % with it,
    /// validation/frequencies); "on"; "off" (the sway stays in the mesh stiffness, massless).
    #[serde(default)]
    pub body_sway: BodySway,
    /// Elastic bodies only: the mass the mesh itself moves, the kinetic energy of the teeth's
    /// bending and the rims' local deformation beyond the gears' rigid motions per unit
    /// approach rate (`ltca::modal::mesh_moving_mass`, from a static FE of the meshed pair),
    /// added to the model's mass along the mesh deflection, M + m_d g gᵀ: no coordinate more,
    /// the statics unchanged. true (default), or false (a massless mesh spring: the mesh mode
    /// reads high by about half the deformation's share of the FE modal's kinetic energy: on
    /// the paper pair +0.46 / +1.19 % driver held / both free against +0.13 / +0.30 % with it,
    /// on 17/53 both free +3.47 against +2.69 %; validation/frequencies).
    #[serde(default = "default_true")]
    pub mesh_mass: bool,
    /// Input shaft from a motor to the driver's hub: torsional stiffness [N·m/rad], and the
    /// motor's inertia [kg·mm²] (0: a massless end, left out under a torque drive; under a
    /// speed drive the shaft's end turns at the prescribed speed).
    pub input_shaft_stiffness_nm_per_rad: Option<f64>,
    pub motor_inertia_kg_mm2: Option<f64>,
    /// Output shaft from the driven hub to a load inertia: stiffness [N·m/rad], inertia
    /// [kg·mm²].
    pub output_shaft_stiffness_nm_per_rad: Option<f64>,
    pub load_inertia_kg_mm2: Option<f64>,
    /// Damping ratio of every shaft and body spring, c = 2ζ√(k m_r) (m_r: the reduced inertia of
    /// the two ends).
    #[serde(default = "default_drivetrain_damping_ratio")]
    pub drivetrain_damping_ratio: f64,
    /// The relief variant whose LTCA k(θ) and unloaded TE the `ltca` source takes; default:
    /// the case's first.
    pub relief: Option<String>,
    /// "load-dependent" (the LTCA's own W(θ, δ) over 0.039–8.3 × the design torque; the `ltca`
    /// source only) or "secant" (k(θ) at the design torque, linear in the approach).
    #[serde(default)]
    pub force_law: ForceLawKind,
}

impl Default for LumpedSection {
    fn default() -> Self {
        Self {
            stiffness: default_stiffness_source(),
            drive: Drive::default(),
            damping_ratio: default_damping_ratio(),
            mesh_damping_n_s_per_m: None,
            inertia_kg_mm2: None,
            bearings: false,
            bearing_stiffness_n_per_m: default_bearing_stiffness(),
            bearing_damping_ratio: default_bearing_damping_ratio(),
            gear_mass_kg: None,
            bodies: BodyModel::default(),
            body_sway: BodySway::default(),
            mesh_mass: default_true(),
            input_shaft_stiffness_nm_per_rad: None,
            motor_inertia_kg_mm2: None,
            output_shaft_stiffness_nm_per_rad: None,
            load_inertia_kg_mm2: None,
            drivetrain_damping_ratio: default_drivetrain_damping_ratio(),
            relief: None,
            force_law: ForceLawKind::default(),
        }
    }
}

fn default_stiffness_source() -> String {
    "ltca".into()
}
fn default_damping_ratio() -> f64 {
    0.05
}
fn default_bearing_stiffness() -> [f64; 2] {
    [5e8, 5e8]
}
fn default_bearing_damping_ratio() -> f64 {
    0.02
}
fn default_drivetrain_damping_ratio() -> f64 {
    0.02
}

/// How the lumped model holds each gear's body (`[lumped] bodies`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BodyModel {
    /// Hub and rim with the body's torsional compliance between them.
    #[default]
    Elastic,
    /// One rigid inertia per gear.
    Rigid,
}

/// Whether the lumped model's elastic bodies sway on their bores (`[lumped] body_sway`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BodySway {
    /// Where the sway moves the mesh mode by more than
    /// [`crate::study::lumped::SWAY_MODE_SHIFT`].
    #[default]
    Auto,
    On,
    Off,
}

/// Element sizes of the gear meshes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSection {
    /// Element size along flanks and fillets of the teeth that engage in the analysis.
    #[serde(default = "default_fine_element")]
    pub fine_element_mm: f64,
    /// Element size on the other teeth and of the body's layers below the teeth.
    #[serde(default = "default_coarse_element")]
    pub coarse_element_mm: f64,
}

impl Default for MeshSection {
    fn default() -> Self {
        Self {
            fine_element_mm: default_fine_element(),
            coarse_element_mm: default_coarse_element(),
        }
    }
}

/// Finite-element model options.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FeSection {
    /// "strain" (default: B/m = 8 for the paper's pair, so the mid-plane is in plane strain) or
    /// "stress".
    #[serde(default = "default_plane")]
    pub plane: PlaneState,
    /// Explicit time step Δt = step_factor · Δt_cr (the paper's β, eq. 29).
    #[serde(default = "default_step_factor")]
    pub step_factor: f64,
    /// The stable step `step_factor` multiplies: "coupled" (default: the pair's own, measured
    /// where the contact is as the run goes, with a fall-back) or "bound" (the worst case of
    /// every contact state, fixed). See [`crate::explicit::scene`].
    #[serde(default)]
    pub time_step: TimeStep,
    /// Which teeth the explicit runs mesh fine: "window" (default: those that engage in the
    /// current window of one driver pitch, remeshed as the gears turn) or "scene" (every tooth
    /// that engages anywhere in the scene, for the whole run). See [`crate::explicit::scene`].
    #[serde(default)]
    pub fine_teeth: FineTeeth,
    /// How the explicit meshes lay out the teeth: "stable-step" (default since 2026-12-06:
    /// columns even at the tip, the upper fillet's rows of equal length; on the paper's teeth
    /// the thinnest elements go and the 3000 rpm scene steps 1.24 × longer, as near the
    /// converged references as graded or nearer on most measures) or "graded" (the LTCA's layout, on
    /// which the explicit results in validation/ before that date were measured). See
    /// [`crate::mesh::ToothLayout`].
    #[serde(default = "default_tooth_layout")]
    pub tooth_layout: ToothLayout,
    /// How a run on windows of fine teeth models each gear's body away from the contact:
    /// "reduced" (default: the coarse sectors as one Craig–Bampton block per gear turning
    /// with its hub, its fixed-interface modes to `far_block_cutoff` times the lowest mode of
    /// the fine sectors beside it) or "full" (every element in the explicit step). See
    /// [`crate::explicit::far`].
    #[serde(default)]
    pub far_body: FarBody,
    /// A reduced far block's fixed-interface modes kept up to this many times the lowest mode
    /// of the fine sectors beside it (`fe.far_body = "reduced"`): higher is nearer the full
    /// body and costs more a step.
    #[serde(default = "default_far_block_cutoff")]
    pub far_block_cutoff: f64,
    /// Contact penalty k_n = penalty_factor · max diag K_e of the master element.
    #[serde(default = "default_penalty_factor")]
    pub penalty_factor: f64,
    /// Lumped mass of the explicit bodies: "corner-twelfth" (default: corners 1/12, mid-sides
    /// 1/6 of the element mass; the longer stable step) or "hrz" (diagonal scaling; the more
    /// accurate high frequencies). See [`crate::fe::MassLumping`].
    #[serde(default)]
    pub mass_lumping: MassLumping,
    /// Stiffness-proportional damping, given as the damping ratio at the highest frequency of
    /// the mesh: β_K = 2ζ/ω_max. It damps numerical noise at the element scale; at the mesh
    /// frequencies (kHz) the damping is ζ·ω/ω_max, a few parts per million.
    #[serde(default = "default_high_frequency_damping")]
    pub high_frequency_damping_ratio: f64,
    /// Damping ratio of the mesh mode: a dashpot on the driven hub against the DTE rate while
    /// the teeth touch, c_t = 2ζ√(k_m R_b2² I₂) with k_m the pair's own mean mesh stiffness —
    /// the lumped model's viscous mesh damping applied to the FE (the elastic bodies themselves
    /// carry almost no damping at the mesh frequencies).
    #[serde(default = "default_mesh_damping")]
    pub mesh_damping_ratio: f64,
    /// Mass scaling at low speeds: each gear's inertia times s so that the mesh mode falls to
    /// `mass_scaling_margin` × the fifth mesh harmonic, when it is above that (the stable step
    /// grows by √s or more, `mass_scaling_mode`; quasi-static response kept). Off by itself
    /// where the mesh frequency is high.
    #[serde(default = "default_true")]
    pub mass_scaling: bool,
    /// The scaled mesh mode over the fifth mesh harmonic.
    #[serde(default = "default_mass_scaling_margin")]
    pub mass_scaling_margin: f64,
    /// Where the added mass goes: "uniform" (every mass times s) or "target-step" (each
    /// element's mass raised to a stable step T_g per gear, at which each gear's inertia is
    /// exactly s times its own).
    #[serde(default)]
    pub mass_scaling_mode: MassScalingMode,
    /// Interval of the recorded time histories [µs].
    #[serde(default = "default_output_interval")]
    pub output_interval_us: f64,
    /// Element size on the engaging flanks for the explicit runs [mm]; default: mesh.fine_element_mm.
    pub explicit_fine_element_mm: Option<f64>,
    /// Element size of the other teeth and of the body below the teeth for the explicit runs [mm];
    /// default: mesh.coarse_element_mm.
    pub explicit_coarse_element_mm: Option<f64>,
}

impl Default for FeSection {
    fn default() -> Self {
        Self {
            plane: default_plane(),
            step_factor: default_step_factor(),
            time_step: TimeStep::default(),
            fine_teeth: FineTeeth::default(),
            tooth_layout: default_tooth_layout(),
            far_body: FarBody::default(),
            far_block_cutoff: default_far_block_cutoff(),
            penalty_factor: default_penalty_factor(),
            mass_lumping: MassLumping::default(),
            high_frequency_damping_ratio: default_high_frequency_damping(),
            mesh_damping_ratio: default_mesh_damping(),
            mass_scaling: true,
            mass_scaling_margin: default_mass_scaling_margin(),
            mass_scaling_mode: MassScalingMode::default(),
            output_interval_us: default_output_interval(),
            explicit_fine_element_mm: None,
            explicit_coarse_element_mm: None,
        }
    }
}

fn default_step_factor() -> f64 {
    0.9
}
/// The explicit meshes' layout (`fe.tooth_layout`): the one with the longer stable step, as
/// accurate against the converged references on balance (validation/performance, lever 2c).
fn default_tooth_layout() -> ToothLayout {
    ToothLayout::StableStep
}

fn default_far_block_cutoff() -> f64 {
    crate::explicit::far::FAR_BLOCK_CUTOFF
}

fn default_penalty_factor() -> f64 {
    1.0
}
fn default_high_frequency_damping() -> f64 {
    0.05
}
fn default_mesh_damping() -> f64 {
    0.05
}
fn default_true() -> bool {
    true
}
fn default_mass_scaling_margin() -> f64 {
    3.0
}
fn default_output_interval() -> f64 {
    10.0
}

/// An explicit FE scene: one run of the meshing pair (`geardyn fe --scene NAME`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSection {
    pub name: String,
    /// Operating point (speed and torque) by name; `speed_rpm` and `torque_nm` override it.
    pub operating_point: Option<String>,
    /// Driver speed [rpm]; default: the operating point's.
    pub speed_rpm: Option<f64>,
    /// Load torque on the driven gear [N·m]; default: the operating point's.
    pub torque_nm: Option<f64>,
    /// Relief variant by name.
    #[serde(default = "default_relief_name")]
    pub relief: String,
    /// Coulomb friction coefficient μ.
    #[serde(default)]
    pub friction: f64,
    /// Simulated time [s].
    pub duration_s: f64,
    /// Lengthen the run where `duration_s` is too short for its statistics window to hold one
    /// base pitch of the driver after the ramp and the mesh mode's settling (a stiffness
    /// extraction on any pair: the scene's duration in seconds fits one pair's pitch only).
    #[serde(default)]
    pub cover_pitch: bool,
    /// End the run before `duration_s` once its DTE has settled: the rms over the last three
    /// stretches of whole mesh periods after the ramp's ringing no longer moves
    /// ([`crate::explicit::scene::SettledStop`]); `duration_s` is then the longest it runs.
    #[serde(default)]
    pub stop_when_settled: bool,
    /// Ramp of the load torque, and of the driver speed when starting from rest [s].
    pub ramp_s: f64,
    /// Ramp shape: "linear" (the seed paper's) or "cosine" (no jump in acceleration).
    #[serde(default)]
    pub ramp: Ramp,
    /// "rest" (spin-up with the load, the seed paper's) or "at-speed" (only the load ramps).
    #[serde(default)]
    pub start: Start,
    /// This scene's `fe.mass_scaling_margin` (e.g. lower for a stiffness extraction, which
    /// needs only the quasi-static contact, not quasi-static dynamics).
    pub mass_scaling_margin: Option<f64>,
}

fn default_relief_name() -> String {
    "none".into()
}

/// The basic rack of the generating cutter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToolSection {
    pub module_mm: f64,
    #[serde(default = "default_pressure_angle")]
    pub pressure_angle_deg: f64,
    #[serde(default = "default_dedendum")]
    pub dedendum_coeff: f64,
    #[serde(default = "default_tip_radius")]
    pub tip_radius_coeff: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GearSection {
    pub teeth: u32,
    #[serde(default)]
    pub profile_shift: f64,
    #[serde(default = "default_addendum")]
    pub addendum_coeff: f64,
    pub face_width_mm: f64,
    pub bore_radius_mm: f64,
    #[serde(default)]
    pub thickness_reduction_um: f64,
}

#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PairSection {
    /// Operating centre distance; default: zero backlash for the nominal teeth.
    pub center_distance_mm: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSection {
    #[serde(default = "default_youngs")]
    pub youngs_modulus_gpa: f64,
    #[serde(default = "default_poisson")]
    pub poisson_ratio: f64,
    #[serde(default = "default_density")]
    pub density_kg_per_m3: f64,
    /// Nominal bending stress number σ_Flim of ISO 6336-5 (the test gear's endurance limit over
    /// its stress correction Y_ST = 2). Default 500 MPa: case-hardened wrought steel, quality MQ
    /// (an assumption, stated in every output that uses it).
    #[serde(default = "default_root_stress_limit")]
    pub root_stress_limit_mpa: f64,
    /// Allowable contact stress number σ_Hlim of ISO 6336-5. Default 1 500 MPa: case-hardened
    /// wrought steel, quality MQ (an assumption).
    #[serde(default = "default_contact_stress_limit")]
    pub contact_stress_limit_mpa: f64,
}

impl Default for MaterialSection {
    fn default() -> Self {
        Self {
            youngs_modulus_gpa: default_youngs(),
            poisson_ratio: default_poisson(),
            density_kg_per_m3: default_density(),
            root_stress_limit_mpa: default_root_stress_limit(),
            contact_stress_limit_mpa: default_contact_stress_limit(),
        }
    }
}

fn default_root_stress_limit() -> f64 {
    500.0
}
fn default_contact_stress_limit() -> f64 {
    1500.0
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OperatingPointSection {
    pub name: String,
    /// Driver (gear 1) speed.
    pub speed_rpm: f64,
    /// Load torque on the driven gear (gear 2).
    pub torque_nm: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReliefVariantSection {
    pub name: String,
    #[serde(default)]
    pub gear1: GearReliefSection,
    #[serde(default)]
    pub gear2: GearReliefSection,
}

#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GearReliefSection {
    pub tip: Option<ReliefSection>,
    pub root: Option<ReliefSection>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReliefSection {
    pub amount_um: f64,
    #[serde(default = "default_shape")]
    pub shape: ReliefShape,
    /// "hpstc", "lpstc" or "short"; at most one of `start`, `start_roll_deg`, `start_diameter_mm`.
    /// None of them: long relief ("hpstc" for tip, "lpstc" for root).
    pub start: Option<String>,
    pub start_roll_deg: Option<f64>,
    pub start_diameter_mm: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSection {
    #[serde(default = "default_friction")]
    pub friction_coefficients: Vec<f64>,
}

impl Default for ContactSection {
    fn default() -> Self {
        Self {
            friction_coefficients: default_friction(),
        }
    }
}

fn default_fine_element() -> f64 {
    0.2
}
fn default_coarse_element() -> f64 {
    1.5
}
fn default_plane() -> PlaneState {
    PlaneState::Strain
}
fn default_pressure_angle() -> f64 {
    20.0
}
fn default_dedendum() -> f64 {
    1.25
}
fn default_tip_radius() -> f64 {
    0.38
}
fn default_addendum() -> f64 {
    1.0
}
fn default_youngs() -> f64 {
    206.0
}
fn default_poisson() -> f64 {
    0.3
}
fn default_density() -> f64 {
    7850.0
}
fn default_shape() -> ReliefShape {
    ReliefShape::Linear
}
fn default_friction() -> Vec<f64> {
    vec![0.0]
}
fn default_relief_variants() -> Vec<ReliefVariantSection> {
    vec![ReliefVariantSection {
        name: "none".into(),
        gear1: GearReliefSection::default(),
        gear2: GearReliefSection::default(),
    }]
}

// ---------------------------------------------------------------------------------------------
// The validated case (SI).
// ---------------------------------------------------------------------------------------------

/// Isotropic linear-elastic material, SI.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Material {
    /// Young's modulus E [Pa].
    pub youngs_modulus: f64,
    /// Poisson's ratio ν.
    pub poisson_ratio: f64,
    /// Density ρ [kg/m³].
    pub density: f64,
    /// ISO 6336-5's σ_Flim and σ_Hlim [Pa] (`strength::safety`).
    pub root_stress_limit: f64,
    pub contact_stress_limit: f64,
}

/// An operating point, SI.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OperatingPoint {
    pub name: String,
    /// Driver angular speed Ω1 [rad/s].
    pub driver_speed: f64,
    /// Load torque on the driven gear [N·m].
    pub torque: f64,
}

/// A relief variant: what was asked per gear, and its resolved zones.
#[derive(Debug, Clone, PartialEq)]
pub struct ReliefVariant {
    pub name: String,
    pub requests: [FlankReliefSpec; 2],
    pub modifications: [FlankModification; 2],
}

/// A loaded, checked case.
#[derive(Debug, Clone)]
pub struct Case {
    /// Where the case came from (a path, or [`EMBEDDED_SOURCE`]).
    pub source: String,
    /// The case file's text, echoed into every output folder.
    pub text: String,
    pub file: CaseFile,
    pub pair_spec: PairSpec,
    pub pair: GearPair,
    pub material: Material,
    pub operating_points: Vec<OperatingPoint>,
    pub relief_variants: Vec<ReliefVariant>,
    pub friction_coefficients: Vec<f64>,
    /// Plane state of the 2D bodies (`fe.plane`).
    pub plane: PlaneState,
    /// The explicit FE's settings (`[fe]`, SI).
    pub fe: FeSettings,
    /// The lumped model's settings (`[lumped]`, SI).
    pub lumped: LumpedSettings,
    pub scenes: Vec<Scene>,
}

/// Where the lumped model's mesh stiffness comes from (`lumped.stiffness`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum StiffnessSource {
    /// The case's FE bodies, quasi-static LTCA of `lumped.relief` (default: the first relief variant).
    Ltca,
    /// The potential-energy (Ishikawa/Sainsot) method.
    PotentialEnergy,
    /// ISO 6336-1 method B, constant c_γα·b.
    Iso,
    /// A stiffness file (path as resolved: relative paths of a case file from its folder).
    Csv(std::path::PathBuf),
}

impl std::str::FromStr for StiffnessSource {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        Self::parse(text).ok_or_else(|| {
            format!(
                "unknown stiffness source {text:?}: use one of {:?} or a .csv file with columns roll_angle_deg, mesh_stiffness_n_per_m[, unloaded_te_um]",
                Self::KINDS
            )
        })
    }
}

impl StiffnessSource {
    /// The names a case file and the command line use.
    pub const KINDS: [&'static str; 3] = ["ltca", "pe", "iso"];

    /// How a case file names it.
    pub fn name(&self) -> String {
        match self {
            Self::Ltca => "ltca".into(),
            Self::PotentialEnergy => "pe".into(),
            Self::Iso => "iso".into(),
            Self::Csv(path) => path.display().to_string(),
        }
    }

    /// Whether its k(θ) runs hub to hub and so holds the gear bodies' twist between bore and
    /// root circle: the LTCA's and an FE stiffness file's do; ISO 6336's and the
    /// potential-energy method's stop at the tooth's foundation.
    pub fn holds_body_twist(&self) -> bool {
        matches!(self, Self::Ltca | Self::Csv(_))
    }

    /// Parses `ltca`, `pe`, `iso` or a path ending in `.csv`; None otherwise.
    pub fn parse(text: &str) -> Option<Self> {
        match text {
            "ltca" => Some(Self::Ltca),
            "pe" => Some(Self::PotentialEnergy),
            "iso" => Some(Self::Iso),
            path if path.ends_with(".csv") => Some(Self::Csv(path.into())),
            _ => None,
        }
    }
}

/// Hertzian pressure above which a case gets a warning [Pa]: twice the allowable contact stress
/// of the strongest case-hardened steels (σ_H,lim ≈ 1.5 GPa, ISO 6336-5), where the flanks
/// yield and no linear-elastic model holds.
pub const HERTZ_PRESSURE_LIMIT: f64 = 3.0e9;

/// The `[lumped]` section in SI, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct LumpedSettings {
    pub stiffness: StiffnessSource,
    pub drive: Drive,
    /// Mesh damping ratio ζ.
    pub damping_ratio: f64,
    /// Mesh damping coefficient c [N·s/m], when given instead of the ratio.
    pub mesh_damping: Option<f64>,
    /// Rotary inertias of the gears [kg·m²]; None: ρ b ∫r² dA of the bodies.
    pub inertias: Option<[f64; 2]>,
    pub bearings: bool,
    /// Bearing stiffness along the line of action [N/m].
    pub bearing_stiffness: [f64; 2],
    pub bearing_damping_ratio: f64,
    /// Translating masses [kg]; None: ρ b A of the bodies.
    pub gear_masses: Option<[f64; 2]>,
    /// Gear bodies elastic (hub and rim) or rigid (`[lumped] bodies`).
    pub bodies: BodyModel,
    /// Whether elastic bodies sway on their bores (`[lumped] body_sway`).
    pub body_sway: BodySway,
    /// Whether elastic bodies carry the mesh's own moving mass (`[lumped] mesh_mass`).
    pub mesh_mass: bool,
    /// Input and output shafts (`[lumped]` *_shaft_stiffness_nm_per_rad [N·m/rad], motor and
    /// load inertias [kg·m²], 0 when not given).
    pub shafts: [Option<crate::lumped::Shaft>; 2],
    pub drivetrain_damping_ratio: f64,
    /// The relief variant of the `ltca` source; None: the case's first.
    pub relief: Option<String>,
    pub force_law: ForceLawKind,
}

impl Case {
    /// The embedded default case (the seed paper's pair).
    pub fn embedded_default() -> Result<Self, CaseError> {
        Self::from_toml_str(EMBEDDED_DEFAULT, EMBEDDED_SOURCE)
    }

    /// Reads and checks a case file.
    pub fn load(path: &Path) -> Result<Self, CaseError> {
        let shown = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| CaseError::Io {
            path: shown.clone(),
            source,
        })?;
        Self::from_toml_str(&text, &shown)
    }

    /// Parses and checks case text; `source` names it in messages.
    pub fn from_toml_str(text: &str, source: &str) -> Result<Self, CaseError> {
        let file: CaseFile = toml::from_str(text).map_err(|e| CaseError::Parse {
            path: source.into(),
            message: e.to_string().trim_end().to_string(),
        })?;
        Self::from_file(file, text, source)
    }

    fn from_file(file: CaseFile, text: &str, source: &str) -> Result<Self, CaseError> {
        let invalid = |parameter: &str, value: String, limit: &str| CaseError::Invalid {
            path: source.into(),
            parameter: parameter.into(),
            value,
            limit: limit.into(),
        };
        // `name` at `key` is one of `variants`, or the error that lists them.
        let known_variant = |key: &str, name: &str, variants: &[ReliefVariant]| {
            if variants.iter().any(|v| v.name == name) {
                return Ok(());
            }
            Err(invalid(
                key,
                format!("{name:?}"),
                &format!(
                    "name one of the relief variants: {:?}",
                    variants.iter().map(|v| v.name.as_str()).collect::<Vec<_>>()
                ),
            ))
        };
        // A mass-scaling margin: the scaled mesh mode over the fifth mesh harmonic.
        let check_mass_scaling_margin = |parameter: &str, margin: f64| {
            if (1.5..=100.0).contains(&margin) {
                Ok(())
            } else {
                Err(invalid(
                    parameter,
                    margin.to_string(),
                    "must be in [1.5, 100] (default 3: the scaled mesh mode at three times the fifth mesh harmonic; below 1.5 it comes near the harmonics and the response is no longer quasi-static)",
                ))
            }
        };
        if file.name.trim().is_empty() || file.name.contains(['/', '\\']) {
            return Err(invalid(
                "name",
                format!("{:?}", file.name),
                "a non-empty name without slashes",
            ));
        }
        let rack = BasicRack {
            module: file.tool.module_mm * 1e-3,
            pressure_angle: file.tool.pressure_angle_deg.to_radians(),
            dedendum_coeff: file.tool.dedendum_coeff,
            tip_radius_coeff: file.tool.tip_radius_coeff,
        };
        let gear_spec = |g: &GearSection| GearSpec {
            teeth: g.teeth,
            profile_shift: g.profile_shift,
            addendum_coeff: g.addendum_coeff,
            face_width: g.face_width_mm * 1e-3,
            bore_radius: g.bore_radius_mm * 1e-3,
            thickness_reduction: g.thickness_reduction_um * 1e-6,
        };
        let pair_spec = PairSpec {
            rack,
            gears: [gear_spec(&file.gear1), gear_spec(&file.gear2)],
            center_distance: file.pair.center_distance_mm.map(|a| a * 1e-3),
        };
        let pair = GearPair::new(&pair_spec).map_err(|e| CaseError::Geometry {
            path: source.into(),
            source: e,
        })?;

        let mat = &file.material;
        if !(mat.youngs_modulus_gpa > 0.0 && mat.youngs_modulus_gpa.is_finite()) {
            return Err(invalid(
                "material.youngs_modulus_gpa",
                mat.youngs_modulus_gpa.to_string(),
                "must be a finite number > 0",
            ));
        }
        if !(mat.poisson_ratio >= 0.0 && mat.poisson_ratio < 0.5) {
            return Err(invalid(
                "material.poisson_ratio",
                mat.poisson_ratio.to_string(),
                "must be in [0, 0.5)",
            ));
        }
        if !(mat.density_kg_per_m3 > 0.0 && mat.density_kg_per_m3.is_finite()) {
            return Err(invalid(
                "material.density_kg_per_m3",
                mat.density_kg_per_m3.to_string(),
                "must be a finite number > 0",
            ));
        }
        for (key, value) in [
            ("material.root_stress_limit_mpa", mat.root_stress_limit_mpa),
            (
                "material.contact_stress_limit_mpa",
                mat.contact_stress_limit_mpa,
            ),
        ] {
            if !(value > 0.0 && value.is_finite()) {
                return Err(invalid(
                    key,
                    value.to_string(),
                    "must be a finite number > 0 [MPa] (ISO 6336-5's σ_Flim / σ_Hlim)",
                ));
            }
        }
        let material = Material {
            youngs_modulus: mat.youngs_modulus_gpa * 1e9,
            poisson_ratio: mat.poisson_ratio,
            density: mat.density_kg_per_m3,
            root_stress_limit: mat.root_stress_limit_mpa * 1e6,
            contact_stress_limit: mat.contact_stress_limit_mpa * 1e6,
        };

        let mut operating_points = Vec::new();
        for (i, op) in file.operating_points.iter().enumerate() {
            let key = |field: &str| format!("operating_point[{i}] (\"{}\").{field}", op.name);
            if !(op.speed_rpm > 0.0 && op.speed_rpm.is_finite()) {
                return Err(invalid(
                    &key("speed_rpm"),
                    op.speed_rpm.to_string(),
                    "must be a finite number > 0",
                ));
            }
            if !(op.torque_nm > 0.0 && op.torque_nm.is_finite()) {
                return Err(invalid(
                    &key("torque_nm"),
                    op.torque_nm.to_string(),
                    "must be a finite number > 0 (the load torque on the driven gear)",
                ));
            }
            if file.operating_points[..i].iter().any(|o| o.name == op.name) {
                return Err(invalid(
                    &key("name"),
                    format!("{:?}", op.name),
                    "names must be unique",
                ));
            }
            operating_points.push(OperatingPoint {
                name: op.name.clone(),
                driver_speed: op.speed_rpm * 2.0 * PI / 60.0,
                torque: op.torque_nm,
            });
        }

        let mut relief_variants = Vec::new();
        for (i, variant) in file.relief_variants.iter().enumerate() {
            if file.relief_variants[..i]
                .iter()
                .any(|v| v.name == variant.name)
            {
                return Err(invalid(
                    &format!("relief_variant[{i}].name"),
                    format!("{:?}", variant.name),
                    "names must be unique",
                ));
            }
            let relief_err = |e: GeometryError| CaseError::Relief {
                path: source.into(),
                variant: variant.name.clone(),
                source: e,
            };
            let requests = [
                gear_relief_request(1, &variant.gear1).map_err(relief_err)?,
                gear_relief_request(2, &variant.gear2).map_err(relief_err)?,
            ];
            let modifications = [
                pair.flank_modification(1, &requests[0])
                    .map_err(relief_err)?,
                pair.flank_modification(2, &requests[1])
                    .map_err(relief_err)?,
            ];
            relief_variants.push(ReliefVariant {
                name: variant.name.clone(),
                requests,
                modifications,
            });
        }

        for (i, mu) in file.contact.friction_coefficients.iter().enumerate() {
            if !(*mu >= 0.0 && *mu < 1.0) {
                return Err(invalid(
                    &format!("contact.friction_coefficients[{i}]"),
                    mu.to_string(),
                    "must be in [0, 1)",
                ));
            }
        }

        let module_mm = file.tool.module_mm;
        let (fine, coarse) = (file.mesh.fine_element_mm, file.mesh.coarse_element_mm);
        if !(fine >= 0.005 * module_mm && fine <= coarse) {
            return Err(invalid(
                "mesh.fine_element_mm",
                fine.to_string(),
                &format!(
                    "must be in [0.005·m, coarse_element_mm] = [{:.4}, {coarse}] mm (m = tool.module_mm = {module_mm})",
                    0.005 * module_mm
                ),
            ));
        }
        if !(coarse <= module_mm) {
            return Err(invalid(
                "mesh.coarse_element_mm",
                coarse.to_string(),
                &format!("must be at most one module ({module_mm} mm)"),
            ));
        }

        let lumped = &file.lumped;
        let stiffness_source = match StiffnessSource::parse(&lumped.stiffness) {
            // A file named in a case file is relative to the case file's folder.
            Some(StiffnessSource::Csv(path)) if path.is_relative() && source != EMBEDDED_SOURCE => {
                StiffnessSource::Csv(match Path::new(source).parent() {
                    Some(dir) => dir.join(path),
                    None => path,
                })
            }
            Some(kind) => kind,
            None => {
                return Err(invalid(
                    "lumped.stiffness",
                    format!("{:?}", lumped.stiffness),
                    "use \"ltca\", \"pe\", \"iso\" or a .csv file with columns roll_angle_deg, mesh_stiffness_n_per_m[, unloaded_te_um]",
                ))
            }
        };
        if !(0.0..1.0).contains(&lumped.damping_ratio) {
            return Err(invalid(
                "lumped.damping_ratio",
                lumped.damping_ratio.to_string(),
                "must be in [0, 1), typically 0.02–0.1",
            ));
        }
        if let Some(c) = lumped.mesh_damping_n_s_per_m {
            if !(c >= 0.0 && c.is_finite()) {
                return Err(invalid(
                    "lumped.mesh_damping_n_s_per_m",
                    c.to_string(),
                    "must be a finite number ≥ 0",
                ));
            }
        }
        if !(0.0..1.0).contains(&lumped.bearing_damping_ratio) {
            return Err(invalid(
                "lumped.bearing_damping_ratio",
                lumped.bearing_damping_ratio.to_string(),
                "must be in [0, 1)",
            ));
        }
        let positive_pair = |name: &str, values: Option<[f64; 2]>| match values {
            Some(v) if !v.iter().all(|x| *x > 0.0 && x.is_finite()) => Err(invalid(
                name,
                format!("{v:?}"),
                "both values must be finite and > 0",
            )),
            _ => Ok(()),
        };
        positive_pair("lumped.inertia_kg_mm2", lumped.inertia_kg_mm2)?;
        if !(0.0..1.0).contains(&lumped.drivetrain_damping_ratio) {
            return Err(invalid(
                "lumped.drivetrain_damping_ratio",
                lumped.drivetrain_damping_ratio.to_string(),
                "must be in [0, 1)",
            ));
        }
        for (shaft, end, stiffness, inertia) in [
            (
                "lumped.input_shaft_stiffness_nm_per_rad",
                "lumped.motor_inertia_kg_mm2",
                lumped.input_shaft_stiffness_nm_per_rad,
                lumped.motor_inertia_kg_mm2,
            ),
            (
                "lumped.output_shaft_stiffness_nm_per_rad",
                "lumped.load_inertia_kg_mm2",
                lumped.output_shaft_stiffness_nm_per_rad,
                lumped.load_inertia_kg_mm2,
            ),
        ] {
            if let Some(k) = stiffness {
                if !(k > 0.0 && k.is_finite()) {
                    return Err(invalid(shaft, k.to_string(), "must be finite and > 0"));
                }
            }
            match (stiffness, inertia) {
                (_, Some(i)) if !(i >= 0.0 && i.is_finite()) => {
                    return Err(invalid(end, i.to_string(), "must be finite and ≥ 0"))
                }
                (None, Some(i)) if i > 0.0 => {
                    return Err(invalid(
                        end,
                        i.to_string(),
                        &format!(
                            "needs {shaft} (the shaft it sits on); for a rigid coupling add \
                             the inertia to lumped.inertia_kg_mm2 instead"
                        ),
                    ))
                }
                _ => {}
            }
        }
        positive_pair("lumped.gear_mass_kg", lumped.gear_mass_kg)?;
        positive_pair(
            "lumped.bearing_stiffness_n_per_m",
            Some(lumped.bearing_stiffness_n_per_m),
        )?;

        let fe = &file.fe;
        if !(fe.step_factor > 0.0 && fe.step_factor <= 3.0) {
            return Err(invalid(
                "fe.step_factor",
                fe.step_factor.to_string(),
                "must be in (0, 3]; values above 1 are unstable and only useful to see the failure (default 0.9)",
            ));
        }
        if !(2.0..=100.0).contains(&fe.far_block_cutoff) {
            return Err(invalid(
                "fe.far_block_cutoff",
                fe.far_block_cutoff.to_string(),
                "must be in [2, 100] (default 6: a reduced far block's fixed-interface modes to 6 times the lowest mode of the fine sectors beside it; at 5 the DTE of the 40/24 pair at 12 000 rpm is already 1.9 % off the full bodies')",
            ));
        }
        if !(fe.penalty_factor > 0.0 && fe.penalty_factor.is_finite()) {
            return Err(invalid(
                "fe.penalty_factor",
                fe.penalty_factor.to_string(),
                "must be a finite number > 0 (default 1)",
            ));
        }
        if !(0.0..=0.5).contains(&fe.high_frequency_damping_ratio) {
            return Err(invalid(
                "fe.high_frequency_damping_ratio",
                fe.high_frequency_damping_ratio.to_string(),
                "must be in [0, 0.5] (default 0.05)",
            ));
        }
        if !(0.0..1.0).contains(&fe.mesh_damping_ratio) {
            return Err(invalid(
                "fe.mesh_damping_ratio",
                fe.mesh_damping_ratio.to_string(),
                "must be in [0, 1)",
            ));
        }
        if !(fe.output_interval_us > 0.0 && fe.output_interval_us.is_finite()) {
            return Err(invalid(
                "fe.output_interval_us",
                fe.output_interval_us.to_string(),
                "must be a finite number > 0",
            ));
        }
        let explicit_coarse = fe.explicit_coarse_element_mm.unwrap_or(coarse);
        if !(explicit_coarse >= 0.005 * module_mm && explicit_coarse <= module_mm) {
            return Err(invalid(
                "fe.explicit_coarse_element_mm",
                explicit_coarse.to_string(),
                &format!(
                    "must be in [0.005·m, m] = [{:.4}, {module_mm}] mm (m = tool.module_mm; the default is mesh.coarse_element_mm)",
                    0.005 * module_mm
                ),
            ));
        }
        let explicit_fine = fe.explicit_fine_element_mm.unwrap_or(fine);
        if !(explicit_fine >= 0.005 * module_mm && explicit_fine <= explicit_coarse) {
            return Err(invalid(
                "fe.explicit_fine_element_mm",
                explicit_fine.to_string(),
                &format!(
                    "must be in [0.005·m, the explicit coarse size] = [{:.4}, {explicit_coarse}] mm (m = tool.module_mm = {module_mm})",
                    0.005 * module_mm
                ),
            ));
        }
        let mut scenes = Vec::new();
        for (i, sc) in file.scenes.iter().enumerate() {
            let key = |field: &str| format!("scene[{i}] (\"{}\").{field}", sc.name);
            if file.scenes[..i].iter().any(|o| o.name == sc.name) {
                return Err(invalid(
                    &key("name"),
                    format!("{:?}", sc.name),
                    "names must be unique",
                ));
            }
            let op = match &sc.operating_point {
                Some(name) => match operating_points.iter().find(|o| &o.name == name) {
                    Some(op) => Some(op),
                    None => {
                        return Err(invalid(
                            &key("operating_point"),
                            format!("{name:?}"),
                            &format!(
                                "name one of the operating points: {:?}",
                                operating_points
                                    .iter()
                                    .map(|o| o.name.as_str())
                                    .collect::<Vec<_>>()
                            ),
                        ))
                    }
                },
                None => None,
            };
            let driver_speed = match (sc.speed_rpm, op) {
                (Some(rpm), _) if !(rpm > 0.0 && rpm.is_finite()) => {
                    return Err(invalid(
                        &key("speed_rpm"),
                        rpm.to_string(),
                        "must be a finite number > 0",
                    ))
                }
                (Some(rpm), _) => rpm * 2.0 * PI / 60.0,
                (None, Some(op)) => op.driver_speed,
                (None, None) => {
                    return Err(invalid(
                        &key("operating_point"),
                        "none".into(),
                        "name an operating point, or give speed_rpm and torque_nm",
                    ))
                }
            };
            let torque = match (sc.torque_nm, op) {
                (Some(t), _) if !(t > 0.0 && t.is_finite()) => {
                    return Err(invalid(
                        &key("torque_nm"),
                        t.to_string(),
                        "must be a finite number > 0 (the load torque on the driven gear)",
                    ))
                }
                (Some(t), _) => t,
                (None, Some(op)) => op.torque,
                (None, None) => {
                    return Err(invalid(
                        &key("operating_point"),
                        "none".into(),
                        "name an operating point, or give speed_rpm and torque_nm",
                    ))
                }
            };
            known_variant(&key("relief"), &sc.relief, &relief_variants)?;
            if !(sc.friction >= 0.0 && sc.friction < 1.0) {
                return Err(invalid(
                    &key("friction"),
                    sc.friction.to_string(),
                    "must be in [0, 1)",
                ));
            }
            if !(sc.duration_s > 0.0 && sc.duration_s.is_finite()) {
                return Err(invalid(
                    &key("duration_s"),
                    sc.duration_s.to_string(),
                    "must be a finite number > 0",
                ));
            }
            if !(sc.ramp_s >= 0.0 && sc.ramp_s < sc.duration_s) {
                return Err(invalid(
                    &key("ramp_s"),
                    sc.ramp_s.to_string(),
                    &format!(
                        "must be ≥ 0 and shorter than {} = {}",
                        key("duration_s"),
                        sc.duration_s
                    ),
                ));
            }
            if let Some(margin) = sc.mass_scaling_margin {
                check_mass_scaling_margin(&key("mass_scaling_margin"), margin)?;
            }
            scenes.push(Scene {
                name: sc.name.clone(),
                driver_speed,
                torque,
                relief: sc.relief.clone(),
                friction: sc.friction,
                duration: sc.duration_s,
                cover_pitch: sc.cover_pitch,
                stop_when_settled: sc.stop_when_settled,
                ramp_time: sc.ramp_s,
                ramp: sc.ramp,
                start: sc.start,
                mass_scaling_margin: sc.mass_scaling_margin,
            });
        }

        check_mass_scaling_margin("fe.mass_scaling_margin", fe.mass_scaling_margin)?;
        let fe_settings = FeSettings {
            mass_scaling_margin: fe.mass_scaling.then_some(fe.mass_scaling_margin),
            mass_scaling_mode: fe.mass_scaling_mode,
            step_factor: fe.step_factor,
            time_step: fe.time_step,
            fine_teeth: fe.fine_teeth,
            tooth_layout: fe.tooth_layout,
            far_body: fe.far_body,
            far_block_cutoff: fe.far_block_cutoff,
            penalty_factor: fe.penalty_factor,
            mass_lumping: fe.mass_lumping,
            high_frequency_damping_ratio: fe.high_frequency_damping_ratio,
            mesh_damping_ratio: fe.mesh_damping_ratio,
            output_interval: fe.output_interval_us * 1e-6,
            fine_size: explicit_fine * 1e-3,
            coarse_size: explicit_coarse * 1e-3,
        };
        let lumped_settings = LumpedSettings {
            stiffness: stiffness_source,
            drive: lumped.drive,
            damping_ratio: lumped.damping_ratio,
            mesh_damping: lumped.mesh_damping_n_s_per_m,
            inertias: lumped.inertia_kg_mm2.map(|i| i.map(|v| v * 1e-6)),
            bearings: lumped.bearings,
            bearing_stiffness: lumped.bearing_stiffness_n_per_m,
            bearing_damping_ratio: lumped.bearing_damping_ratio,
            gear_masses: lumped.gear_mass_kg,
            bodies: lumped.bodies,
            body_sway: lumped.body_sway,
            mesh_mass: lumped.mesh_mass,
            shafts: [
                (
                    lumped.input_shaft_stiffness_nm_per_rad,
                    lumped.motor_inertia_kg_mm2,
                ),
                (
                    lumped.output_shaft_stiffness_nm_per_rad,
                    lumped.load_inertia_kg_mm2,
                ),
            ]
            .map(|(stiffness, inertia)| {
                stiffness.map(|k| crate::lumped::Shaft {
                    stiffness: k,
                    end_inertia: inertia.unwrap_or(0.0) * 1e-6,
                })
            }),
            drivetrain_damping_ratio: lumped.drivetrain_damping_ratio,
            relief: lumped.relief.clone(),
            force_law: lumped.force_law,
        };
        if let Some(name) = &lumped.relief {
            known_variant("lumped.relief", name, &relief_variants)?;
        }
        Ok(Case {
            source: source.into(),
            scenes,
            plane: file.fe.plane,
            fe: fe_settings,
            lumped: lumped_settings,
            text: text.into(),
            friction_coefficients: file.contact.friction_coefficients.clone(),
            file,
            pair_spec,
            pair,
            material,
            operating_points,
            relief_variants,
        })
    }

    pub fn name(&self) -> &str {
        &self.file.name
    }

    /// Largest Hertzian contact pressure at the pitch point over the case's loads (operating
    /// points and scenes) [Pa]: line contact of two cylinders with the flanks' radii of
    /// curvature ρ_i = r_wi sin α_w, carrying the whole normal load F_n = T₂/r_b2 (single
    /// contact) on the face width b: p₀ = √(F_n E* / (π b R)), 1/R = 1/ρ₁ + 1/ρ₂,
    /// E* = E / (2(1 − ν²)) (Johnson, *Contact Mechanics*, eq. 4.45).
    pub fn hertz_pressure_pitch(&self) -> f64 {
        let torque = self
            .operating_points
            .iter()
            .map(|o| o.torque.abs())
            .chain(self.scenes.iter().map(|s| s.torque.abs()))
            .fold(0.0, f64::max);
        self.hertz_pressure_at(torque / self.pair.gears[1].base_radius)
    }

    /// The Hertzian pressure at the pitch point under a normal mesh force `force` [N] carried
    /// by one tooth pair across the face [Pa]: p = √(F E* / (π b ρ)), E* = E / (2(1 − ν²)),
    /// 1/ρ = 1/ρ₁ + 1/ρ₂ with ρᵢ = r_wi sin α_w (Johnson, *Contact Mechanics*, §4.2).
    pub fn hertz_pressure_at(&self, force: f64) -> f64 {
        self.hertz_at_pitch(force).0
    }

    /// The Hertzian half-width of the contact at the pitch point under a normal mesh force
    /// `force` [N] carried by one tooth pair across the face [m]: a = √(4 w R / (π E*))
    /// (Johnson, *Contact Mechanics*, eq. 4.43–4.45).
    pub fn hertz_half_width_at(&self, force: f64) -> f64 {
        self.hertz_at_pitch(force).1
    }

    /// (p₀, a) at the pitch point ([`crate::strength::hertz::line_contact`]).
    fn hertz_at_pitch(&self, force: f64) -> (f64, f64) {
        use crate::strength::hertz::{contact_modulus, line_contact};
        let pair = &self.pair;
        let width = pair.gears[0]
            .spec
            .face_width
            .min(pair.gears[1].spec.face_width);
        let radii = pair
            .working_pitch_radii
            .map(|r| r * pair.operating_pressure_angle.sin());
        let material = crate::strength::iso6336::Elastic {
            youngs_modulus: self.material.youngs_modulus,
            poisson_ratio: self.material.poisson_ratio,
        };
        line_contact(force.abs(), width, radii, contact_modulus([material; 2]))
    }

    /// What the case asks that the models cannot answer faithfully, though it is valid input.
    pub fn warnings(&self) -> Vec<String> {
        let mut warnings = Vec::new();
        let pressure = self.hertz_pressure_pitch();
        if pressure > HERTZ_PRESSURE_LIMIT {
            warnings.push(format!(
                "the largest load gives a Hertzian pressure of {:.1} GPa at the pitch point, above \
                 3 GPa, twice the allowable contact stress of the strongest case-hardened gear \
                 steels (about 1.5 GPa, ISO 6336-5): the flanks may yield, and the linear-elastic, \
                 small-strain models here no longer apply. Check the torque's unit (N·m) and the \
                 face width",
                pressure * 1e-9
            ));
        }
        warnings
    }

    /// The same pair with driver and driven exchanged: gear sections, relief requests and the
    /// lumped model's per-gear values swapped; every load torque transferred to the new driven
    /// gear (T′ = T r_b1/r_b2, the same normal load) and every driver speed to the new driver
    /// (n′ = n z₁/z₂, the same mesh frequency). The swap test of validation/pairs runs the LTCA
    /// of both and compares their STE along the line of action.
    pub fn swapped(&self) -> Result<Case, CaseError> {
        let mut file = self.file.clone();
        std::mem::swap(&mut file.gear1, &mut file.gear2);
        let [rb1, rb2] = [0, 1].map(|g| self.pair.gears[g].base_radius);
        let ratio = self.pair.gears[0].teeth() as f64 / self.pair.gears[1].teeth() as f64;
        for point in &mut file.operating_points {
            point.torque_nm *= rb1 / rb2;
            point.speed_rpm *= ratio;
        }
        for scene in &mut file.scenes {
            scene.torque_nm = scene.torque_nm.map(|t| t * rb1 / rb2);
            scene.speed_rpm = scene.speed_rpm.map(|n| n * ratio);
        }
        for variant in &mut file.relief_variants {
            std::mem::swap(&mut variant.gear1, &mut variant.gear2);
        }
        let lumped = &mut file.lumped;
        for pair in [
            lumped.inertia_kg_mm2.as_mut(),
            Some(&mut lumped.bearing_stiffness_n_per_m),
            lumped.gear_mass_kg.as_mut(),
        ]
        .into_iter()
        .flatten()
        {
            pair.swap(0, 1);
        }
        file.name = format!("{}-swapped", file.name);
        let text = toml::to_string(&file).map_err(|e| CaseError::Parse {
            path: self.source.clone(),
            message: e.to_string(),
        })?;
        Case::from_toml_str(
            &text,
            &format!("{} (driver and driven exchanged)", self.source),
        )
    }

    /// Whether a case file's `text` describes this effective case: compared as TOML values, so
    /// comments, layout and the `--set` header aside. Decides when a finished or interrupted
    /// run on disk may be reused or resumed.
    pub fn is_same_case(&self, text: &str) -> bool {
        let table = |text: &str| text.parse::<toml::Table>().ok();
        table(text).is_some_and(|t| Some(t) == table(&self.text))
    }

    /// Mesh spec of gear `index` (1 or 2) with the given teeth fine.
    pub fn mesh_spec(&self, fine_teeth: Vec<usize>) -> crate::mesh::MeshSpec {
        crate::mesh::MeshSpec {
            fine_size: self.file.mesh.fine_element_mm * 1e-3,
            coarse_size: self.file.mesh.coarse_element_mm * 1e-3,
            fine_teeth,
            layout: crate::mesh::ToothLayout::Graded,
        }
    }

    /// A scene by name.
    pub fn scene(&self, name: &str) -> Option<&Scene> {
        self.scenes.iter().find(|s| s.name == name)
    }

    /// A relief variant by name.
    pub fn relief_variant(&self, name: &str) -> Option<&ReliefVariant> {
        self.relief_variants.iter().find(|v| v.name == name)
    }

    /// The elastic bodies of the LTCA: the case's material and plane state.
    pub fn ltca_material(&self) -> BodyMaterial {
        BodyMaterial {
            youngs_modulus: self.material.youngs_modulus,
            poisson_ratio: self.material.poisson_ratio,
            plane: self.plane,
        }
    }

    /// The explicit bodies: the case's steel, plane state and face width (both gears share it),
    /// with the mass lumping of `fe.mass_lumping`.
    pub fn explicit_material(&self) -> ExplicitMaterial {
        ExplicitMaterial {
            youngs_modulus: self.material.youngs_modulus,
            poisson_ratio: self.material.poisson_ratio,
            density: self.material.density,
            plane: self.plane,
            thickness: self.pair.gears[0].spec.face_width,
            lumping: self.fe.mass_lumping,
        }
    }

    /// Reads the case at `path` (None: the embedded default), applies `overrides` to its TOML
    /// and checks the result as one case file: every value, overridden or not, passes the same
    /// checks with the same messages. Without overrides the text is kept as written (comments
    /// included); with them it is the effective case, re-written.
    pub fn load_with(path: Option<&Path>, overrides: &[Override]) -> Result<Self, CaseError> {
        let (text, source) = match path {
            Some(p) => {
                let shown = p.display().to_string();
                let text = std::fs::read_to_string(p).map_err(|source| CaseError::Io {
                    path: shown.clone(),
                    source,
                })?;
                (text, shown)
            }
            None => (EMBEDDED_DEFAULT.to_string(), EMBEDDED_SOURCE.to_string()),
        };
        if overrides.is_empty() {
            return Self::from_toml_str(&text, &source);
        }
        let mut table: toml::Table = toml::from_str(&text).map_err(|e| CaseError::Parse {
            path: source.clone(),
            message: e.to_string().trim_end().to_string(),
        })?;
        for o in overrides {
            o.apply(&mut table)?;
        }
        // A pair changed by its overrides is another pair: its name (in plot titles, summaries
        // and the default output folder) says so, unless the overrides name it themselves.
        let geometry: Vec<String> = overrides
            .iter()
            .filter(|o| {
                let section = o.key().split(['.', '[']).next().unwrap_or_default();
                PAIR_SECTIONS.contains(&section)
            })
            .map(|o| {
                o.to_string()
                    .chars()
                    .map(|c| match c.is_ascii_alphanumeric() || "._=-".contains(c) {
                        true => c,
                        false => '_',
                    })
                    .collect()
            })
            .collect();
        let renamed = overrides.iter().any(|o| o.key() == "name");
        if let (false, false, Some(toml::Value::String(name))) =
            (geometry.is_empty(), renamed, table.get("name").cloned())
        {
            table.insert(
                "name".into(),
                toml::Value::String(format!("{name}+{}", geometry.join("+"))),
            );
        }
        let effective = toml::to_string(&table).map_err(|e| CaseError::Parse {
            path: source.clone(),
            message: e.to_string(),
        })?;
        let shown: Vec<String> = overrides.iter().map(|o| o.to_string()).collect();
        let header = format!(
            "# {source} with {}\n",
            shown
                .iter()
                .map(|s| format!("--set {s}"))
                .collect::<Vec<_>>()
                .join(" ")
        );
        Self::from_toml_str(&format!("{header}{effective}"), &source)
    }
}

/// The case file's sections that define the pair itself (its cutter, gears and centre
/// distance): an override of one makes another pair, named after it ([`Case::load_with`]).
const PAIR_SECTIONS: [&str; 4] = ["tool", "gear1", "gear2", "pair"];

/// One change to a case file's TOML before it is checked (`--set KEY=VALUE` and the commands'
/// shorthands for it).
///
/// KEY is a dotted path, e.g. `fe.plane` or `mesh.fine_element_mm`; an array of tables is
/// indexed by position or by the `name` of its element: `scene[0].duration_s`,
/// `scene[low-unmodified].duration_s`, `relief_variant[tip20-root10].gear1.tip.amount_um`.
/// VALUE is a TOML value (`0.05`, `true`, `[1, 2]`, `"x"`); anything that is not one is taken
/// as a string, so `fe.plane=stress` needs no quotes.
#[derive(Debug, Clone, PartialEq)]
pub enum Override {
    Set {
        key: String,
        value: toml::Value,
    },
    /// Removes a key (back to its default).
    Remove {
        key: String,
    },
    /// Appends a table to an array of tables (e.g. a new `[[scene]]`).
    Append {
        array: String,
        table: toml::Table,
    },
}

impl Override {
    /// The dotted key it changes (an appended table's array).
    pub fn key(&self) -> &str {
        match self {
            Override::Set { key, .. } | Override::Remove { key } => key,
            Override::Append { array, .. } => array,
        }
    }
}

impl std::fmt::Display for Override {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Override::Set { key, value } => write!(f, "{key}={value}"),
            Override::Remove { key } => write!(f, "{key} removed"),
            Override::Append { array, table } => {
                write!(f, "{array}[+]={}", toml::Value::Table(table.clone()))
            }
        }
    }
}

impl std::str::FromStr for Override {
    type Err = String;

    /// Parses `KEY=VALUE`.
    fn from_str(text: &str) -> Result<Self, String> {
        let Some((key, value)) = text.split_once('=') else {
            return Err(format!(
                "{text:?} is not KEY=VALUE: write e.g. fe.plane=stress or mesh.fine_element_mm=0.05"
            ));
        };
        let key = key.trim();
        if key.is_empty() {
            return Err(format!("{text:?} has no key before '='"));
        }
        Ok(Override::Set {
            key: key.to_string(),
            value: parse_value(value.trim()),
        })
    }
}

impl Override {
    /// `key = value` for a value that serializes to TOML (numbers, strings, booleans).
    pub fn set(key: impl Into<String>, value: impl Into<toml::Value>) -> Self {
        Override::Set {
            key: key.into(),
            value: value.into(),
        }
    }

    fn apply(&self, root: &mut toml::Table) -> Result<(), CaseError> {
        let error = |key: &str, message: String| CaseError::Override {
            key: key.to_string(),
            message,
        };
        match self {
            Override::Set { key, value } => {
                let (parent, last) = walk(root, key, true)?;
                parent.insert(last, value.clone());
            }
            Override::Remove { key } => {
                if let Ok((parent, last)) = walk(root, key, false) {
                    parent.remove(&last);
                }
            }
            Override::Append { array, table } => {
                let (parent, last) = walk(root, array, true)?;
                match parent
                    .entry(last)
                    .or_insert_with(|| toml::Value::Array(Vec::new()))
                {
                    toml::Value::Array(items) => items.push(toml::Value::Table(table.clone())),
                    _ => return Err(error(array, "is not an array of tables".into())),
                }
            }
        }
        Ok(())
    }
}

/// A TOML value, or the text as a string when it is not one.
fn parse_value(text: &str) -> toml::Value {
    toml::from_str::<toml::Table>(&format!("v = {text}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(text.to_string()))
}

/// The table that holds the last segment of `key`, and that segment; missing tables on the way
/// are created when `create`.
fn walk<'a>(
    root: &'a mut toml::Table,
    key: &str,
    create: bool,
) -> Result<(&'a mut toml::Table, String), CaseError> {
    let error = |message: String| CaseError::Override {
        key: key.to_string(),
        message,
    };
    let segments: Vec<&str> = key.split('.').collect();
    if segments.iter().any(|s| s.trim().is_empty()) {
        return Err(error("has an empty part: write e.g. fe.plane".into()));
    }
    let mut table = root;
    for (depth, segment) in segments.iter().enumerate() {
        let (name, index) = match segment.split_once('[') {
            Some((name, rest)) => match rest.strip_suffix(']') {
                Some(index) => (name, Some(index)),
                None => return Err(error(format!("{segment:?}: close the index with ']'"))),
            },
            None => (*segment, None),
        };
        let last = depth + 1 == segments.len();
        if last && index.is_none() {
            return Ok((table, name.to_string()));
        }
        // Missing tables on the way are created; a missing array of tables is an error.
        let entry = if create && index.is_none() {
            table
                .entry(name.to_string())
                .or_insert_with(|| toml::Value::Table(toml::Table::new()))
        } else {
            table
                .get_mut(name)
                .ok_or_else(|| error(format!("the case has no {name:?}")))?
        };
        let value = match (entry, index) {
            (toml::Value::Array(items), Some(index)) => {
                let count = items.len();
                let position = match index.parse::<usize>() {
                    Ok(i) if i < count => i,
                    Ok(i) => {
                        return Err(error(format!(
                            "{name} has {count} entries: index {i} is out of range"
                        )))
                    }
                    Err(_) => {
                        let names: Vec<String> = items
                            .iter()
                            .filter_map(|v| v.get("name").and_then(|n| n.as_str()))
                            .map(str::to_string)
                            .collect();
                        items
                            .iter()
                            .position(|v| v.get("name").and_then(|n| n.as_str()) == Some(index))
                            .ok_or_else(|| {
                                error(format!("no {name} is named {index:?}; they are {names:?}"))
                            })?
                    }
                };
                &mut items[position]
            }
            (_, Some(_)) => {
                return Err(error(format!(
                    "{name} is not an array of tables: drop the index"
                )))
            }
            (value, None) => value,
        };
        if last {
            return Err(error(
                "names a whole table: give a key inside it, e.g. scene[0].duration_s".into(),
            ));
        }
        match value {
            toml::Value::Table(inner) => table = inner,
            _ => {
                return Err(error(format!(
                    "{segment} is a value, not a table: it has no keys below it"
                )))
            }
        }
    }
    unreachable!("the loop returns at the last segment")
}

/// Converts one gear's relief section to SI requests.
fn gear_relief_request(
    gear: usize,
    section: &GearReliefSection,
) -> Result<FlankReliefSpec, GeometryError> {
    let convert = |end: &str, r: &ReliefSection| -> Result<ReliefSpec, GeometryError> {
        let parameter = format!("gear{gear}.{end}");
        let given = [
            r.start.is_some(),
            r.start_roll_deg.is_some(),
            r.start_diameter_mm.is_some(),
        ];
        if given.iter().filter(|g| **g).count() > 1 {
            return Err(GeometryError::Relief {
                parameter,
                reason: "give at most one of start, start_roll_deg, start_diameter_mm".into(),
            });
        }
        let start = if let Some(name) = &r.start {
            match name.as_str() {
                "hpstc" => ReliefStart::Hpstc,
                "lpstc" => ReliefStart::Lpstc,
                "short" => ReliefStart::Short,
                other => {
                    return Err(GeometryError::Relief {
                        parameter: format!("{parameter}.start"),
                        reason: format!("unknown start {other:?}: use \"hpstc\", \"lpstc\" or \"short\", or give start_roll_deg or start_diameter_mm"),
                    })
                }
            }
        } else if let Some(deg) = r.start_roll_deg {
            ReliefStart::RollAngle(deg.to_radians())
        } else if let Some(d) = r.start_diameter_mm {
            ReliefStart::Diameter(d * 1e-3)
        } else if end == "tip" {
            ReliefStart::Hpstc
        } else {
            ReliefStart::Lpstc
        };
        Ok(ReliefSpec {
            amount: r.amount_um * 1e-6,
            shape: r.shape,
            start,
        })
    };
    Ok(FlankReliefSpec {
        tip: section
            .tip
            .as_ref()
            .map(|r| convert("tip", r))
            .transpose()?,
        root: section
            .root
            .as_ref()
            .map(|r| convert("root", r))
            .transpose()?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The paper pair at 143.6 N·m, by hand: r_w = m z/2 = 57.24 mm (no shift, standard centre
    /// distance), ρ = r_w sin 20°, R = ρ/2, F_n = T/(r_w cos 20°) = 2 669.74 N, b = 25.4 mm,
    /// E* = 206 GPa/(2 · 0.91): p₀ = 621.99 MPa, no warning. A hundred times the torque gives
    /// ten times the pressure, 6.2 GPa, and the warning that names it.
    #[test]
    fn hertz_pressure_of_the_paper_pair_and_the_overload_warning() {
        let case = Case::embedded_default().unwrap();
        let p = case.hertz_pressure_pitch();
        assert!((p / 621_985_075.136 - 1.0).abs() < 1e-9, "{p}");
        assert!(case.warnings().is_empty());
        let heavy = Case::load_with(
            None,
            &[Override::set("operating_point[0].torque_nm", 14360.0)],
        )
        .unwrap();
        assert!((heavy.hertz_pressure_pitch() / p - 10.0).abs() < 1e-9);
        // Unequal gears, 36:72, by hand the same way: r_w2 = 114.48 mm carries F_n = T/r_b2
        // and the flank radii differ (R = ρ₁ρ₂/(ρ₁ + ρ₂)): 380.89 MPa. Swapping the gears' roles
        // would give another number.
        let ratio2 = Case::load_with(None, &[Override::set("gear2.teeth", 72)]).unwrap();
        let p2 = ratio2.hertz_pressure_pitch();
        assert!((p2 / 380_886_515.428 - 1.0).abs() < 1e-9, "{p2}");
        let warnings = heavy.warnings();
        assert_eq!(warnings.len(), 1);
        assert!(warnings[0].contains("6.2 GPa") && warnings[0].contains("linear-elastic"));
    }

    /// The Hertzian half-width of the paper pair at the pitch point, by hand from the closed
    /// form a = √(4 F R / (π b E*)) (Johnson eq. 4.43), not through the pressure: F = T/r_b2
    /// = 2 669.7 N, b = 25.4 mm, R = ρ/2 = 9.789 mm, E* = E/(2(1 − ν²)): a = 0.107581 mm.
    #[test]
    fn hertz_half_width_of_the_paper_pair() {
        let case = Case::embedded_default().unwrap();
        let force = 143.6 / case.pair.gears[1].base_radius;
        let a = case.hertz_half_width_at(force);
        assert!((a / 1.075_809_663_5e-4 - 1.0).abs() < 1e-8, "{a}");
        // a ∝ √F.
        assert!((case.hertz_half_width_at(4.0 * force) / a - 2.0).abs() < 1e-12);
    }

    #[test]
    fn embedded_default_is_the_paper_pair() {
        let case = Case::embedded_default().unwrap();
        assert_eq!(case.name(), "paper36");
        assert_eq!(case.pair.gears[0].teeth(), 36);
        assert_eq!(case.operating_points.len(), 2);
        assert!(
            (case.operating_points[0].driver_speed - 60.0 * std::f64::consts::TAU / 60.0).abs()
                < 1e-12
        );
        assert_eq!(case.friction_coefficients, vec![0.0, 0.15]);
        assert!(case.relief_variant("none").unwrap().modifications[0].is_none());
        let paper = case.relief_variant("tip20-root10").unwrap();
        assert!((paper.modifications[1].tip.unwrap().amount - 20e-6).abs() < 1e-18);
    }

    #[test]
    fn unknown_key_names_key_and_line() {
        let text = EMBEDDED_DEFAULT.replace(
            "profile_shift = 0.0\naddendum",
            "profile_shift = 0.0\nprofile_shfit = 0.1\naddendum",
        );
        let err = Case::from_toml_str(&text, "t.toml")
            .unwrap_err()
            .to_string();
        assert!(err.contains("profile_shfit"), "{err}");
        assert!(err.contains("line"), "{err}");
    }

    #[test]
    fn negative_module_is_named() {
        let text = EMBEDDED_DEFAULT.replace("module_mm = 3.18", "module_mm = -3.18");
        let err = Case::from_toml_str(&text, "t.toml")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("tool.module_mm") && err.contains("-3.18"),
            "{err}"
        );
    }

    #[test]
    fn five_teeth_is_an_undercut_error() {
        let text = EMBEDDED_DEFAULT.replacen("teeth = 36", "teeth = 5", 1);
        let err = Case::from_toml_str(&text, "t.toml")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("gear1 is undercut") && err.contains("teeth = 5"),
            "{err}"
        );
    }

    fn set(text: &str) -> Override {
        text.parse().unwrap()
    }

    /// Overrides reach nested keys, arrays of tables by index or by name, and keys the file
    /// does not hold (defaults); the effective text says what was set.
    #[test]
    fn overrides_change_the_case_before_it_is_checked() {
        let case = Case::load_with(
            None,
            &[
                set("fe.plane=stress"),
                set("mesh.fine_element_mm=0.5"),
                set("scene[low-modified].duration_s=0.02"),
                set("scene[0].friction=0.1"),
                set("relief_variant[tip20-root10].gear1.tip.amount_um=15"),
                set("lumped.drive=speed"),
            ],
        )
        .unwrap();
        assert_eq!(case.plane, PlaneState::Stress);
        assert_eq!(case.file.mesh.fine_element_mm, 0.5);
        assert_eq!(case.scene("low-modified").unwrap().duration, 0.02);
        assert_eq!(case.scenes[0].friction, 0.1);
        let tip = case.relief_variant("tip20-root10").unwrap().modifications[0].tip;
        assert!((tip.unwrap().amount - 15e-6).abs() < 1e-18);
        assert_eq!(case.lumped.drive, Drive::Speed);
        assert!(
            case.text.contains("--set fe.plane=\"stress\""),
            "{}",
            case.text
        );
        let again = Case::from_toml_str(&case.text, "effective").unwrap();
        assert_eq!(again.file, case.file);
    }

    /// A pair changed by overrides of its cutter, gears or centre distance is named after
    /// them (plot titles, summaries, the default output folder); other overrides, or a name
    /// given with them, keep the name.
    #[test]
    fn a_pair_changed_by_overrides_is_named_after_them() {
        let name = |o: &[&str]| {
            let overrides: Vec<Override> = o.iter().copied().map(set).collect();
            Case::load_with(None, &overrides)
                .unwrap()
                .name()
                .to_string()
        };
        assert_eq!(
            name(&[
                "gear1.teeth=24",
                "mesh.fine_element_mm=0.5",
                "gear2.teeth=40"
            ]),
            "paper36+gear1.teeth=24+gear2.teeth=40"
        );
        assert_eq!(name(&["mesh.fine_element_mm=0.5"]), "paper36");
        assert_eq!(name(&["gear1.teeth=24", "name=mine"]), "mine");
    }

    #[test]
    fn a_bad_override_gets_the_case_files_message() {
        let message = |o: &str| Case::load_with(None, &[set(o)]).unwrap_err().to_string();
        let unknown = message("fe.plnae=stress");
        assert!(
            unknown.contains("plnae") && unknown.contains("unknown field"),
            "{unknown}"
        );
        let out_of_range = message("mesh.fine_element_mm=3");
        assert!(
            out_of_range.contains("mesh.fine_element_mm = 3 is invalid"),
            "{out_of_range}"
        );
        let wrong_type = message("fe.step_factor=fast");
        assert!(wrong_type.contains("step_factor"), "{wrong_type}");
        let cutoff = message("fe.far_block_cutoff=1.5");
        assert!(
            cutoff.contains("fe.far_block_cutoff = 1.5 is invalid") && cutoff.contains("[2, 100]"),
            "{cutoff}"
        );
        let far = message("fe.far_body=reducd");
        assert!(far.contains("reducd"), "{far}");
        let default = Case::load_with(None, &[]).unwrap();
        assert_eq!(default.fe.far_body, crate::explicit::far::FarBody::Reduced);
        assert_eq!(
            default.fe.far_block_cutoff,
            crate::explicit::far::FAR_BLOCK_CUTOFF
        );
        let full = Case::load_with(None, &[set("fe.far_body=full")]).unwrap();
        assert_eq!(full.fe.far_body, crate::explicit::far::FarBody::Full);
        let no_scene = message("scene[nowhere].duration_s=1");
        assert!(
            no_scene.contains("nowhere") && no_scene.contains("low-unmodified"),
            "{no_scene}"
        );
        let index = message("operating_point[7].torque_nm=1");
        assert!(index.contains("out of range"), "{index}");
        assert!("fe.plane".parse::<Override>().is_err());
    }

    /// A removed key falls back to its default; an appended scene is checked like the others.
    #[test]
    fn removed_keys_and_appended_scenes() {
        let mut scene = toml::Table::new();
        scene.insert("name".into(), "extra".into());
        scene.insert("speed_rpm".into(), 300.0.into());
        scene.insert("torque_nm".into(), 100.0.into());
        scene.insert("duration_s".into(), 0.01.into());
        scene.insert("ramp_s".into(), 0.001.into());
        let case = Case::load_with(
            None,
            &[
                Override::Remove {
                    key: "fe.step_factor".into(),
                },
                Override::Append {
                    array: "scene".into(),
                    table: scene.clone(),
                },
            ],
        )
        .unwrap();
        assert_eq!(case.fe.step_factor, default_step_factor());
        let extra = case.scene("extra").unwrap();
        assert!((extra.driver_speed - 10.0 * PI).abs() < 1e-12);
        assert_eq!(extra.torque, 100.0);
        scene.remove("torque_nm");
        let err = Case::load_with(
            None,
            &[Override::Append {
                array: "scene".into(),
                table: scene,
            }],
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("operating_point") && err.contains("torque_nm"),
            "{err}"
        );
    }

    /// The command line's enumerated values are the case file's spellings.
    #[test]
    fn command_line_and_case_file_spell_enumerations_alike() {
        use clap::ValueEnum;
        fn same<T: ValueEnum + Serialize>() {
            for v in T::value_variants() {
                let clap = v.to_possible_value().unwrap().get_name().to_string();
                assert_eq!(serde_json::to_value(v).unwrap(), clap);
            }
        }
        same::<Drive>();
        same::<MassLumping>();
    }
}
