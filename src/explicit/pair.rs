//! The meshing pair for explicit dynamics: two corotational Q8 bodies on rigid hubs, penalty
//! contact with Coulomb friction between every pair of flanks that can touch, central-difference
//! integration of the whole system, and its energy balance.
//!
//! # Hubs (seed paper §4: the bore nodes carry the drive and the load)
//! * Driver: every bore node follows the prescribed rotation θ₁(t) about its centre,
//!   x = c₁ + R(ψ₁ + θ₁(t)) X; the speed ramps linearly from rest to Ω over t_r:
//!   θ̇₁ = Ω min(t/t_r, 1).
//! * Driven: the bore nodes are slaved to a rigid hub rotating by φ(t) about c₂; the hub carries
//!   the bore nodes' inertia I_h = Σ mᵢ|Xᵢ|² and the load torque T(t) = T min(t/t_r, 1) against
//!   the rotation: I_h φ̈ = Σ (xᵢ − c₂) × fᵢ + T(t), fᵢ the net force on bore node i. The rest
//!   of the driven gear's inertia is in its FE nodes.
//!
//! Bearings are rigid (centres fixed).
//!
//! # Contact (segment-to-segment by Gauss points, two-pass, penalty; [`crate::contact`])
//! For every tooth pair that can engage in the scene, both the drive flanks (tooth-local left
//! flanks of both gears) and the back flanks (right flanks) are contact pairs. Each flank's
//! quadratic edges carry 4 Gauss points, and its tip corner one point more, that are slaves
//! against the other flank's quadratic edges, and vice versa (a slave point whose projection
//! falls beyond the end of the master flank is the other pass's: the master's tip corner is a
//! slave point there). A Gauss point that penetrates (g < 0) gets F_n = k_n(−g) along the
//! master normal and a Coulomb friction force along the master tangent by return mapping; the
//! force goes to the slave edge's three nodes by their shape functions at the point, the
//! reaction to the master edge's nodes by theirs at the projection — so the load moves
//! continuously along the flank as the contact point does, instead of jumping from node to node.
//! The penalty of a master edge is k_e = f_p · max diag K_e of its element (2D: K_e ∝ E·B
//! whatever the size), spread over the edge length: a Gauss point representing slave length
//! w·|x′| gets k_n = (k_e/L_e)·w|x′| — `penalty_factor` f_p; the stick stiffness is k_t = k_n.
//! Search: per step a flank pair is skipped when the spheres about its two flanks' middle
//! nodes, or else their bounding boxes, are apart by more than a quarter module; otherwise a
//! Gauss point outside the master flank's box (widened by that distance) is skipped, the others
//! find the nearest master chord, and only a point that is not clearly outside it — within the
//! edge's bulge |x_m − (x_a + x_b)/2| of the chord line, or inside — is projected (Newton) on
//! the quadratic edge. (Most points of a near pair are clear of contact: the two tests cut the
//! search from 81 to 27 µs per step at the 3000 rpm scene's mesh.)
//!
//! # Energy balance
//! E_kin + E_strain + E_damping + E_contact − W_ext = 0, with E_contact the work done by the
//! contact forces (penalty springs and friction), W_ext the work of the driver's hub (reactions
//! on the prescribed bore nodes) and of the load torque; work terms by the trapezoid rule.
//!
//! # A reduced far body ([`crate::explicit::far`])
//! With [`ExplicitPair::reduce_far_bodies`] each gear's coarse sectors are one reduced block
//! turning with the hub: the step's elements are the fine sectors' only, the block's interface
//! nodes are placed from its state after each drift and its internal nodes are not stepped.
//! The block's accelerations follow from the fine elements' forces on its interface: the
//! driver's hub turns it as prescribed (the hub's torque on it is in the driver's work), the
//! driven hub and the block are solved together (I_h above is then the bore nodes' inertia,
//! the block's own comes with it). Its kinetic, strain and damping terms join the account.

use nalgebra::{Point2, Rotation2, Vector2};
use std::time::Instant;

use crate::contact::{project_on_quadratic_edge, ContactLaw, FrictionState};
use crate::explicit::body::{ExplicitBody, ExplicitMaterial, ForceOutput};
use crate::explicit::far::{BlockCache, FarBlock, Lookup};
use crate::explicit::kicks;
use crate::explicit::lockstep::Lockstep;
use crate::explicit::reduced::{BlockScratch, BlockState, BlockSums, FrameMotion};
use crate::explicit::remesh::NodeTransfer;
use crate::fe::FeError;
use crate::geometry::engagement::ToothPair;
use crate::geometry::{GearPair, Placement, Side};
use crate::mesh::GearMesh;

/// One flank of one gear as a contact surface.
#[derive(Debug, Clone)]
pub struct Flank {
    pub gear: usize,
    pub tooth: usize,
    pub side: Side,
    /// Nodes, form point to tip corner.
    pub nodes: Vec<usize>,
    /// Quadratic edges (corner, mid-side, corner), ordered counter-clockwise around the body so
    /// the edge normal points out of it.
    pub edges: Vec<[usize; 3]>,
    /// Normal penalty stiffness of each edge as a master [N/m], and per unit slave length
    /// [N/m²] (the edge stiffness over the edge length).
    pub penalty: Vec<f64>,
    pub line_penalty: Vec<f64>,
    /// The tip corner as a slave point: the edge that ends there and the end's parameter
    /// (s = −1 or 1 after the orientation).
    pub tip_corner: (usize, f64),
    /// The middle node and a radius about it that holds the whole flank (reference geometry
    /// plus 5 % for deformation): two flanks whose spheres are apart are skipped with one
    /// distance instead of two bounding boxes.
    pub middle: usize,
    pub radius: f64,
}

impl Flank {
    /// [x_min, y_min, x_max, y_max] of the flank's nodes at positions `x` (its gear's).
    fn bounding_box(&self, x: &[f64]) -> [f64; 4] {
        self.nodes.iter().fold(
            [
                f64::INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
            ],
            |b, &n| {
                [
                    b[0].min(x[2 * n]),
                    b[1].min(x[2 * n + 1]),
                    b[2].max(x[2 * n]),
                    b[3].max(x[2 * n + 1]),
                ]
            },
        )
    }
}

/// Two flanks that can touch: `flanks[0]` on gear 1, `flanks[1]` on gear 2.
#[derive(Debug, Clone)]
pub struct FlankPair {
    pub flanks: [usize; 2],
    /// The teeth (gear 1, gear 2) the flanks belong to.
    pub teeth: (usize, usize),
    /// Drive flanks (true: tooth-local left flanks) or back flanks (right flanks).
    pub drive: bool,
}

impl FlankPair {
    /// A name for outputs: `drive_<t1>_<t2>` or `back_<t1>_<t2>`.
    pub fn name(&self) -> String {
        format!(
            "{}_{}_{}",
            if self.drive { "drive" } else { "back" },
            self.teeth.0,
            self.teeth.1
        )
    }
}

/// Gauss–Legendre points and weights on a slave edge, s ∈ [−1, 1] (4 points: the contact point
/// of two convex flanks is resolved to about a fifth of an edge).
const GAUSS_EDGE: [(f64, f64); 4] = [
    (-0.861_136_311_594_052_6, 0.347_854_845_137_453_85),
    (-0.339_981_043_584_856_26, 0.652_145_154_862_546_1),
    (0.339_981_043_584_856_26, 0.652_145_154_862_546_1),
    (0.861_136_311_594_052_6, 0.347_854_845_137_453_85),
];

/// Weight of the tip corner as a slave point, on the scale of [`GAUSS_EDGE`]'s (which sum to 2
/// per edge): the outermost Gauss point's. The Gauss points stop 7 % of an edge short of the
/// corner, so without it the corner of a tooth coming into mesh meets the mating flank
/// unresisted until the last Gauss point reaches it; the other pass skips points beyond the end
/// of its master flank and took the corner's load only once the corner had passed them, already
/// a few µm deep (≈ 0.9 mJ booked from nothing at each engagement at 1 mm flanks, 60 rpm).
const CORNER_WEIGHT: f64 = GAUSS_EDGE[3].1;

/// Quadratic edge shape functions at s: corner, mid-side, corner.
fn edge_shape(s: f64) -> [f64; 3] {
    [0.5 * s * (s - 1.0), 1.0 - s * s, 0.5 * s * (s + 1.0)]
}

/// Friction history of a flank pair: per pass, one state per slave Gauss point.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct PairHistory {
    passes: [Vec<SlaveState>; 2],
    /// Every state is at its default (the pair was apart at the last step): a pair that stays
    /// apart is not cleared again every step.
    cleared: bool,
}

/// Friction history of one slave Gauss point of a flank pair.
#[derive(Debug, Clone, Copy, Default, serde::Serialize, serde::Deserialize)]
struct SlaveState {
    friction: FrictionState,
}

/// The assembled pair.
pub struct ExplicitPair {
    pub pair: GearPair,
    pub meshes: [GearMesh; 2],
    pub bodies: [ExplicitBody; 2],
    pub placement: [Placement; 2],
    /// Whether each DOF integrates freely (false: bore DOFs, slaved to the hub).
    pub free: [Vec<bool>; 2],
    /// 1/m per DOF, zero on the bore DOFs (their motion comes from the hubs).
    inverse_mass: [Vec<f64>; 2],
    /// Driven hub inertia I_h = Σ_bore mᵢ|Xᵢ|² [kg·m²].
    pub hub_inertia: f64,
    pub flanks: Vec<Flank>,
    pub flank_pairs: Vec<FlankPair>,
    /// Tooth pairs (gear-1 tooth, gear-2 tooth) in contact pairs.
    pub tooth_pairs: Vec<(usize, usize)>,
    pub friction: f64,
    pub penalty_factor: f64,
    /// Per gear, the DOFs a step kicks after its serial middle, ascending: those of every
    /// flank's nodes (contact forces are added to them there, and the contact reads their
    /// velocities during the force phase) and of the bore nodes (the hubs read their forces).
    held_dofs: [Vec<usize>; 2],
    /// Per gear, the runs of the other DOFs, which each gear's thread kicks in the force
    /// phase right after its element forces ([`PairIntegrator::step`]).
    body_only_runs: [Vec<std::ops::Range<usize>>; 2],
    /// Per gear, its far body as a reduced block ([`ExplicitPair::reduce_far_bodies`]).
    pub far: [Option<FarGear>; 2],
}

/// A gear whose far body is a reduced block ([`crate::explicit::far`]).
pub struct FarGear {
    pub block: FarBlock,
    /// The fine sectors' elements, the step's (the whole body stays the pair's: its masses,
    /// its stable step).
    pub fine: ExplicitBody,
    /// The runs of DOFs the drift moves: all but the block's internal nodes'.
    moving_runs: Vec<std::ops::Range<usize>>,
    /// Per node: not a node of the block's (interface or internal), so its kinetic energy is
    /// the nodes' and not the block's.
    counted: Vec<bool>,
}

/// The DOFs of the nodes `held` (any order, repeats allowed) among `dofs`, ascending, and the
/// runs of the DOFs between them.
fn split_dofs(
    dofs: usize,
    held: impl Iterator<Item = usize>,
) -> (Vec<usize>, Vec<std::ops::Range<usize>>) {
    let mut is_held = vec![false; dofs];
    for n in held {
        is_held[2 * n] = true;
        is_held[2 * n + 1] = true;
    }
    let held_dofs: Vec<usize> = (0..dofs).filter(|&d| is_held[d]).collect();
    let mut runs = Vec::new();
    let mut start = 0;
    for &d in held_dofs.iter().chain(std::iter::once(&dofs)) {
        if d > start {
            runs.push(start..d);
        }
        start = d + 1;
    }
    (held_dofs, runs)
}

/// Shape of the ramps from zero.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Ramp {
    /// r(t) = t/t_r (the seed paper's): the acceleration jumps at 0 and t_r.
    #[default]
    Linear,
    /// r(t) = (1 − cos(πt/t_r))/2: no jump in acceleration, so the ramp excites the mesh mode
    /// far less (used for quasi-static comparisons).
    Cosine,
}

/// How a run starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Start {
    /// Both gears at rest; the driver's speed ramps up with the load (the seed paper's).
    #[default]
    Rest,
    /// Both gears already turning at the kinematic speeds (rigid rotation); only the load
    /// ramps. No spin-up: the driven gear's inertia torque I₂Ω₂ṙ(t), which with mass scaling
    /// rivals the load, is not there to ring the mesh mode.
    AtSpeed,
}

/// Loads and drive of a run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drive {
    /// Driver speed Ω [rad/s] after the ramp.
    pub driver_speed: f64,
    /// Load torque T on the driven gear [N·m] after the ramp.
    pub load_torque: f64,
    /// Ramp time t_r of the load torque, and of the speed when starting from rest [s].
    pub ramp_time: f64,
    pub ramp: Ramp,
    pub start: Start,
    /// Driver rotation at t = 0 from the placement (tooth 0 at the pitch point) [rad].
    pub start_rotation: f64,
}

impl Drive {
    /// Ramp factor r(t) ∈ [0, 1], its integral ∫₀ᵗ r and its derivative.
    fn ramp(&self, t: f64) -> (f64, f64, f64) {
        let tr = self.ramp_time;
        if t >= tr {
            // Both shapes have mean ½ over the ramp.
            return (1.0, t - 0.5 * tr, 0.0);
        }
        match self.ramp {
            Ramp::Linear => (t / tr, 0.5 * t * t / tr, 1.0 / tr),
            Ramp::Cosine => {
                let w = std::f64::consts::PI / tr;
                (
                    0.5 * (1.0 - (w * t).cos()),
                    0.5 * (t - (w * t).sin() / w),
                    0.5 * w * (w * t).sin(),
                )
            }
        }
    }

