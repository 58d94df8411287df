//! 2D finite-element mesh of a gear: 8-node quadratic (serendipity) quadrilaterals, graded —
//! fine along the flanks and fillets of the teeth that engage in the analysis, coarse elsewhere —
//! from the (modified) rack-generated profile down to the bore.
//!
//! # Layout of one tooth sector (tooth-local frame, the sector spans θ ∈ [−π/z, π/z])
//! * **Tooth block**: a transfinite (Coons) patch between the two side curves — the upper
//!   fillet from F* (where the fillet tangent is 45° from radial) to the form point, then the
//!   flank to the tip — with the tip arc on top and the chord F*_R F*_L at the bottom. Rows join
//!   mirror points of the two sides, so the elements follow the tooth; across the tooth the
//!   intervals grow geometrically from the flanks inwards.
//! * **Base block**: from the bore up to the curve root arc → lower fillet → chord → lower fillet
//!   → root arc, meshed along radial rays through the nodes of that curve, with layers that thin
//!   geometrically towards the root (one layer distribution for all sectors, so neighbouring
//!   sectors share the nodes of their common radial edge). Going down, the columns merge three
//!   into one through 3-to-1 transition units once every triple of the sector has become narrow
//!   against the layer thickness, so the fine columns under an engaging tooth do not run as
//!   slivers down to the bore (they would set the explicit time step and waste DOFs); the layers
//!   grow to the coarse size.
//!
//! Splitting the fillet at F* keeps the corners of both blocks well away from 180° (the fillet
//! meets the root circle tangentially). Coincident nodes of neighbouring blocks are merged.
//! Element node order: corners counter-clockwise, then the mid-side nodes of edges 0-1, 1-2, 2-3,
//! 3-0 (the VTK_QUADRATIC_QUAD order).

pub mod grading;
pub mod merge;

use nalgebra::{Point2, Rotation2, Vector2};
use std::f64::consts::PI;

use crate::geometry::{FlankModification, Gear, Side};
use grading::{symmetric_graded_fractions, uniform_fractions, with_midpoints};
use merge::NodeMerger;

/// How fine to mesh a gear.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshSpec {
    /// Element size along the flanks and fillets of the fine teeth [m].
    pub fine_size: f64,
    /// Element size on the other teeth, and the radial size the body's layers grow to below
    /// the teeth (a column there is at most twice as wide as its layer is thick) [m].
    pub coarse_size: f64,
    /// Teeth meshed fine (tooth k is the reference tooth turned counter-clockwise by k·2π/z).
    pub fine_teeth: Vec<usize>,
    /// How each tooth block is laid out.
    pub layout: ToothLayout,
}

/// How the tooth block's rows and columns are laid out. The flank's nodes (form point to tip
/// corner) are the same in both.
///
/// No `Default`: the case's (`fe.tooth_layout`, stable-step) and a summary's without the key
/// (graded, [`crate::report::compare::summary_tooth_layout`]) differ, so each is named where
/// it is used.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ToothLayout {
    /// Columns graded from both flanks at the chord and at the tip alike (so the column at a
    /// flank narrows towards the tip by the tip land over the chord, to a third on the seed
    /// paper's teeth), the upper fillet's rows placed by its parameter: the static meshes'
    /// (LTCA, modal) layout, and the explicit runs' until 2026-12-06 (`fe.tooth_layout =
    /// "graded"`); the layout of older run summaries without the key.
    Graded,
    /// The explicit runs' default (`fe.tooth_layout`), for the explicit FE, whose stable step
    /// its thinnest elements set (validation/
    /// performance, "Which elements make the 3000 rpm step"): the columns graded at the chord
    /// and even at the tip, blended between them along the tooth, and the upper fillet's rows
    /// of equal arc length. On the paper's teeth at 1 mm flanks Irons' bound of the least
    /// tooth element goes from 2.17e-8 to 2.92e-8 s; on 24/40's 24-tooth gear the least is a
    /// row it leaves as it is: the flank's first, 0.40 mm long, because the flank's rows are
    /// even in roll angle ξ and a row's length r_b ξ Δξ is short near the base circle (a
    /// small form roll angle; tests/gear_mesh.rs). Not for the static meshes: on the LTCA's
    /// 0.2 mm flanks the even tip columns are 2.5–3.5 × wider beside the flank, and the mesh
    /// stiffness of a first version (the fillet in one row) rose by 0.4 %.
    StableStep,
}

