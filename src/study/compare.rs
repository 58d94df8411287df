//! The comparison study (`geardyn compare`): the mesh (torsional) natural frequency of the pair
//! by every method, for both boundary conditions, and the explicit FE's DTE spectra against the
//! lumped model's at the same speeds.
//!
//! # Boundary conditions and masses
//! * **driver held** — the explicit FE's: the driver's bore follows the prescribed speed
//!   (lumped `drive = speed`); with rigid gears the mesh mode moves the driven gear only,
//!   m = I₂/r_b2², with elastic bodies the driver's rim swings on its body's twist too.
//! * **both free** — the lumped model's torque drive: rigid gears m_e = I₁I₂/(I₁r_b2² +
//!   I₂r_b1²). (The seed paper's 2 433 Hz used this mass although its driver is speed-driven.)
//!
//! # Methods
//! (a) √(k̄/m) with k̄ from the LTCA (secant W/δ and tangent dW/dδ, on the explicit FE's mesh)
//! and from the FE DTE (`stiffness.csv` of a stiffness scene); (b) the Floquet frequency of the
//! periodic lumped model with the FE k(θ) at each speed; (c) the FE modal analysis of the meshed
//! pair about the LTCA's loaded state ([`crate::ltca::modal`]) at `positions` positions over the
//! base pitch; (d) the spectral peaks of the explicit FE's DTE, after the ramp's ringing, each
//! labelled as a mesh harmonic n·f_m, the mesh mode f_n or a combination n·f_m ± f_n, and an
//! early window's against a late one's; (e) the lumped model's periodic steady state at the
//! same speed (speed drive, FE k(θ), the FE's mesh damping, the back flanks' own k and e), its
//! first three mesh harmonics against the FE's.
//!
//! # Rigid gears or elastic bodies
//! The hub-to-hub stiffness (LTCA, FE DTE) holds each body's twist between bore and root
//! circle, c_b = r_b² (1/r_i² − 1/r_f²)/(4πGb) ([`crate::geometry::Gear::body_torsional_compliance`]).
//! Most of a gear's inertia lies outside that twist (I ∝ ∫r³dr, the twist ∝ ∫dr/r³), so behind a
//! free, light hub (the FE's driven hub carries only its bore nodes) the mesh mode does not
//! stretch it. The lumped model with rigid gears puts the whole inertia behind the whole
//! compliance and reads the mesh mode low; with elastic bodies ([`crate::lumped::structure`])
//! the twist leaves the mesh (k' = 1/(1/k − c_b)) for the bodies, hub and rim, the inertia where
//! it sits (the FE's lumped twin, [`lumped_twin`]). Both are reported; the speed comparison
//! uses the elastic bodies. The headline frequencies set the case's own lumped model (as the
//! sweeps integrate it) against the FE modal analysis on the case's mesh
//! ([`super::frequencies`]).

use serde::Serialize;

use crate::case::Case;
use crate::ltca::modal::{Hubs, PairModes};
use crate::lumped::{
    floquet_frequency, steady_state, DampingSite, Drive, MeshModel, SpringDamping,
};
use crate::signal::{
    amplitude_spectrum, hann_amplitude_spectrum, harmonic_amplitudes, spectrum_peaks,
};
use crate::stiffness::{ForceLaw, MeshStiffness};

use super::lumped::gear_inertias;
use super::{Progress, StudyError};
use crate::case::BodyModel;

/// Positions of the FE modal analysis on the case's mesh (the headline frequencies): 8 put the
/// mean 0.5–0.6 % above 16's on the paper pair (validation/frequencies), at half the cost in
/// the default `run`; `geardyn validate frequencies --positions N` takes more.
pub const CASE_MESH_MODAL_POSITIONS: usize = 8;

/// Mesh harmonics compared.
pub const HARMONICS: usize = 3;
/// Spectral peaks listed per window.
pub const PEAKS: usize = 8;

/// The DTE record of one explicit FE run.
#[derive(Debug, Clone)]
pub struct FeDte {
    /// Where it comes from (a run folder).
    pub source: String,
    pub speed_rpm: f64,
    pub torque_nm: f64,
    /// The explicit mesh's flank element size [mm] (`None`: not recorded, e.g. a synthetic run).
    pub fine_element_mm: Option<f64>,
    /// The explicit mesh's tooth layout (graded where the run does not record it: every run
    /// before 2026-12-06).
    pub tooth_layout: crate::mesh::ToothLayout,
    /// Uniform sampling interval [s] and the angular DTE of the driven gear [rad].
    pub dt: f64,
    pub dte: Vec<f64>,
    /// The back flanks' total contact force at the same samples [N]; empty when the run's
    /// history does not hold it.
    pub back_flank_force: Vec<f64>,
    /// End of the ramp, and the start of the statistics (the ramp's ringing decayed) [s].
    pub ramp_end_s: f64,
    pub statistics_start_s: f64,
    pub wall_s: f64,
    /// The run's stiffness-proportional (Rayleigh) element damping β [s], of its bodies'
    /// unscaled masses (a mass-scaled run's β over √ of its scaling factor; `None`: not
    /// recorded, e.g. a synthetic run).
    pub stiffness_damping_beta_s: Option<f64>,
    /// The run's mesh dashpot on the driven hub's DTE rate [N·m·s] (`fe.mesh_damping_ratio`
    /// on the LTCA k̄ of the run's own explicit mesh and the driven inertia, so it differs
    /// between meshes: 3.3 % less on 0.25 mm flanks than on 1 mm, paper pair), of the unscaled
    /// masses as β above (`None`: not recorded, or a target-step mass scaling).
    pub mesh_damping_n_m_s: Option<f64>,
}

/// The explicit FE's damping, which its lumped twin carries where the FE has it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FeDamping {
    /// The mesh dashpot on the driven hub against the DTE rate, along the line of action
    /// [N·s/m] (the twin's [`DampingSite::HubTransmissionError`]).
    pub mesh_n_s_per_m: f64,
    /// The elements' stiffness-proportional damping β [s]: the twin's body springs get c = β k
    /// ([`SpringDamping::StiffnessProportional`]), not a drivetrain's damping ratio
    /// (`lumped.drivetrain_damping_ratio`, 0.02 by default), which the FE's bodies do not have.
    /// At the mesh mode it is next to nothing (β ω/2 ≈ 1e-5 on the paper pair); the same β on
    /// the teeth's elements, which the twin's mesh spring leaves out, gives about β k̄ ≈ 0.4
    /// N·s/m beside the mesh dashpot's ≈ 2 000.
    pub stiffness_beta_s: f64,
}

/// The element damping β [s] of the FE runs `runs`: their mean (each of the unscaled bodies,
/// [`FeDte::stiffness_damping_beta_s`]; it varies with the mesh, β = 2ζ/ω_max), 0 where none
/// is recorded.
pub fn runs_element_damping(runs: &[FeDte]) -> f64 {
    let betas: Vec<f64> = runs
        .iter()
        .filter_map(|r| r.stiffness_damping_beta_s)
        .collect();
    match betas.is_empty() {
        true => 0.0,
        false => betas.iter().sum::<f64>() / betas.len() as f64,
    }
}

impl FeDte {
    /// Sample indices where the ramp ends and where the statistics start (never before the
    /// ramp's end).
    pub fn window_starts(&self) -> (usize, usize) {
        let index = |t: f64| ((t / self.dt).round().max(0.0) as usize).min(self.dte.len());
        let ramp = index(self.ramp_end_s);
        (ramp, index(self.statistics_start_s).max(ramp))
    }
}

/// What the study needs beyond the case: FE runs and the FE's k(θ).
pub struct CompareInput {
    pub fe_runs: Vec<FeDte>,
    /// The speeds of the FE speed sweep (`--fe-sweep`) [rpm]; empty: none. Every run of
    /// `fe_runs` inside their range joins it (runs on other explicit meshes as mesh levels of
    /// their own).
    pub fe_sweep_rpm: Vec<f64>,
    /// k(θ), e(θ) from the FE DTE (a stiffness scene), with its source.
    pub fe_stiffness: MeshStiffness,
}

/// The mesh-mode frequency of one boundary condition by every method [Hz].
#[derive(Debug, Clone, Serialize)]
pub struct Frequencies {
    pub hubs: Hubs,
    /// The lumped model's mass for this boundary condition [kg].
    pub effective_mass_kg: f64,
    pub lumped_ltca_secant_hz: f64,
    pub lumped_ltca_tangent_hz: f64,
    pub lumped_fe_hz: f64,
    /// The bodies' twist between bore and root circle along the line of action, both gears
    /// [m/N] ([`body_twist`]; the twist alone: where the case's bodies sway, the twins take
    /// their sway out of the hub-to-hub k too, [`super::lumped::bodies_line_compliance`]).
    pub body_twist_m_per_n: f64,
    /// Elastic bodies (hub and rim, [`crate::lumped::structure`]) under this boundary
    /// condition, the twist taken out of the hub-to-hub k: the structure's mesh mode with the
    /// FE's k(θ) (its mean), the LTCA's secant k̄ and its tangent k̄ (the modal's own
    /// linearization, on the same mesh).
    pub lumped_fe_elastic_hz: f64,
    pub lumped_ltca_elastic_hz: f64,
    pub lumped_ltca_tangent_elastic_hz: f64,
    /// The case's lumped model (what `sweep` and `run` integrate: its stiffness source and force
    /// law on the case's mesh, linearized about the design load, its bodies) on this boundary
    /// condition (no shafts, no bearings, as the FE): its mesh mode frozen at each of the FE
    /// modal's positions, their mean; and the FE modal analysis on the case's mesh, mean over
    /// the same [`CASE_MESH_MODAL_POSITIONS`] ([`super::frequencies`]).
    pub lumped_model_hz: f64,
    pub fe_modal_case_mesh_mean_hz: f64,
    /// Floquet frequency of the undamped lumped model with the FE k(θ) (elastic bodies), per FE
    /// speed: (rpm, Hz).
    pub floquet_hz: Vec<(f64, f64)>,
    /// FE modal mesh mode per position: (driver rotation [deg], Hz), and its mean.
    pub fe_modal_hz: Vec<(f64, f64)>,
    pub fe_modal_mean_hz: f64,
    /// Over the FE modal mean, minus 1: rigid gears with the FE k̄, elastic bodies with the FE
    /// k(θ) (both against the modal on the explicit mesh), and the case's lumped model (against
    /// the modal on the case's mesh).
    pub lumped_fe_over_modal_rel: f64,
    pub lumped_fe_elastic_over_modal_rel: f64,
    pub lumped_model_over_modal_rel: f64,
}

/// A labelled spectral line.
#[derive(Debug, Clone, Serialize)]
pub struct Peak {
    pub frequency_hz: f64,
    pub amplitude_rad: f64,
    /// `n f_m`, `f_n` (FE modal mesh mode, driver held), `n f_m + f_n`, `n f_m - f_n`, `f_b`
    /// (the driver body's torsion, driver held), or `?` when none is within 1.5 bins.
    pub label: String,
}

/// One speed: the FE DTE spectrum against the lumped model's.
#[derive(Debug, Clone, Serialize)]
pub struct SpeedComparison {
    pub speed_rpm: f64,
    pub mesh_hz: f64,
    pub source: String,
    /// Spectral resolution of the late window [Hz].
    pub resolution_hz: f64,
    /// Late window (the statistics window) and early window (ramp end to the statistics start,
    /// or the first half after the ramp when that is shorter than 3 mesh periods) [s].
    pub late_window_s: (f64, f64),
    pub early_window_s: (f64, f64),
    pub fe_peaks: Vec<Peak>,
    pub fe_early_peaks: Vec<Peak>,
    /// Amplitudes of the first mesh harmonics [rad]: FE (late window), lumped (steady state).
    pub fe_harmonics_rad: Vec<f64>,
    pub lumped_harmonics_rad: Vec<f64>,
    /// DTE rms about its mean [rad]: FE (late window), lumped (steady state).
    pub fe_dte_rms_rad: f64,
    pub lumped_dte_rms_rad: f64,
    pub harmonic_error_rel: Vec<f64>,
    /// The same with rigid gears (the FE k as it is, body twist included).
    pub lumped_rigid_harmonics_rad: Vec<f64>,
    pub rigid_harmonic_error_rel: Vec<f64>,
    pub lumped_converged: bool,
    pub lumped_separated: bool,
    /// The twin's response grew without bound here (its numbers are NaN).
    pub lumped_diverged: bool,
    /// f_mesh over the FE modal mesh mode (driver held).
    pub mesh_over_mode: f64,
    #[serde(skip)]
    pub fe_spectrum: Vec<(f64, f64)>,
    #[serde(skip)]
    pub fe_early_spectrum: Vec<(f64, f64)>,
}