    /// Driver rotation θ₁, speed and acceleration at time t.
    pub fn driver_motion(&self, t: f64) -> (f64, f64, f64) {
        let (r, integral, rate) = match self.start {
            Start::Rest => self.ramp(t),
            Start::AtSpeed => (1.0, t, 0.0),
        };
        let w = self.driver_speed;
        (self.start_rotation + w * integral, w * r, w * rate)
    }

    pub fn load_torque_at(&self, t: f64) -> f64 {
        self.load_torque * self.ramp(t).0
    }
}

/// The state of the pair.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PairState {
    pub time: f64,
    pub x: [Vec<f64>; 2],
    pub v: [Vec<f64>; 2],
    pub a: [Vec<f64>; 2],
    /// Driven hub rotation φ from its placement [rad] (negative: the driven gear turns
    /// clockwise), rate and acceleration.
    pub hub: [f64; 3],
    /// Each gear's far block's state, where it is reduced ([`ExplicitPair::reduce_far_bodies`];
    /// the block's internal nodes in x and v are then not kept up).
    #[serde(default)]
    pub blocks: [Option<BlockState>; 2],
}

/// Energy account [J].
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PairEnergy {
    pub kinetic: f64,
    pub strain: f64,
    /// Work taken out by damping: the bodies' stiffness damping and mass damping (dissipation,
    /// ≥ 0) and the mesh dashpot's work on the driven hub, −∫T_d φ̇₂ dt = ∫c_t δ̇ φ̇₂ dt with δ the
    /// angular DTE. The dashpot acts against the kinematic motion, which the driver supplies, so
    /// beside its dissipation c_t δ̇² this holds the exchange c_t δ̇ φ̇₂,kin: negative while the
    /// mean DTE grows (the ramp; with relief, tens of mJ).
    pub damping: f64,
    /// Work done on the contact forces (penalty springs and friction; friction's share is its
    /// dissipation).
    pub contact: f64,
    /// Work of the driver's hub and the load torque, plus the energy of the initial state (the
    /// kinetic energy of a start at speed, as work done before t = 0).
    pub external_work: f64,
    /// The work the pair transmits by design: ∫ T(t) |φ̇₂,kin| dt, the load torque times the
    /// driven gear's kinematic rotation (prescribed motion only, so an unstable run cannot
    /// inflate it). Under load the driver puts this much in and the load takes it out, while the
    /// net external work stays small; errors of the account are measured against it too.
    pub transmitted_work: f64,
    /// Kinetic and strain energy the remeshing of a windowed run added at its switches (the
    /// state carried to the next window's mesh, [`crate::explicit::remesh`]; negative: taken
    /// out, the switched teeth's ringing the coarser mesh cannot hold).
    #[serde(default)]
    pub remeshing: f64,
}

impl PairEnergy {
    /// kinetic + strain + damping + contact − external work − remeshing: zero for an exact
    /// integrator.
    pub fn balance(&self) -> f64 {
        self.kinetic + self.strain + self.damping + self.contact
            - self.external_work
            - self.remeshing
    }
}

/// Contact output of one step.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct ContactOutput {
    /// Resultant contact force on the driven gear (global frame) [N].
    #[serde(with = "vector2_as_array")]
    pub force_on_driven: Vector2<f64>,
    /// Moment of the contact forces on the driven gear about its centre [N·m] (counter-clockwise
    /// positive; the load torque balances it in steady state).
    pub moment_on_driven: f64,
    /// Magnitude of the contact force on the driven gear per flank pair [N].
    pub pair_forces: Vec<f64>,
    /// Slave nodes in contact.
    pub active: usize,
    /// Deepest penetration [m].
    pub max_penetration: f64,
    /// An upper bound of the highest frequency of the closed penalty springs on their own
    /// [rad/s] ([`closed_springs_omega`]): cheap at every step, it tells where the contact has
    /// stiffened, so that a [`crate::explicit::scene::TimeStep::Coupled`] run measures the
    /// pair's own stable step there. (As a bound of the pair's ω_max it is no use: Weyl's
    /// ω² ≤ ω_bodies² + this² lies above the contact springs' worst-case bound on the
    /// paper's scenes.)
    #[serde(default)]
    pub stiffest_spring_omega: f64,
    /// Whether to collect the closed springs and their bound (a run on the pair's own step).
    #[serde(default)]
    pub track_springs: bool,
    /// The closed springs of this step, and a per-node scratch for their bound.
    #[serde(skip)]
    pub springs: Vec<ClosedSpring>,
    #[serde(skip)]
    node_sums: [Vec<f64>; 2],
    /// Per flank pair: near enough to be searched at this step (contact forces can be
    /// non-zero only on the flanks of these pairs).
    pub searched: Vec<bool>,
}

impl ExplicitPair {
    /// Builds the bodies (tooth-local reference frames, shared element prototypes), hubs and
    /// contact surfaces. `tooth_pairs` are the (gear-1, gear-2) teeth that can engage; both must
    /// be fine teeth of the meshes.
    pub fn new(
        pair: &GearPair,
        meshes: [GearMesh; 2],
        material: ExplicitMaterial,
        tooth_pairs: Vec<(usize, usize)>,
        friction: f64,
        penalty_factor: f64,
    ) -> Result<Self, FeError> {
        let body = |g: usize| {
            let mut m = material;
            m.thickness = pair.gears[g].spec.face_width;
            ExplicitBody::with_symmetry(
                &meshes[g].nodes,
                &meshes[g].elements,
                m,
                Some(pair.gears[g].teeth() as usize),
            )
        };
        let bodies = [body(0)?, body(1)?];
        let placement = pair.mesh_placement();
        let free: [Vec<bool>; 2] = std::array::from_fn(|g| {
            let mut free = vec![true; 2 * meshes[g].nodes.len()];
            for &n in &meshes[g].bore_nodes {
                free[2 * n] = false;
                free[2 * n + 1] = false;
            }
            free
        });
        let inverse_mass = std::array::from_fn(|g| inverse_masses(&bodies[g], &free[g]));
        let hub_inertia = hub_inertia_of(&meshes[1], &bodies[1]);
        let mut flanks = Vec::new();
        let mut flank_pairs = Vec::new();
        let mut add_pair = |t1: usize, t2: usize, side: Side, drive: bool| {
            let a = flanks.len();
            for (g, tooth) in [(0, t1), (1, t2)] {
                let teeth = pair.gears[g].teeth() as usize;
                flanks.push(make_flank(
                    &meshes[g],
                    &bodies[g],
                    (g, teeth, tooth),
                    side,
                    penalty_factor,
                ));
            }
            flank_pairs.push(FlankPair {
                flanks: [a, a + 1],
                teeth: (t1, t2),
                drive,
            });
        };
        for &(t1, t2) in &tooth_pairs {
            add_pair(t1, t2, Side::Left, true);
            // The back flank of gear-1 tooth t1 faces the back flank of the gear-2 tooth behind
            // it ([`ToothPair::back_flank_partner`]; indices mod z₂ keep the signed relation).
            let (_, back) = ToothPair {
                driver: t1 as i64,
                driven: t2 as i64,
            }
            .back_flank_partner()
            .indices(pair);
            add_pair(t1, back, Side::Right, false);
        }
        let split: [_; 2] = std::array::from_fn(|g| {
            let flank_nodes = flanks
                .iter()
                .filter(|f: &&Flank| f.gear == g)
                .flat_map(|f| f.nodes.iter().copied());
            let bore = meshes[g].bore_nodes.iter().copied();
            split_dofs(2 * meshes[g].nodes.len(), flank_nodes.chain(bore))
        });
        let [(held0, runs0), (held1, runs1)] = split;
        Ok(ExplicitPair {
            pair: pair.clone(),
            meshes,
            bodies,
            placement,
            free,
            inverse_mass,
            hub_inertia,
            flanks,
            flank_pairs,
            tooth_pairs,
            friction,
            penalty_factor,
            held_dofs: [held0, held1],
            body_only_runs: [runs0, runs1],
            far: [None, None],
        })
    }

    pub fn elements(&self) -> usize {
        self.bodies.iter().map(|b| b.elements.len()).sum()
    }

    /// The elements a step computes: the fine sectors' only where the far body is reduced.
    pub fn stepped_elements(&self) -> usize {
        (0..2).map(|g| self.force_body(g).elements.len()).sum()
    }

    /// The body whose element forces a step computes for gear `g`.
    fn force_body(&self, g: usize) -> &ExplicitBody {
        self.far[g]
            .as_ref()
            .map_or(&self.bodies[g], |far| &far.fine)
    }

    /// Each gear's coarse sectors as one reduced block ([`crate::explicit::far`]), from
    /// `cache` where a block of the same pattern of fine teeth fits; on the masses as they are
    /// (scale them first). A gear whose teeth are all fine keeps its full body. Fails where a
    /// flank's node would be the block's.
    pub fn reduce_far_bodies(&mut self, cache: &mut BlockCache) -> Result<(), FeError> {
        let lookups: [Lookup; 2] = std::array::from_fn(|g| {
            let teeth = self.pair.gears[g].teeth() as usize;
            cache.lookup(g, teeth, &self.meshes[g], &self.bodies[g].mass)
        });

        // The blocks to build, the two gears' side by side (each a few seconds: its modes).
        let build = |g: usize| match &lookups[g] {
            Lookup::Build(request) => {
                let body = &self.bodies[g];
                let (cutoff, bound) = (cache.cutoff, cache.rate_bounds[g]);
                Some(request.build(&self.meshes[g], &body.mass, &body.material, cutoff, bound))
            }
            _ => None,
        };
        let (built0, built1) = rayon::join(|| build(0), || build(1));
        let mut built = [built0, built1];
        let mut blocks: [Option<FarBlock>; 2] = [None, None];
        for (g, lookup) in lookups.into_iter().enumerate() {
            blocks[g] = match (lookup, built[g].take()) {
                (Lookup::Found(block), _) => Some(block),
                (Lookup::Build(request), Some(block)) => {
                    Some(cache.insert(request, block?, &self.bodies[g].mass))
                }
                _ => None,
            };
        }
        for (g, block) in blocks.into_iter().enumerate() {
            let Some(block) = block else {
                continue;
            };
            let (mesh, body) = (&self.meshes[g], &self.bodies[g]);
            let teeth = self.pair.gears[g].teeth() as usize;
            let nodes = mesh.nodes.len();
            let mut counted = vec![true; nodes];
            block
                .interface
                .iter()
                .chain(&block.internal)
                .for_each(|&n| counted[n] = false);
            let flank_nodes: Vec<usize> = self
                .flanks
                .iter()
                .filter(|f| f.gear == g)
                .flat_map(|f| f.nodes.iter().copied())
                .collect();
            if let Some(&n) = flank_nodes.iter().find(|&&n| !counted[n]) {
                return Err(FeError::Remeshing(format!(
                    "gear {}'s node {n} is on a contact flank and in its far block: the far \
                     body cannot be reduced on this mesh (fe.far_body = \"full\")",
                    g + 1
                )));
            }
            let fine_elements: Vec<[usize; 8]> = mesh
                .elements
                .iter()
                .zip(&mesh.element_fine)
                .filter(|(_, &fine)| fine)
                .map(|(e, _)| *e)
                .collect();
            let fine = ExplicitBody::with_symmetry(
                &mesh.nodes,
                &fine_elements,
                body.material,
                Some(teeth),
            )?;
            let dofs = 2 * nodes;
            let (_, moving_runs) = split_dofs(dofs, block.internal.iter().copied());
            let bore = mesh.bore_nodes.iter().copied();
            let (held, _) = split_dofs(dofs, flank_nodes.iter().copied().chain(bore.clone()));
            let stepped_apart = flank_nodes
                .iter()
                .copied()
                .chain(bore)
                .chain(block.interface.iter().copied())
                .chain(block.internal.iter().copied());
            let (_, runs) = split_dofs(dofs, stepped_apart);
            self.held_dofs[g] = held;
            self.body_only_runs[g] = runs;
            self.far[g] = Some(FarGear {
                block,
                fine,
                moving_runs,
                counted,
            });
        }
        Ok(())
    }

    /// Builds into `cache` gear `g`'s far block of this model's mesh (the model of a window
    /// whose blocks a checkpoint names: [`crate::explicit::far::BlockSeed`]), leaving the
    /// model as it is.
    pub fn seed_far_block(&self, g: usize, cache: &mut BlockCache) -> Result<(), FeError> {
        let teeth = self.pair.gears[g].teeth() as usize;
        let (mesh, body) = (&self.meshes[g], &self.bodies[g]);
        if let Lookup::Build(request) = cache.lookup(g, teeth, mesh, &body.mass) {
            let (cutoff, bound) = (cache.cutoff, cache.rate_bounds[g]);
            let block = request.build(mesh, &body.mass, &body.material, cutoff, bound)?;
            cache.insert(request, block, &body.mass);
        }
        Ok(())
    }

