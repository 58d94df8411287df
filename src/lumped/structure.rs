//! The linear structure around the mesh: the gear bodies (hub and rim), shafts, motor and load
//! inertias and the bearings, assembled as a small linear system M ÿ + C ẏ + K y = F l − g W
//! in which the nonlinear mesh force W acts along g.
//!
//! # Coordinates
//! Every rotation is measured along the line of action, u = r_b θ (r_b of the gear whose side
//! of the mesh it turns on), relative to the nominal motion; the bearings' translations along
//! the line of action are coordinates of their own. The chain runs
//! ```text
//! motor ─ input shaft ─ hub₁ ─ body₁ ─ rim₁ ⟷ mesh ⟷ rim₂ ─ body₂ ─ hub₂ ─ output shaft ─ load
//! ```
//! with inertias m = I/r_b² and springs k = k_t/r_b². The mesh deflection is
//! δ = u_rim1 − u_rim2 + y₁ − y₂ (g), the transmission error the model reports is the hubs'
//! u_hub1 − u_hub2 (h), as the explicit FE and the LTCA measure it.
//!
//! # Gear bodies
//! A gear body twists between bore and root circle (an annulus in shear,
//! [`crate::geometry::Gear::body_torsional_compliance`]), with the inertia split between hub and
//! rim along the static twist shape s(r) = (1/r_i² − 1/r²)/(1/r_i² − 1/r_f²): the hub carries
//! ∫(1 − s) dI, the rim ∫ s dI plus the teeth (row sums of the Rayleigh–Ritz mass matrix).
//! A hub with nothing attached (no shaft, not the speed-driven end) is a free end under a
//! constant torque: its own mode (tens of kHz) lies far above the mesh mode, so it is
//! condensed onto its rim (Guyan): its inertia moves with the rim and the body's static twist
//! under the torque, F c_b, is added to the reported transmission error. That keeps the RK4
//! step at the mesh mode's scale.
//!
//! # Rim sway
//! A gear body also lets its rim translate against the held bore (a static FE of the body
//! reduced onto the rim's translation, [`crate::ltca::body::body_translation`]): the sway
//! along the line of action is one
//! coordinate per gear, `rim1 y` / `rim2 y`, mass m_y on the spring k_y to the ground, in the
//! mesh deflection as the bearings' translations are (δ = … + y₁ − y₂), not in the
//! transmission error (the hubs turn about fixed centres). A hub-to-hub stiffness holds the
//! sway's 1/k_y as it holds the twist; both leave the mesh for the bodies. On bearings, a rim
//! sways on its body in series with the bearing, the gear's mass on both springs (the statics
//! exact). Across the line of action a frictionless spur mesh does not drive the sway.
//!
//! # Drives
//! * **torque**: an input force +F at the driver side's outer end and the load −F at the driven
//!   side's; the chain has a rigid rotation u = (1, …, 1) that neither g, K nor the balanced
//!   load excite, so it is removed exactly: y_k = x_k − x_last with x M-orthogonal to u
//!   (uᵀM x = 0), M_y = RᵀMR, R = (I − u uᵀM/uᵀMu) E.
//! * **speed**: the driver side's outer end (the motor, or the driver hub) follows the
//!   prescribed speed; it is removed and the others are measured as its lag, y_k = −x_k.
//!
//! For a pair of rigid gears without shafts both reduce to the 1-DOF relative coordinate
//! p = r_b1θ₁ − r_b2θ₂ with m_e = I₁I₂/(I₁r_b2² + I₂r_b1²) (torque) or I₂/r_b2² (speed).

use nalgebra::{DMatrix, DVector, SymmetricEigen};

use super::{Bearings, Drive};

/// The largest number of coordinates a structure has (5 rotations and 2 translations, the
/// bearings' or the rims' sway, at most).
pub const MAX_DOFS: usize = 8;

/// A Jacobian over a structure's state (q then v, 2n × 2n of the first entries).
pub type Tangent = [[f64; 2 * MAX_DOFS]; 2 * MAX_DOFS];

/// One gear's body: inertias [kg·m²] of hub and rim and the torsional compliance between them
/// [rad/(N·m)] (0: a rigid body, hub and rim one inertia), and the rim's sway on the held bore
/// along the line of action (`None`: the body does not sway, or its sway is left in the mesh).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GearBody {
    pub hub_inertia: f64,
    pub rim_inertia: f64,
    pub torsional_compliance: f64,
    pub translation: Option<RimTranslation>,
}

/// A gear rim's translation on its held bore as one coordinate (a static FE of the body reduced
/// onto it, [`crate::ltca::body::body_translation`]; its frequency a Rayleigh upper bound of
/// the body's lateral mode): mass [kg] and stiffness [N/m].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RimTranslation {
    pub mass: f64,
    pub stiffness: f64,
}

impl GearBody {
    /// A rigid gear of inertia `inertia`.
    pub fn rigid(inertia: f64) -> Self {
        GearBody {
            hub_inertia: 0.0,
            rim_inertia: inertia,
            torsional_compliance: 0.0,
            translation: None,
        }
    }

    /// The compliance the body puts in series with the mesh along the line of action, base
    /// radius `base_radius` [m]: its twist r_b² c_t and its rim's sway 1/k_y [m/N].
    pub fn line_compliance(&self, base_radius: f64) -> f64 {
        self.torsional_compliance * base_radius * base_radius
            + self.translation.map_or(0.0, |t| 1.0 / t.stiffness)
    }

    pub fn inertia(&self) -> f64 {
        self.hub_inertia + self.rim_inertia
    }
}

/// A shaft from a gear's hub to an outer inertia (motor or load) [kg·m²], of torsional stiffness
/// [N·m/rad].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shaft {
    pub stiffness: f64,
    pub end_inertia: f64,
}

/// What the structure is built from.
#[derive(Debug, Clone, PartialEq)]
pub struct DrivetrainSpec {
    pub drive: Drive,
    pub base_radii: [f64; 2],
    pub gears: [GearBody; 2],
    /// Input shaft and motor (driver side), output shaft and load (driven side).
    pub shafts: [Option<Shaft>; 2],
    pub bearings: Option<Bearings>,
    /// The damping of every shaft and body spring ([`SpringDamping`]).
    pub spring_damping: SpringDamping,
}

/// The damping of a structure's springs (shafts, gear bodies).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SpringDamping {
    /// A damping ratio ζ of each spring's own mode, c = 2ζ√(k m_r) with m_r the reduced mass
    /// of the two inertias it joins (the one inertia when the other end is held): a real
    /// drivetrain's material and joint damping (`lumped.drivetrain_damping_ratio`).
    Ratio(f64),
    /// Stiffness-proportional damping c = β k [β in s]: the explicit FE's Rayleigh damping of
    /// its elements, which its lumped twin's bodies carry and nothing more.
    StiffnessProportional(f64),
}

impl SpringDamping {
    /// The dashpot of a spring of `stiffness` [N/m or N·m/rad] whose mode swings `reduced_mass`.
    fn coefficient(self, stiffness: f64, reduced_mass: f64) -> f64 {
        match self {
            SpringDamping::Ratio(zeta) => 2.0 * zeta * (stiffness * reduced_mass).sqrt(),
            SpringDamping::StiffnessProportional(beta) => beta * stiffness,
        }
    }
}

