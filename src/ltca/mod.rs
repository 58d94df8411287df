//! Quasi-static loaded tooth contact analysis (LTCA) over one base pitch: static transmission
//! error, load sharing and the mesh stiffness k(θ) — the stiffness currency of geardyn.
//!
//! # Model
//! * Two elastic FE bodies ([`body::LtcaBody`]) with their bores held; the driver's hub is held at
//!   θ₁, the driven gear's rigid hub rotation φ carries the load torque T.
//! * Frictionless node-to-surface contact: the candidate points are the FE nodes of the loaded
//!   flanks of gear 1's engaging teeth; the opposing surface is gear 2's exact (modified) profile
//!   of the partner tooth — flank, tip corner and tip — so contact outside the nominal path
//!   (corner contact under load, or with relief) is found too. For each candidate k:
//!   ```text
//!   g₀ₖ = (xₖ − yₖ)·n₂ₖ               initial gap to the closest point yₖ, n₂: gear 2's outward normal
//!   aₖ  = ((yₖ − O₂) × n₂ₖ)·ẑ        gap closed per unit lag rotation of gear 2 (≈ r_b2)
//!   C   = G₁ + W G₂ Wᵀ               compliance; W spreads the reaction at yₖ over gear 2's flank
//!                                    nodes with the quadratic edge shape functions
//!   ```
//!   and the contact problem of [`contact`] gives forces F ≥ 0 and the loaded static transmission
//!   error φ (angular, driven gear lagging) with Σ Fₖ aₖ = T.
//! * Unloaded transmission error φ₀ = minₖ g₀ₖ/aₖ (first touch; from relief), elastic approach
//!   δ = r_b2 (φ − φ₀), total normal load W = Σ Fₖ, mesh stiffness k = W / δ.
//!
//! Positions: θ₁ = j·(2π/z₁)/N, j = 0 … N−1, starting with tooth 0 of each gear at the pitch
//! point; the driver's roll angle of tooth 0's contact is ξ = ξ_pitch + θ₁. Only the loaded
//! flanks are in contact ([`Flank`]): the drive flanks for T > 0 (the back flanks open as the
//! driven gear lags), or, for a model on [`Flank::Back`], the back flanks under the reversed
//! torque: candidates on gear 1's back flanks (tooth-local right), gear 2's back profile, the
//! back pairs of [`engagement::back_base_pitch_pairs`], and the rotations counted the other way,
//! ```text
//! n₂ₖ → −n₂ₖ (the back side's outward normal),   aₖ = −((yₖ − O₂) × n₂ₖ)·ẑ
//! ```
//! so φ is gear 2's lead and φ₀ the back flanks' unloaded gap (backlash and relief included),
//! both at the same positions θ₁ as the drive flanks'. For symmetric teeth without backlash the
//! back flanks at driver rotation θ₁ meet as the drive flanks at 2ψ₁ − θ₁ (roll angle ξ → ρ − ξ,
//! [`GearPair::back_flank_reflection`]); tests/ltca.rs holds the two models to that.

pub mod body;
pub mod contact;
pub mod field;
pub mod modal;

use nalgebra::{DMatrix, DVector, Point2, Rotation2, Vector2};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::fe::recovery::edge_traction;
use crate::fe::FeError;
use crate::geometry::engagement::{self, ToothPair};
use crate::geometry::{FlankModification, GearPair, OutlineResolution, Segment, Side};
use crate::mesh::MeshSpec;
use body::{BodyMaterial, LtcaBody};
use contact::{solve_contact, ContactError};

#[derive(Debug, thiserror::Error)]
pub enum LtcaError {
    #[error(
        "torque_nm = {torque} is invalid: the LTCA needs a load torque > 0 on the driven gear"
    )]
    Torque { torque: f64 },
    #[error("positions = {positions} is invalid: use {MIN_POSITIONS} to {MAX_POSITIONS} positions per base pitch")]
    Positions { positions: usize },
    #[error(transparent)]
    Fe(#[from] FeError),
    #[error("contact solve failed at position {position} (driver rotation {rotation_deg:.4}°): {source}. The flank's compliance or gaps there are not a contact problem the solve can hold: refine mesh.fine_element_mm, check the relief amounts (relief_variant) and bore_radius_mm, or change --positions to step over the position")]
    Contact {
        position: usize,
        rotation_deg: f64,
        #[source]
        source: ContactError,
    },
    #[error("the LTCA is not periodic over one base pitch at torque {torque} N·m: the STE is {:.4} µrad at the first position and {:.4} µrad one base pitch later ({:.3e} apart, relative), and a tooth pair's force differs by {:.3e} of the load (tolerance {PERIODICITY_TOLERANCE:.0e}). The tooth pairs in contact are not the ones the geometry expects: report this case", periodicity.ste_first * 1e6, periodicity.ste_one_pitch_on * 1e6, periodicity.ste_relative_difference, periodicity.force_relative_difference)]
    NotPeriodic {
        torque: f64,
        periodicity: Periodicity,
    },
    #[error("no tooth pair is in contact at position {position}: the geometry leaves a gap everywhere within the search window")]
    NoContact { position: usize },
}

/// The fewest positions per base pitch (a contact change needs a position on either side), and
/// the most: a million positions take minutes of solves for steps far below the mesh's
/// resolution, and a slip of a few zeros should not fill the memory with results.
pub const MIN_POSITIONS: usize = 4;
pub const MAX_POSITIONS: usize = 100_000;

/// The flanks an LTCA loads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Flank {
    /// The drive flanks (tooth-local left), under the load torque T > 0.
    Drive,
    /// The back flanks (tooth-local right), under the reversed torque: the driven gear drives.
    Back,
}

impl Flank {
    /// The tooth-local side of the flanks.
    pub fn side(self) -> Side {
        match self {
            Flank::Drive => Side::Left,
            Flank::Back => Side::Right,
        }
    }

    /// The tooth pairs whose flanks meet over one base pitch.
    pub fn base_pitch_pairs(self, pair: &GearPair) -> Vec<ToothPair> {
        match self {
            Flank::Drive => engagement::base_pitch_pairs(pair),
            Flank::Back => engagement::back_base_pitch_pairs(pair),
        }
    }

