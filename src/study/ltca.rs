//! The LTCA study (`geardyn ltca`): the quasi-static loaded tooth contact over one base pitch for
//! every relief variant of the case (or one), with the potential-energy and ISO 6336-1
//! stiffness beside it.

use serde::Serialize;

use crate::case::Case;
use crate::geometry::engagement::{self, ENGAGEMENT_MARGIN};
use crate::geometry::FlankModification;
use crate::ltca::{
    engaging_teeth_on, Flank, LtcaModel, Periodicity, PositionResult, PERIODICITY_TOLERANCE,
};
use crate::stiffness::{self, potential_energy, IsoStiffness, MeshStiffness};
use crate::strength::hertz::{self, PressurePoint};
use crate::strength::iso6336::{self, Elastic};
use crate::strength::safety;

use super::checks::{Check, CheckKind};
use super::{load_torque, Progress, StudyError};
use crate::mesh::ToothLayout;
use crate::signal::largest;

/// Both gear bodies of the case for the LTCA, meshed fine on the engaging teeth with the case's
/// element sizes, factorized and condensed.
pub fn model(case: &Case, modifications: &[FlankModification; 2]) -> Result<LtcaModel, StudyError> {
    model_on_flank(case, modifications, element_sizes(case), Flank::Drive)
}

/// The case's LTCA element sizes: flanks, the rest [m].
pub fn element_sizes(case: &Case) -> (f64, f64) {
    let mesh = &case.file.mesh;
    (mesh.fine_element_mm * 1e-3, mesh.coarse_element_mm * 1e-3)
}

/// [`model`] with other element sizes: flanks `fine_size`, the rest `coarse_size` [m].
pub fn model_with_sizes(
    case: &Case,
    modifications: &[FlankModification; 2],
    fine_size: f64,
    coarse_size: f64,
) -> Result<LtcaModel, StudyError> {
    model_on_flank(case, modifications, (fine_size, coarse_size), Flank::Drive)
}

/// [`model_with_sizes`] on teeth laid out as `layout`: the LTCA on an explicit run's mesh
/// (the case's `fe.tooth_layout`), its same-discretization reference.
pub fn model_with_layout(
    case: &Case,
    modifications: &[FlankModification; 2],
    sizes: (f64, f64),
    layout: ToothLayout,
) -> Result<LtcaModel, StudyError> {
    model_laid_out(case, modifications, sizes, layout, Flank::Drive)
}

/// The LTCA bodies meshed fine on the teeth whose `flank` engages, loading that flank
/// ([`Flank::Back`]: the back flanks under the reversed torque, `modifications` theirs), with
/// flank elements `fine_size` and the rest `coarse_size` [m].
pub fn model_on_flank(
    case: &Case,
    modifications: &[FlankModification; 2],
    sizes: (f64, f64),
    flank: Flank,
) -> Result<LtcaModel, StudyError> {
    model_laid_out(case, modifications, sizes, ToothLayout::Graded, flank)
}

fn model_laid_out(
    case: &Case,
    modifications: &[FlankModification; 2],
    (fine_size, coarse_size): (f64, f64),
    layout: ToothLayout,
    flank: Flank,
) -> Result<LtcaModel, StudyError> {
    let teeth = engaging_teeth_on(&case.pair, flank);
    let spec = |fine_teeth: Vec<usize>| crate::mesh::MeshSpec {
        fine_size,
        coarse_size,
        fine_teeth,
        layout,
    };
    let specs = [spec(teeth[0].clone()), spec(teeth[1].clone())];
    check_memory(case, modifications, &specs)?;
    Ok(LtcaModel::on_flank(
        &case.pair,
        modifications,
        specs,
        case.ltca_material(),
        flank,
    )?)
}

/// Refuses LTCA bodies whose meshes, stiffness triplets and K would not fit in memory
/// ([`crate::resources`]), counted without meshing ([`crate::mesh::mesh_size`]) for the larger
/// body; each factor is checked again before it is computed, on faer's symbolic analysis. (The
/// two bodies are built side by side, so the peak can hold parts of both: not counted yet.)
pub fn check_memory(
    case: &Case,
    modifications: &[FlankModification; 2],
    specs: &[crate::mesh::MeshSpec; 2],
) -> Result<(), StudyError> {
    let [first, second] = [0, 1].map(|g| {
        let size = crate::mesh::mesh_size(&case.pair.gears[g], &modifications[g], &specs[g]);
        crate::fe::assembly::assembly_memory(size)
    });
    crate::resources::check_memory(
        &format!(
            "the LTCA bodies' meshes and stiffness matrices at {} / {} mm elements",
            specs[0].fine_size * 1e3,
            specs[0].coarse_size * 1e3
        ),
        &first.or(second),
        crate::fe::assembly::COARSEN,
    )?;
    Ok(())
}

/// The LTCA's mesh stiffness k(θ), e(θ) of `modifications` at `torque` over `positions`.
pub fn mesh_stiffness(
    case: &Case,
    variant_name: &str,
    modifications: &[FlankModification; 2],
    positions: usize,
    torque: f64,
) -> Result<MeshStiffness, StudyError> {
    let results = model(case, modifications)?.run(positions, torque, &|_| {})?;
    stiffness::from_ltca(
        &case.pair,
        &results,
        torque,
        format!("ltca (relief {variant_name})"),
    )
    .map_err(StudyError::Input)
}

/// Options of the study.
#[derive(Debug, Clone, PartialEq)]
pub struct LtcaOptions {
    /// Mesh positions over one base pitch.
    pub positions: usize,
    /// Only this relief variant; None: every variant of the case.
    pub relief: Option<String>,
}

