//! Modal analysis of the meshed pair about the LTCA's loaded state (1 mm flanks, 3 mm body, as
//! the explicit FE's default mesh): the model's static tangent stiffness against the LTCA's
//! condensed tangent, the mesh mode against the one-DOF √(k/m) of the same stiffness and
//! inertia for both boundary conditions, and the rigid mode of the free pair.

use std::f64::consts::TAU;

use geardyn::ltca::modal::{pair_modes, Hubs, PairModes};
use geardyn::ltca::LtcaModel;
use geardyn::samples;

const TORQUE: f64 = 143.6;
const POSITIONS: usize = 8;

fn model() -> (LtcaModel, geardyn::case::Case) {
    let case = samples::paper36_case();
    let mods = case.relief_variant("none").unwrap().modifications;
    let model = geardyn::study::ltca::model_with_sizes(&case, &mods, 1e-3, 3e-3).unwrap();
    (model, case)
}

fn modes(model: &LtcaModel, case: &geardyn::case::Case, index: usize, hubs: Hubs) -> PairModes {
    pair_modes(
        model,
        (index, POSITIONS),
        TORQUE,
        case.ltca_material(),
        case.material.density,
        hubs,
        8,
    )
    .unwrap()
}

#[test]
fn mesh_mode_is_the_one_dof_oscillator_of_the_tangent_stiffness() {
    let (model, case) = model();
    let rb = [
        model.pair.gears[0].base_radius,
        model.pair.gears[1].base_radius,
    ];
    // Position 0: the pitch point, single contact; position 4: half a pitch on, double contact.
    for index in [0, 4] {
        let held = modes(&model, &case, index, Hubs::DriverHeld);
        let free = modes(&model, &case, index, Hubs::BothFree);
        // The assembled ties reproduce the LTCA's condensation: the same bodies, the same active
        // set; what differs is the hard contact's 1e-4 tie compliance and the ties' nodal
        // normals against the LTCA's exact moment arms.
        let rel = held.static_mesh_stiffness / held.ltca_tangent_stiffness - 1.0;
        assert!(
            rel.abs() < 0.01,
            "position {index}: static tangent {rel:+.4}"
        );
        assert!(held.ltca_tangent_stiffness >= held.ltca_mesh_stiffness * 0.999);
        let [i1, i2] = held.inertias;
        let rigid = geardyn::study::lumped::gear_inertias(&case);
        assert!((i1 / rigid[0] - 1.0).abs() < 1e-4 && (i2 / rigid[1] - 1.0).abs() < 1e-4);
        for result in [&held, &free] {
            let mesh = &result.modes[result.mesh_mode];
            assert!(mesh.mesh_share > 0.99, "mesh share {}", mesh.mesh_share);
            assert!(result.residual < 1e-8);
        }
        let f_held = held.modes[held.mesh_mode].frequency_hz;
        let f_free = free.modes[free.mesh_mode].frequency_hz;
        // The hub-to-hub stiffness holds each body's twist between bore and teeth. A hub that
        // is free and light (bore nodes only) leaves its body's twist out of the mesh mode,
        // whose inertia sits outside it: with both hubs free the mode sees the rim-to-rim
        // compliance c_r = 1/(ω² m_e), with the driver held c_r + c_b1, the driver's body
        // twist c_b1 = (1/k_static − c_r)/2 for equal gears. The free pair's mode predicts the
        // held pair's to 1 %; rigid-gear inertias on the hub-to-hub stiffness miss both.
        let m_held = i2 / (rb[1] * rb[1]);
        let m_free = i1 * i2 / (i1 * rb[1] * rb[1] + i2 * rb[0] * rb[0]);
        let c_rim = 1.0 / ((TAU * f_free).powi(2) * m_free);
        let c_body = (1.0 / held.static_mesh_stiffness - c_rim) / 2.0;
        assert!(c_body > 0.0);
        let predicted = (1.0 / ((c_rim + c_body) * m_held)).sqrt() / TAU;
        assert!(
            (predicted / f_held - 1.0).abs() < 0.01,
            "position {index}: held {f_held:.1} Hz, predicted from the free pair {predicted:.1} Hz"
        );
        // The twist is that of the body between bore and root circle: the annulus in shear
        // gives it to within the rim's and the teeth's foundation share (15 %; measured 7 %).
        let analytic = rb[1].powi(2)
            * model.pair.gears[1].body_torsional_compliance(
                case.material.youngs_modulus,
                case.material.poisson_ratio,
            );
        assert!(
            (analytic / c_body - 1.0).abs() < 0.15,
            "body twist: annulus {analytic:.3e} m/N, modal {c_body:.3e} m/N"
        );
        let one_dof = (held.static_mesh_stiffness / m_held).sqrt() / TAU;
        assert!(f_held > one_dof && f_free > one_dof * 2f64.sqrt());
        assert_eq!(free.modes[0].kind, "rigid");
        assert!(free.modes[0].frequency_hz.abs() < 1.0);
        assert!(held.modes.iter().all(|m| m.kind != "rigid"));
        // Freeing the driver lightens the mesh mode: m_e < I₂/r_b2².
        assert!(free.modes[free.mesh_mode].frequency_hz > held.modes[held.mesh_mode].frequency_hz);
    }
}

