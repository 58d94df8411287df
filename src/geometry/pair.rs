//! A meshing pair: operating centre distance, line of action, contact ratio, backlash and the
//! contact points along the line of action.
//!
//! Gear 1 drives (counter-clockwise). Positions along the line of action (LOA) are distances s
//! from gear 1's base-circle tangency point T1 (ISO 21771 / Niemann–Winter):
//! ```text
//! inv α_w  = inv α + 2 tan α (x_g1 + x_g2)/(z1 + z2)       zero-backlash operating pressure angle
//! cos α_w  = (r_b1 + r_b2) / a                              at a given centre distance a
//! L        = a sin α_w                                      |T1 T2|
//! p_b      = π m cos α                                      base pitch
//! s_E      = √(r_a1² − r_b1²)                               FCP: gear 1's tip leaves contact
//! s_A      = L − √(r_a2² − r_b2²)                           ICP: gear 2's tip starts contact
//! s_B      = s_E − p_b   (LPSTC),   s_D = s_A + p_b  (HPSTC),   s_C = r_b1 tan α_w  (pitch point)
//! g_α      = s_E − s_A,   ε_α = g_α / p_b
//! j_wt     = p_w − 2 r_w1 ψ1(r_w1) − 2 r_w2 ψ2(r_w2),   j_n = j_wt cos α_w     (backlash)
//! ```
//! Roll angles on a gear's own flank: ξ1 = s / r_b1 and ξ2 = (L − s) / r_b2.
//!
//! For ε_α < 2 B and D bound the single-contact zone. For a high contact ratio (2 ≤ ε_α < 3)
//! a tooth alternates between n + 1 and n = ⌊ε_α⌋ pairs in contact; B and D are then the
//! lowest and highest points of its zones of least (n-pair) contact, where a tooth carries the
//! most load and where long relief starts, and [`GearPair::zone_boundaries`] lists every point
//! where the number of pairs changes.

use nalgebra::{Point2, Rotation2, Vector2};
use std::f64::consts::{FRAC_PI_2, PI};

use super::error::{GearIndex, GeometryError};
use super::gear::{BasicRack, Gear, GearSpec};
use super::involute::{inverse_involute, involute};
use super::relief::{FlankModification, FlankReliefSpec, ReliefSpec, ReliefStart, ReliefZone};

/// The highest transverse contact ratio geardyn takes: up to three pairs share the load (the
/// matrix of validation/pairs tests ε_α 2.12, 2.40 and 2.58); four would need deeper teeth than
/// a spur rack cuts sound.
pub const MAX_CONTACT_RATIO: f64 = 3.0;

/// What defines a pair, in SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairSpec {
    pub rack: BasicRack,
    pub gears: [GearSpec; 2],
    /// Operating centre distance [m]; `None`: the zero-backlash distance of the nominal
    /// (un-thinned) teeth.
    pub center_distance: Option<f64>,
}

/// The five characteristic points of the path of contact, as distances from T1 along the LOA [m].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ContactPoints {
    /// Initial contact point (A): the tip of gear 2 meets the root of gear 1.
    pub icp: f64,
    /// Lowest point of single tooth contact on gear 1 (B): E − ⌊ε_α⌋ p_b, the lowest point of
    /// least contact for a high contact ratio.
    pub lpstc: f64,
    /// Pitch point (C).
    pub pitch: f64,
    /// Highest point of single tooth contact on gear 1 (D): A + ⌊ε_α⌋ p_b.
    pub hpstc: f64,
    /// Final contact point (E): the tip of gear 1 leaves.
    pub fcp: f64,
}