    /// Whether each far block's Coriolis couplings hold at the hubs' `rates` [rad/s]
    /// ([`crate::explicit::far::RATE_BOUND_FACTOR`]); a message that says what to change if
    /// not.
    pub fn far_rates_hold(&self, rates: [f64; 2]) -> Result<(), String> {
        for (g, far) in self.far.iter().enumerate() {
            let Some(far) = far else { continue };
            let bound = far.block.block.rate_bound();
            if rates[g].abs() > bound {
                return Err(format!(
                    "gear {} turns at {:.1} rad/s, above the {bound:.1} rad/s its reduced far \
                     block keeps its Coriolis couplings for (sized for {} times its nominal \
                     speed): run it with fe.far_body = \"full\"",
                    g + 1,
                    rates[g].abs(),
                    crate::explicit::far::RATE_BOUND_FACTOR
                ));
            }
        }
        Ok(())
    }

    /// The frame (centre, angle, rate) of gear `g`'s far block with its hub at `motion`
    /// ([angle, rate, …]).
    fn block_frame(&self, g: usize, far: &FarGear, motion: [f64; 3]) -> (Point2<f64>, f64, f64) {
        let placement = &self.placement[g];
        (
            placement.centre,
            far.block.frame_angle(placement.rotation, motion[0]),
            motion[1],
        )
    }

    /// `state` with every far block's nodes written from its block (the step leaves the
    /// internal nodes where they were): for what reads the whole mesh.
    pub fn expanded(&self, state: &PairState, driver_motion: [f64; 3]) -> PairState {
        let mut full = state.clone();
        for g in 0..2 {
            if let (Some(far), Some(block)) = (&self.far[g], &state.blocks[g]) {
                let motion = if g == 0 { driver_motion } else { state.hub };
                let frame = self.block_frame(g, far, motion);
                far.block
                    .expand(block, frame, &mut full.x[g], &mut full.v[g]);
            }
        }
        full
    }

    /// Multiplies every nodal mass and the driven hub's inertia by `factor` (mass scaling): all
    /// natural frequencies, and the stable step's inverse, fall by √factor.
    pub fn scale_mass(&mut self, factor: f64) {
        assert!(
            self.far.iter().all(Option::is_none),
            "masses are scaled before the far bodies are reduced"
        );
        for g in 0..2 {
            self.bodies[g].mass.iter_mut().for_each(|m| *m *= factor);
            self.inverse_mass[g].iter_mut().for_each(|w| *w /= factor);
        }
        self.hub_inertia *= factor;
    }

    /// Per-element mass scaling to the stable steps `steps` [s] (one per gear): each element's
    /// lumped masses times sₑ = max(1, (T_g/Δtₑ)²) ([`ExplicitPair::element_mass_factors`]),
    /// so that by Irons' element bound no element holds its body's stable step below T_g; the
    /// inverse masses and the driven hub's inertia follow. Where uniform scaling
    /// ([`ExplicitPair::scale_mass`]) multiplies the mass of the large, slow body elements as
    /// much as that of the small flank elements that set the step, this puts the mass where
    /// the step is made (the steps for an inertia budget: [`ExplicitPair::mass_scaling_steps`]).
    /// Returns each gear's least and largest factor.
    pub fn scale_mass_to_steps(&mut self, steps: [f64; 2]) -> [[f64; 2]; 2] {
        assert!(
            self.far.iter().all(Option::is_none),
            "masses are scaled before the far bodies are reduced"
        );
        std::array::from_fn(|g| {
            let factors = self.element_mass_factors(g, steps[g]);
            self.bodies[g].set_element_mass_factors(&factors);
            self.inverse_mass[g] = inverse_masses(&self.bodies[g], &self.free[g]);
            if g == 1 {
                self.hub_inertia = hub_inertia_of(&self.meshes[1], &self.bodies[1]);
            }
            let least = factors.iter().copied().fold(f64::INFINITY, f64::min);
            [least, factors.iter().copied().fold(1.0, f64::max)]
        })
    }

    /// The mass factor of each element of gear `g` that raises its own stable step to `step`:
    /// max(1, (step/Δtₑ)²), Δtₑ at the material's density
    /// ([`ExplicitBody::element_critical_steps`]).
    pub fn element_mass_factors(&self, g: usize, step: f64) -> Vec<f64> {
        self.bodies[g]
            .element_critical_steps()
            .iter()
            .map(|dt| (step / dt).powi(2).max(1.0))
            .collect()
    }

