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
    /// The case's lumped model at the mean tangent stiffness [Hz]: the mode the sweep's
    /// primary resonance follows (above the per-position mean, see [`lumped_mesh_modes`]).
    pub lumped_at_mean_stiffness_hz: f64,
    /// FE modal mesh mode per position (driver rotation [deg], Hz) and its mean [Hz].
    pub fe_modal_hz: Vec<(f64, f64)>,
    pub fe_modal_mean_hz: f64,
    /// lumped / FE modal − 1, of the means.
    pub lumped_rel: f64,
    /// The largest |lumped / FE modal − 1| of one position, signed.
    pub lumped_rel_worst_position: f64,
    pub lumped_rigid_rel: f64,
    /// Whether |lumped_rel| ≤ [`MESH_MODE_TOLERANCE`].
    pub pass: bool,
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
}

/// The mesh mode of `model`'s linearized mesh on the FE's boundary conditions under `drive`
/// with `bodies` [Hz], frozen at each of `positions` driver rotations j/N of a base pitch (the
/// FE modal's positions; the tables' θ = 0 is the LTCA's first position): the law's tangent
/// stiffness there, first given back, if hub to hub, the twist `twist` the case's model took out
/// of it, then the bodies' own taken out. Returns those and the mode at the mean stiffness.
///
/// The FE modal analysis gives one frequency per frozen position, so the compared quantity is
/// the same mean of the same per-position frequencies. f ∝ √k is concave, so that mean lies
/// below the frequency at the mean stiffness (the one the sweep's resonance follows) by about
/// var(k)/(8 k̄²): 0.5 % for a stiffness alternating between 1 and 1.6.
fn lumped_mesh_modes(
    case: &Case,
    model: &MeshModel,
    drive: Drive,
    bodies: BodyModel,
    twist_in_model: f64,
    positions: usize,
) -> Result<(Vec<f64>, f64), StudyError> {
    let linear = model.linearized();
    let structure = super::lumped::drivetrain_with(case, drive, bodies, [None; 2], false)?;
    let twist_out = match (bodies, case.lumped.stiffness.holds_body_twist()) {
        (BodyModel::Elastic, true) => super::compare::body_twist(case).iter().sum(),
        _ => 0.0,
    };
    // From the model's mesh back to hub to hub (+ the twist it lost), then to these bodies.
    let hz = |k_mesh: f64| {
        let k = 1.0 / (1.0 / k_mesh + twist_in_model - twist_out);
        structure.mesh_mode(k).frequency / std::f64::consts::TAU
    };
    let period = linear.mesh.period();
    let per_position = (0..positions)
        .map(|j| {
            hz(linear
                .mesh
                .stiffness
                .at(j as f64 / positions as f64 * period))
        })
        .collect();
    Ok((per_position, hz(linear.mesh.mean())))
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
    jobs.into_par_iter()
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
        .collect()
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
    let setup = super::lumped::setup(case)?;
    let twist_in_model = match case.lumped.stiffness.holds_body_twist() {
        true => super::lumped::structure_body_twist(case),
        false => 0.0,
    };
    let variant = super::relief_variant(case, case.lumped.relief.as_deref())?;
    let ltca = super::ltca::model(case, &variant.modifications)?;
    let torque = setup.torque;
    let modal = modal_at_positions(case, &ltca, positions, torque, 6, progress)?;
    let modal_hz: Vec<Vec<(f64, f64)>> = [Hubs::DriverHeld, Hubs::BothFree]
        .iter()
        .map(|&hubs| {
            modal
                .iter()
                .filter(|m| m.hubs == hubs)
                .map(|m| {
                    (
                        m.driver_rotation.to_degrees(),
                        m.modes[m.mesh_mode].frequency_hz,
                    )
                })
                .collect()
        })
        .collect();
    let compare = |b: usize, hubs: Hubs, drive: Drive| -> Result<_, StudyError> {
        let fe_modal_hz = modal_hz[b].clone();
        let fe_modal_mean_hz =
            fe_modal_hz.iter().map(|p| p.1).sum::<f64>() / fe_modal_hz.len() as f64;
        let mean = |hz: &[f64]| hz.iter().sum::<f64>() / hz.len() as f64;
        let (per_position, lumped_at_mean_stiffness_hz) = lumped_mesh_modes(
            case,
            &setup.model,
            drive,
            case.lumped.bodies,
            twist_in_model,
            positions,
        )?;
        let (rigid_per_position, _) = lumped_mesh_modes(
            case,
            &setup.model,
            drive,
            BodyModel::Rigid,
            twist_in_model,
            positions,
        )?;
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
        Ok(MeshModeComparison {
            hubs,
            drive,
            lumped_hz,
            lumped_at_mean_stiffness_hz,
            lumped_rigid_hz,
            lumped_hz_per_position,
            fe_modal_hz,
            fe_modal_mean_hz,
            lumped_rel,
            lumped_rel_worst_position,
            lumped_rigid_rel: lumped_rigid_hz / fe_modal_mean_hz - 1.0,
            pass: lumped_rel.abs() <= MESH_MODE_TOLERANCE,
        })
    };
    let driver_held = compare(0, Hubs::DriverHeld, Drive::Speed)?;
    let both_free = compare(1, Hubs::BothFree, Drive::Torque)?;
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
    })
}