impl ContactPoints {
    /// (name, position) in the order met along the path of contact.
    pub fn named(&self) -> [(&'static str, f64); 5] {
        [
            ("ICP", self.icp),
            ("LPSTC", self.lpstc),
            ("pitch", self.pitch),
            ("HPSTC", self.hpstc),
            ("FCP", self.fcp),
        ]
    }
}

/// Roll angles ξ of the characteristic points on one gear's own flank [rad], root to tip.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct FlankRollAngles {
    /// Form point (fillet meets involute).
    pub form: f64,
    /// Start of active profile: where the mating tip touches.
    pub start_of_active_profile: f64,
    /// Lowest point of single tooth contact on this gear.
    pub lpstc: f64,
    pub pitch: f64,
    /// Highest point of single tooth contact on this gear.
    pub hpstc: f64,
    /// Tip circle (end of active profile).
    pub tip: f64,
}

/// Where a gear sits in the drawing/global frame: centre and counter-clockwise rotation applied to
/// its tooth-local frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    pub centre: Point2<f64>,
    pub rotation: f64,
}

impl Placement {
    pub fn to_global(&self, local: &Point2<f64>) -> Point2<f64> {
        self.centre + Rotation2::new(self.rotation) * local.coords
    }
}

/// A checked meshing pair.
#[derive(Debug, Clone, PartialEq)]
pub struct GearPair {
    pub gears: [Gear; 2],
    /// Operating centre distance a [m].
    pub center_distance: f64,
    /// Centre distance at which the (thinned) teeth would mesh without backlash [m].
    pub zero_backlash_center_distance: f64,
    /// Operating pressure angle α_w [rad].
    pub operating_pressure_angle: f64,
    /// Operating (working) pitch radii r_w = r_b / cos α_w [m].
    pub working_pitch_radii: [f64; 2],
    /// Base pitch p_b [m].
    pub base_pitch: f64,
    /// Length |T1 T2| of the line of action between the base-circle tangency points [m].
    pub line_of_action_length: f64,
    pub contact_points: ContactPoints,
    /// Transverse contact ratio ε_α.
    pub contact_ratio: f64,
    /// Circumferential backlash on the working pitch circle [m].
    pub backlash_circumferential: f64,
    /// Normal backlash along the line of action [m].
    pub backlash_normal: f64,
    /// Radial clearance between gear i's tip circle and the mate's root circle [m].
    pub tip_clearance: [f64; 2],
}