    /// For each gear the step T_g at which [`ExplicitPair::scale_mass_to_steps`] raises its
    /// polar inertia by exactly `factor` (at the masses as built): the root of
    /// Σₑ Iₑ max(1, (T/Δtₑ)²) = factor · Σₑ Iₑ, Iₑ = Σₖ mₑ,ₖ |Xₖ|² the element's share of
    /// the inertia about the gear's centre ([`ExplicitPair::inertia`] element by element), by
    /// bisection between √factor · min Δtₑ (uniform scaling's element step, where the left side
    /// is at most the right) and √factor · max Δtₑ (where it is at least; the left side grows
    /// with T). Each gear's inertia is then uniform scaling's, and so is the rigid gears' mesh
    /// mode; the pair's step is bounded by the smaller T_g.
    pub fn mass_scaling_steps(&self, factor: f64) -> [f64; 2] {
        std::array::from_fn(|g| {
            let body = &self.bodies[g];
            let steps = body.element_critical_steps();
            let inertias: Vec<f64> = (0..body.elements.len())
                .map(|e| {
                    let m = body.element_masses(e);
                    body.elements[e]
                        .iter()
                        .zip(m)
                        .map(|(&n, m)| m * self.meshes[g].nodes[n].coords.norm_squared())
                        .sum()
                })
                .collect();
            let budget = factor * inertias.iter().sum::<f64>();
            let inertia_at = |t: f64| -> f64 {
                steps
                    .iter()
                    .zip(&inertias)
                    .map(|(dt, i)| i * (t / dt).powi(2).max(1.0))
                    .sum()
            };
            let root = factor.max(1.0).sqrt();
            let (mut lo, mut hi) = (
                root * steps.iter().copied().fold(f64::INFINITY, f64::min),
                root * steps.iter().copied().fold(0.0, f64::max),
            );
            for _ in 0..100 {
                let mid = 0.5 * (lo + hi);
                if inertia_at(mid) > budget {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            lo
        })
    }

    /// Inverse nodal masses of gear `g` per DOF, zero on the bore (what the integrator divides
    /// the forces by).
    pub fn inverse_mass(&self, g: usize) -> &[f64] {
        &self.inverse_mass[g]
    }

    /// Polar moment of inertia of gear `g` (body and hub) about its centre [kg m²]:
    /// Σ m_i |X_i|² of the lumped nodal masses.
    pub fn inertia(&self, g: usize) -> f64 {
        self.meshes[g]
            .nodes
            .iter()
            .zip(&self.bodies[g].mass)
            .map(|(p, m)| m * p.coords.norm_squared())
            .sum()
    }

    /// [`ExplicitPair::inertia`] of the driven gear.
    pub fn driven_inertia(&self) -> f64 {
        self.inertia(1)
    }

    /// The driven gear's kinematic hub rotation for driver rotation θ₁: −(z₁/z₂) θ₁.
    pub fn kinematic_hub_rotation(&self, driver_rotation: f64) -> f64 {
        -(self.pair.gears[0].teeth() as f64) / self.pair.gears[1].teeth() as f64 * driver_rotation
    }

    /// Unloaded state at t = 0 of `drive`: the driver turned by its start rotation from the
    /// placement (tooth 0 of each gear at the pitch point), the driven gear at its kinematic
    /// rotation; at rest, or turning rigidly at the kinematic speeds ([`Start::AtSpeed`]).
    pub fn initial_state(&self, drive: &Drive) -> PairState {
        let driver_rotation = drive.start_rotation;
        let driver_rate = match drive.start {
            Start::Rest => 0.0,
            Start::AtSpeed => drive.driver_speed,
        };
        let rates = [driver_rate, self.kinematic_hub_rotation(driver_rate)];
        let hub = self.kinematic_hub_rotation(driver_rotation);
        let x = std::array::from_fn(|g| {
            let placement = Placement {
                centre: self.placement[g].centre,
                rotation: self.placement[g].rotation + if g == 0 { driver_rotation } else { hub },
            };
            self.meshes[g]
                .nodes
                .iter()
                .flat_map(|p| {
                    let q = placement.to_global(p);
                    [q.x, q.y]
                })
                .collect::<Vec<f64>>()
        });
        // v = ω ẑ × (x − c) of the rigid rotation.
        let v = std::array::from_fn(|g| {
            let (c, w) = (self.placement[g].centre, rates[g]);
            x[g].chunks_exact(2)
                .flat_map(|p| [-w * (p[1] - c.y), w * (p[0] - c.x)])
                .collect::<Vec<f64>>()
        });
        let zeros = |g: usize| vec![0.0; 2 * self.meshes[g].nodes.len()];
        PairState {
            time: 0.0,
            x,
            v,
            a: [zeros(0), zeros(1)],
            hub: [hub, rates[1], 0.0],
            // At rest in the hub frame: the rigid rotation is the frame's.
            blocks: std::array::from_fn(|g| self.far[g].as_ref().map(|f| f.block.block.rest())),
        }
    }

    /// Sets the bore nodes of gear `g` on a rigid rotation (from the placement) given as
    /// `[angle, rate, acceleration]`; writes the bore DOFs of that gear's x, v, a.
    fn place_bore(&self, g: usize, x: &mut [f64], v: &mut [f64], a: &mut [f64], motion: [f64; 3]) {
        let [angle, rate, accel] = motion;
        let placement = &self.placement[g];
        let rotation = Rotation2::new(placement.rotation + angle);
        for &n in &self.meshes[g].bore_nodes {
            let r = rotation * self.meshes[g].nodes[n].coords;
            let p = placement.centre + r;
            x[2 * n] = p.x;
            x[2 * n + 1] = p.y;
            // v = ω ẑ × r, a = α ẑ × r − ω² r
            v[2 * n] = -rate * r.y;
            v[2 * n + 1] = rate * r.x;
            a[2 * n] = -accel * r.y - rate * rate * r.x;
            a[2 * n + 1] = accel * r.x - rate * rate * r.y;
        }
    }

    /// Contact forces at positions `x` into `force` (added), with the friction history and
    /// slip from the velocities `v` over `dt` (per gear; only the flanks' nodes are read).
    fn contact_forces(
        &self,
        x: [&[f64]; 2],
        v: [&[f64]; 2],
        dt: f64,
        history: &mut [PairHistory],
        force: &mut [Vec<f64>; 2],
        out: &mut ContactOutput,
    ) {
        out.force_on_driven = Vector2::zeros();
        out.moment_on_driven = 0.0;
        let driven_centre = self.placement[1].centre;
        out.pair_forces.clear();
        out.pair_forces.resize(self.flank_pairs.len(), 0.0);
        out.searched.clear();
        out.searched.resize(self.flank_pairs.len(), false);
        out.active = 0;
        out.max_penetration = 0.0;
        out.springs.clear();
        let reject = 0.25 * self.pair.gears[0].module();
        for (index, fp) in self.flank_pairs.iter().enumerate() {
            let node = |f: usize, n: usize| {
                let x = x[self.flanks[f].gear];
                Point2::new(x[2 * n], x[2 * n + 1])
            };
            let [f1, f2] = fp.flanks.map(|f| &self.flanks[f]);
            let spheres_apart = (node(fp.flanks[0], f1.middle) - node(fp.flanks[1], f2.middle))
                .norm()
                > f1.radius + f2.radius + reject;
            let apart = spheres_apart || {
                let boxes = [f1, f2].map(|flank| flank.bounding_box(x[flank.gear]));
                (boxes[0][0] - boxes[1][2])
                    .max(boxes[1][0] - boxes[0][2])
                    .max(boxes[0][1] - boxes[1][3])
                    .max(boxes[1][1] - boxes[0][3])
                    > reject
            };
            let pair_history = &mut history[index];
            if apart {
                if !pair_history.cleared {
                    for pass in &mut pair_history.passes {
                        pass.iter_mut().for_each(|s| *s = SlaveState::default());
                    }
                    pair_history.cleared = true;
                }
                continue;
            }
            pair_history.cleared = false;
            out.searched[index] = true;
            let mut on_driven = Vector2::zeros();
            for pass in 0..2 {
                let (slave, master) = (
                    &self.flanks[fp.flanks[pass]],
                    &self.flanks[fp.flanks[1 - pass]],
                );
                let (sg, mg) = (slave.gear, master.gear);
                let slots = &mut pair_history.passes[pass];
                let point = |g: usize, n: usize| Point2::new(x[g][2 * n], x[g][2 * n + 1]);
                let velocity = |g: usize, n: usize| Vector2::new(v[g][2 * n], v[g][2 * n + 1]);
                // The master flank's bounding box, widened by the rejection distance: slave
                // points outside it cannot be in contact.
                let [x_lo, y_lo, x_hi, y_hi] = master.bounding_box(x[mg]);
                let near = [x_lo - reject, y_lo - reject, x_hi + reject, y_hi + reject];
                let corner_slot = slave.edges.len() * GAUSS_EDGE.len();
                for (se, slave_edge) in slave.edges.iter().enumerate() {
                    let ends = [
                        point(sg, slave_edge[0]),
                        point(sg, slave_edge[1]),
                        point(sg, slave_edge[2]),
                    ];
                    let corner =
                        (se == slave.tip_corner.0).then_some((slave.tip_corner.1, CORNER_WEIGHT));
                    for (q, &(s_gauss, w_gauss)) in GAUSS_EDGE.iter().chain(&corner).enumerate() {
                        let shape = edge_shape(s_gauss);
                        let p = Point2::from(
                            ends[0].coords * shape[0]
                                + ends[1].coords * shape[1]
                                + ends[2].coords * shape[2],
                        );
                        let slot = if q < GAUSS_EDGE.len() {
                            &mut slots[se * GAUSS_EDGE.len() + q]
                        } else {
                            &mut slots[corner_slot]
                        };
                        if p.x < near[0] || p.y < near[1] || p.x > near[2] || p.y > near[3] {
                            *slot = SlaveState::default();
                            continue;
                        }
                        // Nearest master chord.
                        let mut best = (f64::INFINITY, 0);
                        for (e, edge) in master.edges.iter().enumerate() {
                            let (a, b) = (point(mg, edge[0]), point(mg, edge[2]));
                            let ab = b - a;
                            let t = ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
                            let d = (p - (a + ab * t)).norm_squared();
                            if d < best.0 {
                                best = (d, e);
                            }
                        }
                        let edge = master.edges[best.1];
                        // The quadratic edge x(s) = chord(s) + (1 − s²)(x_m − (x_a + x_b)/2)
                        // stays within |x_m − (x_a + x_b)/2| of its chord line: a point farther
                        // than that on the outer side has a positive gap (no Newton needed).
                        let nodes = edge.map(|n| point(mg, n));
                        let [a, m, b] = nodes;
                        let chord = b - a;
                        let outward = Vector2::new(chord.y, -chord.x) / chord.norm();
                        let bulge = (m - Point2::from((a.coords + b.coords) * 0.5)).norm();
                        if (p - a).dot(&outward) > bulge {
                            *slot = SlaveState::default();
                            continue;
                        }
                        let proj = project_on_quadratic_edge(&p, &nodes);
                        // Off the ends of the master flank the projection clamps: no contact
                        // there (corner contact is the other pass's).
                        let at_end = (best.1 == 0 && proj.parameter <= -1.0)
                            || (best.1 == master.edges.len() - 1 && proj.parameter >= 1.0);
                        if proj.gap >= 0.0 || at_end || proj.gap < -reject {
                            *slot = SlaveState::default();
                            continue;
                        }
                        // Penalty of this Gauss point: the master edge's line stiffness times
                        // the slave length it represents.
                        let tangent_slave = ends[0].coords * (s_gauss - 0.5)
                            - ends[1].coords * (2.0 * s_gauss)
                            + ends[2].coords * (s_gauss + 0.5);
                        let length = w_gauss * tangent_slave.norm();
                        let stiffness = master.line_penalty[best.1] * length;
                        let law = ContactLaw {
                            normal_stiffness: stiffness,
                            tangential_stiffness: stiffness,
                            friction: self.friction,
                        };
                        let slave_velocity = slave_edge
                            .iter()
                            .zip(shape)
                            .fold(Vector2::zeros(), |acc, (&n, w)| acc + velocity(sg, n) * w);
                        let master_velocity = edge
                            .iter()
                            .zip(proj.weights)
                            .fold(Vector2::zeros(), |acc, (&n, w)| acc + velocity(mg, n) * w);
                        let slip = (slave_velocity - master_velocity).dot(&proj.tangent) * dt;
                        let (fn_, ft) = law.forces(proj.gap, slip, &mut slot.friction);
                        let f = proj.normal * fn_ + proj.tangent * ft;
                        for (&n, w) in slave_edge.iter().zip(shape) {
                            force[sg][2 * n] += w * f.x;
                            force[sg][2 * n + 1] += w * f.y;
                        }
                        for (&n, w) in edge.iter().zip(proj.weights) {
                            force[mg][2 * n] -= w * f.x;
                            force[mg][2 * n + 1] -= w * f.y;
                        }
                        let f_driven = if sg == 1 { f } else { -f };
                        on_driven += f_driven;
                        let arm = p - driven_centre;
                        out.moment_on_driven += arm.x * f_driven.y - arm.y * f_driven.x;
                        out.active += 1;
                        out.max_penetration = out.max_penetration.max(-proj.gap);
                        if !out.track_springs {
                            continue;
                        }
                        let mut nodes = [(0, 0, 0.0); 6];
                        for (k, (&n, w)) in slave_edge.iter().zip(shape).enumerate() {
                            nodes[k] = (sg, n, w.abs());
                        }
                        for (k, (&n, w)) in edge.iter().zip(proj.weights).enumerate() {
                            nodes[3 + k] = (mg, n, w.abs());
                        }
                        out.springs.push(ClosedSpring {
                            root_stiffness: stiffness.sqrt(),
                            nodes,
                        });
                    }
                }
            }
            out.force_on_driven += on_driven;
            out.pair_forces[index] = on_driven.norm();
        }
        out.stiffest_spring_omega = if out.track_springs {
            closed_springs_omega(&out.springs, &self.inverse_mass, &mut out.node_sums)
        } else {
            0.0
        };
    }

    /// Calls `visit` once for every DOF of gear `g` on the flanks of the flank pairs selected by
    /// any of `selections` (flags per flank pair). `stamp` (one entry per node of the gear)
    /// removes duplicates: a node is visited when its stamp differs from `id`, which must be
    /// new for each call.
    fn for_flank_dofs(
        &self,
        g: usize,
        selections: &[&[bool]],
        stamp: &mut [u64],
        id: u64,
        mut visit: impl FnMut(usize),
    ) {
        for (index, fp) in self.flank_pairs.iter().enumerate() {
            if !selections.iter().any(|s| s[index]) {
                continue;
            }
            for &f in &fp.flanks {
                let flank = &self.flanks[f];
                if flank.gear != g {
                    continue;
                }
                for &n in &flank.nodes {
                    if stamp[n] != id {
                        stamp[n] = id;
                        visit(2 * n);
                        visit(2 * n + 1);
                    }
                }
            }
        }
    }

    /// Gear `g`'s internal and damping forces into `f` (β = `beta`), then the closing kick of
    /// its DOFs that no contact or hub touches ([`ExplicitPair::body_only_runs`], mass damping
    /// α = `alpha`, half step `half`): one gear's share of a force phase. Returns the body's
    /// forces and energies and the kicked DOFs' mass-damping power.
    fn body_forces_and_kick(
        &self,
        g: usize,
        (beta, alpha, half): (f64, f64, f64),
        x: &[f64],
        v: &mut [f64],
        a: &mut [f64],
        f: &mut [f64],
    ) -> (ForceOutput, f64) {
        let out = self.force_body(g).internal_forces(x, v, beta, f);
        let w = &self.inverse_mass[g];
        let power = kicks::kick(alpha, half, &self.body_only_runs[g], w, a, v, f);
        (out, power)
    }

    /// Gear `g`'s far block's step after its element forces `f` (nothing without one): the
    /// forces on its interface taken into the block frame (and cleared in `f`), the block's
    /// products at its hub's `motion` ([angle, rate, acceleration]) and damping power; the
    /// driver's block's accelerations, returning the hub's torque on it [N m] (the driven
    /// hub's are solved with the hub, [`PairIntegrator::contact_and_hubs`]; 0 returned).
    fn far_block_forces(
        &self,
        g: usize,
        motion: [f64; 3],
        beta: f64,
        f: &mut [f64],
        block: Option<&mut BlockState>,
        step: Option<&mut BlockStep>,
    ) -> f64 {
        let (Some(far), Some(block), Some(step)) = (&self.far[g], block, step) else {
            return 0.0;
        };
        let (_, angle, rate) = self.block_frame(g, far, motion);
        far.block
            .take_interface_force(angle, f, &mut step.interface_force);
        let reduced = &far.block.block;
        step.sums = reduced.prepare(block, rate, beta, &step.interface_force, &mut step.scratch);
        step.damping_power = reduced.damping_power(block, beta);
        if g == 0 {
            let frame = FrameMotion {
                rate,
                accel: motion[2],
            };
            reduced.finish_prescribed(block, &step.sums, frame, &step.scratch)
        } else {
            0.0
        }
    }

    /// Empty friction history for [`ExplicitPair::contact_forces`].
    fn new_history(&self) -> Vec<PairHistory> {
        self.flank_pairs
            .iter()
            .map(|fp| PairHistory {
                passes: [0, 1].map(|pass| {
                    // The Gauss points and the tip corner.
                    let points = self.flanks[fp.flanks[pass]].edges.len() * GAUSS_EDGE.len() + 1;
                    vec![SlaveState::default(); points]
                }),
                cleared: true,
            })
            .collect()
    }

    /// Stable step bound of the contact springs: 2/ω with ω² = k_n (1/m_slave + 1/m_master),
    /// m_master the smallest mass of the edge's nodes, over every flank node and edge.
    pub fn contact_critical_step(&self) -> f64 {
        let mut omega2: f64 = 0.0;
        for fp in &self.flank_pairs {
            for pass in 0..2 {
                let (slave, master) = (
                    &self.flanks[fp.flanks[pass]],
                    &self.flanks[fp.flanks[1 - pass]],
                );
                let slave_mass = slave
                    .nodes
                    .iter()
                    .map(|&n| self.bodies[slave.gear].mass[n])
                    .fold(f64::INFINITY, f64::min);
                for (edge, k) in master.edges.iter().zip(&master.penalty) {
                    let master_mass = edge
                        .iter()
                        .map(|&n| self.bodies[master.gear].mass[n])
                        .fold(f64::INFINITY, f64::min);
                    omega2 = omega2.max(k * (1.0 / slave_mass + 1.0 / master_mass));
                }
            }
        }
        2.0 / omega2.sqrt()
    }
}

/// Inverse nodal masses per DOF of `body`, zero where the DOF is not free (the bore's).
fn inverse_masses(body: &ExplicitBody, free: &[bool]) -> Vec<f64> {
    (0..free.len())
        .map(|d| if free[d] { 1.0 / body.mass[d / 2] } else { 0.0 })
        .collect()
}

/// The hub's inertia: its bore nodes' masses at their radii, Σ mₙ |Xₙ|² [kg m²].
fn hub_inertia_of(mesh: &GearMesh, body: &ExplicitBody) -> f64 {
    mesh.bore_nodes
        .iter()
        .map(|&n| body.mass[n] * mesh.nodes[n].coords.norm_squared())
        .sum()
}

/// A closed penalty spring of one Gauss point: √k and, for the three slave and three master
/// nodes it acts on, (gear, node, |shape function|).
#[derive(Debug, Clone, Copy)]
pub struct ClosedSpring {
    pub root_stiffness: f64,
    pub nodes: [(usize, usize, f64); 6],
}

/// An upper bound of the largest eigenvalue of M^-½ K_c M^-½, K_c = Σ_p k_p g_p g_pᵀ the closed
/// springs (g_p their shape functions along the normal, masses per node from
/// `inverse_mass` per DOF), as its square root [rad/s]. The nonzero eigenvalues are those of
/// the Gram matrix G_pq = √(k_p k_q) g̃_p·g̃_q (g̃ = M^-½ g), and Gershgorin's row sums of G,
/// with |n_p·n_q| ≤ 1, give
/// ```text
/// λ_max ≤ max_p √k_p Σ_n |N_pn| T_n / m_n,   T_n = Σ_q √k_q |N_qn|   (q over the springs on node n)
/// ```
/// exact for springs that share no node (k_p Σ N²/m), the sum of their own for springs that
/// share all. With friction each sticking point also has a tangential spring of the same
/// stiffness, k(nnᵀ + ttᵀ) = k·I₂ on the shape functions: the scalar problem of the normals
/// taken all parallel, which the bound (|n_p·n_q| ≤ 1) covers already. `node_sums` is scratch
/// (per gear, one entry per node), left zero.
pub fn closed_springs_omega(
    springs: &[ClosedSpring],
    inverse_mass: &[Vec<f64>; 2],
    node_sums: &mut [Vec<f64>; 2],
) -> f64 {
    for (sums, w) in node_sums.iter_mut().zip(inverse_mass) {
        if sums.len() != w.len() / 2 {
            *sums = vec![0.0; w.len() / 2];
        }
    }
    for s in springs {
        for &(g, n, w) in &s.nodes {
            node_sums[g][n] += s.root_stiffness * w;
        }
    }
    let mut lambda: f64 = 0.0;
    for s in springs {
        let row: f64 = s
            .nodes
            .iter()
            .map(|&(g, n, w)| w * node_sums[g][n] * inverse_mass[g][2 * n])
            .sum();
        lambda = lambda.max(s.root_stiffness * row);
    }
    for s in springs {
        for &(g, n, _) in &s.nodes {
            node_sums[g][n] = 0.0;
        }
    }
    lambda.sqrt()
}

/// The contact surface of one flank: edges oriented with the outward normal, penalty per edge.
fn make_flank(
    mesh: &GearMesh,
    body: &ExplicitBody,
    (gear, teeth, tooth): (usize, usize, usize),
    side: Side,
    penalty_factor: f64,
) -> Flank {
    let nodes = mesh.flank(tooth, side).nodes.clone();
    let mut edges: Vec<[usize; 3]> = nodes
        .windows(3)
        .step_by(2)
        .map(|w| [w[0], w[1], w[2]])
        .collect();
    // Orientation: the normal (t_y, −t_x) of a counter-clockwise edge points away from the
    // tooth's centre line; test the middle edge in the tooth-local frame.
    let middle = edges[edges.len() / 2];
    let (a, b) = (mesh.nodes[middle[0]], mesh.nodes[middle[2]]);
    let t = b - a;
    let normal = Vector2::new(t.y, -t.x);
    let pitch = 2.0 * std::f64::consts::PI / teeth as f64;
    let axis = Rotation2::new(tooth as f64 * pitch) * Vector2::new(0.0, 1.0);
    let mid = a.coords + t * 0.5;
    let away = mid - axis * mid.dot(&axis);
    if normal.dot(&away) < 0.0 {
        edges.reverse();
        for e in &mut edges {
            e.reverse();
        }
    }
    // Penalty from the stiffness of the element that owns each edge.
    let penalty = edges
        .iter()
        .map(|edge| {
            let owner = mesh
                .elements
                .iter()
                .position(|e| edge.iter().all(|n| e.contains(n)))
                .expect("a flank edge belongs to an element");
            let k = body.element_stiffness(owner);
            let max_diag = (0..16).map(|i| k[(i, i)]).fold(0.0, f64::max);
            penalty_factor * max_diag
        })
        .collect();
    let line_penalty = edges
        .iter()
        .zip(&penalty)
        .map(|(edge, k)| k / (mesh.nodes[edge[2]] - mesh.nodes[edge[0]]).norm())
        .collect();
    let tip = *nodes.last().expect("a flank has nodes");
    let tip_corner = if edges.last().is_some_and(|e| e[2] == tip) {
        (edges.len() - 1, 1.0)
    } else {
        (0, -1.0)
    };
    debug_assert_eq!(edges[tip_corner.0][(tip_corner.1 + 1.0) as usize], tip);
    let middle = nodes[nodes.len() / 2];
    let radius = 1.05
        * nodes
            .iter()
            .map(|&n| (mesh.nodes[n] - mesh.nodes[middle]).norm())
            .fold(0.0, f64::max);
    Flank {
        gear,
        tooth,
        side,
        nodes,
        edges,
        penalty,
        line_penalty,
        tip_corner,
        middle,
        radius,
    }
}

/// A central-difference integrator of the pair.
pub struct PairIntegrator<'a> {
    pub model: &'a ExplicitPair,
    pub drive: Drive,
    pub dt: f64,
    /// Stiffness-proportional damping coefficient β [s] (f_d = β K v on the deformation rate).
    pub beta_k: f64,
    /// Mass-proportional damping α [1/s] (f = −α m v on every free node and −α I_h φ̇ on the
    /// driven hub). It brakes rigid rotation as well, so it is for static solutions by dynamic
    /// relaxation (driver at rest) only; scenes use 0.
    pub mass_damping: f64,
    /// Mesh dashpot c_t [N m s]: torque −c_t (φ̇₂ − φ̇₂,kin) on the driven hub, against the rate
    /// of the angular DTE (the lumped model's viscous mesh damping c_m R_b2²), while any point
    /// is in contact — through the mesh, never across open teeth. Its work is booked as
    /// damping.
    pub mesh_damping: f64,
    pub energy: PairEnergy,
    pub steps: usize,
    pub last_contact: ContactOutput,
    force: [Vec<f64>; 2],
    contact_force: [Vec<f64>; 2],
    previous_contact: [Vec<f64>; 2],
    history: Vec<PairHistory>,
    /// Driver hub reaction on the bore DOFs at the last step, and at the step before.
    driver_reaction: Vec<f64>,
    old_reaction: Vec<f64>,
    /// Flank pairs searched for contact two steps ago and at the last step: the contact forces
    /// of those steps sit on their flanks only, so the per-step loops over contact DOFs visit
    /// those flanks instead of every flank of the scene.
    searched: [Vec<bool>; 2],
    /// Per node of each gear, for visiting shared flank nodes once; and the last stamp used.
    node_stamp: [Vec<u64>; 2],
    stamp_id: u64,
    /// Positions of the driver's bore DOFs at the start of the step.
    old_bore_x: Vec<f64>,
    /// The velocities of the held DOFs ([`ExplicitPair::held_dofs`]) after the drift, for the
    /// contact, while each gear's thread kicks its other DOFs; other entries are stale.
    contact_velocity: [Vec<f64>; 2],
    /// The two gears' phases side by side (a partner thread kept for the run) or in series.
    lockstep: Lockstep,
    /// Where the steps' time went.
    pub phase_wall: PhaseWall,
    /// The gear whose element forces share their thread with the contact (its forces and the
    /// contact one after the other, the other gear's beside them): chosen every
    /// [`BALANCE_EVERY`] steps from the last ones' measured times, so that the longer of the
    /// two threads' shares is the shorter. Which thread computes what changes no result.
    contact_beside: usize,
    /// The contact's and the two bodies' times since that choice [s].
    balance: [f64; 3],
    /// The contact to the other thread at every step instead ([`Self::alternate_contact_thread`]).
    alternate_contact: bool,
    /// Per gear with a far block: its step's work space.
    block_steps: [Option<BlockStep>; 2],
    /// The driver's hub torque on its far block at the last step and the step before [N m]
    /// (its work is the driver's).
    block_torque: f64,
    old_block_torque: f64,
}

/// A far block's step work space: the products' scratch, the interface forces in the block
/// frame, what its prepared step leaves for the hub and its damping power [W].
struct BlockStep {
    scratch: BlockScratch,
    interface_force: Vec<f64>,
    sums: BlockSums,
    damping_power: f64,
}

/// A `Vector2` as `[x, y]` in a checkpoint.
mod vector2_as_array {
    use nalgebra::Vector2;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(v: &Vector2<f64>, s: S) -> Result<S::Ok, S::Error> {
        [v.x, v.y].serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vector2<f64>, D::Error> {
        let [x, y] = <[f64; 2]>::deserialize(d)?;
        Ok(Vector2::new(x, y))
    }
}

/// Where the steps' wall time goes, phase by phase, summed over a run's steps [s]: what the
/// two lock-step threads wait for. Timings only: no result depends on them. Steps a run takes
/// back (its step control's return to a sample) take their times with them.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PhaseWall {
    pub steps: u64,
    /// Whole steps.
    pub step_s: f64,
    /// The drift phase, both gears side by side.
    pub drift_s: f64,
    /// The force phase: the contact search and forces beside the two bodies' element forces.
    pub forces_s: f64,
    /// Within the force phase, on their threads: the contact, and each gear's element forces
    /// with the kick of its DOFs that no contact or hub touches.
    pub contact_s: f64,
    pub body_forces_s: [f64; 2],
    /// The closing half kick of the flank and bore DOFs and the bores' placement, each gear on
    /// its thread (until 2026-12-06 the kick of every DOF: the others' kick is now in the force
    /// phase, on each gear's thread).
    pub accelerate_s: f64,
    /// Steps whose contact ran on the thread of gear 1's element forces, of gear 2's (on one
    /// thread the choice is made all the same, and means nothing).
    pub contact_beside_steps: [u64; 2],
}

/// Per-step means of a [`PhaseWall`] [µs], and the share of steps whose contact ran beside
/// gear 2's element forces (summary.json's `wall_phases_us_per_step`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PhaseWallPerStep {
    pub step: f64,
    pub drift: f64,
    pub forces: f64,
    pub contact: f64,
    pub body_forces: [f64; 2],
    pub accelerate: f64,
    /// The rest of a step: its serial middle (hub, contact forces added, work terms).
    pub serial: f64,
    pub contact_beside_gear2_share: f64,
}