/// One relief variant's cycle.
#[derive(Debug, Clone)]
pub struct VariantCycle {
    pub name: String,
    pub modifications: [FlankModification; 2],
    /// (gear-1 tooth, gear-2 tooth) of `PositionResult::pair_forces`.
    pub tooth_pairs: Vec<(usize, usize)>,
    pub results: Vec<PositionResult>,
    pub mesh_stiffness: MeshStiffness,
    pub summary: VariantSummary,
    /// The run's checks of its own answer ([`self_checks`]).
    pub checks: Vec<Check>,
    /// Hertz pressure of every loaded pair at every position ([`crate::strength::hertz`]).
    pub pressure: Vec<PressurePoint>,
    /// The fillet stress of every tooth of a pair at every position ([`root_stress_cycle`]).
    pub root_stress: Vec<RootStressRow>,
    /// The FE's contact pressure of every loaded pair at every position ([`fe_pressure_cycle`]).
    pub fe_pressure: Vec<FePressureRow>,
}

/// Headline numbers of one relief variant.
#[derive(Debug, Clone, Serialize)]
pub struct VariantSummary {
    pub relief_variant: String,
    pub mesh_stiffness_mean_n_per_m: f64,
    pub mesh_stiffness_min_n_per_m: f64,
    pub mesh_stiffness_max_n_per_m: f64,
    /// Linear loaded STE r_b2·φ along the line of action.
    pub ste_mean_um: f64,
    pub ste_peak_to_peak_um: f64,
    pub unloaded_te_peak_to_peak_um: f64,
    /// Largest KKT residual over the cycle.
    pub max_kkt_residual: f64,
    pub elements: [usize; 2],
    pub free_dofs: [usize; 2],
    pub factorization_wall_s: f64,
    pub condensation_wall_s: f64,
    pub cycle_wall_s: f64,
    /// The largest Hertz pressure over the cycle away from the tips, and where
    /// ([`crate::strength::hertz`]).
    pub contact_pressure_max_mpa: f64,
    pub contact_pressure_max_at: Option<PressureAt>,
    /// The largest at a tip corner, where the involute's Hertz does not hold (null: no tip
    /// carried load).
    pub contact_pressure_at_tip_max_mpa: Option<f64>,
    /// The FE's own contact pressure ([`fe_pressure_cycle`]): the largest away from edge
    /// contacts, and the largest with one (null: none), which the mesh bounds (it grows as the
    /// flank elements shrink) [MPa]. Not resolved where the Hertz half width spans few flank
    /// elements (the default mesh reads about 1.5 × Hertz on the paper pair, validation/strength):
    /// the safety factors take the Hertz pressure.
    pub contact_pressure_fe_max_mpa: f64,
    pub contact_pressure_fe_at_tip_corner_max_mpa: Option<f64>,
    /// Per gear, the largest fillet tension over the cycle, where, and the largest compression
    /// (FE, [`root_stress_cycle`]).
    pub root_stress: [Option<RootStressPeak>; 2],
    /// The static safety factors of this variant's stresses and ISO's.
    pub safety_factors: Option<SafetyFactors>,
}

/// Where a pressure peak sits.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct PressureAt {
    /// Driver roll angle of tooth 0's contact at the position [deg].
    pub roll_angle_deg: f64,
    /// Along the line of action from T₁ [mm], and the pair's normal force there [N].
    pub path_mm: f64,
    pub force_n: f64,
    /// The gear-1 / gear-2 teeth of the pair.
    pub teeth: (usize, usize),
}

/// The tooth-root stress of one tooth at one position: the largest principal stress on the
/// fillet of its loaded flank's side (tension) and the smallest on the other side (compression),
/// each with the radius of its fillet node.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct RootStressRow {
    pub position: usize,
    pub roll_angle_deg: f64,
    /// 1 or 2.
    pub gear: usize,
    pub tooth: usize,
    /// Where this tooth's pair touches, along the line of action from T₁ [mm] (None: the tooth
    /// carries no load here; its fillet feels its loaded neighbours).
    pub path_mm: Option<f64>,
    pub tension_mpa: f64,
    pub tension_radius_mm: f64,
    /// The mesh node of the tension's fillet node.
    #[serde(skip)]
    pub tension_node: usize,
    pub compression_mpa: f64,
    pub compression_radius_mm: f64,
}

/// The fillet stress of every tooth of a tooth pair at every position of the cycle: the LTCA's
/// contact forces at each position through the bodies' fillet influence
/// ([`crate::ltca::LtcaModel::fillet_stresses`]).
pub fn root_stress_cycle(
    model: &LtcaModel,
    positions: usize,
    torque: f64,
) -> Result<Vec<RootStressRow>, StudyError> {
    use crate::fe::recovery::{max_principal, min_principal};
    use rayon::prelude::*;
    let per_position: Vec<Vec<RootStressRow>> = (0..positions)
        .into_par_iter()
        .map(|j| -> Result<Vec<RootStressRow>, StudyError> {
            let contacts = model.loaded_contacts(j, positions, torque)?;
            let stresses = model.fillet_stresses(&contacts);
            let mut rows = Vec::new();
            for (g, gear_stresses) in stresses.iter().enumerate() {
                let fillet = &model.bodies[g].fillet;
                let mut teeth: Vec<usize> = model
                    .tooth_pairs
                    .iter()
                    .map(|p| if g == 0 { p.0 } else { p.1 })
                    .collect();
                teeth.sort_unstable();
                teeth.dedup();
                for tooth in teeth {
                    let result = &contacts.result;
                    let path_mm = model.tooth_pairs.iter().enumerate().find_map(|(k, p)| {
                        let own = if g == 0 { p.0 } else { p.1 };
                        (own == tooth && result.pair_forces[k] > 0.0)
                            .then_some(result.pair_positions[k])
                            .flatten()
                            .map(|s| s * 1e3)
                    });
                    let mut row = RootStressRow {
                        position: j,
                        roll_angle_deg: result.roll_angle.to_degrees(),
                        gear: g + 1,
                        tooth,
                        path_mm,
                        tension_mpa: f64::NEG_INFINITY,
                        tension_radius_mm: f64::NAN,
                        tension_node: usize::MAX,
                        compression_mpa: f64::INFINITY,
                        compression_radius_mm: f64::NAN,
                    };
                    for (node, s) in fillet.nodes.iter().zip(gear_stresses) {
                        if node.tooth != tooth {
                            continue;
                        }
                        if node.loaded_side {
                            let t = max_principal(*s) * 1e-6;
                            if t > row.tension_mpa {
                                (row.tension_mpa, row.tension_radius_mm, row.tension_node) =
                                    (t, node.radius * 1e3, node.node);
                            }
                        } else {
                            let c = min_principal(*s) * 1e-6;
                            if c < row.compression_mpa {
                                (row.compression_mpa, row.compression_radius_mm) =
                                    (c, node.radius * 1e3);
                            }
                        }
                    }
                    if !(row.tension_mpa.is_finite() && row.compression_mpa.is_finite()) {
                        return Err(StudyError::Input(format!(
                            "gear {} tooth {tooth}: no fillet surface node found on {} side \
                             (the mesh's fillet between the root and the form circle)",
                            g + 1,
                            if row.tension_mpa.is_finite() {
                                "the unloaded"
                            } else {
                                "the loaded"
                            }
                        )));
                    }
                    rows.push(row);
                }
            }
            Ok(rows)
        })
        .collect::<Result<_, _>>()?;
    Ok(per_position.into_iter().flatten().collect())
}

