//! The lumped model of a case (shared by `sweep`, `stability`, `optimize`, `compare` and
//! `validate`): the mesh stiffness and force law from the case's source, and the linear
//! structure around the mesh ([`crate::lumped::structure`]) from `[lumped]`: the gear bodies
//! (elastic, hub and rim, or rigid), shafts, motor and load, bearings, the drive and damping.
//!
//! Inertias default to ρ b ∫r² dA of the gear bodies (the FE's bodies, bore to tip), masses to
//! ρ b A; a hub-to-hub stiffness loses the elastic bodies' twist and their rims' sway
//! ([`to_rims`], [`bodies_line_compliance`]); the mesh damping
//! is c = 2ζ√(k̄ m_e) with m_e the rigid pair's effective mass under the drive
//! ([`Drive::effective_mass`]), or the case's coefficient when it gives one.

use crate::case::{BodyModel, BodySway};
use crate::case::{Case, Override, StiffnessSource};
use crate::ltca::body::BodyTranslation;
use crate::ltca::{Flank, LtcaModel, PositionResult};
use crate::lumped::{
    Bearings, DampingSite, Drive, DrivetrainSpec, ForceLawKind, GearBody, MeshModel,
    RimTranslation, SpringDamping, Structure,
};
use crate::stiffness::{self, potential_energy, ForceLaw, MeshStiffness};

use super::checks::{Check, CheckKind};
use super::{load_torque, StudyError};

/// The lumped commands' flags (`sweep`, `stability`, `validate`), each a shorthand for an
/// override of the case.
#[derive(Debug, Clone, Default, PartialEq, clap::Args)]
pub struct LumpedShorthands {
    /// Stiffness source: ltca (the case's FE LTCA of lumped.relief, default the first variant), pe (potential energy), iso
    /// (ISO 6336-1 c_gamma_alpha, constant) or a CSV file with columns roll_angle_deg,
    /// mesh_stiffness_n_per_m[, unloaded_te_um] over one mesh period (lumped.stiffness).
    #[arg(long, value_name = "SOURCE")]
    pub stiffness: Option<StiffnessSource>,
    /// Mesh damping ratio ζ, c = 2ζ√(k̄ m) (lumped.damping_ratio; wins over a coefficient).
    #[arg(long, value_name = "ZETA")]
    pub damping_ratio: Option<f64>,
    /// Load torque on the driven gear [N·m] (operating_point[0].torque_nm).
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub torque_nm: Option<f64>,
    /// How the pair is driven (lumped.drive).
    #[arg(long, value_enum)]
    pub drive: Option<Drive>,
    /// Add each gear's translation on its bearings along the line of action (lumped.bearings).
    #[arg(long)]
    pub bearings: bool,
    /// One rigid inertia per gear instead of hub and rim with the body's twist between them
    /// (lumped.bodies = "rigid").
    #[arg(long)]
    pub rigid_bodies: bool,
}

impl LumpedShorthands {
    /// The overrides; a stiffness file's relative path is taken from the working folder.
    pub fn overrides(&self) -> std::io::Result<Vec<Override>> {
        let mut overrides: Vec<Override> =
            super::torque_override(self.torque_nm).into_iter().collect();
        if let Some(source) = &self.stiffness {
            let name = match source {
                StiffnessSource::Csv(path) => std::path::absolute(path)?.display().to_string(),
                kind => kind.name(),
            };
            overrides.push(Override::set("lumped.stiffness", name));
        }
        if let Some(zeta) = self.damping_ratio {
            overrides.push(Override::set("lumped.damping_ratio", zeta));
            overrides.push(Override::Remove {
                key: "lumped.mesh_damping_n_s_per_m".into(),
            });
        }
        if let Some(drive) = self.drive {
            overrides.push(Override::set("lumped.drive", drive.name()));
        }
        if self.bearings {
            overrides.push(Override::set("lumped.bearings", true));
        }
        if self.rigid_bodies {
            overrides.push(Override::set("lumped.bodies", "rigid"));
        }
        Ok(overrides)
    }
}

/// Mesh positions of the stiffness tables the lumped model is built on.
pub const POSITIONS: usize = 64;

/// The loads of the force law's knots, as fractions of the design torque: a geometric ladder
/// of ratio [`FORCE_LAW_LOAD_RATIO`] from 0.039 to 8.3, offset by half a step from the design
/// load, so every load of [`QUASI_STATIC_LOADS`] (100 % included) falls between two knots and
/// the quasi-static check tests the interpolation, not the knots.
pub fn force_law_loads() -> Vec<f64> {
    (-15..=9)
        .map(|k| FORCE_LAW_LOAD_RATIO.powf(k as f64 + 0.5))
        .collect()
}

/// Positions of the force law over one base pitch (and of the secant k(θ) of the `ltca`
/// source): the STE changes steeply where a pair enters or leaves, and a linear blend between
/// positions misses it there by a share of the step (see validation/lumped-twin).
pub const FORCE_LAW_POSITIONS: usize = 256;

/// The ratio of neighbouring loads of the force law's knots (see validation/lumped-twin for
/// what it costs in accuracy).
pub const FORCE_LAW_LOAD_RATIO: f64 = 1.25;

/// The loads at which the lumped model's quasi-static response is checked against the LTCA,
/// as fractions of the design torque.
pub const QUASI_STATIC_LOADS: [f64; 6] = [0.25, 0.5, 1.0, 1.5, 2.0, 3.0];

/// The rms difference allowed between the lumped model's quasi-static TE and the LTCA's STE at
/// the same torque over one base pitch, over the mean loaded deflection: 1 %.
pub const QUASI_STATIC_TOLERANCE: f64 = 0.01;

/// The largest difference at any position before the quasi-static check warns, over the mean
/// loaded deflection: 10 %, four times what the table's blend misses at a contact change.
pub const QUASI_STATIC_PEAK_TOLERANCE: f64 = 0.1;

