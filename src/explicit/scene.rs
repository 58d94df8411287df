//! An explicit FE scene of the meshing pair: what to mesh fine, the stable time step, the run
//! with its recorded time histories, and the analysis of the DTE (statistics, spectrum, the
//! mesh stiffness from the DTE, impacts).
//!
//! # Model no more than the scene needs
//! Only the teeth that engage while the driver turns through the scene get fine flanks:
//! starting with tooth 0 of each gear at the pitch point, the signed tooth pairs on the path of
//! contact or within 0.2 base pitch of it over the scene's rotation ([`engagement`]: driver
//! tooth s meets driven tooth −s, for any tooth counts), and on gear 2 the teeth on either side
//! of each partner (the back flanks) — the rest of each gear is meshed coarse. Contact pairs
//! are those tooth pairs, drive and back flanks.
//!
//! A scene that turns through many pitches (the 3000 rpm scenes: 1.5 revolutions, every tooth)
//! needs at any instant only the few teeth near the mesh fine. With `fe.fine_teeth = "window"`
//! (the default) such a run goes window by window: each window spans [`WINDOW_PITCHES`] driver
//! pitch, its mesh is fine on the teeth that engage over it (the same rule over its span, plus
//! two output intervals for the switch's lateness, plus every tooth pair in contact at the
//! switch wherever it stands), and its contact pairs are theirs. At the first recorded sample
//! past a window's end the run builds the next window's model and carries the state over
//! ([`crate::explicit::remesh`]): nodes of the sectors that keep their kind copy their values
//! (the meshes share them), the nodes of switched sectors take the old mesh's isoparametric
//! interpolation (exact for the rigid motion), the contact forces and friction history stay
//! with the nodes and flank pairs both models hold, and the accelerations come from the new
//! mesh's forces. The kinetic and strain energy the switch changes is booked as
//! `remeshing` in the energy account (the velocity field is carried as it is, so a rigid motion
//! stays rigid; the switched sectors lump their mass elsewhere, so the momentum changes by the
//! lumping's difference, without a force). A run sent back by its step control goes no
//! further back than its last switch. [`WINDOW_NEIGHBOURS`] teeth on either side are fine as
//! well, and the first window's bodies bound the step beside the scene's. The teeth switch out of contact, so what a switch drops is the
//! leaving teeth's free ringing: on the 3000 rpm scene (45 windows, 0.59 of the elements per
//! step, 0.68 of the wall time) 4e-8 of the transmitted work, the DTE mean within 3e-4 and its
//! mesh lines within 1.2 % of the run with every engaging tooth fine. That ringing is nearly
//! undamped (the element damping is ζ = 0.05 at ω_max, about 1e-4 at the teeth's 40 kHz), so
//! on the scene's mesh it goes on for the whole run and grows as more teeth pass the mesh: the
//! contact force's 38–45 kHz content there rises 3.3× over the run, on windows it stays level,
//! and the level-1 impact measure reads 10 % lower (validation/performance).
//! The history keeps the scene's flank pairs (a pair outside the current window reads zero);
//! a checkpoint holds its window, so a resumed run rebuilds that window's mesh. Scenes that turn
//! through fewer than [`MIN_WINDOWED_PITCHES`] pitches (the low-speed ones) run on one mesh.
//!
//! # Time step (seed paper eqs. 28–31, and the eigenvalue it approximates)
//! Δt_cr = min(2/ω_max of each body with its bore fixed, by power iteration on M⁻¹K;
//! 2/√(k_n(1/m_s + 1/m_m)) of the stiffest contact spring), reduced for the stiffness damping
//! ζ_max = β_K ω_max/2 to Δt_cr(√(1 + ζ_max²) − ζ_max); Δt = step_factor·Δt_cr. The paper's
//! L/c_w and the element-eigenvalue bound are reported beside it. The contact spring's bound
//! (lightest slave and master nodes, the edge's whole penalty) holds for every contact state;
//! it is the step of `fe.time_step = "bound"`, and the step every run starts with.
//!
//! The bound is the worst case of every spring on the lightest nodes; the pair's own
//! 2/ω_max with bodies and the springs actually closed ([`PairIntegrator::coupled_critical_step`],
//! power iteration) lies 10–45 % above it (3000 rpm scene: 2.35e-8 s undamped at the stiffest
//! contact met, against 1.94e-8 s). `fe.time_step = "coupled"` (the default) steps at `step_factor` ×
//! that measured step, reduced for the stiffness damping as above, where the contact is:
//! * it is measured at once wherever the closed springs get stiffer than at any check so far
//!   — their own frequency bound ([`crate::explicit::pair::closed_springs_omega`], Gershgorin
//!   on their Gram matrix, every step) rising 2 % ([`SPRING_RISE`]) above its highest at a
//!   check — and [`COUPLED_RECHECKS`] times over the run besides; the run steps at the
//!   smallest measured so far, 1 % below it ([`STEP_HEADROOM`]), never below the bound's step
//!   and never rising again once lowered;
//! * the step changes only at a recorded sample, to a step that divides the sample interval,
//!   so the samples keep their spacing; the state at every sample is kept, and a check that
//!   finds the step above what the state allows sends the run back to that sample, on from
//!   there at the lower step;
//! * a run that diverges at a raised step goes back to the sample before its last check that
//!   passed (the last sample may already carry the instability's growth) and ends on the
//!   bound's step (`dt_fallback` in summary.json says why).
//!
//! Without any damping the measured step at factor 0.9 is marginal where points close and open:
//! the undamped entering-tooth test (tests/explicit_pair.rs) books 7.4e-5 J jumps in its balance
//! there against 2.6e-6 J on the bound's step, so undamped runs take the bound. With the scenes' element
//! damping (ζ = 0.05 at ω_max) the stiffness scene's k(θ) moves by 2.4e-6 per bin and its
//! energy error from 5.9e-5 to 1.1e-4 of the work (validation/performance).
//!
//! # Mass scaling (low speeds)
//! At low speed the mesh harmonics lie far below the mesh mode and the response is
//! quasi-static, while the step is set by the element and contact frequencies: the run pays for
//! dynamics it does not need. Each gear's polar inertia is raised by
//! s = (f_n / (margin · 5 f_mesh))² when that is above 1 (f_n the mesh mode with the driver
//! held, √(k_m R_b2²/I₂)/2π; 5 f_mesh the highest mesh harmonic kept), so the mesh mode falls
//! by √s to `margin` × the fifth harmonic. Scaled uniformly (every nodal mass and the hub's
//! inertia times s), every natural frequency falls by √s, the element and contact frequencies
//! with it, and the stable step grows by √s; scaled to a target step (below, the default) the
//! step grows by about 3√s. What is kept are the means: of the
//! DTE, of k(θ) = ΣW/Σ(R_b2 θ − e) and of the static TE from it (within 0.1 % of an unscaled
//! run, `geardyn validate mass-scaling`); harmonic h of the mesh frequency is amplified by
//! 1/(1 − (h f_mesh/f_n,scaled)²), +0.4 % at the first, +12.5 % at the fifth with margin 3.
//! What is not kept is the fine detail: the harmonics near 5·margin meet the scaled mode
//! (Q = 1/2ζ = 10) and every contact-ratio step rings it, so the raw DTE peak-to-peak of a
//! scaled run is 40 % larger, the low-passed one 6 %; the ringing also loads the gear body's
//! inertia between the contact and the hub, so W = kδ holds only approximately and single bins
//! of k(θ) move by up to 4 % (the static TE's peak-to-peak by 1.5 % at margin 3, 10.7 % at
//! margin 2; validation/low-speed). The level-1
//! impact detail is not reported for a scaled run (its 25–50 kHz band then holds body modes
//! lowered by √s, or by up to √sₑ). Where 5·margin·f_mesh ≥ f_n (the 3000 rpm scenes:
//! f_mesh = 1 800 Hz against f_n ≈ 3.1 kHz), s = 1: the dynamics matter and nothing is
//! scaled. The scaled mesh mode is
//! the one the dashpot, the settling time and the low-pass use; `summary.json` states the
//! factor and both frequencies.
//!
//! **Where the mass goes** (`fe.mass_scaling_mode`, [`MassScalingMode`]). The mesh mode of the
//! rigid gears sees only each gear's polar inertia, while the stable step is set by the
//! smallest elements: the 1 mm flank elements and the thin rim layers below the teeth (the
//! paper pair's elements' own steps Δtₑ spread over 8× at 1 mm / 3 mm). Uniform scaling
//! multiplies all of them alike. `"target-step"` spends the same inertia budget where the step
//! is made: each element's lumped masses times sₑ = max(1, (T_g/Δtₑ)²), with the T_g at which
//! gear g's inertia Σₑ sₑ Iₑ is s Σₑ Iₑ ([`ExplicitPair::mass_scaling_steps`]). By Irons'
//! element bound no element then holds a body's stable step below its T_g. Each gear's inertia,
//! and so the rigid gears' mesh mode, is uniform scaling's (mass moved towards the contact
//! would lift the real mode above that estimate, as it sits nearer the support than the hub;
//! not measured). No frequency falls by more than √max sₑ (Rayleigh's quotient): on the paper
//! pair at 60 rpm the teeth's own modes stay above 12× the fifth harmonic. The stiffness scene
//! takes 2.95× fewer steps than with uniform scaling, the same budget, and its means, static TE
//! and k(θ) bins stay as close to an unscaled run's (validation/low-speed, "Mass scaling").
//! A run on windows of fine teeth scales uniformly:
//! the fine teeth change at every switch, and most of a target step's mass would move with
//! them.
//!
//! # Mesh damping
//! The elastic bodies' stiffness damping is tuned to the element scale (ζ at ω_max) and is a few
//! ppm at the mesh mode, which would ring on undamped after every engagement. A dashpot on the
//! driven hub against the DTE rate, T_d = −c_t (φ̇₂ − φ̇₂,kin), c_t = 2ζ√(k_m R_b2² I₂), acting
//! only while the teeth are in contact (no torque across open teeth), gives the mesh mode the
//! damping ratio ζ — the lumped model's viscous mesh damping c = 2ζ√(k̄ m) with the driver at
//! prescribed speed (m = I₂/R_b2²). k_m is the pair's own mean mesh stiffness hub to hub (the
//! LTCA on the same bodies, which the caller passes, their twist included), so ζ is the lumped
//! model's at the same nominal value; with the bodies' twist too (0.0482 for 0.05 on the paper
//! pair by its lumped twin, which carries the dashpot where the FE does, `lumped::DampingSite`,
//! and on its bodies only the elements' β: `study::compare::FeDamping`).
//!
//! # Settling after the ramp
//! The ramp leaves the mesh mode ringing; statistics start when that ringing has decayed to
//! [`SETTLED_RINGING`] of the static response. For an undamped mode ω loaded by f(t) (the
//! static response's share, 1 after the ramp), the free vibration left is |∫ f′(t) e^{−iωt} dt|
//! of the static response. Here f = r + c ṙ: the load torque ramp r(t) and, when the gears
//! start from rest, the driven gear's inertia torque I₂Ω₂ṙ(t) over T (c = I₂Ω₂/T), so
//! ```text
//! A = |R(ω)| √(1 + (c ω)²),   |R(ω)| = |∫ ṙ e^{−iωt} dt| ≤ 2/(ω t_r)          linear ramp
//!                                                      ≤ π²/((ω t_r)² − π²)    cosine ramp (ω t_r > √2 π)
//! t_settle = ln(A / SETTLED_RINGING) / (ζ ω),  0 when A is below it
//! ```
//! (the envelopes, not the exact zeros of the sinc, since ω is an estimate). With mass scaling
//! the inertia term matters: at 60 rpm, scaled 33×, I₂Ω₂/T = 4.8 ms and cω = 16, a spin-up
//! rings the mesh mode at 97 % of the static DTE after a 10 ms linear ramp (5.2 decay times to
//! settle); a start at speed with a cosine ramp leaves 0.9 % (0.6 decay times).
//!
//! # Mesh stiffness from the DTE (seed paper eq. 37, read as the lumped model's mesh law)
//! ```text
//! k(θ) = W(θ) / (R_b2 θ_DTE(θ) − e(θ))
//! ```
//! W the mesh force from the contact forces (their moment on the driven gear over R_b2, the
//! torque-equivalent force along the line of action; not the nominal torque), θ_DTE the
//! angular DTE, e(θ) the geometric unloaded transmission error of the relief variant (zero
//! without relief), binned as recorded over the statistics window into [`STIFFNESS_BINS`] bins
//! per base pitch of driver rotation, centred on the LTCA's positions: k = ΣW / Σδ per bin.
//! The mesh mode's free ringing needs no filter here: the contact sets W ≈ k δ sample by sample
//! (the teeth's own modes lie far above the mesh mode), so the ringing moves W and δ together
//! and largely cancels in the ratio, while a low-pass over the (mass-scaled) mode's period, a
//! tenth to a fifteenth of a mesh period, would smear the steps of k(θ) at the contact-ratio
//! transitions by up to 20 %.
//! The low-pass (one mode period) serves only the DTE's quasi-static statistics.
//! Without relief and with W = T/R_b2 this is the paper's
//! k = T/(θ R_b2²); with relief, subtracting e is what makes it the stiffness the lumped model
//! needs beside the same e (the paper's relief "stiffness" is only apparent).

use std::time::Instant;

use crate::explicit::body::{ExplicitBody, ExplicitMaterial};
use crate::explicit::far::{BlockCache, BlockSeed, FarBody};
use crate::explicit::pair::{
    Drive, ExplicitPair, IntegratorCheckpoint, PairEnergy, PairIntegrator, PairState, PhaseWall,
    Ramp, Start,
};
use crate::explicit::remesh::NodeTransfer;
use crate::explicit::solver::critical_step;
use crate::fe::{FeError, MassLumping};
use crate::geometry::engagement::{self, ToothPair};
use crate::geometry::{FlankModification, GearPair};
use crate::mesh::{mesh_gear, ToothLayout};
use crate::resources::MemoryEstimate;
use crate::stiffness::{MeshStiffness, PeriodicTable};

/// An explicit FE scene, SI: one run of the meshing pair.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Scene {
    pub name: String,
    /// Driver speed Ω [rad/s] after the ramp.
    pub driver_speed: f64,
    /// Load torque on the driven gear [N·m] after the ramp.
    pub torque: f64,
    /// Relief variant's name (the modifications are passed to [`prepare`]).
    pub relief: String,
    /// Coulomb friction coefficient μ.
    pub friction: f64,
    /// Simulated time [s] (at least; [`Scene::cover_pitch`]).
    pub duration: f64,
    /// Lengthen the run to [`covering_duration`] where `duration` is shorter ([`prepare`]).
    pub cover_pitch: bool,
    /// End the run once its DTE has settled ([`SettledStop`]), `duration` at the latest.
    pub stop_when_settled: bool,
    /// Ramp of the load torque, and of the driver speed when starting from rest [s].
    pub ramp_time: f64,
    pub ramp: Ramp,
    pub start: Start,
    /// Overrides [`FeSettings::mass_scaling_margin`] when mass scaling is on.
    pub mass_scaling_margin: Option<f64>,
}

/// Settings of an explicit run, SI (the case's `[fe]` section).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FeSettings {
    /// Mass scaling: the scaled mesh mode at least this many times the highest mesh harmonic
    /// kept ([`KEPT_HARMONIC`]); None: off.
    pub mass_scaling_margin: Option<f64>,
    pub mass_scaling_mode: MassScalingMode,
    pub step_factor: f64,
    /// Which stable step `step_factor` multiplies (module doc, "Time step").
    pub time_step: TimeStep,
    pub penalty_factor: f64,
    pub mass_lumping: MassLumping,
    pub high_frequency_damping_ratio: f64,
    /// Damping ratio of the mesh mode (the driven hub's dashpot on the DTE rate).
    pub mesh_damping_ratio: f64,
    /// Recorded sample interval [s].
    pub output_interval: f64,
    /// Flank element size [m] and coarse size [m].
    pub fine_size: f64,
    pub coarse_size: f64,
    /// Which teeth get fine flanks: those of the current window or those of the whole scene.
    pub fine_teeth: FineTeeth,
    /// How the teeth are laid out (the case's `fe.tooth_layout`).
    pub tooth_layout: ToothLayout,
    /// How a run on windows models the gears' bodies away from the contact (the case's
    /// `fe.far_body`), and a reduced block's cutoff over the lowest mode of the fine sectors
    /// beside it (`fe.far_block_cutoff`).
    pub far_body: FarBody,
    pub far_block_cutoff: f64,
}

