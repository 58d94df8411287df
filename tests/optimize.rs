//! The relief optimizer: the trust-region loop on synthetic responses with known optima (free
//! and with an active limit), and on the paper pair's LTCA (feasible, KKT-clean, monotone, below
//! the unmodified STE).

use geardyn::geometry::{FlankModification, ReliefShape};
use geardyn::optimize::relief::ReliefDesign;
use geardyn::optimize::robust::{
    self, end_relief, Limits, LoadRange, LoadResponse, OptimizeError, Settings,
};
use geardyn::samples;
use geardyn::study;

/// A response with a known optimum: two torques (the second 1.5× the first), three positions,
/// s₀ = 1 + u + 0.3u², u = 2 − (C_a1 + C_f2); s₁ = 1 + w + 0.3w², w = 1 − (C_a2 + C_f1);
/// s₂ = 1 [µm]. Like the LTCA it sees only the sums at each end of the path. It is flat at
/// C_a1 + C_f2 = 2, C_a2 + C_f1 = 1 (and again at 16/3 and 13/3 µm, where u, w = −10/3: the L1
/// regularization takes the smaller reliefs), and the regularization puts both on the tips. The
/// loaded contact ratio falls by 0.1 per µm of relief from 1.7. Strength, scaled with the torque
/// like the STE (arbitrary, with known constrained optima): gear 1's root stress at position 0
/// is 100 + 5·(C_a1 + C_f2) MPa, gear 2's 90, both 80 elsewhere;
/// the Hertz pressure at position 1 is 700 + 10·(C_a2 + C_f1) MPa, 600 elsewhere.
fn synthetic(design: &ReliefDesign) -> Result<LoadResponse, OptimizeError> {
    let um = |x: f64| x * 1e6;
    let recess = um(design.tip[0] + design.root[1]);
    let approach = um(design.tip[1] + design.root[0]);
    let (u, w) = (2.0 - recess, 1.0 - approach);
    let base = [1.0 + u + 0.3 * u * u, 1.0 + w + 0.3 * w * w, 1.0];
    let ste_um: Vec<Vec<f64>> = [1.0, 1.5]
        .iter()
        .map(|scale| base.iter().map(|s| s * scale).collect())
        .collect();
    let ste_pp_um: Vec<f64> = ste_um
        .iter()
        .map(|s| {
            s.iter().copied().fold(f64::MIN, f64::max) - s.iter().copied().fold(f64::MAX, f64::min)
        })
        .collect();
    Ok(LoadResponse {
        objective_um: 0.5 * (ste_pp_um[0] + ste_pp_um[1]),
        ste_um,
        ste_pp_um,
        contact_ratio: vec![1.7 - 0.1 * (recess + approach); 2],
        mesh_stiffness_mean: vec![0.0; 2],
        max_kkt_residual: 0.0,
        root_stress_mpa: [1.0, 1.5]
            .iter()
            .map(|t| {
                vec![
                    [t * (100.0 + 5.0 * recess), t * 90.0],
                    [t * 80.0; 2],
                    [t * 80.0; 2],
                ]
            })
            .collect(),
        contact_pressure_mpa: [1.0, 1.5]
            .iter()
            .map(|t| vec![t * 600.0, t * (700.0 + 10.0 * approach), t * 600.0])
            .collect(),
    })
}

fn synthetic_range() -> LoadRange {
    LoadRange {
        torques: vec![1.0, 1.5],
        weights: vec![0.5, 0.5],
    }
}

fn limits(contact_deflection: f64) -> Limits {
    Limits {
        max_amount: 40e-6,
        min_length: 0.25,
        min_contact_ratio: 1.2,
        contact_deflection,
        max_root_stress: None,
        max_contact_pressure: None,
    }
}