/// The seed paper's mean mesh stiffness T/(θ̄ R_b2²) = 1.3427e8 N/m (mean angular deflection
/// 3.695e-4 rad at 143.6 N·m). Used only by the labelled `paper-stiffness` study, never as a
/// default: our LTCA and FE give about 4e8 N/m for the same pair.
pub const PAPER_MEAN_STIFFNESS: f64 = 1.3427e8;

/// The `paper-stiffness` study: our lumped dynamics given the paper's stiffness, to test
/// whether they reproduce the paper's frequency pattern (mesh mode 2 433 Hz with m_e; DTE lines
/// at 1 800 and 2 200 Hz at 3 000 rpm).
#[derive(Debug, Clone, Serialize)]
pub struct PaperStiffness {
    pub note: String,
    /// The compliance put in series with the FE k(θ) so that its mean is the paper's [m/N].
    pub series_compliance_m_per_n: f64,
    pub mean_stiffness_n_per_m: f64,
    /// √(k̄/m) with rigid gears: both free (the paper's m_e) and driver held [Hz].
    pub f_both_free_hz: f64,
    pub f_driver_held_hz: f64,
    pub speed_rpm: f64,
    pub mesh_hz: f64,
    /// A lumped transient at constant speed (speed drive) from the static state at the mean
    /// stiffness, as long as the FE run: peaks of the late window (from the FE run's statistics
    /// start) and of the early one, labelled with f_n = the driver-held frequency. (The early
    /// window's resolution, 1/its length, decides whether f_n separates from the mesh line.)
    pub late_peaks: Vec<Peak>,
    pub early_peaks: Vec<Peak>,
    #[serde(skip)]
    pub late_spectrum: Vec<(f64, f64)>,
    #[serde(skip)]
    pub early_spectrum: Vec<(f64, f64)>,
}

/// Headline numbers (`summary.json`).
#[derive(Debug, Clone, Serialize)]
pub struct CompareSummary {
    pub case: String,
    /// Mesh frequency of the primary FE run ([`primary_run`]) [Hz].
    pub f_mesh_hz: f64,
    /// Both gears free: the case's lumped model frozen at the FE modal's positions, their mean
    /// ([`Frequencies::lumped_model_hz`]), and the FE modal mean on the case's mesh.
    pub f_natural_lumped_hz: f64,
    pub f_natural_fe_modal_hz: f64,
    /// Driver held (I₂/r_b2²).
    pub f_natural_lumped_driver_held_hz: f64,
    pub f_natural_fe_modal_driver_held_hz: f64,
    /// Peaks of the primary FE run's DTE and the lumped model's lines at its speed [Hz].
    pub fe_dte_peaks_hz: Vec<f64>,
    pub lumped_dte_peaks_hz: Vec<f64>,
    pub mean_stiffness_ltca_n_per_m: f64,
    pub mean_tangent_stiffness_ltca_n_per_m: f64,
    pub mean_stiffness_fe_n_per_m: f64,
    pub fe_stiffness_source: String,
    pub driver_held: Frequencies,
    pub both_free: Frequencies,
    pub speeds: Vec<SpeedComparison>,
    /// FE modal at every position and boundary condition.
    pub modal: Vec<PairModes>,
    /// The FE mesh dashpot as `fe.mesh_damping_ratio` sizes it on the LTCA of the case's
    /// explicit mesh [N·s/m]: the one the twins are built for, and carry where the FE runs
    /// recorded none (each twin held against a run carries the run's own,
    /// [`with_fe_dashpot`]).
    pub mesh_damping_n_s_per_m: f64,
    /// The FE runs' element damping β [s] ([`runs_element_damping`]), which the twins' body
    /// springs carry as c = β k ([`FeDamping`]).
    pub twin_body_damping_beta_s: f64,
    /// The mesh mode's damping ratio that the FE's dashpot gives its elastic-body lumped twin
    /// (driver at speed; [`MeshModel::mesh_mode_damping_ratio`]): about fe.mesh_damping_ratio,
    /// the dashpot being sized on the hub-to-hub stiffness and acting on the hub.
    pub mesh_mode_damping_ratio_fe_twin: f64,
    /// The same dashpot's first-order damping of the FE modal analysis's mesh mode, driver
    /// held (c r_b2² φ²/(2ω), φ the driven hub's rotation in the mass-normalized shape), mean
    /// over the positions; at the modal analysis's tied contact, whose mesh mode lies 4–5 %
    /// above the explicit FE's penalty contact (paper pair), so the twin's damping is compared
    /// through the dashpot's share below, not through this ratio.
    pub mesh_mode_damping_ratio_fe_modal: f64,
    /// A unit mesh dashpot's share in the mesh mode, g = (d·φ)²/(φᵀMφ) [1/kg] (ζ = c g/(2ω)):
    /// of the FE modal analysis (driver held, r_b2² φ_hub², mean over the positions; its
    /// frequency is the tied contact's, above the explicit FE's penalty contact, so its ζ is
    /// not the explicit run's) and of the FE-stiffness twin ([`dashpot_share`]). The FE sweep's
    /// models take the FE's share ([`with_dashpot_share`]).
    pub mesh_mode_dashpot_share_fe_modal_per_kg: f64,
    pub mesh_mode_dashpot_share_fe_twin_per_kg: f64,
    /// Only with `--paper-stiffness`.
    pub paper_stiffness: Option<PaperStiffness>,
    /// Only with `--fe-sweep`: the FE speed sweep through the resonance against the lumped
    /// twin ([`super::fe_sweep`]).
    pub fe_sweep: Option<super::fe_sweep::FeSweep>,
    pub model_note: String,
    pub wall_s: f64,
}

/// The explicit scene `compare` runs at each speed, and the one that gives the FE k(θ).
pub const SPEED_SCENE: &str = "high-unmodified";
pub const STIFFNESS_SCENE: &str = "stiffness";

/// The speeds of `speeds` [rpm] that no given run covers: the FE runs still to make.
pub fn speeds_to_run(speeds: &[f64], given_rpm: &[f64]) -> Vec<f64> {
    speeds
        .iter()
        .copied()
        .filter(|rpm| {
            !given_rpm
                .iter()
                .any(|r| super::fe_sweep::same_speed(*r, *rpm))
        })
        .collect()
}

/// The speeds [rpm] of the given `runs` made on the case's own explicit mesh (or not saying
/// which): the speeds compare need not run again and that join the FE sweep's speeds. A run on
/// another mesh does not stand in for the case's mesh: inside the sweep's range it joins the
/// sweep as a mesh level of its own, without adding a speed to run.
pub fn given_rpm_on_case_mesh(case: &Case, runs: &[FeDte]) -> Vec<f64> {
    let case_mesh = Some(case.fe.fine_size * 1e3);
    runs.iter()
        .filter(|r| {
            r.fine_element_mm.is_none() || super::fe_sweep::same_size(r.fine_element_mm, case_mesh)
        })
        .map(|r| r.speed_rpm)
        .collect()
}

/// The case overrides that put [`SPEED_SCENE`] at `rpm`.
pub fn speed_overrides(rpm: f64) -> Vec<crate::case::Override> {
    vec![crate::case::Override::set(
        format!("scene[{SPEED_SCENE}].speed_rpm"),
        rpm,
    )]
}

/// The duration of an FE speed sweep run [s], the longest it runs (it ends earlier once its
/// DTE has settled, [`sweep_speed_overrides`]): near the resonance the FE's response builds
/// up long after the mesh mode's linear decay time (the double-sided contact's slow approach):
/// at 5 275 rpm on 0.7 mm flanks (paper pair, spun up from rest over 10 ms, as the sweep's
/// runs were until 2026-12-07) its rms over 16–30 ms is 277.5 µrad, over 30–40
/// ms 302.3, over 40–50 ms 304.7 (validation/lumped-twin). A 0.05 s run's last third thus reads
/// about 10 % above the 0.03 s run's whole window (277.6), but is not shown settled: 40–45 ms
/// read about 303.3 and 45–50 ms 306.1, still about 1 % up per 5 ms (on 1.0 mm flanks the
/// same speed settles by 30 ms, 2026-11-29). Whether each run settled is measured
/// ([`super::fe_sweep::FeSpeed::settled`]) and a run that did not is named in the summary; a
/// longer duration is a case setting (`scene[high-unmodified].duration_s`), not raised here to
/// keep a sweep of ≥ 8 speeds within a working day on 2 cores.
pub const FE_SWEEP_DURATION_S: f64 = 0.05;

/// The load ramp of an FE speed sweep run [s]: the gears start at the sweep's speed and only
/// the load ramps, on a cosine ([`sweep_speed_overrides`]). Five decay times 1/(ζ ω_n) of the
/// paper pair's mesh mode at the case's ζ = 0.05 (3.1 kHz driver held: 1.0 ms). The ramp's own
/// ringing on that mode is π²/((ω_n t_r)² − π²) = 1.0e-3 of the static response, under
/// [`crate::explicit::scene::SETTLED_RINGING`], so the statistics start at the ramp's end (a
/// pair whose mesh mode is below 1.4 kHz gets the settling time its ringing needs on top,
/// [`crate::explicit::scene::statistics_start`]); what the forced response near the resonance
/// still lacks there (its envelope lags the load by about a decay time) the settled stop waits
/// out.
pub const FE_SWEEP_LOAD_RAMP_S: f64 = 0.005;

/// The case overrides that put [`SPEED_SCENE`] at `rpm` for the FE speed sweep: the gears
/// start turning at that speed and only the load ramps, over [`FE_SWEEP_LOAD_RAMP_S`] on a
/// cosine (as the lumped models start each speed from their static state, not from a
/// spin-up; the scene's 10 ms spin-up from rest was a fifth to a quarter of a sweep run, and
/// its ringing held the statistics back about 6 ms more); the scene's duration raised to
/// [`FE_SWEEP_DURATION_S`] where it is shorter, and the run ended there or earlier, once its
/// DTE has settled (`stop_when_settled`, [`crate::explicit::scene::SettledStop`]): away from
/// the resonance the response settles within a few milliseconds of the ramp, and the sweep
/// reads the settled part only.
pub fn sweep_speed_overrides(case: &Case, rpm: f64) -> Vec<crate::case::Override> {
    use crate::case::Override;
    let key = |field: &str| format!("scene[{SPEED_SCENE}].{field}");
    let mut overrides = speed_overrides(rpm);
    overrides.extend([
        Override::set(key("stop_when_settled"), true),
        Override::set(key("start"), "at-speed"),
        Override::set(key("ramp"), "cosine"),
        Override::set(key("ramp_s"), FE_SWEEP_LOAD_RAMP_S),
    ]);
    let duration = case.scene(SPEED_SCENE).map_or(0.0, |s| s.duration);
    if duration < FE_SWEEP_DURATION_S {
        overrides.push(Override::set(key("duration_s"), FE_SWEEP_DURATION_S));
    }
    overrides
}

/// Each gear body's twist between bore and root circle along the line of action,
/// r_b² φ/T [m/N] ([`crate::geometry::Gear::body_torsional_compliance`]).
pub fn body_twist(case: &Case) -> [f64; 2] {
    std::array::from_fn(|g| {
        let gear = &case.pair.gears[g];
        gear.base_radius.powi(2)
            * gear.body_torsional_compliance(
                case.material.youngs_modulus,
                case.material.poisson_ratio,
            )
    })
}

