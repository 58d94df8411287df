//! The geometry study: the derived quantities of the pair and its relief variants (the headline
//! numbers, a text table for the terminal) and the profile rows. Units in the summary: mm, µm,
//! degrees.

use serde::Serialize;

use crate::case::Case;
use crate::geometry::{
    FlankModification, GearIndex, GearPair, OutlineResolution, ReliefZone, Segment, Side,
};

/// Per-gear derived quantities.
#[derive(Debug, Clone, Serialize)]
pub struct GearSummary {
    pub teeth: u32,
    pub profile_shift: f64,
    pub generating_profile_shift: f64,
    pub reference_radius_mm: f64,
    pub base_radius_mm: f64,
    pub working_pitch_radius_mm: f64,
    pub tip_radius_mm: f64,
    pub root_radius_mm: f64,
    pub form_radius_mm: f64,
    pub start_of_active_profile_radius_mm: f64,
    pub bore_radius_mm: f64,
    pub face_width_mm: f64,
    pub tooth_thickness_reference_mm: f64,
    pub tooth_thickness_working_mm: f64,
    pub tip_thickness_mm: f64,
    pub tip_clearance_mm: f64,
    /// Roll angles on this gear's own flank (root to tip).
    pub roll_angle_form_deg: f64,
    pub roll_angle_sap_deg: f64,
    pub roll_angle_lpstc_deg: f64,
    pub roll_angle_pitch_deg: f64,
    pub roll_angle_hpstc_deg: f64,
    pub roll_angle_tip_deg: f64,
}