impl ToothLayout {
    /// The case file's name of the layout (`fe.tooth_layout`).
    pub fn name(self) -> &'static str {
        match self {
            ToothLayout::Graded => "graded",
            ToothLayout::StableStep => "stable-step",
        }
    }
}

/// The nodes of one flank (form point to tip corner, root to tip) with their roll angles.
#[derive(Debug, Clone, PartialEq)]
pub struct FlankNodes {
    pub tooth: usize,
    pub side: Side,
    pub nodes: Vec<usize>,
    /// Roll angle ξ of the profile point each node was placed on [rad].
    pub roll_angles: Vec<f64>,
}

/// A meshed gear in its tooth-local frame (tooth 0 along +y).
#[derive(Debug, Clone)]
pub struct GearMesh {
    pub nodes: Vec<Point2<f64>>,
    pub elements: Vec<[usize; 8]>,
    /// Whether each element belongs to a fine tooth sector.
    pub element_fine: Vec<bool>,
    /// Nodes on the bore circle.
    pub bore_nodes: Vec<usize>,
    /// Every flank of every tooth.
    pub flanks: Vec<FlankNodes>,
    pub fine_teeth: Vec<usize>,
}

impl GearMesh {
    pub fn flank(&self, tooth: usize, side: Side) -> &FlankNodes {
        self.flanks
            .iter()
            .find(|f| f.tooth == tooth && f.side == side)
            .expect("every tooth has both flanks")
    }
}

/// Growth ratio of graded intervals (across the tooth, and of the base layers).
const GROWTH: f64 = 1.5;

/// Meshes `gear` with profile `modification`.
///
/// # Panics
/// If a fine tooth index is not below the number of teeth or a size is not positive (the case
/// layer checks both).
#[track_caller]
pub fn mesh_gear(gear: &Gear, modification: &FlankModification, spec: &MeshSpec) -> GearMesh {
    let z = gear.teeth() as usize;
    let (fine, coarse, layers) = sector_layouts(gear, modification, spec);

    let mut merger = NodeMerger::new(1e-9 * gear.tip_radius.max(1e-3) * 10.0);
    let mut elements = Vec::new();
    let mut element_fine = Vec::new();
    let mut flanks = Vec::new();
    for tooth in 0..z {
        let is_fine = spec.fine_teeth.contains(&tooth);
        let layout = if is_fine { &fine } else { &coarse };
        let rotation = Rotation2::new(tooth as f64 * gear.angular_pitch());
        // Q8 has no node at the element centre (odd row and odd column of the grid).
        let mut ids = |grid: &[Point2<f64>], cols: usize| -> Vec<usize> {
            grid.iter()
                .enumerate()
                .map(|(i, p)| {
                    if (i / cols) % 2 == 1 && (i % cols) % 2 == 1 {
                        usize::MAX
                    } else {
                        merger.insert(Point2::from(rotation * p.coords))
                    }
                })
                .collect()
        };
        let tooth_ids = ids(&layout.tooth_grid, layout.tooth_cols());
        for e in grid_elements(&tooth_ids, layout.tooth_rows(), layout.tooth_cols()) {
            elements.push(e);
            element_fine.push(is_fine);
        }
        for points in layout.base_elements(&layers) {
            elements.push(points.map(|p| merger.insert(Point2::from(rotation * p.coords))));
            element_fine.push(is_fine);
        }
        let cols = layout.tooth_cols();
        for (side, col) in [(Side::Right, 0), (Side::Left, cols - 1)] {
            let rows = layout.flank_first_row..layout.tooth_rows();
            flanks.push(FlankNodes {
                tooth,
                side,
                nodes: rows.clone().map(|k| tooth_ids[k * cols + col]).collect(),
                roll_angles: layout.flank_roll_angles.clone(),
            });
        }
    }
    let nodes = merger.nodes;
    // Orientation: counter-clockwise corners (positive area).
    for e in elements.iter_mut() {
        let [a, b, _, d] = [nodes[e[0]], nodes[e[1]], nodes[e[2]], nodes[e[3]]];
        if (b - a).perp(&(d - a)) < 0.0 {
            *e = [e[0], e[3], e[2], e[1], e[7], e[6], e[5], e[4]];
        }
    }
    let bore = gear.spec.bore_radius;
    let bore_nodes = (0..nodes.len())
        .filter(|&i| (nodes[i].coords.norm() - bore).abs() < 1e-9 * bore.max(1e-3) * 10.0)
        .collect();
    GearMesh {
        nodes,
        elements,
        element_fine,
        bore_nodes,
        flanks,
        fine_teeth: spec.fine_teeth.clone(),
    }
}