/// Which teeth a run meshes fine (the case's `fe.fine_teeth`; module doc, "Model no more than
/// the scene needs").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FineTeeth {
    /// The teeth that engage in the current window of [`WINDOW_PITCHES`] driver pitches; the
    /// run goes on to the next window's mesh at a recorded sample, its state carried over
    /// ([`crate::explicit::remesh`]). A scene that turns through fewer than
    /// [`MIN_WINDOWED_PITCHES`] pitches runs on one mesh.
    #[default]
    Window,
    /// Every tooth that engages anywhere in the scene, for the whole run.
    Scene,
}

/// Where mass scaling puts the added mass (the case's `fe.mass_scaling_mode`; module doc, "Mass
/// scaling"). Both raise each gear's polar inertia by the same factor s, so the rigid gears'
/// mesh mode falls to the same frequency.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MassScalingMode {
    /// Every nodal mass and the hub's inertia times s: every natural frequency falls by √s,
    /// the stable step grows by √s.
    Uniform,
    /// Each element's mass raised to one stable step T_g per gear, at which the gear's inertia
    /// is s times its own ([`ExplicitPair::mass_scaling_steps`],
    /// [`ExplicitPair::scale_mass_to_steps`]): the small flank elements and the thin rim layers
    /// that set the step take most of the mass, the large body elements little. The stiffness
    /// scene takes 2.95× fewer steps than with uniform scaling, its answers as close to an
    /// unscaled run's (validation/low-speed).
    #[default]
    TargetStep,
}

/// Which stable step a run's step follows (the case's `fe.time_step`; module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TimeStep {
    /// The pair's own stable step where the contact is, measured as the run goes (power
    /// iteration on bodies and penalty springs together) wherever the closed springs stiffen
    /// and at regular intervals; the step never rises again once lowered. A check that finds
    /// the step above what the state allows sends the run back to the last sample, on at the
    /// lower step; a run that diverges goes back to the sample before the last check that
    /// passed and ends on [`TimeStep::Bound`]'s step. Runs without element damping
    /// (`high_frequency_damping_ratio = 0`) take the bound (module doc).
    #[default]
    Coupled,
    /// The bound that holds for every contact state (the contact springs' worst case, the
    /// bodies' own), fixed for the whole run.
    Bound,
}

/// The teeth each gear needs fine and the tooth pairs that can meet while the driver turns by
/// `driver_rotation` from the pitch-point position: the pairs engaged over the window
/// ([`engagement::engaged_pairs`] with its margin), ascending driver tooth; gear 2 also needs
/// the back-flank partners, the teeth on either side of each drive-flank partner.
pub fn scene_teeth(
    pair: &GearPair,
    driver_rotation: f64,
) -> ([Vec<usize>; 2], Vec<(usize, usize)>) {
    window_teeth(pair, 0.0, driver_rotation.max(0.0))
}

/// [`scene_teeth`] while the driver turns from `from` to `to` (from the pitch-point position).
pub fn window_teeth(pair: &GearPair, from: f64, to: f64) -> ([Vec<usize>; 2], Vec<(usize, usize)>) {
    let engaged = engagement::engaged_pairs(pair, from, to, engagement::ENGAGEMENT_MARGIN);
    let mut tooth_pairs: Vec<(usize, usize)> = engaged.iter().map(|p| p.indices(pair)).collect();
    // Over more than a revolution the same teeth meet again: once each.
    let mut seen = std::collections::HashSet::new();
    tooth_pairs.retain(|p| seen.insert(*p));
    let with_neighbours: Vec<ToothPair> = engaged
        .iter()
        .flat_map(|p| {
            [-1, 0, 1].map(|d| ToothPair {
                driver: p.driver,
                driven: p.driven + d,
            })
        })
        .collect();
    let [fine1, _] = engagement::teeth_of(pair, &engaged);
    let [_, fine2] = engagement::teeth_of(pair, &with_neighbours);
    ([fine1, fine2], tooth_pairs)
}

/// A scene ready to run: the pair model and its time step.
pub struct PreparedScene {
    /// How long the run lasts [s]: the scene's duration, or the longer [`covering_duration`]
    /// of a scene that is to cover a base pitch ([`Scene::cover_pitch`]).
    pub duration: f64,
    /// The scene's own duration as the case gives it [s].
    pub scene_duration: f64,
    pub model: ExplicitPair,
    pub drive: Drive,
    /// Critical step of each body (bore fixed, power iteration) and of the contact springs [s].
    pub dt_bodies: [f64; 2],
    pub dt_contact: f64,
    /// Critical step after the damping reduction [s].
    pub dt_critical: f64,
    /// The step the run starts with, `step_factor` × `dt_critical` [s]: the step of
    /// [`TimeStep::Bound`] throughout, and of [`TimeStep::Coupled`] until its first check.
    pub dt: f64,
    pub step_factor: f64,
    pub time_step: TimeStep,
    /// The paper's L/c_w (eq. 28) and the element-eigenvalue bound, for comparison [s].
    pub dt_paper: f64,
    pub dt_element_bound: f64,
    /// Stiffness-proportional damping coefficient [s].
    pub beta_k: f64,
    /// Mesh dashpot on the driven hub [N m s] and the mesh stiffness it was sized with [N/m].
    pub mesh_damping: f64,
    pub mesh_damping_stiffness: f64,
    /// Free ringing of the mesh mode the ramp leaves, over the static response (module doc).
    pub ramp_ringing: f64,
    /// Time after the ramp for that ringing to decay to [`SETTLED_RINGING`], ln(A/0.005)/(ζ ω_n)
    /// with ω_n = √(k_m R_b2²/I₂) [s] (0 without mesh damping, or when A is below it already).
    pub settling_time: f64,
    /// Period of the (scaled) mesh mode 2π/ω_n [s]: the span of the low-pass over the DTE.
    pub mesh_mode_period: f64,
    pub mass_scaling: MassScaling,
    pub mesh_wall_s: f64,
    pub setup_wall_s: f64,
    /// What a window's model is built from: the flank modifications, the material, the element
    /// sizes and which teeth are fine. `model` is the whole scene's (every tooth that engages
    /// fine): its flank pairs name the history's, its nodes the fingerprint's.
    pub modifications: [FlankModification; 2],
    pub material: ExplicitMaterial,
    pub fine_size: f64,
    pub coarse_size: f64,
    pub fine_teeth: FineTeeth,
    pub tooth_layout: ToothLayout,
    /// The far body of a run on windows: full, or one reduced block per gear cut off at
    /// `far_block_cutoff` times the lowest mode of the fine sectors beside it.
    pub far_body: FarBody,
    pub far_block_cutoff: f64,
    /// Where the run may end before `duration` ([`Scene::stop_when_settled`]).
    pub settled_stop: Option<SettledStop>,
}

/// Ringing of the mesh mode, over the static response, at which a run counts as settled.
pub const SETTLED_RINGING: f64 = 0.005;

/// Free ringing that the ramp of `drive` leaves in an undamped mode `omega` [rad/s], over the
/// static response (module doc): |R(ω)| √(1 + (c ω)²), c = I₂Ω₂/T the spin-up's inertia torque
/// per unit ramp rate over the load (0 for a start at speed), `driven_inertia` I₂,
/// `driven_speed` |Ω₂| after the ramp.
pub fn ramp_ringing(drive: &Drive, omega: f64, driven_inertia: f64, driven_speed: f64) -> f64 {
    let wt = omega * drive.ramp_time;
    let pi2 = std::f64::consts::PI.powi(2);
    let ramp = match drive.ramp {
        Ramp::Linear => (2.0 / wt).min(1.0),
        Ramp::Cosine if wt * wt > 2.0 * pi2 => pi2 / (wt * wt - pi2),
        Ramp::Cosine => 1.0,
    };
    let c = match drive.start {
        Start::Rest if drive.load_torque > 0.0 => driven_inertia * driven_speed / drive.load_torque,
        _ => 0.0,
    };
    ramp * (1.0 + (c * omega).powi(2)).sqrt()
}

/// The highest mesh harmonic a scene's response must keep (the sweeps report five).
pub const KEPT_HARMONIC: usize = 5;

/// Mass scaling of a scene (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct MassScaling {
    /// Each gear's polar inertia times this (1: off): every nodal mass and the hub's inertia
    /// times it ([`MassScalingMode::Uniform`]), or each element's mass raised to its gear's
    /// target step within it ([`MassScalingMode::TargetStep`]).
    pub factor: f64,
    /// The mesh mode with the driver held, f_n = √(k_m R_b2²/I₂)/2π, unscaled and scaled [Hz].
    pub mesh_mode_hz: f64,
    pub scaled_mesh_mode_hz: f64,
    /// The highest mesh harmonic kept, [`KEPT_HARMONIC`] × f_mesh [Hz], and the scaled mode
    /// over it.
    pub highest_harmonic_hz: f64,
    pub scaled_mode_over_harmonic: f64,
    /// Where the mass went: the case's mode, uniform for a run on windows of fine teeth.
    pub mode: MassScalingMode,
    /// [`MassScalingMode::TargetStep`]: each gear's element step T_g its masses are raised to
    /// [s] (the pair's stable step then grows by about min T_g over the unscaled elements'
    /// least step).
    pub target_steps_s: Option<[f64; 2]>,
    /// [`MassScalingMode::TargetStep`]: the least and largest element mass factor of both
    /// gears.
    pub element_factor_range: Option<[f64; 2]>,
}

impl MassScaling {
    /// The factor that puts the mesh mode `mesh_mode_hz` at `margin` × the highest kept
    /// harmonic of `mesh_hz`, or 1 when it is not above that already (or `margin` is None).
    pub fn new(mesh_mode_hz: f64, mesh_hz: f64, margin: Option<f64>) -> Self {
        let highest_harmonic_hz = KEPT_HARMONIC as f64 * mesh_hz;
        let factor = match margin {
            Some(m) if mesh_hz > 0.0 => (mesh_mode_hz / (m * highest_harmonic_hz)).powi(2).max(1.0),
            _ => 1.0,
        };
        let scaled_mesh_mode_hz = mesh_mode_hz / factor.sqrt();
        MassScaling {
            factor,
            mesh_mode_hz,
            scaled_mesh_mode_hz,
            highest_harmonic_hz,
            scaled_mode_over_harmonic: scaled_mesh_mode_hz / highest_harmonic_hz,
            mode: MassScalingMode::Uniform,
            target_steps_s: None,
            element_factor_range: None,
        }
    }

    /// Scales `model`'s masses: each element's to `target_steps_s`
    /// ([`ExplicitPair::scale_mass_to_steps`]), else every mass times `factor` (nothing when it
    /// is 1). Returns the element factors' range of a target step.
    fn apply(&self, model: &mut ExplicitPair) -> Option<[f64; 2]> {
        match self.target_steps_s {
            Some(steps) => {
                let [a, b] = model.scale_mass_to_steps(steps);
                Some([a[0].min(b[0]), a[1].max(b[1])])
            }
            None if self.factor > 1.0 => {
                model.scale_mass(self.factor);
                None
            }
            None => None,
        }
    }
}

/// Meshes the pair (relief `modifications`) for `scene` and assembles it, measures its critical
/// step; sizes the mesh dashpot with `mesh_stiffness`, the pair's mean mesh stiffness [N/m].
/// A scene that is to cover a base pitch ([`Scene::cover_pitch`]) and is too short for it is
/// prepared again for [`covering_duration`]: the teeth that engage depend on how far the
/// driver turns, the settling time on the prepared model.
pub fn prepare(
    pair: &GearPair,
    modifications: &[FlankModification; 2],
    material: ExplicitMaterial,
    scene: &Scene,
    settings: &FeSettings,
    mesh_stiffness: f64,
) -> Result<PreparedScene, FeError> {
    let prepare_for = |duration: f64| {
        let scene = Scene {
            duration,
            ..scene.clone()
        };
        prepare_scene(
            pair,
            modifications,
            material,
            &scene,
            settings,
            mesh_stiffness,
        )
    };
    let mut prepared = prepare_for(scene.duration)?;
    if !scene.cover_pitch {
        prepared.settled_stop = SettledStop::of(&prepared, scene);
        return Ok(prepared);
    }
    // Settling and the low-pass span depend on the masses and the damping, hardly on how far
    // the driver turns (a longer run may mesh another tooth fine): a second lengthening, if
    // any, is a small one.
    for _ in 0..3 {
        let needed = covering_duration(&prepared, scene, settings.output_interval);
        if needed <= prepared.duration {
            break;
        }
        prepared = prepare_for(needed)?;
    }
    prepared.scene_duration = scene.duration;
    prepared.settled_stop = SettledStop::of(&prepared, scene);
    Ok(prepared)
}

/// Where a run whose scene asks for it ([`Scene::stop_when_settled`]) ends before its
/// duration: at the first check ([`SettledStop::CHECK_EVERY_S`]) where the DTE's rms about the
/// mean over the last three stretches of whole mesh periods since `from_s`, r₁, r₂, r₃, has
/// stopped moving, over the record to now and over the records to the
/// [`SettledStop::CHECKS`] − 1 checks before: each third at least `min_third_s` long
/// ([`SettledStop::MIN_THIRD_S`]), the settling drift ([`crate::signal::settling_drift`],
/// Aitken's limit where the change slows) within `drift` ([`SettledStop::DRIFT`]) and the last
/// third's rms within `growth` of the first's ([`SettledStop::GROWTH`]).
///
/// The FE speed sweep's runs use it: near the mesh resonance the double-sided contact builds
/// its response up long after the mesh mode's linear decay, away from it the response has
/// settled within a few milliseconds, and the run's statistics only need the settled part
/// (validation/lumped-twin). A response still growing or decaying by more than `growth`
/// across the record, or whose drift reads above `drift` at any of the checks, runs on; its
/// duration is the longest it runs, and the sweep's own test
/// ([`crate::study::fe_sweep::SETTLED_DRIFT`]) judges what it reached. What no rule on the
/// record so far can see: a change that sets in after the stop (a late bifurcation), or a beat
/// slower than the record whose thirds agree at three checks in a row; a fixed duration has the
/// same blind spot further on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SettledStop {
    /// Where the DTE is judged from [s]: the statistics start (after the ramp's ringing).
    pub from_s: f64,
    /// The mesh frequency [Hz]: the thirds hold whole mesh periods.
    pub mesh_hz: f64,
    /// The shortest third [s], the settling drift and the change of the rms from the first
    /// third to the last within which the run stops.
    pub min_third_s: f64,
    pub drift: f64,
    pub growth: f64,
}

impl SettledStop {
    /// The settling drift below which a run may stop: a third of the sweep's
    /// [`crate::study::fe_sweep::SETTLED_DRIFT`], so that the stopped run passes the sweep's
    /// test with room, and its rms carries at most about 1 % of movement still to come.
    pub const DRIFT: f64 = 0.01;
    /// The change of the rms between the first and the last third a stop allows: an approach
    /// that Aitken's limit calls nearly done (its changes shrinking fast) has little left to
    /// rise, but two thirds apart by more than this are still a build-up or a beat's swing (the
    /// sweep's "growing" is 10 %, [`crate::study::fe_sweep::GROWTH_LIMIT`]). The paper pair at
    /// 5 320 rpm stopped with 3.1 % between its first and last third (validation/performance).
    pub const GROWTH: f64 = 0.05;
    /// The shortest third [s]: with thirds of length T, an approach slower than
    /// [`crate::signal::FLAT_THIRDS`] per third is hidden up to about FLAT_THIRDS·τ/T of the rms
    /// (τ its time constant), so thirds of 6 ms hide below 1 % of approaches up to τ = 20 ms
    /// (the slowest the sweep's runs showed: the paper pair at 5 275 rpm on 0.7 mm flanks,
    /// validation/lumped-twin). With the checks before, a stop thus comes about 21 ms after
    /// the statistics start at the earliest (thirds cut to whole mesh periods).
    pub const MIN_THIRD_S: f64 = 6e-3;
    /// Simulated time between two checks [s], and the checks in a row that must pass: one
    /// reading that happens to agree (a beat's thirds passing through equal values) does not
    /// stop a run.
    pub const CHECK_EVERY_S: f64 = 1e-3;
    pub const CHECKS: usize = 3;

    /// The scene's stop, if it asks for one and turns (a run at rest has no mesh period).
    pub fn of(prepared: &PreparedScene, scene: &Scene) -> Option<Self> {
        let mesh_hz = scene.driver_speed.abs() / prepared.model.pair.gears[0].angular_pitch();
        (scene.stop_when_settled && mesh_hz > 0.0).then(|| SettledStop {
            from_s: statistics_start(prepared, scene),
            mesh_hz,
            min_third_s: Self::MIN_THIRD_S,
            drift: Self::DRIFT,
            growth: Self::GROWTH,
        })
    }

