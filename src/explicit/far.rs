//! A gear's far body in the explicit pair: the coarse sectors of a window's mesh, which no
//! contact reaches while the window lasts, as one reduced block ([`super::reduced`]) turning
//! with the gear's hub, the fine sectors in full (the case's `fe.far_body = "reduced"`).
//!
//! # Where the block sits
//! The block is built on the mesh of one window and kept for every later window whose fine
//! teeth form the same pattern (the same teeth relative to the first of their run): by the
//! gear's cyclic symmetry that window's coarse sectors are the first's turned by a whole number
//! of pitches δ = (t₀ − t₀′) · 2π/z, t₀ and t₀′ the patterns' first teeth. A mesh node of the
//! block then lies at R(δ) X, X its reference in the block's own frame, and a block node
//! of gear g is at
//! ```text
//! x = c + R(φ) (X + u),   ẋ = R(φ) (u̇ + ω J (X + u)),   φ = ψ_g + θ_g + δ
//! ```
//! with ψ_g the gear's placement, θ_g its hub rotation, ω its rate and u the block's
//! displacement in its frame (module doc of [`super::reduced`]). Each node is found by its
//! position in the new mesh, and its mass must be the block's: a mesh that differs (another
//! layout of the pattern's neighbours) gets a block of its own.
//!
//! # What it saves, what it costs
//! The block's elements leave the step's element loop, its internal nodes the drift and the
//! kicks; the block's step (two products with its interface modes, one with its gyroscopic
//! matrix among the modes where the Coriolis term matters) takes their place. Its motion is
//! the Craig–Bampton model's: exact for static interface loads and for the rigid turning
//! (centrifugal, Euler terms; the Coriolis couplings to within ε = 1e-3 while the hub turns
//! below [`RATE_BOUND_FACTOR`] times its speed, a run stopped with a message beyond), the
//! body's own vibration to the cutoff, quasi-static above it.

use std::sync::Arc;

use nalgebra::{Point2, Rotation2, Vector2};

use crate::fe::assembly::FeError;
use crate::mesh::GearMesh;

use super::body::ExplicitMaterial;
use super::reduced::{BlockNodes, BlockState, Cutoff, ReducedBlock};
use super::remesh::PointIndex;

/// How a run models each gear's body away from the contact (the case's `fe.far_body`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FarBody {
    /// Every element in the explicit step.
    Full,
    /// The coarse sectors of a run on windows of fine teeth as one reduced block per gear
    /// (module doc), its fixed-interface modes kept to a multiple of the fine sectors' lowest
    /// (the case's `fe.far_block_cutoff`, default [`FAR_BLOCK_CUTOFF`]). The default since
    /// 2026-12-06: within the windows' tolerances of the full bodies on the paper's pair at
    /// 3000 rpm and on 24/40 and 40/24 at 12 000 rpm, and about a fifth faster on the paper's
    /// 3000 rpm scene. Runs on one mesh (no windows) keep their bodies full either way.
    #[default]
    Reduced,
}

/// The cutoff of a far block's fixed-interface modes over the lowest mode of the fine sectors
/// beside it (held at the block and the bore: the sectors that carry the contact, as the
/// block sees them; [`super::reduced::lowest_mode_beside_block`]). The block feeds those teeth and is
/// fed by them, so it keeps its own modes to several times the frequency they vibrate at.
/// Against the full bodies on the coarse windows at 12 000 rpm (tests/explicit_pair.rs), the
/// DTE's rms difference over its peak-to-peak at 5, 6, 7, 8 times: 1.90, 1.21, 0.80, 0.54 % on
/// 40/24 and 0.24, 0.13, 0.08, 0.05 % on 24/40 (the windows' tolerance 2 %;
/// validation/performance, lever 2f). The rule it replaces, a multiple of the block's own lowest
/// mode, did not follow the gears: a large gear's rim has a low lowest mode (11 kHz on the
/// 40-tooth gear), so 16 times left 40/24's DTE peak-to-peak 2.9 % off, while the stiff
/// 24-tooth gear kept its modes to 500 kHz for nothing. On the paper's driver at its real mesh
/// (fine sectors' lowest 31–45 kHz with the window's pattern) 6 times keeps its modes to
/// 190–270 kHz, where 16 times its lowest kept them to 214–225 kHz.
pub const FAR_BLOCK_CUTOFF: f64 = 6.0;