/// The layouts of a fine and of a coarse tooth sector, and the base layers all sectors share.
/// Panics as [`mesh_gear`] says.
#[track_caller]
fn sector_layouts(
    gear: &Gear,
    modification: &FlankModification,
    spec: &MeshSpec,
) -> (SectorLayout, SectorLayout, Vec<f64>) {
    let z = gear.teeth() as usize;
    assert!(
        spec.fine_size > 0.0 && spec.coarse_size >= spec.fine_size,
        "mesh sizes"
    );
    assert!(
        spec.fine_teeth.iter().all(|&t| t < z),
        "fine tooth index out of range"
    );
    let layout = spec.layout;
    let fine = SectorLayout::new(
        gear,
        modification,
        (spec.fine_size, spec.coarse_size),
        layout,
    );
    let coarse = SectorLayout::new(
        gear,
        modification,
        (spec.coarse_size, spec.coarse_size),
        layout,
    );
    let top_layer = if spec.fine_teeth.is_empty() {
        spec.coarse_size
    } else {
        spec.fine_size
    };
    let layers = base_layers(gear, top_layer, spec.coarse_size, &coarse);
    (fine, coarse, layers)
}

/// Node and element counts of a mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MeshSize {
    pub nodes: usize,
    pub elements: usize,
}

/// The counts [`mesh_gear`] would give, without building the mesh: one fine and one coarse
/// sector are laid out and their elements counted, not stored, so the count of a mesh too large
/// to build costs a fraction of a second (the resource check before a model is built).
///
/// The mesh is conforming (no hanging nodes: the transition units and the sectors' shared
/// radial edges are built for it) and covers an annulus, so Euler's formula V − E + F = 0 holds
/// for its corners V, edges E and elements F; with every edge cut once by a mid-side node and
/// 4F = 2E − E_b (E_b: edges on the boundary),
/// ```text
/// nodes = V + E = 2E − F = 3F + E_b
/// ```
/// E_b per sector: both tooth sides, the tip, the root curve beside the tooth and the bore.
///
/// # Panics
/// As [`mesh_gear`].
#[track_caller]
pub fn mesh_size(gear: &Gear, modification: &FlankModification, spec: &MeshSpec) -> MeshSize {
    let z = gear.teeth() as usize;
    let fine_teeth = (0..z).filter(|t| spec.fine_teeth.contains(t)).count();
    let (fine, coarse, layers) = sector_layouts(gear, modification, spec);
    let sector = |layout: &SectorLayout| {
        let (rows, cols) = (layout.tooth_rows() / 2, layout.tooth_cols() / 2);
        let mut base = 0;
        let bore_edges = layout.emit_base_elements(&layers, &mut |_| base += 1);
        let root_edges = (layout.base_top.len() - layout.tooth_cols()) / 2;
        let elements = rows * cols + base;
        (elements, 2 * rows + cols + root_edges + bore_edges)
    };
    let (fine_elements, fine_boundary) = sector(&fine);
    let (coarse_elements, coarse_boundary) = sector(&coarse);
    let elements = fine_teeth * fine_elements + (z - fine_teeth) * coarse_elements;
    let boundary = fine_teeth * fine_boundary + (z - fine_teeth) * coarse_boundary;
    MeshSize {
        nodes: 3 * elements + boundary,
        elements,
    }
}

