//! The explicit FE study (`geardyn fe`): a scene of the case prepared, run and analysed — DTE
//! statistics, its spectrum and peaks, the stiffness from the DTE, impacts (db5 level-1 detail of
//! the contact force), the energy account, and the LTCA at the positions the statistics window
//! covers, on the run's mesh and on the case's mesh.
//!
//! The command's options are shorthands for overrides of the case ([`overrides`]),
//! so a scene's numbers are checked once, by the case.

use serde::Serialize;

use crate::case::{Case, Override};
use crate::explicit::far::FarBody;
use crate::explicit::pair::PairEnergy;
use crate::explicit::scene::{
    analyse_dte, bin_difference, binned_stiffness, common_bins, covering_duration, paired_bins,
    static_te, statistics_start, CoupledStep, DteAnalysis, FeSettings, FineTeeth, History,
    LowpassDte, MassScaling, PreparedScene, Scene, StaticTe, StepChange, TimeStep,
};
use crate::fe::{MassLumping, PlaneState};
use crate::geometry::GearPair;
use crate::ltca::PositionResult;
use crate::mesh::ToothLayout;
use crate::signal;
use crate::stiffness::PeriodicTable;

use super::checks::{Check, CheckKind};
use super::StudyError;

/// The `fe` command's options, each a shorthand for an override of the case (`scene[NAME].…`,
/// a new `[[scene]]`, or `fe.…`); the command line's flags are these fields.
#[derive(Debug, Clone, Default, PartialEq, clap::Args)]
pub struct FeShorthands {
    /// A scene of the case ([[scene]]), e.g. low-unmodified; the options below override it.
    #[arg(long, value_name = "NAME")]
    pub scene: Option<String>,
    /// Driver speed [rpm] (without --scene: required).
    #[arg(long, value_name = "RPM")]
    pub speed_rpm: Option<f64>,
    /// Simulated time [s] (without --scene: required); shortens or lengthens a scene (and turns
    /// its cover_pitch off: the run lasts this long).
    #[arg(long, value_name = "SECONDS")]
    pub duration_s: Option<f64>,
    /// Load torque on the driven gear [N·m]; default: the scene's, or the first operating point.
    #[arg(long, value_name = "T")]
    pub torque_nm: Option<f64>,
    /// Relief variant; default: the scene's, or the first variant.
    #[arg(long, value_name = "NAME")]
    pub relief: Option<String>,
    /// Coulomb friction coefficient; default: the scene's, or 0.
    #[arg(long, value_name = "MU")]
    pub friction: Option<f64>,
    /// Ramp time of speed and torque [s]; default: the scene's, or min(0.01, duration/10).
    #[arg(long, value_name = "SECONDS")]
    pub ramp_s: Option<f64>,
    /// Time step over the critical step (fe.step_factor, default 0.9); above 1 the run diverges.
    #[arg(long, value_name = "BETA")]
    pub step_factor: Option<f64>,
    /// Contact penalty over the master element's largest diagonal stiffness (fe.penalty_factor).
    #[arg(long, value_name = "F")]
    pub penalty_factor: Option<f64>,
    /// Damping ratio of the mesh mode, a dashpot on the DTE rate (fe.mesh_damping_ratio).
    #[arg(long, value_name = "ZETA")]
    pub mesh_damping_ratio: Option<f64>,
    /// Flank element size of the explicit mesh [mm] (fe.explicit_fine_element_mm).
    #[arg(long, value_name = "MM")]
    pub fine_element_mm: Option<f64>,
    /// Largest element size of the explicit mesh: other teeth, body [mm]
    /// (fe.explicit_coarse_element_mm).
    #[arg(long, value_name = "MM")]
    pub coarse_element_mm: Option<f64>,
    /// Lumped mass of the bodies (fe.mass_lumping).
    #[arg(long, value_enum)]
    pub mass_lumping: Option<MassLumping>,
}

/// The overrides that make `shorthands` part of the case, and the scene's name. `base` is the
/// case as read (for the scene's own ramp and the first relief variant). Shortening a scene
/// below twice its ramp shortens the ramp to half the duration, unless a ramp is given.
pub fn overrides(
    base: &Case,
    shorthands: &FeShorthands,
) -> Result<(Vec<Override>, String), StudyError> {
    let s = shorthands;
    let (mut overrides, name) = scene_overrides(base, s)?;
    let fe = |key: &str, value: Option<f64>| value.map(|v| Override::set(format!("fe.{key}"), v));
    overrides.extend(
        [
            fe("step_factor", s.step_factor),
            fe("penalty_factor", s.penalty_factor),
            fe("mesh_damping_ratio", s.mesh_damping_ratio),
            fe("explicit_fine_element_mm", s.fine_element_mm),
            fe("explicit_coarse_element_mm", s.coarse_element_mm),
            s.mass_lumping
                .map(|m| Override::set("fe.mass_lumping", m.name())),
        ]
        .into_iter()
        .flatten(),
    );
    Ok((overrides, name))
}