/// The linear structure around the mesh, reduced to its independent coordinates y.
#[derive(Debug, Clone, PartialEq)]
pub struct Structure {
    /// Number of coordinates n (≤ [`MAX_DOFS`]).
    pub dofs: usize,
    /// What each coordinate is (`rim2`, `hub2`, `y1`, …; rotations relative as described).
    pub names: Vec<String>,
    pub mass: DMatrix<f64>,
    pub stiffness: DMatrix<f64>,
    pub damping: DMatrix<f64>,
    /// δ = gᵀy (mesh deflection), load F l, transmission error hᵀy + F·te_per_force.
    pub mesh_direction: DVector<f64>,
    pub load_direction: DVector<f64>,
    pub te_direction: DVector<f64>,
    /// The static twist of condensed bodies per unit mesh force, in the TE [m/N].
    pub te_per_force: f64,
    /// The effective mass of the rigid pair under this drive (the mesh damping ratio's
    /// convention c = 2ζ√(k̄ m_e)) [kg].
    pub effective_mass: f64,
    /// The simplifications made, for the output.
    pub notes: Vec<String>,
    // M⁻¹K, M⁻¹C, M⁻¹g, M⁻¹l, row-major in fixed arrays for the integrator's inner loop.
    inv_mass_stiffness: [[f64; MAX_DOFS]; MAX_DOFS],
    inv_mass_damping: [[f64; MAX_DOFS]; MAX_DOFS],
    inv_mass_mesh: [f64; MAX_DOFS],
    inv_mass_load: [f64; MAX_DOFS],
    inv_mass_te: [f64; MAX_DOFS],
}

/// A natural mode of the structure with a given mesh stiffness.
#[derive(Debug, Clone, PartialEq)]
pub struct Mode {
    /// Undamped natural frequency [rad/s].
    pub frequency: f64,
    /// Share of the mode's strain energy in the mesh spring (1: the pure mesh mode).
    pub mesh_energy_share: f64,
    /// Mode shape over the coordinates, largest component 1 in magnitude.
    pub shape: Vec<f64>,
}

impl Structure {
    /// The 1-DOF relative coordinate p with mass `effective_mass` [kg].
    pub fn rigid_pair(effective_mass: f64) -> Self {
        Self::from_parts(
            vec!["p".into()],
            DMatrix::from_element(1, 1, effective_mass),
            DMatrix::zeros(1, 1),
            DMatrix::zeros(1, 1),
            [vec![1.0], vec![1.0], vec![1.0]],
            0.0,
            effective_mass,
            Vec::new(),
        )
    }

    /// p and the bearing translations y₁, y₂ (3 DOFs): δ = p + y₁ − y₂.
    pub fn rigid_pair_on_bearings(effective_mass: f64, bearings: &Bearings) -> Self {
        let diagonal = |v: [f64; 3]| DMatrix::from_diagonal(&DVector::from_row_slice(&v));
        Self::from_parts(
            vec!["p".into(), "y1".into(), "y2".into()],
            diagonal([effective_mass, bearings.mass[0], bearings.mass[1]]),
            diagonal([0.0, bearings.stiffness[0], bearings.stiffness[1]]),
            diagonal([0.0, bearings.damping[0], bearings.damping[1]]),
            [
                vec![1.0, 1.0, -1.0],
                vec![1.0, 0.0, 0.0],
                vec![1.0, 0.0, 0.0],
            ],
            0.0,
            effective_mass,
            Vec::new(),
        )
    }

