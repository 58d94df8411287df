//! Property tests over random gears: every input gives a valid, finite tooth or a clear error —
//! never a panic or a NaN.

use geardyn::geometry::{
    BasicRack, FlankReliefSpec, GearPair, GearSpec, OutlineResolution, PairSpec, ReliefShape,
    ReliefSpec, ReliefStart,
};
use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;

fn gear(teeth: u32, shift: f64) -> GearSpec {
    GearSpec {
        teeth,
        profile_shift: shift,
        addendum_coeff: 1.0,
        face_width: 0.02,
        bore_radius: 0.0,
        thickness_reduction: 0.0,
    }
}

proptest! {
    // Failures found before are replayed first from tests/geometry_properties.proptest-regressions
    // (`WithSource`: the default `SourceParallel` finds no lib.rs beside an integration test and
    // silently skips the file).
    #![proptest_config(ProptestConfig {
        cases: 400,
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource("proptest-regressions"))),
        ..ProptestConfig::default()
    })]

    #[test]
    fn random_gears_are_valid_or_rejected_clearly(
        z1 in 10u32..200, z2 in 10u32..200,
        alpha_deg in 14.5f64..25.0,
        x1 in -0.5f64..0.8, x2 in -0.5f64..0.8,
        tip_um in 0.0f64..50.0, root_um in 0.0f64..50.0,
        parabolic in any::<bool>(),
        short in any::<bool>(),
    ) {
        let module = 0.003;
        let rack = BasicRack { module, pressure_angle: alpha_deg.to_radians(), dedendum_coeff: 1.25, tip_radius_coeff: 0.25 };
        let mut g1 = gear(z1, x1);
        let mut g2 = gear(z2, x2);
        // A bore that leaves a rim of a few modules.
        g1.bore_radius = 0.5 * module * z1 as f64 * 0.4;
        g2.bore_radius = 0.5 * module * z2 as f64 * 0.4;
        match GearPair::new(&PairSpec { rack, gears: [g1, g2], center_distance: None }) {
            Err(e) => {
                let message = e.to_string();
                prop_assert!(!message.is_empty() && !message.contains("NaN"), "{message}");
            }
            Ok(pair) => {
                prop_assert!(
                    pair.contact_ratio >= 1.0
                        && pair.contact_ratio < geardyn::geometry::MAX_CONTACT_RATIO
                );
                prop_assert!(pair.backlash_normal.abs() < 1e-12);
                let shape = if parabolic { ReliefShape::Parabolic } else { ReliefShape::Linear };
                let (tip_start, root_start) = if short { (ReliefStart::Short, ReliefStart::Short) } else { (ReliefStart::Hpstc, ReliefStart::Lpstc) };
                let request = FlankReliefSpec {
                    tip: Some(ReliefSpec { amount: tip_um * 1e-6, shape, start: tip_start }),
                    root: Some(ReliefSpec { amount: root_um * 1e-6, shape, start: root_start }),
                };
                for index in 1..=2 {
                    match pair.flank_modification(index, &request) {
                        Err(e) => prop_assert!(!e.to_string().contains("NaN"), "{e}"),
                        Ok(modification) => {
                            let gear = pair.gear(index);
                            let tooth = gear.tooth_outline(&modification, OutlineResolution::default());
                            for p in &tooth {
                                prop_assert!(p.position.x.is_finite() && p.position.y.is_finite());
                                let r = p.position.coords.norm();
                                prop_assert!(r >= gear.root_radius * (1.0 - 1e-12) && r <= gear.tip_radius * (1.0 + 1e-12));
                            }
                            // The half tooth stays on its side of the centre line.
                            let n = tooth.len() / 2;
                            prop_assert!(tooth[..n].iter().all(|p| p.position.x >= -1e-15));
                        }
                    }
                }
            }
        }
    }
}