/// Free optimum: C_a1 = 2 µm, C_a2 = 1 µm, no root relief, objective 0 (to the tolerance),
/// every QP's KKT residual small. Tolerances: 0.01 µm on the amounts (the loop stops when the
/// linear model predicts < 1e-5 µm; the response's slope is ≥ 1 µm/µm near the optimum, the
/// regularization's 1e-3 µm/µm).
#[test]
fn trust_region_finds_the_known_optimum() {
    let start = ReliefDesign::none(ReliefShape::Linear);
    let optimum = robust::optimize(
        &synthetic,
        &start,
        &synthetic_range(),
        &limits(10e-6),
        &Settings::default(),
        &|_| {},
    )
    .unwrap();
    let d = optimum.best.design;
    assert!(optimum.stop.converged(), "{:#?}", optimum.iterations);
    assert!((d.tip[0] * 1e6 - 2.0).abs() < 0.01, "{d:?}");
    assert!((d.tip[1] * 1e6 - 1.0).abs() < 0.01, "{d:?}");
    assert!(d.root.iter().all(|r| *r * 1e6 < 0.01), "{d:?}");
    assert!(optimum.best.response.objective_um < 0.02);
    assert!(optimum.iterations.len() > 1);
    for record in &optimum.iterations {
        assert!(record.kkt_residual < 1e-6, "{record:?}");
    }
}

/// With the no-loss-of-contact limit at 1.5 µm the recess end is held there (s₀ = 1.575 µm) and
/// the best the approach end can do is meet it: 1 + w + 0.3w² = 1.575 gives w = ½, so
/// C_a2 = 0.5 µm (the L1 penalty takes the smallest such relief); objective ½(0.575 + 1.5·0.575).
#[test]
fn an_active_limit_holds_and_gives_the_known_constrained_optimum() {
    let optimum = robust::optimize(
        &synthetic,
        &ReliefDesign::none(ReliefShape::Linear),
        &synthetic_range(),
        &limits(1.5e-6),
        &Settings::default(),
        &|_| {},
    )
    .unwrap();
    let d = optimum.best.design;
    assert!(end_relief(&d)[0] <= 1.5e-6 * (1.0 + 1e-9), "{d:?}");
    assert!((d.tip[0] * 1e6 - 1.5).abs() < 0.01, "{d:?}");
    assert!((d.tip[1] * 1e6 - 0.5).abs() < 0.01, "{d:?}");
    let expected = 0.5 * (0.575 + 1.5 * 0.575);
    assert!(
        (optimum.best.response.objective_um - expected).abs() < 0.01,
        "{} against {expected}",
        optimum.best.response.objective_um
    );
    // A start that already breaks a limit is refused, not repaired silently.
    let over = ReliefDesign {
        tip: [3e-6, 0.0],
        ..ReliefDesign::none(ReliefShape::Linear)
    };
    assert!(matches!(
        robust::optimize(
            &synthetic,
            &over,
            &synthetic_range(),
            &limits(1.5e-6),
            &Settings::default(),
            &|_| {}
        ),
        Err(OptimizeError::InfeasibleStart(_))
    ));
}

/// A response that diverges (NaN, as a contact solve that failed would give) once the recess
/// relief passes 1 µm: the loop does not feed NaN into the QP or take it as a design; it stops
/// the start with `Stop::Failed`, says which iteration and why, and keeps the last good design —
/// finite, feasible, and no worse than the start.
#[test]
fn a_diverging_response_stops_the_start_and_keeps_the_last_good_design() {
    let diverging = |design: &ReliefDesign| {
        let mut response = synthetic(design)?;
        if design.tip[0] + design.root[1] > 1e-6 {
            response.objective_um = f64::NAN;
        }
        Ok(response)
    };
    let optimum = robust::optimize(
        &diverging,
        &ReliefDesign::none(ReliefShape::Linear),
        &synthetic_range(),
        &limits(10e-6),
        &Settings::default(),
        &|_| {},
    )
    .unwrap();
    assert_eq!(optimum.stop, robust::Stop::Failed);
    assert!(!optimum.stop.converged());
    let failure = optimum.failure.as_deref().unwrap();
    assert!(
        failure.starts_with("iteration ") && failure.contains("not finite"),
        "{failure}"
    );
    let best = &optimum.best;
    assert!(best.response.objective_um.is_finite());
    assert!(best.design.tip[0] + best.design.root[1] <= 1e-6);
    assert!(best.response.objective_um <= optimum.start.response.objective_um);
    assert!(robust::feasible(best, &limits(10e-6)));
    // A start that is itself not finite is an error, not a result.
    let nan_everywhere = |design: &ReliefDesign| {
        let mut response = synthetic(design)?;
        response.contact_ratio[0] = f64::NAN;
        Ok(response)
    };
    let start = robust::optimize(
        &nan_everywhere,
        &ReliefDesign::none(ReliefShape::Linear),
        &synthetic_range(),
        &limits(10e-6),
        &Settings::default(),
        &|_| {},
    );
    assert!(matches!(start, Err(OptimizeError::NotFinite(_))));
}

