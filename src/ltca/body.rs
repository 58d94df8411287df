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
use crate::fe::recovery::NodalStress;
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
    /// Position in the gear's frame (mesh coordinates) [m].
    pub position: Point2<f64>,
    /// Unit inward normal in the gear's frame.
    pub inward: Vector2<f64>,
}

/// A node on the fillet of a fine tooth, where the root stress is recovered.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FilletNode {
    pub tooth: usize,
    pub node: usize,
    /// On the loaded flank's side of the tooth (the side in tension under the load) or not.
    pub loaded_side: bool,
    /// Distance from the gear centre [m].
    pub radius: f64,
}

/// The fillets' stress per unit force at each candidate flank node.
#[derive(Debug, Clone, Default)]
pub struct FilletStress {
    pub nodes: Vec<FilletNode>,
    /// Rows 3i, 3i + 1, 3i + 2: (σ_xx, σ_yy, τ_xy) at `nodes[i]` (gear frame) per unit inward
    /// force at each candidate [Pa/N], recovered as [`crate::fe::recovery`] does.
    pub influence: DMatrix<f64>,
}

impl FilletStress {
    /// (σ_xx, σ_yy, τ_xy) at every fillet node under the loads (candidate index, inward force
    /// [N]), a candidate possibly more than once: only the loaded candidates' columns are read, as a contact
    /// loads a few of the hundreds of candidates.
    pub fn stresses(&self, loads: impl IntoIterator<Item = (usize, f64)>) -> Vec<[f64; 3]> {
        let mut s = vec![0.0; self.influence.nrows()];
        for (candidate, force) in loads {
            for (si, c) in s.iter_mut().zip(self.influence.column(candidate).iter()) {
                *si += c * force;
            }
        }
        (0..self.nodes.len())
            .map(|i| [s[3 * i], s[3 * i + 1], s[3 * i + 2]])
            .collect()
    }
}

/// The boundary nodes of `gear`'s mesh on the fillets of its fine teeth: on an element edge no
/// other element shares, between the root circle and the form circle (where the fillet meets
/// the involute), each given to the nearest tooth, and its side told by the loaded flank's
/// (`loaded_side_sign`: the sign of the loaded flank's angle from its tooth's centre line).
fn fillet_nodes(gear: &Gear, mesh: &GearMesh, loaded_side_sign: f64) -> Vec<FilletNode> {
    let mut edges: std::collections::HashMap<(usize, usize), (usize, usize)> =
        std::collections::HashMap::new();
    for e in &mesh.elements {
        for (a, mid, b) in [(0, 4, 1), (1, 5, 2), (2, 6, 3), (3, 7, 0)] {
            let key = (e[a].min(e[b]), e[a].max(e[b]));
            edges.entry(key).or_insert((e[mid], 0)).1 += 1;
        }
    }
    let mut on_boundary = vec![false; mesh.nodes.len()];
    for ((a, b), (mid, count)) in &edges {
        if *count == 1 {
            for n in [*a, *b, *mid] {
                on_boundary[n] = true;
            }
        }
    }
    let pitch = gear.angular_pitch();
    let z = gear.teeth() as f64;
    // A hair beyond both circles: nodes sit on them to round-off.
    let (low, high) = (
        gear.root_radius * (1.0 - 1e-9),
        gear.form_radius * (1.0 + 1e-9),
    );
    let mut nodes = Vec::new();
    for (n, p) in mesh.nodes.iter().enumerate() {
        let radius = p.coords.norm();
        if !on_boundary[n] || radius < low || radius > high {
            continue;
        }
        let angle = (-p.x).atan2(p.y);
        let k = (angle / pitch).round();
        let tooth = (k.rem_euclid(z)) as usize;
        if !mesh.fine_teeth.contains(&tooth) {
            continue;
        }
        let offset = angle - k * pitch;
        nodes.push(FilletNode {
            tooth,
            node: n,
            loaded_side: offset * loaded_side_sign > 0.0,
            radius,
        });
    }
    nodes
}

/// The body's stiffness with its bore nodes held, factorized, and its elasticity matrix.
pub fn bore_held_stiffness(
    mesh: &GearMesh,
    material: BodyMaterial,
    face_width: f64,
) -> Result<(FactorizedStiffness, nalgebra::Matrix3<f64>), FeError> {
    let d = elasticity_matrix(
        material.youngs_modulus,
        material.poisson_ratio,
        material.plane,
    );
    let triplets = stiffness_triplets(&mesh.nodes, &mesh.elements, &d, face_width);
    let fixed: Vec<usize> = mesh
        .bore_nodes
        .iter()
        .flat_map(|&i| [2 * i, 2 * i + 1])
        .collect();
    Ok((
        FactorizedStiffness::new(2 * mesh.nodes.len(), triplets, &fixed)?,
        d,
    ))
}