    /// +1 for the drive flanks, −1 for the back: the sense of gear 2's outward normal against
    /// the drive side's and of the rotation that closes the gap.
    fn sense(self) -> f64 {
        match self {
            Flank::Drive => 1.0,
            Flank::Back => -1.0,
        }
    }
}

/// The two bodies and the geometry an LTCA runs on.
pub struct LtcaModel {
    pub pair: GearPair,
    /// The loaded flanks.
    pub flank: Flank,
    /// Meshed, factorized and condensed once; shared by the models [`LtcaModel::with_relief`]
    /// derives (a relief of a few µm changes the gap, not the bodies' compliance).
    pub bodies: std::sync::Arc<[LtcaBody; 2]>,
    /// Gear 2's loaded-side profile (tooth-local): dense polyline from the tip centre down to the
    /// root, with the roll angle of flank points.
    profile: Vec<(Point2<f64>, Segment, Option<f64>)>,
    /// The signed tooth pairs the model carries ([`engagement`]), by ascending driver tooth.
    pub pairs: Vec<ToothPair>,
    /// The same as (gear-1 tooth, gear-2 tooth) mesh indices: the columns of the results.
    pub tooth_pairs: Vec<(usize, usize)>,
    modifications: [FlankModification; 2],
    /// The bodies' material.
    pub material: BodyMaterial,
    /// Stride of the coarse pass of the first-touch search (1: exhaustive).
    first_touch_stride: usize,
}

/// The teeth of each gear that engage over one base pitch of positions and the one after it
/// ([`engagement::base_pitch_pairs`]): the ones an LTCA meshes fine.
pub fn engaging_teeth(pair: &GearPair) -> [Vec<usize>; 2] {
    engaging_teeth_on(pair, Flank::Drive)
}

/// [`engaging_teeth`] of the drive or the back flanks.
pub fn engaging_teeth_on(pair: &GearPair, flank: Flank) -> [Vec<usize>; 2] {
    engagement::teeth_of(pair, &flank.base_pitch_pairs(pair))
}

impl LtcaModel {
    /// Meshes and factorizes both gears, condenses their flank compliance.
    pub fn new(
        pair: &GearPair,
        modifications: &[FlankModification; 2],
        mesh_specs: [MeshSpec; 2],
        material: BodyMaterial,
    ) -> Result<Self, LtcaError> {
        Self::on_flank(pair, modifications, mesh_specs, material, Flank::Drive)
    }

    /// [`LtcaModel::new`] loading `flank`; `modifications` are those of that flank.
    pub fn on_flank(
        pair: &GearPair,
        modifications: &[FlankModification; 2],
        mesh_specs: [MeshSpec; 2],
        material: BodyMaterial,
        flank: Flank,
    ) -> Result<Self, LtcaError> {
        let [spec1, spec2] = mesh_specs;
        // The two bodies side by side: each one's meshing, ordering and triangular solves are
        // mostly serial, so two cores finish both in about the time of one.
        let body = |g: usize, spec: &MeshSpec| {
            LtcaBody::new(
                &pair.gears[g],
                &modifications[g],
                spec,
                material,
                flank.side(),
            )
        };
        let (body1, body2) = rayon::join(|| body(0, &spec1), || body(1, &spec2));
        let (body1, body2) = (body1?, body2?);
        let profile = loaded_profile(pair, &modifications[1], flank);
        // The engaged pairs whose teeth are both meshed fine (a model built on fewer fine teeth,
        // as some tests do, leaves the others out; the periodicity check then says so).
        let pairs: Vec<ToothPair> = flank
            .base_pitch_pairs(pair)
            .into_iter()
            .filter(|p| {
                let (t1, t2) = p.indices(pair);
                spec1.fine_teeth.contains(&t1) && spec2.fine_teeth.contains(&t2)
            })
            .collect();
        let tooth_pairs = pairs.iter().map(|p| p.indices(pair)).collect();
        Ok(LtcaModel {
            pair: pair.clone(),
            flank,
            bodies: std::sync::Arc::new([body1, body2]),
            profile,
            pairs,
            tooth_pairs,
            modifications: *modifications,
            material,
            first_touch_stride: FIRST_TOUCH_STRIDE,
        })
    }

    /// The same bodies with another relief: the exact modified profiles set the gaps, the
    /// bodies (meshed with the relief this model was built with) keep their compliance — a
    /// relief of a few µm does not change it measurably (tests/ltca.rs holds this against a
    /// re-meshed relief LTCA). No meshing or factorization: what an optimizer's loop needs.
    pub fn with_relief(&self, modifications: &[FlankModification; 2]) -> LtcaModel {
        LtcaModel {
            pair: self.pair.clone(),
            flank: self.flank,
            bodies: self.bodies.clone(),
            profile: loaded_profile(&self.pair, &modifications[1], self.flank),
            pairs: self.pairs.clone(),
            tooth_pairs: self.tooth_pairs.clone(),
            modifications: *modifications,
            material: self.material,
            first_touch_stride: self.first_touch_stride,
        }
    }

    /// Global rotations of the two gears' tooth-local frames at driver rotation θ₁ (unloaded
    /// kinematics: θ₂ = −(z₁/z₂) θ₁).
    fn rotations(&self, driver_rotation: f64) -> [f64; 2] {
        let placement = self.pair.mesh_placement();
        let ratio = self.pair.gears[0].teeth() as f64 / self.pair.gears[1].teeth() as f64;
        [
            placement[0].rotation + driver_rotation,
            placement[1].rotation - ratio * driver_rotation,
        ]
    }

    /// Solves one position.
    pub fn solve_position(
        &self,
        index: usize,
        positions: usize,
        torque: f64,
    ) -> Result<PositionResult, LtcaError> {
        Ok(self.contact_state(index, positions, torque)?.result)
    }

