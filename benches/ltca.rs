//! LTCA cost on the paper's pair at the default mesh (0.2 mm on the engaging flanks):
//! factorization of one gear, the whole setup (mesh, factorize, condense; both gears), and the
//! 64-position cycle after setup; and the modal analysis of the meshed pair at one position on
//! the explicit FE's mesh (1 mm flanks, 3 mm body: assembly, static check, 10 lowest modes);
//! and the relief optimizer: one design over the five torques of the default load range, and
//! one whole trust-region loop (linear relief from none).

use criterion::{criterion_group, criterion_main, Criterion};
use geardyn::fe::assembly::{stiffness_triplets, FactorizedStiffness};
use geardyn::fe::elasticity_matrix;
use geardyn::ltca::engaging_teeth;
use geardyn::ltca::modal::{pair_modes, Hubs};
use geardyn::mesh::mesh_gear;
use geardyn::samples;
use std::hint::black_box;

fn ltca(c: &mut Criterion) {
    let case = samples::paper36_case();
    let teeth = engaging_teeth(&case.pair);
    let mods = case.relief_variant("none").unwrap().modifications;
    let material = case.ltca_material();
    let mut group = c.benchmark_group("ltca_paper36_default_mesh");
    group.sample_size(10);

    let gear = &case.pair.gears[0];
    let mesh = mesh_gear(gear, &mods[0], &case.mesh_spec(teeth[0].clone()));
    let d = elasticity_matrix(
        material.youngs_modulus,
        material.poisson_ratio,
        material.plane,
    );
    let fixed: Vec<usize> = mesh
        .bore_nodes
        .iter()
        .flat_map(|&i| [2 * i, 2 * i + 1])
        .collect();
    group.bench_function("assemble_and_factorize_one_gear", |b| {
        b.iter(|| {
            let triplets =
                stiffness_triplets(&mesh.nodes, &mesh.elements, &d, gear.spec.face_width);
            FactorizedStiffness::new(2 * mesh.nodes.len(), triplets, &fixed).unwrap()
        })
    });
    group.bench_function("setup_both_gears", |b| {
        b.iter(|| geardyn::study::ltca::model(black_box(&case), &mods).unwrap())
    });
    let model = geardyn::study::ltca::model(&case, &mods).unwrap();
    group.bench_function("cycle_64_positions", |b| {
        b.iter(|| model.run(64, black_box(143.6), &|_| {}).unwrap())
    });
    group.finish();

    let mut group = c.benchmark_group("pair_modal_paper36_explicit_mesh");
    group.sample_size(10);
    let explicit = geardyn::study::ltca::model_with_sizes(&case, &mods, 1e-3, 3e-3).unwrap();
    for hubs in [Hubs::DriverHeld, Hubs::BothFree] {
        group.bench_function(format!("{hubs:?}_10_modes"), |b| {
            b.iter(|| {
                pair_modes(
                    &explicit,
                    (black_box(0), 16),
                    143.6,
                    material,
                    case.material.density,
                    hubs,
                    10,
                )
                .unwrap()
            })
        });
    }
    group.finish();

    use geardyn::geometry::{FlankModification, ReliefShape};
    use geardyn::optimize::relief::ReliefDesign;
    use geardyn::optimize::robust::{self, LoadRange, Settings};
    let mut group = c.benchmark_group("relief_optimizer_paper36_default_mesh");
    group.sample_size(10);
    let torque = 143.6;
    let bodies = geardyn::study::ltca::model(&case, &[FlankModification::none(); 2]).unwrap();
    let range = LoadRange::uniform(torque, 0.5, 1.5, 5).unwrap();
    let design = ReliefDesign {
        tip: [5.5e-6; 2],
        root: [0.0; 2],
        length: 0.93,
        shape: ReliefShape::Linear,
    };
    group.bench_function("one_design_5_torques_64_positions", |b| {
        b.iter(|| robust::evaluate(&bodies, black_box(&design), &range, 64).unwrap())
    });
    let deflection = 8.6e-6;
    let limits = robust::Limits {
        max_amount: 40e-6,
        min_length: 0.25,
        min_contact_ratio: 1.2,
        contact_deflection: deflection,
        max_root_stress: None,
        max_contact_pressure: None,
    };
    let respond = |d: &ReliefDesign| robust::evaluate(&bodies, d, &range, 64).map(|e| e.response);
    group.bench_function("trust_region_linear_from_none", |b| {
        b.iter(|| {
            robust::optimize(
                &respond,
                &ReliefDesign::none(ReliefShape::Linear),
                &range,
                &limits,
                &Settings::default(),
                &|_| {},
            )
            .unwrap()
        })
    });
    group.finish();
}

criterion_group!(benches, ltca);
criterion_main!(benches);
