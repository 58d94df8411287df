//! Which teeth engage: the one place that pairs the driver's teeth with the driven gear's, for
//! every consumer (the LTCA, the explicit FE's scenes and meshes, the modal analysis, reports).
//!
//! Tooth indices follow [`GearPair::mesh_placement`]: gear g's tooth t sits at the placement's
//! rotation plus t·2π/z_g, and at driver rotation θ = 0 tooth 0 of both gears touches at the
//! pitch point. The driver turns counter-clockwise by θ, the driven gear by −(z₁/z₂)θ. A signed
//! driver tooth s (s < 0: the teeth behind tooth 0, which enter next) therefore has its drive
//! flank at roll angle
//! ```text
//! ξ₁(s, θ) = ξ₁C + θ + s·2π/z₁            (ξ₁C = s_C / r_b1, the pitch point)
//! ```
//! and meets the driven tooth −s (signed): one pitch of rotation brings driver tooth s − 1 and
//! driven tooth 1 − s to where s and −s were. Unsigned indices are these modulo z₁ and z₂; over
//! more than a revolution of either gear the same index meets other partners (hunting), so
//! pairs are kept signed and mapped only at the end.
//!
//! A pair is *engaged* over a window of driver rotation [θ_a, θ_b] when its roll angle comes
//! within a margin μ of the path of contact [ξ₁A, ξ₁E] (ICP to FCP) somewhere in the window:
//! ```text
//! s_min = ⌈(ξ₁A − μ − ξ₁C − θ_b) / p₁⌉,   s_max = ⌊(ξ₁E + μ − ξ₁C − θ_a) / p₁⌋,   p₁ = 2π/z₁
//! ```
//! Under load the contact extends past the path's ends (tip-corner contact); the margin
//! [`ENGAGEMENT_MARGIN`] of a fifth of a base pitch holds that extension (the LTCA warns when a
//! pair carries load beyond half of it).

use super::pair::GearPair;

/// Roll-angle margin beyond the path of contact within which a tooth pair counts as engaged, in
/// driver angular pitches (one base pitch of roll): 0.2 p_b along the line of action. Loaded
/// contact runs past the ends of the path by the teeth's deflection over the separation's growth
/// rate, a few hundredths of a base pitch at design load for steel gears; a fifth holds several
/// times that.
pub const ENGAGEMENT_MARGIN: f64 = 0.2;

/// A driver tooth and the driven tooth whose drive flanks meet, signed (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ToothPair {
    /// Signed driver tooth s (0: at the pitch point at θ = 0; negative: entering later).
    pub driver: i64,
    /// Signed driven tooth, −s.
    pub driven: i64,
}

impl ToothPair {
    /// The pair of signed driver tooth `s`.
    pub fn of_driver(s: i64) -> Self {
        ToothPair {
            driver: s,
            driven: -s,
        }
    }

    /// Unsigned (gear-1, gear-2) tooth indices of `pair`'s meshes.
    pub fn indices(&self, pair: &GearPair) -> (usize, usize) {
        let [z1, z2] = [0, 1].map(|g| pair.gears[g].teeth() as i64);
        (
            self.driver.rem_euclid(z1) as usize,
            self.driven.rem_euclid(z2) as usize,
        )
    }

    /// The pair whose back flanks face each other across the tooth space behind the driver
    /// tooth: driver tooth s pushes driven tooth −s ahead of it, so the driven tooth in the
    /// space behind it is the one driver tooth s − 1 pushes, −s + 1 (they meet only when the
    /// torque reverses or backlash closes).
    pub fn back_flank_partner(&self) -> ToothPair {
        ToothPair {
            driver: self.driver,
            driven: self.driven + 1,
        }
    }

    /// The driver roll angle of this pair's drive-flank contact at driver rotation θ [rad].
    pub fn roll_angle(&self, pair: &GearPair, driver_rotation: f64) -> f64 {
        pair.roll_angle_at(1, pair.contact_points.pitch)
            + driver_rotation
            + self.driver as f64 * pair.gears[0].angular_pitch()
    }