/// The FE's contact pressure of one loaded tooth pair at one position: the largest traction of
/// the flank nodes of its two teeth ([`crate::ltca::LtcaModel::flank_tractions`]).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct FePressureRow {
    pub position: usize,
    /// Tooth pair (index into the model's `tooth_pairs`).
    pub pair: usize,
    pub pressure_mpa: f64,
    /// The gear (1 or 2) whose flank node carries it, and that node's roll angle on its gear.
    pub gear: usize,
    pub roll_angle_deg: f64,
    /// A contact of the pair lies at or beyond an end of the involute and puts its whole force
    /// on the end of a flank
    /// — a tip corner, or a form point (where the involute meets the fillet, which a mating tip
    /// reaches below the involute): an edge contact, resolved only as far as the mesh is (the
    /// traction near it grows as the flank elements shrink).
    pub at_tip_corner: bool,
}

/// [`FePressureRow`] of every loaded pair at every position of a cycle.
pub fn fe_pressure_cycle(
    model: &LtcaModel,
    positions: usize,
    torque: f64,
) -> Result<Vec<FePressureRow>, StudyError> {
    use rayon::prelude::*;
    // Each tooth's flank runs root to tip: its first candidate is the form point (where the
    // involute meets the fillet), its last the tip corner. A contact beyond either end of the
    // involute puts its whole force there (an edge contact).
    let corner: [Vec<bool>; 2] = std::array::from_fn(|g| {
        let candidates = &model.bodies[g].candidates;
        let tooth = |i: Option<usize>| i.and_then(|i| candidates.get(i)).map(|c| c.tooth);
        (0..candidates.len())
            .map(|i| {
                let own = tooth(Some(i));
                tooth(i.checked_add(1)) != own || tooth(i.checked_sub(1)) != own
            })
            .collect()
    });
    let per_position: Vec<Vec<FePressureRow>> = (0..positions)
        .into_par_iter()
        .map(|j| -> Result<Vec<FePressureRow>, StudyError> {
            let contacts = model.loaded_contacts(j, positions, torque)?;
            let traction = model.flank_tractions(&contacts);
            // The nodes that carry a contact's whole force: a contact at or beyond an end of
            // the involute (`flank_weights` puts it all on the end node); a contact inside the
            // end edge loads the end node by a shape function below 1 and is no edge contact.
            let whole: [std::collections::HashSet<usize>; 2] = [0, 1].map(|g| {
                contacts
                    .active
                    .iter()
                    .flat_map(|c| c.nodes[g])
                    .filter(|(_, weight, _)| *weight >= 1.0 - 1e-9)
                    .map(|(node, _, _)| node)
                    .collect()
            });
            let result = &contacts.result;
            let mut rows = Vec::new();
            for (k, &(t1, t2)) in model.tooth_pairs.iter().enumerate() {
                if !(result.pair_forces[k] > 0.0) {
                    continue;
                }
                let mut best: Option<FePressureRow> = None;
                let at_tip_corner = [(0, t1), (1, t2)].iter().any(|&(g, tooth)| {
                    model.bodies[g].candidates.iter().enumerate().any(|(i, c)| {
                        c.tooth == tooth && corner[g][i] && whole[g].contains(&c.node)
                    })
                });
                for (g, tooth) in [(0, t1), (1, t2)] {
                    for (i, c) in model.bodies[g].candidates.iter().enumerate() {
                        let t = traction[g][i] * 1e-6;
                        if c.tooth == tooth && best.is_none_or(|b| t > b.pressure_mpa) {
                            best = Some(FePressureRow {
                                position: j,
                                pair: k,
                                pressure_mpa: t,
                                gear: g + 1,
                                roll_angle_deg: c.roll_angle.to_degrees(),
                                at_tip_corner,
                            });
                        }
                    }
                }
                rows.extend(best);
            }
            Ok(rows)
        })
        .collect::<Result<_, _>>()?;
    Ok(per_position.into_iter().flatten().collect())
}

/// The stress field of the tooth with the largest fillet tension of a cycle (either gear), at
/// the position where it peaks.
#[derive(Debug, Clone)]
pub struct PeakField {
    pub field: crate::ltca::field::StressField,
    pub peak: RootStressRow,
}

