//! Sampled tooth and gear outlines of the (modified) profile, in the tooth-local frame.
//!
//! One tooth runs counter-clockwise from the centre of the space on its right (θ = π/z) to the
//! centre of the space on its left (θ = −π/z): root arc, fillet, flank, tip arc, then the mirror
//! image. Relief moves the flank by δ(ξ) along its inward normal. Below the form point the root
//! relief is blended into the fillet as δ(ξ_F)·t³, t going from 0 at the root circle to 1 at the
//! form point (uniform in the generating normal angle), so the outline stays continuous and the
//! fillet bottom, where the fillet rises above the root circle only quadratically, is untouched;
//! the deviation there is µm against a fillet of millimetres.

use nalgebra::{Point2, Rotation2, Vector2};

use super::gear::Gear;
use super::relief::FlankModification;

/// Which part of the tooth a point lies on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Segment {
    Root,
    Fillet,
    Flank,
    Tip,
}

/// Right (x > 0) or left flank side of the tooth-local frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Side {
    Right,
    Left,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutlinePoint {
    pub position: Point2<f64>,
    pub segment: Segment,
    pub side: Side,
    /// Involute roll angle ξ of flank points (of the unmodified point they were offset from).
    pub roll_angle: Option<f64>,
}

/// Number of intervals per segment of a half tooth.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OutlineResolution {
    pub root: usize,
    pub fillet: usize,
    pub flank: usize,
    pub tip: usize,
}

impl Default for OutlineResolution {
    fn default() -> Self {
        Self {
            root: 4,
            fillet: 24,
            flank: 64,
            tip: 6,
        }
    }
}

impl Gear {
    /// Point of the modified right flank at roll angle ξ: P(ξ) + δ(ξ)·n_in, with n_in the inward
    /// normal of the involute (−n of the generating rack flank, rotated with the gear).
    pub fn modified_flank_point(
        &self,
        roll_angle: f64,
        modification: &FlankModification,
    ) -> Point2<f64> {
        let p = self.generated_flank_point(roll_angle);
        let inward = self.flank_inward_normal(roll_angle);
        p + modification.deviation(roll_angle) * inward
    }

    /// Unit normal of the right flank at roll angle ξ pointing into the tooth (−n of the generating
    /// rack flank, rotated with the gear; the involute's normal, tangent to the base circle).
    pub fn flank_inward_normal(&self, roll_angle: f64) -> Vector2<f64> {
        let alpha = self.rack.pressure_angle;
        let roll = self.generating_roll_of_flank(roll_angle);
        Rotation2::new(roll) * -Vector2::new(alpha.cos(), alpha.sin())
    }

    /// Point of the right fillet at generating normal angle β (see
    /// [`Gear::generated_fillet_point`]) with the root relief blended in as δ(ξ_F)·t³,
    /// t = (3π/2 − β)/(3π/2 − (π + α)) (0 at the root circle, 1 at the form point).
    pub fn modified_fillet_point(
        &self,
        beta: f64,
        modification: &FlankModification,
    ) -> Point2<f64> {
        let (beta_form, beta_root) = self.fillet_parameter_range();
        let t = (beta_root - beta) / (beta_root - beta_form);
        let (p, inward) = self.generated_fillet_point_and_inward_normal(beta);
        p + modification.deviation(self.form_roll_angle()) * t.powi(3) * inward
    }