/// The lumped twin of the explicit FE on `mesh` (hub to hub, as the FE's DTE and the LTCA give
/// it): the pair under `drive` with elastic bodies and nothing else (the FE's boundary
/// conditions: no shafts, no bearings; [`super::lumped::drivetrain_with`]), the bodies' twist
/// (and their rims' sway, where `[lumped] body_sway` gives it them) taken out of `mesh`, mesh
/// force T/r_b2, the FE's mesh dashpot `damping.mesh_n_s_per_m` where
/// the FE has it (on the hub-to-hub TE rate while a flank touches,
/// [`DampingSite::HubTransmissionError`];
/// with elastic bodies it damps the mesh mode 1.29 × as much as the same c on the mesh
/// deflection would: the FE's ζ, not ζ/1.29, paper pair), the bodies' springs with the FE's
/// element damping (c = β k: near the resonance the case's 2 % drivetrain damping ratio on
/// them held the peak about 15 % lower on the paper pair, validation/lumped-twin), and with zero
/// backlash the back flanks engaging with their own mirrored k and e. `elastic = false`: rigid
/// gears behind the whole hub-to-hub k.
///
/// `driver_body_modes` (speed drive, elastic bodies): the FE modal analysis's mesh mode and
/// driver torsion with the driver held at each of its positions [Hz], whose torsion the
/// twin's driver body then carries ([`with_driver_body_mode`]).
pub fn lumped_twin(
    case: &Case,
    mesh: MeshStiffness,
    (law, back_law): (Option<ForceLaw>, Option<ForceLaw>),
    (drive, elastic): (Drive, bool),
    torque: f64,
    damping: FeDamping,
    driver_body_modes: Option<&[(f64, f64)]>,
) -> Result<MeshModel, StudyError> {
    let pair = &case.pair;
    let bodies = match elastic {
        true => BodyModel::Elastic,
        false => BodyModel::Rigid,
    };
    let springs = (
        bodies,
        SpringDamping::StiffnessProportional(damping.stiffness_beta_s),
    );
    let structure = super::lumped::drivetrain_with(case, drive, springs, [None; 2], false)?;
    let twist: f64 = match elastic {
        true => super::lumped::bodies_line_compliance(case, BodyModel::Elastic)?,
        false => 0.0,
    };
    let (mesh, force_law) = super::lumped::to_rims(mesh, law, twist)?;
    let back_force_law = back_law
        .map(|law| super::lumped::law_to_rims(law, twist))
        .transpose()?;
    let model = MeshModel {
        structure,
        back_reflection: Some(super::lumped::back_reflection(pair, &mesh)),
        mesh,
        damping: damping.mesh_n_s_per_m,
        damping_site: DampingSite::HubTransmissionError,
        force: torque / pair.gears[1].base_radius,
        backlash: Some(pair.backlash_normal.max(0.0)),
        force_law,
        back_force_law,
    };
    match (drive, elastic, driver_body_modes) {
        (Drive::Speed, true, Some(modal)) => with_driver_body_mode(case, model, springs.1, modal),
        _ => Ok(model),
    }
}

/// How far from the two-inertia body's own body mode (hub and rim by [`gear_bodies`]'s
/// Rayleigh–Ritz row sums) an FE modal body mode may lie and still be taken for the same mode:
/// ±25 % (paper pair: 2 %; 24/40: 0.2 %). Farther, the FE modal's driver torsion is presumably
/// not the two-inertia body's mode (a body the annulus model does not describe), and the split
/// stays.
///
/// [`gear_bodies`]: super::lumped::gear_bodies
pub const BODY_MODE_MATCH_RANGE: f64 = 0.25;

/// `model`, a twin as [`lumped_twin`] makes it (speed drive, elastic bodies, no shafts or
/// bearings; `springs` their damping), with the driver body's inertia split between hub and
/// rim so that it has the FE modal analysis's driver torsion (driver held: the driver's rim
/// against its held hub). `modal` holds the FE modal's mesh mode and body mode at each of its
/// positions [Hz]. The body is identified where the modal analysis has it: at each position
/// the structure's mesh spring is set to the k at which its mesh mode is the modal's (the
/// modal analysis ties the contact, about 4 % stiffer in frequency than the explicit FE's
/// penalty contact, and a body mode with a share of its energy in the mesh spring moves with
/// it), and the rim's inertia I_r is found by bisection so that the mean over the positions
/// of the structure's body mode there is the modal's mean. The body's total inertia and its
/// torsional compliance stay, so the statics do not move, and the model keeps its own mesh
/// stiffness, at which its body mode then lies below the modal's as the explicit FE's does.
///
/// With the mesh mode held, the body mode falls as I_r grows while ω_mesh² I_r/k_b is small
/// (below about 0.3 for equal gears, 0.1 for a driven gear ten times the rim's inertia; the
/// paper pair is at 0.1): the bisection takes the bracket [1e-3, 1] × the body's inertia only
/// where its ends straddle the target, and the split only where it gives the target back to
/// 1e-6 (elsewhere, e.g. a mode that is not monotone over the bracket, the row sums stay).
///
/// A modal body mode outside [`BODY_MODE_MATCH_RANGE`] of the model's own, or out of reach of
/// any split, keeps the Rayleigh–Ritz row sums (the model's `body_mode_hz` in compare's
/// summary then shows the mode apart from the FE modal's).
///
/// Why: the row sums lump a distributed body's inertia, which puts the driver body's mode
/// 2 % below the FE modal's on the paper pair (the exact mode of the bore-clamped annulus with
/// its teeth as a rigid ring, in the twin at its own stiffness, lies 0.9 % above where the
/// matched twin puts it: the teeth bend). The mode is damped only by the elements' β
/// (ζ ≈ 4e-5), so its super-harmonic resonance j f_mesh = f_b (paper pair: 4 f_mesh near
/// 4 520 rpm) is a needle, and a twin of the FE must put the mode where the FE has it
/// (validation/lumped-twin).
pub fn with_driver_body_mode(
    case: &Case,
    mut model: MeshModel,
    springs: SpringDamping,
    modal: &[(f64, f64)],
) -> Result<MeshModel, StudyError> {
    let hz = |m: &crate::lumped::Mode| m.frequency / std::f64::consts::TAU;
    let k0 = model.linearized().mesh.mean();
    // The structure's body mode where its mesh mode is the modal's `mesh_hz`: the mesh mode
    // rises with k, so k by bisection over [1e-3, 1e3] × the model's mean (log); NaN where
    // the mesh mode is out of that reach.
    let body_at = |structure: &crate::lumped::Structure, mesh_hz: f64| {
        let mesh_at = |k: f64| structure.modes(k).first().map_or(f64::NAN, hz);
        let (mut lo, mut hi) = (1e-3 * k0, 1e3 * k0);
        if !(mesh_at(lo) <= mesh_hz && mesh_at(hi) >= mesh_hz) {
            return f64::NAN;
        }
        for _ in 0..100 {
            let mid = (lo * hi).sqrt();
            match mesh_at(mid) < mesh_hz {
                true => lo = mid,
                false => hi = mid,
            }
        }
        structure
            .body_mode((lo * hi).sqrt(), "rim1 lag")
            .map_or(f64::NAN, |m| hz(&m))
    };
    let mean_body = |structure: &crate::lumped::Structure| {
        modal
            .iter()
            .map(|(mesh, _)| body_at(structure, *mesh))
            .sum::<f64>()
            / modal.len() as f64
    };
    let target = modal.iter().map(|(_, body)| body).sum::<f64>() / modal.len() as f64;
    if modal.is_empty() || !target.is_finite() {
        return Ok(model);
    }
    let own = mean_body(&model.structure);
    if !((target / own - 1.0).abs() <= BODY_MODE_MATCH_RANGE) {
        return Ok(model);
    }
    let gears = super::lumped::gear_bodies(case, BodyModel::Elastic)?;
    let total = gears[0].hub_inertia + gears[0].rim_inertia;
    let with_rim = |rim: f64| {
        let mut split = gears;
        split[0].rim_inertia = rim;
        split[0].hub_inertia = total - rim;
        super::lumped::drivetrain_of(case, Drive::Speed, (split, springs), [None; 2], false)
    };
    let (mut lo, mut hi) = (1e-3 * total, total);
    if !(mean_body(&with_rim(lo)?) >= target && mean_body(&with_rim(hi)?) <= target) {
        return Ok(model);
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        match mean_body(&with_rim(mid)?) > target {
            true => lo = mid,
            false => hi = mid,
        }
    }
    let split = with_rim(0.5 * (lo + hi))?;
    if !((mean_body(&split) / target - 1.0).abs() <= 1e-6) {
        return Ok(model);
    }
    model.structure = split;
    Ok(model)
}

/// The FE-stiffness twin's tables: the LTCA's secant `mesh` and force law `law` (hub to hub,
/// the same positions: [`super::lumped::ltca_tables`]) made to carry `fe`'s k(θ) at the design
/// mesh force `force` [N] ([`ForceLaw::with_secant_at`]), the secant table then `fe`'s k(θ) at
/// those positions. The unloaded TE e(θ) (first contact) stays the LTCA's (the FE's from its
/// DTE is that of the unmodified pair to 1e-3 µm on the paper pair), and so do the back
/// flanks: the drive law's mirror (exact for symmetric teeth without backlash, the FE sweep's
/// pair; with a backlash about 3 % of the STE off where a pair enters, README `force_law`).
pub fn fe_twin_tables(
    (mesh, law): (&MeshStiffness, &ForceLaw),
    fe: &MeshStiffness,
    force: f64,
) -> Result<(MeshStiffness, ForceLaw), StudyError> {
    let n = law.knots.len();
    if mesh.origin != law.origin || mesh.stiffness.values.len() != n {
        return Err(StudyError::Input(format!(
            "the LTCA's secant ({} positions from {:.6} rad) and force law ({n} from {:.6} rad) \
             are not at the same positions: report this case",
            mesh.stiffness.values.len(),
            mesh.origin,
            law.origin
        )));
    }
    // Both tables from the law's origin; `fe` from its own.
    let fe_at = |theta: f64| fe.stiffness.at(law.origin + theta - fe.origin);
    let mut made = law.with_secant_at(force, fe_at).ok_or_else(|| {
        StudyError::Input(format!(
            "the FE's k(θ) ({}) cannot be carried by the LTCA's force law: at some position it \
             is stiffer than the law's stiffest knot can give (check that the FE stiffness is \
             of this pair and load)",
            fe.source
        ))
    })?;
    made.source = format!("{} at the secant of {}", law.source, fe.source);
    let mut secant = mesh.clone();
    for (j, k) in secant.stiffness.values.iter_mut().enumerate() {
        *k = fe_at(j as f64 * law.period / n as f64);
    }
    secant.source = format!("{} at the positions of {}", fe.source, mesh.source);
    Ok((secant, made))
}

/// The share of a unit mesh dashpot in `model`'s mesh mode, g = (d·φ)²/(φᵀMφ) [1/kg] (d the
/// dashpot's direction, φ the mode at the mean stiffness): the dashpot c gives the mode the
/// first-order damping ratio c g/(2ω) ([`MeshModel::mesh_mode_damping_ratio`], less the
/// structure's own). For rigid gears under a speed drive (one coordinate, the dashpot on it) g
/// is 1/m, m = I₂/r_b2².
pub fn dashpot_share(model: &MeshModel) -> f64 {
    let mut unit = model.clone();
    unit.damping = 1.0;
    let with_unit = unit.mesh_mode_damping_ratio();
    unit.damping = 0.0;
    let own = unit.mesh_mode_damping_ratio();
    2.0 * model.structure.mesh_mode(model.mesh.mean()).frequency * (with_unit - own)
}

/// `model` with its dashpot scaled so that its share in the mesh mode times the coefficient
/// equals `share` [1/kg] times the coefficient given ([`dashpot_share`]): the mode's modal
/// damping coefficient c g then equals what the same c gives a mode of share `share` (the FE's,
/// from the FE modal analysis's mass-normalized shape), each mode at its own frequency. A model
/// whose dashpot does not reach its mode (g = 0), or a share that is not positive and finite,
/// keeps its dashpot.
pub fn with_dashpot_share(mut model: MeshModel, share: f64) -> MeshModel {
    let own = dashpot_share(&model);
    if own > 0.0 && share > 0.0 && share.is_finite() {
        model.damping *= share / own;
    }
    model
}

/// An FE run's mesh dashpot along the line of action [N·s/m]: its torsional coefficient on
/// the driven hub over r_b2² (`None`: not recorded).
pub fn run_dashpot(run: &FeDte, rb2: f64) -> Option<f64> {
    run.mesh_damping_n_m_s.map(|c| c / (rb2 * rb2))
}