/// The lumped model of a case and what it was built from.
#[derive(Debug, Clone)]
pub struct LumpedSetup {
    pub torque: f64,
    pub model: MeshModel,
    /// Wall time of the stiffness source [s].
    pub stiffness_wall_s: f64,
    /// Rotary inertias I₁, I₂ [kg·m²].
    pub inertias: [f64; 2],
    pub drive: Drive,
    pub damping_ratio: f64,
    /// Undamped mesh-mode frequency of the model linearized about the design load [Hz].
    pub natural_frequency_hz: f64,
    /// One line saying which model was used and what it leaves out.
    pub model_note: String,
    /// The bodies' twist and sway the structure carries, Σ r_b² c_b + Σ 1/k_y over elastic
    /// bodies [m/N] ([`structure_body_compliance`]): the mesh stiffness hub to hub is
    /// 1/(1/k + this).
    pub body_compliance: f64,
    /// The model's checks of its own answer: its quasi-static response against the LTCA
    /// ([`quasi_static_checks`]); empty for sources other than the LTCA.
    pub self_checks: Vec<Check>,
}

/// Rotary inertias of the gears [kg·m²]: the case's, or ρ b ∫r² dA of the bodies.
pub fn gear_inertias(case: &Case) -> [f64; 2] {
    case.lumped.inertias.unwrap_or_else(|| {
        std::array::from_fn(|i| {
            let gear = &case.pair.gears[i];
            case.material.density * gear.spec.face_width * gear.area_moments().1
        })
    })
}

/// The mesh stiffness from `source` at load torque `torque`.
pub fn mesh_stiffness(
    case: &Case,
    source: &StiffnessSource,
    torque: f64,
) -> Result<MeshStiffness, StudyError> {
    let pair = &case.pair;
    Ok(match source {
        StiffnessSource::Ltca => {
            // The secant of the force law's LTCA tables, the one the sweeps are built on.
            let variant = super::relief_variant(case, case.lumped.relief.as_deref())?;
            let ltca = super::ltca::model(case, &variant.modifications)?;
            ltca_tables(
                case,
                &ltca,
                torque,
                &format!("ltca (relief {})", variant.name),
            )?
            .0
        }
        StiffnessSource::PotentialEnergy => potential_energy::potential_energy_table(
            pair,
            POSITIONS,
            case.material.youngs_modulus,
            case.material.poisson_ratio,
            case.plane,
        ),
        StiffnessSource::Iso => {
            stiffness::iso_6336_method_b(pair, torque, case.material.youngs_modulus)
                .mesh_stiffness(pair, torque)
        }
        StiffnessSource::Csv(path) => {
            crate::report::stiffness_csv::read_stiffness_csv(path, pair.gears[0].angular_pitch())
                .map_err(StudyError::Input)?
        }
    })
}

/// Where the lumped model reads the back flanks' own k and e ([`MeshModel::back_reflection`]):
/// the pair's mirror angle in the stiffness tables' θ, which counts from their origin.
pub fn back_reflection(pair: &crate::geometry::GearPair, mesh: &MeshStiffness) -> f64 {
    pair.back_flank_reflection() - 2.0 * mesh.origin
}

/// Builds the case's lumped model (`[lumped]`, the first operating point's torque). With the
/// `ltca` source the LTCA is solved at [`force_law_loads`] (the force law, used with
/// `lumped.force_law = "load-dependent"`) and at [`QUASI_STATIC_LOADS`] (the secant k(θ) at the
/// design torque, and the reference of the model's quasi-static checks).
pub fn setup(case: &Case) -> Result<LumpedSetup, StudyError> {
    setup_with(case, None)
}

/// [`setup`] on `ltca`, the case's LTCA model of the lumped relief variant
/// ([`super::ltca::model`]) that the caller has built already: its bodies are not set up twice.
pub fn setup_on(case: &Case, ltca: &LtcaModel) -> Result<LumpedSetup, StudyError> {
    setup_with(case, Some(ltca))
}