/// A gear body's rim swaying on its held bore, as one coordinate: the rim's mean translation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyTranslation {
    /// k_y [N/m]: the force on the teeth per unit translation.
    pub stiffness: f64,
    /// m_y/ρ [m³]: the coordinate's mass per unit density.
    pub mass_per_density: f64,
}

/// A gear body's rim translating on its held bore (`mesh`, its bore held as in `stiffness`,
/// [`bore_held_stiffness`]) as one coordinate: the Guyan reduction of the body onto its rim's
/// translation, the rim being the band one module deep under the root circle (a quarter of
/// the body's depth where that is less: a thin rim). The band is
/// pulled along e by a load proportional to its nodes' masses (a uniform acceleration of the
/// band alone: its resultant has no moment about the centre), the body deflects by u = K⁻¹f
/// (the teeth ride on the band, unloaded, as the mesh force leaves every tooth but the loaded
/// one), the shape ψ = u/ū is scaled to the band's mean translation ū = Σ m_i u_i·e / Σ m_i,
/// and
/// ```text
/// k_y = ψᵀKψ = fᵀu / ū²,    m_y/ρ = ψᵀMψ = Σ m_i |u_i|² / ū²
/// ```
/// (M the HRZ-lumped nodal masses of unit density, the sum over the whole body): the rim
/// moves by F/k_y under a force F on it, and √(k_y/m_y) is the Rayleigh quotient of the
/// static shape, an upper bound of the body's lowest lateral mode (Meirovitch, *Elements of
/// Vibration Analysis*, 1986, § 7.5). The teeth are rigid on the rim here, as in the body's
/// twist ([`crate::geometry::Gear::body_torsional_compliance`]): their bending under a load is
/// the mesh stiffness's, under their own inertia a mode of their own far above the mesh mode.
/// A body of z ≥ 3 equal teeth is isotropic in the plane; the two directions are averaged
/// over what fine teeth break of that.
pub fn body_translation(
    gear: &Gear,
    mesh: &GearMesh,
    stiffness: &FactorizedStiffness,
    face_width: f64,
) -> Result<BodyTranslation, FeError> {
    let sway = sway_shapes(gear, mesh, stiffness, face_width)?;
    let (mut k, mut m) = (0.0, 0.0);
    for (f, u) in sway.loads.iter().zip(&sway.shapes) {
        let work: f64 = f.iter().zip(u).map(|(f, u)| f * u).sum();
        let kinetic: f64 = u
            .iter()
            .enumerate()
            .map(|(i, u)| sway.nodal_mass[i / 2] * u * u)
            .sum();
        k += 0.5 * work;
        m += 0.5 * kinetic;
    }
    if !(k > 0.0 && k.is_finite() && m > 0.0 && m.is_finite()) {
        return Err(FeError::Body(format!(
            "the body's sway came out as k = {k:e} N/m, m/ρ = {m:e} m³: check the mesh"
        )));
    }
    Ok(BodyTranslation {
        stiffness: k,
        mass_per_density: m,
    })
}

/// The static shapes [`body_translation`] reduces a body onto: along x and y, each scaled to
/// a unit mean translation of the rim band (ψ = u/ū), with the band loads f/ū that make them
/// and the HRZ nodal masses of unit density.
pub struct SwayShapes {
    /// ψ along x and y over the mesh's DOFs (2 per node, the bore's zero).
    pub shapes: [Vec<f64>; 2],
    pub loads: [Vec<f64>; 2],
    pub nodal_mass: Vec<f64>,
}