/// How many times its nominal speed a gear's hub may turn before its far block's Coriolis
/// couplings no longer hold ([`ReducedBlock::new`]: they are kept among the own modes below
/// 2 ω_max / ε, ω_max this many times the speed; they then hold up to ε/2 times the first mode
/// left out, [`ReducedBlock::rate_bound`]); the explicit run stops, its results kept, when a
/// hub turns faster. A meshing pair's speeds move by a fraction of a per cent (the DTE's rate;
/// the 3000 rpm scene's driven hub peaks at 1.01 times its speed), so twice leaves room for
/// the spin-up's overshoot and for rattle.
pub const RATE_BOUND_FACTOR: f64 = 2.0;

/// The hubs' rate bounds [rad/s] of a pair whose driver turns at `driver_speed` [rad/s]:
/// [`RATE_BOUND_FACTOR`] times each gear's nominal speed (the driven gear's by the ratio
/// `teeth[0] / teeth[1]`).
pub fn rate_bounds(driver_speed: f64, teeth: [usize; 2]) -> [f64; 2] {
    let driver = RATE_BOUND_FACTOR * driver_speed.abs();
    [driver, driver * teeth[0] as f64 / teeth[1] as f64]
}

/// A far block placed in one mesh.
#[derive(Debug, Clone)]
pub struct FarBlock {
    pub block: Arc<ReducedBlock>,
    /// δ: the mesh frame's turn onto the block's frame [rad] (module doc).
    pub offset: f64,
    /// This mesh's nodes of the block's interface and internal nodes, in the block's orders.
    pub interface: Vec<usize>,
    pub internal: Vec<usize>,
}

/// The blocks built so far, by gear and pattern of fine teeth, at one cutoff.
#[derive(Debug)]
pub struct BlockCache {
    /// The blocks' cutoff over the lowest mode of the fine sectors beside them.
    pub cutoff: f64,
    /// The largest |ω| each gear's hub may reach [rad/s]: its blocks keep their Coriolis
    /// couplings for it ([`ReducedBlock::new`]), and the explicit pair stops a run that
    /// turns faster.
    pub rate_bounds: [f64; 2],
    entries: Vec<CachedBlock>,
    /// Blocks built, and blocks found in the cache.
    pub built: usize,
    pub reused: usize,
}

/// Where a cached block was built: its gear and the fine teeth of that window's mesh. A
/// checkpoint keeps the cache's seeds, and a resumed run builds the same blocks from them (the
/// build is deterministic), so that its blocks' states mean what they meant.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct BlockSeed {
    pub gear: usize,
    pub fine_teeth: Vec<usize>,
}

impl BlockCache {
    /// Where each cached block was built.
    pub fn seeds(&self, teeth: [usize; 2]) -> Vec<BlockSeed> {
        self.entries
            .iter()
            .map(|e| BlockSeed {
                gear: e.gear,
                fine_teeth: e
                    .pattern
                    .iter()
                    .map(|p| (e.first_tooth + p) % teeth[e.gear])
                    .collect(),
            })
            .collect()
    }

    /// An empty cache of blocks cut off at `cutoff` times the lowest mode of the fine sectors
    /// beside them, for hubs turning at most at `rate_bounds` [rad/s].
    pub fn new(cutoff: f64, rate_bounds: [f64; 2]) -> Self {
        BlockCache {
            cutoff,
            rate_bounds,
            entries: Vec::new(),
            built: 0,
            reused: 0,
        }
    }
}

#[derive(Debug)]
struct CachedBlock {
    gear: usize,
    pattern: Vec<usize>,
    /// The first tooth of the pattern in the mesh the block was built on.
    first_tooth: usize,
    block: Arc<ReducedBlock>,
    /// The masses of its interface and internal nodes [kg].
    interface_mass: Vec<f64>,
    internal_mass: Vec<f64>,
}

