//! Modal analysis of the meshed pair, linearized about the LTCA's loaded contact state.
//!
//! # Model
//! * Both gear bodies as the LTCA meshes them (Q8, plane state of the case), with their
//!   consistent mass ρ b ∫NᵀN dA.
//! * Hubs as rigid bodies: the bore nodes follow the hub rotation ψ, u = ψ ẑ × X (X from the
//!   gear centre), so the hub carries the bore nodes' stiffness and inertia. [`Hubs::DriverHeld`]:
//!   the driver's hub is fixed, as in the explicit FE whose driver bore follows the prescribed
//!   speed; [`Hubs::BothFree`]: both hubs rotate, as in the lumped model's torque drive (one
//!   rigid-body mode at 0 Hz). Bearings are rigid.
//! * The contact's tangent stiffness at the loaded state: the LTCA's contact is hard, so each
//!   active point ties the two flanks along its normal. The tie is a spring k_c = 10⁴ / C_kk
//!   (C_kk the point's own compliance through both bodies) on the gap change
//!   Δg = Σ w (n · u) over both gears' flank nodes — the constraint's compliance is 10⁻⁴ of the
//!   bodies', below the model's other errors, and K − σM stays well conditioned. Points that
//!   are open at the loaded state (and the back flanks, open by the load's deflection) carry
//!   nothing. Prestress (geometric stiffness) is left out: the contact stresses are far below
//!   what would change a body's stiffness.
//! * The lowest modes by shift-invert Lanczos ([`crate::fe::modal`]).
//!
//! # The mesh mode
//! A unit torque on the driven hub loads the mesh. Its static hub rotation is the sum over the
//! modes of Γᵢ²/ωᵢ² (Γᵢ = φᵢᵀ f, modal participation of the torque): each mode's share of the
//! mesh's torsional compliance. The mesh mode is the elastic mode with the largest share; the
//! modes above it are the tooth and body modes. [`PairModes::static_mesh_stiffness`] is the
//! same K's static hub-to-hub tangent, held against the LTCA's condensed aᵀC⁻¹a.
//!
//! The mesh mode lies above √(k_static/m) with rigid-gear inertias: the hub-to-hub stiffness
//! holds each body's twist between bore and teeth, while most of the inertia sits outside it;
//! behind a light free hub that twist does not take part (see [`crate::study::compare`]).

use nalgebra::{Point2, Vector2};

use super::{body::BodyMaterial, LoadedContacts, LtcaError, LtcaModel};
use crate::fe::assembly::{
    element_triplets, stiffness_triplets, symmetric_product, FactorizedStiffness,
};
use crate::fe::modal::{lowest_modes, Mode};
use crate::fe::{elasticity_matrix, q8};

/// How the hubs are held: the boundary condition of the pair's rotation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Hubs {
    /// The driver's hub fixed (the explicit FE's speed drive): the mesh mode's mass is the
    /// driven gear's.
    DriverHeld,
    /// Both hubs free (the lumped model's torque drive): one rigid-body mode at 0 Hz.
    BothFree,
}

/// The contact ties' stiffness over the point's own compliance: a hard contact to 10⁻⁴.
const TIE_STIFFENING: f64 = 1e4;

/// Modes below this are the rigid-body rotation of a free pair [Hz].
const RIGID_HZ: f64 = 1.0;

/// A mode of the meshed pair.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PairMode {
    pub frequency_hz: f64,
    /// Share of the driven hub's static torsional compliance (Γ²/ω² over the sum of the elastic
    /// modes found): near 1 for the mesh mode.
    pub mesh_share: f64,
    /// `rigid`, `mesh`, or `tooth/body`.
    pub kind: &'static str,
}

/// The modes of the pair at one mesh position.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PairModes {
    pub hubs: Hubs,
    /// Driver rotation of the position from the pitch-point position [rad].
    pub driver_rotation: f64,
    pub modes: Vec<PairMode>,
    /// Index of the mesh mode in `modes`.
    pub mesh_mode: usize,
    /// Tangent mesh stiffness of the modal model along the line of action, from its static hub
    /// rotation under a torque on the driven hub [N/m] (driver held).
    pub static_mesh_stiffness: f64,
    /// The mesh mode's driven-hub rotation in its mass-normalized shape (φᵀMφ = 1) [rad/√(kg·m²)]:
    /// a torsional dashpot c on the driven hub gives the mode the first-order damping ratio
    /// c φ²/(2ω) (the explicit FE's mesh dashpot with the driver held).
    pub mesh_mode_driven_hub_shape: f64,
    /// The LTCA's secant and tangent mesh stiffness at the position [N/m].
    pub ltca_mesh_stiffness: f64,
    pub ltca_tangent_stiffness: f64,
    /// Rotary inertia of each gear in the model (rigid rotation through the consistent mass)
    /// [kg·m²].
    pub inertias: [f64; 2],
    /// Active contact ties, unknowns, and the largest relative Lanczos residual.
    pub ties: usize,
    pub dofs: usize,
    pub residual: f64,
}