/// Q8 elements of a (2n+1) × (2m+1) quadratic grid of node ids (row-major).
fn grid_elements(ids: &[usize], rows: usize, cols: usize) -> Vec<[usize; 8]> {
    let at = |r: usize, c: usize| ids[r * cols + c];
    let mut out = Vec::new();
    for r in (0..rows - 1).step_by(2) {
        for c in (0..cols - 1).step_by(2) {
            out.push([
                at(r, c),
                at(r, c + 2),
                at(r + 2, c + 2),
                at(r + 2, c),
                at(r, c + 1),
                at(r + 1, c + 2),
                at(r + 2, c + 1),
                at(r + 1, c),
            ]);
        }
    }
    out
}

/// Radial layer fractions g of the base block, from the top (1) to the bore (0).
/// The first layer below the root is `top_size` thick; layers grow by [`GROWTH`] up to the
/// larger of the coarse element size and 2.5 times the width of a coarse sector's top columns
/// at that radius (the solid web's share of the mesh stiffness is resolved at the coarse size:
/// the mean stiffness moves by 0.01 % between 1.5 and 3 mm there).
fn base_layers(gear: &Gear, top_size: f64, coarse_size: f64, coarse: &SectorLayout) -> Vec<f64> {
    let (top, bore) = (gear.root_radius, gear.spec.bore_radius);
    let column_angle = gear.angular_pitch() / (coarse.base_top.len() / 2) as f64;
    let mut thicknesses = Vec::new();
    let (mut r, mut t) = (top, top_size);
    loop {
        let remaining = r - bore;
        // The last one or two layers share the remainder rather than leaving a sliver.
        if remaining <= 1.3 * t {
            thicknesses.push(remaining);
            break;
        }
        if remaining <= 2.3 * t {
            thicknesses.extend([0.5 * remaining; 2]);
            break;
        }
        thicknesses.push(t);
        r -= t;
        let cap = (2.5 * r * column_angle).max(coarse_size).max(top_size);
        t = (t * GROWTH).min(cap);
    }
    let total = top - bore;
    let mut fractions = vec![1.0];
    let mut acc = 0.0;
    for t in &thicknesses {
        acc += t;
        fractions.push((1.0 - acc / total).max(0.0));
    }
    *fractions.last_mut().expect("layers") = 0.0;
    fractions
}

/// The node grids of one tooth sector (tooth 0), for one element size.
struct SectorLayout {
    /// Tooth block grid, row-major: rows bottom (chord) to top (tip), columns right to left.
    tooth_grid: Vec<Point2<f64>>,
    tooth_cols: usize,
    /// Row index (quadratic grid) where the flank starts (the form point).
    flank_first_row: usize,
    flank_roll_angles: Vec<f64>,
    /// Top curve of the base block, right space centre to left space centre (quadratic grid).
    base_top: Vec<Point2<f64>>,
    bore_radius: f64,
}