/// `model`, built for the FE mesh dashpot `built_for` [N·s/m], carrying instead the dashpot
/// `fe_dashpot` [N·s/m] of the FE runs it is held against: its coefficient times their ratio
/// (the share scaling of [`with_dashpot_share`] is linear in it). Each explicit run sizes its
/// dashpot on the LTCA k̄ of its own mesh (`fe.mesh_damping_ratio`, [`crate::study::fe::prepare`]),
/// so runs on finer flanks carry less (paper pair: 3.3 % from 1.0 to 0.25 mm flanks), and near
/// the resonance the fitted peak moves by about 5.5 % per 1 % of it, the rms at the sweep's
/// speeds by about 3 %
/// (validation/lumped-twin): the twin of a run carries the run's own coefficient. `None` (not
/// recorded), or a coefficient that is not positive and finite, keeps the model's.
pub fn with_fe_dashpot(model: &MeshModel, fe_dashpot: Option<f64>, built_for: f64) -> MeshModel {
    let mut model = model.clone();
    if let Some(c) = fe_dashpot.filter(|c| *c > 0.0 && c.is_finite()) {
        if built_for > 0.0 && built_for.is_finite() {
            model.damping *= c / built_for;
        }
    }
    model
}

/// The FE run the headline numbers, the paper-stiffness study and the chart use: the one
/// nearest the speed of the case's `high-unmodified` scene (the seed paper's 3000 rpm), else
/// the first; of several runs at that speed, the one on the finest explicit mesh.
pub fn primary_run(case: &Case, runs: &[FeDte]) -> Option<usize> {
    let target = case
        .scenes
        .iter()
        .find(|s| s.name == SPEED_SCENE)
        .map(|s| s.driver_speed * 60.0 / std::f64::consts::TAU);
    // Among runs at one speed, the one on the finest explicit mesh.
    let finer = |i: usize, j: usize| {
        let size = |k: usize| runs[k].fine_element_mm.unwrap_or(f64::INFINITY);
        match size(j) < size(i) {
            true => j,
            false => i,
        }
    };
    let nearest = match target {
        Some(rpm) => {
            let speeds: Vec<f64> = runs.iter().map(|r| r.speed_rpm).collect();
            crate::signal::nearest_index(&speeds, rpm)?
        }
        None => (!runs.is_empty()).then_some(0)?,
    };
    let speed = runs[nearest].speed_rpm;
    Some(
        (0..runs.len())
            .filter(|&k| super::fe_sweep::same_speed(runs[k].speed_rpm, speed))
            .fold(nearest, finer),
    )
}

/// Refuses FE runs meshed with another tooth layout than the case's (`fe.tooth_layout`): the
/// FE modal and the same-mesh LTCA are of the case's layout, so runs of another would be read
/// against a mesh they did not run on, and mesh levels would mix two meshes of one size.
pub fn runs_of_the_case_layout(case: &Case, runs: &[FeDte]) -> Result<(), StudyError> {
    layouts_of_the_case(
        case,
        runs.iter().map(|r| (r.source.as_str(), r.tooth_layout)),
    )
}

/// [`runs_of_the_case_layout`] for any FE runs, given as (where it is, its layout): the speed
/// runs, the stiffness run compare reads k(θ) from, the accuracy chart's stiffness runs.
pub fn layouts_of_the_case<'a>(
    case: &Case,
    runs: impl IntoIterator<Item = (&'a str, crate::mesh::ToothLayout)>,
) -> Result<(), StudyError> {
    match runs
        .into_iter()
        .find(|(_, layout)| *layout != case.fe.tooth_layout)
    {
        Some((source, layout)) => Err(StudyError::Input(format!(
            "the FE run {source} was meshed with fe.tooth_layout = \"{}\", the case's is \"{}\": give runs of one layout and set the case's to it (--set fe.tooth_layout={})",
            layout.name(),
            case.fe.tooth_layout.name(),
            layout.name()
        ))),
        None => Ok(()),
    }
}

/// Runs the comparison.
pub fn run(
    case: &Case,
    input: &CompareInput,
    positions: usize,
    paper_stiffness: bool,
    progress: Progress,
) -> Result<CompareSummary, StudyError> {
    let started = std::time::Instant::now();
    if positions == 0 {
        return Err(StudyError::Input("--positions must be at least 1".into()));
    }
    runs_of_the_case_layout(case, &input.fe_runs)?;
    if !input.fe_sweep_rpm.is_empty() {
        fe_sweep_runs(&input.fe_runs, &input.fe_sweep_rpm)?;
    }
    let pair = &case.pair;
    let rb = [pair.gears[0].base_radius, pair.gears[1].base_radius];
    let inertias = gear_inertias(case);
    let primary = primary_run(case, &input.fe_runs);
    let torque = primary
        .map(|i| input.fe_runs[i].torque_nm)
        .map_or_else(|| super::load_torque(case), Ok)?;
    // The unmodified pair, whatever the case names its variants (the FE runs are of it).
    let unmodified = [crate::geometry::FlankModification::none(); 2];
    let (fine, coarse) = (case.fe.fine_size, case.fe.coarse_size);
    let model =
        super::ltca::model_with_layout(case, &unmodified, (fine, coarse), case.fe.tooth_layout)?;

    // (c) FE modal analysis, and the LTCA's secant and tangent stiffness at the same positions.
    let modal =
        super::frequencies::modal_at_positions(case, &model, positions, torque, 10, progress)?;
    let mean = |f: &dyn Fn(&PairModes) -> f64, hubs: Hubs| {
        let values: Vec<f64> = modal.iter().filter(|m| m.hubs == hubs).map(f).collect();
        values.iter().sum::<f64>() / values.len() as f64
    };
    let k_secant = mean(&|m| m.ltca_mesh_stiffness, Hubs::DriverHeld);
    let k_tangent = mean(&|m| m.ltca_tangent_stiffness, Hubs::DriverHeld);
    let k_fe = input.fe_stiffness.mean();
    let modal_mean = |hubs| mean(&|m| m.modes[m.mesh_mode].frequency_hz, hubs);
    let held_modal = modal_mean(Hubs::DriverHeld);
    // The driver body's torsional mode, driver held, with the mesh mode at each position (the
    // twins' driver body carries it, [`with_driver_body_mode`]), and its mean.
    let held_modes: Vec<(f64, f64)> = modal
        .iter()
        .filter(|m| m.hubs == Hubs::DriverHeld)
        .filter_map(|m| {
            let body = m.torsion_mode(0)?;
            Some((m.modes[m.mesh_mode].frequency_hz, body.frequency_hz))
        })
        .collect();
    let body_modes = fe_modal_body_modes(&modal);
    let held_body = driver_torsion_hz(&body_modes);
    let held_modes = (!held_modes.is_empty()).then_some(held_modes.as_slice());

    // The lumped model on the FE k(θ), the FE's mesh damping (ζ on the LTCA k̄ and the driven
    // inertia, as the explicit scene sizes it), the back flanks' own k and e.
    let zeta = case.fe.mesh_damping_ratio;
    let damping_of =
        |drive: Drive| 2.0 * zeta * (k_secant * drive.effective_mass(inertias, rb)).sqrt();
    // A unit dashpot's share in the FE modal analysis's mesh mode (driver held): the torsional
    // r_b2² on the driven hub's rotation of the mass-normalized shape, g = r_b2² φ_hub² [1/kg].
    let mesh_mode_dashpot_share_fe_modal = mean(
        &|m| rb[1] * rb[1] * m.mesh_mode_driven_hub_shape.powi(2),
        Hubs::DriverHeld,
    );
    // That dashpot on the FE modal analysis's mesh mode (driver held), first order: the
    // torsional c r_b2² on the driven hub's rotation.
    let mesh_mode_damping_ratio_fe_modal = mean(
        &|m| {
            let omega = std::f64::consts::TAU * m.modes[m.mesh_mode].frequency_hz;
            damping_of(Drive::Speed) * rb[1] * rb[1] * m.mesh_mode_driven_hub_shape.powi(2)
                / (2.0 * omega)
        },
        Hubs::DriverHeld,
    );
    let body_beta = runs_element_damping(&input.fe_runs);
    let fe_damping = |mesh_n_s_per_m: f64| FeDamping {
        mesh_n_s_per_m,
        stiffness_beta_s: body_beta,
    };
    let twin = |drive: Drive, elastic: bool, mesh: MeshStiffness| {
        lumped_twin(
            case,
            mesh,
            (None, None),
            (drive, elastic),
            torque,
            fe_damping(damping_of(drive)),
            held_modes,
        )
    };
    let constant = |k: f64| MeshStiffness::constant("mean", input.fe_stiffness.period(), k);
    // The case's lumped model (its stiffness source and force law on the case's mesh, what
    // `sweep` and `run` integrate), linearized about the design load, on the FE's boundary
    // conditions, frozen at the FE modal's positions, against the FE modal analysis on the
    // case's (converged) mesh at the same positions. (The report's resonance speeds come from
    // the mode at the mean stiffness, which the frequencies' summary gives beside it.)
    let converged = super::frequencies::mesh_modes(case, CASE_MESH_MODAL_POSITIONS, progress)?;
    let twist: f64 = body_twist(case).iter().sum();
    let frequencies = |hubs: Hubs, drive: Drive| -> Result<Frequencies, StudyError> {
        let elastic = twin(drive, true, input.fe_stiffness.clone())?;
        let m = elastic.effective_mass();
        let hz = |k: f64| (k / m).sqrt() / std::f64::consts::TAU;
        // The structure's mesh mode with the hub-to-hub k̄ taken to the rims.
        let elastic_of = |k: f64| -> Result<f64, StudyError> {
            Ok(twin(drive, true, constant(k))?.natural_frequency() / std::f64::consts::TAU)
        };
        let on_case_mesh = match hubs {
            Hubs::DriverHeld => &converged.driver_held,
            Hubs::BothFree => &converged.both_free,
        };
        let elastic_hz = elastic.natural_frequency() / std::f64::consts::TAU;
        let floquet_hz = input
            .fe_runs
            .iter()
            .map(|r| {
                let speed = r.speed_rpm * std::f64::consts::TAU / 60.0;
                let steps = crate::sweep::steps_per_period(&elastic, speed);
                // Undamped: the parametric shift alone, comparable with the modal.
                let undamped = MeshModel {
                    damping: 0.0,
                    ..elastic.clone()
                };
                let w = floquet_frequency(&undamped, speed, steps);
                (r.speed_rpm, w / std::f64::consts::TAU)
            })
            .collect();
        let fe_modal_hz = modal
            .iter()
            .filter(|p| p.hubs == hubs)
            .map(|p| {
                (
                    p.driver_rotation.to_degrees(),
                    p.modes[p.mesh_mode].frequency_hz,
                )
            })
            .collect();
        let fe_modal_mean_hz = modal_mean(hubs);
        Ok(Frequencies {
            hubs,
            effective_mass_kg: m,
            lumped_ltca_secant_hz: hz(k_secant),
            lumped_ltca_tangent_hz: hz(k_tangent),
            lumped_fe_hz: hz(k_fe),
            body_twist_m_per_n: twist,
            lumped_fe_elastic_hz: elastic_hz,
            lumped_ltca_elastic_hz: elastic_of(k_secant)?,
            lumped_ltca_tangent_elastic_hz: elastic_of(k_tangent)?,
            lumped_model_hz: on_case_mesh.lumped_hz,
            fe_modal_case_mesh_mean_hz: on_case_mesh.fe_modal_mean_hz,
            floquet_hz,
            fe_modal_hz,
            fe_modal_mean_hz,
            lumped_fe_over_modal_rel: hz(k_fe) / fe_modal_mean_hz - 1.0,
            lumped_fe_elastic_over_modal_rel: elastic_hz / fe_modal_mean_hz - 1.0,
            lumped_model_over_modal_rel: on_case_mesh.lumped_rel,
        })
    };
    let driver_held = frequencies(Hubs::DriverHeld, Drive::Speed)?;
    let both_free = frequencies(Hubs::BothFree, Drive::Torque)?;

    // (d), (e) per FE speed: the explicit FE holds the driver's bore and drives a light driven
    // hub, so its lumped twin is the speed drive with elastic bodies.
    // The elastic twin's dashpot acts on its mesh mode as the FE's on the FE modal's (the same
    // c g, [`with_dashpot_share`]), here as in the FE sweep; the FE's own coefficient on it
    // gives `mesh_mode_damping_ratio_fe_twin`.
    let with_fe_coefficient = twin(Drive::Speed, true, input.fe_stiffness.clone())?;
    let rim_model = with_dashpot_share(
        with_fe_coefficient.clone(),
        mesh_mode_dashpot_share_fe_modal,
    );
    let rigid_model = twin(Drive::Speed, false, input.fe_stiffness.clone())?;
    let teeth = pair.gears[0].teeth() as f64;
    let speeds: Vec<SpeedComparison> = input
        .fe_runs
        .iter()
        .map(|run| {
            // Each run's twins with its own dashpot.
            let own = |model: &MeshModel| {
                with_fe_dashpot(model, run_dashpot(run, rb[1]), damping_of(Drive::Speed))
            };
            compare_speed(
                run,
                [&own(&rim_model), &own(&rigid_model)],
                teeth,
                rb[1],
                (held_modal, held_body),
            )
        })
        .collect::<Result<_, _>>()?;
    let fe_sweep = match input.fe_sweep_rpm.as_slice() {
        [] => None,
        rpms => {
            // The default lumped model of the unmodified pair (the LTCA's load-dependent force
            // law on the case's mesh, the back flanks' own where the pair has backlash) on the
            // FE's boundary conditions and damping.
            progress("lumped model of the FE sweep", 0, 1);
            let laws =
                super::lumped::ltca_laws(case, &unmodified, torque, "ltca (relief none)", true)?;
            // Each model's dashpot acts on its mesh mode as the FE's on the FE modal analysis's
            // mesh mode (the same modal damping coefficient c g, [`with_dashpot_share`]): the
            // shares differ by under 1 % (paper pair: the FE's 0.8 % larger), but near the
            // resonance, where the teeth swing onto their back flanks, the response's peak moves
            // by about 3.5 % per 1 % of ζ (validation/lumped-twin).
            let case_model = with_dashpot_share(
                lumped_twin(
                    case,
                    laws.mesh.clone(),
                    (Some(laws.law.clone()), laws.back_law),
                    (Drive::Speed, true),
                    torque,
                    fe_damping(damping_of(Drive::Speed)),
                    held_modes,
                )?,
                mesh_mode_dashpot_share_fe_modal,
            );
            // The FE's own k(θ) at the design load with the LTCA's stiffening about it: the
            // twin of the explicit FE's stiffness (its low-speed DTE) that the secant FE twin
            // cannot be near the resonance, where the load swings far from the design load.
            let law_twin = |target: &MeshStiffness| -> Result<MeshModel, StudyError> {
                let (mesh, law) = fe_twin_tables((&laws.mesh, &laws.law), target, torque / rb[1])?;
                Ok(with_dashpot_share(
                    lumped_twin(
                        case,
                        mesh,
                        (Some(law), None),
                        (Drive::Speed, true),
                        torque,
                        fe_damping(damping_of(Drive::Speed)),
                        held_modes,
                    )?,
                    mesh_mode_dashpot_share_fe_modal,
                ))
            };
            let fe_law_model = law_twin(&input.fe_stiffness)?;
            // The case's law at the FE's mean stiffness (its ripple and load dependence the
            // LTCA's): what the case's model misses against the FE for the FE mesh's own
            // stiffness (an explicit mesh converges from the stiff side) and what it misses as
            // a model, apart.
            let fe_mean_model = law_twin(&laws.mesh.scaled_to_mean(input.fe_stiffness.mean()))?;
            progress("FE sweep against the lumped models", 0, 1);
            let models = [
                (
                    "case_model",
                    "lumped model (LTCA force law, elastic bodies)",
                    &case_model,
                ),
                (
                    "fe_k_twin",
                    "FE-stiffness twin (the FE's k(θ), secant)",
                    &rim_model,
                ),
                (
                    "fe_k_law_twin",
                    "FE-stiffness twin (the FE's k(θ) with the LTCA's load dependence)",
                    &fe_law_model,
                ),
                (
                    "case_model_fe_mean",
                    "lumped model at the FE's mean stiffness (the LTCA's ripple and load dependence)",
                    &fe_mean_model,
                ),
            ];
            Some(fe_sweep(
                case,
                input,
                (&models, damping_of(Drive::Speed)),
                (rpms, &body_modes),
            )?)
        }
    };
    let first = primary.map(|i| &speeds[i]);
    let paper = match (paper_stiffness, primary) {
        (false, _) => None,
        (true, None) => {
            return Err(StudyError::Input(
                "--paper-stiffness needs an FE run (its speed and window)".into(),
            ))
        }
        (true, Some(i)) => Some(paper_stiffness_study(
            &with_fe_dashpot(
                &rigid_model,
                run_dashpot(&input.fe_runs[i], rb[1]),
                damping_of(Drive::Speed),
            ),
            inertias,
            rb,
            teeth,
            &input.fe_runs[i],
        )?),
    };
    Ok(CompareSummary {
        case: case.name().to_string(),
        f_mesh_hz: first.map_or(f64::NAN, |s| s.mesh_hz),
        f_natural_lumped_hz: both_free.lumped_model_hz,
        f_natural_fe_modal_hz: both_free.fe_modal_case_mesh_mean_hz,
        f_natural_lumped_driver_held_hz: driver_held.lumped_model_hz,
        f_natural_fe_modal_driver_held_hz: driver_held.fe_modal_case_mesh_mean_hz,
        fe_dte_peaks_hz: first.map_or(Vec::new(), |s| s.fe_peaks.iter().map(|p| p.frequency_hz).collect()),
        lumped_dte_peaks_hz: first.map_or(Vec::new(), |s| {
            let mut lines: Vec<(f64, f64)> = s
                .lumped_harmonics_rad
                .iter()
                .enumerate()
                .map(|(n, a)| ((n + 1) as f64 * s.mesh_hz, *a))
                .collect();
            lines.sort_by(|a, b| b.1.total_cmp(&a.1));
            lines.iter().map(|l| l.0).collect()
        }),
        mean_stiffness_ltca_n_per_m: k_secant,
        mean_tangent_stiffness_ltca_n_per_m: k_tangent,
        mean_stiffness_fe_n_per_m: k_fe,
        fe_stiffness_source: input.fe_stiffness.source.clone(),
        driver_held,
        both_free,
        speeds,
        modal,
        mesh_damping_n_s_per_m: damping_of(Drive::Speed),
        twin_body_damping_beta_s: body_beta,
        mesh_mode_damping_ratio_fe_twin: with_fe_coefficient.mesh_mode_damping_ratio(),
        mesh_mode_damping_ratio_fe_modal,
        mesh_mode_dashpot_share_fe_modal_per_kg: mesh_mode_dashpot_share_fe_modal,
        mesh_mode_dashpot_share_fe_twin_per_kg: dashpot_share(&rim_model),
        paper_stiffness: paper,
        fe_sweep,
        model_note: format!(
            "FE modal: the explicit FE's mesh ({:.2} mm flanks, {:.2} mm body), consistent mass, hubs rigid with the bore nodes' inertia, the LTCA's active contact points tied along their normals, relief none, {positions} positions; lumped twin of the FE: elastic bodies (hub and rim, the bodies' twist out of the FE's hub-to-hub k), speed drive, no shafts or bearings (I = {:.4e} / {:.4e} kg m2), k(theta) from the FE DTE, the dashpot of zeta = {zeta} on the LTCA k and the driven inertia scaled to the FE modal mesh mode's share of it, the bodies' springs with the FE's element damping (c = beta k, beta = {:.3e} s; not the case's drivetrain damping ratio), back flanks with their own k and e",
            fine * 1e3,
            coarse * 1e3,
            inertias[0],
            inertias[1],
            body_beta,
        ),
        wall_s: started.elapsed().as_secs_f64(),
    })
}