/// Where each DOF of a body goes in the pair's unknowns: (unknown, coefficient) terms.
type DofMap = Vec<Vec<(usize, f64)>>;

/// Numbers body `g`'s DOFs from `first`: interior DOFs one unknown each, bore DOFs onto the hub
/// rotation (u = ψ ẑ × X: (−Y, X)), or nowhere when the hub is held. Returns the map and the
/// next free unknown.
fn dof_map(nodes: &[Point2<f64>], bore: &[usize], first: usize, hub_free: bool) -> (DofMap, usize) {
    let mut on_bore = vec![false; nodes.len()];
    bore.iter().for_each(|&n| on_bore[n] = true);
    let mut next = first;
    let mut map = vec![Vec::new(); 2 * nodes.len()];
    for n in 0..nodes.len() {
        if !on_bore[n] {
            map[2 * n] = vec![(next, 1.0)];
            map[2 * n + 1] = vec![(next + 1, 1.0)];
            next += 2;
        }
    }
    let hub = next;
    if hub_free {
        next += 1;
        for &n in bore {
            let p = nodes[n];
            map[2 * n] = vec![(hub, -p.y)];
            map[2 * n + 1] = vec![(hub, p.x)];
        }
    }
    (map, next)
}

/// Maps lower-triangle triplets of a body through its DOF map into the pair's lower triangle.
fn map_triplets(
    triplets: &[(usize, usize, f64)],
    map: &DofMap,
    out: &mut Vec<(usize, usize, f64)>,
) {
    for &(r, c, v) in triplets {
        for &(rr, cr) in &map[r] {
            for &(cc, ccoef) in &map[c] {
                let value = v * cr * ccoef;
                if rr == cc && r != c {
                    // An off-diagonal pair (r, c) and (c, r) landing on one diagonal entry.
                    out.push((rr, rr, 2.0 * value));
                } else {
                    out.push((rr.max(cc), rr.min(cc), value));
                }
            }
        }
    }
}

/// Lower-triangle triplets of the consistent mass of a mesh.
fn mass_triplets(
    nodes: &[Point2<f64>],
    elements: &[[usize; 8]],
    density: f64,
    thickness: f64,
) -> Vec<(usize, usize, f64)> {
    element_triplets(nodes, elements, |xe| {
        q8::consistent_mass(xe, density, thickness)
    })
}

/// The assembled pair: stiffness and mass in the pair's unknowns, the hub unknowns.
struct PairSystem {
    n: usize,
    stiffness: Vec<(usize, usize, f64)>,
    mass: Vec<(usize, usize, f64)>,
    /// Hub rotation unknown of each gear (None: held).
    hubs: [Option<usize>; 2],
    /// Rotary inertia of each gear [kg·m²].
    inertias: [f64; 2],
}