    /// The rms of `dte`'s thirds (samples every `dt`, the first at t = 0) over the record from
    /// `from_s` to its end, where the thirds are long enough; else None.
    pub fn thirds_over(&self, dte: &[f64], dt: f64) -> Option<[f64; 3]> {
        // The first sample as the sweep takes it (`FeDte::window_starts`).
        let start = ((self.from_s / dt).round().max(0.0) as usize).min(dte.len());
        let window = &dte[start..];
        if (window.len() as f64) * dt < 3.0 * self.min_third_s {
            return None;
        }
        let (rms, thirds) = crate::signal::thirds_rms(window, dt, self.mesh_hz)?;
        (thirds[2].len() as f64 * dt >= self.min_third_s - dt).then_some(rms)
    }

    /// Whether the record `dte` reads settled by itself: thirds long enough, the drift within
    /// `drift`, the last third's rms within `growth` of the first's.
    fn reads_settled(&self, dte: &[f64], dt: f64) -> bool {
        self.thirds_over(dte, dt).is_some_and(|r| {
            crate::signal::settling_drift(r) <= self.drift
                && r[0] > 0.0
                && (r[2] / r[0] - 1.0).abs() <= self.growth
        })
    }

    /// Whether a check is due at the sample just recorded (`time`, the record's times): the
    /// first sample at or past each multiple of [`Self::CHECK_EVERY_S`].
    pub fn due(&self, time: &[f64]) -> bool {
        match time {
            [.., before, now] => {
                (now / Self::CHECK_EVERY_S).floor() > (before / Self::CHECK_EVERY_S).floor()
            }
            _ => false,
        }
    }

    /// Whether a run whose record is `dte` may stop now: the record to now and the records to
    /// the [`Self::CHECKS`] − 1 checks before each read settled.
    pub fn settled(&self, dte: &[f64], dt: f64) -> bool {
        let apart = (Self::CHECK_EVERY_S / dt).round() as usize;
        (0..Self::CHECKS)
            .all(|k| k * apart < dte.len() && self.reads_settled(&dte[..dte.len() - k * apart], dt))
    }
}

/// The shortest run of `scene` whose statistics window ([`statistics_start`]) holds one base
/// pitch of the driver and the low-pass's span after the ramp and the mesh mode's settling:
/// ramp + settling + mesh period + mesh-mode period, and two recorded samples for the bins'
/// edges [s]. The scene's speed after the ramp sets the mesh period; a scene at rest needs
/// only the settling.
pub fn covering_duration(prepared: &PreparedScene, scene: &Scene, output_interval: f64) -> f64 {
    let settled = scene.ramp_time + prepared.settling_time;
    match pitch_window(prepared, scene) {
        Some(window) => settled + window + 2.0 * output_interval,
        None => settled,
    }
}

/// What a statistics window needs to cover a base pitch after the ramp: one mesh period (a
/// driver pitch at the scene's speed) and the low-pass's span, one mesh-mode period [s]; None
/// for a scene at rest.
fn pitch_window(prepared: &PreparedScene, scene: &Scene) -> Option<f64> {
    (scene.driver_speed > 0.0).then(|| {
        prepared.model.pair.gears[0].angular_pitch() / scene.driver_speed
            + prepared.mesh_mode_period
    })
}

fn prepare_scene(
    pair: &GearPair,
    modifications: &[FlankModification; 2],
    material: ExplicitMaterial,
    scene: &Scene,
    settings: &FeSettings,
    mesh_stiffness: f64,
) -> Result<PreparedScene, FeError> {
    let started = Instant::now();
    let drive = Drive {
        driver_speed: scene.driver_speed,
        load_torque: scene.torque,
        ramp_time: scene.ramp_time,
        ramp: scene.ramp,
        start: scene.start,
        start_rotation: 0.0,
    };
    let (rotation, _, _) = drive.driver_motion(scene.duration);
    let rotation = rotation - drive.start_rotation;
    let (fine, tooth_pairs) = scene_teeth(pair, rotation);
    let spec = |g: usize| crate::mesh::MeshSpec {
        fine_size: settings.fine_size,
        coarse_size: settings.coarse_size,
        fine_teeth: fine[g].clone(),
        layout: settings.tooth_layout,
    };
    let meshes = [
        mesh_gear(&pair.gears[0], &modifications[0], &spec(0)),
        mesh_gear(&pair.gears[1], &modifications[1], &spec(1)),
    ];
    let mesh_wall_s = started.elapsed().as_secs_f64();
    let mut model = ExplicitPair::new(
        pair,
        meshes,
        material,
        tooth_pairs,
        scene.friction,
        settings.penalty_factor,
    )?;
    let rb2 = pair.gears[1].base_radius;
    // The mesh mode with the driver held, ω_n = √(k_m R_b2²/I₂) [rad/s], of a model's masses.
    let mesh_mode_of =
        |model: &ExplicitPair| (mesh_stiffness * rb2 * rb2 / model.driven_inertia()).sqrt();
    let mesh_mode_hz = mesh_mode_of(&model) / std::f64::consts::TAU;
    let mesh_hz = scene.driver_speed / pair.gears[0].angular_pitch();
    let margin = settings
        .mass_scaling_margin
        .map(|m| scene.mass_scaling_margin.unwrap_or(m));
    let windows = WindowPlan::new(
        settings.fine_teeth,
        pair,
        &drive,
        scene.duration,
        settings.output_interval,
    );
    let mut mass_scaling = MassScaling::new(mesh_mode_hz, mesh_hz, margin);
    // A run on windows changes which teeth are fine at every switch, and a target step's mass
    // sits mostly in the fine teeth: it would come and go with them. Such scenes (300 rpm and
    // long low-speed scenes) scale uniformly.
    if windows.is_none() || mass_scaling.factor <= 1.0 {
        mass_scaling.mode = settings.mass_scaling_mode;
    }
    if mass_scaling.factor > 1.0 && mass_scaling.mode == MassScalingMode::TargetStep {
        mass_scaling.target_steps_s = Some(model.mass_scaling_steps(mass_scaling.factor));
    }
    mass_scaling.element_factor_range = mass_scaling.apply(&mut model);
    // Each gear's inertia is s times its own either way: the scaled model's mesh mode.
    mass_scaling.scaled_mesh_mode_hz = mesh_mode_of(&model) / std::f64::consts::TAU;
    mass_scaling.scaled_mode_over_harmonic =
        mass_scaling.scaled_mesh_mode_hz / mass_scaling.highest_harmonic_hz;
    let body_steps = |model: &ExplicitPair| -> [f64; 2] {
        std::array::from_fn(|g| {
            let fixed: Vec<bool> = model.free[g].iter().map(|f| !f).collect();
            critical_step(&model.bodies[g], &fixed, 200)
        })
    };
    let mut dt_bodies = body_steps(&model);
    // A run on windows steps meshes with fine and coarse sectors side by side, which the
    // scene's mesh may not have (at 3000 rpm every tooth is fine): the first window's bodies
    // bound the step too (the later ones are the same mesh, turned by whole pitches).
    if let Some(plan) = windows {
        let first = window_model_of(
            &model,
            modifications,
            material,
            (
                [settings.fine_size, settings.coarse_size],
                settings.tooth_layout,
            ),
            &mass_scaling,
            &plan.window(pair, 0, 0.0, &[]),
        )?;
        let window_steps = body_steps(&first);
        for (scene_step, window_step) in dt_bodies.iter_mut().zip(window_steps) {
            *scene_step = scene_step.min(window_step);
        }
    }
    let dt_contact = model.contact_critical_step();
    let dt_undamped = dt_bodies[0].min(dt_bodies[1]).min(dt_contact);
    let omega_max = 2.0 / dt_undamped;
    let zeta = settings.high_frequency_damping_ratio;
    let beta_k = 2.0 * zeta / omega_max;
    let dt_critical = dt_undamped * ((1.0 + zeta * zeta).sqrt() - zeta);
    // Both bounds come from the material's density: with uniformly scaled masses they grow by
    // √s; with a target step each element's by √sₑ, the Irons bound to the least T_g.
    let (dt_paper, dt_element_bound) = match mass_scaling.target_steps_s {
        None => {
            let density_scale = mass_scaling.factor.sqrt();
            let least = |f: fn(&ExplicitBody) -> f64| {
                density_scale * f(&model.bodies[0]).min(f(&model.bodies[1]))
            };
            (
                least(ExplicitBody::paper_critical_step),
                least(ExplicitBody::element_eigen_critical_step),
            )
        }
        Some(steps) => {
            let paper = (0..2)
                .flat_map(|g| {
                    let factors = model.element_mass_factors(g, steps[g]);
                    model.bodies[g]
                        .paper_critical_steps()
                        .into_iter()
                        .zip(factors)
                        .map(|(dt, s)| dt * s.sqrt())
                        .collect::<Vec<_>>()
                })
                .fold(f64::INFINITY, f64::min);
            (paper, steps[0].min(steps[1]))
        }
    };
    // Mesh dashpot: ζ of the driven gear turning against the mesh spring (driver prescribed),
    // k_t = k_m R_b2², c_t = 2ζ√(k_t I₂).
    let mesh_damping_stiffness = mesh_stiffness;
    let mesh_damping = 2.0
        * settings.mesh_damping_ratio
        * (mesh_damping_stiffness * rb2 * rb2 * model.driven_inertia()).sqrt();
    let mesh_mode = mesh_mode_of(&model);
    let driven_speed = model.kinematic_hub_rotation(drive.driver_speed).abs();
    let ringing = ramp_ringing(&drive, mesh_mode, model.driven_inertia(), driven_speed);
    let settling_time = if settings.mesh_damping_ratio > 0.0 && ringing > SETTLED_RINGING {
        (ringing / SETTLED_RINGING).ln() / (settings.mesh_damping_ratio * mesh_mode)
    } else {
        0.0
    };
    Ok(PreparedScene {
        duration: scene.duration,
        scene_duration: scene.duration,
        dt: settings.step_factor * dt_critical,
        step_factor: settings.step_factor,
        // Undamped, the measured step is marginal where points close and open (module doc).
        time_step: if zeta > 0.0 {
            settings.time_step
        } else {
            TimeStep::Bound
        },
        ramp_ringing: ringing,
        settling_time,
        mesh_mode_period: std::f64::consts::TAU / mesh_mode,
        mass_scaling,
        mesh_damping,
        mesh_damping_stiffness,
        model,
        drive,
        dt_bodies,
        dt_contact,
        dt_critical,
        dt_paper,
        dt_element_bound,
        beta_k,
        mesh_wall_s,
        setup_wall_s: started.elapsed().as_secs_f64(),
        modifications: *modifications,
        material,
        fine_size: settings.fine_size,
        coarse_size: settings.coarse_size,
        fine_teeth: settings.fine_teeth,
        tooth_layout: settings.tooth_layout,
        far_body: settings.far_body,
        far_block_cutoff: settings.far_block_cutoff,
        settled_stop: None,
    })
}

/// Where the statistics of a run of `duration` start: after the ramp and the settling time of
/// the mesh mode, but early enough to leave one mesh period (a base pitch of the driver) and
/// the low-pass's span (one mesh-mode period, half of it lost at the record's end) when the run has
/// them — so the stiffness from the DTE covers a whole base pitch — and never before the end of
/// the ramp.
pub fn statistics_start(prepared: &PreparedScene, scene: &Scene) -> f64 {
    let ramp = scene.ramp_time;
    let settled = ramp + prepared.settling_time;
    match pitch_window(prepared, scene) {
        Some(needed) => settled.min((prepared.duration - needed).max(ramp)),
        None => settled.min(prepared.duration),
    }
}

/// Recorded time histories of a run: one sample per output interval.
///
/// The signals (rotation, DTE, speeds, forces) are means over the output interval that ends at
/// `time` — the step-by-step signal decimated with a boxcar anti-alias filter (gain
/// |sinc(π f Δt_out)|: 0.98 at 0.1/Δt_out, 0.64 at 0.5/Δt_out, nulls at multiples of
/// 1/Δt_out, first sidelobe 0.21), so content above the output rate folds into the recorded
/// band attenuated; they lag `time` by half an interval. The
/// energy terms, contact counts and the deepest penetration (the largest over the interval) are
/// taken at `time`. The first sample is the initial state.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct History {
    pub time: Vec<f64>,
    /// Driver rotation θ₁ [rad].
    pub driver_rotation: Vec<f64>,
    /// Angular DTE of the driven gear: its rotation minus the kinematic one (positive: lags) [rad].
    pub dte: Vec<f64>,
    /// Driven-gear speed (magnitude) and its kinematic value (z₁/z₂)θ̇₁ [rad/s].
    pub driven_speed: Vec<f64>,
    pub theoretical_speed: Vec<f64>,
    /// Contact force on the driven gear: radial (along the centre line, from gear 1 to gear 2)
    /// and circumferential (perpendicular, the load-transmitting direction) components and the
    /// resultant [N] (the paper's F_y, F_x and F_C, eqs. 32–33).
    pub force_radial: Vec<f64>,
    pub force_circumferential: Vec<f64>,
    pub force_total: Vec<f64>,
    /// Mesh force along the line of action W = −M_c/R_b2 [N]: the moment of the contact forces
    /// on the driven gear over its base radius (the force that turns it; with friction the
    /// resultant also has a component across the line of action).
    pub mesh_force: Vec<f64>,
    /// Contact force magnitude per flank pair [N] (index as `ExplicitPair::flank_pairs`).
    pub pair_forces: Vec<Vec<f64>>,
    pub energy: Vec<PairEnergy>,
    pub active_contacts: Vec<usize>,
    pub max_penetration: Vec<f64>,
}

impl History {
    /// Every f64 series (the flank pairs' forces included), for what is done to all alike.
    fn float_series(&mut self) -> impl Iterator<Item = &mut Vec<f64>> {
        [
            &mut self.time,
            &mut self.driver_rotation,
            &mut self.dte,
            &mut self.driven_speed,
            &mut self.theoretical_speed,
            &mut self.force_radial,
            &mut self.force_circumferential,
            &mut self.force_total,
            &mut self.mesh_force,
            &mut self.max_penetration,
        ]
        .into_iter()
        .chain(self.pair_forces.iter_mut())
    }

    /// The first `samples` samples only (a run going back to an earlier state).
    fn truncate(&mut self, samples: usize) {
        self.float_series().for_each(|s| s.truncate(samples));
        self.energy.truncate(samples);
        self.active_contacts.truncate(samples);
    }

    /// An empty history with room for `samples` samples of `pairs` flank pairs.
    pub fn with_capacity(samples: usize, pairs: usize) -> Self {
        let series = || Vec::with_capacity(samples);
        History {
            time: series(),
            driver_rotation: series(),
            dte: series(),
            driven_speed: series(),
            theoretical_speed: series(),
            force_radial: series(),
            force_circumferential: series(),
            force_total: series(),
            mesh_force: series(),
            pair_forces: (0..pairs).map(|_| series()).collect(),
            energy: Vec::with_capacity(samples),
            active_contacts: Vec::with_capacity(samples),
            max_penetration: series(),
        }
    }

    /// Room for `samples` samples in all (a resumed history read back at its length).
    fn reserve_to(&mut self, samples: usize) {
        let more = samples.saturating_sub(self.time.len());
        self.float_series().for_each(|s| s.reserve_exact(more));
        self.energy.reserve_exact(more);
        self.active_contacts.reserve_exact(more);
    }
}

/// Sums of the averaged signals over the steps of one output interval.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
struct IntervalSums {
    steps: usize,
    /// Driver rotation, DTE, driven speed, theoretical speed, radial, circumferential and
    /// total force, mesh force.
    signals: [f64; 8],
    pair_forces: Vec<f64>,
    max_penetration: f64,
}

impl IntervalSums {
    /// Adds one step: `pair_forces[k]` is the history's flank pair `index[k]` of `pairs`.
    fn add(
        &mut self,
        signals: [f64; 8],
        pair_forces: &[f64],
        index: &[usize],
        pairs: usize,
        penetration: f64,
    ) {
        self.steps += 1;
        for (sum, v) in self.signals.iter_mut().zip(signals) {
            *sum += v;
        }
        self.pair_forces.resize(pairs, 0.0);
        for (&k, v) in index.iter().zip(pair_forces) {
            self.pair_forces[k] += v;
        }
        self.max_penetration = self.max_penetration.max(penetration);
    }
}