/// A response finite everywhere but so steep that its finite differences overflow (the STE
/// jumps to 1e308 µm once any tip relief is applied, as a solve that lost the contact could
/// report): the linearization holds infinity, the step's QP refuses it inside the loop, and
/// the start stops with `Stop::Failed`, naming the QP, with the start design kept as the best.
#[test]
fn a_qp_that_fails_inside_the_loop_stops_the_start_and_keeps_its_design() {
    let overflowing = |design: &ReliefDesign| {
        let mut response = synthetic(design)?;
        if design.tip[0] > 0.0 {
            for ste in &mut response.ste_um {
                ste[0] = 1e308;
            }
        }
        Ok(response)
    };
    let start = ReliefDesign::none(ReliefShape::Linear);
    let optimum = robust::optimize(
        &overflowing,
        &start,
        &synthetic_range(),
        &limits(10e-6),
        &Settings::default(),
        &|_| {},
    )
    .unwrap();
    assert_eq!(optimum.stop, robust::Stop::Failed);
    let failure = optimum.failure.as_deref().unwrap();
    assert!(
        failure.starts_with("iteration 1, the step's QP") && failure.contains("NaN or infinity"),
        "{failure}"
    );
    assert_eq!(optimum.best.design, start);
    assert!(optimum.iterations.is_empty(), "no step was taken");
}

/// With the loaded contact ratio held at ≥ 1.5 the sums may total 2 µm at most (1.7 − 0.1 · 2):
/// the best split makes both ends equally short of flat, u = w = ½, so C_a1 = 1.5 µm,
/// C_a2 = 0.5 µm, s₀ = s₁ = 1.575 µm, objective ½(0.575 + 1.5 · 0.575) — the contact-ratio
/// rows of the QP, linearized by forward differences, hold the limit.
#[test]
fn the_contact_ratio_limit_holds_and_gives_the_known_optimum() {
    let mut tight = limits(10e-6);
    tight.min_contact_ratio = 1.5;
    let optimum = robust::optimize(
        &synthetic,
        &ReliefDesign::none(ReliefShape::Linear),
        &synthetic_range(),
        &tight,
        &Settings::default(),
        &|_| {},
    )
    .unwrap();
    let d = optimum.best.design;
    assert!(
        robust::feasible(&optimum.best, &tight),
        "{:?}",
        optimum.best
    );
    assert!((d.tip[0] * 1e6 - 1.5).abs() < 0.01, "{d:?}");
    assert!((d.tip[1] * 1e6 - 0.5).abs() < 0.01, "{d:?}");
    let expected = 0.5 * (0.575 + 1.5 * 0.575);
    assert!((optimum.best.response.objective_um - expected).abs() < 0.01);
}