    /// Roll angle at which the modified flank reaches the tip circle (≥ ξ_a when tip relief moves
    /// the flank inwards), by bisection on |P(ξ)| = r_a.
    pub fn modified_tip_roll_angle(&self, modification: &FlankModification) -> f64 {
        let xi_a = self.tip_roll_angle();
        if modification.deviation(xi_a) == 0.0 {
            return xi_a;
        }
        let radius =
            |xi| self.modified_flank_point(xi, modification).coords.norm() - self.tip_radius;
        let (mut lo, mut hi) = (xi_a, xi_a);
        let mut step = 1e-3;
        while radius(hi) < 0.0 && step < 1.0 {
            lo = hi;
            hi += step;
            step *= 2.0;
        }
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if radius(mid) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    /// The right half of one tooth from the space centre to the tooth centre line.
    fn right_half_outline(
        &self,
        modification: &FlankModification,
        res: OutlineResolution,
    ) -> Vec<OutlinePoint> {
        let mut points = Vec::with_capacity(res.root + res.fillet + res.flank + res.tip + 4);
        let mut push = |position: Point2<f64>, segment, roll_angle| {
            points.push(OutlinePoint {
                position,
                segment,
                side: Side::Right,
                roll_angle,
            })
        };
        let on_circle =
            |radius: f64, theta: f64| Point2::new(radius * theta.sin(), radius * theta.cos());

        // Root arc: from the space centre π/z to where the fillet reaches the root circle.
        let space_centre = 0.5 * self.angular_pitch();
        let root_end = self.fillet_root_angle();
        for i in 0..res.root {
            let t = i as f64 / res.root as f64;
            push(
                on_circle(
                    self.root_radius,
                    space_centre + (root_end - space_centre) * t,
                ),
                Segment::Root,
                None,
            );
        }

        // Fillet, from the root circle (β = 3π/2) to the form point (β = π + α).
        let (beta_form, beta_root) = self.fillet_parameter_range();
        for i in 0..res.fillet {
            let beta = beta_root + (beta_form - beta_root) * i as f64 / res.fillet as f64;
            push(
                self.modified_fillet_point(beta, modification),
                Segment::Fillet,
                None,
            );
        }

        // Flank, from the form point to the tip circle.
        let (xi_f, xi_end) = (
            self.form_roll_angle(),
            self.modified_tip_roll_angle(modification),
        );
        for i in 0..=res.flank {
            let xi = xi_f + (xi_end - xi_f) * i as f64 / res.flank as f64;
            push(
                self.modified_flank_point(xi, modification),
                Segment::Flank,
                Some(xi),
            );
        }

        // Tip arc, from the flank's end to the centre line.
        let tip_start = {
            let p = self.modified_flank_point(xi_end, modification);
            p.x.atan2(p.y)
        };
        for i in 1..=res.tip {
            let t = i as f64 / res.tip as f64;
            push(
                on_circle(self.tip_radius, tip_start * (1.0 - t)),
                Segment::Tip,
                None,
            );
        }
        points
    }

    /// One tooth, counter-clockwise from the right space centre (θ = π/z) to the left one
    /// (θ = −π/z), tooth-local frame; the two halves are exact mirror images.
    pub fn tooth_outline(
        &self,
        modification: &FlankModification,
        res: OutlineResolution,
    ) -> Vec<OutlinePoint> {
        let right = self.right_half_outline(modification, res);
        let mut outline = right.clone();
        // The centre-line tip point is shared; mirror the rest in reverse order.
        outline.extend(right.iter().rev().skip(1).map(|p| OutlinePoint {
            position: Point2::new(-p.position.x, p.position.y),
            side: Side::Left,
            ..*p
        }));
        outline
    }

    /// The whole gear as a closed counter-clockwise polygon (last point not repeated), tooth-local
    /// frame of tooth 0.
    pub fn gear_outline(
        &self,
        modification: &FlankModification,
        res: OutlineResolution,
    ) -> Vec<Point2<f64>> {
        let tooth = self.tooth_outline(modification, res);
        let z = self.teeth() as usize;
        let mut polygon = Vec::with_capacity(z * tooth.len());
        for k in 0..z {
            let rotation = Rotation2::new(k as f64 * self.angular_pitch());
            polygon.extend(
                tooth[..tooth.len() - 1]
                    .iter()
                    .map(|p| Point2::from(rotation * p.position.coords)),
            );
        }
        polygon
    }

    /// Area A and polar second moment J = ∫ r² dA of the gear body (outline polygon of the
    /// unmodified profile minus the bore), by the polygon formulas
    /// A = ½ Σ (xᵢ yᵢ₊₁ − xᵢ₊₁ yᵢ), J = 1/12 Σ (xᵢ yᵢ₊₁ − xᵢ₊₁ yᵢ)(xᵢ² + xᵢxᵢ₊₁ + xᵢ₊₁² + yᵢ² + yᵢyᵢ₊₁ + yᵢ₊₁²).
    /// Rotary inertia I = ρ B J.
    pub fn area_moments(&self) -> (f64, f64) {
        let res = OutlineResolution {
            root: 8,
            fillet: 48,
            flank: 96,
            tip: 8,
        };
        let polygon = self.gear_outline(&FlankModification::none(), res);
        let (mut area, mut polar) = (0.0, 0.0);
        for (a, b) in polygon.iter().zip(polygon.iter().cycle().skip(1)) {
            let cross = a.x * b.y - b.x * a.y;
            area += 0.5 * cross;
            polar += cross
                * (a.x * a.x + a.x * b.x + b.x * b.x + a.y * a.y + a.y * b.y + b.y * b.y)
                / 12.0;
        }
        let r = self.spec.bore_radius;
        (
            area - std::f64::consts::PI * r * r,
            polar - std::f64::consts::PI * r.powi(4) / 2.0,
        )
    }

    /// Generating roll φ at which the rack flank cuts the involute point of roll angle ξ.
    pub(crate) fn generating_roll_of_flank(&self, roll_angle: f64) -> f64 {
        roll_angle - self.flank_line_offset() / self.base_radius
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::involute::involute;
    use crate::samples;

    #[test]
    fn tooth_is_mirror_symmetric_and_closed_between_space_centres() {
        let pair = samples::paper36_pair();
        let gear = &pair.gears[0];
        let modification = pair
            .flank_modification(1, &samples::paper_relief())
            .unwrap();
        let tooth = gear.tooth_outline(&modification, OutlineResolution::default());
        let n = tooth.len();
        for i in 0..n {
            let (a, b) = (tooth[i].position, tooth[n - 1 - i].position);
            assert!((a.x + b.x).abs() < 1e-15 && (a.y - b.y).abs() < 1e-15);
        }
        let half_pitch = 0.5 * gear.angular_pitch();
        let first = tooth[0].position;
        assert!((first.x.atan2(first.y) - half_pitch).abs() < 1e-14);
        assert!((first.coords.norm() - gear.root_radius).abs() < 1e-14);
    }

    #[test]
    fn outline_has_no_jumps() {
        let pair = samples::paper36_pair();
        let gear = &pair.gears[0];
        let modification = pair
            .flank_modification(1, &samples::paper_relief())
            .unwrap();
        let polygon = gear.gear_outline(&modification, OutlineResolution::default());
        let m = gear.module();
        for w in polygon.windows(2) {
            assert!(
                (w[1] - w[0]).norm() < 0.2 * m,
                "gap between {:?} and {:?}",
                w[0],
                w[1]
            );
        }
    }

    /// The fillet meets the involute at the form circle in position and tangent direction.
    #[test]
    fn fillet_meets_involute_tangentially_at_the_form_circle() {
        let pair = samples::paper36_pair();
        let gear = &pair.gears[0];
        let (beta_form, _) = gear.fillet_parameter_range();
        let xi_f = gear.form_roll_angle();
        let fillet_end = gear.generated_fillet_point(beta_form);
        let flank_start = gear.generated_flank_point(xi_f);
        assert!((fillet_end - flank_start).norm() < 1e-12);
        assert!((fillet_end.coords.norm() - gear.form_radius).abs() < 1e-12);
        // Tangents: one-sided differences towards the junction.
        let h = 1e-6;
        let t_fillet = (fillet_end - gear.generated_fillet_point(beta_form + h)).normalize();
        let t_flank = (gear.generated_flank_point(xi_f + h) - flank_start).normalize();
        let angle = t_fillet.perp(&t_flank).atan2(t_fillet.dot(&t_flank));
        assert!(angle.abs() < 1e-5, "tangent kink {angle} rad");
    }

    /// The body's polar moment lies between the discs of the root and tip radii (less the bore).
    #[test]
    fn polar_moment_is_bounded_by_root_and_tip_discs() {
        let pair = samples::paper36_pair();
        let gear = &pair.gears[0];
        let (area, polar) = gear.area_moments();
        let disc = |r: f64| {
            (
                std::f64::consts::PI * r * r,
                std::f64::consts::PI * r.powi(4) / 2.0,
            )
        };
        let bore = disc(gear.spec.bore_radius);
        let (root, tip) = (disc(gear.root_radius), disc(gear.tip_radius));
        assert!(area > root.0 - bore.0 && area < tip.0 - bore.0);
        assert!(polar > root.1 - bore.1 && polar < tip.1 - bore.1);
    }

    #[test]
    fn thickness_on_the_reference_circle_is_analytic() {
        let pair = samples::paper36_pair();
        let gear = &pair.gears[0];
        let m = gear.module();
        let alpha = gear.rack.pressure_angle;
        let r = gear.reference_radius;
        // The flank point at the reference circle: roll angle tan α.
        let p = gear.generated_flank_point(alpha.tan());
        assert!((p.coords.norm() - r).abs() < 1e-12);
        let half_angle = p.x.atan2(p.y);
        let expected =
            m * (std::f64::consts::FRAC_PI_2 + 2.0 * gear.spec.profile_shift * alpha.tan());
        assert!((2.0 * r * half_angle - expected).abs() < 1e-12 * expected.max(1.0));
        assert!(involute(alpha) > 0.0);
    }

    #[test]
    fn relief_deviation_is_the_amount_at_the_tip_and_zero_before_its_start() {
        let pair = samples::paper36_pair();
        let gear = &pair.gears[0];
        let modification = pair
            .flank_modification(1, &samples::paper_relief())
            .unwrap();
        let tip = modification.tip.unwrap();
        let root = modification.root.unwrap();
        let xi_a = gear.tip_roll_angle();
        // Normal distance between modified and unmodified flank at the tip roll angle.
        let shift =
            gear.modified_flank_point(xi_a, &modification) - gear.generated_flank_point(xi_a);
        assert!((shift.norm() - 20e-6).abs() < 1e-15);
        let sap = pair.flank_roll_angles(1).start_of_active_profile;
        let shift_root =
            gear.modified_flank_point(sap, &modification) - gear.generated_flank_point(sap);
        assert!((shift_root.norm() - 10e-6).abs() < 1e-15);
        // Between the two starts the flank is the involute itself.
        for k in 0..=20 {
            let xi = root.start_roll_angle
                + (tip.start_roll_angle - root.start_roll_angle) * k as f64 / 20.0;
            assert_eq!(
                gear.modified_flank_point(xi, &modification),
                gear.generated_flank_point(xi)
            );
        }
        // The shift is along the involute normal: perpendicular to the flank tangent.
        let xi = 0.5 * (tip.start_roll_angle + xi_a);
        let tangent = gear.generated_flank_point(xi + 1e-7) - gear.generated_flank_point(xi - 1e-7);
        let shift = gear.modified_flank_point(xi, &modification) - gear.generated_flank_point(xi);
        assert!(shift.normalize().dot(&tangent.normalize()).abs() < 1e-6);
    }
}