    /// Where the pair stands against the path of contact at driver rotation θ, in base pitches:
    /// negative before the ICP, 0 on the path, positive past the FCP.
    pub fn beyond_path(&self, pair: &GearPair, driver_rotation: f64) -> f64 {
        let xi = self.roll_angle(pair, driver_rotation);
        let [from, to] = path_roll_angles(pair);
        let p1 = pair.gears[0].angular_pitch();
        if xi < from {
            (xi - from) / p1
        } else if xi > to {
            (xi - to) / p1
        } else {
            0.0
        }
    }
}

/// The driver roll angles of the path of contact's ends, ICP and FCP [rad].
pub fn path_roll_angles(pair: &GearPair) -> [f64; 2] {
    let c = &pair.contact_points;
    [pair.roll_angle_at(1, c.icp), pair.roll_angle_at(1, c.fcp)]
}

/// The tooth pairs engaged while the driver turns from `from` to `to` (driver rotation from
/// the pitch-point position [rad], `from` ≤ `to`), within `margin` base pitches of the path of
/// contact; each signed pair once, by ascending driver tooth: the pair that enters last first,
/// the one leaving first last, so that one tooth's engagement over consecutive pitches reads
/// along the list (pair s at θ + p₁ stands where pair s + 1 stood at θ).
///
/// # Panics
/// When `from` > `to`, either is not finite, or `margin` is negative.
#[track_caller]
pub fn engaged_pairs(pair: &GearPair, from: f64, to: f64, margin: f64) -> Vec<ToothPair> {
    assert!(
        from.is_finite() && to.is_finite() && from <= to && margin >= 0.0,
        "engaged_pairs: window [{from}, {to}] with margin {margin}"
    );
    let p1 = pair.gears[0].angular_pitch();
    let xi_pitch = pair.roll_angle_at(1, pair.contact_points.pitch);
    let [xi_a, xi_e] = path_roll_angles(pair);
    let mu = margin * p1;
    // A hair of tolerance keeps a pair exactly at the window's edge from flickering with
    // round-off in the roll angles.
    let eps = 1e-9;
    let s_min = ((xi_a - mu - xi_pitch - to) / p1 - eps).ceil() as i64;
    let s_max = ((xi_e + mu - xi_pitch - from) / p1 + eps).floor() as i64;
    (s_min..=s_max).map(ToothPair::of_driver).collect()
}

/// The pairs an LTCA over one base pitch needs: positions θ ∈ [0, p₁] (the last one is the
/// first one a pitch later, for the periodicity check), with [`ENGAGEMENT_MARGIN`].
pub fn base_pitch_pairs(pair: &GearPair) -> Vec<ToothPair> {
    engaged_pairs(pair, 0.0, pair.gears[0].angular_pitch(), ENGAGEMENT_MARGIN)
}

/// The pairs whose back flanks an LTCA over one base pitch loads (positions θ ∈ [0, p₁] under
/// a reversed torque). Mirroring the pair about its centre line when driver tooth 0 sits on it
/// (driver rotation ψ₁, [`GearPair::back_flank_reflection`] ρ = 2(ξ_p + ψ₁)) turns driver
/// rotation θ into 2ψ₁ − θ, driver tooth s into −s, driven tooth u into 1 − u, and back-flank
/// contacts into drive-flank ones. So the back pairs over [0, p₁] are the mirrors of the drive
/// pairs engaged over [2ψ₁ − p₁, 2ψ₁]: drive pair (s, −s) gives back pair (−s, s + 1), the
/// [`ToothPair::back_flank_partner`] of driver tooth −s. By ascending driver tooth. Exact for
/// symmetric teeth without backlash; a backlash shifts the mirror by its rotation, which
/// [`ENGAGEMENT_MARGIN`] holds.
pub fn back_base_pitch_pairs(pair: &GearPair) -> Vec<ToothPair> {
    let p1 = pair.gears[0].angular_pitch();
    let psi1 =
        pair.back_flank_reflection() / 2.0 - pair.roll_angle_at(1, pair.contact_points.pitch);
    let mut pairs: Vec<ToothPair> =
        engaged_pairs(pair, 2.0 * psi1 - p1, 2.0 * psi1, ENGAGEMENT_MARGIN)
            .into_iter()
            .map(|p| ToothPair::of_driver(-p.driver).back_flank_partner())
            .collect();
    pairs.sort();
    pairs
}