impl SectorLayout {
    fn new(
        gear: &Gear,
        modification: &FlankModification,
        (size, coarse): (f64, f64),
        layout: ToothLayout,
    ) -> Self {
        let (beta_form, beta_root) = gear.fillet_parameter_range();
        let beta_split = fillet_split(gear, modification);
        let fillet = |b: f64| gear.modified_fillet_point(b, modification);
        let xi_form = gear.form_roll_angle();
        let xi_end = gear.modified_tip_roll_angle(modification);
        let flank = |xi: f64| gear.modified_flank_point(xi, modification);
        let count = |length: f64| ((length / size).ceil() as usize).max(1);

        // Side curve: upper fillet then flank, with midpoints.
        // The fillets turn by ~45° each: at least two quadratic elements follow them closely.
        // Graded places the rows by the fillet's parameter, which leaves the lower row about
        // 0.6 × the upper one (0.45 and 0.78 mm on the seed paper's teeth at 1 mm); the layout
        // for the stable step places them at equal arc lengths.
        let upper_fillet = curve_length(&fillet, beta_split, beta_form);
        let n_uf = count(upper_fillet).max(2);
        let fillet_rows: Vec<f64> = match layout {
            ToothLayout::Graded => with_midpoints(&uniform_fractions(n_uf))
                .iter()
                .map(|t| beta_split + (beta_form - beta_split) * t)
                .collect(),
            ToothLayout::StableStep => {
                let arc = ArcLengthTable::new(&fillet, beta_split, beta_split, beta_form, 0.0);
                with_midpoints(&uniform_fractions(n_uf))
                    .iter()
                    .map(|t| arc.parameter_at(*t))
                    .collect()
            }
        };
        let n_fl = count(curve_length(&flank, xi_form, xi_end)).max(2);
        let mut side: Vec<Point2<f64>> = fillet_rows.iter().map(|b| fillet(*b)).collect();
        let flank_params: Vec<f64> = with_midpoints(&uniform_fractions(n_fl))
            .iter()
            .map(|t| xi_form + (xi_end - xi_form) * t)
            .collect();
        side.pop(); // the form point is the flank's first point
        let flank_first_row = side.len();
        side.extend(flank_params.iter().map(|&xi| flank(xi)));
        let mirror = |p: &Point2<f64>| Point2::new(-p.x, p.y);

        // Across the tooth: graded from both flanks.
        let corner_r = side[0];
        let corner_l = mirror(&corner_r);
        let across = with_midpoints(&symmetric_graded_fractions(
            (corner_r - corner_l).norm(),
            size,
            GROWTH,
            coarse.max(size),
        ));
        let across_top = match layout {
            ToothLayout::Graded => across.clone(),
            ToothLayout::StableStep => with_midpoints(&uniform_fractions((across.len() - 1) / 2)),
        };
        let bottom: Vec<Point2<f64>> = across
            .iter()
            .map(|u| corner_r + (corner_l - corner_r) * *u)
            .collect();
        let tip_corner = *side.last().expect("side");
        let theta_tip = tip_corner.x.atan2(tip_corner.y);
        let top: Vec<Point2<f64>> = across_top
            .iter()
            .map(|u| polar(gear.tip_radius, theta_tip * (1.0 - 2.0 * u)))
            .collect();

        // Arc-length parameter of the side curve, for the Coons blend.
        let mut v = vec![0.0];
        for w in side.windows(2) {
            v.push(v.last().unwrap() + (w[1] - w[0]).norm());
        }
        let total = *v.last().unwrap();
        v.iter_mut().for_each(|x| *x /= total);

        let (rows, cols) = (side.len(), across.len());
        let mut grid = Vec::with_capacity(rows * cols);
        for k in 0..rows {
            for j in 0..cols {
                let vk = v[k];
                // Graded: the chord's fractions all the way up (bit for bit as before the
                // blend); else blended from the chord's to the tip's.
                let u = match layout {
                    ToothLayout::Graded => across[j],
                    ToothLayout::StableStep => across[j] * (1.0 - vk) + across_top[j] * vk,
                };
                let p = if k == 0 {
                    bottom[j]
                } else if k == rows - 1 {
                    top[j]
                } else if j == 0 {
                    side[k]
                } else if j == cols - 1 {
                    mirror(&side[k])
                } else {
                    let coons = side[k].coords * (1.0 - u)
                        + mirror(&side[k]).coords * u
                        + bottom[j].coords * (1.0 - vk)
                        + top[j].coords * vk
                        - (bottom[0].coords * ((1.0 - u) * (1.0 - vk))
                            + bottom[cols - 1].coords * (u * (1.0 - vk))
                            + top[0].coords * ((1.0 - u) * vk)
                            + top[cols - 1].coords * (u * vk));
                    Point2::from(coons)
                };
                grid.push(p);
            }
        }

        // Base-block top: root arc + lower fillet as one curve (the root arc alone is a fraction
        // of a module wide and would leave a thin column down to the bore), chord, and mirror.
        let half_pitch = 0.5 * gear.angular_pitch();
        let root_end = gear.fillet_root_angle();
        let root_length = (half_pitch - root_end) * gear.root_radius;
        let lower_fillet_length = curve_length(&fillet, beta_root, beta_split);
        // Parameter s ∈ [0, 1] over the root arc, s ∈ [1, 2] over the lower fillet.
        let point_at = |s: f64| {
            if s <= 1.0 {
                polar(gear.root_radius, half_pitch + (root_end - half_pitch) * s)
            } else {
                fillet(beta_root + (beta_split - beta_root) * (s - 1.0))
            }
        };
        let arc = ArcLengthTable::new(&point_at, 0.0, 1.0, 2.0, root_length);
        let n_rl = count(root_length + lower_fillet_length).max(2);
        let mut right: Vec<Point2<f64>> = with_midpoints(&uniform_fractions(n_rl))
            .iter()
            .map(|t| point_at(arc.parameter_at(*t)))
            .collect();
        right.pop(); // F*, the chord's first point
        let mut base_top = right.clone();
        base_top.extend(bottom.iter().copied());
        base_top.extend(right.iter().rev().map(mirror));

        SectorLayout {
            tooth_grid: grid,
            tooth_cols: cols,
            flank_first_row,
            flank_roll_angles: flank_params,
            base_top,
            bore_radius: gear.spec.bore_radius,
        }
    }

