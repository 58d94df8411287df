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
    /// The case's lumped model at the mean linearized stiffness [Hz]: the mode the sweep's
    /// primary resonance follows (how it differs from the per-position mean:
    /// [`lumped_mesh_modes`]).
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
    /// Driver held, elastic bodies: the driver body's torsion (its rim against the held hub),
    /// the FE modal's ([`PairModes::torsion_mode`]) and the case's lumped model's, each the
    /// mean over the positions [Hz], and lumped / FE modal − 1; `None` where either has none.
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
/// [`crate::lumped::Structure::body_mode`] on `rim1 lag`, the speed drive's coordinate).
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
    let hz = |k_mesh: f64| structure.mesh_mode(k_of(k_mesh)).frequency / std::f64::consts::TAU;
    let pair = &case.pair;
    let roll_pitch = pair.roll_angle_at(1, pair.contact_points.pitch);
    let stiffness: Vec<f64> = rotations
        .iter()
        .map(|rotation| {
            let theta = roll_pitch + rotation - linear.mesh.origin;
            linear.mesh.stiffness.at(theta)
        })
        .collect();
    let per_position = stiffness.iter().map(|k| hz(*k)).collect();
    // The driver held with elastic bodies: the driver's rim against its held hub.
    let torsion = match (drive, bodies) {
        (Drive::Speed, BodyModel::Elastic) => stiffness
            .iter()
            .map(|k| {
                structure
                    .body_mode(k_of(*k), "rim1 lag")
                    .map(|m| m.frequency / std::f64::consts::TAU)
            })
            .collect::<Option<Vec<f64>>>(),
        _ => None,
    };
    Ok(LumpedModes {
        mesh_hz: per_position,
        mesh_hz_at_mean_stiffness: hz(linear.mesh.mean()),
        driver_torsion_hz: torsion,
    })
}

/// What [`lumped_mesh_modes`] finds [Hz].
struct LumpedModes {
    /// The mesh mode at each position.
    mesh_hz: Vec<f64>,
    mesh_hz_at_mean_stiffness: f64,
    /// The driver body's torsion at each position (driver held, elastic bodies).
    driver_torsion_hz: Option<Vec<f64>>,
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
        let fe_modal_hz: Vec<(f64, f64)> = at
            .iter()
            .map(|m| {
                (
                    m.driver_rotation.to_degrees(),
                    m.modes[m.mesh_mode].frequency_hz,
                )
            })
            .collect();
        let mean = |hz: &[f64]| hz.iter().sum::<f64>() / hz.len() as f64;
        let fe_modal_mean_hz = mean(&fe_modal_hz.iter().map(|p| p.1).collect::<Vec<_>>());
        let LumpedModes {
            mesh_hz: per_position,
            mesh_hz_at_mean_stiffness: lumped_at_mean_stiffness_hz,
            driver_torsion_hz: torsion,
        } = lumped_mesh_modes(
            case,
            &setup.model,
            (drive, case.lumped.bodies),
            twist_in_model,
            &rotations,
        )?;
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
        let driver_torsion_fe_modal_hz =
            super::compare::driver_torsion_hz(&excited_body_modes_fe_modal);
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
