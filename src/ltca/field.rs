//! The stress field of one loaded body at one LTCA position: the position's contact forces put
//! on the body's flank nodes (bore held, as in the LTCA), K u = f solved, and the stress
//! recovered at every node of a window around one tooth ([`crate::fe::recovery`]: Barlow
//! points extrapolated and averaged at the nodes) — the picture behind the fillet stresses the
//! LTCA reports ([`super::LtcaModel::fillet_stresses`] gives the same numbers at the fillet
//! nodes, through the influence rows instead of the displacements).
//!
//! Von Mises with the out-of-plane stress of the plane state (σ_zz = ν(σ_xx + σ_yy) in plane
//! strain, 0 in plane stress):
//! ```text
//! σ_vM = √(½[(σ_xx − σ_yy)² + (σ_yy − σ_zz)² + (σ_zz − σ_xx)²] + 3τ_xy²)
//! ```

use nalgebra::{Point2, Vector2};

use super::{LoadedContacts, LtcaModel};
use crate::fe::assembly::FeError;
use crate::fe::recovery::{max_principal, NodalStress};
use crate::fe::PlaneState;

/// The displacements and stresses of a window of one body's mesh.
#[derive(Debug, Clone)]
pub struct StressField {
    /// 0 or 1.
    pub gear: usize,
    /// The tooth the window is centred on.
    pub tooth: usize,
    /// Node positions in the gear's frame (undeformed) [m].
    pub nodes: Vec<Point2<f64>>,
    /// Each node's index in the body's mesh.
    pub mesh_node: Vec<usize>,
    /// The window's elements (Q8, indices into `nodes`).
    pub elements: Vec<[usize; 8]>,
    /// Displacement of each node [m].
    pub displacement: Vec<Vector2<f64>>,
    /// (σ_xx, σ_yy, τ_xy) at each node [Pa].
    pub stress: Vec<[f64; 3]>,
    pub plane: PlaneState,
    pub poisson_ratio: f64,
}

impl StressField {
    /// The larger in-plane principal stress at each node [Pa].
    pub fn max_principal(&self) -> Vec<f64> {
        self.stress.iter().map(|s| max_principal(*s)).collect()
    }

    /// The von Mises stress at each node [Pa].
    pub fn von_mises(&self) -> Vec<f64> {
        self.stress
            .iter()
            .map(|&[sx, sy, txy]| {
                let sz = match self.plane {
                    PlaneState::Strain => self.poisson_ratio * (sx + sy),
                    PlaneState::Stress => 0.0,
                };
                (0.5 * ((sx - sy).powi(2) + (sy - sz).powi(2) + (sz - sx).powi(2))
                    + 3.0 * txy * txy)
                    .sqrt()
            })
            .collect()
    }
}

impl LtcaModel {
    /// The field of gear `gear` (0 or 1) under the loaded state `contacts`, on the elements
    /// whose centroid lies within `half_window` angular pitches of tooth `tooth`'s centre line.
    /// Assembles and factorizes the body once more (the LTCA keeps only its condensed
    /// compliance).
    pub fn stress_field(
        &self,
        contacts: &LoadedContacts,
        gear: usize,
        tooth: usize,
        half_window: f64,
    ) -> Result<StressField, FeError> {
        let body = &self.bodies[gear];
        let mesh = &body.mesh;
        let spec = &self.pair.gears[gear];
        let (stiffness, d) =
            super::body::bore_held_stiffness(mesh, self.material, spec.spec.face_width)?;
        let mut load = vec![0.0; 2 * mesh.nodes.len()];
        for contact in &contacts.active {
            for (node, weight, inward) in contact.nodes[gear] {
                load[2 * node] += contact.force * weight * inward.x;
                load[2 * node + 1] += contact.force * weight * inward.y;
            }
        }
        let u = stiffness.solve(&load);

        // The window: elements by their centroid's angle from the tooth's centre line (the
        // angle measured as the fillet nodes' is, from +y towards −x).
        let pitch = spec.angular_pitch();
        let centre = tooth as f64 * pitch;
        let inside = |e: &[usize; 8]| {
            let c = e[..4]
                .iter()
                .fold(Vector2::zeros(), |s, &n| s + mesh.nodes[n].coords)
                / 4.0;
            let angle = (-c.x).atan2(c.y);
            let offset = (angle - centre + std::f64::consts::PI)
                .rem_euclid(2.0 * std::f64::consts::PI)
                - std::f64::consts::PI;
            offset.abs() <= half_window * pitch
        };
        let mut index = vec![usize::MAX; mesh.nodes.len()];
        let mut targets = Vec::new();
        let elements: Vec<[usize; 8]> = mesh
            .elements
            .iter()
            .filter(|e| inside(e))
            .map(|e| {
                e.map(|n| {
                    if index[n] == usize::MAX {
                        index[n] = targets.len();
                        targets.push(n);
                    }
                    index[n]
                })
            })
            .collect();
        let recovered = NodalStress::new(&mesh.nodes, &mesh.elements, &d, &targets);
        Ok(StressField {
            gear,
            tooth,
            nodes: targets.iter().map(|&n| mesh.nodes[n]).collect(),
            elements,
            displacement: targets
                .iter()
                .map(|&n| Vector2::new(u[2 * n], u[2 * n + 1]))
                .collect(),
            stress: (0..targets.len()).map(|i| recovered.at(i, &u)).collect(),
            plane: self.material.plane,
            poisson_ratio: self.material.poisson_ratio,
            mesh_node: targets,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Von Mises of known states: uniaxial σ in plane stress is σ; pure shear τ is √3 τ; equal
    /// biaxial σ in plane strain with ν = 0.3 has σ_zz = 0.6σ, so σ_vM = 0.4σ.
    #[test]
    fn von_mises_of_known_states() {
        let field = |stress: [f64; 3], plane| StressField {
            gear: 0,
            tooth: 0,
            nodes: vec![Point2::origin()],
            mesh_node: vec![0],
            elements: vec![],
            displacement: vec![Vector2::zeros()],
            stress: vec![stress],
            plane,
            poisson_ratio: 0.3,
        };
        let vm = |s, p| field(s, p).von_mises()[0];
        assert!((vm([100.0, 0.0, 0.0], PlaneState::Stress) - 100.0).abs() < 1e-12);
        assert!((vm([0.0, 0.0, 50.0], PlaneState::Stress) - 50.0 * 3f64.sqrt()).abs() < 1e-12);
        assert!((vm([100.0, 100.0, 0.0], PlaneState::Strain) - 40.0).abs() < 1e-12);
        assert!(
            (field([30.0, -10.0, 0.0], PlaneState::Stress).max_principal()[0] - 30.0).abs() < 1e-12
        );
    }
}