fn scene_overrides(
    base: &Case,
    shorthands: &FeShorthands,
) -> Result<(Vec<Override>, String), StudyError> {
    let s = shorthands;
    let names = || {
        base.scenes
            .iter()
            .map(|s| s.name.as_str())
            .collect::<Vec<_>>()
    };
    match &s.scene {
        Some(name) => {
            let scene = base.scene(name).ok_or_else(|| {
                StudyError::Input(format!(
                    "no scene {name:?} in the case; its scenes are: {:?}",
                    names()
                ))
            })?;
            let key = |field: &str| format!("scene[{name}].{field}");
            let mut overrides = Vec::new();
            if let Some(rpm) = s.speed_rpm {
                overrides.push(Override::set(key("speed_rpm"), rpm));
            }
            if let Some(duration) = s.duration_s {
                overrides.push(Override::set(key("duration_s"), duration));
                // A duration given on the command line is the run's, not a least one.
                overrides.push(Override::set(key("cover_pitch"), false));
                if s.ramp_s.is_none() && scene.ramp_time > 0.5 * duration {
                    overrides.push(Override::set(key("ramp_s"), 0.5 * duration));
                }
            }
            if let Some(ramp) = s.ramp_s {
                overrides.push(Override::set(key("ramp_s"), ramp));
            }
            if let Some(torque) = s.torque_nm {
                overrides.push(Override::set(key("torque_nm"), torque));
            }
            if let Some(relief) = &s.relief {
                overrides.push(Override::set(key("relief"), relief.as_str()));
            }
            if let Some(mu) = s.friction {
                overrides.push(Override::set(key("friction"), mu));
            }
            Ok((overrides, name.clone()))
        }
        None => {
            let (Some(rpm), Some(duration)) = (s.speed_rpm, s.duration_s) else {
                return Err(StudyError::Input(format!(
                    "give --scene NAME (one of {:?}) or both --speed-rpm and --duration-s",
                    names()
                )));
            };
            let name = format!("{rpm}rpm");
            let relief = match &s.relief {
                Some(r) => r.clone(),
                None => super::relief_variant(base, None)?.name.clone(),
            };
            let torque = match s.torque_nm {
                Some(t) => t,
                None => super::load_torque(base)?,
            };
            let mut table = toml::Table::new();
            table.insert("name".into(), name.clone().into());
            table.insert("speed_rpm".into(), rpm.into());
            table.insert("torque_nm".into(), torque.into());
            table.insert("relief".into(), relief.into());
            table.insert("friction".into(), s.friction.unwrap_or(0.0).into());
            table.insert("duration_s".into(), duration.into());
            table.insert(
                "ramp_s".into(),
                s.ramp_s.unwrap_or((0.1 * duration).min(0.01)).into(),
            );
            Ok((
                vec![Override::Append {
                    array: "scene".into(),
                    table,
                }],
                name,
            ))
        }
    }
}

/// The scene named, from the (overridden) case.
pub fn scene<'a>(case: &'a Case, name: &str) -> Result<&'a Scene, StudyError> {
    case.scene(name)
        .ok_or_else(|| StudyError::Input(format!("no scene {name:?} in the case")))
}

/// Steps timed on the prepared scene for the up-front estimate (a fraction of a second).
pub const CALIBRATION_STEPS: usize = 200;

/// The least wall time per element and step the estimate takes [ns]: the fastest measured
/// whole scene on 2 cores (36 ns at 3000 rpm, validation/performance), rounded down; the
/// calibration from rest can read lower, without the contact's share.
pub const ESTIMATE_MIN_NS_PER_ELEMENT_STEP: f64 = 30.0;

/// Estimated wall time above which an explicit run needs `--force` [s]: 4 hours, twice the
/// longest scene the validation runs.
pub const ESTIMATE_LIMIT_S: f64 = 4.0 * 3600.0;

/// The cost of running `prepared` for `duration` seconds, before it starts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CostEstimate {
    pub elements: usize,
    pub steps: usize,
    /// Wall time per element and step measured on this machine over [`CALIBRATION_STEPS`]
    /// steps of the scene, at least [`ESTIMATE_MIN_NS_PER_ELEMENT_STEP`] [ns].
    pub ns_per_element_step: f64,
    /// elements × steps × the rate [s].
    pub wall_s: f64,
}

impl CostEstimate {
    /// Times [`CALIBRATION_STEPS`] steps of `prepared` and scales them to `duration` at the
    /// elements per step it starts with (a run on windows of fine teeth: its first window's) and
    /// the step it starts with (the bound of every contact state): a run on the pair's own
    /// step ([`crate::explicit::scene::TimeStep::Coupled`]) takes fewer.
    pub fn of(prepared: &PreparedScene, duration: f64) -> Self {
        let elements = crate::explicit::scene::run_elements(prepared, duration);
        let steps = (duration / prepared.dt).ceil() as usize;
        let measured =
            crate::explicit::scene::measure_step_cost(prepared, CALIBRATION_STEPS.min(steps)) * 1e9;
        let rate = measured.max(ESTIMATE_MIN_NS_PER_ELEMENT_STEP);
        CostEstimate {
            elements,
            steps,
            ns_per_element_step: rate,
            wall_s: elements as f64 * steps as f64 * rate * 1e-9,
        }
    }

    /// Whether it is above [`ESTIMATE_LIMIT_S`].
    pub fn too_long(&self) -> bool {
        self.wall_s > ESTIMATE_LIMIT_S
    }

    /// In words, with the rate it assumed.
    pub fn describe(&self) -> String {
        format!(
            "{} elements × {} steps ≈ {} ({:.0} ns per element-step, timed on {} steps here)",
            self.elements,
            self.steps,
            duration_words(self.wall_s),
            self.ns_per_element_step,
            CALIBRATION_STEPS.min(self.steps)
        )
    }
}

/// A duration as seconds, minutes, hours or days.
pub fn duration_words(seconds: f64) -> String {
    if seconds < 120.0 {
        format!("{seconds:.0} s")
    } else if seconds < 7200.0 {
        format!("{:.0} minutes", seconds / 60.0)
    } else if seconds < 2.0 * 86400.0 {
        format!("{:.1} hours", seconds / 3600.0)
    } else {
        format!("{:.1} days", seconds / 86400.0)
    }
}

/// Meshes and assembles the pair for `scene` with the case's `[fe]` settings and measures its
/// critical step: the one constructor of an explicit scene (the command, tests and benches).
/// The mesh dashpot is sized with the pair's own mean mesh stiffness: the LTCA of the scene's
/// relief and torque on the explicit bodies' mesh (64 positions).
pub fn prepare(case: &Case, scene: &Scene) -> Result<PreparedScene, StudyError> {
    let variant = super::relief_variant(case, Some(&scene.relief))?;
    let settings = &case.fe;
    let model = super::ltca::model_with_layout(
        case,
        &variant.modifications,
        (settings.fine_size, settings.coarse_size),
        settings.tooth_layout,
    )?;
    let results = model.run(64, scene.torque, &|_| {})?;
    let mesh_stiffness = results.iter().map(|r| r.mesh_stiffness).sum::<f64>() / 64.0;
    Ok(crate::explicit::scene::prepare(
        &case.pair,
        &variant.modifications,
        case.explicit_material(),
        scene,
        settings,
        mesh_stiffness,
    )?)
}

