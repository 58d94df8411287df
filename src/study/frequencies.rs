//! The lumped model's mesh mode against the FE modal analysis, on the case's own mesh
//! (`geardyn validate frequencies`, and compare's headline frequencies).
//!
//! The reference is [`crate::ltca::modal::pair_modes`]: the meshed pair with consistent mass,
//! its contact tied along the LTCA's active normals at the design torque, rigid hubs, on the
//! LTCA's mesh of the case (the one the lumped model's force law comes from, converged to
//! 0.46 % in k̄, validation/ltca), at `positions` positions over a base pitch; its mean mesh-mode
//! frequency per boundary condition:
//! * **driver held** (the explicit FE's: the driver's bore follows the prescribed speed) against
//!   the lumped speed drive;
//! * **both free** against the lumped torque drive.
//!
//! Both follow one mode: the lumped model's of the rank its mesh mode has at the mean
//! stiffness, the FE modal's paired with it by shape at each position ([`pair_by_shape`]), so a
//! body mode that shares the mesh's compliance (a large driver's torsion below the mesh mode)
//! is not compared with the other model's mesh mode.
//!
//! The lumped model is the one `sweep` and `run` integrate ([`super::lumped::setup`]: its
//! stiffness source and force law, linearized about the design load), on the FE's boundary
//! conditions (no shafts, no bearings), with the case's bodies and, for comparison, with rigid
//! gears behind the hub-to-hub stiffness.

use rayon::prelude::*;
use serde::Serialize;

use crate::case::{BodyModel, Case};
use crate::ltca::modal::{pair_modes, Hubs, PairModes};
use crate::lumped::{Drive, MeshModel};

use super::{Progress, StudyError};

/// The tolerance of the lumped mesh mode against the FE modal's (issue target): 2 %.
pub const MESH_MODE_TOLERANCE: f64 = 0.02;

/// One boundary condition.
#[derive(Debug, Clone, Serialize)]
pub struct MeshModeComparison {
    pub hubs: Hubs,
    pub drive: Drive,
    /// The case's lumped model (its bodies), frozen at the FE modal's positions, their mean
    /// [Hz] (the quantity compared), and rigid gears behind the hub-to-hub k, the same way.
    pub lumped_hz: f64,
    pub lumped_rigid_hz: f64,
    /// The case's lumped model at each position (driver rotation [deg], Hz).
    pub lumped_hz_per_position: Vec<(f64, f64)>,
    /// The case's lumped model at the mean linearized stiffness [Hz]: the mode the sweep's
    /// primary resonance follows (how it differs from the per-position mean:
    /// [`lumped_mesh_modes`]).
    pub lumped_at_mean_stiffness_hz: f64,
    /// FE modal mesh mode per position (driver rotation [deg], Hz) and its mean [Hz]: at each
    /// position the FE mode paired by shape with the lumped mesh mode ([`pair_by_shape`]).
    pub fe_modal_hz: Vec<(f64, f64)>,
    pub fe_modal_mean_hz: f64,
    /// The mean of the FE modal's own mesh mode (the largest compliance share at each position,
    /// [`PairModes::mesh_mode`]) [Hz], and at how many positions the paired mode is another:
    /// where a body mode near the mesh mode shares its compliance.
    pub fe_modal_largest_share_mean_hz: f64,
    pub positions_paired_off_largest_share: usize,
    /// lumped / FE modal − 1, of the means.
    pub lumped_rel: f64,
    /// The largest |lumped / FE modal − 1| of one position, signed.
    pub lumped_rel_worst_position: f64,
    pub lumped_rigid_rel: f64,
    /// Whether |lumped_rel| ≤ [`MESH_MODE_TOLERANCE`].
    pub pass: bool,
    /// Driver held, elastic bodies: the driver body's torsion (its rim against the held hub),
    /// the case's lumped model's and the FE modal's mode paired with it by shape (where the
    /// lumped model has none, the FE's own, [`PairModes::torsion_mode`]), each the mean over
    /// the positions [Hz], and lumped / FE modal − 1; `None` where either has none.
    pub driver_torsion_fe_modal_hz: Option<f64>,
    pub driver_torsion_lumped_hz: Option<f64>,
    pub driver_torsion_rel: Option<f64>,
    /// The FE modal's driver torsion and the other body modes the mesh drives, each kind's
    /// mean over the positions ([`super::compare::fe_modal_body_modes`]; the lumped models
    /// have the torsions, and the rims' sway where `[lumped] body_sway` gives it, not matched
    /// to the modal's lateral modes).
    pub excited_body_modes_fe_modal: Vec<super::fe_sweep::BodyMode>,
}

