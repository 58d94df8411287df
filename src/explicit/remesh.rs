//! Transfer of a body's nodal fields from one mesh of a gear to another mesh of the same gear
//! (the explicit run's windows: the teeth that engage in the next window get fine flanks, those
//! that left it go back to coarse; [`crate::explicit::scene`], "Model no more than the scene
//! needs").
//!
//! Both meshes come from [`crate::mesh::mesh_gear`] with other fine teeth, so every sector that
//! keeps its kind keeps its nodes (to round-off), and the sectors that change kind share their
//! radial edges with their neighbours. A node of the new mesh is
//! * the old node at the same reference point (within [`SAME_NODE`]), whose values it copies, or
//! * a point of an old element: its values are the element's isoparametric interpolation
//!   u(X) = Σ Nᵢ(ξ, η) uᵢ at the natural coordinates of the node's reference point X,
//!   found by Newton's method on X = Σ Nᵢ(ξ, η) Xᵢ.
//!
//! The interpolation reproduces every field linear in X exactly (the isoparametric elements hold
//! X itself), so a rigid motion x = c + R X, v = ω ẑ × (x − c) carries over without error;
//! what a switched tooth loses is the part of its deformation that the other mesh cannot hold
//! (the teeth switch out of contact, where that part is their free ringing).

use nalgebra::Point2;

use crate::fe::q8;
use crate::mesh::GearMesh;

/// Two reference points closer than this [m] are the same node. The meshes of two sets of fine
/// teeth agree on the sectors they share bit for bit, but for about a dozen nodes per gear that
/// differ by up to 1e-10 m (round-off of the mesher's arc-length parametrisation); the
/// elements are 1e-4 m and larger, so distinct nodes are never this close.
pub const SAME_NODE: f64 = 1e-9;

/// How far outside an element's natural square a node may lie and still take the element's
/// values: a new flank node on the exact profile lies up to a hair outside the old mesh's
/// quadratic boundary edge (the coarse edges' chord error, under 1 µm at 3 mm).
const OUTSIDE_TOLERANCE: f64 = 0.05;

/// Where a node of the new mesh takes its values from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Source {
    /// The old node at the same reference point.
    Node(usize),
    /// The old element's nodes with these shape-function weights.
    Element {
        nodes: [usize; 8],
        weights: [f64; 8],
    },
}

/// The sources of every node of one gear's new mesh in its old mesh.
#[derive(Debug, Clone)]
pub struct NodeTransfer {
    pub sources: Vec<Source>,
    /// New nodes interpolated (the others are copied).
    pub interpolated: usize,
}

impl NodeTransfer {
    /// Finds the source of every node of `new` in `old`; fails where a node lies in no element
    /// of `old` (the meshes are not of the same gear).
    pub fn between(old: &GearMesh, new: &GearMesh) -> Result<Self, String> {
        let index = PointIndex::new(&old.nodes);
        let boxes: Vec<[f64; 4]> = old
            .elements
            .iter()
            .map(|e| {
                e.iter().fold(
                    [
                        f64::INFINITY,
                        f64::INFINITY,
                        f64::NEG_INFINITY,
                        f64::NEG_INFINITY,
                    ],
                    |b, &n| {
                        let p = old.nodes[n];
                        [b[0].min(p.x), b[1].min(p.y), b[2].max(p.x), b[3].max(p.y)]
                    },
                )
            })
            .collect();
        let mut interpolated = 0;
        let sources = new
            .nodes
            .iter()
            .map(|p| {
                if let Some(n) = index.find(p) {
                    return Ok(Source::Node(n));
                }
                interpolated += 1;
                locate(old, &boxes, p).ok_or_else(|| {
                    format!(
                        "remeshing: the node at ({:.6e}, {:.6e}) m lies in no element of the \
                         previous mesh",
                        p.x, p.y
                    )
                })
            })
            .collect::<Result<Vec<_>, String>>()?;
        Ok(NodeTransfer {
            sources,
            interpolated,
        })
    }

