//! The tooth-root stress from the LTCA (`study::ltca::root_stress_cycle`: the contact forces of
//! each position through each body's fillet influence, stresses recovered from the Barlow
//! points) on a light mesh (0.4 mm flanks and fillets, 32 positions): the same pair driven from
//! the other gear, a symmetric pair, and ISO 6336-3 method B beside it; and Hertz between two
//! cylinders from the FE's own contact solve.

use geardyn::case::Case;
use geardyn::samples;
use geardyn::study::ltca::{
    iso_strength, model_with_sizes, root_stress_cycle, root_stress_peaks, RootStressPeak,
};

const POSITIONS: usize = 32;

/// The paper pair, 24/40 (x = +0.3 / −0.3) and the same pair driven from the 40-tooth gear.
fn unequal_and_inverse() -> Vec<(&'static str, Case)> {
    vec![
        ("36/36", samples::paper36_case()),
        ("24/40", samples::shifted_24_40(false)),
        ("40/24", samples::shifted_24_40(true)),
    ]
}

/// The unmodified pair's fillet peaks (tension per gear) at the case's torque on 0.4 mm flanks.
fn peaks(case: &Case) -> [RootStressPeak; 2] {
    peaks_at(case, 0.4e-3)
}

/// [`peaks`] with fillet and flank elements of `fine` [m].
fn peaks_at(case: &Case, fine: f64) -> [RootStressPeak; 2] {
    let mods = case.relief_variant("none").unwrap().modifications;
    let coarse = case.file.mesh.coarse_element_mm * 1e-3;
    let model = model_with_sizes(case, &mods, fine, coarse).unwrap();
    let torque = case.operating_points[0].torque;
    let rows = root_stress_cycle(&model, POSITIONS, torque).unwrap();
    assert!(
        rows.iter()
            .all(|r| r.tension_mpa.is_finite() && r.compression_mpa.is_finite()),
        "every loaded tooth has both fillets"
    );
    let [a, b] = root_stress_peaks(&rows, case);
    [a.unwrap(), b.unwrap()]
}

/// 24/40 (x = +0.3 / −0.3) driven by the 24-tooth gear, and the same pair driven by the 40-tooth
/// gear (40/24, x = −0.3 / +0.3). Frictionless and static, a tooth's fillet sees the same
/// contact point either way; only the load differs, the torque being on the driven gear: F_t =
/// T/r₂. So each gear's largest fillet tension scales with F_t, within 3 % (the 32 positions
/// sample the jump at the end of single contact at different points). Each is within 15 % of
/// ISO 6336-3 method B's σ_F0 (its 30° tangent section and empirical Y_S against the FE's true
/// maximum: 4–10 % below ISO on these pairs at 0.2 mm, validation/strength), and its fillet
/// node within 0.5 mm (radius) of ISO's 30° tangent point.
#[test]
fn the_fillet_stress_scales_with_the_load_when_the_other_gear_drives() {
    let (case_a, case_b) = (samples::shifted_24_40(false), samples::shifted_24_40(true));
    let (a, b) = (peaks(&case_a), peaks(&case_b));
    let f_t = |case: &Case| case.operating_points[0].torque / case.pair.gears[1].reference_radius;
    let scale = f_t(&case_b) / f_t(&case_a);
    assert!((scale - 40.0 / 24.0).abs() < 1e-9);
    // The 24-tooth gear is gear 1 in A and gear 2 in B.
    for (in_a, in_b, name) in [(&a[0], &b[1], "24 teeth"), (&a[1], &b[0], "40 teeth")] {
        let ratio = in_b.tension_mpa / (in_a.tension_mpa * scale);
        eprintln!(
            "{name}: {:.2} MPa driving, {:.2} MPa driven, ratio over F_t {ratio:.4}",
            in_a.tension_mpa, in_b.tension_mpa
        );
        assert!((ratio - 1.0).abs() < 0.03, "{name}: {ratio}");
    }
    for (case, peaks) in [(&case_a, &a), (&case_b, &b)] {
        let iso = iso_strength(case, case.operating_points[0].torque);
        for (g, peak) in peaks.iter().enumerate() {
            let (fe, standard) = (peak.tension_mpa, iso.root_stress_iso_mpa[g]);
            eprintln!(
                "gear {}: FE {fe:.2} MPa at r = {:.3} mm, ISO {standard:.2} MPa at r = {:.3} mm",
                g + 1,
                peak.radius_mm,
                peak.iso_30_degree_tangent_radius_mm
            );
            assert!(
                (fe / standard - 1.0).abs() < 0.15,
                "gear {}: {fe} against {standard}",
                g + 1
            );
            assert!(
                (peak.radius_mm - peak.iso_30_degree_tangent_radius_mm).abs() < 0.5,
                "gear {}",
                g + 1
            );
            assert!(
                peaks[g].compression_mpa < 0.0,
                "the other fillet in compression"
            );
        }
    }
}

