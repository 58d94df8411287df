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

use super::{
    body::{BodyMaterial, SwayShapes},
    LoadedContacts, LtcaError, LtcaModel,
};
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
    /// Each gear's share of its rigid rotation in the mode, Γ²/(rᵀMr) with Γ = φᵀMr, r the
    /// gear's rigid rotation ψ ẑ × X over its free nodes (and its hub when free), φ
    /// mass-normalized: the mode's effective polar inertia over the gear's. The shares of one
    /// gear sum to 1 over all modes (modal effective mass; Clough & Penzien §13-3); a torsional
    /// body mode carries a large share of its gear's, a lateral or tooth mode next to none.
    pub rotation_share: [f64; 2],
    /// Each gear's share of its in-plane translation in the mode, (Γ_x² + Γ_y²)/(tᵀMt) with t
    /// a unit translation of the gear's free nodes (the bore cannot translate: the bearings
    /// are rigid): large for a lateral body mode, the rim swaying on the body against the
    /// held bore, which the mesh force excites along the line of action.
    pub lateral_share: [f64; 2],
    /// `rigid`, `mesh`, `driver torsion`, `driven torsion`, `driver lateral`, `driven lateral`
    /// (the largest of the shares above, when at least [`BODY_MODE_SHARE`]; a lateral mode
    /// with both gears' shares within a factor 2, [`BOTH_LATERAL`]), or `tooth/body`.
    pub kind: &'static str,
}

/// The least share of a gear's rigid rotation or translation for a mode to be named that
/// gear's torsional or lateral body mode (else `tooth/body`).
pub const BODY_MODE_SHARE: f64 = 0.05;

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

impl PairModes {
    /// The mode above the mesh mode that twists gear `gear`'s body most, its rim against its
    /// hub: of the modes named its torsion ([`PairMode::kind`]), the one with the largest
    /// [`PairMode::rotation_share`] of that gear. Not simply the next mode up: the bodies'
    /// lateral modes (the rim swaying against the held bore, in pairs across and along the line
    /// of action) can lie below it — on a 24/40 pair the driven gear's at 14.7 / 15.3 kHz, the
    /// pinion's torsion at 28.4 kHz. Meaningful for a held hub (the driver, driver held): a
    /// rim turning against a light free hub has next to no net rigid rotation, so a free gear's
    /// body torsion is not found this way. `None` when no mode among those computed is named
    /// so (a pair whose torsion lies above them).
    pub fn torsion_mode(&self, gear: usize) -> Option<&PairMode> {
        self.modes
            .iter()
            .skip(self.mesh_mode + 1)
            .filter(|m| m.kind == BODY_MODE_KINDS[gear])
            .max_by(|a, b| a.rotation_share[gear].total_cmp(&b.rotation_share[gear]))
    }

    /// The body modes above the mesh mode that the mesh drives: of each named body kind
    /// ([`ALL_BODY_MODE_KINDS`]) the mode with
    /// the largest [`PairMode::mesh_share`], when that is at least [`EXCITED_MESH_SHARE`]; in
    /// the order of the kinds. Of a lateral pair this is the one along the line of action (the
    /// one across it has a share near round-off).
    pub fn excited_body_modes(&self) -> Vec<&PairMode> {
        ALL_BODY_MODE_KINDS
            .iter()
            .filter_map(|kind| {
                self.modes
                    .iter()
                    .skip(self.mesh_mode + 1)
                    .filter(|m| m.kind == *kind)
                    .max_by(|a, b| a.mesh_share.total_cmp(&b.mesh_share))
                    .filter(|m| m.mesh_share >= EXCITED_MESH_SHARE)
            })
            .collect()
    }
}

/// The named body modes of one gear, in order.
pub const BODY_MODE_KINDS: [&str; 4] = [
    "driver torsion",
    "driven torsion",
    "driver lateral",
    "driven lateral",
];

/// A lateral mode of both gears at once (each with at least half the other's share): equal
/// gears' lateral modes share a frequency and mix.
pub const BOTH_LATERAL: &str = "lateral, both gears";

/// Every kind a body mode is named ([`PairMode::kind`]), in order.
pub const ALL_BODY_MODE_KINDS: [&str; 5] = [
    BODY_MODE_KINDS[0],
    BODY_MODE_KINDS[1],
    BODY_MODE_KINDS[2],
    BODY_MODE_KINDS[3],
    BOTH_LATERAL,
];