/// Both boundary conditions.
#[derive(Debug, Clone, Serialize)]
pub struct MeshModes {
    pub case: String,
    pub torque_nm: f64,
    pub positions: usize,
    pub fine_element_mm: f64,
    pub coarse_element_mm: f64,
    pub driver_held: MeshModeComparison,
    pub both_free: MeshModeComparison,
    pub model_note: String,
    pub wall_s: f64,
    /// The FE modal analysis's modes at every position, both boundary conditions
    /// (`modal.csv`).
    #[serde(skip)]
    pub modal: Vec<PairModes>,
}

/// The mesh mode of `model`'s linearized mesh on the FE's boundary conditions under `drive`
/// with `bodies` [Hz], frozen at each of the driver rotations `rotations` [rad] from the
/// pitch-point position (the FE modal's positions, placed in the tables' θ, which counts from
/// their origin's roll angle): the linearized stiffness there (the force law's tangent at the
/// quasi-static state, or the secant k(θ)), first given back, if hub to hub, the twist
/// `twist_in_model` the case's model took out of it, then the bodies' own taken out. Returns
/// those, the mode at the mean stiffness, and, with the driver held (speed drive) and elastic
/// bodies, the driver body's torsion at each position (its rim against the held hub,
/// [`crate::lumped::Structure::body_mode_index`] on `rim1 lag`, the speed drive's coordinate),
/// with every mode's [`ModeSignature`] for [`pair_by_shape`]. The mesh mode and the torsion
/// are the structure's modes of the rank they have at the mean stiffness, at every position.
///
/// The FE modal analysis gives one frequency per frozen position, so the compared quantity is
/// the same mean of the same per-position frequencies. The mode at the mean stiffness (the one
/// the sweep's primary resonance follows) differs from that mean in two ways: f ∝ √k is
/// concave, which puts the per-position mean below it by about var(k)/(8 k̄²) (0.7 % for a
/// stiffness alternating between 1 and 1.6 in equal halves), and a few positions sample the
/// steps of k(θ) unevenly, either way (+0.2 / +0.4 % at 8 positions on the paper pair).
fn lumped_mesh_modes(
    case: &Case,
    model: &MeshModel,
    (drive, bodies): (Drive, BodyModel),
    twist_in_model: f64,
    rotations: &[f64],
) -> Result<LumpedModes, StudyError> {
    let linear = model.linearized();
    // Undamped modes: the springs' damping does not enter.
    let springs = (bodies, crate::lumped::SpringDamping::Ratio(0.0));
    let structure = super::lumped::drivetrain_with(case, drive, springs, [None; 2], false)?;
    let twist_out = match (bodies, case.lumped.stiffness.holds_body_twist()) {
        (BodyModel::Elastic, true) => super::lumped::bodies_line_compliance(case, bodies)?,
        _ => 0.0,
    };
    // From the model's mesh back to hub to hub (+ the twist it lost), then to these bodies.
    let k_of = |k_mesh: f64| 1.0 / (1.0 / k_mesh + twist_in_model - twist_out);
    let pair = &case.pair;
    let roll_pitch = pair.roll_angle_at(1, pair.contact_points.pitch);
    let stiffness: Vec<f64> = rotations
        .iter()
        .map(|rotation| {
            let theta = roll_pitch + rotation - linear.mesh.origin;
            linear.mesh.stiffness.at(theta)
        })
        .collect();
    // Which of the structure's modes (by rank, ascending) are its mesh mode and, driver held
    // with elastic bodies, the driver body's torsion (its rim against the held hub): the ones
    // at the mean stiffness, followed by rank through the positions (modes that share the
    // mesh veer and keep their order; the largest share alone can jump between them).
    let at_mean = structure.modes(k_of(linear.mesh.mean()));
    let mesh = crate::lumped::Structure::mesh_mode_index(&at_mean).expect("a structure has a mode");
    let torsion = match (drive, bodies) {
        (Drive::Speed, BodyModel::Elastic) => structure.body_mode_index(&at_mean, "rim1 lag"),
        _ => None,
    };
    let hz = |m: &crate::lumped::Mode| m.frequency / std::f64::consts::TAU;
    // Every mode's signature at each position, for pairing with the FE modal's by shape.
    let positions: Vec<Vec<ModeSignature>> = stiffness
        .iter()
        .map(|k| {
            let modes = structure.modes(k_of(*k));
            let shares = structure.load_compliance_shares(&modes);
            modes
                .iter()
                .zip(shares)
                .map(|(m, compliance_share)| ModeSignature {
                    frequency_hz: hz(m),
                    compliance_share,
                    driver_rotation_share: match drive {
                        Drive::Speed => structure.coordinate_mass_share(m, "rim1 lag"),
                        Drive::Torque => None,
                    },
                })
                .collect()
        })
        .collect();
    Ok(LumpedModes {
        mesh_hz: positions.iter().map(|p| p[mesh].frequency_hz).collect(),
        mesh_hz_at_mean_stiffness: hz(&at_mean[mesh]),
        driver_torsion_hz: torsion.map(|t| positions.iter().map(|p| p[t].frequency_hz).collect()),
        positions,
        mesh,
        torsion,
    })
}

