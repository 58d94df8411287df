//! The potential-energy (analytical) mesh stiffness: each tooth a non-uniform cantilever on a
//! flexible fillet foundation, in series with Hertzian contact.
//!
//! For a unit normal load at the contact point P = (x_P, y_P) of a tooth (tooth-local frame: the
//! centre line is +y), with α₁ the angle between the load line and the normal to the centre line
//! (Yang & Lin 1987; Tian 2004; Chaari et al. 2009), integrating over the tooth from its root
//! section y₀ to y_P with half-width x(y), A = 2xB, I = (2x)³B/12:
//! ```text
//! 1/k_b = ∫ [(y_P − y) cos α₁ − x_P sin α₁]² / (E′ I) dy        bending
//! 1/k_s = ∫ 1.2 cos² α₁ / (G A) dy                              shear
//! 1/k_a = ∫ sin² α₁ / (E′ A) dy                                 axial compression
//! 1/k_f = cos² α₁/(E′ B) [L*(u_f/S_f)² + M*(u_f/S_f) + P*(1 + Q* tan² α₁)]   fillet foundation
//!         (Sainsot, Velex & Duverger 2004: X* = A/θ_f² + B h_f² + C h_f/θ_f + D/θ_f + E h_f + F,
//!          h_f = r_f/r_bore, θ_f the half tooth angle at the root circle, S_f = 2 r_f θ_f,
//!          u_f the distance from the root circle to where the load line crosses the centre line)
//! 1/k_h = 4 (1 − ν²) / (π E B)                                  Hertz, line contact (Yang & Sun 1985)
//! 1/k_pair = 1/k_h + Σ_gears (1/k_b + 1/k_s + 1/k_a + 1/k_f),     k(θ) = Σ_pairs in contact k_pair
//! ```
//! E′ = E in plane stress, E/(1 − ν²) in plane strain; G = E/(2(1 + ν)). The tooth profile is the
//! exact rack-generated one (fillet and involute), unmodified; the pairs in contact are the
//! geometric ones (no load sharing by deflection).

use crate::fe::PlaneState;
use crate::geometry::{FlankModification, Gear, GearPair, OutlineResolution, Segment, Side};

use super::{MeshStiffness, PeriodicTable};

/// Sainsot et al. (2004), Table 1: rows L*, M*, P*, Q*; columns A, B, C, D, E, F.
const SAINSOT: [[f64; 6]; 4] = [
    [-5.574e-5, -1.9986e-3, -2.3015e-4, 4.7702e-3, 0.0271, 6.8045],
    [60.111e-5, 28.100e-3, -83.431e-4, -9.9256e-3, 0.1624, 0.9086],
    [-50.952e-5, 185.50e-3, 0.0538e-4, 53.300e-3, 0.2895, 0.9236],
    [
        -6.2042e-5, 9.0889e-3, -4.0964e-4, 7.8297e-3, -0.1472, 0.6904,
    ],
];

/// Compliance contributions of one tooth for a unit load at roll angle ξ [m/N].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToothCompliance {
    pub bending: f64,
    pub shear: f64,
    pub axial: f64,
    pub foundation: f64,
}

impl ToothCompliance {
    pub fn total(&self) -> f64 {
        self.bending + self.shear + self.axial + self.foundation
    }
}

/// The tooth's half-width x(y) from the root section up, sampled from the exact profile.
struct ToothShape {
    /// (y, x) of the right side, y ascending, from the fillet's root point to the tip corner.
    samples: Vec<(f64, f64)>,
}

impl ToothShape {
    fn new(gear: &Gear) -> Self {
        let res = OutlineResolution {
            root: 1,
            fillet: 400,
            flank: 1600,
            tip: 1,
        };
        let samples = gear
            .tooth_outline(&FlankModification::none(), res)
            .iter()
            .filter(|p| {
                p.side == Side::Right && matches!(p.segment, Segment::Fillet | Segment::Flank)
            })
            .map(|p| (p.position.y, p.position.x))
            .collect();
        ToothShape { samples }
    }