impl PhaseWall {
    pub fn per_step_us(&self) -> PhaseWallPerStep {
        let per = |t: f64| 1e6 * t / (self.steps.max(1) as f64);
        PhaseWallPerStep {
            step: per(self.step_s),
            drift: per(self.drift_s),
            forces: per(self.forces_s),
            contact: per(self.contact_s),
            body_forces: self.body_forces_s.map(per),
            accelerate: per(self.accelerate_s),
            serial: per(self.step_s - self.drift_s - self.forces_s - self.accelerate_s),
            contact_beside_gear2_share: self.contact_beside_steps[1] as f64
                / (self.contact_beside_steps[0] + self.contact_beside_steps[1]).max(1) as f64,
        }
    }
}

/// Steps between the choices of the thread that runs the contact ([`PairIntegrator`]).
const BALANCE_EVERY: usize = 1024;
/// The gain in the longer thread's share that moves the contact to the other thread.
const BALANCE_MARGIN: f64 = 0.02;

/// The integrator's state between two steps, beside the pair's [`PairState`]: with both, a run
/// goes on exactly as if it had not stopped. Scratch is not kept: the internal force array is
/// zero between steps and the node stamps only compare with the stamp counter, which restarts
/// with them.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct IntegratorCheckpoint {
    energy: PairEnergy,
    /// Timings, carried from window to window (absent from older checkpoints: zero).
    #[serde(default)]
    phase_wall: PhaseWall,
    steps: usize,
    last_contact: ContactOutput,
    contact_force: [Vec<f64>; 2],
    previous_contact: [Vec<f64>; 2],
    history: Vec<PairHistory>,
    driver_reaction: Vec<f64>,
    old_reaction: Vec<f64>,
    searched: [Vec<bool>; 2],
    old_bore_x: Vec<f64>,
    /// The driver's hub torque on its far block (absent from older checkpoints: zero).
    #[serde(default)]
    block_torque: f64,
}

impl PairState {
    /// This state carried to another mesh of the same gears (`transfers`, one per gear, old
    /// nodes to new): positions and velocities interpolated, accelerations zero until
    /// [`PairIntegrator::settle_remeshed`] sets them from the forces; the hubs as they are.
    ///
    /// The velocity field is carried as it is, so a rigid motion stays exactly rigid, bore
    /// nodes and hub included. The new mesh lumps the switched sectors' mass at other points,
    /// so each gear's momentum changes by the lumping's difference (ΔI ω about its centre):
    /// no force acts, and the kinetic energy it changes is booked as remeshing. (Restoring the
    /// old momentum by a rigid correction of the free nodes instead would set the rim turning
    /// against the bore nodes, which follow the hub.)
    pub fn remeshed(&self, transfers: &[NodeTransfer; 2]) -> PairState {
        PairState {
            time: self.time,
            x: std::array::from_fn(|g| transfers[g].apply(&self.x[g], 2)),
            v: std::array::from_fn(|g| transfers[g].apply(&self.v[g], 2)),
            a: std::array::from_fn(|g| vec![0.0; transfers[g].sources.len() * 2]),
            hub: self.hub,
            // Projected from x and v on the new mesh's blocks by
            // [`PairIntegrator::settle_remeshed`] (expand the old ones first:
            // [`ExplicitPair::expanded`]).
            blocks: [None, None],
        }
    }
}

impl IntegratorCheckpoint {
    /// This checkpoint of a run on `old` carried to `new`, a model of the same pair on other
    /// meshes (`transfers` from `old`'s nodes to `new`'s): the contact forces stay on the nodes
    /// both meshes share (a tooth switches kind out of contact, so its new nodes carry none),
    /// the friction history and search flags stay with the flank pairs both models hold (by
    /// teeth and flank) and start afresh on the others, and the driver's hub reactions are
    /// recomputed by [`PairIntegrator::settle_remeshed`].
    ///
    /// Fails where a flank of a pair that is searched (near contact or in it) is not on nodes
    /// both meshes share: its contact forces would be lost.
    pub fn remeshed(
        self,
        old: &ExplicitPair,
        new: &ExplicitPair,
        transfers: &[NodeTransfer; 2],
    ) -> Result<IntegratorCheckpoint, String> {
        let old_index = |fp: &FlankPair| {
            old.flank_pairs
                .iter()
                .position(|o| o.teeth == fp.teeth && o.drive == fp.drive)
        };
        let map = new
            .flank_pairs
            .iter()
            .map(old_index)
            .collect::<Vec<Option<usize>>>();
        for (k, m) in map.iter().enumerate() {
            let searched = m.is_some_and(|j| {
                self.searched
                    .iter()
                    .any(|f| f.get(j).copied().unwrap_or(false))
            });
            if !searched {
                continue;
            }
            for &f in &new.flank_pairs[k].flanks {
                let flank = &new.flanks[f];
                if let Some(n) = flank
                    .nodes
                    .iter()
                    .find(|&&n| transfers[flank.gear].copied_from(n).is_none())
                {
                    return Err(format!(
                        "remeshing: node {n} of gear {}'s flank of tooth pair {:?}, near contact, \
                         is not a node of the previous mesh",
                        flank.gear + 1,
                        new.flank_pairs[k].teeth
                    ));
                }
            }
        }
        let mut fresh = new.new_history();
        for (h, m) in fresh.iter_mut().zip(&map) {
            if let Some(&j) = m.as_ref() {
                let kept = &self.history[j];
                let fits = (0..2).all(|p| kept.passes[p].len() == h.passes[p].len());
                if fits {
                    *h = kept.clone();
                }
            }
        }
        let flags = |old_flags: &[bool]| -> Vec<bool> {
            map.iter()
                .map(|m| m.is_some_and(|j| old_flags.get(j).copied().unwrap_or(false)))
                .collect()
        };
        let mut last_contact = self.last_contact;
        last_contact.pair_forces = map
            .iter()
            .map(|m| {
                m.map_or(0.0, |j| {
                    last_contact.pair_forces.get(j).copied().unwrap_or(0.0)
                })
            })
            .collect();
        last_contact.searched = flags(&last_contact.searched);
        last_contact.springs.clear();
        last_contact.node_sums = Default::default();
        let bore = 2 * new.meshes[0].bore_nodes.len();
        Ok(IntegratorCheckpoint {
            energy: self.energy,
            phase_wall: self.phase_wall,
            steps: self.steps,
            last_contact,
            contact_force: std::array::from_fn(|g| {
                transfers[g].copy_or_zero(&self.contact_force[g], 2)
            }),
            previous_contact: std::array::from_fn(|g| {
                transfers[g].copy_or_zero(&self.previous_contact[g], 2)
            }),
            history: fresh,
            driver_reaction: vec![0.0; bore],
            old_reaction: vec![0.0; bore],
            searched: [flags(&self.searched[0]), flags(&self.searched[1])],
            old_bore_x: vec![0.0; bore],
            // With the reactions, by [`PairIntegrator::settle_remeshed`].
            block_torque: 0.0,
        })
    }