fn setup_with(case: &Case, ltca: Option<&LtcaModel>) -> Result<LumpedSetup, StudyError> {
    let settings = &case.lumped;
    let torque = load_torque(case)?;
    let started = std::time::Instant::now();
    let (mut mesh, mut force_law, back_law, reference) = match &settings.stiffness {
        StiffnessSource::Ltca => {
            let variant = super::relief_variant(case, settings.relief.as_deref())?;
            let source = format!("ltca (relief {})", variant.name);
            let load_dependent = settings.force_law == ForceLawKind::LoadDependent;
            let modifications = &variant.modifications;
            let own;
            let ltca = match ltca {
                Some(ltca) => ltca,
                None => {
                    own = super::ltca::model(case, modifications)?;
                    &own
                }
            };
            let laws = ltca_laws_on(case, ltca, modifications, torque, &source, load_dependent)?;
            // Lend the bodies to the mesh's own mass, which the structure below asks for.
            if settings.mesh_mass && settings.bodies == BodyModel::Elastic {
                let translating =
                    gear_bodies(case, settings.bodies)?.map(|b| b.translation.is_some());
                mesh_moving_mass_on(case, ltca, translating)?;
            }
            (
                laws.mesh,
                load_dependent.then_some(laws.law),
                laws.back_law,
                Some(laws.reference),
            )
        }
        source => (mesh_stiffness(case, source, torque)?, None, None, None),
    };
    let stiffness_wall_s = started.elapsed().as_secs_f64();
    // A hub-to-hub source holds the bodies' twist and sway; elastic bodies carry them.
    let body_compliance = structure_body_compliance(case)?;
    let twist = match settings.stiffness.holds_body_twist() {
        true => body_compliance,
        false => 0.0,
    };
    (mesh, force_law) = to_rims(mesh, force_law, twist)?;
    let back_law = back_law.map(|law| law_to_rims(law, twist)).transpose()?;
    let inertias = gear_inertias(case);
    let (mut model, damping_ratio) = model_on(case, mesh, torque)?;
    let law_note = match (&force_law, &settings.stiffness) {
        (Some(law), _) => format!(
            "; mesh force law W(θ, δ) from the LTCA at {} loads, {:.3}–{:.3} × the design torque (load-dependent stiffness and loaded contact ratio; beyond them the last tangent)",
            law.torques.len(),
            law.torques[0] / torque,
            law.torques[law.torques.len() - 1] / torque
        ),
        (None, StiffnessSource::Ltca) => {
            "; secant mesh force law k(θ)(δ − e) at the design torque (lumped.force_law = \"secant\": right at that torque only)".to_string()
        }
        (None, _) => "; mesh force linear in the approach, k(θ)(δ − e) (the source gives one k(θ))".to_string(),
    };
    let law_note = law_note
        + match (&back_law, case.pair.backlash_normal > 0.0) {
            (Some(_), _) => "; back flanks: their own force law, from the LTCA of the back flanks under the reversed torque (the backlash shifts the mirror)",
            (None, false) => "; back flanks: the drive flanks' law mirrored about the centre line (exact for these symmetric teeth without backlash)",
            (None, true) => "; back flanks: the drive flanks' k(θ) mirrored about the centre line with the backlash added",
        };
    model.force_law = force_law;
    model.back_force_law = back_law;
    let natural_frequency_hz = model.linearized().natural_frequency() / std::f64::consts::TAU;
    let self_checks = match &reference {
        Some(reference) => {
            // The LTCA holds the bearings: so does the check.
            let held = MeshModel {
                structure: drivetrain(case, settings.drive, false)?,
                ..model.clone()
            };
            quasi_static_checks(case, &held, reference)
        }
        None => Vec::new(),
    };
    let model_note = structure_note(case, &model.structure, twist)? + &law_note;
    Ok(LumpedSetup {
        torque,
        model,
        stiffness_wall_s,
        inertias,
        drive: settings.drive,
        damping_ratio,
        natural_frequency_hz,
        model_note,
        self_checks,
        body_compliance,
    })
}

/// The LTCA's answers the lumped model is built from ([`ltca_laws`]).
pub struct LtcaLaws {
    /// The secant k(θ), e(θ) at the design torque (hub to hub).
    pub mesh: MeshStiffness,
    /// The drive flanks' force law (hub to hub).
    pub law: ForceLaw,
    /// The back flanks' own law where the mirror of the drive flanks is not exact.
    pub back_law: Option<ForceLaw>,
    pub reference: QuasiStaticReference,
}

/// The case's LTCA with `modifications` about the design `torque`: [`ltca_tables`], and with
/// `back` the back flanks' own force law wherever the pair has a backlash. The mirror is exact
/// for symmetric teeth without backlash (tests/ltca.rs: 7e-6 of the loaded approach); a
/// backlash shifts it by its rotation (3 % of the STE where a pair enters), so the back flanks
/// then get the LTCA of the back flanks under the reversed torque.
pub fn ltca_laws(
    case: &Case,
    modifications: &[crate::geometry::FlankModification; 2],
    torque: f64,
    source: &str,
    back: bool,
) -> Result<LtcaLaws, StudyError> {
    let ltca = super::ltca::model(case, modifications)?;
    ltca_laws_on(case, &ltca, modifications, torque, source, back)
}

/// [`ltca_laws`] on `ltca`, the case's LTCA model with `modifications`, already built.
pub fn ltca_laws_on(
    case: &Case,
    ltca: &LtcaModel,
    modifications: &[crate::geometry::FlankModification; 2],
    torque: f64,
    source: &str,
    back: bool,
) -> Result<LtcaLaws, StudyError> {
    let (mesh, law, reference) = ltca_tables(case, ltca, torque, source)?;
    let back_law = match back && case.pair.backlash_normal > 0.0 {
        true => {
            let sizes = super::ltca::element_sizes(case);
            let back = super::ltca::model_on_flank(case, modifications, sizes, Flank::Back)?;
            Some(force_law_of(
                case,
                &back,
                torque,
                &format!("{source}, back flanks"),
            )?)
        }
        false => None,
    };
    Ok(LtcaLaws {
        mesh,
        law,
        back_law,
        reference,
    })
}

/// The LTCA's cycles at [`QUASI_STATIC_LOADS`] × the design torque (`torques`, `cycles`), at
/// twice the law's positions: every other one half-way between two of the law's.
pub struct QuasiStaticReference {
    pub torques: Vec<f64>,
    pub cycles: Vec<Vec<PositionResult>>,
}

/// The LTCA of `ltca` at [`force_law_loads`] × `torque` on [`FORCE_LAW_POSITIONS`] positions
/// (the force law) and at [`QUASI_STATIC_LOADS`] × `torque` on twice as many (the quasi-static
/// reference, whose design-torque cycle at the law's positions gives the secant k(θ)).
pub fn ltca_tables(
    case: &Case,
    ltca: &LtcaModel,
    torque: f64,
    source: &str,
) -> Result<(MeshStiffness, ForceLaw, QuasiStaticReference), StudyError> {
    let check_torques: Vec<f64> = QUASI_STATIC_LOADS.iter().map(|f| f * torque).collect();
    let law_torques = force_law_torques(torque);
    // One pass over the check's positions for every torque: the law's positions are every
    // other one of them (the same angles, bit for bit), so each position's geometry (its
    // compliance solves, the costly part) is made once for both.
    let all: Vec<f64> = law_torques.iter().chain(&check_torques).copied().collect();
    let mut cycles = ltca.run_torques(2 * FORCE_LAW_POSITIONS, &all)?;
    let check_cycles = cycles.split_off(law_torques.len());
    let law_cycles: Vec<Vec<PositionResult>> = cycles
        .into_iter()
        .map(|cycle| cycle.into_iter().step_by(2).collect())
        .collect();
    let law = law_from_cycles(case, &law_torques, &law_cycles, source)?;
    let design = QUASI_STATIC_LOADS
        .iter()
        .position(|f| *f == 1.0)
        .expect("the design load is checked");
    let at_law_positions: Vec<PositionResult> =
        check_cycles[design].iter().step_by(2).cloned().collect();
    let mesh = stiffness::from_ltca(&case.pair, &at_law_positions, torque, source)
        .map_err(StudyError::Input)?;
    Ok((
        mesh,
        law,
        QuasiStaticReference {
            torques: check_torques,
            cycles: check_cycles,
        },
    ))
}