impl GearPair {
    /// Builds and checks the pair: both gears generated, centre distance, tip clearance,
    /// interference (involute and fillet), contact ratio in [1, [`MAX_CONTACT_RATIO`]).
    pub fn new(spec: &PairSpec) -> Result<Self, GeometryError> {
        let g1 = Gear::generate(1, spec.gears[0], spec.rack)?;
        let g2 = Gear::generate(2, spec.gears[1], spec.rack)?;
        let alpha = spec.rack.pressure_angle;
        let reference_sum = g1.reference_radius + g2.reference_radius;
        let z_sum = (g1.teeth() + g2.teeth()) as f64;
        let zero_backlash_distance = |x_sum: f64| -> Result<f64, GeometryError> {
            let inv_w = involute(alpha) + 2.0 * alpha.tan() * x_sum / z_sum;
            let alpha_w = inverse_involute(inv_w).ok_or_else(|| GeometryError::OutOfRange {
                parameter: "gear1.profile_shift + gear2.profile_shift".into(),
                value: x_sum,
                limit: format!(
                    "above {:.4} (no meshing centre distance below it)",
                    -involute(alpha) * z_sum / (2.0 * alpha.tan())
                ),
            })?;
            Ok(reference_sum * alpha.cos() / alpha_w.cos())
        };
        let zero_backlash = zero_backlash_distance(g1.generating_shift + g2.generating_shift)?;
        let center_distance = match spec.center_distance {
            Some(a) => {
                if !(a.is_finite() && a > 0.0) {
                    return Err(GeometryError::OutOfRange {
                        parameter: "pair.center_distance_mm".into(),
                        value: a * 1e3,
                        limit: "a finite number > 0".into(),
                    });
                }
                if a < zero_backlash * (1.0 - 1e-12) {
                    return Err(GeometryError::CentreDistanceTooSmall {
                        center_distance_mm: a * 1e3,
                        zero_backlash_mm: zero_backlash * 1e3,
                    });
                }
                a
            }
            None => {
                zero_backlash_distance(spec.gears[0].profile_shift + spec.gears[1].profile_shift)?
            }
        };
        let (rb1, rb2) = (g1.base_radius, g2.base_radius);
        let alpha_w = ((rb1 + rb2) / center_distance).clamp(-1.0, 1.0).acos();
        let working_pitch_radii = [rb1 / alpha_w.cos(), rb2 / alpha_w.cos()];

        let tip_clearance = [
            center_distance - g1.tip_radius - g2.root_radius,
            center_distance - g2.tip_radius - g1.root_radius,
        ];
        for (i, clearance) in tip_clearance.iter().enumerate() {
            if !(*clearance > 0.0) {
                return Err(GeometryError::TipRootClash {
                    gear: i + 1,
                    mate: 2 - i,
                    clearance_mm: clearance * 1e3,
                });
            }
        }

        let loa = center_distance * alpha_w.sin();
        let base_pitch = PI * spec.rack.module * alpha.cos();
        let fcp = (g1.tip_radius.powi(2) - rb1.powi(2)).sqrt();
        let icp = loa - (g2.tip_radius.powi(2) - rb2.powi(2)).sqrt();
        // Start of active profile on each gear, as roll length from its own tangency point.
        let sap_lengths = [icp, loa - fcp];
        let gears = [g1, g2];
        for (i, gear) in gears.iter().enumerate() {
            let sap = sap_lengths[i];
            let mate = 2 - i;
            if sap < 0.0 {
                return Err(GeometryError::InvoluteInterference {
                    gear: i + 1,
                    mate,
                    sap_mm: sap * 1e3,
                });
            }
            let form_length = gear.base_radius * gear.form_roll_angle();
            if sap < form_length {
                return Err(GeometryError::FilletInterference {
                    gear: i + 1,
                    mate,
                    sap_radius_mm: gear.radius_at_roll_angle(sap / gear.base_radius) * 1e3,
                    form_radius_mm: gear.form_radius * 1e3,
                });
            }
        }
        let path_of_contact = fcp - icp;
        let contact_ratio = path_of_contact / base_pitch;
        if !(contact_ratio >= 1.0) {
            return Err(GeometryError::ContactRatioBelowOne { contact_ratio });
        }
        if contact_ratio >= MAX_CONTACT_RATIO {
            return Err(GeometryError::ContactRatioTooHigh {
                contact_ratio,
                limit: MAX_CONTACT_RATIO,
            });
        }
        // The outermost zones of least contact: n = ⌊ε_α⌋ pairs between E − n p_b and A + n p_b
        // (single contact for ε_α < 2).
        let least = contact_ratio.floor();
        let contact_points = ContactPoints {
            icp,
            lpstc: fcp - least * base_pitch,
            pitch: rb1 * alpha_w.tan(),
            hpstc: icp + least * base_pitch,
            fcp,
        };

        let working_pitch = 2.0 * PI * working_pitch_radii[0] / gears[0].teeth() as f64;
        let backlash_circumferential = working_pitch
            - gears[0].thickness_at_radius(working_pitch_radii[0])
            - gears[1].thickness_at_radius(working_pitch_radii[1]);

        Ok(GearPair {
            gears,
            center_distance,
            zero_backlash_center_distance: zero_backlash,
            operating_pressure_angle: alpha_w,
            working_pitch_radii,
            base_pitch,
            line_of_action_length: loa,
            contact_points,
            contact_ratio,
            backlash_circumferential,
            backlash_normal: backlash_circumferential * alpha_w.cos(),
            tip_clearance,
        })
    }