/// Where the field picture is and what it shows (`summary.json`'s `stress_field`).
#[derive(Debug, Clone, Serialize)]
pub struct PeakFieldSummary {
    /// 1 or 2.
    pub gear: usize,
    pub tooth: usize,
    pub position: usize,
    pub roll_angle_deg: f64,
    /// The fillet tension there (the cycle's peak) and the field's largest max principal and
    /// von Mises stress over its window (the window holds the contact's Hertz zone too) [MPa].
    pub fillet_tension_mpa: f64,
    pub max_principal_max_mpa: f64,
    pub von_mises_max_mpa: f64,
    /// Angular pitches either side of the tooth's centre line in the window.
    pub half_window_pitches: f64,
}

impl PeakField {
    pub fn summary(&self) -> PeakFieldSummary {
        let max = |v: Vec<f64>| v.into_iter().fold(f64::NEG_INFINITY, f64::max) * 1e-6;
        PeakFieldSummary {
            gear: self.peak.gear,
            tooth: self.peak.tooth,
            position: self.peak.position,
            roll_angle_deg: self.peak.roll_angle_deg,
            fillet_tension_mpa: self.peak.tension_mpa,
            max_principal_max_mpa: max(self.field.max_principal()),
            von_mises_max_mpa: max(self.field.von_mises()),
            half_window_pitches: FIELD_HALF_WINDOW,
        }
    }
}

/// The field window: the tooth and half of each neighbour.
pub const FIELD_HALF_WINDOW: f64 = 1.0;

/// The [`PeakField`] of `rows` (a [`root_stress_cycle`] of `model` at `positions`, `torque`).
pub fn peak_field(
    model: &LtcaModel,
    rows: &[RootStressRow],
    positions: usize,
    torque: f64,
) -> Result<Option<PeakField>, StudyError> {
    let Some(peak) = rows
        .iter()
        .max_by(|a, b| a.tension_mpa.total_cmp(&b.tension_mpa))
    else {
        return Ok(None);
    };
    let contacts = model.loaded_contacts(peak.position, positions, torque)?;
    let field = model
        .stress_field(&contacts, peak.gear - 1, peak.tooth, FIELD_HALF_WINDOW)
        .map_err(|e| StudyError::Input(format!("the stress field of the peak: {e}")))?;
    Ok(Some(PeakField { field, peak: *peak }))
}

/// The largest fillet tension of one gear over a cycle, and where.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct RootStressPeak {
    pub tension_mpa: f64,
    pub roll_angle_deg: f64,
    pub tooth: usize,
    /// Radius of the fillet node, and of ISO 6336-3's 30° tangent point on the same fillet [mm].
    pub radius_mm: f64,
    pub iso_30_degree_tangent_radius_mm: f64,
    /// The smallest principal stress on the other fillet over the cycle (compression) [MPa].
    pub compression_mpa: f64,
}

/// Each gear's [`RootStressPeak`] over `rows`.
pub fn root_stress_peaks(rows: &[RootStressRow], case: &Case) -> [Option<RootStressPeak>; 2] {
    let iso = iso_strength(case, 1.0);
    std::array::from_fn(|g| {
        let of_gear = || rows.iter().filter(move |r| r.gear == g + 1);
        let peak = of_gear().max_by(|a, b| a.tension_mpa.total_cmp(&b.tension_mpa))?;
        Some(RootStressPeak {
            tension_mpa: peak.tension_mpa,
            roll_angle_deg: peak.roll_angle_deg,
            tooth: peak.tooth,
            radius_mm: peak.tension_radius_mm,
            iso_30_degree_tangent_radius_mm: iso.root_stress_iso_radius_mm[g],
            compression_mpa: of_gear()
                .map(|r| r.compression_mpa)
                .fold(f64::INFINITY, f64::min),
        })
    })
}

/// Static safety factors at the design torque ([`crate::strength::safety`]).
#[derive(Debug, Clone, Serialize)]
pub struct SafetyFactors {
    /// σ_Flim and σ_Hlim used (`material.root_stress_limit_mpa`, `contact_stress_limit_mpa`).
    pub root_stress_limit_mpa: f64,
    pub contact_stress_limit_mpa: f64,
    /// S_F per gear from the FE's fillet maximum and from ISO's σ_F0.
    pub root_fe: [Option<f64>; 2],
    pub root_iso: [f64; 2],
    /// S_H from the LTCA's largest Hertz pressure away from the tips (both gears share it) and
    /// from ISO's σ_H per gear.
    pub contact_fe: Option<f64>,
    pub contact_iso: [f64; 2],
    pub basis: &'static str,
}

/// The static safety factors of one variant's FE stresses (the fillet maxima per gear, the
/// largest Hertz pressure) and of ISO's.
pub fn safety_factors(
    case: &Case,
    root_fe_mpa: [Option<f64>; 2],
    contact_fe_mpa: Option<f64>,
    iso: &IsoStrength,
) -> SafetyFactors {
    let (root_limit, contact_limit) = (
        case.material.root_stress_limit * 1e-6,
        case.material.contact_stress_limit * 1e-6,
    );
    SafetyFactors {
        root_stress_limit_mpa: root_limit,
        contact_stress_limit_mpa: contact_limit,
        root_fe: root_fe_mpa.map(|s| s.map(|s| safety::root_safety(s, root_limit))),
        root_iso: iso
            .root_stress_iso_mpa
            .map(|s| safety::root_safety(s, root_limit)),
        contact_fe: contact_fe_mpa.map(|p| safety::contact_safety(p, contact_limit)),
        contact_iso: iso
            .contact_pressure_iso_mpa
            .map(|p| safety::contact_safety(p, contact_limit)),
        basis: "S_F = σ_Flim·Y_ST/σ_F (Y_ST = 2), S_H = σ_Hlim/σ_H; load, life, size, surface and lubrication factors 1. σ_Flim is calibrated on ISO's σ_F0, which lies 4–13 % above the FE's fillet maximum (validation/strength): the FE-based S_F reads that much higher",
    }
}