/// The paper's 36/36 pair: driver and driven teeth are mirror images under the same load, so
/// their largest fillet tensions agree (within 1 %: the positions sample each gear's end of
/// single contact at mirrored points, to round-off in the geometry).
#[test]
fn a_symmetric_pair_stresses_both_gears_alike() {
    let [g1, g2] = peaks(&samples::paper36_case());
    eprintln!(
        "gear 1 {:.3} MPa, gear 2 {:.3} MPa",
        g1.tension_mpa, g2.tension_mpa
    );
    assert!((g1.tension_mpa / g2.tension_mpa - 1.0).abs() < 0.01);
    assert!((g1.compression_mpa / g2.compression_mpa - 1.0).abs() < 0.01);
}

/// The paper pair's largest fillet tension as the flank and fillet elements halve, 0.4 → 0.2 →
/// 0.1 mm: the change shrinks (75.6 → 76.4 → 76.5 MPa at these 32 positions; 76.1 → 76.9 →
/// 77.0 at 64, validation/strength), and the two finer meshes agree within 0.5 %.
#[test]
fn the_fillet_stress_converges_under_refinement() {
    let case = samples::paper36_case();
    let peak = |fine: f64| peaks_at(&case, fine)[0].tension_mpa;
    let (coarse, middle, fine) = (peak(0.4e-3), peak(0.2e-3), peak(0.1e-3));
    eprintln!("0.4 mm {coarse:.3}, 0.2 mm {middle:.3}, 0.1 mm {fine:.3} MPa");
    assert!((fine - middle).abs() < (middle - coarse).abs());
    assert!((fine / middle - 1.0).abs() < 5e-3);
}