/// Each mode's shares of the gears' rigid motions (modal effective inertia and mass) name the
/// body modes. Known answer: the free pair's rigid mode turns the gears as a tied mesh does,
/// r_b1 θ₁ = −r_b2 θ₂, so it holds the share I₁θ₁²/(I₁θ₁² + I₂θ₂²) of the driver's rotation,
/// the rest of the driven gear's, and (the bodies being balanced) none of their translation.
/// On an unequal pair with a small pinion (24/40) the driven gear's lateral pair (its rim
/// swaying against the held bore, along and across the line of action) lies below the pinion's
/// torsion: the torsion is the mode with the pinion's rotation share, not the next one up, and
/// a lateral mode carries no rotation. The lumped model's rim sway bounds the lateral mode
/// across the line of action from above.
#[test]
fn body_modes_are_named_by_their_shares_of_the_rigid_motions() {
    use geardyn::case::{Case, Override};
    let case = Case::load_with(
        None,
        &[
            Override::set("gear1.teeth", 24i64),
            Override::set("gear2.teeth", 40i64),
        ],
    )
    .unwrap();
    let mods = case.relief_variant("none").unwrap().modifications;
    let model = geardyn::study::ltca::model_with_sizes(&case, &mods, 1e-3, 3e-3).unwrap();
    let run = |hubs| {
        pair_modes(
            &model,
            (0, POSITIONS),
            TORQUE,
            case.ltca_material(),
            case.material.density,
            hubs,
            10,
        )
        .unwrap()
    };
    let free = run(Hubs::BothFree);
    let rigid = &free.modes[0];
    assert_eq!(rigid.kind, "rigid");
    let [i1, i2] = free.inertias;
    let rb = [
        model.pair.gears[0].base_radius,
        model.pair.gears[1].base_radius,
    ];
    let theta2 = rb[0] / rb[1];
    let expected = i1 / (i1 + i2 * theta2 * theta2);
    // The tie's 1e-4 compliance and the shift's 10 Hz leave the rigid mode rigid to ~1e-6.
    assert!(
        (rigid.rotation_share[0] / expected - 1.0).abs() < 1e-4
            && (rigid.rotation_share[1] / (1.0 - expected) - 1.0).abs() < 1e-4,
        "rigid mode's rotation shares {:?}, expected {expected:.6} / {:.6}",
        rigid.rotation_share,
        1.0 - expected
    );
    assert!(rigid.lateral_share.iter().all(|s| *s < 1e-6));

    let held = run(Hubs::DriverHeld);
    let torsion = held
        .torsion_mode(0)
        .expect("the pinion's torsion among ten modes");
    assert_eq!(torsion.kind, "driver torsion");
    assert!(torsion.rotation_share[0] > 0.8, "{torsion:?}");
    let next_up = &held.modes[held.mesh_mode + 1];
    assert_eq!(next_up.kind, "driven lateral", "{:?}", held.modes);
    assert!(next_up.frequency_hz < torsion.frequency_hz);
    assert!(next_up.rotation_share.iter().all(|s| *s < 0.01));
    // The lateral pair: along and across the line of action, nearly one frequency (the mesh
    // spring stiffens the one along it).
    let lateral: Vec<_> = held
        .modes
        .iter()
        .filter(|m| m.kind == "driven lateral")
        .collect();
    assert_eq!(lateral.len(), 2, "{:?}", held.modes);
    assert!(lateral[1].frequency_hz / lateral[0].frequency_hz - 1.0 < 0.05);
    // The mesh excites the one along the line of action, not the one across it.
    assert!(lateral[1].mesh_share > 1e3 * lateral[0].mesh_share);
    // The lumped model's sway of the driven rim (a static FE of the body alone on the case's
    // mesh, Guyan onto the rim's translation) against the pair's modal analysis: the Rayleigh
    // quotient of a static shape bounds the mode across the line of action from above, close
    // to it (+2.7 % on 0.15 mm flanks, validation/frequencies; the teeth ride rigidly on the
    // rim there, bend here).
    let sway = geardyn::study::lumped::rim_sway(&case).unwrap()[1];
    let sway_hz = (sway.stiffness / sway.mass).sqrt() / std::f64::consts::TAU;
    let above = sway_hz / lateral[0].frequency_hz - 1.0;
    assert!(
        (-0.005..0.05).contains(&above),
        "sway {sway_hz:.0} Hz, modal {:.0} Hz",
        lateral[0].frequency_hz
    );
}