/// ISO 6336's nominal stresses at the design torque, in MPa, with every factor
/// ([`crate::strength::iso6336`]).
#[derive(Debug, Clone, Serialize)]
pub struct IsoStrength {
    /// σ_F0 by method B, gear 1 and gear 2.
    pub root_stress_iso_mpa: [f64; 2],
    /// Radius of the 30° tangent point on each gear's fillet, where ISO puts the root stress [mm].
    pub root_stress_iso_radius_mm: [f64; 2],
    /// σ_H (Z_B or Z_D × σ_H0) of gear 1 and gear 2, and σ_H0 at the pitch point.
    pub contact_pressure_iso_mpa: [f64; 2],
    pub contact_pressure_iso_pitch_point_mpa: f64,
    /// The factors and the intermediate geometry (SI).
    #[serde(rename = "iso_6336")]
    pub factors: crate::strength::iso6336::Iso6336,
}

/// The study's headline numbers (`summary.json`): the first variant's, every variant's, and the
/// analytic references.
#[derive(Debug, Clone, Serialize)]
pub struct LtcaSummary {
    pub case: String,
    pub torque_nm: f64,
    pub positions: usize,
    pub plane: crate::fe::PlaneState,
    pub fine_element_mm: f64,
    pub coarse_element_mm: f64,
    pub relief_variant: String,
    pub mesh_stiffness_mean_n_per_m: f64,
    pub mesh_stiffness_min_n_per_m: f64,
    pub mesh_stiffness_max_n_per_m: f64,
    pub ste_mean_um: f64,
    pub ste_peak_to_peak_um: f64,
    pub iso_c_gamma_n_per_m: f64,
    pub iso_c_prime_n_per_m: f64,
    pub potential_energy_mean_n_per_m: f64,
    pub potential_energy_min_n_per_m: f64,
    pub potential_energy_max_n_per_m: f64,
    /// The first variant's largest Hertz pressure away from the tips, and where.
    pub contact_pressure_max_mpa: f64,
    pub contact_pressure_max_at: Option<PressureAt>,
    /// The first variant's largest fillet tension per gear over the cycle (FE), and where.
    pub root_stress_max_mpa: [Option<f64>; 2],
    pub root_stress_max_at: [Option<RootStressPeak>; 2],
    /// ISO 6336-2/-3 at the design torque (load factors 1): its stresses as flat keys beside
    /// the FE's, the factors under `iso_6336`.
    #[serde(flatten)]
    pub iso_6336: IsoStrength,
    /// S_F and S_H at the design torque, the first variant's FE stresses and ISO's (each
    /// variant's in `variants`).
    pub safety_factors: SafetyFactors,
    /// The first variant's stress field at its largest fillet tension (`stress_field.vtk`,
    /// `stress_field.png`).
    pub stress_field: Option<PeakFieldSummary>,
    pub elements: usize,
    pub wall_s: f64,
    pub variants: Vec<VariantSummary>,
    pub model: &'static str,
    /// Every variant's self-checks, the variant's name before each quantity, and the mesh's
    /// resolution of the contact ([`contact_resolution_check`]).
    pub self_checks: Vec<Check>,
    /// The self-checks that failed (errors) and that flag a suspicious result (warnings).
    pub self_check_errors: usize,
    pub self_check_warnings: usize,
}

/// The study's result.
#[derive(Debug, Clone)]
pub struct LtcaStudy {
    pub torque: f64,
    pub cycles: Vec<VariantCycle>,
    pub potential_energy: MeshStiffness,
    pub iso: IsoStiffness,
    /// The first variant's stress field at its largest fillet tension.
    pub peak_field: Option<PeakField>,
    pub summary: LtcaSummary,
}