    /// The points of the path of contact where the number of tooth pairs in contact changes
    /// (distances from T1 [m], ascending), with the number of pairs on the stretch that ends at
    /// each: A + k p_b and E − k p_b for k = 1 … n, n = ⌊ε_α⌋, then E.
    pub fn zone_boundaries(&self) -> Vec<(f64, usize)> {
        let c = &self.contact_points;
        let pb = self.base_pitch;
        let n = self.contact_ratio.floor() as usize;
        let mut points: Vec<f64> = (1..=n)
            .flat_map(|k| [c.icp + k as f64 * pb, c.fcp - k as f64 * pb])
            .filter(|s| *s > c.icp && *s < c.fcp)
            .collect();
        points.push(c.fcp);
        points.sort_by(f64::total_cmp);
        let pairs_at = |s: f64| {
            (-(n as i64) - 1..=n as i64 + 1)
                .filter(|k| {
                    let t = s + *k as f64 * pb;
                    t >= c.icp && t <= c.fcp
                })
                .count()
        };
        let mut previous = c.icp;
        points
            .into_iter()
            .map(|s| {
                let count = pairs_at(0.5 * (previous + s));
                previous = s;
                (s, count)
            })
            .collect()
    }

    /// Gear 1 or 2.
    pub fn gear(&self, index: GearIndex) -> &Gear {
        &self.gears[index - 1]
    }

    /// Length of the path of contact g_α [m].
    pub fn path_of_contact(&self) -> f64 {
        self.contact_points.fcp - self.contact_points.icp
    }

    /// Roll angle on gear `index`'s own flank of the LOA position `s` (distance from T1).
    pub fn roll_angle_at(&self, index: GearIndex, s: f64) -> f64 {
        match index {
            1 => s / self.gears[0].base_radius,
            _ => (self.line_of_action_length - s) / self.gears[1].base_radius,
        }
    }

    /// The characteristic roll angles on gear `index`'s own flank, root to tip.
    pub fn flank_roll_angles(&self, index: GearIndex) -> FlankRollAngles {
        let c = &self.contact_points;
        let xi = |s| self.roll_angle_at(index, s);
        let (sap, low, high, tip) = match index {
            1 => (c.icp, c.lpstc, c.hpstc, c.fcp),
            _ => (c.fcp, c.hpstc, c.lpstc, c.icp),
        };
        FlankRollAngles {
            form: self.gear(index).form_roll_angle(),
            start_of_active_profile: xi(sap),
            lpstc: xi(low),
            pitch: xi(c.pitch),
            hpstc: xi(high),
            tip: xi(tip),
        }
    }