/// How a run ended.
#[derive(Debug, Clone)]
pub struct RunOutcome {
    pub history: History,
    pub steps: usize,
    pub wall_s: f64,
    /// Why the run stopped early, if it did.
    pub diverged: Option<String>,
    /// Where the run stopped on a stop request ([`crate::interrupt`]), if it did.
    pub interrupted: Option<String>,
    /// Where the run ended before its duration because its DTE had settled
    /// ([`SettledStop`]) [s], if it did.
    pub settled_at_s: Option<f64>,
    pub final_energy: PairEnergy,
    /// Where the steps' wall time went, phase by phase.
    pub phase_wall: PhaseWall,
    /// The pair's stable step where the contact was, at every check: [`COUPLED_CHECKS`]
    /// instants spread over a [`TimeStep::Bound`] run (those with points in contact), and
    /// wherever the springs stiffened and about [`COUPLED_RECHECKS`] times besides in a
    /// [`TimeStep::Coupled`] run.
    pub coupled_steps: Vec<CoupledStep>,
    /// The step's changes ([`TimeStep::Coupled`]; empty for a run on one step).
    pub step_changes: Vec<StepChange>,
    /// Why a [`TimeStep::Coupled`] run went back to the bound's step, if it did.
    pub fallback: Option<String>,
    /// Where an interrupted run can go on from ([`run`]'s `resume`).
    pub checkpoint: Option<Box<RunCheckpoint>>,
    /// Σ elements × steps over the run's meshes (a [`FineTeeth::Window`] run's change from
    /// window to window).
    pub element_steps: f64,
    /// The windows the run went through (0: the scene's own mesh throughout).
    pub windows: usize,
    /// Far blocks built, and found built for a window of their pattern (`fe.far_body =
    /// "reduced"`; a resumed run's count from its resumption).
    pub far_blocks_built: usize,
    pub far_blocks_reused: usize,
}

/// A change of a run's step.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StepChange {
    /// From this instant on [s].
    pub time_s: f64,
    pub dt_s: f64,
    /// Steps per recorded sample from then on.
    pub steps_per_sample: usize,
}

/// Where a [`TimeStep::Coupled`] run stands: its current step and what it has measured.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct StepControl {
    dt: f64,
    /// Steps per recorded sample at `dt`.
    every: usize,
    /// The step the current `dt` started after (samples are counted from it).
    offset: usize,
    total_steps: usize,
    /// The recorded samples' spacing, the same at every step: `every` × `dt` [s].
    sample_interval: f64,
    /// `step_factor` × the smallest stable step checked so far [s].
    lowest_allowed: Option<f64>,
    last_check: usize,
    /// The highest closed springs' own frequency bound at a check [rad/s].
    checked_spring: f64,
    changes: Vec<StepChange>,
    fallback: Option<String>,
}

impl StepControl {
    /// A run starting on `dt` for `total_steps` steps, a sample every `every`.
    fn new(dt: f64, total_steps: usize, every: usize) -> Self {
        StepControl {
            dt,
            every,
            offset: 0,
            total_steps,
            sample_interval: dt * every as f64,
            lowest_allowed: None,
            last_check: 0,
            checked_spring: 0.0,
            changes: Vec::new(),
            fallback: None,
        }
    }

    /// After `step` at `time`, a check that allows the step `allowed`: the run goes on at the
    /// largest step that divides the sample interval and is at most the smallest step allowed
    /// so far, and at least the bound's `bound_dt` (so the step rises once, at the first check,
    /// and only falls after). The run then ends at the first step at or past `duration`, as on
    /// one step.
    fn lower_to(&mut self, bound_dt: f64, allowed: f64, step: usize, time: f64, duration: f64) {
        let lowest = self.lowest_allowed.map_or(allowed, |l| l.min(allowed));
        self.lowest_allowed = Some(lowest);
        // A little below what is allowed, so that a state a hair stiffer does not send the run
        // back again.
        let lowest = lowest * (1.0 - STEP_HEADROOM);
        let every = ((self.sample_interval / lowest).ceil() as usize).max(1);
        let dt = self.sample_interval / every as f64;
        let (dt, every) = if dt > bound_dt {
            (dt, every)
        } else {
            (bound_dt, self.bound_every(bound_dt))
        };
        if dt != self.dt {
            self.set(dt, every, step, time, duration);
        }
    }

    /// Steps per sample at the bound's step, as [`step_counts`] has them.
    fn bound_every(&self, bound_dt: f64) -> usize {
        ((self.sample_interval / bound_dt).round() as usize).max(1)
    }

    /// Back to the bound's step `bound_dt` after `step` at `time`, for `reason`.
    fn fall_back(&mut self, bound_dt: f64, step: usize, time: f64, duration: f64, reason: String) {
        let every = self.bound_every(bound_dt);
        self.set(bound_dt, every, step, time, duration);
        self.fallback = Some(reason);
    }

    fn set(&mut self, dt: f64, every: usize, step: usize, time: f64, duration: f64) {
        // A change at the same instant replaces the one made there before (a run sent back to
        // that sample).
        if self.changes.last().is_some_and(|c| c.time_s == time) {
            self.changes.pop();
        }
        self.dt = dt;
        self.every = every;
        self.offset = step;
        self.total_steps = step + (((duration - time) / dt).ceil().max(1.0) as usize);
        self.changes.push(StepChange {
            time_s: time,
            dt_s: dt,
            steps_per_sample: every,
        });
    }
}

/// The state of a [`TimeStep::Coupled`] run at a recorded sample.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct Snapshot {
    step: usize,
    state: PairState,
    integrator: IntegratorCheckpoint,
    samples: usize,
    checks: usize,
    control: StepControl,
}

impl Snapshot {
    fn at(
        step: usize,
        state: &PairState,
        integrator: &PairIntegrator,
        history: &History,
        checks: &[CoupledStep],
        control: &StepControl,
    ) -> Self {
        Snapshot {
            step,
            state: state.clone(),
            integrator: integrator.checkpoint(),
            samples: history.time.len(),
            checks: checks.len(),
            control: control.clone(),
        }
    }

    /// Puts the run back to this state; returns its step and step control.
    fn restore(
        self,
        integrator: &mut PairIntegrator,
        state: &mut PairState,
        history: &mut History,
        checks: &mut Vec<CoupledStep>,
    ) -> (usize, StepControl) {
        *state = self.state;
        integrator
            .restore(self.integrator)
            .expect("a checkpoint of the same integrator fits it");
        history.truncate(self.samples);
        checks.truncate(self.checks);
        (self.step, self.control)
    }

    /// This snapshot moved to `step`, reusing its buffers.
    fn update(
        &mut self,
        step: usize,
        state: &PairState,
        integrator: &PairIntegrator,
        history: &History,
        checks: &[CoupledStep],
        control: &StepControl,
    ) {
        self.step = step;
        self.state.clone_from(state);
        self.integrator = integrator.checkpoint();
        self.samples = history.time.len();
        self.checks = checks.len();
        self.control.clone_from(control);
    }
}

/// How far below the step its states allow a [`TimeStep::Coupled`] run steps.
pub const STEP_HEADROOM: f64 = 0.01;

/// A [`TimeStep::Coupled`] run re-checks its step at a sample after every 1/this of the run's
/// steps on the bound's step (so somewhat less often on its longer step, and not out of
/// contact), besides where the contact stiffens.
pub const COUPLED_RECHECKS: usize = 64;

/// A [`TimeStep::Coupled`] run checks its step at once when the closed springs' own frequency
/// bound ([`crate::explicit::pair::ContactOutput::stiffest_spring_omega`]) rises this far above
/// its highest at a check.
pub const SPRING_RISE: f64 = 0.02;

/// An interrupted run between two steps: the pair's and the integrator's state and the open
/// output interval; with the history recorded so far (kept apart: the run's result holds it),
/// [`run`] goes on from it to the same history, bit for bit, as the run that was not
/// interrupted (tests/interrupt.rs).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct RunCheckpoint {
    /// [`scene_fingerprint`] of the scene it was made on: another scene is refused.
    pub fingerprint: u64,
    pub total_steps: usize,
    /// The step the run goes on with.
    pub next_step: usize,
    /// Wall time spent before the interruption [s].
    pub wall_s: f64,
    state: PairState,
    integrator: IntegratorCheckpoint,
    sums: IntervalSums,
    coupled_steps: Vec<CoupledStep>,
    /// None in a checkpoint of an older geardyn.
    #[serde(default)]
    control: Option<StepControl>,
    /// The state at the last sample of a [`TimeStep::Coupled`] run, and at the sample before
    /// its last check that passed.
    #[serde(default)]
    snapshot: Option<Snapshot>,
    #[serde(default)]
    trusted: Option<Snapshot>,
    /// The window of a [`FineTeeth::Window`] run the state belongs to (None: the scene's mesh).
    #[serde(default)]
    pub window: Option<Window>,
    /// Σ elements × steps so far.
    #[serde(default)]
    element_steps: f64,
    /// Where the run's far blocks were built (`fe.far_body = "reduced"`): a resumed run builds
    /// the same ones, which its blocks' states belong to.
    #[serde(default)]
    far_blocks: Vec<BlockSeed>,
}

impl RunCheckpoint {
    /// This checkpoint of a run on `old` (at a recorded sample) carried to `new`, the model of
    /// `window` (`transfers` from `old`'s nodes to `new`'s). The snapshots of the old mesh
    /// are dropped: a run sent back goes no further back than the switch.
    fn remeshed(
        self,
        (old, driver_motion): (&ExplicitPair, [f64; 3]),
        new: &ExplicitPair,
        transfers: &[NodeTransfer; 2],
        window: Window,
    ) -> Result<Self, String> {
        let integrator = self.integrator.remeshed(old, new, transfers)?;
        // The old far blocks' nodes as the blocks have them, for the transfer.
        let state = old.expanded(&self.state, driver_motion);
        Ok(RunCheckpoint {
            state: state.remeshed(transfers),
            integrator,
            snapshot: None,
            trusted: None,
            window: Some(window),
            ..self
        })
    }

    /// The run up to this checkpoint as an outcome that stopped for `reason` (a state that
    /// could not be carried to the next window's mesh): its history is kept, as a diverged
    /// run's is.
    fn stopped(self, history: History, reason: String) -> RunOutcome {
        let control = self.control.unwrap_or_else(|| StepControl::new(0.0, 0, 1));
        RunOutcome {
            history,
            steps: self.integrator.steps(),
            wall_s: self.wall_s,
            diverged: Some(reason),
            interrupted: None,
            settled_at_s: None,
            final_energy: self.integrator.energy(),
            phase_wall: self.integrator.phase_wall(),
            coupled_steps: self.coupled_steps,
            step_changes: control.changes,
            fallback: control.fallback,
            checkpoint: None,
            element_steps: self.element_steps,
            windows: self.window.map_or(0, |w| w.index + 1),
            far_blocks_built: 0,
            far_blocks_reused: 0,
        }
    }
}

/// The driver pitches one window of a [`FineTeeth::Window`] run spans.
pub const WINDOW_PITCHES: f64 = 1.0;

/// The teeth on either side of a window's engaging teeth that are fine too (not in contact):
/// the rim's and the neighbouring teeth's dynamics near the mesh at the scene's resolution. On
/// the 3000 rpm scene the DTE lines at 2.6 and 18.8 kHz move by −7.5 % and −9.1 % against the
/// run with every engaging tooth fine without them, by −1.2 % and −3.9 % with one
/// (validation/performance), for 5 % more elements.
pub const WINDOW_NEIGHBOURS: usize = 1;

/// A scene that turns the driver through fewer pitches than this runs on one mesh: its windows
/// would save a tooth or two per gear.
pub const MIN_WINDOWED_PITCHES: f64 = 4.0;

/// One window of a [`FineTeeth::Window`] run: its fine teeth and tooth pairs.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Window {
    pub index: usize,
    /// Driver rotation from the pitch-point position where the window starts, and past which
    /// the run moves on to the next window at its next recorded sample (infinite in the
    /// last) [rad].
    pub start_rotation: f64,
    pub end_rotation: f64,
    pub fine_teeth: [Vec<usize>; 2],
    pub tooth_pairs: Vec<(usize, usize)>,
}

/// The windows of a [`FineTeeth::Window`] run.
struct WindowPlan {
    /// The driver's angular pitch [rad].
    pitch: f64,
    /// How far the driver turns in the scene [rad].
    scene_rotation: f64,
    /// How far past a window's end its teeth must reach: the switch comes at the first
    /// recorded sample past the end, so two output intervals at full speed [rad].
    pad: f64,
}

impl WindowPlan {
    /// The plan of a run of `prepared` over `duration`, None when it runs on the scene's mesh.
    fn of(prepared: &PreparedScene, duration: f64, output_interval: f64) -> Option<Self> {
        // Masses scaled to a target step belong to the scene's one mesh ([`prepare`] decided
        // it there: a run on windows scales uniformly).
        if prepared.mass_scaling.target_steps_s.is_some() {
            return None;
        }
        Self::new(
            prepared.fine_teeth,
            &prepared.model.pair,
            &prepared.drive,
            duration,
            output_interval,
        )
    }

    /// [`Self::of`] from the setting, the pair and the drive.
    fn new(
        fine_teeth: FineTeeth,
        pair: &GearPair,
        drive: &Drive,
        duration: f64,
        output_interval: f64,
    ) -> Option<Self> {
        if fine_teeth != FineTeeth::Window {
            return None;
        }
        let pitch = pair.gears[0].angular_pitch();
        let (rotation, _, _) = drive.driver_motion(duration);
        let scene_rotation = rotation - drive.start_rotation;
        (scene_rotation >= MIN_WINDOWED_PITCHES * pitch).then(|| WindowPlan {
            pitch,
            scene_rotation,
            pad: 2.0 * drive.driver_speed.abs() * output_interval,
        })
    }

    /// Window `index`, from driver rotation `from`: the teeth that engage until its end (and
    /// the pad), and the tooth pairs `kept` (in contact or near it at the switch) wherever
    /// they are, so that no tooth leaves the fine mesh while it can still touch; and
    /// [`WINDOW_NEIGHBOURS`] teeth on either side of those fine as well.
    fn window(&self, pair: &GearPair, index: usize, from: f64, kept: &[(usize, usize)]) -> Window {
        let end = from + WINDOW_PITCHES * self.pitch;
        let (end_rotation, to) = if end + self.pad >= self.scene_rotation {
            (f64::INFINITY, self.scene_rotation)
        } else {
            (end, end + self.pad)
        };
        let (mut fine_teeth, mut tooth_pairs) = window_teeth(pair, from, to.max(from));
        let z2 = pair.gears[1].teeth() as usize;
        for &(t1, t2) in kept {
            if !tooth_pairs.contains(&(t1, t2)) {
                tooth_pairs.push((t1, t2));
                fine_teeth[0].push(t1);
                // The drive partner and the teeth on either side (the back flanks), as
                // [`window_teeth`] has them.
                fine_teeth[1].extend([(t2 + z2 - 1) % z2, t2, (t2 + 1) % z2]);
            }
        }
        for (g, teeth) in fine_teeth.iter_mut().enumerate() {
            let z = pair.gears[g].teeth() as usize;
            let own = teeth.clone();
            for t in own {
                for d in 1..=WINDOW_NEIGHBOURS {
                    teeth.extend([(t + d) % z, (t + z - d) % z]);
                }
            }
            teeth.sort_unstable();
            teeth.dedup();
        }
        Window {
            index,
            start_rotation: from,
            end_rotation,
            fine_teeth,
            tooth_pairs,
        }
    }
}

/// An empty cache of the scene's far blocks: its cutoff, its hubs' rate bounds.
fn block_cache(prepared: &PreparedScene) -> BlockCache {
    let gears = &prepared.model.pair.gears;
    let teeth = [gears[0].teeth() as usize, gears[1].teeth() as usize];
    let bounds = crate::explicit::far::rate_bounds(prepared.drive.driver_speed, teeth);
    BlockCache::new(prepared.far_block_cutoff, bounds)
}

/// The pair model of `window`: the scene's, meshed fine on the window's teeth only; its far
/// bodies reduced if the scene says so, the blocks from `cache` where they fit.
fn window_model(
    prepared: &PreparedScene,
    window: &Window,
    cache: &mut BlockCache,
) -> Result<ExplicitPair, FeError> {
    let mut model = full_window_model(prepared, window)?;
    if prepared.far_body == FarBody::Reduced {
        model.reduce_far_bodies(cache)?;
    }
    Ok(model)
}