/// Runs the LTCA cycle of every variant asked for; `progress` sees the positions done.
pub fn run(
    case: &Case,
    options: &LtcaOptions,
    progress: Progress,
) -> Result<LtcaStudy, StudyError> {
    let started = std::time::Instant::now();
    let torque = load_torque(case)?;
    let variants: Vec<_> = match &options.relief {
        Some(name) => vec![super::relief_variant(case, Some(name))?],
        None => case.relief_variants.iter().collect(),
    };
    let rb2 = case.pair.gears[1].base_radius;
    let positions = options.positions;
    let mut cycles = Vec::new();
    let mut peak = None;
    for variant in variants {
        let stage = format!("LTCA \"{}\"", variant.name);
        progress(&stage, 0, positions);
        let model = model(case, &variant.modifications)?;
        let cycle_started = std::time::Instant::now();
        let (results, periodicity) =
            model.run_checked(positions, torque, &|done| progress(&stage, done, positions))?;
        let cycle_s = cycle_started.elapsed().as_secs_f64();
        let checks = self_checks(
            &model,
            &variant.modifications,
            &results,
            &periodicity,
            positions,
            torque,
        )?;
        let [b1, b2] = &*model.bodies;
        let pressure = hertz::along_path(&case.pair, elastic(case), &results);
        let root_stress = root_stress_cycle(&model, positions, torque)?;
        if cycles.is_empty() {
            peak = peak_field(&model, &root_stress, positions, torque)?;
        }
        let mut summary = variant_summary(
            &variant.name,
            &results,
            (&pressure, &model.tooth_pairs),
            rb2,
            [b1.mesh.elements.len(), b2.mesh.elements.len()],
            [b1.free_dofs, b2.free_dofs],
            (
                b1.factorization_s + b2.factorization_s,
                b1.condensation_s + b2.condensation_s,
                cycle_s,
            ),
        );
        summary.root_stress = root_stress_peaks(&root_stress, case);
        let fe_pressure = fe_pressure_cycle(&model, positions, torque)?;
        let fe_peak = |corner: bool| {
            fe_pressure
                .iter()
                .filter(|r| r.at_tip_corner == corner)
                .map(|r| r.pressure_mpa)
                .reduce(f64::max)
        };
        summary.contact_pressure_fe_max_mpa = fe_peak(false).unwrap_or(0.0);
        summary.contact_pressure_fe_at_tip_corner_max_mpa = fe_peak(true);
        summary.safety_factors = Some(safety_factors(
            case,
            summary.root_stress.map(|p| p.map(|p| p.tension_mpa)),
            (summary.contact_pressure_max_mpa > 0.0).then_some(summary.contact_pressure_max_mpa),
            &iso_strength(case, torque),
        ));
        let mesh_stiffness = stiffness::from_ltca(
            &case.pair,
            &results,
            torque,
            format!("ltca (relief {})", variant.name),
        )
        .map_err(StudyError::Input)?;
        cycles.push(VariantCycle {
            name: variant.name.clone(),
            modifications: variant.modifications,
            tooth_pairs: model.tooth_pairs.clone(),
            results,
            mesh_stiffness,
            summary,
            checks,
            pressure,
            root_stress,
            fe_pressure,
        });
    }
    let pe = potential_energy::potential_energy_table(
        &case.pair,
        positions,
        case.material.youngs_modulus,
        case.material.poisson_ratio,
        case.plane,
    );
    let iso = stiffness::iso_6336_method_b(&case.pair, torque, case.material.youngs_modulus);
    let first = &cycles[0].summary;
    let iso_6336 = iso_strength(case, torque);
    let self_checks: Vec<Check> = cycles
        .iter()
        .flat_map(|c| {
            c.checks.iter().map(|check| Check {
                quantity: format!("{}: {}", c.name, check.quantity),
                ..check.clone()
            })
        })
        .chain([contact_resolution_check(case, torque)])
        .collect();
    let summary = LtcaSummary {
        case: case.name().to_string(),
        torque_nm: torque,
        positions,
        plane: case.plane,
        fine_element_mm: case.file.mesh.fine_element_mm,
        coarse_element_mm: case.file.mesh.coarse_element_mm,
        relief_variant: first.relief_variant.clone(),
        mesh_stiffness_mean_n_per_m: first.mesh_stiffness_mean_n_per_m,
        mesh_stiffness_min_n_per_m: first.mesh_stiffness_min_n_per_m,
        mesh_stiffness_max_n_per_m: first.mesh_stiffness_max_n_per_m,
        ste_mean_um: first.ste_mean_um,
        ste_peak_to_peak_um: first.ste_peak_to_peak_um,
        iso_c_gamma_n_per_m: iso.mean_n_per_m,
        iso_c_prime_n_per_m: iso.single_pair_n_per_m,
        potential_energy_mean_n_per_m: pe.mean(),
        potential_energy_min_n_per_m: pe.min(),
        potential_energy_max_n_per_m: pe.max(),
        contact_pressure_max_mpa: first.contact_pressure_max_mpa,
        contact_pressure_max_at: first.contact_pressure_max_at,
        root_stress_max_mpa: first.root_stress.map(|p| p.map(|p| p.tension_mpa)),
        root_stress_max_at: first.root_stress,
        safety_factors: first
            .safety_factors
            .clone()
            .expect("every variant's safety factors are set with its root stress"),
        stress_field: peak.as_ref().map(PeakField::summary),
        iso_6336,
        elements: first.elements[0] + first.elements[1],
        wall_s: started.elapsed().as_secs_f64(),
        variants: cycles.iter().map(|c| c.summary.clone()).collect(),
        self_check_errors: self_checks.iter().filter(|c| c.is_error()).count(),
        self_check_warnings: self_checks
            .iter()
            .filter(|c| !c.passed && c.warning_only)
            .count(),
        self_checks,
        model: "2D FE (Q8), bores held rigid; frictionless node-to-surface contact on the drive flanks; one base pitch",
    };
    Ok(LtcaStudy {
        torque,
        cycles,
        potential_energy: pe,
        iso,
        peak_field: peak,
        summary,
    })
}

/// Both gears' elastic constants (one material for the pair).
pub fn elastic(case: &Case) -> [Elastic; 2] {
    [Elastic {
        youngs_modulus: case.material.youngs_modulus,
        poisson_ratio: case.material.poisson_ratio,
    }; 2]
}

/// ISO 6336's stresses of the case's pair under `driven_torque` [N·m].
pub fn iso_strength(case: &Case, driven_torque: f64) -> IsoStrength {
    let factors = iso6336::iso6336(&case.pair, elastic(case), driven_torque);
    IsoStrength {
        root_stress_iso_mpa: [0, 1].map(|g| factors.root[g].sigma_f0_pa * 1e-6),
        root_stress_iso_radius_mm: [0, 1]
            .map(|g| factors.root[g].method_b.tangent_point_radius_m * 1e3),
        contact_pressure_iso_mpa: factors.contact.sigma_h_pa.map(|p| p * 1e-6),
        contact_pressure_iso_pitch_point_mpa: factors.contact.sigma_h0_pa * 1e-6,
        factors,
    }
}