    /// Resolves a tip/root relief request on gear `index` into roll-angle zones, checking that it
    /// fits on the flank: amounts within [0, 0.05·m] (tip relief also ≤ ¼ of the tip thickness),
    /// starts inside the active profile, tip and root zones apart, and a slope δ/length ≤ 0.05 so
    /// the relief stays a small deviation of the involute.
    pub fn flank_modification(
        &self,
        index: GearIndex,
        request: &FlankReliefSpec,
    ) -> Result<FlankModification, GeometryError> {
        let gear = self.gear(index);
        let roll = self.flank_roll_angles(index);
        let prefix = format!("gear{index}");
        let resolve = |spec: &ReliefSpec, end: &str| -> Result<Option<ReliefZone>, GeometryError> {
            let name = format!("{prefix}.{end}");
            let err = |field: &str, reason: String| GeometryError::Relief {
                parameter: format!("{name}.{field}"),
                reason,
            };
            let m = gear.module();
            let mut max_amount = 0.05 * m;
            if end == "tip" {
                max_amount = max_amount.min(0.25 * gear.tip_thickness());
            }
            if !(spec.amount >= 0.0 && spec.amount <= max_amount) {
                return Err(err(
                    "amount_um",
                    format!(
                        "{:.3} µm is out of range: it must be in [0, {:.3}] µm (0.05·m{})",
                        spec.amount * 1e6,
                        max_amount * 1e6,
                        if end == "tip" {
                            ", and at most ¼ of the tip thickness"
                        } else {
                            ""
                        }
                    ),
                ));
            }
            if spec.amount == 0.0 {
                return Ok(None);
            }
            let (full, single_contact) = match end {
                "tip" => (roll.tip, roll.hpstc),
                _ => (roll.start_of_active_profile, roll.lpstc),
            };
            let start = match spec.start {
                ReliefStart::Hpstc => roll.hpstc,
                ReliefStart::Lpstc => roll.lpstc,
                ReliefStart::Short => 0.5 * (single_contact + full),
                ReliefStart::RollAngle(xi) => xi,
                ReliefStart::Diameter(d) => {
                    if !(d > 2.0 * gear.base_radius) {
                        return Err(err(
                            "start_diameter_mm",
                            format!(
                                "{:.4} mm is not above the base diameter {:.4} mm",
                                d * 1e3,
                                2e3 * gear.base_radius
                            ),
                        ));
                    }
                    gear.roll_angle_at_radius(d / 2.0)
                }
            };
            let (lo, hi) = (roll.start_of_active_profile, roll.tip);
            let inside = start.is_finite() && start > lo && start < hi;
            if !inside {
                return Err(err(
                    "start",
                    format!(
                        "the relief starts at roll angle {:.4}° (diameter {:.4} mm), outside the active \
                         profile ({:.4}° .. {:.4}°, diameters {:.4} .. {:.4} mm); move the start inside it",
                        start.to_degrees(),
                        2e3 * gear.radius_at_roll_angle(start.max(0.0)),
                        lo.to_degrees(),
                        hi.to_degrees(),
                        2e3 * gear.radius_at_roll_angle(lo),
                        2e3 * gear.radius_at_roll_angle(hi),
                    ),
                ));
            }
            let length = gear.base_radius * (full - start).abs();
            let slope = spec.amount / length;
            if slope > 0.05 {
                return Err(err(
                    "amount_um",
                    format!(
                        "{:.3} µm over a relief length of {:.4} mm is a slope of {:.4}, above the limit \
                         0.05: lengthen the relief or reduce the amount",
                        spec.amount * 1e6,
                        length * 1e3,
                        slope
                    ),
                ));
            }
            Ok(Some(ReliefZone {
                amount: spec.amount,
                start_roll_angle: start,
                full_roll_angle: full,
                shape: spec.shape,
            }))
        };
        let tip = request
            .tip
            .as_ref()
            .map(|s| resolve(s, "tip"))
            .transpose()?
            .flatten();
        let root = request
            .root
            .as_ref()
            .map(|s| resolve(s, "root"))
            .transpose()?
            .flatten();
        if let (Some(t), Some(r)) = (tip, root) {
            if t.start_roll_angle <= r.start_roll_angle {
                return Err(GeometryError::Relief {
                    parameter: format!("{prefix}.tip.start"),
                    reason: format!(
                        "the tip relief starts at roll angle {:.4}°, not above the root relief start \
                         {:.4}°: the two zones overlap",
                        t.start_roll_angle.to_degrees(),
                        r.start_roll_angle.to_degrees()
                    ),
                });
            }
        }
        Ok(FlankModification { tip, root })
    }

    /// Placement of both gears with a tooth pair touching at the pitch point: gear 1 at the origin,
    /// gear 2 at (a, 0); the line of action rises from T1 (below the x axis) to T2.
    pub fn mesh_placement(&self) -> [Placement; 2] {
        let [rw1, rw2] = self.working_pitch_radii;
        let psi1 = self.gears[0].half_thickness_angle(rw1);
        let psi2 = self.gears[1].half_thickness_angle(rw2);
        [
            Placement {
                centre: Point2::origin(),
                rotation: -psi1 - FRAC_PI_2,
            },
            Placement {
                centre: Point2::new(self.center_distance, 0.0),
                rotation: FRAC_PI_2 - psi2,
            },
        ]
    }