/// A root-stress limit of 157.5 MPa binds at the top torque (1.5 × (100 + 5·recess)): recess
/// relief ≤ 1 µm, u = 1, s₀ = 2.3 µm. The approach end can then sit anywhere in [1, 2.3] µm of
/// STE without changing the peak-to-peak, and the L1 penalty takes no approach relief:
/// C_a1 = 1, C_a2 = 0, objective ½(1.3 + 1.5·1.3). A Hertz limit of 1 054.5 MPa (1.5 × (700 +
/// 10·approach)) caps the approach relief at 0.3 µm: w = 0.7, s₁ = 1.847 µm; the recess end
/// then takes the least relief that keeps s₀ ≤ s₁, u + 0.3u² = 0.847, u = 0.7: C_a1 = 1.3 µm,
/// objective ½(0.847 + 1.5·0.847). A start beyond a limit is refused with the stress named.
#[test]
fn strength_limits_hold_and_give_the_known_constrained_optima() {
    let run = |limits: &Limits| {
        robust::optimize(
            &synthetic,
            &ReliefDesign::none(ReliefShape::Linear),
            &synthetic_range(),
            limits,
            &Settings::default(),
            &|_| {},
        )
        .unwrap()
    };
    let root = Limits {
        max_root_stress: Some([157.5e6; 2]),
        ..limits(10e-6)
    };
    let optimum = run(&root);
    let d = optimum.best.design;
    assert!(robust::feasible(&optimum.best, &root), "{:?}", optimum.best);
    assert!((d.tip[0] * 1e6 - 1.0).abs() < 0.01, "{d:?}");
    assert!(d.tip[1] * 1e6 < 0.01, "{d:?}");
    assert!((optimum.best.response.objective_um - 0.5 * (1.3 + 1.5 * 1.3)).abs() < 0.01);

    let pressure = Limits {
        max_contact_pressure: Some(1054.5e6),
        ..limits(10e-6)
    };
    let optimum = run(&pressure);
    let d = optimum.best.design;
    assert!(robust::feasible(&optimum.best, &pressure));
    assert!((d.tip[1] * 1e6 - 0.3).abs() < 0.01, "{d:?}");
    assert!((d.tip[0] * 1e6 - 1.3).abs() < 0.01, "{d:?}");
    let w: f64 = 0.7;
    let s1 = 1.0 + w + 0.3 * w * w;
    assert!(
        (optimum.best.response.objective_um - 0.5 * (s1 - 1.0) * 2.5).abs() < 0.01,
        "{}",
        optimum.best.response.objective_um
    );

    // The unmodified start's root stress (150 MPa at the top torque) is above a 140 MPa limit.
    let below_start = Limits {
        max_root_stress: Some([140e6; 2]),
        ..limits(10e-6)
    };
    match robust::optimize(
        &synthetic,
        &ReliefDesign::none(ReliefShape::Linear),
        &synthetic_range(),
        &below_start,
        &Settings::default(),
        &|_| {},
    ) {
        Err(OptimizeError::InfeasibleStart(reason)) => {
            assert!(reason.contains("root stress 150.0 MPa"), "{reason}")
        }
        other => panic!("{other:?}"),
    }
}

/// The unmodified bodies of `case` (case mesh), the load range 50–150 % in three torques, 32
/// positions, and the single-pair deflection (the largest approach at the design torque).
struct LtcaSetup {
    model: geardyn::ltca::LtcaModel,
    range: LoadRange,
    positions: usize,
    deflection: f64,
}

impl LtcaSetup {
    /// A design's robust response over the load range on these bodies.
    fn respond(&self, design: &ReliefDesign) -> Result<LoadResponse, OptimizeError> {
        robust::evaluate(&self.model, design, &self.range, self.positions).map(|e| e.response)
    }
}

fn ltca_setup(case: &geardyn::case::Case) -> LtcaSetup {
    let torque = study::load_torque(case).unwrap();
    let model = study::ltca::model(case, &[FlankModification::none(); 2]).unwrap();
    let positions = 32;
    let rb2 = case.pair.gears[1].base_radius;
    let deflection = model
        .run(positions, torque, &|_| {})
        .unwrap()
        .iter()
        .map(|r| rb2 * (r.ste - r.unloaded_te))
        .fold(0.0, f64::max);
    LtcaSetup {
        model,
        range: LoadRange::uniform(torque, 0.5, 1.5, 3).unwrap(),
        positions,
        deflection,
    }
}