/// The FE run's spectra and harmonics against the lumped steady state at its speed.
fn compare_speed(
    run: &FeDte,
    [model, rigid]: [&MeshModel; 2],
    teeth: f64,
    rb2: f64,
    (mesh_mode_hz, body_hz): (f64, Option<f64>),
) -> Result<SpeedComparison, StudyError> {
    let mesh_hz = run.speed_rpm / 60.0 * teeth;
    let (ramp, stats) = run.window_starts();
    let end = run.dte.len();
    let late = &run.dte[stats..end];
    // Early: the ringing after the ramp, or the first half after it when that is too short.
    let min_len = (3.0 / (mesh_hz * run.dt)).ceil() as usize;
    let early_end = if stats - ramp >= min_len {
        stats
    } else {
        ramp + (end - ramp) / 2
    };
    let early = &run.dte[ramp..early_end];
    let fe_spectrum = hann_amplitude_spectrum(late, run.dt);
    let fe_early_spectrum = hann_amplitude_spectrum(early, run.dt);
    let resolution_hz = 1.0 / (late.len().max(1) as f64 * run.dt);
    let label =
        |f: f64, resolution: f64| label_line(f, mesh_hz, mesh_mode_hz, body_hz, 1.5 * resolution);
    let peaks = |spectrum: &[(f64, f64)], resolution: f64| {
        spectrum_peaks(spectrum, 0.5 * mesh_hz, PEAKS)
            .into_iter()
            .map(|(f, a)| Peak {
                frequency_hz: f,
                amplitude_rad: a,
                label: label(f, resolution),
            })
            .collect::<Vec<_>>()
    };
    let fe_peaks = peaks(&fe_spectrum, resolution_hz);
    let early_resolution = 1.0 / (early.len().max(1) as f64 * run.dt);
    let fe_early_peaks = peaks(&fe_early_spectrum, early_resolution);
    let fe_harmonics_rad = harmonic_amplitudes(late, run.dt, mesh_hz, HARMONICS);

    let speed = run.speed_rpm * std::f64::consts::TAU / 60.0;
    let harmonics = |model: &MeshModel| {
        let steps = crate::sweep::steps_per_period(model, speed);
        let steady = steady_state(model, speed, steps, model.static_state(), 1e-9, 2000);
        let lines = amplitude_spectrum(&steady.displacement);
        // A response that grew without bound has no amplitudes: NaN, flagged, not fatal (the
        // FE's outcome there is what the user came for).
        let lost = if steady.diverged { f64::NAN } else { 1.0 };
        let rms = lost * crate::signal::rms_about_mean(&steady.displacement) / rb2;
        let amplitudes: Vec<f64> = (0..HARMONICS)
            .map(|n| lost * lines.get(n).copied().unwrap_or(0.0) / rb2)
            .collect();
        let errors: Vec<f64> = amplitudes
            .iter()
            .zip(&fe_harmonics_rad)
            .map(|(l, f)| l / f - 1.0)
            .collect();
        (steady, amplitudes, errors, rms)
    };
    let (steady, lumped_harmonics_rad, harmonic_error_rel, lumped_dte_rms_rad) = harmonics(model);
    let (_, lumped_rigid_harmonics_rad, rigid_harmonic_error_rel, _) = harmonics(rigid);
    Ok(SpeedComparison {
        speed_rpm: run.speed_rpm,
        mesh_hz,
        source: run.source.clone(),
        resolution_hz,
        late_window_s: (stats as f64 * run.dt, end as f64 * run.dt),
        early_window_s: (ramp as f64 * run.dt, early_end as f64 * run.dt),
        fe_peaks,
        fe_early_peaks,
        fe_dte_rms_rad: crate::signal::rms_about_mean(late),
        fe_harmonics_rad,
        lumped_harmonics_rad,
        lumped_dte_rms_rad,
        harmonic_error_rel,
        lumped_rigid_harmonics_rad,
        rigid_harmonic_error_rel,
        lumped_converged: steady.converged,
        lumped_separated: steady.separated,
        lumped_diverged: steady.diverged,
        mesh_over_mode: mesh_hz / mesh_mode_hz,
        fe_spectrum,
        fe_early_spectrum,
    })
}