    /// The driver roll angle ρ about which the back flanks mirror the drive flanks: the pair
    /// turned to driver roll angle ξ meets on its back flanks as it meets on its drive flanks
    /// at ρ − ξ. In [`GearPair::mesh_placement`] the driver's tooth 0 touches at the pitch
    /// point (roll angle ξ_p) with its axis ψ₁ (half the tooth angle at the working pitch
    /// circle) off the centre line; mirroring about the centre line turns the axis angle
    /// ψ + θ into −ψ − θ, i.e. θ into 2ψ₁ − θ: ρ = 2(ξ_p + ψ₁). Exact for symmetric teeth
    /// without backlash (with backlash, to the backlash's rotation).
    pub fn back_flank_reflection(&self) -> f64 {
        let psi1 = self.gears[0].half_thickness_angle(self.working_pitch_radii[0]);
        2.0 * (self.roll_angle_at(1, self.contact_points.pitch) + psi1)
    }

    /// Global position (placement frame) of the LOA point at distance `s` from T1.
    pub fn loa_point(&self, s: f64) -> Point2<f64> {
        let aw = self.operating_pressure_angle;
        let t1 = Point2::new(aw.cos(), -aw.sin()) * self.gears[0].base_radius;
        t1 + Vector2::new(aw.sin(), aw.cos()) * s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::samples;

    #[test]
    fn paper_pair_contact_ratio_and_points() {
        let pair = samples::paper36_pair();
        assert!(
            (pair.contact_ratio - 1.6924).abs() < 5e-4,
            "ε = {}",
            pair.contact_ratio
        );
        let c = pair.contact_points;
        assert!(c.icp < c.lpstc && c.lpstc < c.pitch && c.pitch < c.hpstc && c.hpstc < c.fcp);
        // Equal gears: the path is symmetric about the pitch point.
        assert!(((c.pitch - c.icp) - (c.fcp - c.pitch)).abs() < 1e-12);
        assert!(pair.backlash_normal.abs() < 1e-12);
        // The drawing's LOA reaches T2 on gear 2's base circle.
        let t2 = pair.loa_point(pair.line_of_action_length);
        let o2 = Point2::new(pair.center_distance, 0.0);
        assert!(((t2 - o2).norm() - pair.gears[1].base_radius).abs() < 1e-12);
    }

    /// The mirror that maps drive flanks onto back flanks: turned by ρ/2 − ξ_p = ψ₁ from the
    /// pitch-point position, the driver's tooth 0 sits on the centre line, and (zero backlash)
    /// the driven gear must then have a tooth or a tooth space centred on it too, so the whole
    /// configuration is symmetric about the centre line. Checked on the driven gear's own
    /// placement, which ρ does not use.
    #[test]
    fn back_flank_reflection_is_a_symmetry_of_the_tight_mesh() {
        for (z1, z2) in [(36, 36), (19, 53)] {
            let mut spec = samples::paper36_case().pair_spec;
            spec.gears[0].teeth = z1;
            spec.gears[1].teeth = z2;
            spec.center_distance = None;
            let pair = GearPair::new(&spec).unwrap();
            let placement = pair.mesh_placement();
            let turn = pair.back_flank_reflection() / 2.0
                - pair.roll_angle_at(1, pair.contact_points.pitch);
            let psi1 = pair.gears[0].half_thickness_angle(pair.working_pitch_radii[0]);
            assert!((turn - psi1).abs() < 1e-12);
            // Gear 2's tooth-0 axis (local y) after the driver turns by ψ₁, against the centre
            // line seen from O2 (angle π): a multiple of half a pitch.
            let axis = placement[1].rotation + FRAC_PI_2 - z1 as f64 / z2 as f64 * turn;
            let half_pitch = pair.gears[1].angular_pitch() / 2.0;
            let offset = (axis - std::f64::consts::PI).rem_euclid(half_pitch);
            let offset = offset.min(half_pitch - offset);
            assert!(
                offset < 1e-9,
                "z = {z1}/{z2}: {offset:e} rad off the mirror"
            );
        }
    }

    #[test]
    fn gear2_flank_points_mirror_gear1_for_equal_gears() {
        let pair = samples::paper36_pair();
        let (a, b) = (pair.flank_roll_angles(1), pair.flank_roll_angles(2));
        for (x, y) in [
            (a.start_of_active_profile, b.start_of_active_profile),
            (a.lpstc, b.lpstc),
            (a.hpstc, b.hpstc),
            (a.tip, b.tip),
        ] {
            assert!((x - y).abs() < 1e-12);
        }
        assert!((a.tip - pair.gears[0].tip_roll_angle()).abs() < 1e-12);
    }

    #[test]
    fn thinning_opens_backlash_as_predicted() {
        // Δs on each gear opens j_t on the reference circle by 2Δs (at a = a_0 of the nominal teeth,
        // α_w = α, so the working circle is the reference circle).
        let (rack, mut g1, mut g2) = samples::paper36_specs();
        g1.thickness_reduction = 50e-6;
        g2.thickness_reduction = 50e-6;
        let pair = GearPair::new(&PairSpec {
            rack,
            gears: [g1, g2],
            center_distance: None,
        })
        .unwrap();
        assert!((pair.backlash_circumferential - 100e-6).abs() < 1e-10);
        assert!(pair.zero_backlash_center_distance < pair.center_distance);
    }
}

#[cfg(test)]
mod placement_tests {
    use super::*;
    use crate::geometry::OutlineResolution;
    use crate::samples;