    fn tooth_cols(&self) -> usize {
        self.tooth_cols
    }

    fn tooth_rows(&self) -> usize {
        self.tooth_grid.len() / self.tooth_cols
    }

    /// Base-block node on the ray through top-curve grid point `index` (corner column c is index
    /// 2c, the mid-side between c and c+1 is 2c+1) at layer fraction g: r = r_bore + (|p| − r_bore)·g.
    fn base_point(&self, index: usize, g: f64) -> Point2<f64> {
        let p = self.base_top[index];
        if g == 1.0 {
            return p;
        }
        let r = p.coords.norm();
        Point2::from(p.coords * ((self.bore_radius + (r - self.bore_radius) * g) / r))
    }

    /// Base-block elements (8 node positions each) from the top curve down to the bore, layer by
    /// layer. The columns form fixed groups — triples, with the one or two left over in the
    /// middle — and once every triple has become narrow against the layer thickness (joint width
    /// at most twice the layer), a layer of 3-to-1 transition units merges all of them:
    /// ```text
    ///   T0 ── T1 ── T2 ── T3        four quads: T0 T1 I1 B0 | T1 T2 I2 I1 | T2 T3 B1 I2 | I1 I2 B1 B0
    ///   │     │     │     │         I1, I2 half-way down the layer below T1, T2
    ///   │     I1 ── I2    │         the unit's side edges T0–B0 and T3–B1 are ordinary column
    ///   │   ╱         ╲   │         edges, so units and plain columns sit side by side and the
    ///   B0 ───────────── B1         neighbouring sector sees the same radial edge.
    /// ```
    /// Mid-side nodes of edges along a ray or across columns lie on the ray through the
    /// corresponding top-curve grid point (column indices ca, cb → grid index ca + cb), so two
    /// elements sharing an edge compute the same node; the slanted edges take the straight
    /// midpoint.
    fn base_elements(&self, layers: &[f64]) -> Vec<[Point2<f64>; 8]> {
        let mut out = Vec::new();
        self.emit_base_elements(layers, &mut |element| out.push(element));
        out
    }