/// Headline numbers of a variant's cycle: its results, and the Hertz pressure along the path
/// with the tooth pairs it indexes.
pub fn variant_summary(
    name: &str,
    results: &[PositionResult],
    (pressure, tooth_pairs): (&[PressurePoint], &[(usize, usize)]),
    base_radius_driven: f64,
    elements: [usize; 2],
    free_dofs: [usize; 2],
    times: (f64, f64, f64),
) -> VariantSummary {
    let peak = |at_tip: bool| {
        pressure
            .iter()
            .filter(|p| p.at_tip == at_tip)
            .max_by(|a, b| a.pressure_pa.total_cmp(&b.pressure_pa))
    };
    let k: Vec<f64> = results.iter().map(|r| r.mesh_stiffness).collect();
    let ste: Vec<f64> = results
        .iter()
        .map(|r| r.ste * base_radius_driven * 1e6)
        .collect();
    let te0: Vec<f64> = results
        .iter()
        .map(|r| r.unloaded_te * base_radius_driven * 1e6)
        .collect();
    VariantSummary {
        relief_variant: name.into(),
        mesh_stiffness_mean_n_per_m: k.iter().sum::<f64>() / k.len() as f64,
        mesh_stiffness_min_n_per_m: k.iter().copied().fold(f64::INFINITY, f64::min),
        mesh_stiffness_max_n_per_m: k.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        ste_mean_um: ste.iter().sum::<f64>() / ste.len() as f64,
        ste_peak_to_peak_um: crate::signal::peak_to_peak(&ste),
        unloaded_te_peak_to_peak_um: crate::signal::peak_to_peak(&te0),
        max_kkt_residual: results.iter().map(|r| r.kkt_residual).fold(0.0, f64::max),
        elements,
        free_dofs,
        factorization_wall_s: times.0,
        condensation_wall_s: times.1,
        cycle_wall_s: times.2,
        contact_pressure_max_mpa: peak(false).map_or(0.0, |p| p.pressure_pa * 1e-6),
        contact_pressure_max_at: peak(false).map(|p| PressureAt {
            roll_angle_deg: results[p.position].roll_angle.to_degrees(),
            path_mm: p.path_m * 1e3,
            force_n: p.force_n,
            teeth: tooth_pairs[p.pair],
        }),
        contact_pressure_at_tip_max_mpa: peak(true).map(|p| p.pressure_pa * 1e-6),
        contact_pressure_fe_max_mpa: 0.0,
        contact_pressure_fe_at_tip_corner_max_mpa: None,
        // The caller that computed the fillet stress sets these.
        root_stress: [None, None],
        safety_factors: None,
    }
}

/// The load of the low-load check, over the design load: low enough that the contact hardly
/// runs past the path's ends (the teeth deflect 1 % as far), high enough to stay far above the
/// contact solve's round-off.
pub const LOW_LOAD_FRACTION: f64 = 0.01;

/// How close to a change in the number of pairs a position may be and still be counted by the
/// low-load check [driver angular pitches]: the contact runs past each end of the path by the
/// deflection over the separation rate, far less than this at 1 % of the load.
pub const LOW_LOAD_SKIP: f64 = 0.03;

/// Largest relative KKT residual of a contact solve: the active-set solve is exact up to
/// round-off (1e-15 measured), so anything near this is a solve gone wrong.
pub const KKT_TOLERANCE: f64 = 1e-9;

/// Largest peak-to-peak unloaded TE of an unmodified pair [m]: the exact profiles are sampled
/// as polylines of 2000 flank segments, whose chords sit a few nm inside the involute.
pub const UNLOADED_TE_TOLERANCE: f64 = 0.01e-6;

/// Σ W r_b2 against T of an unmodified pair: the normals lie on the line of action, so only
/// the solve's round-off and the flank discretization's normals remain.
pub const BALANCE_TOLERANCE: f64 = 1e-3;

/// Σ W r_b2 against T with relief: the relieved flank's normals turn off the line of action
/// (0.3 % of the load at the paper's tip and root relief, measured).
pub const RELIEVED_BALANCE_TOLERANCE: f64 = 1e-2;

/// Flank elements at most this many Hertzian half-widths a (at the pitch point, under the mean
/// load a pair carries over its contact, F/ε_α): beyond it the mean mesh stiffness is 0.5 % or
/// more above the mesh-converged one. The node-to-surface contact's error depends on h/a nearly
/// alone, measured on eleven pairs of validation/pairs at 71.8–2 140 N·m (ε_α 1.5 to 2.4):
/// h/a 2.07 → +0.21 %, 2.24–2.25 → +0.18, +0.35 %, 2.36–2.46 → +0.43 … +0.63 %,
/// 2.66–2.77 → +0.96, +1.14 %, 3.02–3.20 → +1.35 … +1.43 %, 3.40–3.52 → +1.60 … +2.44 %,
/// 3.92 → +2.75 % against h/4. (With the whole load on one pair instead, the high-contact-ratio
/// pairs fell off the others' curve.)
pub const CONTACT_RESOLUTION_LIMIT: f64 = 2.45;

/// The flank elements the check recommends, in those half-widths: about 0.2 % on the mean.
pub const CONTACT_RESOLUTION_RECOMMENDED: f64 = 2.0;

/// The Hertzian half-width the mesh must resolve: at the pitch point under the mean load of a
/// pair over its contact, F/ε_α with F = T/r_b2 ([`Case::hertz_half_width_at`]).
pub fn contact_half_width(case: &Case, torque: f64) -> f64 {
    let pair = &case.pair;
    case.hertz_half_width_at(torque / pair.gears[1].base_radius / pair.contact_ratio)
}

/// A warning when the flank elements are coarse against the Hertzian contact they carry:
/// h / a ≤ [`CONTACT_RESOLUTION_LIMIT`], a from [`contact_half_width`]. The stiffness comes out
/// too high, more so at lower loads (a ∝ √F).
pub fn contact_resolution_check(case: &Case, torque: f64) -> Check {
    let half_width = contact_half_width(case, torque);
    let fine = case.file.mesh.fine_element_mm * 1e-3;
    Check::new(
        "ltca",
        format!(
            "flank elements over the Hertzian half-width at the pitch point ({:.3} mm under the \
             mean load of a pair; above {CONTACT_RESOLUTION_LIMIT} the mean stiffness is 0.5 % \
             or more too high: set mesh.fine_element_mm to {:.3} or less)",
            half_width * 1e3,
            CONTACT_RESOLUTION_RECOMMENDED * half_width * 1e3
        ),
        (fine / half_width, CONTACT_RESOLUTION_LIMIT),
        "the mesh-converged contact (validation/pairs)",
        (CheckKind::Below, 0.0),
    )
    .warning()
}