/// The force law of `ltca` (the case's bodies with a relief variant's modifications) about the
/// design `torque`: the LTCA at [`force_law_loads`] × `torque` on [`FORCE_LAW_POSITIONS`]
/// positions from the pitch point (so its origin is the LTCA's k(θ)'s).
pub fn force_law_of(
    case: &Case,
    ltca: &LtcaModel,
    torque: f64,
    source: &str,
) -> Result<ForceLaw, StudyError> {
    let law_torques = force_law_torques(torque);
    let cycles = ltca.run_torques(FORCE_LAW_POSITIONS, &law_torques)?;
    law_from_cycles(case, &law_torques, &cycles, source)
}

/// The torques of the force law about the design `torque` ([`force_law_loads`] × it).
fn force_law_torques(torque: f64) -> Vec<f64> {
    force_law_loads().iter().map(|f| f * torque).collect()
}

/// The force law from the LTCA's cycles at the law's torques.
fn law_from_cycles(
    case: &Case,
    torques: &[f64],
    cycles: &[Vec<PositionResult>],
    source: &str,
) -> Result<ForceLaw, StudyError> {
    ForceLaw::from_ltca(&case.pair, torques, cycles, source).map_err(StudyError::Input)
}

/// The model's quasi-static TE, hub to hub ([`MeshModel::quasi_static_transmission_error`]:
/// W(θ, δ) = T/r_b2, the bodies' static twist included; give it a structure without bearings,
/// which the LTCA does not have) against the LTCA's STE r_b2 φ at each torque of `reference`, at the law's
/// positions and half-way between them, over the mean loaded deflection r_b2 (φ − φ₀):
/// * the rms difference over the cycle within [`QUASI_STATIC_TOLERANCE`]: an error for the
///   load-dependent law (the table must hold the LTCA's answer between its knots and
///   positions) and for any law at the design torque; a warning for the secant law elsewhere
///   (right at one torque only, by construction);
/// * the largest difference within [`QUASI_STATIC_PEAK_TOLERANCE`], a warning: where a pair
///   enters or leaves, the STE turns sharply between two positions and the table's linear blend
///   cuts the corner (2.4 % of the deflection at 256 positions on the paper pair, measured).
pub fn quasi_static_checks(
    case: &Case,
    model: &MeshModel,
    reference: &QuasiStaticReference,
) -> Vec<Check> {
    let rb2 = case.pair.gears[1].base_radius;
    let design = model.force * rb2;
    let mut checks = Vec::new();
    for (&torque, cycle) in reference.torques.iter().zip(&reference.cycles) {
        let force = torque / rb2;
        let loaded = MeshModel {
            force,
            ..model.clone()
        };
        let n = cycle.len() as f64;
        let deflection: f64 = cycle
            .iter()
            .map(|r| rb2 * (r.ste - r.unloaded_te) / n)
            .sum();
        let differences: Vec<f64> = cycle
            .iter()
            .map(|r| {
                let theta = r.roll_angle - model.mesh.origin;
                loaded.quasi_static_transmission_error(theta) - rb2 * r.ste
            })
            .collect();
        let rms = (differences.iter().map(|d| d * d).sum::<f64>() / n).sqrt();
        let largest = crate::signal::largest(differences.iter().map(|d| d.abs()));
        let percent = 100.0 * torque / design;
        let source = format!(
            "the LTCA at {torque:.4} N·m on the same mesh, {} positions",
            cycle.len()
        );
        let rms_check = Check::new(
            "lumped",
            format!(
                "quasi-static TE at {percent:.0} % of the design torque: rms difference from the LTCA's STE over the mean loaded deflection"
            ),
            (rms / deflection, 0.0),
            source.clone(),
            (CheckKind::Absolute, QUASI_STATIC_TOLERANCE),
        );
        let at_design = (torque / design - 1.0).abs() < 1e-9;
        checks.push(if model.force_law.is_none() && !at_design {
            rms_check.warning()
        } else {
            rms_check
        });
        checks.push(
            Check::new(
                "lumped",
                format!(
                    "quasi-static TE at {percent:.0} % of the design torque: largest difference from the LTCA's STE over the mean loaded deflection"
                ),
                (largest / deflection, 0.0),
                source,
                (CheckKind::Absolute, QUASI_STATIC_PEAK_TOLERANCE),
            )
            .warning(),
        );
    }
    checks
}

/// `mesh` and `law`, hub to hub, with the bodies' compliance `twist` [m/N] (their twist and
/// their rims' sway, [`bodies_line_compliance`]) taken out of series: k′ = 1/(1/k − c_b), and
/// δ′ = δ − c_b W for the law: the mesh between the rims.
pub fn to_rims(
    mesh: MeshStiffness,
    law: Option<ForceLaw>,
    twist: f64,
) -> Result<(MeshStiffness, Option<ForceLaw>), StudyError> {
    if twist == 0.0 {
        return Ok((mesh, law));
    }
    let refused = |what: &str| {
        StudyError::Input(format!(
            "the gear bodies' twist and sway ({twist:.3e} m/N) is not below the {what}: check \
             bore_radius_mm and the stiffness source, or set lumped.body_sway = \"off\" or \
             lumped.bodies = \"rigid\""
        ))
    };
    let mesh = mesh
        .without_series_compliance(twist)
        .ok_or_else(|| refused("mesh compliance"))?;
    Ok((mesh, law.map(|law| law_to_rims(law, twist)).transpose()?))
}

