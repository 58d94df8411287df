//! Profile modification: tip and root relief as a deviation along the flank normal.
//!
//! The deviation δ(ξ) ≥ 0 removes material along the involute's normal (the line of action
//! direction), as a function of the gear's own roll angle ξ:
//! ```text
//! tip relief   δ(ξ) = C_a · ((ξ − ξ_s) / (ξ_a − ξ_s))^p      for ξ > ξ_s,   ξ_a: tip circle
//! root relief  δ(ξ) = C_f · ((ξ_s − ξ) / (ξ_s − ξ_N))^p      for ξ < ξ_s,   ξ_N: start of active profile
//! ```
//! with p = 1 (linear) or 2 (parabolic). So C_a is the relief at the tip and C_f the relief where the
//! mating tip first touches (the paper's points K and F in its Fig. 15). Below the start of active
//! profile the root law continues to the form circle. Roll angle is linear in the path of contact,
//! so linear in ξ is linear along the line of action (ISO 21771 convention).
//!
//! Relief start conventions (Smith, *Gear Noise and Vibration*, 2nd ed., §3.3):
//! * `hpstc` — tip relief from the highest point of single tooth contact: **long relief**, it
//!   covers the whole double-contact zone at the tip.
//! * `lpstc` — root relief from the lowest point of single tooth contact: long root relief.
//! * `short` — half of that double-contact zone (the start is half-way between the single-contact
//!   point and the end of the active profile).
//! * an explicit roll angle of the gear, or a diameter on the gear.
//!
//! For a high contact ratio (2 ≤ ε_α < 3) the HPSTC and LPSTC are the boundaries of the zones of
//! least contact ([`super::GearPair`]: A + ⌊ε_α⌋ p_b and E − ⌊ε_α⌋ p_b), and "double contact"
//! above reads "the end zone of more contact" (three pairs against two).

/// Shape of the relief curve.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ReliefShape {
    Linear,
    Parabolic,
}

impl ReliefShape {
    /// The case file's name of the shape.
    pub fn name(self) -> &'static str {
        match self {
            ReliefShape::Linear => "linear",
            ReliefShape::Parabolic => "parabolic",
        }
    }

    fn exponent(self) -> i32 {
        match self {
            ReliefShape::Linear => 1,
            ReliefShape::Parabolic => 2,
        }
    }
}

/// Where a relief starts on the flank.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ReliefStart {
    /// Highest point of single tooth contact of this gear (long tip relief).
    Hpstc,
    /// Lowest point of single tooth contact of this gear (long root relief).
    Lpstc,
    /// Half of the double-contact zone next to the relieved end (short relief).
    Short,
    /// Roll angle ξ of this gear [rad].
    RollAngle(f64),
    /// Diameter on this gear [m].
    Diameter(f64),
}

/// One relief as asked for (SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReliefSpec {
    /// Amount C [m]: at the tip (tip relief) or at the start of active profile (root relief).
    pub amount: f64,
    pub shape: ReliefShape,
    pub start: ReliefStart,
}

/// Tip and root relief asked for on one gear (both flanks alike).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FlankReliefSpec {
    pub tip: Option<ReliefSpec>,
    pub root: Option<ReliefSpec>,
}

/// A resolved relief zone in roll angle: δ = amount·(|ξ − start| / |full − start|)^p on the relieved
/// side of `start`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ReliefZone {
    /// Amount reached at `full_roll_angle` [m].
    pub amount: f64,
    /// Roll angle where the relief starts (δ = 0) [rad].
    pub start_roll_angle: f64,
    /// Roll angle where δ equals `amount` [rad].
    pub full_roll_angle: f64,
    pub shape: ReliefShape,
}

impl ReliefZone {
    /// Deviation δ(ξ) [m]: zero on the unrelieved side of the start, `amount`·t^p between the
    /// start and the full point; beyond the full point `amount` for root relief, the power law
    /// continued for tip relief.
    ///
    /// Beyond a root relief's full point (the SAP) lies the form-to-SAP stretch, which never
    /// meets the mate, and the fillet's blend takes δ at the form point. Continuing the power law
    /// there would cut millimetres where a short relief zone is µm-narrow in roll and the form
    /// point lies far below the SAP (a 157/82 pair at ε ≈ 1.03: 6.5 µm at the SAP became 4 mm at
    /// the form point). Beyond a tip relief's full point (the unmodified tip) lie only the few
    /// µrad of roll the relieved flank needs to reach the tip circle, where the law stays as it
    /// was.
    pub fn deviation(&self, roll_angle: f64) -> f64 {
        let span = self.full_roll_angle - self.start_roll_angle;
        let t = (roll_angle - self.start_roll_angle) / span;
        if t <= 0.0 {
            0.0
        } else {
            let t = if span < 0.0 { t.min(1.0) } else { t };
            self.amount * t.powi(self.shape.exponent())
        }
    }
}

/// The resolved profile modification of one gear.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct FlankModification {
    pub tip: Option<ReliefZone>,
    pub root: Option<ReliefZone>,
}

impl FlankModification {
    /// The unmodified involute.
    pub fn none() -> Self {
        Self::default()
    }

    /// Total normal deviation δ(ξ) = δ_tip(ξ) + δ_root(ξ) [m] (material removed).
    pub fn deviation(&self, roll_angle: f64) -> f64 {
        self.tip.map_or(0.0, |z| z.deviation(roll_angle))
            + self.root.map_or(0.0, |z| z.deviation(roll_angle))
    }

    pub fn is_none(&self) -> bool {
        self.tip.is_none() && self.root.is_none()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_and_parabolic_laws() {
        let zone = ReliefZone {
            amount: 20e-6,
            start_roll_angle: 0.4,
            full_roll_angle: 0.5,
            shape: ReliefShape::Linear,
        };
        assert_eq!(zone.deviation(0.39), 0.0);
        assert!((zone.deviation(0.45) - 10e-6).abs() < 1e-18);
        assert!((zone.deviation(0.5) - 20e-6).abs() < 1e-18);
        let parabolic = ReliefZone {
            shape: ReliefShape::Parabolic,
            ..zone
        };
        assert!((parabolic.deviation(0.45) - 5e-6).abs() < 1e-18);
        // Beyond a tip relief's full point the law goes on: 20 µm · 1.5².
        assert!((parabolic.deviation(0.55) - 45e-6).abs() < 1e-18);
        // Root relief: the relieved side is below the start.
        let root = ReliefZone {
            amount: 10e-6,
            start_roll_angle: 0.3,
            full_roll_angle: 0.2,
            shape: ReliefShape::Linear,
        };
        assert_eq!(root.deviation(0.31), 0.0);
        assert!((root.deviation(0.2) - 10e-6).abs() < 1e-18);
        // Beyond a root relief's full point the amount holds.
        assert_eq!(root.deviation(0.05), 10e-6);
    }
}