    /// The loaded contact state of one position: its result and its active contact points with
    /// the flank nodes they tie together — what a linearization about the loaded state needs.
    pub fn loaded_contacts(
        &self,
        index: usize,
        positions: usize,
        torque: f64,
    ) -> Result<LoadedContacts, LtcaError> {
        let state = self.contact_state(index, positions, torque)?;
        let node = |body: &LtcaBody, (candidate, weight): (usize, f64)| {
            let c = &body.candidates[candidate];
            (c.node, weight, c.inward)
        };
        let active = state
            .points
            .iter()
            .enumerate()
            .filter(|(i, _)| state.forces[*i] > 0.0)
            .map(|(i, p)| ActiveContact {
                nodes: [
                    p.weights1.map(|w| node(&self.bodies[0], w)),
                    p.weights2.map(|w| node(&self.bodies[1], w)),
                ],
                force: state.forces[i],
                compliance: state.compliance[(i, i)],
            })
            .collect();
        Ok(LoadedContacts {
            result: state.result,
            active,
        })
    }

    fn contact_state(
        &self,
        index: usize,
        positions: usize,
        torque: f64,
    ) -> Result<ContactState, LtcaError> {
        let geometry = self.position_geometry(index, positions)?;
        let (result, forces) = geometry.solve(self, torque)?;
        Ok(ContactState {
            result,
            points: geometry.points,
            compliance: geometry.compliance,
            forces,
        })
    }

    /// The torque-independent part of one position: the candidate contact points with their
    /// initial gaps, arms and compliance (the geometric search is most of an LTCA's cost, so a
    /// torque sweep does it once per position).
    fn position_geometry(
        &self,
        index: usize,
        positions: usize,
    ) -> Result<PositionGeometry, LtcaError> {
        let driver_rotation = index as f64 / positions as f64 * self.pair.gears[0].angular_pitch();
        self.geometry_at(index, driver_rotation)
    }

    /// The loaded state at any driver rotation θ₁ [rad] (`index` names it in errors), not only
    /// at the positions of a cycle.
    pub fn solve_at(
        &self,
        index: usize,
        driver_rotation: f64,
        torque: f64,
    ) -> Result<PositionResult, LtcaError> {
        if !(torque > 0.0 && torque.is_finite()) {
            return Err(LtcaError::Torque { torque });
        }
        Ok(self
            .geometry_at(index, driver_rotation)?
            .solve(self, torque)?
            .0)
    }

    fn geometry_at(
        &self,
        index: usize,
        driver_rotation: f64,
    ) -> Result<PositionGeometry, LtcaError> {
        let pair = &self.pair;
        let sense = self.flank.sense();
        let back_gap = match self.flank {
            Flank::Drive => 0.0,
            Flank::Back => pair.backlash_normal.max(0.0),
        };
        let [rot1, rot2] = self.rotations(driver_rotation);
        let placement = pair.mesh_placement();
        let (o1, o2) = (placement[0].centre, placement[1].centre);
        let [body1, body2] = &*self.bodies;
        let gear1 = &pair.gears[0];
        let aw = pair.operating_pressure_angle;
        let loa_direction = Vector2::new(aw.sin(), aw.cos());
        let t1 = pair.loa_point(0.0);

        let mut points: Vec<ContactPoint> = Vec::new();
        let mut unloaded = f64::INFINITY;
        for (pair_index, &(tooth1, tooth2)) in self.tooth_pairs.iter().enumerate() {
            let rotation1 = Rotation2::new(rot1 + tooth1 as f64 * gear1.angular_pitch());
            let rotation2 = Rotation2::new(rot2 + tooth2 as f64 * pair.gears[1].angular_pitch());
            let surface: Vec<Point2<f64>> = self
                .profile
                .iter()
                .map(|(p, _, _)| o2 + rotation2 * p.coords)
                .collect();
            let nodes1 = tooth_nodes(body1, tooth1);
            let nodes2 = tooth_nodes(body2, tooth2);
            let (xi_first, xi_last) = (
                body1.candidates[nodes1[0]].roll_angle,
                body1.candidates[*nodes1.last().unwrap()].roll_angle,
            );
            // Gear 1's loaded flank point at roll angle ξ, global.
            let flank_point = |xi: f64| {
                let p = self.flank1(xi);
                o1 + rotation1 * p.coords
            };
            let probe = |xi: f64| -> Option<Probe> {
                let x = flank_point(xi);
                let (segment, t) = closest_segment(&surface, &x)?;
                let (a, b) = (surface[segment], surface[segment + 1]);
                let y = a + (b - a) * t;
                let tangent = (b - a).normalize();
                let normal = sense * Vector2::new(tangent.y, -tangent.x);
                let r = y - o2;
                let arm = sense * (r.x * normal.y - r.y * normal.x);
                (arm > 0.0).then(|| Probe {
                    gap: (x - y).dot(&normal),
                    arm,
                    segment,
                    t,
                    y,
                })
            };
            // Geometric contact: the flank point that closes first (min g/a) on a grid of 800
            // spacings, searched coarse (every 8th point) then fine around the coarse minimum:
            // g/a is smooth along the flank, so this finds the grid's minimum with 1/6 of the
            // probes (the search is most of a position's cost).
            let samples = 800;
            let stride = self.first_touch_stride;
            let closing_at = |i: usize| {
                let xi = xi_first + (xi_last - xi_first) * i as f64 / samples as f64;
                probe(xi).map(|p| (xi, p.gap / p.arm))
            };
            let lowest = |indices: &mut dyn Iterator<Item = usize>| {
                let mut best: Option<(usize, f64, f64)> = None;
                for i in indices {
                    if let Some((xi, closing)) = closing_at(i) {
                        if best.is_none_or(|(_, _, c)| closing < c) {
                            best = Some((i, xi, closing));
                        }
                    }
                }
                best
            };
            let best = lowest(&mut (0..=samples).step_by(stride)).and_then(|(coarse, _, _)| {
                let from = coarse.saturating_sub(stride);
                lowest(&mut (from..=(coarse + stride).min(samples)))
            });
            let best = best.map(|(_, xi, closing)| (xi, closing));
            let Some((xi_contact, closing)) = best else {
                continue;
            };
            // A pair whose first touch needs more rotation than a tooth can deflect stays open
            // (beyond the backlash, which the back flanks' gap holds as a whole).
            if closing * pair.gears[1].base_radius - back_gap > 0.05 * gear1.module() {
                continue;
            }
            unloaded = unloaded.min(closing);
            // Contact lattice: node spacing, centred on the geometric contact point.
            let spacing = (xi_last - xi_first) / (nodes1.len() - 1) as f64;
            for j in -LATTICE_HALF_WIDTH..=LATTICE_HALF_WIDTH {
                let xi = xi_contact + j as f64 * spacing;
                if xi < xi_first - 1e-12 || xi > xi_last + 1e-12 {
                    continue;
                }
                let xi = xi.clamp(xi_first, xi_last);
                let Some(p) = probe(xi) else { continue };
                points.push(ContactPoint {
                    pair: pair_index,
                    gap: p.gap,
                    arm: p.arm,
                    // Along the back flanks' line of action, the drive one's mirror about
                    // the centre line (the x axis).
                    loa: (Point2::new(p.y.x, sense * p.y.y) - t1).dot(&loa_direction),
                    weights1: flank_weights(body1, &nodes1, Some(xi), true),
                    weights2: self.surface_weights(p.segment, p.t, &nodes2),
                });
            }
        }
        if points.is_empty() {
            return Err(LtcaError::NoContact { position: index });
        }

        let m = points.len();
        let compliance = DMatrix::from_fn(m, m, |i, j| {
            let (p, q) = (&points[i], &points[j]);
            let mut c = 0.0;
            for (a, wa) in p.weights1 {
                for (b, wb) in q.weights1 {
                    c += wa * wb * body1.compliance[(a, b)];
                }
            }
            for (a, wa) in p.weights2 {
                for (b, wb) in q.weights2 {
                    c += wa * wb * body2.compliance[(a, b)];
                }
            }
            c
        });
        Ok(PositionGeometry {
            index,
            driver_rotation,
            unloaded,
            points,
            compliance,
        })
    }