    /// [`Self::base_elements`] handed one by one to `emit` (a count needs no storage); returns
    /// the number of element edges on the bore.
    fn emit_base_elements(&self, layers: &[f64], emit: &mut dyn FnMut([Point2<f64>; 8])) -> usize {
        let columns = self.base_top.len() / 2;
        let mut active: Vec<usize> = (0..=columns).collect();
        let mut out = Emit(emit);
        let depth = self.base_top[0].coords.norm() - self.bore_radius;
        let mid = |a: Point2<f64>, b: Point2<f64>| Point2::from((a.coords + b.coords) * 0.5);
        for (k, w) in layers.windows(2).enumerate() {
            let (gt, gb) = (w[0], w[1]);
            let gm = 0.5 * (gt + gb);
            let thickness = depth * (gt - gb);
            let at = |c: usize, g: f64| self.base_point(2 * c, g);
            let on = |index: usize, g: f64| self.base_point(index, g);
            // Mid-side of an edge across columns ca–cb at fraction g: the top curve's own mid-side
            // for neighbouring columns (the top row follows the fillet exactly), else the polar
            // midpoint of the two ends, which both elements sharing the edge compute alike.
            let across = |ca: usize, cb: usize, g: f64| {
                if ca.abs_diff(cb) == 1 {
                    return on(ca + cb, g);
                }
                let (a, b) = (at(ca, g), at(cb, g));
                let angle = 0.5 * (a.x.atan2(a.y) + b.x.atan2(b.y));
                let radius = 0.5 * (a.coords.norm() + b.coords.norm());
                Point2::new(radius * angle.sin(), radius * angle.cos())
            };
            // Columns in fixed groups: triples, with the one or two left over in the middle
            // (under the tooth, where the columns are widest). A layer merges every triple or
            // none, so the groups of the next layer line up again; merging triple by triple
            // left narrow columns between wide ones, running down to the bore as slivers that
            // set the body's time step.
            let columns = active.len() - 1;
            let (triples, singles) = (columns / 3, columns % 3);
            let right = triples - triples / 2;
            let groups: Vec<usize> = std::iter::repeat_n(3, right)
                .chain(std::iter::repeat_n(1, singles))
                .chain(std::iter::repeat_n(3, triples - right))
                .collect();
            let merge_layer = k >= 2
                && triples > 0
                && groups
                    .iter()
                    .scan(0, |start, &size| {
                        let first = *start;
                        *start += size;
                        Some((first, size))
                    })
                    .filter(|&(_, size)| size == 3)
                    .all(|(first, _)| {
                        (at(active[first + 3], gb) - at(active[first], gb)).norm()
                            <= 2.0 * thickness
                    });
            let mut next = vec![active[0]];
            let mut i = 0;
            for size in groups {
                let merge = merge_layer && size == 3;
                if merge {
                    let [c0, c1, c2, c3] = [active[i], active[i + 1], active[i + 2], active[i + 3]];
                    let (t0, t1, t2, t3) = (at(c0, gt), at(c1, gt), at(c2, gt), at(c3, gt));
                    let (i1, i2) = (at(c1, gm), at(c2, gm));
                    let (b0, b1) = (at(c0, gb), at(c3, gb));
                    let half = 0.5 * (gt + gm);
                    out.push([
                        t0,
                        t1,
                        i1,
                        b0,
                        across(c0, c1, gt),
                        on(2 * c1, half),
                        mid(i1, b0),
                        on(2 * c0, gm),
                    ]);
                    out.push([
                        t1,
                        t2,
                        i2,
                        i1,
                        across(c1, c2, gt),
                        on(2 * c2, half),
                        across(c1, c2, gm),
                        on(2 * c1, half),
                    ]);
                    out.push([
                        t2,
                        t3,
                        b1,
                        i2,
                        across(c2, c3, gt),
                        on(2 * c3, gm),
                        mid(b1, i2),
                        on(2 * c2, half),
                    ]);
                    out.push([
                        i1,
                        i2,
                        b1,
                        b0,
                        across(c1, c2, gm),
                        mid(i2, b1),
                        across(c0, c3, gb),
                        mid(b0, i1),
                    ]);
                    next.push(c3);
                    i += 3;
                    continue;
                }
                for _ in 0..size {
                    let (ca, cb) = (active[i], active[i + 1]);
                    out.push([
                        at(ca, gt),
                        at(cb, gt),
                        at(cb, gb),
                        at(ca, gb),
                        across(ca, cb, gt),
                        on(2 * cb, gm),
                        across(ca, cb, gb),
                        on(2 * ca, gm),
                    ]);
                    next.push(cb);
                    i += 1;
                }
            }
            active = next;
        }
        active.len() - 1
    }
}