    /// Even-odd point-in-polygon test.
    fn inside(polygon: &[Point2<f64>], p: &Point2<f64>) -> bool {
        let mut inside = false;
        let n = polygon.len();
        for i in 0..n {
            let (a, b) = (polygon[i], polygon[(i + 1) % n]);
            if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y) {
                inside = !inside;
            }
        }
        inside
    }

    /// In the mesh placement the unmodified teeth touch at the pitch point and nowhere overlap
    /// (beyond the chord error of the sampled outline).
    #[test]
    fn placed_pair_touches_at_the_pitch_point_without_overlap() {
        let pair = samples::paper36_pair();
        let placement = pair.mesh_placement();
        let res = OutlineResolution {
            root: 8,
            fillet: 64,
            flank: 400,
            tip: 8,
        };
        let none = FlankModification::none();
        let outlines: Vec<Vec<Point2<f64>>> = (0..2)
            .map(|i| {
                pair.gears[i]
                    .gear_outline(&none, res)
                    .iter()
                    .map(|p| placement[i].to_global(p))
                    .collect()
            })
            .collect();
        let pitch = pair.loa_point(pair.contact_points.pitch);
        for (i, outline) in outlines.iter().enumerate() {
            let nearest = outline
                .iter()
                .map(|p| (p - pitch).norm())
                .fold(f64::INFINITY, f64::min);
            assert!(
                nearest < 5e-6,
                "gear{} is {nearest} m from the pitch point",
                i + 1
            );
        }
        for (i, j) in [(0, 1), (1, 0)] {
            // Only the teeth near the mesh can touch.
            let near_mesh = outlines[i].iter().filter(|p| (*p - pitch).norm() < 0.02);
            for p in near_mesh {
                if inside(&outlines[j], p) {
                    let depth = outlines[j]
                        .iter()
                        .map(|q| (q - p).norm())
                        .fold(f64::INFINITY, f64::min);
                    assert!(
                        depth < 2e-6,
                        "gear{} point {p:?} is {depth} m inside gear{}",
                        i + 1,
                        j + 1
                    );
                }
            }
        }
    }
}