/// Derived signals of a history: de-noised DTE, level-1 db5 detail of the contact force.
pub struct Derived {
    pub dte_denoised: Vec<f64>,
    pub force_detail: Vec<f64>,
}

pub fn derive(history: &History) -> Derived {
    Derived {
        dte_denoised: signal::denoise(&history.dte, 5),
        force_detail: if history.force_total.len() >= 2 {
            signal::level1_detail(&history.force_total)
        } else {
            vec![0.0; history.force_total.len()]
        },
    }
}

/// DTE spectrum over the statistics window from `from` [s] (Hann), amplitudes in rad.
pub fn dte_spectrum(history: &History, from: f64) -> Vec<(f64, f64)> {
    let Some(start) = history.time.iter().position(|t| *t >= from) else {
        return Vec::new();
    };
    if history.time.len() - start < 8 {
        return Vec::new();
    }
    let dt = (history.time[history.time.len() - 1] - history.time[start])
        / (history.time.len() - 1 - start) as f64;
    signal::hann_amplitude_spectrum(&history.dte[start..], dt)
}

/// The LTCA at the positions the statistics window covers, on one mesh.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LtcaCheck {
    pub fine_element_mm: f64,
    pub coarse_element_mm: f64,
    pub ste_mean_rad: f64,
    pub ste_max_rad: f64,
    pub ste_min_rad: f64,
    pub ste_peak_to_peak_rad: f64,
    pub mesh_stiffness_mean_n_per_m: f64,
    pub dte_over_ste_mean: f64,
    pub dte_over_ste_peak_to_peak: f64,
    pub dte_lowpass_over_ste_mean: Option<f64>,
    pub dte_lowpass_over_ste_peak_to_peak: Option<f64>,
}

/// Penalty stiffness per contact edge [N/m].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PenaltyRange {
    pub mean: f64,
    pub min: f64,
    pub max: f64,
}

/// Cost and step numbers of a prepared scene.
#[derive(Debug, Clone, Serialize)]
pub struct StepSummary {
    pub dt_s: f64,
    pub dt_critical_s: f64,
    pub dt_critical_bodies_s: [f64; 2],
    pub dt_critical_contact_s: f64,
    pub dt_paper_formula_s: f64,
    pub dt_element_eigenvalue_bound_s: f64,
    pub stiffness_damping_beta_s: f64,
    pub mesh_damping_n_m_s: f64,
    pub mesh_damping_sized_with_stiffness_n_per_m: f64,
    pub driven_inertia_kg_m2: f64,
    pub penalty_stiffness_per_edge_n_per_m: PenaltyRange,
    pub elements: usize,
    pub nodes: usize,
    pub fine_teeth: [Vec<usize>; 2],
    pub tooth_pairs: Vec<(usize, usize)>,
    pub setup_wall_s: f64,
}

impl StepSummary {
    pub fn new(prepared: &PreparedScene) -> Self {
        let model = &prepared.model;
        let edges: Vec<f64> = model
            .flanks
            .iter()
            .flat_map(|f| f.penalty.iter().copied())
            .collect();
        let (min, max) = edges
            .iter()
            .fold((f64::INFINITY, 0.0_f64), |(a, b), k| (a.min(*k), b.max(*k)));
        StepSummary {
            dt_s: prepared.dt,
            dt_critical_s: prepared.dt_critical,
            dt_critical_bodies_s: prepared.dt_bodies,
            dt_critical_contact_s: prepared.dt_contact,
            dt_paper_formula_s: prepared.dt_paper,
            dt_element_eigenvalue_bound_s: prepared.dt_element_bound,
            stiffness_damping_beta_s: prepared.beta_k,
            mesh_damping_n_m_s: prepared.mesh_damping,
            mesh_damping_sized_with_stiffness_n_per_m: prepared.mesh_damping_stiffness,
            driven_inertia_kg_m2: model.driven_inertia(),
            penalty_stiffness_per_edge_n_per_m: PenaltyRange {
                mean: edges.iter().sum::<f64>() / edges.len().max(1) as f64,
                min,
                max,
            },
            elements: model.elements(),
            nodes: model.meshes.iter().map(|m| m.nodes.len()).sum(),
            fine_teeth: [
                model.meshes[0].fine_teeth.clone(),
                model.meshes[1].fine_teeth.clone(),
            ],
            tooth_pairs: model.tooth_pairs.clone(),
            setup_wall_s: prepared.setup_wall_s,
        }
    }
}

/// A spectral peak of the DTE.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DtePeak {
    pub frequency_hz: f64,
    pub amplitude_rad: f64,
}