    /// ∫_{y₀}^{y_P} f(y, x(y)) dy by the trapezoidal rule on the profile samples.
    fn integrate(&self, y_load: f64, f: impl Fn(f64, f64) -> f64) -> f64 {
        let mut sum = 0.0;
        for w in self.samples.windows(2) {
            let ((y0, x0), (y1, x1)) = (w[0], w[1]);
            if y0 >= y_load {
                break;
            }
            let (y1c, x1c) = if y1 > y_load {
                (y_load, x0 + (x1 - x0) * (y_load - y0) / (y1 - y0))
            } else {
                (y1, x1)
            };
            sum += 0.5 * (f(y0, x0) + f(y1c, x1c)) * (y1c - y0);
        }
        sum
    }
}

/// Compliances of `gear`'s tooth for a unit load at roll angle ξ on its flank.
pub fn tooth_compliance(
    gear: &Gear,
    roll_angle: f64,
    youngs_modulus: f64,
    poisson_ratio: f64,
    plane: PlaneState,
) -> ToothCompliance {
    let shape = ToothShape::new(gear);
    tooth_compliance_with(
        gear,
        &shape,
        roll_angle,
        youngs_modulus,
        poisson_ratio,
        plane,
    )
}

fn tooth_compliance_with(
    gear: &Gear,
    shape: &ToothShape,
    roll_angle: f64,
    youngs_modulus: f64,
    poisson_ratio: f64,
    plane: PlaneState,
) -> ToothCompliance {
    let b = gear.spec.face_width;
    let e_eff = match plane {
        PlaneState::Stress => youngs_modulus,
        PlaneState::Strain => youngs_modulus / (1.0 - poisson_ratio * poisson_ratio),
    };
    let g = youngs_modulus / (2.0 * (1.0 + poisson_ratio));
    let p = gear.generated_flank_point(roll_angle);
    let f = gear.flank_inward_normal(roll_angle);
    // Load angle below the normal to the centre line: f = (−cos α₁, −sin α₁).
    let alpha1 = (-f.y).atan2(-f.x);
    let (c, s) = (alpha1.cos(), alpha1.sin());
    let bending = shape.integrate(p.y, |y, x| {
        let moment = (p.y - y) * c - p.x * s;
        moment * moment / (e_eff * b * (2.0 * x).powi(3) / 12.0)
    });
    let shear = shape.integrate(p.y, |_, x| 1.2 * c * c / (g * 2.0 * x * b));
    let axial = shape.integrate(p.y, |_, x| s * s / (e_eff * 2.0 * x * b));
    // Fillet foundation.
    let theta_f = gear.fillet_root_angle();
    let h_f = gear.root_radius / gear.spec.bore_radius;
    let star: Vec<f64> = SAINSOT
        .iter()
        .map(|[a, bb, cc, d, e, ff]| {
            a / theta_f.powi(2) + bb * h_f * h_f + cc * h_f / theta_f + d / theta_f + e * h_f + ff
        })
        .collect();
    let crossing = p.y - p.x * alpha1.tan();
    let u_f = crossing - gear.root_radius;
    let s_f = 2.0 * gear.root_radius * theta_f;
    let ratio = u_f / s_f;
    let foundation = c * c / (e_eff * b)
        * (star[0] * ratio * ratio
            + star[1] * ratio
            + star[2] * (1.0 + star[3] * alpha1.tan().powi(2)));
    ToothCompliance {
        bending,
        shear,
        axial,
        foundation,
    }
}

/// Hertzian line-contact compliance 4(1 − ν²)/(π E B) [m/N].
pub fn hertz_compliance(youngs_modulus: f64, poisson_ratio: f64, face_width: f64) -> f64 {
    4.0 * (1.0 - poisson_ratio * poisson_ratio)
        / (std::f64::consts::PI * youngs_modulus * face_width)
}