fn assemble(
    model: &LtcaModel,
    contacts: &LoadedContacts,
    material: BodyMaterial,
    density: f64,
    hubs: Hubs,
) -> PairSystem {
    let d = elasticity_matrix(
        material.youngs_modulus,
        material.poisson_ratio,
        material.plane,
    );
    let mut stiffness = Vec::new();
    let mut mass = Vec::new();
    let mut maps: Vec<DofMap> = Vec::new();
    let mut hub_index = [None, None];
    let mut inertias = [0.0; 2];
    let mut next = 0;
    for (g, body) in model.bodies.iter().enumerate() {
        let mesh = &body.mesh;
        let thickness = model.pair.gears[g].spec.face_width;
        let hub_free = g == 1 || hubs == Hubs::BothFree;
        let (map, end) = dof_map(&mesh.nodes, &mesh.bore_nodes, next, hub_free);
        if hub_free {
            hub_index[g] = Some(end - 1);
        }
        next = end;
        let k = stiffness_triplets(&mesh.nodes, &mesh.elements, &d, thickness);
        map_triplets(&k, &map, &mut stiffness);
        let m = mass_triplets(&mesh.nodes, &mesh.elements, density, thickness);
        map_triplets(&m, &map, &mut mass);
        // The gear's inertia: its rigid rotation (ψ ẑ × X at every node) through its mass.
        let rotation: Vec<f64> = mesh.nodes.iter().flat_map(|p| [-p.y, p.x]).collect();
        let mr = symmetric_product(&m, &rotation);
        inertias[g] = rotation.iter().zip(&mr).map(|(a, b)| a * b).sum::<f64>();
        maps.push(map);
    }
    for tie in &contacts.active {
        // Gap gradient b: Δg = bᵀ x over the pair's unknowns; the tie adds k_c b bᵀ.
        let mut b: Vec<(usize, f64)> = Vec::new();
        for (g, nodes) in tie.nodes.iter().enumerate() {
            for &(node, weight, normal) in nodes {
                let normal: Vector2<f64> = normal;
                for (axis, component) in [normal.x, normal.y].into_iter().enumerate() {
                    for &(unknown, coefficient) in &maps[g][2 * node + axis] {
                        b.push((unknown, weight * component * coefficient));
                    }
                }
            }
        }
        let k_tie = TIE_STIFFENING / tie.compliance;
        for &(i, bi) in &b {
            for &(j, bj) in &b {
                if i >= j {
                    stiffness.push((i, j, k_tie * bi * bj));
                }
            }
        }
    }
    PairSystem {
        inertias,
        n: next,
        stiffness,
        mass,
        hubs: hub_index,
    }
}

/// The `count` lowest modes of the pair at LTCA position `(index, positions)` (index of
/// positions per base pitch) under `torque`, with the mesh mode identified.
pub fn pair_modes(
    model: &LtcaModel,
    (index, positions): (usize, usize),
    torque: f64,
    material: BodyMaterial,
    density: f64,
    hubs: Hubs,
    count: usize,
) -> Result<PairModes, LtcaError> {
    let contacts = model.loaded_contacts(index, positions, torque)?;
    let system = assemble(model, &contacts, material, density, hubs);
    let n = system.n;
    let driven = system.hubs[1].expect("the driven hub is free");
    let rb2 = model.pair.gears[1].base_radius;

    // Static tangent: the driver held, a unit torque on the driven hub.
    let held: Vec<usize> = system.hubs[0].into_iter().collect();
    let mut torque_load = vec![0.0; n];
    torque_load[driven] = 1.0;
    let static_rotation =
        FactorizedStiffness::new(n, system.stiffness.clone(), &held)?.solve(&torque_load)[driven];
    let static_mesh_stiffness = 1.0 / (static_rotation * rb2 * rb2);

    // A shift well below the mesh mode: (2π·10 Hz)² under zero.
    let shift = -(std::f64::consts::TAU * 10.0).powi(2);
    let modes: Vec<Mode> = lowest_modes(n, &system.stiffness, &system.mass, count, shift)?;
    let residual = modes.iter().map(|m| m.residual).fold(0.0, f64::max);
    let compliance: Vec<f64> = modes
        .iter()
        .map(|m| {
            if m.frequency_hz < RIGID_HZ {
                0.0
            } else {
                m.shape[driven].powi(2) / m.eigenvalue
            }
        })
        .collect();
    let total: f64 = compliance.iter().sum();
    let mesh_mode = (0..modes.len())
        .max_by(|&a, &b| compliance[a].total_cmp(&compliance[b]))
        .unwrap_or(0);
    let mesh_mode_driven_hub_shape = modes.get(mesh_mode).map_or(f64::NAN, |m| m.shape[driven]);
    let modes = modes
        .iter()
        .zip(&compliance)
        .enumerate()
        .map(|(i, (m, c))| PairMode {
            frequency_hz: m.frequency_hz,
            mesh_share: c / total,
            kind: if m.frequency_hz < RIGID_HZ {
                "rigid"
            } else if i == mesh_mode {
                "mesh"
            } else {
                "tooth/body"
            },
        })
        .collect();
    Ok(PairModes {
        hubs,
        driver_rotation: contacts.result.driver_rotation,
        modes,
        mesh_mode,
        static_mesh_stiffness,
        mesh_mode_driven_hub_shape,
        ltca_mesh_stiffness: contacts.result.mesh_stiffness,
        ltca_tangent_stiffness: contacts.result.tangent_stiffness,
        inertias: system.inertias,
        ties: contacts.active.len(),
        dofs: n,
        residual,
    })
}