/// Headline numbers (`summary.json`).
#[derive(Debug, Clone, Serialize)]
pub struct FeSummary {
    pub case: String,
    /// The scene as run: its duration the run's ([`PreparedScene::duration`]).
    pub scene: Scene,
    /// The case's duration of a scene lengthened to cover a base pitch (`cover_pitch`) [s].
    pub duration_lengthened_from_s: Option<f64>,
    pub dte_mean_rad: Option<f64>,
    pub dte_max_rad: Option<f64>,
    pub dte_min_rad: Option<f64>,
    pub dte_peak_to_peak_rad: Option<f64>,
    pub mesh_stiffness_mean_n_per_m: Option<f64>,
    pub mesh_stiffness_from_mean_dte_n_per_m: Option<f64>,
    pub stiffness_pitch_coverage: Option<f64>,
    pub stats_window_s: Option<[f64; 2]>,
    pub dte_lowpass: Option<LowpassDte>,
    /// The static TE the run's k(θ) gives at the load: the quasi-static DTE without the mesh
    /// mode's ringing and without a filter.
    pub static_te_from_stiffness: Option<StaticTe>,
    pub ltca_ste_mean_rad_same_positions: Option<f64>,
    pub ltca_mesh_stiffness_mean_n_per_m: Option<f64>,
    pub dte_over_ltca_mean: Option<f64>,
    pub ltca_same_mesh: Option<LtcaCheck>,
    pub ltca_case_mesh: Option<LtcaCheck>,
    pub mesh_frequency_hz: f64,
    pub dte_spectrum_peaks: Vec<DtePeak>,
    pub contact_force_max_n: f64,
    /// Largest |db5 level-1 detail| of the contact force over the statistics window.
    /// None for a mass-scaled run: its body modes are lowered by √s or more, so the level-1 band
    /// (25–50 kHz at 10 µs) no longer reads the real pair's impacts.
    pub impact_d1_max_n: Option<f64>,
    /// k(θ) from the DTE against the LTCA's, bin by bin, on the run's mesh and the case's.
    pub stiffness_vs_ltca_same_mesh: Option<StiffnessDifference>,
    pub stiffness_vs_ltca_case_mesh: Option<StiffnessDifference>,
    pub energy: PairEnergy,
    pub energy_error_rel: f64,
    pub energy_error_rel_transmitted: f64,
    pub steps: usize,
    /// Wall time over Σ elements × steps of the run's meshes [ns].
    pub wall_ns_per_element_step: f64,
    /// Which teeth the run meshed fine (`fe.fine_teeth`; `fine_teeth` holds the whole scene's
    /// fine teeth), the windows it went through (0: the
    /// scene's own mesh throughout), its elements per step on average against the whole
    /// scene's fine teeth (`elements`), and the kinetic and strain energy its remeshing added
    /// (negative: took out) over the transmitted work.
    pub fe_fine_teeth: FineTeeth,
    pub windows: usize,
    pub elements_mean: f64,
    pub remeshing_energy_rel_transmitted: f64,
    pub wall_s: f64,
    pub total_wall_s: f64,
    /// Threads the wall times were measured with.
    pub wall_threads: usize,
    /// The element kernel this CPU ran (`avx512`, `avx2`, `portable`; chosen at run time, capped
    /// by `GEARDYN_KERNEL`): on CPUs of different kinds a run agrees to round-off, not bit for
    /// bit (README, Determinism).
    pub element_kernel: crate::explicit::body::Kernel,
    /// Where a step's wall time went [µs per step]: the drift, the force phase (and within it,
    /// on their threads, the contact and each gear's element forces), the accelerations, the
    /// serial rest; and the share of steps whose contact ran beside gear 2's element forces
    /// (the integrator puts it where the two threads finish closest together).
    pub wall_phases_us_per_step: crate::explicit::pair::PhaseWallPerStep,
    pub diverged: Option<String>,
    /// Where a stop request ended the run early ([`crate::interrupt`]).
    pub interrupted: Option<String>,
    /// Where the run ended before the scene's duration because its DTE had settled (the
    /// scene's `stop_when_settled`, [`crate::explicit::scene::SettledStop`]) [s]; None: it ran
    /// its duration.
    pub settled_at_s: Option<f64>,
    pub dt_critical_coupled_s: Option<f64>,
    pub dt_critical_coupled_checks: Vec<CoupledStep>,
    /// Which stable step the run's step followed; `dt_s` is the step it started with.
    pub time_step: TimeStep,
    /// Where the step changed (`time_step` "coupled"), and why the run went back to the
    /// bound's step, if it did.
    pub dt_changes: Vec<StepChange>,
    pub dt_fallback: Option<String>,
    pub model: String,
    #[serde(flatten)]
    pub step: StepSummary,
    pub penalty_factor: f64,
    pub step_factor: f64,
    pub mass_lumping: MassLumping,
    /// Mass scaling: factor, the mesh mode unscaled and scaled, the highest mesh harmonic kept.
    pub mass_scaling: MassScaling,
    /// Free ringing of the mesh mode the ramp leaves, over the static response, the time it
    /// takes to decay to 0.5 % and where the statistics start [s].
    pub ramp_ringing: f64,
    pub settling_time_s: f64,
    pub statistics_start_s: f64,
    pub mesh_damping_ratio: f64,
    pub fine_element_mm: f64,
    pub coarse_element_mm: f64,
    /// How the explicit mesh laid out the teeth (`fe.tooth_layout`).
    pub tooth_layout: ToothLayout,
    /// How the run modelled the bodies away from the contact: `fe.far_body` on a run on
    /// windows, "full" on one mesh (the reduced blocks act on runs on windows only).
    pub far_body: FarBody,
    /// The run's checks of its own answer against the LTCA on its own mesh ([`self_checks`]).
    pub self_checks: Vec<Check>,
}

/// The explicit FE's k(θ) and DTE against the LTCA on the run's own mesh, relative: beyond
/// this a warning. Twice the paper pair's difference at the default explicit mesh (+5.7 % in
/// the mean k at 1.0 mm flanks; +3.0 % at 0.5 mm: the penalty contact's share, which shrinks
/// under refinement; validation/low-speed).
pub const FE_LTCA_WARNING_BAND: f64 = 0.10;

/// Beyond this the FE's contact is not the LTCA's (a wrong tooth pairing gave several hundred
/// percent): an error.
pub const FE_LTCA_ERROR_BAND: f64 = 0.30;

/// The checks a quasi-static run (the fifth mesh harmonic below its mesh mode: the DTE is the
/// static TE) makes of its answer against the LTCA on its own mesh: the mean k(θ) from the DTE,
/// and the mean static TE that k(θ) gives at the load (the DTE without the mesh mode's ringing,
/// which a raw mean over a short window still holds). Each is one check: an error beyond
/// [`FE_LTCA_ERROR_BAND`], else a warning beyond [`FE_LTCA_WARNING_BAND`]. A quasi-static run
/// with no comparison (its window holds no bin) gets a warning; a dynamic run, whose DTE is not
/// the static TE, no check. With `coverage` (the share of the base pitch the window's bins
/// cover, and the [`covering_duration`] that would cover it all), a warning where a bin is
/// missing.
pub fn self_checks(
    quasi_static: bool,
    stiffness: Option<&StiffnessDifference>,
    coverage: Option<(f64, f64)>,
) -> Vec<Check> {
    if !quasi_static {
        return Vec::new();
    }
    // Bins the window misses are interpolated across in k(θ) and in everything fed by it.
    let covered = coverage.map(|(share, needed)| {
        Check::new(
            "fe",
            "share of the base pitch that k(θ) from the DTE covers (the rest is interpolated)",
            (share, 1.0),
            format!(
                "one whole base pitch: the scene's cover_pitch = true, or a duration_s of at \
                 least {needed:.4} s"
            ),
            (CheckKind::Absolute, 0.0),
        )
        .warning()
    });
    let Some(k) = stiffness else {
        return vec![Check::new(
            "fe",
            "k(θ) from the DTE against the LTCA on the same mesh: no bin to compare (the \
             statistics window is too short)",
            (f64::NAN, 1.0),
            "the LTCA on the run's mesh",
            (CheckKind::Relative, FE_LTCA_WARNING_BAND),
        )
        .warning()]
        .into_iter()
        .chain(covered)
        .collect();
    };
    [
        (
            "mean k(θ) from the DTE against the LTCA's on the same mesh, FE/LTCA",
            1.0 + k.mean_rel,
        ),
        (
            "mean static TE from k(θ) at the load against the LTCA's STE, same mesh, FE/LTCA",
            1.0 + k.static_te_mean_rel,
        ),
    ]
    .into_iter()
    .map(|(quantity, ratio)| {
        let error = Check::new(
            "fe",
            quantity,
            (ratio, 1.0),
            "the LTCA on the run's mesh (exact contact, no penalty): beyond this the contact is \
             not the LTCA's",
            (CheckKind::Relative, FE_LTCA_ERROR_BAND),
        );
        if error.passed {
            Check::new(
                "fe",
                quantity,
                (ratio, 1.0),
                "the LTCA on the run's mesh: twice the paper pair's penalty share",
                (CheckKind::Relative, FE_LTCA_WARNING_BAND),
            )
            .warning()
        } else {
            error
        }
    })
    .chain(covered)
    .collect()
}