    /// Gear 1's loaded flank (tooth-local left for the drive, right for the back flanks) at
    /// roll angle ξ, tooth-local frame of tooth 0.
    fn flank1(&self, roll_angle: f64) -> Point2<f64> {
        let p = self.pair.gears[0].modified_flank_point(roll_angle, &self.modifications[0]);
        match self.flank.side() {
            Side::Left => Point2::new(-p.x, p.y),
            Side::Right => p,
        }
    }

    /// Weights spreading a point of gear 2's surface (segment, parameter) over gear 2's flank
    /// nodes of that tooth (`nodes`, root to tip): quadratic edge shape functions at the point's
    /// roll angle; tip points go to the tip-corner node, fillet points to the form-point node.
    fn surface_weights(&self, segment: usize, t: f64, nodes: &[usize]) -> [(usize, f64); 3] {
        let (pa, pb) = (&self.profile[segment], &self.profile[segment + 1]);
        let roll = match (pa.2, pb.2) {
            (Some(a), Some(b)) => Some(a + (b - a) * t),
            (Some(a), None) if t < 0.5 => Some(a),
            (None, Some(b)) if t >= 0.5 => Some(b),
            _ => None,
        };
        let at_tip = pa.1 == Segment::Tip || pb.1 == Segment::Tip;
        flank_weights(&self.bodies[1], nodes, roll, at_tip)
    }

    /// Runs the LTCA over one base pitch; `progress` is called with the number of positions done.
    pub fn run(
        &self,
        positions: usize,
        torque: f64,
        progress: &(dyn Fn(usize) + Sync),
    ) -> Result<Vec<PositionResult>, LtcaError> {
        Ok(self.run_checked(positions, torque, progress)?.0)
    }

    /// The fillet stress of both gears in a loaded state: each active contact's force spread on
    /// its flank nodes by its weights, through [`body::FilletStress`]. Per gear, (σ_xx, σ_yy,
    /// τ_xy) at each of `bodies[g].fillet.nodes` [Pa].
    pub fn fillet_stresses(&self, contacts: &LoadedContacts) -> [Vec<[f64; 3]>; 2] {
        std::array::from_fn(|g| {
            let forces = self.candidate_forces(contacts, g);
            self.bodies[g].fillet.stresses(
                forces
                    .iter()
                    .enumerate()
                    .filter(|(_, f)| **f != 0.0)
                    .map(|(i, f)| (i, *f)),
            )
        })
    }

    /// Gear `g`'s inward force at each candidate flank node in a loaded state: each active
    /// contact's force spread by its weights [N].
    fn candidate_forces(&self, contacts: &LoadedContacts, g: usize) -> Vec<f64> {
        let body = &self.bodies[g];
        let candidate_of: std::collections::HashMap<usize, usize> = body
            .candidates
            .iter()
            .enumerate()
            .map(|(i, c)| (c.node, i))
            .collect();
        let mut forces = vec![0.0; body.candidates.len()];
        for contact in &contacts.active {
            for (node, weight, _) in contact.nodes[g] {
                if weight != 0.0 {
                    forces[candidate_of[&node]] += contact.force * weight;
                }
            }
        }
        forces
    }

    /// Per gear, the contact pressure at each candidate flank node in a loaded state [Pa]: the
    /// nodal forces of each tooth's flank as the consistent traction of its quadratic edges
    /// ([`crate::fe::recovery::edge_traction`], over the pair's common face width, as the
    /// Hertz pressure is). Where a
    /// tip corner carries load the force sits on the corner node and the traction there grows
    /// as the flank elements shrink: an edge contact, which the FE resolves only as far as its
    /// mesh does.
    pub fn flank_tractions(&self, contacts: &LoadedContacts) -> [Vec<f64>; 2] {
        let face_width = self.pair.gears[0]
            .spec
            .face_width
            .min(self.pair.gears[1].spec.face_width);
        std::array::from_fn(|g| {
            let body = &self.bodies[g];
            let forces = self.candidate_forces(contacts, g);
            let mut traction = vec![0.0; forces.len()];
            let mut teeth: Vec<usize> = body.candidates.iter().map(|c| c.tooth).collect();
            teeth.dedup();
            for tooth in teeth {
                let nodes = tooth_nodes(body, tooth);
                if nodes.iter().all(|&i| forces[i] == 0.0) {
                    continue;
                }
                let points: Vec<Point2<f64>> =
                    nodes.iter().map(|&i| body.candidates[i].position).collect();
                let f: Vec<f64> = nodes.iter().map(|&i| forces[i]).collect();
                for (&i, t) in nodes.iter().zip(edge_traction(&points, &f, face_width)) {
                    traction[i] = t;
                }
            }
            traction
        })
    }