/// What [`lumped_mesh_modes`] finds [Hz].
struct LumpedModes {
    /// The mesh mode at each position.
    mesh_hz: Vec<f64>,
    mesh_hz_at_mean_stiffness: f64,
    /// The driver body's torsion at each position (driver held, elastic bodies).
    driver_torsion_hz: Option<Vec<f64>>,
    /// Every mode at each position, ascending.
    positions: Vec<Vec<ModeSignature>>,
    /// Which of them (the same rank at every position) are the mesh mode and the driver
    /// body's torsion.
    mesh: usize,
    torsion: Option<usize>,
}

/// What a mode of either model is paired by: its frequency, its share of the static compliance
/// under the load on the driven side ([`crate::lumped::Structure::load_compliance_shares`],
/// [`crate::ltca::modal::PairMode::mesh_share`]) and, driver held, its share of the driver
/// rim's rotation against the held hub (the modal effective mass;
/// [`crate::lumped::Structure::coordinate_mass_share`] on `rim1 lag`,
/// [`crate::ltca::modal::PairMode::rotation_share`]), `None` where the model has no such
/// coordinate.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ModeSignature {
    pub frequency_hz: f64,
    pub compliance_share: f64,
    pub driver_rotation_share: Option<f64>,
}

/// Modes further apart in frequency than this factor are not one mode of two models (the
/// lumped rigid-gear model, the crudest compared, is within 13 % of the FE modal's mesh mode on
/// every pair measured): a lumped body mode above the FE modal's modes computed (a 17-tooth
/// pinion's torsion at 95 kHz against ten modes up to 24 kHz) stays unpaired rather than taking
/// the FE mode with the most of its shares.
pub const PAIR_FREQUENCY_RATIO: f64 = 1.5;

impl ModeSignature {
    /// How alike two modes are: the overlap √(s_a s_b) of their compliance shares plus that of
    /// their driver rotation shares where both have one (the Bhattacharyya coefficient of
    /// each share against its complement would also count what neither mode has; the
    /// products count only what both have). In [0, 2]; 0 for modes more than
    /// [`PAIR_FREQUENCY_RATIO`] apart in frequency.
    fn overlap(&self, other: &ModeSignature) -> f64 {
        let ratio = self.frequency_hz / other.frequency_hz;
        if !(1.0 / PAIR_FREQUENCY_RATIO..=PAIR_FREQUENCY_RATIO).contains(&ratio) {
            return 0.0;
        }
        let rotation = match (self.driver_rotation_share, other.driver_rotation_share) {
            (Some(a), Some(b)) => (a * b).max(0.0).sqrt(),
            _ => 0.0,
        };
        (self.compliance_share * other.compliance_share)
            .max(0.0)
            .sqrt()
            + rotation
    }
}