/// [`window_model`] with its bodies in full.
fn full_window_model(prepared: &PreparedScene, window: &Window) -> Result<ExplicitPair, FeError> {
    window_model_of(
        &prepared.model,
        &prepared.modifications,
        prepared.material,
        (
            [prepared.fine_size, prepared.coarse_size],
            prepared.tooth_layout,
        ),
        &prepared.mass_scaling,
        window,
    )
}

/// [`window_model`] of the scene's model `scene` (its pair, friction and penalty), meshed with
/// `modifications` at element sizes `sizes` (fine, coarse) [m] and `layout`, masses scaled as the scene's
/// (`mass_scaling`: the same factor, or the same target step).
fn window_model_of(
    scene: &ExplicitPair,
    modifications: &[FlankModification; 2],
    material: ExplicitMaterial,
    (sizes, layout): ([f64; 2], ToothLayout),
    mass_scaling: &MassScaling,
    window: &Window,
) -> Result<ExplicitPair, FeError> {
    let pair = &scene.pair;
    let spec = |g: usize| crate::mesh::MeshSpec {
        fine_size: sizes[0],
        coarse_size: sizes[1],
        fine_teeth: window.fine_teeth[g].clone(),
        layout,
    };
    let meshes = [
        mesh_gear(&pair.gears[0], &modifications[0], &spec(0)),
        mesh_gear(&pair.gears[1], &modifications[1], &spec(1)),
    ];
    let mut model = ExplicitPair::new(
        pair,
        meshes,
        material,
        window.tooth_pairs.clone(),
        scene.friction,
        scene.penalty_factor,
    )?;
    mass_scaling.apply(&mut model);
    Ok(model)
}

/// The elements a run of `prepared` over `duration` steps at its start: its first window's
/// (a [`FineTeeth::Window`] run; the later windows hold about as many), else the scene's. For
/// the cost estimate before a run; counted without meshing ([`crate::mesh::mesh_size`]).
pub fn run_elements(prepared: &PreparedScene, duration: f64) -> usize {
    let Some(plan) = WindowPlan::of(prepared, duration, 0.0) else {
        return prepared.model.elements();
    };
    let pair = &prepared.model.pair;
    let window = plan.window(pair, 0, 0.0, &[]);
    (0..2)
        .map(|g| {
            crate::mesh::mesh_size(
                &pair.gears[g],
                &prepared.modifications[g],
                &crate::mesh::MeshSpec {
                    fine_size: prepared.fine_size,
                    coarse_size: prepared.coarse_size,
                    fine_teeth: window.fine_teeth[g].clone(),
                    layout: prepared.tooth_layout,
                },
            )
            .elements
        })
        .sum()
}

/// Where a run leaves a window: the checkpoint it goes on from, the history so far and the
/// tooth pairs in contact or near it.
type Switch = (RunCheckpoint, History, Vec<(usize, usize)>);

/// How [`run_window`] ended.
enum WindowEnd {
    Done(Box<RunOutcome>),
    /// At a recorded sample past the window's end: where the run goes on from, the history so
    /// far and the tooth pairs in contact or near it.
    Switch(Box<Switch>),
}

/// Where a running scene keeps checkpoints as it goes: every `every_s` seconds on its clock
/// (wall time in use; checked every [`KEEP_CHECK_STEPS`] steps, on one clock across the run's
/// windows) `keep` gets one, with the history so far, so a process killed outright (SIGKILL, a
/// batch job's time limit) can go on from the last one.
pub struct Keeping<'a> {
    pub every_s: f64,
    pub keep: &'a mut dyn FnMut(&RunCheckpoint, &History),
    /// The clock `every_s` is counted on, in its unit (seconds of wall time in use,
    /// [`Keeping::every`]), read once at the run's start, at each check and after each
    /// checkpoint kept; a test gives a counter, which makes when a checkpoint is kept
    /// deterministic.
    pub clock: Box<dyn FnMut() -> f64 + 'a>,
}

impl<'a> Keeping<'a> {
    /// A checkpoint to `keep` every `every_s` seconds of wall time.
    pub fn every(every_s: f64, keep: &'a mut dyn FnMut(&RunCheckpoint, &History)) -> Self {
        let start = Instant::now();
        Keeping {
            every_s,
            keep,
            clock: Box::new(move || start.elapsed().as_secs_f64()),
        }
    }
}

/// Steps between two looks at the clock for [`Keeping`].
pub const KEEP_CHECK_STEPS: usize = 64;

/// The far body a run of `prepared` over `duration` really has: its reduced blocks act on
/// runs on windows of fine teeth only, a run on the scene's one mesh keeps its bodies full.
pub fn run_far_body(prepared: &PreparedScene, duration: f64, output_interval: f64) -> FarBody {
    match WindowPlan::of(prepared, duration, output_interval) {
        Some(_) => prepared.far_body,
        None => FarBody::Full,
    }
}

/// A fingerprint of everything a run's steps depend on: the step, the step count and output
/// stride, the drive, the damping, the friction, and every body's reference nodes, masses and
/// flank penalties (FNV-1a over their bits). Two scenes that differ in any of them — another
/// relief, friction coefficient, speed, mesh or duration — differ here.
pub fn scene_fingerprint(prepared: &PreparedScene, duration: f64, output_interval: f64) -> u64 {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for b in bytes {
            hash = (hash ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3);
        }
    };
    let model = &prepared.model;
    let (total_steps, every) = step_counts(prepared, duration, output_interval);
    for x in [
        prepared.dt,
        prepared.beta_k,
        prepared.mesh_damping,
        model.friction,
    ] {
        eat(&x.to_bits().to_le_bytes());
    }
    eat(&(total_steps as u64).to_le_bytes());
    eat(&(every as u64).to_le_bytes());
    eat(format!("{:?}", prepared.time_step).as_bytes());
    // A run that may stop early ends elsewhere than one that may not; runs without the stop
    // hash as before.
    if let Some(stop) = &prepared.settled_stop {
        eat(b"settled stop");
        let rule = [
            stop.from_s,
            stop.mesh_hz,
            stop.min_third_s,
            stop.drift,
            stop.growth,
            SettledStop::CHECK_EVERY_S,
            SettledStop::CHECKS as f64,
        ];
        for x in rule {
            eat(&x.to_bits().to_le_bytes());
        }
    }
    // Blocks change the run's answers; a full far body hashes as before. The blocks' modal
    // state means what their build makes of it: its order and Coriolis tolerance (since
    // 2026-12-06's second basis: modes ascending, couplings to ε) and what the cutoff
    // multiplies (the third: the fine sectors' lowest mode, not the block's) go in too.
    // Of the far body the run has: a run on one mesh hashes as before whatever the setting.
    let far_body = run_far_body(prepared, duration, output_interval);
    if far_body != FarBody::Full {
        eat(format!("{far_body:?}").as_bytes());
        eat(&prepared.far_block_cutoff.to_bits().to_le_bytes());
        eat(b"far block basis 3");
        eat(&crate::explicit::reduced::CORIOLIS_TOLERANCE
            .to_bits()
            .to_le_bytes());
    }
    // Debug prints every f64 in its shortest exact form.
    eat(format!("{:?}", prepared.drive).as_bytes());
    for body in &model.bodies {
        for p in &body.reference {
            eat(&p.x.to_bits().to_le_bytes());
            eat(&p.y.to_bits().to_le_bytes());
        }
        for m in &body.mass {
            eat(&m.to_bits().to_le_bytes());
        }
    }
    for flank in &model.flanks {
        for k in flank.penalty.iter().chain(&flank.line_penalty) {
            eat(&k.to_bits().to_le_bytes());
        }
    }
    hash
}

/// How many times a [`TimeStep::Bound`] run measures the stable step of the pair in its
/// current contact state (for the record).
pub const COUPLED_CHECKS: usize = 8;

/// [`PairIntegrator::coupled_critical_step`] at one instant of a run.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CoupledStep {
    pub time_s: f64,
    /// Gauss points in contact.
    pub contacts: usize,
    /// 2/ω_max of bodies and penalty springs, undamped [s].
    pub dt_critical_undamped_s: f64,
    /// The same reduced for the stiffness damping as the run's step was
    /// (Δt_cr (√(1 + ζ²) − ζ)), comparable with `dt_critical_s` and `dt_s` [s].
    pub dt_critical_s: f64,
}

/// The integrator of `prepared` and the scene's initial state, ready for its first step.
fn start(prepared: &PreparedScene) -> (PairIntegrator<'_>, PairState) {
    start_on(prepared, &prepared.model)
}

/// [`start`] on `model`, the scene's or a window's.
fn start_on<'a>(
    prepared: &PreparedScene,
    model: &'a ExplicitPair,
) -> (PairIntegrator<'a>, PairState) {
    let mut integrator = PairIntegrator::new(model, prepared.drive, prepared.dt, prepared.beta_k);
    integrator.mesh_damping = prepared.mesh_damping;
    integrator.last_contact.track_springs = prepared.time_step == TimeStep::Coupled;
    let mut state = model.initial_state(&prepared.drive);
    integrator.initialize(&mut state);
    (integrator, state)
}

/// Wall time per element and step of `prepared` on this machine and thread count [s]: `steps`
/// steps from the scene's initial state, timed (the first of them warm the caches and are
/// included, so the figure errs high).
pub fn measure_step_cost(prepared: &PreparedScene, steps: usize) -> f64 {
    let model = &prepared.model;
    let (mut integrator, mut state) = start(prepared);
    let started = Instant::now();
    for _ in 0..steps {
        if integrator.step(&mut state).is_err() {
            break;
        }
    }
    started.elapsed().as_secs_f64() / (steps.max(1) as f64 * model.elements().max(1) as f64)
}

/// The steps [`run`] takes over `duration`, and how many steps one output interval holds.
fn step_counts(prepared: &PreparedScene, duration: f64, output_interval: f64) -> (usize, usize) {
    let total_steps = (duration / prepared.dt).ceil() as usize;
    let every = ((output_interval / prepared.dt).round() as usize).max(1);
    (total_steps, every)
}

/// Samples [`run`] records over `duration`: the initial state, one per output interval and the
/// last step.
pub fn recorded_samples(prepared: &PreparedScene, duration: f64, output_interval: f64) -> usize {
    let (total_steps, every) = step_counts(prepared, duration, output_interval);
    total_steps / every + 2
}

/// The memory [`run`] adds to the prepared scene [bytes]: the history, reserved up front for
/// every sample (time, eight signals, the flank pairs' forces, the energies, the active contact
/// count and the penetration), and per node of both bodies the integrator's arrays (position,
/// velocity, acceleration, internal, contact and previous contact force, and the velocities'
/// copy for the contact, on two DOFs; a search stamp and flag) and those of the coupled stable-step check (eight more per DOF:
/// [`PairIntegrator::coupled_critical_step`]; three more with reduced far bodies, its state
/// expanded). The far blocks' own matrices are not counted (a few MB).
pub fn run_memory(prepared: &PreparedScene, duration: f64, output_interval: f64) -> MemoryEstimate {
    let samples = recorded_samples(prepared, duration, output_interval) as f64;
    let pairs = prepared.model.flank_pairs.len();
    let per_sample =
        (9 + pairs) * 8 + std::mem::size_of::<PairEnergy>() + std::mem::size_of::<usize>() + 8;
    let nodes: usize = prepared
        .model
        .bodies
        .iter()
        .map(|b| b.reference.len())
        .sum();
    let nodes = nodes as f64;
    MemoryEstimate::part("history", samples * per_sample as f64)
        .and(MemoryEstimate::part(
            "integrator state",
            nodes * (7.0 * 2.0 * 8.0 + 9.0),
        ))
        .and(MemoryEstimate::part(
            "stable-step check",
            // With reduced far bodies, a copy of the state with their nodes expanded besides.
            nodes
                * match run_far_body(prepared, duration, output_interval) {
                    FarBody::Full => 8.0,
                    FarBody::Reduced => 11.0,
                }
                * 2.0
                * 8.0,
        ))
        .and(MemoryEstimate::part(
            "step snapshots",
            // Two states kept (position, velocity, acceleration) with the integrator's
            // contact forces, on a run on the pair's own step.
            if prepared.time_step == TimeStep::Coupled {
                2.0 * nodes * 5.0 * 2.0 * 8.0
            } else {
                0.0
            },
        ))
}

/// Integrates the scene for `duration` seconds, from its start or from `resume` (a checkpoint
/// of an interrupted run of the same scene); `progress` sees the fraction done (called about
/// every 0.5 % of the run). On divergence, or on a stop request ([`crate::interrupt`]), the
/// history up to the last recorded sample is kept; a stop request also leaves a checkpoint.
/// A [`FineTeeth::Window`] run goes from window to window, each on its own mesh (module doc).
pub fn run(
    prepared: &PreparedScene,
    duration: f64,
    output_interval: f64,
    resume: Option<(RunCheckpoint, History)>,
    mut keeping: Option<Keeping>,
    progress: &mut dyn FnMut(f64),
) -> Result<RunOutcome, FeError> {
    if let Some((checkpoint, _)) = &resume {
        if checkpoint.fingerprint != scene_fingerprint(prepared, duration, output_interval) {
            return Err(FeError::Resume(
                "it was made on another scene (its step, duration, drive, damping, friction \
                 or mesh differ): resume with the scene, case file, --set and flags of the \
                 interrupted run (a checkpoint from before 2026-12-06 was meshed with the \
                 graded tooth layout, then the default: add --set fe.tooth_layout=graded; \
                 one of a run on windows from before 2026-12-06's reduced far body default \
                 had full bodies: add --set fe.far_body=full)"
                    .to_string(),
            ));
        }
    }
    // One clock for the whole run: a window shorter than `every_s` must not restart it, or a
    // run on windows would keep no checkpoint after its first.
    let mut last_kept = keeping.as_mut().map_or(0.0, |k| (k.clock)());
    let plan = WindowPlan::of(prepared, duration, output_interval);
    let Some(plan) = plan else {
        if resume.as_ref().is_some_and(|(c, _)| c.window.is_some()) {
            return Err(FeError::Resume(
                "it was made by a run on windows of fine teeth (fe.fine_teeth = \"window\"), \
                 this run meshes the whole scene fine"
                    .to_string(),
            ));
        }
        let from = resume.map(|(c, h)| (c, h, false));
        return match run_window(
            prepared,
            (&prepared.model, &block_cache(prepared)),
            None,
            duration,
            output_interval,
            from,
            (&mut keeping, &mut last_kept),
            progress,
        )? {
            WindowEnd::Done(outcome) => Ok(*outcome),
            WindowEnd::Switch(_) => unreachable!("a run on the scene's mesh has no windows"),
        };
    };
    let pair = &prepared.model.pair;
    let mut window = match &resume {
        Some((checkpoint, _)) => checkpoint.window.clone().ok_or_else(|| {
            FeError::Resume(
                "it was made by a run on the whole scene's fine teeth (fe.fine_teeth = \
                 \"scene\"), this run goes window by window"
                    .to_string(),
            )
        })?,
        None => plan.window(pair, 0, 0.0, &[]),
    };
    // One far block per gear and pattern of fine teeth, for the whole run; a resumed run's the
    // interrupted run's, built again where they were.
    let mut cache = block_cache(prepared);
    if let Some((checkpoint, _)) = &resume {
        for seed in &checkpoint.far_blocks {
            let mut fine_teeth = window.fine_teeth.clone();
            fine_teeth[seed.gear].clone_from(&seed.fine_teeth);
            let seeded = Window {
                fine_teeth,
                tooth_pairs: Vec::new(),
                ..window.clone()
            };
            full_window_model(prepared, &seeded)?.seed_far_block(seed.gear, &mut cache)?;
        }
    }
    let mut model = window_model(prepared, &window, &mut cache)?;
    let mut from = resume.map(|(c, h)| (c, h, false));
    loop {
        match run_window(
            prepared,
            (&model, &cache),
            Some(&window),
            duration,
            output_interval,
            from.take(),
            (&mut keeping, &mut last_kept),
            progress,
        )? {
            WindowEnd::Done(outcome) => return Ok(*outcome),
            WindowEnd::Switch(switch) => {
                let (checkpoint, history, near) = *switch;
                let (theta, _, _) = prepared.drive.driver_motion(checkpoint.state.time);
                let next = plan.window(
                    pair,
                    window.index + 1,
                    theta - prepared.drive.start_rotation,
                    &near,
                );
                let next_model = window_model(prepared, &next, &mut cache)?;
                let carried = NodeTransfer::between(&model.meshes[0], &next_model.meshes[0])
                    .and_then(|t0| {
                        let t1 = NodeTransfer::between(&model.meshes[1], &next_model.meshes[1])?;
                        let (theta, rate, accel) =
                            prepared.drive.driver_motion(checkpoint.state.time);
                        checkpoint.clone().remeshed(
                            (&model, [theta, rate, accel]),
                            &next_model,
                            &[t0, t1],
                            next.clone(),
                        )
                    });
                let carried = match carried {
                    Ok(carried) => carried,
                    Err(cause) => {
                        let at = history.time.last().copied().unwrap_or(0.0);
                        return Ok(checkpoint.stopped(
                            history,
                            format!(
                                "the run could not go on to its next window's mesh at t = \
                                 {at:.6e} s ({cause}); the results up to there are kept. Run \
                                 the scene with fe.fine_teeth = \"scene\""
                            ),
                        ));
                    }
                };
                model = next_model;
                window = next;
                from = Some((carried, history, true));
            }
        }
    }
}