/// The checks an LTCA cycle makes of its own answer:
/// * periodicity over one base pitch (the STE and every pair's force one pitch on equal the
///   first position's; a failure is an error before this, from the kernel);
/// * the contact solve's KKT residual (no penetration, no tension, Σ F a = T) at round-off;
/// * no pair loaded farther than half the engagement margin beyond the path of contact (a
///   warning: beyond the margin a pair would be missing from the model);
/// * Σ W r_b2 = T at every position to 1e-3 for an unmodified pair (an involute's forces act
///   along the line of action, on the base radius), to 1e-2 with relief (which bends the
///   normals off it);
/// * for an unmodified pair: the unloaded TE is constant (zero but for a thickness reduction),
///   and at 1 % of the load the number of loaded pairs at each position is the number the
///   unloaded geometry puts on the path of contact (positions within 0.03 pitch of a change
///   skipped).
pub fn self_checks(
    model: &LtcaModel,
    modifications: &[FlankModification; 2],
    results: &[PositionResult],
    periodicity: &Periodicity,
    positions: usize,
    torque: f64,
) -> Result<Vec<Check>, StudyError> {
    let pair = &model.pair;
    let rb2 = pair.gears[1].base_radius;
    let mut checks = vec![
        Check::new(
            "ltca",
            "STE one base pitch on against the first position, relative",
            (periodicity.ste_relative_difference, 0.0),
            "periodicity over one base pitch",
            (CheckKind::Absolute, PERIODICITY_TOLERANCE),
        ),
        Check::new(
            "ltca",
            "largest tooth-pair force one base pitch on against the first position, over the load",
            (periodicity.force_relative_difference, 0.0),
            "periodicity over one base pitch",
            (CheckKind::Absolute, PERIODICITY_TOLERANCE),
        ),
    ];
    let worst_kkt = largest(results.iter().map(|r| r.kkt_residual));
    checks.push(Check::new(
        "ltca",
        "largest KKT residual of the contact solves (penetration, tension, torque balance Σ F a = T)",
        (worst_kkt, 0.0),
        "the contact conditions, relative to the gap and force scales",
        (CheckKind::Absolute, KKT_TOLERANCE),
    ));
    let farthest = results.iter().flat_map(|r| {
        model
            .pairs
            .iter()
            .zip(&r.pair_forces)
            .filter(|(_, f)| **f > 0.0)
            .map(|(p, _)| p.beyond_path(pair, r.driver_rotation).abs())
    });
    let farthest = largest(farthest);
    checks.push(
        Check::new(
            "ltca",
            "farthest loaded pair beyond the path of contact [base pitches]",
            (farthest, 0.0),
            "half the engagement margin the model's pairs are chosen with",
            (CheckKind::Absolute, 0.5 * ENGAGEMENT_MARGIN),
        )
        .warning(),
    );
    let unmodified = *modifications == [FlankModification::none(); 2];
    // On unmodified involutes every contact normal is tangent to the base circle, so the forces
    // balance the torque on the base radius; relief and tip corners bend the normals off it
    // (by 0.3 % of the load at the paper's relief), so a relieved pair is held to 1 %.
    let worst_balance = largest(
        results
            .iter()
            .map(|p| (p.total_force * rb2 / torque - 1.0).abs()),
    );
    checks.push(Check::new(
        "ltca",
        "largest abs(Σ W r_b2 / T − 1) over the cycle",
        (worst_balance, 0.0),
        if unmodified {
            "torque balance along the line of action"
        } else {
            "torque balance along the line of action (relief bends the normals off it)"
        },
        (
            CheckKind::Absolute,
            if unmodified {
                BALANCE_TOLERANCE
            } else {
                RELIEVED_BALANCE_TOLERANCE
            },
        ),
    ));
    if unmodified {
        let te = || results.iter().map(|r| r.unloaded_te * rb2);
        checks.push(Check::new(
            "ltca",
            "unloaded TE peak-to-peak of the unmodified pair [m]",
            (largest(te()) + largest(te().map(|t| -t)), 0.0),
            "conjugate involutes transmit uniform motion",
            (CheckKind::Absolute, UNLOADED_TE_TOLERANCE),
        ));
        let low = model.run_torques(positions, &[LOW_LOAD_FRACTION * torque])?;
        let [xi_a, xi_e] = engagement::path_roll_angles(pair);
        let p1 = pair.gears[0].angular_pitch();
        let mut counted = 0;
        let mut mismatched = 0;
        for r in &low[0] {
            let near_a_change = model.pairs.iter().any(|p| {
                let xi = p.roll_angle(pair, r.driver_rotation);
                ((xi - xi_a).abs() / p1).min((xi - xi_e).abs() / p1) < LOW_LOAD_SKIP
            });
            if near_a_change {
                continue;
            }
            counted += 1;
            let loaded = r.pair_forces.iter().filter(|f| **f > 0.0).count();
            if loaded != engagement::pairs_on_path(pair, r.driver_rotation) {
                mismatched += 1;
            }
        }
        checks.push(Check::new(
            "ltca",
            format!(
                "positions whose loaded pairs at {:.0} % load differ from the pairs on the path (of {counted})",
                LOW_LOAD_FRACTION * 100.0
            ),
            // Fewer than half the positions compared is no check.
            (
                if 2 * counted >= low[0].len() {
                    mismatched as f64
                } else {
                    f64::NAN
                },
                0.0,
            ),
            "the unloaded geometry's path of contact",
            (CheckKind::Absolute, 0.0),
        ));
    }
    Ok(checks)
}