/// A sink that reads like the `Vec` the element loop once pushed to.
struct Emit<'a>(&'a mut dyn FnMut([Point2<f64>; 8]));

impl Emit<'_> {
    fn push(&mut self, element: [Point2<f64>; 8]) {
        (self.0)(element)
    }
}

/// Arc-length parametrisation of a two-piece curve: parameters [a, m] and [m, b], sampled finely;
/// `parameter_at(f)` returns the parameter at fraction f of the total length.
struct ArcLengthTable {
    parameters: Vec<f64>,
    lengths: Vec<f64>,
}

impl ArcLengthTable {
    fn new(curve: &dyn Fn(f64) -> Point2<f64>, a: f64, m: f64, b: f64, first_length: f64) -> Self {
        // Sample each piece evenly in its parameter; the pieces can differ in length a lot.
        let n = 512;
        let mut parameters = Vec::with_capacity(2 * n + 1);
        for i in 0..n {
            parameters.push(a + (m - a) * i as f64 / n as f64);
        }
        for i in 0..=n {
            parameters.push(m + (b - m) * i as f64 / n as f64);
        }
        let mut lengths = vec![0.0];
        for w in parameters.windows(2) {
            lengths.push(lengths.last().unwrap() + (curve(w[1]) - curve(w[0])).norm());
        }
        debug_assert!((lengths[n] - first_length).abs() < 1e-6 * first_length.max(1e-9) + 1e-12);
        let total = *lengths.last().unwrap();
        lengths.iter_mut().for_each(|l| *l /= total);
        Self {
            parameters,
            lengths,
        }
    }

    fn parameter_at(&self, fraction: f64) -> f64 {
        let k = self
            .lengths
            .partition_point(|l| *l < fraction)
            .clamp(1, self.lengths.len() - 1);
        let (l0, l1) = (self.lengths[k - 1], self.lengths[k]);
        let t = if l1 > l0 {
            (fraction - l0) / (l1 - l0)
        } else {
            0.0
        };
        self.parameters[k - 1] + (self.parameters[k] - self.parameters[k - 1]) * t
    }
}

fn polar(radius: f64, theta: f64) -> Point2<f64> {
    Point2::new(radius * theta.sin(), radius * theta.cos())
}

/// Length of a parametric curve between two parameters (256-segment polyline).
fn curve_length(curve: &dyn Fn(f64) -> Point2<f64>, from: f64, to: f64) -> f64 {
    let n = 256;
    (0..n)
        .map(|i| {
            let a = curve(from + (to - from) * i as f64 / n as f64);
            let b = curve(from + (to - from) * (i + 1) as f64 / n as f64);
            (b - a).norm()
        })
        .sum()
}

/// Fillet parameter β* where the fillet's tangent makes 45° with the radial direction (bisection;
/// the angle falls from 90° at the root circle to the involute's α_F at the form point).
fn fillet_split(gear: &Gear, modification: &FlankModification) -> f64 {
    let (beta_form, beta_root) = gear.fillet_parameter_range();
    let angle_from_radial = |beta: f64| {
        let h = 1e-7;
        let p = gear.modified_fillet_point(beta, modification);
        let t: Vector2<f64> = gear.modified_fillet_point(beta - h, modification)
            - gear.modified_fillet_point(beta + h, modification);
        let radial = p.coords.normalize();
        (t.normalize().dot(&radial)).abs().clamp(0.0, 1.0).acos()
    };
    let (mut lo, mut hi) = (beta_form, beta_root - 1e-6);
    if angle_from_radial(lo) >= PI / 4.0 {
        return 0.5 * (beta_form + beta_root);
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if angle_from_radial(mid) < PI / 4.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}
