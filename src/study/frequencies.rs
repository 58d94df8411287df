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

use serde::Serialize;

use crate::case::{BodyModel, Case};
use crate::ltca::modal::{pair_modes, Hubs};
use crate::lumped::{Drive, MeshModel};

use super::{Progress, StudyError};

/// The tolerance of the lumped mesh mode against the FE modal's (issue target): 2 %.
pub const MESH_MODE_TOLERANCE: f64 = 0.02;

/// One boundary condition.
#[derive(Debug, Clone, Serialize)]
pub struct MeshModeComparison {
    pub hubs: Hubs,
    pub drive: Drive,
    /// The case's lumped model (its bodies) [Hz], and rigid gears behind the hub-to-hub k.
    pub lumped_hz: f64,
    pub lumped_rigid_hz: f64,
    /// FE modal mesh mode per position (driver rotation [deg], Hz) and its mean [Hz].
    pub fe_modal_hz: Vec<(f64, f64)>,
    pub fe_modal_mean_hz: f64,
    /// lumped / FE modal − 1.
    pub lumped_rel: f64,
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
/// with `bodies` [Hz]; a hub-to-hub stiffness is first given back the twist `twist` the case's
/// model took out of it, then the bodies' own taken out.
fn lumped_mesh_mode(
    case: &Case,
    model: &MeshModel,
    drive: Drive,
    bodies: BodyModel,
    twist_in_model: f64,
) -> Result<f64, StudyError> {
    let linear = model.linearized();
    let structure = super::lumped::drivetrain_with(case, drive, bodies, [None; 2], false)?;
    let twist_out = match (bodies, case.lumped.stiffness.holds_body_twist()) {
        (BodyModel::Elastic, true) => super::compare::body_twist(case).iter().sum(),
        _ => 0.0,
    };
    // From the model's mesh back to hub to hub (+ the twist it lost), then to these bodies.
    let k = 1.0 / (1.0 / linear.mesh.mean() + twist_in_model - twist_out);
    Ok(structure.mesh_mode(k).frequency / std::f64::consts::TAU)
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
    let total = 2 * positions;
    let compare = |b: usize, hubs: Hubs, drive: Drive| -> Result<_, StudyError> {
        let mut fe_modal_hz = Vec::with_capacity(positions);
        for j in 0..positions {
            progress("FE modal", b * positions + j, total);
            let modes = pair_modes(
                &ltca,
                (j, positions),
                torque,
                case.ltca_material(),
                case.material.density,
                hubs,
                6,
            )?;
            fe_modal_hz.push((
                modes.driver_rotation.to_degrees(),
                modes.modes[modes.mesh_mode].frequency_hz,
            ));
        }
        let fe_modal_mean_hz =
            fe_modal_hz.iter().map(|p| p.1).sum::<f64>() / fe_modal_hz.len() as f64;
        let lumped_hz = lumped_mesh_mode(
            case,
            &setup.model,
            drive,
            case.lumped.bodies,
            twist_in_model,
        )?;
        let lumped_rigid_hz =
            lumped_mesh_mode(case, &setup.model, drive, BodyModel::Rigid, twist_in_model)?;
        let lumped_rel = lumped_hz / fe_modal_mean_hz - 1.0;
        Ok(MeshModeComparison {
            hubs,
            drive,
            lumped_hz,
            lumped_rigid_hz,
            fe_modal_hz,
            fe_modal_mean_hz,
            lumped_rel,
            lumped_rigid_rel: lumped_rigid_hz / fe_modal_mean_hz - 1.0,
            pass: lumped_rel.abs() <= MESH_MODE_TOLERANCE,
        })
    };
    let driver_held = compare(0, Hubs::DriverHeld, Drive::Speed)?;
    let both_free = compare(1, Hubs::BothFree, Drive::Torque)?;
    progress("FE modal", total, total);
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