/// A resolved relief zone in case-file units.
#[derive(Debug, Clone, Serialize)]
pub struct ReliefZoneSummary {
    pub amount_um: f64,
    pub shape: crate::geometry::ReliefShape,
    pub start_roll_deg: f64,
    pub start_diameter_mm: f64,
    pub full_roll_deg: f64,
    pub full_diameter_mm: f64,
    pub length_along_loa_mm: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct GearReliefSummary {
    pub tip: Option<ReliefZoneSummary>,
    pub root: Option<ReliefZoneSummary>,
}

#[derive(Debug, Clone, Serialize)]
pub struct ReliefVariantSummary {
    pub name: String,
    pub gear1: GearReliefSummary,
    pub gear2: GearReliefSummary,
}

/// Distances of the contact points from T1 along the line of action.
#[derive(Debug, Clone, Serialize)]
pub struct ContactPointsMm {
    pub icp: f64,
    pub lpstc: f64,
    pub pitch: f64,
    pub hpstc: f64,
    pub fcp: f64,
}

/// `summary.json` of `geardyn geometry`. Roll angles without a gear prefix are the driver's
/// (gear 1) roll angles ξ1 = s/r_b1 of the contact points.
#[derive(Debug, Clone, Serialize)]
pub struct GeometrySummary {
    pub case: String,
    pub source: String,
    pub base_radius_mm: f64,
    pub contact_ratio: f64,
    pub base_pitch_mm: f64,
    pub path_of_contact_mm: f64,
    pub roll_angle_icp_deg: f64,
    pub roll_angle_lpstc_deg: f64,
    pub roll_angle_pitch_deg: f64,
    pub roll_angle_hpstc_deg: f64,
    pub roll_angle_fcp_deg: f64,
    pub center_distance_mm: f64,
    pub zero_backlash_center_distance_mm: f64,
    pub operating_pressure_angle_deg: f64,
    pub line_of_action_length_mm: f64,
    pub backlash_circumferential_um: f64,
    pub backlash_normal_um: f64,
    pub contact_points_from_t1_mm: ContactPointsMm,
    pub gear1: GearSummary,
    pub gear2: GearSummary,
    pub relief_variants: Vec<ReliefVariantSummary>,
    pub warnings: Vec<String>,
}

fn gear_summary(pair: &GearPair, index: GearIndex) -> GearSummary {
    let gear = pair.gear(index);
    let roll = pair.flank_roll_angles(index);
    let rw = pair.working_pitch_radii[index - 1];
    GearSummary {
        teeth: gear.teeth(),
        profile_shift: gear.spec.profile_shift,
        generating_profile_shift: gear.generating_shift,
        reference_radius_mm: gear.reference_radius * 1e3,
        base_radius_mm: gear.base_radius * 1e3,
        working_pitch_radius_mm: rw * 1e3,
        tip_radius_mm: gear.tip_radius * 1e3,
        root_radius_mm: gear.root_radius * 1e3,
        form_radius_mm: gear.form_radius * 1e3,
        start_of_active_profile_radius_mm: gear.radius_at_roll_angle(roll.start_of_active_profile)
            * 1e3,
        bore_radius_mm: gear.spec.bore_radius * 1e3,
        face_width_mm: gear.spec.face_width * 1e3,
        tooth_thickness_reference_mm: gear.reference_thickness * 1e3,
        tooth_thickness_working_mm: gear.thickness_at_radius(rw) * 1e3,
        tip_thickness_mm: gear.tip_thickness() * 1e3,
        tip_clearance_mm: pair.tip_clearance[index - 1] * 1e3,
        roll_angle_form_deg: roll.form.to_degrees(),
        roll_angle_sap_deg: roll.start_of_active_profile.to_degrees(),
        roll_angle_lpstc_deg: roll.lpstc.to_degrees(),
        roll_angle_pitch_deg: roll.pitch.to_degrees(),
        roll_angle_hpstc_deg: roll.hpstc.to_degrees(),
        roll_angle_tip_deg: roll.tip.to_degrees(),
    }
}

fn zone_summary(pair: &GearPair, index: GearIndex, zone: &ReliefZone) -> ReliefZoneSummary {
    let gear = pair.gear(index);
    ReliefZoneSummary {
        amount_um: zone.amount * 1e6,
        shape: zone.shape,
        start_roll_deg: zone.start_roll_angle.to_degrees(),
        start_diameter_mm: 2e3 * gear.radius_at_roll_angle(zone.start_roll_angle),
        full_roll_deg: zone.full_roll_angle.to_degrees(),
        full_diameter_mm: 2e3 * gear.radius_at_roll_angle(zone.full_roll_angle),
        length_along_loa_mm: 1e3
            * gear.base_radius
            * (zone.full_roll_angle - zone.start_roll_angle).abs(),
    }
}

fn relief_summary(
    pair: &GearPair,
    index: GearIndex,
    modification: &FlankModification,
) -> GearReliefSummary {
    GearReliefSummary {
        tip: modification
            .tip
            .as_ref()
            .map(|z| zone_summary(pair, index, z)),
        root: modification
            .root
            .as_ref()
            .map(|z| zone_summary(pair, index, z)),
    }
}

/// Design-rule notes that are not errors (the case still runs).
fn warnings(pair: &GearPair) -> Vec<String> {
    let mut notes = Vec::new();
    for gear in &pair.gears {
        let m = gear.module();
        if gear.tip_thickness() < 0.2 * m {
            notes.push(format!(
                "gear{}: tip thickness {:.3} mm is below the usual design minimum 0.2·m = {:.3} mm",
                gear.index,
                gear.tip_thickness() * 1e3,
                0.2 * m * 1e3
            ));
        }
    }
    if pair.contact_ratio < 1.2 {
        notes.push(format!(
            "contact ratio {:.4} is below 1.2: little margin against loss of contact under load",
            pair.contact_ratio
        ));
    }
    notes
}

/// Backlash of a zero-backlash pair comes out as ±1e-12 µm of roundoff; show it as 0.
fn without_roundoff(micrometres: f64) -> f64 {
    if micrometres.abs() < 1e-9 {
        0.0
    } else {
        micrometres
    }
}

impl GeometrySummary {
    pub fn new(case: &Case) -> Self {
        let pair = &case.pair;
        let c = pair.contact_points;
        let roll1 = |s: f64| pair.roll_angle_at(1, s).to_degrees();
        GeometrySummary {
            case: case.name().to_string(),
            source: case.source.clone(),
            base_radius_mm: pair.gears[0].base_radius * 1e3,
            contact_ratio: pair.contact_ratio,
            base_pitch_mm: pair.base_pitch * 1e3,
            path_of_contact_mm: pair.path_of_contact() * 1e3,
            roll_angle_icp_deg: roll1(c.icp),
            roll_angle_lpstc_deg: roll1(c.lpstc),
            roll_angle_pitch_deg: roll1(c.pitch),
            roll_angle_hpstc_deg: roll1(c.hpstc),
            roll_angle_fcp_deg: roll1(c.fcp),
            center_distance_mm: pair.center_distance * 1e3,
            zero_backlash_center_distance_mm: pair.zero_backlash_center_distance * 1e3,
            operating_pressure_angle_deg: pair.operating_pressure_angle.to_degrees(),
            line_of_action_length_mm: pair.line_of_action_length * 1e3,
            backlash_circumferential_um: without_roundoff(pair.backlash_circumferential * 1e6),
            backlash_normal_um: without_roundoff(pair.backlash_normal * 1e6),
            contact_points_from_t1_mm: ContactPointsMm {
                icp: c.icp * 1e3,
                lpstc: c.lpstc * 1e3,
                pitch: c.pitch * 1e3,
                hpstc: c.hpstc * 1e3,
                fcp: c.fcp * 1e3,
            },
            gear1: gear_summary(pair, 1),
            gear2: gear_summary(pair, 2),
            relief_variants: case
                .relief_variants
                .iter()
                .map(|v| ReliefVariantSummary {
                    name: v.name.clone(),
                    gear1: relief_summary(pair, 1, &v.modifications[0]),
                    gear2: relief_summary(pair, 2, &v.modifications[1]),
                })
                .collect(),
            warnings: warnings(pair),
        }
    }

