//! Contact pressure along the path of contact: each loaded tooth pair of an LTCA position as two
//! cylinders of the involutes' curvature radii at its contact point (Hertz, line contact).
//!
//! ```text
//! ρ₁ = s,  ρ₂ = T₁T₂ − s              (s: the contact's distance from T₁ along the line of action)
//! 1/R = 1/ρ₁ + 1/ρ₂,   w = W/b,   E* = 1/[(1 − ν₁²)/E₁ + (1 − ν₂²)/E₂]
//! p_H = √(w E* / (π R)) = Z_E √(w/R),   half width a = √(4 w R / (π E*))
//! ```
//! W is the pair's normal force from the LTCA (its own load sharing, relief and loaded contact
//! ratio), s its force-weighted contact position. At the pitch point with one pair carrying the
//! whole normal force this is ISO 6336-2's σ_H0/Z_ε exactly (tested). Where the contact sits at
//! a tip corner (a relief that does not clear the entering or leaving tip, or none) the involute's
//! curvature is not the corner's: such points are flagged `at_tip`, and what the FE's contact
//! gives there (edge contact) is larger than this formula.

use std::f64::consts::PI;

use super::iso6336::Elastic;
use crate::geometry::GearPair;
use crate::ltca::PositionResult;

/// A contact closer than this share of a base pitch to the path's ends (A, E) is at a tip.
pub const TIP_ZONE: f64 = 0.02;

/// The Hertz pressure of one loaded tooth pair at one position.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PressurePoint {
    /// Position index in the cycle and the driver's rotation there [rad].
    pub position: usize,
    pub driver_rotation_rad: f64,
    /// Tooth pair (index into the LTCA's `tooth_pairs`).
    pub pair: usize,
    /// Contact position along the line of action from T₁ [m].
    pub path_m: f64,
    pub force_n: f64,
    /// Involute curvature radii of gear 1 and gear 2 at the contact [m].
    pub curvature_radii_m: [f64; 2],
    pub pressure_pa: f64,
    pub half_width_m: f64,
    /// The contact is at a tip corner: the involute's curvature does not hold there.
    pub at_tip: bool,
}

/// E* of two elastic bodies [Pa].
pub fn contact_modulus(materials: [Elastic; 2]) -> f64 {
    1.0 / materials
        .iter()
        .map(|m| (1.0 - m.poisson_ratio * m.poisson_ratio) / m.youngs_modulus)
        .sum::<f64>()
}

/// Hertz line contact of a normal force `force` [N] over the face width `width` [m] between
/// radii `radii` [m]: (p_H [Pa], half width a [m]).
pub fn line_contact(force: f64, width: f64, radii: [f64; 2], modulus: f64) -> (f64, f64) {
    let r = 1.0 / (1.0 / radii[0] + 1.0 / radii[1]);
    let w = force / width;
    (
        (w * modulus / (PI * r)).sqrt(),
        (4.0 * w * r / (PI * modulus)).sqrt(),
    )
}

/// The pressure of every loaded pair at every position of an LTCA cycle.
pub fn along_path(
    pair: &GearPair,
    materials: [Elastic; 2],
    results: &[PositionResult],
) -> Vec<PressurePoint> {
    let modulus = contact_modulus(materials);
    let width = pair.gears[0]
        .spec
        .face_width
        .min(pair.gears[1].spec.face_width);
    let length = pair.line_of_action_length;
    let points = pair.contact_points;
    let tip = TIP_ZONE * pair.base_pitch;
    let mut out = Vec::new();
    for (position, result) in results.iter().enumerate() {
        for (k, (&force, s)) in result
            .pair_forces
            .iter()
            .zip(&result.pair_positions)
            .enumerate()
        {
            let Some(s) = *s else { continue };
            if !(force > 0.0) {
                continue;
            }
            let radii = [s, length - s];
            let (pressure, half_width) = line_contact(force, width, radii, modulus);
            out.push(PressurePoint {
                position,
                driver_rotation_rad: result.driver_rotation,
                pair: k,
                path_m: s,
                force_n: force,
                curvature_radii_m: radii,
                pressure_pa: pressure,
                half_width_m: half_width,
                at_tip: s < points.icp + tip || s > points.fcp - tip,
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::strength::iso6336::{contact_stress, tangential_force};

    /// One pair carrying the whole normal force W = F_t/cos α at the pitch point is ISO
    /// 6336-2's σ_H0 without the load sharing Z_ε: Z_H Z_E √(F_t/(d₁b)·(u+1)/u) (the zone
    /// factor is the pitch point's curvature in Hertz's formula), on the paper's pair and on a
    /// shifted 24/40 pair at its own centre distance.
    #[test]
    fn hertz_at_the_pitch_point_is_the_standards_nominal_stress() {
        let steel = Elastic {
            youngs_modulus: 206e9,
            poisson_ratio: 0.3,
        };
        for case in [
            crate::samples::paper36_case(),
            crate::case::Case::load_with(
                None,
                &[
                    crate::case::Override::set("gear1.teeth", 24),
                    crate::case::Override::set("gear2.teeth", 40),
                    crate::case::Override::set("gear1.profile_shift", 0.3),
                    crate::case::Override::set("gear2.profile_shift", -0.1),
                ],
            )
            .unwrap(),
        ] {
            let pair = &case.pair;
            let f_t = tangential_force(pair, 143.6);
            let iso = contact_stress(pair, [steel; 2], f_t);
            let normal = f_t / pair.gears[0].rack.pressure_angle.cos();
            let s = pair.contact_points.pitch;
            let (p, _) = line_contact(
                normal,
                pair.gears[0].spec.face_width,
                [s, pair.line_of_action_length - s],
                contact_modulus([steel; 2]),
            );
            let nominal = iso.sigma_h0_pa / iso.contact_ratio_factor;
            assert!((p / nominal - 1.0).abs() < 1e-12, "{p} against {nominal}");
        }
    }

    /// E* and the half width against the closed form for equal steel cylinders: p = √(wE*/πR),
    /// a = 2√(wR/πE*), so p·a = 2w/π (the semi-elliptic pressure's resultant is w).
    #[test]
    fn the_pressure_integrates_to_the_load() {
        let steel = Elastic {
            youngs_modulus: 206e9,
            poisson_ratio: 0.3,
        };
        let modulus = contact_modulus([steel; 2]);
        assert!((modulus - 206e9 / (2.0 * 0.91)).abs() < 1.0);
        let (p, a) = line_contact(2000.0, 0.02, [0.01, 0.03], modulus);
        assert!((p * a * PI / 2.0 - 2000.0 / 0.02).abs() < 1e-6 * 1e5);
    }
}