    /// A field with `width` values per node of the old mesh, transferred to the new mesh.
    pub fn apply(&self, old: &[f64], width: usize) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.sources.len() * width);
        for source in &self.sources {
            match source {
                Source::Node(n) => out.extend_from_slice(&old[width * n..width * (n + 1)]),
                Source::Element { nodes, weights } => {
                    for c in 0..width {
                        out.push(
                            nodes
                                .iter()
                                .zip(weights)
                                .map(|(&n, w)| w * old[width * n + c])
                                .sum(),
                        );
                    }
                }
            }
        }
        out
    }

    /// A field that only copied nodes carry (contact forces, which sit on the flanks in
    /// contact: a switched tooth is out of contact, so its new nodes get zero).
    pub fn copy_or_zero(&self, old: &[f64], width: usize) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.sources.len() * width);
        for source in &self.sources {
            match source {
                Source::Node(n) => out.extend_from_slice(&old[width * n..width * (n + 1)]),
                Source::Element { .. } => out.extend(std::iter::repeat_n(0.0, width)),
            }
        }
        out
    }

    /// The old node a new node copies, if it does.
    pub fn copied_from(&self, new_node: usize) -> Option<usize> {
        match self.sources[new_node] {
            Source::Node(n) => Some(n),
            Source::Element { .. } => None,
        }
    }
}

/// The element of `old` that holds `p` (the least outside its natural square, within
/// [`OUTSIDE_TOLERANCE`]) and the shape-function weights there.
fn locate(old: &GearMesh, boxes: &[[f64; 4]], p: &Point2<f64>) -> Option<Source> {
    let mut best: Option<(f64, Source)> = None;
    for (e, b) in old.elements.iter().zip(boxes) {
        let pad = OUTSIDE_TOLERANCE * (b[2] - b[0]).max(b[3] - b[1]);
        if p.x < b[0] - pad || p.x > b[2] + pad || p.y < b[1] - pad || p.y > b[3] + pad {
            continue;
        }
        let xe = e.map(|n| old.nodes[n]);
        let Some((xi, eta)) = natural_coordinates(&xe, p) else {
            continue;
        };
        let outside = (xi.abs().max(eta.abs()) - 1.0).max(0.0);
        if outside <= OUTSIDE_TOLERANCE && best.as_ref().is_none_or(|(o, _)| outside < *o) {
            best = Some((
                outside,
                Source::Element {
                    nodes: *e,
                    weights: q8::shape(xi, eta),
                },
            ));
        }
    }
    best.map(|(_, s)| s)
}

/// Natural coordinates (ξ, η) of `p` in the Q8 element `xe`: Newton on Σ Nᵢ(ξ, η) Xᵢ = p from
/// the centre, converged to 1e-12; None when it does not converge (a point far outside).
pub fn natural_coordinates(xe: &[Point2<f64>; 8], p: &Point2<f64>) -> Option<(f64, f64)> {
    let (mut xi, mut eta) = (0.0, 0.0);
    for _ in 0..30 {
        let n = q8::shape(xi, eta);
        let d = q8::shape_derivatives(xi, eta);
        let (mut rx, mut ry) = (-p.x, -p.y);
        let (mut j11, mut j12, mut j21, mut j22) = (0.0, 0.0, 0.0, 0.0);
        for i in 0..8 {
            rx += n[i] * xe[i].x;
            ry += n[i] * xe[i].y;
            j11 += d[i].0 * xe[i].x;
            j12 += d[i].1 * xe[i].x;
            j21 += d[i].0 * xe[i].y;
            j22 += d[i].1 * xe[i].y;
        }
        let det = j11 * j22 - j12 * j21;
        if det.abs() < f64::MIN_POSITIVE {
            return None;
        }
        let dxi = (j22 * rx - j12 * ry) / det;
        let deta = (-j21 * rx + j11 * ry) / det;
        xi -= dxi;
        eta -= deta;
        if !(xi.is_finite() && eta.is_finite()) || xi.abs() > 3.0 || eta.abs() > 3.0 {
            return None;
        }
        if dxi.abs().max(deta.abs()) < 1e-12 {
            return Some((xi, eta));
        }
    }
    None
}

/// Reference points hashed on a grid of cells [`SAME_NODE`] × 1000 wide, for finding a point's
/// twin among them.
pub(crate) struct PointIndex<'a> {
    points: &'a [Point2<f64>],
    cells: std::collections::HashMap<(i64, i64), Vec<usize>>,
}

impl<'a> PointIndex<'a> {
    const CELL: f64 = SAME_NODE * 1000.0;

    fn cell(p: &Point2<f64>) -> (i64, i64) {
        (
            (p.x / Self::CELL).floor() as i64,
            (p.y / Self::CELL).floor() as i64,
        )
    }

    pub(crate) fn new(points: &'a [Point2<f64>]) -> Self {
        let mut cells: std::collections::HashMap<(i64, i64), Vec<usize>> =
            std::collections::HashMap::new();
        for (i, p) in points.iter().enumerate() {
            cells.entry(Self::cell(p)).or_default().push(i);
        }
        PointIndex { points, cells }
    }