/// [`run`] on one mesh: the scene's (`window` None) or a window's, until the end of the run or
/// the first recorded sample past the window's end. `from`: a checkpoint to go on from, with
/// the history so far and whether it was just carried to this mesh (its accelerations and
/// energy then come from this mesh first: [`PairIntegrator::settle_remeshed`]).
#[allow(clippy::too_many_arguments)]
fn run_window(
    prepared: &PreparedScene,
    (model, cache): (&ExplicitPair, &BlockCache),
    window: Option<&Window>,
    duration: f64,
    output_interval: f64,
    from: Option<(RunCheckpoint, History, bool)>,
    (keeping, last_kept): (&mut Option<Keeping>, &mut f64),
    progress: &mut dyn FnMut(f64),
) -> Result<WindowEnd, FeError> {
    let (total_steps, every) = step_counts(prepared, duration, output_interval);
    let report_every = (total_steps / 200).max(1);
    // Reserved for every sample: no doubling on growth, and the size run_memory announced.
    let samples = recorded_samples(prepared, duration, output_interval);
    // The history's flank pairs are the scene's; this mesh's pair k is the history's index[k].
    let pairs = prepared.model.flank_pairs.len();
    let index: Vec<usize> = model
        .flank_pairs
        .iter()
        .map(|fp| {
            prepared
                .model
                .flank_pairs
                .iter()
                .position(|o| o.teeth == fp.teeth && o.drive == fp.drive)
                .expect("a window's flank pairs are among the scene's")
        })
        .collect();
    let mut remeshed = false;
    let mut element_steps_before = 0.0;
    let (mut integrator, mut state, mut history, first_step, wall_before, resumed) = match from {
        None => {
            let (integrator, state) = start_on(prepared, model);
            let history = History::with_capacity(samples, pairs);
            (integrator, state, history, 1, 0.0, None)
        }
        Some((checkpoint, mut history, carried)) => {
            remeshed = carried;
            element_steps_before = checkpoint.element_steps;
            let fits = checkpoint
                .state
                .x
                .iter()
                .zip(&model.bodies)
                .all(|(x, body)| x.len() == 2 * body.reference.len())
                && history.pair_forces.len() == pairs
                // A far block's state of this mesh's block (one just carried is projected).
                && (0..2).all(|g| match (&model.far[g], &checkpoint.state.blocks[g]) {
                    (Some(far), Some(block)) => block.eta.len() == far.block.block.dofs(),
                    (Some(_), None) => carried,
                    (None, block) => block.is_none(),
                });
            if !fits {
                return Err(FeError::Resume(
                    "its state does not fit this mesh".to_string(),
                ));
            }
            let Some(control) = checkpoint.control else {
                return Err(FeError::Resume(
                    "it holds no step control (made by an older geardyn): run the scene anew"
                        .to_string(),
                ));
            };
            let mut integrator =
                PairIntegrator::new(model, prepared.drive, control.dt, prepared.beta_k);
            integrator.mesh_damping = prepared.mesh_damping;
            integrator
                .restore(checkpoint.integrator)
                .map_err(FeError::Resume)?;
            integrator.last_contact.track_springs = prepared.time_step == TimeStep::Coupled;
            let mut state = checkpoint.state;
            if carried {
                integrator.settle_remeshed(&mut state);
            }
            history.reserve_to(samples);
            (
                integrator,
                state,
                history,
                checkpoint.next_step,
                checkpoint.wall_s,
                Some((
                    checkpoint.sums,
                    checkpoint.coupled_steps,
                    control,
                    checkpoint.snapshot,
                    checkpoint.trusted,
                )),
            )
        }
    };
    let ratio = model.pair.gears[0].teeth() as f64 / model.pair.gears[1].teeth() as f64;
    let teeth = model.pair.gears.each_ref().map(|g| g.teeth() as usize);
    let rb2 = model.pair.gears[1].base_radius;
    let started = Instant::now();
    let mut diverged = None;
    let mut interrupted = None;
    let mut settled_at_s = None;
    // The signals at the integrator's current state: driver rotation, DTE, driven speed, its
    // kinematic value, radial, circumferential and total contact force, mesh force.
    let signals = |integrator: &PairIntegrator, state: &PairState| {
        let (theta, rate, _) = prepared.drive.driver_motion(state.time);
        let contact = &integrator.last_contact;
        let f = contact.force_on_driven;
        [
            theta,
            state.hub[0] - model.kinematic_hub_rotation(theta),
            -state.hub[1],
            ratio * rate,
            f.x,
            f.y,
            f.norm(),
            -contact.moment_on_driven / rb2,
        ]
    };
    let record = |history: &mut History,
                  integrator: &PairIntegrator,
                  state: &PairState,
                  sums: &IntervalSums| {
        let n = sums.steps as f64;
        let mean = |k: usize| sums.signals[k] / n;
        history.time.push(state.time);
        history.driver_rotation.push(mean(0));
        history.dte.push(mean(1));
        history.driven_speed.push(mean(2));
        history.theoretical_speed.push(mean(3));
        history.force_radial.push(mean(4));
        history.force_circumferential.push(mean(5));
        history.force_total.push(mean(6));
        history.mesh_force.push(mean(7));
        for (k, series) in history.pair_forces.iter_mut().enumerate() {
            series.push(sums.pair_forces.get(k).copied().unwrap_or(0.0) / n);
        }
        history.energy.push(integrator.energy);
        history.active_contacts.push(integrator.last_contact.active);
        history.max_penetration.push(sums.max_penetration);
    };
    let (mut sums, mut coupled_steps, mut control, mut snapshot, mut trusted) = match resumed {
        Some(open) => open,
        None => {
            let mut sums = IntervalSums::default();
            sums.add(
                signals(&integrator, &state),
                &integrator.last_contact.pair_forces,
                &index,
                pairs,
                integrator.last_contact.max_penetration,
            );
            record(&mut history, &integrator, &state, &sums);
            (
                IntervalSums::default(),
                Vec::new(),
                StepControl::new(prepared.dt, total_steps, every),
                None,
                None,
            )
        }
    };
    let steps_before = integrator.steps;
    if remeshed {
        // The switch is where a run of this mesh goes back to, if it must.
        snapshot = Some(Snapshot::at(
            first_step - 1,
            &state,
            &integrator,
            &history,
            &coupled_steps,
            &control,
        ));
        trusted = None;
    }
    // The damping reduction of the step, as `prepare` applied it.
    let damping_reduction = prepared.dt_critical
        / prepared.dt_bodies[0]
            .min(prepared.dt_bodies[1])
            .min(prepared.dt_contact);
    let check_every = (total_steps / COUPLED_CHECKS).max(1);
    // The regular re-check of a coupled run's step, besides those where the contact changes.
    let recheck_every = (total_steps / COUPLED_RECHECKS).max(every);
    let adaptive = prepared.time_step == TimeStep::Coupled;
    // `snapshot`: the state at the last sample, where a check that fails sends the run back;
    // `trusted`: the sample before the last check that passed, where a divergence does.
    let mut stopped_before = None;
    let fingerprint = scene_fingerprint(prepared, duration, output_interval);
    // The one constructor of a checkpoint: the kept ones and the stop request's.
    let checkpoint_at = |next_step: usize,
                         wall_s: f64,
                         state: &PairState,
                         integrator: &PairIntegrator,
                         sums: &IntervalSums,
                         coupled_steps: &[CoupledStep],
                         control: &StepControl,
                         snapshot: &Option<Snapshot>,
                         trusted: &Option<Snapshot>| RunCheckpoint {
        fingerprint,
        total_steps: control.total_steps,
        next_step,
        wall_s,
        state: state.clone(),
        integrator: integrator.checkpoint(),
        sums: sums.clone(),
        coupled_steps: coupled_steps.to_vec(),
        control: Some(control.clone()),
        snapshot: snapshot.clone(),
        trusted: trusted.clone(),
        window: window.cloned(),
        element_steps: element_steps_before
            + (integrator.steps as f64 - steps_before as f64) * model.stepped_elements() as f64,
        far_blocks: cache.seeds(teeth),
    };
    let mut step = first_step;
    while step <= control.total_steps {
        if crate::interrupt::stop_requested() {
            interrupted = Some(format!(
                "interrupted at t = {:.6e} s (step {} of {}); the results up to t = {:.6e} s are kept",
                state.time,
                step - 1,
                control.total_steps,
                history.time.last().copied().unwrap_or(0.0)
            ));
            stopped_before = Some(step);
            break;
        }
        let recording = (step - control.offset) % control.every == 0 || step == control.total_steps;
        let result = integrator.step(&mut state).and_then(|()| {
            if recording {
                integrator.update_energy(&state)
            } else {
                Ok(())
            }
        });
        if let Err(cause) = result {
            let back = trusted.take().or_else(|| snapshot.take());
            if let Some(back) = back.filter(|_| control.dt > prepared.dt) {
                // A state the raised step does not hold: from the sample before the last check
                // that passed (the last sample may already carry the instability's growth; the
                // last sample if no check passed yet), on the bound's step.
                snapshot = None;
                (step, control) = back.restore(
                    &mut integrator,
                    &mut state,
                    &mut history,
                    &mut coupled_steps,
                );
                control.fall_back(
                    prepared.dt,
                    step,
                    state.time,
                    duration,
                    format!("the run diverged at the raised step ({cause})"),
                );
                integrator.dt = control.dt;
                sums = IntervalSums::default();
                step += 1;
                continue;
            }
            let remedy = if prepared.dt > prepared.dt_critical {
                format!(
                    "The time step {:.4e} s is above the stable step {:.4e} s; use fe.step_factor \
                     below 1 (default 0.9)",
                    prepared.dt, prepared.dt_critical
                )
            } else {
                format!(
                    "The time step {:.4e} s is {:.2} of the estimated stable step {:.4e} s, so a \
                     contact state stiffer than the estimate's bound set in: lower fe.step_factor \
                     (e.g. 0.6) or fe.penalty_factor",
                    prepared.dt,
                    prepared.dt / prepared.dt_critical,
                    prepared.dt_critical
                )
            };
            diverged = Some(format!(
                "the explicit run diverged at t = {:.6e} s (step {step}): {cause}. {remedy}. The \
                 results up to t = {:.6e} s are kept",
                state.time,
                history.time.last().copied().unwrap_or(0.0)
            ));
            break;
        }
        // Not a divergence: the reduced far blocks' model no longer holds (no lower step helps).
        if let Err(reason) = integrator.far_rates_hold(&state) {
            diverged = Some(format!(
                "the explicit run stopped at t = {:.6e} s (step {step}): {reason}. The results up \
                 to t = {:.6e} s are kept",
                state.time,
                history.time.last().copied().unwrap_or(0.0)
            ));
            break;
        }
        sums.add(
            signals(&integrator, &state),
            &integrator.last_contact.pair_forces,
            &index,
            pairs,
            integrator.last_contact.max_penetration,
        );
        if recording {
            record(&mut history, &integrator, &state, &sums);
            sums = IntervalSums::default();
        }
        let spring = integrator.last_contact.stiffest_spring_omega;
        let in_contact = integrator.last_contact.active > 0;
        let due = if adaptive && control.fallback.is_none() {
            // The pair's own step is measured where the contact may have stiffened: closed
            // springs stiffer than at any check so far (at once), or a while since the last
            // check (at a sample).
            in_contact
                && (spring > (1.0 + SPRING_RISE) * control.checked_spring
                    || recording && step - control.last_check >= recheck_every)
        } else {
            step % check_every == 0 && in_contact
        };
        if due {
            // 100 iterations: converged to 1e-4 on the 3000 rpm scene in mesh (by 50).
            let undamped = integrator.coupled_critical_step(&state, 100);
            let critical = undamped * damping_reduction;
            coupled_steps.push(CoupledStep {
                time_s: state.time,
                contacts: integrator.last_contact.active,
                dt_critical_undamped_s: undamped,
                dt_critical_s: critical,
            });
            control.last_check = step;
            control.checked_spring = control.checked_spring.max(spring);
            let passed = !(adaptive
                && control.dt > prepared.dt
                && control.dt > prepared.step_factor * critical);
            if adaptive && passed {
                trusted.clone_from(&snapshot);
            }
            let allowed = prepared.step_factor * critical;
            control.lowest_allowed =
                Some(control.lowest_allowed.map_or(allowed, |l| l.min(allowed)));
            if adaptive && control.dt > prepared.dt && control.dt > allowed {
                // This state holds less than the step taken: back to the last sample and on
                // from there at the step it allows.
                if let Some(back) = snapshot.take() {
                    let lowest = control.lowest_allowed;
                    let checked_spring = control.checked_spring;
                    let check = coupled_steps.last().copied();
                    (step, control) = back.restore(
                        &mut integrator,
                        &mut state,
                        &mut history,
                        &mut coupled_steps,
                    );
                    // The check that sent the run back stays on record.
                    coupled_steps.extend(check);
                    sums = IntervalSums::default();
                    // What was measured stays known.
                    control.checked_spring = checked_spring;
                    control.last_check = step;
                    control.lower_to(
                        prepared.dt,
                        lowest.unwrap_or(allowed),
                        step,
                        state.time,
                        duration,
                    );
                    integrator.dt = control.dt;
                    snapshot = Some(Snapshot::at(
                        step,
                        &state,
                        &integrator,
                        &history,
                        &coupled_steps,
                        &control,
                    ));
                    step += 1;
                    continue;
                }
            }
        }
        if adaptive && control.fallback.is_none() && recording && step < control.total_steps {
            // Step changes only at a sample, so that the samples keep their spacing and a
            // return here loses no open interval.
            if let Some(lowest) = control.lowest_allowed {
                control.lower_to(prepared.dt, lowest, step, state.time, duration);
                integrator.dt = control.dt;
            }
            match snapshot.as_mut() {
                Some(kept) => kept.update(
                    step,
                    &state,
                    &integrator,
                    &history,
                    &coupled_steps,
                    &control,
                ),
                None => {
                    snapshot = Some(Snapshot::at(
                        step,
                        &state,
                        &integrator,
                        &history,
                        &coupled_steps,
                        &control,
                    ))
                }
            }
        }
        // After the step's checks: a sample the coupled step's check sends the run back from
        // is not one to stop at.
        if let Some(stop) = &prepared.settled_stop {
            if recording && step < control.total_steps && stop.due(&history.time) {
                let dt = state.time / (history.time.len() - 1) as f64;
                if stop.settled(&history.dte, dt) {
                    settled_at_s = Some(state.time);
                    break;
                }
            }
        }
        if step % report_every == 0 {
            progress(step as f64 / control.total_steps as f64);
        }
        // Before a kept checkpoint: one kept at the switching step would resume on the old
        // window's mesh and switch a sample late.
        if let Some(window) = window {
            if recording && step < control.total_steps {
                let (theta, _, _) = prepared.drive.driver_motion(state.time);
                if theta - prepared.drive.start_rotation >= window.end_rotation {
                    let checkpoint = checkpoint_at(
                        step + 1,
                        wall_before + started.elapsed().as_secs_f64(),
                        &state,
                        &integrator,
                        &sums,
                        &coupled_steps,
                        &control,
                        &snapshot,
                        &trusted,
                    );
                    // The flank pairs near enough to be searched (within a quarter module)
                    // or in contact: a tooth that has left the path of contact can still
                    // strike its back flank (at the 3000 rpm scene's ramp end 1.35 pitches
                    // past its pitch point, 405 N), so it stays fine until it is clear.
                    let contact = &integrator.last_contact;
                    let near = contact
                        .pair_forces
                        .iter()
                        .zip(&contact.searched)
                        .enumerate()
                        .filter(|(_, (f, searched))| **f > 0.0 || **searched)
                        .map(|(k, _)| model.tooth_pairs[k / 2])
                        .collect::<Vec<_>>();
                    return Ok(WindowEnd::Switch(Box::new((checkpoint, history, near))));
                }
            }
        }
        if let Some(keeping) = keeping.as_mut() {
            if step % KEEP_CHECK_STEPS == 0
                && step < control.total_steps
                && (keeping.clock)() - *last_kept >= keeping.every_s
            {
                let checkpoint = checkpoint_at(
                    step + 1,
                    wall_before + started.elapsed().as_secs_f64(),
                    &state,
                    &integrator,
                    &sums,
                    &coupled_steps,
                    &control,
                    &snapshot,
                    &trusted,
                );
                (keeping.keep)(&checkpoint, &history);
                *last_kept = (keeping.clock)();
            }
        }
        step += 1;
    }
    let wall_s = wall_before + started.elapsed().as_secs_f64();
    let checkpoint = stopped_before.map(|next_step| {
        Box::new(checkpoint_at(
            next_step,
            wall_s,
            &state,
            &integrator,
            &sums,
            &coupled_steps,
            &control,
            &snapshot,
            &trusted,
        ))
    });
    // In floating point: a run sent back to a snapshot taken before it resumed has fewer
    // steps than it started with.
    let element_steps = element_steps_before
        + (integrator.steps as f64 - steps_before as f64) * model.stepped_elements() as f64;
    Ok(WindowEnd::Done(Box::new(RunOutcome {
        element_steps,
        windows: window.map_or(0, |w| w.index + 1),
        far_blocks_built: cache.built,
        far_blocks_reused: cache.reused,
        history,
        steps: integrator.steps,
        wall_s,
        diverged,
        interrupted,
        settled_at_s,
        final_energy: integrator.energy,
        phase_wall: integrator.phase_wall,
        coupled_steps,
        step_changes: control.changes,
        fallback: control.fallback,
        checkpoint,
    })))
}