/// The study's result.
pub struct FeStudy {
    pub scene: Scene,
    pub history: History,
    pub derived: Derived,
    pub analysis: Option<DteAnalysis>,
    /// DTE spectrum over the statistics window: (frequency [Hz], amplitude [rad]).
    pub spectrum: Vec<(f64, f64)>,
    /// Names of the flank pairs (columns of the pair forces).
    pub pair_names: Vec<String>,
    /// k(θ) from the DTE against the LTCA on the run's mesh and on the case's.
    pub stiffness_comparison: [Option<StiffnessComparison>; 2],
    /// The relief's geometric unloaded TE e along the line of action [m] against the driver
    /// rotation from the pitch-point position (the same-mesh LTCA's), as the analysis used it.
    pub unloaded_te: PeriodicTable,
    pub summary: FeSummary,
    /// Where an interrupted run goes on from (`geardyn fe --resume`, `run --resume`).
    pub checkpoint: Option<Box<crate::explicit::scene::RunCheckpoint>>,
}

/// Runs a prepared scene, from its start or from the checkpoint of an interrupted run of it,
/// keeping checkpoints as it goes where `keeping` says, and analyses it; `progress` sees the
/// fraction done. A diverged or interrupted run is a
/// result too (`summary.diverged` or `summary.interrupted` says why), so its partial histories
/// can be written; an interrupted one carries its checkpoint.
pub fn run(
    case: &Case,
    scene: &Scene,
    prepared: &PreparedScene,
    resume: Option<(crate::explicit::scene::RunCheckpoint, History)>,
    keeping: Option<crate::explicit::scene::Keeping>,
    progress: &mut dyn FnMut(f64),
) -> Result<FeStudy, StudyError> {
    let started = std::time::Instant::now();
    let settings: &FeSettings = &case.fe;
    crate::resources::check_memory(
        "the explicit run's history and state",
        &crate::explicit::scene::run_memory(prepared, prepared.duration, settings.output_interval),
        "shorten the scene (--duration-s) or record it less often (fe.output_interval_us)",
    )?;
    let outcome = crate::explicit::scene::run(
        prepared,
        prepared.duration,
        settings.output_interval,
        resume,
        keeping,
        progress,
    )?;
    let history = outcome.history;
    let stats_start = statistics_start(prepared, scene);
    let (fine_mm, coarse_mm) = (settings.fine_size * 1e3, settings.coarse_size * 1e3);
    let case_mesh = (
        case.file.mesh.fine_element_mm,
        case.file.mesh.coarse_element_mm,
    );
    // The LTCA on the run's mesh gives the relief's geometric unloaded TE (exact profiles) and
    // the same-discretization reference; on the case's mesh, the converged reference.
    let same = ltca_cycle(case, scene, (fine_mm, coarse_mm), settings.tooth_layout)?;
    let converged = if (case_mesh.0 - fine_mm).abs() > 1e-9
        || (case_mesh.1 - coarse_mm).abs() > 1e-9
        || settings.tooth_layout != ToothLayout::Graded
    {
        Some(ltca_cycle(case, scene, case_mesh, ToothLayout::Graded)?)
    } else {
        None
    };
    let rb2 = case.pair.gears[1].base_radius;
    let pitch = case.pair.gears[0].angular_pitch();
    let unloaded_te = unloaded_te_table(&same, rb2, pitch);
    let analysis = analyse_dte(
        &history,
        &case.pair,
        prepared.model.driven_inertia(),
        scene.torque,
        stats_start,
        &unloaded_te,
        None,
    );
    let derived = derive(&history);
    let spectrum = dte_spectrum(&history, stats_start);
    let mesh_hz = scene.driver_speed / pitch;
    let peaks = signal::spectrum_peaks(&spectrum, 0.5 * mesh_hz, 8);
    let pair_names: Vec<String> = prepared
        .model
        .flank_pairs
        .iter()
        .map(|fp| fp.name())
        .collect();
    let check = |results: &[PositionResult], mesh: (f64, f64)| {
        analysis.as_ref().map(|a| {
            (
                ltca_check(a, &history, results, pitch, mesh),
                compare_stiffness(a, &history, results, scene.torque, &case.pair, mesh),
            )
        })
    };
    let same_checks = check(&same, (fine_mm, coarse_mm));
    let case_checks = match &converged {
        Some(results) => check(results, case_mesh),
        None => same_checks.clone(),
    };
    let ltca_same = same_checks.as_ref().map(|c| c.0);
    let ltca_case_mesh = case_checks.as_ref().map(|c| c.0);
    let stiffness_same = same_checks.and_then(|c| c.1);
    let stiffness_case = case_checks.and_then(|c| c.1);
    let stats_sample = history
        .time
        .iter()
        .position(|t| *t >= stats_start)
        .unwrap_or(history.time.len());
    // The work done during the run: a start at speed books its initial kinetic energy as
    // external work at t = 0, which is not a scale of the run's errors.
    let initial_work = history.energy.first().map_or(0.0, |e| e.external_work);
    let max_work = history
        .energy
        .iter()
        .map(|e| (e.external_work - initial_work).abs())
        .fold(0.0, f64::max);
    let max_balance = history
        .energy
        .iter()
        .map(|e| e.balance().abs())
        .fold(0.0, f64::max);
    let energy_error_rel = if max_work > 0.0 {
        max_balance / max_work
    } else {
        0.0
    };
    let transmitted = history.energy.last().map_or(0.0, |e| e.transmitted_work);
    let energy_error_rel_transmitted = if transmitted > 0.0 {
        max_balance / transmitted
    } else {
        0.0
    };
    let wall_ns_per_element_step = outcome.wall_s * 1e9 / outcome.element_steps.max(1.0);
    let elements_mean = outcome.element_steps / outcome.steps.max(1) as f64;
    let remeshing_energy_rel_transmitted = if transmitted > 0.0 {
        outcome.final_energy.remeshing / transmitted
    } else {
        0.0
    };
    let get = |f: &dyn Fn(&DteAnalysis) -> f64| analysis.as_ref().map(f);
    let fe_checks = self_checks(
        prepared.mass_scaling.scaled_mode_over_harmonic >= 1.0
            && outcome.diverged.is_none()
            && outcome.interrupted.is_none(),
        stiffness_same.as_ref().map(|c| &c.summary),
        analysis.as_ref().map(|a| {
            (
                a.pitch_coverage,
                covering_duration(prepared, scene, settings.output_interval),
            )
        }),
    );
    let outcome_mesh = RunMesh {
        windows: outcome.windows,
        elements_mean,
    };
    let summary = FeSummary {
        case: case.name().to_string(),
        scene: Scene {
            duration: prepared.duration,
            ..scene.clone()
        },
        duration_lengthened_from_s: (prepared.duration > prepared.scene_duration)
            .then_some(prepared.scene_duration),
        dte_mean_rad: get(&|a| a.dte_mean_rad),
        dte_max_rad: get(&|a| a.dte_max_rad),
        dte_min_rad: get(&|a| a.dte_min_rad),
        dte_peak_to_peak_rad: get(&|a| a.dte_peak_to_peak_rad),
        mesh_stiffness_mean_n_per_m: get(&|a| a.mesh_stiffness_mean_n_per_m),
        mesh_stiffness_from_mean_dte_n_per_m: get(&|a| a.mesh_stiffness_from_mean_dte_n_per_m),
        stiffness_pitch_coverage: get(&|a| a.pitch_coverage),
        stats_window_s: analysis.as_ref().map(|a| [a.window.0, a.window.1]),
        dte_lowpass: analysis.as_ref().and_then(|a| a.lowpass),
        static_te_from_stiffness: analysis.as_ref().and_then(|a| a.static_te),
        ltca_ste_mean_rad_same_positions: ltca_same.map(|l| l.ste_mean_rad),
        ltca_mesh_stiffness_mean_n_per_m: ltca_same.map(|l| l.mesh_stiffness_mean_n_per_m),
        dte_over_ltca_mean: ltca_same.map(|l| l.dte_over_ste_mean),
        ltca_same_mesh: ltca_same,
        ltca_case_mesh,
        mesh_frequency_hz: mesh_hz,
        dte_spectrum_peaks: peaks
            .iter()
            .map(|(f, a)| DtePeak {
                frequency_hz: *f,
                amplitude_rad: *a,
            })
            .collect(),
        contact_force_max_n: history.force_total.iter().copied().fold(0.0, f64::max),
        impact_d1_max_n: (prepared.mass_scaling.factor <= 1.0)
            .then(|| signal::level1_detail_max(&history.force_total, stats_sample)),
        stiffness_vs_ltca_same_mesh: stiffness_same.as_ref().map(|c| c.summary),
        stiffness_vs_ltca_case_mesh: stiffness_case.as_ref().map(|c| c.summary),
        energy: outcome.final_energy,
        energy_error_rel,
        energy_error_rel_transmitted,
        steps: outcome.steps,
        wall_ns_per_element_step,
        fe_fine_teeth: prepared.fine_teeth,
        windows: outcome.windows,
        elements_mean,
        remeshing_energy_rel_transmitted,
        wall_s: outcome.wall_s,
        total_wall_s: started.elapsed().as_secs_f64() + prepared.setup_wall_s,
        wall_threads: rayon::current_num_threads(),
        element_kernel: crate::explicit::body::Kernel::best(),
        wall_phases_us_per_step: outcome.phase_wall.per_step_us(),
        diverged: outcome.diverged,
        interrupted: outcome.interrupted,
        settled_at_s: outcome.settled_at_s,
        dt_critical_coupled_s: outcome
            .coupled_steps
            .iter()
            .map(|c| c.dt_critical_s)
            .reduce(f64::min),
        dt_critical_coupled_checks: outcome.coupled_steps,
        time_step: settings.time_step,
        dt_changes: outcome.step_changes,
        dt_fallback: outcome.fallback,
        model: model_description(case, prepared, &outcome_mesh),
        step: StepSummary::new(prepared),
        penalty_factor: settings.penalty_factor,
        step_factor: settings.step_factor,
        mass_lumping: settings.mass_lumping,
        mass_scaling: prepared.mass_scaling,
        ramp_ringing: prepared.ramp_ringing,
        settling_time_s: prepared.settling_time,
        statistics_start_s: stats_start,
        mesh_damping_ratio: settings.mesh_damping_ratio,
        fine_element_mm: fine_mm,
        coarse_element_mm: coarse_mm,
        tooth_layout: settings.tooth_layout,
        far_body: if outcome.windows > 0 {
            settings.far_body
        } else {
            FarBody::Full
        },
        self_checks: fe_checks,
    };
    Ok(FeStudy {
        scene: scene.clone(),
        history,
        derived,
        analysis,
        spectrum,
        pair_names,
        stiffness_comparison: [stiffness_same, stiffness_case],
        unloaded_te,
        summary,
        checkpoint: outcome.checkpoint,
    })
}