/// The fine teeth `fine` of a gear of `teeth` teeth as a pattern: every fine tooth's place
/// after a first one, the first tooth of a run of fine teeth (its predecessor coarse) whose
/// pattern is the least (so the pattern is the same however the teeth are turned), and that
/// tooth. None if every tooth is fine.
fn pattern_of(fine: &[usize], teeth: usize) -> Option<(usize, Vec<usize>)> {
    let mut is_fine = vec![false; teeth];
    fine.iter().for_each(|&t| is_fine[t % teeth] = true);
    let relative_to = |first: usize| -> Vec<usize> {
        let mut pattern: Vec<usize> = (0..teeth)
            .filter(|&t| is_fine[t])
            .map(|t| (t + teeth - first) % teeth)
            .collect();
        pattern.sort_unstable();
        pattern
    };
    (0..teeth)
        .filter(|&t| is_fine[t] && !is_fine[(t + teeth - 1) % teeth])
        .map(|first| (first, relative_to(first)))
        .min_by(|a, b| a.1.cmp(&b.1).then(a.0.cmp(&b.0)))
}

/// What [`BlockCache::lookup`] found for a gear's mesh.
pub enum Lookup {
    /// A cached block, placed in the mesh.
    Found(FarBlock),
    /// None fits: the block to build ([`BlockRequest::build`]), then [`BlockCache::insert`].
    Build(BlockRequest),
    /// Every tooth is fine: no far body.
    AllFine,
}

/// A far block to build: its gear, pattern of fine teeth and elements.
pub struct BlockRequest {
    gear: usize,
    first_tooth: usize,
    pattern: Vec<usize>,
    in_block: Vec<bool>,
}

impl BlockRequest {
    /// The block of `mesh` with nodal masses `mass` (the whole mesh's): every element outside
    /// the fine sectors, the bore held, its modes to `cutoff` times the fine sectors' lowest
    /// ([`Cutoff::BesideBlockTimes`]), its Coriolis couplings for a hub turning at most at
    /// `rate_bound` [rad/s].
    pub fn build(
        &self,
        mesh: &GearMesh,
        mass: &[f64],
        material: &ExplicitMaterial,
        cutoff: f64,
        rate_bound: f64,
    ) -> Result<ReducedBlock, FeError> {
        ReducedBlock::new(
            &mesh.nodes,
            &mesh.elements,
            &self.in_block,
            &mesh.bore_nodes,
            mass,
            material,
            Cutoff::BesideBlockTimes(cutoff),
            rate_bound,
        )
    }
}

impl BlockCache {
    /// The far block of gear `gear` (`teeth` teeth) meshed as `mesh` with nodal masses `mass`
    /// (the whole mesh's): a cached block of the same pattern of fine teeth placed in the
    /// mesh, if one fits it, else what to build.
    pub fn lookup(&mut self, gear: usize, teeth: usize, mesh: &GearMesh, mass: &[f64]) -> Lookup {
        let Some((first_tooth, pattern)) = pattern_of(&mesh.fine_teeth, teeth) else {
            return Lookup::AllFine;
        };
        let in_block: Vec<bool> = mesh.element_fine.iter().map(|f| !f).collect();
        if let Some(entry) = self
            .entries
            .iter()
            .find(|e| e.gear == gear && e.pattern == pattern)
        {
            let nodes = BlockNodes::of(
                mesh.nodes.len(),
                &mesh.elements,
                &in_block,
                &mesh.bore_nodes,
            );
            let turns = (first_tooth + teeth - entry.first_tooth) % teeth;
            let offset = turns as f64 * std::f64::consts::TAU / teeth as f64;
            if let Some(placed) = place(entry, offset, mesh, mass, &nodes) {
                self.reused += 1;
                return Lookup::Found(placed);
            }
        }
        Lookup::Build(BlockRequest {
            gear,
            first_tooth,
            pattern,
            in_block,
        })
    }

    /// `block`, built for `request` on a mesh with nodal masses `mass`, kept for the later
    /// windows of its pattern (in place of one that did not fit); placed in that mesh.
    pub fn insert(&mut self, request: BlockRequest, block: ReducedBlock, mass: &[f64]) -> FarBlock {
        let BlockRequest {
            gear,
            first_tooth,
            pattern,
            ..
        } = request;
        let entry = CachedBlock {
            gear,
            pattern,
            first_tooth,
            interface_mass: block.interface.iter().map(|&n| mass[n]).collect(),
            internal_mass: block.internal.iter().map(|&n| mass[n]).collect(),
            block: Arc::new(block),
        };
        let placed = FarBlock {
            block: entry.block.clone(),
            offset: 0.0,
            interface: entry.block.interface.clone(),
            internal: entry.block.internal.clone(),
        };
        self.entries
            .retain(|e| !(e.gear == entry.gear && e.pattern == entry.pattern));
        self.entries.push(entry);
        self.built += 1;
        placed
    }
}