/// The runs of `fe_runs` that join the FE speed sweep over `rpms`: every run inside the sweep's
/// range, on any mesh (runs on other explicit meshes form their own mesh levels). Two runs at
/// one speed on one mesh are refused: they would weigh that speed twice in the fits and leave
/// the extrapolation to pick one of them silently. Checked before any FE run is made.
pub fn fe_sweep_runs<'a>(fe_runs: &'a [FeDte], rpms: &[f64]) -> Result<Vec<&'a FeDte>, StudyError> {
    let (lo, hi) = rpms
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(l, h), r| (l.min(*r), h.max(*r)));
    let inside: Vec<&FeDte> = fe_runs
        .iter()
        .filter(|run| run.speed_rpm >= lo * (1.0 - 1e-6) && run.speed_rpm <= hi * (1.0 + 1e-6))
        .collect();
    for (i, a) in inside.iter().enumerate() {
        if let Some(b) = inside[i + 1..].iter().find(|b| {
            super::fe_sweep::same_speed(a.speed_rpm, b.speed_rpm)
                && super::fe_sweep::same_size(a.fine_element_mm, b.fine_element_mm)
        }) {
            return Err(StudyError::Input(format!(
                "--fe-sweep: {} and {} are both FE runs at {:.1} rpm on the same mesh ({}): give one run per speed and flank size",
                a.source,
                b.source,
                a.speed_rpm,
                a.fine_element_mm
                    .map_or("flank size not recorded".to_string(), |mm| format!("{mm} mm flanks")),
            )));
        }
    }
    Ok(inside)
}

/// The FE modal analysis's body modes with the driver held, each kind's mean frequency over
/// the positions where it is found, of the kinds found at half of them or more: first the
/// driver body's torsion ([`PairModes::torsion_mode`], what the twins' driver body carries),
/// then the other body modes the mesh drives ([`PairModes::excited_body_modes`]: the driven
/// gear's torsion, the lateral modes along the line of action).
pub fn fe_modal_body_modes(modal: &[PairModes]) -> Vec<super::fe_sweep::BodyMode> {
    let held: Vec<&PairModes> = modal
        .iter()
        .filter(|m| m.hubs == Hubs::DriverHeld)
        .collect();
    let mean_of = |kind: &str, hz: Vec<f64>| {
        (!hz.is_empty() && 2 * hz.len() >= held.len())
            .then(|| super::fe_sweep::BodyMode::new(kind, hz.iter().sum::<f64>() / hz.len() as f64))
    };
    let torsion_kind = crate::ltca::modal::BODY_MODE_KINDS[0];
    let torsion = held
        .iter()
        .filter_map(|m| m.torsion_mode(0).map(|b| b.frequency_hz))
        .collect();
    let driven = crate::ltca::modal::ALL_BODY_MODE_KINDS
        .iter()
        .filter(|kind| **kind != torsion_kind)
        .filter_map(|kind| {
            let hz = held
                .iter()
                .filter_map(|m| {
                    m.excited_body_modes()
                        .into_iter()
                        .find(|b| b.kind == *kind)
                        .map(|b| b.frequency_hz)
                })
                .collect();
            mean_of(kind, hz)
        });
    mean_of(torsion_kind, torsion)
        .into_iter()
        .chain(driven)
        .collect()
}

/// The driver body's torsion among `modes` [Hz] ([`fe_modal_body_modes`]).
pub fn driver_torsion_hz(modes: &[super::fe_sweep::BodyMode]) -> Option<f64> {
    modes
        .iter()
        .find(|m| m.kind == crate::ltca::modal::BODY_MODE_KINDS[0])
        .map(|m| m.hz)
}

/// The FE runs of `input` at `rpms` against `models` (built for the FE mesh dashpot
/// `models_dashpot` [N·s/m]), the case's model first, with the body modes the mesh drives in
/// the FE modal analysis, driver held, `body_modes` ([`super::fe_sweep::run`]).
fn fe_sweep(
    case: &Case,
    input: &CompareInput,
    (models, models_dashpot): (&[(&str, &str, &MeshModel)], f64),
    (rpms, body_modes): (&[f64], &[super::fe_sweep::BodyMode]),
) -> Result<super::fe_sweep::FeSweep, StudyError> {
    let rb2 = case.pair.gears[1].base_radius;
    let back_contact = -case.pair.backlash_normal.max(0.0) / rb2;
    let teeth = case.pair.gears[0].teeth() as f64;
    let inside = fe_sweep_runs(&input.fe_runs, rpms)?;
    let mut fe: Vec<super::fe_sweep::FeSpeed> = inside
        .into_iter()
        // A back-flank force above 1e-3 of the static mesh force counts as contact.
        .map(|run| {
            let threshold = 1e-3 * run.torque_nm / rb2;
            super::fe_sweep::FeSpeed {
                mesh_damping_n_s_per_m: run_dashpot(run, rb2),
                ..super::fe_sweep::FeSpeed::measure(run, teeth, back_contact, threshold)
            }
        })
        .collect();
    fe.sort_by(|a, b| a.speed_rpm.total_cmp(&b.speed_rpm));
    let decay_time = 1.0 / (case.fe.mesh_damping_ratio * models[0].2.natural_frequency());
    let body = Some((teeth, body_modes));
    super::fe_sweep::run(fe, models, rb2, models_dashpot, decay_time, body).ok_or_else(|| {
        StudyError::Input(
            "--fe-sweep needs at least three FE speeds with a mesh-harmonic response, and lumped models that settle at three of four times as many".into(),
        )
    })
}

/// Speeds of the FE speed sweep `run --full` makes.
pub const FE_SWEEP_SPEEDS: usize = 9;

/// The FE speed sweep of `run --full`: [`FE_SWEEP_SPEEDS`] driver speeds from 0.8 to 1.2 × the
/// speed-driven pair's resonance (f_mesh = f_n of the case's lumped model on the explicit FE's
/// boundary: speed drive, no shafts or bearings; within 1 % of the FE modal analysis on the
/// paper pair, validation/frequencies), to 10 rpm.
pub fn fe_sweep_speeds(case: &Case) -> Result<Vec<f64>, StudyError> {
    let mut on_fe_boundary = case.clone();
    on_fe_boundary.lumped.drive = Drive::Speed;
    on_fe_boundary.lumped.shafts = [None; 2];
    on_fe_boundary.lumped.bearings = false;
    let setup = super::lumped::setup(&on_fe_boundary)?;
    let resonance = super::lumped::speed_for_mesh_frequency(case, setup.natural_frequency_hz);
    Ok((0..FE_SWEEP_SPEEDS)
        .map(|i| {
            let factor = 0.8 + 0.4 * i as f64 / (FE_SWEEP_SPEEDS - 1) as f64;
            (factor * resonance / 10.0).round() * 10.0
        })
        .collect())
}

/// The speeds of an FE speed sweep on `grid` (ascending, [`fe_sweep_speeds`]) with compare's
/// own speeds `asked` and the finished runs `given` on the case's explicit mesh: those inside
/// the grid's range join the sweep; an asked speed, which compare runs as a sweep speed
/// ([`sweep_speed_overrides`]), takes the place of an inner grid speed within a quarter of the
/// grid's spacing (two runs 10 rpm apart tell the resonance fit what one does, at twice the
/// cost), while a given run (of whatever duration) only joins, and the grid's ends stay, so
/// that the range is the grid's. Ascending, each speed once.
pub fn sweep_speeds_with(grid: &[f64], asked: &[f64], given: &[f64]) -> Vec<f64> {
    let (Some(&from), Some(&to)) = (grid.first(), grid.last()) else {
        return Vec::new();
    };
    let spacing = (to - from) / (grid.len().max(2) - 1) as f64;
    let inside = |speeds: &[f64]| -> Vec<f64> {
        speeds
            .iter()
            .copied()
            .filter(|rpm| (from..=to).contains(rpm))
            .collect()
    };
    let (asked, given) = (inside(asked), inside(given));
    let last = grid.len() - 1;
    let speeds: Vec<f64> = grid
        .iter()
        .enumerate()
        .filter(|&(i, g)| {
            i == 0
                || i == last
                || !asked
                    .iter()
                    .any(|r| (r - g).abs() < 0.25 * spacing && !super::fe_sweep::same_speed(*r, *g))
        })
        .map(|(_, g)| *g)
        .chain(asked.iter().copied())
        .chain(given.iter().copied())
        .collect();
    super::fe_sweep::distinct_speeds(speeds)
}

/// The first resonance speed's reference for the accuracy chart: the explicit FE's speed sweep
/// (each run's first harmonic read over its window's last third), when compare ran one, else
/// the FE modal analysis on the case's mesh, driver held (the explicit FE's boundary), with its
/// difference to the modal analysis on the explicit FE's mesh as the uncertainty. Of the sweep:
/// with three meshes whose fitted peaks converge monotonically, their resonance extrapolated to
/// zero flank size ([`super::fe_sweep::ExtrapolatedFe::resonance_rpm`]), made undamped with the
/// headline mesh's fitted ζ (n_n = n_peak/√(1 − 2ζ²); the meshes' own ζ differ by about 0.005
/// on the paper pair, about 1 rpm here), uncertain by the larger of the extrapolation's and the
/// headline fit's jackknife; else the headline (finest fitted with four speeds) mesh's
/// undamped resonance, uncertain by the larger of its jackknife and the FE's shift under its
/// last refinement ([`super::fe_sweep::refinement_shift_rpm`]) where there are two meshes.
pub fn resonance_reference(
    case: &Case,
    summary: &CompareSummary,
) -> super::accuracy::ResonanceReference {
    let per_hz = 60.0 / case.pair.gears[0].teeth() as f64;
    match &summary.fe_sweep {
        Some(sweep) => {
            let jackknife = sweep.undamped_resonance_rpm_fe_uncertainty;
            let extrapolated = sweep
                .extrapolated
                .as_ref()
                .map(|e| (e.resonance_rpm, e.fine_element_mm))
                .filter(|(r, _)| {
                    r.order.is_some() && r.value.is_finite() && r.uncertainty.is_finite()
                });
            let zeta = sweep.fitted_damping_ratio_fe;
            match (extrapolated, super::fe_sweep::refinement_shift_rpm(sweep)) {
                (Some((r, [h1, h2, h3])), _) => (
                    r.value / (1.0 - 2.0 * zeta * zeta).max(1e-12).sqrt(),
                    jackknife.max(r.uncertainty),
                    format!(
                        "explicit FE speed sweep on {h1:.2} / {h2:.2} / {h3:.2} mm flanks, the fitted one-DOF responses' resonance extrapolated to zero flank size (observed order {:.2}), made undamped with the headline ({}) mesh's fitted ζ = {zeta:.4}; uncertainty: the larger of the extrapolation's ({:.1} rpm) and the headline fit's leave-one-out jackknife ({jackknife:.1} rpm)",
                        r.order.unwrap_or(f64::NAN),
                        sweep.fine_element_mm.map_or("unrecorded".into(), |mm| format!("{mm:.2} mm")),
                        r.uncertainty
                    ),
                ),
                (None, Some(shift)) => (
                    sweep.undamped_resonance_rpm_fe,
                    jackknife.max(shift.abs()),
                    format!(
                        "explicit FE speed sweep ({} speeds) on its finest mesh, the fitted one-DOF response's undamped resonance; uncertainty: the larger of its leave-one-out jackknife ({jackknife:.1} rpm) and the resonance's shift from the next coarser mesh over the speeds both ran ({shift:+.1} rpm)",
                        sweep.fe.len()
                    ),
                ),
                (None, None) => (
                    sweep.undamped_resonance_rpm_fe,
                    jackknife,
                    format!(
                        "explicit FE speed sweep ({} speeds), the fitted one-DOF response's undamped resonance; uncertainty: its leave-one-out jackknife",
                        sweep.fe.len()
                    ),
                ),
            }
        }
        None => {
            let held = &summary.driver_held;
            (
                per_hz * held.fe_modal_case_mesh_mean_hz,
                per_hz * (held.fe_modal_case_mesh_mean_hz - held.fe_modal_mean_hz).abs(),
                "FE modal analysis of the meshed pair on the case's mesh, driver held (f_mesh = f_n); uncertainty: its difference to the explicit FE's mesh".into(),
            )
        }
    }
}