/// A force law `law`, hub to hub, with the bodies' twist `twist` [m/N] taken out of series
/// (δ′ = δ − c_b W, [`to_rims`]).
pub fn law_to_rims(law: ForceLaw, twist: f64) -> Result<ForceLaw, StudyError> {
    law.without_series_compliance(twist).ok_or_else(|| {
        StudyError::Input(format!(
            "the gear bodies' twist and sway ({twist:.3e} m/N) is not below the mesh's tangent \
             compliance at every load of the force law: check bore_radius_mm and the stiffness \
             source, or set lumped.body_sway = \"off\" or lumped.bodies = \"rigid\""
        ))
    })
}

/// Each gear body as the lumped model holds it (`[lumped] bodies`): elastic, hub and rim with
/// the annulus's torsional compliance between them and the hub's share of the inertia
/// ([`crate::geometry::Gear::body_hub_area_moment`]), the rims swaying on their bores where
/// `[lumped] body_sway` asks for it ([`rim_sway`], [`sway_matters`]); or rigid. The case's
/// inertias, when they exceed the body's own, add what turns with the gear (coupling, shaft)
/// at the hub; when they fall short (a lightened body), both shares scale.
pub fn gear_bodies(case: &Case, bodies: BodyModel) -> Result<[GearBody; 2], StudyError> {
    let twisting = twisting_bodies(case, bodies);
    if bodies == BodyModel::Rigid || case.lumped.body_sway == BodySway::Off {
        return Ok(twisting);
    }
    let swaying = swaying_bodies(case, twisting)?;
    Ok(match case.lumped.body_sway {
        BodySway::Auto if !sway_matters(case, [twisting, swaying])? => twisting,
        _ => swaying,
    })
}

/// `twisting`, the case's elastic bodies, with their rims' sway ([`rim_sway`]).
fn swaying_bodies(case: &Case, twisting: [GearBody; 2]) -> Result<[GearBody; 2], StudyError> {
    let mut swaying = twisting;
    for (body, sway) in swaying.iter_mut().zip(rim_sway(case)?) {
        body.translation = Some(sway);
    }
    Ok(swaying)
}

/// How far the rims' sway moves the case's mesh mode ([`sway_shift`]) with elastic bodies,
/// whatever `[lumped] body_sway` says: what `"auto"` decides on, for the model's note.
pub fn case_sway_shift(case: &Case) -> Result<f64, StudyError> {
    let twisting = twisting_bodies(case, BodyModel::Elastic);
    sway_shift(case, [twisting, swaying_bodies(case, twisting)?])
}

/// [`gear_bodies`] without the sway: the bodies' inertias and twist.
fn twisting_bodies(case: &Case, bodies: BodyModel) -> [GearBody; 2] {
    let inertias = gear_inertias(case);
    std::array::from_fn(|i| {
        let gear = &case.pair.gears[i];
        match bodies {
            BodyModel::Rigid => GearBody::rigid(inertias[i]),
            BodyModel::Elastic => {
                let density = case.material.density * gear.spec.face_width;
                let own = density * gear.area_moments().1;
                let hub_own = density * gear.body_hub_area_moment();
                let hub = match inertias[i] >= own {
                    true => hub_own + (inertias[i] - own),
                    false => hub_own / own * inertias[i],
                };
                GearBody {
                    hub_inertia: hub,
                    rim_inertia: inertias[i] - hub,
                    torsional_compliance: gear.body_torsional_compliance(
                        case.material.youngs_modulus,
                        case.material.poisson_ratio,
                    ),
                    translation: None,
                }
            }
        }
    })
}

/// How far the rims' sway must move the pair's mesh mode, driver held or both free, for
/// `body_sway = "auto"` to give the bodies their sway: 0.5 % (a quarter of the 2 % the lumped
/// mesh mode is held to against the FE modal). Below it the sway stays in the mesh stiffness,
/// massless, and the model keeps its coordinates and its RK4 step (the sway's own mode lies
/// at 17.6 kHz on the seed paper's pair, 3.6 × the lumped both-free mesh mode).
pub const SWAY_MODE_SHIFT: f64 = 0.005;

/// Whether the rims' sway moves the mesh mode of the pair by more than [`SWAY_MODE_SHIFT`]
/// under either drive (driver held, both free; no shafts or bearings, as the FE modal): the
/// structure's mesh mode on the bodies `[twisting, swaying]`, the teeth's mesh stiffness
/// estimated by ISO 6336-1's c_γα·b at the design torque (the decision needs its order only;
/// the estimate's load factor makes it, and so the decision near the threshold, depend on the
/// torque below 100 N/mm of face width, and with no load the sway is kept), the sway in series
/// with it, massless, on the twisting bodies.
pub fn sway_matters(case: &Case, bodies: [[GearBody; 2]; 2]) -> Result<bool, StudyError> {
    // NaN (no estimate, no load): keep the sway rather than guess it away.
    Ok(!(sway_shift(case, bodies)? <= SWAY_MODE_SHIFT))
}