/// What the explicit model is and what it leaves out, in one sentence.
/// How a run meshed its teeth, for [`model_description`]: windows gone through and elements
/// per step on average.
struct RunMesh {
    windows: usize,
    elements_mean: f64,
}

fn model_description(case: &Case, prepared: &PreparedScene, mesh: &RunMesh) -> String {
    let settings = &case.fe;
    let scaling = &prepared.mass_scaling;
    let mass_scaling = if let (Some([t1, t2]), Some([least, largest])) =
        (scaling.target_steps_s, scaling.element_factor_range)
    {
        format!(
            "; element masses raised to element steps of {:.4e} / {:.4e} s, each gear's inertia {:.1} x (element factors {:.2} to {:.1}; quasi-static: mesh mode {:.0} -> {:.0} Hz, {:.1} x the fifth mesh harmonic {:.0} Hz)",
            t1,
            t2,
            scaling.factor,
            least,
            largest,
            scaling.mesh_mode_hz,
            scaling.scaled_mesh_mode_hz,
            scaling.scaled_mode_over_harmonic,
            scaling.highest_harmonic_hz,
        )
    } else if scaling.factor > 1.0 {
        format!(
            "; every mass scaled by {:.1} (quasi-static: mesh mode {:.0} -> {:.0} Hz, {:.1} x the fifth mesh harmonic {:.0} Hz; stable step {:.2} x)",
            scaling.factor,
            scaling.mesh_mode_hz,
            scaling.scaled_mesh_mode_hz,
            scaling.scaled_mode_over_harmonic,
            scaling.highest_harmonic_hz,
            scaling.factor.sqrt()
        )
    } else {
        format!(
            "; masses unscaled (mesh mode {:.0} Hz, {:.2} x the fifth mesh harmonic)",
            scaling.mesh_mode_hz, scaling.scaled_mode_over_harmonic
        )
    };
    format!(
        "2D {} ({} plane), corotational 8-node quadrilaterals, lumped mass ({}); rigid hubs, rigid bearings; driver at prescribed speed, driven hub with load torque and a mesh dashpot (zeta {:.3}) on the DTE rate; segment-to-segment penalty contact (two-pass, 4 Gauss points per edge and the tip corner) with Coulomb friction on drive and back flanks of {} tooth pairs; fine flank elements {:.2} mm only on the teeth that engage {}, {:.2} mm elsewhere",
        if case.plane == PlaneState::Strain {
            "plane strain"
        } else {
            "plane stress"
        },
        case.pair.gears[0].spec.face_width * 1e3,
        match settings.mass_lumping {
            MassLumping::CornerTwelfth => "corners 1/12, mid-sides 1/6 of each element's mass",
            MassLumping::Hrz => "HRZ diagonal scaling",
        },
        settings.mesh_damping_ratio,
        prepared.model.tooth_pairs.len(),
        settings.fine_size * 1e3,
        if mesh.windows > 0 {
            format!(
                "in the current window of {} driver pitch (remeshed at a recorded sample as the gears turn, the state carried over: {} windows, {:.0} elements per step on average against {} with every engaging tooth fine)",
                crate::explicit::scene::WINDOW_PITCHES,
                mesh.windows,
                mesh.elements_mean,
                prepared.model.elements()
            )
        } else {
            "during the scene".to_string()
        },
        settings.coarse_size * 1e3
    ) + match settings.tooth_layout {
        ToothLayout::Graded => "",
        ToothLayout::StableStep => {
            "; teeth laid out for the stable step (columns even at the tip, the upper fillet's rows of equal length; fe.tooth_layout)"
        }
    } + &match (settings.far_body, mesh.windows > 0) {
        (FarBody::Full, _) => String::new(),
        (FarBody::Reduced, true) => format!(
            "; each window's coarse sectors one reduced Craig–Bampton block per gear turning with its hub (fixed-interface modes to {} times the lowest of the fine sectors beside it, static interface and spin loads exact; fe.far_body, fe.far_block_cutoff), the step's elements the fine sectors' only",
            settings.far_block_cutoff
        ),
        (FarBody::Reduced, false) => {
            "; bodies in full (fe.far_body = \"reduced\" acts on runs on windows of fine teeth only)".to_string()
        }
    } + &mass_scaling
}