    /// Assembles and reduces the chain of `spec` (module docs).
    pub fn drivetrain(spec: &DrivetrainSpec) -> Result<Self, String> {
        let rb = spec.base_radii;
        let speed = spec.drive == Drive::Speed;
        // Nodes along the chain: (name, side, mass [kg] along the line of action).
        let mut nodes: Vec<(String, usize, f64)> = Vec::new();
        // Springs between consecutive nodes: (left, right, k [N/m]).
        let mut springs: Vec<(usize, usize, f64)> = Vec::new();
        let mut notes = Vec::new();
        let mut te_per_force = 0.0;
        let mut rims = [0usize; 2];
        let mut hubs = [0usize; 2];
        let mut prescribed = None;
        for (side, body) in spec.gears.iter().enumerate() {
            let r2 = rb[side] * rb[side];
            let gear = side + 1;
            if !(body.hub_inertia >= 0.0
                && body.rim_inertia > 0.0
                && body.torsional_compliance >= 0.0)
            {
                return Err(format!(
                    "gear {gear}: the body needs a positive rim inertia, a hub inertia ≥ 0 and a \
                     torsional compliance ≥ 0"
                ));
            }
            let shaft = spec.shafts[side];
            if let Some(s) = shaft {
                if !(s.stiffness > 0.0 && s.end_inertia >= 0.0) {
                    return Err(format!(
                        "the {} shaft needs a positive stiffness and an end inertia ≥ 0",
                        ["input", "output"][side]
                    ));
                }
            }
            // A massless shaft end under a constant torque transmits it statically: no
            // coordinate, unless it is the speed-driven end.
            let shaft = shaft.filter(|s| s.end_inertia > 0.0 || (speed && side == 0));
            if spec.shafts[side].is_some() && shaft.is_none() {
                notes.push(format!(
                    "the {} shaft has no inertia at its end: it carries the torque statically \
                     and is left out",
                    ["input", "output"][side]
                ));
            }
            let compliant = body.torsional_compliance > 0.0;
            let held_hub = speed && side == 0 && shaft.is_none();
            let separate_hub = compliant && (shaft.is_some() || held_hub);
            let body_stiffness = if compliant {
                1.0 / (body.torsional_compliance * r2)
            } else {
                0.0
            };
            // The side from its outer end inwards: (name, mass), and the spring inside each
            // consecutive pair.
            if separate_hub && !held_hub && !(body.hub_inertia > 0.0) {
                return Err(format!(
                    "gear {gear}: a hub between its body and a shaft needs an inertia > 0"
                ));
            }
            let mut chain: Vec<(String, f64)> = Vec::new();
            let mut joints: Vec<f64> = Vec::new();
            if let Some(s) = shaft {
                chain.push((["motor", "load"][side].to_string(), s.end_inertia / r2));
                joints.push(s.stiffness / r2);
            }
            if separate_hub {
                chain.push((format!("hub{gear}"), body.hub_inertia / r2));
                joints.push(body_stiffness);
                chain.push((format!("rim{gear}"), body.rim_inertia / r2));
            } else {
                chain.push((format!("rim{gear}"), body.inertia() / r2));
                if compliant {
                    // The free hub's static twist under the end load, F c_b, in the TE.
                    te_per_force += body.torsional_compliance * r2;
                    notes.push(format!(
                        "gear {gear}'s free hub moves with its rim (its body mode lies far above \
                         the mesh mode); the body's static twist is added to the TE"
                    ));
                }
            }
            if side == 1 {
                chain.reverse();
                joints.reverse();
            }
            let first = nodes.len();
            for (j, (name, mass)) in chain.into_iter().enumerate() {
                if name.starts_with("rim") {
                    rims[side] = first + j;
                }
                if name.starts_with("hub") || (name.starts_with("rim") && !separate_hub) {
                    hubs[side] = first + j;
                }
                nodes.push((name, side, mass));
            }
            for (j, stiffness) in joints.into_iter().enumerate() {
                springs.push((first + j, first + j + 1, stiffness));
            }
            if speed && side == 0 {
                prescribed = Some(first);
            }
        }
        let n_rot = nodes.len();
        // The translations along the line of action: (name, side, mass, stiffness, damping).
        // A rim that sways on its body, on a gear that also sits on bearings, sways on both
        // springs in series with the bearings' mass (its statics exact).
        let mut translations = Vec::new();
        for side in 0..2 {
            let sway = spec.gears[side].translation;
            let gear = side + 1;
            let valid = |t: RimTranslation| {
                t.mass > 0.0 && t.stiffness > 0.0 && t.mass.is_finite() && t.stiffness.is_finite()
            };
            if sway.is_some_and(|t| !valid(t)) {
                return Err(format!(
                    "gear {gear}: a swaying rim needs a positive, finite mass and stiffness"
                ));
            }
            match (&spec.bearings, sway) {
                (Some(b), sway) => {
                    let stiffness = match sway {
                        Some(t) => 1.0 / (1.0 / b.stiffness[side] + 1.0 / t.stiffness),
                        None => b.stiffness[side],
                    };
                    translations.push((
                        format!("y{gear}"),
                        side,
                        b.mass[side],
                        stiffness,
                        b.damping[side],
                    ));
                }
                (None, Some(t)) => {
                    translations.push((
                        format!("rim{gear} y"),
                        side,
                        t.mass,
                        t.stiffness,
                        spec.spring_damping.coefficient(t.stiffness, t.mass),
                    ));
                }
                (None, None) => {}
            }
        }
        if spec.bearings.is_some() && spec.gears.iter().any(|g| g.translation.is_some()) {
            notes.push(
                "each rim's sway on its body in series with its bearing, the gear's mass on \
                 both springs"
                    .to_string(),
            );
        }
        // Full (unreduced) matrices over the rotations, then the translations.
        let n_x = n_rot + translations.len();
        let mut m = DMatrix::zeros(n_x, n_x);
        let mut k = DMatrix::zeros(n_x, n_x);
        let mut c = DMatrix::zeros(n_x, n_x);
        for (i, node) in nodes.iter().enumerate() {
            m[(i, i)] = node.2;
        }
        for &(a, b, stiffness) in &springs {
            // The spring's own mode swings everything on either side of it (the chain is joined
            // through the mesh): the reduced inertia of the two sides, or the free side's alone
            // when the other holds the prescribed end.
            let side_mass = |range: std::ops::Range<usize>| -> f64 {
                match prescribed {
                    Some(p) if range.contains(&p) => f64::INFINITY,
                    _ => range.map(|i| nodes[i].2).sum(),
                }
            };
            let (ma, mb) = (side_mass(0..a + 1), side_mass(b..nodes.len()));
            let reduced = match (ma.is_finite(), mb.is_finite()) {
                (false, _) => mb,
                (_, false) => ma,
                _ => ma * mb / (ma + mb),
            };
            let damping = spec.spring_damping.coefficient(stiffness, reduced);
            for (matrix, value) in [(&mut k, stiffness), (&mut c, damping)] {
                matrix[(a, a)] += value;
                matrix[(b, b)] += value;
                matrix[(a, b)] -= value;
                matrix[(b, a)] -= value;
            }
        }
        let mut g = DVector::zeros(n_x);
        g[rims[0]] += 1.0;
        g[rims[1]] -= 1.0;
        let mut names: Vec<String> = nodes.iter().map(|n| n.0.clone()).collect();
        for (i, (name, side, mass, stiffness, damping)) in translations.into_iter().enumerate() {
            let j = n_rot + i;
            m[(j, j)] = mass;
            k[(j, j)] = stiffness;
            c[(j, j)] = damping;
            g[j] = if side == 0 { 1.0 } else { -1.0 };
            names.push(name);
        }
        let mut load = DVector::zeros(n_x);
        load[n_rot - 1] -= 1.0;
        let mut te = DVector::zeros(n_x);
        te[hubs[0]] += 1.0;
        te[hubs[1]] -= 1.0;
        // The reduction x = R y (module docs).
        let (reduction, kept): (DMatrix<f64>, Vec<usize>) = match prescribed {
            Some(p) => {
                let kept: Vec<usize> = (0..n_x).filter(|&i| i != p).collect();
                let r = DMatrix::from_fn(n_x, kept.len(), |i, j| {
                    if i != kept[j] {
                        0.0
                    } else if i < n_rot {
                        -1.0
                    } else {
                        1.0
                    }
                });
                (r, kept)
            }
            None => {
                load[0] += 1.0;
                let last = n_rot - 1;
                let kept: Vec<usize> = (0..n_x).filter(|&i| i != last).collect();
                let e = DMatrix::from_fn(n_x, kept.len(), |i, j| f64::from(i == kept[j]));
                let u = DVector::from_fn(n_x, |i, _| f64::from(i < n_rot));
                let mu = &m * &u;
                let projector = DMatrix::identity(n_x, n_x) - &u * mu.transpose() / u.dot(&mu);
                (projector * e, kept)
            }
        };
        if kept.len() > MAX_DOFS || kept.is_empty() {
            return Err(format!(
                "the drivetrain has {} coordinates; the lumped model takes 1 to {MAX_DOFS}",
                kept.len()
            ));
        }
        let rt = reduction.transpose();
        let effective_mass = spec.drive.effective_mass(
            [spec.gears[0].inertia(), spec.gears[1].inertia()],
            spec.base_radii,
        );
        // Names of the reduced coordinates: relative to the last rotation (torque drive), the lag
        // behind the prescribed motion (speed drive), the bearings' own.
        let reduced_names = kept
            .iter()
            .map(|&i| match prescribed {
                _ if i >= n_rot => names[i].clone(),
                Some(_) => format!("{} lag", names[i]),
                None => format!("{} - {}", names[i], names[n_rot - 1]),
            })
            .collect();
        Ok(Self::from_parts(
            reduced_names,
            &rt * &m * &reduction,
            &rt * &k * &reduction,
            &rt * &c * &reduction,
            [
                (&rt * &g).iter().copied().collect(),
                (&rt * &load).iter().copied().collect(),
                (&rt * &te).iter().copied().collect(),
            ],
            te_per_force,
            effective_mass,
            notes,
        ))
    }

    #[allow(clippy::too_many_arguments)]
    fn from_parts(
        names: Vec<String>,
        mass: DMatrix<f64>,
        stiffness: DMatrix<f64>,
        damping: DMatrix<f64>,
        [mesh, load, te]: [Vec<f64>; 3],
        te_per_force: f64,
        effective_mass: f64,
        notes: Vec<String>,
    ) -> Self {
        let n = names.len();
        let inverse = mass
            .clone()
            .cholesky()
            .expect("a positive definite mass matrix")
            .inverse();
        let to_square = |a: DMatrix<f64>| {
            let mut out = [[0.0; MAX_DOFS]; MAX_DOFS];
            for i in 0..n {
                for j in 0..n {
                    out[i][j] = a[(i, j)];
                }
            }
            out
        };
        let to_vector = |v: &[f64]| {
            let w = &inverse * DVector::from_row_slice(v);
            std::array::from_fn(|i| if i < n { w[i] } else { 0.0 })
        };
        Structure {
            dofs: n,
            inv_mass_stiffness: to_square(&inverse * &stiffness),
            inv_mass_damping: to_square(&inverse * &damping),
            inv_mass_mesh: to_vector(&mesh),
            inv_mass_load: to_vector(&load),
            inv_mass_te: to_vector(&te),
            names,
            mass,
            stiffness,
            damping,
            mesh_direction: DVector::from_vec(mesh),
            load_direction: DVector::from_vec(load),
            te_direction: DVector::from_vec(te),
            te_per_force,
            effective_mass,
            notes,
        }
    }