/// The largest |f_with/f_without − 1| of [`sway_matters`]'s mesh modes over the two drives;
/// NaN where the teeth's stiffness has no estimate (no load).
pub fn sway_shift(case: &Case, [twisting, swaying]: [[GearBody; 2]; 2]) -> Result<f64, StudyError> {
    let pair = &case.pair;
    // The estimate at the design torque's size (a reversed torque loads the same teeth).
    let torque = load_torque(case)?.abs();
    let teeth = stiffness::iso_6336_method_b(pair, torque, case.material.youngs_modulus)
        .mesh_stiffness(pair, torque)
        .mean();
    if !(teeth > 0.0 && teeth.is_finite()) {
        return Ok(f64::NAN);
    }
    let sway: f64 = swaying
        .iter()
        .filter_map(|b| b.translation.map(|t| 1.0 / t.stiffness))
        .sum();
    let undamped = SpringDamping::Ratio(0.0);
    let mut largest: f64 = 0.0;
    for drive in [Drive::Speed, Drive::Torque] {
        let mode = |gears: [GearBody; 2], k: f64| -> Result<f64, StudyError> {
            // The decision is the sway's alone: both without the mesh's own mass.
            let structure = bare_drivetrain(case, drive, (gears, undamped), [None; 2], false)?;
            Ok(structure.mesh_mode(k).frequency)
        };
        let without = mode(twisting, 1.0 / (1.0 / teeth + sway))?;
        let with = mode(swaying, teeth)?;
        let shift = (with / without - 1.0).abs();
        // A NaN shift is not "no shift".
        if !(shift <= largest) {
            largest = shift;
        }
    }
    Ok(largest)
}

/// Each gear rim's sway on its held bore ([`crate::ltca::body::body_translation_of`] on the
/// case's coarse element size all round, both gears side by side): mass and stiffness. Its
/// frequency √(k_y/m_y) lies 2.4–3.1 % above the pair FE modal's lateral mode across the line
/// of action (paper pair, 24/40, 17/53: the Rayleigh quotient of a static shape with rigid
/// teeth) and within 0.2 % of the same on half the element size (a thin pinion rim within
/// 5 % at 110 kHz, far above any mesh mode). Each body's is solved once per
/// process (0.1 to 0.25 s on the paper's and 17/53's gears), as every structure asks for it.
pub fn rim_sway(case: &Case) -> Result<[RimTranslation; 2], StudyError> {
    type Memo = std::sync::Mutex<std::collections::HashMap<String, BodyTranslation>>;
    static MEMO: std::sync::OnceLock<Memo> = std::sync::OnceLock::new();
    let memo = MEMO.get_or_init(Default::default);
    let material = case.ltca_material();
    let spec = case.mesh_spec(Vec::new());
    let one = |i: usize| -> Result<RimTranslation, StudyError> {
        let gear = &case.pair.gears[i];
        let key = format!("{gear:?} {material:?} {spec:?}");
        let known = memo.lock().expect("the memo's lock").get(&key).copied();
        let translation = match known {
            Some(t) => t,
            None => {
                let t = crate::ltca::body::body_translation_of(gear, &spec, material)
                    .map_err(|e| StudyError::Input(format!("gear {}'s body sway: {e}", i + 1)))?;
                memo.lock().expect("the memo's lock").insert(key, t);
                t
            }
        };
        Ok(RimTranslation {
            mass: translation.mass_per_density * case.material.density,
            stiffness: translation.stiffness,
        })
    };
    let (first, second) = rayon::join(|| one(0), || one(1));
    Ok([first?, second?])
}

/// The compliance the case's `bodies` put in series with the mesh along the line of action,
/// Σ r_b² c_t + Σ 1/k_y over their twist and sway [m/N] (what a hub-to-hub stiffness loses to
/// them, [`GearBody::line_compliance`]).
pub fn bodies_line_compliance(case: &Case, bodies: BodyModel) -> Result<f64, StudyError> {
    Ok(gear_bodies(case, bodies)?
        .iter()
        .zip(&case.pair.gears)
        .map(|(body, gear)| body.line_compliance(gear.base_radius))
        .sum())
}

/// [`bodies_line_compliance`] of the case's own `[lumped] bodies`.
pub fn structure_body_compliance(case: &Case) -> Result<f64, StudyError> {
    bodies_line_compliance(case, case.lumped.bodies)
}

/// The case's drivetrain under `drive`: its bodies, shafts and (with `bearings`, when the case
/// asks for them) bearings.
pub fn drivetrain(case: &Case, drive: Drive, bearings: bool) -> Result<Structure, StudyError> {
    let settings = &case.lumped;
    let damping = SpringDamping::Ratio(settings.drivetrain_damping_ratio);
    drivetrain_with(
        case,
        drive,
        (settings.bodies, damping),
        settings.shafts,
        bearings,
    )
}

/// The pair under `drive` with `bodies`, their and the shafts' spring damping, `shafts` and
/// (with `bearings`, when the case asks for them) the case's bearings: e.g. the explicit FE's
/// boundary conditions (elastic bodies with the FE's stiffness-proportional damping, no
/// shafts, no bearings).
pub fn drivetrain_with(
    case: &Case,
    drive: Drive,
    (bodies, spring_damping): (BodyModel, SpringDamping),
    shafts: [Option<crate::lumped::Shaft>; 2],
    bearings: bool,
) -> Result<Structure, StudyError> {
    let gears = gear_bodies(case, bodies)?;
    drivetrain_of(case, drive, (gears, spring_damping), shafts, bearings)
}

/// [`drivetrain_with`] on the gear bodies `gears` as given (e.g. an inertia split other than
/// [`gear_bodies`]'s).
pub fn drivetrain_of(
    case: &Case,
    drive: Drive,
    (gears, spring_damping): ([GearBody; 2], SpringDamping),
    shafts: [Option<crate::lumped::Shaft>; 2],
    bearings: bool,
) -> Result<Structure, StudyError> {
    let structure = bare_drivetrain(case, drive, (gears, spring_damping), shafts, bearings)?;
    // Elastic bodies carry the mesh's own moving mass (the rigid-gear model is the old one).
    let elastic = gears.iter().any(|g| g.torsional_compliance > 0.0);
    Ok(match case.lumped.mesh_mass && elastic {
        true => structure.with_mesh_mass(mesh_moving_mass(
            case,
            gears.map(|g| g.translation.is_some()),
        )?),
        false => structure,
    })
}