    /// Per gear, the largest principal stress on its loaded-side fillet nodes under the contact
    /// forces `forces` of `points` [Pa] (−∞ without fillet nodes).
    fn fillet_tension(&self, points: &[ContactPoint], forces: &DVector<f64>) -> [f64; 2] {
        std::array::from_fn(|g| {
            let loads = points
                .iter()
                .zip(forces.iter())
                .filter(|(_, f)| **f > 0.0)
                .flat_map(|(p, f)| {
                    let weights = if g == 0 { p.weights1 } else { p.weights2 };
                    weights
                        .into_iter()
                        .filter(|(_, w)| *w != 0.0)
                        .map(move |(candidate, w)| (candidate, f * w))
                });
            let fillet = &self.bodies[g].fillet;
            fillet
                .nodes
                .iter()
                .zip(fillet.stresses(loads))
                .filter(|(node, _)| node.loaded_side)
                .map(|(_, s)| crate::fe::recovery::max_principal(s))
                .fold(f64::NEG_INFINITY, f64::max)
        })
    }

    /// [`LtcaModel::run`] with its periodicity check's numbers (a failed check is an error).
    pub fn run_checked(
        &self,
        positions: usize,
        torque: f64,
        progress: &(dyn Fn(usize) + Sync),
    ) -> Result<(Vec<PositionResult>, Periodicity), LtcaError> {
        let (mut cycles, mut periodicity) = self.cycles(positions, &[torque], progress)?;
        Ok((
            cycles.pop().expect("one torque, one cycle"),
            periodicity.pop().expect("one torque, one check"),
        ))
    }

    /// One base pitch at each of `torques`: `[torque][position]`. The geometric contact search of
    /// a position is done once and solved for every torque — what a load-range objective (a
    /// Harris map, the robust relief optimizer) needs; each result equals [`LtcaModel::run`]'s.
    pub fn run_torques(
        &self,
        positions: usize,
        torques: &[f64],
    ) -> Result<Vec<Vec<PositionResult>>, LtcaError> {
        Ok(self.cycles(positions, torques, &|_| {})?.0)
    }

    /// The cycles of [`LtcaModel::run`] and [`LtcaModel::run_torques`]: rayon over positions,
    /// each position's contact search solved for every torque; `progress` sees positions done.
    /// Every cycle is checked for periodicity: the first position is solved again one base
    /// pitch on ([`LtcaModel::periodicity`]); a cycle that fails it is an error.
    fn cycles(
        &self,
        positions: usize,
        torques: &[f64],
        progress: &(dyn Fn(usize) + Sync),
    ) -> Result<(Vec<Vec<PositionResult>>, Vec<Periodicity>), LtcaError> {
        if let Some(&torque) = torques.iter().find(|t| !(**t > 0.0 && t.is_finite())) {
            return Err(LtcaError::Torque { torque });
        }
        if !(MIN_POSITIONS..=MAX_POSITIONS).contains(&positions) {
            return Err(LtcaError::Positions { positions });
        }
        let done = AtomicUsize::new(0);
        // Position N is position 0 one base pitch later: solved for the periodicity check only.
        let mut by_position: Vec<Vec<PositionResult>> = (0..=positions)
            .into_par_iter()
            .map(|j| {
                let geometry = self.position_geometry(j, positions)?;
                let results = torques
                    .iter()
                    .map(|&torque| Ok(geometry.solve(self, torque)?.0))
                    .collect();
                if j < positions {
                    progress(done.fetch_add(1, Ordering::Relaxed) + 1);
                }
                results
            })
            // Collected whole first, so a failure reports the first failing position whatever
            // the thread count.
            .collect::<Vec<Result<Vec<PositionResult>, LtcaError>>>()
            .into_iter()
            .collect::<Result<_, LtcaError>>()?;
        let one_pitch_on = by_position.pop().expect("position N");
        let mut checks = Vec::with_capacity(torques.len());
        for ((first, later), &torque) in by_position[0].iter().zip(&one_pitch_on).zip(torques) {
            let periodicity = self.periodicity(first, later);
            if !periodicity.holds() {
                return Err(LtcaError::NotPeriodic {
                    torque,
                    periodicity,
                });
            }
            checks.push(periodicity);
        }
        let mut cycles: Vec<Vec<PositionResult>> = torques
            .iter()
            .map(|_| Vec::with_capacity(positions))
            .collect();
        for results in by_position {
            for (cycle, result) in cycles.iter_mut().zip(results) {
                cycle.push(result);
            }
        }
        Ok((cycles, checks))
    }

    /// The position one base pitch on against the first: the pair of signed driver tooth s − 1
    /// one pitch on stands where pair s stood (a pair the model does not carry counts zero).
    pub fn periodicity(&self, first: &PositionResult, later: &PositionResult) -> Periodicity {
        let force = |results: &PositionResult, driver: i64| {
            self.pairs
                .iter()
                .position(|p| p.driver == driver)
                .map_or(0.0, |i| results.pair_forces[i])
        };
        let force_difference = self
            .pairs
            .iter()
            .flat_map(|p| [p.driver, p.driver + 1])
            .map(|s| (force(first, s) - force(later, s - 1)).abs());
        let force_difference = crate::signal::largest(force_difference);
        Periodicity {
            ste_first: first.ste,
            ste_one_pitch_on: later.ste,
            // Over the loaded deflection: a backlash or relief gap in φ would loosen it.
            ste_relative_difference: (later.ste - first.ste).abs()
                / (first.ste - first.unloaded_te).abs(),
            force_relative_difference: force_difference / first.total_force,
        }
    }
}

/// Relative tolerance of the periodicity check. The bodies are not rotationally periodic (fine
/// elements on the engaged teeth only, the coarse teeth beyond), so the teeth loaded one pitch
/// on sit in a slightly different mesh: a few 1e-6 of the STE at most over the matrix of pairs
/// (validation/pairs). A missing or wrong partner moves either by tens of percent.
pub const PERIODICITY_TOLERANCE: f64 = 1e-4;

