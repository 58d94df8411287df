//! LTCA on the paper's pair with a light mesh (0.4 mm on the engaging flanks, 16 positions):
//! equilibrium, exact geometry (zero unloaded TE), periodicity, single- vs double-contact
//! stiffness, the effect of relief, and clear errors.

use std::sync::OnceLock;

use geardyn::case::Case;
use geardyn::ltca::{Flank, LtcaError, LtcaModel, PositionResult};
use geardyn::samples;

const TORQUE: f64 = 143.6;
const POSITIONS: usize = 16;

/// The case's LTCA model with 0.4 mm flank elements.
fn model(case: &Case, variant: &str) -> LtcaModel {
    let mods = case.relief_variant(variant).unwrap().modifications;
    let coarse = case.file.mesh.coarse_element_mm * 1e-3;
    geardyn::study::ltca::model_with_sizes(case, &mods, 0.4e-3, coarse).unwrap()
}

fn cycle(variant: &'static str) -> &'static (LtcaModel, Vec<PositionResult>) {
    static NONE: OnceLock<(LtcaModel, Vec<PositionResult>)> = OnceLock::new();
    static RELIEF: OnceLock<(LtcaModel, Vec<PositionResult>)> = OnceLock::new();
    let cell = if variant == "none" { &NONE } else { &RELIEF };
    cell.get_or_init(|| {
        let case = samples::paper36_case();
        let m = model(&case, variant);
        let results = m.run(POSITIONS, TORQUE, &|_| {}).unwrap();
        (m, results)
    })
}

#[test]
fn loads_balance_the_torque_and_sum_to_t_over_rb() {
    let (model, results) = cycle("none");
    let rb2 = model.pair.gears[1].base_radius;
    for r in results {
        assert!(r.kkt_residual < 1e-9, "KKT residual {}", r.kkt_residual);
        // Unmodified involutes: every contact normal lies on the line of action, arm = r_b2.
        assert!(
            (r.total_force - TORQUE / rb2).abs() < 1e-3 * TORQUE / rb2,
            "W = {}",
            r.total_force
        );
        let pair_sum: f64 = r.pair_forces.iter().sum();
        assert!((pair_sum - r.total_force).abs() < 1e-9 * r.total_force);
    }
}

#[test]
fn unmodified_pair_has_no_unloaded_transmission_error() {
    let (model, results) = cycle("none");
    let rb2 = model.pair.gears[1].base_radius;
    for r in results {
        assert!(
            (r.unloaded_te * rb2).abs() < 0.05e-6,
            "unloaded TE {} um",
            r.unloaded_te * rb2 * 1e6
        );
    }
}

#[test]
fn ste_is_periodic_over_one_base_pitch() {
    let (model, results) = cycle("none");
    let next = model.solve_position(POSITIONS, POSITIONS, TORQUE).unwrap();
    let first = &results[0];
    assert!(
        ((next.ste - first.ste) / first.ste).abs() < 5e-3,
        "{} vs {}",
        next.ste,
        first.ste
    );
    assert!(((next.mesh_stiffness - first.mesh_stiffness) / first.mesh_stiffness).abs() < 5e-3);
}

#[test]
fn single_contact_is_softer_than_double_contact() {
    let (_, results) = cycle("none");
    let results: &[PositionResult] = results;
    let loaded_pairs = |r: &PositionResult| {
        r.pair_forces
            .iter()
            .filter(|f| **f > 0.05 * r.total_force)
            .count()
    };
    let single: Vec<f64> = results
        .iter()
        .filter(|r| loaded_pairs(r) == 1)
        .map(|r| r.mesh_stiffness)
        .collect();
    let double: Vec<f64> = results
        .iter()
        .filter(|r| loaded_pairs(r) == 2)
        .map(|r| r.mesh_stiffness)
        .collect();
    assert!(!single.is_empty() && !double.is_empty());
    let max_single = single.iter().copied().fold(0.0, f64::max);
    let min_double = double.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(
        max_single < min_double,
        "single {max_single:e} vs double {min_double:e}"
    );
    // Geometrically ε − 1 = 69 % of the cycle has two pairs; under load the deflection brings
    // the next pair in early and keeps the last one late, so the loaded share is larger.
    let fraction = double.len() as f64 / results.len() as f64;
    let geometric = samples::paper36_pair().contact_ratio - 1.0;
    assert!(
        fraction >= geometric - 1.0 / POSITIONS as f64 && fraction < 0.95,
        "double-contact fraction {fraction}"
    );
}

#[test]
fn relief_raises_ste_near_the_transitions_and_opens_unloaded_te() {
    let (model, relieved) = cycle("tip20-root10");
    let (_, plain) = cycle("none");
    let rb2 = model.pair.gears[1].base_radius;
    // Roll angles are the same grid for both variants.
    let hpstc = model.pair.flank_roll_angles(1).hpstc;
    let near = relieved
        .iter()
        .zip(plain)
        .filter(|(r, _)| (r.roll_angle - hpstc).abs() < 1.5_f64.to_radians())
        .map(|(r, p)| (r.ste - p.ste) * rb2)
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(
        near > 1e-6,
        "relief raises STE near the HPSTC by only {} um",
        near * 1e6
    );
    let max_unloaded = relieved
        .iter()
        .map(|r| r.unloaded_te * rb2)
        .fold(0.0, f64::max);
    // Tip relief 20 µm of one gear plus root relief of the other meet in the middle of the
    // double-contact zone: the unloaded TE stays below their sum.
    assert!(
        max_unloaded > 5e-6 && max_unloaded < 30e-6,
        "unloaded TE {} um",
        max_unloaded * 1e6
    );
}

#[test]
fn non_positive_torque_is_rejected() {
    let (model, _) = cycle("none");
    for torque in [0.0, -10.0, f64::NAN] {
        let err = model.run(8, torque, &|_| {}).unwrap_err();
        assert!(matches!(err, LtcaError::Torque { .. }));
        assert!(err.to_string().contains("torque"));
    }
}

/// The relief as a gap on fixed bodies (`with_relief`: the unmodified pair's meshes and
/// compliance) against the relief meshed into the bodies: the optimizer's shortcut. The
/// 20/10 µm relief moves flank nodes by at most 20 µm of a 0.4 mm element, so the compliance
/// barely changes: mean stiffness, STE peak-to-peak and the unloaded TE within 1 %.
#[test]
fn relief_as_a_gap_on_fixed_bodies_matches_the_remeshed_relief() {
    let (unmodified, _) = cycle("none");
    let (_, meshed) = cycle("tip20-root10");
    let case = samples::paper36_case();
    let mods = case.relief_variant("tip20-root10").unwrap().modifications;
    let gap = unmodified
        .with_relief(&mods)
        .run(POSITIONS, TORQUE, &|_| {})
        .unwrap();
    let stats = |r: &[PositionResult]| {
        let k = r.iter().map(|p| p.mesh_stiffness).sum::<f64>() / r.len() as f64;
        let ste: Vec<f64> = r.iter().map(|p| p.ste).collect();
        let pp = ste.iter().cloned().fold(f64::MIN, f64::max)
            - ste.iter().cloned().fold(f64::MAX, f64::min);
        let e = r.iter().map(|p| p.unloaded_te).fold(f64::MIN, f64::max);
        (k, pp, e)
    };
    let (a, b) = (stats(&gap), stats(meshed));
    for (name, x, y) in [
        ("mean k", a.0, b.0),
        ("STE p-p", a.1, b.1),
        ("max unloaded TE", a.2, b.2),
    ] {
        assert!(
            (x / y - 1.0).abs() < 0.01,
            "{name}: fixed bodies {x:.6e}, re-meshed {y:.6e}"
        );
    }
    // It is the relief that acts: the unmodified cycle is far from it.
    let (_, plain) = cycle("none");
    assert!((stats(plain).1 / b.1 - 1.0).abs() > 0.05);
}

/// A matrix pair's LTCA model (relief none) with 0.4 mm flank elements, run over 16 positions
/// with its periodicity numbers.
fn matrix_cycle(case: &Case) -> (LtcaModel, Vec<PositionResult>, geardyn::ltca::Periodicity) {
    let m = model(case, "none");
    let torque = case.operating_points[0].torque;
    let (results, periodicity) = m.run_checked(POSITIONS, torque, &|_| {}).unwrap();
    (m, results, periodicity)
}

/// The pair that exposed the old pairing (right only where z1 is a multiple of z2): 24/40.
/// Four tooth pairs are carried — the −2 and the +1 within the margin, the entering −1, the present 0 — with
/// their partners from the geometry; the cycle comes back to itself one base pitch on (the
/// wrong partner made the STE 126 µrad at the first position and 1 044 µrad at the last); the
/// run's own checks (KKT, balance, unloaded TE, loaded pairs at 1 % load against the path)
/// pass; and the inverse pair 40/24 with the torque transferred gives the same STE along the
/// line of action at the mirrored positions (mean within 0.5 %, each position within 2 %: the
/// node-to-surface contact's jitter of about 1 % between neighbouring positions).
#[test]
fn an_unequal_pair_and_its_inverse_give_one_periodic_ste() {
    let case = samples::matrix_pair("24-40").unwrap().case().unwrap();
    let (m, results, periodicity) = matrix_cycle(&case);
    // −2 (22/2), −1 (23/1), 0 (0/0) and +1 (1/39): the +1 pair is within the margin by 0.001
    // pitch only (CE/p_b + 0.2 = 1.001), so it is not asserted.
    let index = |p: (usize, usize)| m.tooth_pairs.iter().position(|q| *q == p).unwrap();
    let (entering, present) = (index((23, 1)), index((0, 0)));
    let _ = index((22, 2));
    assert!(
        periodicity.ste_relative_difference < 1e-4,
        "{periodicity:?}"
    );
    assert!(
        periodicity.force_relative_difference < 1e-4,
        "{periodicity:?}"
    );
    // Over θ ∈ [0, p] from the pitch point, the present pair 0 and the entering −1 carry the
    // load; the approach AC = 0.857 p_b and the recess CE = 0.800 p_b (ε_α = 1.66) are both
    // shorter than a base pitch, so the −2 pair enters and the +1 pair leaves only within the
    // margin and never touch.
    let loaded: Vec<usize> = (0..m.tooth_pairs.len())
        .filter(|&p| results.iter().any(|r| r.pair_forces[p] > 0.0))
        .collect();
    assert_eq!(loaded, vec![entering, present]);
    let none = [geardyn::geometry::FlankModification::none(); 2];
    let torque = case.operating_points[0].torque;
    let checks =
        geardyn::study::ltca::self_checks(&m, &none, &results, &periodicity, POSITIONS, torque)
            .unwrap();
    assert!(checks.len() >= 7);
    for c in &checks {
        assert!(c.passed, "{}", c.line());
    }

    let swapped_case = case.swapped().unwrap();
    assert_eq!(swapped_case.pair.gears[0].teeth(), 40);
    let (_, swapped, _) = matrix_cycle(&swapped_case);
    let (mean, largest) = geardyn::study::pairs::swap_differences(
        &results,
        case.pair.gears[1].base_radius,
        &swapped,
        swapped_case.pair.gears[1].base_radius,
    );
    assert!(mean < 0.005, "swap: mean STE differs by {mean}");
    assert!(largest < 0.02, "swap: an STE differs by {largest}");
}

/// Without the entering tooth meshed fine, the model cannot carry the pair that takes over one
/// pitch on; the periodicity check says so instead of returning a cycle.
#[test]
fn the_periodicity_check_catches_a_missing_pair() {
    let case = samples::matrix_pair("24-40").unwrap().case().unwrap();
    let none = [geardyn::geometry::FlankModification::none(); 2];
    let spec = |teeth: Vec<usize>| geardyn::mesh::MeshSpec {
        fine_size: 0.4e-3,
        coarse_size: case.file.mesh.coarse_element_mm * 1e-3,
        fine_teeth: teeth,
        layout: geardyn::mesh::ToothLayout::Graded,
    };
    let m = LtcaModel::new(
        &case.pair,
        &none,
        [spec(vec![0, 1]), spec(vec![0, 39])],
        case.ltca_material(),
    )
    .unwrap();
    assert_eq!(m.tooth_pairs, vec![(0, 0), (1, 39)]);
    match m.run(POSITIONS, case.operating_points[0].torque, &|_| {}) {
        Err(LtcaError::NotPeriodic { periodicity, .. }) => {
            assert!(periodicity.ste_relative_difference > 0.1, "{periodicity:?}");
            let text = LtcaError::NotPeriodic {
                torque: 1.0,
                periodicity,
            }
            .to_string();
            assert!(text.contains("not periodic over one base pitch"), "{text}");
        }
        other => panic!("expected NotPeriodic, got {:?}", other.map(|r| r.len())),
    }
}

/// A high-contact-ratio pair (ε_α 2.40): two or three pairs carry the load at every position,
/// three at some; the loaded contact ratio is above 2 and near ε_α; its self-checks pass.
#[test]
fn a_high_contact_ratio_pair_shares_the_load_among_two_and_three_pairs() {
    let case = samples::matrix_pair("hcr-2.4").unwrap().case().unwrap();
    assert!(case.pair.contact_ratio > 2.35 && case.pair.contact_ratio < 2.45);
    let (m, results, periodicity) = matrix_cycle(&case);
    let loaded: Vec<usize> = results
        .iter()
        .map(|r| r.pair_forces.iter().filter(|f| **f > 0.0).count())
        .collect();
    assert!(loaded.iter().all(|n| *n == 2 || *n == 3), "{loaded:?}");
    assert!(loaded.contains(&3) && loaded.contains(&2), "{loaded:?}");
    let eps = m.loaded_contact_ratio(&results);
    assert!(eps > 2.3 && eps < 2.7, "loaded contact ratio {eps}");
    let none = [geardyn::geometry::FlankModification::none(); 2];
    let torque = case.operating_points[0].torque;
    let checks =
        geardyn::study::ltca::self_checks(&m, &none, &results, &periodicity, POSITIONS, torque)
            .unwrap();
    for c in &checks {
        assert!(c.passed, "{}", c.line());
    }
}

/// Every pair of the matrix is a valid case whose contact ratio and centre distance are the
/// ones its description gives.
#[test]
fn every_matrix_pair_is_a_valid_case() {
    for pair in samples::PAIR_MATRIX {
        let case = pair.case().unwrap_or_else(|e| panic!("{}: {e}", pair.name));
        assert!(case.pair.contact_ratio >= 1.0, "{}", pair.name);
        let swapped = case.swapped().unwrap();
        assert!((swapped.pair.contact_ratio - case.pair.contact_ratio).abs() < 1e-9);
        assert!((swapped.pair.center_distance - case.pair.center_distance).abs() < 1e-12);
    }
    let eps = |name: &str| {
        samples::matrix_pair(name)
            .unwrap()
            .case()
            .unwrap()
            .pair
            .contact_ratio
    };
    assert!((eps("hcr-2.1") - 2.12).abs() < 0.01);
    assert!((eps("hcr-2.4") - 2.40).abs() < 0.01);
    assert!((eps("hcr-2.65") - 2.65).abs() < 0.01);
    // The shifted 19/57 at its own zero-backlash centre distance, and 0.136 mm beyond it.
    let center = |name: &str| {
        samples::matrix_pair(name)
            .unwrap()
            .case()
            .unwrap()
            .pair
            .center_distance
    };
    assert!((center("19-57-shift") - 121.464e-3).abs() < 1e-6);
    assert!((center("19-57-backlash") - 121.6e-3).abs() < 1e-12);
    let backlash = samples::matrix_pair("19-57-backlash")
        .unwrap()
        .case()
        .unwrap()
        .pair;
    assert!(backlash.backlash_normal > 50e-6);
}

/// The back flanks under the reversed torque, solved on their own (bodies meshed fine on the
/// back flanks, the back pairs, gear 2 leading), against the mirror that the lumped model uses
/// for symmetric teeth: the back flanks at driver rotation θ meet as the drive flanks at
/// 2ψ₁ − θ ([`geardyn::geometry::GearPair::back_flank_reflection`] ρ = 2(ξ_p + ψ₁)), with the
/// backlash j added to the gap. On the paper pair, 24/40 and its inverse (zero backlash) the two
/// agree at every position to 2e-5 of the loaded deflection (measured 7e-6: the bodies are
/// meshed fine on opposite flanks, so the meshes are mirror images only up to the mesher's
/// seams), and carry the same pair loads in mirrored order. With a thickness reduction
/// (40 / 20 µm, j = 56 µm) the unloaded gap is j/r_b2 + the mirrored one to 1e-4 of it, and the
/// mean loaded approach agrees to 2 % (0.2 % measured); position by position the mirror is off by the
/// backlash's rotation (the configuration is no longer symmetric), 3 % where a pair enters,
/// which is why the back flanks get their own LTCA. The same on module 1 with a backlash
/// beyond 5 % of the module (mean approach 1.1 % apart).
#[test]
fn the_back_flanks_mirror_the_drive_flanks_of_symmetric_teeth() {
    let paper = samples::paper36_case();
    let thinned = Case::load_with(
        None,
        &[
            geardyn::case::Override::set("gear1.thickness_reduction_um", 40.0),
            geardyn::case::Override::set("gear2.thickness_reduction_um", 20.0),
        ],
    )
    .unwrap();
    // Module 1 with 40 µm off each tooth: a backlash (75 µm) beyond 5 % of the module, the
    // first-touch search's reach past the gap.
    let module_1 = samples::matrix_pair("module-1").unwrap();
    let mut overrides = module_1.parsed_overrides();
    overrides.extend([
        geardyn::case::Override::set("gear1.thickness_reduction_um", 40.0),
        geardyn::case::Override::set("gear2.thickness_reduction_um", 40.0),
    ]);
    let cases = [
        ("paper", paper),
        (
            "24-40",
            samples::matrix_pair("24-40").unwrap().case().unwrap(),
        ),
        (
            "40-24",
            samples::matrix_pair("40-24").unwrap().case().unwrap(),
        ),
        ("thinned", thinned),
        (
            "module-1 thinned",
            Case::load_with(None, &overrides).unwrap(),
        ),
    ];
    for (name, case) in cases {
        let none = [geardyn::geometry::FlankModification::none(); 2];
        let coarse = case.file.mesh.coarse_element_mm * 1e-3;
        // Twice the case's flank size, at most 0.4 mm (the paper pair's light mesh).
        let fine = (2.0 * case.file.mesh.fine_element_mm).min(0.4) * 1e-3;
        if name.starts_with("module") {
            assert!(case.pair.backlash_normal > 0.05 * case.pair.gears[0].module());
        }
        let drive = geardyn::study::ltca::model_with_sizes(&case, &none, fine, coarse).unwrap();
        let back = geardyn::study::ltca::model_on_flank(&case, &none, (fine, coarse), Flank::Back)
            .unwrap();
        let torque = case.operating_points[0].torque;
        let (results, periodicity) = back.run_checked(8, torque, &|_| {}).unwrap();
        assert!(periodicity.holds(), "{name}: {periodicity:?}");
        // In driver rotation from the pitch-point position the mirror is θ → 2ψ₁ − θ, taken
        // back into the drive cycle's base pitch.
        let pair = &case.pair;
        let two_psi1 =
            pair.back_flank_reflection() - 2.0 * pair.roll_angle_at(1, pair.contact_points.pitch);
        let p1 = pair.gears[0].angular_pitch();
        let gap = case.pair.backlash_normal / pair.gears[1].base_radius;
        let (mut back_mean, mut mirror_mean) = (0.0, 0.0);
        for (i, r) in results.iter().enumerate() {
            let mirrored = drive
                .solve_at(i, (two_psi1 - r.driver_rotation).rem_euclid(p1), torque)
                .unwrap();
            let approach = r.ste - r.unloaded_te;
            back_mean += approach / results.len() as f64;
            mirror_mean += (mirrored.ste - mirrored.unloaded_te) / results.len() as f64;
            let unloaded = mirrored.unloaded_te + gap;
            assert!(
                (r.unloaded_te - unloaded).abs() < 1e-4 * unloaded.max(approach),
                "{name} {i}: unloaded back TE {:e} vs mirrored {unloaded:e}",
                r.unloaded_te
            );
            if gap == 0.0 {
                let difference = (r.ste - mirrored.ste).abs() / approach;
                assert!(difference < 2e-5, "{name} {i}: STE {difference:e} apart");
                let sorted = |f: &[f64]| {
                    let mut f: Vec<f64> = f.iter().copied().filter(|f| *f > 0.0).collect();
                    f.sort_by(f64::total_cmp);
                    f
                };
                let (a, b) = (sorted(&r.pair_forces), sorted(&mirrored.pair_forces));
                assert_eq!(a.len(), b.len(), "{name} {i}: loaded pairs");
                for (x, y) in a.iter().zip(&b) {
                    assert!(
                        (x - y).abs() < 1e-4 * r.total_force,
                        "{name} {i}: {x} vs {y}"
                    );
                }
            }
        }
        // Without backlash the two are one; with it the mirror's shift moves the 8 positions'
        // mean: 0.2 % on the paper pair (j = 1.8 % of the module), 1.1 % on module 1 (7.5 %).
        let tolerance = if gap == 0.0 { 1e-4 } else { 2e-2 };
        assert!(
            (back_mean / mirror_mean - 1.0).abs() < tolerance,
            "{name}: mean approach {back_mean:e} vs {mirror_mean:e}"
        );
    }
}