/// [`drivetrain_of`] with a massless mesh spring (without [`mesh_moving_mass`]).
fn bare_drivetrain(
    case: &Case,
    drive: Drive,
    (gears, spring_damping): ([GearBody; 2], SpringDamping),
    shafts: [Option<crate::lumped::Shaft>; 2],
    bearings: bool,
) -> Result<Structure, StudyError> {
    let settings = &case.lumped;
    let pair = &case.pair;
    let bearings = (bearings && settings.bearings).then(|| {
        let mass = settings.gear_masses.unwrap_or_else(|| {
            std::array::from_fn(|i| {
                let gear = &pair.gears[i];
                case.material.density * gear.spec.face_width * gear.area_moments().0
            })
        });
        let stiffness = settings.bearing_stiffness;
        Bearings {
            mass,
            stiffness,
            damping: std::array::from_fn(|i| {
                2.0 * settings.bearing_damping_ratio * (stiffness[i] * mass[i]).sqrt()
            }),
        }
    });
    Structure::drivetrain(&DrivetrainSpec {
        drive,
        base_radii: [pair.gears[0].base_radius, pair.gears[1].base_radius],
        gears,
        shafts,
        bearings,
        spring_damping,
    })
    .map_err(|e| StudyError::Input(format!("[lumped] drivetrain: {e}")))
}

/// Positions over a base pitch at which [`mesh_moving_mass`] takes the pair's static shape.
/// m_d about doubles from single to double contact (7 / 14 g on the paper pair), so four
/// equal steps sample the double-contact share to a quarter: m_d to about ±10 %, the mesh
/// mode to ±0.1 % on the paper pair (the whole mass moves it 0.9 %).
pub const MESH_MASS_POSITIONS: usize = 4;

/// The mass the mesh itself moves, m_d [kg] along the line of action, beyond the gears' rigid
/// rotations and, where `translating`, the rims' sway (the coordinates the lumped model has,
/// the sway by its own static shapes, [`crate::ltca::modal::ltca_sway_shapes`]):
/// [`crate::ltca::modal::mesh_moving_mass`] on the pair of the lumped relief variant
/// (`[lumped] relief`, the flanks the model's force law comes from) at its LTCA mesh under the
/// design torque, the mean over [`MESH_MASS_POSITIONS`] positions of a base pitch, side by
/// side. Once per process and pair (the LTCA's bodies, unless [`setup`] lends its own, and
/// four static solves of the tied pair, and where the rims sway a factorization of each body:
/// about 2 s, 0.9 s with the bodies lent).
pub fn mesh_moving_mass(case: &Case, translating: [bool; 2]) -> Result<f64, StudyError> {
    let key = mesh_mass_key(case, translating)?;
    if let Some(mass) = known_mesh_mass(&key) {
        return Ok(mass);
    }
    let variant = super::relief_variant(case, case.lumped.relief.as_deref())?;
    let ltca = super::ltca::model(case, &variant.modifications).map_err(mesh_mass_error)?;
    mesh_moving_mass_on(case, &ltca, translating)
}

/// An error on the way to the mesh's own mass, with what to do about it.
fn mesh_mass_error(e: impl std::fmt::Display) -> StudyError {
    StudyError::Input(format!(
        "the mesh's own moving mass (lumped.mesh_mass) needs the LTCA of the pair, which \
         stopped: {e}; set lumped.mesh_mass = false to leave it out"
    ))
}

/// [`mesh_moving_mass`] on `ltca`, the case's LTCA model of the lumped relief variant, already
/// built.
pub(crate) fn mesh_moving_mass_on(
    case: &Case,
    ltca: &LtcaModel,
    translating: [bool; 2],
) -> Result<f64, StudyError> {
    use rayon::prelude::*;
    let key = mesh_mass_key(case, translating)?;
    if let Some(mass) = known_mesh_mass(&key) {
        return Ok(mass);
    }
    let torque = load_torque(case)?.abs();
    let material = case.ltca_material();
    let shapes = match translating.iter().any(|t| *t) {
        true => {
            Some(crate::ltca::modal::ltca_sway_shapes(ltca, material).map_err(mesh_mass_error)?)
        }
        false => None,
    };
    let sway: [Option<&crate::ltca::body::SwayShapes>; 2] =
        std::array::from_fn(|g| shapes.as_ref().filter(|_| translating[g]).map(|s| &s[g]));
    let masses: Vec<f64> = (0..MESH_MASS_POSITIONS)
        .into_par_iter()
        .map(|j| {
            crate::ltca::modal::mesh_moving_mass(
                ltca,
                (j, MESH_MASS_POSITIONS),
                torque,
                (material, case.material.density),
                sway,
            )
        })
        .collect::<Result<Vec<_>, _>>()
        .map_err(mesh_mass_error)?
        .into_iter()
        .map(|m| {
            // Its own checks: the load does no work on the rolling, and the gears' rotations
            // approach alike at every tie (both round-off: 1e-12 and 6e-8 on the paper pair).
            match m.held_reaction < 1e-6 && m.approach_spread < 1e-6 {
                true => Ok(m.mass),
                false => Err(StudyError::Input(format!(
                    "the mesh's own moving mass failed its checks (held hub's reaction {:.1e} of \
                     the load, approach spread {:.1e} over the ties): report this case, or set \
                     lumped.mesh_mass = false",
                    m.held_reaction, m.approach_spread
                ))),
            }
        })
        .collect::<Result<_, _>>()?;
    let mass = masses.iter().sum::<f64>() / masses.len() as f64;
    if !(mass.is_finite() && mass >= 0.0) {
        return Err(StudyError::Input(format!(
            "the mesh's moving mass came out {mass:e} kg: check bore_radius_mm and the mesh \
             sizes, or set lumped.mesh_mass = false"
        )));
    }
    mesh_mass_memo()
        .lock()
        .expect("the memo's lock")
        .insert(key, mass);
    Ok(mass)
}

type MeshMassMemo = std::sync::Mutex<std::collections::HashMap<String, f64>>;