/// Bins per base pitch of the stiffness from the DTE, centred on the LTCA's 64 positions.
pub const STIFFNESS_BINS: usize = 64;

/// Statistics of the DTE over the window after the ramp, and the stiffness from it.
#[derive(Debug, Clone, serde::Serialize)]
pub struct DteAnalysis {
    /// Statistics window [s] and its first sample.
    pub window: (f64, f64),
    #[serde(skip)]
    pub window_start: usize,
    pub dte_mean_rad: f64,
    pub dte_min_rad: f64,
    pub dte_max_rad: f64,
    pub dte_peak_to_peak_rad: f64,
    /// k(θ) = ΣW/Σ(R_b2 θ_DTE − e) of the recorded samples per bin, with the unloaded TE e(θ)
    /// at the bin centres; bins the window does not reach are interpolated. None without a
    /// bin.
    #[serde(skip)]
    pub stiffness: Option<MeshStiffness>,
    /// k per bin where the window reached it (bins centred on j·pitch/[`STIFFNESS_BINS`] of
    /// driver rotation from the pitch-point position).
    #[serde(skip)]
    pub stiffness_bins: Vec<Option<f64>>,
    /// The low-pass of the DTE statistics.
    #[serde(skip)]
    pub filter: Option<Lowpass>,
    /// Mean of the k(θ) table, and T/(mean θ_DTE R_b2²) (the paper's k0).
    pub mesh_stiffness_mean_n_per_m: f64,
    pub mesh_stiffness_from_mean_dte_n_per_m: f64,
    /// Fraction of the bins of one base pitch the window reaches.
    pub pitch_coverage: f64,
    /// The quasi-static part of the DTE (see [`Lowpass`]).
    pub lowpass: Option<LowpassDte>,
    /// The static TE the run's own k(θ) gives at the load (see [`static_te`]).
    pub static_te: Option<StaticTe>,
}

/// Statistics of a static transmission error over the bins of a base pitch [rad].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct StaticTe {
    pub mean_rad: f64,
    pub max_rad: f64,
    pub min_rad: f64,
    pub peak_to_peak_rad: f64,
    /// Bins it covers (of [`STIFFNESS_BINS`]).
    pub bins: usize,
}

/// The static TE that a stiffness per bin gives under `torque`: the driven gear's rotation
/// under the mesh force of static equilibrium W = T/R_b2 (W is the contact moment over R_b2, so
/// this holds with friction too),
/// ```text
/// φ_s(θ) = (T/(R_b2 k(θ)) + e(θ)) / R_b2
/// ```
/// over the bins that have a k; `unloaded_te` e [m] as in [`analyse_dte`]. From the FE's k(θ)
/// it is the FE's quasi-static DTE, free of the mesh mode's ringing and of any filter (a
/// mass-scaled run keeps its mean; its peak-to-peak within 1.5 % at margin 3, module doc).
pub fn static_te(
    pair: &GearPair,
    torque: f64,
    stiffness_bins: &[Option<f64>],
    unloaded_te: &PeriodicTable,
) -> Option<StaticTe> {
    let rb2 = pair.gears[1].base_radius;
    let pitch = pair.gears[0].angular_pitch();
    let te: Vec<f64> = stiffness_bins
        .iter()
        .enumerate()
        .filter_map(|(b, k)| {
            let e = unloaded_te.at(b as f64 / stiffness_bins.len() as f64 * pitch);
            k.map(|k| (torque / (rb2 * k) + e) / rb2)
        })
        .collect();
    if te.is_empty() {
        return None;
    }
    let (min, max) = crate::signal::extremes(&te);
    Some(StaticTe {
        mean_rad: te.iter().sum::<f64>() / te.len() as f64,
        max_rad: max,
        min_rad: min,
        peak_to_peak_rad: max - min,
        bins: te.len(),
    })
}

/// Statistics of the low-passed DTE over the window.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct LowpassDte {
    pub period_s: f64,
    pub mean_rad: f64,
    pub max_rad: f64,
    pub min_rad: f64,
    pub peak_to_peak_rad: f64,
}

/// A centred moving average over one period of the mesh mode, T_n = 2π/ω_n with
/// ω_n = √(k_t/I₂) (k_t the torsional mesh stiffness, I₂ the driven gear): a sinc filter with
/// its first null at f_n, which removes the mode's free ringing and keeps what changes slower.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lowpass {
    pub period_s: f64,
    /// Samples averaged.
    pub width: usize,
}

impl Lowpass {
    /// The filter for torsional stiffness `k_t` [N·m/rad] and inertia `inertia` over samples
    /// `sample` [s] apart; None unless both are positive.
    pub fn new(k_t: f64, inertia: f64, sample: f64) -> Option<Self> {
        if !(k_t > 0.0 && inertia > 0.0 && sample > 0.0) {
            return None;
        }
        Self::with_period(std::f64::consts::TAU / (k_t / inertia).sqrt(), sample)
    }

    /// The moving average over `period_s` of samples `sample` [s] apart; None unless both are
    /// positive.
    pub fn with_period(period_s: f64, sample: f64) -> Option<Self> {
        (period_s > 0.0 && sample > 0.0).then(|| Lowpass {
            period_s,
            width: ((period_s / sample).round() as usize).max(1),
        })
    }

    /// The averages centred on samples `first..` of `values`, as far as a whole span fits:
    /// (index of the first average, the averages; `values.len()` and none when no span fits).
    pub fn apply(&self, values: &[f64], first: usize) -> (usize, Vec<f64>) {
        let (width, half, n) = (self.width, self.width / 2, values.len());
        let first = first.max(half);
        if first + width > n + half {
            return (n, Vec::new());
        }
        let mut prefix = vec![0.0; n + 1];
        for (i, v) in values.iter().enumerate() {
            prefix[i + 1] = prefix[i] + v;
        }
        let averages = (first..n + half + 1 - width)
            .map(|i| (prefix[i - half + width] - prefix[i - half]) / width as f64)
            .collect();
        (first, averages)
    }
}

/// ΣW/Σδ per bin of driver rotation (bins centred on j·pitch/[`STIFFNESS_BINS`]); None where no
/// sample falls, or where ΣW or Σδ is not positive (teeth apart, or the back flanks carrying
/// the load in a transient: no drive-side stiffness to read).
pub fn binned_stiffness(
    pitch: f64,
    rotations: &[f64],
    mesh_force: &[f64],
    deflection: &[f64],
) -> Vec<Option<f64>> {
    let mut sums = vec![(0.0, 0.0); STIFFNESS_BINS];
    for ((theta, w), delta) in rotations.iter().zip(mesh_force).zip(deflection) {
        let bin = ((theta / pitch).rem_euclid(1.0) * STIFFNESS_BINS as f64).round() as usize
            % STIFFNESS_BINS;
        sums[bin].0 += w;
        sums[bin].1 += delta;
    }
    sums.iter()
        .map(|(w, d)| (*d > 0.0 && *w > 0.0).then(|| w / d))
        .collect()
}

/// Mean over mean − 1 and the worst |a/b − 1| of the bins both have, and their count; None
/// without one.
pub fn bin_difference(a: &[Option<f64>], b: &[Option<f64>]) -> Option<(f64, f64, usize)> {
    let both: Vec<(f64, f64)> = a
        .iter()
        .zip(b)
        .filter_map(|(x, y)| Some(((*x)?, (*y)?)))
        .collect();
    if both.is_empty() {
        return None;
    }
    let n = both.len() as f64;
    let mean = |f: fn(&(f64, f64)) -> f64| both.iter().map(f).sum::<f64>() / n;
    let worst = both
        .iter()
        .map(|(x, y)| (x / y - 1.0).abs())
        .fold(0.0, f64::max);
    Some((mean(|p| p.0) / mean(|p| p.1) - 1.0, worst, both.len()))
}

/// The table `own` where `other` has a bin too (None elsewhere).
pub fn common_bins(own: &[Option<f64>], other: &[Option<f64>]) -> Vec<Option<f64>> {
    own.iter().zip(other).map(|(x, y)| y.and(*x)).collect()
}

/// The bins both tables have: (driver rotation of the bin centre from the pitch-point position
/// [rad], a, b), bins centred on j·`pitch`/[`STIFFNESS_BINS`].
pub fn paired_bins(pitch: f64, a: &[Option<f64>], b: &[Option<f64>]) -> Vec<(f64, f64, f64)> {
    (0..STIFFNESS_BINS)
        .filter_map(|j| {
            let theta = j as f64 * pitch / STIFFNESS_BINS as f64;
            Some((theta, a[j]?, b[j]?))
        })
        .collect()
}