/// The least share of the mesh's compliance for a body mode to count as driven by the mesh
/// ([`PairModes::excited_body_modes`]): 1e-6. The body modes the mesh couples to carry 1e-5 to
/// 1e-3 (paper pair: the driver's torsion 5e-4, the lateral mode along the line of action
/// 1.3e-4; 24/40: 1e-5 to 2.5e-4); those it does not (across the line of action, or
/// symmetric) 1e-10 and below.
pub const EXCITED_MESH_SHARE: f64 = 1e-6;

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
    /// Each gear's rigid rotation and its translations along x and y in the pair's unknowns,
    /// as M v and vᵀMv: what [`PairMode::rotation_share`] and [`PairMode::lateral_share`]
    /// project the modes on.
    rigid: [[(Vec<f64>, f64); 3]; 2],
    /// Each gear's rigid rotation v itself.
    rotations: [Vec<f64>; 2],
    /// Each body's DOFs in the pair's unknowns.
    maps: Vec<DofMap>,
    /// Each active tie's gap gradient b (Δg = bᵀx).
    tie_gradients: Vec<Vec<(usize, f64)>>,
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
    let mut rigid: [[Vec<f64>; 3]; 2] = Default::default();
    for (g, body) in model.bodies.iter().enumerate() {
        // The gear's rigid motions on its own unknowns: the free nodes carry them one to one,
        // the bore's rotation is the hub's (1 when free); the bore does not translate.
        let shapes: [&dyn Fn(Point2<f64>) -> [f64; 2]; 3] =
            [&|p| [-p.y, p.x], &|_| [1.0, 0.0], &|_| [0.0, 1.0]];
        for (motion, shape) in shapes.iter().enumerate() {
            let mut v = vec![0.0; next];
            for (n, &p) in body.mesh.nodes.iter().enumerate() {
                for (axis, value) in shape(p).into_iter().enumerate() {
                    if let [(unknown, coefficient)] = maps[g][2 * n + axis][..] {
                        if Some(unknown) != hub_index[g] {
                            v[unknown] = coefficient * value;
                        }
                    }
                }
            }
            if motion == 0 {
                if let Some(hub) = hub_index[g] {
                    v[hub] = 1.0;
                }
            }
            rigid[g][motion] = v;
        }
    }
    let rotations = [rigid[0][0].clone(), rigid[1][0].clone()];
    let rigid = rigid.map(|motions| {
        motions.map(|v| {
            let mv = symmetric_product(&mass, &v);
            let norm = v.iter().zip(&mv).map(|(a, b)| a * b).sum::<f64>();
            (mv, norm)
        })
    });
    let mut tie_gradients = Vec::new();
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
        tie_gradients.push(b);
    }
    PairSystem {
        inertias,
        rigid,
        n: next,
        stiffness,
        mass,
        hubs: hub_index,
        rotations,
        maps,
        tie_gradients,
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
    // Γ²/(vᵀMv), Γ = φᵀMv, of the mode `shape` on the rigid motion (Mv, vᵀMv).
    let share = |shape: &[f64], (mv, norm): &(Vec<f64>, f64)| match *norm > 0.0 {
        true => {
            shape
                .iter()
                .zip(mv)
                .map(|(x, y)| x * y)
                .sum::<f64>()
                .powi(2)
                / norm
        }
        false => 0.0,
    };
    let modes = modes
        .iter()
        .zip(&compliance)
        .enumerate()
        .map(|(i, (m, c))| {
            let [driver, driven] = &system.rigid;
            let rotation_share = [share(&m.shape, &driver[0]), share(&m.shape, &driven[0])];
            let lateral_of =
                |g: &[(Vec<f64>, f64); 3]| share(&m.shape, &g[1]) + share(&m.shape, &g[2]);
            let lateral_share = [lateral_of(driver), lateral_of(driven)];
            let body = [
                rotation_share[0],
                rotation_share[1],
                lateral_share[0],
                lateral_share[1],
            ]
            .into_iter()
            .zip(BODY_MODE_KINDS)
            .max_by(|a, b| a.0.total_cmp(&b.0))
            .filter(|(s, _)| *s >= BODY_MODE_SHARE)
            .map_or("tooth/body", |(s, name)| {
                // Equal gears' lateral modes lie at one frequency and mix.
                match lateral_share[0].min(lateral_share[1]) >= 0.5 * s {
                    true if name.ends_with("lateral") => BOTH_LATERAL,
                    _ => name,
                }
            });
            PairMode {
                frequency_hz: m.frequency_hz,
                mesh_share: c / total,
                rotation_share,
                lateral_share,
                kind: if m.frequency_hz < RIGID_HZ {
                    "rigid"
                } else if i == mesh_mode {
                    "mesh"
                } else {
                    body
                },
            }
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

/// The mesh's own moving mass at one position ([`mesh_moving_mass`]).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct MeshMovingMass {
    /// m_d = 2T_d/δ̇² [kg]: the kinetic energy of the pair's deformation beyond the gears' rigid
    /// motions per unit rate of the rigid motions' approach along the line of action.
    pub mass: f64,
    /// The largest spread of the gears' rotations' approach over the active ties, relative to
    /// its mean (rigid rotations of involute flanks approach uniformly along the line of
    /// action: a check of the projection and the ties, round-off size; the sway shapes' part,
    /// the teeth riding on the rim band, is not uniform to round-off and is not in it).
    pub approach_spread: f64,
    /// The held driver hub's reaction over the load's torque on the driver: zero when the
    /// load does no work on the pair's rolling (a check of the rolling's sense, round-off
    /// size).
    pub held_reaction: f64,
}

/// The mass the mesh itself moves: a lumped model whose gears are rigid bodies (rotations, and
/// the rims' sway where it has it) joined by a massless mesh spring leaves
/// out the kinetic energy of the teeth's bending and the rims' local deformation, which in the
/// FE modal's mesh mode carry 0.2–0.5 % (driver held) and 0.6–1.9 % (both free) of its kinetic
/// energy on the paper pair and 24/40 and 4–12 % both free on a 17-tooth pinion with a thin rim
/// (beyond the gears' rigid rotations and translations; validation/frequencies). Its Rayleigh share
/// is m_d, with T = ½ (Σ rigid) + ½ m_d δ̇², δ the rigid motions' approach along the line of
/// action, so the lumped model gains the consistent mass term m_d g gᵀ (the distributed mass
/// of a spring, as m/3 of a uniform bar: Rayleigh, *Theory of Sound* §156).
///
/// The shape: the static response of the pair (both hubs free, the contact tied at the
/// position's loaded state under `torque`) to the d'Alembert loads of the mesh mode's rigid
/// part, M(c₁r₁ + r₂) with c₁ = (r_b1/r_b2) I₂/I₁ so that they do no work on the pair's rolling
/// r₁ − (r_b1/r_b2) r₂ (each gear carries its own inertia, the hubs no concentrated torque:
/// the body twist is as small as in the free mode). The driver's hub is held to fix the
/// rolling (the balanced load leaves it no reaction). Projected M-orthogonally onto each
/// gear's rigid rotation and, where `sway` gives a gear's [`SwayShapes`]
/// ([`ltca_sway_shapes`]: the lumped sway coordinate's own static shapes on this mesh), onto
/// those, u = R a + u_d: T_d ∝ u_dᵀMu_d = uᵀMu − aᵀRᵀMu, δ = bᵀ(R a) on the active ties (their
/// gap gradients), m_d = u_dᵀMu_d/δ². Without a gear's sway its translation stays in u_d, as
/// its compliance stays in the mesh stiffness. A static shape is the first Ritz vector: it
/// overstates m_d where the deforming parts' own modes lie near the mesh mode (a thin rim's
/// ring modes). The teeth stay on the rims while the flanks are apart: m_d moves with the
/// mesh deflection whether the mesh carries a force or not (a free flight across a backlash
/// carries its few grams of tooth inertia too).
pub fn mesh_moving_mass(
    model: &LtcaModel,
    (index, positions): (usize, usize),
    torque: f64,
    (material, density): (BodyMaterial, f64),
    sway: [Option<&SwayShapes>; 2],
) -> Result<MeshMovingMass, LtcaError> {
    let contacts = model.loaded_contacts(index, positions, torque)?;
    let system = assemble(model, &contacts, material, density, Hubs::BothFree);
    let n = system.n;
    let [driver_hub, _] = system.hubs;
    let driver_hub = driver_hub.expect("both hubs free");
    let [rb1, rb2] = [0, 1].map(|g| model.pair.gears[g].base_radius);
    let inertia = |g: usize| system.rigid[g][0].1;
    let c1 = rb1 / rb2 * inertia(1) / inertia(0);
    let load: Vec<f64> = (0..n)
        .map(|i| c1 * system.rigid[0][0].0[i] + system.rigid[1][0].0[i])
        .collect();
    let shape = FactorizedStiffness::new(n, system.stiffness.clone(), &[driver_hub])?.solve(&load);
    let mass_shape = symmetric_product(&system.mass, &shape);
    let held_reaction =
        (symmetric_product(&system.stiffness, &shape)[driver_hub] - load[driver_hub]).abs()
            / (c1 * inertia(0));
    // The motions projected out: each gear's rigid rotation, and its sway shapes where the
    // model sways (the lumped coordinate's own static shapes, mapped onto the pair's unknowns:
    // uniform translations would leave the body's graded part of the sway in u_d, counted
    // twice, and read the approach from a mass-averaged translation below the rim's).
    let mut motions: Vec<Vec<f64>> = system.rotations.to_vec();
    for (g, shapes) in sway.iter().enumerate() {
        for shape in shapes.iter().flat_map(|s| &s.shapes) {
            let mut v = vec![0.0; n];
            for (dof, value) in shape.iter().enumerate() {
                for &(unknown, coefficient) in &system.maps[g][dof] {
                    v[unknown] += coefficient * value;
                }
            }
            motions.push(v);
        }
    }
    let k = motions.len();
    // M v: the rotations' the assembly has, the sway shapes' here.
    let mass_motions: Vec<Vec<f64>> = (0..k)
        .map(|i| match i {
            0 | 1 => system.rigid[i][0].0.clone(),
            _ => symmetric_product(&system.mass, &motions[i]),
        })
        .collect();
    let dot = crate::fe::modal::lane_dot;
    let gram = nalgebra::DMatrix::from_fn(k, k, |i, j| dot(&motions[i], &mass_motions[j]));
    let projections = nalgebra::DVector::from_fn(k, |i, _| dot(&mass_motions[i], &shape));
    let coefficients = gram.lu().solve(&projections).ok_or_else(|| {
        LtcaError::Fe(crate::fe::FeError::Body(
            "the gears' rotations and sway shapes are not independent motions".into(),
        ))
    })?;
    let kinetic = dot(&shape, &mass_shape);
    let deformation = kinetic - coefficients.dot(&projections);
    // The approach of the motions projected out, on every active tie: all of them (δ), and
    // the rotations alone (the check).
    let approach_of = |count: usize| -> Vec<f64> {
        let mut displacement = vec![0.0; n];
        for (motion, c) in motions.iter().zip(coefficients.iter()).take(count) {
            for (x, v) in displacement.iter_mut().zip(motion) {
                *x += c * v;
            }
        }
        system
            .tie_gradients
            .iter()
            .map(|b| b.iter().map(|&(i, bi)| bi * displacement[i]).sum::<f64>())
            .collect()
    };
    let (approaches, rotations) = (approach_of(k), approach_of(2));
    if approaches.is_empty() {
        return Err(LtcaError::NoContact { position: index });
    }
    let mean = |a: &[f64]| a.iter().sum::<f64>() / a.len() as f64;
    let approach = mean(&approaches);
    let rotation_mean = mean(&rotations);
    let approach_spread = rotations
        .iter()
        .map(|a| (a / rotation_mean - 1.0).abs())
        .fold(0.0, f64::max);
    Ok(MeshMovingMass {
        mass: deformation / (approach * approach),
        approach_spread,
        held_reaction,
    })
}

/// Each gear body's sway shapes ([`super::body::sway_shapes`]) on the LTCA's own mesh of it,
/// its bore held: what [`mesh_moving_mass`] projects out where the lumped model lets a rim sway.
/// One factorization per body, both side by side.
pub fn ltca_sway_shapes(
    model: &LtcaModel,
    material: BodyMaterial,
) -> Result<[SwayShapes; 2], LtcaError> {
    let one = |g: usize| -> Result<SwayShapes, LtcaError> {
        let gear = &model.pair.gears[g];
        let mesh = &model.bodies[g].mesh;
        let face_width = gear.spec.face_width;
        let (stiffness, _) = super::body::bore_held_stiffness(mesh, material, face_width)?;
        Ok(super::body::sway_shapes(
            gear, mesh, &stiffness, face_width,
        )?)
    };
    let (first, second) = rayon::join(|| one(0), || one(1));
    Ok([first?, second?])
}