    /// Steps taken up to this checkpoint.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// The energy account at this checkpoint.
    pub fn energy(&self) -> PairEnergy {
        self.energy
    }

    /// The steps' wall time up to this checkpoint, phase by phase.
    pub fn phase_wall(&self) -> PhaseWall {
        self.phase_wall
    }
}

impl<'a> PairIntegrator<'a> {
    /// What [`Self::restore`] needs to go on from here.
    pub fn checkpoint(&self) -> IntegratorCheckpoint {
        IntegratorCheckpoint {
            energy: self.energy,
            phase_wall: self.phase_wall,
            steps: self.steps,
            last_contact: self.last_contact.clone(),
            contact_force: self.contact_force.clone(),
            previous_contact: self.previous_contact.clone(),
            history: self.history.clone(),
            driver_reaction: self.driver_reaction.clone(),
            old_reaction: self.old_reaction.clone(),
            searched: self.searched.clone(),
            old_bore_x: self.old_bore_x.clone(),
            block_torque: self.block_torque,
        }
    }

    /// Takes up `checkpoint` on a new integrator of the same model; refuses one whose arrays do
    /// not fit the model (another mesh).
    pub fn restore(&mut self, checkpoint: IntegratorCheckpoint) -> Result<(), String> {
        let fits = (0..2).all(|g| {
            checkpoint.contact_force[g].len() == self.contact_force[g].len()
                && checkpoint.previous_contact[g].len() == self.previous_contact[g].len()
                && checkpoint.searched[g].len() == self.searched[g].len()
        }) && checkpoint.history.len() == self.history.len()
            && checkpoint.old_bore_x.len() == self.old_bore_x.len()
            && checkpoint.driver_reaction.len() == self.driver_reaction.len();
        if !fits {
            return Err("the checkpoint was made on another mesh".to_string());
        }
        let IntegratorCheckpoint {
            energy,
            phase_wall,
            steps,
            last_contact,
            contact_force,
            previous_contact,
            history,
            driver_reaction,
            old_reaction,
            searched,
            old_bore_x,
            block_torque,
        } = checkpoint;
        self.energy = energy;
        self.phase_wall = phase_wall;
        self.steps = steps;
        self.last_contact = last_contact;
        self.contact_force = contact_force;
        self.previous_contact = previous_contact;
        self.history = history;
        self.driver_reaction = driver_reaction;
        self.old_reaction = old_reaction;
        self.searched = searched;
        self.old_bore_x = old_bore_x;
        self.block_torque = block_torque;
        Ok(())
    }

    pub fn new(model: &'a ExplicitPair, drive: Drive, dt: f64, beta_k: f64) -> Self {
        let zeros = |g: usize| vec![0.0; 2 * model.meshes[g].nodes.len()];
        PairIntegrator {
            model,
            drive,
            dt,
            beta_k,
            mass_damping: 0.0,
            mesh_damping: 0.0,
            energy: PairEnergy::default(),
            steps: 0,
            last_contact: ContactOutput::default(),
            force: [zeros(0), zeros(1)],
            contact_force: [zeros(0), zeros(1)],
            previous_contact: [zeros(0), zeros(1)],
            history: model.new_history(),
            driver_reaction: vec![0.0; 2 * model.meshes[0].bore_nodes.len()],
            old_reaction: vec![0.0; 2 * model.meshes[0].bore_nodes.len()],
            searched: [
                vec![false; model.flank_pairs.len()],
                vec![false; model.flank_pairs.len()],
            ],
            node_stamp: [
                vec![0; model.meshes[0].nodes.len()],
                vec![0; model.meshes[1].nodes.len()],
            ],
            stamp_id: 0,
            old_bore_x: vec![0.0; 2 * model.meshes[0].bore_nodes.len()],
            contact_velocity: [zeros(0), zeros(1)],
            lockstep: Lockstep::for_current_pool(),
            phase_wall: PhaseWall::default(),
            // Until the first measurement: the gear of fewer elements.
            contact_beside: usize::from(
                model.bodies[0].elements.len() > model.bodies[1].elements.len(),
            ),
            balance: [0.0; 3],
            alternate_contact: false,
            block_steps: std::array::from_fn(|g| {
                model.far[g].as_ref().map(|far| {
                    let block = &far.block.block;
                    BlockStep {
                        scratch: block.scratch(),
                        interface_force: vec![0.0; block.interface_dofs()],
                        sums: BlockSums::default(),
                        damping_power: 0.0,
                    }
                })
            }),
            block_torque: 0.0,
            old_block_torque: 0.0,
        }
    }

    /// From here on the contact runs on the other thread at every step, not where the threads
    /// balance: for the tests that hold the claim that the contact's thread changes no result.
    #[doc(hidden)]
    pub fn alternate_contact_thread(&mut self) {
        self.alternate_contact = true;
    }

    /// Whether the integrator steps the two gears on two threads (a partner thread of its own).
    pub fn is_parallel(&self) -> bool {
        self.lockstep.is_parallel()
    }

    /// The first phase of a step, per gear and in parallel: the drift x += Δt v after the half
    /// kick v += ½Δt a (skipped with `dt` = None; a far block's nodes by the block's drift,
    /// its interface nodes then placed from it), the hub motion of the bore nodes, and the
    /// held DOFs' velocities copied for the contact.
    fn drift(&mut self, state: &mut PairState, dt: Option<f64>, bore: [[f64; 3]; 2]) {
        let model = self.model;
        let [x0, x1] = &mut state.x;
        let [v0, v1] = &mut state.v;
        let [a0, a1] = &mut state.a;
        let [b0, b1] = &mut state.blocks;
        let [s0, s1] = &mut self.block_steps;
        let [c0, c1] = &mut self.contact_velocity;
        let gear = |g: usize,
                    (x, v, a): (&mut [f64], &mut [f64], &mut [f64]),
                    held_v: &mut [f64],
                    block: Option<&mut BlockState>,
                    step: Option<&mut BlockStep>| {
            match (&model.far[g], block, step) {
                (Some(far), Some(block), Some(step)) => {
                    if let Some(dt) = dt {
                        for r in &far.moving_runs {
                            let r = r.clone();
                            kicks::drift(dt, &mut x[r.clone()], &mut v[r.clone()], &a[r]);
                        }
                        block.drift(dt);
                    }
                    let reduced = &far.block.block;
                    reduced.interface_motion(block, &mut step.scratch);
                    let scratch = &step.scratch;
                    far.block.place_interface(
                        model.block_frame(g, far, bore[g]),
                        (scratch.interface_displacement(), scratch.interface_rate()),
                        x,
                        v,
                    );
                }
                (Some(_), _, _) => panic!("a far block without its state"),
                (None, _, _) => {
                    if let Some(dt) = dt {
                        kicks::drift(dt, x, v, a);
                    }
                }
            }
            model.place_bore(g, x, v, a, bore[g]);
            for &d in &model.held_dofs[g] {
                held_v[d] = v[d];
            }
        };
        self.lockstep.join(
            || gear(0, (x0, v0, a0), c0, b0.as_mut(), s0.as_mut()),
            || gear(1, (x1, v1, a1), c1, b1.as_mut(), s1.as_mut()),
        );
    }

    /// The middle phase, on both threads at once: the contact forces (into `contact_force`,
    /// with their bookkeeping) beside the bodies' internal and damping forces (into `force`,
    /// whose contact forces are not yet added; `force` is zero here: the kicks clear it as they
    /// read it). Right after its element forces each gear's thread kicks the DOFs no contact
    /// and no hub touches ([`ExplicitPair::body_only_runs`], with `half` = ½Δt, zero at the
    /// start), while their forces are fresh in its cache; the contact reads only the held DOFs'
    /// positions and their velocities' copy. (Until 2026-12-06 the kick of every DOF waited for
    /// the serial middle; now only the flank and bore DOFs' does: validation/performance.)
    /// The contact goes with the gear whose thread then finishes first by the last
    /// [`BALANCE_EVERY`] steps' times ([`PairIntegrator::contact_beside`]). Splitting a body
    /// between the threads to balance them gained nothing (validation/performance): its nodes'
    /// cache lines then move between the cores at every step.
    ///
    /// A far block's step follows its gear's element forces on the same thread (the fine
    /// elements' forces on its interface are its load; [`ExplicitPair::far_block_forces`]),
    /// with the hubs' `frames` ([angle, rate, acceleration] of the driver and the driven hub).
    ///
    /// Returns the bodies' forces and energies, the mass damping's power in the kicked DOFs,
    /// and the phase's times [s]: the contact's, each gear's element forces and kick.
    fn contact_and_body_forces(
        &mut self,
        state: &mut PairState,
        half: f64,
        frames: [[f64; 3]; 2],
    ) -> ([ForceOutput; 2], f64, [f64; 3]) {
        let PairIntegrator {
            model,
            dt,
            beta_k,
            mass_damping,
            force,
            contact_force,
            previous_contact,
            history,
            searched,
            node_stamp,
            stamp_id,
            last_contact,
            lockstep,
            contact_beside,
            contact_velocity,
            block_steps,
            block_torque,
            ..
        } = self;
        let (model, dt, beta, alpha) = (*model, *dt, *beta_k, *mass_damping);
        let [f0, f1] = force;
        let PairState {
            x, v, a, blocks, ..
        } = state;
        let [v0, v1] = v;
        let [a0, a1] = a;
        let [b0, b1] = blocks;
        let [s0, s1] = block_steps;
        let x: [&[f64]; 2] = [&x[0], &x[1]];
        let forces = |g: usize,
                      (f, v, a): (&mut [f64], &mut [f64], &mut [f64]),
                      block: Option<&mut BlockState>,
                      step: Option<&mut BlockStep>| {
            let started = Instant::now();
            let (out, power) = model.body_forces_and_kick(g, (beta, alpha, half), x[g], v, a, f);
            let torque = model.far_block_forces(g, frames[g], beta, f, block, step);
            (out, power, torque, started.elapsed().as_secs_f64())
        };
        let held_v: [&[f64]; 2] = [&contact_velocity[0], &contact_velocity[1]];
        let mut contact = || {
            let started = Instant::now();
            // After the swap, `contact_force` holds the forces of two steps ago, on the flanks
            // searched then.
            for g in 0..2 {
                std::mem::swap(&mut previous_contact[g], &mut contact_force[g]);
                *stamp_id += 1;
                let current = &mut contact_force[g];
                model.for_flank_dofs(g, &[&searched[0]], &mut node_stamp[g], *stamp_id, |d| {
                    current[d] = 0.0
                });
            }
            model.contact_forces(x, held_v, dt, history, contact_force, last_contact);
            searched.swap(0, 1);
            searched[1].copy_from_slice(&last_contact.searched);
            started.elapsed().as_secs_f64()
        };
        let mut gear0 = || forces(0, (f0, v0, a0), b0.as_mut(), s0.as_mut());
        let mut gear1 = || forces(1, (f1, v1, a1), b1.as_mut(), s1.as_mut());
        let ((o0, p0, torque, t0), (o1, p1, _, t1), t_contact) = if *contact_beside == 0 {
            let ((c, g0), g1) = lockstep.join(|| (contact(), gear0()), gear1);
            (g0, g1, c)
        } else {
            let (g0, (c, g1)) = lockstep.join(gear0, || (contact(), gear1()));
            (g0, g1, c)
        };
        *block_torque = torque;
        ([o0, o1], p0 + p1, [t_contact, t0, t1])
    }

    /// Books a step's force-phase times and, every [`BALANCE_EVERY`] steps, puts the contact
    /// where the threads finish closest together: beside the other gear's element forces only
    /// if that shortens the longer thread's share by more than [`BALANCE_MARGIN`] (the times of
    /// the placement not in use are estimates, taken from the one in use).
    fn book_force_phase(&mut self, wall_s: f64, times: [f64; 3]) {
        let beside = self.contact_beside;
        let [contact, t0, t1] = times;
        let wall = &mut self.phase_wall;
        wall.forces_s += wall_s;
        wall.contact_s += contact;
        wall.body_forces_s[0] += t0;
        wall.body_forces_s[1] += t1;
        wall.contact_beside_steps[beside] += 1;
        for (sum, t) in self.balance.iter_mut().zip(times) {
            *sum += t;
        }
        if self.alternate_contact {
            self.contact_beside = 1 - beside;
        } else if self.phase_wall.steps % BALANCE_EVERY as u64 == BALANCE_EVERY as u64 - 1 {
            let [c, b0, b1] = self.balance;
            // The longer thread's share with the contact beside gear 0's forces or gear 1's.
            let longer = [(c + b0).max(b1), (c + b1).max(b0)];
            let other = 1 - beside;
            if longer[other] < (1.0 - BALANCE_MARGIN) * longer[beside] {
                self.contact_beside = other;
            }
            self.balance = [0.0; 3];
        }
    }