    /// The point within [`SAME_NODE`] of `p`, if any (the cell and its neighbours).
    pub(crate) fn find(&self, p: &Point2<f64>) -> Option<usize> {
        let (cx, cy) = Self::cell(p);
        (-1..=1)
            .flat_map(|dx| (-1..=1).map(move |dy| (cx + dx, cy + dy)))
            .filter_map(|c| self.cells.get(&c))
            .flatten()
            .copied()
            .find(|&i| (self.points[i] - p).norm() < SAME_NODE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::case::Case;
    use crate::geometry::FlankModification;
    use crate::mesh::{mesh_gear, MeshSpec};
    use nalgebra::{Rotation2, Vector2};

    fn meshes() -> (GearMesh, GearMesh) {
        let case = Case::load_with(None, &[]).unwrap();
        let gear = &case.pair.gears[0];
        let spec = |fine_teeth: Vec<usize>| MeshSpec {
            fine_size: 1.5e-3,
            coarse_size: 3e-3,
            fine_teeth,
            layout: crate::mesh::ToothLayout::Graded,
        };
        let m = FlankModification::default();
        (
            mesh_gear(gear, &m, &spec(vec![0, 1, 2])),
            mesh_gear(gear, &m, &spec(vec![1, 2, 3])),
        )
    }

    /// A rigid motion x = c + R X, v = ω ẑ × (x − c) goes from one mesh to the other exactly, on
    /// the copied and on the interpolated nodes, up to the meshes' own round-off: a dozen shared
    /// nodes of the two meshes differ by about 1e-10 m (0.1 m × 1e-9 here); a copied node keeps
    /// its old value bit for bit.
    #[test]
    fn a_rigid_motion_carries_over_exactly() {
        let (old, new) = meshes();
        let transfer = NodeTransfer::between(&old, &new).unwrap();
        // Tooth 0 went coarse, tooth 3 fine: both sectors' interiors are new.
        assert!(transfer.interpolated > 50, "{}", transfer.interpolated);
        assert!(transfer.interpolated < new.nodes.len() / 4);
        let (c, angle, omega) = (Vector2::new(0.01, -0.02), 0.7, 314.0);
        let rotation = Rotation2::new(angle);
        let motion = |p: &Point2<f64>| {
            let x = c + rotation * p.coords;
            let r = x - c;
            [x.x, x.y, -omega * r.y, omega * r.x]
        };
        let old_field: Vec<f64> = old.nodes.iter().flat_map(motion).collect();
        let moved = transfer.apply(&old_field, 4);
        let mut worst: f64 = 0.0;
        for (i, p) in new.nodes.iter().enumerate() {
            let exact = motion(p);
            for k in 0..4 {
                let scale = if k < 2 { 0.1 } else { 0.1 * omega };
                worst = worst.max((moved[4 * i + k] - exact[k]).abs() / scale);
            }
            if let Some(n) = transfer.copied_from(i) {
                assert_eq!(moved[4 * i], old_field[4 * n]);
            }
        }
        assert!(worst < 1e-8, "worst relative error {worst:e}");
    }

    /// The copy-or-zero transfer copies the copied nodes' values and leaves the interpolated
    /// ones at zero.
    #[test]
    fn copy_or_zero_zeroes_only_the_new_nodes() {
        let (old, new) = meshes();
        let transfer = NodeTransfer::between(&old, &new).unwrap();
        let old_field: Vec<f64> = (0..2 * old.nodes.len()).map(|i| 1.0 + i as f64).collect();
        let zeroed = transfer.copy_or_zero(&old_field, 2);
        for i in 0..new.nodes.len() {
            match transfer.copied_from(i) {
                Some(n) => assert_eq!(zeroed[2 * i..2 * i + 2], old_field[2 * n..2 * n + 2]),
                None => assert_eq!(zeroed[2 * i..2 * i + 2], [0.0, 0.0]),
            }
        }
    }

    /// A point of an element is found at its natural coordinates.
    #[test]
    fn natural_coordinates_invert_the_map() {
        let (old, _) = meshes();
        for e in old.elements.iter().step_by(97) {
            let xe = e.map(|n| old.nodes[n]);
            let (xi0, eta0) = (0.3, -0.55);
            let n = q8::shape(xi0, eta0);
            let p = Point2::from((0..8).map(|i| n[i] * xe[i].coords).sum::<Vector2<f64>>());
            let (xi, eta) = natural_coordinates(&xe, &p).unwrap();
            assert!((xi - xi0).abs() < 1e-10 && (eta - eta0).abs() < 1e-10);
        }
    }
}