/// The LTCA's first position against the same position one base pitch later.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Periodicity {
    /// Loaded STE φ at the first position and one pitch on [rad].
    pub ste_first: f64,
    pub ste_one_pitch_on: f64,
    /// |φ(p) − φ(0)| / |φ(0) − φ₀(0)|: over the loaded deflection (φ₀ the unloaded TE).
    pub ste_relative_difference: f64,
    /// Largest difference of a tooth pair's force over the total load.
    pub force_relative_difference: f64,
}

impl Periodicity {
    /// Both differences within [`PERIODICITY_TOLERANCE`].
    pub fn holds(&self) -> bool {
        self.ste_relative_difference <= PERIODICITY_TOLERANCE
            && self.force_relative_difference <= PERIODICITY_TOLERANCE
    }
}

/// Gear 2's loaded-side profile (tooth-local) with `modification`: dense polyline from the tip
/// centre down to the root, with the roll angle of flank points (the outline's second half
/// for the drive flanks, its first half reversed for the back flanks).
fn loaded_profile(
    pair: &GearPair,
    modification: &FlankModification,
    flank: Flank,
) -> Vec<(Point2<f64>, Segment, Option<f64>)> {
    let res = OutlineResolution {
        root: 4,
        fillet: 64,
        flank: 2000,
        tip: 16,
    };
    let outline = pair.gears[1].tooth_outline(modification, res);
    let mid = (outline.len() - 1) / 2;
    let point = |p: &crate::geometry::OutlinePoint| (p.position, p.segment, p.roll_angle);
    match flank {
        Flank::Drive => outline[mid..].iter().map(point).collect(),
        Flank::Back => outline[..=mid].iter().rev().map(point).collect(),
    }
}

/// Stride of the first-touch search's coarse pass over its 800 flank samples.
const FIRST_TOUCH_STRIDE: usize = 8;

/// Half the number of lattice points per tooth pair: the lattice spans ±8 node spacings around
/// the geometric contact point, several times the Hertzian contact width at any sensible mesh.
const LATTICE_HALF_WIDTH: i32 = 8;

/// The candidate contact points of one position, before a torque is applied.
struct PositionGeometry {
    index: usize,
    driver_rotation: f64,
    /// Unloaded transmission error φ₀ [rad].
    unloaded: f64,
    points: Vec<ContactPoint>,
    compliance: DMatrix<f64>,
}

/// The contact problem of one position, solved.
struct ContactState {
    result: PositionResult,
    points: Vec<ContactPoint>,
    compliance: DMatrix<f64>,
    forces: DVector<f64>,
}

impl PositionGeometry {
    /// The contact problem of this position at `torque`, solved.
    fn solve(
        &self,
        model: &LtcaModel,
        torque: f64,
    ) -> Result<(PositionResult, DVector<f64>), LtcaError> {
        let pair = &model.pair;
        let PositionGeometry {
            index,
            driver_rotation,
            unloaded,
            points,
            compliance,
        } = self;
        let (index, driver_rotation, unloaded) = (*index, *driver_rotation, *unloaded);
        let m = points.len();
        let gaps = DVector::from_iterator(m, points.iter().map(|p| p.gap));
        let arms = DVector::from_iterator(m, points.iter().map(|p| p.arm));
        let mut forces = DVector::zeros(m);
        let solution =
            solve_contact(compliance, &gaps, &arms, torque, &mut forces).map_err(|source| {
                LtcaError::Contact {
                    position: index,
                    rotation_deg: driver_rotation.to_degrees(),
                    source,
                }
            })?;
        let total_force: f64 = forces.iter().sum();
        let rb2 = pair.gears[1].base_radius;
        let mut pair_forces = vec![0.0; model.tooth_pairs.len()];
        let mut pair_moment = vec![0.0; model.tooth_pairs.len()];
        for (i, p) in points.iter().enumerate() {
            pair_forces[p.pair] += forces[i];
            pair_moment[p.pair] += forces[i] * p.loa;
        }
        let pair_positions = pair_forces
            .iter()
            .zip(&pair_moment)
            .map(|(f, fm)| if *f > 0.0 { Some(fm / f) } else { None })
            .collect();
        let roll_pitch = pair.roll_angle_at(1, pair.contact_points.pitch);
        let tangent_stiffness =
            tangent_torsional_stiffness(compliance, &arms, &forces) / (rb2 * rb2);
        let result = PositionResult {
            driver_rotation,
            roll_angle: roll_pitch + driver_rotation,
            ste: solution.rotation,
            unloaded_te: unloaded,
            total_force,
            pair_forces,
            pair_positions,
            mesh_stiffness: total_force / (rb2 * (solution.rotation - unloaded)),
            tangent_stiffness,
            kkt_residual: solution.kkt_residual,
            active_points: forces.iter().filter(|f| **f > 0.0).count(),
            candidate_points: m,
            iterations: solution.iterations,
            root_stress: model.fillet_tension(points, &forces),
        };
        Ok((result, forces))
    }
}

/// The tangent torsional mesh stiffness dT/dφ = aᵀ C_AA⁻¹ a [N·m/rad] on the active set A (the
/// points with F > 0): with the active set held, g_A = g₀ + C_AA F_A − φ a_A = 0 and aᵀF = T give
/// dF_A = C_AA⁻¹ a_A dφ. It is above the secant W/(r_b2(φ − φ₀)) where the curved flanks close
/// more points as the load grows.
fn tangent_torsional_stiffness(
    compliance: &DMatrix<f64>,
    arms: &DVector<f64>,
    forces: &DVector<f64>,
) -> f64 {
    let active: Vec<usize> = (0..forces.len()).filter(|&i| forces[i] > 0.0).collect();
    let c = DMatrix::from_fn(active.len(), active.len(), |i, j| {
        compliance[(active[i], active[j])]
    });
    let a = DVector::from_iterator(active.len(), active.iter().map(|&i| arms[i]));
    match c.cholesky() {
        Some(llt) => a.dot(&llt.solve(&a)),
        None => f64::NAN,
    }
}