    /// The serial middle of a step: the contact forces added to the body forces, the driven
    /// hub's angular acceleration and the driver's hub reactions. Returns the power dissipated
    /// on the hub (mesh dashpot and mass damping).
    fn contact_and_hubs(&mut self, state: &mut PairState) -> f64 {
        let model = self.model;
        for g in 0..2 {
            self.stamp_id += 1;
            let (force, current) = (&mut self.force[g], &self.contact_force[g]);
            model.for_flank_dofs(
                g,
                &[&self.searched[1]],
                &mut self.node_stamp[g],
                self.stamp_id,
                |d| force[d] += current[d],
            );
        }
        // Driven hub: moment of the net forces on its bore nodes plus the load torque.
        let c2 = model.placement[1].centre;
        let mut moment = self.drive.load_torque_at(state.time);
        for &n in &model.meshes[1].bore_nodes {
            let (rx, ry) = (state.x[1][2 * n] - c2.x, state.x[1][2 * n + 1] - c2.y);
            moment += rx * self.force[1][2 * n + 1] - ry * self.force[1][2 * n];
        }
        let (_, driver_rate, _) = self.drive.driver_motion(state.time);
        let dte_rate = state.hub[1] - model.kinematic_hub_rotation(driver_rate);
        // The mesh damping acts through the contact: none while no point is in contact.
        let mesh_torque = if self.last_contact.active > 0 {
            -self.mesh_damping * dte_rate
        } else {
            0.0
        };
        moment += mesh_torque;
        let alpha = self.mass_damping;
        assert!(
            alpha == 0.0 || model.far.iter().all(Option::is_none),
            "mass damping (dynamic relaxation) on a reduced far body"
        );
        state.hub[2] = match (
            &model.far[1],
            state.blocks[1].as_mut(),
            &self.block_steps[1],
        ) {
            (Some(far), Some(block), Some(step)) => {
                // The hub and its block solved together.
                far.block.block.finish_free(
                    block,
                    &step.sums,
                    model.hub_inertia,
                    state.hub[1],
                    moment,
                    &step.scratch,
                )
            }
            _ => moment / model.hub_inertia - alpha * state.hub[1],
        };
        // Driver reactions: what the hub must apply so the bore nodes follow their path (their
        // prescribed accelerations are in state.a from place_bore).
        for (i, &n) in model.meshes[0].bore_nodes.iter().enumerate() {
            let m = model.bodies[0].mass[n];
            for c in 0..2 {
                self.driver_reaction[2 * i + c] =
                    m * state.a[0][2 * n + c] - self.force[0][2 * n + c];
            }
        }
        alpha * model.hub_inertia * state.hub[1] * state.hub[1] - mesh_torque * state.hub[1]
    }

    /// The last phase, per gear and in parallel: the kick of the held DOFs
    /// ([`ExplicitPair::held_dofs`]: the flanks', now with their contact forces, and the
    /// bore's, whose w = 0 gives a = 0), then the hub motion of the bore nodes. With `dt` = None
    /// no half kick. Returns the mass damping's power in the held DOFs. (On each gear's own
    /// thread: done serially, the partner's cache lines of a few hundred scattered DOFs made it
    /// slower than the hand-over.)
    fn kick_held(&mut self, state: &mut PairState, dt: Option<f64>, bore: [[f64; 3]; 2]) -> f64 {
        let (model, alpha) = (self.model, self.mass_damping);
        let half = 0.5 * dt.unwrap_or(0.0);
        let [x0, x1] = &mut state.x;
        let [v0, v1] = &mut state.v;
        let [a0, a1] = &mut state.a;
        let [f0, f1] = &mut self.force;
        let [b0, b1] = &mut state.blocks;
        let gear = |g: usize,
                    (x, v, a): (&mut [f64], &mut [f64], &mut [f64]),
                    f: &mut [f64],
                    block: Option<&mut BlockState>| {
            let w = &model.inverse_mass[g];
            let mut power = 0.0;
            for &d in &model.held_dofs[g] {
                power += kicks::kick_one(alpha, half, w[d], &mut a[d], &mut v[d], &mut f[d]);
            }
            if let Some(block) = block {
                block.kick(half);
            }
            model.place_bore(g, x, v, a, bore[g]);
            power
        };
        let (p0, p1) = self.lockstep.join(
            || gear(0, (x0, v0, a0), f0, b0.as_mut()),
            || gear(1, (x1, v1, a1), f1, b1.as_mut()),
        );
        p0 + p1
    }

    /// Hub placement of both gears at the state's time; then forces and accelerations.
    pub fn initialize(&mut self, state: &mut PairState) {
        let (theta, rate, accel) = self.drive.driver_motion(state.time);
        let [phi, phi_rate, _] = state.hub;
        let frames = [[theta, rate, accel], [phi, phi_rate, 0.0]];
        self.drift(state, None, frames);
        let (body, _, _) = self.contact_and_body_forces(state, 0.0, frames);
        self.contact_and_hubs(state);
        self.kick_held(state, None, [[theta, rate, accel], state.hub]);
        self.energy.strain =
            body[0].strain_energy + body[1].strain_energy + self.block_strain(state);
        self.energy.kinetic = self.kinetic(state);
        // A start at speed: the initial kinetic energy is work done on the pair before t = 0.
        self.energy.external_work = self.energy.kinetic + self.energy.strain;
    }

    /// After [`PairState::remeshed`] and [`IntegratorCheckpoint::remeshed`] restored on this
    /// integrator (a model on the next window's meshes): the bore nodes placed by the hubs, the
    /// accelerations from the internal forces at the carried state and the contact forces
    /// carried with it (the contact is not evaluated again, so the friction history does not
    /// see the same instant twice), the driven hub's acceleration and the driver's reactions.
    /// The kinetic and strain energy on the new meshes less those the account held before is
    /// booked as [`PairEnergy::remeshing`]; returns it [J].
    pub fn settle_remeshed(&mut self, state: &mut PairState) -> f64 {
        let before = self.energy.kinetic + self.energy.strain;
        let (theta, rate, accel) = self.drive.driver_motion(state.time);
        let (model, beta, alpha) = (self.model, self.beta_k, self.mass_damping);
        let frames = [[theta, rate, accel], state.hub];
        // The carried nodes onto this mesh's far blocks.
        for (g, frame) in frames.iter().enumerate() {
            if let (Some(far), None) = (&model.far[g], &state.blocks[g]) {
                let frame = model.block_frame(g, far, *frame);
                state.blocks[g] = Some(far.block.project(frame, &state.x[g], &state.v[g]));
            }
        }
        self.drift(state, None, frames);
        let [f0, f1] = &mut self.force;
        let [s0, s1] = &mut self.block_steps;
        let PairState {
            x, v, a, blocks, ..
        } = &mut *state;
        let [v0, v1] = v;
        let [a0, a1] = a;
        let [b0, b1] = blocks;
        let gear = |g: usize,
                    (f, v, a): (&mut [f64], &mut [f64], &mut [f64]),
                    block: Option<&mut BlockState>,
                    step: Option<&mut BlockStep>| {
            let out = model
                .body_forces_and_kick(g, (beta, alpha, 0.0), &x[g], v, a, f)
                .0;
            let torque = model.far_block_forces(g, frames[g], beta, f, block, step);
            (out, torque)
        };
        let ((o0, torque), (o1, _)) = self.lockstep.join(
            || gear(0, (f0, v0, a0), b0.as_mut(), s0.as_mut()),
            || gear(1, (f1, v1, a1), b1.as_mut(), s1.as_mut()),
        );
        self.block_torque = torque;
        self.contact_and_hubs(state);
        self.kick_held(state, None, [[theta, rate, accel], state.hub]);
        self.energy.strain = o0.strain_energy + o1.strain_energy + self.block_strain(state);
        self.energy.kinetic = self.kinetic(state);
        let added = self.energy.kinetic + self.energy.strain - before;
        self.energy.remeshing += added;
        added
    }

    /// The nodes' kinetic energy, a far block's nodes' from the block ([`ReducedBlock`]'s
    /// T, turning with its hub).
    ///
    /// [`ReducedBlock`]: crate::explicit::reduced::ReducedBlock
    fn kinetic(&self, state: &PairState) -> f64 {
        let model = self.model;
        let (_, driver_rate, _) = self.drive.driver_motion(state.time);
        (0..2)
            .map(|g| {
                let mass = &model.bodies[g].mass;
                let node = |(d, v): (usize, &f64)| 0.5 * mass[d / 2] * v * v;
                match (&model.far[g], &state.blocks[g]) {
                    (Some(far), Some(block)) => {
                        let rate = if g == 0 { driver_rate } else { state.hub[1] };
                        let nodes: f64 = state.v[g]
                            .iter()
                            .enumerate()
                            .filter(|(d, _)| far.counted[d / 2])
                            .map(node)
                            .sum();
                        nodes + far.block.block.kinetic_energy(block, rate)
                    }
                    _ => state.v[g].iter().enumerate().map(node).sum::<f64>(),
                }
            })
            .sum()
    }

    /// The far blocks' strain energy [J].
    fn block_strain(&self, state: &PairState) -> f64 {
        (0..2)
            .filter_map(|g| {
                let (far, block) = (self.model.far[g].as_ref()?, state.blocks[g].as_ref()?);
                Some(far.block.block.strain_energy(block))
            })
            .sum()
    }

    /// One central-difference step (no allocation):
    /// ```text
    /// v ← v + ½Δt a;  x ← x + Δt v;  hubs → bore DOFs            per gear, parallel
    /// f = −f_int(x) − f_damp(v), then a = f/m;  v ← v + ½Δt a
    ///   on the DOFs no contact or hub touches, per gear;
    ///   f_contact(x, v) beside them                                3 tasks on 2 threads
    /// f += f_contact;  driven hub: φ̈ = M/I_h;  driver reactions     serial
    /// a = f/m;  v ← v + ½Δt a on the flank and bore DOFs;  hubs     per gear, parallel
    /// ```
    /// Every DOF gets the same arithmetic as in a separate kick phase, so the state is the bits
    /// of the three-phase step ([`kicks`]); with mass damping (dynamic relaxation only) the
    /// damping energy's sum is grouped otherwise, equal to round-off.
    /// The parallel phases go through [`Lockstep`]: with one thread they run one after the
    /// other, with the same arithmetic.
    /// The energy account's kinetic and strain parts are state functions, updated by
    /// [`PairIntegrator::update_energy`] when asked; the work terms accumulate every step. A
    /// non-finite hub state is reported as divergence here; energy growth is checked in
    /// `update_energy`.
    pub fn step(&mut self, state: &mut PairState) -> Result<(), String> {
        let started = Instant::now();
        let model = self.model;
        let dt = self.dt;
        for (i, &n) in model.meshes[0].bore_nodes.iter().enumerate() {
            self.old_bore_x[2 * i] = state.x[0][2 * n];
            self.old_bore_x[2 * i + 1] = state.x[0][2 * n + 1];
        }
        self.old_reaction.copy_from_slice(&self.driver_reaction);
        self.old_block_torque = self.block_torque;
        let (old_phi, old_torque) = (state.hub[0], self.drive.load_torque_at(state.time));
        let (old_theta, _, _) = self.drive.driver_motion(state.time);
        state.time += dt;
        let (theta, rate, accel) = self.drive.driver_motion(state.time);
        state.hub[1] += 0.5 * dt * state.hub[2];
        state.hub[0] += dt * state.hub[1];
        // Half kick and drift on every DOF, then the hubs set the bore DOFs.
        let phase = Instant::now();
        let frames = [[theta, rate, accel], state.hub];
        self.drift(state, Some(dt), frames);
        self.phase_wall.drift_s += phase.elapsed().as_secs_f64();
        let phase = Instant::now();
        let (body, body_node_power, times) = self.contact_and_body_forces(state, 0.5 * dt, frames);
        self.book_force_phase(phase.elapsed().as_secs_f64(), times);
        let hub_power = self.contact_and_hubs(state);
        state.hub[1] += 0.5 * dt * state.hub[2];
        let phase = Instant::now();
        let node_power =
            body_node_power + self.kick_held(state, Some(dt), [[theta, rate, accel], state.hub]);
        self.phase_wall.accelerate_s += phase.elapsed().as_secs_f64();
        let strain = body[0].strain_energy + body[1].strain_energy + self.block_strain(state);
        let block_damping: f64 = self
            .block_steps
            .iter()
            .flatten()
            .map(|s| s.damping_power)
            .sum();
        let damping_power =
            body[0].damping_power + body[1].damping_power + block_damping + hub_power + node_power;
        // Work: driver reactions, load torque, contact forces (trapezoid).
        let mut work = 0.0;
        for (i, &n) in model.meshes[0].bore_nodes.iter().enumerate() {
            for c in 0..2 {
                let dx = state.x[0][2 * n + c] - self.old_bore_x[2 * i + c];
                work += 0.5 * (self.old_reaction[2 * i + c] + self.driver_reaction[2 * i + c]) * dx;
            }
        }
        // The driver's hub turning its far block.
        work += 0.5 * (self.old_block_torque + self.block_torque) * (theta - old_theta);
        let mean_torque = 0.5 * (old_torque + self.drive.load_torque_at(state.time));
        work += mean_torque * (state.hub[0] - old_phi);
        let transmitted = (mean_torque * model.kinematic_hub_rotation(theta - old_theta)).abs();
        // Contact work on the flanks searched at this step or the last (the only DOFs with
        // forces); x_{n+1} − x_n = Δt v_{n+½} with v_{n+½} = v_{n+1} − ½Δt a_{n+1}.
        let mut contact = 0.0;
        for g in 0..2 {
            self.stamp_id += 1;
            let (v, a) = (&state.v[g], &state.a[g]);
            let (previous, current) = (&self.previous_contact[g], &self.contact_force[g]);
            model.for_flank_dofs(
                g,
                &[&self.searched[0], &self.searched[1]],
                &mut self.node_stamp[g],
                self.stamp_id,
                |d| {
                    let dx = dt * (v[d] - 0.5 * dt * a[d]);
                    contact -= 0.5 * (previous[d] + current[d]) * dx;
                },
            );
        }
        self.steps += 1;
        self.energy.external_work += work;
        self.energy.transmitted_work += transmitted;
        self.energy.contact += contact;
        self.energy.damping += damping_power * dt;
        self.energy.strain = strain;
        self.phase_wall.steps += 1;
        self.phase_wall.step_s += started.elapsed().as_secs_f64();
        if !(state.hub[0].is_finite() && strain.is_finite()) {
            return Err("the state is not finite (NaN or infinity)".into());
        }
        Ok(())
    }