    /// This structure with the mesh's own moving mass `mesh_mass` m_d [kg] along its
    /// deflection: M + m_d g gᵀ, the kinetic energy ½ m_d δ̇² of the teeth's and rims'
    /// deformation ([`crate::ltca::modal::mesh_moving_mass`]; the consistent mass of a spring's
    /// own distributed mass, Rayleigh). No coordinate more and the statics unchanged; the rigid
    /// rotation a torque drive removes has gᵀu = 0, so its reduction stays exact. The damping
    /// convention's rigid-pair [`Self::effective_mass`] stays as it was.
    pub fn with_mesh_mass(self, mesh_mass: f64) -> Self {
        if mesh_mass == 0.0 {
            return self;
        }
        let g = &self.mesh_direction;
        let mass = &self.mass + g * g.transpose() * mesh_mass;
        let directions = [
            self.mesh_direction.as_slice().to_vec(),
            self.load_direction.as_slice().to_vec(),
            self.te_direction.as_slice().to_vec(),
        ];
        Self::from_parts(
            self.names,
            mass,
            self.stiffness,
            self.damping,
            directions,
            self.te_per_force,
            self.effective_mass,
            self.notes,
        )
    }

    /// Accelerations M⁻¹(F l − K q − C v − g W − h D) into `out`: W the mesh force, D a force
    /// on the hub-to-hub transmission error (the FE's dashpot, [`super::DampingSite`]).
    #[inline]
    pub(crate) fn accelerations(
        &self,
        q: &[f64; MAX_DOFS],
        v: &[f64; MAX_DOFS],
        force: f64,
        [mesh_force, te_force]: [f64; 2],
        out: &mut [f64; MAX_DOFS],
    ) {
        let n = self.dofs;
        for (i, a) in out.iter_mut().enumerate().take(n) {
            let (k, c) = (&self.inv_mass_stiffness[i], &self.inv_mass_damping[i]);
            *a = force * self.inv_mass_load[i]
                - mesh_force * self.inv_mass_mesh[i]
                - te_force * self.inv_mass_te[i]
                - (0..n).map(|j| k[j] * q[j] + c[j] * v[j]).sum::<f64>();
        }
    }

    /// The Jacobian of (q̇, v̇) = (v, a) over (q, v) into the first 2n × 2n entries of `out`:
    /// ∂a/∂q = −M⁻¹K − M⁻¹g W′ gᵀ, ∂a/∂v = −M⁻¹C − M⁻¹g c_g gᵀ − M⁻¹h c_h hᵀ, with W′ the mesh
    /// force's slope dW/dδ and c_g, c_h the dampers on the mesh deflection and on the hubs' TE.
    pub(crate) fn state_jacobian(
        &self,
        mesh_slope: f64,
        [c_mesh, c_hub]: [f64; 2],
        out: &mut Tangent,
    ) {
        let n = self.dofs;
        for row in out.iter_mut().take(n) {
            row[..2 * n].fill(0.0);
        }
        for (i, row) in out.iter_mut().enumerate().take(n) {
            row[n + i] = 1.0;
        }
        let (g, h) = (&self.mesh_direction, &self.te_direction);
        for i in 0..n {
            let (k, c) = (&self.inv_mass_stiffness[i], &self.inv_mass_damping[i]);
            let (mg, mh) = (self.inv_mass_mesh[i], self.inv_mass_te[i]);
            let row = &mut out[n + i];
            for j in 0..n {
                row[j] = -k[j] - mg * mesh_slope * g[j];
                row[n + j] = -c[j] - mg * c_mesh * g[j] - mh * c_hub * h[j];
            }
        }
    }

    /// gᵀx over the first `dofs` entries.
    #[inline]
    pub(crate) fn mesh_of(&self, x: &[f64; MAX_DOFS]) -> f64 {
        (0..self.dofs).map(|i| self.mesh_direction[i] * x[i]).sum()
    }

    /// hᵀx over the first `dofs` entries (without the static twist of condensed hubs).
    #[inline]
    pub(crate) fn te_of(&self, x: &[f64; MAX_DOFS]) -> f64 {
        (0..self.dofs).map(|i| self.te_direction[i] * x[i]).sum()
    }

    /// The static coordinates under the mesh force F with the mesh at deflection `deflection`:
    /// K y + g F = F l with gᵀy = δ, solved as (K + κggᵀ) y = F l + κ(δ − F/κ) g for any
    /// κ > 0: |F/δ| (the right side then loses nothing to cancellation), else K's largest
    /// diagonal entry.
    pub fn static_coordinates(&self, force: f64, deflection: f64) -> [f64; MAX_DOFS] {
        let n = self.dofs;
        let secant = (force / deflection).abs();
        let kappa = if secant.is_finite() && secant > 0.0 {
            secant
        } else {
            (0..n)
                .map(|i| self.stiffness[(i, i)])
                .fold(0.0, f64::max)
                .max(1.0)
        };
        let g = &self.mesh_direction;
        let a = &self.stiffness + g * g.transpose() * kappa;
        let rhs = &self.load_direction * force + g * (kappa * (deflection - force / kappa));
        let y = a
            .lu()
            .solve(&rhs)
            .expect("the structure is held by the mesh");
        std::array::from_fn(|i| if i < n { y[i] } else { 0.0 })
    }

    /// Natural modes with the mesh spring k, ascending in frequency: K + k ggᵀ against M.
    pub fn modes(&self, mesh_stiffness: f64) -> Vec<Mode> {
        let g = &self.mesh_direction;
        let total = &self.stiffness + g * g.transpose() * mesh_stiffness;
        if self.dofs == 1 {
            // √(k/m) as it stands: the schemes' stability test resolves 1e-12 in ωh.
            return vec![Mode {
                frequency: (total[(0, 0)] / self.mass[(0, 0)]).max(0.0).sqrt(),
                mesh_energy_share: 1.0,
                shape: vec![1.0],
            }];
        }
        let l = self
            .mass
            .clone()
            .cholesky()
            .expect("a positive definite mass matrix")
            .l();
        let l_inv = l.clone().try_inverse().expect("a regular Cholesky factor");
        let a = &l_inv * &total * l_inv.transpose();
        let a = (&a + a.transpose()) * 0.5;
        let eigen = SymmetricEigen::new(a);
        let mut modes: Vec<Mode> = (0..self.dofs)
            .map(|j| {
                let phi = l_inv.transpose() * eigen.eigenvectors.column(j);
                let strain = phi.dot(&(&total * &phi));
                let mesh = mesh_stiffness * g.dot(&phi).powi(2);
                let largest = phi
                    .iter()
                    .fold(0.0f64, |m, x| if x.abs() > m.abs() { *x } else { m });
                Mode {
                    frequency: eigen.eigenvalues[j].max(0.0).sqrt(),
                    mesh_energy_share: if strain > 0.0 { mesh / strain } else { 0.0 },
                    shape: phi.iter().map(|x| x / largest).collect(),
                }
            })
            .collect();
        modes.sort_by(|a, b| a.frequency.total_cmp(&b.frequency));
        modes
    }