/// The error of a lumped steady state that grew without bound at `speed_rpm`.
pub fn lumped_diverged(speed_rpm: f64) -> StudyError {
    StudyError::Input(format!(
        "the lumped twin's response at {speed_rpm:.0} rpm grew without bound (1000 static \
         deflections): the speed lies in a parametric-instability region or on an undamped \
         resonance; raise fe.mesh_damping_ratio (the twin's damping) or choose another speed"
    ))
}

/// The lumped speed-drive model `model` with a compliance in series that brings its mean
/// stiffness to [`PAPER_MEAN_STIFFNESS`], run for 0.03 s at `speed_rpm`.
fn paper_stiffness_study(
    model: &MeshModel,
    inertias: [f64; 2],
    rb: [f64; 2],
    teeth: f64,
    run: &FeDte,
) -> Result<PaperStiffness, StudyError> {
    let speed_rpm = run.speed_rpm;
    if !(model.mesh.mean() > PAPER_MEAN_STIFFNESS) {
        return Err(StudyError::Input(format!(
            "the FE mean stiffness {:.4e} N/m is not above the paper's {PAPER_MEAN_STIFFNESS:.4e} N/m: no compliance in series can bring it there",
            model.mesh.mean()
        )));
    }
    let softened = |c: f64| {
        let mut mesh = model.mesh.clone();
        mesh.stiffness
            .values
            .iter_mut()
            .for_each(|k| *k = 1.0 / (1.0 / *k + c));
        mesh
    };
    // The mean falls monotonically with c: bisection on [0, 1/k_paper].
    let (mut lo, mut hi) = (0.0, 1.0 / PAPER_MEAN_STIFFNESS);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if softened(mid).mean() > PAPER_MEAN_STIFFNESS {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let c = 0.5 * (lo + hi);
    let mut paper = model.clone();
    paper.mesh = softened(c);
    paper.mesh.source = format!(
        "paper-stiffness: {} + {c:.4e} m/N in series",
        model.mesh.source
    );
    let k = paper.mesh.mean();
    paper.damping = model.damping * (k / model.mesh.mean()).sqrt();
    let hz = |m: f64| (k / m).sqrt() / std::f64::consts::TAU;
    let (f_both_free_hz, f_driver_held_hz) = (
        hz(Drive::Torque.effective_mass(inertias, rb)),
        hz(Drive::Speed.effective_mass(inertias, rb)),
    );
    let speed = speed_rpm * std::f64::consts::TAU / 60.0;
    let mesh_hz = speed_rpm / 60.0 * teeth;
    // As long as the FE run, split where its statistics start.
    let duration = run.dt * run.dte.len() as f64;
    let record = crate::lumped::run_up(&paper, speed, speed, duration, 30_000);
    let dt = record.time[1] - record.time[0];
    let split = ((run.statistics_start_s / dt) as usize).min(record.time.len());
    let dte: Vec<f64> = record.displacement.iter().map(|p| p / rb[1]).collect();
    let (early, late) = dte.split_at(split);
    let late_spectrum = hann_amplitude_spectrum(late, dt);
    let early_spectrum = hann_amplitude_spectrum(early, dt);
    let peaks = |spectrum: &[(f64, f64)], length: usize| {
        let resolution = 1.0 / (length.max(1) as f64 * dt);
        spectrum_peaks(spectrum, 0.5 * mesh_hz, PEAKS)
            .into_iter()
            .map(|(f, a)| Peak {
                frequency_hz: f,
                amplitude_rad: a,
                label: label_line(f, mesh_hz, f_driver_held_hz, None, 1.5 * resolution),
            })
            .collect()
    };
    Ok(PaperStiffness {
        note: format!(
            "PAPER-STIFFNESS STUDY, not our prediction: the FE k(theta) with {c:.4e} m/N in series so that its mean is the seed paper's {PAPER_MEAN_STIFFNESS:.4e} N/m; lumped, rigid gears, speed drive, the FE's damping ratio"
        ),
        series_compliance_m_per_n: c,
        mean_stiffness_n_per_m: k,
        f_both_free_hz,
        f_driver_held_hz,
        speed_rpm,
        mesh_hz,
        late_peaks: peaks(&late_spectrum, late.len()),
        early_peaks: peaks(&early_spectrum, early.len()),
        late_spectrum,
        early_spectrum,
    })
}

/// Names a spectral line: the nearest of n·f_m (n = 1 … 8), f_n and n·f_m ± f_n (n = 1 … 4),
/// and the driver body's torsion f_b when given, within `tolerance` [Hz], or `?`.
pub fn label_line(
    f: f64,
    mesh_hz: f64,
    mode_hz: f64,
    body_hz: Option<f64>,
    tolerance: f64,
) -> String {
    let mut candidates: Vec<(f64, String)> = (1..=8)
        .map(|n| (n as f64 * mesh_hz, format!("{n} f_m")))
        .collect();
    candidates.push((mode_hz, "f_n".into()));
    if let Some(b) = body_hz {
        candidates.push((b, "f_b".into()));
    }
    for n in 1..=4 {
        let base = n as f64 * mesh_hz;
        candidates.push((base + mode_hz, format!("{n} f_m + f_n")));
        candidates.push(((base - mode_hz).abs(), format!("{n} f_m - f_n")));
    }
    candidates
        .into_iter()
        .filter(|(c, _)| (c - f).abs() <= tolerance)
        .min_by(|a, b| (a.0 - f).abs().total_cmp(&(b.0 - f).abs()))
        .map_or_else(|| "?".into(), |(_, name)| name)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// An FE run meshed with another tooth layout than the case's is refused before anything
    /// runs, with both layouts named.
    #[test]
    fn runs_of_another_tooth_layout_are_refused() {
        use crate::mesh::ToothLayout;
        let case = crate::samples::paper36_case();
        let run = |layout| FeDte {
            source: "a run".into(),
            speed_rpm: 3000.0,
            torque_nm: 143.6,
            fine_element_mm: Some(1.0),
            tooth_layout: layout,
            dt: 1e-5,
            dte: Vec::new(),
            back_flank_force: Vec::new(),
            ramp_end_s: 0.0,
            statistics_start_s: 0.0,
            wall_s: 0.0,
            stiffness_damping_beta_s: None,
            mesh_damping_n_m_s: None,
        };
        let input = |layout| CompareInput {
            fe_runs: vec![run(layout)],
            fe_sweep_rpm: Vec::new(),
            fe_stiffness: MeshStiffness::constant("constant", 0.17, 4e8),
        };
        let message = |layout| match run_compare(&case, &input(layout)) {
            Err(StudyError::Input(message)) => message,
            other => panic!("expected an input error, got {:?}", other.map(|_| ())),
        };
        // The layout the case does not use, whichever its default.
        let other = match case.fe.tooth_layout {
            ToothLayout::Graded => ToothLayout::StableStep,
            ToothLayout::StableStep => ToothLayout::Graded,
        };
        let refused = message(other);
        assert!(
            refused.contains(&format!("fe.tooth_layout = \"{}\"", other.name()))
                && refused.contains(&format!(
                    "the case's is \"{}\"",
                    case.fe.tooth_layout.name()
                )),
            "{refused}"
        );
    }

    /// Any FE run given as (where, layout): the first of another layout than the case's is
    /// named in the refusal.
    #[test]
    fn layouts_of_the_case_name_the_run_of_another() {
        let case = crate::samples::paper36_case();
        let own = case.fe.tooth_layout;
        let other = match own {
            crate::mesh::ToothLayout::Graded => crate::mesh::ToothLayout::StableStep,
            crate::mesh::ToothLayout::StableStep => crate::mesh::ToothLayout::Graded,
        };
        assert!(layouts_of_the_case(&case, [("a", own), ("b", own)]).is_ok());
        let refused = layouts_of_the_case(&case, [("a", own), ("chart/fe-0.7mm", other)])
            .unwrap_err()
            .to_string();
        assert!(refused.contains("chart/fe-0.7mm"), "{refused}");
        assert!(
            refused.contains(&format!("fe.tooth_layout={}", other.name())),
            "{refused}"
        );
    }

    fn run_compare(case: &Case, input: &CompareInput) -> Result<CompareSummary, StudyError> {
        let progress: Progress = &|_: &str, _: usize, _: usize| {};
        run(case, input, 2, false, progress)
    }

    /// The FE-stiffness twin's tables carry the FE's k(θ) at the design load at the law's
    /// positions, the FE's table read from its own origin (here 0.31 of a period before the
    /// law's): a linear law of 24 positions (k = 5e8 − 1e8 cos, e = 0) made to an FE k(θ) of
    /// another shape gives, at each position, the FE's value there — the made law's secant and
    /// the secant table alike — and tables at other positions are refused.
    #[test]
    fn the_fe_twin_carries_the_fe_stiffness_at_its_own_angles() {
        use crate::stiffness::force_law::Knot;
        use crate::stiffness::PeriodicTable;
        use std::f64::consts::TAU;
        let (n, period, origin) = (24, 0.1745, 0.42);
        let ltca_k = |theta: f64| 5e8 - 1e8 * (TAU * theta / period).cos();
        let knots = (0..n)
            .map(|j| {
                let k = ltca_k(j as f64 * period / n as f64);
                (0..6)
                    .map(|i| {
                        let w = if i == 0 { 0.0 } else { 500.0 * 2f64.powi(i) };
                        Knot {
                            deflection: w / k,
                            force: w,
                            slope: if i == 0 { f64::NAN } else { k },
                        }
                    })
                    .collect()
            })
            .collect();
        let law = ForceLaw {
            source: "synthetic".into(),
            period,
            origin,
            torques: vec![],
            knots,
        };
        let mut mesh = MeshStiffness::from_tables(
            "synthetic secant",
            None,
            PeriodicTable::from_fn(period, n, ltca_k),
            PeriodicTable::constant(period, 0.0),
        );
        mesh.origin = origin;
        // The FE's table from 0.31 periods earlier, of its own shape, sampled more finely.
        let fe_origin = origin - 0.31 * period;
        let fe_k = |absolute: f64| 4.2e8 + 0.6e8 * (TAU * (absolute - 0.1) / period).sin();
        let mut fe = MeshStiffness::from_tables(
            "synthetic FE",
            None,
            PeriodicTable::from_fn(period, 960, |t| fe_k(fe_origin + t)),
            PeriodicTable::constant(period, 0.0),
        );
        fe.origin = fe_origin;
        let force = 2345.0;
        let (secant, made) = fe_twin_tables((&mesh, &law), &fe, force).unwrap();
        let made_secant = made.secant_stiffness(force, n);
        let tables = secant.stiffness.values.iter().zip(&made_secant);
        for (j, (table, carried)) in tables.enumerate() {
            let expected = fe_k(origin + j as f64 * period / n as f64);
            // The FE table is linear between its 960 samples: 1e-4 of the sine's swing.
            assert!(
                (table / expected - 1.0).abs() < 1e-4,
                "{j}: {table} vs {expected}"
            );
            assert!(
                (carried / expected - 1.0).abs() < 1e-4,
                "{j}: {carried} vs {expected}"
            );
        }
        assert_eq!(secant.origin, origin);
        // Scaled to another mean: that mean, the shape kept.
        let scaled = mesh.scaled_to_mean(4.4e8);
        assert!((scaled.mean() / 4.4e8 - 1.0).abs() < 1e-12);
        for (a, b) in scaled.stiffness.values.iter().zip(&mesh.stiffness.values) {
            assert!((a / b / (4.4e8 / mesh.mean()) - 1.0).abs() < 1e-12);
        }
        let mut shifted = mesh.clone();
        shifted.origin += 1e-3;
        assert!(fe_twin_tables((&shifted, &law), &fe, force).is_err());
    }

    /// The paper pair, an unequal shifted pair (24/40, x = 0.2 / −0.1) and its inverse.
    pub(crate) fn paper_and_unequal_pairs() -> Vec<Case> {
        use crate::case::Override;
        let unequal = |z1: i64, z2: i64| {
            vec![
                Override::set("gear1.teeth", z1),
                Override::set("gear2.teeth", z2),
                Override::set("gear1.profile_shift", 0.2),
                Override::set("gear2.profile_shift", -0.1),
            ]
        };
        [vec![], unequal(24, 40), unequal(40, 24)]
            .iter()
            .map(|overrides| Case::load_with(None, overrides).unwrap())
            .collect()
    }

    /// The twin's driver body takes the inertia split whose modes it is given: modes made by a
    /// known split (the rim's inertia 0.85 and 0.95 × the Rayleigh–Ritz row sum's) at four
    /// mesh stiffnesses (0.6–1.4 × the model's, as a modal analysis's positions would) give
    /// that split back to 1e-9, on the paper pair, a shifted 24/40 pair and its inverse, with
    /// the body's compliance kept (the static mesh deflection to 1e-12) and the model's mesh
    /// mode moved by under 1 %; modes beyond BODY_MODE_MATCH_RANGE or beyond any split, a
    /// torque drive and rigid bodies keep the row sums.
    #[test]
    fn the_twin_takes_the_body_split_whose_modes_it_is_given() {
        for case in paper_and_unequal_pairs() {
            let k = 4.0e8;
            let mesh = MeshStiffness::constant("k", 0.1, k);
            let damping = FeDamping {
                mesh_n_s_per_m: 2000.0,
                stiffness_beta_s: 1e-9,
            };
            let springs = SpringDamping::StiffnessProportional(1e-9);
            let twin = |(drive, elastic): (Drive, bool), modal: Option<&[(f64, f64)]>| {
                let torque = 143.6;
                let laws = (None, None);
                lumped_twin(
                    &case,
                    mesh.clone(),
                    laws,
                    (drive, elastic),
                    torque,
                    damping,
                    modal,
                )
                .unwrap()
            };
            let own = twin((Drive::Speed, true), None);
            let rb1 = case.pair.gears[0].base_radius;
            // The rim's own inertia: the mass matrix's entry less the mesh's own mass there.
            let bodies = super::super::lumped::gear_bodies(&case, BodyModel::Elastic).unwrap();
            let mesh_mass = super::super::lumped::mesh_moving_mass(
                &case,
                bodies.map(|b| b.translation.is_some()),
            )
            .unwrap();
            let rim = |m: &MeshModel| {
                let g = m.structure.mesh_direction[0];
                (m.structure.mass[(0, 0)] - mesh_mass * g * g) * rb1 * rb1
            };
            let row_sum = bodies[0];
            let total = row_sum.hub_inertia + row_sum.rim_inertia;
            assert!((rim(&own) / row_sum.rim_inertia - 1.0).abs() < 1e-12);
            let hz = |m: &crate::lumped::Mode| m.frequency / std::f64::consts::TAU;
            let modes_of = |rim: f64| -> Vec<(f64, f64)> {
                let mut gears =
                    super::super::lumped::gear_bodies(&case, BodyModel::Elastic).unwrap();
                gears[0].rim_inertia = rim;
                gears[0].hub_inertia = total - rim;
                let s = super::super::lumped::drivetrain_of(
                    &case,
                    Drive::Speed,
                    (gears, springs),
                    [None; 2],
                    false,
                )
                .unwrap();
                [0.6, 0.9, 1.1, 1.4]
                    .iter()
                    .map(|f| {
                        let modes = s.modes(f * k);
                        (hz(&modes[0]), hz(&modes[1]))
                    })
                    .collect()
            };
            let deflection = |m: &MeshModel| m.static_state().q[0] - m.static_state().q[1];
            for share in [0.85, 0.95] {
                let known = share * row_sum.rim_inertia;
                let made = twin((Drive::Speed, true), Some(&modes_of(known)));
                assert!(
                    (rim(&made) / known - 1.0).abs() < 1e-9,
                    "{} {known}",
                    rim(&made)
                );
                let mesh_mode = |m: &MeshModel| m.structure.modes(k)[0].frequency;
                assert!((mesh_mode(&made) / mesh_mode(&own) - 1.0).abs() < 0.01);
                assert!((deflection(&made) / deflection(&own) - 1.0).abs() < 1e-12);
            }
            let row_sum_modes = modes_of(row_sum.rim_inertia);
            let scaled = |factor: f64| -> Vec<(f64, f64)> {
                row_sum_modes
                    .iter()
                    .map(|(m, b)| (*m, factor * b))
                    .collect()
            };
            // Beyond the range; within it but beyond any split (the whole inertia on the rim
            // lowers the body mode by about √(row-sum share), 5 %): the row sums stay.
            for factor in [1.0 + 1.1 * BODY_MODE_MATCH_RANGE, 0.9] {
                let kept = twin((Drive::Speed, true), Some(&scaled(factor)));
                assert_eq!(rim(&kept), rim(&own));
            }
            let given = Some(&modes_of(0.9 * row_sum.rim_inertia)[..]);
            for bc in [(Drive::Torque, true), (Drive::Speed, false)] {
                assert_eq!(
                    twin(bc, None).structure.mass,
                    twin(bc, given).structure.mass
                );
            }
        }
    }

    /// A unit dashpot's share in the mesh mode has its analytic value on rigid gears under a
    /// speed drive (one coordinate, the DTE: g = 1/m, m = I₂/r_b2²); scaling a model to its own
    /// share keeps its dashpot, to a share 0.9 × its own scales the dashpot's part of the mode's
    /// damping ratio by 0.9; a share it cannot take keeps the dashpot; the elastic twin's bodies
    /// carry the FE's element damping β K. On the paper pair, a shifted 24/40 pair and its
    /// inverse.
    #[test]
    fn a_twin_takes_the_dashpot_share_it_is_given() {
        for case in paper_and_unequal_pairs() {
            twin_takes_the_dashpot_share(&case);
        }
    }

    fn twin_takes_the_dashpot_share(case: &Case) {
        let case = case.clone();
        let k = || MeshStiffness::constant("mean", 1e-3, 4.0e8);
        let twin = |elastic: bool| {
            lumped_twin(
                &case,
                k(),
                (None, None),
                (Drive::Speed, elastic),
                143.6,
                FeDamping {
                    mesh_n_s_per_m: 2000.0,
                    stiffness_beta_s: BETA,
                },
                None,
            )
            .unwrap()
        };
        const BETA: f64 = 1e-9;
        let rigid = twin(false);
        let mass = Drive::Speed.effective_mass(gear_inertias(&case), {
            let g = &case.pair.gears;
            [g[0].base_radius, g[1].base_radius]
        });
        assert!(
            (dashpot_share(&rigid) * mass - 1.0).abs() < 1e-9,
            "{}",
            dashpot_share(&rigid) * mass
        );
        let elastic = twin(true);
        // The bodies carry the FE's element damping, C = β K, not the case's drivetrain ratio.
        let s = &elastic.structure;
        let body_damping = &s.stiffness * BETA;
        assert!(s.stiffness.amax() > 0.0);
        assert!((&s.damping - &body_damping).amax() <= 1e-12 * body_damping.amax());
        let share = dashpot_share(&elastic);
        assert!(share > 0.0);
        let same = with_dashpot_share(elastic.clone(), share);
        assert!((same.damping / 2000.0 - 1.0).abs() < 1e-12);
        let mut undamped = elastic.clone();
        undamped.damping = 0.0;
        let own = undamped.mesh_mode_damping_ratio();
        let less = with_dashpot_share(elastic.clone(), 0.9 * share);
        let ratio =
            (less.mesh_mode_damping_ratio() - own) / (elastic.mesh_mode_damping_ratio() - own);
        assert!((ratio - 0.9).abs() < 1e-9, "{ratio}");
        assert_eq!(
            with_dashpot_share(elastic.clone(), f64::NAN).damping,
            2000.0
        );
        assert_eq!(with_dashpot_share(elastic, -1.0).damping, 2000.0);
        // A run's own dashpot scales the coefficient by its ratio to the one the model was
        // built for, and with it the mesh mode's damping ratio (first order, linear in c);
        // none recorded, or not a coefficient, keeps it.
        let built = same.damping;
        let of_run = with_fe_dashpot(&same, Some(0.967 * 2000.0), 2000.0);
        assert!((of_run.damping / (0.967 * built) - 1.0).abs() < 1e-12);
        let ratio =
            (of_run.mesh_mode_damping_ratio() - own) / (same.mesh_mode_damping_ratio() - own);
        assert!((ratio - 0.967).abs() < 1e-9, "{ratio}");
        for kept in [None, Some(f64::NAN), Some(0.0), Some(-5.0)] {
            assert_eq!(with_fe_dashpot(&same, kept, 2000.0).damping, built);
        }
        assert_eq!(with_fe_dashpot(&same, Some(1900.0), 0.0).damping, built);
    }

    #[test]
    fn lines_are_named_by_the_nearest_combination() {
        let (fm, fn_) = (1800.0, 2880.0);
        let fb = Some(10_900.0);
        assert_eq!(label_line(1805.0, fm, fn_, fb, 100.0), "1 f_m");
        assert_eq!(label_line(3590.0, fm, fn_, fb, 100.0), "2 f_m");
        assert_eq!(label_line(2870.0, fm, fn_, fb, 100.0), "f_n");
        assert_eq!(label_line(1080.0, fm, fn_, fb, 100.0), "1 f_m - f_n");
        assert_eq!(label_line(4700.0, fm, fn_, fb, 100.0), "1 f_m + f_n");
        assert_eq!(label_line(10_870.0, fm, fn_, fb, 100.0), "f_b");
        assert_eq!(label_line(2300.0, fm, fn_, fb, 100.0), "?");
    }

    /// The sweep's grid takes compare's own speeds and the given runs inside its range; an
    /// inner grid speed next to an asked speed gives way to it (`run --full`'s 4 800 rpm run
    /// replaces the grid's 4 790), next to a given run it stays, and the grid's ends stay;
    /// speeds outside the range stay out; an exact match runs once.
    #[test]
    fn a_sweep_takes_the_speeds_run_anyway_inside_its_range() {
        let grid = [4250.0, 4520.0, 4790.0, 5050.0, 5320.0];
        assert_eq!(
            sweep_speeds_with(&grid, &[1200.0, 4800.0], &[]),
            vec![4250.0, 4520.0, 4800.0, 5050.0, 5320.0]
        );
        assert_eq!(
            sweep_speeds_with(&grid, &[4520.0, 4900.0], &[3000.0]),
            vec![4250.0, 4520.0, 4790.0, 4900.0, 5050.0, 5320.0]
        );
        assert_eq!(
            sweep_speeds_with(&grid, &[4260.0, 5310.0], &[4800.0]),
            vec![4250.0, 4260.0, 4520.0, 4790.0, 4800.0, 5050.0, 5310.0, 5320.0]
        );
        assert_eq!(sweep_speeds_with(&grid, &[], &[]), grid.to_vec());
        assert!(sweep_speeds_with(&[], &[4800.0], &[4800.0]).is_empty());
    }

    /// A sweep speed's run lasts [`FE_SWEEP_DURATION_S`] where the scene is shorter (the
    /// paper's 0.03 s), keeps a longer scene's duration, and may end once settled (the case's
    /// own scene may not).
    #[test]
    fn sweep_runs_last_long_enough_to_settle() {
        use crate::case::Override;
        let duration = |overrides: &[Override]| {
            let case = Case::load_with(None, overrides).unwrap();
            let scene = case.scene(SPEED_SCENE).unwrap();
            (
                scene.duration,
                scene.driver_speed * 60.0 / std::f64::consts::TAU,
            )
        };
        let base = Case::embedded_default().unwrap();
        let (short, rpm) = duration(&sweep_speed_overrides(&base, 5275.0));
        assert_eq!(short, FE_SWEEP_DURATION_S);
        let swept = Case::load_with(None, &sweep_speed_overrides(&base, 5275.0)).unwrap();
        assert!(swept.scene(SPEED_SCENE).unwrap().stop_when_settled);
        assert!(!base.scene(SPEED_SCENE).unwrap().stop_when_settled);
        assert!((rpm - 5275.0).abs() < 1e-9);
        assert!(base.scene(SPEED_SCENE).unwrap().duration < FE_SWEEP_DURATION_S);
        let longer = vec![Override::set(
            format!("scene[{SPEED_SCENE}].duration_s"),
            0.08,
        )];
        let long_case = Case::load_with(None, &longer).unwrap();
        let mut overrides = longer.clone();
        overrides.extend(sweep_speed_overrides(&long_case, 5275.0));
        assert_eq!(duration(&overrides).0, 0.08);
    }
}