/// LTCA positions per base pitch of the references (twice the stiffness bins, so a contact
/// transition is placed within half a bin).
pub const LTCA_POSITIONS: usize = 128;

/// The LTCA cycle of the scene's relief and torque on a mesh of `fine_mm` / `coarse_mm`, teeth
/// laid out as `layout`.
fn ltca_cycle(
    case: &Case,
    scene: &Scene,
    (fine_mm, coarse_mm): (f64, f64),
    layout: ToothLayout,
) -> Result<Vec<PositionResult>, StudyError> {
    let variant = super::relief_variant(case, Some(&scene.relief))?;
    let model = super::ltca::model_with_layout(
        case,
        &variant.modifications,
        (fine_mm * 1e-3, coarse_mm * 1e-3),
        layout,
    )?;
    Ok(model.run(LTCA_POSITIONS, scene.torque, &|_| {})?)
}

/// A quantity of the LTCA cycle at driver rotation θ (periodic, linear between positions).
fn at_rotation(
    results: &[PositionResult],
    pitch: f64,
    theta: f64,
    f: fn(&PositionResult) -> f64,
) -> f64 {
    let n = results.len();
    let u = (theta / pitch).rem_euclid(1.0) * n as f64;
    let i = (u.floor() as usize).min(n - 1);
    let w = u - i as f64;
    f(&results[i]) * (1.0 - w) + f(&results[(i + 1) % n]) * w
}

