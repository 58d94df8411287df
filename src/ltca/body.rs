//! An elastic gear body for the LTCA: mesh, factorized stiffness with the bore held, and the
//! compliance condensed onto the candidate flank nodes.
//!
//! The bore nodes are fixed: the driver's hub is held, and the driven gear's rigid hub rotation
//! φ is carried by the contact problem as a rigid-body term (a rigid rotation does not deform
//! the body), so both bodies need only the bore-fixed compliance
//! ```text
//! G[k, l] = n_kᵀ K⁻¹ n_l     (n: unit inward flank normal at the node, placed in the global DOFs)
//! ```
//! — one sparse Cholesky factorization per body, one forward/back solve per candidate node.

use nalgebra::{DMatrix, Point2, Rotation2, Vector2};

use crate::fe::assembly::{check_elements, stiffness_triplets, FactorizedStiffness, FeError};
use crate::fe::{elasticity_matrix, PlaneState};
use crate::geometry::{FlankModification, Gear, Side};
use crate::mesh::{mesh_gear, GearMesh, MeshSpec};

/// One candidate node on an engaging flank.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlankCandidate {
    pub tooth: usize,
    pub node: usize,
    /// Roll angle of the node on the modified flank [rad].
    pub roll_angle: f64,
    /// Position in the gear's tooth-local frame [m].
    pub position: Point2<f64>,
    /// Unit inward normal in the tooth-local frame.
    pub inward: Vector2<f64>,
}

/// A meshed, factorized gear with its condensed flank compliance.
pub struct LtcaBody {
    pub mesh: GearMesh,
    /// Candidate nodes: the loaded flank (tooth-local left side) of every fine tooth.
    pub candidates: Vec<FlankCandidate>,
    /// G[k, l]: inward displacement of candidate k per unit inward force at candidate l [m/N].
    pub compliance: DMatrix<f64>,
    pub free_dofs: usize,
    /// Wall time of assembly + factorization, and of the compliance solves [s].
    pub factorization_s: f64,
    pub condensation_s: f64,
}

/// Material and plane state of the bodies.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyMaterial {
    pub youngs_modulus: f64,
    pub poisson_ratio: f64,
    pub plane: PlaneState,
}

impl LtcaBody {
    /// Meshes `gear` (the `loaded_side` flank of `spec.fine_teeth` are the contact candidates),
    /// factorizes K with the bore fixed and condenses the compliance onto the candidates.
    pub fn new(
        gear: &Gear,
        modification: &FlankModification,
        spec: &MeshSpec,
        material: BodyMaterial,
        loaded_side: Side,
    ) -> Result<Self, FeError> {
        let started = std::time::Instant::now();
        let mesh = mesh_gear(gear, modification, spec);
        check_elements(&mesh.nodes, &mesh.elements)?;
        let d = elasticity_matrix(
            material.youngs_modulus,
            material.poisson_ratio,
            material.plane,
        );
        let triplets = stiffness_triplets(&mesh.nodes, &mesh.elements, &d, gear.spec.face_width);
        let fixed: Vec<usize> = mesh
            .bore_nodes
            .iter()
            .flat_map(|&i| [2 * i, 2 * i + 1])
            .collect();
        let dofs = 2 * mesh.nodes.len();
        let stiffness = FactorizedStiffness::new(dofs, triplets, &fixed)?;
        let factorization_s = started.elapsed().as_secs_f64();

        let started = std::time::Instant::now();
        let mut candidates = Vec::new();
        for &tooth in &spec.fine_teeth {
            let flank = mesh.flank(tooth, loaded_side);
            let rotation = Rotation2::new(tooth as f64 * gear.angular_pitch());
            for (&node, &xi) in flank.nodes.iter().zip(&flank.roll_angles) {
                let right = gear.flank_inward_normal(xi);
                let local = match loaded_side {
                    Side::Right => right,
                    Side::Left => Vector2::new(-right.x, right.y),
                };
                candidates.push(FlankCandidate {
                    tooth,
                    node,
                    roll_angle: xi,
                    position: mesh.nodes[node],
                    inward: rotation * local,
                });
            }
        }
        let points: Vec<(usize, [f64; 2])> = candidates
            .iter()
            .map(|c| (c.node, [c.inward.x, c.inward.y]))
            .collect();
        let compliance = stiffness.compliance_between(&points);
        // Maxwell–Betti: G is symmetric; average away the round-off.
        let compliance = (&compliance + compliance.transpose()) * 0.5;
        Ok(LtcaBody {
            free_dofs: stiffness.free_dofs(),
            mesh,
            candidates,
            compliance,
            factorization_s,
            condensation_s: started.elapsed().as_secs_f64(),
        })
    }
}