    /// Whether the far blocks' Coriolis couplings hold at `state`'s hub rates
    /// ([`ExplicitPair::far_rates_hold`]): the run stops if not.
    pub fn far_rates_hold(&self, state: &PairState) -> Result<(), String> {
        let (_, rate, _) = self.drive.driver_motion(state.time);
        self.model.far_rates_hold([rate, state.hub[1]])
    }

    /// Stable step of the pair linearized at `state`: Δt_cr = 2/ω_max, ω_max² the largest
    /// eigenvalue of M⁻¹(K_bodies + K_contact) with the bore DOFs held, by power iteration on
    /// M^{-½} K M^{-½}. K is applied without assembling it, as the change of the bodies'
    /// internal forces and of the contact forces under a small perturbation δx, with δv = δx/Δt
    /// so that the sticking friction springs (which see the slip increment) are in K as well.
    /// Penalty contact is linear in the gap, so the product is exact while δx (at most 0.1 nm
    /// per DOF) leaves the set of points in contact as it is. What the step must respect at
    /// this contact state; [`ExplicitPair::contact_critical_step`] bounds every state.
    pub fn coupled_critical_step(&self, state: &PairState, iterations: usize) -> f64 {
        let model = self.model;
        // The whole bodies at the far blocks' state (the reduced blocks, Rayleigh–Ritz models
        // of theirs, hold no higher frequency).
        let expanded;
        let state = if model.far.iter().any(Option::is_some) {
            let (theta, rate, accel) = self.drive.driver_motion(state.time);
            expanded = model.expanded(state, [theta, rate, accel]);
            &expanded
        } else {
            state
        };
        let inv_sqrt_m: [Vec<f64>; 2] =
            std::array::from_fn(|g| model.inverse_mass[g].iter().map(|w| w.sqrt()).collect());
        let mut probe = state.clone();
        let forces = |probe: &PairState| -> [Vec<f64>; 2] {
            let mut f = [vec![0.0; probe.x[0].len()], vec![0.0; probe.x[1].len()]];
            // The two bodies side by side, as in a step (each body's sum is the same on any
            // thread).
            let [f0, f1] = &mut f;
            rayon::join(
                || model.bodies[0].internal_forces(&probe.x[0], &probe.v[0], 0.0, f0),
                || model.bodies[1].internal_forces(&probe.x[1], &probe.v[1], 0.0, f1),
            );
            // The friction history as it stands at `state`, for every evaluation.
            let mut history = self.history.clone();
            let mut out = ContactOutput::default();
            let (x, v) = (&probe.x, &probe.v);
            model.contact_forces(
                [&x[0], &x[1]],
                [&v[0], &v[1]],
                self.dt,
                &mut history,
                &mut f,
                &mut out,
            );
            f
        };
        let base = forces(state);
        // A deterministic start with content in the highest modes: alternating signs.
        let mut y: [Vec<f64>; 2] = std::array::from_fn(|g| {
            (0..inv_sqrt_m[g].len())
                .map(|d| match (inv_sqrt_m[g][d] > 0.0, (d / 2 + d) % 2 == 0) {
                    (false, _) => 0.0,
                    (true, true) => 1.0,
                    (true, false) => -0.7,
                })
                .collect()
        });
        let mut lambda: f64 = 0.0;
        for _ in 0..iterations {
            let norm = y.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
            y.iter_mut().flatten().for_each(|v| *v /= norm);
            // δx = scale · M^{-½} y, its largest component 0.1 nm.
            let largest = (0..2)
                .flat_map(|g| y[g].iter().zip(&inv_sqrt_m[g]).map(|(y, w)| (y * w).abs()))
                .fold(0.0, f64::max);
            let scale = 1e-10 / largest;
            for g in 0..2 {
                for d in 0..y[g].len() {
                    let dx = scale * inv_sqrt_m[g][d] * y[g][d];
                    probe.x[g][d] = state.x[g][d] + dx;
                    probe.v[g][d] = state.v[g][d] + dx / self.dt;
                }
            }
            let perturbed = forces(&probe);
            let z: [Vec<f64>; 2] = std::array::from_fn(|g| {
                (0..y[g].len())
                    .map(|d| -(perturbed[g][d] - base[g][d]) / scale * inv_sqrt_m[g][d])
                    .collect()
            });
            lambda = (0..2)
                .map(|g| y[g].iter().zip(&z[g]).map(|(a, b)| a * b).sum::<f64>())
                .sum();
            y = z;
        }
        2.0 / lambda.sqrt()
    }

    /// Updates the kinetic energy and checks the energy balance: an unstable step creates
    /// energy from nothing, so the balance error then grows with the energy itself. Diverged
    /// when |balance| exceeds 1 % of the largest of the net work put in, the energy present, the
    /// kinetic energy of both gears at the drive's full speed (the last keeps the start of a run,
    /// when little energy is present and the account's O(Δt) start-up error is relatively large,
    /// from tripping the check) and the transmitted work (at low speed the others are small: at
    /// 60 rpm a tenth of a joule, so a discretization error of a millijoule per mesh cycle
    /// would read as divergence). Stable runs stay below 5e-5 of the net work; a step 1.3 × the
    /// critical one on the loaded pair passes 1 % within 0.15 ms (validation/fe-elements).
    pub fn update_energy(&mut self, state: &PairState) -> Result<(), String> {
        self.energy.kinetic = self.kinetic(state);
        let total = self.energy.kinetic + self.energy.strain;
        if !total.is_finite() {
            return Err("the energy is not finite (NaN or infinity)".into());
        }
        let driver_speed = self.drive.driver_speed;
        let driven_speed = self.model.kinematic_hub_rotation(driver_speed);
        let full_speed = 0.5 * self.model.inertia(0) * driver_speed * driver_speed
            + 0.5 * self.model.inertia(1) * driven_speed * driven_speed;
        let scale = self
            .energy
            .external_work
            .abs()
            .max(total)
            .max(full_speed)
            .max(self.energy.transmitted_work)
            + 1e-12;
        let error = self.energy.balance().abs();
        if error > 0.01 * scale {
            return Err(format!(
                "the energy balance is lost: kinetic + strain {total:.3e} J against {:.3e} J of work, an error of {error:.3e} J (the integrator is creating energy)",
                self.energy.external_work
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, SymmetricEigen};
    use proptest::prelude::*;

    /// λ_max of M^-½ Σ_p k_p g_p g_pᵀ M^-½ by a dense eigen-solve, g_p = (±N n_p) on the nodes of
    /// `springs` (first three slave +, last three master −), normals `normals`.
    fn exact_omega(
        springs: &[ClosedSpring],
        normals: &[[f64; 2]],
        inverse_mass: &[Vec<f64>; 2],
    ) -> f64 {
        let dofs = inverse_mass[0].len() + inverse_mass[1].len();
        let index = |g: usize, n: usize, c: usize| g * inverse_mass[0].len() + 2 * n + c;
        let mut a = DMatrix::<f64>::zeros(dofs, dofs);
        for (s, n) in springs.iter().zip(normals) {
            let mut g = vec![0.0; dofs];
            for (k, &(gear, node, w)) in s.nodes.iter().enumerate() {
                let sign = if k < 3 { 1.0 } else { -1.0 };
                for c in 0..2 {
                    g[index(gear, node, c)] +=
                        sign * w * n[c] * inverse_mass[gear][2 * node + c].sqrt();
                }
            }
            let k = s.root_stiffness * s.root_stiffness;
            for i in 0..dofs {
                for j in 0..dofs {
                    a[(i, j)] += k * g[i] * g[j];
                }
            }
        }
        SymmetricEigen::new(a).eigenvalues.max().sqrt()
    }

    fn masses(nodes: usize, seed: f64) -> [Vec<f64>; 2] {
        std::array::from_fn(|g| {
            (0..2 * nodes)
                .map(|d| 1.0 / (0.5 + ((d / 2 + 3 * g) as f64 * 0.37 + seed).sin().abs()))
                .collect()
        })
    }

    /// Held DOFs and runs cover every DOF exactly once, in order, the held ones those of the
    /// nodes given (repeats allowed), at either end and side by side.
    #[test]
    fn split_dofs_covers_every_dof_once() {
        for (nodes, held) in [
            (10, vec![0, 3, 3, 4, 9]),
            (5, vec![]),
            (4, vec![0, 1, 2, 3]),
            (6, vec![5, 2]),
        ] {
            let dofs = 2 * nodes;
            let (held_dofs, runs) = split_dofs(dofs, held.iter().copied());
            let mut seen = vec![0; dofs];
            held_dofs.iter().for_each(|&d| seen[d] += 1);
            runs.iter()
                .flat_map(|r| r.clone())
                .for_each(|d| seen[d] += 1);
            assert!(
                seen.iter().all(|&k| k == 1),
                "{nodes} nodes, held {held:?}: {seen:?}"
            );
            let expected: Vec<usize> = (0..dofs).filter(|d| held.contains(&(d / 2))).collect();
            assert_eq!(held_dofs, expected);
            assert!(runs.iter().all(|r| !r.is_empty()));
        }
    }

    /// One spring alone: the bound is its frequency, k Σ N²/m over its six nodes; two equal
    /// springs on the same nodes along the same normal: twice that in ω² (rank one, so the
    /// eigenvalues add) — exact both times.
    #[test]
    fn the_springs_bound_is_exact_for_one_spring_and_for_two_alike() {
        let inverse_mass = masses(8, 0.3);
        let spring = ClosedSpring {
            root_stiffness: 3.0e4,
            nodes: [
                (0, 1, 0.2),
                (0, 2, 0.7),
                (0, 3, 0.1),
                (1, 4, 0.5),
                (1, 5, 0.5),
                (1, 6, 0.05),
            ],
        };
        let own = (spring.nodes.iter())
            .map(|&(g, n, w)| w * w * inverse_mass[g][2 * n])
            .sum::<f64>()
            * 9.0e8;
        let mut scratch = [Vec::new(), Vec::new()];
        let one = closed_springs_omega(&[spring], &inverse_mass, &mut scratch);
        assert!(
            (one / own.sqrt() - 1.0).abs() < 1e-12,
            "{one} against {}",
            own.sqrt()
        );
        assert!((one / exact_omega(&[spring], &[[0.6, 0.8]], &inverse_mass) - 1.0).abs() < 1e-9);
        let two = closed_springs_omega(&[spring, spring], &inverse_mass, &mut scratch);
        assert!((two / (2.0 * own).sqrt() - 1.0).abs() < 1e-12);
        assert!(
            scratch.iter().flatten().all(|s| *s == 0.0),
            "scratch left zero"
        );
    }

    proptest! {
        /// Springs on overlapping nodes, any normals and masses: the bound is never below the
        /// exact largest eigenvalue, with the sticking points' tangential springs (k_t = k_n)
        /// too.
        #[test]
        fn the_springs_bound_is_above_the_exact_frequency(
            seed in 0.0..10.0f64,
            picks in proptest::collection::vec((0usize..5, 0.0..1.0f64, 0.0..6.3f64, 1.0..100.0f64), 1..6),
        ) {
            let inverse_mass = masses(12, seed);
            let springs: Vec<ClosedSpring> = picks
                .iter()
                .map(|&(first, s, _, k)| {
                    let shape = [s * (s - 1.0) / 2.0, 1.0 - s * s, s * (s + 1.0) / 2.0];
                    ClosedSpring {
                        root_stiffness: k.sqrt(),
                        nodes: [
                            (0, first, shape[0].abs()),
                            (0, first + 1, shape[1].abs()),
                            (0, first + 2, shape[2].abs()),
                            (1, first + 1, shape[2].abs()),
                            (1, first + 2, shape[1].abs()),
                            (1, first + 3, shape[0].abs()),
                        ],
                    }
                })
                .collect();
            let normals: Vec<[f64; 2]> = picks.iter().map(|p| [p.2.cos(), p.2.sin()]).collect();
            let tangents: Vec<[f64; 2]> = normals.iter().map(|n| [-n[1], n[0]]).collect();
            let mut scratch = [Vec::new(), Vec::new()];
            let bound = closed_springs_omega(&springs, &inverse_mass, &mut scratch);
            let exact = exact_omega(&springs, &normals, &inverse_mass);
            prop_assert!(bound >= exact * (1.0 - 1e-9), "{bound} below {exact}");
            let both: Vec<ClosedSpring> = springs.iter().chain(&springs).copied().collect();
            let directions: Vec<[f64; 2]> = normals.iter().chain(&tangents).copied().collect();
            let exact = exact_omega(&both, &directions, &inverse_mass);
            prop_assert!(bound >= exact * (1.0 - 1e-9), "{bound} below {exact} with friction");
        }
    }
}