/// The LTCA's STE over the driver positions of the statistics window, against the run's DTE.
fn ltca_check(
    a: &DteAnalysis,
    history: &History,
    results: &[PositionResult],
    pitch: f64,
    (fine_mm, coarse_mm): (f64, f64),
) -> LtcaCheck {
    let covered: Vec<f64> = history.driver_rotation[a.window_start..]
        .iter()
        .map(|theta| at_rotation(results, pitch, *theta, |r| r.ste))
        .collect();
    let mean = covered.iter().sum::<f64>() / covered.len() as f64;
    let (min, max) = crate::signal::extremes(&covered);
    let k_mean = results.iter().map(|r| r.mesh_stiffness).sum::<f64>() / results.len() as f64;
    LtcaCheck {
        fine_element_mm: fine_mm,
        coarse_element_mm: coarse_mm,
        ste_mean_rad: mean,
        ste_max_rad: max,
        ste_min_rad: min,
        ste_peak_to_peak_rad: max - min,
        mesh_stiffness_mean_n_per_m: k_mean,
        dte_over_ste_mean: a.dte_mean_rad / mean,
        dte_over_ste_peak_to_peak: a.dte_peak_to_peak_rad / (max - min),
        dte_lowpass_over_ste_mean: a.lowpass.map(|l| l.mean_rad / mean),
        dte_lowpass_over_ste_peak_to_peak: a.lowpass.map(|l| l.peak_to_peak_rad / (max - min)),
    }
}

/// k(θ) from the DTE over the LTCA's, bin by bin.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StiffnessDifference {
    pub fine_element_mm: f64,
    pub coarse_element_mm: f64,
    /// Mean of the FE's bins over the mean of the LTCA's, minus one.
    pub mean_rel: f64,
    /// The largest |k_FE/k_LTCA − 1| of a bin.
    pub max_abs_rel: f64,
    /// The static TE each k(θ) gives at the load over these bins ([`static_te`]): FE over
    /// LTCA − 1, mean and peak-to-peak.
    pub static_te_mean_rel: f64,
    pub static_te_peak_to_peak_rel: f64,
    /// Bins compared (of [`STIFFNESS_BINS`]).
    pub bins: usize,
}

/// The comparison and its bins: (driver rotation from the pitch-point position [rad], k from
/// the DTE, k of the LTCA) [N/m].
#[derive(Debug, Clone, PartialEq)]
pub struct StiffnessComparison {
    pub summary: StiffnessDifference,
    pub bins: Vec<(f64, f64, f64)>,
}

/// The relief's unloaded TE of an LTCA cycle along the line of action [m] against the driver
/// rotation from the pitch-point position.
fn unloaded_te_table(results: &[PositionResult], rb2: f64, pitch: f64) -> PeriodicTable {
    PeriodicTable {
        period: pitch,
        values: results.iter().map(|r| r.unloaded_te * rb2).collect(),
    }
}

/// The LTCA's k(θ) on the same footing as the FE's: its STE and e at the window's driver
/// positions, k = Σ(T/R_b2)/Σ(R_b2 φ − e) per bin (frictionless: the LTCA's mesh force is
/// T/R_b2), unfiltered, like the FE's; then bin by bin against the FE's table.
fn compare_stiffness(
    a: &DteAnalysis,
    history: &History,
    results: &[PositionResult],
    torque: f64,
    pair: &GearPair,
    (fine_mm, coarse_mm): (f64, f64),
) -> Option<StiffnessComparison> {
    let rb2 = pair.gears[1].base_radius;
    let pitch = pair.gears[0].angular_pitch();
    let rotations = &history.driver_rotation[a.window_start..];
    let deflection: Vec<f64> = rotations
        .iter()
        .map(|theta| {
            let ste = at_rotation(results, pitch, *theta, |r| r.ste);
            let e = at_rotation(results, pitch, *theta, |r| r.unloaded_te);
            rb2 * (ste - e)
        })
        .collect();
    let force = vec![torque / rb2; deflection.len()];
    let reference = binned_stiffness(pitch, rotations, &force, &deflection);
    let fe_bins = &a.stiffness_bins;
    let (mean_rel, max_abs_rel, count) = bin_difference(fe_bins, &reference)?;
    let unloaded_te = unloaded_te_table(results, rb2, pitch);
    // The static TE of each over the bins both have, with the same e: the difference is k's.
    let static_of = |own: &[Option<f64>], other: &[Option<f64>]| {
        static_te(pair, torque, &common_bins(own, other), &unloaded_te)
    };
    let (fe_te, ltca_te) = (
        static_of(fe_bins, &reference)?,
        static_of(&reference, fe_bins)?,
    );
    Some(StiffnessComparison {
        summary: StiffnessDifference {
            fine_element_mm: fine_mm,
            coarse_element_mm: coarse_mm,
            mean_rel,
            max_abs_rel,
            static_te_mean_rel: fe_te.mean_rad / ltca_te.mean_rad - 1.0,
            static_te_peak_to_peak_rel: fe_te.peak_to_peak_rad / ltca_te.peak_to_peak_rad - 1.0,
            bins: count,
        },
        bins: paired_bins(pitch, fe_bins, &reference),
    })
}

#[cfg(test)]
mod tests {
    use super::{self_checks, StiffnessDifference};

    /// A quasi-static run's checks: the FE against the LTCA within the bands, and the window's
    /// share of the base pitch, which fails (as a warning that names the duration to give)
    /// wherever a bin is missing and passes at a whole pitch; a dynamic run gets none.
    #[test]
    fn a_window_short_of_a_base_pitch_is_flagged() {
        let k = StiffnessDifference {
            fine_element_mm: 1.0,
            coarse_element_mm: 3.0,
            mean_rel: -0.05,
            max_abs_rel: 0.1,
            static_te_mean_rel: 0.05,
            static_te_peak_to_peak_rel: 0.2,
            bins: 54,
        };
        let short = self_checks(true, Some(&k), Some((54.0 / 64.0, 0.0666)));
        assert_eq!(short.len(), 3);
        assert!(short[..2].iter().all(|c| c.passed));
        let coverage = &short[2];
        assert!(!coverage.passed && coverage.warning_only);
        assert_eq!(coverage.value, 0.84375);
        assert!(coverage.reference_source.contains("0.0666 s"));
        let whole = self_checks(true, Some(&k), Some((1.0, 0.0666)));
        assert!(whole.iter().all(|c| c.passed));
        let none = self_checks(true, None, Some((0.0, 0.0666)));
        assert_eq!(none.len(), 2);
        assert!(none.iter().all(|c| !c.passed && c.warning_only));
        assert!(self_checks(false, Some(&k), Some((0.5, 0.0666))).is_empty());
    }
}