    /// The mode with the largest share of its strain energy in the mesh: the mesh mode.
    pub fn mesh_mode(&self, mesh_stiffness: f64) -> Mode {
        let mut modes = self.modes(mesh_stiffness);
        let mesh = Self::mesh_mode_index(&modes).expect("at least one mode");
        modes.swap_remove(mesh)
    }

    /// Which of `modes` is the mesh mode: the largest share of its strain energy in the mesh.
    pub fn mesh_mode_index(modes: &[Mode]) -> Option<usize> {
        (0..modes.len()).max_by(|&a, &b| {
            modes[a]
                .mesh_energy_share
                .total_cmp(&modes[b].mesh_energy_share)
        })
    }

    /// The mode other than the mesh mode with the largest share of its kinetic energy in the
    /// coordinate `name` (φ_i (Mφ)_i / φᵀMφ): with `rim1 lag` (the speed drive), the driver
    /// body's torsion, its rim against the held hub. `None` without that coordinate or a
    /// second mode.
    pub fn body_mode(&self, mesh_stiffness: f64, name: &str) -> Option<Mode> {
        let mut modes = self.modes(mesh_stiffness);
        let body = self.body_mode_index(&modes, name)?;
        Some(modes.swap_remove(body))
    }

    /// Which of `modes` (of this structure) is [`Self::body_mode`]'s.
    pub fn body_mode_index(&self, modes: &[Mode], name: &str) -> Option<usize> {
        let i = self.names.iter().position(|n| n == name)?;
        let mesh = Self::mesh_mode_index(modes)?;
        let share = |m: &Mode| {
            let phi = DVector::from_column_slice(&m.shape);
            let m_phi = &self.mass * &phi;
            phi[i] * m_phi[i] / phi.dot(&m_phi)
        };
        (0..modes.len())
            .filter(|j| *j != mesh)
            .max_by(|&a, &b| share(&modes[a]).total_cmp(&share(&modes[b])))
    }

    /// Each mode's share of the structure's static compliance under its load l:
    /// (φᵀl)²/(ω² φᵀMφ) over the sum of the modes' (0 for a mode at rest). The modal expansion
    /// of the static response, lᵀK⁻¹l = Σ (φᵀl)²/(ω² φᵀMφ), as the FE modal analysis's
    /// [`crate::ltca::modal::PairMode::mesh_share`] splits its driven hub's: the one measure
    /// of "how much of the mesh's compliance this mode carries" both models have.
    pub fn load_compliance_shares(&self, modes: &[Mode]) -> Vec<f64> {
        let compliance: Vec<f64> = modes
            .iter()
            .map(|m| {
                let phi = DVector::from_column_slice(&m.shape);
                let generalized = phi.dot(&(&self.mass * &phi));
                match m.frequency > 0.0 && generalized > 0.0 {
                    true => {
                        phi.dot(&self.load_direction).powi(2) / (m.frequency.powi(2) * generalized)
                    }
                    false => 0.0,
                }
            })
            .collect();
        let total: f64 = compliance.iter().sum();
        compliance
            .iter()
            .map(|c| if total > 0.0 { c / total } else { 0.0 })
            .collect()
    }