/// An active contact point of the loaded state: the gear-1 and gear-2 flank nodes it ties
/// together, each as (mesh node, weight, unit inward normal in the gear's frame), so that the
/// gap opens by Σ w (n · u) over both gears' nodal displacements u.
#[derive(Debug, Clone, PartialEq)]
pub struct ActiveContact {
    pub nodes: [[(usize, f64, Vector2<f64>); 3]; 2],
    /// Contact force [N].
    pub force: f64,
    /// The point's own compliance C_kk of both bodies with their bores held [m/N].
    pub compliance: f64,
}

/// The loaded state of one position with its active contact points.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedContacts {
    pub result: PositionResult,
    pub active: Vec<ActiveContact>,
}

/// A candidate contact point of one position.
struct ContactPoint {
    pair: usize,
    gap: f64,
    arm: f64,
    loa: f64,
    /// Gear 1 / gear 2 flank-node (candidate index) weights.
    weights1: [(usize, f64); 3],
    weights2: [(usize, f64); 3],
}

/// The closest point of gear 2's surface to a gear-1 flank point.
struct Probe {
    gap: f64,
    arm: f64,
    segment: usize,
    t: f64,
    y: Point2<f64>,
}

/// Candidate indices of `tooth`'s loaded flank, root to tip.
fn tooth_nodes(body: &LtcaBody, tooth: usize) -> Vec<usize> {
    (0..body.candidates.len())
        .filter(|&i| body.candidates[i].tooth == tooth)
        .collect()
}

/// Weights of a flank point at roll angle ξ over the flank nodes `nodes` (uniform in ξ, 2n+1
/// nodes of n quadratic edges): the edge's shape functions [s(s−1)/2, 1−s², s(s+1)/2]. Without a
/// roll angle the point is beyond the flank: all weight on the tip corner (`at_tip`) or on the
/// form point.
fn flank_weights(
    body: &LtcaBody,
    nodes: &[usize],
    roll: Option<f64>,
    at_tip: bool,
) -> [(usize, f64); 3] {
    let last = nodes.len() - 1;
    let Some(xi) = roll else {
        let node = if at_tip { nodes[last] } else { nodes[0] };
        return [(node, 1.0), (node, 0.0), (node, 0.0)];
    };
    let (xi_first, xi_last) = (
        body.candidates[nodes[0]].roll_angle,
        body.candidates[nodes[last]].roll_angle,
    );
    let u = ((xi - xi_first) / (xi_last - xi_first) * last as f64).clamp(0.0, last as f64);
    let element = ((u / 2.0).floor() as usize).min(last / 2 - 1);
    let s = u - 2.0 * element as f64 - 1.0;
    let base = 2 * element;
    [
        (nodes[base], 0.5 * s * (s - 1.0)),
        (nodes[base + 1], 1.0 - s * s),
        (nodes[base + 2], 0.5 * s * (s + 1.0)),
    ]
}

/// Closest point of a polyline to `x`: (segment index, parameter t ∈ [0, 1]). A coarse pass
/// over every 16th vertex picks the neighbourhood, then the segments within ±64 of it are
/// searched (the profile's curvature radius is far larger than 16 vertex spacings).
fn closest_segment(polyline: &[Point2<f64>], x: &Point2<f64>) -> Option<(usize, f64)> {
    let segments = polyline.len().checked_sub(1)?;
    let centre = (0..polyline.len())
        .step_by(16)
        .min_by(|&i, &j| {
            (polyline[i] - x)
                .norm_squared()
                .total_cmp(&(polyline[j] - x).norm_squared())
        })
        .unwrap_or(0);
    let (from, to) = (centre.saturating_sub(64), (centre + 64).min(segments));
    let mut best: Option<(usize, f64, f64)> = None;
    for i in from..to {
        let (a, b) = (polyline[i], polyline[i + 1]);
        let d = b - a;
        let length2 = d.norm_squared();
        if length2 == 0.0 {
            continue;
        }
        let t = ((x - a).dot(&d) / length2).clamp(0.0, 1.0);
        let distance = (x - (a + d * t)).norm_squared();
        if best.is_none_or(|(_, _, b)| distance < b) {
            best = Some((i, t, distance));
        }
    }
    best.map(|(i, t, _)| (i, t))
}

/// The LTCA answer at one mesh position.
#[derive(Debug, Clone, PartialEq)]
pub struct PositionResult {
    /// Driver rotation θ₁ from the pitch-point position [rad].
    pub driver_rotation: f64,
    /// Driver roll angle of tooth 0's contact, ξ_pitch + θ₁ [rad].
    pub roll_angle: f64,
    /// Loaded static transmission error: driven-gear lag φ [rad].
    pub ste: f64,
    /// Unloaded transmission error φ₀ (from relief) [rad].
    pub unloaded_te: f64,
    /// Total normal contact force W [N].
    pub total_force: f64,
    /// Normal force per tooth pair (order of `LtcaModel::tooth_pairs`) [N].
    pub pair_forces: Vec<f64>,
    /// Force-weighted contact position of each loaded pair, distance from T1 [m].
    pub pair_positions: Vec<Option<f64>>,
    /// Mesh stiffness k = W / (r_b2 (φ − φ₀)) [N/m] (secant).
    pub mesh_stiffness: f64,
    /// Tangent mesh stiffness dW/dδ on the active set, aᵀC_AA⁻¹a / r_b2² [N/m]: what small
    /// vibrations about the loaded state feel.
    pub tangent_stiffness: f64,
    pub kkt_residual: f64,
    pub active_points: usize,
    pub candidate_points: usize,
    pub iterations: usize,
    /// Per gear, the largest principal stress on the loaded flanks' fillets of its fine teeth
    /// [Pa] ([`LtcaModel::fillet_stresses`]; −∞ for a body without fillet nodes): the tooth-root
    /// tension at this position, what a root-stress limit reads.
    pub root_stress: [f64; 2],
}