/// Every pair of the test matrix (`samples::PAIR_MATRIX`: ratios and their inverse, shifts,
/// backlash, a hunting tooth, modules 1 and 8, a thin rim, 25°, contact ratios up to 2.65) on
/// its own mesh, 16 positions: the fillet stress of every loaded tooth is found (a tooth without
/// both fillets is an error), in tension on the loaded side and compression on the other, and
/// where ISO 6336-3 method B's load point is one of single contact (ε_α < 2) within 20 % of its
/// σ_F0 without the rim factor Y_B (the FE holds the bore rigid, which backs a thin rim; ISO's
/// Y_B is for a rim that flexes). Measured 4–11 % below it at 64 positions; 16 positions may
/// miss the end of single contact by 1/16 of a base pitch. The LTCA's per-position root stress
/// (`PositionResult::root_stress`, the optimizer's limit) is the cycle's peak to round-off.
#[test]
fn every_pair_of_the_matrix_has_its_root_stress() {
    for pair in geardyn::samples::PAIR_MATRIX {
        let case = pair.case().unwrap();
        let mods = case.relief_variant("none").unwrap().modifications;
        let (fine, coarse) = geardyn::study::ltca::element_sizes(&case);
        let model = model_with_sizes(&case, &mods, fine, coarse).unwrap();
        let torque = case.operating_points[0].torque;
        let rows = root_stress_cycle(&model, 16, torque).unwrap();
        let peaks = root_stress_peaks(&rows, &case);
        let iso = iso_strength(&case, torque);
        // The LTCA's own per-position root stress (what the optimizer's limit reads, computed
        // from the contact forces as they are solved) is the cycle's tooth-by-tooth maximum.
        let cycle = model.run(16, torque, &|_| {}).unwrap();
        for (g, peak) in peaks.iter().enumerate() {
            let own = cycle
                .iter()
                .map(|r| r.root_stress[g] * 1e-6)
                .fold(f64::NEG_INFINITY, f64::max);
            let peak = peak.as_ref().unwrap().tension_mpa;
            assert!(
                (own / peak - 1.0).abs() < 1e-9,
                "{} gear {}: {own} against {peak}",
                pair.name,
                g + 1
            );
        }
        for (g, peak) in peaks.iter().enumerate() {
            let peak = peak.as_ref().unwrap();
            let standard = iso.root_stress_iso_mpa[g] / iso.factors.root[g].rim_factor;
            let applies = case.pair.contact_ratio < 2.0;
            eprintln!(
                "{:<16} gear {}: FE {:8.2} MPa (compression {:8.2}), ISO/Y_B {:8.2} MPa{}",
                pair.name,
                g + 1,
                peak.tension_mpa,
                peak.compression_mpa,
                standard,
                if applies {
                    ""
                } else {
                    " (ε_α ≥ 2: no single contact)"
                }
            );
            assert!(
                peak.tension_mpa > 0.0 && peak.compression_mpa < 0.0,
                "{}",
                pair.name
            );
            if applies {
                assert!(
                    (peak.tension_mpa / standard - 1.0).abs() < 0.2,
                    "{} gear {}: {} against {standard}",
                    pair.name,
                    g + 1,
                    peak.tension_mpa
                );
            }
        }
    }
}