/// [`SwayShapes`] of `mesh` (its bore held as in `stiffness`).
pub fn sway_shapes(
    gear: &Gear,
    mesh: &GearMesh,
    stiffness: &FactorizedStiffness,
    face_width: f64,
) -> Result<SwayShapes, FeError> {
    let mut mass = vec![0.0; mesh.nodes.len()];
    for element in &mesh.elements {
        let nodes = crate::fe::assembly::element_nodes(&mesh.nodes, element);
        let lumped =
            crate::fe::q8::lumped_mass(&nodes, 1.0, face_width, crate::fe::q8::MassLumping::Hrz);
        for (&n, m) in element.iter().zip(lumped) {
            mass[n] += m;
        }
    }
    // A module deep, or a quarter of a thin rim; nodes on the root circle sit on it to
    // round-off.
    let depth = gear
        .module()
        .min(0.25 * (gear.root_radius - gear.spec.bore_radius));
    let (low, high) = (gear.root_radius - depth, gear.root_radius * (1.0 + 1e-9));
    let rim: Vec<usize> = (0..mesh.nodes.len())
        .filter(|&n| (low..=high).contains(&mesh.nodes[n].coords.norm()))
        .collect();
    let rim_mass: f64 = rim.iter().map(|&n| mass[n]).sum();
    if !(rim_mass > 0.0) {
        return Err(FeError::Body(format!(
            "no mesh nodes in the rim band {:.3}–{:.3} mm under the root circle: check the \
             bore and root radii",
            low * 1e3,
            high * 1e3
        )));
    }
    let loads: Vec<Vec<f64>> = (0..2)
        .map(|d| {
            let mut f = vec![0.0; 2 * mass.len()];
            for &n in &rim {
                f[2 * n + d] = mass[n];
            }
            f
        })
        .collect();
    let deflections = stiffness.solve_columns(&loads);
    let mut scaled = Vec::with_capacity(2);
    for (d, (f, u)) in loads.into_iter().zip(deflections).enumerate() {
        let mean = rim.iter().map(|&n| mass[n] * u[2 * n + d]).sum::<f64>() / rim_mass;
        if !(mean.is_finite() && mean != 0.0) {
            return Err(FeError::Body(format!(
                "the body's rim band did not move under its load (mean translation {mean:e} m): \
                 check the mesh"
            )));
        }
        scaled.push((
            f.iter().map(|x| x / mean).collect::<Vec<f64>>(),
            u.iter().map(|x| x / mean).collect::<Vec<f64>>(),
        ));
    }
    let [(fx, ux), (fy, uy)]: [(Vec<f64>, Vec<f64>); 2] =
        scaled.try_into().expect("two directions");
    Ok(SwayShapes {
        shapes: [ux, uy],
        loads: [fx, fy],
        nodal_mass: mass,
    })
}

/// [`body_translation`] of `gear` unmodified on a mesh of `spec`, its bore held.
pub fn body_translation_of(
    gear: &Gear,
    spec: &MeshSpec,
    material: BodyMaterial,
) -> Result<BodyTranslation, FeError> {
    let mesh = mesh_gear(gear, &FlankModification::default(), spec);
    check_elements(&mesh.nodes, &mesh.elements)?;
    let (stiffness, _) = bore_held_stiffness(&mesh, material, gear.spec.face_width)?;
    body_translation(gear, &mesh, &stiffness, gear.spec.face_width)
}

/// A meshed, factorized gear with its condensed flank compliance.
pub struct LtcaBody {
    pub mesh: GearMesh,
    /// Candidate nodes: the loaded flank (tooth-local left side) of every fine tooth.
    pub candidates: Vec<FlankCandidate>,
    /// G[k, l]: inward displacement of candidate k per unit inward force at candidate l [m/N].
    pub compliance: DMatrix<f64>,
    /// The root stress per unit candidate force.
    pub fillet: FilletStress,
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
        let (stiffness, d) = bore_held_stiffness(&mesh, material, gear.spec.face_width)?;
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
        // The loaded flank's side of its tooth's centre line, from its first candidate.
        let loaded_side_sign = candidates.first().map_or(1.0, |c| {
            let pitch = gear.angular_pitch();
            let angle = (-c.position.x).atan2(c.position.y);
            // From the nearest tooth's centre line, as `fillet_nodes` measures it (an angle past
            // π would flip the sign).
            (angle - (angle / pitch).round() * pitch).signum()
        });
        let fillet_nodes = fillet_nodes(gear, &mesh, loaded_side_sign);
        let targets: Vec<usize> = fillet_nodes.iter().map(|f| f.node).collect();
        let recovered = NodalStress::new(&mesh.nodes, &mesh.elements, &d, &targets);
        let sensors: Vec<Vec<(usize, f64)>> = recovered.rows.into_iter().flatten().collect();
        let (compliance, influence) = stiffness.compliance_and_influence(&points, &sensors);
        // Maxwell–Betti: G is symmetric; average away the round-off.
        let compliance = (&compliance + compliance.transpose()) * 0.5;
        Ok(LtcaBody {
            free_dofs: stiffness.free_dofs(),
            mesh,
            candidates,
            compliance,
            fillet: FilletStress {
                nodes: fillet_nodes,
                influence,
            },
            factorization_s,
            condensation_s: started.elapsed().as_secs_f64(),
        })
    }
}