/// The memo's m_d under `key`, if any.
fn known_mesh_mass(key: &str) -> Option<f64> {
    mesh_mass_memo()
        .lock()
        .expect("the memo's lock")
        .get(key)
        .copied()
}

fn mesh_mass_memo() -> &'static MeshMassMemo {
    static MEMO: std::sync::OnceLock<MeshMassMemo> = std::sync::OnceLock::new();
    MEMO.get_or_init(Default::default)
}

/// What [`mesh_moving_mass`] depends on: the pair, the lumped variant's flanks, the LTCA's
/// mesh and material, the torque.
fn mesh_mass_key(case: &Case, translating: [bool; 2]) -> Result<String, StudyError> {
    let variant = super::relief_variant(case, case.lumped.relief.as_deref())?;
    Ok(format!(
        "{:?} {:?} {:?} {:?} {:e} {} {translating:?}",
        case.pair,
        variant.modifications,
        case.ltca_material(),
        case.mesh_spec(Vec::new()),
        load_torque(case)?.abs(),
        case.material.density
    ))
}

/// One line saying what the structure is and what it leaves out.
fn structure_note(case: &Case, structure: &Structure, twist: f64) -> Result<String, StudyError> {
    let drive = case.lumped.drive.name();
    let mut note = format!(
        "{}-DOF lumped model ({drive} drive; coordinates {}): ",
        structure.dofs,
        structure.names.join(", ")
    );
    note += match case.lumped.bodies {
        BodyModel::Elastic => {
            "elastic gear bodies (hub and rim, the annulus's twist between bore and root circle)"
        }
        BodyModel::Rigid => "rigid gear bodies",
    };
    let swaying = gear_bodies(case, case.lumped.bodies)?
        .iter()
        .any(|b| b.translation.is_some());
    if swaying {
        note += ", each rim swaying on its held bore along the line of action (a static FE of the body reduced onto the rim's translation, one coordinate per gear)";
    }
    if twist > 0.0 {
        let what = if swaying { "twist and sway" } else { "twist" };
        note += &format!(
            ", the hub-to-hub stiffness with that {what} ({twist:.3e} m/N) taken out of the mesh"
        );
    }
    if case.lumped.bodies == BodyModel::Elastic && !swaying {
        // With the mesh's own mass the sway's mass rides in it (its static share).
        let massless = match case.lumped.mesh_mass {
            true => "its mass in the mesh's moving mass below",
            false => "massless",
        };
        note += &match case.lumped.body_sway {
            BodySway::Off => format!("; the rims' sway on their bores left in the mesh stiffness, {massless} (lumped.body_sway = \"off\")"),
            _ => format!(
                "; the rims' sway on their bores left in the mesh stiffness, {massless} (as a coordinate of its own it would move a massless mesh's mode by {:.2} %, under {} %; lumped.body_sway = \"on\" makes it one)",
                100.0 * case_sway_shift(case)?,
                100.0 * SWAY_MODE_SHIFT
            ),
        };
    }
    if case.lumped.bodies == BodyModel::Elastic {
        note += &match case.lumped.mesh_mass {
            true => {
                let translating =
                    gear_bodies(case, case.lumped.bodies)?.map(|b| b.translation.is_some());
                format!(
                    "; the mesh's own moving mass, {:.2} g along its deflection (the teeth's bending and the rims' local deformation beyond the coordinates' rigid motions, from a static FE of the meshed pair)",
                    1e3 * mesh_moving_mass(case, translating)?
                )
            }
            false => "; the mesh spring massless (lumped.mesh_mass = false)".to_string(),
        };
    }
    if case.lumped.bearings {
        note += "; each gear's translation on its bearings along the line of action (across it left out: a frictionless spur mesh force does not excite it)";
    }
    for n in &structure.notes {
        note += "; ";
        note += n;
    }
    Ok(note)
}

/// The case's lumped model (`[lumped]`: drive, bodies, shafts, bearings, damping) on the mesh
/// stiffness `mesh` (between the rims: a hub-to-hub one through [`to_rims`] first) under
/// `torque`, with the damping ratio it was given.
pub fn model_on(
    case: &Case,
    mesh: MeshStiffness,
    torque: f64,
) -> Result<(MeshModel, f64), StudyError> {
    let settings = &case.lumped;
    let pair = &case.pair;
    // Zero backlash: the back flanks engage as soon as the drive flanks open, with their own
    // k and e (back_reflection below).
    let backlash = Some(pair.backlash_normal.max(0.0));
    let mut model = MeshModel {
        structure: drivetrain(case, settings.drive, true)?,
        back_reflection: Some(back_reflection(pair, &mesh)),
        mesh,
        damping: 0.0,
        damping_site: DampingSite::MeshDeflection,
        force: torque / pair.gears[1].base_radius,
        backlash,
        force_law: None,
        back_force_law: None,
    };
    // A coefficient in the case wins over its ratio (`--damping-ratio` removes the coefficient).
    let damping_ratio = match settings.mesh_damping {
        Some(c) => c / model.damping_from_ratio(1.0),
        None => settings.damping_ratio,
    };
    model.damping = model.damping_from_ratio(damping_ratio);
    Ok((model, damping_ratio))
}

/// The driver speed at which the mesh frequency equals `frequency_hz`: f_mesh = z₁ n / 60 [rpm].
pub fn speed_for_mesh_frequency(case: &Case, frequency_hz: f64) -> f64 {
    frequency_hz * 60.0 / case.pair.gears[0].teeth() as f64
}

/// Undamped natural frequencies of the lumped model linearized about the design load (the
/// force law's mean tangent stiffness; a linear law's k̄) [Hz].
pub fn mode_frequencies_hz(model: &MeshModel) -> Vec<f64> {
    let linear = model.linearized();
    linear
        .mode_frequencies(linear.mesh.mean())
        .iter()
        .map(|w| w / std::f64::consts::TAU)
        .collect()
}