    /// The mode's share of the effective mass of the coordinate `name` moved alone,
    /// (φᵀMe)²/(φᵀMφ · eᵀMe) (modal effective mass; Clough & Penzien §13-3): with `rim1 lag`
    /// under the speed drive, the share of the driver rim's rotation against its held hub, as
    /// the FE modal's [`crate::ltca::modal::PairMode::rotation_share`] of the driver. `None`
    /// without that coordinate.
    pub fn coordinate_mass_share(&self, mode: &Mode, name: &str) -> Option<f64> {
        let i = self.names.iter().position(|n| n == name)?;
        let phi = DVector::from_column_slice(&mode.shape);
        let m_phi = &self.mass * &phi;
        Some(m_phi[i].powi(2) / (phi.dot(&m_phi) * self.mass[(i, i)]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The speed drive's driver held at its hub: its rim m_r on the body spring k_b, the mesh
    /// k_m to the driven gear m₂ (rigid, base radii 1 m). det(K − ω²M) = 0 with
    /// K = [[k_b + k_m, −k_m], [−k_m, k_m]], M = diag(m_r, m₂):
    /// ω⁴ m_r m₂ − ω² ((k_b + k_m) m₂ + k_m m_r) + k_b k_m = 0. With m₂ = 10 m_r and k_b = 10 k_m
    /// the upper root is the rim's (its kinetic energy almost all in rim1), the lower the mesh
    /// mode, which `body_mode` leaves out however the shares fall.
    #[test]
    fn the_body_mode_is_the_rims_root_of_the_two_dof_pair() {
        let (m_r, m2, k_m) = (0.2, 2.0, 3e8);
        let k_b = 10.0 * k_m;
        let driver = GearBody {
            hub_inertia: 0.05,
            rim_inertia: m_r,
            torsional_compliance: 1.0 / k_b,
            translation: None,
        };
        let structure = Structure::drivetrain(&DrivetrainSpec {
            drive: Drive::Speed,
            base_radii: [1.0, 1.0],
            gears: [driver, GearBody::rigid(m2)],
            shafts: [None; 2],
            bearings: None,
            spring_damping: SpringDamping::Ratio(0.0),
        })
        .expect("a valid pair");
        assert_eq!(structure.names, ["rim1 lag", "rim2 lag"]);
        let (a, b, c) = (m_r * m2, (k_b + k_m) * m2 + k_m * m_r, k_b * k_m);
        let root = |sign: f64| ((b + sign * (b * b - 4.0 * a * c).sqrt()) / (2.0 * a)).sqrt();
        let body = structure.body_mode(k_m, "rim1 lag").expect("two modes");
        assert!((body.frequency / root(1.0) - 1.0).abs() < 1e-9);
        assert!((structure.mesh_mode(k_m).frequency / root(-1.0) - 1.0).abs() < 1e-9);
        assert!(structure.body_mode(k_m, "hub1").is_none());
    }

    /// Among four coordinates (the speed drive's driver rim; the driven gear's rim and hub, a
    /// light rim on a very stiff body; a load behind a shaft), `body_mode` picks the one in
    /// which the driver's light rim moves: neither the lowest mode (the mesh's, or the load's)
    /// nor the highest (the driven rim's). With the rim m_r on its body k_b and the mesh k_m
    /// against a driven gear a hundred times heavier it is the rim alone on both springs,
    /// ω² ≈ (k_b + k_m)/m_r, to the neighbours' share (here under 0.5 %).
    #[test]
    fn the_body_mode_is_the_driver_rims_among_four_coordinates() {
        let (m_r, k_b, k_m) = (0.01, 1e10, 3e8);
        let driver = GearBody {
            hub_inertia: 0.05,
            rim_inertia: m_r,
            torsional_compliance: 1.0 / k_b,
            translation: None,
        };
        let driven = GearBody {
            hub_inertia: 1.0,
            rim_inertia: 1e-3,
            torsional_compliance: 1e-12,
            translation: None,
        };
        let structure = Structure::drivetrain(&DrivetrainSpec {
            drive: Drive::Speed,
            base_radii: [1.0, 1.0],
            gears: [driver, driven],
            shafts: [
                None,
                Some(Shaft {
                    stiffness: 1e8,
                    end_inertia: 5.0,
                }),
            ],
            bearings: None,
            spring_damping: SpringDamping::Ratio(0.0),
        })
        .expect("a valid chain");
        assert_eq!(structure.dofs, 4, "{:?}", structure.names);
        let modes = structure.modes(k_m);
        let body = structure.body_mode(k_m, "rim1 lag").expect("four modes");
        let expected = ((k_b + k_m) / m_r).sqrt();
        assert!(
            (body.frequency / expected - 1.0).abs() < 5e-3,
            "{} against {expected}",
            body.frequency
        );
        assert!(body.frequency > modes[1].frequency && body.frequency < modes[3].frequency);
    }

    /// [`swaying_pair`] with both shafts (2e5 N·m/rad to 0.02 kg·m²) and the rims that `sway`
    /// says swaying (0.8 kg on 4e9 N/m).
    fn shafted_swaying_pair(drive: Drive, sway: [bool; 2]) -> Structure {
        let shaft = Some(Shaft {
            stiffness: 2.0e5,
            end_inertia: 0.02,
        });
        let translation = RimTranslation {
            mass: 0.8,
            stiffness: 4e9,
        };
        swaying_pair(
            drive,
            [shaft; 2],
            None,
            sway.map(|s| s.then_some(translation)),
        )
    }

    /// The modal expansions the shares rest on, on a four-coordinate chain with shafts and
    /// swaying rims under both drives: the modes' load compliances (φᵀl)²/(ω² φᵀMφ) sum to the
    /// static compliance lᵀ(K + k ggᵀ)⁻¹l (the shares are those over it), and the modal
    /// effective masses of a coordinate, (φᵀMe)²/(φᵀMφ), sum to eᵀMe (Clough & Penzien §13-3),
    /// so its shares sum to 1.
    #[test]
    fn mode_shares_are_the_modal_expansions_of_compliance_and_mass() {
        let k_m = 3e8;
        for drive in [Drive::Speed, Drive::Torque] {
            let s = shafted_swaying_pair(drive, [true, true]);
            let modes = s.modes(k_m);
            let total = &s.stiffness + &s.mesh_direction * s.mesh_direction.transpose() * k_m;
            let compliance = s
                .load_direction
                .dot(&total.lu().solve(&s.load_direction).unwrap());
            let shares = s.load_compliance_shares(&modes);
            for (mode, share) in modes.iter().zip(&shares) {
                let phi = DVector::from_column_slice(&mode.shape);
                let own = phi.dot(&s.load_direction).powi(2)
                    / (mode.frequency.powi(2) * phi.dot(&(&s.mass * &phi)));
                assert!(
                    (share * compliance - own).abs() <= 1e-9 * compliance,
                    "{drive:?}"
                );
            }
            assert!((shares.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            for name in s.names.clone() {
                let sum: f64 = modes
                    .iter()
                    .map(|m| s.coordinate_mass_share(m, &name).unwrap())
                    .sum();
                assert!((sum - 1.0).abs() < 1e-9, "{drive:?} {name}: {sum}");
            }
            assert_eq!(s.coordinate_mass_share(&modes[0], "no such"), None);
        }
    }

    /// The mesh's own mass m_d along the deflection: one coordinate, ω = √(k/(m + m_d))
    /// exactly; on four coordinates under both drives every mode falls or stays (Rayleigh: M
    /// grows by a positive semidefinite m_d ggᵀ), the mesh mode measurably; and added after the
    /// torque drive's removal of the rigid rotation it gives the frequencies of the whole
    /// chain with m_d added before it (motor, gears and load on shafts, the driver's rim
    /// swaying, so that g is not the TE's direction; the generalized eigenproblem of the five
    /// unreduced coordinates, one root at zero), to 1e-9.
    #[test]
    fn the_meshs_own_mass_lowers_the_modes_and_reduces_exactly() {
        let (m, m_d, k): (f64, f64, f64) = (0.57, 0.0097, 4.0e8);
        let one = Structure::rigid_pair(m).with_mesh_mass(m_d);
        let expected = (k / (m + m_d)).sqrt();
        assert!((one.modes(k)[0].frequency / expected - 1.0).abs() < 1e-14);
        for drive in [Drive::Speed, Drive::Torque] {
            let bare = shafted_swaying_pair(drive, [true, false]);
            let massive = bare.clone().with_mesh_mass(m_d);
            for (lighter, heavier) in bare.modes(k).iter().zip(massive.modes(k)) {
                assert!(
                    heavier.frequency <= lighter.frequency * (1.0 + 1e-12),
                    "{drive:?}"
                );
            }
            let (f0, f1) = (bare.mesh_mode(k).frequency, massive.mesh_mode(k).frequency);
            assert!(f1 < f0 * (1.0 - 1e-4), "{drive:?}: {f1} / {f0}");
        }
        // The whole chain, unreduced, the mesh's mass added first: motor, gear 1, gear 2, load
        // (inertia m, base radii 1 m) on two shafts k, the mesh k between the gears, gear 1's
        // rim swaying (m_y on k_y), so g = (0, 1, −1, 0, 1) differs from the TE's direction.
        let (m, k_chain, m_d, m_y, k_y) = (2.5, 4.0e6, 0.6, 1.5, 9.0e6);
        let swaying = Structure::drivetrain(&DrivetrainSpec {
            drive: Drive::Torque,
            base_radii: [1.0, 1.0],
            gears: [
                GearBody {
                    translation: Some(RimTranslation {
                        mass: m_y,
                        stiffness: k_y,
                    }),
                    ..GearBody::rigid(m)
                },
                GearBody::rigid(m),
            ],
            shafts: [Some(Shaft {
                stiffness: k_chain,
                end_inertia: m,
            }); 2],
            bearings: None,
            spring_damping: SpringDamping::Ratio(0.0),
        })
        .expect("a valid chain");
        assert_eq!(swaying.dofs, 4, "{:?}", swaying.names);
        let reduced = swaying.with_mesh_mass(m_d);
        let g = DVector::from_vec(vec![0.0, 1.0, -1.0, 0.0, 1.0]);
        let mass = DMatrix::from_diagonal(&DVector::from_vec(vec![m, m, m, m, m_y]))
            + &g * g.transpose() * m_d;
        let mut stiffness = &g * g.transpose() * k_chain;
        for (i, j) in [(0, 1), (2, 3)] {
            stiffness[(i, i)] += k_chain;
            stiffness[(j, j)] += k_chain;
            stiffness[(i, j)] -= k_chain;
            stiffness[(j, i)] -= k_chain;
        }
        stiffness[(4, 4)] += k_y;
        let l_inv = mass.cholesky().unwrap().l().try_inverse().unwrap();
        let a = &l_inv * stiffness * l_inv.transpose();
        let mut whole: Vec<f64> = SymmetricEigen::new((&a + a.transpose()) * 0.5)
            .eigenvalues
            .iter()
            .map(|l| l.max(0.0).sqrt())
            .collect();
        whole.sort_by(f64::total_cmp);
        assert!(whole[0] < 1e-6 * whole[1], "{whole:?}");
        for (mode, expected) in reduced.modes(k_chain).iter().zip(&whole[1..]) {
            assert!(
                (mode.frequency / expected - 1.0).abs() < 1e-9,
                "{} against {expected}",
                mode.frequency
            );
        }
    }

    fn chain(drive: Drive, inertia: f64, stiffness: f64) -> Structure {
        // Base radii 1 m: the line-of-action coordinates are the rotations themselves.
        Structure::drivetrain(&DrivetrainSpec {
            drive,
            base_radii: [1.0, 1.0],
            gears: [GearBody::rigid(inertia); 2],
            shafts: [Some(Shaft {
                stiffness,
                end_inertia: inertia,
            }); 2],
            bearings: None,
            spring_damping: SpringDamping::Ratio(0.0),
        })
        .expect("a valid chain")
    }

    /// Motor, two gears and load, all of inertia m, joined by three springs k (shafts and the
    /// mesh): a uniform chain. Free-free (torque drive) it has ω_j = 2√(k/m) sin(jπ/8),
    /// j = 1..3, besides the rigid rotation it removes; held at the motor (speed drive) the
    /// fixed-free chain of three masses has ω_j = 2√(k/m) sin((2j − 1)π/14) (the uniform
    /// lattice's dispersion relation, e.g. Rao, *Mechanical Vibrations*, §6.12 / §8.6).
    #[test]
    fn uniform_chain_has_the_lattice_frequencies() {
        let (m, k): (f64, f64) = (2.5, 4.0e6);
        let scale = 2.0 * (k / m).sqrt();
        let free = chain(Drive::Torque, m, k);
        assert_eq!(free.dofs, 3);
        let modes = free.modes(k);
        for (j, mode) in modes.iter().enumerate() {
            let expected = scale * ((j + 1) as f64 * std::f64::consts::PI / 8.0).sin();
            assert!(
                (mode.frequency / expected - 1.0).abs() < 1e-12,
                "{j}: {}",
                mode.frequency
            );
        }
        let held = chain(Drive::Speed, m, k);
        assert_eq!(held.dofs, 3);
        for (j, mode) in held.modes(k).iter().enumerate() {
            let expected = scale * ((2 * j + 1) as f64 * std::f64::consts::PI / 14.0).sin();
            assert!(
                (mode.frequency / expected - 1.0).abs() < 1e-12,
                "{j}: {}",
                mode.frequency
            );
        }
    }

    /// Rigid gears without shafts reduce to p with the 1-DOF effective masses.
    #[test]
    fn rigid_pair_reduces_to_the_relative_coordinate() {
        let (i1, i2, rb) = (3.0e-3, 7.0e-3, [0.05, 0.08]);
        for drive in [Drive::Torque, Drive::Speed] {
            let s = Structure::drivetrain(&DrivetrainSpec {
                drive,
                base_radii: rb,
                gears: [GearBody::rigid(i1), GearBody::rigid(i2)],
                shafts: [None; 2],
                bearings: None,
                spring_damping: SpringDamping::Ratio(0.02),
            })
            .unwrap();
            assert_eq!(s.dofs, 1);
            let m = drive.effective_mass([i1, i2], rb);
            assert!((s.mass[(0, 0)] / m - 1.0).abs() < 1e-12);
            assert_eq!(
                (s.mesh_direction[0], s.load_direction[0], s.te_direction[0]),
                (1.0, 1.0, 1.0)
            );
        }
    }

    /// A pair of elastic gears (base radii 50 / 80 mm, hub 10 % of 3e-3 / 7e-3 kg·m², body
    /// compliances 2e-8 / 5e-8 rad/(N·m)) under `drive` with `shafts` and `bearings`.
    fn elastic_pair(
        drive: Drive,
        shafts: [Option<Shaft>; 2],
        bearings: Option<Bearings>,
    ) -> Structure {
        swaying_pair(drive, shafts, bearings, [None; 2])
    }

    /// [`elastic_pair`] with the rims swaying as `sway` gives.
    fn swaying_pair(
        drive: Drive,
        shafts: [Option<Shaft>; 2],
        bearings: Option<Bearings>,
        sway: [Option<RimTranslation>; 2],
    ) -> Structure {
        let body = |i: f64, c: f64, translation| GearBody {
            hub_inertia: 0.1 * i,
            rim_inertia: 0.9 * i,
            torsional_compliance: c,
            translation,
        };
        Structure::drivetrain(&DrivetrainSpec {
            drive,
            base_radii: RB,
            gears: [body(3e-3, TWIST[0], sway[0]), body(7e-3, TWIST[1], sway[1])],
            shafts,
            bearings,
            spring_damping: SpringDamping::Ratio(0.02),
        })
        .unwrap()
    }

    /// Stiffness-proportional spring damping (the explicit FE's Rayleigh β) is C = β K over the
    /// whole structure, shafts and bodies, whatever the drive: the reduction to independent
    /// coordinates maps both matrices alike. A damping ratio is not proportional: its c grows
    /// as √k, so the same check fails for it.
    #[test]
    fn stiffness_proportional_springs_give_beta_times_the_stiffness() {
        let shaft = Some(Shaft {
            stiffness: 2.0e5,
            end_inertia: 0.05,
        });
        let body = |i: f64, c: f64| GearBody {
            hub_inertia: 0.1 * i,
            rim_inertia: 0.9 * i,
            torsional_compliance: c,
            translation: None,
        };
        let beta = 1.0e-9;
        for drive in [Drive::Torque, Drive::Speed] {
            let build = |spring_damping| {
                Structure::drivetrain(&DrivetrainSpec {
                    drive,
                    base_radii: RB,
                    gears: [body(3e-3, TWIST[0]), body(7e-3, TWIST[1])],
                    shafts: [shaft; 2],
                    bearings: None,
                    spring_damping,
                })
                .unwrap()
            };
            let s = build(SpringDamping::StiffnessProportional(beta));
            let expected = &s.stiffness * beta;
            let scale = expected.amax();
            assert!(scale > 0.0);
            assert!(
                (&s.damping - &expected).amax() <= 1e-12 * scale,
                "{drive:?}: {} vs {}",
                s.damping,
                expected
            );
            let ratio = build(SpringDamping::Ratio(0.02));
            let c_over_k: Vec<f64> = ratio
                .damping
                .iter()
                .zip(ratio.stiffness.iter())
                .filter(|(_, k)| k.abs() > 0.0)
                .map(|(c, k)| c / k)
                .collect();
            let spread = c_over_k.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                - c_over_k.iter().copied().fold(f64::INFINITY, f64::min);
            assert!(spread > 1e-3 * c_over_k[0].abs(), "{drive:?}: {c_over_k:?}");
        }
    }

    const RB: [f64; 2] = [0.05, 0.08];
    const TWIST: [f64; 2] = [2e-8, 5e-8];
    const FORCE: f64 = 3000.0;
    const DELTA: f64 = 7e-6;

    /// The static state of `s` at mesh deflection δ under F: δ comes back (1e-12), and the TE
    /// hub to hub is δ + F(c₁r_b1² + c₂r_b2²) + F·`extra_compliance` (1e-9).
    fn assert_static_te(s: &Structure, extra_compliance: f64, what: &str) {
        let q = s.static_coordinates(FORCE, DELTA);
        assert!((s.mesh_of(&q) / DELTA - 1.0).abs() < 1e-12);
        let te = s.te_of(&q) + FORCE * s.te_per_force;
        let twist = TWIST[0] * RB[0] * RB[0] + TWIST[1] * RB[1] * RB[1];
        let expected = DELTA + FORCE * (twist + extra_compliance);
        assert!(
            (te / expected - 1.0).abs() < 1e-9,
            "{what}: {te} vs {expected}"
        );
    }

    /// Elastic bodies: the static TE is the mesh deflection plus each body's twist under the
    /// load, c_b F, whether a hub is a coordinate (the held driver's) or condensed (free).
    #[test]
    fn static_transmission_error_holds_the_bodies_twist() {
        for drive in [Drive::Torque, Drive::Speed] {
            let s = elastic_pair(drive, [None; 2], None);
            assert_static_te(&s, 0.0, drive.name());
            // The held driver's hub is the ground, its rim a coordinate; free hubs condense.
            assert_eq!(s.dofs, if drive == Drive::Speed { 2 } else { 1 });
        }
    }

    /// Swaying rims: the static TE hub to hub is δ + the twist + F/k_y1 + F/k_y2 (the rims
    /// give way along the line of action, y₁ = −F/k_y1, y₂ = F/k_y2), with two coordinates
    /// more; on bearings too, each rim's sway in series with its bearing, F(1/k_b + 1/k_y) per
    /// gear, on the bearings' two coordinates. Both drives.
    #[test]
    fn static_transmission_error_holds_the_rims_sway() {
        let sway = |mass: f64, stiffness: f64| Some(RimTranslation { mass, stiffness });
        let sways = [sway(0.5, 2e10), sway(1.5, 8e9)];
        let bearings = Bearings {
            mass: [2.0, 3.0],
            stiffness: [4e8, 6e8],
            damping: [100.0, 100.0],
        };
        for drive in [Drive::Torque, Drive::Speed] {
            let s = swaying_pair(drive, [None; 2], None, sways);
            assert_static_te(&s, 1.0 / 2e10 + 1.0 / 8e9, drive.name());
            let rotations = if drive == Drive::Speed { 2 } else { 1 };
            assert_eq!(s.dofs, rotations + 2, "{:?}", s.names);
            assert_eq!(&s.names[rotations..], ["rim1 y", "rim2 y"]);
            let s = swaying_pair(drive, [None; 2], Some(bearings.clone()), sways);
            let series = 1.0 / 4e8 + 1.0 / 2e10 + 1.0 / 6e8 + 1.0 / 8e9;
            assert_static_te(&s, series, drive.name());
            assert_eq!(&s.names[rotations..], ["y1", "y2"]);
            // One gear swaying: one coordinate.
            let s = swaying_pair(drive, [None; 2], None, [None, sways[1]]);
            assert_static_te(&s, 1.0 / 8e9, drive.name());
            assert_eq!(s.dofs, rotations + 1);
        }
    }

    /// The driven gear's rim swaying against the held driver's rigid mesh: speed drive, rigid
    /// gears, coordinates the driven lag q and its rim's sway y, δ = q − y (base radii 1 m).
    /// M = diag(m₂, m_y), K = k_m g gᵀ + diag(0, k_y), g = (1, −1):
    /// m₂ m_y ω⁴ − ω²(k_m m_y + (k_m + k_y) m₂) + k_m k_y = 0; the mesh mode (most of its
    /// strain in the mesh) is the lower root where the sway is stiffer than the mesh, and a
    /// sway far stiffer leaves the rigid pair's √(k_m/m₂).
    #[test]
    fn a_swaying_rim_lowers_the_mesh_mode_as_the_two_dof_system_does() {
        let (m2, m_y, k_m) = (2.0, 1.2, 3e8);
        let structure = |k_y: f64| {
            Structure::drivetrain(&DrivetrainSpec {
                drive: Drive::Speed,
                base_radii: [1.0, 1.0],
                gears: [
                    GearBody::rigid(0.5),
                    GearBody {
                        translation: Some(RimTranslation {
                            mass: m_y,
                            stiffness: k_y,
                        }),
                        ..GearBody::rigid(m2)
                    },
                ],
                shafts: [None; 2],
                bearings: None,
                spring_damping: SpringDamping::Ratio(0.0),
            })
            .expect("a valid pair")
        };
        for k_y in [0.5 * k_m, 2.0 * k_m, 10.0 * k_m] {
            let s = structure(k_y);
            assert_eq!(s.names, ["rim2 lag", "rim2 y"]);
            let (a, b, c) = (m2 * m_y, k_m * m_y + (k_m + k_y) * m2, k_m * k_y);
            let root = |sign: f64| ((b + sign * (b * b - 4.0 * a * c).sqrt()) / (2.0 * a)).sqrt();
            let modes = s.modes(k_m);
            assert!((modes[0].frequency / root(-1.0) - 1.0).abs() < 1e-9);
            assert!((modes[1].frequency / root(1.0) - 1.0).abs() < 1e-9);
            // A sway stiffer than the mesh (a gear body's: 17/53's large gear 27 × its mesh)
            // leaves the mesh most strain in the lower root; a softer one in the upper.
            let mesh_root = if k_y > k_m { root(-1.0) } else { root(1.0) };
            assert!((s.mesh_mode(k_m).frequency / mesh_root - 1.0).abs() < 1e-9);
        }
        let stiff = structure(1e6 * k_m).mesh_mode(k_m).frequency;
        assert!((stiff / (k_m / m2).sqrt() - 1.0).abs() < 1e-5);
    }

    /// With shafts, motor and load, and bearings, the hubs are coordinates of their own: the
    /// static TE hub to hub is δ + F(c₁r_b1² + c₂r_b2²) + F/k_b1 + F/k_b2 — the bodies' twist
    /// and the centres giving way along the line of action (y₁ = −F/k_b1, y₂ = F/k_b2), the
    /// shafts outside the hubs adding nothing — and the mesh deflection is δ; both drives.
    #[test]
    fn static_transmission_error_with_shafts_and_bearings() {
        for drive in [Drive::Torque, Drive::Speed] {
            let shaft = |stiffness: f64, end_inertia: f64| {
                Some(Shaft {
                    stiffness,
                    end_inertia,
                })
            };
            let s = elastic_pair(
                drive,
                [shaft(2e5, 2e-2), shaft(3e5, 5e-2)],
                Some(Bearings {
                    mass: [2.0, 3.0],
                    stiffness: [4e8, 6e8],
                    damping: [100.0, 100.0],
                }),
            );
            // motor, hub1, rim1, rim2, hub2, load, y1, y2 less the rigid rotation or the motor.
            assert_eq!(s.dofs, 7, "{:?}", s.names);
            assert_static_te(&s, 1.0 / 4e8 + 1.0 / 6e8, drive.name());
            assert_eq!(s.te_per_force, 0.0);
        }
    }
}