/// Pairs the lumped model's modes with the FE modal's by shape: each list ascending in
/// frequency, the pairing keeps their order (a monotone alignment, the largest total
/// [`ModeSignature::overlap`], by dynamic programming over both lists) and may leave modes of
/// either unpaired (the FE has tooth and lateral modes the lumped model lacks; a pair with no
/// overlap stays unpaired). Returns each lumped mode's FE partner.
///
/// Why the order: where a body mode lies near the mesh mode, the two share the mesh's
/// compliance and veer rather than cross as the stiffness changes over a base pitch, so the
/// lower stays the lower; the mode with the largest share alone jumps between them from one
/// position to the next, in either model on its own (a 53-tooth driver held: its torsion
/// 4.1 kHz below the mesh mode, the shares 0.40 / 0.55). Pairing by order and shape compares
/// the same mode of both.
pub fn pair_by_shape(lumped: &[ModeSignature], fe: &[ModeSignature]) -> Vec<Option<usize>> {
    let (n, m) = (lumped.len(), fe.len());
    // best[i][j]: the largest overlap of the first i lumped modes with the first j FE modes.
    let mut best = vec![vec![0.0f64; m + 1]; n + 1];
    for i in 1..=n {
        for j in 1..=m {
            let paired = best[i - 1][j - 1] + lumped[i - 1].overlap(&fe[j - 1]);
            best[i][j] = paired.max(best[i - 1][j]).max(best[i][j - 1]);
        }
    }
    let mut partner = vec![None; n];
    let (mut i, mut j) = (n, m);
    while i > 0 && j > 0 {
        if best[i][j] == best[i - 1][j] {
            i -= 1;
        } else if best[i][j] == best[i][j - 1] {
            j -= 1;
        } else {
            partner[i - 1] = Some(j - 1);
            i -= 1;
            j -= 1;
        }
    }
    partner
}

/// The FE modal's modes at one position as [`ModeSignature`]s (its elastic modes, ascending),
/// each with its index in `modal.modes`; the driver's rotation share with the driver held.
fn fe_signatures(modal: &PairModes) -> Vec<(usize, ModeSignature)> {
    modal
        .modes
        .iter()
        .enumerate()
        .filter(|(_, m)| m.kind != "rigid")
        .map(|(i, m)| {
            (
                i,
                ModeSignature {
                    frequency_hz: m.frequency_hz,
                    compliance_share: m.mesh_share,
                    driver_rotation_share: match modal.hubs {
                        Hubs::DriverHeld => Some(m.rotation_share[0]),
                        Hubs::BothFree => None,
                    },
                },
            )
        })
        .collect()
}

/// The FE modal analysis of `ltca`'s pair at `positions` positions over a base pitch under
/// `torque`, its `count` lowest modes, driver held then both free, each position in order.
/// Every position of both boundary conditions side by side: each modal solve (Lanczos, one
/// triangular solve per step) keeps one core busy.
pub fn modal_at_positions(
    case: &Case,
    ltca: &crate::ltca::LtcaModel,
    positions: usize,
    torque: f64,
    count: usize,
    progress: Progress,
) -> Result<Vec<PairModes>, StudyError> {
    let total = 2 * positions;
    let done = std::sync::atomic::AtomicUsize::new(0);
    progress("FE modal", 0, total);
    let jobs: Vec<(Hubs, usize)> = [Hubs::DriverHeld, Hubs::BothFree]
        .into_iter()
        .flat_map(|hubs| (0..positions).map(move |j| (hubs, j)))
        .collect();
    let results: Vec<Result<PairModes, StudyError>> = jobs
        .into_par_iter()
        .map(|(hubs, j)| {
            let modes = pair_modes(
                ltca,
                (j, positions),
                torque,
                case.ltca_material(),
                case.material.density,
                hubs,
                count,
            )?;
            let finished = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            progress("FE modal", finished + 1, total);
            Ok(modes)
        })
        .collect();
    // Collected whole first, so a failure reports the first failing position whatever the
    // thread count.
    results.into_iter().collect()
}

