//! LTCA cost on the paper's pair at the default mesh (0.2 mm on the engaging flanks):
//! factorization of one gear, the whole setup (mesh, factorize, condense; both gears), and the
//! 64-position cycle after setup; and the modal analysis of the meshed pair at one position on
//! the explicit FE's mesh (1 mm flanks, 3 mm body: assembly, static check, 10 lowest modes).

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
            FactorizedStiffness::new(2 * mesh.nodes.len(), &triplets, &fixed).unwrap()
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
}

criterion_group!(benches, ltca);
criterion_main!(benches);