impl FarBlock {
    /// The block frame's angle φ of a gear placed at `placement` [rad] turned by its hub
    /// `hub` [rad] (module doc).
    pub fn frame_angle(&self, placement: f64, hub: f64) -> f64 {
        placement + hub + self.offset
    }

    /// Writes the interface nodes' positions and velocities into `x`, `v` (the gear's arrays)
    /// from the block's u_b, u̇_b (`displacement`, `rate`, block frame) with the frame at
    /// angle `angle` turning at `omega` about `centre`.
    pub fn place_interface(
        &self,
        frame: (Point2<f64>, f64, f64),
        (displacement, rate): (&[f64], &[f64]),
        x: &mut [f64],
        v: &mut [f64],
    ) {
        let nodes = (&self.interface[..], self.block.interface_reference());
        place_nodes(frame, nodes, (displacement, rate), x, v);
    }

    /// The forces `f` (the gear's array, global frame) on the interface nodes, turned into
    /// the block frame at `angle`, into `out`; their entries of `f` cleared for the next
    /// step's sums.
    pub fn take_interface_force(&self, angle: f64, f: &mut [f64], out: &mut [f64]) {
        let back = Rotation2::new(-angle);
        for (k, &n) in self.interface.iter().enumerate() {
            let local = back * Vector2::new(f[2 * n], f[2 * n + 1]);
            out[2 * k] = local.x;
            out[2 * k + 1] = local.y;
            f[2 * n] = 0.0;
            f[2 * n + 1] = 0.0;
        }
    }

    /// Writes every block node's position and velocity into `x`, `v` from the block `state`
    /// (the frame at `angle` turning at `omega` about `centre`): for what reads the whole mesh
    /// (remeshing, the pair's coupled step).
    pub fn expand(
        &self,
        state: &BlockState,
        frame: (Point2<f64>, f64, f64),
        x: &mut [f64],
        v: &mut [f64],
    ) {
        let block = &self.block;
        let (z, z_rate) = (
            block.coordinates(&state.eta),
            block.coordinates(&state.rate),
        );
        // z's first entries are u_b.
        let nb = block.interface_dofs();
        self.place_interface(frame, (&z.as_slice()[..nb], &z_rate.as_slice()[..nb]), x, v);
        let (u_i, w_i) = (
            block.internal_displacements(&z),
            block.internal_displacements(&z_rate),
        );
        let nodes = (&self.internal[..], block.internal_reference());
        place_nodes(frame, nodes, (u_i.as_slice(), w_i.as_slice()), x, v);
    }

    /// The block's state of the mesh's positions `x` and velocities `v` (the frame at
    /// `angle` turning at `omega` about `centre`): the displacements in the block frame
    /// projected on its basis ([`ReducedBlock::project`]; exact for a state of its span).
    pub fn project(
        &self,
        (centre, angle, omega): (Point2<f64>, f64, f64),
        x: &[f64],
        v: &[f64],
    ) -> BlockState {
        let back = Rotation2::new(-angle);
        let local = |nodes: &[usize], reference: &[Point2<f64>]| -> (Vec<f64>, Vec<f64>) {
            let mut u = Vec::with_capacity(2 * nodes.len());
            let mut w = Vec::with_capacity(2 * nodes.len());
            for (&n, p) in nodes.iter().zip(reference) {
                let y = back * Vector2::new(x[2 * n] - centre.x, x[2 * n + 1] - centre.y);
                let dy = back * Vector2::new(v[2 * n], v[2 * n + 1]);
                u.extend([y.x - p.x, y.y - p.y]);
                // u̇ = ẏ − ω J y
                w.extend([dy.x + omega * y.y, dy.y - omega * y.x]);
            }
            (u, w)
        };
        let block = &self.block;
        let (u_b, w_b) = local(&self.interface, block.interface_reference());
        let (u_i, w_i) = local(&self.internal, block.internal_reference());
        let z = block.project(&u_b, &u_i);
        let z_rate = block.project(&w_b, &w_i);
        block.state_of(&z, &z_rate)
    }
}