/// A 53-tooth driver held driving a 17-tooth pinion (x = −0.1 / +0.1, the case's 0.2 mm mesh):
/// the driver body's torsion (about 4.1 kHz) lies below the mesh mode (about 8.4 kHz) and takes
/// 0.4 of the mesh's compliance, so the FE modal's largest share alone picks the torsion at some
/// positions and the mesh mode at others (a factor 2 between them). `validate frequencies`
/// pairs the modes by shape: at every position the FE mode compared is the lumped mesh mode's
/// partner, within 6 % of it (the 17-tooth pinion's thin rim puts the lumped model 3.1–4.0 %
/// high on this pair, both free as well, 3.5–4.7 % with a massless mesh; validation/frequencies),
/// and the driver's torsion with the lumped model's within 3 % (measured −1.3 %).
#[test]
fn a_body_mode_below_the_mesh_mode_is_compared_mode_for_mode() {
    use geardyn::case::{Case, Override};
    let case = Case::load_with(
        None,
        &[
            Override::set("gear1.teeth", 53),
            Override::set("gear2.teeth", 17),
            Override::set("gear1.profile_shift", -0.1),
            Override::set("gear2.profile_shift", 0.1),
        ],
    )
    .unwrap();
    let modes = geardyn::study::frequencies::mesh_modes(&case, POSITIONS, &|_, _, _| {}).unwrap();
    let held = &modes.driver_held;
    assert!(
        held.positions_paired_off_largest_share > 0,
        "the largest share no longer jumps: this test no longer tests the pairing"
    );
    for ((deg, fe), (_, lumped)) in held.fe_modal_hz.iter().zip(&held.lumped_hz_per_position) {
        assert!(
            (lumped / fe - 1.0).abs() < 0.06,
            "{deg:.2}°: lumped {lumped:.0} Hz against the FE modal's {fe:.0}"
        );
    }
    assert!(held.lumped_rel.abs() < 0.06, "{}", held.lumped_rel);
    let torsion = held
        .driver_torsion_rel
        .expect("both models have the driver's torsion");
    assert!(torsion.abs() < 0.03, "driver torsion {torsion}");
}

/// The mesh's own moving mass (`ltca::modal::mesh_moving_mass`) on the paper pair: the static
/// shape's load does no work on the pair's rolling (the held driver hub's reaction at
/// round-off), the gears' rotations approach uniformly over the active ties (to 1e-6; 6e-8
/// measured), and, without the sway
/// (the default for this pair), the deformation's share of the kinetic energy,
/// m_d/(m_e + m_d), is the FE modal's mesh mode's own (both free: one minus the gears'
/// rigid-rotation shares) within −20 … +25 %: the static shape is the mode's first Ritz vector,
/// and a ratio of two kinetic-energy shares has no Rayleigh bound (measured on this 1 / 3 mm
/// mesh: 1.23 % against 1.31 % at the first position, 2.47 % against 2.72 % half a base
/// pitch on). With the rims' sway shapes projected out m_d is smaller (the sway's mass is the sway
/// coordinate's) and positive.
#[test]
fn the_mesh_moves_the_mass_its_modal_shape_does() {
    let (model, case) = model();
    let rb = [0, 1].map(|g| case.pair.gears[g].base_radius);
    let material = case.ltca_material();
    let shapes = geardyn::ltca::modal::ltca_sway_shapes(&model, material).unwrap();
    for index in [0, POSITIONS / 2] {
        let moving = |swaying: bool| {
            let sway = [0, 1].map(|g| swaying.then_some(&shapes[g]));
            let moving = geardyn::ltca::modal::mesh_moving_mass(
                &model,
                (index, POSITIONS),
                TORQUE,
                (material, case.material.density),
                sway,
            )
            .unwrap();
            assert!(moving.held_reaction < 1e-6, "{moving:?}");
            assert!(moving.approach_spread < 1e-6, "{moving:?}");
            moving.mass
        };
        let (without, with) = (moving(false), moving(true));
        assert!(0.0 < with && with < without, "{with} {without}");
        let free = modes(&model, &case, index, Hubs::BothFree);
        let mesh = &free.modes[free.mesh_mode];
        // The rigid pair's effective mass along the line of action, m_e = I₁I₂/(I₁r₂² + I₂r₁²):
        // the mesh mode's rigid kinetic energy per approach rate.
        let [i1, i2] = free.inertias;
        let m_e = i1 * i2 / (i1 * rb[1] * rb[1] + i2 * rb[0] * rb[0]);
        let modal_share = 1.0 - mesh.rotation_share.iter().sum::<f64>();
        let static_share = without / (m_e + without);
        let ratio = static_share / modal_share;
        assert!(
            (0.8..1.25).contains(&ratio),
            "position {index}: static {static_share:.4} (m_d {without:.4} kg, m_e {m_e:.4} kg), modal {modal_share:.4}"
        );
    }
}