/// The potential-energy mesh stiffness over one base pitch at `positions` driver rotations
/// θ₁ = j (2π/z₁)/N from the pitch-point position (the LTCA's grid).
pub fn potential_energy_table(
    pair: &GearPair,
    positions: usize,
    youngs_modulus: f64,
    poisson_ratio: f64,
    plane: PlaneState,
) -> MeshStiffness {
    let shapes = [
        ToothShape::new(&pair.gears[0]),
        ToothShape::new(&pair.gears[1]),
    ];
    let face = pair.gears[0]
        .spec
        .face_width
        .min(pair.gears[1].spec.face_width);
    let hertz = hertz_compliance(youngs_modulus, poisson_ratio, face);
    let c = pair.contact_points;
    let pair_stiffness = |s: f64| {
        let mut compliance = hertz;
        for (i, gear) in pair.gears.iter().enumerate() {
            let xi = pair.roll_angle_at(i + 1, s);
            compliance +=
                tooth_compliance_with(gear, &shapes[i], xi, youngs_modulus, poisson_ratio, plane)
                    .total();
        }
        1.0 / compliance
    };
    let rb1 = pair.gears[0].base_radius;
    let period = pair.gears[0].angular_pitch();
    let stiffness = PeriodicTable::from_fn(period, positions, |rotation| {
        crate::geometry::engaged_pairs(pair, rotation, rotation, 0.0)
            .iter()
            .map(|p| rb1 * p.roll_angle(pair, rotation))
            .filter(|s| *s >= c.icp && *s <= c.fcp)
            .map(pair_stiffness)
            .sum()
    });
    // Linear in the load (Hertz linearized): no load; no relief: no unloaded TE.
    MeshStiffness {
        source: "potential-energy".into(),
        load_torque: None,
        origin: c.pitch / rb1,
        stiffness,
        unloaded_te: PeriodicTable::constant(period, 0.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::samples;

    /// A uniform cantilever check of the integrator: for a load at the tip of a beam of constant
    /// half-width the bending term reduces to F L³/(3 E I); here the real tooth is tapered, so we
    /// check the ordering the physics demands instead: compliance grows towards the tip, bending
    /// dominates, and the pair stiffness lies in the range ISO 6336 gives for steel spur teeth
    /// (c′ ≈ 12–18 N/(mm·µm)).
    #[test]
    fn tooth_compliance_grows_towards_the_tip() {
        let pair = samples::paper36_pair();
        let gear = &pair.gears[0];
        let roll = pair.flank_roll_angles(1);
        let low = tooth_compliance(
            gear,
            roll.start_of_active_profile,
            206e9,
            0.3,
            PlaneState::Stress,
        );
        let high = tooth_compliance(gear, roll.tip, 206e9, 0.3, PlaneState::Stress);
        assert!(high.bending > 3.0 * low.bending);
        assert!(high.total() > low.total());
        assert!(high.bending > high.shear && high.bending > high.axial);
        // Single pair at the pitch point, per unit face width.
        let s = pair.contact_points.pitch;
        let k = 1.0
            / (hertz_compliance(206e9, 0.3, 0.0254)
                + (1..=2)
                    .map(|i| {
                        tooth_compliance(
                            pair.gear(i),
                            pair.roll_angle_at(i, s),
                            206e9,
                            0.3,
                            PlaneState::Stress,
                        )
                        .total()
                    })
                    .sum::<f64>());
        let per_width = k / 25.4 / 1e6; // N/(mm·µm)
        assert!(
            (10.0..20.0).contains(&per_width),
            "single-pair stiffness {per_width} N/(mm·µm)"
        );
    }

    #[test]
    fn table_has_double_contact_steps() {
        let pair = samples::paper36_pair();
        let table = potential_energy_table(&pair, 64, 206e9, 0.3, PlaneState::Strain);
        assert!(table.max() > 1.3 * table.min());
        assert_eq!(table.stiffness.values.len(), 64);
    }
}