/// The loaded length of one tooth pair's engagement [samples]: the span over which `forces`
/// (one pair's normal force at uniform positions) is positive, each loaded run starting and
/// ending between samples — the crossing extrapolated linearly from the run's two boundary
/// forces f (outermost) and g (next inside), f/(g − f) spacings beyond f when the force rises
/// inward (g > f), clamped to one spacing, and a whole spacing when it does not (the limit of the
/// same rule, so the length changes continuously with the forces — what a linearized constraint
/// needs); a run of one sample counts one spacing. Sample j stands for [j − ½, j + ½), so a run
/// at either end of `forces` counts to that end, and with every extension ½ the length is the
/// plain count of loaded samples.
pub fn engagement_loaded_length(forces: &[f64]) -> f64 {
    let n = forces.len();
    let extension = |f: f64, g: f64| if g > f { (f / (g - f)).min(1.0) } else { 1.0 };
    let mut loaded = 0.0;
    let mut j = 0;
    while j < n {
        if forces[j] <= 0.0 {
            j += 1;
            continue;
        }
        let first = j;
        while j < n && forces[j] > 0.0 {
            j += 1;
        }
        let last = j - 1;
        let (start, end) = if first == last {
            (first as f64 - 0.5, last as f64 + 0.5)
        } else {
            (
                first as f64 - extension(forces[first], forces[first + 1]),
                last as f64 + extension(forces[last], forces[last - 1]),
            )
        };
        loaded += end.min(n as f64 - 0.5) - start.max(-0.5);
    }
    loaded
}

impl LtcaModel {
    /// The loaded contact ratio ε_load: the mean number of tooth pairs carrying load over the
    /// cycle, which is one pair's loaded length over the base pitch. A driver tooth k at
    /// position N (one pitch on) is where tooth k + 1 was at position 0, so the forces of the
    /// consecutive driver teeth (k₀, k₀ + 1, …) of `results` laid end to end are one tooth
    /// pair's whole engagement over as many pitches:
    /// ```text
    /// ε_load = L(F_k₀ ‖ F_k₀₊₁ ‖ …) / N          (L: engagement_loaded_length)
    /// ```
    /// Unmodified gears load a little beyond the geometric path under load (ε_load ≳ ε_α);
    /// relief that exceeds the deflection shortens it. NaN when the model's tooth pairs are not
    /// consecutive driver teeth in order (the engaging teeth always are).
    pub fn loaded_contact_ratio(&self, results: &[PositionResult]) -> f64 {
        let consecutive = self
            .pairs
            .windows(2)
            .all(|w| w[1].driver == w[0].driver + 1);
        if !consecutive || results.is_empty() {
            return f64::NAN;
        }
        let engagement: Vec<f64> = (0..self.tooth_pairs.len())
            .flat_map(|p| results.iter().map(move |r| r.pair_forces[p]))
            .collect();
        engagement_loaded_length(&engagement) / results.len() as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{FlankReliefSpec, ReliefShape, ReliefSpec, ReliefStart};

    /// The coarse-to-fine first-touch search finds the exhaustive search's grid minimum: the
    /// same STE and forces to round-off at every position, on the unmodified pair, the paper's
    /// 20/10 µm relief, and a strong short parabolic tip relief whose corner and flank compete
    /// (1 mm mesh, 32 positions, three torques).
    #[test]
    fn coarse_to_fine_first_touch_equals_the_exhaustive_search() {
        let case = crate::samples::paper36_case();
        let pair = &case.pair;
        let none = [FlankModification::none(); 2];
        let model = crate::study::ltca::model_with_sizes(&case, &none, 1e-3, 3e-3).unwrap();
        let short = |g| {
            pair.flank_modification(
                g,
                &FlankReliefSpec {
                    tip: Some(ReliefSpec {
                        amount: 30e-6,
                        shape: ReliefShape::Parabolic,
                        start: ReliefStart::Short,
                    }),
                    root: None,
                },
            )
            .unwrap()
        };
        let reliefs = [
            none,
            case.relief_variant("tip20-root10").unwrap().modifications,
            [short(1), short(2)],
        ];
        for modifications in &reliefs {
            let fast = model.with_relief(modifications);
            let mut exhaustive = model.with_relief(modifications);
            exhaustive.first_touch_stride = 1;
            let torques = [50.0, 143.6, 300.0];
            let (a, b) = (
                fast.run_torques(32, &torques).unwrap(),
                exhaustive.run_torques(32, &torques).unwrap(),
            );
            for (ra, rb) in a.iter().flatten().zip(b.iter().flatten()) {
                assert!(
                    (ra.ste - rb.ste).abs() <= 1e-12 * rb.ste.abs(),
                    "{ra:?} {rb:?}"
                );
                assert_eq!(ra.active_points, rb.active_points);
            }
        }
    }

    /// Linear ramps with known zero crossings give the exact loaded length: a pair loading from
    /// 5.6 and unloading at 30.3 spacings; a plateau that ends abruptly counts a whole spacing
    /// beyond its last sample (the continuous limit of the ramp rule); one loaded sample counts
    /// one spacing; a run at an end of the record counts to that end.
    #[test]
    fn engagement_loaded_length_finds_the_crossings_of_linear_ramps() {
        let ramp: Vec<f64> = (0..40)
            .map(|j| {
                let j = j as f64;
                ((j - 5.6) * 70.0).min((30.3 - j) * 100.0).max(0.0)
            })
            .collect();
        assert!((engagement_loaded_length(&ramp) - (30.3 - 5.6)).abs() < 1e-12);
        let plateau = [0.0, 0.0, 50.0, 50.0, 50.0, 0.0];
        assert!((engagement_loaded_length(&plateau) - 4.0).abs() < 1e-12);
        // Continuity: a plateau sloping by a hair towards its ends tends to the same length.
        let almost = [0.0, 0.0, 49.999, 50.0, 49.999, 0.0];
        assert!((engagement_loaded_length(&almost) - 4.0).abs() < 1e-9);
        let single = [0.0, 0.0, 5.0, 0.0];
        assert!((engagement_loaded_length(&single) - 1.0).abs() < 1e-12);
        let at_ends = [3.0, 2.0, 1.0, 0.0, 0.0, 1.0];
        // [−½, 3) from the start to the ramp's zero at 3, then [4½, 5½) for the last sample.
        assert!((engagement_loaded_length(&at_ends) - (3.5 + 1.0)).abs() < 1e-12);
    }
}