/// The teeth of each gear in `pairs` (unsigned, sorted, once each).
pub fn teeth_of(pair: &GearPair, pairs: &[ToothPair]) -> [Vec<usize>; 2] {
    let mut teeth: [Vec<usize>; 2] = [Vec::new(), Vec::new()];
    for p in pairs {
        let (t1, t2) = p.indices(pair);
        teeth[0].push(t1);
        teeth[1].push(t2);
    }
    for t in &mut teeth {
        t.sort_unstable();
        t.dedup();
    }
    teeth
}

/// The number of tooth pairs on the path of contact (no margin) at driver rotation θ: what the
/// unloaded geometry expects to carry load at low torque (pairs exactly at a path end count).
pub fn pairs_on_path(pair: &GearPair, driver_rotation: f64) -> usize {
    engaged_pairs(pair, driver_rotation, driver_rotation, 0.0)
        .iter()
        .filter(|p| p.beyond_path(pair, driver_rotation) == 0.0)
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::PairSpec;

    fn pair(z1: u32, z2: u32, shifts: [f64; 2], addendum: f64, alpha_deg: f64) -> GearPair {
        let (mut rack, mut g1, mut g2) = crate::samples::paper36_specs();
        rack.pressure_angle = alpha_deg.to_radians();
        if addendum > 1.0 {
            rack.dedendum_coeff = addendum + 0.25;
            rack.tip_radius_coeff = 0.2;
        }
        for (g, z, x) in [(&mut g1, z1, shifts[0]), (&mut g2, z2, shifts[1])] {
            g.teeth = z;
            g.profile_shift = x;
            g.addendum_coeff = addendum;
        }
        GearPair::new(&PairSpec {
            rack,
            gears: [g1, g2],
            center_distance: None,
        })
        .unwrap()
    }

    /// Pairs of every kind the matrix holds, as geometry only.
    fn pairs() -> Vec<GearPair> {
        vec![
            crate::samples::paper36_pair(),
            pair(24, 40, [0.0; 2], 1.0, 20.0),
            pair(40, 24, [0.0; 2], 1.0, 20.0),
            pair(31, 32, [0.0; 2], 1.0, 20.0),
            pair(19, 57, [0.4, -0.2], 1.0, 20.0),
            pair(32, 48, [0.0; 2], 1.2, 18.0),
            pair(32, 48, [0.15, -0.15], 1.35, 17.0),
        ]
    }

    /// The paper's pair over a base pitch and the position after it: the leaving tooth +1, the
    /// present 0, the entering −1, and −2, which comes within the margin of the path's start
    /// by the last position.
    #[test]
    fn the_paper_pair_engages_teeth_minus_two_to_one() {
        let p = crate::samples::paper36_pair();
        let drivers: Vec<i64> = base_pitch_pairs(&p).iter().map(|t| t.driver).collect();
        assert_eq!(drivers, vec![-2, -1, 0, 1]);
        let indices: Vec<(usize, usize)> =
            base_pitch_pairs(&p).iter().map(|t| t.indices(&p)).collect();
        assert_eq!(indices, vec![(34, 2), (35, 1), (0, 0), (1, 35)]);
    }

    /// The partner of a driver tooth is the driven tooth that the LTCA's and the explicit
    /// scenes' kinematics (driver tooth t at placement + θ + t p₁, driven tooth u at
    /// placement − (z₁/z₂)θ + u p₂) bring to the pitch point together: at θ = −s p₁ both stand
    /// where tooth 0 stood at θ = 0, modulo a revolution. Unequal pairs included, over several
    /// revolutions of the driver (hunting teeth meet new partners).
    #[test]
    fn partners_arrive_at_the_pitch_point_together() {
        use std::f64::consts::TAU;
        let wrapped = |a: f64| (a.rem_euclid(TAU)).min(TAU - a.rem_euclid(TAU));
        for p in pairs() {
            let [z1, z2] = [0, 1].map(|g| p.gears[g].teeth() as f64);
            let [p1, p2] = [0, 1].map(|g| p.gears[g].angular_pitch());
            for s in -3 * z1 as i64..3 {
                let tooth = ToothPair::of_driver(s);
                let (t1, t2) = tooth.indices(&p);
                let theta = -(s as f64) * p1;
                assert!(wrapped(theta + t1 as f64 * p1) < 1e-9, "{z1}/{z2} s {s}");
                assert!(
                    wrapped(-(z1 / z2) * theta + t2 as f64 * p2) < 1e-9,
                    "{z1}/{z2} s {s}: driven tooth {t2}"
                );
                // And it is at the pitch point then.
                let at_pitch =
                    tooth.roll_angle(&p, theta) - p.roll_angle_at(1, p.contact_points.pitch);
                assert!(at_pitch.abs() < 1e-9);
            }
        }
    }

    /// Averaged over a base pitch, the pairs on the path of contact number ε_α (the path is
    /// ε_α base pitches long and a pair crosses it at one base pitch per pitch of rotation),
    /// for ε_α below and above 2; and the count is always ⌊ε_α⌋ or ⌈ε_α⌉.
    #[test]
    fn pairs_on_the_path_average_the_contact_ratio() {
        for p in pairs() {
            let n = 20_000;
            let p1 = p.gears[0].angular_pitch();
            let counts: Vec<usize> = (0..n)
                .map(|j| pairs_on_path(&p, (j as f64 + 0.5) / n as f64 * p1))
                .collect();
            let mean = counts.iter().sum::<usize>() as f64 / n as f64;
            assert!(
                (mean - p.contact_ratio).abs() < 2.0 / n as f64,
                "{} vs {}",
                mean,
                p.contact_ratio
            );
            let (low, high) = (
                p.contact_ratio.floor() as usize,
                p.contact_ratio.ceil() as usize,
            );
            assert!(counts.iter().all(|c| *c == low || *c == high));
        }
    }

    /// Every pair on the path anywhere in a window is among the window's engaged pairs, and
    /// nothing beyond the margin is.
    #[test]
    fn a_window_holds_every_pair_on_its_path_and_no_more() {
        for p in pairs() {
            let p1 = p.gears[0].angular_pitch();
            let (from, to) = (0.3 * p1, 3.7 * p1);
            let engaged = engaged_pairs(&p, from, to, ENGAGEMENT_MARGIN);
            for j in 0..=400 {
                let theta = from + (to - from) * j as f64 / 400.0;
                for s in -10..10 {
                    let t = ToothPair::of_driver(s);
                    if t.beyond_path(&p, theta) == 0.0 {
                        assert!(engaged.contains(&t), "pair {s} at {theta}");
                    }
                }
            }
            for t in &engaged {
                let nearest = [from, to]
                    .iter()
                    .map(|&th| t.beyond_path(&p, th).abs())
                    .fold(f64::INFINITY, f64::min);
                let inside = (from..=to).contains(&(-(t.driver as f64) * p1));
                assert!(inside || nearest <= ENGAGEMENT_MARGIN + 1e-9, "{t:?}");
            }
        }
    }

    /// The zone boundaries split the path into stretches of ⌈ε_α⌉ and ⌊ε_α⌋ pairs, alternating,
    /// with B and D (LPSTC, HPSTC) among them; for ε_α < 2, A–B two pairs, B–D one, D–E two.
    #[test]
    fn zone_boundaries_alternate_between_the_two_counts() {
        for p in pairs() {
            let zones = p.zone_boundaries();
            let c = p.contact_points;
            assert!(zones.iter().any(|(s, _)| (s - c.lpstc).abs() < 1e-12));
            assert!(zones.iter().any(|(s, _)| (s - c.hpstc).abs() < 1e-12));
            assert!((zones.last().unwrap().0 - c.fcp).abs() < 1e-12);
            let (low, high) = (
                p.contact_ratio.floor() as usize,
                p.contact_ratio.ceil() as usize,
            );
            for w in zones.windows(2) {
                assert_ne!(w[0].1, w[1].1);
            }
            assert!(zones.iter().all(|z| z.1 == low || z.1 == high));
            assert_eq!(zones[0].1, high);
            if p.contact_ratio < 2.0 {
                let counts: Vec<usize> = zones.iter().map(|z| z.1).collect();
                assert_eq!(counts, vec![2, 1, 2]);
            }
        }
    }
}