/// On the paper pair's LTCA (case mesh, 32 positions, three torques 50–150 %): every accepted
/// design keeps the limits and is a relief the geometry accepts; f falls monotonically over
/// accepted steps; every QP is KKT-clean; the optimum's STE peak-to-peak at
/// the design torque is below the unmodified pair's. Also with tight limits (3 µm at most,
/// loaded contact ratio ≥ 1.55), and with the root stress held within 1 % of the unmodified
/// pair's peak (unlimited, the optimum raises it by about 1.5 %), the result keeps them.
#[test]
fn ltca_optimum_is_feasible_and_beats_the_unmodified_pair() {
    let case = samples::paper36_case();
    let setup = ltca_setup(&case);
    let (range, deflection) = (&setup.range, setup.deflection);
    let respond = |d: &ReliefDesign| setup.respond(d);
    let unmodified = respond(&ReliefDesign::none(ReliefShape::Linear)).unwrap();
    let [root1, root2] = unmodified.root_stress_peak_mpa();
    for (max_um, min_ratio, root_percent) in [
        (40.0, 1.2, None),
        (3.0, 1.55, None),
        (40.0, 1.2, Some(101.0)),
    ] {
        let limits = Limits {
            max_amount: max_um * 1e-6,
            min_length: 0.25,
            min_contact_ratio: min_ratio,
            contact_deflection: deflection,
            max_root_stress: root_percent.map(|p: f64| [root1, root2].map(|r| p / 100.0 * r * 1e6)),
            max_contact_pressure: None,
        };
        let accepted = std::sync::Mutex::new(Vec::new());
        let optimum = robust::optimize(
            &respond,
            &ReliefDesign::none(ReliefShape::Linear),
            range,
            &limits,
            &Settings::default(),
            &|r| {
                if r.accepted {
                    accepted.lock().unwrap().push(r.clone());
                }
            },
        )
        .unwrap();
        assert!(
            robust::feasible(&optimum.best, &limits),
            "{:?}",
            optimum.best
        );
        assert!(optimum.best.design.modifications(&case.pair).is_ok());
        assert!(optimum
            .best
            .design
            .tip
            .iter()
            .chain(&optimum.best.design.root)
            .all(|a| *a <= max_um * 1e-6));
        for r in &optimum.iterations {
            assert!(r.kkt_residual < 1e-6, "{r:?}");
        }
        let accepted = accepted.into_inner().unwrap();
        // Every accepted step lowers f = objective + regularization.
        for pair in accepted.windows(2) {
            assert!(pair[1].merit_um < pair[0].merit_um);
        }
        assert!(optimum.best.response.objective_um < unmodified.objective_um);
        // The free optimum raises the root stress beyond the 1 % the third run allows, so
        // that run's limit binds.
        if max_um == 40.0 && root_percent.is_none() {
            let [a, b] = optimum.best.response.root_stress_peak_mpa();
            assert!(
                a.max(b) > 1.01 * root1.max(root2),
                "{a} {b} against {root1} {root2}"
            );
        }
        // The design torque is the middle one of the range.
        assert!(
            optimum.best.response.ste_pp_um[1] < unmodified.ste_pp_um[1],
            "{} against {}",
            optimum.best.response.ste_pp_um[1],
            unmodified.ste_pp_um[1]
        );
    }
}

/// A root-stress limit on an unequal, shifted pair (24/40, x = +0.3 / −0.3, case mesh, 32
/// positions, three torques 50–150 %), per gear at 101 % of each gear's unmodified peak: the free
/// optimum breaks it on a gear (so it binds), the limited optimum keeps both gears' limits and
/// still beats the unmodified pair's robust objective.
#[test]
fn a_per_gear_root_limit_binds_and_holds_on_an_unequal_pair() {
    let case = samples::shifted_24_40(false);
    let setup = ltca_setup(&case);
    let (range, deflection) = (&setup.range, setup.deflection);
    let respond = |d: &ReliefDesign| setup.respond(d);
    let unmodified = respond(&ReliefDesign::none(ReliefShape::Linear)).unwrap();
    let peaks = unmodified.root_stress_peak_mpa();
    let free = Limits {
        max_amount: 40e-6,
        min_length: 0.25,
        min_contact_ratio: study::optimize::default_min_contact_ratio(&case.pair),
        contact_deflection: deflection,
        max_root_stress: None,
        max_contact_pressure: None,
    };
    let limited = Limits {
        max_root_stress: Some(peaks.map(|p| 1.01 * p * 1e6)),
        ..free
    };
    let run = |limits: &Limits| {
        robust::optimize(
            &respond,
            &ReliefDesign::none(ReliefShape::Linear),
            range,
            limits,
            &Settings::default(),
            &|_| {},
        )
        .unwrap()
    };
    let free_optimum = run(&free);
    let raised = free_optimum.best.response.root_stress_peak_mpa();
    eprintln!("unmodified {peaks:?} MPa, free optimum {raised:?} MPa");
    assert!(
        (0..2).any(|g| raised[g] > 1.01 * peaks[g]),
        "{raised:?} against {peaks:?}"
    );
    let optimum = run(&limited);
    let kept = optimum.best.response.root_stress_peak_mpa();
    eprintln!(
        "limited optimum {kept:?} MPa, objective {:.3} against {:.3} um unmodified",
        optimum.best.response.objective_um, unmodified.objective_um
    );
    assert!(robust::feasible(&optimum.best, &limited), "{kept:?}");
    assert!(optimum.best.response.objective_um < unmodified.objective_um);
}