    /// The derived table as text, for the terminal.
    pub fn table(&self) -> String {
        use std::fmt::Write;
        let mut t = String::new();
        let _ = writeln!(t, "case {} ({})", self.case, self.source);
        let _ = writeln!(t, "{:<44} {:>14} {:>14}", "", "gear1 (drive)", "gear2");
        let g = [&self.gear1, &self.gear2];
        let row = |t: &mut String, name: &str, f: &dyn Fn(&GearSummary) -> f64, digits: usize| {
            let _ = writeln!(
                t,
                "{:<44} {:>14.*} {:>14.*}",
                name,
                digits,
                f(g[0]),
                digits,
                f(g[1])
            );
        };
        row(&mut t, "teeth", &|s| s.teeth as f64, 0);
        row(&mut t, "profile shift x", &|s| s.profile_shift, 4);
        row(
            &mut t,
            "reference radius r [mm]",
            &|s| s.reference_radius_mm,
            4,
        );
        row(&mut t, "base radius r_b [mm]", &|s| s.base_radius_mm, 4);
        row(
            &mut t,
            "working pitch radius r_w [mm]",
            &|s| s.working_pitch_radius_mm,
            4,
        );
        row(&mut t, "tip radius r_a [mm]", &|s| s.tip_radius_mm, 4);
        row(&mut t, "root radius r_f [mm]", &|s| s.root_radius_mm, 4);
        row(
            &mut t,
            "form radius r_F (fillet/involute) [mm]",
            &|s| s.form_radius_mm,
            4,
        );
        row(
            &mut t,
            "start of active profile radius [mm]",
            &|s| s.start_of_active_profile_radius_mm,
            4,
        );
        row(
            &mut t,
            "tooth thickness at r [mm]",
            &|s| s.tooth_thickness_reference_mm,
            4,
        );
        row(&mut t, "tip thickness [mm]", &|s| s.tip_thickness_mm, 4);
        row(&mut t, "tip clearance [mm]", &|s| s.tip_clearance_mm, 4);
        row(
            &mut t,
            "roll angle: form point [deg]",
            &|s| s.roll_angle_form_deg,
            4,
        );
        row(
            &mut t,
            "roll angle: start of active profile [deg]",
            &|s| s.roll_angle_sap_deg,
            4,
        );
        row(
            &mut t,
            "roll angle: LPSTC [deg]",
            &|s| s.roll_angle_lpstc_deg,
            4,
        );
        row(
            &mut t,
            "roll angle: pitch point [deg]",
            &|s| s.roll_angle_pitch_deg,
            4,
        );
        row(
            &mut t,
            "roll angle: HPSTC [deg]",
            &|s| s.roll_angle_hpstc_deg,
            4,
        );
        row(
            &mut t,
            "roll angle: tip [deg]",
            &|s| s.roll_angle_tip_deg,
            4,
        );
        let _ = writeln!(t);
        let pair_rows: [(&str, f64, usize); 9] = [
            ("centre distance [mm]", self.center_distance_mm, 4),
            (
                "operating pressure angle [deg]",
                self.operating_pressure_angle_deg,
                4,
            ),
            ("base pitch p_b [mm]", self.base_pitch_mm, 4),
            ("line of action T1T2 [mm]", self.line_of_action_length_mm, 4),
            ("path of contact g_a [mm]", self.path_of_contact_mm, 4),
            ("contact ratio e_a", self.contact_ratio, 4),
            (
                "backlash, circumferential [um]",
                self.backlash_circumferential_um,
                3,
            ),
            ("backlash, normal [um]", self.backlash_normal_um, 3),
            (
                "zero-backlash centre distance [mm]",
                self.zero_backlash_center_distance_mm,
                4,
            ),
        ];
        for (name, value, digits) in pair_rows {
            let _ = writeln!(t, "{name:<44} {value:>14.digits$}");
        }
        let _ = writeln!(
            t,
            "\ncontact points (distance from T1 [mm], driver roll angle [deg]):"
        );
        let c = &self.contact_points_from_t1_mm;
        for (name, s, xi) in [
            ("ICP", c.icp, self.roll_angle_icp_deg),
            ("LPSTC", c.lpstc, self.roll_angle_lpstc_deg),
            ("pitch", c.pitch, self.roll_angle_pitch_deg),
            ("HPSTC", c.hpstc, self.roll_angle_hpstc_deg),
            ("FCP", c.fcp, self.roll_angle_fcp_deg),
        ] {
            let _ = writeln!(t, "  {name:<8} {s:>10.4} {xi:>10.4}");
        }
        for v in &self.relief_variants {
            let _ = writeln!(t, "\nrelief variant \"{}\":", v.name);
            for (gear, r) in [("gear1", &v.gear1), ("gear2", &v.gear2)] {
                for (end, zone) in [("tip", &r.tip), ("root", &r.root)] {
                    match zone {
                        Some(z) => {
                            let _ = writeln!(
                                t,
                                "  {gear} {end:<4} {:>6.2} um {:?}, from roll {:.3} deg (d = {:.4} mm) to {:.3} deg (d = {:.4} mm), {:.4} mm along the LOA",
                                z.amount_um, z.shape, z.start_roll_deg, z.start_diameter_mm, z.full_roll_deg, z.full_diameter_mm, z.length_along_loa_mm
                            );
                        }
                        None => {
                            let _ = writeln!(t, "  {gear} {end:<4} none");
                        }
                    }
                }
            }
        }
        for w in &self.warnings {
            let _ = writeln!(t, "warning: {w}");
        }
        t
    }
}

/// Rows of the tooth-profile CSV of one gear and relief variant: x, y [mm] in the tooth-local
/// frame, segment, side, roll angle [deg], relief deviation [µm].
pub fn profile_rows(
    case: &Case,
    index: GearIndex,
    modification: &FlankModification,
) -> Vec<Vec<String>> {
    let gear = case.pair.gear(index);
    gear.tooth_outline(modification, OutlineResolution::default())
        .iter()
        .map(|p| {
            let segment = match p.segment {
                Segment::Root => "root",
                Segment::Fillet => "fillet",
                Segment::Flank => "flank",
                Segment::Tip => "tip",
            };
            let side = match p.side {
                Side::Right => "right",
                Side::Left => "left",
            };
            vec![
                format!("{:.9}", p.position.x * 1e3),
                format!("{:.9}", p.position.y * 1e3),
                segment.into(),
                side.into(),
                p.roll_angle
                    .map_or(String::new(), |xi| format!("{:.6}", xi.to_degrees())),
                p.roll_angle.map_or(String::new(), |xi| {
                    format!("{:.4}", modification.deviation(xi) * 1e6)
                }),
            ]
        })
        .collect()
}

pub const PROFILE_HEADER: [&str; 6] = [
    "x_mm",
    "y_mm",
    "segment",
    "side",
    "roll_angle_deg",
    "relief_um",
];