/// Runs the comparison at `positions` positions over a base pitch.
pub fn mesh_modes(
    case: &Case,
    positions: usize,
    progress: Progress,
) -> Result<MeshModes, StudyError> {
    let started = std::time::Instant::now();
    if positions == 0 {
        return Err(StudyError::Input("--positions must be at least 1".into()));
    }
    let variant = super::relief_variant(case, case.lumped.relief.as_deref())?;
    let ltca = super::ltca::model(case, &variant.modifications)?;
    // The same bodies for the lumped model's tables and the modal analysis.
    let setup = super::lumped::setup_on(case, &ltca)?;
    let twist_in_model = match case.lumped.stiffness.holds_body_twist() {
        true => setup.body_compliance,
        false => 0.0,
    };
    let torque = setup.torque;
    // Ten modes: the bodies' lateral pairs can lie below a small pinion's torsion (24/40: the
    // pinion's torsion the fifth mode above the mesh mode, driver held).
    let modal = modal_at_positions(case, &ltca, positions, torque, 10, progress)?;
    let compare = |hubs: Hubs, drive: Drive| -> Result<_, StudyError> {
        let at: Vec<&PairModes> = modal.iter().filter(|m| m.hubs == hubs).collect();
        let rotations: Vec<f64> = at.iter().map(|m| m.driver_rotation).collect();
        let mean = |hz: &[f64]| hz.iter().sum::<f64>() / hz.len() as f64;
        let LumpedModes {
            mesh_hz: per_position,
            mesh_hz_at_mean_stiffness: lumped_at_mean_stiffness_hz,
            driver_torsion_hz: torsion,
            positions: lumped_positions,
            mesh: lumped_mesh,
            torsion: lumped_torsion,
        } = lumped_mesh_modes(
            case,
            &setup.model,
            (drive, case.lumped.bodies),
            twist_in_model,
            &rotations,
        )?;
        // The FE modal's mode paired by shape with the lumped mesh mode (and driver torsion)
        // at each position; the FE's own mesh mode (the largest compliance share) where the
        // lumped mode has no partner.
        let paired: Vec<(usize, Option<usize>)> = at
            .iter()
            .zip(&lumped_positions)
            .map(|(fe, lumped)| {
                let signatures = fe_signatures(fe);
                let only: Vec<ModeSignature> = signatures.iter().map(|s| s.1).collect();
                let partner = pair_by_shape(lumped, &only);
                let index = |lumped_mode: usize| partner[lumped_mode].map(|k| signatures[k].0);
                (
                    index(lumped_mesh).unwrap_or(fe.mesh_mode),
                    lumped_torsion.and_then(index),
                )
            })
            .collect();
        let fe_modal_hz: Vec<(f64, f64)> = at
            .iter()
            .zip(&paired)
            .map(|(m, (mesh, _))| (m.driver_rotation.to_degrees(), m.modes[*mesh].frequency_hz))
            .collect();
        let fe_modal_mean_hz = mean(&fe_modal_hz.iter().map(|p| p.1).collect::<Vec<_>>());
        let fe_modal_largest_share_mean_hz = mean(
            &at.iter()
                .map(|m| m.modes[m.mesh_mode].frequency_hz)
                .collect::<Vec<_>>(),
        );
        let positions_paired_off_largest_share = at
            .iter()
            .zip(&paired)
            .filter(|(m, (mesh, _))| *mesh != m.mesh_mode)
            .count();
        let rigid_per_position = lumped_mesh_modes(
            case,
            &setup.model,
            (drive, BodyModel::Rigid),
            twist_in_model,
            &rotations,
        )?
        .mesh_hz;
        let lumped_hz = mean(&per_position);
        let lumped_rigid_hz = mean(&rigid_per_position);
        let lumped_rel = lumped_hz / fe_modal_mean_hz - 1.0;
        let lumped_rel_worst_position = fe_modal_hz
            .iter()
            .zip(&per_position)
            .map(|(&(_, fe), lumped)| lumped / fe - 1.0)
            .fold(0.0, |worst: f64, rel| match rel.abs() > worst.abs() {
                true => rel,
                false => worst,
            });
        let lumped_hz_per_position = fe_modal_hz
            .iter()
            .zip(per_position)
            .map(|(&(deg, _), hz)| (deg, hz))
            .collect();
        let mean_of = |hz: Option<Vec<f64>>| hz.filter(|v| !v.is_empty()).map(|v| mean(&v));
        let excited_body_modes_fe_modal = match hubs {
            Hubs::DriverHeld => super::compare::fe_modal_body_modes(&modal),
            Hubs::BothFree => Vec::new(),
        };
        // The FE partner of the lumped driver torsion where every position has one, else
        // the FE modal's own (its mode above the mesh mode most like the driver's rotation).
        let driver_torsion_fe_modal_hz = paired
            .iter()
            .zip(&at)
            .map(|((_, torsion), m)| torsion.map(|t| m.modes[t].frequency_hz))
            .collect::<Option<Vec<f64>>>()
            .filter(|v| !v.is_empty())
            .map(|v| mean(&v))
            .or_else(|| super::compare::driver_torsion_hz(&excited_body_modes_fe_modal));
        let driver_torsion_lumped_hz = mean_of(torsion);
        let driver_torsion_rel = driver_torsion_fe_modal_hz
            .zip(driver_torsion_lumped_hz)
            .map(|(fe, lumped)| lumped / fe - 1.0);
        Ok(MeshModeComparison {
            driver_torsion_fe_modal_hz,
            driver_torsion_lumped_hz,
            driver_torsion_rel,
            excited_body_modes_fe_modal,
            hubs,
            drive,
            lumped_hz,
            lumped_at_mean_stiffness_hz,
            lumped_rigid_hz,
            lumped_hz_per_position,
            fe_modal_hz,
            fe_modal_mean_hz,
            fe_modal_largest_share_mean_hz,
            positions_paired_off_largest_share,
            lumped_rel,
            lumped_rel_worst_position,
            lumped_rigid_rel: lumped_rigid_hz / fe_modal_mean_hz - 1.0,
            pass: lumped_rel.abs() <= MESH_MODE_TOLERANCE,
        })
    };
    let driver_held = compare(Hubs::DriverHeld, Drive::Speed)?;
    let both_free = compare(Hubs::BothFree, Drive::Torque)?;
    Ok(MeshModes {
        case: case.name().to_string(),
        torque_nm: torque,
        positions,
        fine_element_mm: case.file.mesh.fine_element_mm,
        coarse_element_mm: case.file.mesh.coarse_element_mm,
        driver_held,
        both_free,
        model_note: setup.model_note,
        wall_s: started.elapsed().as_secs_f64(),
        modal,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::case::Override;
    use crate::stiffness::{MeshStiffness, PeriodicTable};

    fn mode(frequency_hz: f64, compliance_share: f64, rotation: Option<f64>) -> ModeSignature {
        ModeSignature {
            frequency_hz,
            compliance_share,
            driver_rotation_share: rotation,
        }
    }

    /// Pairing by shape on synthetic modes whose answer is known.
    #[test]
    fn modes_pair_by_order_and_shape() {
        // A veering pair (a driver body's torsion just below the mesh mode, both sharing the
        // mesh's compliance): the lumped model's mesh mode (the upper, 0.7) is the FE's upper
        // although the FE's largest share is its lower mode (0.55); a lateral and a tooth
        // mode above stay unpaired.
        let lumped = [mode(4100.0, 0.3, Some(0.6)), mode(6000.0, 0.7, Some(0.2))];
        let fe = [
            mode(4158.0, 0.55, Some(0.4)),
            mode(5900.0, 0.40, Some(0.35)),
            mode(9900.0, 0.03, Some(0.0)),
            mode(16000.0, 0.02, Some(0.0)),
        ];
        assert_eq!(pair_by_shape(&lumped, &fe), vec![Some(0), Some(1)]);
        // Paired by the largest overlap without the order, the mesh mode would take the FE's
        // lower mode: the order is what decides it here.
        let overlap = |l: usize, f: usize| lumped[l].overlap(&fe[f]);
        assert!(overlap(1, 0) + overlap(0, 1) > overlap(0, 0) + overlap(1, 1));
        // A mode the lumped model lacks below both (a lateral mode with a small share), the
        // torsion above the mesh mode and a tooth mode between them: skipped.
        let lumped = [
            mode(5000.0, 0.98, Some(0.04)),
            mode(20000.0, 0.02, Some(0.85)),
        ];
        let fe = [
            mode(4800.0, 0.05, Some(0.0)),
            mode(4960.0, 0.90, Some(0.05)),
            mode(15000.0, 0.03, Some(0.0)),
            mode(21000.0, 0.01, Some(0.80)),
        ];
        assert_eq!(pair_by_shape(&lumped, &fe), vec![Some(1), Some(3)]);
        // The torsion far above the FE modes computed (a small pinion's, 95 kHz): unpaired,
        // although the FE's highest mode has the most of its rotation.
        let lumped = [
            mode(5000.0, 0.98, Some(0.04)),
            mode(95000.0, 0.02, Some(0.85)),
        ];
        assert_eq!(pair_by_shape(&lumped, &fe), vec![Some(1), None]);
        // One lumped mode (rigid gears; no rotation share): the FE's largest share.
        let fe_free: Vec<ModeSignature> = fe
            .iter()
            .map(|m| ModeSignature {
                driver_rotation_share: None,
                ..*m
            })
            .collect();
        assert_eq!(
            pair_by_shape(&[mode(5000.0, 1.0, None)], &fe_free),
            vec![Some(1)]
        );
        // More lumped modes than FE modes, and a lumped mode with nothing in common: unpaired,
        // no panic.
        let lumped = [
            mode(1.0, 0.0, None),
            mode(5000.0, 1.0, None),
            mode(9000.0, 0.0, None),
        ];
        assert_eq!(
            pair_by_shape(&lumped, &[mode(5100.0, 1.0, None)]),
            vec![None, Some(0), None]
        );
        assert_eq!(pair_by_shape(&lumped, &[]), vec![None; 3]);
    }

    /// A synthetic two-level k(θ) (1 over 60 % of the period, 1.6 over the rest) on rigid gears
    /// with the torque drive: each frozen position's mode is √(k_j/m_e)/2π with k_j the level at
    /// that rotation, also with the table's origin moved off the pitch point (the rotations are
    /// placed in the table's θ), and the mode at the mean stiffness is √(k̄/m_e)/2π, above the
    /// positions' mean by what the levels give.
    #[test]
    fn frozen_positions_read_the_stiffness_at_their_rotation() {
        let case = Case::load_with(
            None,
            &[
                Override::set("lumped.stiffness", "pe"),
                Override::set("lumped.bodies", "rigid"),
            ],
        )
        .unwrap();
        let mut model = super::super::lumped::setup(&case).unwrap().model;
        let period = model.mesh.period();
        let roll_pitch = case.pair.roll_angle_at(1, case.pair.contact_points.pitch);
        let k1 = 4e8;
        let level = |theta: f64| match theta.rem_euclid(period) < 0.6 * period {
            true => k1,
            false => 1.6 * k1,
        };
        let m_e = Drive::Torque.effective_mass(
            super::super::lumped::gear_inertias(&case),
            [
                case.pair.gears[0].base_radius,
                case.pair.gears[1].base_radius,
            ],
        );
        let hz = |k: f64| (k / m_e).sqrt() / std::f64::consts::TAU;
        let positions = 16;
        let rotations: Vec<f64> = (0..positions)
            .map(|j| j as f64 / positions as f64 * period)
            .collect();
        for shift in [0.0, 0.3 * period] {
            // The table starts `shift` after the pitch point: rotation r reads θ = r − shift.
            let stiffness = PeriodicTable::from_fn(period, 1000, |theta| level(theta + shift));
            model.mesh = MeshStiffness {
                origin: roll_pitch + shift,
                ..MeshStiffness::from_tables(
                    "two levels",
                    None,
                    stiffness,
                    PeriodicTable::constant(period, 0.0),
                )
            };
            let LumpedModes {
                mesh_hz: per_position,
                mesh_hz_at_mean_stiffness: at_mean,
                ..
            } = lumped_mesh_modes(
                &case,
                &model,
                (Drive::Torque, BodyModel::Rigid),
                0.0,
                &rotations,
            )
            .unwrap();
            for (r, f) in rotations.iter().zip(&per_position) {
                // Away from the table's steps (linear between its 1 000 samples).
                let expected = hz(level(*r));
                assert!((f / expected - 1.0).abs() < 1e-9, "{r}: {f} vs {expected}");
            }
            let k_mean = model.mesh.stiffness.mean();
            assert!((at_mean / hz(k_mean) - 1.0).abs() < 1e-12);
            // 10 of the 16 positions at k1, against 60 % of the period: the mean of √k over the
            // positions, (10 + 6 √1.6)/16, below √k̄ = √1.24 by 1.30 %.
            let mean = per_position.iter().sum::<f64>() / positions as f64;
            let gap = at_mean / mean - 1.0;
            let expected = 1.24f64.sqrt() / ((10.0 + 6.0 * 1.6f64.sqrt()) / 16.0) - 1.0;
            assert!((gap - expected).abs() < 1e-6, "gap {gap} vs {expected}");
            assert!((expected - 0.0130).abs() < 5e-4);
        }
    }
}
