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
    engaged_pairs(
        pair,
        0.0,
        pair.gears[0].angular_pitch(),
        ENGAGEMENT_MARGIN,
    )
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