/// Hertz between two cylinders from the FE's own contact: two steel cylinders (R₁ = 20 mm,
/// R₂ = 40 mm, 10 mm wide, plane strain) pressed together by 5 kN, each body a Q8 block
/// 50a × 25a (a the Hertz half width) meshed at a/4 within ±2a of the contact and graded
/// (×1.3) beyond, its base held; the initial gap (x − x₀)²/2R between the two surfaces is
/// Hertz's own parabolic one, its centre x₀ 0.37 of an element off a node, and the two
/// identical blocks make the combined compliance 2C at the facing nodes. The frictionless contact is solved as the LTCA solves it
/// ([`geardyn::ltca::contact::solve_contact`]), and its nodal forces are turned into a pressure
/// by the consistent edge traction ([`geardyn::fe::recovery::edge_traction`]). Against Hertz
/// (p₀ = √(wE*/πR), a = √(4wR/πE*)): the peak pressure within 3 %, the loaded width within one
/// element either side, and the second moment Σ F x²/Σ F against Hertz's a²/4 within 3 % (a
/// measure of the pressure's whole shape). Measured: −0.02 %, 256.7 against 273.8 µm (h = 68 µm),
/// 0.9955 (at a/2: +1.1 %, 0.988; at a/10: +0.03 %, 0.9986).
#[test]
fn fe_contact_of_two_cylinders_is_hertz() {
    use geardyn::fe::assembly::{stiffness_triplets, FactorizedStiffness};
    use geardyn::fe::recovery::edge_traction;
    use geardyn::fe::{elasticity_matrix, PlaneState};
    use geardyn::strength::hertz::{contact_modulus, line_contact};
    use geardyn::strength::iso6336::Elastic;
    use nalgebra::DVector;

    let steel = Elastic {
        youngs_modulus: 206e9,
        poisson_ratio: 0.3,
    };
    let (width, load, radii) = (0.01, 5000.0, [0.02, 0.04]);
    let radius = 1.0 / (1.0 / radii[0] + 1.0 / radii[1]);
    let (p0, a) = line_contact(load, width, radii, contact_modulus([steel; 2]));

    // Corner coordinates from 0 outwards: a/4 to 2a, then ×1.3 to 25a.
    let h = a / 4.0;
    let mut outward: Vec<f64> = (0..=8).map(|k| k as f64 * h).collect();
    let mut size = h;
    while *outward.last().unwrap() < 25.0 * a {
        size *= 1.3;
        outward.push(outward.last().unwrap() + size);
    }
    let xs: Vec<f64> = outward
        .iter()
        .rev()
        .map(|x| -x)
        .chain(outward.iter().skip(1).copied())
        .collect();
    let ys: Vec<f64> = outward.iter().rev().map(|y| -y).collect();
    let (nodes, elements) = geardyn::samples::block_mesh(&xs, &ys);
    let d = elasticity_matrix(
        steel.youngs_modulus,
        steel.poisson_ratio,
        PlaneState::Strain,
    );
    let bottom = ys[0];
    let fixed: Vec<usize> = (0..nodes.len())
        .filter(|&n| (nodes[n].y - bottom).abs() < 1e-12)
        .flat_map(|n| [2 * n, 2 * n + 1])
        .collect();
    let stiffness = FactorizedStiffness::new(
        2 * nodes.len(),
        stiffness_triplets(&nodes, &elements, &d, width),
        &fixed,
    )
    .unwrap();
    let mut surface: Vec<usize> = (0..nodes.len())
        .filter(|&n| nodes[n].y.abs() < 1e-12 && nodes[n].x.abs() <= 2.0 * a * (1.0 + 1e-9))
        .collect();
    surface.sort_by(|&i, &j| nodes[i].x.total_cmp(&nodes[j].x));
    assert_eq!(surface.len(), 33, "corner, mid-side, ..., corner over ±2a");
    let points: Vec<(usize, [f64; 2])> = surface.iter().map(|&n| (n, [0.0, -1.0])).collect();
    let compliance = stiffness.compliance_between(&points) * 2.0;
    let offset = 0.37 * h;
    let gaps = DVector::from_iterator(
        surface.len(),
        surface
            .iter()
            .map(|&n| (nodes[n].x - offset).powi(2) / (2.0 * radius)),
    );
    let arms = DVector::from_element(surface.len(), 1.0);
    let mut forces = DVector::zeros(surface.len());
    geardyn::ltca::contact::solve_contact(&compliance, &gaps, &arms, load, &mut forces).unwrap();

    let positions: Vec<_> = surface.iter().map(|&n| nodes[n]).collect();
    let traction = edge_traction(&positions, forces.as_slice(), width);
    let peak = traction.iter().copied().fold(0.0, f64::max);
    let loaded: Vec<f64> = surface
        .iter()
        .zip(forces.iter())
        .filter(|(_, f)| **f > 0.0)
        .map(|(&n, _)| nodes[n].x)
        .collect();
    let half_width = 0.5 * (loaded.last().unwrap() - loaded[0]);
    let total: f64 = forces.iter().sum();
    let second_moment = surface
        .iter()
        .zip(forces.iter())
        .map(|(&n, f)| f * (nodes[n].x - offset).powi(2))
        .sum::<f64>()
        / total;
    eprintln!(
        "Hertz: p0 {:.1} MPa, a {:.1} um; FE: peak {:.1} MPa ({:+.2} %), loaded half width {:.1} um, \
         second moment / (a²/4) {:.4}",
        p0 * 1e-6,
        a * 1e6,
        peak * 1e-6,
        (peak / p0 - 1.0) * 100.0,
        half_width * 1e6,
        second_moment / (a * a / 4.0)
    );
    assert!((total / load - 1.0).abs() < 1e-9);
    assert!((peak / p0 - 1.0).abs() < 0.03, "{peak} against {p0}");
    assert!((half_width - a).abs() <= h, "{half_width} against {a}");
    assert!((second_moment / (a * a / 4.0) - 1.0).abs() < 0.03);
}