/// Writes the mesh nodes `nodes` (with their references in the block frame) at the block
/// displacements `displacement` and rates `rate` (x and y per node) into `x`, `v`, the frame
/// at angle φ turning at ω about c: x = c + R(φ)(X + u), ẋ = R(φ)(u̇ + ω J (X + u)).
fn place_nodes(
    (centre, angle, omega): (Point2<f64>, f64, f64),
    (nodes, reference): (&[usize], &[Point2<f64>]),
    (displacement, rate): (&[f64], &[f64]),
    x: &mut [f64],
    v: &mut [f64],
) {
    let turn = Rotation2::new(angle);
    for (k, (&n, p)) in nodes.iter().zip(reference).enumerate() {
        let y = Vector2::new(p.x + displacement[2 * k], p.y + displacement[2 * k + 1]);
        let relative = Vector2::new(rate[2 * k] - omega * y.y, rate[2 * k + 1] + omega * y.x);
        let (q, w) = (centre + turn * y, turn * relative);
        x[2 * n] = q.x;
        x[2 * n + 1] = q.y;
        v[2 * n] = w.x;
        v[2 * n + 1] = w.y;
    }
}

/// `entry`'s block placed in `mesh` turned by `offset`, if every block node of it is a node of
/// the mesh with the same mass and the mesh's block has no other node.
fn place(
    entry: &CachedBlock,
    offset: f64,
    mesh: &GearMesh,
    mass: &[f64],
    nodes: &BlockNodes,
) -> Option<FarBlock> {
    let block = &entry.block;
    if nodes.interface.len() != block.interface.len()
        || nodes.internal.len() != block.internal.len()
    {
        return None;
    }
    let index = PointIndex::new(&mesh.nodes);
    let turn = Rotation2::new(offset);
    let find = |reference: &[Point2<f64>], masses: &[f64]| -> Option<Vec<usize>> {
        reference
            .iter()
            .zip(masses)
            .map(|(p, m)| {
                let n = index.find(&Point2::from(turn * p.coords))?;
                ((mass[n] - m).abs() <= 1e-9 * m.abs()).then_some(n)
            })
            .collect()
    };
    let interface = find(block.interface_reference(), &entry.interface_mass)?;
    let internal = find(block.internal_reference(), &entry.internal_mass)?;
    let same = |found: &[usize], own: &[usize]| {
        let mut sorted = found.to_vec();
        sorted.sort_unstable();
        sorted == own
    };
    (same(&interface, &nodes.interface) && same(&internal, &nodes.internal)).then(|| FarBlock {
        block: block.clone(),
        offset,
        interface,
        internal,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::explicit::body::ExplicitBody;
    use crate::samples;

    /// The paper's driver meshed with `fine` teeth fine, its nodal masses and material.
    fn driver(fine: Vec<usize>) -> (GearMesh, Vec<f64>, ExplicitMaterial) {
        let case = samples::paper36_case();
        let mesh = samples::explicit_gear_mesh(&case, 0, fine);
        let mut material = case.explicit_material();
        material.thickness = case.pair.gears[0].spec.face_width;
        let body = ExplicitBody::new(&mesh.nodes, &mesh.elements, material).unwrap();
        (mesh, body.mass, material)
    }

    /// A block built on one window is found for a window of the same pattern five pitches on,
    /// turned by five pitches onto the mesh's nodes of the same masses; a window of another
    /// pattern gets a block of its own.
    #[test]
    fn a_cached_block_is_turned_into_a_later_window_of_its_pattern() {
        let mut cache = BlockCache::new(3.0, [f64::INFINITY; 2]);
        let (first, mass, material) = driver((0..6).collect());
        let request = match cache.lookup(0, 36, &first, &mass) {
            Lookup::Build(request) => request,
            _ => panic!("an empty cache builds"),
        };
        let block = request
            .build(&first, &mass, &material, 3.0, f64::INFINITY)
            .unwrap();
        cache.insert(request, block, &mass);
        let (later, later_mass, _) = driver((5..11).collect());
        let Lookup::Found(placed) = cache.lookup(0, 36, &later, &later_mass) else {
            panic!("the same pattern five pitches on is the cached block's");
        };
        let pitch = std::f64::consts::TAU / 36.0;
        assert!((placed.offset - 5.0 * pitch).abs() < 1e-12);
        let turn = Rotation2::new(placed.offset);
        let block = &placed.block;
        for (nodes, reference) in [
            (&placed.interface, block.interface_reference()),
            (&placed.internal, block.internal_reference()),
        ] {
            for (&n, p) in nodes.iter().zip(reference) {
                assert!((later.nodes[n] - Point2::from(turn * p.coords)).norm() < 1e-9);
            }
        }
        // Its interface: the nodes the later window's fine and coarse sectors share.
        let in_block: Vec<bool> = later.element_fine.iter().map(|f| !f).collect();
        let own = BlockNodes::of(
            later.nodes.len(),
            &later.elements,
            &in_block,
            &later.bore_nodes,
        );
        let mut interface = placed.interface.clone();
        interface.sort_unstable();
        assert_eq!(interface, own.interface);
        assert_eq!((cache.built, cache.reused), (1, 1));
        let (other, other_mass, _) = driver((0..7).collect());
        assert!(matches!(
            cache.lookup(0, 36, &other, &other_mass),
            Lookup::Build(_)
        ));
    }

    /// A block state written onto the mesh's nodes (turned and spinning) and projected back
    /// is the same state: the frame's turn and spin come off exactly.
    #[test]
    fn a_block_state_expanded_and_projected_comes_back() {
        let (mesh, mass, material) = driver((3..9).collect());
        let mut cache = BlockCache::new(3.0, [f64::INFINITY; 2]);
        let Lookup::Build(request) = cache.lookup(0, 36, &mesh, &mass) else {
            panic!("an empty cache builds");
        };
        let block = request
            .build(&mesh, &mass, &material, 3.0, f64::INFINITY)
            .unwrap();
        let placed = cache.insert(request, block, &mass);
        let n = placed.block.dofs();
        let z = nalgebra::DVector::from_fn(n, |k, _| 1e-7 * (0.4 + 0.77 * k as f64).sin());
        let z_rate = nalgebra::DVector::from_fn(n, |k, _| 1e-3 * (1.1 + 0.31 * k as f64).cos());
        let state = placed.block.state_of(&z, &z_rate);
        let frame = (Point2::new(0.02, -0.07), 0.83, 314.0);
        let (mut x, mut v) = (
            vec![0.0; 2 * mesh.nodes.len()],
            vec![0.0; 2 * mesh.nodes.len()],
        );
        placed.expand(&state, frame, &mut x, &mut v);
        let back = placed.project(frame, &x, &v);
        let worst = |a: &[f64], b: &[f64]| {
            a.iter()
                .zip(b)
                .map(|(p, q)| (p - q).abs())
                .fold(0.0, f64::max)
                / b.iter().fold(0.0_f64, |m, q| m.max(q.abs()))
        };
        assert!(
            worst(&back.eta, &state.eta) < 1e-7,
            "{}",
            worst(&back.eta, &state.eta)
        );
        assert!(
            worst(&back.rate, &state.rate) < 1e-7,
            "{}",
            worst(&back.rate, &state.rate)
        );
    }

    #[test]
    fn a_pattern_starts_at_the_first_tooth_of_its_first_run() {
        assert_eq!(pattern_of(&[3, 4, 5], 10), Some((3, vec![0, 1, 2])));
        // Wrapping around tooth 0.
        assert_eq!(pattern_of(&[0, 1, 9], 10), Some((9, vec![0, 1, 2])));
        // Two runs: the start of the least pattern, the same for the teeth turned.
        assert_eq!(pattern_of(&[2, 3, 7], 10), Some((2, vec![0, 1, 5])));
        assert_eq!(pattern_of(&[7, 8, 2], 10), Some((7, vec![0, 1, 5])));
        assert_eq!(pattern_of(&(0..10).collect::<Vec<_>>(), 10), None);
    }
}