/// Analyses the DTE of `history` in the window [t_from, end]. `unloaded_te` is the relief's
/// geometric unloaded TE e along the line of action [m] against the driver rotation from the
/// pitch-point position (the LTCA's), `torque` the load torque on the driven gear. The low-pass
/// spans one period of the mesh mode of `driven_inertia` on the mean stiffness, or `span` [s]
/// when given (to compare two runs through one filter).
pub fn analyse_dte(
    history: &History,
    pair: &GearPair,
    driven_inertia: f64,
    torque: f64,
    t_from: f64,
    unloaded_te: &PeriodicTable,
    span: Option<f64>,
) -> Option<DteAnalysis> {
    let start = history.time.iter().position(|t| *t >= t_from)?;
    let window = &history.dte[start..];
    if window.len() < 2 {
        return None;
    }
    let n = window.len() as f64;
    let mean = window.iter().sum::<f64>() / n;
    let (min, max) = crate::signal::extremes(window);
    let rb2 = pair.gears[1].base_radius;
    let pitch = pair.gears[0].angular_pitch();
    // The unloaded TE over the window (the only place k and the filter's stiffness read it).
    let e: Vec<f64> = history.driver_rotation[start..]
        .iter()
        .map(|theta| unloaded_te.at(*theta))
        .collect();
    let e_mean = e.iter().sum::<f64>() / n;
    // Torsional mesh stiffness k̄ R_b2² = T/(θ̄ − ē/R_b2) for the filter's period.
    let k_t = torque / (mean - e_mean / rb2);
    let sample = history.time.get(1).map_or(0.0, |t| t - history.time[0]);
    let lowpass = match span {
        Some(period) => Lowpass::with_period(period, sample),
        None => Lowpass::new(k_t, driven_inertia, sample),
    };
    let mut lowpass_stats = None;
    if let Some(filter) = lowpass {
        let (_, dte) = filter.apply(&history.dte, start);
        if !dte.is_empty() {
            let lp_mean = dte.iter().sum::<f64>() / dte.len() as f64;
            let (lo, hi) = crate::signal::extremes(&dte);
            lowpass_stats = Some(LowpassDte {
                period_s: filter.period_s,
                mean_rad: lp_mean,
                max_rad: hi,
                min_rad: lo,
                peak_to_peak_rad: hi - lo,
            });
        }
    }
    let deflection: Vec<f64> = window.iter().zip(&e).map(|(d, e)| rb2 * d - e).collect();
    let stiffness_bins = binned_stiffness(
        pitch,
        &history.driver_rotation[start..],
        &history.mesh_force[start..],
        &deflection,
    );
    let filled: Vec<usize> = (0..STIFFNESS_BINS)
        .filter(|b| stiffness_bins[*b].is_some())
        .collect();
    let coverage = filled.len() as f64 / STIFFNESS_BINS as f64;
    let position = |b: usize| b as f64 / STIFFNESS_BINS as f64 * pitch;
    let roll_pitch = pair.roll_angle_at(1, pair.contact_points.pitch);
    let angles: Vec<f64> = filled.iter().map(|b| roll_pitch + position(*b)).collect();
    let k: Vec<f64> = filled.iter().filter_map(|b| stiffness_bins[*b]).collect();
    let e_bins: Vec<f64> = filled
        .iter()
        .map(|b| unloaded_te.at(position(*b)))
        .collect();
    let stiffness = MeshStiffness::from_samples(
        "explicit FE DTE (k = sum W / sum (Rb2 theta_DTE - e) per bin)",
        Some(torque),
        pitch,
        &angles,
        &k,
        &e_bins,
    )
    .ok();
    let k_mean = stiffness.as_ref().map_or(f64::NAN, |k| k.mean());
    let static_te = static_te(pair, torque, &stiffness_bins, unloaded_te);
    Some(DteAnalysis {
        window: (history.time[start], *history.time.last()?),
        window_start: start,
        dte_mean_rad: mean,
        dte_min_rad: min,
        dte_max_rad: max,
        dte_peak_to_peak_rad: max - min,
        stiffness,
        stiffness_bins,
        filter: lowpass,
        mesh_stiffness_mean_n_per_m: k_mean,
        mesh_stiffness_from_mean_dte_n_per_m: torque / (mean * rb2 * rb2),
        pitch_coverage: coverage,
        lowpass: lowpass_stats,
        static_te,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Where [`SettledStop`] stops a synthetic DTE `amplitude(t)·sin(2π f_m t)` sampled every
    /// 10 µs (the runs' output interval), checked as the run checks it: the record to each due
    /// sample; None where it runs to `end_s`.
    fn settled_stop_time(amplitude: impl Fn(f64) -> f64, end_s: f64) -> Option<f64> {
        let (dt, mesh_hz) = (1e-5, 3192.0);
        let stop = SettledStop {
            from_s: 0.016,
            mesh_hz,
            min_third_s: SettledStop::MIN_THIRD_S,
            drift: SettledStop::DRIFT,
            growth: SettledStop::GROWTH,
        };
        let mut time = Vec::new();
        let mut dte = Vec::new();
        for k in 0..=((end_s / dt).round() as usize) {
            let t = k as f64 * dt;
            time.push(t);
            dte.push(1e-4 + amplitude(t) * (std::f64::consts::TAU * mesh_hz * t).sin());
            if stop.due(&time) && stop.settled(&dte, dt) {
                return Some(t);
            }
        }
        None
    }

    /// A steady response stops at the first check whose record and the two before hold thirds
    /// of 20 whole mesh periods (6.27 ms ≥ 6 ms at 3 192 Hz), 18.8 ms after the statistics
    /// start at 16 ms: 35, 36, 37 ms, so at 37 ms. An exponential approach stops only where
    /// what is left of it is within the stop's drift of the settled rms (Aitken's limit of the
    /// thirds is exact for it); one as slow as τ = 20 ms or 60 ms, whose first third (from the
    /// statistics start on) stays more than the stop's growth below its last, runs on to its
    /// end, as a growing response does. A rise of 9 % that sets in at 30 ms (the slow build-up
    /// near the resonance, validation/lumped-twin) does not stop before it has risen (it runs
    /// on: its first third stays 9 % below its last); a beat of ±10 % whose
    /// period (30, 40 ms) is longer than a third stops, if at all, where its reading is within
    /// a few per cent of its mean rms.
    #[test]
    fn a_settled_stop_waits_for_the_dte_to_settle() {
        let steady = settled_stop_time(|_| 2e-4, 0.05).unwrap();
        assert!(
            (steady - 0.037).abs() < 0.5e-5,
            "steady: stopped at {steady}"
        );
        // What is left to come at a stop at t: the remainder of the amplitude at the middle of
        // the last third, over the final amplitude.
        let left = |amplitude: &dyn Fn(f64) -> f64, t: f64, last: f64| {
            1.0 - amplitude(t - 0.5 * SettledStop::MIN_THIRD_S) / last
        };
        for tau in [2e-3, 5e-3, 10e-3, 20e-3, 60e-3] {
            let approach = move |t: f64| 2e-4 * (1.0 - 0.5 * (-t / tau).exp());
            let stopped = settled_stop_time(approach, 0.1);
            eprintln!("approach, τ = {tau} s: stopped at {stopped:?} s");
            match stopped {
                Some(t) => {
                    let rest = left(&approach, t, 2e-4);
                    assert!(
                        rest <= 1.5 * SettledStop::DRIFT,
                        "τ {tau}: stopped at {t} s with {rest} still to come"
                    );
                    assert!(
                        t >= steady - 1e-9,
                        "τ {tau}: stopped at {t} before {steady}"
                    );
                }
                None => assert!(tau >= 20e-3, "τ {tau} did not stop"),
            }
        }
        assert_eq!(settled_stop_time(|t| 2e-4 * (t / 0.05).exp(), 0.1), None);
        // Too little record: never.
        assert_eq!(settled_stop_time(|_| 2e-4, 0.036), None);
        // A late rise of 9 % with τ = 5 ms from 30 ms on.
        let late = |t: f64| 2e-4 * (1.0 + 0.09 * (1.0 - (-(t - 0.03).max(0.0) / 5e-3).exp()));
        let stopped = settled_stop_time(late, 0.1);
        eprintln!("late rise: stopped at {stopped:?} s");
        if let Some(t) = stopped {
            let rest = left(&late, t, late(1.0));
            assert!(
                rest <= 1.5 * SettledStop::DRIFT,
                "late rise: {rest} still to come"
            );
        }
        for period in [0.03, 0.04] {
            let beat =
                move |t: f64| 2e-4 * (1.0 + 0.1 * (std::f64::consts::TAU * t / period).sin());
            let stopped = settled_stop_time(beat, 0.1);
            eprintln!("beat of {period} s: stopped at {stopped:?} s");
            if let Some(t) = stopped {
                let reading = crate::signal::rms_about_mean(
                    &(0..((SettledStop::MIN_THIRD_S / 1e-5) as usize))
                        .map(|k| {
                            let s = t - k as f64 * 1e-5;
                            beat(s) * (std::f64::consts::TAU * 3192.0 * s).sin()
                        })
                        .collect::<Vec<_>>(),
                ) * std::f64::consts::SQRT_2
                    / 2e-4;
                eprintln!("  its last 6 ms read {reading:.4} of the mean amplitude");
                assert!(
                    (reading - 1.0).abs() < 0.05,
                    "beat {period}: reads {reading}"
                );
            }
        }
    }

    /// A window holds the teeth that engage over its span (and the pad) as [`window_teeth`]
    /// has them and their neighbours, ends one pitch on, keeps a tooth pair loaded at the switch wherever it stands
    /// (its teeth fine, the driven partner's neighbours too), and the last window runs to the
    /// scene's end. On 24/40 and 40/24, so that the driven gear's neighbours wrap around its
    /// own tooth count.
    #[test]
    fn a_window_holds_its_teeth_and_keeps_a_loaded_pair() {
        for name in ["24-40", "40-24"] {
            let overrides = crate::samples::matrix_pair(name)
                .unwrap()
                .parsed_overrides();
            let case = crate::case::Case::load_with(None, &overrides).unwrap();
            let pair = &case.pair;
            let pitch = pair.gears[0].angular_pitch();
            let plan = WindowPlan {
                pitch,
                scene_rotation: 20.0 * pitch,
                pad: 0.01 * pitch,
            };
            let w = plan.window(pair, 3, 5.0 * pitch, &[]);
            assert_eq!(w.index, 3);
            assert!((w.end_rotation - 6.0 * pitch).abs() < 1e-12);
            let (fine, pairs) = window_teeth(pair, 5.0 * pitch, 6.01 * pitch);
            // The engaging teeth and their neighbours.
            let widened: [Vec<usize>; 2] = std::array::from_fn(|g| {
                let z = pair.gears[g].teeth() as usize;
                let mut teeth: Vec<usize> = fine[g]
                    .iter()
                    .flat_map(|&t| [(t + z - 1) % z, t, (t + 1) % z])
                    .collect();
                teeth.sort_unstable();
                teeth.dedup();
                teeth
            });
            assert_eq!(WINDOW_NEIGHBOURS, 1);
            assert_eq!(w.fine_teeth, widened);
            assert!(w.fine_teeth[0].len() > fine[0].len());
            assert_eq!(w.tooth_pairs, pairs);
            let z2 = pair.gears[1].teeth() as usize;
            // A pair far from this window: driver tooth 1 with its partner two pitches on.
            let far = (1, z2 - 1);
            assert!(!pairs.contains(&far));
            let kept = plan.window(pair, 3, 5.0 * pitch, &[far, pairs[0]]);
            assert!(kept.tooth_pairs.contains(&far));
            assert_eq!(kept.tooth_pairs.len(), pairs.len() + 1);
            assert!(kept.fine_teeth[0].contains(&1));
            for t in [z2 - 2, z2 - 1, 0] {
                assert!(kept.fine_teeth[1].contains(&t), "{name}: {t}");
            }
            let last = plan.window(pair, 19, 19.5 * pitch, &[]);
            assert!(last.end_rotation.is_infinite());
            assert_eq!(
                last.tooth_pairs,
                window_teeth(pair, 19.5 * pitch, 20.0 * pitch).1
            );
        }
    }

    /// The coupled step's control: it rises once to the step allowed (less the headroom, a
    /// divisor of the sample interval), only falls after, never below the bound's step, keeps
    /// every × dt the sample interval, and ends the run at the first step past the duration.
    #[test]
    fn the_step_control_rises_once_falls_after_and_keeps_the_samples_spacing() {
        let mut control = StepControl::new(1.0, 1000, 10);
        control.lower_to(1.0, 1.3, 100, 100.0, 1000.0);
        assert_eq!((control.every, control.dt), (8, 1.25));
        assert_eq!(control.total_steps, 100 + 720);
        control.lower_to(1.0, 1.5, 200, 225.0, 1000.0);
        assert_eq!(
            (control.every, control.changes.len()),
            (8, 1),
            "no rise after the first"
        );
        control.lower_to(1.0, 1.2, 300, 350.0, 1000.0);
        assert_eq!(control.every, 9);
        assert_eq!(
            control.total_steps,
            300 + (650.0_f64 / (10.0 / 9.0)).ceil() as usize
        );
        control.lower_to(1.0, 0.5, 400, 461.0, 1000.0);
        assert_eq!(
            (control.every, control.dt),
            (10, 1.0),
            "never below the bound's step"
        );
        for change in &control.changes {
            assert!((change.dt_s * change.steps_per_sample as f64 - 10.0).abs() < 1e-12);
        }
        assert!(control.fallback.is_none());
        control.fall_back(1.0, 500, 561.0, 1000.0, "why".into());
        assert_eq!(control.fallback.as_deref(), Some("why"));
    }

    /// Ringing at the mesh mode on top of a slow square wave: the one-period average removes the
    /// ringing exactly (a whole period of a sine averages to zero) and keeps the plateaus.
    #[test]
    fn lowpass_removes_the_mesh_mode_and_keeps_the_quasi_static_dte() {
        let (sample, f_n) = (1e-5, 2500.0);
        let omega = std::f64::consts::TAU * f_n;
        let inertia = 3e-3;
        let k_t = omega * omega * inertia;
        let dte: Vec<f64> = (0..1000)
            .map(|i| {
                let t = i as f64 * sample;
                let plateau = if ((t / 2.5e-3) as usize).is_multiple_of(2) {
                    1.0e-4
                } else {
                    1.5e-4
                };
                plateau + 3e-5 * (omega * t + 0.3).sin()
            })
            .collect();
        let filter = Lowpass::new(k_t, inertia, sample).unwrap();
        assert!((filter.period_s - 4e-4).abs() < 1e-12);
        assert_eq!(filter.width, 40);
        let (first, averages) = filter.apply(&dte, 100);
        assert_eq!(first, 100);
        let (lo, hi) = crate::signal::extremes(&averages);
        assert!((hi - 1.5e-4).abs() < 1e-12, "{hi}");
        assert!((lo - 1.0e-4).abs() < 1e-12, "{lo}");
    }

    /// A synthetic 60 rpm record whose answer is known: k(θ) with the steps of single and
    /// double contact (k̄ × 0.8 over 31 % of the base pitch, × 1.3 elsewhere, the steps on bin
    /// edges) and a cosine on top, an unloaded TE e(θ) = 5 µm sin 2πθ/p, a mesh force
    /// W = F(1 + 0.05 sin 2πθ/p), the deflection δ = W/k ringing by 10 % at the mesh mode of a
    /// mass-scaled gear (360 Hz, a tenth of a mesh period) and the force with it, W = kδ, as the
    /// contact makes them; θ_DTE = (δ + e)/R_b2. The analysis returns k at every bin within
    /// 0.1 % (what varies inside a bin: the cosine's curvature) and e exactly. A low-pass over
    /// the mode's period before the ratio, as before, smeared the steps: up to 20 % off at the
    /// bins beside them. With the nominal torque and e left in, k would even come out negative
    /// where e exceeds the deflection.
    #[test]
    fn the_stiffness_from_a_synthetic_dte_is_recovered_bin_by_bin() {
        let pair = crate::samples::paper36_pair();
        let rb2 = pair.gears[1].base_radius;
        let pitch = pair.gears[0].angular_pitch();
        let (torque, k_mean) = (143.6, 4.0e8);
        let force = torque / rb2;
        let omega_n = std::f64::consts::TAU * 360.0;
        let inertia = k_mean * rb2 * rb2 / (omega_n * omega_n);
        let phase = |theta: f64| std::f64::consts::TAU * theta / pitch;
        let bin = |theta: f64| (theta / pitch).rem_euclid(1.0) * STIFFNESS_BINS as f64;
        let k = |theta: f64| {
            let steps = if (10.5..30.5).contains(&bin(theta)) {
                0.8
            } else {
                1.3
            };
            k_mean * steps * (1.0 + 0.05 * phase(theta).cos())
        };
        let e = |theta: f64| 5e-6 * phase(theta).sin();
        let speed = std::f64::consts::TAU; // 60 rpm
        let mut history = History::default();
        for i in 0..6000 {
            let t = i as f64 * 1e-5;
            let theta = speed * t;
            let w = force * (1.0 + 0.05 * phase(theta).sin());
            let delta = w / k(theta) * (1.0 + 0.1 * (omega_n * t).sin());
            history.time.push(t);
            history.driver_rotation.push(theta);
            history.mesh_force.push(k(theta) * delta);
            history.dte.push((delta + e(theta)) / rb2);
        }
        let unloaded = PeriodicTable::from_fn(pitch, 4096, e);
        let a = analyse_dte(&history, &pair, inertia, torque, 0.006, &unloaded, None).unwrap();
        assert_eq!(a.pitch_coverage, 1.0);
        let table = a.stiffness.unwrap();
        assert_eq!(table.stiffness.values.len(), STIFFNESS_BINS);
        for (j, (_, k_fe, e_fe)) in table.samples().iter().enumerate() {
            let theta = j as f64 * pitch / STIFFNESS_BINS as f64;
            assert!(
                (k_fe / k(theta) - 1.0).abs() < 1e-3,
                "bin {j}: {k_fe} vs {}",
                k(theta)
            );
            assert!(
                (e_fe - e(theta)).abs() < 1e-9,
                "bin {j}: {e_fe} vs {}",
                e(theta)
            );
        }
        // The static TE at the load from it: (T/(R_b2 k) + e)/R_b2 at the bin centres, within
        // the 0.1 % of k (the load's 5 % variation in W does not enter: W = T/R_b2 statically).
        let exact: Vec<f64> = (0..STIFFNESS_BINS)
            .map(|j| {
                let theta = j as f64 * pitch / STIFFNESS_BINS as f64;
                (torque / (rb2 * k(theta)) + e(theta)) / rb2
            })
            .collect();
        let te = a.static_te.unwrap();
        let mean = exact.iter().sum::<f64>() / exact.len() as f64;
        let (lo, hi) = crate::signal::extremes(&exact);
        assert_eq!(te.bins, STIFFNESS_BINS);
        assert!((te.mean_rad / mean - 1.0).abs() < 1e-3, "{te:?} vs {mean}");
        assert!(
            (te.peak_to_peak_rad / (hi - lo) - 1.0).abs() < 2e-3,
            "{te:?} vs {}",
            hi - lo
        );
    }

    #[test]
    fn bin_difference_reads_only_bins_both_have() {
        let a = [Some(1.02), None, Some(2.0), Some(3.0)];
        let b = [Some(1.0), Some(5.0), None, Some(3.0)];
        let (mean, worst, n) = bin_difference(&a, &b).unwrap();
        assert_eq!(n, 2);
        assert!((mean - (4.02 / 4.0 - 1.0)).abs() < 1e-12);
        assert!((worst - 0.02).abs() < 1e-12);
        assert!(bin_difference(&[None], &[Some(1.0)]).is_none());
    }

    /// The ringing a ramp leaves in an undamped oscillator x″ + ω²x = ω²f(t), f the load
    /// torque's ramp plus the spin-up's inertia torque I₂α₂(t), both over T, integrated with a
    /// fine step: never above `ramp_ringing` (an envelope), and equal to it (0.5 %) where the
    /// envelope is attained — a linear ramp with sin(ωt_r/2) = ±1, a cosine ramp with
    /// cos(ωt_r/2) = ±1 — from rest (inertia term large, as with mass scaling) and at speed.
    #[test]
    fn the_ramp_leaves_the_ringing_the_settling_time_assumes() {
        let omega = std::f64::consts::TAU * 540.0;
        let (inertia, ratio, torque) = (0.11, 1.0, 143.6);
        let residual = |drive: &Drive| {
            let steps_per_period = 4000.0;
            let h = std::f64::consts::TAU / omega / steps_per_period;
            let force = |t: f64| {
                let (_, _, alpha) = drive.driver_motion(t);
                (drive.load_torque_at(t) + inertia * ratio * alpha) / torque
            };
            let (mut x, mut v, mut t) = (0.0, 0.0, 0.0);
            while t < drive.ramp_time + 2.0 * std::f64::consts::TAU / omega {
                // Velocity Verlet on x'' = ω²(f − x).
                let a0 = omega * omega * (force(t) - x);
                x += h * v + 0.5 * h * h * a0;
                let a1 = omega * omega * (force(t + h) - x);
                v += 0.5 * h * (a0 + a1);
                t += h;
            }
            ((x - 1.0).powi(2) + (v / omega).powi(2)).sqrt()
        };
        let pi = std::f64::consts::PI;
        for (ramp, attained) in [(Ramp::Linear, 9.5 * pi), (Ramp::Cosine, 10.0 * pi)] {
            for start in [Start::Rest, Start::AtSpeed] {
                for (half_phase, exact) in [(attained, true), (attained + 0.4, false)] {
                    let drive = Drive {
                        driver_speed: std::f64::consts::TAU,
                        load_torque: torque,
                        ramp_time: 2.0 * half_phase / omega,
                        ramp,
                        start,
                        start_rotation: 0.0,
                    };
                    let simulated = residual(&drive);
                    let envelope = ramp_ringing(&drive, omega, inertia, ratio * drive.driver_speed);
                    let case = format!("{ramp:?} {start:?} ωt_r/2 = {half_phase:.2}");
                    assert!(
                        simulated <= envelope * 1.005,
                        "{case}: {simulated} > {envelope}"
                    );
                    if exact {
                        assert!(
                            (simulated / envelope - 1.0).abs() < 5e-3,
                            "{case}: {simulated} vs {envelope}"
                        );
                    }
                }
            }
        }
    }
}