/// The FE's contact pressure of the LTCA (`fe_pressure_cycle`, nodal tractions of the flanks):
/// a row for every loaded pair at every position, positive; the unmodified paper pair loads a
/// tip corner or form point at the ends of its path (edge contact, which a plain Hertz formula
/// cannot give), and the paper's 20 µm tip relief, more than the pair's deflection, clears
/// every end (0.4 mm flanks, 32 positions); likewise on 24/40 and its inverse 40/24.
#[test]
fn relief_clears_the_edge_contacts_of_the_unmodified_pair() {
    use geardyn::study::ltca::fe_pressure_cycle;
    for (name, case) in unequal_and_inverse() {
        let coarse = case.file.mesh.coarse_element_mm * 1e-3;
        let torque = case.operating_points[0].torque;
        for (variant, edges) in [("none", true), ("tip20-root10", false)] {
            let mods = case.relief_variant(variant).unwrap().modifications;
            let model = model_with_sizes(&case, &mods, 0.4e-3, coarse).unwrap();
            let results = model.run(POSITIONS, torque, &|_| {}).unwrap();
            let loaded: usize = results
                .iter()
                .map(|r| r.pair_forces.iter().filter(|f| **f > 0.0).count())
                .sum();
            let rows = fe_pressure_cycle(&model, POSITIONS, torque).unwrap();
            assert_eq!(rows.len(), loaded, "{name} {variant}");
            assert!(
                rows.iter().all(|r| r.pressure_mpa > 0.0),
                "{name} {variant}"
            );
            assert_eq!(
                rows.iter().any(|r| r.at_tip_corner),
                edges,
                "{name} {variant}"
            );
        }
    }
}

/// The field picture's stresses (`peak_field`: the body solved once more under the position's
/// contact forces, every node recovered) at the peak tooth's loaded fillet give the cycle's
/// peak tension (`root_stress_cycle`, through the influence rows of the same solves) to
/// round-off, and its window holds the peak's node (0.4 mm flanks; the paper pair, 24/40 and
/// 40/24).
#[test]
fn the_stress_field_holds_the_fillet_peak() {
    use geardyn::study::ltca::peak_field;
    for (name, case) in unequal_and_inverse() {
        let mods = case.relief_variant("none").unwrap().modifications;
        let coarse = case.file.mesh.coarse_element_mm * 1e-3;
        let model = model_with_sizes(&case, &mods, 0.4e-3, coarse).unwrap();
        let torque = case.operating_points[0].torque;
        let rows = root_stress_cycle(&model, POSITIONS, torque).unwrap();
        let peak = peak_field(&model, &rows, POSITIONS, torque)
            .unwrap()
            .unwrap();
        let field = &peak.field;
        let g = peak.peak.gear - 1;
        let fillet: std::collections::HashSet<usize> = model.bodies[g]
            .fillet
            .nodes
            .iter()
            .filter(|f| f.tooth == peak.peak.tooth && f.loaded_side)
            .map(|f| f.node)
            .collect();
        let principal = field.max_principal();
        let at_fillet = field
            .mesh_node
            .iter()
            .zip(&principal)
            .filter(|(n, _)| fillet.contains(n))
            .map(|(_, s)| *s * 1e-6)
            .fold(f64::NEG_INFINITY, f64::max);
        assert!(
            (at_fillet / peak.peak.tension_mpa - 1.0).abs() < 1e-6,
            "{name}: {at_fillet} against {}",
            peak.peak.tension_mpa
        );
        assert!(field.mesh_node.contains(&peak.peak.tension_node), "{name}");
        assert!(field.von_mises().iter().all(|v| v.is_finite()), "{name}");
    }
}
