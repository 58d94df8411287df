//! The design variables of the relief optimizer and the profile modifications they make.
//!
//! Per gear a tip relief amount C_a and a root relief amount C_f [m], and one relief length
//! shared by all four zones: the fraction λ ∈ (0, 1] of the double-contact zone next to the
//! relieved end that the relief covers — λ = 1 is long relief (tip relief from the HPSTC, root
//! relief from the LPSTC), λ = ½ short relief (Smith, *Gear Noise and Vibration*, §3.3):
//! ```text
//! tip:   ξ_s = ξ_tip − λ (ξ_tip − ξ_HPSTC)       root:  ξ_s = ξ_SAP + λ (ξ_LPSTC − ξ_SAP)
//! ```
//! The shape (linear or parabolic) is not a variable: the optimizer enumerates it outside. A
//! zero amount is no zone. Every design goes through [`GearPair::flank_modification`], so its
//! manufacturing checks (amount ≤ 0.05 m, slope, zones apart) hold for every design tried.

use crate::geometry::{
    FlankModification, FlankReliefSpec, GearPair, GeometryError, ReliefShape, ReliefSpec,
    ReliefStart,
};

/// One relief design.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ReliefDesign {
    /// Tip relief amount of gear 1 and gear 2 [m].
    pub tip: [f64; 2],
    /// Root relief amount of gear 1 and gear 2 [m].
    pub root: [f64; 2],
    /// Fraction λ of the double-contact zone the reliefs cover (1: long, ½: short).
    pub length: f64,
    pub shape: ReliefShape,
}

/// Number of continuous design variables: C_a1, C_f1, C_a2, C_f2, λ.
pub const VARIABLES: usize = 5;

impl ReliefDesign {
    /// No relief.
    pub fn none(shape: ReliefShape) -> Self {
        ReliefDesign {
            tip: [0.0; 2],
            root: [0.0; 2],
            length: 1.0,
            shape,
        }
    }

    /// The variables in order C_a1, C_f1, C_a2, C_f2 [m], λ.
    pub fn to_vector(&self) -> [f64; VARIABLES] {
        [
            self.tip[0],
            self.root[0],
            self.tip[1],
            self.root[1],
            self.length,
        ]
    }

    pub fn from_vector(x: &[f64; VARIABLES], shape: ReliefShape) -> Self {
        ReliefDesign {
            tip: [x[0], x[2]],
            root: [x[1], x[3]],
            length: x[4],
            shape,
        }
    }

    /// The resolved modifications of both gears; a design the geometry cannot carry is the
    /// geometry's error (it names the gear, the zone and the limit).
    pub fn modifications(&self, pair: &GearPair) -> Result<[FlankModification; 2], GeometryError> {
        if !(self.length > 0.0 && self.length <= 1.0) {
            return Err(GeometryError::Relief {
                parameter: "relief length fraction".into(),
                reason: format!(
                    "{} is outside (0, 1]: 1 is long relief (from the HPSTC / LPSTC), 0.5 short",
                    self.length
                ),
            });
        }
        let mut out = [FlankModification::none(); 2];
        for (g, modification) in out.iter_mut().enumerate() {
            let index = g + 1;
            let roll = pair.flank_roll_angles(index);
            let spec = |amount: f64, start: f64| {
                (amount > 0.0).then_some(ReliefSpec {
                    amount,
                    shape: self.shape,
                    start: ReliefStart::RollAngle(start),
                })
            };
            let request = FlankReliefSpec {
                tip: spec(
                    self.tip[g],
                    roll.tip - self.length * (roll.tip - roll.hpstc),
                ),
                root: spec(
                    self.root[g],
                    roll.start_of_active_profile
                        + self.length * (roll.lpstc - roll.start_of_active_profile),
                ),
            };
            *modification = pair.flank_modification(index, &request)?;
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::samples;

    /// λ = 1 is the case's long relief exactly: the paper's 20 µm tip / 10 µm root variant.
    #[test]
    fn long_relief_is_the_case_variant_and_vectors_round_trip() {
        let case = samples::paper36_case();
        let variant = case.relief_variant("tip20-root10").unwrap().modifications;
        let design = ReliefDesign {
            tip: [20e-6; 2],
            root: [10e-6; 2],
            length: 1.0,
            shape: variant[0].tip.unwrap().shape,
        };
        let made = design.modifications(&case.pair).unwrap();
        for g in 0..2 {
            for (a, b) in [
                (made[g].tip, variant[g].tip),
                (made[g].root, variant[g].root),
            ] {
                let (a, b) = (a.unwrap(), b.unwrap());
                assert!((a.amount - b.amount).abs() < 1e-15);
                assert!((a.start_roll_angle - b.start_roll_angle).abs() < 1e-12);
                assert!((a.full_roll_angle - b.full_roll_angle).abs() < 1e-12);
            }
        }
        let x = design.to_vector();
        assert_eq!(ReliefDesign::from_vector(&x, design.shape), design);
        // Zero amounts are no zones; an impossible amount is the geometry's error.
        let none = ReliefDesign::none(ReliefShape::Linear)
            .modifications(&case.pair)
            .unwrap();
        assert!(none.iter().all(|m| m.is_none()));
        let huge = ReliefDesign {
            tip: [1e-3, 0.0],
            ..design
        };
        assert!(huge.modifications(&case.pair).is_err());
        let bad = ReliefDesign {
            length: 0.0,
            ..design
        };
        assert!(bad.modifications(&case.pair).is_err());
    }

    /// Short relief (λ = ½) starts half-way between the single-contact point and the tip.
    #[test]
    fn short_relief_starts_half_way() {
        let pair = samples::paper36_pair();
        let design = ReliefDesign {
            tip: [10e-6; 2],
            root: [0.0; 2],
            length: 0.5,
            shape: ReliefShape::Linear,
        };
        let made = design.modifications(&pair).unwrap();
        let roll = pair.flank_roll_angles(1);
        let tip = made[0].tip.unwrap();
        assert!((tip.start_roll_angle - 0.5 * (roll.tip + roll.hpstc)).abs() < 1e-12);
    }
}
